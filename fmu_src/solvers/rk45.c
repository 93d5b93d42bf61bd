/* Explicit Runge-Kutta 5(4) of Dormand and Prince with dense output and root finding (rk45.h).
 *
 * References for the formulas (the coefficients are the method's published constants):
 *   J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput. Appl.
 *   Math. 6 (1980) 19-26 (the table, error coefficients);
 *   L. F. Shampine, "Some practical Runge-Kutta formulas", Math. Comp. 46 (1986) 135-150 (the
 *   4th-order continuous extension);
 *   E. Hairer, S. P. Norsett, G. Wanner, Solving ODEs I, 2nd ed., Springer 1993, II.4-II.6 (the
 *   initial step estimate, the PI step-size control, the stiffness indicator, II.4 and IV.2).
 */
#include "rk45.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rk45_internal.h"

/* Butcher table (c2..c7 and the rows of A; row 7 is the 5th-order solution, FSAL). */
#define C2 (1.0 / 5.0)
#define C3 (3.0 / 10.0)
#define C4 (4.0 / 5.0)
#define C5 (8.0 / 9.0)
#define A21 (1.0 / 5.0)
#define A31 (3.0 / 40.0)
#define A32 (9.0 / 40.0)
#define A41 (44.0 / 45.0)
#define A42 (-56.0 / 15.0)
#define A43 (32.0 / 9.0)
#define A51 (19372.0 / 6561.0)
#define A52 (-25360.0 / 2187.0)
#define A53 (64448.0 / 6561.0)
#define A54 (-212.0 / 729.0)
#define A61 (9017.0 / 3168.0)
#define A62 (-355.0 / 33.0)
#define A63 (46732.0 / 5247.0)
#define A64 (49.0 / 176.0)
#define A65 (-5103.0 / 18656.0)
#define A71 (35.0 / 384.0)
#define A73 (500.0 / 1113.0)
#define A74 (125.0 / 192.0)
#define A75 (-2187.0 / 6784.0)
#define A76 (11.0 / 84.0)
/* error estimate: b (5th order) - bhat (4th order) */
#define E1 (71.0 / 57600.0)
#define E3 (-71.0 / 16695.0)
#define E4 (71.0 / 1920.0)
#define E5 (-17253.0 / 339200.0)
#define E6 (22.0 / 525.0)
#define E7 (-1.0 / 40.0)
/* step-size control (Hairer-Norsett-Wanner II.4, IV.2) */
#define SAFETY 0.9
#define FAC_MIN 0.2            /* the step shrinks by at most 5x per step ... */
#define FAC_MAX 10.0           /* ... and grows by at most 10x */
#define PI_ALPHA 0.17          /* exponent of the current error: 1/5 - 0.75 PI_BETA */
#define PI_BETA 0.04           /* exponent of the previous error (PI control) */
#define FAC_MIN_REPEATED 0.01  /* ... 100x after repeated rejections */
#define MAX_ERR_FAILS 20       /* rejected attempts in a row before RK45_ERR_FAILURE */
#define MAX_RHS_FAILS 10       /* recoverable f failures in a row before RK45_RHS_FAILURE */
#define STIFF_H_LAMBDA 2.5   /* h |lambda| flagged as held by stability: within 25 % of the
                                stability boundary (DP5: 3.3 on the negative real axis); a
                                step that accuracy sets is far shorter */


