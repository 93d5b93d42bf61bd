/* Co-simulation: fmi2DoStep integrates the model with an integrator inside the FMU (SUNDIALS
 * CVODE, or our explicit Runge-Kutta 5(4), ../../solvers/rk45.c; both behind the interface of
 * integrator.h) and locates every event inside the step by root finding on the model-exchange
 * event indicators (csfh: the gap, so every contact onset and release). At each root the discrete
 * state is updated (csfh: the onset indentation rate is captured) and the integrator is
 * restarted; the step then continues to its end, however many events it holds. The communication
 * points do not cut the integrator's steps short: it may step past the end of a communication
 * step, the FMU's state there is its interpolant (to the same tolerance), and the next fmi2DoStep
 * goes on from the integrator's internal state, so a fine communication grid costs no extra
 * integration steps.
 *
 * Method (fmu_model.cs_method; csfh: parameter solver.method):
 *   BDF    CVODE: BDF with Newton iteration, dense direct linear solver, difference-quotient
 *          Jacobian;
 *   Adams  CVODE: Adams-Moulton with fixed-point iteration: no Jacobian and no linear algebra;
 *   RK45   explicit Runge-Kutta 5(4) of Dormand and Prince: 6 right-hand sides per step and
 *          almost no bookkeeping, dense output and root finding on it; the cheapest choice while
 *          the motion is not stiff (flight, impacts resolved in time);
 *   auto   RK45, and BDF where the motion is stiff (auto_policy.h); every event restarts with
 *          RK45.
 *
 * Inputs are held constant over the communication step (zero-order hold); a changed input value,
 * a changed state or tunable parameter, and fmi2Get/SetFMUstate restart the integrator at the
 * communication point, so that its history never reaches across a discontinuity of the
 * right-hand side. Tolerances: relative = the fmi2SetupExperiment tolerance
 * (FMU_DEFAULT_TOLERANCE = 1e-6 when none is given), absolute = relative x the nominal value of
 * each state.
 *
 * A failure of the integrator returns FMU_ERROR with its own message and return flag in the
 * log; the instance then holds the last state it reached successfully, at that time (also
 * reported by fmi2GetRealStatus(fmi2LastSuccessfulTime)); fmi2SetFMUstate can roll it back.
 *
 * Time: the integrator runs in a local time tau = t - origin, measured from a time origin the
 * instance holds (the communication point where it was last started from outside: first step,
 * changed input, state or parameter, FMU state taken or restored; never moved at events). The
 * integration, its step sizes and its root finding are then the same whatever the start time: a
 * run from t0 = 1e10 s reproduces the run from 0, shifted, where an integrator in the absolute
 * time could not resolve its steps (ulp(1e10) = 1.9e-6 s) and drifted. A communication point
 * maps to tau exactly (t_end - origin, both multiples of ulp(origin) near the origin). CVODE's
 * own warnings (e.g. "t + h = t" after a very long run) make fmi2DoStep return fmi2Warning;
 * fmi2DoStep itself (fmu_instance.c: fmu_check_step) reports steps that the double time cannot
 * resolve.
 *
 * Work per step and per communication point: the outputs are not computed at the end of a step
 * but when they are read (fmi2GetReal, fmu_update_outputs), the event message is formatted only
 * when logEvents is on, and the peak outputs cost nothing outside the contact mode.
 *
 * FMI types: none. cs_do_step uses only the instance (fmu_instance.h: the model, the log, its own
 * status type), the integrator interface and the kept steps: the FMI 2.0 and FMI 3.0
 * front-ends (fmi2_glue.c, fmi3_glue.c) call the same cs_do_step; FMI 3.0's early return is its
 * stop_at_event option (the step ends at the first contact onset or release).
 *
 * A model without continuous states (the comb-drive actuator) just advances its time. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cosimulation.h"
#include "fmu_instance.h"
#include "auto_policy.h"
#include "integrator.h"
#include "kept_steps.h"

#define NX fmu_model.n_states
#define MAX_EVENTS_PER_STEP 1000000L  /* guards against an endless chain of events */
#ifndef MAX_STEPS_PER_CALL
#define MAX_STEPS_PER_CALL 500000L    /* integrator steps per fmi2DoStep (the fuzz build lowers it) */
#endif
#define FIRST_STEP_HORIZON 1.0        /* s: bound of the first step after a (re)start (see cs_do_step) */
#define FMU_EVENT_KINDS 8             /* the first-step memory: event_update codes 1..7 */

