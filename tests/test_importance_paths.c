/* test_importance_paths.c — the importance pass's gather count and path pass (kernels/sppm.cl,
 * kernels/lib/hit_point_grid.h) against host recomputations from a snapshot of one iteration:
 *
 *   gather count   per stored photon vertex, the number of valid hit points within the radius
 *                  on the same side, by brute force over all hit points
 *   path pass      each path walked backwards with the running sum of gather counts, in the
 *                  kernels' integers: equal to the last bit
 *   path layout    path p at p·8 .. p·8 + len - 1, each vertex on its triangle's plane with
 *                  that triangle's normal, weight in [0, 1]
 *
 * on the shipped Cornell box (64 x 64 hit points, 20k photons) and on Bitterli's glass of water
 * from ../shared/data (glass, water, ice and glossy surfaces; hit points at 1/20 of the film,
 * 64 x 36): camera and photon paths through dielectrics, hit points behind them. Each scene
 * runs once per device; each test checks one formula on that run. */
#include "importance_common.h"

static scene *cornell_scene(void)
{
    return test_load_scene(CORNELL_SCENE);
}

static scene *glass_of_water_scene(void)
{
    scene *s = test_load_scene(GLASS_OF_WATER_SCENE);
    assert_true(s->features & IDMR_FEATURE_DIELECTRIC);
    return s;
}

static imp_run cornell_run, glass_of_water_run;

static const imp_run *cornell(void)
{
    importance_options o;
    imp_small_options(&o, 1, 20000);
    o.sppm.resolution = 0.25f; /* 256 x 256 film -> 64 x 64 hit points */
    return imp_run_once(&cornell_run, cornell_scene, &o);
}

static const imp_run *glass_of_water(void)
{
    importance_options o;
    imp_small_options(&o, 1, 20000);
    o.sppm.resolution = 0.05f;
    return imp_run_once(&glass_of_water_run, glass_of_water_scene, &o);
}

/* ---- formulas ---- */

/* Valid hit points, more than half of the pixels. */
static void expect_most_pixels_valid(const importance_snapshot *snap)
{
    unsigned int pixels = snap->core.params.width * snap->core.params.height, valid = 0;
    for (unsigned int i = 0; i < pixels; i++)
        valid += snap->core.hit_points[i].valid != 0;
    print_message("  %u of %u pixels hold a hit point\n", valid, pixels);
    assert_true(valid > pixels / 2);
}

/* Every stored vertex's gather count equals the brute-force count over all valid hit points
 * with the kernel's float test (|hp - v|² < r², hp normal · vertex normal > 1e-3); empty slots
 * hold 0. A disagreement is allowed only for a hit point within 1e-5 relative of the radius
 * (the device's dot() may round differently); there may be at most a handful. */
static void expect_gather_counts(const importance_snapshot *snap)
{
    const idmr_sppm_params *pp = &snap->core.params;
    unsigned int pixels = pp->width * pp->height, valid_count = 0;
    idmr_hit_point *valid = malloc(pixels * sizeof *valid);
    for (unsigned int i = 0; i < pixels; i++)
        if (snap->core.hit_points[i].valid)
            valid[valid_count++] = snap->core.hit_points[i];
    float r = pp->radius, r2 = r * r;
    size_t vertices = 0, mismatches = 0, boundary_disagreements = 0, nonzero = 0, empty_errors = 0;
    uint64_t total = 0;
    for (uint32_t path = 0; path < pp->path_count; path++)
        for (uint32_t j = 0; j < IDMR_PATH_VERTICES; j++) {
            size_t slot = (size_t)path * IDMR_PATH_VERTICES + j;
            if (j >= snap->core.path_length[path]) {
                empty_errors += snap->gathered[slot] != 0;
                continue;
            }
            const idmr_photon_vertex *v = &snap->vertices[slot];
            uint32_t count = 0, near = 0;
            for (unsigned int i = 0; i < valid_count; i++) {
                const idmr_hit_point *hp = &valid[i];
                float dx = hp->position[0] - v->position[0];
                float dy = hp->position[1] - v->position[1];
                float dz = hp->position[2] - v->position[2];
                float d2 = dx * dx + dy * dy + dz * dz;
                float side = hp->normal[0] * v->normal[0] + hp->normal[1] * v->normal[1] +
                             hp->normal[2] * v->normal[2];
                if (!(side > 1e-3f)) /* the kernel's side test (kernels/lib/hit_point_grid.h) */
                    continue;
                count += d2 < r2;
                near += fabsf(d2 - r2) <= 1e-5f * r2;
            }
            uint32_t on_device = snap->gathered[slot];
            vertices++;
            total += count;
            nonzero += count > 0;
            if (on_device == count)
                continue;
            uint32_t difference = on_device > count ? on_device - count : count - on_device;
            if (difference <= near)
                boundary_disagreements++;
            else if (mismatches++ < 5)
                print_message("  path %u vertex %u: device %u, brute force %u\n", path, j,
                              on_device, count);
        }
    print_message("  %u hit points, radius %.5g, %zu vertices, %zu gathering (%llu gathers); "
                  "%zu mismatches, %zu disagreements at the radius\n",
                  valid_count, r, vertices, nonzero, (unsigned long long)total, mismatches,
                  boundary_disagreements);
    free(valid);
    assert_int_equal(empty_errors, 0);
    assert_true(nonzero > vertices / 100); /* gathering is exercised */
    assert_int_equal(mismatches, 0);
    assert_true(boundary_disagreements <= 5);
}

