/* Conformance importer: model exchange with SUNDIALS CVODE (BDF, dense linear solver, root
 * finding on the event indicators), the way a generic FMI tool drives an FMU; written once for
 * both FMI versions against the model-exchange table of import_me.h.
 *
 *   --mode flags   (default) after an event the integrator is re-initialised only when the event
 *                  iteration reports valuesOfContinuousStatesChanged or
 *                  nominalsOfContinuousStatesChanged (as Reference-FMUs' fmusim does); otherwise
 *                  CVODE goes on from its own internal state and history
 *   --mode always  re-initialise after every event
 *
 * After initialization the FMU is in Event Mode: the first event iteration starts there. Time
 * events (nextEventTime) stop the integrator there. CVODE integrates to each output point
 * (CV_NORMAL: it may step past the point and interpolates), relative tolerance --rtol (default:
 * the DefaultExperiment tolerance), absolute tolerance rtol x the nominal of each state. Output
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

#include "import_me.h"

typedef struct {
    const imp_me_t *me;
    int failed;
} rhs_data_t;

/* CVODE and what it works on. */
typedef struct {
    SUNContext ctx;
    void *mem;
    N_Vector y, atol;
    SUNMatrix J;
    SUNLinearSolver LS;
    rhs_data_t data;
} solver_t;

/* The run's settings: from the command line, else the DefaultExperiment. */
typedef struct {
    double rtol, t_stop, dt_out;
    int always;
} settings_t;

static int set_time_state(const imp_me_t *me, double t, N_Vector y)
{
    const size_t nx = (size_t)me->run->md.n_states;
    if (me->set_time(me->fmu, t) != 0) {
        return -1;
    }
    return nx > 0 ? me->set_states(me->fmu, N_VGetArrayPointer(y), nx) : 0;
}

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    const imp_me_t *me = d->me;
    if (set_time_state(me, t, y) != 0 ||
        me->get_derivatives(me->fmu, N_VGetArrayPointer(ydot), (size_t)me->run->md.n_states) !=
            0) {
        d->failed = 1;
        imp_fail(me->run, "the FMU failed to evaluate the derivatives at t = %.17g", t);
        return -1;
    }
    return 0;
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *g, void *user_data)
{
    rhs_data_t *d = (rhs_data_t *)user_data;
    const imp_me_t *me = d->me;
    if (set_time_state(me, t, y) != 0 ||
        me->get_event_indicators(me->fmu, g, (size_t)me->run->md.n_event_indicators) != 0) {
        d->failed = 1;
        imp_fail(me->run, "the FMU failed to evaluate the event indicators at t = %.17g", t);
        return -1;
    }
    return 0;
}

/* The settings, or exit status 2 with a message. */
static int read_settings(const imp_me_t *me, const char *program, settings_t *s)
{
    imp_run_t *run = me->run;
    s->always = run->opt.mode != NULL && strcmp(run->opt.mode, "always") == 0;
    if (run->opt.mode != NULL && !s->always && strcmp(run->opt.mode, "flags") != 0) {
        fprintf(stderr, "%s: --mode must be flags or always, got %s\n", program, run->opt.mode);
        return 2;
    }
    s->rtol = isfinite(run->opt.rtol) ? run->opt.rtol : run->md.tolerance;
    s->t_stop = isfinite(run->opt.stop) ? run->opt.stop : run->md.stop_time;
    s->dt_out = isfinite(run->opt.interval) ? run->opt.interval : run->md.step_size;
    if (!(s->rtol > 0) || !isfinite(s->t_stop) || !(s->dt_out > 0)) {
        fprintf(stderr, "%s: no tolerance, stop time or output interval (give --rtol, --stop, "
                        "--interval or a DefaultExperiment)\n", program);
        return 2;
    }
    run->opt.stop = s->t_stop;
    return 0;
}

/* CVODE from the FMU's states at time t, absolute tolerances rtol x the nominals; 0 or -1. */
static int create_solver(solver_t *sv, const imp_me_t *me, double t, double rtol)
{
    const int nx = me->run->md.n_states, nz = me->run->md.n_event_indicators;
    if (SUNContext_Create(NULL, &sv->ctx) != 0) {
        imp_fail(me->run, "SUNContext_Create failed");
        return -1;
    }
    sv->y = N_VNew_Serial(nx, sv->ctx);
    sv->atol = N_VNew_Serial(nx, sv->ctx);
    sv->J = SUNDenseMatrix(nx, nx, sv->ctx);
    sv->LS = SUNLinSol_Dense(sv->y, sv->J, sv->ctx);
    sv->mem = CVodeCreate(CV_BDF, sv->ctx);
    if (sv->y == NULL || sv->atol == NULL || sv->J == NULL || sv->LS == NULL || sv->mem == NULL) {
        imp_fail(me->run, "cannot allocate CVODE");
        return -1;
    }
    double *a = N_VGetArrayPointer(sv->atol);
    if (me->get_states(me->fmu, N_VGetArrayPointer(sv->y), (size_t)nx) != 0 ||
        me->get_nominals(me->fmu, a, (size_t)nx) != 0) {
        imp_fail(me->run, "cannot read the states or their nominals");
        return -1;
    }
    for (int i = 0; i < nx; i++) {
        a[i] = rtol * fabs(a[i]);
    }
    if (CVodeInit(sv->mem, rhs, t, sv->y) < 0 || CVodeSetUserData(sv->mem, &sv->data) < 0 ||
        CVodeSVtolerances(sv->mem, rtol, sv->atol) < 0 ||
        CVodeSetLinearSolver(sv->mem, sv->LS, sv->J) < 0 ||
        CVodeSetMaxNumSteps(sv->mem, 1000000) < 0 ||
        (nz > 0 && CVodeRootInit(sv->mem, nz, roots) < 0)) {
        imp_fail(me->run, "CVODE setup failed");
        return -1;
    }
    return 0;
}

