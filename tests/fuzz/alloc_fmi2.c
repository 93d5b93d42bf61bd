/* The failed-allocation test's FMI 2.0 scenario (alloc_fail.c runs it): co-simulation with each
 * method the FMU has (BDF, Adams, RK45, auto through a switch to BDF), FMU states taken,
 * serialized, deserialized and restored in the middle of each run, then model exchange with an
 * explicit Euler master through events; each part on its own instance, freed at its end. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"

#include "alloc_fail.h"
#include "alloc_scene.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof(text), message, args);
    va_end(args);
    alloc_logged((int)status, category, text);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static void read_reals(fmi2Component c)
{
    size_t n = 0;
    const fmi2ValueReference *reals = alloc_reals(&n);
    double *x = (double *)alloc_own(n * sizeof(double));
    const int s = ALLOC_CALL("fmi2GetReal", fmi2GetReal(c, reals, n, x));
    alloc_values("fmi2GetReal", s, x, n);
    alloc_own_free(x);
}

/* The scene's values (alloc_scene.h) and the method, for the variables the FMU has. */
static void set_scene(fmi2Component c, int method)
{
    for (size_t i = 0; i < ALLOC_SCENE_SIZE; i++) {
        const csfh_variable_t *v = alloc_variable(alloc_scene[i].name);
        if (v != NULL) {
            ALLOC_CALL("fmi2SetReal", fmi2SetReal(c, &v->vr, 1, &alloc_scene[i].value));
        }
    }
    const csfh_variable_t *m = alloc_variable("solver.method");
    if (m != NULL && method != 0) {
        ALLOC_CALL("fmi2SetInteger", fmi2SetInteger(c, &m->vr, 1, &method));
    }
}

