/* test_convert.c — `idmr convert` (io/scene_export.h): a scene written as Mitsuba 3 or pbrt-v4.
 *   - Mitsuba round trips: the shipped Cornell box, a scene written here with every material kind
 *     (a texture, twosided, plastic and roughplastic, roughconductor, conductor, dielectric,
 *     thindielectric), every light kind (point, spot, directional, an envmap with a scale and a
 *     rotation, an area light) and a camera looking along -x, and a glTF model (a texture, no
 *     camera, the white environment the glTF loader adds): read back, they give the same meshes
 *     (names, counts, positions, normals, uvs), the same material per mesh, the same lights in the
 *     same order, the same camera and the same environment map.
 *   - pbrt-v4 text: the camera-from-world matrix of a camera at (2, 0, 0) looking along -x
 *     worked out by hand, the fov of the shorter image axis, each material and light statement,
 *     and the environment as a square (equal-area) EXR.
 *   - Mitsuba 3 (scripts/mitsuba-render, .venv) renders the converted Cornell box as the
 *     original: the paired error of two seeds each is zero within four standard errors.
 *   - Errors: an unknown extension, an output that is the input, a mesh folder that holds an
 *     input, an existing output without --force; from the command line, exit code 2 and the
 *     message, and `idmr --help` lists the command.
 * Runs from the repository root (as `make test` does). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "command_common.h"
#include "core/error.h"
#include "core/scene.h"
#include "io/image.h"
#include "io/image_compare.h"
#include "io/scene_export.h"
#include "io/scene_load.h"

#define CORNELL "data/cornell/scene.xml"
#define BOX_GLTF "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf"

static char work[64];

static int make_work_dir(void **state)
{
    (void)state;
    make_temp_dir(work, "idmr-test-convert");
    return 0;
}

static int remove_work_dir(void **state)
{
    (void)state;
    remove_tree(work);
    return 0;
}

static scene *load(const char *path)
{
    error_clear();
    warn_silence(1);
    scene *s = scene_load(path);
    warn_silence(0);
    if (!s)
        fail_msg("loading %s failed: %s", path, error_message());
    return s;
}

static void export_ok(scene *s, const char *out, int force)
{
    error_clear();
    warn_silence(1);
    int status = scene_export(s, out, force);
    warn_silence(0);
    if (status)
        fail_msg("exporting %s to %s failed: %s", s->file, out, error_message());
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot read %s", path);
    char *text = slurp(f);
    fclose(f);
    return text;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

/* ---- scenes compared ---- */

static void assert_near3(const float *a, const float *b, double tolerance, const char *what)
{
    for (int k = 0; k < 3; k++)
        if (!(fabs((double)a[k] - b[k]) <= tolerance * fmax(1.0, fabs((double)b[k]))))
            fail_msg("%s: (%g, %g, %g) != (%g, %g, %g)", what, a[0], a[1], a[2], b[0], b[1], b[2]);
}

static void assert_near(double a, double b, double tolerance, const char *what)
{
    if (!(fabs(a - b) <= tolerance * fmax(1.0, fabs(b))))
        fail_msg("%s: %.9g != %.9g", what, a, b);
}

static void assert_same_material(const scene *a, const idmr_material *x, const scene *b,
                                 const idmr_material *y, const char *mesh)
{
    char what[256];
    snprintf(what, sizeof what, "material of %s", mesh);
    if (x->kind != y->kind)
        fail_msg("%s: kind %s != %s", what, scene_material_kind_name(x->kind),
                 scene_material_kind_name(y->kind));
    unsigned flags = x->kind == IDMR_MATERIAL_DIELECTRIC ? IDMR_MATERIAL_THIN : ~0u;
    if ((x->flags & flags) != (y->flags & flags))
        fail_msg("%s: flags %u != %u", what, x->flags, y->flags);
    assert_int_equal(x->texture >= 0, y->texture >= 0);
    if (x->texture >= 0) {
        char *p = realpath(a->textures[x->texture].file, NULL);
        char *q = realpath(b->textures[y->texture].file, NULL);
        assert_non_null(p);
        assert_non_null(q);
        assert_string_equal(p, q);
        free(p);
        free(q);
    }
    if (x->kind != IDMR_MATERIAL_DIELECTRIC && x->kind != IDMR_MATERIAL_MIRROR)
        assert_near3(x->reflectance, y->reflectance, 1e-6, what);
    int plastic = x->kind == IDMR_MATERIAL_GLOSSY && (x->reflectance[0] > 0 ||
                                                      x->reflectance[1] > 0 ||
                                                      x->reflectance[2] > 0);
    if (x->kind == IDMR_MATERIAL_GLOSSY || x->kind == IDMR_MATERIAL_MIRROR) {
        assert_near3(x->specular, y->specular, 1e-6, what);
        /* a plastic smoother than idmr simulates is written smooth (export_mitsuba.c) */
        if (plastic && x->roughness < IDMR_MIN_GLOSSY_ROUGHNESS)
            assert_near(y->roughness, 0.0, 1e-6, what);
        else
            assert_near(x->roughness, y->roughness, 1e-6, what);
    }
    if (plastic || x->kind == IDMR_MATERIAL_DIELECTRIC) {
        assert_near(x->int_ior, y->int_ior, 1e-6, what);
        assert_near(x->ext_ior, y->ext_ior, 1e-6, what);
    }
}