rk45_t *rk45_create(int n, int n_roots, rk45_rhs_fn f, rk45_root_fn g, void *user)
{
    if (n < 1 || n_roots < 0 || f == NULL || (n_roots > 0 && g == NULL)) {
        return NULL;
    }
    rk45_t *r = (rk45_t *)calloc(1, sizeof(*r));
    /* y, y_old, y_new, ys, k[7], dense[5], w, y_mid, atol: 19 vectors; g: 4 vectors of n_roots */
    double *block = (double *)calloc((size_t)(19 * n + 4 * n_roots + 1), sizeof(double));
    if (r == NULL || block == NULL) {
        free(r);
        free(block);
        return NULL;
    }
    r->block = block;
    r->n = n;
    r->n_roots = n_roots;
    r->f = f;
    r->g = g;
    r->user = user;
    double *p = block;
    r->y = p, p += n;
    r->y_old = p, p += n;
    r->y_new = p, p += n;
    r->ys = p, p += n;
    for (int i = 0; i < 7; i++) {
        r->k[i] = p, p += n;
    }
    for (int i = 0; i < 5; i++) {
        r->dense[i] = p, p += n;
    }
    r->w = p, p += n;
    r->y_mid = p, p += n;
    r->atol = p, p += n;
    r->g_n = p, p += n_roots;
    r->g_lo = p, p += n_roots;
    r->g_hi = p, p += n_roots;
    r->g_mid = p;
    r->rtol = 1e-6;
    for (int i = 0; i < n; i++) {
        r->atol[i] = 1e-6;
    }
    return r;
}

void rk45_free(rk45_t *r)
{
    if (r == NULL) {
        return;
    }
    free(r->block);
    free(r);
}

int rk45_set_tolerances(rk45_t *r, double rtol, const double *atol)
{
    if (!(rtol > 0.0) || !isfinite(rtol)) {
        return RK45_ILL_INPUT;
    }
    for (int i = 0; i < r->n; i++) {
        if (!(atol[i] > 0.0) || !isfinite(atol[i])) {
            return RK45_ILL_INPUT;
        }
    }
    r->rtol = rtol;
    memcpy(r->atol, atol, (size_t)r->n * sizeof(double));
    return RK45_SUCCESS;
}

int rk45_init(rk45_t *r, double t0, const double *y0, double h_max_first, double h_first)
{
    if (!isfinite(t0) || !(h_max_first > 0.0) || !(h_first >= 0.0) || !isfinite(h_first)) {
        return RK45_ILL_INPUT;
    }
    memcpy(r->y, y0, (size_t)r->n * sizeof(double));
    r->t_n = r->t_old = t0;
    r->h_last = 0.0;
    r->h = rk45_min(h_first, h_max_first); /* 0: estimated at the first step */
    r->h_max_first = h_max_first;
    r->log_fac_old = log(1e-4);
    r->fsal_swap = 0;
    r->rejected = 0;
    r->dense_valid = 0;
    r->have_step = 0;
    r->resume_roots = 0;
    r->has_stop = r->at_stop = 0;
    r->initialized = 0;
    r->stats.rhs++;
    const int status = r->f(t0, r->y, r->k[0], r->user);
    if (status != 0) {
        rk45_set_message(r, "the right-hand side failed at the start, t = %.17g", t0);
        return RK45_RHS_FAILURE;
    }
    const int rs = rk45_eval_roots(r, t0, r->y, r->g_n);
    if (rs != RK45_SUCCESS) {
        return rs;
    }
    r->initialized = 1;
    return RK45_SUCCESS;
}

/* sqrt(mean((v / sc)^2)) with sc = atol + rtol max(|a|, |b|) */
static double wrms(const rk45_t *r, const double *v, const double *a, const double *b)
{
    double sum = 0.0;
    for (int i = 0; i < r->n; i++) {
        const double sc = r->atol[i] + r->rtol * rk45_max(fabs(a[i]), fabs(b[i]));
        const double q = v[i] / sc;
        sum += q * q;
    }
    return sqrt(sum / r->n);
}

/* The first step's size (Hairer-Norsett-Wanner II.4): from the size of y, f and an estimate of
 * the second derivative (one more evaluation of f). */
