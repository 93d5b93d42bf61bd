/* FMU states and their owner, under ASan + UBSan + LeakSanitizer: states the
 * importer never freed are freed by fmi2FreeInstance (LeakSanitizer reports any leak at exit and
 * the test fails), fmi2Reset keeps them usable, and the FMU-state functions refuse a pointer that
 * is not one of this instance's live states (freed, another instance's, never made) without
 * reading a byte of it (ASan would report the read). Linked with one FMU (cmake/fuzz.cmake). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_model.h"

static int failures = 0;
static int errors_logged = 0;

#define CHECK(cond)                                                                            \
    do {                                                                                       \
        if (!(cond)) {                                                                         \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);           \
            failures++;                                                                        \
        }                                                                                      \
    } while (0)

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof(text), message, args);
    va_end(args);
    if (status >= fmi2Error) {
        errors_logged++;
    }
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static fmi2Component running(fmi2Type type, const char *name)
{
    fmi2Component c = fmi2Instantiate(name, type, fmu_model.guid, "", &callbacks, fmi2False,
                                      fmi2False);
    CHECK(c != NULL);
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK);
    return c;
}

static void check_type(fmi2Type type)
{
    fmi2Component c = running(type, "owner");
    fmi2Component other = running(type, "other");

    /* states made by this instance: two taken, one deserialized, one freed */
    fmi2FMUstate a = NULL, b = NULL, d = NULL, o = NULL;
    CHECK(fmi2GetFMUstate(c, &a) == fmi2OK && a != NULL);
    CHECK(fmi2GetFMUstate(c, &b) == fmi2OK && b != NULL && b != a);
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, a, &size) == fmi2OK && size > 0);
    fmi2Byte *bytes = (fmi2Byte *)malloc(size);
    CHECK(bytes != NULL && fmi2SerializeFMUstate(c, a, bytes, size) == fmi2OK);
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &d) == fmi2OK && d != NULL);
    fmi2FMUstate stale = b;
    CHECK(fmi2FreeFMUstate(c, &b) == fmi2OK && b == NULL);

    /* pointers that are not this instance's live states: refused, not read, not freed */
    int before = errors_logged;
    CHECK(fmi2SetFMUstate(c, stale) == fmi2Error); /* freed */
    CHECK(fmi2FreeFMUstate(c, &stale) == fmi2Error && stale != NULL); /* double free */
    CHECK(fmi2GetFMUstate(other, &o) == fmi2OK && o != NULL);
    CHECK(fmi2SetFMUstate(c, o) == fmi2Error); /* another instance's */
    fmi2FMUstate o_copy = o;
    CHECK(fmi2FreeFMUstate(c, &o_copy) == fmi2Error && o_copy == o);
    CHECK(fmi2SerializedFMUstateSize(c, o, &size) == fmi2Error);
    void *tiny = malloc(4); /* never made: 4 bytes, far smaller than a state's header */
    CHECK(tiny != NULL);
    CHECK(fmi2SetFMUstate(c, tiny) == fmi2Error);
    CHECK(fmi2SerializeFMUstate(c, tiny, bytes, size) == fmi2Error);
    fmi2FMUstate reuse = tiny;
    CHECK(fmi2GetFMUstate(c, &reuse) == fmi2Error && reuse == tiny); /* would be overwritten */
    free(tiny);
    CHECK(errors_logged == before + 8); /* every refusal says why */

    /* the instance's own states still work, also after fmi2Reset */
    CHECK(fmi2SetFMUstate(c, d) == fmi2OK);
    CHECK(fmi2Reset(c) == fmi2OK);
    CHECK(fmi2SetFMUstate(c, a) == fmi2OK);
    CHECK(fmi2GetFMUstate(c, &a) == fmi2OK); /* reused in place */
    free(bytes);

    /* a and d (this instance) and o (the other) are left for fmi2FreeInstance */
    fmi2FreeInstance(c);
    fmi2FreeInstance(other);
}

int main(void)
{
    check_type(fmi2CoSimulation);
    check_type(fmi2ModelExchange);
    /* many states left behind: all freed (LeakSanitizer checks at exit) */
    fmi2Component c = running(fmi2CoSimulation, "many");
    for (int i = 0; i < 100; i++) {
        fmi2FMUstate s = NULL;
        CHECK(fmi2GetFMUstate(c, &s) == fmi2OK);
    }
    fmi2FreeInstance(c);
    if (failures > 0) {
        fprintf(stderr, "%d checks failed (%s)\n", failures, fmu_model.model_identifier);
        return 1;
    }
    printf("FMU states: owned, refused when foreign, freed with the instance (%s)\n",
           fmu_model.model_identifier);
    return 0;
}
