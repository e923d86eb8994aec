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

/* 256 x 256 film -> 64 x 64 hit points; 1280 x 720 -> 64 x 36. */
static imp_case cornell = {
    .make = cornell_scene, .iterations = 1, .photons = 20000, .resolution = 0.25f};
static imp_case glass_of_water = {
    .make = glass_of_water_scene, .iterations = 1, .photons = 20000, .resolution = 0.05f};

/* ---- formulas, each a test of a case (IMP_CASE_TEST) ---- */

/* Valid hit points, more than half of the pixels. */
static void test_most_pixels_hold_hit_points(void **state)
{
    const importance_snapshot *snap = &imp_run_state(state)->snapshot;
    unsigned int pixels = snap->core.params.width * snap->core.params.height, valid = 0;
    for (unsigned int i = 0; i < pixels; i++)
        valid += snap->core.hit_points[i].offset > 0.0f;
    print_message("  %u of %u pixels hold a hit point\n", valid, pixels);
    assert_true(valid > pixels / 2);
}

/* The valid hit points of a snapshot into a new array; *count gets how many. */
static idmr_hit_point *valid_hit_points(const importance_snapshot *snap, unsigned int *count)
{
    unsigned int pixels = snap->core.params.width * snap->core.params.height;
    idmr_hit_point *valid = malloc(pixels * sizeof *valid);
    *count = 0;
    for (unsigned int i = 0; i < pixels; i++)
        if (snap->core.hit_points[i].offset > 0.0f)
            valid[(*count)++] = snap->core.hit_points[i];
    return valid;
}

/* The hit points that gather vertex v by the kernel's float test (kernels/lib/hit_point_grid.h:
 * |hp - v|² < r², hp normal · vertex normal > 1e-3); *near gets those within 1e-5 relative of
 * the radius, which the device's dot() may round to the other side. */
static uint32_t brute_force_gathers(const idmr_hit_point *valid, unsigned int count,
                                    const idmr_photon_vertex *v, float r2, uint32_t *near)
{
    uint32_t gathers = 0;
    *near = 0;
    for (unsigned int i = 0; i < count; i++) {
        const idmr_hit_point *hp = &valid[i];
        float dx = hp->position[0] - v->position[0];
        float dy = hp->position[1] - v->position[1];
        float dz = hp->position[2] - v->position[2];
        float d2 = dx * dx + dy * dy + dz * dz;
        float side = hp->normal[0] * v->normal[0] + hp->normal[1] * v->normal[1] +
                     hp->normal[2] * v->normal[2];
        if (!(side > 1e-3f))
            continue;
        gathers += d2 < r2;
        *near += fabsf(d2 - r2) <= 1e-5f * r2;
    }
    return gathers;
}

/* Every stored vertex's gather count equals the brute-force count over all valid hit points
 * (gather_count writes only those: empty slots are not looked at). A disagreement is allowed
 * only by hit points at the radius (brute_force_gathers); there may be at most a handful. */
static void test_gather_counts_match_brute_force(void **state)
{
    const importance_snapshot *snap = &imp_run_state(state)->snapshot;
    const idmr_sppm_params *pp = &snap->core.params;
    unsigned int valid_count;
    idmr_hit_point *valid = valid_hit_points(snap, &valid_count);
    size_t vertices = 0, mismatches = 0, boundary_disagreements = 0, nonzero = 0;
    for (size_t slot = 0; slot < (size_t)pp->path_count * IDMR_PATH_VERTICES; slot++) {
        uint32_t on_device = snap->gathered[slot], near;
        if (slot % IDMR_PATH_VERTICES >= snap->core.path_length[slot / IDMR_PATH_VERTICES])
            continue;
        uint32_t count = brute_force_gathers(valid, valid_count, &snap->vertices[slot],
                                             pp->radius * pp->radius, &near);
        vertices++;
        nonzero += count > 0;
        if (on_device == count)
            continue;
        if ((on_device > count ? on_device - count : count - on_device) <= near)
            boundary_disagreements++;
        else if (mismatches++ < 5)
            print_message("  slot %zu: device %u, brute force %u\n", slot, on_device, count);
    }
    print_message("  %u hit points, radius %.5g, %zu vertices, %zu gathering; %zu mismatches, "
                  "%zu disagreements at the radius\n",
                  valid_count, pp->radius, vertices, nonzero, mismatches, boundary_disagreements);
    free(valid);
    assert_true(nonzero > vertices / 100); /* gathering is exercised */
    assert_int_equal(mismatches, 0);
    assert_true(boundary_disagreements <= 5);
}

