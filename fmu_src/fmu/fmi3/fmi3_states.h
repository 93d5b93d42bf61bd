/* The state table of the FMI 3.0 front-end (fmi3_glue.c): in which instance states each fmi3
 * function may be called, and by which interface, one line per function, in the order of the
 * standard's state machines of model exchange and co-simulation. Their columns share one mask:
 * the states are apart (ContinuousTimeMode is model exchange's, Step Mode, FMU_STEP_COMPLETE,
 * co-simulation's; an instance in Step Mode after a failed step is in FMU_STEP_FAILED). This FMU
 * has no Scheduled Execution, no clocks and no configuration mode: it never enters their states.
 * Every function makes this one check first (fmu_allowed); a refused call changes nothing. */
#ifndef CSFH_FMI3_STATES_H
#define CSFH_FMI3_STATES_H

#include "fmu_instance.h"

#define S_ME FMU_FOR_ME
#define S_CS FMU_FOR_CS
#define S_ANY (FMU_ANY_STATE | S_ME | S_CS)
/* the states where values can be read or written */
#define S_GET                                                                                  \
    (FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | FMU_STEP_FAILED |      \
     FMU_TERMINATED | FMU_ERROR_STATE)
#define S_SET                                                                                  \
    (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE)

/* common functions */
#define STATES_fmi3SetDebugLogging S_ANY
#define STATES_fmi3EnterInitializationMode (FMU_INSTANTIATED | S_ME | S_CS)
#define STATES_fmi3ExitInitializationMode (FMU_INITIALIZATION | S_ME | S_CS)
#define STATES_fmi3EnterEventMode (FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | S_ME | S_CS)
#define STATES_fmi3Terminate                                                                   \
    (FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | FMU_STEP_FAILED | S_ME | S_CS)
#define STATES_fmi3Reset S_ANY
/* (the types without variables refuse every value reference) */
#define STATES_fmi3GetFloat32 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetFloat64 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetInt8 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetUInt8 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetInt16 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetUInt16 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetInt32 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetUInt32 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetInt64 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetUInt64 (S_GET | S_ME | S_CS)
#define STATES_fmi3GetBoolean (S_GET | S_ME | S_CS)
#define STATES_fmi3GetString (S_GET | S_ME | S_CS)
#define STATES_fmi3GetBinary (S_GET | S_ME | S_CS)
#define STATES_fmi3GetClock (S_GET | S_ME | S_CS)
#define STATES_fmi3SetFloat32 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetFloat64 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetInt8 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetUInt8 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetInt16 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetUInt16 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetInt32 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetUInt32 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetInt64 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetUInt64 (S_SET | S_ME | S_CS)
#define STATES_fmi3SetBoolean (S_SET | S_ME | S_CS)
#define STATES_fmi3SetString (S_SET | S_ME | S_CS)
#define STATES_fmi3SetBinary (S_SET | S_ME | S_CS)
#define STATES_fmi3SetClock (S_SET | S_ME | S_CS)
#define STATES_fmi3GetFMUState S_ANY
#define STATES_fmi3SetFMUState S_ANY
#define STATES_fmi3FreeFMUState S_ANY
#define STATES_fmi3SerializedFMUStateSize S_ANY
#define STATES_fmi3SerializeFMUState S_ANY
#define STATES_fmi3DeserializeFMUState S_ANY
#define STATES_fmi3UpdateDiscreteStates (FMU_EVENT | S_ME | S_CS)
#define STATES_fmi3GetDirectionalDerivative (S_GET | S_ME | S_CS)
#define STATES_fmi3GetAdjointDerivative (S_GET | S_ME | S_CS)
/* not provided: refused in every state */
#define STATES_fmi3GetNumberOfVariableDependencies S_ANY
#define STATES_fmi3GetVariableDependencies S_ANY
#define STATES_fmi3EnterConfigurationMode S_ANY
#define STATES_fmi3ExitConfigurationMode S_ANY
#define STATES_fmi3GetIntervalDecimal S_ANY
#define STATES_fmi3GetIntervalFraction S_ANY
#define STATES_fmi3GetShiftDecimal S_ANY
#define STATES_fmi3GetShiftFraction S_ANY
#define STATES_fmi3SetIntervalDecimal S_ANY
#define STATES_fmi3SetIntervalFraction S_ANY
#define STATES_fmi3SetShiftDecimal S_ANY
#define STATES_fmi3SetShiftFraction S_ANY
#define STATES_fmi3EvaluateDiscreteStates S_ANY
#define STATES_fmi3ActivateModelPartition S_ANY
#define STATES_fmi3GetOutputDerivatives S_ANY

/* model exchange */
#define STATES_fmi3EnterContinuousTimeMode (FMU_EVENT | S_ME)
#define STATES_fmi3CompletedIntegratorStep (FMU_CONTINUOUS | S_ME)
#define STATES_fmi3SetTime (FMU_EVENT | FMU_CONTINUOUS | S_ME)
#define STATES_fmi3SetContinuousStates (FMU_CONTINUOUS | S_ME)
#define STATES_fmi3GetContinuousStateDerivatives (S_GET | S_ME)
#define STATES_fmi3GetEventIndicators (S_GET | S_ME)
#define STATES_fmi3GetContinuousStates (S_GET | S_ME)
#define STATES_fmi3GetNominalsOfContinuousStates (FMU_ANY_STATE | S_ME)
#define STATES_fmi3GetNumberOfEventIndicators S_ANY
#define STATES_fmi3GetNumberOfContinuousStates S_ANY

/* co-simulation */
#define STATES_fmi3EnterStepMode (FMU_EVENT | S_CS)
#define STATES_fmi3DoStep (FMU_STEP_COMPLETE | S_CS)

/* The one state check of function f (fmu_allowed). */
#define ALLOWED(inst, f) fmu_allowed((inst), #f, STATES_##f)

#endif
