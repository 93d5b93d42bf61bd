/* A bounded random FMI 2.0 call-sequence driver for one FMU (linked in: cmake/fuzz.cmake builds
 * it with the csfh FMU and with the comb-drive actuator, under ASan + UBSan + LeakSanitizer).
 *
 * Each sequence instantiates a model-exchange and a co-simulation instance and makes up to
 * --calls calls on them: mostly the call a master would make next in the instance's state, with
 * valid arguments ("legal-biased"), otherwise any of the FMI functions with hostile arguments:
 * values out of range, NaN, +-Inf, huge; steps of 0, negative, NaN, +-Inf, huge (1e300) and
 * below the time's resolution; communication points off by ulps or by far; NULL pointers and
 * unknown value references; FMU states corrupted (flipped bytes, NaN/Inf/huge/negative words,
 * invalid ints), truncated, extended, random, of the other interface, other instances' state
 * pointers, freed ones. Seeds are fixed; a run is deterministic (checked: the first sequence is
 * run twice and must give the same trace hash).
 *
 * Invariants checked after every call (any violation prints the last calls and exits 1):
 *   - the status is OK, Warning, Discard or Error; every Error is logged (logStatusError);
 *   - the state machine: a call illegal in the instance's state (the driver's own model of it)
 *     is an Error and changes nothing; a legal call with valid arguments that cannot fail is
 *     accepted, and never answered "illegal call in state X";
 *   - a rejected call (illegal state, bad argument, bad FMU state) leaves the instance exactly
 *     as it was: its serialized FMU state is byte for byte the same before and after, and its
 *     state in the state machine too (for fmi2DoStep, probed with a zero step); evaluation
 *     failures (non-finite derivative, a failed step) leave it usable (restore or reset works);
 *   - no non-finite value is returned with fmi2OK or fmi2Warning (get functions, derivatives,
 *     event indicators, states, nominals, status);
 *   - a successful fmi2DoStep(t, h) ends at exactly t + h, and the time never goes backwards;
 *   - no crash, no sanitizer report, no leak (LeakSanitizer at exit: FMU states are often left
 *     for fmi2FreeInstance), no hang (an alarm per sequence). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, alarm */

#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "fmi2Functions.h"
#include "fmu_instance.h" /* (the tolerances the FMU accepts) */
#include "fmu_model.h"

#define SEQUENCE_ALARM_S 60 /* a sequence that takes longer is a hang */
#define MAX_OWNED 12        /* FMU states held per instance */
#define POOL 6              /* serialized states kept per sequence */
#define TRACE 48            /* calls printed on failure */

/* ------------------------------------------------------------------------------------------ */
/* random numbers (splitmix64) */

static uint64_t rng;

static uint64_t next_u64(void)
{
    uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform(void)
{
    return (double)(next_u64() >> 11) * 0x1.0p-53;
}

static int below(int n)
{
    return (int)(next_u64() % (uint64_t)n);
}

static int chance(double p)
{
    return uniform() < p;
}

/* ------------------------------------------------------------------------------------------ */
/* trace, hash, failure */

static char trace[TRACE][200];
static long trace_count;
static uint64_t trace_hash;
static unsigned long seed_now, sequence_now;

static void hash_bytes(const void *p, size_t n)
{
    const unsigned char *b = (const unsigned char *)p;
    for (size_t i = 0; i < n; i++) {
        trace_hash = (trace_hash ^ b[i]) * 0x100000001B3ull;
    }
}

static int print_trace = 0; /* --trace: print every call */

static void note(const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(trace[trace_count % TRACE], sizeof(trace[0]), fmt, args);
    va_end(args);
    if (print_trace) {
        fprintf(stderr, "%6ld %s\n", trace_count, trace[trace_count % TRACE]);
    }
    trace_count++;
}

static char last_error[1024];

static void fail(const char *fmt, ...)
{
    char msg[400];
    va_list args;
    va_start(args, fmt);
    vsnprintf(msg, sizeof(msg), fmt, args);
    va_end(args);
    fprintf(stderr, "\nFUZZ FAILURE (%s, seed %lu, sequence %lu): %s\nlast FMU error: %s\n"
                    "last calls:\n",
            fmu_model.model_identifier, seed_now, sequence_now, msg, last_error);
    const long first = trace_count > TRACE ? trace_count - TRACE : 0;
    for (long i = first; i < trace_count; i++) {
        fprintf(stderr, "  %6ld %s\n", i, trace[i % TRACE]);
    }
    _exit(1); /* no leak report: the failure is the report */
}

static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "\nFUZZ FAILURE: a sequence did not finish in time (hang)\n";
    ssize_t unused = write(2, msg, sizeof(msg) - 1);
    (void)unused;
    _exit(1);
}

/* ------------------------------------------------------------------------------------------ */
/* the FMU's log */

static long errors_logged;
static char illegal_in[64]; /* "illegal call in state X": X of the last such message */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof(text), message, args); /* the FMU escapes '%' */
    va_end(args);
    if (name == NULL || category == NULL) {
        fail("log line without instance name or category: %s", text);
    }
    if (status >= fmi2Error) {
        errors_logged++;
        snprintf(last_error, sizeof(last_error), "%s", text);
        const char *p = strstr(text, "illegal call in state ");
        if (p != NULL) {
            snprintf(illegal_in, sizeof(illegal_in), "%s", p + strlen("illegal call in state "));
        }
    }
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

/* ------------------------------------------------------------------------------------------ */
/* the driver's model of an instance */

typedef enum {
    M_INSTANTIATED,
    M_INIT,
    M_EVENT,
    M_CONT,
    M_STEP_COMPLETE,
    M_STEP_FAILED,
    M_TERMINATED,
    M_UNKNOWN
} mstate_t;

/* the FMU's own names (fmi2_glue.c, "illegal call in state X") */
static const char *const mstate_name[] = {"Instantiated", "InitializationMode", "EventMode",
                                          "ContinuousTimeMode", "StepComplete", "StepFailed",
                                          "Terminated", "unknown"};

#define BIT(s) (1u << (s))
#define ANY_STATE 0xFFu
#define GET_OK (BIT(M_INIT) | BIT(M_EVENT) | BIT(M_CONT) | BIT(M_STEP_COMPLETE) | BIT(M_STEP_FAILED) | BIT(M_TERMINATED))
#define SET_OK (BIT(M_INSTANTIATED) | BIT(M_INIT) | BIT(M_EVENT) | BIT(M_CONT) | BIT(M_STEP_COMPLETE))

typedef struct {
    fmi2FMUstate ptr;
    mstate_t taken_in; /* M_UNKNOWN: restored from corrupted bytes that were accepted */
} owned_t;

typedef struct {
    fmi2Component c;
    fmi2Type type;
    mstate_t state;
    double me_time; /* model exchange: the time the driver integrates in */
    owned_t owned[MAX_OWNED];
    int n_owned;
} instance_t;

