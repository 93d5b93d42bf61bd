/* The kept steps of co-simulation (kept_steps.h). */
#include "kept_steps.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_model.h"

#define NX fmu_model.n_states
#define KEPT_MAX 64       /* steps kept before they are analysed anyway */
#define KEPT_SNAPSHOTS 8  /* discrete states kept for them (events in one communication step) */

struct kept_entry {
    double t0, tn; /* the step */
    double t_cut;  /* where it stops counting: tn, or the event that cut it short */
    int snapshot;  /* the model it ran with: snapshots[snapshot] */
};

/* A kept step as the model sees it (fmu_step_t first: the model's calls come back with it). */
typedef struct {
    fmu_step_t step;
    const kept_steps_t *k;
    const double *record;
} kept_view_t;

static size_t aligned(size_t size)
{
    const size_t align = _Alignof(max_align_t);
    return (size + align - 1) / align * align;
}

static size_t snapshot_stride(void)
{
    return aligned(fmu_model.size);
}

static size_t memory_stride(void)
{
    return aligned(fmu_model.step_memory);
}

static unsigned char *snapshot(const kept_steps_t *k, int i)
{
    return k->snapshots + (size_t)i * snapshot_stride();
}

static unsigned char *memory(const kept_steps_t *k, int i)
{
    return k->memory + (size_t)i * memory_stride();
}

static double *record(const kept_steps_t *k, int i)
{
    return k->records + (size_t)i * k->record_stride;
}

void kept_clear(kept_steps_t *k)
{
    k->n = 0;
    k->n_snapshots = 0;
    k->stale = 1;
}

void kept_free(kept_steps_t *k)
{
    free(k->room);
    k->room = NULL;
}

/* The room at its full size in one block (nothing is zeroed: a restart from outside frees
 * nothing): the snapshots of the model, the entries, the model's memory of each, their records.
 * Grown in steps instead, each growth copied the kept records. */
static int room_alloc(kept_steps_t *k, const cs_integrator_ops_t *ops)
{
    const size_t states = (size_t)KEPT_SNAPSHOTS * snapshot_stride();
    const size_t entries = aligned((size_t)KEPT_MAX * sizeof(kept_entry_t));
    const size_t memories = (size_t)KEPT_MAX * memory_stride();
    const size_t stride = ops->record_size(NX);
    const size_t data = (size_t)KEPT_MAX * stride * sizeof(double);
    unsigned char *room = (unsigned char *)malloc(states + entries + memories + data);
    if (room == NULL) {
        return 0;
    }
    k->room = room;
    k->snapshots = room;
    k->entry = (kept_entry_t *)(void *)(room + states);
    k->memory = room + states + entries;
    k->records = (double *)(void *)(room + states + entries + memories);
    k->record_stride = stride;
    k->ops = ops;
    return 1;
}

/* Keep only the steps from `first` on, and the snapshots they refer to. */
static void keep_from(kept_steps_t *k, int first)
{
    if (first > 0) {
        const size_t n = (size_t)(k->n - first);
        memmove(k->entry, k->entry + first, n * sizeof(kept_entry_t));
        memmove(k->memory, memory(k, first), n * memory_stride());
        memmove(k->records, record(k, first), n * k->record_stride * sizeof(double));
        k->n -= first;
    }
    if (k->n == 0) {
        k->n_snapshots = 0;
        k->stale = 1;
        return;
    }
    const int used = k->entry[0].snapshot; /* the snapshots are in the steps' order */
    if (used > 0) {
        memmove(k->snapshots, snapshot(k, used), (size_t)(k->n_snapshots - used) * snapshot_stride());
        k->n_snapshots -= used;
        for (int i = 0; i < k->n; i++) {
            k->entry[i].snapshot -= used;
        }
    }
}

void kept_drop(kept_steps_t *k, double t)
{
    int first = 0;
    while (first < k->n && k->entry[first].t_cut <= t) {
        first++;
    }
    keep_from(k, first > 0 ? first - 1 : 0);
}

int kept_keep(kept_steps_t *k, void *model, const cs_integrator_ops_t *ops, void *it,
              double comm_start, double t_now, double rtol)
{
    if (k->room == NULL && !room_alloc(k, ops)) {
        return 0;
    }
    if (ops != k->ops) {
        return 0; /* (the records of one integrator: RK45's) */
    }
    if (k->n == KEPT_MAX || (k->stale && k->n_snapshots == KEPT_SNAPSHOTS)) {
        /* piled up in this communication step: analyse them now, keep the last (its end values
         * start the new step) */
        kept_analyse(k, model, comm_start, t_now, rtol);
        keep_from(k, k->n - 1);
    }
    if (k->stale || k->n_snapshots == 0) {
        memcpy(snapshot(k, k->n_snapshots), model, fmu_model.size);
        k->n_snapshots++;
        k->stale = 0;
    }
    const int i = k->n;
    double *rec = record(k, i);
    if (ops->save_step(it, rec) != 0) {
        return 0;
    }
    cs_record_view_t view;
    ops->record_view(rec, NX, &view);
    kept_entry_t *e = &k->entry[i];
    e->t0 = view.t0;
    e->tn = view.tn;
    e->t_cut = e->tn;
    e->snapshot = k->n_snapshots - 1;
    memset(memory(k, i), 0, fmu_model.step_memory);
    k->n++;
    return 1;
}

void kept_event(kept_steps_t *k, double t)
{
    if (k->n > 0) {
        kept_entry_t *e = &k->entry[k->n - 1];
        if (t > e->t0 && t < e->t_cut) {
            e->t_cut = t;
        }
    }
    k->stale = 1;
}

static int kept_dense(const fmu_step_t *step, double t, int k, double *out)
{
    const kept_view_t *v = (const kept_view_t *)(const void *)step;
    v->k->ops->record_dense(v->record, NX, t, k, out);
    return 0;
}

static void view_of(const kept_steps_t *k, int i, double rtol, kept_view_t *v)
{
    const kept_entry_t *e = &k->entry[i];
    cs_record_view_t r;
    k->ops->record_view(record(k, i), NX, &r);
    const fmu_step_t step = {0, 0, e->t0, e->tn, e->tn - e->t0, e->t_cut, rtol, kept_dense,
                             r.y0, r.f0, r.y1, r.f1, snapshot(k, e->snapshot), memory(k, i),
                             NULL, NULL};
    v->step = step;
    v->k = k;
    v->record = record(k, i);
}

void kept_analyse(kept_steps_t *k, void *model, double comm_start, double t, double rtol)
{
    for (int i = 0; i < k->n; i++) {
        const kept_entry_t *e = &k->entry[i];
        if (!(e->t_cut > comm_start && e->t0 < t)) {
            continue; /* outside (kept for its end values only, or not yet reached) */
        }
        kept_view_t v, prev;
        view_of(k, i, rtol, &v);
        const kept_entry_t *p = i > 0 ? &k->entry[i - 1] : NULL;
        if (p != NULL && p->tn == e->t0 && p->t_cut == p->tn && p->snapshot == e->snapshot) {
            view_of(k, i - 1, rtol, &prev);
            v.step.previous = &prev.step;
        }
        fmu_model.analyse_step(model, &v.step, comm_start, t);
    }
}
