/* test_cli.c — bin/idmr end to end: exit codes, messages, and the JSON of `devices` and
 * `info` on the shipped Cornell box and on real scenes from ../shared/data; one warning per
 * bsdf; option errors of importance, reduce and render; `reduce` (both importance methods) and
 * `render` on the shipped scene, with `compare` on its images.
 * Runs from the repository root (as `make test` does). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

typedef struct run_result {
    int status;
    char *out;
    char *err;
} run_result;

static char *slurp(FILE *f)
{
    size_t size = 0, capacity = 4096;
    char *text = malloc(capacity);
    size_t got;
    while ((got = fread(text + size, 1, capacity - size - 1, f)) > 0) {
        size += got;
        if (capacity - size < 2) {
            capacity *= 2;
            text = realloc(text, capacity);
        }
    }
    text[size] = '\0';
    return text;
}

/* Runs a shell command line; captures stdout, stderr and the exit status. */
static run_result run(const char *command)
{
    char err_path[] = "/tmp/idmr-test-cli-XXXXXX";
    int fd = mkstemp(err_path);
    close(fd);
    char line[4096];
    snprintf(line, sizeof line, "%s 2>%s", command, err_path);
    FILE *p = popen(line, "r");
    run_result r;
    r.out = slurp(p);
    int status = pclose(p);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    FILE *e = fopen(err_path, "r");
    r.err = slurp(e);
    fclose(e);
    unlink(err_path);
    return r;
}

static void run_free(run_result *r)
{
    free(r->out);
    free(r->err);
}

static cJSON *parse_or_fail(const char *text)
{
    cJSON *json = cJSON_Parse(text);
    if (!json)
        fail_msg("not JSON: %.200s", text);
    return json;
}

static int array_has_string(const cJSON *array, const char *value)
{
    const cJSON *item;
    cJSON_ArrayForEach(item, array) if (cJSON_IsString(item) && !strcmp(item->valuestring, value))
        return 1;
    return 0;
}

static void test_devices_json(void **state)
{
    run_result r = run("bin/idmr devices --json");
    assert_int_equal(r.status, 0);
    cJSON *json = parse_or_fail(r.out);
    assert_true(cJSON_IsArray(json));
    assert_true(cJSON_GetArraySize(json) >= 1);
    const cJSON *d = cJSON_GetArrayItem(json, 0);
    assert_true(cJSON_IsString(cJSON_GetObjectItem(d, "kind")));
    assert_true(cJSON_GetObjectItem(d, "compute_units")->valuedouble >= 1);
    assert_true(cJSON_GetObjectItem(d, "global_memory")->valuedouble > 0);
    assert_non_null(strstr(cJSON_GetObjectItem(d, "opencl_c_version")->valuestring, "OpenCL C"));
    cJSON_Delete(json);
    run_free(&r);
}

/* With no ICD registered the loader finds no platform: exit 2 and advice to install PoCL. */
static void test_no_platform(void **state)
{
    char dir[] = "/tmp/idmr-no-icd-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char command[256];
    snprintf(command, sizeof command, "OCL_ICD_VENDORS=%s bin/idmr devices", dir);
    run_result r = run(command);
    rmdir(dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "no OpenCL platform"));
    assert_non_null(strstr(r.err, "pocl-opencl-icd"));
    run_free(&r);
}

