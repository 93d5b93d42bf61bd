/* The FMU instance: everything of an FMU instance that does not depend on the FMI version, shared
 * by the thin FMI front-ends (fmi2_glue.c: FMI 2.0, fmi3_glue.c: FMI 3.0) and the co-simulation
 * stepper (cosimulation.c). No FMI header is included here: statuses, instance kinds and the
 * logger are our own types, which the front-ends translate (the status values are those of both
 * standards: OK, Warning, Discard, Error, Fatal). The model itself is behind the interface of
 * fmu_model.h.
 *
 * One file per concern: fmu_log.c (the log, the state machine's check of a call), fmu_instance.c
 * (life cycle, the model helpers: prepare, outputs, derivatives, event update; the experiment and
 * initialization), fmu_values.c (get and set through the generated variable table), fmu_state.c
 * (the FMU state: snapshot, validation on restore, serialization), fmu_me.c (model exchange),
 * fmu_step.c (the communication step's check). */
#ifndef CSFH_FMU_INSTANCE_H
#define CSFH_FMU_INSTANCE_H

#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "csfh_visibility.h"
#include "fmu_model.h"

CSFH_INTERNAL_BEGIN

/* Status of a call: the numbering of fmi2Status and fmi3Status (OK .. Fatal). */
typedef enum {
    FMU_OK = 0,
    FMU_WARNING = 1,
    FMU_DISCARD = 2,
    FMU_ERROR = 3,
    FMU_FATAL = 4
} fmu_status_t;

/* The interface an instance was made for (the values of fmi2Type: states serialized by FMI 2.0
 * instances keep their meaning). */
typedef enum { FMU_ME = 0, FMU_CS = 1 } fmu_kind_t;

/* Instance states (bits of the state tables' masks). FMI 3.0's Step Mode is FMU_STEP_COMPLETE; a
 * co-simulation instance of FMI 3.0 with eventModeUsed also enters FMU_EVENT. */
typedef enum {
    FMU_INSTANTIATED = 1 << 0,
    FMU_INITIALIZATION = 1 << 1,
    FMU_EVENT = 1 << 2,
    FMU_CONTINUOUS = 1 << 3,    /* ME */
    FMU_STEP_COMPLETE = 1 << 4, /* CS */
    FMU_STEP_FAILED = 1 << 5,   /* CS */
    FMU_TERMINATED = 1 << 6,
    FMU_ERROR_STATE = 1 << 7
} fmu_state_t;

#define FMU_ANY_STATE                                                                          \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE |  \
     FMU_STEP_FAILED | FMU_TERMINATED | FMU_ERROR_STATE)

/* The interfaces a function is for, in the masks of the front-ends' state tables (with the
 * states' bits). */
enum { FMU_FOR_ME = 1 << 8, FMU_FOR_CS = 1 << 9 };

/* Log categories of modelDescription.xml. */
enum {
    LOG_EVENTS = 1 << 0,
    LOG_STATUS_WARNING = 1 << 1,
    LOG_STATUS_ERROR = 1 << 2,
    LOG_ALL = 1 << 3
};

typedef struct cs_integration cs_integration_t; /* opaque, cosim/cosimulation.c */
typedef struct fmu_instance fmu_instance_t;

/* What the instance asks of the co-simulation stepper (cosimulation.h: cs_stepper), set by the
 * FMI front-end that made the instance; the instance does not call the stepper otherwise, so
 * the dependencies go one way: front-end -> stepper -> instance -> model. */
typedef struct {
    void (*free)(fmu_instance_t *inst);  /* release the integrator (none: nothing) */
    /* bring the model's analysis of the communication step's integrator steps up to date */
    void (*flush)(fmu_instance_t *inst);
} fmu_stepper_t;

/* The front-end's logger: passes a formatted message to the importer's callback. */
typedef void (*fmu_logger_t)(const fmu_instance_t *inst, fmu_status_t status,
                             const char *category, const char *message);
/* Any function pointer (the importer's callback, called only through its own type). */
typedef void (*fmu_callback_t)(void);

/* The size of every message the instance formats. */
#define FMU_MSG_SIZE 512

