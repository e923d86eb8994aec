/* test_budget.c — decimation factors across meshes (host/reduce/budget.c, paper Eq. 3).
 *
 * Small hand-worked plans first, one table row each (the arithmetic is in the comments: d_i
 * starts at the mesh's importance, is scaled so that Σ v_i d_i is the budget, clamped,
 * renormalised), then the properties on random scenes: Σ target == V_D whenever feasible, every
 * target within its bounds, and the plan is the clamp solution d_i = clamp(λ I_i, floor/v_i, 1) up
 * to the rounding to whole vertices. Then the edge cases: zero importance, D near 0, bad
 * arguments, empty lists, 10,000 meshes. Random scenes come from the project's counter-based
 * generator (idmr/rng.h), one stream per scene. */
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

#include "core/error.h"
#include "idmr/rng.h"
#include "reduce/budget.h"

/* Builds meshes from parallel arrays (pinned and own_floor may be NULL). */
static budget_mesh *make_meshes(size_t count, const uint64_t *vertices, const double *importance,
                                const int *pinned, const uint64_t *own_floor)
{
    budget_mesh *meshes = calloc(count ? count : 1, sizeof *meshes);
    for (size_t i = 0; i < count; i++) {
        meshes[i].name = "mesh";
        meshes[i].vertices = vertices[i];
        meshes[i].importance = importance[i];
        meshes[i].pinned = pinned ? pinned[i] : 0;
        meshes[i].floor = own_floor ? own_floor[i] : 0;
    }
    return meshes;
}

/* ---- hand-worked plans ---- */

#define MAX_CASE_MESHES 4

/* One plan worked out on paper: the meshes, D, the floor, and the targets and rounds expected;
 * own_floor (the meshes' own floors) is last so most rows leave it zero. */
typedef struct worked_case {
    const char *name;
    size_t count;
    uint64_t vertices[MAX_CASE_MESHES];
    double importance[MAX_CASE_MESHES];
    int pinned[MAX_CASE_MESHES];
    double fraction;
    uint64_t min_vertices;
    uint64_t expected[MAX_CASE_MESHES];
    unsigned int rounds;
    uint64_t own_floor[MAX_CASE_MESHES];
} worked_case;

