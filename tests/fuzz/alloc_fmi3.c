/* The failed-allocation test's FMI 3.0 scenario (alloc_fail.c runs it): the FMI 2.0 scenario's
 * parts (alloc_fmi2.c) through the FMI 3.0 front-end, co-simulation in Step Mode with early
 * return allowed (the step ends at each contact event), and model exchange through Event
 * Mode. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#endif
#include "fmi3Functions.h"
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "alloc_fail.h"
#include "alloc_scene.h"

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    (void)env;
    alloc_logged((int)status, category, message);
}

static void read_reals(fmi3Instance c)
{
    size_t n = 0;
    const fmi3ValueReference *reals = alloc_reals(&n);
    double *x = (double *)alloc_own(n * sizeof(double));
    const int s = ALLOC_CALL("fmi3GetFloat64", fmi3GetFloat64(c, reals, n, x, n));
    alloc_values("fmi3GetFloat64", s, x, n);
    alloc_own_free(x);
}

static void set_scene(fmi3Instance c, int method)
{
    for (size_t i = 0; i < ALLOC_SCENE_SIZE; i++) {
        const csfh_variable_t *v = alloc_variable(alloc_scene[i].name);
        if (v != NULL) {
            ALLOC_CALL("fmi3SetFloat64", fmi3SetFloat64(c, &v->vr, 1, &alloc_scene[i].value, 1));
        }
    }
    const csfh_variable_t *m = alloc_variable("solver.method");
    if (m != NULL && method != 0) {
        const fmi3Int64 value = method;
        ALLOC_CALL("fmi3SetInt64", fmi3SetInt64(c, &m->vr, 1, &value, 1));
    }
}

static int start(fmi3Instance c)
{
    return ALLOC_CALL("fmi3EnterInitializationMode",
                      fmi3EnterInitializationMode(c, true, ALLOC_TOLERANCE, 0.0, false, 0.0)) <=
               ALLOC_WARNING &&
           ALLOC_CALL("fmi3ExitInitializationMode", fmi3ExitInitializationMode(c)) <=
               ALLOC_WARNING;
}

static void fmu_states(fmi3Instance c)
{
    fmi3FMUState s = NULL, d = NULL;
    size_t size = 0;
    if (ALLOC_CALL("fmi3GetFMUState", fmi3GetFMUState(c, &s)) > ALLOC_WARNING) {
        return;
    }
    if (ALLOC_CALL("fmi3SerializedFMUStateSize", fmi3SerializedFMUStateSize(c, s, &size)) <=
        ALLOC_WARNING) {
        fmi3Byte *bytes = (fmi3Byte *)alloc_own(size);
        if (ALLOC_CALL("fmi3SerializeFMUState", fmi3SerializeFMUState(c, s, bytes, size)) <=
                ALLOC_WARNING &&
            ALLOC_CALL("fmi3DeserializeFMUState", fmi3DeserializeFMUState(c, bytes, size, &d)) <=
                ALLOC_WARNING) {
            ALLOC_CALL("fmi3SetFMUState", fmi3SetFMUState(c, d));
            ALLOC_CALL("fmi3FreeFMUState", fmi3FreeFMUState(c, &d));
        }
        alloc_own_free(bytes);
    }
    ALLOC_CALL("fmi3FreeFMUState", fmi3FreeFMUState(c, &s));
}

void alloc_co_simulation(const char *method_name, int method)
{
    char name[64];
    snprintf(name, sizeof(name), "fmi3InstantiateCoSimulation%s%s", method_name[0] ? " " : "", method_name);
    fmi3Instance c;
    if (!ALLOC_INSTANCE(name, c,
                        fmi3InstantiateCoSimulation("alloc-cs", fmu_model.guid, NULL, false, true,
                                                    false, true, NULL, 0, NULL, logger, NULL))) {
        return;
    }
    set_scene(c, method);
    if (start(c)) {
        double t = 0.0;
        const double end = ALLOC_CS_STEPS * ALLOC_CS_STEP;
        int taken = 0;
        for (int k = 0; k < 4 * ALLOC_CS_STEPS && t < end; k++) {
            bool handling = false, terminate = false, early = false;
            double last = t;
            if (ALLOC_CALL("fmi3DoStep", fmi3DoStep(c, t, ALLOC_CS_STEP, true, &handling,
                                                    &terminate, &early, &last)) >
                ALLOC_WARNING) {
                break;
            }
            t = early ? last : t + ALLOC_CS_STEP;
            read_reals(c);
            if (!taken && t >= ALLOC_STATES_AT) {
                fmu_states(c);
                taken = 1;
            }
        }
        ALLOC_CALL("fmi3Terminate", fmi3Terminate(c));
    }
    fmi3FreeInstance(c);
}

/* Event Mode until the discrete states settle, then Continuous-Time Mode: 0, or -1. */
static int events(fmi3Instance c)
{
    for (int i = 0; i < 10; i++) {
        bool update = false, terminate = false, nominals = false, values = false, next = false;
        double next_time = 0.0;
        if (ALLOC_CALL("fmi3UpdateDiscreteStates",
                       fmi3UpdateDiscreteStates(c, &update, &terminate, &nominals, &values, &next,
                                                &next_time)) > ALLOC_WARNING) {
            return -1;
        }
        if (!update) {
            break;
        }
    }
    return ALLOC_CALL("fmi3EnterContinuousTimeMode", fmi3EnterContinuousTimeMode(c)) <=
                   ALLOC_WARNING
               ? 0
               : -1;
}

