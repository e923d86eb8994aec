/* test_budget.c — decimation factors across meshes (host/budget.c, paper Eq. 3).
 *
 * Small hand-worked plans first (the arithmetic is in the comments: d_i starts at the mesh's
 * importance, is scaled so that Σ v_i d_i is the budget, clamped, renormalised), then the
 * properties on random scenes: Σ target == V_D whenever feasible, every target within its
 * bounds, and the plan is the clamp solution d_i = clamp(λ I_i, floor/v_i, 1) up to the rounding
 * to whole vertices. Then the edge cases: zero importance, D == 1, D near 0, bad arguments,
 * pinned meshes, empty lists and meshes, 10,000 meshes. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "reduce/budget.h"
#include "core/error.h"

/* Builds meshes from parallel arrays (pinned may be NULL). */
static budget_mesh *make_meshes(size_t count, const uint64_t *vertices, const double *importance,
                                const int *pinned)
{
    budget_mesh *meshes = calloc(count ? count : 1, sizeof *meshes);
    for (size_t i = 0; i < count; i++) {
        meshes[i].name = "mesh";
        meshes[i].vertices = vertices[i];
        meshes[i].importance = importance[i];
        meshes[i].pinned = pinned ? pinned[i] : 0;
    }
    return meshes;
}

/* Plans and checks the targets against the expected ones and the totals against each other. */
static void check_plan(size_t count, const uint64_t *vertices, const double *importance,
                       const int *pinned, double fraction, uint64_t min_vertices,
                       const uint64_t *expected, unsigned int expected_rounds)
{
    budget_mesh *meshes = make_meshes(count, vertices, importance, pinned);
    budget_plan plan;
    assert_int_equal(budget_distribute(meshes, count, fraction, min_vertices, &plan), 0);
    uint64_t sum = 0, before = 0;
    for (size_t i = 0; i < count; i++) {
        assert_int_equal(plan.target[i], expected[i]);
        assert_int_equal(plan.decimate[i], expected[i] < vertices[i]);
        if (vertices[i] == 0 || expected[i] == vertices[i])
            assert_true(plan.factor[i] == 1.0);
        else
            assert_true(fabs(plan.factor[i] - (double)expected[i] / (double)vertices[i]) < 1e-12);
        sum += expected[i];
        before += vertices[i];
    }
    assert_int_equal(plan.total_planned, sum);
    assert_int_equal(plan.total_before, before);
    assert_int_equal(plan.rounds, expected_rounds);
    assert_int_equal(plan.uniform_fallback, 0);
    budget_plan_free(&plan);
    assert_null(plan.target);
    free(meshes);
}

/* v = (100, 100, 200), I = (1, 1, 2), D = 0.6: V_D = 240, V_d = 100 + 100 + 400 = 600,
 * d' = (1, 1, 2) · 240/600 = (0.4, 0.4, 0.8) → targets (40, 40, 160), one round. Note that
 * importance proportional to v does not give equal factors: d_i follows the importance sum. */
static void test_worked_proportional(void **state)
{
    const uint64_t v[] = {100, 100, 200};
    const double importance[] = {1, 1, 2};
    const uint64_t expected[] = {40, 40, 160};
    check_plan(3, v, importance, NULL, 0.6, 0, expected, 1);
}

/* v = (100, 100), I = (9, 1), D = 0.6: V_D = 120, d' = 120/(900 + 100) · (9, 1) = (1.08, 0.12)
 * → the first clamps to 1 (100 vertices); round 2: 120 - 100 = 20 left, d = 20/100 = 0.2.
 * Targets (100, 20). */
static void test_worked_one_clamp(void **state)
{
    const uint64_t v[] = {100, 100};
    const double importance[] = {9, 1};
    const uint64_t expected[] = {100, 20};
    check_plan(2, v, importance, NULL, 0.6, 0, expected, 2);
}

/* v = (100, 100, 100), I = (10, 5, 1), D = 0.8: V_D = 240, V_d = 1600,
 * d' = 240/1600 · (10, 5, 1) = (1.5, 0.75, 0.15) → clamp the first; 140 left,
 * d' = 140/600 · (5, 1) = (1.1667, 0.2333) → clamp the second; 40 left → third 0.4.
 * Targets (100, 100, 40), three rounds. */
