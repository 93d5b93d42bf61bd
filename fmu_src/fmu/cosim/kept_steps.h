/* The kept steps of co-simulation: integrator steps saved (their records: dense output, states
 * and derivatives at both ends) with the model's discrete state they ran with, so that the model
 * analyses them (fmu_model.analyse_step) only when its outputs are needed, not at every step: a
 * master that reads no output of a communication step does not pay for the analysis. The result
 * does not depend on when (or whether) the analysis runs: each step is analysed once, with the
 * discrete state it ran with, and hands its part of each communication step over again.
 *
 * Used by the stepper (cosimulation.c) for integrators that can save their steps (RK45); the
 * steps of the others are handed to the model live, as they are taken. */
#ifndef CSFH_KEPT_STEPS_H
#define CSFH_KEPT_STEPS_H

#include "csfh_visibility.h"
#include "integrator.h"

CSFH_INTERNAL_BEGIN

typedef struct kept_entry kept_entry_t;

typedef struct {
    void *room;             /* one block, allocated at the first step kept, for: */
    kept_entry_t *entry;    /* the steps that may still count, in order */
    unsigned char *memory;  /* the model's memory of each (fmu_model.step_memory) */
    double *records;        /* their integrator records (record_stride doubles each) */
    size_t record_stride;
    const cs_integrator_ops_t *ops; /* the integrator whose records they are */
    int n;
    unsigned char *snapshots; /* the model structs the steps saw (their discrete states) */
    int n_snapshots;
    int stale;                /* the discrete state changed since the last snapshot */
} kept_steps_t;

/* Forget every kept step (a restart from outside: the next ones start afresh). */
void kept_clear(kept_steps_t *k);
void kept_free(kept_steps_t *k);

/* Keep the last step of integrator `it` (which can save its steps) with the model's discrete
 * state; t_now: where the communication step (comm_start, ...] has got to before it. 1, or 0 if
 * it cannot be kept (out of memory): the caller analyses it now. */
int kept_keep(kept_steps_t *k, void *model, const cs_integrator_ops_t *ops, void *it,
              double comm_start, double t_now, double rtol);

/* An event at t changes the discrete state: the kept step holding it stops counting there. */
void kept_event(kept_steps_t *k, double t);

/* Hand the kept steps that cover part of (comm_start, t] to the model (analyse_step). */
void kept_analyse(kept_steps_t *k, void *model, double comm_start, double t, double rtol);

/* Drop the kept steps that count only up to t, except the last of them (its end values may
 * start the next step). */
void kept_drop(kept_steps_t *k, double t);

CSFH_INTERNAL_END

#endif
