/* csfh's stand-in for SUNDIALS' private cvode_impl.h in the FMU's sources/ (written for this
 * project, see cmake/fmu.cmake): SUNDIALS declares CVODE's internal functions (cvEwtSet,
 * cvProcessError, ...) without an export macro, so an importer compiling sources/ without
 * -fvisibility=hidden would export them from the FMU binary. The CVODE sources include
 * "cvode_impl.h" and get this header, which includes SUNDIALS' own (sources/sundials_private/)
 * with its declarations hidden. What that header includes comes first, outside the hidden region
 * (csfh_visibility.h says why). Our own builds compile the SUNDIALS tree as it is. */
#ifndef CSFH_HIDDEN_CVODE_IMPL_H
#define CSFH_HIDDEN_CVODE_IMPL_H

#include <stdarg.h>

#include <cvode/cvode.h>
#include <sundials/sundials_math.h>

#include "csfh_visibility.h"
#include "cvode_proj_impl.h"
#include "sundials_context_impl.h"
#include "sundials_logger_impl.h"

CSFH_INTERNAL_BEGIN
#include "sundials_private/cvode_impl.h"
CSFH_INTERNAL_END

#endif
