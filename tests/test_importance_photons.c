/* test_importance_photons.c — the importance pass's photon paths (kernels/lib/paths.h,
 * kernels/lib/lights.h) against exact formulas, on scenes built in code:
 *
 *   emission   a point light's paths reach a rectangle with probability Ω/4π (its solid
 *              angle), isotropically, with first-vertex weight 1 - h/|p - light|; an area
 *              light's directions are cosine-distributed (mean cos 2/3, P(cos < x) = x²)
 *   scattering Russian roulette survives with the largest albedo channel; a one-sided back
 *              absorbs, a two-sided back reflects its albedo
 *   glass      photons refracted through a glass sphere light a tile in its shadow, and the
 *              sphere's triangles get light importance without holding a hit point
 *
 * Counts are checked within 5 binomial standard deviations. Each scene runs once per device. */
#include "importance_common.h"

/* |hits / trials - expected| within 5 σ of a binomial of `trials` (σ² = p (1 - p) / trials,
 * with p (1 - p) at least 1e-4 (1 - 1e-4) so that an expected 0 or 1 keeps a bound). */
static void expect_binomial(const char *what, size_t hits, size_t trials, double expected)
{
    double fraction = (double)hits / trials;
    double sigma = sqrt(fmax(expected * (1 - expected), 1e-4 * (1 - 1e-4)) / trials);
    print_message("  %s: %zu of %zu, %.5f, expected %.5f (%.2f σ)\n", what, hits, trials,
                  fraction, expected, (fraction - expected) / sigma);
    assert_true(trials > 0);
    assert_true(fabs(fraction - expected) <= 5 * sigma);
}

/* ---- a point light over a rectangle ---- */

#define POINT_HEIGHT 1.3

/* A point light at height h = 1.3 over the centre of a 2 x 3 rectangle (nothing else). */
static scene *point_light_scene(void)
{
    scene *s = scene_create("point-emission.xml");
    imp_add_quad(s, "rectangle", imp_diffuse(s, "white", 0.5f, 0), V3(0, 0, 0), V3(0, 0, 1.5f),
                 V3(1, 0, 0)); /* normal +y */
    imp_point_light(s, V3(0, (float)POINT_HEIGHT, 0), 1.0f);
    imp_look_at(s, V3(0, 3, 3), V3(0, 0, 0), V3(0, 1, 0), 32, 32, 0.8f);
    return test_finalize_scene(s);
}

static imp_case point_light = {.make = point_light_scene, .iterations = 1, .photons = 200000};

/* A path has a first vertex iff its isotropic direction falls in the rectangle's solid angle
 * Ω = 4 asin(sin α sin β), tan α = a/h, tan β = b/h for half sides a = 1, b = 1.5. */
static void test_point_light_reaches_the_solid_angle(void **state)
{
    const imp_case *run = imp_run(&point_light);
    size_t n = run->snapshot.core.params.path_count, first = 0;
    for (size_t p = 0; p < n; p++)
        first += run->snapshot.core.path_length[p] > 0;
    double omega = 4.0 * asin(sin(atan(1.0 / POINT_HEIGHT)) * sin(atan(1.5 / POINT_HEIGHT)));
    expect_binomial("paths reaching the rectangle", first, n, omega / (4.0 * M_PI));
}

/* Each first vertex lies on the rectangle with weight 1 - h/|p - light| (Eq. 2 of the light's
 * ray with the normal +y). */
static void test_point_light_first_vertex_weight(void **state)
{
    const imp_case *run = imp_run(&point_light);
    double worst = 0;
    for (size_t p = 0; p < run->snapshot.core.params.path_count; p++) {
        if (run->snapshot.core.path_length[p] == 0)
            continue;
        const idmr_photon_vertex *vx = &run->snapshot.vertices[p * IDMR_PATH_VERTICES];
        assert_float_equal(vx->position[1], 0.0, 1e-5);
        assert_true(fabsf(vx->position[0]) <= 1.0f + 1e-5f);
        assert_true(fabsf(vx->position[2]) <= 1.5f + 1e-5f);
        double dx = vx->position[0], dz = vx->position[2], h = POINT_HEIGHT;
        worst = fmax(worst, fabs(vx->weight - (1.0 - h / sqrt(dx * dx + h * h + dz * dz))));
    }
    print_message("  worst first-vertex weight error %.2e\n", worst);
    assert_true(worst < 1e-5);
}

