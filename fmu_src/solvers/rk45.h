/* An explicit Runge-Kutta 5(4) integrator with dense output and root finding, for small
 * non-stiff systems: the method of Dormand and Prince (7 stages, first same as last, so 6
 * right-hand sides per accepted step), local error of the embedded 4th-order solution in a
 * weighted RMS norm, PI step-size control, Shampine's free 4th-order continuous extension, and
 * root finding on it (Muller's parabola in a bracket). A stiffness indicator (h times the local
 * Lipschitz estimate from the last two stages, against the method's stability boundary) tells
 * the caller when the steps are held by stability, not accuracy.
 *
 * Why our own and not SUNDIALS ARKODE's ERKStep (same Dormand-Prince table, root finding and
 * dense output): for six states its per-step bookkeeping (vector operations through function
 * pointers, Hermite interpolation that costs an extra right-hand side per evaluation at degree 4)
 * costs more than the steps themselves; benchmarks/rk45/bench_rk45_arkode.c measures both in the
 * same loop.
 *
 * No FMI types and no SUNDIALS: the co-simulation stepper (cosimulation.c) drives it. One step per
 * call (rk45_step), like CVODE's CV_ONE_STEP mode: a step may end anywhere; the state at any time
 * inside the last step comes from rk45_dense. */
#ifndef CSFH_RK45_H
#define CSFH_RK45_H

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* ydot = f(t, y): 0 on success, > 0 recoverable (the step is retried 4x smaller), < 0 fatal. */
typedef int (*rk45_rhs_fn)(double t, const double *y, double *ydot, void *user);
/* g(t, y), n_roots values: 0 on success, nonzero fails the step. */
typedef int (*rk45_root_fn)(double t, const double *y, double *g, void *user);

/* Return values of rk45_init, rk45_step and rk45_dense. */
enum {
    RK45_SUCCESS = 0,
    RK45_ROOT = 1,              /* rk45_step: a root of g inside the step (t, y: at the root) */
    RK45_TSTOP = 2,             /* rk45_step: the step ended at the stop time (rk45_set_stop_time) */
    RK45_MEM_FAIL = -1,
    RK45_ILL_INPUT = -2,
    RK45_ERR_FAILURE = -3,      /* the error test failed repeatedly */
    RK45_RHS_FAILURE = -4,      /* f failed unrecoverably, or recoverably too often */
    RK45_ROOT_FAILURE = -5,     /* g failed */
    RK45_TOO_SMALL = -6         /* the step size underflowed the time's resolution */
};

typedef struct {
    long steps;      /* accepted steps */
    long fails;      /* rejected attempts (error test or recoverable f failure) */
    long rhs;        /* evaluations of f */
    long roots;      /* evaluations of g */
    long stiff;      /* accepted steps whose h |lambda| estimate (from the last two stages) lies
                        beyond 2.5, near the method's stability boundary 3.3: steps held by
                        stability rather than accuracy (stiffness indicator) */
} rk45_stats_t;

typedef struct rk45 rk45_t;

/* n >= 1 states, n_roots >= 0 root functions (g may be NULL when n_roots = 0). NULL when out of
 * memory or n < 1. */
rk45_t *rk45_create(int n, int n_roots, rk45_rhs_fn f, rk45_root_fn g, void *user);
void rk45_free(rk45_t *r);

/* Relative tolerance and n absolute tolerances (> 0; copied). */
int rk45_set_tolerances(rk45_t *r, double rtol, const double *atol);

/* (Re)start at (t0, y0): evaluates f and g there. The first step is h_first if > 0, else
 * estimated (one more evaluation of f); at most h_max_first either way. Statistics are kept
 * across restarts. */
int rk45_init(rk45_t *r, double t0, const double *y0, double h_max_first, double h_first);

/* A stop time > the current time: no step goes beyond it, the one that reaches it ends exactly
 * there and rk45_step returns RK45_TSTOP (after any root before it); then it is cleared. A
 * (re)start clears it too. RK45_ILL_INPUT if not after the current time. */
int rk45_set_stop_time(rk45_t *r, double t_stop);

/* One step: the next root inside the step already taken, or a new step (with its roots). On
 * RK45_SUCCESS (t, y) is the end of the step, on RK45_ROOT the root (the first point found past
 * the sign change, within 100 eps of it); on failure the last successful point. */
int rk45_step(rk45_t *r, double *t, double *y);

/* The state (k = 0) or its time derivative (k = 1) at t inside the last step [t_n - h, t_n]
 * (round-off beyond its ends is clamped). RK45_ILL_INPUT outside it or before a step. */
int rk45_dense(rk45_t *r, double t, int k, double *out);

/* The last step as a self-contained record of RK45_RECORD_SIZE(n) doubles (for analysing it
 * later, after further steps): its times, Shampine's coefficients, the states and f at both
 * ends. RK45_ILL_INPUT before a step. */
#define RK45_RECORD_SIZE(n) (2 + 8 * (size_t)(n))
int rk45_save_step(rk45_t *r, double *record);
/* The state (k = 0) or its derivative (k = 1) at t in a record's step (clamped to it). */
void rk45_record_dense(const double *record, int n, double t, int k, double *out);
double rk45_record_start(const double *record); /* the step's start time */
double rk45_record_end(const double *record);   /* the step's end time */
/* The state (end = 0: at the start, 1: at the end) and f there, exactly as the step used them. */
const double *rk45_record_y(const double *record, int n, int end);
const double *rk45_record_f(const double *record, int n, int end);

double rk45_current_time(const rk45_t *r); /* t_n: the end of the last step (or the start) */
double rk45_last_step(const rk45_t *r);    /* h of the last step, 0 before it */
double rk45_next_step(const rk45_t *r);    /* h the step-size control proposes next (0: none yet) */
void rk45_get_stats(const rk45_t *r, rk45_stats_t *s);
const char *rk45_message(const rk45_t *r); /* what the last failure was, with its values */
const char *rk45_flag_name(int flag);

CSFH_INTERNAL_END

#endif
