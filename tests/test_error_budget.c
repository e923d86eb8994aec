/* test_error_budget.c — `idmr reduce --max-error E` (reduce/error_search.h,
 * reduce/reduce_error_budget.c) and the paired estimator it measures with
 * (io/image_compare.h).
 *
 * Host tests: the search on error curves written by hand (where the answer is known: the
 * smallest D whose error + standard error is within E, to within the step), its bounds (E = 0
 * keeps everything, a huge E goes to the floor), its refusals; the paired estimator against the
 * exact formula, and correlated sampling (A1 and B1 sharing their noise where nothing changed)
 * against independent noise on synthetic images: the same expectation, a smaller spread.
 *
 * Device tests, on the shipped Cornell box with its knot replaced by a sphere (Mitsuba's
 * `sphere`, 32 × 32 segments: 994 vertices, nearly all of the scene's 1,026; a coarser sphere
 * changes its outline, shading and shadow more, so the error grows as D shrinks): the search's
 * result is within E, and smallest within a step (a failing step just below it); an independent
 * paired render (other seeds, twice the iterations) of the written scene is within E too; the
 * written scene is byte for byte what `reduce --target D` writes from the same importance; E = 0
 * gives D = 1 and a huge E the floor; --max-error-relative scales by the mean radiance; bad
 * options are refused; and on a real pair, the correlated estimate agrees with the independent
 * one and has the smaller standard error; and a glass ball (a caustic, noisy check renders)
 * within E by the search and by an independent render. --refine (reduce_refine.c): each round
 * kept exactly by its rule and the written scene the chosen round's; a warning where round 0's
 * check renders see the change too faintly, and none where they see it. Small films and photon
 * counts: a few seconds each. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <setjmp.h>

#include <cmocka.h>

#include "device_test.h"
#include "io/image_compare.h"
#include "reduce/error_search.h"
#include "reduce/refine_weights.h"
#include "reduce_common.h"

/* |a - b| <= tolerance (this cmocka has no assert_double_equal). */
#define assert_near(a, b, tolerance) assert_near_at((a), (b), (tolerance), #a, __LINE__)
static void assert_near_at(double a, double b, double tolerance, const char *what, int line)
{
    if (!(fabs(a - b) <= tolerance))
        fail_msg("line %d: %s = %.17g, expected %.17g within %g", line, what, a, b, tolerance);
}

/* ---- the search on curves written by hand ---- */

/* error(D) = slope · (−ln D) (0 at D = 1, growing as D shrinks), a constant standard error;
 * `fail_at` > 0 makes the measure fail at its call of that number. */
typedef struct curve {
    double slope, standard_error;
    unsigned int calls, fail_at;
} curve;

static int measure_curve(double target, error_search_step *step, void *context)
{
    curve *c = context;
    c->calls++;
    if (c->fail_at && c->calls == c->fail_at)
        return error_set(IDMR_EXIT_FAILURE, "measure failed on purpose");
    step->error = c->slope * -log(target);
    step->standard_error = c->standard_error;
    step->vertices = (uint64_t)(target * 1000.0 + 0.5);
    return 0;
}

/* The result passes, a failing measured step lies below it within 1 + step, and every step's
 * verdict is error + standard_error <= E. */
static void assert_smallest_within_step(const error_search_result *r, double max_error,
                                        double step)
{
    const error_search_step *chosen = &r->steps[r->chosen];
    assert_true(chosen->passes);
    assert_true(chosen->error + chosen->standard_error <= max_error);
    assert_true(chosen->target == r->target);
    int failing_below = 0;
    for (size_t k = 0; k < r->count; k++) {
        const error_search_step *s = &r->steps[k];
        assert_int_equal(s->passes, s->error + s->standard_error <= max_error);
        if (s->passes)
            assert_true(s->target >= r->target);
        else if (s->target < r->target && s->target * (1.0 + step) >= r->target * (1 - 1e-12))
            failing_below = 1;
    }
    assert_true(failing_below);
}

static void test_search_on_curve(void **state)
{
    /* error + se = 0.1 (−ln D) + 0.002 <= 0.1 for D >= exp(−0.98) = 0.3753 */
    curve c = {.slope = 0.1, .standard_error = 0.002};
    error_search_result r;
    assert_int_equal(error_search_run(0.1, 0.1, 1e-4, measure_curve, &c, &r), 0);
    double exact = exp(-0.98);
    assert_true(r.target >= exact && r.target <= exact * 1.1);
    assert_smallest_within_step(&r, 0.1, 0.1);
    assert_true(r.steps[0].target == 1.0 && !r.steps[0].measured && r.steps[0].passes);
    /* bracket 0.25 (fails), then bisection of [0.25, 1] to 10 %: four steps */
    assert_int_equal(c.calls, r.count - 1);
    assert_true(c.calls <= 6);
    error_search_result_free(&r);
    /* a finer step lands closer */
    c.calls = 0;
    assert_int_equal(error_search_run(0.1, 0.01, 1e-4, measure_curve, &c, &r), 0);
    assert_true(r.target >= exact && r.target <= exact * 1.01);
    assert_smallest_within_step(&r, 0.1, 0.01);
    error_search_result_free(&r);
}

/* The noise counts: a step whose error alone is within E but error + standard error is not
 * fails, so the answer is a larger D than the error alone would give. */
static void test_search_counts_standard_error(void **state)
{
    curve c = {.slope = 0.1, .standard_error = 0.03};
    error_search_result r;
    assert_int_equal(error_search_run(0.1, 0.05, 1e-4, measure_curve, &c, &r), 0);
    double with_noise = exp(-0.7), without = exp(-1.0);
    assert_true(r.target >= with_noise && r.target <= with_noise * 1.05);
    assert_true(r.target > without * 1.3);
    assert_smallest_within_step(&r, 0.1, 0.05);
    error_search_result_free(&r);
}

