/* test_mitsuba.c — the Mitsuba loader (host/mitsuba.c) and its helpers (xform, spectrum,
 * shapes).
 *
 * Most tests write a small scene into a fresh temporary directory, load it, and compare what
 * came out with values worked out by hand: transform matrices, camera frames, material fields,
 * vertex/triangle counts and bounding boxes. Error tests check that loading fails and that the
 * message names the file, the line and the element. The last tests load the real scenes from
 * ../shared/data (via IDMR_ROOT); a missing data directory fails them, it never skips. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"
#include "io/image.h"
#include "io/mitsuba.h"
#include "io/mitsuba_xml.h"
#include "core/scene.h"
#include "io/shapes.h"
#include "io/spectrum.h"
#include "io/xform.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define SCENES IDMR_ROOT "/../shared/data/scenes"

#define EPS 1e-4f

/* ---------------------------------------------------------------------------------------- */
/* Helpers                                                                                  */

static char temp_dir[64];

static int make_temp_dir(void **state)
{
    snprintf(temp_dir, sizeof temp_dir, "/tmp/idmr-test-mitsuba-XXXXXX");
    if (!mkdtemp(temp_dir))
        return -1;
    return 0;
}

static int remove_temp_dir(void **state)
{
    char command[128];
    snprintf(command, sizeof command, "rm -rf '%s'", temp_dir);
    return system(command) == 0 ? 0 : -1;
}

/* Writes `text` to temp_dir/name (sub-directories must exist); returns the path (static). */
static const char *write_file(const char *name, const char *text)
{
    static char path[256];
    snprintf(path, sizeof path, "%s/%s", temp_dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

static void make_subdir(const char *name)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", temp_dir, name);
    mkdir(path, 0755);
}

/* Loads `xml` written as temp_dir/scene.xml; fails the test if it does not load. */
static scene *load_ok(const char *xml)
{
    error_clear();
    warn_silence(1); /* most small scenes have no sensor */
    scene *s = mitsuba_load(write_file("scene.xml", xml));
    warn_silence(0);
    if (!s)
        fail_msg("load failed: %s", error_message());
    return s;
}

/* Loads `xml` expecting failure; checks the message holds "scene.xml:<line>:", `element`, and
 * `what`. */
static void load_fails(const char *xml, int line, const char *element, const char *what)
{
    char where[64];
    error_clear();
    scene *s = mitsuba_load(write_file("scene.xml", xml));
    if (s) {
        scene_free(s);
        fail_msg("expected a load error mentioning '%s'", what);
    }
    const char *message = error_message();
    snprintf(where, sizeof where, "scene.xml:%d:", line);
    if (!strstr(message, where) || !strstr(message, element) || !strstr(message, what))
        fail_msg("message '%s' lacks '%s', '%s' or '%s'", message, where, element, what);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* Runs mitsuba_load with stderr captured into `captured`. */
static scene *load_capturing_stderr(const char *path, char *captured, size_t size)
{
    char log_path[256];
    snprintf(log_path, sizeof log_path, "%s/stderr.log", temp_dir);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    int log = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && log >= 0);
    dup2(log, STDERR_FILENO);
    close(log);
    scene *s = mitsuba_load(path);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    FILE *f = fopen(log_path, "r");
    assert_non_null(f);
    size_t n = fread(captured, 1, size - 1, f);
    captured[n] = '\0';
    fclose(f);
    return s;
}

static void assert_vec3(const float *got, double x, double y, double z, float eps)
{
    if (fabs(got[0] - x) > eps || fabs(got[1] - y) > eps || fabs(got[2] - z) > eps)
        fail_msg("got (%g, %g, %g), expected (%g, %g, %g)", got[0], got[1], got[2], x, y, z);
}

static void assert_matrix(const float *got, const double *expected)
{
    for (int i = 0; i < 16; i++)
        if (fabs(got[i] - expected[i]) > 1e-5)
            fail_msg("matrix element %d (row %d, col %d): got %g, expected %g", i, i / 4, i % 4,
                     got[i], expected[i]);
}

static void mesh_bbox(const scene_mesh *m, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = FLT_MAX;
        hi[k] = -FLT_MAX;
    }
    for (uint32_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], m->positions[3 * v + k]);
            hi[k] = fmaxf(hi[k], m->positions[3 * v + k]);
        }
}

/* Geometric normal (unnormalised) of triangle t. */
static void triangle_normal(const scene_mesh *m, uint32_t t, double n[3])
{
    double p[3][3];
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            p[k][i] = m->positions[3 * m->indices[3 * t + k] + i];
    double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    xform_cross(e1, e2, n);
}

static double mesh_volume(const scene_mesh *m)
{
    mesh_data data = {m->vertex_count, m->triangle_count, m->positions, m->indices, NULL};
    return shapes_signed_volume(&data);
}

/* A sensor wrapping `transform_body` (children of <transform name="to_world">). */
static scene *load_sensor_transform(const char *transform_body)
{
    char xml[2048];
    snprintf(xml, sizeof xml,
             "<scene version=\"3.0.0\">\n"
             "  <sensor type=\"perspective\">\n"
             "    <float name=\"fov\" value=\"45\"/>\n"
             "    <transform name=\"to_world\">%s</transform>\n"
             "  </sensor>\n"
             "</scene>\n",
             transform_body);
    return load_ok(xml);
}

/* A scene with one rectangle carrying `bsdf` (inline XML); returns its material. */
static idmr_material load_bsdf(const char *version, const char *bsdf, scene **out)
{
    char xml[4096];
    snprintf(xml, sizeof xml,
             "<scene version=\"%s\">\n"
             "  <shape type=\"rectangle\" id=\"r\">%s</shape>\n"
             "</scene>\n",
             version, bsdf);
    scene *s = load_ok(xml);
    assert_int_equal(s->mesh_count, 1);
    idmr_material m = s->materials[s->meshes[0].material];
    *out = s;
    return m;
}

static const char *quad_obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

/* ---------------------------------------------------------------------------------------- */
/* Helpers' own maths                                                                       */

static void test_snake_case(void **state)
{
    static const char *cases[][2] = {
        {"toWorld", "to_world"},       {"intIOR", "int_ior"},       {"extIOR", "ext_ior"},
        {"fovAxis", "fov_axis"},       {"sampleCount", "sample_count"},
        {"diffuseReflectance", "diffuse_reflectance"},              {"to_world", "to_world"},
        {"fov", "fov"},                {"HTTPServer", "http_server"},
        {"cutoffAngle", "cutoff_angle"},
    };
    char out[64];
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        mitsuba_snake_case(cases[i][0], out, sizeof out);
        assert_string_equal(out, cases[i][1]);
    }
}

