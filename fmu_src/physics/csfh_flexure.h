/* Circular-arc flexure: closed-form compliance, co-rotated stiffness and the generalized elastic
 * force on body 1 (docs/model.md §1.3, 2.2-2.5; paper Eqs. 5-9). Pure functions, SI units. */
#ifndef CSFH_FLEXURE_H
#define CSFH_FLEXURE_H

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* Beam of the flexure: a circular arc clamped at the root C2, loaded at the tip C1. */
typedef struct {
    double rho;       /* m    radius of the centreline */
    double beta;      /* rad  opening angle (0, 2 pi) */
    double E;         /* Pa   Young's modulus */
    double nu;        /* 1    Poisson's ratio */
    double h;         /* m    in-plane section height */
    double b;         /* m    out-of-plane section width */
    double kappa;     /* 1    shear correction factor (6/5 for a rectangle) */
    int bending_only; /* 1: bending compliance only; 0: bending + axial + shear */
} csfh_arc_beam_t;

/* Everything the force evaluation needs, computed once from the parameters. */
typedef struct {
    double K0[3][3];  /* stiffness at C1 in the body frame (= global at theta = 0) [N/m, N, N m] */
    double sbar[2];   /* G1 -> C1 in the body frame, m */
    int conservative; /* 1: fixed K0 (exact potential); 0: co-rotated K(theta) */
} csfh_flexure_t;

/* Tip compliance C in the tip frame (n, t, phi) of docs/model.md §2.2:
 * [dp_n, dp_t, dphi] = C [F_n, F_t, M]. Units m/N, 1/N, 1/(N m). */
void csfh_arc_compliance(const csfh_arc_beam_t *beam, double C[3][3]);

/* Inverse of a 3x3 matrix; returns 0 on success, -1 if singular or not finite. */
int csfh_mat3_inverse(const double A[3][3], double Ainv[3][3]);

/* Angle of the local frame R_nt = [n t] = A(angle) at the tip: the beam tangent at C1 for a
 * counter-clockwise arc from the root at phi_root (docs/model.md §1.3): phi_root + beta + pi/2. */
double csfh_flexure_frame_angle(double phi_root, double beta);

/* Precompute K0 = blk(R_nt) inv(C) blk(R_nt)^T and the attachment point
 * sbar = O_F + rho [cos(phi_root + beta), sin(phi_root + beta)] (G1 at the origin, theta0 = 0,
 * docs/model.md §1.2). Returns 0 on success, -1 if the compliance is singular. */
int csfh_flexure_setup(const csfh_arc_beam_t *beam, const double OF[2], double phi_root,
                       int conservative, csfh_flexure_t *flex);

/* Generalized elastic force of the beam ON body 1, reduced to G1, at q = [x, y, theta]:
 * Q_e = -T_e(s) K(theta) dp (docs/model.md §2.4). Returns the elastic energy 1/2 dp^T K dp [J]. */
double csfh_flexure_force(const csfh_flexure_t *flex, const double q[3], double Q[3]);

/* The wrench w = [F_x, F_y, M] that body 1 applies to the beam tip C1 at q, in the frame of the
 * beam's reference geometry (the arc of docs/model.md §1.2): body-frame components for the
 * co-rotated law (the beam turns with body 1), global components for the conservative law
 * (fixed K0). The same wrench as csfh_flexure_force's (w = K(theta) dp, docs/model.md §2.4). */
void csfh_flexure_tip_wrench(const csfh_flexure_t *flex, const double q[3], double w[3]);

/* The beam's section data for the stress outputs (docs/model.md §14.2), from the beam and the
 * root angle (csfh_arc_section_setup). */
typedef struct {
    double rho, beta;         /* m, rad */
    double area;              /* b h, m^2 */
    double section_modulus;   /* b h^2 / 6, m^3 */
    double cos_psi, sin_psi;  /* the tip frame n = e(psi) of docs/model.md §1.3 */
    double cos_beta, sin_beta;
} csfh_arc_section_t;

void csfh_arc_section_setup(const csfh_arc_beam_t *beam, double phi_root, csfh_arc_section_t *sec);

/* Largest normal stress over the arc under the tip wrench w (reference-frame components, as
 * csfh_flexure_tip_wrench gives), docs/model.md §14.2: with the internal axial force N(alpha) and
 * bending moment m(alpha) of Eq. (2.2) at the section alpha from the tip,
 *   sigma(alpha) = |N| / (b h) + 6 |m| / (b h^2)
 * (slender beam, straight-beam bending stress at the outer fibres, shear stress neglected).
 * m = (M + rho F_n) - rho N makes sigma a convex function of N, so its maximum over the arc lies
 * at the root, at the tip or where N is extreme (|N| = |F|): four candidates, no search. Returns
 * sigma_max [Pa] and, in *location (may be NULL), the arc angle of that section measured from
 * the root C2 [rad, 0 .. beta] (ties: the section nearest the root). */
double csfh_arc_stress_max(const csfh_arc_section_t *sec, const double w[3], double *location);

CSFH_INTERNAL_END

#endif
