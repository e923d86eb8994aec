/* test_instance_totals.c — each instance's own importance totals (passes/importance.h, "Copies";
 * kernels/lib/paths.h, importance_add): beside its prototype's per-triangle sums, every copy of
 * an instanced shape keeps its own camera, light and shadow totals, added by the kernels from the
 * paths that met that copy. The scene: instanced_cornell.h's box with its knot placed four
 * times — "seen" where the box has it, "turned", "mirrored" (a non-uniform mirroring scale), and
 * "hidden" behind the back wall (z = -5: the box's one opening faces the camera, so neither a
 * camera path nor a photon path can get there) — and the same scene written flat (each copy a
 * mesh of its own), and a variant whose knots are mirrors.
 *
 *   words add up     the last iteration's fixed-point words (the snapshot), every kind: the
 *                    knot's instances' words add up to its triangles' words exactly (integers),
 *                    prototype 0's instance word to the triangles of the meshes that are not
 *                    instanced; over the run the copies' double totals add up to the
 *                    prototype's sums, and importance_copy_sums() to importance_mesh_sums() of
 *                    the representative, within the rounding of doubles (1e-12 relative)
 *   hidden copy      every total exactly 0; the three others have camera and light importance
 *   as flattened     each copy's totals against its flat twin's mesh sums: within 2 % (the
 *                    passes trace the same paths up to the rounding of the placement,
 *                    test_instanced_passes) where the twin's sum is not small; the hidden one 0
 *   mirror knots     seen light (camera paths that reach the light through the mirrors) goes
 *                    to the copies too: its words add up as above, and are not all 0
 *   two devices      the device under test and a second context on it (sppm_run_devices, a
 *                    fixed 1 : 3 split of the photon paths): the copy totals of one device bit
 *                    for bit
 *   simulation.bin   written and read back: the copy totals bit for bit; the same file made a
 *                    version 4 one (no copy totals) is refused for this scene with a message,
 *                    and read for a flat scene, its copy totals 0
 *   flat scene       no instance words, copy totals all 0
 *   CLI              `idmr importance` report.json: every copy has copy_importance_sum (the
 *                    representative's importance_sum the prototype's, their sum), and `idmr
 *                    reduce --simulation` keeps them in its report */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "command_common.h"
#include "core/hash.h"
#include "instanced_cornell.h"
#include "passes/importance_file.h"
#include "test_support.h"

#define COPIES 4
static const char *const copy_names[COPIES] = {"seen", "turned", "mirrored", "hidden"};
static const char *const copy_placements[COPIES] = {
    "",
    "<scale value=\"0.5\"/><rotate y=\"1\" angle=\"40\"/><translate x=\"-0.3\" y=\"0.6\" z=\"0.1\"/>",
    "<scale x=\"-0.6\" y=\"0.45\" z=\"0.75\"/><translate y=\"0.2\"/>",
    "<translate z=\"-5\"/>"};
static const int copy_mirrored[COPIES] = {0, 0, 1, 0};
enum { HIDDEN = 3 };

#define ITERATIONS 4
#define PHOTONS 100000

/* The scenes, their runs (made on first use: per device, freed in the group teardown). */
typedef struct totals_case {
    char dir[64];
    char instanced_path[4200], flat_path[4200], mirrors_path[4200];
    scene *instanced, *flat;
    importance_options o;
    importance_result run; /* the instanced scene, seed 1 */
    int has_run;
} totals_case;

static totals_case c;

static int group_setup(void **state)
{
    (void)state;
    memset(&c, 0, sizeof c);
    make_temp_dir(c.dir, "idmr-instance-totals");
    instanced_cornell_variant four = {COPIES, copy_names, copy_placements, copy_mirrored,
                                      "<ref id=\"orange\"/>"};
    instanced_cornell_variant mirrors = four;
    mirrors.bsdf = "<bsdf type=\"conductor\"/>";
    if (instanced_cornell_write_variant(c.dir, 0, 1.0, &four, "", c.instanced_path,
                                        sizeof c.instanced_path) ||
        instanced_cornell_write_variant(c.dir, 1, 1.0, &four, "", c.flat_path,
                                        sizeof c.flat_path) ||
        instanced_cornell_write_variant(c.dir, 0, 1.0, &mirrors, "-mirrors", c.mirrors_path,
                                        sizeof c.mirrors_path))
        return -1;
    c.instanced = test_load_scene(c.instanced_path);
    c.flat = test_load_scene(c.flat_path);
    test_importance_options(&c.o, ITERATIONS, PHOTONS);
    c.o.sppm.resolution = 0.5f;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    if (c.has_run)
        importance_result_free(&c.run);
    scene_free(c.instanced);
    scene_free(c.flat);
    remove_tree(c.dir);
    return 0;
}

