/* The co-simulation integrator interface (integrator.h) over our explicit Runge-Kutta 5(4)
 * (../../solvers/rk45.h): the cheapest choice while the motion is not stiff (6 right-hand sides
 * per step, dense output and root finding on it), and the one integrator whose steps can be
 * saved for a later analysis. */
#include <stdlib.h>

#include "integrator.h"
#include "rk45.h"

typedef struct {
    cs_problem_t problem;
    rk45_t *rk;
    rk45_stats_t at_start; /* its counters at its last (re)start */
} rk45_integrator_t;

/* A failed call: RK45's own message (what failed, with its values), then the flag. */
static int failed(const rk45_integrator_t *it, int flag, const char *call)
{
    const cs_problem_t *p = &it->problem;
    p->message(p->host, 0, "RK45", call, it->rk != NULL ? rk45_message(it->rk) : "out of memory");
    p->failed(p->host, call, rk45_flag_name(flag));
    return -1;
}

static void rk45_integrator_free(void *self)
{
    rk45_integrator_t *it = (rk45_integrator_t *)self;
    if (it != NULL) {
        rk45_free(it->rk);
        free(it);
    }
}

static void *rk45_integrator_create(const cs_problem_t *problem)
{
    rk45_integrator_t *it = (rk45_integrator_t *)calloc(1, sizeof(*it));
    if (it == NULL) {
        problem->error(problem->host, "out of memory");
        return NULL;
    }
    it->problem = *problem;
    it->rk = rk45_create(problem->n, problem->n_roots, problem->rhs,
                         problem->n_roots > 0 ? problem->roots : NULL, problem->host);
    if (it->rk == NULL ||
        rk45_set_tolerances(it->rk, problem->rtol, problem->atol) != RK45_SUCCESS) {
        failed(it, RK45_MEM_FAIL, "rk45_create");
        rk45_integrator_free(it);
        return NULL;
    }
    return it;
}

static int rk45_integrator_start(void *self, double t, const double *y, double h_first)
{
    rk45_integrator_t *it = (rk45_integrator_t *)self;
    rk45_get_stats(it->rk, &it->at_start);
    const int flag = rk45_init(it->rk, t, y, it->problem.first_step_max, h_first);
    return flag < 0 ? failed(it, flag, "rk45_init") : 0;
}

static int rk45_integrator_step(void *self, double *t, double *y)
{
    rk45_integrator_t *it = (rk45_integrator_t *)self;
    const int flag = rk45_step(it->rk, t, y);
    if (flag < 0) {
        failed(it, flag, "rk45_step");
        return CS_STEP_FAILED;
    }
    return flag == RK45_ROOT ? CS_STEP_ROOT : flag == RK45_TSTOP ? CS_STEP_TSTOP : CS_STEP_OK;
}

static int rk45_integrator_set_stop_time(void *self, double t_stop)
{
    rk45_integrator_t *it = (rk45_integrator_t *)self;
    const int flag = rk45_set_stop_time(it->rk, t_stop);
    return flag < 0 ? failed(it, flag, "rk45_set_stop_time") : 0;
}

static int rk45_integrator_dense(void *self, double t, int k, double *out)
{
    return rk45_dense(((rk45_integrator_t *)self)->rk, t, k, out);
}

static double rk45_integrator_time(const void *self)
{
    return rk45_current_time(((const rk45_integrator_t *)self)->rk);
}

static double rk45_integrator_last_step(const void *self)
{
    return rk45_last_step(((const rk45_integrator_t *)self)->rk);
}

static double rk45_integrator_next_step(const void *self)
{
    return rk45_next_step(((const rk45_integrator_t *)self)->rk);
}

static void rk45_integrator_counts(const void *self, cs_counts_t *counts)
{
    const rk45_integrator_t *it = (const rk45_integrator_t *)self;
    rk45_stats_t st;
    rk45_get_stats(it->rk, &st);
    counts->steps = st.steps - it->at_start.steps;
    counts->fails = st.fails - it->at_start.fails;
    counts->stiff = st.stiff - it->at_start.stiff;
    counts->jacobians = 0;
}

static size_t rk45_integrator_record_size(int n)
{
    return RK45_RECORD_SIZE(n);
}

static int rk45_integrator_save_step(void *self, double *record)
{
    return rk45_save_step(((rk45_integrator_t *)self)->rk, record);
}

static void rk45_integrator_record_view(const double *record, int n, cs_record_view_t *view)
{
    view->t0 = rk45_record_start(record);
    view->tn = rk45_record_end(record);
    view->y0 = rk45_record_y(record, n, 0);
    view->f0 = rk45_record_f(record, n, 0);
    view->y1 = rk45_record_y(record, n, 1);
    view->f1 = rk45_record_f(record, n, 1);
}

const cs_integrator_ops_t cs_integrator_rk45 = {
    .name = "RK45",
    .start_is_new = 1, /* rk45_init sets every value a step uses */
    .create = rk45_integrator_create,
    .free = rk45_integrator_free,
    .start = rk45_integrator_start,
    .step = rk45_integrator_step,
    .set_stop_time = rk45_integrator_set_stop_time,
    .dense = rk45_integrator_dense,
    .time = rk45_integrator_time,
    .last_step = rk45_integrator_last_step,
    .next_step = rk45_integrator_next_step,
    .counts = rk45_integrator_counts,
    .record_size = rk45_integrator_record_size,
    .save_step = rk45_integrator_save_step,
    .record_dense = rk45_record_dense,
    .record_view = rk45_integrator_record_view,
};