/* what one pass of cs_do_step's loop reached: the end of a step, a root, a time event (the
 * integrator's stop time), auto's switch of method at the end of a step (kept pending when that
 * lies beyond the communication point, like a root there), or a failure */
enum {
    STEP_OK = CS_STEP_OK,
    STEP_ROOT = CS_STEP_ROOT,
    STEP_TSTOP = CS_STEP_TSTOP,
    STEP_SWITCH = 3,
    STEP_FAILED = CS_STEP_FAILED
};

/* An integrator of the run, made when it first runs and kept (CVODE's memory while RK45 runs). */
typedef struct {
    const cs_integrator_ops_t *ops;
    void *self;
} integrator_t;

/* The methods of fmu_model.cs_method: the integrator each one starts with (and restarts with at
 * every event), and the one auto takes where the motion is stiff (NULL: no switching). */
typedef struct {
    const cs_integrator_ops_t *start, *stiff;
} method_t;

static const method_t METHODS[] = {
    [FMU_CS_AUTO] = {&cs_integrator_rk45, &cs_integrator_bdf},
    [FMU_CS_BDF] = {&cs_integrator_bdf, NULL},
    [FMU_CS_ADAMS] = {&cs_integrator_adams, NULL},
    [FMU_CS_RK45] = {&cs_integrator_rk45, NULL},
};

/* the integrators a run can use (one of each: a restored FMU state may bring another method) */
#define N_INTEGRATORS 3

struct cs_integration {
    integrator_t integrators[N_INTEGRATORS];
    integrator_t *current;  /* the integrator running */
    const method_t *method; /* the configured method (at the last start from outside) */
    cs_problem_t problem;   /* what every integrator solves (rhs, roots: the model) */
    double *abstol;         /* absolute tolerances (NX) */
    /* the first step after an event of each kind (the model's event_update code): what the
     * step-size control proposed after the first step that followed the last such event, 0 if
     * none since the last restart from outside; hint_code: the kind of the last event, until its
     * segment's first step is taken */
    double event_h[FMU_EVENT_KINDS];
    int hint_code;
    double *y;              /* the integrator's solution at the time it returned (NX) */
    double tolerance;       /* the relative tolerance the solver was set up with */
    double *y_root;   /* a root (or time event) reported beyond the end of the last */
    double t_root;    /* communication step: the state there and its time, */
    int root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH, handled in the communication
                         step that contains it (0: none) */
    const cs_integrator_ops_t *switch_to; /* STEP_SWITCH pending: the integrator auto chose at t_root */
    long counted_steps; /* steps since the last (re)start already added to the model's counter */
    cs_auto_t automatic;    /* auto's policy (auto_policy.h) */
    /* the model's analysis of the steps (analyse_live, kept_steps.h) */
    double comm_start;        /* the communication step being taken: (comm_start, FMU time] */
    void *live_memory;        /* the model's memory of the live steps (step_memory bytes) */
    kept_steps_t kept;
    double origin;      /* s: the integrator's time 0 (see the top of this file); its times are local */
    long warnings;      /* CVODE warnings so far (integrator_message) */
    double arrays[];    /* y, abstol, y_root: one block with the struct */
};

/* ------------------------------------------------------------------------------------------ */
/* the model as the integrators see it, and where their messages go */

static int rhs(double t, const double *y, double *ydot, void *host)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    /* the model's time at the integrator's local time t (a time-dependent model: the shock
     * pulse) */
    const int status = fmu_model.derivatives(inst->model, inst->integration->origin + t, y, ydot);
    return status == FMU_MODEL_NONFINITE ? 1 : 0; /* recoverable: the integrator retries a smaller step */
}

static int roots(double t, const double *y, double *gout, void *host)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    (void)t;
    fmu_model.event_indicators(inst->model, y, gout);
    for (int i = 0; i < fmu_model.n_event_indicators; i++) {
        if (!isfinite(gout[i])) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: non-finite event indicator z[%d] = %g",
                    inst->step_function, i, gout[i]);
            return 1; /* the integrator fails the step */
        }
    }
    return 0;
}

