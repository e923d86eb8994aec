/* test_specialise.c — kernels built for the scene's features (issue: "simulate only the effects a
 * scene calls for"): the options a scene gets; specialised and generic programs giving
 * bit-identical importance and bit-identical renders; γ = 0 leaving camera importance out
 * without touching light importance; and the program cache (a second build comes from it, a
 * changed kernel source or other options do not). Every test runs on every device
 * (tests/device_test.h); the scenes are the shipped Cornell box (diffuse, one area light) and
 * the glass of water from ../shared/data (dielectric, glossy). */
#include "test_support.h"

/* The scenes with their BVHs, loaded once per device and program. */
static struct loaded {
    const char *path;
    scene *s;
    bvh b;
} loaded[2];

static const struct loaded *load(const char *path)
{
    int i = strcmp(path, CORNELL_SCENE) == 0 ? 0 : 1;
    if (!loaded[i].s) {
        scene *s = test_load_scene(path);
        test_build_bvh(s, &loaded[i].b);
        loaded[i].s = s;
        loaded[i].path = path;
    }
    assert_string_equal(loaded[i].path, path);
    return &loaded[i];
}

/* ---- the options a scene gets ---- */

/* Feature bits: diffuse 0x1, glossy 0x2, dielectric 0x8, area 0x20. */
static void expect_features(const char *path, unsigned int features, const char *define)
{
    unsigned int found = load(path)->s->features;
    char *options = device_build_options(device_test_device(), found, NULL);
    int has_define = strstr(options, define) != NULL;
    print_message("  %s: features 0x%x, options %s\n", path, found, options);
    free(options);
    assert_int_equal(found, features);
    assert_true(has_define);
}

static void test_cornell_options(void **state)
{
    expect_features(CORNELL_SCENE, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA,
                    "-D IDMR_FEATURES=0x21u");
}

static void test_glass_of_water_options(void **state)
{
    expect_features(GLASS_OF_WATER_SCENE,
                    IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_GLOSSY | IDMR_FEATURE_DIELECTRIC |
                        IDMR_FEATURE_AREA,
                    "-D IDMR_FEATURES=0x2bu");
}

/* ---- generic and specialised programs ---- */

/* Two iterations of 20k paths at a quarter of the film, specialised or generic. */
static void small_sppm(sppm_options *o, int generic)
{
    o->iterations = 2;
    o->photons = 20000;
    o->resolution = 0.25f;
    o->generic = generic;
}

static void run_importance(const scene *s, const bvh *b, int generic, float gamma,
                           importance_result *r)
{
    importance_options o;
    importance_options_default(&o);
    small_sppm(&o.sppm, generic);
    o.gamma = gamma;
    test_run_importance(s, b, &o, r);
}

static void run_render(const scene *s, const bvh *b, int generic, render_result *r)
{
    render_options o;
    render_options_default(&o);
    small_sppm(&o.sppm, generic);
    test_run_render(s, b, &o, r);
}

/* The generic program was built with every feature, the specialised one not. */
static void expect_programs(const sppm_summary *specialised, const sppm_summary *generic)
{
    assert_non_null(strstr(generic->build_options, "IDMR_FEATURES=0x3ffu"));
    assert_null(strstr(specialised->build_options, "IDMR_FEATURES=0x3ffu"));
}

/* The same seed gives the same per-triangle sums, to the bit, with either program. */
static void expect_identical_importance(const char *path)
{
    const struct loaded *l = load(path);
    importance_result specialised, generic;
    run_importance(l->s, &l->b, 0, 1.0f, &specialised);
    run_importance(l->s, &l->b, 1, 1.0f, &generic);
    expect_programs(&specialised.sppm, &generic.sppm);
    size_t n = specialised.triangle_count;
    double total = 0;
    for (size_t t = 0; t < n; t++)
        total += specialised.camera[t] + specialised.light[t];
    print_message("  %s: %zu triangles, total %.6g\n", path, n, total);
    assert_true(total > 0);
    assert_memory_equal(specialised.camera, generic.camera, n * sizeof(double));
    assert_memory_equal(specialised.light, generic.light, n * sizeof(double));
    importance_result_free(&specialised);
    importance_result_free(&generic);
}

/* The same seed renders the same image, to the bit, with either program. */
static void expect_identical_render(const char *path)
{
    const struct loaded *l = load(path);
    render_result specialised, generic;
    run_render(l->s, &l->b, 0, &specialised);
    run_render(l->s, &l->b, 1, &generic);
    expect_programs(&specialised.sppm, &generic.sppm);
    size_t values = (size_t)specialised.sppm.width * specialised.sppm.height * 3;
    double total = 0;
    for (size_t i = 0; i < values; i++)
        total += specialised.image[i];
    print_message("  %s: %ux%u, mean %.6g\n", path, specialised.sppm.width,
                  specialised.sppm.height, total / values);
    assert_true(total > 0);
    assert_memory_equal(specialised.image, generic.image, values * sizeof(float));
    render_result_free(&specialised);
    render_result_free(&generic);
}

static void test_generic_importance_equals_specialised_on_cornell(void **state)
{
    expect_identical_importance(CORNELL_SCENE);
}

static void test_generic_render_equals_specialised_on_cornell(void **state)
{
    expect_identical_render(CORNELL_SCENE);
}

static void test_generic_importance_equals_specialised_on_glass(void **state)
{
    expect_identical_importance(GLASS_OF_WATER_SCENE);
}

