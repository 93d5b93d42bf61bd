/* Failed allocations: every allocation of a representative run of one FMU fails in turn, and
 * the FMU must answer with an error status and a log line, never crash, leak or return a
 * non-finite value as a success (cmake/fuzz.cmake: ctest label "alloc", under ASan + UBSan +
 * LeakSanitizer).
 *
 * The executable is linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc: every
 * allocation of the FMU's code and of the SUNDIALS modules compiled into it (a static library
 * of the same link) comes here first, is counted, and the one numbered CSFH_ALLOC_FAIL returns
 * NULL. The scenario (alloc_fmi2.c or alloc_fmi3.c) is run once with nothing failing (the
 * reference: how many allocations, the digest of the values read), then, in a child process
 * each, once for every allocation N = 1 .. that count with the N-th failing, and once more
 * with every allocation failing while SUNDIALS' reserve is in place (the storm: the reserve
 * alone must serve SUNDIALS, sundials/csfh_sundials_alloc.h). A child that dies of a signal
 * crashed; one that exits nonzero broke an invariant (its message says which), met a sanitizer
 * or leaked (LeakSanitizer). A run whose calls all succeeded must have read exactly the
 * reference's values: a failed allocation is reported or absorbed, never a different result.
 *
 *   alloc_fail_csfh_fmi2                          every allocation in turn, then the storm
 *   CSFH_ALLOC_FAIL=N alloc_fail_csfh_fmi2        only the N-th, in this process (a debugger)
 *   CSFH_ALLOC_FAIL=storm alloc_fail_csfh_fmi2    only the storm
 *   alloc_fail_csfh_fmi2 --verbose                the reference run's calls and messages
 *
 * Allocations inside the C library and the dynamic loader (stdio, thread-local storage) are not
 * the FMU's and are not failed. */
#define _POSIX_C_SOURCE 200809L /* alarm, fork */

#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "alloc_fail.h"
#define CSFH_SUNDIALS_ALLOC_IMPL /* (its declarations, not its names for the C library's) */
#include "sundials/csfh_sundials_alloc.h"

#define RUN_ALARM_S 60 /* a run that takes longer hangs */

/* ------------------------------------------------------------------------------------------ */
/* the allocator */

void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);
void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t size);

static long allocations; /* counted so far in this run */
static long fail_at;     /* the allocation that fails (0: none) */
static int storm;        /* every allocation while SUNDIALS' reserve is in place fails */

static int fails(void)
{
    return ++allocations == fail_at || (storm && csfh_sundials_reserve_active());
}

void *__wrap_malloc(size_t size)
{
    return fails() ? NULL : __real_malloc(size);
}

void *__wrap_calloc(size_t n, size_t size)
{
    return fails() ? NULL : __real_calloc(n, size);
}

void *__wrap_realloc(void *p, size_t size)
{
    return fails() ? NULL : __real_realloc(p, size);
}

void *alloc_own(size_t size)
{
    void *p = __real_malloc(size > 0 ? size : 1);
    if (p == NULL) {
        fprintf(stderr, "alloc_fail: the driver is out of memory\n");
        _exit(2);
    }
    return p;
}

void alloc_own_free(void *p)
{
    free(p);
}

/* ------------------------------------------------------------------------------------------ */
/* judging the calls */

static int verbose;
static long errors_logged;
static long mark_allocations, mark_errors;
static int errors_returned;   /* calls that returned Error in this run */
static char failed_in[96];    /* the call during which the allocation failed */
static uint64_t digest;       /* of the values read */

/* what fails in this run, for messages */
static const char *failing(char *text, size_t size)
{
    if (storm) {
        snprintf(text, size, "every allocation of SUNDIALS failing");
    } else {
        snprintf(text, size, "allocation %ld failing", fail_at);
    }
    return text;
}

static void broken(const char *name, const char *what)
{
    char text[64];
    fprintf(stderr, "alloc_fail (%s): %s (in %s): %s returned %s\n", fmu_model.model_identifier,
            failing(text, sizeof(text)), failed_in[0] ? failed_in : "no call yet", name, what);
    _exit(1); /* (the failure is the report: no leak check on top) */
}

void alloc_call_begin(void)
{
    mark_allocations = allocations;
    mark_errors = errors_logged;
}

static void note_failure(const char *name)
{
    if (fail_at > mark_allocations && fail_at <= allocations) {
        snprintf(failed_in, sizeof(failed_in), "%s", name);
    }
}

int alloc_call_end(const char *name, int status)
{
    note_failure(name);
    if (verbose) {
        fprintf(stderr, "  %-40s -> %d (%ld allocations)\n", name, status,
                allocations - mark_allocations);
    }
    if (status < ALLOC_OK || status > ALLOC_ERROR) {
        char what[48];
        snprintf(what, sizeof(what), "status %d", status);
        broken(name, what);
    }
    if (status == ALLOC_ERROR) {
        errors_returned++;
        if (errors_logged == mark_errors) {
            broken(name, "an error without logging one");
        }
    }
    return status;
}

int alloc_instance_end(const char *name, int made)
{
    note_failure(name);
    if (verbose) {
        fprintf(stderr, "%s -> %s (%ld allocations)\n", name, made ? "made" : "NULL",
                allocations - mark_allocations);
    }
    if (!made) {
        errors_returned++;
        if (errors_logged == mark_errors) {
            broken(name, "NULL without logging an error");
        }
    }
    return made;
}