static void integrator_message(void *host, int warning, const char *module, const char *function,
                               const char *text)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    if (!warning) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s %s: %s", module, function, text);
        return;
    }
    if (inst->integration != NULL) {
        inst->integration->warnings++; /* the step returns a warning */
    }
    fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING, "%s %s (local time from t0 = %.17g): %s",
            module, function, inst->integration != NULL ? inst->integration->origin : 0.0, text);
}

static void integrator_failed(void *host, const char *call, const char *flag)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: %s failed with %s at t = %.17g",
            inst->step_function, call, flag, *fmu_time(inst));
}

static void integrator_error(void *host, const char *what)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: %s", inst->step_function, what);
}

void cs_free(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    if (cs == NULL) {
        return;
    }
    for (int i = 0; i < N_INTEGRATORS; i++) {
        if (cs->integrators[i].ops != NULL) {
            cs->integrators[i].ops->free(cs->integrators[i].self);
        }
    }
    kept_free(&cs->kept);
    free(cs->live_memory);
    free(cs);
    inst->integration = NULL;
}

/* ------------------------------------------------------------------------------------------ */
/* the integrator in use (times are local, see the top of this file) */

static double solver_time(const cs_integration_t *cs)
{
    return cs->current->ops->time(cs->current->self);
}

static int solver_dense(const cs_integration_t *cs, double t, int k, double *out)
{
    return cs->current->ops->dense(cs->current->self, t, k, out);
}

/* The integrator `ops` of the run, made when it first runs: NULL if it cannot be (reported). */
static integrator_t *integrator_of(cs_integration_t *cs, const cs_integrator_ops_t *ops)
{
    for (int i = 0; i < N_INTEGRATORS; i++) {
        integrator_t *it = &cs->integrators[i];
        if (it->ops == ops) {
            return it;
        }
        if (it->ops == NULL) {
            it->self = ops->create(&cs->problem);
            it->ops = it->self != NULL ? ops : NULL;
            return it->self != NULL ? it : NULL;
        }
    }
    return NULL; /* (every slot holds another integrator: not with N_INTEGRATORS) */
}

/* (Re)start the integrator `ops` at the local time tau from the state in cs->y, with the first
 * step h_first if > 0 and the integrator takes a hint (else its estimate): no steps counted yet,
 * no pending root. */
static fmu_status_t solver_start(cs_integration_t *cs, const cs_integrator_ops_t *ops, double tau,
                                 double h_first)
{
    integrator_t *it = integrator_of(cs, ops);
    if (it == NULL) {
        return FMU_ERROR;
    }
    cs->current = it;
    cs->counted_steps = 0;
    cs->root_pending = 0;
    return ops->start(it->self, tau, cs->y, h_first) == 0 ? FMU_OK : FMU_ERROR;
}

/* One internal step (or the next root inside the last one): STEP_OK, STEP_ROOT, STEP_TSTOP or
 * STEP_FAILED (logged); (tret, cs->y) is the point reached, on failure the last successful one. */
static int solver_step(cs_integration_t *cs, double *tret)
{
    return cs->current->ops->step(cs->current->self, tret, cs->y);
}

/* The next stop time (local; > the integrator's current time): no step goes beyond it. */
static fmu_status_t solver_set_stop_time(cs_integration_t *cs, double tau_stop)
{
    return cs->current->ops->set_stop_time(cs->current->self, tau_stop) == 0 ? FMU_OK : FMU_ERROR;
}

/* ------------------------------------------------------------------------------------------ */
/* auto (auto_policy.h) over the integrators of the method */

/* A new window of steps (the integrator's counters restart with every (re)start). */
static void start_window(cs_integration_t *cs, double t)
{
    cs_counts_t c;
    cs->current->ops->counts(cs->current->self, &c);
    cs_auto_window(&cs->automatic, &c, t);
}

/* A new segment of smooth motion (start, event, restart): no trial, no hold-off. */
static void start_segment(cs_integration_t *cs, double t)
{
    cs_counts_t c;
    cs->current->ops->counts(cs->current->self, &c);
    cs_auto_segment(&cs->automatic, &c, t);
}

