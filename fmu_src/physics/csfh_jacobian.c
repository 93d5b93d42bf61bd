#include "csfh_jacobian.h"

#include <math.h>
#include <string.h>

#include "csfh_common.h"
#include "csfh_friction.h"

/* The flexure's kinematics at q (docs/model.md §2.4, Eq. (5) with r0 = 0, theta0 = 0): the arm
 * s = A(theta) sbar, dp and D[i][j] = d dp_i / d q_j. */
typedef struct {
    double c, s, sx, sy, dp[3], D[3][3];
} flexure_kin_t;

static void flexure_kin(const csfh_flexure_t *flex, const double q[3], flexure_kin_t *k)
{
    k->c = cos(q[2]);
    k->s = sin(q[2]);
    k->sx = k->c * flex->sbar[0] - k->s * flex->sbar[1];
    k->sy = k->s * flex->sbar[0] + k->c * flex->sbar[1];
    k->dp[0] = q[0] + k->sx - flex->sbar[0];
    k->dp[1] = q[1] + k->sy - flex->sbar[1];
    k->dp[2] = q[2];
    const double D[3][3] = {{1.0, 0.0, -k->sy}, {0.0, 1.0, k->sx}, {0.0, 0.0, 1.0}};
    memcpy(k->D, D, sizeof(D));
}

static void mat3_times(const double K[3][3], const double v[3], double out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = K[i][0] * v[0] + K[i][1] * v[1] + K[i][2] * v[2];
    }
}

/* The tip wrench w (global) and wr (the reference frame of csfh_flexure_tip_wrench), with
 * dw[i][j] = d w_i / d q_j and dwr likewise. Co-rotated: w = blk(A) K0 blk(A)^T dp, and
 * d A / d theta v = rot90(A v), d A^T / d theta v = -A^T rot90(v) (docs/model.md §2.5). */
static void flexure_wrench_jacobian(const csfh_flexure_t *flex, const flexure_kin_t *k,
                                    double w[3], double dw[3][3], double wr[3], double dwr[3][3])
{
    if (flex->conservative) {
        mat3_times(flex->K0, k->dp, w);
        for (int j = 0; j < 3; j++) {
            const double col[3] = {k->D[0][j], k->D[1][j], k->D[2][j]};
            double dcol[3];
            mat3_times(flex->K0, col, dcol);
            for (int i = 0; i < 3; i++) {
                dw[i][j] = dwr[i][j] = dcol[i];
            }
        }
        memcpy(wr, w, 3 * sizeof(double));
        return;
    }
    const double c = k->c, s = k->s;
    const double db[3] = {c * k->dp[0] + s * k->dp[1], -s * k->dp[0] + c * k->dp[1], k->dp[2]};
    mat3_times(flex->K0, db, wr);
    w[0] = c * wr[0] - s * wr[1];
    w[1] = s * wr[0] + c * wr[1];
    w[2] = wr[2];
    for (int j = 0; j < 3; j++) {
        double ddb[3] = {c * k->D[0][j] + s * k->D[1][j], -s * k->D[0][j] + c * k->D[1][j],
                         k->D[2][j]};
        if (j == 2) {
            ddb[0] += db[1];
            ddb[1] -= db[0];
        }
        double dwb[3];
        mat3_times(flex->K0, ddb, dwb);
        for (int i = 0; i < 3; i++) {
            dwr[i][j] = dwb[i];
        }
        dw[0][j] = c * dwb[0] - s * dwb[1] - (j == 2 ? w[1] : 0.0);
        dw[1][j] = s * dwb[0] + c * dwb[1] + (j == 2 ? w[0] : 0.0);
        dw[2][j] = dwb[2];
    }
}

