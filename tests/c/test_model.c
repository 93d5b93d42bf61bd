/* The model layer (csfh_model.[ch], with the FMU's variables of models/csfh/csfh_fmu.h):
 * defaults and parameter validation, the right-hand side with parts switched off (evaluation
 * counters), free fall, flexure and contact forces in the derivatives, outputs, and the event
 * indicator / event update logic of the compliant contact. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csfh_fmu.h"
#include "csfh_model.h"
#include "csfh_test.h"

#define MSG_SIZE 512

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

static void setup_default(csfh_fmu_t *fmu)
{
    char msg[MSG_SIZE] = "";
    csfh_fmu_set_defaults(fmu);
    const int rc = csfh_fmu_prepare(fmu, msg, sizeof(msg));
    if (rc != 0) {
        printf("     prepare failed: %s\n", msg);
    }
}

/* ---------------------------------------------------------------------------------------- */
static void test_defaults_prepare(void)
{
    csfh_fmu_t fmu;
    char msg[MSG_SIZE] = "";
    csfh_fmu_set_defaults(&fmu);
    /* a few start values of the `paper` preset (docs/model.md §1.1, 9) */
    CHECK_ABS(fmu.m.p.m1, 10.0, 0.0, "default body1.m = 10");
    CHECK_ABS(fmu.m.p.I1, 0.1617, 0.0, "default body1.I = 0.1617");
    CHECK_ABS(fmu.m.p.g, 9.81, 0.0, "default g = 9.81");
    CHECK_ABS(fmu.m.p.R1, 0.18, 0.0, "default R1");
    CHECK_ABS(fmu.m.p.R2, 0.20, 0.0, "default R2");
    CHECK_ABS(fmu.m.p.cr, 0.9, 0.0, "default c_r");
    CHECK_ABS(fmu.m.p.E1, 210e9, 0.0, "default E1 = 210 GPa (paper preset)");
    CHECK_ABS(fmu.m.p.beta, 5.0 * TEST_PI / 3.0, 1e-15, "default beta = 300 deg");
    CHECK_ABS(fmu.m.x[0], 0.01, 0.0, "default q0 = [0.01, 0.01, 0]: x");
    CHECK_ABS(fmu.m.x[1], 0.01, 0.0, "default q0: y");
    CHECK_INT(fmu.m.p.law, CSFH_CONTACTLAW_LN_SPHERES, "default law LN_spheres");
    CHECK_INT(fmu.m.p.esdu_reading, CSFH_ESDUREADING_I3, "default ESDU reading I3 (paper)");
    CHECK_INT(fmu.m.p.flexure_enabled, 1, "flexure on by default");
    CHECK_INT(fmu.m.p.friction_enabled, 1, "friction on by default");
    CHECK_INT(fmu.m.p.conservative, 0, "co-rotated flexure by default");

    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare succeeds with the start values");
    const double ssum = 2.0 * (1.0 - 0.09) / 210e9;
    CHECK_CLOSE(fmu.m.d.delta, 0.02, 1e-14, "delta = R2 - R1 = 0.02");
    CHECK_CLOSE(fmu.m.d.K_spheres, 4.0 / (3.0 * ssum) * sqrt(0.18 * 0.2 / 0.38), 1e-14,
                "K_spheres = Eq. 14 external with E = 210 GPa");
    CHECK_CLOSE(fmu.m.d.K_spheres, 4.7353e10, tol_digits(4.7353e10, 5), "K_spheres = 47.353 GPa m^0.5");
    CHECK_CLOSE(fmu.m.d.K_cylinders, 0.25 * TEST_PI / ssum * 0.025, 1e-14, "K_cylinders = (pi/4) E* b");
    CHECK_CLOSE(fmu.m.d.xi, 0.1425, 1e-14, "xi (LN, c_r = 0.9) = 0.1425");
    CHECK_CLOSE(fmu.m.d.esdu_F_max, 4.0 * 0.025 * 0.02 / (2.0 * 0.91 / (TEST_PI * 210e9)), 1e-13,
                "ESDU F* = 4 L dR/(sigma1 + sigma2), sigma with pi");
    CHECK_CLOSE(fmu.m.d.sbar[0], 0.292, 1e-14, "sbar_x = 0.292");
    CHECK_CLOSE(fmu.m.d.sbar[1], 0.1 - 0.072 * sqrt(3.0), 1e-13, "sbar_y = -0.0247077");
    CHECK_CLOSE(fmu.m.d.normal.K, fmu.m.d.K_spheres, 0.0, "LN_spheres uses K_spheres");
    CHECK_CLOSE(fmu.m.d.normal.n, 1.5, 0.0, "LN_spheres exponent 1.5");
    CHECK_CLOSE(fmu.m.d.flexure.K0[0][0], 3235.980, 1e-6, "K0[0][0] = 3235.980 (full compliance)");
    CHECK_CLOSE(fmu.m.d.flexure.K0[2][2], 150.6236, 1e-6, "K0[2][2] = 150.6236");

    /* K given instead of from materials (Table 2 values), and the cylinder law's exponent */
    set_by_name(&fmu, "contact.K_from_materials", 0);
    set_by_name(&fmu, "contact.law", CSFH_CONTACTLAW_LN_CYLINDERS);
    set_by_name(&fmu, "contact.n_cylinders", 1.0);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare with given K");
    CHECK_ABS(fmu.m.d.K_spheres, 47.35e9, 0.0, "K_spheres_given used");
    CHECK_ABS(fmu.m.d.K_cylinders, 2.27e9, 0.0, "K_cylinders_given used");
    CHECK_ABS(fmu.m.d.normal.K, 2.27e9, 0.0, "LN_cylinders uses K_cylinders");
    CHECK_ABS(fmu.m.d.normal.n, 1.0, 0.0, "LN_cylinders uses n_cylinders");
    /* consistent preset: internal R_eff with E = 100 GPa -> 9.8289e10 */
    csfh_fmu_set_defaults(&fmu);
    set_by_name(&fmu, "contact.E1", 100e9);
    set_by_name(&fmu, "contact.E2", 100e9);
    set_by_name(&fmu, "contact.Reff_internal", 1);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare, consistent preset");
    CHECK_CLOSE(fmu.m.d.K_spheres, 9.8289e10, tol_digits(9.8289e10, 5), "consistent: K_spheres internal = 9.8289e10");
    /* other laws select their damping factor */
    set_by_name(&fmu, "contact.law", CSFH_CONTACTLAW_FLORES);
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    CHECK_CLOSE(fmu.m.d.xi, 0.8 / 4.5, 1e-14, "Flores xi in the model");
    set_by_name(&fmu, "contact.law", CSFH_CONTACTLAW_HUNTCROSSLEY);
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    CHECK_CLOSE(fmu.m.d.xi, 0.15, 1e-14, "Hunt-Crossley xi in the model");
    set_by_name(&fmu, "contact.law", CSFH_CONTACTLAW_NONE);
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    CHECK_ABS(fmu.m.d.xi, 0.0, 0.0, "law none: xi = 0");
}

/* ---------------------------------------------------------------------------------------- */
typedef struct {
    const char *name;   /* variable to corrupt */
    double value;
    const char *named;  /* text that the message must contain (variable name) */
} bad_case_t;

/* The message must show the corrupted value after "<name> = ", readable back exactly (or as
 * nan / inf of the right sign). */
