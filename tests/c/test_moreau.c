/* The Moreau stepper (csfh_moreau.c) against closed-form results of docs/model.md §6 and
 * 7.4-7.6, computed here from the geometry (not with the core's kinematics):
 *
 *  - one impact step of the central drop: Lambda_N = m1 ((1 + c_r) v + g h), the post-step
 *    normal velocity -c_r times the pre-step one (6.3), no restitution below v_eps;
 *  - one step of the first asymmetric impact (7.6): the normal impulse, the stick impulse
 *    -c_T/G_TT (paper rule, f_a), the slip impulse -f_d Lambda_N (memory rule, an arriving
 *    slide), the memory rule's "once stuck stays stuck while |Lambda_T| <= f_a Lambda_N", and
 *    the spin omega+ = -R1 Lambda_T / I1 (6.2 with G of 3.6: the inertia I1, not m1);
 *  - the central bounce sequence (7.4): v+/v- = c_r at every impact, the impulses, the times;
 *  - energy conservation with c_r = 1, no friction and an eccentric cylinder (s1-bar != 0, so
 *    the normal impulse has a moment about G1: the inertia enters), the energy computed here;
 *  - rolling without slip where static friction holds (6.4, memory rule): the rolling pendulum
 *    phi'' = -g sin(phi) / (delta (1 + I1/(m1 R1^2))), integrated here by RK4. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_fmu.h"
#include "csfh_model.h"
#include "csfh_moreau.h"
#include "csfh_test.h"

#define H 1e-5

static void make_model(csfh_model_t *m, int friction, double cr, double s1x, double s1y)
{
    char msg[256] = "";
    csfh_fmu_model_defaults(m);
    m->p.flexure_enabled = 0;
    m->p.friction_enabled = friction;
    m->p.cr = cr;
    m->p.s1bar[0] = s1x;
    m->p.s1bar[1] = s1y;
    CHECK_INT(csfh_model_prepare(m, msg, sizeof(msg)), 0, TFMT("prepare: %s", msg));
}

/* The state at the step start whose midpoint q_A + h/2 u_A lies `depth` inside the bore along
 * the unit vector `dir` from O2 (s1-bar = 0): the midpoint contact of (6.1) step 3. */
static void start_at_contact(const csfh_model_t *m, const double dir[2], double depth,
                             const double u[3], double q[3])
{
    const double r = m->d.delta + depth;
    q[0] = r * dir[0] - 0.5 * H * u[0];
    q[1] = r * dir[1] - 0.5 * H * u[1];
    q[2] = -0.5 * H * u[2];
}

/* ---------------------------------------------------------------------------------------- */
/* Closed form of one contact step for s1-bar = 0 (docs/model.md §6.2, G of 3.6): normal n_c =
 * -e/|e| at the midpoint, t_c = rot90(n_c), D_N = [n, 0], D_T = [t, -R1], G = diag(1/m1,
 * 1/m1 + R1^2/I1). mu_stick: f_a or f_d. */
typedef struct {
    double Lambda_N, Lambda_T, uE[3], gamma_A[2], gamma_E[2];
    int stick;
} expected_step_t;

static void closed_form_step(const csfh_model_t *m, const double q[3], const double u[3],
                             double mu_stick, double fd, int restitution, expected_step_t *x)
{
    const double m1 = m->p.m1, I1 = m->p.I1, R1 = m->p.R1, g = m->p.g, cr = m->p.cr;
    const double qM[2] = {q[0] + 0.5 * H * u[0], q[1] + 0.5 * H * u[1]};
    const double en = hypot(qM[0], qM[1]);
    const double n[2] = {-qM[0] / en, -qM[1] / en};
    const double t[2] = {-n[1], n[0]};
    const double u_free[3] = {u[0], u[1] - H * g, u[2]};
    const double GNN = 1.0 / m1, GTT = 1.0 / m1 + R1 * R1 / I1;
    x->gamma_A[0] = n[0] * u[0] + n[1] * u[1];
    x->gamma_A[1] = t[0] * u[0] + t[1] * u[1] - R1 * u[2];
    const double gf_N = n[0] * u_free[0] + n[1] * u_free[1];
    const double gf_T = t[0] * u_free[0] + t[1] * u_free[1] - R1 * u_free[2];
    const double cN = gf_N + (restitution ? cr * x->gamma_A[0] : 0.0), cT = gf_T;
    x->Lambda_N = -cN / GNN;
    const double LT_stick = -cT / GTT;
    x->stick = fabs(LT_stick) <= mu_stick * x->Lambda_N;
    x->Lambda_T = x->stick ? LT_stick : -fd * x->Lambda_N * (cT > 0.0 ? 1.0 : -1.0);
    x->uE[0] = u_free[0] + (n[0] * x->Lambda_N + t[0] * x->Lambda_T) / m1;
    x->uE[1] = u_free[1] + (n[1] * x->Lambda_N + t[1] * x->Lambda_T) / m1;
    x->uE[2] = u_free[2] - R1 * x->Lambda_T / I1;
    x->gamma_E[0] = n[0] * x->uE[0] + n[1] * x->uE[1];
    x->gamma_E[1] = t[0] * x->uE[0] + t[1] * x->uE[1] - R1 * x->uE[2];
}

