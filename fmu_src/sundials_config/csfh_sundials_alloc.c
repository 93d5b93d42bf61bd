/* csfh's allocator for SUNDIALS (written for this project; sundials/csfh_sundials_alloc.h says
 * why): the C library's allocation first, and while a reserve is in place, a block cut from it
 * when the C library has none. A cut block carries its size (realloc copies it) and is never
 * given back one by one: the reserve goes as a whole. */
#include <stdint.h>
#include <string.h>

#define CSFH_SUNDIALS_ALLOC_IMPL
#include "sundials/csfh_sundials_alloc.h"

#if defined(_MSC_VER) && !defined(__clang__)
#define THREAD_LOCAL __declspec(thread)
#else
#define THREAD_LOCAL _Thread_local
#endif

/* the header of a cut block: its size, and the alignment malloc gives */
typedef union {
    size_t size;
    long double ld;
    void *p;
    long long ll;
} header_t;

static THREAD_LOCAL csfh_sundials_reserve_t *in_place;

int csfh_sundials_reserve_make(csfh_sundials_reserve_t *r, size_t size)
{
    memset(r, 0, sizeof(*r));
    r->base = (unsigned char *)malloc(size);
    r->size = r->base != NULL ? size : 0;
    return r->base != NULL ? 0 : -1;
}

void csfh_sundials_reserve_free(csfh_sundials_reserve_t *r)
{
    free(r->base);
    memset(r, 0, sizeof(*r));
}

void csfh_sundials_reserve_enter(csfh_sundials_reserve_t *r)
{
    r->outer = in_place;
    in_place = r;
}

void csfh_sundials_reserve_leave(csfh_sundials_reserve_t *r)
{
    in_place = r->outer;
    r->outer = NULL;
}

int csfh_sundials_reserve_used(const csfh_sundials_reserve_t *r)
{
    return r->served > 0 || r->short_of > 0;
}

void csfh_sundials_reserve_reset(csfh_sundials_reserve_t *r)
{
    r->used = 0;
    r->served = 0;
    r->short_of = 0;
}

int csfh_sundials_reserve_active(void)
{
    return in_place != NULL;
}

/* A block of `size` bytes from the innermost reserve in place, or NULL (counted as short). */
static void *cut(size_t size)
{
    csfh_sundials_reserve_t *r = in_place;
    if (r == NULL) {
        return NULL;
    }
    const size_t unit = sizeof(header_t);
    const size_t need = size / unit + (size % unit != 0) + 1; /* units, with the header */
    if (size > r->size || need > (r->size - r->used) / unit) {
        r->short_of += size;
        return NULL;
    }
    header_t *h = (header_t *)(void *)(r->base + r->used);
    h->size = size;
    r->used += need * unit;
    r->served++;
    return h + 1;
}

/* Was p cut from a reserve in place? (Addresses as integers: p and the reserves are different
 * objects.) */
static int is_cut(const void *p)
{
    const uintptr_t a = (uintptr_t)p;
    for (const csfh_sundials_reserve_t *r = in_place; r != NULL; r = r->outer) {
        if (a >= (uintptr_t)r->base && a < (uintptr_t)r->base + r->size) {
            return 1;
        }
    }
    return 0;
}

void *csfh_sundials_malloc(size_t size)
{
    void *p = malloc(size);
    return p != NULL ? p : cut(size);
}

void *csfh_sundials_calloc(size_t n, size_t size)
{
    void *p = calloc(n, size);
    if (p != NULL || n == 0 || size > SIZE_MAX / n) {
        return p;
    }
    p = cut(n * size);
    if (p != NULL) {
        memset(p, 0, n * size);
    }
    return p;
}

void *csfh_sundials_realloc(void *p, size_t size)
{
    if (p == NULL) {
        return csfh_sundials_malloc(size);
    }
    if (!is_cut(p)) {
        return realloc(p, size); /* (its old size is unknown here: nothing to copy into a cut) */
    }
    const size_t old = ((const header_t *)p - 1)->size;
    void *q = csfh_sundials_malloc(size);
    if (q != NULL) {
        memcpy(q, p, old < size ? old : size);
    }
    return q;
}

void csfh_sundials_free(void *p)
{
    if (p != NULL && !is_cut(p)) {
        free(p);
    }
}
