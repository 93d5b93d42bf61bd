/* FMI 3.0 front-end: the fmi3* functions, a thin layer over the FMI-independent instance
 * (fmu_instance.c) and the co-simulation stepper (cosimulation.c), like fmi2_glue.c for FMI 2.0.
 * The same model, variable table, checks, log categories and FMU state as the FMI 2.0 build.
 *
 * What is FMI 3.0's own:
 *   types     Float64 (the Real variables), Int32 (Integer), Int64 (the enumerations), Boolean
 *             (C bool); the other types have no variables and refuse any value reference;
 *   ME        the gap as the event indicator (modelDescription: ModelStructure/EventIndicator),
 *             fmi3UpdateDiscreteStates with the same flags as fmi2NewDiscreteStates;
 *   CS        Event Mode when the importer uses it (eventModeUsed), and early return
 *             (earlyReturnAllowed): fmi3DoStep then stops at the first contact onset or release
 *             inside the step, with the event handled (the contact mode switched), and returns
 *             earlyReturn = true and lastSuccessfulTime = the event time, so that a master
 *             can update its actuators there; with eventModeUsed it also asks for Event Mode
 *             (eventHandlingNeeded). Without earlyReturnAllowed the step is never cut: the
 *             events inside it are handled as in FMI 2.0.
 * Not provided (refused with a message, fmi3_unsupported.c): Scheduled Execution, clocks,
 * configuration mode, output derivatives, intermediate update. Directional and adjoint
 * derivatives: fmu_derivatives.c. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "cosimulation.h"
#include "fmi3_front_end.h"

#define MSG_SIZE 512

/* The importer's logger (the message is plain text, no format string). */
static void log_fmi3(const fmu_instance_t *inst, fmu_status_t status, const char *category,
                     const char *message)
{
    const fmi3LogMessageCallback logger = (fmi3LogMessageCallback)inst->logger;
    logger((fmi3InstanceEnvironment)inst->environment, (fmi3Status)status, category, message);
}

/* ------------------------------------------------------------------------------------------ */
/* common functions */

const char *fmi3GetVersion(void)
{
    return fmi3Version;
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    if (!ALLOWED(INST(instance), fmi3SetDebugLogging)) {
        return fmi3Error;
    }
    return ST(fmu_set_debug_logging(INST(instance), "fmi3SetDebugLogging", loggingOn,
                                    nCategories, categories));
}

static fmu_instance_t *instantiate(const char *function, fmi3String instanceName,
                                   fmi3String instantiationToken, fmu_kind_t kind,
                                   fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                   fmi3LogMessageCallback logger)
{
    if (instanceName == NULL || instanceName[0] == '\0') {
        if (logger) {
            char msg[MSG_SIZE];
            snprintf(msg, sizeof(msg), "%s: instanceName is NULL or empty", function);
            logger(env, fmi3Error, "logStatusError", msg);
        }
        return NULL;
    }
    if (instantiationToken == NULL || strcmp(instantiationToken, fmu_model.guid) != 0) {
        if (logger) {
            char msg[MSG_SIZE];
            snprintf(msg, sizeof(msg),
                     "%s: instantiationToken does not match this binary (expected %s)", function,
                     fmu_model.guid);
            logger(env, fmi3Error, "logStatusError", msg);
        }
        return NULL;
    }
    fmu_instance_t *inst = fmu_instance_new(instanceName, kind, 3, loggingOn);
    if (inst == NULL) {
        if (logger) {
            char msg[MSG_SIZE];
            snprintf(msg, sizeof(msg), "%s: out of memory", function);
            logger(env, fmi3Error, "logStatusError", msg);
        }
        return NULL;
    }
    inst->stepper = &cs_stepper;
    inst->log_message = logger != NULL ? log_fmi3 : NULL;
    inst->logger = (fmu_callback_t)logger;
    inst->environment = env;
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)resourcePath;
    (void)visible;
    return instantiate("fmi3InstantiateModelExchange", instanceName, instantiationToken, FMU_ME,
                       loggingOn, instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath;
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate; /* providesIntermediateUpdate = false: never called */
    if (nRequiredIntermediateVariables > 0) {
        if (logMessage) {
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: requiredIntermediateVariables given, but "
                       "the FMU provides no intermediate update (providesIntermediateUpdate = "
                       "false)");
        }
        return NULL;
    }
    fmu_instance_t *inst = instantiate("fmi3InstantiateCoSimulation", instanceName,
                                       instantiationToken, FMU_CS, loggingOn,
                                       instanceEnvironment, logMessage);
    if (inst != NULL) {
        inst->event_mode_used = eventModeUsed ? 1 : 0;
        inst->early_return_allowed = earlyReturnAllowed ? 1 : 0;
    }
    return inst;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: the FMU has no Scheduled Execution "
                   "interface");
    }
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    fmu_instance_free(INST(instance));
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3EnterInitializationMode)) {
        return fmi3Error;
    }
    if (fmu_setup_experiment(inst, "fmi3EnterInitializationMode", toleranceDefined, tolerance,
                             startTime, stopTimeDefined, stopTime) != FMU_OK) {
        return fmi3Error; /* refused: still Instantiated */
    }
    inst->state = FMU_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3ExitInitializationMode)) {
        return fmi3Error;
    }
    if (fmu_exit_initialization(inst, "fmi3ExitInitializationMode") != FMU_OK) {
        return fmi3Error;
    }
    /* ME: Event Mode; CS: Event Mode if the importer uses it, else Step Mode */
    inst->state = inst->type == FMU_ME || inst->event_mode_used ? FMU_EVENT : FMU_STEP_COMPLETE;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3EnterEventMode)) {
        return fmi3Error;
    }
    if (inst->type == FMU_CS && !inst->event_mode_used) {
        LOG_ERROR(inst, "fmi3EnterEventMode: the instance was made with eventModeUsed = false");
        return fmi3Error;
    }
    inst->state = FMU_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3Terminate)) {
        return fmi3Error;
    }
    inst->state = FMU_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3Reset)) {
        return fmi3Error;
    }
    fmu_instance_reset(inst);
    return fmi3OK;
}