static void test_worked_clamp_chain(void **state)
{
    const uint64_t v[] = {100, 100, 100};
    const double importance[] = {10, 5, 1};
    const uint64_t expected[] = {100, 100, 40};
    check_plan(3, v, importance, NULL, 0.8, 0, expected, 3);
}

/* Largest remainder: v = 4 × 100, I = (8, 4, 2, 1), D = 0.5: V_D = 200, V_d = 1500,
 * d' = 200/1500 · (8, 4, 2, 1) = (1.067, 0.533, 0.267, 0.133) → clamp the first; 100 left,
 * d' = 100/700 · (4, 2, 1) → counts (57.14, 28.57, 14.29): floors 57 + 28 + 14 = 99, the one
 * vertex left goes to the largest remainder (.57, the second). Targets (100, 57, 29, 14). */
static void test_worked_largest_remainder(void **state)
{
    const uint64_t v[] = {100, 100, 100, 100};
    const double importance[] = {8, 4, 2, 1};
    const uint64_t expected[] = {100, 57, 29, 14};
    check_plan(4, v, importance, NULL, 0.5, 0, expected, 2);
}

/* One mesh holds all importance, floor 10: v = (1000, 100, 100), I = (1, 0, 0), D = 0.5:
 * V_D = 600; d' = (0.6, 0, 0) → counts (600, 0, 0): the two below the floor are raised to 10
 * and fixed; round 2: 580 left → first 580/1000 = 0.58. Targets (580, 10, 10). */
static void test_worked_importance_in_one_mesh(void **state)
{
    const uint64_t v[] = {1000, 100, 100};
    const double importance[] = {1, 0, 0};
    const uint64_t expected[] = {580, 10, 10};
    check_plan(3, v, importance, NULL, 0.5, 10, expected, 2);
}

/* Ceiling and floor in the same round, ceiling larger: v = 3 × 100, I = (10, 1, 0), floor 20,
 * D = 0.5: V_D = 150, d' = 150/1100 · (10, 1, 0) → counts (136.4, 13.6, 0): excess 36.4 over the
 * ceiling, deficit 6.4 + 20 = 26.4 under the floor → fix the first at 100. Round 2: 50 left,
 * d' = 50/100 · (1, 0) → (50, 0): the third goes to its floor 20. Round 3: 30 left → second 30.
 * Targets (100, 30, 20). */
static void test_worked_ceiling_before_floor(void **state)
{
    const uint64_t v[] = {100, 100, 100};
    const double importance[] = {10, 1, 0};
    const uint64_t expected[] = {100, 30, 20};
    check_plan(3, v, importance, NULL, 0.5, 20, expected, 3);
}

/* Floor larger than ceiling: v = 3 × 100, I = (3, 1, 0), floor 30, D = 0.5: V_D = 150,
 * d' = 150/400 · (3, 1, 0) → counts (112.5, 37.5, 0): excess 12.5, deficit 30 → fix the third
 * at 30. Round 2: 120 left, d' = 120/400 · (3, 1) = (0.9, 0.3) → (90, 30), in bounds.
 * Targets (90, 30, 30), Σ = 150. (Clamping the first at 100 instead would leave 50 for two
 * meshes whose floors need 60.) */
static void test_worked_floor_before_ceiling(void **state)
{
    const uint64_t v[] = {100, 100, 100};
    const double importance[] = {3, 1, 0};
    const uint64_t expected[] = {90, 30, 30};
    check_plan(3, v, importance, NULL, 0.5, 30, expected, 2);
}

/* Pinned meshes keep everything and their importance takes nothing: v = 3 × 100, the first
 * pinned with I = 1000, I = (1, 4) for the others, D = 0.5: V_D = 150, 100 fixed, 50 left,
 * d' = 50/500 · (1, 4) = (0.1, 0.4). Targets (100, 10, 40). */
static void test_worked_pinned(void **state)
{
    const uint64_t v[] = {100, 100, 100};
    const double importance[] = {1000, 1, 4};
    const int pinned[] = {1, 0, 0};
    const uint64_t expected[] = {100, 10, 40};
    check_plan(3, v, importance, pinned, 0.5, 0, expected, 1);
}