static void test_xform_rotate_and_compose(void **state)
{
    double z[3] = {0, 0, 1}, x[3] = {1, 0, 0}, p[3] = {1, 0, 0}, q[3];
    xform r = xform_rotate(z, 90.0);
    xform_apply_point(&r, p, q);
    assert_float_equal(q[0], 0.0, 1e-9);
    assert_float_equal(q[1], 1.0, 1e-9);
    xform t = xform_translate(1, 2, 3);
    xform rt = xform_multiply(&r, &t); /* translate, then rotate */
    double origin[3] = {0, 0, 0};
    xform_apply_point(&rt, origin, q);
    assert_float_equal(q[0], -2.0, 1e-9);
    assert_float_equal(q[1], 1.0, 1e-9);
    assert_float_equal(q[2], 3.0, 1e-9);
    xform rx = xform_rotate(x, 90.0);
    double y[3] = {0, 1, 0};
    xform_apply_vector(&rx, y, q);
    assert_float_equal(q[2], 1.0, 1e-9);
    xform mirror = xform_scale(-1, 1, 1);
    assert_true(xform_determinant3(&mirror) < 0.0);
}

static void test_spectrum_flat_and_grey(void **state)
{
    double lambda[2] = {400, 700}, one[2] = {1, 1}, half[1] = {0.5}, at[1] = {550};
    float rgb[3];
    spectrum_to_rgb(lambda, one, 2, rgb);
    assert_vec3(rgb, 1, 1, 1, 1e-3f);
    spectrum_to_rgb(at, half, 1, rgb);
    assert_vec3(rgb, 0.5, 0.5, 0.5, 1e-3f);
    double xyz[3];
    spectrum_cie_xyz(555.0, xyz); /* ȳ peaks at 1 near 555 nm */
    assert_float_equal(xyz[1], 1.0, 0.03);
    spectrum_cie_xyz(445.0, xyz); /* z̄ peaks near 1.78 around 445 nm */
    assert_float_equal(xyz[2], 1.78, 0.1);
}

static void test_spectrum_colours(void **state)
{
    double lambda[4] = {400, 550, 600, 700};
    double red[4] = {0.05, 0.05, 0.6, 0.65}, blue[4] = {0.8, 0.1, 0.05, 0.05};
    float rgb[3];
    spectrum_to_rgb(lambda, red, 4, rgb);
    assert_true(rgb[0] > rgb[1] && rgb[0] > rgb[2]);
    spectrum_to_rgb(lambda, blue, 4, rgb);
    assert_true(rgb[2] > rgb[0] && rgb[2] > rgb[1]);
}

static void test_srgb_to_linear(void **state)
{
    assert_float_equal(spectrum_srgb_to_linear(0.0f), 0.0f, 1e-7f);
    assert_float_equal(spectrum_srgb_to_linear(1.0f), 1.0f, 1e-6f);
    assert_float_equal(spectrum_srgb_to_linear(0.5f), 0.214041f, 1e-5f);
    assert_float_equal(spectrum_srgb_to_linear(0.04f), 0.04f / 12.92f, 1e-7f);
}

static void test_shapes_closed_and_outward(void **state)
{
    mesh_data mesh;
    double center[3] = {0, 0, 0};
    shapes_cube(&mesh);
    assert_float_equal(shapes_signed_volume(&mesh), 8.0, 1e-6);
    mesh_data_free(&mesh);
    shapes_sphere(center, 1.0, 32, 32, &mesh);
    assert_int_equal(mesh.triangle_count, 1984);
    double volume = shapes_signed_volume(&mesh);
    assert_true(volume > 0.97 * 4.0 / 3.0 * M_PI && volume < 4.0 / 3.0 * M_PI);
    mesh_data_free(&mesh);
    shapes_disk(64, &mesh);
    assert_int_equal(mesh.vertex_count, 65);
    assert_int_equal(mesh.triangle_count, 64);
    mesh_data_free(&mesh);
}

/* ---------------------------------------------------------------------------------------- */
/* Transforms through the XML                                                               */

static void test_transform_translate_then_rotate(void **state)
{
    scene *s = load_sensor_transform("<translate x=\"1\" y=\"0\" z=\"0\"/>"
                                     "<rotate z=\"1\" angle=\"90\"/>");
    /* R_z(90) · T(1,0,0) */
    static const double expected[16] = {0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, expected);
    scene_free(s);
}

static void test_transform_scale(void **state)
{
    scene *s = load_sensor_transform("<scale value=\"2\"/>");
    static const double uniform[16] = {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, uniform);
    scene_free(s);
    s = load_sensor_transform("<scale x=\"2\" y=\"3\"/>");
    static const double axes[16] = {2, 0, 0, 0, 0, 3, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, axes);
    scene_free(s);
    s = load_sensor_transform("<scale value=\"2, 3, 4\"/>");
    static const double values[16] = {2, 0, 0, 0, 0, 3, 0, 0, 0, 0, 4, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, values);
    scene_free(s);
}

static void test_transform_lookat(void **state)
{
    scene *s =
        load_sensor_transform("<lookat origin=\"1, 2, 3\" target=\"1, 2, 4\" up=\"0, 1, 0\"/>");
    static const double expected[16] = {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, expected);
    scene_free(s);
    /* Looking along +x with z up: camera x (image left) is +y. */
    s = load_sensor_transform("<lookat origin=\"0,0,0\" target=\"5,0,0\" up=\"0,0,1\"/>");
    static const double along_x[16] = {0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, along_x);
    scene_free(s);
}

static void test_transform_matrix(void **state)
{
    scene *s = load_sensor_transform(
        "<matrix value=\"1 0 0 4  0 0 -1 5  0 1 0 6  0 0 0 1\"/>");
    static const double full[16] = {1, 0, 0, 4, 0, 0, -1, 5, 0, 1, 0, 6, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, full);
    scene_free(s);
    s = load_sensor_transform("<matrix value=\"0,-1,0, 1,0,0, 0,0,1\"/>");
    static const double three[16] = {0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, three);
    scene_free(s);
}

static void test_transform_sequence(void **state)
{
    /* R_x(90) · T(1,2,3) · S(2) */
    scene *s = load_sensor_transform("<scale value=\"2\"/><translate value=\"1 2 3\"/>"
                                     "<rotate value=\"1, 0, 0\" angle=\"90\"/>");
    static const double expected[16] = {2, 0, 0, 1, 0, 0, -2, -3, 0, 2, 0, 2, 0, 0, 0, 1};
    assert_matrix(s->camera_info.to_world, expected);
    scene_free(s);
}

