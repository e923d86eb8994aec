/* test_reduce_scenes.c — `idmr reduce` end to end through reduce_run() (host/reduce/reduce.c) on
 * scenes the tests write: the Cornell box with more meshes to decimate, and a scene of two knots.
 * One case a test; the helpers are in reduce_common.h. The quadric method, with no importance
 * pass, except where the importance is what is tested.
 *
 *   quadric      every decimated mesh gets the same factor (up to rounding); no importance files
 *   compensation vertices a mesh cannot give up are taken from the others, meeting the target;
 *                with importance, by importance (the plan of Eq. 3 with that mesh's floor)
 *   locks        under a budget no mesh can meet, an unseen open mesh loses its boundary lock,
 *                a seen one keeps some (it keeps covering what it covered)
 *   file names   two mesh names that make the same PLY name get distinct files
 *   no area      a mesh whose points coincide, and one whose points lie on a line, are kept as
 *                they are (decimated, they became PLYs without faces no reader loads)
 *   never larger a double-sided sheet and a strip wound every other way round come out with no
 *                more vertices than they have; one that cannot be reduced is kept, and the
 *                report says why */
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

/* ---- quadric: one factor for all ---- */

/* DIR/scene.xml: the shipped Cornell box, its knot by absolute path, plus `extra` shapes. */
static void write_cornell_plus(const char *dir, const char *extra, char *scene_path, size_t size)
{
    size_t length;
    char *xml = read_file(CORNELL, &length);
    char *end = strstr(xml, "</scene>");
    assert_non_null(end);
    char knot[4096];
    assert_non_null(realpath(KNOT, knot));
    *end = 0;
    const char *relative = "value=\"meshes/knot.ply\"";
    char *first = strstr(xml, relative);
    assert_non_null(first);
    *first = 0;
    snprintf(scene_path, size, "%s/scene.xml", dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f, "%svalue=\"%s\"%s%s</scene>\n", xml, knot, first + strlen(relative), extra);
    assert_int_equal(fclose(f), 0);
    free(xml);
}

/* The Cornell box plus a second knot (moved) and a sphere (994 vertices): three meshes to
 * decimate. The file names the knot by its absolute path (it is written elsewhere). */
static void write_three_mesh_scene(const char *dir, char *scene_path, size_t size)
{
    char knot[4096], extra[8192];
    assert_non_null(realpath(KNOT, knot));
    snprintf(extra, sizeof extra,
             "    <shape type=\"ply\" id=\"knot2\">\n"
             "        <string name=\"filename\" value=\"%s\"/>\n"
             "        <transform name=\"to_world\">\n"
             "            <scale value=\"0.5\"/>\n"
             "            <translate x=\"-0.4\" y=\"0.4\" z=\"0.2\"/>\n"
             "        </transform>\n"
             "        <ref id=\"orange\"/>\n"
             "    </shape>\n"
             "    <shape type=\"sphere\" id=\"ball\">\n"
             "        <point name=\"center\" x=\"0.5\" y=\"0.5\" z=\"-0.3\"/>\n"
             "        <float name=\"radius\" value=\"0.2\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n",
             knot);
    write_cornell_plus(dir, extra, scene_path, size);
}

/* Equal factors: (V_D - fixed) / free vertices for every decimated mesh, each within a vertex
 * of it, and the output within 1 % (or one vertex) of the factor. */
static void check_uniform_factors(const cJSON *report, const scene *s, const char **decimated,
                                  size_t count)
{
    double fixed = 0, free_vertices = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        int is_free = 0;
        for (size_t k = 0; k < count; k++)
            is_free |= strcmp(s->meshes[m].name, decimated[k]) == 0;
        if (is_free)
            free_vertices += s->meshes[m].vertex_count;
        else
            fixed += s->meshes[m].vertex_count;
    }
    double uniform = (number(report, "vertices_requested") - fixed) / free_vertices;
    for (size_t k = 0; k < count; k++) {
        const cJSON *entry = mesh_entry(report, decimated[k]);
        double factor = number(entry, "factor"), before = number(entry, "vertices_before");
        double after = number(entry, "vertices_after");
        print_message("  quadric %s: factor %.5f (uniform %.5f), %g -> %g vertices\n",
                      decimated[k], factor, uniform, before, after);
        assert_true(is_decimated(entry));
        assert_true(fabs(factor * before - uniform * before) <= 1.0);
        assert_true(fabs(after - factor * before) <= fmax(1.0, 0.01 * factor * before));
    }
}

