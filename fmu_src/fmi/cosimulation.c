/* Co-simulation: fmi2DoStep integrates the model with SUNDIALS CVODE (BDF, dense direct linear
 * solver, difference-quotient Jacobian) and locates every contact onset and release inside the
 * step by root finding on the gap (the model-exchange event indicator). At each root the contact
 * mode is updated (the onset indentation rate is captured) and CVODE is re-initialised.
 * Inputs are held constant over the communication step. */
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

#include "csfh_variables.h"
#include "fmu_instance.h"

#define NX CSFH_NUMBER_OF_STATES
#define MAX_EVENTS_PER_STEP 1000000L  /* guards against an endless chain of contact events */
#define MAX_STEPS_PER_CALL 500000L    /* CVODE steps per CVode() call */

struct csfh_cvode {
    SUNContext ctx;
    void *mem;
    N_Vector y;
    N_Vector abstol;
    SUNMatrix J;
    SUNLinearSolver LS;
    double tolerance; /* the relative tolerance the solver was set up with */
    long counted_steps; /* CVODE steps already added to the model's counter */
};

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    (void)t;
    const int status = csfh_model_derivatives(&inst->model, N_VGetArrayPointer(y),
                                              N_VGetArrayPointer(ydot));
    return status == CSFH_ERR_NONFINITE ? 1 : 0; /* recoverable: CVODE retries a smaller step */
}

static int roots(sunrealtype t, N_Vector y, sunrealtype *gout, void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    (void)t;
    gout[0] = csfh_model_event_indicator(&inst->model, N_VGetArrayPointer(y));
    return 0;
}

