/* The csfh model behind the generic FMU layer (../../fmu/fmu_model.h): the physics'
 * functions on the FMU's model struct (csfh_fmu.h) and the generated variable table, the log
 * messages of contact events, the co-simulation method and the peak outputs (csfh_peaks.c). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "csfh_constants.h"
#include "csfh_fmu.h"
#include "csfh_jacobian.h"
#include "csfh_peaks.h"
#include "csfh_variables.h"
#include "fmu_model.h"

#define MODEL(p) (&((csfh_fmu_t *)(p))->m)
#define CONST_MODEL(p) (&((const csfh_fmu_t *)(p))->m)

static void set_defaults(void *f)
{
    csfh_fmu_set_defaults((csfh_fmu_t *)f);
}

static int prepare(void *f, char *msg, size_t msg_size)
{
    return csfh_fmu_prepare((csfh_fmu_t *)f, msg, msg_size);
}

static int check_start(void *f, char *msg, size_t msg_size)
{
    /* called once, at fmi2ExitInitializationMode (the glue restores the model if refused) */
    csfh_model_apply_initial_parameters(MODEL(f));
    return csfh_model_check_start(CONST_MODEL(f), msg, msg_size);
}

static void init_discrete(void *f, char *msg, size_t msg_size)
{
    csfh_model_t *m = MODEL(f);
    csfh_model_init_discrete(m);
    if (m->z.in_contact) {
        snprintf(msg, msg_size, "t = %.17g: starts in contact", m->time);
    } else if (msg_size > 0) {
        msg[0] = '\0';
    }
}

static int derivatives(void *f, double t, const double *x, double *xdot)
{
    const int status = csfh_model_derivatives(MODEL(f), t, x, xdot);
    if (status == CSFH_ERR_NONFINITE) {
        return FMU_MODEL_NONFINITE;
    }
    return status == CSFH_WARN_ESDU_CLAMPED ? FMU_MODEL_WARNING : FMU_MODEL_OK;
}

static double next_time_event(const void *f, double t)
{
    return csfh_model_next_time_event(CONST_MODEL(f), t);
}

static void event_indicators(const void *f, const double *x, double *z)
{
    z[0] = csfh_model_event_indicator(CONST_MODEL(f), x);
}

static int event_update(void *f, char *msg, size_t msg_size)
{
    csfh_model_t *m = MODEL(f);
    const int change = csfh_model_event_update(m);
    if (msg_size == 0) {
        return change; /* not logged: nothing to format */
    }
    if (change == 1) {
        snprintf(msg, msg_size, "t = %.17g: contact %d starts, onset indentation rate %g m/s",
                 m->time, m->z.contact_count, m->z.onset_speed);
    } else if (change == 2) {
        snprintf(msg, msg_size, "t = %.17g: contact ends", m->time);
    } else {
        msg[0] = '\0';
    }
    return change;
}

/* The status of outputs computed with model status `status`: the first of `values` that is not
 * finite, else the ESDU clamp's warning (messages in msg). */
static int outputs_status(const csfh_fmu_t *f, int status, const double *values, size_t n,
                          char *msg, size_t msg_size)
{
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(values[i])) {
            snprintf(msg, msg_size, "non-finite output at t = %.17g", f->m.time);
            return FMU_MODEL_NONFINITE;
        }
    }
    if (status == CSFH_WARN_ESDU_CLAMPED) {
        snprintf(msg, msg_size,
                 "indentation beyond the validity of the ESDU law (4 (R2 - R1)); the force is "
                 "held at contact.esdu_F_max = %g N",
                 f->m.d.esdu_F_max);
        return FMU_MODEL_WARNING;
    }
    return FMU_MODEL_OK;
}

/* The loads of csfh_fmu_load_outputs, as fields of csfh_outputs_t: what comm_step_begins takes
 * from the outputs (F_N, F_T, indentation, stress_max) is among them. */
#define LOAD_FIELDS(o)                                                                          \
    (o)->F_N, (o)->F_T, (o)->indentation, (o)->F_N_peak, (o)->F_T_peak, (o)->indentation_peak,  \
        (o)->stress_max, (o)->stress_location, (o)->stress_max_peak, (o)->stress_margin,        \
        (o)->pressure_max, (o)->half_width, (o)->pressure_max_peak, (o)->pressure_margin

static int outputs(void *fv, char *msg, size_t msg_size)
{
    csfh_fmu_t *f = (csfh_fmu_t *)fv;
    const int status = csfh_fmu_outputs(f);
    const csfh_outputs_t *o = &f->out;
    const double values[] = {LOAD_FIELDS(o), o->gap, o->v_T, o->indentation_rate, o->E_total,
                             o->a_frame[0], o->a_frame[1]};
    return outputs_status(f, status, values, sizeof(values) / sizeof(values[0]), msg, msg_size);
}

