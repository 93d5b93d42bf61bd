/* The integration of one co-simulation instance (integration.h): the integrators of the
 * configured method behind the interface of integrator.h, made when each first runs and kept
 * (CVODE's memory while RK45 runs), the model as they see it (right-hand side, event indicators,
 * the time origin), where their messages go, auto's policy, and the model's analysis of the
 * steps taken live. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cosimulation.h"
#include "integration.h"

#define NX fmu_model.n_states

static const method_t METHODS[] = {
    [FMU_CS_AUTO] = {&cs_integrator_rk45, &cs_integrator_bdf},
    [FMU_CS_BDF] = {&cs_integrator_bdf, NULL},
    [FMU_CS_ADAMS] = {&cs_integrator_adams, NULL},
    [FMU_CS_RK45] = {&cs_integrator_rk45, NULL},
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

/* The model's Jacobian at the model's time of the integrator's local time t. */
static int jacobian(double t, const double *y, double *J, void *host)
{
    fmu_instance_t *inst = (fmu_instance_t *)host;
    const int status = fmu_model.state_jacobian(inst->model, inst->integration->origin + t, y, J);
    return status == FMU_MODEL_NONFINITE ? 1 : 0; /* recoverable: CVODE tries a smaller step */
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

/* The next step starts the integration afresh (integration_start) in this memory: the kept
 * steps are the last run's, and the integrators that a start does not make as new are freed
 * (CVODE's re-initialisation keeps settings, e.g. a stop time, a new CVODE has not). */
void cs_reset(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    if (cs == NULL) {
        return;
    }
    int kept = 0;
    for (int i = 0; i < N_INTEGRATORS; i++) {
        integrator_t it = cs->integrators[i];
        cs->integrators[i].ops = NULL;
        if (it.ops != NULL && !it.ops->start_is_new) {
            it.ops->free(it.self);
        } else if (it.ops != NULL) {
            cs->integrators[kept++] = it; /* integrator_of: the slots in use come first */
        }
    }
    cs->current = NULL;
    kept_clear(&cs->kept);
    inst->restart_integration = 1;
}

/* ------------------------------------------------------------------------------------------ */
/* the integrators of the run (times are local: cosimulation.c, time) */

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
fmu_status_t integration_restart(cs_integration_t *cs, const cs_integrator_ops_t *ops, double tau,
                                 double h_first)
{
    integrator_t *it = integrator_of(cs, ops);
    if (it == NULL) {
        return FMU_ERROR;
    }
    cs->current = it;
    cs->counted_steps = cs->counted_jacobians = 0;
    cs->root_pending = 0;
    const int started = ops->start(it->self, tau, cs->y, h_first);
    integration_observe(cs);
    return started == 0 ? FMU_OK : FMU_ERROR;
}

/* ------------------------------------------------------------------------------------------ */
/* auto (auto_policy.h) over the integrators of the method */

/* A new window of steps (the integrator's counters restart with every (re)start). */
void integration_window(cs_integration_t *cs, double t)
{
    cs_auto_window(&cs->automatic, &cs->counts, t);
}

/* A new segment of smooth motion (start, event, restart): no trial, no hold-off. */
void integration_segment(cs_integration_t *cs, double t)
{
    cs_auto_segment(&cs->automatic, &cs->counts, t);
}

/* auto: at the end of each step (t: the local time), the integrator for what follows; writes
 * what it decided to `why` (empty when nothing changes). */
static const cs_integrator_ops_t *auto_choose(cs_integration_t *cs, double t, char *why,
                                              size_t why_size)
{
    why[0] = '\0';
    const cs_integrator_ops_t *running = cs->current->ops;
    char text[200];
    const int choice = cs_auto_step_end(&cs->automatic, &cs->counts, t, running->name,
                                        running == cs->method->stiff, cs->method->start->name,
                                        text, sizeof(text));
    if (text[0] != '\0') {
        snprintf(why, why_size, "t = %.17g: %s", cs->origin + t, text);
    }
    return choice == CS_AUTO_STIFF      ? cs->method->stiff
           : choice == CS_AUTO_NONSTIFF ? cs->method->start
                                        : running;
}

/* auto's decision at the local time t (logged when it changes something): the method for what
 * follows. */
const cs_integrator_ops_t *integration_auto_choice(fmu_instance_t *inst, double t)
{
    char why[256];
    const cs_integrator_ops_t *method = auto_choose(inst->integration, t, why, sizeof(why));
    if (why[0] != '\0') {
        fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", why);
    }
    return method;
}


/* ------------------------------------------------------------------------------------------ */
/* Create the integration (first step) or restart it at the current state, with the configured
 * method (auto starts with RK45); the FMU's time becomes the origin of the local time. */

static const method_t *configured_method(const fmu_instance_t *inst)
{
    const int m = fmu_model.cs_method != NULL ? fmu_model.cs_method(inst->model) : FMU_CS_BDF;
    return &METHODS[m >= 0 && m < (int)(sizeof(METHODS) / sizeof(METHODS[0])) ? m : FMU_CS_BDF];
}

static int live_dense(const fmu_step_t *step, double t, int k, double *out);

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
    cs->analytic = fmu_model.cs_jacobian != NULL && fmu_model.cs_jacobian(inst->model);
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
        rhs, roots, integrator_message, integrator_failed, integrator_error, inst,
        cs->analytic ? jacobian : NULL};
    cs->problem = problem;
    const live_view_t live = {{1, 0, 0.0, 0.0, 0.0, 0.0, inst->tolerance, live_dense, NULL, NULL,
                               NULL, NULL, NULL, live_memory, NULL, NULL},
                              inst,
                              0.0};
    cs->live = live;
    return cs;
}

