/* test_reduce_instances.c — `idmr reduce` keeps a Mitsuba scene's instances
 * (host/reduce/reduce_instances.c), end to end through reduce_run() on the shipped Cornell box
 * with its knot made a shapegroup's shape and placed by instances:
 *
 *   kept         the reduced scene holds the shapegroup, its instances and one PLY for the
 *                knot; vertices_after counts the prototype once and equals what the plan
 *                requested, vertices_rendered_after counts every copy (what the output holds
 *                flattened); each copy reports the copy it is reduced as
 *   in place     rewritten (D = 1), every copy, the mirrored one included, is where and as the
 *                input's: its box, area and signed volume (which a winding turned the wrong
 *                way negates) within float rounding
 *   summed       a copy that nothing sees or lights (behind the back wall) changes neither the
 *                stored total nor the prototype's importance: beside a sphere that competes
 *                for the budget by importance, the knot is planned to the same target with and
 *                without it, where counting copies in the plan, averaging their importance or
 *                planning them apart would not
 *   flattened    the same copies written as shapes of their own (the group's and the
 *                instance's transforms in one to_world) get the same importance: the
 *                prototype's sums (over its copies, on the two-level BVH) against the two flat
 *                shapes' together, camera and light within 1 %
 *   kept whole   --keep naming a copy keeps the prototype whole, in every instance
 *   two passes   after an initial reduction (each prototype reduced once, the other copies
 *                moved from it), the second pass simulates every copy reduced
 *   pbrt-v4      an object placed by three ObjectInstances (one mirrored) is written once, in
 *                its ObjectBegin, its instances kept; the copies read back keep the input's
 *                orientation relative to one another (signed volumes) */
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

#include "reduce_common.h"

/* DIR/scene.xml: the shipped Cornell box with its knot (by absolute path, under its own
 * to_world) made the shape of shapegroup "knots", placed by `instances` (XML text, which may
 * add other shapes). */
static void write_instanced_cornell(const char *dir, const char *instances, char *scene_path,
                                    size_t size)
{
    size_t length;
    char *xml = read_file(CORNELL, &length);
    char *knot_shape = strstr(xml, "    <shape type=\"ply\" id=\"knot\">");
    assert_non_null(knot_shape);
    char *after = strstr(knot_shape, "</shape>");
    assert_non_null(after);
    after += strlen("</shape>");
    char knot[4096];
    assert_non_null(realpath(KNOT, knot));
    *knot_shape = 0;
    snprintf(scene_path, size, "%s/scene.xml", dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f,
            "%s    <shape type=\"shapegroup\" id=\"knots\">\n"
            "        <shape type=\"ply\" id=\"knot\">\n"
            "            <string name=\"filename\" value=\"%s\"/>\n"
            "            <transform name=\"to_world\">\n"
            "                <rotate x=\"1\" angle=\"-70\"/>\n"
            "                <translate x=\"0.35\" y=\"-0.5\" z=\"0.25\"/>\n"
            "            </transform>\n"
            "            <ref id=\"orange\"/>\n"
            "        </shape>\n"
            "    </shape>\n%s%s",
            xml, knot, instances, after);
    assert_int_equal(fclose(f), 0);
    free(xml);
}

/* The knot where the Cornell box has it (seen), one smaller up left (turned), one mirrored in x
 * on the left. */
static const char three_instances[] =
    "    <shape type=\"instance\" id=\"seen\"><ref id=\"knots\"/></shape>\n"
    "    <shape type=\"instance\" id=\"turned\"><ref id=\"knots\"/>\n"
    "        <transform name=\"to_world\"><scale value=\"0.5\"/><rotate y=\"1\" angle=\"40\"/>"
    "<translate x=\"-0.3\" y=\"0.6\" z=\"0.1\"/></transform></shape>\n"
    "    <shape type=\"instance\" id=\"mirrored\"><ref id=\"knots\"/>\n"
    "        <transform name=\"to_world\"><scale x=\"-0.6\" y=\"0.6\" z=\"0.6\"/>"
    "<translate y=\"0.2\"/></transform></shape>\n";

/* How often `needle` occurs in DIR/NAME. */
static int occurrences(const char *dir, const char *name, const char *needle)
{
    char path[4200];
    size_t length;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char *text = read_file(path, &length);
    int count = 0;
    for (const char *at = text; (at = strstr(at, needle)); at += strlen(needle))
        count++;
    free(text);
    return count;
}