static void test_search_bounds(void **state)
{
    error_search_result r;
    /* E = 0: every reduction changes the image, D = 1 (approached from below, never measured) */
    curve c = {.slope = 0.1, .standard_error = 0.001};
    assert_int_equal(error_search_run(0.0, 0.1, 1e-4, measure_curve, &c, &r), 0);
    assert_true(r.target == 1.0);
    assert_int_equal(r.chosen, 0);
    for (size_t k = 1; k < r.count; k++)
        assert_false(r.steps[k].passes);
    assert_true(r.steps[r.count - 1].target * 1.1 >= 1.0);
    error_search_result_free(&r);
    /* a huge E: down to the floor, every step passing, no bisection */
    c.calls = 0;
    assert_int_equal(error_search_run(1e9, 0.1, 0.003, measure_curve, &c, &r), 0);
    assert_true(r.target == 0.003);
    assert_true(r.steps[r.chosen].target == 0.003);
    for (size_t k = 0; k < r.count; k++)
        assert_true(r.steps[k].passes);
    /* 0.25, then down to the floor: 0.25 / 16 (the longest jump on the line through D = 1 and
     * 0.25), then the floor (0.25 / 16 / 64 is below it) */
    assert_int_equal(c.calls, 3);
    error_search_result_free(&r);
    /* nothing to decimate (floor 1): D = 1 without a measure */
    c.calls = 0;
    assert_int_equal(error_search_run(0.01, 0.1, 1.0, measure_curve, &c, &r), 0);
    assert_true(r.target == 1.0);
    assert_int_equal(c.calls, 0);
    error_search_result_free(&r);
}

/* error(D) = scale · D^-power (+ a deterministic noise of relative size `noise`, from a hash of
 * D), a constant standard error: the falling power law that the search's line models, and,
 * with noise or a jump, curves it does not. */
typedef struct power_curve {
    double scale, power, noise, standard_error;
    double jump_below, jump; /* error + jump below D = jump_below (a glint lost) */
    unsigned int calls;
} power_curve;

static int measure_power(double target, error_search_step *step, void *context)
{
    power_curve *c = context;
    c->calls++;
    uint64_t bits;
    memcpy(&bits, &target, sizeof bits);
    bits = (bits ^ (bits >> 29)) * 0xbf58476d1ce4e5b9ull;
    bits ^= bits >> 32;
    double wobble = (double)(bits % 2001) / 1000.0 - 1.0; /* in [-1, 1] */
    step->error = c->scale * pow(target, -c->power) * (1.0 + c->noise * wobble) +
                  (target < c->jump_below ? c->jump : 0.0);
    step->standard_error = c->standard_error;
    step->vertices = (uint64_t)(target * 1e6 + 0.5);
    return 0;
}

/* On a power law the line through two steps lands near the crossing: fewer steps than a
 * bisection (0.25, 0.0625, 0.0156 and four bisections of [0.0156, 0.0625] to 10 %: seven). */
static void test_search_interpolates(void **state)
{
    /* error + se = 0.0006 D^-0.75 + 0.0001 <= 0.01 for D >= (0.0099 / 0.0006)^(-1 / 0.75) */
    power_curve c = {.scale = 0.0006, .power = 0.75, .standard_error = 0.0001};
    error_search_result r;
    assert_int_equal(error_search_run(0.01, 0.1, 1e-5, measure_power, &c, &r), 0);
    double exact = pow(0.0099 / 0.0006, -1.0 / 0.75);
    assert_true(r.target >= exact && r.target <= exact * 1.1);
    assert_smallest_within_step(&r, 0.01, 0.1);
    assert_true(c.calls <= 5);
    error_search_result_free(&r);
}

/* The most bracketing steps from D = 1 to `floor`: the first goes down by ERROR_SEARCH_BRACKET,
 * each later one at least (nearly) a step, doubled after each, or its longest jump. */
static unsigned int bracket_steps_at_most(double step, double floor)
{
    double left = -log(floor) - log(ERROR_SEARCH_BRACKET), least = 0.95 * log1p(step);
    unsigned int count = 1;
    for (; left > 0; count++, least *= 2)
        left -= fmin(least, log(count == 1 ? ERROR_SEARCH_FIRST_JUMP : ERROR_SEARCH_LONGEST_JUMP));
    return count;
}

/* Whatever the curve (powers, noise that makes it rise as D shrinks in places, a jump the line
 * cannot see), the result is the smallest measured pass with a measured failure within a step
 * below it, the bracket's steps are bounded, and the narrowing stays within twice a bisection's
 * steps (the safeguard promises three times: a halving at least every three steps; these curves
 * need no more than twice). */
static void test_search_any_curve(void **state)
{
    const double steps[] = {0.1, 0.02, 0.5};
    unsigned int most = 0;
    for (unsigned int k = 0; k < 600; k++) {
        power_curve c = {.scale = 1e-4 * (1 + k % 7), .power = 0.2 + 0.15 * (k % 11),
                         .noise = (k % 3) * 0.3, .standard_error = 1e-5 * (k % 5),
                         .jump_below = k % 4 == 0 ? 0.002 * (1 + k % 13) : 0,
                         .jump = 0.01 * (k % 2)};
        double step = steps[k % 3], max_error = 0.002 * (1 + k % 17);
        error_search_result r;
        assert_int_equal(error_search_run(max_error, step, 1e-6, measure_power, &c, &r), 0);
        if (r.target < 1.0 && r.target > 1e-6)
            assert_smallest_within_step(&r, max_error, step);
        /* bracketing from 1 to 1e-6, then twice the bisection of its longest jump to the step */
        unsigned int bound =
            bracket_steps_at_most(step, 1e-6) +
            2 * (unsigned int)ceil(log2(log(ERROR_SEARCH_LONGEST_JUMP) / log1p(step)) + 1);
        if (c.calls > bound)
            fail_msg("curve %u: %u steps, more than %u", k, c.calls, bound);
        most = c.calls > most ? c.calls : most;
        error_search_result_free(&r);
    }
    print_message("  at most %u steps over 600 curves\n", most);
}