static void check_step(const csfh_moreau_step_t *info, const double q0[3], const double u0[3],
                       const double q[3], const double u[3], const expected_step_t *x,
                       const char *what)
{
    CHECK_CLOSE(info->Lambda_N, x->Lambda_N, 1e-13, TFMT("%s: Lambda_N", what));
    CHECK_ABS(info->Lambda_T, x->Lambda_T, 1e-13 * x->Lambda_N, TFMT("%s: Lambda_T", what));
    CHECK_INT(info->mode, x->stick ? CSFH_MOREAU_STICK : CSFH_MOREAU_SLIP, TFMT("%s: mode", what));
    for (int i = 0; i < 3; i++) {
        CHECK_ABS(u[i], x->uE[i], 1e-13, TFMT("%s: u_E[%d]", what, i));
        /* drift-kick-drift: q_E = q_A + h/2 u_A + h/2 u_E */
        CHECK_ABS(q[i], q0[i] + 0.5 * H * u0[i] + 0.5 * H * x->uE[i], 1e-17,
                  TFMT("%s: q_E[%d]", what, i));
    }
}

/* ---------------------------------------------------------------------------------------- */
static void test_central_impact_step(void)
{
    csfh_model_t m;
    make_model(&m, 1, 0.9, 0.0, 0.0);
    csfh_moreau_options_t o;
    csfh_moreau_default_options(&o);
    o.h = H;
    const double v = sqrt(2.0 * 9.81 * 0.03); /* docs/model.md §7.1 */
    const double dir[2] = {0.0, -1.0};
    double u[3] = {0.0, -v, 0.0}, q[3];
    start_at_contact(&m, dir, 1e-9, u, q);
    const double q0[3] = {q[0], q[1], q[2]}, u0[3] = {u[0], u[1], u[2]};
    expected_step_t x;
    closed_form_step(&m, q0, u0, m.p.fa, m.p.fd, 1, &x);
    csfh_moreau_memory_t mem = {0, 0};
    csfh_moreau_step_t info;
    CHECK_INT(csfh_moreau_step(&m, &o, &mem, q, u, &info), CSFH_OK, "central impact step");
    CHECK_INT(info.restitution, 1, "central impact: restitution applied (closing)");
    /* 6.3: the impulse absorbs the step's gravity impulse and reverses c_r times the velocity at
     * the step START: Lambda_N = m1 ((1 + c_r) v + g h), gamma_E,N = -c_r gamma_A,N exactly */
    CHECK_CLOSE(info.Lambda_N, m.p.m1 * ((1.0 + m.p.cr) * v + m.p.g * H), 1e-14,
                "7.4: Lambda_N = m1 ((1 + c_r) v + g h)");
    CHECK_CLOSE(info.gamma_A[0], -v, 1e-15, "gamma_A,N = -v (the velocity at the step start)");
    CHECK_CLOSE(info.gamma_E[0], m.p.cr * v, 1e-14, "6.3: gamma_E,N = -c_r gamma_A,N");
    CHECK_CLOSE(u[1], m.p.cr * v, 1e-14, "v+ = c_r v-");
    CHECK_ABS(u[0], 0.0, 0.0, "central: no sideways velocity");
    CHECK_ABS(u[2], 0.0, 0.0, "central: no spin");
    check_step(&info, q0, u0, q, u, &x, "central impact");

    /* below v_eps no restitution: a perfectly plastic step, gamma_E,N = 0 */
    o.v_eps = 1e-3;
    double u2[3] = {0.0, -5e-4, 0.0}, q2[3];
    start_at_contact(&m, dir, 1e-9, u2, q2);
    mem.sticking = mem.active = 0;
    CHECK_INT(csfh_moreau_step(&m, &o, &mem, q2, u2, &info), CSFH_OK, "slow approach step");
    CHECK_INT(info.restitution, 0, "6.3: no restitution for gamma_A,N > -v_eps");
    CHECK_ABS(info.gamma_E[0], 0.0, 1e-17, "slow approach: gamma_E,N = 0");
    CHECK_CLOSE(info.Lambda_N, m.p.m1 * (5e-4 + m.p.g * H), 1e-13,
                "slow approach: Lambda_N = m1 (v + g h)");
}

