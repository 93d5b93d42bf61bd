/* Shared part of the conformance importers (tests/importers/): load an unzipped FMI 2.0 FMU,
 * read what an importer needs from its modelDescription.xml, parse the command line, instantiate
 * and initialise, write results.
 *
 * Portable C11: the only platform-specific code is the shared-library shim in fmi2_import.c
 * (dlopen / LoadLibrary); everything else is the C standard library, so the importers build for
 * linux64 and win64 alike.
 *
 * Common command line of every importer:
 *
 *   IMPORTER FMU_DIR [options] [NAME=VALUE ...]
 *     FMU_DIR           the unzipped FMU (modelDescription.xml, binaries/<platform>/)
 *     NAME=VALUE        start values by variable name (Real, Integer/Enumeration as a number,
 *                       Boolean as true/false/1/0), set in initialization mode
 *     --stop T          stop time (default: DefaultExperiment stopTime)
 *     --rtol R          relative tolerance (default: DefaultExperiment tolerance)
 *     --step H          step size (default: DefaultExperiment stepSize)
 *     --interval DT     output interval (default: DefaultExperiment stepSize)
 *     --outputs A,B,..  Real variables written to the CSV (default: the states)
 *     --out FILE        CSV: time and the outputs at every output point
 *     --events FILE     CSV: time and kind (onset/release/event) of every event
 *     --summary FILE    key = value lines: status, counts, extremes of every output over every
 *                       accepted step
 *     --mode M          importer-specific (me_cvode: flags | always; cs_master: memory |
 *                       serialize)
 *     --watch NAME      cs_master: the Integer variable whose change asks for a smaller step
 *     --max-steps N     give up (status "budget") after N steps (default 10000000)
 *     --verbose         log every FMU message
 * Exit status: 0 completed, 1 the FMU or the integrator failed (the summary says where), 2 bad
 * command line or FMU directory. */
#ifndef CSFH_FMI2_IMPORT_H
#define CSFH_FMI2_IMPORT_H

#include <stdio.h>

#include "fmi2FunctionTypes.h"

#define IMP_MAX_OUTPUTS 32
#define IMP_MAX_STARTS 64

typedef struct {
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode;
    fmi2TerminateTYPE *Terminate;
    fmi2SetRealTYPE *SetReal;
    fmi2SetIntegerTYPE *SetInteger;
    fmi2SetBooleanTYPE *SetBoolean;
    fmi2GetRealTYPE *GetReal;
    fmi2GetIntegerTYPE *GetInteger;
    fmi2GetBooleanTYPE *GetBoolean;
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    /* model exchange */
    fmi2EnterEventModeTYPE *EnterEventMode;
    fmi2NewDiscreteStatesTYPE *NewDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE *EnterContinuousTimeMode;
    fmi2CompletedIntegratorStepTYPE *CompletedIntegratorStep;
    fmi2SetTimeTYPE *SetTime;
    fmi2SetContinuousStatesTYPE *SetContinuousStates;
    fmi2GetDerivativesTYPE *GetDerivatives;
    fmi2GetEventIndicatorsTYPE *GetEventIndicators;
    fmi2GetContinuousStatesTYPE *GetContinuousStates;
    fmi2GetNominalsOfContinuousStatesTYPE *GetNominalsOfContinuousStates;
    /* co-simulation */
    fmi2DoStepTYPE *DoStep;
} imp_api_t;

/* What the importers read from modelDescription.xml. */
typedef struct {
    char guid[128];
    char model_identifier[128];
    int n_states;           /* Real variables with a derivative attribute */
    int n_event_indicators;
    double start_time, stop_time, tolerance, step_size; /* DefaultExperiment (NAN: absent) */
    char *xml;              /* the whole file, kept for variable look-ups */
} imp_model_t;

typedef struct {
    const char *fmu_dir;
    double stop, rtol, step, interval; /* NAN: from the DefaultExperiment */
    const char *mode;
    const char *watch;
    const char *out_path, *events_path, *summary_path;
    long max_steps;
    int verbose;
    int n_outputs;
    const char *output_names[IMP_MAX_OUTPUTS];
    fmi2ValueReference output_vrs[IMP_MAX_OUTPUTS];
    int n_starts;
    const char *starts[IMP_MAX_STARTS]; /* "NAME=VALUE" */
} imp_options_t;

typedef struct {
    imp_api_t api;
    imp_model_t md;
    imp_options_t opt;
    void *library;
    fmi2CallbackFunctions callbacks;
    fmi2Component c;
    FILE *out, *events;
    /* summary */
    long steps, events_count, reinits, rollbacks;
    double t_reached;
    double out_min[IMP_MAX_OUTPUTS], out_max[IMP_MAX_OUTPUTS];
    char status[256];
} importer_t;

/* Parse the command line and load the FMU (modelDescription.xml and the binary); exits with
 * status 2 and a message on failure. `kind` is fmi2ModelExchange or fmi2CoSimulation. */
void imp_open(importer_t *imp, int argc, char **argv, fmi2Type kind, const char *program);

/* Value reference and type ("Real", "Integer", "Boolean", "Enumeration") of a variable; 0 if
 * found, -1 otherwise. */
int imp_lookup(const importer_t *imp, const char *name, fmi2ValueReference *vr, char type[16]);

/* Instantiate, fmi2SetupExperiment(tolerance, start, stop), initialization mode with the start
 * values of the command line, exit initialization mode. fmi2OK or the failing status. */
fmi2Status imp_initialize(importer_t *imp, fmi2Type kind, double tolerance);

/* Record the outputs at time t: to the CSV when `write`, and into the extremes always. */
fmi2Status imp_record(importer_t *imp, double t, int write);

/* One event line. */
void imp_event(importer_t *imp, double t, const char *kind);

/* Write the summary, free everything; returns the exit status (0 if status is "completed"). */
int imp_close(importer_t *imp);

/* Set the summary status (printf-style) unless one is already set; returns 1 for chaining. */
int imp_fail(importer_t *imp, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
