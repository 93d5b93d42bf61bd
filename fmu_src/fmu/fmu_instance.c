/* The FMI-independent part of an FMU instance (fmu_instance.h): shared by the FMI 2.0 and FMI 3.0
 * front-ends (fmi2_glue.c, fmi3_glue.c) and the co-simulation stepper (cosimulation.c).
 * Model-independent: the model is behind the interface of fmu_model.h (csfh: ../models/csfh/,
 * physics in ../physics/; the comb-drive actuator: ../models/combdrive/). Messages name the FMI
 * function the importer called (`function`, given by the front-end). */
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_instance.h"

/* the co-simulation stepper's hooks (fmu_stepper_t), where the front-end gave them */
static void stepper_free(fmu_instance_t *inst)
{
    if (inst->stepper != NULL) {
        inst->stepper->free(inst);
    }
}

static void stepper_flush(fmu_instance_t *inst)
{
    if (inst->stepper != NULL) {
        inst->stepper->flush(inst);
    }
}

#define MSG_SIZE 512

/* ------------------------------------------------------------------------------------------ */
/* logging */

const char *fmu_category_name(unsigned int category)
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

void fmu_log(const fmu_instance_t *inst, fmu_status_t status, unsigned int category,
             const char *fmt, ...)
{
    if (inst == NULL || inst->log_message == NULL || !(inst->log_categories & category)) {
        return;
    }
    char msg[MSG_SIZE];
    va_list args;
    va_start(args, fmt);
    vsnprintf(msg, sizeof(msg), fmt, args);
    va_end(args);
    inst->log_message(inst, status, fmu_category_name(category), msg);
}

static void states_free_all(fmu_instance_t *inst); /* FMU state section */
static void step_reference(fmu_instance_t *inst);  /* model helpers */

const char *fmu_state_name(fmu_state_t s)
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

int fmu_allowed(fmu_instance_t *inst, const char *function, unsigned int states)
{
    if (inst == NULL) {
        return 0;
    }
    if (!(inst->state & states)) {
        const char *name = fmu_state_name(inst->state);
        if (inst->fmi_version == 3 && inst->state == FMU_STEP_COMPLETE) {
            name = "StepMode";
        }
        FMU_LOG_ERROR(inst, "%s: illegal call in state %s", function, name);
        return 0;
    }
    if (inst->log_categories & LOG_ALL) { /* (fmu_log is cold: not called on every call) */
        fmu_log(inst, FMU_OK, LOG_ALL, "%s", function);
    }
    return 1;
}

int fmu_not_null(fmu_instance_t *inst, const char *function, const void *p, const char *arg)
{
    if (p == NULL) {
        FMU_LOG_ERROR(inst, "%s: argument %s is NULL", function, arg);
        return 0;
    }
    return 1;
}

int fmu_is_me(fmu_instance_t *inst, const char *function)
{
    if (inst->type != FMU_ME) {
        FMU_LOG_ERROR(inst, "%s: only for model exchange", function);
        return 0;
    }
    return 1;
}

int fmu_is_cs(fmu_instance_t *inst, const char *function)
{
    if (inst->type != FMU_CS) {
        FMU_LOG_ERROR(inst, "%s: only for co-simulation", function);
        return 0;
    }
    return 1;
}

