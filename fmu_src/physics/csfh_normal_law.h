/* Normal contact force laws (docs/model.md §4; paper Eqs. 13-25), selected by
 * csfh_contact_law_t behind one interface. Pure functions, SI units. */
#ifndef CSFH_NORMAL_LAW_H
#define CSFH_NORMAL_LAW_H

#include "csfh_enums.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* ESDU-78035 journal-bearing law rho(F) = a F [ln(F_max/F) + 1] (Eq. 18 rewritten):
 * a = (sigma1 + sigma2)/L, F_max = F* = 4 L dR/(sigma1 + sigma2) (docs/model.md §4.5). */
typedef struct {
    double a;     /* m/N */
    double F_max; /* N: rho(F) is increasing only below F*, rho(F*) = 4 dR */
} csfh_esdu_t;

typedef struct {
    csfh_contact_law_t law;
    csfh_esdu_reading_t esdu_reading;
    double K;     /* stiffness of the power law K rho^n, N/m^n (unused by LN_ESDU I2) */
    double n;     /* exponent */
    double xi;    /* damping factor of F = F_el (1 + xi rhodot / rhodot0) */
    double v_min; /* floor of the onset rate rhodot0, m/s (docs/model.md §5.2) */
    csfh_esdu_t esdu;
} csfh_normal_law_t;

/* Status of a force evaluation. */
#define CSFH_LAW_OK 0
#define CSFH_LAW_ESDU_CLAMPED 1 /* rho beyond the ESDU validity range: F held at F* */

/* Material constant sigma = (1 - nu^2)/E (Eq. 15), or (1 - nu^2)/(pi E) with with_pi. */
double csfh_sigma(double E, double nu, int with_pi);

/* Hertz sphere stiffness K = 4/(3 (sigma1 + sigma2)) sqrt(R_eff) (Eq. 14), N/m^1.5; R_eff is
 * R1 R2/(R1 + R2) (as printed) or, with internal, R1 R2/(R2 - R1) (conformal, docs/model.md §4.1). */
double csfh_stiffness_spheres(double E1, double nu1, double E2, double nu2, double R1, double R2,
                              int internal);

/* Cylinder stiffness (pi/4) E* L (Eqs. 16-17 times the contact length, docs/model.md §4.2), N/m. */
double csfh_stiffness_cylinders(double E1, double nu1, double E2, double nu2, double L);

/* Contact modulus E* of Eq. (17): 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (docs/model.md §4.2), Pa. */
double csfh_contact_modulus(double E1, double nu1, double E2, double nu2);

/* Hertz line contact of parallel cylinders along the length L under the normal force F_N
 * (docs/model.md §14.3): the peak pressure p0 = sqrt(F_N E* / (pi L R')) [Pa], returned, and the
 * half-width of the contact strip b = sqrt(4 F_N R' / (pi L E*)) [m] in *half_width (if not
 * NULL); R' is the effective radius, for the pin in the bore 1/R' = 1/R1 - 1/R2. Both are 0 for
 * F_N <= 0. */
double csfh_hertz_line_pressure(double F_N, double E_star, double L, double R_eff,
                                double *half_width);

/* Damping factor xi (docs/model.md §4.4): LN 3(1 - cr^2)/4, Hunt-Crossley 3(1 - cr)/2,
 * Flores 8(1 - cr)/(5 cr); 0 for CSFH_CONTACTLAW_NONE. */
double csfh_damping_factor(csfh_contact_law_t law, double cr);

void csfh_esdu_setup(double E1, double nu1, double E2, double nu2, double L, double dR,
                     int with_pi, csfh_esdu_t *esdu);

/* rho(F), Eq. (18). */
double csfh_esdu_indentation(const csfh_esdu_t *esdu, double F);

/* Inverse F(rho) by safeguarded Newton on ln F inside a bracket; returns CSFH_LAW_OK or
 * CSFH_LAW_ESDU_CLAMPED (rho >= 4 dR: F = F*). */
int csfh_esdu_force(const csfh_esdu_t *esdu, double rho, double *F);

/* Tangent stiffness dF/drho = 1/(a ln(F_max/F)), N/m (docs/model.md §4.5). */
double csfh_esdu_tangent_stiffness(const csfh_esdu_t *esdu, double F);

/* Elastic part F_el(rho) of the selected law (rho > 0). */
int csfh_normal_elastic_force(const csfh_normal_law_t *law, double rho, double *F_el);

/* F_N = F_el(rho) [1 + xi rhodot / max(rhodot0, v_min)], clamped >= 0; 0 for rho <= 0. */
int csfh_normal_force(const csfh_normal_law_t *law, double rho, double rho_dot,
                      double rho_dot_onset, double *F_N);

/* Elastic energy: integral of F_el from 0 to rho (closed form except LN_ESDU I3: quadrature). */
double csfh_normal_elastic_energy(const csfh_normal_law_t *law, double rho);

CSFH_INTERNAL_END

#endif
