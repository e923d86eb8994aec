/* test_mitsuba_write.c — writing the reduced scene's XML (host/mitsuba_write.c).
 *
 * Each test writes a small scene into a fresh input directory (an OBJ, a PLY written through
 * OpenMesh, a PNG texture, built-in shapes, <include> fragments, <default>/$name), loads it
 * with mitsuba_load(), writes the world-space geometry of some meshes as PLYs into
 * outdir/meshes, calls mitsuba_write_reduced() and loads outdir/scene.xml again. Checked: the
 * replaced meshes now come from the PLYs (type ply, same counts, positions and bbox), the other
 * meshes are unchanged, textures still load, fragment copies exist exactly when needed, the
 * input files are byte-identical to before, the raw text (<default>, $name, comments) survives,
 * and a replacement naming no <shape> is an error naming file and line. The last tests do the
 * same on real scenes from ../shared/data (via IDMR_ROOT); a missing data directory fails
 * them, it never skips. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"
#include "io/image.h"
#include "io/mesh_io.h"
#include "io/mitsuba.h"
#include "io/mitsuba_write.h"
#include "core/scene.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define SCENES IDMR_ROOT "/../shared/data/scenes"

/* ---------------------------------------------------------------------------------------- */
/* Helpers                                                                                  */

static char in_dir[64], out_dir[64];

static int make_dirs(void **state)
{
    char meshes[128];
    snprintf(in_dir, sizeof in_dir, "/tmp/idmr-test-mw-in-XXXXXX");
    snprintf(out_dir, sizeof out_dir, "/tmp/idmr-test-mw-out-XXXXXX");
    if (!mkdtemp(in_dir) || !mkdtemp(out_dir))
        return -1;
    snprintf(meshes, sizeof meshes, "%s/meshes", out_dir);
    return mkdir(meshes, 0755);
}

static int remove_dirs(void **state)
{
    char command[192];
    snprintf(command, sizeof command, "rm -rf '%s' '%s'", in_dir, out_dir);
    return system(command) == 0 ? 0 : -1;
}

/* dir/name into a static buffer (one of four, so a few can be alive at once). */
static const char *path_in(const char *dir, const char *name)
{
    static char paths[4][2 * PATH_MAX];
    static int next;
    char *path = paths[next++ % 4];
    snprintf(path, sizeof paths[0], "%s/%s", dir, name);
    return path;
}

