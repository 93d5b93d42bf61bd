/* FMI 2.0 glue: instance life cycle, state machine, get/set through the generated variable table,
 * model-exchange functions and FMU state handling. Model-independent: the model is behind the
 * interface of fmu_model.h (csfh: csfh_fmu_model.c, physics in ../core; the comb-drive actuator:
 * ../combdrive/). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_instance.h"

#define MSG_SIZE 512

/* ------------------------------------------------------------------------------------------ */
/* logging */

static const char *category_name(unsigned int category)
{
    switch (category) {
    case LOG_EVENTS:
        return "logEvents";
    case LOG_STATUS_WARNING:
        return "logStatusWarning";
    case LOG_STATUS_ERROR:
        return "logStatusError";
    default:
        return "logAll";
    }
}

void fmu_log(fmu_instance_t *inst, fmi2Status status, unsigned int category, const char *fmt, ...)
{
    if (inst == NULL || inst->logger == NULL || !(inst->log_categories & category)) {
        return;
    }
    char raw[MSG_SIZE], escaped[2 * MSG_SIZE];
    va_list args;
    va_start(args, fmt);
    vsnprintf(raw, sizeof(raw), fmt, args);
    va_end(args);
    /* the logger treats the message as a format string: escape '%' */
    size_t j = 0;
    for (size_t i = 0; raw[i] != '\0' && j + 2 < sizeof(escaped); i++) {
        if (raw[i] == '%') {
            escaped[j++] = '%';
        }
        escaped[j++] = raw[i];
    }
    escaped[j] = '\0';
    inst->logger(inst->environment, inst->instance_name, status, category_name(category),
                 escaped);
}

#define LOG_ERROR(inst, ...) fmu_log((inst), fmi2Error, LOG_STATUS_ERROR, __VA_ARGS__)

static const char *state_name(fmu_state_t s)
{
    switch (s) {
    case FMU_INSTANTIATED:
        return "Instantiated";
    case FMU_INITIALIZATION:
        return "InitializationMode";
    case FMU_EVENT:
        return "EventMode";
    case FMU_CONTINUOUS:
        return "ContinuousTimeMode";
    case FMU_STEP_COMPLETE:
        return "StepComplete";
    case FMU_STEP_FAILED:
        return "StepFailed";
    case FMU_TERMINATED:
        return "Terminated";
    default:
        return "Error";
    }
}

/* One state-machine check per call. */
static int allowed(fmu_instance_t *inst, const char *function, unsigned int states)
{
    if (inst == NULL) {
        return 0;
    }
    if (!(inst->state & states)) {
        LOG_ERROR(inst, "%s: illegal call in state %s", function, state_name(inst->state));
        return 0;
    }
    fmu_log(inst, fmi2OK, LOG_ALL, "%s", function);
    return 1;
}

static int not_null(fmu_instance_t *inst, const char *function, const void *p, const char *arg)
{
    if (p == NULL) {
        LOG_ERROR(inst, "%s: argument %s is NULL", function, arg);
        return 0;
    }
    return 1;
}

void fmu_invalidate(fmu_instance_t *inst)
{
    inst->outputs_valid = 0;
    inst->derivatives_valid = 0;
}

/* ------------------------------------------------------------------------------------------ */
/* model helpers */

static fmi2Status prepare(fmu_instance_t *inst, const char *function)
{
    if (inst->prepared) {
        return fmi2OK;
    }
    char msg[MSG_SIZE];
    if (fmu_model.prepare(inst->model, msg, sizeof(msg)) != 0) {
        LOG_ERROR(inst, "%s: %s", function, msg);
        return fmi2Error;
    }
    inst->prepared = 1;
    return fmi2OK;
}

