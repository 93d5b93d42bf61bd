/* The core ctypes library's entry points driven from C, as csfh.runners.moreau and .rk4 call
 * them through ctypes: built for the host and for every cross platform (csfh_add_test_importer),
 * so the win64 build runs the wheel's csfh_core.dll under wine and the linux64 build the
 * manylinux libcsfh_core.so (tests/tools/test_wheels.py compares the two).
 *
 * Usage: csfh_ctypes_driver CORE_LIBRARY STOP [NAME=VALUE ...]
 * Sets each parameter (and start state) by its FMI name, prepares the model, runs STOP seconds
 * (at most 0.5) of the Moreau stepper (h = 1e-5 s, the paper's stick rule) and of the paper's RK4
 * (h0 = 1e-5 s, tol = 1e-9) from the model's start state, and prints one line per run: its name,
 * the ABI version, the end state and the run's counters, numbers with 17 significant digits.
 *
 * Usage: csfh_ctypes_driver BATCH_LIBRARY STOP FMU_BINARY GUID OUT_VRS [VR:T=VALUE ...]
 * One co-simulation run of the FMU binary through csfh_cs_batch_run (communication step 1e-3 s,
 * tolerance 1e-8) with the start values VR:T=VALUE (T: r Real, i Integer, b Boolean); prints
 * "batch", the ABI version, the run's status and the final values of the outputs OUT_VRS (value
 * references, comma-separated). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_cs_batch.h"
#include "fmu_library.h"

typedef int (*abi_t)(void);
typedef void *(*new_t)(void);
typedef void (*free_t)(void *);
typedef int (*set_t)(void *, const char *, double, char *, size_t);
typedef int (*prepare_t)(void *, char *, size_t);
typedef void (*get_state_t)(const void *, double *);
typedef int (*moreau_t)(void *, double, int, double, double, double, double, const double *,
                        long long, long long, double *, size_t, double *, size_t, double *,
                        long long *);
typedef long long (*batch_run_t)(const csfh_cs_batch_spec_t *, size_t, const double *, double *,
                                 double *, int *, char *, size_t);
typedef int (*rk4_t)(void *, double, double, double, double, const double *, double, double,
                     double *, size_t, double *, size_t, double *, long long *);

enum { N_STATES = 6, MAX_RECORDS = 64, MAX_EVENTS = 4096, RECORD_COLUMNS = 32, MAX_VARIABLES = 64 };

static void *symbol(void *library, const char *name) {
    fmu_library_function_t f = fmu_library_symbol(library, name);
    if (!f) {
        fprintf(stderr, "ctypes_driver: %s not exported\n", name);
        exit(1);
    }
    return *(void **)&f;
}

static void print_run(const char *name, int abi, int status, const double *x, const long long *stats,
                      int n_stats) {
    printf("%s abi=%d status=%d x=", name, abi, status);
    for (int i = 0; i < N_STATES; i++) {
        printf("%s%.17g", i ? "," : "", x[i]);
    }
    printf(" stats=");
    for (int i = 0; i < n_stats; i++) {
        printf("%s%lld", i ? "," : "", stats[i]);
    }
    printf("\n");
}

/* a model with the parameters of argv[3..]: NAME=VALUE */
static void *model_with(void *lib, int argc, char **argv) {
    void *model = ((new_t)symbol(lib, "csfh_api_new"))();
    set_t set = (set_t)symbol(lib, "csfh_api_set");
    char msg[512];
    for (int i = 3; i < argc; i++) {
        const char *eq = strchr(argv[i], '=');
        char name[256];
        size_t length = eq ? (size_t)(eq - argv[i]) : 0;
        if (!eq || length >= sizeof name) {
            fprintf(stderr, "ctypes_driver: %s is not NAME=VALUE\n", argv[i]);
            exit(2);
        }
        memcpy(name, argv[i], length);
        name[length] = '\0';
        if (set(model, name, strtod(eq + 1, NULL), msg, sizeof msg) != 0) {
            fprintf(stderr, "ctypes_driver: %s: %s\n", name, msg);
            exit(2);
        }
    }
    if (((prepare_t)symbol(lib, "csfh_api_prepare"))(model, msg, sizeof msg) != 0) {
        fprintf(stderr, "ctypes_driver: prepare: %s\n", msg);
        exit(2);
    }
    return model;
}

