#include "csfh_friction.h"

#include <math.h>

double csfh_ambrosio_cd(double v_abs, double v0, double v1)
{
    if (v_abs <= v0) {
        return 0.0;
    }
    if (v_abs >= v1) {
        return 1.0;
    }
    return (v_abs - v0) / (v1 - v0);
}

double csfh_ambrosio_force(double fd, double v0, double v1, double F_N, double v_T)
{
    const double cd = csfh_ambrosio_cd(fabs(v_T), v0, v1);
    if (cd == 0.0) {
        return 0.0;
    }
    return (v_T > 0.0 ? -1.0 : 1.0) * fd * cd * F_N;
}
