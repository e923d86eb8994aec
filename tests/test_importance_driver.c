/* test_importance_driver.c — the importance pass's iteration driver (host/passes/importance.c
 * on the SPPM core, host/passes/sppm.c): the convergence measure Δ, the early stop, the radius
 * schedule and the input errors, on the hidden-wall scene of importance_common.h (white wall).
 *
 *   Δ_n = Σ (I_n - I_{n-1})² / Σ I_n² over triangles with area, I_n the per-area importance
 *         after n iterations; Δ_1 = 1
 *   stop  with a tolerance, at the first iteration that ends 3 calm ones in a row (Δ < tol)
 *   radii r_{n+1}² = r_n² (n + α) / (n + 1) from r_1 = 2.5 pixel footprints at the median hit
 *         point distance, also on a close-up of a large floor, where the old scene-diagonal
 *         rule would have gathered over a sixth of the image
 *   γ     means the same at two hit-point resolutions (the meshes' shares agree within 10 %) */
#include "importance_common.h"

static scene *white_wall_scene(void)
{
    return imp_hidden_wall_scene(0.9f);
}

/* The same seed, 1 and 2 iterations (the first iteration is the same in both), and up to 60
 * iterations with tolerance 1e-3. */
static imp_case one = {.make = white_wall_scene, .iterations = 1, .photons = 20000};
static imp_case two = {.make = white_wall_scene, .iterations = 2, .photons = 20000};
static imp_case stopping = {
    .make = white_wall_scene, .iterations = 60, .photons = 20000, .tolerance = 1e-3};

static void test_first_delta_is_one(void **state)
{
    assert_true(imp_run(&one)->r.convergence[0] == 1.0);
    assert_true(imp_run(&two)->r.convergence[0] == 1.0);
    assert_true(imp_run(&stopping)->r.convergence[0] == 1.0);
}

/* Δ_2 recomputed on the host from the 1- and 2-iteration runs. */
static void test_second_delta_matches_the_host(void **state)
{
    const imp_case *first = imp_run(&one), *second = imp_run(&two);
    importance_weights w = importance_weights_of(&second->options);
    double change = 0, magnitude = 0;
    for (size_t t = 0; t < second->s->triangle_count; t++) {
        double now = importance_triangle(&second->r, second->s, &w, t);
        double before = importance_triangle(&first->r, first->s, &w, t);
        change += (now - before) * (now - before);
        magnitude += now * now;
    }
    print_message("  Δ_2 host %.6e, device run %.6e\n", change / magnitude,
                  second->r.convergence[1]);
    assert_float_equal(second->r.convergence[1], change / magnitude, 1e-9 * change / magnitude);
}

/* The run stops before its 60 iterations, at the first iteration that ends 3 calm ones. */
static void test_stops_after_three_calm_iterations(void **state)
{
    const imp_case *run = imp_run(&stopping);
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
    const imp_case *run = imp_run(&stopping);
    const sppm_summary *summary = &run->r.sppm;
    double r2 = summary->radius[0] * summary->radius[0];
    assert_true(summary->iterations > 1);
    for (unsigned int n = 0; n < summary->iterations; n++) {
        assert_float_equal(summary->radius[n], sqrt(r2), 1e-6 * sqrt(r2));
        r2 *= (n + 1 + run->options.sppm.alpha) / (n + 2.0);
    }
}

/* A 20 x 20 floor seen from 1 unit above, straight down, 90 degrees wide: the camera sees a
 * patch 2 units across, a tenth of the floor, lit by a point light above. */
static scene *close_up_scene(void)
{
    scene *s = scene_create("close-up floor");
    const float centre[3] = {0, 0, 0}, u[3] = {10, 0, 0}, v[3] = {0, 0, -10};
    imp_add_quad(s, "floor", imp_diffuse(s, "grey", 0.5f, 0), centre, u, v);
    const float light[3] = {0, 5, 0}, eye[3] = {0, 1, 0}, up[3] = {0, 0, -1};
    imp_point_light(s, light, 20.0f);
    imp_look_at(s, eye, centre, up, 64, 64, 1.0f);
    return test_finalize_scene(s);
}

static imp_case close_up = {.make = close_up_scene, .iterations = 1, .photons = 20000};

/* On the close-up every pixel sees the floor at distance 1 / cos θ: the first radius is 2.5 times
 * the median of that times the pixel angle 2 / 64, computed from the pixel centres (the jitter
 * moves the median by well under 1 %), and far below the scene-diagonal rule's. */
