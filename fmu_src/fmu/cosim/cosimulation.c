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
 * (fmu_model.default_tolerance when none is given), absolute = relative x the nominal value of
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
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cosimulation.h"
#include "integration.h"

#define NX fmu_model.n_states
#define MAX_EVENTS_PER_STEP 1000000L  /* guards against an endless chain of events */
#ifndef MAX_STEPS_PER_CALL
#define MAX_STEPS_PER_CALL 500000L    /* integrator steps per fmi2DoStep (the fuzz build lowers it) */
#endif

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
    const double tn = integration_time(cs);
    double after = cs->origin + tn;
    for (int i = 0; i < 8; i++) { /* events that round to CVODE's current time are behind it */
        const double te = fmu_model.next_time_event(inst->model, after);
        if (!isfinite(te)) {
            return FMU_OK;
        }
        if (te - cs->origin > tn) {
            return integration_stop_time(cs, te - cs->origin);
        }
        after = te;
    }
    return FMU_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the communication step */

/* One communication step being taken: its ends (the FMU's times and the local ones) and what
 * its loop has counted. */
typedef struct {
    double now_abs, t_end_abs;
    double now, t_end;
    long events, steps;
    long warnings; /* the integrator's warnings before it */
} comm_step_t;

/* The state at t_end from the last step, which reaches past it (and may hold a root there). */
static int interpolate_to_end(fmu_instance_t *inst, const comm_step_t *c, double *tret)
{
    cs_integration_t *cs = inst->integration;
    const int flag = integration_dense(cs, c->t_end, 0, cs->y) < 0 ? STEP_FAILED : STEP_OK;
    if (flag == STEP_FAILED) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                "%s: the interpolant of %s does not reach t = %.17g", inst->step_function,
                cs->current->ops->name, c->t_end_abs);
    }
    *tret = c->t_end;
    return flag;
}

/* One internal step of the integrator (or the next root inside its last step). auto decides at
 * the end of every step, also of one that reaches the communication point, and switches there
 * (at once, or in the communication step that contains it): its decisions do not depend on the
 * grid. A root, time event or switch beyond t_end is kept pending. STEP_ABORTED: no stop time
 * could be set (logged). */
static int new_step(fmu_instance_t *inst, const comm_step_t *c, double *tret)
{
    cs_integration_t *cs = inst->integration;
    if (fmu_model.next_time_event != NULL && set_time_event_stop(inst) != FMU_OK) {
        return STEP_ABORTED;
    }
    int flag = integration_step(cs, tret);
    if (flag == STEP_OK && cs->method->stiff != NULL && *tret >= c->t_end) {
        const cs_integrator_ops_t *method = integration_auto_choice(inst, *tret);
        if (method != cs->current->ops) {
            flag = STEP_SWITCH;
            cs->switch_to = method;
        }
    }
    if (flag != STEP_FAILED && *tret > c->t_end) {
        if (flag != STEP_OK) {
            memcpy(cs->y_root, cs->y, NX * sizeof(double));
            cs->t_root = *tret;
            cs->root_pending = flag;
        }
        flag = integration_dense(cs, c->t_end, 0, cs->y) < 0 ? STEP_FAILED : STEP_OK;
        *tret = c->t_end;
    }
    return flag;
}

/* One pass of the loop: from (tret, cs->y) to the next point, a pending root of the last
 * communication step, the communication point inside the last step, or a new step's end or
 * root. One internal step per pass: the solution is taken at every step, and auto can check
 * the stiffness without waiting for the end of the communication step. No stop time: the
 * communication points do not cut the integrator's steps short. A step that ends beyond t_end
 * is not repeated: the state at t_end comes from the interpolant (for this and for later
 * communication points the step covers), and a root reported beyond t_end is kept pending
 * until the communication step that contains it. */
static int advance(fmu_instance_t *inst, const comm_step_t *c, double *tret)
{
    cs_integration_t *cs = inst->integration;
    if (cs->root_pending && cs->t_root <= c->t_end) {
        memcpy(cs->y, cs->y_root, NX * sizeof(double));
        *tret = cs->t_root;
        const int flag = cs->root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH */
        cs->root_pending = 0;
        return flag;
    }
    if (cs->root_pending || integration_time(cs) >= c->t_end) {
        return interpolate_to_end(inst, c, tret);
    }
    return new_step(inst, c, tret);
}