static int initial_step(rk45_t *r)
{
    const int n = r->n;
    const double *y = r->y, *f0 = r->k[0];
    double dy = 0.0, df = 0.0;
    for (int i = 0; i < n; i++) {
        const double sc = r->atol[i] + r->rtol * fabs(y[i]);
        dy += (y[i] / sc) * (y[i] / sc);
        df += (f0[i] / sc) * (f0[i] / sc);
    }
    dy = sqrt(dy / n);
    df = sqrt(df / n);
    double h = (dy <= 1e-5 || df <= 1e-5) ? 1e-6 : 0.01 * dy / df;
    h = rk45_min(h, r->h_max_first);
    for (int i = 0; i < n; i++) {
        r->ys[i] = y[i] + h * f0[i];
    }
    r->stats.rhs++;
    const int status = r->f(r->t_n + h, r->ys, r->w, r->user);
    if (status < 0) {
        rk45_set_message(r, "the right-hand side failed at t = %.17g", r->t_n + h);
        return RK45_RHS_FAILURE;
    }
    double d2 = 0.0;
    if (status == 0) {
        for (int i = 0; i < n; i++) {
            const double sc = r->atol[i] + r->rtol * fabs(y[i]);
            const double q = (r->w[i] - f0[i]) / sc;
            d2 += q * q;
        }
        d2 = sqrt(d2 / n) / h;
    } else {
        d2 = 1e6 * df / h; /* recoverable failure: take a small step */
    }
    const double dmax = rk45_max(d2, df);
    const double h1 = dmax <= 1e-15 ? rk45_max(1e-6, 1e-3 * h) : pow(0.01 / dmax, 0.2);
    r->h = rk45_min(rk45_min(100.0 * h, h1), r->h_max_first);
    return RK45_SUCCESS;
}

int rk45_set_stop_time(rk45_t *r, double t_stop)
{
    if (!(t_stop > r->t_n) || !isfinite(t_stop)) {
        return RK45_ILL_INPUT;
    }
    r->t_stop = t_stop;
    r->has_stop = 1;
    return RK45_SUCCESS;
}

/* f at stage (t0 + c h, y) into k: its status (0, > 0 recoverable, < 0 fatal). */
static int stage(rk45_t *r, double t0, double c, double h, const double *y, double *k)
{
    r->stats.rhs++;
    return r->f(t0 + c * h, y, k, r->user);
}

/* The stages 2..7 of a step of size h from (t0, y0) (stage 7 is the solution yn, and its f the
 * next step's first stage): the status of f, 0 or that of the first stage that failed. The
 * vectors are distinct ones of the block (rk45_create), each reached only through its argument
 * here (f writes a stage through the one it is given): the loops need no overlap checks. */
static int stages_of(rk45_t *r, double t0, double h, const double *restrict y0,
                     const double *restrict k1, double *restrict k2, double *restrict k3,
                     double *restrict k4, double *restrict k5, double *restrict k6,
                     double *restrict k7, double *restrict ys, double *restrict yn)
{
    const int n = r->n;
    int status;
    for (int i = 0; i < n; i++) {
        ys[i] = y0[i] + h * A21 * k1[i];
    }
    if ((status = stage(r, t0, C2, h, ys, k2)) != 0) {
        return status;
    }
    for (int i = 0; i < n; i++) {
        ys[i] = y0[i] + h * (A31 * k1[i] + A32 * k2[i]);
    }
    if ((status = stage(r, t0, C3, h, ys, k3)) != 0) {
        return status;
    }
    for (int i = 0; i < n; i++) {
        ys[i] = y0[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
    }
    if ((status = stage(r, t0, C4, h, ys, k4)) != 0) {
        return status;
    }
    for (int i = 0; i < n; i++) {
        ys[i] = y0[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
    }
    if ((status = stage(r, t0, C5, h, ys, k5)) != 0) {
        return status;
    }
    for (int i = 0; i < n; i++) {
        ys[i] = y0[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] +
                             A65 * k5[i]);
    }
    if ((status = stage(r, t0, 1.0, h, ys, k6)) != 0) {
        return status;
    }
    for (int i = 0; i < n; i++) {
        yn[i] = y0[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] +
                             A76 * k6[i]);
    }
    return stage(r, t0, 1.0, h, yn, k7);
}

static int stages(rk45_t *r, double t0, double h)
{
    return stages_of(r, t0, h, r->y, r->k[0], r->k[1], r->k[2], r->k[3], r->k[4], r->k[5],
                     r->k[6], r->ys, r->y_new);
}

/* The error estimate of the step of size h (the embedded 4th-order solution's difference) in
 * the weighted RMS norm. */
/* The embedded solution's difference (h times the error stages) into w (the vectors distinct:
 * the loop needs no overlap checks). */