static int load_outputs(void *fv, char *msg, size_t msg_size)
{
    csfh_fmu_t *f = (csfh_fmu_t *)fv;
    const int status = csfh_fmu_load_outputs(f);
    const csfh_outputs_t *o = &f->out;
    const double values[] = {LOAD_FIELDS(o)};
    return outputs_status(f, status, values, sizeof(values) / sizeof(values[0]), msg, msg_size);
}

static int is_load_output(size_t offset)
{
    static const size_t loads[] = {
        offsetof(csfh_fmu_t, out.F_N),          offsetof(csfh_fmu_t, out.F_T),
        offsetof(csfh_fmu_t, out.indentation),  offsetof(csfh_fmu_t, out.F_N_peak),
        offsetof(csfh_fmu_t, out.F_T_peak),     offsetof(csfh_fmu_t, out.indentation_peak),
        offsetof(csfh_fmu_t, out.stress_max),   offsetof(csfh_fmu_t, out.stress_location),
        offsetof(csfh_fmu_t, out.stress_max_peak), offsetof(csfh_fmu_t, out.stress_margin),
        offsetof(csfh_fmu_t, out.pressure_max), offsetof(csfh_fmu_t, out.half_width),
        offsetof(csfh_fmu_t, out.pressure_max_peak), offsetof(csfh_fmu_t, out.pressure_margin)};
    for (size_t i = 0; i < sizeof(loads) / sizeof(loads[0]); i++) {
        if (offset == loads[i]) {
            return 1;
        }
    }
    return 0;
}

static int cs_method(const void *f)
{
    switch (((const csfh_fmu_t *)f)->cs_method) {
    case CSFH_SOLVERMETHOD_BDF:
        return FMU_CS_BDF;
    case CSFH_SOLVERMETHOD_ADAMS:
        return FMU_CS_ADAMS;
    case CSFH_SOLVERMETHOD_RK45:
        return FMU_CS_RK45;
    default:
        return FMU_CS_AUTO;
    }
}

/* counter += n, saturating at INT_MAX */
static void add_saturating(int *counter, long n)
{
    const long room = 0x7fffffffL - *counter;
    *counter += (int)(n < room ? n : room);
}

static void add_integrator_steps(void *fv, long steps)
{
    add_saturating(&((csfh_fmu_t *)fv)->integrator_steps, steps);
}

static void add_jacobians(void *fv, long jacobians)
{
    add_saturating(&((csfh_fmu_t *)fv)->jacobian_evaluations, jacobians);
}

static int cs_jacobian(const void *f)
{
    return ((const csfh_fmu_t *)f)->cs_analytic_jacobian;
}

/* d xdot / d x of csfh_model_derivatives (docs/model.md §15.1), column-major */
static int state_jacobian(void *f, double t, const double *x, double *J)
{
    (void)t; /* the pulse of §14.8 depends on time only */
    double dx[6][6], du[6][CSFH_N_JAC_INPUTS];
    if (csfh_model_rhs_jacobian(MODEL(f), x, dx, du) != CSFH_OK) {
        return FMU_MODEL_NONFINITE;
    }
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            J[i + 6 * j] = dx[i][j];
        }
    }
    return FMU_MODEL_OK;
}

/* Restored FMU state: the fields that are not stored table variables (checked by the glue:
 * time, states, inputs, parameters, contact.active/onset_speed/onset_time/release_*, the
 * method and the Integer twins) and not recomputed (m.d, der, out): the counts, and the running
 * peaks. */
static int check_state(const void *fv, char *msg, size_t msg_size)
{
    const csfh_fmu_t *f = (const csfh_fmu_t *)fv;
    const csfh_model_t *m = &f->m;
    const struct {
        const char *name;
        int value;
    } counts[] = {{"contact.count", m->z.contact_count},
                  {"diagnostics.rhs_evaluations", m->counters.rhs},
                  {"diagnostics.flexure_evaluations", m->counters.flexure},
                  {"diagnostics.contact_evaluations", m->counters.contact},
                  {"diagnostics.friction_evaluations", m->counters.friction},
                  {"diagnostics.integrator_steps", f->integrator_steps},
                  {"diagnostics.jacobian_evaluations", f->jacobian_evaluations}};
    for (size_t i = 0; i < sizeof(counts) / sizeof(counts[0]); i++) {
        if (counts[i].value < 0) {
            snprintf(msg, msg_size, "%s = %d is negative", counts[i].name, counts[i].value);
            return -1;
        }
    }
    if (f->peaks.active != 0 && f->peaks.active != 1) {
        snprintf(msg, msg_size, "peaks.active = %d is not 0 or 1", f->peaks.active);
        return -1;
    }
    static const char *const peak_names[CSFH_N_PEAKS] = {"contact.F_N_peak", "contact.F_T_peak",
                                                         "contact.indentation_peak",
                                                         "flexure.stress_max_peak"};
    for (int j = 0; j < CSFH_N_PEAKS; j++) {
        if (!(isfinite(f->peaks.v[j]) && f->peaks.v[j] >= 0.0)) {
            snprintf(msg, msg_size, "%s (running peak) = %g is not finite and >= 0", peak_names[j],
                     f->peaks.v[j]);
            return -1;
        }
    }
    return 0;
}

