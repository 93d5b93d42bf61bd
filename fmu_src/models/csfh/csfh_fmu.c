/* The csfh FMU's model struct and its variables (csfh_fmu.h). */
#include "csfh_fmu.h"

#include <string.h>

#include "csfh_variables.h"

void csfh_fmu_set_defaults(csfh_fmu_t *f)
{
    memset(f, 0, sizeof(*f));
    for (int i = 0; i < CSFH_NUMBER_OF_VARIABLES; i++) {
        const csfh_variable_t *v = &csfh_variables[i];
        if (!v->has_start) {
            continue;
        }
        if (v->type == CSFH_TYPE_REAL) {
            *csfh_fmu_real(f, v) = v->start;
        } else {
            *csfh_fmu_int(f, v) = (int)v->start;
        }
    }
}

void csfh_fmu_model_defaults(csfh_model_t *m)
{
    csfh_fmu_t f;
    csfh_fmu_set_defaults(&f);
    *m = f.m;
}

const csfh_variable_t *csfh_fmu_variable(const char *name)
{
    if (name == NULL) {
        return NULL;
    }
    for (int i = 0; i < CSFH_NUMBER_OF_VARIABLES; i++) {
        if (strcmp(csfh_variables[i].name, name) == 0) {
            return &csfh_variables[i];
        }
    }
    return NULL;
}

double *csfh_fmu_real(csfh_fmu_t *f, const csfh_variable_t *v)
{
    return (double *)(void *)((char *)f + v->offset);
}

int *csfh_fmu_int(csfh_fmu_t *f, const csfh_variable_t *v)
{
    return (int *)(void *)((char *)f + v->offset);
}

/* Every parameter, state and input in its range and finite: 0, or -1 with a message. */
static int check_all_values(csfh_fmu_t *f, char *msg, size_t msg_size)
{
    for (int i = 0; i < CSFH_NUMBER_OF_VARIABLES; i++) {
        const csfh_variable_t *v = &csfh_variables[i];
        const int checked = v->causality == CSFH_CAUS_PARAMETER || v->is_state ||
                            v->causality == CSFH_CAUS_INPUT;
        if (!checked) {
            continue;
        }
        const double value =
            v->type == CSFH_TYPE_REAL ? *csfh_fmu_real(f, v) : (double)*csfh_fmu_int(f, v);
        if (csfh_check_value(v, value, msg, msg_size) != 0) {
            return -1;
        }
    }
    return 0;
}

int csfh_fmu_prepare(csfh_fmu_t *f, char *msg, size_t msg_size)
{
    if (check_all_values(f, msg, msg_size) != 0) {
        return -1;
    }
    /* the Enumeration parameters set as Integers (for importers that ignore Enumerations); the
     * numbers are range-checked above like the Enumerations */
    if (f->law_number != 0) {
        f->m.p.law = f->law_number;
    }
    if (f->esdu_reading_number != 0) {
        f->m.p.esdu_reading = f->esdu_reading_number;
    }
    if (f->cs_method_number != 0) {
        f->cs_method = f->cs_method_number;
    }
    return csfh_model_prepare(&f->m, msg, msg_size);
}

int csfh_fmu_outputs(csfh_fmu_t *f)
{
    return csfh_model_outputs(&f->m, f->peaks.active ? f->peaks.v : NULL, &f->out);
}

int csfh_fmu_load_outputs(csfh_fmu_t *f)
{
    return csfh_model_load_outputs(&f->m, f->peaks.active ? f->peaks.v : NULL, &f->out);
}