/* x and y equal within `tolerance` (0: exactly). */
static void assert_same_arrays(const float *x, const float *y, size_t n, double tolerance,
                               const char *what, const char *mesh)
{
    assert_int_equal(x != NULL, y != NULL);
    for (size_t i = 0; x && i < n; i++)
        if (!(fabs((double)x[i] - y[i]) <= tolerance))
            fail_msg("mesh %s: %s[%zu] %.9g != %.9g", mesh, what, i, x[i], y[i]);
}

static void assert_same_meshes(const scene *a, const scene *b)
{
    assert_int_equal(a->mesh_count, b->mesh_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    for (size_t m = 0; m < a->mesh_count; m++) {
        const scene_mesh *x = &a->meshes[m], *y = &b->meshes[m];
        assert_int_equal(x->triangle_count, y->triangle_count);
        assert_int_equal(x->vertex_count, y->vertex_count);
        assert_memory_equal(x->indices, y->indices, 3 * sizeof(uint32_t) * x->triangle_count);
        assert_same_arrays(x->positions, y->positions, 3 * (size_t)x->vertex_count, 0,
                           "position", x->name);
        assert_same_arrays(x->texcoords, y->texcoords, 2 * (size_t)x->vertex_count, 0, "uv",
                           x->name);
        /* normals as written, normalised again by the reader: a few ulps apart */
        if (!x->flat_normals)
            assert_same_arrays(x->normals, y->normals, 3 * (size_t)x->vertex_count, 1e-6,
                               "normal", x->name);
        assert_int_equal(x->light >= 0, y->light >= 0);
        assert_same_material(a, &a->materials[x->material], b, &b->materials[y->material],
                             x->name);
    }
}

static void assert_same_lights(const scene *a, const scene *b)
{
    assert_int_equal(a->light_count, b->light_count);
    for (size_t l = 0; l < a->light_count; l++) {
        const idmr_light *x = &a->lights[l], *y = &b->lights[l];
        char what[64];
        snprintf(what, sizeof what, "light %zu (%s)", l, scene_light_kind_name(x->kind));
        assert_int_equal(x->kind, y->kind);
        assert_near3(x->emission, y->emission, 1e-6, what);
        assert_near(x->power, y->power, 1e-5, what);
        if (x->kind == IDMR_LIGHT_POINT || x->kind == IDMR_LIGHT_SPOT)
            assert_near3(x->position, y->position, 1e-6, what);
        if (x->kind == IDMR_LIGHT_SPOT || x->kind == IDMR_LIGHT_DIRECTIONAL)
            assert_near3(x->direction, y->direction, 1e-6, what);
        if (x->kind == IDMR_LIGHT_SPOT) {
            assert_near(x->cos_cutoff, y->cos_cutoff, 1e-6, what);
            assert_near(x->cos_falloff_start, y->cos_falloff_start, 1e-6, what);
        }
        if (x->kind == IDMR_LIGHT_AREA) {
            assert_int_equal(x->triangle_count, y->triangle_count);
            assert_near(x->area, y->area, 1e-6, what);
        }
    }
    const scene_environment *e = &a->environment, *f = &b->environment;
    assert_int_equal(e->width, f->width);
    assert_int_equal(e->height, f->height);
    if (e->width) {
        assert_memory_equal(e->rgb, f->rgb, 3 * sizeof(float) * e->width * e->height);
        for (int i = 0; i < 9; i++)
            assert_near(e->to_world[i], f->to_world[i], 1e-6, "environment to_world");
    }
}

static void assert_same_camera(const scene *a, const scene *b)
{
    assert_int_equal(a->has_camera, b->has_camera);
    const idmr_camera *x = &a->camera, *y = &b->camera;
    assert_int_equal(x->width, y->width);
    assert_int_equal(x->height, y->height);
    assert_near3(x->origin, y->origin, 1e-6, "camera origin");
    assert_near3(x->forward, y->forward, 1e-6, "camera forward");
    assert_near3(x->right, y->right, 1e-6, "camera right");
    assert_near3(x->up, y->up, 1e-6, "camera up");
    assert_near(x->tan_half_x, y->tan_half_x, 1e-6, "camera tan_half_x");
    assert_near(x->tan_half_y, y->tan_half_y, 1e-6, "camera tan_half_y");
    assert_near(a->camera_info.fov_degrees, b->camera_info.fov_degrees, 1e-6, "fov");
    assert_string_equal(a->camera_info.fov_axis, b->camera_info.fov_axis);
}

/* `input` converted to work/name.xml and read back: the same scene. */
static void check_mitsuba_round_trip(const char *input, const char *name)
{
    char out[160];
    snprintf(out, sizeof out, "%s/%s.xml", work, name);
    scene *a = load(input);
    export_ok(a, out, 0);
    scene *b = load(out);
    assert_same_meshes(a, b);
    assert_same_lights(a, b);
    assert_same_camera(a, b);
    assert_int_equal(a->material_count, b->material_count);
    scene_free(a);
    scene_free(b);
}

static void test_cornell_mitsuba_round_trip(void **state)
{
    (void)state;
    check_mitsuba_round_trip(CORNELL, "cornell");
    /* the mesh folder holds one PLY per mesh, and the box's walls are flat (face_normals) */
    char path[160];
    snprintf(path, sizeof path, "%s/cornell/knot.ply", work);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    snprintf(path, sizeof path, "%s/cornell.xml", work);
    char *text = read_text(path);
    assert_non_null(strstr(text, "<scene version=\"3.0.0\">"));
    assert_non_null(strstr(text, "<boolean name=\"face_normals\" value=\"true\"/>"));
    assert_non_null(strstr(text, "<rgb name=\"radiance\" value=\"17, 12, 4\"/>"));
    free(text);
}

/* A scene with every material and light kind idmr reads (and a camera at (2, 0, 0) looking
 * along -x, 64 × 48, 60 degrees across x), written into work/kinds/. */
static void write_kinds_scene(char scene_path[160])
{
    char dir[128], path[192];
    snprintf(dir, sizeof dir, "%s/kinds", work);
    assert_int_equal(mkdir(dir, 0777), 0);
    unsigned char texture[4 * 4 * 3];
    for (int i = 0; i < 48; i++)
        texture[i] = (unsigned char)(i * 5);
    snprintf(path, sizeof path, "%s/tex.png", dir);
    assert_int_equal(image_write_rgb8(path, 4, 4, texture), 0);
    float environment[8 * 4 * 3];
    for (int i = 0; i < 96; i++)
        environment[i] = 0.1f + 0.05f * (float)(i % 7) + 0.01f * (float)(i / 3);
    snprintf(path, sizeof path, "%s/env.exr", dir);
    assert_int_equal(image_write_rgb_float(path, 8, 4, environment), 0);
    snprintf(scene_path, 160, "%s/scene.xml", dir);
    write_text(
        scene_path,
        "<scene version=\"3.0.0\">\n"
        "  <sensor type=\"perspective\">\n"
        "    <float name=\"fov\" value=\"60\"/><string name=\"fov_axis\" value=\"x\"/>\n"
        "    <transform name=\"to_world\"><lookat origin=\"2, 0, 0\" target=\"0, 0, 0\" "
        "up=\"0, 1, 0\"/></transform>\n"
        "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"64\"/>"
        "<integer name=\"height\" value=\"48\"/></film>\n"
        "  </sensor>\n"
        "  <bsdf type=\"twosided\" id=\"painted\"><bsdf type=\"diffuse\">\n"
        "    <texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" "
        "value=\"tex.png\"/></texture></bsdf></bsdf>\n"
        "  <bsdf type=\"roughplastic\" id=\"rough_plastic\"><rgb name=\"diffuse_reflectance\" "
        "value=\"0.2, 0.3, 0.4\"/><float name=\"alpha\" value=\"0.25\"/><string "
        "name=\"distribution\" value=\"ggx\"/><float name=\"int_ior\" value=\"1.6\"/></bsdf>\n"
        "  <bsdf type=\"roughplastic\" id=\"nearly_smooth\"><rgb name=\"diffuse_reflectance\" "
        "value=\"0.6, 0.6, 0.6\"/><float name=\"alpha\" value=\"0.001\"/></bsdf>\n"
        "  <bsdf type=\"plastic\" id=\"smooth_plastic\"><rgb name=\"diffuse_reflectance\" "
        "value=\"0.5, 0.1, 0.1\"/><rgb name=\"specular_reflectance\" value=\"0.9, 0.8, "
        "0.7\"/></bsdf>\n"
        "  <bsdf type=\"roughconductor\" id=\"gold\"><string name=\"material\" value=\"Au\"/>"
        "<float name=\"alpha\" value=\"0.1\"/><string name=\"distribution\" "
        "value=\"ggx\"/></bsdf>\n"
        "  <bsdf type=\"conductor\" id=\"mirror\"><rgb name=\"specular_reflectance\" "
        "value=\"0.9, 0.9, 0.8\"/></bsdf>\n"
        "  <bsdf type=\"dielectric\" id=\"glass\"><float name=\"int_ior\" value=\"1.33\"/>"
        "</bsdf>\n"
        "  <bsdf type=\"thindielectric\" id=\"pane\"/>\n"
        "  <emitter type=\"point\"><point name=\"position\" value=\"0, 1.5, 0\"/>"
        "<rgb name=\"intensity\" value=\"3, 2, 1\"/></emitter>\n"
        "  <emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0, 2, 0\" "
        "target=\"0.3, 0, 0.1\" up=\"1, 0, 0\"/></transform><float name=\"cutoff_angle\" "
        "value=\"30\"/><float name=\"beam_width\" value=\"20\"/><rgb name=\"intensity\" "
        "value=\"5, 5, 5\"/></emitter>\n"
        "  <emitter type=\"directional\"><vector name=\"direction\" value=\"0.2, -1, 0.1\"/>"
        "<rgb name=\"irradiance\" value=\"0.5, 0.6, 0.7\"/></emitter>\n"
        "  <emitter type=\"envmap\"><string name=\"filename\" value=\"env.exr\"/>"
        "<float name=\"scale\" value=\"0.5\"/><transform name=\"to_world\"><rotate y=\"1\" "
        "angle=\"30\"/></transform></emitter>\n"
        "  <shape type=\"rectangle\" id=\"floor\"><transform name=\"to_world\"><rotate x=\"1\" "
        "angle=\"-90\"/><translate y=\"-1\"/></transform><ref id=\"painted\"/></shape>\n"
        "  <shape type=\"cube\" id=\"box\"><transform name=\"to_world\"><scale value=\"0.2\"/>"
        "</transform><ref id=\"rough_plastic\"/></shape>\n"
        "  <shape type=\"sphere\" id=\"ball\"><point name=\"center\" value=\"0.5, 0, 0.5\"/>"
        "<float name=\"radius\" value=\"0.2\"/><ref id=\"gold\"/></shape>\n"
        "  <shape type=\"sphere\" id=\"bead\"><point name=\"center\" value=\"0.5, 0, -0.5\"/>"
        "<float name=\"radius\" value=\"0.1\"/><ref id=\"smooth_plastic\"/></shape>\n"
        "  <shape type=\"rectangle\" id=\"looking_glass\"><transform name=\"to_world\">"
        "<translate z=\"-1\"/></transform><ref id=\"mirror\"/></shape>\n"
        "  <shape type=\"sphere\" id=\"pebble\"><point name=\"center\" value=\"0, 0.5, 0\"/>"
        "<float name=\"radius\" value=\"0.1\"/><ref id=\"nearly_smooth\"/></shape>\n"
        "  <shape type=\"sphere\" id=\"drop\"><point name=\"center\" value=\"-0.5, 0, 0\"/>"
        "<float name=\"radius\" value=\"0.2\"/><ref id=\"glass\"/></shape>\n"
        "  <shape type=\"disk\" id=\"window\"><transform name=\"to_world\"><translate "
        "z=\"1\"/></transform><ref id=\"pane\"/></shape>\n"
        "  <shape type=\"rectangle\" id=\"lamp\"><transform name=\"to_world\"><scale "
        "value=\"0.2\"/><rotate x=\"1\" angle=\"90\"/><translate y=\"0.99\"/></transform>\n"
        "    <bsdf type=\"diffuse\"/><emitter type=\"area\"><rgb name=\"radiance\" "
        "value=\"10, 9, 8\"/></emitter></shape>\n"
        "</scene>\n");
}

static void test_kinds_mitsuba_round_trip(void **state)
{
    (void)state;
    char input[160];
    write_kinds_scene(input);
    check_mitsuba_round_trip(input, "kinds-out");
    char path[160];
    snprintf(path, sizeof path, "%s/kinds-out.xml", work);
    char *text = read_text(path);
    static const char *expected[] = {
        "<bsdf type=\"twosided\" id=\"painted\">", "<texture type=\"bitmap\" name=\"reflectance\">",
        "<bsdf type=\"roughplastic\" id=\"rough_plastic\">",
        "<bsdf type=\"plastic\" id=\"smooth_plastic\">",
        /* alpha 0.001 is written as the smooth plastic idmr simulates it as */
        "<bsdf type=\"plastic\" id=\"nearly_smooth\">",
        "<bsdf type=\"roughconductor\" id=\"gold\">",
        "<bsdf type=\"conductor\" id=\"mirror\">", "<bsdf type=\"dielectric\" id=\"glass\">",
        "<bsdf type=\"thindielectric\" id=\"pane\">", "<emitter type=\"spot\">",
        "<emitter type=\"envmap\">", "kinds-out/environment.exr", "<emitter type=\"area\">",
        /* the texture named relative to the output's directory */
        "value=\"kinds/tex.png\"",
    };
    for (size_t i = 0; i < sizeof expected / sizeof *expected; i++)
        if (!strstr(text, expected[i]))
            fail_msg("%s lacks %s", path, expected[i]);
    free(text);
}

static void test_gltf_mitsuba_round_trip(void **state)
{
    (void)state;
    check_mitsuba_round_trip(BOX_GLTF, "box");
    char path[160];
    snprintf(path, sizeof path, "%s/box.xml", work);
    char *text = read_text(path);
    assert_non_null(strstr(text, "<emitter type=\"constant\">"));
    assert_non_null(strstr(text, "CesiumLogoFlat.png"));
    free(text);
}

/* Names that a file system or Mitsuba would not take apart: "a/b" and "a_b" make the same file
 * name, "A_B" the same on a case-blind file system, "_x" an id Mitsuba keeps for itself, and a
 * material named as a mesh would share its id. One triangle each, built in code. */
static void test_names_made_apart(void **state)
{
    (void)state;
    static const char *names[] = {"wall", "a/b", "a_b", "A_B", "_x"};
    static const char *expected[] = {"wall", "a_b", "a_b.2", "A_B.3", "mesh_x"};
    scene *s = scene_create("built-in-code.xml");
    idmr_material m = {{0.5f, 0.5f, 0.5f}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1, -1, 0};
    uint32_t material = scene_add_material(s, "wall", "diffuse", &m);
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        float *p = calloc(9, sizeof *p);
        uint32_t *t = malloc(3 * sizeof *t);
        p[3] = 1, p[7] = 1, p[2] = p[5] = p[8] = (float)i;
        t[0] = 0, t[1] = 1, t[2] = 2;
        scene_mesh *mesh = scene_add_mesh(s, names[i], "ply", NULL, 0, 3, p, 1, t, NULL);
        mesh->material = material;
    }
    if (scene_finalize(s))
        fail_msg("%s", error_message());
    char out[160], path[192];
    snprintf(out, sizeof out, "%s/names.xml", work);
    export_ok(s, out, 0);
    scene_free(s);
    scene *b = load(out);
    assert_int_equal(b->mesh_count, sizeof names / sizeof *names);
    for (size_t i = 0; i < b->mesh_count; i++) {
        assert_string_equal(b->meshes[i].name, expected[i]);
        snprintf(path, sizeof path, "%s/names/%s.ply", work, expected[i]);
        struct stat st;
        if (stat(path, &st) != 0)
            fail_msg("no %s", path);
    }
    assert_int_equal(b->material_count, 1);
    assert_string_equal(b->material_info[0].name, "wall.2");
    scene_free(b);
}