static void test_quadric(void **state)
{
    char in_dir[64], scene_path[4200];
    temp_dir(in_dir, sizeof in_dir);
    write_three_mesh_scene(in_dir, scene_path, sizeof scene_path);
    scene *s = test_load_scene(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = REDUCE_QUADRIC;
    reduction r;
    reduction_run(&r, s, &o);
    assert_false(file_exists(r.dir, "importance.png"));
    assert_false(file_exists(r.dir, "importance"));
    const char *decimated[] = {"knot", "knot2", "ball"};
    for (int k = 0; k < 3; k++) {
        char file[64];
        snprintf(file, sizeof file, "meshes/%s.ply", decimated[k]);
        assert_true(file_exists(r.dir, file));
    }
    assert_method(r.report, "quadric");
    uint64_t total = check_report_against_output(r.report, s, r.out);
    check_uniform_factors(r.report, s, decimated, 3);
    double requested = number(r.report, "vertices_requested");
    assert_true(fabs((double)total - requested) <= 0.01 * requested);
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

/* DIR/confetti.obj: 200 separate triangles (no collapse is legal), 600 vertices. */
static void write_confetti(const char *dir)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/confetti.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int t = 0; t < 200; t++) {
        float x = -0.9f + 0.09f * (float)(t % 20), y = -0.9f + 0.09f * (float)(t / 20);
        fprintf(f, "v %g %g 0.5\nv %g %g 0.5\nv %g %g 0.5\n", x, y, x + 0.05f, y, x, y + 0.05f);
    }
    for (int t = 0; t < 200; t++)
        fprintf(f, "f %d %d %d\n", 3 * t + 1, 3 * t + 2, 3 * t + 3);
    assert_int_equal(fclose(f), 0);
}

/* The Cornell box plus `extra` (written in in_dir), loaded into *s and reduced by `method` to
 * `target` into r; keep_knot keeps the knot as it is (--keep knot: its 48,000 vertices need no
 * decimating where the test is about the other meshes). */
