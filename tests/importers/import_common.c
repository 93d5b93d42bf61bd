/* The FMI-version-independent part of the conformance importers: see import_common.h. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L
#endif

#include "import_common.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

imp_function_t imp_symbol(const imp_run_t *run, const char *name)
{
    return fmu_library_symbol(run->library, name);
}

void imp_load_library(imp_run_t *run, const char *platform, const char *program)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/binaries/%s/%s%s", run->opt.fmu_dir, platform,
             run->md.model_identifier, FMU_LIBRARY_SUFFIX);
    run->library = fmu_library_open(path);
    if (run->library == NULL) {
        imp_die(program, "cannot load %s", path);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* small helpers */

void imp_die(const char *program, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    fprintf(stderr, "%s: ", program);
    vfprintf(stderr, fmt, args);
    fputc('\n', stderr);
    va_end(args);
    exit(2);
}

int imp_fail(imp_run_t *run, const char *fmt, ...)
{
    if (run->status[0] == '\0') {
        va_list args;
        va_start(args, fmt);
        vsnprintf(run->status, sizeof(run->status), fmt, args);
        va_end(args);
    }
    return 1;
}

static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    size_t size = 0, capacity = 1 << 16;
    char *text = (char *)malloc(capacity);
    while (text != NULL) {
        size += fread(text + size, 1, capacity - size - 1, f);
        if (size + 1 < capacity) {
            break;
        }
        capacity *= 2;
        char *bigger = (char *)realloc(text, capacity);
        if (bigger == NULL) {
            free(text);
        }
        text = bigger;
    }
    fclose(f);
    if (text != NULL) {
        text[size] = '\0';
    }
    return text;
}

/* ------------------------------------------------------------------------------------------ */
/* XML scanning */

int imp_xml_attribute(const char *tag, const char *name, char *value, size_t size)
{
    const char *end = strchr(tag, '>');
    const size_t n = strlen(name);
    for (const char *p = tag; p != NULL && (end == NULL || p < end); p = strchr(p + 1, ' ')) {
        const char *a = p + 1;
        while (*a == ' ' || *a == '\n' || *a == '\t' || *a == '\r') {
            a++;
        }
        if (strncmp(a, name, n) == 0 && a[n] == '=' && a[n + 1] == '"') {
            const char *v = a + n + 2;
            const char *q = strchr(v, '"');
            if (q == NULL || (size_t)(q - v) >= size) {
                return -1;
            }
            memcpy(value, v, (size_t)(q - v));
            value[q - v] = '\0';
            return 0;
        }
    }
    return -1;
}

double imp_xml_attribute_real(const char *tag, const char *name)
{
    char text[64];
    return tag != NULL && imp_xml_attribute(tag, name, text, sizeof(text)) == 0
               ? strtod(text, NULL)
               : NAN;
}

const char *imp_xml_element(const char *xml, const char *name)
{
    char pattern[64];
    snprintf(pattern, sizeof(pattern), "<%s", name);
    const char *p = xml;
    while ((p = strstr(p, pattern)) != NULL) {
        const char c = p[strlen(pattern)];
        if (c == ' ' || c == '>' || c == '/' || c == '\n' || c == '\r' || c == '\t') {
            return p;
        }
        p++;
    }
    return NULL;
}

void imp_read_model_description(imp_run_t *run, const char *program)
{
    imp_model_t *md = &run->md;
    char path[4096];
    snprintf(path, sizeof(path), "%s/modelDescription.xml", run->opt.fmu_dir);
    md->xml = read_file(path);
    if (md->xml == NULL) {
        imp_die(program, "cannot read %s", path);
    }
    const char *de = imp_xml_element(md->xml, "DefaultExperiment");
    md->start_time = imp_xml_attribute_real(de, "startTime");
    md->stop_time = imp_xml_attribute_real(de, "stopTime");
    md->tolerance = imp_xml_attribute_real(de, "tolerance");
    md->step_size = imp_xml_attribute_real(de, "stepSize");
}

/* ------------------------------------------------------------------------------------------ */
/* command line */

static double option_number(const char *program, const char *option, const char *text)
{
    char *end = NULL;
    const double x = text != NULL ? strtod(text, &end) : NAN;
    if (text == NULL || end == text || *end != '\0' || !isfinite(x)) {
        imp_die(program, "%s needs a finite number, got \"%s\"", option, text != NULL ? text : "");
    }
    return x;
}

