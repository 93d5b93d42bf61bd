/* Shared part of the conformance importers: see fmi2_import.h. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L
#endif

#include "fmi2_import.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* the one platform-specific part: shared libraries */

typedef void (*imp_function_t)(void);

#if defined(_WIN32)
#include <windows.h>
#define IMP_PLATFORM "win64"
#define IMP_SUFFIX ".dll"
static void *library_open(const char *path)
{
    return (void *)LoadLibraryA(path);
}
static imp_function_t library_symbol(void *library, const char *name)
{
    return (imp_function_t)(void (*)(void))GetProcAddress((HMODULE)library, name);
}
static void library_close(void *library)
{
    FreeLibrary((HMODULE)library);
}
#else
#include <dlfcn.h>
#if defined(__APPLE__)
#define IMP_PLATFORM "darwin64"
#define IMP_SUFFIX ".dylib"
#else
#define IMP_PLATFORM "linux64"
#define IMP_SUFFIX ".so"
#endif
static void *library_open(const char *path)
{
    return dlopen(path, RTLD_NOW | RTLD_LOCAL);
}
static imp_function_t library_symbol(void *library, const char *name)
{
    void *p = dlsym(library, name);
    imp_function_t f;
    memcpy(&f, &p, sizeof(f)); /* POSIX: object and function pointers have the same form */
    return f;
}
static void library_close(void *library)
{
    dlclose(library);
}
#endif

/* ------------------------------------------------------------------------------------------ */
/* small helpers */

static void die(const char *program, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    fprintf(stderr, "%s: ", program);
    vfprintf(stderr, fmt, args);
    fputc('\n', stderr);
    va_end(args);
    exit(2);
}

int imp_fail(importer_t *imp, const char *fmt, ...)
{
    if (imp->status[0] == '\0') {
        va_list args;
        va_start(args, fmt);
        vsnprintf(imp->status, sizeof(imp->status), fmt, args);
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

/* The attribute `name` of the XML element starting at `tag` (up to its '>'): copies the value
 * (entities are not decoded: the names read here have none) and returns 0, or -1. */
static int attribute(const char *tag, const char *name, char *value, size_t size)
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

static double attribute_real(const char *tag, const char *name)
{
    char text[64];
    return tag != NULL && attribute(tag, name, text, sizeof(text)) == 0 ? strtod(text, NULL) : NAN;
}

static const char *element(const char *xml, const char *name)
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

/* ------------------------------------------------------------------------------------------ */
/* model description */

static void read_model_description(importer_t *imp, fmi2Type kind, const char *program)
{
    imp_model_t *md = &imp->md;
    char path[4096];
    snprintf(path, sizeof(path), "%s/modelDescription.xml", imp->opt.fmu_dir);
    md->xml = read_file(path);
    if (md->xml == NULL) {
        die(program, "cannot read %s", path);
    }
    const char *root = element(md->xml, "fmiModelDescription");
    const char *iface = element(md->xml, kind == fmi2ModelExchange ? "ModelExchange" : "CoSimulation");
    char text[64];
    if (root == NULL || attribute(root, "guid", md->guid, sizeof(md->guid)) != 0) {
        die(program, "%s: no fmiModelDescription guid", path);
    }
    if (iface == NULL || attribute(iface, "modelIdentifier", md->model_identifier,
                                   sizeof(md->model_identifier)) != 0) {
        die(program, "%s: the FMU has no %s interface", path,
            kind == fmi2ModelExchange ? "ModelExchange" : "CoSimulation");
    }
    md->n_event_indicators = 0;
    if (attribute(root, "numberOfEventIndicators", text, sizeof(text)) == 0) {
        md->n_event_indicators = atoi(text);
    }
    md->n_states = 0;
    for (const char *p = md->xml; (p = element(p, "Real")) != NULL; p++) {
        if (attribute(p, "derivative", text, sizeof(text)) == 0) {
            md->n_states++;
        }
    }
    const char *de = element(md->xml, "DefaultExperiment");
    md->start_time = attribute_real(de, "startTime");
    md->stop_time = attribute_real(de, "stopTime");
    md->tolerance = attribute_real(de, "tolerance");
    md->step_size = attribute_real(de, "stepSize");
}

int imp_lookup(const importer_t *imp, const char *name, fmi2ValueReference *vr, char type[16])
{
    char text[256];
    for (const char *p = imp->md.xml; (p = element(p, "ScalarVariable")) != NULL; p++) {
        if (attribute(p, "name", text, sizeof(text)) != 0 || strcmp(text, name) != 0) {
            continue;
        }
        if (attribute(p, "valueReference", text, sizeof(text)) != 0) {
            return -1;
        }
        *vr = (fmi2ValueReference)strtoul(text, NULL, 10);
        const char *types[] = {"Real", "Integer", "Boolean", "Enumeration", "String"};
        const char *first = NULL;
        for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); i++) {
            const char *e = element(p + 1, types[i]);
            if (e != NULL && (first == NULL || e < first)) {
                first = e;
                snprintf(type, 16, "%s", types[i]);
            }
        }
        return first != NULL ? 0 : -1;
    }
    return -1;
}

