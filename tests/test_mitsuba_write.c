/* test_mitsuba_write.c — writing the reduced scene's XML (host/io/mitsuba/mitsuba_write*.c).
 *
 * Each scenario writes a small scene into a fresh input directory (an OBJ, a PLY written
 * through OpenMesh, a PNG texture, built-in shapes, <include> fragments, <default>/$name),
 * loads it with mitsuba_load(), writes the world-space geometry of some meshes as PLYs into
 * outdir/meshes, calls mitsuba_write_reduced() and loads outdir/scene.xml again; each test then
 * checks one aspect of the result. Checked: the replaced meshes now come from the PLYs (type
 * ply, same counts, positions and bbox), the other meshes are unchanged, textures still load,
 * fragment copies exist exactly when needed, the input files are byte-identical to before
 * (after every scenario), the raw text (<default>, $name, comments) survives, and a replacement
 * naming no <shape> is an error naming file and line. The last tests do the same on real scenes
 * from ../shared/data (via IDMR_ROOT); a missing data directory fails them, it never skips. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "io/image.h"
#include "io/mesh/mesh_io.h"
#include "io/mitsuba_paths.h"
#include "io/mitsuba/mitsuba_write.h"
#include "core/shapes.h"
#include "core/xform.h"

/* ---------------------------------------------------------------------------------------- */
/* Helpers                                                                                  */

static char in_dir[64], out_dir[64];
static int bundle; /* the next reduction copies what the scene reads into out_dir (--bundle) */

static int make_dirs(void **state)
{
    bundle = 0;
    if (temp_dir_make(in_dir, "mw-in") || temp_dir_make(out_dir, "mw-out"))
        return -1;
    return mkdir(path_in(out_dir, "meshes"), 0755);
}

static int remove_dirs(void **state)
{
    return temp_dir_remove(in_dir) || temp_dir_remove(out_dir) ? -1 : 0;
}

/* The input files and their bytes, to prove they are never written. */
typedef struct snapshot {
    size_t count;
    char paths[16][PATH_MAX];
    char *bytes[16];
    size_t sizes[16];
} snapshot;

static void snapshot_add(snapshot *s, const char *path)
{
    assert_true(s->count < 16);
    snprintf(s->paths[s->count], PATH_MAX, "%s", path);
    s->bytes[s->count] = read_all(path, &s->sizes[s->count]);
    assert_non_null(s->bytes[s->count]);
    s->count++;
}

/* Snapshots the files `names` in `dir`. */
static void snapshot_files(snapshot *s, const char *dir, const char *const *names, size_t count)
{
    for (size_t i = 0; i < count; i++)
        snapshot_add(s, path_in(dir, names[i]));
}

static void snapshot_check(snapshot *s)
{
    for (size_t i = 0; i < s->count; i++) {
        size_t size;
        char *now = read_all(s->paths[i], &size);
        if (!now || size != s->sizes[i] || memcmp(now, s->bytes[i], size) != 0)
            fail_msg("input file %s changed", s->paths[i]);
        free(now);
        free(s->bytes[i]);
    }
    s->count = 0;
}

/* outdir/name, read whole (malloc'd); fails the test when it is missing. */
static char *read_output(const char *name)
{
    char *text = read_all(path_in(out_dir, name), NULL);
    if (!text)
        fail_msg("no %s in %s", name, out_dir);
    return text;
}

static void assert_has(const char *text, const char *needle)
{
    if (!strstr(text, needle))
        fail_msg("no '%s' in:\n%s", needle, text);
}

static void assert_lacks(const char *text, const char *needle)
{
    if (strstr(text, needle))
        fail_msg("'%s' still in:\n%s", needle, text);
}

static void assert_lacks_all(const char *text, const char *const *needles, size_t count)
{
    for (size_t i = 0; i < count; i++)
        assert_lacks(text, needles[i]);
}

static size_t count_substrings(const char *text, const char *needle)
{
    size_t n = 0;
    for (const char *p = strstr(text, needle); p; p = strstr(p + 1, needle))
        n++;
    return n;
}

/* in_dir/name as the output names it: relative to out_dir, "../<in_dir's name>/name" (both
 * directories are made side by side; static buffer). */
static const char *from_out(const char *name)
{
    static char relative[PATH_MAX];
    char in_real[PATH_MAX], out_real[PATH_MAX];
    assert_non_null(realpath(in_dir, in_real));
    assert_non_null(realpath(out_dir, out_real));
    const char *in_base = strrchr(in_real, '/') + 1, *out_base = strrchr(out_real, '/') + 1;
    assert_true(in_base - in_real == out_base - out_real &&
                strncmp(in_real, out_real, (size_t)(in_base - in_real)) == 0);
    snprintf(relative, sizeof relative, "../%s/%s", in_base, name);
    return relative;
}

/* `format` with from_out(name) in place of its %s (static buffer). */
static const char *with_from_out(const char *format, const char *name)
{
    static char text[PATH_MAX + 64];
    snprintf(text, sizeof text, format, from_out(name));
    return text;
}

/* Whether two paths name the same existing file. */
static void assert_same_file(const char *a, const char *b)
{
    char real_a[PATH_MAX], real_b[PATH_MAX];
    assert_non_null(realpath(a, real_a));
    assert_non_null(realpath(b, real_b));
    assert_string_equal(real_b, real_a);
}

/* `copy` is a copy of `original` under out_dir/assets/ (--bundle). */
static void assert_bundled_copy(const char *original, const char *copy)
{
    char assets[PATH_MAX], real_copy[PATH_MAX];
    size_t size_a = 0, size_b = 0;
    assert_non_null(realpath(path_in(out_dir, "assets"), assets));
    assert_non_null(realpath(copy, real_copy));
    assert_true(strncmp(real_copy, assets, strlen(assets)) == 0);
    char *a = read_all(original, &size_a), *b = read_all(copy, &size_b);
    assert_true(a && b && size_a == size_b && memcmp(a, b, size_a) == 0);
    free(a);
    free(b);
}

/* A unit quad in the xy plane (OBJ, 4 vertices, 2 triangles). */
static const char quad_obj[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

/* Writes `data` as a PLY through OpenMesh. */
static void write_ply(const char *path, const mesh_data *data)
{
    if (mesh_io_write_ply(path, data, NULL, NULL, NULL))
        fail_msg("writing %s: %s", path, error_message());
}

/* A tetrahedron written through OpenMesh as in_dir/name. */
static void write_tetrahedron_ply(const char *name)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    mesh_data data = {4, 4, positions, indices, NULL, NULL, 0};
    write_ply(path_in(in_dir, name), &data);
}

static void write_png(const char *name)
{
    const unsigned char rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    if (image_write_rgb8(path_in(in_dir, name), 2, 2, rgb))
        fail_msg("%s", error_message());
}

