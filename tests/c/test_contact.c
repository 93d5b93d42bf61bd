/* Contact kinematics (docs/model.md §3): gap, normal, arm a = s1 - R1 n_c and the Jacobian
 * rows DN, DT, against finite differences of g(q) and of the velocity of the material point of
 * body 1 that is the contact point; the worked example of section 3; G = D M^-1 D^T; |e| -> 0. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csfh_contact.h"
#include "csfh_test.h"

#define R1 0.18
#define R2 0.20
#define DELTA (R2 - R1)

/* position of a material point of body 1 given by its body-frame offset cbar from G1 */
static void material_point(const double q[3], const double cbar[2], double P[2])
{
    const double c = cos(q[2]), s = sin(q[2]);
    P[0] = q[0] + c * cbar[0] - s * cbar[1];
    P[1] = q[1] + s * cbar[0] + c * cbar[1];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void check_state(const double s1bar[2], const double q[3], const double u[3], int idx)
{
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(DELTA, R1, s1bar, q, &kin);

    /* gap: g = delta - |r + A(theta) s1bar| computed here */
    const double c = cos(q[2]), s = sin(q[2]);
    const double s1[2] = {c * s1bar[0] - s * s1bar[1], s * s1bar[0] + c * s1bar[1]};
    const double e[2] = {q[0] + s1[0], q[1] + s1[1]};
    const double en = sqrt(e[0] * e[0] + e[1] * e[1]);
    CHECK_ABS(kin.gap, DELTA - en, 1e-16, TFMT("gap = delta - |e| (state %d)", idx));
    CHECK_ABS(csfh_contact_gap(DELTA, s1bar, q), kin.gap, 0.0,
              TFMT("csfh_contact_gap = kinematics gap (state %d)", idx));
    CHECK_ABS(kin.e_norm, en, 1e-16, TFMT("|e| (state %d)", idx));
    /* frame */
    CHECK_ABS(kin.n[0], -e[0] / en, 1e-15, TFMT("n_c = -e/|e|, x (state %d)", idx));
    CHECK_ABS(kin.n[1], -e[1] / en, 1e-15, TFMT("n_c = -e/|e|, y (state %d)", idx));
    CHECK_TRUE(kin.t[0] == -kin.n[1] && kin.t[1] == kin.n[0], "t_c = rot90(n_c)");
    /* contact points: C = r + a (body 1), C2 = -R2 n_c (body 2): C - C2 = e (1 - delta/|e|) */
    const double C[2] = {q[0] + kin.a[0], q[1] + kin.a[1]};
    const double C2[2] = {-R2 * kin.n[0], -R2 * kin.n[1]};
    CHECK_ABS(C[0] - C2[0], e[0] * (1.0 - DELTA / en), 1e-15, TFMT("C - C2 = e (1 - delta/|e|), x (%d)", idx));
    CHECK_ABS(C[1] - C2[1], e[1] * (1.0 - DELTA / en), 1e-15, TFMT("C - C2 = e (1 - delta/|e|), y (%d)", idx));
    CHECK_ABS(hypot(C[0] - C2[0], C[1] - C2[1]), fabs(kin.gap), 1e-15,
              TFMT("|C - C2| = |gap| (state %d)", idx));

    /* DN = grad g by central differences of g(q) */
    const double hq = 1e-7;
    for (int j = 0; j < 3; j++) {
        double qp[3] = {q[0], q[1], q[2]}, qm[3] = {q[0], q[1], q[2]};
        qp[j] += hq;
        qm[j] -= hq;
        const double dg = (csfh_contact_gap(DELTA, s1bar, qp) - csfh_contact_gap(DELTA, s1bar, qm)) /
                          (2.0 * hq);
        CHECK_ABS(kin.DN[j], dg, 1e-9, TFMT("DN[%d] = dg/dq_%d by FD (state %d)", j, j, idx));
    }

    /* velocity of the material point of body 1 at the contact point (cbar frozen in the body),
     * by central differences along q + tau u */
    const double cbar[2] = {c * kin.a[0] + s * kin.a[1], -s * kin.a[0] + c * kin.a[1]};
    const double ht = 1e-6;
    const double qp[3] = {q[0] + ht * u[0], q[1] + ht * u[1], q[2] + ht * u[2]};
    const double qm[3] = {q[0] - ht * u[0], q[1] - ht * u[1], q[2] - ht * u[2]};
    double Pp[2], Pm[2];
    material_point(qp, cbar, Pp);
    material_point(qm, cbar, Pm);
    const double vC_fd[2] = {(Pp[0] - Pm[0]) / (2.0 * ht), (Pp[1] - Pm[1]) / (2.0 * ht)};
    /* closed form v_C = v_G + omega rot90(a) */
    const double vC[2] = {u[0] - u[2] * kin.a[1], u[1] + u[2] * kin.a[0]};
    CHECK_ABS(vC_fd[0], vC[0], 1e-9, TFMT("v_C FD = v_G + omega rot90(a), x (state %d)", idx));
    CHECK_ABS(vC_fd[1], vC[1], 1e-9, TFMT("v_C FD = v_G + omega rot90(a), y (state %d)", idx));
    const double vT = dot3(kin.DT, u), gN = dot3(kin.DN, u);
    CHECK_ABS(vT, kin.t[0] * vC_fd[0] + kin.t[1] * vC_fd[1], 1e-9,
              TFMT("v_T = DT u = t_c . v_C (FD) (state %d)", idx));
    CHECK_ABS(gN, kin.n[0] * vC_fd[0] + kin.n[1] * vC_fd[1], 1e-9,
              TFMT("gamma_N = DN u = n_c . v_C (FD) (state %d)", idx));
    /* dg/dt along u with a smaller step: the third derivative of g ~ |u|^3/|e|^2 is large */
    const double hg = 1e-7;
    const double qgp[3] = {q[0] + hg * u[0], q[1] + hg * u[1], q[2] + hg * u[2]};
    const double qgm[3] = {q[0] - hg * u[0], q[1] - hg * u[1], q[2] - hg * u[2]};
    const double gdot = (csfh_contact_gap(DELTA, s1bar, qgp) - csfh_contact_gap(DELTA, s1bar, qgm)) /
                        (2.0 * hg);
    CHECK_ABS(gN, gdot, 1e-9, TFMT("gamma_N = dg/dt along u (FD) (state %d)", idx));

    /* Q_c = D^T [F_N, F_T] = [F_c; a x F_c] and its power F_N gamma_N + F_T v_T */
    const double FN = test_uniform(0.0, 1e3), FT = test_uniform(-50.0, 50.0);
    double Q[3] = {0.0, 0.0, 0.0};
    csfh_contact_add_force(&kin, FN, FT, Q);
    const double Fc[2] = {FN * kin.n[0] + FT * kin.t[0], FN * kin.n[1] + FT * kin.t[1]};
    CHECK_ABS(Q[0], Fc[0], 1e-12 * FN + 1e-12, TFMT("Q_c x = F_c x (state %d)", idx));
    CHECK_ABS(Q[1], Fc[1], 1e-12 * FN + 1e-12, TFMT("Q_c y = F_c y (state %d)", idx));
    CHECK_ABS(Q[2], kin.a[0] * Fc[1] - kin.a[1] * Fc[0], 1e-12 * FN + 1e-12,
              TFMT("Q_c theta = a x F_c (state %d)", idx));
    CHECK_ABS(dot3(Q, u), FN * gN + FT * vT, 1e-10 * FN + 1e-10,
              TFMT("power Q_c . u = F_N gamma_N + F_T v_T (state %d)", idx));
}

static void test_jacobians(void)
{
    const double zero[2] = {0.0, 0.0};
    int idx = 0;
    /* s1bar = 0 (the paper) and random s1bar != 0, random states near and inside contact */
    for (int k = 0; k < 50; k++) {
        const double s1r[2] = {test_uniform(-0.05, 0.05), test_uniform(-0.05, 0.05)};
        for (int variant = 0; variant < 2; variant++) {
            const double *s1bar = variant == 0 ? zero : s1r;
            const double th = test_uniform(-1.0, 1.0), ang = test_uniform(-TEST_PI, TEST_PI);
            const double rad = DELTA * test_uniform(0.7, 1.05);
            const double c = cos(th), s = sin(th);
            const double s1[2] = {c * s1bar[0] - s * s1bar[1], s * s1bar[0] + c * s1bar[1]};
            /* choose q so that e = rad [cos ang, sin ang] */
            const double q[3] = {rad * cos(ang) - s1[0], rad * sin(ang) - s1[1], th};
            const double u[3] = {test_uniform(-1.0, 1.0), test_uniform(-1.0, 1.0),
                                 test_uniform(-3.0, 3.0)};
            check_state(s1bar, q, u, idx++);
        }
    }
}

/* docs/model.md §3: pure rotation theta_dot = 1 rad/s, contact at the bottom -> v_T = -0.180 m/s */
static void test_rotation_example(void)
{
    const double s1bar[2] = {0.0, 0.0};
    const double q[3] = {0.0, -DELTA - 1e-5, 0.0}; /* body pushed down: contact at the bottom */
    const double u[3] = {0.0, 0.0, 1.0};
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(DELTA, R1, s1bar, q, &kin);
    CHECK_ABS(kin.n[0], 0.0, 1e-16, "bottom contact: n_c = [0, 1] (x)");
    CHECK_ABS(kin.n[1], 1.0, 1e-16, "bottom contact: n_c = [0, 1] (y)");
    CHECK_CLOSE(kin.gap, -1e-5, 1e-9, "bottom contact: gap = -1e-5");
    CHECK_CLOSE(dot3(kin.DT, u), -0.180, 1e-14, "pure rotation 1 rad/s: v_T = -0.180 m/s");
    CHECK_ABS(dot3(kin.DN, u), 0.0, 1e-16, "pure rotation: gamma_N = 0 (s1bar = 0)");
    /* D = [[n^T, 0], [t^T, -R1]] for s1bar = 0 */
    CHECK_ABS(kin.DN[2], 0.0, 1e-17, "s1bar = 0: DN[2] = 0");
    CHECK_CLOSE(kin.DT[2], -R1, 1e-15, "s1bar = 0: DT[2] = -R1");
    /* the printed Eq. (38) simplification (arm s1, no -R1) would give 0: guard against it */
    CHECK_TRUE(fabs(dot3(kin.DT, u)) > 0.1, "friction torque arm includes -R1 (errata Eq. 38)");
}

/* G = D M^-1 D^T = diag(1/m, 1/m + R1^2/I) for s1bar = 0 */
static void test_delassus(void)
{
    const double m = 10.0, I = 0.1617;
    const double s1bar[2] = {0.0, 0.0};
    for (int k = 0; k < 20; k++) {
        const double ang = test_uniform(-TEST_PI, TEST_PI), th = test_uniform(-1.0, 1.0);
        const double q[3] = {0.0201 * cos(ang), 0.0201 * sin(ang), th};
        csfh_contact_kin_t kin;
        csfh_contact_kinematics(DELTA, R1, s1bar, q, &kin);
        const double Minv[3] = {1.0 / m, 1.0 / m, 1.0 / I};
        double G[2][2];
        const double *D[2] = {kin.DN, kin.DT};
        for (int i = 0; i < 2; i++) {
            for (int j = 0; j < 2; j++) {
                G[i][j] = D[i][0] * Minv[0] * D[j][0] + D[i][1] * Minv[1] * D[j][1] +
                          D[i][2] * Minv[2] * D[j][2];
            }
        }
        CHECK_CLOSE(G[0][0], 0.1, 1e-14, TFMT("G_NN = 1/m = 0.1 (%d)", k));
        CHECK_CLOSE(G[1][1], 0.30037, 2e-5, TFMT("G_TT = 0.30037 (docs/model.md §3) (%d)", k));
        CHECK_CLOSE(G[1][1], 1.0 / m + R1 * R1 / I, 1e-14, TFMT("G_TT = 1/m + R1^2/I (%d)", k));
        CHECK_ABS(G[0][1], 0.0, 1e-16, TFMT("G_NT = 0: normal and tangent decouple (%d)", k));
        CHECK_ABS(G[0][1], G[1][0], 1e-16, "G symmetric");
    }
}

/* |e| -> 0 guard: finite output */
static void test_concentric_guard(void)
{
    csfh_contact_kin_t kin;
    const double zero[2] = {0.0, 0.0};
    const double q0[3] = {0.0, 0.0, 0.3};
    for (int variant = 0; variant < 3; variant++) {
        const double s1bar[2] = {variant == 2 ? 0.01 : 0.0, variant == 2 ? -0.02 : 0.0};
        const double delta = variant == 1 ? 0.0 : DELTA;
        double q[3] = {q0[0], q0[1], q0[2]};
        if (variant == 2) { /* place O1 exactly on O2 */
            const double c = cos(q[2]), s = sin(q[2]);
            q[0] = -(c * s1bar[0] - s * s1bar[1]);
            q[1] = -(s * s1bar[0] + c * s1bar[1]);
        }
        memset(&kin, 0, sizeof(kin));
        csfh_contact_kinematics(delta, R1, variant == 2 ? s1bar : zero, q, &kin);
        int finite = isfinite(kin.gap) && isfinite(kin.e_norm);
        for (int i = 0; i < 2; i++) {
            finite &= isfinite(kin.n[i]) && isfinite(kin.t[i]) && isfinite(kin.a[i]);
        }
        for (int i = 0; i < 3; i++) {
            finite &= isfinite(kin.DN[i]) && isfinite(kin.DT[i]);
        }
        CHECK_TRUE(finite, TFMT("|e| = 0: all kinematic outputs finite (variant %d)", variant));
        CHECK_ABS(hypot(kin.n[0], kin.n[1]), 1.0, 1e-15, TFMT("|e| = 0: unit normal (variant %d)", variant));
        CHECK_ABS(kin.gap, delta, 1e-17, TFMT("|e| = 0: gap = delta (variant %d)", variant));
        CHECK_TRUE(isfinite(csfh_contact_gap(delta, variant == 2 ? s1bar : zero, q)),
                   "csfh_contact_gap finite at |e| = 0");
    }
    /* tiny but nonzero |e| still gives the exact normal */
    const double q[3] = {3e-200, -4e-200, 0.0};
    csfh_contact_kinematics(0.0, R1, zero, q, &kin);
    CHECK_CLOSE(kin.n[0], -0.6, 1e-15, "|e| = 5e-200: n_c = -e/|e| (x)");
    CHECK_CLOSE(kin.n[1], 0.8, 1e-15, "|e| = 5e-200: n_c = -e/|e| (y)");
}

int main(void)
{
    test_jacobians();
    test_rotation_example();
    test_delassus();
    test_concentric_guard();
    return TEST_SUMMARY();
}
