/* The FMU instance's data, whatever the FMI version: statuses, states, interfaces, the instance
 * itself and its inline accessors (the model's time, states and derivatives; the caches). The
 * functions on it are declared by the files of the FMU layer: fmu_instance.h lists them. */
#ifndef CSFH_FMU_TYPES_H
#define CSFH_FMU_TYPES_H

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
    /* the instance is reset: the next step starts as in a new instance (the memory may stay) */
    void (*reset)(fmu_instance_t *inst);
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
    int outputs_valid;      /* model.out matches the current state/inputs: FMU_OUTPUTS_* */
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

enum {
    FMU_REFRESH_NONE,
    FMU_REFRESH_PREPARE,
    FMU_REFRESH_DERIVATIVES,
    FMU_REFRESH_OUTPUTS,
    FMU_REFRESH_SUBSET /* an output of fmu_model.subset_outputs */
};

/* How much of model.out is up to date (outputs_valid): nothing, the model's subset, all. */
enum { FMU_OUTPUTS_NONE, FMU_OUTPUTS_SUBSET, FMU_OUTPUTS_ALL };

/* ------------------------------------------------------------------------------------------ */
/* the instance's inline helpers */

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
