/* The FMI 2.0 loader of the conformance importers: see fmi2_import.h (and import_common.h for
 * the part shared with the FMI 3.0 loader). */
#include "fmi2_import.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#define IMP_PLATFORM "win64"
#elif defined(__APPLE__)
#define IMP_PLATFORM "darwin64"
#else
#define IMP_PLATFORM "linux64"
#endif

/* ------------------------------------------------------------------------------------------ */
/* model description */

static void read_model_description(importer_t *imp, fmi2Type kind, const char *program)
{
    imp_read_model_description(&imp->run, program);
    imp_model_t *md = &imp->run.md;
    const char *root = imp_xml_element(md->xml, "fmiModelDescription");
    const char *iface =
        imp_xml_element(md->xml, kind == fmi2ModelExchange ? "ModelExchange" : "CoSimulation");
    char text[64];
    if (root == NULL || imp_xml_attribute(root, "guid", md->token, sizeof(md->token)) != 0) {
        imp_die(program, "%s/modelDescription.xml: no fmiModelDescription guid",
                imp->run.opt.fmu_dir);
    }
    if (iface == NULL || imp_xml_attribute(iface, "modelIdentifier", md->model_identifier,
                                           sizeof(md->model_identifier)) != 0) {
        imp_die(program, "%s: the FMU has no %s interface", imp->run.opt.fmu_dir,
                kind == fmi2ModelExchange ? "ModelExchange" : "CoSimulation");
    }
    md->n_event_indicators = 0;
    if (imp_xml_attribute(root, "numberOfEventIndicators", text, sizeof(text)) == 0) {
        md->n_event_indicators = atoi(text);
    }
    md->n_states = 0; /* the Real variables with a derivative attribute */
    for (const char *p = md->xml; (p = imp_xml_element(p, "Real")) != NULL; p++) {
        if (imp_xml_attribute(p, "derivative", text, sizeof(text)) == 0) {
            md->n_states++;
        }
    }
}

