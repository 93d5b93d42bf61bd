/* Shared libraries (fmu_library.h). */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L
#endif

#include "fmu_library.h"

#include <stdio.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>

void *fmu_library_open(const char *path)
{
    return (void *)LoadLibraryA(path);
}

fmu_library_function_t fmu_library_symbol(void *library, const char *name)
{
    return (fmu_library_function_t)(void (*)(void))GetProcAddress((HMODULE)library, name);
}

void fmu_library_close(void *library)
{
    FreeLibrary((HMODULE)library);
}

const char *fmu_library_error(void)
{
    static char message[64];
    snprintf(message, sizeof message, "LoadLibrary failed, error %lu", (unsigned long)GetLastError());
    return message;
}
#else
#include <dlfcn.h>

void *fmu_library_open(const char *path)
{
    return dlopen(path, RTLD_NOW | RTLD_LOCAL);
}

fmu_library_function_t fmu_library_symbol(void *library, const char *name)
{
    void *p = dlsym(library, name);
    fmu_library_function_t f;
    memcpy(&f, &p, sizeof f); /* POSIX: object and function pointers have the same form */
    return f;
}

void fmu_library_close(void *library)
{
    dlclose(library);
}

const char *fmu_library_error(void)
{
    const char *e = dlerror();
    return e != NULL ? e : "unknown error";
}
#endif
