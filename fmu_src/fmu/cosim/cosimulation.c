/* Co-simulation: fmi2DoStep integrates the model with an integrator inside the FMU (SUNDIALS
 * CVODE, or our explicit Runge-Kutta 5(4), rk45.c) and locates every event inside the step by
 * root finding on the model-exchange event indicators (csfh: the gap, so every contact onset and
 * release). At each root the discrete state is updated (csfh: the onset indentation rate is
 * captured) and the integrator is restarted; the step then continues to its end, however many
 * events it holds. The communication points do not cut the integrator's steps short: it may step
 * past the end of a communication step, the FMU's state there is its interpolant (to the same
 * tolerance), and the next fmi2DoStep goes on from the integrator's internal state, so a fine
 * communication grid costs no extra integration steps.
 *
 * Method (fmu_model.cs_method; csfh: parameter solver.method):
 *   BDF    CVODE: BDF with Newton iteration, dense direct linear solver, difference-quotient
 *          Jacobian;
 *   Adams  CVODE: Adams-Moulton with fixed-point iteration: no Jacobian and no linear algebra;
 *   RK45   explicit Runge-Kutta 5(4) of Dormand and Prince (rk45.c): 6 right-hand sides per step
 *          and almost no bookkeeping, dense output and root finding on it; the cheapest choice
 *          while the motion is not stiff (flight, impacts resolved in time);
 *   auto   RK45; where it struggles (in a window of AUTO_WINDOW steps more than
 *          AUTO_SUSPECT_FAILED of the steps fail, or more than AUTO_SUSPECT_STIFF of them sit at
 *          its stability limit), BDF is tried for two windows (start-up, then measured) and kept
 *          if its mean step is more than AUTO_BDF_COST times RK45's (a BDF step costs about that
 *          much more), i.e. where the motion is stiff (resting or rolling contact); otherwise
 *          back to RK45, with the next trial after 1, 2, 4, ... windows. Every event restarts
 *          with RK45. The decision (auto_decide) is a pure function of the window's counts.
 *
 * Inputs are held constant over the communication step (zero-order hold); a changed input value,
 * a changed state or tunable parameter, and fmi2Get/SetFMUstate restart the integrator at the
 * communication point, so that its history never reaches across a discontinuity of the
 * right-hand side. Tolerances: relative = the fmi2SetupExperiment tolerance
 * (FMU_DEFAULT_TOLERANCE = 1e-6 when none is given), absolute = relative x the nominal value of
 * each state.
 *
 * A failure of the integrator returns FMU_ERROR with its own message and return flag in the
 * log; the instance then holds the last state it reached successfully, at that time (also
 * reported by fmi2GetRealStatus(fmi2LastSuccessfulTime)); fmi2SetFMUstate can roll it back.
 *
 * Time: the integrator runs in a local time tau = t - origin, measured from a time origin the
 * instance holds (the communication point where it was last started from outside: first step,
 * changed input, state or parameter, FMU state taken or restored; never moved at events). The
 * integration, its step sizes and its root finding are then the same whatever the start time: a
 * run from t0 = 1e10 s reproduces the run from 0, shifted, where an integrator in the absolute
 * time could not resolve its steps (ulp(1e10) = 1.9e-6 s) and drifted. A communication point
 * maps to tau exactly (t_end - origin, both multiples of ulp(origin) near the origin). CVODE's
 * own warnings (e.g. "t + h = t" after a very long run) make fmi2DoStep return fmi2Warning;
 * fmi2DoStep itself (fmu_instance.c: fmu_check_step) reports steps that the double time cannot
 * resolve.
 *
 * Work per step and per communication point: the outputs are not computed at the end of a step
 * but when they are read (fmi2GetReal, fmu_update_outputs), the event message is formatted only
 * when logEvents is on, and the peak outputs cost nothing outside the contact mode.
 *
 * FMI types: none. The solver_* wrappers, the peak analysis and cs_do_step use only the instance
 * (fmu_instance.h: the model, the log, the integrator, its own status type): the FMI 2.0 and
 * FMI 3.0 front-ends (fmi2_glue.c, fmi3_glue.c) call the same cs_do_step; FMI 3.0's early
 * return is its stop_at_event option (the step ends at the first contact onset or release).
 *
 * A model without continuous states (the comb-drive actuator) just advances its time. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include "cosimulation.h"
#include "fmu_instance.h"
#include "rk45.h"

#define NX fmu_model.n_states
#define MAX_EVENTS_PER_STEP 1000000L  /* guards against an endless chain of events */
#ifndef MAX_STEPS_PER_CALL
#define MAX_STEPS_PER_CALL 500000L    /* integrator steps per fmi2DoStep (the fuzz build lowers it) */
#endif
#define AUTO_WINDOW 100L              /* auto: steps per decision */
#define AUTO_SUSPECT_FAILED 0.05      /* auto: failed fraction of a window that triggers a trial */
#define AUTO_SUSPECT_STIFF 0.5        /* auto: fraction of RK45's steps at its stability limit
                                         that triggers a trial */
#define AUTO_BDF_COST 2.0             /* auto: cost of a BDF step over an RK45 step (measured:
                                         1.9 in resting contact, C master, 4 s of the
                                         central drop with c_r = 0.9 at rtol 1e-6) */
#define AUTO_MAX_HOLDOFF 64           /* auto: most windows between two trials */
#define FIRST_STEP_HORIZON 1.0        /* s: bound of the first step after a (re)start (see cs_do_step) */
#define FMU_EVENT_KINDS 8             /* RK45's first-step memory: event_update codes 1..7 */

/* Results of solver_step. */
/* what one pass of cs_do_step's loop reached: the end of a step, a root, a time event (the
 * integrator's stop time), auto's switch of method at the end of a step (kept pending when that
 * lies beyond the communication point, like a root there), or a failure */
enum { STEP_OK = 0, STEP_ROOT = 1, STEP_TSTOP = 2, STEP_SWITCH = 3, STEP_FAILED = -1 };

#define PEAK_LOG_MAX 64   /* RK45 steps kept for the peaks before they are analysed anyway */
#define PEAK_SNAPSHOTS 8  /* discrete states kept for them (events in one communication step) */

/* One RK45 step kept for the peak outputs (see the peak section). */
typedef struct {
    double t0, tn;     /* the step */
    double t_cut;      /* where it stops counting: tn, or the event that cut it short */
    int snapshot;      /* the model's discrete state it ran with: snap[snapshot] */
    int start_done, end_done, analysed;
    int start_valid, end_valid; /* the quantities are tracked there, values and slopes: */
    double v0[FMU_MAX_PEAKS], s0[FMU_MAX_PEAKS], v1[FMU_MAX_PEAKS], s1[FMU_MAX_PEAKS];
    int n_max;         /* the maxima inside it: times and values */
    double max_t[FMU_MAX_PEAKS];
    double max_v[FMU_MAX_PEAKS][FMU_MAX_PEAKS];
} peak_record_t;