/* the batch library: one run of an FMU binary (argv: LIBRARY STOP BINARY GUID OUT_VRS VR:T=V...) */
static int run_batch(void *lib, double stop, int argc, char **argv) {
    if (argc < 6 || argc - 6 > MAX_VARIABLES) {
        fprintf(stderr, "ctypes_driver: batch: LIBRARY STOP BINARY GUID OUT_VRS [VR:T=VALUE ...]\n");
        return 2;
    }
    static unsigned int set_vr[MAX_VARIABLES], out_vr[MAX_VARIABLES];
    static int set_type[MAX_VARIABLES], out_type[MAX_VARIABLES], out_reduce[MAX_VARIABLES],
        out_arg[MAX_VARIABLES];
    static double values[MAX_VARIABLES], results[MAX_VARIABLES];
    size_t n_set = 0, n_out = 0;
    for (int i = 6; i < argc; i++, n_set++) {
        char kind = 0;
        if (sscanf(argv[i], "%u:%c=%lf", &set_vr[n_set], &kind, &values[n_set]) != 3) {
            fprintf(stderr, "ctypes_driver: %s is not VR:T=VALUE\n", argv[i]);
            return 2;
        }
        set_type[n_set] = kind == 'b' ? CSFH_BATCH_BOOLEAN : kind == 'i' ? CSFH_BATCH_INTEGER : CSFH_BATCH_REAL;
    }
    for (const char *p = argv[5]; *p && n_out < MAX_VARIABLES; n_out++) {
        char *end;
        out_vr[n_out] = (unsigned int)strtoul(p, &end, 10);
        out_type[n_out] = CSFH_BATCH_REAL;
        out_reduce[n_out] = CSFH_BATCH_FINAL;
        out_arg[n_out] = 0;
        p = *end == ',' ? end + 1 : end;
    }
    csfh_cs_batch_spec_t spec = {argv[3], argv[4], NULL, "ctypes_driver", 1e-8, stop, 1e-3,
                                 n_set, set_vr, set_type, n_out, out_vr, out_type, out_reduce,
                                 out_arg};
    int status = 0;
    char message[512] = "";
    long long failed = ((batch_run_t)symbol(lib, "csfh_cs_batch_run"))(
        &spec, 1, values, results, NULL, &status, message, sizeof message);
    printf("batch abi=%d status=%d x=", ((abi_t)symbol(lib, "csfh_cs_batch_abi_version"))(),
           failed == 0 ? status : -1);
    for (size_t i = 0; i < n_out; i++) {
        printf("%s%.17g", i ? "," : "", results[i]);
    }
    printf(" message=%s\n", message[0] ? "yes" : "none");
    if (message[0]) {
        fprintf(stderr, "ctypes_driver: %s\n", message);
    }
    return 0;
}

/* the core library: Moreau and RK4 runs (argv: LIBRARY STOP NAME=VALUE...) */
static int run_core(void *lib, double stop, int argc, char **argv) {
    long long steps = (long long)(stop / 1e-5 + 0.5);
    int abi = ((abi_t)symbol(lib, "csfh_api_abi_version"))();
    const char *columns[] = {"csfh_api_moreau_record_columns", "csfh_api_moreau_impact_columns",
                             "csfh_api_rk4_record_columns", "csfh_api_contact_record_columns"};
    for (size_t i = 0; i < sizeof columns / sizeof *columns; i++) {
        if (((abi_t)symbol(lib, columns[i]))() > RECORD_COLUMNS) {
            fprintf(stderr, "ctypes_driver: %s > %d\n", columns[i], RECORD_COLUMNS);
            return 1;
        }
    }
    static double records[MAX_RECORDS * RECORD_COLUMNS], events[MAX_EVENTS * RECORD_COLUMNS];
    double x0[N_STATES], x_end[N_STATES];
    long long stats[9] = {0};

    void *model = model_with(lib, argc, argv);
    ((get_state_t)symbol(lib, "csfh_api_get_state"))(model, x0);
    int status = ((moreau_t)symbol(lib, "csfh_api_moreau_run"))(
        model, 1e-5, 1, 0.0, 1e-9, 0.0, 0.0, x0, steps, steps, records, MAX_RECORDS, events,
        MAX_EVENTS, x_end, stats);
    print_run("moreau", abi, status, x_end, stats, 9);
    ((free_t)symbol(lib, "csfh_api_free"))(model);

    model = model_with(lib, argc, argv);
    status = ((rk4_t)symbol(lib, "csfh_api_rk4_run"))(model, 1e-5, 1e-9, 1e-5 * 0x1p-40, 0.0, x0,
                                                      stop, stop / 16, records, MAX_RECORDS,
                                                      events, MAX_EVENTS, x_end, stats);
    print_run("rk4", abi, status, x_end, stats, 5);
    ((free_t)symbol(lib, "csfh_api_free"))(model);
    return 0;
}

int main(int argc, char **argv) {
    double stop = argc >= 3 ? strtod(argv[2], NULL) : 0.0;
    if (argc < 3 || !(stop > 0.0 && stop <= 0.5)) {
        fprintf(stderr, "usage: csfh_ctypes_driver LIBRARY STOP ... (0 < STOP <= 0.5)\n");
        return 2;
    }
    void *lib = fmu_library_open(argv[1]);
    if (!lib) {
        fprintf(stderr, "ctypes_driver: %s: %s\n", argv[1], fmu_library_error());
        return 1;
    }
    /* which library it is: the batch master exports csfh_cs_batch_run */
    int rc = fmu_library_symbol(lib, "csfh_cs_batch_run") ? run_batch(lib, stop, argc, argv)
                                                          : run_core(lib, stop, argc, argv);
    fmu_library_close(lib);
    return rc;
}