void imp_parse_command_line(imp_run_t *run, int argc, char **argv, const char *program)
{
    memset(run, 0, sizeof(*run));
    imp_options_t *o = &run->opt;
    o->stop = o->rtol = o->step = o->interval = NAN;
    o->max_steps = 10000000L;
    run->t_reached = NAN;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--stop") == 0) {
            o->stop = option_number(program, a, next), i++;
        } else if (strcmp(a, "--rtol") == 0) {
            o->rtol = option_number(program, a, next), i++;
        } else if (strcmp(a, "--step") == 0) {
            o->step = option_number(program, a, next), i++;
        } else if (strcmp(a, "--interval") == 0) {
            o->interval = option_number(program, a, next), i++;
        } else if (strcmp(a, "--max-steps") == 0) {
            o->max_steps = (long)option_number(program, a, next), i++;
        } else if (strcmp(a, "--outputs") == 0 && next != NULL) {
            o->outputs = next, i++;
        } else if (strcmp(a, "--out") == 0 && next != NULL) {
            o->out_path = next, i++;
        } else if (strcmp(a, "--events") == 0 && next != NULL) {
            o->events_path = next, i++;
        } else if (strcmp(a, "--summary") == 0 && next != NULL) {
            o->summary_path = next, i++;
        } else if (strcmp(a, "--watch") == 0 && next != NULL) {
            o->watch = next, i++;
        } else if (strcmp(a, "--mode") == 0 && next != NULL) {
            o->mode = next, i++;
        } else if (strcmp(a, "--verbose") == 0) {
            o->verbose = 1;
        } else if (a[0] == '-' && a[1] == '-') {
            imp_die(program, "unknown option or missing value: %s", a);
        } else if (strchr(a, '=') != NULL) {
            if (o->n_starts == IMP_MAX_STARTS) {
                imp_die(program, "more than %d start values", IMP_MAX_STARTS);
            }
            o->starts[o->n_starts++] = a;
        } else if (o->fmu_dir == NULL) {
            o->fmu_dir = a;
        } else {
            imp_die(program, "unexpected argument %s", a);
        }
    }
    if (o->fmu_dir == NULL) {
        imp_die(program, "usage: %s FMU_DIR [options] [NAME=VALUE ...] (see import_common.h)",
                program);
    }
}

void imp_add_output(imp_run_t *run, const char *name, size_t length, const char *program)
{
    imp_options_t *o = &run->opt;
    if (o->n_outputs == IMP_MAX_OUTPUTS || length == 0 ||
        length >= sizeof(run->output_name_storage[0])) {
        imp_die(program, "outputs: too many names or an empty/long name");
    }
    char *storage = run->output_name_storage[o->n_outputs];
    memcpy(storage, name, length);
    storage[length] = '\0';
    o->output_names[o->n_outputs++] = storage;
}

void imp_split_outputs(imp_run_t *run, const char *program)
{
    const char *p = run->opt.outputs;
    while (p != NULL && *p != '\0') {
        const char *comma = strchr(p, ',');
        const size_t n = comma != NULL ? (size_t)(comma - p) : strlen(p);
        imp_add_output(run, p, n, program);
        p += n + (comma != NULL ? 1 : 0);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* results */

void imp_open_results(imp_run_t *run, const char *program)
{
    const imp_options_t *o = &run->opt;
    for (int k = 0; k < o->n_outputs; k++) {
        run->out_min[k] = INFINITY;
        run->out_max[k] = -INFINITY;
    }
    if (o->out_path != NULL && (run->out = fopen(o->out_path, "w")) == NULL) {
        imp_die(program, "cannot write %s", o->out_path);
    }
    if (o->events_path != NULL && (run->events = fopen(o->events_path, "w")) == NULL) {
        imp_die(program, "cannot write %s", o->events_path);
    }
    if (run->out != NULL) {
        fprintf(run->out, "time");
        for (int k = 0; k < o->n_outputs; k++) {
            fprintf(run->out, ",%s", o->output_names[k]);
        }
        fputc('\n', run->out);
    }
    if (run->events != NULL) {
        fprintf(run->events, "time,kind\n");
    }
}

void imp_record_values(imp_run_t *run, double t, const double *values, int write)
{
    const int n = run->opt.n_outputs;
    for (int k = 0; k < n; k++) {
        run->out_min[k] = values[k] < run->out_min[k] ? values[k] : run->out_min[k];
        run->out_max[k] = values[k] > run->out_max[k] ? values[k] : run->out_max[k];
    }
    if (write && run->out != NULL) {
        fprintf(run->out, "%.17g", t);
        for (int k = 0; k < n; k++) {
            fprintf(run->out, ",%.17g", values[k]);
        }
        fputc('\n', run->out);
    }
}

void imp_event(imp_run_t *run, double t, const char *kind)
{
    run->events_count++;
    if (run->events != NULL) {
        fprintf(run->events, "%.17g,%s\n", t, kind);
    }
}

int imp_completed(imp_run_t *run)
{
    if (run->status[0] == '\0') {
        snprintf(run->status, sizeof(run->status), "completed");
    }
    return strcmp(run->status, "completed") == 0;
}

int imp_finish(imp_run_t *run)
{
    const int ok = imp_completed(run);
    if (run->opt.summary_path != NULL) {
        FILE *f = fopen(run->opt.summary_path, "w");
        if (f != NULL) {
            fprintf(f, "status = %s\n", run->status);
            fprintf(f, "t_reached = %.17g\n", run->t_reached);
            fprintf(f, "steps = %ld\nevents = %ld\nreinits = %ld\nrollbacks = %ld\n", run->steps,
                    run->events_count, run->reinits, run->rollbacks);
            for (int k = 0; k < run->opt.n_outputs; k++) {
                fprintf(f, "min %s = %.17g\nmax %s = %.17g\n", run->opt.output_names[k],
                        run->out_min[k], run->opt.output_names[k], run->out_max[k]);
            }
            fclose(f);
        }
    }
    if (!ok) {
        fprintf(stderr, "importer: %s\n", run->status);
    }
    if (run->out != NULL) {
        fclose(run->out);
    }
    if (run->events != NULL) {
        fclose(run->events);
    }
    if (run->library != NULL) {
        fmu_library_close(run->library);
    }
    free(run->md.xml);
    return ok ? 0 : 1;
}
