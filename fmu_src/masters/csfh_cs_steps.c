/* The communication loop of one run in C (csfh_cs_batch.h: csfh_cs_steps). */
#include <stdbool.h>
#include <string.h>

#include "csfh_cs_batch.h"
#include "fmi2FunctionTypes.h"

/* the loop's functions, converted from object pointers as dlsym's results are */
typedef struct {
    fmi2DoStepTYPE *do_step;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2GetBooleanTYPE *get_boolean;
} steps_calls_t;

/* a group of outputs is usable when it is empty or has its function, references and rows */
static bool group_ok(size_t n, const void *get, const void *vr, const void *rows)
{
    return n == 0 || (get != NULL && vr != NULL && rows != NULL);
}

static bool arguments_ok(const csfh_cs_steps_t *loop, long long k_first, long long k_last,
                         const double *times, const double *reals, const int *integers,
                         const int *booleans)
{
    return loop != NULL && loop->do_step != NULL && loop->component != NULL && times != NULL &&
           k_first >= 0 && k_last >= k_first &&
           group_ok(loop->n_real, loop->get_real, loop->real_vr, reals) &&
           group_ok(loop->n_integer, loop->get_integer, loop->integer_vr, integers) &&
           group_ok(loop->n_boolean, loop->get_boolean, loop->boolean_vr, booleans);
}

static steps_calls_t steps_calls(const csfh_cs_steps_t *loop)
{
    steps_calls_t calls = {0};
    memcpy(&calls.do_step, &loop->do_step, sizeof(calls.do_step));
    if (loop->n_real > 0) {
        memcpy(&calls.get_real, &loop->get_real, sizeof(calls.get_real));
    }
    if (loop->n_integer > 0) {
        memcpy(&calls.get_integer, &loop->get_integer, sizeof(calls.get_integer));
    }
    if (loop->n_boolean > 0) {
        memcpy(&calls.get_boolean, &loop->get_boolean, sizeof(calls.get_boolean));
    }
    return calls;
}

/* Reads one row of outputs; returns the failing call (CSFH_STEPS_NONE when all succeed) and
 * its status in *s. */
static int read_row(const csfh_cs_steps_t *loop, const steps_calls_t *calls, size_t row,
                    double *reals, int *integers, int *booleans, fmi2Status *s)
{
    fmi2Component c = loop->component;
    const size_t nr = loop->n_real, ni = loop->n_integer, nb = loop->n_boolean;
    if (nr > 0 && (*s = calls->get_real(c, loop->real_vr, nr, reals + row * nr)) > fmi2Warning) {
        return CSFH_STEPS_GET_REAL;
    }
    if (ni > 0 && (*s = calls->get_integer(c, loop->integer_vr, ni, integers + row * ni)) >
                      fmi2Warning) {
        return CSFH_STEPS_GET_INTEGER;
    }
    if (nb > 0 && (*s = calls->get_boolean(c, loop->boolean_vr, nb, booleans + row * nb)) >
                      fmi2Warning) {
        return CSFH_STEPS_GET_BOOLEAN;
    }
    return CSFH_STEPS_NONE;
}

long long csfh_cs_steps(const csfh_cs_steps_t *loop, long long k_first, long long k_last, double t,
                        double *times, double *reals, int *integers, int *booleans, int *failure)
{
    if (failure == NULL) {
        return -1;
    }
    failure[0] = CSFH_STEPS_NONE;
    failure[1] = fmi2OK;
    if (!arguments_ok(loop, k_first, k_last, times, reals, integers, booleans)) {
        return -1;
    }
    const steps_calls_t calls = steps_calls(loop);
    for (long long k = k_first; k < k_last; k++) {
        const size_t row = (size_t)(k - k_first);
        /* the times of simulate_cs's Python loop, bitwise: min((k + 1) h, t_end), steps
         * t_next - t */
        const double t_grid = (double)(k + 1) * loop->step;
        const double t_next = t_grid <= loop->stop_time ? t_grid : loop->stop_time;
        fmi2Status s = calls.do_step(loop->component, t, t_next - t, fmi2True);
        int call = s > fmi2Warning ? CSFH_STEPS_DO_STEP : CSFH_STEPS_NONE;
        if (call == CSFH_STEPS_NONE) {
            t = t_next;
            times[row] = t;
            call = read_row(loop, &calls, row, reals, integers, booleans, &s);
        }
        if (call != CSFH_STEPS_NONE) {
            failure[0] = call;
            failure[1] = (int)s;
            return (long long)row;
        }
    }
    return k_last - k_first;
}
