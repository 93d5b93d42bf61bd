/* csfh's stand-in for SUNDIALS' private cvode_ls_impl.h in the FMU's sources/: the same as
 * cvode_impl.h beside it, for the internal functions of CVODE's linear solver interface
 * (cvLsSetup, cvLsDQJac, ...). */
#ifndef CSFH_HIDDEN_CVODE_LS_IMPL_H
#define CSFH_HIDDEN_CVODE_LS_IMPL_H

#include <cvode/cvode_ls.h>

#include "csfh_visibility.h"
#include "cvode_impl.h"

CSFH_INTERNAL_BEGIN
#include "sundials_private/cvode_ls_impl.h"
CSFH_INTERNAL_END

#endif