/* ---------------------------------------------------------------------------------------- */
/* docs/model.md §7.6: the first asymmetric impact, from q0 = [0.01, 0.01, 0]: the contact at -60
 * degrees (n_c = [-0.5, 0.866]), the free-fall velocity 0.732140 m/s, gamma_N- = -0.634 m/s,
 * v_T- = +0.366 m/s; sticking needs |Lambda_T|/Lambda_N = 0.1012, between f_d and f_a. */
static void asymmetric_state(const csfh_model_t *m, double q[3], double u[3])
{
    const double y_c = -sqrt(0.02 * 0.02 - 0.01 * 0.01);
    const double v = sqrt(2.0 * 9.81 * (0.01 - y_c));
    const double dir[2] = {0.5, -sqrt(3.0) / 2.0};
    u[0] = 0.0;
    u[1] = -v;
    u[2] = 0.0;
    start_at_contact(m, dir, 1e-9, u, q);
}

static void test_asymmetric_impact_step(void)
{
    csfh_model_t m;
    make_model(&m, 1, 0.9, 0.0, 0.0);
    for (int rule = CSFH_STICK_PAPER; rule <= CSFH_STICK_MEMORY; rule++) {
        for (int was_stuck = 0; was_stuck <= 1; was_stuck++) {
            csfh_moreau_options_t o;
            csfh_moreau_default_options(&o);
            o.h = H;
            o.stick_rule = rule;
            double q[3], u[3];
            asymmetric_state(&m, q, u);
            const double q0[3] = {q[0], q[1], q[2]}, u0[3] = {u[0], u[1], u[2]};
            /* 6.4: f_a decides (paper rule; memory rule when the previous step stuck), f_d
             * for an arriving slide under the memory rule */
            const int use_fa = rule == CSFH_STICK_PAPER || was_stuck;
            expected_step_t x;
            closed_form_step(&m, q0, u0, use_fa ? m.p.fa : m.p.fd, m.p.fd, 1, &x);
            const char *what = TFMT("asymmetric impact, %s rule, previous step %s",
                                    rule == CSFH_STICK_PAPER ? "paper" : "memory",
                                    was_stuck ? "stuck" : "free");
            /* the data of 7.6 */
            CHECK_ABS(x.gamma_A[0], -0.634051, 1e-6, TFMT("%s: gamma_N- (7.1)", what));
            CHECK_ABS(x.gamma_A[1], 0.366070, 1e-6, TFMT("%s: v_T- (7.1)", what));
            const double ratio = fabs(-x.gamma_A[1] / (1.0 / m.p.m1 + m.p.R1 * m.p.R1 / m.p.I1)) /
                                 x.Lambda_N;
            CHECK_TRUE(m.p.fd < ratio && ratio < m.p.fa, TFMT("%s: f_d < %.4f < f_a", what, ratio));
            CHECK_INT(x.stick, use_fa, TFMT("%s: closed form sticks iff f_a decides", what));
            csfh_moreau_memory_t mem = {was_stuck, was_stuck};
            csfh_moreau_step_t info;
            CHECK_INT(csfh_moreau_step(&m, &o, &mem, q, u, &info), CSFH_OK, what);
            check_step(&info, q0, u0, q, u, &x, what);
            /* the spin after the impact: omega+ = -R1 Lambda_T / I1 (7.6) */
            CHECK_CLOSE(u[2], -m.p.R1 * info.Lambda_T / m.p.I1, 1e-13, TFMT("%s: omega+", what));
            CHECK_CLOSE(info.gamma_E[0], -m.p.cr * info.gamma_A[0], 1e-13,
                        TFMT("%s: gamma_E,N = -c_r gamma_A,N", what));
            if (use_fa) {
                CHECK_ABS(info.gamma_E[1], 0.0, 1e-14, TFMT("%s: stick: v_T+ = 0", what));
                CHECK_INT(mem.sticking, 1, TFMT("%s: remembered as stuck", what));
            } else {
                CHECK_CLOSE(info.Lambda_T, -m.p.fd * info.Lambda_N, 1e-14,
                            TFMT("%s: slip: Lambda_T = -f_d Lambda_N", what));
                CHECK_TRUE(info.gamma_E[1] > 0.0, TFMT("%s: slip goes on forwards", what));
                CHECK_INT(mem.sticking, 0, TFMT("%s: remembered as slipping", what));
            }
        }
    }
}

