/* The paper's event-driven scheme (section 6 and Fig. 3), as a baseline: explicit fourth-order
 * Runge-Kutta with a nominal step h0; when a step would end with the bodies interpenetrating by
 * more than the event tolerance, the step is bisected until the penetration is within the
 * tolerance, the contact starts there (onset rate captured), and the integration continues with
 * the reduced step until the contact ends, after which the step returns to h0. The right-hand side
 * is the FMU's with the contact force by the gap (csfh_model_derivatives_by_gap): the scheme has
 * no root finding, so the force acts wherever the gap is negative. */
#ifndef CSFH_RK4EVENT_H
#define CSFH_RK4EVENT_H

#include <stddef.h>

#include "csfh_model.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

typedef struct {
    double h0;    /* nominal step, s (paper: 2e-4) */
    double tol;   /* event tolerance on the penetration at the onset, m (paper: 1e-4) */
    double h_min; /* bisection stops here (then the step is accepted as is), s */
} csfh_rk4_options_t;

/* One contact, as every integrator of the harness reports it. */
enum {
    CSFH_CR_T_ONSET,        /* s */
    CSFH_CR_ONSET_SPEED,    /* indentation rate at the onset, m/s */
    CSFH_CR_T_RELEASE,      /* s (NaN while the contact lasts) */
    CSFH_CR_RELEASE_SPEED,  /* separation speed dg/dt at the release, m/s */
    CSFH_CR_PEAK_F_N,       /* largest normal force seen at an accepted step, N */
    CSFH_CR_MAX_INDENTATION,/* largest indentation seen at an accepted step, m */
    CSFH_CR_NCOLS
};

/* Record columns: t, x, y, theta, vx, vy, omega, F_N, F_T, indentation, v_T, gap, energy. */
#define CSFH_RK4_RECORD_NCOLS 13

typedef struct {
    long long steps;          /* accepted steps */
    long long rejected_steps; /* bisected (rejected) attempts */
    long long rhs;            /* right-hand-side evaluations */
    size_t records, contacts;
} csfh_rk4_stats_t;

/* Integrate from x0 at t0 to t_end. A record is written at every output time t0 + k dt_out
 * (the state at the first accepted step at or after it: the scheme has no dense output), plus the
 * initial state; every contact writes a row of CSFH_CR_NCOLS to contacts. Returns CSFH_OK or
 * CSFH_ERR_NONFINITE. */
int csfh_rk4_event_run(csfh_model_t *m, const csfh_rk4_options_t *o, double t0,
                       const double x0[6], double t_end, double dt_out, double *records,
                       size_t max_records, double *contacts, size_t max_contacts, double x_end[6],
                       csfh_rk4_stats_t *stats);

CSFH_INTERNAL_END

#endif
