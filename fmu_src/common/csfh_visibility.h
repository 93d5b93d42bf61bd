/* Hidden visibility for our internal functions and objects, whatever the compiler flags. The FMU
 * binary must export only the FMI functions: our CMake build hides the rest with
 * -fvisibility=hidden and a version script, but an importer compiling the FMU's sources/ uses its
 * own flags, and an exported internal function (cs_free, fmu_log, ...) could then be interposed
 * by a same-named symbol of another library in the importer's process.
 *
 * Every header of ours puts its declarations between CSFH_INTERNAL_BEGIN and CSFH_INTERNAL_END:
 * they are hidden on ELF and Mach-O, and so are their definitions in the .c files, which take
 * the visibility of the declaration. An explicit attribute still wins (FMI2_Export, CSFH_API).
 * The pair goes AFTER a header's #include lines: a libc or libm function declared hidden would
 * be taken for one of ours and no longer link. Windows DLLs export only what is dllexport'ed. */
#ifndef CSFH_VISIBILITY_H
#define CSFH_VISIBILITY_H

#if (defined(__GNUC__) || defined(__clang__)) && !defined(_WIN32) && !defined(__CYGWIN__)
#define CSFH_INTERNAL_BEGIN _Pragma("GCC visibility push(hidden)")
#define CSFH_INTERNAL_END _Pragma("GCC visibility pop")
#else
#define CSFH_INTERNAL_BEGIN
#define CSFH_INTERNAL_END
#endif

#endif
