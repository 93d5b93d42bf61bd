/* The communication step's arguments against the FMU's time (fmu_instance.h: fmu_check_step). */
#include <float.h>
#include <math.h>

#include "fmu_instance.h"

/* Round-off allowed in a master's time arithmetic (fmi2DoStep): a currentCommunicationPoint t
 * is the FMU's time T if |t - T| <= COMM_POINT_ROUNDOFF * max(|t|, |T|), i.e. a few units in the
 * last place (4 to 8 ulp): what t0 + k h against t_(k-1) + h, or integer nanoseconds converted to
 * seconds, give. */
#define COMM_POINT_ROUNDOFF (16.0 * DBL_EPSILON)

/* fmax (the same value, also for a NaN argument), inline: libm's is a call on every step */
static inline double larger(double a, double b)
{
    return (a > b || b != b) ? a : b;
}

/* The step's arguments against the FMU's time T: the communication point t must be T up to
 * round-off (COMM_POINT_ROUNDOFF; a t behind T would take the time backwards, one ahead would
 * skip an interval), the step h finite and >= 0, and the end t + h (computed as the master
 * computes it) finite and, for h > 0, later than T. The FMU integrates from its own time T to
 * t + h, so its time never goes backwards. A refused step is FMU_ERROR and changes nothing.
 * Precision lost: if the double time represents the step T -> t + h worse than the integration
 * tolerance (|(t + h - T) - h| > max(tolerance, 1e-6) h, e.g. h = 1e-3 s at t = 1e10 s, where
 * the resolution is 1.9e-6 s), the step is taken and reported with FMU_WARNING (logged once). */
fmu_status_t fmu_check_step(fmu_instance_t *inst, const char *function, double t, double h,
                            double *t_end)
{
    const double T = *fmu_time(inst);
    if (!isfinite(t) || !isfinite(h) || h < 0.0) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint = %g, communicationStepSize = %g "
                        "must be finite and the step >= 0",
                  function, t, h);
        return FMU_ERROR;
    }
    if (fabs(t - T) > COMM_POINT_ROUNDOFF * larger(fabs(t), fabs(T))) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint = %.17g does not match the FMU time "
                        "%.17g (%s by %.3g s; allowed: round-off, %.3g s)",
                  function, t, T, t < T ? "behind" : "ahead", fabs(t - T),
                  COMM_POINT_ROUNDOFF * larger(fabs(t), fabs(T)));
        return FMU_ERROR;
    }
    *t_end = t + h;
    if (h == 0.0) {
        return FMU_OK;
    }
    if (!isfinite(*t_end)) {
        FMU_LOG_ERROR(inst, "%s: currentCommunicationPoint + communicationStepSize = %.17g + "
                        "%g is not finite", function, t, h);
        return FMU_ERROR;
    }
    if (!(*t_end > T)) {
        FMU_LOG_ERROR(inst, "%s: communicationStepSize = %g at t = %.17g is below the "
                        "resolution of the time (%g s): t + h = %.17g does not advance the FMU "
                        "time %.17g",
                  function, h, t, nextafter(fabs(T), INFINITY) - fabs(T), *t_end, T);
        return FMU_ERROR;
    }
    const double taken = *t_end - T;
    if (fabs(taken - h) > fmu_time_resolution(inst) * h) {
        if (!inst->warned_time) {
            inst->warned_time = 1;
            fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING,
                    "%s: the time t = %.17g resolves steps to %g s only: "
                    "communicationStepSize = %.17g is taken as %.17g (relative difference %.3g > "
                    "%g); the FMU integrates exactly that step, but the communication points are "
                    "not where the master meant them (further such steps return a warning "
                    "without a message)",
                    function, T, nextafter(fabs(*t_end), INFINITY) - fabs(*t_end), h, taken,
                    fabs(taken - h) / h, fmu_time_resolution(inst));
        }
        return FMU_WARNING;
    }
    return FMU_OK;
}
