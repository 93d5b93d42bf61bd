/* The LN-ESDU force F(rho) of Eq. (18) (docs/model.md §4.5) against a long-double reference:
 * with r = rho/(a F*) and s = ln(F_max/F), Eq. (18) reads s - ln(1 + s) = -ln r, solved here by
 * bisection to the long double's resolution, F = rho/(a (1 + s)). The reference takes the same
 * clamp indentation a F* (a double) as the model. Relative error <= 1e-12 over 1e-16 ... 1 of the
 * clamp indentation, up to the last doubles below it; the clamp itself and rho <= 0; reading I3's
 * tangent stiffness 1/(a s) against the reference's. */
#include <float.h>
#include <math.h>
#include <stdio.h>

#include "csfh_normal_law.h"
#include "csfh_test.h"

/* s = ln(F_max/F) for 0 < rho < c = a F*, by bisection on [0, 2 L + 2 sqrt(L) + 1] in long double */
static long double ref_log_ratio(double rho, double c)
{
    const long double r = (long double)rho / (long double)c;
    const long double L = r > 0.5L ? -log1pl(((long double)rho - (long double)c) / (long double)c)
                                   : -logl(r);
    long double lo = 0.0L, hi = 2.0L * L + 2.0L * sqrtl(L) + 1.0L;
    for (int it = 0; it < 20000; it++) {
        const long double mid = 0.5L * (lo + hi);
        if (!(mid > lo && mid < hi)) {
            break; /* the bracket holds two adjacent long doubles */
        }
        if (mid - log1pl(mid) < L) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return 0.5L * (lo + hi);
}

static long double ref_force(const csfh_esdu_t *es, double rho)
{
    return (long double)rho / ((long double)es->a * (1.0L + ref_log_ratio(rho, es->a * es->F_max)));
}

typedef struct {
    double worst;    /* largest relative error of F */
    double at_ratio; /* rho/(a F*) where it occurs */
    int bad_status;  /* points below the clamp not reported CSFH_LAW_OK */
} sweep_t;

static void check_point(const csfh_esdu_t *es, double rho, sweep_t *sw)
{
    double F;
    if (csfh_esdu_force(es, rho, &F) != CSFH_LAW_OK) {
        sw->bad_status++;
        return;
    }
    const long double F_ref = ref_force(es, rho);
    const double err = (double)fabsl(((long double)F - F_ref) / F_ref);
    if (!(err <= sw->worst)) {
        sw->worst = err;
        sw->at_ratio = rho / (es->a * es->F_max);
    }
}

static void test_force_sweep(double E, int with_pi, double dR)
{
    csfh_esdu_t es;
    csfh_esdu_setup(E, 0.3, E, 0.3, 0.05, dR, with_pi, &es);
    const double c = es.a * es.F_max;
    sweep_t sw = {0.0, 0.0, 0};
    /* a logarithmic grid of 4000 points over 1e-16 c ... c (the last point replaced by the
     * double just below c) */
    for (int k = 0; k <= 4000; k++) {
        const double rho = k == 4000 ? nextafter(c, 0.0) : c * pow(10.0, -16.0 + 16.0 * k / 4000.0);
        check_point(&es, rho, &sw);
    }
    /* approaching the clamp: 1 - 10^-j and the last 64 doubles below c */
    for (int j = 1; j <= 15; j++) {
        check_point(&es, c * (1.0 - pow(10.0, -j)), &sw);
    }
    double rho = c;
    for (int k = 0; k < 64; k++) {
        rho = nextafter(rho, 0.0);
        check_point(&es, rho, &sw);
    }
    CHECK_INT(sw.bad_status, 0, TFMT("E = %g, pi %d, dR = %g: status OK below the clamp", E, with_pi, dR));
    CHECK_TRUE(sw.worst <= 1e-12,
               TFMT("E = %g, pi %d, dR = %g: F within 1e-12 of the reference (worst %.2e at rho = %.17g c)",
                    E, with_pi, dR, sw.worst, sw.at_ratio));
    if (getenv("CSFH_TEST_VERBOSE") != NULL) {
        printf("  worst relative error of F %.3e at rho/c = %.17g\n", sw.worst, sw.at_ratio);
    }
}

static void test_clamp_and_sign(void)
{
    csfh_esdu_t es;
    csfh_esdu_setup(210e9, 0.3, 210e9, 0.3, 0.05, 0.02, 1, &es);
    const double c = es.a * es.F_max;
    const double over[4] = {c, nextafter(c, INFINITY), 2.0 * c, INFINITY};
    for (int i = 0; i < 4; i++) {
        double F = -1.0;
        CHECK_INT(csfh_esdu_force(&es, over[i], &F), CSFH_LAW_ESDU_CLAMPED,
                  TFMT("rho = %.17g c: clamped", over[i] / c));
        CHECK_ABS(F, es.F_max, 0.0, TFMT("rho = %.17g c: F = F*", over[i] / c));
    }
    const double below = nextafter(c, 0.0);
    double F_below;
    csfh_esdu_force(&es, below, &F_below);
    CHECK_TRUE(F_below < es.F_max && F_below > 0.9999999 * es.F_max,
               "the double below the clamp: F just below F*");
    const double none[3] = {0.0, -1e-6, NAN};
    for (int i = 0; i < 3; i++) {
        double F = -1.0;
        CHECK_INT(csfh_esdu_force(&es, none[i], &F), CSFH_LAW_OK, TFMT("rho = %g: OK", none[i]));
        CHECK_ABS(F, 0.0, 0.0, TFMT("rho = %g: F = 0", none[i]));
    }
    /* the smallest positive indentations: finite, positive, increasing */
    double F_min, F_sub;
    csfh_esdu_force(&es, DBL_MIN, &F_min);
    csfh_esdu_force(&es, 4.9e-324, &F_sub);
    CHECK_TRUE(isfinite(F_min) && F_min > 0.0 && F_sub >= 0.0 && F_sub < F_min,
               "rho = DBL_MIN and the smallest subnormal: 0 <= F finite, increasing");
    CHECK_CLOSE(F_min, (double)ref_force(&es, DBL_MIN), 1e-12, "rho = DBL_MIN: F to 1e-12");
}

/* reading I3: K_t = 1/(a s) times rho^n; where s >= 1e-3 (rho <= 0.9999995 c) to 1e-12 */
static void test_i3_stiffness(void)
{
    csfh_normal_law_t law;
    memset(&law, 0, sizeof law);
    law.law = CSFH_CONTACTLAW_LN_ESDU;
    law.esdu_reading = CSFH_ESDUREADING_I3;
    law.n = 1.5;
    csfh_esdu_setup(210e9, 0.3, 210e9, 0.3, 0.05, 0.02, 1, &law.esdu);
    const double c = law.esdu.a * law.esdu.F_max;
    double worst = 0.0;
    for (int k = 0; k <= 1000; k++) {
        const double rho = 0.9999995 * c * pow(10.0, -16.0 + 16.0 * k / 1000.0);
        double F_el;
        csfh_normal_elastic_force(&law, rho, &F_el);
        const long double K_ref = 1.0L / ((long double)law.esdu.a * ref_log_ratio(rho, c));
        const long double F_ref = K_ref * powl((long double)rho, 1.5L);
        worst = fmax(worst, (double)fabsl(((long double)F_el - F_ref) / F_ref));
    }
    CHECK_TRUE(worst <= 1e-12, TFMT("I3: K_t rho^n within 1e-12 of the reference (worst %.2e)", worst));
}

int main(void)
{
    test_force_sweep(100e9, 1, 0.02);
    test_force_sweep(210e9, 0, 0.02);
    test_force_sweep(210e9, 1, 1e-5);
    test_force_sweep(2e9, 1, 3.0); /* clamp indentation above 1 m */
    test_clamp_and_sign();
    test_i3_stiffness();
    return TEST_SUMMARY();
}
