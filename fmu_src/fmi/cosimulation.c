/* Co-simulation: fmi2DoStep integrates the model with SUNDIALS CVODE and locates every event
 * inside the step by root finding on the model-exchange event indicators (csfh: the gap, so
 * every contact onset and release). At each root the discrete state is updated (csfh: the onset
 * indentation rate is captured) and CVODE is re-initialised; the step then continues to its end,
 * however many events it holds. The communication points do not cut CVODE's steps short: CVODE
 * may step past the end of a communication step, the FMU's state there is CVODE's interpolant
 * (to the same tolerance), and the next fmi2DoStep goes on from CVODE's internal state, so a
 * fine communication grid costs no extra integration steps.
 *
 * Method (fmu_model.cs_method; csfh: parameter solver.method):
 *   BDF    BDF with Newton iteration, dense direct linear solver, difference-quotient Jacobian;
 *   Adams  Adams-Moulton with fixed-point iteration: no Jacobian and no linear algebra, the
 *          cheaper choice while the motion is not stiff (flight, impacts resolved in time);
 *   auto   Adams; where it struggles (more than AUTO_SUSPECT_FAILED of the steps of a window of
 *          AUTO_WINDOW steps fail, fixed-point convergence or error test), BDF is tried for
 *          two windows (start-up, then measured) and kept if its mean step is more than
 *          AUTO_BDF_COST times Adams' (a BDF step costs about that much more: Newton iteration
 *          and linear algebra), i.e. where the motion is stiff (resting or rolling contact);
 *          otherwise back to Adams, with the next trial after 1, 2, 4, ... windows. Every
 *          event restarts with Adams.
 *
 * Inputs are held constant over the communication step (zero-order hold); a changed input value,
 * a changed state or tunable parameter, and fmi2Get/SetFMUstate restart CVODE at the
 * communication point, so that the multistep history never reaches across a discontinuity of
 * the right-hand side. Tolerances: relative = the fmi2SetupExperiment tolerance
 * (FMU_DEFAULT_TOLERANCE = 1e-6 when none is given), absolute = relative x the nominal value of
 * each state.
 *
 * A CVODE failure returns FMU_ERROR with CVODE's own message and return flag in the log; the
 * instance then holds the last state CVODE reached successfully, at that time (also reported by
 * fmi2GetRealStatus(fmi2LastSuccessfulTime)); fmi2SetFMUstate can roll it back.
 *
 * Time: CVODE integrates in a local time tau = t - origin, measured from a time origin the
 * instance holds (the communication point where CVODE was last started from outside: first
 * step, changed input, state or parameter, FMU state taken or restored; never moved at events).
 * The integration, its step sizes and its root finding are then the same whatever the start
 * time: a run from t0 = 1e10 s reproduces the run from 0, shifted, where CVODE in the absolute
 * time could not resolve its steps (ulp(1e10) = 1.9e-6 s) and drifted. A communication point
 * maps to tau exactly (t_end - origin, both multiples of ulp(origin) near the origin). CVODE's
 * own warnings (e.g. "t + h = t" after a very long run) make fmi2DoStep return FMU_WARNING;
 * fmi2DoStep itself (fmi2_glue.c) reports steps that the double time cannot resolve.
 *
 * A model without continuous states (the comb-drive actuator) just advances its time. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include "fmu_instance.h"

#define NX fmu_model.n_states
#define MAX_EVENTS_PER_STEP 1000000L  /* guards against an endless chain of events */
#ifndef MAX_STEPS_PER_CALL
#define MAX_STEPS_PER_CALL 500000L    /* CVODE steps per fmi2DoStep (the fuzz build lowers it) */
#endif
#define AUTO_WINDOW 100L              /* auto: steps per decision */
#define AUTO_SUSPECT_FAILED 0.05      /* auto: failed fraction of an Adams window that triggers a trial */
#define AUTO_BDF_COST 1.5             /* auto: cost of a BDF step over an Adams step */
#define AUTO_MAX_HOLDOFF 64           /* auto: most windows between two trials */
#define FIRST_STEP_HORIZON 1.0        /* s: the tout of CVODE's first-step estimate (see cs_do_step) */