/* Path p at p·8 .. p·8 + len - 1, len <= 8; each vertex on a triangle with area, on its plane
 * (within 1e-4 of the scene diagonal) with that triangle's normal (either side), weight in
 * [0, 1]; the result counts the stored vertices. */
static void test_path_layout(void **state)
{
    const imp_case *run = imp_run_state(state);
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

/* The list of records the gathers run over (kernels/sppm.cl, photon_paths) holds each path's
 * records once: the record index sends every record of every path to its own place in the list,
 * and the list is exactly as long as the paths' records together. */
static void test_record_list_holds_every_record_once(void **state)
{
    const sppm_snapshot *core = &imp_run_state(state)->snapshot.core;
    size_t records = 0, misplaced = 0;
    uint8_t *taken = calloc(core->stored + 1, 1);
    assert_non_null(taken);
    for (size_t path = 0; path < core->params.device_paths; path++)
        for (size_t j = 0; j < core->path_length[path]; j++) {
            uint32_t at = core->record_index[path * IDMR_PATH_VERTICES + j];
            records++;
            if (at >= core->stored || taken[at]++)
                misplaced++;
        }
    free(taken);
    print_message("  %zu records, %zu in the list, %zu misplaced\n", records, core->stored,
                  misplaced);
    assert_int_equal(core->stored, records);
    assert_int_equal(misplaced, 0);
}

/* Light importance recomputed from the snapshot: each path walked from its last vertex with
 * the running sum s of gather counts; vertex j adds round(weight_j · 2^20) · s (integers) to
 * its triangle. Must equal the device's accumulators bit for bit. */
static void test_path_sums_exact(void **state)
{
    const imp_case *run = imp_run_state(state);
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
static void test_result_is_the_accumulators(void **state)
{
    const imp_case *run = imp_run_state(state);
    for (size_t t = 0; t < run->r.triangle_count; t++) {
        assert_true(run->r.light[t] == (double)run->snapshot.light_fixed[t] * IMP_FIXED_UNIT);
        assert_true(run->r.camera[t] == (double)run->snapshot.camera_fixed[t] * IMP_FIXED_UNIT);
    }
}

/* The radius of the first (here the only) iteration: 2.5 pixel footprints at the median
 * distance of its hit points. */
static void test_first_radius(void **state)
{
    const imp_case *run = imp_run_state(state);
    const idmr_sppm_params *pp = &run->snapshot.core.params;
    assert_int_equal(pp->iteration, 0);
    double expected = imp_expected_first_radius(run->s, run->snapshot.core.hit_points,
                                                (size_t)pp->width * pp->height, pp->width);
    assert_float_equal(pp->radius, expected, 1e-5 * expected);
}

/* The hit-point images: the films scaled by the cases' resolution. */
static void test_hit_point_images_are_scaled(void **state)
{
    const idmr_sppm_params *box = &imp_run(&cornell)->snapshot.core.params;
    const idmr_sppm_params *glass = &imp_run(&glass_of_water)->snapshot.core.params;
    assert_true(box->width == 64 && box->height == 64);
    assert_true(glass->width == 64 && glass->height == 36);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hit_point_images_are_scaled),
        IMP_CASE_TEST(test_most_pixels_hold_hit_points, cornell),
        IMP_CASE_TEST(test_first_radius, cornell),
        IMP_CASE_TEST(test_gather_counts_match_brute_force, cornell),
        IMP_CASE_TEST(test_path_layout, cornell),
        IMP_CASE_TEST(test_record_list_holds_every_record_once, cornell),
        IMP_CASE_TEST(test_path_sums_exact, cornell),
        IMP_CASE_TEST(test_result_is_the_accumulators, cornell),
        IMP_CASE_TEST(test_most_pixels_hold_hit_points, glass_of_water),
        IMP_CASE_TEST(test_first_radius, glass_of_water),
        IMP_CASE_TEST(test_gather_counts_match_brute_force, glass_of_water),
        IMP_CASE_TEST(test_path_layout, glass_of_water),
        IMP_CASE_TEST(test_record_list_holds_every_record_once, glass_of_water),
        IMP_CASE_TEST(test_path_sums_exact, glass_of_water),
        IMP_CASE_TEST(test_result_is_the_accumulators, glass_of_water),
    };
    return DEVICE_TEST_RUN("importance paths", tests, NULL, imp_teardown) != 0;
}