static void write_text(const char *name, const char *text)
{
    FILE *f = fopen(path_in(in_dir, name), "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void make_subdir(const char *name)
{
    assert_int_equal(mkdir(path_in(in_dir, name), 0755), 0);
}

/* The whole file, malloc'd and NUL-terminated; NULL if it cannot be read. */
static char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long length = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *bytes = malloc((size_t)length + 1);
    assert_non_null(bytes);
    assert_int_equal(fread(bytes, 1, (size_t)length, f), (size_t)length);
    bytes[length] = '\0';
    fclose(f);
    if (size)
        *size = (size_t)length;
    return bytes;
}

static int file_exists(const char *path)
{
    return access(path, F_OK) == 0;
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

static scene *load_ok(const char *path)
{
    error_clear();
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    if (!s)
        fail_msg("loading %s failed: %s", path, error_message());
    return s;
}

static const scene_mesh *find_mesh(const scene *s, const char *name)
{
    for (size_t i = 0; i < s->mesh_count; i++)
        if (strcmp(s->meshes[i].name, name) == 0)
            return &s->meshes[i];
    fail_msg("no mesh '%s' in %s", name, s->file);
    return NULL;
}

static void mesh_bbox(const scene_mesh *m, float lo[3], float hi[3])
{
    for (int c = 0; c < 3; c++) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (uint32_t v = 0; v < m->vertex_count; v++)
        for (int c = 0; c < 3; c++) {
            lo[c] = fminf(lo[c], m->positions[3 * v + c]);
            hi[c] = fmaxf(hi[c], m->positions[3 * v + c]);
        }
}

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
    mesh_data data = {m->vertex_count, m->triangle_count, m->positions, m->indices, NULL};
    snprintf(ply, size, "meshes/%s.ply", m->name);
    if (mesh_io_write_ply(path_in(out_dir, ply), &data, NULL, NULL, NULL))
        fail_msg("writing %s: %s", ply, error_message());
    r->xml_file = m->xml_file;
    r->xml_line = m->xml_line;
    r->ply = ply;
}

static void write_ok(const char *scene_file, const mitsuba_replacement *r, size_t count)
{
    error_clear();
    if (mitsuba_write_reduced(scene_file, out_dir, r, count))
        fail_msg("mitsuba_write_reduced failed: %s", error_message());
}

/* A unit quad in the xy plane (OBJ, 4 vertices, 2 triangles). */
static const char quad_obj[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

/* A tetrahedron written through OpenMesh as in_dir/name. */
static void write_tetrahedron_ply(const char *name)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    mesh_data data = {4, 4, positions, indices, NULL};
    if (mesh_io_write_ply(path_in(in_dir, name), &data, NULL, NULL, NULL))
        fail_msg("%s", error_message());
}

static void write_png(const char *name)
{
    const unsigned char rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    if (image_write_rgb8(path_in(in_dir, name), 2, 2, rgb))
        fail_msg("%s", error_message());
}

static size_t count_substrings(const char *text, const char *needle)
{
    size_t n = 0;
    for (const char *p = strstr(text, needle); p; p = strstr(p + 1, needle))
        n++;
    return n;
}

/* The real path of in_dir/name (static buffer). */
static const char *real_in(const char *name)
{
    static char real[PATH_MAX];
    if (!realpath(path_in(in_dir, name), real))
        fail_msg("realpath %s failed", name);
    return real;
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

static void write_scene3(snapshot *inputs)
{
    make_subdir("textures");
    make_subdir("parts");
    write_text("quad.obj", quad_obj);
    write_text("parts/part.obj", quad_obj);
    write_tetrahedron_ply("tet.ply");
    write_png("textures/tex.png");
    write_text("scene.xml", scene3);
    write_text("parts/frag.xml", fragment3);
    const char *files[] = {"scene.xml",      "parts/frag.xml", "quad.obj",
                           "parts/part.obj", "tet.ply",        "textures/tex.png"};
    for (size_t i = 0; i < sizeof files / sizeof *files; i++)
        snapshot_add(inputs, path_in(in_dir, files[i]));
}

/* Replaces `names` of the scene at in_dir/scene.xml, writes, reloads, and checks every mesh:
 * replaced ones come from their PLY with the input's geometry, the others are unchanged. */
static scene *reduce_and_check(const char *scene_file, const char *const *names, size_t count,
                               scene **input_out)
{
    scene *input = load_ok(scene_file);
    mitsuba_replacement r[8];
    char ply[8][256];
    assert_true(count <= 8);
    for (size_t i = 0; i < count; i++)
        replace_mesh(find_mesh(input, names[i]), &r[i], ply[i], sizeof ply[i]);
    write_ok(scene_file, r, count);
    scene *output = load_ok(path_in(out_dir, "scene.xml"));
    assert_int_equal(output->mesh_count, input->mesh_count);
    assert_int_equal(output->vertex_count, input->vertex_count);
    assert_int_equal(output->triangle_count, input->triangle_count);
    for (int c = 0; c < 3; c++) {
        assert_float_equal(output->bbox_min[c], input->bbox_min[c], 1e-4f);
        assert_float_equal(output->bbox_max[c], input->bbox_max[c], 1e-4f);
    }
    for (size_t m = 0; m < input->mesh_count; m++) {
        const scene_mesh *a = &input->meshes[m];
        const scene_mesh *b = find_mesh(output, a->name);
        assert_same_mesh(a, b);
        assert_int_equal(a->light >= 0, b->light >= 0);
        int replaced = 0;
        for (size_t i = 0; i < count; i++)
            replaced |= strcmp(names[i], a->name) == 0;
        if (replaced) {
            assert_string_equal(b->shape_type, "ply");
            char expected[PATH_MAX], got[PATH_MAX], ply_path[PATH_MAX];
            snprintf(ply_path, sizeof ply_path, "%s/meshes/%s.ply", out_dir, a->name);
            assert_non_null(realpath(ply_path, expected));
            assert_non_null(realpath(b->file, got));
            assert_string_equal(got, expected);
        } else {
            assert_string_equal(b->shape_type, a->shape_type);
            if (a->file) {
                char ra[PATH_MAX], rb[PATH_MAX];
                assert_non_null(realpath(a->file, ra));
                assert_non_null(realpath(b->file, rb));
                assert_string_equal(ra, rb);
            }
        }
    }
    if (input_out)
        *input_out = input;
    else
        scene_free(input);
    return output;
}

static void test_v3_replace_in_scene_keep_fragment(void **state)
{
    snapshot inputs = {0};
    write_scene3(&inputs);
    const char *names[] = {"quad", "lamp", "ball"};
    scene *input;
    scene *output = reduce_and_check(path_in(in_dir, "scene.xml"), names, 3, &input);

    /* The texture still loads, from the input's file. */
    assert_int_equal(output->texture_count, 1);
    char expected[PATH_MAX], got[PATH_MAX];
    assert_non_null(realpath(input->textures[0].file, expected));
    assert_non_null(realpath(output->textures[0].file, got));
    assert_string_equal(got, expected);
    assert_true(output->materials[find_mesh(output, "quad")->material].texture >= 0);
    assert_int_equal(output->camera.width, 32);
    /* The replaced area light has the same area. */
    assert_float_equal(output->lights[find_mesh(output, "lamp")->light].area,
                       input->lights[find_mesh(input, "lamp")->light].area, 1e-5f);

    /* Nothing replaced in the fragment: no copy, included from its place. */
    assert_false(file_exists(path_in(out_dir, "includes")));
    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    assert_non_null(text);
    char include[PATH_MAX + 32];
    snprintf(include, sizeof include, "<include filename=\"%s\"/>", real_in("parts/frag.xml"));
    if (!strstr(text, include))
        fail_msg("no '%s' in:\n%s", include, text);

    /* The raw text survives: declaration, defaults, $name, comments. */
    assert_true(strncmp(text, "<?xml", 5) == 0);
    assert_non_null(strstr(text, "<default name=\"res\" value=\"32\"/>"));
    assert_non_null(strstr(text, "<default name=\"plyname\" value=\"tet.ply\"/>"));
    assert_int_equal(count_substrings(text, "value=\"$res\""), 2);
    assert_non_null(strstr(text, "<!-- the textured material -->"));
    assert_non_null(strstr(text, "\n        <ref id=\"checker\"/>\n"));
    /* Paths: absolute for what stays, the $name one resolved, the PLYs relative to outdir. */
    snprintf(include, sizeof include, "value=\"%s\"", real_in("tet.ply"));
    assert_non_null(strstr(text, include));
    snprintf(include, sizeof include, "value=\"%s\"", real_in("textures/tex.png"));
    assert_non_null(strstr(text, include));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"quad\">\n"
                                 "        <string name=\"filename\" value=\"meshes/quad.ply\"/>\n"
                                 "        <ref id=\"checker\"/>\n"
                                 "    </shape>"));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"ball\">\n"
                                 "        <string name=\"filename\" value=\"meshes/ball.ply\"/>\n"
                                 "        <bsdf type=\"dielectric\"/>\n"
                                 "    </shape>"));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"lamp\">\n"
                                 "        <string name=\"filename\" value=\"meshes/lamp.ply\"/>\n"
                                 "        <emitter type=\"area\">"));
    assert_non_null(strstr(text, "<shape type=\"cube\" id=\"box\"/>"));
    assert_null(strstr(text, "flip_normals"));
    assert_null(strstr(text, "flip_tex_coords"));
    assert_null(strstr(text, "center"));
    assert_null(strstr(text, "radius\""));
    assert_int_equal(count_substrings(text, "name=\"to_world\""), 1); /* the tet's */
    free(text);
    snapshot_check(&inputs);
    scene_free(input);
    scene_free(output);
}

