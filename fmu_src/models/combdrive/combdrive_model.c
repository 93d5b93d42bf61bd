#include "combdrive_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "combdrive_variables.h"

static double *real_of(combdrive_model_t *m, const csfh_variable_t *v)
{
    return (double *)((char *)m + v->offset);
}

static int *int_of(combdrive_model_t *m, const csfh_variable_t *v)
{
    return (int *)((char *)m + v->offset);
}

void combdrive_set_defaults(combdrive_model_t *m)
{
    memset(m, 0, sizeof(*m));
    for (int i = 0; i < COMBDRIVE_NUMBER_OF_VARIABLES; i++) {
        const csfh_variable_t *v = &combdrive_variables[i];
        if (!v->has_start) {
            continue;
        }
        if (v->type == CSFH_TYPE_REAL) {
            *real_of(m, v) = v->start;
        } else {
            *int_of(m, v) = (int)v->start;
        }
    }
}

int combdrive_prepare(combdrive_model_t *m, char *msg, size_t msg_size)
{
    for (int i = 0; i < COMBDRIVE_NUMBER_OF_VARIABLES; i++) {
        const csfh_variable_t *v = &combdrive_variables[i];
        if (v->causality != CSFH_CAUS_PARAMETER && v->causality != CSFH_CAUS_INPUT) {
            continue;
        }
        const double value = v->type == CSFH_TYPE_REAL ? *real_of(m, v) : (double)*int_of(m, v);
        if (csfh_check_value(v, value, msg, msg_size) != 0) {
            return -1;
        }
    }
    const combdrive_params_t *p = &m->p;
    const double k = (double)p->fingers * p->permittivity * p->thickness / p->gap;
    if (!(isfinite(k) && k > 0.0)) {
        char b1[32], b2[32], b3[32];
        snprintf(msg, msg_size,
                 "force_constant = n eps t / g = %g is not finite and positive (fingers = %d, "
                 "permittivity = %s, thickness = %s, gap = %s)",
                 k, p->fingers, csfh_format_value(b1, p->permittivity),
                 csfh_format_value(b2, p->thickness), csfh_format_value(b3, p->gap));
        return -1;
    }
    if (!(p->ramp.t1 >= p->ramp.t0)) {
        char b1[32], b2[32];
        snprintf(msg, msg_size, "ramp.t1 = %s must not be smaller than ramp.t0 = %s",
                 csfh_format_value(b1, p->ramp.t1), csfh_format_value(b2, p->ramp.t0));
        return -1;
    }
    m->d.k = k;
    m->d.dir[0] = cos(p->direction);
    m->d.dir[1] = sin(p->direction);
    return 0;
}

double combdrive_ramp(double V0, double V1, double t0, double t1, double t)
{
    if (t <= t0) {
        return V0;
    }
    if (t >= t1) {
        return V1;
    }
    return V0 + (V1 - V0) * (t - t0) / (t1 - t0);
}

int combdrive_outputs(combdrive_model_t *m, char *msg, size_t msg_size)
{
    const double V = m->u_in[0] + combdrive_ramp(m->p.ramp.V0, m->p.ramp.V1, m->p.ramp.t0,
                                                 m->p.ramp.t1, m->time);
    const double theta = m->u_in[1];
    combdrive_outputs_t o;
    o.F = m->d.k * V * V; /* n eps t V^2 / g */
    o.F_x = o.F * m->d.dir[0];
    o.F_y = o.F * m->d.dir[1];
    const double c = cos(theta), s = sin(theta);
    const double a[2] = {c * m->p.arm[0] - s * m->p.arm[1], s * m->p.arm[0] + c * m->p.arm[1]};
    o.M = a[0] * o.F_y - a[1] * o.F_x;
    if (!(isfinite(o.F) && isfinite(o.M))) {
        char b1[32];
        snprintf(msg, msg_size, "non-finite force F = %g N at V = %s V (t = %.17g)", o.F,
                 csfh_format_value(b1, V), m->time);
        return -1;
    }
    m->out = o;
    return 0;
}