static int start(fmi2Component c)
{
    return ALLOC_CALL("fmi2SetupExperiment",
                      fmi2SetupExperiment(c, fmi2True, ALLOC_TOLERANCE, 0.0, fmi2False, 0.0)) <=
               ALLOC_WARNING &&
           ALLOC_CALL("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)) <=
               ALLOC_WARNING &&
           ALLOC_CALL("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)) <=
               ALLOC_WARNING;
}

/* An FMU state taken, serialized, deserialized and restored; both freed. */
static void fmu_states(fmi2Component c)
{
    fmi2FMUstate s = NULL, d = NULL;
    size_t size = 0;
    if (ALLOC_CALL("fmi2GetFMUstate", fmi2GetFMUstate(c, &s)) > ALLOC_WARNING) {
        return;
    }
    if (ALLOC_CALL("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(c, s, &size)) <=
        ALLOC_WARNING) {
        fmi2Byte *bytes = (fmi2Byte *)alloc_own(size);
        if (ALLOC_CALL("fmi2SerializeFMUstate", fmi2SerializeFMUstate(c, s, bytes, size)) <=
                ALLOC_WARNING &&
            ALLOC_CALL("fmi2DeSerializeFMUstate", fmi2DeSerializeFMUstate(c, bytes, size, &d)) <=
                ALLOC_WARNING) {
            ALLOC_CALL("fmi2SetFMUstate", fmi2SetFMUstate(c, d));
            ALLOC_CALL("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &d));
        }
        alloc_own_free(bytes);
    }
    ALLOC_CALL("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &s));
}

void alloc_co_simulation(const char *method_name, int method)
{
    char name[64];
    snprintf(name, sizeof(name), "fmi2Instantiate CS%s%s", method_name[0] ? " " : "", method_name);
    fmi2Component c;
    if (!ALLOC_INSTANCE(name, c,
                        fmi2Instantiate("alloc-cs", fmi2CoSimulation, fmu_model.guid, NULL,
                                        &callbacks, fmi2False, fmi2True))) {
        return;
    }
    set_scene(c, method);
    if (start(c)) {
        double t = 0.0;
        int taken = 0;
        for (int k = 0; k < ALLOC_CS_STEPS; k++) {
            if (ALLOC_CALL("fmi2DoStep", fmi2DoStep(c, t, ALLOC_CS_STEP, fmi2True)) >
                ALLOC_WARNING) {
                break;
            }
            t += ALLOC_CS_STEP;
            read_reals(c);
            if (!taken && t >= ALLOC_STATES_AT) {
                fmu_states(c);
                taken = 1;
            }
        }
        ALLOC_CALL("fmi2Terminate", fmi2Terminate(c));
    }
    fmi2FreeInstance(c);
}

/* Event mode until the discrete states settle, then continuous-time mode: 0, or -1. */
static int events(fmi2Component c)
{
    fmi2EventInfo info;
    for (int i = 0; i < 10; i++) {
        if (ALLOC_CALL("fmi2NewDiscreteStates", fmi2NewDiscreteStates(c, &info)) >
            ALLOC_WARNING) {
            return -1;
        }
        if (!info.newDiscreteStatesNeeded) {
            break;
        }
    }
    return ALLOC_CALL("fmi2EnterContinuousTimeMode", fmi2EnterContinuousTimeMode(c)) <=
                   ALLOC_WARNING
               ? 0
               : -1;
}

/* One explicit Euler step of model exchange: 0, or -1. */
static int euler_step(fmi2Component c, double *t, double *x, double *dx, double *z, size_t nx,
                      size_t nz)
{
    int s = ALLOC_CALL("fmi2GetDerivatives", fmi2GetDerivatives(c, dx, nx));
    alloc_values("fmi2GetDerivatives", s, dx, nx);
    for (size_t i = 0; i < nx && s <= ALLOC_WARNING; i++) {
        x[i] += ALLOC_ME_STEP * dx[i];
    }
    *t += ALLOC_ME_STEP;
    if (s > ALLOC_WARNING || ALLOC_CALL("fmi2SetTime", fmi2SetTime(c, *t)) > ALLOC_WARNING ||
        ALLOC_CALL("fmi2SetContinuousStates", fmi2SetContinuousStates(c, x, nx)) >
            ALLOC_WARNING) {
        return -1;
    }
    s = ALLOC_CALL("fmi2GetEventIndicators", fmi2GetEventIndicators(c, z, nz));
    alloc_values("fmi2GetEventIndicators", s, z, nz);
    fmi2Boolean enter = fmi2False, terminate = fmi2False;
    if (s > ALLOC_WARNING ||
        ALLOC_CALL("fmi2CompletedIntegratorStep",
                   fmi2CompletedIntegratorStep(c, fmi2True, &enter, &terminate)) > ALLOC_WARNING) {
        return -1;
    }
    if (enter &&
        (ALLOC_CALL("fmi2EnterEventMode", fmi2EnterEventMode(c)) > ALLOC_WARNING || events(c))) {
        return -1;
    }
    return 0;
}

void alloc_model_exchange(void)
{
    fmi2Component c;
    if (!ALLOC_INSTANCE("fmi2Instantiate ME", c,
                        fmi2Instantiate("alloc-me", fmi2ModelExchange, fmu_model.guid, NULL,
                                        &callbacks, fmi2False, fmi2True))) {
        return;
    }
    const size_t nx = (size_t)fmu_model.n_states, nz = (size_t)fmu_model.n_event_indicators;
    double *x = (double *)alloc_own(3 * nx * sizeof(double) + nz * sizeof(double));
    double *dx = x + nx, *nominal = dx + nx, *z = nominal + nx;
    set_scene(c, 0); /* (no method: model exchange) */
    if (start(c) && events(c) == 0 &&
        ALLOC_CALL("fmi2GetContinuousStates", fmi2GetContinuousStates(c, x, nx)) <=
            ALLOC_WARNING) {
        const int s = ALLOC_CALL("fmi2GetNominalsOfContinuousStates",
                                 fmi2GetNominalsOfContinuousStates(c, nominal, nx));
        alloc_values("fmi2GetNominalsOfContinuousStates", s, nominal, nx);
        double t = 0.0;
        for (int k = 0; k < ALLOC_ME_STEPS && euler_step(c, &t, x, dx, z, nx, nz) == 0; k++) {
            read_reals(c);
            if (k == ALLOC_ME_STEPS / 2) {
                fmu_states(c);
            }
        }
        ALLOC_CALL("fmi2Terminate", fmi2Terminate(c));
    }
    alloc_own_free(x);
    fmi2FreeInstance(c);
}