static void reduce_cornell_plus(const char *in_dir, const char *extra, reduce_method method,
                                double target, int keep_knot, scene **s, reduction *r)
{
    char scene_path[4200];
    write_cornell_plus(in_dir, extra, scene_path, sizeof scene_path);
    *s = test_load_scene(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = method;
    o.target = target;
    const char *keep[] = {"knot"};
    if (keep_knot) {
        o.keep = keep;
        o.keep_count = 1;
    }
    reduction_run(r, *s, &o);
}

static const char CONFETTI_SHAPE[] = "    <shape type=\"obj\" id=\"confetti\">\n"
                                     "        <string name=\"filename\" value=\"confetti.obj\"/>\n"
                                     "        <ref id=\"white\"/>\n"
                                     "    </shape>\n";

/* The confetti beside the knot, reduced with uniform factors: the confetti keeps all 600
 * vertices (it is kept as it is, and the report says why), and the compensation rounds take
 * them from the knot, so the total still meets the target exactly. */
static void test_compensation(void **state)
{
    char in_dir[64];
    temp_dir(in_dir, sizeof in_dir);
    write_confetti(in_dir);
    scene *s;
    reduction r;
    reduce_cornell_plus(in_dir, CONFETTI_SHAPE, REDUCE_QUADRIC, 0.2, 0, &s, &r);
    const cJSON *confetti = mesh_entry(r.report, "confetti");
    print_message("  confetti %g -> %g vertices; total %g for %g requested, %g compensation "
                  "rounds\n",
                  number(confetti, "vertices_before"), number(confetti, "vertices_after"),
                  number(r.report, "vertices_after"), number(r.report, "vertices_requested"),
                  number(r.report, "compensation_rounds"));
    assert_true(number(confetti, "vertices_after") == 600);
    assert_true(number(r.report, "compensation_rounds") >= 1);
    assert_true(number(r.report, "vertices_after") == number(r.report, "vertices_requested"));
    /* No collapse is legal on it: its input is kept (not rewritten), and the report says why. */
    const cJSON *why = cJSON_GetObjectItemCaseSensitive(confetti, "not_reduced");
    assert_true(cJSON_IsString(why) && strstr(why->valuestring, "no collapse"));
    assert_false(is_decimated(confetti));
    assert_same_mesh(test_find_mesh(s, "confetti"), test_find_mesh(r.out, "confetti"));
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

/* The confetti and two spheres of 994 vertices (a large one near the light, a small one at the
 * back) beside the knot (kept), reduced by importance-quadric (importance budgets, Eq. 3) to
 * D = 0.97, which leaves the spheres and the confetti about 1,070 vertices: the confetti keeps
 * its 600 (its floor, in the report), and what it cannot give is taken from the spheres by
 * importance: both keep the same multiple of their importance (λ I_i within a vertex of
 * rounding), and the total meets the target exactly. */
static void test_compensation_by_importance(void **state)
{
    char in_dir[64], extra[8192];
    temp_dir(in_dir, sizeof in_dir);
    write_confetti(in_dir);
    snprintf(extra, sizeof extra,
             "%s    <shape type=\"sphere\" id=\"large\">\n"
             "        <point name=\"center\" x=\"0.3\" y=\"0.6\" z=\"0\"/>\n"
             "        <float name=\"radius\" value=\"0.2\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n"
             "    <shape type=\"sphere\" id=\"small\">\n"
             "        <point name=\"center\" x=\"-0.5\" y=\"0.5\" z=\"-0.5\"/>\n"
             "        <float name=\"radius\" value=\"0.15\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n",
             CONFETTI_SHAPE);
    scene *s;
    reduction r;
    reduce_cornell_plus(in_dir, extra, REDUCE_IMPORTANCE_QUADRIC, 0.97, 1, &s, &r);
    const cJSON *confetti = mesh_entry(r.report, "confetti");
    assert_true(number(confetti, "vertices_after") == 600);
    assert_true(number(confetti, "vertices_floor") == 600);
    const char *spheres[] = {"large", "small"};
    double ratio[2];
    for (int k = 0; k < 2; k++) {
        const cJSON *entry = mesh_entry(r.report, spheres[k]);
        double target = number(entry, "vertices_target");
        ratio[k] = target / number(entry, "importance_sum");
        print_message("  %s: importance %g, target %g, kept %g\n", spheres[k],
                      number(entry, "importance_sum"), target, number(entry, "vertices_after"));
    }
    for (int k = 0; k < 2; k++) {
        const cJSON *entry = mesh_entry(r.report, spheres[k]);
        double target = number(entry, "vertices_target");
        assert_true(target > 16 && target < number(entry, "vertices_before"));
        assert_true(number(entry, "vertices_after") <= target);
    }
    /* The two targets are λ I_i up to the rounding to whole vertices. */
    const cJSON *small = mesh_entry(r.report, "small");
    assert_true(fabs(ratio[0] - ratio[1]) * number(small, "importance_sum") <= 1.0);
    assert_true(number(r.report, "compensation_rounds") >= 1);
    assert_true(number(r.report, "vertices_after") == number(r.report, "vertices_requested"));
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

/* DIR/name: a flat plate of 30 × 30 cells with 3 × 3 square holes (4 × 4 cells each), `size`
 * wide, centred at (x, y, z) in a plane of constant z, its front towards +z. Under any boundary
 * lock every hole keeps its four corners (40 vertices with the plate's), without one it keeps at
 * least three. */
static void write_plate_obj(const char *dir, const char *name, double size, double x, double y,
                            double z)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    const int cells = 30;
    for (int j = 0; j <= cells; j++)
        for (int i = 0; i <= cells; i++)
            fprintf(f, "v %.9g %.9g %.9g\n", x + size * ((double)i / cells - 0.5),
                    y + size * ((double)j / cells - 0.5), z);
    for (int j = 0; j < cells; j++)
        for (int i = 0; i < cells; i++) {
            if (i % 10 >= 3 && i % 10 < 7 && j % 10 >= 3 && j % 10 < 7)
                continue;
            int a = j * (cells + 1) + i + 1, b = a + 1, c = a + cells + 1, d = c + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c);
        }
    assert_int_equal(fclose(f), 0);
}

/* A budget no mesh can meet (the confetti alone keeps more than requested), by the combined
 * method: every stuck mesh has its locks relaxed, but only the plate nobody sees (behind the back
 * wall) loses its boundary lock entirely; the plate the camera sees keeps one (at most 25 %), so
 * it keeps covering what it covered. The report says by how much the request is missed. */
static void test_locks_yield_where_unseen(void **state)
{
    char in_dir[64];
    temp_dir(in_dir, sizeof in_dir);
    write_confetti(in_dir);
    write_plate_obj(in_dir, "seen.obj", 1.2, 0.0, 0.2, -0.8);
    write_plate_obj(in_dir, "unseen.obj", 1.2, 0.0, 0.0, -3.0);
    char extra[8192];
    snprintf(extra, sizeof extra,
             "%s    <shape type=\"obj\" id=\"seen\">\n"
             "        <string name=\"filename\" value=\"seen.obj\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n"
             "    <shape type=\"obj\" id=\"unseen\">\n"
             "        <string name=\"filename\" value=\"unseen.obj\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n",
             CONFETTI_SHAPE);
    scene *s;
    reduction r;
    warn_silence(1);
    reduce_cornell_plus(in_dir, extra, REDUCE_COMBINED, 0.005, 1, &s, &r);
    warn_silence(0);
    const cJSON *seen = mesh_entry(r.report, "seen"), *unseen = mesh_entry(r.report, "unseen");
    const cJSON *seen_lock = cJSON_GetObjectItemCaseSensitive(seen, "boundary_tolerance");
    const cJSON *unseen_lock = cJSON_GetObjectItemCaseSensitive(unseen, "boundary_tolerance");
    print_message("  seen plate: importance %g, %g -> %g vertices, lock %s; unseen: importance "
                  "%g, %g -> %g, lock %s; total %g for %g requested\n",
                  number(seen, "importance_sum"), number(seen, "vertices_before"),
                  number(seen, "vertices_after"), cJSON_IsNumber(seen_lock) ? "kept" : "off",
                  number(unseen, "importance_sum"), number(unseen, "vertices_before"),
                  number(unseen, "vertices_after"), cJSON_IsNumber(unseen_lock) ? "kept" : "off",
                  number(r.report, "vertices_after"), number(r.report, "vertices_requested"));
    assert_true(number(seen, "importance_sum") > 0);
    assert_true(number(unseen, "importance_sum") == 0);
    assert_true(cJSON_IsNumber(seen_lock) && seen_lock->valuedouble <= 0.25);
    assert_true(cJSON_IsNull(unseen_lock));
    assert_true(number(unseen, "vertices_after") < number(seen, "vertices_after"));
    assert_true(number(r.report, "vertices_after") > number(r.report, "vertices_requested"));
    assert_true(number(mesh_entry(r.report, "confetti"), "vertices_floor") == 600);
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

/* DIR/name: `triangles` triangles whose corners all lie on the line through (0.1, 0.2, 0.3)
 * along (step, 2 step, 0): step 0 makes every point coincide. */
static void write_degenerate_obj(const char *dir, const char *name, int triangles, float step)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int v = 0; v < 3 * triangles; v++)
        fprintf(f, "v %g %g 0.3\n", 0.1f + step * (float)v, 0.2f + 2 * step * (float)v);
    for (int t = 0; t < triangles; t++)
        fprintf(f, "f %d %d %d\n", 3 * t + 1, 3 * t + 2, 3 * t + 3);
    assert_int_equal(fclose(f), 0);
}