fmu_status_t fmu_set_debug_logging(fmu_instance_t *inst, const char *function, int on, size_t n,
                                   const char *const categories[])
{
    if (inst == NULL) {
        return FMU_ERROR;
    }
    if (n > 0 && !fmu_not_null(inst, function, categories, "categories")) {
        return FMU_ERROR;
    }
    const unsigned int always = LOG_STATUS_ERROR | LOG_STATUS_WARNING;
    if (n == 0) {
        inst->log_categories = on ? (LOG_EVENTS | LOG_ALL | always) : always;
        return FMU_OK;
    }
    for (size_t i = 0; i < n; i++) {
        unsigned int bit = 0;
        if (categories[i] == NULL) {
            FMU_LOG_ERROR(inst, "%s: categories[%zu] is NULL", function, i);
            return FMU_ERROR;
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
            FMU_LOG_ERROR(inst, "%s: unknown log category \"%s\"", function, categories[i]);
            return FMU_ERROR;
        }
        if (on) {
            inst->log_categories |= bit;
        } else {
            inst->log_categories &= ~bit;
        }
    }
    return FMU_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* life cycle */

/* What must be up to date before variable v is read (fmu_get_values). */
static unsigned char refresh_kind(const csfh_variable_t *v)
{
    if (v->causality == CSFH_CAUS_CALCULATED_PARAMETER) {
        return FMU_REFRESH_PREPARE;
    }
    if (v->storage != CSFH_STORE_COMPUTED) {
        return FMU_REFRESH_NONE;
    }
    if (v->offset >= fmu_model.der_offset &&
        v->offset < fmu_model.der_offset + (size_t)fmu_model.n_states * sizeof(double)) {
        return FMU_REFRESH_DERIVATIVES;
    }
    return FMU_REFRESH_OUTPUTS;
}

static fmu_vr_get_t vr_get_entry(const csfh_variable_t *v)
{
    const fmu_vr_get_t e = {(unsigned int)v->offset, (unsigned char)FMU_ACCEPT(v->type),
                            refresh_kind(v), v->type == CSFH_TYPE_BOOLEAN};
    return e;
}

fmu_instance_t *fmu_instance_new(const char *instance_name, fmu_kind_t type, int fmi_version,
                                 int logging_on)
{
    fmu_instance_t *inst = (fmu_instance_t *)calloc(1, sizeof(fmu_instance_t));
    if (inst == NULL) {
        return NULL;
    }
    inst->instance_name = (char *)malloc(strlen(instance_name) + 1);
    inst->model = calloc(1, fmu_model.size);
    inst->last_step_x = (double *)calloc((size_t)fmu_model.n_states + 1, sizeof(double));
    unsigned int max_vr = 0;
    for (int i = 0; i < fmu_model.n_variables; i++) {
        max_vr = fmu_model.variables[i].vr > max_vr ? fmu_model.variables[i].vr : max_vr;
    }
    inst->n_vr_index = max_vr + 1;
    inst->vr_index = (int *)malloc((size_t)inst->n_vr_index * sizeof(int));
    inst->vr_get = (fmu_vr_get_t *)calloc(inst->n_vr_index, sizeof(fmu_vr_get_t));
    if (inst->instance_name == NULL || inst->model == NULL || inst->last_step_x == NULL ||
        inst->vr_index == NULL || inst->vr_get == NULL) {
        free(inst->instance_name);
        free(inst->model);
        free(inst->last_step_x);
        free(inst->vr_index);
        free(inst->vr_get);
        free(inst);
        return NULL;
    }
    for (unsigned int r = 0; r < inst->n_vr_index; r++) {
        inst->vr_index[r] = -1;
    }
    for (int i = fmu_model.n_variables - 1; i >= 0; i--) { /* the first of equal references */
        inst->vr_index[fmu_model.variables[i].vr] = i;
    }
    for (unsigned int r = 0; r < inst->n_vr_index; r++) {
        if (inst->vr_index[r] >= 0) {
            inst->vr_get[r] = vr_get_entry(&fmu_model.variables[inst->vr_index[r]]);
        }
    }
    strcpy(inst->instance_name, instance_name);
    inst->type = type;
    inst->fmi_version = fmi_version;
    inst->step_function = fmi_version == 3 ? "fmi3DoStep" : "fmi2DoStep";
    inst->log_categories = LOG_STATUS_ERROR | LOG_STATUS_WARNING;
    if (logging_on) {
        inst->log_categories |= LOG_EVENTS | LOG_ALL;
    }
    fmu_model.set_defaults(inst->model);
    inst->state = FMU_INSTANTIATED;
    inst->tolerance = FMU_DEFAULT_TOLERANCE;
    return inst;
}

void fmu_instance_free(fmu_instance_t *inst)
{
    if (inst == NULL) {
        return;
    }
    stepper_free(inst);
    states_free_all(inst); /* FMU states the importer did not free */
    free(inst->last_step_x);
    free(inst->vr_index);
    free(inst->vr_get);
    free(inst->model);
    free(inst->instance_name);
    free(inst);
}

void fmu_instance_reset(fmu_instance_t *inst)
{
    stepper_free(inst);
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
}

/* ------------------------------------------------------------------------------------------ */
/* model helpers */

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

fmu_status_t fmu_prepare(fmu_instance_t *inst, const char *function)
{
    if (inst->prepared) {
        return FMU_OK;
    }
    char msg[MSG_SIZE];
    if (fmu_model.prepare(inst->model, msg, sizeof(msg)) != 0) {
        FMU_LOG_ERROR(inst, "%s: %s", function, msg);
        return FMU_ERROR;
    }
    inst->prepared = 1;
    return FMU_OK;
}

/* The continuous states as text, for messages. */
const char *fmu_state_text(fmu_instance_t *inst, char *text, size_t size)
{
    const double *x = fmu_states(inst);
    size_t k = 0;
    text[0] = '\0';
    for (int i = 0; i < fmu_model.n_states && k + 1 < size; i++) {
        k += (size_t)snprintf(text + k, size - k, "%s%g", i ? ", " : "", x[i]);
    }
    return text;
}

fmu_status_t fmu_update_derivatives(fmu_instance_t *inst, const char *function)
{
    if (inst->derivatives_valid || fmu_model.n_states == 0) {
        return FMU_OK;
    }
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    double *x = fmu_states(inst);
    const int status =
        fmu_model.derivatives(inst->model, *fmu_time(inst), x, fmu_derivatives(inst));
    if (status == FMU_MODEL_NONFINITE) {
        char text[MSG_SIZE];
        FMU_LOG_ERROR(inst, "%s: non-finite derivative at t = %.17g, state [%s]", function,
                  *fmu_time(inst), fmu_state_text(inst, text, sizeof(text)));
        return FMU_ERROR;
    }
    inst->derivatives_valid = 1;
    /* no model warning here: integrators probe trial states (e.g. far inside a contact); the
     * warning comes from the outputs, which are evaluated at accepted states */
    return FMU_OK;
}

fmu_status_t fmu_update_outputs(fmu_instance_t *inst, const char *function)
{
    if (inst->outputs_valid) {
        return FMU_OK;
    }
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    stepper_flush(inst); /* the model's outputs over the communication step (peaks) */
    char msg[MSG_SIZE];
    msg[0] = '\0';
    const int status = fmu_model.outputs(inst->model, msg, sizeof(msg));
    if (status == FMU_MODEL_NONFINITE) {
        FMU_LOG_ERROR(inst, "%s: %s", function, msg);
        return FMU_ERROR;
    }
    inst->outputs_valid = 1;
    if (status == FMU_MODEL_WARNING) {
        if (!inst->warned_outputs) {
            inst->warned_outputs = 1;
            fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING, "%s: %s", function, msg);
        }
        return FMU_WARNING;
    }
    return FMU_OK;
}

