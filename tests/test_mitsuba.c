/* test_mitsuba.c — the Mitsuba loader (host/io/mitsuba/mitsuba_*.c) and its helpers (xform,
 * spectrum, shapes).
 *
 * Most tests write a small scene into a temporary directory, load it, and compare what came
 * out with values worked out by hand: transform matrices, camera frames, material fields,
 * light fields, vertex/triangle counts and bounding boxes. Where many scenes differ only in a
 * few lines and in the values expected (transforms, fov axes, bsdfs, emitters, errors), the
 * cases are tables and each case runs as its own test, named by the case. Error tests check
 * that loading fails and that the message names the file, the line and the element. The last
 * tests load the real scenes from ../shared/data (via IDMR_ROOT); a missing data directory
 * fails them, it never skips; one of them loads the living room streaming (meshes released once
 * read) and checks that each mesh read again is what the whole load read. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "io/image.h"
#include "io/mitsuba/mitsuba_xml.h"
#include "core/shapes.h"
#include "core/spectrum.h"
#include "core/xform.h"

#define EPS 1e-4f

/* ---------------------------------------------------------------------------------------- */
/* Helpers                                                                                  */

static char temp_dir[64];

static int make_temp_dir(void **state)
{
    return temp_dir_make(temp_dir, "mitsuba");
}

static int remove_temp_dir(void **state)
{
    return temp_dir_remove(temp_dir);
}

static const char *write_file(const char *name, const char *text)
{
    return write_text(temp_dir, name, text);
}

/* `body` inside <scene version=...> ... </scene>, written as temp_dir/scene.xml (the body
 * starts on line 2); returns its path. */
static const char *write_scene(const char *version, const char *body)
{
    char xml[8192];
    snprintf(xml, sizeof xml, "<scene version=\"%s\">\n%s</scene>\n", version, body);
    return write_file("scene.xml", xml);
}

/* Loads the scene `body` (see write_scene); fails the test if it does not load. */
static scene *load_scene(const char *version, const char *body)
{
    return test_load_scene(write_scene(version, body));
}

/* Runs mitsuba_load with stderr captured; *log gets what was printed (malloc'd). */
static scene *load_capturing_stderr(const char *path, char **log)
{
    const char *log_path = path_in(temp_dir, "stderr.log");
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    int log_fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && log_fd >= 0);
    dup2(log_fd, STDERR_FILENO);
    close(log_fd);
    error_clear();
    scene *s = mitsuba_load(path);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    *log = read_all(log_path, NULL);
    assert_non_null(*log);
    return s;
}

static void assert_vec3(const float *got, double x, double y, double z, float eps)
{
    if (fabs(got[0] - x) > eps || fabs(got[1] - y) > eps || fabs(got[2] - z) > eps)
        fail_msg("got (%g, %g, %g), expected (%g, %g, %g)", got[0], got[1], got[2], x, y, z);
}

static void assert_float3(const float *got, const float *expected, float eps)
{
    assert_vec3(got, expected[0], expected[1], expected[2], eps);
}

