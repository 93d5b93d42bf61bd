/* The FMI 2.0 model-exchange table of the conformance importers (import_me.h) and their main:
 * built once per integrator, which CSFH_IMPORTER_INTEGRATOR and CSFH_IMPORTER_PROGRAM name
 * (CMakeLists.txt). */
#include <math.h>
#include <string.h>

#include "fmi2_import.h"
#include "import_me.h"

#define OK(call) ((call) > fmi2Warning ? -1 : 0)

static int initialize(void *fmu, double tolerance)
{
    return OK(imp_initialize((importer_t *)fmu, fmi2ModelExchange, tolerance));
}

static int set_time(void *fmu, double t)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.SetTime(imp->c, t));
}

static int set_states(void *fmu, const double *x, size_t n)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.SetContinuousStates(imp->c, x, n));
}

static int get_states(void *fmu, double *x, size_t n)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.GetContinuousStates(imp->c, x, n));
}

static int get_nominals(void *fmu, double *nominals, size_t n)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.GetNominalsOfContinuousStates(imp->c, nominals, n));
}

static int get_derivatives(void *fmu, double *dx, size_t n)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.GetDerivatives(imp->c, dx, n));
}

static int get_event_indicators(void *fmu, double *z, size_t n)
{
    importer_t *imp = (importer_t *)fmu;
    return OK(imp->api.GetEventIndicators(imp->c, z, n));
}

static int completed_integrator_step(void *fmu, int *enter_event_mode, int *terminate)
{
    importer_t *imp = (importer_t *)fmu;
    fmi2Boolean enter = fmi2False, stop = fmi2False;
    const int r = OK(imp->api.CompletedIntegratorStep(imp->c, fmi2True, &enter, &stop));
    *enter_event_mode = enter != fmi2False;
    *terminate = stop != fmi2False;
    return r;
}

/* FMI 2.0 model exchange: fmi2NewDiscreteStates until newDiscreteStatesNeeded is false. */
static int event_iteration(void *fmu, int in_event_mode, imp_event_info_t *out)
{
    importer_t *imp = (importer_t *)fmu;
    fmi2EventInfo info;
    memset(out, 0, sizeof(*out));
    if (!in_event_mode && OK(imp->api.EnterEventMode(imp->c)) < 0) {
        return -1;
    }
    do {
        memset(&info, 0, sizeof(info));
        if (OK(imp->api.NewDiscreteStates(imp->c, &info)) < 0 || info.terminateSimulation) {
            return -1;
        }
        out->values_changed |= info.valuesOfContinuousStatesChanged != fmi2False;
        out->nominals_changed |= info.nominalsOfContinuousStatesChanged != fmi2False;
    } while (info.newDiscreteStatesNeeded);
    out->t_next = info.nextEventTimeDefined ? info.nextEventTime : INFINITY;
    return OK(imp->api.EnterContinuousTimeMode(imp->c));
}

static int record(void *fmu, double t, int write)
{
    return OK(imp_record((importer_t *)fmu, t, write));
}

static int close_fmu(void *fmu)
{
    return imp_close((importer_t *)fmu);
}

int main(int argc, char **argv)
{
    importer_t imp;
    imp_open(&imp, argc, argv, fmi2ModelExchange, CSFH_IMPORTER_PROGRAM);
    const imp_me_t me = {
        &imp.run, &imp, "fmi2GetDerivatives", "fmi2CompletedIntegratorStep",
        "fmi2GetEventIndicators", initialize, set_time, set_states, get_states, get_nominals,
        get_derivatives, get_event_indicators, completed_integrator_step, event_iteration, record,
        close_fmu,
    };
    return CSFH_IMPORTER_INTEGRATOR(&me, CSFH_IMPORTER_PROGRAM);
}