/* Meshes without area beside the knot: pinned, written as they were, and the reduced scene
 * loads (reduction_run loads it). */
static void test_meshes_without_area_are_kept(void **state)
{
    char in_dir[64];
    temp_dir(in_dir, sizeof in_dir);
    write_degenerate_obj(in_dir, "dot.obj", 30, 0.0f);
    write_degenerate_obj(in_dir, "line.obj", 30, 0.01f);
    scene *s;
    reduction r;
    reduce_cornell_plus(in_dir,
                        "    <shape type=\"obj\" id=\"dot\">\n"
                        "        <string name=\"filename\" value=\"dot.obj\"/>\n"
                        "    </shape>\n"
                        "    <shape type=\"obj\" id=\"line\">\n"
                        "        <string name=\"filename\" value=\"line.obj\"/>\n"
                        "    </shape>\n",
                        REDUCE_QUADRIC, 0.1, 0, &s, &r);
    const char *names[] = {"dot", "line"};
    for (int i = 0; i < 2; i++) {
        const cJSON *entry = mesh_entry(r.report, names[i]);
        assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(entry, "pinned")));
        assert_true(number(entry, "vertices_after") == number(entry, "vertices_before"));
        assert_int_equal(test_find_mesh(r.out, names[i])->triangle_count, 30);
    }
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