int imp_lookup(const importer_t *imp, const char *name, fmi2ValueReference *vr, char type[16])
{
    char text[256];
    const char *p = imp->run.md.xml;
    for (; (p = imp_xml_element(p, "ScalarVariable")) != NULL; p++) {
        if (imp_xml_attribute(p, "name", text, sizeof(text)) != 0 || strcmp(text, name) != 0) {
            continue;
        }
        if (imp_xml_attribute(p, "valueReference", text, sizeof(text)) != 0) {
            return -1;
        }
        *vr = (fmi2ValueReference)strtoul(text, NULL, 10);
        const char *types[] = {"Real", "Integer", "Boolean", "Enumeration", "String"};
        const char *first = NULL;
        for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); i++) {
            const char *e = imp_xml_element(p + 1, types[i]);
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
    if (status < fmi2Warning && (imp == NULL || !imp->run.opt.verbose)) {
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

void imp_open(importer_t *imp, int argc, char **argv, fmi2Type kind, const char *program)
{
    memset(imp, 0, sizeof(*imp));
    imp_parse_command_line(&imp->run, argc, argv, program);
    imp_options_t *o = &imp->run.opt;
    read_model_description(imp, kind, program);
    /* outputs: the named variables, or the states (the Real variables that have a derivative) */
    if (o->outputs != NULL) {
        imp_split_outputs(&imp->run, program);
    } else {
        char text[256];
        for (const char *p = imp->run.md.xml; (p = imp_xml_element(p, "Real")) != NULL; p++) {
            if (imp_xml_attribute(p, "derivative", text, sizeof(text)) != 0) {
                continue;
            }
            /* the state is the variable with index `derivative` (1-based) */
            const int index = atoi(text);
            const char *v = imp->run.md.xml;
            for (int k = 0; k < index && v != NULL; k++) {
                v = imp_xml_element(v + 1, "ScalarVariable");
            }
            char name[256];
            if (v == NULL || imp_xml_attribute(v, "name", name, sizeof(name)) != 0) {
                imp_die(program, "modelDescription.xml: bad derivative index %s", text);
            }
            imp_add_output(&imp->run, name, strlen(name), program);
        }
    }
    for (int k = 0; k < o->n_outputs; k++) {
        char type[16];
        if (imp_lookup(imp, o->output_names[k], &o->output_vrs[k], type) != 0 ||
            strcmp(type, "Real") != 0) {
            imp_die(program, "--outputs: %s is not a Real variable of the FMU", o->output_names[k]);
        }
    }
    imp_load_library(&imp->run, IMP_PLATFORM, program);
    const unsigned int required =
        FMI2_API_COMMON | (kind == fmi2ModelExchange ? FMI2_API_ME : FMI2_API_CS);
    const char *missing = fmi2_api_load(&imp->api, imp->run.library, required);
    if (missing != NULL) {
        imp_die(program, "%s not found in the binary of %s", missing, imp->run.opt.fmu_dir);
    }
    imp_open_results(&imp->run, program);
}

/* ------------------------------------------------------------------------------------------ */
/* instantiation and initialization */

static fmi2Status set_start(importer_t *imp, const char *assignment)
{
    char name[256];
    const char *eq = strchr(assignment, '=');
    const size_t n = (size_t)(eq - assignment);
    if (n >= sizeof(name)) {
        imp_fail(&imp->run, "start value: name too long");
        return fmi2Error;
    }
    memcpy(name, assignment, n);
    name[n] = '\0';
    const char *value = eq + 1;
    fmi2ValueReference vr;
    char type[16];
    if (imp_lookup(imp, name, &vr, type) != 0) {
        imp_fail(&imp->run, "start value: no variable %s", name);
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
        imp_fail(&imp->run, "start value: %s has the unsupported type %s", name, type);
        return fmi2Error;
    }
    if (s > fmi2Warning) {
        imp_fail(&imp->run, "fmi2Set* of %s = %s failed", name, value);
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
    snprintf(uri, sizeof(uri), "file:///%s/resources", imp->run.opt.fmu_dir);
    imp->c = imp->api.Instantiate("importer", kind, imp->run.md.token, uri, &imp->callbacks,
                                  fmi2False, imp->run.opt.verbose ? fmi2True : fmi2False);
    if (imp->c == NULL) {
        imp_fail(&imp->run, "fmi2Instantiate failed");
        return fmi2Error;
    }
    const double t0 = isfinite(imp->run.md.start_time) ? imp->run.md.start_time : 0.0;
    fmi2Status s = imp->api.SetupExperiment(imp->c, isfinite(tolerance), tolerance, t0, fmi2True,
                                            imp->run.opt.stop);
    if (s > fmi2Warning) {
        imp_fail(&imp->run, "fmi2SetupExperiment failed");
        return s;
    }
    if ((s = imp->api.EnterInitializationMode(imp->c)) > fmi2Warning) {
        imp_fail(&imp->run, "fmi2EnterInitializationMode failed");
        return s;
    }
    for (int i = 0; i < imp->run.opt.n_starts; i++) {
        if ((s = set_start(imp, imp->run.opt.starts[i])) > fmi2Warning) {
            return s;
        }
    }
    if ((s = imp->api.ExitInitializationMode(imp->c)) > fmi2Warning) {
        imp_fail(&imp->run, "fmi2ExitInitializationMode failed");
        return s;
    }
    imp->run.t_reached = t0;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* results */

fmi2Status imp_record(importer_t *imp, double t, int write)
{
    fmi2Real values[IMP_MAX_OUTPUTS];
    const int n = imp->run.opt.n_outputs;
    const fmi2Status s = imp->api.GetReal(imp->c, imp->run.opt.output_vrs, (size_t)n, values);
    if (s > fmi2Warning) {
        imp_fail(&imp->run, "fmi2GetReal of the outputs failed at t = %.17g", t);
        return s;
    }
    imp_record_values(&imp->run, t, values, write);
    return s;
}

int imp_close(importer_t *imp)
{
    const int ok = imp_completed(&imp->run);
    if (imp->c != NULL) {
        if (ok) {
            imp->api.Terminate(imp->c);
        }
        imp->api.FreeInstance(imp->c);
    }
    return imp_finish(&imp->run);
}
