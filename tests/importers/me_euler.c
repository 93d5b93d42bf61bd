/* Conformance importer: model exchange with the explicit (forward) Euler method at a fixed step,
 * the simplest integrator a tool offers, with the tool's default step: the DefaultExperiment
 * stepSize (--step to override). Written once for both FMI versions against the model-exchange
 * table of import_me.h.
 *
 * After initialization the FMU is in Event Mode: the first event iteration starts there. Each
 * step: x += h f(x) (set time, set states, completed integrator step); the event indicators are
 * read at the end of the step and a sign change (z > 0 to z <= 0 or back, as fmusim and
 * FMUComplianceChecker test it) starts an event at the end of the step (no root location: the
 * event is up to one step late, as in those tools); so does a step event (enterEventMode). After
 * the event iteration the states are read back when the FMU reports valuesOfContinuousStatesChanged
 * (counted in `reinits`), and the indicators are read again. Time events (nextEventTime) shorten
 * the step that would pass nextEventTime so that it ends there; the grid of the fixed steps goes
 * on unchanged. Every step is recorded into the extremes of the summary (so a penetration between
 * output points is seen); the CSV gets the output points every --interval (default: the
 * stepSize) and the state before each event. Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "import_me.h"

#define MAX_STATES 64
#define MAX_INDICATORS 64

/* The integrator's state between steps. */
typedef struct {
    const imp_me_t *me;
    int nx, nz;
    double x[MAX_STATES], dx[MAX_STATES], z[MAX_INDICATORS], z_prev[MAX_INDICATORS];
    double t_next; /* the next time event, INFINITY if none */
} euler_t;

/* A sign change of an event indicator since the last step (and the indicators kept). */
static int indicators_crossed(euler_t *e)
{
    int crossed = 0;
    for (int j = 0; j < e->nz; j++) {
        crossed |= (e->z_prev[j] > 0 && e->z[j] <= 0) || (e->z_prev[j] <= 0 && e->z[j] > 0);
        e->z_prev[j] = e->z[j];
    }
    return crossed;
}

/* The event iteration at time t, then the states and indicators read again; 0 or -1. */
static int handle_event(euler_t *e, double t)
{
    const imp_me_t *me = e->me;
    imp_event_info_t info;
    if (me->event_iteration(me->fmu, 0, &info) != 0) {
        imp_fail(me->run, "the event iteration failed at t = %.17g", t);
        return -1;
    }
    e->t_next = info.t_next;
    const int changed = info.values_changed;
    imp_event(me->run, t, changed ? "reinit-requested" : "event");
    if ((changed && me->get_states(me->fmu, e->x, (size_t)e->nx) != 0) ||
        (e->nz > 0 && me->get_event_indicators(me->fmu, e->z_prev, (size_t)e->nz) != 0)) {
        imp_fail(me->run, "cannot read the states after the event at t = %.17g", t);
        return -1;
    }
    me->run->reinits += changed;
    return 0;
}

/* One step to time t, `output` if it ends on an output point; 0 or -1. */
static int step(euler_t *e, double t, int output)
{
    const imp_me_t *me = e->me;
    imp_run_t *run = me->run;
    const double dt = t - run->t_reached;
    if (me->get_derivatives(me->fmu, e->dx, (size_t)e->nx) != 0) {
        imp_fail(run, "%s failed at t = %.17g", me->derivatives_call, run->t_reached);
        return -1;
    }
    for (int i = 0; i < e->nx; i++) {
        e->x[i] += dt * e->dx[i];
    }
    if (me->set_time(me->fmu, t) != 0 || me->set_states(me->fmu, e->x, (size_t)e->nx) != 0) {
        imp_fail(run, "the FMU refused the state at t = %.17g", t);
        return -1;
    }
    run->t_reached = t;
    run->steps++;
    int enter = 0, terminate = 0;
    if (me->completed_integrator_step(me->fmu, &enter, &terminate) != 0 || terminate) {
        imp_fail(run, "%s failed or asked to terminate", me->completed_call);
        return -1;
    }
    int event = enter || t >= e->t_next;
    if (e->nz > 0) {
        if (me->get_event_indicators(me->fmu, e->z, (size_t)e->nz) != 0) {
            imp_fail(run, "%s failed at t = %.17g", me->indicators_call, t);
            return -1;
        }
        event |= indicators_crossed(e);
    }
    if (me->record(me->fmu, t, output || event) != 0) {
        return -1;
    }
    return event ? handle_event(e, t) : 0;
}

/* The fixed steps from t0 to t_stop: 0, or -1 when a step failed. */
static int integrate(euler_t *e, double t0, double t_stop, double h, double dt_out)
{
    imp_run_t *run = e->me->run;
    const long n_steps = (long)ceil((t_stop - t0) / h - 1e-9);
    const long every = (long)fmax(1.0, floor(dt_out / h + 0.5));
    for (long n = 1; n <= n_steps; n++) {
        const double t_grid = n == n_steps ? t_stop : t0 + (double)n * h;
        while (run->t_reached < t_grid) { /* one step, or two when a time event cuts it */
            if (run->steps >= run->opt.max_steps) {
                imp_fail(run, "budget: more than %ld steps", run->opt.max_steps);
                return -1;
            }
            /* a time event strictly inside the step ends it (one at or before the current time
             * would not advance: it is taken at the end of the step, as a state event) */
            const double t = (e->t_next > run->t_reached && e->t_next < t_grid) ? e->t_next : t_grid;
            const int output = t >= t_grid && (n % every == 0 || n == n_steps);
            if (step(e, t, output) != 0) {
                return -1;
            }
        }
    }
    return 0;
}

int imp_me_euler(const imp_me_t *me, const char *program)
{
    imp_run_t *run = me->run;
    const double h = isfinite(run->opt.step) ? run->opt.step : run->md.step_size;
    const double t_stop = isfinite(run->opt.stop) ? run->opt.stop : run->md.stop_time;
    const double dt_out = isfinite(run->opt.interval) ? run->opt.interval : h;
    if (!(h > 0) || !isfinite(t_stop) || !(dt_out > 0)) {
        fprintf(stderr, "%s: no step size or stop time (give --step and --stop, or a "
                        "DefaultExperiment with stepSize and stopTime)\n", program);
        return 2;
    }
    run->opt.stop = t_stop;
    euler_t e;
    memset(&e, 0, sizeof(e));
    e.me = me;
    e.nx = run->md.n_states;
    e.nz = run->md.n_event_indicators;
    if (e.nx < 1 || e.nx > MAX_STATES || e.nz > MAX_INDICATORS) {
        fprintf(stderr, "%s: %d states and %d event indicators are not supported\n", program, e.nx,
                e.nz);
        return 2;
    }
    const double tol = isfinite(run->opt.rtol) ? run->opt.rtol : run->md.tolerance;
    imp_event_info_t info;
    if (me->initialize(me->fmu, tol) != 0 ||
        me->event_iteration(me->fmu, 1, &info) != 0) { /* in Event Mode already */
        imp_fail(run, "initialization failed");
        return me->close(me->fmu);
    }
    e.t_next = info.t_next;
    const double t0 = run->t_reached;
    if (me->get_states(me->fmu, e.x, (size_t)e.nx) != 0 ||
        (e.nz > 0 && me->get_event_indicators(me->fmu, e.z_prev, (size_t)e.nz) != 0)) {
        imp_fail(run, "cannot read the initial states or event indicators");
        return me->close(me->fmu);
    }
    me->record(me->fmu, t0, 1);
    integrate(&e, t0, t_stop, h, dt_out);
    return me->close(me->fmu);
}