fmu_status_t integration_start(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    const int analytic = fmu_model.cs_jacobian != NULL && fmu_model.cs_jacobian(inst->model);
    if (cs != NULL && (cs->tolerance != inst->tolerance || cs->analytic != analytic)) {
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
    const fmu_status_t s = integration_restart(cs, cs->method->start, 0.0, 0.0);
    if (s != FMU_OK) {
        cs_free(inst);
        return s;
    }
    integration_segment(cs, 0.0);
    return s;
}

/* Add the steps taken since the last call to the model's step counter. */
long integration_count_steps(fmu_instance_t *inst)
{
    cs_integration_t *cs = inst->integration;
    const cs_counts_t c = cs->counts;
    const long added = c.steps - cs->counted_steps;
    cs->counted_steps = c.steps;
    if (fmu_model.add_integrator_steps != NULL && added != 0) {
        fmu_model.add_integrator_steps(inst->model, added);
    }
    const long jacobians = c.jacobians - cs->counted_jacobians;
    cs->counted_jacobians = c.jacobians;
    if (fmu_model.add_jacobians != NULL && jacobians != 0) {
        fmu_model.add_jacobians(inst->model, jacobians);
    }
    return added;
}

/* ------------------------------------------------------------------------------------------ */
/* the model's analysis of the steps (fmu_model.analyse_step; csfh: the peak outputs): the steps
 * of an integrator that can save them are kept (kept_steps.h) and handed over when the model's
 * outputs are needed; the others are handed over live, at every pass of cs_do_step's loop */

static int live_dense(const fmu_step_t *step, double t, int k, double *out)
{
    const live_view_t *v = (const live_view_t *)(const void *)step;
    return integration_dense(v->inst->integration, t, k, out);
}

static int live_keep(const fmu_step_t *step)
{
    const live_view_t *v = (const live_view_t *)(const void *)step;
    cs_integration_t *cs = v->inst->integration;
    return kept_keep(&cs->kept, v->inst->model, cs->current->ops, cs->current->self,
                     cs->comm_start, v->from, v->inst->tolerance);
}

/* Forget the live step (the integrator restarted: a new dense output). */
void integration_forget_live(cs_integration_t *cs)
{
    if (cs->live_memory != NULL) {
        memset(cs->live_memory, 0, fmu_model.step_memory);
    }
}

/* The part [ta, tb] of the communication step, the state at tb in cs->y; `stepped`: the
 * integrator took a new step to get there (tb is its end unless a root or the communication
 * point came first). */
void integration_analyse_live(fmu_instance_t *inst, double ta, double tb, int stepped)
{
    cs_integration_t *cs = inst->integration;
    if (fmu_model.analyse_step == NULL) {
        return;
    }
    const double tn = cs->tn, hu = cs->hu;
    live_view_t *v = &cs->live; /* (the rest: integration_new) */
    v->step.new_step = stepped;
    v->step.t0 = tn - hu;
    v->step.tn = v->step.cut = tn;
    v->step.h = hu;
    v->step.y1 = tb == tn ? cs->y : NULL;
    v->step.keep = cs->current->ops->save_step != NULL ? live_keep : NULL;
    v->from = ta;
    fmu_model.analyse_step(inst->model, &v->step, ta, tb);
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
void integration_take_solution(fmu_instance_t *inst, double tret)
{
    memcpy(fmu_states(inst), inst->integration->y, NX * sizeof(double));
    *fmu_time(inst) = inst->integration->origin + tret;
    fmu_invalidate(inst);
}
