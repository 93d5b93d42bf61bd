/* The csfh FMU's model struct: everything its variable table addresses (the generated
 * csfh_variables[]; modelDescription/variables.toml `field`, relative to this struct). The
 * physics (../../physics/csfh_model.h) is one member; around it what only the FMU has: the
 * derivative cache and the outputs that fmi2GetReal reads, the co-simulation method, the Integer
 * twins of the Enumeration parameters (for importers that ignore Enumerations: libcosim), the
 * running peaks of a communication step and the integrator's step counter.
 *
 * The harness's core library (../../harness/csfh_api.c) uses the same struct: it addresses the
 * variables by the same names, through the same table. */
#ifndef CSFH_FMU_H
#define CSFH_FMU_H

#include <stddef.h>

#include "csfh_model.h"
#include "csfh_vartable.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* The running peaks of co-simulation (contact.F_N_peak, ...; csfh_model.h: CSFH_N_PEAKS). */
typedef struct {
    int active;               /* 1 after the first communication step */
    double v[CSFH_N_PEAKS];   /* F_N, |F_T|, indentation, flexure stress so far in this step */
} csfh_peaks_t;

typedef struct {
    csfh_model_t m;       /* the physics: time, states, inputs, parameters, discrete state */
    double der[6];        /* the derivatives at the current state (read by get) */
    csfh_outputs_t out;   /* the outputs at the current state */
    csfh_peaks_t peaks;
    int cs_method;        /* solver.method (SolverMethod): the co-simulation integrator */
    /* 0, or the value the Enumeration takes (solver.method, contact.law, contact.esdu_reading) */
    int cs_method_number, law_number, esdu_reading_number;
    int integrator_steps; /* co-simulation: integrator steps (saturates at INT_MAX) */
    int cs_analytic_jacobian; /* solver.analytic_jacobian: BDF's Newton matrix analytic */
    int jacobian_evaluations; /* co-simulation: Jacobians formed (saturates at INT_MAX) */
} csfh_fmu_t;

/* Start values of every variable (the `paper` preset) from the generated table. */
void csfh_fmu_set_defaults(csfh_fmu_t *f);
/* The physics alone with those start values (for the physics' and the solvers' own users). */
void csfh_fmu_model_defaults(csfh_model_t *m);

/* The variable of that name (NULL: none), and where its value is. */
const csfh_variable_t *csfh_fmu_variable(const char *name);
double *csfh_fmu_real(csfh_fmu_t *f, const csfh_variable_t *v);
int *csfh_fmu_int(csfh_fmu_t *f, const csfh_variable_t *v);

/* Validate every parameter, state and input (the table's ranges and finiteness), take the
 * Integer twins of the Enumerations that are set, then the physics' cross-checks and derived
 * quantities (csfh_model_prepare). 0, or -1 with a message naming the variable and its value
 * (the derived quantities are then left unchanged). */
int csfh_fmu_prepare(csfh_fmu_t *f, char *msg, size_t msg_size);

/* f->out at the current state, the peak outputs with the running peaks of the communication
 * step where there are any: CSFH_OK or CSFH_WARN_ESDU_CLAMPED. */
int csfh_fmu_outputs(csfh_fmu_t *f);
/* Of f->out only the loads (csfh_model_load_outputs), as csfh_fmu_outputs gives them. */
int csfh_fmu_load_outputs(csfh_fmu_t *f);

CSFH_INTERNAL_END

#endif