/* The partial derivatives (docs/model.md §15): the derivatives, the states (outputs too), the
 * frame's acceleration, then the outputs of csfh_model_output_jacobian (the peaks as the
 * instantaneous values they equal in model exchange; in co-simulation only the inputs are
 * knowns); with respect to the states and the inputs of CSFH_N_JAC_INPUTS. */
#define N_FIXED 14
static const struct {
    unsigned int vr;
    int row; /* CSFH_JOUT_* */
} output_rows[] = {
    {CSFH_VR_CONTACT_F_N, CSFH_JOUT_F_N},
    {CSFH_VR_CONTACT_F_T, CSFH_JOUT_F_T},
    {CSFH_VR_CONTACT_INDENTATION, CSFH_JOUT_INDENTATION},
    {CSFH_VR_CONTACT_GAP, CSFH_JOUT_GAP},
    {CSFH_VR_CONTACT_V_T, CSFH_JOUT_V_T},
    {CSFH_VR_CONTACT_INDENTATION_RATE, CSFH_JOUT_INDENTATION_RATE},
    {CSFH_VR_CONTACT_F_N_PEAK, CSFH_JOUT_F_N},
    {CSFH_VR_CONTACT_F_T_PEAK, CSFH_JOUT_F_T_ABS},
    {CSFH_VR_CONTACT_INDENTATION_PEAK, CSFH_JOUT_INDENTATION},
    {CSFH_VR_ENERGY_TOTAL, CSFH_JOUT_E_TOTAL},
    {CSFH_VR_ENERGY_KINETIC, CSFH_JOUT_E_KINETIC},
    {CSFH_VR_ENERGY_GRAVITY, CSFH_JOUT_E_GRAVITY},
    {CSFH_VR_ENERGY_FLEXURE, CSFH_JOUT_E_FLEXURE},
    {CSFH_VR_ENERGY_CONTACT, CSFH_JOUT_E_CONTACT},
    {CSFH_VR_FLEXURE_STRESS_MAX, CSFH_JOUT_STRESS_MAX},
    {CSFH_VR_FLEXURE_STRESS_LOCATION, CSFH_JOUT_STRESS_LOCATION},
    {CSFH_VR_FLEXURE_STRESS_MAX_PEAK, CSFH_JOUT_STRESS_MAX},
    {CSFH_VR_FLEXURE_STRESS_MARGIN, CSFH_JOUT_STRESS_MARGIN},
    {CSFH_VR_CONTACT_PRESSURE_MAX, CSFH_JOUT_PRESSURE_MAX},
    {CSFH_VR_CONTACT_HALF_WIDTH, CSFH_JOUT_HALF_WIDTH},
    {CSFH_VR_CONTACT_PRESSURE_MAX_PEAK, CSFH_JOUT_PRESSURE_MAX},
    {CSFH_VR_CONTACT_PRESSURE_MARGIN, CSFH_JOUT_PRESSURE_MARGIN},
};
#define N_OUTPUT_ROWS (sizeof(output_rows) / sizeof(output_rows[0]))
#define N_JAC_UNKNOWNS (N_FIXED + (int)N_OUTPUT_ROWS)
#define N_JAC_KNOWNS (6 + CSFH_N_JAC_INPUTS)

