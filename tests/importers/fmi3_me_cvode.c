/* Conformance importer: FMI 3.0 model exchange with SUNDIALS CVODE (BDF, dense linear solver,
 * root finding on the event indicators), the FMI 3.0 counterpart of me_cvode.c.
 *
 *   --mode flags   (default) after an event the integrator is re-initialised only when
 *                  fmi3UpdateDiscreteStates reports valuesOfContinuousStatesChanged or
 *                  nominalsOfContinuousStatesChanged; otherwise CVODE goes on from its own
 *                  internal state and history
 *   --mode always  re-initialise after every event
 *
 * After fmi3ExitInitializationMode the FMU is in Event Mode (FMI 3.0): the first event
 * iteration starts there without fmi3EnterEventMode. Time events (nextEventTimeDefined) stop the
 * integrator at nextEventTime. CVODE integrates to each output point (CV_NORMAL: it may step
 * past the point and interpolates), relative tolerance --rtol (default: the DefaultExperiment
 * tolerance), absolute tolerance rtol x the nominal of each state. Output points every
 * --interval (default: the DefaultExperiment stepSize); events are written to --events and the
 * state before each event to --out as well. Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "fmi3_import.h"

#define PROGRAM "csfh_import_fmi3_me_cvode"

typedef struct {
    importer3_t *imp;
    int failed;
} rhs_data_t;

static int set_time_state(importer3_t *imp, double t, N_Vector y)
{
    if (imp->api.SetTime(imp->c, t) > fmi3Warning) {
        return -1;
    }
    if (imp->run.md.n_states > 0 &&
        imp->api.SetContinuousStates(imp->c, N_VGetArrayPointer(y), (size_t)imp->run.md.n_states) >
            fmi3Warning) {
        return -1;
    }
    return 0;
}

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    importer3_t *imp = d->imp;
    if (set_time_state(imp, t, y) != 0 ||
        imp->api.GetContinuousStateDerivatives(imp->c, N_VGetArrayPointer(ydot),
                                               (size_t)imp->run.md.n_states) >
            fmi3Warning) {
        d->failed = 1;
        imp_fail(&imp->run, "the FMU failed to evaluate the derivatives at t = %.17g", t);
        return -1;
    }
    return 0;
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *g, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    importer3_t *imp = d->imp;
    if (set_time_state(imp, t, y) != 0 ||
        imp->api.GetEventIndicators(imp->c, g, (size_t)imp->run.md.n_event_indicators) >
            fmi3Warning) {
        d->failed = 1;
        imp_fail(&imp->run, "the FMU failed to evaluate the event indicators at t = %.17g", t);
        return -1;
    }
    return 0;
}

/* Event Mode at the current time and state (entered first unless `in_event_mode`): the event
 * iteration; returns 1 if the FMU asked for a re-initialisation, 0 if not, -1 on failure. The
 * next time event (or INFINITY) into *t_next. */
static int event_iteration(importer3_t *imp, int in_event_mode, double *t_next)
{
    fmi3Boolean again = fmi3False, terminate = fmi3False, nominals = fmi3False;
    fmi3Boolean values = fmi3False, next_defined = fmi3False;
    fmi3Float64 next = 0.0;
    int reinit = 0;
    if (!in_event_mode && imp->api.EnterEventMode(imp->c) > fmi3Warning) {
        return -1;
    }
    do {
        if (imp->api.UpdateDiscreteStates(imp->c, &again, &terminate, &nominals, &values,
                                          &next_defined, &next) > fmi3Warning ||
            terminate) {
            return -1;
        }
        reinit |= values || nominals;
    } while (again);
    *t_next = next_defined ? next : INFINITY;
    if (imp->api.EnterContinuousTimeMode(imp->c) > fmi3Warning) {
        return -1;
    }
    return reinit;
}

