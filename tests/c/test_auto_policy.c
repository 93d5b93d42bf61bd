/* The `auto` policy of co-simulation (fmu_src/fmu/cosim/auto_policy.c) on windows made up here:
 * a trial of the stiff integrator when the non-stiff one's steps fail or sit at its stability
 * limit, the unmeasured start-up window, keeping the stiff integrator where its steps are longer
 * than AUTO_BDF_COST x the non-stiff ones, going back otherwise with a doubling hold-off, and no
 * decision before a window is complete. */
#include <string.h>

#include "auto_policy.h"
#include "csfh_test.h"

static cs_auto_window_t window(int stiff_method, double failed, double stiff, double mean_h)
{
    const cs_auto_window_t w = {stiff_method ? "BDF" : "RK45", stiff_method, 100, failed, stiff,
                                mean_h};
    return w;
}

static void test_trial_starts_where_the_nonstiff_integrator_struggles(void)
{
    const cs_counts_t zero = {0, 0, 0, 0};
    cs_auto_t a;
    cs_auto_segment(&a, &zero, 0.0);
    char why[256];
    cs_auto_window_t w = window(0, 0.01, 0.1, 1e-4);
    CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_KEEP, "smooth: keep RK45");
    CHECK_INT((int)strlen(why), 0, "nothing to say");
    w = window(0, 0.06, 0.1, 1e-4);
    CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_STIFF,
              "6 % of the steps failed: try BDF");
    CHECK_STR_CONTAINS(why, "auto: trying BDF (6 % of RK45's steps failed", "the reason");
    CHECK_INT(a.trial, 1, "on trial, starting up");
    CHECK_CLOSE(a.nonstiff_h, 1e-4, 0.0, "RK45's mean step kept for the comparison");
    cs_auto_segment(&a, &zero, 0.0);
    w = window(0, 0.0, 0.6, 1e-4);
    CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_STIFF,
              "60 % at the stability limit: try BDF");
}

static void test_stiff_integrator_is_kept_only_where_its_steps_are_longer(void)
{
    const cs_counts_t zero = {0, 0, 0, 0};
    cs_auto_t a;
    char why[256];
    cs_auto_segment(&a, &zero, 0.0);
    cs_auto_window_t w = window(0, 0.1, 0.0, 1e-4);
    cs_auto_decide(&a, &w, "RK45", why, sizeof why);
    w = window(1, 0.0, 0.0, 1e-2);
    CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_KEEP, "start-up window");
    CHECK_INT(a.trial, 2, "the next window is measured");
    CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_KEEP,
              "BDF's steps 100x longer: kept");
    CHECK_STR_CONTAINS(why, "auto: BDF kept", "the reason");
    CHECK_INT(a.trial, 0, "the trial is over");
    /* trials that fail: back to RK45, with 1, 2, 4, ... 64 windows before the next trial */
    int waiting = 0;
    for (int round = 0; round < 8; round++) {
        w = window(0, 0.1, 0.0, 1e-4);
        for (int k = 0; k < waiting; k++) {
            CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_KEEP,
                      TFMT("round %d: held off", round));
        }
        CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_STIFF,
                  TFMT("round %d: a trial after the hold-off", round));
        w = window(1, 0.0, 0.0, 1.5e-4);
        cs_auto_decide(&a, &w, "RK45", why, sizeof why);
        CHECK_INT(cs_auto_decide(&a, &w, "RK45", why, sizeof why), CS_AUTO_NONSTIFF,
                  TFMT("round %d: BDF's steps only 1.5x longer: back to RK45", round));
        CHECK_STR_CONTAINS(why, "auto: back to RK45", "the reason");
        CHECK_INT(a.holdoff, round < 7 ? 1 << round : 64,
                  TFMT("round %d: the hold-off doubles up to 64", round));
        waiting = a.holdoff;
    }
}

static void test_no_decision_before_a_window_is_complete(void)
{
    const cs_counts_t zero = {0, 0, 0, 0};
    cs_auto_t a;
    char why[256];
    cs_auto_segment(&a, &zero, 0.0);
    const cs_counts_t some = {99, 50, 50, 0};
    CHECK_INT(cs_auto_step_end(&a, &some, 1e-2, "RK45", 0, "RK45", why, sizeof why),
              CS_AUTO_KEEP, "99 steps: no decision, whatever they were");
    CHECK_INT((int)a.at.steps, 0, "the window goes on");
    const cs_counts_t window_done = {100, 50, 0, 0};
    CHECK_INT(cs_auto_step_end(&a, &window_done, 1e-2, "RK45", 0, "RK45", why, sizeof why),
              CS_AUTO_STIFF, "100 steps, half of them failed: try BDF");
    CHECK_CLOSE(a.nonstiff_h, 1e-4, 1e-15, "the mean step: the window's time over its steps");
    CHECK_INT((int)a.at.steps, 100, "a new window starts");
}

int main(void)
{
    test_trial_starts_where_the_nonstiff_integrator_struggles();
    test_stiff_integrator_is_kept_only_where_its_steps_are_longer();
    test_no_decision_before_a_window_is_complete();
    return TEST_SUMMARY();
}