/* The instanced Cornell box of `instances`, written into a fresh directory and loaded. */
typedef struct instanced_case {
    char dir[64];
    scene *s;
} instanced_case;

static void instanced_case_open(instanced_case *c, const char *instances)
{
    char scene_path[4200];
    temp_dir(c->dir, sizeof c->dir);
    write_instanced_cornell(c->dir, instances, scene_path, sizeof scene_path);
    c->s = test_load_scene(scene_path);
}

static void instanced_case_close(instanced_case *c)
{
    scene_free(c->s);
    remove_tree(c->dir);
}

static void test_instances_kept(void **state)
{
    instanced_case c;
    instanced_case_open(&c, three_instances);
    scene *s = c.s;
    const scene_mesh *seen = test_find_mesh(s, "seen/knot");
    reduce_options o;
    small_options(&o);
    reduction r;
    reduction_run(&r, s, &o);
    assert_int_equal(occurrences(r.dir, "scene.xml", "type=\"shapegroup\""), 1);
    assert_int_equal(occurrences(r.dir, "scene.xml", "type=\"instance\""), 3);
    assert_int_equal(occurrences(r.dir, "scene.xml", "value=\"meshes/"), 1);
    assert_true(file_exists(r.dir, "meshes/knot.ply"));
    /* Stored: the prototype once (the scene's vertex_count); rendered: every copy. */
    assert_true(s->rendered_vertex_count == s->vertex_count + 2 * (uint64_t)seen->vertex_count);
    assert_true(number(r.report, "vertices_before") == (double)s->vertex_count);
    const scene_mesh *reduced = test_find_mesh(r.out, "seen/knot");
    assert_true(reduced->vertex_count < seen->vertex_count);
    assert_true(number(r.report, "vertices_after") == (double)r.out->vertex_count);
    assert_true(number(r.report, "vertices_after") == number(r.report, "vertices_requested"));
    assert_true(number(r.report, "vertices_rendered_after") ==
                (double)r.out->rendered_vertex_count);
    const char *copies[] = {"turned/knot", "mirrored/knot"};
    for (int k = 0; k < 2; k++) {
        const cJSON *entry = mesh_entry(r.report, copies[k]);
        const cJSON *of = cJSON_GetObjectItemCaseSensitive(entry, "instance_of");
        assert_true(cJSON_IsString(of) && strcmp(of->valuestring, "seen/knot") == 0);
        assert_true(number(entry, "vertices_after") == (double)reduced->vertex_count);
        assert_int_equal(test_find_mesh(r.out, copies[k])->vertex_count, reduced->vertex_count);
    }
    reduction_free(&r);
    instanced_case_close(&c);
}

/* Every mesh of s in memory: a later copy of an instanced shape holds its geometry only once
 * restored (core/scene.h), and these tests look at every copy where it stands. */
static void restore_all(scene *s)
{
    for (size_t m = 0; m < s->mesh_count; m++)
        if (scene_mesh_restore(s, m))
            fail_msg("%s", error_message());
}

/* A mesh's bounding box, area and signed volume (the divergence theorem's sum over its
 * triangles: negated by a winding turned the wrong way). */
typedef struct mesh_measure {
    double low[3], high[3], area, volume;
} mesh_measure;

static mesh_measure measure(const scene_mesh *m)
{
    mesh_measure r = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, 0, 0};
    for (uint32_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            r.low[k] = fmin(r.low[k], m->positions[3 * v + k]);
            r.high[k] = fmax(r.high[k], m->positions[3 * v + k]);
        }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *p[3];
        for (int c = 0; c < 3; c++)
            p[c] = &m->positions[3 * (size_t)m->indices[3 * t + c]];
        double a[3], b[3], n[3];
        for (int k = 0; k < 3; k++)
            a[k] = (double)p[1][k] - p[0][k], b[k] = (double)p[2][k] - p[0][k];
        n[0] = a[1] * b[2] - a[2] * b[1];
        n[1] = a[2] * b[0] - a[0] * b[2];
        n[2] = a[0] * b[1] - a[1] * b[0];
        r.area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        r.volume += (p[0][0] * n[0] + p[0][1] * n[1] + p[0][2] * n[2]) / 6.0;
    }
    return r;
}

