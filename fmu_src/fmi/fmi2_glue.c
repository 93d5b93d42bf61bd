/* FMI 2.0 glue: instance life cycle, state machine, get/set through the generated variable table,
 * model-exchange functions and FMU state handling. Model-independent: the model is behind the
 * interface of fmu_model.h (csfh: csfh_fmu_model.c, physics in ../core; the comb-drive actuator:
 * ../combdrive/). */
#include <float.h>
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

static void states_free_all(fmu_instance_t *inst); /* FMU state section */

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

/* The relative resolution of a time step below which precision lost to the double time is
 * reported (fmi2DoStep, fmi2CompletedIntegratorStep): the integration tolerance, but not finer
 * than TIME_RESOLUTION_FLOOR (one part in a million: a step of 1e-7 s at t = 5 s is resolved to
 * 1e-8 relative, which no result here notices, and a warning there would be noise). */
#define TIME_RESOLUTION_FLOOR 1e-6

static double time_resolution_needed(const fmu_instance_t *inst)
{
    return inst->tolerance > TIME_RESOLUTION_FLOOR ? inst->tolerance : TIME_RESOLUTION_FLOOR;
}

/* Model exchange: the time and states the next completed integrator step is compared with
 * (check_me_time_resolution): set at the end of initialization, at every completed step and
 * when an FMU state is restored. */