static fmi2Status update_derivatives(fmu_instance_t *inst, const char *function)
{
    if (inst->derivatives_valid || fmu_model.n_states == 0) {
        return fmi2OK;
    }
    if (prepare(inst, function) != fmi2OK) {
        return fmi2Error;
    }
    double *x = fmu_states(inst);
    const int status = fmu_model.derivatives(inst->model, x, fmu_derivatives(inst));
    if (status == FMU_MODEL_NONFINITE) {
        char text[MSG_SIZE];
        size_t k = 0;
        text[0] = '\0';
        for (int i = 0; i < fmu_model.n_states && k + 1 < sizeof(text); i++) {
            k += (size_t)snprintf(text + k, sizeof(text) - k, "%s%g", i ? ", " : "", x[i]);
        }
        LOG_ERROR(inst, "%s: non-finite derivative at t = %.17g, state [%s]", function,
                  *fmu_time(inst), text);
        return fmi2Error;
    }
    inst->derivatives_valid = 1;
    /* no model warning here: integrators probe trial states (e.g. far inside a contact); the
     * warning comes from the outputs, which are evaluated at accepted states */
    return fmi2OK;
}

fmi2Status fmu_update_outputs(fmu_instance_t *inst, const char *function)
{
    if (inst->outputs_valid) {
        return fmi2OK;
    }
    if (prepare(inst, function) != fmi2OK) {
        return fmi2Error;
    }
    char msg[MSG_SIZE];
    msg[0] = '\0';
    const int status = fmu_model.outputs(inst->model, msg, sizeof(msg));
    if (status == FMU_MODEL_NONFINITE) {
        LOG_ERROR(inst, "%s: %s", function, msg);
        return fmi2Error;
    }
    inst->outputs_valid = 1;
    if (status == FMU_MODEL_WARNING) {
        if (!inst->warned_outputs) {
            inst->warned_outputs = 1;
            fmu_log(inst, fmi2Warning, LOG_STATUS_WARNING, "%s: %s", function, msg);
        }
        return fmi2Warning;
    }
    return fmi2OK;
}

int fmu_event_update(fmu_instance_t *inst)
{
    if (fmu_model.n_event_indicators == 0) {
        return 0;
    }
    char msg[MSG_SIZE];
    msg[0] = '\0';
    const int change = fmu_model.event_update(inst->model, msg, sizeof(msg));
    if (msg[0] != '\0') {
        fmu_log(inst, fmi2OK, LOG_EVENTS, "%s", msg);
    }
    if (change != 0) {
        fmu_invalidate(inst);
    }
    return change;
}

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
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst == NULL) {
        return fmi2Error;
    }
    if (nCategories > 0 && !not_null(inst, "fmi2SetDebugLogging", categories, "categories")) {
        return fmi2Error;
    }
    const unsigned int always = LOG_STATUS_ERROR | LOG_STATUS_WARNING;
    if (nCategories == 0) {
        inst->log_categories = loggingOn ? (LOG_EVENTS | LOG_ALL | always) : always;
        return fmi2OK;
    }
    for (size_t i = 0; i < nCategories; i++) {
        unsigned int bit = 0;
        if (categories[i] == NULL) {
            LOG_ERROR(inst, "fmi2SetDebugLogging: categories[%zu] is NULL", i);
            return fmi2Error;
        }
        if (strcmp(categories[i], "logEvents") == 0) {
            bit = LOG_EVENTS;
        } else if (strcmp(categories[i], "logStatusWarning") == 0) {
            bit = LOG_STATUS_WARNING;
        } else if (strcmp(categories[i], "logStatusError") == 0) {
            bit = LOG_STATUS_ERROR;
        } else if (strcmp(categories[i], "logAll") == 0) {
            bit = LOG_ALL;
        } else {
            LOG_ERROR(inst, "fmi2SetDebugLogging: unknown log category \"%s\"", categories[i]);
            return fmi2Error;
        }
        if (loggingOn) {
            inst->log_categories |= bit;
        } else {
            inst->log_categories &= ~bit;
        }
    }
    return fmi2OK;
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
    const char *name = instanceName != NULL ? instanceName : fmu_model.model_identifier;
    if (instanceName == NULL || instanceName[0] == '\0') {
        if (logger) {
            logger(env, name, fmi2Error, "logStatusError",
                   "fmi2Instantiate: instanceName is NULL or empty");
        }
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, fmu_model.guid) != 0) {
        if (logger) {
            char msg[MSG_SIZE];
            snprintf(msg, sizeof(msg),
                     "fmi2Instantiate: fmuGUID does not match this binary (expected %s)",
                     fmu_model.guid);
            logger(env, name, fmi2Error, "logStatusError", msg);
        }
        return NULL;
    }
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        if (logger) {
            logger(env, name, fmi2Error, "logStatusError", "fmi2Instantiate: unknown fmuType");
        }
        return NULL;
    }
    fmu_instance_t *inst = (fmu_instance_t *)calloc(1, sizeof(fmu_instance_t));
    if (inst == NULL) {
        return NULL;
    }
    inst->instance_name = (char *)malloc(strlen(instanceName) + 1);
    inst->model = calloc(1, fmu_model.size);
    if (inst->instance_name == NULL || inst->model == NULL) {
        free(inst->instance_name);
        free(inst->model);
        free(inst);
        return NULL;
    }
    strcpy(inst->instance_name, instanceName);
    inst->type = fmuType;
    inst->logger = logger;
    inst->environment = env;
    inst->log_categories = LOG_STATUS_ERROR | LOG_STATUS_WARNING;
    if (loggingOn) {
        inst->log_categories |= LOG_EVENTS | LOG_ALL;
    }
    fmu_model.set_defaults(inst->model);
    inst->state = FMU_INSTANTIATED;
    inst->tolerance = FMU_DEFAULT_TOLERANCE;
    return inst;
}

