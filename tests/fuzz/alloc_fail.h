/* The failed-allocation test (alloc_fail.c): what a scenario (alloc_fmi2.c, alloc_fmi3.c) asks of
 * the driver. The scenario makes a fixed sequence of FMI calls on one FMU; the driver runs it
 * once to count the allocations, then once more for every allocation with that one failing, and
 * judges every call through these functions. */
#ifndef CSFH_ALLOC_FAIL_H
#define CSFH_ALLOC_FAIL_H

#include <stddef.h>

#include "fmu_model.h"

/* the FMI statuses of both versions (fmi2Status, fmi3Status) */
enum { ALLOC_OK = 0, ALLOC_WARNING = 1, ALLOC_DISCARD = 2, ALLOC_ERROR = 3 };

/* The scenario's parts (one file per FMI version), on an instance each: co-simulation with the
 * method `method` (its SolverMethod value, 0: the FMU has none; `name` for messages), and model
 * exchange. Every call through ALLOC_CALL, every value read through alloc_values, every instance
 * made through ALLOC_INSTANCE. */
void alloc_co_simulation(const char *name, int method);
void alloc_model_exchange(void);

/* Before a call: its allocations and errors start here (the macros below). */
void alloc_call_begin(void);
/* After the call `name`: its status must be OK, Warning, Discard or Error, and an Error must
 * have been logged; returns the status. */
int alloc_call_end(const char *name, int status);
/* An instance made (made != 0), or NULL: then an error must have been logged. */
int alloc_instance_end(const char *name, int made);
#define ALLOC_CALL(name, expr) (alloc_call_begin(), alloc_call_end((name), (int)(expr)))
#define ALLOC_INSTANCE(name, c, expr)                                                          \
    (alloc_call_begin(), (c) = (expr), alloc_instance_end((name), (c) != NULL))

/* The FMU's logger: one message of `status` (errors are counted). */
void alloc_logged(int status, const char *category, const char *message);
/* Values read by the call `name` with `status`: finite unless the call failed; they go into the
 * run's digest (a run whose calls all succeeded must give the reference's). */
void alloc_values(const char *name, int status, const double *x, size_t n);

/* The driver's own memory (never counted, never failed). */
void *alloc_own(size_t size);
void alloc_own_free(void *p);

/* Variable `name` of the FMU (NULL: it has none). */
const csfh_variable_t *alloc_variable(const char *name);
/* The value references of every Real variable (read after each step), *n of them. */
const unsigned int *alloc_reals(size_t *n);

#endif
