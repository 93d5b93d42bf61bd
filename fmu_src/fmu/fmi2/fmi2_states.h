/* The state table of the FMI 2.0 front-end (fmi2_glue.c): in which instance states each fmi2
 * function may be called, and by which interface, one line per function, in the order of the
 * standard's tables (FMI 2.0: model exchange section 3.2.3, co-simulation section 4.2.4). Model
 * exchange's and co-simulation's columns share one mask: their states are apart
 * (ContinuousTimeMode is model exchange's, StepComplete and StepFailed co-simulation's). This FMU
 * takes synchronous steps and has no fatal error: it never enters StepInProgress, StepCanceled
 * or Fatal, and has no columns for them. Every function makes this one check first
 * (fmu_allowed); a refused call changes nothing. */
#ifndef CSFH_FMI2_STATES_H
#define CSFH_FMI2_STATES_H

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
#define STATES_fmi2SetDebugLogging S_ANY
#define STATES_fmi2SetupExperiment (FMU_INSTANTIATED | S_ME | S_CS)
#define STATES_fmi2EnterInitializationMode (FMU_INSTANTIATED | S_ME | S_CS)
#define STATES_fmi2ExitInitializationMode (FMU_INITIALIZATION | S_ME | S_CS)
#define STATES_fmi2Terminate                                                                   \
    (FMU_EVENT | FMU_CONTINUOUS | FMU_STEP_COMPLETE | FMU_STEP_FAILED | S_ME | S_CS)
#define STATES_fmi2Reset S_ANY
#define STATES_fmi2GetReal (S_GET | S_ME | S_CS)
#define STATES_fmi2GetInteger (S_GET | S_ME | S_CS)
#define STATES_fmi2GetBoolean (S_GET | S_ME | S_CS)
#define STATES_fmi2GetString (S_GET | S_ME | S_CS)
#define STATES_fmi2SetReal (S_SET | S_ME | S_CS)
#define STATES_fmi2SetInteger (S_SET | S_ME | S_CS)
#define STATES_fmi2SetBoolean (S_SET | S_ME | S_CS)
#define STATES_fmi2SetString (S_SET | S_ME | S_CS)
#define STATES_fmi2GetFMUstate S_ANY
#define STATES_fmi2SetFMUstate S_ANY
#define STATES_fmi2FreeFMUstate S_ANY
#define STATES_fmi2SerializedFMUstateSize S_ANY
#define STATES_fmi2SerializeFMUstate S_ANY
#define STATES_fmi2DeSerializeFMUstate S_ANY
#define STATES_fmi2GetDirectionalDerivative (S_GET | S_ME | S_CS)

/* model exchange */
#define STATES_fmi2EnterEventMode (FMU_EVENT | FMU_CONTINUOUS | S_ME)
#define STATES_fmi2NewDiscreteStates (FMU_EVENT | S_ME)
#define STATES_fmi2EnterContinuousTimeMode (FMU_EVENT | S_ME)
#define STATES_fmi2CompletedIntegratorStep (FMU_CONTINUOUS | S_ME)
#define STATES_fmi2SetTime (FMU_EVENT | FMU_CONTINUOUS | S_ME)
#define STATES_fmi2SetContinuousStates (FMU_CONTINUOUS | S_ME)
#define STATES_fmi2GetDerivatives (S_GET | S_ME)
#define STATES_fmi2GetEventIndicators (S_GET | S_ME)
#define STATES_fmi2GetContinuousStates (S_GET | S_ME)
#define STATES_fmi2GetNominalsOfContinuousStates (FMU_ANY_STATE | S_ME)

/* co-simulation: the input and output derivatives, cancelling and the asynchronous status are
 * not provided (refused in every state); the last successful time and the terminated flag are
 * answered in every state */
#define STATES_fmi2SetRealInputDerivatives S_ANY
#define STATES_fmi2GetRealOutputDerivatives S_ANY
#define STATES_fmi2DoStep (FMU_STEP_COMPLETE | S_CS)
#define STATES_fmi2CancelStep S_ANY
#define STATES_fmi2GetStatus S_ANY
#define STATES_fmi2GetRealStatus S_ANY
#define STATES_fmi2GetIntegerStatus S_ANY
#define STATES_fmi2GetBooleanStatus S_ANY
#define STATES_fmi2GetStringStatus S_ANY

/* The one state check of function f (fmu_allowed). */
#define ALLOWED(inst, f) fmu_allowed((inst), #f, STATES_##f)

#endif
