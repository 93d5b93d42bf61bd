/* Moreau-Jean midpoint time stepping for the single frictional contact (docs/model.md §6,
 * paper Eqs. 31-39), written as a recipe: system (csfh_model_t: smooth forces and contact
 * kinematics, the same functions the FMU uses), law (Newton restitution + Coulomb friction with
 * f_a / f_d), integrator (midpoint drift-kick-drift) and solver (exact case enumeration of the
 * 2-D one-contact problem, no iterations). Impulses Lambda [N s] are the unknowns. */
#ifndef CSFH_MOREAU_H
#define CSFH_MOREAU_H

#include <stddef.h>

#include "csfh_model.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

typedef enum {
    CSFH_STICK_PAPER = 1,  /* f_a decides whether an arriving contact sticks (paper-literal) */
    CSFH_STICK_MEMORY = 2  /* an arriving sliding contact is stopped only if f_d suffices; once
                              stuck it stays stuck while |Lambda_T| <= f_a Lambda_N (6.4) */
} csfh_stick_rule_t;

typedef struct {
    double h;       /* step, s */
    int stick_rule; /* csfh_stick_rule_t */
    double v_eps;   /* restitution only for closing contacts gamma_A,N < -v_eps, m/s (6.3) */
    double v_stick; /* memory rule: arriving with |gamma_A,T| <= v_stick counts as sticking */
    double g_tol;   /* the contact is active when g(q_M) <= g_tol, m */
} csfh_moreau_options_t;

/* Result of the contact problem of one step. */
typedef enum {
    CSFH_MOREAU_FREE = 0,  /* gap open at the midpoint */
    CSFH_MOREAU_OPEN = 1,  /* active but separating: Lambda = 0 */
    CSFH_MOREAU_STICK = 2,
    CSFH_MOREAU_SLIP = 3,
    CSFH_MOREAU_FALLBACK = 4 /* no branch admissible (cannot happen for f_d |G_NT| < G_NN):
                                frictionless normal impulse */
} csfh_moreau_mode_t;

typedef struct {
    int mode;            /* csfh_moreau_mode_t */
    int restitution;     /* Newton restitution applied (closing contact) */
    double Lambda_N, Lambda_T; /* impulses of the step, N s */
    double gamma_A[2];   /* contact velocities (normal, tangential) at the step start */
    double gamma_E[2];   /* ... and at the step end (with the midpoint Jacobian) */
    double gap_M;        /* gap at the midpoint */
} csfh_moreau_step_t;

/* Memory carried from step to step. */
typedef struct {
    int sticking;   /* the previous step ended in stick */
    int active;     /* the previous step had an active contact */
} csfh_moreau_memory_t;

void csfh_moreau_default_options(csfh_moreau_options_t *o);

/* One step from (q, u) at the step start to the step end, in place. Returns CSFH_OK or
 * CSFH_ERR_NONFINITE. */
int csfh_moreau_step(csfh_model_t *m, const csfh_moreau_options_t *o, csfh_moreau_memory_t *mem,
                     double q[3], double u[3], csfh_moreau_step_t *info);

/* Columns of a record of csfh_moreau_run (one record per `record_every` steps). */
enum {
    CSFH_MR_T, CSFH_MR_X, CSFH_MR_Y, CSFH_MR_THETA, CSFH_MR_VX, CSFH_MR_VY, CSFH_MR_OMEGA,
    CSFH_MR_F_N,        /* largest Lambda_N/h of the steps since the last record, N */
    CSFH_MR_F_T,        /* Lambda_T/h of that same step, N */
    CSFH_MR_LAMBDA_N,   /* sum of Lambda_N since the last record, N s */
    CSFH_MR_LAMBDA_T,   /* sum of Lambda_T since the last record, N s */
    CSFH_MR_GAP,        /* gap at the record, m */
    CSFH_MR_INDENTATION,/* max(0, -gap), m */
    CSFH_MR_V_T,        /* tangential velocity of the contact point at the record, m/s */
    CSFH_MR_ENERGY,     /* kinetic + gravity + flexure, J */
    CSFH_MR_MODE,       /* mode of the step with the largest Lambda_N since the last record */
    CSFH_MR_NCOLS
};

/* Columns of an impact record: every step whose contact becomes active after a step without. */
enum {
    CSFH_MI_T,          /* time at the step start, s */
    CSFH_MI_GAMMA_N_A, CSFH_MI_GAMMA_T_A, CSFH_MI_GAMMA_N_E, CSFH_MI_GAMMA_T_E,
    CSFH_MI_LAMBDA_N, CSFH_MI_LAMBDA_T,
    CSFH_MI_MODE, CSFH_MI_RESTITUTION,
    CSFH_MI_OMEGA_E,    /* angular velocity after the step */
    CSFH_MI_NCOLS
};

typedef struct {
    long long steps, active_steps, stick_steps, slip_steps, fallback_steps, onsets;
    size_t records, impacts;     /* rows written */
    long long impacts_dropped;   /* onsets beyond the impact buffer */
} csfh_moreau_stats_t;

/* The statistics as CSFH_MOREAU_NSTATS integers, in the order of csfh_moreau_stats_t (the
 * harness's array: steps, active, stick, slip, fallback, onsets, records, impacts,
 * impacts_dropped). */
#define CSFH_MOREAU_NSTATS 9
void csfh_moreau_stats_array(const csfh_moreau_stats_t *s, long long out[CSFH_MOREAU_NSTATS]);

/* Integrate n_steps steps from x0 (6 states) at t0. Every `record_every` steps (and never more
 * than max_records) a row of CSFH_MR_NCOLS doubles is written to records (the first row is the
 * initial state); every contact onset writes a row of CSFH_MI_NCOLS to impacts (up to
 * max_impacts). The final state is written to x_end. Memory stays bounded by the buffers.
 * Returns CSFH_OK or CSFH_ERR_NONFINITE (the run stops at the first non-finite state). */
int csfh_moreau_run(csfh_model_t *m, const csfh_moreau_options_t *o, double t0, const double x0[6],
                    long long n_steps, long long record_every, double *records, size_t max_records,
                    double *impacts, size_t max_impacts, double x_end[6],
                    csfh_moreau_stats_t *stats);

CSFH_INTERNAL_END

#endif