struct csfh_cvode {
    /* SUNDIALS' objects, made when CVODE first runs (a run that RK45 takes alone never touches
     * SUNDIALS): its context, and vectors that wrap our arrays y and abstol, and any array
     * CVodeGetDky writes to (work) */
    SUNContext ctx;
    N_Vector ny, nabstol, nwork;
    int method;             /* the integrator running: FMU_CS_BDF, FMU_CS_ADAMS or FMU_CS_RK45 */
    /* CVODE (BDF, Adams); its memory is kept while RK45 runs */
    void *mem;
    int mem_method;         /* the method CVODE's memory was created with */
    int mem_stop_set;       /* CVODE holds a stop time it has not reached, mem_stop (local; SUNDIALS
                               6.4 clears it only when reached, CVodeReInit keeps it) */
    double mem_stop;
    double *abstol;         /* absolute tolerances (NX) */
    SUNMatrix J;
    SUNLinearSolver LS;
    SUNNonlinearSolver NLS; /* fixed-point iteration (Adams) */
    /* RK45 */
    rk45_t *rk;
    rk45_stats_t rk_start;  /* its counters at its last (re)start */
    /* the first step after an event of each kind (the model's event_update code): what the
     * step-size control proposed after the first step that followed the last such event, 0 if
     * none since the last restart from outside; hint_code: the kind of the last event, until its
     * segment's first step is taken */
    double event_h[FMU_EVENT_KINDS];
    int hint_code;
    double *y;              /* the integrator's solution at the time it returned (NX) */
    double tolerance;       /* the relative tolerance the solver was set up with */
    double *y_root;   /* a root (or time event) reported beyond the end of the last */
    double t_root;    /* communication step: the state there and its time, */
    int root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH, handled in the communication
                         step that contains it (0: none) */
    int switch_method; /* STEP_SWITCH pending: the method auto chose at t_root */
    long counted_steps; /* steps since the last (re)start already added to the model's counter */
    /* auto (auto_decide) */
    long window_steps;      /* the integrator's step, failure and stiff-step counts since its */
    long window_fails;      /* (re)start, and the time, at the start of the current window */
    long window_stiff;
    double window_t0;
    int trial;              /* 0, or BDF on trial: 1 starting up, 2 measured */
    int holdoff;            /* non-stiff windows left before the next trial */
    int next_holdoff;
    double nonstiff_h;      /* mean step of the non-stiff method in the window before the trial */
    /* peak outputs (fmu_model.n_peaks > 0, track_peaks): CVODE's steps, analysed when taken */
    double *peak_y, *peak_dy; /* work arrays (NX) */
    double peak_t;            /* the end of the last analysed step: */
    int peak_slope_valid;     /* its slopes and values there are valid */
    double peak_slope[FMU_MAX_PEAKS];
    double peak_end_v[FMU_MAX_PEAKS];
    int peak_n_max;           /* the maxima inside it: times and values */
    double peak_max_t[FMU_MAX_PEAKS];
    double peak_max_v[FMU_MAX_PEAKS][FMU_MAX_PEAKS];
    /* ... RK45's steps, kept and analysed when the peaks are read (peak_log_*) */
    double comm_start;        /* the communication step being taken: (comm_start, FMU time] */
    void *peak_room;          /* one block, allocated at the first step kept, for: */
    peak_record_t *log;       /* the steps that may still hold peaks of it, in order */
    double *log_data;         /* their RK45 records (RK45_RECORD_SIZE(NX) each) */
    int log_n;                /* (up to PEAK_LOG_MAX) */
    unsigned char *snap;      /* the discrete states the steps ran with (peaks_state_save) */
    int snap_n;               /* (up to PEAK_SNAPSHOTS) */
    int snap_stale;           /* the discrete state changed since the last copy */
    void *scratch;            /* the model's own one while analysing */
    double origin;      /* s: the integrator's time 0 (see the top of this file); its times are local */
    long warnings;      /* CVODE warnings so far (error_handler) */
    double arrays[];    /* y, abstol, y_root, peak_y, peak_dy: one block with the struct */
};

static const char *method_name(int method)
{
    switch (method) {
    case FMU_CS_BDF:
        return "BDF";
    case FMU_CS_ADAMS:
        return "Adams";
    case FMU_CS_RK45:
        return "RK45";
    default:
        return "auto";
    }
}

/* ------------------------------------------------------------------------------------------ */
/* the model as the integrators see it */

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    /* the model's time at CVODE's local time t (a time-dependent model: the shock pulse) */
    const int status = fmu_model.derivatives(inst->model, inst->cvode->origin + t,
                                             N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    return status == FMU_MODEL_NONFINITE ? 1 : 0; /* recoverable: CVODE retries a smaller step */
}

static int check_indicators(fmu_instance_t *inst, const double *gout)
{
    for (int i = 0; i < fmu_model.n_event_indicators; i++) {
        if (!isfinite(gout[i])) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: non-finite event indicator z[%d] = %g",
                    inst->step_function, i, gout[i]);
            return 1; /* the integrator fails the step */
        }
    }
    return 0;
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *gout, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    (void)t;
    fmu_model.event_indicators(inst->model, N_VGetArrayPointer(y), gout);
    return check_indicators(inst, gout);
}

static int rk_rhs(double t, const double *y, double *ydot, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    /* the model's time at the local time t, as for CVODE (rhs) */
    const int status = fmu_model.derivatives(inst->model, inst->cvode->origin + t, y, ydot);
    return status == FMU_MODEL_NONFINITE ? 1 : 0; /* recoverable: a smaller step */
}

static int rk_roots(double t, const double *y, double *gout, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    (void)t;
    fmu_model.event_indicators(inst->model, y, gout);
    return check_indicators(inst, gout);
}

static void error_handler(int error_code, const char *module, const char *function, char *msg,
                          void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    if (error_code < 0) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s %s: %s", module, function, msg);
    } else {
        if (inst->cvode != NULL) {
            inst->cvode->warnings++; /* the step returns a warning */
        }
        fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING, "%s %s (local time from t0 = %.17g): %s",
                module, function, inst->cvode != NULL ? inst->cvode->origin : 0.0, msg);
    }
}

/* SUNDIALS' context and the vectors that wrap our arrays (after everything made with them). */
static void cvode_objects_free(csfh_cvode_t *cv)
{
    N_Vector *vectors[] = {&cv->ny, &cv->nabstol, &cv->nwork}; /* (the arrays are ours) */
    for (size_t i = 0; i < sizeof(vectors) / sizeof(vectors[0]); i++) {
        if (*vectors[i] != NULL) {
            N_VDestroy(*vectors[i]);
            *vectors[i] = NULL;
        }
    }
    if (cv->ctx != NULL) {
        SUNContext_Free(&cv->ctx);
        cv->ctx = NULL;
    }
}

/* ... made when CVODE first runs: 0, or -1 with nothing made. */
static int cvode_objects(csfh_cvode_t *cv)
{
    if (SUNContext_Create(NULL, &cv->ctx) != 0) {
        cv->ctx = NULL;
        return -1;
    }
    cv->ny = N_VMake_Serial(NX, cv->y, cv->ctx);
    cv->nabstol = N_VMake_Serial(NX, cv->abstol, cv->ctx);
    cv->nwork = N_VMake_Serial(NX, cv->y, cv->ctx);
    if (cv->ny == NULL || cv->nabstol == NULL || cv->nwork == NULL) {
        cvode_objects_free(cv);
        return -1;
    }
    return 0;
}

void cs_free(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv == NULL) {
        return;
    }
    if (cv->mem != NULL) {
        CVodeFree(&cv->mem);
    }
    rk45_free(cv->rk);
    if (cv->LS != NULL) {
        SUNLinSolFree(cv->LS);
    }
    if (cv->NLS != NULL) {
        SUNNonlinSolFree(cv->NLS);
    }
    if (cv->J != NULL) {
        SUNMatDestroy(cv->J);
    }
    free(cv->peak_room);
    cvode_objects_free(cv);
    free(cv);
    inst->cvode = NULL;
}

static fmu_status_t cv_check(fmu_instance_t *inst, int flag, const char *call)
{
    if (flag >= 0) {
        return FMU_OK;
    }
    char *name = CVodeGetReturnFlagName(flag);
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: %s failed with %s at t = %.17g",
            inst->step_function, call,
            name != NULL ? name : "an unknown flag", *fmu_time(inst));
    free(name);
    return FMU_ERROR;
}

static fmu_status_t rk_check(fmu_instance_t *inst, int flag, const char *call)
{
    if (flag >= 0) {
        return FMU_OK;
    }
    /* RK45's own message (what failed, with its values), then the flag, as for CVODE */
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "RK45 %s: %s", call,
            inst->cvode->rk != NULL ? rk45_message(inst->cvode->rk) : "out of memory");
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: %s failed with %s at t = %.17g",
            inst->step_function, call,
            rk45_flag_name(flag), *fmu_time(inst));
    return FMU_ERROR;
}