static void assert_matrix(const float *got, const double *expected)
{
    for (int i = 0; i < 16; i++)
        if (fabs(got[i] - expected[i]) > 1e-5)
            fail_msg("matrix element %d (row %d, col %d): got %g, expected %g", i, i / 4, i % 4,
                     got[i], expected[i]);
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
    mesh_data data = {m->vertex_count, m->triangle_count, m->positions, m->indices, NULL, NULL, 0};
    return shapes_signed_volume(&data);
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

static void test_xform_rotate_z(void **state)
{
    double z[3] = {0, 0, 1}, p[3] = {1, 0, 0}, q[3];
    xform r = xform_rotate(z, 90.0);
    xform_apply_point(&r, p, q);
    assert_float_equal(q[0], 0.0, 1e-9);
    assert_float_equal(q[1], 1.0, 1e-9);
}

static void test_xform_compose_translate_then_rotate(void **state)
{
    double z[3] = {0, 0, 1}, origin[3] = {0, 0, 0}, q[3];
    xform r = xform_rotate(z, 90.0);
    xform t = xform_translate(1, 2, 3);
    xform rt = xform_multiply(&r, &t); /* translate, then rotate */
    xform_apply_point(&rt, origin, q);
    assert_float_equal(q[0], -2.0, 1e-9);
    assert_float_equal(q[1], 1.0, 1e-9);
    assert_float_equal(q[2], 3.0, 1e-9);
}

static void test_xform_rotate_x_and_mirror(void **state)
{
    double x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, q[3];
    xform rx = xform_rotate(x, 90.0);
    xform_apply_vector(&rx, y, q);
    assert_float_equal(q[2], 1.0, 1e-9);
    xform mirror = xform_scale(-1, 1, 1);
    assert_true(xform_determinant3(&mirror) < 0.0);
}

/* Flat and grey spectra against exact values: a grey reflectance is itself, a flat reflectance
 * over the whole range is D65 white (1, 1, 1), a flat emission is equal-energy white
 * (XYZ = (1, 1, 1)) in linear sRGB: the rows of the XYZ → sRGB matrix summed. */
static void test_spectrum_flat_and_grey(void **state)
{
    double whole[2] = {360, 830}, one[2] = {1, 1}, half[1] = {0.5};
    float rgb[3];
    spectrum_to_rgb(whole, one, 2, SPECTRUM_REFLECTANCE, rgb);
    assert_vec3(rgb, 1, 1, 1, 2e-3f);
    spectrum_to_rgb(NULL, half, 1, SPECTRUM_REFLECTANCE, rgb);
    assert_vec3(rgb, 0.5, 0.5, 0.5, 0.0f);
    spectrum_to_rgb(whole, one, 2, SPECTRUM_EMISSION, rgb);
    assert_vec3(rgb, 3.2404542 - 1.5371385 - 0.4985314, -0.9692660 + 1.8760108 + 0.0415560,
                0.0556434 - 0.2040259 + 1.0572252, 6e-3f);
    spectrum_to_rgb(NULL, half, 1, SPECTRUM_EMISSION, rgb);
    assert_float_equal(rgb[0], 0.5 * (3.2404542 - 1.5371385 - 0.4985314), 3e-3);
    double xyz[3];
    spectrum_cie_xyz(555.0, xyz); /* ȳ peaks at 1 near 555 nm */
    assert_float_equal(xyz[1], 1.0, 0.03);
    spectrum_cie_xyz(445.0, xyz); /* z̄ peaks near 1.78 around 445 nm */
    assert_float_equal(xyz[2], 1.78, 0.1);
}

/* What Mitsuba 3 makes of a spectrum in its RGB variants, and what idmr makes of it. The
 * expected triples were read from Mitsuba 3.9.1 (scalar_rgb: mi.traverse() of a diffuse bsdf's
 * reflectance and of an area emitter's radiance holding the spectrum); Mitsuba integrates
 * tabulated colour matching functions, idmr an analytic fit, so they agree to 0.005 + 1 %. */
typedef struct mitsuba_spectrum_case {
    int count;
    double lambda[4], value[4];
    spectrum_use use;
    float expected[3];
} mitsuba_spectrum_case;

static void test_spectrum_as_mitsuba(void **state)
{
    static const mitsuba_spectrum_case cases[] = {
        {2, {400, 700}, {1, 1}, SPECTRUM_REFLECTANCE, {0.995342f, 0.999756f, 0.994909f}},
        {2, {400, 700}, {0.9, 0.9}, SPECTRUM_REFLECTANCE, {0.895808f, 0.899781f, 0.895418f}},
        {4, {400, 500, 600, 700}, {0.5, 0.6, 0.2, 0.1}, SPECTRUM_REFLECTANCE,
         {0.0790617f, 0.442535f, 0.573315f}},
        {2, {400, 700}, {1, 1}, SPECTRUM_EMISSION, {1.19969f, 0.94952f, 0.903443f}},
        {2, {360, 830}, {1, 1}, SPECTRUM_EMISSION, {1.20488f, 0.948228f, 0.909267f}},
        {4, {400, 500, 600, 700}, {0.5, 0.6, 0.2, 0.1}, SPECTRUM_EMISSION,
         {0.130632f, 0.417629f, 0.522094f}},
        /* The Cornell box's luminaire (cbox-mitsuba/cbox.xml). */
        {4, {400, 500, 600, 700}, {0, 8, 15.6, 18.4}, SPECTRUM_EMISSION,
         {20.7108f, 10.8546f, 2.77115f}},
    };
    for (size_t i = 0; i < ARRAY_COUNT(cases); i++) {
        const mitsuba_spectrum_case *c = &cases[i];
        float rgb[3];
        spectrum_to_rgb(c->lambda, c->value, c->count, c->use, rgb);
        for (int k = 0; k < 3; k++)
            if (fabsf(rgb[k] - c->expected[k]) > 0.005f + 0.01f * fabsf(c->expected[k]))
                fail_msg("case %zu channel %d: idmr %g, Mitsuba 3 %g", i, k, rgb[k],
                         c->expected[k]);
    }
}

static void test_spectrum_colours(void **state)
{
    double lambda[4] = {400, 550, 600, 700};
    double red[4] = {0.05, 0.05, 0.6, 0.65}, blue[4] = {0.8, 0.1, 0.05, 0.05};
    float rgb[3];
    spectrum_to_rgb(lambda, red, 4, SPECTRUM_REFLECTANCE, rgb);
    assert_true(rgb[0] > rgb[1] && rgb[0] > rgb[2]);
    spectrum_to_rgb(lambda, blue, 4, SPECTRUM_REFLECTANCE, rgb);
    assert_true(rgb[2] > rgb[0] && rgb[2] > rgb[1]);
}

static void test_srgb_to_linear(void **state)
{
    assert_float_equal(spectrum_srgb_to_linear(0.0f), 0.0f, 1e-7f);
    assert_float_equal(spectrum_srgb_to_linear(1.0f), 1.0f, 1e-6f);
    assert_float_equal(spectrum_srgb_to_linear(0.5f), 0.214041f, 1e-5f);
    assert_float_equal(spectrum_srgb_to_linear(0.04f), 0.04f / 12.92f, 1e-7f);
}

static void test_shapes_cube_closed(void **state)
{
    mesh_data mesh;
    shapes_cube(&mesh);
    assert_float_equal(shapes_signed_volume(&mesh), 8.0, 1e-6);
    mesh_data_free(&mesh);
}

static void test_shapes_sphere_outward(void **state)
{
    mesh_data mesh;
    double center[3] = {0, 0, 0};
    shapes_sphere(center, 1.0, 32, 32, &mesh);
    assert_int_equal(mesh.triangle_count, 1984);
    double volume = shapes_signed_volume(&mesh);
    assert_true(volume > 0.97 * 4.0 / 3.0 * M_PI && volume < 4.0 / 3.0 * M_PI);
    mesh_data_free(&mesh);
}

static void test_shapes_disk_fan(void **state)
{
    mesh_data mesh;
    shapes_disk(64, &mesh);
    assert_int_equal(mesh.vertex_count, 65);
    assert_int_equal(mesh.triangle_count, 64);
    mesh_data_free(&mesh);
}

/* ---------------------------------------------------------------------------------------- */
/* Transforms through the XML: a sensor's to_world, read back from camera_info               */

typedef struct transform_case {
    const char *name;
    const char *steps;   /* the children of <transform name="to_world"> */
    double expected[16]; /* row-major */
} transform_case;

static const transform_case transform_cases[] = {
    /* R_z(90) · T(1,0,0) */
    {"transform_translate_then_rotate",
     "<translate x=\"1\" y=\"0\" z=\"0\"/><rotate z=\"1\" angle=\"90\"/>",
     {0, -1, 0, 0, /**/ 1, 0, 0, 1, /**/ 0, 0, 1, 0, /**/ 0, 0, 0, 1}},
    {"transform_scale_uniform", "<scale value=\"2\"/>",
     {2, 0, 0, 0, /**/ 0, 2, 0, 0, /**/ 0, 0, 2, 0, /**/ 0, 0, 0, 1}},
    {"transform_scale_axes", "<scale x=\"2\" y=\"3\"/>",
     {2, 0, 0, 0, /**/ 0, 3, 0, 0, /**/ 0, 0, 1, 0, /**/ 0, 0, 0, 1}},
    {"transform_scale_values", "<scale value=\"2, 3, 4\"/>",
     {2, 0, 0, 0, /**/ 0, 3, 0, 0, /**/ 0, 0, 4, 0, /**/ 0, 0, 0, 1}},
    {"transform_lookat", "<lookat origin=\"1, 2, 3\" target=\"1, 2, 4\" up=\"0, 1, 0\"/>",
     {1, 0, 0, 1, /**/ 0, 1, 0, 2, /**/ 0, 0, 1, 3, /**/ 0, 0, 0, 1}},
    /* Looking along +x with z up: camera x (image left) is +y. */
    {"transform_lookat_along_x", "<lookat origin=\"0,0,0\" target=\"5,0,0\" up=\"0,0,1\"/>",
     {0, 0, 1, 0, /**/ 1, 0, 0, 0, /**/ 0, 1, 0, 0, /**/ 0, 0, 0, 1}},
    {"transform_matrix_4x4", "<matrix value=\"1 0 0 4  0 0 -1 5  0 1 0 6  0 0 0 1\"/>",
     {1, 0, 0, 4, /**/ 0, 0, -1, 5, /**/ 0, 1, 0, 6, /**/ 0, 0, 0, 1}},
    {"transform_matrix_3x3", "<matrix value=\"0,-1,0, 1,0,0, 0,0,1\"/>",
     {0, -1, 0, 0, /**/ 1, 0, 0, 0, /**/ 0, 0, 1, 0, /**/ 0, 0, 0, 1}},
    /* R_x(90) · T(1,2,3) · S(2) */
    {"transform_sequence",
     "<scale value=\"2\"/><translate value=\"1 2 3\"/><rotate value=\"1, 0, 0\" angle=\"90\"/>",
     {2, 0, 0, 1, /**/ 0, 0, -2, -3, /**/ 0, 2, 0, 2, /**/ 0, 0, 0, 1}},
};

static void run_transform_case(void **state)
{
    const transform_case *c = *state;
    char body[1024];
    snprintf(body, sizeof body,
             "  <sensor type=\"perspective\">\n"
             "    <float name=\"fov\" value=\"45\"/>\n"
             "    <transform name=\"to_world\">%s</transform>\n"
             "  </sensor>\n",
             c->steps);
    scene *s = load_scene("3.0.0", body);
    assert_matrix(s->camera_info.to_world, c->expected);
    scene_free(s);
}

static void test_transform_old_dialect(void **state)
{
    scene *s = load_scene("0.5.0", "  <sensor type=\"perspective\">\n"
                                   "    <float name=\"fov\" value=\"45\"/>\n"
                                   "    <transform name=\"toWorld\"><translate x=\"7\"/>"
                                   "</transform>\n"
                                   "  </sensor>\n");
    assert_float_equal(s->camera_info.to_world[3], 7.0f, EPS);
    assert_vec3(s->camera.origin, 7, 0, 0, EPS);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Camera                                                                                   */

/* A 200x100 camera at (1,2,3) looking along +z with fov 90 measured along `axis`. */
static scene *load_camera(const char *axis)
{
    char body[1024];
    snprintf(body, sizeof body,
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
             "  </sensor>\n",
             axis);
    return load_scene("3.0.0", body);
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

typedef struct fov_axis_case {
    const char *name;
    const char *axis;
    double tan_half_x, tan_half_y; /* of the 200x100 camera with fov 90 (tan 45° = 1) */
} fov_axis_case;

static const fov_axis_case fov_axis_cases[] = {
    {"camera_fov_axis_y", "y", 2.0, 1.0},
    {"camera_fov_axis_smaller", "smaller", 2.0, 1.0}, /* 200x100: the smaller axis is y */
    {"camera_fov_axis_larger", "larger", 1.0, 0.5},
    {"camera_fov_axis_diagonal", "diagonal", 200.0 / 223.60679774997897,
     100.0 / 223.60679774997897}, /* the diagonal is sqrt(200² + 100²) */
};

static void run_fov_axis_case(void **state)
{
    const fov_axis_case *c = *state;
    scene *s = load_camera(c->axis);
    assert_float_equal(s->camera.tan_half_x, c->tan_half_x, EPS);
    assert_float_equal(s->camera.tan_half_y, c->tan_half_y, EPS);
    assert_string_equal(s->camera_info.fov_axis, c->axis);
    scene_free(s);
}

static void test_camera_old_dialect_defaults(void **state)
{
    /* fovAxis, default film 768x576, thinlens as pinhole. */
    scene *s = load_scene("0.6.0", "  <sensor type=\"thinlens\">\n"
                                   "    <float name=\"fov\" value=\"60\"/>\n"
                                   "    <string name=\"fovAxis\" value=\"y\"/>\n"
                                   "    <float name=\"apertureRadius\" value=\"0.1\"/>\n"
                                   "  </sensor>\n");
    assert_int_equal(s->camera.width, 768);
    assert_int_equal(s->camera.height, 576);
    assert_float_equal(s->camera.tan_half_y, tan(M_PI / 6), EPS);
    assert_float_equal(s->camera.tan_half_x, tan(M_PI / 6) * 768 / 576, EPS);
    assert_vec3(s->camera.right, -1, 0, 0, EPS);
    scene_free(s);
}

static void test_no_sensor_warns(void **state)
{
    char *log;
    scene *s = load_capturing_stderr(write_scene("3.0.0", "  <shape type=\"cube\"/>\n"), &log);
    assert_non_null(s);
    assert_int_equal(s->has_camera, 0);
    assert_non_null(strstr(log, "no <sensor>"));
    free(log);
    scene_free(s);
}

/* A property no reader asks for, a property without a name and an element where nothing reads
 * it each warn with file and line; the same warning for many shapes comes once with a count;
 * a valid Mitsuba property idmr has no use for passes in silence; the scene still loads. */
static void test_unread_properties_warn(void **state)
{
    char *log;
    scene *s = load_capturing_stderr(
        write_scene("3.0.0",
                    "  <emitter type=\"point\">\n"                           /* line 2 */
                    "    <rgb name=\"Radiance2\" value=\"1\"/>\n"            /* 3 */
                    "    <float value=\"3\"/>\n"                             /* 4 */
                    "    <shape type=\"cube\"/>\n"                           /* 5 */
                    "  </emitter>\n"
                    "  <bsdf type=\"roughplastic\" id=\"p\">\n"              /* 7 */
                    "    <boolean name=\"nonlinear\" value=\"true\"/>\n"     /* 8 */
                    "  </bsdf>\n"
                    "  <shape type=\"cube\"><float name=\"raduis\" value=\"1\"/></shape>\n"
                    "  <shape type=\"cube\"><float name=\"raduis\" value=\"1\"/></shape>\n"
                    "  <shape type=\"cube\"><float name=\"raduis\" value=\"1\"/>"
                    "<ref id=\"p\"/></shape>\n"),
        &log);
    assert_non_null(s);
    const char *expected[] = {
        "scene.xml:3: <rgb name=\"Radiance2\">: ignored: not a property idmr reads in <emitter "
        "type=\"point\">",
        "scene.xml:4: <float>: ignored: a property needs a name attribute",
        "scene.xml:5: <shape type=\"cube\">: ignored: idmr reads no such element in <emitter "
        "type=\"point\">",
        "scene.xml:10: <float name=\"raduis\">: ignored: not a property idmr reads in <shape "
        "type=\"cube\">",
        "scene.xml:10: <float name=\"raduis\"> in <shape type=\"cube\">: the warning came 3 "
        "times in all",
    };
    for (size_t i = 0; i < sizeof expected / sizeof *expected; i++)
        if (!strstr(log, expected[i]))
            fail_msg("no '%s' in:\n%s", expected[i], log);
    if (strstr(log, "nonlinear") || strstr(log, "scene.xml:11:") || strstr(log, "scene.xml:12:"))
        fail_msg("a valid property or a repeat was warned about:\n%s", log);
    free(log);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Shapes                                                                                   */

static void test_shape_rectangle(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"rectangle\">\n"
                                   "    <transform name=\"to_world\"><scale value=\"2\"/>"
                                   "<translate z=\"5\"/></transform>\n"
                                   "  </shape>\n");
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

/* An OBJ whose normals (vn) oppose its winding: the winding (0,0,0) (0,1,0) (1,0,0) has the
 * normal (0,1,0) x (1,0,0) = (0,0,-1), against vn +z. Returns the z of the loaded triangle's
 * normal with face_normals set as given. */
static float load_flipped_obj_normal_z(const char *face_normals)
{
    char body[512];
    write_file("flipped.obj", "v 0 0 0\nv 0 1 0\nv 1 0 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    snprintf(body, sizeof body,
             "  <shape type=\"obj\">\n"
             "    <string name=\"filename\" value=\"flipped.obj\"/>\n"
             "    <boolean name=\"face_normals\" value=\"%s\"/>\n"
             "  </shape>\n",
             face_normals);
    scene *s = load_scene("3.0.0", body);
    const scene_mesh *m = &s->meshes[0];
    const float *a = &m->positions[3 * m->indices[0]], *b = &m->positions[3 * m->indices[1]],
                *c = &m->positions[3 * m->indices[2]];
    float nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    scene_free(s);
    return nz;
}

/* The front side comes from the normals, as in Mitsuba, so the triangle is turned to face +z
 * like the normals. */
static void test_obj_oriented_by_its_normals(void **state)
{
    assert_true(load_flipped_obj_normal_z("false") > 0);
}

/* With face_normals the winding rules and stays as written. */
static void test_obj_face_normals_keep_winding(void **state)
{
    assert_true(load_flipped_obj_normal_z("true") < 0);
}

/* A mirroring to_world turns a built-in shape's normal (Mitsuba transforms it as a normal), so
 * the winding must flip with it: the rectangle mirrored in z faces -z. */
static void test_shape_mirrored_builtin(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"rectangle\">\n"
                                   "    <transform name=\"to_world\"><scale z=\"-1\"/>"
                                   "</transform>\n"
                                   "  </shape>\n"
                                   "  <shape type=\"cube\">\n"
                                   "    <transform name=\"to_world\"><scale x=\"-2\"/>"
                                   "</transform>\n"
                                   "  </shape>\n");
    double n[3];
    triangle_normal(&s->meshes[0], 0, n);
    assert_true(n[2] < 0.0);
    assert_float_equal(mesh_volume(&s->meshes[1]), 16.0, 1e-3); /* still outward */
    scene_free(s);
}

/* Every shading normal of m points away from `center` (an outward sphere or tetrahedron). */
static void assert_normals_outward(const scene_mesh *m, const double center[3])
{
    assert_non_null(m->normals);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double out = 0;
        for (int k = 0; k < 3; k++)
            out += (m->positions[3 * v + k] - center[k]) * m->normals[3 * v + k];
        if (!(out > 0))
            fail_msg("mesh '%s' vertex %u: the normal (%g, %g, %g) points inward", m->name, v,
                     m->normals[3 * v], m->normals[3 * v + 1], m->normals[3 * v + 2]);
    }
}

/* A mirrored sphere keeps its outside out: its winding (volume) and its shading normals, which
 * are transformed by the inverse transpose (the cofactor alone would turn them in). */
static void test_shape_mirrored_sphere_normals(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"sphere\">\n"
                                   "    <transform name=\"to_world\"><scale x=\"-1\"/>"
                                   "<translate x=\"5\"/></transform>\n"
                                   "  </shape>\n");
    static const double center[3] = {5, 0, 0};
    assert_true(mesh_volume(&s->meshes[0]) > 0.97 * 4.0 / 3.0 * M_PI);
    assert_normals_outward(&s->meshes[0], center);
    scene_free(s);
}

static void test_shape_cube(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"cube\" id=\"box\">\n"
                                   "    <transform name=\"to_world\"><scale x=\"1\" y=\"2\" "
                                   "z=\"3\"/><translate x=\"10\"/></transform>\n"
                                   "  </shape>\n");
    const scene_mesh *cube = &s->meshes[0];
    float lo[3], hi[3];
    assert_string_equal(cube->name, "box");
    assert_int_equal(cube->vertex_count, 8);
    assert_int_equal(cube->triangle_count, 12);
    mesh_bbox(cube, lo, hi);
    assert_vec3(lo, 9, -2, -3, EPS);
    assert_vec3(hi, 11, 2, 3, EPS);
    assert_float_equal(mesh_volume(cube), 2.0 * 4.0 * 6.0, 1e-3);
    scene_free(s);
}