static void test_v3_replace_in_fragment_copies_it(void **state)
{
    snapshot inputs = {0};
    write_scene3(&inputs);
    const char *names[] = {"part", "box"};
    scene *output = reduce_and_check(path_in(in_dir, "scene.xml"), names, 2, NULL);
    scene_free(output);

    const char *copy = path_in(out_dir, "includes/frag.xml");
    assert_true(file_exists(copy));
    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    assert_non_null(strstr(text, "<include filename=\"includes/frag.xml\"/>"));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"box\">\n"
                                 "        <string name=\"filename\" value=\"meshes/box.ply\"/>\n"
                                 "    </shape>"));
    free(text);
    /* In the copy: the replaced shape names its PLY relative to outdir, the kept disk keeps its
     * transform, and no <?xml?> declaration appears where the input had none. */
    text = read_all(copy, NULL);
    assert_true(strncmp(text, "<scene version=\"3.0.0\">\n", 24) == 0);
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"part\">\n"
                                 "        <string name=\"filename\" value=\"meshes/part.ply\"/>\n"
                                 "    </shape>"));
    assert_int_equal(count_substrings(text, "to_world"), 1);
    free(text);
    snapshot_check(&inputs);
}

/* A fragment's relative path that resolves only from the scene's directory (the cbox
 * fragments' convention) would break from outdir: the fragment is copied with it absolute. Two
 * replaced fragments with one base name get distinct copies. */
