/* A minimal compiled co-simulation master, for benchmarks/bench_cosim.py: the fmi2DoStep loop
 * as a C or C++ importer (a system-level tool, a co-simulation engine) runs it, without the
 * per-call cost of a Python master. It loads an FMU's binary, instantiates it as a
 * co-simulation slave, sets start values, and times the loop
 *
 *     for k in 0 .. n-1: fmi2DoStep(k h, h); fmi2GetReal(read)
 *
 * `repeats` times after one untimed warm-up run (fmi2Reset between the runs, as a master re-using
 * its instance), printing one JSON line: the median
 * loop time, the final values of the read variables, and the values of the count variables.
 *
 * Usage: bench_cs_master BINARY GUID RTOL H STOP REPEATS READ COUNT [VR:TYPE=VALUE ...]
 *   BINARY   path of binaries/<platform>/<model>.{so,dll,dylib} in the unzipped FMU
 *   READ     comma-separated value references of Reals read at every communication point
 *   COUNT    comma-separated value references of Integers read at the end
 *   TYPE     r (Real), i (Integer) or b (Boolean)
 * The headers are fmpy's FMI 2.0 headers, as for the FMU itself. Portable C11: POSIX (dlopen,
 * clock_gettime) or Windows (LoadLibrary, QueryPerformanceCounter), so the same master runs the
 * win64 binary (cross-built by cmake/platforms.cmake, run under wine in
 * tests/fmu/test_platforms.py). */
#if defined(_WIN32)
#include <windows.h>
#else
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <time.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_REFS 64
#define MAX_REPEATS 101

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2ResetTYPE *reset;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2DoStepTYPE *do_step;
} fmi_api_t;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    if (status >= fmi2Warning) {
        va_list args;
        va_start(args, message);
        fprintf(stderr, "%s [%s]: ", instance, category);
        vfprintf(stderr, message, args);
        fputc('\n', stderr);
        va_end(args);
    }
}

/* the shared library: the one platform-specific part besides the clock */
typedef void (*function_t)(void);

#if defined(_WIN32)
static void *library_open(const char *path)
{
    return (void *)LoadLibraryA(path);
}
static function_t library_symbol(void *library, const char *name)
{
    return (function_t)(void (*)(void))GetProcAddress((HMODULE)library, name);
}
static const char *library_error(void)
{
    static char message[64];
    snprintf(message, sizeof message, "LoadLibrary failed, error %lu", (unsigned long)GetLastError());
    return message;
}
static void library_close(void *library)
{
    FreeLibrary((HMODULE)library);
}
static double now(void)
{
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
}
#else
static void *library_open(const char *path)
{
    return dlopen(path, RTLD_NOW | RTLD_LOCAL);
}
static function_t library_symbol(void *library, const char *name)
{
    void *p = dlsym(library, name);
    function_t f;
    memcpy(&f, &p, sizeof f); /* POSIX: object and function pointers have the same form */
    return f;
}
static const char *library_error(void)
{
    return dlerror();
}
static void library_close(void *library)
{
    dlclose(library);
}
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
#endif

static function_t symbol(void *dll, const char *name)
{
    function_t p = library_symbol(dll, name);
    if (p == NULL) {
        fprintf(stderr, "bench_cs_master: %s not found\n", name);
        exit(2);
    }
    return p;
}

/* every function pointer has the same representation on the platforms the FMU is built for */
#define LOAD(field, name)                                                                        \
    do {                                                                                         \
        const function_t f_ = symbol(dll, name);                                                 \
        memcpy(&api->field, &f_, sizeof f_);                                                     \
    } while (0)

static void load(void *dll, fmi_api_t *api)
{
    LOAD(instantiate, "fmi2Instantiate");
    LOAD(free_instance, "fmi2FreeInstance");
    LOAD(setup_experiment, "fmi2SetupExperiment");
    LOAD(enter_init, "fmi2EnterInitializationMode");
    LOAD(exit_init, "fmi2ExitInitializationMode");
    LOAD(reset, "fmi2Reset");
    LOAD(set_real, "fmi2SetReal");
    LOAD(set_integer, "fmi2SetInteger");
    LOAD(set_boolean, "fmi2SetBoolean");
    LOAD(get_real, "fmi2GetReal");
    LOAD(get_integer, "fmi2GetInteger");
    LOAD(do_step, "fmi2DoStep");
}

