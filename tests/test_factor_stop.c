/* test_factor_stop.c — the stop rule of the importance pass on the decimation factors
 * (host/reduce/factor_stop.c): the factor and ranking changes against hand-worked values, the
 * rule's counting of calm checkpoints, and the rule on a synthetic series: Monte Carlo estimates
 * of three meshes' importance (true value × a noisy factor per iteration), planned by Eq. 3
 * (budget.c) at every checkpoint as `idmr reduce` does. It must stop, on a checkpoint, and with
 * a plan close to the plan of the true importance; a series whose importance keeps drifting
 * must not stop. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "idmr/rng.h"
#include "reduce/budget.h"
#include "reduce/factor_stop.h"

static void test_factor_change_worked(void **state)
{
    (void)state;
    const uint64_t before[] = {100, 50, 0}, after[] = {90, 60, 0};
    /* |90 - 100| + |60 - 50| = 20 vertices moved, of the 150 planned before. */
    assert_float_equal(factor_change(before, after, 3), 20.0 / 150.0, 1e-15);
    assert_float_equal(factor_change(after, after, 3), 0.0, 0.0);
    const uint64_t none[] = {0, 0};
    assert_float_equal(factor_change(none, before, 2), 0.0, 0.0);
}

/* The ranking change of two value lists: each ranked (mean_ranks), then compared. */
static double change_of(const double *before, const double *after, size_t n)
{
    double rank_before[8], rank_after[8];
    assert_true(n <= 8);
    mean_ranks(before, n, rank_before);
    mean_ranks(after, n, rank_after);
    return ranking_change(rank_before, rank_after, n);
}

static void test_ranking_change_worked(void **state)
{
    (void)state;
    const double a[] = {1, 2, 3, 4, 5}, swapped[] = {2, 1, 4, 3, 5}, reversed[] = {5, 4, 3, 2, 1};
    assert_float_equal(change_of(a, a, 5), 0.0, 1e-15);
    /* ρ = 1 - 6 Σd² / (n (n² - 1)) = 1 - 6 · 4 / 120 = 0.8 */
    assert_float_equal(change_of(a, swapped, 5), 0.2, 1e-12);
    assert_float_equal(change_of(a, reversed, 5), 2.0, 1e-12);
    /* Ties take their mean rank: (1.5, 1.5, 3, 4) against (1.5, 1.5, 4, 3); about the mean 2.5
     * the products sum to 3.5 and the squares to 4.5 each: ρ = 7/9. */
    const double tied[] = {0, 0, 1, 2}, tied_swapped[] = {0, 0, 2, 1};
    double ranks[4];
    mean_ranks(tied_swapped, 4, ranks);
    assert_float_equal(ranks[0], 1.5, 0.0);
    assert_float_equal(ranks[1], 1.5, 0.0);
    assert_float_equal(ranks[2], 4.0, 0.0);
    assert_float_equal(ranks[3], 3.0, 0.0);
    assert_float_equal(change_of(tied, tied_swapped, 4), 2.0 / 9.0, 1e-12);
    /* Monotone maps keep the ranks. */
    const double squared[] = {1, 4, 9, 16, 25};
    assert_float_equal(change_of(a, squared, 5), 0.0, 1e-15);
    /* No order to compare: constant lists, fewer than two values. */
    const double flat[] = {3, 3, 3, 3, 3};
    assert_float_equal(change_of(a, flat, 5), 0.0, 0.0);
    assert_float_equal(change_of(a, a, 1), 0.0, 0.0);
}

static void test_rule_counts_calm_checkpoints(void **state)
{
    (void)state;
    factor_stop rule = {.tolerance = 0.01};
    assert_false(factor_stop_update(&rule, -1, -1)); /* the first: nothing to compare */
    assert_false(factor_stop_update(&rule, 0.005, 0));
    assert_false(factor_stop_update(&rule, 0.02, 0)); /* a jump starts the count again */
    assert_false(factor_stop_update(&rule, 0.005, 0));
    assert_true(factor_stop_update(&rule, 0.009, 0));
    assert_int_equal(rule.checkpoints, 5);

    factor_stop off = {.tolerance = 0};
    for (int k = 0; k < 10; k++)
        assert_false(factor_stop_update(&off, 0, 0));

    /* With a ranking tolerance, calm factors alone do not stop the pass. */
    factor_stop ranked = {.tolerance = 0.01, .ranking_tolerance = 0.01};
    assert_false(factor_stop_update(&ranked, 0, 0.05));
    assert_false(factor_stop_update(&ranked, 0, 0.05));
    assert_false(factor_stop_update(&ranked, 0, 0.005));
    assert_true(factor_stop_update(&ranked, 0, 0.005));
}