static int message_shows_value(const char *msg, const char *name, double value)
{
    char key[128];
    snprintf(key, sizeof(key), "%s = ", name);
    const char *p = strstr(msg, key);
    if (p == NULL) {
        return 0;
    }
    p += strlen(key);
    char *end = NULL;
    const double got = strtod(p, &end);
    if (end == p) {
        return 0;
    }
    return isnan(value) ? isnan(got) : got == value;
}

static void test_prepare_rejects(void)
{
    const double nan = NAN, inf = INFINITY;
    const bad_case_t cases[] = {
        {"contact.R1", 0.2, "contact.R1"}, /* R1 = R2 */
        {"contact.R1", 0.25, "contact.R1"}, /* R1 > R2 */
        {"contact.R2", 0.1, "contact.R2"}, /* R2 < R1 */
        {"contact.R1", 0.0, "contact.R1"},
        {"body1.m", 0.0, "body1.m"},
        {"body1.m", -1.0, "body1.m"},
        {"body1.I", 0.0, "body1.I"},
        {"body1.I", -0.1617, "body1.I"},
        {"contact.cr", 0.0, "contact.cr"},
        {"contact.cr", -0.1, "contact.cr"},
        {"contact.cr", 1.0000001, "contact.cr"},
        {"contact.cr", 2.0, "contact.cr"},
        {"contact.E1", 0.0, "contact.E1"},
        {"contact.E2", -210e9, "contact.E2"},
        {"flexure.E", 0.0, "flexure.E"},
        {"flexure.E", -1.0, "flexure.E"},
        {"contact.nu1", -1.0, "contact.nu1"},
        {"contact.nu1", 0.5, "contact.nu1"},
        {"contact.nu2", 0.7, "contact.nu2"},
        {"flexure.nu", 0.5, "flexure.nu"},
        {"flexure.nu", -1.5, "flexure.nu"},
        {"flexure.rho", 0.0, "flexure.rho"},
        {"flexure.rho", -0.144, "flexure.rho"},
        {"flexure.h", 0.0, "flexure.h"},
        {"flexure.h", -0.005, "flexure.h"},
        {"flexure.b", 0.0, "flexure.b"},
        {"contact.L", 0.0, "contact.L"},
        {"flexure.beta", 0.0, "flexure.beta"},
        {"flexure.beta", 2.0 * TEST_PI, "flexure.beta"},
        {"flexure.beta", 7.0, "flexure.beta"},
        {"flexure.beta", -1.0, "flexure.beta"},
        {"friction.v1", 1e-4, "friction.v1"}, /* v1 = v0 */
        {"friction.v1", 5e-5, "friction.v1"},
        {"friction.v0", 0.02, "friction.v1"}, /* v0 > v1: cross-check */
        {"friction.v0", -1e-4, "friction.v0"},
        {"friction.fd", -0.1, "friction.fd"},
        {"g", -9.81, "g ="},
        {"contact.v_min", 0.0, "contact.v_min"},
        {"contact.gap_hysteresis", 0.0, "contact.gap_hysteresis"},
        {"contact.law", 0, "contact.law"},
        {"contact.law", 7, "contact.law"},
        {"contact.esdu_reading", 0, "contact.esdu_reading"},
        {"contact.esdu_reading", 3, "contact.esdu_reading"},
        {"friction.enabled", 2, "friction.enabled"},
        {"flexure.bending_only", -1, "flexure.bending_only"},
        /* non-finite values, also in parameters without a range, states and inputs */
        {"contact.cr", nan, "contact.cr"},
        {"body1.m", inf, "body1.m"},
        {"g", -inf, "g ="},
        {"flexure.OF[1]", nan, "flexure.OF[1]"},
        {"body1.s1[2]", inf, "body1.s1[2]"},
        {"flexure.phi_root", -inf, "flexure.phi_root"},
        {"contact.K_spheres_given", inf, "contact.K_spheres_given"},
        {"body1.x", nan, "body1.x"},
        {"body1.omega", inf, "body1.omega"},
        {"F_ext[1]", nan, "F_ext[1]"},
        {"M_ext", -inf, "M_ext"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        setup_default(&fmu);
        const csfh_derived_t before = fmu.m.d;
        if (set_by_name(&fmu, cases[i].name, cases[i].value) != 0) {
            continue;
        }
        const int rc = csfh_fmu_prepare(&fmu, msg, sizeof(msg));
        CHECK_INT(rc, -1, TFMT("prepare rejects %s = %g", cases[i].name, cases[i].value));
        CHECK_STR_CONTAINS(msg, cases[i].named, TFMT("message names %s", cases[i].named));
        if (!CHECK_TRUE(message_shows_value(msg, cases[i].name, cases[i].value),
                        TFMT("message shows %s = %.17g", cases[i].name, cases[i].value))) {
            printf("     message: %s\n", msg);
        }
        CHECK_TRUE(memcmp(&before, &fmu.m.d, sizeof(before)) == 0,
                   TFMT("derived quantities unchanged after rejecting %s", cases[i].name));
        if (csfh_test_verbose()) {
            printf("     message: %s\n", msg);
        }
    }
    /* the R1 >= R2 message names both radii */
    {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        setup_default(&fmu);
        fmu.m.p.R1 = 0.2;
        csfh_fmu_prepare(&fmu, msg, sizeof(msg));
        CHECK_STR_CONTAINS(msg, "contact.R2", "R1 >= R2 message names contact.R2 too");
    }
    /* a derived quantity that overflows is named, with the parameters it comes from and their
     * values: E1 = E2 = 1e308 are each in range, but the ESDU force scale 4 L dR / sum overflows
     * (sum = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 ~ 1.8e-308) */
    {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        setup_default(&fmu);
        const csfh_derived_t before = fmu.m.d;
        fmu.m.p.E1 = 1e308;
        fmu.m.p.E2 = 1e308;
        CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), -1, "E1 = E2 = 1e308 refused");
        CHECK_STR_CONTAINS(msg, "contact.esdu_F_max = inf is not finite", "names the quantity");
        CHECK_STR_CONTAINS(msg, "contact.E1 = 1e+308", "names E1 and its value");
        CHECK_STR_CONTAINS(msg, "contact.E2 = 1e+308", "names E2 and its value");
        CHECK_STR_CONTAINS(msg, "contact.R2 = 0.2", "names R2 and its value");
        CHECK_TRUE(memcmp(&before, &fmu.m.d, sizeof(before)) == 0, "derived unchanged (overflow)");
        /* the message is cut, never overrun, in a short buffer */
        char small[40];
        memset(small, 'x', sizeof(small));
        csfh_fmu_prepare(&fmu, small, 24);
        CHECK_INT((int)strlen(small), 23, "message cut at the buffer size");
        CHECK_TRUE(small[25] == 'x', "nothing written past the buffer");
    }
    /* valid boundary values are accepted */
    const struct {
        const char *name;
        double value;
    } good[] = {
        {"contact.cr", 1.0},       {"contact.cr", 1e-6},       {"contact.nu1", 0.49},
        {"contact.nu1", -0.99},    {"flexure.nu", 0.0},        {"flexure.beta", 1e-3},
        {"flexure.beta", 6.28},    {"g", 0.0},                 {"friction.v0", 0.0},
        {"friction.fd", 0.0},      {"body1.s1[1]", -0.05},     {"flexure.phi_root", -2.0},
        {"contact.R1", 0.19999},   {"contact.law", 1},         {"contact.law", 6},
        {"contact.esdu_reading", 2}, {"F_ext[2]", -1e6},
    };
    for (size_t i = 0; i < sizeof(good) / sizeof(good[0]); i++) {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        setup_default(&fmu);
        set_by_name(&fmu, good[i].name, good[i].value);
        const int rc = csfh_fmu_prepare(&fmu, msg, sizeof(msg));
        if (!CHECK_INT(rc, 0, TFMT("prepare accepts %s = %.17g", good[i].name, good[i].value))) {
            printf("     message: %s\n", msg);
        }
    }
    /* a small message buffer is not overrun (ASan) and stays terminated */
    {
        csfh_fmu_t fmu;
        char small[8];
        setup_default(&fmu);
        fmu.m.p.cr = 5.0;
        CHECK_INT(csfh_fmu_prepare(&fmu, small, sizeof(small)), -1, "rejects with a small buffer");
        CHECK_TRUE(memchr(small, '\0', sizeof(small)) != NULL, "small message buffer terminated");
    }
}