/* The integrator failed (its message and flag are in the log); it returns the last successful
 * point in (tret, y): keep it, so that what the master reads is consistent (time, state,
 * discrete state), never a half-taken step. */
static fmu_status_t step_failed(fmu_instance_t *inst, const comm_step_t *c, double tret)
{
    const double *y = inst->integration->y;
    int finite = isfinite(tret) && tret >= c->now && tret <= c->t_end;
    for (int i = 0; i < NX; i++) {
        finite = finite && isfinite(y[i]);
    }
    if (finite) {
        integration_take_solution(inst, tret);
    }
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
            "%s: the step from t = %.17g to %.17g failed; the FMU holds the last "
            "successful state, at t = %.17g", inst->step_function,
            c->now_abs, c->t_end_abs, *fmu_time(inst));
    inst->restart_integration = 1;
    return FMU_ERROR;
}

/* A root: the event update (its kind, 0 if the discrete state did not change; -1: too many
 * events, logged). */
static int event_at(fmu_instance_t *inst, comm_step_t *c, double tret)
{
    if (++c->events > MAX_EVENTS_PER_STEP) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                "%s: more than %ld events in one step at t = %.17g", inst->step_function,
                MAX_EVENTS_PER_STEP, *fmu_time(inst));
        return -1;
    }
    const int kind = fmu_event_update(inst);
    if (kind != 0) {
        cs_integration_t *cs = inst->integration;
        integration_forget_live(cs); /* what follows the event has a new dense output */
        kept_event(&cs->kept, tret);
    }
    return kind;
}

/* Restart the method's first integrator at an event of `kind` (0: a time event). RK45 starts
 * with the step that suited the last event of this kind: the first-step estimate, made for
 * smooth solutions, overshoots at a contact onset (the force grows as the indentation^1.5) by
 * orders of magnitude, and the rejected attempts cost 6 evaluations each. */
static fmu_status_t restart_at_event(cs_integration_t *cs, int kind, double tret)
{
    const int code = kind > 0 && kind < FMU_EVENT_KINDS ? kind : 0;
    cs->hint_code = code;
    const fmu_status_t s =
        integration_restart(cs, cs->method->start, tret, code > 0 ? cs->event_h[code] : 0.0);
    integration_segment(cs, tret);
    return s;
}

/* auto's decision at the end of the step (made already for a step that reached the
 * communication point: STEP_SWITCH), and the new integrator from the current point (cs->y at
 * tret is the step's end). */
static fmu_status_t auto_switch(fmu_instance_t *inst, int flag, double tret)
{
    cs_integration_t *cs = inst->integration;
    const cs_integrator_ops_t *method =
        flag == STEP_SWITCH ? cs->switch_to : integration_auto_choice(inst, tret);
    if (method == cs->current->ops) {
        return FMU_OK;
    }
    const fmu_status_t s = integration_restart(cs, method, tret, 0.0);
    cs->hint_code = 0;
    integration_window(cs, tret);
    integration_forget_live(cs);
    return s;
}

/* What follows a pass that reached tret: at a root the event update and, if the discrete state
 * changed, the restart; at a time event (the right-hand side's kink, see set_time_event_stop)
 * the restart; else auto's switch. *kind: the event's kind (0: none). */
static fmu_status_t after_pass(fmu_instance_t *inst, comm_step_t *c, int flag, double tret,
                               int *kind)
{
    cs_integration_t *cs = inst->integration;
    *kind = 0;
    int restart = 0;
    if (flag == STEP_ROOT) {
        *kind = event_at(inst, c, tret);
        if (*kind < 0) {
            return FMU_ERROR;
        }
        restart = *kind != 0;
    } else if (flag == STEP_TSTOP) {
        restart = 1;
        integration_forget_live(cs);
    }
    if (restart) {
        return restart_at_event(cs, *kind, tret);
    }
    return cs->method->stiff != NULL ? auto_switch(inst, flag, tret) : FMU_OK;
}

