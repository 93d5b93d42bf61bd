/* The FMI 2.0 functions of an FMU's binary (fmi2_api.h). */
#include "fmi2_api.h"

#include <stddef.h>
#include <string.h>

#include "fmu_library.h"

#define FUNCTION(f, group) {"fmi2" #f, offsetof(fmi2_api_t, f), group}

static const struct {
    const char *name;
    size_t offset; /* of its pointer in fmi2_api_t */
    unsigned int group;
} FUNCTIONS[] = {
    FUNCTION(Instantiate, FMI2_API_COMMON),
    FUNCTION(FreeInstance, FMI2_API_COMMON),
    FUNCTION(SetupExperiment, FMI2_API_COMMON),
    FUNCTION(EnterInitializationMode, FMI2_API_COMMON),
    FUNCTION(ExitInitializationMode, FMI2_API_COMMON),
    FUNCTION(Terminate, FMI2_API_COMMON),
    FUNCTION(SetReal, FMI2_API_COMMON),
    FUNCTION(SetInteger, FMI2_API_COMMON),
    FUNCTION(SetBoolean, FMI2_API_COMMON),
    FUNCTION(GetReal, FMI2_API_COMMON),
    FUNCTION(GetInteger, FMI2_API_COMMON),
    FUNCTION(GetBoolean, FMI2_API_COMMON),
    FUNCTION(Reset, FMI2_API_RESET),
    FUNCTION(GetFMUstate, FMI2_API_STATE),
    FUNCTION(SetFMUstate, FMI2_API_STATE),
    FUNCTION(FreeFMUstate, FMI2_API_STATE),
    FUNCTION(SerializedFMUstateSize, FMI2_API_STATE),
    FUNCTION(SerializeFMUstate, FMI2_API_STATE),
    FUNCTION(DeSerializeFMUstate, FMI2_API_STATE),
    FUNCTION(EnterEventMode, FMI2_API_ME),
    FUNCTION(NewDiscreteStates, FMI2_API_ME),
    FUNCTION(EnterContinuousTimeMode, FMI2_API_ME),
    FUNCTION(CompletedIntegratorStep, FMI2_API_ME),
    FUNCTION(SetTime, FMI2_API_ME),
    FUNCTION(SetContinuousStates, FMI2_API_ME),
    FUNCTION(GetDerivatives, FMI2_API_ME),
    FUNCTION(GetEventIndicators, FMI2_API_ME),
    FUNCTION(GetContinuousStates, FMI2_API_ME),
    FUNCTION(GetNominalsOfContinuousStates, FMI2_API_ME),
    FUNCTION(DoStep, FMI2_API_CS),
};

const char *fmi2_api_load(fmi2_api_t *api, void *library, unsigned int required)
{
    memset(api, 0, sizeof(*api));
    const char *missing = NULL;
    for (size_t i = 0; i < sizeof(FUNCTIONS) / sizeof(FUNCTIONS[0]); i++) {
        const fmu_library_function_t f = fmu_library_symbol(library, FUNCTIONS[i].name);
        if (f == NULL && (required & FUNCTIONS[i].group) && missing == NULL) {
            missing = FUNCTIONS[i].name;
        }
        /* every function pointer has the same representation on the platforms the FMU is
         * built for: the library's function is stored as the pointer type of its slot */
        memcpy((char *)api + FUNCTIONS[i].offset, &f, sizeof(f));
    }
    return missing;
}
