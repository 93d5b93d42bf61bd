/* Description of one interface variable: the generated table csfh_variables[] (from
 * modelDescription/variables.toml) is an array of these. Pure data, no FMI types: the FMI glue,
 * the core library's by-name API and the Python harness all read the same table. */
#ifndef CSFH_VARTABLE_H
#define CSFH_VARTABLE_H

#include <stddef.h>

#include "csfh_format.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

typedef enum {
    CSFH_TYPE_REAL,
    CSFH_TYPE_INTEGER,
    CSFH_TYPE_BOOLEAN,
    CSFH_TYPE_ENUMERATION
} csfh_type_t;

typedef enum {
    CSFH_CAUS_PARAMETER,
    CSFH_CAUS_CALCULATED_PARAMETER,
    CSFH_CAUS_INPUT,
    CSFH_CAUS_OUTPUT,
    CSFH_CAUS_LOCAL,
    CSFH_CAUS_INDEPENDENT
} csfh_causality_t;

typedef enum {
    CSFH_STORE_PLAIN,   /* stored in the model struct, read and written directly */
    CSFH_STORE_COMPUTED /* output or derivative: recomputed on demand before it is read */
} csfh_storage_t;

typedef struct {
    unsigned int vr;
    const char *name;
    csfh_type_t type;        /* Real: double storage; Integer/Boolean/Enumeration: int storage */
    csfh_causality_t causality;
    int tunable;             /* variability == tunable */
    int is_state;
    csfh_storage_t storage;
    size_t offset;           /* offset of the value inside the model struct */
    int has_start;
    double start;
    int has_range;           /* value must lie in lo..hi (open or closed ends) */
    double lo, hi;
    int lo_open, hi_open;
    double nominal;          /* nominal value (1 when none is declared) */
} csfh_variable_t;

/* Check one value against the variable's range and finiteness. Returns 0 if valid, else writes
 * a message naming the variable and the value (csfh_vartable.c). */
int csfh_check_value(const csfh_variable_t *v, double value, char *msg, size_t msg_size);

CSFH_INTERNAL_END

#endif