/* ---- never larger ---- */

/* DIR/sheet.obj: a double-sided sheet, a wavy 13 x 13 grid at the back of the box with every
 * triangle again, reversed (169 vertices, 576 triangles); DIR/strip.obj: a zigzag strip of 129
 * vertices written as the strip's vertex triples without turning every other one (127
 * triangles, each wound against its neighbours). */
static void write_sheet_and_strip(const char *dir)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/sheet.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    const int n = 12;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            fprintf(f, "v %g %g %g\n", 1.2 * i / n - 0.6, 1.2 * j / n - 0.4,
                    -0.5 + 0.02 * ((i * 7 + j * 3) % 5));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\nf %d %d %d\nf %d %d %d\n", a, b, d, a, d, c, a,
                    d, b, a, c, d);
        }
    assert_int_equal(fclose(f), 0);
    snprintf(path, sizeof path, "%s/strip.obj", dir);
    f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; i < 129; i++)
        fprintf(f, "v %g %g %g\n", 1.6 * (i / 2) / 64.0 - 0.8, i % 2 ? -0.5 : -0.7,
                0.1 * sin(i));
    for (int i = 1; i <= 127; i++)
        fprintf(f, "f %d %d %d\n", i, i + 1, i + 2);
    assert_int_equal(fclose(f), 0);
}

static const char SHEET_AND_STRIP[] = "    <shape type=\"obj\" id=\"sheet\">\n"
                                      "        <string name=\"filename\" value=\"sheet.obj\"/>\n"
                                      "        <ref id=\"white\"/>\n"
                                      "    </shape>\n"
                                      "    <shape type=\"obj\" id=\"strip\">\n"
                                      "        <string name=\"filename\" value=\"strip.obj\"/>\n"
                                      "        <ref id=\"white\"/>\n"
                                      "    </shape>\n";

/* The counts in the header of the PLY the report names for mesh `name` of reduction r. */
static void ply_counts(const reduction *r, const char *name, unsigned *vertices, unsigned *faces)
{
    const cJSON *file = cJSON_GetObjectItemCaseSensitive(mesh_entry(r->report, name), "file");
    assert_true(cJSON_IsString(file));
    char path[4200];
    size_t size;
    snprintf(path, sizeof path, "%s/%s", r->dir, file->valuestring);
    char *text = read_file(path, &size);
    const char *v = strstr(text, "element vertex "), *f = strstr(text, "element face ");
    assert_true(v && f && sscanf(v, "element vertex %u", vertices) == 1 &&
                sscanf(f, "element face %u", faces) == 1);
    free(text);
}

/* The sheet and the strip beside the knot (kept), reduced by quadric to 0.3 of what may go:
 * neither comes out with more vertices than it has (before: made of the copies the OpenMesh
 * rebuild gave the faces it could not attach, both grew). The smooth normals computed on load
 * cancel between the sheet's two layers and between the strip's opposed triangles, so they
 * point behind most triangles and hold most collapses; where a mesh is kept as it is, the
 * report says why. Without normals carried (--recompute-normals) both are reduced to their
 * targets, the sheet one layer with every triangle's twin, in the written files too. */