/* A mesh with v <= min_vertices is not decimated: v = (50, 1000, 1000), floor 50, I = 1 each,
 * D = 0.4: V_D = 820, 50 fixed, 770 left over 2000 → d = 0.385. Targets (50, 385, 385). */
static void test_worked_small_mesh_kept(void **state)
{
    const uint64_t v[] = {50, 1000, 1000};
    const double importance[] = {1, 1, 1};
    const uint64_t expected[] = {50, 385, 385};
    check_plan(3, v, importance, NULL, 0.4, 50, expected, 1);
}

/* Zero-importance meshes share what the important ones leave: v = (100, 100, 300),
 * I = (1, 0, 0), D = 0.8: V_D = 400, d' = (4, 0, 0) → clamp the first at 100; round 2: 300 left
 * over zero importance → equal factors 300/400 = 0.75 → (75, 225). No fallback, no warning. */
static void test_worked_zero_importance_share_leftover(void **state)
{
    const uint64_t v[] = {100, 100, 300};
    const double importance[] = {1, 0, 0};
    const uint64_t expected[] = {100, 75, 225};
    check_plan(3, v, importance, NULL, 0.8, 0, expected, 2);
}

/* A mesh with 0 vertices: target 0, factor 1, not decimated. v = (0, 100), I = (5, 1),
 * D = 0.5: V_D = 50, the empty mesh is fixed (0 <= min_vertices) → second 50. */
static void test_empty_mesh(void **state)
{
    const uint64_t v[] = {0, 100};
    const double importance[] = {5, 1};
    const uint64_t expected[] = {0, 50};
    check_plan(2, v, importance, NULL, 0.5, 0, expected, 1);

    /* Only empty meshes: nothing to plan, no NaN. */
    const uint64_t none[] = {0, 0};
    const uint64_t zero[] = {0, 0};
    check_plan(2, none, importance, NULL, 0.3, 0, zero, 0);
}

static void test_empty_list(void **state)
{
    budget_plan plan;
    assert_int_equal(budget_distribute(NULL, 0, 0.5, 10, &plan), 0);
    assert_int_equal(plan.total_before, 0);
    assert_int_equal(plan.total_requested, 0);
    assert_int_equal(plan.total_planned, 0);
    assert_int_equal(plan.rounds, 0);
    assert_int_equal(plan.uniform_fallback, 0);
    budget_plan_free(&plan);
    budget_plan_free(NULL);
}

/* D == 1: nothing decimated whatever the importance. */
static void test_fraction_one(void **state)
{
    const uint64_t v[] = {100, 5000, 7, 300};
    const double importance[] = {0, 1e9, 3, 0.5};
    check_plan(4, v, importance, NULL, 1.0, 10, v, 0);
}

/* Runs fn with stderr redirected to a file; returns what was written (caller frees). */
static char *capture_stderr(void (*fn)(void *), void *arg)
{
    char path[] = "/tmp/test_budget_stderr_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    dup2(fd, STDERR_FILENO);
    fn(arg);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    FILE *file = fdopen(fd, "r");
    fseek(file, 0, SEEK_SET);
    char *text = calloc(4096, 1);
    size_t length = fread(text, 1, 4095, file);
    text[length] = '\0';
    fclose(file);
    unlink(path);
    return text;
}

