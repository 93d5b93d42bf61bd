#include "csfh_model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_common.h"
#include "csfh_format.h"
#include "csfh_friction.h"


/* A quantity, by the name of its variable, and its value (for messages). */
typedef struct {
    const char *name;
    double value;
} named_value_t;

/* A derived quantity and what it is derived from (for the message when it is not finite). */
typedef struct {
    named_value_t q;
    const named_value_t *from; /* ending with a NULL name */
} derived_check_t;

/* "contact.esdu_F_max = inf is not finite (derived from contact.E1 = 1e+308, ...)" */
static void derived_not_finite(const derived_check_t *d, char *msg, size_t msg_size)
{
    char b[32];
    int n = snprintf(msg, msg_size, "%s = %s is not finite (derived from ", d->q.name,
                     csfh_format_value(b, d->q.value));
    for (const named_value_t *v = d->from; v->name != NULL; v++) {
        if (n >= 0 && (size_t)n < msg_size) {
            n += snprintf(msg + n, msg_size - (size_t)n, "%s%s = %s", v == d->from ? "" : ", ",
                          v->name, csfh_format_value(b, v->value));
        }
    }
    if (n >= 0 && (size_t)n < msg_size) {
        snprintf(msg + n, msg_size - (size_t)n, ")");
    }
}

/* Every derived quantity finite, else the message names it, its value and the parameters it is
 * derived from, with their values (e.g. contact.E1 = contact.E2 = 1e308 overflow the ESDU force
 * scale): 0, or -1. */
static int check_derived(const csfh_params_t *p, const csfh_derived_t *d, char *msg,
                         size_t msg_size)
{
#define END {NULL, 0.0}
    const named_value_t E1 = {"contact.E1", p->E1}, nu1 = {"contact.nu1", p->nu1};
    const named_value_t E2 = {"contact.E2", p->E2}, nu2 = {"contact.nu2", p->nu2};
    const named_value_t R1 = {"contact.R1", p->R1}, R2 = {"contact.R2", p->R2};
    const named_value_t L = {"contact.L", p->L};
    const named_value_t rho = {"flexure.rho", p->rho}, phi = {"flexure.phi_root", p->phi_root};
    const named_value_t beta = {"flexure.beta", p->beta};
    const named_value_t from_delta[] = {R1, R2, END};
    const named_value_t from_spheres[] = {E1, nu1, E2, nu2, R1, R2, END};
    const named_value_t from_cylinders[] = {E1, nu1, E2, nu2, L, END};
    const named_value_t from_spheres_given[] = {{"contact.K_spheres_given", p->K_spheres_given}, END};
    const named_value_t from_cylinders_given[] = {{"contact.K_cylinders_given", p->K_cylinders_given},
                                                  END};
    const named_value_t from_xi[] = {{"contact.law", (double)p->law}, {"contact.cr", p->cr}, END};
    const named_value_t from_esdu[] = {E1, nu1, E2, nu2, L, R1, R2,
                                       {"contact.esdu_sigma_pi", (double)p->esdu_sigma_pi}, END};
    const named_value_t from_sbar1[] = {{"flexure.OF[1]", p->OF[0]}, rho, phi, beta, END};
    const named_value_t from_sbar2[] = {{"flexure.OF[2]", p->OF[1]}, rho, phi, beta, END};
    const named_value_t from_E_star[] = {E1, nu1, E2, nu2, END};
    const named_value_t from_delassus[] = {{"body1.m", p->m1}, {"body1.I", p->I1}, R1, END};
#undef END
    /* Moreau's Delassus matrix (docs/model.md Eq. (3.6)) and its determinant, which the exact
     * solution of §6.2 divides by: an overflow there gives a zero impulse, the body would pass
     * through the bore */
    const double G_TT = 1.0 / p->m1 + p->R1 * p->R1 / p->I1;
    const derived_check_t derived[] = {
        {{"contact.delta", d->delta}, from_delta},
        {{"contact.K_spheres", d->K_spheres}, p->K_from_materials ? from_spheres : from_spheres_given},
        {{"contact.K_cylinders", d->K_cylinders},
         p->K_from_materials ? from_cylinders : from_cylinders_given},
        {{"contact.xi", d->xi}, from_xi},
        {{"contact.esdu_F_max", d->esdu_F_max}, from_esdu},
        {{"flexure.sbar[1]", d->sbar[0]}, from_sbar1},
        {{"flexure.sbar[2]", d->sbar[1]}, from_sbar2},
        /* not FMU variables: named by what they are */
        {{"the contact modulus E* (Hertz line contact)", d->E_star}, from_E_star},
        {{"the conformal radius R1 R2 / (R2 - R1)", d->R_conformal}, from_delta},
        {{"the Moreau step's Delassus determinant scale (1/m1 + R1^2/I1)^2", G_TT * G_TT},
         from_delassus},
    };
    for (size_t i = 0; i < sizeof(derived) / sizeof(derived[0]); i++) {
        if (!isfinite(derived[i].q.value)) {
            derived_not_finite(&derived[i], msg, msg_size);
            return -1;
        }
    }
    return 0;
}

