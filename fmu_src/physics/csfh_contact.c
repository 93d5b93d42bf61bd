#include "csfh_contact.h"

#include <math.h>

#include "csfh_common.h"

static void eccentricity(const double s1bar[2], const double q[3], double e[2], double s1[2])
{
    if (s1bar[0] == 0.0 && s1bar[1] == 0.0) { /* O1 at G1 (the paper's scenes): no rotation */
        s1[0] = s1[1] = 0.0;
        e[0] = q[0];
        e[1] = q[1];
        return;
    }
    const double c = cos(q[2]), s = sin(q[2]);
    s1[0] = c * s1bar[0] - s * s1bar[1];
    s1[1] = s * s1bar[0] + c * s1bar[1];
    e[0] = q[0] + s1[0]; /* e = r + s1 - r2, r2 = O2 = 0 (Eq. 11) */
    e[1] = q[1] + s1[1];
}

double csfh_contact_gap(double delta, const double s1bar[2], const double q[3])
{
    double e[2], s1[2];
    eccentricity(s1bar, q, e, s1);
    return delta - csfh_norm2(e[0], e[1]);
}

void csfh_contact_kinematics(double delta, double R1, const double s1bar[2], const double q[3],
                             csfh_contact_kin_t *kin)
{
    double e[2], s1[2];
    eccentricity(s1bar, q, e, s1);
    const double en = csfh_norm2(e[0], e[1]);
    kin->e_norm = en;
    kin->gap = delta - en;
    if (en > 1e-300) {
        kin->n[0] = -e[0] / en;
        kin->n[1] = -e[1] / en;
    } else { /* guard |e| -> 0: no contact can exist there for delta > 0 */
        kin->n[0] = 0.0;
        kin->n[1] = 1.0;
    }
    kin->t[0] = -kin->n[1]; /* rot90 */
    kin->t[1] = kin->n[0];
    kin->a[0] = s1[0] - R1 * kin->n[0]; /* corrected arm (docs/model.md §3, errata of Eqs. 30, 38) */
    kin->a[1] = s1[1] - R1 * kin->n[1];
    kin->DN[0] = kin->n[0];
    kin->DN[1] = kin->n[1];
    kin->DN[2] = csfh_cross2(kin->a, kin->n);
    kin->DT[0] = kin->t[0];
    kin->DT[1] = kin->t[1];
    kin->DT[2] = csfh_cross2(kin->a, kin->t);
}

void csfh_contact_add_force(const csfh_contact_kin_t *kin, double F_N, double F_T, double Q[3])
{
    for (int i = 0; i < 3; i++) {
        Q[i] += kin->DN[i] * F_N + kin->DT[i] * F_T;
    }
}
