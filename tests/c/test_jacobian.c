/* The analytic partial derivatives (csfh_jacobian.c, docs/model.md §15) against sixth-order
 * central differences of the functions they differentiate: the elastic stiffness of every normal
 * law, Ambrosio friction, and the right-hand side's and the outputs' Jacobians with respect to
 * the states and the inputs, in flight and in contact with each law, the co-rotated and the
 * conservative flexure, with and without an eccentric cylinder. Each entry must agree to 1e-7
 * relative to the largest entry of its row (rows mix quantities of different units). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csfh_fmu.h"
#include "csfh_friction.h"
#include "csfh_jacobian.h"
#include "csfh_model.h"
#include "csfh_test.h"

#define MSG_SIZE 512
#define TOL 1e-7

typedef double (*scalar_fn_t)(const void *ctx, double x);

/* Sixth-order central difference of f at x with step h. */
static double fd6(scalar_fn_t f, const void *ctx, double x, double h)
{
    const double d1 = f(ctx, x + h) - f(ctx, x - h);
    const double d2 = f(ctx, x + 2.0 * h) - f(ctx, x - 2.0 * h);
    const double d3 = f(ctx, x + 3.0 * h) - f(ctx, x - 3.0 * h);
    return (45.0 * d1 - 9.0 * d2 + d3) / (60.0 * h);
}