int main(int argc, char **argv)
{
    importer3_t imp;
    imp3_open(&imp, argc, argv, IMP3_MODEL_EXCHANGE, PROGRAM);
    const int always = imp.run.opt.mode != NULL && strcmp(imp.run.opt.mode, "always") == 0;
    if (imp.run.opt.mode != NULL && !always && strcmp(imp.run.opt.mode, "flags") != 0) {
        fprintf(stderr, PROGRAM ": --mode must be flags or always, got %s\n", imp.run.opt.mode);
        return 2;
    }
    const double rtol = isfinite(imp.run.opt.rtol) ? imp.run.opt.rtol : imp.run.md.tolerance;
    const double t_stop = isfinite(imp.run.opt.stop) ? imp.run.opt.stop : imp.run.md.stop_time;
    const double dt_out =
        isfinite(imp.run.opt.interval) ? imp.run.opt.interval : imp.run.md.step_size;
    if (!(rtol > 0) || !isfinite(t_stop) || !(dt_out > 0)) {
        fprintf(stderr, PROGRAM ": no tolerance, stop time or output interval (give --rtol, "
                        "--stop, --interval or a DefaultExperiment)\n");
        return 2;
    }
    imp.run.opt.stop = t_stop;
    const int nx = imp.run.md.n_states, nz = imp.run.md.n_event_indicators;
    SUNContext ctx = NULL;
    void *mem = NULL;
    N_Vector y = NULL, atol = NULL;
    SUNMatrix J = NULL;
    SUNLinearSolver LS = NULL;
    rhs_data_t data = {&imp, 0};
    int flag = 0;

    if (nx < 1 || imp3_initialize(&imp, rtol, 0, 0) > fmi3Warning) {
        imp_fail(&imp.run, "initialization failed (or the FMU has no states)");
        goto done;
    }
    double t_next = INFINITY;
    int r = event_iteration(&imp, 1, &t_next); /* the initialization's, in Event Mode already */
    if (r < 0) {
        imp_fail(&imp.run, "the initial event iteration failed");
        goto done;
    }
    double t = imp.run.t_reached;
    if (SUNContext_Create(NULL, &ctx) != 0) {
        imp_fail(&imp.run, "SUNContext_Create failed");
        goto done;
    }
    y = N_VNew_Serial(nx, ctx);
    atol = N_VNew_Serial(nx, ctx);
    J = SUNDenseMatrix(nx, nx, ctx);
    LS = SUNLinSol_Dense(y, J, ctx);
    mem = CVodeCreate(CV_BDF, ctx);
    if (y == NULL || atol == NULL || J == NULL || LS == NULL || mem == NULL) {
        imp_fail(&imp.run, "cannot allocate CVODE");
        goto done;
    }
    double *a = N_VGetArrayPointer(atol);
    if (imp.api.GetContinuousStates(imp.c, N_VGetArrayPointer(y), (size_t)nx) > fmi3Warning ||
        imp.api.GetNominalsOfContinuousStates(imp.c, a, (size_t)nx) > fmi3Warning) {
        imp_fail(&imp.run, "cannot read the states or their nominals");
        goto done;
    }
    for (int i = 0; i < nx; i++) {
        a[i] = rtol * fabs(a[i]);
    }
    if (CVodeInit(mem, rhs, t, y) < 0 || CVodeSetUserData(mem, &data) < 0 ||
        CVodeSVtolerances(mem, rtol, atol) < 0 || CVodeSetLinearSolver(mem, LS, J) < 0 ||
        CVodeSetMaxNumSteps(mem, 1000000) < 0 || (nz > 0 && CVodeRootInit(mem, nz, roots) < 0)) {
        imp_fail(&imp.run, "CVODE setup failed");
        goto done;
    }
    /* no stop at the output points (CVODE interpolates there): at the end and time events */
    CVodeSetStopTime(mem, fmin(t_stop, t_next));
    imp3_record(&imp, t, 1);
    long k_out = 1;
    const double t0 = t;
    while (t < t_stop) {
        double t_out = t0 + (double)k_out * dt_out;
        if (t_out > t_stop || t_stop - t_out < 1e-9 * dt_out) {
            t_out = t_stop;
        }
        flag = CVode(mem, t_out, y, &t, CV_NORMAL);
        long nst = 0;
        CVodeGetNumSteps(mem, &nst);
        if (flag < 0 || data.failed) {
            imp_fail(&imp.run, "CVode failed with flag %d at t = %.17g", flag, t);
            break;
        }
        if (set_time_state(&imp, t, y) != 0) {
            imp_fail(&imp.run, "cannot set the state at t = %.17g", t);
            break;
        }
        imp.run.t_reached = t;
        fmi3Boolean enter = fmi3False, terminate = fmi3False;
        if (imp.api.CompletedIntegratorStep(imp.c, fmi3True, &enter, &terminate) > fmi3Warning ||
            terminate) {
            imp_fail(&imp.run, "fmi3CompletedIntegratorStep failed or asked to terminate");
            break;
        }
        const int time_event = t >= t_next;
        int reinitialised = 0;
        if (flag == CV_ROOT_RETURN || enter || time_event) {
            imp3_record(&imp, t, 1); /* the state at the event, before it */
            r = event_iteration(&imp, 0, &t_next);
            if (r < 0) {
                imp_fail(&imp.run, "the event iteration failed at t = %.17g", t);
                break;
            }
            imp_event(&imp.run, t, r ? "reinit-requested" : "event");
            if (r || always) {
                if (imp.api.GetContinuousStates(imp.c, N_VGetArrayPointer(y), (size_t)nx) >
                        fmi3Warning ||
                    CVodeReInit(mem, t, y) < 0) {
                    imp_fail(&imp.run, "re-initialisation failed at t = %.17g", t);
                    break;
                }
                imp.run.reinits++;
                reinitialised = 1;
            }
            CVodeSetStopTime(mem, fmin(t_stop, t_next)); /* the next time event or the end */
        } else {
            imp3_record(&imp, t, 1);
            k_out++;
        }
        if (imp.run.steps + nst > imp.run.opt.max_steps) {
            imp_fail(&imp.run, "budget: more than %ld steps", imp.run.opt.max_steps);
            break;
        }
        if (reinitialised) {
            imp.run.steps += nst; /* CVodeReInit restarts the count */
        } else if (t >= t_stop) {
            imp.run.steps += nst;
        }
    }
done:
    if (mem != NULL) {
        CVodeFree(&mem);
    }
    if (LS != NULL) {
        SUNLinSolFree(LS);
    }
    if (J != NULL) {
        SUNMatDestroy(J);
    }
    if (y != NULL) {
        N_VDestroy(y);
    }
    if (atol != NULL) {
        N_VDestroy(atol);
    }
    if (ctx != NULL) {
        SUNContext_Free(&ctx);
    }
    return imp3_close(&imp);
}