static void test_info_shipped_scene(void **state)
{
    run_result r = run("bin/idmr info --json data/cornell/scene.xml");
    assert_int_equal(r.status, 0);
    cJSON *json = parse_or_fail(r.out);
    const cJSON *meshes = cJSON_GetObjectItem(json, "meshes");
    assert_int_equal(cJSON_GetArraySize(meshes), 8);
    int found_knot = 0;
    const cJSON *m;
    cJSON_ArrayForEach(m, meshes)
    {
        assert_true(cJSON_IsString(cJSON_GetObjectItem(m, "name")));
        assert_true(cJSON_IsString(cJSON_GetObjectItem(m, "material")));
        assert_true(cJSON_IsNumber(cJSON_GetObjectItem(m, "vertices")));
        if (!strcmp(cJSON_GetObjectItem(m, "name")->valuestring, "knot")) {
            found_knot = 1;
            assert_int_equal(cJSON_GetObjectItem(m, "vertices")->valueint, 48000);
            assert_int_equal(cJSON_GetObjectItem(m, "triangles")->valueint, 96000);
        }
    }
    assert_true(found_knot);
    const cJSON *lights = cJSON_GetObjectItem(json, "lights");
    assert_int_equal(cJSON_GetArraySize(lights), 1);
    assert_string_equal(cJSON_GetObjectItem(cJSON_GetArrayItem(lights, 0), "type")->valuestring,
                        "area");
    const cJSON *features = cJSON_GetObjectItem(json, "features");
    assert_true(array_has_string(features, "diffuse"));
    assert_true(array_has_string(features, "area"));
    assert_false(array_has_string(features, "dielectric"));
    assert_false(array_has_string(features, "spot"));
    const cJSON *bbox = cJSON_GetObjectItem(json, "bbox");
    const cJSON *lo = cJSON_GetObjectItem(bbox, "min"), *hi = cJSON_GetObjectItem(bbox, "max");
    for (int k = 0; k < 3; k++) {
        assert_float_equal(cJSON_GetArrayItem(lo, k)->valuedouble, -1.0, 1e-5);
        assert_float_equal(cJSON_GetArrayItem(hi, k)->valuedouble, 1.0, 1e-5);
    }
    const cJSON *memory = cJSON_GetObjectItem(json, "device_memory");
    assert_true(cJSON_GetObjectItem(memory, "bvh")->valuedouble > 96000 * 48.0);
    cJSON_Delete(json);
    run_free(&r);
}

static void test_info_glass_of_water(void **state)
{
    run_result r =
        run("bin/idmr info --json ../shared/data/scenes/glass-of-water/scene-without-mesh000.xml");
    assert_int_equal(r.status, 0);
    cJSON *json = parse_or_fail(r.out);
    const cJSON *features = cJSON_GetObjectItem(json, "features");
    assert_true(array_has_string(features, "dielectric"));
    assert_true(array_has_string(features, "glossy"));
    assert_true(array_has_string(features, "area"));
    cJSON_Delete(json);
    run_free(&r);
}

static void test_info_living_room_warns_about_envmap(void **state)
{
    run_result r = run("bin/idmr info --json ../shared/data/scenes/living-room/scene.xml");
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.err, "envmap"));
    cJSON *json = parse_or_fail(r.out);
    assert_true(cJSON_GetArraySize(cJSON_GetObjectItem(json, "meshes")) >= 60);
    assert_true(array_has_string(cJSON_GetObjectItem(json, "features"), "textured"));
    cJSON_Delete(json);
    run_free(&r);
}

static void test_missing_mesh_is_named(void **state)
{
    run_result r = run("bin/idmr info ../shared/data/scenes/glass-of-water/scene.xml");
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "models/Mesh000.obj"));
    assert_string_equal(r.out, "");
    run_free(&r);
}

static void test_malformed_xml(void **state)
{
    char path[] = "/tmp/idmr-bad-XXXXXX.xml";
    int fd = mkstemps(path, 4);
    const char text[] = "<scene version=\"3.0.0\">\n  <shape type=\"obj\">\n</scene>\n";
    assert_int_equal(write(fd, text, sizeof text - 1), (ssize_t)(sizeof text - 1));
    close(fd);
    char command[256];
    snprintf(command, sizeof command, "bin/idmr info %s", path);
    run_result r = run(command);
    unlink(path);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, path));
    run_free(&r);
}