int fmu_event_update(fmu_instance_t *inst)
{
    if (fmu_model.n_event_indicators == 0) {
        return 0;
    }
    /* the message is formatted only when it will be logged (an event costs far less than its
     * 17-digit message) */
    const int logged = inst->log_message != NULL && (inst->log_categories & LOG_EVENTS) != 0;
    char msg[MSG_SIZE];
    msg[0] = '\0';
    const int change = fmu_model.event_update(inst->model, msg, logged ? sizeof(msg) : 0);
    if (logged && msg[0] != '\0') {
        fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", msg);
    }
    if (change != 0) {
        fmu_invalidate(inst);
    }
    return change;
}
double fmu_next_time_event(fmu_instance_t *inst)
{
    return fmu_model.next_time_event != NULL
               ? fmu_model.next_time_event(inst->model, *fmu_time(inst))
               : INFINITY;
}

/* ------------------------------------------------------------------------------------------ */
/* experiment, initialization */

fmu_status_t fmu_setup_experiment(fmu_instance_t *inst, const char *function, int tolerance_defined,
                                  double tolerance, double start_time, int stop_time_defined,
                                  double stop_time)
{
    if (tolerance_defined && !(isfinite(tolerance) && tolerance > 0.0 && tolerance < 1.0)) {
        FMU_LOG_ERROR(inst, "%s: tolerance = %g must be in (0, 1)", function, tolerance);
        return FMU_ERROR;
    }
    if (!isfinite(start_time)) {
        FMU_LOG_ERROR(inst, "%s: startTime = %g is not finite", function, start_time);
        return FMU_ERROR;
    }
    if (stop_time_defined && !(isfinite(stop_time) && stop_time >= start_time)) {
        FMU_LOG_ERROR(inst, "%s: stopTime = %g must be finite and >= startTime = %g", function,
                      stop_time, start_time);
        return FMU_ERROR;
    }
    if (tolerance_defined) {
        inst->tolerance = tolerance;
    }
    inst->start_time = start_time;
    inst->stop_time = stop_time;
    inst->stop_time_defined = stop_time_defined ? 1 : 0;
    *fmu_time(inst) = start_time;
    return FMU_OK;
}

