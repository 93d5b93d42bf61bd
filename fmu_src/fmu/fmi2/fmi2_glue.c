/* FMI 2.0 front-end: the fmi2* functions, a thin layer over the FMI-independent instance
 * (fmu_instance.c: state machine, get/set through the variable table, model exchange, FMU state)
 * and the co-simulation stepper (cosimulation.c). What is FMI 2.0's own is here: the types and
 * calling conventions, the logger callback (its message is a format string), fmi2SetupExperiment,
 * fmi2NewDiscreteStates' event info and the asynchronous status functions. The FMI 3.0 front-end
 * is fmi3_glue.c. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"

#include "cosimulation.h"
#include "fmi2_states.h"
#include "fmu_instance.h"

#define MSG_SIZE 512

/* The importer's logger: it treats the message as a format string, so '%' is escaped. */
static void log_fmi2(const fmu_instance_t *inst, fmu_status_t status, const char *category,
                     const char *message)
{
    char escaped[2 * MSG_SIZE];
    size_t j = 0;
    for (size_t i = 0; message[i] != '\0' && j + 2 < sizeof(escaped); i++) {
        if (message[i] == '%') {
            escaped[j++] = '%';
        }
        escaped[j++] = message[i];
    }
    escaped[j] = '\0';
    const fmi2CallbackLogger logger = (fmi2CallbackLogger)inst->logger;
    logger((fmi2ComponentEnvironment)inst->environment, inst->instance_name, (fmi2Status)status,
           category, escaped);
}

#define INST(c) ((fmu_instance_t *)(c))
#define ST(s) ((fmi2Status)(s))
#define LOG_ERROR FMU_LOG_ERROR

/* ------------------------------------------------------------------------------------------ */
/* common functions */

const char *fmi2GetTypesPlatform(void)
{
    return fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    if (!ALLOWED(INST(c), fmi2SetDebugLogging)) {
        return fmi2Error;
    }
    return ST(fmu_set_debug_logging(INST(c), "fmi2SetDebugLogging", loggingOn, nCategories,
                                    categories));
}

/* fmi2Instantiate's arguments: 0 if they are fine, else -1 (told to the logger, if any). */
static int instantiate_refused(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                               fmi2CallbackLogger logger, fmi2ComponentEnvironment env)
{
    const char *name = instanceName != NULL ? instanceName : fmu_model.model_identifier;
    char msg[MSG_SIZE];
    if (instanceName == NULL || instanceName[0] == '\0') {
        snprintf(msg, sizeof(msg), "fmi2Instantiate: instanceName is NULL or empty");
    } else if (fmuGUID == NULL || strcmp(fmuGUID, fmu_model.guid) != 0) {
        snprintf(msg, sizeof(msg),
                 "fmi2Instantiate: fmuGUID does not match this binary (expected %s)",
                 fmu_model.guid);
    } else if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        snprintf(msg, sizeof(msg), "fmi2Instantiate: unknown fmuType");
    } else {
        return 0;
    }
    if (logger) {
        logger(env, name, fmi2Error, "logStatusError", msg);
    }
    return -1;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    fmi2CallbackLogger logger = functions != NULL ? functions->logger : NULL;
    fmi2ComponentEnvironment env = functions != NULL ? functions->componentEnvironment : NULL;
    if (instantiate_refused(instanceName, fmuType, fmuGUID, logger, env) != 0) {
        return NULL;
    }
    fmu_instance_t *inst = fmu_instance_new(instanceName,
                                            fmuType == fmi2ModelExchange ? FMU_ME : FMU_CS, 2,
                                            loggingOn);
    if (inst == NULL) {
        if (logger) {
            logger(env, instanceName, fmi2Error, "logStatusError",
                   "fmi2Instantiate: out of memory");
        }
        return NULL;
    }
    inst->stepper = &cs_stepper;
    inst->log_message = logger != NULL ? log_fmi2 : NULL;
    inst->logger = (fmu_callback_t)logger;
    inst->environment = env;
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    fmu_instance_free(INST(c));
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2SetupExperiment)) {
        return fmi2Error;
    }
    return ST(fmu_setup_experiment(inst, "fmi2SetupExperiment", toleranceDefined, tolerance,
                                   startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2EnterInitializationMode)) {
        return fmi2Error;
    }
    inst->state = FMU_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2ExitInitializationMode)) {
        return fmi2Error;
    }
    if (fmu_exit_initialization(inst, "fmi2ExitInitializationMode") != FMU_OK) {
        return fmi2Error;
    }
    inst->state = inst->type == FMU_ME ? FMU_EVENT : FMU_STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2Terminate)) {
        return fmi2Error;
    }
    inst->state = FMU_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2Reset)) {
        return fmi2Error;
    }
    fmu_instance_reset(inst);
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* get and set: Integer covers the enumerations, Booleans are fmi2Boolean (int) */

