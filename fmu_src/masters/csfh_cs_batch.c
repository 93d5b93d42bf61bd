/* The batch co-simulation master (csfh_cs_batch.h). */
#include "csfh_cs_batch.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_constants.h"
#include "fmi2_api.h"
#include "fmu_library.h"

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

/* One output's reduction: its value x at time t (first: at the start) into acc (held: the
 * largest value so far, for the time of the maximum; trigger: the value of the output it
 * waits for). */
typedef void (*reduce_fn)(double x, double t, int first, double trigger, double *acc,
                          double *held);

static void reduce_final(double x, double t, int first, double trigger, double *acc, double *held)
{
    (void)t, (void)first, (void)trigger, (void)held;
    *acc = x;
}

static void reduce_max(double x, double t, int first, double trigger, double *acc, double *held)
{
    (void)t, (void)trigger, (void)held;
    *acc = first || x > *acc ? x : *acc;
}

static void reduce_min(double x, double t, int first, double trigger, double *acc, double *held)
{
    (void)t, (void)trigger, (void)held;
    *acc = first || x < *acc ? x : *acc;
}

static void reduce_absmax(double x, double t, int first, double trigger, double *acc,
                          double *held)
{
    (void)t, (void)trigger, (void)held;
    *acc = first || fabs(x) > *acc ? fabs(x) : *acc;
}

static void reduce_first_when(double x, double t, int first, double trigger, double *acc,
                              double *held)
{
    (void)t, (void)held;
    if (first) {
        *acc = NAN;
    }
    if (isnan(*acc) && trigger > 0.0) {
        *acc = x;
    }
}

static void reduce_time_of_max(double x, double t, int first, double trigger, double *acc,
                               double *held)
{
    (void)trigger;
    if (first || x > *held) {
        *held = x;
        *acc = t;
    }
}

static const reduce_fn REDUCTIONS[] = {
    [CSFH_BATCH_FINAL] = reduce_final,
    [CSFH_BATCH_MAX] = reduce_max,
    [CSFH_BATCH_MIN] = reduce_min,
    [CSFH_BATCH_ABSMAX] = reduce_absmax,
    [CSFH_BATCH_FIRST_WHEN] = reduce_first_when,
    [CSFH_BATCH_TIME_OF_MAX] = reduce_time_of_max,
};

/* The outputs (already read into v) enter their reductions at time t (an unknown reduction is
 * the final value). */