/* The normal law's parameters (docs/model.md §4): its stiffness and exponent (the cylinders'
 * for LN_cylinders, the spheres' for the others and for the ESDU reading I3). */
static void normal_law_setup(const csfh_params_t *p, csfh_derived_t *d)
{
    d->normal.law = (csfh_contact_law_t)p->law;
    d->normal.esdu_reading = (csfh_esdu_reading_t)p->esdu_reading;
    d->normal.xi = d->xi;
    d->normal.v_min = p->v_min;
    if (p->law == CSFH_CONTACTLAW_LN_CYLINDERS) {
        d->normal.K = d->K_cylinders;
        d->normal.n = p->n_cylinders;
    } else {
        d->normal.K = d->K_spheres; /* spheres, HC, Flores; the exponent of LN-ESDU I3 */
        d->normal.n = p->n_spheres;
    }
}

int csfh_model_prepare(csfh_model_t *m, char *msg, size_t msg_size)
{
    const csfh_params_t *p = &m->p;
    char b1[32], b2[32];
    if (!(p->R1 < p->R2)) {
        snprintf(msg, msg_size, "contact.R1 = %s must be smaller than contact.R2 = %s",
                 csfh_format_value(b1, p->R1), csfh_format_value(b2, p->R2));
        return -1;
    }
    if (!(p->v1 > p->v0)) {
        snprintf(msg, msg_size, "friction.v1 = %s must be greater than friction.v0 = %s",
                 csfh_format_value(b1, p->v1), csfh_format_value(b2, p->v0));
        return -1;
    }
    csfh_derived_t d;
    memset(&d, 0, sizeof(d));
    d.delta = p->R2 - p->R1;
    if (p->K_from_materials) {
        d.K_spheres = csfh_stiffness_spheres(p->E1, p->nu1, p->E2, p->nu2, p->R1, p->R2,
                                             p->Reff_internal);
        d.K_cylinders = csfh_stiffness_cylinders(p->E1, p->nu1, p->E2, p->nu2, p->L);
    } else {
        d.K_spheres = p->K_spheres_given;
        d.K_cylinders = p->K_cylinders_given;
    }
    d.xi = csfh_damping_factor((csfh_contact_law_t)p->law, p->cr);
    csfh_esdu_setup(p->E1, p->nu1, p->E2, p->nu2, p->L, d.delta, p->esdu_sigma_pi,
                    &d.normal.esdu);
    d.esdu_F_max = d.normal.esdu.F_max;
    normal_law_setup(p, &d);
    const csfh_arc_beam_t beam = {p->rho, p->beta, p->Eh, p->nuh, p->h, p->b, p->kappa,
                                  p->bending_only};
    if (csfh_flexure_setup(&beam, p->OF, p->phi_root, p->conservative, &d.flexure) != 0) {
        snprintf(msg, msg_size,
                 "flexure: the compliance matrix is singular for flexure.rho = %g, "
                 "flexure.beta = %g, flexure.h = %g",
                 p->rho, p->beta, p->h);
        return -1;
    }
    d.sbar[0] = d.flexure.sbar[0];
    d.sbar[1] = d.flexure.sbar[1];
    csfh_arc_section_setup(&beam, p->phi_root, &d.arc);
    /* Hertz line contact of the pin in the bore (docs/model.md §14.3) */
    d.E_star = csfh_contact_modulus(p->E1, p->nu1, p->E2, p->nu2);
    d.R_conformal = p->R1 * p->R2 / (p->R2 - p->R1);
    d.shock_dir[0] = cos(p->shock_angle);
    d.shock_dir[1] = sin(p->shock_angle);
    if (check_derived(p, &d, msg, msg_size) != 0) {
        return -1;
    }
    m->d = d;
    return 0;
}