static void test_instances_rewritten_in_place(void **state)
{
    instanced_case c;
    instanced_case_open(&c, three_instances);
    scene *s = c.s;
    reduce_options o;
    small_options(&o);
    o.target = 1;
    o.method = REDUCE_QUADRIC;
    reduction r;
    reduction_run(&r, s, &o);
    restore_all(s);
    restore_all(r.out);
    const char *copies[] = {"seen/knot", "turned/knot", "mirrored/knot"};
    for (int k = 0; k < 3; k++) {
        const scene_mesh *in = test_find_mesh(s, copies[k]), *out = test_find_mesh(r.out, copies[k]);
        assert_int_equal(in->vertex_count, out->vertex_count);
        assert_int_equal(in->triangle_count, out->triangle_count);
        mesh_measure a = measure(in), b = measure(out);
        print_message("  %s: volume %.6f -> %.6f, area %.6f -> %.6f\n", copies[k], a.volume,
                      b.volume, a.area, b.area);
        for (int i = 0; i < 3; i++) {
            assert_true(fabs(a.low[i] - b.low[i]) < 1e-5);
            assert_true(fabs(a.high[i] - b.high[i]) < 1e-5);
        }
        assert_true(fabs(a.area - b.area) < 1e-5 * a.area);
        assert_true(fabs(a.volume - b.volume) < 1e-5 * fabs(a.volume));
    }
    reduction_free(&r);
    instanced_case_close(&c);
}

/* The knot's planned target in the reduction of the scene at `path` (its mesh `name`). */
static double planned_target(const char *path, const char *name)
{
    scene *s = test_load_scene(path);
    reduce_options o;
    small_options(&o);
    reduction r;
    reduction_run(&r, s, &o);
    double target = number(mesh_entry(r.report, name), "vertices_target");
    print_message("  %s: %s planned to %g of %g stored vertices\n", path, name, target,
                  number(r.report, "vertices_before"));
    reduction_free(&r);
    scene_free(s);
    return target;
}

static void test_instances_importance_summed(void **state)
{
    char in_dir[64], scene_path[4200];
    temp_dir(in_dir, sizeof in_dir);
    static const char seen[] =
        "    <shape type=\"instance\" id=\"seen\"><ref id=\"knots\"/></shape>\n"
        "    <shape type=\"sphere\" id=\"ball\">\n"
        "        <point name=\"center\" x=\"-0.5\" y=\"0.4\" z=\"-0.3\"/>\n"
        "        <float name=\"radius\" value=\"0.3\"/><ref id=\"white\"/>\n"
        "    </shape>\n";
    char both[1024], alone_path[4200];
    snprintf(both, sizeof both,
             "%s    <shape type=\"instance\" id=\"hidden\"><ref id=\"knots\"/>\n"
             "        <transform name=\"to_world\"><translate z=\"-3\"/></transform></shape>\n",
             seen);
    write_instanced_cornell(in_dir, seen, alone_path, sizeof alone_path);
    double alone = planned_target(alone_path, "seen/knot");
    write_instanced_cornell(in_dir, both, scene_path, sizeof scene_path);
    double with_hidden = planned_target(scene_path, "seen/knot");
    /* The sphere (994 vertices) takes a share by importance (4,903 requested, 32 in fixed
     * meshes): the knot's target is not simply what the fixed meshes leave. Halving the knot's
     * importance moves about 90 vertices to the sphere (measured). */
    assert_true(alone > 100 && alone < 4903 - 32 - 50);
    assert_true(fabs(alone - with_hidden) <= fmax(1.0, 0.005 * alone));
    remove_tree(in_dir);
}

/* The knot's copies "seen" and "turned" of three_instances, as two shapes of their own. */
static const char two_flattened[] =
    "    <shape type=\"ply\" id=\"seen_knot\">\n"
    "        <string name=\"filename\" value=\"%s\"/>\n"
    "        <transform name=\"to_world\"><rotate x=\"1\" angle=\"-70\"/>"
    "<translate x=\"0.35\" y=\"-0.5\" z=\"0.25\"/></transform>\n"
    "        <ref id=\"orange\"/>\n"
    "    </shape>\n"
    "    <shape type=\"ply\" id=\"turned_knot\">\n"
    "        <string name=\"filename\" value=\"%s\"/>\n"
    "        <transform name=\"to_world\"><rotate x=\"1\" angle=\"-70\"/>"
    "<translate x=\"0.35\" y=\"-0.5\" z=\"0.25\"/><scale value=\"0.5\"/>"
    "<rotate y=\"1\" angle=\"40\"/><translate x=\"-0.3\" y=\"0.6\" z=\"0.1\"/></transform>\n"
    "        <ref id=\"orange\"/>\n"
    "    </shape>\n";