fmu_status_t fmu_exit_initialization(fmu_instance_t *inst, const char *function)
{
    /* a refused call changes nothing: the derived quantities that prepare() computes are put
     * back if the start state is then refused */
    void *saved = malloc(fmu_model.size);
    if (saved == NULL) {
        FMU_LOG_ERROR(inst, "%s: out of memory", function);
        return FMU_ERROR;
    }
    memcpy(saved, inst->model, fmu_model.size);
    const int was_prepared = inst->prepared;
    inst->prepared = 0; /* validate everything once more, whatever was read before */
    char msg[MSG_SIZE];
    msg[0] = '\0';
    int refused = fmu_prepare(inst, function) != FMU_OK;
    if (!refused && fmu_model.check_start != NULL &&
        fmu_model.check_start(inst->model, msg, sizeof(msg)) != 0) {
        FMU_LOG_ERROR(inst, "%s: %s", function, msg);
        refused = 1;
    }
    if (refused) {
        memcpy(inst->model, saved, fmu_model.size);
        inst->prepared = was_prepared;
    }
    free(saved);
    if (refused) {
        return FMU_ERROR;
    }
    fmu_model.init_discrete(inst->model, msg, sizeof(msg));
    fmu_invalidate(inst);
    if (msg[0] != '\0') {
        fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", msg);
    }
    inst->restart_integration = 1;
    step_reference(inst);
    return FMU_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* get and set */

static const csfh_variable_t *lookup(fmu_instance_t *inst, const char *function, unsigned int vr,
                                     unsigned int accept)
{
    const csfh_variable_t *v = NULL;
    if (vr < inst->n_vr_index && inst->vr_index[vr] >= 0) {
        v = &fmu_model.variables[inst->vr_index[vr]];
    }
    const int type_ok = v != NULL && (accept & FMU_ACCEPT(v->type)) != 0;
    if (!type_ok) {
        FMU_LOG_ERROR(inst, "%s: unknown value reference %u", function, vr);
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

/* Bring computed values up to date before they are read (what: FMU_REFRESH_*). */
static fmu_status_t refresh(fmu_instance_t *inst, unsigned char what, const char *function)
{
    switch (what) {
    case FMU_REFRESH_PREPARE:
        return fmu_prepare(inst, function);
    case FMU_REFRESH_DERIVATIVES:
        return fmu_update_derivatives(inst, function);
    case FMU_REFRESH_OUTPUTS:
        return fmu_update_outputs(inst, function);
    default:
        return FMU_OK;
    }
}

fmu_status_t fmu_get_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind, void *value)
{
    if (!fmu_allowed(inst, function, FMU_GET_STATES)) {
        return FMU_ERROR;
    }
    if (nvr > 0 && (!fmu_not_null(inst, function, vr, "vr") || !fmu_not_null(inst, function, value, "value"))) {
        return FMU_ERROR;
    }
    fmu_status_t status = FMU_OK;
    const char *model = (const char *)inst->model;
    for (size_t i = 0; i < nvr; i++) {
        /* the reference's 8-byte entry (fmu_vr_get_t); lookup only for the message */
        const fmu_vr_get_t *e = vr[i] < inst->n_vr_index ? &inst->vr_get[vr[i]] : NULL;
        if (e == NULL || (accept & e->accept) == 0) {
            lookup(inst, function, vr[i], accept);
            return FMU_ERROR;
        }
        /* up-to-date outputs (the common case) are seen here, without a call per value */
        if (e->refresh != FMU_REFRESH_NONE &&
            !(e->refresh == FMU_REFRESH_OUTPUTS && inst->outputs_valid)) {
            const fmu_status_t s = refresh(inst, e->refresh, function);
            if (s > FMU_WARNING) {
                return s;
            }
            status = s > status ? s : status;
        }
        const char *p = model + e->offset;
        switch (kind) {
        case FMU_VALUE_DOUBLE:
            memcpy((double *)value + i, p, sizeof(double));
            break;
        case FMU_VALUE_INT: {
            int n;
            memcpy(&n, p, sizeof(n));
            ((int *)value)[i] = e->boolean ? (n != 0) : n;
            break;
        }
        case FMU_VALUE_INT64: {
            int n;
            memcpy(&n, p, sizeof(n));
            ((int64_t *)value)[i] = (int64_t)n;
            break;
        }
        default: {
            int n;
            memcpy(&n, p, sizeof(n));
            ((bool *)value)[i] = n != 0;
            break;
        }
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
        FMU_LOG_ERROR(inst, "%s: variable %s cannot be set in state %s", function, v->name,
                  fmu_state_name(inst->state));
    }
    return ok;
}

/* The i-th value of a set call as a double. */
static double set_value_at(const csfh_variable_t *v, fmu_value_kind_t kind, const void *value,
                           size_t i)
{
    switch (kind) {
    case FMU_VALUE_DOUBLE:
        return ((const double *)value)[i];
    case FMU_VALUE_INT:
        if (v->type == CSFH_TYPE_BOOLEAN) {
            return ((const int *)value)[i] ? 1.0 : 0.0;
        }
        return (double)((const int *)value)[i];
    case FMU_VALUE_INT64:
        return (double)((const int64_t *)value)[i]; /* exact for |n| < 2^53; the range check
                                                      refuses anything outside an int's */
    default:
        return ((const bool *)value)[i] ? 1.0 : 0.0;
    }
}

/* All or nothing: every value is checked before any is applied, and tunable parameters set while
 * running are validated together (the model's cross-checks) and rolled back together, so a
 * rejected call leaves the instance exactly as it was. */
fmu_status_t fmu_set_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind,
                            const void *value)
{
    if (!fmu_allowed(inst, function, FMU_SET_STATES)) {
        return FMU_ERROR;
    }
    if (nvr > 0 && (!fmu_not_null(inst, function, vr, "vr") || !fmu_not_null(inst, function, value, "value"))) {
        return FMU_ERROR;
    }
    char msg[MSG_SIZE];
    int tunable = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], accept);
        if (v == NULL || !settable(inst, v, function)) {
            return FMU_ERROR;
        }
        if (csfh_check_value(v, set_value_at(v, kind, value, i), msg, sizeof(msg)) != 0) {
            FMU_LOG_ERROR(inst, "%s: %s", function, msg);
            return FMU_ERROR;
        }
        tunable = tunable || (v->causality == CSFH_CAUS_PARAMETER &&
                              !(inst->state & (FMU_INSTANTIATED | FMU_INITIALIZATION)));
    }
    /* every value is valid: first the outputs over the communication step (peaks), with the
     * values they were taken with (a parameter changes them; kept if the new ones are rolled
     * back) */
    stepper_flush(inst);
    void *saved = NULL;
    if (tunable) { /* tunable parameters while running: apply, re-validate, roll back on failure */
        saved = malloc(fmu_model.size);
        if (saved == NULL) {
            FMU_LOG_ERROR(inst, "%s: out of memory", function);
            return FMU_ERROR;
        }
        memcpy(saved, inst->model, fmu_model.size);
    }
    int restart = tunable, parameter = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], accept);
        const double x = set_value_at(v, kind, value, i);
        const double old = v->type == CSFH_TYPE_REAL ? *real_of(inst, v) : (double)*int_of(inst, v);
        if (v->type == CSFH_TYPE_REAL) {
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
            FMU_LOG_ERROR(inst, "%s: %s", function, msg);
            return FMU_ERROR;
        }
    } else if (parameter) {
        inst->prepared = 0;
    }
    if (restart) {
        inst->restart_integration = 1;
    }
    fmu_invalidate(inst);
    return FMU_OK;
}
/* ------------------------------------------------------------------------------------------ */
/* FMU state */

