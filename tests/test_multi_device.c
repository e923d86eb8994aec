/* test_multi_device.c — the importance pass on several OpenCL devices at once (passes/sppm.h,
 * sppm_run_devices): the photon paths split between the devices, the camera-side sums from the
 * first, the devices' 64-bit integer sums added before their one conversion to double. The
 * result must be the single device's bit for bit, whatever the split: every test compares the
 * double arrays with memcmp, so adding per-device doubles (which rounds differently) fails them.
 *
 * PoCL exposes two CPU devices when POCL_DEVICES="pthread pthread": main() sets it before the
 * first OpenCL call, so devices 0 and 1 are two PoCL devices that compute alike. Fewer than two
 * devices is a failed test, never a skip. Cases: the Cornell box (data/), device 0 alone
 * against {0, 1} with the measured rebalancing, a fixed uneven split each way, three cores
 * (device 0 opened twice beside device 1) with a split that leaves the first device almost
 * nothing, Bitterli's glass of water (seen light through glass and mirrors, from the first
 * device only), the water-filling split on cases worked out by hand, and the CLI:
 * `idmr importance --device all` writes the simulation.bin of `--device 0` byte for byte. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "command_common.h"
#include "test_support.h"

#define MULTI_PHOTONS 20000
#define MULTI_ITERATIONS 5 /* rebalancing happens after iterations 1 to 3 */

static device devices[3]; /* 0, 1, and device 0 again */
static int opened;

typedef struct cornell_case {
    scene *s;
    bvh b;
    importance_options o;
    importance_result one; /* device 0 alone */
} cornell_case;

static cornell_case cornell;

/* The Cornell box, its BVH and its run on device 0 alone: once, for the tests below. */
static int cornell_setup(void)
{
    cornell.s = mitsuba_load(CORNELL_SCENE);
    if (!cornell.s || bvh_build(cornell.s, &cornell.b)) {
        fprintf(stderr, "%s: %s\n", CORNELL_SCENE, error_message());
        return -1;
    }
    test_importance_options(&cornell.o, MULTI_ITERATIONS, MULTI_PHOTONS);
    cornell.o.sppm.resolution = 0.5f;
    if (importance_run(devices, cornell.s, &cornell.b, &cornell.o, &cornell.one)) {
        fprintf(stderr, "importance_run on device 0: %s\n", error_message());
        return -1;
    }
    return 0;
}

static void cornell_teardown(void)
{
    importance_result_free(&cornell.one);
    if (cornell.s)
        bvh_free(&cornell.b);
    scene_free(cornell.s);
}

static int open_devices(void **state)
{
    (void)state;
    device_info *infos;
    size_t found;
    if (device_list(&infos, &found)) {
        fprintf(stderr, "device_list: %s\n", error_message());
        return -1;
    }
    free(infos);
    if (found < 2) {
        fprintf(stderr, "multi-device tests need two OpenCL devices (POCL_DEVICES=\"pthread "
                        "pthread\" gives them), found %zu\n", found);
        return -1;
    }
    int indices[3] = {0, 1, 0};
    for (; opened < 3; opened++)
        if (device_open(devices + opened, indices[opened])) {
            fprintf(stderr, "device_open(%d): %s\n", indices[opened], error_message());
            return -1;
        }
    return cornell_setup();
}

static int close_devices(void **state)
{
    (void)state;
    cornell_teardown();
    while (opened > 0)
        device_close(devices + --opened);
    return 0;
}

/* One run of the importance pass on `count` devices (devices[] from `first`) with `o`. */
static void run_on(const scene *s, const bvh *b, const importance_options *o, unsigned int first,
                   unsigned int count, importance_result *r)
{
    if (importance_run_devices(devices + first, count, s, b, o, r))
        fail_msg("importance_run_devices on %u device(s): %s", count, error_message());
}