static void test_v3_fragment_copies_fallback_and_names(void **state)
{
    snapshot inputs = {0};
    make_subdir("a");
    make_subdir("b");
    make_subdir("c");
    write_text("quad.obj", quad_obj);
    write_text("scene.xml", "<scene version=\"3.0.0\">\n"
                            "    <include filename=\"a/shapes.xml\"/>\n"
                            "    <include filename=\"b/shapes.xml\"/>\n"
                            "    <include filename=\"c/kept.xml\"/>\n"
                            "</scene>\n");
    write_text("a/shapes.xml", "<scene version=\"3.0.0\">\n"
                               "    <shape type=\"rectangle\" id=\"ra\"/>\n"
                               "</scene>\n");
    write_text("b/shapes.xml", "<scene version=\"3.0.0\">\n"
                               "    <shape type=\"rectangle\" id=\"rb\">\n"
                               "        <transform name=\"to_world\"><translate x=\"3\"/></transform>\n"
                               "    </shape>\n"
                               "</scene>\n");
    write_text("c/kept.xml", "<scene version=\"3.0.0\">\n"
                             "    <shape type=\"obj\" id=\"q\">\n"
                             "        <string name=\"filename\" value=\"quad.obj\"/>\n"
                             "    </shape>\n"
                             "</scene>\n");
    const char *files[] = {"scene.xml", "a/shapes.xml", "b/shapes.xml", "c/kept.xml", "quad.obj"};
    for (size_t i = 0; i < sizeof files / sizeof *files; i++)
        snapshot_add(&inputs, path_in(in_dir, files[i]));

    const char *names[] = {"ra", "rb"};
    scene *output = reduce_and_check(path_in(in_dir, "scene.xml"), names, 2, NULL);
    scene_free(output);
    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    assert_non_null(strstr(text, "<include filename=\"includes/shapes.xml\"/>"));
    assert_non_null(strstr(text, "<include filename=\"includes/shapes-2.xml\"/>"));
    assert_non_null(strstr(text, "<include filename=\"includes/kept.xml\"/>"));
    free(text);
    text = read_all(path_in(out_dir, "includes/kept.xml"), NULL);
    assert_non_null(text);
    char value[PATH_MAX + 16];
    snprintf(value, sizeof value, "value=\"%s\"", real_in("quad.obj"));
    assert_non_null(strstr(text, value));
    free(text);
    text = read_all(path_in(out_dir, "includes/shapes-2.xml"), NULL);
    assert_non_null(strstr(text, "value=\"meshes/rb.ply\""));
    assert_null(strstr(text, "to_world"));
    free(text);
    snapshot_check(&inputs);
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

static void test_v05_replace(void **state)
{
    snapshot inputs = {0};
    make_subdir("models");
    write_text("models/quad.obj", quad_obj);
    write_text("models/other.obj", quad_obj);
    write_tetrahedron_ply("tet.ply");
    write_png("tex.png");
    write_text("scene.xml", scene05);
    write_text("more.xml", "<scene version=\"0.5.0\">\n"
                           "\t<shape type=\"cube\" id=\"crate\">\n"
                           "\t\t<transform name=\"toWorld\"><scale value=\"0.5\"/></transform>\n"
                           "\t</shape>\n"
                           "</scene>\n");
    const char *files[] = {"scene.xml", "more.xml", "models/quad.obj", "models/other.obj",
                           "tet.ply", "tex.png"};
    for (size_t i = 0; i < sizeof files / sizeof *files; i++)
        snapshot_add(&inputs, path_in(in_dir, files[i]));

    const char *names[] = {"quad", "Light", "Backdrop"};
    scene *input;
    scene *output = reduce_and_check(path_in(in_dir, "scene.xml"), names, 3, &input);
    assert_int_equal(output->texture_count, 1);
    assert_true(output->materials[find_mesh(output, "other")->material].texture >= 0);
    assert_int_equal(output->light_count, 1);
    assert_float_equal(output->lights[0].area, input->lights[0].area, 1e-5f);
    assert_true(output->has_camera);
    assert_int_equal(output->camera.width, 40);

    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    assert_true(strncmp(text, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n", 39) == 0);
    assert_non_null(strstr(text, "\t<shape type=\"ply\">\n"
                                 "\t\t<string name=\"filename\" value=\"meshes/quad.ply\"/>\n"
                                 "\t\t<ref id=\"Floor\"/>\n"
                                 "\t</shape>"));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"Light\">\n"
                                 "\t\t<string name=\"filename\" value=\"meshes/Light.ply\"/>\n"
                                 "\t\t<emitter type=\"area\">"));
    assert_non_null(strstr(text, "<shape type=\"ply\" id=\"Backdrop\">\n"
                                 "\t\t<string name=\"filename\" value=\"meshes/Backdrop.ply\"/>\n"
                                 "\t</shape>"));
    assert_null(strstr(text, "flipNormals"));
    assert_null(strstr(text, "flipTexCoords"));
    assert_null(strstr(text, "center"));
    /* The sensor's and other.obj's toWorld stay. */
    assert_int_equal(count_substrings(text, "name=\"toWorld\""), 2);
    char value[PATH_MAX + 32];
    snprintf(value, sizeof value, "value=\"%s\"", real_in("models/other.obj"));
    assert_non_null(strstr(text, value));
    snprintf(value, sizeof value, "<include filename=\"%s\"/>", real_in("more.xml"));
    assert_non_null(strstr(text, value));
    free(text);
    assert_false(file_exists(path_in(out_dir, "includes")));
    snapshot_check(&inputs);
    scene_free(input);
    scene_free(output);
}

/* ---------------------------------------------------------------------------------------- */
/* Errors                                                                                   */

static void test_error_no_shape_at_line(void **state)
{
    snapshot inputs = {0};
    write_scene3(&inputs);
    const char *scene_file = path_in(in_dir, "scene.xml");
    mitsuba_replacement r = {scene_file, 13, "meshes/x.ply"}; /* the <bsdf> line */
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, &r, 1), -1);
    char where[PATH_MAX + 16];
    snprintf(where, sizeof where, "%s:13:", scene_file);
    if (!strstr(error_message(), where) || !strstr(error_message(), "no <shape>"))
        fail_msg("unexpected message: %s", error_message());
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);

    /* A line of the fragment that holds no shape, and a file that is not part of the scene. */
    char fragment[PATH_MAX];
    snprintf(fragment, sizeof fragment, "%s/parts/frag.xml", in_dir);
    mitsuba_replacement fr = {fragment, 4, "meshes/x.ply"};
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, &fr, 1), -1);
    snprintf(where, sizeof where, "%s:4:", fragment);
    if (!strstr(error_message(), where))
        fail_msg("unexpected message: %s", error_message());
    mitsuba_replacement other = {"/nonexistent/other.xml", 2, "meshes/x.ply"};
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, &other, 1), -1);
    if (!strstr(error_message(), "/nonexistent/other.xml:2:"))
        fail_msg("unexpected message: %s", error_message());

    /* The same shape twice. */
    scene *s = load_ok(scene_file);
    const scene_mesh *quad = find_mesh(s, "quad");
    mitsuba_replacement twice[2] = {{quad->xml_file, quad->xml_line, "meshes/a.ply"},
                                    {quad->xml_file, quad->xml_line, "meshes/b.ply"}};
    error_clear();
    assert_int_equal(mitsuba_write_reduced(scene_file, out_dir, twice, 2), -1);
    assert_non_null(strstr(error_message(), "replaced twice"));
    scene_free(s);

    assert_false(file_exists(path_in(out_dir, "scene.xml")));
    snapshot_check(&inputs);
}