static size_t count_substrings(const char *text, const char *needle)
{
    size_t n = 0;
    for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

typedef struct distribute_call {
    const budget_mesh *meshes;
    size_t count;
    double fraction;
    uint64_t min_vertices;
    budget_plan plan;
    int result;
} distribute_call;

static void run_distribute(void *arg)
{
    distribute_call *call = arg;
    call->result = budget_distribute(call->meshes, call->count, call->fraction,
                                     call->min_vertices, &call->plan);
}

/* Zero total importance of the free meshes: uniform factors and one warning.
 * v = (100, 300, 50 pinned), I = 0, D = 0.5: V_D = 225, 50 fixed, 175 left over 400 vertices →
 * factor 0.4375 → counts (43.75, 131.25): floors 43 + 131 = 174, the last vertex to the larger
 * remainder (.75) → (44, 131). */
static void test_zero_importance_uniform(void **state)
{
    const uint64_t v[] = {100, 300, 50};
    const double importance[] = {0, 0, 7};
    const int pinned[] = {0, 0, 1};
    budget_mesh *meshes = make_meshes(3, v, importance, pinned);
    warn_silence(0);
    distribute_call call = {meshes, 3, 0.5, 0, {0}, 0};
    char *text = capture_stderr(run_distribute, &call);
    assert_int_equal(call.result, 0);
    assert_int_equal(call.plan.uniform_fallback, 1);
    assert_int_equal(call.plan.target[0], 44);
    assert_int_equal(call.plan.target[1], 131);
    assert_int_equal(call.plan.target[2], 50);
    assert_int_equal(call.plan.total_planned, 225);
    assert_int_equal(count_substrings(text, "warning"), 1);
    assert_non_null(strstr(text, "zero total importance"));
    budget_plan_free(&call.plan);
    free(text);

    /* With importance somewhere among the free meshes there is no warning. */
    meshes[1].importance = 1;
    text = capture_stderr(run_distribute, &call);
    assert_int_equal(call.result, 0);
    assert_int_equal(call.plan.uniform_fallback, 0);
    assert_int_equal(count_substrings(text, "warning"), 0);
    budget_plan_free(&call.plan);
    free(text);
    free(meshes);
}

/* D near 0 with a large pinned mesh: V_D = round(1e-6 · 101000) = 0 < 1000 pinned + 10 × 100
 * floors: infeasible, every free mesh at its floor, the pinned one untouched, and the plan says
 * it misses by 2000. */
static void test_tiny_fraction_infeasible(void **state)
{
    uint64_t v[11];
    double importance[11];
    int pinned[11] = {0};
    v[0] = 1000, importance[0] = 5, pinned[0] = 1;
    for (int i = 1; i < 11; i++)
        v[i] = 10000, importance[i] = i;
    budget_mesh *meshes = make_meshes(11, v, importance, pinned);
    budget_plan plan;
    assert_int_equal(budget_distribute(meshes, 11, 1e-6, 100, &plan), 0);
    assert_int_equal(plan.total_before, 101000);
    assert_int_equal(plan.total_requested, 0);
    assert_int_equal(plan.total_planned, 2000);
    assert_int_equal(plan.target[0], 1000);
    assert_int_equal(plan.decimate[0], 0);
    for (int i = 1; i < 11; i++) {
        assert_int_equal(plan.target[i], 100);
        assert_int_equal(plan.decimate[i], 1);
        assert_true(fabs(plan.factor[i] - 0.01) < 1e-15);
    }
    budget_plan_free(&plan);

    /* Exactly at the floors is feasible: v = (1000, 1000), floor 100, D = 0.1 → (100, 100). */
    const uint64_t v2[] = {1000, 1000};
    const double importance2[] = {1, 1000};
    const uint64_t expected[] = {100, 100};
    check_plan(2, v2, importance2, NULL, 0.1, 100, expected, 0);
    free(meshes);
}

static void expect_input_error(const budget_mesh *meshes, size_t count, double fraction,
                               const char *fragment)
{
    budget_plan plan;
    memset(&plan, 0xff, sizeof plan);
    error_clear();
    assert_int_equal(budget_distribute(meshes, count, fraction, 0, &plan), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), fragment));
    assert_null(plan.target);
    assert_null(plan.factor);
    assert_null(plan.decimate);
    budget_plan_free(&plan);
}