static int euler_step(fmi3Instance c, double *t, double *x, double *dx, double *z, size_t nx,
                      size_t nz)
{
    int s = ALLOC_CALL("fmi3GetContinuousStateDerivatives",
                       fmi3GetContinuousStateDerivatives(c, dx, nx));
    alloc_values("fmi3GetContinuousStateDerivatives", s, dx, nx);
    for (size_t i = 0; i < nx && s <= ALLOC_WARNING; i++) {
        x[i] += ALLOC_ME_STEP * dx[i];
    }
    *t += ALLOC_ME_STEP;
    if (s > ALLOC_WARNING || ALLOC_CALL("fmi3SetTime", fmi3SetTime(c, *t)) > ALLOC_WARNING ||
        ALLOC_CALL("fmi3SetContinuousStates", fmi3SetContinuousStates(c, x, nx)) >
            ALLOC_WARNING) {
        return -1;
    }
    s = ALLOC_CALL("fmi3GetEventIndicators", fmi3GetEventIndicators(c, z, nz));
    alloc_values("fmi3GetEventIndicators", s, z, nz);
    bool enter = false, terminate = false;
    if (s > ALLOC_WARNING ||
        ALLOC_CALL("fmi3CompletedIntegratorStep",
                   fmi3CompletedIntegratorStep(c, true, &enter, &terminate)) > ALLOC_WARNING) {
        return -1;
    }
    if (enter &&
        (ALLOC_CALL("fmi3EnterEventMode", fmi3EnterEventMode(c)) > ALLOC_WARNING || events(c))) {
        return -1;
    }
    return 0;
}

void alloc_model_exchange(void)
{
    fmi3Instance c;
    if (!ALLOC_INSTANCE("fmi3InstantiateModelExchange", c,
                        fmi3InstantiateModelExchange("alloc-me", fmu_model.guid, NULL, false,
                                                     true, NULL, logger))) {
        return;
    }
    const size_t nx = (size_t)fmu_model.n_states, nz = (size_t)fmu_model.n_event_indicators;
    double *x = (double *)alloc_own(3 * nx * sizeof(double) + nz * sizeof(double));
    double *dx = x + nx, *nominal = dx + nx, *z = nominal + nx;
    set_scene(c, 0); /* (no method: model exchange) */
    if (start(c) && events(c) == 0 &&
        ALLOC_CALL("fmi3GetContinuousStates", fmi3GetContinuousStates(c, x, nx)) <=
            ALLOC_WARNING) {
        const int s = ALLOC_CALL("fmi3GetNominalsOfContinuousStates",
                                 fmi3GetNominalsOfContinuousStates(c, nominal, nx));
        alloc_values("fmi3GetNominalsOfContinuousStates", s, nominal, nx);
        double t = 0.0;
        for (int k = 0; k < ALLOC_ME_STEPS && euler_step(c, &t, x, dx, z, nx, nz) == 0; k++) {
            read_reals(c);
            if (k == ALLOC_ME_STEPS / 2) {
                fmu_states(c);
            }
        }
        ALLOC_CALL("fmi3Terminate", fmi3Terminate(c));
    }
    alloc_own_free(x);
    fmi3FreeInstance(c);
}