struct fmu_instance {
    void *model;            /* the model struct, fmu_model.size bytes */
    fmu_kind_t type;
    int fmi_version;        /* 2 or 3: the front-end that made the instance */
    char *instance_name;
    fmu_logger_t log_message;  /* the front-end's adapter (NULL: no logger) */
    fmu_callback_t logger;     /* the importer's logger, for the adapter */
    void *environment;         /* the importer's environment pointer */
    unsigned int log_categories;
    fmu_state_t state;
    int prepared;           /* model.d is valid for the current parameters */
    int outputs_valid;      /* model.out matches the current state/inputs */
    int derivatives_valid;  /* model.der matches the current state/inputs */
    int warned_outputs;     /* the model's output warning (e.g. the ESDU clamp) was logged */
    /* experiment */
    double tolerance;       /* relative tolerance of the co-simulation integrator */
    double start_time;
    double stop_time;
    int stop_time_defined;
    /* co-simulation */
    const char *step_function; /* "fmi2DoStep" or "fmi3DoStep": the name in the stepper's messages */
    int event_mode_used;       /* FMI 3.0: the importer handles events in Event Mode */
    int early_return_allowed;  /* FMI 3.0: fmi3DoStep may return at an event */
    const fmu_stepper_t *stepper; /* NULL: none (nothing to free or flush) */
    cs_integration_t *integration; /* the co-simulation integration (NULL: none yet) */
    int restart_integration; /* restart it at the next step: states, inputs or tunable parameters
                                were changed from outside, an FMU state was taken or restored */
    /* FMU states made by this instance (get, deserialize) and not yet freed: only these are
     * accepted, freeing the instance frees the rest */
    void **fmu_states;
    size_t n_fmu_states, cap_fmu_states;
    /* time resolution: the warning that the double time does not resolve the steps was logged;
     * model exchange: time and states at the last completed integrator step (last_step_x:
     * n_states doubles) */
    int warned_time;
    int last_step_valid;
    double last_step_time;
    double *last_step_x;
    /* value reference -> index in fmu_model.variables (-1: none), n_vr_index entries: get and
     * set find a variable in constant time, not by a search of the table */
    int *vr_index;
    unsigned int n_vr_index;
    /* value reference -> what a get needs of its variable, n_vr_index entries (fmu_vr_get_t) */
    struct fmu_vr_get *vr_get;
};

/* What fmu_get_values needs of a value reference, in 8 bytes: a get reads these instead of the
 * variable's whole table entry (the values read at every communication point stay in cache). */
typedef struct fmu_vr_get {
    unsigned int offset;   /* of the value in the model struct */
    unsigned char accept;  /* FMU_ACCEPT(type); 0: no variable has this reference */
    unsigned char refresh; /* FMU_REFRESH_*: what must be up to date before it is read */
    unsigned char boolean; /* stored as an int read as 0 or 1 */
} fmu_vr_get_t;

enum { FMU_REFRESH_NONE, FMU_REFRESH_PREPARE, FMU_REFRESH_DERIVATIVES, FMU_REFRESH_OUTPUTS };

/* ------------------------------------------------------------------------------------------ */
/* life cycle */

/* A new instance (state Instantiated, start values set), or NULL when out of memory. */
fmu_instance_t *fmu_instance_new(const char *instance_name, fmu_kind_t type, int fmi_version,
                                 int logging_on);
void fmu_instance_free(fmu_instance_t *inst);
/* Back to Instantiated with the start values (fmi2Reset, fmi3Reset). */
void fmu_instance_reset(fmu_instance_t *inst);

/* ------------------------------------------------------------------------------------------ */
/* logging and call checks */

/* (cold: the compiler moves the paths that log, errors above all, out of the hot code) */
void fmu_log(const fmu_instance_t *inst, fmu_status_t status, unsigned int category,
             const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5), cold))
#endif
    ;
#define FMU_LOG_ERROR(inst, ...) fmu_log((inst), FMU_ERROR, LOG_STATUS_ERROR, __VA_ARGS__)

const char *fmu_category_name(unsigned int category);
const char *fmu_state_name(fmu_state_t s);
/* The one check of a call, at the start of every FMI function (the masks: each front-end's state
 * table, fmi2/fmi2_states.h, fmi3/fmi3_states.h): 1 if the instance is in one of the mask's
 * states (the call is logged under logAll) and of one of its interfaces (FMU_FOR_ME,
 * FMU_FOR_CS), else 0 (logged; 0 also for a NULL instance). The instance's functions below
 * rely on it: they check their arguments, not the state. */