struct csfh_cvode {
    SUNContext ctx;
    void *mem;
    N_Vector y;
    N_Vector abstol;
    SUNMatrix J;
    SUNLinearSolver LS;
    SUNNonlinearSolver NLS; /* fixed-point iteration (Adams) */
    int method;             /* FMU_CS_BDF or FMU_CS_ADAMS: the method CVODE was created with */
    long window_steps;      /* auto: CVODE's step and failure counts and the time at the start */
    long window_fails;      /*       of the current window */
    double window_t0;
    int trial;              /* auto: 0, or BDF on trial: 1 starting up, 2 measured */
    int holdoff;            /* auto: Adams windows left before the next trial */
    int next_holdoff;
    double adams_h;         /* auto: mean Adams step of the window before the trial, s */
    double tolerance; /* the relative tolerance the solver was set up with */
    N_Vector y_root;  /* a root (or time event) CVODE reported beyond the end of the last */
    double t_root;    /* communication step: the state there and its time, */
    int root_pending; /* CV_ROOT_RETURN or CV_TSTOP_RETURN, handled in the communication step
                         that contains it (0: none) */
    long counted_steps; /* CVODE steps already added to the model's counter */
    /* peak outputs (fmu_model.n_peaks > 0, track_peaks) */
    N_Vector peak_y, peak_dy; /* work vectors */
    double peak_t;            /* the end of the last analysed CVODE step: */
    int peak_slope_valid;     /* its slopes and values there are valid */
    double peak_slope[FMU_MAX_PEAKS];
    double peak_end_v[FMU_MAX_PEAKS];
    int peak_n_max;           /* the maxima inside it: times and values */
    double peak_max_t[FMU_MAX_PEAKS];
    double peak_max_v[FMU_MAX_PEAKS][FMU_MAX_PEAKS];
    double origin;      /* s: CVODE's time 0 (see the top of this file); CVODE's times are local */
    long warnings;      /* CVODE warnings so far (error_handler) */
};

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    /* the model's time at CVODE's local time t (a time-dependent model: the shock pulse) */
    const int status = fmu_model.derivatives(inst->model, inst->cvode->origin + t,
                                             N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    return status == FMU_MODEL_NONFINITE ? 1 : 0; /* recoverable: CVODE retries a smaller step */
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *gout, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    (void)t;
    fmu_model.event_indicators(inst->model, N_VGetArrayPointer(y), gout);
    for (int i = 0; i < fmu_model.n_event_indicators; i++) {
        if (!isfinite(gout[i])) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "fmi2DoStep: non-finite event indicator z[%d] = %g", i, gout[i]);
            return 1; /* CVODE fails the step (CV_RTFUNC_FAIL) */
        }
    }
    return 0;
}

static void error_handler(int error_code, const char *module, const char *function, char *msg,
                          void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    if (error_code < 0) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "%s %s: %s", module, function, msg);
    } else {
        if (inst->cvode != NULL) {
            inst->cvode->warnings++; /* fmi2DoStep returns FMU_WARNING */
        }
        fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING, "%s %s (local time from t0 = %.17g): %s",
                module, function, inst->cvode != NULL ? inst->cvode->origin : 0.0, msg);
    }
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
    if (cv->LS != NULL) {
        SUNLinSolFree(cv->LS);
    }
    if (cv->NLS != NULL) {
        SUNNonlinSolFree(cv->NLS);
    }
    if (cv->J != NULL) {
        SUNMatDestroy(cv->J);
    }
    if (cv->y != NULL) {
        N_VDestroy(cv->y);
    }
    if (cv->abstol != NULL) {
        N_VDestroy(cv->abstol);
    }
    if (cv->y_root != NULL) {
        N_VDestroy(cv->y_root);
    }
    if (cv->peak_y != NULL) {
        N_VDestroy(cv->peak_y);
    }
    if (cv->peak_dy != NULL) {
        N_VDestroy(cv->peak_dy);
    }
    if (cv->ctx != NULL) {
        SUNContext_Free(&cv->ctx);
    }
    free(cv);
    inst->cvode = NULL;
}

