/* The FMU instance shared by the generic FMI glue (fmi2_glue.c) and the co-simulation stepper
 * (cosimulation.c). The model itself is behind the interface of fmu_model.h. */
#ifndef CSFH_FMU_INSTANCE_H
#define CSFH_FMU_INSTANCE_H

#include "fmi2Functions.h"

#include "fmu_model.h"

/* FMI 2.0 instance states (bit mask, one check per call). */
typedef enum {
    FMU_INSTANTIATED = 1 << 0,
    FMU_INITIALIZATION = 1 << 1,
    FMU_EVENT = 1 << 2,      /* ME */
    FMU_CONTINUOUS = 1 << 3, /* ME */
    FMU_STEP_COMPLETE = 1 << 4, /* CS */
    FMU_STEP_FAILED = 1 << 5,   /* CS */
    FMU_TERMINATED = 1 << 6,
    FMU_ERROR = 1 << 7
} fmu_state_t;

/* Log categories of modelDescription.xml. */
enum {
    LOG_EVENTS = 1 << 0,
    LOG_STATUS_WARNING = 1 << 1,
    LOG_STATUS_ERROR = 1 << 2,
    LOG_ALL = 1 << 3
};

typedef struct csfh_cvode csfh_cvode_t; /* opaque, cosimulation.c */

/* Relative tolerance of the co-simulation integrator when fmi2SetupExperiment defines none (also
 * the DefaultExperiment tolerance of modelDescription.xml). */
#define FMU_DEFAULT_TOLERANCE 1e-6

typedef struct {
    void *model;            /* the model struct, fmu_model.size bytes */
    fmi2Type type;
    char *instance_name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
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
    csfh_cvode_t *cvode;
    int cvode_needs_reinit; /* restart CVODE: states, inputs or tunable parameters were changed
                               from outside, an FMU state was taken or restored */
    /* FMU states made by this instance (fmi2GetFMUstate, fmi2DeSerializeFMUstate) and not yet
     * freed by fmi2FreeFMUstate: only these are accepted, fmi2FreeInstance frees the rest */
    void **fmu_states;
    size_t n_fmu_states, cap_fmu_states;
    /* time resolution: the warning that the double time does not resolve the steps was logged;
     * model exchange: time and states at the last fmi2CompletedIntegratorStep (last_step_x:
     * n_states doubles) */
    int warned_time;
    int last_step_valid;
    double last_step_time;
    double *last_step_x;
    /* value reference -> index in fmu_model.variables (-1: none), n_vr_index entries: get and
     * set find a variable in constant time (a linear search cost 0.5 us per value) */
    int *vr_index;
    unsigned int n_vr_index;
} fmu_instance_t;

void fmu_log(fmu_instance_t *inst, fmi2Status status, unsigned int category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Invalidate the output and derivative caches after the state, inputs or time changed. */
void fmu_invalidate(fmu_instance_t *inst);

/* Discrete-state update at an event, with logging; returns fmu_model.event_update's value. */
int fmu_event_update(fmu_instance_t *inst);

/* Outputs at the current state; logs a model warning once per instance. fmi2OK, fmi2Warning or
 * fmi2Error (logged, prefixed with `function`). */
fmi2Status fmu_update_outputs(fmu_instance_t *inst, const char *function);

/* The model's time, continuous states and derivative cache. */
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

/* Co-simulation (cosimulation.c). */
void cs_free(fmu_instance_t *inst);
/* Integrate from the FMU's time to t_end (> the FMU's time; fmi2DoStep checked the arguments). */
fmi2Status cs_do_step(fmu_instance_t *inst, double t_end);
fmi2Status cs_reset(fmu_instance_t *inst);
/* Bring the peak outputs of the communication step up to date (the co-simulation stepper
 * analyses RK45's steps for them only when needed): before the outputs are computed, an FMU
 * state is taken or values are set. Nothing without co-simulation. */
void cs_peaks_flush(fmu_instance_t *inst);

#endif