/* ------------------------------------------------------------------------------------------ */
/* the integrator in use, behind one set of calls (times are local, see the top of this file) */

/* The end of the integrator's last step. */
static double solver_time(const csfh_cvode_t *cv)
{
    if (cv->method == FMU_CS_RK45) {
        return rk45_current_time(cv->rk);
    }
    double tn = 0.0;
    CVodeGetCurrentTime(cv->mem, &tn);
    return tn;
}

/* The size of the integrator's last step. */
static double solver_last_step(const csfh_cvode_t *cv)
{
    if (cv->method == FMU_CS_RK45) {
        return rk45_last_step(cv->rk);
    }
    double hu = 0.0;
    CVodeGetLastStep(cv->mem, &hu);
    return hu;
}

/* The state (k = 0) or its derivative (k = 1) at t inside the last step, from the integrator's
 * interpolant: 0, or < 0 outside it. */
static int solver_dense(const csfh_cvode_t *cv, double t, int k, double *out)
{
    if (cv->method == FMU_CS_RK45) {
        return rk45_dense(cv->rk, t, k, out);
    }
    N_VSetArrayPointer(out, cv->nwork);
    return CVodeGetDky(cv->mem, t, k, cv->nwork);
}

/* Steps, failed steps and steps at the stability limit (RK45) since the last (re)start. */
static void solver_counts(const csfh_cvode_t *cv, long *steps, long *fails, long *stiff)
{
    if (cv->method == FMU_CS_RK45) {
        rk45_stats_t st;
        rk45_get_stats(cv->rk, &st);
        *steps = st.steps - cv->rk_start.steps;
        *fails = st.fails - cv->rk_start.fails;
        *stiff = st.stiff - cv->rk_start.stiff;
        return;
    }
    long nconv = 0, nerr = 0;
    *steps = 0;
    CVodeGetNumSteps(cv->mem, steps);
    CVodeGetNumNonlinSolvConvFails(cv->mem, &nconv);
    CVodeGetNumErrTestFails(cv->mem, &nerr);
    *fails = nconv + nerr;
    *stiff = 0;
}

/* The bookkeeping of a (re)start: no steps counted yet, no pending root. */
static void solver_started(csfh_cvode_t *cv)
{
    cv->counted_steps = 0;
    cv->root_pending = 0;
    if (cv->rk != NULL) {
        rk45_get_stats(cv->rk, &cv->rk_start);
    }
}

/* (Re)start `method` at the local time tau from the state in cv->y; RK45 starts with the step
 * h_first if > 0 (else its estimate). CVODE's memory is created when missing or made with the
 * other CVODE method, else re-initialised; the vectors, the matrix and the solvers are kept from
 * one method to the next. */
static fmu_status_t solver_start(fmu_instance_t *inst, int method, double tau, double h_first)
{
    csfh_cvode_t *cv = inst->cvode;
    cv->method = method;
    if (method == FMU_CS_RK45) {
        if (cv->rk == NULL) {
            cv->rk = rk45_create(NX, fmu_model.n_event_indicators, rk_rhs,
                                 fmu_model.n_event_indicators > 0 ? rk_roots : NULL, inst);
            if (cv->rk == NULL ||
                rk45_set_tolerances(cv->rk, inst->tolerance, cv->abstol) != RK45_SUCCESS) {
                return rk_check(inst, RK45_MEM_FAIL, "rk45_create");
            }
        }
        solver_started(cv);
        return rk_check(inst,
                        rk45_init(cv->rk, tau, cv->y, FIRST_STEP_HORIZON, h_first),
                        "rk45_init");
    }
    if (cv->mem != NULL && cv->mem_method == method && !(cv->mem_stop_set && cv->mem_stop <= tau)) {
        solver_started(cv);
        return cv_check(inst, CVodeReInit(cv->mem, tau, cv->ny), "CVodeReInit");
    }
    /* new memory also where the old one holds a stop time at or behind tau: RK45 has passed it
     * since (auto), and CVODE would refuse to step */
    cv->mem_stop_set = 0;
    if (cv->mem != NULL) {
        CVodeFree(&cv->mem);
    }
    if (cv->ctx == NULL && cvode_objects(cv) != 0) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                "%s: cannot allocate SUNDIALS' context and vectors", inst->step_function);
        return FMU_ERROR;
    }
    cv->mem = CVodeCreate(method == FMU_CS_ADAMS ? CV_ADAMS : CV_BDF, cv->ctx);
    if (method == FMU_CS_ADAMS && cv->NLS == NULL) {
        cv->NLS = SUNNonlinSol_FixedPoint(cv->ny, 0, cv->ctx);
    }
    if (method != FMU_CS_ADAMS && cv->J == NULL) {
        cv->J = SUNDenseMatrix(NX, NX, cv->ctx);
        cv->LS = cv->J != NULL ? SUNLinSol_Dense(cv->ny, cv->J, cv->ctx) : NULL;
    }
    if (cv->mem == NULL || (method == FMU_CS_ADAMS ? cv->NLS == NULL : cv->LS == NULL)) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: cannot allocate CVODE",
                inst->step_function);
        return FMU_ERROR;
    }
    cv->mem_method = method;
    solver_started(cv);
    fmu_status_t s = cv_check(inst, CVodeSetErrHandlerFn(cv->mem, error_handler, inst), "CVodeSetErrHandlerFn");
    if (s == FMU_OK) s = cv_check(inst, CVodeInit(cv->mem, rhs, tau, cv->ny), "CVodeInit");
    if (s == FMU_OK) s = cv_check(inst, CVodeSetUserData(cv->mem, inst), "CVodeSetUserData");
    if (s == FMU_OK) s = cv_check(inst, CVodeSVtolerances(cv->mem, inst->tolerance, cv->nabstol), "CVodeSVtolerances");
    if (s == FMU_OK && method == FMU_CS_ADAMS) {
        s = cv_check(inst, CVodeSetNonlinearSolver(cv->mem, cv->NLS), "CVodeSetNonlinearSolver");
    } else if (s == FMU_OK) {
        s = cv_check(inst, CVodeSetLinearSolver(cv->mem, cv->LS, cv->J), "CVodeSetLinearSolver");
    }
    if (s == FMU_OK) s = cv_check(inst, CVodeRootInit(cv->mem, fmu_model.n_event_indicators, roots), "CVodeRootInit");
    if (s == FMU_OK) s = cv_check(inst, CVodeSetNoInactiveRootWarn(cv->mem), "CVodeSetNoInactiveRootWarn");
    if (s != FMU_OK) {
        CVodeFree(&cv->mem); /* half set up: never reused */
    }
    return s;
}

/* One internal step (or the next root inside the last one): STEP_OK, STEP_ROOT or STEP_FAILED
 * (logged); (tret, cv->y) is the point reached, on failure the last successful one. */
static int solver_step(fmu_instance_t *inst, double *tret)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv->method == FMU_CS_RK45) {
        const int flag = rk45_step(cv->rk, tret, cv->y);
        if (flag < 0) {
            rk_check(inst, flag, "rk45_step");
            return STEP_FAILED;
        }
        return flag == RK45_ROOT ? STEP_ROOT : flag == RK45_TSTOP ? STEP_TSTOP : STEP_OK;
    }
    /* tout only sets the size of the first step after a (re)start (CVODE's estimate is bounded
     * by a tenth of the distance to tout): a fixed horizon, so that the step sequence does not
     * depend on the communication grid */
    const int flag = CVode(cv->mem, *tret + FIRST_STEP_HORIZON, cv->ny, tret, CV_ONE_STEP);
    if (flag < 0) {
        /* CVODE's message is already in the log (error_handler); add the flag */
        cv_check(inst, flag, "CVode");
        return STEP_FAILED;
    }
    if (flag == CV_TSTOP_RETURN) {
        cv->mem_stop_set = 0; /* reached: CVODE has cleared it */
        return STEP_TSTOP;
    }
    return flag == CV_ROOT_RETURN ? STEP_ROOT : STEP_OK;
}