/* ---------------------------------------------------------------------------------------- */
static void test_counters(void)
{
    /* a state in contact and sliding: gap = -1e-4, v_T != 0 */
    const double x[6] = {0.0, -0.0201, 0.0, 0.3, -0.5, 0.2};
    double xdot[6];
    for (int variant = 0; variant < 4; variant++) {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        csfh_fmu_set_defaults(&fmu);
        const char *what = "all on";
        if (variant == 1) {
            fmu.m.p.flexure_enabled = 0;
            what = "flexure off";
        } else if (variant == 2) {
            fmu.m.p.friction_enabled = 0;
            what = "friction off";
        } else if (variant == 3) {
            fmu.m.p.law = CSFH_CONTACTLAW_NONE;
            what = "law none";
        }
        CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, TFMT("prepare (%s)", what));
        memcpy(fmu.m.x, x, sizeof(x));
        fmu.m.z.in_contact = 1; /* the contact mode the event update sets (the force acts in it only) */
        fmu.m.z.onset_speed = 0.5;
        for (int k = 0; k < 5; k++) {
            CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, x, xdot), CSFH_OK, TFMT("derivatives OK (%s)", what));
        }
        csfh_fmu_outputs(&fmu);
        CHECK_INT(fmu.m.counters.rhs, 5, TFMT("rhs counter = 5 (%s)", what));
        CHECK_INT(fmu.m.counters.flexure, variant == 1 ? 0 : 6, TFMT("flexure counter (%s)", what));
        CHECK_INT(fmu.m.counters.contact, variant == 3 ? 0 : 6, TFMT("contact counter (%s)", what));
        CHECK_INT(fmu.m.counters.friction, (variant == 2 || variant == 3) ? 0 : 6,
                  TFMT("friction counter (%s)", what));
        if (variant == 3) {
            CHECK_ABS(fmu.out.F_N, 0.0, 0.0, "law none: no normal force even inside the gap");
            CHECK_ABS(fmu.out.F_T, 0.0, 0.0, "law none: no friction force");
        }
        if (variant == 2) {
            CHECK_TRUE(fmu.out.F_N > 0.0, "friction off: normal force present");
            CHECK_ABS(fmu.out.F_T, 0.0, 0.0, "friction off: F_T = 0");
        }
    }
    /* counters saturate instead of overflowing (UBSan) */
    csfh_fmu_t fmu;
    setup_default(&fmu);
    fmu.m.counters.rhs = 2147483647;
    csfh_model_derivatives(&fmu.m, fmu.m.time, x, xdot);
    CHECK_INT(fmu.m.counters.rhs, 2147483647, "rhs counter saturates at INT_MAX");
}