double csfh_half_sine(double A, double T, double t0, double t)
{
    /* docs/model.md Eq. (14.9): a half period of a sine of period 2T */
    if (!(t >= t0 && t <= t0 + T)) {
        return 0.0;
    }
    return A * sin(CSFH_PI * (t - t0) / T);
}

void csfh_model_frame_acceleration(const csfh_model_t *m, double t, double a[2])
{
    a[0] = m->a_base[0];
    a[1] = m->a_base[1];
    if (m->p.shock_peak != 0.0) {
        const double s =
            csfh_half_sine(m->p.shock_peak, m->p.shock_duration, m->p.shock_start, t);
        a[0] += s * m->d.shock_dir[0];
        a[1] += s * m->d.shock_dir[1];
    }
}

double csfh_model_next_time_event(const csfh_model_t *m, double t)
{
    if (m->p.shock_peak == 0.0) {
        return INFINITY;
    }
    const double t_end = m->p.shock_start + m->p.shock_duration;
    if (t < m->p.shock_start) {
        return m->p.shock_start;
    }
    return t < t_end ? t_end : INFINITY;
}

void csfh_model_smooth_forces(csfh_model_t *m, double t, const double q[3], double Q[3])
{
    /* Q_ext + Q_g, Q_g = [0, -m1 g, 0], and the d'Alembert force -m1 a_base at G1 of the frame's
     * acceleration (docs/model.md Eq. (14.1)); with a_base = 0 the sums are bitwise those
     * without it (x - 0 = x) */
    Q[0] = m->u_in[0] - m->p.m1 * m->a_base[0];
    Q[1] = m->u_in[1] - m->p.m1 * m->p.g - m->p.m1 * m->a_base[1];
    Q[2] = m->u_in[2];
    if (m->p.shock_peak != 0.0) {
        /* the shock pulse at the integrator's time t (§14.8): one more d'Alembert force; without
         * a pulse nothing is added, so the sums stay bitwise those of an autonomous model */
        const double s =
            csfh_half_sine(m->p.shock_peak, m->p.shock_duration, m->p.shock_start, t);
        Q[0] -= m->p.m1 * s * m->d.shock_dir[0];
        Q[1] -= m->p.m1 * s * m->d.shock_dir[1];
    }
    if (m->p.flexure_enabled) {
        double Qe[3];
        csfh_count(&m->counters.flexure);
        csfh_flexure_force(&m->d.flexure, q, Qe);
        Q[0] += Qe[0];
        Q[1] += Qe[1];
        Q[2] += Qe[2];
    }
}

/* The contact force at (q, u) where the bodies touch (the kinematics give gap < 0), with the
 * onset rate captured at the event (docs/model.md §5.2) in the contact mode, else (by the gap)
 * the state's own rate, continuous at the event. */
static void contact_force(csfh_model_t *m, const double q[3], const double u[3],
                          csfh_contact_eval_t *c)
{
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, q, &c->kin);
    if (!(c->kin.gap < 0.0)) {
        return;
    }
    c->touching = 1;
    c->rho = -c->kin.gap;
    c->rho_dot = -(c->kin.DN[0] * u[0] + c->kin.DN[1] * u[1] + c->kin.DN[2] * u[2]);
    const double onset = m->z.in_contact ? m->z.onset_speed : c->rho_dot;
    c->status = csfh_normal_force(&m->d.normal, c->rho, c->rho_dot, onset, &c->F_N);
    if (m->p.friction_enabled && c->F_N > 0.0) {
        csfh_count(&m->counters.friction);
        const double v_T = c->kin.DT[0] * u[0] + c->kin.DT[1] * u[1] + c->kin.DT[2] * u[2];
        c->F_T = csfh_ambrosio_force(m->p.fd, m->p.v0, m->p.v1, c->F_N, v_T);
    }
}

/* No contact force yet; 0 if no law is selected (nothing evaluated, nothing counted). */
static int contact_begin(csfh_model_t *m, csfh_contact_eval_t *c)
{
    c->touching = 0;
    c->F_N = c->F_T = 0.0;
    c->rho = c->rho_dot = 0.0;
    c->status = CSFH_LAW_OK;
    if (m->p.law == CSFH_CONTACTLAW_NONE) {
        return 0;
    }
    csfh_count(&m->counters.contact);
    return 1;
}

