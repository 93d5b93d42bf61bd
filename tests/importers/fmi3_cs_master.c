/* Conformance importer: an FMI 3.0 co-simulation master with early return, variable
 * communication steps and rollback, the FMI 3.0 counterpart of cs_master.c.
 *
 * The instance is made with eventModeUsed = true and earlyReturnAllowed = true. After
 * fmi3ExitInitializationMode (Event Mode) and after every fmi3DoStep that asks for it
 * (eventHandlingNeeded) the master runs the event iteration (fmi3UpdateDiscreteStates until no
 * update is needed) and fmi3EnterStepMode. When fmi3DoStep returns early, the step is accepted up
 * to lastSuccessfulTime, the CSV gets that point and --events an "early-return" line, and the
 * next step starts there (currentCommunicationPoint = lastSuccessfulTime).
 *
 * Communication steps h between h_min = h_max / 64 and h_max = --step (default: the
 * DefaultExperiment stepSize): h_min after every early return (the communication grid is fine
 * right after an event), then doubling after every accepted step up to h_max. Before every step
 * the master saves the FMU state (fmi3GetFMUState); every 7th step is replayed: the FMU is rolled
 * back (fmi3SetFMUState) and the same step is taken again; the outputs, earlyReturn and
 * lastSuccessfulTime must be bitwise the same, otherwise the run fails.
 *
 *   --mode memory     (default) the saved states stay in the FMU's memory
 *   --mode serialize  every saved state goes through fmi3SerializeFMUState and
 *                     fmi3DeserializeFMUState before it is restored
 *   --watch NAME      an Int32 variable (e.g. contact.count): a change during a step is written
 *                     to --events as "watched-change" at the end of the step
 * Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_import.h"

#define PROGRAM "csfh_import_fmi3_cs_master"
#define REPLAY_EVERY 7

typedef struct {
    importer3_t *imp;
    int serialize;
    fmi3FMUState state;
} saved_t;

static int save(saved_t *s)
{
    importer3_t *imp = s->imp;
    if (imp->api.GetFMUState(imp->c, &s->state) > fmi3Warning) {
        return imp_fail(&imp->run, "fmi3GetFMUState failed at t = %.17g", imp->run.t_reached), -1;
    }
    if (!s->serialize) {
        return 0;
    }
    size_t size = 0;
    if (imp->api.SerializedFMUStateSize(imp->c, s->state, &size) > fmi3Warning) {
        return imp_fail(&imp->run, "fmi3SerializedFMUStateSize failed"), -1;
    }
    fmi3Byte *bytes = (fmi3Byte *)malloc(size);
    fmi3FMUState copy = NULL;
    const int ok =
        bytes != NULL && imp->api.SerializeFMUState(imp->c, s->state, bytes, size) <= fmi3Warning &&
        imp->api.FreeFMUState(imp->c, &s->state) <= fmi3Warning &&
        imp->api.DeserializeFMUState(imp->c, bytes, size, &copy) <= fmi3Warning;
    free(bytes);
    if (!ok) {
        return imp_fail(&imp->run, "FMU state serialization round trip failed"), -1;
    }
    s->state = copy;
    return 0;
}

static int restore(saved_t *s)
{
    if (s->imp->api.SetFMUState(s->imp->c, s->state) > fmi3Warning) {
        return imp_fail(&s->imp->run, "fmi3SetFMUState failed"), -1;
    }
    s->imp->run.rollbacks++;
    return 0;
}

static void release(saved_t *s)
{
    if (s->state != NULL) {
        s->imp->api.FreeFMUState(s->imp->c, &s->state);
        s->state = NULL;
    }
}

/* Event Mode (entered first unless `in_event_mode`): update the discrete states until no update
 * is needed, then Step Mode. 0, or -1 on failure. */
static int handle_event(importer3_t *imp, int in_event_mode)
{
    fmi3Boolean again = fmi3False, terminate = fmi3False, nominals = fmi3False;
    fmi3Boolean values = fmi3False, next_defined = fmi3False;
    fmi3Float64 next = 0.0;
    if (!in_event_mode && imp->api.EnterEventMode(imp->c) > fmi3Warning) {
        return imp_fail(&imp->run, "fmi3EnterEventMode failed"), -1;
    }
    do {
        if (imp->api.UpdateDiscreteStates(imp->c, &again, &terminate, &nominals, &values,
                                          &next_defined, &next) > fmi3Warning ||
            terminate) {
            return imp_fail(&imp->run, "fmi3UpdateDiscreteStates failed or asked to terminate"),
                   -1;
        }
    } while (again);
    if (imp->api.EnterStepMode(imp->c) > fmi3Warning) {
        return imp_fail(&imp->run, "fmi3EnterStepMode failed"), -1;
    }
    return 0;
}

typedef struct {
    fmi3Boolean handling, terminate, early;
    fmi3Float64 t_last;
} step_result_t;