static const worked_case worked_cases[] = {
    /* v = (100, 100, 200), I = (1, 1, 2), D = 0.6: V_D = 240, V_d = 100 + 100 + 400 = 600,
     * d' = (1, 1, 2) · 240/600 = (0.4, 0.4, 0.8) → targets (40, 40, 160), one round. Note that
     * importance proportional to v does not give equal factors: d_i follows the importance sum. */
    {"worked: proportional", 3, {100, 100, 200}, {1, 1, 2}, {0}, 0.6, 0, {40, 40, 160}, 1, {0}},
    /* v = (100, 100), I = (9, 1), D = 0.6: V_D = 120, d' = 120/(900 + 100) · (9, 1) = (1.08, 0.12)
     * → the first clamps to 1 (100 vertices); round 2: 120 - 100 = 20 left, d = 20/100 = 0.2. */
    {"worked: one clamp", 2, {100, 100}, {9, 1}, {0}, 0.6, 0, {100, 20}, 2, {0}},
    /* v = (100, 100, 100), I = (10, 5, 1), D = 0.8: V_D = 240, V_d = 1600,
     * d' = 240/1600 · (10, 5, 1) = (1.5, 0.75, 0.15) → clamp the first; 140 left,
     * d' = 140/600 · (5, 1) = (1.1667, 0.2333) → clamp the second; 40 left → third 0.4. */
    {"worked: clamp chain", 3, {100, 100, 100}, {10, 5, 1}, {0}, 0.8, 0, {100, 100, 40}, 3, {0}},
    /* Largest remainder: v = 4 × 100, I = (8, 4, 2, 1), D = 0.5: V_D = 200, V_d = 1500,
     * d' = 200/1500 · (8, 4, 2, 1) = (1.067, 0.533, 0.267, 0.133) → clamp the first; 100 left,
     * d' = 100/700 · (4, 2, 1) → counts (57.14, 28.57, 14.29): floors 57 + 28 + 14 = 99, the one
     * vertex left goes to the largest remainder (.57, the second). */
    {"worked: largest remainder", 4, {100, 100, 100, 100}, {8, 4, 2, 1}, {0}, 0.5, 0,
     {100, 57, 29, 14}, 2, {0}},
    /* One mesh holds all importance, floor 10: v = (1000, 100, 100), I = (1, 0, 0), D = 0.5:
     * V_D = 600; d' = (0.6, 0, 0) → counts (600, 0, 0): the two below the floor are raised to 10
     * and fixed; round 2: 580 left → first 580/1000 = 0.58. */
    {"worked: importance in one mesh", 3, {1000, 100, 100}, {1, 0, 0}, {0}, 0.5, 10,
     {580, 10, 10}, 2, {0}},
    /* Ceiling and floor in the same round, ceiling larger: v = 3 × 100, I = (10, 1, 0), floor 20,
     * D = 0.5: V_D = 150, d' = 150/1100 · (10, 1, 0) → counts (136.4, 13.6, 0): excess 36.4 over
     * the ceiling, deficit 6.4 + 20 = 26.4 under the floor → fix the first at 100. Round 2: 50
     * left, d' = 50/100 · (1, 0) → (50, 0): the third goes to its floor 20. Round 3: 30 left →
     * second 30. */
    {"worked: ceiling before floor", 3, {100, 100, 100}, {10, 1, 0}, {0}, 0.5, 20,
     {100, 30, 20}, 3, {0}},
    /* Floor larger than ceiling: v = 3 × 100, I = (3, 1, 0), floor 30, D = 0.5: V_D = 150,
     * d' = 150/400 · (3, 1, 0) → counts (112.5, 37.5, 0): excess 12.5, deficit 30 → fix the third
     * at 30. Round 2: 120 left, d' = 120/400 · (3, 1) = (0.9, 0.3) → (90, 30), in bounds; Σ = 150.
     * (Clamping the first at 100 instead would leave 50 for two meshes whose floors need 60.) */
    {"worked: floor before ceiling", 3, {100, 100, 100}, {3, 1, 0}, {0}, 0.5, 30, {90, 30, 30}, 2,
     {0}},
    /* Pinned meshes keep everything and their importance takes nothing: v = 3 × 100, the first
     * pinned with I = 1000, I = (1, 4) for the others, D = 0.5: V_D = 150, 100 fixed, 50 left,
     * d' = 50/500 · (1, 4) = (0.1, 0.4). */
    {"worked: pinned", 3, {100, 100, 100}, {1000, 1, 4}, {1, 0, 0}, 0.5, 0, {100, 10, 40}, 1, {0}},
    /* A mesh with v <= min_vertices is not decimated: v = (50, 1000, 1000), floor 50, I = 1 each,
     * D = 0.4: V_D = 820, 50 fixed, 770 left over 2000 → d = 0.385. */
    {"worked: small mesh kept", 3, {50, 1000, 1000}, {1, 1, 1}, {0}, 0.4, 50, {50, 385, 385}, 1,
     {0}},
    /* Zero-importance meshes share what the important ones leave: v = (100, 100, 300),
     * I = (1, 0, 0), D = 0.8: V_D = 400, d' = (4, 0, 0) → clamp the first at 100; round 2: 300
     * left over zero importance → equal factors 300/400 = 0.75 → (75, 225). No fallback. */
    {"worked: zero importance shares the leftover", 3, {100, 100, 300}, {1, 0, 0}, {0}, 0.8, 0,
     {100, 75, 225}, 2, {0}},
    /* A mesh with 0 vertices: target 0, factor 1, not decimated. v = (0, 100), I = (5, 1),
     * D = 0.5: V_D = 50, the empty mesh is fixed (0 <= min_vertices) → second 50. */
    {"worked: empty mesh", 2, {0, 100}, {5, 1}, {0}, 0.5, 0, {0, 50}, 1, {0}},
    /* Only empty meshes: nothing to plan, no NaN. */
    {"worked: only empty meshes", 2, {0, 0}, {5, 1}, {0}, 0.3, 0, {0, 0}, 0, {0}},
    /* D == 1: nothing decimated whatever the importance. */
    {"worked: fraction one", 4, {100, 5000, 7, 300}, {0, 1e9, 3, 0.5}, {0}, 1.0, 10,
     {100, 5000, 7, 300}, 0, {0}},
    /* Exactly at the floors is feasible: v = (1000, 1000), floor 100, D = 0.1 → (100, 100). */
    {"worked: exactly at the floors", 2, {1000, 1000}, {1, 1000}, {0}, 0.1, 100, {100, 100}, 0,
     {0}},
    /* A mesh's own floor (what a decimation found it cannot go below) gives the budget it cannot
     * use to the others by importance: v = 3 × 100, I = (1, 1, 2), own floors (60, 0, 0), D = 0.5:
     * V_D = 150, d' = 150/400 · (1, 1, 2) → counts (37.5, 37.5, 75): the first is under its
     * floor → fixed at 60. Round 2: 90 left, d' = 90/300 · (1, 2) = (0.3, 0.6) → (30, 60). */
    {"worked: own floor", 3, {100, 100, 100}, {1, 1, 2}, {0}, 0.5, 0, {60, 30, 60}, 2,
     {60, 0, 0}},
    /* An own floor at the mesh's count fixes it like a pinned mesh: v = (100, 100), own floors
     * (100, 0), D = 0.75: V_D = 150, 100 fixed → second 50. */
    {"worked: own floor at the count", 2, {100, 100}, {5, 1}, {0}, 0.75, 0, {100, 50}, 1,
     {100, 0}},
    /* Own floors above min_vertices count in the infeasible plan: v = (100, 100), min 10, own
     * floors (40, 0), D = 0.2: V_D = 40 <= 40 + 10 → every mesh at its floor: (40, 10). */
    {"worked: own floors infeasible", 2, {100, 100}, {1, 1}, {0}, 0.2, 10, {40, 10}, 0,
     {40, 0}},
};