void csfh_model_contact(csfh_model_t *m, const double q[3], const double u[3],
                        csfh_contact_eval_t *c)
{
    /* The contact force acts in the contact mode only, the mode the event update sets where the
     * gap crosses 0 (the relation gap < 0 is frozen between events, as FMI and Modelica do).
     * A state inside the gap that the integrator probes before it has located the onset thus
     * sees the smooth flight forces, and the onset (time, rate) lies on the smooth flight
     * solution: a step that reaches past the onset does not smear the stiff contact force
     * into the interpolant the root finder uses. In the contact mode the bodies touch almost
     * always: the kinematics (with the gap) once. */
    if (contact_begin(m, c) && m->z.in_contact) {
        contact_force(m, q, u, c);
    }
}

void csfh_model_contact_by_gap(csfh_model_t *m, const double q[3], const double u[3],
                               csfh_contact_eval_t *c)
{
    if (!contact_begin(m, c)) {
        return;
    }
    if (!m->z.in_contact && !(csfh_contact_gap(m->d.delta, m->p.s1bar, q) < 0.0)) {
        return; /* in flight: the gap alone */
    }
    contact_force(m, q, u, c);
}

/* The contact force of one of the two rules (csfh_model_contact, csfh_model_contact_by_gap). */
typedef void (*contact_rule_t)(csfh_model_t *m, const double q[3], const double u[3],
                               csfh_contact_eval_t *c);

static inline int derivatives(csfh_model_t *m, contact_rule_t contact, double t,
                              const double x[6], double xdot[6])
{
    csfh_count(&m->counters.rhs);
    double Q[3];
    csfh_model_smooth_forces(m, t, x, Q);
    csfh_contact_eval_t c;
    contact(m, x, x + 3, &c);
    if (c.touching) {
        csfh_contact_add_force(&c.kin, c.F_N, c.F_T, Q);
    }
    xdot[0] = x[3];
    xdot[1] = x[4];
    xdot[2] = x[5];
    xdot[3] = Q[0] / m->p.m1;
    xdot[4] = Q[1] / m->p.m1;
    xdot[5] = Q[2] / m->p.I1;
    for (int i = 0; i < 6; i++) {
        if (!isfinite(xdot[i])) {
            return CSFH_ERR_NONFINITE;
        }
    }
    return c.status == CSFH_LAW_ESDU_CLAMPED ? CSFH_WARN_ESDU_CLAMPED : CSFH_OK;
}

int csfh_model_derivatives(csfh_model_t *m, double t, const double x[6], double xdot[6])
{
    return derivatives(m, csfh_model_contact, t, x, xdot);
}

int csfh_model_derivatives_by_gap(csfh_model_t *m, double t, const double x[6], double xdot[6])
{
    return derivatives(m, csfh_model_contact_by_gap, t, x, xdot);
}

double csfh_model_event_indicator(const csfh_model_t *m, const double x[6])
{
    if (m->p.law == CSFH_CONTACTLAW_NONE) {
        return 1.0;
    }
    const double gap = csfh_contact_gap(m->d.delta, m->p.s1bar, x);
    /* out of contact: z = g (onset where g falls through 0); in contact: z = g - 2 eps (release
     * where g rises through 2 eps). Each mode switch leaves z at about -2 eps or +2 eps. */
    return m->z.in_contact ? gap - 2.0 * m->p.gap_hysteresis : gap;
}

static double indentation_rate(const csfh_model_t *m)
{
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, m->x, &kin);
    return -(kin.DN[0] * m->x[3] + kin.DN[1] * m->x[4] + kin.DN[2] * m->x[5]);
}

int csfh_model_event_update(csfh_model_t *m)
{
    if (m->p.law == CSFH_CONTACTLAW_NONE) {
        return 0;
    }
    const double gap = csfh_contact_gap(m->d.delta, m->p.s1bar, m->x);
    const double eps = m->p.gap_hysteresis;
    if (!m->z.in_contact && gap <= eps) {
        m->z.in_contact = 1;
        csfh_count(&m->z.contact_count);
        m->z.onset_speed = indentation_rate(m); /* pre-impact rate, used until release */
        m->z.onset_time = m->time;
        return 1;
    }
    if (m->z.in_contact && gap >= eps) {
        m->z.in_contact = 0;
        m->z.release_time = m->time;
        m->z.release_speed = -indentation_rate(m);
        return 2;
    }
    return 0;
}