static void test_usage_errors(void **state)
{
    run_result r = run("bin/idmr frobnicate");
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "unknown command"));
    run_free(&r);
    r = run("bin/idmr info");
    assert_int_equal(r.status, 2);
    run_free(&r);
    r = run("bin/idmr info --bogus data/cornell/scene.xml");
    assert_int_equal(r.status, 2);
    run_free(&r);
    r = run("bin/idmr info /nonexistent/scene.xml");
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "/nonexistent/scene.xml"));
    run_free(&r);
}

/* A bsdf's warning comes once per bsdf: a declared one referenced by two shapes warns once,
 * an inline one once. */
static void test_each_bsdf_warns_once(void **state)
{
    char dir[] = "/tmp/idmr-cli-warn-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256], command[512];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("<scene version=\"3.0.0\">\n"
          "  <bsdf type=\"roughdielectric\" id=\"glass\"/>\n"
          "  <shape type=\"sphere\"><ref id=\"glass\"/></shape>\n"
          "  <shape type=\"cube\"><ref id=\"glass\"/></shape>\n"
          "  <shape type=\"rectangle\"><bsdf type=\"roughdielectric\"/></shape>\n"
          "</scene>\n",
          f);
    fclose(f);
    snprintf(command, sizeof command, "bin/idmr info %s", path);
    run_result r = run(command);
    assert_int_equal(r.status, 0);
    int count = 0;
    for (const char *at = r.err; (at = strstr(at, "roughdielectric is treated")); at++)
        count++;
    if (count != 2)
        fail_msg("expected 2 roughdielectric warnings, got %d:\n%s", count, r.err);
    run_free(&r);
    snprintf(command, sizeof command, "rm -rf %s", dir);
    assert_int_equal(system(command), 0);
}

/* importance, reduce and render: every bad option value is refused with exit 2 and a message naming it,
 * before any work starts. */