static void test_shape_sphere(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"sphere\">\n"
                                   "    <point name=\"center\" x=\"1\" y=\"2\" z=\"3\"/>\n"
                                   "    <float name=\"radius\" value=\"2\"/>\n"
                                   "  </shape>\n");
    const scene_mesh *sphere = &s->meshes[0];
    float lo[3], hi[3];
    assert_string_equal(sphere->name, "sphere");
    assert_int_equal(sphere->triangle_count, 1984);
    mesh_bbox(sphere, lo, hi);
    assert_vec3(lo, -1, 0, 1, 0.01f); /* the poles lie on z; x/y extremes at vertices */
    assert_vec3(hi, 3, 4, 5, 0.01f);
    assert_true(mesh_volume(sphere) > 0.97 * 4.0 / 3.0 * M_PI * 8.0);
    scene_free(s);
}

static void test_shape_disk_flipped(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"disk\">\n"
                                   "    <boolean name=\"flip_normals\" value=\"true\"/>\n"
                                   "  </shape>\n");
    const scene_mesh *disk = &s->meshes[0];
    double n[3];
    assert_int_equal(disk->vertex_count, 65);
    assert_int_equal(disk->triangle_count, 64);
    triangle_normal(disk, 0, n);
    assert_true(n[2] < 0.0); /* flipped */
    scene_free(s);
}