static void error_handler(int error_code, const char *module, const char *function, char *msg,
                          void *user_data)
{
    fmu_instance_t *inst = (fmu_instance_t *)user_data;
    if (error_code < 0) {
        fmu_log(inst, fmi2Error, LOG_STATUS_ERROR, "%s %s: %s", module, function, msg);
    } else {
        fmu_log(inst, fmi2Warning, LOG_STATUS_WARNING, "%s %s: %s", module, function, msg);
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
    if (cv->J != NULL) {
        SUNMatDestroy(cv->J);
    }
    if (cv->y != NULL) {
        N_VDestroy(cv->y);
    }
    if (cv->abstol != NULL) {
        N_VDestroy(cv->abstol);
    }
    if (cv->ctx != NULL) {
        SUNContext_Free(&cv->ctx);
    }
    free(cv);
    inst->cvode = NULL;
}

static fmi2Status cv_check(fmu_instance_t *inst, int flag, const char *call)
{
    if (flag >= 0) {
        return fmi2OK;
    }
    char *name = CVodeGetReturnFlagName(flag);
    fmu_log(inst, fmi2Error, LOG_STATUS_ERROR, "fmi2DoStep: %s failed with %s at t = %.17g", call,
            name != NULL ? name : "an unknown flag", inst->model.time);
    free(name);
    return fmi2Error;
}

/* Create CVODE (first step) or re-initialise it at the current state. */
static fmi2Status cs_start(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    if (cv != NULL && cv->tolerance != inst->tolerance) {
        cs_free(inst);
        cv = NULL;
    }
    if (cv != NULL) {
        memcpy(N_VGetArrayPointer(cv->y), inst->model.x, NX * sizeof(double));
        cv->counted_steps = 0;
        return cv_check(inst, CVodeReInit(cv->mem, inst->model.time, cv->y), "CVodeReInit");
    }
    cv = (csfh_cvode_t *)calloc(1, sizeof(*cv));
    if (cv == NULL) {
        fmu_log(inst, fmi2Error, LOG_STATUS_ERROR, "fmi2DoStep: out of memory");
        return fmi2Error;
    }
    inst->cvode = cv;
    cv->tolerance = inst->tolerance;
    if (SUNContext_Create(NULL, &cv->ctx) != 0) {
        fmu_log(inst, fmi2Error, LOG_STATUS_ERROR, "fmi2DoStep: SUNContext_Create failed");
        cs_free(inst);
        return fmi2Error;
    }
    cv->y = N_VNew_Serial(NX, cv->ctx);
    cv->abstol = N_VNew_Serial(NX, cv->ctx);
    cv->J = SUNDenseMatrix(NX, NX, cv->ctx);
    cv->mem = CVodeCreate(CV_BDF, cv->ctx);
    if (cv->y == NULL || cv->abstol == NULL || cv->J == NULL || cv->mem == NULL) {
        fmu_log(inst, fmi2Error, LOG_STATUS_ERROR, "fmi2DoStep: cannot allocate CVODE");
        cs_free(inst);
        return fmi2Error;
    }
    cv->LS = SUNLinSol_Dense(cv->y, cv->J, cv->ctx);
    memcpy(N_VGetArrayPointer(cv->y), inst->model.x, NX * sizeof(double));
    /* absolute tolerance: relative tolerance times the nominal value of each state */
    double *atol = N_VGetArrayPointer(cv->abstol);
    int k = 0;
    for (int i = 0; i < CSFH_NUMBER_OF_VARIABLES && k < NX; i++) {
        if (csfh_variables[i].is_state) {
            atol[k++] = inst->tolerance * csfh_variables[i].nominal;
        }
    }
    fmi2Status s = cv_check(inst, CVodeSetErrHandlerFn(cv->mem, error_handler, inst), "CVodeSetErrHandlerFn");
    if (s == fmi2OK) s = cv_check(inst, CVodeInit(cv->mem, rhs, inst->model.time, cv->y), "CVodeInit");
    if (s == fmi2OK) s = cv_check(inst, CVodeSetUserData(cv->mem, inst), "CVodeSetUserData");
    if (s == fmi2OK) s = cv_check(inst, CVodeSVtolerances(cv->mem, inst->tolerance, cv->abstol), "CVodeSVtolerances");
    if (s == fmi2OK) s = cv_check(inst, CVodeSetLinearSolver(cv->mem, cv->LS, cv->J), "CVodeSetLinearSolver");
    if (s == fmi2OK) s = cv_check(inst, CVodeRootInit(cv->mem, CSFH_NUMBER_OF_EVENT_INDICATORS, roots), "CVodeRootInit");
    if (s == fmi2OK) s = cv_check(inst, CVodeSetNoInactiveRootWarn(cv->mem), "CVodeSetNoInactiveRootWarn");
    if (s == fmi2OK) s = cv_check(inst, CVodeSetMaxNumSteps(cv->mem, MAX_STEPS_PER_CALL), "CVodeSetMaxNumSteps");
    if (s != fmi2OK) {
        cs_free(inst);
    }
    return s;
}

/* Add the CVODE steps taken since the last call to the model's step counter. */
static void count_steps(fmu_instance_t *inst)
{
    csfh_cvode_t *cv = inst->cvode;
    long nsteps = 0;
    CVodeGetNumSteps(cv->mem, &nsteps);
    const long added = nsteps - cv->counted_steps;
    cv->counted_steps = nsteps;
    const long room = (long)INT_MAX - inst->model.counters.steps;
    inst->model.counters.steps += (int)(added < room ? added : room);
}

fmi2Status cs_do_step(fmu_instance_t *inst, double t, double h)
{
    csfh_model_t *m = &inst->model;
    if (fabs(t - m->time) > 1e-9 * (1.0 + fabs(t))) {
        fmu_log(inst, fmi2Error, LOG_STATUS_ERROR,
                "fmi2DoStep: currentCommunicationPoint = %.17g does not match the FMU time %.17g",
                t, m->time);
        return fmi2Error;
    }
    if (h == 0.0) {
        return fmi2OK;
    }
    const double t_end = t + h;
    if (inst->cvode == NULL || inst->cvode_needs_reinit) {
        if (cs_start(inst) != fmi2OK) {
            return fmi2Error;
        }
        inst->cvode_needs_reinit = 0;
    }
    csfh_cvode_t *cv = inst->cvode;
    if (cv_check(inst, CVodeSetStopTime(cv->mem, t_end), "CVodeSetStopTime") != fmi2OK) {
        return fmi2Error;
    }
    long events = 0;
    double tret = m->time;
    fmi2Status status = fmi2OK;
    while (tret < t_end) {
        const int flag = CVode(cv->mem, t_end, cv->y, &tret, CV_NORMAL);
        count_steps(inst);
        if (flag < 0) {
            memcpy(m->x, N_VGetArrayPointer(cv->y), NX * sizeof(double));
            fmu_invalidate(inst);
            cv_check(inst, flag, "CVode");
            inst->cvode_needs_reinit = 1;
            return fmi2Error;
        }
        memcpy(m->x, N_VGetArrayPointer(cv->y), NX * sizeof(double));
        m->time = tret;
        fmu_invalidate(inst);
        if (!inst->warned_esdu && csfh_model_outputs(m) == CSFH_WARN_ESDU_CLAMPED) {
            inst->warned_esdu = 1;
            fmu_log(inst, fmi2Warning, LOG_STATUS_WARNING,
                    "fmi2DoStep: indentation beyond the validity of the ESDU law; the force is "
                    "held at contact.esdu_F_max = %g N", m->d.esdu_F_max);
            status = fmi2Warning;
        }
        if (flag == CV_ROOT_RETURN) {
            if (++events > MAX_EVENTS_PER_STEP) {
                fmu_log(inst, fmi2Error, LOG_STATUS_ERROR,
                        "fmi2DoStep: more than %ld contact events in one step at t = %.17g",
                        MAX_EVENTS_PER_STEP, tret);
                return fmi2Error;
            }
            if (fmu_event_update(inst) != 0) {
                /* the indicator switched branch: restart the integrator at the event */
                cv->counted_steps = 0;
                if (cv_check(inst, CVodeReInit(cv->mem, tret, cv->y), "CVodeReInit") != fmi2OK ||
                    cv_check(inst, CVodeSetStopTime(cv->mem, t_end), "CVodeSetStopTime") != fmi2OK) {
                    return fmi2Error;
                }
            }
        }
    }
    m->time = t_end; /* exact communication point (tret == t_end up to round-off) */
    return status;
}

fmi2Status cs_reset(fmu_instance_t *inst)
{
    cs_free(inst);
    return fmi2OK;
}