/* ------------------------------------------------------------------------------------------ */
/* get and set: scalar variables only, so nValues must equal nValueReferences */

static int counts_match(fmu_instance_t *inst, const char *function, size_t nvr, size_t nValues)
{
    if (nvr != nValues) {
        LOG_ERROR(inst, "%s: nValues = %zu, expected nValueReferences = %zu (every variable is a "
                        "scalar)", function, nValues, nvr);
        return 0;
    }
    return 1;
}

#define GET(name, accept, kind, type)                                                          \
    fmi3Status fmi3Get##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                             type values[], size_t nValues)                                     \
    {                                                                                          \
        if (!ALLOWED(INST(instance), fmi3Get##name) ||                                         \
            !counts_match(INST(instance), "fmi3Get" #name, nvr, nValues)) {                    \
            return fmi3Error;                                                                  \
        }                                                                                      \
        return ST(fmu_get_values(INST(instance), "fmi3Get" #name, vr, nvr, accept, kind,       \
                                 values));                                                     \
    }
#define SET(name, accept, kind, type)                                                          \
    fmi3Status fmi3Set##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                             const type values[], size_t nValues)                               \
    {                                                                                          \
        if (!ALLOWED(INST(instance), fmi3Set##name) ||                                         \
            !counts_match(INST(instance), "fmi3Set" #name, nvr, nValues)) {                    \
            return fmi3Error;                                                                  \
        }                                                                                      \
        return ST(fmu_set_values(INST(instance), "fmi3Set" #name, vr, nvr, accept, kind,       \
                                 values));                                                     \
    }

GET(Float64, FMU_ACCEPT(CSFH_TYPE_REAL), FMU_VALUE_DOUBLE, fmi3Float64)
GET(Int32, FMU_ACCEPT(CSFH_TYPE_INTEGER), FMU_VALUE_INT, fmi3Int32)
GET(Int64, FMU_ACCEPT(CSFH_TYPE_ENUMERATION), FMU_VALUE_INT64, fmi3Int64)
GET(Boolean, FMU_ACCEPT(CSFH_TYPE_BOOLEAN), FMU_VALUE_BOOL, fmi3Boolean)
SET(Float64, FMU_ACCEPT(CSFH_TYPE_REAL), FMU_VALUE_DOUBLE, fmi3Float64)
SET(Int32, FMU_ACCEPT(CSFH_TYPE_INTEGER), FMU_VALUE_INT, fmi3Int32)
SET(Int64, FMU_ACCEPT(CSFH_TYPE_ENUMERATION), FMU_VALUE_INT64, fmi3Int64)
SET(Boolean, FMU_ACCEPT(CSFH_TYPE_BOOLEAN), FMU_VALUE_BOOL, fmi3Boolean)

/* ------------------------------------------------------------------------------------------ */
/* FMU state (fmu_instance.c: snapshot, the same validation on restore as FMI 2.0) */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    if (!ALLOWED(INST(instance), fmi3GetFMUState)) {
        return fmi3Error;
    }
    return ST(fmu_state_get(INST(instance), "fmi3GetFMUState", FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    if (!ALLOWED(INST(instance), fmi3SetFMUState)) {
        return fmi3Error;
    }
    return ST(fmu_state_set(INST(instance), "fmi3SetFMUState", FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    if (!ALLOWED(INST(instance), fmi3FreeFMUState)) {
        return fmi3Error;
    }
    return ST(fmu_state_free(INST(instance), "fmi3FreeFMUState", FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    if (!ALLOWED(INST(instance), fmi3SerializedFMUStateSize)) {
        return fmi3Error;
    }
    return ST(fmu_state_size(INST(instance), "fmi3SerializedFMUStateSize", FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    if (!ALLOWED(INST(instance), fmi3SerializeFMUState)) {
        return fmi3Error;
    }
    return ST(fmu_state_serialize(INST(instance), "fmi3SerializeFMUState", FMUState,
                                  serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    if (!ALLOWED(INST(instance), fmi3DeserializeFMUState)) {
        return fmi3Error;
    }
    return ST(fmu_state_deserialize(INST(instance), "fmi3DeserializeFMUState", serializedState,
                                    size, FMUState));
}

/* ------------------------------------------------------------------------------------------ */
/* Event Mode (model exchange, and co-simulation with eventModeUsed) */

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    fmu_instance_t *inst = INST(instance);
    const char *f = "fmi3UpdateDiscreteStates";
    if (!ALLOWED(inst, fmi3UpdateDiscreteStates) ||
        !fmu_not_null(inst, f, discreteStatesNeedUpdate, "discreteStatesNeedUpdate") ||
        !fmu_not_null(inst, f, terminateSimulation, "terminateSimulation") ||
        !fmu_not_null(inst, f, nominalsOfContinuousStatesChanged,
                      "nominalsOfContinuousStatesChanged") ||
        !fmu_not_null(inst, f, valuesOfContinuousStatesChanged, "valuesOfContinuousStatesChanged") ||
        !fmu_not_null(inst, f, nextEventTimeDefined, "nextEventTimeDefined") ||
        !fmu_not_null(inst, f, nextEventTime, "nextEventTime")) {
        return fmi3Error;
    }
    /* the same event update as fmi2NewDiscreteStates (fmi2_glue.c: why the values-changed flag
     * is set at every contact mode switch, and only then). In co-simulation the stepper has
     * handled the event already (the switch is done, nothing changes here) */
    const int mode_changed = fmu_event_update(inst) != 0;
    if (mode_changed && inst->type == FMU_CS) {
        inst->restart_integration = 1;
    }
    *discreteStatesNeedUpdate = false;
    *terminateSimulation = false;
    *nominalsOfContinuousStatesChanged = false;
    *valuesOfContinuousStatesChanged = mode_changed;
    const double next = fmu_next_time_event(inst);
    *nextEventTimeDefined = isfinite(next) && inst->type == FMU_ME;
    *nextEventTime = *nextEventTimeDefined ? next : 0.0;
    return fmi3OK;
}

/* ------------------------------------------------------------------------------------------ */
/* model exchange */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3EnterContinuousTimeMode)) {
        return fmi3Error;
    }
    inst->state = FMU_CONTINUOUS;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    fmu_instance_t *inst = INST(instance);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!ALLOWED(inst, fmi3CompletedIntegratorStep) ||
        !fmu_not_null(inst, "fmi3CompletedIntegratorStep", enterEventMode, "enterEventMode") ||
        !fmu_not_null(inst, "fmi3CompletedIntegratorStep", terminateSimulation,
                      "terminateSimulation")) {
        return fmi3Error;
    }
    const fmu_status_t status = fmu_completed_integrator_step(inst, "fmi3CompletedIntegratorStep");
    if (status <= FMU_WARNING) {
        *enterEventMode = false;
        *terminateSimulation = false;
    }
    return ST(status);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    if (!ALLOWED(INST(instance), fmi3SetTime)) {
        return fmi3Error;
    }
    return ST(fmu_set_time(INST(instance), "fmi3SetTime", time));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    if (!ALLOWED(INST(instance), fmi3SetContinuousStates)) {
        return fmi3Error;
    }
    return ST(fmu_set_continuous_states(INST(instance), "fmi3SetContinuousStates",
                                        continuousStates, nContinuousStates));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    if (!ALLOWED(INST(instance), fmi3GetContinuousStateDerivatives)) {
        return fmi3Error;
    }
    return ST(fmu_get_derivatives(INST(instance), "fmi3GetContinuousStateDerivatives",
                                  derivatives, nContinuousStates));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    if (!ALLOWED(INST(instance), fmi3GetEventIndicators)) {
        return fmi3Error;
    }
    return ST(fmu_get_event_indicators(INST(instance), "fmi3GetEventIndicators", eventIndicators,
                                       nEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    if (!ALLOWED(INST(instance), fmi3GetContinuousStates)) {
        return fmi3Error;
    }
    return ST(fmu_get_continuous_states(INST(instance), "fmi3GetContinuousStates",
                                        continuousStates, nContinuousStates));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    if (!ALLOWED(INST(instance), fmi3GetNominalsOfContinuousStates)) {
        return fmi3Error;
    }
    return ST(fmu_get_nominals(INST(instance), "fmi3GetNominalsOfContinuousStates", nominals,
                               nContinuousStates));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3GetNumberOfEventIndicators) ||
        !fmu_not_null(inst, "fmi3GetNumberOfEventIndicators", nEventIndicators,
                      "nEventIndicators")) {
        return fmi3Error;
    }
    *nEventIndicators = (size_t)fmu_model.n_event_indicators;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3GetNumberOfContinuousStates) ||
        !fmu_not_null(inst, "fmi3GetNumberOfContinuousStates", nContinuousStates,
                      "nContinuousStates")) {
        return fmi3Error;
    }
    *nContinuousStates = (size_t)fmu_model.n_states;
    return fmi3OK;
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation (the stepper is in cosimulation.c) */

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    fmu_instance_t *inst = INST(instance);
    if (!ALLOWED(inst, fmi3EnterStepMode)) {
        return fmi3Error;
    }
    inst->state = FMU_STEP_COMPLETE;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    fmu_instance_t *inst = INST(instance);
    const char *f = "fmi3DoStep";
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!ALLOWED(inst, fmi3DoStep) ||
        !fmu_not_null(inst, f, eventHandlingNeeded, "eventHandlingNeeded") ||
        !fmu_not_null(inst, f, terminateSimulation, "terminateSimulation") ||
        !fmu_not_null(inst, f, earlyReturn, "earlyReturn") ||
        !fmu_not_null(inst, f, lastSuccessfulTime, "lastSuccessfulTime")) {
        return fmi3Error;
    }
    *eventHandlingNeeded = false;
    *terminateSimulation = false;
    *earlyReturn = false;
    *lastSuccessfulTime = *fmu_time(inst);
    double t_end = 0.0;
    const fmu_status_t checked = fmu_check_step(inst, f, currentCommunicationPoint,
                                                communicationStepSize, &t_end);
    if (checked > FMU_WARNING) {
        return ST(checked); /* refused: the instance is unchanged and still usable */
    }
    if (communicationStepSize == 0.0) {
        return fmi3OK;
    }
    int stopped = 0;
    const fmu_status_t status = cs_do_step(inst, t_end, inst->early_return_allowed, &stopped);
    *lastSuccessfulTime = *fmu_time(inst);
    if (status > FMU_WARNING) {
        inst->state = FMU_STEP_FAILED;
        return ST(status);
    }
    if (stopped) {
        /* a contact onset or release at *lastSuccessfulTime (<= t_end): the master may update
         * its inputs there (in Event Mode when it uses it) */
        *earlyReturn = *lastSuccessfulTime < t_end;
        *eventHandlingNeeded = inst->event_mode_used != 0;
    }
    return ST(status > checked ? status : checked);
}

/* ------------------------------------------------------------------------------------------ */
/* partial derivatives (docs/model.md §15) */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    if (!ALLOWED(INST(instance), fmi3GetDirectionalDerivative)) {
        return fmi3Error;
    }
    const fmu_derivative_call_t call = {unknowns, knowns,      nUnknowns,    nKnowns, seed,
                                        sensitivity, nSeed, nSensitivity, 0};
    return ST(fmu_partial_derivatives(INST(instance), "fmi3GetDirectionalDerivative", &call));
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    if (!ALLOWED(INST(instance), fmi3GetAdjointDerivative)) {
        return fmi3Error;
    }
    const fmu_derivative_call_t call = {unknowns, knowns,      nUnknowns,    nKnowns, seed,
                                        sensitivity, nSeed, nSensitivity, 1};
    return ST(fmu_partial_derivatives(INST(instance), "fmi3GetAdjointDerivative", &call));
}
