/* The co-simulation integrator interface (integrator.h) over SUNDIALS CVODE:
 *   BDF    with Newton iteration, a dense direct linear solver and a difference-quotient
 *          Jacobian, or the host's (cs_problem_t.jacobian): for stiff motion (resting or
 *          rolling contact);
 *   Adams  Adams-Moulton with fixed-point iteration: no Jacobian and no linear algebra.
 * SUNDIALS' objects are made when CVODE first starts (a run that RK45 takes alone never touches
 * SUNDIALS). The memory is re-initialised at a restart, and made anew where it holds a stop time
 * at or behind the restart (SUNDIALS 6.4 clears a stop time only when it is reached, and
 * CVodeReInit keeps it: CVODE would refuse to step).
 *
 * Out of memory: SUNDIALS allocates when it makes its objects, at CVODE's first step (the
 * linear solver's saved Jacobian) and at every difference-quotient Jacobian (a vector). The
 * integrator sets aside a reserve when it is created and puts it in place around these calls
 * (sundials/csfh_sundials_alloc.h): SUNDIALS never sees a failed allocation, and when it needed
 * the reserve, every SUNDIALS object of the integrator is destroyed and the call fails, out of
 * memory (the next start makes them anew). */
#include <stdlib.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <sundials/csfh_sundials_alloc.h>

#include "integrator.h"

typedef struct {
    cs_problem_t problem;
    int lmm; /* CV_BDF or CV_ADAMS */
    /* vectors over the caller's arrays: the solution (ny), the absolute tolerances, and any
     * array CVodeGetDky writes to (nwork) */
    SUNContext ctx;
    N_Vector ny, nabstol, nwork;
    void *mem;
    int stop_set; /* CVODE holds a stop time it has not reached: stop */
    double stop;
    SUNMatrix J;
    SUNLinearSolver LS;
    SUNNonlinearSolver NLS; /* fixed-point iteration (Adams) */
    csfh_sundials_reserve_t reserve; /* in place around the calls of SUNDIALS that allocate */
} cvode_integrator_t;

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    const cvode_integrator_t *it = (const cvode_integrator_t *)user_data;
    return it->problem.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), it->problem.host);
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *gout, void *user_data)
{
    const cvode_integrator_t *it = (const cvode_integrator_t *)user_data;
    return it->problem.roots(t, N_VGetArrayPointer(y), gout, it->problem.host);
}

/* The host's Jacobian into CVODE's dense matrix (column-major, as cs_problem_t.jacobian's). */
static int jacobian(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *user_data,
                    N_Vector tmp1, N_Vector tmp2, N_Vector tmp3)
{
    (void)fy;
    (void)tmp1;
    (void)tmp2;
    (void)tmp3;
    const cvode_integrator_t *it = (const cvode_integrator_t *)user_data;
    return it->problem.jacobian(t, N_VGetArrayPointer(y), SUNDenseMatrix_Data(J),
                                it->problem.host);
}

static void error_handler(int error_code, const char *module, const char *function, char *msg,
                          void *user_data)
{
    const cvode_integrator_t *it = (const cvode_integrator_t *)user_data;
    it->problem.message(it->problem.host, error_code >= 0, module, function, msg);
}

/* A negative flag of `call`: reported (CVODE's own message is already out, error_handler). Only
 * with the reserve in place: SUNDIALS allocates the flag's name and writes it unchecked. */
static int check(const cvode_integrator_t *it, int flag, const char *call)
{
    if (flag >= 0) {
        return 0;
    }
    char *name = CVodeGetReturnFlagName(flag);
    it->problem.failed(it->problem.host, call, name != NULL ? name : "an unknown flag");
    free(name);
    return -1;
}