/* The next stop time (local; > the integrator's current time): no step goes beyond it. */
static fmu_status_t solver_set_stop_time(fmu_instance_t *inst, double tau_stop)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv->method == FMU_CS_RK45) {
        return rk_check(inst, rk45_set_stop_time(cv->rk, tau_stop), "rk45_set_stop_time");
    }
    cv->mem_stop_set = 1;
    cv->mem_stop = tau_stop;
    return cv_check(inst, CVodeSetStopTime(cv->mem, tau_stop), "CVodeSetStopTime");
}

/* ------------------------------------------------------------------------------------------ */
/* auto */

/* A new window of steps (the integrator's counters restart with every (re)start). */
static void start_window(csfh_cvode_t *cv, double t)
{
    solver_counts(cv, &cv->window_steps, &cv->window_fails, &cv->window_stiff);
    cv->window_t0 = t;
}

/* A new segment of smooth motion (start, event, restart): no trial, no hold-off. */
static void start_segment(csfh_cvode_t *cv, double t)
{
    start_window(cv, t);
    cv->trial = 0;
    cv->holdoff = 0;
    cv->next_holdoff = 1;
}

/* What auto knows of a finished window, and what it decides. */
typedef struct {
    int method;        /* the method that ran the window */
    long steps;        /* its steps (>= AUTO_WINDOW), */
    double failed;     /* the fraction of them that failed, */
    double stiff;      /* the fraction at the stability limit (RK45), */
    double mean_h;     /* and their mean size, s */
} auto_window_t;

typedef struct {
    int trial, holdoff, next_holdoff; /* (as in csfh_cvode_t) */
    double nonstiff_h;
} auto_state_t;

/* The method for the next window, from the one just finished (pure: no integrator, no FMI);
 * `nonstiff` is the method auto uses while not stiff. Writes the decision, if any, to `why`
 * (empty when nothing changes). */
static int auto_decide(auto_state_t *a, const auto_window_t *w, int nonstiff, char *why,
                       size_t why_size)
{
    why[0] = '\0';
    if (w->method != FMU_CS_BDF) {
        if (a->holdoff > 0) {
            a->holdoff--;
        } else if (w->failed > AUTO_SUSPECT_FAILED || w->stiff > AUTO_SUSPECT_STIFF) {
            a->nonstiff_h = w->mean_h;
            a->trial = 1;
            snprintf(why, why_size,
                     "auto: trying BDF (%.0f %% of %s's steps failed, %.0f %% at its stability "
                     "limit, mean step %.3g s)",
                     100.0 * w->failed, method_name(w->method), 100.0 * w->stiff, w->mean_h);
            return FMU_CS_BDF;
        }
        return w->method;
    }
    if (a->trial == 1) { /* BDF's start-up window: not measured */
        a->trial = 2;
        return FMU_CS_BDF;
    }
    if (a->trial == 2) {
        a->trial = 0;
        if (w->mean_h > AUTO_BDF_COST * a->nonstiff_h) {
            snprintf(why, why_size, "auto: BDF kept (stiff: mean step %.3g s, %s %.3g s)",
                     w->mean_h, method_name(nonstiff), a->nonstiff_h);
            return FMU_CS_BDF;
        }
        a->holdoff = a->next_holdoff;
        a->next_holdoff = a->next_holdoff < AUTO_MAX_HOLDOFF ? 2 * a->next_holdoff : AUTO_MAX_HOLDOFF;
        snprintf(why, why_size, "auto: back to %s (BDF's mean step %.3g s, %s %.3g s)",
                 method_name(nonstiff), w->mean_h, method_name(nonstiff), a->nonstiff_h);
        return nonstiff;
    }
    return FMU_CS_BDF;
}

/* auto: at the end of each window of AUTO_WINDOW steps (t: the local time), the method for the
 * next window; writes what it decided to `why` (empty when nothing changes). */
static int auto_choose(csfh_cvode_t *cv, double t, char *why, size_t why_size)
{
    why[0] = '\0';
    long steps = 0, fails = 0, stiff = 0;
    solver_counts(cv, &steps, &fails, &stiff);
    auto_window_t w = {cv->method, steps - cv->window_steps, 0.0, 0.0, 0.0};
    if (w.steps < AUTO_WINDOW) {
        return cv->method;
    }
    w.failed = (double)(fails - cv->window_fails) / (double)w.steps;
    w.stiff = (double)(stiff - cv->window_stiff) / (double)w.steps;
    w.mean_h = (t - cv->window_t0) / (double)w.steps;
    cv->window_steps = steps;
    cv->window_fails = fails;
    cv->window_stiff = stiff;
    cv->window_t0 = t;
    auto_state_t a = {cv->trial, cv->holdoff, cv->next_holdoff, cv->nonstiff_h};
    char text[200];
    const int method = auto_decide(&a, &w, FMU_CS_RK45, text, sizeof(text));
    cv->trial = a.trial;
    cv->holdoff = a.holdoff;
    cv->next_holdoff = a.next_holdoff;
    cv->nonstiff_h = a.nonstiff_h;
    if (text[0] != '\0') {
        snprintf(why, why_size, "t = %.17g: %s", cv->origin + t, text);
    }
    return method;
}

/* ------------------------------------------------------------------------------------------ */
/* Create the integrator (first step) or restart it at the current state, with the configured
 * method (auto starts with RK45); the FMU's time becomes the origin of the local time. */

static int configured_method(const fmu_instance_t *inst)
{
    return fmu_model.cs_method != NULL ? fmu_model.cs_method(inst->model) : FMU_CS_BDF;
}

static fmu_status_t cs_start(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv != NULL && cv->tolerance != inst->tolerance) {
        cs_free(inst);
        cv = NULL;
    }
    const int configured = configured_method(inst);
    const int method = configured == FMU_CS_AUTO ? FMU_CS_RK45 : configured;
    if (cv == NULL) {
        cv = (csfh_cvode_t *)calloc(1, sizeof(*cv) + 5 * (size_t)NX * sizeof(double));
        if (cv == NULL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s: out of memory", inst->step_function);
            return FMU_ERROR;
        }
        inst->cvode = cv;
        cv->tolerance = inst->tolerance;
        double *p = cv->arrays;
        cv->y = p, p += NX;
        cv->abstol = p, p += NX;
        cv->y_root = p, p += NX;
        cv->peak_y = p, p += NX;
        cv->peak_dy = p;
        /* absolute tolerance: relative tolerance times the nominal value of each state */
        double *atol = cv->abstol;
        int k = 0;
        for (int i = 0; i < fmu_model.n_variables && k < NX; i++) {
            if (fmu_model.variables[i].is_state) {
                atol[k++] = inst->tolerance * fmu_model.variables[i].nominal;
            }
        }
    }
    memcpy(cv->y, fmu_states(inst), NX * sizeof(double));
    cv->origin = *fmu_time(inst);
    memset(cv->event_h, 0, sizeof(cv->event_h)); /* a start from outside: no memory of events */
    cv->hint_code = 0;
    const fmu_status_t s = solver_start(inst, method, 0.0, 0.0);
    if (s != FMU_OK) {
        cs_free(inst);
        return s;
    }
    start_segment(cv, 0.0);
    return s;
}

/* Add the steps taken since the last call to the model's step counter. */
static long count_steps(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    long nsteps = 0, fails = 0, stiff = 0;
    solver_counts(cv, &nsteps, &fails, &stiff);
    const long added = nsteps - cv->counted_steps;
    cv->counted_steps = nsteps;
    if (fmu_model.add_integrator_steps != NULL && added != 0) {
        fmu_model.add_integrator_steps(inst->model, added);
    }
    return added;
}