/* Isotropic emission: each quadrant of the rectangle gets a quarter of the first vertices. */
static void test_point_light_is_isotropic(void **state)
{
    const imp_case *run = imp_run(&point_light);
    size_t first = 0, quadrant[4] = {0, 0, 0, 0};
    for (size_t p = 0; p < run->snapshot.core.params.path_count; p++) {
        if (run->snapshot.core.path_length[p] == 0)
            continue;
        const idmr_photon_vertex *vx = &run->snapshot.vertices[p * IDMR_PATH_VERTICES];
        quadrant[(vx->position[0] > 0) + 2 * (vx->position[2] > 0)]++;
        first++;
    }
    for (int q = 0; q < 4; q++)
        expect_binomial("a quadrant's share of the hits", quadrant[q], first, 0.25);
}

/* ---- a small area light over a wide floor ---- */

/* A 0.1 x 0.1 area light at y = 1 facing down over a floor 200 wide: directions are
 * cosine-distributed about the light's normal, so cos θ at the first vertex (1 - its weight:
 * floor and light are parallel) has density 2c on [0, 1]. */
static scene *area_light_scene(void)
{
    scene *s = scene_create("area-emission.xml");
    imp_add_quad(s, "floor", imp_diffuse(s, "white", 0.5f, 0), V3(0, 0, 0), V3(0, 0, 100),
                 V3(100, 0, 0)); /* normal +y; triangles 0, 1 */
    scene_mesh *light = imp_add_quad(s, "light", imp_diffuse(s, "black", 0, 0), V3(0, 1, 0),
                                     V3(0.05f, 0, 0), V3(0, 0, 0.05f)); /* normal -y */
    imp_area_light(s, light, 10.0f);
    imp_look_at(s, V3(0, 3, 3), V3(0, 0, 0), V3(0, 1, 0), 32, 32, 0.8f);
    return test_finalize_scene(s);
}

static imp_case area_light = {.make = area_light_scene, .iterations = 1, .photons = 100000};

/* The cosines of the first vertices into cosines[] (may be NULL); returns how many. */
static size_t area_light_cosines(const imp_case *run, double *cosines)
{
    size_t first = 0;
    for (size_t p = 0; p < run->snapshot.core.params.path_count; p++)
        if (run->snapshot.core.path_length[p] > 0) {
            double weight = run->snapshot.vertices[p * IDMR_PATH_VERTICES].weight;
            if (cosines)
                cosines[first] = 1.0 - weight;
            first++;
        }
    return first;
}

/* Every first vertex lies on the floor, below the light (it emits from its front only); rays
 * with cos θ < 0.014 may miss the floor (probability 2e-4), so at most 1/1000 of the paths
 * store nothing. */
static void test_area_light_emits_from_its_front(void **state)
{
    const imp_case *run = imp_run(&area_light);
    size_t n = run->snapshot.core.params.path_count;
    for (size_t p = 0; p < n; p++)
        if (run->snapshot.core.path_length[p] > 0) {
            const idmr_photon_vertex *vx = &run->snapshot.vertices[p * IDMR_PATH_VERTICES];
            assert_true(vx->triangle < 2); /* the floor */
            assert_true(vx->position[1] < 1.0f);
        }
    assert_true(area_light_cosines(run, NULL) >= n - n / 1000);
}

/* Mean cos θ = 2/3, within 5 σ (variance 1/2 - 4/9). */
static void test_area_light_mean_cosine(void **state)
{
    const imp_case *run = imp_run(&area_light);
    double *cosines = malloc(run->snapshot.core.params.path_count * sizeof *cosines), sum = 0;
    size_t first = area_light_cosines(run, cosines);
    for (size_t i = 0; i < first; i++)
        sum += cosines[i];
    free(cosines);
    double mean = sum / first, sigma = sqrt((0.5 - 4.0 / 9.0) / first);
    print_message("  mean cos %.5f, expected 2/3 (%.2f σ)\n", mean, (mean - 2.0 / 3.0) / sigma);
    assert_true(fabs(mean - 2.0 / 3.0) <= 5 * sigma);
}

/* P(cos θ in [a, b)) = b² - a² for four quarters of [0, 1]. */
static void test_area_light_cosine_distribution(void **state)
{
    const imp_case *run = imp_run(&area_light);
    double *cosines = malloc(run->snapshot.core.params.path_count * sizeof *cosines);
    size_t first = area_light_cosines(run, cosines), bins[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < first; i++)
        bins[cosines[i] < 0.25 ? 0 : cosines[i] < 0.5 ? 1 : cosines[i] < 0.75 ? 2 : 3]++;
    free(cosines);
    const double edges[5] = {0, 0.25, 0.5, 0.75, 1};
    for (int b = 0; b < 4; b++)
        expect_binomial("cos θ in a quarter of [0, 1]", bins[b], first,
                        edges[b + 1] * edges[b + 1] - edges[b] * edges[b]);
}

