/* The FMU's log and the one check of every call against the state machine (fmu_log.c). */
#ifndef CSFH_FMU_LOG_H
#define CSFH_FMU_LOG_H

#include <stddef.h>

#include "fmu_types.h"

CSFH_INTERNAL_BEGIN

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

CSFH_INTERNAL_END

#endif