/* ---------------------------------------------------------------------------------------- */
/* Reducing a scene and checking every mesh                                                 */

/* Same counts, same positions (in order) and indices, same bbox. */
static void assert_same_mesh(const scene_mesh *a, const scene_mesh *b)
{
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count)
        fail_msg("mesh %s: %u vertices / %u triangles, expected %u / %u", b->name,
                 b->vertex_count, b->triangle_count, a->vertex_count, a->triangle_count);
    for (uint32_t i = 0; i < 3 * a->vertex_count; i++)
        if (fabsf(a->positions[i] - b->positions[i]) > 1e-6f * (1.0f + fabsf(a->positions[i])))
            fail_msg("mesh %s: coordinate %u is %g, expected %g", b->name, i, b->positions[i],
                     a->positions[i]);
    assert_memory_equal(a->indices, b->indices, 3 * sizeof(uint32_t) * a->triangle_count);
    float alo[3], ahi[3], blo[3], bhi[3];
    mesh_bbox(a, alo, ahi);
    mesh_bbox(b, blo, bhi);
    for (int c = 0; c < 3; c++) {
        assert_float_equal(alo[c], blo[c], 1e-5f);
        assert_float_equal(ahi[c], bhi[c], 1e-5f);
    }
}

/* Writes mesh `m` (world space) as out_dir/meshes/<name>.ply and fills `r` for it; `ply`
 * receives the outdir-relative name (must outlive the write). */
static void replace_mesh(const scene_mesh *m, mitsuba_replacement *r, char *ply, size_t size)
{
    mesh_data data = {m->vertex_count, m->triangle_count, m->positions, m->indices, NULL, NULL, 0};
    snprintf(ply, size, "meshes/%s.ply", m->name);
    write_ply(path_in(out_dir, ply), &data);
    r->xml_file = m->xml_file;
    r->xml_line = m->xml_line;
    r->ply = ply;
    r->face_normals = m->flat_normals;
}

/* Output mesh b of input mesh a: the same geometry and light; a replaced one comes from its
 * PLY, a kept one has its type and file. */
static void check_output_mesh(const scene_mesh *a, const scene_mesh *b, int replaced)
{
    assert_same_mesh(a, b);
    assert_int_equal(a->light >= 0, b->light >= 0);
    if (replaced) {
        char ply[PATH_MAX];
        assert_string_equal(b->shape_type, "ply");
        snprintf(ply, sizeof ply, "%s/meshes/%s.ply", out_dir, a->name);
        assert_same_file(ply, b->file);
    } else {
        assert_string_equal(b->shape_type, a->shape_type);
        if (a->file && bundle)
            assert_bundled_copy(a->file, b->file);
        else if (a->file)
            assert_same_file(a->file, b->file);
    }
}

static int is_named(const char *name, const char *const *names, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (strcmp(names[i], name) == 0)
            return 1;
    return 0;
}

/* A scene reduced: what was loaded before and after, and the written outdir/scene.xml. */
typedef struct reduction {
    snapshot inputs; /* the files the writer must leave untouched */
    scene *input, *output;
    char *text;
} reduction;

/* Replaces the meshes `names` of `scene_file`, writes, reloads, and checks every mesh: the
 * scene's counts and bbox are the input's, each mesh as check_output_mesh says. */
static void reduce_and_check(reduction *r, const char *scene_file, const char *const *names,
                             size_t count)
{
    mitsuba_replacement replacements[8];
    char ply[8][256];
    assert_true(count <= 8);
    r->input = test_load_scene(scene_file);
    for (size_t i = 0; i < count; i++)
        replace_mesh(test_find_mesh(r->input, names[i]), &replacements[i], ply[i], sizeof ply[i]);
    error_clear();
    if (mitsuba_write_reduced(scene_file, out_dir, replacements, count, bundle))
        fail_msg("mitsuba_write_reduced failed: %s", error_message());
    r->output = test_load_scene(path_in(out_dir, "scene.xml"));
    r->text = read_output("scene.xml");
    assert_int_equal(r->output->mesh_count, r->input->mesh_count);
    assert_int_equal(r->output->vertex_count, r->input->vertex_count);
    assert_int_equal(r->output->triangle_count, r->input->triangle_count);
    for (int c = 0; c < 3; c++) {
        assert_float_equal(r->output->bbox_min[c], r->input->bbox_min[c], 1e-4f);
        assert_float_equal(r->output->bbox_max[c], r->input->bbox_max[c], 1e-4f);
    }
    for (size_t m = 0; m < r->input->mesh_count; m++) {
        const scene_mesh *a = &r->input->meshes[m];
        check_output_mesh(a, test_find_mesh(r->output, a->name), is_named(a->name, names, count));
    }
}

/* Snapshots the inputs `files` (in in_dir), then reduces in_dir/scene.xml replacing `names`
 * (reduce_and_check). */
static void reduce_in_dir(reduction *r, const char *const *files, size_t file_count,
                          const char *const *names, size_t name_count)
{
    memset(r, 0, sizeof *r);
    snapshot_files(&r->inputs, in_dir, files, file_count);
    reduce_and_check(r, path_in(in_dir, "scene.xml"), names, name_count);
}

/* Checks that the inputs are unchanged and frees the reduction. */
static void reduction_finish(reduction *r)
{
    snapshot_check(&r->inputs);
    scene_free(r->input);
    scene_free(r->output);
    free(r->text);
}

/* ---------------------------------------------------------------------------------------- */
/* Small scenes, Mitsuba 3 dialect                                                          */

