#define _POSIX_C_SOURCE 199309L
/* Why the FMU has its own explicit Runge-Kutta 5(4) (fmu_src/solvers/rk45.c) instead of SUNDIALS
 * ARKODE's ERKStep with the same Dormand-Prince table: both integrate the central scene (body 1
 * dropped onto the bore, first three contacts, 0.42 s) in the same event loop as the FMU's
 * co-simulation (one step at a time, the state at every 10 ms communication point from the dense
 * output, root finding on the gap, a restart at every event with the first step that suited the
 * last event of the same kind), with the same right-hand side (the core's), against the paper's
 * RK4 + bisection (csfh_rk4event.c, h0 = 2e-4 s, tol = 1e-4 m, a record every 1e-4 s as the
 * harness runs it). For each law and relative tolerance: the largest error of the first three
 * contact onset times against a reference (both integrators at rtol 1e-13; their difference is
 * printed), the right-hand-side evaluations and the median wall time (runs interleaved); then,
 * at the paper's error (RK4's own), the cheapest run of each integrator that is at least as
 * accurate, and its speed-up over RK4.
 *
 * Build: cmake --build build --target bench_rk45_arkode; run: build/bench_rk45_arkode [repeats]. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "csfh_fmu.h"
#include "csfh_model.h"
#include "csfh_rk4event.h"
#include "rk45.h"

#define T_END 0.42
#define DT_COMM 1e-2
#define N_ONSETS 3
#define MAX_REPEATS 101

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* the central scene (docs/model.md §7.1): paper preset, no flexure, no friction, q0 = [0, 0.01, 0] */
static void setup(csfh_model_t *m, int law)
{
    char msg[256];
    csfh_fmu_model_defaults(m);
    m->p.law = law;
    m->p.flexure_enabled = 0;
    m->p.friction_enabled = 0;
    if (csfh_model_prepare(m, msg, sizeof msg) != 0) {
        fprintf(stderr, "%s\n", msg);
        exit(1);
    }
    const double x0[6] = {0.0, 0.01, 0.0, 0.0, 0.0, 0.0};
    memcpy(m->x, x0, sizeof x0);
    m->time = 0.0;
    csfh_model_init_discrete(m);
}

static void abstol(double rtol, double a[6])
{
    const double nominal[6] = {0.01, 0.01, 0.1, 1.0, 1.0, 1.0}; /* the FMU's state nominals */
    for (int i = 0; i < 6; i++) {
        a[i] = rtol * nominal[i];
    }
}

typedef struct {
    double onset[N_ONSETS];
    long rhs;
    double wall;
} run_t;

/* ---- our RK45 ---------------------------------------------------------------------------- */
static int rk_f(double t, const double *y, double *ydot, void *m)
{
    return csfh_model_derivatives(m, t, y, ydot) < 0;
}

static int rk_g(double t, const double *y, double *g, void *m)
{
    (void)t;
    g[0] = csfh_model_event_indicator(m, y);
    return 0;
}

static run_t run_rk45(int law, double rtol)
{
    run_t out = {{NAN, NAN, NAN}, 0, 0.0};
    csfh_model_t m;
    setup(&m, law);
    double y[6], a[6], yc[6], t = 0.0, hint[4] = {0.0, 0.0, 0.0, 0.0};
    memcpy(y, m.x, sizeof y);
    abstol(rtol, a);
    const double t0 = now();
    rk45_t *r = rk45_create(6, 1, rk_f, rk_g, &m);
    rk45_set_tolerances(r, rtol, a);
    rk45_init(r, 0.0, y, 1.0, 0.0);
    int k = 0, comm = 1, kind = 0;
    while (comm * DT_COMM <= T_END + 1e-12) {
        if (rk45_current_time(r) >= comm * DT_COMM) {
            rk45_dense(r, comm * DT_COMM, 0, yc); /* the communication point */
            comm++;
            continue;
        }
        const int flag = rk45_step(r, &t, y);
        if (kind > 0) {
            hint[kind] = rk45_next_step(r);
            kind = 0;
        }
        if (flag < 0) {
            fprintf(stderr, "rk45: %s\n", rk45_message(r));
            break;
        }
        if (flag == RK45_ROOT) {
            while (comm * DT_COMM < t) {
                rk45_dense(r, comm * DT_COMM, 0, yc);
                comm++;
            }
            memcpy(m.x, y, sizeof y);
            m.time = t;
            const int c = csfh_model_event_update(&m);
            if (c == 1 && k < N_ONSETS) {
                out.onset[k++] = t;
            }
            if (c > 0) {
                rk45_init(r, t, y, 1.0, hint[c]);
                kind = c;
            }
        }
    }
    rk45_free(r);
    out.wall = now() - t0;
    out.rhs = m.counters.rhs;
    return out;
}