static void test_transform_old_dialect(void **state)
{
    scene *s = load_ok("<scene version=\"0.5.0\">\n"
                       "  <sensor type=\"perspective\">\n"
                       "    <float name=\"fov\" value=\"45\"/>\n"
                       "    <transform name=\"toWorld\"><translate x=\"7\"/></transform>\n"
                       "  </sensor>\n"
                       "</scene>\n");
    assert_float_equal(s->camera_info.to_world[3], 7.0f, EPS);
    assert_vec3(s->camera.origin, 7, 0, 0, EPS);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Camera                                                                                   */

static const char *camera_xml = "<scene version=\"3.0.0\">\n"
                                "  <sensor type=\"perspective\">\n"
                                "    <float name=\"fov\" value=\"90\"/>\n"
                                "    <string name=\"fov_axis\" value=\"%s\"/>\n"
                                "    <transform name=\"to_world\">\n"
                                "      <lookat origin=\"1,2,3\" target=\"1,2,13\" up=\"0,1,0\"/>\n"
                                "    </transform>\n"
                                "    <film type=\"hdrfilm\">\n"
                                "      <integer name=\"width\" value=\"200\"/>\n"
                                "      <integer name=\"height\" value=\"100\"/>\n"
                                "    </film>\n"
                                "  </sensor>\n"
                                "</scene>\n";

static scene *load_camera(const char *axis)
{
    char xml[1024];
    snprintf(xml, sizeof xml, camera_xml, axis);
    return load_ok(xml);
}

static void test_camera_frame_axis_x(void **state)
{
    scene *s = load_camera("x");
    assert_true(s->has_camera);
    assert_vec3(s->camera.origin, 1, 2, 3, EPS);
    assert_vec3(s->camera.forward, 0, 0, 1, EPS);
    assert_vec3(s->camera.up, 0, 1, 0, EPS);
    /* Mitsuba's camera +x = up × forward = +x world is image-left, so right = -x. */
    assert_vec3(s->camera.right, -1, 0, 0, EPS);
    assert_int_equal(s->camera.width, 200);
    assert_int_equal(s->camera.height, 100);
    assert_float_equal(s->camera.tan_half_x, 1.0f, EPS);
    assert_float_equal(s->camera.tan_half_y, 0.5f, EPS);
    assert_float_equal(s->camera_info.fov_degrees, 90.0f, EPS);
    assert_string_equal(s->camera_info.fov_axis, "x");
    scene_free(s);
}

static void test_camera_axis_y_smaller_diagonal(void **state)
{
    scene *s = load_camera("y");
    assert_float_equal(s->camera.tan_half_y, 1.0f, EPS);
    assert_float_equal(s->camera.tan_half_x, 2.0f, EPS);
    scene_free(s);
    s = load_camera("smaller"); /* 200x100: the smaller axis is y */
    assert_float_equal(s->camera.tan_half_y, 1.0f, EPS);
    assert_float_equal(s->camera.tan_half_x, 2.0f, EPS);
    scene_free(s);
    s = load_camera("larger");
    assert_float_equal(s->camera.tan_half_x, 1.0f, EPS);
    scene_free(s);
    s = load_camera("diagonal");
    assert_float_equal(s->camera.tan_half_x, 200.0 / sqrt(200.0 * 200 + 100 * 100), EPS);
    assert_float_equal(s->camera.tan_half_y, 100.0 / sqrt(200.0 * 200 + 100 * 100), EPS);
    scene_free(s);
}

static void test_camera_old_dialect_defaults(void **state)
{
    /* fovAxis, default film 768x576, thinlens as pinhole. */
    scene *s = load_ok("<scene version=\"0.6.0\">\n"
                       "  <sensor type=\"thinlens\">\n"
                       "    <float name=\"fov\" value=\"60\"/>\n"
                       "    <string name=\"fovAxis\" value=\"y\"/>\n"
                       "    <float name=\"apertureRadius\" value=\"0.1\"/>\n"
                       "  </sensor>\n"
                       "</scene>\n");
    assert_int_equal(s->camera.width, 768);
    assert_int_equal(s->camera.height, 576);
    assert_float_equal(s->camera.tan_half_y, tan(M_PI / 6), EPS);
    assert_float_equal(s->camera.tan_half_x, tan(M_PI / 6) * 768 / 576, EPS);
    assert_vec3(s->camera.right, -1, 0, 0, EPS);
    scene_free(s);
}

static void test_no_sensor_warns(void **state)
{
    char log[4096];
    const char *path = write_file("scene.xml", "<scene version=\"3.0.0\">\n"
                                               "  <shape type=\"cube\"/>\n"
                                               "</scene>\n");
    scene *s = load_capturing_stderr(path, log, sizeof log);
    assert_non_null(s);
    assert_int_equal(s->has_camera, 0);
    assert_non_null(strstr(log, "no <sensor>"));
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Shapes                                                                                   */

static void test_shape_rectangle(void **state)
{
    scene *s = load_ok("<scene version=\"3.0.0\">\n"
                       "  <shape type=\"rectangle\">\n"
                       "    <transform name=\"to_world\"><scale value=\"2\"/>"
                       "<translate z=\"5\"/></transform>\n"
                       "  </shape>\n"
                       "</scene>\n");
    const scene_mesh *m = &s->meshes[0];
    float lo[3], hi[3];
    double n[3];
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangle_count, 2);
    assert_string_equal(m->name, "rectangle");
    assert_string_equal(m->shape_type, "rectangle");
    assert_null(m->file);
    mesh_bbox(m, lo, hi);
    assert_vec3(lo, -2, -2, 5, EPS);
    assert_vec3(hi, 2, 2, 5, EPS);
    for (uint32_t t = 0; t < 2; t++) {
        triangle_normal(m, t, n);
        assert_true(n[2] > 0.0);
    }
    /* No bsdf: Mitsuba's default diffuse 0.5. */
    const idmr_material *mat = &s->materials[m->material];
    assert_int_equal(mat->kind, IDMR_MATERIAL_DIFFUSE);
    assert_vec3(mat->reflectance, 0.5, 0.5, 0.5, EPS);
    assert_int_equal(m->light, -1);
    scene_free(s);
}

/* An OBJ whose normals (vn) oppose its winding: the front side comes from the normals, as in
 * Mitsuba, so the triangle is turned; with face_normals the winding rules and stays. */
static void test_obj_oriented_by_its_normals(void **state)
{
    write_file("flipped.obj", "v 0 0 0\nv 0 1 0\nv 1 0 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    /* winding (0,0,0) (0,1,0) (1,0,0): normal (0,1,0) x (1,0,0) = (0,0,-1), against vn +z */
    for (int face_normals = 0; face_normals < 2; face_normals++) {
        char text[512];
        snprintf(text, sizeof text,
                 "<scene version=\"3.0.0\">\n"
                 "  <shape type=\"obj\">\n"
                 "    <string name=\"filename\" value=\"flipped.obj\"/>\n"
                 "    <boolean name=\"face_normals\" value=\"%s\"/>\n"
                 "  </shape>\n"
                 "</scene>\n",
                 face_normals ? "true" : "false");
        warn_silence(1);
        scene *s = mitsuba_load(write_file("scene.xml", text));
        warn_silence(0);
        if (!s)
            fail_msg("load failed: %s", error_message());
        const scene_mesh *m = &s->meshes[0];
        const float *a = &m->positions[3 * m->indices[0]], *b = &m->positions[3 * m->indices[1]],
                    *c = &m->positions[3 * m->indices[2]];
        float nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if (face_normals)
            assert_true(nz < 0); /* the winding as written */
        else
            assert_true(nz > 0); /* turned to face +z like the normals */
        scene_free(s);
    }
}

/* A mirroring to_world turns a built-in shape's normal (Mitsuba transforms it as a normal), so
 * the winding must flip with it: the rectangle mirrored in z faces -z. */
static void test_shape_mirrored_builtin(void **state)
{
    scene *s = load_ok("<scene version=\"3.0.0\">\n"
                       "  <shape type=\"rectangle\">\n"
                       "    <transform name=\"to_world\"><scale z=\"-1\"/></transform>\n"
                       "  </shape>\n"
                       "  <shape type=\"cube\">\n"
                       "    <transform name=\"to_world\"><scale x=\"-2\"/></transform>\n"
                       "  </shape>\n"
                       "</scene>\n");
    double n[3];
    triangle_normal(&s->meshes[0], 0, n);
    assert_true(n[2] < 0.0);
    assert_float_equal(mesh_volume(&s->meshes[1]), 16.0, 1e-3); /* still outward */
    scene_free(s);
}

static void test_shape_cube_sphere_disk(void **state)
{
    scene *s = load_ok(
        "<scene version=\"3.0.0\">\n"
        "  <shape type=\"cube\" id=\"box\">\n"
        "    <transform name=\"to_world\"><scale x=\"1\" y=\"2\" z=\"3\"/>"
        "<translate x=\"10\"/></transform>\n"
        "  </shape>\n"
        "  <shape type=\"sphere\">\n"
        "    <point name=\"center\" x=\"1\" y=\"2\" z=\"3\"/>\n"
        "    <float name=\"radius\" value=\"2\"/>\n"
        "  </shape>\n"
        "  <shape type=\"disk\">\n"
        "    <boolean name=\"flip_normals\" value=\"true\"/>\n"
        "  </shape>\n"
        "</scene>\n");
    float lo[3], hi[3];
    double n[3];
    assert_int_equal(s->mesh_count, 3);
    const scene_mesh *cube = &s->meshes[0], *sphere = &s->meshes[1], *disk = &s->meshes[2];
    assert_string_equal(cube->name, "box");
    assert_int_equal(cube->vertex_count, 8);
    assert_int_equal(cube->triangle_count, 12);
    mesh_bbox(cube, lo, hi);
    assert_vec3(lo, 9, -2, -3, EPS);
    assert_vec3(hi, 11, 2, 3, EPS);
    assert_float_equal(mesh_volume(cube), 2.0 * 4.0 * 6.0, 1e-3);

    assert_string_equal(sphere->name, "sphere");
    assert_int_equal(sphere->triangle_count, 1984);
    mesh_bbox(sphere, lo, hi);
    assert_vec3(lo, -1, 0, 1, 0.01f); /* the poles lie on z; x/y extremes at vertices */
    assert_vec3(hi, 3, 4, 5, 0.01f);
    assert_true(mesh_volume(sphere) > 0.97 * 4.0 / 3.0 * M_PI * 8.0);

    assert_int_equal(disk->vertex_count, 65);
    assert_int_equal(disk->triangle_count, 64);
    triangle_normal(disk, 0, n);
    assert_true(n[2] < 0.0); /* flipped */
    scene_free(s);
}

static void test_shape_obj_file(void **state)
{
    make_subdir("models");
    write_file("models/quad.obj", quad_obj);
    scene *s = load_ok("<scene version=\"0.5.0\">\n"
                       "  <shape type=\"obj\">\n"
                       "    <string name=\"filename\" value=\"models/quad.obj\"/>\n"
                       "    <boolean name=\"faceNormals\" value=\"true\"/>\n"
                       "    <transform name=\"toWorld\"><translate x=\"1\" y=\"2\" z=\"3\"/>"
                       "</transform>\n"
                       "  </shape>\n"
                       "  <shape type=\"obj\">\n"
                       "    <string name=\"filename\" value=\"models/quad.obj\"/>\n"
                       "  </shape>\n"
                       "</scene>\n");
    float lo[3], hi[3];
    assert_int_equal(s->mesh_count, 2);
    const scene_mesh *m = &s->meshes[0];
    assert_string_equal(m->name, "quad");
    assert_string_not_equal(s->meshes[1].name, "quad"); /* made unique */
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangle_count, 2);
    assert_non_null(strstr(m->file, "models/quad.obj"));
    assert_int_equal(m->xml_line, 2);
    mesh_bbox(m, lo, hi);
    assert_vec3(lo, 1, 2, 3, EPS);
    assert_vec3(hi, 2, 3, 3, EPS);
    scene_free(s);
}

static void test_area_emitter_attaches(void **state)
{
    scene *s = load_ok("<scene version=\"3.0.0\">\n"
                       "  <emitter type=\"area\" id=\"glow\">\n"
                       "    <rgb name=\"radiance\" value=\"4, 5, 6\"/>\n"
                       "  </emitter>\n"
                       "  <shape type=\"cube\"/>\n"
                       "  <shape type=\"rectangle\">\n"
                       "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1, 2, 3\"/>"
                       "</emitter>\n"
                       "  </shape>\n"
                       "  <shape type=\"disk\"><ref id=\"glow\"/></shape>\n"
                       "</scene>\n");
    assert_int_equal(s->light_count, 2);
    assert_int_equal(s->meshes[0].light, -1);
    const idmr_light *rect = &s->lights[s->meshes[1].light];
    assert_int_equal(rect->kind, IDMR_LIGHT_AREA);
    assert_vec3(rect->emission, 1, 2, 3, EPS);
    assert_int_equal(rect->first_triangle, 12);
    assert_int_equal(rect->triangle_count, 2);
    assert_float_equal(rect->area, 4.0f, EPS);
    const idmr_light *disk = &s->lights[s->meshes[2].light];
    assert_vec3(disk->emission, 4, 5, 6, EPS);
    assert_int_equal(disk->triangle_count, 64);
    assert_true(s->features & IDMR_FEATURE_AREA);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Materials                                                                                */

static void test_bsdf_diffuse_colours(void **state)
{
    scene *s;
    idmr_material m = load_bsdf("3.0.0",
                                "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
                                "value=\"0.1, 0.2, 0.3\"/></bsdf>",
                                &s);
    assert_int_equal(m.kind, IDMR_MATERIAL_DIFFUSE);
    assert_vec3(m.reflectance, 0.1, 0.2, 0.3, EPS);
    assert_int_equal(m.texture, -1);
    assert_string_equal(s->material_info[s->meshes[0].material].name, "r/bsdf");
    assert_string_equal(s->material_info[s->meshes[0].material].bsdf_type, "diffuse");
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"diffuse\"><srgb name=\"reflectance\" value=\"0.5, 1, 0\"/></bsdf>",
                  &s);
    assert_vec3(m.reflectance, 0.214041, 1, 0, EPS);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.25\"/></bsdf>",
                  &s);
    assert_vec3(m.reflectance, 0.25, 0.25, 0.25, EPS);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" "
                  "value=\"400:1, 500:1, 600:1, 700:1\"/></bsdf>",
                  &s);
    assert_vec3(m.reflectance, 1, 1, 1, 1e-3f);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" "
                  "value=\"400:0.05, 560:0.05, 600:0.6, 700:0.65\"/></bsdf>",
                  &s);
    assert_true(m.reflectance[0] > m.reflectance[1] && m.reflectance[0] > m.reflectance[2]);
    scene_free(s);
}