void fmi2FreeInstance(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst == NULL) {
        return;
    }
    cs_free(inst);
    free(inst->model);
    free(inst->instance_name);
    free(inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SetupExperiment", FMU_INSTANTIATED)) {
        return fmi2Error;
    }
    if (toleranceDefined && !(isfinite(tolerance) && tolerance > 0.0 && tolerance < 1.0)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: tolerance = %g must be in (0, 1)", tolerance);
        return fmi2Error;
    }
    if (!isfinite(startTime)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: startTime = %g is not finite", startTime);
        return fmi2Error;
    }
    if (stopTimeDefined && !(isfinite(stopTime) && stopTime >= startTime)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: stopTime = %g must be finite and >= startTime = %g",
                  stopTime, startTime);
        return fmi2Error;
    }
    if (toleranceDefined) {
        inst->tolerance = tolerance;
    }
    inst->start_time = startTime;
    inst->stop_time = stopTime;
    inst->stop_time_defined = stopTimeDefined ? 1 : 0;
    *fmu_time(inst) = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2EnterInitializationMode", FMU_INSTANTIATED)) {
        return fmi2Error;
    }
    inst->state = FMU_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2ExitInitializationMode", FMU_INITIALIZATION)) {
        return fmi2Error;
    }
    inst->prepared = 0; /* validate everything once more, whatever was read before */
    if (prepare(inst, "fmi2ExitInitializationMode") != fmi2OK) {
        return fmi2Error;
    }
    char msg[MSG_SIZE];
    msg[0] = '\0';
    if (fmu_model.check_start != NULL && fmu_model.check_start(inst->model, msg, sizeof(msg)) != 0) {
        LOG_ERROR(inst, "fmi2ExitInitializationMode: %s", msg);
        return fmi2Error;
    }
    fmu_model.init_discrete(inst->model, msg, sizeof(msg));
    fmu_invalidate(inst);
    if (msg[0] != '\0') {
        fmu_log(inst, fmi2OK, LOG_EVENTS, "%s", msg);
    }
    inst->cvode_needs_reinit = 1;
    inst->state = inst->type == fmi2ModelExchange ? FMU_EVENT : FMU_STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2Terminate",
                 FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | FMU_STEP_FAILED)) {
        return fmi2Error;
    }
    inst->state = FMU_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2Reset", ~0u)) {
        return fmi2Error;
    }
    cs_free(inst);
    fmu_model.set_defaults(inst->model);
    inst->prepared = 0;
    inst->warned_outputs = 0;
    inst->tolerance = FMU_DEFAULT_TOLERANCE;
    inst->start_time = 0.0;
    inst->stop_time_defined = 0;
    fmu_invalidate(inst);
    inst->state = FMU_INSTANTIATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* get and set */

#define GET_STATES                                                                             \
    (FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | FMU_STEP_FAILED |  \
     FMU_TERMINATED | FMU_ERROR)
#define SET_STATES                                                                             \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE)

