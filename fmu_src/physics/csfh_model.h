/* The CSFH model: parameters, states and the right-hand side of
 * M q'' = Q_e + Q_g + Q_c + Q_ext + Q_base (docs/model.md conventions, paper Eqs. 27-30; the base
 * acceleration of docs/model.md §14.1), plus the contact mode logic of the event-driven compliant
 * models and the outputs with the stresses (§12, §14.2-14.4). No solver, FMI or importer fields
 * here: the FMU (../models/csfh/), the solvers and the Python harness (through the core library)
 * call these functions. */
#ifndef CSFH_MODEL_H
#define CSFH_MODEL_H

#include <stddef.h>

#include "csfh_contact.h"
#include "csfh_enums.h"
#include "csfh_flexure.h"
#include "csfh_normal_law.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* User parameters, one field per FMI parameter (names in modelDescription/variables.toml). */
typedef struct {
    /* body 1 and gravity */
    double m1, I1;     /* kg, kg m^2 */
    double s1bar[2];   /* O1 relative to G1, body frame, m */
    double g;          /* m/s^2, along -Y */
    /* contact */
    int law;           /* csfh_contact_law_t */
    double R1, R2;     /* m */
    double E1, E2, nu1, nu2;
    double L;          /* contact length, m */
    double cr;
    double n_spheres, n_cylinders;
    int Reff_internal, K_from_materials;
    double K_spheres_given, K_cylinders_given;
    int esdu_reading;  /* csfh_esdu_reading_t */
    int esdu_sigma_pi;
    double v_min;      /* m/s */
    double gap_hysteresis; /* m */
    double max_initial_indentation; /* m: deepest start state accepted */
    double pressure_allowable; /* Pa: allowable Hertz pressure of the conjugate surfaces */
    /* friction */
    int friction_enabled;
    double fd, fa, v0, v1;
    /* flexure */
    int flexure_enabled, bending_only, conservative;
    double rho, beta, OF[2], phi_root, h, b, Eh, nuh, kappa;
    double stress_allowable; /* Pa: allowable normal stress of the flexure */
    int track_stress_peak;   /* co-simulation: the flexure stress peak is tracked (§14.5) */
    /* half-sine shock pulse of the frame (docs/model.md §14.8) */
    double shock_peak;       /* m/s^2; 0: no pulse */
    double shock_duration;   /* s */
    double shock_start;      /* s */
    double shock_angle;      /* rad, direction of the frame's acceleration */
    /* the start state as parameters (importers that set only parameters: libcosim's SSP
     * loader); applied once, by csfh_model_apply_initial_parameters */
    int initial_from_parameters;
    double initial_state[6]; /* body1.x, y, theta, vx, vy, omega */
} csfh_params_t;

/* Quantities derived from the parameters (csfh_model_prepare). */
typedef struct {
    double delta;       /* R2 - R1 */
    double K_spheres, K_cylinders, xi, esdu_F_max;
    double sbar[2];     /* flexure attachment, body frame */
    csfh_flexure_t flexure;
    csfh_arc_section_t arc; /* the flexure's section data (stress outputs) */
    csfh_normal_law_t normal;
    double E_star;          /* contact modulus of Eq. (17), Pa */
    double R_conformal;     /* effective radius of the pin in the bore, R1 R2 / (R2 - R1), m */
    double shock_dir[2];    /* cos, sin of shock.angle */
} csfh_derived_t;

/* Discrete state of the event-driven compliant contact. */
typedef struct {
    int in_contact;       /* contact mode */
    int contact_count;    /* number of onsets */
    double onset_speed;   /* indentation rate captured at the onset, m/s (raw, floored at use) */
    double onset_time;    /* time of the last onset, s */
    double release_time;  /* time of the last release, s */
    double release_speed; /* separation speed dg/dt at the last release, m/s */
} csfh_discrete_t;

typedef struct {
    int rhs, flexure, contact, friction; /* evaluation counters (saturate at INT_MAX) */
} csfh_counters_t;

