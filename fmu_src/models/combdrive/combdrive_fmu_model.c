/* The comb-drive actuator behind the generic FMU layer (../../fmu/fmu_model.h): no continuous
 * states, no events; the outputs follow the inputs (direct feedthrough). */
#include <stdio.h>

#include "combdrive_constants.h"
#include "combdrive_model.h"
#include "combdrive_variables.h"
#include "fmu_model.h"

static void set_defaults(void *m)
{
    combdrive_set_defaults((combdrive_model_t *)m);
}

static int prepare(void *m, char *msg, size_t msg_size)
{
    return combdrive_prepare((combdrive_model_t *)m, msg, msg_size);
}

static void init_discrete(void *m, char *msg, size_t msg_size)
{
    (void)m;
    if (msg_size > 0) {
        msg[0] = '\0';
    }
}

static int outputs(void *m, char *msg, size_t msg_size)
{
    return combdrive_outputs((combdrive_model_t *)m, msg, msg_size) == 0 ? FMU_MODEL_OK
                                                                        : FMU_MODEL_NONFINITE;
}

const fmu_model_t fmu_model = {
    .guid = COMBDRIVE_GUID,
    .model_identifier = COMBDRIVE_MODEL_IDENTIFIER,
    .n_states = COMBDRIVE_NUMBER_OF_STATES,
    .n_event_indicators = COMBDRIVE_NUMBER_OF_EVENT_INDICATORS,
    .n_variables = COMBDRIVE_NUMBER_OF_VARIABLES,
    .variables = combdrive_variables,
    .default_tolerance = COMBDRIVE_DEFAULT_TOLERANCE,
    .size = sizeof(combdrive_model_t),
    .time_offset = offsetof(combdrive_model_t, time),
    .x_offset = offsetof(combdrive_model_t, time), /* no states */
    .der_offset = offsetof(combdrive_model_t, time),
    .set_defaults = set_defaults,
    .prepare = prepare,
    .init_discrete = init_discrete,
    .derivatives = NULL,
    .event_indicators = NULL,
    .event_update = NULL,
    .outputs = outputs,
    .add_integrator_steps = NULL,
    .cs_method = NULL,
    .check_state = NULL, /* every field is a table variable or recomputed (d, out) */
};
