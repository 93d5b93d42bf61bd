/* Conformance importer: model exchange with SUNDIALS CVODE (BDF, dense linear solver, root
 * finding on the event indicators), the way a generic FMI 2.0 tool drives an FMU.
 *
 *   --mode flags   (default) after an event the integrator is re-initialised only when
 *                  fmi2NewDiscreteStates reports valuesOfContinuousStatesChanged or
 *                  nominalsOfContinuousStatesChanged (as Reference-FMUs' fmusim does);
 *                  otherwise CVODE goes on from its own internal state and history
 *   --mode always  re-initialise after every event
 *
 * CVODE integrates to each output point (CV_NORMAL: it may step past the point and
 * interpolates; the only stop time is the end of the run), relative tolerance --rtol (default: the
 * DefaultExperiment tolerance), absolute tolerance rtol x the nominal of each state. Output
 * points every --interval (default: the DefaultExperiment stepSize); events are written to
 * --events and the state before each event to --out as well. Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "fmi2_import.h"

#define PROGRAM "csfh_import_me_cvode"

typedef struct {
    importer_t *imp;
    int failed;
} rhs_data_t;

static int set_time_state(importer_t *imp, double t, N_Vector y)
{
    if (imp->api.SetTime(imp->c, t) > fmi2Warning) {
        return -1;
    }
    if (imp->run.md.n_states > 0 &&
        imp->api.SetContinuousStates(imp->c, N_VGetArrayPointer(y), (size_t)imp->run.md.n_states) >
            fmi2Warning) {
        return -1;
    }
    return 0;
}

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    importer_t *imp = d->imp;
    if (set_time_state(imp, t, y) != 0 ||
        imp->api.GetDerivatives(imp->c, N_VGetArrayPointer(ydot), (size_t)imp->run.md.n_states) >
            fmi2Warning) {
        d->failed = 1;
        imp_fail(&imp->run, "the FMU failed to evaluate the derivatives at t = %.17g", t);
        return -1;
    }
    return 0;
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *g, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    importer_t *imp = d->imp;
    if (set_time_state(imp, t, y) != 0 ||
        imp->api.GetEventIndicators(imp->c, g, (size_t)imp->run.md.n_event_indicators) >
            fmi2Warning) {
        d->failed = 1;
        imp_fail(&imp->run, "the FMU failed to evaluate the event indicators at t = %.17g", t);
        return -1;
    }
    return 0;
}

/* Event mode at the current time and state: the event iteration; returns 1 if the FMU asked for
 * a re-initialisation, 0 if not, -1 on failure. */
static int event_iteration(importer_t *imp)
{
    fmi2EventInfo info;
    int reinit = 0;
    if (imp->api.EnterEventMode(imp->c) > fmi2Warning) {
        return -1;
    }
    do {
        memset(&info, 0, sizeof(info));
        if (imp->api.NewDiscreteStates(imp->c, &info) > fmi2Warning || info.terminateSimulation) {
            return -1;
        }
        reinit |= info.valuesOfContinuousStatesChanged || info.nominalsOfContinuousStatesChanged;
    } while (info.newDiscreteStatesNeeded);
    if (imp->api.EnterContinuousTimeMode(imp->c) > fmi2Warning) {
        return -1;
    }
    return reinit;
}

int main(int argc, char **argv)
{
    importer_t imp;
    imp_open(&imp, argc, argv, fmi2ModelExchange, PROGRAM);
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

    if (nx < 1 || imp_initialize(&imp, fmi2ModelExchange, rtol) > fmi2Warning) {
        imp_fail(&imp.run, "initialization failed (or the FMU has no states)");
        goto done;
    }
    int r = event_iteration(&imp); /* the event iteration of the initialization */
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
    if (imp.api.GetContinuousStates(imp.c, N_VGetArrayPointer(y), (size_t)nx) > fmi2Warning ||
        imp.api.GetNominalsOfContinuousStates(imp.c, a, (size_t)nx) > fmi2Warning) {
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
    CVodeSetStopTime(mem, t_stop); /* no stop at the output points: CVODE interpolates there */
    imp_record(&imp, t, 1);
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
        fmi2Boolean enter = fmi2False, terminate = fmi2False;
        if (imp.api.CompletedIntegratorStep(imp.c, fmi2True, &enter, &terminate) > fmi2Warning ||
            terminate) {
            imp_fail(&imp.run, "fmi2CompletedIntegratorStep failed or asked to terminate");
            break;
        }
        if (flag == CV_ROOT_RETURN || enter) {
            imp_record(&imp, t, 1); /* the state at the event, before it */
            r = event_iteration(&imp);
            if (r < 0) {
                imp_fail(&imp.run, "the event iteration failed at t = %.17g", t);
                break;
            }
            imp_event(&imp.run, t, r ? "reinit-requested" : "event");
            if (r || always) {
                if (imp.api.GetContinuousStates(imp.c, N_VGetArrayPointer(y), (size_t)nx) >
                        fmi2Warning ||
                    CVodeReInit(mem, t, y) < 0) {
                    imp_fail(&imp.run, "re-initialisation failed at t = %.17g", t);
                    break;
                }
                imp.run.reinits++;
            }
        } else {
            imp_record(&imp, t, 1);
            k_out++;
        }
        if (imp.run.steps + nst > imp.run.opt.max_steps) {
            imp_fail(&imp.run, "budget: more than %ld steps", imp.run.opt.max_steps);
            break;
        }
        if (flag == CV_ROOT_RETURN && (r || always)) {
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
    return imp_close(&imp);
}