static fmu_status_t cv_check(fmu_instance_t *inst, int flag, const char *call)
{
    if (flag >= 0) {
        return FMU_OK;
    }
    char *name = CVodeGetReturnFlagName(flag);
    fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "fmi2DoStep: %s failed with %s at t = %.17g", call,
            name != NULL ? name : "an unknown flag", *fmu_time(inst));
    free(name);
    return FMU_ERROR;
}

/* auto: a new window of steps (CVODE's counters restart with every (re)initialisation). */
static void start_window(csfh_cvode_t *cv, double t)
{
    cv->window_steps = 0;
    cv->window_fails = 0;
    cv->window_t0 = t;
}

/* auto: a new segment of smooth motion (start, event, restart): no trial, no hold-off. */
static void start_segment(csfh_cvode_t *cv, double t)
{
    start_window(cv, t);
    cv->trial = 0;
    cv->holdoff = 0;
    cv->next_holdoff = 1;
}

static int configured_method(const fmu_instance_t *inst)
{
    return fmu_model.cs_method != NULL ? fmu_model.cs_method(inst->model) : FMU_CS_BDF;
}

/* (Re)create CVODE's memory with `method` (FMU_CS_BDF or FMU_CS_ADAMS) at the local time tau
 * and the FMU's state; the vectors, the matrix and the solvers are kept from one method to the
 * next. */
static fmu_status_t cv_create(fmu_instance_t *inst, int method, double tau)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv->mem != NULL) {
        CVodeFree(&cv->mem);
    }
    memcpy(N_VGetArrayPointer(cv->y), fmu_states(inst), NX * sizeof(double));
    cv->mem = CVodeCreate(method == FMU_CS_ADAMS ? CV_ADAMS : CV_BDF, cv->ctx);
    if (method == FMU_CS_ADAMS && cv->NLS == NULL) {
        cv->NLS = SUNNonlinSol_FixedPoint(cv->y, 0, cv->ctx);
    }
    if (method != FMU_CS_ADAMS && cv->J == NULL) {
        cv->J = SUNDenseMatrix(NX, NX, cv->ctx);
        cv->LS = cv->J != NULL ? SUNLinSol_Dense(cv->y, cv->J, cv->ctx) : NULL;
    }
    if (cv->mem == NULL || (method == FMU_CS_ADAMS ? cv->NLS == NULL : cv->LS == NULL)) {
        fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "fmi2DoStep: cannot allocate CVODE");
        return FMU_ERROR;
    }
    cv->method = method;
    cv->counted_steps = 0;
    cv->root_pending = 0;
    start_window(cv, tau);
    fmu_status_t s = cv_check(inst, CVodeSetErrHandlerFn(cv->mem, error_handler, inst), "CVodeSetErrHandlerFn");
    if (s == FMU_OK) s = cv_check(inst, CVodeInit(cv->mem, rhs, tau, cv->y), "CVodeInit");
    if (s == FMU_OK) s = cv_check(inst, CVodeSetUserData(cv->mem, inst), "CVodeSetUserData");
    if (s == FMU_OK) s = cv_check(inst, CVodeSVtolerances(cv->mem, inst->tolerance, cv->abstol), "CVodeSVtolerances");
    if (s == FMU_OK && method == FMU_CS_ADAMS) {
        s = cv_check(inst, CVodeSetNonlinearSolver(cv->mem, cv->NLS), "CVodeSetNonlinearSolver");
    } else if (s == FMU_OK) {
        s = cv_check(inst, CVodeSetLinearSolver(cv->mem, cv->LS, cv->J), "CVodeSetLinearSolver");
    }
    if (s == FMU_OK) s = cv_check(inst, CVodeRootInit(cv->mem, fmu_model.n_event_indicators, roots), "CVodeRootInit");
    if (s == FMU_OK) s = cv_check(inst, CVodeSetNoInactiveRootWarn(cv->mem), "CVodeSetNoInactiveRootWarn");
    return s;
}