/* Everything the pass's outputs are made of, the same bit for bit. */
static void assert_same_result(const importance_result *one, const importance_result *several)
{
    size_t n = one->triangle_count;
    assert_int_equal(n, several->triangle_count);
    assert_int_equal(one->sppm.iterations, several->sppm.iterations);
    assert_memory_equal(one->camera, several->camera, n * sizeof *one->camera);
    assert_memory_equal(one->light, several->light, n * sizeof *one->light);
    assert_memory_equal(one->shadow, several->shadow, n * sizeof *one->shadow);
    assert_memory_equal(one->convergence, several->convergence,
                        one->sppm.iterations * sizeof *one->convergence);
    assert_memory_equal(one->sppm.radius, several->sppm.radius,
                        one->sppm.iterations * sizeof *one->sppm.radius);
    assert_memory_equal(&one->seen_light, &several->seen_light, sizeof one->seen_light);
    assert_int_equal(one->gathered, several->gathered);
    assert_int_equal(one->sppm.hit_points, several->sppm.hit_points);
    assert_int_equal(one->sppm.photon_records, several->sppm.photon_records);
    size_t pixels = (size_t)one->sppm.width * one->sppm.height;
    assert_memory_equal(one->pixel_triangle, several->pixel_triangle,
                        pixels * sizeof *one->pixel_triangle);
}

/* Each device traced its range every iteration, and together all the paths. */
static void assert_paths_shared(const importance_result *r, unsigned int count)
{
    assert_int_equal(r->sppm.devices, count);
    uint64_t paths = 0, last = 0;
    for (unsigned int k = 0; k < count; k++) {
        paths += r->sppm.device[k].paths;
        last += r->sppm.device[k].last_paths;
        assert_true(r->sppm.device[k].last_paths <= r->sppm.device[k].capacity);
    }
    assert_int_equal(paths, (uint64_t)r->sppm.photons * r->sppm.iterations);
    assert_int_equal(last, r->sppm.photons);
}

/* Devices 0 and 1, split by compute units and then by their measured speeds. */
static void test_two_devices_give_the_one_device_sums(void **state)
{
    (void)state;
    importance_result two;
    run_on(cornell.s, &cornell.b, &cornell.o, 0, 2, &two);
    assert_same_result(&cornell.one, &two);
    assert_paths_shared(&two, 2);
    assert_true(two.sppm.device[0].paths > 0 && two.sppm.device[1].paths > 0);
    importance_result_free(&two);
}

/* A fixed split of 1 : 7, then of 7 : 1: the first device's share is what it traced. */
static void test_uneven_fixed_splits_give_the_same_sums(void **state)
{
    (void)state;
    const double splits[2][2] = {{1, 7}, {7, 1}};
    for (int i = 0; i < 2; i++) {
        importance_options o = cornell.o;
        o.sppm.split = splits[i];
        o.sppm.fixed_split = 1;
        importance_result two;
        run_on(cornell.s, &cornell.b, &o, 0, 2, &two);
        assert_same_result(&cornell.one, &two);
        assert_paths_shared(&two, 2);
        unsigned int expected = (unsigned int)(MULTI_PHOTONS * splits[i][0] / 8);
        assert_int_equal(two.sppm.device[0].last_paths, expected);
        assert_int_equal(two.sppm.device[0].paths, (uint64_t)expected * MULTI_ITERATIONS);
        importance_result_free(&two);
    }
}

/* Three cores (device 0, device 1, device 0 in a second context), the first given almost no
 * photon paths: its camera-side sums still count once, the others' not at all. */
static void test_three_cores_and_a_tiny_first_share(void **state)
{
    (void)state;
    const double split[3] = {0.001, 2, 3};
    importance_options o = cornell.o;
    o.sppm.split = split;
    importance_result three;
    run_on(cornell.s, &cornell.b, &o, 0, 3, &three);
    assert_same_result(&cornell.one, &three);
    assert_paths_shared(&three, 3);
    importance_result_free(&three);
}