/* ------------------------------------------------------------------------------------------ */
/* peak outputs: the largest values of the model's peak quantities over the communication step,
 * on the integrator's interpolant (the dense output of each step). Every step is analysed once:
 * its end values, and every maximum inside it (the quantity's slope + at the step's start, <= 0
 * at its end). Each communication step then takes the maxima that lie in it and the end values
 * of the steps that end in it; the values at the communication points themselves are the
 * outputs there (the model's outputs take the max with the step's peaks). Outside the contact
 * mode the model has nothing to track and nothing is evaluated.
 *
 * When: CVODE's steps are analysed when taken (its interpolant is gone after the next step).
 * RK45's steps are kept (their dense output, the states and f at their ends: rk45_save_step)
 * with the discrete state they ran with, and analysed only when the peaks are needed: when an
 * output is read (fmu_update_outputs), an FMU state is taken or a value set (cs_peaks_flush), or
 * PEAK_LOG_MAX steps or PEAK_SNAPSHOTS events have piled up. A master that reads no output of a
 * communication step does not pay for its peaks. The result does not depend on when (or
 * whether) the analysis runs: the values and slopes at a step's ends are functions of the state
 * and f there (the slope a forward difference along f, which the adjacent steps share exactly),
 * computed by the step that ends there and taken over by the next (the step kept before the
 * first one still needed is kept for that).
 *
 * A maximum inside a step is searched only if it can matter: the tangents at the bracket's ends
 * bound it (for a function concave between them, as any is near its maximum) by the height of
 * their intersection, and the search stops once that bound is within PEAK_RTOL x the integration
 * tolerance of the largest value found. Each iteration takes the maximum of the cubic Hermite
 * polynomial through the bracket's values and slopes (4th order: one or two iterations), so a
 * wiggle of the resting contact's force costs nothing and an impact's peak a few evaluations. */

#define PEAK_ITERATIONS 40 /* at most (a few are used) */
#define PEAK_RTOL 1.0      /* x the integration tolerance: the accuracy of a located maximum */

/* Where a step's states come from: the live integrator (CVODE, record NULL) or a kept RK45
 * step. */
typedef struct {
    const double *record;
    double t0, tn, h;
} peak_source_t;

/* The peak quantities v at time t of the step, and their time derivatives in slope (a forward
 * difference along the derivative of the state); 0 when the model has nothing to track there.
 * y_at_t, f_at_t: the state and its derivative at t if known (else NULL: interpolated). */
static int peak_point(fmu_instance_t *inst, const peak_source_t *src, double t,
                      const double *y_at_t, const double *f_at_t, double *v, double *slope)
{
    csfh_cvode_t *cv = inst->cvode;
    t = t < src->t0 ? src->t0 : (t > src->tn ? src->tn : t); /* round-off at the step's ends */
    double *py = cv->peak_y, *pd = cv->peak_dy;
    if (y_at_t != NULL) {
        memcpy(py, y_at_t, NX * sizeof(double));
    } else if (src->record != NULL) {
        rk45_record_dense(src->record, NX, t, 0, py);
    } else if (solver_dense(cv, t, 0, cv->peak_y) < 0) {
        return 0;
    }
    if (!fmu_model.peak_values(inst->model, py, v)) {
        return 0;
    }
    if (f_at_t != NULL) {
        memcpy(pd, f_at_t, NX * sizeof(double));
    } else if (src->record != NULL) {
        rk45_record_dense(src->record, NX, t, 1, pd);
    } else if (solver_dense(cv, t, 1, cv->peak_dy) < 0) {
        return 0;
    }
    const double eps = 1e-7 * (fabs(src->h) > 0.0 ? fabs(src->h) : 1e-9);
    for (int i = 0; i < NX; i++) {
        pd[i] = py[i] + eps * pd[i];
    }
    double ve[FMU_MAX_PEAKS];
    fmu_model.peak_values(inst->model, pd, ve);
    for (int j = 0; j < fmu_model.n_peaks; j++) {
        slope[j] = (ve[j] - v[j]) / eps;
    }
    return 1;
}

/* Forget what is known of CVODE's last step (restarted: a new interpolant). */
static void peaks_forget(csfh_cvode_t *cv)
{
    cv->peak_slope_valid = 0;
    cv->peak_n_max = 0;
}

/* Upper bound of a maximum between (a, va, sa) and (b, vb, sb) with sa > 0 >= sb: the height of
 * the intersection of the two tangents, over the larger end value (0 if below). */
static double peak_gain_bound(double a, double va, double sa, double b, double vb, double sb)
{
    double tx = (vb - va + sa * a - sb * b) / (sa - sb);
    tx = tx < a ? a : (tx > b ? b : tx);
    const double gain = va + sa * (tx - a) - (va > vb ? va : vb);
    return gain > 0.0 ? gain : 0.0;
}

/* The maximum in (0, 1) of the cubic Hermite polynomial with slopes d0 > 0 at 0 and d1 <= 0 at
 * 1 (slopes times the interval's length) and rise dv from 0 to 1; NaN if it has none there. */
static double hermite_max(double dv, double d0, double d1)
{
    /* p'(u) = d0 + B u + A u^2 */
    const double A = 3.0 * (d0 + d1 - 2.0 * dv), B = 2.0 * (3.0 * dv - 2.0 * d0 - d1);
    const double C = d0;
    double roots[2] = {NAN, NAN};
    if (fabs(A) <= 1e-12 * (fabs(B) + fabs(C))) {
        roots[0] = B != 0.0 ? -C / B : NAN;
    } else {
        const double disc = B * B - 4.0 * A * C;
        if (disc < 0.0) {
            return NAN;
        }
        const double q = -0.5 * (B + (B >= 0.0 ? sqrt(disc) : -sqrt(disc)));
        roots[0] = q / A;
        roots[1] = q != 0.0 ? C / q : NAN;
    }
    for (int i = 0; i < 2; i++) {
        const double u = roots[i];
        if (u > 0.0 && u < 1.0 && 2.0 * A * u + B <= 0.0) { /* p'' <= 0: a maximum */
            return u;
        }
    }
    return NAN;
}

/* The maxima inside a step with values and slopes v0, s0 at its start and v1, s1 at its end:
 * their times and the quantities there; returns how many. */
static int peak_maxima(fmu_instance_t *inst, const peak_source_t *src, const double *v0,
                       const double *s0, const double *v1, const double *s1, double *max_t,
                       double (*max_v)[FMU_MAX_PEAKS])
{
    int n_max = 0;
    for (int j = 0; j < fmu_model.n_peaks; j++) {
        if (!(s0[j] > 0.0 && s1[j] <= 0.0)) {
            continue;
        }
        double lo = src->t0, hi = src->tn, v_lo = v0[j], v_hi = v1[j], s_lo = s0[j], s_hi = s1[j];
        double best_t = NAN, best_v = -INFINITY, best[FMU_MAX_PEAKS];
        for (int k = 0; k < PEAK_ITERATIONS && hi - lo > 1e-7 * src->h; k++) {
            const double tol = PEAK_RTOL * inst->tolerance * fmax(fabs(v_lo), fabs(v_hi));
            if (peak_gain_bound(lo, v_lo, s_lo, hi, v_hi, s_hi) <= tol) {
                break;
            }
            const double L = hi - lo;
            double u = hermite_max(v_hi - v_lo, L * s_lo, L * s_hi);
            if (!(u > 0.0 && u < 1.0)) {
                u = s_lo / (s_lo - s_hi); /* secant on the slope */
            }
            u = u < 0.01 ? 0.01 : (u > 0.99 ? 0.99 : u); /* the bracket must shrink */
            const double mid = lo + u * L;
            double v[FMU_MAX_PEAKS], s[FMU_MAX_PEAKS];
            if (!peak_point(inst, src, mid, NULL, NULL, v, s)) {
                break;
            }
            if (v[j] > best_v) {
                best_v = v[j], best_t = mid;
                memcpy(best, v, sizeof(best));
            }
            if (s[j] > 0.0) {
                lo = mid, v_lo = v[j], s_lo = s[j];
            } else {
                hi = mid, v_hi = v[j], s_hi = s[j];
            }
        }
        if (best_v > v0[j] && best_v > v1[j]) { /* inside the step, above its ends */
            max_t[n_max] = best_t;
            memcpy(max_v[n_max], best, sizeof(best));
            n_max++;
        }
    }
    return n_max;
}

