/* Electrostatic comb-drive actuator for the CSFH (a second, small FMU: build/combdrive.fmu).
 *
 * Physics. n movable fingers (the rotor, fixed to body 1) each sit between two stator fingers
 * (fixed to the ground) with a gap g on either side, thickness t, engagement (overlap) x along
 * the finger axis. With a parallel-plate field in the 2 n gaps the capacitance is
 *     C(x) = 2 n eps t x / g,
 * and at a fixed drive voltage V the electrostatic force along the finger axis is the derivative
 * of the co-energy W = C(x) V^2 / 2:
 *     F = dW/dx = n eps t V^2 / g            (the comb-drive formula, e.g. Tang, Nguyen & Howe,
 *                                             "Laterally driven polysilicon resonant
 *                                             microstructures", 1989)
 * Assumptions: fringing fields neglected (g << t and g << x); the gap g stays constant (no
 * lateral motion of the fingers, so no side instability); the force is independent of the
 * engagement x as long as the fingers stay engaged and away from the ends of their travel (which
 * must exceed the hinge's, about 2 delta = 40 mm); electrostatics is quasi-static and the source
 * ideal (no RC dynamics); the force is attractive whatever the sign of V (it goes with V^2).
 *
 * The finger axis is fixed in the CSFH global frame at angle `direction` from +X (the stator is
 * fixed; the small rotation of the rotor with body 1 is neglected for the direction), so
 *     F_x = F cos(direction),  F_y = F sin(direction).
 * The force is applied at the point arm[] of body 1 (relative to G1, body frame); its moment
 * about G1 is M = (A(theta) arm) x F, with theta the rotation of body 1 (an input).
 *
 * Scale. F = n eps t V^2 / g with the defaults (n = 20000, t = 25 mm, g = 5 um, vacuum) is
 * 8.85e-4 N/V^2 x V^2: about 140 N at 400 V, the scale of the 10-kg hinge's weight. A real
 * MEMS comb gives micro-newtons; this is an idealised, scaled-up actuator. */
#ifndef COMBDRIVE_MODEL_H
#define COMBDRIVE_MODEL_H

#include <stddef.h>

#include "csfh_vartable.h"
#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

typedef struct {
    int fingers;          /* n */
    double gap;           /* g, m */
    double thickness;     /* t, m */
    double permittivity;  /* eps, F/m */
    double direction;     /* rad, global frame */
    double arm[2];        /* application point relative to G1, body frame, m */
    struct {
        double V0, V1, t0, t1; /* V0 until t0, linear to V1 at t1, V1 after (V, s) */
    } ramp;               /* added to the input V */
} combdrive_params_t;

typedef struct {
    double k;             /* n eps t / g, N/V^2 */
    double dir[2];        /* cos(direction), sin(direction) */
} combdrive_derived_t;

typedef struct {
    double F, F_x, F_y, M;
} combdrive_outputs_t;

typedef struct {
    double time;
    double u_in[2];       /* V, theta */
    combdrive_params_t p;
    combdrive_derived_t d;
    combdrive_outputs_t out;
} combdrive_model_t;

/* Start values of every variable from the generated table. */
void combdrive_set_defaults(combdrive_model_t *m);

/* Validate every parameter and input (ranges, finiteness) and compute k and the direction.
 * 0, or -1 with a message naming the variable and its value (the model is then unchanged). */
int combdrive_prepare(combdrive_model_t *m, char *msg, size_t msg_size);

/* The ramp voltage at time t: V0 until t0, linear to V1 at t1, V1 afterwards. Pure. */
double combdrive_ramp(double V0, double V1, double t0, double t1, double t);

/* F, F_x, F_y, M at the current inputs and time (drive voltage V + ramp(time)). 0, or -1 with
 * a message if a value is not finite. */
int combdrive_outputs(combdrive_model_t *m, char *msg, size_t msg_size);

CSFH_INTERNAL_END

#endif