static void step_reference(fmu_instance_t *inst)
{
    inst->last_step_time = *fmu_time(inst);
    if (fmu_model.n_states > 0) {
        memcpy(inst->last_step_x, fmu_states(inst), (size_t)fmu_model.n_states * sizeof(double));
    }
    inst->last_step_valid = 1;
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

/* The continuous states as text, for messages. */
static const char *state_text(fmu_instance_t *inst, char *text, size_t size)
{
    const double *x = fmu_states(inst);
    size_t k = 0;
    text[0] = '\0';
    for (int i = 0; i < fmu_model.n_states && k + 1 < size; i++) {
        k += (size_t)snprintf(text + k, size - k, "%s%g", i ? ", " : "", x[i]);
    }
    return text;
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
    const int status =
        fmu_model.derivatives(inst->model, *fmu_time(inst), x, fmu_derivatives(inst));
    if (status == FMU_MODEL_NONFINITE) {
        char text[MSG_SIZE];
        LOG_ERROR(inst, "%s: non-finite derivative at t = %.17g, state [%s]", function,
                  *fmu_time(inst), state_text(inst, text, sizeof(text)));
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
    cs_peaks_flush(inst); /* the peak outputs of the communication step */
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
    /* the message is formatted only when it will be logged (an event costs far less than its
     * 17-digit message) */
    const int logged = inst->logger != NULL && (inst->log_categories & LOG_EVENTS) != 0;
    char msg[MSG_SIZE];
    msg[0] = '\0';
    const int change = fmu_model.event_update(inst->model, msg, logged ? sizeof(msg) : 0);
    if (logged && msg[0] != '\0') {
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
    inst->last_step_x = (double *)calloc((size_t)fmu_model.n_states + 1, sizeof(double));
    unsigned int max_vr = 0;
    for (int i = 0; i < fmu_model.n_variables; i++) {
        max_vr = fmu_model.variables[i].vr > max_vr ? fmu_model.variables[i].vr : max_vr;
    }
    inst->n_vr_index = max_vr + 1;
    inst->vr_index = (int *)malloc((size_t)inst->n_vr_index * sizeof(int));
    if (inst->instance_name == NULL || inst->model == NULL || inst->last_step_x == NULL ||
        inst->vr_index == NULL) {
        free(inst->instance_name);
        free(inst->model);
        free(inst->last_step_x);
        free(inst->vr_index);
        free(inst);
        return NULL;
    }
    for (unsigned int r = 0; r < inst->n_vr_index; r++) {
        inst->vr_index[r] = -1;
    }
    for (int i = fmu_model.n_variables - 1; i >= 0; i--) { /* the first of equal references */
        inst->vr_index[fmu_model.variables[i].vr] = i;
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
    states_free_all(inst); /* FMU states the importer did not free */
    free(inst->last_step_x);
    free(inst->vr_index);
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
    /* a refused call changes nothing: the derived quantities that prepare() computes are put
     * back if the start state is then refused */
    void *saved = malloc(fmu_model.size);
    if (saved == NULL) {
        LOG_ERROR(inst, "fmi2ExitInitializationMode: out of memory");
        return fmi2Error;
    }
    memcpy(saved, inst->model, fmu_model.size);
    const int was_prepared = inst->prepared;
    inst->prepared = 0; /* validate everything once more, whatever was read before */
    char msg[MSG_SIZE];
    msg[0] = '\0';
    int refused = prepare(inst, "fmi2ExitInitializationMode") != fmi2OK;
    if (!refused && fmu_model.check_start != NULL &&
        fmu_model.check_start(inst->model, msg, sizeof(msg)) != 0) {
        LOG_ERROR(inst, "fmi2ExitInitializationMode: %s", msg);
        refused = 1;
    }
    if (refused) {
        memcpy(inst->model, saved, fmu_model.size);
        inst->prepared = was_prepared;
    }
    free(saved);
    if (refused) {
        return fmi2Error;
    }
    fmu_model.init_discrete(inst->model, msg, sizeof(msg));
    fmu_invalidate(inst);
    if (msg[0] != '\0') {
        fmu_log(inst, fmi2OK, LOG_EVENTS, "%s", msg);
    }
    inst->cvode_needs_reinit = 1;
    step_reference(inst);
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
    inst->warned_time = 0;
    inst->last_step_valid = 0;
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
    if (vr < inst->n_vr_index && inst->vr_index[vr] >= 0) {
        v = &fmu_model.variables[inst->vr_index[vr]];
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

/* The i-th value of a set call as a double. */
static double set_value_at(csfh_type_t type, const void *value, size_t i)
{
    if (type == CSFH_TYPE_REAL) {
        return ((const fmi2Real *)value)[i];
    }
    if (type == CSFH_TYPE_BOOLEAN) {
        return ((const fmi2Boolean *)value)[i] ? 1.0 : 0.0;
    }
    return (double)((const fmi2Integer *)value)[i];
}

/* All or nothing: every value is checked before any is applied, and tunable parameters set while
 * running are validated together (the model's cross-checks) and rolled back together, so a
 * rejected call leaves the instance exactly as it was. */
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
    char msg[MSG_SIZE];
    int tunable = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], type);
        if (v == NULL || !settable(inst, v, function)) {
            return fmi2Error;
        }
        if (csfh_check_value(v, set_value_at(type, value, i), msg, sizeof(msg)) != 0) {
            LOG_ERROR(inst, "%s: %s", function, msg);
            return fmi2Error;
        }
        tunable = tunable || (v->causality == CSFH_CAUS_PARAMETER &&
                              !(inst->state & (FMU_INSTANTIATED | FMU_INITIALIZATION)));
    }
    /* every value is valid: first the peaks of the communication step, with the values they
     * were taken with (a parameter changes them; kept if the new ones are rolled back) */
    cs_peaks_flush(inst);
    void *saved = NULL;
    if (tunable) { /* tunable parameters while running: apply, re-validate, roll back on failure */
        saved = malloc(fmu_model.size);
        if (saved == NULL) {
            LOG_ERROR(inst, "%s: out of memory", function);
            return fmi2Error;
        }
        memcpy(saved, inst->model, fmu_model.size);
    }
    int restart = tunable, parameter = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], type);
        const double x = set_value_at(type, value, i);
        const double old = type == CSFH_TYPE_REAL ? *real_of(inst, v) : (double)*int_of(inst, v);
        if (type == CSFH_TYPE_REAL) {
            *real_of(inst, v) = x;
        } else {
            *int_of(inst, v) = (int)x;
        }
        parameter = parameter || v->causality == CSFH_CAUS_PARAMETER;
        /* a new state, or a new input value (inputs are held constant over a communication step,
         * so a change is a discontinuity of the right-hand side): restart the CS integrator */
        restart = restart || v->is_state || (v->causality == CSFH_CAUS_INPUT && old != x);
    }
    if (tunable) {
        const int failed = fmu_model.prepare(inst->model, msg, sizeof(msg)) != 0;
        if (failed) {
            memcpy(inst->model, saved, fmu_model.size);
        }
        free(saved);
        if (failed) {
            LOG_ERROR(inst, "%s: %s", function, msg);
            return fmi2Error;
        }
    } else if (parameter) {
        inst->prepared = 0;
    }
    if (restart) {
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
#define FMU_STATE_VERSION 3u

/* An FMU state: this header, then the model struct (fmu_model.size bytes). The header holds no
 * enum types: its bytes may come from anywhere (fmi2DeSerializeFMUstate), and every field is
 * checked before it is used. */
typedef struct {
    unsigned int magic;
    unsigned int version;
    unsigned int size; /* of the whole snapshot */
    char guid[40];
    int type;           /* fmi2Type */
    unsigned int state; /* fmu_state_t */
    int prepared;       /* not trusted: the parameters are validated again on restore */
    int warned_outputs;
    unsigned char model[];
} fmu_snapshot_t;

/* The instance states a restored FMU state may put an instance of each type into: those this
 * FMU can be in while the importer may call fmi2GetFMUstate (FMU_ERROR is never entered). */
#define ME_RESTORABLE (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_TERMINATED)
#define CS_RESTORABLE                                                                          \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_STEP_COMPLETE | FMU_STEP_FAILED | FMU_TERMINATED)

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
    s->type = (int)inst->type;
    s->state = (unsigned int)inst->state;
    s->prepared = inst->prepared;
    s->warned_outputs = inst->warned_outputs;
    memcpy(s->model, inst->model, fmu_model.size);
}