/* Create CVODE (first step) or re-initialise it at the current state, with the configured
 * method (auto starts with Adams); the FMU's time becomes the origin of CVODE's local time. */
static fmu_status_t cs_start(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv != NULL && cv->tolerance != inst->tolerance) {
        cs_free(inst);
        cv = NULL;
    }
    const int method = configured_method(inst) == FMU_CS_BDF ? FMU_CS_BDF : FMU_CS_ADAMS;
    if (cv != NULL && cv->mem != NULL && cv->method == method) {
        memcpy(N_VGetArrayPointer(cv->y), fmu_states(inst), NX * sizeof(double));
        cv->counted_steps = 0;
        cv->root_pending = 0;
        cv->origin = *fmu_time(inst);
        start_segment(cv, 0.0);
        return cv_check(inst, CVodeReInit(cv->mem, 0.0, cv->y), "CVodeReInit");
    }
    if (cv == NULL) {
        cv = (csfh_cvode_t *)calloc(1, sizeof(*cv));
        if (cv == NULL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "fmi2DoStep: out of memory");
            return FMU_ERROR;
        }
        inst->cvode = cv;
        cv->tolerance = inst->tolerance;
        if (SUNContext_Create(NULL, &cv->ctx) != 0) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "fmi2DoStep: SUNContext_Create failed");
            cs_free(inst);
            return FMU_ERROR;
        }
        cv->y = N_VNew_Serial(NX, cv->ctx);
        cv->abstol = N_VNew_Serial(NX, cv->ctx);
        cv->y_root = N_VNew_Serial(NX, cv->ctx);
        if (cv->y == NULL || cv->abstol == NULL || cv->y_root == NULL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR, "fmi2DoStep: cannot allocate CVODE");
            cs_free(inst);
            return FMU_ERROR;
        }
        /* absolute tolerance: relative tolerance times the nominal value of each state */
        double *atol = N_VGetArrayPointer(cv->abstol);
        int k = 0;
        for (int i = 0; i < fmu_model.n_variables && k < NX; i++) {
            if (fmu_model.variables[i].is_state) {
                atol[k++] = inst->tolerance * fmu_model.variables[i].nominal;
            }
        }
    }
    cv->origin = *fmu_time(inst);
    const fmu_status_t s = cv_create(inst, method, 0.0);
    if (s != FMU_OK) {
        cs_free(inst);
        return s;
    }
    start_segment(inst->cvode, 0.0);
    return s;
}

/* Add the CVODE steps taken since the last call to the model's step counter. */
static long count_steps(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    long nsteps = 0;
    CVodeGetNumSteps(cv->mem, &nsteps);
    const long added = nsteps - cv->counted_steps;
    cv->counted_steps = nsteps;
    if (fmu_model.add_integrator_steps != NULL) {
        fmu_model.add_integrator_steps(inst->model, added);
    }
    return added;
}

/* auto: at the end of each window of AUTO_WINDOW steps (t: CVODE's local time), the method for
 * the next window; writes what it decided to `why` (empty when nothing changes). */
