/* Numbers in messages: every message that names a value (a refused parameter, a start state, a
 * derived quantity) writes it the same way, in the physics, the FMU layer and the models. */
#ifndef CSFH_FORMAT_H
#define CSFH_FORMAT_H

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* Shortest "%g" text that reads back as the same double (0.3, not 0.29999999999999999). */
const char *csfh_format_value(char buf[32], double value);

CSFH_INTERNAL_END

#endif
