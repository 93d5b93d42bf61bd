/* A bounded random FMI 3.0 call-sequence driver for one FMU (linked in: cmake/fuzz.cmake builds
 * it with the csfh FMU's and the comb-drive actuator's FMI 3.0 front-end, under ASan + UBSan +
 * LeakSanitizer). The FMI 2.0 driver (fuzz_fmi.c) covers the shared instance in depth; this one
 * covers what the FMI 3.0 front-end adds and how it reaches the shared code: its state machine
 * (Event Mode in co-simulation, Step Mode, early return), the typed get/set functions (Float64,
 * Int32, Int64 enumerations, Boolean, also as foreign bytes: 2, 0x80, ...; the types without
 * variables), the ME functions, and FMU states: taken, restored, serialized, and deserialized
 * after corruption (flipped bytes, hostile words, truncated, extended, random, the header
 * broken).
 *
 * Each sequence instantiates a model-exchange instance and a co-simulation instance (random
 * eventModeUsed / earlyReturnAllowed) and makes --calls calls on them, mostly legal, with valid
 * or hostile arguments. Invariants checked after every call (a violation prints the last calls
 * and exits 1):
 *   - the status is OK, Warning or Error, and every Error is logged (logStatusError);
 *   - a call refused with Error for a bad argument or a bad FMU state leaves the instance as it
 *     was: its serialized state is byte for byte the same before and after;
 *   - no non-finite value comes back with OK or Warning;
 *   - fmi3DoStep(t, h) ends at t + h, or, with earlyReturn (only if allowed), at
 *     lastSuccessfulTime in [t, t + h) = the FMU's new time; the time never goes backwards;
 *   - no crash, sanitizer report, leak or hang (an alarm per sequence). */
#define _POSIX_C_SOURCE 200809L /* alarm */

#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#endif
#include "fmi3Functions.h"
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "fmu_model.h"

#define SEQUENCE_ALARM_S 60
#define TRACE 32

/* ------------------------------------------------------------------------------------------ */
/* random numbers (splitmix64), trace, failure */

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
    return n <= 0 ? 0 : (int)(next_u64() % (uint64_t)n);
}

static int chance(double p)
{
    return uniform() < p;
}

static char trace[TRACE][160];
static long trace_count;
static unsigned long seed_now, sequence_now;

static void note(const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(trace[trace_count % TRACE], sizeof(trace[0]), fmt, args);
    va_end(args);
    trace_count++;
}

static void fail(const char *fmt, ...)
{
    fprintf(stderr, "fuzz_fmi3 (%s): seed %lu sequence %lu: invariant broken: ",
            fmu_model.model_identifier, seed_now, sequence_now);
    va_list args;
    va_start(args, fmt);
    vfprintf(stderr, fmt, args);
    va_end(args);
    fprintf(stderr, "\nlast calls:\n");
    const long first = trace_count > TRACE ? trace_count - TRACE : 0;
    for (long i = first; i < trace_count; i++) {
        fprintf(stderr, "  %s\n", trace[i % TRACE]);
    }
    exit(1);
}

static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "fuzz_fmi3: a sequence took too long (hang)\n";
    (void)!write(2, msg, sizeof(msg) - 1);
    _exit(1);
}