void csfh_model_apply_initial_parameters(csfh_model_t *m)
{
    if (m->p.initial_from_parameters) {
        for (int i = 0; i < 6; i++) {
            m->x[i] = m->p.initial_state[i];
        }
    }
}

int csfh_model_check_start(const csfh_model_t *m, char *msg, size_t msg_size)
{
    if (m->p.law == CSFH_CONTACTLAW_NONE) {
        return 0;
    }
    /* indentation = -g, the gap of docs/model.md §3 */
    const double indentation = -csfh_contact_gap(m->d.delta, m->p.s1bar, m->x);
    if (!(indentation > m->p.max_initial_indentation)) {
        return 0;
    }
    char b[4][32];
    snprintf(msg, msg_size,
             "the start state body1.x = %s m, body1.y = %s m, body1.theta = %s rad is %.6g m deep "
             "in the bore (contact.indentation = %.6g m > contact.max_initial_indentation = %s m)",
             csfh_format_value(b[0], m->x[0]), csfh_format_value(b[1], m->x[1]),
             csfh_format_value(b[2], m->x[2]), indentation, indentation,
             csfh_format_value(b[3], m->p.max_initial_indentation));
    return -1;
}

void csfh_model_init_discrete(csfh_model_t *m)
{
    m->z.in_contact = 0;
    m->z.contact_count = 0;
    m->z.onset_speed = 0.0;
    m->z.onset_time = m->z.release_time = m->time; /* until a contact happens */
    m->z.release_speed = 0.0;
    csfh_model_event_update(m);
}

int csfh_model_peaks_tracked(const csfh_model_t *m)
{
    const int contact = m->z.in_contact && m->p.law != CSFH_CONTACTLAW_NONE;
    const int stress = m->p.track_stress_peak && m->p.flexure_enabled;
    return contact || stress;
}

int csfh_model_peak_values(csfh_model_t *m, const double x[6], double v[CSFH_N_PEAKS])
{
    v[0] = v[1] = v[2] = v[3] = 0.0;
    const int contact = m->z.in_contact && m->p.law != CSFH_CONTACTLAW_NONE;
    const int stress = m->p.track_stress_peak && m->p.flexure_enabled;
    if (!contact && !stress) {
        return 0;
    }
    if (contact) {
        csfh_contact_eval_t c;
        csfh_model_contact(m, x, x + 3, &c);
        v[0] = c.F_N;
        v[1] = fabs(c.F_T);
        v[2] = c.rho;
    }
    if (stress) {
        v[3] = csfh_model_flexure_stress(m, x, NULL);
    }
    return 1;
}

double csfh_model_flexure_stress(const csfh_model_t *m, const double q[3], double *location)
{
    if (!m->p.flexure_enabled) {
        if (location != NULL) {
            *location = 0.0;
        }
        return 0.0;
    }
    double w[3];
    csfh_flexure_tip_wrench(&m->d.flexure, q, w);
    return csfh_arc_stress_max(&m->d.arc, w, location);
}

void csfh_model_stresses(const csfh_model_t *m, const double q[3], double F_N,
                         csfh_stresses_t *s)
{
    s->flexure_stress = csfh_model_flexure_stress(m, q, &s->flexure_location);
    s->contact_pressure = csfh_hertz_line_pressure(F_N, m->d.E_star, m->p.L, m->d.R_conformal,
                                                   &s->contact_half_width);
}

/* The contact's kinematic outputs at x: gap, indentation rate, sliding speed. */
static void contact_outputs(csfh_model_t *m, const csfh_contact_eval_t *c, const double *x,
                            csfh_outputs_t *o)
{
    if (c->touching) {
        o->gap = c->kin.gap;
        o->indentation_rate = c->rho_dot;
        o->v_T = c->kin.DT[0] * x[3] + c->kin.DT[1] * x[4] + c->kin.DT[2] * x[5];
    } else {
        csfh_contact_kin_t kin;
        csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, x, &kin);
        o->gap = kin.gap;
        o->indentation_rate = -(kin.DN[0] * x[3] + kin.DN[1] * x[4] + kin.DN[2] * x[5]);
        o->v_T = kin.DT[0] * x[3] + kin.DT[1] * x[4] + kin.DT[2] * x[5];
    }
}