/* ------------------------------------------------------------------------------------------ */
/* loading */

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    const importer_t *imp = (const importer_t *)env;
    if (status < fmi2Warning && (imp == NULL || !imp->opt.verbose)) {
        return;
    }
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s %s] ", instance != NULL ? instance : "?", category != NULL ? category : "?");
    vfprintf(stderr, message, args);
    fputc('\n', stderr);
    va_end(args);
}

static void *allocate(size_t n, size_t size)
{
    return calloc(n, size);
}

#define LOAD(field, required)                                                                  \
    do {                                                                                       \
        imp_function_t f_ = library_symbol(imp->library, "fmi2" #field);                       \
        if (f_ == NULL && (required)) {                                                        \
            die(program, "fmi2" #field " not found in %s", path);                              \
        }                                                                                      \
        imp->api.field = (fmi2##field##TYPE *)f_;                                              \
    } while (0)

static double option_number(const char *program, const char *option, const char *text)
{
    char *end = NULL;
    const double x = text != NULL ? strtod(text, &end) : NAN;
    if (text == NULL || end == text || *end != '\0' || !isfinite(x)) {
        die(program, "%s needs a finite number, got \"%s\"", option, text != NULL ? text : "");
    }
    return x;
}

void imp_open(importer_t *imp, int argc, char **argv, fmi2Type kind, const char *program)
{
    memset(imp, 0, sizeof(*imp));
    imp_options_t *o = &imp->opt;
    o->stop = o->rtol = o->step = o->interval = NAN;
    o->max_steps = 10000000L;
    const char *outputs = NULL;
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
            outputs = next, i++;
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
            die(program, "unknown option or missing value: %s", a);
        } else if (strchr(a, '=') != NULL) {
            if (o->n_starts == IMP_MAX_STARTS) {
                die(program, "more than %d start values", IMP_MAX_STARTS);
            }
            o->starts[o->n_starts++] = a;
        } else if (o->fmu_dir == NULL) {
            o->fmu_dir = a;
        } else {
            die(program, "unexpected argument %s", a);
        }
    }
    if (o->fmu_dir == NULL) {
        die(program, "usage: %s FMU_DIR [options] [NAME=VALUE ...] (see fmi2_import.h)", program);
    }
    read_model_description(imp, kind, program);
    /* outputs: the named variables, or the states (the Real variables that have a derivative) */
    static char names[IMP_MAX_OUTPUTS][256];
    if (outputs != NULL) {
        const char *p = outputs;
        while (*p != '\0') {
            const char *comma = strchr(p, ',');
            const size_t n = comma != NULL ? (size_t)(comma - p) : strlen(p);
            if (o->n_outputs == IMP_MAX_OUTPUTS || n == 0 || n >= sizeof(names[0])) {
                die(program, "--outputs: too many names or an empty/long name");
            }
            memcpy(names[o->n_outputs], p, n);
            names[o->n_outputs][n] = '\0';
            o->output_names[o->n_outputs] = names[o->n_outputs];
            o->n_outputs++;
            p += n + (comma != NULL ? 1 : 0);
        }
    } else {
        char text[256];
        for (const char *p = imp->md.xml; (p = element(p, "Real")) != NULL; p++) {
            if (attribute(p, "derivative", text, sizeof(text)) != 0) {
                continue;
            }
            /* the state is the variable with index `derivative` (1-based) */
            const int index = atoi(text);
            const char *v = imp->md.xml;
            for (int k = 0; k < index && v != NULL; k++) {
                v = element(v + 1, "ScalarVariable");
            }
            if (v == NULL || o->n_outputs == IMP_MAX_OUTPUTS ||
                attribute(v, "name", names[o->n_outputs], sizeof(names[0])) != 0) {
                die(program, "modelDescription.xml: bad derivative index %s", text);
            }
            o->output_names[o->n_outputs] = names[o->n_outputs];
            o->n_outputs++;
        }
    }
    for (int k = 0; k < o->n_outputs; k++) {
        char type[16];
        if (imp_lookup(imp, o->output_names[k], &o->output_vrs[k], type) != 0 ||
            strcmp(type, "Real") != 0) {
            die(program, "--outputs: %s is not a Real variable of the FMU", o->output_names[k]);
        }
        imp->out_min[k] = INFINITY;
        imp->out_max[k] = -INFINITY;
    }
    char path[4096];
    snprintf(path, sizeof(path), "%s/binaries/%s/%s%s", o->fmu_dir, IMP_PLATFORM,
             imp->md.model_identifier, IMP_SUFFIX);
    imp->library = library_open(path);
    if (imp->library == NULL) {
        die(program, "cannot load %s", path);
    }
    LOAD(Instantiate, 1);
    LOAD(FreeInstance, 1);
    LOAD(SetupExperiment, 1);
    LOAD(EnterInitializationMode, 1);
    LOAD(ExitInitializationMode, 1);
    LOAD(Terminate, 1);
    LOAD(SetReal, 1);
    LOAD(SetInteger, 1);
    LOAD(SetBoolean, 1);
    LOAD(GetReal, 1);
    LOAD(GetInteger, 1);
    LOAD(GetBoolean, 1);
    LOAD(GetFMUstate, 0);
    LOAD(SetFMUstate, 0);
    LOAD(FreeFMUstate, 0);
    LOAD(SerializedFMUstateSize, 0);
    LOAD(SerializeFMUstate, 0);
    LOAD(DeSerializeFMUstate, 0);
    const int me = kind == fmi2ModelExchange;
    LOAD(EnterEventMode, me);
    LOAD(NewDiscreteStates, me);
    LOAD(EnterContinuousTimeMode, me);
    LOAD(CompletedIntegratorStep, me);
    LOAD(SetTime, me);
    LOAD(SetContinuousStates, me);
    LOAD(GetDerivatives, me);
    LOAD(GetEventIndicators, me);
    LOAD(GetContinuousStates, me);
    LOAD(GetNominalsOfContinuousStates, me);
    LOAD(DoStep, !me);
    if (o->out_path != NULL && (imp->out = fopen(o->out_path, "w")) == NULL) {
        die(program, "cannot write %s", o->out_path);
    }
    if (o->events_path != NULL && (imp->events = fopen(o->events_path, "w")) == NULL) {
        die(program, "cannot write %s", o->events_path);
    }
    if (imp->out != NULL) {
        fprintf(imp->out, "time");
        for (int k = 0; k < o->n_outputs; k++) {
            fprintf(imp->out, ",%s", o->output_names[k]);
        }
        fputc('\n', imp->out);
    }
    if (imp->events != NULL) {
        fprintf(imp->events, "time,kind\n");
    }
    imp->t_reached = NAN;
}

/* ------------------------------------------------------------------------------------------ */
/* instantiation and initialization */

static fmi2Status set_start(importer_t *imp, const char *assignment)
{
    char name[256];
    const char *eq = strchr(assignment, '=');
    const size_t n = (size_t)(eq - assignment);
    if (n >= sizeof(name)) {
        imp_fail(imp, "start value: name too long");
        return fmi2Error;
    }
    memcpy(name, assignment, n);
    name[n] = '\0';
    const char *value = eq + 1;
    fmi2ValueReference vr;
    char type[16];
    if (imp_lookup(imp, name, &vr, type) != 0) {
        imp_fail(imp, "start value: no variable %s", name);
        return fmi2Error;
    }
    fmi2Status s;
    if (strcmp(type, "Real") == 0) {
        const fmi2Real x = strtod(value, NULL);
        s = imp->api.SetReal(imp->c, &vr, 1, &x);
    } else if (strcmp(type, "Boolean") == 0) {
        const fmi2Boolean b = strcmp(value, "true") == 0 || strcmp(value, "1") == 0;
        s = imp->api.SetBoolean(imp->c, &vr, 1, &b);
    } else if (strcmp(type, "Integer") == 0 || strcmp(type, "Enumeration") == 0) {
        const fmi2Integer i = (fmi2Integer)strtol(value, NULL, 10);
        s = imp->api.SetInteger(imp->c, &vr, 1, &i);
    } else {
        imp_fail(imp, "start value: %s has the unsupported type %s", name, type);
        return fmi2Error;
    }
    if (s > fmi2Warning) {
        imp_fail(imp, "fmi2Set* of %s = %s failed", name, value);
    }
    return s;
}

fmi2Status imp_initialize(importer_t *imp, fmi2Type kind, double tolerance)
{
    imp->callbacks.logger = logger;
    imp->callbacks.allocateMemory = allocate;
    imp->callbacks.freeMemory = free;
    imp->callbacks.stepFinished = NULL;
    imp->callbacks.componentEnvironment = imp;
    char uri[4200];
    snprintf(uri, sizeof(uri), "file:///%s/resources", imp->opt.fmu_dir);
    imp->c = imp->api.Instantiate("importer", kind, imp->md.guid, uri, &imp->callbacks, fmi2False,
                                  imp->opt.verbose ? fmi2True : fmi2False);
    if (imp->c == NULL) {
        imp_fail(imp, "fmi2Instantiate failed");
        return fmi2Error;
    }
    const double t0 = isfinite(imp->md.start_time) ? imp->md.start_time : 0.0;
    fmi2Status s = imp->api.SetupExperiment(imp->c, isfinite(tolerance), tolerance, t0, fmi2True,
                                            imp->opt.stop);
    if (s > fmi2Warning) {
        imp_fail(imp, "fmi2SetupExperiment failed");
        return s;
    }
    if ((s = imp->api.EnterInitializationMode(imp->c)) > fmi2Warning) {
        imp_fail(imp, "fmi2EnterInitializationMode failed");
        return s;
    }
    for (int i = 0; i < imp->opt.n_starts; i++) {
        if ((s = set_start(imp, imp->opt.starts[i])) > fmi2Warning) {
            return s;
        }
    }
    if ((s = imp->api.ExitInitializationMode(imp->c)) > fmi2Warning) {
        imp_fail(imp, "fmi2ExitInitializationMode failed");
        return s;
    }
    imp->t_reached = t0;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* results */

fmi2Status imp_record(importer_t *imp, double t, int write)
{
    fmi2Real values[IMP_MAX_OUTPUTS];
    const int n = imp->opt.n_outputs;
    const fmi2Status s = imp->api.GetReal(imp->c, imp->opt.output_vrs, (size_t)n, values);
    if (s > fmi2Warning) {
        imp_fail(imp, "fmi2GetReal of the outputs failed at t = %.17g", t);
        return s;
    }
    for (int k = 0; k < n; k++) {
        imp->out_min[k] = values[k] < imp->out_min[k] ? values[k] : imp->out_min[k];
        imp->out_max[k] = values[k] > imp->out_max[k] ? values[k] : imp->out_max[k];
    }
    if (write && imp->out != NULL) {
        fprintf(imp->out, "%.17g", t);
        for (int k = 0; k < n; k++) {
            fprintf(imp->out, ",%.17g", values[k]);
        }
        fputc('\n', imp->out);
    }
    return s;
}

void imp_event(importer_t *imp, double t, const char *kind)
{
    imp->events_count++;
    if (imp->events != NULL) {
        fprintf(imp->events, "%.17g,%s\n", t, kind);
    }
}

int imp_close(importer_t *imp)
{
    if (imp->status[0] == '\0') {
        snprintf(imp->status, sizeof(imp->status), "completed");
    }
    const int ok = strcmp(imp->status, "completed") == 0;
    if (imp->c != NULL) {
        if (ok) {
            imp->api.Terminate(imp->c);
        }
        imp->api.FreeInstance(imp->c);
    }
    if (imp->opt.summary_path != NULL) {
        FILE *f = fopen(imp->opt.summary_path, "w");
        if (f != NULL) {
            fprintf(f, "status = %s\n", imp->status);
            fprintf(f, "t_reached = %.17g\n", imp->t_reached);
            fprintf(f, "steps = %ld\nevents = %ld\nreinits = %ld\nrollbacks = %ld\n", imp->steps,
                    imp->events_count, imp->reinits, imp->rollbacks);
            for (int k = 0; k < imp->opt.n_outputs; k++) {
                fprintf(f, "min %s = %.17g\nmax %s = %.17g\n", imp->opt.output_names[k],
                        imp->out_min[k], imp->opt.output_names[k], imp->out_max[k]);
            }
            fclose(f);
        }
    }
    if (!ok) {
        fprintf(stderr, "importer: %s\n", imp->status);
    }
    if (imp->out != NULL) {
        fclose(imp->out);
    }
    if (imp->events != NULL) {
        fclose(imp->events);
    }
    if (imp->library != NULL) {
        library_close(imp->library);
    }
    free(imp->md.xml);
    return ok ? 0 : 1;
}