typedef struct {
    unsigned char *bytes;
    size_t size;
    fmi2Type type;
    mstate_t taken_in;
} blob_t;

static instance_t inst[2]; /* [0] model exchange, [1] co-simulation */
static blob_t pool[POOL];
static int n_pool;

/* What the driver predicts for a call. */
typedef enum {
    MUST_ACCEPT, /* legal, valid arguments, cannot fail */
    MAY_REJECT,  /* legal; may fail on the model's own checks, or arguments of unknown validity */
    MUST_REJECT  /* illegal in this state or a bad argument: Error, nothing changes */
} expect_t;

/* Calls whose Error may come from evaluating the model (not a rejection): they may change
 * caches and counters, and fmi2DoStep a failed step changes the state (StepFailed). */
typedef enum { PURE, EVALUATES } call_kind_t;

static int is_legal(const instance_t *in, unsigned int states)
{
    return in->state != M_UNKNOWN && (states & BIT(in->state)) != 0;
}

/* ------------------------------------------------------------------------------------------ */
/* variables and values */

static const csfh_variable_t *time_variable(void)
{
    for (int i = 0; i < fmu_model.n_variables; i++) {
        if (fmu_model.variables[i].causality == CSFH_CAUS_INDEPENDENT) {
            return &fmu_model.variables[i];
        }
    }
    return NULL;
}

static const csfh_variable_t *random_variable(void)
{
    return &fmu_model.variables[below(fmu_model.n_variables)];
}

/* fmi2_glue.c's rule, from FMI 2.0: inputs always; parameters before the end of initialization,
 * tunable ones also in event mode / step complete; the states' start values before it. */
static int settable(const csfh_variable_t *v, mstate_t s)
{
    const int before = s == M_INSTANTIATED || s == M_INIT;
    const int running_event = s == M_EVENT || s == M_STEP_COMPLETE;
    switch (v->causality) {
    case CSFH_CAUS_INPUT:
        return 1;
    case CSFH_CAUS_PARAMETER:
        return before || (v->tunable && running_event);
    case CSFH_CAUS_OUTPUT:
        return v->is_state && before;
    default:
        return 0;
    }
}

static double hostile_double(void)
{
    static const double values[] = {NAN, INFINITY, -INFINITY, 1e308, -1e308, 0.0, -1.0,
                                    1e-300, -1e-300, DBL_MIN, 1e20, -1e20, 77.0, 1e10, 2.0};
    return values[below((int)(sizeof(values) / sizeof(values[0])))];
}

/* A value the variable's table accepts, near its start value. */
static double valid_value(const csfh_variable_t *v)
{
    if (v->type == CSFH_TYPE_BOOLEAN) {
        return (double)below(2);
    }
    if (v->type == CSFH_TYPE_ENUMERATION) {
        return v->lo + (double)below((int)(v->hi - v->lo) + 1);
    }
    const double base = v->has_start ? v->start : v->nominal;
    double x = base != 0.0 ? base * (1.0 + 0.2 * (uniform() - 0.5)) : v->nominal * (uniform() - 0.5);
    if (v->type == CSFH_TYPE_INTEGER) {
        x = round(x);
    }
    char msg[256];
    return csfh_check_value(v, x, msg, sizeof(msg)) == 0 ? x : base;
}

static int value_valid(const csfh_variable_t *v, double x)
{
    char msg[256];
    return csfh_check_value(v, x, msg, sizeof(msg)) == 0;
}

/* ------------------------------------------------------------------------------------------ */
/* fingerprint: the instance's serialized FMU state */

typedef struct {
    unsigned char *bytes;
    size_t size;
} print_t;

static print_t fingerprint(instance_t *in)
{
    print_t p = {NULL, 0};
    fmi2FMUstate s = NULL;
    if (fmi2GetFMUstate(in->c, &s) != fmi2OK || fmi2SerializedFMUstateSize(in->c, s, &p.size) != fmi2OK) {
        fail("fingerprint: fmi2GetFMUstate failed");
    }
    p.bytes = (unsigned char *)malloc(p.size);
    if (p.bytes == NULL || fmi2SerializeFMUstate(in->c, s, (fmi2Byte *)p.bytes, p.size) != fmi2OK) {
        fail("fingerprint: fmi2SerializeFMUstate failed");
    }
    if (fmi2FreeFMUstate(in->c, &s) != fmi2OK || s != NULL) {
        fail("fingerprint: fmi2FreeFMUstate failed");
    }
    return p;
}

/* ------------------------------------------------------------------------------------------ */
/* checks */

static void check_finite(const double *x, size_t n, const char *what, fmi2Status status)
{
    if (status > fmi2Warning) {
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            fail("%s returned %s with a non-finite value [%zu] = %g", what,
                 status == fmi2OK ? "fmi2OK" : "fmi2Warning", i, x[i]);
        }
    }
    hash_bytes(x, n * sizeof(double));
}

/* Every real variable, readable in this state: finite whenever the read is not an Error. */
static void read_all(instance_t *in)
{
    if (!is_legal(in, GET_OK)) {
        return;
    }
    for (int i = 0; i < fmu_model.n_variables; i++) {
        const csfh_variable_t *v = &fmu_model.variables[i];
        if (v->type != CSFH_TYPE_REAL) {
            continue;
        }
        double x = 0.0;
        const fmi2Status s = fmi2GetReal(in->c, &v->vr, 1, &x);
        check_finite(&x, 1, v->name, s);
    }
}