static void reduce(const csfh_cs_batch_spec_t *spec, const double *v, double t, int first,
                   double *acc, double *max_for_time)
{
    const int n_reductions = (int)(sizeof(REDUCTIONS) / sizeof(REDUCTIONS[0]));
    for (size_t j = 0; j < spec->n_out; j++) {
        const int how = spec->out_reduce[j];
        const reduce_fn f = how >= 0 && how < n_reductions ? REDUCTIONS[how] : reduce_final;
        const double trigger = how == CSFH_BATCH_FIRST_WHEN ? v[spec->out_arg[j]] : 0.0;
        f(v[j], t, first, trigger, &acc[j], &max_for_time[j]);
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
    static const char *const calls[3] = {"fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean"};
    for (int t = 0; t < 3; t++) {
        if (s[t] > fmi2Warning) {
            call_failed(log, calls[t], s[t]);
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

/* Set up the experiment, set the start values one by one in initialization mode and leave it:
 * the status, and the call that returned it. */
static fmi2Status initialize(const fmi2_api_t *api, fmi2Component c,
                             const csfh_cs_batch_spec_t *spec, const double *values,
                             const char **call)
{
    fmi2Status s = api->SetupExperiment(c, fmi2True, spec->tolerance, 0.0, fmi2True,
                                        spec->stop_time);
    *call = "fmi2SetupExperiment";
    if (s <= fmi2Warning) {
        s = api->EnterInitializationMode(c);
        *call = "fmi2EnterInitializationMode";
    }
    for (size_t i = 0; i < spec->n_set && s <= fmi2Warning; i++) {
        const fmi2ValueReference vr = spec->set_vr[i];
        if (spec->set_type[i] == CSFH_BATCH_INTEGER) {
            const fmi2Integer x = (fmi2Integer)values[i];
            s = api->SetInteger(c, &vr, 1, &x);
            *call = "fmi2SetInteger";
        } else if (spec->set_type[i] == CSFH_BATCH_BOOLEAN) {
            const fmi2Boolean x = values[i] != 0.0 ? fmi2True : fmi2False;
            s = api->SetBoolean(c, &vr, 1, &x);
            *call = "fmi2SetBoolean";
        } else {
            s = api->SetReal(c, &vr, 1, &values[i]);
            *call = "fmi2SetReal";
        }
    }
    if (s <= fmi2Warning) {
        s = api->ExitInitializationMode(c);
        *call = "fmi2ExitInitializationMode";
    }
    return s;
}

/* What a run keeps of its outputs. */
typedef struct {
    const out_groups_t *groups;
    double *result, *record;
    double v[MAX_OUT], max_for_time[MAX_OUT];
} run_outputs_t;

/* The outputs at the communication point k (0: the start) at time t: read, reduced, recorded. */
static fmi2Status outputs_at(const fmi2_api_t *api, fmi2Component c,
                             const csfh_cs_batch_spec_t *spec, run_outputs_t *o, long long k,
                             double t, run_log_t *log)
{
    if (read_outputs(api, c, o->groups, o->v, log) > fmi2Warning) {
        return fmi2Error;
    }
    reduce(spec, o->v, t, k == 0, o->result, o->max_for_time);
    if (o->record != NULL) {
        memcpy(o->record + (size_t)k * spec->n_out, o->v, spec->n_out * sizeof(double));
    }
    return fmi2OK;
}

/* The communication steps of a run, the outputs read after each: fmi2OK or the failure. */
static fmi2Status steps(const fmi2_api_t *api, fmi2Component c, const csfh_cs_batch_spec_t *spec,
                        run_outputs_t *o, long long n_steps, run_log_t *log)
{
    double t = 0.0;
    for (long long k = 0; k < n_steps; k++) {
        /* the times of simulate_cs: min((k + 1) h, t_end), steps t_next - t */
        const double t_grid = (double)(k + 1) * spec->step;
        const double t_next = t_grid <= spec->stop_time ? t_grid : spec->stop_time;
        const fmi2Status s = api->DoStep(c, t, t_next - t, fmi2True);
        if (s > fmi2Warning) {
            call_failed(log, "fmi2DoStep", s);
            return s;
        }
        log->have_warning |= s == fmi2Warning;
        t = t_next;
        if (outputs_at(api, c, spec, o, k + 1, t, log) > fmi2Warning) {
            return fmi2Error;
        }
    }
    return fmi2OK;
}

/* One run; returns its status. */
static int run_one(const fmi2_api_t *api, const csfh_cs_batch_spec_t *spec,
                   const out_groups_t *groups, const double *values, long long n_steps,
                   double *result, double *record, run_log_t *log)
{
    const fmi2CallbackFunctions callbacks = {logger, allocate, free, NULL, log};
    fmi2Component c = api->Instantiate(spec->instance_name, fmi2CoSimulation, spec->guid,
                                       spec->resource_uri, &callbacks, fmi2False, fmi2False);
    if (c == NULL) {
        call_failed(log, "fmi2Instantiate", fmi2Error);
        return CSFH_BATCH_FAILED;
    }
    const char *call = NULL;
    fmi2Status s = initialize(api, c, spec, values, &call);
    if (s > fmi2Warning) {
        call_failed(log, call, s);
        api->FreeInstance(c);
        return CSFH_BATCH_FAILED;
    }
    log->have_warning |= s == fmi2Warning;
    run_outputs_t o = {groups, result, record, {0}, {0}};
    if (outputs_at(api, c, spec, &o, 0, 0.0, log) > fmi2Warning ||
        steps(api, c, spec, &o, n_steps, log) > fmi2Warning) {
        api->FreeInstance(c);
        return CSFH_BATCH_FAILED;
    }
    s = api->Terminate(c);
    api->FreeInstance(c);
    if (s > fmi2Warning) {
        call_failed(log, "fmi2Terminate", s);
        return CSFH_BATCH_FAILED;
    }
    return log->have_warning ? CSFH_BATCH_WARNING : CSFH_BATCH_OK;
}

/* The spec's pointers and its start values: 1 if they are unusable. */
static int bad_arguments(const csfh_cs_batch_spec_t *spec, const double *values,
                         const double *results, const int *status)
{
    if (spec == NULL || spec->binary == NULL || spec->guid == NULL ||
        spec->instance_name == NULL || results == NULL || status == NULL) {
        return 1;
    }
    return spec->n_set > 0 && (values == NULL || spec->set_vr == NULL || spec->set_type == NULL);
}

/* The spec's outputs: 1 if they are unusable (too many, NULL arrays). */
static int bad_outputs(const csfh_cs_batch_spec_t *spec)
{
    return spec->n_out > MAX_OUT ||
           (spec->n_out > 0 && (spec->out_vr == NULL || spec->out_type == NULL ||
                                spec->out_reduce == NULL || spec->out_arg == NULL));
}

/* The spec's arguments and experiment: 0, or -1 with the reason in message. */
static int spec_refused(const csfh_cs_batch_spec_t *spec, const double *values,
                        const double *results, const int *status, char *message, size_t size)
{
    if (bad_arguments(spec, values, results, status) || bad_outputs(spec)) {
        snprintf(message, size, "csfh_cs_batch_run: bad arguments (NULL, or more than 64 outputs)");
        return -1;
    }
    for (size_t j = 0; j < spec->n_out; j++) {
        if (spec->out_reduce[j] == CSFH_BATCH_FIRST_WHEN &&
            (spec->out_arg[j] < 0 || (size_t)spec->out_arg[j] >= spec->n_out)) {
            snprintf(message, size, "csfh_cs_batch_run: output %zu: trigger %d out of range", j,
                     spec->out_arg[j]);
            return -1;
        }
    }
    if (csfh_cs_batch_points(spec->stop_time, spec->step) < 1 || !(spec->tolerance > 0.0)) {
        snprintf(message, size,
                 "csfh_cs_batch_run: bad experiment (stop %g s, step %g s, tolerance %g)",
                 spec->stop_time, spec->step, spec->tolerance);
        return -1;
    }
    return 0;
}

/* The FMU's binary and its functions: the library, or NULL with the reason in message. */
static void *load(const char *binary, fmi2_api_t *api, char *message, size_t size)
{
    void *library = fmu_library_open(binary);
    if (library == NULL) {
        snprintf(message, size, "csfh_cs_batch_run: cannot load %s", binary);
        return NULL;
    }
    const char *missing = fmi2_api_load(api, library, FMI2_API_COMMON | FMI2_API_CS);
    if (missing != NULL) {
        snprintf(message, size, "csfh_cs_batch_run: %s has no %s", binary, missing);
        fmu_library_close(library);
        return NULL;
    }
    return library;
}

long long csfh_cs_batch_run(const csfh_cs_batch_spec_t *spec, size_t n_runs, const double *values,
                            double *results, double *records, int *status, char *messages,
                            size_t message_size)
{
    char local[256];
    const int have_messages = messages != NULL && message_size > 0;
    char *first = have_messages ? messages : local;
    const size_t first_size = have_messages ? message_size : sizeof(local);
    first[0] = '\0';
    fmi2_api_t api;
    void *library = NULL;
    if (spec_refused(spec, values, results, status, first, first_size) != 0 ||
        (library = load(spec->binary, &api, first, first_size)) == NULL) {
        return -1;
    }
    const long long n_points = csfh_cs_batch_points(spec->stop_time, spec->step);
    out_groups_t groups;
    group_outputs(spec, &groups);
    long long failed = 0;
    for (size_t r = 0; r < n_runs; r++) {
        char dummy[1];
        run_log_t log = {have_messages ? messages + r * message_size : dummy,
                         have_messages ? message_size : sizeof(dummy), 0, 0};
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
    return CSFH_BATCH_ABI_VERSION; /* [abi] of variables.toml, as csfh.runners.cs_steps expects */
}
