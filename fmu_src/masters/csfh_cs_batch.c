/* The batch co-simulation master (csfh_cs_batch.h). */
#include "csfh_cs_batch.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_api.h"
#include "fmu_library.h"

#define ABI_VERSION 2 /* 2: csfh_cs_steps */
#define MAX_OUT 64 /* outputs per run */

/* ------------------------------------------------------------------------------------------ */
/* one run's context: the FMU's log goes here (the first error, else the first warning) */
typedef struct {
    char *message;
    size_t size;
    int have_error, have_warning;
} run_log_t;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)instance;
    (void)category;
    run_log_t *log = (run_log_t *)env;
    if (log == NULL || log->message == NULL || log->size == 0 || message == NULL) {
        return;
    }
    const int error = status >= fmi2Error;
    const int warning = status == fmi2Warning;
    if (!(error && !log->have_error) && !(warning && !log->have_error && !log->have_warning)) {
        return;
    }
    va_list args;
    va_start(args, message);
    vsnprintf(log->message, log->size, message, args);
    va_end(args);
    log->have_error |= error;
    log->have_warning |= warning;
}

static void *allocate(size_t n, size_t size)
{
    return calloc(n, size);
}

/* Record a failed call (unless the FMU logged why). */
static void call_failed(run_log_t *log, const char *call, fmi2Status s)
{
    if (!log->have_error && log->message != NULL && log->size > 0) {
        snprintf(log->message, log->size, "%s returned status %d", call, (int)s);
    }
    log->have_error = 1;
}

/* The value of output j (already read into v) enters the reductions at time t. */
static void reduce(const csfh_cs_batch_spec_t *spec, const double *v, double t, int first,
                   double *acc, double *max_for_time)
{
    for (size_t j = 0; j < spec->n_out; j++) {
        const double x = v[j];
        switch (spec->out_reduce[j]) {
        case CSFH_BATCH_MAX:
            acc[j] = first || x > acc[j] ? x : acc[j];
            break;
        case CSFH_BATCH_MIN:
            acc[j] = first || x < acc[j] ? x : acc[j];
            break;
        case CSFH_BATCH_ABSMAX:
            acc[j] = first || fabs(x) > acc[j] ? fabs(x) : acc[j];
            break;
        case CSFH_BATCH_FIRST_WHEN:
            if (first) {
                acc[j] = NAN;
            }
            if (isnan(acc[j]) && v[spec->out_arg[j]] > 0.0) {
                acc[j] = x;
            }
            break;
        case CSFH_BATCH_TIME_OF_MAX:
            if (first || x > max_for_time[j]) {
                max_for_time[j] = x;
                acc[j] = t;
            }
            break;
        default: /* CSFH_BATCH_FINAL */
            acc[j] = x;
            break;
        }
    }
}

/* The outputs grouped by type, so that each step reads them in one call per type. */
typedef struct {
    size_t n[3];                       /* per type: how many */
    fmi2ValueReference vr[3][MAX_OUT]; /* their value references */
    size_t index[3][MAX_OUT];          /* their places among the outputs */
} out_groups_t;

static void group_outputs(const csfh_cs_batch_spec_t *spec, out_groups_t *g)
{
    memset(g->n, 0, sizeof(g->n));
    for (size_t j = 0; j < spec->n_out; j++) {
        const int t = spec->out_type[j] == CSFH_BATCH_INTEGER   ? 1
                      : spec->out_type[j] == CSFH_BATCH_BOOLEAN ? 2
                                                                : 0;
        g->vr[t][g->n[t]] = spec->out_vr[j];
        g->index[t][g->n[t]++] = j;
    }
}

