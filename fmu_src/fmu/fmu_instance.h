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
 * fmu_step.c (the communication step's check). The instance's data is fmu_types.h; fmu_log.h
 * and fmu_state.h declare the functions of their files, this header the rest and includes them. */
#ifndef CSFH_FMU_INSTANCE_H
#define CSFH_FMU_INSTANCE_H

#include <float.h>
#include <stddef.h>

#include "csfh_visibility.h"
#include "fmu_log.h"
#include "fmu_state.h"
#include "fmu_types.h"

CSFH_INTERNAL_BEGIN

/* ------------------------------------------------------------------------------------------ */
/* life cycle */

/* A new instance (state Instantiated, start values set), or NULL when out of memory. */
fmu_instance_t *fmu_instance_new(const char *instance_name, fmu_kind_t type, int fmi_version,
                                 int logging_on);
void fmu_instance_free(fmu_instance_t *inst);
/* Back to Instantiated with the start values (fmi2Reset, fmi3Reset). */
void fmu_instance_reset(fmu_instance_t *inst);

/* ------------------------------------------------------------------------------------------ */
/* model helpers */

/* Validate the parameters and compute derived quantities once (logged on failure). */
fmu_status_t fmu_prepare(fmu_instance_t *inst, const char *function);
fmu_status_t fmu_update_derivatives(fmu_instance_t *inst, const char *function);
/* Outputs at the current state; logs a model warning once per instance. FMU_OK, FMU_WARNING or
 * FMU_ERROR (logged, prefixed with `function`). */
fmu_status_t fmu_update_outputs(fmu_instance_t *inst, const char *function);
/* Only fmu_model.subset_outputs (at least: all outputs that are up to date stay so). */
fmu_status_t fmu_update_output_subset(fmu_instance_t *inst, const char *function);
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

CSFH_INTERNAL_END

#endif
