/* The model interface of the generic FMU layer.
 *
 * The instance (fmu_instance.c: life cycle, state machine, get/set through the generated variable
 * table, model exchange, FMU state), the co-simulation stepper (cosim/cosimulation.c) and the FMI
 * front-ends (fmi2/, fmi3/) know nothing about the physics: an FMU binary is that layer linked
 * with one model adapter that defines the constant `fmu_model` below. The csfh FMU's adapter is
 * ../models/csfh/csfh_fmu_model.c, the comb-drive actuator's is
 * ../models/combdrive/combdrive_fmu_model.c.
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

/* A finished integrator step of co-simulation, as the stepper hands it to the model's
 * analyse_step (all times are the integrator's local times: the model's time is origin + t):
 *   live   the integrator's last step, at every pass of the stepper's loop over it: new_step
 *          when the pass took it, else a continuation (a root inside it, or the communication
 *          point before its end); its dense output is the integrator's own, valid until the
 *          next step. keep (NULL: the integrator cannot save its steps) asks the stepper to keep
 *          the step for later: 1, or 0 if it cannot (then analyse it now). memory: the model's
 *          memory of the live steps, zeroed at every restart of the integrator.
 *   kept   a step kept earlier, handed over when the model's outputs are needed (an output read,
 *          an FMU state taken, a value set) or the stepper's room is full: its dense output is
 *          the saved record, `model` is the model struct as it was when the step was taken (its
 *          discrete state), `previous` the step kept before it if this one continues it (it ends
 *          where this one starts, uncut, in the same discrete state), cut where it stops
 *          counting (tn, or an event that cut it short), memory the model's for this step,
 *          zeroed when it was kept. */
typedef struct fmu_step fmu_step_t;
struct fmu_step {
    int live, new_step;
    double t0, tn, h; /* the step and its size */
    double cut;
    double rtol;      /* the integration's relative tolerance */
    /* the state (k = 0) or its derivative (k = 1) at t in [t0, tn]: 0, or < 0 if unavailable */
    int (*dense)(const fmu_step_t *step, double t, int k, double *out);
    /* the state and its derivative at t0 and tn exactly as the integrator used them (NULL:
     * unknown, interpolate) */
    const double *y0, *f0, *y1, *f1;
    const void *model;          /* kept: the model struct as the step saw it */
    void *memory;               /* fmu_model.step_memory bytes */
    const fmu_step_t *previous; /* kept */
    int (*keep)(const fmu_step_t *step); /* live */
};

typedef struct {
    const char *guid;
    const char *model_identifier;
    int n_states;              /* continuous states x[], derivatives der[] (may be 0) */
    int n_event_indicators;    /* 0 or more */
    int n_variables;
    const csfh_variable_t *variables; /* the generated table */
    double default_tolerance;  /* relative tolerance when fmi2SetupExperiment gives none (the
                                  [default_experiment] tolerance: <prefix>_constants.h) */
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
    /* A subset of the outputs alone (both NULL: none), for a master that reads only those at
     * every communication point: subset_outputs fills the outputs whose fields in_subset
     * accepts (by offset in the model struct), each with the value outputs() gives it, and
     * returns as outputs() does; every field comm_step_begins takes from the outputs is in it. */
    int (*subset_outputs)(void *m, char *msg, size_t msg_size);
    int (*in_subset)(size_t offset);
    /* Add co-simulation integrator steps, and Jacobians formed, to the model's counters (may be
     * NULL). */
    void (*add_integrator_steps)(void *m, long steps);
    void (*add_jacobians)(void *m, long jacobians);
    /* Co-simulation's BDF: the Jacobian J[i + j * n_states] = d xdot_i / d x_j at (t, x) as its
     * Newton matrix, where cs_jacobian (may be NULL) says so for the model's parameters (else
     * difference quotients); FMU_MODEL_OK or FMU_MODEL_NONFINITE. */
    int (*cs_jacobian)(const void *m);
    int (*state_jacobian)(void *m, double t, const double *x, double *A);
    /* The co-simulation method, FMU_CS_AUTO, FMU_CS_BDF, FMU_CS_ADAMS or FMU_CS_RK45 (NULL:
     * BDF). */
    int (*cs_method)(const void *m);
    /* Outputs over each communication step of co-simulation (csfh: the peak outputs; all NULL
     * and 0: none): comm_step_begins at the start of every communication step (the outputs are
     * current at the state there if outputs_current), then every integrator step through
     * analyse_step (fmu_step_t) with the part (from, to] of the communication step it covers;
     * step_memory bytes of memory are kept with every step for the model. */
    size_t step_memory;
    void (*comm_step_begins)(void *m, int outputs_current);
    void (*analyse_step)(void *m, const fmu_step_t *step, double from, double to);
    /* A restored FMU state (fmi2SetFMUstate, fmi2DeSerializeFMUstate): check the fields of the
     * model struct that are neither stored table variables (the glue checks those: finite, in
     * range) nor recomputed (derived quantities, outputs, derivative cache), e.g. counts that
     * must be >= 0 and internal flags. 0, or -1 with a message naming the field and its value.
     * NULL when there are no such fields. Every new field of the model struct must be covered
     * by one of the three. */
    int (*check_state)(const void *m, char *msg, size_t msg_size);
    /* Partial derivatives (NULL and 0: not provided): the value references of the model's
     * differentiable unknowns (derivatives and continuous outputs) and of its knowns (states
     * and inputs); jacobian fills J[i * n_jac_knowns + j] = d unknown_i / d known_j at the
     * current time, states, inputs and discrete state (at most 1024 entries):
     * FMU_MODEL_OK or FMU_MODEL_NONFINITE. */
    int n_jac_unknowns, n_jac_knowns;
    const unsigned int *jac_unknowns, *jac_knowns;
    int (*jacobian)(void *m, double *J);
} fmu_model_t;

/* Defined by the model adapter linked into the FMU binary. */
extern const fmu_model_t fmu_model;

CSFH_INTERNAL_END

#endif
