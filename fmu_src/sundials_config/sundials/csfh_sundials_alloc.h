/* SUNDIALS allocates through csfh's allocator (written for this project; csfh_sundials_alloc.c).
 * sundials_config.h includes this header, so every SUNDIALS source, and every file of ours that
 * includes SUNDIALS' headers, calls malloc, calloc, realloc and free through it.
 *
 * Why: SUNDIALS 6.4.1 does not survive every failed allocation. N_VClone, N_VCloneEmpty and
 * SUNMatClone write to the clone before anyone checks it, SUNContext_Create uses its logger's
 * hash map unchecked, and CVodeFree of a CVODE memory whose set-up failed half-way destroys
 * vectors that were never made. So SUNDIALS never sees a failed allocation: the caller sets
 * aside a reserve up front (csfh_sundials_reserve_make) and puts it in place around its calls of
 * SUNDIALS (csfh_sundials_reserve_enter, _leave); while it is in place, an allocation the C
 * library cannot serve is cut from it. SUNDIALS then goes on with consistent objects, which the
 * caller, seeing the reserve used (csfh_sundials_reserve_used), destroys as usual while the
 * reserve is still in place (free leaves its blocks alone) and reports as out of memory; the
 * reserve is then empty again (csfh_sundials_reserve_reset). No block cut from a reserve
 * outlives the SUNDIALS call it was cut in.
 *
 * The reserve in place is the calling thread's: instances on different threads do not share
 * one. */
#ifndef CSFH_SUNDIALS_ALLOC_H
#define CSFH_SUNDIALS_ALLOC_H

#include <stddef.h>
#include <stdlib.h> /* declared before the macros below rename the names */

#if (defined(__GNUC__) || defined(__clang__)) && !defined(_WIN32)
#define CSFH_SUNDIALS_ALLOC_API __attribute__((visibility("hidden")))
#else
#define CSFH_SUNDIALS_ALLOC_API
#endif

typedef struct csfh_sundials_reserve csfh_sundials_reserve_t;
struct csfh_sundials_reserve {
    unsigned char *base;
    size_t size, used;
    long served;        /* allocations cut from it */
    size_t short_of;    /* bytes it could not serve (then SUNDIALS saw a failure) */
    csfh_sundials_reserve_t *outer; /* the reserve it was set inside of (NULL: none) */
};

/* Set aside `size` bytes: 0, or -1 when out of memory (then r holds nothing). */
CSFH_SUNDIALS_ALLOC_API int csfh_sundials_reserve_make(csfh_sundials_reserve_t *r, size_t size);
CSFH_SUNDIALS_ALLOC_API void csfh_sundials_reserve_free(csfh_sundials_reserve_t *r);
/* Put it in place for the calling thread, and take it away again (the one in place before, if
 * any, is back in place). */
CSFH_SUNDIALS_ALLOC_API void csfh_sundials_reserve_enter(csfh_sundials_reserve_t *r);
CSFH_SUNDIALS_ALLOC_API void csfh_sundials_reserve_leave(csfh_sundials_reserve_t *r);
/* Did an allocation need the reserve (then destroy what SUNDIALS made, before it leaves)? */
CSFH_SUNDIALS_ALLOC_API int csfh_sundials_reserve_used(const csfh_sundials_reserve_t *r);
/* Empty again: every block cut from it is gone. */
CSFH_SUNDIALS_ALLOC_API void csfh_sundials_reserve_reset(csfh_sundials_reserve_t *r);
/* Is a reserve in place on this thread? */
CSFH_SUNDIALS_ALLOC_API int csfh_sundials_reserve_active(void);

CSFH_SUNDIALS_ALLOC_API void *csfh_sundials_malloc(size_t size);
CSFH_SUNDIALS_ALLOC_API void *csfh_sundials_calloc(size_t n, size_t size);
CSFH_SUNDIALS_ALLOC_API void *csfh_sundials_realloc(void *p, size_t size);
CSFH_SUNDIALS_ALLOC_API void csfh_sundials_free(void *p);

/* Object-like, not function-like: SUNDIALS also names members of its operation tables `free`
 * (S->ops->free(S)), which are then renamed alike in every file that sees them. */
#ifndef CSFH_SUNDIALS_ALLOC_IMPL /* (the allocator itself calls the C library's) */
#define malloc csfh_sundials_malloc
#define calloc csfh_sundials_calloc
#define realloc csfh_sundials_realloc
#define free csfh_sundials_free
#endif

#endif
