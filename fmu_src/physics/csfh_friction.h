/* Ambrosio friction (docs/model.md §5.1, paper Eq. 26). Pure functions, SI units. */
#ifndef CSFH_FRICTION_H
#define CSFH_FRICTION_H

#include "csfh_visibility.h"

CSFH_INTERNAL_BEGIN

/* Dynamic correction coefficient c_d(|v_T|): 0 below v0, linear ramp to 1 at v1. */
double csfh_ambrosio_cd(double v_abs, double v0, double v1);

/* Friction force along t_c on body 1: F_T = -f_d c_d(|v_T|) F_N sgn(v_T). */
double csfh_ambrosio_force(double fd, double v0, double v1, double F_N, double v_T);

CSFH_INTERNAL_END

#endif