static void test_search_refusals(void **state)
{
    curve c = {.slope = 0.1};
    error_search_result r;
    const double bad_bounds[] = {-0.01, NAN, INFINITY};
    for (size_t k = 0; k < 3; k++) {
        error_clear();
        assert_int_equal(error_search_run(bad_bounds[k], 0.1, 0.01, measure_curve, &c, &r), -1);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
        assert_non_null(strstr(error_message(), "--max-error"));
    }
    error_clear();
    assert_int_equal(error_search_run(0.1, 0.0, 0.01, measure_curve, &c, &r), -1);
    assert_non_null(strstr(error_message(), "--max-error-step"));
    assert_int_equal(c.calls, 0);
    /* a failing measure ends the search with its error */
    c.fail_at = 2;
    error_clear();
    assert_int_equal(error_search_run(0.1, 0.1, 0.01, measure_curve, &c, &r), -1);
    assert_non_null(strstr(error_message(), "on purpose"));
    assert_null(r.steps);
}

/* ---- the paired estimator ---- */

/* A1 − B1 = d + n, A2 − B2 = d − n with d = 0.5 and n = ±0.1 in a checkerboard: every product
 * is d² − n² = 0.24 exactly, A1 against B1 has RMSE sqrt(d² + n²) (the mean of n is 0). */
static void test_paired_exact(void **state)
{
    enum { W = 8, H = 8, V = 3 * W * H };
    float a1[V], a2[V], b1[V], b2[V];
    for (int i = 0; i < V; i++) {
        int pixel = i / 3, x = pixel % W, y = pixel / W;
        float n = ((x + y) % 2) ? 0.1f : -0.1f;
        a1[i] = 2.0f;
        a2[i] = 2.0f;
        b1[i] = 2.0f - (0.5f + n);
        b2[i] = 2.0f - (0.5f - n);
    }
    image_paired_error e;
    image_paired_error_of(a1, a2, b1, b2, W, H, 2, &e);
    double d1 = 2.0 - (double)(2.0f - 0.6f), d2 = 2.0 - (double)(2.0f - 0.4f);
    assert_near(e.mse, d1 * d2, 1e-7);
    assert_near(e.rmse, sqrt(d1 * d2), 1e-7);
    assert_near(e.noisy_rmse, sqrt(0.5 * (d1 * d1 + d2 * d2)), 1e-7);
    /* z = (x1² − x2²)/2 = 2 d n per value: over a 2 × 2 tile it sums to 0 (two +n, two −n) */
    assert_near(e.mse_standard_error, 0.0, 1e-9);
    /* equal images: 0 ± 0 */
    image_paired_error_of(a1, a2, a1, a2, W, H, 0, &e);
    assert_true(e.mse == 0 && e.rmse == 0 && e.mse_standard_error == 0);
}

/* A counter-based normal deviate (Box–Muller on a 64-bit hash). */
static double uniform_of(uint64_t key)
{
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    key *= 0xc4ceb9fe1a85ec53ull;
    key ^= key >> 33;
    return ((double)(key >> 11) + 0.5) / 9007199254740992.0;
}

static double normal_of(uint64_t key)
{
    double u = uniform_of(2 * key), v = uniform_of(2 * key + 1);
    return sqrt(-2.0 * log(u)) * cos(2.0 * M_PI * v);
}

/* Synthetic renders: the original a and the reduced b differ by d in a quarter of the image.
 * Correlated: B shares A's noise of the same seed where nothing changed (as a render with the
 * same random numbers does), and has its own where it changed. Independent: B's noise is its
 * own everywhere. Over many draws both estimates' means are the exact mean of d² (unbiased),
 * and the correlated one's spread is far smaller. */
