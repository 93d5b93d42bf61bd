/* The communication loop of one run in C (csfh_cs_batch.h: csfh_cs_steps). */
#include <string.h>

#include "csfh_cs_batch.h"
#include "fmi2FunctionTypes.h"

long long csfh_cs_steps(const csfh_cs_steps_t *loop, long long k_first, long long k_last, double t,
                        double *times, double *reals, int *integers, int *booleans, int *failure)
{
    if (failure == NULL) {
        return -1;
    }
    failure[0] = CSFH_STEPS_NONE;
    failure[1] = fmi2OK;
    if (loop == NULL || loop->do_step == NULL || loop->component == NULL || times == NULL ||
        k_first < 0 || k_last < k_first ||
        (loop->n_real > 0 && (loop->get_real == NULL || loop->real_vr == NULL || reals == NULL)) ||
        (loop->n_integer > 0 &&
         (loop->get_integer == NULL || loop->integer_vr == NULL || integers == NULL)) ||
        (loop->n_boolean > 0 &&
         (loop->get_boolean == NULL || loop->boolean_vr == NULL || booleans == NULL))) {
        return -1;
    }
    /* object to function pointers, as dlsym's results are converted */
    fmi2DoStepTYPE *do_step;
    fmi2GetRealTYPE *get_real = NULL;
    fmi2GetIntegerTYPE *get_integer = NULL;
    fmi2GetBooleanTYPE *get_boolean = NULL;
    memcpy(&do_step, &loop->do_step, sizeof(do_step));
    if (loop->n_real > 0) {
        memcpy(&get_real, &loop->get_real, sizeof(get_real));
    }
    if (loop->n_integer > 0) {
        memcpy(&get_integer, &loop->get_integer, sizeof(get_integer));
    }
    if (loop->n_boolean > 0) {
        memcpy(&get_boolean, &loop->get_boolean, sizeof(get_boolean));
    }
    fmi2Component c = loop->component;
    const size_t nr = loop->n_real, ni = loop->n_integer, nb = loop->n_boolean;
    for (long long k = k_first; k < k_last; k++) {
        const size_t row = (size_t)(k - k_first);
        /* the times of simulate_cs's Python loop, bitwise: min((k + 1) h, t_end), steps
         * t_next - t */
        const double t_grid = (double)(k + 1) * loop->step;
        const double t_next = t_grid <= loop->stop_time ? t_grid : loop->stop_time;
        fmi2Status s = do_step(c, t, t_next - t, fmi2True);
        if (s > fmi2Warning) {
            failure[0] = CSFH_STEPS_DO_STEP;
            failure[1] = (int)s;
            return (long long)row;
        }
        t = t_next;
        times[row] = t;
        int call = CSFH_STEPS_NONE;
        if (nr > 0 && (s = get_real(c, loop->real_vr, nr, reals + row * nr)) > fmi2Warning) {
            call = CSFH_STEPS_GET_REAL;
        } else if (ni > 0 && (s = get_integer(c, loop->integer_vr, ni, integers + row * ni)) >
                                 fmi2Warning) {
            call = CSFH_STEPS_GET_INTEGER;
        } else if (nb > 0 && (s = get_boolean(c, loop->boolean_vr, nb, booleans + row * nb)) >
                                 fmi2Warning) {
            call = CSFH_STEPS_GET_BOOLEAN;
        }
        if (call != CSFH_STEPS_NONE) {
            failure[0] = call;
            failure[1] = (int)s;
            return (long long)row;
        }
    }
    return k_last - k_first;
}