#define FMU_STATE_MAGIC 0x48465343u /* "CSFH" */
#define FMU_STATE_VERSION 4u /* raised with every change of the snapshot's layout */

/* An FMU state: this header, then the model struct (fmu_model.size bytes). The header holds no
 * enum types: its bytes may come from anywhere (deserialization), and every field is
 * checked before it is used. */
typedef struct {
    unsigned int magic;
    unsigned int version;
    unsigned int size; /* of the whole snapshot */
    char guid[40];
    int type;           /* fmu_kind_t */
    unsigned int state; /* fmu_state_t */
    int prepared;       /* not trusted: the parameters are validated again on restore */
    int warned_outputs;
    unsigned char model[];
} fmu_snapshot_t;

/* The instance states a restored FMU state may put an instance of each type into: those this
 * FMU can be in while the importer may take a state (FMU_ERROR_STATE is never entered); FMI 3.0
 * co-simulation with eventModeUsed: Event Mode too. */
#define ME_RESTORABLE (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_TERMINATED)
#define CS_RESTORABLE                                                                          \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_STEP_COMPLETE | FMU_STEP_FAILED | FMU_TERMINATED)

/* The name of the FMU-state argument in the standard's signatures. */
static const char *state_arg(const fmu_instance_t *inst)
{
    return inst->fmi_version == 3 ? "FMUState" : "FMUstate";
}

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

/* FMU states of this instance: getting and deserializing a state register what they allocate,
 * freeing the state forgets it, freeing the instance frees what is left. Any other pointer
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
        FMU_LOG_ERROR(inst, "%s: the FMUstate was not made by this instance (get or deserialize "
                        "FMU state), or was freed; states move between instances "
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
        FMU_LOG_ERROR(inst, "%s: the bytes are not a state of this FMU (header: magic, version, size "
                        "or GUID)", function);
        return -1;
    }
    if (s->type != (int)FMU_ME && s->type != (int)FMU_CS) {
        FMU_LOG_ERROR(inst, "%s: the FMUstate's instance type %d is neither model exchange nor "
                        "co-simulation", function, s->type);
        return -1;
    }
    if (s->type != (int)inst->type) {
        FMU_LOG_ERROR(inst, "%s: the FMUstate was made by a %s instance, this one is %s", function,
                  s->type == (int)FMU_ME ? "model-exchange" : "co-simulation",
                  inst->type == FMU_ME ? "model-exchange" : "co-simulation");
        return -1;
    }
    const unsigned int restorable =
        inst->type == FMU_ME ? ME_RESTORABLE
                             : CS_RESTORABLE | (inst->event_mode_used ? FMU_EVENT : 0u);
    const unsigned int st = s->state;
    if (st == 0 || (st & (st - 1)) != 0 || (st & restorable) == 0) { /* exactly one valid bit */
        FMU_LOG_ERROR(inst, "%s: the FMUstate's instance state %u is not a state a %s instance can "
                        "be restored to", function, st,
                  inst->type == FMU_ME ? "model-exchange" : "co-simulation");
        return -1;
    }
    if (s->warned_outputs != 0 && s->warned_outputs != 1) {
        FMU_LOG_ERROR(inst, "%s: the FMUstate's output-warning flag %d is not 0 or 1", function,
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
            FMU_LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
            return -1;
        }
    }
    if (fmu_model.check_state != NULL && fmu_model.check_state(model, msg, sizeof(msg)) != 0) {
        FMU_LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
        return -1;
    }
    *prepared = fmu_model.prepare(model, msg, sizeof(msg)) == 0;
    if (!*prepared && !(st & (FMU_INSTANTIATED | FMU_INITIALIZATION))) {
        FMU_LOG_ERROR(inst, "%s: FMUstate: %s", function, msg);
        return -1;
    }
    return 0;
}

