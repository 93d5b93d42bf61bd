/* Root finding of the explicit Runge-Kutta 5(4) (rk45.h) on its dense output: Illinois regula
 * falsi, as CVODE does on its interpolant. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "rk45_internal.h"

int rk45_eval_roots(rk45_t *r, double t, const double *y, double *g)
{
    if (r->n_roots == 0) {
        return RK45_SUCCESS;
    }
    r->stats.roots++;
    if (r->g(t, y, g, r->user) != 0) {
        rk45_set_message(r, "the root function failed at t = %.17g", t);
        return RK45_ROOT_FAILURE;
    }
    return RK45_SUCCESS;
}

/* Sign change of component i between a and b (or b exactly zero, a not). */
static int crosses(double a, double b)
{
    return (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0);
}

/* Of the m components with a sign change between lo and hi, the one whose secant root lies
 * nearest lo (the largest |hi / (hi - lo)|), or -1 if none; *zero is set if one of them is
 * exactly 0 at hi. */
static int strongest(const double *lo, const double *hi, int m, int *zero)
{
    int imax = -1;
    double maxfrac = -1.0;
    for (int i = 0; i < m; i++) {
        if (crosses(lo[i], hi[i])) {
            if (hi[i] == 0.0) {
                *zero = 1;
            }
            const double frac = fabs(hi[i] / (hi[i] - lo[i]));
            if (frac > maxfrac) {
                maxfrac = frac, imax = i;
            }
        }
    }
    return imax;
}

/* The next point inside the bracket [t_lo, t_hi]: the secant root of component i with the
 * Illinois weight alpha on the low end, kept ttol / 2 away from both ends. */
static double next_point(const rk45_t *r, double t_lo, double t_hi, double alpha, int i,
                         double ttol)
{
    const double *g_lo = r->g_lo, *g_hi = r->g_hi;
    double t_mid = t_hi - (t_hi - t_lo) * g_hi[i] / (g_hi[i] - alpha * g_lo[i]);
    if (!(t_mid - t_lo >= 0.5 * ttol)) {
        const double half = 0.5 * (t_hi - t_lo) / r->h_last;
        const double frac = half > 0.1 ? 0.1 : half;
        t_mid = t_lo + rk45_max(frac, 0.0) * (t_hi - t_lo);
        t_mid = t_mid - t_lo >= 0.5 * ttol ? t_mid : t_lo + 0.5 * ttol;
    }
    if (!(t_hi - t_mid >= 0.5 * ttol)) {
        const double half = 0.5 * (t_hi - t_lo) / r->h_last;
        const double frac = half > 0.1 ? 0.1 : half;
        t_mid = t_hi - rk45_max(frac, 0.0) * (t_hi - t_lo);
        t_mid = t_hi - t_mid >= 0.5 * ttol ? t_mid : t_hi - 0.5 * ttol;
    }
    return t_mid;
}

/* The first root of g in (t_lo, t_n] given g_lo (at t_lo) and g_n (at t_n): 0 if none, 1 with
 * the time in *t_root (the end of the final bracket, past the sign change) and g there in
 * g_hi, or a failure; *y_known: the state at *t_root is in y_mid (the last evaluation there).
 * Illinois regula falsi on the component whose secant root lies nearest t_lo; each iteration's
 * bracket keeps a sign change of some component. The vectors of g and the state at the
 * bracket's end trade places with the new point's instead of being copied. */
static int find_root(rk45_t *r, double t_lo, double *t_root, int *y_known)
{
    const int m = r->n_roots;
    int unused = 0;
    int imax = strongest(r->g_lo, r->g_n, m, &unused);
    if (imax < 0) {
        return 0;
    }
    memcpy(r->g_hi, r->g_n, (size_t)m * sizeof(double));
    double t_hi = r->t_n;
    const double ttol = 100.0 * DBL_EPSILON * (fabs(r->t_n) + fabs(r->h_last));
    double alpha = 1.0;
    int side = 0, side_prev = -1;
    *y_known = 0;
    while (t_hi - t_lo > ttol) {
        /* Illinois: halve the weight of the end kept twice in a row */
        if (side == side_prev) {
            alpha = side == 2 ? 2.0 * alpha : 0.5 * alpha;
        } else {
            alpha = 1.0;
        }
        const double t_mid = next_point(r, t_lo, t_hi, alpha, imax, ttol);
        rk45_dense(r, t_mid, 0, r->w);
        const int rs = rk45_eval_roots(r, t_mid, r->w, r->g_mid);
        if (rs != RK45_SUCCESS) {
            return rs;
        }
        side_prev = side;
        double *g_mid = r->g_mid;
        /* a sign change in [t_lo, t_mid]? */
        int zero = 0;
        imax = strongest(r->g_lo, g_mid, m, &zero);
        if (imax >= 0) {
            t_hi = t_mid;
            r->g_mid = r->g_hi;
            r->g_hi = g_mid;
            double *w = r->w;
            r->w = r->y_mid;
            r->y_mid = w;
            *y_known = 1;
            if (zero) {
                break; /* g is exactly zero at t_mid */
            }
            side = 1;
            continue;
        }
        /* no: the root is in [t_mid, t_hi] */
        t_lo = t_mid;
        r->g_mid = r->g_lo;
        r->g_lo = g_mid;
        side = 2;
        imax = strongest(r->g_lo, r->g_hi, m, &unused);
        if (imax < 0) {
            break; /* round-off: keep t_hi */
        }
    }
    *t_root = t_hi;
    return 1;
}

/* Roots in (t_lo, t_n] of the last step, g_lo at t_lo given: RK45_ROOT with (t, y) at the root,
 * RK45_SUCCESS with the step's end, or a failure. */
int rk45_check_roots(rk45_t *r, double t_lo, double *t, double *y)
{
    if (r->n_roots > 0) {
        double t_root = r->t_n;
        int y_known = 0;
        const int found = find_root(r, t_lo, &t_root, &y_known);
        if (found < 0) {
            return found;
        }
        if (found > 0) {
            if (y_known) {
                memcpy(y, r->y_mid, (size_t)r->n * sizeof(double));
            } else {
                rk45_dense(r, t_root, 0, y);
            }
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
