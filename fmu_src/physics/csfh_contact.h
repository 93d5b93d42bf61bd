/* Contact kinematics of the conjugate cylinders, with the corrected arm a = s1 - R1 n_c
 * (docs/model.md §3; paper Eqs. 10-12, 32, 34, 38, 39). Pure functions, SI units. */
#ifndef CSFH_CONTACT_H
#define CSFH_CONTACT_H

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

typedef struct {
    double gap;     /* g = delta - |e|, m (contact when <= 0) */
    double e_norm;  /* |e|, m */
    double n[2];    /* n_c = -e/|e|: from the contact point toward O2; F_N acts along +n_c */
    double t[2];    /* t_c = rot90(n_c) */
    double a[2];    /* G1 -> contact point C of body 1, a = s1 - R1 n_c */
    double DN[3];   /* normal Jacobian row [n_c^T, a x n_c]: gamma_N = DN u = dg/dt */
    double DT[3];   /* tangent Jacobian row [t_c^T, a x t_c]: v_T = DT u */
} csfh_contact_kin_t;

/* Gap g(q) = delta - |r + A(theta) s1bar| (Eq. 32). */
double csfh_contact_gap(double delta, const double s1bar[2], const double q[3]);

/* Full kinematics at q. With |e| -> 0 (only possible when delta -> 0) the normal is taken along
 * +Y so that everything stays finite. */
void csfh_contact_kinematics(double delta, double R1, const double s1bar[2], const double q[3],
                             csfh_contact_kin_t *kin);

/* Generalized contact force Q_c = D^T [F_N, F_T] (docs/model.md §3), added to Q. */
void csfh_contact_add_force(const csfh_contact_kin_t *kin, double F_N, double F_T, double Q[3]);

CSFH_INTERNAL_END

#endif