/* ---------------------------------------------------------------------------------------- */
static void test_derivatives(void)
{
    char msg[MSG_SIZE] = "";
    csfh_fmu_t fmu;
    double xdot[6];

    /* first free-fall derivatives of the default start state, flexure off: [v, -g] */
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.flexure_enabled = 0;
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    csfh_model_init_discrete(&fmu.m);
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, fmu.m.x, xdot), CSFH_OK, "free fall: OK");
    const double ff[6] = {0.0, 0.0, 0.0, 0.0, -9.81, 0.0};
    for (int i = 0; i < 6; i++) {
        CHECK_ABS(xdot[i], ff[i], 0.0, TFMT("free fall from the start state: xdot[%d]", i));
    }
    /* moving, rotated, out of contact, with inputs */
    const double x1[6] = {0.005, 0.01, 0.1, 0.3, -0.2, 0.5};
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, x1, xdot), CSFH_OK, "free flight: OK");
    const double exp1[6] = {0.3, -0.2, 0.5, 0.0, -9.81, 0.0};
    for (int i = 0; i < 6; i++) {
        CHECK_ABS(xdot[i], exp1[i], 0.0, TFMT("free flight: xdot[%d] = [v, 0, -g, 0]", i));
    }
    fmu.m.u_in[0] = 1.0;
    fmu.m.u_in[1] = 2.0;
    fmu.m.u_in[2] = 0.3;
    csfh_model_derivatives(&fmu.m, fmu.m.time, x1, xdot);
    CHECK_CLOSE(xdot[3], 0.1, 1e-15, "input F_ext[1]/m");
    CHECK_CLOSE(xdot[4], -9.81 + 0.2, 1e-15, "input (F_ext[2] - m g)/m");
    CHECK_CLOSE(xdot[5], 0.3 / 0.1617, 1e-15, "input M_ext/I");
    fmu.m.u_in[0] = fmu.m.u_in[1] = fmu.m.u_in[2] = 0.0;
    /* non-finite derivatives -> CSFH_ERR_NONFINITE (the contract is on the derivatives: a NaN
     * velocity is one; a NaN position with flexure off and no contact yields finite ones) */
    const double xbad[6] = {0.0, 0.0, 0.0, NAN, 0.0, 0.0};
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, xbad, xdot), CSFH_ERR_NONFINITE, "NaN velocity -> error");
    const double xinf[6] = {0.0, 0.0, 0.0, 0.0, 0.0, INFINITY};
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, xinf, xdot), CSFH_ERR_NONFINITE, "Inf angular velocity -> error");
    fmu.m.p.flexure_enabled = 1;
    const double xbad2[6] = {NAN, 0.0, 0.0, 0.0, 0.0, 0.0};
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, xbad2, xdot), CSFH_ERR_NONFINITE, "NaN position with flexure -> error");
    fmu.m.p.flexure_enabled = 0;

    /* flexure at q0 = [0.01, 0.01, 0] (out of contact): Q_e/M with docs/model.md §2.4's numbers */
    csfh_fmu_set_defaults(&fmu);
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    csfh_model_init_discrete(&fmu.m);
    CHECK_INT(fmu.m.z.in_contact, 0, "q0 starts out of contact");
    csfh_model_derivatives(&fmu.m, fmu.m.time, fmu.m.x, xdot);
    CHECK_ABS(xdot[3] * 10.0, -38.914, 0.505e-3, "flexure: m xdot_vx = Q_e,x = -38.914");
    CHECK_ABS(xdot[4] * 10.0 + 98.1, -46.482, 0.505e-3, "flexure: m (xdot_vy + g) = Q_e,y = -46.482");
    /* moment: the reference used the rounded Table-1 sbar (see test_flexure): bound 1.5e-4 N m */
    CHECK_ABS(xdot[5] * 0.1617, -4.6926, 0.505e-4 + 1.5e-4, "flexure: I xdot_omega = Q_e,theta ~ -4.6926");

    /* contact, central, flexure off: F_N = K rho^1.5 (1 + xi rhodot/rhodot0) along +Y */
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.flexure_enabled = 0;
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    const double ssum = 2.0 * (1.0 - 0.09) / 210e9;
    const double K = 4.0 / (3.0 * ssum) * sqrt(0.18 * 0.2 / 0.38);
    const double rho = 1e-5, v = 0.5;
    const double delta = fmu.m.d.delta;
    double x2[6] = {0.0, -(delta + rho), 0.0, 0.0, -v, 0.0};
    /* not yet in contact mode (a state the integrator probes before it located the onset): the
     * relation gap < 0 is frozen between events, so only gravity acts */
    CHECK_INT(csfh_model_derivatives(&fmu.m, fmu.m.time, x2, xdot), CSFH_OK, "contact: OK");
    CHECK_CLOSE(xdot[4], -9.81, 1e-12, "probe before the event: no contact force (frozen mode)");
    /* the contact by the gap (the paper's fixed-step RK4): the force acts wherever the gap is
     * negative, with the state's own rate as the onset rate */
    CHECK_INT(csfh_model_derivatives_by_gap(&fmu.m, fmu.m.time, x2, xdot), CSFH_OK,
              "contact by gap: OK");
    const double FN1 = K * pow(rho, 1.5) * (1.0 + 0.1425);
    CHECK_CLOSE(xdot[4], (FN1 - 98.1) / 10.0, 1e-9, "contact by gap: F_N = K rho^1.5 (1 + xi)");
    CHECK_ABS(xdot[3], 0.0, 1e-12, "central contact: no horizontal force");
    CHECK_ABS(xdot[5], 0.0, 1e-12, "central contact: no moment");
    /* in contact mode with the onset speed captured at the event */
    fmu.m.z.in_contact = 1;
    fmu.m.z.onset_speed = 2.0;
    csfh_model_derivatives(&fmu.m, fmu.m.time, x2, xdot);
    const double FN2 = K * pow(rho, 1.5) * (1.0 + 0.1425 * v / 2.0);
    CHECK_CLOSE(xdot[4], (FN2 - 98.1) / 10.0, 1e-9, "contact mode: F_N uses the stored onset speed");
    /* sliding to +X at the bottom: v_T = -0.3, friction +f_d F_N along t_c = [-1, 0];
     * moment a x F_T t_c = -R1 f_d F_N */
    x2[3] = 0.3;
    csfh_model_derivatives(&fmu.m, fmu.m.time, x2, xdot);
    CHECK_CLOSE(xdot[3], -0.055 * FN2 / 10.0, 1e-9, "sliding: friction opposes the motion");
    CHECK_CLOSE(xdot[5], -0.18 * 0.055 * FN2 / 0.1617, 1e-9, "sliding: friction moment -R1 f_d F_N");
    CHECK_CLOSE(xdot[4], (FN2 - 98.1) / 10.0, 1e-9, "sliding: normal force unchanged");
    /* outputs at this state */
    memcpy(fmu.m.x, x2, sizeof(x2));
    CHECK_INT(csfh_fmu_outputs(&fmu), CSFH_OK, "outputs OK");
    CHECK_CLOSE(fmu.out.F_N, FN2, 1e-12, "output F_N");
    CHECK_CLOSE(fmu.out.F_T, 0.055 * FN2, 1e-12, "output F_T");
    CHECK_CLOSE(fmu.out.gap, -rho, 1e-9, "output gap");
    CHECK_CLOSE(fmu.out.indentation, rho, 1e-9, "output indentation");
    CHECK_CLOSE(fmu.out.indentation_rate, v, 1e-14, "output indentation rate");
    CHECK_CLOSE(fmu.out.v_T, -0.3, 1e-14, "output v_T");
    CHECK_CLOSE(fmu.out.E_kinetic, 0.5 * 10.0 * (0.09 + 0.25), 1e-14, "output kinetic energy");
    CHECK_CLOSE(fmu.out.E_gravity, 10.0 * 9.81 * x2[1], 1e-14, "output gravity energy m g y");
    CHECK_CLOSE(fmu.out.E_contact, K * pow(rho, 2.5) / 2.5, 1e-9, "output contact energy K rho^2.5/2.5");
    CHECK_ABS(fmu.out.E_flexure, 0.0, 0.0, "flexure off: no flexure energy");
    CHECK_CLOSE(fmu.out.E_total, fmu.out.E_kinetic + fmu.out.E_gravity + fmu.out.E_contact, 1e-14, "total energy");
}

/* ---------------------------------------------------------------------------------------- */
static double own_gap(const csfh_model_t *m, const double x[6])
{
    const double c = cos(x[2]), s = sin(x[2]);
    const double ex = x[0] + c * m->p.s1bar[0] - s * m->p.s1bar[1];
    const double ey = x[1] + s * m->p.s1bar[0] + c * m->p.s1bar[1];
    return (m->p.R2 - m->p.R1) - sqrt(ex * ex + ey * ey);
}

