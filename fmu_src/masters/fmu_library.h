/* Shared libraries for the masters and importers that load an FMU's binary (the batch master,
 * the conformance importers of tests/importers/, the benchmark master): the one
 * platform-specific part of them, POSIX dlopen or Windows LoadLibrary. */
#ifndef CSFH_FMU_LIBRARY_H
#define CSFH_FMU_LIBRARY_H

/* The file name suffix of a shared library on this platform (binaries/<platform>/<id><suffix>). */
#if defined(_WIN32)
#define FMU_LIBRARY_SUFFIX ".dll"
#elif defined(__APPLE__)
#define FMU_LIBRARY_SUFFIX ".dylib"
#else
#define FMU_LIBRARY_SUFFIX ".so"
#endif

/* Any function of a library (called only through its own type). */
typedef void (*fmu_library_function_t)(void);

/* The library at path, or NULL (fmu_library_error says why). */
void *fmu_library_open(const char *path);
/* Its function `name`, or NULL. */
fmu_library_function_t fmu_library_symbol(void *library, const char *name);
void fmu_library_close(void *library);
/* Why the last fmu_library_open failed. */
const char *fmu_library_error(void);

#endif