static const csfh_variable_t *lookup(fmu_instance_t *inst, const char *function, fmi2ValueReference vr,
                                     csfh_type_t type)
{
    const csfh_variable_t *v = NULL;
    for (int i = 0; i < fmu_model.n_variables; i++) {
        if (fmu_model.variables[i].vr == vr) {
            v = &fmu_model.variables[i];
            break;
        }
    }
    const int type_ok = v != NULL && (v->type == type ||
                                      (type == CSFH_TYPE_INTEGER && v->type == CSFH_TYPE_ENUMERATION));
    if (!type_ok) {
        LOG_ERROR(inst, "%s: unknown value reference %u", function, vr);
        return NULL;
    }
    return v;
}

static double *real_of(fmu_instance_t *inst, const csfh_variable_t *v)
{
    return (double *)((char *)inst->model + v->offset);
}

static int *int_of(fmu_instance_t *inst, const csfh_variable_t *v)
{
    return (int *)((char *)inst->model + v->offset);
}

/* Bring computed values up to date before they are read. */
static fmi2Status refresh(fmu_instance_t *inst, const csfh_variable_t *v, const char *function)
{
    if (v->causality == CSFH_CAUS_CALCULATED_PARAMETER) {
        return prepare(inst, function);
    }
    if (v->storage != CSFH_STORE_COMPUTED) {
        return fmi2OK;
    }
    if (v->offset >= fmu_model.der_offset &&
        v->offset < fmu_model.der_offset + (size_t)fmu_model.n_states * sizeof(double)) {
        return update_derivatives(inst, function);
    }
    return fmu_update_outputs(inst, function);
}

static fmi2Status get_values(fmu_instance_t *inst, const char *function,
                             const fmi2ValueReference vr[], size_t nvr, csfh_type_t type,
                             void *value)
{
    if (!allowed(inst, function, GET_STATES)) {
        return fmi2Error;
    }
    if (nvr > 0 && (!not_null(inst, function, vr, "vr") || !not_null(inst, function, value, "value"))) {
        return fmi2Error;
    }
    fmi2Status status = fmi2OK;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], type);
        if (v == NULL) {
            return fmi2Error;
        }
        const fmi2Status s = refresh(inst, v, function);
        if (s > fmi2Warning) {
            return s;
        }
        status = s > status ? s : status;
        if (type == CSFH_TYPE_REAL) {
            ((fmi2Real *)value)[i] = *real_of(inst, v);
        } else if (type == CSFH_TYPE_BOOLEAN) {
            ((fmi2Boolean *)value)[i] = *int_of(inst, v) ? fmi2True : fmi2False;
        } else {
            ((fmi2Integer *)value)[i] = *int_of(inst, v);
        }
    }
    return status;
}

/* May variable v be set in the instance's current state? */
static int settable(fmu_instance_t *inst, const csfh_variable_t *v, const char *function)
{
    const unsigned int before_init = FMU_INSTANTIATED | FMU_INITIALIZATION;
    const int running_event = inst->state & (FMU_EVENT | FMU_STEP_COMPLETE);
    int ok = 0;
    switch (v->causality) {
    case CSFH_CAUS_INPUT:
        ok = 1;
        break;
    case CSFH_CAUS_PARAMETER:
        ok = (inst->state & before_init) || (v->tunable && running_event);
        break;
    case CSFH_CAUS_OUTPUT:
        ok = v->is_state && (inst->state & before_init); /* start values of the states */
        break;
    default:
        ok = 0;
        break;
    }
    if (!ok) {
        LOG_ERROR(inst, "%s: variable %s cannot be set in state %s", function, v->name,
                  state_name(inst->state));
    }
    return ok;
}

