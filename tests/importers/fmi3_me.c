/* The FMI 3.0 model-exchange table of the conformance importers (import_me.h) and their main:
 * built once per integrator, which CSFH_IMPORTER_INTEGRATOR and CSFH_IMPORTER_PROGRAM name
 * (CMakeLists.txt). */
#include <math.h>
#include <string.h>

#include "fmi3_import.h"
#include "import_me.h"

#define OK(call) ((call) > fmi3Warning ? -1 : 0)

static int initialize(void *fmu, double tolerance)
{
    return OK(imp3_initialize((importer3_t *)fmu, tolerance, 0, 0));
}

static int set_time(void *fmu, double t)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.SetTime(imp->c, t));
}

static int set_states(void *fmu, const double *x, size_t n)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.SetContinuousStates(imp->c, x, n));
}

static int get_states(void *fmu, double *x, size_t n)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.GetContinuousStates(imp->c, x, n));
}

static int get_nominals(void *fmu, double *nominals, size_t n)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.GetNominalsOfContinuousStates(imp->c, nominals, n));
}

static int get_derivatives(void *fmu, double *dx, size_t n)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.GetContinuousStateDerivatives(imp->c, dx, n));
}

static int get_event_indicators(void *fmu, double *z, size_t n)
{
    importer3_t *imp = (importer3_t *)fmu;
    return OK(imp->api.GetEventIndicators(imp->c, z, n));
}

static int completed_integrator_step(void *fmu, int *enter_event_mode, int *terminate)
{
    importer3_t *imp = (importer3_t *)fmu;
    fmi3Boolean enter = fmi3False, stop = fmi3False;
    const int r = OK(imp->api.CompletedIntegratorStep(imp->c, fmi3True, &enter, &stop));
    *enter_event_mode = enter != fmi3False;
    *terminate = stop != fmi3False;
    return r;
}

/* FMI 3.0 model exchange: fmi3UpdateDiscreteStates until discreteStatesNeedUpdate is false. */
static int event_iteration(void *fmu, int in_event_mode, imp_event_info_t *out)
{
    importer3_t *imp = (importer3_t *)fmu;
    fmi3Boolean again = fmi3False, terminate = fmi3False, nominals = fmi3False;
    fmi3Boolean values = fmi3False, next_defined = fmi3False;
    fmi3Float64 next = 0.0;
    memset(out, 0, sizeof(*out));
    if (!in_event_mode && OK(imp->api.EnterEventMode(imp->c)) < 0) {
        return -1;
    }
    do {
        if (OK(imp->api.UpdateDiscreteStates(imp->c, &again, &terminate, &nominals, &values,
                                             &next_defined, &next)) < 0 ||
            terminate) {
            return -1;
        }
        out->values_changed |= values != fmi3False;
        out->nominals_changed |= nominals != fmi3False;
    } while (again);
    out->t_next = next_defined ? next : INFINITY;
    return OK(imp->api.EnterContinuousTimeMode(imp->c));
}

static int record(void *fmu, double t, int write)
{
    return OK(imp3_record((importer3_t *)fmu, t, write));
}

static int close_fmu(void *fmu)
{
    return imp3_close((importer3_t *)fmu);
}

int main(int argc, char **argv)
{
    importer3_t imp;
    imp3_open(&imp, argc, argv, IMP3_MODEL_EXCHANGE, CSFH_IMPORTER_PROGRAM);
    const imp_me_t me = {
        &imp.run, &imp, "fmi3GetContinuousStateDerivatives", "fmi3CompletedIntegratorStep",
        "fmi3GetEventIndicators", initialize, set_time, set_states, get_states, get_nominals,
        get_derivatives, get_event_indicators, completed_integrator_step, event_iteration, record,
        close_fmu,
    };
    return CSFH_IMPORTER_INTEGRATOR(&me, CSFH_IMPORTER_PROGRAM);
}