static const char scene3[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "<scene version=\"3.0.0\">\n"
    "    <default name=\"res\" value=\"32\"/>\n"
    "    <default name=\"plyname\" value=\"tet.ply\"/>\n"
    "    <sensor type=\"perspective\">\n"
    "        <float name=\"fov\" value=\"45\"/>\n"
    "        <film type=\"hdrfilm\">\n"
    "            <integer name=\"width\" value=\"$res\"/>\n"
    "            <integer name=\"height\" value=\"$res\"/>\n"
    "        </film>\n"
    "    </sensor>\n"
    "    <!-- the textured material -->\n"
    "    <bsdf type=\"diffuse\" id=\"checker\">\n"
    "        <texture type=\"bitmap\" name=\"reflectance\">\n"
    "            <string name=\"filename\" value=\"textures/tex.png\"/>\n"
    "        </texture>\n"
    "    </bsdf>\n"
    "    <shape type=\"obj\" id=\"quad\">\n"
    "        <string name=\"filename\" value=\"quad.obj\"/>\n"
    "        <transform name=\"to_world\">\n"
    "            <translate x=\"1\" y=\"2\" z=\"3\"/>\n"
    "        </transform>\n"
    "        <boolean name=\"flip_tex_coords\" value=\"false\"/>\n"
    "        <ref id=\"checker\"/>\n"
    "    </shape>\n"
    "    <shape type=\"ply\" id=\"tet\">\n"
    "        <string name=\"filename\" value=\"$plyname\"/>\n"
    "        <transform name=\"to_world\">\n"
    "            <scale value=\"2\"/>\n"
    "        </transform>\n"
    "    </shape>\n"
    "    <shape type=\"rectangle\" id=\"lamp\">\n"
    "        <transform name=\"to_world\">\n"
    "            <rotate x=\"1\" angle=\"90\"/>\n"
    "            <translate y=\"5\"/>\n"
    "        </transform>\n"
    "        <boolean name=\"flip_normals\" value=\"true\"/>\n"
    "        <emitter type=\"area\">\n"
    "            <rgb name=\"radiance\" value=\"4, 4, 4\"/>\n"
    "        </emitter>\n"
    "    </shape>\n"
    "    <shape type=\"sphere\" id=\"ball\">\n"
    "        <point name=\"center\" x=\"0\" y=\"1\" z=\"-2\"/>\n"
    "        <float name=\"radius\" value=\"0.5\"/>\n"
    "        <bsdf type=\"dielectric\"/>\n"
    "    </shape>\n"
    "    <shape type=\"cube\" id=\"box\"/>\n"
    "    <include filename=\"parts/frag.xml\"/>\n"
    "</scene>\n";

/* A fragment in a sub-directory: its mesh path is relative to the fragment. */
static const char fragment3[] = "<scene version=\"3.0.0\">\n"
                                "    <shape type=\"obj\" id=\"part\">\n"
                                "        <string name=\"filename\" value=\"part.obj\"/>\n"
                                "        <transform name=\"to_world\">\n"
                                "            <translate z=\"-4\"/>\n"
                                "        </transform>\n"
                                "    </shape>\n"
                                "    <shape type=\"disk\" id=\"plate\">\n"
                                "        <transform name=\"to_world\">\n"
                                "            <scale value=\"3\"/>\n"
                                "        </transform>\n"
                                "    </shape>\n"
                                "</scene>\n";

/* The files of scene3, all inputs. */
static const char *const scene3_files[] = {"scene.xml",      "parts/frag.xml", "quad.obj",
                                           "parts/part.obj", "tet.ply",        "textures/tex.png"};

static void write_scene3(void)
{
    make_subdir(in_dir, "textures");
    make_subdir(in_dir, "parts");
    write_text(in_dir, "quad.obj", quad_obj);
    write_text(in_dir, "parts/part.obj", quad_obj);
    write_tetrahedron_ply("tet.ply");
    write_png("textures/tex.png");
    write_text(in_dir, "scene.xml", scene3);
    write_text(in_dir, "parts/frag.xml", fragment3);
}

/* scene3 with meshes of the scene file replaced (none of its fragment). */
static void reduce_scene3_in_scene(reduction *r)
{
    static const char *const names[] = {"quad", "lamp", "ball"};
    write_scene3();
    reduce_in_dir(r, scene3_files, ARRAY_COUNT(scene3_files), names, ARRAY_COUNT(names));
}

/* The replaced area light keeps its area. */
static void test_v3_in_scene_meshes_replaced(void **state)
{
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_float_equal(r.output->lights[test_find_mesh(r.output, "lamp")->light].area,
                       r.input->lights[test_find_mesh(r.input, "lamp")->light].area, 1e-5f);
    reduction_finish(&r);
}

/* The texture still loads, from the input's file, and the $res default still applies. */
static void test_v3_in_scene_texture_and_defaults_apply(void **state)
{
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_int_equal(r.output->texture_count, 1);
    assert_same_file(r.input->textures[0].file, r.output->textures[0].file);
    assert_true(r.output->materials[test_find_mesh(r.output, "quad")->material].texture >= 0);
    assert_int_equal(r.output->camera.width, 32);
    reduction_finish(&r);
}

/* Nothing replaced in the fragment: no copy, included from its place. */
static void test_v3_in_scene_fragment_stays(void **state)
{
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_false(file_exists(path_in(out_dir, "includes")));
    assert_has(r.text, with_from_out("<include filename=\"%s\"/>", "parts/frag.xml"));
    reduction_finish(&r);
}

/* The raw text survives: declaration, defaults, $name, comments, indentation. */
static void test_v3_in_scene_raw_text_survives(void **state)
{
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_true(strncmp(r.text, "<?xml", 5) == 0);
    assert_has(r.text, "<default name=\"res\" value=\"32\"/>");
    assert_has(r.text, "<default name=\"plyname\" value=\"tet.ply\"/>");
    assert_int_equal(count_substrings(r.text, "value=\"$res\""), 2);
    assert_has(r.text, "<!-- the textured material -->");
    assert_has(r.text, "\n        <ref id=\"checker\"/>\n");
    reduction_finish(&r);
}

/* Paths: relative to outdir for what stays, the $name one resolved, the PLYs in outdir. */
static void test_v3_in_scene_paths(void **state)
{
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_has(r.text, with_from_out("value=\"%s\"", "tet.ply"));
    assert_has(r.text, with_from_out("value=\"%s\"", "textures/tex.png"));
    assert_has(r.text, "<shape type=\"ply\" id=\"quad\">\n"
                       "        <string name=\"filename\" value=\"meshes/quad.ply\"/>\n"
                       "        <ref id=\"checker\"/>\n"
                       "    </shape>");
    assert_has(r.text, "<shape type=\"ply\" id=\"ball\">\n"
                       "        <string name=\"filename\" value=\"meshes/ball.ply\"/>\n"
                       "        <bsdf type=\"dielectric\"/>\n"
                       "    </shape>");
    assert_has(r.text, "<shape type=\"ply\" id=\"lamp\">\n"
                       "        <string name=\"filename\" value=\"meshes/lamp.ply\"/>\n"
                       "        <emitter type=\"area\">");
    assert_has(r.text, "<shape type=\"cube\" id=\"box\"/>");
    reduction_finish(&r);
}

/* What a world-space PLY no longer has is gone: flip_normals, the obj's flip_tex_coords, the
 * sphere's center and radius, every replaced shape's to_world (the tet's stays). */
static void test_v3_in_scene_properties_dropped(void **state)
{
    static const char *const dropped[] = {"flip_normals", "flip_tex_coords", "center",
                                          "radius\""};
    reduction r;
    reduce_scene3_in_scene(&r);
    assert_lacks_all(r.text, dropped, ARRAY_COUNT(dropped));
    assert_int_equal(count_substrings(r.text, "name=\"to_world\""), 1);
    reduction_finish(&r);
}

/* scene3 with a mesh of its fragment and one of the scene replaced. */
static void reduce_scene3_in_fragment(reduction *r)
{
    static const char *const names[] = {"part", "box"};
    write_scene3();
    reduce_in_dir(r, scene3_files, ARRAY_COUNT(scene3_files), names, ARRAY_COUNT(names));
}

static void test_v3_in_fragment_copies_it(void **state)
{
    reduction r;
    reduce_scene3_in_fragment(&r);
    assert_true(file_exists(path_in(out_dir, "includes/frag.xml")));
    assert_has(r.text, "<include filename=\"includes/frag.xml\"/>");
    assert_has(r.text, "<shape type=\"ply\" id=\"box\">\n"
                       "        <string name=\"filename\" value=\"meshes/box.ply\"/>\n"
                       "        <boolean name=\"face_normals\" value=\"true\"/>\n"
                       "    </shape>");
    reduction_finish(&r);
}

/* In the copy: the replaced shape names its PLY relative to outdir, the kept disk keeps its
 * transform, and no <?xml?> declaration appears where the input had none. */
static void test_v3_in_fragment_copy_contents(void **state)
{
    reduction r;
    reduce_scene3_in_fragment(&r);
    char *copy = read_output("includes/frag.xml");
    assert_true(strncmp(copy, "<scene version=\"3.0.0\">\n", 24) == 0);
    assert_has(copy, "<shape type=\"ply\" id=\"part\">\n"
                     "        <string name=\"filename\" value=\"meshes/part.ply\"/>\n"
                     "    </shape>");
    assert_int_equal(count_substrings(copy, "to_world"), 1);
    free(copy);
    reduction_finish(&r);
}

/* Three fragments: a/shapes.xml and b/shapes.xml (one base name) with a replaced rectangle
 * each, and c/kept.xml naming quad.obj relative to the scene's directory (the cbox fragments'
 * convention), which would break from outdir. */
static void reduce_three_fragments(reduction *r)
{
    static const char *const names[] = {"ra", "rb"};
    static const char *const files[] = {"scene.xml", "a/shapes.xml", "b/shapes.xml",
                                        "c/kept.xml", "quad.obj"};
    make_subdir(in_dir, "a");
    make_subdir(in_dir, "b");
    make_subdir(in_dir, "c");
    write_text(in_dir, "quad.obj", quad_obj);
    write_text(in_dir, "scene.xml",
               "<scene version=\"3.0.0\">\n"
               "    <include filename=\"a/shapes.xml\"/>\n"
               "    <include filename=\"b/shapes.xml\"/>\n"
               "    <include filename=\"c/kept.xml\"/>\n"
               "</scene>\n");
    write_text(in_dir, "a/shapes.xml",
               "<scene version=\"3.0.0\">\n"
               "    <shape type=\"rectangle\" id=\"ra\"/>\n"
               "</scene>\n");
    write_text(in_dir, "b/shapes.xml",
               "<scene version=\"3.0.0\">\n"
               "    <shape type=\"rectangle\" id=\"rb\">\n"
               "        <transform name=\"to_world\"><translate x=\"3\"/></transform>\n"
               "    </shape>\n"
               "</scene>\n");
    write_text(in_dir, "c/kept.xml",
               "<scene version=\"3.0.0\">\n"
               "    <shape type=\"obj\" id=\"q\">\n"
               "        <string name=\"filename\" value=\"quad.obj\"/>\n"
               "    </shape>\n"
               "</scene>\n");
    reduce_in_dir(r, files, ARRAY_COUNT(files), names, ARRAY_COUNT(names));
}

/* Two replaced fragments with one base name get distinct copies. */
static void test_fragment_copies_named_apart(void **state)
{
    reduction r;
    reduce_three_fragments(&r);
    assert_has(r.text, "<include filename=\"includes/shapes.xml\"/>");
    assert_has(r.text, "<include filename=\"includes/shapes-2.xml\"/>");
    char *copy = read_output("includes/shapes-2.xml");
    assert_has(copy, "value=\"meshes/rb.ply\"");
    assert_lacks(copy, "to_world");
    free(copy);
    reduction_finish(&r);
}

/* A fragment whose relative path resolves only from the scene's directory is copied with the
 * path made relative to outdir (where Mitsuba 3 and idmr's loader both find it). */
static void test_fragment_with_scene_relative_path_copied(void **state)
{
    reduction r;
    reduce_three_fragments(&r);
    assert_has(r.text, "<include filename=\"includes/kept.xml\"/>");
    char *copy = read_output("includes/kept.xml");
    assert_has(copy, with_from_out("value=\"%s\"", "quad.obj"));
    free(copy);
    reduction_finish(&r);
}

/* ---------------------------------------------------------------------------------------- */
/* Moving the output                                                                        */

/* Paths relative to a directory, computed from the components alone. */
static void test_path_relative(void **state)
{
    static const char *const cases[][3] = {
        {"/a/b/out", "/a/b/in/tex.png", "../in/tex.png"},
        {"/a/b/out", "/a/b/out/meshes/m.ply", "meshes/m.ply"},
        {"/a/b/out/", "/a//x/y.png", "../../x/y.png"},
        {"/a", "/a/b.png", "b.png"},
        {"/tmp/out", "/work/in/tex.png", NULL}, /* only the root shared: stays absolute */
        {"/a/out", "/a/in/../tex.png", NULL},   /* never resolved */
        {"/a/out", "relative.png", NULL},
    };
    for (size_t i = 0; i < ARRAY_COUNT(cases); i++) {
        char *got = mitsuba_path_relative(cases[i][0], cases[i][1]);
        if (!cases[i][2])
            assert_null(got);
        else
            assert_string_equal(got, cases[i][2]);
        free(got);
    }
}

/* Moves in_dir and out_dir (by their names) into `parent`, or back from it. */
static void move_pair(const char *parent, int back)
{
    const char *dirs[2] = {in_dir, out_dir};
    for (int i = 0; i < 2; i++) {
        const char *moved = path_in(parent, strrchr(dirs[i], '/') + 1);
        assert_int_equal(back ? rename(moved, dirs[i]) : rename(dirs[i], moved), 0);
    }
}

/* The output and its input, moved together to another directory, still load: textures,
 * fragments (one copied, relative to outdir) and kept meshes included. */
static void test_output_moves_with_its_input(void **state)
{
    static const char *const names[] = {"part", "quad"};
    char parent[64];
    reduction r;
    write_scene3();
    reduce_in_dir(&r, scene3_files, ARRAY_COUNT(scene3_files), names, ARRAY_COUNT(names));
    assert_int_equal(temp_dir_make(parent, "mw-moved"), 0);
    move_pair(parent, 0);
    char moved_scene[PATH_MAX];
    snprintf(moved_scene, sizeof moved_scene, "%s/%s/scene.xml", parent, strrchr(out_dir, '/') + 1);
    scene *moved = test_load_scene(moved_scene);
    move_pair(parent, 1);
    assert_int_equal(moved->mesh_count, r.input->mesh_count);
    assert_int_equal(moved->vertex_count, r.input->vertex_count);
    assert_int_equal(moved->texture_count, 1);
    assert_non_null(strstr(moved->textures[0].file, parent));
    scene_free(moved);
    temp_dir_remove(parent);
    reduction_finish(&r);
}

/* --bundle: what the scene reads is copied beside the output, named relative to it, and the
 * output alone, moved elsewhere with its input gone, loads as the input did. */
static void test_bundle_moves_alone(void **state)
{
    static const char *const names[] = {"quad", "lamp"};
    char parent[64], hidden[80], moved[96], moved_scene[128];
    reduction r;
    bundle = 1;
    write_scene3();
    reduce_in_dir(&r, scene3_files, ARRAY_COUNT(scene3_files), names, ARRAY_COUNT(names));
    assert_has(r.text, "value=\"assets/tex.png\"");
    assert_has(r.text, "value=\"assets/tet.ply\"");
    assert_has(r.text, "<include filename=\"includes/frag.xml\"/>");
    char *copy = read_output("includes/frag.xml");
    assert_has(copy, "value=\"assets/part.obj\"");
    free(copy);
    assert_true(file_exists(path_in(out_dir, "assets/tex.png")));
    assert_int_equal(temp_dir_make(parent, "mw-bundle"), 0);
    snprintf(hidden, sizeof hidden, "%s-hidden", in_dir);
    assert_int_equal(rename(in_dir, hidden), 0);
    snprintf(moved, sizeof moved, "%s/anywhere", parent);
    snprintf(moved_scene, sizeof moved_scene, "%s/scene.xml", moved);
    assert_int_equal(rename(out_dir, moved), 0);
    scene *alone = test_load_scene(moved_scene);
    assert_int_equal(rename(moved, out_dir), 0);
    assert_int_equal(rename(hidden, in_dir), 0);
    assert_int_equal(alone->mesh_count, r.input->mesh_count);
    assert_int_equal(alone->vertex_count, r.input->vertex_count);
    assert_int_equal(alone->texture_count, 1);
    assert_non_null(strstr(alone->textures[0].file, parent));
    scene_free(alone);
    temp_dir_remove(parent);
    reduction_finish(&r);
}

/* --bundle never copies over a file the scene reads: a texture that already sits where its
 * copy would go (out_dir/assets/tex.png) is refused, and stays as it was. */
static void test_bundle_refuses_to_overwrite_an_input(void **state)
{
    char xml[PATH_MAX + 1024], assets[PATH_MAX];
    snapshot inputs = {0};
    static const char *const texture[] = {"tex.png"};
    snprintf(assets, sizeof assets, "%s", path_in(out_dir, "assets"));
    assert_int_equal(mkdir(assets, 0755), 0);
    const unsigned char rgb[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    assert_int_equal(image_write_rgb8(path_in(assets, "tex.png"), 2, 2, rgb), 0);
    snapshot_files(&inputs, assets, texture, 1);
    write_text(in_dir, "quad.obj", quad_obj);
    snprintf(xml, sizeof xml,
             "<scene version=\"3.0.0\">\n"
             "    <shape type=\"obj\" id=\"quad\">\n"
             "        <string name=\"filename\" value=\"quad.obj\"/>\n"
             "        <bsdf type=\"diffuse\">\n"
             "            <texture type=\"bitmap\" name=\"reflectance\">\n"
             "                <string name=\"filename\" value=\"%s/tex.png\"/>\n"
             "            </texture>\n"
             "        </bsdf>\n"
             "    </shape>\n"
             "</scene>\n",
             assets);
    const char *scene_file = write_text(in_dir, "scene.xml", xml);
    scene *input = test_load_scene(scene_file);
    mitsuba_replacement replacement;
    char ply[256];
    replace_mesh(test_find_mesh(input, "quad"), &replacement, ply, sizeof ply);
    bundle = 1;
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, &replacement, 1, bundle), -1);
    if (!strstr(error_message(), "tex.png") || !strstr(error_message(), "never overwritten"))
        fail_msg("message '%s' lacks the file or the reason", error_message());
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_false(file_exists(path_in(out_dir, "scene.xml")));
    snapshot_check(&inputs);
    scene_free(input);
}