static fmi2Status set_values(fmu_instance_t *inst, const char *function,
                             const fmi2ValueReference vr[], size_t nvr, csfh_type_t type,
                             const void *value)
{
    if (!allowed(inst, function, SET_STATES)) {
        return fmi2Error;
    }
    if (nvr > 0 && (!not_null(inst, function, vr, "vr") || !not_null(inst, function, value, "value"))) {
        return fmi2Error;
    }
    int tunable_changed = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], type);
        if (v == NULL || !settable(inst, v, function)) {
            return fmi2Error;
        }
        double x;
        if (type == CSFH_TYPE_REAL) {
            x = ((const fmi2Real *)value)[i];
        } else if (type == CSFH_TYPE_BOOLEAN) {
            x = ((const fmi2Boolean *)value)[i] ? 1.0 : 0.0;
        } else {
            x = (double)((const fmi2Integer *)value)[i];
        }
        char msg[MSG_SIZE];
        if (csfh_check_value(v, x, msg, sizeof(msg)) != 0) {
            LOG_ERROR(inst, "%s: %s", function, msg);
            return fmi2Error;
        }
        if (v->causality == CSFH_CAUS_PARAMETER && !(inst->state & (FMU_INSTANTIATED | FMU_INITIALIZATION))) {
            /* a tunable parameter while running: apply, re-validate, roll back on failure */
            void *saved = malloc(fmu_model.size);
            if (saved == NULL) {
                LOG_ERROR(inst, "%s: out of memory", function);
                return fmi2Error;
            }
            memcpy(saved, inst->model, fmu_model.size);
            if (type == CSFH_TYPE_REAL) {
                *real_of(inst, v) = x;
            } else {
                *int_of(inst, v) = (int)x;
            }
            const int failed = fmu_model.prepare(inst->model, msg, sizeof(msg)) != 0;
            if (failed) {
                memcpy(inst->model, saved, fmu_model.size);
            }
            free(saved);
            if (failed) {
                LOG_ERROR(inst, "%s: %s", function, msg);
                return fmi2Error;
            }
            tunable_changed = 1;
            continue;
        }
        const double old = type == CSFH_TYPE_REAL ? *real_of(inst, v) : (double)*int_of(inst, v);
        if (type == CSFH_TYPE_REAL) {
            *real_of(inst, v) = x;
        } else {
            *int_of(inst, v) = (int)x;
        }
        if (v->causality == CSFH_CAUS_PARAMETER) {
            inst->prepared = 0;
        }
        /* a new state, or a new input value (inputs are held constant over a communication step,
         * so a change is a discontinuity of the right-hand side): restart the CS integrator */
        if (v->is_state || (v->causality == CSFH_CAUS_INPUT && old != x)) {
            inst->cvode_needs_reinit = 1;
        }
    }
    if (tunable_changed) {
        inst->cvode_needs_reinit = 1;
    }
    fmu_invalidate(inst);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    return get_values((fmu_instance_t *)c, "fmi2GetReal", vr, nvr, CSFH_TYPE_REAL, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    return get_values((fmu_instance_t *)c, "fmi2GetInteger", vr, nvr, CSFH_TYPE_INTEGER, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    return get_values((fmu_instance_t *)c, "fmi2GetBoolean", vr, nvr, CSFH_TYPE_BOOLEAN, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)value;
    if (!allowed(inst, "fmi2GetString", GET_STATES)) {
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
    return set_values((fmu_instance_t *)c, "fmi2SetReal", vr, nvr, CSFH_TYPE_REAL, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    return set_values((fmu_instance_t *)c, "fmi2SetInteger", vr, nvr, CSFH_TYPE_INTEGER, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    return set_values((fmu_instance_t *)c, "fmi2SetBoolean", vr, nvr, CSFH_TYPE_BOOLEAN, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)value;
    if (!allowed(inst, "fmi2SetString", SET_STATES)) {
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
/* FMU state */

#define FMU_STATE_MAGIC 0x48465343u /* "CSFH" */
#define FMU_STATE_VERSION 2u

/* An FMU state: this header, then the model struct (fmu_model.size bytes). */
typedef struct {
    unsigned int magic;
    unsigned int version;
    unsigned int size; /* of the whole snapshot */
    char guid[40];
    fmi2Type type;
    fmu_state_t state;
    int prepared;
    int warned_outputs;
    unsigned char model[];
} fmu_snapshot_t;

static size_t snapshot_size(void)
{
    return sizeof(fmu_snapshot_t) + fmu_model.size;
}

static void snapshot_take(const fmu_instance_t *inst, fmu_snapshot_t *s)
{
    memset(s, 0, snapshot_size());
    s->magic = FMU_STATE_MAGIC;
    s->version = FMU_STATE_VERSION;
    s->size = (unsigned int)snapshot_size();
    strncpy(s->guid, fmu_model.guid, sizeof(s->guid) - 1);
    s->type = inst->type;
    s->state = inst->state;
    s->prepared = inst->prepared;
    s->warned_outputs = inst->warned_outputs;
    memcpy(s->model, inst->model, fmu_model.size);
}

/* Is the header that of a state of this FMU? (Only the header is read.) */
static int snapshot_valid(const fmu_snapshot_t *s)
{
    return s->magic == FMU_STATE_MAGIC && s->version == FMU_STATE_VERSION &&
           s->size == snapshot_size() && strncmp(s->guid, fmu_model.guid, sizeof(s->guid)) == 0;
}

/* A state can only be restored into an instance of the same kind (ME or CS). */
static int snapshot_fits(const fmu_instance_t *inst, const fmu_snapshot_t *s, const char *function)
{
    if (!snapshot_valid(s)) {
        fmu_log((fmu_instance_t *)inst, fmi2Error, LOG_STATUS_ERROR,
                "%s: the given FMUstate was not made by this FMU", function);
        return 0;
    }
    if (s->type != inst->type) {
        fmu_log((fmu_instance_t *)inst, fmi2Error, LOG_STATUS_ERROR,
                "%s: the FMUstate was made by a %s instance, this one is %s", function,
                s->type == fmi2ModelExchange ? "model-exchange" : "co-simulation",
                inst->type == fmi2ModelExchange ? "model-exchange" : "co-simulation");
        return 0;
    }
    return 1;
}

static void snapshot_restore(fmu_instance_t *inst, const fmu_snapshot_t *s)
{
    inst->state = s->state;
    inst->prepared = s->prepared;
    inst->warned_outputs = s->warned_outputs;
    memcpy(inst->model, s->model, fmu_model.size);
    inst->cvode_needs_reinit = 1;
    fmu_invalidate(inst);
}

#define STATE_STATES                                                                           \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE |  \
     FMU_STEP_FAILED | FMU_TERMINATED | FMU_ERROR)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2GetFMUstate", STATE_STATES) ||
        !not_null(inst, "fmi2GetFMUstate", FMUstate, "FMUstate")) {
        return fmi2Error;
    }
    fmu_snapshot_t *s = (fmu_snapshot_t *)*FMUstate;
    if (s == NULL) {
        s = (fmu_snapshot_t *)calloc(1, snapshot_size());
        if (s == NULL) {
            LOG_ERROR(inst, "fmi2GetFMUstate: out of memory");
            return fmi2Error;
        }
    } else if (!snapshot_valid(s)) {
        LOG_ERROR(inst, "fmi2GetFMUstate: the given FMUstate was not made by this FMU");
        return fmi2Error;
    }
    snapshot_take(inst, s);
    /* CVODE's history (step size, order, Nordsieck array) is not part of the snapshot, and
     * fmi2SetFMUstate restarts the integrator at the restored point. Restart it here as well, so
     * that the run continuing from this point and any re-run after restoring this state take the
     * same integrator path (identical results). */
    inst->cvode_needs_reinit = 1;
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SetFMUstate", STATE_STATES) ||
        !not_null(inst, "fmi2SetFMUstate", FMUstate, "FMUstate")) {
        return fmi2Error;
    }
    const fmu_snapshot_t *s = (const fmu_snapshot_t *)FMUstate;
    if (!snapshot_fits(inst, s, "fmi2SetFMUstate")) {
        return fmi2Error;
    }
    snapshot_restore(inst, s);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2FreeFMUstate", STATE_STATES)) {
        return fmi2Error;
    }
    if (FMUstate == NULL || *FMUstate == NULL) {
        return fmi2OK;
    }
    free(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SerializedFMUstateSize", STATE_STATES) ||
        !not_null(inst, "fmi2SerializedFMUstateSize", FMUstate, "FMUstate") ||
        !not_null(inst, "fmi2SerializedFMUstateSize", size, "size")) {
        return fmi2Error;
    }
    *size = snapshot_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SerializeFMUstate", STATE_STATES) ||
        !not_null(inst, "fmi2SerializeFMUstate", FMUstate, "FMUstate") ||
        !not_null(inst, "fmi2SerializeFMUstate", serializedState, "serializedState")) {
        return fmi2Error;
    }
    if (size < snapshot_size()) {
        LOG_ERROR(inst, "fmi2SerializeFMUstate: size = %zu is smaller than %zu", size,
                  snapshot_size());
        return fmi2Error;
    }
    memcpy(serializedState, FMUstate, snapshot_size());
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2DeSerializeFMUstate", STATE_STATES) ||
        !not_null(inst, "fmi2DeSerializeFMUstate", serializedState, "serializedState") ||
        !not_null(inst, "fmi2DeSerializeFMUstate", FMUstate, "FMUstate")) {
        return fmi2Error;
    }
    fmu_snapshot_t header;
    if (size != snapshot_size()) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: size = %zu, expected %zu", size, snapshot_size());
        return fmi2Error;
    }
    memcpy(&header, serializedState, sizeof(header));
    if (!snapshot_valid(&header)) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: the bytes are not a state of this FMU");
        return fmi2Error;
    }
    fmu_snapshot_t *s = (fmu_snapshot_t *)calloc(1, snapshot_size());
    if (s == NULL) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    memcpy(s, serializedState, snapshot_size());
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (inst != NULL) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: not provided "
                        "(providesDirectionalDerivative = false)");
    }
    return fmi2Error;
}