static void test_bad_arguments(void **state)
{
    budget_mesh meshes[2] = {{"dragon", 100, 1.0, 0}, {"bunny", 100, 2.0, 0}};
    expect_input_error(meshes, 2, 0.0, "outside (0, 1]");
    expect_input_error(meshes, 2, -0.5, "outside (0, 1]");
    expect_input_error(meshes, 2, 1.5, "outside (0, 1]");
    expect_input_error(meshes, 2, NAN, "outside (0, 1]");
    expect_input_error(meshes, 2, INFINITY, "outside (0, 1]");

    meshes[1].importance = NAN;
    expect_input_error(meshes, 2, 0.5, "'bunny'");
    meshes[1].importance = -1.0;
    expect_input_error(meshes, 2, 0.5, "'bunny' (index 1) has importance -1");
    meshes[1].importance = INFINITY;
    expect_input_error(meshes, 2, 0.5, "'bunny'");
    meshes[1].importance = 1.0;

    meshes[0].vertices = UINT64_MAX / 2 + 1;
    meshes[1].vertices = UINT64_MAX / 2 + 1;
    expect_input_error(meshes, 2, 0.5, "overflows");

    expect_input_error(NULL, 2, 0.5, "no mesh array");
    assert_int_equal(budget_distribute(meshes, 2, 0.5, 0, NULL), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* splitmix64: a small deterministic generator for the random scenes. */
static uint64_t next_random(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double random_unit(uint64_t *s) { return (double)(next_random(s) >> 11) / 9007199254740992.0; }

/* Checks every property of a plan that does not need a hand-worked answer:
 * - totals: V_D = round(D Σ v), Σ target == total_planned, == V_D if feasible, else every free
 *   mesh at its floor;
 * - per mesh: fixed meshes untouched; free ones within [floor, v]; factor = target / v in
 *   [0, 1], decimate == (target < v);
 * - the plan is the clamp solution up to whole vertices: one λ with |t_i - λ v_i w_i| <= 1 for
 *   meshes strictly inside their bounds, λ v_i w_i >= v_i - 1 at the ceiling and
 *   λ v_i w_i <= floor + 1 at the floor (w = importance, or 1 under the uniform fallback);
 *   zero-importance meshes are above their floor only when every important mesh is at its
 *   ceiling. */
static void check_properties(const budget_mesh *meshes, size_t count, double fraction,
                             uint64_t min_vertices, const budget_plan *plan)
{
    uint64_t total = 0, fixed = 0, floors = 0, planned = 0;
    double free_importance = 0.0;
    for (size_t i = 0; i < count; i++) {
        total += meshes[i].vertices;
        if (meshes[i].pinned || meshes[i].vertices <= min_vertices)
            fixed += meshes[i].vertices;
        else
            floors += min_vertices, free_importance += meshes[i].importance;
    }
    uint64_t requested = (uint64_t)llround(fraction * (double)total);
    assert_int_equal(plan->total_before, total);
    assert_int_equal(plan->total_requested, requested);
    int feasible = fixed + floors <= requested;
    int uniform = free_importance == 0.0 && fixed + floors < requested && requested < total;
    assert_int_equal(plan->uniform_fallback, uniform);

    double lambda_low = 0.0, lambda_high = INFINITY;
    int zero_above_floor = 0, important_below_ceiling = 0;
    for (size_t i = 0; i < count; i++) {
        uint64_t v = meshes[i].vertices, t = plan->target[i];
        planned += t;
        assert_true(plan->factor[i] >= 0.0 && plan->factor[i] <= 1.0);
        assert_int_equal(plan->decimate[i], t < v);
        if (v > 0)
            assert_true(fabs(plan->factor[i] - (double)t / (double)v) < 1e-12);
        else
            assert_true(plan->factor[i] == 1.0);
        if (meshes[i].pinned || v <= min_vertices) {
            assert_int_equal(t, v);
            continue;
        }
        assert_true(t >= min_vertices && t <= v);
        if (!feasible) {
            assert_int_equal(t, min_vertices);
            continue;
        }
        double w = uniform ? 1.0 : meshes[i].importance;
        if (w == 0.0) {
            zero_above_floor |= t > min_vertices;
            continue;
        }
        important_below_ceiling |= t < v;
        double weight = (double)v * w;
        if (t > min_vertices) /* not held up by the floor: λ v w >= t - 1 */
            lambda_low = fmax(lambda_low, ((double)t - 1.0) / weight);
        if (t < v) /* not held down by the ceiling: λ v w <= t + 1 */
            lambda_high = fmin(lambda_high, ((double)t + 1.0) / weight);
    }
    assert_true(lambda_low <= lambda_high * (1.0 + 1e-9));
    assert_false(zero_above_floor && important_below_ceiling);
    assert_int_equal(plan->total_planned, planned);
    if (feasible)
        assert_int_equal(planned, requested);
    else
        assert_true(planned > requested);
}

static void random_scene(uint64_t *seed, budget_mesh *meshes, size_t count, int steep)
{
    for (size_t i = 0; i < count; i++) {
        meshes[i].name = "random";
        meshes[i].vertices = 1 + next_random(seed) % 1000000;
        double kind = random_unit(seed);
        if (steep)
            meshes[i].importance = pow((double)(i + 1), 3.0);
        else if (kind < 0.25)
            meshes[i].importance = 0.0;
        else
            meshes[i].importance = pow(10.0, 12.0 * random_unit(seed) - 6.0);
        meshes[i].pinned = random_unit(seed) < 0.1;
    }
}

static void test_random_scenes(void **state)
{
    static const uint64_t floors[] = {0, 4, 100, 1000, 20000};
    uint64_t seed = 12345;
    budget_mesh meshes[64];
    size_t feasible = 0;
    warn_silence(1);
    for (int trial = 0; trial < 3000; trial++) {
        size_t count = 1 + next_random(&seed) % 64;
        random_scene(&seed, meshes, count, 0);
        if (trial % 7 == 0) /* some scenes without importance */
            for (size_t i = 0; i < count; i++)
                meshes[i].importance = 0.0;
        double fraction = trial % 11 == 0 ? 1.0 : fmax(1e-6, pow(random_unit(&seed), 2.0));
        uint64_t min_vertices = floors[next_random(&seed) % 5];
        budget_plan plan;
        assert_int_equal(budget_distribute(meshes, count, fraction, min_vertices, &plan), 0);
        check_properties(meshes, count, fraction, min_vertices, &plan);
        feasible += plan.total_planned == plan.total_requested;
        budget_plan_free(&plan);
    }
    warn_silence(0);
    assert_true(feasible > 2000); /* most random scenes must be feasible to test anything */
}

/* 10,000 meshes: random importance, and a steep one (I_i = i³) that clamps over many rounds. */
static void test_many_meshes(void **state)
{
    enum { COUNT = 10000 };
    budget_mesh *meshes = calloc(COUNT, sizeof *meshes);
    uint64_t seed = 777;
    for (int steep = 0; steep < 2; steep++) {
        random_scene(&seed, meshes, COUNT, steep);
        double fraction = steep ? 0.95 : 0.7;
        budget_plan plan;
        assert_int_equal(budget_distribute(meshes, COUNT, fraction, 50, &plan), 0);
        check_properties(meshes, COUNT, fraction, 50, &plan);
        assert_int_equal(plan.total_planned, plan.total_requested);
        size_t at_ceiling = 0, decimated = 0;
        for (size_t i = 0; i < COUNT; i++) {
            at_ceiling += !meshes[i].pinned && !plan.decimate[i];
            decimated += plan.decimate[i];
        }
        assert_true(decimated > 500);
        if (steep) /* the most important meshes clamp at 1, over several rounds */
            assert_true(plan.rounds >= 5 && at_ceiling > 1000);
        budget_plan_free(&plan);
    }
    free(meshes);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_worked_proportional),
        cmocka_unit_test(test_worked_one_clamp),
        cmocka_unit_test(test_worked_clamp_chain),
        cmocka_unit_test(test_worked_largest_remainder),
        cmocka_unit_test(test_worked_importance_in_one_mesh),
        cmocka_unit_test(test_worked_ceiling_before_floor),
        cmocka_unit_test(test_worked_floor_before_ceiling),
        cmocka_unit_test(test_worked_pinned),
        cmocka_unit_test(test_worked_small_mesh_kept),
        cmocka_unit_test(test_worked_zero_importance_share_leftover),
        cmocka_unit_test(test_empty_mesh),
        cmocka_unit_test(test_empty_list),
        cmocka_unit_test(test_fraction_one),
        cmocka_unit_test(test_zero_importance_uniform),
        cmocka_unit_test(test_tiny_fraction_infeasible),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_random_scenes),
        cmocka_unit_test(test_many_meshes),
    };
    return cmocka_run_group_tests_name("budget", tests, NULL, NULL);
}
