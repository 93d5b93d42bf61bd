/* Get and set by value reference through the generated variable table (fmu_instance.h): the
 * refresh of computed values before they are read, the settability of each variable in the
 * instance's state, all-or-nothing sets with the tunable parameters validated together. */
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_instance.h"

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
    case FMU_REFRESH_SUBSET:
        return fmu_update_output_subset(inst, function);
    default:
        return FMU_OK;
    }
}

/* Whether the outputs a reference needs (FMU_REFRESH_OUTPUTS or _SUBSET) are up to date. */
static inline int up_to_date(const fmu_instance_t *inst, unsigned char refresh)
{
    return (refresh == FMU_REFRESH_OUTPUTS && inst->outputs_valid == FMU_OUTPUTS_ALL) ||
           (refresh == FMU_REFRESH_SUBSET && inst->outputs_valid != FMU_OUTPUTS_NONE);
}

/* Whether one of the references vr[0 .. n) needs all the outputs: then a subset read before it
 * computes them all at once, not the subset first. */
static int needs_all(const fmu_instance_t *inst, const unsigned int vr[], size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (vr[i] < inst->n_vr_index && inst->vr_get[vr[i]].refresh == FMU_REFRESH_OUTPUTS) {
            return 1;
        }
    }
    return 0;
}

/* The value at p (of the reference's entry e) into value[i], as `kind`. */
static inline void copy_value(const char *p, const fmu_vr_get_t *e, fmu_value_kind_t kind,
                              void *value, size_t i)
{
    int n;
    switch (kind) {
    case FMU_VALUE_DOUBLE:
        memcpy((double *)value + i, p, sizeof(double));
        break;
    case FMU_VALUE_INT:
        memcpy(&n, p, sizeof(n));
        ((int *)value)[i] = e->boolean ? (n != 0) : n;
        break;
    case FMU_VALUE_INT64:
        memcpy(&n, p, sizeof(n));
        ((int64_t *)value)[i] = (int64_t)n;
        break;
    default:
        memcpy(&n, p, sizeof(n));
        ((bool *)value)[i] = n != 0;
        break;
    }
}

fmu_status_t fmu_get_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind, void *value)
{
    if (nvr > 0 && (!fmu_not_null(inst, function, vr, "vr") ||
                    !fmu_not_null(inst, function, value, "value"))) {
        return FMU_ERROR;
    }
    fmu_status_t status = FMU_OK;
    const char *model = (const char *)inst->model;
    /* read once: the values written could alias the instance for all the compiler knows */
    const fmu_vr_get_t *const table = inst->vr_get;
    const unsigned int n_index = inst->n_vr_index;
    for (size_t i = 0; i < nvr; i++) {
        /* the reference's 8-byte entry (fmu_vr_get_t); lookup only for the message */
        if (vr[i] >= n_index || (accept & table[vr[i]].accept) == 0) {
            lookup(inst, function, vr[i], accept);
            return FMU_ERROR;
        }
        const fmu_vr_get_t *e = &table[vr[i]];
        /* up-to-date outputs (the common case) are seen here, without a call per value */
        if (e->refresh != FMU_REFRESH_NONE && !up_to_date(inst, e->refresh)) {
            const unsigned char what =
                e->refresh == FMU_REFRESH_SUBSET && needs_all(inst, vr + i + 1, nvr - i - 1)
                    ? FMU_REFRESH_OUTPUTS
                    : e->refresh;
            const fmu_status_t s = refresh(inst, what, function);
            if (s > FMU_WARNING) {
                return s;
            }
            status = s > status ? s : status;
        }
        copy_value(model + e->offset, e, kind, value, i);
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

/* fmi3Boolean is C's bool, one byte on every platform the FMU is built for. */
_Static_assert(sizeof(bool) == 1, "an fmi3Boolean array is read as bytes");

/* The i-th value of a set call as a double. An fmi3Boolean comes from the importer's memory,
 * where any byte may stand: it is read as a byte, nonzero for true (a bool holding 2 is not a
 * valid bool, and reading it as one is undefined). */
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
        return ((const unsigned char *)value)[i] != 0 ? 1.0 : 0.0;
    }
}

/* Every value of a set call valid for its variable in the instance's state (logged if not): 0,
 * or -1. *tunable: a parameter is set while running. */
static int check_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                        size_t nvr, unsigned int accept, fmu_value_kind_t kind, const void *value,
                        int *tunable)
{
    char msg[FMU_MSG_SIZE];
    *tunable = 0;
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], accept);
        if (v == NULL || !settable(inst, v, function)) {
            return -1;
        }
        if (csfh_check_value(v, set_value_at(v, kind, value, i), msg, sizeof(msg)) != 0) {
            FMU_LOG_ERROR(inst, "%s: %s", function, msg);
            return -1;
        }
        *tunable = *tunable || (v->causality == CSFH_CAUS_PARAMETER &&
                                !(inst->state & (FMU_INSTANTIATED | FMU_INITIALIZATION)));
    }
    return 0;
}

/* Set the (checked) values; *parameter: a parameter was set, *restart: the co-simulation
 * integrator must restart (a new state, or a new input value: inputs are held constant over a
 * communication step, so a change is a discontinuity of the right-hand side). */
static void apply_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                         size_t nvr, unsigned int accept, fmu_value_kind_t kind, const void *value,
                         int *parameter, int *restart)
{
    for (size_t i = 0; i < nvr; i++) {
        const csfh_variable_t *v = lookup(inst, function, vr[i], accept);
        const double x = set_value_at(v, kind, value, i);
        const double old = v->type == CSFH_TYPE_REAL ? *real_of(inst, v) : (double)*int_of(inst, v);
        if (v->type == CSFH_TYPE_REAL) {
            *real_of(inst, v) = x;
        } else {
            *int_of(inst, v) = (int)x;
        }
        *parameter = *parameter || v->causality == CSFH_CAUS_PARAMETER;
        *restart = *restart || v->is_state || (v->causality == CSFH_CAUS_INPUT && old != x);
    }
}

/* All or nothing: every value is checked before any is applied, and tunable parameters set while
 * running are validated together (the model's cross-checks) and rolled back together, so a
 * rejected call leaves the instance exactly as it was. */
fmu_status_t fmu_set_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind,
                            const void *value)
{
    if (nvr > 0 && (!fmu_not_null(inst, function, vr, "vr") ||
                    !fmu_not_null(inst, function, value, "value"))) {
        return FMU_ERROR;
    }
    int tunable = 0;
    if (check_values(inst, function, vr, nvr, accept, kind, value, &tunable) != 0) {
        return FMU_ERROR;
    }
    /* every value is valid: first the outputs over the communication step (peaks), with the
     * values they were taken with (a parameter changes them; kept if the new ones are rolled
     * back) */
    fmu_flush(inst);
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
    apply_values(inst, function, vr, nvr, accept, kind, value, &parameter, &restart);
    if (tunable) {
        char msg[FMU_MSG_SIZE];
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
