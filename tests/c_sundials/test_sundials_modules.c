/* The SUNDIALS modules compiled by cmake/sundials.cmake (with our configuration header
 * fmu_src/sundials_config/) link completely and solve y' = -y, y(0) = 1 as the analytic solution
 * y = exp(-t) says, in double precision:
 *   - CVODE, Adams with fixed-point iteration and BDF with Newton iteration + dense linear
 *     solver (the FMU's two methods), to t = 2;
 *   - ARKODE ERKStep with the Dormand-Prince 5(4) table, root finding (y = 1/2 at t = ln 2) and
 *     dense output (the co-simulation Runge-Kutta method to come).
 * Tolerances: rtol = 1e-10, so the errors must be below 1e-8 (a hundred times the tolerance),
 * far above round-off and far below a wrong configuration (single precision: 1e-7 at best). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

static int failures = 0;

static void expect_close(const char *what, double got, double want, double tol)
{
    const int ok = fabs(got - want) <= tol;
    printf("%s %s: %.17g (expected %.17g, tolerance %g)\n", ok ? "ok  " : "FAIL", what, got, want,
           tol);
    failures += !ok;
}

static void expect(const char *what, int ok)
{
    printf("%s %s\n", ok ? "ok  " : "FAIL", what);
    failures += !ok;
}

static int decay(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    (void)t;
    (void)user_data;
    NV_Ith_S(ydot, 0) = -NV_Ith_S(y, 0);
    return 0;
}

static int half(sunrealtype t, N_Vector y, sunrealtype *g, void *user_data)
{
    (void)t;
    (void)user_data;
    g[0] = NV_Ith_S(y, 0) - 0.5;
    return 0;
}

static void cvode_run(SUNContext ctx, int lmm)
{
    N_Vector y = N_VNew_Serial(1, ctx);
    NV_Ith_S(y, 0) = 1.0;
    void *mem = CVodeCreate(lmm, ctx);
    SUNMatrix A = NULL;
    SUNLinearSolver LS = NULL;
    SUNNonlinearSolver NLS = NULL;
    int flag = CVodeInit(mem, decay, 0.0, y);
    flag |= CVodeSStolerances(mem, 1e-10, 1e-14);
    if (lmm == CV_BDF) {
        A = SUNDenseMatrix(1, 1, ctx);
        LS = SUNLinSol_Dense(y, A, ctx);
        flag |= CVodeSetLinearSolver(mem, LS, A);
    } else {
        NLS = SUNNonlinSol_FixedPoint(y, 0, ctx);
        flag |= CVodeSetNonlinearSolver(mem, NLS);
    }
    sunrealtype t = 0.0;
    flag |= CVode(mem, 2.0, y, &t, CV_NORMAL) < 0;
    expect(lmm == CV_BDF ? "CVODE BDF runs" : "CVODE Adams runs", flag == 0);
    expect_close(lmm == CV_BDF ? "CVODE BDF y(2)" : "CVODE Adams y(2)", NV_Ith_S(y, 0), exp(-2.0),
                 1e-8);
    CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (NLS) SUNNonlinSolFree(NLS);
    N_VDestroy(y);
}

static void erk_run(SUNContext ctx)
{
    N_Vector y = N_VNew_Serial(1, ctx);
    N_Vector dky = N_VNew_Serial(1, ctx);
    NV_Ith_S(y, 0) = 1.0;
    void *mem = ERKStepCreate(decay, 0.0, y, ctx);
    int flag = ERKStepSetTableNum(mem, ARKODE_DORMAND_PRINCE_7_4_5);
    flag |= ERKStepSStolerances(mem, 1e-10, 1e-14);
    flag |= ERKStepRootInit(mem, 1, half);
    sunrealtype t = 0.0;
    const int rc = ERKStepEvolve(mem, 2.0, y, &t, ARK_NORMAL);
    expect("ERKStep (Dormand-Prince 5(4)) stops at the root", flag == 0 && rc == ARK_ROOT_RETURN);
    expect_close("ERKStep root time (ln 2)", t, log(2.0), 1e-8);
    /* dense output inside the last step */
    long steps = 0;
    ERKStepGetNumSteps(mem, &steps);
    expect("ERKStep took steps", steps > 0);
    const int rc_dky = ERKStepGetDky(mem, t, 0, dky);
    expect_close("ERKStep dense output at the root", rc_dky == 0 ? NV_Ith_S(dky, 0) : NAN, 0.5,
                 1e-8);
    ERKStepFree(&mem);
    N_VDestroy(dky);
    N_VDestroy(y);
}

int main(void)
{
    SUNContext ctx = NULL;
    if (SUNContext_Create(NULL, &ctx) != 0) {
        printf("FAIL SUNContext_Create\n");
        return 1;
    }
    expect("sunrealtype is double", sizeof(sunrealtype) == sizeof(double));
    cvode_run(ctx, CV_ADAMS);
    cvode_run(ctx, CV_BDF);
    erk_run(ctx);
    SUNContext_Free(&ctx);
    printf("%d failed\n", failures);
    return failures == 0 ? 0 : 1;
}
