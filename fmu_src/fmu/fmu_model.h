/* The model interface of the generic FMI 2.0 glue.
 *
 * fmi2_glue.c (instance life cycle, state machine, get/set through the generated variable table,
 * model exchange, FMU state) and cosimulation.c (fmi2DoStep with CVODE) know nothing about the
 * physics: an FMU binary is the glue linked with one model adapter that defines the constant
 * `fmu_model` below. The csfh FMU's adapter is ../models/csfh/csfh_fmu_model.c, the comb-drive
 * actuator's is ../models/combdrive/combdrive_fmu_model.c.
 *
 * The model is one plain C struct (`size` bytes) holding everything: time, states, inputs,
 * parameters, derived quantities, discrete state and outputs. The generated variable table
 * (modelDescription/generate.py) addresses every FMI variable by its offset in that struct, so
 * get/set, start values and range checks are generic. The struct is copied bytewise for FMU
 * states, so it must not hold pointers. */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>

#include "csfh_vartable.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* Return values of derivatives() and outputs(). */
#define FMU_MODEL_OK 0
#define FMU_MODEL_WARNING 1 /* computed, with a caveat (message); the glue logs it once */
#define FMU_MODEL_NONFINITE (-1)

/* Integration methods of the co-simulation interface (cosimulation.c). */
#define FMU_CS_AUTO 0  /* RK45, BDF while stiff */
#define FMU_CS_BDF 1   /* CVODE: BDF, Newton iteration, dense linear solver */
#define FMU_CS_ADAMS 2 /* CVODE: Adams-Moulton, fixed-point iteration */
#define FMU_CS_RK45 3  /* explicit Runge-Kutta 5(4), Dormand-Prince (rk45.c) */

#define FMU_MAX_PEAKS 4 /* peak outputs tracked by the co-simulation stepper (csfh: 4) */

typedef struct {
    const char *guid;
    const char *model_identifier;
    int n_states;              /* continuous states x[], derivatives der[] (may be 0) */
    int n_event_indicators;    /* 0 or more */
    int n_variables;
    const csfh_variable_t *variables; /* the generated table */
    size_t size;               /* sizeof the model struct */
    size_t time_offset;        /* double time */
    size_t x_offset;           /* double x[n_states] */
    size_t der_offset;         /* double der[n_states] (derivative cache read by fmi2GetReal) */

    /* Start values of every variable (from the table) and a clean discrete state. */
    void (*set_defaults)(void *m);
    /* Validate every parameter, input and state start value, compute derived quantities.
     * 0, or -1 with a message naming the variable and its value. */
    int (*prepare)(void *m, char *msg, size_t msg_size);
    /* End of initialization, after prepare: check the start state (may be NULL); 0, or -1 with
     * a message naming the values. */
    int (*check_start)(void *m, char *msg, size_t msg_size);
    /* End of initialization: set the discrete state from the initial continuous state. Writes a
     * logEvents message (or an empty string). */
    void (*init_discrete)(void *m, char *msg, size_t msg_size);
    /* xdot = f(t, x) with the current inputs and discrete state, at the integrator's time t (model
     * exchange: the model's time; co-simulation: CVODE's time, not the model's); FMU_MODEL_OK,
     * FMU_MODEL_WARNING or FMU_MODEL_NONFINITE. NULL when n_states == 0. */
    int (*derivatives)(void *m, double t, const double *x, double *xdot);
    /* Time events (may be NULL: none): the first time > t at which the right-hand side changes
     * its form (csfh: the start and the end of the shock pulse), or INFINITY. Co-simulation stops
     * CVODE exactly there and restarts it; model exchange reports it as nextEventTime. */
    double (*next_time_event)(const void *m, double t);
    /* z[n_event_indicators] at state x. NULL when n_event_indicators == 0. */
    void (*event_indicators)(const void *m, const double *x, double *z);
    /* Discrete-state update at an event (from the model's time and state): 0 if nothing changed,
     * > 0 if the discrete state changed (the integrator must restart); writes a logEvents
     * message (none when msg_size is 0: logging is off). NULL when n_event_indicators == 0. */
    int (*event_update)(void *m, char *msg, size_t msg_size);
    /* Fill the outputs at the current time, state and inputs: FMU_MODEL_OK, FMU_MODEL_WARNING
     * (message) or FMU_MODEL_NONFINITE (message). */
    int (*outputs)(void *m, char *msg, size_t msg_size);
    /* Add co-simulation integrator steps to the model's counter (may be NULL). */
    void (*add_integrator_steps)(void *m, long steps);
    /* The co-simulation method, FMU_CS_AUTO, FMU_CS_BDF, FMU_CS_ADAMS or FMU_CS_RK45 (NULL:
     * BDF). */
    int (*cs_method)(const void *m);
    /* Peak outputs of co-simulation (all NULL and n_peaks 0: none): the co-simulation stepper
     * tracks the largest values of n_peaks (<= FMU_MAX_PEAKS) quantities over each
     * communication step on CVODE's interpolant. peaks_begin starts a communication step with
     * the values at the current state (taken from the outputs when outputs_current, else
     * evaluated), peak_values gives the quantities at state x with the current discrete state
     * (returns 0, without evaluating, when they are all 0: nothing to track), peaks_add takes
     * values in. */
    int n_peaks;
    void (*peaks_begin)(void *m, int outputs_current);
    int (*peak_values)(void *m, const double *x, double *v);
    void (*peaks_add)(void *m, const double *v);
    /* The discrete state the peak quantities depend on (csfh: the contact mode and onset rate),
     * peaks_state_size bytes: saved from m into `state`, and restored into m, so that a step can
     * be analysed for its peaks after an event has changed it (NULL: every step is analysed
     * when taken). */
    size_t peaks_state_size;
    void (*peaks_state_save)(const void *m, void *state);
    void (*peaks_state_restore)(void *m, const void *state);
    /* 1 if the peak quantities can be nonzero in the current discrete state (csfh: in the
     * contact mode), 0 if peak_values would return 0 whatever the state (NULL: always 1). */
    int (*peaks_tracked)(const void *m);
    /* A restored FMU state (fmi2SetFMUstate, fmi2DeSerializeFMUstate): check the fields of the
     * model struct that are neither stored table variables (the glue checks those: finite, in
     * range) nor recomputed (derived quantities, outputs, derivative cache), e.g. counts that
     * must be >= 0 and internal flags. 0, or -1 with a message naming the field and its value.
     * NULL when there are no such fields. Every new field of the model struct must be covered
     * by one of the three. */
    int (*check_state)(const void *m, char *msg, size_t msg_size);
} fmu_model_t;

/* Defined by the model adapter linked into the FMU binary. */
extern const fmu_model_t fmu_model;

CSFH_INTERNAL_END

#endif
