/* The state of the explicit Runge-Kutta 5(4) (rk45.h), shared by its files: rk45.c (the steps
 * and their size), rk45_dense.c (dense output, saved steps), rk45_roots.c (root finding),
 * rk45_message.c (failure messages). */
#ifndef CSFH_RK45_INTERNAL_H
#define CSFH_RK45_INTERNAL_H

#include "rk45.h"

CSFH_INTERNAL_BEGIN

struct rk45 {
    int n, n_roots;
    rk45_rhs_fn f;
    rk45_root_fn g;
    void *user;
    double rtol;
    double *atol;
    /* solution: y at t_n, y_old at t_old = t_n - h_last; k[0..6] the stages of the last step
     * (k[0] = f(y_old); k[6] = f(y), the next step's first stage) */
    double t_n, t_old, h_last;
    double *y, *y_old, *y_new, *ys, *k[7];
    double *dense[5]; /* Shampine's coefficients of the last step (dense_valid) */
    double *w;        /* work vector */
    double *y_mid;    /* root finding: the state at the bracket's end last evaluated there */
    double h;         /* the next step's size (0: estimate it) */
    double h_max_first;
    double log_fac_old; /* PI control: log of the previous accepted error */
    int fsal_swap;    /* the last step was accepted: k[6] becomes the next k[0] */
    int rejected;     /* the last attempt was rejected: no growth on the next acceptance */
    int dense_valid;
    int initialized;
    int have_step;    /* a step has been taken since the last (re)start */
    /* root finding: g at t_n, and where the search in the last step resumes (after a root) */
    double *g_n, *g_lo, *g_hi, *g_mid;
    double t_lo;
    int resume_roots; /* a root was returned: the rest of the step [t_lo, t_n] is searched next */
    double t_stop;    /* stop time (has_stop), and the last step ended there (at_stop) */
    int has_stop, at_stop;
    rk45_stats_t stats;
    char message[256];
    double *block; /* every vector above */
};

/* fmax and fmin, the same values (also for a NaN argument: the other one), inline: without
 * -ffinite-math-only the compiler calls libm's for every use, one call per state in the error
 * norm of each step attempt. */
static inline double rk45_max(double a, double b)
{
    return (a > b || b != b) ? a : b;
}

static inline double rk45_min(double a, double b)
{
    return (a < b || b != b) ? a : b;
}

/* The message of the last failure (rk45_message; rk45_message.c). */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3), cold))
#endif
void rk45_set_message(rk45_t *r, const char *fmt, ...);

/* Shampine's coefficients of the last step, once per step (rk45_dense.c). */
void rk45_dense_coefficients(rk45_t *r);
/* rk45_dense's state at a t known to lie in the last step (root finding: inside the bracket),
 * without its checks (rk45_dense.c). */
void rk45_dense_inside(rk45_t *r, double t, double *out);

/* g at (t, y) into g: RK45_SUCCESS or RK45_ROOT_FAILURE (rk45_roots.c). */
int rk45_eval_roots(rk45_t *r, double t, const double *y, double *g);
/* The roots in (t_lo, t_n] of the last step, g_lo at t_lo given: RK45_ROOT with (t, y) at the
 * root, RK45_SUCCESS (or RK45_TSTOP) with the step's end, or a failure (rk45_roots.c). */
int rk45_check_roots(rk45_t *r, double t_lo, double *t, double *y);

CSFH_INTERNAL_END

#endif
