/* The FMU state (fmu_instance.h): snapshots of the instance, the states an instance owns, the
 * validation of a state on restore (as if its content were set), serialization. */
#include <stdlib.h>
#include <string.h>

#include "fmu_log.h"
#include "fmu_state.h"
#include "fmu_types.h"

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

void fmu_states_free_all(fmu_instance_t *inst)
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

static const char *kind_name(int type)
{
    return type == (int)FMU_ME ? "model-exchange" : "co-simulation";
}

/* The snapshot's header (snapshot_check): 0, or -1 (logged). */
static int header_check(fmu_instance_t *inst, const fmu_snapshot_t *s, const char *function)
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
                      kind_name(s->type), kind_name((int)inst->type));
        return -1;
    }
    const unsigned int restorable =
        inst->type == FMU_ME ? ME_RESTORABLE
                             : CS_RESTORABLE | (inst->event_mode_used ? FMU_EVENT : 0u);
    const unsigned int st = s->state;
    if (st == 0 || (st & (st - 1)) != 0 || (st & restorable) == 0) { /* exactly one valid bit */
        FMU_LOG_ERROR(inst, "%s: the FMUstate's instance state %u is not a state a %s instance can "
                        "be restored to", function, st, kind_name((int)inst->type));
        return -1;
    }
    if (s->warned_outputs != 0 && s->warned_outputs != 1) {
        FMU_LOG_ERROR(inst, "%s: the FMUstate's output-warning flag %d is not 0 or 1", function,
                  s->warned_outputs);
        return -1;
    }
    return 0;
}

/* The snapshot's model (snapshot_check), restored into the instance state st: 0, or -1
 * (logged). */
static int model_check(fmu_instance_t *inst, void *model, unsigned int st, int *prepared,
                       const char *function)
{
    char msg[FMU_MSG_SIZE];
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
    if (header_check(inst, s, function) != 0) {
        return -1;
    }
    memcpy(model, s->model, fmu_model.size);
    return model_check(inst, model, s->state, prepared, function);
}

fmu_status_t fmu_state_get(fmu_instance_t *inst, const char *function, void **state)
{
    if (!fmu_not_null(inst, function, state, state_arg(inst))) {
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
    fmu_flush(inst); /* the snapshot holds the outputs over the communication step */
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
    if (!fmu_not_null(inst, function, state, state_arg(inst)) || !state_owned(inst, state, function)) {
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
    fmu_step_reference(inst);
    inst->restart_integration = 1;
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_state_free(fmu_instance_t *inst, const char *function, void **state)
{
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
    if (!fmu_not_null(inst, function, state, state_arg(inst)) ||
        !fmu_not_null(inst, function, size, "size") || !state_owned(inst, state, function)) {
        return FMU_ERROR;
    }
    *size = snapshot_size();
    return FMU_OK;
}

fmu_status_t fmu_state_serialize(fmu_instance_t *inst, const char *function, void *state,
                                 unsigned char bytes[], size_t size)
{
    if (!fmu_not_null(inst, function, state, state_arg(inst)) ||
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
    if (!fmu_not_null(inst, function, bytes, "serializedState") ||
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