static void test_generic_render_equals_specialised_on_glass(void **state)
{
    expect_identical_render(GLASS_OF_WATER_SCENE);
}

/* ---- γ = 0 ---- */

/* The Cornell box with γ = 1 and γ = 0, once per device. */
static importance_result with_gamma, without_gamma;

static void run_both_gammas(void)
{
    if (without_gamma.light)
        return;
    const struct loaded *cornell = load(CORNELL_SCENE);
    run_importance(cornell->s, &cornell->b, 0, 1.0f, &with_gamma);
    run_importance(cornell->s, &cornell->b, 0, 0.0f, &without_gamma);
}

static double camera_total(const importance_result *r)
{
    double sum = 0;
    for (size_t t = 0; t < r->triangle_count; t++)
        sum += r->camera[t];
    return sum;
}

/* γ = 0 compiles the camera atomics out: camera importance is all zero (γ = 1 does accumulate
 * it). */
static void test_gamma_zero_leaves_camera_importance_out(void **state)
{
    run_both_gammas();
    assert_non_null(strstr(without_gamma.sppm.build_options, "-D IDMR_CAMERA_IMPORTANCE=0"));
    assert_true(camera_total(&without_gamma) == 0.0);
    assert_true(camera_total(&with_gamma) > 0.0);
}

/* Light importance is the same as with γ = 1 (the camera pass draws the same random numbers
 * either way). */
static void test_gamma_zero_keeps_light_importance(void **state)
{
    run_both_gammas();
    assert_memory_equal(with_gamma.light, without_gamma.light,
                        with_gamma.triangle_count * sizeof(double));
}

/* ---- the program cache ---- */

/* A copy of kernels/ and include/ as IDMR_ROOT and an empty IDMR_CACHE_DIR, and the options of
 * the Cornell box, for one test. */
static char root[64], cache[64];
static char *options;

static int cache_setup(void **state)
{
    snprintf(root, sizeof root, "/tmp/idmr-cache-root-XXXXXX");
    snprintf(cache, sizeof cache, "/tmp/idmr-cache-XXXXXX");
    if (!mkdtemp(root) || !mkdtemp(cache))
        return -1;
    char command[256];
    snprintf(command, sizeof command, "cp -r kernels include %s/", root);
    if (system(command) != 0)
        return -1;
    setenv("IDMR_ROOT", root, 1);
    setenv("IDMR_CACHE_DIR", cache, 1);
    options = device_build_options(device_test_device(), IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA,
                                   NULL);
    return 0;
}

static int cache_teardown(void **state)
{
    free(options);
    options = NULL;
    unsetenv("IDMR_ROOT");
    unsetenv("IDMR_CACHE_DIR");
    return test_remove_directory(root) || test_remove_directory(cache) ? -1 : 0;
}

/* Builds trace.cl with `build_options`; returns whether it came from the cache. */
static int build_trace(const char *build_options)
{
    cl_program program;
    if (device_build_program(device_test_device(), "trace.cl", build_options, &program))
        fail_msg("%s", error_message());
    clReleaseProgram(program);
    return device_last_build_cached();
}

static void test_second_build_comes_from_the_cache(void **state)
{
    assert_false(build_trace(options));
    assert_true(build_trace(options));
}

/* A header that trace.cl includes (kernels/lib/traverse.h), changed by one comment: another
 * key, and a build that does not come from the cache. */
static void test_changed_source_is_built_again(void **state)
{
    device *d = device_test_device();
    assert_false(build_trace(options));
    uint64_t before = device_program_key(d, "trace.cl", options);
    char command[256];
    snprintf(command, sizeof command, "echo '/* changed */' >> %s/kernels/lib/traverse.h", root);
    assert_int_equal(system(command), 0);
    assert_true(device_program_key(d, "trace.cl", options) != before);
    assert_false(build_trace(options));
}

static void test_other_options_other_key(void **state)
{
    device *d = device_test_device();
    char *other = device_build_options(d, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_POINT, NULL);
    uint64_t key = device_program_key(d, "trace.cl", other);
    free(other);
    assert_true(key != device_program_key(d, "trace.cl", options));
}

static int group_teardown(void **state)
{
    importance_result_free(&with_gamma);
    importance_result_free(&without_gamma);
    for (int i = 0; i < 2; i++)
        if (loaded[i].s) {
            bvh_free(&loaded[i].b);
            scene_free(loaded[i].s);
            loaded[i].s = NULL;
        }
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_options),
        cmocka_unit_test(test_glass_of_water_options),
        cmocka_unit_test(test_generic_importance_equals_specialised_on_cornell),
        cmocka_unit_test(test_generic_render_equals_specialised_on_cornell),
        cmocka_unit_test(test_generic_importance_equals_specialised_on_glass),
        cmocka_unit_test(test_generic_render_equals_specialised_on_glass),
        cmocka_unit_test(test_gamma_zero_leaves_camera_importance_out),
        cmocka_unit_test(test_gamma_zero_keeps_light_importance),
        cmocka_unit_test_setup_teardown(test_second_build_comes_from_the_cache, cache_setup,
                                        cache_teardown),
        cmocka_unit_test_setup_teardown(test_changed_source_is_built_again, cache_setup,
                                        cache_teardown),
        cmocka_unit_test_setup_teardown(test_other_options_other_key, cache_setup, cache_teardown),
    };
    return DEVICE_TEST_RUN("specialise", tests, NULL, group_teardown) != 0;
}