static long errors_logged, errors_total;
static long steps_taken, early_returns;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    (void)env;
    if (category == NULL || message == NULL) {
        fail("the FMU logged a NULL category or message");
    }
    if (status == fmi3Error) {
        if (strcmp(category, "logStatusError") != 0) {
            fail("an error logged under category %s", category);
        }
        errors_logged++;
        errors_total++;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* values */

static double hostile_double(void)
{
    static const double values[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 0.0, -1.0,
                                    1e-300, DBL_MAX, -5e-324};
    return values[below((int)(sizeof(values) / sizeof(values[0])))];
}

static const csfh_variable_t *random_variable(void)
{
    return &fmu_model.variables[below(fmu_model.n_variables)];
}

/* A value inside the variable's range (its start value, mostly). */
static double valid_value(const csfh_variable_t *v)
{
    if (v->has_start && chance(0.7)) {
        return v->start;
    }
    if (v->type == CSFH_TYPE_BOOLEAN) {
        return (double)below(2);
    }
    if (v->type == CSFH_TYPE_ENUMERATION) {
        return v->lo + below((int)(v->hi - v->lo) + 1);
    }
    return v->has_start ? v->start * (1.0 + 1e-3 * (uniform() - 0.5)) : 0.0;
}

/* ------------------------------------------------------------------------------------------ */
/* instances */

typedef struct {
    fmi3Instance c;
    int cs;                 /* co-simulation */
    int event_mode_used, early_return_allowed;
    fmi3FMUState states[4]; /* taken by this instance */
    unsigned char *saved;   /* a serialized state of this instance (for corruption) */
    size_t saved_size;
} instance_t;

static instance_t inst[2];

/* The instance's serialized state (NULL if it cannot be taken), malloc'ed. */
static unsigned char *snapshot(instance_t *in, size_t *size)
{
    fmi3FMUState s = NULL;
    if (fmi3GetFMUState(in->c, &s) != fmi3OK) {
        return NULL;
    }
    unsigned char *bytes = NULL;
    if (fmi3SerializedFMUStateSize(in->c, s, size) == fmi3OK) {
        bytes = (unsigned char *)malloc(*size);
        if (bytes == NULL || fmi3SerializeFMUState(in->c, s, bytes, *size) != fmi3OK) {
            free(bytes);
            bytes = NULL;
        }
    }
    fmi3FreeFMUState(in->c, &s);
    return bytes;
}

/* A call refused with Error must leave the instance unchanged (compared by its serialized state,
 * which getting a state does not change: the integrator restart it asks for is not in it). */
typedef struct {
    unsigned char *before;
    size_t size;
    long errors;
} probe_t;

static probe_t probe(instance_t *in)
{
    probe_t p;
    p.before = snapshot(in, &p.size);
    p.errors = errors_logged;
    return p;
}

static void judge(instance_t *in, probe_t *p, const char *call, fmi3Status status,
                  int rejected_must_not_change)
{
    if (status != fmi3OK && status != fmi3Warning && status != fmi3Error) {
        fail("%s returned status %d", call, (int)status);
    }
    if (status == fmi3Error && errors_logged == p->errors) {
        fail("%s returned fmi3Error without logging an error", call);
    }
    if (status == fmi3Error && rejected_must_not_change && p->before != NULL) {
        size_t size = 0;
        unsigned char *after = snapshot(in, &size);
        if (after == NULL || size != p->size || memcmp(after, p->before, size) != 0) {
            fail("%s was refused but changed the instance", call);
        }
        free(after);
    }
    free(p->before);
    p->before = NULL;
}

static double fmu_time_of(instance_t *in)
{
    const fmi3ValueReference vr = fmu_model.variables[0].vr; /* the time: the first variable */
    double t = NAN;
    fmi3GetFloat64(in->c, &vr, 1, &t, 1);
    return t;
}

static void check_finite(const double *x, size_t n, const char *what, fmi3Status status)
{
    if (status > fmi3Warning) {
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            fail("%s returned %g with status %d", what, x[i], (int)status);
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* calls */

/* fmi3SetBoolean of `value`, often as a foreign byte (an importer's true need not be 1: any
 * nonzero byte, which the FMU must read as a byte, never as C's bool); an accepted value must
 * read back as C's false or true. */
static fmi3Status set_boolean(instance_t *in, fmi3ValueReference vr, int value)
{
    static const unsigned char foreign[] = {2, 3, 0x7F, 0x80, 0xFF};
    unsigned char byte = (unsigned char)(value != 0);
    if (byte && chance(0.5)) {
        byte = foreign[below((int)sizeof(foreign))];
    }
    const fmi3Status s = fmi3SetBoolean(in->c, &vr, 1, (const fmi3Boolean *)(const void *)&byte, 1);
    unsigned char back = 0;
    if (s == fmi3OK &&
        fmi3GetBoolean(in->c, &vr, 1, (fmi3Boolean *)(void *)&back, 1) == fmi3OK &&
        back != (byte != 0)) {
        fail("fmi3SetBoolean of the byte %u read back as the byte %u", byte, back);
    }
    note("fmi3SetBoolean(vr %u, byte %u) -> %d", vr, byte, (int)s);
    return s;
}

static void do_set(instance_t *in)
{
    const csfh_variable_t *v = random_variable();
    const fmi3ValueReference vr = chance(0.05) ? 999999u : v->vr;
    const int valid = chance(0.6);
    const double x = valid ? valid_value(v) : hostile_double();
    probe_t p = probe(in);
    fmi3Status s;
    switch (v->type) {
    case CSFH_TYPE_REAL:
        s = fmi3SetFloat64(in->c, &vr, 1, &x, 1);
        break;
    case CSFH_TYPE_INTEGER: {
        const fmi3Int32 n = valid ? (fmi3Int32)x : (fmi3Int32)(next_u64() & 0xFFFFFFFFu);
        s = fmi3SetInt32(in->c, &vr, 1, &n, 1);
        break;
    }
    case CSFH_TYPE_ENUMERATION: {
        const fmi3Int64 n = valid ? (fmi3Int64)x : (fmi3Int64)next_u64();
        s = chance(0.1) ? fmi3SetInt32(in->c, &vr, 1, (const fmi3Int32 *)&n, 1) /* wrong type */
                        : fmi3SetInt64(in->c, &vr, 1, &n, 1);
        break;
    }
    default:
        s = set_boolean(in, vr, valid ? x != 0.0 : chance(0.5));
        break;
    }
    note("set %s = %g (vr %u) -> %d", v->name, x, vr, (int)s);
    judge(in, &p, "set", s, 1);
}

static void do_get(instance_t *in)
{
    const csfh_variable_t *v = random_variable();
    const fmi3ValueReference vr = v->vr;
    probe_t p = probe(in);
    fmi3Status s;
    if (v->type == CSFH_TYPE_REAL) {
        double x = 0.0;
        s = fmi3GetFloat64(in->c, &vr, 1, &x, 1);
        check_finite(&x, 1, v->name, s);
    } else if (v->type == CSFH_TYPE_INTEGER) {
        fmi3Int32 n = 0;
        s = fmi3GetInt32(in->c, &vr, 1, &n, 1);
    } else if (v->type == CSFH_TYPE_ENUMERATION) {
        fmi3Int64 n = 0;
        s = fmi3GetInt64(in->c, &vr, 1, &n, 1);
        if (s <= fmi3Warning && (n < (fmi3Int64)v->lo || n > (fmi3Int64)v->hi)) {
            fail("%s = %lld outside its enumeration", v->name, (long long)n);
        }
    } else {
        fmi3Boolean b = false;
        s = fmi3GetBoolean(in->c, &vr, 1, &b, 1);
    }
    if (chance(0.1)) { /* types without variables, mismatched counts */
        float f = 0.0f;
        s = fmi3GetFloat32(in->c, &vr, 1, &f, 1);
        if (s != fmi3Error) {
            fail("fmi3GetFloat32 of vr %u accepted", vr);
        }
        double x[2];
        s = fmi3GetFloat64(in->c, &vr, 1, x, 2);
        if (s != fmi3Error) {
            fail("fmi3GetFloat64 with nValues = 2 for 1 scalar accepted");
        }
    }
    note("get %s -> %d", v->name, (int)s);
    judge(in, &p, "get", s, 0);
}

static void do_step(instance_t *in)
{
    const double t = fmu_time_of(in);
    double h = chance(0.8) ? 1e-3 * (1.0 + 20.0 * uniform()) : hostile_double();
    double t_comm = chance(0.9) ? t : t + (chance(0.5) ? 1e-3 : -1e-3);
    fmi3Boolean handling = true, terminate = true, early = true;
    double last = NAN;
    probe_t p = probe(in);
    const fmi3Status s =
        fmi3DoStep(in->c, t_comm, h, false, &handling, &terminate, &early, &last);
    note("doStep(%.17g, %g) -> %d early %d handling %d last %.17g", t_comm, h, (int)s, early,
         handling, last);
    const int refused = s == fmi3Error && (!(isfinite(h) && h >= 0.0) || t_comm != t ||
                                           !isfinite(t + h));
    judge(in, &p, "fmi3DoStep", s, refused);
    if (s > fmi3Warning) {
        return;
    }
    const double t_new = fmu_time_of(in);
    steps_taken++;
    early_returns += early;
    if (early && !in->early_return_allowed) {
        fail("earlyReturn without earlyReturnAllowed");
    }
    if (handling && !in->event_mode_used) {
        fail("eventHandlingNeeded without eventModeUsed");
    }
    if (early ? !(last >= t && last < t + h && last == t_new) : t_new != t + h) {
        fail("fmi3DoStep(%.17g, %g) ended at %.17g (early %d, last %.17g)", t, h, t_new, early,
             last);
    }
}

/* The calls a master makes to get the instance running (those illegal in its state are refused
 * and judged like any call). */
static void do_advance(instance_t *in)
{
    probe_t p = probe(in);
    fmi3Status s = fmi3EnterInitializationMode(in->c, true, 1e-6, 0.0, false, 0.0);
    judge(in, &p, "fmi3EnterInitializationMode", s, 1);
    p = probe(in);
    s = fmi3ExitInitializationMode(in->c);
    judge(in, &p, "fmi3ExitInitializationMode", s, 1);
    fmi3Boolean a, b, c, d, e;
    double next;
    p = probe(in);
    s = fmi3UpdateDiscreteStates(in->c, &a, &b, &c, &d, &e, &next);
    judge(in, &p, "fmi3UpdateDiscreteStates", s, 1);
    p = probe(in);
    s = in->cs ? fmi3EnterStepMode(in->c) : fmi3EnterContinuousTimeMode(in->c);
    judge(in, &p, "enter step/continuous-time mode", s, 1);
    note("advance");
}

static void do_me(instance_t *in)
{
    double x[64], z[8];
    const size_t nx = (size_t)fmu_model.n_states, nz = (size_t)fmu_model.n_event_indicators;
    probe_t p = probe(in);
    fmi3Status s;
    switch (below(5)) {
    case 0:
        s = fmi3GetContinuousStateDerivatives(in->c, x, nx);
        check_finite(x, nx, "derivatives", s);
        break;
    case 1:
        s = fmi3GetEventIndicators(in->c, z, nz);
        check_finite(z, nz, "event indicators", s);
        break;
    case 2:
        s = fmi3GetContinuousStates(in->c, x, nx);
        check_finite(x, nx, "states", s);
        if (s == fmi3OK && chance(0.5)) {
            const int bad = chance(0.3);
            if (bad && nx > 0) {
                x[below((int)nx)] = hostile_double();
            }
            for (size_t i = 0; i < nx && !bad; i++) {
                x[i] *= 1.0 + 1e-6 * (uniform() - 0.5);
            }
            s = fmi3SetContinuousStates(in->c, x, nx);
        }
        break;
    case 3: {
        fmi3Boolean enter = true, term = true;
        s = fmi3CompletedIntegratorStep(in->c, true, &enter, &term);
        if (s <= fmi3Warning && (enter || term)) {
            fail("fmi3CompletedIntegratorStep asked for an event or termination");
        }
        break;
    }
    default:
        s = fmi3SetTime(in->c, chance(0.8) ? fmu_time_of(in) + 1e-4 : hostile_double());
        break;
    }
    note("me call -> %d", (int)s);
    judge(in, &p, "ME call", s, 0);
}

/* Directional or adjoint derivatives of the model's own unknowns by its knowns (refused in the
 * wrong state or interface: co-simulation knows inputs only), sometimes with a hostile seed or
 * sizes that do not match: a success is finite, a refusal changes nothing. */
static void do_derivative(instance_t *in)
{
    if (fmu_model.n_jac_unknowns == 0) {
        return;
    }
    const fmi3ValueReference u[2] = {fmu_model.jac_unknowns[below(fmu_model.n_jac_unknowns)],
                                     fmu_model.jac_unknowns[below(fmu_model.n_jac_unknowns)]};
    const fmi3ValueReference k = fmu_model.jac_knowns[below(fmu_model.n_jac_knowns)];
    double seed[2] = {1.0, chance(0.1) ? hostile_double() : -0.5}, out[2] = {0.0, 0.0};
    const int adjoint = chance(0.5);
    const size_t n_seed = adjoint ? 2 : 1, n_out = adjoint ? 1 : 2;
    const size_t n_out_given = chance(0.1) ? n_out + 1 : n_out;
    probe_t p = probe(in);
    const fmi3Status s =
        adjoint ? fmi3GetAdjointDerivative(in->c, u, 2, &k, 1, seed, n_seed, out, n_out_given)
                : fmi3GetDirectionalDerivative(in->c, u, 2, &k, 1, seed, n_seed, out, n_out_given);
    note("%s -> %d", adjoint ? "fmi3GetAdjointDerivative" : "fmi3GetDirectionalDerivative",
         (int)s);
    if (s <= fmi3Warning) {
        check_finite(out, n_out, "derivatives", s);
    }
    judge(in, &p, "derivative call", s, 1);
}

static void do_mode(instance_t *in)
{
    probe_t p = probe(in);
    fmi3Status s;
    const int which = below(9);
    switch (which) {
    case 0:
        s = fmi3EnterInitializationMode(in->c, chance(0.8), chance(0.9) ? 1e-6 : hostile_double(),
                                        chance(0.9) ? 0.0 : hostile_double(), false, 0.0);
        break;
    case 1:
        s = fmi3ExitInitializationMode(in->c);
        break;
    case 2:
        s = fmi3EnterEventMode(in->c);
        break;
    case 3: {
        fmi3Boolean a, b, c, d, e;
        double next;
        s = fmi3UpdateDiscreteStates(in->c, &a, &b, &c, &d, &e, &next);
        break;
    }
    case 4:
        s = in->cs ? fmi3EnterStepMode(in->c) : fmi3EnterContinuousTimeMode(in->c);
        break;
    case 5:
        s = fmi3Terminate(in->c);
        break;
    case 6:
        s = chance(0.3) ? fmi3Reset(in->c) : fmi3EnterStepMode(in->c);
        break;
    case 7:
        s = fmi3EnterConfigurationMode(in->c);
        break;
    default: {
        const fmi3String categories[] = {"logEvents", chance(0.2) ? "nonsense" : "logAll"};
        s = fmi3SetDebugLogging(in->c, chance(0.5), 2, categories);
        break;
    }
    }
    note("mode call %d -> %d", which, (int)s);
    judge(in, &p, "mode call", s, 1);
}

/* Mutations of a serialized state. */
static void corrupt(unsigned char **bytes, size_t *size)
{
    unsigned char *b = *bytes;
    const size_t n = *size;
    switch (below(7)) {
    case 0:
        for (int i = 0, k = 1 + below(8); i < k; i++) {
            b[below((int)n)] ^= (unsigned char)(1u << below(8));
        }
        break;
    case 1:
        for (int i = 0, k = 1 + below(6); i < k; i++) {
            const double x = hostile_double();
            memcpy(b + below((int)(n - sizeof(double))), &x, sizeof(x));
        }
        break;
    case 2: {
        static const int values[] = {0, -1, 77, 1 << 20, 3, 128, 2, -2147483647 - 1};
        const int x = values[below(8)];
        memcpy(b + 4 * below((int)(n / 4)), &x, sizeof(x));
        break;
    }
    case 3:
        *size = (size_t)below((int)n);
        break;
    case 4:
        *bytes = (unsigned char *)realloc(b, n + 8);
        memset(*bytes + n, 0xAB, 8);
        *size = n + 1 + (size_t)below(8);
        break;
    case 5:
        for (size_t i = 0; i < n; i++) {
            b[i] = (unsigned char)next_u64();
        }
        break;
    default:
        b[below(64)] ^= 0x5A; /* the header */
        break;
    }
}

static void do_state(instance_t *in)
{
    const int k = below(4);
    probe_t p = probe(in);
    fmi3Status s;
    const char *what;
    switch (below(5)) {
    case 0:
        what = "fmi3GetFMUState";
        s = fmi3GetFMUState(in->c, &in->states[k]);
        p.before = (free(p.before), NULL); /* taking a state is not a change to check */
        break;
    case 1:
        what = "fmi3SetFMUState";
        if (in->states[k] == NULL) {
            free(p.before);
            return;
        }
        s = fmi3SetFMUState(in->c, in->states[k]);
        break;
    case 2:
        what = "fmi3FreeFMUState";
        s = fmi3FreeFMUState(in->c, &in->states[k]);
        break;
    case 3: { /* keep a serialized state of this instance */
        what = "serialize";
        free(p.before);
        p.before = NULL;
        free(in->saved);
        in->saved = snapshot(in, &in->saved_size);
        s = fmi3OK;
        break;
    }
    default: { /* deserialize a (mostly corrupted) copy; a good one is set */
        what = "fmi3DeserializeFMUState";
        if (in->saved == NULL) {
            free(p.before);
            return;
        }
        size_t size = in->saved_size;
        unsigned char *bytes = (unsigned char *)malloc(size);
        memcpy(bytes, in->saved, size);
        const int corrupted = chance(0.8);
        if (corrupted) {
            corrupt(&bytes, &size);
        }
        fmi3FMUState st = NULL;
        s = fmi3DeserializeFMUState(in->c, bytes, size, &st);
        free(bytes);
        if (!corrupted && s != fmi3OK) {
            fail("a state serialized by this instance was refused");
        }
        if (s == fmi3OK) {
            const fmi3Status set = fmi3SetFMUState(in->c, st);
            if (set != fmi3OK) {
                fail("a deserialized (accepted) state was not restored: %d", (int)set);
            }
            fmi3FreeFMUState(in->c, &st);
        }
        break;
    }
    }
    note("%s [%d] -> %d", what, k, (int)s);
    judge(in, &p, what, s, 1);
}

static void instantiate(instance_t *in, int cs)
{
    memset(in, 0, sizeof(*in));
    in->cs = cs;
    if (cs) {
        in->event_mode_used = chance(0.5);
        in->early_return_allowed = chance(0.6);
        in->c = fmi3InstantiateCoSimulation("fuzz3", fmu_model.guid, NULL, false, chance(0.3),
                                            in->event_mode_used, in->early_return_allowed, NULL,
                                            0, NULL, logger, NULL);
    } else {
        in->c = fmi3InstantiateModelExchange("fuzz3", fmu_model.guid, NULL, false, chance(0.3),
                                             NULL, logger);
    }
    if (in->c == NULL) {
        fail("instantiation failed");
    }
}

static void free_instance(instance_t *in)
{
    free(in->saved);
    fmi3FreeInstance(in->c); /* frees the FMU states left */
    memset(in, 0, sizeof(*in));
}

static void sequence(int calls)
{
    errors_logged = 0;
    alarm(SEQUENCE_ALARM_S);
    /* bad instantiations: refused, logged */
    if (fmi3InstantiateModelExchange("x", "{wrong}", NULL, false, false, NULL, logger) != NULL ||
        fmi3InstantiateCoSimulation("", fmu_model.guid, NULL, false, false, false, false, NULL, 0,
                                    NULL, logger, NULL) != NULL) {
        fail("a bad instantiation was accepted");
    }
    instantiate(&inst[0], 0);
    instantiate(&inst[1], 1);
    for (int i = 0; i < calls; i++) {
        instance_t *in = &inst[below(2)];
        const int r = below(100);
        if (r < 10) {
            do_advance(in);
        } else if (r < 20) {
            do_set(in);
        } else if (r < 35) {
            do_get(in);
        } else if (r < 60) {
            if (in->cs) {
                do_step(in);
            } else {
                do_me(in);
            }
        } else if (r < 72) {
            do_mode(in);
        } else if (r < 75) {
            do_derivative(in);
        } else {
            do_state(in);
        }
    }
    free_instance(&inst[0]);
    free_instance(&inst[1]);
    alarm(0);
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
        } else {
            fprintf(stderr, "usage: %s [--seeds FIRST LAST] [--sequences N] [--calls M]\n",
                    argv[0]);
            return 2;
        }
    }
    signal(SIGALRM, on_alarm);
    for (unsigned long seed = seed_first; seed <= seed_last; seed++) {
        for (unsigned long s = 0; s < sequences; s++) {
            seed_now = seed;
            sequence_now = s;
            rng = seed * 0x9E3779B97F4A7C15ull;
            rng = next_u64() ^ ((s + 1) * 0xD1B54A32D192ED03ull);
            sequence(calls);
        }
    }
    printf("%s (FMI 3.0): %lu seeds x %lu sequences x %d calls: no invariant broken (%ld calls, "
           "%ld FMU errors logged, %ld steps taken, %ld early returns)\n",
           fmu_model.model_identifier, seed_last - seed_first + 1, sequences, calls, trace_count,
           errors_total, steps_taken, early_returns);
    return 0;
}
