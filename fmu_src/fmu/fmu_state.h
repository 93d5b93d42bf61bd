/* The FMU state: snapshot, validation on restore, serialization (fmu_state.c). */
#ifndef CSFH_FMU_STATE_H
#define CSFH_FMU_STATE_H

#include <stddef.h>

#include "fmu_types.h"

CSFH_INTERNAL_BEGIN

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

/* Free the FMU states the instance owns (at fmu_instance_free). */
void fmu_states_free_all(fmu_instance_t *inst);

CSFH_INTERNAL_END

#endif
