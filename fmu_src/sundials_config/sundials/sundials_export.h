/* csfh's export macros for SUNDIALS (written for this project, see sundials_config.h): SUNDIALS is
 * compiled into the FMU binary, whose only exported functions are the fmi2* ones. Its API is
 * therefore hidden on ELF and Mach-O, even in a source build compiled without
 * -fvisibility=hidden, and carries no dllexport/dllimport on Windows. */
#ifndef CSFH_SUNDIALS_EXPORT_H
#define CSFH_SUNDIALS_EXPORT_H

#if (defined(__GNUC__) || defined(__clang__)) && !defined(_WIN32)
#define SUNDIALS_EXPORT __attribute__((visibility("hidden")))
#else
#define SUNDIALS_EXPORT
#endif
#define SUNDIALS_NO_EXPORT SUNDIALS_EXPORT

#if defined(__GNUC__) || defined(__clang__)
#define SUNDIALS_DEPRECATED __attribute__((__deprecated__))
#elif defined(_MSC_VER)
#define SUNDIALS_DEPRECATED __declspec(deprecated)
#else
#define SUNDIALS_DEPRECATED
#endif
#define SUNDIALS_DEPRECATED_EXPORT SUNDIALS_EXPORT SUNDIALS_DEPRECATED
#define SUNDIALS_DEPRECATED_NO_EXPORT SUNDIALS_NO_EXPORT SUNDIALS_DEPRECATED

#endif