static void free_solver(solver_t *sv)
{
    if (sv->mem != NULL) {
        CVodeFree(&sv->mem);
    }
    if (sv->LS != NULL) {
        SUNLinSolFree(sv->LS);
    }
    if (sv->J != NULL) {
        SUNMatDestroy(sv->J);
    }
    if (sv->y != NULL) {
        N_VDestroy(sv->y);
    }
    if (sv->atol != NULL) {
        N_VDestroy(sv->atol);
    }
    if (sv->ctx != NULL) {
        SUNContext_Free(&sv->ctx);
    }
}

/* An event at time t: the iteration, then CVODE re-initialised when the FMU asks (or always).
 * 1 if re-initialised, 0 if not, -1 on failure. */
static int handle_event(solver_t *sv, const imp_me_t *me, const settings_t *s, double t,
                        double *t_next)
{
    imp_event_info_t info;
    me->record(me->fmu, t, 1); /* the state at the event, before it */
    if (me->event_iteration(me->fmu, 0, &info) != 0) {
        imp_fail(me->run, "the event iteration failed at t = %.17g", t);
        return -1;
    }
    *t_next = info.t_next;
    const int asked = info.values_changed || info.nominals_changed;
    imp_event(me->run, t, asked ? "reinit-requested" : "event");
    int reinitialised = 0;
    if (asked || s->always) {
        if (me->get_states(me->fmu, N_VGetArrayPointer(sv->y),
                           (size_t)me->run->md.n_states) != 0 ||
            CVodeReInit(sv->mem, t, sv->y) < 0) {
            imp_fail(me->run, "re-initialisation failed at t = %.17g", t);
            return -1;
        }
        me->run->reinits++;
        reinitialised = 1;
    }
    CVodeSetStopTime(sv->mem, fmin(s->t_stop, *t_next)); /* the next time event or the end */
    return reinitialised;
}

/* From time t to the stop time, output point after output point. */
static void integrate(solver_t *sv, const imp_me_t *me, const settings_t *s, double t,
                      double t_next)
{
    imp_run_t *run = me->run;
    long k_out = 1;
    const double t0 = t;
    while (t < s->t_stop) {
        double t_out = t0 + (double)k_out * s->dt_out;
        if (t_out > s->t_stop || s->t_stop - t_out < 1e-9 * s->dt_out) {
            t_out = s->t_stop;
        }
        const int flag = CVode(sv->mem, t_out, sv->y, &t, CV_NORMAL);
        long nst = 0;
        CVodeGetNumSteps(sv->mem, &nst);
        if (flag < 0 || sv->data.failed) {
            imp_fail(run, "CVode failed with flag %d at t = %.17g", flag, t);
            return;
        }
        if (set_time_state(me, t, sv->y) != 0) {
            imp_fail(run, "cannot set the state at t = %.17g", t);
            return;
        }
        run->t_reached = t;
        int enter = 0, terminate = 0;
        if (me->completed_integrator_step(me->fmu, &enter, &terminate) != 0 || terminate) {
            imp_fail(run, "%s failed or asked to terminate", me->completed_call);
            return;
        }
        int reinitialised = 0;
        if (flag == CV_ROOT_RETURN || enter || t >= t_next) {
            if ((reinitialised = handle_event(sv, me, s, t, &t_next)) < 0) {
                return;
            }
        } else {
            me->record(me->fmu, t, 1);
            k_out++;
        }
        if (run->steps + nst > run->opt.max_steps) {
            imp_fail(run, "budget: more than %ld steps", run->opt.max_steps);
            return;
        }
        if (reinitialised || t >= s->t_stop) {
            run->steps += nst; /* CVodeReInit restarts the count */
        }
    }
}

int imp_me_cvode(const imp_me_t *me, const char *program)
{
    settings_t s;
    const int bad = read_settings(me, program, &s);
    if (bad != 0) {
        return bad;
    }
    solver_t sv;
    memset(&sv, 0, sizeof(sv));
    sv.data.me = me;
    imp_event_info_t info;
    if (me->run->md.n_states < 1 || me->initialize(me->fmu, s.rtol) != 0) {
        imp_fail(me->run, "initialization failed (or the FMU has no states)");
    } else if (me->event_iteration(me->fmu, 1, &info) != 0) { /* in Event Mode already */
        imp_fail(me->run, "the initial event iteration failed");
    } else if (create_solver(&sv, me, me->run->t_reached, s.rtol) == 0) {
        /* no stop at the output points (CVODE interpolates there): at the end and time events */
        CVodeSetStopTime(sv.mem, fmin(s.t_stop, info.t_next));
        me->record(me->fmu, me->run->t_reached, 1);
        integrate(&sv, me, &s, me->run->t_reached, info.t_next);
    }
    free_solver(&sv);
    return me->close(me->fmu);
}