/* Path p at p·8 .. p·8 + len - 1, len <= 8; each vertex on a triangle with area, on its plane
 * (within 1e-4 of the scene diagonal) with that triangle's normal (either side), weight in
 * [0, 1]; the result counts the stored vertices. */
static void expect_path_layout(const imp_run *run)
{
    const scene *s = run->s;
    const importance_snapshot *snap = &run->snapshot;
    double diagonal = scene_diagonal(s);
    size_t vertices = 0, long_paths = 0, empty = 0;
    for (uint32_t path = 0; path < snap->core.params.path_count; path++) {
        uint32_t length = snap->core.path_length[path];
        assert_true(length <= IDMR_PATH_VERTICES);
        empty += length == 0;
        long_paths += length == IDMR_PATH_VERTICES;
        vertices += length;
        const idmr_photon_vertex *v = &snap->vertices[(size_t)path * IDMR_PATH_VERTICES];
        for (uint32_t j = 0; j < length; j++) {
            assert_true(v[j].triangle < s->triangle_count);
            assert_true(scene_triangle_area(s, v[j].triangle) > 0);
            assert_true(v[j].weight >= 0.0f && v[j].weight <= 1.0f);
            assert_true(fabs(imp_plane_distance(s, v[j].triangle, v[j].position)) <
                        1e-4 * diagonal);
            float n[3];
            imp_triangle_normal(s, v[j].triangle, n);
            assert_true(fabs(fabs(imp_dot(n, v[j].normal)) - 1.0) < 1e-5);
        }
    }
    print_message("  %u paths: %zu vertices, %zu empty, %zu of full length\n",
                  snap->core.params.path_count, vertices, empty, long_paths);
    assert_int_equal(run->r.sppm.photon_records, vertices);
}

/* Light importance recomputed from the snapshot: each path walked from its last vertex with
 * the running sum s of gather counts; vertex j adds round(weight_j · 2^20) · s (integers) to
 * its triangle. Must equal the device's accumulators bit for bit. */
static void expect_path_sums_exact(const imp_run *run)
{
    const importance_snapshot *snap = &run->snapshot;
    size_t triangles = (size_t)run->s->triangle_count;
    uint64_t *expected = calloc(triangles, sizeof *expected);
    for (uint32_t path = 0; path < snap->core.params.path_count; path++) {
        const idmr_photon_vertex *v = &snap->vertices[(size_t)path * IDMR_PATH_VERTICES];
        const uint32_t *gathered = &snap->gathered[(size_t)path * IDMR_PATH_VERTICES];
        uint64_t running = 0;
        for (int j = (int)snap->core.path_length[path] - 1; j >= 0; j--) {
            running += gathered[j];
            uint64_t units = (uint64_t)floor((double)v[j].weight * 1048576.0 + 0.5);
            if (v[j].triangle < triangles)
                expected[v[j].triangle] += units * running;
        }
    }
    size_t mismatches = 0, nonzero = 0;
    for (size_t t = 0; t < triangles; t++) {
        nonzero += expected[t] != 0;
        if (expected[t] != snap->light_fixed[t] && mismatches++ < 5)
            print_message("  triangle %zu: device %llu, host %llu\n", t,
                          (unsigned long long)snap->light_fixed[t],
                          (unsigned long long)expected[t]);
    }
    print_message("  %zu triangles with light importance, %zu mismatches\n", nonzero, mismatches);
    free(expected);
    assert_int_equal(mismatches, 0);
    assert_true(nonzero > 100);
}

