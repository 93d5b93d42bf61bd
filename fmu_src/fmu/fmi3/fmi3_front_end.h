/* What the files of the FMI 3.0 front-end share (fmi3_glue.c, fmi3_unsupported.c): the
 * standard's header, the state table, and the casts between its types and the instance's. */
#ifndef CSFH_FMI3_FRONT_END_H
#define CSFH_FMI3_FRONT_END_H

/* the standard's header declares two callback types without a prototype (`()`) */
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#endif
#include "fmi3Functions.h"
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "fmi3_states.h"
#include "fmu_instance.h"

#define INST(c) ((fmu_instance_t *)(c))
#define ST(s) ((fmi3Status)(s))
#define LOG_ERROR FMU_LOG_ERROR

#endif
