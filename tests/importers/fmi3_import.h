/* The FMI 3.0 loader of the conformance importers (tests/importers/): load an unzipped FMI 3.0
 * FMU (binaries/<arch>-<os>/, e.g. x86_64-linux), read what an importer needs from its FMI 3.0
 * modelDescription.xml (instantiationToken, the states from ModelStructure/
 * ContinuousStateDerivative, the event indicators from ModelStructure/EventIndicator, value
 * references and types of the variables), instantiate and initialise, record the outputs.
 * Start values: Float64, Int32, Int64, Enumeration (as Int64) and Boolean. The same command line
 * as the FMI 2.0 importers (import_common.h, shared with fmi2_import.c). */
#ifndef CSFH_FMI3_IMPORT_H
#define CSFH_FMI3_IMPORT_H

#include <stdio.h>

/* the standard's header declares two callback types without a prototype (`()`) */
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#endif
#include "fmi3FunctionTypes.h"
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
#include "import_common.h"

typedef struct {
    fmi3InstantiateModelExchangeTYPE *InstantiateModelExchange;
    fmi3InstantiateCoSimulationTYPE *InstantiateCoSimulation;
    fmi3FreeInstanceTYPE *FreeInstance;
    fmi3EnterInitializationModeTYPE *EnterInitializationMode;
    fmi3ExitInitializationModeTYPE *ExitInitializationMode;
    fmi3TerminateTYPE *Terminate;
    fmi3SetFloat64TYPE *SetFloat64;
    fmi3SetInt32TYPE *SetInt32;
    fmi3SetInt64TYPE *SetInt64;
    fmi3SetBooleanTYPE *SetBoolean;
    fmi3GetFloat64TYPE *GetFloat64;
    fmi3GetInt32TYPE *GetInt32;
    fmi3GetInt64TYPE *GetInt64;
    fmi3GetBooleanTYPE *GetBoolean;
    fmi3GetFMUStateTYPE *GetFMUState;
    fmi3SetFMUStateTYPE *SetFMUState;
    fmi3FreeFMUStateTYPE *FreeFMUState;
    fmi3SerializedFMUStateSizeTYPE *SerializedFMUStateSize;
    fmi3SerializeFMUStateTYPE *SerializeFMUState;
    fmi3DeserializeFMUStateTYPE *DeserializeFMUState;
    fmi3EnterEventModeTYPE *EnterEventMode;
    fmi3UpdateDiscreteStatesTYPE *UpdateDiscreteStates;
    /* model exchange */
    fmi3EnterContinuousTimeModeTYPE *EnterContinuousTimeMode;
    fmi3CompletedIntegratorStepTYPE *CompletedIntegratorStep;
    fmi3SetTimeTYPE *SetTime;
    fmi3SetContinuousStatesTYPE *SetContinuousStates;
    fmi3GetContinuousStateDerivativesTYPE *GetContinuousStateDerivatives;
    fmi3GetEventIndicatorsTYPE *GetEventIndicators;
    fmi3GetContinuousStatesTYPE *GetContinuousStates;
    fmi3GetNominalsOfContinuousStatesTYPE *GetNominalsOfContinuousStates;
    /* co-simulation */
    fmi3EnterStepModeTYPE *EnterStepMode;
    fmi3DoStepTYPE *DoStep;
} imp3_api_t;

typedef enum { IMP3_MODEL_EXCHANGE, IMP3_CO_SIMULATION } imp3_kind_t;

typedef struct {
    imp_run_t run; /* options, model description, results (import_common.h) */
    imp3_api_t api;
    imp3_kind_t kind;
    fmi3Instance c;
} importer3_t;

/* Parse the command line and load the FMU (modelDescription.xml and the binary); exits with
 * status 2 and a message on failure. */
void imp3_open(importer3_t *imp, int argc, char **argv, imp3_kind_t kind, const char *program);

/* Value reference and type (the element name: "Float64", "Int32", "Int64", "Boolean",
 * "Enumeration", ...) of a variable; 0 if found, -1 otherwise. */
int imp3_lookup(const importer3_t *imp, const char *name, fmi3ValueReference *vr, char type[16]);

/* Instantiate (co-simulation: with eventModeUsed and earlyReturnAllowed as given),
 * fmi3EnterInitializationMode(tolerance, start, stop) with the start values of the command
 * line, fmi3ExitInitializationMode. fmi3OK or the failing status. */
fmi3Status imp3_initialize(importer3_t *imp, double tolerance, int event_mode_used,
                           int early_return_allowed);

/* Record the outputs at time t: to the CSV when `write`, and into the extremes always. */
fmi3Status imp3_record(importer3_t *imp, double t, int write);

/* Terminate (when completed), free the instance, write the summary, close everything; returns
 * the exit status (0 if the status is "completed"). */
int imp3_close(importer3_t *imp);

#endif