static void error_vector(int n, double h, const double *restrict k1, const double *restrict k3,
                         const double *restrict k4, const double *restrict k5,
                         const double *restrict k6, const double *restrict k7,
                         double *restrict w)
{
    for (int i = 0; i < n; i++) {
        w[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
    }
}

static double error_norm(rk45_t *r, double h)
{
    error_vector(r->n, h, r->k[0], r->k[2], r->k[3], r->k[4], r->k[5], r->k[6], r->w);
    return wrms(r, r->w, r->y, r->y_new);
}

/* The attempts at one step: rejections so far, and the last rejected size and error. */
typedef struct {
    int err_fails, rhs_fails;
    double h_failed, err_failed;
} attempts_t;

/* A recoverable failure of f: a 4x smaller step, or RK45_RHS_FAILURE after too many. */
static int rhs_failed(rk45_t *r, attempts_t *a, double t0, double *h)
{
    r->stats.fails++;
    if (++a->rhs_fails >= MAX_RHS_FAILS) {
        rk45_set_message(r, "the right-hand side failed recoverably %d times in a row at t = %.17g",
                         MAX_RHS_FAILS, t0);
        return RK45_RHS_FAILURE;
    }
    *h *= 0.25;
    r->rejected = 1;
    return RK45_SUCCESS;
}

/* The error test failed with err: a smaller step, or RK45_ERR_FAILURE after too many. The first
 * reduction assumes the method's order (error ~ h^5); from the second on, the order observed
 * between the last two attempts is used (a kink or a jump of the right-hand side inside the
 * step gives error ~ h^1..2, for which h^5 would take many attempts). */
static int error_failed(rk45_t *r, attempts_t *a, double t0, double err, double *h)
{
    r->stats.fails++;
    if (!isfinite(err)) {
        *h *= FAC_MIN; /* a non-finite trial state: much smaller */
    } else {
        double order = 5.0;
        if (a->err_fails > 0 && a->h_failed > *h && a->err_failed > err) {
            order = log(a->err_failed / err) / log(a->h_failed / *h);
            order = order < 0.5 ? 0.5 : (order > 5.0 ? 5.0 : order);
        }
        a->err_failed = err;
        a->h_failed = *h;
        const double fac = SAFETY * pow(err, -1.0 / order);
        *h *= rk45_min(SAFETY, rk45_max(a->err_fails > 0 ? FAC_MIN_REPEATED : FAC_MIN, fac));
    }
    r->rejected = 1;
    if (++a->err_fails >= MAX_ERR_FAILS) {
        rk45_set_message(r,
                         "the error test failed %d times in a row at t = %.17g, last step %.3g s",
                         MAX_ERR_FAILS, t0, *h);
        return RK45_ERR_FAILURE;
    }
    return RK45_SUCCESS;
}

/* Attempts at a step from t0 until one passes the error test: its size in *h and its error in
 * *err, or a failure. */
static int attempt(rk45_t *r, double t0, double *h, double *err)
{
    attempts_t a = {0, 0, 0.0, 0.0};
    for (;;) {
        /* the stop time: the step that would pass it ends on it */
        if (r->has_stop && t0 + *h >= r->t_stop) {
            *h = r->t_stop - t0;
        }
        if (!(t0 + *h > t0) || !isfinite(*h)) {
            rk45_set_message(r, "the step size %.3g underflows the time t = %.17g", *h, t0);
            return RK45_TOO_SMALL;
        }
        const int status = stages(r, t0, *h);
        if (status < 0) {
            rk45_set_message(r, "the right-hand side failed in the step from t = %.17g, h = %.3g",
                             t0, *h);
            return RK45_RHS_FAILURE;
        }
        int s;
        if (status > 0) {
            s = rhs_failed(r, &a, t0, h);
        } else {
            *err = error_norm(r, *h);
            if (*err <= 1.0) {
                return RK45_SUCCESS;
            }
            s = error_failed(r, &a, t0, *err, h);
        }
        if (s != RK45_SUCCESS) {
            return s;
        }
    }
}

/* The accepted step of size h from t0 with error err: the stiffness indicator (h |lambda| from
 * the last two stages at the same time), the next step's size (PI control), and the solution
 * advanced (y_old <- y <- y_new). */
static void accept(rk45_t *r, double t0, double h, double err)
{
    const double *k6 = r->k[5], *k7 = r->k[6], *yn = r->y_new, *ys = r->ys;
    double num = 0.0, den = 0.0;
    for (int i = 0; i < r->n; i++) {
        num += (k7[i] - k6[i]) * (k7[i] - k6[i]);
        den += (yn[i] - ys[i]) * (yn[i] - ys[i]);
    }
    if (den > 0.0 && h * h * num > STIFF_H_LAMBDA * STIFF_H_LAMBDA * den) {
        r->stats.stiff++;
    }
    /* SAFETY err^-alpha err_old^beta, as one exponential */
    const double log_err = log(rk45_max(err, 1e-10));
    double fac = SAFETY * exp(-PI_ALPHA * log_err + PI_BETA * r->log_fac_old);
    fac = rk45_min(FAC_MAX, rk45_max(FAC_MIN, fac));
    if (r->rejected) {
        fac = rk45_min(fac, 1.0);
    }
    r->log_fac_old = log_err > log(1e-4) ? log_err : log(1e-4);
    r->rejected = 0;
    double *old = r->y_old;
    r->y_old = r->y;
    r->y = r->y_new;
    r->y_new = old;
    r->t_old = t0;
    r->t_n = t0 + h;
    r->h_last = h;
    if (r->has_stop && r->t_n >= r->t_stop) { /* the stop time reached: exactly */
        r->t_n = r->t_stop;
        r->has_stop = 0;
        r->at_stop = 1;
    }
    r->h = h * fac;
    r->fsal_swap = 1;
    r->dense_valid = 0;
    r->have_step = 1;
    r->stats.steps++;
}

/* A failure s of the step from (t0, y0): that point, the last successful one, in (t, y). */
static int failed_at(const rk45_t *r, int s, double t0, const double *y0, double *t, double *y)
{
    *t = t0;
    memcpy(y, y0, (size_t)r->n * sizeof(double));
    return s;
}

int rk45_step(rk45_t *r, double *t, double *y)
{
    if (r->resume_roots) { /* the rest of the step after a returned root */
        return rk45_check_roots(r, r->t_lo, t, y);
    }
    if (!r->initialized) {
        return RK45_ILL_INPUT;
    }
    if (r->h <= 0.0) {
        const int s = initial_step(r);
        if (s != RK45_SUCCESS) {
            return failed_at(r, s, r->t_n, r->y, t, y);
        }
    }
    if (r->fsal_swap) { /* first same as last */
        double *k = r->k[0];
        r->k[0] = r->k[6];
        r->k[6] = k;
        r->fsal_swap = 0;
    }
    const double t0 = r->t_n;
    double h = r->h, err = 0.0;
    const int s = attempt(r, t0, &h, &err);
    if (s != RK45_SUCCESS) {
        return failed_at(r, s, t0, r->y, t, y);
    }
    accept(r, t0, h, err);
    /* roots in (t_old, t_n]: g at the step's start is g at the last step's end */
    if (r->n_roots > 0) {
        double *g = r->g_lo;
        r->g_lo = r->g_n;
        r->g_n = g;
        const int rs = rk45_eval_roots(r, r->t_n, r->y, r->g_n);
        if (rs != RK45_SUCCESS) {
            return failed_at(r, rs, t0, r->y_old, t, y);
        }
    }
    const int rc = rk45_check_roots(r, r->t_old, t, y);
    return rc < 0 ? failed_at(r, rc, t0, r->y_old, t, y) : rc;
}

double rk45_current_time(const rk45_t *r)
{
    return r->t_n;
}

double rk45_last_step(const rk45_t *r)
{
    return r->h_last;
}

double rk45_next_step(const rk45_t *r)
{
    return r->h;
}

void rk45_get_stats(const rk45_t *r, rk45_stats_t *s)
{
    *s = r->stats;
}