fmu_status_t fmu_state_get(fmu_instance_t *inst, const char *function, void **state)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) ||
        !fmu_not_null(inst, function, state, state_arg(inst))) {
        return FMU_ERROR;
    }
    fmu_snapshot_t *s = (fmu_snapshot_t *)*state;
    if (s == NULL) {
        s = (fmu_snapshot_t *)calloc(1, snapshot_size());
        if (s == NULL || state_register(inst, s) != 0) {
            free(s);
            FMU_LOG_ERROR(inst, "%s: out of memory", function);
            return FMU_ERROR;
        }
    } else if (!state_owned(inst, s, function)) {
        return FMU_ERROR;
    }
    stepper_flush(inst); /* the snapshot holds the outputs over the communication step */
    snapshot_take(inst, s);
    /* the integrator's history (step size, order, Nordsieck array) is not part of the snapshot,
     * and restoring restarts the integrator at the restored point. Restart it here as well, so
     * that the run continuing from this point and any re-run after restoring this state take the
     * same integrator path (identical results). */
    inst->restart_integration = 1;
    *state = s;
    return FMU_OK;
}

fmu_status_t fmu_state_set(fmu_instance_t *inst, const char *function, void *state)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) ||
        !fmu_not_null(inst, function, state, state_arg(inst)) || !state_owned(inst, state, function)) {
        return FMU_ERROR;
    }
    const fmu_snapshot_t *s = (const fmu_snapshot_t *)state;
    void *model = malloc(fmu_model.size);
    if (model == NULL) {
        FMU_LOG_ERROR(inst, "%s: out of memory", function);
        return FMU_ERROR;
    }
    int prepared = 0;
    if (snapshot_check(inst, s, model, &prepared, function) != 0) {
        free(model); /* the instance is unchanged */
        return FMU_ERROR;
    }
    free(inst->model);
    inst->model = model;
    inst->state = (fmu_state_t)s->state;
    inst->prepared = prepared;
    inst->warned_outputs = s->warned_outputs;
    step_reference(inst);
    inst->restart_integration = 1;
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_state_free(fmu_instance_t *inst, const char *function, void **state)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE)) {
        return FMU_ERROR;
    }
    if (state == NULL || *state == NULL) {
        return FMU_OK;
    }
    const long i = state_index(inst, *state);
    if (i < 0) {
        state_owned(inst, *state, function); /* logs */
        return FMU_ERROR;
    }
    free(*state);
    inst->fmu_states[i] = inst->fmu_states[--inst->n_fmu_states];
    *state = NULL;
    return FMU_OK;
}

fmu_status_t fmu_state_size(fmu_instance_t *inst, const char *function, void *state, size_t *size)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) ||
        !fmu_not_null(inst, function, state, state_arg(inst)) ||
        !fmu_not_null(inst, function, size, "size") || !state_owned(inst, state, function)) {
        return FMU_ERROR;
    }
    *size = snapshot_size();
    return FMU_OK;
}

fmu_status_t fmu_state_serialize(fmu_instance_t *inst, const char *function, void *state,
                                 unsigned char bytes[], size_t size)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) ||
        !fmu_not_null(inst, function, state, state_arg(inst)) ||
        !fmu_not_null(inst, function, bytes, "serializedState") ||
        !state_owned(inst, state, function)) {
        return FMU_ERROR;
    }
    if (size < snapshot_size()) {
        FMU_LOG_ERROR(inst, "%s: size = %zu is smaller than %zu", function, size, snapshot_size());
        return FMU_ERROR;
    }
    memcpy(bytes, state, snapshot_size());
    return FMU_OK;
}

/* The bytes get the same checks as restoring gives them (snapshot_check): a state that could not
 * be restored into this instance is refused here already. */
fmu_status_t fmu_state_deserialize(fmu_instance_t *inst, const char *function,
                                   const unsigned char bytes[], size_t size, void **state)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) ||
        !fmu_not_null(inst, function, bytes, "serializedState") ||
        !fmu_not_null(inst, function, state, state_arg(inst))) {
        return FMU_ERROR;
    }
    if (size != snapshot_size()) {
        FMU_LOG_ERROR(inst, "%s: size = %zu, expected %zu", function, size, snapshot_size());
        return FMU_ERROR;
    }
    fmu_snapshot_t *s = (fmu_snapshot_t *)calloc(1, snapshot_size());
    void *model = malloc(fmu_model.size);
    if (s == NULL || model == NULL) {
        free(s);
        free(model);
        FMU_LOG_ERROR(inst, "%s: out of memory", function);
        return FMU_ERROR;
    }
    memcpy(s, bytes, snapshot_size()); /* aligned from here on */
    int prepared = 0;
    const int bad = snapshot_check(inst, s, model, &prepared, function) != 0;
    free(model);
    if (bad || state_register(inst, s) != 0) {
        if (!bad) {
            FMU_LOG_ERROR(inst, "%s: out of memory", function);
        }
        free(s);
        return FMU_ERROR;
    }
    *state = s;
    return FMU_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* model exchange */

