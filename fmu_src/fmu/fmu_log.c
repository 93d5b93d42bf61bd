/* The instance's log and call checks (fmu_instance.h): messages to the importer's logger by
 * category, the state machine's check of a call, NULL arguments, the debug-logging settings. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_log.h"
#include "fmu_types.h"

const char *fmu_category_name(unsigned int category)
{
    switch (category) {
    case LOG_EVENTS:
        return "logEvents";
    case LOG_STATUS_WARNING:
        return "logStatusWarning";
    case LOG_STATUS_ERROR:
        return "logStatusError";
    default:
        return "logAll";
    }
}

void fmu_log(const fmu_instance_t *inst, fmu_status_t status, unsigned int category,
             const char *fmt, ...)
{
    if (inst == NULL || inst->log_message == NULL || !(inst->log_categories & category)) {
        return;
    }
    char msg[FMU_MSG_SIZE];
    va_list args;
    va_start(args, fmt);
    vsnprintf(msg, sizeof(msg), fmt, args);
    va_end(args);
    inst->log_message(inst, status, fmu_category_name(category), msg);
}

const char *fmu_state_name(fmu_state_t s)
{
    switch (s) {
    case FMU_INSTANTIATED:
        return "Instantiated";
    case FMU_INITIALIZATION:
        return "InitializationMode";
    case FMU_EVENT:
        return "EventMode";
    case FMU_CONTINUOUS:
        return "ContinuousTimeMode";
    case FMU_STEP_COMPLETE:
        return "StepComplete";
    case FMU_STEP_FAILED:
        return "StepFailed";
    case FMU_TERMINATED:
        return "Terminated";
    default:
        return "Error";
    }
}

int fmu_allowed(fmu_instance_t *inst, const char *function, unsigned int mask)
{
    if (inst == NULL) {
        return 0;
    }
    if (!(inst->state & mask)) {
        const char *name = fmu_state_name(inst->state);
        if (inst->fmi_version == 3 && inst->state == FMU_STEP_COMPLETE) {
            name = "StepMode";
        }
        FMU_LOG_ERROR(inst, "%s: illegal call in state %s", function, name);
        return 0;
    }
    if (inst->log_categories & LOG_ALL) { /* (fmu_log is cold: not called on every call) */
        fmu_log(inst, FMU_OK, LOG_ALL, "%s", function);
    }
    if (!(mask & (inst->type == FMU_ME ? FMU_FOR_ME : FMU_FOR_CS))) {
        FMU_LOG_ERROR(inst, "%s: only for %s", function,
                      inst->type == FMU_ME ? "co-simulation" : "model exchange");
        return 0;
    }
    return 1;
}

int fmu_not_null(fmu_instance_t *inst, const char *function, const void *p, const char *arg)
{
    if (p == NULL) {
        FMU_LOG_ERROR(inst, "%s: argument %s is NULL", function, arg);
        return 0;
    }
    return 1;
}

fmu_status_t fmu_set_debug_logging(fmu_instance_t *inst, const char *function, int on, size_t n,
                                   const char *const categories[])
{
    if (inst == NULL) {
        return FMU_ERROR;
    }
    if (n > 0 && !fmu_not_null(inst, function, categories, "categories")) {
        return FMU_ERROR;
    }
    const unsigned int always = LOG_STATUS_ERROR | LOG_STATUS_WARNING;
    if (n == 0) {
        inst->log_categories = on ? (LOG_EVENTS | LOG_ALL | always) : always;
        return FMU_OK;
    }
    for (size_t i = 0; i < n; i++) {
        unsigned int bit = 0;
        if (categories[i] == NULL) {
            FMU_LOG_ERROR(inst, "%s: categories[%zu] is NULL", function, i);
            return FMU_ERROR;
        }
        if (strcmp(categories[i], "logEvents") == 0) {
            bit = LOG_EVENTS;
        } else if (strcmp(categories[i], "logStatusWarning") == 0) {
            bit = LOG_STATUS_WARNING;
        } else if (strcmp(categories[i], "logStatusError") == 0) {
            bit = LOG_STATUS_ERROR;
        } else if (strcmp(categories[i], "logAll") == 0) {
            bit = LOG_ALL;
        } else {
            FMU_LOG_ERROR(inst, "%s: unknown log category \"%s\"", function, categories[i]);
            return FMU_ERROR;
        }
        if (on) {
            inst->log_categories |= bit;
        } else {
            inst->log_categories &= ~bit;
        }
    }
    return FMU_OK;
}