static void test_bsdf_dielectric_named_ior(void **state)
{
    scene *s;
    idmr_material m = load_bsdf("3.0.0", "<bsdf type=\"dielectric\"/>", &s);
    assert_int_equal(m.kind, IDMR_MATERIAL_DIELECTRIC);
    assert_float_equal(m.int_ior, 1.5046f, EPS);
    assert_float_equal(m.ext_ior, 1.000277f, 1e-6f);
    assert_int_equal(m.flags, 0);
    assert_true(s->features & IDMR_FEATURE_DIELECTRIC);
    scene_free(s);
    m = load_bsdf("0.5.0",
                  "<bsdf type=\"thindielectric\"><string name=\"intIOR\" value=\"water\"/>"
                  "<string name=\"extIOR\" value=\"air\"/></bsdf>",
                  &s);
    assert_float_equal(m.int_ior, 1.333f, EPS);
    assert_float_equal(m.ext_ior, 1.000277f, 1e-6f);
    assert_int_equal(m.flags, IDMR_MATERIAL_THIN);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"diamond\"/>"
                  "<float name=\"ext_ior\" value=\"1.33\"/></bsdf>",
                  &s);
    assert_float_equal(m.int_ior, 2.419f, EPS);
    assert_float_equal(m.ext_ior, 1.33f, EPS);
    scene_free(s);
}

