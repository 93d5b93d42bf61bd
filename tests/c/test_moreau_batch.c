/* The batched Moreau runs (csfh_moreau_batch.c): every variant of a batch equals, bit for
 * bit, the single run of csfh_moreau_run with the same model, whatever its place in the batch;
 * the buffers of one variant never touch another's (run under ASan); bad arguments are refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_fmu.h"
#include "csfh_model.h"
#include "csfh_moreau_batch.h"
#include "csfh_test.h"

#define N_VAR 3
#define N_STEPS 20000 /* 0.2 s at h = 1e-5 s: the first impact of the csfh scene at 0.072 s */
#define EVERY 100
#define MAX_REC (N_STEPS / EVERY + 2)
#define MAX_IMP 16

static void make_model(csfh_model_t *m, double R1, double h_beam)
{
    char msg[256] = "";
    csfh_fmu_model_defaults(m);
    m->p.R1 = R1;
    m->p.h = h_beam;
    CHECK_INT(csfh_model_prepare(m, msg, sizeof(msg)), 0, TFMT("prepare: %s", msg));
}

int main(void)
{
    const double x0[6] = {0.01, 0.01, 0.0, 0.0, 0.0, 0.0};
    const double R1[N_VAR] = {0.18, 0.181, 0.179};
    const double hb[N_VAR] = {0.005, 0.006, 0.005};
    csfh_model_t models[N_VAR], single;
    csfh_model_t *handles[N_VAR];
    double x0s[N_VAR * 6];
    for (int i = 0; i < N_VAR; i++) {
        make_model(&models[i], R1[i], hb[i]);
        handles[i] = &models[i];
        memcpy(x0s + 6 * i, x0, sizeof(x0));
    }
    double *rec = calloc((size_t)N_VAR * MAX_REC * CSFH_MR_NCOLS, sizeof(double));
    double *imp = calloc((size_t)N_VAR * MAX_IMP * CSFH_MI_NCOLS, sizeof(double));
    double x_end[N_VAR * 6];
    long long stats[N_VAR * CSFH_MOREAU_BATCH_NSTATS];
    int status[N_VAR];
    const long long failed = csfh_moreau_batch(handles, N_VAR, 1e-5, CSFH_STICK_PAPER, 0.0,
                                                   1e-9, 0.0, 0.0, x0s, N_STEPS, EVERY, rec,
                                                   MAX_REC, imp, MAX_IMP, x_end, stats, status);
    CHECK_INT((int)failed, 0, "no variant fails");

    /* each variant against its single run */
    double *rec1 = calloc((size_t)MAX_REC * CSFH_MR_NCOLS, sizeof(double));
    double *imp1 = calloc((size_t)MAX_IMP * CSFH_MI_NCOLS, sizeof(double));
    for (int i = 0; i < N_VAR; i++) {
        csfh_moreau_options_t o;
        csfh_moreau_default_options(&o);
        csfh_moreau_stats_t s;
        double xe[6];
        make_model(&single, R1[i], hb[i]);
        CHECK_INT(csfh_moreau_run(&single, &o, 0.0, x0, N_STEPS, EVERY, rec1, MAX_REC, imp1,
                                  MAX_IMP, xe, &s),
                  CSFH_OK, "single run");
        const long long *st = stats + i * CSFH_MOREAU_BATCH_NSTATS;
        CHECK_TRUE(st[0] == s.steps && st[6] == (long long)s.records &&
                       st[7] == (long long)s.impacts && st[5] == s.onsets,
                   TFMT("variant %d: the same statistics", i));
        CHECK_TRUE(s.impacts >= 1, TFMT("variant %d reaches the first impact", i));
        CHECK_TRUE(memcmp(rec + (size_t)i * MAX_REC * CSFH_MR_NCOLS, rec1,
                          s.records * CSFH_MR_NCOLS * sizeof(double)) == 0,
                   TFMT("variant %d: records bitwise equal", i));
        CHECK_TRUE(memcmp(imp + (size_t)i * MAX_IMP * CSFH_MI_NCOLS, imp1,
                          s.impacts * CSFH_MI_NCOLS * sizeof(double)) == 0,
                   TFMT("variant %d: impacts bitwise equal", i));
        CHECK_TRUE(memcmp(x_end + 6 * i, xe, sizeof(xe)) == 0,
                   TFMT("variant %d: final state bitwise equal", i));
    }
    /* the variants are different runs: the clearance moves the first impact */
    const double t_imp0 = imp[CSFH_MI_T];
    const double t_imp1 = imp[(size_t)MAX_IMP * CSFH_MI_NCOLS + CSFH_MI_T];
    CHECK_TRUE(t_imp1 < t_imp0, "a smaller clearance (R1 + 1 mm) touches earlier");

    /* bad arguments */
    CHECK_INT((int)csfh_moreau_batch(NULL, N_VAR, 1e-5, 1, 0, 0, 0, 0, x0s, 10, 1, rec,
                                         MAX_REC, imp, MAX_IMP, x_end, stats, status),
              -1, "NULL models refused");
    CHECK_INT((int)csfh_moreau_batch(handles, N_VAR, 1e-5, 1, 0, 0, 0, 0, x0s, 10, 1, NULL,
                                         MAX_REC, imp, MAX_IMP, x_end, stats, status),
              -1, "NULL records with a size refused");
    /* no records and no impacts are allowed */
    CHECK_INT((int)csfh_moreau_batch(handles, N_VAR, 1e-5, 1, 0, 0, 0, 0, x0s, 10, 1, NULL, 0,
                                         NULL, 0, x_end, stats, status),
              0, "outputs optional");
    free(rec);
    free(imp);
    free(rec1);
    free(imp1);
    return TEST_SUMMARY();
}