/* ---- pbrt-v4 text ---- */

/* The numbers of the statement that starts with `keyword` (up to 32), after its "[". */
static int statement_numbers(const char *text, const char *keyword, double *values, int max)
{
    const char *at = strstr(text, keyword);
    if (!at)
        fail_msg("no '%s' in:\n%s", keyword, text);
    const char *p = strchr(at, '[');
    assert_non_null(p);
    int n = 0;
    for (p++; n < max;) {
        char *end;
        double v = strtod(p, &end);
        if (end == p)
            break;
        values[n++] = v;
        p = end;
    }
    return n;
}

static void test_kinds_pbrt_text(void **state)
{
    (void)state;
    char input[160], out[160], path[192];
    write_kinds_scene(input);
    snprintf(out, sizeof out, "%s/kinds-pbrt.pbrt", work);
    scene *s = load(input);
    export_ok(s, out, 0);
    scene_free(s);
    char *text = read_text(out);
    /* Camera at o = (2, 0, 0) looking along f = (-1, 0, 0), up u = (0, 1, 0): the image's right
     * is f × u = (0, 0, -1). Camera from world has rows (r, -r.o) = (0 0 -1 | 0), (u, -u.o) =
     * (0 1 0 | 0), (f, -f.o) = (-1 0 0 | 2); written column by column. */
    static const double camera_from_world[16] = {0, 0, -1, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 2, 1};
    double values[32];
    assert_int_equal(statement_numbers(text, "\nTransform", values, 32), 16);
    for (int i = 0; i < 16; i++)
        assert_near(values[i], camera_from_world[i], 1e-6, "Transform");
    /* 60 degrees across x on a 64 × 48 film: the shorter axis (y) spans
     * 2 atan(tan 30° × 48 / 64) = 46.8264 degrees. */
    assert_int_equal(statement_numbers(text, "\"float fov\"", values, 32), 1);
    assert_near(values[0], 2 * atan(tan(M_PI / 6) * 48.0 / 64.0) * 180 / M_PI, 1e-6, "fov");
    assert_int_equal(statement_numbers(text, "\"integer xresolution\"", values, 32), 1);
    assert_near(values[0], 64, 0, "xresolution");
    assert_int_equal(statement_numbers(text, "\"integer yresolution\"", values, 32), 1);
    assert_near(values[0], 48, 0, "yresolution");
    /* the spot: cutoff 30, beam 20 */
    assert_int_equal(statement_numbers(text, "\"float coneangle\"", values, 32), 1);
    assert_near(values[0], 30, 1e-5, "coneangle");
    assert_int_equal(statement_numbers(text, "\"float conedeltaangle\"", values, 32), 1);
    assert_near(values[0], 10, 1e-4, "conedeltaangle");
    /* the glass: eta 1.33 / air */
    assert_int_equal(statement_numbers(strstr(text, "MakeNamedMaterial \"glass\""), "\"float eta\"",
                                       values, 32),
                     1);
    assert_near(values[0], 1.33 / 1.000277, 1e-6, "eta");
    static const char *expected[] = {
        "WorldBegin",
        "Texture \"painted:reflectance\" \"spectrum\" \"imagemap\" \"string filename\" [ "
        "\"kinds/tex.png\" ]",
        "MakeNamedMaterial \"painted\"\n    \"string type\" [ \"diffuse\" ] \"texture "
        "reflectance\" \"painted:reflectance\"",
        "MakeNamedMaterial \"rough_plastic\"\n    \"string type\" [ \"coateddiffuse\" ] "
        "\"rgb reflectance\" [ 0.200000003 0.300000012 0.400000006 ]",
        "\"float roughness\" [ 0.25 ] \"bool remaproughness\" [ false ]",
        "MakeNamedMaterial \"gold\"\n    \"string type\" [ \"conductor\" ] \"rgb reflectance\" [ 1 "
        "0.782000005 0.344000012 ]",
        "MakeNamedMaterial \"mirror\"\n    \"string type\" [ \"conductor\" ]",
        "MakeNamedMaterial \"pane\"\n    \"string type\" [ \"thindielectric\" ]",
        "LightSource \"point\" \"rgb I\" [ 3 2 1 ] \"point3 from\" [ 0 1.5 0 ]",
        "LightSource \"distant\" \"rgb L\" [ 0.5 0.600000024 0.699999988 ]",
        "LightSource \"infinite\" \"string filename\" [ \"kinds-pbrt/environment.exr\" ]",
        "AttributeBegin # lamp\n    AreaLightSource \"diffuse\" \"rgb L\" [ 10 9 8 ]",
        "Shape \"plymesh\" \"string filename\" [ \"kinds-pbrt/ball.ply\" ]",
    };
    for (size_t i = 0; i < sizeof expected / sizeof *expected; i++)
        if (!strstr(text, expected[i]))
            fail_msg("%s lacks\n%s\nin\n%s", out, expected[i], text);
    free(text);
    /* pbrt-v4's image infinite light takes an equal-area square */
    int width, height, channels;
    snprintf(path, sizeof path, "%s/kinds-pbrt/environment.exr", work);
    assert_int_equal(image_info(path, &width, &height, &channels), 0);
    assert_int_equal(width, height);
    assert_true(width >= 64);
}

