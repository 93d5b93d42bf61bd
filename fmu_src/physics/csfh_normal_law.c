#include "csfh_normal_law.h"

#include <math.h>
#include <stddef.h>

#include "csfh_common.h"

double csfh_sigma(double E, double nu, int with_pi)
{
    return (1.0 - nu * nu) / (with_pi ? CSFH_PI * E : E); /* Eq. (15) */
}

double csfh_stiffness_spheres(double E1, double nu1, double E2, double nu2, double R1, double R2,
                              int internal)
{
    const double sum = csfh_sigma(E1, nu1, 0) + csfh_sigma(E2, nu2, 0);
    const double R_eff = internal ? R1 * R2 / (R2 - R1) : R1 * R2 / (R1 + R2);
    return 4.0 / (3.0 * sum) * sqrt(R_eff); /* Eq. (14) */
}

double csfh_stiffness_cylinders(double E1, double nu1, double E2, double nu2, double L)
{
    const double E_star = 1.0 / (csfh_sigma(E1, nu1, 0) + csfh_sigma(E2, nu2, 0)); /* Eq. (17) */
    return 0.25 * CSFH_PI * E_star * L;                                            /* Eq. (16) */
}

double csfh_contact_modulus(double E1, double nu1, double E2, double nu2)
{
    return 1.0 / (csfh_sigma(E1, nu1, 0) + csfh_sigma(E2, nu2, 0)); /* Eq. (17) */
}

double csfh_hertz_line_pressure(double F_N, double E_star, double L, double R_eff,
                                double *half_width)
{
    if (!(F_N > 0.0)) {
        if (half_width != NULL) {
            *half_width = 0.0;
        }
        return 0.0;
    }
    /* docs/model.md Eqs. (14.5)-(14.6): p0 = 2 F_N / (pi b L) */
    if (half_width != NULL) {
        *half_width = sqrt(4.0 * F_N * R_eff / (CSFH_PI * L * E_star));
    }
    return sqrt(F_N * E_star / (CSFH_PI * L * R_eff));
}

double csfh_damping_factor(csfh_contact_law_t law, double cr)
{
    switch (law) {
    case CSFH_CONTACTLAW_LN_SPHERES:
    case CSFH_CONTACTLAW_LN_CYLINDERS:
    case CSFH_CONTACTLAW_LN_ESDU:
        return 0.75 * (1.0 - cr * cr); /* Eq. (22) */
    case CSFH_CONTACTLAW_HUNTCROSSLEY:
        return 1.5 * (1.0 - cr); /* Eq. (21) */
    case CSFH_CONTACTLAW_FLORES:
        return 8.0 * (1.0 - cr) / (5.0 * cr); /* Eq. (23) */
    case CSFH_CONTACTLAW_NONE:
    default:
        return 0.0;
    }
}

void csfh_esdu_setup(double E1, double nu1, double E2, double nu2, double L, double dR,
                     int with_pi, csfh_esdu_t *esdu)
{
    const double sum = csfh_sigma(E1, nu1, with_pi) + csfh_sigma(E2, nu2, with_pi);
    esdu->a = sum / L;
    esdu->F_max = 4.0 * L * dR / sum;
}

double csfh_esdu_indentation(const csfh_esdu_t *esdu, double F)
{
    if (F <= 0.0) {
        return 0.0;
    }
    return esdu->a * F * (log(esdu->F_max / F) + 1.0); /* Eq. (18) */
}

/* First guess for s = ln(F_max/F) solving s - ln(1 + s) = L (Eq. 18 with r = rho/(4 dR) = e^-L):
 * near the clamp the inversion series in sigma = sqrt(2 L) (the series of the Gamma function's
 * saddle point), otherwise s = L + ln(1 + s) expanded once about s = L. Relative error <= 2.4e-3,
 * below 1e-3 outside 2.38 < L < 3.96. */
static double esdu_guess(double L, double sigma)
{
    if (L < 3.3) {
        const double g = sigma;
        return g * (1.0 + g * (1.0 / 3.0 + g * (1.0 / 36.0 +
                    g * (-1.0 / 270.0 + g * (1.0 / 4320.0 + g * (1.0 / 17010.0))))));
    }
    const double l = log1p(L);
    return L + l + l / (1.0 + L);
}

/* Solves s - ln(1 + s) = L for s > 0 inside the bracket sigma <= s <= sigma + 2 L (valid for all
 * L > 0). Each step sums the inverse function's Taylor series to fifth order: with the residual
 * h = L - g(s), t = h ds/dL = h (1 + s)/s and v = t/(s (1 + s)), the correction is
 * t (1 - v/2 + (2s + 3) v^2/6 - (6s^2 + 20s + 15) v^3/24). A correction below 1e-3 s leaves an
 * error below the rounding of s; a step leaving the bracket is replaced by bisection. */
static double esdu_log_ratio(double L)
{
    const double sigma = sqrt(2.0 * L);
    double s = esdu_guess(L, sigma);
    if (L < 5e-5) {
        return s; /* the series alone is exact to rounding (next term ~ 2.6e-5 sigma^7) */
    }
    double lo = sigma, hi = sigma + 2.0 * L;
    if (!(s > lo && s < hi)) {
        s = 0.5 * (lo + hi);
    }
    for (int it = 0; it < 100; it++) {
        const double h = L - (s - log1p(s));
        if (h > 0.0) {
            lo = s;
        } else {
            hi = s;
        }
        const double t = h * (1.0 + s) / s, v = t / (s * (1.0 + s));
        double next = s + t * (1.0 + v * (-0.5 + v * ((2.0 * s + 3.0) / 6.0 -
                                                      v * ((6.0 * s + 20.0) * s + 15.0) / 24.0)));
        const int bisect = !(next >= lo && next <= hi); /* a zero correction stays */
        if (bisect) {
            next = 0.5 * (lo + hi);
        }
        const double step = fabs(next - s);
        s = next;
        if (bisect ? hi - lo <= 1e-15 * s : step <= 1e-3 * s) {
            break;
        }
    }
    return s;
}