/* ---------------------------------------------------------------------------------------- */
/* Mitsuba 0.5 dialect                                                                      */

static const char scene05[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "\n"
    "<scene version=\"0.5.0\" >\n"
    "\t<sensor type=\"perspective\" >\n"
    "\t\t<float name=\"fov\" value=\"35\" />\n"
    "\t\t<transform name=\"toWorld\" >\n"
    "\t\t\t<lookat origin=\"0, 0, 10\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>\n"
    "\t\t</transform>\n"
    "\t\t<film type=\"hdrfilm\" >\n"
    "\t\t\t<integer name=\"width\" value=\"40\" />\n"
    "\t\t\t<integer name=\"height\" value=\"30\" />\n"
    "\t\t</film>\n"
    "\t</sensor>\n"
    "\t<texture type=\"bitmap\" id=\"wood\" >\n"
    "\t\t<string name=\"filename\" value=\"tex.png\" />\n"
    "\t</texture>\n"
    "\t<bsdf type=\"diffuse\" id=\"Floor\" >\n"
    "\t\t<ref name=\"reflectance\" id=\"wood\" />\n"
    "\t</bsdf>\n"
    "\t<shape type=\"obj\" >\n"
    "\t\t<string name=\"filename\" value=\"models/quad.obj\" />\n"
    "\t\t<transform name=\"toWorld\" >\n"
    "\t\t\t<matrix value=\"2 0 0 1 0 2 0 0 0 0 2 -1 0 0 0 1\"/>\n"
    "\t\t</transform>\n"
    "\t\t<boolean name=\"flipTexCoords\" value=\"false\" />\n"
    "\t\t<ref id=\"Floor\" />\n"
    "\t</shape>\n"
    "\t<shape type=\"obj\" >\n"
    "\t\t<string name=\"filename\" value=\"models/other.obj\" />\n"
    "\t\t<transform name=\"toWorld\" >\n"
    "\t\t\t<matrix value=\"1 0 0 0 0 1 0 3 0 0 1 0 0 0 0 1\"/>\n"
    "\t\t</transform>\n"
    "\t\t<ref id=\"Floor\" />\n"
    "\t</shape>\n"
    "\t<shape type=\"ply\" id=\"tet\" >\n"
    "\t\t<string name=\"filename\" value=\"tet.ply\" />\n"
    "\t</shape>\n"
    "\t<shape type=\"sphere\" id=\"Light\" >\n"
    "\t\t<point name=\"center\" x=\"0\" y=\"4\" z=\"0\" />\n"
    "\t\t<float name=\"radius\" value=\"0.25\" />\n"
    "\t\t<boolean name=\"flipNormals\" value=\"true\" />\n"
    "\t\t<emitter type=\"area\" >\n"
    "\t\t\t<rgb name=\"radiance\" value=\"10, 10, 10\"/>\n"
    "\t\t</emitter>\n"
    "\t</shape>\n"
    "\t<shape type=\"rectangle\" id=\"Backdrop\" >\n"
    "\t\t<transform name=\"toWorld\" >\n"
    "\t\t\t<matrix value=\"0 0 5 0 0 5 0 0 -5 0 0 -3 0 0 0 1\"/>\n"
    "\t\t</transform>\n"
    "\t</shape>\n"
    "\t<include filename=\"more.xml\" />\n"
    "</scene>\n";

/* scene05 (tab-indented, camelCase names) with an obj, a sphere light and a rectangle
 * replaced; more.xml is included and kept. */
static void reduce_scene05(reduction *r)
{
    static const char *const names[] = {"quad", "Light", "Backdrop"};
    static const char *const files[] = {"scene.xml",        "more.xml", "models/quad.obj",
                                        "models/other.obj", "tet.ply",  "tex.png"};
    make_subdir(in_dir, "models");
    write_text(in_dir, "models/quad.obj", quad_obj);
    write_text(in_dir, "models/other.obj", quad_obj);
    write_tetrahedron_ply("tet.ply");
    write_png("tex.png");
    write_text(in_dir, "scene.xml", scene05);
    write_text(in_dir, "more.xml",
               "<scene version=\"0.5.0\">\n"
               "\t<shape type=\"cube\" id=\"crate\">\n"
               "\t\t<transform name=\"toWorld\"><scale value=\"0.5\"/></transform>\n"
               "\t</shape>\n"
               "</scene>\n");
    reduce_in_dir(r, files, ARRAY_COUNT(files), names, ARRAY_COUNT(names));
}

static void test_v05_scene_reloads(void **state)
{
    reduction r;
    reduce_scene05(&r);
    assert_int_equal(r.output->texture_count, 1);
    assert_true(r.output->materials[test_find_mesh(r.output, "other")->material].texture >= 0);
    assert_int_equal(r.output->light_count, 1);
    assert_float_equal(r.output->lights[0].area, r.input->lights[0].area, 1e-5f);
    assert_true(r.output->has_camera);
    assert_int_equal(r.output->camera.width, 40);
    reduction_finish(&r);
}

/* The replaced shapes keep the tab indentation and the declaration stays. */
static void test_v05_replaced_shapes_text(void **state)
{
    reduction r;
    reduce_scene05(&r);
    assert_true(strncmp(r.text, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n", 39) == 0);
    assert_has(r.text, "\t<shape type=\"ply\">\n"
                       "\t\t<string name=\"filename\" value=\"meshes/quad.ply\"/>\n"
                       "\t\t<ref id=\"Floor\"/>\n"
                       "\t</shape>");
    assert_has(r.text, "<shape type=\"ply\" id=\"Light\">\n"
                       "\t\t<string name=\"filename\" value=\"meshes/Light.ply\"/>\n"
                       "\t\t<emitter type=\"area\">");
    assert_has(r.text, "<shape type=\"ply\" id=\"Backdrop\">\n"
                       "\t\t<string name=\"filename\" value=\"meshes/Backdrop.ply\"/>\n"
                       "\t\t<boolean name=\"faceNormals\" value=\"true\"/>\n"
                       "\t</shape>");
    reduction_finish(&r);
}

/* camelCase properties are dropped as their snake_case forms are; what stays is relative. */
static void test_v05_properties_and_paths(void **state)
{
    static const char *const dropped[] = {"flipNormals", "flipTexCoords", "center"};
    reduction r;
    reduce_scene05(&r);
    assert_lacks_all(r.text, dropped, ARRAY_COUNT(dropped));
    /* The sensor's and other.obj's toWorld stay. */
    assert_int_equal(count_substrings(r.text, "name=\"toWorld\""), 2);
    assert_has(r.text, with_from_out("value=\"%s\"", "models/other.obj"));
    assert_has(r.text, with_from_out("<include filename=\"%s\"/>", "more.xml"));
    assert_false(file_exists(path_in(out_dir, "includes")));
    reduction_finish(&r);
}

/* ---------------------------------------------------------------------------------------- */
/* Instances: kept, a group's shape replaced in its own space                            */

/* A shapegroup in a fragment (a tetrahedron OBJ with an inline bsdf that has an id, and a
 * rectangle) placed twice by the scene, moved and mirrored. */
static const char instanced_scene[] = "<scene version=\"3.0.0\">\n"
                                      "    <include filename=\"parts/group.xml\"/>\n"
                                      "    <shape type=\"instance\" id=\"a\">\n"
                                      "        <ref id=\"G\"/>\n"
                                      "        <transform name=\"to_world\">\n"
                                      "            <translate x=\"10\"/>\n"
                                      "        </transform>\n"
                                      "    </shape>\n"
                                      "    <shape type=\"instance\" id=\"m\">\n"
                                      "        <ref name=\"shapegroup\" id=\"G\"/>\n"
                                      "        <transform name=\"to_world\">\n"
                                      "            <scale z=\"-1\"/>\n"
                                      "        </transform>\n"
                                      "    </shape>\n"
                                      "</scene>\n";
static const char instanced_group[] =
    "<scene version=\"3.0.0\">\n"
    "    <shape type=\"shapegroup\" id=\"G\">\n"
    "        <shape type=\"obj\" id=\"tet\">\n"
    "            <string name=\"filename\" value=\"tet.obj\"/>\n"
    "            <bsdf type=\"diffuse\" id=\"red\">\n"
    "                <rgb name=\"reflectance\" value=\"0.8, 0.1, 0.1\"/>\n"
    "            </bsdf>\n"
    "        </shape>\n"
    "        <shape type=\"rectangle\">\n"
    "            <transform name=\"to_world\">\n"
    "                <translate z=\"2\"/>\n"
    "            </transform>\n"
    "        </shape>\n"
    "    </shape>\n"
    "</scene>\n";
static const char *const instanced_files[] = {"scene.xml", "parts/group.xml", "tet.obj"};

static scene *write_instanced_scene(snapshot *inputs)
{
    make_subdir(in_dir, "parts");
    write_text(in_dir, "scene.xml", instanced_scene);
    write_text(in_dir, "parts/group.xml", instanced_group);
    write_text(in_dir, "tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                  "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    snapshot_files(inputs, in_dir, instanced_files, ARRAY_COUNT(instanced_files));
    return test_load_scene(path_in(in_dir, "scene.xml"));
}

/* Each group shape replaced by its first copy moved back into the group's space (as
 * reduce_instances.c writes it), as meshes/group<m>.ply: the output places the same meshes in
 * the same order (the mirrored instance's winding included, the points within the rounding of
 * the move there and back), keeps the shapegroup (in the fragment's copy) and both instances,
 * and the inline bsdf's id once. */
static void test_instances_kept(void **state)
{
    snapshot inputs = {0};
    scene *input = write_instanced_scene(&inputs);
    assert_int_equal(input->mesh_count, 4);
    mitsuba_replacement replacements[2];
    char ply[2][64];
    size_t n = 0;
    for (size_t i = 0; i < input->mesh_count; i++) {
        const scene_mesh *mesh = &input->meshes[i];
        assert_true(mesh->instanced);
        if (mesh->instance_first != i)
            continue;
        assert_true(n < 2);
        xform to_world = xform_from_rows(mesh->instance_to_world), to_group;
        assert_int_equal(xform_invert_affine(&to_world, &to_group), 0);
        size_t points = 3 * (size_t)mesh->vertex_count, corners = 3 * (size_t)mesh->triangle_count;
        mesh_data data = {mesh->vertex_count, mesh->triangle_count,
                          malloc(points * sizeof(float)), malloc(corners * sizeof(uint32_t)),
                          NULL, NULL, 0};
        memcpy(data.positions, mesh->positions, points * sizeof(float));
        memcpy(data.indices, mesh->indices, corners * sizeof(uint32_t));
        shapes_transform_keeping_side(&data, &to_group);
        snprintf(ply[n], sizeof ply[n], "meshes/group%zu.ply", i);
        write_ply(path_in(out_dir, ply[n]), &data);
        mesh_data_free(&data);
        replacements[n] = (mitsuba_replacement){mesh->xml_file, mesh->xml_line, ply[n],
                                                mesh->flat_normals};
        n++;
    }
    assert_int_equal(n, 2);
    error_clear();
    if (mitsuba_write_reduced(path_in(in_dir, "scene.xml"), out_dir, replacements, n, 0))
        fail_msg("mitsuba_write_reduced failed: %s", error_message());
    scene *output = test_load_scene(path_in(out_dir, "scene.xml"));
    assert_int_equal(output->mesh_count, 4);
    for (size_t i = 0; i < 4; i++) {
        /* a later copy holds its geometry once restored (core/scene.h) */
        assert_int_equal(scene_mesh_restore(input, i), 0);
        assert_int_equal(scene_mesh_restore(output, i), 0);
        const scene_mesh *a = &input->meshes[i], *b = &output->meshes[i];
        assert_int_equal(a->vertex_count, b->vertex_count);
        assert_int_equal(a->triangle_count, b->triangle_count);
        assert_memory_equal(a->indices, b->indices, 3 * sizeof(uint32_t) * a->triangle_count);
        for (size_t k = 0; k < 3 * (size_t)a->vertex_count; k++)
            assert_true(fabsf(a->positions[k] - b->positions[k]) < 1e-5f);
        assert_string_equal(b->shape_type, "ply");
        assert_true(b->instanced);
    }
    assert_int_equal(output->material_count, input->material_count);
    char *text = read_output("scene.xml");
    char *fragment = read_output("includes/group.xml");
    assert_int_equal(count_substrings(text, "type=\"instance\""), 2);
    assert_int_equal(count_substrings(fragment, "type=\"shapegroup\""), 1);
    assert_int_equal(count_substrings(fragment, "meshes/group"), 2);
    assert_int_equal(count_substrings(fragment, "id=\"red\""), 1);
    free(text);
    free(fragment);
    scene_free(output);
    scene_free(input);
    snapshot_check(&inputs);
}

/* ---------------------------------------------------------------------------------------- */
/* Errors                                                                                   */

/* mitsuba_write_reduced fails with an input error whose message holds `where` and `what` (may
 * be NULL), and writes no scene. */
static void assert_write_fails(const char *scene_file, const mitsuba_replacement *r,
                               size_t count, const char *where, const char *what)
{
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, r, count, bundle), -1);
    if (!strstr(error_message(), where) || (what && !strstr(error_message(), what)))
        fail_msg("message '%s' lacks '%s' or '%s'", error_message(), where, what ? what : "");
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_false(file_exists(path_in(out_dir, "scene.xml")));
}

/* scene3 written, a replacement of `file` (in_dir/file when relative) at `line` fails with
 * "file:line:" and `what`, and the inputs are unchanged. */
static void write_failing_replacement(const char *file, int line, const char *what)
{
    snapshot inputs = {0};
    char path[PATH_MAX], where[PATH_MAX + 16];
    write_scene3();
    snapshot_files(&inputs, in_dir, scene3_files, ARRAY_COUNT(scene3_files));
    snprintf(path, sizeof path, "%s", file[0] == '/' ? file : path_in(in_dir, file));
    mitsuba_replacement r = {path, line, "meshes/x.ply", 0};
    snprintf(where, sizeof where, "%s:%d:", path, line);
    assert_write_fails(path_in(in_dir, "scene.xml"), &r, 1, where, what);
    snapshot_check(&inputs);
}

/* Line 13 of the scene is its <bsdf>. */
static void test_error_no_shape_at_line(void **state)
{
    write_failing_replacement("scene.xml", 13, "no <shape>");
}

/* A line of the fragment that holds no shape. */
static void test_error_no_shape_at_fragment_line(void **state)
{
    write_failing_replacement("parts/frag.xml", 4, "no <shape>");
}

/* A file that is not part of the scene. */
static void test_error_file_not_in_scene(void **state)
{
    write_failing_replacement("/nonexistent/other.xml", 2, "no <shape>");
}

static void test_error_shape_replaced_twice(void **state)
{
    snapshot inputs = {0};
    write_scene3();
    snapshot_files(&inputs, in_dir, scene3_files, ARRAY_COUNT(scene3_files));
    const char *scene_file = path_in(in_dir, "scene.xml");
    scene *s = test_load_scene(scene_file);
    const scene_mesh *quad = test_find_mesh(s, "quad");
    mitsuba_replacement twice[2] = {{quad->xml_file, quad->xml_line, "meshes/a.ply", 0},
                                    {quad->xml_file, quad->xml_line, "meshes/b.ply", 0}};
    assert_write_fails(scene_file, twice, 2, "scene.xml:", "replaced twice");
    scene_free(s);
    snapshot_check(&inputs);
}

static void test_error_malformed_scene(void **state)
{
    const char *bad = write_text(in_dir, "bad.xml",
                                 "<scene version=\"3.0.0\">\n  <shape type=\"cube\">\n</scene>\n");
    assert_write_fails(bad, NULL, 0, "bad.xml:", "malformed XML");
}

static void test_error_missing_scene(void **state)
{
    assert_write_fails(path_in(in_dir, "absent.xml"), NULL, 0, "absent.xml", NULL);
}

static void test_error_missing_include(void **state)
{
    const char *scene_file = write_text(in_dir, "inc.xml",
                                        "<scene version=\"3.0.0\">\n"
                                        "  <include filename=\"gone.xml\"/>\n"
                                        "</scene>\n");
    assert_write_fails(scene_file, NULL, 0, "inc.xml:2:", "gone.xml");
}

/* ---------------------------------------------------------------------------------------- */
/* Real scenes                                                                              */

static void test_real_cbox(void **state)
{
    static const char *const xml[] = {"cbox.xml", "meshes/cbox_luminaire.obj"};
    static const char *const names[] = {"cbox_luminaire"}; /* with a to_world and an emitter */
    require_shared_data();
    reduction r = {0};
    snapshot_files(&r.inputs, SCENES "/cbox-mitsuba", xml, ARRAY_COUNT(xml));
    reduce_and_check(&r, SCENES "/cbox-mitsuba/cbox.xml", names, ARRAY_COUNT(names));
    assert_int_equal(r.output->mesh_count, 8);
    assert_int_equal(r.output->light_count, 1);
    assert_int_equal(r.output->camera.width, 256);
    assert_has(r.text, "<integer name=\"width\" value=\"$res\"/>");
    assert_has(r.text, "<default name=\"res\" value=\"256\"/>");
    assert_has(r.text, "value=\"meshes/cbox_luminaire.ply\"");
    reduction_finish(&r);
}

/* The cbox fragments (shapes.xml names its meshes relative to the scene's directory) included
 * from a scene of our own: replacing a shape of shapes.xml copies it, the other fragments stay
 * where they are, and their <default>s still apply. */
static void test_real_cbox_fragments(void **state)
{
    static const char *const fragment_names[] = {"base.xml", "bsdfs-rgb.xml", "shapes.xml"};
    static const char *const replace[] = {"cbox_luminaire", "cbox_floor"};
    require_shared_data();
    char fragments[PATH_MAX], meshes[PATH_MAX], xml[4 * PATH_MAX], expected[PATH_MAX + 64];
    assert_non_null(realpath(SCENES "/cbox-mitsuba/fragments", fragments));
    assert_non_null(realpath(SCENES "/cbox-mitsuba/meshes", meshes));
    assert_int_equal(symlink(meshes, path_in(in_dir, "meshes")), 0);
    snprintf(xml, sizeof xml,
             "<scene version=\"3.0.0\">\n"
             "    <include filename=\"%s/base.xml\"/>\n"
             "    <include filename=\"%s/bsdfs-rgb.xml\"/>\n"
             "    <emitter type=\"area\" id=\"area-emitter\">\n"
             "        <rgb name=\"radiance\" value=\"18, 15, 8\"/>\n"
             "    </emitter>\n"
             "    <include filename=\"%s/shapes.xml\"/>\n"
             "</scene>\n",
             fragments, fragments, fragments);
    reduction r = {0};
    snapshot_files(&r.inputs, fragments, fragment_names, ARRAY_COUNT(fragment_names));
    reduce_and_check(&r, write_text(in_dir, "scene.xml", xml), replace, ARRAY_COUNT(replace));
    assert_int_equal(r.output->mesh_count, 8);
    assert_int_equal(r.output->light_count, 1);
    assert_int_equal(r.output->camera.width, 256);
    snprintf(expected, sizeof expected, "<include filename=\"%s/base.xml\"/>", fragments);
    assert_has(r.text, expected);
    assert_has(r.text, "<include filename=\"includes/shapes.xml\"/>");
    char *copy = read_output("includes/shapes.xml");
    assert_has(copy, "value=\"meshes/cbox_floor.ply\"");
    assert_has(copy, "<ref id=\"area-emitter\"/>");
    snprintf(expected, sizeof expected, "value=\"%s/cbox_back.obj\"", meshes);
    assert_has(copy, expected);
    free(copy);
    assert_false(file_exists(path_in(out_dir, "includes/base.xml")));
    reduction_finish(&r);
}

static void test_real_glass_of_water(void **state)
{
    static const char *const xml[] = {"scene-without-mesh000.xml"};
    const char *file = SCENES "/glass-of-water/scene-without-mesh000.xml";
    require_shared_data();
    reduction r = {0};
    snapshot_files(&r.inputs, SCENES "/glass-of-water", xml, ARRAY_COUNT(xml));
    scene *first = test_load_scene(file);
    char chosen[256];
    snprintf(chosen, sizeof chosen, "%s", first->meshes[0].name);
    scene_free(first);
    const char *names[] = {chosen};
    reduce_and_check(&r, file, names, ARRAY_COUNT(names));
    assert_int_equal(r.output->mesh_count, 16);
    assert_int_equal(r.output->camera.width, 1280);
    reduction_finish(&r);
}

int main(void)
{
#define WRITER_TEST(f) cmocka_unit_test_setup_teardown(f, make_dirs, remove_dirs)
    const struct CMUnitTest tests[] = {
        WRITER_TEST(test_v3_in_scene_meshes_replaced),
        WRITER_TEST(test_v3_in_scene_texture_and_defaults_apply),
        WRITER_TEST(test_v3_in_scene_fragment_stays),
        WRITER_TEST(test_v3_in_scene_raw_text_survives),
        WRITER_TEST(test_v3_in_scene_paths),
        WRITER_TEST(test_v3_in_scene_properties_dropped),
        WRITER_TEST(test_v3_in_fragment_copies_it),
        WRITER_TEST(test_v3_in_fragment_copy_contents),
        WRITER_TEST(test_fragment_copies_named_apart),
        WRITER_TEST(test_fragment_with_scene_relative_path_copied),
        WRITER_TEST(test_path_relative),
        WRITER_TEST(test_output_moves_with_its_input),
        WRITER_TEST(test_bundle_moves_alone),
        WRITER_TEST(test_bundle_refuses_to_overwrite_an_input),
        WRITER_TEST(test_v05_scene_reloads),
        WRITER_TEST(test_v05_replaced_shapes_text),
        WRITER_TEST(test_v05_properties_and_paths),
        WRITER_TEST(test_instances_kept),
        WRITER_TEST(test_error_no_shape_at_line),
        WRITER_TEST(test_error_no_shape_at_fragment_line),
        WRITER_TEST(test_error_file_not_in_scene),
        WRITER_TEST(test_error_shape_replaced_twice),
        WRITER_TEST(test_error_malformed_scene),
        WRITER_TEST(test_error_missing_scene),
        WRITER_TEST(test_error_missing_include),
        WRITER_TEST(test_real_cbox),
        WRITER_TEST(test_real_cbox_fragments),
        WRITER_TEST(test_real_glass_of_water),
    };
#undef WRITER_TEST
    return cmocka_run_group_tests(tests, NULL, NULL);
}