void csfh_flexure_force_jacobian(const csfh_flexure_t *flex, const double q[3], double dQ[3][3],
                                 double dE[3])
{
    flexure_kin_t k;
    flexure_kin(flex, q, &k);
    double w[3], dw[3][3], wr[3], dwr[3][3];
    flexure_wrench_jacobian(flex, &k, w, dw, wr, dwr);
    for (int j = 0; j < 3; j++) {
        /* Q_e = -[w_x, w_y, s x w_F + w_M] (Eq. 9), d s / d theta = rot90(s) */
        const double dsx = j == 2 ? -k.sy : 0.0, dsy = j == 2 ? k.sx : 0.0;
        dQ[0][j] = -dw[0][j];
        dQ[1][j] = -dw[1][j];
        dQ[2][j] = -(dsx * w[1] + k.sx * dw[1][j] - dsy * w[0] - k.sy * dw[0][j] + dw[2][j]);
        if (dE != NULL) { /* E = dp . w / 2 */
            dE[j] = 0.5 * (k.D[0][j] * w[0] + k.D[1][j] * w[1] + k.D[2][j] * w[2] +
                           k.dp[0] * dw[0][j] + k.dp[1] * dw[1][j] + k.dp[2] * dw[2][j]);
        }
    }
}

void csfh_contact_kinematics_jacobian(double R1, const csfh_contact_kin_t *kin,
                                      csfh_contact_kin_jac_t *jac)
{
    memset(jac, 0, sizeof(*jac));
    const double en = kin->e_norm;
    if (!(en > 1e-300)) {
        return;
    }
    /* s1 = a + R1 n_c; e = r + s1, d e / d q = [I, rot90(s1)]; d n_c = -t_c (t_c . de) / |e|,
     * d t_c = rot90(d n_c) = n_c (t_c . de) / |e| (docs/model.md §3) */
    const double s1[2] = {kin->a[0] + R1 * kin->n[0], kin->a[1] + R1 * kin->n[1]};
    const double de[2][3] = {{1.0, 0.0, -s1[1]}, {0.0, 1.0, s1[0]}};
    for (int j = 0; j < 3; j++) {
        const double tde = (kin->t[0] * de[0][j] + kin->t[1] * de[1][j]) / en;
        const double dn[2] = {-kin->t[0] * tde, -kin->t[1] * tde};
        const double dt[2] = {kin->n[0] * tde, kin->n[1] * tde};
        /* a = s1 - R1 n_c */
        const double da[2] = {(j == 2 ? -s1[1] : 0.0) - R1 * dn[0],
                              (j == 2 ? s1[0] : 0.0) - R1 * dn[1]};
        for (int i = 0; i < 2; i++) {
            jac->dn[i][j] = jac->dDN[i][j] = dn[i];
            jac->dt[i][j] = jac->dDT[i][j] = dt[i];
        }
        jac->dDN[2][j] = csfh_cross2(da, kin->n) + csfh_cross2(kin->a, dn);
        jac->dDT[2][j] = csfh_cross2(da, kin->t) + csfh_cross2(kin->a, dt);
    }
}

/* dF/drho of LN_ESDU reading I3, F_el = K_t(F(rho)) rho^n with K_t = 1/(a ln(F* / F)): d K_t / dF =
 * a K_t^2 / F and dF/drho = K_t (docs/model.md §4.6, §15.3). */
static double esdu_i3_stiffness(const csfh_normal_law_t *law, double rho)
{
    double F;
    const int status = csfh_esdu_force(&law->esdu, rho, &F);
    const int live = status == CSFH_LAW_OK && F > 0.0;
    const double K_t = csfh_esdu_tangent_stiffness(&law->esdu, live ? F : 0.5 * law->esdu.F_max);
    const double rn = csfh_pow_n(rho, law->n);
    const double dK = live ? law->esdu.a * K_t * K_t * K_t / F : 0.0;
    return dK * rn + K_t * law->n * rn / rho;
}