static int auto_choose(csfh_cvode_t *cv, double t, char *why, size_t why_size)
{
    why[0] = '\0';
    long nsteps = 0, nconv = 0, nerr = 0;
    CVodeGetNumSteps(cv->mem, &nsteps);
    const long steps = nsteps - cv->window_steps;
    if (steps < AUTO_WINDOW) {
        return cv->method;
    }
    CVodeGetNumNonlinSolvConvFails(cv->mem, &nconv);
    CVodeGetNumErrTestFails(cv->mem, &nerr);
    const double failed = (double)(nconv + nerr - cv->window_fails) / (double)steps;
    const double mean_h = (t - cv->window_t0) / (double)steps;
    cv->window_steps = nsteps;
    cv->window_fails = nconv + nerr;
    cv->window_t0 = t;
    if (cv->method == FMU_CS_ADAMS) {
        if (cv->holdoff > 0) {
            cv->holdoff--;
        } else if (failed > AUTO_SUSPECT_FAILED) {
            cv->adams_h = mean_h;
            cv->trial = 1;
            snprintf(why, why_size,
                     "t = %.17g: auto: trying BDF (%.0f %% of Adams' steps failed, mean step %.3g s)",
                     cv->origin + t, 100.0 * failed, mean_h);
            return FMU_CS_BDF;
        }
        return FMU_CS_ADAMS;
    }
    if (cv->trial == 1) { /* BDF's start-up window: not measured */
        cv->trial = 2;
        return FMU_CS_BDF;
    }
    if (cv->trial == 2) {
        cv->trial = 0;
        if (mean_h > AUTO_BDF_COST * cv->adams_h) {
            snprintf(why, why_size, "t = %.17g: auto: BDF kept (stiff: mean step %.3g s, Adams %.3g s)",
                     cv->origin + t, mean_h, cv->adams_h);
            return FMU_CS_BDF;
        }
        cv->holdoff = cv->next_holdoff;
        cv->next_holdoff = cv->next_holdoff < AUTO_MAX_HOLDOFF ? 2 * cv->next_holdoff : AUTO_MAX_HOLDOFF;
        snprintf(why, why_size, "t = %.17g: auto: back to Adams (BDF's mean step %.3g s, Adams %.3g s)",
                 cv->origin + t, mean_h, cv->adams_h);
        return FMU_CS_ADAMS;
    }
    return FMU_CS_BDF;
}

/* ------------------------------------------------------------------------------------------ */
/* peak outputs: the largest values of the model's peak quantities over the communication step,
 * on CVODE's interpolant (the dense output of its last step). Each CVODE step is analysed once,
 * when it is taken: its end values, and every maximum inside it (the quantity's slope + at the
 * step's start, <= 0 at its end: the slope's root by regula falsi). Each part of a communication
 * step then takes the maxima that lie in it; the values at the communication points themselves
 * are the outputs there (the model's outputs take the max with the step's peaks). */

#define PEAK_ITERATIONS 40 /* regula falsi (Illinois) on the slope: a few are used */

/* The peak quantities v at time t of CVODE's last step, and their time derivatives (a forward
 * difference along the interpolant's derivative) in slope; 0 when the model has nothing to
 * track there. */