static int do_step(importer3_t *imp, double t, double h, step_result_t *r)
{
    memset(r, 0, sizeof(*r));
    if (imp->api.DoStep(imp->c, t, h, fmi3False, &r->handling, &r->terminate, &r->early,
                        &r->t_last) > fmi3Warning ||
        r->terminate) {
        return imp_fail(&imp->run, "fmi3DoStep(%.17g, %.17g) failed or asked to terminate", t,
                        h),
               -1;
    }
    if (r->early && !(r->t_last >= t && r->t_last < t + h)) {
        return imp_fail(&imp->run,
                        "fmi3DoStep(%.17g, %.17g) returned early at %.17g, outside the step", t,
                        h, r->t_last),
               -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    importer3_t imp;
    imp3_open(&imp, argc, argv, IMP3_CO_SIMULATION, PROGRAM);
    const char *mode = imp.run.opt.mode;
    const int serialize = mode != NULL && strcmp(mode, "serialize") == 0;
    if (mode != NULL && !serialize && strcmp(mode, "memory") != 0) {
        fprintf(stderr, PROGRAM ": --mode must be memory or serialize, got %s\n", mode);
        return 2;
    }
    const double h_max = isfinite(imp.run.opt.step) ? imp.run.opt.step : imp.run.md.step_size;
    const double h_min = h_max / 64.0;
    const double t_stop = isfinite(imp.run.opt.stop) ? imp.run.opt.stop : imp.run.md.stop_time;
    const double rtol = isfinite(imp.run.opt.rtol) ? imp.run.opt.rtol : imp.run.md.tolerance;
    if (!(h_max > 0) || !isfinite(t_stop)) {
        fprintf(stderr, PROGRAM ": no step size or stop time\n");
        return 2;
    }
    if (imp.api.GetFMUState == NULL || imp.api.SetFMUState == NULL ||
        imp.api.FreeFMUState == NULL || imp.api.EnterEventMode == NULL ||
        imp.api.UpdateDiscreteStates == NULL ||
        (serialize && (imp.api.SerializedFMUStateSize == NULL ||
                       imp.api.SerializeFMUState == NULL || imp.api.DeserializeFMUState == NULL))) {
        fprintf(stderr, PROGRAM ": the FMU lacks the FMU state or Event Mode functions\n");
        return 2;
    }
    imp.run.opt.stop = t_stop;
    fmi3ValueReference watch_vr = 0;
    int watching = 0;
    if (imp.run.opt.watch != NULL) {
        char type[16];
        if (imp3_lookup(&imp, imp.run.opt.watch, &watch_vr, type) != 0 ||
            strcmp(type, "Int32") != 0) {
            fprintf(stderr, PROGRAM ": --watch: %s is not an Int32 variable\n", imp.run.opt.watch);
            return 2;
        }
        watching = 1;
    }
    saved_t saved = {&imp, serialize, NULL};
    if (imp3_initialize(&imp, rtol, 1, 1) > fmi3Warning || handle_event(&imp, 1) != 0) {
        return imp3_close(&imp);
    }
    double t = imp.run.t_reached, h = h_min;
    imp3_record(&imp, t, 1);
    fmi3Int32 watched = 0, now = 0;
    if (watching && imp.api.GetInt32(imp.c, &watch_vr, 1, &watched, 1) > fmi3Warning) {
        imp_fail(&imp.run, "fmi3GetInt32 of the watched variable failed");
    }
    long accepted = 0;
    fmi3Float64 first[IMP_MAX_OUTPUTS], again[IMP_MAX_OUTPUTS];
    fmi3ValueReference vrs[IMP_MAX_OUTPUTS];
    const size_t n_out = (size_t)imp.run.opt.n_outputs;
    for (size_t k = 0; k < n_out; k++) {
        vrs[k] = (fmi3ValueReference)imp.run.opt.output_vrs[k];
    }
    while (imp.run.status[0] == '\0' && t < t_stop * (1 - 1e-15)) {
        if (imp.run.steps >= imp.run.opt.max_steps) {
            imp_fail(&imp.run, "budget: more than %ld steps", imp.run.opt.max_steps);
            break;
        }
        const double step = t + h > t_stop ? t_stop - t : h;
        if (save(&saved) != 0) {
            break;
        }
        imp.run.steps++;
        step_result_t r, r2;
        if (do_step(&imp, t, step, &r) != 0) {
            break;
        }
        if (++accepted % REPLAY_EVERY == 0) {
            /* the same step once more from the saved state: bitwise the same results */
            if (imp.api.GetFloat64(imp.c, vrs, n_out, first, n_out) > fmi3Warning ||
                restore(&saved) != 0 || do_step(&imp, t, step, &r2) != 0 ||
                imp.api.GetFloat64(imp.c, vrs, n_out, again, n_out) > fmi3Warning) {
                imp_fail(&imp.run, "the replay of the step at t = %.17g failed", t);
                break;
            }
            if (memcmp(first, again, n_out * sizeof(fmi3Float64)) != 0 || r.early != r2.early ||
                r.handling != r2.handling || memcmp(&r.t_last, &r2.t_last, sizeof(double)) != 0) {
                imp_fail(&imp.run, "replay: the step from t = %.17g differs after a rollback", t);
                break;
            }
        }
        release(&saved);
        const double t_end = r.early ? r.t_last : (step == t_stop - t ? t_stop : t + step);
        if (watching && imp.api.GetInt32(imp.c, &watch_vr, 1, &now, 1) > fmi3Warning) {
            imp_fail(&imp.run, "fmi3GetInt32 of the watched variable failed");
            break;
        }
        if (r.early) {
            imp_event(&imp.run, t_end, "early-return");
        }
        if (watching && now != watched) {
            imp_event(&imp.run, t_end, "watched-change");
        }
        watched = now;
        t = t_end;
        imp.run.t_reached = t;
        if (imp3_record(&imp, t, 1) > fmi3Warning) {
            break;
        }
        if (r.handling && handle_event(&imp, 0) != 0) {
            break;
        }
        h = r.early ? h_min : fmin(2.0 * h, h_max);
    }
    release(&saved);
    return imp3_close(&imp);
}