/* ------------------------------------------------------------------------------------------ */
/* model exchange */

static int is_me(fmu_instance_t *inst, const char *function)
{
    if (inst->type != fmi2ModelExchange) {
        LOG_ERROR(inst, "%s: only for model exchange", function);
        return 0;
    }
    return 1;
}

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2EnterEventMode", FMU_EVENT | FMU_CONTINUOUS) ||
        !is_me(inst, "fmi2EnterEventMode")) {
        return fmi2Error;
    }
    inst->state = FMU_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2NewDiscreteStates", FMU_EVENT) ||
        !is_me(inst, "fmi2NewDiscreteStates") ||
        !not_null(inst, "fmi2NewDiscreteStates", eventInfo, "eventInfo")) {
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
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2EnterContinuousTimeMode", FMU_EVENT) ||
        !is_me(inst, "fmi2EnterContinuousTimeMode")) {
        return fmi2Error;
    }
    inst->state = FMU_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(inst, "fmi2CompletedIntegratorStep", FMU_CONTINUOUS) ||
        !is_me(inst, "fmi2CompletedIntegratorStep") ||
        !not_null(inst, "fmi2CompletedIntegratorStep", enterEventMode, "enterEventMode") ||
        !not_null(inst, "fmi2CompletedIntegratorStep", terminateSimulation, "terminateSimulation")) {
        return fmi2Error;
    }
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SetTime", FMU_EVENT | FMU_CONTINUOUS) || !is_me(inst, "fmi2SetTime")) {
        return fmi2Error;
    }
    if (!isfinite(time)) {
        LOG_ERROR(inst, "fmi2SetTime: time = %g is not finite", time);
        return fmi2Error;
    }
    *fmu_time(inst) = time;
    fmu_invalidate(inst);
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SetContinuousStates", FMU_CONTINUOUS) ||
        !is_me(inst, "fmi2SetContinuousStates") ||
        !not_null(inst, "fmi2SetContinuousStates", x, "x")) {
        return fmi2Error;
    }
    if (nx != (size_t)fmu_model.n_states) {
        LOG_ERROR(inst, "fmi2SetContinuousStates: nx = %zu, expected %d", nx, fmu_model.n_states);
        return fmi2Error;
    }
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            LOG_ERROR(inst, "fmi2SetContinuousStates: x[%zu] = %g is not finite (t = %.17g)", i,
                      x[i], *fmu_time(inst));
            return fmi2Error;
        }
    }
    if (nx > 0) {
        memcpy(fmu_states(inst), x, nx * sizeof(double));
    }
    fmu_invalidate(inst);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2GetDerivatives", GET_STATES) || !is_me(inst, "fmi2GetDerivatives") ||
        !not_null(inst, "fmi2GetDerivatives", derivatives, "derivatives")) {
        return fmi2Error;
    }
    if (nx != (size_t)fmu_model.n_states) {
        LOG_ERROR(inst, "fmi2GetDerivatives: nx = %zu, expected %d", nx, fmu_model.n_states);
        return fmi2Error;
    }
    const fmi2Status status = update_derivatives(inst, "fmi2GetDerivatives");
    if (status > fmi2Warning) {
        return status;
    }
    if (nx > 0) {
        memcpy(derivatives, fmu_derivatives(inst), nx * sizeof(double));
    }
    return status;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2GetEventIndicators", GET_STATES) ||
        !is_me(inst, "fmi2GetEventIndicators") ||
        !not_null(inst, "fmi2GetEventIndicators", eventIndicators, "eventIndicators")) {
        return fmi2Error;
    }
    if (ni != (size_t)fmu_model.n_event_indicators) {
        LOG_ERROR(inst, "fmi2GetEventIndicators: ni = %zu, expected %d", ni,
                  fmu_model.n_event_indicators);
        return fmi2Error;
    }
    if (prepare(inst, "fmi2GetEventIndicators") != fmi2OK) {
        return fmi2Error;
    }
    if (ni > 0) {
        fmu_model.event_indicators(inst->model, fmu_states(inst), eventIndicators);
    }
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2GetContinuousStates", GET_STATES) ||
        !is_me(inst, "fmi2GetContinuousStates") ||
        !not_null(inst, "fmi2GetContinuousStates", x, "x")) {
        return fmi2Error;
    }
    if (nx != (size_t)fmu_model.n_states) {
        LOG_ERROR(inst, "fmi2GetContinuousStates: nx = %zu, expected %d", nx, fmu_model.n_states);
        return fmi2Error;
    }
    if (nx > 0) {
        memcpy(x, fmu_states(inst), nx * sizeof(double));
    }
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2GetNominalsOfContinuousStates", STATE_STATES) ||
        !is_me(inst, "fmi2GetNominalsOfContinuousStates") ||
        !not_null(inst, "fmi2GetNominalsOfContinuousStates", x_nominal, "x_nominal")) {
        return fmi2Error;
    }
    if (nx != (size_t)fmu_model.n_states) {
        LOG_ERROR(inst, "fmi2GetNominalsOfContinuousStates: nx = %zu, expected %d", nx,
                  fmu_model.n_states);
        return fmi2Error;
    }
    size_t k = 0;
    for (int i = 0; i < fmu_model.n_variables && k < nx; i++) {
        if (fmu_model.variables[i].is_state) {
            x_nominal[k++] = fmu_model.variables[i].nominal;
        }
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation entry points (the stepper is in cosimulation.c) */

static int is_cs(fmu_instance_t *inst, const char *function)
{
    if (inst->type != fmi2CoSimulation) {
        LOG_ERROR(inst, "%s: only for co-simulation", function);
        return 0;
    }
    return 1;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (inst != NULL) {
        LOG_ERROR(inst, "fmi2SetRealInputDerivatives: not supported (canInterpolateInputs = "
                        "false; inputs are held over the step)");
    }
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (inst != NULL) {
        LOG_ERROR(inst, "fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder = 0)");
    }
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(inst, "fmi2DoStep", FMU_STEP_COMPLETE) || !is_cs(inst, "fmi2DoStep")) {
        return fmi2Error;
    }
    if (!isfinite(currentCommunicationPoint) || !isfinite(communicationStepSize) ||
        communicationStepSize < 0.0) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint = %g, communicationStepSize = %g "
                        "must be finite and the step >= 0",
                  currentCommunicationPoint, communicationStepSize);
        return fmi2Error;
    }
    const fmi2Status status = cs_do_step(inst, currentCommunicationPoint, communicationStepSize);
    if (status > fmi2Warning) {
        inst->state = FMU_STEP_FAILED;
    }
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst != NULL) {
        LOG_ERROR(inst, "fmi2CancelStep: not supported (canRunAsynchronuously = false)");
    }
    return fmi2Error;
}

static fmi2Status get_status(fmi2Component c, const char *function)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst == NULL) {
        return fmi2Error; /* like every other function: no instance is an error, not a discard */
    }
    LOG_ERROR(inst, "%s: no asynchronous step to report on", function);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    return get_status(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst != NULL && value != NULL && s == fmi2LastSuccessfulTime) {
        *value = *fmu_time(inst);
        return fmi2OK;
    }
    return get_status(c, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return get_status(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (inst != NULL && value != NULL && s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return get_status(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return get_status(c, "fmi2GetStringStatus");
}
