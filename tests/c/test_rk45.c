/* The explicit Runge-Kutta 5(4) of the co-simulation FMU (fmu_src/solvers/rk45.c), against
 * analytic solutions: exponential decay and a harmonic oscillator (solution, dense output and
 * its derivative, the error's fall with the tolerance), roots of the oscillator's position at
 * the known instants (one per call, also several inside one step), a restart at a root with a
 * given first step, the self-contained step records, the stiffness indicator on a stiff
 * problem, and the failures: an unrecoverable right-hand side, a recoverable one that keeps
 * failing, a failing root function, bad input. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csfh_test.h"
#include "rk45.h"

typedef struct {
    double lambda; /* y' = lambda y (decay), or the oscillator's frequency */
    int fail;      /* 1: f fails recoverably, -1: unrecoverably, 0: never */
    int calls;
    int root_fail;
} problem_t;

static int decay(double t, const double *y, double *ydot, void *user)
{
    problem_t *p = (problem_t *)user;
    (void)t;
    p->calls++;
    ydot[0] = p->lambda * y[0];
    return p->fail;
}

/* x'' = -w^2 x as (x, v): x = cos(w t), v = -w sin(w t) from (1, 0) */
static int oscillator(double t, const double *y, double *ydot, void *user)
{
    problem_t *p = (problem_t *)user;
    (void)t;
    p->calls++;
    ydot[0] = y[1];
    ydot[1] = -p->lambda * p->lambda * y[0];
    return p->fail;
}

static int position(double t, const double *y, double *g, void *user)
{
    problem_t *p = (problem_t *)user;
    (void)t;
    g[0] = y[0];
    return p->root_fail;
}

static void test_decay_and_tolerance(void)
{
    double errors[3];
    const double rtols[3] = {1e-4, 1e-7, 1e-10};
    for (int k = 0; k < 3; k++) {
        problem_t p = {-2.0, 0, 0, 0};
        rk45_t *r = rk45_create(1, 0, decay, NULL, &p);
        const double atol = rtols[k] * 1e-3;
        CHECK_INT(rk45_set_tolerances(r, rtols[k], &atol), RK45_SUCCESS, "tolerances");
        double y = 1.0, t = 0.0;
        CHECK_INT(rk45_init(r, 0.0, &y, 1.0, 0.0), RK45_SUCCESS, "init");
        double worst = 0.0;
        while (t < 3.0) {
            CHECK_INT(rk45_step(r, &t, &y), RK45_SUCCESS, "step");
            worst = fmax(worst, fabs(y - exp(-2.0 * t)) / exp(-2.0 * t));
        }
        errors[k] = worst;
        /* the dense output and its derivative inside the last step */
        const double tm = rk45_current_time(r) - 0.37 * rk45_last_step(r);
        double ym, dm;
        rk45_dense(r, tm, 0, &ym);
        rk45_dense(r, tm, 1, &dm);
        CHECK_CLOSE(ym, exp(-2.0 * tm), 20.0 * rtols[k], TFMT("dense at rtol %g", rtols[k]));
        CHECK_CLOSE(dm, -2.0 * exp(-2.0 * tm), 200.0 * rtols[k],
                    TFMT("dense derivative at rtol %g", rtols[k]));
        rk45_free(r);
    }
    printf("     decay, largest relative error: %.2g (rtol 1e-4), %.2g (1e-7), %.2g (1e-10)\n",
           errors[0], errors[1], errors[2]);
    for (int k = 0; k < 3; k++) {
        CHECK_TRUE(errors[k] <= 10.0 * rtols[k], TFMT("error within 10 rtol at %g", rtols[k]));
    }
    CHECK_TRUE(errors[0] > 30.0 * errors[1] && errors[1] > 30.0 * errors[2],
               "the error falls with the tolerance");
}

/* The root returned lies past the sign change (sign `before` is cos's before the root) and
 * within the documented 100 eps (|t_n| + |h|) of it: the dense output there still has `before`. */
static void check_root_bracket(rk45_t *r, double t, double x, double before)
{
    const double ttol = 100.0 * DBL_EPSILON * (fabs(rk45_current_time(r)) + rk45_last_step(r));
    double w[2];
    rk45_dense(r, t - ttol, 0, w);
    CHECK_TRUE(before * x <= 0.0, TFMT("past the sign change at t = %.17g", t));
    CHECK_TRUE(before * w[0] > 0.0, TFMT("within 100 eps (|t_n| + |h|) of it at t = %.17g", t));
}

