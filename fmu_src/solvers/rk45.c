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
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
/* Shampine's continuous extension */
#define D1 (-12715105075.0 / 11282082432.0)
#define D3 (87487479700.0 / 32700410799.0)
#define D4 (-10690763975.0 / 1880347072.0)
#define D5 (701980252875.0 / 199316789632.0)
#define D6 (-1453857185.0 / 822651844.0)
#define D7 (69997945.0 / 29380423.0)

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

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3), cold))
#endif
static void set_message(rk45_t *r, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(r->message, sizeof r->message, fmt, args);
    va_end(args);
}

rk45_t *rk45_create(int n, int n_roots, rk45_rhs_fn f, rk45_root_fn g, void *user)
{
    if (n < 1 || n_roots < 0 || f == NULL || (n_roots > 0 && g == NULL)) {
        return NULL;
    }
    rk45_t *r = (rk45_t *)calloc(1, sizeof(*r));
    /* y, y_old, y_new, ys, k[7], dense[5], w, atol: 18 vectors; g: 4 vectors of n_roots */
    double *block = (double *)calloc((size_t)(18 * n + 4 * n_roots + 1), sizeof(double));
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

static int eval_roots(rk45_t *r, double t, const double *y, double *g)
{
    if (r->n_roots == 0) {
        return RK45_SUCCESS;
    }
    r->stats.roots++;
    if (r->g(t, y, g, r->user) != 0) {
        set_message(r, "the root function failed at t = %.17g", t);
        return RK45_ROOT_FAILURE;
    }
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
    r->h = fmin(h_first, h_max_first); /* 0: estimated at the first step */
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
        set_message(r, "the right-hand side failed at the start, t = %.17g", t0);
        return RK45_RHS_FAILURE;
    }
    const int rs = eval_roots(r, t0, r->y, r->g_n);
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
        const double sc = r->atol[i] + r->rtol * fmax(fabs(a[i]), fabs(b[i]));
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
    h = fmin(h, r->h_max_first);
    for (int i = 0; i < n; i++) {
        r->ys[i] = y[i] + h * f0[i];
    }
    r->stats.rhs++;
    const int status = r->f(r->t_n + h, r->ys, r->w, r->user);
    if (status < 0) {
        set_message(r, "the right-hand side failed at t = %.17g", r->t_n + h);
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
    const double dmax = fmax(d2, df);
    const double h1 = dmax <= 1e-15 ? fmax(1e-6, 1e-3 * h) : pow(0.01 / dmax, 0.2);
    r->h = fmin(fmin(100.0 * h, h1), r->h_max_first);
    return RK45_SUCCESS;
}

/* Shampine's coefficients of the last step, once per step. */
static void dense_coefficients(rk45_t *r)
{
    if (r->dense_valid) {
        return;
    }
    const double h = r->h_last;
    const double *k1 = r->k[0], *k3 = r->k[2], *k4 = r->k[3], *k5 = r->k[4], *k6 = r->k[5],
                 *k7 = r->k[6];
    for (int i = 0; i < r->n; i++) {
        const double dy = r->y[i] - r->y_old[i];
        const double b = h * k1[i] - dy;
        r->dense[0][i] = r->y_old[i];
        r->dense[1][i] = dy;
        r->dense[2][i] = b;
        r->dense[3][i] = dy - h * k7[i] - b;
        r->dense[4][i] =
            h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
    }
    r->dense_valid = 1;
}

/* The dense output (k = 0) or its derivative (k = 1) at theta in [0, 1] of a step of size h
 * from Shampine's coefficients r1..r5 (each n long, consecutive). */
static void dense_eval(const double *c, int n, double h, double th, int k, double *out)
{
    const double th1 = 1.0 - th;
    const double *r1 = c, *r2 = c + n, *r3 = c + 2 * n, *r4 = c + 3 * n, *r5 = c + 4 * n;
    if (k == 0) {
        /* y = r1 + th (r2 + (1 - th) (r3 + th (r4 + (1 - th) r5))) */
        for (int i = 0; i < n; i++) {
            out[i] = r1[i] + th * (r2[i] + th1 * (r3[i] + th * (r4[i] + th1 * r5[i])));
        }
    } else {
        /* d/dt of the same polynomial (product rule, inside out), / h */
        for (int i = 0; i < n; i++) {
            const double cc = r4[i] + th1 * r5[i], dc = -r5[i];
            const double b = r3[i] + th * cc, db = cc + th * dc;
            const double a = r2[i] + th1 * b, da = -b + th1 * db;
            out[i] = (a + th * da) / h;
        }
    }
}

int rk45_dense(rk45_t *r, double t, int k, double *out)
{
    if (!r->have_step || (k != 0 && k != 1)) {
        return RK45_ILL_INPUT;
    }
    const double h = r->h_last;
    const double slack = 100.0 * DBL_EPSILON * (fabs(r->t_n) + fabs(h));
    if (!(t >= r->t_old - slack && t <= r->t_n + slack)) {
        set_message(r, "dense output at t = %.17g outside the last step, ending at %.17g", t,
                    r->t_n);
        return RK45_ILL_INPUT;
    }
    dense_coefficients(r);
    double th = (t - r->t_old) / h;
    th = th < 0.0 ? 0.0 : (th > 1.0 ? 1.0 : th);
    dense_eval(r->dense[0], r->n, h, th, k, out);
    return RK45_SUCCESS;
}

int rk45_save_step(rk45_t *r, double *record)
{
    if (!r->have_step) {
        return RK45_ILL_INPUT;
    }
    const size_t n = (size_t)r->n;
    dense_coefficients(r);
    record[0] = r->t_old;
    record[1] = r->h_last;
    memcpy(record + 2, r->dense[0], 5 * n * sizeof(double)); /* contiguous (rk45_create) */
    memcpy(record + 2 + 5 * n, r->y, n * sizeof(double));
    /* the step's first stage is k[0] until the next step swaps it with k[6] (FSAL) */
    memcpy(record + 2 + 6 * n, r->fsal_swap ? r->k[0] : r->k[6], n * sizeof(double));
    memcpy(record + 2 + 7 * n, r->fsal_swap ? r->k[6] : r->k[0], n * sizeof(double));
    return RK45_SUCCESS;
}

void rk45_record_dense(const double *record, int n, double t, int k, double *out)
{
    const double h = record[1];
    double th = (t - record[0]) / h;
    th = th < 0.0 ? 0.0 : (th > 1.0 ? 1.0 : th);
    dense_eval(record + 2, n, h, th, k, out);
}

double rk45_record_start(const double *record)
{
    return record[0];
}

double rk45_record_end(const double *record)
{
    return record[0] + record[1];
}

const double *rk45_record_y(const double *record, int n, int end)
{
    return end ? record + 2 + 5 * (size_t)n : record + 2; /* the start: r1 = y_old */
}

const double *rk45_record_f(const double *record, int n, int end)
{
    return record + 2 + (end ? 7 : 6) * (size_t)n;
}

/* Sign change of component i between a and b (or b exactly zero, a not). */
static int crosses(double a, double b)
{
    return (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0);
}

/* The first root of g in (t_lo, t_n] given g_lo (at t_lo) and g_hi (at t_n): 0 if none, 1 with
 * the time in *t_root (the end of the final bracket, past the sign change) and g there in
 * g_hi, or a failure. Illinois regula falsi on the component whose secant root lies nearest
 * t_lo; each iteration's bracket keeps a sign change of some component. */
static int find_root(rk45_t *r, double t_lo, double *t_root)
{
    const int m = r->n_roots;
    double *g_lo = r->g_lo, *g_hi = r->g_hi, *g_mid = r->g_mid;
    int imax = -1;
    double maxfrac = -1.0;
    for (int i = 0; i < m; i++) {
        if (crosses(g_lo[i], g_hi[i])) {
            const double frac = fabs(g_hi[i] / (g_hi[i] - g_lo[i]));
            if (frac > maxfrac) {
                maxfrac = frac, imax = i;
            }
        }
    }
    if (imax < 0) {
        return 0;
    }
    double t_hi = r->t_n;
    const double ttol = 100.0 * DBL_EPSILON * (fabs(r->t_n) + fabs(r->h_last));
    double alpha = 1.0;
    int side = 0, side_prev = -1;
    while (t_hi - t_lo > ttol) {
        /* Illinois: halve the weight of the end kept twice in a row */
        if (side == side_prev) {
            alpha = side == 2 ? 2.0 * alpha : 0.5 * alpha;
        } else {
            alpha = 1.0;
        }
        double t_mid = t_hi - (t_hi - t_lo) * g_hi[imax] / (g_hi[imax] - alpha * g_lo[imax]);
        if (!(t_mid - t_lo >= 0.5 * ttol)) {
            const double frac = 0.5 * (t_hi - t_lo) / r->h_last > 0.1 ? 0.1 : 0.5 * (t_hi - t_lo) / r->h_last;
            t_mid = t_lo + fmax(frac, 0.0) * (t_hi - t_lo);
            t_mid = t_mid - t_lo >= 0.5 * ttol ? t_mid : t_lo + 0.5 * ttol;
        }
        if (!(t_hi - t_mid >= 0.5 * ttol)) {
            const double frac = 0.5 * (t_hi - t_lo) / r->h_last > 0.1 ? 0.1 : 0.5 * (t_hi - t_lo) / r->h_last;
            t_mid = t_hi - fmax(frac, 0.0) * (t_hi - t_lo);
            t_mid = t_hi - t_mid >= 0.5 * ttol ? t_mid : t_hi - 0.5 * ttol;
        }
        rk45_dense(r, t_mid, 0, r->w);
        const int rs = eval_roots(r, t_mid, r->w, g_mid);
        if (rs != RK45_SUCCESS) {
            return rs;
        }
        side_prev = side;
        /* a sign change in [t_lo, t_mid]? */
        imax = -1;
        maxfrac = -1.0;
        int zero = 0;
        for (int i = 0; i < m; i++) {
            if (crosses(g_lo[i], g_mid[i])) {
                if (g_mid[i] == 0.0) {
                    zero = 1;
                }
                const double frac = fabs(g_mid[i] / (g_mid[i] - g_lo[i]));
                if (frac > maxfrac) {
                    maxfrac = frac, imax = i;
                }
            }
        }
        if (imax >= 0) {
            t_hi = t_mid;
            memcpy(g_hi, g_mid, (size_t)m * sizeof(double));
            if (zero) {
                break; /* g is exactly zero at t_mid */
            }
            side = 1;
            continue;
        }
        /* no: the root is in [t_mid, t_hi] */
        t_lo = t_mid;
        memcpy(g_lo, g_mid, (size_t)m * sizeof(double));
        side = 2;
        maxfrac = -1.0;
        for (int i = 0; i < m; i++) {
            if (crosses(g_lo[i], g_hi[i])) {
                const double frac = fabs(g_hi[i] / (g_hi[i] - g_lo[i]));
                if (frac > maxfrac) {
                    maxfrac = frac, imax = i;
                }
            }
        }
        if (imax < 0) {
            break; /* round-off: keep t_hi */
        }
    }
    *t_root = t_hi;
    return 1;
}

/* Roots in (t_lo, t_n] of the last step, g_lo at t_lo given: RK45_ROOT with (t, y) at the root,
 * RK45_SUCCESS with the step's end, or a failure. */
static int check_roots(rk45_t *r, double t_lo, double *t, double *y)
{
    if (r->n_roots > 0) {
        memcpy(r->g_hi, r->g_n, (size_t)r->n_roots * sizeof(double));
        double t_root = r->t_n;
        const int found = find_root(r, t_lo, &t_root);
        if (found < 0) {
            return found;
        }
        if (found > 0) {
            rk45_dense(r, t_root, 0, y);
            *t = t_root;
            r->t_lo = t_root;
            memcpy(r->g_lo, r->g_hi, (size_t)r->n_roots * sizeof(double)); /* g at the root */
            r->resume_roots = t_root < r->t_n;
            return RK45_ROOT;
        }
    }
    r->resume_roots = 0;
    *t = r->t_n;
    memcpy(y, r->y, (size_t)r->n * sizeof(double));
    if (r->at_stop) {
        r->at_stop = 0;
        return RK45_TSTOP;
    }
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

int rk45_step(rk45_t *r, double *t, double *y)
{
    const int n = r->n;
    if (r->resume_roots) { /* the rest of the step after a returned root */
        return check_roots(r, r->t_lo, t, y);
    }
    if (!r->initialized) {
        return RK45_ILL_INPUT;
    }
    *t = r->t_n;
    memcpy(y, r->y, (size_t)n * sizeof(double));
    if (r->h <= 0.0) {
        const int s = initial_step(r);
        if (s != RK45_SUCCESS) {
            return s;
        }
    }
    if (r->fsal_swap) { /* first same as last */
        double *k = r->k[0];
        r->k[0] = r->k[6];
        r->k[6] = k;
        r->fsal_swap = 0;
    }
    const double t0 = r->t_n;
    const double *y0 = r->y;
    double *const k1 = r->k[0], *const k2 = r->k[1], *const k3 = r->k[2], *const k4 = r->k[3],
                 *const k5 = r->k[4], *const k6 = r->k[5], *const k7 = r->k[6];
    double *const ys = r->ys, *const yn = r->y_new;
    int err_fails = 0, rhs_fails = 0;
    double h = r->h, err = 0.0, h_failed = 0.0, err_failed = 0.0;
    for (;;) {
        /* the stop time: the step that would pass it ends on it */
        const int hits_stop = r->has_stop && t0 + h >= r->t_stop;
        if (hits_stop) {
            h = r->t_stop - t0;
        }
        if (!(t0 + h > t0) || !isfinite(h)) {
            set_message(r, "the step size %.3g underflows the time t = %.17g", h, t0);
            return RK45_TOO_SMALL;
        }
        /* the stages 2..7 (stage 7 is the solution, and its f the next step's first stage) */
        int status = 0;
#define STAGE(tc, yy, kk)                                                                        \
    if (status == 0) {                                                                           \
        r->stats.rhs++;                                                                          \
        status = r->f(t0 + (tc) * h, (yy), (kk), r->user);                                       \
    }
        for (int i = 0; i < n; i++) {
            ys[i] = y0[i] + h * A21 * k1[i];
        }
        STAGE(C2, ys, k2)
        for (int i = 0; status == 0 && i < n; i++) {
            ys[i] = y0[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        STAGE(C3, ys, k3)
        for (int i = 0; status == 0 && i < n; i++) {
            ys[i] = y0[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        STAGE(C4, ys, k4)
        for (int i = 0; status == 0 && i < n; i++) {
            ys[i] = y0[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        STAGE(C5, ys, k5)
        for (int i = 0; status == 0 && i < n; i++) {
            ys[i] = y0[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] +
                                 A65 * k5[i]);
        }
        STAGE(1.0, ys, k6)
        for (int i = 0; status == 0 && i < n; i++) {
            yn[i] = y0[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] +
                                 A76 * k6[i]);
        }
        STAGE(1.0, yn, k7)
#undef STAGE
        if (status < 0) {
            set_message(r, "the right-hand side failed in the step from t = %.17g, h = %.3g", t0,
                        h);
            return RK45_RHS_FAILURE;
        }
        if (status > 0) {
            r->stats.fails++;
            if (++rhs_fails >= MAX_RHS_FAILS) {
                set_message(r,
                            "the right-hand side failed recoverably %d times in a row at "
                            "t = %.17g",
                            MAX_RHS_FAILS, t0);
                return RK45_RHS_FAILURE;
            }
            h *= 0.25;
            r->rejected = 1;
            continue;
        }
        for (int i = 0; i < n; i++) {
            r->w[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] +
                           E7 * k7[i]);
        }
        err = wrms(r, r->w, y0, yn);
        if (err <= 1.0) {
            break;
        }
        /* rejected: a smaller step. The first reduction assumes the method's order (error ~
         * h^5); from the second on, the order observed between the last two attempts is used
         * (a kink or a jump of the right-hand side inside the step gives error ~ h^1..2, for
         * which h^5 would take many attempts) */
        r->stats.fails++;
        if (!isfinite(err)) {
            h *= FAC_MIN; /* a non-finite trial state: much smaller */
        } else {
            double order = 5.0;
            if (err_fails > 0 && h_failed > h && err_failed > err) {
                order = log(err_failed / err) / log(h_failed / h);
                order = order < 0.5 ? 0.5 : (order > 5.0 ? 5.0 : order);
            }
            err_failed = err;
            h_failed = h;
            const double fac = SAFETY * pow(err, -1.0 / order);
            h *= fmin(SAFETY, fmax(err_fails > 0 ? FAC_MIN_REPEATED : FAC_MIN, fac));
        }
        r->rejected = 1;
        if (++err_fails >= MAX_ERR_FAILS) {
            set_message(r, "the error test failed %d times in a row at t = %.17g, last step %.3g s",
                        MAX_ERR_FAILS, t0, h);
            return RK45_ERR_FAILURE;
        }
    }
    /* accepted: stiffness indicator (h |lambda| from the last two stages at the same time) */
    double num = 0.0, den = 0.0;
    for (int i = 0; i < n; i++) {
        num += (k7[i] - k6[i]) * (k7[i] - k6[i]);
        den += (yn[i] - ys[i]) * (yn[i] - ys[i]);
    }
    if (den > 0.0 && h * h * num > STIFF_H_LAMBDA * STIFF_H_LAMBDA * den) {
        r->stats.stiff++;
    }
    /* the next step's size: PI control */
    /* SAFETY err^-alpha err_old^beta, as one exponential */
    const double log_err = log(fmax(err, 1e-10));
    double fac = SAFETY * exp(-PI_ALPHA * log_err + PI_BETA * r->log_fac_old);
    fac = fmin(FAC_MAX, fmax(FAC_MIN, fac));
    if (r->rejected) {
        fac = fmin(fac, 1.0);
    }
    r->log_fac_old = log_err > log(1e-4) ? log_err : log(1e-4);
    r->rejected = 0;
    /* advance: y_old <- y <- y_new */
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
    /* roots in (t_old, t_n] */
    if (r->n_roots > 0) {
        memcpy(r->g_lo, r->g_n, (size_t)r->n_roots * sizeof(double));
        const int rs = eval_roots(r, r->t_n, r->y, r->g_n);
        if (rs != RK45_SUCCESS) {
            return rs;
        }
    }
    return check_roots(r, r->t_old, t, y);
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

const char *rk45_message(const rk45_t *r)
{
    return r->message;
}

const char *rk45_flag_name(int flag)
{
    switch (flag) {
    case RK45_SUCCESS:
        return "RK45_SUCCESS";
    case RK45_ROOT:
        return "RK45_ROOT";
    case RK45_MEM_FAIL:
        return "RK45_MEM_FAIL";
    case RK45_ILL_INPUT:
        return "RK45_ILL_INPUT";
    case RK45_ERR_FAILURE:
        return "RK45_ERR_FAILURE";
    case RK45_RHS_FAILURE:
        return "RK45_RHS_FAILURE";
    case RK45_ROOT_FAILURE:
        return "RK45_ROOT_FAILURE";
    case RK45_TOO_SMALL:
        return "RK45_TOO_SMALL";
    default:
        return "an unknown flag";
    }
}