/* ---- Russian roulette and one-sided backs ---- */

/* Two parallel planes 200 wide: a floor (y = 0, facing up, reflectance (0.3, 0.6, 0.45),
 * triangles 0, 1) and a ceiling (y = 1, facing up: its back faces the point light at y = 0.5;
 * triangles 2, 3), one-sided or two-sided. A path scattered at either plane almost surely
 * (>= 1 - 1e-4) hits the other one, so the fraction of paths going on after their first vertex
 * measures the scattering there. */
static scene *planes_scene(unsigned int ceiling_flags)
{
    scene *s = scene_create("roulette.xml");
    idmr_material coloured = {{0.3f, 0.6f, 0.45f}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1,
                              -1, 0};
    uint32_t floor_material = scene_add_material(s, "coloured", "diffuse", &coloured);
    uint32_t ceiling_material = imp_diffuse(s, "white", 0.8f, ceiling_flags);
    imp_add_quad(s, "floor", floor_material, V3(0, 0, 0), V3(0, 0, 100), V3(100, 0, 0));
    imp_add_quad(s, "ceiling", ceiling_material, V3(0, 1, 0), V3(0, 0, 100), V3(100, 0, 0));
    imp_point_light(s, V3(0, 0.5f, 0), 1.0f);
    imp_look_at(s, V3(0, 0.5f, 5), V3(0, 0, 0), V3(0, 1, 0), 32, 32, 0.8f);
    return test_finalize_scene(s);
}

static scene *one_sided_scene(void)
{
    return planes_scene(0);
}

static scene *two_sided_scene(void)
{
    return planes_scene(IDMR_MATERIAL_TWOSIDED);
}

static imp_case one_sided = {.make = one_sided_scene, .iterations = 1, .photons = 100000};
static imp_case two_sided = {.make = two_sided_scene, .iterations = 1, .photons = 100000};

/* Of more than 10000 paths whose first vertex lies on the ceiling (1) or the floor (0) of case
 * c, the fraction `expected` goes on; returns how many went on. */
static size_t expect_going_on(imp_case *c, int ceiling, double expected, const char *what)
{
    const imp_case *run = imp_run(c);
    size_t first = 0, going_on = 0;
    for (size_t p = 0; p < run->snapshot.core.params.path_count; p++) {
        uint32_t length = run->snapshot.core.path_length[p];
        const idmr_photon_vertex *vx = &run->snapshot.vertices[p * IDMR_PATH_VERTICES];
        if (length == 0 || (vx->triangle >= 2) != ceiling)
            continue;
        first++;
        going_on += length > 1;
    }
    assert_true(first > 10000);
    expect_binomial(what, going_on, first, expected);
    return going_on;
}

/* On the floor, Russian roulette survives with the largest channel, 0.6. */
static void test_roulette_survives_with_the_largest_channel(void **state)
{
    expect_going_on(&one_sided, 0, 0.6, "floor paths going on (survival = max channel 0.6)");
}

/* The back of a one-sided ceiling absorbs: no path goes on. */
static void test_one_sided_back_absorbs(void **state)
{
    assert_int_equal(expect_going_on(&one_sided, 1, 0.0, "one-sided ceiling's back going on"), 0);
}

/* The back of a two-sided ceiling reflects its albedo, 0.8. */
static void test_two_sided_back_reflects_its_albedo(void **state)
{
    expect_going_on(&two_sided, 1, 0.8, "two-sided ceiling's back going on (albedo 0.8)");
}

/* The ceiling's vertices carry the normal of the side the photon arrived from (down). */
static void test_back_vertices_face_the_photon(void **state)
{
    for (int i = 0; i < 2; i++) {
        const imp_case *run = imp_run(i ? &two_sided : &one_sided);
        for (size_t p = 0; p < run->snapshot.core.params.path_count; p++) {
            const idmr_photon_vertex *vx = &run->snapshot.vertices[p * IDMR_PATH_VERTICES];
            if (run->snapshot.core.path_length[p] > 0 && vx->triangle >= 2)
                assert_true(vx->normal[1] < -0.999f);
        }
    }
}

