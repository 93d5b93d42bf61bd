/* The `auto` policy of co-simulation (auto_policy.h). */
#include "auto_policy.h"

#include <stdio.h>

#define AUTO_WINDOW 100L         /* steps per decision */
#define AUTO_SUSPECT_FAILED 0.05 /* failed fraction of a window that triggers a trial */
#define AUTO_SUSPECT_STIFF 0.5   /* fraction of the steps at the stability limit that does */
#define AUTO_BDF_COST 2.0        /* the cost of a BDF step over an RK45 step */
#define AUTO_MAX_HOLDOFF 64      /* most windows between two trials */

int cs_auto_decide(cs_auto_t *a, const cs_auto_window_t *w, const char *nonstiff, char *why,
                   size_t why_size)
{
    why[0] = '\0';
    if (!w->stiff_method) {
        if (a->holdoff > 0) {
            a->holdoff--;
        } else if (w->failed > AUTO_SUSPECT_FAILED || w->stiff > AUTO_SUSPECT_STIFF) {
            a->nonstiff_h = w->mean_h;
            a->trial = 1;
            snprintf(why, why_size,
                     "auto: trying BDF (%.0f %% of %s's steps failed, %.0f %% at its stability "
                     "limit, mean step %.3g s)",
                     100.0 * w->failed, w->name, 100.0 * w->stiff, w->mean_h);
            return CS_AUTO_STIFF;
        }
        return CS_AUTO_KEEP;
    }
    if (a->trial == 1) { /* the start-up window: not measured */
        a->trial = 2;
        return CS_AUTO_KEEP;
    }
    if (a->trial == 2) {
        a->trial = 0;
        if (w->mean_h > AUTO_BDF_COST * a->nonstiff_h) {
            snprintf(why, why_size, "auto: BDF kept (stiff: mean step %.3g s, %s %.3g s)",
                     w->mean_h, nonstiff, a->nonstiff_h);
            return CS_AUTO_KEEP;
        }
        a->holdoff = a->next_holdoff;
        a->next_holdoff = a->next_holdoff < AUTO_MAX_HOLDOFF ? 2 * a->next_holdoff : AUTO_MAX_HOLDOFF;
        snprintf(why, why_size, "auto: back to %s (BDF's mean step %.3g s, %s %.3g s)",
                 nonstiff, w->mean_h, nonstiff, a->nonstiff_h);
        return CS_AUTO_NONSTIFF;
    }
    return CS_AUTO_KEEP;
}

void cs_auto_window(cs_auto_t *a, const cs_counts_t *c, double t)
{
    a->at = *c;
    a->t0 = t;
}

void cs_auto_segment(cs_auto_t *a, const cs_counts_t *c, double t)
{
    cs_auto_window(a, c, t);
    a->trial = 0;
    a->holdoff = 0;
    a->next_holdoff = 1;
}

int cs_auto_step_end(cs_auto_t *a, const cs_counts_t *c, double t, const char *running,
                     int stiff_method, const char *nonstiff, char *why, size_t why_size)
{
    why[0] = '\0';
    cs_auto_window_t w = {running, stiff_method, c->steps - a->at.steps, 0.0, 0.0, 0.0};
    if (w.steps < AUTO_WINDOW) {
        return CS_AUTO_KEEP;
    }
    w.failed = (double)(c->fails - a->at.fails) / (double)w.steps;
    w.stiff = (double)(c->stiff - a->at.stiff) / (double)w.steps;
    w.mean_h = (t - a->t0) / (double)w.steps;
    cs_auto_window(a, c, t);
    return cs_auto_decide(a, &w, nonstiff, why, why_size);
}
