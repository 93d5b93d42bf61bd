/* The FMI-version-independent part of the conformance importers (tests/importers/), shared by the
 * FMI 2.0 loader (fmi2_import.c) and the FMI 3.0 loader (fmi3_import.c): the command line, the
 * scanning of modelDescription.xml, loading the binary, and the results (CSV, events, summary).
 *
 * Portable C11: the only platform-specific code is the masters' shared-library shim
 * (fmu_src/masters/fmu_library.c: dlopen / LoadLibrary); everything else is the C standard
 * library, so the importers build for linux64 and win64 alike.
 *
 * Common command line of every importer (FMI 2.0 and FMI 3.0):
 *
 *   IMPORTER FMU_DIR [options] [NAME=VALUE ...]
 *     FMU_DIR           the unzipped FMU (modelDescription.xml, binaries/<platform>/)
 *     NAME=VALUE        start values by variable name (Real/Float64, Integer/Int32/Int64/
 *                       Enumeration as a number, Boolean as true/false/1/0), set in
 *                       initialization mode
 *     --stop T          stop time (default: DefaultExperiment stopTime)
 *     --rtol R          relative tolerance (default: DefaultExperiment tolerance)
 *     --step H          step size (default: DefaultExperiment stepSize)
 *     --interval DT     output interval (default: DefaultExperiment stepSize)
 *     --outputs A,B,..  Real (Float64) variables written to the CSV (default: the states)
 *     --out FILE        CSV: time and the outputs at every output point
 *     --events FILE     CSV: time and kind of every event
 *     --summary FILE    key = value lines: status, counts, extremes of every output over every
 *                       accepted step
 *     --mode M          importer-specific (see each importer)
 *     --watch NAME      co-simulation masters: the Integer variable whose change asks for a
 *                       smaller step
 *     --max-steps N     give up (status "budget") after N steps (default 10000000)
 *     --verbose         log every FMU message
 * Exit status: 0 completed, 1 the FMU or the integrator failed (the summary says where), 2 bad
 * command line or FMU directory. */
#ifndef CSFH_IMPORT_COMMON_H
#define CSFH_IMPORT_COMMON_H

#include <stddef.h>
#include <stdio.h>

#include "fmu_library.h"

#define IMP_MAX_OUTPUTS 32
#define IMP_MAX_STARTS 64

/* What the importers read from modelDescription.xml. */
typedef struct {
    char token[128];        /* FMI 2.0 guid, FMI 3.0 instantiationToken */
    char model_identifier[128];
    int n_states;
    int n_event_indicators;
    double start_time, stop_time, tolerance, step_size; /* DefaultExperiment (NAN: absent) */
    char *xml;              /* the whole file, kept for variable look-ups */
} imp_model_t;

typedef struct {
    const char *fmu_dir;
    double stop, rtol, step, interval; /* NAN: from the DefaultExperiment */
    const char *mode;
    const char *watch;
    const char *out_path, *events_path, *summary_path;
    long max_steps;
    int verbose;
    int n_outputs;
    const char *output_names[IMP_MAX_OUTPUTS];
    unsigned int output_vrs[IMP_MAX_OUTPUTS]; /* value references (both versions: 32 bits) */
    int n_starts;
    const char *starts[IMP_MAX_STARTS]; /* "NAME=VALUE" */
    const char *outputs;                /* the --outputs list as given (NULL: the states) */
} imp_options_t;

/* One importer run, whatever the FMI version. */
typedef struct {
    imp_options_t opt;
    imp_model_t md;
    void *library;
    FILE *out, *events;
    /* summary */
    long steps, events_count, reinits, rollbacks;
    double t_reached;
    double out_min[IMP_MAX_OUTPUTS], out_max[IMP_MAX_OUTPUTS];
    char status[256];
    char output_name_storage[IMP_MAX_OUTPUTS][256];
} imp_run_t;

typedef fmu_library_function_t imp_function_t;

/* Print "program: message" and exit with status 2 (bad command line or FMU directory). */
void imp_die(const char *program, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3), noreturn))
#endif
    ;

/* Set the summary status (printf-style) unless one is already set; returns 1 for chaining. */
int imp_fail(imp_run_t *run, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Parse the command line into run->opt (everything zeroed first); exits with status 2 on a bad
 * one. */
void imp_parse_command_line(imp_run_t *run, int argc, char **argv, const char *program);

/* Read FMU_DIR/modelDescription.xml into run->md.xml and the DefaultExperiment; exits with status
 * 2 if it cannot be read. */
void imp_read_model_description(imp_run_t *run, const char *program);

/* XML scanning (enough for the modelDescription.xml files read here; entities not decoded). */
const char *imp_xml_element(const char *xml, const char *name); /* next "<name" element */
int imp_xml_attribute(const char *tag, const char *name, char *value, size_t size); /* 0 or -1 */
double imp_xml_attribute_real(const char *tag, const char *name);                  /* or NAN */

/* The outputs: record name k (from --outputs or a default) in run->opt. */
void imp_add_output(imp_run_t *run, const char *name, size_t length, const char *program);
/* Split --outputs into run->opt.output_names (no-op without --outputs). */
void imp_split_outputs(imp_run_t *run, const char *program);

/* Load FMU_DIR/binaries/<platform>/<modelIdentifier><.so|.dll|.dylib>; exits with status 2. */
void imp_load_library(imp_run_t *run, const char *platform, const char *program);
imp_function_t imp_symbol(const imp_run_t *run, const char *name);

/* Open --out and --events and write their headers; reset the extremes. Exits with status 2. */
void imp_open_results(imp_run_t *run, const char *program);

/* Record the outputs `values` at time t: to the CSV when `write`, into the extremes always. */
void imp_record_values(imp_run_t *run, double t, const double *values, int write);

/* One event line. */
void imp_event(imp_run_t *run, double t, const char *kind);

/* Set the status "completed" if none was set; 1 if the run completed. */
int imp_completed(imp_run_t *run);

/* Write the summary, close the files and the library, free the XML (after the instance was
 * freed); returns the exit status (0 if the status is "completed"). */
int imp_finish(imp_run_t *run);

#endif