static int peak_point(fmu_instance_t *inst, double t, double *v, double *slope)
{
    csfh_cvode_t *cv = inst->cvode;
    double tn = t, hu = 0.0;
    CVodeGetCurrentTime(cv->mem, &tn);
    CVodeGetLastStep(cv->mem, &hu);
    t = t < tn - hu ? tn - hu : (t > tn ? tn : t); /* round-off at the step's ends */
    if (CVodeGetDky(cv->mem, t, 0, cv->peak_y) < 0) {
        return 0;
    }
    double *py = N_VGetArrayPointer(cv->peak_y), *pd = N_VGetArrayPointer(cv->peak_dy);
    if (!fmu_model.peak_values(inst->model, py, v) ||
        CVodeGetDky(cv->mem, t, 1, cv->peak_dy) < 0) {
        return 0;
    }
    const double eps = 1e-7 * (fabs(hu) > 0.0 ? fabs(hu) : 1e-9);
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

/* Forget what is known of the last step (CVODE restarted: a new interpolant). */
static void peaks_forget(csfh_cvode_t *cv)
{
    cv->peak_slope_valid = 0;
    cv->peak_n_max = 0;
}

/* Analyse CVODE's new step [tn - hu, tn]: its maxima and its end. */
static void peak_step(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    double tn = 0.0, hu = 0.0, v1[FMU_MAX_PEAKS], s1[FMU_MAX_PEAKS], s0[FMU_MAX_PEAKS];
    CVodeGetCurrentTime(cv->mem, &tn);
    CVodeGetLastStep(cv->mem, &hu);
    const double t0 = tn - hu;
    const int have_start = cv->peak_slope_valid && cv->peak_t == t0;
    cv->peak_n_max = 0;
    if (have_start) {
        memcpy(s0, cv->peak_slope, sizeof(s0));
    }
    if (!peak_point(inst, tn, v1, s1)) {
        cv->peak_slope_valid = 0;
        return;
    }
    if (have_start || peak_point(inst, t0, cv->peak_max_v[0], s0)) {
        for (int j = 0; j < fmu_model.n_peaks; j++) {
            if (!(s0[j] > 0.0 && s1[j] <= 0.0)) {
                continue;
            }
            /* the root of the slope: regula falsi with the Illinois modification (a few
             * evaluations; the value is flat there, so a time 1e-7 of the step off changes it
             * by ~1e-14 relative) */
            double lo = t0, hi = tn, f_lo = s0[j], f_hi = s1[j], v[FMU_MAX_PEAKS], s[FMU_MAX_PEAKS];
            int side = 0;
            for (int k = 0; k < PEAK_ITERATIONS && hi - lo > 1e-7 * hu; k++) {
                double mid = hi - f_hi * (hi - lo) / (f_hi - f_lo);
                if (!(mid > lo && mid < hi)) {
                    mid = 0.5 * (lo + hi);
                }
                if (!peak_point(inst, mid, v, s)) {
                    break;
                }
                if (s[j] > 0.0) {
                    lo = mid, f_lo = s[j];
                    f_hi = side == -1 ? 0.5 * f_hi : f_hi;
                    side = -1;
                } else {
                    hi = mid, f_hi = s[j];
                    f_lo = side == 1 ? 0.5 * f_lo : f_lo;
                    side = 1;
                }
                if (s[j] == 0.0) {
                    lo = hi = mid;
                }
            }
            const int m = cv->peak_n_max;
            if (peak_point(inst, 0.5 * (lo + hi), cv->peak_max_v[m], s)) {
                cv->peak_max_t[m] = 0.5 * (lo + hi);
                cv->peak_n_max++;
            }
        }
    }
    memcpy(cv->peak_slope, s1, sizeof(s1));
    memcpy(cv->peak_end_v, v1, sizeof(v1));
    cv->peak_t = tn;
    cv->peak_slope_valid = 1;
}

/* The part [ta, tb] of the communication step, the state at tb in cv->y; `stepped`: CVODE took
 * a new step to get there. */
static void track_peaks(fmu_instance_t *inst, double ta, double tb, int stepped)
{
    csfh_cvode_t *cv = inst->cvode;
    if (fmu_model.n_peaks <= 0) {
        return;
    }
    if (cv->peak_y == NULL) {
        cv->peak_y = N_VClone(cv->y);
        cv->peak_dy = N_VClone(cv->y);
        if (cv->peak_y == NULL || cv->peak_dy == NULL) {
            return; /* out of memory: the peaks fall back to the communication points */
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
        peak_step(inst);
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

/* Take CVODE's solution (local time tret, y) as the model's time and state. */
static void take_solution(fmu_instance_t *inst, double tret)
{
    memcpy(fmu_states(inst), N_VGetArrayPointer(inst->cvode->y), NX * sizeof(double));
    *fmu_time(inst) = inst->cvode->origin + tret;
    fmu_invalidate(inst);
}

/* The step ends at t_end: evaluate the outputs once (a model warning is logged once, a
 * non-finite output is an error). */
static fmu_status_t finish_step(fmu_instance_t *inst, double t_end, fmu_status_t status)
{
    *fmu_time(inst) = t_end; /* exact communication point (tret == t_end up to round-off) */
    fmu_invalidate(inst);
    const fmu_status_t s = fmu_update_outputs(inst, "fmi2DoStep");
    return s > status ? s : status;
}

/* ------------------------------------------------------------------------------------------ */
/* time events (fmu_model.next_time_event; csfh: the start and end of the shock pulse, where the
 * right-hand side has a kink): CVODE is given the next one as its stop time, so that no step
 * straddles it; it returns CV_TSTOP_RETURN there, and cs_do_step restarts it as at a state
 * event. Without time events nothing here is called. */

static fmu_status_t set_time_event_stop(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    double tn = 0.0;
    CVodeGetCurrentTime(cv->mem, &tn);
    double after = cv->origin + tn;
    for (int i = 0; i < 8; i++) { /* events that round to CVODE's current time are behind it */
        const double te = fmu_model.next_time_event(inst->model, after);
        if (!isfinite(te)) {
            return FMU_OK;
        }
        if (te - cv->origin > tn) {
            return cv_check(inst, CVodeSetStopTime(cv->mem, te - cv->origin), "CVodeSetStopTime");
        }
        after = te;
    }
    return FMU_OK;
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
    }
    csfh_cvode_t *cv = inst->cvode;
    const long warnings = cv->warnings;
    /* CVODE's local times (see the top of this file) */
    const double now = now_abs - cv->origin;
    const double t_end = t_end_abs - cv->origin;
    const int automatic = configured_method(inst) == FMU_CS_AUTO;
    long events = 0, steps = 0;
    double tret = now;
    if (fmu_model.n_peaks > 0) { /* the step's peaks start with the values at its start */
        fmu_model.peaks_begin(inst->model, inst->outputs_valid);
    }
    while (tret < t_end) {
        /* One internal step per call: the solution is taken at every step, and auto can check
         * the stiffness without waiting for the end of the communication step. No stop time:
         * the communication points do not cut CVODE's steps short. A step that ends beyond
         * t_end is not repeated: the state at t_end comes from CVODE's interpolant (for this
         * and for later communication points the step covers), and a root CVODE reports beyond
         * t_end is kept pending until the communication step that contains it. */
        int flag, stepped = 0;
        const double tret_before = tret;
        double tn = tret;
        CVodeGetCurrentTime(cv->mem, &tn);
        if (cv->root_pending && cv->t_root <= t_end) {
            memcpy(N_VGetArrayPointer(cv->y), N_VGetArrayPointer(cv->y_root), NX * sizeof(double));
            tret = cv->t_root;
            flag = cv->root_pending; /* CV_ROOT_RETURN or CV_TSTOP_RETURN */
            cv->root_pending = 0;
        } else if (cv->root_pending || tn >= t_end) {
            /* CVODE's last step (and the root check) already reaches past t_end */
            flag = CVodeGetDky(cv->mem, t_end, 0, cv->y);
            tret = t_end;
        } else {
            /* tout only sets the size of the first step after a (re)start (CVODE's estimate is
             * bounded by a tenth of the distance to tout): a fixed horizon, so that the step
             * sequence does not depend on the communication grid */
            if (fmu_model.next_time_event != NULL && set_time_event_stop(inst) != FMU_OK) {
                inst->cvode_needs_reinit = 1;
                return FMU_ERROR;
            }
            flag = CVode(cv->mem, tret + FIRST_STEP_HORIZON, cv->y, &tret, CV_ONE_STEP);
            stepped = flag >= 0;
            if (flag >= 0 && tret > t_end) {
                if (flag == CV_ROOT_RETURN || flag == CV_TSTOP_RETURN) {
                    memcpy(N_VGetArrayPointer(cv->y_root), N_VGetArrayPointer(cv->y), NX * sizeof(double));
                    cv->t_root = tret;
                    cv->root_pending = flag;
                }
                flag = CVodeGetDky(cv->mem, t_end, 0, cv->y);
                tret = t_end;
            }
        }
        steps += count_steps(inst);
        if (flag < 0) {
            /* CVODE's message is already in the log (error_handler); add the flag. CVODE returns
             * the last successful point in (tret, y): keep it, so that what the master reads is
             * consistent (time, state, discrete state), never a half-taken step. */
            cv_check(inst, flag, "CVode");
            const double *y = N_VGetArrayPointer(cv->y);
            int finite = isfinite(tret) && tret >= now && tret <= t_end;
            for (int i = 0; i < NX; i++) {
                finite = finite && isfinite(y[i]);
            }
            if (finite) {
                take_solution(inst, tret);
            }
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "fmi2DoStep: the step from t = %.17g to %.17g failed; the FMU holds the last "
                    "successful state, at t = %.17g",
                    now_abs, t_end_abs, *fmu_time(inst));
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        track_peaks(inst, tret_before, tret, stepped);
        take_solution(inst, tret);
        if (flag != CV_ROOT_RETURN && flag != CV_TSTOP_RETURN && tret >= t_end) {
            break;
        }
        if (steps > MAX_STEPS_PER_CALL) {
            fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                    "fmi2DoStep: more than %ld CVODE steps in the step from t = %.17g to %.17g; "
                    "the FMU holds the state at t = %.17g",
                    MAX_STEPS_PER_CALL, now_abs, t_end_abs, *fmu_time(inst));
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        int restart = 0, mode_switched = 0;
        if (flag == CV_ROOT_RETURN) {
            if (++events > MAX_EVENTS_PER_STEP) {
                fmu_log(inst, FMU_ERROR, LOG_STATUS_ERROR,
                        "fmi2DoStep: more than %ld events in one step at t = %.17g",
                        MAX_EVENTS_PER_STEP, *fmu_time(inst));
                inst->cvode_needs_reinit = 1;
                return FMU_ERROR;
            }
            /* the discrete state changed: restart the integrator at the event (auto: with
             * Adams again) */
            restart = fmu_event_update(inst) != 0;
            if (restart) {
                peaks_forget(cv); /* what follows the event has a new interpolant */
                mode_switched = 1;
            }
        } else if (flag == CV_TSTOP_RETURN) {
            restart = 1; /* a time event: the right-hand side's kink (see set_time_event_stop) */
            peaks_forget(cv);
        }
        fmu_status_t s = FMU_OK;
        if (restart && automatic && cv->method != FMU_CS_ADAMS) {
            s = cv_create(inst, FMU_CS_ADAMS, tret);
            start_segment(cv, tret);
        } else if (restart) {
            cv->counted_steps = 0;
            cv->root_pending = 0;
            start_segment(cv, tret);
            s = cv_check(inst, CVodeReInit(cv->mem, tret, cv->y), "CVodeReInit");
        } else if (automatic) {
            char why[160];
            const int method = auto_choose(cv, tret, why, sizeof(why));
            if (why[0] != '\0') {
                fmu_log(inst, FMU_OK, LOG_EVENTS, "%s", why);
            }
            if (method == cv->method) {
                continue;
            }
            s = cv_create(inst, method, tret);
        } else {
            continue;
        }
        if (s != FMU_OK) {
            inst->cvode_needs_reinit = 1;
            return FMU_ERROR;
        }
        if (stop_at_event && mode_switched) {
            /* early return (FMI 3.0): the step ends at the event, with the event handled and the
             * integrator restarted there; the FMU's time is the event time */
            *stopped = 1;
            const fmu_status_t o = fmu_update_outputs(inst, inst->step_function);
            const fmu_status_t w = cv->warnings > warnings ? FMU_WARNING : FMU_OK;
            return o > w ? o : w;
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