/* F(rho) of Eq. (18) and s = ln(F_max/F) (F = 0 at rho <= 0); returns CSFH_LAW_ESDU_CLAMPED (F = F*,
 * s = 0) at rho >= 4 dR */
static int esdu_solve(const csfh_esdu_t *esdu, double rho, double *F, double *s)
{
    const double c = esdu->a * esdu->F_max; /* = 4 dR, the indentation at F* */
    if (!(rho > 0.0)) {
        *F = 0.0;
        *s = INFINITY;
        return CSFH_LAW_OK;
    }
    if (!(rho < c)) {
        *F = esdu->F_max;
        *s = 0.0;
        return CSFH_LAW_ESDU_CLAMPED;
    }
    /* L = -ln(rho/c) > 0; near the clamp from the exact difference c - rho (Sterbenz), since F
     * there is as sensitive to L as 1/s */
    const double r = rho / c;
    const double L = r > 0.5 ? -log1p((rho - c) / c) : (r > 0.0 ? -log(r) : log(c) - log(rho));
    *s = esdu_log_ratio(L);
    *F = rho / (esdu->a * (1.0 + *s)); /* Eq. (18): rho = a F (s + 1) */
    return CSFH_LAW_OK;
}

int csfh_esdu_force(const csfh_esdu_t *esdu, double rho, double *F)
{
    double s;
    return esdu_solve(esdu, rho, F, &s);
}

double csfh_esdu_tangent_stiffness(const csfh_esdu_t *esdu, double F)
{
    /* d rho/dF = a ln(F_max/F) (docs/model.md §4.5) */
    return 1.0 / (esdu->a * log(esdu->F_max / F));
}

int csfh_normal_elastic_force(const csfh_normal_law_t *law, double rho, double *F_el)
{
    if (law->law != CSFH_CONTACTLAW_LN_ESDU) {
        *F_el = law->K * csfh_pow_n(rho, law->n); /* Eq. (13) */
        return CSFH_LAW_OK;
    }
    double F_esdu, s;
    const int status = esdu_solve(&law->esdu, rho, &F_esdu, &s);
    if (law->esdu_reading == CSFH_ESDUREADING_I2) {
        *F_el = F_esdu; /* reading I2 (docs/model.md §4.6) */
    } else {
        /* reading I3: tangent stiffness 1/(a s) used as K in K rho^n (docs/model.md §4.6) */
        const double K_t = status == CSFH_LAW_OK && F_esdu > 0.0
                               ? 1.0 / (law->esdu.a * s)
                               : csfh_esdu_tangent_stiffness(&law->esdu, 0.5 * law->esdu.F_max);
        *F_el = K_t * csfh_pow_n(rho, law->n);
    }
    return status;
}

int csfh_normal_force(const csfh_normal_law_t *law, double rho, double rho_dot,
                      double rho_dot_onset, double *F_N)
{
    if (!(rho > 0.0) || law->law == CSFH_CONTACTLAW_NONE) {
        *F_N = 0.0;
        return CSFH_LAW_OK;
    }
    double F_el;
    const int status = csfh_normal_elastic_force(law, rho, &F_el);
    const double onset = rho_dot_onset > law->v_min ? rho_dot_onset : law->v_min; /* 5.2 */
    const double F = F_el * (1.0 + law->xi * rho_dot / onset); /* Eqs. (21)-(23) */
    *F_N = F > 0.0 ? F : 0.0; /* no adhesion */
    return status;
}

/* Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre polynomial). */
static void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; i++) {
        double z = cos(CSFH_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; k++) {
                const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16) {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}

double csfh_normal_elastic_energy(const csfh_normal_law_t *law, double rho)
{
    if (!(rho > 0.0) || law->law == CSFH_CONTACTLAW_NONE) {
        return 0.0;
    }
    if (law->law != CSFH_CONTACTLAW_LN_ESDU) {
        return law->K * rho * csfh_pow_n(rho, law->n) / (law->n + 1.0);
    }
    if (law->esdu_reading == CSFH_ESDUREADING_I2) {
        /* closed form: U = a F^2 [ln(F_max/F)/2 + 1/4] (dU/drho = F with rho(F) of Eq. 18) */
        double F;
        csfh_esdu_force(&law->esdu, rho, &F);
        return law->esdu.a * F * F * (0.5 * log(law->esdu.F_max / F) + 0.25);
    }
    /* I3: integral of K_t(s) s^n over [0, rho], Gauss-Legendre in s = rho x^2 (smooths the
     * logarithmic behaviour of K_t at s -> 0) */
    enum { NQ = 24 };
    double xg[NQ], wg[NQ], sum = 0.0;
    gauss_legendre(NQ, xg, wg);
    for (int i = 0; i < NQ; i++) {
        const double x = 0.5 * (xg[i] + 1.0); /* x in (0, 1), ds = 2 rho x dx */
        double F_el;
        csfh_normal_elastic_force(law, rho * x * x, &F_el);
        sum += 0.5 * wg[i] * F_el * 2.0 * rho * x;
    }
    return sum;
}
