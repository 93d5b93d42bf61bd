#include "csfh_api.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_variables.h"

#define CSFH_ABI_VERSION 2 /* 2: csfh_api_moreau_batch (csfh_moreau_batch.h) */

int csfh_api_abi_version(void)
{
    return CSFH_ABI_VERSION;
}

size_t csfh_api_model_size(void)
{
    return sizeof(csfh_model_t);
}

csfh_model_t *csfh_api_new(void)
{
    csfh_model_t *m = (csfh_model_t *)malloc(sizeof(csfh_model_t));
    if (m != NULL) {
        csfh_model_set_defaults(m);
    }
    return m;
}

void csfh_api_free(csfh_model_t *m)
{
    free(m);
}

csfh_model_t *csfh_api_clone(const csfh_model_t *m)
{
    csfh_model_t *c = (csfh_model_t *)malloc(sizeof(csfh_model_t));
    if (c != NULL && m != NULL) {
        *c = *m;
    }
    return c;
}

int csfh_api_variable_count(void)
{
    return CSFH_NUMBER_OF_VARIABLES;
}

const char *csfh_api_variable_name(int index)
{
    return index >= 0 && index < CSFH_NUMBER_OF_VARIABLES ? csfh_variables[index].name : NULL;
}

int csfh_api_variable_type(int index)
{
    return index >= 0 && index < CSFH_NUMBER_OF_VARIABLES ? (int)csfh_variables[index].type : -1;
}

int csfh_api_variable_causality(int index)
{
    return index >= 0 && index < CSFH_NUMBER_OF_VARIABLES ? (int)csfh_variables[index].causality
                                                          : -1;
}

int csfh_api_set(csfh_model_t *m, const char *name, double value, char *msg, size_t msg_size)
{
    const csfh_variable_t *v = csfh_variable_by_name(name);
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
        *csfh_variable_real(m, v) = value;
    } else {
        *csfh_variable_int(m, v) = (int)value;
    }
    return 0;
}

int csfh_api_get(csfh_model_t *m, const char *name, double *value)
{
    const csfh_variable_t *v = csfh_variable_by_name(name);
    if (v == NULL || value == NULL) {
        return -2;
    }
    if (v->storage == CSFH_STORE_COMPUTED) {
        csfh_model_outputs(m);
        csfh_model_derivatives(m, m->time, m->x, m->der);
    }
    *value = v->type == CSFH_TYPE_REAL ? *csfh_variable_real(m, v) : (double)*csfh_variable_int(m, v);
    return 0;
}

int csfh_api_prepare(csfh_model_t *m, char *msg, size_t msg_size)
{
    char local[256];
    if (csfh_model_prepare(m, msg != NULL ? msg : local, msg != NULL ? msg_size : sizeof(local)) != 0) {
        return -1;
    }
    csfh_model_init_discrete(m);
    return 0;
}

void csfh_api_set_state(csfh_model_t *m, const double x[6])
{
    memcpy(m->x, x, sizeof(m->x));
}

void csfh_api_get_state(const csfh_model_t *m, double x[6])
{
    memcpy(x, m->x, sizeof(m->x));
}

void csfh_api_set_inputs(csfh_model_t *m, const double u[3])
{
    memcpy(m->u_in, u, sizeof(m->u_in));
}

int csfh_api_derivatives(csfh_model_t *m, const double x[6], double xdot[6])
{
    return csfh_model_derivatives(m, m->time, x, xdot);
}

void csfh_api_smooth_forces(csfh_model_t *m, const double q[3], double Q[3])
{
    csfh_model_smooth_forces(m, m->time, q, Q);
}

double csfh_api_event_indicator(const csfh_model_t *m, const double x[6])
{
    return csfh_model_event_indicator(m, x);
}

int csfh_api_event_update(csfh_model_t *m)
{
    return csfh_model_event_update(m);
}

void csfh_api_counters(const csfh_model_t *m, long long out[5])
{
    out[0] = m->counters.rhs;
    out[1] = m->counters.flexure;
    out[2] = m->counters.contact;
    out[3] = m->counters.friction;
    out[4] = m->counters.steps;
}

int csfh_api_moreau_run(csfh_model_t *m, double h, int stick_rule, double v_eps, double v_stick,
                        double g_tol, double t0, const double x0[6], long long n_steps,
                        long long record_every, double *records, size_t max_records,
                        double *impacts, size_t max_impacts, double x_end[6], long long stats[9])
{
    const csfh_moreau_options_t o = {h, stick_rule, v_eps, v_stick, g_tol};
    csfh_moreau_stats_t s;
    const int status = csfh_moreau_run(m, &o, t0, x0, n_steps, record_every, records, max_records,
                                       impacts, max_impacts, x_end, &s);
    stats[0] = s.steps;
    stats[1] = s.active_steps;
    stats[2] = s.stick_steps;
    stats[3] = s.slip_steps;
    stats[4] = s.fallback_steps;
    stats[5] = s.onsets;
    stats[6] = (long long)s.records;
    stats[7] = (long long)s.impacts;
    stats[8] = s.impacts_dropped;
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

int csfh_api_rk4_run(csfh_model_t *m, double h0, double tol, double h_min, double t0,
                     const double x0[6], double t_end, double dt_out, double *records,
                     size_t max_records, double *contacts, size_t max_contacts, double x_end[6],
                     long long stats[5])
{
    const csfh_rk4_options_t o = {h0, tol, h_min};
    csfh_rk4_stats_t s;
    const int status = csfh_rk4_event_run(m, &o, t0, x0, t_end, dt_out, records, max_records,
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