typedef struct {
    double F_N, F_T, indentation, gap, v_T, indentation_rate;
    double E_total, E_kinetic, E_gravity, E_flexure, E_contact;
    double F_N_peak, F_T_peak, indentation_peak; /* see CSFH_N_PEAKS */
    /* stresses (docs/model.md §14.2-14.4): evaluated with the outputs, never in the RHS */
    double stress_max, stress_location, stress_max_peak, stress_margin;
    double pressure_max, half_width, pressure_max_peak, pressure_margin;
    double a_frame[2]; /* the frame's acceleration at the output time: a_base + shock pulse */
} csfh_outputs_t;

/* The peak quantities (contact.F_N_peak, contact.F_T_peak = the largest |F_T|,
 * contact.indentation_peak, flexure.stress_max_peak): F_N, |F_T|, the indentation and the
 * flexure stress, whose largest values over a communication step the FMU tracks in
 * co-simulation (../models/csfh/csfh_peaks.c); where no step was taken (model exchange, the
 * harness) the outputs are the instantaneous values. The flexure stress counts only with
 * flexure.track_stress_peak (it costs evaluations in flight too); contact.pressure_max_peak is
 * the pressure of contact.F_N_peak (p0 grows with F_N: docs/model.md §14.5). */
#define CSFH_N_PEAKS 4

typedef struct {
    double time;
    double x[6];        /* x, y, theta, vx, vy, omega */
    double u_in[3];     /* F_ext[1], F_ext[2], M_ext */
    double a_base[2];   /* a_base[1], a_base[2]: acceleration of body 2 (the frame), global, m/s^2 */
    csfh_params_t p;
    csfh_derived_t d;
    csfh_discrete_t z;
    csfh_counters_t counters;
} csfh_model_t;

/* Contact force evaluation at one state (for outputs and the Moreau harness). */
typedef struct {
    int touching;           /* gap < 0 and a law is selected */
    csfh_contact_kin_t kin; /* valid when touching */
    double rho, rho_dot;    /* indentation and its rate (> 0 approaching) */
    double F_N, F_T;
    int status;             /* CSFH_LAW_OK or CSFH_LAW_ESDU_CLAMPED */
} csfh_contact_eval_t;

/* Status bits of the evaluation functions. */
#define CSFH_OK 0
#define CSFH_WARN_ESDU_CLAMPED 1
#define CSFH_ERR_NONFINITE (-1)

/* The cross-checks of the parameters (R1 < R2, v0 < v1; their ranges are the variable table's:
 * ../models/csfh/csfh_fmu.h) and the derived quantities, each checked finite. Returns 0 on
 * success, -1 with a message otherwise (the derived quantities are then left unchanged). */
int csfh_model_prepare(csfh_model_t *m, char *msg, size_t msg_size);

/* End of initialization, before csfh_model_check_start: with initial.from_parameters the
 * state x takes the initial.body1.* parameters (already checked by csfh_model_prepare). */
void csfh_model_apply_initial_parameters(csfh_model_t *m);

/* The start state must not be deeper in the bore than contact.max_initial_indentation (a start
 * far inside the clearance is a typo, and the contact law would answer it with an unphysical
 * force): 0, or -1 with a message naming the state and the indentation. No check without a
 * contact law. */
int csfh_model_check_start(const csfh_model_t *m, char *msg, size_t msg_size);

/* Set the discrete contact state from the initial continuous state (end of initialization). */
void csfh_model_init_discrete(csfh_model_t *m);

/* The half-sine pulse A sin(pi (t - t0) / T) for t0 <= t <= t0 + T, 0 elsewhere (m/s^2;
 * docs/model.md Eq. (14.9)). Pure. */
double csfh_half_sine(double A, double T, double t0, double t);

/* The frame's acceleration at time t, global components: the a_base inputs plus the shock
 * pulse along shock.angle (docs/model.md §14.1, §14.8). */
void csfh_model_frame_acceleration(const csfh_model_t *m, double t, double a[2]);

/* The next time event after t: the shock pulse's start or end, whichever comes first after t;
 * INFINITY when there is none (no pulse, or t past its end). */
double csfh_model_next_time_event(const csfh_model_t *m, double t);

/* Smooth generalized forces at time t and q: gravity + inputs + the d'Alembert force
 * -m1 a_frame(t) of the frame's acceleration at G1 (the a_base inputs and the shock pulse,
 * docs/model.md §14.1, §14.8) + flexure (if enabled). The Moreau stepper and the RK4 baseline
 * take them from here too. Without a pulse t is not used. */