/* Analyse CVODE's new step [tn - hu, tn] (y_end: the state at tn, or NULL): its maxima and its
 * end. */
static void peak_step(fmu_instance_t *inst, const double *y_end)
{
    csfh_cvode_t *cv = inst->cvode;
    double v1[FMU_MAX_PEAKS], s1[FMU_MAX_PEAKS], s0[FMU_MAX_PEAKS], v0[FMU_MAX_PEAKS];
    const double tn = solver_time(cv), hu = solver_last_step(cv);
    const peak_source_t src = {NULL, tn - hu, tn, hu};
    const int have_start = cv->peak_slope_valid && cv->peak_t == src.t0;
    cv->peak_n_max = 0;
    if (have_start) {
        memcpy(s0, cv->peak_slope, sizeof(s0));
        memcpy(v0, cv->peak_end_v, sizeof(v0));
    }
    if (!peak_point(inst, &src, tn, y_end, NULL, v1, s1)) {
        cv->peak_slope_valid = 0;
        return;
    }
    if (have_start || peak_point(inst, &src, src.t0, NULL, NULL, v0, s0)) {
        cv->peak_n_max = peak_maxima(inst, &src, v0, s0, v1, s1, cv->peak_max_t, cv->peak_max_v);
    }
    memcpy(cv->peak_slope, s1, sizeof(s1));
    memcpy(cv->peak_end_v, v1, sizeof(v1));
    cv->peak_t = tn;
    cv->peak_slope_valid = 1;
}

/* --- RK45's steps, kept and analysed when needed ------------------------------------------ */

/* The discrete states kept for the peaks: peaks_state_size bytes each, at the strictest
 * alignment. */
static size_t snapshot_stride(void)
{
    const size_t align = _Alignof(max_align_t);
    return (fmu_model.peaks_state_size + align - 1) / align * align;
}

static unsigned char *snapshot(csfh_cvode_t *cv, int k)
{
    return cv->snap + (size_t)k * snapshot_stride();
}

static double *log_record(csfh_cvode_t *cv, int k)
{
    return cv->log_data + (size_t)k * RK45_RECORD_SIZE(NX);
}

/* Forget the kept steps (a restart from outside: the next ones start afresh). */
static void peak_log_clear(csfh_cvode_t *cv)
{
    cv->log_n = 0;
    cv->snap_n = 0;
    cv->snap_stale = 1;
}

/* Put the model into the discrete state kept step k ran with (set), or back into its own. Only
 * that discrete state is saved (peaks_state_save into the scratch), not the whole model: a copy
 * of the whole model (1.2 kB) for every analysed step was a tenth of the peaks' cost. */
static void with_step_state(fmu_instance_t *inst, int k, int set)
{
    csfh_cvode_t *cv = inst->cvode;
    if (set) {
        fmu_model.peaks_state_save(inst->model, cv->scratch);
        fmu_model.peaks_state_restore(inst->model, snapshot(cv, cv->log[k].snapshot));
    } else {
        fmu_model.peaks_state_restore(inst->model, cv->scratch);
    }
}

/* The values and slopes at the end (end = 1) or start (0) of kept step k (the model in its
 * discrete state). */
static void log_point(fmu_instance_t *inst, int k, int end)
{
    csfh_cvode_t *cv = inst->cvode;
    peak_record_t *r = &cv->log[k];
    const double *rec = log_record(cv, k);
    const peak_source_t src = {rec, r->t0, r->tn, r->tn - r->t0};
    if (end) {
        r->end_valid = peak_point(inst, &src, r->tn, rk45_record_y(rec, NX, 1),
                                  rk45_record_f(rec, NX, 1), r->v1, r->s1);
        r->end_done = 1;
    } else {
        r->start_valid = peak_point(inst, &src, r->t0, rk45_record_y(rec, NX, 0),
                                    rk45_record_f(rec, NX, 0), r->v0, r->s0);
        r->start_done = 1;
    }
}

/* Analyse kept step k: its ends (the start is the previous step's end when that one is kept,
 * ends where this one starts and ran in the same discrete state) and its maxima. */
static void log_analyse(fmu_instance_t *inst, int k)
{
    csfh_cvode_t *cv = inst->cvode;
    peak_record_t *r = &cv->log[k];
    if (r->analysed) {
        return;
    }
    peak_record_t *p = k > 0 ? &cv->log[k - 1] : NULL;
    const int chained =
        p != NULL && p->tn == r->t0 && p->t_cut == p->tn && p->snapshot == r->snapshot;
    with_step_state(inst, k, 1);
    if (chained) {
        if (!p->end_done) {
            log_point(inst, k - 1, 1); /* (the same discrete state) */
        }
        r->start_valid = p->end_valid;
        memcpy(r->v0, p->v1, sizeof(r->v0));
        memcpy(r->s0, p->s1, sizeof(r->s0));
        r->start_done = 1;
    } else {
        log_point(inst, k, 0);
    }
    log_point(inst, k, 1);
    r->n_max = 0;
    if (r->start_valid && r->end_valid) {
        const peak_source_t src = {log_record(cv, k), r->t0, r->tn, r->tn - r->t0};
        r->n_max = peak_maxima(inst, &src, r->v0, r->s0, r->v1, r->s1, r->max_t, r->max_v);
    }
    with_step_state(inst, k, 0);
    r->analysed = 1;
}

/* Add the peaks of the kept steps that lie in the communication step so far, (comm_start, t]. */
static void peak_log_add(fmu_instance_t *inst, double t)
{
    csfh_cvode_t *cv = inst->cvode;
    for (int k = 0; k < cv->log_n; k++) {
        peak_record_t *r = &cv->log[k];
        if (!(r->t_cut > cv->comm_start && r->t0 < t)) {
            continue; /* outside (kept for its end values only, or not yet reached) */
        }
        log_analyse(inst, k);
        for (int m = 0; m < r->n_max; m++) {
            if (r->max_t[m] > cv->comm_start && r->max_t[m] <= t && r->max_t[m] <= r->t_cut) {
                fmu_model.peaks_add(inst->model, r->max_v[m]);
            }
        }
        if (r->end_valid && r->t_cut == r->tn && r->tn <= t) {
            fmu_model.peaks_add(inst->model, r->v1);
        }
    }
}

/* Keep only the kept steps from `first` on, and the discrete states they refer to. */
static void peak_log_keep_from(csfh_cvode_t *cv, int first)
{
    if (first > 0) {
        memmove(cv->log, cv->log + first, (size_t)(cv->log_n - first) * sizeof(peak_record_t));
        memmove(cv->log_data, log_record(cv, first),
                (size_t)(cv->log_n - first) * RK45_RECORD_SIZE(NX) * sizeof(double));
        cv->log_n -= first;
    }
    if (cv->log_n == 0) {
        cv->snap_n = 0;
        cv->snap_stale = 1;
        return;
    }
    const int used = cv->log[0].snapshot; /* the snapshots are in the steps' order */
    if (used > 0) {
        memmove(cv->snap, snapshot(cv, used), (size_t)(cv->snap_n - used) * snapshot_stride());
        cv->snap_n -= used;
        for (int k = 0; k < cv->log_n; k++) {
            cv->log[k].snapshot -= used;
        }
    }
}