/* ---- a caustic through glass ---- */

/* A point light 2 above the centre of a glass sphere (radius 0.5, IOR 1.5) which hangs over a
 * 0.6 x 0.6 floor tile lying wholly inside its shadow (shadow radius 0.77 at the floor), seen
 * from the side; two iterations. */
static scene *glass_scene(void)
{
    scene *s = scene_create("glass.xml");
    imp_add_quad(s, "floor", imp_diffuse(s, "white", 0.8f, 0), V3(0, 0, 0), V3(0, 0, 0.3f),
                 V3(0.3f, 0, 0)); /* triangles 0, 1 */
    imp_add_sphere(s, "sphere", imp_glass(s, "glass"), V3(0, 1, 0), 0.5f);
    imp_point_light(s, V3(0, 3, 0), 1.0f);
    imp_look_at(s, V3(1.5f, 0.8f, 0), V3(0, 0, 0), V3(0, 1, 0), 64, 48, 0.5f);
    return test_finalize_scene(s);
}

static imp_case glass = {.make = glass_scene, .iterations = 2, .photons = 100000};

/* Photon vertices on the tile: as a path's first vertex (direct), or after the glass. */
static void count_tile_vertices(size_t *direct, size_t *through_glass)
{
    const imp_case *run = imp_run(&glass);
    *direct = *through_glass = 0;
    for (size_t p = 0; p < run->snapshot.core.params.path_count; p++)
        for (uint32_t j = 0; j < run->snapshot.core.path_length[p]; j++)
            if (run->snapshot.vertices[p * IDMR_PATH_VERTICES + j].triangle < 2) {
                *direct += j == 0;
                *through_glass += j > 0;
            }
}

/* The tile lies in the sphere's shadow: no photon reaches it directly. */
static void test_no_direct_photon_in_the_shadow(void **state)
{
    size_t direct, through_glass;
    count_tile_vertices(&direct, &through_glass);
    assert_int_equal(direct, 0);
}

/* Photons refracted through the sphere reach the tile, which the camera sees and which gets
 * light importance. */
static void test_caustic_lights_the_tile(void **state)
{
    size_t direct, through_glass;
    count_tile_vertices(&direct, &through_glass);
    const imp_case *run = imp_run(&glass);
    const importance_weights defaults = {1.0f, 1.0f};
    importance_sums floor = importance_mesh_sums(
        &run->r, run->s, (size_t)imp_mesh_index(run->s, "floor"), &defaults);
    print_message("  %zu photon vertices on the tile through the glass; camera %.4g, light "
                  "%.4g\n",
                  through_glass, floor.camera, floor.light);
    assert_true(through_glass > 50);
    assert_true(floor.camera > 0);
    assert_true(floor.light > 0);
}

/* The sphere's triangles — on the paths, but never holding a hit point — get light importance:
 * importance_mesh_sums with γ = σ = 0 is their light importance, > 0. */
static void test_glass_gets_light_importance(void **state)
{
    const imp_case *run = imp_run(&glass);
    const importance_weights light_only = {0.0f, 0.0f};
    importance_sums sphere = importance_mesh_sums(
        &run->r, run->s, (size_t)imp_mesh_index(run->s, "sphere"), &light_only);
    print_message("  sphere: γ = σ = 0 sum %.4g, light %.4g, camera %.4g\n", sphere.amount,
                  sphere.light, sphere.camera);
    assert_true(sphere.amount > 0 && sphere.amount == sphere.light);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light_reaches_the_solid_angle),
        cmocka_unit_test(test_point_light_first_vertex_weight),
        cmocka_unit_test(test_point_light_is_isotropic),
        cmocka_unit_test(test_area_light_emits_from_its_front),
        cmocka_unit_test(test_area_light_mean_cosine),
        cmocka_unit_test(test_area_light_cosine_distribution),
        cmocka_unit_test(test_roulette_survives_with_the_largest_channel),
        cmocka_unit_test(test_one_sided_back_absorbs),
        cmocka_unit_test(test_two_sided_back_reflects_its_albedo),
        cmocka_unit_test(test_back_vertices_face_the_photon),
        cmocka_unit_test(test_no_direct_photon_in_the_shadow),
        cmocka_unit_test(test_caustic_lights_the_tile),
        cmocka_unit_test(test_glass_gets_light_importance),
    };
    return DEVICE_TEST_RUN("importance photons", tests, NULL, imp_teardown) != 0;
}
