/* The FMU instance shared by the FMI glue (fmi2_glue.c) and the co-simulation stepper
 * (cosimulation.c). */
#ifndef CSFH_FMU_INSTANCE_H
#define CSFH_FMU_INSTANCE_H

#include "fmi2Functions.h"

#include "csfh_model.h"

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

typedef struct {
    csfh_model_t model;
    fmi2Type type;
    char *instance_name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    unsigned int log_categories;
    fmu_state_t state;
    int prepared;           /* model.d is valid for the current parameters */
    int outputs_valid;      /* model.out matches the current state/inputs */
    int derivatives_valid;  /* model.der matches the current state/inputs */
    int warned_esdu;        /* the ESDU clamp warning was logged */
    /* experiment */
    double tolerance;       /* relative tolerance of the co-simulation integrator */
    double start_time;
    double stop_time;
    int stop_time_defined;
    /* co-simulation */
    csfh_cvode_t *cvode;
    int cvode_needs_reinit; /* states were changed from outside (set state, restore) */
} fmu_instance_t;

void fmu_log(fmu_instance_t *inst, fmi2Status status, unsigned int category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Invalidate the output and derivative caches after the state, inputs or time changed. */
void fmu_invalidate(fmu_instance_t *inst);

/* Contact mode update at an event, with logging; returns csfh_model_event_update's value. */
int fmu_event_update(fmu_instance_t *inst);

/* Co-simulation (cosimulation.c). */
void cs_free(fmu_instance_t *inst);
fmi2Status cs_do_step(fmu_instance_t *inst, double t, double h);
fmi2Status cs_reset(fmu_instance_t *inst);

#endif
