/* Helpers on one entry of a generated variable table (csfh_vartable.h). Model-independent: the
 * csfh core and any other model built with the same generator (the comb-drive actuator) use them
 * to validate values and write the messages the FMI glue logs. */
#include "csfh_vartable.h"

#include <math.h>
#include <stdio.h>

int csfh_check_value(const csfh_variable_t *v, double value, char *msg, size_t msg_size)
{
    if (!isfinite(value)) {
        snprintf(msg, msg_size, "%s = %g is not finite", v->name, value);
        return -1;
    }
    if (!v->has_range) {
        return 0;
    }
    const int below = v->lo_open ? !(value > v->lo) : !(value >= v->lo);
    const int above = v->hi_open ? !(value < v->hi) : !(value <= v->hi);
    if (below || above) {
        if (v->type == CSFH_TYPE_ENUMERATION) {
            /* %.0f: an FMI 3.0 Int64 value may be far outside an int */
            snprintf(msg, msg_size, "%s = %.0f is not a valid enumeration value (%g..%g)",
                     v->name, value, v->lo, v->hi);
        } else if (v->type == CSFH_TYPE_BOOLEAN) {
            snprintf(msg, msg_size, "%s = %d is not a Boolean (0 or 1)", v->name, (int)value);
        } else {
            char b1[32], b2[32], b3[32];
            snprintf(msg, msg_size, "%s = %s is out of range %c%s, %s%c", v->name,
                     csfh_format_value(b1, value), v->lo_open ? '(' : '[',
                     csfh_format_value(b2, v->lo), csfh_format_value(b3, v->hi),
                     v->hi_open ? ')' : ']');
        }
        return -1;
    }
    return 0;
}