/* auto: at the end of each step (t: the local time), the integrator for what follows; writes
 * what it decided to `why` (empty when nothing changes). */
static const cs_integrator_ops_t *auto_choose(cs_integration_t *cs, double t, char *why,
                                              size_t why_size)
{
    why[0] = '\0';
    const cs_integrator_ops_t *running = cs->current->ops;
    cs_counts_t c;
    running->counts(cs->current->self, &c);
    char text[200];
    const int choice = cs_auto_step_end(&cs->automatic, &c, t, running->name,
                                        running == cs->method->stiff, cs->method->start->name,
                                        text, sizeof(text));
    if (text[0] != '\0') {
        snprintf(why, why_size, "t = %.17g: %s", cs->origin + t, text);
    }
    return choice == CS_AUTO_STIFF      ? cs->method->stiff
           : choice == CS_AUTO_NONSTIFF ? cs->method->start
                                        : running;
}

/* ------------------------------------------------------------------------------------------ */
/* Create the integration (first step) or restart it at the current state, with the configured
 * method (auto starts with RK45); the FMU's time becomes the origin of the local time. */

static const method_t *configured_method(const fmu_instance_t *inst)
{
    const int m = fmu_model.cs_method != NULL ? fmu_model.cs_method(inst->model) : FMU_CS_BDF;
    return &METHODS[m >= 0 && m < (int)(sizeof(METHODS) / sizeof(METHODS[0])) ? m : FMU_CS_BDF];
}

/* The integration's memory, with the absolute tolerances (relative x the nominal value of each
 * state) and the problem every integrator solves; NULL when out of memory (logged). */
static cs_integration_t *integration_new(fmu_instance_t *inst)
{
    cs_integration_t *cs =
        (cs_integration_t *)calloc(1, sizeof(*cs) + 3 * (size_t)NX * sizeof(double));
    void *live_memory = fmu_model.step_memory > 0 ? calloc(1, fmu_model.step_memory) : NULL;
    if (cs == NULL || (fmu_model.step_memory > 0 && live_memory == NULL)) {
        free(cs);
        free(live_memory);
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: out of memory", inst->step_function);
        return NULL;
    }
    cs->live_memory = live_memory;
    cs->tolerance = inst->tolerance;
    double *p = cs->arrays;
    cs->y = p, p += NX;
    cs->abstol = p, p += NX;
    cs->y_root = p;
    int k = 0;
    for (int i = 0; i < fmu_model.n_variables && k < NX; i++) {
        if (fmu_model.variables[i].is_state) {
            cs->abstol[k++] = inst->tolerance * fmu_model.variables[i].nominal;
        }
    }
    const cs_problem_t problem = {
        NX, fmu_model.n_event_indicators, inst->tolerance, cs->abstol, FIRST_STEP_HORIZON,
        rhs, roots, integrator_message, integrator_failed, integrator_error, inst};
    cs->problem = problem;
    return cs;
}

static fmu_status_t cs_start(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    if (cs != NULL && cs->tolerance != inst->tolerance) {
        cs_free(inst);
        cs = NULL;
    }
    if (cs == NULL) {
        cs = integration_new(inst);
        if (cs == NULL) {
            return FMU_ERROR;
        }
        inst->integration = cs;
    }
    cs->method = configured_method(inst);
    memcpy(cs->y, fmu_states(inst), NX * sizeof(double));
    cs->origin = *fmu_time(inst);
    memset(cs->event_h, 0, sizeof(cs->event_h)); /* a start from outside: no memory of events */
    cs->hint_code = 0;
    const fmu_status_t s = solver_start(cs, cs->method->start, 0.0, 0.0);
    if (s != FMU_OK) {
        cs_free(inst);
        return s;
    }
    start_segment(cs, 0.0);
    return s;
}

/* Add the steps taken since the last call to the model's step counter. */
static long count_steps(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    cs_counts_t c;
    cs->current->ops->counts(cs->current->self, &c);
    const long added = c.steps - cs->counted_steps;
    cs->counted_steps = c.steps;
    if (fmu_model.add_integrator_steps != NULL && added != 0) {
        fmu_model.add_integrator_steps(inst->model, added);
    }
    return added;
}