/* The equal-area square keeps the map's mean radiance: every pixel of the square covers the
 * same solid angle, so its plain mean is the map's mean over the sphere. */
static void test_pbrt_environment_mean(void **state)
{
    (void)state;
    char input[160], out[160], path[192];
    write_kinds_scene(input);
    snprintf(out, sizeof out, "%s/mean.pbrt", work);
    scene *s = load(input);
    export_ok(s, out, 0);
    double expected[3] = {0, 0, 0}, total = 0;
    const scene_environment *e = &s->environment;
    for (int y = 0; y < e->height; y++) {
        double w = scene_environment_pixel_solid_angle(e->width, e->height, y);
        for (int x = 0; x < e->width; x++, total += w)
            for (int c = 0; c < 3; c++)
                expected[c] += w * e->rgb[3 * ((size_t)y * e->width + x) + c];
    }
    int width, height;
    float *rgb;
    snprintf(path, sizeof path, "%s/mean/environment.exr", work);
    assert_int_equal(image_read_rgb(path, &width, &height, &rgb), 0);
    for (int c = 0; c < 3; c++) {
        double mean = 0;
        for (size_t i = 0; i < (size_t)width * height; i++)
            mean += rgb[3 * i + c];
        mean /= (double)width * height;
        assert_near(mean, expected[c] / total, 0.01, "environment mean");
    }
    free(rgb);
    scene_free(s);
}

