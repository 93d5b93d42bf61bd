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

/* x against the extreme so far (first: there is none yet), for the largest (sign 1) or the
 * smallest (sign -1) value. */
static inline double extreme(double x, double acc, int first, double sign)
{
    return first || sign * x > sign * acc ? x : acc;
}

static inline void first_when(double x, int first, double trigger, double *acc)
{
    *acc = first ? NAN : *acc;
    *acc = isnan(*acc) && trigger > 0.0 ? x : *acc;
}

static inline void time_of_max(double x, double t, int first, double *acc, double *held)
{
    if (first || x > *held) {
        *held = x;
        *acc = t;
    }
}

/* One output's reduction at a communication point: its value x at time t (first: the start)
 * into acc (held: the largest value so far, for the time of the maximum; trigger: the value of
 * the output it waits for). */
static inline void reduce_one(int how, double x, double t, int first, double trigger,
                              double *acc, double *held)
{
    switch (how) {
    case CSFH_BATCH_MAX:
        *acc = extreme(x, *acc, first, 1.0);
        break;
    case CSFH_BATCH_MIN:
        *acc = extreme(x, *acc, first, -1.0);
        break;
    case CSFH_BATCH_ABSMAX:
        *acc = extreme(fabs(x), *acc, first, 1.0);
        break;
    case CSFH_BATCH_FIRST_WHEN:
        first_when(x, first, trigger, acc);
        break;
    case CSFH_BATCH_TIME_OF_MAX:
        time_of_max(x, t, first, acc, held);
        break;
    default: /* CSFH_BATCH_FINAL, and an unknown reduction: the final value */
        *acc = x;
        break;
    }
}

/* A set of outputs read together: each value reference once per type (an output reduced two
 * ways is read once), in one call per type. */
typedef struct {
    size_t n_vr[3];                    /* per type: how many references */
    fmi2ValueReference vr[3][MAX_OUT]; /* per type: the references */
    size_t n;                          /* the outputs of the set */
    size_t out[MAX_OUT];               /* their places among the outputs */
    int type[MAX_OUT];                 /* their types (0 Real, 1 Integer, 2 Boolean) */
    size_t slot[MAX_OUT];              /* their places among the references of their type */
} out_set_t;

static int type_index(int type)
{
    return type == CSFH_BATCH_INTEGER ? 1 : type == CSFH_BATCH_BOOLEAN ? 2 : 0;
}

static void set_add(out_set_t *s, fmi2ValueReference vr, int type, size_t j)
{
    size_t slot = 0;
    while (slot < s->n_vr[type] && s->vr[type][slot] != vr) {
        slot++;
    }
    if (slot == s->n_vr[type]) {
        s->vr[type][s->n_vr[type]++] = vr;
    }
    s->out[s->n] = j;
    s->type[s->n] = type;
    s->slot[s->n++] = slot;
}

/* The outputs as a run reads them: at every communication point those whose reduction needs
 * every point (and the triggers they wait for), once at the stop time those that are only
 * final values; with a record, all of them at every point. Outputs do not feed back into the
 * integration, so a value read only at the end is the one a read at every point ends with. */
typedef struct {
    out_set_t every, last;
} out_plan_t;

static void plan_outputs(const csfh_cs_batch_spec_t *spec, int record, out_plan_t *p)
{
    memset(p, 0, sizeof(*p));
    int every[MAX_OUT] = {0};
    for (size_t j = 0; j < spec->n_out; j++) {
        if (record || spec->out_reduce[j] != CSFH_BATCH_FINAL) {
            every[j] = 1;
        }
        if (spec->out_reduce[j] == CSFH_BATCH_FIRST_WHEN) {
            every[spec->out_arg[j]] = 1;
        }
    }
    for (size_t j = 0; j < spec->n_out; j++) {
        set_add(every[j] ? &p->every : &p->last, spec->out_vr[j], type_index(spec->out_type[j]),
                j);
    }
}

