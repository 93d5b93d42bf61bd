#include "csfh_moreau.h"

#include <math.h>
#include <string.h>

#include "csfh_common.h"
#include "csfh_constants.h"
#include "csfh_flexure.h"

void csfh_moreau_default_options(csfh_moreau_options_t *o)
{
    /* the harness's defaults ([harness] of variables.toml) */
    o->h = CSFH_MOREAU_STEP;
    o->stick_rule = CSFH_STICK_PAPER;
    o->v_eps = CSFH_MOREAU_V_EPS;
    o->v_stick = CSFH_MOREAU_V_STICK;
    o->g_tol = CSFH_MOREAU_G_TOL;
}

/* Solve the one-contact problem for Lambda given G (2x2 SPD), c = gamma_free + [eps gamma_A,N, 0]
 * (docs/model.md §6.2, exact case enumeration). Returns the mode. */
static int solve_contact(const double G[2][2], const double c[2], double mu_stick, double fd,
                         double Lambda[2])
{
    Lambda[0] = Lambda[1] = 0.0;
    if (c[0] >= 0.0) {
        return CSFH_MOREAU_OPEN; /* 1. open */
    }
    /* 2. stick: Lambda = -G^-1 c */
    const double det = G[0][0] * G[1][1] - G[0][1] * G[1][0];
    if (det > 0.0) {
        const double LN = -(G[1][1] * c[0] - G[0][1] * c[1]) / det;
        const double LT = -(-G[1][0] * c[0] + G[0][0] * c[1]) / det;
        if (LN >= 0.0 && fabs(LT) <= mu_stick * LN) {
            Lambda[0] = LN;
            Lambda[1] = LT;
            return CSFH_MOREAU_STICK;
        }
    }
    /* 3. slip in direction sigma of xi_T */
    for (int k = 0; k < 2; k++) {
        const double sigma = k == 0 ? 1.0 : -1.0;
        const double denom = G[0][0] - sigma * fd * G[0][1];
        if (!(denom > 0.0)) {
            continue;
        }
        const double LN = -c[0] / denom;
        const double xi_T = (G[1][0] - sigma * fd * G[1][1]) * LN + c[1];
        if (LN >= 0.0 && sigma * xi_T > 0.0) {
            Lambda[0] = LN;
            Lambda[1] = -sigma * fd * LN;
            return CSFH_MOREAU_SLIP;
        }
    }
    /* without friction the slip branch has xi_T of either sign: frictionless impulse */
    Lambda[0] = -c[0] / G[0][0];
    Lambda[1] = 0.0;
    return fd == 0.0 ? CSFH_MOREAU_SLIP : CSFH_MOREAU_FALLBACK;
}

/* Steps 4-6 at a contact (the midpoint qM within g_tol of it): the local problem on the normal
 * and tangential velocities from the free velocity u_free, and the velocity uE after the
 * impulses. */
static void contact_impulses(csfh_model_t *m, const csfh_moreau_options_t *o,
                             csfh_moreau_memory_t *mem, const double qM[3], const double u[3],
                             const double u_free[3], const double Minv[3], double uE[3],
                             csfh_moreau_step_t *info)
{
    csfh_count(&m->counters.contact);
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, qM, &kin);
    const double *D[2] = {kin.DN, kin.DT};
    double G[2][2];
    for (int a = 0; a < 2; a++) {
        for (int b = 0; b < 2; b++) {
            G[a][b] = D[a][0] * Minv[0] * D[b][0] + D[a][1] * Minv[1] * D[b][1] +
                      D[a][2] * Minv[2] * D[b][2];
        }
    }
    double gamma_free[2];
    for (int a = 0; a < 2; a++) {
        info->gamma_A[a] = D[a][0] * u[0] + D[a][1] * u[1] + D[a][2] * u[2];
        gamma_free[a] = D[a][0] * u_free[0] + D[a][1] * u_free[1] + D[a][2] * u_free[2];
    }
    /* restitution only for a closing contact (6.1 step 4, 6.3) */
    info->restitution = info->gamma_A[0] < -o->v_eps;
    const double eps = info->restitution ? m->p.cr : 0.0;
    const double c[2] = {gamma_free[0] + eps * info->gamma_A[0], gamma_free[1]};
    if (m->p.friction_enabled) {
        csfh_count(&m->counters.friction);
    }
    const double fd = m->p.friction_enabled ? m->p.fd : 0.0;
    const double fa = m->p.friction_enabled ? m->p.fa : 0.0;
    double mu_stick = fa; /* paper-literal: f_a decides (6.4) */
    if (o->stick_rule == CSFH_STICK_MEMORY) {
        const int was_stuck = mem->sticking || fabs(info->gamma_A[1]) <= o->v_stick;
        mu_stick = was_stuck ? fa : fd;
    }
    double Lambda[2];
    info->mode = solve_contact(G, c, mu_stick, fd, Lambda);
    info->Lambda_N = Lambda[0];
    info->Lambda_T = Lambda[1];
    /* 6. velocity update */
    for (int i = 0; i < 3; i++) {
        uE[i] = u_free[i] + Minv[i] * (D[0][i] * Lambda[0] + D[1][i] * Lambda[1]);
    }
    for (int a = 0; a < 2; a++) {
        info->gamma_E[a] = D[a][0] * uE[0] + D[a][1] * uE[1] + D[a][2] * uE[2];
    }
    mem->sticking = info->mode == CSFH_MOREAU_STICK;
    mem->active = 1;
}