/* One iteration: the result's sums are the accumulators. */
static void expect_result_is_the_accumulators(const imp_run *run)
{
    for (size_t t = 0; t < run->r.triangle_count; t++) {
        assert_true(run->r.light[t] == (double)run->snapshot.light_fixed[t] * IMP_FIXED_UNIT);
        assert_true(run->r.camera[t] == (double)run->snapshot.camera_fixed[t] * IMP_FIXED_UNIT);
    }
}

/* ---- the Cornell box ---- */

static void test_cornell_most_pixels_hold_hit_points(void **state)
{
    const imp_run *run = cornell();
    assert_int_equal(run->snapshot.core.params.width, 64);
    assert_int_equal(run->snapshot.core.params.height, 64);
    expect_most_pixels_valid(&run->snapshot);
}

/* The radius of the first iteration: 5 x scene diagonal / (width + height). */
static void test_cornell_first_radius(void **state)
{
    const imp_run *run = cornell();
    float radius = run->snapshot.core.params.radius;
    assert_float_equal(radius, 5.0 * scene_diagonal(run->s) / (64 + 64), 1e-5 * radius);
}

static void test_cornell_gather_counts_match_brute_force(void **state)
{
    expect_gather_counts(&cornell()->snapshot);
}

static void test_cornell_path_layout(void **state)
{
    expect_path_layout(cornell());
}

static void test_cornell_path_sums_exact(void **state)
{
    expect_path_sums_exact(cornell());
}

static void test_cornell_result_is_the_accumulators(void **state)
{
    expect_result_is_the_accumulators(cornell());
}

/* ---- the glass of water ---- */

static void test_glass_of_water_most_pixels_hold_hit_points(void **state)
{
    expect_most_pixels_valid(&glass_of_water()->snapshot);
}

static void test_glass_of_water_gather_counts_match_brute_force(void **state)
{
    expect_gather_counts(&glass_of_water()->snapshot);
}

static void test_glass_of_water_path_layout(void **state)
{
    expect_path_layout(glass_of_water());
}

static void test_glass_of_water_path_sums_exact(void **state)
{
    expect_path_sums_exact(glass_of_water());
}

static void test_glass_of_water_result_is_the_accumulators(void **state)
{
    expect_result_is_the_accumulators(glass_of_water());
}

static int group_teardown(void **state)
{
    imp_run_free(&cornell_run);
    imp_run_free(&glass_of_water_run);
    return 0;
}

int main(void)
{
    static const device_test tests[] = {
        DEVICE_TEST(test_cornell_most_pixels_hold_hit_points),
        DEVICE_TEST(test_cornell_first_radius),
        DEVICE_TEST(test_cornell_gather_counts_match_brute_force),
        DEVICE_TEST(test_cornell_path_layout),
        DEVICE_TEST(test_cornell_path_sums_exact),
        DEVICE_TEST(test_cornell_result_is_the_accumulators),
        DEVICE_TEST(test_glass_of_water_most_pixels_hold_hit_points),
        DEVICE_TEST(test_glass_of_water_gather_counts_match_brute_force),
        DEVICE_TEST(test_glass_of_water_path_layout),
        DEVICE_TEST(test_glass_of_water_path_sums_exact),
        DEVICE_TEST(test_glass_of_water_result_is_the_accumulators),
    };
    return DEVICE_TEST_RUN("importance paths", tests, NULL, group_teardown) != 0;
}
