/* The peak outputs of the csfh FMU in co-simulation (contact.F_N_peak, contact.F_T_peak,
 * contact.indentation_peak, flexure.stress_max_peak; csfh_fmu.h: csfh_peaks_t): the largest
 * values over each communication step, located on the integrator's dense output of every step
 * the stepper hands over (fmu_model.h: fmu_step_t). */
#ifndef CSFH_PEAKS_H
#define CSFH_PEAKS_H

#include <stddef.h>

#include "csfh_fmu.h"
#include "csfh_visibility.h"
#include "fmu_model.h"

CSFH_INTERNAL_BEGIN

/* What is known of one step, the memory the stepper keeps with every step for the peaks
 * (fmu_model.step_memory): of a kept step its own analysis, of the live steps the last one's
 * (zeroed at every restart of the integrator). */
typedef struct {
    int analysed, start_done, end_done; /* (kept steps) */
    int start_valid, end_valid; /* the quantities are tracked there, values and slopes: */
    double v0[CSFH_N_PEAKS], s0[CSFH_N_PEAKS], v1[CSFH_N_PEAKS], s1[CSFH_N_PEAKS];
    double t_end;               /* (live) the end of the last analysed step */
    int n_max;                  /* the maxima inside it: times and values */
    double max_t[CSFH_N_PEAKS];
    double max_v[CSFH_N_PEAKS][CSFH_N_PEAKS];
} csfh_step_peaks_t;

/* A communication step begins: the peaks start with the values at the current state (taken
 * from the outputs when outputs_current, else evaluated). */
void csfh_peaks_begin(void *model, int outputs_current);

/* The peaks of an integrator step in the part (from, to] of the communication step. */
void csfh_peaks_analyse_step(void *model, const fmu_step_t *step, double from, double to);

CSFH_INTERNAL_END

#endif