/* SUNDIALS' context and the vectors (after everything made with them). */
static void objects_free(cvode_integrator_t *it)
{
    N_Vector *vectors[] = {&it->ny, &it->nabstol, &it->nwork}; /* (the arrays are the host's) */
    for (size_t i = 0; i < sizeof(vectors) / sizeof(vectors[0]); i++) {
        if (*vectors[i] != NULL) {
            N_VDestroy(*vectors[i]);
            *vectors[i] = NULL;
        }
    }
    if (it->ctx != NULL) {
        SUNContext_Free(&it->ctx);
        it->ctx = NULL;
    }
}

/* ... made when CVODE first starts: 0, or -1 with nothing made. */
static int objects(cvode_integrator_t *it)
{
    if (SUNContext_Create(NULL, &it->ctx) != 0) {
        it->ctx = NULL;
        return -1;
    }
    const int n = it->problem.n;
    it->ny = N_VMake_Serial(n, NULL, it->ctx); /* over the caller's y at every call */
    it->nabstol = N_VMake_Serial(n, (sunrealtype *)it->problem.atol, it->ctx);
    it->nwork = N_VMake_Serial(n, NULL, it->ctx);
    if (it->ny == NULL || it->nabstol == NULL || it->nwork == NULL) {
        objects_free(it);
        return -1;
    }
    return 0;
}

/* Every SUNDIALS object of the integrator. */
static void sundials_free(cvode_integrator_t *it)
{
    if (it->mem != NULL) {
        CVodeFree(&it->mem);
    }
    if (it->LS != NULL) {
        SUNLinSolFree(it->LS);
        it->LS = NULL;
    }
    if (it->NLS != NULL) {
        SUNNonlinSolFree(it->NLS);
        it->NLS = NULL;
    }
    if (it->J != NULL) {
        SUNMatDestroy(it->J);
        it->J = NULL;
    }
    objects_free(it);
    it->stop_set = 0;
}

static void cvode_integrator_free(void *self)
{
    cvode_integrator_t *it = (cvode_integrator_t *)self;
    if (it == NULL) {
        return;
    }
    sundials_free(it);
    csfh_sundials_reserve_free(&it->reserve);
    free(it);
}

/* The reserve: what SUNDIALS 6.4.1 asks for when it makes every object of CVODE at once, with
 * room to spare: CVODE's memory, the context and the solvers, at most 32 vectors (Adams: 13 of
 * history), each with its table of operations, the dense matrix twice and the root finding's
 * arrays. The alloc test's run in which every allocation of SUNDIALS fails checks that it
 * suffices. */
static size_t reserve_size(const cs_problem_t *p)
{
    const size_t n = (size_t)p->n, vector = 1024 + n * sizeof(double);
    return 8192 + 32 * vector + 2 * n * n * sizeof(double) + 64 * (size_t)p->n_roots;
}

static void *create(const cs_problem_t *problem, int lmm)
{
    cvode_integrator_t *it = (cvode_integrator_t *)calloc(1, sizeof(*it));
    if (it == NULL || csfh_sundials_reserve_make(&it->reserve, reserve_size(problem)) != 0) {
        free(it);
        problem->error(problem->host, "out of memory");
        return NULL;
    }
    it->problem = *problem;
    it->lmm = lmm;
    return it;
}

/* Put the reserve in place before calling SUNDIALS. */
static void enter(cvode_integrator_t *it)
{
    csfh_sundials_reserve_enter(&it->reserve);
}

/* Take it away after: 0, or -1 when SUNDIALS needed it (then its objects are destroyed first,
 * while the blocks cut from the reserve are still known as such; reported). */
static int leave(cvode_integrator_t *it)
{
    const int used = csfh_sundials_reserve_used(&it->reserve);
    if (used) {
        const int short_of = it->reserve.short_of > 0;
        sundials_free(it);
        csfh_sundials_reserve_reset(&it->reserve);
        it->problem.error(it->problem.host,
                          short_of ? "out of memory in SUNDIALS (and its reserve was short)"
                                   : "out of memory in SUNDIALS (CVODE is made anew at the "
                                     "next step)");
    }
    csfh_sundials_reserve_leave(&it->reserve);
    return used ? -1 : 0;
}