/* The instanced scene's run with c.o on the device under test (once per device). */
static const importance_result *instanced_run(void)
{
    if (!c.has_run) {
        test_run_importance(c.instanced, NULL, &c.o, &c.run);
        c.has_run = 1;
    }
    return &c.run;
}

/* Mesh index of copy k of the knot in the instanced scene. */
static size_t copy_mesh(const scene *s, int k)
{
    char name[64];
    snprintf(name, sizeof name, "%s/knot", copy_names[k]);
    return (size_t)(test_find_mesh(s, name) - s->meshes);
}

/* Σ over mesh m's triangles of a per-triangle array. */
static double mesh_sum(const scene_mesh *m, const double *per_triangle)
{
    double sum = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        sum += per_triangle[m->first_triangle + t];
    return sum;
}

static int close_to(double x, double y, double relative)
{
    return fabs(x - y) <= relative * fmax(fabs(x), fabs(y));
}

/* Checks one kind's words of one iteration (snapshot): each prototype's instance words add up to
 * its triangles' words, as integers. Returns the knot copies' instance words' sum. */
static uint64_t assert_words_add_up(const scene *s, const uint64_t *words, const char *kind)
{
    size_t *mesh_of = malloc((s->mesh_count + 1) * sizeof *mesh_of);
    size_t instances = bvh_scene_instances(s, mesh_of);
    assert_int_equal(instances, 1 + COPIES); /* the box's own meshes, four knots */
    uint64_t triangles_plain = 0, triangles_knot = 0, plain = 0, knot = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        if (scene_mesh_is_later_copy(s, m))
            continue; /* its triangles are its representative's */
        uint64_t sum = 0;
        for (uint32_t t = 0; t < mesh->triangle_count; t++)
            sum += words[mesh->first_triangle + t];
        *(mesh->instanced ? &triangles_knot : &triangles_plain) += sum;
    }
    for (size_t i = 0; i < instances; i++) {
        uint64_t word = words[s->triangle_count + i];
        *(mesh_of[i] == BVH_NO_MESH ? &plain : &knot) += word;
    }
    print_message("  %s words: knot triangles %llu, its instances %llu; other triangles %llu, "
                  "prototype 0's instance %llu\n",
                  kind, (unsigned long long)triangles_knot, (unsigned long long)knot,
                  (unsigned long long)triangles_plain, (unsigned long long)plain);
    assert_true(knot == triangles_knot);
    assert_true(plain == triangles_plain);
    free(mesh_of);
    return knot;
}

/* The copies' totals of kind per_mesh against the prototype's sum of its per-triangle array. */
static void assert_copies_add_up(const scene *s, const double *per_mesh, const double *per_triangle,
                                 const char *kind)
{
    double copies = 0;
    for (int k = 0; k < COPIES; k++)
        copies += per_mesh[copy_mesh(s, k)];
    double prototype = mesh_sum(&s->meshes[copy_mesh(s, 0)], per_triangle);
    print_message("  %s: copies' totals %.10g, prototype's triangles %.10g\n", kind, copies,
                  prototype);
    assert_true(prototype > 0 || strcmp(kind, "shadow") == 0);
    assert_true(close_to(copies, prototype, 1e-12));
}

