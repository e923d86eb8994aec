/* test_specialise.c — kernels built for the scene's features (issue: "simulate only the effects a
 * scene calls for"): the options a scene gets, specialised and generic programs giving
 * bit-identical importance and bit-identical renders, γ = 0 leaving camera importance out without touching light
 * importance, and the program cache (a second build comes from it, a changed kernel source does
 * not). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "device/bvh.h"
#include "device/device.h"
#include "device/program.h"
#include "core/error.h"
#include "passes/importance.h"
#include "io/mitsuba.h"
#include "passes/render.h"

static device dev;

static int group_setup(void **state)
{
    if (device_open(&dev, -1)) {
        fprintf(stderr, "test_specialise: %s\n", error_message());
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    device_close(&dev);
    return 0;
}

static scene *load(const char *path)
{
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    if (!s)
        fail_msg("%s", error_message());
    return s;
}

/* The shipped Cornell box: diffuse and an area light only; the glass of water: dielectric. */
static void test_options_follow_the_scene(void **state)
{
    scene *box = load("data/cornell/scene.xml");
    scene *glass = load("../shared/data/scenes/glass-of-water/scene-without-mesh000.xml");
    assert_int_equal(box->features, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA);
    char *options = device_build_options(&dev, box->features, NULL);
    assert_non_null(strstr(options, "-D IDMR_FEATURES=0x21u"));
    assert_false(box->features & (IDMR_FEATURE_DIELECTRIC | IDMR_FEATURE_SPOT));
    free(options);
    /* diffuse (0x1), glossy (0x2), dielectric (0x8), area (0x20) */
    assert_int_equal(glass->features, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_GLOSSY |
                                          IDMR_FEATURE_DIELECTRIC | IDMR_FEATURE_AREA);
    options = device_build_options(&dev, glass->features, NULL);
    assert_non_null(strstr(options, "-D IDMR_FEATURES=0x2bu"));
    free(options);
    scene_free(box);
    scene_free(glass);
}

static void run_pass(const scene *s, const bvh *b, int generic, float gamma,
                     importance_result *r)
{
    importance_options o;
    importance_options_default(&o);
    o.sppm.iterations = 2;
    o.sppm.photons = 20000;
    o.sppm.resolution = 0.25f;
    o.sppm.generic = generic;
    o.gamma = gamma;
    if (importance_run(&dev, s, b, &o, r))
        fail_msg("%s", error_message());
}

static void expect_identical(const char *path)
{
    scene *s = load(path);
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    importance_result specialised, generic;
    run_pass(s, &b, 0, 1.0f, &specialised);
    run_pass(s, &b, 1, 1.0f, &generic);
    assert_non_null(strstr(generic.sppm.build_options, "IDMR_FEATURES=0x3ffu"));
    assert_null(strstr(specialised.sppm.build_options, "IDMR_FEATURES=0x3ffu"));
    size_t n = specialised.triangle_count;
    double total = 0;
    for (size_t t = 0; t < n; t++)
        total += specialised.camera[t] + specialised.light[t];
    assert_true(total > 0);
    assert_memory_equal(specialised.camera, generic.camera, n * sizeof(double));
    assert_memory_equal(specialised.light, generic.light, n * sizeof(double));
    print_message("  %s: %zu triangles, identical sums (total %.6g)\n", path, n, total);
    importance_result_free(&specialised);
    importance_result_free(&generic);
    bvh_free(&b);
    scene_free(s);
}

static void render_scene(const scene *s, const bvh *b, int generic, render_result *r)
{
    render_options o;
    render_options_default(&o);
    o.sppm.iterations = 2;
    o.sppm.photons = 20000;
    o.sppm.resolution = 0.25f;
    o.sppm.generic = generic;
    if (render_run(&dev, s, b, &o, r))
        fail_msg("%s", error_message());
}