static void test_bsdf_conductors(void **state)
{
    scene *s;
    /* 3.x default material: none, a perfect mirror. */
    idmr_material m = load_bsdf("3.0.0", "<bsdf type=\"conductor\"/>", &s);
    assert_int_equal(m.kind, IDMR_MATERIAL_MIRROR);
    assert_vec3(m.specular, 1, 1, 1, EPS);
    assert_true(s->features & IDMR_FEATURE_MIRROR);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"conductor\"><string name=\"material\" value=\"Au\"/></bsdf>", &s);
    assert_true(m.specular[0] > m.specular[1] && m.specular[1] > m.specular[2]);
    scene_free(s);
    /* eta = 2, k = 0 → F0 = 1/9; tinted by specular_reflectance 0.5. */
    m = load_bsdf("0.5.0",
                  "<bsdf type=\"roughconductor\"><rgb name=\"eta\" value=\"2, 2, 2\"/>"
                  "<rgb name=\"k\" value=\"0, 0, 0\"/><float name=\"extEta\" value=\"1\"/>"
                  "<rgb name=\"specularReflectance\" value=\"0.5\"/>"
                  "<float name=\"alpha\" value=\"0.3\"/>"
                  "<string name=\"distribution\" value=\"ggx\"/></bsdf>",
                  &s);
    assert_int_equal(m.kind, IDMR_MATERIAL_GLOSSY);
    assert_vec3(m.specular, 0.5 / 9.0, 0.5 / 9.0, 0.5 / 9.0, EPS);
    assert_vec3(m.reflectance, 0, 0, 0, EPS);
    assert_float_equal(m.roughness, 0.3f, EPS);
    assert_string_equal(s->material_info[0].bsdf_type, "roughconductor");
    scene_free(s);
    m = load_bsdf("3.0.0", "<bsdf type=\"roughconductor\"/>", &s);
    assert_float_equal(m.roughness, 0.1f, EPS);
    scene_free(s);
}

static void test_bsdf_plastics(void **state)
{
    scene *s;
    idmr_material m = load_bsdf("0.5.0",
                                "<bsdf type=\"plastic\"><rgb name=\"diffuseReflectance\" "
                                "value=\"0.2, 0.3, 0.4\"/><float name=\"intIOR\" "
                                "value=\"1.6\"/></bsdf>",
                                &s);
    assert_int_equal(m.kind, IDMR_MATERIAL_GLOSSY);
    assert_vec3(m.reflectance, 0.2, 0.3, 0.4, EPS);
    assert_vec3(m.specular, 1, 1, 1, EPS);
    assert_float_equal(m.roughness, 0.0f, EPS);
    assert_float_equal(m.int_ior, 1.6f, EPS);
    scene_free(s);
    m = load_bsdf("3.0.0",
                  "<bsdf type=\"roughplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.7\"/>"
                  "<float name=\"alpha\" value=\"0.25\"/></bsdf>",
                  &s);
    assert_vec3(m.reflectance, 0.7, 0.7, 0.7, EPS);
    assert_float_equal(m.roughness, 0.25f, EPS);
    assert_float_equal(m.int_ior, 1.49f, EPS); /* polypropylene */
    assert_true(s->features & IDMR_FEATURE_GLOSSY);
    scene_free(s);
}