double csfh_normal_elastic_stiffness(const csfh_normal_law_t *law, double rho)
{
    if (!(rho > 0.0) || law->law == CSFH_CONTACTLAW_NONE) {
        return 0.0;
    }
    if (law->law != CSFH_CONTACTLAW_LN_ESDU) {
        return law->K * law->n * csfh_pow_n(rho, law->n) / rho; /* Eq. (13) */
    }
    if (law->esdu_reading != CSFH_ESDUREADING_I2) {
        return esdu_i3_stiffness(law, rho);
    }
    /* I2: rho(F) of Eq. (18) has d rho / dF = a ln(F* / F), so dF/drho = 1/(a ln(F* / F)) by the
     * implicit-function theorem; F held at F* beyond the validity range */
    double F;
    if (csfh_esdu_force(&law->esdu, rho, &F) != CSFH_LAW_OK || !(F > 0.0)) {
        return 0.0;
    }
    return csfh_esdu_tangent_stiffness(&law->esdu, F);
}

void csfh_normal_force_partials(const csfh_normal_law_t *law, double rho, double rho_dot,
                                double rho_dot_onset, double *dF_drho, double *dF_drhodot)
{
    *dF_drho = *dF_drhodot = 0.0;
    if (!(rho > 0.0) || law->law == CSFH_CONTACTLAW_NONE) {
        return;
    }
    double F_el;
    csfh_normal_elastic_force(law, rho, &F_el);
    const double onset = rho_dot_onset > law->v_min ? rho_dot_onset : law->v_min; /* 5.2 */
    const double factor = 1.0 + law->xi * rho_dot / onset;
    if (!(F_el * factor > 0.0)) {
        return; /* no adhesion: F_N = 0 here */
    }
    *dF_drho = csfh_normal_elastic_stiffness(law, rho) * factor;
    *dF_drhodot = F_el * law->xi / onset;
}

void csfh_ambrosio_partials(double fd, double v0, double v1, double F_N, double v_T,
                            double *dF_dFN, double *dF_dvT)
{
    const double v = fabs(v_T);
    const double cd = csfh_ambrosio_cd(v, v0, v1);
    *dF_dFN = *dF_dvT = 0.0;
    if (cd == 0.0) {
        return;
    }
    /* F_T = -sgn(v_T) f_d c_d(|v_T|) F_N, c_d' = 1/(v1 - v0) on the ramp (docs/model.md §5.1) */
    *dF_dFN = (v_T > 0.0 ? -1.0 : 1.0) * fd * cd;
    if (v > v0 && v < v1) {
        *dF_dvT = -fd * F_N / (v1 - v0);
    }
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The contact force's derivatives where the bodies touch (cp->touching), by the chain rule
 * through rho = -g (d rho / d q = -DN), rho_dot = -DN u and v_T = DT u. */
static void touching_partials(const csfh_model_t *m, const csfh_contact_kin_t *kin,
                              const csfh_contact_kin_jac_t *kj, csfh_contact_partials_t *cp)
{
    const double rho = -kin->gap;
    const double onset = m->z.onset_speed;
    csfh_normal_force(&m->d.normal, rho, cp->rho_dot, onset, &cp->F_N);
    csfh_normal_elastic_force(&m->d.normal, rho, &cp->F_el);
    double dF_drho, dF_drd;
    csfh_normal_force_partials(&m->d.normal, rho, cp->rho_dot, onset, &dF_drho, &dF_drd);
    for (int j = 0; j < 6; j++) {
        cp->dF_N[j] = -dF_drho * cp->dgap[j] + dF_drd * cp->drho_dot[j];
    }
    double dT_dFN = 0.0, dT_dvT = 0.0;
    if (m->p.friction_enabled && cp->F_N > 0.0) {
        cp->F_T = csfh_ambrosio_force(m->p.fd, m->p.v0, m->p.v1, cp->F_N, cp->v_T);
        csfh_ambrosio_partials(m->p.fd, m->p.v0, m->p.v1, cp->F_N, cp->v_T, &dT_dFN, &dT_dvT);
    }
    for (int j = 0; j < 6; j++) {
        cp->dF_T[j] = dT_dFN * cp->dF_N[j] + dT_dvT * cp->dv_T[j];
    }
    for (int i = 0; i < 3; i++) {
        cp->Q[i] = kin->DN[i] * cp->F_N + kin->DT[i] * cp->F_T;
        for (int j = 0; j < 6; j++) {
            const double geo = j < 3 ? kj->dDN[i][j] * cp->F_N + kj->dDT[i][j] * cp->F_T : 0.0;
            cp->dQ[i][j] = geo + kin->DN[i] * cp->dF_N[j] + kin->DT[i] * cp->dF_T[j];
        }
    }
}

void csfh_model_contact_partials(const csfh_model_t *m, const double x[6],
                                 csfh_contact_partials_t *cp)
{
    memset(cp, 0, sizeof(*cp));
    csfh_contact_kin_t kin;
    csfh_contact_kin_jac_t kj;
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, x, &kin);
    csfh_contact_kinematics_jacobian(m->p.R1, &kin, &kj);
    const double *u = x + 3;
    cp->gap = kin.gap;
    cp->rho_dot = -dot3(kin.DN, u);
    cp->v_T = dot3(kin.DT, u);
    for (int j = 0; j < 3; j++) {
        cp->dgap[j] = kin.DN[j]; /* g = delta - |e|, d|e| = -n_c . de */
        cp->drho_dot[j] = -(kj.dDN[0][j] * u[0] + kj.dDN[1][j] * u[1] + kj.dDN[2][j] * u[2]);
        cp->dv_T[j] = kj.dDT[0][j] * u[0] + kj.dDT[1][j] * u[1] + kj.dDT[2][j] * u[2];
        cp->drho_dot[3 + j] = -kin.DN[j];
        cp->dv_T[3 + j] = kin.DT[j];
    }
    /* the force acts in the contact mode where the gap is negative (csfh_model_contact) */
    if (m->p.law == CSFH_CONTACTLAW_NONE || !m->z.in_contact || !(kin.gap < 0.0)) {
        return;
    }
    cp->touching = 1;
    touching_partials(m, &kin, &kj, cp);
}