static void *bdf_create(const cs_problem_t *problem)
{
    return create(problem, CV_BDF);
}

static void *adams_create(const cs_problem_t *problem)
{
    return create(problem, CV_ADAMS);
}

/* The new memory's problem (t, ny), messages, tolerances, solver and roots: 0, or -1 (reported;
 * the memory is then freed, never reused half set up). */
static int configure(cvode_integrator_t *it, double t)
{
    void *mem = it->mem;
    int s = check(it, CVodeSetErrHandlerFn(mem, error_handler, it), "CVodeSetErrHandlerFn");
    if (s == 0) s = check(it, CVodeInit(mem, rhs, t, it->ny), "CVodeInit");
    if (s == 0) s = check(it, CVodeSetUserData(mem, it), "CVodeSetUserData");
    if (s == 0) s = check(it, CVodeSVtolerances(mem, it->problem.rtol, it->nabstol), "CVodeSVtolerances");
    if (s == 0 && it->lmm == CV_ADAMS) {
        s = check(it, CVodeSetNonlinearSolver(mem, it->NLS), "CVodeSetNonlinearSolver");
    } else if (s == 0) {
        s = check(it, CVodeSetLinearSolver(mem, it->LS, it->J), "CVodeSetLinearSolver");
        if (s == 0 && it->problem.jacobian != NULL) {
            s = check(it, CVodeSetJacFn(mem, jacobian), "CVodeSetJacFn");
        }
    }
    if (s == 0) s = check(it, CVodeRootInit(mem, it->problem.n_roots, roots), "CVodeRootInit");
    if (s == 0) s = check(it, CVodeSetNoInactiveRootWarn(mem), "CVodeSetNoInactiveRootWarn");
    if (s != 0) {
        CVodeFree(&it->mem);
    }
    return s;
}

/* New CVODE memory at (t, ny), its solvers made once: 0, or -1 (reported). */
static int new_memory(cvode_integrator_t *it, double t)
{
    const int adams = it->lmm == CV_ADAMS;
    it->mem = CVodeCreate(it->lmm, it->ctx);
    if (adams && it->NLS == NULL) {
        it->NLS = SUNNonlinSol_FixedPoint(it->ny, 0, it->ctx);
    }
    if (!adams && it->J == NULL) {
        it->J = SUNDenseMatrix(it->problem.n, it->problem.n, it->ctx);
        it->LS = it->J != NULL ? SUNLinSol_Dense(it->ny, it->J, it->ctx) : NULL;
    }
    if (it->mem == NULL || (adams ? it->NLS == NULL : it->LS == NULL)) {
        it->problem.error(it->problem.host, "cannot allocate CVODE");
        if (it->mem != NULL) {
            CVodeFree(&it->mem); /* (never re-initialised half made) */
        }
        return -1;
    }
    return configure(it, t);
}

/* CVODE's memory made anew at (t, y), with the context, vectors and solvers it needs: 0, or -1
 * (reported). */
static int make(cvode_integrator_t *it, double t, const double *y)
{
    it->stop_set = 0;
    if (it->mem != NULL) {
        CVodeFree(&it->mem);
    }
    if (it->ctx == NULL && objects(it) != 0) {
        it->problem.error(it->problem.host, "cannot allocate SUNDIALS' context and vectors");
        return -1;
    }
    N_VSetArrayPointer((sunrealtype *)y, it->ny);
    return new_memory(it, t);
}

static int start(cvode_integrator_t *it, double t, const double *y)
{
    if (it->mem != NULL && !(it->stop_set && it->stop <= t)) {
        N_VSetArrayPointer((sunrealtype *)y, it->ny);
        return check(it, CVodeReInit(it->mem, t, it->ny), "CVodeReInit");
    }
    return make(it, t, y);
}

static int cvode_integrator_start(void *self, double t, const double *y, double h_first)
{
    cvode_integrator_t *it = (cvode_integrator_t *)self;
    (void)h_first; /* CVODE chooses its first step */
    enter(it);
    const int s = start(it, t, y);
    return leave(it) == 0 ? s : -1;
}