static void test_paired_correlated_unbiased(void **state)
{
    enum { W = 64, H = 64, V = 3 * W * H, DRAWS = 200 };
    float *a1 = malloc(V * sizeof *a1), *a2 = malloc(V * sizeof *a2);
    float *b1 = malloc(V * sizeof *b1), *b2 = malloc(V * sizeof *b2);
    double exact = 0;
    for (int i = 0; i < V; i++) {
        int pixel = i / 3;
        double d = (pixel % W < W / 2 && pixel / W < H / 2) ? 0.02 : 0.0;
        exact += d * d / V;
    }
    double sum[2] = {0, 0}, sum2[2] = {0, 0}, reported_se[2] = {0, 0};
    for (int correlated = 0; correlated < 2; correlated++)
        for (uint64_t draw = 0; draw < DRAWS; draw++) {
            for (int i = 0; i < V; i++) {
                int pixel = i / 3;
                int changed = pixel % W < W / 2 && pixel / W < H / 2;
                double d = changed ? 0.02 : 0.0, sigma = 0.1;
                uint64_t key = ((draw * 8 + (uint64_t)correlated) * V + (uint64_t)i) * 4;
                double na1 = sigma * normal_of(key), na2 = sigma * normal_of(key + 1);
                double nb1 = sigma * normal_of(key + 2), nb2 = sigma * normal_of(key + 3);
                if (correlated && !changed) {
                    nb1 = na1;
                    nb2 = na2;
                }
                a1[i] = (float)(1.0 + na1);
                a2[i] = (float)(1.0 + na2);
                b1[i] = (float)(1.0 - d + nb1);
                b2[i] = (float)(1.0 - d + nb2);
            }
            image_paired_error e;
            image_paired_error_of(a1, a2, b1, b2, W, H, 0, &e);
            sum[correlated] += e.mse;
            sum2[correlated] += e.mse * e.mse;
            reported_se[correlated] += e.mse_standard_error / DRAWS;
        }
    for (int k = 0; k < 2; k++) {
        double mean = sum[k] / DRAWS, spread = sqrt(sum2[k] / DRAWS - mean * mean);
        /* unbiased: the mean over draws within 4 standard errors of the mean of the exact */
        if (fabs(mean - exact) > 4 * spread / sqrt((double)DRAWS))
            fail_msg("%s: mean %g, exact %g, spread %g", k ? "correlated" : "independent", mean,
                     exact, spread);
        /* the reported standard error describes the spread (within a factor of 1.5) */
        assert_true(reported_se[k] > spread / 1.5 && reported_se[k] < spread * 1.5);
    }
    double spread_independent = sqrt(sum2[0] / DRAWS - (sum[0] / DRAWS) * (sum[0] / DRAWS));
    double spread_correlated = sqrt(sum2[1] / DRAWS - (sum[1] / DRAWS) * (sum[1] / DRAWS));
    assert_true(spread_correlated < 0.5 * spread_independent);
    free(a1);
    free(a2);
    free(b1);
    free(b2);
}

/* ---- reduce --max-error on the device ---- */

/* The Cornell box with its knot replaced by a sphere of `material` (a bsdf element or a ref),
 * written in a fresh directory. */
#define ORANGE "<ref id=\"orange\"/>"
#define GLASS "<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"1.5\"/></bsdf>"
static void write_sphere_scene_of(const char *material, char *dir, size_t size, char *path,
                                  size_t path_size)
{
    size_t length;
    char *xml = read_file(CORNELL, &length);
    char *begin = strstr(xml, "<shape type=\"ply\" id=\"knot\">");
    assert_non_null(begin);
    char *end = strstr(begin, "</shape>");
    assert_non_null(end);
    end += strlen("</shape>");
    temp_dir(dir, size);
    snprintf(path, path_size, "%s/scene.xml", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fwrite(xml, 1, (size_t)(begin - xml), f);
    fputs("<shape type=\"sphere\" id=\"ball\">\n"
          "        <point name=\"center\" x=\"0.35\" y=\"-0.55\" z=\"0.2\"/>\n"
          "        <float name=\"radius\" value=\"0.42\"/>\n        ",
          f);
    fputs(material, f);
    fputs("\n    </shape>", f);
    fputs(end, f);
    assert_int_equal(fclose(f), 0);
    free(xml);
}

static void write_sphere_scene(char *dir, size_t size, char *path, size_t path_size)
{
    write_sphere_scene_of(ORANGE, dir, size, path, path_size);
}

/* Small runs: 3 importance iterations (all of them: the stop rule off, so a plain reduce from the
 * same seed has the same importance), check renders of 4 iterations of 20,000 photons at a
 * quarter of the 256 × 256 film. */
static void search_options(reduce_options *o, reduce_error_bound bound, double max_error)
{
    small_options(o);
    o->importance.sppm.photons = 20000;
    o->factor_tolerance = 0;
    o->error.bound = bound;
    o->error.max_error = max_error;
    o->error.iterations = 4;
    o->error.photons = 20000;
    o->error.resolution = 0.25;
}

static const cJSON *object(const cJSON *parent, const char *key)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(parent, key);
    if (!item)
        fail_msg("report: no '%s'", key);
    return item;
}

/* The paired error of the written scene against the original, rendered independently of the
 * search: seeds 3 and 4, twice the iterations, the search's first radius and film. */
static void independent_check(const scene *original, const scene *reduced, const cJSON *check,
                              image_paired_error *e)
{
    float *images[2][2];
    const scene *scenes[2] = {original, reduced};
    unsigned int width = 0, height = 0;
    for (int s = 0; s < 2; s++)
        for (int k = 0; k < 2; k++) {
            render_options o;
            test_render_options(&o, 2 * (unsigned int)number(check, "iterations"),
                                (unsigned int)number(check, "photons"));
            o.sppm.resolution = (float)number(check, "resolution");
            o.sppm.radius = number(check, "first_radius");
            o.sppm.seed = 3 + (unsigned int)k;
            o.sppm.progress = 0;
            render_result r;
            test_run_render(scenes[s], NULL, &o, &r);
            images[s][k] = r.image;
            width = r.sppm.width;
            height = r.sppm.height;
            r.image = NULL;
            render_result_free(&r);
        }
    image_paired_error_of(images[0][0], images[0][1], images[1][0], images[1][1], (int)width,
                          (int)height, 0, e);
    for (int s = 0; s < 2; s++)
        for (int k = 0; k < 2; k++)
            free(images[s][k]);
}

/* The independent check of the written scene (above) agrees that it is within E, allowing
 * three of its own standard errors of noise. */