static void test_bsdf_wrappers_and_refs(void **state)
{
    scene *s = load_ok(
        "<scene version=\"3.0.0\">\n"
        "  <bsdf type=\"twosided\" id=\"wall\">\n"
        "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.3\"/></bsdf>\n"
        "  </bsdf>\n"
        "  <bsdf type=\"mask\" id=\"leaf\">\n"
        "    <float name=\"opacity\" value=\"0.5\"/>\n"
        "    <ref id=\"wall\"/>\n"
        "  </bsdf>\n"
        "  <bsdf type=\"plastic\" id=\"unused\"/>\n"
        "  <shape type=\"cube\"><ref id=\"wall\"/></shape>\n"
        "  <shape type=\"cube\"><ref id=\"wall\"/></shape>\n"
        "  <shape type=\"cube\"><ref id=\"leaf\"/></shape>\n"
        "</scene>\n");
    assert_int_equal(s->meshes[0].material, s->meshes[1].material); /* shared */
    const idmr_material *wall = &s->materials[s->meshes[0].material];
    assert_int_equal(wall->kind, IDMR_MATERIAL_DIFFUSE);
    assert_int_equal(wall->flags, IDMR_MATERIAL_TWOSIDED);
    assert_vec3(wall->reflectance, 0.3, 0.3, 0.3, EPS);
    assert_string_equal(s->material_info[s->meshes[0].material].name, "wall");
    assert_string_equal(s->material_info[s->meshes[0].material].bsdf_type, "diffuse");
    const idmr_material *leaf = &s->materials[s->meshes[2].material];
    assert_int_equal(leaf->flags, IDMR_MATERIAL_TWOSIDED);
    assert_string_equal(s->material_info[s->meshes[2].material].name, "leaf");
    assert_int_equal(s->material_count, 2); /* the unused plastic is not added */
    assert_false(s->features & IDMR_FEATURE_GLOSSY);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Emitters, parameters, includes                                                           */

static void test_emitters(void **state)
{
    scene *s = load_ok(
        "<scene version=\"3.0.0\">\n"
        "  <emitter type=\"point\">\n"
        "    <point name=\"position\" value=\"1, 2, 3\"/>\n"
        "    <rgb name=\"intensity\" value=\"10\"/>\n"
        "  </emitter>\n"
        "  <emitter type=\"point\">\n"
        "    <transform name=\"to_world\"><translate x=\"4\" y=\"5\" z=\"6\"/></transform>\n"
        "  </emitter>\n"
        "  <emitter type=\"spot\">\n"
        "    <transform name=\"to_world\"><lookat origin=\"0,0,0\" target=\"0,-2,0\" "
        "up=\"0,0,1\"/></transform>\n"
        "    <float name=\"cutoff_angle\" value=\"40\"/>\n"
        "  </emitter>\n"
        "  <emitter type=\"directional\">\n"
        "    <vector name=\"direction\" value=\"0, 0, -2\"/>\n"
        "    <spectrum name=\"irradiance\" value=\"3\"/>\n"
        "  </emitter>\n"
        "  <shape type=\"cube\"/>\n"
        "</scene>\n");
    assert_int_equal(s->light_count, 4);
    const idmr_light *l = s->lights;
    assert_int_equal(l[0].kind, IDMR_LIGHT_POINT);
    assert_vec3(l[0].position, 1, 2, 3, EPS);
    assert_vec3(l[0].emission, 10, 10, 10, EPS);
    assert_vec3(l[1].position, 4, 5, 6, EPS);
    assert_vec3(l[1].emission, 1, 1, 1, EPS);
    assert_int_equal(l[2].kind, IDMR_LIGHT_SPOT);
    assert_vec3(l[2].direction, 0, -1, 0, EPS);
    assert_float_equal(l[2].cos_cutoff, cos(40 * M_PI / 180), EPS);
    assert_float_equal(l[2].cos_falloff_start, cos(30 * M_PI / 180), EPS);
    assert_int_equal(l[3].kind, IDMR_LIGHT_DIRECTIONAL);
    assert_vec3(l[3].direction, 0, 0, -1, EPS);
    assert_vec3(l[3].emission, 3, 3, 3, EPS);
    assert_true((s->features & (IDMR_FEATURE_POINT | IDMR_FEATURE_SPOT |
                                IDMR_FEATURE_DIRECTIONAL)) ==
                (IDMR_FEATURE_POINT | IDMR_FEATURE_SPOT | IDMR_FEATURE_DIRECTIONAL));
    scene_free(s);
}

static void test_emitters_old_dialect(void **state)
{
    scene *s = load_ok("<scene version=\"0.6.0\">\n"
                       "  <emitter type=\"spot\">\n"
                       "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
                       "<translate y=\"3\"/></transform>\n"
                       "    <float name=\"cutoffAngle\" value=\"30\"/>\n"
                       "    <float name=\"beamWidth\" value=\"10\"/>\n"
                       "  </emitter>\n"
                       "  <emitter type=\"directional\">\n"
                       "    <transform name=\"toWorld\">"
                       "<rotate y=\"1\" angle=\"90\"/></transform>\n"
                       "  </emitter>\n"
                       "</scene>\n");
    /* R_x(-90) takes +z to +y. */
    assert_vec3(s->lights[0].position, 0, 3, 0, EPS);
    assert_vec3(s->lights[0].direction, 0, 1, 0, EPS);
    assert_float_equal(s->lights[0].cos_falloff_start, cos(10 * M_PI / 180), EPS);
    /* R_y(90) takes +z to +x. */
    assert_vec3(s->lights[1].direction, 1, 0, 0, EPS);
    scene_free(s);
}

static void test_default_substitution(void **state)
{
    scene *s = load_ok("<scene version=\"3.0.0\">\n"
                       "  <default name=\"res\" value=\"64\"/>\n"
                       "  <default name=\"angle\" value=\"30\"/>\n"
                       "  <default name=\"grey\" value=\"0.25\"/>\n"
                       "  <sensor type=\"perspective\">\n"
                       "    <float name=\"fov\" value=\"$angle\"/>\n"
                       "    <film type=\"hdrfilm\">\n"
                       "      <integer name=\"width\" value=\"$res\"/>\n"
                       "      <integer name=\"height\" value=\"$res\"/>\n"
                       "    </film>\n"
                       "  </sensor>\n"
                       "  <shape type=\"cube\"><bsdf type=\"diffuse\">"
                       "<rgb name=\"reflectance\" value=\"$grey, 0.5, $grey\"/></bsdf></shape>\n"
                       "</scene>\n");
    assert_int_equal(s->camera.width, 64);
    assert_int_equal(s->camera.height, 64);
    assert_float_equal(s->camera_info.fov_degrees, 30.0f, EPS);
    assert_vec3(s->materials[0].reflectance, 0.25, 0.5, 0.25, EPS);
    scene_free(s);
}

static void test_include(void **state)
{
    make_subdir("fragments");
    write_file("fragments/materials.xml",
               "<scene version=\"3.0.0\">\n"
               "  <bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.9, 0, 0\"/>"
               "</bsdf>\n"
               "</scene>\n");
    scene *s = load_ok("<scene version=\"3.0.0\">\n"
                       "  <include filename=\"fragments/materials.xml\"/>\n"
                       "  <shape type=\"cube\"><ref id=\"red\"/></shape>\n"
                       "</scene>\n");
    assert_vec3(s->materials[s->meshes[0].material].reflectance, 0.9, 0, 0, EPS);
    scene_free(s);
}

static void test_texture_missing_file(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "    <bsdf type=\"diffuse\">\n"
               "      <texture name=\"reflectance\" type=\"bitmap\">\n"
               "        <string name=\"filename\" value=\"textures/none.png\"/>\n"
               "      </texture>\n"
               "    </bsdf>\n"
               "  </shape>\n"
               "</scene>\n",
               4, "<texture name=\"reflectance\" type=\"bitmap\">", "none.png");
}

/* ---------------------------------------------------------------------------------------- */
/* Errors                                                                                   */

static void test_error_malformed_xml(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "  </shap>\n"
               "</scene>\n",
               3, "malformed XML", "shap");
}