/* The same seed renders the same image, to the bit, with either program. */
static void expect_identical_render(const char *path)
{
    scene *s = load(path);
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    render_result specialised, generic;
    render_scene(s, &b, 0, &specialised);
    render_scene(s, &b, 1, &generic);
    assert_non_null(strstr(generic.sppm.build_options, "IDMR_FEATURES=0x3ffu"));
    assert_null(strstr(specialised.sppm.build_options, "IDMR_FEATURES=0x3ffu"));
    size_t values = (size_t)specialised.sppm.width * specialised.sppm.height * 3;
    double total = 0;
    for (size_t i = 0; i < values; i++)
        total += specialised.image[i];
    assert_true(total > 0);
    assert_memory_equal(specialised.image, generic.image, values * sizeof(float));
    print_message("  %s: %ux%u, identical images (mean %.6g)\n", path, specialised.sppm.width,
                  specialised.sppm.height, total / values);
    render_result_free(&specialised);
    render_result_free(&generic);
    bvh_free(&b);
    scene_free(s);
}

static void test_generic_equals_specialised_diffuse(void **state)
{
    expect_identical("data/cornell/scene.xml");
    expect_identical_render("data/cornell/scene.xml");
}

static void test_generic_equals_specialised_glass(void **state)
{
    expect_identical("../shared/data/scenes/glass-of-water/scene-without-mesh000.xml");
    expect_identical_render("../shared/data/scenes/glass-of-water/scene-without-mesh000.xml");
}

/* γ = 0 compiles the camera atomics out: camera importance is all zero, light importance is the
 * same as with γ = 1 (the camera pass draws the same random numbers either way). */
static void test_gamma_zero_skips_camera_importance(void **state)
{
    scene *s = load("data/cornell/scene.xml");
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    importance_result with, without;
    run_pass(s, &b, 0, 1.0f, &with);
    run_pass(s, &b, 0, 0.0f, &without);
    assert_non_null(strstr(without.sppm.build_options, "-D IDMR_CAMERA_IMPORTANCE=0"));
    double camera = 0, camera_with = 0;
    for (size_t t = 0; t < without.triangle_count; t++) {
        camera += without.camera[t];
        camera_with += with.camera[t];
    }
    assert_true(camera == 0.0);
    assert_true(camera_with > 0.0); /* γ = 1 does accumulate it */
    assert_memory_equal(with.light, without.light, with.triangle_count * sizeof(double));
    importance_result_free(&with);
    importance_result_free(&without);
    bvh_free(&b);
    scene_free(s);
}

/* A second build is served from the cache; a kernel source changed by one comment is not. */
static void test_program_cache(void **state)
{
    char root[] = "/tmp/idmr-cache-root-XXXXXX", cache[] = "/tmp/idmr-cache-XXXXXX";
    assert_non_null(mkdtemp(root));
    assert_non_null(mkdtemp(cache));
    char command[1024];
    snprintf(command, sizeof command, "cp -r kernels include %s/", root);
    assert_int_equal(system(command), 0);
    setenv("IDMR_ROOT", root, 1);
    setenv("IDMR_CACHE_DIR", cache, 1);
    char *options = device_build_options(&dev, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA, NULL);
    cl_program program;
    uint64_t before = device_program_key(&dev, "trace.cl", options);
    assert_int_equal(device_build_program(&dev, "trace.cl", options, &program), 0);
    assert_false(device_last_build_cached());
    clReleaseProgram(program);
    assert_int_equal(device_build_program(&dev, "trace.cl", options, &program), 0);
    assert_true(device_last_build_cached());
    clReleaseProgram(program);

    snprintf(command, sizeof command, "echo '/* changed */' >> %s/kernels/traverse.h", root);
    assert_int_equal(system(command), 0);
    assert_true(device_program_key(&dev, "trace.cl", options) != before);
    assert_int_equal(device_build_program(&dev, "trace.cl", options, &program), 0);
    assert_false(device_last_build_cached());
    clReleaseProgram(program);

    /* Other options, other program. */
    char *other = device_build_options(&dev, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_POINT, NULL);
    assert_true(device_program_key(&dev, "trace.cl", other) !=
                device_program_key(&dev, "trace.cl", options));
    free(other);
    free(options);
    unsetenv("IDMR_ROOT");
    unsetenv("IDMR_CACHE_DIR");
    snprintf(command, sizeof command, "rm -rf %s %s", root, cache);
    assert_int_equal(system(command), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_options_follow_the_scene),
        cmocka_unit_test(test_generic_equals_specialised_diffuse),
        cmocka_unit_test(test_generic_equals_specialised_glass),
        cmocka_unit_test(test_gamma_zero_skips_camera_importance),
        cmocka_unit_test(test_program_cache),
    };
    return cmocka_run_group_tests_name("specialise", tests, group_setup, group_teardown);
}