static void test_events(void)
{
    char msg[MSG_SIZE] = "";
    csfh_fmu_t fmu;
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.flexure_enabled = 0;
    fmu.m.p.gap_hysteresis = 1e-6;
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    const double eps = 1e-6, delta = fmu.m.d.delta;

    /* out of contact: z = gap */
    const double xa[6] = {0.0, 0.01, 0.0, 0.1, -0.7, 0.3};
    memcpy(fmu.m.x, xa, sizeof(xa));
    csfh_model_init_discrete(&fmu.m);
    CHECK_INT(fmu.m.z.in_contact, 0, "start out of contact");
    CHECK_INT(fmu.m.z.contact_count, 0, "no contacts yet");
    CHECK_ABS(csfh_model_event_indicator(&fmu.m, fmu.m.x), own_gap(&fmu.m, fmu.m.x), 1e-17, "out of contact: z = gap");
    CHECK_INT(csfh_model_event_update(&fmu.m), 0, "no mode change with gap > eps");

    /* onset at gap <= 0: the indentation rate is captured */
    const double xb[6] = {0.0, -(delta + 1e-9), 0.0, 0.1, -0.7, 0.3};
    memcpy(fmu.m.x, xb, sizeof(xb));
    CHECK_TRUE(csfh_model_event_indicator(&fmu.m, fmu.m.x) < 0.0, "indicator negative after crossing");
    CHECK_INT(csfh_model_event_update(&fmu.m), 1, "onset at gap <= 0");
    CHECK_INT(fmu.m.z.in_contact, 1, "in contact after the onset");
    CHECK_INT(fmu.m.z.contact_count, 1, "contact count 1");
    CHECK_CLOSE(fmu.m.z.onset_speed, 0.7, 1e-13, "onset speed = indentation rate -gamma_N = 0.7");
    CHECK_ABS(csfh_model_event_indicator(&fmu.m, fmu.m.x), own_gap(&fmu.m, fmu.m.x) - 2.0 * eps, 1e-17,
              "in contact: z = gap - 2 eps");
    CHECK_TRUE(csfh_model_event_indicator(&fmu.m, fmu.m.x) <= -2.0 * eps, "indicator away from 0 after onset");
    CHECK_INT(csfh_model_event_update(&fmu.m), 0, "no change at the same state");
    /* still in contact for gap in (0, eps) */
    const double xc[6] = {0.0, -(delta - 0.5 * eps), 0.0, 0.0, 0.7, 0.0};
    memcpy(fmu.m.x, xc, sizeof(xc));
    CHECK_INT(csfh_model_event_update(&fmu.m), 0, "no release for 0 < gap < eps");
    CHECK_INT(fmu.m.z.in_contact, 1, "still in contact");
    /* release when gap >= eps; indicator crosses 0 at gap = 2 eps */
    const double xd[6] = {0.0, -(delta - 2.0 * eps), 0.0, 0.0, 0.7, 0.0};
    memcpy(fmu.m.x, xd, sizeof(xd));
    CHECK_ABS(csfh_model_event_indicator(&fmu.m, fmu.m.x), 0.0, 1e-15, "release indicator zero at gap = 2 eps");
    CHECK_INT(csfh_model_event_update(&fmu.m), 2, "release at gap >= eps");
    CHECK_INT(fmu.m.z.in_contact, 0, "out of contact after release");
    CHECK_ABS(csfh_model_event_indicator(&fmu.m, fmu.m.x), own_gap(&fmu.m, fmu.m.x), 1e-17, "after release: z = gap");
    CHECK_TRUE(csfh_model_event_indicator(&fmu.m, fmu.m.x) >= 1.9 * eps, "indicator away from 0 after release");
    CHECK_CLOSE(fmu.m.z.onset_speed, 0.7, 1e-13, "onset speed kept after release (last contact)");
    /* second onset counts */
    memcpy(fmu.m.x, xb, sizeof(xb));
    fmu.m.x[4] = -0.2;
    CHECK_INT(csfh_model_event_update(&fmu.m), 1, "second onset");
    CHECK_INT(fmu.m.z.contact_count, 2, "contact count 2");
    CHECK_CLOSE(fmu.m.z.onset_speed, 0.2, 1e-13, "second onset speed 0.2");

    /* eccentric O1 (s1bar != 0), rotating: onset speed = -dg/dt along the velocity (FD) */
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.flexure_enabled = 0;
    fmu.m.p.s1bar[0] = 0.01;
    fmu.m.p.s1bar[1] = -0.004;
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    {
        const double th = 0.4, ang = -2.0;
        const double c = cos(th), s = sin(th);
        const double s1[2] = {c * 0.01 + s * 0.004, s * 0.01 - c * 0.004};
        const double r = fmu.m.d.delta + 1e-8;
        const double x[6] = {r * cos(ang) - s1[0], r * sin(ang) - s1[1], th, 0.2, -0.6, 1.5};
        memcpy(fmu.m.x, x, sizeof(x));
        CHECK_INT(csfh_model_event_update(&fmu.m), 1, "eccentric: onset");
        const double h = 1e-7;
        double xp[6], xm[6];
        for (int i = 0; i < 3; i++) {
            xp[i] = x[i] + h * x[3 + i];
            xm[i] = x[i] - h * x[3 + i];
        }
        const double gdot = (own_gap(&fmu.m, xp) - own_gap(&fmu.m, xm)) / (2.0 * h);
        CHECK_ABS(fmu.m.z.onset_speed, -gdot, 1e-8, "eccentric: onset speed = -dg/dt (FD)");
    }

    /* initial state inside the contact -> contact mode from the start */
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.flexure_enabled = 0;
    csfh_fmu_prepare(&fmu, msg, sizeof(msg));
    memcpy(fmu.m.x, xb, sizeof(xb));
    csfh_model_init_discrete(&fmu.m);
    CHECK_INT(fmu.m.z.in_contact, 1, "init inside the gap: contact mode");
    CHECK_INT(fmu.m.z.contact_count, 1, "init inside the gap: count 1");

    /* law none: constant indicator, no mode changes */
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.law = CSFH_CONTACTLAW_NONE;
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare law none");
    const double *states[3] = {xa, xb, xd};
    double z0 = csfh_model_event_indicator(&fmu.m, xa);
    for (int k = 0; k < 3; k++) {
        memcpy(fmu.m.x, states[k], 6 * sizeof(double));
        if (k == 0) {
            csfh_model_init_discrete(&fmu.m);
        }
        CHECK_ABS(csfh_model_event_indicator(&fmu.m, fmu.m.x), z0, 0.0, TFMT("law none: indicator constant (%d)", k));
        CHECK_INT(csfh_model_event_update(&fmu.m), 0, TFMT("law none: no mode change (%d)", k));
        CHECK_INT(fmu.m.z.in_contact, 0, TFMT("law none: never in contact (%d)", k));
        CHECK_INT(fmu.m.z.contact_count, 0, TFMT("law none: no contacts counted (%d)", k));
    }
    CHECK_TRUE(z0 > 0.0, "law none: indicator positive");
}

/* ---------------------------------------------------------------------------------------- */
/* energy balance of the whole right-hand side (docs/model.md §7.5): c_r = 1, no friction, the
 * conservative flexure (fixed K0) and gravity; own fixed-step RK4 through several impacts.
 * The total energy output (kinetic + gravity + flexure + contact) must be conserved. */