/* ------------------------------------------------------------------------------------------ */
/* the model's analysis of the steps (fmu_model.analyse_step; csfh: the peak outputs): the steps
 * of an integrator that can save them are kept (kept_steps.h) and handed over when the model's
 * outputs are needed; the others are handed over live, at every pass of cs_do_step's loop */

/* The live step as the model sees it (fmu_step_t first: its calls come back with it). */
typedef struct {
    fmu_step_t step;
    fmu_instance_t *inst;
    double from; /* where the communication step had got to before it */
} live_view_t;

static int live_dense(const fmu_step_t *step, double t, int k, double *out)
{
    const live_view_t *v = (const live_view_t *)(const void *)step;
    return solver_dense(v->inst->integration, t, k, out);
}

static int live_keep(const fmu_step_t *step)
{
    const live_view_t *v = (const live_view_t *)(const void *)step;
    cs_integration_t *cs = v->inst->integration;
    return kept_keep(&cs->kept, v->inst->model, cs->current->ops, cs->current->self,
                     cs->comm_start, v->from, v->inst->tolerance);
}

/* Forget the live step (the integrator restarted: a new dense output). */
static void forget_live(cs_integration_t *cs)
{
    if (cs->live_memory != NULL) {
        memset(cs->live_memory, 0, fmu_model.step_memory);
    }
}

/* The part [ta, tb] of the communication step, the state at tb in cs->y; `stepped`: the
 * integrator took a new step to get there (tb is its end unless a root or the communication
 * point came first). */
static void analyse_live(fmu_instance_t *inst, double ta, double tb, int stepped)
{
    cs_integration_t *cs = inst->integration;
    if (fmu_model.analyse_step == NULL) {
        return;
    }
    const integrator_t *it = cs->current;
    const double tn = it->ops->time(it->self), hu = it->ops->last_step(it->self);
    const fmu_step_t step = {1, stepped, tn - hu, tn, hu, tn, inst->tolerance, live_dense,
                             NULL, NULL, tb == tn ? cs->y : NULL, NULL, NULL, cs->live_memory,
                             NULL, it->ops->save_step != NULL ? live_keep : NULL};
    const live_view_t v = {step, inst, ta};
    fmu_model.analyse_step(inst->model, &v.step, ta, tb);
}

void cs_flush(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    if (cs == NULL || cs->kept.n == 0 || NX == 0) {
        return;
    }
    const double now = *fmu_time(inst) - cs->origin;
    kept_analyse(&cs->kept, inst->model, cs->comm_start, now, inst->tolerance);
    /* what ends by now is done for this communication step, but the next one may need the
     * last of them */
    kept_drop(&cs->kept, now);
}

/* Take the integrator's solution (local time tret, cs->y) as the model's time and state. */
static void take_solution(fmu_instance_t *inst, double tret)
{
    memcpy(fmu_states(inst), inst->integration->y, NX * sizeof(double));
    *fmu_time(inst) = inst->integration->origin + tret;
    fmu_invalidate(inst);
}

/* The step ends at t_end. The outputs are left to be computed when they are read
 * (fmu_update_outputs: fmi2GetReal, or the next step's peaks), so that a master that reads only
 * states pays nothing for them. */
static fmu_status_t finish_step(fmu_instance_t *inst, double t_end, fmu_status_t status)
{
    *fmu_time(inst) = t_end; /* exact communication point (tret == t_end up to round-off) */
    fmu_invalidate(inst);
    return status;
}

/* ------------------------------------------------------------------------------------------ */
/* time events (fmu_model.next_time_event; csfh: the start and end of the shock pulse, where the
 * right-hand side has a kink): the integrator is given the next one as its stop time, so that no
 * step straddles it; it returns STEP_TSTOP there, and cs_do_step restarts it as at a state
 * event. Without time events nothing here is called. */

static fmu_status_t set_time_event_stop(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    const double tn = solver_time(cs);
    double after = cs->origin + tn;
    for (int i = 0; i < 8; i++) { /* events that round to CVODE's current time are behind it */
        const double te = fmu_model.next_time_event(inst->model, after);
        if (!isfinite(te)) {
            return FMU_OK;
        }
        if (te - cs->origin > tn) {
            return solver_set_stop_time(cs, te - cs->origin);
        }
        after = te;
    }
    return FMU_OK;
}