void csfh_model_smooth_forces(csfh_model_t *m, double t, const double q[3], double Q[3]);

/* Compliant contact force at (q, u) with the current discrete state: zero outside the contact
 * mode (set by csfh_model_event_update), whatever the gap. */
void csfh_model_contact(csfh_model_t *m, const double q[3], const double u[3],
                        csfh_contact_eval_t *c);

/* xdot = f(t, x) with the current inputs and discrete state (t enters through the shock pulse
 * only: the integrator's own time, not m->time). Returns CSFH_OK, CSFH_WARN_ESDU_CLAMPED, or
 * CSFH_ERR_NONFINITE if any derivative is not finite. */
int csfh_model_derivatives(csfh_model_t *m, double t, const double x[6], double xdot[6]);

/* The same with the contact force wherever the gap is negative, also before the onset event,
 * with the state's own indentation rate until the onset is captured: the paper's RK4 scheme
 * (../solvers/csfh_rk4event.c), which has no root finding and bisects the step instead. */
void csfh_model_contact_by_gap(csfh_model_t *m, const double q[3], const double u[3],
                               csfh_contact_eval_t *c);
int csfh_model_derivatives_by_gap(csfh_model_t *m, double t, const double x[6], double xdot[6]);

/* Event indicator of the contact: the gap, offset by the hysteresis so that it never sits at 0
 * right after an event (1 when the contact law is none: no events). */
double csfh_model_event_indicator(const csfh_model_t *m, const double x[6]);

/* Contact mode update at an event, from m->x at m->time. Returns 0 (no change), 1 (onset: the
 * indentation rate and the time are captured) or 2 (release: time and separation speed). */
int csfh_model_event_update(csfh_model_t *m);

/* The quantities of the peak outputs at state x with the current contact mode: v = {F_N, |F_T|,
 * indentation}. Returns 0 (and zeros) outside the contact mode, without evaluating anything. */
int csfh_model_peak_values(csfh_model_t *m, const double x[6], double v[CSFH_N_PEAKS]);

/* 1 if csfh_model_peak_values can return anything but zeros in the current discrete state and
 * parameters (the contact mode, or the flexure stress tracked), whatever the state. */
int csfh_model_peaks_tracked(const csfh_model_t *m);

/* Stresses at one configuration (docs/model.md §14.2-14.3). */
typedef struct {
    double flexure_stress;     /* Pa: largest |sigma| over the arc (0 with the flexure off) */
    double flexure_location;   /* rad: arc angle of that section from the root C2 */
    double contact_pressure;   /* Pa: Hertz peak pressure p0 of F_N (0 for F_N = 0) */
    double contact_half_width; /* m: half-width b of the contact strip */
} csfh_stresses_t;

/* The flexure's largest stress at q (0 with the flexure off); *location (may be NULL) as in
 * csfh_arc_stress_max. Pure: no counters, evaluated for outputs only, never in the RHS. */
double csfh_model_flexure_stress(const csfh_model_t *m, const double q[3], double *location);

/* The flexure stress at q and the contact pressure of the normal force F_N. Pure. */
void csfh_model_stresses(const csfh_model_t *m, const double q[3], double F_N,
                         csfh_stresses_t *s);

/* The outputs at the current state (forces, gap, energies, stresses, peaks, margins): the peak
 * outputs take the largest of the current values and `peaks` (CSFH_N_PEAKS values so far in the
 * communication step; NULL: none). CSFH_OK or CSFH_WARN_ESDU_CLAMPED. */
int csfh_model_outputs(csfh_model_t *m, const double *peaks, csfh_outputs_t *out);
/* Of these only the loads (a master that reduces the peaks reads these alone): the contact
 * forces F_N, F_T and the indentation, the stresses, the peaks and margins, each the value
 * csfh_model_outputs gives it; the other outputs are left as they are. */
int csfh_model_load_outputs(csfh_model_t *m, const double *peaks, csfh_outputs_t *out);
/* ... with the contact force by the gap (the RK4 scheme: csfh_model_contact_by_gap), no peaks. */
int csfh_model_outputs_by_gap(csfh_model_t *m, csfh_outputs_t *out);

CSFH_INTERNAL_END

#endif