void alloc_logged(int status, const char *category, const char *message)
{
    if (status == ALLOC_ERROR) {
        errors_logged++;
    }
    if (strstr(message, "reserve was short") != NULL) {
        fprintf(stderr, "alloc_fail (%s): %s\n", fmu_model.model_identifier, message);
        broken("SUNDIALS", "a failed allocation: its reserve was too small");
    }
    if (verbose || (status == ALLOC_ERROR && getenv("CSFH_ALLOC_FAIL") != NULL)) {
        fprintf(stderr, "    [%s] %s\n", category, message);
    }
}

void alloc_values(const char *name, int status, const double *x, size_t n)
{
    if (status > ALLOC_WARNING) {
        return;
    }
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            broken(name, "a non-finite value with a success status");
        }
    }
    const unsigned char *b = (const unsigned char *)x;
    for (size_t i = 0; i < n * sizeof(double); i++) {
        digest = (digest ^ b[i]) * 0x100000001B3ull;
    }
}

const csfh_variable_t *alloc_variable(const char *name)
{
    for (int i = 0; i < fmu_model.n_variables; i++) {
        if (strcmp(fmu_model.variables[i].name, name) == 0) {
            return &fmu_model.variables[i];
        }
    }
    return NULL;
}

const unsigned int *alloc_reals(size_t *n)
{
    static unsigned int *reals;
    static size_t n_reals;
    if (reals == NULL) {
        reals = (unsigned int *)alloc_own((size_t)fmu_model.n_variables * sizeof(*reals));
        for (int i = 0; i < fmu_model.n_variables; i++) {
            if (fmu_model.variables[i].type == CSFH_TYPE_REAL) {
                reals[n_reals++] = fmu_model.variables[i].vr;
            }
        }
    }
    *n = n_reals;
    return reals;
}

/* ------------------------------------------------------------------------------------------ */
/* the runs */

/* solver.method (the SolverMethod enumeration of modelDescription/variables.toml): auto last,
 * through its switch to BDF */
static const struct {
    const char *name;
    int value;
} methods[] = {{"BDF", 2}, {"Adams", 3}, {"RK45", 4}, {"auto", 1}};

static void run(long n)
{
    allocations = 0;
    fail_at = n;
    errors_logged = 0;
    errors_returned = 0;
    failed_in[0] = '\0';
    digest = 0xCBF29CE484222325ull;
    if (alloc_variable("solver.method") == NULL) {
        alloc_co_simulation("", 0);
    } else {
        for (size_t i = 0; i < sizeof(methods) / sizeof(methods[0]); i++) {
            alloc_co_simulation(methods[i].name, methods[i].value);
        }
    }
    alloc_model_exchange();
}

/* The N-th allocation failing, in this process: 0 if every invariant held. */
static int run_failing(long n, uint64_t reference)
{
    run(n);
    if (errors_returned == 0 && digest != reference) {
        broken("the run", "success everywhere, with values that differ from the reference");
    }
    return 0;
}

static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "alloc_fail: a run did not finish in time (hang)\n";
    (void)!write(2, msg, sizeof(msg) - 1);
    _exit(1);
}

/* The N-th allocation failing (or the storm), in a child: 0, or 1 (reported). */
static int child_run(long n, uint64_t reference)
{
    fflush(NULL);
    const pid_t pid = fork();
    if (pid < 0) {
        perror("alloc_fail: fork");
        exit(2);
    }
    if (pid == 0) {
        alarm(RUN_ALARM_S);
        run_failing(n, reference);
        exit(0); /* LeakSanitizer checks the child's memory at exit */
    }
    int status = 0;
    if (waitpid(pid, &status, 0) != pid) {
        perror("alloc_fail: waitpid");
        exit(2);
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
        return 0;
    }
    fail_at = n;
    char text[64];
    fprintf(stderr, "alloc_fail (%s): %s: %s %d (CSFH_ALLOC_FAIL=%s%.0ld reproduces it)\n",
            fmu_model.model_identifier, failing(text, sizeof(text)),
            WIFSIGNALED(status) ? "killed by signal" : "exit status",
            WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status), storm ? "storm" : "",
            storm ? 0L : n);
    return 1;
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--verbose") == 0) {
            verbose = 1;
        } else {
            fprintf(stderr, "usage: [CSFH_ALLOC_FAIL=N] %s [--verbose]\n", argv[0]);
            return 2;
        }
    }
    signal(SIGALRM, on_alarm);
    run(0); /* the reference */
    verbose = 0;
    const long total = allocations;
    const uint64_t reference = digest;
    if (errors_returned != 0) {
        fprintf(stderr, "alloc_fail (%s): the reference run has %d failed calls\n",
                fmu_model.model_identifier, errors_returned);
        return 1;
    }
    const char *one = getenv("CSFH_ALLOC_FAIL");
    if (one != NULL) {
        storm = strcmp(one, "storm") == 0;
        const long n = storm ? 0 : strtol(one, NULL, 10);
        run_failing(n, reference);
        char text[64];
        printf("%s: %s of %ld (in %s): every call answered\n", fmu_model.model_identifier,
               failing(text, sizeof(text)), total, failed_in[0] ? failed_in : "no call");
        return 0;
    }
    long broken_runs = 0;
    for (long n = 1; n <= total; n++) {
        broken_runs += child_run(n, reference);
    }
    storm = 1; /* every allocation SUNDIALS makes fails: its reserve must serve them all */
    broken_runs += child_run(0, reference);
    printf("%s: %ld allocations, each failed in turn, then every allocation of SUNDIALS: %ld "
           "runs crashed, leaked or broke an invariant\n",
           fmu_model.model_identifier, total, broken_runs);
    return broken_runs == 0 ? 0 : 1;
}
