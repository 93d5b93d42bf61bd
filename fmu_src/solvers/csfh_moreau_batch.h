/* Batched Moreau runs: many parameter sets (one csfh_model_t each, prepared by the caller) stepped
 * in one call, for parameter sweeps and Monte Carlo studies. Each variant is integrated by
 * csfh_moreau_run itself, one after the other: a batched result is bitwise the result of the
 * single run, whatever the batch size or the order. The saving is the call overhead (one call
 * instead of one per variant from Python) and the buffers, which the caller allocates once. */
#ifndef CSFH_MOREAU_BATCH_H
#define CSFH_MOREAU_BATCH_H

#include <stddef.h>

#include "csfh_moreau.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* Number of statistics per variant written by csfh_moreau_batch (csfh_moreau_stats_array). */
#define CSFH_MOREAU_BATCH_NSTATS CSFH_MOREAU_NSTATS

/* Run n variants with the same step options, start time and number of steps.
 *   models       n model handles (parameters set and prepared; each is modified as by a run)
 *   x0           n x 6 initial states
 *   records      n x max_records x CSFH_MR_NCOLS (may be NULL with max_records 0)
 *   impacts      n x max_impacts x CSFH_MI_NCOLS (may be NULL with max_impacts 0)
 *   x_end        n x 6 final states
 *   stats        n x CSFH_MOREAU_BATCH_NSTATS
 *   status       n return codes of csfh_moreau_run (CSFH_OK or CSFH_ERR_NONFINITE)
 * Returns the number of variants whose status is not CSFH_OK, or -1 for bad arguments. */
long long csfh_moreau_batch(csfh_model_t *const *models, size_t n, double h, int stick_rule,
                            double v_eps, double v_stick, double g_tol, double t0,
                            const double *x0, long long n_steps, long long record_every,
                            double *records, size_t max_records, double *impacts,
                            size_t max_impacts, double *x_end, long long *stats, int *status);

CSFH_INTERNAL_END

#endif
