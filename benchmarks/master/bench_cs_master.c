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
 * The headers are fmpy's FMI 2.0 headers, as for the FMU itself; the binary is loaded with the
 * masters' shared loader (fmu_src/masters/fmi2_api.h). Portable C11: POSIX (clock_gettime) or
 * Windows (QueryPerformanceCounter), so the same master runs the win64 binary (cross-built by
 * cmake/platforms.cmake, run under wine in tests/fmu/test_platforms.py). */
#if defined(_WIN32)
#include <windows.h>
#else
#define _POSIX_C_SOURCE 200809L
#include <time.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi2_api.h"
#include "fmu_library.h"

#define MAX_REFS 64
#define MAX_REPEATS 100001 /* long enough for a profiler (perf record) on one process */

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

/* the clock: the platform-specific part besides loading the binary */
#if defined(_WIN32)
static double now(void)
{
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
}
#else
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
#endif

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
static void set_start(const fmi2_api_t *api, fmi2Component c, int argc, char **argv)
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
            check(api->SetReal(c, &ref, 1, &value), argv[i]);
        } else if (type == 'i') {
            const fmi2Integer v = (fmi2Integer)value;
            check(api->SetInteger(c, &ref, 1, &v), argv[i]);
        } else if (type == 'b') {
            const fmi2Boolean v = value != 0.0 ? fmi2True : fmi2False;
            check(api->SetBoolean(c, &ref, 1, &v), argv[i]);
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
        {repeats >= 1 && repeats <= MAX_REPEATS, 6, "REPEATS must be 1..100001"},
    };
    for (size_t i = 0; i < sizeof(checks) / sizeof(checks[0]); i++) {
        if (!checks[i].ok) {
            fprintf(stderr, "bench_cs_master: %s, got %s\n", checks[i].rule, argv[checks[i].arg]);
            return 2;
        }
    }
    void *dll = fmu_library_open(binary);
    if (dll == NULL) {
        fprintf(stderr, "bench_cs_master: %s: %s\n", binary, fmu_library_error());
        return 2;
    }
    fmi2_api_t api_storage;
    fmi2_api_t *api = &api_storage;
    const char *missing = fmi2_api_load(api, dll, FMI2_API_COMMON | FMI2_API_RESET | FMI2_API_CS);
    if (missing != NULL) {
        fprintf(stderr, "bench_cs_master: %s not found\n", missing);
        exit(2);
    }
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = api->Instantiate("master", fmi2CoSimulation, guid, "", &callbacks,
                                       fmi2False, fmi2False);
    if (c == NULL) {
        fprintf(stderr, "bench_cs_master: fmi2Instantiate failed\n");
        return 1;
    }
    double *times = (double *)malloc((size_t)repeats * sizeof(double));
    if (times == NULL) {
        fprintf(stderr, "bench_cs_master: out of memory\n");
        return 1;
    }
    fmi2Real values[MAX_REFS];
    fmi2Integer counts[MAX_REFS];
    for (int r = -1; r < repeats; r++) { /* r = -1: a warm-up run, not timed */
        if (r > -1) {
            check(api->Reset(c), "fmi2Reset");
        }
        check(api->SetupExperiment(c, fmi2True, rtol, 0.0, fmi2True, stop), "fmi2SetupExperiment");
        check(api->EnterInitializationMode(c), "fmi2EnterInitializationMode");
        set_start(api, c, argc - 9, argv + 9);
        check(api->ExitInitializationMode(c), "fmi2ExitInitializationMode");
        const double t0 = now();
        for (long k = 0; k < n_steps; k++) {
            check(api->DoStep(c, (double)k * h, h, fmi2True), "fmi2DoStep");
            check(api->GetReal(c, read, n_read, values), "fmi2GetReal");
        }
        if (r > -1) {
            times[r] = now() - t0;
        }
        check(api->GetInteger(c, count, n_count, counts), "fmi2GetInteger");
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
    free(times);
    api->FreeInstance(c);
    fmu_library_close(dll);
    return 0;
}