static void rk4_step(csfh_model_t *m, double *x, double h)
{
    /* fixed steps that do not locate the onset: the force acts by the gap (the paper's RK4) */
    double k1[6], k2[6], k3[6], k4[6], xt[6];
    csfh_model_derivatives_by_gap(m, m->time, x, k1);
    for (int i = 0; i < 6; i++) {
        xt[i] = x[i] + 0.5 * h * k1[i];
    }
    csfh_model_derivatives_by_gap(m, m->time, xt, k2);
    for (int i = 0; i < 6; i++) {
        xt[i] = x[i] + 0.5 * h * k2[i];
    }
    csfh_model_derivatives_by_gap(m, m->time, xt, k3);
    for (int i = 0; i < 6; i++) {
        xt[i] = x[i] + h * k3[i];
    }
    csfh_model_derivatives_by_gap(m, m->time, xt, k4);
    for (int i = 0; i < 6; i++) {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/* max |E_total - E0| over 0.3 s with step h; returns the number of contact onsets */
static double energy_drift(int flex, double h, int *contacts, double *E0_out)
{
    char msg[MSG_SIZE] = "";
    csfh_fmu_t fmu;
    csfh_fmu_set_defaults(&fmu);
    fmu.m.p.cr = 1.0;
    fmu.m.p.friction_enabled = 0;
    fmu.m.p.flexure_enabled = flex;
    fmu.m.p.conservative = 1;
    if (!flex) { /* docs/model.md §7.5: q0 = [0, 0.01, 0], u0 = [0.3, 0, 0.5] */
        const double x0[6] = {0.0, 0.01, 0.0, 0.3, 0.0, 0.5};
        memcpy(fmu.m.x, x0, sizeof(x0));
    }
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare (energy test)");
    csfh_model_init_discrete(&fmu.m);
    csfh_model_outputs_by_gap(&fmu.m, &fmu.out);
    const double E0 = fmu.out.E_total;
    double dEmax = 0.0;
    double z = csfh_model_event_indicator(&fmu.m, fmu.m.x);
    const int n = (int)(0.3 / h + 0.5);
    for (int k = 0; k < n; k++) {
        rk4_step(&fmu.m, fmu.m.x, h);
        const double znew = csfh_model_event_indicator(&fmu.m, fmu.m.x);
        if ((z > 0.0) != (znew > 0.0)) {
            csfh_model_event_update(&fmu.m); /* mode bookkeeping only: xi = 0 at c_r = 1 */
        }
        z = csfh_model_event_indicator(&fmu.m, fmu.m.x);
        if (k % 50 == 0) {
            csfh_model_outputs_by_gap(&fmu.m, &fmu.out);
            dEmax = fmax(dEmax, fabs(fmu.out.E_total - E0));
        }
    }
    *contacts = fmu.m.z.contact_count;
    *E0_out = E0;
    return dEmax;
}

static void test_energy_conservation(void)
{
    for (int flex = 0; flex <= 1; flex++) {
        int c1, c2;
        double E0;
        const double d1 = energy_drift(flex, 1e-6, &c1, &E0);
        const double d2 = energy_drift(flex, 5e-7, &c2, &E0);
        if (!flex) {
            CHECK_CLOSE(E0, 1.4512, tol_digits(1.4512, 5), "docs/model.md §7.5: E0 = 1.4512 J");
        }
        CHECK_TRUE(c1 >= 2 && c1 == c2,
                   TFMT("energy test goes through impacts (flexure %d: %d contacts)", flex, c2));
        CHECK_TRUE(d2 <= 1e-7 * E0,
                   TFMT("c_r = 1, no friction, conservative flexure %d: |E - E0| = %.2e J of %.4f J",
                        flex, d2, E0));
        CHECK_TRUE(d2 < 0.25 * d1,
                   TFMT("energy error converges with the step (flexure %d: %.2e -> %.2e)", flex, d1, d2));
    }
}

/* ---------------------------------------------------------------------------------------- */
/* the start-state check, the peak quantities, the Integer twins of the Enumerations */
static void test_start_check_peaks_and_numbers(void)
{
    csfh_fmu_t fmu;
    char msg[MSG_SIZE] = "";
    setup_default(&fmu);
    CHECK_INT(csfh_model_check_start(&fmu.m, msg, sizeof(msg)), 0, "default start accepted");
    /* q0 = [0.05, 0, 0]: |e| = 0.05, delta = 0.02: 0.03 m deep (docs/model.md §3) */
    fmu.m.x[0] = 0.05;
    fmu.m.x[1] = 0.0;
    CHECK_INT(csfh_model_check_start(&fmu.m, msg, sizeof(msg)), -1, "0.03 m deep refused");
    CHECK_STR_CONTAINS(msg, "body1.x = 0.05 m, body1.y = 0 m, body1.theta = 0 rad", "names the state");
    CHECK_STR_CONTAINS(msg, "contact.indentation = 0.03 m", "names the indentation");
    fmu.m.p.max_initial_indentation = 0.031;
    CHECK_INT(csfh_model_check_start(&fmu.m, msg, sizeof(msg)), 0, "accepted under a larger limit");
    fmu.m.p.law = CSFH_CONTACTLAW_NONE;
    fmu.m.p.max_initial_indentation = 1e-3;
    CHECK_INT(csfh_model_check_start(&fmu.m, msg, sizeof(msg)), 0, "no check without a contact law");

    /* peak quantities: zero and unevaluated in flight; F_N, |F_T|, rho in contact */
    setup_default(&fmu);
    double v[CSFH_N_PEAKS] = {1, 1, 1};
    const double x[6] = {0.0, -0.02 - 5e-5, 0.0, 0.3, -0.1, 0.0};
    fmu.m.z.in_contact = 0;
    const int contacts = fmu.m.counters.contact;
    CHECK_INT(csfh_model_peak_values(&fmu.m, x, v), 0, "flight: nothing to track");
    CHECK_TRUE(v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0, "flight: zeros");
    CHECK_INT(fmu.m.counters.contact, contacts, "flight: no contact evaluation");
    fmu.m.z.in_contact = 1;
    fmu.m.z.onset_speed = 0.1;
    CHECK_INT(csfh_model_peak_values(&fmu.m, x, v), 1, "contact: tracked");
    csfh_contact_eval_t c;
    csfh_model_contact(&fmu.m, x, x + 3, &c);
    CHECK_ABS(v[0], c.F_N, 0.0, "peak quantity 0 is F_N");
    CHECK_ABS(v[1], fabs(c.F_T), 0.0, "peak quantity 1 is |F_T|");
    CHECK_ABS(v[2], 5e-5, 1e-15, "peak quantity 2 is the indentation");
    CHECK_TRUE(c.F_N > 0.0 && c.F_T != 0.0, "in contact and sliding");

    /* NAME_number, when not 0, sets the Enumeration in prepare */
    csfh_fmu_set_defaults(&fmu);
    set_by_name(&fmu, "contact.law_number", CSFH_CONTACTLAW_LN_CYLINDERS);
    set_by_name(&fmu, "solver.method_number", CSFH_SOLVERMETHOD_RK45);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "prepare with the numbers");
    CHECK_INT(fmu.m.p.law, CSFH_CONTACTLAW_LN_CYLINDERS, "contact.law set by its number");
    CHECK_INT(fmu.cs_method, CSFH_SOLVERMETHOD_RK45, "solver.method set by its number");
    CHECK_ABS(fmu.m.d.normal.K, fmu.m.d.K_cylinders, 0.0, "the cylinder stiffness is in use");
    set_by_name(&fmu, "contact.law_number", 7);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), -1, "law number 7 refused");
    CHECK_STR_CONTAINS(msg, "contact.law_number", "names the number");
}

/* ---------------------------------------------------------------------------------------- */
/* Each law's force in the model at one state (docs/model.md §4.1-4.4): the stiffness the law uses
 * (spheres for LN_spheres, Hunt-Crossley and Flores; cylinders for LN_cylinders), computed here
 * from the materials (Eq. 14 external radius, Eq. 16 times L), and its damping factor (4.6):
 * F_N = K rho^n (1 + xi rho'/rho'-) at the bottom of the bore, in contact mode. */
static void test_each_law_uses_its_stiffness(void)
{
    const double E = 210e9, nu = 0.3, R1 = 0.18, R2 = 0.20, L = 0.025, cr = 0.9;
    const double sigma = (1.0 - nu * nu) / E;
    const double K_sph = 4.0 / (3.0 * 2.0 * sigma) * sqrt(R1 * R2 / (R1 + R2));
    const double K_cyl = 0.25 * TEST_PI / (2.0 * sigma) * L;
    const struct {
        int law;
        const char *name;
        double K, xi;
    } cases[] = {
        {CSFH_CONTACTLAW_LN_SPHERES, "LN_spheres", K_sph, 0.75 * (1.0 - cr * cr)},
        {CSFH_CONTACTLAW_LN_CYLINDERS, "LN_cylinders", K_cyl, 0.75 * (1.0 - cr * cr)},
        {CSFH_CONTACTLAW_HUNTCROSSLEY, "HuntCrossley", K_sph, 1.5 * (1.0 - cr)},
        {CSFH_CONTACTLAW_FLORES, "Flores", K_sph, 8.0 * (1.0 - cr) / (5.0 * cr)},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        csfh_fmu_t fmu;
        char msg[MSG_SIZE] = "";
        csfh_fmu_set_defaults(&fmu);
        fmu.m.p.law = cases[i].law;
        fmu.m.p.flexure_enabled = 0;
        fmu.m.p.friction_enabled = 0;
        CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, TFMT("%s: prepare", cases[i].name));
        CHECK_CLOSE(fmu.m.d.normal.K, cases[i].K, 1e-13, TFMT("%s: stiffness in use", cases[i].name));
        const double rho = 2e-5, v = 0.4, onset = 0.8;
        const double delta = fmu.m.d.delta;
        const double x[6] = {0.0, -(delta + rho), 0.0, 0.0, -v, 0.0};
        const double rho_seen = (delta + rho) - delta; /* the rounding of delta + rho */
        fmu.m.z.in_contact = 1;
        fmu.m.z.onset_speed = onset;
        csfh_contact_eval_t c;
        csfh_model_contact(&fmu.m, x, x + 3, &c);
        CHECK_CLOSE(c.F_N, cases[i].K * pow(rho_seen, 1.5) * (1.0 + cases[i].xi * v / onset), 1e-12,
                    TFMT("%s: F_N = K rho^1.5 (1 + xi rho'/rho'-)", cases[i].name));
    }
}