/* Read every output (converted to double). */
static fmi2Status read_outputs(const fmi2_api_t *api, fmi2Component c, const out_groups_t *g,
                               double *v, run_log_t *log)
{
    double reals[MAX_OUT];
    fmi2Integer ints[MAX_OUT];
    fmi2Boolean bools[MAX_OUT];
    fmi2Status s[3] = {fmi2OK, fmi2OK, fmi2OK};
    if (g->n[0] > 0) {
        s[0] = api->GetReal(c, g->vr[0], g->n[0], reals);
    }
    if (g->n[1] > 0 && s[0] <= fmi2Warning) {
        s[1] = api->GetInteger(c, g->vr[1], g->n[1], ints);
    }
    if (g->n[2] > 0 && s[0] <= fmi2Warning && s[1] <= fmi2Warning) {
        s[2] = api->GetBoolean(c, g->vr[2], g->n[2], bools);
    }
    for (int t = 0; t < 3; t++) {
        if (s[t] > fmi2Warning) {
            call_failed(log, t == 0 ? "fmi2GetReal" : t == 1 ? "fmi2GetInteger" : "fmi2GetBoolean", s[t]);
            return s[t];
        }
        log->have_warning |= s[t] == fmi2Warning;
    }
    for (size_t k = 0; k < g->n[0]; k++) {
        v[g->index[0][k]] = reals[k];
    }
    for (size_t k = 0; k < g->n[1]; k++) {
        v[g->index[1][k]] = (double)ints[k];
    }
    for (size_t k = 0; k < g->n[2]; k++) {
        v[g->index[2][k]] = bools[k] ? 1.0 : 0.0;
    }
    return fmi2OK;
}

long long csfh_cs_batch_points(double stop_time, double step)
{
    if (!(stop_time > 0.0 && step > 0.0 && isfinite(stop_time) && isfinite(step))) {
        return -1;
    }
    /* the grid of csfh.runners.fmu.simulate_cs: ceil(t_end / h - 1e-9) steps */
    return (long long)ceil(stop_time / step - 1e-9) + 1;
}

/* One run; returns its status. */
static int run_one(const fmi2_api_t *api, const csfh_cs_batch_spec_t *spec, const out_groups_t *groups,
                   const double *values, long long n_steps, double *result, double *record,
                   run_log_t *log)
{
    const fmi2CallbackFunctions callbacks = {logger, allocate, free, NULL, log};
    fmi2Component c = api->Instantiate(spec->instance_name, fmi2CoSimulation, spec->guid,
                                       spec->resource_uri, &callbacks, fmi2False, fmi2False);
    if (c == NULL) {
        call_failed(log, "fmi2Instantiate", fmi2Error);
        return CSFH_BATCH_FAILED;
    }
    double v[MAX_OUT], max_for_time[MAX_OUT];
    fmi2Status s = api->SetupExperiment(c, fmi2True, spec->tolerance, 0.0, fmi2True,
                                        spec->stop_time);
    const char *call = "fmi2SetupExperiment";
    if (s <= fmi2Warning) {
        s = api->EnterInitializationMode(c);
        call = "fmi2EnterInitializationMode";
    }
    for (size_t i = 0; i < spec->n_set && s <= fmi2Warning; i++) {
        const fmi2ValueReference vr = spec->set_vr[i];
        if (spec->set_type[i] == CSFH_BATCH_INTEGER) {
            const fmi2Integer x = (fmi2Integer)values[i];
            s = api->SetInteger(c, &vr, 1, &x);
            call = "fmi2SetInteger";
        } else if (spec->set_type[i] == CSFH_BATCH_BOOLEAN) {
            const fmi2Boolean x = values[i] != 0.0 ? fmi2True : fmi2False;
            s = api->SetBoolean(c, &vr, 1, &x);
            call = "fmi2SetBoolean";
        } else {
            s = api->SetReal(c, &vr, 1, &values[i]);
            call = "fmi2SetReal";
        }
    }
    if (s <= fmi2Warning) {
        s = api->ExitInitializationMode(c);
        call = "fmi2ExitInitializationMode";
    }
    if (s > fmi2Warning) {
        call_failed(log, call, s);
        api->FreeInstance(c);
        return CSFH_BATCH_FAILED;
    }
    log->have_warning |= s == fmi2Warning;
    if (read_outputs(api, c, groups, v, log) > fmi2Warning) {
        api->FreeInstance(c);
        return CSFH_BATCH_FAILED;
    }
    reduce(spec, v, 0.0, 1, result, max_for_time);
    if (record != NULL) {
        memcpy(record, v, spec->n_out * sizeof(double));
    }
    double t = 0.0;
    for (long long k = 0; k < n_steps; k++) {
        /* the times of simulate_cs: min((k + 1) h, t_end), steps t_next - t */
        const double t_grid = (double)(k + 1) * spec->step;
        const double t_next = t_grid <= spec->stop_time ? t_grid : spec->stop_time;
        s = api->DoStep(c, t, t_next - t, fmi2True);
        if (s > fmi2Warning) {
            call_failed(log, "fmi2DoStep", s);
            api->FreeInstance(c);
            return CSFH_BATCH_FAILED;
        }
        log->have_warning |= s == fmi2Warning;
        t = t_next;
        if (read_outputs(api, c, groups, v, log) > fmi2Warning) {
            api->FreeInstance(c);
            return CSFH_BATCH_FAILED;
        }
        reduce(spec, v, t, 0, result, max_for_time);
        if (record != NULL) {
            memcpy(record + (size_t)(k + 1) * spec->n_out, v, spec->n_out * sizeof(double));
        }
    }
    s = api->Terminate(c);
    api->FreeInstance(c);
    if (s > fmi2Warning) {
        call_failed(log, "fmi2Terminate", s);
        return CSFH_BATCH_FAILED;
    }
    return log->have_warning ? CSFH_BATCH_WARNING : CSFH_BATCH_OK;
}