/* Model exchange and large times: the importer integrates in its own time, and the model is
 * autonomous (the time only stamps the recorded onset and release times), so the FMU's
 * derivatives, event indicators and outputs do not depend on the start time at all; what the
 * FMU can promise is to report what it sees of the importer's time losing precision. At every
 * completed integrator step it compares the time with the previous completed step's: if the
 * states moved but the double time represents the increment dt worse than the tolerance
 * (ulp(t) > max(tolerance, 1e-6) * dt, including dt = 0: steps below the resolution of t), it
 * returns FMU_WARNING (logged once per instance). A time that went backwards (the importer
 * rolled its integrator back) is not judged. */
static fmu_status_t check_me_time_resolution(fmu_instance_t *inst, const char *function)
{
    const double t = *fmu_time(inst);
    const double *x = fmu_states(inst);
    const size_t bytes = (size_t)fmu_model.n_states * sizeof(double);
    fmu_status_t status = FMU_OK;
    if (inst->last_step_valid && bytes > 0) {
        const double dt = t - inst->last_step_time;
        const double ulp = nextafter(fabs(t), INFINITY) - fabs(t);
        const int moved = memcmp(x, inst->last_step_x, bytes) != 0;
        if (moved && dt >= 0.0 && ulp > time_resolution_needed(inst) * dt) {
            status = FMU_WARNING;
            if (!inst->warned_time) {
                inst->warned_time = 1;
                fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING,
                        "%s: the time t = %.17g resolves steps to %g s "
                        "only; the integrator step from t = %.17g (dt = %g s) is represented to "
                        "worse than %g relative: integrate in a time measured from a nearer "
                        "origin (further such steps return a warning without a message)",
                        function, t, ulp, inst->last_step_time, dt, time_resolution_needed(inst));
            }
        }
    }
    step_reference(inst);
    return status;
}

fmu_status_t fmu_completed_integrator_step(fmu_instance_t *inst, const char *function)
{
    if (!fmu_allowed(inst, function, FMU_CONTINUOUS) || !fmu_is_me(inst, function)) {
        return FMU_ERROR;
    }
    return check_me_time_resolution(inst, function);
}