static void test_oscillator_roots(void)
{
    const double w = 3.0, rtol = 1e-10;
    problem_t p = {w, 0, 0, 0};
    rk45_t *r = rk45_create(2, 1, oscillator, position, &p);
    const double atol[2] = {1e-12, 1e-12};
    rk45_set_tolerances(r, rtol, atol);
    double y[2] = {1.0, 0.0}, t = 0.0;
    rk45_init(r, 0.0, y, 1.0, 0.0);
    int roots = 0;
    while (t < 10.0) {
        const int flag = rk45_step(r, &t, y);
        if (!CHECK_TRUE(flag >= 0, "no failure")) {
            break;
        }
        if (flag == RK45_ROOT) {
            /* x = cos(3 t) = 0 at t = (k + 1/2) pi / 3 */
            const double exact = (roots + 0.5) * TEST_PI / w;
            CHECK_ABS(t, exact, 1e-9, TFMT("root %d at (k + 1/2) pi / w", roots));
            CHECK_ABS(y[0], 0.0, 1e-9, "the state at the root is on the zero");
            check_root_bracket(r, t, y[0], roots % 2 == 0 ? 1.0 : -1.0);
            roots++;
        } else {
            CHECK_ABS(y[0], cos(w * t), 1e-8, "the solution at the step's end");
            CHECK_ABS(y[1], -w * sin(w * t), 3e-8, "its velocity");
        }
    }
    CHECK_INT(roots, 10, "every root of cos(3 t) in [0, 10] s");
    rk45_stats_t st;
    rk45_get_stats(r, &st);
    /* a superlinear search: bisection to the tolerance would take ~40 evaluations per root */
    const long search = st.roots - st.steps - 1;
    CHECK_TRUE(search <= 6 * roots, "at most 6 evaluations of g per root on average");
    rk45_free(r);
}

/* Loose tolerance on a slow oscillator: one step holds several roots, returned one per call. */
static void test_several_roots_in_one_step(void)
{
    problem_t p = {20.0, 0, 0, 0};
    rk45_t *r = rk45_create(2, 1, oscillator, position, &p);
    const double atol[2] = {1.0, 1.0};
    rk45_set_tolerances(r, 1.0, atol); /* everything passes: long steps */
    double y[2] = {1.0, 0.0}, t = 0.0;
    rk45_init(r, 0.0, y, 0.5, 0.5); /* a first step of 0.5 s: a sign change or several */
    rk45_stats_t s0, s1;
    rk45_get_stats(r, &s0);
    int flag = rk45_step(r, &t, y);
    rk45_get_stats(r, &s1);
    CHECK_INT(s1.steps - s0.steps, 1, "one step taken");
    CHECK_TRUE(fabs(rk45_last_step(r) - 0.5) < 1e-15, "of the given first size");
    int roots = 0;
    double last = 0.0;
    while (flag == RK45_ROOT) {
        CHECK_TRUE(t > last && t <= 0.5, "the roots come in order, inside the step");
        last = t;
        roots++;
        flag = rk45_step(r, &t, y);
    }
    rk45_get_stats(r, &s1);
    CHECK_INT(flag, RK45_SUCCESS, "then the step's end");
    CHECK_ABS(t, 0.5, 1e-15, "at the step's end");
    CHECK_INT(s1.steps - s0.steps, 1, "no new step for the roots inside the last one");
    CHECK_TRUE(roots >= 1, "at least one root found inside the long step");
    /* the long step's g is far from linear: a parabola follows it to the root, a regula falsi
     * creeps along it (~60 evaluations), bisection to the tolerance would take ~45 */
    CHECK_TRUE(s1.roots - s0.roots <= 16 * roots, "at most 16 evaluations of g per root");
    rk45_free(r);
}

static void test_records(void)
{
    problem_t p = {3.0, 0, 0, 0};
    rk45_t *r = rk45_create(2, 0, oscillator, NULL, &p);
    const double atol[2] = {1e-9, 1e-9};
    rk45_set_tolerances(r, 1e-8, atol);
    double y[2] = {1.0, 0.0}, t = 0.0, record[RK45_RECORD_SIZE(2)];
    rk45_init(r, 0.0, y, 1.0, 0.0);
    CHECK_INT(rk45_save_step(r, record), RK45_ILL_INPUT, "no record before a step");
    rk45_step(r, &t, y);
    rk45_step(r, &t, y);
    CHECK_INT(rk45_save_step(r, record), RK45_SUCCESS, "record of the last step");
    CHECK_ABS(rk45_record_end(record), t, 0.0, "its end is the step's end");
    CHECK_ABS(rk45_record_start(record), t - rk45_last_step(r), 1e-15, "its start");
    CHECK_ABS(rk45_record_y(record, 2, 1)[0], y[0], 0.0, "the state at its end");
    double f[2];
    oscillator(t, y, f, &p);
    CHECK_ABS(rk45_record_f(record, 2, 1)[1], f[1], 0.0, "f at its end (first same as last)");
    const double tm = rk45_record_start(record) + 0.3 * rk45_last_step(r);
    for (int k = 0; k < 2; k++) {
        double a[2], b[2];
        rk45_dense(r, tm, k, a);
        rk45_record_dense(record, 2, tm, k, b);
        CHECK_TRUE(a[0] == b[0] && a[1] == b[1], TFMT("record's dense output (k = %d) is the step's", k));
    }
    rk45_step(r, &t, y); /* the record stays valid after the integrator moves on */
    double b[2];
    rk45_record_dense(record, 2, tm, 0, b);
    CHECK_ABS(b[0], cos(3.0 * tm), 1e-7, "the record after the next step");
    rk45_free(r);
}