int csfh_model_rhs_jacobian(const csfh_model_t *m, const double x[6], double A[6][6],
                            double B[6][CSFH_N_JAC_INPUTS])
{
    memset(A, 0, 36 * sizeof(double));
    memset(B, 0, 6 * CSFH_N_JAC_INPUTS * sizeof(double));
    double dQ[3][6] = {{0.0}};
    if (m->p.flexure_enabled) {
        double dQe[3][3];
        csfh_flexure_force_jacobian(&m->d.flexure, x, dQe, NULL);
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                dQ[i][j] = dQe[i][j];
            }
        }
    }
    csfh_contact_partials_t cp;
    csfh_model_contact_partials(m, x, &cp);
    if (cp.touching) {
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 6; j++) {
                dQ[i][j] += cp.dQ[i][j];
            }
        }
    }
    const double mass[3] = {m->p.m1, m->p.m1, m->p.I1};
    for (int i = 0; i < 3; i++) {
        A[i][3 + i] = 1.0; /* q' = u */
        for (int j = 0; j < 6; j++) {
            A[3 + i][j] = dQ[i][j] / mass[i];
        }
        B[3 + i][i] = 1.0 / mass[i]; /* Q_ext, Eq. (0.4) */
    }
    /* the d'Alembert force -m1 a_base of Eq. (14.1) */
    B[3][3] = B[4][4] = -1.0;
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            if (!isfinite(A[i][j])) {
                return CSFH_ERR_NONFINITE;
            }
        }
    }
    return CSFH_OK;
}

/* One candidate section of csfh_arc_stress_max: its axial force N and arc angle alpha, with
 * their gradients with respect to the tip wrench w. */
typedef struct {
    double N, alpha, dN[3], dalpha[3];
} stress_candidate_t;

/* The sections where N = +-|F| inside the arc (csfh_arc_stress_max's middle candidates, in its
 * order) appended to cand; returns their count. */
