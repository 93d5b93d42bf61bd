/* The FMI 3.0 loader of the conformance importers: see fmi3_import.h (and import_common.h for
 * the part shared with the FMI 2.0 loader). */
#include "fmi3_import.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the FMI 3.0 platform tuple of binaries/ (FMI 3.0 standard, section 2.5.1.1) */
#if defined(_WIN32)
#define IMP3_PLATFORM "x86_64-windows"
#elif defined(__APPLE__) && defined(__aarch64__)
#define IMP3_PLATFORM "aarch64-darwin"
#elif defined(__APPLE__)
#define IMP3_PLATFORM "x86_64-darwin"
#elif defined(__aarch64__)
#define IMP3_PLATFORM "aarch64-linux"
#else
#define IMP3_PLATFORM "x86_64-linux"
#endif

/* the variable elements of an FMI 3.0 ModelVariables */
static const char *const variable_types[] = {
    "Float32", "Float64", "Int8",   "UInt8",  "Int16",       "UInt16", "Int32", "UInt32",
    "Int64",   "UInt64",  "Boolean", "String", "Binary", "Enumeration", "Clock"};

/* ------------------------------------------------------------------------------------------ */
/* model description */

/* The variable element whose attribute `key` is `value` (e.g. name, valueReference) in
 * ModelVariables; its type (the element name) into `type`. NULL if there is none. */
static const char *find_variable(const imp_run_t *run, const char *key, const char *value,
                                 char type[16])
{
    const char *begin = imp_xml_element(run->md.xml, "ModelVariables");
    const char *end = begin != NULL ? strstr(begin, "</ModelVariables>") : NULL;
    char text[256];
    for (const char *p = begin; p != NULL && p < end; p = strchr(p + 1, '<')) {
        const size_t n_types = sizeof(variable_types) / sizeof(variable_types[0]);
        for (size_t i = 0; i < n_types; i++) {
            const size_t n = strlen(variable_types[i]);
            const char after = p[n + 1];
            if (strncmp(p + 1, variable_types[i], n) != 0 || (after != ' ' && after != '\n')) {
                continue;
            }
            if (imp_xml_attribute(p, key, text, sizeof(text)) == 0 && strcmp(text, value) == 0) {
                snprintf(type, 16, "%s", variable_types[i]);
                return p;
            }
            break;
        }
    }
    return NULL;
}

static int count_elements(const char *xml, const char *name)
{
    int n = 0;
    for (const char *p = xml; (p = imp_xml_element(p, name)) != NULL; p++) {
        n++;
    }
    return n;
}

static void read_model_description(importer3_t *imp, const char *program)
{
    imp_read_model_description(&imp->run, program);
    imp_model_t *md = &imp->run.md;
    const char *iface_name = imp->kind == IMP3_MODEL_EXCHANGE ? "ModelExchange" : "CoSimulation";
    const char *root = imp_xml_element(md->xml, "fmiModelDescription");
    const char *iface = imp_xml_element(md->xml, iface_name);
    char version[16];
    if (root == NULL || imp_xml_attribute(root, "fmiVersion", version, sizeof(version)) != 0 ||
        strncmp(version, "3.", 2) != 0) {
        imp_die(program, "%s/modelDescription.xml: not an FMI 3.0 model description",
                imp->run.opt.fmu_dir);
    }
    if (imp_xml_attribute(root, "instantiationToken", md->token, sizeof(md->token)) != 0) {
        imp_die(program, "%s/modelDescription.xml: no instantiationToken", imp->run.opt.fmu_dir);
    }
    if (iface == NULL || imp_xml_attribute(iface, "modelIdentifier", md->model_identifier,
                                           sizeof(md->model_identifier)) != 0) {
        imp_die(program, "%s: the FMU has no %s interface", imp->run.opt.fmu_dir, iface_name);
    }
    /* FMI 3.0: the states are listed by their derivatives, the event indicators by themselves,
     * in ModelStructure (in the order of the state and indicator vectors) */
    md->n_states = count_elements(md->xml, "ContinuousStateDerivative");
    md->n_event_indicators = count_elements(md->xml, "EventIndicator");
}

int imp3_lookup(const importer3_t *imp, const char *name, fmi3ValueReference *vr, char type[16])
{
    const char *v = find_variable(&imp->run, "name", name, type);
    char text[32];
    if (v == NULL || imp_xml_attribute(v, "valueReference", text, sizeof(text)) != 0) {
        return -1;
    }
    *vr = (fmi3ValueReference)strtoul(text, NULL, 10);
    return 0;
}

