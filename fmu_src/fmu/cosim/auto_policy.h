/* The `auto` method of co-simulation as a policy over two integrators: one for non-stiff motion
 * (RK45) and one for stiff motion (BDF). It watches windows of AUTO_WINDOW steps: where the
 * non-stiff integrator struggles (more than AUTO_SUSPECT_FAILED of a window's steps fail, or more
 * than AUTO_SUSPECT_STIFF of them sit at its stability limit), the stiff one is tried for two
 * windows (start-up, then measured) and kept if its mean step is more than AUTO_BDF_COST times
 * the non-stiff one's (a BDF step costs about that much more), i.e. where the motion is stiff
 * (resting or rolling contact); otherwise back, with the next trial after 1, 2, 4, ... windows.
 * Every event starts a new segment with the non-stiff integrator.
 *
 * No integrator and no FMI here: the stepper (cosimulation.c) hands over the running
 * integrator's counts and starts what the policy chooses. */
#ifndef CSFH_AUTO_POLICY_H
#define CSFH_AUTO_POLICY_H

#include <stddef.h>

#include "csfh_visibility.h"
#include "integrator.h"

CSFH_INTERNAL_BEGIN

typedef struct {
    cs_counts_t at;   /* the running integrator's counts at the start of the current window */
    double t0;        /* and its time */
    int trial;        /* 0, or the stiff integrator on trial: 1 starting up, 2 measured */
    int holdoff;      /* non-stiff windows left before the next trial */
    int next_holdoff;
    double nonstiff_h; /* the non-stiff integrator's mean step in the window before the trial */
} cs_auto_t;

/* What the policy knows of a finished window. */
typedef struct {
    const char *name; /* the integrator that ran it, */
    int stiff_method; /* 1 if that is the one for stiff motion */
    long steps;       /* its steps, */
    double failed;    /* the fraction of them that failed, */
    double stiff;     /* the fraction at the stability limit, */
    double mean_h;    /* and their mean size, s */
} cs_auto_window_t;

/* What follows a window: the integrator that ran it, the stiff one, or the non-stiff one. */
enum { CS_AUTO_KEEP, CS_AUTO_STIFF, CS_AUTO_NONSTIFF };

/* The choice after the finished window w (pure: a function of the window and the policy's
 * state, which it updates); `nonstiff` names the non-stiff integrator. Writes the decision, if
 * any, to `why` (empty when nothing changes). */
int cs_auto_decide(cs_auto_t *a, const cs_auto_window_t *w, const char *nonstiff, char *why,
                   size_t why_size);

/* A new window at time t, the running integrator's counts `c` (they restart with every (re)start
 * of an integrator). */
void cs_auto_window(cs_auto_t *a, const cs_counts_t *c, double t);
/* A new segment of smooth motion (start, event): a new window, no trial, no hold-off. */
void cs_auto_segment(cs_auto_t *a, const cs_counts_t *c, double t);

/* At the end of a step at t: the choice (CS_AUTO_*) once the running integrator (`running`,
 * stiff_method as in cs_auto_window_t) has completed a window, else CS_AUTO_KEEP. */
int cs_auto_step_end(cs_auto_t *a, const cs_counts_t *c, double t, const char *running,
                     int stiff_method, const char *nonstiff, char *why, size_t why_size);

CSFH_INTERNAL_END

#endif