static int extreme_candidates(const csfh_arc_section_t *sec, double Fn, double Ft,
                              const double dFn[3], const double dFt[3], stress_candidate_t *cand)
{
    const double F = sqrt(Fn * Fn + Ft * Ft);
    if (!(F > 0.0)) {
        return 0;
    }
    double a_max = atan2(-Ft, Fn);
    a_max = a_max < 0.0 ? a_max + 2.0 * CSFH_PI : a_max;
    const double a_min = a_max < CSFH_PI ? a_max + CSFH_PI : a_max - CSFH_PI;
    const double a_sorted[2] = {a_max > a_min ? a_max : a_min, a_max > a_min ? a_min : a_max};
    int n = 0;
    for (int s = 0; s < 2; s++) {
        if (a_sorted[s] > 0.0 && a_sorted[s] < sec->beta) {
            const double sign = a_sorted[s] == a_max ? 1.0 : -1.0;
            cand[n] = (stress_candidate_t){sign * F, a_sorted[s], {0}, {0}};
            for (int k = 0; k < 3; k++) {
                cand[n].dN[k] = sign * (Fn * dFn[k] + Ft * dFt[k]) / F;
                cand[n].dalpha[k] = (Ft * dFn[k] - Fn * dFt[k]) / (F * F);
            }
            n++;
        }
    }
    return n;
}

/* The gradient of csfh_arc_stress_max with respect to w at the section it selects (the same
 * candidates in the same order, docs/model.md §14.2): dsigma and dloc (location = beta - alpha). */
static void arc_stress_gradient(const csfh_arc_section_t *sec, const double w[3],
                                double dsigma[3], double dloc[3])
{
    const double cp = sec->cos_psi, sp = sec->sin_psi;
    const double Fn = cp * w[0] + sp * w[1], Ft = -sp * w[0] + cp * w[1];
    const double dFn[3] = {cp, sp, 0.0}, dFt[3] = {-sp, cp, 0.0};
    const double M0 = w[2] + sec->rho * Fn, dM0[3] = {sec->rho * cp, sec->rho * sp, 1.0};
    stress_candidate_t cand[4];
    int n = 0;
    cand[n] = (stress_candidate_t){sec->cos_beta * Fn - sec->sin_beta * Ft, sec->beta, {0}, {0}};
    for (int k = 0; k < 3; k++) {
        cand[n].dN[k] = sec->cos_beta * dFn[k] - sec->sin_beta * dFt[k];
    }
    n++;
    n += extreme_candidates(sec, Fn, Ft, dFn, dFt, cand + n);
    cand[n++] = (stress_candidate_t){Fn, 0.0, {dFn[0], dFn[1], dFn[2]}, {0}};
    double best = -1.0;
    for (int i = 0; i < n; i++) {
        const double mb = M0 - sec->rho * cand[i].N;
        const double sigma = fabs(cand[i].N) / sec->area + fabs(mb) / sec->section_modulus;
        if (sigma > best) {
            best = sigma;
            const double sn = cand[i].N < 0.0 ? -1.0 : 1.0, sm = mb < 0.0 ? -1.0 : 1.0;
            for (int k = 0; k < 3; k++) {
                dsigma[k] = sn * cand[i].dN[k] / sec->area +
                            sm * (dM0[k] - sec->rho * cand[i].dN[k]) / sec->section_modulus;
                dloc[k] = -cand[i].dalpha[k];
            }
        }
    }
}

/* d stress_max / d q and d stress_location / d q (0 with the flexure off). */
static void stress_jacobian(const csfh_model_t *m, const double q[3], double ds[3], double dl[3])
{
    for (int j = 0; j < 3; j++) {
        ds[j] = dl[j] = 0.0;
    }
    if (!m->p.flexure_enabled) {
        return;
    }
    flexure_kin_t k;
    flexure_kin(&m->d.flexure, q, &k);
    double w[3], dw[3][3], wr[3], dwr[3][3], gs[3], gl[3];
    flexure_wrench_jacobian(&m->d.flexure, &k, w, dw, wr, dwr);
    arc_stress_gradient(&m->d.arc, wr, gs, gl);
    for (int j = 0; j < 3; j++) {
        for (int i = 0; i < 3; i++) {
            ds[j] += gs[i] * dwr[i][j];
            dl[j] += gl[i] * dwr[i][j];
        }
    }
}