/* ---- Mitsuba 3 renders the converted scene as the original ---- */

static void mitsuba_render(const char *scene_file, const char *image, double resolution, int spp,
                           int seed)
{
    run_result r = run("scripts/mitsuba-render %s -o %s --resolution %g --spp %d --seed %d "
                       "--max-depth 16",
                       scene_file, image, resolution, spp, seed);
    assert_succeeded(&r);
    run_free(&r);
}

/* `input` converted to work/name.xml renders in Mitsuba 3 as `input` does: the paired error of
 * two seeds each is zero within four standard errors. */
static void check_converted_renders_as_input(const char *input, const char *name,
                                             double resolution, int spp)
{
    char out[160], images[4][192];
    snprintf(out, sizeof out, "%s/%s.xml", work, name);
    scene *s = load(input);
    export_ok(s, out, 0);
    scene_free(s);
    for (int seed = 0; seed < 2; seed++) {
        snprintf(images[seed], sizeof images[seed], "%s/%s-in-%d.exr", work, name, seed + 1);
        snprintf(images[2 + seed], sizeof images[2 + seed], "%s/%s-out-%d.exr", work, name,
                 seed + 1);
        mitsuba_render(input, images[seed], resolution, spp, seed + 1);
        mitsuba_render(out, images[2 + seed], resolution, spp, seed + 1);
    }
    image_paired_error e;
    if (image_compare_paired(images[0], images[1], images[2], images[3], 0, &e))
        fail_msg("%s", error_message());
    print_message("%s converted, Mitsuba 3 path (%dx%d, %d spp): paired mse %.3g +- %.3g, "
                  "noisy rmse %.3g\n",
                  name, e.width, e.height, spp, e.mse, e.mse_standard_error, e.noisy_rmse);
    assert_true(e.mse <= 4.0 * e.mse_standard_error + 1e-8);
}

