/* Model exchange as the conformance importers drive it, whatever the FMI version: the calls an
 * integrator makes, as one table (import_me.h), filled by each version's loader (fmi2_me.c,
 * fmi3_me.c), and the integrators written once against it (me_cvode.c, me_euler.c). Each
 * executable is one loader with one integrator (CMakeLists.txt). */
#ifndef CSFH_IMPORT_ME_H
#define CSFH_IMPORT_ME_H

#include <stddef.h>

#include "import_common.h"

/* What an event iteration reports. */
typedef struct {
    int values_changed;   /* valuesOfContinuousStatesChanged */
    int nominals_changed; /* nominalsOfContinuousStatesChanged */
    double t_next;        /* the next time event, INFINITY if none */
} imp_event_info_t;

/* The model-exchange calls of one FMU instance. Every function returns 0, or -1 when the FMU
 * answered worse than a warning. */
typedef struct {
    imp_run_t *run; /* options, model description, results (import_common.h) */
    void *fmu;      /* the loader's importer (importer_t, importer3_t) */
    const char *derivatives_call; /* the FMI function's name, for messages */
    const char *completed_call;
    const char *indicators_call;
    /* instantiate, set up, initialise with the start values of the command line (import_common.h);
     * the FMU is then in Event Mode */
    int (*initialize)(void *fmu, double tolerance);
    int (*set_time)(void *fmu, double t);
    int (*set_states)(void *fmu, const double *x, size_t n);
    int (*get_states)(void *fmu, double *x, size_t n);
    int (*get_nominals)(void *fmu, double *nominals, size_t n);
    int (*get_derivatives)(void *fmu, double *dx, size_t n);
    int (*get_event_indicators)(void *fmu, double *z, size_t n);
    int (*completed_integrator_step)(void *fmu, int *enter_event_mode, int *terminate);
    /* Event Mode (entered first unless in_event_mode), discrete updates until none is needed,
     * then Continuous-Time Mode; terminateSimulation counts as a failure */
    int (*event_iteration)(void *fmu, int in_event_mode, imp_event_info_t *info);
    /* the outputs at time t: to the CSV when `write`, into the extremes always */
    int (*record)(void *fmu, double t, int write);
    /* terminate (when completed), free, write the summary; the exit status */
    int (*close)(void *fmu);
} imp_me_t;

/* An integrator: runs the FMU from its start to the stop time; the exit status. */
typedef int imp_me_integrator_t(const imp_me_t *me, const char *program);

/* SUNDIALS CVODE (BDF, root finding on the event indicators): me_cvode.c. */
imp_me_integrator_t imp_me_cvode;
/* Explicit Euler at a fixed step: me_euler.c. */
imp_me_integrator_t imp_me_euler;

#endif
