/* The FMI 2.0 loader of the conformance importers (tests/importers/): load an unzipped FMI 2.0
 * FMU, read what an importer needs from its modelDescription.xml, instantiate and initialise,
 * record the outputs. The version-independent part (command line, XML scanning, shared
 * libraries, CSV and summary files) is import_common.h, which documents the command line common
 * to every importer. */
#ifndef CSFH_FMI2_IMPORT_H
#define CSFH_FMI2_IMPORT_H

#include <stdio.h>

#include "fmi2_api.h"
#include "fmi2FunctionTypes.h"
#include "import_common.h"

typedef struct {
    imp_run_t run; /* options, model description, results (import_common.h) */
    fmi2_api_t api; /* the FMU's functions (fmu_src/masters/fmi2_api.h) */
    fmi2CallbackFunctions callbacks;
    fmi2Component c;
} importer_t;

/* Parse the command line and load the FMU (modelDescription.xml and the binary); exits with
 * status 2 and a message on failure. `kind` is fmi2ModelExchange or fmi2CoSimulation. */
void imp_open(importer_t *imp, int argc, char **argv, fmi2Type kind, const char *program);

/* Value reference and type ("Real", "Integer", "Boolean", "Enumeration") of a variable; 0 if
 * found, -1 otherwise. */
int imp_lookup(const importer_t *imp, const char *name, fmi2ValueReference *vr, char type[16]);

/* Instantiate, fmi2SetupExperiment(tolerance, start, stop), initialization mode with the start
 * values of the command line, exit initialization mode. fmi2OK or the failing status. */
fmi2Status imp_initialize(importer_t *imp, fmi2Type kind, double tolerance);

/* Record the outputs at time t: to the CSV when `write`, and into the extremes always. */
fmi2Status imp_record(importer_t *imp, double t, int write);

/* Write the summary, free everything; returns the exit status (0 if status is "completed"). */
int imp_close(importer_t *imp);

#endif
