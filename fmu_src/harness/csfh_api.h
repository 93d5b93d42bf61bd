/* The core library's public C API (libcsfh_core.so), used by the Python harness through ctypes.
 * Parameters are addressed by their FMI variable names (modelDescription/variables.toml), so the
 * harness and the FMU share one vocabulary and one set of physics functions: a handle is the
 * csfh FMU's model struct (../models/csfh/csfh_fmu.h), the solvers run on its physics. */
#ifndef CSFH_API_H
#define CSFH_API_H

#include <stddef.h>

#include "csfh_fmu.h"
#include "csfh_moreau.h"
#include "csfh_rk4event.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

#if defined(_WIN32)
#define CSFH_API __declspec(dllexport)
#elif defined(__GNUC__)
#define CSFH_API __attribute__((visibility("default")))
#else
#define CSFH_API
#endif

CSFH_API int csfh_api_abi_version(void);
CSFH_API size_t csfh_api_model_size(void);

/* A model with the start values of modelDescription (the `paper` preset). */
CSFH_API csfh_fmu_t *csfh_api_new(void);
CSFH_API void csfh_api_free(csfh_fmu_t *model);
CSFH_API csfh_fmu_t *csfh_api_clone(const csfh_fmu_t *model);

/* Set by name (with the FMU's range check); returns 0, or -1 with a message naming the variable
 * and the value, or -2 for an unknown name. */
CSFH_API int csfh_api_set(csfh_fmu_t *model, const char *name, double value, char *msg,
                          size_t msg_size);
/* Get by name (computed outputs are refreshed); returns 0 or -2 for an unknown name. */
CSFH_API int csfh_api_get(csfh_fmu_t *model, const char *name, double *value);

/* Validate all parameters and compute derived quantities; then set the discrete contact state
 * from the current state. Returns 0 or -1 with a message. */
CSFH_API int csfh_api_prepare(csfh_fmu_t *model, char *msg, size_t msg_size);

CSFH_API void csfh_api_set_state(csfh_fmu_t *model, const double x[6]);
CSFH_API void csfh_api_get_state(const csfh_fmu_t *model, double x[6]);
CSFH_API void csfh_api_set_inputs(csfh_fmu_t *model, const double u[3]);

/* f(t, x) at the model's time t = model->m.time (the shock pulse) with its current discrete state and
 * inputs; returns csfh_model_derivatives'. */
CSFH_API int csfh_api_derivatives(csfh_fmu_t *model, const double x[6], double xdot[6]);
/* Smooth generalized forces (gravity + inputs + base acceleration + flexure) at q and model->m.time. */
CSFH_API void csfh_api_smooth_forces(csfh_fmu_t *model, const double q[3], double Q[3]);
CSFH_API double csfh_api_event_indicator(const csfh_fmu_t *model, const double x[6]);
CSFH_API int csfh_api_event_update(csfh_fmu_t *model);

/* Counters: rhs, flexure, contact, friction, steps. */
CSFH_API void csfh_api_counters(const csfh_fmu_t *model, long long out[5]);

/* Moreau (csfh_moreau.h). */
CSFH_API int csfh_api_moreau_run(csfh_fmu_t *model, double h, int stick_rule, double v_eps,
                                 double v_stick, double g_tol, double t0, const double x0[6],
                                 long long n_steps, long long record_every, double *records,
                                 size_t max_records, double *impacts, size_t max_impacts,
                                 double x_end[6], long long stats[9]);
CSFH_API int csfh_api_moreau_record_columns(void);
CSFH_API int csfh_api_moreau_impact_columns(void);
/* Batched Moreau runs (csfh_moreau_batch.h: csfh_moreau_batch) of n handles. */
CSFH_API long long csfh_api_moreau_batch(csfh_fmu_t *const *handles, size_t n, double h,
                                         int stick_rule, double v_eps, double v_stick,
                                         double g_tol, double t0, const double *x0,
                                         long long n_steps, long long record_every,
                                         double *records, size_t max_records, double *impacts,
                                         size_t max_impacts, double *x_end, long long *stats,
                                         int *status);

/* The paper's RK4 + bisection event-driven scheme (csfh_rk4event.h). stats: steps, rejected
 * steps, rhs evaluations, records, contacts. */
CSFH_API int csfh_api_rk4_run(csfh_fmu_t *model, double h0, double tol, double h_min, double t0,
                              const double x0[6], double t_end, double dt_out, double *records,
                              size_t max_records, double *contacts, size_t max_contacts,
                              double x_end[6], long long stats[5]);
CSFH_API int csfh_api_rk4_record_columns(void);
CSFH_API int csfh_api_contact_record_columns(void);

CSFH_INTERNAL_END

#endif