static void test_instances_importance_as_flattened(void **state)
{
    char in_dir[64], instanced_path[4200], flat_path[4200], knot[4096], extra[9000];
    temp_dir(in_dir, sizeof in_dir);
    assert_non_null(realpath(KNOT, knot));
    write_instanced_cornell(in_dir,
                            "    <shape type=\"instance\" id=\"seen\"><ref id=\"knots\"/></shape>\n"
                            "    <shape type=\"instance\" id=\"turned\"><ref id=\"knots\"/>\n"
                            "        <transform name=\"to_world\"><scale value=\"0.5\"/>"
                            "<rotate y=\"1\" angle=\"40\"/>"
                            "<translate x=\"-0.3\" y=\"0.6\" z=\"0.1\"/></transform></shape>\n",
                            instanced_path, sizeof instanced_path);
    char flat_dir[64];
    temp_dir(flat_dir, sizeof flat_dir);
    snprintf(extra, sizeof extra, two_flattened, knot, knot);
    write_instanced_cornell(flat_dir, extra, flat_path, sizeof flat_path);
    scene *a = test_load_scene(instanced_path), *b = test_load_scene(flat_path);
    reduce_options o;
    small_options(&o);
    reduction ra, rb;
    reduction_run(&ra, a, &o);
    reduction_run(&rb, b, &o);
    /* The copies' triangles are the prototype's (core/scene.h): its sums, on the first copy,
     * are over both copies, as the two flat shapes' together. */
    const char *sums[] = {"camera_sum", "light_sum"};
    for (int q = 0; q < 2; q++) {
        double x = number(mesh_entry(ra.report, "seen/knot"), sums[q]);
        double y = number(mesh_entry(rb.report, "seen_knot"), sums[q]) +
                   number(mesh_entry(rb.report, "turned_knot"), sums[q]);
        print_message("  knot %s: instanced %.6g, flattened %.6g\n", sums[q], x, y);
        assert_true(x > 0 && fabs(x - y) <= 0.01 * fmax(x, y));
    }
    reduction_free(&ra);
    reduction_free(&rb);
    scene_free(a);
    scene_free(b);
    remove_tree(in_dir);
    remove_tree(flat_dir);
}

static void test_instances_keep_names_a_copy(void **state)
{
    instanced_case c;
    instanced_case_open(&c, three_instances);
    scene *s = c.s;
    reduce_options o;
    small_options(&o);
    o.method = REDUCE_QUADRIC;
    const char *keep[] = {"mirrored/knot"};
    o.keep = keep;
    o.keep_count = 1;
    reduction r;
    reduction_run(&r, s, &o);
    assert_false(is_decimated(mesh_entry(r.report, "seen/knot")));
    assert_int_equal(occurrences(r.dir, "scene.xml", "value=\"meshes/"), 0);
    restore_all(s);
    restore_all(r.out);
    for (size_t m = 0; m < s->mesh_count; m++)
        assert_same_mesh(&s->meshes[m], test_find_mesh(r.out, s->meshes[m].name));
    reduction_free(&r);
    instanced_case_close(&c);
}

static void test_instances_two_passes(void **state)
{
    instanced_case c;
    instanced_case_open(&c, three_instances);
    scene *s = c.s;
    reduce_options o;
    small_options(&o);
    o.initial = 0.25;
    o.passes = 2;
    reduction r;
    reduction_run(&r, s, &o);
    uint64_t knot_vertices = test_find_mesh(s, "seen/knot")->vertex_count;
    const cJSON *initial = cJSON_GetObjectItemCaseSensitive(r.report, "initial");
    assert_true(number(initial, "vertices_after") ==
                (double)(s->vertex_count - knot_vertices + knot_vertices / 4));
    const cJSON *passes = cJSON_GetObjectItemCaseSensitive(r.report, "passes");
    const cJSON *first = cJSON_GetArrayItem(passes, 0), *second = cJSON_GetArrayItem(passes, 1);
    /* The first pass's output: the stored vertices, the reduced knot once (the other meshes
     * are whole). */
    double stored = number(first, "vertices_after");
    double knot = stored - (double)(s->vertex_count - knot_vertices);
    print_message("  first pass: %g stored, knot %g; second pass simulated %g\n", stored, knot,
                  number(second, "vertices_simulated"));
    assert_true(knot > 0 && knot < test_find_mesh(s, "seen/knot")->vertex_count);
    /* the second pass holds the reduced prototype once, placed at every copy */
    assert_true(number(second, "vertices_simulated") == stored);
    assert_true(number(r.report, "vertices_rendered_after") ==
                (double)r.out->rendered_vertex_count);
    reduction_free(&r);
    instanced_case_close(&c);
}

