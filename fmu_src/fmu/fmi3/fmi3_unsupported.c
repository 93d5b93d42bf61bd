/* The parts of FMI 3.0 the FMU does not have, refused with a message after the state check of
 * every call (fmi3_states.h): the variable types without variables (every value reference is
 * unknown) and the functions not provided. */
#include <stdio.h>

#include "fmi3_front_end.h"

/* Types without variables: any value reference is unknown. */
static fmi3Status no_variables(fmi3Instance instance, const char *function,
                               const fmi3ValueReference vr[], size_t nvr)
{
    fmu_instance_t *inst = INST(instance);
    if (nvr > 0) {
        LOG_ERROR(inst, "%s: unknown value reference %u (the model has no variables of this type)",
                  function, vr != NULL ? vr[0] : 0u);
        return fmi3Error;
    }
    return fmi3OK;
}

#define GET_NONE(name, type)                                                                   \
    fmi3Status fmi3Get##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                             type values[], size_t nValues)                                     \
    {                                                                                          \
        (void)values;                                                                          \
        (void)nValues;                                                                         \
        if (!ALLOWED(INST(instance), fmi3Get##name)) {                                         \
            return fmi3Error;                                                                  \
        }                                                                                      \
        return no_variables(instance, "fmi3Get" #name, vr, nvr);                               \
    }
#define SET_NONE(name, type)                                                                   \
    fmi3Status fmi3Set##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                             const type values[], size_t nValues)                               \
    {                                                                                          \
        (void)values;                                                                          \
        (void)nValues;                                                                         \
        if (!ALLOWED(INST(instance), fmi3Set##name)) {                                         \
            return fmi3Error;                                                                  \
        }                                                                                      \
        return no_variables(instance, "fmi3Set" #name, vr, nvr);                               \
    }

GET_NONE(Float32, fmi3Float32)
GET_NONE(Int8, fmi3Int8)
GET_NONE(UInt8, fmi3UInt8)
GET_NONE(Int16, fmi3Int16)
GET_NONE(UInt16, fmi3UInt16)
GET_NONE(UInt32, fmi3UInt32)
GET_NONE(UInt64, fmi3UInt64)
GET_NONE(String, fmi3String)
SET_NONE(Float32, fmi3Float32)
SET_NONE(Int8, fmi3Int8)
SET_NONE(UInt8, fmi3UInt8)
SET_NONE(Int16, fmi3Int16)
SET_NONE(UInt16, fmi3UInt16)
SET_NONE(UInt32, fmi3UInt32)
SET_NONE(UInt64, fmi3UInt64)
SET_NONE(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueSizes;
    (void)values;
    (void)nValues;
    if (!ALLOWED(INST(instance), fmi3GetBinary)) {
        return fmi3Error;
    }
    return no_variables(instance, "fmi3GetBinary", vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes;
    (void)values;
    (void)nValues;
    if (!ALLOWED(INST(instance), fmi3SetBinary)) {
        return fmi3Error;
    }
    return no_variables(instance, "fmi3SetBinary", vr, nvr);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[])
{
    (void)values;
    if (!ALLOWED(INST(instance), fmi3GetClock)) {
        return fmi3Error;
    }
    return no_variables(instance, "fmi3GetClock", vr, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)values;
    if (!ALLOWED(INST(instance), fmi3SetClock)) {
        return fmi3Error;
    }
    return no_variables(instance, "fmi3SetClock", vr, nvr);
}

/* ------------------------------------------------------------------------------------------ */
/* what the FMU does not provide */

static fmi3Status not_provided(fmu_instance_t *inst, const char *what)
{
    LOG_ERROR(inst, "%s", what);
    return fmi3Error;
}

/* function f, not provided: refused, after its state check (fmi3_states.h) */
#define NOT_PROVIDED(instance, f, what)                                                        \
    (ALLOWED(INST(instance), f) ? not_provided(INST(instance), what) : fmi3Error)

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference;
    (void)nDependencies;
    return NOT_PROVIDED(instance, fmi3GetNumberOfVariableDependencies, "fmi3GetNumberOfVariableDependencies: not provided (the "
                                  "dependencies are in modelDescription.xml)");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return NOT_PROVIDED(instance, fmi3GetVariableDependencies, "fmi3GetVariableDependencies: not provided (the dependencies "
                                  "are in modelDescription.xml)");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return NOT_PROVIDED(instance, fmi3EnterConfigurationMode, "fmi3EnterConfigurationMode: the FMU has no structural "
                                  "parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return NOT_PROVIDED(instance, fmi3ExitConfigurationMode, "fmi3ExitConfigurationMode: the FMU has no structural "
                                  "parameters");
}

#define NO_CLOCKS "the FMU has no clocks"

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)vr;
    (void)nvr;
    (void)intervals;
    (void)qualifiers;
    return NOT_PROVIDED(instance, fmi3GetIntervalDecimal, "fmi3GetIntervalDecimal: " NO_CLOCKS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return NOT_PROVIDED(instance, fmi3GetIntervalFraction, "fmi3GetIntervalFraction: " NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[])
{
    (void)vr;
    (void)nvr;
    (void)shifts;
    return NOT_PROVIDED(instance, fmi3GetShiftDecimal, "fmi3GetShiftDecimal: " NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return NOT_PROVIDED(instance, fmi3GetShiftFraction, "fmi3GetShiftFraction: " NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[])
{
    (void)vr;
    (void)nvr;
    (void)intervals;
    return NOT_PROVIDED(instance, fmi3SetIntervalDecimal, "fmi3SetIntervalDecimal: " NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return NOT_PROVIDED(instance, fmi3SetIntervalFraction, "fmi3SetIntervalFraction: " NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[])
{
    (void)vr;
    (void)nvr;
    (void)shifts;
    return NOT_PROVIDED(instance, fmi3SetShiftDecimal, "fmi3SetShiftDecimal: " NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return NOT_PROVIDED(instance, fmi3SetShiftFraction, "fmi3SetShiftFraction: " NO_CLOCKS);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return NOT_PROVIDED(instance, fmi3EvaluateDiscreteStates, "fmi3EvaluateDiscreteStates: not provided "
                                  "(providesEvaluateDiscreteStates = false)");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    return NOT_PROVIDED(instance, fmi3ActivateModelPartition, "fmi3ActivateModelPartition: the FMU has no Scheduled "
                                  "Execution interface");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr;
    (void)nvr;
    (void)orders;
    (void)values;
    (void)nValues;
    return NOT_PROVIDED(instance, fmi3GetOutputDerivatives, "fmi3GetOutputDerivatives: not provided "
                                  "(maxOutputDerivativeOrder = 0)");
}