static void test_error_malformed_and_missing(void **state)
{
    write_text("bad.xml", "<scene version=\"3.0.0\">\n  <shape type=\"cube\">\n</scene>\n");
    error_clear();
    assert_int_equal(mitsuba_write_reduced(path_in(in_dir, "bad.xml"), out_dir, NULL, 0), -1);
    if (!strstr(error_message(), "bad.xml:") || !strstr(error_message(), "malformed XML"))
        fail_msg("unexpected message: %s", error_message());
    error_clear();
    assert_int_equal(mitsuba_write_reduced(path_in(in_dir, "absent.xml"), out_dir, NULL, 0), -1);
    assert_non_null(strstr(error_message(), "absent.xml"));
    write_text("inc.xml", "<scene version=\"3.0.0\">\n  <include filename=\"gone.xml\"/>\n</scene>\n");
    error_clear();
    assert_int_equal(mitsuba_write_reduced(path_in(in_dir, "inc.xml"), out_dir, NULL, 0), -1);
    if (!strstr(error_message(), "inc.xml:2:") || !strstr(error_message(), "gone.xml"))
        fail_msg("unexpected message: %s", error_message());
    assert_false(file_exists(path_in(out_dir, "scene.xml")));
}

/* ---------------------------------------------------------------------------------------- */
/* Real scenes                                                                              */

