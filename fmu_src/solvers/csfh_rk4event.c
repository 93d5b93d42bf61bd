#include "csfh_rk4event.h"

#include <math.h>
#include <string.h>

#include "csfh_contact.h"

/* Classical RK4 step with the model's right-hand side (current discrete state), the contact force
 * by the gap (the paper's scheme: the force acts as soon as the gap is negative). */
static int rk4_step(csfh_model_t *m, double t, const double x[6], double h, double xn[6])
{
    double k1[6], k2[6], k3[6], k4[6], y[6];
    int status = csfh_model_derivatives_by_gap(m, t, x, k1);
    for (int i = 0; i < 6; i++) {
        y[i] = x[i] + 0.5 * h * k1[i];
    }
    status |= csfh_model_derivatives_by_gap(m, t + 0.5 * h, y, k2);
    for (int i = 0; i < 6; i++) {
        y[i] = x[i] + 0.5 * h * k2[i];
    }
    status |= csfh_model_derivatives_by_gap(m, t + 0.5 * h, y, k3);
    for (int i = 0; i < 6; i++) {
        y[i] = x[i] + h * k3[i];
    }
    status |= csfh_model_derivatives_by_gap(m, t + h, y, k4);
    for (int i = 0; i < 6; i++) {
        xn[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        if (!isfinite(xn[i])) {
            return CSFH_ERR_NONFINITE;
        }
    }
    return status < 0 ? CSFH_ERR_NONFINITE : CSFH_OK;
}

static void write_record(csfh_model_t *m, double t, const double x[6], double *row)
{
    memcpy(m->x, x, 6 * sizeof(double));
    csfh_outputs_t out;
    csfh_model_outputs_by_gap(m, &out);
    row[0] = t;
    for (int i = 0; i < 6; i++) {
        row[1 + i] = x[i];
    }
    row[7] = out.F_N;
    row[8] = out.F_T;
    row[9] = out.indentation;
    row[10] = out.v_T;
    row[11] = out.gap;
    row[12] = out.E_total;
}

/* Where the contacts of a run go (CSFH_CR_NCOLS values each), and the one being filled. */
typedef struct {
    double *rows;
    size_t max;
    double *current; /* NULL: none, or no room for it */
} contacts_t;

/* A new contact record at t with the onset rate: its row, or NULL when there is no room. */
static double *contact_begins(contacts_t *c, csfh_rk4_stats_t *stats, double t,
                              double onset_speed)
{
    if (c->rows == NULL || stats->contacts >= c->max) {
        return NULL;
    }
    double *row = c->rows + stats->contacts * CSFH_CR_NCOLS;
    row[CSFH_CR_T_ONSET] = t;
    row[CSFH_CR_ONSET_SPEED] = onset_speed;
    row[CSFH_CR_T_RELEASE] = row[CSFH_CR_RELEASE_SPEED] = NAN;
    row[CSFH_CR_PEAK_F_N] = row[CSFH_CR_MAX_INDENTATION] = 0.0;
    stats->contacts++;
    return row;
}

/* The contact mode after an accepted step to (t, x) with the gap there: the onset (its
 * indentation rate captured) where the gap has closed, the release where it has opened (back
 * to the nominal step, *h = h0); in contact, the record's peak force and indentation. */
static void contact_events(csfh_model_t *m, const csfh_rk4_options_t *o, contacts_t *c,
                           csfh_rk4_stats_t *stats, double gap, double t, const double x[6],
                           double *h)
{
    if (m->p.law != CSFH_CONTACTLAW_NONE && !m->z.in_contact && gap <= 0.0) {
        csfh_model_event_update(m); /* onset: the indentation rate is captured */
        c->current = contact_begins(c, stats, t, m->z.onset_speed);
    } else if (m->z.in_contact && gap > 0.0) {
        m->z.in_contact = 0; /* release; back to the nominal step */
        *h = o->h0;
        if (c->current != NULL) {
            csfh_contact_kin_t kin;
            csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, x, &kin);
            c->current[CSFH_CR_T_RELEASE] = t;
            c->current[CSFH_CR_RELEASE_SPEED] =
                kin.DN[0] * x[3] + kin.DN[1] * x[4] + kin.DN[2] * x[5];
            c->current = NULL;
        }
        m->z.release_time = t;
    }
    if (m->z.in_contact && c->current != NULL) {
        csfh_contact_eval_t e;
        csfh_model_contact_by_gap(m, x, x + 3, &e);
        c->current[CSFH_CR_PEAK_F_N] = fmax(c->current[CSFH_CR_PEAK_F_N], e.F_N);
        c->current[CSFH_CR_MAX_INDENTATION] = fmax(c->current[CSFH_CR_MAX_INDENTATION], e.rho);
    }
}

/* The output times t0 + k dt_out and where their records go. */
typedef struct {
    double t0, dt_out, next;
    long long k;
    double *rows;
    size_t max;
} outputs_t;

/* A record at the first accepted step at or after each output time (the scheme has no dense
 * output). */
static void output_if_due(csfh_model_t *m, outputs_t *out, csfh_rk4_stats_t *stats, double t,
                          const double x[6])
{
    if (!(t >= out->next - 1e-12 * fabs(out->next))) {
        return;
    }
    if (out->rows != NULL && stats->records < out->max) {
        write_record(m, t, x, out->rows + stats->records * CSFH_RK4_RECORD_NCOLS);
        stats->records++;
    }
    while (out->next <= t + 1e-12 * fabs(t)) {
        out->next = out->t0 + (double)(++out->k) * out->dt_out;
    }
}

int csfh_rk4_event_run(csfh_model_t *m, const csfh_rk4_options_t *o, double t0,
                       const double x0[6], double t_end, double dt_out, double *records,
                       size_t max_records, double *contacts, size_t max_contacts, double x_end[6],
                       csfh_rk4_stats_t *stats)
{
    memset(stats, 0, sizeof(*stats));
    const int rhs_before = m->counters.rhs;
    double x[6], xn[6];
    memcpy(x, x0, sizeof(x));
    memcpy(m->x, x0, sizeof(x));
    m->time = t0;
    csfh_model_init_discrete(m);
    contacts_t c = {contacts, max_contacts, NULL};
    if (m->z.in_contact) {
        c.current = contact_begins(&c, stats, t0, m->z.onset_speed);
    }
    if (records != NULL && max_records > 0) {
        write_record(m, t0, x, records);
        stats->records = 1;
    }
    outputs_t out = {t0, dt_out, t0 + dt_out, 1, records, max_records};
    double t = t0, h = o->h0;
    int status = CSFH_OK;
    while (t < t_end - 1e-12 * fabs(t_end)) {
        const double h_try = fmin(h, t_end - t);
        status = rk4_step(m, t, x, h_try, xn);
        if (status != CSFH_OK) {
            break;
        }
        const double gap = csfh_contact_gap(m->d.delta, m->p.s1bar, xn);
        if (m->p.law != CSFH_CONTACTLAW_NONE && !m->z.in_contact && gap < -o->tol &&
            h_try > o->h_min) {
            h = 0.5 * h_try; /* bisection toward the event (paper, Fig. 3) */
            stats->rejected_steps++;
            continue;
        }
        t += h_try;
        memcpy(x, xn, sizeof(x));
        memcpy(m->x, x, sizeof(x));
        m->time = t;
        stats->steps++;
        contact_events(m, o, &c, stats, gap, t, x, &h);
        output_if_due(m, &out, stats, t, x);
    }
    memcpy(x_end, x, sizeof(x));
    stats->rhs = m->counters.rhs - rhs_before;
    return status;
}