/* Plans a worked case and checks the targets against the expected ones and the totals against
 * each other. */
static void test_worked_case(void **state)
{
    const worked_case *c = *state;
    budget_mesh *meshes =
        make_meshes(c->count, c->vertices, c->importance, c->pinned, c->own_floor);
    budget_plan plan;
    assert_int_equal(budget_distribute(meshes, c->count, c->fraction, c->min_vertices, &plan), 0);
    uint64_t sum = 0, before = 0;
    for (size_t i = 0; i < c->count; i++) {
        uint64_t v = c->vertices[i], expected = c->expected[i];
        assert_int_equal(plan.target[i], expected);
        assert_int_equal(plan.decimate[i], expected < v);
        if (v == 0 || expected == v)
            assert_true(plan.factor[i] == 1.0);
        else
            assert_true(fabs(plan.factor[i] - (double)expected / (double)v) < 1e-12);
        sum += expected;
        before += v;
    }
    assert_int_equal(plan.total_planned, sum);
    assert_int_equal(plan.total_before, before);
    assert_int_equal(plan.rounds, c->rounds);
    assert_int_equal(plan.uniform_fallback, 0);
    budget_plan_free(&plan);
    assert_null(plan.target);
    free(meshes);
}

/* ---- edge cases ---- */

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

/* Plans v = (100, 300, 50 pinned), I = (0, second, 7), D = 0.5 with stderr captured; returns
 * what was written (the caller frees it). */
static char *plan_capturing_stderr(double second, budget_plan *plan)
{
    const uint64_t vertices[] = {100, 300, 50};
    const double importance[] = {0, second, 7};
    const int pinned[] = {0, 0, 1};
    budget_mesh *meshes = make_meshes(3, vertices, importance, pinned, NULL);
    distribute_call call = {meshes, 3, 0.5, 0, {0}, 0};
    warn_silence(0);
    char *text = capture_stderr(run_distribute, &call);
    assert_int_equal(call.result, 0);
    *plan = call.plan;
    free(meshes);
    return text;
}

/* Zero total importance of the free meshes (second = 0): uniform factors and one warning.
 * V_D = 225, 50 fixed, 175 left over 400 vertices → factor 0.4375 → counts (43.75, 131.25):
 * floors 43 + 131 = 174, the last vertex to the larger remainder (.75) → (44, 131). */
static void test_zero_importance_uniform(void **state)
{
    budget_plan plan;
    char *text = plan_capturing_stderr(0, &plan);
    assert_int_equal(plan.uniform_fallback, 1);
    assert_int_equal(plan.target[0], 44);
    assert_int_equal(plan.target[1], 131);
    assert_int_equal(plan.target[2], 50);
    assert_int_equal(plan.total_planned, 225);
    assert_int_equal(count_substrings(text, "warning"), 1);
    assert_non_null(strstr(text, "zero total importance"));
    budget_plan_free(&plan);
    free(text);
}

/* With importance somewhere among the free meshes there is no fallback and no warning. */
static void test_some_importance_no_warning(void **state)
{
    budget_plan plan;
    char *text = plan_capturing_stderr(1, &plan);
    assert_int_equal(plan.uniform_fallback, 0);
    assert_int_equal(count_substrings(text, "warning"), 0);
    budget_plan_free(&plan);
    free(text);
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
    budget_mesh *meshes = make_meshes(11, v, importance, pinned, NULL);
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
    free(meshes);
}