/* FMU states of this instance: fmi2GetFMUstate and fmi2DeSerializeFMUstate register what they
 * allocate, fmi2FreeFMUstate forgets it, fmi2FreeInstance frees what is left. Any other pointer
 * is refused before a byte of it is read. */
static long state_index(const fmu_instance_t *inst, const void *s)
{
    for (size_t i = 0; i < inst->n_fmu_states; i++) {
        if (inst->fmu_states[i] == s) {
            return (long)i;
        }
    }
    return -1;
}

static int state_register(fmu_instance_t *inst, void *s)
{
    if (inst->n_fmu_states == inst->cap_fmu_states) {
        const size_t cap = inst->cap_fmu_states > 0 ? 2 * inst->cap_fmu_states : 8;
        void **grown = (void **)realloc(inst->fmu_states, cap * sizeof(void *));
        if (grown == NULL) {
            return -1;
        }
        inst->fmu_states = grown;
        inst->cap_fmu_states = cap;
    }
    inst->fmu_states[inst->n_fmu_states++] = s;
    return 0;
}

static void states_free_all(fmu_instance_t *inst)
{
    for (size_t i = 0; i < inst->n_fmu_states; i++) {
        free(inst->fmu_states[i]);
    }
    free(inst->fmu_states);
    inst->fmu_states = NULL;
    inst->n_fmu_states = inst->cap_fmu_states = 0;
}

/* Is FMUstate one of this instance's states? Logs an error if not. */
static int state_owned(fmu_instance_t *inst, const void *FMUstate, const char *function)
{
    if (state_index(inst, FMUstate) < 0) {
        LOG_ERROR(inst, "%s: the FMUstate was not made by this instance (fmi2GetFMUstate or "
                        "fmi2DeSerializeFMUstate), or was freed; states move between instances "
                        "as serialized bytes",
                  function);
        return 0;
    }
    return 1;
}

/* Check a snapshot as if its content were set with fmi2Set* (the same table checks and model
 * checks; the instance is not touched):
 *   header      magic, version, size, GUID; made by an instance of the same type (ME or CS);
 *               its instance state one that this type can be in (ME_RESTORABLE/CS_RESTORABLE);
 *   variables   every stored (not computed) variable of the table, i.e. time, states, inputs,
 *               parameters, discrete states, counters: finite and in its range (enumerations,
 *               Booleans 0/1, declared min/max), as fmi2Set* checks parameters;
 *   model       the model's own checks of what is not a table variable (fmu_model.check_state);
 *   prepare     after initialization, the model's cross-checks (e.g. R1 < R2), with the derived
 *               quantities recomputed, never taken from the bytes; before it, they are
 *               recomputed at the first use as for any parameter set then.
 * The checked model is left in `model` (fmu_model.size bytes) and *prepared says whether its
 * derived quantities are valid. Returns 0, or -1 after logging an error naming the variable and
 * its value. */
