/* The integrator interface of co-simulation: what the event loop (cosimulation.c) asks of an
 * integrator, as a table of functions, with one implementation per file:
 *   integrator_rk45.c   our explicit Runge-Kutta 5(4) (../../solvers/rk45.c);
 *   integrator_cvode.c  SUNDIALS CVODE, BDF (Newton iteration, dense linear solver) or Adams
 *                       (fixed-point iteration).
 * The stepper never asks which one runs: what differs (a first-step hint, saved step records) is
 * in the table, NULL where an integrator does not have it.
 *
 * No FMI types: the host (the stepper) gives the right-hand side, the root functions (the event
 * indicators) and where the integrator's messages go. Every time here is the stepper's local time
 * (cosimulation.c: measured from its time origin). */
#ifndef CSFH_INTEGRATOR_H
#define CSFH_INTEGRATOR_H

#include <stddef.h>

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* What one call of step reached: the end of a new step, a root (the first one inside the last
 * step), the stop time, or a failure (reported through the problem's callbacks). */
enum { CS_STEP_OK = 0, CS_STEP_ROOT = 1, CS_STEP_TSTOP = 2, CS_STEP_FAILED = -1 };

/* The problem an integrator solves, and its host. */
typedef struct {
    int n;                 /* states (>= 1) */
    int n_roots;           /* root functions (>= 0) */
    double rtol;           /* relative tolerance */
    const double *atol;    /* n absolute tolerances, the host's array (it outlives the integrator) */
    double first_step_max; /* s: bound of the first step after a (re)start */
    /* ydot = f(t, y): 0, > 0 recoverable (the integrator tries a smaller step), < 0 fatal */
    int (*rhs)(double t, const double *y, double *ydot, void *host);
    /* g(t, y), n_roots values: 0, or nonzero to fail the step (NULL when n_roots is 0) */
    int (*roots)(double t, const double *y, double *g, void *host);
    /* the integrator's own message, from `function` of `module`: an error, or a warning (the
     * call succeeds with a caveat) */
    void (*message)(void *host, int warning, const char *module, const char *function,
                    const char *text);
    /* the integrator's call `call` failed with the return flag named `flag` */
    void (*failed)(void *host, const char *call, const char *flag);
    /* what the integrator could not allocate */
    void (*error)(void *host, const char *what);
    void *host;
    /* J[i + j n] = d f_i / d y_j at (t, y), the layout of a dense SUNDIALS matrix: 0, > 0
     * recoverable (NULL: the integrator differentiates by itself, if it needs to) */
    int (*jacobian)(double t, const double *y, double *J, void *host);
} cs_problem_t;

/* Steps, failed steps, steps held by stability (not accuracy) and Jacobians formed since the
 * last (re)start. */
typedef struct {
    long steps, fails, stiff;
    long jacobians; /* Jacobians formed (an integrator without Newton iteration: 0) */
} cs_counts_t;

/* A saved step: its interval, and the state and its derivative at both ends exactly as the
 * integrator used them. */
typedef struct {
    double t0, tn;
    const double *y0, *f0, *y1, *f1;
} cs_record_view_t;

typedef struct {
    const char *name; /* in messages: "RK45", "BDF", "Adams" */
    /* 1: start leaves nothing of the earlier runs that shapes the solution (the integrator is
     * kept across a reset of the instance); 0: it is made anew */
    int start_is_new;
    /* An integrator of the problem (copied), or NULL (reported). Nothing is solved yet. */
    void *(*create)(const cs_problem_t *problem);
    void (*free)(void *it);
    /* (Re)start at (t, y): 0, or -1 (reported). h_first > 0: the first step's size (an
     * integrator that chooses its own ignores it), at most problem.first_step_max. */
    int (*start)(void *it, double t, const double *y, double h_first);
    /* One step: the next root inside the last step, or a new step. (*t, y): in, the point the
     * caller is at; out, the point reached (on failure the last successful one). CS_STEP_*. */
    int (*step)(void *it, double *t, double *y);
    /* No step goes beyond t_stop (> the current time); the step that reaches it returns
     * CS_STEP_TSTOP. 0, or -1 (reported). */
    int (*set_stop_time)(void *it, double t_stop);
    /* The state (k = 0) or its derivative (k = 1) at t inside the last step: 0, < 0 outside. */
    int (*dense)(void *it, double t, int k, double *out);
    double (*time)(const void *it);      /* the end of the last step */
    double (*last_step)(const void *it); /* the size of the last step */
    /* The size the step-size control proposes next, for the first step of a later start
     * (NULL: the integrator takes no first-step hint). */
    double (*next_step)(const void *it);
    void (*counts)(const void *it, cs_counts_t *counts);
    /* Saved steps, for analysing a step after the integrator has gone on (all NULL: its steps
     * cannot be saved): a record of record_size(n) doubles, its dense output and its view. */
    size_t (*record_size)(int n);
    int (*save_step)(void *it, double *record); /* the last step: 0, or < 0 before any */
    void (*record_dense)(const double *record, int n, double t, int k, double *out);
    void (*record_view)(const double *record, int n, cs_record_view_t *view);
} cs_integrator_ops_t;

extern const cs_integrator_ops_t cs_integrator_rk45;
extern const cs_integrator_ops_t cs_integrator_bdf;
extern const cs_integrator_ops_t cs_integrator_adams;

CSFH_INTERNAL_END

#endif