static void test_stiffness_indicator(void)
{
    /* y' = -1e5 y: the steps are held at the stability limit, h |lambda| ~ 3.3 */
    problem_t p = {-1e5, 0, 0, 0};
    rk45_t *r = rk45_create(1, 0, decay, NULL, &p);
    const double atol = 1e-3;
    rk45_set_tolerances(r, 1e-3, &atol);
    double y = 1.0, t = 0.0;
    rk45_init(r, 0.0, &y, 1.0, 0.0);
    while (t < 0.05) {
        rk45_step(r, &t, &y);
    }
    rk45_stats_t s;
    rk45_get_stats(r, &s);
    printf("     y' = -1e5 y: %ld steps, %ld at the stability limit, %ld rejected\n", s.steps,
           s.stiff, s.fails);
    CHECK_TRUE(s.steps > 0.05 * 1e5 / 4.0, "steps held near 3.3 / |lambda|");
    CHECK_TRUE(s.stiff > s.steps / 4, "a quarter or more flagged at the stability limit");
    CHECK_ABS(y, 0.0, 1e-3, "decayed, stable");
    rk45_free(r);
    /* the same at a mild lambda: never flagged */
    problem_t q = {-1.0, 0, 0, 0};
    r = rk45_create(1, 0, decay, NULL, &q);
    rk45_set_tolerances(r, 1e-3, &atol);
    y = 1.0, t = 0.0;
    rk45_init(r, 0.0, &y, 1.0, 0.0);
    while (t < 5.0) {
        rk45_step(r, &t, &y);
    }
    rk45_get_stats(r, &s);
    CHECK_INT(s.stiff, 0, "y' = -y: no step at the stability limit");
    rk45_free(r);
}

static void test_failures(void)
{
    problem_t p = {-1.0, 0, 0, 0};
    rk45_t *r = rk45_create(1, 1, decay, position, &p);
    const double atol = 1e-8, bad = -1.0;
    CHECK_INT(rk45_set_tolerances(r, 0.0, &atol), RK45_ILL_INPUT, "rtol 0 refused");
    CHECK_INT(rk45_set_tolerances(r, 1e-6, &bad), RK45_ILL_INPUT, "atol < 0 refused");
    CHECK_INT(rk45_set_tolerances(r, 1e-6, &atol), RK45_SUCCESS, "good tolerances");
    double y = 1.0, t = 0.0;
    CHECK_INT(rk45_step(r, &t, &y), RK45_ILL_INPUT, "no step before init");
    CHECK_INT(rk45_init(r, NAN, &y, 1.0, 0.0), RK45_ILL_INPUT, "non-finite start time refused");
    CHECK_INT(rk45_init(r, 0.0, &y, 1.0, 0.0), RK45_SUCCESS, "init");
    CHECK_INT(rk45_dense(r, 0.0, 0, &y), RK45_ILL_INPUT, "no dense output before a step");
    rk45_step(r, &t, &y);
    double out;
    CHECK_INT(rk45_dense(r, t + 1.0, 0, &out), RK45_ILL_INPUT, "no dense output beyond the step");
    CHECK_STR_CONTAINS(rk45_message(r), "outside the last step", "says why");
    const double t_ok = t, y_ok = y;
    p.fail = -1; /* unrecoverable */
    CHECK_INT(rk45_step(r, &t, &y), RK45_RHS_FAILURE, "f fails: RHS failure");
    CHECK_STR_CONTAINS(rk45_message(r), "right-hand side failed", "its message");
    CHECK_TRUE(t == t_ok && y == y_ok, "the last successful point is returned");
    p.fail = 1; /* recoverable, always */
    CHECK_INT(rk45_step(r, &t, &y), RK45_RHS_FAILURE, "f keeps failing recoverably");
    CHECK_STR_CONTAINS(rk45_message(r), "recoverably", "its message");
    CHECK_TRUE(t == t_ok && y == y_ok, "still the last successful point");
    p.fail = 0;
    p.root_fail = 1;
    CHECK_INT(rk45_step(r, &t, &y), RK45_ROOT_FAILURE, "g fails");
    CHECK_STR_CONTAINS(rk45_flag_name(RK45_ROOT_FAILURE), "RK45_ROOT_FAILURE", "flag name");
    rk45_free(r);
    CHECK_TRUE(rk45_create(0, 0, decay, NULL, NULL) == NULL, "n = 0 refused");
    CHECK_TRUE(rk45_create(1, 1, decay, NULL, NULL) == NULL, "roots without g refused");
}

int main(void)
{
    test_decay_and_tolerance();
    test_oscillator_roots();
    test_several_roots_in_one_step();
    test_records();
    test_stiffness_indicator();
    test_failures();
    return TEST_SUMMARY();
}