static void test_totals_add_up_to_the_prototype(void **state)
{
    (void)state;
    const scene *s = c.instanced;
    importance_snapshot snapshot;
    memset(&snapshot, 0, sizeof snapshot);
    importance_options o = c.o;
    o.snapshot = &snapshot;
    importance_result r;
    test_run_importance(s, NULL, &o, &r);
    assert_true(assert_words_add_up(s, snapshot.camera_fixed, "camera") > 0);
    assert_true(assert_words_add_up(s, snapshot.light_fixed, "light") > 0);
    assert_true(assert_words_add_up(s, snapshot.shadow_fixed, "shadow") > 0);
    assert_words_add_up(s, snapshot.seen_light_fixed, "seen light");
    importance_snapshot_free(&snapshot);
    assert_copies_add_up(s, r.copy_camera, r.camera, "camera");
    assert_copies_add_up(s, r.copy_light, r.light, "light");
    assert_copies_add_up(s, r.copy_shadow, r.shadow, "shadow");
    importance_weights w = importance_weights_of(&o);
    importance_sums prototype = importance_mesh_sums(&r, s, copy_mesh(s, 0), &w), copies = {0};
    for (int k = 0; k < COPIES; k++) {
        importance_sums own = importance_copy_sums(&r, s, copy_mesh(s, k), &w);
        print_message("  copy %-8s amount %.6g (camera %.6g, light %.6g, shadow %.6g)\n",
                      copy_names[k], own.amount, own.camera, own.light, own.shadow);
        copies.amount += own.amount;
        copies.camera += own.camera;
        copies.light += own.light;
        copies.shadow += own.shadow;
    }
    print_message("  prototype amount %.6g, copies' %.6g\n", prototype.amount, copies.amount);
    assert_true(close_to(copies.amount, prototype.amount, 1e-12));
    assert_true(close_to(copies.camera, prototype.camera, 1e-12));
    assert_true(close_to(copies.light, prototype.light, 1e-12));
    assert_true(close_to(copies.shadow, prototype.shadow, 1e-12));
    /* a mesh that is not instanced has none */
    size_t floor = (size_t)(test_find_mesh(s, "floor") - s->meshes);
    importance_sums none = importance_copy_sums(&r, s, floor, &w);
    assert_true(none.amount == 0 && r.copy_camera[floor] == 0 && r.copy_light[floor] == 0);
    importance_result_free(&r);
}

static void test_hidden_copy_has_nothing(void **state)
{
    (void)state;
    const scene *s = c.instanced;
    const importance_result *r = instanced_run();
    size_t hidden = copy_mesh(s, HIDDEN);
    assert_true(r->copy_camera[hidden] == 0);
    assert_true(r->copy_light[hidden] == 0);
    assert_true(r->copy_shadow[hidden] == 0);
    for (int k = 0; k < COPIES; k++)
        if (k != HIDDEN) {
            size_t m = copy_mesh(s, k);
            assert_true(r->copy_camera[m] > 0);
            assert_true(r->copy_light[m] > 0);
        }
    assert_true(r->copy_shadow[copy_mesh(s, 0)] > 0); /* the knot where the box has it */
}

static void test_totals_as_flattened(void **state)
{
    (void)state;
    const importance_result *r = instanced_run();
    importance_result flat;
    test_run_importance(c.flat, NULL, &c.o, &flat);
    importance_weights w = importance_weights_of(&c.o);
    const char *kinds[3] = {"camera", "light", "shadow"};
    for (int k = 0; k < COPIES; k++) {
        char name[64];
        snprintf(name, sizeof name, "%s_knot", copy_names[k]);
        size_t twin = (size_t)(test_find_mesh(c.flat, name) - c.flat->meshes);
        importance_sums own = importance_copy_sums(r, c.instanced, copy_mesh(c.instanced, k), &w);
        importance_sums flat_sums = importance_mesh_sums(&flat, c.flat, twin, &w);
        double a[3] = {own.camera, own.light, own.shadow};
        double b[3] = {flat_sums.camera, flat_sums.light, flat_sums.shadow};
        /* small: under 1 % of the copies' largest (a few samples: Monte Carlo error) */
        double largest[3] = {0, 0, 0};
        for (int j = 0; j < COPIES; j++) {
            importance_sums other =
                importance_copy_sums(r, c.instanced, copy_mesh(c.instanced, j), &w);
            largest[0] = fmax(largest[0], other.camera);
            largest[1] = fmax(largest[1], other.light);
            largest[2] = fmax(largest[2], other.shadow);
        }
        for (int kind = 0; kind < 3; kind++) {
            print_message("  %-8s %-6s instanced %.6g, flat %.6g\n", copy_names[k], kinds[kind],
                          a[kind], b[kind]);
            if (k == HIDDEN)
                assert_true(a[kind] == 0 && b[kind] == 0);
            else
                assert_true(fabs(a[kind] - b[kind]) <= 0.02 * fmax(a[kind], b[kind]) ||
                            fmax(a[kind], b[kind]) < 0.01 * largest[kind]);
        }
    }
    importance_result_free(&flat);
}

static void test_mirror_knots_credit_seen_light(void **state)
{
    (void)state;
    scene *s = test_load_scene(c.mirrors_path);
    importance_snapshot snapshot;
    memset(&snapshot, 0, sizeof snapshot);
    importance_options o = c.o;
    o.snapshot = &snapshot;
    importance_result r;
    test_run_importance(s, NULL, &o, &r);
    assert_true(assert_words_add_up(s, snapshot.seen_light_fixed, "seen light") > 0);
    assert_words_add_up(s, snapshot.camera_fixed, "camera");
    assert_words_add_up(s, snapshot.light_fixed, "light");
    assert_words_add_up(s, snapshot.shadow_fixed, "shadow");
    assert_true(r.seen_light > 0);
    assert_copies_add_up(s, r.copy_light, r.light, "light (with the seen light)");
    assert_true(r.copy_light[copy_mesh(s, HIDDEN)] == 0);
    importance_snapshot_free(&snapshot);
    importance_result_free(&r);
    scene_free(s);
}

