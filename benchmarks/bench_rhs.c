#define _POSIX_C_SOURCE 199309L
/* Cost of one right-hand-side evaluation of the C model, and what switching parts off saves.
 * All configurations are timed in the same run, interleaved and repeated; the report gives the
 * median time per call, the fastest repeat (on a shared machine the least disturbed one: what
 * the code itself costs) and ratios to the full model. The stress outputs (flexure stress,
 * Hertz pressure: docs/model.md §14.2-14.3) are not part of the right-hand side: their cost is
 * timed separately, per evaluation, as what reading them costs at an output point. Build:
 * cmake --build build --target bench_rhs; run: build/bench_rhs. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "csfh_fmu.h"
#include "csfh_model.h"
#include "csfh_variables.h"

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

typedef struct {
    const char *name;
    int law, flexure, friction;
    double x[6]; /* state: in contact (gap < 0) or free */
} config_t;

/* What is timed for a configuration: the RHS, or one of the output-time stress evaluations. */
enum { KIND_RHS, KIND_STRESSES, KIND_FLEXURE_STRESS, KIND_PRESSURE };

int main(void)
{
    /* a state in contact with sliding (indentation 5e-5 m at -60 deg, v_T != 0) and a free one */
    const double in_contact[6] = {0.5 * 0.02005, -0.8660254 * 0.02005, 0.01, 0.05, -0.02, 0.3};
    const double free_state[6] = {0.005, 0.005, 0.01, 0.05, -0.02, 0.3};
    const config_t configs[] = {
        {"full: LN_spheres + friction + flexure, in contact", CSFH_CONTACTLAW_LN_SPHERES, 1, 1, {0}},
        {"LN_ESDU (I3) + friction + flexure, in contact", CSFH_CONTACTLAW_LN_ESDU, 1, 1, {0}},
        {"LN_spheres + friction, flexure off, in contact", CSFH_CONTACTLAW_LN_SPHERES, 0, 1, {0}},
        {"LN_spheres, friction off, flexure off, in contact", CSFH_CONTACTLAW_LN_SPHERES, 0, 0, {0}},
        {"full, free flight (gap > 0)", CSFH_CONTACTLAW_LN_SPHERES, 1, 1, {0}},
        {"law none, flexure on", CSFH_CONTACTLAW_NONE, 1, 1, {0}},
        {"law none, flexure off (gravity only)", CSFH_CONTACTLAW_NONE, 0, 0, {0}},
        {"outputs only: stresses (flexure + Hertz pressure)", CSFH_CONTACTLAW_LN_SPHERES, 1, 1, {0}},
        {"outputs only: flexure stress", CSFH_CONTACTLAW_LN_SPHERES, 1, 1, {0}},
        {"outputs only: Hertz pressure", CSFH_CONTACTLAW_LN_SPHERES, 1, 1, {0}},
    };
    const int kind[] = {KIND_RHS, KIND_RHS, KIND_RHS, KIND_RHS, KIND_RHS, KIND_RHS, KIND_RHS,
                        KIND_STRESSES, KIND_FLEXURE_STRESS, KIND_PRESSURE};
    enum { NC = sizeof(configs) / sizeof(configs[0]), REPEATS = 15, CALLS = 200000 };
    csfh_model_t models[NC];
    double xs[NC][6];
    for (int c = 0; c < NC; c++) {
        csfh_fmu_model_defaults(&models[c]);
        models[c].p.law = configs[c].law;
        models[c].p.flexure_enabled = configs[c].flexure;
        models[c].p.friction_enabled = configs[c].friction;
        char msg[256];
        if (csfh_model_prepare(&models[c], msg, sizeof msg) != 0) {
            fprintf(stderr, "%s\n", msg);
            return 1;
        }
        const double *x = c == 4 ? free_state : in_contact;
        for (int i = 0; i < 6; i++) {
            xs[c][i] = x[i];
        }
        models[c].z.in_contact = c != 4;
        models[c].z.onset_speed = 0.5;
    }
    double samples[NC][REPEATS];
    volatile double sink = 0.0;
    for (int r = 0; r < REPEATS; r++) {
        for (int c = 0; c < NC; c++) { /* interleaved: load changes hit all configurations */
            double xdot[6];
            const double t0 = now();
            if (kind[c] == KIND_RHS) {
                for (int k = 0; k < CALLS; k++) {
                    xs[c][5] += 1e-12; /* defeat hoisting */
                    csfh_model_derivatives(&models[c], 0.0, xs[c], xdot);
                    sink += xdot[3];
                }
            } else if (kind[c] == KIND_STRESSES) {
                for (int k = 0; k < CALLS; k++) {
                    xs[c][2] += 1e-12;
                    csfh_stresses_t st;
                    csfh_model_stresses(&models[c], xs[c], 2000.0 + xs[c][2], &st);
                    sink += st.flexure_stress + st.contact_pressure;
                }
            } else if (kind[c] == KIND_FLEXURE_STRESS) {
                for (int k = 0; k < CALLS; k++) {
                    xs[c][2] += 1e-12;
                    sink += csfh_model_flexure_stress(&models[c], xs[c], NULL);
                }
            } else {
                for (int k = 0; k < CALLS; k++) {
                    xs[c][2] += 1e-12;
                    sink += csfh_hertz_line_pressure(2000.0 + xs[c][2], models[c].d.E_star,
                                                     models[c].p.L, models[c].d.R_conformal, NULL);
                }
            }
            samples[c][r] = (now() - t0) / CALLS;
        }
    }
    double median[NC], fastest[NC];
    for (int c = 0; c < NC; c++) {
        qsort(samples[c], REPEATS, sizeof(double), cmp);
        median[c] = samples[c][REPEATS / 2];
        fastest[c] = samples[c][0];
    }
    printf("RHS cost of the C model (%d repeats of %d calls)\n", REPEATS, CALLS);
    printf("%-55s %10s %10s %9s\n", "configuration", "ns median", "ns best", "vs full");
    for (int c = 0; c < NC; c++) {
        printf("%-55s %10.1f %10.1f %9.3f\n", configs[c].name, 1e9 * median[c], 1e9 * fastest[c],
               median[c] / median[0]);
    }
    printf("target: full model in contact <= 80 ns per call: median %s, best repeat %s\n",
           median[0] <= 80e-9 ? "met" : "NOT met", fastest[0] <= 80e-9 ? "met" : "NOT met");
    printf("the right-hand side evaluates no stress (csfh_model_derivatives); the stresses cost the\n"
           "last rows per output point that reads them (docs/model.md §14.5)\n");
    return sink == 12345.0;
}
