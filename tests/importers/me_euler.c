/* Conformance importer: model exchange with the explicit (forward) Euler method at a fixed step,
 * the simplest integrator a tool offers, with the tool's default step: the DefaultExperiment
 * stepSize (--step to override).
 *
 * Each step: x += h f(x); the event indicators are read at the end of the step and a sign change
 * (z > 0 to z <= 0 or back, as fmusim and FMUComplianceChecker test it) starts an event at the
 * end of the step (no root location: the event is up to one step late, as in those tools). After
 * the event iteration the states are read back when the FMU reports a change, and the indicators
 * are read again. Time events (nextEventTimeDefined) shorten the step that would pass
 * nextEventTime so that it ends there; the grid of the fixed steps goes on unchanged. Every step is recorded into the extremes of the summary (so a penetration
 * between output points is seen); the CSV gets the output points every --interval (default: the
 * stepSize) and the state before each event. Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_import.h"

#define PROGRAM "csfh_import_me_euler"
#define MAX_STATES 64
#define MAX_INDICATORS 64

/* Event Mode at the current time and state: the event iteration; returns 1 if the FMU changed
 * the continuous states, 0 if not, -1 on failure. The next time event (or INFINITY) into
 * *t_next. */
static int event_iteration(importer_t *imp, double *t_next)
{
    fmi2EventInfo info;
    int changed = 0;
    if (imp->api.EnterEventMode(imp->c) > fmi2Warning) {
        return -1;
    }
    do {
        memset(&info, 0, sizeof(info));
        if (imp->api.NewDiscreteStates(imp->c, &info) > fmi2Warning || info.terminateSimulation) {
            return -1;
        }
        changed |= info.valuesOfContinuousStatesChanged;
    } while (info.newDiscreteStatesNeeded);
    *t_next = info.nextEventTimeDefined ? info.nextEventTime : INFINITY;
    if (imp->api.EnterContinuousTimeMode(imp->c) > fmi2Warning) {
        return -1;
    }
    return changed;
}

int main(int argc, char **argv)
{
    importer_t imp;
    imp_open(&imp, argc, argv, fmi2ModelExchange, PROGRAM);
    const double h = isfinite(imp.run.opt.step) ? imp.run.opt.step : imp.run.md.step_size;
    const double t_stop = isfinite(imp.run.opt.stop) ? imp.run.opt.stop : imp.run.md.stop_time;
    const double dt_out = isfinite(imp.run.opt.interval) ? imp.run.opt.interval : h;
    if (!(h > 0) || !isfinite(t_stop) || !(dt_out > 0)) {
        fprintf(stderr, PROGRAM ": no step size or stop time (give --step and --stop, or a "
                        "DefaultExperiment with stepSize and stopTime)\n");
        return 2;
    }
    imp.run.opt.stop = t_stop;
    const int nx = imp.run.md.n_states, nz = imp.run.md.n_event_indicators;
    double x[MAX_STATES], dx[MAX_STATES], z[MAX_INDICATORS], z_prev[MAX_INDICATORS];
    if (nx < 1 || nx > MAX_STATES || nz > MAX_INDICATORS) {
        fprintf(stderr, PROGRAM ": %d states and %d event indicators are not supported\n", nx, nz);
        return 2;
    }
    const double tol = isfinite(imp.run.opt.rtol) ? imp.run.opt.rtol : imp.run.md.tolerance;
    double t_next = INFINITY;
    if (imp_initialize(&imp, fmi2ModelExchange, tol) > fmi2Warning ||
        event_iteration(&imp, &t_next) < 0) {
        imp_fail(&imp.run, "initialization failed");
        return imp_close(&imp);
    }
    const double t0 = imp.run.t_reached;
    if (imp.api.GetContinuousStates(imp.c, x, (size_t)nx) > fmi2Warning ||
        (nz > 0 && imp.api.GetEventIndicators(imp.c, z_prev, (size_t)nz) > fmi2Warning)) {
        imp_fail(&imp.run, "cannot read the initial states or event indicators");
        return imp_close(&imp);
    }
    imp_record(&imp, t0, 1);
    const long n_steps = (long)ceil((t_stop - t0) / h - 1e-9);
    const long every = (long)fmax(1.0, floor(dt_out / h + 0.5));
    int failed = 0;
    for (long n = 1; n <= n_steps && !failed; n++) {
        const double t_grid = n == n_steps ? t_stop : t0 + (double)n * h;
        while (imp.run.t_reached < t_grid) { /* one step, or two when a time event cuts it */
            if (imp.run.steps >= imp.run.opt.max_steps) {
                imp_fail(&imp.run, "budget: more than %ld steps", imp.run.opt.max_steps);
                failed = 1;
                break;
            }
            /* a time event strictly inside the step ends it (one at or before the current time
             * would not advance: it is taken at the end of the step, as a state event) */
            const double t =
                (t_next > imp.run.t_reached && t_next < t_grid) ? t_next : t_grid;
            const double dt = t - imp.run.t_reached;
            if (imp.api.GetDerivatives(imp.c, dx, (size_t)nx) > fmi2Warning) {
                imp_fail(&imp.run, "fmi2GetDerivatives failed at t = %.17g", imp.run.t_reached);
                failed = 1;
                break;
            }
            for (int i = 0; i < nx; i++) {
                x[i] += dt * dx[i];
            }
            if (imp.api.SetTime(imp.c, t) > fmi2Warning ||
                imp.api.SetContinuousStates(imp.c, x, (size_t)nx) > fmi2Warning) {
                imp_fail(&imp.run, "the FMU refused the state at t = %.17g", t);
                failed = 1;
                break;
            }
            imp.run.t_reached = t;
            imp.run.steps++;
            fmi2Boolean enter = fmi2False, terminate = fmi2False;
            if (imp.api.CompletedIntegratorStep(imp.c, fmi2True, &enter, &terminate) >
                    fmi2Warning ||
                terminate) {
                imp_fail(&imp.run, "fmi2CompletedIntegratorStep failed or asked to terminate");
                failed = 1;
                break;
            }
            int event = enter || t >= t_next;
            if (nz > 0) {
                if (imp.api.GetEventIndicators(imp.c, z, (size_t)nz) > fmi2Warning) {
                    imp_fail(&imp.run, "fmi2GetEventIndicators failed at t = %.17g", t);
                    failed = 1;
                    break;
                }
                for (int j = 0; j < nz; j++) {
                    event |= (z_prev[j] > 0 && z[j] <= 0) || (z_prev[j] <= 0 && z[j] > 0);
                    z_prev[j] = z[j];
                }
            }
            const int output = t >= t_grid && (n % every == 0 || n == n_steps);
            if (imp_record(&imp, t, output || event) > fmi2Warning) {
                failed = 1;
                break;
            }
            if (event) {
                const int changed = event_iteration(&imp, &t_next);
                if (changed < 0) {
                    imp_fail(&imp.run, "the event iteration failed at t = %.17g", t);
                    failed = 1;
                    break;
                }
                imp_event(&imp.run, t, changed ? "reinit-requested" : "event");
                if ((changed &&
                     imp.api.GetContinuousStates(imp.c, x, (size_t)nx) > fmi2Warning) ||
                    (nz > 0 &&
                     imp.api.GetEventIndicators(imp.c, z_prev, (size_t)nz) > fmi2Warning)) {
                    imp_fail(&imp.run, "cannot read the states after the event at t = %.17g", t);
                    failed = 1;
                    break;
                }
                imp.run.reinits += changed;
            }
        }
    }
    return imp_close(&imp);
}