static void test_two_devices_keep_the_totals(void **state)
{
    (void)state;
    const importance_result *one = instanced_run();
    device devices[2];
    int index = device_test_device()->info.index;
    for (int j = 0; j < 2; j++)
        if (device_open(devices + j, index))
            fail_msg("device_open(%d): %s", index, error_message());
    const double split[2] = {1, 3};
    importance_options o = c.o;
    o.sppm.split = split;
    o.sppm.fixed_split = 1;
    bvh b;
    test_build_bvh(c.instanced, &b);
    importance_result two;
    if (importance_run_devices(devices, 2, c.instanced, &b, &o, &two))
        fail_msg("importance_run_devices: %s", error_message());
    assert_int_equal(two.sppm.devices, 2);
    assert_true(two.sppm.device[0].paths > 0 && two.sppm.device[1].paths > 0);
    size_t n = one->triangle_count, meshes = c.instanced->mesh_count;
    assert_int_equal(two.mesh_count, meshes);
    assert_memory_equal(one->light, two.light, n * sizeof *one->light);
    assert_memory_equal(one->copy_camera, two.copy_camera, meshes * sizeof *one->copy_camera);
    assert_memory_equal(one->copy_light, two.copy_light, meshes * sizeof *one->copy_light);
    assert_memory_equal(one->copy_shadow, two.copy_shadow, meshes * sizeof *one->copy_shadow);
    importance_result_free(&two);
    bvh_free(&b);
    for (int j = 0; j < 2; j++)
        device_close(devices + j);
}

/* The version 5 file at `path` rewritten as version 4 (no `meshes`, no copy totals) at `out`. */
static void write_as_version_4(const char *path, const char *out, const scene *s)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    size_t size = (size_t)ftell(f);
    rewind(f);
    unsigned char *bytes = malloc(size), *old = malloc(size);
    assert_int_equal(fread(bytes, 1, size, f), size);
    fclose(f);
    assert_true(size > 88);
    uint64_t triangles, meshes;
    uint32_t iterations;
    memcpy(&triangles, bytes + 16, sizeof triangles);
    memcpy(&iterations, bytes + 24, sizeof iterations);
    memcpy(&meshes, bytes + 80, sizeof meshes);
    assert_int_equal(meshes, s->mesh_count);
    size_t arrays = 16 * (size_t)iterations + 24 * (size_t)triangles;
    size_t copies = 24 * (size_t)meshes, rest = size - 88 - arrays - copies - 8;
    memcpy(old, "IDMRSIM4", 8);
    memcpy(old + 8, bytes + 8, 72);
    memcpy(old + 80, bytes + 88, arrays);
    memcpy(old + 80 + arrays, bytes + 88 + arrays + copies, rest);
    size_t body = 80 + arrays + rest;
    uint64_t checksum = hash_fnv1a(HASH_FNV1A_START, old, body);
    memcpy(old + body, &checksum, sizeof checksum);
    f = fopen(out, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(old, 1, body + 8, f), body + 8);
    assert_int_equal(fclose(f), 0);
    free(bytes);
    free(old);
}

