/* test_numeric_stress.c — numbers at their limits, run to the end:
 *
 *   long run     10,000 importance iterations on a quad seen head-on: the camera importance is
 *                the sum of Eq. 2 over every iteration's camera rays, worked out on the host
 *                (the 64-bit fixed-point accumulators are drained into double sums each
 *                iteration: nothing saturates), and the gather radius after 10,000 iterations
 *                is positive, finite and the host's recurrence r²(n+1) = r²(n)(n+1+α)/(n+2)
 *   grid cells   the hash grid's cells for a tiny radius in a scene reaching the coordinate
 *                limit: never numbered beyond 2^60 (no saturation, no merged cells), never
 *                narrower than the gather ball
 *
 * The factor distribution over 10,000 meshes with importance from 1e-30 to 1e30 is in
 * test_budget.c; scenes scaled to 1e-8 and 1e8 and geometry 3e10 away in
 * test_importance_invariants.c. */
#include "importance_common.h"

#include "passes/hit_point_grid.h"
#include "passes/sppm.h"

#define LONG_RUN_ITERATIONS 10000u
#define LONG_RUN_WIDTH 16u
#define LONG_RUN_HEIGHT 12u

/* A quad 20 x 20 at z = 0 filling the view of a camera at z = 5, a point light over it. */
static scene *long_run_scene(void)
{
    scene *s = scene_create("long-run.xml");
    imp_add_quad(s, "quad", imp_diffuse(s, "white", 0.8f, 0), V3(0, 0, 0), V3(10, 0, 0),
                 V3(0, 10, 0));
    imp_point_light(s, V3(0, 0, 3), 1.0f);
    imp_look_at(s, V3(0, 0, 5), V3(0, 0, 0), V3(0, 1, 0), LONG_RUN_WIDTH, LONG_RUN_HEIGHT, 0.5f);
    return test_finalize_scene(s);
}

static imp_case long_run = {.make = long_run_scene, .iterations = LONG_RUN_ITERATIONS,
                            .photons = 64, .resolution = 1.0f, .without_shadows = 1};

static void test_long_run_camera_importance_is_eq2(void **state)
{
    const imp_case *run = imp_run(&long_run);
    assert_int_equal(run->r.sppm.iterations, LONG_RUN_ITERATIONS);
    const float n[3] = {0, 0, 1};
    double expected = 0;
    for (unsigned int i = 0; i < LONG_RUN_ITERATIONS; i++)
        for (unsigned int p = 0; p < LONG_RUN_WIDTH * LONG_RUN_HEIGHT; p++) {
            float d[3];
            imp_camera_direction(&run->s->camera, LONG_RUN_WIDTH, LONG_RUN_HEIGHT,
                                 run->options.sppm.seed, i, p, d);
            expected += idmr_eq2_weight(n[0], n[1], n[2], d[0], d[1], d[2]);
        }
    double on_device = run->r.camera[0] + run->r.camera[1];
    double adds = (double)LONG_RUN_ITERATIONS * LONG_RUN_WIDTH * LONG_RUN_HEIGHT;
    double bound = adds * (0.5 * IMP_FIXED_UNIT + 1e-6);
    print_message("  camera importance after %u iterations: device %.6f, host %.6f (bound "
                  "%.2e)\n",
                  LONG_RUN_ITERATIONS, on_device, expected, bound);
    assert_true(expected > 1000);
    assert_true(fabs(on_device - expected) <= bound);
}

static void test_long_run_radius_follows_the_recurrence(void **state)
{
    const imp_case *run = imp_run(&long_run);
    const double *radius = run->r.sppm.radius;
    double radius2 = radius[0] * radius[0];
    for (unsigned int i = 1; i < LONG_RUN_ITERATIONS; i++) {
        radius2 = sppm_next_radius2(radius2, i - 1, run->options.sppm.alpha);
        if (!(radius[i] > 0 && isfinite(radius[i])) ||
            fabs(radius[i] - sqrt(radius2)) > 1e-6 * sqrt(radius2))
            fail_msg("iteration %u: radius %g, the recurrence gives %g", i, radius[i],
                     sqrt(radius2));
    }
    double last = radius[LONG_RUN_ITERATIONS - 1];
    print_message("  radius %g at the first iteration, %g after %u\n", radius[0], last,
                  LONG_RUN_ITERATIONS);
    assert_true(last < radius[0]); /* it shrank, as α < 1 makes it */
}

