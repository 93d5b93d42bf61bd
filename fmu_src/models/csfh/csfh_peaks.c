/* The peak outputs of co-simulation (csfh_peaks.h): the largest values of F_N, |F_T|, the
 * indentation and the flexure stress (csfh_model_peak_values) over the communication step, on
 * the integrator's dense output of each step. Every step is analysed once: its end values, and
 * every maximum inside it (the quantity's slope > 0 at the step's start, <= 0 at its end). Each
 * communication step then takes the maxima that lie in it and the end values of the steps that
 * end in it; the values at the communication points themselves are the outputs there (the
 * outputs take the max with the step's peaks). Outside the contact mode there is nothing to track
 * and nothing is evaluated.
 *
 * When: a step of an integrator that cannot save its steps (CVODE) is analysed when taken (its
 * dense output is gone after the next step). RK45's steps are kept by the stepper and analysed
 * only when the outputs are needed (fmu_model.h: fmu_step_t), with the discrete state they ran
 * with. The result does not depend on when the analysis runs: the values and slopes at a step's
 * ends are functions of the state and f there (the slope a forward difference along f, which
 * the adjacent steps share exactly), computed by the step that ends there and taken over by the
 * next.
 *
 * A maximum inside a step is searched only if it can matter: the tangents at the bracket's ends
 * bound it (for a function concave between them, as any is near its maximum) by the height of
 * their intersection, and the search stops once that bound is within PEAK_RTOL x the integration
 * tolerance of the largest value found. Each iteration takes the maximum of the cubic Hermite
 * polynomial through the bracket's values and slopes (4th order: one or two iterations), so a
 * wiggle of the resting contact's force costs nothing and an impact's peak a few evaluations. */
#include "csfh_peaks.h"

#include <math.h>
#include <string.h>

#define N CSFH_N_PEAKS
#define NX 6               /* the model's states */
#define PEAK_ITERATIONS 40 /* at most (a few are used) */
#define PEAK_RTOL 1.0      /* x the integration tolerance: the accuracy of a located maximum */

void csfh_peaks_begin(void *fv, int outputs_current)
{
    csfh_fmu_t *f = (csfh_fmu_t *)fv;
    f->peaks.active = 1;
    if (outputs_current) {
        f->peaks.v[0] = f->out.F_N;
        f->peaks.v[1] = fabs(f->out.F_T);
        f->peaks.v[2] = f->out.indentation;
        f->peaks.v[3] = f->m.p.track_stress_peak ? f->out.stress_max : 0.0;
    } else {
        csfh_model_peak_values(&f->m, f->m.x, f->peaks.v);
    }
}

static void peaks_add(csfh_fmu_t *f, const double *v)
{
    for (int j = 0; j < N; j++) {
        f->peaks.v[j] = v[j] > f->peaks.v[j] ? v[j] : f->peaks.v[j];
    }
}

/* The peak quantities v at time t of the step, and their time derivatives in slope (a forward
 * difference along the derivative of the state); 0 when there is nothing to track there.
 * y_at_t, f_at_t: the state and its derivative at t if known (else NULL: interpolated). */
static int peak_point(csfh_fmu_t *f, const fmu_step_t *step, double t, const double *y_at_t,
                      const double *f_at_t, double *v, double *slope)
{
    t = t < step->t0 ? step->t0 : (t > step->tn ? step->tn : t); /* round-off at the ends */
    double py[NX], pd[NX];
    if (y_at_t != NULL) {
        memcpy(py, y_at_t, sizeof(py));
    } else if (step->dense(step, t, 0, py) < 0) {
        return 0;
    }
    if (!csfh_model_peak_values(&f->m, py, v)) {
        return 0;
    }
    if (f_at_t != NULL) {
        memcpy(pd, f_at_t, sizeof(pd));
    } else if (step->dense(step, t, 1, pd) < 0) {
        return 0;
    }
    const double eps = 1e-7 * (fabs(step->h) > 0.0 ? fabs(step->h) : 1e-9);
    for (int i = 0; i < NX; i++) {
        pd[i] = py[i] + eps * pd[i];
    }
    double ve[N];
    csfh_model_peak_values(&f->m, pd, ve);
    for (int j = 0; j < N; j++) {
        slope[j] = (ve[j] - v[j]) / eps;
    }
    return 1;
}

/* Upper bound of a maximum between (a, va, sa) and (b, vb, sb) with sa > 0 >= sb: the height of
 * the intersection of the two tangents, over the larger end value (0 if below). */
static double peak_gain_bound(double a, double va, double sa, double b, double vb, double sb)
{
    double tx = (vb - va + sa * a - sb * b) / (sa - sb);
    tx = tx < a ? a : (tx > b ? b : tx);
    const double gain = va + sa * (tx - a) - (va > vb ? va : vb);
    return gain > 0.0 ? gain : 0.0;
}