/* Drop the kept steps that count only up to t, except the last of them (its end values may
 * start the next step). */
static void peak_log_drop(csfh_cvode_t *cv, double t)
{
    int first = 0;
    while (first < cv->log_n && cv->log[first].t_cut <= t) {
        first++;
    }
    peak_log_keep_from(cv, first > 0 ? first - 1 : 0);
}

/* The room for the kept steps, at its full size in one block (nothing is zeroed: a restart
 * from outside frees nothing): the scratch copy of the model's discrete state and the
 * snapshots of it (snapshot_stride() apart), the records, their RK45 data. Grown in steps
 * instead, each growth copied the kept records (the larger part of the memory that a short run
 * touched for the first time). */
static int peak_room_alloc(csfh_cvode_t *cv)
{
    const size_t states = (1 + (size_t)PEAK_SNAPSHOTS) * snapshot_stride();
    const size_t log = (size_t)PEAK_LOG_MAX * sizeof(peak_record_t);
    const size_t data = (size_t)PEAK_LOG_MAX * RK45_RECORD_SIZE(NX) * sizeof(double);
    unsigned char *room = (unsigned char *)malloc(states + log + data);
    if (room == NULL) {
        return 0;
    }
    cv->peak_room = room;
    cv->scratch = room;
    cv->snap = room + snapshot_stride();
    cv->log = (peak_record_t *)(void *)(room + states);
    cv->log_data = (double *)(void *)(room + states + log);
    return 1;
}

/* Keep RK45's new step for the peaks (t_now: where the communication step has got to before
 * it); 0 if it cannot be kept (out of memory, or a model without peaks_state_save: the step is
 * then analysed now, as CVODE's). */
static int peak_log_keep(fmu_instance_t *inst, double t_now)
{
    csfh_cvode_t *cv = inst->cvode;
    if (fmu_model.peaks_state_save == NULL) {
        return 0;
    }
    if (cv->peak_room == NULL && !peak_room_alloc(cv)) {
        return 0;
    }
    if (cv->log_n == PEAK_LOG_MAX || (cv->snap_stale && cv->snap_n == PEAK_SNAPSHOTS)) {
        /* piled up in this communication step: analyse them now, keep the last (its end
         * values start the new step) */
        peak_log_add(inst, t_now);
        peak_log_keep_from(cv, cv->log_n - 1);
    }
    if (cv->snap_stale || cv->snap_n == 0) {
        fmu_model.peaks_state_save(inst->model, snapshot(cv, cv->snap_n));
        cv->snap_n++;
        cv->snap_stale = 0;
    }
    const int k = cv->log_n;
    double *rec = log_record(cv, k);
    if (rk45_save_step(cv->rk, rec) != RK45_SUCCESS) {
        return 0;
    }
    peak_record_t *r = &cv->log[k];
    r->t0 = rk45_record_start(rec);
    r->tn = rk45_record_end(rec);
    r->t_cut = r->tn;
    r->snapshot = cv->snap_n - 1;
    r->start_done = r->end_done = r->analysed = 0;
    r->start_valid = r->end_valid = 0;
    r->n_max = 0;
    cv->log_n++;
    return 1;
}

/* An event at t (local time) changes the discrete state: the kept step holding it stops counting
 * there. */
static void peak_log_event(csfh_cvode_t *cv, double t)
{
    if (cv->log_n > 0) {
        peak_record_t *r = &cv->log[cv->log_n - 1];
        if (t > r->t0 && t < r->t_cut) {
            r->t_cut = t;
        }
    }
    cv->snap_stale = 1;
}

void cs_peaks_flush(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv == NULL || cv->log_n == 0 || NX == 0) {
        return;
    }
    const double now = *fmu_time(inst) - cv->origin;
    peak_log_add(inst, now);
    /* what ends by now is done for this communication step, but the next one may need the
     * last of them */
    peak_log_drop(cv, now);
}

/* The part [ta, tb] of the communication step, the state at tb in cv->y; `stepped`: the
 * integrator took a new step to get there (tb is its end unless a root or the communication
 * point came first). */
static void track_peaks(fmu_instance_t *inst, double ta, double tb, int stepped)
{
    csfh_cvode_t *cv = inst->cvode;
    if (fmu_model.n_peaks <= 0) {
        return;
    }
    if (fmu_model.peaks_tracked != NULL && !fmu_model.peaks_tracked(inst->model)) {
        peaks_forget(cv); /* nothing to track in this discrete state (out of contact) */
        return;
    }
    if (cv->method == FMU_CS_RK45) {
        if (!stepped || peak_log_keep(inst, ta)) {
            return; /* analysed when needed */
        }
    }
    if (stepped) {
        /* the previous CVODE step may reach into this part (it ended beyond the last
         * communication point): take its maxima and its end there before the new step's
         * analysis replaces them */
        for (int m = 0; m < cv->peak_n_max; m++) {
            if (cv->peak_max_t[m] > ta && cv->peak_max_t[m] <= tb) {
                fmu_model.peaks_add(inst->model, cv->peak_max_v[m]);
            }
        }
        if (cv->peak_slope_valid && cv->peak_t > ta && cv->peak_t <= tb) {
            fmu_model.peaks_add(inst->model, cv->peak_end_v);
        }
        const double tn = solver_time(cv);
        peak_step(inst, tb == tn ? cv->y : NULL);
        if (cv->peak_slope_valid && tb == cv->peak_t) {
            fmu_model.peaks_add(inst->model, cv->peak_end_v);
        }
    }
    for (int m = 0; m < cv->peak_n_max; m++) {
        if (cv->peak_max_t[m] > ta && cv->peak_max_t[m] <= tb) {
            fmu_model.peaks_add(inst->model, cv->peak_max_v[m]);
        }
    }
}

/* Take the integrator's solution (local time tret, cv->y) as the model's time and state. */
static void take_solution(fmu_instance_t *inst, double tret)
{
    memcpy(fmu_states(inst), inst->cvode->y, NX * sizeof(double));
    *fmu_time(inst) = inst->cvode->origin + tret;
    fmu_invalidate(inst);
}

/* The step ends at t_end. The outputs are left to be computed when they are read
 * (fmu_update_outputs: fmi2GetReal, or the next step's peaks), so that a master that reads only
 * states pays nothing for them. */
static fmu_status_t finish_step(fmu_instance_t *inst, double t_end, fmu_status_t status)
{
    *fmu_time(inst) = t_end; /* exact communication point (tret == t_end up to round-off) */
    fmu_invalidate(inst);
    return status;
}

/* ------------------------------------------------------------------------------------------ */
/* time events (fmu_model.next_time_event; csfh: the start and end of the shock pulse, where the
 * right-hand side has a kink): the integrator is given the next one as its stop time, so that no
 * step straddles it; it returns STEP_TSTOP there, and cs_do_step restarts it as at a state
 * event. Without time events nothing here is called. */

static fmu_status_t set_time_event_stop(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    const double tn = solver_time(cv);
    double after = cv->origin + tn;
    for (int i = 0; i < 8; i++) { /* events that round to CVODE's current time are behind it */
        const double te = fmu_model.next_time_event(inst->model, after);
        if (!isfinite(te)) {
            return FMU_OK;
        }
        if (te - cv->origin > tn) {
            return solver_set_stop_time(inst, te - cv->origin);
        }
        after = te;
    }
    return FMU_OK;
}

/* auto's decision at the local time t (logged when it changes something): the method for what
 * follows. */
static int auto_next_method(fmu_instance_t *inst, double t)
{
    char why[256];
    const int method = auto_choose(inst->cvode, t, why, sizeof(why));
    if (why[0] != '\0') {
        fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", why);
    }
    return method;
}