static void test_never_larger(void **state)
{
    char in_dir[64], scene_path[4200];
    temp_dir(in_dir, sizeof in_dir);
    write_sheet_and_strip(in_dir);
    write_cornell_plus(in_dir, SHEET_AND_STRIP, scene_path, sizeof scene_path);
    scene *s = test_load_scene(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = REDUCE_QUADRIC;
    o.target = 0.3;
    const char *keep[] = {"knot"};
    o.keep = keep;
    o.keep_count = 1;
    for (int recompute = 0; recompute < 2; recompute++) {
        o.recompute_normals = recompute;
        reduction r;
        warn_silence(1);
        reduction_run(&r, s, &o);
        warn_silence(0);
        const char *names[] = {"sheet", "strip"};
        for (int i = 0; i < 2; i++) {
            const cJSON *entry = mesh_entry(r.report, names[i]);
            const cJSON *why = cJSON_GetObjectItemCaseSensitive(entry, "not_reduced");
            print_message("  %s%s: %g -> %g vertices (target %g)%s%s\n", names[i],
                          recompute ? " (normals recomputed)" : "",
                          number(entry, "vertices_before"), number(entry, "vertices_after"),
                          number(entry, "vertices_target"), why ? ": " : "",
                          why ? why->valuestring : "");
            assert_true(number(entry, "vertices_after") <= number(entry, "vertices_before"));
            if (recompute) {
                assert_true(number(entry, "vertices_after") <= number(entry, "vertices_target"));
                assert_null(why);
            }
        }
        const cJSON *sheet = mesh_entry(r.report, "sheet");
        if (!recompute) {
            for (int i = 0; i < 2; i++) {
                const cJSON *entry = mesh_entry(r.report, names[i]);
                const cJSON *why = cJSON_GetObjectItemCaseSensitive(entry, "not_reduced");
                assert_true(!why || (cJSON_IsString(why) && strstr(why->valuestring, "normal")));
                if (why)
                    assert_same_mesh(test_find_mesh(s, names[i]), test_find_mesh(r.out, names[i]));
                else
                    assert_true(test_find_mesh(r.out, names[i])->vertex_count ==
                                number(entry, "vertices_after"));
            }
        } else {
            unsigned vertices, faces;
            ply_counts(&r, "sheet", &vertices, &faces);
            assert_true(vertices == number(sheet, "vertices_after"));
            assert_true(faces == number(sheet, "triangles_after") && faces % 2 == 0);
            ply_counts(&r, "strip", &vertices, &faces);
            assert_true(vertices == number(mesh_entry(r.report, "strip"), "vertices_after"));
            /* Read back, the files hold what the report says (a half-edge reader would split
             * the sheet's twins onto copies). */
            assert_true(test_find_mesh(r.out, "sheet")->vertex_count ==
                        number(sheet, "vertices_after"));
        }
        reduction_free(&r);
    }
    scene_free(s);
    remove_tree(in_dir);
}

/* Two meshes whose names make the same file name ("knot x" and "knot_x") get two files. */
static void test_file_name_collision(void **state)
{
    char in_dir[64], scene_path[4200], knot[4096];
    temp_dir(in_dir, sizeof in_dir);
    assert_non_null(realpath(KNOT, knot));
    snprintf(scene_path, sizeof scene_path, "%s/scene.xml", in_dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f,
            "<scene version=\"3.0.0\">\n"
            "  <sensor type=\"perspective\"><transform name=\"to_world\">"
            "<lookat origin=\"0, 0, 4\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor>\n"
            "  <shape type=\"ply\" id=\"knot x\">"
            "<string name=\"filename\" value=\"%s\"/></shape>\n"
            "  <shape type=\"ply\" id=\"knot_x\"><string name=\"filename\" value=\"%s\"/>\n"
            "    <transform name=\"to_world\"><translate x=\"2\"/></transform></shape>\n"
            "</scene>\n",
            knot, knot);
    assert_int_equal(fclose(f), 0);
    scene *s = test_load_scene(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = REDUCE_QUADRIC; /* no light needed */
    reduction r;
    reduction_run(&r, s, &o);
    assert_true(file_exists(r.dir, "meshes/knot_x.ply"));
    assert_true(file_exists(r.dir, "meshes/knot_x.2.ply"));
    assert_int_equal(r.out->mesh_count, 2);
    /* Each kept its own geometry: the second is the one moved by x = 2. */
    assert_true(r.out->meshes[1].positions[0] > r.out->meshes[0].positions[0] + 1.0f);
    reduction_free(&r);
    scene_free(s);
    remove_tree(in_dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quadric),
        cmocka_unit_test(test_compensation),
        cmocka_unit_test(test_compensation_by_importance),
        cmocka_unit_test(test_locks_yield_where_unseen),
        cmocka_unit_test(test_file_name_collision),
        cmocka_unit_test(test_meshes_without_area_are_kept),
        cmocka_unit_test(test_never_larger),
    };
    return DEVICE_TEST_RUN("reduce_scenes", tests, NULL, NULL) != 0;
}