int fmu_allowed(fmu_instance_t *inst, const char *function, unsigned int mask);
int fmu_not_null(fmu_instance_t *inst, const char *function, const void *p, const char *arg);
/* Debug logging: every category (n == 0) or the named ones on or off. */
fmu_status_t fmu_set_debug_logging(fmu_instance_t *inst, const char *function, int on, size_t n,
                                   const char *const categories[]);

/* ------------------------------------------------------------------------------------------ */
/* model helpers */

/* Validate the parameters and compute derived quantities once (logged on failure). */
fmu_status_t fmu_prepare(fmu_instance_t *inst, const char *function);
fmu_status_t fmu_update_derivatives(fmu_instance_t *inst, const char *function);
/* Outputs at the current state; logs a model warning once per instance. FMU_OK, FMU_WARNING or
 * FMU_ERROR (logged, prefixed with `function`). */
fmu_status_t fmu_update_outputs(fmu_instance_t *inst, const char *function);
/* A directional (adjoint 0: sensitivity = J seed) or adjoint (1: sensitivity = J^T seed)
 * derivative, J = d unknowns / d knowns (fmu_derivatives.c); FMI 2.0 passes n_seed = n_knowns
 * and n_sensitivity = n_unknowns. FMU_OK, or FMU_ERROR (logged: a bad argument, an unknown or a
 * known the interface does not allow, a non-finite derivative, a model without jacobian). */
typedef struct {
    const unsigned int *unknowns, *knowns;
    size_t n_unknowns, n_knowns;
    const double *seed;
    double *sensitivity;
    size_t n_seed, n_sensitivity;
    int adjoint;
} fmu_derivative_call_t;
fmu_status_t fmu_partial_derivatives(fmu_instance_t *inst, const char *function,
                                     const fmu_derivative_call_t *call);
/* Discrete-state update at an event, with logging; returns fmu_model.event_update's value. */
int fmu_event_update(fmu_instance_t *inst);
/* The continuous states as text, for messages. */
const char *fmu_state_text(fmu_instance_t *inst, char *text, size_t size);
/* The next time event after the model's time (INFINITY: none). */
double fmu_next_time_event(fmu_instance_t *inst);

/* ------------------------------------------------------------------------------------------ */
/* experiment, initialization */

/* The relative tolerances the co-simulation integrators (RK45, CVODE) can honour: from ten
 * units of round-off, below which their error estimates are round-off themselves (and the
 * absolute tolerances, relative x nominal, underflow), up to but not including 1, where an error
 * as large as the solution passes. fmu_setup_experiment refuses any other. */
#define FMU_TOLERANCE_MIN (10.0 * DBL_EPSILON)
#define FMU_TOLERANCE_MAX 1.0

/* The checks and settings of fmi2SetupExperiment / fmi3EnterInitializationMode. */
fmu_status_t fmu_setup_experiment(fmu_instance_t *inst, const char *function, int tolerance_defined,
                                  double tolerance, double start_time, int stop_time_defined,
                                  double stop_time);
/* End of initialization: validate everything, check the start state, set the discrete state.
 * A refused call changes nothing. The caller sets the next instance state. */
fmu_status_t fmu_exit_initialization(fmu_instance_t *inst, const char *function);

/* ------------------------------------------------------------------------------------------ */
/* get and set through the variable table */

/* The C type of the importer's value array. */
typedef enum {
    FMU_VALUE_DOUBLE,  /* fmi2Real, fmi3Float64 */
    FMU_VALUE_INT,     /* fmi2Integer, fmi2Boolean (int), fmi3Int32 */
    FMU_VALUE_INT64,   /* fmi3Int64 (enumerations) */
    FMU_VALUE_BOOL     /* fmi3Boolean (C bool) */
} fmu_value_kind_t;

/* Variable types a call accepts: bit (1 << csfh_type_t). */
#define FMU_ACCEPT(type) (1u << (unsigned int)(type))

/* value[i] of vr[i] for variables of the accepted types; the values of `accept`'s types are
 * written as `kind`. */
fmu_status_t fmu_get_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind, void *value);
/* All or nothing: every value is checked (range, finiteness, the state's settability) before
 * any is applied; tunable parameters set while running are validated together and rolled back
 * together. */
fmu_status_t fmu_set_values(fmu_instance_t *inst, const char *function, const unsigned int vr[],
                            size_t nvr, unsigned int accept, fmu_value_kind_t kind,
                            const void *value);

/* ------------------------------------------------------------------------------------------ */
/* model exchange and co-simulation steps */