static void test_close_up_radius_follows_the_view(void **state)
{
    const imp_case *run = imp_run(&close_up);
    const idmr_camera *c = &run->s->camera;
    double distance[64 * 64];
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            float d[3];
            idmr_camera_direction(c, x + 0.5f, y + 0.5f, d);
            double length = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
            distance[y * 64 + x] = length / -d[1]; /* height 1 over the floor, looking down */
        }
    qsort(distance, 64 * 64, sizeof *distance, imp_compare_doubles);
    double expected = 2.5 * distance[64 * 64 / 2] * 2.0 / 64;
    double diagonal_rule = 5.0 * scene_diagonal(run->s) / (64 + 64);
    double r1 = run->r.sppm.radius[0];
    print_message("  close-up: first radius %.5f, expected %.5f; the diagonal rule's %.4f\n", r1,
                  expected, diagonal_rule);
    assert_int_equal(run->r.sppm.hit_points, 64 * 64);
    assert_float_equal(r1, expected, 0.01 * expected);
    assert_true(r1 < diagonal_rule / 10);
}

/* The shipped Cornell box at two hit-point resolutions, 16 x 16 and 32 x 32 pixels per 256, with
 * the same photons: camera and shadow importance are taken per pixel and light importance per
 * photon path, so γ means the same at both and the meshes' shares of the importance agree. */
static scene *cornell_box(void) { return test_load_scene(CORNELL_SCENE); }
static imp_case coarse = {.make = cornell_box, .iterations = 8, .photons = 40000, .resolution = 0.125f};
static imp_case fine = {.make = cornell_box, .iterations = 8, .photons = 40000, .resolution = 0.25f};

static void test_gamma_means_the_same_at_any_resolution(void **state)
{
    const imp_case *a = imp_run(&coarse), *b = imp_run(&fine);
    importance_weights w = importance_weights_of(&a->options);
    double total_a = 0, total_b = 0, share_a[16], share_b[16];
    size_t meshes = a->s->mesh_count;
    assert_true(meshes <= 16);
    for (size_t m = 0; m < meshes; m++) {
        share_a[m] = importance_mesh_sums(&a->r, a->s, m, &w).amount;
        share_b[m] = importance_mesh_sums(&b->r, b->s, m, &w).amount;
        total_a += share_a[m];
        total_b += share_b[m];
    }
    assert_true(a->r.sppm.width * 2 == b->r.sppm.width);
    for (size_t m = 0; m < meshes; m++) {
        share_a[m] /= total_a;
        share_b[m] /= total_b;
        print_message("  %-10s share %.4f at %ux%u, %.4f at %ux%u\n", a->s->meshes[m].name,
                      share_a[m], a->r.sppm.width, a->r.sppm.height, share_b[m],
                      b->r.sppm.width, b->r.sppm.height);
        if (share_b[m] > 0.05)
            assert_float_equal(share_a[m], share_b[m], 0.1 * share_b[m]);
    }
    /* The totals too: the same γ gives the same importance per sample. */
    assert_float_equal(total_a, total_b, 0.1 * total_b);
}

/* A quad with either a point light or a camera, not both: importance_run() refuses it, and the
 * message names the scene file. */
static void expect_refused(const char *file, int with_light)
{
    scene *s = scene_create(file);
    imp_add_quad(s, "quad", imp_diffuse(s, "white", 0.8f, 0), V3(0, 0, 0), V3(1, 0, 0),
                 V3(0, 1, 0));
    if (with_light)
        imp_point_light(s, V3(0, 0, 2), 1.0f);
    else
        imp_look_at(s, V3(0, 0, 3), V3(0, 0, 0), V3(0, 1, 0), 16, 16, 0.5f);
    test_expect_refused(s, 0, file);
}

static void test_missing_camera_is_an_input_error(void **state)
{
    expect_refused("tests/no-camera-scene.xml", 1);
}

static void test_missing_light_is_an_input_error(void **state)
{
    expect_refused("tests/no-light-scene.xml", 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_delta_is_one),
        cmocka_unit_test(test_second_delta_matches_the_host),
        cmocka_unit_test(test_stops_after_three_calm_iterations),
        cmocka_unit_test(test_radius_schedule),
        cmocka_unit_test(test_close_up_radius_follows_the_view),
        cmocka_unit_test(test_gamma_means_the_same_at_any_resolution),
        cmocka_unit_test(test_missing_camera_is_an_input_error),
        cmocka_unit_test(test_missing_light_is_an_input_error),
    };
    return DEVICE_TEST_RUN("importance driver", tests, NULL, imp_teardown) != 0;
}