#define ACCEPT_REAL FMU_ACCEPT(CSFH_TYPE_REAL)
#define ACCEPT_INTEGER (FMU_ACCEPT(CSFH_TYPE_INTEGER) | FMU_ACCEPT(CSFH_TYPE_ENUMERATION))
#define ACCEPT_BOOLEAN FMU_ACCEPT(CSFH_TYPE_BOOLEAN)

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    if (!ALLOWED(INST(c), fmi2GetReal)) {
        return fmi2Error;
    }
    return ST(fmu_get_values(INST(c), "fmi2GetReal", vr, nvr, ACCEPT_REAL, FMU_VALUE_DOUBLE,
                             value));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    if (!ALLOWED(INST(c), fmi2GetInteger)) {
        return fmi2Error;
    }
    return ST(fmu_get_values(INST(c), "fmi2GetInteger", vr, nvr, ACCEPT_INTEGER, FMU_VALUE_INT,
                             value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    if (!ALLOWED(INST(c), fmi2GetBoolean)) {
        return fmi2Error;
    }
    return ST(fmu_get_values(INST(c), "fmi2GetBoolean", vr, nvr, ACCEPT_BOOLEAN, FMU_VALUE_INT,
                             value));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    fmu_instance_t *inst = INST(c);
    (void)value;
    if (!ALLOWED(inst, fmi2GetString)) {
        return fmi2Error;
    }
    if (nvr > 0) {
        LOG_ERROR(inst, "fmi2GetString: unknown value reference %u (the model has no String "
                        "variables)", vr != NULL ? vr[0] : 0u);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    if (!ALLOWED(INST(c), fmi2SetReal)) {
        return fmi2Error;
    }
    return ST(fmu_set_values(INST(c), "fmi2SetReal", vr, nvr, ACCEPT_REAL, FMU_VALUE_DOUBLE,
                             value));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    if (!ALLOWED(INST(c), fmi2SetInteger)) {
        return fmi2Error;
    }
    return ST(fmu_set_values(INST(c), "fmi2SetInteger", vr, nvr, ACCEPT_INTEGER, FMU_VALUE_INT,
                             value));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    if (!ALLOWED(INST(c), fmi2SetBoolean)) {
        return fmi2Error;
    }
    return ST(fmu_set_values(INST(c), "fmi2SetBoolean", vr, nvr, ACCEPT_BOOLEAN, FMU_VALUE_INT,
                             value));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    fmu_instance_t *inst = INST(c);
    (void)value;
    if (!ALLOWED(inst, fmi2SetString)) {
        return fmi2Error;
    }
    if (nvr > 0) {
        LOG_ERROR(inst, "fmi2SetString: unknown value reference %u (the model has no String "
                        "variables)", vr != NULL ? vr[0] : 0u);
        return fmi2Error;
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* FMU state (fmu_instance.c: snapshot, validation on restore) */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    if (!ALLOWED(INST(c), fmi2GetFMUstate)) {
        return fmi2Error;
    }
    return ST(fmu_state_get(INST(c), "fmi2GetFMUstate", FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    if (!ALLOWED(INST(c), fmi2SetFMUstate)) {
        return fmi2Error;
    }
    return ST(fmu_state_set(INST(c), "fmi2SetFMUstate", FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    if (!ALLOWED(INST(c), fmi2FreeFMUstate)) {
        return fmi2Error;
    }
    return ST(fmu_state_free(INST(c), "fmi2FreeFMUstate", FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    if (!ALLOWED(INST(c), fmi2SerializedFMUstateSize)) {
        return fmi2Error;
    }
    return ST(fmu_state_size(INST(c), "fmi2SerializedFMUstateSize", FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    if (!ALLOWED(INST(c), fmi2SerializeFMUstate)) {
        return fmi2Error;
    }
    return ST(fmu_state_serialize(INST(c), "fmi2SerializeFMUstate", FMUstate,
                                  (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    if (!ALLOWED(INST(c), fmi2DeSerializeFMUstate)) {
        return fmi2Error;
    }
    return ST(fmu_state_deserialize(INST(c), "fmi2DeSerializeFMUstate",
                                    (const unsigned char *)serializedState, size, FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    if (!ALLOWED(INST(c), fmi2GetDirectionalDerivative)) {
        return fmi2Error;
    }
    const fmu_derivative_call_t call = {vUnknown_ref, vKnown_ref, nUnknown, nKnown, dvKnown,
                                        dvUnknown, nKnown, nUnknown, 0};
    return ST(fmu_partial_derivatives(INST(c), "fmi2GetDirectionalDerivative", &call));
}

/* ------------------------------------------------------------------------------------------ */
/* model exchange */

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2EnterEventMode)) {
        return fmi2Error;
    }
    inst->state = FMU_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2NewDiscreteStates) ||
        !fmu_not_null(inst, "fmi2NewDiscreteStates", eventInfo, "eventInfo")) {
        return fmi2Error;
    }
    const int mode_changed = fmu_event_update(inst) != 0;
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    /* The states keep their values at a contact event, but the right-hand side switches (the
     * contact force acts in the contact mode only), so the importer's integrator must restart
     * here: what it computed past the event used the other mode, and a multistep history
     * reaching across the switch is wrong. FMI 2.0 has no separate "restart" flag, and importers
     * restart when this flag is set (e.g. Reference-FMUs' fmusim restarts only then), so it is
     * set at every mode switch, and only then. The states returned are the unchanged ones, and
     * the event indicator keeps its sign across the switch (hysteresis), so re-reading them
     * cannot start another event: the event iteration ends (README, "Using the FMU in other
     * tools"). */
    eventInfo->valuesOfContinuousStatesChanged = mode_changed ? fmi2True : fmi2False;
    /* time events (csfh: the ends of the shock pulse): the next one after the current time */
    const double next = fmu_next_time_event(inst);
    eventInfo->nextEventTimeDefined = isfinite(next) ? fmi2True : fmi2False;
    eventInfo->nextEventTime = isfinite(next) ? next : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2EnterContinuousTimeMode)) {
        return fmi2Error;
    }
    inst->state = FMU_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    fmu_instance_t *inst = INST(c);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!ALLOWED(inst, fmi2CompletedIntegratorStep) ||
        !fmu_not_null(inst, "fmi2CompletedIntegratorStep", enterEventMode, "enterEventMode") ||
        !fmu_not_null(inst, "fmi2CompletedIntegratorStep", terminateSimulation,
                      "terminateSimulation")) {
        return fmi2Error;
    }
    const fmu_status_t status = fmu_completed_integrator_step(inst, "fmi2CompletedIntegratorStep");
    if (status <= FMU_WARNING) {
        *enterEventMode = fmi2False;
        *terminateSimulation = fmi2False;
    }
    return ST(status);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    if (!ALLOWED(INST(c), fmi2SetTime)) {
        return fmi2Error;
    }
    return ST(fmu_set_time(INST(c), "fmi2SetTime", time));
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    if (!ALLOWED(INST(c), fmi2SetContinuousStates)) {
        return fmi2Error;
    }
    return ST(fmu_set_continuous_states(INST(c), "fmi2SetContinuousStates", x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    if (!ALLOWED(INST(c), fmi2GetDerivatives)) {
        return fmi2Error;
    }
    return ST(fmu_get_derivatives(INST(c), "fmi2GetDerivatives", derivatives, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    if (!ALLOWED(INST(c), fmi2GetEventIndicators)) {
        return fmi2Error;
    }
    return ST(fmu_get_event_indicators(INST(c), "fmi2GetEventIndicators", eventIndicators, ni));
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    if (!ALLOWED(INST(c), fmi2GetContinuousStates)) {
        return fmi2Error;
    }
    return ST(fmu_get_continuous_states(INST(c), "fmi2GetContinuousStates", x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    if (!ALLOWED(INST(c), fmi2GetNominalsOfContinuousStates)) {
        return fmi2Error;
    }
    return ST(fmu_get_nominals(INST(c), "fmi2GetNominalsOfContinuousStates", x_nominal, nx));
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation (the stepper is in cosimulation.c) */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    fmu_instance_t *inst = INST(c);
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (!ALLOWED(inst, fmi2SetRealInputDerivatives)) {
        return fmi2Error;
    }
    LOG_ERROR(inst, "fmi2SetRealInputDerivatives: not supported (canInterpolateInputs = "
              "false; inputs are held over the step)");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    fmu_instance_t *inst = INST(c);
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (!ALLOWED(inst, fmi2GetRealOutputDerivatives)) {
        return fmi2Error;
    }
    LOG_ERROR(inst, "fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder = 0)");
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    fmu_instance_t *inst = INST(c);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!ALLOWED(inst, fmi2DoStep)) {
        return fmi2Error;
    }
    double t_end = 0.0;
    const fmu_status_t checked = fmu_check_step(inst, "fmi2DoStep", currentCommunicationPoint,
                                                communicationStepSize, &t_end);
    if (checked > FMU_WARNING) {
        return ST(checked); /* refused: the instance is unchanged and still usable */
    }
    if (communicationStepSize == 0.0) {
        return fmi2OK;
    }
    const fmu_status_t status = cs_do_step(inst, t_end, 0, NULL);
    if (status > FMU_WARNING) {
        inst->state = FMU_STEP_FAILED;
        return ST(status);
    }
    return ST(status > checked ? status : checked);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2CancelStep)) {
        return fmi2Error;
    }
    LOG_ERROR(inst, "fmi2CancelStep: not supported (canRunAsynchronuously = false)");
    return fmi2Error;
}

/* No asynchronous step: nothing to report. */
static fmi2Status no_status(fmu_instance_t *inst, const char *function)
{
    LOG_ERROR(inst, "%s: no asynchronous step to report on", function);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    if (!ALLOWED(INST(c), fmi2GetStatus)) {
        return fmi2Error;
    }
    return no_status(INST(c), "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2GetRealStatus)) {
        return fmi2Error;
    }
    if (value != NULL && s == fmi2LastSuccessfulTime) {
        *value = *fmu_time(inst);
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    if (!ALLOWED(INST(c), fmi2GetIntegerStatus)) {
        return fmi2Error;
    }
    return no_status(INST(c), "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    fmu_instance_t *inst = INST(c);
    if (!ALLOWED(inst, fmi2GetBooleanStatus)) {
        return fmi2Error;
    }
    if (value != NULL && s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    if (!ALLOWED(INST(c), fmi2GetStringStatus)) {
        return fmi2Error;
    }
    return no_status(INST(c), "fmi2GetStringStatus");
}
