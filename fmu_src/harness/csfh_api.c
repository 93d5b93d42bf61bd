/* The core library's ctypes API (csfh_api.h): a handle is the csfh FMU's model struct, whose
 * variables are addressed by their FMI names through the generated table; the physics and the
 * harness's solvers run on its member m. */
#include "csfh_api.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_constants.h"
#include "csfh_moreau_batch.h"
#include "csfh_variables.h"

int csfh_api_abi_version(void)
{
    return CSFH_CORE_ABI_VERSION; /* [abi] of variables.toml, as csfh.model.core expects */
}

size_t csfh_api_model_size(void)
{
    return sizeof(csfh_fmu_t);
}

csfh_fmu_t *csfh_api_new(void)
{
    csfh_fmu_t *model = (csfh_fmu_t *)malloc(sizeof(csfh_fmu_t));
    if (model != NULL) {
        csfh_fmu_set_defaults(model);
    }
    return model;
}

void csfh_api_free(csfh_fmu_t *model)
{
    free(model);
}

csfh_fmu_t *csfh_api_clone(const csfh_fmu_t *model)
{
    csfh_fmu_t *c = (csfh_fmu_t *)malloc(sizeof(csfh_fmu_t));
    if (c != NULL && model != NULL) {
        *c = *model;
    }
    return c;
}

int csfh_api_set(csfh_fmu_t *model, const char *name, double value, char *msg, size_t msg_size)
{
    const csfh_variable_t *v = csfh_fmu_variable(name);
    if (v == NULL || v->storage == CSFH_STORE_COMPUTED ||
        v->causality == CSFH_CAUS_CALCULATED_PARAMETER) {
        if (msg != NULL && msg_size > 0) {
            snprintf(msg, msg_size, "unknown or read-only variable \"%s\"", name ? name : "(null)");
        }
        return -2;
    }
    char local[256];
    if (csfh_check_value(v, value, msg != NULL ? msg : local, msg != NULL ? msg_size : sizeof(local)) != 0) {
        return -1;
    }
    if (v->type == CSFH_TYPE_REAL) {
        *csfh_fmu_real(model, v) = value;
    } else {
        *csfh_fmu_int(model, v) = (int)value;
    }
    return 0;
}

int csfh_api_get(csfh_fmu_t *model, const char *name, double *value)
{
    const csfh_variable_t *v = csfh_fmu_variable(name);
    if (v == NULL || value == NULL) {
        return -2;
    }
    if (v->storage == CSFH_STORE_COMPUTED) {
        csfh_fmu_outputs(model);
        csfh_model_derivatives(&model->m, model->m.time, model->m.x, model->der);
    }
    *value = v->type == CSFH_TYPE_REAL ? *csfh_fmu_real(model, v) : (double)*csfh_fmu_int(model, v);
    return 0;
}

int csfh_api_prepare(csfh_fmu_t *model, char *msg, size_t msg_size)
{
    char local[256];
    if (csfh_fmu_prepare(model, msg != NULL ? msg : local, msg != NULL ? msg_size : sizeof(local)) !=
        0) {
        return -1;
    }
    csfh_model_init_discrete(&model->m);
    return 0;
}

void csfh_api_set_state(csfh_fmu_t *model, const double x[6])
{
    memcpy(model->m.x, x, sizeof(model->m.x));
}

void csfh_api_get_state(const csfh_fmu_t *model, double x[6])
{
    memcpy(x, model->m.x, sizeof(model->m.x));
}

void csfh_api_set_inputs(csfh_fmu_t *model, const double u[3])
{
    memcpy(model->m.u_in, u, sizeof(model->m.u_in));
}

int csfh_api_derivatives(csfh_fmu_t *model, const double x[6], double xdot[6])
{
    return csfh_model_derivatives(&model->m, model->m.time, x, xdot);
}

void csfh_api_smooth_forces(csfh_fmu_t *model, const double q[3], double Q[3])
{
    csfh_model_smooth_forces(&model->m, model->m.time, q, Q);
}

double csfh_api_event_indicator(const csfh_fmu_t *model, const double x[6])
{
    return csfh_model_event_indicator(&model->m, x);
}

int csfh_api_event_update(csfh_fmu_t *model)
{
    return csfh_model_event_update(&model->m);
}

void csfh_api_counters(const csfh_fmu_t *model, long long out[5])
{
    out[0] = model->m.counters.rhs;
    out[1] = model->m.counters.flexure;
    out[2] = model->m.counters.contact;
    out[3] = model->m.counters.friction;
    out[4] = model->integrator_steps;
}

int csfh_api_moreau_run(csfh_fmu_t *model, double h, int stick_rule, double v_eps, double v_stick,
                        double g_tol, double t0, const double x0[6], long long n_steps,
                        long long record_every, double *records, size_t max_records,
                        double *impacts, size_t max_impacts, double x_end[6], long long stats[9])
{
    const csfh_moreau_options_t o = {h, stick_rule, v_eps, v_stick, g_tol};
    csfh_moreau_stats_t s;
    const int status = csfh_moreau_run(&model->m, &o, t0, x0, n_steps, record_every, records, max_records,
                                       impacts, max_impacts, x_end, &s);
    csfh_moreau_stats_array(&s, stats);
    return status;
}

int csfh_api_moreau_record_columns(void)
{
    return CSFH_MR_NCOLS;
}

int csfh_api_moreau_impact_columns(void)
{
    return CSFH_MI_NCOLS;
}

long long csfh_api_moreau_batch(csfh_fmu_t *const *handles, size_t n, double h, int stick_rule,
                                double v_eps, double v_stick, double g_tol, double t0,
                                const double *x0, long long n_steps, long long record_every,
                                double *records, size_t max_records, double *impacts,
                                size_t max_impacts, double *x_end, long long *stats, int *status)
{
    if (handles == NULL) {
        return -1;
    }
    csfh_model_t **models = (csfh_model_t **)malloc((n > 0 ? n : 1) * sizeof(csfh_model_t *));
    if (models == NULL) {
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        models[i] = handles[i] != NULL ? &handles[i]->m : NULL;
    }
    const long long failed =
        csfh_moreau_batch(models, n, h, stick_rule, v_eps, v_stick, g_tol, t0, x0, n_steps,
                          record_every, records, max_records, impacts, max_impacts, x_end, stats,
                          status);
    free(models);
    return failed;
}

int csfh_api_rk4_run(csfh_fmu_t *model, double h0, double tol, double h_min, double t0,
                     const double x0[6], double t_end, double dt_out, double *records,
                     size_t max_records, double *contacts, size_t max_contacts, double x_end[6],
                     long long stats[5])
{
    const csfh_rk4_options_t o = {h0, tol, h_min};
    csfh_rk4_stats_t s;
    const int status = csfh_rk4_event_run(&model->m, &o, t0, x0, t_end, dt_out, records, max_records,
                                          contacts, max_contacts, x_end, &s);
    stats[0] = s.steps;
    stats[1] = s.rejected_steps;
    stats[2] = s.rhs;
    stats[3] = (long long)s.records;
    stats[4] = (long long)s.contacts;
    return status;
}

int csfh_api_rk4_record_columns(void)
{
    return CSFH_RK4_RECORD_NCOLS;
}

int csfh_api_contact_record_columns(void)
{
    return CSFH_CR_NCOLS;
}
