/* The FMI 2.0 functions of an FMU's binary, for the masters and importers that load one (the
 * batch master, the conformance importers of tests/importers/, the benchmark master): one table
 * of function pointers, loaded from the library by name. Plain C11 and the FMI 2.0 headers. */
#ifndef CSFH_FMI2_API_H
#define CSFH_FMI2_API_H

#include "fmi2FunctionTypes.h"

typedef struct {
    /* FMI2_API_COMMON */
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
    /* FMI2_API_RESET */
    fmi2ResetTYPE *Reset;
    /* FMI2_API_STATE */
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    /* FMI2_API_ME: model exchange */
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
    /* FMI2_API_CS: co-simulation */
    fmi2DoStepTYPE *DoStep;
} fmi2_api_t;

/* The groups of functions a caller needs (bits of `required`). */
enum {
    FMI2_API_COMMON = 1 << 0,
    FMI2_API_RESET = 1 << 1,
    FMI2_API_STATE = 1 << 2,
    FMI2_API_ME = 1 << 3,
    FMI2_API_CS = 1 << 4
};

/* Every function of the table that the library (fmu_library.h) has; NULL if the `required`
 * groups are all there, else the name of the first one missing (the others found are set). */
const char *fmi2_api_load(fmi2_api_t *api, void *library, unsigned int required);

#endif
