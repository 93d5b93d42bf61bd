/* Ambrosio friction (docs/model.md §5.1, paper Eq. 26): properties over a sweep of v_T and F_N. */
#include <math.h>
#include <stdio.h>

#include "csfh_friction.h"
#include "csfh_test.h"

#define FD 0.055
#define V0 1e-4
#define V1 1e-2

/* c_d written here from the text of 5.1 */
static double ref_cd(double v, double v0, double v1)
{
    v = fabs(v);
    if (v <= v0) {
        return 0.0;
    }
    if (v >= v1) {
        return 1.0;
    }
    return (v - v0) / (v1 - v0);
}

static void test_sweep(void)
{
    const double FNs[] = {0.0, 1e-3, 1.0, 98.1, 1e4, 6.2e4};
    int bounded = 1, dissipative = 1, dead = 1, full = 1, odd = 1, formula = 1;
    for (size_t i = 0; i < sizeof(FNs) / sizeof(FNs[0]); i++) {
        const double FN = FNs[i];
        for (int k = -4000; k <= 4000; k++) {
            /* log-spaced speeds from 1e-7 to 1 m/s, both signs, plus 0 */
            const double mag = k == 0 ? 0.0 : pow(10.0, -7.0 + 7.0 * (abs(k) - 1) / 3999.0);
            const double v = k < 0 ? -mag : mag;
            const double F = csfh_ambrosio_force(FD, V0, V1, FN, v);
            bounded &= fabs(F) <= FD * FN;
            dissipative &= F * v <= 0.0;
            if (fabs(v) <= V0) {
                dead &= F == 0.0;
            }
            if (fabs(v) >= V1) {
                full &= F == -FD * FN * (v > 0.0 ? 1.0 : -1.0);
            }
            odd &= csfh_ambrosio_force(FD, V0, V1, FN, -v) == -F;
            const double ref = -FD * ref_cd(v, V0, V1) * FN * (v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0));
            formula &= fabs(F - ref) <= 1e-15 * FD * FN;
            formula &= fabs(csfh_ambrosio_cd(fabs(v), V0, V1) - ref_cd(v, V0, V1)) <= 1e-15;
        }
    }
    CHECK_TRUE(bounded, "|F_T| <= f_d F_N over the sweep");
    CHECK_TRUE(dissipative, "F_T v_T <= 0 over the sweep (dissipative)");
    CHECK_TRUE(dead, "F_T = 0 for |v_T| <= v0");
    CHECK_TRUE(full, "F_T = -f_d F_N sgn(v_T) for |v_T| >= v1");
    CHECK_TRUE(odd, "odd symmetry F_T(-v) = -F_T(v)");
    CHECK_TRUE(formula, "c_d and F_T = -f_d c_d F_N sgn(v_T) as written in docs/model.md §5.1");
}

static void test_points_and_continuity(void)
{
    const double FN = 100.0;
    CHECK_ABS(csfh_ambrosio_force(FD, V0, V1, FN, 0.0), 0.0, 0.0, "v_T = 0: no force");
    CHECK_ABS(csfh_ambrosio_force(FD, V0, V1, FN, V0), 0.0, 0.0, "v_T = v0: no force");
    CHECK_ABS(csfh_ambrosio_force(FD, V0, V1, FN, -V0), 0.0, 0.0, "v_T = -v0: no force");
    CHECK_CLOSE(csfh_ambrosio_force(FD, V0, V1, FN, V1), -FD * FN, 1e-15, "v_T = v1: full friction");
    CHECK_CLOSE(csfh_ambrosio_force(FD, V0, V1, FN, -V1), FD * FN, 1e-15, "v_T = -v1: full friction");
    const double vm = 0.5 * (V0 + V1);
    CHECK_CLOSE(csfh_ambrosio_force(FD, V0, V1, FN, vm), -0.5 * FD * FN, 1e-14, "midpoint of the ramp: half");
    CHECK_CLOSE(csfh_ambrosio_cd(vm, V0, V1), 0.5, 1e-14, "c_d = 1/2 at the ramp midpoint");
    CHECK_CLOSE(csfh_ambrosio_force(FD, V0, V1, FN, 2.0), -FD * FN, 1e-15, "2 m/s: full");
    /* continuity at v0 and v1: Lipschitz with constant f_d F_N/(v1 - v0) */
    const double Lip = FD * FN / (V1 - V0);
    const double eps[] = {1e-6, 1e-9, 1e-12};
    for (int i = 0; i < 3; i++) {
        const double e = eps[i] * V1;
        for (int s = -1; s <= 1; s += 2) {
            const double a0 = csfh_ambrosio_force(FD, V0, V1, FN, s * (V0 - e));
            const double b0 = csfh_ambrosio_force(FD, V0, V1, FN, s * (V0 + e));
            CHECK_TRUE(fabs(a0 - b0) <= Lip * 2.0 * e * (1.0 + 1e-6) + 1e-15,
                       TFMT("continuous at %cv0 (eps %g)", s > 0 ? '+' : '-', e));
            const double a1 = csfh_ambrosio_force(FD, V0, V1, FN, s * (V1 - e));
            const double b1 = csfh_ambrosio_force(FD, V0, V1, FN, s * (V1 + e));
            CHECK_TRUE(fabs(a1 - b1) <= Lip * 2.0 * e * (1.0 + 1e-6) + 1e-15,
                       TFMT("continuous at %cv1 (eps %g)", s > 0 ? '+' : '-', e));
        }
    }
    /* monotone non-increasing in v_T (F_T = -f_d c_d F_N sgn v_T) */
    double prev = INFINITY;
    int mono = 1;
    for (int k = 0; k <= 10000; k++) {
        const double v = -0.02 + 0.04 * k / 10000.0;
        const double F = csfh_ambrosio_force(FD, V0, V1, FN, v);
        mono &= F <= prev;
        prev = F;
    }
    CHECK_TRUE(mono, "F_T non-increasing in v_T");
    /* no friction without normal force; f_d = 0 disables */
    CHECK_ABS(csfh_ambrosio_force(FD, V0, V1, 0.0, 0.5), 0.0, 0.0, "F_N = 0: no friction");
    CHECK_ABS(csfh_ambrosio_force(0.0, V0, V1, FN, 0.5), 0.0, 0.0, "f_d = 0: no friction");
    /* v0 = 0 is allowed: friction for any nonzero speed, none at rest */
    CHECK_ABS(csfh_ambrosio_force(FD, 0.0, V1, FN, 0.0), 0.0, 0.0, "v0 = 0: v_T = 0 gives 0");
    CHECK_CLOSE(csfh_ambrosio_force(FD, 0.0, V1, FN, 1e-3), -FD * FN * 0.1, 1e-14, "v0 = 0: ramp from 0");
    /* creep speed for a force ratio r < f_d (5.1): v = v0 + (v1 - v0) r/f_d */
    const double r = 0.02, vc = V0 + (V1 - V0) * r / FD;
    CHECK_CLOSE(-csfh_ambrosio_force(FD, V0, V1, FN, vc) / FN, r, 1e-13, "creep speed v0 + (v1 - v0) r/f_d");
}

int main(void)
{
    test_sweep();
    test_points_and_continuity();
    return TEST_SUMMARY();
}