static void require_shared_data(void)
{
    if (access(SCENES, R_OK) != 0)
        fail_msg("%s is missing: the real-scene tests need ../shared/data (see DESIGN.md); "
                 "they fail rather than skip",
                 SCENES);
}

/* Snapshots the files `names` in `dir` (the XML files a test must leave untouched). */
static void snapshot_xml(snapshot *s, const char *dir, const char *const *names, size_t count)
{
    for (size_t i = 0; i < count; i++)
        snapshot_add(s, path_in(dir, names[i]));
}

static void test_real_cbox(void **state)
{
    require_shared_data();
    snapshot inputs = {0};
    const char *xml[] = {"cbox.xml", "meshes/cbox_luminaire.obj"};
    snapshot_xml(&inputs, SCENES "/cbox-mitsuba", xml, 2);
    const char *names[] = {"cbox_luminaire"}; /* the one with a to_world and an emitter */
    scene *output = reduce_and_check(SCENES "/cbox-mitsuba/cbox.xml", names, 1, NULL);
    assert_int_equal(output->mesh_count, 8);
    assert_int_equal(output->light_count, 1);
    assert_int_equal(output->camera.width, 256);
    scene_free(output);
    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    assert_non_null(strstr(text, "<integer name=\"width\" value=\"$res\"/>"));
    assert_non_null(strstr(text, "<default name=\"res\" value=\"256\"/>"));
    assert_non_null(strstr(text, "value=\"meshes/cbox_luminaire.ply\""));
    free(text);
    snapshot_check(&inputs);
}

