/* test_importance_driver.c — the importance pass's iteration driver (host/passes/importance.c
 * on the SPPM core, host/passes/sppm.c): the convergence measure Δ, the early stop, the radius
 * schedule and the input errors, on the hidden-wall scene of importance_common.h (white wall).
 *
 *   Δ_n = Σ (I_n - I_{n-1})² / Σ I_n² over triangles with area, I_n the per-area importance
 *         after n iterations; Δ_1 = 1
 *   stop  with a tolerance, at the first iteration that ends 3 calm ones in a row (Δ < tol)
 *   radii r_{n+1}² = r_n² (n + α) / (n + 1) from r_1 = 5 × diagonal / (width + height) */
#include "importance_common.h"

static scene *white_wall_scene(void)
{
    return imp_hidden_wall_scene(0.9f);
}

static imp_run one_run, two_run, stopping_run;

/* The same seed, 1 and 2 iterations (the first iteration is the same in both). */
static const imp_run *iterations(unsigned int n)
{
    importance_options o;
    imp_small_options(&o, n, 20000);
    return imp_run_once(n == 1 ? &one_run : &two_run, white_wall_scene, &o);
}

/* Up to 60 iterations with tolerance 1e-3. */
static const imp_run *stopping(void)
{
    importance_options o;
    imp_small_options(&o, 60, 20000);
    o.tolerance = 1e-3;
    return imp_run_once(&stopping_run, white_wall_scene, &o);
}

static void test_first_delta_is_one(void **state)
{
    assert_true(iterations(1)->r.convergence[0] == 1.0);
    assert_true(iterations(2)->r.convergence[0] == 1.0);
    assert_true(stopping()->r.convergence[0] == 1.0);
}

/* Δ_2 recomputed on the host from the 1- and 2-iteration runs. */
static void test_second_delta_matches_the_host(void **state)
{
    const imp_run *one = iterations(1), *two = iterations(2);
    double change = 0, magnitude = 0;
    for (size_t t = 0; t < two->s->triangle_count; t++) {
        double area = scene_triangle_area(two->s, t);
        double now = (two->r.camera[t] + two->r.light[t]) / (2 * area);
        double before = (one->r.camera[t] + one->r.light[t]) / area;
        change += (now - before) * (now - before);
        magnitude += now * now;
    }
    print_message("  Δ_2 host %.6e, device run %.6e\n", change / magnitude,
                  two->r.convergence[1]);
    assert_float_equal(two->r.convergence[1], change / magnitude, 1e-9 * change / magnitude);
}

/* The run stops before its 60 iterations, at the first iteration that ends 3 calm ones. */
static void test_stops_after_three_calm_iterations(void **state)
{
    const imp_run *run = stopping();
    int calm = 0, stop = 0;
    for (unsigned int n = 0; n < run->r.sppm.iterations; n++) {
        assert_true(isfinite(run->r.convergence[n]) && run->r.convergence[n] >= 0);
        calm = run->r.convergence[n] < run->options.tolerance ? calm + 1 : 0;
        if (calm == 3 && !stop)
            stop = (int)n + 1;
    }
    print_message("  tolerance %.0e: stopped after %u of %u iterations; last Δ %.3g\n",
                  run->options.tolerance, run->r.sppm.iterations, run->options.sppm.iterations,
                  run->r.convergence[run->r.sppm.iterations - 1]);
    assert_true(run->r.sppm.iterations < run->options.sppm.iterations);
    assert_int_equal(stop, (int)run->r.sppm.iterations);
}

static void test_radius_schedule(void **state)
{
    const imp_run *run = stopping();
    const sppm_summary *summary = &run->r.sppm;
    double r1 = 5.0 * scene_diagonal(run->s) / (summary->width + summary->height), r2 = r1 * r1;
    assert_true(summary->iterations > 1);
    for (unsigned int n = 0; n < summary->iterations; n++) {
        assert_float_equal(summary->radius[n], sqrt(r2), 1e-6 * sqrt(r2));
        r2 *= (n + 1 + run->options.sppm.alpha) / (n + 2.0);
    }
}

/* A quad with either a point light or a camera, not both. */
static scene *incomplete_scene(const char *file, int with_light)
{
    scene *s = scene_create(file);
    uint32_t white = imp_diffuse(s, "white", 0.8f, 0);
    const float c[3] = {0, 0, 0}, u[3] = {1, 0, 0}, v[3] = {0, 1, 0};
    imp_add_quad(s, "quad", white, c, u, v);
    const float light[3] = {0, 0, 2}, eye[3] = {0, 0, 3}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    if (with_light)
        imp_point_light(s, light, 1.0f);
    else
        imp_look_at(s, eye, target, up, 16, 16, 0.5f);
    return test_finalize_scene(s);
}

/* importance_run() refuses the scene: IDMR_EXIT_INPUT, and the message names the file. */
static void expect_input_error(const char *file, int with_light)
{
    scene *s = incomplete_scene(file, with_light);
    bvh b;
    test_build_bvh(s, &b);
    importance_options o;
    imp_small_options(&o, 1, 1000);
    importance_result r;
    error_clear();
    int status = importance_run(device_test_device(), s, &b, &o, &r);
    print_message("  %s\n", error_message());
    importance_result_free(&r);
    bvh_free(&b);
    scene_free(s);
    assert_int_equal(status, -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), file));
}

static void test_missing_camera_is_an_input_error(void **state)
{
    expect_input_error("tests/no-camera-scene.xml", 1);
}

static void test_missing_light_is_an_input_error(void **state)
{
    expect_input_error("tests/no-light-scene.xml", 0);
}

static int group_teardown(void **state)
{
    imp_run_free(&one_run);
    imp_run_free(&two_run);
    imp_run_free(&stopping_run);
    return 0;
}

int main(void)
{
    static const device_test tests[] = {
        DEVICE_TEST(test_first_delta_is_one),
        DEVICE_TEST(test_second_delta_matches_the_host),
        DEVICE_TEST(test_stops_after_three_calm_iterations),
        DEVICE_TEST(test_radius_schedule),
        DEVICE_TEST(test_missing_camera_is_an_input_error),
        DEVICE_TEST(test_missing_light_is_an_input_error),
    };
    return DEVICE_TEST_RUN("importance driver", tests, NULL, group_teardown) != 0;
}
