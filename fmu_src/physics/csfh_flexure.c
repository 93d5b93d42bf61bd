#include "csfh_flexure.h"

#include "csfh_common.h"

#include <math.h>
#include <stddef.h>

void csfh_arc_compliance(const csfh_arc_beam_t *beam, double C[3][3])
{
    const double rho = beam->rho, beta = beam->beta;
    const double s = sin(beta), c = cos(beta), s2 = sin(2.0 * beta);
    const double EI = beam->E * beam->b * beam->h * beam->h * beam->h / 12.0;

    /* bending part, docs/model.md §2.2 */
    const double kb = rho / EI;
    C[0][0] = kb * rho * rho * (1.5 * beta - 2.0 * s + 0.25 * s2);
    C[0][1] = kb * rho * rho * (1.0 - c - 0.5 * s * s);
    C[0][2] = kb * rho * (beta - s);
    C[1][1] = kb * rho * rho * (0.5 * beta - 0.25 * s2);
    C[1][2] = kb * rho * (1.0 - c);
    C[2][2] = kb * beta;

    if (!beam->bending_only) {
        /* axial and shear parts act on the force block only, docs/model.md §2.2 */
        const double EA = beam->E * beam->b * beam->h;
        const double GA = beam->E / (2.0 * (1.0 + beam->nu)) * beam->b * beam->h;
        const double ka = rho / EA, ks = beam->kappa * rho / GA;
        C[0][0] += ka * (0.5 * beta + 0.25 * s2) + ks * (0.5 * beta - 0.25 * s2);
        C[0][1] += ka * (-0.5 * s * s) + ks * (0.5 * s * s);
        C[1][1] += ka * (0.5 * beta - 0.25 * s2) + ks * (0.5 * beta + 0.25 * s2);
    }
    C[1][0] = C[0][1];
    C[2][0] = C[0][2];
    C[2][1] = C[1][2];
}

int csfh_mat3_inverse(const double A[3][3], double Ainv[3][3])
{
    const double c00 = A[1][1] * A[2][2] - A[1][2] * A[2][1];
    const double c01 = A[1][2] * A[2][0] - A[1][0] * A[2][2];
    const double c02 = A[1][0] * A[2][1] - A[1][1] * A[2][0];
    const double det = A[0][0] * c00 + A[0][1] * c01 + A[0][2] * c02;
    if (!isfinite(det) || det == 0.0) {
        return -1;
    }
    const double inv = 1.0 / det;
    Ainv[0][0] = c00 * inv;
    Ainv[1][0] = c01 * inv;
    Ainv[2][0] = c02 * inv;
    Ainv[0][1] = (A[0][2] * A[2][1] - A[0][1] * A[2][2]) * inv;
    Ainv[1][1] = (A[0][0] * A[2][2] - A[0][2] * A[2][0]) * inv;
    Ainv[2][1] = (A[0][1] * A[2][0] - A[0][0] * A[2][1]) * inv;
    Ainv[0][2] = (A[0][1] * A[1][2] - A[0][2] * A[1][1]) * inv;
    Ainv[1][2] = (A[0][2] * A[1][0] - A[0][0] * A[1][2]) * inv;
    Ainv[2][2] = (A[0][0] * A[1][1] - A[0][1] * A[1][0]) * inv;
    return 0;
}

double csfh_flexure_frame_angle(double phi_root, double beta)
{
    return phi_root + beta + 0.5 * CSFH_PI; /* docs/model.md §1.3: n = tangent at the tip */
}

int csfh_flexure_setup(const csfh_arc_beam_t *beam, const double OF[2], double phi_root,
                       int conservative, csfh_flexure_t *flex)
{
    double C[3][3], Khat[3][3];
    csfh_arc_compliance(beam, C);
    if (csfh_mat3_inverse(C, Khat) != 0) {
        return -1;
    }
    /* K0 = blk(R) Khat blk(R)^T with R = A(psi) the local -> body rotation (docs/model.md §1.3, 2.5) */
    const double psi = csfh_flexure_frame_angle(phi_root, beam->beta);
    const double R[3][3] = {{cos(psi), -sin(psi), 0.0}, {sin(psi), cos(psi), 0.0}, {0.0, 0.0, 1.0}};
    double RK[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            RK[i][j] = R[i][0] * Khat[0][j] + R[i][1] * Khat[1][j] + R[i][2] * Khat[2][j];
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            flex->K0[i][j] = RK[i][0] * R[j][0] + RK[i][1] * R[j][1] + RK[i][2] * R[j][2];
        }
    }
    /* symmetrise against round-off */
    for (int i = 0; i < 3; i++) {
        for (int j = i + 1; j < 3; j++) {
            const double avg = 0.5 * (flex->K0[i][j] + flex->K0[j][i]);
            flex->K0[i][j] = flex->K0[j][i] = avg;
        }
    }
    /* attachment point with G1 = O2 = origin in the undeformed state (docs/model.md §1.2) */
    const double phi_tip = phi_root + beam->beta;
    flex->sbar[0] = OF[0] + beam->rho * cos(phi_tip);
    flex->sbar[1] = OF[1] + beam->rho * sin(phi_tip);
    flex->conservative = conservative;
    return 0;
}

