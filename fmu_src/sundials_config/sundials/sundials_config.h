/* csfh's configuration of SUNDIALS 6.4.1 (written for this project; SUNDIALS' own build generates
 * this header from its template). One fixed configuration for every build of the FMUs: the host
 * build, every cross-compiled platform and the FMU's source build (sources/ of the FMU, where an
 * importer compiles everything with nothing but `-I sources`):
 *
 *   - double precision (sunrealtype = double), 64-bit indices (sunindextype = int64_t);
 *   - serial only: no MPI, no threads, no GPU, no third-party libraries;
 *   - no logging, no profiling, no monitoring, no fused kernels;
 *   - compiled into the FMU binary (static): no symbol of SUNDIALS is exported (see
 *     sundials_export.h for its API, ../hidden/ for the internal functions of CVODE);
 *   - allocations through csfh's allocator, which never lets SUNDIALS see a failed one
 *     (csfh_sundials_alloc.h).
 *
 * Only the macros the compiled modules (cmake/sundials.cmake) read are defined. */
#ifndef CSFH_SUNDIALS_CONFIG_H
#define CSFH_SUNDIALS_CONFIG_H

#include "sundials/sundials_export.h"

/* the release this configuration is for; cmake/sundials.cmake checks the unpacked source */
#define SUNDIALS_VERSION "6.4.1"
#define SUNDIALS_VERSION_MAJOR 6
#define SUNDIALS_VERSION_MINOR 4
#define SUNDIALS_VERSION_PATCH 1
#define SUNDIALS_VERSION_LABEL ""
#define SUNDIALS_GIT_VERSION ""

/* C99 and later compilers (every compiler that builds the FMU is C11) */
#define SUNDIALS_C_COMPILER_HAS_MATH_PRECISIONS
#define SUNDIALS_C_COMPILER_HAS_ISINF_ISNAN
#define SUNDIALS_C_COMPILER_HAS_INLINE
#define SUNDIALS_C_COMPILER_HAS_SNPRINTF_AND_VA_COPY

#define SUNDIALS_DOUBLE_PRECISION 1
#define SUNDIALS_INT64_T 1
#define SUNDIALS_INDEX_TYPE int64_t

#define SUNDIALS_LOGGING_LEVEL 0
#define SUNDIALS_MPI_ENABLED 0

/* the modules compiled in (cmake/sundials.cmake lists their sources) */
#define SUNDIALS_CVODE 1
#define SUNDIALS_ARKODE 1
#define SUNDIALS_NVECTOR_SERIAL 1
#define SUNDIALS_SUNMATRIX_DENSE 1
#define SUNDIALS_SUNLINSOL_DENSE 1
#define SUNDIALS_SUNNONLINSOL_NEWTON 1
#define SUNDIALS_SUNNONLINSOL_FIXEDPOINT 1

#if defined(__GNUC__) || defined(__clang__)
#define SUNDIALS_DEPRECATED_MSG(msg) __attribute__((__deprecated__(msg)))
#elif defined(_MSC_VER)
#define SUNDIALS_DEPRECATED_MSG(msg) __declspec(deprecated(msg))
#else
#define SUNDIALS_DEPRECATED_MSG(msg)
#endif
#define SUNDIALS_DEPRECATED_EXPORT_MSG(msg) SUNDIALS_EXPORT SUNDIALS_DEPRECATED_MSG(msg)
#define SUNDIALS_DEPRECATED_NO_EXPORT_MSG(msg) SUNDIALS_NO_EXPORT SUNDIALS_DEPRECATED_MSG(msg)

#ifndef SUNDIALS_CXX_INLINE
#define SUNDIALS_CXX_INLINE inline
#endif
#ifndef SUNDIALS_C_INLINE
#define SUNDIALS_C_INLINE inline
#endif
#ifdef __cplusplus
#define SUNDIALS_INLINE SUNDIALS_CXX_INLINE
#else
#define SUNDIALS_INLINE SUNDIALS_C_INLINE
#endif
#define SUNDIALS_STATIC_INLINE static SUNDIALS_INLINE

/* last: the allocator's names replace the C library's in what follows */
#include "sundials/csfh_sundials_alloc.h"

#endif