static void test_simulation_file_keeps_the_totals(void **state)
{
    (void)state;
    const importance_result *r = instanced_run();
    char path[4200], old[4200];
    snprintf(path, sizeof path, "%s/simulation.bin", c.dir);
    snprintf(old, sizeof old, "%s/version4.bin", c.dir);
    assert_int_equal(importance_file_write(path, c.instanced, &c.o, r), 0);
    importance_result back;
    if (importance_file_read(path, c.instanced, &c.o, &back))
        fail_msg("importance_file_read: %s", error_message());
    size_t meshes = c.instanced->mesh_count;
    assert_int_equal(back.mesh_count, meshes);
    assert_memory_equal(r->copy_camera, back.copy_camera, meshes * sizeof *r->copy_camera);
    assert_memory_equal(r->copy_light, back.copy_light, meshes * sizeof *r->copy_light);
    assert_memory_equal(r->copy_shadow, back.copy_shadow, meshes * sizeof *r->copy_shadow);
    assert_memory_equal(r->camera, back.camera, r->triangle_count * sizeof *r->camera);
    importance_result_free(&back);
    /* version 4: refused for a scene with instances, read for a flat one */
    write_as_version_4(path, old, c.instanced);
    error_clear();
    assert_int_equal(importance_file_read(old, c.instanced, &c.o, &back), -1);
    print_message("  version 4, instanced: %s\n", error_message());
    assert_non_null(strstr(error_message(), "older idmr"));
    assert_non_null(strstr(error_message(), "instance"));
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    importance_result_free(&back);
    importance_options o = c.o;
    o.sppm.iterations = 1;
    importance_result flat;
    test_run_importance(c.flat, NULL, &o, &flat);
    for (size_t m = 0; m < c.flat->mesh_count; m++)
        assert_true(flat.copy_camera[m] == 0 && flat.copy_light[m] == 0 &&
                    flat.copy_shadow[m] == 0);
    assert_int_equal(importance_file_write(path, c.flat, &o, &flat), 0);
    write_as_version_4(path, old, c.flat);
    if (importance_file_read(old, c.flat, &o, &back))
        fail_msg("importance_file_read (version 4, flat): %s", error_message());
    assert_memory_equal(flat.light, back.light, flat.triangle_count * sizeof *flat.light);
    for (size_t m = 0; m < c.flat->mesh_count; m++)
        assert_true(back.copy_camera[m] == 0 && back.copy_light[m] == 0);
    importance_result_free(&back);
    importance_result_free(&flat);
}

/* report.json's mesh entry `name`. */
static cJSON *report_mesh(cJSON *report, const char *name)
{
    cJSON *mesh;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItem(report, "meshes"))
    {
        cJSON *n = cJSON_GetObjectItem(mesh, "name");
        if (n && strcmp(n->valuestring, name) == 0)
            return mesh;
    }
    fail_msg("report.json has no mesh '%s'", name);
    return NULL;
}

static cJSON *read_report(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot read %s", path);
    char *text = slurp(f);
    fclose(f);
    cJSON *report = cJSON_Parse(text);
    free(text);
    assert_non_null(report);
    return report;
}

/* Each copy's copy_importance_sum in report `path`; the representative's importance_sum is
 * their sum. */
static void assert_report_copies(const char *path)
{
    cJSON *report = read_report(path);
    double copies = 0;
    for (int k = 0; k < COPIES; k++) {
        char name[64];
        snprintf(name, sizeof name, "%s/knot", copy_names[k]);
        cJSON *own = cJSON_GetObjectItem(report_mesh(report, name), "copy_importance_sum");
        assert_non_null(own);
        assert_non_null(cJSON_GetObjectItem(report_mesh(report, name), "copy_light_sum"));
        assert_true(k == HIDDEN ? own->valuedouble == 0 : own->valuedouble > 0);
        copies += own->valuedouble;
    }
    double prototype =
        cJSON_GetObjectItem(report_mesh(report, "seen/knot"), "importance_sum")->valuedouble;
    assert_true(close_to(copies, prototype, 1e-9));
    assert_null(cJSON_GetObjectItem(report_mesh(report, "floor"), "copy_importance_sum"));
    cJSON_Delete(report);
}

static void test_cli_reports_the_totals(void **state)
{
    (void)state;
    char out[4200];
    snprintf(out, sizeof out, "%s/cli", c.dir);
    run_result r = run("bin/idmr importance %s --iterations 2 --photons 20000 --resolution 0.25 "
                       "--quiet -o %s/importance",
                       c.instanced_path, out);
    assert_succeeded(&r);
    run_free(&r);
    char path[4400];
    snprintf(path, sizeof path, "%s/importance/report.json", out);
    assert_report_copies(path);
    r = run("bin/idmr reduce %s --target 0.5 --simulation %s/importance/simulation.bin --quiet "
            "-o %s/reduced",
            c.instanced_path, out, out);
    assert_succeeded(&r);
    run_free(&r);
    snprintf(path, sizeof path, "%s/reduced/report.json", out);
    assert_report_copies(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_totals_add_up_to_the_prototype),
        cmocka_unit_test(test_hidden_copy_has_nothing),
        cmocka_unit_test(test_totals_as_flattened),
        cmocka_unit_test(test_mirror_knots_credit_seen_light),
        cmocka_unit_test(test_two_devices_keep_the_totals),
        cmocka_unit_test(test_simulation_file_keeps_the_totals),
        cmocka_unit_test(test_cli_reports_the_totals),
    };
    return DEVICE_TEST_RUN("instance totals", tests, group_setup, group_teardown) != 0;
}