static void test_cornell_converted_renders_in_mitsuba3(void **state)
{
    (void)state;
    check_converted_renders_as_input(CORNELL, "cornell", 0.25, 16);
}

/* Every bsdf and emitter the writer uses is one Mitsuba 3 takes, with the same meaning (its
 * sphere and disk are exact, the converted ones tessellated). */
static void test_kinds_converted_renders_in_mitsuba3(void **state)
{
    (void)state;
    char input[160];
    write_kinds_scene(input);
    check_converted_renders_as_input(input, "kinds-render", 1.0, 16);
}

/* ---- errors ---- */

static void test_unknown_extension_refused(void **state)
{
    (void)state;
    scene *s = load(CORNELL);
    char out[160];
    snprintf(out, sizeof out, "%s/cornell.obj", work);
    error_clear();
    assert_int_equal(scene_export(s, out, 0), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), ".xml"));
    assert_non_null(strstr(error_message(), ".pbrt"));
    scene_free(s);
    struct stat st;
    assert_int_not_equal(stat(out, &st), 0);
}

static void test_output_over_input_refused(void **state)
{
    (void)state;
    /* a copy of the Cornell box, so that a failure cannot harm the shipped one */
    run_result r = run("cp -r data/cornell %s/input", work);
    assert_succeeded(&r);
    run_free(&r);
    char input[160], out[160];
    snprintf(input, sizeof input, "%s/input/scene.xml", work);
    char *before = read_text(input);
    scene *s = load(input);
    error_clear();
    assert_int_equal(scene_export(s, input, 1), -1); /* the scene itself, even with force */
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    /* a mesh folder that holds an input mesh: input/meshes/knot.ply */
    snprintf(out, sizeof out, "%s/input/meshes.xml", work);
    error_clear();
    assert_int_equal(scene_export(s, out, 1), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    char *after = read_text(input);
    assert_string_equal(before, after);
    free(before);
    free(after);
    /* an existing output is replaced only with force */
    snprintf(out, sizeof out, "%s/twice.pbrt", work);
    export_ok(s, out, 0);
    error_clear();
    assert_int_equal(scene_export(s, out, 0), -1);
    assert_non_null(strstr(error_message(), "--force"));
    export_ok(s, out, 1);
    scene_free(s);
}

static void test_command_line(void **state)
{
    (void)state;
    run_result r = run("bin/idmr convert %s -o %s/cli.obj", CORNELL, work);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "extension"));
    run_free(&r);
    r = run("bin/idmr convert %s", CORNELL);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "-o OUT is required"));
    run_free(&r);
    r = run("bin/idmr convert %s -o %s/cli.xml", CORNELL, work);
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "8 meshes"));
    run_free(&r);
    r = run("bin/idmr --help");
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "convert SCENE -o OUT"));
    run_free(&r);
    r = run("bin/idmr convert --help");
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "pbrt-v4"));
    run_free(&r);
}

int main(void)
{
#define CONVERT_TEST(f) cmocka_unit_test_setup_teardown(f, make_work_dir, remove_work_dir)
    const struct CMUnitTest tests[] = {
        CONVERT_TEST(test_cornell_mitsuba_round_trip),
        CONVERT_TEST(test_kinds_mitsuba_round_trip),
        CONVERT_TEST(test_gltf_mitsuba_round_trip),
        CONVERT_TEST(test_names_made_apart),
        CONVERT_TEST(test_kinds_pbrt_text),
        CONVERT_TEST(test_pbrt_environment_mean),
        CONVERT_TEST(test_cornell_converted_renders_in_mitsuba3),
        CONVERT_TEST(test_kinds_converted_renders_in_mitsuba3),
        CONVERT_TEST(test_unknown_extension_refused),
        CONVERT_TEST(test_output_over_input_refused),
        CONVERT_TEST(test_command_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
