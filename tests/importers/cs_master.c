/* Conformance importer: a co-simulation master with variable communication steps and rollback.
 *
 * The master steps with h between h_max = --step (default: the DefaultExperiment stepSize) and
 * h_min = h_max / 64. Before every step it saves the FMU state (fmi2GetFMUstate); when the
 * Integer variable --watch NAME changed during the step (e.g. contact.count: a contact began)
 * and h > h_min, it rolls the FMU back (fmi2SetFMUstate) and retries with h / 4, so the events
 * are resolved on a finer communication grid; after an accepted step h doubles again (up to
 * h_max). Every 7th accepted step is replayed: the FMU is rolled back to the state before the
 * step and the same step is taken again; the outputs must be bitwise the same (a rollback must
 * not change the result), otherwise the run fails.
 *
 *   --mode memory     (default) the saved states stay in the FMU's memory
 *   --mode serialize  every saved state goes through fmi2SerializeFMUstate and
 *                     fmi2DeSerializeFMUstate before it is restored
 * The CSV gets every accepted communication point. Common options: import_common.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_import.h"

#define PROGRAM "csfh_import_cs_master"
#define REPLAY_EVERY 7

typedef struct {
    importer_t *imp;
    int serialize;
    fmi2FMUstate state;
} saved_t;

static int save(saved_t *s)
{
    importer_t *imp = s->imp;
    if (imp->api.GetFMUstate(imp->c, &s->state) > fmi2Warning) {
        return imp_fail(&imp->run, "fmi2GetFMUstate failed at t = %.17g", imp->run.t_reached), -1;
    }
    if (!s->serialize) {
        return 0;
    }
    size_t size = 0;
    if (imp->api.SerializedFMUstateSize(imp->c, s->state, &size) > fmi2Warning) {
        return imp_fail(&imp->run, "fmi2SerializedFMUstateSize failed"), -1;
    }
    fmi2Byte *bytes = (fmi2Byte *)malloc(size);
    fmi2FMUstate copy = NULL;
    int ok = bytes != NULL && imp->api.SerializeFMUstate(imp->c, s->state, bytes, size) <= fmi2Warning &&
             imp->api.FreeFMUstate(imp->c, &s->state) <= fmi2Warning &&
             imp->api.DeSerializeFMUstate(imp->c, bytes, size, &copy) <= fmi2Warning;
    free(bytes);
    if (!ok) {
        return imp_fail(&imp->run, "FMU state serialization round trip failed"), -1;
    }
    s->state = copy;
    return 0;
}

static int restore(saved_t *s)
{
    if (s->imp->api.SetFMUstate(s->imp->c, s->state) > fmi2Warning) {
        return imp_fail(&s->imp->run, "fmi2SetFMUstate failed"), -1;
    }
    s->imp->run.rollbacks++;
    return 0;
}

static void release(saved_t *s)
{
    if (s->state != NULL) {
        s->imp->api.FreeFMUstate(s->imp->c, &s->state);
        s->state = NULL;
    }
}

int main(int argc, char **argv)
{
    importer_t imp;
    imp_open(&imp, argc, argv, fmi2CoSimulation, PROGRAM);
    const int serialize = imp.run.opt.mode != NULL && strcmp(imp.run.opt.mode, "serialize") == 0;
    if (imp.run.opt.mode != NULL && !serialize && strcmp(imp.run.opt.mode, "memory") != 0) {
        fprintf(stderr, PROGRAM ": --mode must be memory or serialize, got %s\n", imp.run.opt.mode);
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
    if (imp.api.GetFMUstate == NULL || imp.api.SetFMUstate == NULL || imp.api.FreeFMUstate == NULL ||
        (serialize && (imp.api.SerializeFMUstate == NULL || imp.api.DeSerializeFMUstate == NULL))) {
        fprintf(stderr, PROGRAM ": the FMU does not export the FMU state functions\n");
        return 2;
    }
    imp.run.opt.stop = t_stop;
    /* the watched Integer (optional): a change during a step asks for a smaller step */
    fmi2ValueReference watch_vr = 0;
    int watching = 0;
    if (imp.run.opt.watch != NULL) {
        char type[16];
        if (imp_lookup(&imp, imp.run.opt.watch, &watch_vr, type) != 0 ||
            (strcmp(type, "Integer") != 0 && strcmp(type, "Enumeration") != 0)) {
            fprintf(stderr, PROGRAM ": --watch: %s is not an Integer variable\n",
                    imp.run.opt.watch);
            return 2;
        }
        watching = 1;
    }
    saved_t saved = {&imp, serialize, NULL};
    if (imp_initialize(&imp, fmi2CoSimulation, rtol) > fmi2Warning) {
        return imp_close(&imp);
    }
    double t = imp.run.t_reached, h = h_max;
    imp_record(&imp, t, 1);
    fmi2Integer watched = 0, now = 0;
    if (watching && imp.api.GetInteger(imp.c, &watch_vr, 1, &watched) > fmi2Warning) {
        imp_fail(&imp.run, "fmi2GetInteger of the watched variable failed");
    }
    long accepted = 0;
    fmi2Real first[IMP_MAX_OUTPUTS], again[IMP_MAX_OUTPUTS];
    const size_t n_out = (size_t)imp.run.opt.n_outputs;
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
        if (imp.api.DoStep(imp.c, t, step, fmi2True) > fmi2Warning) {
            imp_fail(&imp.run, "fmi2DoStep(%.17g, %.17g) failed", t, step);
            break;
        }
        if (watching && imp.api.GetInteger(imp.c, &watch_vr, 1, &now) > fmi2Warning) {
            imp_fail(&imp.run, "fmi2GetInteger of the watched variable failed");
            break;
        }
        if (watching && now != watched && step > h_min * (1 + 1e-12)) {
            if (restore(&saved) != 0) {
                break;
            }
            release(&saved);
            h = fmax(h / 4.0, h_min);
            continue;
        }
        if (++accepted % REPLAY_EVERY == 0) {
            /* the same step once more from the saved state: bitwise the same outputs */
            if (imp.api.GetReal(imp.c, imp.run.opt.output_vrs, n_out, first) > fmi2Warning ||
                restore(&saved) != 0 ||
                imp.api.DoStep(imp.c, t, step, fmi2True) > fmi2Warning ||
                imp.api.GetReal(imp.c, imp.run.opt.output_vrs, n_out, again) > fmi2Warning) {
                imp_fail(&imp.run, "the replay of the step at t = %.17g failed", t);
                break;
            }
            if (memcmp(first, again, n_out * sizeof(fmi2Real)) != 0) {
                imp_fail(&imp.run, "replay: the step from t = %.17g differs after a rollback", t);
                break;
            }
        }
        release(&saved);
        if (watching && now != watched) {
            imp_event(&imp.run, t + step, "watched-change");
        }
        watched = now;
        t = step == t_stop - t ? t_stop : t + step;
        imp.run.t_reached = t;
        if (imp_record(&imp, t, 1) > fmi2Warning) {
            break;
        }
        h = fmin(2.0 * h, h_max);
    }
    release(&saved);
    return imp_close(&imp);
}