/* Default outputs: the states, in the order of ModelStructure/ContinuousStateDerivative (each
 * derivative's `derivative` attribute is the value reference of its state). */
static void add_state_outputs(importer3_t *imp, const char *program)
{
    char vr[32], state_vr[32], name[256], type[16];
    const char *p = imp->run.md.xml;
    for (; (p = imp_xml_element(p, "ContinuousStateDerivative")) != NULL; p++) {
        const char *der = NULL, *state = NULL;
        if (imp_xml_attribute(p, "valueReference", vr, sizeof(vr)) != 0 ||
            (der = find_variable(&imp->run, "valueReference", vr, type)) == NULL ||
            imp_xml_attribute(der, "derivative", state_vr, sizeof(state_vr)) != 0 ||
            (state = find_variable(&imp->run, "valueReference", state_vr, type)) == NULL ||
            imp_xml_attribute(state, "name", name, sizeof(name)) != 0) {
            imp_die(program, "modelDescription.xml: no state for the derivative %s", vr);
        }
        imp_add_output(&imp->run, name, strlen(name), program);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* loading */

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    const importer3_t *imp = (const importer3_t *)env;
    if (status < fmi3Warning && (imp == NULL || !imp->run.opt.verbose)) {
        return;
    }
    fprintf(stderr, "[importer %s] %s\n", category != NULL ? category : "?",
            message != NULL ? message : "");
}

#define LOAD(field, required)                                                                  \
    do {                                                                                       \
        imp_function_t f_ = imp_symbol(&imp->run, "fmi3" #field);                              \
        if (f_ == NULL && (required)) {                                                        \
            imp_die(program, "fmi3" #field " not found in the binary of %s",                   \
                    imp->run.opt.fmu_dir);                                                     \
        }                                                                                      \
        imp->api.field = (fmi3##field##TYPE *)f_;                                              \
    } while (0)

void imp3_open(importer3_t *imp, int argc, char **argv, imp3_kind_t kind, const char *program)
{
    memset(imp, 0, sizeof(*imp));
    imp_parse_command_line(&imp->run, argc, argv, program);
    imp->kind = kind;
    imp_options_t *o = &imp->run.opt;
    read_model_description(imp, program);
    if (o->outputs != NULL) {
        imp_split_outputs(&imp->run, program);
    } else {
        add_state_outputs(imp, program);
    }
    for (int k = 0; k < o->n_outputs; k++) {
        char type[16];
        fmi3ValueReference vr = 0;
        if (imp3_lookup(imp, o->output_names[k], &vr, type) != 0 || strcmp(type, "Float64") != 0) {
            imp_die(program, "--outputs: %s is not a Float64 variable of the FMU",
                    o->output_names[k]);
        }
        o->output_vrs[k] = vr;
    }
    imp_load_library(&imp->run, IMP3_PLATFORM, program);
    const int me = kind == IMP3_MODEL_EXCHANGE;
    LOAD(InstantiateModelExchange, me);
    LOAD(InstantiateCoSimulation, !me);
    LOAD(FreeInstance, 1);
    LOAD(EnterInitializationMode, 1);
    LOAD(ExitInitializationMode, 1);
    LOAD(Terminate, 1);
    LOAD(SetFloat64, 1);
    LOAD(SetInt32, 1);
    LOAD(SetInt64, 1);
    LOAD(SetBoolean, 1);
    LOAD(GetFloat64, 1);
    LOAD(GetInt32, 1);
    LOAD(GetInt64, 1);
    LOAD(GetBoolean, 1);
    LOAD(GetFMUState, 0);
    LOAD(SetFMUState, 0);
    LOAD(FreeFMUState, 0);
    LOAD(SerializedFMUStateSize, 0);
    LOAD(SerializeFMUState, 0);
    LOAD(DeserializeFMUState, 0);
    LOAD(EnterEventMode, me);
    LOAD(UpdateDiscreteStates, me);
    LOAD(EnterContinuousTimeMode, me);
    LOAD(CompletedIntegratorStep, me);
    LOAD(SetTime, me);
    LOAD(SetContinuousStates, me);
    LOAD(GetContinuousStateDerivatives, me);
    LOAD(GetEventIndicators, me);
    LOAD(GetContinuousStates, me);
    LOAD(GetNominalsOfContinuousStates, me);
    LOAD(EnterStepMode, !me);
    LOAD(DoStep, !me);
    imp_open_results(&imp->run, program);
}

/* ------------------------------------------------------------------------------------------ */
/* instantiation and initialization */

static fmi3Status set_start(importer3_t *imp, const char *assignment)
{
    char name[256];
    const char *eq = strchr(assignment, '=');
    const size_t n = (size_t)(eq - assignment);
    if (n >= sizeof(name)) {
        imp_fail(&imp->run, "start value: name too long");
        return fmi3Error;
    }
    memcpy(name, assignment, n);
    name[n] = '\0';
    const char *value = eq + 1;
    fmi3ValueReference vr;
    char type[16];
    if (imp3_lookup(imp, name, &vr, type) != 0) {
        imp_fail(&imp->run, "start value: no variable %s", name);
        return fmi3Error;
    }
    fmi3Status s;
    if (strcmp(type, "Float64") == 0) {
        const fmi3Float64 x = strtod(value, NULL);
        s = imp->api.SetFloat64(imp->c, &vr, 1, &x, 1);
    } else if (strcmp(type, "Boolean") == 0) {
        const fmi3Boolean b = strcmp(value, "true") == 0 || strcmp(value, "1") == 0;
        s = imp->api.SetBoolean(imp->c, &vr, 1, &b, 1);
    } else if (strcmp(type, "Int32") == 0) {
        const fmi3Int32 i = (fmi3Int32)strtol(value, NULL, 10);
        s = imp->api.SetInt32(imp->c, &vr, 1, &i, 1);
    } else if (strcmp(type, "Int64") == 0 || strcmp(type, "Enumeration") == 0) {
        const fmi3Int64 i = (fmi3Int64)strtoll(value, NULL, 10);
        s = imp->api.SetInt64(imp->c, &vr, 1, &i, 1);
    } else {
        imp_fail(&imp->run, "start value: %s has the unsupported type %s", name, type);
        return fmi3Error;
    }
    if (s > fmi3Warning) {
        imp_fail(&imp->run, "fmi3Set%s of %s = %s failed", type, name, value);
    }
    return s;
}

fmi3Status imp3_initialize(importer3_t *imp, double tolerance, int event_mode_used,
                           int early_return_allowed)
{
    char resources[4200];
    snprintf(resources, sizeof(resources), "%s/resources/", imp->run.opt.fmu_dir);
    const fmi3Boolean logging = imp->run.opt.verbose ? fmi3True : fmi3False;
    if (imp->kind == IMP3_MODEL_EXCHANGE) {
        imp->c = imp->api.InstantiateModelExchange("importer", imp->run.md.token, resources,
                                                   fmi3False, logging, imp, logger);
    } else {
        imp->c = imp->api.InstantiateCoSimulation(
            "importer", imp->run.md.token, resources, fmi3False, logging,
            event_mode_used ? fmi3True : fmi3False, early_return_allowed ? fmi3True : fmi3False,
            NULL, 0, imp, logger, NULL);
    }
    if (imp->c == NULL) {
        imp_fail(&imp->run, "fmi3Instantiate%s failed",
                 imp->kind == IMP3_MODEL_EXCHANGE ? "ModelExchange" : "CoSimulation");
        return fmi3Error;
    }
    const double t0 = isfinite(imp->run.md.start_time) ? imp->run.md.start_time : 0.0;
    fmi3Status s = imp->api.EnterInitializationMode(imp->c, isfinite(tolerance), tolerance, t0,
                                                    fmi3True, imp->run.opt.stop);
    if (s > fmi3Warning) {
        imp_fail(&imp->run, "fmi3EnterInitializationMode failed");
        return s;
    }
    for (int i = 0; i < imp->run.opt.n_starts; i++) {
        if ((s = set_start(imp, imp->run.opt.starts[i])) > fmi3Warning) {
            return s;
        }
    }
    if ((s = imp->api.ExitInitializationMode(imp->c)) > fmi3Warning) {
        imp_fail(&imp->run, "fmi3ExitInitializationMode failed");
        return s;
    }
    imp->run.t_reached = t0;
    return fmi3OK;
}

/* ------------------------------------------------------------------------------------------ */
/* results */

fmi3Status imp3_record(importer3_t *imp, double t, int write)
{
    fmi3Float64 values[IMP_MAX_OUTPUTS];
    fmi3ValueReference vrs[IMP_MAX_OUTPUTS];
    const int n = imp->run.opt.n_outputs;
    for (int k = 0; k < n; k++) {
        vrs[k] = (fmi3ValueReference)imp->run.opt.output_vrs[k];
    }
    const fmi3Status s = imp->api.GetFloat64(imp->c, vrs, (size_t)n, values, (size_t)n);
    if (s > fmi3Warning) {
        imp_fail(&imp->run, "fmi3GetFloat64 of the outputs failed at t = %.17g", t);
        return s;
    }
    imp_record_values(&imp->run, t, values, write);
    return s;
}

int imp3_close(importer3_t *imp)
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