/* ---------------------------------------------------------------------------------------- */
/* 7.4: the central bounce sequence (c_r = 0.9, h = 1e-5 s) through csfh_moreau_run. */
static void test_bounce_sequence(void)
{
    csfh_model_t m;
    make_model(&m, 0, 0.9, 0.0, 0.0);
    csfh_moreau_options_t o;
    csfh_moreau_default_options(&o);
    o.h = H;
    const double x0[6] = {0.0, 0.01, 0.0, 0.0, 0.0, 0.0};
    enum { MAX_IMP = 8 };
    double imp[MAX_IMP * CSFH_MI_NCOLS], x_end[6];
    csfh_moreau_stats_t st;
    CHECK_INT(csfh_moreau_run(&m, &o, 0.0, x0, 70000, 70000, NULL, 0, imp, MAX_IMP, x_end, &st),
              CSFH_OK, "bounce sequence runs");
    CHECK_TRUE(st.impacts >= 6, "at least six impacts in 0.7 s");
    const double g = m.p.g, cr = m.p.cr;
    double v = sqrt(2.0 * g * 0.03), t_exact = sqrt(2.0 * 0.03 / g); /* 7.1 */
    for (size_t k = 0; k < 6 && k < st.impacts; k++) {
        const double *row = imp + k * CSFH_MI_NCOLS;
        const double gA = row[CSFH_MI_GAMMA_N_A], gE = row[CSFH_MI_GAMMA_N_E];
        CHECK_CLOSE(-gE / gA, cr, 1e-12, TFMT("7.4: impact %zu: v+/v- = c_r", k));
        CHECK_CLOSE(row[CSFH_MI_LAMBDA_N], m.p.m1 * ((1.0 + cr) * -gA + g * H), 1e-12,
                    TFMT("7.4: impact %zu: Lambda_N = m1 ((1 + c_r) |gamma_A| + g h)", k));
        CHECK_ABS(-gA, v, 2e-3 * v, TFMT("7.4: impact %zu: the rigid speed c_r^k v_imp", k));
        /* the impact step starts at most a few steps after the exact instant (6.3) */
        CHECK_TRUE(row[CSFH_MI_T] >= t_exact - H && row[CSFH_MI_T] <= t_exact + 6 * H,
                   TFMT("7.4: impact %zu at %.6f s, exact %.6f s", k, row[CSFH_MI_T], t_exact));
        CHECK_ABS(row[CSFH_MI_OMEGA_E], 0.0, 0.0, TFMT("impact %zu: no spin", k));
        v *= cr;
        t_exact += 2.0 * v / g;
    }
}

/* ---------------------------------------------------------------------------------------- */
/* 7.5 with an eccentric cylinder: c_r = 1, no friction, no flexure, O1 off G1 by s1-bar: the
 * normal impulses have a moment about G1, so the spin changes at every impact, and the energy
 * (1/2 m1 |v|^2 + 1/2 I1 omega^2 + m1 g y, computed here) is conserved to round-off only if the
 * stepper uses I1 for the rotation. */
static void test_energy_eccentric_elastic(void)
{
    csfh_model_t m;
    make_model(&m, 0, 1.0, 0.004, -0.003);
    csfh_moreau_options_t o;
    csfh_moreau_default_options(&o);
    o.h = H;
    const double x0[6] = {0.0, 0.01, 0.0, 0.3, 0.0, 0.5};
    enum { N_REC = 101, MAX_IMP = 64 };
    double *rec = calloc((size_t)N_REC * CSFH_MR_NCOLS, sizeof(double));
    double imp[MAX_IMP * CSFH_MI_NCOLS], x_end[6];
    csfh_moreau_stats_t st;
    CHECK_INT(csfh_moreau_run(&m, &o, 0.0, x0, 100000, 1000, rec, N_REC, imp, MAX_IMP, x_end, &st),
              CSFH_OK, "eccentric elastic run");
    CHECK_TRUE(st.onsets >= 10, TFMT("at least ten impacts in 1 s (%lld)", st.onsets));
    double E0 = 0.0, worst = 0.0, spin_change = 0.0;
    for (size_t k = 0; k < st.records; k++) {
        const double *r = rec + k * CSFH_MR_NCOLS;
        const double E = 0.5 * m.p.m1 * (r[CSFH_MR_VX] * r[CSFH_MR_VX] + r[CSFH_MR_VY] * r[CSFH_MR_VY]) +
                         0.5 * m.p.I1 * r[CSFH_MR_OMEGA] * r[CSFH_MR_OMEGA] + m.p.m1 * m.p.g * r[CSFH_MR_Y];
        if (k == 0) {
            E0 = E;
        }
        worst = fmax(worst, fabs(E - E0));
        spin_change = fmax(spin_change, fabs(r[CSFH_MR_OMEGA] - 0.5));
    }
    CHECK_CLOSE(E0, 0.5 * 10.0 * 0.09 + 0.5 * 0.1617 * 0.25 + 10.0 * 9.81 * 0.01, 1e-15,
                "7.5: E0 = 1.4512 J");
    CHECK_TRUE(spin_change > 0.1, TFMT("the impacts change the spin (by %.3g rad/s)", spin_change));
    /* round-off over 1e5 steps: ~1e-12 J of 1.45 J */
    CHECK_TRUE(worst < 1e-10 * E0, TFMT("energy conserved: drift %.3e J", worst));
    free(rec);
}

