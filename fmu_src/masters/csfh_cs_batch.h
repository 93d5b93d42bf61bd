/* A batch co-simulation master: many runs of one FMU binary in one call, in this process, each
 * driven through the FMU's own fmi2 functions exactly as the Python harness drives a single run
 * (csfh.runners.fmu.simulate_cs): instantiate, set up the experiment, set the start values one
 * by one in initialization mode, read the outputs at the start and after every fmi2DoStep of a
 * fixed communication grid. Only scalars are kept per run (reductions of the outputs over the
 * communication points: final value, maximum, ...), and optionally the outputs on the grid.
 * The runs share one instance, put back by fmi2Reset into the state fmi2Instantiate leaves it in
 * (made anew after a failed run). Each communication point reads the outputs its reductions
 * need there (each value reference once); an output reduced to its final value only is read
 * at the stop time (outputs do not feed back into the integration, so that is the value a read
 * at every point ends with); with a record, every output at every point.
 *
 * The master loads the very binary the single run loads (dlopen of the unzipped FMU's
 * binaries/<platform>/<id>.so), so a batched run is the single run by construction: the same
 * machine code, the same calls, the same arguments. What the batch saves is the per-run overhead
 * of Python (fmpy's wrappers, one ctypes call per value and per step), which for a run of the
 * csfh scene is several times the FMU's own work.
 *
 * Plain C11 and the FMI 2.0 headers; the binary is loaded through the masters' shared loader
 * (fmu_library.h, fmi2_api.h). Used from Python through ctypes (csfh.runners.cs_batch). */
#ifndef CSFH_CS_BATCH_H
#define CSFH_CS_BATCH_H

#include <stddef.h>

#if defined(_WIN32)
#define CSFH_BATCH_API __declspec(dllexport)
#elif defined(__GNUC__)
#define CSFH_BATCH_API __attribute__((visibility("default")))
#else
#define CSFH_BATCH_API
#endif

/* Types of the variables set and read (FMI 2.0: Enumerations are set and read as Integers). */
#define CSFH_BATCH_REAL 0
#define CSFH_BATCH_INTEGER 1
#define CSFH_BATCH_BOOLEAN 2

/* Reductions of one output over the communication points (the start included). */
#define CSFH_BATCH_FINAL 0       /* the value at the stop time */
#define CSFH_BATCH_MAX 1         /* the largest value */
#define CSFH_BATCH_MIN 2         /* the smallest value */
#define CSFH_BATCH_ABSMAX 3      /* the largest magnitude */
#define CSFH_BATCH_FIRST_WHEN 4  /* the value at the first point where output `arg` is > 0
                                    (NaN if it never is), e.g. the onset time of the first
                                    contact when `arg` is the contact count */
#define CSFH_BATCH_TIME_OF_MAX 5 /* the time of the first point where the output is largest */

/* Run status. */
#define CSFH_BATCH_OK 0
#define CSFH_BATCH_WARNING 1 /* completed; some call returned fmi2Warning (see the message) */
#define CSFH_BATCH_FAILED (-1) /* a call failed: its results are NaN, the message says why */

typedef struct {
    /* the FMU */
    const char *binary;       /* path of the FMU's shared library */
    const char *guid;
    const char *resource_uri; /* fmi2Instantiate's fmuResourceLocation (may be NULL) */
    const char *instance_name;
    /* the experiment: fmi2SetupExperiment(tolerance, start 0, stop_time), then steps on the
     * grid t_k = min(k step, stop_time), k = 1 .. ceil(stop_time / step - 1e-9) */
    double tolerance;
    double stop_time;
    double step;
    /* start values, set one by one in initialization mode in this order */
    size_t n_set;
    const unsigned int *set_vr;
    const int *set_type;
    /* outputs read at t = 0 and after every step, each with its reduction (arg: the trigger
     * output of CSFH_BATCH_FIRST_WHEN, an index into these outputs) */
    size_t n_out;
    const unsigned int *out_vr;
    const int *out_type;
    const int *out_reduce;
    const int *out_arg;
} csfh_cs_batch_spec_t;

/* The number of communication points of a run, the start included. */
CSFH_BATCH_API long long csfh_cs_batch_points(double stop_time, double step);

/* Run n_runs variants:
 *   values    n_runs x n_set start values (Integers and Booleans as numbers)
 *   results   n_runs x n_out reductions
 *   records   n_runs x n_points x n_out: every output at every communication point (may be
 *             NULL; n_points = csfh_cs_batch_points(...))
 *   status    n_runs statuses (CSFH_BATCH_OK, _WARNING, _FAILED)
 *   messages  n_runs x message_size: the first error (or warning) the FMU logged, else ""
 * Returns the number of failed runs, or -1 if nothing could run (bad arguments, a binary that
 * does not load: the reason in messages[0..message_size)). */
CSFH_BATCH_API long long csfh_cs_batch_run(const csfh_cs_batch_spec_t *spec, size_t n_runs,
                                           const double *values, double *results,
                                           double *records, int *status, char *messages,
                                           size_t message_size);

/* ------------------------------------------------------------------------------------------ */
/* The communication loop of one run on an instance someone else created (csfh_cs_steps.c):
 * what csfh.runners.fmu.simulate_cs does per communication point (fmi2DoStep, then read fixed
 * sets of Real, Integer and Boolean outputs), for a chunk of steps in one call, so that Python
 * pays one call per chunk instead of several per step. The FMU's functions are passed as
 * pointers (those of the binary the caller loaded, e.g. fmpy's), the instance stays the
 * caller's. */
typedef struct {
    void *do_step;     /* fmi2DoStepTYPE * */
    void *get_real;    /* fmi2GetRealTYPE * */
    void *get_integer; /* fmi2GetIntegerTYPE * */
    void *get_boolean; /* fmi2GetBooleanTYPE * */
    void *component;   /* fmi2Component */
    /* the grid of simulate_cs: t_k = min(k step, stop_time) */
    double step;
    double stop_time;
    /* the outputs read after every step (any count may be 0) */
    size_t n_real;
    const unsigned int *real_vr;
    size_t n_integer;
    const unsigned int *integer_vr;
    size_t n_boolean;
    const unsigned int *boolean_vr;
} csfh_cs_steps_t;

/* Which call failed (failure[0]); failure[1] is its fmi2Status. */
#define CSFH_STEPS_NONE (-1)
#define CSFH_STEPS_DO_STEP 0
#define CSFH_STEPS_GET_REAL 1
#define CSFH_STEPS_GET_INTEGER 2
#define CSFH_STEPS_GET_BOOLEAN 3

/* Steps k = k_first .. k_last - 1 from time t (the grid time reached by step k_first - 1, 0 at
 * the start): step k goes from t to t_next = min((k + 1) step, stop_time), then the outputs are
 * read. Row i (step k_first + i) of the buffers gets t_next (times), the Reals (reals, n_real
 * per row), Integers and Booleans (as fmi2Integer / fmi2Boolean, ints). Returns the number of
 * steps completed with their outputs read; failure = {call, status}: CSFH_STEPS_NONE if all
 * went through (fmi2Warning counts as success), else the call that returned fmi2Error or worse
 * at step k_first + returned value (times[returned value] is then set if fmi2DoStep itself
 * succeeded). -1 for bad arguments. */
CSFH_BATCH_API long long csfh_cs_steps(const csfh_cs_steps_t *loop, long long k_first,
                                       long long k_last, double t, double *times, double *reals,
                                       int *integers, int *booleans, int *failure);

/* The version of this interface (the Python side checks it). */
CSFH_BATCH_API int csfh_cs_batch_abi_version(void);

#endif
