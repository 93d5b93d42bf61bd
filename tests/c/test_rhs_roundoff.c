/* The right-hand side's cheaper arithmetic does not move results beyond round-off:
 * x sqrt(x) for pow(x, 1.5), sqrt(x^2 + y^2) for hypot (hypot itself where the squares would
 * overflow or underflow), no rotation of a zero s1bar, and the contact kinematics computed once.
 * Each is checked against the textbook formula computed here, in the test, with pow and hypot:
 * the helpers over many decades, and the whole right-hand side (flexure, LN_spheres with
 * damping, Ambrosio friction, central and eccentric mass centre) at many states in contact. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csfh_common.h"
#include "csfh_fmu.h"
#include "csfh_friction.h"
#include "csfh_model.h"
#include "csfh_test.h"

#define EPS DBL_EPSILON

/* a reproducible uniform number in [0, 1) */
static double uniform(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0;
}

static void test_helpers(void)
{
    unsigned long long rng = 1;
    double worst_pow = 0.0, worst_norm = 0.0;
    for (int i = 0; i < 200000; i++) {
        const double x = pow(10.0, -15.0 + 17.0 * uniform(&rng)); /* 1e-15 .. 1e2 */
        const double rel = fabs(csfh_pow_n(x, 1.5) - pow(x, 1.5)) / pow(x, 1.5);
        worst_pow = rel > worst_pow ? rel : worst_pow;
        const double a = (uniform(&rng) - 0.5) * pow(10.0, -8.0 + 8.0 * uniform(&rng));
        const double b = (uniform(&rng) - 0.5) * pow(10.0, -8.0 + 8.0 * uniform(&rng));
        const double ref = hypot(a, b);
        const double rn = ref > 0.0 ? fabs(csfh_norm2(a, b) - ref) / ref : 0.0;
        worst_norm = rn > worst_norm ? rn : worst_norm;
    }
    printf("     worst relative difference: x sqrt(x) vs pow %.2g eps, sqrt vs hypot %.2g eps\n",
           worst_pow / EPS, worst_norm / EPS);
    CHECK_TRUE(worst_pow <= 2.0 * EPS, "x sqrt(x) is pow(x, 1.5) within 2 eps");
    CHECK_TRUE(worst_norm <= 2.0 * EPS, "sqrt(x^2 + y^2) is hypot within 2 eps");
    CHECK_CLOSE(csfh_pow_n(3.0, 1.0), 3.0, 0.0, "n = 1: x itself");
    CHECK_CLOSE(csfh_pow_n(3.0, 1.3), pow(3.0, 1.3), 0.0, "other n: pow");
    /* where the squares overflow or underflow: hypot itself */
    const double big[][2] = {{1e200, 3e199}, {-1e300, 1e300}, {1e-200, 4e-201}, {5e-324, 0.0}};
    for (size_t i = 0; i < sizeof(big) / sizeof(big[0]); i++) {
        CHECK_CLOSE(csfh_norm2(big[i][0], big[i][1]), hypot(big[i][0], big[i][1]), 0.0,
                    TFMT("norm of (%g, %g) is hypot's", big[i][0], big[i][1]));
    }
    CHECK_TRUE(csfh_norm2(0.0, 0.0) == 0.0, "norm of 0 is 0");
}

/* The contact force on body 1 at (q, u), textbook formulas with hypot and pow (docs/model.md §3,
 * 4.1, 5.1): returns Q_c, and in Q_scale the round-off scale of each component: the sizes of
 * the terms that were summed, the elastic force's amplified by the gap's conditioning (rho =
 * |e| - delta cancels: an ulp of |e| is |e| / rho ulps of rho, and F ~ rho^1.5). */
static void reference_contact(const csfh_model_t *m, const double x[6], double Q[3],
                              double Q_scale[3])
{
    const double *q = x, *u = x + 3;
    const double c = cos(q[2]), s = sin(q[2]);
    const double s1[2] = {c * m->p.s1bar[0] - s * m->p.s1bar[1],
                          s * m->p.s1bar[0] + c * m->p.s1bar[1]};
    const double e[2] = {q[0] + s1[0], q[1] + s1[1]};
    const double en = hypot(e[0], e[1]);
    const double rho = en - m->d.delta;
    Q[0] = Q[1] = Q[2] = 0.0;
    Q_scale[0] = Q_scale[1] = Q_scale[2] = 0.0;
    if (!(rho > 0.0)) {
        return;
    }
    const double n[2] = {-e[0] / en, -e[1] / en}, t[2] = {-n[1], n[0]};
    const double a[2] = {s1[0] - m->p.R1 * n[0], s1[1] - m->p.R1 * n[1]};
    const double DN[3] = {n[0], n[1], a[0] * n[1] - a[1] * n[0]};
    const double DT[3] = {t[0], t[1], a[0] * t[1] - a[1] * t[0]};
    const double rho_dot = -(DN[0] * u[0] + DN[1] * u[1] + DN[2] * u[2]);
    const double onset = fmax(m->z.onset_speed, m->p.v_min);
    const double F_el = m->d.normal.K * pow(rho, 1.5);
    double F_N = F_el * (1.0 + m->d.xi * rho_dot / onset);
    F_N = F_N > 0.0 ? F_N : 0.0;
    const double v_T = DT[0] * u[0] + DT[1] * u[1] + DT[2] * u[2];
    const double F_T = csfh_ambrosio_force(m->p.fd, m->p.v0, m->p.v1, F_N, v_T);
    const double u_size = fabs(u[0]) + fabs(u[1]) + fabs(DN[2] * u[2]);
    const double F_N_scale =
        F_el * (1.0 + 3.0 * en / rho / 64.0) * (1.0 + m->d.xi * u_size / onset);
    for (int i = 0; i < 3; i++) {
        Q[i] = DN[i] * F_N + DT[i] * F_T;
        Q_scale[i] = (fabs(DN[i]) + fabs(DT[i]) * m->p.fd) * F_N_scale;
    }
}