/* A scene box from -limit to +limit on every axis, and nothing else hit_point_grid_place reads. */
static void grid_cells_for(double limit, double radius, idmr_sppm_params *params)
{
    scene *s = scene_create("grid.xml");
    for (int k = 0; k < 3; k++) {
        s->bbox_min[k] = (float)-limit;
        s->bbox_max[k] = (float)limit;
    }
    hit_point_grid g = {0};
    g.cells = 1024;
    memset(params, 0, sizeof *params);
    hit_point_grid_place(&g, s, radius * radius, params);
    scene_free(s);
}

static void test_grid_cells_never_saturate(void **state)
{
    const double limits[] = {1e-8, 1.0, 1e5, SCENE_COORDINATE_LIMIT};
    const double radii[] = {1e-12, 1e-6, 1e-2, 1.0};
    for (size_t a = 0; a < 4; a++)
        for (size_t b = 0; b < 4; b++) {
            idmr_sppm_params params;
            grid_cells_for(limits[a], radii[b], &params);
            double cell = params.cell_size, reach = limits[a] + params.radius;
            if (!(cell >= 2.0 * params.radius) || !(reach / cell <= HIT_POINT_GRID_MAX_CELL))
                fail_msg("scene to %g, radius %g: cell %g, %g cells out", limits[a], radii[b],
                         cell, reach / cell);
        }
    /* Cells stay 2r (and a little more) where floats are fine enough. */
    idmr_sppm_params params;
    grid_cells_for(10.0, 1e-2, &params);
    assert_float_equal(params.cell_size, (2e-2 + ldexp(10.0 + 1e-2, -22)) * 1.0001, 1e-8);
}

/* A gather reads the cells of p - r and p + r only (kernels/lib/hit_point_grid.h,
 * grid_buckets_near), computed in float as the kernel does: they must be the same cell or
 * neighbours for every p of the scene, also where the radius is as small as the floats'
 * spacing (there, cells of exactly 2r let the two fall 2 cells apart and a hit point at p itself
 * was missed). */
static void test_grid_ball_reaches_neighbouring_cells_only(void **state)
{
    const double limits[] = {1.0, 1e5, 3e7};
    const double radii[] = {1e-2, 4e-3, 1e-3, 1e-7};
    size_t apart = 0, points = 0;
    for (size_t a = 0; a < 3; a++)
        for (size_t b = 0; b < 4; b++) {
            idmr_sppm_params params;
            grid_cells_for(limits[a], radii[b], &params);
            float r = params.radius, cell = params.cell_size;
            /* points up to the scene's edge, many of them where floats are coarsest */
            for (int i = 0; i < 200000; i++) {
                float p = (float)(limits[a] * (1.0 - (double)i / 1e7));
                volatile float low = p - r, high = p + r; /* rounded to float, as the kernel */
                volatile float low_cells = low / cell, high_cells = high / cell;
                long lo = (long)floorf(low_cells), hi = (long)floorf(high_cells);
                points++;
                if (hi - lo > 1 && apart++ < 3)
                    print_message("  scene to %g, radius %g: p %.9g in cells %ld .. %ld\n",
                                  limits[a], radii[b], p, lo, hi);
            }
        }
    print_message("  %zu points, %zu whose ball reaches more than 2 cells on an axis\n", points,
                  apart);
    assert_int_equal(apart, 0);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_grid_cells_never_saturate),
        cmocka_unit_test(test_grid_ball_reaches_neighbouring_cells_only),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_long_run_camera_importance_is_eq2),
        cmocka_unit_test(test_long_run_radius_follows_the_recurrence),
    };
    return DEVICE_TEST_MAIN("numeric stress", host_tests, tests, NULL, imp_teardown);
}