static int set_by_name(csfh_fmu_t *fmu, const char *name, double value)
{
    const csfh_variable_t *v = csfh_fmu_variable(name);
    if (!CHECK_TRUE(v != NULL, TFMT("variable %s exists", name))) {
        return -1;
    }
    if (v->type == CSFH_TYPE_REAL) {
        *csfh_fmu_real(fmu, v) = value;
    } else {
        *csfh_fmu_int(fmu, v) = (int)value;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* the normal laws and friction */

static double elastic_force(const void *law, double rho)
{
    double F;
    csfh_normal_elastic_force((const csfh_normal_law_t *)law, rho, &F);
    return F;
}

static void test_normal_laws(void)
{
    static const struct {
        int law, reading;
        const char *name;
    } laws[] = {{CSFH_CONTACTLAW_LN_SPHERES, 1, "LN_spheres"},
                {CSFH_CONTACTLAW_LN_CYLINDERS, 1, "LN_cylinders"},
                {CSFH_CONTACTLAW_HUNTCROSSLEY, 1, "Hunt-Crossley"},
                {CSFH_CONTACTLAW_FLORES, 1, "Flores"},
                {CSFH_CONTACTLAW_LN_ESDU, CSFH_ESDUREADING_I2, "LN_ESDU I2"},
                {CSFH_CONTACTLAW_LN_ESDU, CSFH_ESDUREADING_I3, "LN_ESDU I3"}};
    const double rhos[] = {1e-7, 3e-6, 2e-5, 1e-4, 1e-3};
    for (size_t i = 0; i < sizeof(laws) / sizeof(laws[0]); i++) {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        csfh_fmu_set_defaults(&fmu);
        set_by_name(&fmu, "contact.law", laws[i].law);
        set_by_name(&fmu, "contact.esdu_reading", laws[i].reading);
        CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare");
        const csfh_normal_law_t *law = &fmu.m.d.normal;
        for (size_t k = 0; k < sizeof(rhos) / sizeof(rhos[0]); k++) {
            const double rho = rhos[k];
            const double fd = fd6(elastic_force, law, rho, 1e-3 * rho);
            CHECK_CLOSE(csfh_normal_elastic_stiffness(law, rho), fd, TOL,
                        TFMT("%s: dF_el/drho at rho = %g", laws[i].name, rho));
        }
    }
}

typedef struct {
    double fd, v0, v1, F_N, v_T;
} friction_ctx_t;

static double friction_of_v(const void *p, double v)
{
    const friction_ctx_t *c = (const friction_ctx_t *)p;
    return csfh_ambrosio_force(c->fd, c->v0, c->v1, c->F_N, v);
}

static double friction_of_FN(const void *p, double F_N)
{
    const friction_ctx_t *c = (const friction_ctx_t *)p;
    return csfh_ambrosio_force(c->fd, c->v0, c->v1, F_N, c->v_T);
}

static void test_friction(void)
{
    const double speeds[] = {-0.5, -3e-3, -5e-5, 2e-5, 2e-4, 7e-3, 0.02};
    for (size_t i = 0; i < sizeof(speeds) / sizeof(speeds[0]); i++) {
        const friction_ctx_t c = {0.055, 1e-4, 1e-2, 250.0, speeds[i]};
        double dFN, dv;
        csfh_ambrosio_partials(c.fd, c.v0, c.v1, c.F_N, c.v_T, &dFN, &dv);
        const double h = 1e-3 * fmin(fabs(c.v_T), 1e-5);
        CHECK_ABS(dv, fd6(friction_of_v, &c, c.v_T, h), TOL * c.fd * c.F_N / (c.v1 - c.v0),
                  TFMT("dF_T/dv_T at v_T = %g", c.v_T));
        CHECK_ABS(dFN, fd6(friction_of_FN, &c, c.F_N, 1.0), TOL * c.fd,
                  TFMT("dF_T/dF_N at v_T = %g", c.v_T));
    }
}

/* ---------------------------------------------------------------------------------------- */
/* the right-hand side and the outputs */

/* The model at x with the inputs v; f(x, v) is one of the two functions below. */
typedef struct {
    csfh_fmu_t fmu;
    double x[6], v[CSFH_N_JAC_INPUTS];
    int column; /* which of x (0..5) or v (6..10) is varied */
    int row;    /* which component is returned */
} model_ctx_t;

static void load(model_ctx_t *c, double s, double x[6])
{
    memcpy(x, c->x, sizeof(c->x));
    double v[CSFH_N_JAC_INPUTS];
    memcpy(v, c->v, sizeof(v));
    if (c->column < 6) {
        x[c->column] = s;
    } else {
        v[c->column - 6] = s;
    }
    memcpy(c->fmu.m.u_in, v, 3 * sizeof(double));
    memcpy(c->fmu.m.a_base, v + 3, 2 * sizeof(double));
}

static double rhs_component(const void *p, double s)
{
    model_ctx_t *c = (model_ctx_t *)p;
    double x[6], xdot[6];
    load(c, s, x);
    csfh_model_derivatives(&c->fmu.m, 0.0, x, xdot);
    return xdot[c->row];
}

static double output_component(const void *p, double s)
{
    model_ctx_t *c = (model_ctx_t *)p;
    load(c, s, c->fmu.m.x);
    csfh_outputs_t o;
    csfh_model_outputs(&c->fmu.m, NULL, &o);
    const double values[CSFH_N_JOUT] = {
        [CSFH_JOUT_F_N] = o.F_N,
        [CSFH_JOUT_F_T] = o.F_T,
        [CSFH_JOUT_INDENTATION] = o.indentation,
        [CSFH_JOUT_GAP] = o.gap,
        [CSFH_JOUT_V_T] = o.v_T,
        [CSFH_JOUT_INDENTATION_RATE] = o.indentation_rate,
        [CSFH_JOUT_E_TOTAL] = o.E_total,
        [CSFH_JOUT_E_KINETIC] = o.E_kinetic,
        [CSFH_JOUT_E_GRAVITY] = o.E_gravity,
        [CSFH_JOUT_E_FLEXURE] = o.E_flexure,
        [CSFH_JOUT_E_CONTACT] = o.E_contact,
        [CSFH_JOUT_STRESS_MAX] = o.stress_max,
        [CSFH_JOUT_STRESS_LOCATION] = o.stress_location,
        [CSFH_JOUT_PRESSURE_MAX] = o.pressure_max,
        [CSFH_JOUT_HALF_WIDTH] = o.half_width,
        [CSFH_JOUT_F_T_ABS] = o.F_T_peak,
        [CSFH_JOUT_STRESS_MARGIN] = o.stress_margin,
        [CSFH_JOUT_PRESSURE_MARGIN] = o.pressure_margin,
    };
    return values[c->row];
}

/* Step of the difference in column j: small against the indentation (positions) and against
 * the friction ramp's width (velocities), so that no branch changes within 3 steps. */
static double step_of(int column)
{
    return column < 3 ? 1e-8 : (column < 6 ? 1e-5 : 1e-3);
}

/* Each row of the analytic matrix J (rows x 11 columns: the states, then the inputs; n_cols
 * columns given) against the differences of f. */
static void check_matrix(model_ctx_t *c, scalar_fn_t f, const double *J, int rows, int n_cols,
                         const char *what_in)
{
    char what[256];
    snprintf(what, sizeof(what), "%s", what_in);
    for (int i = 0; i < rows; i++) {
        double fd[6 + CSFH_N_JAC_INPUTS], scale = 0.0;
        c->row = i;
        for (int j = 0; j < n_cols; j++) {
            c->column = j;
            const double at = j < 6 ? c->x[j] : c->v[j - 6];
            fd[j] = fd6(f, c, at, step_of(j));
            scale = fmax(scale, fmax(fabs(fd[j]), fabs(J[i * n_cols + j])));
        }
        for (int j = 0; j < n_cols; j++) {
            CHECK_ABS(J[i * n_cols + j], fd[j], TOL * scale + 1e-300,
                      TFMT("%s: d row %d / d column %d", what, i, j));
        }
    }
}

/* The state at indentation rho (rho < 0: a gap) with the eccentricity along angle phi, the
 * indentation rate rho_dot, the sliding speed v_T and the rotation omega. */
static void contact_state(const csfh_model_t *m, double rho, double phi, double rho_dot,
                          double v_T, double omega, double x[6])
{
    const double en = m->d.delta + rho, th = 0.02;
    const double c = cos(th), s = sin(th);
    const double s1[2] = {c * m->p.s1bar[0] - s * m->p.s1bar[1],
                          s * m->p.s1bar[0] + c * m->p.s1bar[1]};
    x[0] = en * cos(phi) - s1[0];
    x[1] = en * sin(phi) - s1[1];
    x[2] = th;
    x[3] = x[4] = 0.0;
    x[5] = omega;
    csfh_contact_kin_t kin;
    csfh_contact_kinematics(m->d.delta, m->p.R1, m->p.s1bar, x, &kin);
    /* v = alpha n + beta t: rho_dot = -(alpha + DN_3 omega), v_T = beta + DT_3 omega */
    const double alpha = -rho_dot - kin.DN[2] * omega, beta = v_T - kin.DT[2] * omega;
    x[3] = alpha * kin.n[0] + beta * kin.t[0];
    x[4] = alpha * kin.n[1] + beta * kin.t[1];
}

static void check_case(model_ctx_t *c, const char *what_in)
{
    char what[200];
    snprintf(what, sizeof(what), "%s", what_in);
    double A[6][6], B[6][CSFH_N_JAC_INPUTS], J[6][6 + CSFH_N_JAC_INPUTS];
    CHECK_INT(csfh_model_rhs_jacobian(&c->fmu.m, c->x, A, B), CSFH_OK, TFMT("%s: rhs", what));
    for (int i = 0; i < 6; i++) {
        memcpy(J[i], A[i], sizeof(A[i]));
        memcpy(J[i] + 6, B[i], sizeof(B[i]));
    }
    check_matrix(c, rhs_component, &J[0][0], 6, 6 + CSFH_N_JAC_INPUTS, TFMT("%s: A, B", what));
    double D[CSFH_N_JOUT][6];
    memcpy(c->fmu.m.x, c->x, sizeof(c->x));
    CHECK_INT(csfh_model_output_jacobian(&c->fmu.m, c->x, D), CSFH_OK, TFMT("%s: out", what));
    check_matrix(c, output_component, &D[0][0], CSFH_N_JOUT, 6, TFMT("%s: C", what));
}

static void setup_case(model_ctx_t *c, int law, int reading, int conservative, double s1x)
{
    char msg[MSG_SIZE] = "";
    memset(c, 0, sizeof(*c));
    csfh_fmu_set_defaults(&c->fmu);
    set_by_name(&c->fmu, "contact.law", law);
    set_by_name(&c->fmu, "contact.esdu_reading", reading);
    set_by_name(&c->fmu, "flexure.conservative", conservative);
    set_by_name(&c->fmu, "body1.s1[1]", s1x);
    set_by_name(&c->fmu, "body1.s1[2]", -0.5 * s1x);
    CHECK_INT(csfh_fmu_prepare(&c->fmu, msg, sizeof(msg)), 0, "prepare");
    const double v[CSFH_N_JAC_INPUTS] = {3.0, -2.0, 0.4, 1.5, -0.7};
    memcpy(c->v, v, sizeof(v));
}

static void test_flight(void)
{
    model_ctx_t c;
    setup_case(&c, CSFH_CONTACTLAW_LN_SPHERES, 1, 0, 0.0);
    const double x[6] = {0.004, -0.006, 0.03, 0.2, -0.1, 1.5};
    memcpy(c.x, x, sizeof(x));
    check_case(&c, "flight, co-rotated");
    setup_case(&c, CSFH_CONTACTLAW_LN_SPHERES, 1, 1, 0.001);
    memcpy(c.x, x, sizeof(x));
    check_case(&c, "flight, conservative, eccentric");
}

static void test_contact(void)
{
    static const struct {
        int law, reading;
        const char *name;
    } laws[] = {{CSFH_CONTACTLAW_LN_SPHERES, 1, "LN_spheres"},
                {CSFH_CONTACTLAW_LN_CYLINDERS, 1, "LN_cylinders"},
                {CSFH_CONTACTLAW_HUNTCROSSLEY, 1, "Hunt-Crossley"},
                {CSFH_CONTACTLAW_FLORES, 1, "Flores"},
                {CSFH_CONTACTLAW_LN_ESDU, CSFH_ESDUREADING_I2, "LN_ESDU I2"},
                {CSFH_CONTACTLAW_LN_ESDU, CSFH_ESDUREADING_I3, "LN_ESDU I3"}};
    /* sliding on the friction ramp and beyond it; approaching and separating */
    const double slides[][3] = {{3e-3, 0.05, 0.2}, {-0.04, -0.03, -1.0}};
    for (size_t i = 0; i < sizeof(laws) / sizeof(laws[0]); i++) {
        for (int k = 0; k < 2; k++) {
            model_ctx_t c;
            setup_case(&c, laws[i].law, laws[i].reading, k, k ? 0.002 : 0.0);
            c.fmu.m.z.in_contact = 1;
            c.fmu.m.z.onset_speed = 0.3;
            contact_state(&c.fmu.m, 2e-5, -1.9, slides[k][1], slides[k][0], slides[k][2], c.x);
            csfh_contact_partials_t cp;
            csfh_model_contact_partials(&c.fmu.m, c.x, &cp);
            CHECK_TRUE(cp.touching && cp.F_N > 0.0 && cp.F_T != 0.0, "the case is in contact");
            CHECK_CLOSE(cp.v_T, slides[k][0], 1e-9, "the sliding speed of the case");
            check_case(&c, TFMT("contact %s, %s", laws[i].name, k ? "conservative" : "co-rotated"));
        }
    }
    /* in the contact mode with a gap (the hysteresis band): no force, the kinematics' rows */
    model_ctx_t c;
    setup_case(&c, CSFH_CONTACTLAW_LN_SPHERES, 1, 0, 0.0);
    c.fmu.m.z.in_contact = 1;
    c.fmu.m.z.onset_speed = 0.3;
    contact_state(&c.fmu.m, -1e-6, 0.7, -0.1, 0.02, 0.5, c.x);
    check_case(&c, "contact mode, open gap");
}

int main(void)
{
    test_normal_laws();
    test_friction();
    test_flight();
    test_contact();
    return TEST_SUMMARY();
}