/* The maximum in (0, 1) of the cubic Hermite polynomial with slopes d0 > 0 at 0 and d1 <= 0 at
 * 1 (slopes times the interval's length) and rise dv from 0 to 1; NaN if it has none there. */
static double hermite_max(double dv, double d0, double d1)
{
    /* p'(u) = d0 + B u + A u^2 */
    const double A = 3.0 * (d0 + d1 - 2.0 * dv), B = 2.0 * (3.0 * dv - 2.0 * d0 - d1);
    const double C = d0;
    double roots[2] = {NAN, NAN};
    if (fabs(A) <= 1e-12 * (fabs(B) + fabs(C))) {
        roots[0] = B != 0.0 ? -C / B : NAN;
    } else {
        const double disc = B * B - 4.0 * A * C;
        if (disc < 0.0) {
            return NAN;
        }
        const double q = -0.5 * (B + (B >= 0.0 ? sqrt(disc) : -sqrt(disc)));
        roots[0] = q / A;
        roots[1] = q != 0.0 ? C / q : NAN;
    }
    for (int i = 0; i < 2; i++) {
        const double u = roots[i];
        if (u > 0.0 && u < 1.0 && 2.0 * A * u + B <= 0.0) { /* p'' <= 0: a maximum */
            return u;
        }
    }
    return NAN;
}

/* A bracket [lo, hi] of a maximum of quantity j: the values and slopes at its ends. */
typedef struct {
    double lo, hi, v_lo, v_hi, s_lo, s_hi;
} bracket_t;

/* The maximum of quantity j in the bracket: its time in *best_t and the quantities there in
 * best (best_v: its value; -INFINITY and NaN if the search evaluated nothing). */
static double peak_search(csfh_fmu_t *f, const fmu_step_t *step, int j, bracket_t b,
                          double *best_t, double *best)
{
    double best_v = -INFINITY;
    *best_t = NAN;
    for (int k = 0; k < PEAK_ITERATIONS && b.hi - b.lo > 1e-7 * step->h; k++) {
        const double tol = PEAK_RTOL * step->rtol * fmax(fabs(b.v_lo), fabs(b.v_hi));
        if (peak_gain_bound(b.lo, b.v_lo, b.s_lo, b.hi, b.v_hi, b.s_hi) <= tol) {
            break;
        }
        const double L = b.hi - b.lo;
        double u = hermite_max(b.v_hi - b.v_lo, L * b.s_lo, L * b.s_hi);
        if (!(u > 0.0 && u < 1.0)) {
            u = b.s_lo / (b.s_lo - b.s_hi); /* secant on the slope */
        }
        u = u < 0.01 ? 0.01 : (u > 0.99 ? 0.99 : u); /* the bracket must shrink */
        const double mid = b.lo + u * L;
        double v[N], s[N];
        if (!peak_point(f, step, mid, NULL, NULL, v, s)) {
            break;
        }
        if (v[j] > best_v) {
            best_v = v[j], *best_t = mid;
            memcpy(best, v, sizeof(v));
        }
        if (s[j] > 0.0) {
            b.lo = mid, b.v_lo = v[j], b.s_lo = s[j];
        } else {
            b.hi = mid, b.v_hi = v[j], b.s_hi = s[j];
        }
    }
    return best_v;
}

/* The maxima inside a step with values and slopes v0, s0 at its start and v1, s1 at its end:
 * their times and the quantities there; returns how many. */
static int peak_maxima(csfh_fmu_t *f, const fmu_step_t *step, const double *v0,
                       const double *s0, const double *v1, const double *s1, double *max_t,
                       double (*max_v)[N])
{
    int n_max = 0;
    for (int j = 0; j < N; j++) {
        if (!(s0[j] > 0.0 && s1[j] <= 0.0)) {
            continue;
        }
        const bracket_t b = {step->t0, step->tn, v0[j], v1[j], s0[j], s1[j]};
        double best_t, best[N];
        const double best_v = peak_search(f, step, j, b, &best_t, best);
        if (best_v > v0[j] && best_v > v1[j]) { /* inside the step, above its ends */
            max_t[n_max] = best_t;
            memcpy(max_v[n_max], best, sizeof(best));
            n_max++;
        }
    }
    return n_max;
}

/* --- live steps: analysed when taken ----------------------------------------------------- */

/* Analyse the live step: its maxima and its end (into the live memory). */
static void live_step(csfh_fmu_t *f, const fmu_step_t *step, csfh_step_peaks_t *mem)
{
    double v1[N], s1[N], s0[N], v0[N];
    const int have_start = mem->end_valid && mem->t_end == step->t0;
    mem->n_max = 0;
    if (have_start) {
        memcpy(s0, mem->s1, sizeof(s0));
        memcpy(v0, mem->v1, sizeof(v0));
    }
    if (!peak_point(f, step, step->tn, step->y1, NULL, v1, s1)) {
        mem->end_valid = 0;
        return;
    }
    if (have_start || peak_point(f, step, step->t0, NULL, NULL, v0, s0)) {
        mem->n_max = peak_maxima(f, step, v0, s0, v1, s1, mem->max_t, mem->max_v);
    }
    memcpy(mem->s1, s1, sizeof(s1));
    memcpy(mem->v1, v1, sizeof(v1));
    mem->t_end = step->tn;
    mem->end_valid = 1;
}