/* ---- bad arguments ---- */

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

static void test_bad_fraction(void **state)
{
    const budget_mesh meshes[2] = {{"dragon", 100, 1.0, 0, 0}, {"bunny", 100, 2.0, 0, 0}};
    const double fractions[] = {0.0, -0.5, 1.5, NAN, INFINITY};
    for (size_t i = 0; i < sizeof fractions / sizeof *fractions; i++)
        expect_input_error(meshes, 2, fractions[i], "outside (0, 1]");
}

/* The message names the mesh (and for a negative value, its index and the value). */
static void test_bad_importance(void **state)
{
    const struct {
        double importance;
        const char *fragment;
    } cases[] = {{NAN, "'bunny'"},
                 {-1.0, "'bunny' (index 1) has importance -1"},
                 {INFINITY, "'bunny'"}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        const budget_mesh meshes[2] = {{"dragon", 100, 1.0, 0, 0},
                                       {"bunny", 100, cases[i].importance, 0, 0}};
        expect_input_error(meshes, 2, 0.5, cases[i].fragment);
    }
}

static void test_vertex_overflow(void **state)
{
    const budget_mesh meshes[2] = {{"dragon", UINT64_MAX / 2 + 1, 1.0, 0, 0},
                                   {"bunny", UINT64_MAX / 2 + 1, 2.0, 0, 0}};
    expect_input_error(meshes, 2, 0.5, "overflows");
}