/* The glass of water: light seen through glass and mirrors (seen light), specular paths; one
 * iteration more than rebalancing needs. */
static void test_glass_of_water_with_seen_light(void **state)
{
    (void)state;
    scene *s = test_load_scene(GLASS_OF_WATER_SCENE);
    bvh b;
    test_build_bvh(s, &b);
    importance_options o;
    test_importance_options(&o, 3, 10000);
    o.sppm.resolution = 0.25f;
    importance_result one, two;
    if (importance_run(devices, s, &b, &o, &one))
        fail_msg("importance_run: %s", error_message());
    run_on(s, &b, &o, 0, 2, &two);
    assert_true(one.seen_light > 0);
    assert_same_result(&one, &two);
    importance_result_free(&one);
    importance_result_free(&two);
    bvh_free(&b);
    scene_free(s);
}

/* sppm_split_paths on cases worked out by hand. */
static void test_split_paths_by_hand(void **state)
{
    (void)state;
    unsigned int counts[3];
    /* equal weights, room everywhere: 7 = 2.33 each, rounded down, the 1 left to the first */
    sppm_split_paths(7, 3, (const double[]){1, 1, 1}, (const unsigned int[]){7, 7, 7}, counts);
    assert_int_equal(counts[0], 3);
    assert_int_equal(counts[1], 2);
    assert_int_equal(counts[2], 2);
    /* the fast device (9 : 1) is full at 6: the rest goes to the slow one */
    sppm_split_paths(10, 2, (const double[]){9, 1}, (const unsigned int[]){6, 10}, counts);
    assert_int_equal(counts[0], 6);
    assert_int_equal(counts[1], 4);
    /* 1 : 3 of 8 */
    sppm_split_paths(8, 2, (const double[]){1, 3}, (const unsigned int[]){8, 8}, counts);
    assert_int_equal(counts[0], 2);
    assert_int_equal(counts[1], 6);
    /* the second full at 1, the third at 2: the first takes the rest */
    sppm_split_paths(9, 3, (const double[]){1, 5, 5}, (const unsigned int[]){9, 1, 2}, counts);
    assert_int_equal(counts[0], 6);
    assert_int_equal(counts[1], 1);
    assert_int_equal(counts[2], 2);
}

/* A device budget that no device meets: the error names the first device checked. */
static void test_memory_error_names_the_device(void **state)
{
    (void)state;
    importance_options o = cornell.o;
    o.sppm.device_budget = 4096;
    importance_result r;
    error_clear();
    assert_int_equal(importance_run_devices(devices, 2, cornell.s, &cornell.b, &o, &r), -1);
    assert_non_null(strstr(error_message(), "device 0 ("));
    assert_non_null(strstr(error_message(), "memory budget"));
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    importance_result_free(&r);
}

/* importance_add_words: the devices' words added as integers, then converted once. 2^53 + 1
 * and 1 make 2^53 + 2, a double; converted one by one they would make 2^53 + 1 -> 2^53 (ties to
 * even), and 2^53 + 1.0 -> 2^53 again. A sum at the saturation limit is an error naming it. */
