/* Directional and adjoint derivatives (fmi2GetDirectionalDerivative, fmi3GetDirectionalDerivative,
 * fmi3GetAdjointDerivative) on the model's partial derivatives (fmu_model.h: jacobian): the
 * arguments checked, each value reference found among the model's unknowns and knowns and
 * allowed for the interface (model exchange: derivatives and outputs with respect to states and
 * inputs; co-simulation: outputs with respect to inputs, FMI 2.0 section 4.2.1, FMI 3.0 section
 * 2.2.11), then the product of the dense Jacobian with the seed. */
#include <math.h>
#include <string.h>

#include "fmu_instance.h"

/* The largest Jacobian a model may declare (csfh: 36 unknowns x 11 knowns). */
#define FMU_JAC_MAX_ENTRIES 1024

static const csfh_variable_t *variable_of(const fmu_instance_t *inst, unsigned int vr)
{
    if (vr < inst->n_vr_index && inst->vr_index[vr] >= 0) {
        return &fmu_model.variables[inst->vr_index[vr]];
    }
    return NULL;
}

/* Position of vr in list (n entries), or -1. */
static int position(const unsigned int *list, int n, unsigned int vr)
{
    for (int i = 0; i < n; i++) {
        if (list[i] == vr) {
            return i;
        }
    }
    return -1;
}

/* Each unknown a derivative (model exchange only) or a continuous output of the model's list:
 * 0, else -1 with a message naming it. */
static int check_unknowns(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                          size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const csfh_variable_t *v = variable_of(inst, vr[i]);
        const int row = position(fmu_model.jac_unknowns, fmu_model.n_jac_unknowns, vr[i]);
        const int allowed = v != NULL && (inst->type == FMU_ME || v->causality == CSFH_CAUS_OUTPUT);
        if (row < 0 || !allowed) {
            FMU_LOG_ERROR(inst, "%s: unknowns[%zu] = %u (%s) is not %s", function, i, vr[i],
                          v != NULL ? v->name : "no variable",
                          inst->type == FMU_ME ? "a derivative or a continuous output"
                                               : "a continuous output");
            return -1;
        }
    }
    return 0;
}

/* Each known a state (model exchange only) or an input. */
static int check_knowns(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                        size_t n)
{
    for (size_t j = 0; j < n; j++) {
        const csfh_variable_t *v = variable_of(inst, vr[j]);
        const int col = position(fmu_model.jac_knowns, fmu_model.n_jac_knowns, vr[j]);
        const int allowed = v != NULL && (inst->type == FMU_ME || v->causality == CSFH_CAUS_INPUT);
        if (col < 0 || !allowed) {
            FMU_LOG_ERROR(inst, "%s: knowns[%zu] = %u (%s) is not %s", function, j, vr[j],
                          v != NULL ? v->name : "no variable",
                          inst->type == FMU_ME ? "a continuous state or an input" : "an input");
            return -1;
        }
    }
    return 0;
}

/* NULL arrays with entries, the sizes of FMI 3.0's seed and sensitivity, a seed not finite. */
static int arguments_ok(fmu_instance_t *inst, const char *function, const fmu_derivative_call_t *a)
{
    const size_t n_seed = a->adjoint ? a->n_unknowns : a->n_knowns;
    const size_t n_sens = a->adjoint ? a->n_knowns : a->n_unknowns;
    if ((a->n_unknowns > 0 && !fmu_not_null(inst, function, a->unknowns, "unknowns")) ||
        (a->n_knowns > 0 && !fmu_not_null(inst, function, a->knowns, "knowns")) ||
        (n_seed > 0 && !fmu_not_null(inst, function, a->seed, "seed")) ||
        (n_sens > 0 && !fmu_not_null(inst, function, a->sensitivity, "sensitivity"))) {
        return 0;
    }
    if (a->n_seed != n_seed || a->n_sensitivity != n_sens) {
        FMU_LOG_ERROR(inst, "%s: nSeed = %zu and nSensitivity = %zu, expected %zu and %zu",
                      function, a->n_seed, a->n_sensitivity, n_seed, n_sens);
        return 0;
    }
    for (size_t k = 0; k < n_seed; k++) {
        if (!isfinite(a->seed[k])) {
            FMU_LOG_ERROR(inst, "%s: seed[%zu] = %g is not finite", function, k, a->seed[k]);
            return 0;
        }
    }
    return 1;
}

/* The model's Jacobian at the current state (J: n_jac_unknowns x n_jac_knowns). */
static fmu_status_t evaluate(fmu_instance_t *inst, const char *function, double *J)
{
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    if (fmu_model.jacobian(inst->model, J) != FMU_MODEL_OK) {
        char text[FMU_MSG_SIZE];
        FMU_LOG_ERROR(inst, "%s: non-finite partial derivative at t = %.17g, state [%s]",
                      function, *fmu_time(inst), fmu_state_text(inst, text, sizeof(text)));
        return FMU_ERROR;
    }
    return FMU_OK;
}

fmu_status_t fmu_partial_derivatives(fmu_instance_t *inst, const char *function,
                                     const fmu_derivative_call_t *a)
{
    if (fmu_model.jacobian == NULL ||
        fmu_model.n_jac_unknowns * fmu_model.n_jac_knowns > FMU_JAC_MAX_ENTRIES) {
        FMU_LOG_ERROR(inst, "%s: not provided (the model has no partial derivatives)", function);
        return FMU_ERROR;
    }
    if (!arguments_ok(inst, function, a) ||
        check_unknowns(inst, function, a->unknowns, a->n_unknowns) != 0 ||
        check_knowns(inst, function, a->knowns, a->n_knowns) != 0) {
        return FMU_ERROR;
    }
    double J[FMU_JAC_MAX_ENTRIES];
    const fmu_status_t status = evaluate(inst, function, J);
    if (status != FMU_OK) {
        return status;
    }
    const int nu = fmu_model.n_jac_unknowns, nk = fmu_model.n_jac_knowns;
    const size_t n_out = a->adjoint ? a->n_knowns : a->n_unknowns;
    if (n_out > 0) {
        memset(a->sensitivity, 0, n_out * sizeof(double));
    }
    for (size_t i = 0; i < a->n_unknowns; i++) {
        const int row = position(fmu_model.jac_unknowns, nu, a->unknowns[i]);
        for (size_t j = 0; j < a->n_knowns; j++) {
            const double d = J[row * nk + position(fmu_model.jac_knowns, nk, a->knowns[j])];
            if (a->adjoint) {
                a->sensitivity[j] += d * a->seed[i];
            } else {
                a->sensitivity[i] += d * a->seed[j];
            }
        }
    }
    for (size_t k = 0; k < n_out; k++) {
        if (!isfinite(a->sensitivity[k])) { /* finite J, a seed too large for it */
            FMU_LOG_ERROR(inst, "%s: sensitivity[%zu] = %g is not finite", function, k,
                          a->sensitivity[k]);
            return FMU_ERROR;
        }
    }
    return FMU_OK;
}