static void test_pbrt_object_instances_kept(void **state)
{
    char in_dir[64], scene_path[4200], knot[4096];
    temp_dir(in_dir, sizeof in_dir);
    assert_non_null(realpath(KNOT, knot));
    snprintf(scene_path, sizeof scene_path, "%s/scene.pbrt", in_dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f,
            "LookAt 0 0 5  0 0 0  0 1 0\n"
            "Camera \"perspective\" \"float fov\" [ 40 ]\n"
            "WorldBegin\n"
            "ObjectBegin \"knots\"\n"
            "Shape \"plymesh\" \"string filename\" [ \"%s\" ]\n"
            "ObjectEnd\n"
            "AttributeBegin\nObjectInstance \"knots\"\nAttributeEnd\n"
            "AttributeBegin\nTranslate 1 0 0\nScale 0.5 0.5 0.5\nObjectInstance \"knots\"\n"
            "AttributeEnd\n"
            "AttributeBegin\nScale -1 1 1\nObjectInstance \"knots\"\nAttributeEnd\n",
            knot);
    assert_int_equal(fclose(f), 0);
    warn_silence(1);
    scene *s = scene_load(scene_path);
    warn_silence(0);
    if (!s)
        fail_msg("%s", error_message());
    assert_int_equal(s->mesh_count, 3);
    reduce_options o;
    small_options(&o);
    o.method = REDUCE_QUADRIC;
    char out[80];
    snprintf(out, sizeof out, "%s/out", in_dir);
    reduce_ok(s, out, &o);
    cJSON *report = read_report(out);
    assert_int_equal(occurrences(out, "scene.pbrt", "ObjectInstance"), 3);
    assert_int_equal(occurrences(out, "scene.pbrt", "meshes/"), 1);
    assert_true(number(report, "vertices_after") == number(report, "vertices_requested"));
    char written[4200];
    snprintf(written, sizeof written, "%s/scene.pbrt", out);
    warn_silence(1);
    scene *back = scene_load(written);
    warn_silence(0);
    if (!back)
        fail_msg("%s", error_message());
    assert_int_equal(back->mesh_count, 3);
    assert_true(number(report, "vertices_rendered_after") == (double)back->rendered_vertex_count);
    restore_all(s);
    restore_all(back);
    mesh_measure in0 = measure(&s->meshes[0]), out0 = measure(&back->meshes[0]);
    for (size_t m = 0; m < 3; m++) {
        assert_int_equal(back->meshes[m].vertex_count, back->meshes[0].vertex_count);
        assert_true(back->meshes[m].vertex_count < s->meshes[m].vertex_count);
        mesh_measure a = measure(&s->meshes[m]), b = measure(&back->meshes[m]);
        print_message("  copy %zu: volume %.6f of the first's %.6f in, %.6f of %.6f out\n", m,
                      a.volume, in0.volume, b.volume, out0.volume);
        assert_true(fabs(a.volume / in0.volume - b.volume / out0.volume) < 1e-4);
    }
    cJSON_Delete(report);
    scene_free(back);
    scene_free(s);
    remove_tree(in_dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_instances_kept),
        cmocka_unit_test(test_instances_rewritten_in_place),
        cmocka_unit_test(test_instances_importance_summed),
        cmocka_unit_test(test_instances_importance_as_flattened),
        cmocka_unit_test(test_instances_keep_names_a_copy),
        cmocka_unit_test(test_instances_two_passes),
        cmocka_unit_test(test_pbrt_object_instances_kept),
    };
    return DEVICE_TEST_RUN("reduce_instances", tests, NULL, NULL) != 0;
}
