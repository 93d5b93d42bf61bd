/* Minimal assertion helpers shared by the C unit tests (no external framework).
 *
 *   CHECK_CLOSE(actual, expected, rel_tol, what)   |a - e| <= rel_tol |e|  (|a - e| <= rel_tol if e == 0)
 *   CHECK_ABS(actual, expected, abs_tol, what)     |a - e| <= abs_tol
 *   CHECK_TRUE(cond, what)
 *   CHECK_INT(actual, expected, what)
 *   CHECK_STR_CONTAINS(haystack, needle, what)
 *
 * `what` is a plain string; TFMT(fmt, ...) formats one into a rotating static buffer (for loops).
 * Every failure prints file:line, the values and the error, and is counted; a non-finite actual
 * value always fails. TEST_SUMMARY() prints the totals and evaluates to the exit status of main
 * (nonzero on any failure). With the environment variable CSFH_TEST_VERBOSE set, passing checks
 * are printed too. */
#ifndef CSFH_TEST_H
#define CSFH_TEST_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TEST_PI 3.14159265358979323846

static inline int *csfh_test_failures(void)
{
    static int n = 0;
    return &n;
}

static inline int *csfh_test_checks(void)
{
    static int n = 0;
    return &n;
}

static inline int csfh_test_verbose(void)
{
    static int v = -1;
    if (v < 0) {
        v = getenv("CSFH_TEST_VERBOSE") != NULL;
    }
    return v;
}

/* Format a description into one of 8 rotating buffers (valid until 8 more calls). */
__attribute__((format(printf, 1, 2))) static inline const char *TFMT(const char *fmt, ...)
{
    static char buf[8][256];
    static int next = 0;
    char *b = buf[next];
    next = (next + 1) % 8;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(b, sizeof(buf[0]), fmt, ap);
    va_end(ap);
    return b;
}

static inline void csfh_test_report(int ok, const char *file, int line, const char *what)
{
    (*csfh_test_checks())++;
    if (!ok) {
        (*csfh_test_failures())++;
        printf("FAIL %s:%d: %s\n", file, line, what);
    } else if (csfh_test_verbose()) {
        printf("ok   %s:%d: %s\n", file, line, what);
    }
}

static inline int csfh_test_close(double actual, double expected, double rel_tol, const char *what,
                                  const char *file, int line)
{
    const double diff = fabs(actual - expected);
    const double rel = expected != 0.0 ? diff / fabs(expected) : diff;
    const int ok = isfinite(actual) && isfinite(expected) && rel <= rel_tol;
    csfh_test_report(ok, file, line, what);
    if (!ok || csfh_test_verbose()) {
        printf("     actual %.17g  expected %.17g  rel.err %.3e  (tol %.3e)\n", actual, expected,
               rel, rel_tol);
    }
    return ok;
}

static inline int csfh_test_abs(double actual, double expected, double abs_tol, const char *what,
                                const char *file, int line)
{
    const double diff = fabs(actual - expected);
    const int ok = isfinite(actual) && isfinite(expected) && diff <= abs_tol;
    csfh_test_report(ok, file, line, what);
    if (!ok || csfh_test_verbose()) {
        printf("     actual %.17g  expected %.17g  abs.err %.3e  (tol %.3e)\n", actual, expected,
               diff, abs_tol);
    }
    return ok;
}

static inline int csfh_test_true(int cond, const char *cond_text, const char *what,
                                 const char *file, int line)
{
    csfh_test_report(cond, file, line, what);
    if (!cond) {
        printf("     condition false: %s\n", cond_text);
    }
    return cond;
}

static inline int csfh_test_int(long actual, long expected, const char *what, const char *file,
                                int line)
{
    const int ok = actual == expected;
    csfh_test_report(ok, file, line, what);
    if (!ok) {
        printf("     actual %ld  expected %ld\n", actual, expected);
    }
    return ok;
}

static inline int csfh_test_contains(const char *hay, const char *needle, const char *what,
                                     const char *file, int line)
{
    const int ok = hay != NULL && needle != NULL && strstr(hay, needle) != NULL;
    csfh_test_report(ok, file, line, what);
    if (!ok) {
        printf("     \"%s\" does not contain \"%s\"\n", hay ? hay : "(null)",
               needle ? needle : "(null)");
    }
    return ok;
}

#define CHECK_CLOSE(actual, expected, rel_tol, what)                                             \
    csfh_test_close((actual), (expected), (rel_tol), (what), __FILE__, __LINE__)
#define CHECK_ABS(actual, expected, abs_tol, what)                                               \
    csfh_test_abs((actual), (expected), (abs_tol), (what), __FILE__, __LINE__)
#define CHECK_TRUE(cond, what) csfh_test_true(!!(cond), #cond, (what), __FILE__, __LINE__)
#define CHECK_INT(actual, expected, what)                                                        \
    csfh_test_int((long)(actual), (long)(expected), (what), __FILE__, __LINE__)
#define CHECK_STR_CONTAINS(hay, needle, what)                                                    \
    csfh_test_contains((hay), (needle), (what), __FILE__, __LINE__)

/* Deterministic pseudo-random numbers (xorshift64*), so that failures are reproducible. */
static inline double test_uniform(double lo, double hi)
{
    static uint64_t state = 0x9E3779B97F4A7C15ull;
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    const uint64_t r = state * 0x2545F4914F6CDD1Dull;
    return lo + (hi - lo) * ((double)(r >> 11) * (1.0 / 9007199254740992.0));
}

/* Relative tolerance that reflects a value quoted with `sig` significant digits: half a unit of
 * the last quoted digit, plus 1 % for the rounding of the reference itself. */
static inline double tol_digits(double quoted, int sig)
{
    const double aq = fabs(quoted);
    const double unit = pow(10.0, floor(log10(aq)) - (sig - 1));
    return 0.505 * unit / aq;
}

/* Print the totals; evaluates to the exit status of main. */
static inline int csfh_test_summary(const char *name)
{
    printf("%s: %d checks, %d failures\n", name, *csfh_test_checks(), *csfh_test_failures());
    return *csfh_test_failures() != 0 ? 1 : 0;
}
#define TEST_SUMMARY() csfh_test_summary(__FILE__)

#endif