/* The cbox fragments (shapes.xml names its meshes relative to the scene's directory) included
 * from a scene of our own: replacing a shape of shapes.xml copies it, the other fragments stay
 * where they are, and their <default>s still apply. */
static void test_real_cbox_fragments(void **state)
{
    require_shared_data();
    char fragments[PATH_MAX], meshes[PATH_MAX], xml[4 * PATH_MAX];
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
    write_text("scene.xml", xml);
    snapshot inputs = {0};
    const char *names[] = {"base.xml", "bsdfs-rgb.xml", "shapes.xml"};
    snapshot_xml(&inputs, fragments, names, 3);

    const char *replace[] = {"cbox_luminaire", "cbox_floor"};
    scene *output = reduce_and_check(path_in(in_dir, "scene.xml"), replace, 2, NULL);
    assert_int_equal(output->mesh_count, 8);
    assert_int_equal(output->light_count, 1);
    assert_int_equal(output->camera.width, 256);
    scene_free(output);
    char *text = read_all(path_in(out_dir, "scene.xml"), NULL);
    char include[PATH_MAX + 64];
    snprintf(include, sizeof include, "<include filename=\"%s/base.xml\"/>", fragments);
    assert_non_null(strstr(text, include));
    assert_non_null(strstr(text, "<include filename=\"includes/shapes.xml\"/>"));
    free(text);
    text = read_all(path_in(out_dir, "includes/shapes.xml"), NULL);
    assert_non_null(text);
    assert_non_null(strstr(text, "value=\"meshes/cbox_floor.ply\""));
    assert_non_null(strstr(text, "<ref id=\"area-emitter\"/>"));
    char value[PATH_MAX + 64];
    snprintf(value, sizeof value, "value=\"%s/cbox_back.obj\"", meshes);
    assert_non_null(strstr(text, value));
    free(text);
    assert_false(file_exists(path_in(out_dir, "includes/base.xml")));
    snapshot_check(&inputs);
}

static void test_real_glass_of_water(void **state)
{
    require_shared_data();
    snapshot inputs = {0};
    const char *xml[] = {"scene-without-mesh000.xml"};
    snapshot_xml(&inputs, SCENES "/glass-of-water", xml, 1);
    const char *file = SCENES "/glass-of-water/scene-without-mesh000.xml";
    scene *input = load_ok(file);
    const char *name = input->meshes[0].name;
    char chosen[256];
    snprintf(chosen, sizeof chosen, "%s", name);
    scene_free(input);
    const char *names[] = {chosen};
    scene *output = reduce_and_check(file, names, 1, NULL);
    assert_int_equal(output->mesh_count, 16);
    assert_int_equal(output->camera.width, 1280);
    scene_free(output);
    snapshot_check(&inputs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_v3_replace_in_scene_keep_fragment, make_dirs,
                                        remove_dirs),
        cmocka_unit_test_setup_teardown(test_v3_replace_in_fragment_copies_it, make_dirs,
                                        remove_dirs),
        cmocka_unit_test_setup_teardown(test_v3_fragment_copies_fallback_and_names, make_dirs,
                                        remove_dirs),
        cmocka_unit_test_setup_teardown(test_v05_replace, make_dirs, remove_dirs),
        cmocka_unit_test_setup_teardown(test_error_no_shape_at_line, make_dirs, remove_dirs),
        cmocka_unit_test_setup_teardown(test_error_malformed_and_missing, make_dirs, remove_dirs),
        cmocka_unit_test_setup_teardown(test_real_cbox, make_dirs, remove_dirs),
        cmocka_unit_test_setup_teardown(test_real_cbox_fragments, make_dirs, remove_dirs),
        cmocka_unit_test_setup_teardown(test_real_glass_of_water, make_dirs, remove_dirs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
