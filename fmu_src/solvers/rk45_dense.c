/* Dense output and saved steps of the explicit Runge-Kutta 5(4) (rk45.h): Shampine's
 * free 4th-order continuous extension (L. F. Shampine, "Some practical Runge-Kutta formulas",
 * Math. Comp. 46 (1986) 135-150). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "rk45_internal.h"

/* Shampine's continuous extension */
#define D1 (-12715105075.0 / 11282082432.0)
#define D3 (87487479700.0 / 32700410799.0)
#define D4 (-10690763975.0 / 1880347072.0)
#define D5 (701980252875.0 / 199316789632.0)
#define D6 (-1453857185.0 / 822651844.0)
#define D7 (69997945.0 / 29380423.0)


/* The coefficients r1..r5 (consecutive in d) of the step of size h from y_old to y with the
 * stages k[0..6] (none of them in d: the loop needs no overlap checks). */
static void coefficients(int n, double h, const double *restrict y_old, const double *restrict y,
                         const double *const k[7], double *restrict d)
{
    const double *restrict k1 = k[0], *restrict k3 = k[2], *restrict k4 = k[3],
                           *restrict k5 = k[4], *restrict k6 = k[5], *restrict k7 = k[6];
    for (int i = 0; i < n; i++) {
        const double dy = y[i] - y_old[i];
        const double b = h * k1[i] - dy;
        d[i] = y_old[i];
        d[n + i] = dy;
        d[2 * n + i] = b;
        d[3 * n + i] = dy - h * k7[i] - b;
        d[4 * n + i] =
            h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
    }
}

/* Shampine's coefficients of the last step, once per step. */
void rk45_dense_coefficients(rk45_t *r)
{
    if (r->dense_valid) {
        return;
    }
    coefficients(r->n, r->h_last, r->y_old, r->y, (const double *const *)r->k, r->dense[0]);
    r->dense_valid = 1;
}

/* The dense output (k = 0) or its derivative (k = 1) at theta in [0, 1] of a step of size h
 * from Shampine's coefficients r1..r5 (each n long, consecutive; out is never one of them: the
 * loops need no overlap checks). */
static void dense_eval(const double *restrict c, int n, double h, double th, int k,
                       double *restrict out)
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

void rk45_dense_inside(rk45_t *r, double t, double *out)
{
    rk45_dense_coefficients(r);
    const double h = r->h_last;
    double th = (t - r->t_old) / h;
    th = th < 0.0 ? 0.0 : (th > 1.0 ? 1.0 : th);
    dense_eval(r->dense[0], r->n, h, th, 0, out);
}

int rk45_dense(rk45_t *r, double t, int k, double *out)
{
    if (!r->have_step || (k != 0 && k != 1)) {
        return RK45_ILL_INPUT;
    }
    const double h = r->h_last;
    const double slack = 100.0 * DBL_EPSILON * (fabs(r->t_n) + fabs(h));
    if (!(t >= r->t_old - slack && t <= r->t_n + slack)) {
        rk45_set_message(r, "dense output at t = %.17g outside the last step, ending at %.17g", t,
                    r->t_n);
        return RK45_ILL_INPUT;
    }
    rk45_dense_coefficients(r);
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
    rk45_dense_coefficients(r);
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