/* auto's decision at the local time t (logged when it changes something): the method for what
 * follows. */
static const cs_integrator_ops_t *auto_next_method(fmu_instance_t *inst, double t)
{
    char why[256];
    const cs_integrator_ops_t *method = auto_choose(inst->integration, t, why, sizeof(why));
    if (why[0] != '\0') {
        fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", why);
    }
    return method;
}

fmu_status_t cs_do_step(fmu_instance_t *inst, double t_end_abs, int stop_at_event, int *stopped)
{
    const double now_abs = *fmu_time(inst);
    if (stopped != NULL) {
        *stopped = 0;
    }
    if (NX == 0) {
        return finish_step(inst, t_end_abs, FMU_OK); /* no continuous states: nothing to integrate */
    }
    if (inst->integration == NULL || inst->restart_integration) {
        if (cs_start(inst) != FMU_OK) {
            return FMU_ERROR;
        }
        inst->restart_integration = 0;
        forget_live(inst->integration); /* a new dense output */
        kept_clear(&inst->integration->kept);
    }
    cs_integration_t *cs = inst->integration;
    const long warnings = cs->warnings;
    /* the integrator's local times (see the top of this file) */
    const double now = now_abs - cs->origin;
    const double t_end = t_end_abs - cs->origin;
    const int automatic = cs->method->stiff != NULL;
    long events = 0, steps = 0;
    double tret = now;
    if (fmu_model.comm_step_begins != NULL) {
        fmu_model.comm_step_begins(inst->model, inst->outputs_valid);
    }
    cs->comm_start = now;
    kept_drop(&cs->kept, now); /* the kept steps that ended before: their outputs were not read */
    while (tret < t_end) {
        /* One internal step per call: the solution is taken at every step, and auto can check
         * the stiffness without waiting for the end of the communication step. No stop time:
         * the communication points do not cut the integrator's steps short. A step that ends
         * beyond t_end is not repeated: the state at t_end comes from the interpolant (for this
         * and for later communication points the step covers), and a root reported beyond t_end
         * is kept pending until the communication step that contains it. */
        int flag;
        const double tret_before = tret;
        if (cs->root_pending && cs->t_root <= t_end) {
            memcpy(cs->y, cs->y_root, NX * sizeof(double));
            tret = cs->t_root;
            flag = cs->root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH */
            cs->root_pending = 0;
        } else if (cs->root_pending || solver_time(cs) >= t_end) {
            /* the last step (and the root check) already reaches past t_end */
            flag = solver_dense(cs, t_end, 0, cs->y) < 0 ? STEP_FAILED : STEP_OK;
            if (flag == STEP_FAILED) {
                fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                        "%s: the interpolant of %s does not reach t = %.17g", inst->step_function,
                        cs->current->ops->name, t_end_abs);
            }
            tret = t_end;
        } else {
            if (fmu_model.next_time_event != NULL && set_time_event_stop(inst) != FMU_OK) {
                inst->restart_integration = 1;
                return FMU_ERROR;
            }
            flag = solver_step(cs, &tret);
            if (flag == STEP_OK && automatic && tret >= t_end) {
                /* auto decides at the end of every step, also of one that reaches the
                 * communication point, and switches there (at once, or in the communication
                 * step that contains it): its decisions do not depend on the grid */
                const cs_integrator_ops_t *method = auto_next_method(inst, tret);
                if (method != cs->current->ops) {
                    flag = STEP_SWITCH;
                    cs->switch_to = method;
                }
            }
            if (flag != STEP_FAILED && tret > t_end) {
                if (flag != STEP_OK) { /* a root, time event or switch beyond t_end */
                    memcpy(cs->y_root, cs->y, NX * sizeof(double));
                    cs->t_root = tret;
                    cs->root_pending = flag;
                }
                flag = solver_dense(cs, t_end, 0, cs->y) < 0 ? STEP_FAILED : STEP_OK;
                tret = t_end;
            }
        }
        const long added = count_steps(inst);
        const int stepped = added > 0; /* a new step (not a second root inside the last one) */
        steps += added;
        if (cs->hint_code > 0 && stepped && cs->current->ops->next_step != NULL) {
            /* the first step after an event: remember where the step-size control went */
            cs->event_h[cs->hint_code] = cs->current->ops->next_step(cs->current->self);
            cs->hint_code = 0;
        }
        if (flag == STEP_FAILED) {
            /* the integrator's message and flag are in the log; it returns the last successful
             * point in (tret, y): keep it, so that what the master reads is consistent (time,
             * state, discrete state), never a half-taken step */
            const double *y = cs->y;
            int finite = isfinite(tret) && tret >= now && tret <= t_end;
            for (int i = 0; i < NX; i++) {
                finite = finite && isfinite(y[i]);
            }
            if (finite) {
                take_solution(inst, tret);
            }
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "%s: the step from t = %.17g to %.17g failed; the FMU holds the last "
                    "successful state, at t = %.17g", inst->step_function,
                    now_abs, t_end_abs, *fmu_time(inst));
            inst->restart_integration = 1;
            return FMU_ERROR;
        }
        analyse_live(inst, tret_before, tret, stepped);
        take_solution(inst, tret);
        if (flag == STEP_OK && tret >= t_end) {
            break;
        }
        if (steps > MAX_STEPS_PER_CALL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "%s: more than %ld %s steps in the step from t = %.17g to %.17g; "
                    "the FMU holds the state at t = %.17g", inst->step_function,
                    MAX_STEPS_PER_CALL, cs->current->ops->name, now_abs, t_end_abs,
                    *fmu_time(inst));
            inst->restart_integration = 1;
            return FMU_ERROR;
        }
        int restart = 0, kind = 0;
        if (flag == STEP_ROOT) {
            if (++events > MAX_EVENTS_PER_STEP) {
                fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                        "%s: more than %ld events in one step at t = %.17g", inst->step_function,
                        MAX_EVENTS_PER_STEP, *fmu_time(inst));
                inst->restart_integration = 1;
                return FMU_ERROR;
            }
            /* the discrete state changed: restart the integrator at the event (auto: with the
             * non-stiff method again) */
            kind = fmu_event_update(inst);
            restart = kind != 0;
            if (restart) {
                forget_live(cs); /* what follows the event has a new dense output */
                kept_event(&cs->kept, tret);
            }
        } else if (flag == STEP_TSTOP) {
            restart = 1; /* a time event: the right-hand side's kink (see set_time_event_stop) */
            forget_live(cs);
        }
        fmu_status_t s = FMU_OK;
        if (restart) {
            /* RK45 starts with the step that suited the last event of this kind: the first-step
             * estimate, made for smooth solutions, overshoots at a contact onset (the force
             * grows as the indentation^1.5) by orders of magnitude, and the rejected attempts
             * cost 6 evaluations each */
            const int code = kind > 0 && kind < FMU_EVENT_KINDS ? kind : 0;
            cs->hint_code = code;
            s = solver_start(cs, cs->method->start, tret, code > 0 ? cs->event_h[code] : 0.0);
            start_segment(cs, tret);
        } else if (automatic) {
            /* auto's decision at the end of the step (made already for a step that reached
             * the communication point: STEP_SWITCH) */
            const cs_integrator_ops_t *method =
                flag == STEP_SWITCH ? cs->switch_to : auto_next_method(inst, tret);
            if (method == cs->current->ops) {
                continue;
            }
            /* a new method from the current point (cs->y at tret is the step's end) */
            s = solver_start(cs, method, tret, 0.0);
            cs->hint_code = 0;
            start_window(cs, tret);
            forget_live(cs);
        } else {
            continue;
        }
        if (s != FMU_OK) {
            inst->restart_integration = 1;
            return FMU_ERROR;
        }
        if (stop_at_event && kind != 0) {
            /* early return (FMI 3.0): the step ends at the contact event, handled, with the
             * integrator restarted there; the FMU's time is the event time (take_solution) */
            *stopped = 1;
            return cs->warnings > warnings ? FMU_WARNING : FMU_OK;
        }
    }
    /* CVODE warned (logged by error_handler): the step is done, with a caveat */
    return finish_step(inst, t_end_abs, cs->warnings > warnings ? FMU_WARNING : FMU_OK);
}

fmu_status_t cs_reset(fmu_instance_t *inst)
{
    cs_free(inst);
    return FMU_OK;
}

const fmu_stepper_t cs_stepper = {cs_free, cs_flush};