static void test_words_are_added_as_integers(void **state)
{
    (void)state;
    const uint64_t big = (1ull << 53) + 1;
    const uint64_t first[3] = {big, 3, 0}, second[3] = {1, 5, 0}, third[3] = {0, 0, 7};
    const uint64_t *words[3] = {first, second, third};
    double sums[3] = {0, 1, 0}, added = 0;
    assert_int_equal(importance_add_words(sums, words, 3, 3, 1.0, "light", "less", &added), 0);
    assert_true(sums[0] == 0x1p53 + 2);
    assert_true(sums[1] == 9);
    assert_true(sums[2] == 7);
    assert_true(added == 0x1p53 + 2 + 8 + 7);
    /* the scale of the accumulators: one product of the integer sum */
    double scaled[1] = {0};
    const uint64_t odd[1] = {(1ull << 60) + 3}, even[1] = {(1ull << 58) + 5};
    const uint64_t *pair[2] = {odd, even};
    assert_int_equal(importance_add_words(scaled, pair, 2, 1, 1.0 / 1048576.0, "light", "less",
                                          NULL), 0);
    assert_true(scaled[0] == (double)(odd[0] + even[0]) / 1048576.0);
    /* 2^61 + 2^61 reaches the limit of 2^62 */
    const uint64_t half[1] = {1ull << 61};
    const uint64_t *halves[2] = {half, half};
    error_clear();
    assert_int_equal(importance_add_words(scaled, halves, 2, 1, 1.0, "light importance",
                                          "fewer photons per iteration", NULL), -1);
    assert_non_null(strstr(error_message(), "light importance of triangle 0"));
}

/* bin/idmr importance --device all (and 1,0) against --device 0: simulation.bin byte for byte;
 * report.json names both devices; `reduce --device all` writes the same reduced scene and
 * importance maps. The renderer and a memory budget refuse more than one device, a list with a
 * device twice is refused. */
static void test_cli_device_all_writes_the_same_simulation(void **state)
{
    (void)state;
    char dir[64];
    make_temp_dir(dir, "idmr-test-multi");
    const char *common = "data/cornell/scene.xml --photons 20000 --iterations 4 --resolution 0.5 "
                         "--quiet";
    run_result r = run("bin/idmr importance %s --device 0 -o %s/one", common, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("bin/idmr importance %s --device all -o %s/all", common, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("bin/idmr importance %s --device 1,0 -o %s/list", common, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("(cmp %s/one/simulation.bin %s/all/simulation.bin && "
            "cmp %s/one/simulation.bin %s/list/simulation.bin)",
            dir, dir, dir, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("grep -c '\"paths\"' %s/all/report.json", dir);
    assert_succeeded(&r);
    assert_string_equal(r.out, "2\n");
    run_free(&r);
    r = run("(bin/idmr reduce %s --target 0.5 --device 0 -o %s/reduced-one && "
            "bin/idmr reduce %s --target 0.5 --device all -o %s/reduced-all && "
            "cmp %s/reduced-one/meshes/knot.ply %s/reduced-all/meshes/knot.ply && "
            "cmp %s/reduced-one/scene.xml %s/reduced-all/scene.xml && "
            "diff -r %s/reduced-one/importance %s/reduced-all/importance)",
            common, dir, common, dir, dir, dir, dir, dir, dir, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("bin/idmr reduce %s --memory-budget 100M --device all -o %s/budget", common, dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "plans the scene for one device"));
    run_free(&r);
    r = run("bin/idmr render data/cornell/scene.xml --device all --iterations 1 -o %s/x.exr", dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "renderer runs on one device"));
    run_free(&r);
    r = run("bin/idmr importance data/cornell/scene.xml --device 0,0 -o %s/twice", dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "device 0 is listed twice"));
    run_free(&r);
    remove_tree(dir);
}

int main(void)
{
    /* Before the first OpenCL call: PoCL reads it when the platform is first asked for. */
    setenv("POCL_DEVICES", "pthread pthread", 1);
    unsetenv("IDMR_DEVICE");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_split_paths_by_hand),
        cmocka_unit_test(test_words_are_added_as_integers),
        cmocka_unit_test(test_two_devices_give_the_one_device_sums),
        cmocka_unit_test(test_uneven_fixed_splits_give_the_same_sums),
        cmocka_unit_test(test_three_cores_and_a_tiny_first_share),
        cmocka_unit_test(test_glass_of_water_with_seen_light),
        cmocka_unit_test(test_memory_error_names_the_device),
        cmocka_unit_test(test_cli_device_all_writes_the_same_simulation),
    };
    return cmocka_run_group_tests_name("multi-device importance", tests, open_devices,
                                       close_devices) != 0;
}