/* The part (ta, tb] of the communication step on the live step: a new step (new_step; tb is
 * its end unless a root or the communication point came first) or more of the last one. */
static void live_part(csfh_fmu_t *f, const fmu_step_t *step, double ta, double tb)
{
    csfh_step_peaks_t *mem = (csfh_step_peaks_t *)step->memory;
    if (step->new_step) {
        /* the previous step may reach into this part (it ended beyond the last communication
         * point): take its maxima and its end there before the new step's analysis replaces
         * them */
        for (int k = 0; k < mem->n_max; k++) {
            if (mem->max_t[k] > ta && mem->max_t[k] <= tb) {
                peaks_add(f, mem->max_v[k]);
            }
        }
        if (mem->end_valid && mem->t_end > ta && mem->t_end <= tb) {
            peaks_add(f, mem->v1);
        }
        live_step(f, step, mem);
        if (mem->end_valid && tb == mem->t_end) {
            peaks_add(f, mem->v1);
        }
    }
    for (int k = 0; k < mem->n_max; k++) {
        if (mem->max_t[k] > ta && mem->max_t[k] <= tb) {
            peaks_add(f, mem->max_v[k]);
        }
    }
}

/* --- kept steps: analysed when the outputs are needed ------------------------------------- */

/* The values and slopes at the end (end = 1) or start (0) of a kept step (the model in its
 * discrete state). */
static void kept_point(csfh_fmu_t *f, const fmu_step_t *step, int end)
{
    csfh_step_peaks_t *r = (csfh_step_peaks_t *)step->memory;
    if (end) {
        r->end_valid = peak_point(f, step, step->tn, step->y1, step->f1, r->v1, r->s1);
        r->end_done = 1;
    } else {
        r->start_valid = peak_point(f, step, step->t0, step->y0, step->f0, r->v0, r->s0);
        r->start_done = 1;
    }
}

/* Analyse a kept step once, in the discrete state it ran with (only that is taken from the
 * step's model: the rest is the live model's): its ends (the start is the previous step's end
 * when it continues that one) and its maxima. */
static void kept_step(csfh_fmu_t *f, const fmu_step_t *step)
{
    csfh_step_peaks_t *r = (csfh_step_peaks_t *)step->memory;
    if (r->analysed) {
        return;
    }
    const csfh_discrete_t live = f->m.z;
    f->m.z = ((const csfh_fmu_t *)step->model)->m.z;
    if (step->previous != NULL) {
        csfh_step_peaks_t *p = (csfh_step_peaks_t *)step->previous->memory;
        if (!p->end_done) {
            kept_point(f, step->previous, 1); /* (the same discrete state) */
        }
        r->start_valid = p->end_valid;
        memcpy(r->v0, p->v1, sizeof(r->v0));
        memcpy(r->s0, p->s1, sizeof(r->s0));
        r->start_done = 1;
    } else {
        kept_point(f, step, 0);
    }
    kept_point(f, step, 1);
    r->n_max = 0;
    if (r->start_valid && r->end_valid) {
        r->n_max = peak_maxima(f, step, r->v0, r->s0, r->v1, r->s1, r->max_t, r->max_v);
    }
    f->m.z = live;
    r->analysed = 1;
}

/* The peaks of a kept step that lie in (from, to] and before its cut. */
static void kept_part(csfh_fmu_t *f, const fmu_step_t *step, double from, double to)
{
    kept_step(f, step);
    const csfh_step_peaks_t *r = (const csfh_step_peaks_t *)step->memory;
    for (int k = 0; k < r->n_max; k++) {
        if (r->max_t[k] > from && r->max_t[k] <= to && r->max_t[k] <= step->cut) {
            peaks_add(f, r->max_v[k]);
        }
    }
    if (r->end_valid && step->cut == step->tn && step->tn <= to) {
        peaks_add(f, r->v1);
    }
}

void csfh_peaks_analyse_step(void *mv, const fmu_step_t *step, double from, double to)
{
    csfh_fmu_t *f = (csfh_fmu_t *)mv;
    if (!step->live) {
        kept_part(f, step, from, to);
        return;
    }
    if (!csfh_model_peaks_tracked(&f->m)) {
        /* nothing to track in this discrete state (out of contact): forget the last step */
        csfh_step_peaks_t *mem = (csfh_step_peaks_t *)step->memory;
        mem->end_valid = 0;
        mem->n_max = 0;
        return;
    }
    if (step->keep != NULL && (!step->new_step || step->keep(step))) {
        return; /* kept (or a part of a kept step): analysed when needed */
    }
    live_part(f, step, from, to);
}