int csfh_moreau_step(csfh_model_t *m, const csfh_moreau_options_t *o, csfh_moreau_memory_t *mem,
                     double q[3], double u[3], csfh_moreau_step_t *info)
{
    const double h = o->h;
    const double Minv[3] = {1.0 / m->p.m1, 1.0 / m->p.m1, 1.0 / m->p.I1};
    memset(info, 0, sizeof(*info));

    /* 1. midpoint */
    double qM[3];
    for (int i = 0; i < 3; i++) {
        qM[i] = q[i] + 0.5 * h * u[i];
    }
    /* 2. smooth forces at the midpoint (gravity, flexure, inputs, the shock pulse at the
     * midpoint's time: the FMU's functions); m->time is the step's start */
    double Q[3], u_free[3];
    csfh_model_smooth_forces(m, m->time + 0.5 * h, qM, Q);
    for (int i = 0; i < 3; i++) {
        u_free[i] = u[i] + h * Minv[i] * Q[i];
    }
    /* 3. contact detection at the midpoint */
    info->gap_M = csfh_contact_gap(m->d.delta, m->p.s1bar, qM);
    double uE[3] = {u_free[0], u_free[1], u_free[2]};
    if (info->gap_M > o->g_tol) {
        info->mode = CSFH_MOREAU_FREE;
        mem->sticking = 0;
        mem->active = 0;
    } else {
        contact_impulses(m, o, mem, qM, u, u_free, Minv, uE, info); /* 4.-6. */
    }
    /* 7. second half drift */
    for (int i = 0; i < 3; i++) {
        u[i] = uE[i];
        q[i] = qM[i] + 0.5 * h * uE[i];
    }
    for (int i = 0; i < 3; i++) {
        if (!isfinite(q[i]) || !isfinite(u[i])) {
            return CSFH_ERR_NONFINITE;
        }
    }
    return CSFH_OK;
}

static double energy(csfh_model_t *m, const double q[3], const double u[3])
{
    double E = 0.5 * m->p.m1 * (u[0] * u[0] + u[1] * u[1]) + 0.5 * m->p.I1 * u[2] * u[2] +
               m->p.m1 * m->p.g * q[1];
    if (m->p.flexure_enabled) {
        double Qe[3];
        E += csfh_flexure_force(&m->d.flexure, q, Qe);
    }
    return E;
}

static void write_record(csfh_model_t *m, double t, const double q[3], const double u[3],
                         const double acc[5], double *row)
{
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, q, &kin);
    row[CSFH_MR_T] = t;
    for (int i = 0; i < 3; i++) {
        row[CSFH_MR_X + i] = q[i];
        row[CSFH_MR_VX + i] = u[i];
    }
    row[CSFH_MR_F_N] = acc[0];
    row[CSFH_MR_F_T] = acc[1];
    row[CSFH_MR_LAMBDA_N] = acc[2];
    row[CSFH_MR_LAMBDA_T] = acc[3];
    row[CSFH_MR_MODE] = acc[4];
    row[CSFH_MR_GAP] = kin.gap;
    row[CSFH_MR_INDENTATION] = kin.gap < 0.0 ? -kin.gap : 0.0;
    row[CSFH_MR_V_T] = kin.DT[0] * u[0] + kin.DT[1] * u[1] + kin.DT[2] * u[2];
    row[CSFH_MR_ENERGY] = energy(m, q, u);
}

/* The step's counts: its mode, and at an onset (a contact after a step without) its impact
 * record at t (u: the velocity after it). */