enum { MESHES = 3, CAP = 400 };
static const uint64_t VERTICES[MESHES] = {20000, 5000, 60000};
static const double TRUE_IMPORTANCE[MESHES] = {3.0, 1.0, 0.2};

static void plan(const double *importance, budget_plan *out)
{
    budget_mesh meshes[MESHES];
    for (int m = 0; m < MESHES; m++)
        meshes[m] = (budget_mesh){"mesh", VERTICES[m], importance[m], 0, 0};
    assert_int_equal(budget_distribute(meshes, MESHES, 0.1, 16, out), 0);
}

/* Runs the rule over a synthetic pass: per iteration each mesh adds its importance (times
 * `drift`^n, 1: none) times a noisy factor (mean 1, ±100 %); returns the iteration it stopped
 * at (0: never), with the plan there in *stopped_plan. */
static unsigned int run_series(double drift, uint64_t *stopped_plan)
{
    idmr_rng rng = idmr_rng_init(7, 0, 0, 0);
    double sums[MESHES] = {0};
    uint64_t previous[MESHES];
    int have_previous = 0;
    factor_stop rule = {.tolerance = FACTOR_STOP_TOLERANCE};
    for (unsigned int n = 1; n <= CAP; n++) {
        for (int m = 0; m < MESHES; m++)
            sums[m] += TRUE_IMPORTANCE[m] * pow(drift, n) * 2.0 * idmr_rng_float(&rng);
        if (n % FACTOR_STOP_EVERY)
            continue;
        budget_plan p;
        plan(sums, &p);
        double change = have_previous ? factor_change(previous, p.target, MESHES) : -1.0;
        for (int m = 0; m < MESHES; m++)
            previous[m] = stopped_plan[m] = p.target[m];
        have_previous = 1;
        budget_plan_free(&p);
        if (factor_stop_update(&rule, change, -1.0))
            return n;
    }
    return 0;
}

static void test_rule_on_a_converging_series(void **state)
{
    (void)state;
    uint64_t at_stop[MESHES];
    unsigned int n = run_series(1.0, at_stop);
    assert_true(n > 0);
    assert_int_equal(n % FACTOR_STOP_EVERY, 0);
    assert_true(n >= FACTOR_STOP_EVERY * (FACTOR_STOP_CALM + 1));
    budget_plan truth;
    plan(TRUE_IMPORTANCE, &truth);
    /* Where it stopped, the plan is within a few tolerances of the plan of the true importance
     * (the remaining error of the estimate is larger than one checkpoint's change). */
    double off = factor_change(truth.target, at_stop, MESHES);
    budget_plan_free(&truth);
    print_message("stopped after %u iterations; plan %.4f of the budget off the true plan\n", n,
                  off);
    assert_true(off < 5 * FACTOR_STOP_TOLERANCE);
}

static void test_rule_waits_for_a_drifting_series(void **state)
{
    (void)state;
    uint64_t at_stop[MESHES];
    unsigned int steady = run_series(1.0, at_stop);
    /* A series whose later iterations count ever more (5 % more each) is dominated by its last
     * few iterations: its estimate stays about as noisy as a few iterations' worth, so the plan
     * keeps moving, and the rule stops later than on the steady series, if at all. */
    unsigned int drifting = run_series(1.05, at_stop);
    print_message("steady series stopped at %u, drifting series at %u\n", steady, drifting);
    assert_true(drifting == 0 || drifting > steady);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_factor_change_worked),
        cmocka_unit_test(test_ranking_change_worked),
        cmocka_unit_test(test_rule_counts_calm_checkpoints),
        cmocka_unit_test(test_rule_on_a_converging_series),
        cmocka_unit_test(test_rule_waits_for_a_drifting_series),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
