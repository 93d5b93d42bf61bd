/* The FMI-independent part of an FMU instance (fmu_instance.h), shared by the FMI 2.0 and FMI 3.0
 * front-ends (fmi2/, fmi3/) and the co-simulation stepper (cosim/): its life cycle, the model
 * helpers (prepare, derivatives, outputs, event update) and the experiment and initialization.
 * Model-independent: the model is behind the interface of fmu_model.h (csfh: ../models/csfh/,
 * physics in ../physics/; the comb-drive actuator: ../models/combdrive/). Messages name the FMI
 * function the importer called (`function`, given by the front-end). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_format.h"
#include "fmu_instance.h"

/* the co-simulation stepper's hooks (fmu_stepper_t), where the front-end gave them */
static void stepper_free(fmu_instance_t *inst)
{
    if (inst->stepper != NULL) {
        inst->stepper->free(inst);
    }
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
    if (fmu_model.subset_outputs != NULL && fmu_model.in_subset(v->offset)) {
        return FMU_REFRESH_SUBSET;
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
    inst->tolerance = fmu_model.default_tolerance;
    return inst;
}

void fmu_instance_free(fmu_instance_t *inst)
{
    if (inst == NULL) {
        return;
    }
    stepper_free(inst);
    fmu_states_free_all(inst); /* FMU states the importer did not free */
    free(inst->last_step_x);
    free(inst->vr_index);
    free(inst->vr_get);
    free(inst->model);
    free(inst->instance_name);
    free(inst);
}

void fmu_instance_reset(fmu_instance_t *inst)
{
    if (inst->stepper != NULL) {
        inst->stepper->reset(inst);
    }
    fmu_model.set_defaults(inst->model);
    inst->prepared = 0;
    inst->warned_outputs = 0;
    inst->tolerance = fmu_model.default_tolerance;
    inst->start_time = 0.0;
    inst->stop_time_defined = 0;
    inst->warned_time = 0;
    inst->last_step_valid = 0;
    fmu_invalidate(inst);
    inst->state = FMU_INSTANTIATED;
}

/* ------------------------------------------------------------------------------------------ */
/* model helpers */

fmu_status_t fmu_prepare(fmu_instance_t *inst, const char *function)
{
    if (inst->prepared) {
        return FMU_OK;
    }
    char msg[FMU_MSG_SIZE];
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
        char text[FMU_MSG_SIZE];
        FMU_LOG_ERROR(inst, "%s: non-finite derivative at t = %.17g, state [%s]", function,
                  *fmu_time(inst), fmu_state_text(inst, text, sizeof(text)));
        return FMU_ERROR;
    }
    inst->derivatives_valid = 1;
    /* no model warning here: integrators probe trial states (e.g. far inside a contact); the
     * warning comes from the outputs, which are evaluated at accepted states */
    return FMU_OK;
}

/* The outputs by `compute` (fmu_model.outputs or .subset_outputs), up to date as `level`
 * (FMU_OUTPUTS_*) unless they are already; a model warning is logged once per instance. */
static fmu_status_t compute_outputs(fmu_instance_t *inst, const char *function,
                                    int (*compute)(void *m, char *msg, size_t msg_size),
                                    int level)
{
    if (inst->outputs_valid >= level) {
        return FMU_OK;
    }
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    fmu_flush(inst); /* the model's outputs over the communication step (peaks) */
    char msg[FMU_MSG_SIZE];
    msg[0] = '\0';
    const int status = compute(inst->model, msg, sizeof(msg));
    if (status == FMU_MODEL_NONFINITE) {
        FMU_LOG_ERROR(inst, "%s: %s", function, msg);
        return FMU_ERROR;
    }
    inst->outputs_valid = level;
    if (status == FMU_MODEL_WARNING) {
        if (!inst->warned_outputs) {
            inst->warned_outputs = 1;
            fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING, "%s: %s", function, msg);
        }
        return FMU_WARNING;
    }
    return FMU_OK;
}

fmu_status_t fmu_update_outputs(fmu_instance_t *inst, const char *function)
{
    return compute_outputs(inst, function, fmu_model.outputs, FMU_OUTPUTS_ALL);
}

fmu_status_t fmu_update_output_subset(fmu_instance_t *inst, const char *function)
{
    return compute_outputs(inst, function, fmu_model.subset_outputs, FMU_OUTPUTS_SUBSET);
}

int fmu_event_update(fmu_instance_t *inst)
{
    if (fmu_model.n_event_indicators == 0) {
        return 0;
    }
    /* the message is formatted only when it will be logged (an event costs far less than its
     * 17-digit message) */
    const int logged = inst->log_message != NULL && (inst->log_categories & LOG_EVENTS) != 0;
    char msg[FMU_MSG_SIZE];
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
    if (tolerance_defined && !(tolerance >= FMU_TOLERANCE_MIN && tolerance < FMU_TOLERANCE_MAX)) {
        char value[32], lo[32];
        FMU_LOG_ERROR(inst,
                      "%s: tolerance = %s must be in [%s, %g): the integrators cannot honour a "
                      "relative tolerance below 10 machine epsilons, nor one of 1 or more",
                      function, csfh_format_value(value, tolerance),
                      csfh_format_value(lo, FMU_TOLERANCE_MIN), FMU_TOLERANCE_MAX);
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
    char msg[FMU_MSG_SIZE];
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
    fmu_step_reference(inst);
    return FMU_OK;
}