double csfh_flexure_force(const csfh_flexure_t *flex, const double q[3], double Q[3])
{
    const double c = cos(q[2]), s = sin(q[2]);
    /* s = A(theta) sbar: G1 -> C1 in the global frame */
    const double sx = c * flex->sbar[0] - s * flex->sbar[1];
    const double sy = s * flex->sbar[0] + c * flex->sbar[1];
    /* dp = [r + (A - I) sbar; theta], Eq. (5) with r0 = 0, theta0 = 0 */
    const double dp[3] = {q[0] + sx - flex->sbar[0], q[1] + sy - flex->sbar[1], q[2]};
    double w[3]; /* wrench applied to the beam tip, global: w = K(theta) dp (Eq. 8) */
    if (flex->conservative) {
        for (int i = 0; i < 3; i++) {
            w[i] = flex->K0[i][0] * dp[0] + flex->K0[i][1] * dp[1] + flex->K0[i][2] * dp[2];
        }
    } else {
        /* K(theta) = blk(A) K0 blk(A)^T: rotate dp into the body frame, apply K0, rotate back */
        const double db[3] = {c * dp[0] + s * dp[1], -s * dp[0] + c * dp[1], dp[2]};
        double wb[3];
        for (int i = 0; i < 3; i++) {
            wb[i] = flex->K0[i][0] * db[0] + flex->K0[i][1] * db[1] + flex->K0[i][2] * db[2];
        }
        w[0] = c * wb[0] - s * wb[1];
        w[1] = s * wb[0] + c * wb[1];
        w[2] = wb[2];
    }
    /* Q_e = -T_e(s) w, T_e row 3 = [s^T 1bar, 1]: s^T 1bar F = s x F (Eq. 9, docs/model.md §2.4) */
    Q[0] = -w[0];
    Q[1] = -w[1];
    Q[2] = -(sx * w[1] - sy * w[0] + w[2]);
    return 0.5 * (dp[0] * w[0] + dp[1] * w[1] + dp[2] * w[2]);
}

void csfh_flexure_tip_wrench(const csfh_flexure_t *flex, const double q[3], double w[3])
{
    /* the same operations as csfh_flexure_force, stopped before the rotation back to global */
    const double c = cos(q[2]), s = sin(q[2]);
    const double sx = c * flex->sbar[0] - s * flex->sbar[1];
    const double sy = s * flex->sbar[0] + c * flex->sbar[1];
    const double dp[3] = {q[0] + sx - flex->sbar[0], q[1] + sy - flex->sbar[1], q[2]};
    if (flex->conservative) {
        for (int i = 0; i < 3; i++) {
            w[i] = flex->K0[i][0] * dp[0] + flex->K0[i][1] * dp[1] + flex->K0[i][2] * dp[2];
        }
        return;
    }
    const double db[3] = {c * dp[0] + s * dp[1], -s * dp[0] + c * dp[1], dp[2]};
    for (int i = 0; i < 3; i++) {
        w[i] = flex->K0[i][0] * db[0] + flex->K0[i][1] * db[1] + flex->K0[i][2] * db[2];
    }
}

void csfh_arc_section_setup(const csfh_arc_beam_t *beam, double phi_root, csfh_arc_section_t *sec)
{
    const double psi = csfh_flexure_frame_angle(phi_root, beam->beta);
    sec->rho = beam->rho;
    sec->beta = beam->beta;
    sec->area = beam->b * beam->h;
    sec->section_modulus = beam->b * beam->h * beam->h / 6.0;
    sec->cos_psi = cos(psi);
    sec->sin_psi = sin(psi);
    sec->cos_beta = cos(beam->beta);
    sec->sin_beta = sin(beam->beta);
}

double csfh_arc_stress_max(const csfh_arc_section_t *sec, const double w[3], double *location)
{
    /* the wrench in the tip frame (n, t): F_n, F_t, M (Eq. 2.2) */
    const double Fn = sec->cos_psi * w[0] + sec->sin_psi * w[1];
    const double Ft = -sec->sin_psi * w[0] + sec->cos_psi * w[1];
    /* Eq. (2.2): N(alpha) = cos(alpha) F_n - sin(alpha) F_t and m(alpha) = M0 - rho N(alpha),
     * M0 = M + rho F_n; sigma(N) = |N| / A + |M0 - rho N| / Z (docs/model.md Eq. (14.4)) */
    const double M0 = w[2] + sec->rho * Fn;
    /* candidates from the root (alpha = beta) to the tip (alpha = 0); N = +-|F| where
     * [cos(alpha), sin(alpha)] = +-[F_n, -F_t] / |F| */
    double N[4], alpha[4];
    int n = 0;
    N[n] = sec->cos_beta * Fn - sec->sin_beta * Ft;
    alpha[n++] = sec->beta;
    const double F = sqrt(Fn * Fn + Ft * Ft);
    if (F > 0.0) {
        double a_max = atan2(-Ft, Fn); /* N = +|F| */
        a_max = a_max < 0.0 ? a_max + 2.0 * CSFH_PI : a_max;
        const double a_min = a_max < CSFH_PI ? a_max + CSFH_PI : a_max - CSFH_PI; /* N = -|F| */
        const double first = a_max > a_min ? a_max : a_min, second = a_max > a_min ? a_min : a_max;
        const double a_sorted[2] = {first, second};
        for (int k = 0; k < 2; k++) {
            if (a_sorted[k] > 0.0 && a_sorted[k] < sec->beta) {
                N[n] = a_sorted[k] == a_max ? F : -F;
                alpha[n++] = a_sorted[k];
            }
        }
    }
    N[n] = Fn;
    alpha[n++] = 0.0;
    double best = -1.0, best_alpha = sec->beta;
    for (int i = 0; i < n; i++) {
        const double sigma = fabs(N[i]) / sec->area + fabs(M0 - sec->rho * N[i]) / sec->section_modulus;
        if (sigma > best) {
            best = sigma;
            best_alpha = alpha[i];
        }
    }
    if (location != NULL) {
        *location = sec->beta - best_alpha;
    }
    return best;
}