/* The first step after an event: remember where the step-size control went. */
static void remember_first_step(cs_integration_t *cs, int stepped)
{
    if (cs->hint_code > 0 && stepped && cs->current->ops->next_step != NULL) {
        cs->event_h[cs->hint_code] = cs->current->ops->next_step(cs->current->self);
        cs->hint_code = 0;
    }
}

static fmu_status_t too_many_steps(fmu_instance_t *inst, const comm_step_t *c)
{
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
            "%s: more than %ld %s steps in the step from t = %.17g to %.17g; "
            "the FMU holds the state at t = %.17g", inst->step_function,
            MAX_STEPS_PER_CALL, inst->integration->current->ops->name, c->now_abs, c->t_end_abs,
            *fmu_time(inst));
    inst->restart_integration = 1;
    return FMU_ERROR;
}

/* The integration ready for a communication step from the FMU's time: (re)started where it
 * must be, the communication step begun for the model's analysis. */
static fmu_status_t begin_comm_step(fmu_instance_t *inst, double t_end_abs, comm_step_t *c)
{
    if (inst->integration == NULL || inst->restart_integration) {
        if (integration_start(inst) != FMU_OK) {
            return FMU_ERROR;
        }
        inst->restart_integration = 0;
        integration_forget_live(inst->integration); /* a new dense output */
        kept_clear(&inst->integration->kept);
    }
    cs_integration_t *cs = inst->integration;
    const comm_step_t begun = {*fmu_time(inst), t_end_abs, *fmu_time(inst) - cs->origin,
                               t_end_abs - cs->origin, 0, 0, cs->warnings};
    *c = begun;
    if (fmu_model.comm_step_begins != NULL) {
        fmu_model.comm_step_begins(inst->model, inst->outputs_valid);
    }
    cs->comm_start = c->now;
    kept_drop(&cs->kept, c->now); /* the kept steps that ended before: their outputs were not read */
    return FMU_OK;
}

fmu_status_t cs_do_step(fmu_instance_t *inst, double t_end_abs, int stop_at_event, int *stopped)
{
    if (stopped != NULL) {
        *stopped = 0;
    }
    if (NX == 0) {
        return finish_step(inst, t_end_abs, FMU_OK); /* no continuous states: nothing to integrate */
    }
    comm_step_t c;
    if (begin_comm_step(inst, t_end_abs, &c) != FMU_OK) {
        return FMU_ERROR;
    }
    cs_integration_t *cs = inst->integration;
    double tret = c.now;
    while (tret < c.t_end) {
        const double tret_before = tret;
        const int flag = advance(inst, &c, &tret);
        if (flag == STEP_ABORTED) {
            inst->restart_integration = 1;
            return FMU_ERROR;
        }
        const long added = integration_count_steps(inst);
        const int stepped = added > 0; /* a new step (not a second root inside the last one) */
        c.steps += added;
        remember_first_step(cs, stepped);
        if (flag == STEP_FAILED) {
            return step_failed(inst, &c, tret);
        }
        integration_analyse_live(inst, tret_before, tret, stepped);
        integration_take_solution(inst, tret);
        if (flag == STEP_OK && tret >= c.t_end) {
            break;
        }
        if (c.steps > MAX_STEPS_PER_CALL) {
            return too_many_steps(inst, &c);
        }
        int kind = 0;
        if (after_pass(inst, &c, flag, tret, &kind) != FMU_OK) {
            inst->restart_integration = 1;
            return FMU_ERROR;
        }
        if (stop_at_event && kind != 0) {
            /* early return (FMI 3.0): the step ends at the contact event, handled, with the
             * integrator restarted there; the FMU's time is the event time (take_solution) */
            *stopped = 1;
            return cs->warnings > c.warnings ? FMU_WARNING : FMU_OK;
        }
    }
    /* the integrator warned (logged): the step is done, with a caveat */
    return finish_step(inst, t_end_abs, cs->warnings > c.warnings ? FMU_WARNING : FMU_OK);
}

const fmu_stepper_t cs_stepper = {cs_free, cs_reset, cs_flush};