static void count_step(csfh_moreau_stats_t *stats, const csfh_moreau_step_t *info, int was_active,
                       double t, const double u[3], double *impacts, size_t max_impacts)
{
    if (info->mode == CSFH_MOREAU_FREE) {
        return;
    }
    stats->active_steps++;
    stats->stick_steps += info->mode == CSFH_MOREAU_STICK;
    stats->slip_steps += info->mode == CSFH_MOREAU_SLIP;
    stats->fallback_steps += info->mode == CSFH_MOREAU_FALLBACK;
    if (was_active) {
        return;
    }
    stats->onsets++;
    if (impacts == NULL || stats->impacts >= max_impacts) {
        stats->impacts_dropped++;
        return;
    }
    double *row = impacts + stats->impacts * CSFH_MI_NCOLS;
    row[CSFH_MI_T] = t;
    row[CSFH_MI_GAMMA_N_A] = info->gamma_A[0];
    row[CSFH_MI_GAMMA_T_A] = info->gamma_A[1];
    row[CSFH_MI_GAMMA_N_E] = info->gamma_E[0];
    row[CSFH_MI_GAMMA_T_E] = info->gamma_E[1];
    row[CSFH_MI_LAMBDA_N] = info->Lambda_N;
    row[CSFH_MI_LAMBDA_T] = info->Lambda_T;
    row[CSFH_MI_MODE] = info->mode;
    row[CSFH_MI_RESTITUTION] = info->restitution;
    row[CSFH_MI_OMEGA_E] = u[2];
    stats->impacts++;
}

/* The step's impulses into what the next record reports: the peak F_N with its F_T and mode,
 * the sums of the impulses. */
static void accumulate(double acc[5], const csfh_moreau_step_t *info, double h)
{
    const double F_N = info->Lambda_N / h;
    if (F_N > acc[0] || (acc[0] == 0.0 && info->mode != CSFH_MOREAU_FREE && acc[4] == 0.0)) {
        acc[0] = F_N;
        acc[1] = info->Lambda_T / h;
        acc[4] = info->mode;
    }
    acc[2] += info->Lambda_N;
    acc[3] += info->Lambda_T;
}

void csfh_moreau_stats_array(const csfh_moreau_stats_t *s, long long out[CSFH_MOREAU_NSTATS])
{
    out[0] = s->steps;
    out[1] = s->active_steps;
    out[2] = s->stick_steps;
    out[3] = s->slip_steps;
    out[4] = s->fallback_steps;
    out[5] = s->onsets;
    out[6] = (long long)s->records;
    out[7] = (long long)s->impacts;
    out[8] = s->impacts_dropped;
}

int csfh_moreau_run(csfh_model_t *m, const csfh_moreau_options_t *o, double t0, const double x0[6],
                    long long n_steps, long long record_every, double *records, size_t max_records,
                    double *impacts, size_t max_impacts, double x_end[6],
                    csfh_moreau_stats_t *stats)
{
    memset(stats, 0, sizeof(*stats));
    double q[3] = {x0[0], x0[1], x0[2]}, u[3] = {x0[3], x0[4], x0[5]};
    csfh_moreau_memory_t mem = {0, 0};
    double acc[5] = {0.0, 0.0, 0.0, 0.0, 0.0}; /* peak F_N, its F_T, sum Lambda_N, T, mode */
    if (record_every < 1) {
        record_every = 1;
    }
    if (records != NULL && max_records > 0) {
        write_record(m, t0, q, u, acc, records);
        stats->records = 1;
    }
    int status = CSFH_OK;
    long long k;
    for (k = 0; k < n_steps; k++) {
        const double t = t0 + (double)k * o->h;
        const int was_active = mem.active;
        csfh_moreau_step_t info;
        m->time = t; /* the step's start (the shock pulse is evaluated at its midpoint) */
        status = csfh_moreau_step(m, o, &mem, q, u, &info);
        stats->steps++;
        count_step(stats, &info, was_active, t, u, impacts, max_impacts);
        accumulate(acc, &info, o->h);
        if (status != CSFH_OK) {
            k++;
            break;
        }
        if ((k + 1) % record_every == 0 && records != NULL && stats->records < max_records) {
            write_record(m, t0 + (double)(k + 1) * o->h, q, u, acc,
                         records + stats->records * CSFH_MR_NCOLS);
            stats->records++;
            acc[0] = acc[1] = acc[2] = acc[3] = acc[4] = 0.0;
        }
    }
    x_end[0] = q[0];
    x_end[1] = q[1];
    x_end[2] = q[2];
    x_end[3] = u[0];
    x_end[4] = u[1];
    x_end[5] = u[2];
    m->time = t0 + (double)k * o->h;
    return status;
}