static void assert_independent_check_within(const scene *original, const scene *reduced,
                                            const cJSON *budget, double E)
{
    const cJSON *chosen = object(budget, "chosen");
    image_paired_error check;
    independent_check(original, reduced, object(budget, "check_render"), &check);
    print_message("  chosen D %g: search %g ± %g, independent check %g ± %g, E %g\n",
                  number(chosen, "target"), number(chosen, "error"),
                  number(chosen, "standard_error"), check.rmse, check.rmse_standard_error, E);
    if (!(check.rmse <= E + 3 * check.rmse_standard_error))
        fail_msg("independent check: %g ± %g above E %g", check.rmse, check.rmse_standard_error,
                 E);
}

/* Every file under meshes/ of two reductions, byte for byte. */
static void assert_same_meshes(const char *a, const char *b, const scene *s)
{
    for (size_t m = 0; m < s->mesh_count; m++) {
        char pa[4200], pb[4200];
        snprintf(pa, sizeof pa, "%s/meshes/%s.ply", a, s->meshes[m].name);
        snprintf(pb, sizeof pb, "%s/meshes/%s.ply", b, s->meshes[m].name);
        FILE *fa = fopen(pa, "rb"), *fb = fopen(pb, "rb");
        assert_int_equal(fa != NULL, fb != NULL);
        if (!fa)
            continue;
        fclose(fa);
        fclose(fb);
        size_t la, lb;
        char *da = read_file(pa, &la), *db = read_file(pb, &lb);
        assert_int_equal(la, lb);
        assert_memory_equal(da, db, la);
        free(da);
        free(db);
    }
    size_t la, lb;
    char pa[4200], pb[4200];
    snprintf(pa, sizeof pa, "%s/scene.xml", a);
    snprintf(pb, sizeof pb, "%s/scene.xml", b);
    char *da = read_file(pa, &la), *db = read_file(pb, &lb);
    assert_int_equal(la, lb);
    assert_memory_equal(da, db, la);
    free(da);
    free(db);
}