static const unsigned int jac_unknowns[N_JAC_UNKNOWNS] = {
    CSFH_VR_DER_BODY1_X, CSFH_VR_DER_BODY1_Y, CSFH_VR_DER_BODY1_THETA, CSFH_VR_DER_BODY1_VX,
    CSFH_VR_DER_BODY1_VY, CSFH_VR_DER_BODY1_OMEGA, CSFH_VR_BODY1_X, CSFH_VR_BODY1_Y,
    CSFH_VR_BODY1_THETA, CSFH_VR_BODY1_VX, CSFH_VR_BODY1_VY, CSFH_VR_BODY1_OMEGA,
    CSFH_VR_A_FRAME_1, CSFH_VR_A_FRAME_2, CSFH_VR_CONTACT_F_N, CSFH_VR_CONTACT_F_T,
    CSFH_VR_CONTACT_INDENTATION, CSFH_VR_CONTACT_GAP, CSFH_VR_CONTACT_V_T,
    CSFH_VR_CONTACT_INDENTATION_RATE, CSFH_VR_CONTACT_F_N_PEAK, CSFH_VR_CONTACT_F_T_PEAK,
    CSFH_VR_CONTACT_INDENTATION_PEAK, CSFH_VR_ENERGY_TOTAL, CSFH_VR_ENERGY_KINETIC,
    CSFH_VR_ENERGY_GRAVITY, CSFH_VR_ENERGY_FLEXURE, CSFH_VR_ENERGY_CONTACT,
    CSFH_VR_FLEXURE_STRESS_MAX, CSFH_VR_FLEXURE_STRESS_LOCATION, CSFH_VR_FLEXURE_STRESS_MAX_PEAK,
    CSFH_VR_FLEXURE_STRESS_MARGIN, CSFH_VR_CONTACT_PRESSURE_MAX, CSFH_VR_CONTACT_HALF_WIDTH,
    CSFH_VR_CONTACT_PRESSURE_MAX_PEAK, CSFH_VR_CONTACT_PRESSURE_MARGIN};
static const unsigned int jac_knowns[N_JAC_KNOWNS] = {
    CSFH_VR_BODY1_X,  CSFH_VR_BODY1_Y,  CSFH_VR_BODY1_THETA, CSFH_VR_BODY1_VX,
    CSFH_VR_BODY1_VY, CSFH_VR_BODY1_OMEGA, CSFH_VR_F_EXT_1,   CSFH_VR_F_EXT_2,
    CSFH_VR_M_EXT,    CSFH_VR_A_BASE_1, CSFH_VR_A_BASE_2};

static int jacobian(void *f, double *J)
{
    const csfh_model_t *m = MODEL(f);
    double A[6][6], B[6][CSFH_N_JAC_INPUTS], D[CSFH_N_JOUT][6];
    if (csfh_model_rhs_jacobian(m, m->x, A, B) != CSFH_OK ||
        csfh_model_output_jacobian(m, m->x, D) != CSFH_OK) {
        return FMU_MODEL_NONFINITE;
    }
    memset(J, 0, (size_t)N_JAC_UNKNOWNS * N_JAC_KNOWNS * sizeof(double));
    for (int i = 0; i < 6; i++) {
        memcpy(J + i * N_JAC_KNOWNS, A[i], sizeof(A[i]));
        memcpy(J + i * N_JAC_KNOWNS + 6, B[i], sizeof(B[i]));
        J[(6 + i) * N_JAC_KNOWNS + i] = 1.0; /* the states as outputs */
    }
    /* a_frame = a_base + pulse (docs/model.md §14.1) */
    J[12 * N_JAC_KNOWNS + 6 + 3] = J[13 * N_JAC_KNOWNS + 6 + 4] = 1.0;
    for (size_t k = 0; k < N_OUTPUT_ROWS; k++) {
        memcpy(J + (N_FIXED + (int)k) * N_JAC_KNOWNS, D[output_rows[k].row], sizeof(D[0]));
    }
    return FMU_MODEL_OK;
}

const fmu_model_t fmu_model = {
    .guid = CSFH_GUID,
    .model_identifier = CSFH_MODEL_IDENTIFIER,
    .n_states = CSFH_NUMBER_OF_STATES,
    .n_event_indicators = CSFH_NUMBER_OF_EVENT_INDICATORS,
    .n_variables = CSFH_NUMBER_OF_VARIABLES,
    .variables = csfh_variables,
    .default_tolerance = CSFH_DEFAULT_TOLERANCE,
    .size = sizeof(csfh_fmu_t),
    .time_offset = offsetof(csfh_fmu_t, m.time),
    .x_offset = offsetof(csfh_fmu_t, m.x),
    .der_offset = offsetof(csfh_fmu_t, der),
    .set_defaults = set_defaults,
    .prepare = prepare,
    .check_start = check_start,
    .init_discrete = init_discrete,
    .derivatives = derivatives,
    .next_time_event = next_time_event,
    .event_indicators = event_indicators,
    .event_update = event_update,
    .outputs = outputs,
    .subset_outputs = load_outputs,
    .in_subset = is_load_output,
    .add_integrator_steps = add_integrator_steps,
    .add_jacobians = add_jacobians,
    .cs_jacobian = cs_jacobian,
    .state_jacobian = state_jacobian,
    .cs_method = cs_method,
    .step_memory = sizeof(csfh_step_peaks_t),
    .comm_step_begins = csfh_peaks_begin,
    .analyse_step = csfh_peaks_analyse_step,
    .check_state = check_state,
    .n_jac_unknowns = N_JAC_UNKNOWNS,
    .n_jac_knowns = N_JAC_KNOWNS,
    .jac_unknowns = jac_unknowns,
    .jac_knowns = jac_knowns,
    .jacobian = jacobian,
};