/* Model exchange: compare the completed integrator step with the previous one (fmu_instance.c:
 * the time losing precision); FMU_OK or FMU_WARNING. */
fmu_status_t fmu_completed_integrator_step(fmu_instance_t *inst, const char *function);
fmu_status_t fmu_set_time(fmu_instance_t *inst, const char *function, double time);
fmu_status_t fmu_set_continuous_states(fmu_instance_t *inst, const char *function,
                                       const double x[], size_t nx);
fmu_status_t fmu_get_derivatives(fmu_instance_t *inst, const char *function, double der[],
                                 size_t nx);
fmu_status_t fmu_get_event_indicators(fmu_instance_t *inst, const char *function, double z[],
                                      size_t ni);
fmu_status_t fmu_get_continuous_states(fmu_instance_t *inst, const char *function, double x[],
                                       size_t nx);
fmu_status_t fmu_get_nominals(fmu_instance_t *inst, const char *function, double nominal[],
                              size_t nx);

/* A communication step's arguments against the FMU's time: FMU_OK, FMU_WARNING (precision lost,
 * logged once) or FMU_ERROR (refused, nothing changed); *t_end = t + h. */
fmu_status_t fmu_check_step(fmu_instance_t *inst, const char *function, double t, double h,
                            double *t_end);

/* ------------------------------------------------------------------------------------------ */
/* FMU state */

fmu_status_t fmu_state_get(fmu_instance_t *inst, const char *function, void **state);
fmu_status_t fmu_state_set(fmu_instance_t *inst, const char *function, void *state);
fmu_status_t fmu_state_free(fmu_instance_t *inst, const char *function, void **state);
fmu_status_t fmu_state_size(fmu_instance_t *inst, const char *function, void *state,
                            size_t *size);
fmu_status_t fmu_state_serialize(fmu_instance_t *inst, const char *function, void *state,
                                 unsigned char bytes[], size_t size);
fmu_status_t fmu_state_deserialize(fmu_instance_t *inst, const char *function,
                                   const unsigned char bytes[], size_t size, void **state);

/* ------------------------------------------------------------------------------------------ */
/* what the instance's files share */

/* Free the FMU states the instance owns (fmu_state.c). */
void fmu_states_free_all(fmu_instance_t *inst);

/* The relative resolution of a time step below which precision lost to the double time is
 * reported (fmi2DoStep, fmi2CompletedIntegratorStep): the integration tolerance, but not finer
 * than one part in a million (a step of 1e-7 s at t = 5 s is resolved to 1e-8 relative, which
 * no result here notices, and a warning there would be noise). */
static inline double fmu_time_resolution(const fmu_instance_t *inst)
{
    return inst->tolerance > 1e-6 ? inst->tolerance : 1e-6;
}

/* ------------------------------------------------------------------------------------------ */
/* the model's time, continuous states and derivative cache */

static inline double *fmu_time(fmu_instance_t *inst)
{
    return (double *)((char *)inst->model + fmu_model.time_offset);
}
static inline double *fmu_states(fmu_instance_t *inst)
{
    return (double *)((char *)inst->model + fmu_model.x_offset);
}
static inline double *fmu_derivatives(fmu_instance_t *inst)
{
    return (double *)((char *)inst->model + fmu_model.der_offset);
}

/* Invalidate the output and derivative caches after the state, inputs or time changed. */
static inline void fmu_invalidate(fmu_instance_t *inst)
{
    inst->outputs_valid = 0;
    inst->derivatives_valid = 0;
}

/* Bring the model's analysis of the co-simulation steps up to date (the stepper's flush): before
 * the outputs are computed, values are set or an FMU state is taken. */
static inline void fmu_flush(fmu_instance_t *inst)
{
    if (inst->stepper != NULL) {
        inst->stepper->flush(inst);
    }
}

/* Model exchange: the time and states the next completed integrator step is compared with
 * (fmu_me.c): set at the end of initialization, at every completed step and when an FMU state
 * is restored. */
static inline void fmu_step_reference(fmu_instance_t *inst)
{
    inst->last_step_time = *fmu_time(inst);
    if (fmu_model.n_states > 0) {
        memcpy(inst->last_step_x, fmu_states(inst), (size_t)fmu_model.n_states * sizeof(double));
    }
    inst->last_step_valid = 1;
}

CSFH_INTERNAL_END

#endif