static int snapshot_check(fmu_instance_t *inst, const fmu_snapshot_t *s, void *model,
                          int *prepared, const char *function)
{
    if (s->magic != FMU_STATE_MAGIC || s->version != FMU_STATE_VERSION ||
        s->size != snapshot_size() || strncmp(s->guid, fmu_model.guid, sizeof(s->guid)) != 0) {
        LOG_ERROR(inst, "%s: the bytes are not a state of this FMU (header: magic, version, size "
                        "or GUID)", function);
        return -1;
    }
    if (s->type != (int)fmi2ModelExchange && s->type != (int)fmi2CoSimulation) {
        LOG_ERROR(inst, "%s: the FMUstate's instance type %d is neither model exchange nor "
                        "co-simulation", function, s->type);
        return -1;
    }
    if (s->type != (int)inst->type) {
        LOG_ERROR(inst, "%s: the FMUstate was made by a %s instance, this one is %s", function,
                  s->type == (int)fmi2ModelExchange ? "model-exchange" : "co-simulation",
                  inst->type == fmi2ModelExchange ? "model-exchange" : "co-simulation");
        return -1;
    }
    const unsigned int restorable = inst->type == fmi2ModelExchange ? ME_RESTORABLE : CS_RESTORABLE;
    const unsigned int st = s->state;
    if (st == 0 || (st & (st - 1)) != 0 || (st & restorable) == 0) { /* exactly one valid bit */
        LOG_ERROR(inst, "%s: the FMUstate's instance state %u is not a state a %s instance can "
                        "be restored to", function, st,
                  inst->type == fmi2ModelExchange ? "model-exchange" : "co-simulation");
        return -1;
    }
    if (s->warned_outputs != 0 && s->warned_outputs != 1) {
        LOG_ERROR(inst, "%s: the FMUstate's output-warning flag %d is not 0 or 1", function,
                  s->warned_outputs);
        return -1;
    }
    memcpy(model, s->model, fmu_model.size);
    char msg[MSG_SIZE];
    for (int i = 0; i < fmu_model.n_variables; i++) {
        const csfh_variable_t *v = &fmu_model.variables[i];
        if (v->storage != CSFH_STORE_PLAIN || v->causality == CSFH_CAUS_CALCULATED_PARAMETER) {
            continue; /* recomputed before it is read */
        }
        const void *at = (const char *)model + v->offset;
        const double value = v->type == CSFH_TYPE_REAL ? *(const double *)at : (double)*(const int *)at;
        if (csfh_check_value(v, value, msg, sizeof(msg)) != 0) {
            LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
            return -1;
        }
    }
    if (fmu_model.check_state != NULL && fmu_model.check_state(model, msg, sizeof(msg)) != 0) {
        LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
        return -1;
    }
    *prepared = fmu_model.prepare(model, msg, sizeof(msg)) == 0;
    if (!*prepared && !(st & (FMU_INSTANTIATED | FMU_INITIALIZATION))) {
        LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
        return -1;
    }
    return 0;
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
        if (s == NULL || state_register(inst, s) != 0) {
            free(s);
            LOG_ERROR(inst, "fmi2GetFMUstate: out of memory");
            return fmi2Error;
        }
    } else if (!state_owned(inst, s, "fmi2GetFMUstate")) {
        return fmi2Error;
    }
    cs_peaks_flush(inst); /* the snapshot holds the peaks of the communication step */
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
        !not_null(inst, "fmi2SetFMUstate", FMUstate, "FMUstate") ||
        !state_owned(inst, FMUstate, "fmi2SetFMUstate")) {
        return fmi2Error;
    }
    const fmu_snapshot_t *s = (const fmu_snapshot_t *)FMUstate;
    void *model = malloc(fmu_model.size);
    if (model == NULL) {
        LOG_ERROR(inst, "fmi2SetFMUstate: out of memory");
        return fmi2Error;
    }
    int prepared = 0;
    if (snapshot_check(inst, s, model, &prepared, "fmi2SetFMUstate") != 0) {
        free(model); /* the instance is unchanged */
        return fmi2Error;
    }
    free(inst->model);
    inst->model = model;
    inst->state = (fmu_state_t)s->state;
    inst->prepared = prepared;
    inst->warned_outputs = s->warned_outputs;
    step_reference(inst);
    inst->cvode_needs_reinit = 1;
    fmu_invalidate(inst);
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
    const long i = state_index(inst, *FMUstate);
    if (i < 0) {
        state_owned(inst, *FMUstate, "fmi2FreeFMUstate"); /* logs */
        return fmi2Error;
    }
    free(*FMUstate);
    inst->fmu_states[i] = inst->fmu_states[--inst->n_fmu_states];
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2SerializedFMUstateSize", STATE_STATES) ||
        !not_null(inst, "fmi2SerializedFMUstateSize", FMUstate, "FMUstate") ||
        !not_null(inst, "fmi2SerializedFMUstateSize", size, "size") ||
        !state_owned(inst, FMUstate, "fmi2SerializedFMUstateSize")) {
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
        !not_null(inst, "fmi2SerializeFMUstate", serializedState, "serializedState") ||
        !state_owned(inst, FMUstate, "fmi2SerializeFMUstate")) {
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

/* The bytes get the same checks as fmi2SetFMUstate gives them (snapshot_check): a state that
 * could not be restored into this instance is refused here already. */
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    if (!allowed(inst, "fmi2DeSerializeFMUstate", STATE_STATES) ||
        !not_null(inst, "fmi2DeSerializeFMUstate", serializedState, "serializedState") ||
        !not_null(inst, "fmi2DeSerializeFMUstate", FMUstate, "FMUstate")) {
        return fmi2Error;
    }
    if (size != snapshot_size()) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: size = %zu, expected %zu", size, snapshot_size());
        return fmi2Error;
    }
    fmu_snapshot_t *s = (fmu_snapshot_t *)calloc(1, snapshot_size());
    void *model = malloc(fmu_model.size);
    if (s == NULL || model == NULL) {
        free(s);
        free(model);
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    memcpy(s, serializedState, snapshot_size()); /* aligned from here on */
    int prepared = 0;
    const int bad = snapshot_check(inst, s, model, &prepared, "fmi2DeSerializeFMUstate") != 0;
    free(model);
    if (bad || state_register(inst, s) != 0) {
        if (!bad) {
            LOG_ERROR(inst, "fmi2DeSerializeFMUstate: out of memory");
        }
        free(s);
        return fmi2Error;
    }
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
    /* time events (csfh: the ends of the shock pulse): the next one after the current time */
    const double next = fmu_model.next_time_event != NULL
                            ? fmu_model.next_time_event(inst->model, *fmu_time(inst))
                            : INFINITY;
    eventInfo->nextEventTimeDefined = isfinite(next) ? fmi2True : fmi2False;
    eventInfo->nextEventTime = isfinite(next) ? next : 0.0;
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

/* Model exchange and large times: the importer integrates in its own time, and the model is
 * autonomous (the time only stamps the recorded onset and release times), so the FMU's
 * derivatives, event indicators and outputs do not depend on the start time at all; what the
 * FMU can promise is to report what it sees of the importer's time losing precision. At every
 * completed integrator step it compares the time with the previous completed step's: if the
 * states moved but the double time represents the increment dt worse than the tolerance
 * (ulp(t) > max(tolerance, 1e-6) * dt, including dt = 0: steps below the resolution of t), it
 * returns fmi2Warning (logged once per instance). A time that went backwards (the importer
 * rolled its integrator back) is not judged. */
static fmi2Status check_me_time_resolution(fmu_instance_t *inst)
{
    const double t = *fmu_time(inst);
    const double *x = fmu_states(inst);
    const size_t bytes = (size_t)fmu_model.n_states * sizeof(double);
    fmi2Status status = fmi2OK;
    if (inst->last_step_valid && bytes > 0) {
        const double dt = t - inst->last_step_time;
        const double ulp = nextafter(fabs(t), INFINITY) - fabs(t);
        const int moved = memcmp(x, inst->last_step_x, bytes) != 0;
        if (moved && dt >= 0.0 && ulp > time_resolution_needed(inst) * dt) {
            status = fmi2Warning;
            if (!inst->warned_time) {
                inst->warned_time = 1;
                fmu_log(inst, fmi2Warning, LOG_STATUS_WARNING,
                        "fmi2CompletedIntegratorStep: the time t = %.17g resolves steps to %g s "
                        "only; the integrator step from t = %.17g (dt = %g s) is represented to "
                        "worse than %g relative: integrate in a time measured from a nearer "
                        "origin (further such steps return fmi2Warning without a message)",
                        t, ulp, inst->last_step_time, dt, time_resolution_needed(inst));
            }
        }
    }
    step_reference(inst);
    return status;
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
    return check_me_time_resolution(inst);
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
    for (size_t i = 0; i < ni; i++) {
        if (!isfinite(eventIndicators[i])) {
            char text[MSG_SIZE];
            LOG_ERROR(inst, "fmi2GetEventIndicators: non-finite event indicator z[%zu] = %g at "
                            "t = %.17g, state [%s]",
                      i, eventIndicators[i], *fmu_time(inst), state_text(inst, text, sizeof(text)));
            return fmi2Error;
        }
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

/* Round-off allowed in a master's time arithmetic (fmi2DoStep): a currentCommunicationPoint t
 * is the FMU's time T if |t - T| <= COMM_POINT_ROUNDOFF * max(|t|, |T|), i.e. a few units in the
 * last place (4 to 8 ulp): what t0 + k h against t_(k-1) + h, or integer nanoseconds converted to
 * seconds, give. */
#define COMM_POINT_ROUNDOFF (16.0 * DBL_EPSILON)

/* The step's arguments against the FMU's time T: the communication point t must be T up to
 * round-off (COMM_POINT_ROUNDOFF; a t behind T would take the time backwards, one ahead would
 * skip an interval), the step h finite and >= 0, and the end t + h (computed as the master
 * computes it) finite and, for h > 0, later than T. The FMU integrates from its own time T to
 * t + h, so its time never goes backwards. A refused step is fmi2Error and changes nothing.
 * Precision lost: if the double time represents the step T -> t + h worse than the integration
 * tolerance (|(t + h - T) - h| > max(tolerance, 1e-6) h, e.g. h = 1e-3 s at t = 1e10 s, where
 * the resolution is 1.9e-6 s), the step is taken and reported with fmi2Warning (logged once). */
static fmi2Status check_step(fmu_instance_t *inst, double t, double h, double *t_end)
{
    const double T = *fmu_time(inst);
    if (!isfinite(t) || !isfinite(h) || h < 0.0) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint = %g, communicationStepSize = %g "
                        "must be finite and the step >= 0",
                  t, h);
        return fmi2Error;
    }
    if (fabs(t - T) > COMM_POINT_ROUNDOFF * fmax(fabs(t), fabs(T))) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint = %.17g does not match the FMU time "
                        "%.17g (%s by %.3g s; allowed: round-off, %.3g s)",
                  t, T, t < T ? "behind" : "ahead", fabs(t - T),
                  COMM_POINT_ROUNDOFF * fmax(fabs(t), fabs(T)));
        return fmi2Error;
    }
    *t_end = t + h;
    if (h == 0.0) {
        return fmi2OK;
    }
    if (!isfinite(*t_end)) {
        LOG_ERROR(inst, "fmi2DoStep: currentCommunicationPoint + communicationStepSize = %.17g + "
                        "%g is not finite", t, h);
        return fmi2Error;
    }
    if (!(*t_end > T)) {
        LOG_ERROR(inst, "fmi2DoStep: communicationStepSize = %g at t = %.17g is below the "
                        "resolution of the time (%g s): t + h = %.17g does not advance the FMU "
                        "time %.17g",
                  h, t, nextafter(fabs(T), INFINITY) - fabs(T), *t_end, T);
        return fmi2Error;
    }
    const double taken = *t_end - T;
    if (fabs(taken - h) > time_resolution_needed(inst) * h) {
        if (!inst->warned_time) {
            inst->warned_time = 1;
            fmu_log(inst, fmi2Warning, LOG_STATUS_WARNING,
                    "fmi2DoStep: the time t = %.17g resolves steps to %g s only: "
                    "communicationStepSize = %.17g is taken as %.17g (relative difference %.3g > "
                    "%g); the FMU integrates exactly that step, but the communication points are "
                    "not where the master meant them (further such steps return fmi2Warning "
                    "without a message)",
                    T, nextafter(fabs(*t_end), INFINITY) - fabs(*t_end), h, taken,
                    fabs(taken - h) / h, time_resolution_needed(inst));
        }
        return fmi2Warning;
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    fmu_instance_t *inst = (fmu_instance_t *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(inst, "fmi2DoStep", FMU_STEP_COMPLETE) || !is_cs(inst, "fmi2DoStep")) {
        return fmi2Error;
    }
    double t_end = 0.0;
    const fmi2Status checked = check_step(inst, currentCommunicationPoint, communicationStepSize,
                                          &t_end);
    if (checked > fmi2Warning) {
        return checked; /* refused: the instance is unchanged and still usable */
    }
    if (communicationStepSize == 0.0) {
        return fmi2OK;
    }
    const fmi2Status status = cs_do_step(inst, t_end);
    if (status > fmi2Warning) {
        inst->state = FMU_STEP_FAILED;
        return status;
    }
    return status > checked ? status : checked;
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