/* ---- ARKODE ERKStep, Dormand-Prince ------------------------------------------------------ */
static SUNContext ctx;

static int ark_f(double t, N_Vector y, N_Vector ydot, void *m)
{
    return csfh_model_derivatives(m, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) < 0;
}

static int ark_g(double t, N_Vector y, double *g, void *m)
{
    (void)t;
    g[0] = csfh_model_event_indicator(m, N_VGetArrayPointer(y));
    return 0;
}

static run_t run_arkode(int law, double rtol)
{
    run_t out = {{NAN, NAN, NAN}, 0, 0.0};
    csfh_model_t m;
    setup(&m, law);
    N_Vector y = N_VNew_Serial(6, ctx), atol = N_VNew_Serial(6, ctx), yc = N_VNew_Serial(6, ctx);
    memcpy(N_VGetArrayPointer(y), m.x, 6 * sizeof(double));
    abstol(rtol, N_VGetArrayPointer(atol));
    double t = 0.0, hint[4] = {0.0, 0.0, 0.0, 0.0};
    const double t0 = now();
    void *mem = ERKStepCreate(ark_f, 0.0, y, ctx);
    ERKStepSetTableNum(mem, ARKODE_DORMAND_PRINCE_7_4_5);
    ERKStepSVtolerances(mem, rtol, atol);
    ERKStepSetUserData(mem, &m);
    ERKStepRootInit(mem, 1, ark_g);
    ERKStepSetNoInactiveRootWarn(mem);
    ERKStepSetMaxNumSteps(mem, 100000);
    int k = 0, comm = 1, kind = 0;
    while (comm * DT_COMM <= T_END + 1e-12) {
        double tn = 0.0;
        ERKStepGetCurrentTime(mem, &tn);
        if (tn >= comm * DT_COMM) {
            ERKStepGetDky(mem, comm * DT_COMM, 0, yc);
            comm++;
            continue;
        }
        const int flag = ERKStepEvolve(mem, t + 1.0, y, &t, ARK_ONE_STEP);
        if (kind > 0) {
            ERKStepGetCurrentStep(mem, &hint[kind]);
            kind = 0;
        }
        if (flag < 0) {
            fprintf(stderr, "ERKStep failed: %d\n", flag);
            break;
        }
        if (flag == ARK_ROOT_RETURN) {
            while (comm * DT_COMM < t) {
                ERKStepGetDky(mem, comm * DT_COMM, 0, yc);
                comm++;
            }
            memcpy(m.x, N_VGetArrayPointer(y), 6 * sizeof(double));
            m.time = t;
            const int c = csfh_model_event_update(&m);
            if (c == 1 && k < N_ONSETS) {
                out.onset[k++] = t;
            }
            if (c > 0) {
                ERKStepReInit(mem, ark_f, t, y);
                ERKStepSetInitStep(mem, hint[c]);
                kind = c;
            }
        }
    }
    ERKStepFree(&mem);
    out.wall = now() - t0;
    out.rhs = m.counters.rhs;
    N_VDestroy(y);
    N_VDestroy(atol);
    N_VDestroy(yc);
    return out;
}

/* ---- the paper's RK4 --------------------------------------------------------------------- */
static run_t run_rk4(int law)
{
    enum { MAX_RECORDS = 4300 }; /* T_END / 1e-4 + a margin */
    static double records[MAX_RECORDS * CSFH_RK4_RECORD_NCOLS];
    double contacts[100 * CSFH_CR_NCOLS], x_end[6];
    run_t out = {{NAN, NAN, NAN}, 0, 0.0};
    csfh_model_t m;
    setup(&m, law);
    const csfh_rk4_options_t o = {2e-4, 1e-4, 2e-4 * pow(2.0, -40)};
    const double x0[6] = {0.0, 0.01, 0.0, 0.0, 0.0, 0.0};
    csfh_rk4_stats_t st;
    const double t0 = now();
    csfh_rk4_event_run(&m, &o, 0.0, x0, T_END, 1e-4, records, MAX_RECORDS, contacts, 100, x_end,
                       &st);
    out.wall = now() - t0;
    for (size_t i = 0; i < N_ONSETS && i < st.contacts; i++) {
        out.onset[i] = contacts[i * CSFH_CR_NCOLS + CSFH_CR_T_ONSET];
    }
    out.rhs = st.rhs;
    return out;
}

static double onset_error(const run_t *r, const double *ref)
{
    double e = 0.0;
    for (int i = 0; i < N_ONSETS; i++) {
        e = fmax(e, fabs(r->onset[i] - ref[i]));
    }
    return e; /* NaN if an onset is missing */
}

enum { N_RTOL = 11 };
static const double RTOLS[N_RTOL] = {1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};