/* ---------------------------------------------------------------------------------------- */
/* base acceleration (docs/model.md §14.1) and the stress outputs (§14.2-14.5) */
static void test_base_acceleration_and_stresses(void)
{
    csfh_fmu_t fmu, f;
    setup_default(&fmu);
    /* a state in contact, sliding, with the flexure loaded */
    const double x[6] = {0.5 * 0.02005, -0.8660254 * 0.02005, 0.01, 0.05, -0.02, 0.3};
    fmu.m.z.in_contact = 1;
    fmu.m.z.onset_speed = 0.5;
    double ref[6], xdot[6], xf[6];
    csfh_model_derivatives(&fmu.m, fmu.m.time, x, ref);
    /* a_base = 0 (the default) is bitwise the model without it: the values of a model whose
     * a_base was never touched, and x - 0 = x in every sum */
    CHECK_TRUE(fmu.m.a_base[0] == 0.0 && fmu.m.a_base[1] == 0.0, "a_base starts at 0");
    /* body 1 feels -m1 a_base at G1: bitwise the same as F_ext = -m1 a_base */
    f = fmu;
    fmu.m.a_base[0] = 3000.0;
    fmu.m.a_base[1] = -1234.5;
    f.m.u_in[0] = -fmu.m.p.m1 * fmu.m.a_base[0];
    f.m.u_in[1] = -fmu.m.p.m1 * fmu.m.a_base[1];
    csfh_model_derivatives(&fmu.m, fmu.m.time, x, xdot);
    csfh_model_derivatives(&f.m, f.m.time, x, xf);
    CHECK_TRUE(memcmp(xdot, xf, sizeof(xdot)) == 0, "a_base is bitwise F_ext = -m1 a_base");
    CHECK_CLOSE(xdot[3], ref[3] - 3000.0, 1e-12, "a_base[1] decelerates body 1 along X");
    CHECK_CLOSE(xdot[4], ref[4] + 1234.5, 1e-12, "a_base[2] < 0 accelerates body 1 along +Y");
    CHECK_ABS(xdot[5], ref[5], 0.0, "the d'Alembert force acts at G1: no moment");
    /* the same smooth forces serve the Moreau stepper and the RK4 baseline */
    double Q[3];
    csfh_model_smooth_forces(&fmu.m, fmu.m.time, x, Q);
    double Q0[3];
    fmu.m.a_base[0] = fmu.m.a_base[1] = 0.0;
    csfh_model_smooth_forces(&fmu.m, fmu.m.time, x, Q0);
    CHECK_CLOSE(Q[0], Q0[0] - fmu.m.p.m1 * 3000.0, 1e-14, "smooth forces: -m1 a_base, X");
    CHECK_CLOSE(Q[1], Q0[1] + fmu.m.p.m1 * 1234.5, 1e-14, "smooth forces: -m1 a_base, Y");
    csfh_model_derivatives(&fmu.m, fmu.m.time, x, xdot);
    CHECK_TRUE(memcmp(xdot, ref, sizeof(xdot)) == 0, "a_base back to 0: bitwise as before");

    /* outputs: stresses at the state, the pure functions' values */
    fmu.m.time = 0.0;
    memcpy(fmu.m.x, x, sizeof(fmu.m.x));
    const int rhs_before = fmu.m.counters.rhs;
    csfh_fmu_outputs(&fmu);
    CHECK_INT(fmu.m.counters.rhs, rhs_before, "outputs evaluate no right-hand side");
    double w[3], loc = -1.0;
    csfh_flexure_tip_wrench(&fmu.m.d.flexure, x, w);
    const double sigma = csfh_arc_stress_max(&fmu.m.d.arc, w, &loc);
    CHECK_ABS(fmu.out.stress_max, sigma, 0.0, "flexure.stress_max from the tip wrench");
    CHECK_ABS(fmu.out.stress_location, loc, 0.0, "flexure.stress_location");
    CHECK_TRUE(fmu.out.stress_max > 0.0, "the flexure is loaded");
    const double E_star = 1.0 / (2.0 * (1.0 - 0.3 * 0.3) / 210e9), Rc = 0.18 * 0.2 / 0.02;
    const double p0 = sqrt(fmu.out.F_N * E_star / (TEST_PI * 0.025 * Rc));
    CHECK_TRUE(fmu.out.F_N > 0.0, "in contact");
    CHECK_CLOSE(fmu.out.pressure_max, p0, 1e-14, "contact.pressure_max = sqrt(F_N E*/(pi L R'))");
    CHECK_CLOSE(fmu.out.half_width, 2.0 * fmu.out.F_N / (TEST_PI * p0 * 0.025), 1e-14,
                "contact.half_width = 2 F_N/(pi p0 L)");
    CHECK_ABS(fmu.out.stress_max_peak, fmu.out.stress_max, 0.0, "no step: the peak is the value");
    CHECK_ABS(fmu.out.pressure_max_peak, fmu.out.pressure_max, 0.0, "no step: the peak is the value");
    CHECK_CLOSE(fmu.out.stress_margin, 1.0 - sigma / fmu.m.p.stress_allowable, 1e-15,
                "flexure.stress_margin = 1 - sigma/allowable");
    CHECK_CLOSE(fmu.out.pressure_margin, 1.0 - p0 / fmu.m.p.pressure_allowable, 1e-14,
                "contact.pressure_margin = 1 - p0/allowable");
    /* peaks over a step: the contact ones always, the flexure stress only when tracked */
    fmu.peaks.active = 1;
    fmu.peaks.v[0] = 4.0 * fmu.out.F_N;
    fmu.peaks.v[3] = 3.0 * sigma;
    csfh_fmu_outputs(&fmu);
    CHECK_CLOSE(fmu.out.pressure_max_peak, 2.0 * p0, 1e-14, "pressure peak = p0(F_N_peak)");
    CHECK_ABS(fmu.out.stress_max_peak, sigma, 0.0, "untracked stress peak: the value");
    fmu.m.p.track_stress_peak = 1;
    csfh_fmu_outputs(&fmu);
    CHECK_ABS(fmu.out.stress_max_peak, 3.0 * sigma, 0.0, "tracked stress peak");
    CHECK_CLOSE(fmu.out.stress_margin, 1.0 - 3.0 * sigma / fmu.m.p.stress_allowable, 1e-15,
                "the margin of the peak");
    double v[CSFH_N_PEAKS];
    fmu.m.z.in_contact = 0;
    CHECK_INT(csfh_model_peak_values(&fmu.m, x, v), 1, "tracked stress: evaluated in flight too");
    CHECK_ABS(v[3], sigma, 0.0, "peak quantity 3 is the flexure stress");
    fmu.peaks.active = 0;
    fmu.m.p.track_stress_peak = 0;
    /* zero stress: finite margins of 1; flexure off: no stress, no flexure evaluation */
    setup_default(&fmu);
    fmu.m.p.flexure_enabled = 0;
    const double x0[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    memcpy(fmu.m.x, x0, sizeof(fmu.m.x));
    const int flex_before = fmu.m.counters.flexure;
    csfh_fmu_outputs(&fmu);
    CHECK_INT(fmu.m.counters.flexure, flex_before, "flexure off: never evaluated");
    CHECK_ABS(fmu.out.stress_max, 0.0, 0.0, "flexure off: no stress");
    CHECK_ABS(fmu.out.pressure_max, 0.0, 0.0, "out of contact: no pressure");
    CHECK_ABS(fmu.out.half_width, 0.0, 0.0, "out of contact: no strip");
    CHECK_ABS(fmu.out.stress_margin, 1.0, 0.0, "zero stress: margin 1");
    CHECK_ABS(fmu.out.pressure_margin, 1.0, 0.0, "zero pressure: margin 1");
}

/* ---------------------------------------------------------------------------------------- */
/* the shock pulse (docs/model.md §14.8): a half-sine of the frame's acceleration in time */
static void test_shock_pulse(void)
{
    /* the pure pulse: zero outside [t0, t0 + T], A at the middle, sin elsewhere */
    const double A = 1500.0 * 9.80665, T = 5e-4, t0 = 2e-4;
    CHECK_ABS(csfh_half_sine(A, T, t0, t0 - 1e-9), 0.0, 0.0, "before the pulse: 0");
    CHECK_ABS(csfh_half_sine(A, T, t0, t0 + T + 1e-9), 0.0, 0.0, "after the pulse: 0");
    CHECK_CLOSE(csfh_half_sine(A, T, t0, t0 + 0.5 * T), A, 1e-15, "the middle: the peak");
    CHECK_CLOSE(csfh_half_sine(A, T, t0, t0 + 0.25 * T), A * sqrt(0.5), 1e-14, "a quarter in");
    /* its integral, the velocity change 2 A T / pi, by the composite Simpson rule */
    const int n = 2000;
    double sum = 0.0;
    for (int i = 0; i <= n; i++) {
        const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * csfh_half_sine(A, T, t0, t0 + T * i / n);
    }
    CHECK_CLOSE(sum * T / n / 3.0, 2.0 * A * T / TEST_PI, 1e-12, "integral = 2 A T / pi");

    /* in the model: -m1 a(t) along shock.angle at G1, on top of a_base; no moment */
    csfh_fmu_t fmu, ref;
    setup_default(&fmu);
    set_by_name(&fmu, "shock.peak", A);
    set_by_name(&fmu, "shock.duration", T);
    set_by_name(&fmu, "shock.start", t0);
    set_by_name(&fmu, "shock.angle", 2.0); /* rad */
    char msg[MSG_SIZE] = "";
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), 0, "a pulse prepares");
    setup_default(&ref);
    const double x[6] = {0.001, -0.002, 0.01, 0.05, -0.02, 0.3};
    double xdot[6], xref[6];
    const double t = t0 + 0.3 * T, a = A * sin(TEST_PI * 0.3);
    csfh_model_derivatives(&fmu.m, t, x, xdot);
    csfh_model_derivatives(&ref.m, t, x, xref);
    CHECK_CLOSE(xdot[3], xref[3] - a * cos(2.0), 1e-12, "pulse: X acceleration -a cos(angle)");
    CHECK_CLOSE(xdot[4], xref[4] - a * sin(2.0), 1e-12, "pulse: Y acceleration -a sin(angle)");
    CHECK_ABS(xdot[5], xref[5], 0.0, "pulse: no moment");
    /* the integrator's time decides, not the model's: m->time is not read */
    fmu.m.time = t0 + 0.5 * T;
    double again[6];
    csfh_model_derivatives(&fmu.m, t, x, again);
    CHECK_TRUE(memcmp(xdot, again, sizeof(xdot)) == 0, "the RHS takes the time it is given");
    /* outside the pulse: bitwise the model without one */
    csfh_model_derivatives(&fmu.m, t0 + T + 1e-6, x, xdot);
    csfh_model_derivatives(&ref.m, t0 + T + 1e-6, x, xref);
    CHECK_TRUE(memcmp(xdot, xref, sizeof(xdot)) == 0, "after the pulse: bitwise no pulse");
    /* with a_base: the frame's acceleration output is their sum */
    fmu.m.a_base[0] = 10.0;
    fmu.m.a_base[1] = -20.0;
    double af[2];
    csfh_model_frame_acceleration(&fmu.m, t, af);
    CHECK_CLOSE(af[0], 10.0 + a * cos(2.0), 1e-14, "a_frame[1] = a_base[1] + pulse");
    CHECK_CLOSE(af[1], -20.0 + a * sin(2.0), 1e-14, "a_frame[2] = a_base[2] + pulse");
    fmu.m.time = t;
    memcpy(fmu.m.x, x, sizeof(fmu.m.x));
    csfh_fmu_outputs(&fmu);
    CHECK_ABS(fmu.out.a_frame[0], af[0], 0.0, "output a_frame[1] at the model's time");
    CHECK_ABS(fmu.out.a_frame[1], af[1], 0.0, "output a_frame[2] at the model's time");
    /* time events: the start, then the end, then none */
    CHECK_ABS(csfh_model_next_time_event(&fmu.m, 0.0), t0, 0.0, "next time event: the start");
    CHECK_ABS(csfh_model_next_time_event(&fmu.m, t0), t0 + T, 0.0, "at the start: the end");
    CHECK_ABS(csfh_model_next_time_event(&fmu.m, t), t0 + T, 0.0, "inside: the end");
    CHECK_TRUE(isinf(csfh_model_next_time_event(&fmu.m, t0 + T)), "at the end: none");
    CHECK_TRUE(isinf(csfh_model_next_time_event(&ref.m, 0.0)), "no pulse: no time event");
    /* bad pulse parameters are refused, naming the variable */
    setup_default(&fmu);
    set_by_name(&fmu, "shock.duration", -1e-4);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), -1, "negative duration refused");
    CHECK_STR_CONTAINS(msg, "shock.duration", "names shock.duration");
    setup_default(&fmu);
    set_by_name(&fmu, "shock.peak", -1.0);
    CHECK_INT(csfh_fmu_prepare(&fmu, msg, sizeof(msg)), -1, "negative peak refused");
    CHECK_STR_CONTAINS(msg, "shock.peak", "names shock.peak");
}

int main(void)
{
    test_defaults_prepare();
    test_prepare_rejects();
    test_counters();
    test_derivatives();
    test_events();
    test_energy_conservation();
    test_start_check_peaks_and_numbers();
    test_each_law_uses_its_stiffness();
    test_base_acceleration_and_stresses();
    test_shock_pulse();
    return TEST_SUMMARY();
}