static void test_missing_arrays(void **state)
{
    const budget_mesh meshes[2] = {{"dragon", 100, 1.0, 0, 0}, {"bunny", 100, 2.0, 0, 0}};
    expect_input_error(NULL, 2, 0.5, "no mesh array");
    error_clear();
    assert_int_equal(budget_distribute(meshes, 2, 0.5, 0, NULL), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* ---- random scenes ---- */

/* Checks every property of a plan that does not need a hand-worked answer (f_i = the larger of
 * min_vertices and the mesh's own floor):
 * - totals: V_D = round(D Σ v), Σ target == total_planned, == V_D if feasible, else every free
 *   mesh at its floor f_i;
 * - per mesh: fixed meshes (pinned, v <= f_i) untouched; free ones within [f_i, v];
 *   factor = target / v in [0, 1], decimate == (target < v);
 * - the plan is the clamp solution up to whole vertices: one λ with |t_i - λ v_i w_i| <= 1 for
 *   meshes strictly inside their bounds, λ v_i w_i >= v_i - 1 at the ceiling and
 *   λ v_i w_i <= f_i + 1 at the floor (w = importance, or 1 under the uniform fallback);
 *   zero-importance meshes are above their floor only when every important mesh is at its
 *   ceiling. */
static void check_properties(const budget_mesh *meshes, size_t count, double fraction,
                             uint64_t min_vertices, const budget_plan *plan)
{
    uint64_t total = 0, fixed = 0, floors = 0, planned = 0;
    double free_importance = 0.0;
    for (size_t i = 0; i < count; i++) {
        uint64_t floor = meshes[i].floor > min_vertices ? meshes[i].floor : min_vertices;
        total += meshes[i].vertices;
        if (meshes[i].pinned || meshes[i].vertices <= floor)
            fixed += meshes[i].vertices;
        else
            floors += floor, free_importance += meshes[i].importance;
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
        uint64_t floor = meshes[i].floor > min_vertices ? meshes[i].floor : min_vertices;
        planned += t;
        assert_true(plan->factor[i] >= 0.0 && plan->factor[i] <= 1.0);
        assert_int_equal(plan->decimate[i], t < v);
        if (v > 0)
            assert_true(fabs(plan->factor[i] - (double)t / (double)v) < 1e-12);
        else
            assert_true(plan->factor[i] == 1.0);
        if (meshes[i].pinned || v <= floor) {
            assert_int_equal(t, v);
            continue;
        }
        assert_true(t >= floor && t <= v);
        if (!feasible) {
            assert_int_equal(t, floor);
            continue;
        }
        double w = uniform ? 1.0 : meshes[i].importance;
        if (w == 0.0) {
            zero_above_floor |= t > floor;
            continue;
        }
        important_below_ceiling |= t < v;
        double weight = (double)v * w;
        if (t > floor) /* not held up by the floor: λ v w >= t - 1 */
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

/* Random meshes from `rng`: 1 to 10^6 vertices, a quarter without importance, the rest with
 * importance over twelve decades (steep: I_i = (i + 1)^3 instead), one in ten pinned, one in
 * five with an own floor up to a fifth of its count. */
static void random_scene(idmr_rng *rng, budget_mesh *meshes, size_t count, int steep)
{
    for (size_t i = 0; i < count; i++) {
        meshes[i].name = "random";
        meshes[i].vertices = 1 + idmr_rng_next(rng) % 1000000;
        double kind = idmr_rng_float(rng);
        if (steep)
            meshes[i].importance = pow((double)(i + 1), 3.0);
        else if (kind < 0.25)
            meshes[i].importance = 0.0;
        else
            meshes[i].importance = pow(10.0, 12.0 * idmr_rng_float(rng) - 6.0);
        meshes[i].pinned = idmr_rng_float(rng) < 0.1;
        meshes[i].floor = idmr_rng_float(rng) < 0.2
                              ? (uint64_t)(0.2 * idmr_rng_float(rng) * (double)meshes[i].vertices)
                              : 0;
    }
}

static void test_random_scenes(void **state)
{
    static const uint64_t floors[] = {0, 4, 100, 1000, 20000};
    budget_mesh meshes[64];
    size_t feasible = 0;
    warn_silence(1);
    for (unsigned int trial = 0; trial < 3000; trial++) {
        idmr_rng rng = idmr_rng_init(12345, 0, 0, trial);
        size_t count = 1 + idmr_rng_next(&rng) % 64;
        random_scene(&rng, meshes, count, 0);
        if (trial % 7 == 0) /* some scenes without importance */
            for (size_t i = 0; i < count; i++)
                meshes[i].importance = 0.0;
        double fraction = trial % 11 == 0 ? 1.0 : fmax(1e-6, pow(idmr_rng_float(&rng), 2.0));
        uint64_t min_vertices = floors[idmr_rng_next(&rng) % 5];
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
    for (unsigned int steep = 0; steep < 2; steep++) {
        idmr_rng rng = idmr_rng_init(777, 0, 0, steep);
        random_scene(&rng, meshes, COUNT, (int)steep);
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

/* 10,000 meshes whose importance spans 1e-30 to 1e30 (a factor 10^60, evenly in the exponent):
 * the water-filling stays exact (check_properties), every factor finite; the most important
 * meshes keep everything, the least get the floor. */
static void test_many_meshes_extreme_importance(void **state)
{
    enum { COUNT = 10000 };
    budget_mesh *meshes = calloc(COUNT, sizeof *meshes);
    idmr_rng rng = idmr_rng_init(4242, 0, 0, 0);
    for (size_t i = 0; i < COUNT; i++) {
        meshes[i].name = "extreme";
        meshes[i].vertices = 100 + idmr_rng_next(&rng) % 100000;
        meshes[i].importance = pow(10.0, -30.0 + 60.0 * (double)i / (COUNT - 1));
    }
    budget_plan plan;
    assert_int_equal(budget_distribute(meshes, COUNT, 0.1, 50, &plan), 0);
    check_properties(meshes, COUNT, 0.1, 50, &plan);
    for (size_t i = 0; i < COUNT; i++)
        assert_true(isfinite(plan.factor[i]));
    assert_int_equal(plan.target[COUNT - 1], meshes[COUNT - 1].vertices);
    assert_int_equal(plan.target[0], 50);
    budget_plan_free(&plan);
    free(meshes);
}

int main(void)
{
    enum { WORKED = sizeof worked_cases / sizeof *worked_cases };
    const struct CMUnitTest others[] = {
        cmocka_unit_test(test_empty_list),
        cmocka_unit_test(test_zero_importance_uniform),
        cmocka_unit_test(test_some_importance_no_warning),
        cmocka_unit_test(test_tiny_fraction_infeasible),
        cmocka_unit_test(test_bad_fraction),
        cmocka_unit_test(test_bad_importance),
        cmocka_unit_test(test_vertex_overflow),
        cmocka_unit_test(test_missing_arrays),
        cmocka_unit_test(test_random_scenes),
        cmocka_unit_test(test_many_meshes),
        cmocka_unit_test(test_many_meshes_extreme_importance),
    };
    enum { OTHERS = sizeof others / sizeof *others };
    struct CMUnitTest tests[WORKED + OTHERS];
    for (size_t i = 0; i < WORKED; i++)
        tests[i] = (struct CMUnitTest){worked_cases[i].name, test_worked_case, NULL, NULL,
                                       (void *)&worked_cases[i]};
    memcpy(&tests[WORKED], others, sizeof others);
    return _cmocka_run_group_tests("budget", tests, WORKED + OTHERS, NULL, NULL);
}
