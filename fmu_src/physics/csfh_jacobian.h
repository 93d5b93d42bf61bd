/* Analytic partial derivatives of the right-hand side and of the continuous outputs with respect
 * to the states and the inputs (docs/model.md §15): the flexure force, the contact kinematics, the
 * normal laws (LN_ESDU's implicit force by the implicit-function theorem), Ambrosio friction and
 * the base excitation. Pure functions, no counters, SI units. */
#ifndef CSFH_JACOBIAN_H
#define CSFH_JACOBIAN_H

#include "csfh_contact.h"
#include "csfh_flexure.h"
#include "csfh_model.h"
#include "csfh_normal_law.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* The inputs the right-hand side depends on, in this order: F_ext[1], F_ext[2], M_ext,
 * a_base[1], a_base[2]. */
#define CSFH_N_JAC_INPUTS 5

/* dQ[i][j] = d Q_e,i / d q_j of csfh_flexure_force, and dE[j] = d E_flexure / d q_j (dE may be
 * NULL). */
void csfh_flexure_force_jacobian(const csfh_flexure_t *flex, const double q[3], double dQ[3][3],
                                 double dE[3]);

/* Derivatives of the contact kinematics at q with respect to q (kin from csfh_contact_kinematics
 * at the same q; all zero where |e| -> 0, the guard of the kinematics). */
typedef struct {
    double dn[2][3];  /* d n_c,i / d q_j */
    double dt[2][3];  /* d t_c,i / d q_j */
    double dDN[3][3]; /* d DN_i / d q_j */
    double dDT[3][3]; /* d DT_i / d q_j */
} csfh_contact_kin_jac_t;

void csfh_contact_kinematics_jacobian(double R1, const csfh_contact_kin_t *kin,
                                      csfh_contact_kin_jac_t *jac);

/* d F_el / d rho of csfh_normal_elastic_force (rho > 0): K n rho^(n-1) for the power laws; for
 * LN_ESDU reading I2 the implicit force's 1/(a ln(F* / F)) (0 where it is clamped at F*), for I3
 * the tangent stiffness's own change with rho added. */
double csfh_normal_elastic_stiffness(const csfh_normal_law_t *law, double rho);

/* dF_N/drho and dF_N/drhodot of csfh_normal_force at the same arguments (the onset rate held:
 * a discrete state); both 0 where F_N = 0 (no contact, or the force clamped at 0). */
void csfh_normal_force_partials(const csfh_normal_law_t *law, double rho, double rho_dot,
                                double rho_dot_onset, double *dF_drho, double *dF_drhodot);

/* dF_T/dF_N and dF_T/dv_T of csfh_ambrosio_force (one-sided at |v_T| = v0, v1: the branch the
 * force takes). */
void csfh_ambrosio_partials(double fd, double v0, double v1, double F_N, double v_T,
                            double *dF_dFN, double *dF_dvT);

/* The contact force of csfh_model_contact at x = [q, u] (the current discrete state) and its
 * derivatives with respect to x, with the gap, the indentation rate and the sliding speed. */
typedef struct {
    int touching;
    double gap, rho_dot, v_T, F_N, F_T, F_el;
    double dgap[6], drho_dot[6], dv_T[6], dF_N[6], dF_T[6];
    double Q[3], dQ[3][6]; /* Q_c = DN^T F_N + DT^T F_T and d Q_c / d x */
} csfh_contact_partials_t;

void csfh_model_contact_partials(const csfh_model_t *m, const double x[6],
                                 csfh_contact_partials_t *cp);

/* A[i][j] = d xdot_i / d x_j and B[i][k] = d xdot_i / d v_k (v the inputs of CSFH_N_JAC_INPUTS)
 * of csfh_model_derivatives at x (the pulse of §14.8 depends on time only). CSFH_OK, or
 * CSFH_ERR_NONFINITE if an entry is not finite. */
int csfh_model_rhs_jacobian(const csfh_model_t *m, const double x[6], double A[6][6],
                            double B[6][CSFH_N_JAC_INPUTS]);

/* The continuous outputs of csfh_model_outputs (instantaneous: the peaks of model exchange)
 * that depend on the state, and their derivatives with respect to it. */
enum {
    CSFH_JOUT_F_N,
    CSFH_JOUT_F_T,
    CSFH_JOUT_INDENTATION,
    CSFH_JOUT_GAP,
    CSFH_JOUT_V_T,
    CSFH_JOUT_INDENTATION_RATE,
    CSFH_JOUT_E_TOTAL,
    CSFH_JOUT_E_KINETIC,
    CSFH_JOUT_E_GRAVITY,
    CSFH_JOUT_E_FLEXURE,
    CSFH_JOUT_E_CONTACT,
    CSFH_JOUT_STRESS_MAX,
    CSFH_JOUT_STRESS_LOCATION,
    CSFH_JOUT_PRESSURE_MAX,
    CSFH_JOUT_HALF_WIDTH,
    CSFH_JOUT_F_T_ABS,
    CSFH_JOUT_STRESS_MARGIN,
    CSFH_JOUT_PRESSURE_MARGIN,
    CSFH_N_JOUT
};

/* D[k][j] = d output_k / d x_j (k of CSFH_JOUT_*); the inputs enter the outputs only through
 * a_frame = a_base + pulse (d a_frame / d a_base = I). CSFH_OK or CSFH_ERR_NONFINITE. */
int csfh_model_output_jacobian(const csfh_model_t *m, const double x[6], double D[CSFH_N_JOUT][6]);

CSFH_INTERNAL_END

#endif