long long csfh_cs_batch_run(const csfh_cs_batch_spec_t *spec, size_t n_runs, const double *values,
                            double *results, double *records, int *status, char *messages,
                            size_t message_size)
{
    char local[256];
    char *first = messages != NULL && message_size > 0 ? messages : local;
    const size_t first_size = messages != NULL && message_size > 0 ? message_size : sizeof(local);
    first[0] = '\0';
    if (spec == NULL || spec->binary == NULL || spec->guid == NULL ||
        spec->instance_name == NULL || results == NULL || status == NULL ||
        (spec->n_set > 0 && (values == NULL || spec->set_vr == NULL || spec->set_type == NULL)) ||
        spec->n_out > MAX_OUT || (spec->n_out > 0 && (spec->out_vr == NULL || spec->out_type == NULL ||
                                                 spec->out_reduce == NULL || spec->out_arg == NULL))) {
        snprintf(first, first_size, "csfh_cs_batch_run: bad arguments (NULL, or more than 64 outputs)");
        return -1;
    }
    for (size_t j = 0; j < spec->n_out; j++) {
        if (spec->out_reduce[j] == CSFH_BATCH_FIRST_WHEN &&
            (spec->out_arg[j] < 0 || (size_t)spec->out_arg[j] >= spec->n_out)) {
            snprintf(first, first_size, "csfh_cs_batch_run: output %zu: trigger %d out of range", j,
                     spec->out_arg[j]);
            return -1;
        }
    }
    const long long n_points = csfh_cs_batch_points(spec->stop_time, spec->step);
    if (n_points < 1 || !(spec->tolerance > 0.0)) {
        snprintf(first, first_size, "csfh_cs_batch_run: bad experiment (stop %g s, step %g s, tolerance %g)",
                 spec->stop_time, spec->step, spec->tolerance);
        return -1;
    }
    void *library = fmu_library_open(spec->binary);
    if (library == NULL) {
        snprintf(first, first_size, "csfh_cs_batch_run: cannot load %s", spec->binary);
        return -1;
    }
    fmi2_api_t api;
    const char *missing = fmi2_api_load(&api, library, FMI2_API_COMMON | FMI2_API_CS);
    if (missing != NULL) {
        snprintf(first, first_size, "csfh_cs_batch_run: %s has no %s", spec->binary, missing);
        fmu_library_close(library);
        return -1;
    }
    out_groups_t groups;
    group_outputs(spec, &groups);
    long long failed = 0;
    for (size_t r = 0; r < n_runs; r++) {
        char dummy[1];
        run_log_t log = {messages != NULL && message_size > 0 ? messages + r * message_size : dummy,
                         messages != NULL && message_size > 0 ? message_size : sizeof(dummy), 0, 0};
        log.message[0] = '\0';
        double *result = results + r * spec->n_out;
        double *record = records != NULL ? records + r * (size_t)n_points * spec->n_out : NULL;
        const double *v = values != NULL ? values + r * spec->n_set : NULL;
        status[r] = run_one(&api, spec, &groups, v, n_points - 1, result, record, &log);
        if (status[r] == CSFH_BATCH_FAILED) {
            for (size_t j = 0; j < spec->n_out; j++) {
                result[j] = NAN;
            }
            failed++;
        }
    }
    fmu_library_close(library);
    return failed;
}

int csfh_cs_batch_abi_version(void)
{
    return ABI_VERSION;
}
