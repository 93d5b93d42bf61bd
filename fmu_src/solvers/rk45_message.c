/* The messages of the explicit Runge-Kutta 5(4) (rk45.h): the last failure's text and the
 * flags' names, shared by its files so that none of them depends on the stepping. */
#include <stdarg.h>
#include <stdio.h>

#include "rk45_internal.h"

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3), cold))
#endif
void rk45_set_message(rk45_t *r, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(r->message, sizeof r->message, fmt, args);
    va_end(args);
}

const char *rk45_message(const rk45_t *r)
{
    return r->message;
}

const char *rk45_flag_name(int flag)
{
    switch (flag) {
    case RK45_SUCCESS:
        return "RK45_SUCCESS";
    case RK45_ROOT:
        return "RK45_ROOT";
    case RK45_MEM_FAIL:
        return "RK45_MEM_FAIL";
    case RK45_ILL_INPUT:
        return "RK45_ILL_INPUT";
    case RK45_ERR_FAILURE:
        return "RK45_ERR_FAILURE";
    case RK45_RHS_FAILURE:
        return "RK45_RHS_FAILURE";
    case RK45_ROOT_FAILURE:
        return "RK45_ROOT_FAILURE";
    case RK45_TOO_SMALL:
        return "RK45_TOO_SMALL";
    default:
        return "an unknown flag";
    }
}