/* The peak outputs: the communication step's so far (co-simulation), and the current values;
 * the flexure stress only where it is tracked. Then what follows from them: p0 increases with
 * F_N, so the pressure of the peak force is the peak pressure (§14.5), and the margins
 * 1 - peak / allowable (§14.4): 1 unloaded, 0 at the allowable, < 0 beyond. */
static void peak_outputs(const csfh_model_t *m, const double *peaks, csfh_outputs_t *o)
{
    const double now[CSFH_N_PEAKS] = {o->F_N, fabs(o->F_T), o->indentation, o->stress_max};
    double *peak[CSFH_N_PEAKS] = {&o->F_N_peak, &o->F_T_peak, &o->indentation_peak,
                                  &o->stress_max_peak};
    for (int j = 0; j < CSFH_N_PEAKS; j++) {
        const int tracked = peaks != NULL && (j < 3 || m->p.track_stress_peak);
        *peak[j] = tracked && peaks[j] > now[j] ? peaks[j] : now[j];
    }
    o->pressure_max_peak =
        csfh_hertz_line_pressure(o->F_N_peak, m->d.E_star, m->p.L, m->d.R_conformal, NULL);
    o->stress_margin = 1.0 - o->stress_max_peak / m->p.stress_allowable;
    o->pressure_margin = 1.0 - o->pressure_max_peak / m->p.pressure_allowable;
}

/* The loads at the current state: the contact force (c: its evaluation), the indentation, the
 * stresses (docs/model.md §14.2-14.3: at output time only), the peaks and margins. */
static void load_outputs(csfh_model_t *m, contact_rule_t contact, const double *peaks,
                         csfh_outputs_t *o, csfh_contact_eval_t *c)
{
    const double *x = m->x;
    contact(m, x, x + 3, c);
    o->F_N = c->F_N;
    o->F_T = c->F_T;
    o->indentation = c->touching ? c->rho : 0.0;
    csfh_stresses_t st;
    csfh_model_stresses(m, x, o->F_N, &st);
    o->stress_max = st.flexure_stress;
    o->stress_location = st.flexure_location;
    o->pressure_max = st.contact_pressure;
    o->half_width = st.contact_half_width;
    peak_outputs(m, peaks, o);
}

static int outputs(csfh_model_t *m, contact_rule_t contact, const double *peaks,
                   csfh_outputs_t *o)
{
    const double *x = m->x;
    csfh_contact_eval_t c;
    load_outputs(m, contact, peaks, o, &c);
    contact_outputs(m, &c, x, o);
    o->E_kinetic = 0.5 * m->p.m1 * (x[3] * x[3] + x[4] * x[4]) + 0.5 * m->p.I1 * x[5] * x[5];
    o->E_gravity = m->p.m1 * m->p.g * x[1];
    o->E_flexure = 0.0;
    if (m->p.flexure_enabled) {
        double Qe[3];
        csfh_count(&m->counters.flexure);
        o->E_flexure = csfh_flexure_force(&m->d.flexure, x, Qe);
    }
    o->E_contact = c.touching ? csfh_normal_elastic_energy(&m->d.normal, c.rho) : 0.0;
    o->E_total = o->E_kinetic + o->E_gravity + o->E_flexure + o->E_contact;
    csfh_model_frame_acceleration(m, m->time, o->a_frame);
    return c.status == CSFH_LAW_ESDU_CLAMPED ? CSFH_WARN_ESDU_CLAMPED : CSFH_OK;
}

int csfh_model_load_outputs(csfh_model_t *m, const double *peaks, csfh_outputs_t *out)
{
    csfh_contact_eval_t c;
    load_outputs(m, csfh_model_contact, peaks, out, &c);
    return c.status == CSFH_LAW_ESDU_CLAMPED ? CSFH_WARN_ESDU_CLAMPED : CSFH_OK;
}

int csfh_model_outputs(csfh_model_t *m, const double *peaks, csfh_outputs_t *out)
{
    return outputs(m, csfh_model_contact, peaks, out);
}

int csfh_model_outputs_by_gap(csfh_model_t *m, csfh_outputs_t *out)
{
    return outputs(m, csfh_model_contact_by_gap, NULL, out);
}