static void test_rhs(double s1x, double s1y)
{
    csfh_model_t m;
    char msg[512];
    csfh_fmu_model_defaults(&m);
    m.p.law = CSFH_CONTACTLAW_LN_SPHERES;
    m.p.s1bar[0] = s1x;
    m.p.s1bar[1] = s1y;
    if (!CHECK_INT(csfh_model_prepare(&m, msg, sizeof(msg)), 0, "prepare")) {
        printf("     %s\n", msg);
        return;
    }
    CHECK_CLOSE(m.p.n_spheres, 1.5, 0.0, "the Hertz exponent of the preset");
    m.z.in_contact = 1;
    m.z.onset_speed = 0.4;
    unsigned long long rng = 7;
    double worst = 0.0;
    int touching = 0;
    for (int k = 0; k < 20000; k++) {
        /* a state with the contact point 1e-9 .. 1e-4 m deep, any direction, any velocity */
        const double phi = 2.0 * TEST_PI * uniform(&rng);
        const double theta = 0.2 * (uniform(&rng) - 0.5);
        const double depth = pow(10.0, -9.0 + 5.0 * uniform(&rng));
        const double c = cos(theta), s = sin(theta);
        const double s1[2] = {c * s1x - s * s1y, s * s1x + c * s1y};
        const double r = m.d.delta + depth;
        double x[6] = {r * cos(phi) - s1[0], r * sin(phi) - s1[1], theta, 0.0, 0.0, 0.0};
        for (int i = 3; i < 6; i++) {
            x[i] = 2.0 * (uniform(&rng) - 0.5) * (i == 5 ? 5.0 : 1.0);
        }
        double xdot[6], Qs[3], Qc[3], Qc_scale[3];
        m.counters.rhs = 0;
        csfh_model_derivatives(&m, 0.0, x, xdot);
        csfh_model_smooth_forces(&m, 0.0, x, Qs);
        reference_contact(&m, x, Qc, Qc_scale);
        touching += Qc[0] != 0.0 || Qc[1] != 0.0;
        const double ref[3] = {(Qs[0] + Qc[0]) / m.p.m1, (Qs[1] + Qc[1]) / m.p.m1,
                               (Qs[2] + Qc[2]) / m.p.I1};
        /* round-off scale of each component: its smooth and contact parts */
        const double mass[3] = {m.p.m1, m.p.m1, m.p.I1};
        for (int i = 0; i < 3; i++) {
            const double scale = (fabs(Qs[i]) + Qc_scale[i] + 1e-300) / mass[i];
            const double rel = fabs(xdot[3 + i] - ref[i]) / scale;
            worst = rel > worst ? rel : worst;
        }
    }
    printf("     s1bar = (%g, %g): worst difference %.2g eps of the round-off scale\n", s1x, s1y,
           worst / EPS);
    CHECK_TRUE(touching == 20000, TFMT("s1bar = (%g, %g): every state is in contact", s1x, s1y));
    CHECK_TRUE(worst <= 64.0 * EPS,
               TFMT("s1bar = (%g, %g): the right-hand side is the textbook one to round-off "
                    "(64 eps of its terms' scale)",
                    s1x, s1y));
}

static void test_energy(void)
{
    csfh_model_t m;
    char msg[512];
    csfh_fmu_model_defaults(&m);
    m.p.law = CSFH_CONTACTLAW_LN_SPHERES;
    CHECK_INT(csfh_model_prepare(&m, msg, sizeof(msg)), 0, "prepare");
    for (double rho = 1e-9; rho < 1e-3; rho *= 3.7) {
        CHECK_CLOSE(csfh_normal_elastic_energy(&m.d.normal, rho),
                    m.d.normal.K * pow(rho, 2.5) / 2.5, 4.0 * EPS,
                    TFMT("elastic energy K rho^2.5 / 2.5 at rho = %g", rho));
    }
}

int main(void)
{
    test_helpers();
    test_rhs(0.0, 0.0);
    test_rhs(2e-3, -1e-3);
    test_energy();
    return TEST_SUMMARY();
}