static void test_error_unknown_element(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\"/>\n"
               "  <medium type=\"homogeneous\" id=\"fog\"/>\n"
               "</scene>\n",
               3, "<medium type=\"homogeneous\" id=\"fog\">", "unsupported element");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "    <transform name=\"to_world\"><shear value=\"1\"/></transform>\n"
               "  </shape>\n"
               "</scene>\n",
               3, "<shear>", "unknown transform operation");
}

static void test_error_unsupported_types(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "\n"
               "  <bsdf type=\"hair\" id=\"h\"/>\n"
               "</scene>\n",
               3, "<bsdf type=\"hair\" id=\"h\">", "unsupported bsdf type 'hair'");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "    <bsdf type=\"twosided\"><bsdf type=\"blendbsdf\"/></bsdf>\n"
               "  </shape>\n"
               "</scene>\n",
               3, "<bsdf type=\"blendbsdf\">", "unsupported bsdf type");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <emitter type=\"sunsky\"/>\n"
               "</scene>\n",
               2, "<emitter type=\"sunsky\">", "unsupported emitter type");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"serialized\"><string name=\"filename\" value=\"a.serialized\"/>"
               "</shape>\n"
               "</scene>\n",
               2, "<shape type=\"serialized\">", "unsupported shape type 'serialized'");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\"><bsdf type=\"dielectric\">\n"
               "    <string name=\"int_ior\" value=\"unobtainium\"/>\n"
               "  </bsdf></shape>\n"
               "</scene>\n",
               3, "<string name=\"int_ior\">", "unknown index of refraction 'unobtainium'");
}

static void test_error_bad_number(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <sensor type=\"perspective\">\n"
               "    <float name=\"fov\" value=\"abc\"/>\n"
               "  </sensor>\n"
               "</scene>\n",
               3, "<float name=\"fov\">", "'abc' is not a number");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "    <transform name=\"to_world\">\n"
               "      <translate x=\"1\" y=\"nan\"/>\n"
               "    </transform>\n"
               "  </shape>\n"
               "</scene>\n",
               4, "<translate>", "'nan' is not a number");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\"><bsdf type=\"diffuse\">\n"
               "    <spectrum name=\"reflectance\" value=\"400:0.5, 500:x\"/>\n"
               "  </bsdf></shape>\n"
               "</scene>\n",
               3, "<spectrum name=\"reflectance\">", "'x' is not a number");
    load_fails("<scene version=\"3.0.0\">\n"
               "  <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\n"
               "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"12.5\"/></film>\n"
               "  </sensor>\n"
               "</scene>\n",
               3, "<integer name=\"width\">", "'12.5' is not an integer");
}

static void test_error_old_dialect_names_as_written(void **state)
{
    load_fails("<scene version=\"0.5.0\">\n"
               "  <shape type=\"cube\"><bsdf type=\"dielectric\">\n"
               "    <float name=\"intIOR\" value=\"1,5\"/>\n"
               "  </bsdf></shape>\n"
               "</scene>\n",
               3, "<float name=\"intIOR\">", "'1,5' is not a number");
}

static void test_error_missing_mesh_file(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"obj\">\n"
               "    <string name=\"filename\" value=\"models/Mesh000.obj\"/>\n"
               "  </shape>\n"
               "</scene>\n",
               2, "<shape type=\"obj\">", "cannot read 'models/Mesh000.obj'");
    assert_non_null(strstr(error_message(), "No such file or directory"));
}

static void test_error_missing_ref(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <shape type=\"cube\">\n"
               "    <ref id=\"nowhere\"/>\n"
               "  </shape>\n"
               "</scene>\n",
               3, "<ref id=\"nowhere\">", "unknown id 'nowhere'");
}

static void test_error_undefined_parameter(void **state)
{
    load_fails("<scene version=\"3.0.0\">\n"
               "  <integrator type=\"path\">\n"
               "    <integer name=\"max_depth\" value=\"$depth\"/>\n"
               "  </integrator>\n"
               "</scene>\n",
               3, "<integer name=\"max_depth\">", "undefined parameter '$depth'");
}

