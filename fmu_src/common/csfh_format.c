/* Numbers in messages (csfh_format.h). */
#include "csfh_format.h"

#include <stdio.h>
#include <stdlib.h>

const char *csfh_format_value(char buf[32], double value)
{
    for (int precision = 6; precision <= 17; precision++) {
        snprintf(buf, 32, "%.*g", precision, value);
        if (strtod(buf, NULL) == value) {
            break;
        }
    }
    return buf;
}