static size_t parse_refs(const char *text, fmi2ValueReference refs[MAX_REFS])
{
    size_t n = 0;
    const char *p = text;
    while (*p != '\0' && n < MAX_REFS) {
        char *end = NULL;
        refs[n++] = (fmi2ValueReference)strtoul(p, &end, 10);
        if (end == p) {
            fprintf(stderr, "bench_cs_master: bad value reference list '%s'\n", text);
            exit(2);
        }
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

static void check(fmi2Status s, const char *what)
{
    if (s > fmi2Warning) {
        fprintf(stderr, "bench_cs_master: %s failed (status %d)\n", what, (int)s);
        exit(1);
    }
}

/* Start values "VR:TYPE=VALUE", in initialization mode. */
static void set_start(const fmi_api_t *api, fmi2Component c, int argc, char **argv)
{
    for (int i = 0; i < argc; i++) {
        unsigned vr = 0;
        char type = 0;
        double value = 0.0;
        if (sscanf(argv[i], "%u:%c=%lf", &vr, &type, &value) != 3) {
            fprintf(stderr, "bench_cs_master: bad start value '%s'\n", argv[i]);
            exit(2);
        }
        const fmi2ValueReference ref = vr;
        if (type == 'r') {
            check(api->set_real(c, &ref, 1, &value), argv[i]);
        } else if (type == 'i') {
            const fmi2Integer v = (fmi2Integer)value;
            check(api->set_integer(c, &ref, 1, &v), argv[i]);
        } else if (type == 'b') {
            const fmi2Boolean v = value != 0.0 ? fmi2True : fmi2False;
            check(api->set_boolean(c, &ref, 1, &v), argv[i]);
        } else {
            fprintf(stderr, "bench_cs_master: bad type in '%s'\n", argv[i]);
            exit(2);
        }
    }
}

static int compare(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc < 9) {
        fprintf(stderr, "usage: %s BINARY GUID RTOL H STOP REPEATS READ COUNT [VR:TYPE=VALUE ...]\n",
                argv[0]);
        return 2;
    }
    const char *binary = argv[1], *guid = argv[2];
    const double rtol = atof(argv[3]), h = atof(argv[4]), stop = atof(argv[5]);
    int repeats = atoi(argv[6]);
    fmi2ValueReference read[MAX_REFS], count[MAX_REFS];
    const size_t n_read = parse_refs(argv[7], read), n_count = parse_refs(argv[8], count);
    const long n_steps = (long)(stop / h + 0.5);
    /* each argument checked on its own: the message names it and its value */
    const struct {
        int ok;
        int arg;
        const char *rule;
    } checks[] = {
        {rtol > 0.0 && isfinite(rtol), 3, "RTOL must be > 0"},
        {h > 0.0 && isfinite(h), 4, "H must be > 0"},
        {isfinite(stop) && n_steps >= 1, 5, "STOP must be >= H"},
        {repeats >= 1 && repeats <= MAX_REPEATS, 6, "REPEATS must be 1..101"},
    };
    for (size_t i = 0; i < sizeof(checks) / sizeof(checks[0]); i++) {
        if (!checks[i].ok) {
            fprintf(stderr, "bench_cs_master: %s, got %s\n", checks[i].rule, argv[checks[i].arg]);
            return 2;
        }
    }
    void *dll = library_open(binary);
    if (dll == NULL) {
        fprintf(stderr, "bench_cs_master: %s: %s\n", binary, library_error());
        return 2;
    }
    fmi_api_t api_storage;
    fmi_api_t *api = &api_storage;
    load(dll, api);
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = api->instantiate("master", fmi2CoSimulation, guid, "", &callbacks,
                                       fmi2False, fmi2False);
    if (c == NULL) {
        fprintf(stderr, "bench_cs_master: fmi2Instantiate failed\n");
        return 1;
    }
    double times[MAX_REPEATS];
    fmi2Real values[MAX_REFS];
    fmi2Integer counts[MAX_REFS];
    for (int r = -1; r < repeats; r++) { /* r = -1: a warm-up run, not timed */
        if (r > -1) {
            check(api->reset(c), "fmi2Reset");
        }
        check(api->setup_experiment(c, fmi2True, rtol, 0.0, fmi2True, stop), "fmi2SetupExperiment");
        check(api->enter_init(c), "fmi2EnterInitializationMode");
        set_start(api, c, argc - 9, argv + 9);
        check(api->exit_init(c), "fmi2ExitInitializationMode");
        const double t0 = now();
        for (long k = 0; k < n_steps; k++) {
            check(api->do_step(c, (double)k * h, h, fmi2True), "fmi2DoStep");
            check(api->get_real(c, read, n_read, values), "fmi2GetReal");
        }
        if (r > -1) {
            times[r] = now() - t0;
        }
        check(api->get_integer(c, count, n_count, counts), "fmi2GetInteger");
    }
    qsort(times, (size_t)repeats, sizeof(double), compare);
    printf("{\"loop_seconds\": %.9g, \"steps\": %ld, \"read\": [", times[repeats / 2], n_steps);
    for (size_t i = 0; i < n_read; i++) {
        printf("%s%.17g", i ? ", " : "", values[i]);
    }
    printf("], \"count\": [");
    for (size_t i = 0; i < n_count; i++) {
        printf("%s%d", i ? ", " : "", (int)counts[i]);
    }
    printf("]}\n");
    api->free_instance(c);
    library_close(dll);
    return 0;
}
