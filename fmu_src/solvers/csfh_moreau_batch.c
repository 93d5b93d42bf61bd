#include "csfh_moreau_batch.h"

long long csfh_moreau_batch(csfh_model_t *const *models, size_t n, double h, int stick_rule,
                            double v_eps, double v_stick, double g_tol, double t0,
                            const double *x0, long long n_steps, long long record_every,
                            double *records, size_t max_records, double *impacts,
                            size_t max_impacts, double *x_end, long long *stats, int *status)
{
    if (models == NULL || x0 == NULL || x_end == NULL || stats == NULL || status == NULL ||
        (records == NULL && max_records > 0) || (impacts == NULL && max_impacts > 0)) {
        return -1;
    }
    const csfh_moreau_options_t o = {h, stick_rule, v_eps, v_stick, g_tol};
    long long failed = 0;
    for (size_t i = 0; i < n; i++) {
        if (models[i] == NULL) {
            return -1;
        }
    }
    for (size_t i = 0; i < n; i++) {
        csfh_moreau_stats_t s;
        double *rec = records != NULL ? records + i * max_records * CSFH_MR_NCOLS : NULL;
        double *imp = impacts != NULL ? impacts + i * max_impacts * CSFH_MI_NCOLS : NULL;
        status[i] = csfh_moreau_run(models[i], &o, t0, x0 + 6 * i, n_steps, record_every, rec,
                                    max_records, imp, max_impacts, x_end + 6 * i, &s);
        csfh_moreau_stats_array(&s, stats + i * CSFH_MOREAU_BATCH_NSTATS);
        failed += status[i] != CSFH_OK;
    }
    return failed;
}