static void test_shape_obj_file(void **state)
{
    make_subdir(temp_dir, "models");
    write_file("models/quad.obj", quad_obj);
    scene *s = load_scene("0.5.0", "  <shape type=\"obj\">\n"
                                   "    <string name=\"filename\" value=\"models/quad.obj\"/>\n"
                                   "    <boolean name=\"faceNormals\" value=\"true\"/>\n"
                                   "    <transform name=\"toWorld\"><translate x=\"1\" y=\"2\" "
                                   "z=\"3\"/></transform>\n"
                                   "  </shape>\n"
                                   "  <shape type=\"obj\">\n"
                                   "    <string name=\"filename\" value=\"models/quad.obj\"/>\n"
                                   "  </shape>\n");
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
    scene *s = load_scene("3.0.0", "  <emitter type=\"area\" id=\"glow\">\n"
                                   "    <rgb name=\"radiance\" value=\"4, 5, 6\"/>\n"
                                   "  </emitter>\n"
                                   "  <shape type=\"cube\"/>\n"
                                   "  <shape type=\"rectangle\">\n"
                                   "    <emitter type=\"area\"><rgb name=\"radiance\" "
                                   "value=\"1, 2, 3\"/></emitter>\n"
                                   "  </shape>\n"
                                   "  <shape type=\"disk\"><ref id=\"glow\"/></shape>\n");
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
/* Materials: one rectangle (id "r") carrying an inline bsdf                                */

/* The feature bit that a material kind turns on. */
static const unsigned int material_feature[] = {
    [IDMR_MATERIAL_DIFFUSE] = IDMR_FEATURE_DIFFUSE,
    [IDMR_MATERIAL_GLOSSY] = IDMR_FEATURE_GLOSSY,
    [IDMR_MATERIAL_MIRROR] = IDMR_FEATURE_MIRROR,
    [IDMR_MATERIAL_DIELECTRIC] = IDMR_FEATURE_DIELECTRIC,
};

/* A bsdf and the whole material it must become (colours within colour_eps, or EPS when 0;
 * indices of refraction and roughness within 1e-6). */
typedef struct bsdf_case {
    const char *name, *version, *bsdf;
    const char *type; /* material_info.bsdf_type */
    unsigned int kind, flags;
    float reflectance[3], specular[3];
    float int_ior, ext_ior, roughness;
    float colour_eps;
} bsdf_case;

#define IOR_AIR 1.000277f

static const bsdf_case bsdf_cases[] = {
    {"bsdf_diffuse_rgb", "3.0.0",
     "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.1, 0.2, 0.3\"/></bsdf>",
     "diffuse", IDMR_MATERIAL_DIFFUSE, 0, {0.1f, 0.2f, 0.3f}, {0, 0, 0}, 1, 1, 0, 0},
    {"bsdf_diffuse_srgb", "3.0.0",
     "<bsdf type=\"diffuse\"><srgb name=\"reflectance\" value=\"0.5, 1, 0\"/></bsdf>", "diffuse",
     IDMR_MATERIAL_DIFFUSE, 0, {0.214041f, 1, 0}, {0, 0, 0}, 1, 1, 0, 0},
    {"bsdf_diffuse_spectrum_grey", "3.0.0",
     "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.25\"/></bsdf>", "diffuse",
     IDMR_MATERIAL_DIFFUSE, 0, {0.25f, 0.25f, 0.25f}, {0, 0, 0}, 1, 1, 0, 0},
    {"bsdf_diffuse_spectrum_flat", "3.0.0",
     "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" "
     "value=\"400:1, 500:1, 600:1, 700:1\"/></bsdf>",
     "diffuse", IDMR_MATERIAL_DIFFUSE, 0, {1, 1, 1}, {0, 0, 0}, 1, 1, 0, 6e-3f},
    /* Mitsuba's defaults: BK7 inside, air outside. */
    {"bsdf_dielectric_default", "3.0.0", "<bsdf type=\"dielectric\"/>", "dielectric",
     IDMR_MATERIAL_DIELECTRIC, 0, {0, 0, 0}, {1, 1, 1}, 1.5046f, IOR_AIR, 0, 0},
    {"bsdf_thindielectric_named_iors", "0.5.0",
     "<bsdf type=\"thindielectric\"><string name=\"intIOR\" value=\"water\"/>"
     "<string name=\"extIOR\" value=\"air\"/></bsdf>",
     "thindielectric", IDMR_MATERIAL_DIELECTRIC, IDMR_MATERIAL_THIN, {0, 0, 0}, {1, 1, 1}, 1.333f,
     IOR_AIR, 0, 0},
    {"bsdf_dielectric_named_and_numeric_ior", "3.0.0",
     "<bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"diamond\"/>"
     "<float name=\"ext_ior\" value=\"1.33\"/></bsdf>",
     "dielectric", IDMR_MATERIAL_DIELECTRIC, 0, {0, 0, 0}, {1, 1, 1}, 2.419f, 1.33f, 0, 0},
    /* 3.x default material: none, a perfect mirror. */
    {"bsdf_conductor_default_mirror", "3.0.0", "<bsdf type=\"conductor\"/>", "conductor",
     IDMR_MATERIAL_MIRROR, 0, {0, 0, 0}, {1, 1, 1}, 1, 1, 0, 0},
    /* Gold's tabulated normal-incidence reflectance: red above green above blue. */
    {"bsdf_conductor_gold", "3.0.0",
     "<bsdf type=\"conductor\"><string name=\"material\" value=\"Au\"/></bsdf>", "conductor",
     IDMR_MATERIAL_MIRROR, 0, {0, 0, 0}, {1.000f, 0.782f, 0.344f}, 1, 1, 0, 0},
    /* eta = 2, k = 0 → F0 = 1/9; tinted by specular_reflectance 0.5. */
    {"bsdf_roughconductor_eta_k", "0.5.0",
     "<bsdf type=\"roughconductor\"><rgb name=\"eta\" value=\"2, 2, 2\"/>"
     "<rgb name=\"k\" value=\"0, 0, 0\"/><float name=\"extEta\" value=\"1\"/>"
     "<rgb name=\"specularReflectance\" value=\"0.5\"/><float name=\"alpha\" value=\"0.3\"/>"
     "<string name=\"distribution\" value=\"ggx\"/></bsdf>",
     "roughconductor", IDMR_MATERIAL_GLOSSY, 0, {0, 0, 0}, {0.5f / 9, 0.5f / 9, 0.5f / 9}, 1, 1,
     0.3f, 0},
    {"bsdf_roughconductor_default_alpha", "3.0.0", "<bsdf type=\"roughconductor\"/>",
     "roughconductor", IDMR_MATERIAL_GLOSSY, 0, {0, 0, 0}, {1, 1, 1}, 1, 1, 0.1f, 0},
    {"bsdf_plastic_old_dialect", "0.5.0",
     "<bsdf type=\"plastic\"><rgb name=\"diffuseReflectance\" value=\"0.2, 0.3, 0.4\"/>"
     "<float name=\"intIOR\" value=\"1.6\"/></bsdf>",
     "plastic", IDMR_MATERIAL_GLOSSY, 0, {0.2f, 0.3f, 0.4f}, {1, 1, 1}, 1.6f, IOR_AIR, 0, 0},
    /* int_ior defaults to polypropylene's 1.49. */
    {"bsdf_roughplastic", "3.0.0",
     "<bsdf type=\"roughplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.7\"/>"
     "<float name=\"alpha\" value=\"0.25\"/></bsdf>",
     "roughplastic", IDMR_MATERIAL_GLOSSY, 0, {0.7f, 0.7f, 0.7f}, {1, 1, 1}, 1.49f, IOR_AIR, 0.25f,
     0},
};

/* A scene with one rectangle (id "r") carrying `bsdf` (inline XML); returns its material. */
static idmr_material load_bsdf(const char *version, const char *bsdf, scene **out)
{
    char body[4096];
    snprintf(body, sizeof body, "  <shape type=\"rectangle\" id=\"r\">%s</shape>\n", bsdf);
    scene *s = load_scene(version, body);
    assert_int_equal(s->mesh_count, 1);
    *out = s;
    return s->materials[s->meshes[0].material];
}

static void run_bsdf_case(void **state)
{
    const bsdf_case *c = *state;
    float colour_eps = c->colour_eps > 0 ? c->colour_eps : EPS;
    scene *s;
    idmr_material m = load_bsdf(c->version, c->bsdf, &s);
    assert_int_equal(m.kind, c->kind);
    assert_int_equal(m.flags, c->flags);
    assert_int_equal(m.texture, -1);
    assert_float3(m.reflectance, c->reflectance, colour_eps);
    assert_float3(m.specular, c->specular, colour_eps);
    assert_float_equal(m.int_ior, c->int_ior, 1e-6f);
    assert_float_equal(m.ext_ior, c->ext_ior, 1e-6f);
    assert_float_equal(m.roughness, c->roughness, 1e-6f);
    assert_string_equal(s->material_info[s->meshes[0].material].name, "r/bsdf");
    assert_string_equal(s->material_info[s->meshes[0].material].bsdf_type, c->type);
    assert_true(s->features & material_feature[c->kind]);
    scene_free(s);
}

/* A spectrum rising towards red integrates to a red colour. */
static void test_bsdf_diffuse_red_spectrum(void **state)
{
    scene *s;
    idmr_material m = load_bsdf("3.0.0",
                                "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" "
                                "value=\"400:0.05, 560:0.05, 600:0.6, 700:0.65\"/></bsdf>",
                                &s);
    assert_true(m.reflectance[0] > m.reflectance[1] && m.reflectance[0] > m.reflectance[2]);
    scene_free(s);
}

/* One spectrum, two meanings (as in Mitsuba 3): inside an <emitter> an emission, in a <bsdf> a
 * reflectance; a grey spectrum in an emitter is that multiple of equal-energy white. */
static void test_spectrum_use_by_element(void **state)
{
    static const double lambda[2] = {400, 700}, value[2] = {0.8, 0.4}, grey = 3;
    float emission[3], reflectance[3], grey_emission[3];
    spectrum_to_rgb(lambda, value, 2, SPECTRUM_EMISSION, emission);
    spectrum_to_rgb(lambda, value, 2, SPECTRUM_REFLECTANCE, reflectance);
    spectrum_to_rgb(NULL, &grey, 1, SPECTRUM_EMISSION, grey_emission);
    scene *s = load_scene("3.0.0", "  <shape type=\"rectangle\">\n"
                                   "    <bsdf type=\"diffuse\">\n"
                                   "      <spectrum name=\"reflectance\" value=\"400:0.8, 700:0.4\"/>\n"
                                   "    </bsdf>\n"
                                   "    <emitter type=\"area\">\n"
                                   "      <spectrum name=\"radiance\" value=\"400:0.8, 700:0.4\"/>\n"
                                   "    </emitter>\n"
                                   "  </shape>\n"
                                   "  <emitter type=\"directional\">\n"
                                   "    <spectrum name=\"irradiance\" value=\"3\"/>\n"
                                   "  </emitter>\n");
    assert_int_equal(s->light_count, 2);
    assert_float3(s->materials[s->meshes[0].material].reflectance, reflectance, 1e-6f);
    for (size_t i = 0; i < s->light_count; i++)
        assert_float3(s->lights[i].emission,
                      s->lights[i].kind == IDMR_LIGHT_AREA ? emission : grey_emission, 1e-6f);
    assert_true(emission[0] > 1.1f * reflectance[0]); /* no white balance on emission */
    scene_free(s);
}

static void test_bsdf_wrappers_and_refs(void **state)
{
    scene *s = load_scene(
        "3.0.0", "  <bsdf type=\"twosided\" id=\"wall\">\n"
                 "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.3\"/></bsdf>\n"
                 "  </bsdf>\n"
                 "  <bsdf type=\"mask\" id=\"leaf\">\n"
                 "    <float name=\"opacity\" value=\"0.5\"/>\n"
                 "    <ref id=\"wall\"/>\n"
                 "  </bsdf>\n"
                 "  <bsdf type=\"plastic\" id=\"unused\"/>\n"
                 "  <shape type=\"cube\"><ref id=\"wall\"/></shape>\n"
                 "  <shape type=\"cube\"><ref id=\"wall\"/></shape>\n"
                 "  <shape type=\"cube\"><ref id=\"leaf\"/></shape>\n");
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
/* Emitters                                                                                 */

/* The feature bit that a light kind turns on. */
static const unsigned int light_feature[] = {
    [IDMR_LIGHT_AREA] = IDMR_FEATURE_AREA,
    [IDMR_LIGHT_POINT] = IDMR_FEATURE_POINT,
    [IDMR_LIGHT_SPOT] = IDMR_FEATURE_SPOT,
    [IDMR_LIGHT_DIRECTIONAL] = IDMR_FEATURE_DIRECTIONAL,
    [IDMR_LIGHT_ENVIRONMENT] = IDMR_FEATURE_ENVIRONMENT,
};

/* One emitter and the light it must become (a field a kind does not use is 0). */
typedef struct emitter_case {
    const char *name, *version, *emitter;
    unsigned int kind;
    float position[3], direction[3], emission[3];
    double cutoff_degrees, falloff_degrees; /* a spot's; 90 (cos 0) for the others */
} emitter_case;

static const emitter_case emitter_cases[] = {
    {"emitter_point_position", "3.0.0",
     "<emitter type=\"point\"><point name=\"position\" value=\"1, 2, 3\"/>"
     "<rgb name=\"intensity\" value=\"10\"/></emitter>",
     IDMR_LIGHT_POINT, {1, 2, 3}, {0, 0, 0}, {10, 10, 10}, 90, 90},
    /* No position: the origin moved by to_world; the intensity defaults to 1. */
    {"emitter_point_to_world", "3.0.0",
     "<emitter type=\"point\"><transform name=\"to_world\"><translate x=\"4\" y=\"5\" "
     "z=\"6\"/></transform></emitter>",
     IDMR_LIGHT_POINT, {4, 5, 6}, {0, 0, 0}, {1, 1, 1}, 90, 90},
    /* The beam width defaults to 3/4 of the cutoff angle. */
    {"emitter_spot_lookat", "3.0.0",
     "<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0,0,0\" "
     "target=\"0,-2,0\" up=\"0,0,1\"/></transform><float name=\"cutoff_angle\" "
     "value=\"40\"/></emitter>",
     IDMR_LIGHT_SPOT, {0, 0, 0}, {0, -1, 0}, {1, 1, 1}, 40, 30},
    {"emitter_directional_vector", "3.0.0",
     "<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, -2\"/>"
     "<rgb name=\"irradiance\" value=\"3\"/></emitter>",
     IDMR_LIGHT_DIRECTIONAL, {0, 0, 0}, {0, 0, -1}, {3, 3, 3}, 90, 90},
    /* R_x(-90) takes +z to +y. */
    {"emitter_spot_old_dialect", "0.6.0",
     "<emitter type=\"spot\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/>"
     "<translate y=\"3\"/></transform><float name=\"cutoffAngle\" value=\"30\"/>"
     "<float name=\"beamWidth\" value=\"10\"/></emitter>",
     IDMR_LIGHT_SPOT, {0, 3, 0}, {0, 1, 0}, {1, 1, 1}, 30, 10},
    /* R_y(90) takes +z to +x. */
    {"emitter_directional_old_dialect", "0.6.0",
     "<emitter type=\"directional\"><transform name=\"toWorld\"><rotate y=\"1\" "
     "angle=\"90\"/></transform></emitter>",
     IDMR_LIGHT_DIRECTIONAL, {0, 0, 0}, {1, 0, 0}, {1, 1, 1}, 90, 90},
};

static void run_emitter_case(void **state)
{
    const emitter_case *c = *state;
    char body[2048];
    snprintf(body, sizeof body, "  %s\n", c->emitter);
    scene *s = load_scene(c->version, body);
    assert_int_equal(s->light_count, 1);
    const idmr_light *l = &s->lights[0];
    assert_int_equal(l->kind, c->kind);
    assert_float3(l->position, c->position, EPS);
    assert_float3(l->direction, c->direction, EPS);
    assert_float3(l->emission, c->emission, EPS);
    assert_float_equal(l->cos_cutoff, cos(c->cutoff_degrees * M_PI / 180), EPS);
    assert_float_equal(l->cos_falloff_start, cos(c->falloff_degrees * M_PI / 180), EPS);
    assert_true(s->features & light_feature[c->kind]);
    scene_free(s);
}

/* An envmap becomes the scene's environment map, times its scale, in its frame: a white 8-bit
 * 4 x 2 map (sRGB 255 = linear 1) with scale 2 has radiance 2 everywhere (the light's mean),
 * the to_world rotation and its inverse are kept, and the luminance integral is 4π × 2. */
static void test_envmap_is_the_environment(void **state)
{
    unsigned char white[4 * 2 * 3];
    memset(white, 255, sizeof white);
    assert_int_equal(image_write_rgb8(path_in(temp_dir, "sky.png"), 4, 2, white), 0);
    scene *s = load_scene("3.0.0", "  <shape type=\"cube\"/>\n"
                                   "  <emitter type=\"envmap\">\n"
                                   "    <string name=\"filename\" value=\"sky.png\"/>\n"
                                   "    <float name=\"scale\" value=\"2\"/>\n"
                                   "    <transform name=\"to_world\">\n"
                                   "      <rotate y=\"1\" angle=\"90\"/>\n"
                                   "    </transform>\n"
                                   "  </emitter>\n");
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    for (int c = 0; c < 3; c++)
        assert_float_equal(s->lights[0].emission[c], 2.0f, 1e-4f);
    assert_true(s->features & IDMR_FEATURE_ENVIRONMENT);
    const scene_environment *e = &s->environment;
    assert_int_equal(e->width, 4);
    assert_int_equal(e->height, 2);
    assert_float_equal(e->rgb[0], 2.0f, 1e-4f);
    assert_float_equal(e->luminance_integral, 4 * M_PI * 2.0, 1e-3);
    /* R_y(90°) takes +z to +x: row 0 is (0, 0, 1); its inverse is its transpose. */
    const double expected[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
    for (int k = 0; k < 9; k++) {
        assert_float_equal(e->to_world[k], expected[k], 1e-9);
        assert_float_equal(e->to_map[k], expected[3 * (k % 3) + k / 3], 1e-9);
    }
    scene_free(s);
}

static void test_constant_environment(void **state)
{
    scene *s = load_scene("3.0.0", "  <shape type=\"cube\"/>\n"
                                   "  <emitter type=\"constant\">\n"
                                   "    <rgb name=\"radiance\" value=\"0.5, 1, 2\"/>\n"
                                   "  </emitter>\n");
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    assert_float_equal(s->lights[0].emission[2], 2.0f, 1e-6f);
    assert_true(s->lights[0].power > 0);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Parameters and includes                                                                  */

static void test_default_substitution(void **state)
{
    scene *s = load_scene("3.0.0", "  <default name=\"res\" value=\"64\"/>\n"
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
                                   "<rgb name=\"reflectance\" value=\"$grey, 0.5, $grey\"/>"
                                   "</bsdf></shape>\n");
    assert_int_equal(s->camera.width, 64);
    assert_int_equal(s->camera.height, 64);
    assert_float_equal(s->camera_info.fov_degrees, 30.0f, EPS);
    assert_vec3(s->materials[0].reflectance, 0.25, 0.5, 0.25, EPS);
    scene_free(s);
}

static void test_include(void **state)
{
    make_subdir(temp_dir, "fragments");
    write_file("fragments/materials.xml",
               "<scene version=\"3.0.0\">\n"
               "  <bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.9, 0, 0\"/>"
               "</bsdf>\n"
               "</scene>\n");
    scene *s = load_scene("3.0.0", "  <include filename=\"fragments/materials.xml\"/>\n"
                                   "  <shape type=\"cube\"><ref id=\"red\"/></shape>\n");
    assert_vec3(s->materials[s->meshes[0].material].reflectance, 0.9, 0, 0, EPS);
    scene_free(s);
}

/* Fragments that include the next one 4 times, 12 levels deep (4^12 reads, which used to run
 * without end, memory growing): an error once MITSUBA_MAX_INCLUDES are read, naming the file
 * and line of the include that passed it. Every level's fragment holds a cube, so the meshes
 * read up to there (named cube, cube.2, ...) stress the unique naming too. */
static void test_include_fan_out_is_bounded(void **state)
{
    char name[32], text[512];
    for (int level = 0; level < 12; level++) {
        snprintf(name, sizeof name, "fan%d.xml", level);
        snprintf(text, sizeof text,
                 "<scene version=\"3.0.0\">\n  <shape type=\"cube\"/>\n"
                 "  <include filename=\"fan%d.xml\"/>\n  <include filename=\"fan%d.xml\"/>\n"
                 "  <include filename=\"fan%d.xml\"/>\n  <include filename=\"fan%d.xml\"/>\n"
                 "</scene>\n",
                 level + 1, level + 1, level + 1, level + 1);
        write_file(name, text);
    }
    write_file("fan12.xml", "<scene version=\"3.0.0\"/>\n");
    error_clear();
    scene *s = mitsuba_load(write_scene("3.0.0", "  <include filename=\"fan0.xml\"/>\n"));
    assert_null(s);
    if (!strstr(error_message(), "more than 4096 includes") || !strstr(error_message(), "fan") ||
        !strstr(error_message(), "<include>"))
        fail_msg("message '%s' lacks the limit, the file or the element", error_message());
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* ---------------------------------------------------------------------------------------- */
/* Instancing: shapegroup and instance, each group shape held once                          */

/* A tetrahedron at the origin, wound outward (volume 1/6). */
static const char *tet_obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                             "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/* A shapegroup of two shapes (the tetrahedron moved to x + 0.5, a rectangle shrunk to half and
 * lifted to z = 2, facing +z) placed three times: moved by x + 10, scaled by 2 and moved by
 * y + 10, mirrored in z. The group's shapes start on lines 3 and 7, the instances on 11, 15
 * and 19. */
static const char *instanced_body =
    "  <shape type=\"shapegroup\" id=\"G\">\n"
    "    <shape type=\"obj\">\n"
    "      <string name=\"filename\" value=\"tet.obj\"/>\n"
    "      <transform name=\"to_world\"><translate x=\"0.5\"/></transform>\n"
    "    </shape>\n"
    "    <shape type=\"rectangle\">\n"
    "      <transform name=\"to_world\"><scale value=\"0.5\"/><translate z=\"2\"/>"
    "</transform>\n"
    "    </shape>\n"
    "  </shape>\n"
    "  <shape type=\"instance\" id=\"a\">\n"
    "    <ref id=\"G\"/>\n"
    "    <transform name=\"to_world\"><translate x=\"10\"/></transform>\n"
    "  </shape>\n"
    "  <shape type=\"instance\">\n"
    "    <ref name=\"shapegroup\" id=\"G\"/>\n"
    "    <transform name=\"to_world\"><scale value=\"2\"/><translate y=\"10\"/></transform>\n"
    "  </shape>\n"
    "  <shape type=\"instance\" id=\"m\">\n"
    "    <ref id=\"G\"/>\n"
    "    <transform name=\"to_world\"><scale z=\"-1\"/></transform>\n"
    "  </shape>\n";

/* Mesh m has a vertex at (x, y, z). */
static void assert_has_vertex(const scene_mesh *m, double x, double y, double z)
{
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (fabs(m->positions[3 * v] - x) < 1e-5 && fabs(m->positions[3 * v + 1] - y) < 1e-5 &&
            fabs(m->positions[3 * v + 2] - z) < 1e-5)
            return;
    fail_msg("mesh '%s' has no vertex at (%g, %g, %g)", m->name, x, y, z);
}

/* A copy of the tetrahedron: its four corners at offset + scale * (tet moved to x + 0.5), in
 * the mirror when z_sign is -1, still wound outward with its normals pointing out. */
static void check_tet_copy(const scene_mesh *m, const double offset[3], double scale,
                           double z_sign)
{
    static const double corners[4][3] = {{0.5, 0, 0}, {1.5, 0, 0}, {0.5, 1, 0}, {0.5, 0, 1}};
    double center[3] = {0, 0, 0};
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangle_count, 4);
    for (int c = 0; c < 4; c++) {
        double p[3] = {offset[0] + scale * corners[c][0], offset[1] + scale * corners[c][1],
                       offset[2] + scale * z_sign * corners[c][2]};
        assert_has_vertex(m, p[0], p[1], p[2]);
        for (int k = 0; k < 3; k++)
            center[k] += p[k] / 4.0;
    }
    assert_float_equal(mesh_volume(m), scale * scale * scale / 6.0, 1e-5);
    assert_normals_outward(m, center);
}

/* A copy of the rectangle: corners offset + scale * (±0.5, ±0.5, 2 z_sign), its triangles (and
 * shading normals, if any) facing z_sign (the mirror turns the normal, as Mitsuba turns it by
 * the inverse transpose). */
static void check_rectangle_copy(const scene_mesh *m, const double offset[3], double scale,
                                 double z_sign)
{
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangle_count, 2);
    for (int corner = 0; corner < 4; corner++)
        assert_has_vertex(m, offset[0] + scale * (corner & 1 ? 0.5 : -0.5),
                          offset[1] + scale * (corner & 2 ? 0.5 : -0.5),
                          offset[2] + scale * 2.0 * z_sign);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double n[3];
        triangle_normal(m, t, n);
        assert_true(n[2] * z_sign > 0);
    }
    for (uint32_t v = 0; m->normals && v < m->vertex_count; v++)
        assert_true(m->normals[3 * v + 2] * z_sign > 0.99);
}

/* Each group shape's first copy holds its geometry; the later copies hold none, share its
 * triangles, and are made where they stand when restored (core/scene.h). */
static void test_instances_held_once(void **state)
{
    write_file("tet.obj", tet_obj);
    scene *s = load_scene("3.0.0", instanced_body);
    static const char *const names[] = {"a/tet", "a/rectangle", "G/tet",
                                        "G/rectangle", "m/tet", "m/rectangle"};
    static const int instance_lines[] = {11, 11, 15, 15, 19, 19};
    assert_int_equal(s->mesh_count, 6);
    assert_int_equal(s->triangle_count, 6); /* the tet's 4 and the rectangle's 2, once */
    assert_int_equal(s->vertex_count, 8);
    assert_int_equal(s->rendered_triangle_count, 18);
    assert_int_equal(s->rendered_vertex_count, 24);
    assert_true(s->features & IDMR_FEATURE_INSTANCES);
    for (size_t i = 2; i < 6; i++) {
        assert_true(scene_mesh_is_later_copy(s, i));
        assert_true(s->meshes[i].released);
        assert_null(s->meshes[i].positions);
        assert_int_equal(s->meshes[i].first_triangle, s->meshes[i % 2].first_triangle);
        assert_int_equal(scene_mesh_of_triangle(s, s->meshes[i].first_triangle), i % 2);
        assert_int_equal(scene_mesh_restore(s, i), 0);
    }
    for (size_t i = 0; i < 6; i++) {
        assert_string_equal(s->meshes[i].name, names[i]);
        assert_int_equal(s->meshes[i].xml_line, i % 2 ? 7 : 3);
        assert_int_equal(s->meshes[i].instance_xml_line, instance_lines[i]);
        assert_non_null(strstr(s->meshes[i].instance_xml_file, "scene.xml"));
        /* The copies of each group shape are chained from its first (the tet's 0, 2, 4; the
         * rectangle's 1, 3, 5), each with its instance's transform. */
        assert_true(s->meshes[i].instanced);
        assert_int_equal(s->meshes[i].instance_first, i % 2);
        assert_int_equal(s->meshes[i].instance_next, i < 4 ? i + 2 : 0);
    }
    assert_true(s->meshes[0].instance_to_world[3] == 10.0);  /* a: x + 10 */
    assert_true(s->meshes[2].instance_to_world[0] == 2.0);   /* scaled by 2 */
    assert_true(s->meshes[4].instance_to_world[10] == -1.0); /* m: mirrored in z */
    static const double moved[3] = {10, 0, 0}, lifted[3] = {0, 10, 0}, origin[3] = {0, 0, 0};
    check_tet_copy(&s->meshes[0], moved, 1, 1);
    check_rectangle_copy(&s->meshes[1], moved, 1, 1);
    check_tet_copy(&s->meshes[2], lifted, 2, 1);
    check_rectangle_copy(&s->meshes[3], lifted, 2, 1);
    check_tet_copy(&s->meshes[4], origin, 1, -1);
    check_rectangle_copy(&s->meshes[5], origin, 1, -1);
    assert_vec3(s->bbox_min, -1, -0.5, -2, EPS);
    assert_vec3(s->bbox_max, 11.5, 12, 4, EPS);
    scene_free(s);
}

/* Mitsuba 0.5 names them alike (toWorld); the group's shapes read again (streaming) come back
 * placed as the load placed them. */
static void test_instances_old_dialect_and_restored(void **state)
{
    write_file("tet.obj", tet_obj);
    scene *s = load_scene("0.5.0",
                          "  <shape type=\"shapegroup\" id=\"G\">\n"
                          "    <shape type=\"obj\">\n"
                          "      <string name=\"filename\" value=\"tet.obj\"/>\n"
                          "      <transform name=\"toWorld\"><translate x=\"0.5\"/></transform>\n"
                          "    </shape>\n"
                          "  </shape>\n"
                          "  <shape type=\"instance\">\n"
                          "    <ref id=\"G\"/>\n"
                          "    <transform name=\"toWorld\"><scale z=\"-1\"/></transform>\n"
                          "  </shape>\n");
    static const double origin[3] = {0, 0, 0};
    assert_int_equal(s->mesh_count, 1);
    check_tet_copy(&s->meshes[0], origin, 1, -1);
    scene_mesh_release(s, 0);
    assert_true(s->meshes[0].released);
    assert_int_equal(scene_mesh_restore(s, 0), 0);
    check_tet_copy(&s->meshes[0], origin, 1, -1);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Errors: the message names scene.xml, the line and the element, and says what is wrong     */

typedef struct error_case {
    const char *name, *version, *body;
    int line;
    const char *element, *what;
    const char *also; /* one more text the message must hold, or NULL */
} error_case;

static const error_case error_cases[] = {
    {"error_texture_missing_file", "3.0.0",
     "  <shape type=\"cube\">\n"
     "    <bsdf type=\"diffuse\">\n"
     "      <texture name=\"reflectance\" type=\"bitmap\">\n"
     "        <string name=\"filename\" value=\"textures/none.png\"/>\n"
     "      </texture>\n"
     "    </bsdf>\n"
     "  </shape>\n",
     4, "<texture name=\"reflectance\" type=\"bitmap\">", "none.png", NULL},
    {"error_malformed_xml", "3.0.0", "  <shape type=\"cube\">\n  </shap>\n", 3, "malformed XML",
     "shap", NULL},
    {"error_unknown_element", "3.0.0",
     "  <shape type=\"cube\"/>\n  <medium type=\"homogeneous\" id=\"fog\"/>\n", 3,
     "<medium type=\"homogeneous\" id=\"fog\">", "unsupported element", NULL},
    {"error_unknown_transform_operation", "3.0.0",
     "  <shape type=\"cube\">\n"
     "    <transform name=\"to_world\"><shear value=\"1\"/></transform>\n"
     "  </shape>\n",
     3, "<shear>", "unknown transform operation", NULL},
    {"error_unsupported_bsdf", "3.0.0", "\n  <bsdf type=\"hair\" id=\"h\"/>\n", 3,
     "<bsdf type=\"hair\" id=\"h\">", "unsupported bsdf type 'hair'", NULL},
    {"error_unsupported_nested_bsdf", "3.0.0",
     "  <shape type=\"cube\">\n"
     "    <bsdf type=\"twosided\"><bsdf type=\"blendbsdf\"/></bsdf>\n"
     "  </shape>\n",
     3, "<bsdf type=\"blendbsdf\">", "unsupported bsdf type", NULL},
    {"error_coordinates_too_large", "3.0.0",
     "  <shape type=\"cube\" id=\"big\">\n"
     "    <transform name=\"to_world\"><scale value=\"2e38\"/></transform>\n"
     "  </shape>\n",
     2, "mesh 'big'", "beyond the 1e+11", NULL},
    {"error_second_environment", "3.0.0",
     "  <emitter type=\"constant\"/>\n  <emitter type=\"constant\"/>\n", 3,
     "<emitter type=\"constant\">", "at most one", NULL},
    {"error_unsupported_emitter", "3.0.0", "  <emitter type=\"sunsky\"/>\n", 2,
     "<emitter type=\"sunsky\">", "unsupported emitter type", NULL},
    {"error_unsupported_shape", "3.0.0",
     "  <shape type=\"serialized\"><string name=\"filename\" value=\"a.serialized\"/>"
     "</shape>\n",
     2, "<shape type=\"serialized\">", "unsupported shape type 'serialized'", NULL},
    {"error_unknown_ior", "3.0.0",
     "  <shape type=\"cube\"><bsdf type=\"dielectric\">\n"
     "    <string name=\"int_ior\" value=\"unobtainium\"/>\n"
     "  </bsdf></shape>\n",
     3, "<string name=\"int_ior\">", "unknown index of refraction 'unobtainium'", NULL},
    {"error_float_not_a_number", "3.0.0",
     "  <sensor type=\"perspective\">\n"
     "    <float name=\"fov\" value=\"abc\"/>\n"
     "  </sensor>\n",
     3, "<float name=\"fov\">", "'abc' is not a number", NULL},
    {"error_translate_nan", "3.0.0",
     "  <shape type=\"cube\">\n"
     "    <transform name=\"to_world\">\n"
     "      <translate x=\"1\" y=\"nan\"/>\n"
     "    </transform>\n"
     "  </shape>\n",
     4, "<translate>", "'nan' is not a number", NULL},
    {"error_spectrum_not_a_number", "3.0.0",
     "  <shape type=\"cube\"><bsdf type=\"diffuse\">\n"
     "    <spectrum name=\"reflectance\" value=\"400:0.5, 500:x\"/>\n"
     "  </bsdf></shape>\n",
     3, "<spectrum name=\"reflectance\">", "'x' is not a number", NULL},
    {"error_integer_not_an_integer", "3.0.0",
     "  <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\n"
     "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"12.5\"/></film>\n"
     "  </sensor>\n",
     3, "<integer name=\"width\">", "'12.5' is not an integer", NULL},
    /* The message spells the property as the file does. */
    {"error_old_dialect_names_as_written", "0.5.0",
     "  <shape type=\"cube\"><bsdf type=\"dielectric\">\n"
     "    <float name=\"intIOR\" value=\"1,5\"/>\n"
     "  </bsdf></shape>\n",
     3, "<float name=\"intIOR\">", "'1,5' is not a number", NULL},
    {"error_missing_mesh_file", "3.0.0",
     "  <shape type=\"obj\">\n"
     "    <string name=\"filename\" value=\"models/Mesh000.obj\"/>\n"
     "  </shape>\n",
     2, "<shape type=\"obj\">", "cannot read 'models/Mesh000.obj'", "No such file or directory"},
    {"error_missing_ref", "3.0.0",
     "  <shape type=\"cube\">\n"
     "    <ref id=\"nowhere\"/>\n"
     "  </shape>\n",
     3, "<ref id=\"nowhere\">", "unknown id 'nowhere'", NULL},
    {"error_undefined_parameter", "3.0.0",
     "  <integrator type=\"path\">\n"
     "    <integer name=\"max_depth\" value=\"$depth\"/>\n"
     "  </integrator>\n",
     3, "<integer name=\"max_depth\">", "undefined parameter '$depth'", NULL},
    {"error_instance_unknown_id", "3.0.0",
     "  <shape type=\"instance\">\n"
     "    <ref id=\"nowhere\"/>\n"
     "  </shape>\n",
     3, "<ref id=\"nowhere\">", "unknown id 'nowhere'", NULL},
    {"error_instance_of_a_bsdf", "3.0.0",
     "  <bsdf type=\"diffuse\" id=\"grey\"/>\n"
     "  <shape type=\"instance\">\n"
     "    <ref id=\"grey\"/>\n"
     "  </shape>\n",
     4, "<ref id=\"grey\">", "'grey' is not a shapegroup", NULL},
    {"error_instance_without_ref", "3.0.0",
     "  <shape type=\"shapegroup\" id=\"G\">\n"
     "    <shape type=\"cube\"/>\n"
     "  </shape>\n"
     "  <shape type=\"instance\">\n"
     "    <transform name=\"to_world\"><translate x=\"1\"/></transform>\n"
     "  </shape>\n",
     5, "<shape type=\"instance\">", "needs a <ref", NULL},
    {"error_shapegroup_with_emitter", "3.0.0",
     "  <shape type=\"shapegroup\" id=\"G\">\n"
     "    <shape type=\"rectangle\">\n"
     "      <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>\n"
     "    </shape>\n"
     "  </shape>\n",
     3, "<shape type=\"rectangle\">", "area emitter inside a shapegroup", NULL},
    {"error_shapegroup_nested", "3.0.0",
     "  <shape type=\"shapegroup\" id=\"G\">\n"
     "    <shape type=\"shapegroup\" id=\"H\">\n"
     "      <shape type=\"cube\"/>\n"
     "    </shape>\n"
     "  </shape>\n",
     3, "<shape type=\"shapegroup\" id=\"H\">", "nested instancing", NULL},
    {"error_shapegroup_shape_fails_in_instance", "3.0.0",
     "  <shape type=\"shapegroup\" id=\"G\">\n"
     "    <shape type=\"ply\">\n"
     "      <string name=\"filename\" value=\"absent.ply\"/>\n"
     "    </shape>\n"
     "  </shape>\n"
     "  <shape type=\"instance\" id=\"first\">\n"
     "    <ref id=\"G\"/>\n"
     "  </shape>\n",
     7, "<shape type=\"instance\" id=\"first\">", "absent.ply", "scene.xml:3:"},
    {"error_envmap_missing_file", "3.0.0",
     "  <emitter type=\"envmap\">\n"
     "    <string name=\"filename\" value=\"absent-sky.exr\"/>\n"
     "  </emitter>\n",
     2, "<emitter type=\"envmap\">", "absent-sky.exr", NULL},
};

/* Loading fails; the message holds "scene.xml:<line>:", the element, what is wrong (and
 * `also`), and the error is an input error. */
static void run_error_case(void **state)
{
    const error_case *c = *state;
    char where[64];
    error_clear();
    scene *s = mitsuba_load(write_scene(c->version, c->body));
    if (s) {
        scene_free(s);
        fail_msg("expected a load error mentioning '%s'", c->what);
    }
    const char *message = error_message();
    snprintf(where, sizeof where, "scene.xml:%d:", c->line);
    if (!strstr(message, where) || !strstr(message, c->element) || !strstr(message, c->what))
        fail_msg("message '%s' lacks '%s', '%s' or '%s'", message, where, c->element, c->what);
    if (c->also && !strstr(message, c->also))
        fail_msg("message '%s' lacks '%s'", message, c->also);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* PLY files cut off or mislabelled fail with a message naming the file and what is wrong; a
 * header cut off before "end_header" used to make OpenMesh's reader loop forever. A header
 * with CRLF line ends still loads. */
static void test_broken_ply_files(void **state)
{
    static const struct {
        const char *file, *text, *what;
    } cases[] = {
        {"cut.ply", "ply\nformat ascii 1.0\n", "no \"end_header\" line"},
        {"cut-in-element.ply", "ply\nformat ascii 1.0\nelement vertex 3\nprop",
         "no \"end_header\" line"},
        {"empty.ply", "", "not a PLY file"},
        {"obj-inside.ply", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not a PLY file"},
        {"crlf.ply",
         "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n"
         "property float y\r\nproperty float z\r\nelement face 1\r\n"
         "property list uchar int vertex_indices\r\nend_header\r\n0 0 0\r\n1 0 0\r\n"
         "0 1 0\r\n3 0 1 2\r\n",
         NULL},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char body[256];
        write_file(cases[i].file, cases[i].text);
        snprintf(body, sizeof body,
                 "  <shape type=\"ply\"><string name=\"filename\" value=\"%s\"/></shape>\n",
                 cases[i].file);
        error_clear();
        scene *s = mitsuba_load(write_scene("3.0.0", body));
        if (!cases[i].what) {
            if (!s)
                fail_msg("%s: %s", cases[i].file, error_message());
            assert_int_equal(s->meshes[0].triangle_count, 1);
            scene_free(s);
            continue;
        }
        if (s) {
            scene_free(s);
            fail_msg("%s loaded", cases[i].file);
        }
        const char *message = error_message();
        if (!strstr(message, cases[i].file) || !strstr(message, cases[i].what) ||
            !strstr(message, "scene.xml:2:"))
            fail_msg("%s: unexpected message '%s'", cases[i].file, message);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    }
}

static void test_error_missing_scene_file(void **state)
{
    error_clear();
    assert_null(mitsuba_load("/nonexistent/idmr/scene.xml"));
    assert_non_null(strstr(error_message(), "/nonexistent/idmr/scene.xml"));
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

/* ---------------------------------------------------------------------------------------- */
/* Real scenes                                                                              */

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
    scene *s = test_load_scene(SCENES "/cbox-mitsuba/cbox.xml");
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
    scene *s = test_load_scene(SCENES "/glass-of-water/scene-without-mesh000.xml");
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
    char *log;
    require_shared_data();
    scene *s = load_capturing_stderr(SCENES "/living-room/scene.xml", &log);
    if (!s)
        fail_msg("%s", error_message());
    assert_true(s->mesh_count >= 60);
    assert_true(s->features & IDMR_FEATURE_TEXTURED);
    assert_true(s->texture_count >= 1);
    /* The sky map becomes the one environment light. */
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    assert_true(s->lights[0].emission[0] > 0 && s->lights[0].emission[2] > 0);
    assert_true(s->features & IDMR_FEATURE_ENVIRONMENT);
    assert_true(s->environment.width > 1 && s->environment.height > 1);
    assert_null(strstr(log, "envmap"));
    free(log);
    scene_free(s);
}

/* Streaming (mitsuba_load_streaming, scene_mesh_restore): the living room (OBJ meshes with
 * texture coordinates, normals, flipped v, transforms) loaded with every mesh file released
 * once read has the whole load's counts and bounding box; each mesh read again is the whole
 * load's byte for byte. */
static void test_streaming_restores_what_was_loaded(void **state)
{
    require_shared_data();
    warn_silence(1);
    scene *whole = mitsuba_load(SCENES "/living-room/scene.xml");
    scene *streamed = mitsuba_load_streaming(SCENES "/living-room/scene.xml", 1);
    warn_silence(0);
    assert_non_null(whole);
    assert_non_null(streamed);
    assert_int_equal(streamed->mesh_count, whole->mesh_count);
    assert_true(streamed->vertex_count == whole->vertex_count);
    assert_memory_equal(streamed->bbox_min, whole->bbox_min, sizeof whole->bbox_min);
    assert_memory_equal(streamed->bbox_max, whole->bbox_max, sizeof whole->bbox_max);
    size_t released = 0;
    for (size_t m = 0; m < whole->mesh_count; m++) {
        const scene_mesh *a = &whole->meshes[m];
        scene_mesh *b = &streamed->meshes[m];
        assert_int_equal(b->released, a->file != NULL && a->light < 0);
        released += b->released;
        if (b->released)
            assert_null(b->positions);
        assert_int_equal(scene_mesh_restore(streamed, m), 0);
        assert_false(b->released);
        assert_int_equal(b->vertex_count, a->vertex_count);
        assert_int_equal(b->triangle_count, a->triangle_count);
        assert_memory_equal(b->positions, a->positions, 12 * (size_t)a->vertex_count);
        assert_memory_equal(b->indices, a->indices, 12 * (size_t)a->triangle_count);
        assert_int_equal(b->texcoords != NULL, a->texcoords != NULL);
        assert_int_equal(b->normals != NULL, a->normals != NULL);
        if (a->texcoords)
            assert_memory_equal(b->texcoords, a->texcoords, 8 * (size_t)a->vertex_count);
        if (a->normals)
            assert_memory_equal(b->normals, a->normals, 12 * (size_t)a->vertex_count);
        assert_int_equal(b->file_normals, a->file_normals);
        assert_int_equal(b->flat_normals, a->flat_normals);
    }
    assert_true(released >= 60);
    scene_free(whole);
    scene_free(streamed);
}

int main(void)
{
    static const struct CMUnitTest single_tests[] = {
        cmocka_unit_test(test_snake_case),
        cmocka_unit_test(test_xform_rotate_z),
        cmocka_unit_test(test_xform_compose_translate_then_rotate),
        cmocka_unit_test(test_xform_rotate_x_and_mirror),
        cmocka_unit_test(test_spectrum_flat_and_grey),
        cmocka_unit_test(test_spectrum_as_mitsuba),
        cmocka_unit_test(test_spectrum_colours),
        cmocka_unit_test(test_srgb_to_linear),
        cmocka_unit_test(test_shapes_cube_closed),
        cmocka_unit_test(test_shapes_sphere_outward),
        cmocka_unit_test(test_shapes_disk_fan),
        cmocka_unit_test(test_transform_old_dialect),
        cmocka_unit_test(test_camera_frame_axis_x),
        cmocka_unit_test(test_camera_old_dialect_defaults),
        cmocka_unit_test(test_no_sensor_warns),
        cmocka_unit_test(test_unread_properties_warn),
        cmocka_unit_test(test_shape_rectangle),
        cmocka_unit_test(test_shape_mirrored_builtin),
        cmocka_unit_test(test_shape_mirrored_sphere_normals),
        cmocka_unit_test(test_instances_held_once),
        cmocka_unit_test(test_instances_old_dialect_and_restored),
        cmocka_unit_test(test_obj_oriented_by_its_normals),
        cmocka_unit_test(test_obj_face_normals_keep_winding),
        cmocka_unit_test(test_shape_cube),
        cmocka_unit_test(test_shape_sphere),
        cmocka_unit_test(test_shape_disk_flipped),
        cmocka_unit_test(test_shape_obj_file),
        cmocka_unit_test(test_area_emitter_attaches),
        cmocka_unit_test(test_bsdf_diffuse_red_spectrum),
        cmocka_unit_test(test_spectrum_use_by_element),
        cmocka_unit_test(test_bsdf_wrappers_and_refs),
        cmocka_unit_test(test_envmap_is_the_environment),
        cmocka_unit_test(test_constant_environment),
        cmocka_unit_test(test_default_substitution),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_include_fan_out_is_bounded),
        cmocka_unit_test(test_error_missing_scene_file),
        cmocka_unit_test(test_real_cbox),
        cmocka_unit_test(test_real_glass_of_water_without_mesh000),
        cmocka_unit_test(test_real_glass_of_water_missing_mesh),
        cmocka_unit_test(test_broken_ply_files),
        cmocka_unit_test(test_real_living_room),
        cmocka_unit_test(test_streaming_restores_what_was_loaded),
    };
    struct CMUnitTest tests[128];
    size_t count = 0;
    for (size_t i = 0; i < sizeof single_tests / sizeof *single_tests; i++)
        tests[count++] = single_tests[i];
    ADD_CASE_TESTS(tests, count, run_transform_case, transform_cases);
    ADD_CASE_TESTS(tests, count, run_fov_axis_case, fov_axis_cases);
    ADD_CASE_TESTS(tests, count, run_bsdf_case, bsdf_cases);
    ADD_CASE_TESTS(tests, count, run_emitter_case, emitter_cases);
    ADD_CASE_TESTS(tests, count, run_error_case, error_cases);
    return _cmocka_run_group_tests("test_mitsuba", tests, count, make_temp_dir, remove_temp_dir);
}