static int cvode_integrator_step(void *self, double *t, double *y)
{
    cvode_integrator_t *it = (cvode_integrator_t *)self;
    N_VSetArrayPointer(y, it->ny);
    /* tout only sets the size of the first step after a (re)start (CVODE's estimate is bounded
     * by a tenth of the distance to tout): a fixed horizon, so that the step sequence does not
     * depend on the communication grid */
    enter(it);
    const int flag = CVode(it->mem, *t + it->problem.first_step_max, it->ny, t, CV_ONE_STEP);
    if (flag < 0) {
        check(it, flag, "CVode");
    }
    if (leave(it) != 0 || flag < 0) {
        return CS_STEP_FAILED;
    }
    if (flag == CV_TSTOP_RETURN) {
        it->stop_set = 0; /* reached: CVODE has cleared it */
        return CS_STEP_TSTOP;
    }
    return flag == CV_ROOT_RETURN ? CS_STEP_ROOT : CS_STEP_OK;
}

static int cvode_integrator_set_stop_time(void *self, double t_stop)
{
    cvode_integrator_t *it = (cvode_integrator_t *)self;
    it->stop_set = 1;
    it->stop = t_stop;
    enter(it);
    const int s = check(it, CVodeSetStopTime(it->mem, t_stop), "CVodeSetStopTime");
    return leave(it) == 0 ? s : -1;
}

/* (The memory is NULL after SUNDIALS ran out of memory, until the next start: nothing to read.) */
static int cvode_integrator_dense(void *self, double t, int k, double *out)
{
    cvode_integrator_t *it = (cvode_integrator_t *)self;
    if (it->mem == NULL) {
        return -1;
    }
    N_VSetArrayPointer(out, it->nwork);
    return CVodeGetDky(it->mem, t, k, it->nwork);
}

static double cvode_integrator_time(const void *self)
{
    double tn = 0.0;
    void *mem = ((const cvode_integrator_t *)self)->mem;
    if (mem != NULL) {
        CVodeGetCurrentTime(mem, &tn);
    }
    return tn;
}

static double cvode_integrator_last_step(const void *self)
{
    double hu = 0.0;
    void *mem = ((const cvode_integrator_t *)self)->mem;
    if (mem != NULL) {
        CVodeGetLastStep(mem, &hu);
    }
    return hu;
}

static void cvode_integrator_counts(const void *self, cs_counts_t *counts)
{
    void *mem = ((const cvode_integrator_t *)self)->mem;
    long nconv = 0, nerr = 0;
    counts->steps = counts->jacobians = 0;
    if (mem != NULL) {
        CVodeGetNumSteps(mem, &counts->steps);
        if (((const cvode_integrator_t *)self)->lmm == CV_BDF) {
            CVodeGetNumJacEvals(mem, &counts->jacobians);
        }
        CVodeGetNumNonlinSolvConvFails(mem, &nconv);
        CVodeGetNumErrTestFails(mem, &nerr);
    }
    counts->fails = nconv + nerr;
    counts->stiff = 0;
}

#define CVODE_OPS(method_name, create_fn)                                                      \
    {                                                                                          \
        .name = method_name, .start_is_new = 0, .create = create_fn,                           \
        .free = cvode_integrator_free,                                                         \
        .start = cvode_integrator_start, .step = cvode_integrator_step,                        \
        .set_stop_time = cvode_integrator_set_stop_time, .dense = cvode_integrator_dense,      \
        .time = cvode_integrator_time, .last_step = cvode_integrator_last_step,                \
        .next_step = NULL, .counts = cvode_integrator_counts, .record_size = NULL,             \
        .save_step = NULL, .record_dense = NULL, .record_view = NULL,                          \
    }

const cs_integrator_ops_t cs_integrator_bdf = CVODE_OPS("BDF", bdf_create);
const cs_integrator_ops_t cs_integrator_adams = CVODE_OPS("Adams", adams_create);
