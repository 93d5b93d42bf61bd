/* Root finding of the explicit Runge-Kutta 5(4) (rk45.h) on its dense output: Muller's parabola
 * kept inside a bracket of the sign change, the bracket closed to the tolerance in one evaluation
 * once the root is known. */
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

/* The search on component i: the newest end of the bracket (1: t_lo, 2: t_hi, 0: neither, at
 * the start) and the point that end replaced (t_c, g_c), the third point of the parabola. */
typedef struct {
    double t_c, g_c;
    int newest;
} bracket_t;

/* A point ttol / 2 or more inside [t_lo, t_hi] near t (CVODE's rule at the ends). */
static double inside(const rk45_t *r, double t_lo, double t_hi, double t, double ttol)
{
    const double half = 0.5 * (t_hi - t_lo) / r->h_last;
    const double frac = rk45_max(half > 0.1 ? 0.1 : half, 0.0);
    if (!(t - t_lo >= 0.5 * ttol)) {
        t = t_lo + frac * (t_hi - t_lo);
        t = t - t_lo >= 0.5 * ttol ? t : t_lo + 0.5 * ttol;
    }
    if (!(t_hi - t >= 0.5 * ttol)) {
        t = t_hi - frac * (t_hi - t_lo);
        t = t_hi - t >= 0.5 * ttol ? t : t_hi - 0.5 * ttol;
    }
    return t;
}

/* The root in [t_lo, t_hi] of the parabola through (t_lo, g_lo), (t_hi, g_hi) (opposite signs:
 * it has exactly one there) and (t_c, g_c) (Muller's method, order 1.84 per evaluation; unlike a
 * secant it follows g over a hump, as after a release); the secant root if it is lost to
 * round-off. */
static double parabola_root(double t_lo, double g_lo, double t_hi, double g_hi, double t_c,
                            double g_c)
{
    const double w = t_hi - t_lo, d1 = (g_hi - g_lo) / w;
    const double d2 = ((g_c - g_lo) / (t_c - t_lo) - d1) / (t_c - t_hi);
    /* g_lo + d1 u + d2 u (u - w) = a u^2 + b u + g_lo, u = t - t_lo */
    const double a = d2, b = d1 - d2 * w;
    const double disc = b * b - 4.0 * a * g_lo;
    const double q = -0.5 * (b + copysign(sqrt(rk45_max(disc, 0.0)), b));
    const double u1 = q / a, u2 = g_lo / q;
    const double u = u1 >= 0.0 && u1 <= w ? u1 : u2;
    return u >= 0.0 && u <= w ? t_lo + u : t_lo - g_lo / d1;
}

/* The next point inside the bracket [t_lo, t_hi] (g_i there: g_lo, g_hi): the parabola's root,
 * the regula falsi root at the start. Once it lies within ttol / 2 of the newest end the root is
 * known to far below ttol, so the point goes 3 ttol / 4 past that end: the sign change falls
 * inside and the bracket closes to the tolerance in this one evaluation instead of creeping up
 * to it from one side. */
static double next_point(const rk45_t *r, double t_lo, double t_hi, double g_lo, double g_hi,
                         const bracket_t *b, double ttol)
{
    const double t = b->newest == 0 ? t_hi - (t_hi - t_lo) * g_hi / (g_hi - g_lo)
                                    : parabola_root(t_lo, g_lo, t_hi, g_hi, b->t_c, b->g_c);
    if (b->newest == 1 && t - t_lo < 0.5 * ttol) {
        return inside(r, t_lo, t_hi, t_lo + 0.75 * ttol, ttol);
    }
    if (b->newest == 2 && t_hi - t < 0.5 * ttol) {
        return inside(r, t_lo, t_hi, t_hi - 0.75 * ttol, ttol);
    }
    return inside(r, t_lo, t_hi, t, ttol);
}

/* The end `moved` (1: t_lo, 2: t_hi) of the bracket, at (t_old, g_old), is replaced: it is the
 * parabola's third point from now on. */
static void move_end(bracket_t *b, int moved, double t_old, double g_old)
{
    b->t_c = t_old;
    b->g_c = g_old;
    b->newest = moved;
}

/* The first root of g in (t_lo, t_n] given g_lo (at t_lo) and g_n (at t_n): 0 if none, 1 with
 * the time in *t_root (the end of the final bracket, past the sign change) and g there in
 * g_hi, or a failure; *y_known: the state at *t_root is in y_mid (the last evaluation there).
 * Muller's parabola on the component whose secant root lies nearest t_lo; each
 * iteration's bracket keeps a sign change of some component. The vectors of g and the state at
 * the bracket's end trade places with the new point's instead of being copied. */
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
    bracket_t b = {0.0, 0.0, 0};
    *y_known = 0;
    while (t_hi - t_lo > ttol) {
        const double t_mid =
            next_point(r, t_lo, t_hi, r->g_lo[imax], r->g_hi[imax], &b, ttol);
        rk45_dense_inside(r, t_mid, r->w);
        const int rs = rk45_eval_roots(r, t_mid, r->w, r->g_mid);
        if (rs != RK45_SUCCESS) {
            return rs;
        }
        double *g_mid = r->g_mid;
        /* a sign change in [t_lo, t_mid]? */
        int zero = 0;
        const int i_prev = imax;
        imax = strongest(r->g_lo, g_mid, m, &zero);
        if (imax >= 0) {
            move_end(&b, 2, t_hi, r->g_hi[i_prev]);
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
        } else {
            /* no: the root is in [t_mid, t_hi] */
            move_end(&b, 1, t_lo, r->g_lo[i_prev]);
            t_lo = t_mid;
            r->g_mid = r->g_lo;
            r->g_lo = g_mid;
            imax = strongest(r->g_lo, r->g_hi, m, &unused);
            if (imax < 0) {
                break; /* round-off: keep t_hi */
            }
        }
        if (imax != i_prev) {
            b.newest = 0; /* another component crosses first: its search starts afresh */
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
                rk45_dense_inside(r, t_root, y);
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