fmu_status_t cs_do_step(fmu_instance_t *inst, double t_end_abs, int stop_at_event, int *stopped)
{
    const double now_abs = *fmu_time(inst);
    if (stopped != NULL) {
        *stopped = 0;
    }
    if (NX == 0) {
        return finish_step(inst, t_end_abs, FMU_OK); /* no continuous states: nothing to integrate */
    }
    if (inst->cvode == NULL || inst->cvode_needs_reinit) {
        if (cs_start(inst) != FMU_OK) {
            return FMU_ERROR;
        }
        inst->cvode_needs_reinit = 0;
        peaks_forget(inst->cvode); /* a new interpolant */
        peak_log_clear(inst->cvode);
    }
    csfh_cvode_t *cv = inst->cvode;
    const long warnings = cv->warnings;
    /* the integrator's local times (see the top of this file) */
    const double now = now_abs - cv->origin;
    const double t_end = t_end_abs - cv->origin;
    const int automatic = configured_method(inst) == FMU_CS_AUTO;
    long events = 0, steps = 0;
    double tret = now;
    if (fmu_model.n_peaks > 0) { /* the step's peaks start with the values at its start */
        fmu_model.peaks_begin(inst->model, inst->outputs_valid);
    }
    cv->comm_start = now;
    peak_log_drop(cv, now); /* RK45's steps that ended before: their peaks were not read */
    while (tret < t_end) {
        /* One internal step per call: the solution is taken at every step, and auto can check
         * the stiffness without waiting for the end of the communication step. No stop time:
         * the communication points do not cut the integrator's steps short. A step that ends
         * beyond t_end is not repeated: the state at t_end comes from the interpolant (for this
         * and for later communication points the step covers), and a root reported beyond t_end
         * is kept pending until the communication step that contains it. */
        int flag;
        const double tret_before = tret;
        if (cv->root_pending && cv->t_root <= t_end) {
            memcpy(cv->y, cv->y_root, NX * sizeof(double));
            tret = cv->t_root;
            flag = cv->root_pending; /* STEP_ROOT, STEP_TSTOP or STEP_SWITCH */
            cv->root_pending = 0;
        } else if (cv->root_pending || solver_time(cv) >= t_end) {
            /* the last step (and the root check) already reaches past t_end */
            flag = solver_dense(cv, t_end, 0, cv->y) < 0 ? STEP_FAILED : STEP_OK;
            if (flag == STEP_FAILED) {
                fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                        "%s: the interpolant of %s does not reach t = %.17g", inst->step_function,
                        method_name(cv->method), t_end_abs);
            }
            tret = t_end;
        } else {
            if (fmu_model.next_time_event != NULL && set_time_event_stop(inst) != FMU_OK) {
                inst->cvode_needs_reinit = 1;
                return FMU_ERROR;
            }
            flag = solver_step(inst, &tret);
            if (flag == STEP_OK && automatic && tret >= t_end) {
                /* auto decides at the end of every step, also of one that reaches the
                 * communication point, and switches there (at once, or in the communication
                 * step that contains it): its decisions do not depend on the grid */
                const int method = auto_next_method(inst, tret);
                if (method != cv->method) {
                    flag = STEP_SWITCH;
                    cv->switch_method = method;
                }
            }
            if (flag != STEP_FAILED && tret > t_end) {
                if (flag != STEP_OK) { /* a root, time event or switch beyond t_end */
                    memcpy(cv->y_root, cv->y, NX * sizeof(double));
                    cv->t_root = tret;
                    cv->root_pending = flag;
                }
                flag = solver_dense(cv, t_end, 0, cv->y) < 0 ? STEP_FAILED : STEP_OK;
                tret = t_end;
            }
        }
        const long added = count_steps(inst);
        const int stepped = added > 0; /* a new step (not a second root inside the last one) */
        steps += added;
        if (cv->hint_code > 0 && stepped && cv->method == FMU_CS_RK45) {
            /* the first step after an event: remember where the step-size control went */
            cv->event_h[cv->hint_code] = rk45_next_step(cv->rk);
            cv->hint_code = 0;
        }
        if (flag == STEP_FAILED) {
            /* the integrator's message and flag are in the log; it returns the last successful
             * point in (tret, y): keep it, so that what the master reads is consistent (time,
             * state, discrete state), never a half-taken step */
            const double *y = cv->y;
            int finite = isfinite(tret) && tret >= now && tret <= t_end;
            for (int i = 0; i < NX; i++) {
                finite = finite && isfinite(y[i]);
            }
            if (finite) {
                take_solution(inst, tret);
            }
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "%s: the step from t = %.17g to %.17g failed; the FMU holds the last "
                    "successful state, at t = %.17g", inst->step_function,
                    now_abs, t_end_abs, *fmu_time(inst));
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        track_peaks(inst, tret_before, tret, stepped);
        take_solution(inst, tret);
        if (flag == STEP_OK && tret >= t_end) {
            break;
        }
        if (steps > MAX_STEPS_PER_CALL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "%s: more than %ld %s steps in the step from t = %.17g to %.17g; "
                    "the FMU holds the state at t = %.17g", inst->step_function,
                    MAX_STEPS_PER_CALL, method_name(cv->method), now_abs, t_end_abs,
                    *fmu_time(inst));
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        int restart = 0, kind = 0;
        if (flag == STEP_ROOT) {
            if (++events > MAX_EVENTS_PER_STEP) {
                fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                        "%s: more than %ld events in one step at t = %.17g", inst->step_function,
                        MAX_EVENTS_PER_STEP, *fmu_time(inst));
                inst->cvode_needs_reinit = 1;
                return FMU_ERROR;
            }
            /* the discrete state changed: restart the integrator at the event (auto: with the
             * non-stiff method again) */
            kind = fmu_event_update(inst);
            restart = kind != 0;
            if (restart) {
                peaks_forget(cv); /* what follows the event has a new interpolant */
                peak_log_event(cv, tret);
            }
        } else if (flag == STEP_TSTOP) {
            restart = 1; /* a time event: the right-hand side's kink (see set_time_event_stop) */
            peaks_forget(cv);
        }
        fmu_status_t s = FMU_OK;
        if (restart) {
            /* RK45 starts with the step that suited the last event of this kind: the first-step
             * estimate, made for smooth solutions, overshoots at a contact onset (the force
             * grows as the indentation^1.5) by orders of magnitude, and the rejected attempts
             * cost 6 evaluations each */
            const int code = kind > 0 && kind < FMU_EVENT_KINDS ? kind : 0;
            cv->hint_code = code;
            s = solver_start(inst, automatic ? FMU_CS_RK45 : cv->method, tret,
                             code > 0 ? cv->event_h[code] : 0.0);
            start_segment(cv, tret);
        } else if (automatic) {
            /* auto's decision at the end of the step (made already for a step that reached
             * the communication point: STEP_SWITCH) */
            const int method = flag == STEP_SWITCH ? cv->switch_method : auto_next_method(inst, tret);
            if (method == cv->method) {
                continue;
            }
            /* a new method from the current point (cv->y at tret is the step's end) */
            s = solver_start(inst, method, tret, 0.0);
            cv->hint_code = 0;
            start_window(cv, tret);
            peaks_forget(cv);
        } else {
            continue;
        }
        if (s != FMU_OK) {
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        if (stop_at_event && kind != 0) {
            /* early return (FMI 3.0): the step ends at the contact event, handled, with the
             * integrator restarted there; the FMU's time is the event time (take_solution) */
            *stopped = 1;
            return cv->warnings > warnings ? FMU_WARNING : FMU_OK;
        }
    }
    /* CVODE warned (logged by error_handler): the step is done, with a caveat */
    return finish_step(inst, t_end_abs, cv->warnings > warnings ? FMU_WARNING : FMU_OK);
}

fmu_status_t cs_reset(fmu_instance_t *inst)
{
    cs_free(inst);
    return FMU_OK;
}

const fmu_stepper_t cs_stepper = {cs_free, cs_peaks_flush};
