/* The co-simulation stepper (cosimulation.c): what the FMI front-ends (fmi2_glue.c,
 * fmi3_glue.c) call. It works on the FMI-independent instance (fmu_instance.h) and never calls
 * the front-ends; the instance reaches it only through the hooks of cs_stepper. */
#ifndef CSFH_COSIMULATION_H
#define CSFH_COSIMULATION_H

#include "csfh_visibility.h"
#include "fmu_instance.h"

CSFH_INTERNAL_BEGIN

/* The hooks the front-end gives every instance it makes (fmu_instance_t.stepper). */
extern const fmu_stepper_t cs_stepper;

void cs_free(fmu_instance_t *inst);
/* Integrate from the FMU's time to t_end (> the FMU's time; the caller checked the arguments).
 * stop_at_event: return at the first event inside the step that switches the discrete state
 * (csfh: a contact onset or release), handled, with the FMU's time = the event time and
 * *stopped = 1 (FMI 3.0 early return); else the step goes to t_end, however many events it
 * holds (*stopped = 0; stopped may be NULL). */
fmu_status_t cs_do_step(fmu_instance_t *inst, double t_end, int stop_at_event, int *stopped);
/* fmi2Reset, fmi3Reset: the next step starts the integration as in a new instance, in the
 * memory of the last run (what a re-initialisation cannot make as new is freed). */
void cs_reset(fmu_instance_t *inst);
/* Hand the kept steps of the communication step to the model (fmu_model.analyse_step: the
 * steps of RK45 are analysed only when needed): before the outputs are computed, an FMU state is
 * taken or values are set. Nothing without co-simulation. */
void cs_flush(fmu_instance_t *inst);

CSFH_INTERNAL_END

#endif