fmu_status_t fmu_set_time(fmu_instance_t *inst, const char *function, double time)
{
    if (!fmu_allowed(inst, function, FMU_EVENT | FMU_CONTINUOUS) || !fmu_is_me(inst, function)) {
        return FMU_ERROR;
    }
    if (!isfinite(time)) {
        FMU_LOG_ERROR(inst, "%s: time = %g is not finite", function, time);
        return FMU_ERROR;
    }
    *fmu_time(inst) = time;
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_set_continuous_states(fmu_instance_t *inst, const char *function,
                                       const double x[], size_t nx)
{
    if (!fmu_allowed(inst, function, FMU_CONTINUOUS) || !fmu_is_me(inst, function) ||
        !fmu_not_null(inst, function, x, "x")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            FMU_LOG_ERROR(inst, "%s: x[%zu] = %g is not finite (t = %.17g)", function, i, x[i],
                          *fmu_time(inst));
            return FMU_ERROR;
        }
    }
    if (nx > 0) {
        memcpy(fmu_states(inst), x, nx * sizeof(double));
    }
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_get_derivatives(fmu_instance_t *inst, const char *function, double der[],
                                 size_t nx)
{
    if (!fmu_allowed(inst, function, FMU_GET_STATES) || !fmu_is_me(inst, function) ||
        !fmu_not_null(inst, function, der, "derivatives")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    const fmu_status_t status = fmu_update_derivatives(inst, function);
    if (status > FMU_WARNING) {
        return status;
    }
    if (nx > 0) {
        memcpy(der, fmu_derivatives(inst), nx * sizeof(double));
    }
    return status;
}

fmu_status_t fmu_get_event_indicators(fmu_instance_t *inst, const char *function, double z[],
                                      size_t ni)
{
    if (!fmu_allowed(inst, function, FMU_GET_STATES) || !fmu_is_me(inst, function) ||
        !fmu_not_null(inst, function, z, "eventIndicators")) {
        return FMU_ERROR;
    }
    if (ni != (size_t)fmu_model.n_event_indicators) {
        FMU_LOG_ERROR(inst, "%s: ni = %zu, expected %d", function, ni,
                      fmu_model.n_event_indicators);
        return FMU_ERROR;
    }
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    if (ni > 0) {
        fmu_model.event_indicators(inst->model, fmu_states(inst), z);
    }
    for (size_t i = 0; i < ni; i++) {
        if (!isfinite(z[i])) {
            char text[MSG_SIZE];
            FMU_LOG_ERROR(inst, "%s: non-finite event indicator z[%zu] = %g at t = %.17g, state [%s]",
                          function, i, z[i], *fmu_time(inst), fmu_state_text(inst, text, sizeof(text)));
            return FMU_ERROR;
        }
    }
    return FMU_OK;
}

fmu_status_t fmu_get_continuous_states(fmu_instance_t *inst, const char *function, double x[],
                                       size_t nx)
{
    if (!fmu_allowed(inst, function, FMU_GET_STATES) || !fmu_is_me(inst, function) ||
        !fmu_not_null(inst, function, x, "x")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    if (nx > 0) {
        memcpy(x, fmu_states(inst), nx * sizeof(double));
    }
    return FMU_OK;
}

fmu_status_t fmu_get_nominals(fmu_instance_t *inst, const char *function, double nominal[],
                              size_t nx)
{
    if (!fmu_allowed(inst, function, FMU_ANY_STATE) || !fmu_is_me(inst, function) ||
        !fmu_not_null(inst, function, nominal, "x_nominal")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    size_t k = 0;
    for (int i = 0; i < fmu_model.n_variables && k < nx; i++) {
        if (fmu_model.variables[i].is_state) {
            nominal[k++] = fmu_model.variables[i].nominal;
        }
    }
    return FMU_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation */

/* Round-off allowed in a master's time arithmetic (fmi2DoStep): a currentCommunicationPoint t
 * is the FMU's time T if |t - T| <= COMM_POINT_ROUNDOFF * max(|t|, |T|), i.e. a few units in the
 * last place (4 to 8 ulp): what t0 + k h against t_(k-1) + h, or integer nanoseconds converted to
 * seconds, give. */
#define COMM_POINT_ROUNDOFF (16.0 * DBL_EPSILON)

/* The step's arguments against the FMU's time T: the communication point t must be T up to
 * round-off (COMM_POINT_ROUNDOFF; a t behind T would take the time backwards, one ahead would
 * skip an interval), the step h finite and >= 0, and the end t + h (computed as the master
 * computes it) finite and, for h > 0, later than T. The FMU integrates from its own time T to
 * t + h, so its time never goes backwards. A refused step is FMU_ERROR and changes nothing.
 * Precision lost: if the double time represents the step T -> t + h worse than the integration
 * tolerance (|(t + h - T) - h| > max(tolerance, 1e-6) h, e.g. h = 1e-3 s at t = 1e10 s, where
 * the resolution is 1.9e-6 s), the step is taken and reported with FMU_WARNING (logged once). */
fmu_status_t fmu_check_step(fmu_instance_t *inst, const char *function, double t, double h,
                            double *t_end)
{
    const double T = *fmu_time(inst);
    if (!isfinite(t) || !isfinite(h) || h < 0.0) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint = %g, communicationStepSize = %g "
                        "must be finite and the step >= 0",
                  function, t, h);
        return FMU_ERROR;
    }
    if (fabs(t - T) > COMM_POINT_ROUNDOFF * fmax(fabs(t), fabs(T))) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint = %.17g does not match the FMU time "
                        "%.17g (%s by %.3g s; allowed: round-off, %.3g s)",
                  function, t, T, t < T ? "behind" : "ahead", fabs(t - T),
                  COMM_POINT_ROUNDOFF * fmax(fabs(t), fabs(T)));
        return FMU_ERROR;
    }
    *t_end = t + h;
    if (h == 0.0) {
        return FMU_OK;
    }
    if (!isfinite(*t_end)) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint + communicationStepSize = %.17g + "
                        "%g is not finite", function, t, h);
        return FMU_ERROR;
    }
    if (!(*t_end > T)) {
        FMU_LOG_ERROR(inst, "%s: communicationStepSize = %g at t = %.17g is below the "
                        "resolution of the time (%g s): t + h = %.17g does not advance the FMU "
                        "time %.17g",
                  function, h, t, nextafter(fabs(T), INFINITY) - fabs(T), *t_end, T);
        return FMU_ERROR;
    }
    const double taken = *t_end - T;
    if (fabs(taken - h) > time_resolution_needed(inst) * h) {
        if (!inst->warned_time) {
            inst->warned_time = 1;
            fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING,
                    "%s: the time t = %.17g resolves steps to %g s only: "
                    "communicationStepSize = %.17g is taken as %.17g (relative difference %.3g > "
                    "%g); the FMU integrates exactly that step, but the communication points are "
                    "not where the master meant them (further such steps return a warning "
                    "without a message)",
                    function, T, nextafter(fabs(*t_end), INFINITY) - fabs(*t_end), h, taken,
                    fabs(taken - h) / h, time_resolution_needed(inst));
        }
        return FMU_WARNING;
    }
    return FMU_OK;
}