static void test_error_missing_scene_file(void **state)
{
    error_clear();
    assert_null(mitsuba_load("/nonexistent/idmr/scene.xml"));
    assert_non_null(strstr(error_message(), "/nonexistent/idmr/scene.xml"));
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* An envmap becomes a uniform environment light of the map's mean radiance times scale: a
 * white 8-bit map (sRGB 255 = linear 1) with scale 2 gives radiance 2. */
static void test_envmap_is_uniform_environment(void **state)
{
    char log[4096], sky[512];
    unsigned char white[4 * 2 * 3];
    memset(white, 255, sizeof white);
    snprintf(sky, sizeof sky, "%s/sky.png", temp_dir);
    assert_int_equal(image_write_rgb8(sky, 4, 2, white), 0);
    const char *path = write_file("scene.xml",
                                  "<scene version=\"3.0.0\">\n"
                                  "  <shape type=\"cube\"/>\n"
                                  "  <emitter type=\"envmap\">\n"
                                  "    <string name=\"filename\" value=\"sky.png\"/>\n"
                                  "    <float name=\"scale\" value=\"2\"/>\n"
                                  "  </emitter>\n"
                                  "</scene>\n");
    scene *s = load_capturing_stderr(path, log, sizeof log);
    if (!s)
        fail_msg("load failed: %s", error_message());
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    for (int c = 0; c < 3; c++)
        assert_float_equal(s->lights[0].emission[c], 2.0f, 1e-4f);
    assert_true(s->features & IDMR_FEATURE_ENVIRONMENT);
    if (!strstr(log, "scene.xml:3:") || !strstr(log, "<emitter type=\"envmap\">") ||
        !strstr(log, "directional structure is ignored"))
        fail_msg("warning '%s' lacks file:line, element or reason", log);
    scene_free(s);
}

static void test_constant_environment(void **state)
{
    const char *path = write_file("scene.xml",
                                  "<scene version=\"3.0.0\">\n"
                                  "  <shape type=\"cube\"/>\n"
                                  "  <emitter type=\"constant\">\n"
                                  "    <rgb name=\"radiance\" value=\"0.5, 1, 2\"/>\n"
                                  "  </emitter>\n"
                                  "</scene>\n");
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    if (!s)
        fail_msg("load failed: %s", error_message());
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    assert_float_equal(s->lights[0].emission[2], 2.0f, 1e-6f);
    assert_true(s->lights[0].power > 0);
    scene_free(s);
}

static void test_error_envmap_missing_file(void **state)
{
    const char *path = write_file("scene.xml",
                                  "<scene version=\"3.0.0\">\n"
                                  "  <emitter type=\"envmap\">\n"
                                  "    <string name=\"filename\" value=\"absent-sky.exr\"/>\n"
                                  "  </emitter>\n"
                                  "</scene>\n");
    error_clear();
    assert_null(mitsuba_load(path));
    const char *message = error_message();
    if (!strstr(message, "absent-sky.exr") || !strstr(message, "scene.xml:2"))
        fail_msg("unexpected message: %s", message);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
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

static size_t count_lights(const scene *s, unsigned int kind)
{
    size_t n = 0;
    for (size_t i = 0; i < s->light_count; i++)
        n += s->lights[i].kind == kind;
    return n;
}

static void test_real_cbox(void **state)
{
    require_shared_data();
    error_clear();
    scene *s = mitsuba_load(SCENES "/cbox-mitsuba/cbox.xml");
    if (!s)
        fail_msg("%s", error_message());
    assert_int_equal(s->mesh_count, 8);
    assert_int_equal(s->light_count, 1);
    assert_int_equal(count_lights(s, IDMR_LIGHT_AREA), 1);
    assert_true(s->has_camera);
    assert_int_equal(s->camera.width, 256);
    assert_int_equal(s->camera.height, 256);
    assert_float_equal(s->camera_info.fov_degrees, 39.3077f, EPS);
    assert_float_equal(s->camera.tan_half_x, tan(39.3077 * M_PI / 360), EPS);
    assert_vec3(s->camera.origin, 278, 273, -800, 1e-3f);
    assert_vec3(s->camera.forward, 0, 0, 1, EPS);
    /* The luminaire's radiance spectrum rises towards red. */
    const idmr_light *light = &s->lights[0];
    assert_true(light->emission[0] > light->emission[2]);
    assert_true(light->area > 0.0f);
    /* The red wall is red. */
    int red_walls = 0;
    for (size_t i = 0; i < s->mesh_count; i++)
        if (strcmp(s->meshes[i].name, "cbox_redwall") == 0) {
            const float *r = s->materials[s->meshes[i].material].reflectance;
            assert_true(r[0] > 2 * r[1] && r[0] > 2 * r[2]);
            red_walls++;
        }
    assert_int_equal(red_walls, 1);
    scene_free(s);
}

static void test_real_glass_of_water_without_mesh000(void **state)
{
    require_shared_data();
    error_clear();
    scene *s = mitsuba_load(SCENES "/glass-of-water/scene-without-mesh000.xml");
    if (!s)
        fail_msg("%s", error_message());
    assert_int_equal(s->mesh_count, 16);
    assert_int_equal(s->light_count, 1);
    assert_true(s->features & IDMR_FEATURE_DIELECTRIC);
    assert_true(s->features & IDMR_FEATURE_GLOSSY);
    assert_true(s->features & IDMR_FEATURE_AREA);
    assert_int_equal(s->camera.width, 1280);
    assert_int_equal(s->camera.height, 720);
    scene_free(s);
}

static void test_real_glass_of_water_missing_mesh(void **state)
{
    require_shared_data();
    error_clear();
    scene *s = mitsuba_load(SCENES "/glass-of-water/scene.xml");
    if (s) {
        scene_free(s);
        fail_msg("glass-of-water/scene.xml loaded, but its models/Mesh000.obj is absent");
    }
    const char *message = error_message();
    if (!strstr(message, "models/Mesh000.obj") || !strstr(message, "scene.xml:169:") ||
        !strstr(message, "<shape type=\"obj\">"))
        fail_msg("unexpected message: %s", message);
}

static void test_real_living_room(void **state)
{
    char log[16384];
    require_shared_data();
    error_clear();
    scene *s = load_capturing_stderr(SCENES "/living-room/scene.xml", log, sizeof log);
    if (!s)
        fail_msg("%s", error_message());
    assert_true(s->mesh_count >= 60);
    assert_true(s->features & IDMR_FEATURE_TEXTURED);
    assert_true(s->texture_count >= 1);
    /* The sky map becomes one environment light of its mean radiance. */
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    assert_true(s->lights[0].emission[0] > 0 && s->lights[0].emission[2] > 0);
    assert_true(s->features & IDMR_FEATURE_ENVIRONMENT);
    if (!strstr(log, "directional structure is ignored"))
        fail_msg("no envmap warning in: %s", log);
    scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_snake_case),
        cmocka_unit_test(test_xform_rotate_and_compose),
        cmocka_unit_test(test_spectrum_flat_and_grey),
        cmocka_unit_test(test_spectrum_colours),
        cmocka_unit_test(test_srgb_to_linear),
        cmocka_unit_test(test_shapes_closed_and_outward),
        cmocka_unit_test(test_transform_translate_then_rotate),
        cmocka_unit_test(test_transform_scale),
        cmocka_unit_test(test_transform_lookat),
        cmocka_unit_test(test_transform_matrix),
        cmocka_unit_test(test_transform_sequence),
        cmocka_unit_test(test_transform_old_dialect),
        cmocka_unit_test(test_camera_frame_axis_x),
        cmocka_unit_test(test_camera_axis_y_smaller_diagonal),
        cmocka_unit_test(test_camera_old_dialect_defaults),
        cmocka_unit_test(test_no_sensor_warns),
        cmocka_unit_test(test_shape_rectangle),
        cmocka_unit_test(test_shape_mirrored_builtin),
        cmocka_unit_test(test_obj_oriented_by_its_normals),
        cmocka_unit_test(test_shape_cube_sphere_disk),
        cmocka_unit_test(test_shape_obj_file),
        cmocka_unit_test(test_area_emitter_attaches),
        cmocka_unit_test(test_bsdf_diffuse_colours),
        cmocka_unit_test(test_bsdf_dielectric_named_ior),
        cmocka_unit_test(test_bsdf_conductors),
        cmocka_unit_test(test_bsdf_plastics),
        cmocka_unit_test(test_bsdf_wrappers_and_refs),
        cmocka_unit_test(test_emitters),
        cmocka_unit_test(test_emitters_old_dialect),
        cmocka_unit_test(test_default_substitution),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_texture_missing_file),
        cmocka_unit_test(test_error_malformed_xml),
        cmocka_unit_test(test_error_unknown_element),
        cmocka_unit_test(test_error_unsupported_types),
        cmocka_unit_test(test_error_bad_number),
        cmocka_unit_test(test_error_old_dialect_names_as_written),
        cmocka_unit_test(test_error_missing_mesh_file),
        cmocka_unit_test(test_error_missing_ref),
        cmocka_unit_test(test_error_undefined_parameter),
        cmocka_unit_test(test_error_missing_scene_file),
        cmocka_unit_test(test_envmap_is_uniform_environment),
        cmocka_unit_test(test_constant_environment),
        cmocka_unit_test(test_error_envmap_missing_file),
        cmocka_unit_test(test_real_cbox),
        cmocka_unit_test(test_real_glass_of_water_without_mesh000),
        cmocka_unit_test(test_real_glass_of_water_missing_mesh),
        cmocka_unit_test(test_real_living_room),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