static void test_max_error_sphere(void **state)
{
    char dir[64], path[128];
    write_sphere_scene(dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    const double E = 0.01, step = REDUCE_ERROR_STEP;
    reduce_options o;
    search_options(&o, REDUCE_ERROR_ABSOLUTE, E);
    reduction r;
    reduction_run(&r, s, &o);
    const cJSON *budget = object(r.report, "error_budget");
    const cJSON *chosen = object(budget, "chosen");
    double target = number(chosen, "target");
    assert_near(number(budget, "max_error"), E, 0);
    assert_near(number(r.report, "target"), target, 0);
    /* within E, noise included */
    assert_true(number(chosen, "error") + number(chosen, "standard_error") <= E);
    /* neither end: the sphere's error crosses E between the floor and 1 */
    assert_true(target < 0.99 && target > number(budget, "floor"));
    /* smallest within a step: a measured step just below it fails; every step's verdict holds;
     * and the error grows as D shrinks (the coarsest step's error above the chosen one's) */
    const cJSON *item;
    int failing_below = 0;
    double coarsest = 1, coarsest_error = 0;
    cJSON_ArrayForEach(item, object(budget, "curve"))
    {
        double d = number(item, "target"), e = number(item, "error");
        double se = number(item, "standard_error");
        int within = cJSON_IsTrue(object(item, "within"));
        assert_int_equal(within, e + se <= E);
        if (within)
            assert_true(d >= target);
        else if (d < target && d * (1 + step) >= target)
            failing_below = 1;
        if (d < coarsest) {
            coarsest = d;
            coarsest_error = e;
        }
        print_message("  D %.4g: %.4g \u00b1 %.2g%s\n", d, e, se, within ? ", within" : "");
        assert_true(number(item, "seconds") >= 0);
        /* where a measured step's seconds went: its decimation and the renders' iterations */
        const cJSON *stages = object(item, "seconds_by_stage");
        if (cJSON_IsTrue(object(item, "measured")))
            assert_true(number(stages, "decimation") > 0 && number(stages, "iterations") > 0 &&
                        number(stages, "decimation") + number(stages, "bvh") +
                                number(stages, "iterations") <=
                            number(item, "seconds"));
    }
    assert_true(failing_below);
    assert_true(coarsest_error > number(chosen, "error"));
    /* the scene written is the one measured */
    uint64_t vertices = check_report_against_output(r.report, s, r.out);
    assert_int_equal(vertices, (uint64_t)number(chosen, "vertices"));
    /* an independent paired render (seeds 3 and 4, twice the iterations) agrees it is within E,
     * allowing its own noise */
    assert_independent_check_within(s, r.out, budget, E);
    /* a plain reduce at that D, from the same importance, writes the same scene */
    reduce_options plain;
    small_options(&plain);
    plain.importance.sppm.photons = 20000;
    plain.factor_tolerance = 0;
    plain.target = target;
    reduction p;
    reduction_run(&p, s, &plain);
    assert_same_meshes(r.dir, p.dir, s);
    assert_true(cJSON_IsNull(object(p.report, "error_budget")));
    /* seconds: the search (renders and decimations) and what the plain reduce would take */
    const cJSON *seconds = object(budget, "seconds");
    assert_true(number(seconds, "search") > number(seconds, "originals"));
    assert_true(number(seconds, "plain_reduce") > 0);
    reduction_free(&p);
    reduction_free(&r);
    scene_free(s);
    remove_tree(dir);
}

/* A glass ball: its caustic on the floor and the light seen through it change with its
 * tessellation, and its check renders are noisy (paths through glass that reach the light): the
 * search's answer is still within E, and an independent paired render (seeds 3 and 4, twice the
 * iterations) agrees, allowing its own noise. */
static void test_max_error_glass_caustic(void **state)
{
    char dir[64], path[128];
    write_sphere_scene_of(GLASS, dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    const double E = 0.02;
    reduce_options o;
    search_options(&o, REDUCE_ERROR_ABSOLUTE, E);
    reduction r;
    reduction_run(&r, s, &o);
    const cJSON *budget = object(r.report, "error_budget");
    const cJSON *chosen = object(budget, "chosen");
    assert_true(number(chosen, "error") + number(chosen, "standard_error") <= E);
    assert_true(number(chosen, "target") < 1);
    /* the steps below the D found that only their noise failed are counted (a warning) */
    unsigned int by_noise = 0;
    const cJSON *item;
    cJSON_ArrayForEach(item, object(budget, "curve"))
    {
        by_noise += !cJSON_IsTrue(object(item, "within")) && number(item, "error") <= E &&
                    number(item, "target") < number(chosen, "target");
    }
    assert_int_equal((unsigned int)number(budget, "steps_failed_by_noise"), by_noise);
    assert_independent_check_within(s, r.out, budget, E);
    reduction_free(&r);
    scene_free(s);
    remove_tree(dir);
}

static void test_max_error_ends(void **state)
{
    char dir[64], path[128];
    write_sphere_scene(dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    /* E = 0: nothing may change, D = 1, every vertex kept */
    reduce_options o;
    search_options(&o, REDUCE_ERROR_ABSOLUTE, 0.0);
    reduction r;
    reduction_run(&r, s, &o);
    const cJSON *budget = object(r.report, "error_budget");
    assert_near(number(object(budget, "chosen"), "target"), 1.0, 0);
    assert_int_equal((uint64_t)number(r.report, "vertices_after"), s->vertex_count);
    reduction_free(&r);
    /* a huge E: the floor, every decimatable mesh at --min-vertices */
    search_options(&o, REDUCE_ERROR_ABSOLUTE, 1e6);
    reduction_run(&r, s, &o);
    budget = object(r.report, "error_budget");
    double floor = number(budget, "floor");
    assert_near(number(object(budget, "chosen"), "target"), floor, 0);
    assert_true(floor * (double)s->vertex_count <= 1026 - 994 + 16 + 0.5);
    assert_true(number(r.report, "vertices_after") < 100);
    reduction_free(&r);
    /* relative: E is F times the original's mean radiance */
    search_options(&o, REDUCE_ERROR_RELATIVE, 0.05);
    reduction_run(&r, s, &o);
    budget = object(r.report, "error_budget");
    double mean = number(budget, "mean_radiance");
    assert_true(mean > 0.01 && mean < 10);
    assert_near(number(budget, "max_error"), 0.05 * mean, 1e-12 * mean);
    assert_near(number(budget, "max_error_relative"), 0.05, 0);
    const cJSON *chosen = object(budget, "chosen");
    assert_true(number(chosen, "error") + number(chosen, "standard_error") <= 0.05 * mean);
    reduction_free(&r);
    scene_free(s);
    remove_tree(dir);
}

static void test_max_error_refused(void **state)
{
    scene *s = test_load_scene(CORNELL);
    char dir[64];
    temp_dir(dir, sizeof dir);
    char out[128];
    snprintf(out, sizeof out, "%s/out", dir);
    reduce_options o;
    search_options(&o, REDUCE_ERROR_ABSOLUTE, -0.01);
    expect_input_error(s, out, &o, "--max-error must be");
    search_options(&o, REDUCE_ERROR_RELATIVE, NAN);
    expect_input_error(s, out, &o, "--max-error-relative must be");
    search_options(&o, REDUCE_ERROR_ABSOLUTE, 0.01);
    o.error.step = 0;
    expect_input_error(s, out, &o, "--max-error-step");
    search_options(&o, REDUCE_ERROR_ABSOLUTE, 0.01);
    o.memory_budget = 1u << 30;
    expect_input_error(s, out, &o, "cannot be combined with --memory-budget");
    search_options(&o, REDUCE_ERROR_ABSOLUTE, 0.01);
    o.passes = 2;
    expect_input_error(s, out, &o, "--passes");
    /* nothing was written */
    assert_false(file_exists(dir, "out"));
    remove_tree(dir);
    scene_free(s);
}

/* On a real pair (the sphere at D = 0.1 against the original): the reduced scene rendered with
 * the original's seeds (correlated) and with seeds of its own (independent) estimate the same
 * squared change, and the correlated estimate is the more precise. */
static void test_correlated_real_pair(void **state)
{
    char dir[64], path[128];
    write_sphere_scene(dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    reduce_options o;
    small_options(&o);
    o.target = 0.1;
    reduction r;
    reduction_run(&r, s, &o);
    /* A with seeds 1, 2; B with seeds 1, 2 (correlated with A) and 3, 4 (independent) */
    const scene *scenes[6] = {s, s, r.out, r.out, r.out, r.out};
    const unsigned int seeds[6] = {1, 2, 1, 2, 3, 4};
    float *images[6];
    unsigned int width = 0, height = 0;
    for (int k = 0; k < 6; k++) {
        render_options ro;
        test_render_options(&ro, 8, 20000);
        ro.sppm.resolution = 0.25f;
        ro.sppm.radius = 0.11;
        ro.sppm.progress = 0;
        ro.sppm.seed = seeds[k];
        render_result rr;
        test_run_render(scenes[k], NULL, &ro, &rr);
        images[k] = rr.image;
        width = rr.sppm.width;
        height = rr.sppm.height;
        rr.image = NULL;
        render_result_free(&rr);
    }
    float **a = images, **b = images + 2;
    image_paired_error correlated, independent;
    image_paired_error_of(a[0], a[1], b[0], b[1], (int)width, (int)height, 0, &correlated);
    image_paired_error_of(a[0], a[1], b[2], b[3], (int)width, (int)height, 0, &independent);
    double both = sqrt(correlated.mse_standard_error * correlated.mse_standard_error +
                       independent.mse_standard_error * independent.mse_standard_error);
    if (fabs(correlated.mse - independent.mse) > 3 * both)
        fail_msg("correlated %g ± %g, independent %g ± %g", correlated.mse,
                 correlated.mse_standard_error, independent.mse, independent.mse_standard_error);
    assert_true(correlated.mse > 0);
    if (!(correlated.mse_standard_error < 0.7 * independent.mse_standard_error))
        fail_msg("correlated se %g not below independent se %g", correlated.mse_standard_error,
                 independent.mse_standard_error);
    assert_true(correlated.noisy_rmse < independent.noisy_rmse);
    for (int k = 0; k < 6; k++)
        free(images[k]);
    reduction_free(&r);
    scene_free(s);
    remove_tree(dir);
}

/* ---- reduce --refine ---- */

/* Pixel weights by hand (refine_weights.h): an 8 x 4 film in two 4 x 4 tiles. Left tile: A = 1,
 * B = 0 in every channel, a change of 3 per pixel, no spread: the largest, weight 64. Right
 * tile: A1 - B1 = 1, A2 - B2 = -1 (a negative product: noise, not change): 0. Then the right
 * tile's odd rows changed by 3 per pixel, its even rows not: mean m = 1.5, sample variance
 * 16/15 · 2.25, standard error s = sqrt(2.4 / 16); its value m - 2 s, of the left's 3, gives
 * weight round(64 (1.5 - 2 s) / 3) = 15. */
static void test_refine_weights_by_hand(void **state)
{
    enum { W = 8, H = 4 };
    float a1[3 * W * H], a2[3 * W * H], b1[3 * W * H], b2[3 * W * H];
    uint32_t weights[W * H];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int k = 0; k < 3; k++) {
                int i = 3 * (y * W + x) + k;
                a1[i] = a2[i] = 1.0f;
                b1[i] = 0.0f;
                b2[i] = x < 4 ? 0.0f : 2.0f; /* right: (1 - 0)(1 - 2) = -1 */
            }
    assert_int_equal(refine_pixel_weights(a1, a2, b1, b2, W, H, 4, 64, weights), 16);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            assert_int_equal(weights[y * W + x], x < 4 ? 64 : 0);
    /* right tile: every other row changed by 1 per channel (3 per pixel), the rest unchanged */
    for (int y = 0; y < H; y++)
        for (int x = 4; x < W; x++)
            for (int k = 0; k < 3; k++) {
                int i = 3 * (y * W + x) + k;
                b1[i] = b2[i] = y % 2 ? 0.0f : 1.0f;
            }
    assert_int_equal(refine_pixel_weights(a1, a2, b1, b2, W, H, 4, 64, weights), 32);
    double s = sqrt(16.0 / 15.0 * 2.25 / 16.0), expected = 64 * (1.5 - 2 * s) / 3;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            assert_int_equal(weights[y * W + x], x < 4 ? 64 : (uint32_t)lround(expected));
    /* nothing changed: no weight anywhere */
    assert_int_equal(refine_pixel_weights(a1, a2, a1, a2, W, H, 4, 64, weights), 0);
    for (int i = 0; i < W * H; i++)
        assert_int_equal(weights[i], 0);
}

/* --refine 2 on the sphere at D = 0.05: round 0 is the importance-only reduction; each later
 * round is kept exactly when its error + standard error is below the best error before it, the
 * round written is the last kept (its error never above round 0's), and the written scene is
 * the one measured: rendered again with the check renders' seeds,
 * radius and film it gives that round's error (to the written files' rounding), and its
 * vertices. Every round decimates
 * to the same D: vertices within 2 % of round 0's. */
static void test_refine_keeps_the_better(void **state)
{
    char dir[64], path[128];
    write_sphere_scene(dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    reduce_options o;
    small_options(&o);
    o.target = 0.05;
    o.refine = 2;
    o.error.iterations = 4;
    o.error.photons = 20000;
    o.error.resolution = 0.25;
    reduction r;
    reduction_run(&r, s, &o);
    const cJSON *refine = object(r.report, "refine");
    const cJSON *rounds = object(refine, "rounds");
    int count = cJSON_GetArraySize(rounds);
    assert_true(count >= 2);
    unsigned int chosen = (unsigned int)number(refine, "chosen");
    double first = number(cJSON_GetArrayItem(rounds, 0), "error");
    double first_vertices = number(cJSON_GetArrayItem(rounds, 0), "vertices");
    /* the rule: a round is kept when its error + standard error is below the best error so far;
     * the last kept is chosen */
    double best_error = first;
    int expected = 0;
    for (int k = 0; k < count; k++) {
        const cJSON *round = cJSON_GetArrayItem(rounds, k);
        double e = number(round, "error"), se = number(round, "standard_error");
        int kept = cJSON_IsTrue(object(round, "kept"));
        print_message("  round %d: mix %g, error %g ± %g, %g vertices, %s\n", k,
                      number(round, "mix"), e, se, number(round, "vertices"),
                      kept ? "kept" : "not kept");
        if (k > 0) {
            assert_int_equal(kept, e + se < best_error);
            if (kept) {
                best_error = e;
                expected = k;
            }
        }
        assert_true(fabs(number(round, "vertices") - first_vertices) <= 0.02 * first_vertices);
    }
    assert_int_equal(chosen, expected);
    const cJSON *best = cJSON_GetArrayItem(rounds, (int)chosen);
    assert_true(number(best, "error") == best_error);
    assert_true(number(refine, "error") <= first);
    assert_int_equal(check_report_against_output(r.report, s, r.out),
                     (uint64_t)number(best, "vertices"));
    /* the written scene, rendered as the rounds were measured */
    const cJSON *check = object(refine, "check_render");
    float *images[2][2];
    const scene *scenes[2] = {s, r.out};
    unsigned int width = 0, height = 0;
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 2; k++) {
            render_options ro;
            render_options_default(&ro);
            ro.sppm.iterations = (unsigned int)number(check, "iterations");
            ro.sppm.photons = (unsigned int)number(check, "photons");
            ro.sppm.resolution = (float)number(check, "resolution");
            ro.sppm.radius = number(check, "first_radius");
            ro.sppm.seed = 1 + (unsigned int)k;
            ro.sppm.progress = 0;
            render_result rr;
            test_run_render(scenes[i], NULL, &ro, &rr);
            images[i][k] = rr.image;
            width = rr.sppm.width;
            height = rr.sppm.height;
            rr.image = NULL;
            render_result_free(&rr);
        }
    image_paired_error e;
    image_paired_error_of(images[0][0], images[0][1], images[1][0], images[1][1], (int)width,
                          (int)height, 0, &e);
    print_message("  written scene: %g (round %u: %g)\n", e.rmse, chosen, number(best, "error"));
    /* the same up to the written files' rounding (the PLY's floats): 2e-10 of 0.02 seen */
    assert_near(e.rmse, number(best, "error"), 1e-4 * number(best, "error"));
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < 2; k++)
            free(images[i][k]);
    reduction_free(&r);
    scene_free(s);
    remove_tree(dir);
}

/* reduction_run() with what it prints on stderr into *text (freed by the caller). */
static void reduction_run_capturing(reduction *r, scene *s, const reduce_options *o, char **text)
{
    char path[] = "/tmp/test_error_budget_stderr_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    dup2(fd, STDERR_FILENO);
    reduction_run(r, s, o);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    FILE *file = fdopen(fd, "r");
    fseek(file, 0, SEEK_END);
    long length = ftell(file);
    fseek(file, 0, SEEK_SET);
    *text = calloc((size_t)(length > 0 ? length : 0) + 1, 1);
    size_t got = fread(*text, 1, (size_t)(length > 0 ? length : 0), file);
    (*text)[got] = '\0';
    fclose(file);
    unlink(path);
}

/* --refine warns where round 0's check renders see the change too faintly to refine by (its
 * standard error above half its error: the sphere kept at D = 0.9, whose change is within the
 * check renders' noise), and not where they see it (D = 0.05, the change some 20 standard
 * errors). */
static void test_refine_warns_when_faint(void **state)
{
    char dir[64], path[128];
    write_sphere_scene(dir, sizeof dir, path, sizeof path);
    scene *s = test_load_scene(path);
    const double targets[2] = {0.9, 0.05};
    for (int k = 0; k < 2; k++) {
        reduce_options o;
        small_options(&o);
        o.target = targets[k];
        o.refine = 1;
        o.error.iterations = 4;
        o.error.photons = 20000;
        o.error.resolution = 0.25;
        reduction r;
        char *text;
        reduction_run_capturing(&r, s, &o, &text);
        const cJSON *round0 = cJSON_GetArrayItem(object(object(r.report, "refine"), "rounds"), 0);
        double e = number(round0, "error"), se = number(round0, "standard_error");
        int faint = !(se <= 0.5 * e);
        print_message("  D = %g: round 0 %g \u00b1 %g, %s\n", targets[k], e, se,
                      faint ? "faint" : "seen");
        assert_int_equal(faint, k == 0);
        assert_int_equal(strstr(text, "too faintly to tell a better round") != NULL, faint);
        free(text);
        reduction_free(&r);
    }
    scene_free(s);
    remove_tree(dir);
}

static void test_refine_refused(void **state)
{
    scene *s = test_load_scene(CORNELL);
    char dir[64];
    temp_dir(dir, sizeof dir);
    char out[128];
    snprintf(out, sizeof out, "%s/out", dir);
    reduce_options o;
    small_options(&o);
    o.refine = 1;
    o.method = REDUCE_QUADRIC;
    expect_input_error(s, out, &o, "--refine moves importance");
    small_options(&o);
    o.refine = 1;
    o.passes = 2;
    expect_input_error(s, out, &o, "--refine mixes");
    small_options(&o);
    o.refine = REDUCE_MAX_REFINE + 1;
    expect_input_error(s, out, &o, "--refine must be");
    assert_false(file_exists(dir, "out"));
    remove_tree(dir);
    scene_free(s);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_search_on_curve),
        cmocka_unit_test(test_search_counts_standard_error),
        cmocka_unit_test(test_search_interpolates),
        cmocka_unit_test(test_search_any_curve),
        cmocka_unit_test(test_search_bounds),
        cmocka_unit_test(test_search_refusals),
        cmocka_unit_test(test_paired_exact),
        cmocka_unit_test(test_paired_correlated_unbiased),
        cmocka_unit_test(test_refine_weights_by_hand),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_max_error_sphere),
        cmocka_unit_test(test_max_error_glass_caustic),
        cmocka_unit_test(test_max_error_ends),
        cmocka_unit_test(test_max_error_refused),
        cmocka_unit_test(test_correlated_real_pair),
        cmocka_unit_test(test_refine_keeps_the_better),
        cmocka_unit_test(test_refine_warns_when_faint),
        cmocka_unit_test(test_refine_refused),
    };
    return DEVICE_TEST_MAIN("error_budget", host_tests, tests, NULL, NULL);
}