/* Read the outputs of a set into v (converted to double). */
static fmi2Status read_set(const fmi2_api_t *api, fmi2Component c, const out_set_t *set,
                           double *v, run_log_t *log)
{
    double reals[MAX_OUT];
    fmi2Integer ints[MAX_OUT];
    fmi2Boolean bools[MAX_OUT];
    fmi2Status s[3] = {fmi2OK, fmi2OK, fmi2OK};
    if (set->n_vr[0] > 0) {
        s[0] = api->GetReal(c, set->vr[0], set->n_vr[0], reals);
    }
    if (set->n_vr[1] > 0 && s[0] <= fmi2Warning) {
        s[1] = api->GetInteger(c, set->vr[1], set->n_vr[1], ints);
    }
    if (set->n_vr[2] > 0 && s[0] <= fmi2Warning && s[1] <= fmi2Warning) {
        s[2] = api->GetBoolean(c, set->vr[2], set->n_vr[2], bools);
    }
    static const char *const calls[3] = {"fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean"};
    for (int t = 0; t < 3; t++) {
        if (s[t] > fmi2Warning) {
            call_failed(log, calls[t], s[t]);
            return s[t];
        }
        log->have_warning |= s[t] == fmi2Warning;
    }
    for (size_t i = 0; i < set->n; i++) {
        const size_t k = set->slot[i];
        v[set->out[i]] = set->type[i] == 0   ? reals[k]
                         : set->type[i] == 1 ? (double)ints[k]
                                             : (bools[k] ? 1.0 : 0.0);
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
    const out_plan_t *plan;
    long long n_steps; /* the communication steps: the last point is k = n_steps */
    double *result, *record;
    double v[MAX_OUT], max_for_time[MAX_OUT];
} run_outputs_t;

/* The outputs at the communication point k (0: the start) at time t: read, reduced, recorded;
 * at the last point also those read only there (their final values). */
static fmi2Status outputs_at(const fmi2_api_t *api, fmi2Component c,
                             const csfh_cs_batch_spec_t *spec, run_outputs_t *o, long long k,
                             double t, run_log_t *log)
{
    const out_set_t *every = &o->plan->every;
    if (read_set(api, c, every, o->v, log) > fmi2Warning) {
        return fmi2Error;
    }
    for (size_t i = 0; i < every->n; i++) {
        const size_t j = every->out[i];
        const int how = spec->out_reduce[j];
        const double trigger = how == CSFH_BATCH_FIRST_WHEN ? o->v[spec->out_arg[j]] : 0.0;
        reduce_one(how, o->v[j], t, k == 0, trigger, &o->result[j], &o->max_for_time[j]);
    }
    if (k == o->n_steps && o->plan->last.n > 0) {
        const out_set_t *last = &o->plan->last;
        if (read_set(api, c, last, o->v, log) > fmi2Warning) {
            return fmi2Error;
        }
        for (size_t i = 0; i < last->n; i++) {
            o->result[last->out[i]] = o->v[last->out[i]];
        }
    }
    if (o->record != NULL) {
        memcpy(o->record + (size_t)k * spec->n_out, o->v, spec->n_out * sizeof(double));
    }
    return fmi2OK;
}

/* The communication steps of a run, the outputs read after each: fmi2OK or the failure. */
static fmi2Status steps(const fmi2_api_t *api, fmi2Component c, const csfh_cs_batch_spec_t *spec,
                        run_outputs_t *o, run_log_t *log)
{
    double t = 0.0;
    for (long long k = 0; k < o->n_steps; k++) {
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

/* The FMU instance a batch's runs share: one instance, reset between runs (fmi2Reset puts it
 * back as fmi2Instantiate leaves it: start values, no integration), made anew after a failed
 * run. Its log goes to `log`, which each run points at its own message. */
typedef struct {
    const fmi2_api_t *api;
    const csfh_cs_batch_spec_t *spec;
    fmi2CallbackFunctions callbacks;
    run_log_t log;
    fmi2Component c; /* NULL: none yet */
} batch_instance_t;

/* The instance, ready for a run (NULL: it could not be made, the failure in the run's log). */
static fmi2Component fresh_instance(batch_instance_t *b)
{
    const fmi2_api_t *api = b->api;
    if (b->c != NULL && (api->Reset == NULL || api->Reset(b->c) > fmi2Warning)) {
        api->FreeInstance(b->c);
        b->c = NULL;
    }
    if (b->c == NULL) {
        b->c = api->Instantiate(b->spec->instance_name, fmi2CoSimulation, b->spec->guid,
                                b->spec->resource_uri, &b->callbacks, fmi2False, fmi2False);
    }
    if (b->c == NULL) {
        call_failed(&b->log, "fmi2Instantiate", fmi2Error);
    }
    return b->c;
}

/* The end of a run on the shared instance: its status; a failed run's instance is freed. */
static int end_run(batch_instance_t *b, int failed)
{
    if (!failed) {
        const fmi2Status s = b->api->Terminate(b->c);
        if (s > fmi2Warning) {
            call_failed(&b->log, "fmi2Terminate", s);
            failed = 1;
        }
    }
    if (failed) {
        b->api->FreeInstance(b->c);
        b->c = NULL;
        return CSFH_BATCH_FAILED;
    }
    return b->log.have_warning ? CSFH_BATCH_WARNING : CSFH_BATCH_OK;
}

/* One run on the shared instance; returns its status. */
static int run_one(batch_instance_t *b, const double *values, run_outputs_t *o)
{
    const fmi2_api_t *api = b->api;
    const fmi2Component c = fresh_instance(b);
    if (c == NULL) {
        return CSFH_BATCH_FAILED;
    }
    const char *call = NULL;
    const fmi2Status s = initialize(api, c, b->spec, values, &call);
    if (s > fmi2Warning) {
        call_failed(&b->log, call, s);
        return end_run(b, 1);
    }
    b->log.have_warning |= s == fmi2Warning;
    const int failed = outputs_at(api, c, b->spec, o, 0, 0.0, &b->log) > fmi2Warning ||
                       steps(api, c, b->spec, o, &b->log) > fmi2Warning;
    return end_run(b, failed);
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
    out_plan_t plan;
    plan_outputs(spec, records != NULL, &plan);
    batch_instance_t b = {&api, spec, {logger, allocate, free, NULL, &b.log}, {NULL, 0, 0, 0},
                          NULL};
    long long failed = 0;
    char dummy[1]; /* the log of a run without a message buffer */
    for (size_t r = 0; r < n_runs; r++) {
        const run_log_t log = {have_messages ? messages + r * message_size : dummy,
                               have_messages ? message_size : sizeof(dummy), 0, 0};
        b.log = log;
        b.log.message[0] = '\0';
        run_outputs_t o = {&plan, n_points - 1, results + r * spec->n_out,
                           records != NULL ? records + r * (size_t)n_points * spec->n_out : NULL,
                           {0}, {0}};
        status[r] = run_one(&b, values != NULL ? values + r * spec->n_set : NULL, &o);
        if (status[r] == CSFH_BATCH_FAILED) {
            for (size_t j = 0; j < spec->n_out; j++) {
                o.result[j] = NAN;
            }
            failed++;
        }
    }
    if (b.c != NULL) {
        api.FreeInstance(b.c);
    }
    fmu_library_close(library);
    return failed;
}

int csfh_cs_batch_abi_version(void)
{
    return CSFH_BATCH_ABI_VERSION; /* [abi] of variables.toml, as csfh.runners.cs_steps expects */
}
