/* Model exchange (fmu_instance.h): the time, the continuous states, derivatives, event
 * indicators and nominals, and the completed integrator step with its time-resolution check. */
#include <math.h>
#include <string.h>

#include "fmu_instance.h"

/* Model exchange and large times: the importer integrates in its own time, and the model is
 * autonomous (the time only stamps the recorded onset and release times), so the FMU's
 * derivatives, event indicators and outputs do not depend on the start time at all; what the
 * FMU can promise is to report what it sees of the importer's time losing precision. At every
 * completed integrator step it compares the time with the previous completed step's: if the
 * states moved but the double time represents the increment dt worse than the tolerance
 * (ulp(t) > max(tolerance, 1e-6) * dt, including dt = 0: steps below the resolution of t), it
 * returns FMU_WARNING (logged once per instance). A time that went backwards (the importer
 * rolled its integrator back) is not judged. */
static fmu_status_t check_me_time_resolution(fmu_instance_t *inst, const char *function)
{
    const double t = *fmu_time(inst);
    const double *x = fmu_states(inst);
    const size_t bytes = (size_t)fmu_model.n_states * sizeof(double);
    fmu_status_t status = FMU_OK;
    if (inst->last_step_valid && bytes > 0) {
        const double dt = t - inst->last_step_time;
        const double ulp = nextafter(fabs(t), INFINITY) - fabs(t);
        const int moved = memcmp(x, inst->last_step_x, bytes) != 0;
        if (moved && dt >= 0.0 && ulp > fmu_time_resolution(inst) * dt) {
            status = FMU_WARNING;
            if (!inst->warned_time) {
                inst->warned_time = 1;
                fmu_log(inst, FMU_WARNING, LOG_STATUS_WARNING,
                        "%s: the time t = %.17g resolves steps to %g s "
                        "only; the integrator step from t = %.17g (dt = %g s) is represented to "
                        "worse than %g relative: integrate in a time measured from a nearer "
                        "origin (further such steps return a warning without a message)",
                        function, t, ulp, inst->last_step_time, dt, fmu_time_resolution(inst));
            }
        }
    }
    fmu_step_reference(inst);
    return status;
}

fmu_status_t fmu_completed_integrator_step(fmu_instance_t *inst, const char *function)
{
    return check_me_time_resolution(inst, function);
}

fmu_status_t fmu_set_time(fmu_instance_t *inst, const char *function, double time)
{
    if (!isfinite(time)) {
        FMU_LOG_ERROR(inst, "%s: time = %g is not finite", function, time);
        return FMU_ERROR;
    }
    *fmu_time(inst) = time;
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_set_continuous_states(fmu_instance_t *inst, const char *function,
                                       const double x[], size_t nx)
{
    if (!fmu_not_null(inst, function, x, "x")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            FMU_LOG_ERROR(inst, "%s: x[%zu] = %g is not finite (t = %.17g)", function, i, x[i],
                          *fmu_time(inst));
            return FMU_ERROR;
        }
    }
    if (nx > 0) {
        memcpy(fmu_states(inst), x, nx * sizeof(double));
    }
    fmu_invalidate(inst);
    return FMU_OK;
}

fmu_status_t fmu_get_derivatives(fmu_instance_t *inst, const char *function, double der[],
                                 size_t nx)
{
    if (!fmu_not_null(inst, function, der, "derivatives")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    const fmu_status_t status = fmu_update_derivatives(inst, function);
    if (status > FMU_WARNING) {
        return status;
    }
    if (nx > 0) {
        memcpy(der, fmu_derivatives(inst), nx * sizeof(double));
    }
    return status;
}

fmu_status_t fmu_get_event_indicators(fmu_instance_t *inst, const char *function, double z[],
                                      size_t ni)
{
    if (!fmu_not_null(inst, function, z, "eventIndicators")) {
        return FMU_ERROR;
    }
    if (ni != (size_t)fmu_model.n_event_indicators) {
        FMU_LOG_ERROR(inst, "%s: ni = %zu, expected %d", function, ni,
                      fmu_model.n_event_indicators);
        return FMU_ERROR;
    }
    if (fmu_prepare(inst, function) != FMU_OK) {
        return FMU_ERROR;
    }
    if (ni > 0) {
        fmu_model.event_indicators(inst->model, fmu_states(inst), z);
    }
    for (size_t i = 0; i < ni; i++) {
        if (!isfinite(z[i])) {
            char text[FMU_MSG_SIZE];
            FMU_LOG_ERROR(inst, "%s: non-finite event indicator z[%zu] = %g at t = %.17g, state [%s]",
                          function, i, z[i], *fmu_time(inst), fmu_state_text(inst, text, sizeof(text)));
            return FMU_ERROR;
        }
    }
    return FMU_OK;
}

fmu_status_t fmu_get_continuous_states(fmu_instance_t *inst, const char *function, double x[],
                                       size_t nx)
{
    if (!fmu_not_null(inst, function, x, "x")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    if (nx > 0) {
        memcpy(x, fmu_states(inst), nx * sizeof(double));
    }
    return FMU_OK;
}

fmu_status_t fmu_get_nominals(fmu_instance_t *inst, const char *function, double nominal[],
                              size_t nx)
{
    if (!fmu_not_null(inst, function, nominal, "x_nominal")) {
        return FMU_ERROR;
    }
    if (nx != (size_t)fmu_model.n_states) {
        FMU_LOG_ERROR(inst, "%s: nx = %zu, expected %d", function, nx, fmu_model.n_states);
        return FMU_ERROR;
    }
    size_t k = 0;
    for (int i = 0; i < fmu_model.n_variables && k < nx; i++) {
        if (fmu_model.variables[i].is_state) {
            nominal[k++] = fmu_model.variables[i].nominal;
        }
    }
    return FMU_OK;
}