/* The outcome of one call against the prediction. */
static void judge(instance_t *in, const char *call, fmi2Status status, expect_t expect,
                  call_kind_t kind, long errors_before, const print_t *before)
{
    hash_bytes(&status, sizeof(status));
    if (status != fmi2OK && status != fmi2Warning && status != fmi2Discard && status != fmi2Error) {
        fail("%s returned status %d", call, (int)status);
    }
    if (status == fmi2Error && errors_logged == errors_before) {
        fail("%s returned fmi2Error without logging why", call);
    }
    if (expect == MUST_REJECT && status != fmi2Error) {
        fail("%s was accepted (status %d), but it is illegal in state %s or has a bad argument",
             call, (int)status, mstate_name[in->state]);
    }
    if (expect == MUST_ACCEPT && status > fmi2Warning) {
        fail("%s was refused in state %s", call, mstate_name[in->state]);
    }
    if (status == fmi2Error && illegal_in[0] != '\0' && in->state != M_UNKNOWN && expect != MUST_REJECT) {
        fail("%s: the FMU says illegal in state %s, the driver's model says %s", call, illegal_in,
             mstate_name[in->state]);
    }
    if (status == fmi2Error && before != NULL && kind == PURE) {
        print_t after = fingerprint(in);
        if (after.size != before->size || memcmp(after.bytes, before->bytes, after.size) != 0) {
            size_t k = 0;
            while (k < after.size && k < before->size && after.bytes[k] == before->bytes[k]) {
                k++;
            }
            free(after.bytes);
            fail("%s was refused but changed the instance (first differing byte %zu)", call, k);
        }
        free(after.bytes);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* one call */

static double slow_call_s = 0.0; /* --slow: print calls slower than this */
static int huge_left = 2;          /* --huge: steps of 1e300 s left in this run */

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    double started;
    instance_t *in;
    expect_t expect;
    call_kind_t kind;
    long errors_before;
    print_t before;
    int have_before;
} call_t;

/* Before a call: what is expected, and (for a predicted or possible rejection) the fingerprint. */
static call_t begin(instance_t *in, expect_t expect, call_kind_t kind)
{
    call_t c = {0.0, in, expect, kind, errors_logged, {NULL, 0}, 0};
    illegal_in[0] = '\0';
    if (in->c != NULL && (expect == MUST_REJECT || chance(0.15))) {
        c.before = fingerprint(in);
        c.have_before = 1;
    }
    c.errors_before = errors_logged;
    illegal_in[0] = '\0';
    c.started = now_s();
    return c;
}

static void end(call_t *c, const char *call, fmi2Status status)
{
    const double took = now_s() - c->started;
    if (slow_call_s > 0.0 && took > slow_call_s) {
        fprintf(stderr, "slow (%.2f s, status %d, seed %lu, sequence %lu): %s%s%s\n", took,
                (int)status, seed_now, sequence_now, trace[(trace_count - 1) % TRACE],
                status == fmi2Error ? "\n    FMU: " : "", status == fmi2Error ? last_error : "");
    }
    judge(c->in, call, status, c->expect, c->kind, c->errors_before,
          c->have_before ? &c->before : NULL);
    free(c->before.bytes);
    c->before.bytes = NULL;
}

/* After a successful call that moves the state machine (also from an unknown state). */
static void moved(instance_t *in, fmi2Status status, mstate_t to)
{
    if (status <= fmi2Warning) {
        in->state = to;
    }
}

static expect_t legal(const instance_t *in, unsigned int states)
{
    if (in->state == M_UNKNOWN) {
        return MAY_REJECT;
    }
    return (states & BIT(in->state)) ? MUST_ACCEPT : MUST_REJECT;
}

/* Legal, but the model may refuse (evaluation, cross-checks). */
static expect_t may(expect_t e)
{
    return e == MUST_ACCEPT ? MAY_REJECT : e;
}

/* ------------------------------------------------------------------------------------------ */
/* FMU states */

static void forget_owned(instance_t *in, int k)
{
    in->owned[k] = in->owned[--in->n_owned];
}

static void own(instance_t *in, fmi2FMUstate s, mstate_t taken_in)
{
    for (int k = 0; k < in->n_owned; k++) {
        if (in->owned[k].ptr == s) { /* fmi2GetFMUstate into an existing state */
            in->owned[k].taken_in = taken_in;
            return;
        }
    }
    if (in->n_owned == MAX_OWNED) { /* leave the oldest to fmi2FreeInstance */
        fmi2FMUstate old = in->owned[0].ptr;
        call_t c = begin(in, MUST_ACCEPT, PURE);
        note("fmi2FreeFMUstate(%s, old)", in->type == fmi2ModelExchange ? "ME" : "CS");
        end(&c, "fmi2FreeFMUstate", fmi2FreeFMUstate(in->c, &old));
        forget_owned(in, 0);
    }
    in->owned[in->n_owned].ptr = s;
    in->owned[in->n_owned].taken_in = taken_in;
    in->n_owned++;
}

static void do_get_state(instance_t *in)
{
    fmi2FMUstate s = NULL;
    int reuse = in->n_owned > 0 && chance(0.3);
    if (reuse) {
        s = in->owned[below(in->n_owned)].ptr;
    }
    call_t c = begin(in, MUST_ACCEPT, PURE);
    note("fmi2GetFMUstate(%s, %s) in %s", in->type == fmi2ModelExchange ? "ME" : "CS",
         reuse ? "existing" : "new", mstate_name[in->state]);
    const fmi2Status st = fmi2GetFMUstate(in->c, &s);
    end(&c, "fmi2GetFMUstate", st);
    if (st <= fmi2Warning) {
        own(in, s, in->state);
    }
}

static void do_free_state(instance_t *in)
{
    if (in->n_owned == 0 || chance(0.2)) { /* NULL, or a pointer that is not this instance's */
        fmi2FMUstate s = NULL;
        instance_t *other = &inst[in == &inst[0] ? 1 : 0];
        const int foreign = other->n_owned > 0 && chance(0.5);
        if (foreign) {
            s = other->owned[0].ptr;
        }
        call_t c = begin(in, foreign ? MUST_REJECT : MUST_ACCEPT, PURE);
        note("fmi2FreeFMUstate(%s, %s)", in->type == fmi2ModelExchange ? "ME" : "CS",
             foreign ? "another instance's" : "NULL");
        end(&c, "fmi2FreeFMUstate", fmi2FreeFMUstate(in->c, &s));
        return;
    }
    const int k = below(in->n_owned);
    fmi2FMUstate s = in->owned[k].ptr;
    const fmi2FMUstate s_freed = s;
    call_t c = begin(in, MUST_ACCEPT, PURE);
    note("fmi2FreeFMUstate(%s, owned %d)", in->type == fmi2ModelExchange ? "ME" : "CS", k);
    const fmi2Status st = fmi2FreeFMUstate(in->c, &s);
    end(&c, "fmi2FreeFMUstate", st);
    if (s != NULL) {
        fail("fmi2FreeFMUstate did not set the pointer to NULL");
    }
    forget_owned(in, k);
    if (chance(0.3)) { /* the freed pointer again: refused, not read (ASan would see a read) */
        fmi2FMUstate stale = s_freed;
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2SetFMUstate(%s, freed)", in->type == fmi2ModelExchange ? "ME" : "CS");
        end(&c, "fmi2SetFMUstate", fmi2SetFMUstate(in->c, stale));
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2FreeFMUstate(%s, freed)", in->type == fmi2ModelExchange ? "ME" : "CS");
        end(&c, "fmi2FreeFMUstate", fmi2FreeFMUstate(in->c, &stale));
    }
}

static void do_set_state(instance_t *in)
{
    if (in->n_owned == 0 || chance(0.1)) {
        instance_t *other = &inst[in == &inst[0] ? 1 : 0];
        if (other->n_owned == 0) {
            return;
        }
        call_t c = begin(in, MUST_REJECT, PURE);
        note("fmi2SetFMUstate(%s, another instance's)", in->type == fmi2ModelExchange ? "ME" : "CS");
        end(&c, "fmi2SetFMUstate", fmi2SetFMUstate(in->c, other->owned[0].ptr));
        return;
    }
    const owned_t o = in->owned[below(in->n_owned)];
    call_t c = begin(in, o.taken_in == M_UNKNOWN ? MAY_REJECT : MUST_ACCEPT, PURE);
    note("fmi2SetFMUstate(%s, taken in %s) in %s", in->type == fmi2ModelExchange ? "ME" : "CS",
         mstate_name[o.taken_in], mstate_name[in->state]);
    const fmi2Status st = fmi2SetFMUstate(in->c, o.ptr);
    end(&c, "fmi2SetFMUstate", st);
    if (st <= fmi2Warning) {
        in->state = o.taken_in;
        if (in->type == fmi2ModelExchange && is_legal(in, GET_OK)) {
            const csfh_variable_t *tv = time_variable();
            fmi2GetReal(in->c, &tv->vr, 1, &in->me_time);
        }
        read_all(in);
    }
}

static void do_serialize(instance_t *in)
{
    if (in->n_owned == 0) {
        do_get_state(in);
        return;
    }
    const owned_t o = in->owned[below(in->n_owned)];
    size_t size = 0;
    call_t c = begin(in, MUST_ACCEPT, PURE);
    note("fmi2SerializedFMUstateSize(%s)", in->type == fmi2ModelExchange ? "ME" : "CS");
    end(&c, "fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(in->c, o.ptr, &size));
    unsigned char *bytes = (unsigned char *)malloc(size + 1);
    const int small = chance(0.1);
    c = begin(in, small ? MUST_REJECT : MUST_ACCEPT, PURE);
    note("fmi2SerializeFMUstate(%s, size %zu%s)", in->type == fmi2ModelExchange ? "ME" : "CS",
         size, small ? " - 1" : "");
    const fmi2Status st = fmi2SerializeFMUstate(in->c, o.ptr, (fmi2Byte *)bytes, small ? size - 1 : size);
    end(&c, "fmi2SerializeFMUstate", st);
    if (st > fmi2Warning || o.taken_in == M_UNKNOWN) {
        free(bytes);
        return;
    }
    const int slot = n_pool < POOL ? n_pool++ : below(POOL);
    free(pool[slot].bytes);
    pool[slot].bytes = bytes;
    pool[slot].size = size;
    pool[slot].type = in->type;
    pool[slot].taken_in = o.taken_in;
}

/* Mutations of a serialized state; returns 1 if the bytes are certainly not a valid state. */
static int corrupt(unsigned char **bytes, size_t *size)
{
    unsigned char *b = *bytes;
    const size_t n = *size;
    switch (below(10)) {
    case 0: { /* flip 1 to 8 random bytes */
        const int k = 1 + below(8);
        for (int i = 0; i < k; i++) {
            b[below((int)n)] ^= (unsigned char)(1u << below(8));
        }
        return 0;
    }
    case 1: { /* a double word becomes NaN, Inf, huge, negative, ... */
        const double x = hostile_double();
        memcpy(b + below((int)(n - sizeof(double))), &x, sizeof(x));
        return 0;
    }
    case 2: { /* an int word becomes 0, -1, 77, 1 << 20, ... */
        static const int values[] = {0, -1, 77, 1 << 20, 3, 128, 2, -2147483647 - 1};
        const int x = values[below((int)(sizeof(values) / sizeof(values[0])))];
        memcpy(b + 4 * below((int)(n / 4)), &x, sizeof(x));
        return 0;
    }
    case 3: /* truncated */
        *size = (size_t)below((int)n);
        return 1;
    case 4: /* extended */
        *bytes = (unsigned char *)realloc(b, n + 8);
        memset(*bytes + n, 0xAB, 8);
        *size = n + 1 + (size_t)below(8);
        return 1;
    case 5: /* random bytes of the right size */
        for (size_t i = 0; i < n; i++) {
            b[i] = (unsigned char)next_u64();
        }
        return 1;
    case 6: /* the header only (the first 64 bytes kept), the rest zero */
        if (n > 64) {
            memset(b + 64, 0, n - 64);
        }
        return 0;
    case 7: /* the header's first word (magic) broken */
        b[0] ^= 0x5A;
        return 1;
    case 8: { /* another FMU's state: its GUID differs (found by value in the bytes) */
        const size_t len = strlen(fmu_model.guid);
        for (size_t i = 0; i + len <= n; i++) {
            if (memcmp(b + i, fmu_model.guid, len) == 0) {
                b[i + 1 + (size_t)below((int)len - 2)] ^= 0x01;
                return 1;
            }
        }
        fail("the GUID is not in the serialized state");
        return 1;
    }
    default: { /* many doubles across the model */
        for (int i = 0; i < 6; i++) {
            const double x = hostile_double();
            memcpy(b + below((int)(n - sizeof(double))), &x, sizeof(x));
        }
        return 0;
    }
    }
}

static void do_deserialize(instance_t *in)
{
    if (n_pool == 0) {
        do_serialize(in);
        return;
    }
    const blob_t *src = &pool[below(n_pool)];
    size_t size = src->size;
    unsigned char *bytes = (unsigned char *)malloc(size);
    memcpy(bytes, src->bytes, size);
    const int mutate = chance(0.6);
    int certainly_bad = 0;
    if (mutate) {
        certainly_bad = corrupt(&bytes, &size);
    }
    /* a state of the other interface is refused; an unmodified one of this interface restores */
    expect_t expect = MAY_REJECT;
    if (certainly_bad || (!mutate && src->type != in->type)) {
        expect = MUST_REJECT;
    } else if (!mutate) {
        expect = MUST_ACCEPT;
    }
    fmi2FMUstate s = NULL;
    call_t c = begin(in, expect, PURE);
    note("fmi2DeSerializeFMUstate(%s, %zu bytes of a %s state%s)",
         in->type == fmi2ModelExchange ? "ME" : "CS", size,
         src->type == fmi2ModelExchange ? "ME" : "CS", mutate ? ", corrupted" : "");
    const fmi2Status st = fmi2DeSerializeFMUstate(in->c, (const fmi2Byte *)bytes, size, &s);
    end(&c, "fmi2DeSerializeFMUstate", st);
    free(bytes);
    if (st <= fmi2Warning) {
        own(in, s, mutate ? M_UNKNOWN : src->taken_in);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* life cycle and get/set */

static void instantiate(instance_t *in, fmi2Type type)
{
    memset(in, 0, sizeof(*in));
    in->type = type;
    note("fmi2Instantiate(%s)", type == fmi2ModelExchange ? "ME" : "CS");
    in->c = fmi2Instantiate(type == fmi2ModelExchange ? "fuzz-me" : "fuzz-cs", type,
                            fmu_model.guid, "", &callbacks, fmi2False, chance(0.2));
    if (in->c == NULL) {
        fail("fmi2Instantiate failed");
    }
    in->state = M_INSTANTIATED;
}

static void free_instance(instance_t *in)
{
    note("fmi2FreeInstance(%s) with %d FMU states left", in->type == fmi2ModelExchange ? "ME" : "CS",
         in->n_owned);
    fmi2FreeInstance(in->c); /* the FMU states left are the FMU's to free */
    in->c = NULL;
    in->n_owned = 0;
}

static void do_setup(instance_t *in)
{
    const int bad = chance(0.2);
    double tol = bad ? hostile_double() : pow(10.0, -3.0 - 7.0 * uniform());
    double start = chance(0.2) ? (chance(0.5) ? 1e10 : -5.0) : 0.0;
    if (bad && chance(0.5)) {
        start = hostile_double();
        tol = 1e-6;
    }
    const int tol_ok = tol >= FMU_TOLERANCE_MIN && tol < FMU_TOLERANCE_MAX;
    expect_t e = legal(in, BIT(M_INSTANTIATED));
    if (e != MUST_REJECT && (!tol_ok || !isfinite(start))) {
        e = MUST_REJECT;
    }
    call_t c = begin(in, e, PURE);
    note("fmi2SetupExperiment(tol %g, start %g)", tol, start);
    const fmi2Status st = fmi2SetupExperiment(in->c, fmi2True, tol, start, fmi2False, 0.0);
    end(&c, "fmi2SetupExperiment", st);
    if (st <= fmi2Warning) {
        in->me_time = start;
        if (in->state == M_UNKNOWN) {
            in->state = M_INSTANTIATED;
        }
    }
}

static void do_simple(instance_t *in, int which)
{
    fmi2Status st;
    call_t c;
    switch (which) {
    case 0:
        c = begin(in, legal(in, BIT(M_INSTANTIATED)), PURE);
        note("fmi2EnterInitializationMode in %s", mstate_name[in->state]);
        st = fmi2EnterInitializationMode(in->c);
        end(&c, "fmi2EnterInitializationMode", st);
        moved(in, st, M_INIT);
        break;
    case 1: {
        c = begin(in, may(legal(in, BIT(M_INIT))), PURE); /* cross-checks (R1 < R2) */
        note("fmi2ExitInitializationMode in %s", mstate_name[in->state]);
        st = fmi2ExitInitializationMode(in->c);
        end(&c, "fmi2ExitInitializationMode", st);
        moved(in, st, in->type == fmi2ModelExchange ? M_EVENT : M_STEP_COMPLETE);
        if (st <= fmi2Warning) {
            read_all(in);
        }
        break;
    }
    case 2:
        c = begin(in, legal(in, BIT(M_EVENT) | BIT(M_CONT) | BIT(M_STEP_COMPLETE) | BIT(M_STEP_FAILED)), PURE);
        note("fmi2Terminate in %s", mstate_name[in->state]);
        st = fmi2Terminate(in->c);
        end(&c, "fmi2Terminate", st);
        moved(in, st, M_TERMINATED);
        break;
    case 3:
        c = begin(in, MUST_ACCEPT, PURE);
        note("fmi2Reset in %s", mstate_name[in->state]);
        st = fmi2Reset(in->c);
        end(&c, "fmi2Reset", st);
        moved(in, st, M_INSTANTIATED);
        in->me_time = 0.0;
        break;
    default: {
        const unsigned int me_only = in->type == fmi2ModelExchange ? ~0u : 0u;
        if (which == 4) {
            c = begin(in, legal(in, (BIT(M_EVENT) | BIT(M_CONT)) & me_only), PURE);
            note("fmi2EnterEventMode in %s", mstate_name[in->state]);
            st = fmi2EnterEventMode(in->c);
            end(&c, "fmi2EnterEventMode", st);
            moved(in, st, M_EVENT);
        } else if (which == 5) {
            fmi2EventInfo info;
            c = begin(in, legal(in, BIT(M_EVENT) & me_only), PURE);
            note("fmi2NewDiscreteStates in %s", mstate_name[in->state]);
            st = fmi2NewDiscreteStates(in->c, &info);
            end(&c, "fmi2NewDiscreteStates", st);
        } else {
            c = begin(in, legal(in, BIT(M_EVENT) & me_only), PURE);
            note("fmi2EnterContinuousTimeMode in %s", mstate_name[in->state]);
            st = fmi2EnterContinuousTimeMode(in->c);
            end(&c, "fmi2EnterContinuousTimeMode", st);
            moved(in, st, M_CONT);
        }
        break;
    }
    }
}

static void do_get(instance_t *in)
{
    const csfh_variable_t *v = random_variable();
    fmi2ValueReference vr = v->vr;
    const int unknown = chance(0.05);
    if (unknown) {
        vr = 100000u + (fmi2ValueReference)below(1000);
    }
    expect_t e = legal(in, GET_OK);
    if (unknown && e != MAY_REJECT) {
        e = MUST_REJECT;
    }
    fmi2Status st;
    if (v->type == CSFH_TYPE_REAL || unknown) {
        double x = 0.0;
        call_t c = begin(in, may(e), EVALUATES);
        note("fmi2GetReal(%s) in %s", unknown ? "unknown" : v->name, mstate_name[in->state]);
        st = fmi2GetReal(in->c, &vr, 1, &x);
        end(&c, "fmi2GetReal", st);
        check_finite(&x, 1, "fmi2GetReal", st);
    } else if (v->type == CSFH_TYPE_BOOLEAN) {
        fmi2Boolean x = 0;
        call_t c = begin(in, may(e), EVALUATES);
        note("fmi2GetBoolean(%s) in %s", v->name, mstate_name[in->state]);
        st = fmi2GetBoolean(in->c, &vr, 1, &x);
        end(&c, "fmi2GetBoolean", st);
    } else {
        fmi2Integer x = 0;
        call_t c = begin(in, may(e), EVALUATES);
        note("fmi2GetInteger(%s) in %s", v->name, mstate_name[in->state]);
        st = fmi2GetInteger(in->c, &vr, 1, &x);
        end(&c, "fmi2GetInteger", st);
    }
}

static void do_set(instance_t *in, int valid_bias)
{
    const csfh_variable_t *v = random_variable();
    if (valid_bias) { /* a variable this state can set, if there is one */
        for (int tries = 0; tries < 20 && !settable(v, in->state); tries++) {
            v = random_variable();
        }
    }
    const int hostile = !valid_bias || chance(0.15);
    const double x = hostile ? hostile_double() : valid_value(v);
    /* the value the setter of the variable's type passes */
    const fmi2Boolean b = isfinite(x) && x != 0.0 ? fmi2True : fmi2False;
    const fmi2Integer k = isfinite(x) && fabs(x) < 2e9 ? (fmi2Integer)x : 77;
    const double applied = v->type == CSFH_TYPE_REAL ? x
                           : v->type == CSFH_TYPE_BOOLEAN ? (double)b : (double)k;
    expect_t e = legal(in, SET_OK);
    if (e == MUST_ACCEPT) {
        const int running = !(in->state == M_INSTANTIATED || in->state == M_INIT);
        if (!settable(v, in->state) || !value_valid(v, applied)) {
            e = MUST_REJECT;
        } else if (v->causality == CSFH_CAUS_PARAMETER && running) {
            e = MAY_REJECT; /* a tunable parameter while running: the model's cross-checks */
        }
    }
    fmi2Status st;
    const fmi2ValueReference vr = v->vr;
    if (v->type == CSFH_TYPE_REAL) {
        call_t c = begin(in, e, PURE);
        note("fmi2SetReal(%s = %g) in %s", v->name, x, mstate_name[in->state]);
        st = fmi2SetReal(in->c, &vr, 1, &x);
        end(&c, "fmi2SetReal", st);
    } else if (v->type == CSFH_TYPE_BOOLEAN) {
        call_t c = begin(in, e, PURE);
        note("fmi2SetBoolean(%s = %d) in %s", v->name, b, mstate_name[in->state]);
        st = fmi2SetBoolean(in->c, &vr, 1, &b);
        end(&c, "fmi2SetBoolean", st);
    } else {
        call_t c = begin(in, e, PURE);
        note("fmi2SetInteger(%s = %d) in %s", v->name, k, mstate_name[in->state]);
        st = fmi2SetInteger(in->c, &vr, 1, &k);
        end(&c, "fmi2SetInteger", st);
    }
    if (st <= fmi2Warning && is_legal(in, GET_OK) && chance(0.3)) {
        read_all(in);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* co-simulation */

static double current_time(instance_t *in)
{
    double t = NAN;
    const csfh_variable_t *tv = time_variable();
    if (tv != NULL && is_legal(in, GET_OK)) {
        fmi2GetReal(in->c, &tv->vr, 1, &t);
    }
    return t;
}

static double ulp_of(double t)
{
    return nextafter(fabs(t), INFINITY) - fabs(t);
}

static void do_step(instance_t *in, int valid_bias)
{
    const double T = current_time(in);
    double t = isfinite(T) ? T : 0.0;
    double h = pow(10.0, -4.0 + 3.0 * uniform());
    int bad_point = 0;
    if (!valid_bias || chance(0.2)) {
        switch (below(8)) {
        case 0:
            h = 0.0;
            break;
        case 1:
            h = -h;
            break;
        case 2:
            h = chance(0.5) ? NAN : (chance(0.5) ? INFINITY : -INFINITY);
            break;
        case 3: /* huge: 1e300 s runs into the FMU's limit of CVODE steps per call (seconds under
                 * the sanitizers), so only --huge of them per run; otherwise 1 s */
            h = huge_left > 0 ? 1e300 : 1.0;
            huge_left -= huge_left > 0;
            break;
        case 4:
            h = 1e-300;
            break;
        case 5: /* a few ulps off: round-off, accepted */
            t = t + (double)(below(9) - 4) * ulp_of(t);
            break;
        case 6: /* behind or ahead by far more than round-off */
            t = t + (chance(0.5) ? -1.0 : 1.0) * (1e-9 * (1.0 + fabs(t)));
            bad_point = 1;
            break;
        default:
            t = NAN;
            bad_point = 1;
            break;
        }
    }
    expect_t e = legal(in, in->type == fmi2CoSimulation ? BIT(M_STEP_COMPLETE) : 0u);
    const double t_end = t + h;
    /* the documented rule: the FMU's time T up to 16 DBL_EPSILON max(|t|, |T|) */
    if (isfinite(T) && !(fabs(t - T) <= 16.0 * DBL_EPSILON * fmax(fabs(t), fabs(T)))) {
        bad_point = 1;
    }
    if (e != MUST_REJECT && isfinite(T)) {
        if (bad_point || !isfinite(h) || h < 0.0 || (h > 0.0 && !(isfinite(t_end) && t_end > T))) {
            e = MUST_REJECT;
        } else if (h > 0.0) {
            e = MAY_REJECT; /* the integration may fail */
        }
    } else if (e != MUST_REJECT) {
        e = MAY_REJECT;
    }
    const mstate_t was = in->state;
    call_t c = begin(in, e, e == MUST_REJECT ? PURE : EVALUATES);
    note("fmi2DoStep(%.17g, %g) at T = %.17g in %s", t, h, T, mstate_name[in->state]);
    const fmi2Status st = fmi2DoStep(in->c, t, h, fmi2True);
    end(&c, "fmi2DoStep", st);
    if (st <= fmi2Warning) {
        in->state = M_STEP_COMPLETE;
        const double after = current_time(in);
        if (h > 0.0 && after != t_end) {
            fail("fmi2DoStep(%.17g, %g) ended at %.17g, not at t + h = %.17g", t, h, after, t_end);
        }
        if (isfinite(T) && after < T) {
            fail("the time went backwards: %.17g -> %.17g", T, after);
        }
        read_all(in);
    } else if (was == M_STEP_COMPLETE && e != MUST_REJECT) {
        /* refused or failed? A zero step at the FMU's time is legal only in StepComplete */
        const double now = current_time(in);
        illegal_in[0] = '\0';
        const fmi2Status probe = fmi2DoStep(in->c, now, 0.0, fmi2True);
        in->state = probe == fmi2OK ? M_STEP_COMPLETE : M_STEP_FAILED;
        if (in->state == M_STEP_FAILED && strcmp(illegal_in, "StepFailed") != 0) {
            fail("after a failed step the FMU is neither in StepComplete nor in StepFailed (%s)",
                 illegal_in);
        }
        read_all(in); /* reading is allowed after a failure, and finite */
    }
    if (st > fmi2Warning && e == MUST_REJECT && was == M_STEP_COMPLETE) {
        const double now = current_time(in);
        if (fmi2DoStep(in->c, now, 0.0, fmi2True) != fmi2OK) {
            fail("a refused fmi2DoStep left the instance unable to step");
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* model exchange */

static void do_me(instance_t *in, int valid_bias)
{
    const size_t n = (size_t)fmu_model.n_states;
    const size_t ni = (size_t)fmu_model.n_event_indicators;
    double x[64], dx[64], z[64];
    const int me = in->type == fmi2ModelExchange;
    const unsigned int me_only = me ? ~0u : 0u;
    fmi2Status st;
    call_t c;
    switch (below(6)) {
    case 0: { /* time */
        const double h = valid_bias ? pow(10.0, -6.0 + 4.0 * uniform()) : hostile_double();
        const double t = in->me_time + h;
        expect_t e = legal(in, (BIT(M_EVENT) | BIT(M_CONT)) & me_only);
        if (e == MUST_ACCEPT && !isfinite(t)) {
            e = MUST_REJECT;
        }
        c = begin(in, e, PURE);
        note("fmi2SetTime(%.17g) in %s", t, mstate_name[in->state]);
        st = fmi2SetTime(in->c, t);
        end(&c, "fmi2SetTime", st);
        if (st <= fmi2Warning) {
            in->me_time = t;
        }
        break;
    }
    case 1: { /* an explicit Euler step of the states */
        c = begin(in, legal(in, GET_OK & me_only), PURE);
        note("fmi2GetContinuousStates in %s", mstate_name[in->state]);
        st = fmi2GetContinuousStates(in->c, x, n);
        end(&c, "fmi2GetContinuousStates", st);
        check_finite(x, n, "fmi2GetContinuousStates", st);
        if (st > fmi2Warning) {
            break;
        }
        c = begin(in, may(legal(in, GET_OK & me_only)), EVALUATES);
        note("fmi2GetDerivatives in %s", mstate_name[in->state]);
        st = fmi2GetDerivatives(in->c, dx, n);
        end(&c, "fmi2GetDerivatives", st);
        check_finite(dx, n, "fmi2GetDerivatives", st);
        if (st > fmi2Warning) {
            break;
        }
        const double h = pow(10.0, -6.0 + 3.0 * uniform());
        int finite = 1;
        for (size_t i = 0; i < n; i++) {
            x[i] += h * dx[i];
            if (!valid_bias && chance(0.3)) {
                x[i] = hostile_double();
            }
            finite = finite && isfinite(x[i]);
        }
        expect_t e = legal(in, BIT(M_CONT) & me_only);
        if (e == MUST_ACCEPT && !finite) {
            e = MUST_REJECT;
        }
        c = begin(in, e, PURE);
        note("fmi2SetContinuousStates(%s) in %s", finite ? "finite" : "non-finite",
             mstate_name[in->state]);
        st = fmi2SetContinuousStates(in->c, x, n);
        end(&c, "fmi2SetContinuousStates", st);
        break;
    }
    case 2: {
        fmi2Boolean enter = fmi2False, terminate = fmi2False;
        c = begin(in, legal(in, BIT(M_CONT) & me_only), PURE);
        note("fmi2CompletedIntegratorStep in %s", mstate_name[in->state]);
        st = fmi2CompletedIntegratorStep(in->c, fmi2True, &enter, &terminate);
        end(&c, "fmi2CompletedIntegratorStep", st);
        break;
    }
    case 3:
        c = begin(in, may(legal(in, GET_OK & me_only)), EVALUATES);
        note("fmi2GetEventIndicators in %s", mstate_name[in->state]);
        st = fmi2GetEventIndicators(in->c, z, ni);
        end(&c, "fmi2GetEventIndicators", st);
        check_finite(z, ni, "fmi2GetEventIndicators", st);
        break;
    case 4:
        c = begin(in, legal(in, ANY_STATE & me_only), PURE);
        note("fmi2GetNominalsOfContinuousStates in %s", mstate_name[in->state]);
        st = fmi2GetNominalsOfContinuousStates(in->c, x, n);
        end(&c, "fmi2GetNominalsOfContinuousStates", st);
        check_finite(x, n, "fmi2GetNominalsOfContinuousStates", st);
        break;
    default: /* wrong sizes */
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2GetDerivatives(nx = %zu) in %s", n + 1, mstate_name[in->state]);
        st = fmi2GetDerivatives(in->c, dx, n + 1);
        end(&c, "fmi2GetDerivatives", st);
        break;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* rare calls: NULL arguments, unsupported functions, statuses, logging */

static void do_rare(instance_t *in)
{
    fmi2Status st;
    call_t c;
    const fmi2ValueReference vr = fmu_model.variables[0].vr;
    switch (below(8)) {
    case 0:
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2GetReal(value = NULL)");
        st = fmi2GetReal(in->c, &vr, 1, NULL);
        end(&c, "fmi2GetReal", st);
        break;
    case 1:
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2SetReal(vr = NULL)");
        st = fmi2SetReal(in->c, NULL, 1, (const fmi2Real[]){1.0});
        end(&c, "fmi2SetReal", st);
        break;
    case 2: {
        /* the time is no unknown; the model's own unknowns and knowns may be refused only by
         * the state (or the interface: co-simulation knows inputs only) */
        double x = 0.0, d[2] = {0.0, 0.0};
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2GetDirectionalDerivative(time)");
        st = fmi2GetDirectionalDerivative(in->c, &vr, 1, &vr, 1, &x, &x);
        end(&c, "fmi2GetDirectionalDerivative", st);
        if (fmu_model.n_jac_unknowns > 0) {
            const fmi2ValueReference u[2] = {fmu_model.jac_unknowns[below(fmu_model.n_jac_unknowns)],
                                             fmu_model.jac_unknowns[below(fmu_model.n_jac_unknowns)]};
            const fmi2ValueReference k = fmu_model.jac_knowns[below(fmu_model.n_jac_knowns)];
            const double seed = 1.0;
            c = begin(in, may(legal(in, GET_OK)), EVALUATES);
            note("fmi2GetDirectionalDerivative in %s", mstate_name[in->state]);
            st = fmi2GetDirectionalDerivative(in->c, u, 2, &k, 1, &seed, d);
            end(&c, "fmi2GetDirectionalDerivative", st);
            if (st <= fmi2Warning) {
                check_finite(d, 2, "fmi2GetDirectionalDerivative", st);
            }
        }
        break;
    }
    case 3: {
        double t = 0.0;
        c = begin(in, MAY_REJECT, PURE);
        note("fmi2GetRealStatus(LastSuccessfulTime)");
        st = fmi2GetRealStatus(in->c, fmi2LastSuccessfulTime, &t);
        end(&c, "fmi2GetRealStatus", st);
        check_finite(&t, 1, "fmi2GetRealStatus", st);
        break;
    }
    case 4: {
        const fmi2String categories[] = {"logEvents", chance(0.5) ? "logAll" : "noSuchCategory"};
        c = begin(in, MAY_REJECT, PURE);
        note("fmi2SetDebugLogging(%s)", categories[1]);
        st = fmi2SetDebugLogging(in->c, chance(0.5), 2, categories);
        end(&c, "fmi2SetDebugLogging", st);
        break;
    }
    case 5: /* no instance at all */
        note("fmi2* with a NULL instance");
        if (fmi2DoStep(NULL, 0.0, 1e-3, fmi2True) != fmi2Error ||
            fmi2SetFMUstate(NULL, NULL) != fmi2Error || fmi2Reset(NULL) != fmi2Error ||
            fmi2GetReal(NULL, &vr, 1, (fmi2Real[]){0.0}) != fmi2Error) {
            fail("a call with a NULL instance was not an error");
        }
        fmi2FreeInstance(NULL);
        break;
    case 6: {
        fmi2Status s = fmi2OK;
        c = begin(in, MAY_REJECT, PURE);
        note("fmi2GetStatus");
        st = fmi2GetStatus(in->c, fmi2DoStepStatus, &s);
        end(&c, "fmi2GetStatus", st);
        break;
    }
    default:
        c = begin(in, MUST_REJECT, PURE);
        note("fmi2CancelStep");
        st = fmi2CancelStep(in->c);
        end(&c, "fmi2CancelStep", st);
        break;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* the sequences */

/* The call a master would make next in this state (valid arguments), or any call. */
static void one_call(instance_t *in)
{
    const int natural = chance(0.75);
    if (chance(0.12)) { /* FMU states, in any state */
        switch (below(5)) {
        case 0:
            do_get_state(in);
            break;
        case 1:
            do_set_state(in);
            break;
        case 2:
            do_free_state(in);
            break;
        case 3:
            do_serialize(in);
            break;
        default:
            do_deserialize(in);
            break;
        }
        return;
    }
    if (!natural) {
        switch (below(9)) {
        case 0:
            do_setup(in);
            break;
        case 1:
            do_simple(in, below(7));
            break;
        case 2:
            do_get(in);
            break;
        case 3:
        case 4:
            do_set(in, 0);
            break;
        case 5:
            do_step(in, 0);
            break;
        case 6:
            do_me(in, 0);
            break;
        case 7:
            do_rare(in);
            break;
        default:
            do_simple(in, 3); /* reset */
            break;
        }
        return;
    }
    switch (in->state) {
    case M_INSTANTIATED:
        if (chance(0.3)) {
            do_setup(in);
        } else if (chance(0.4)) {
            do_set(in, 1);
        } else {
            do_simple(in, 0);
        }
        break;
    case M_INIT:
        if (chance(0.5)) {
            do_set(in, 1);
        } else if (chance(0.2)) {
            do_get(in);
        } else {
            do_simple(in, 1);
        }
        break;
    case M_EVENT:
        if (chance(0.3)) {
            do_simple(in, 5);
        } else if (chance(0.2)) {
            do_set(in, 1);
        } else if (chance(0.2)) {
            do_get(in);
        } else {
            do_simple(in, 6);
        }
        break;
    case M_CONT:
        if (chance(0.08)) {
            do_simple(in, 4);
        } else if (chance(0.1)) {
            do_get(in);
        } else {
            do_me(in, 1);
        }
        break;
    case M_STEP_COMPLETE:
        if (chance(0.6)) {
            do_step(in, 1);
        } else if (chance(0.5)) {
            do_set(in, 1);
        } else {
            do_get(in);
        }
        break;
    case M_STEP_FAILED:
        if (in->n_owned > 0 && chance(0.6)) {
            do_set_state(in);
        } else if (chance(0.5)) {
            do_get(in);
        } else {
            do_simple(in, 3);
        }
        break;
    case M_TERMINATED:
        if (chance(0.5)) {
            do_simple(in, 3);
        } else {
            do_get(in);
        }
        break;
    default: /* unknown (a corrupted state was accepted): reset or restore */
        if (in->n_owned > 0 && chance(0.5)) {
            do_set_state(in);
        } else if (chance(0.5)) {
            do_get(in);
        } else {
            do_simple(in, 3);
        }
        break;
    }
}

static void sequence(int calls)
{
    alarm(SEQUENCE_ALARM_S);
    instantiate(&inst[0], fmi2ModelExchange);
    instantiate(&inst[1], fmi2CoSimulation);
    n_pool = 0;
    for (int k = 0; k < calls; k++) {
        instance_t *in = &inst[below(2)];
        if (chance(0.004)) { /* a new instance (the old one's FMU states are left to it) */
            const fmi2Type type = in->type;
            free_instance(in);
            instantiate(in, type);
            continue;
        }
        one_call(in);
    }
    for (int i = 0; i < 2; i++) {
        while (inst[i].n_owned > 0 && chance(0.5)) { /* free some, leave the rest */
            fmi2FMUstate s = inst[i].owned[0].ptr;
            if (fmi2FreeFMUstate(inst[i].c, &s) != fmi2OK) {
                fail("fmi2FreeFMUstate of an owned state failed at the end");
            }
            forget_owned(&inst[i], 0);
        }
        free_instance(&inst[i]);
    }
    for (int i = 0; i < n_pool; i++) {
        free(pool[i].bytes);
        pool[i].bytes = NULL;
    }
    n_pool = 0;
    alarm(0);
}

static uint64_t run_sequence(unsigned long seed, unsigned long s, int calls)
{
    seed_now = seed;
    sequence_now = s;
    rng = seed * 0x9E3779B97F4A7C15ull; /* independent streams for (seed, sequence) */
    rng = next_u64() ^ ((s + 1) * 0xD1B54A32D192ED03ull);
    rng = next_u64();
    trace_hash = 0xCBF29CE484222325ull;
    sequence(calls);
    return trace_hash;
}

int main(int argc, char **argv)
{
    unsigned long seed_first = 1, seed_last = 4, sequences = 20;
    int calls = 150;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--seeds") == 0 && i + 2 < argc) {
            seed_first = strtoul(argv[i + 1], NULL, 10);
            seed_last = strtoul(argv[i + 2], NULL, 10);
            i += 2;
        } else if (strcmp(argv[i], "--sequences") == 0 && i + 1 < argc) {
            sequences = strtoul(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--calls") == 0 && i + 1 < argc) {
            calls = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--trace") == 0) {
            print_trace = 1;
        } else if (strcmp(argv[i], "--huge") == 0 && i + 1 < argc) {
            huge_left = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--slow") == 0 && i + 1 < argc) {
            slow_call_s = atof(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--seeds FIRST LAST] [--sequences N] [--calls M] [--huge N] "
                            "[--slow SECONDS] [--trace]\n", argv[0]);
            return 2;
        }
    }
    signal(SIGALRM, on_alarm);
    /* the first sequence runs twice (determinism), without huge steps: they are costly */
    const int huge_budget = huge_left;
    huge_left = 0;
    const uint64_t first_hash = run_sequence(seed_first, 0, calls);
    huge_left = huge_budget;
    for (unsigned long seed = seed_first; seed <= seed_last; seed++) {
        for (unsigned long s = seed == seed_first ? 1 : 0; s < sequences; s++) {
            run_sequence(seed, s, calls);
        }
    }
    huge_left = 0;
    if (run_sequence(seed_first, 0, calls) != first_hash) {
        seed_now = seed_first;
        sequence_now = 0;
        fail("the same seed gave a different trace the second time");
    }
    printf("%s: %lu seeds x %lu sequences x %d calls: no invariant broken (%ld calls, %ld FMU "
           "errors logged)\n",
           fmu_model.model_identifier, seed_last - seed_first + 1, sequences, calls, trace_count,
           errors_logged);
    return 0;
}