/* ---------------------------------------------------------------------------------------- */
/* 6.4: a stuck contact stays stuck while static friction holds. Body 1 at rest touching the
 * bore at phi0 from the bottom, where rolling needs |F_T|/F_N = tan(phi0) I1/(I1 + m1 R1^2) =
 * 0.0825 (between f_d and f_a; it only falls as the body speeds up): every step sticks (under
 * both rules) and body 1 rolls as the pendulum phi'' = -g sin(phi) / (delta k),
 * k = 1 + I1/(m1 R1^2), omega = -(delta/R1) phi'. */
static void rolling_pendulum(double phi0, double k_delta, double g, double t_end, double *phi,
                             double *rate)
{
    const int n = 20000;
    const double dt = t_end / n;
    double p = phi0, w = 0.0;
    for (int i = 0; i < n; i++) { /* RK4 */
        const double k1p = w, k1w = -g * sin(p) / k_delta;
        const double k2p = w + 0.5 * dt * k1w, k2w = -g * sin(p + 0.5 * dt * k1p) / k_delta;
        const double k3p = w + 0.5 * dt * k2w, k3w = -g * sin(p + 0.5 * dt * k2p) / k_delta;
        const double k4p = w + dt * k3w, k4w = -g * sin(p + dt * k3p) / k_delta;
        p += dt / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p);
        w += dt / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
    }
    *phi = p;
    *rate = w;
}

static void test_rolling_without_slip(void)
{
    for (int rule = CSFH_STICK_PAPER; rule <= CSFH_STICK_MEMORY; rule++) {
        csfh_model_t m;
        make_model(&m, 1, 0.9, 0.0, 0.0);
        const double m1 = m.p.m1, I1 = m.p.I1, R1 = m.p.R1, delta = m.d.delta;
        const double ratio = 0.0825;
        const double phi0 = atan(ratio * (I1 + m1 * R1 * R1) / I1);
        csfh_moreau_options_t o;
        csfh_moreau_default_options(&o);
        o.h = H;
        o.stick_rule = rule;
        const double x0[6] = {delta * sin(phi0), -delta * cos(phi0), 0.0, 0.0, 0.0, 0.0};
        const long long n = 20000; /* 0.2 s: most of a half swing */
        double x_end[6];
        csfh_moreau_stats_t st;
        const char *what = rule == CSFH_STICK_PAPER ? "paper rule" : "memory rule";
        CHECK_INT(csfh_moreau_run(&m, &o, 0.0, x0, n, n, NULL, 0, NULL, 0, x_end, &st), CSFH_OK,
                  TFMT("rolling, %s", what));
        CHECK_INT(st.stick_steps, n, TFMT("rolling, %s: every step sticks", what));
        double phi, rate;
        rolling_pendulum(phi0, delta * (1.0 + I1 / (m1 * R1 * R1)), m.p.g, n * H, &phi, &rate);
        CHECK_TRUE(phi < 0.0, TFMT("rolling, %s: past the bottom at 0.2 s", what));
        /* Moreau's error: O(h phi') = 1e-5 x 4 rad/s; measured 3e-7 rad */
        CHECK_ABS(atan2(x_end[0], -x_end[1]), phi, 1e-5, TFMT("rolling, %s: phi(0.2 s)", what));
        CHECK_ABS(x_end[5], -(delta / R1) * rate, 1e-5,
                  TFMT("rolling, %s: omega = -(delta/R1) phi'", what));
    }
}

int main(void)
{
    test_central_impact_step();
    test_asymmetric_impact_step();
    test_bounce_sequence();
    test_energy_eccentric_elastic();
    test_rolling_without_slip();
    return TEST_SUMMARY();
}