int main(int argc, char **argv)
{
    int repeats = argc > 1 ? atoi(argv[1]) : 11;
    repeats = repeats < 1 ? 1 : (repeats > MAX_REPEATS ? MAX_REPEATS : repeats);
    SUNContext_Create(NULL, &ctx);
    const struct {
        const char *name;
        int law;
    } laws[] = {{"LN_spheres", CSFH_CONTACTLAW_LN_SPHERES},
                {"LN_cylinders", CSFH_CONTACTLAW_LN_CYLINDERS},
                {"LN_ESDU", CSFH_CONTACTLAW_LN_ESDU}};
    printf("central scene, first %d contacts (%.2f s), communication points every %g s; "
           "medians of %d interleaved runs\n",
           N_ONSETS, T_END, DT_COMM, repeats);
    for (size_t L = 0; L < sizeof laws / sizeof laws[0]; L++) {
        const int law = laws[L].law;
        const run_t ref_rk45 = run_rk45(law, 1e-13), ref_ark = run_arkode(law, 1e-13);
        double ref[N_ONSETS];
        for (int i = 0; i < N_ONSETS; i++) {
            ref[i] = 0.5 * (ref_rk45.onset[i] + ref_ark.onset[i]);
        }
        printf("\n%s: reference onsets %.9f %.9f %.9f s (RK45 and ERKStep at rtol 1e-13 differ "
               "by %.1e s)\n",
               laws[L].name, ref[0], ref[1], ref[2], onset_error(&ref_rk45, ref_ark.onset));
        static double w_rk45[N_RTOL][MAX_REPEATS], w_ark[N_RTOL][MAX_REPEATS], w_rk4[MAX_REPEATS];
        run_t rk45_runs[N_RTOL], ark_runs[N_RTOL], rk4 = run_rk4(law);
        for (int r = 0; r < repeats; r++) { /* interleaved: load changes hit every variant */
            w_rk4[r] = run_rk4(law).wall;
            for (int i = 0; i < N_RTOL; i++) {
                rk45_runs[i] = run_rk45(law, RTOLS[i]);
                ark_runs[i] = run_arkode(law, RTOLS[i]);
                w_rk45[i][r] = rk45_runs[i].wall;
                w_ark[i][r] = ark_runs[i].wall;
            }
        }
        qsort(w_rk4, (size_t)repeats, sizeof(double), cmp);
        rk4.wall = w_rk4[repeats / 2];
        const double e_rk4 = onset_error(&rk4, ref);
        printf("  %-7s | %-28s | %-28s\n", "rtol", "RK45 (ours): error, RHS, wall",
               "ERKStep (ARKODE): error, RHS, wall");
        int best_rk45 = -1, best_ark = -1;
        for (int i = 0; i < N_RTOL; i++) {
            qsort(w_rk45[i], (size_t)repeats, sizeof(double), cmp);
            qsort(w_ark[i], (size_t)repeats, sizeof(double), cmp);
            rk45_runs[i].wall = w_rk45[i][repeats / 2];
            ark_runs[i].wall = w_ark[i][repeats / 2];
            const double e1 = onset_error(&rk45_runs[i], ref), e2 = onset_error(&ark_runs[i], ref);
            printf("  %-7.0e | %8.1e s %6ld %8.2f us | %8.1e s %6ld %8.2f us\n", RTOLS[i], e1,
                   rk45_runs[i].rhs, 1e6 * rk45_runs[i].wall, e2, ark_runs[i].rhs,
                   1e6 * ark_runs[i].wall);
            if (e1 <= e_rk4 && (best_rk45 < 0 || rk45_runs[i].wall < rk45_runs[best_rk45].wall)) {
                best_rk45 = i;
            }
            if (e2 <= e_rk4 && (best_ark < 0 || ark_runs[i].wall < ark_runs[best_ark].wall)) {
                best_ark = i;
            }
        }
        printf("  paper's RK4 (h0 = 2e-4 s, tol = 1e-4 m): error %.1e s, %ld RHS, %.1f us\n",
               e_rk4, rk4.rhs, 1e6 * rk4.wall);
        if (best_rk45 >= 0) {
            printf("  at that error: RK45 (ours) rtol %.0e, %.1f us: %.1fx faster than RK4\n",
                   RTOLS[best_rk45], 1e6 * rk45_runs[best_rk45].wall,
                   rk4.wall / rk45_runs[best_rk45].wall);
        }
        if (best_ark >= 0) {
            printf("  at that error: ERKStep rtol %.0e, %.1f us: %.1fx faster than RK4\n",
                   RTOLS[best_ark], 1e6 * ark_runs[best_ark].wall, rk4.wall / ark_runs[best_ark].wall);
        }
    }
    SUNContext_Free(&ctx);
    return 0;
}