/* The energies' gradients (docs/model.md §12): kinetic, gravity, flexure, contact. */
static void energy_jacobian(const csfh_model_t *m, const double x[6],
                            const csfh_contact_partials_t *cp, double D[CSFH_N_JOUT][6])
{
    for (int i = 0; i < 3; i++) {
        D[CSFH_JOUT_E_KINETIC][3 + i] = (i < 2 ? m->p.m1 : m->p.I1) * x[3 + i];
    }
    D[CSFH_JOUT_E_GRAVITY][1] = m->p.m1 * m->p.g;
    if (m->p.flexure_enabled) {
        double dQe[3][3];
        csfh_flexure_force_jacobian(&m->d.flexure, x, dQe, D[CSFH_JOUT_E_FLEXURE]);
    }
    for (int j = 0; j < 6; j++) {
        /* dU/drho = F_el, rho = -g */
        D[CSFH_JOUT_E_CONTACT][j] = cp->touching ? -cp->F_el * cp->dgap[j] : 0.0;
        D[CSFH_JOUT_E_TOTAL][j] = D[CSFH_JOUT_E_KINETIC][j] + D[CSFH_JOUT_E_GRAVITY][j] +
                                  D[CSFH_JOUT_E_FLEXURE][j] + D[CSFH_JOUT_E_CONTACT][j];
    }
}

int csfh_model_output_jacobian(const csfh_model_t *m, const double x[6], double D[CSFH_N_JOUT][6])
{
    memset(D, 0, CSFH_N_JOUT * 6 * sizeof(double));
    csfh_contact_partials_t cp;
    csfh_model_contact_partials(m, x, &cp);
    /* the Hertz line contact of §14.3: p0 and b grow as sqrt(F_N) */
    double half_width = 0.0;
    const double pressure =
        csfh_hertz_line_pressure(cp.F_N, m->d.E_star, m->p.L, m->d.R_conformal, &half_width);
    const double sgn_T = cp.F_T < 0.0 ? -1.0 : 1.0;
    for (int j = 0; j < 6; j++) {
        D[CSFH_JOUT_GAP][j] = cp.dgap[j];
        D[CSFH_JOUT_INDENTATION_RATE][j] = cp.drho_dot[j];
        D[CSFH_JOUT_V_T][j] = cp.dv_T[j];
        if (cp.touching) {
            D[CSFH_JOUT_F_N][j] = cp.dF_N[j];
            D[CSFH_JOUT_F_T][j] = cp.dF_T[j];
            D[CSFH_JOUT_F_T_ABS][j] = sgn_T * cp.dF_T[j];
            D[CSFH_JOUT_INDENTATION][j] = -cp.dgap[j];
        }
        if (cp.F_N > 0.0) {
            D[CSFH_JOUT_PRESSURE_MAX][j] = 0.5 * pressure / cp.F_N * cp.dF_N[j];
            D[CSFH_JOUT_HALF_WIDTH][j] = 0.5 * half_width / cp.F_N * cp.dF_N[j];
        }
        D[CSFH_JOUT_PRESSURE_MARGIN][j] = -D[CSFH_JOUT_PRESSURE_MAX][j] / m->p.pressure_allowable;
    }
    energy_jacobian(m, x, &cp, D);
    stress_jacobian(m, x, D[CSFH_JOUT_STRESS_MAX], D[CSFH_JOUT_STRESS_LOCATION]);
    for (int j = 0; j < 6; j++) {
        D[CSFH_JOUT_STRESS_MARGIN][j] = -D[CSFH_JOUT_STRESS_MAX][j] / m->p.stress_allowable;
    }
    for (int k = 0; k < CSFH_N_JOUT; k++) {
        for (int j = 0; j < 6; j++) {
            if (!isfinite(D[k][j])) {
                return CSFH_ERR_NONFINITE;
            }
        }
    }
    return CSFH_OK;
}
