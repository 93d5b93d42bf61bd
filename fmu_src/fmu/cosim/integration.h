/* The integration of one co-simulation instance (integration.c), shared by the communication
 * step's loop (cosimulation.c): the integrators of the configured method (integrator.h), the
 * solution and the time origin, auto's policy (auto_policy.h), and the model's analysis of the
 * integrator steps (fmu_model.h: analyse_step; kept_steps.h). Times are local: measured from
 * the origin (cosimulation.c). */
#ifndef CSFH_INTEGRATION_H
#define CSFH_INTEGRATION_H

#include "auto_policy.h"
#include "csfh_visibility.h"
#include "fmu_instance.h"
#include "integrator.h"
#include "kept_steps.h"

CSFH_INTERNAL_BEGIN

#define FIRST_STEP_HORIZON 1.0 /* s: bound of the first step after a (re)start (cosimulation.c) */
#define FMU_EVENT_KINDS 8      /* the first-step memory: event_update codes 1..7 */

/* what one pass of cs_do_step's loop reached: the end of a step, a root, a time event (the
 * integrator's stop time), auto's switch of method at the end of a step (kept pending when that
 * lies beyond the communication point, like a root there), or a failure */
enum {
    STEP_OK = CS_STEP_OK,
    STEP_ROOT = CS_STEP_ROOT,
    STEP_TSTOP = CS_STEP_TSTOP,
    STEP_SWITCH = 3,
    STEP_FAILED = CS_STEP_FAILED,
    STEP_ABORTED = -2 /* (no integrator step: the loop stops with an error, logged) */
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

/* the integrators a run can use (one of each: a restored FMU state may bring another method) */
#define N_INTEGRATORS 3

/* The live step as the model sees it (fmu_step_t first: its calls come back with it). */
typedef struct {
    fmu_step_t step;
    fmu_instance_t *inst;
    double from; /* where the communication step had got to before it */
} live_view_t;

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
    int analytic;           /* and whether with the model's Jacobian (problem.jacobian) */
    double *y_root;   /* a root (or time event) reported beyond the end of the last */
    double t_root;    /* communication step: the state there and its time, */
    int root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH, handled in the communication
                         step that contains it (0: none) */
    const cs_integrator_ops_t *switch_to; /* STEP_SWITCH pending: the integrator auto chose at t_root */
    long counted_steps; /* steps since the last (re)start already added to the model's counter */
    long counted_jacobians; /* the same for the Jacobians formed */
    cs_auto_t automatic;    /* auto's policy (auto_policy.h) */
    /* the model's analysis of the steps (analyse_live, kept_steps.h) */
    double comm_start;        /* the communication step being taken: (comm_start, FMU time] */
    void *live_memory;        /* the model's memory of the live steps (step_memory bytes) */
    live_view_t live;         /* the last live step handed over (what stays is set once) */
    kept_steps_t kept;
    double origin;      /* s: the integrator's time 0 (cosimulation.c: time); its times are local */
    long warnings;      /* CVODE warnings so far (integrator_message) */
    /* the running integrator as its last start or step left it (integration_observe): the end
     * of its last step, that step's size and its counts; read many times per step */
    double tn, hu;
    cs_counts_t counts;
    double arrays[];    /* y, abstol, y_root: one block with the struct */
};

/* What the running integrator reports after a start or a step (cs->tn, hu, counts). */
static inline void integration_observe(cs_integration_t *cs)
{
    const integrator_t *it = cs->current;
    cs->tn = it->ops->time(it->self);
    cs->hu = it->ops->last_step(it->self);
    it->ops->counts(it->self, &cs->counts);
}

/* The end of the running integrator's last step (its start before one). */
static inline double integration_time(const cs_integration_t *cs)
{
    return cs->tn;
}

static inline int integration_dense(const cs_integration_t *cs, double t, int k, double *out)
{
    return cs->current->ops->dense(cs->current->self, t, k, out);
}

/* One internal step (or the next root inside the last one): STEP_OK, STEP_ROOT, STEP_TSTOP or
 * STEP_FAILED (logged); (tret, cs->y) is the point reached, on failure the last successful one. */
static inline int integration_step(cs_integration_t *cs, double *tret)
{
    const int flag = cs->current->ops->step(cs->current->self, tret, cs->y);
    integration_observe(cs);
    return flag;
}

/* The next stop time (local; > the integrator's current time): no step goes beyond it. */
static inline fmu_status_t integration_stop_time(cs_integration_t *cs, double tau_stop)
{
    return cs->current->ops->set_stop_time(cs->current->self, tau_stop) == 0 ? FMU_OK : FMU_ERROR;
}

/* Create the integration (first step) or restart it from outside at the current state, with
 * the configured method; the FMU's time becomes the origin of the local time. */
fmu_status_t integration_start(fmu_instance_t *inst);
/* (Re)start the integrator `ops` at tau from the state in cs->y (h_first: a first step, if it
 * takes one; 0: its estimate): no steps counted yet, no pending root. */
fmu_status_t integration_restart(cs_integration_t *cs, const cs_integrator_ops_t *ops, double tau,
                                 double h_first);
/* auto: a new window, a new segment of smooth motion (at t), and its choice at the end of a
 * step at t (logged when it changes something). */
void integration_window(cs_integration_t *cs, double t);
void integration_segment(cs_integration_t *cs, double t);
const cs_integrator_ops_t *integration_auto_choice(fmu_instance_t *inst, double t);
/* Add the steps taken since the last call to the model's step counter: how many. */
long integration_count_steps(fmu_instance_t *inst);
/* The model's analysis: forget the live step (the integrator restarted), and hand it the part
 * [ta, tb] of the communication step, the state at tb in cs->y (stepped: a new step). */
void integration_forget_live(cs_integration_t *cs);
void integration_analyse_live(fmu_instance_t *inst, double ta, double tb, int stepped);
/* Take the integrator's solution (local time tret, cs->y) as the model's time and state. */
void integration_take_solution(fmu_instance_t *inst, double tret);

CSFH_INTERNAL_END

#endif