static void test_pass_option_errors(void **state)
{
    const struct {
        const char *command, *expect;
    } cases[] = {
        {"bin/idmr importance data/cornell/scene.xml", "-o DIR is required"},
        {"bin/idmr importance data/cornell/scene.xml -o /tmp/x --iterations 0", "--iterations"},
        {"bin/idmr importance data/cornell/scene.xml -o /tmp/x --photons many", "--photons"},
        {"bin/idmr importance data/cornell/scene.xml -o /tmp/x --alpha 1.5", "--alpha"},
        {"bin/idmr importance data/cornell/scene.xml -o /tmp/x --gamma -1", "--gamma"},
        {"bin/idmr reduce data/cornell/scene.xml -o /tmp/x", "--target D and -o OUTDIR"},
        {"bin/idmr reduce data/cornell/scene.xml -o /tmp/x --target 0", "--target"},
        {"bin/idmr reduce data/cornell/scene.xml -o /tmp/x --target 0.5 --method median",
         "'median'"},
        {"bin/idmr reduce data/cornell/scene.xml -o /tmp/x --target 0.5 --max-normal-angle 0",
         "--max-normal-angle"},
        {"bin/idmr render data/cornell/scene.xml", "-o IMAGE is required"},
        {"bin/idmr render data/cornell/scene.xml -o /tmp/x --iterations 0", "--iterations"},
        {"bin/idmr render data/cornell/scene.xml -o /tmp/x --gamma 2", "importance pass option"},
        {"bin/idmr render data/cornell/scene.xml -o /tmp/x --time-limit soon", "--time-limit"},
        {"bin/idmr render data/cornell/scene.xml -o /tmp/x --exposure 100", "--exposure"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        run_result r = run(cases[i].command);
        if (r.status != 2 || !strstr(r.err, cases[i].expect))
            fail_msg("'%s': exit %d, message '%s' (expected 2 and '%s')", cases[i].command,
                     r.status, r.err, cases[i].expect);
        run_free(&r);
    }
}

/* The main job from the command line: reduce the shipped scene (a short importance pass), and
 * the reduced scene loads again with the vertex total the report gives; importance-quadric
 * meets the same total with other collapses. */
static void test_reduce_shipped_scene(void **state)
{
    char dir[] = "/tmp/idmr-cli-reduce-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char command[512];
    snprintf(command, sizeof command,
             "bin/idmr reduce data/cornell/scene.xml --target 0.2 -o %s/out --iterations 2 "
             "--photons 20000 --resolution 0.25 --quiet",
             dir);
    run_result r = run(command);
    if (r.status != 0)
        fail_msg("reduce failed (%d): %s", r.status, r.err);
    assert_non_null(strstr(r.err, "reduced scene in"));
    run_free(&r);
    snprintf(command, sizeof command, "cat %s/out/report.json", dir);
    r = run(command);
    cJSON *report = parse_or_fail(r.out);
    double after = cJSON_GetObjectItem(report, "vertices_after")->valuedouble;
    double requested = cJSON_GetObjectItem(report, "vertices_requested")->valuedouble;
    assert_true(after == requested); /* the knot is the only mesh above the floor */
    assert_string_equal(cJSON_GetObjectItem(report, "method")->valuestring, "importance");
    cJSON_Delete(report);
    run_free(&r);
    snprintf(command, sizeof command, "bin/idmr info --json --no-bvh %s/out/scene.xml", dir);
    r = run(command);
    assert_int_equal(r.status, 0);
    cJSON *info = parse_or_fail(r.out);
    assert_true(cJSON_GetObjectItem(info, "vertices")->valuedouble == after);
    cJSON_Delete(info);
    run_free(&r);

    /* importance-quadric: the same budget (same seed, same importance), other collapses. */
    snprintf(command, sizeof command,
             "bin/idmr reduce data/cornell/scene.xml --target 0.2 -o %s/hybrid "
             "--method importance-quadric --iterations 2 --photons 20000 --resolution 0.25 "
             "--quiet",
             dir);
    r = run(command);
    if (r.status != 0)
        fail_msg("reduce --method importance-quadric failed (%d): %s", r.status, r.err);
    run_free(&r);
    snprintf(command, sizeof command, "cmp -s %s/out/meshes/knot.ply %s/hybrid/meshes/knot.ply",
             dir, dir);
    r = run(command);
    assert_int_equal(r.status, 1); /* cmp: the files differ */
    run_free(&r);
    snprintf(command, sizeof command, "cat %s/hybrid/report.json", dir);
    r = run(command);
    cJSON *hybrid = parse_or_fail(r.out);
    assert_string_equal(cJSON_GetObjectItem(hybrid, "method")->valuestring, "importance-quadric");
    assert_true(cJSON_GetObjectItem(hybrid, "vertices_after")->valuedouble == after);
    cJSON_Delete(hybrid);
    run_free(&r);
    snprintf(command, sizeof command, "rm -rf %s", dir);
    assert_int_equal(system(command), 0);
}

/* idmr render on the shipped scene: IMAGE.exr, IMAGE.png and IMAGE.json beside each other (the
 * directory created), the report's figures, --time-limit stopping after the first iteration,
 * and `compare` telling a render from itself and from another seed's. */
static void test_render_shipped_scene(void **state)
{
    char dir[] = "/tmp/idmr-cli-render-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char command[768];
    const char *common = "--photons 20000 --resolution 0.25 --quiet";
    snprintf(command, sizeof command,
             "bin/idmr render data/cornell/scene.xml -o %s/images/a.exr --iterations 3 %s", dir,
             common);
    run_result r = run(command);
    if (r.status != 0)
        fail_msg("render failed (%d): %s", r.status, r.err);
    assert_non_null(strstr(r.out, "s per iteration"));
    run_free(&r);
    snprintf(command, sizeof command, "cat %s/images/a.json", dir);
    r = run(command);
    cJSON *report = parse_or_fail(r.out);
    assert_int_equal(cJSON_GetObjectItem(report, "iterations")->valueint, 3);
    assert_int_equal(cJSON_GetObjectItem(report, "width")->valueint, 64);
    assert_int_equal(cJSON_GetObjectItem(report, "photons_per_iteration")->valueint, 20000);
    cJSON *memory = cJSON_GetObjectItem(report, "device_bytes");
    double geometry = cJSON_GetObjectItem(memory, "geometry")->valuedouble;
    double bvh = cJSON_GetObjectItem(memory, "bvh")->valuedouble;
    double sppm = cJSON_GetObjectItem(memory, "sppm")->valuedouble;
    assert_true(geometry > 0 && bvh > 0 && sppm > 0);
    assert_true(cJSON_GetObjectItem(memory, "total")->valuedouble == geometry + bvh + sppm);
    cJSON *seconds = cJSON_GetObjectItem(report, "seconds");
    assert_true(cJSON_GetObjectItem(seconds, "per_iteration")->valuedouble > 0);
    assert_non_null(cJSON_GetObjectItem(seconds, "per_iteration_by_stage"));
    cJSON_Delete(report);
    run_free(&r);
    /* `info` reports the geometry memory the render allocated. */
    r = run("bin/idmr info --json --no-bvh data/cornell/scene.xml");
    cJSON *info = parse_or_fail(r.out);
    assert_true(cJSON_GetObjectItem(cJSON_GetObjectItem(info, "device_memory"), "geometry")
                    ->valuedouble == geometry);
    cJSON_Delete(info);
    run_free(&r);

    snprintf(command, sizeof command,
             "bin/idmr render data/cornell/scene.xml -o %s/images/b --iterations 5 --seed 2 "
             "--time-limit 0.000001 %s && cat %s/images/b.json && ls %s/images",
             dir, common, dir, dir);
    r = run(command);
    if (r.status != 0)
        fail_msg("render failed (%d): %s", r.status, r.err);
    assert_non_null(strstr(r.out, "\"iterations\":\t1,"));
    assert_non_null(strstr(r.out, "b.exr"));
    assert_non_null(strstr(r.out, "b.png"));
    assert_non_null(strstr(r.out, "a.png"));
    run_free(&r);

    snprintf(command, sizeof command, "bin/idmr compare --json %s/images/a.exr %s/images/a.exr",
             dir, dir);
    r = run(command);
    assert_int_equal(r.status, 0);
    cJSON *same = parse_or_fail(r.out);
    assert_true(cJSON_GetObjectItem(same, "rmse")->valuedouble == 0);
    cJSON_Delete(same);
    run_free(&r);
    snprintf(command, sizeof command, "bin/idmr compare --json %s/images/b.exr %s/images/a.exr",
             dir, dir);
    r = run(command);
    assert_int_equal(r.status, 0);
    cJSON *other = parse_or_fail(r.out);
    assert_true(cJSON_GetObjectItem(other, "rmse")->valuedouble > 0);
    cJSON_Delete(other);
    run_free(&r);
    snprintf(command, sizeof command, "rm -rf %s", dir);
    assert_int_equal(system(command), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_devices_json),
        cmocka_unit_test(test_no_platform),
        cmocka_unit_test(test_info_shipped_scene),
        cmocka_unit_test(test_info_glass_of_water),
        cmocka_unit_test(test_info_living_room_warns_about_envmap),
        cmocka_unit_test(test_missing_mesh_is_named),
        cmocka_unit_test(test_malformed_xml),
        cmocka_unit_test(test_each_bsdf_warns_once),
        cmocka_unit_test(test_usage_errors),
        cmocka_unit_test(test_pass_option_errors),
        cmocka_unit_test(test_reduce_shipped_scene),
        cmocka_unit_test(test_render_shipped_scene),
    };
    return cmocka_run_group_tests_name("cli", tests, NULL, NULL);
}
