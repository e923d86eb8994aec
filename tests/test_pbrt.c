/* test_pbrt.c — the pbrt-v4 reader and writer (host/io/pbrt/pbrt_*.c).
 *
 * Host tests: the lexer and parameter lists on small inline strings (malformed ones each give a
 * message naming file and line), transforms against exact matrices, the camera against a ray
 * worked out from pbrt's own definition of its camera space, the material mapping as tables of
 * cases, lights, shapes (orientation under ReverseOrientation and mirrors, instances flattened),
 * statement errors, the writer on a small scene (read back: the same world-space geometry and
 * winding, paths that still resolve, the input untouched) and Bitterli's coffee maker from
 * ../shared/data (a missing data directory fails, it never skips). Device test: `idmr reduce`
 * of the coffee maker, its OUT/scene.pbrt read back by the reader. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "io/mesh/mesh_io.h"
#include "io/pbrt/pbrt.h"
#include "io/pbrt/pbrt_loader.h"
#include "io/scene_export.h"
#include "core/xform.h"
#include <zlib.h>
#include "reduce/reduce.h"

#define EPS 1e-5
#define COFFEE SCENES "/pbrt-v4/coffee/scene-v4.pbrt"

static char temp_dir[64];
#define TEST_PATH_MAX (2 * PATH_MAX)

/* ---------------------------------------------------------------------------------------- */
/* Helpers                                                                                  */

/* Writes `text` as temp_dir/name; returns its path. */
static const char *write_pbrt(const char *name, const char *text)
{
    return write_text(temp_dir, name, text);
}

/* Loads a pbrt file, warnings silenced; NULL when it fails (error set). */
static scene *load_quiet(const char *path)
{
    error_clear();
    warn_silence(1);
    scene *s = pbrt_load(path);
    warn_silence(0);
    return s;
}

/* Loads `text` as temp_dir/scene.pbrt; fails the test if it does not load. */
static scene *load_text(const char *text)
{
    const char *path = write_pbrt("scene.pbrt", text);
    scene *s = load_quiet(path);
    if (!s)
        fail_msg("loading failed: %s\n--- scene:\n%s", error_message(), text);
    return s;
}

/* Loading `text` must fail with a message holding `fragment`. */
static void expect_load_error(const char *text, const char *fragment)
{
    const char *path = write_pbrt("scene.pbrt", text);
    scene *s = load_quiet(path);
    if (s) {
        scene_free(s);
        fail_msg("expected an error holding \"%s\" for:\n%s", fragment, text);
    }
    if (!strstr(error_message(), fragment))
        fail_msg("expected \"%s\" in: %s", fragment, error_message());
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
}

static int file_exists_in(const char *dir, const char *name)
{
    struct stat info;
    return stat(path_in(dir, name), &info) == 0;
}

static void assert_near(double a, double b, double eps)
{
    if (!(fabs(a - b) <= eps))
        fail_msg("%.9g differs from %.9g by more than %g", a, b, eps);
}

static void assert_vec3(const float *v, double x, double y, double z, double eps)
{
    assert_near(v[0], x, eps);
    assert_near(v[1], y, eps);
    assert_near(v[2], z, eps);
}

/* One triangle at the origin, for statements that need a shape. */
#define ONE_TRIANGLE "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ] \"integer indices\" [ 0 1 2 ]\n"

/* Geometric normal (unnormalised) of triangle t of mesh m. */
static void triangle_normal(const scene_mesh *m, uint32_t t, double n[3])
{
    const uint32_t *ix = &m->indices[3 * t];
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)m->positions[3 * ix[1] + k] - m->positions[3 * ix[0] + k];
        v[k] = (double)m->positions[3 * ix[2] + k] - m->positions[3 * ix[0] + k];
    }
    xform_cross(u, v, n);
}

/* ---------------------------------------------------------------------------------------- */
/* Lexer and parameter lists                                                                */

static void test_lexer_tokens(void **state)
{
    const char *text = "Shape \"trianglemesh\" # a comment [ \"no\"\n  [ 1 -2.5e1 ] \"a\\\"b\" true";
    pbrt_lexer lx;
    pbrt_token t;
    pbrt_lexer_init(&lx, "inline", text, strlen(text));
    static const pbrt_token_kind kinds[] = {PBRT_TOKEN_WORD,   PBRT_TOKEN_STRING, PBRT_TOKEN_OPEN,
                                            PBRT_TOKEN_NUMBER, PBRT_TOKEN_NUMBER, PBRT_TOKEN_CLOSE,
                                            PBRT_TOKEN_STRING, PBRT_TOKEN_WORD,   PBRT_TOKEN_END};
    static const int lines[] = {1, 1, 2, 2, 2, 2, 2, 2, 2};
    for (size_t i = 0; i < ARRAY_COUNT(kinds); i++) {
        assert_int_equal(pbrt_lexer_next(&lx, &t), 0);
        assert_int_equal(t.kind, kinds[i]);
        assert_int_equal(t.line, lines[i]);
        if (i == 1) {
            assert_int_equal(t.offset, 6); /* the opening quote */
            assert_int_equal(t.end, 20);
        }
        if (i == 4) {
            double v;
            assert_int_equal(pbrt_token_number(&lx, &t, &v), 0);
            assert_true(v == -25.0);
        }
        if (i == 6) {
            char *s = pbrt_token_string(&t);
            assert_string_equal(s, "a\"b");
            free(s);
        }
    }
}

static void test_lexer_unterminated_string(void **state)
{
    const char *text = "WorldBegin\nShape \"trianglemesh\n\"point3 P\" [ 0 0 0 ]";
    pbrt_lexer lx;
    pbrt_token t;
    pbrt_lexer_init(&lx, "inline.pbrt", text, strlen(text));
    assert_int_equal(pbrt_lexer_next(&lx, &t), 0);
    assert_int_equal(pbrt_lexer_next(&lx, &t), 0);
    error_clear();
    assert_int_equal(pbrt_lexer_next(&lx, &t), -1);
    assert_non_null(strstr(error_message(), "inline.pbrt:2:"));
    assert_non_null(strstr(error_message(), "unterminated string"));
}

static void test_params_read(void **state)
{
    const char *text = "\"float fov\" 45 \"integer indices\" [0 1 2] \"bool b\" true \"bool q\" "
                       "[ \"false\" ]\n\"string s\" \"v\" \"rgb c\" [1 2 3] \"spectrum eta\" "
                       "\"metal-Ag-eta\" \"spectrum k\" [ 400 1 700 2 ] Shape";
    pbrt_lexer lx;
    pbrt_params params;
    pbrt_lexer_init(&lx, "inline", text, strlen(text));
    assert_int_equal(pbrt_params_read(&lx, &params), 0);
    assert_int_equal(params.count, 8);
    double fov;
    long missing;
    int b, q;
    const char *s;
    assert_int_equal(pbrt_param_float("inline", &params, "fov", 0, &fov), 0);
    assert_true(fov == 45.0);
    assert_int_equal(pbrt_param_bool("inline", &params, "b", 0, &b), 0);
    assert_int_equal(pbrt_param_bool("inline", &params, "q", 1, &q), 0);
    assert_true(b == 1 && q == 0);
    assert_int_equal(pbrt_param_string("inline", &params, "s", NULL, &s), 0);
    assert_string_equal(s, "v");
    assert_int_equal(pbrt_param_int("inline", &params, "nothere", 7, &missing), 0);
    assert_int_equal(missing, 7);
    pbrt_param *indices = pbrt_param_find(&params, "indices");
    assert_int_equal(indices->number_count, 3);
    pbrt_param *c = pbrt_param_find(&params, "c");
    assert_true(c->numbers[2] == 3.0);
    assert_int_equal(c->line, 2);
    pbrt_param *eta = pbrt_param_find(&params, "eta");
    assert_string_equal(eta->strings[0], "metal-Ag-eta");
    assert_int_equal(pbrt_param_find(&params, "k")->number_count, 4);
    /* A look-up of the wrong type is an error naming the parameter. */
    error_clear();
    assert_int_equal(pbrt_param_float("inline", &params, "s", 0, &fov), -1);
    assert_non_null(strstr(error_message(), "inline:2:"));
    /* The list ends before the next statement. */
    pbrt_token t;
    assert_int_equal(pbrt_lexer_next(&lx, &t), 0);
    assert_true(pbrt_token_is(&t, "Shape"));
    pbrt_params_free(&params);
}

typedef struct param_error_case {
    const char *name;
    const char *text; /* the error is on line 2 */
    const char *fragment;
} param_error_case;

static const param_error_case param_error_cases[] = {
    {"param rgb needs 3", "\n\"rgb c\" [ 1 2 ]", "where 3 are expected"},
    {"param unknown type", "\n\"colour c\" [ 1 2 3 ]", "unknown parameter type"},
    {"param missing value", "\n\"float x\" Shape", "a value is missing"},
    {"param mixed values", "\n\"float x\" [ 1 \"a\" ]", "numbers and strings mixed"},
    {"param integer fraction", "\n\"integer n\" [ 1.5 ]", "not an integer"},
    {"param bool word", "\n\"bool b\" \"maybe\"", "not true or false"},
    {"param unclosed bracket", "\n\"float x\" [ 1 2", "without a matching ']'"},
    {"param bad number", "\n\"float x\" [ 1 2..5 ]", "bad number"},
    {"param point3 count", "\n\"point3 P\" [ 1 2 3 4 ]", "not a multiple of 3"},
    {"param declaration words", "\n\"float\" [ 1 ]", "declared as \"type name\""},
    {"param twice", "\"float x\" 1\n\"float x\" 2", "given twice"},
};

static void run_param_error_case(void **state)
{
    const param_error_case *c = *state;
    pbrt_lexer lx;
    pbrt_params params;
    pbrt_lexer_init(&lx, "p.pbrt", c->text, strlen(c->text));
    error_clear();
    assert_int_equal(pbrt_params_read(&lx, &params), -1);
    if (!strstr(error_message(), c->fragment) || !strstr(error_message(), "p.pbrt:2:"))
        fail_msg("expected \"p.pbrt:2:\" and \"%s\" in: %s", c->fragment, error_message());
}

/* ---------------------------------------------------------------------------------------- */
/* Statements: transforms                                                                   */

typedef struct transform_case {
    const char *name;
    const char *statements; /* before the triangle, inside the world */
    double expected[16];    /* the shape's object_to_world, row-major */
} transform_case;

static const transform_case transform_cases[] = {
    {"transform translate", "Translate 1 2 3\n", {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1}},
    {"transform scale", "Scale 2 3 4\n", {2, 0, 0, 0, 0, 3, 0, 0, 0, 0, 4, 0, 0, 0, 0, 1}},
    {"transform rotate z", "Rotate 90 0 0 1\n",
     {0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
    /* Translate then Scale: points are scaled first, then translated. */
    {"transform order", "Translate 1 0 0\nScale 2 2 2\n",
     {2, 0, 0, 1, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1}},
    /* The 16 values are the matrix column by column: the translation is values 12-14. */
    {"transform column major", "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1 ]\n",
     {1, 0, 0, 5, 0, 1, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1}},
    {"transform concat", "Translate 1 0 0\nConcatTransform [ 0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1 ]\n",
     {0, -1, 0, 1, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
    {"transform attribute restores", "AttributeBegin\nTranslate 9 9 9\nAttributeEnd\nScale 2 2 2\n",
     {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1}},
    {"transform transformbegin", "TransformBegin\nTranslate 9 9 9\nTransformEnd\nTranslate 0 1 0\n",
     {1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1}},
    {"transform identity", "Translate 4 4 4\nIdentity\n",
     {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
    {"transform coordinate system",
     "Translate 3 0 0\nCoordinateSystem \"here\"\nIdentity\nScale 5 5 5\nCoordSysTransform \"here\"\n",
     {1, 0, 0, 3, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
    /* LookAt's camera-from-world: eye (0,0,5) looking at the origin, up +y: x' = -x,
     * y' = y, z' = 5 - z. */
    {"transform lookat", "LookAt 0 0 5  0 0 0  0 1 0\n",
     {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 5, 0, 0, 0, 1}},
};

static void run_transform_case(void **state)
{
    const transform_case *c = *state;
    char text[2048];
    snprintf(text, sizeof text, "WorldBegin\n%s" ONE_TRIANGLE, c->statements);
    scene *s = load_text(text);
    assert_int_equal(s->mesh_count, 1);
    for (int i = 0; i < 16; i++)
        assert_near(s->meshes[0].object_to_world[i], c->expected[i], 1e-12);
    /* The triangle's corner (1, 0, 0) went where the matrix sends it. */
    const float *p = &s->meshes[0].positions[3];
    assert_vec3(p, c->expected[0] + c->expected[3], c->expected[4] + c->expected[7],
                c->expected[8] + c->expected[11], 1e-5);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Camera                                                                                   */

/* pbrt's camera: raster (0, 0) is the top-left; screen space spans [-ratio, ratio] × [-1, 1]
 * on a film wider than tall, the shorter axis (y) at tan(fov / 2); raster x grows with camera
 * x, raster y falls with camera y. LookAt from (0,0,5) to the origin with up +y gives camera
 * x = world -x, y = world y, z = world -z. With fov 90 and a 200 × 100 film, the ray through
 * the top-left corner is camera (-2, 1, 1), world (2, 1, -1). */
static void test_camera_ray(void **state)
{
    scene *s = load_text("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 90\n"
                         "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                         "WorldBegin\n" ONE_TRIANGLE);
    assert_true(s->has_camera);
    const idmr_camera *c = &s->camera;
    assert_int_equal(c->width, 200);
    assert_int_equal(c->height, 100);
    assert_vec3(c->origin, 0, 0, 5, EPS);
    assert_vec3(c->forward, 0, 0, -1, EPS);
    assert_vec3(c->up, 0, 1, 0, EPS);
    assert_vec3(c->right, -1, 0, 0, EPS);
    float d[3];
    idmr_camera_direction(c, 0.0f, 0.0f, d);
    assert_vec3(d, 2, 1, -1, EPS);
    idmr_camera_direction(c, 100.0f, 50.0f, d); /* the centre */
    assert_vec3(d, 0, 0, -1, EPS);
    assert_string_equal(s->camera_info.fov_axis, "smaller");
    scene_free(s);
}

/* fov spans the shorter axis: on a film taller than wide, x. */
static void test_camera_portrait(void **state)
{
    scene *s = load_text("Camera \"perspective\" \"float fov\" 40\n"
                         "Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 300\n"
                         "WorldBegin\n" ONE_TRIANGLE);
    assert_near(s->camera.tan_half_x, tan(20 * M_PI / 180), 1e-6);
    assert_near(s->camera.tan_half_y, 3 * tan(20 * M_PI / 180), 1e-6);
    /* No transform: pbrt's camera looks down +z with +x to the right. */
    assert_vec3(s->camera.forward, 0, 0, 1, EPS);
    assert_vec3(s->camera.right, 1, 0, 0, EPS);
    scene_free(s);
}

/* A mirroring Scale -1 1 1 before LookAt (as exporters write) mirrors the image. */
static void test_camera_mirrored(void **state)
{
    scene *s = load_text("Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
                         "WorldBegin\n" ONE_TRIANGLE);
    assert_vec3(s->camera.forward, 0, 0, -1, EPS);
    assert_vec3(s->camera.right, 1, 0, 0, EPS);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Materials                                                                                */

typedef struct material_case {
    const char *name;
    const char *material; /* a Material statement's type and parameters */
    unsigned int kind;
    float reflectance[3];
    float specular[3];
    float roughness;
    float int_ior;
    unsigned int flags;
} material_case;

#define TWO IDMR_MATERIAL_TWOSIDED
static const material_case material_cases[] = {
    {"material diffuse default", "\"diffuse\"", IDMR_MATERIAL_DIFFUSE, {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 0, 1, TWO},
    {"material diffuse rgb", "\"diffuse\" \"rgb reflectance\" [ 0.1 0.2 0.3 ]", IDMR_MATERIAL_DIFFUSE,
     {0.1f, 0.2f, 0.3f}, {0, 0, 0}, 0, 1, TWO},
    {"material diffuse flat spectrum", "\"diffuse\" \"spectrum reflectance\" [ 300 0.7 900 0.7 ]",
     IDMR_MATERIAL_DIFFUSE, {0.7f, 0.7f, 0.7f}, {0, 0, 0}, 0, 1, TWO},
    /* roughness 0.01 remapped: alpha = sqrt(0.01) = 0.1. */
    {"material coateddiffuse", "\"coateddiffuse\" \"rgb reflectance\" [ 1 0.5 0 ] \"float roughness\" 0.01",
     IDMR_MATERIAL_GLOSSY, {1, 0.5f, 0}, {1, 1, 1}, 0.1f, 1.5f, TWO},
    {"material coateddiffuse no remap",
     "\"coateddiffuse\" \"float uroughness\" 0.04 \"float vroughness\" 0.01 \"bool remaproughness\" false \"float eta\" 1.4",
     IDMR_MATERIAL_GLOSSY, {0.5f, 0.5f, 0.5f}, {1, 1, 1}, 0.02f, 1.4f, TWO},
    {"material conductor silver", "\"conductor\" \"spectrum eta\" \"metal-Ag-eta\" \"spectrum k\" \"metal-Ag-k\"",
     IDMR_MATERIAL_MIRROR, {0, 0, 0}, {0.972f, 0.960f, 0.915f}, 0, 1, TWO},
    {"material conductor default copper", "\"conductor\"", IDMR_MATERIAL_MIRROR, {0, 0, 0},
     {0.955f, 0.638f, 0.538f}, 0, 1, TWO},
    {"material conductor rough", "\"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"float roughness\" 0.04",
     IDMR_MATERIAL_GLOSSY, {0, 0, 0}, {1.0f, 0.782f, 0.344f}, 0.2f, 1, TWO},
    /* F0 of eta 2, k 0: (1/3)² = 1/9. */
    {"material conductor rgb eta", "\"conductor\" \"rgb eta\" [ 2 2 2 ] \"rgb k\" [ 0 0 0 ]",
     IDMR_MATERIAL_MIRROR, {0, 0, 0}, {1 / 9.0f, 1 / 9.0f, 1 / 9.0f}, 0, 1, TWO},
    {"material conductor reflectance", "\"conductor\" \"rgb reflectance\" [ 0.9 0.8 0.7 ]",
     IDMR_MATERIAL_MIRROR, {0, 0, 0}, {0.9f, 0.8f, 0.7f}, 0, 1, TWO},
    {"material coatedconductor", "\"coatedconductor\" \"spectrum conductor.eta\" \"metal-Al-eta\" \"float conductor.roughness\" 0.09",
     IDMR_MATERIAL_GLOSSY, {0, 0, 0}, {0.913f, 0.922f, 0.924f}, 0.3f, 1, TWO},
    {"material dielectric", "\"dielectric\" \"float eta\" 1.33", IDMR_MATERIAL_DIELECTRIC, {0, 0, 0},
     {1, 1, 1}, 0, 1.33f, 0},
    {"material dielectric named glass", "\"dielectric\" \"spectrum eta\" \"glass-BK7\"",
     IDMR_MATERIAL_DIELECTRIC, {0, 0, 0}, {1, 1, 1}, 0, 1.5168f, 0},
    {"material thindielectric", "\"thindielectric\"", IDMR_MATERIAL_DIELECTRIC, {0, 0, 0},
     {1, 1, 1}, 0, 1.5f, IDMR_MATERIAL_THIN},
    {"material diffusetransmission", "\"diffusetransmission\"", IDMR_MATERIAL_DIFFUSE,
     {0.25f, 0.25f, 0.25f}, {0, 0, 0}, 0, 1, TWO},
    /* An interface passes light straight through: a thin dielectric of IOR 1. */
    {"material interface", "\"interface\"", IDMR_MATERIAL_DIELECTRIC, {0, 0, 0}, {1, 1, 1}, 0, 1,
     IDMR_MATERIAL_THIN},
};

static void run_material_case(void **state)
{
    const material_case *c = *state;
    char text[2048];
    snprintf(text, sizeof text, "WorldBegin\nMaterial %s\n" ONE_TRIANGLE, c->material);
    scene *s = load_text(text);
    const idmr_material *m = &s->materials[s->meshes[0].material];
    assert_int_equal(m->kind, c->kind);
    /* (a flat spectrum lit by D65 comes out grey to about 1e-3) */
    assert_vec3(m->reflectance, c->reflectance[0], c->reflectance[1], c->reflectance[2], 2e-3);
    assert_vec3(m->specular, c->specular[0], c->specular[1], c->specular[2], 1e-5);
    assert_near(m->roughness, c->roughness, 1e-6);
    assert_near(m->int_ior, c->int_ior, 1e-6);
    assert_int_equal(m->flags, c->flags);
    assert_int_equal(m->texture, -1);
    scene_free(s);
}

static void test_material_named_and_mix(void **state)
{
    scene *s = load_text("WorldBegin\n"
                         "MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 1 0 0 ]\n"
                         "MakeNamedMaterial \"glass\" \"string type\" \"dielectric\"\n"
                         "MakeNamedMaterial \"both\" \"string type\" \"mix\" \"string materials\" [ \"red\" \"glass\" ] \"float amount\" 0.25\n"
                         "NamedMaterial \"both\"\n" ONE_TRIANGLE
                         "NamedMaterial \"glass\"\n" ONE_TRIANGLE
                         "AttributeBegin\nNamedMaterial \"red\"\nAttributeEnd\n" ONE_TRIANGLE);
    assert_int_equal(s->mesh_count, 3);
    /* amount 0.25 < 0.5: the first material. */
    assert_int_equal(s->materials[s->meshes[0].material].kind, IDMR_MATERIAL_DIFFUSE);
    assert_vec3(s->materials[s->meshes[0].material].reflectance, 1, 0, 0, 0);
    assert_int_equal(s->materials[s->meshes[1].material].kind, IDMR_MATERIAL_DIELECTRIC);
    /* The attribute block restored the material. */
    assert_int_equal(s->meshes[2].material, s->meshes[1].material);
    scene_free(s);
}

static void test_material_texture(void **state)
{
    /* A 2 × 1 texture: a red and a blue pixel (PPM, which OpenImageIO reads). */
    static const unsigned char ppm[] = "P6\n2 1\n255\n\xff\x00\x00\x00\x00\xff";
    FILE *f = fopen(path_in(temp_dir, "tex.ppm"), "wb");
    assert_non_null(f);
    fwrite(ppm, 1, sizeof ppm - 1, f);
    fclose(f);
    scene *s = load_text("WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex.ppm\"\n"
                         "Texture \"c\" \"spectrum\" \"checkerboard\"\n"
                         "Material \"diffuse\" \"texture reflectance\" \"t\"\n" ONE_TRIANGLE
                         "Material \"diffuse\" \"texture reflectance\" \"c\"\n" ONE_TRIANGLE);
    const idmr_material *m = &s->materials[s->meshes[0].material];
    assert_true(m->texture >= 0);
    assert_int_equal(s->textures[m->texture].width, 2);
    assert_vec3(m->reflectance, 0.5, 0, 0.5, 1e-5);
    /* Another kind of texture stands for a constant. */
    assert_int_equal(s->materials[s->meshes[1].material].texture, -1);
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Lights                                                                                   */

static void test_lights(void **state)
{
    scene *s = load_text(
        "WorldBegin\n"
        "AttributeBegin\nTranslate 1 2 3\nLightSource \"point\" \"rgb I\" [ 1 2 3 ] \"float scale\" 2\nAttributeEnd\n"
        "LightSource \"spot\" \"point3 from\" [ 0 5 0 ] \"point3 to\" [ 0 0 0 ] \"float coneangle\" 40 \"float conedeltaangle\" 10\n"
        "LightSource \"distant\" \"point3 from\" [ 0 0 0 ] \"point3 to\" [ 0 -2 0 ] \"rgb L\" [ 3 3 3 ]\n"
        "LightSource \"infinite\" \"rgb L\" [ 0.5 0.25 0.125 ]\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 4 4 4 ] \"float scale\" 0.5\n" ONE_TRIANGLE
        "AttributeEnd\n" ONE_TRIANGLE);
    assert_int_equal(s->light_count, 5);
    const idmr_light *point = &s->lights[0], *spot = &s->lights[1], *distant = &s->lights[2];
    assert_int_equal(point->kind, IDMR_LIGHT_POINT);
    assert_vec3(point->position, 1, 2, 3, EPS);
    assert_vec3(point->emission, 2, 4, 6, EPS);
    assert_int_equal(spot->kind, IDMR_LIGHT_SPOT);
    assert_vec3(spot->direction, 0, -1, 0, EPS);
    assert_near(spot->cos_cutoff, cos(40 * M_PI / 180), 1e-6);
    assert_near(spot->cos_falloff_start, cos(30 * M_PI / 180), 1e-6);
    assert_int_equal(distant->kind, IDMR_LIGHT_DIRECTIONAL);
    assert_vec3(distant->direction, 0, -1, 0, EPS); /* travelling from `from` to `to` */
    assert_vec3(distant->emission, 3, 3, 3, EPS);
    assert_int_equal(s->lights[3].kind, IDMR_LIGHT_ENVIRONMENT);
    assert_int_equal(s->environment.width, 1);
    assert_vec3(s->environment.rgb, 0.5, 0.25, 0.125, EPS);
    /* The area light: only the shape inside the block emits. */
    assert_int_equal(s->mesh_count, 2);
    assert_int_equal(s->meshes[0].light, 4);
    assert_int_equal(s->meshes[1].light, -1);
    assert_vec3(s->lights[4].emission, 2, 2, 2, EPS);
    scene_free(s);
}

/* An octahedral environment image is resampled to an equirectangular map (2N × N). Its texel
 * at the square's centre is pbrt's +z; with the infinite light rotated so that +z is world +y,
 * the map's top row (Mitsuba's +y) shows it. */
static void test_infinite_image(void **state)
{
    /* 9 × 9: white in the centre 5 × 5 (around +z), black elsewhere. */
    unsigned char ppm[512];
    int header = snprintf((char *)ppm, sizeof ppm, "P6\n9 9\n255\n");
    memset(ppm + header, 0, 243);
    for (int y = 2; y < 7; y++)
        memset(ppm + header + 3 * (9 * y + 2), 255, 15);
    FILE *f = fopen(path_in(temp_dir, "sky.ppm"), "wb");
    assert_non_null(f);
    fwrite(ppm, 1, (size_t)header + 243, f);
    fclose(f);
    scene *s = load_text("WorldBegin\nAttributeBegin\nRotate -90 1 0 0\n"
                         "LightSource \"infinite\" \"string filename\" \"sky.ppm\"\nAttributeEnd\n" ONE_TRIANGLE);
    assert_int_equal(s->environment.width, 18);
    assert_int_equal(s->environment.height, 9);
    /* Map space is pbrt's light space; to_world is the rotation. The light's +z (the square's
     * centre) is map direction +z: Mitsuba's u = atan2(0, -1) / 2π = 0.5, v = 0.5, the middle
     * row at column 9 (θ = 90°, φ = 190°: 10° from +z); the top row looks along +y, which the
     * square holds on its edge (black). */
    const float *mid = &s->environment.rgb[3 * (4 * 18 + 9)];
    assert_true(mid[0] > 0.5f);
    const float *top = &s->environment.rgb[3 * (0 * 18 + 0)];
    assert_true(top[0] < 0.5f);
    const float *back = &s->environment.rgb[3 * (4 * 18 + 0)]; /* -z: the corners */
    assert_true(back[0] < 0.5f);
    /* to_world sends map +z to world +y (Rotate -90 about x). */
    assert_near(s->environment.to_world[5], 1.0, 1e-9); /* row 1 (y), column 2 (z) */
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Shapes                                                                                   */

/* A gzipped PLY (pbrt-v4 scenes store them so) reads as the plain one; a damaged one is an
 * error naming the statement (error_cases). */
static void test_gzipped_plymesh(void **state)
{
    (void)state;
    const char *ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                      "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    char path[TEST_PATH_MAX];
    snprintf(path, sizeof path, "%s/quad.ply.gz", temp_dir);
    gzFile out = gzopen(path, "wb");
    assert_non_null(out);
    assert_int_equal(gzwrite(out, ply, (unsigned)strlen(ply)), (int)strlen(ply));
    assert_int_equal(gzclose(out), Z_OK);
    write_pbrt("damaged.ply.gz", "\x1f\x8b\x08 not deflate data");
    scene *s = load_text("WorldBegin\nShape \"plymesh\" \"string filename\" \"quad.ply.gz\"\n");
    assert_int_equal(s->mesh_count, 1);
    assert_int_equal(s->meshes[0].vertex_count, 4);
    assert_int_equal(s->meshes[0].triangle_count, 2);
    assert_near(s->meshes[0].positions[3 * 2 + 1], 1, 0);
    scene_free(s);
}

static void test_shapes_tessellated(void **state)
{
    scene *s = load_text("WorldBegin\nShape \"sphere\" \"float radius\" 2\nShape \"disk\" \"float radius\" 3 \"float height\" 1\n"
                         "Shape \"bilinearmesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 0 ]\n"
                         "Shape \"cylinder\"\n");
    assert_int_equal(s->mesh_count, 3); /* the cylinder is left out */
    float lo[3], hi[3];
    mesh_bbox(&s->meshes[0], lo, hi);
    assert_near(hi[2], 2, 1e-5);
    assert_true(s->meshes[0].triangle_count > 100);
    mesh_bbox(&s->meshes[1], lo, hi);
    assert_near(hi[0], 3, 1e-5);
    assert_near(lo[2], 1, 1e-6);
    assert_int_equal(s->meshes[2].triangle_count, 2);
    /* The patch's normal is (p10 - p00) × (p01 - p00) = +z. */
    for (uint32_t t = 0; t < 2; t++) {
        double n[3];
        triangle_normal(&s->meshes[2], t, n);
        assert_true(n[2] > 0);
    }
    scene_free(s);
}

/* pbrt's front side: the winding's normal, reversed by ReverseOrientation xor a mirroring
 * transform; with N given, towards N. */
typedef struct orientation_case {
    const char *name;
    const char *statements;
    double front_z; /* sign of the front's z */
} orientation_case;

static const orientation_case orientation_cases[] = {
    {"orientation plain", "", 1},
    {"orientation reversed", "ReverseOrientation\n", -1},
    /* The points of the z = 0 triangle stay, the winding's +z is reversed: the object's +z
     * front mirrored. */
    {"orientation mirrored", "Scale 1 1 -1\n", -1},
    {"orientation mirrored reversed", "Scale 1 1 -1\nReverseOrientation\n", 1},
    {"orientation by normals", "#N\n", -1},
};

static void run_orientation_case(void **state)
{
    const orientation_case *c = *state;
    char text[1024];
    if (strcmp(c->statements, "#N\n") == 0)
        snprintf(text, sizeof text, "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ] "
                                    "\"normal N\" [ 0 0 -1  0 0 -1  0 0 -1 ]\n");
    else
        snprintf(text, sizeof text, "WorldBegin\n%s" ONE_TRIANGLE, c->statements);
    scene *s = load_text(text);
    double n[3];
    triangle_normal(&s->meshes[0], 0, n);
    /* Mirroring z sends the triangle's plane onto itself: compare the normal with +z. */
    assert_true(n[2] * c->front_z > 0);
    scene_free(s);
}

/* The object's shape is held once: the first instance's copy holds it, the second none until
 * restored (core/scene.h), both sharing its triangle. */
static void test_instances_held_once(void **state)
{
    scene *s = load_text("WorldBegin\nObjectBegin \"tri\"\n" ONE_TRIANGLE "ObjectEnd\n"
                         "AttributeBegin\nTranslate 10 0 0\nObjectInstance \"tri\"\nAttributeEnd\n"
                         "AttributeBegin\nTranslate 20 0 0\nObjectInstance \"tri\"\nAttributeEnd\n");
    assert_int_equal(s->mesh_count, 2);
    assert_int_equal(s->triangle_count, 1);
    assert_int_equal(s->rendered_triangle_count, 2);
    assert_string_not_equal(s->meshes[0].name, s->meshes[1].name);
    assert_vec3(&s->meshes[0].positions[3], 11, 0, 0, EPS);
    assert_null(s->meshes[1].positions);
    assert_int_equal(s->meshes[1].first_triangle, s->meshes[0].first_triangle);
    assert_vec3(s->bbox_max, 21, 1, 0, EPS);
    assert_int_equal(scene_mesh_restore(s, 1), 0);
    assert_vec3(&s->meshes[1].positions[3], 21, 0, 0, EPS);
    assert_int_equal(s->meshes[0].source_offset, s->meshes[1].source_offset);
    /* Chained as copies of one shape (reduce/reduce_instances.c), each with its instance's
     * transform. */
    assert_true(s->meshes[0].instanced && s->meshes[1].instanced);
    assert_int_equal(s->meshes[0].instance_first, 0);
    assert_int_equal(s->meshes[1].instance_first, 0);
    assert_int_equal(s->meshes[0].instance_next, 1);
    assert_int_equal(s->meshes[1].instance_next, 0);
    assert_true(s->meshes[0].instance_to_world[3] == 10.0);
    assert_true(s->meshes[1].instance_to_world[3] == 20.0);
    scene_free(s);
}

static void test_include(void **state)
{
    write_pbrt("inc.pbrt", "Translate 0 0 1\n" ONE_TRIANGLE);
    scene *s = load_text("WorldBegin\nAttributeBegin\nInclude \"inc.pbrt\"\nAttributeEnd\n" ONE_TRIANGLE);
    assert_int_equal(s->mesh_count, 2);
    assert_non_null(strstr(s->meshes[0].xml_file, "inc.pbrt"));
    assert_int_equal(s->meshes[0].xml_line, 2);
    assert_near(s->meshes[0].positions[2], 1, 0);
    assert_near(s->meshes[1].positions[2], 0, 0); /* the include's Translate stayed inside */
    scene_free(s);
}

typedef struct error_case {
    const char *name;
    const char *text;
    const char *fragment;
} error_case;

static const error_case error_cases[] = {
    {"error unknown statement", "WorldBegin\nShapes \"trianglemesh\"\n", "scene.pbrt:2: unknown statement 'Shapes'"},
    {"error index out of range", "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" [ 0 1 3 ]\n",
     "scene.pbrt:2: Shape: index 3 is out of range"},
    {"error missing P", "WorldBegin\n\nShape \"trianglemesh\" \"integer indices\" [ 0 1 2 ]\n", "scene.pbrt:3:"},
    {"error missing ply", "WorldBegin\nShape \"plymesh\" \"string filename\" \"nothere.ply\"\n", "scene.pbrt:2: Shape \"plymesh\": cannot read 'nothere.ply'"},
    {"error damaged gzipped ply", "WorldBegin\nShape \"plymesh\" \"string filename\" \"damaged.ply.gz\"\n", "scene.pbrt:2: Shape \"plymesh\""},
    {"error missing include", "WorldBegin\nInclude \"nothere.pbrt\"\n", "scene.pbrt:2: Include"},
    {"error unknown material", "WorldBegin\nMaterial \"velvet\"\n", "scene.pbrt:2: unknown material type 'velvet'"},
    {"error unknown named material", "WorldBegin\n\nNamedMaterial \"nope\"\n", "scene.pbrt:3: NamedMaterial: no material named 'nope'"},
    {"error attribute end", "WorldBegin\nAttributeEnd\n", "scene.pbrt:2: AttributeEnd without a matching AttributeBegin"},
    {"error unclosed attribute", "WorldBegin\nAttributeBegin\n", "ends inside AttributeBegin"},
    {"error translate count", "Translate 1 2\nWorldBegin\n", "Translate: 3 numbers expected"},
    {"error bad number", "Scale 1 x 2\n", "scene.pbrt:1: Scale: 3 numbers expected"},
    {"error unterminated", "WorldBegin\nShape \"trianglemesh\n", "scene.pbrt:2: unterminated string"},
    {"error wrong count", "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 ]\n", "scene.pbrt:2:"},
    {"error shape before world", "Shape \"sphere\"\n", "scene.pbrt:1: Shape before WorldBegin"},
    {"error unknown instance", "WorldBegin\nObjectInstance \"x\"\n", "scene.pbrt:2: ObjectInstance: no object named 'x'"},
    {"error orthographic camera", "Camera \"orthographic\"\n", "scene.pbrt:1: Camera \"orthographic\""},
};

static void run_error_case(void **state)
{
    const error_case *c = *state;
    expect_load_error(c->text, c->fragment);
}

/* ---------------------------------------------------------------------------------------- */
/* The writer                                                                               */

/* Writes the world-space geometry of the meshes named in `names` of scene `s` as PLYs under
 * out/meshes (in each shape's space) and calls pbrt_write_reduced; returns the output scene. */
static scene *write_and_reload(const scene *s, const char *out, const char *const *names,
                               size_t count)
{
    char dir[TEST_PATH_MAX];
    snprintf(dir, sizeof dir, "%s/meshes", out);
    mkdir(out, 0755);
    mkdir(dir, 0755);
    pbrt_replacement replacements[8];
    char plys[8][64];
    size_t n = 0;
    for (size_t m = 0; m < s->mesh_count; m++)
        for (size_t i = 0; i < count; i++) {
            if (strcmp(s->meshes[m].name, names[i]) != 0)
                continue;
            const scene_mesh *mesh = &s->meshes[m];
            mesh_data world = {mesh->vertex_count, mesh->triangle_count, mesh->positions,
                               mesh->indices, mesh->texcoords, mesh->normals, 0};
            mesh_data object;
            assert_int_equal(pbrt_mesh_to_object_space(mesh, &world, &object), 0);
            snprintf(plys[n], sizeof plys[n], "meshes/%zu.ply", n);
            char path[TEST_PATH_MAX];
            snprintf(path, sizeof path, "%s/%s", out, plys[n]);
            assert_int_equal(mesh_io_write_ply(path, &object, NULL, NULL, NULL), 0);
            mesh_data_free(&object);
            replacements[n] = (pbrt_replacement){mesh->xml_file, mesh->source_offset,
                                                 mesh->xml_line, plys[n]};
            n++;
        }
    assert_int_equal(n, count);
    error_clear();
    if (pbrt_write_reduced(s->file, out, replacements, n))
        fail_msg("pbrt_write_reduced: %s", error_message());
    char scene_path[TEST_PATH_MAX];
    snprintf(scene_path, sizeof scene_path, "%s/scene.pbrt", out);
    scene *back = load_quiet(scene_path);
    if (!back)
        fail_msg("reading the written scene: %s", error_message());
    return back;
}

static void test_writer_round_trip(void **state)
{
    static const unsigned char ppm[] = "P6\n1 1\n255\n\x80\x80\x80";
    char in[PATH_MAX], out[PATH_MAX];
    snprintf(in, sizeof in, "%s/in", temp_dir);
    snprintf(out, sizeof out, "%s/out", temp_dir);
    mkdir(in, 0755);
    mkdir(path_in(in, "tex"), 0755);
    FILE *f = fopen(path_in(in, "tex/grey.ppm"), "wb");
    fwrite(ppm, 1, sizeof ppm - 1, f);
    fclose(f);
    write_text(in, "part.pbrt",
               "# a fragment with a shape and a texture path\n"
               "Texture \"g2\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/grey.ppm\"\n"
               "AttributeBegin\n  Translate 0 3 0\n  Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n"
               "    \"integer indices\" [ 0 1 2 ]\nAttributeEnd\n");
    write_text(in, "plain.pbrt", "Shape \"sphere\" \"float radius\" 0.1\n");
    const char *scene_text =
        "LookAt 0 0 5  0 0 0  0 1 0 # eye, target, up\n"
        "Camera \"perspective\" \"float fov\" 30\n"
        "WorldBegin\n"
        "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/grey.ppm\"\n"
        "Material \"diffuse\" \"texture reflectance\" \"g\"\n"
        "AttributeBegin\n"
        "  Scale 1 1 -1\n  ReverseOrientation\n  Translate 1 2 3\n  Rotate 30 1 1 0\n"
        "  AreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\n"
        "  Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 0.5 ]\n"
        "      \"integer indices\" [ 0 1 2  2 1 3 ] \"point2 uv\" [ 0 0 1 0 0 1 1 1 ]\n"
        "      \"float alpha\" 1\n"
        "AttributeEnd\n"
        "Include \"part.pbrt\"\n"
        "Include \"plain.pbrt\"\n";
    write_text(in, "scene.pbrt", scene_text);
    char scene_path[TEST_PATH_MAX];
    snprintf(scene_path, sizeof scene_path, "%s/scene.pbrt", in);
    scene *s = load_quiet(scene_path);
    if (!s)
        fail_msg("%s", error_message());
    assert_int_equal(s->mesh_count, 3);
    static const char *const names[] = {"trianglemesh", "trianglemesh.2"};
    scene *back = write_and_reload(s, out, names, 2);
    assert_int_equal(back->mesh_count, 3);
    for (size_t m = 0; m < 2; m++) {
        const scene_mesh *a = &s->meshes[m], *b = &back->meshes[m];
        assert_string_equal(b->shape_type, "plymesh");
        assert_int_equal(a->triangle_count, b->triangle_count);
        for (size_t i = 0; i < 3 * (size_t)a->vertex_count; i++)
            assert_near(b->positions[i], a->positions[i], 1e-5);
        for (uint32_t t = 0; t < a->triangle_count; t++) { /* the same front side */
            double na[3], nb[3];
            triangle_normal(a, t, na);
            triangle_normal(b, t, nb);
            assert_true(xform_dot(na, nb) > 0);
        }
        for (size_t i = 0; a->texcoords && i < 2 * (size_t)a->vertex_count; i++)
            assert_near(b->texcoords[i], a->texcoords[i], 1e-6);
    }
    assert_int_equal(back->light_count, 1);
    assert_int_equal(back->meshes[0].light, 0);
    assert_int_equal(back->texture_count, 1);
    assert_memory_equal(&back->camera, &s->camera, sizeof s->camera);
    /* The fragment with the replaced shape is a copy; the plain one is named where it is. */
    char *text = read_all(path_in(out, "scene.pbrt"), NULL);
    assert_non_null(strstr(text, "Include \"includes/part.pbrt\""));
    assert_non_null(strstr(text, "../in/plain.pbrt"));
    assert_non_null(strstr(text, "\"../in/tex/grey.ppm\""));
    assert_non_null(strstr(text, "\"float alpha\" 1"));          /* a non-geometric parameter */
    assert_non_null(strstr(text, "LookAt 0 0 5  0 0 0  0 1 0 # eye, target, up\n"));
    assert_null(strstr(text, "\"point2 uv\""));
    free(text);
    assert_true(file_exists_in(out, "includes/part.pbrt"));
    /* The input is untouched. */
    char *again = read_all(scene_path, NULL);
    assert_string_equal(again, scene_text);
    free(again);
    scene_free(back);
    scene_free(s);
}

static void test_writer_unknown_offset(void **state)
{
    scene *s = load_text("WorldBegin\n" ONE_TRIANGLE);
    char out[PATH_MAX];
    snprintf(out, sizeof out, "%s/out-bad", temp_dir);
    mkdir(out, 0755);
    pbrt_replacement r = {s->meshes[0].xml_file, 3, 2, "meshes/x.ply"};
    error_clear();
    assert_int_equal(pbrt_write_reduced(s->file, out, &r, 1), -1);
    assert_non_null(strstr(error_message(), "scene.pbrt:2: no Shape statement"));
    scene_free(s);
}

/* ---------------------------------------------------------------------------------------- */
/* Bitterli's coffee maker                                                                  */

/* The number of faces a PLY header declares (all triangles in this scene). */
static unsigned long ply_faces(const char *path)
{
    char *bytes = read_all(path, NULL);
    assert_non_null(bytes);
    const char *face = strstr(bytes, "element face ");
    assert_non_null(face);
    unsigned long count = strtoul(face + 13, NULL, 10);
    free(bytes);
    return count;
}

static void test_coffee(void **state)
{
    require_shared_data();
    scene *s = load_quiet(COFFEE);
    if (!s)
        fail_msg("%s", error_message());
    /* 20 PLYs and 3 inline quads (two triangles each) behind area lights. */
    unsigned long ply_triangles = 0;
    size_t plys = 0, quads = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        if (strcmp(mesh->shape_type, "plymesh") == 0) {
            plys++;
            ply_triangles += ply_faces(mesh->file);
            assert_int_equal(mesh->light, -1);
        } else {
            quads++;
            assert_int_equal(mesh->triangle_count, 2);
            assert_true(mesh->light >= 0);
            assert_vec3(s->lights[mesh->light].emission, 2, 2, 2, 0);
        }
    }
    assert_int_equal(plys, 20);
    assert_int_equal(quads, 3);
    assert_int_equal(ply_triangles, 235265);
    assert_int_equal(s->triangle_count, 235265 + 6);
    assert_int_equal(s->light_count, 3);
    /* Plastic_Orange, Plastic_Black, Floor: coated diffuse; Glass; Metal (smooth silver); the
     * three emitters' black diffuse. */
    size_t kinds[IDMR_MATERIAL_KIND_COUNT] = {0};
    for (size_t i = 0; i < s->material_count; i++)
        kinds[s->materials[i].kind]++;
    assert_int_equal(kinds[IDMR_MATERIAL_DIFFUSE], 3);
    assert_int_equal(kinds[IDMR_MATERIAL_GLOSSY], 3);
    assert_int_equal(kinds[IDMR_MATERIAL_MIRROR], 1);
    assert_int_equal(kinds[IDMR_MATERIAL_DIELECTRIC], 1);
    const scene_mesh *glass = test_find_mesh(s, "Mesh010");
    assert_near(s->materials[glass->material].int_ior, 1.5, 1e-6);
    const scene_mesh *orange = test_find_mesh(s, "Mesh009");
    assert_vec3(s->materials[orange->material].reflectance, 1, 0.378676, 0.013473, 1e-6);
    assert_near(s->materials[orange->material].roughness, 0.001, 1e-7);
    /* 800 × 1000 film, fov 25 on the shorter (x) axis; the camera at the inverse of the
     * Transform's translation. */
    assert_int_equal(s->camera.width, 800);
    assert_int_equal(s->camera.height, 1000);
    assert_near(s->camera.tan_half_x, tan(12.5 * M_PI / 180), 1e-6);
    assert_vec3(s->camera.forward, 0.00726551, -0.0393187, -0.9992, 1e-5);
    scene_free(s);
}

/* The shipped Cornell box written as pbrt-v4 by `idmr convert` (io/pbrt/export_pbrt.c, written by
 * another hand from pbrt's documentation) and read back here: the same camera frame, film and
 * field of view, meshes, materials and light, so the two agree on pbrt's camera space and
 * conventions. */
static void test_convert_round_trip(void **state)
{
    scene *mitsuba = test_load_scene(IDMR_ROOT "/data/cornell/scene.xml");
    char out[TEST_PATH_MAX];
    snprintf(out, sizeof out, "%s/convert/box.pbrt", temp_dir);
    mkdir(path_in(temp_dir, "convert"), 0755);
    warn_silence(1);
    int status = scene_export(mitsuba, out, 0);
    warn_silence(0);
    if (status)
        fail_msg("convert: %s", error_message());
    scene *s = load_quiet(out);
    if (!s)
        fail_msg("reading the converted scene: %s", error_message());
    const idmr_camera *a = &mitsuba->camera, *b = &s->camera;
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_vec3(b->origin, a->origin[0], a->origin[1], a->origin[2], 1e-5);
    assert_vec3(b->forward, a->forward[0], a->forward[1], a->forward[2], 1e-6);
    assert_vec3(b->right, a->right[0], a->right[1], a->right[2], 1e-6);
    assert_vec3(b->up, a->up[0], a->up[1], a->up[2], 1e-6);
    assert_near(b->tan_half_x, a->tan_half_x, 1e-6);
    assert_near(b->tan_half_y, a->tan_half_y, 1e-6);
    assert_int_equal(s->mesh_count, mitsuba->mesh_count);
    assert_int_equal(s->triangle_count, mitsuba->triangle_count);
    assert_int_equal(s->light_count, mitsuba->light_count);
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *ma = &mitsuba->meshes[m], *mb = &s->meshes[m];
        assert_int_equal(ma->triangle_count, mb->triangle_count);
        assert_int_equal(ma->light >= 0, mb->light >= 0);
        const idmr_material *x = &mitsuba->materials[ma->material], *y = &s->materials[mb->material];
        assert_int_equal(x->kind, y->kind);
        assert_vec3(y->reflectance, x->reflectance[0], x->reflectance[1], x->reflectance[2], 1e-6);
        for (uint32_t t = 0; t < ma->triangle_count; t++) { /* the same front side */
            double na[3], nb[3];
            triangle_normal(ma, t, na);
            triangle_normal(mb, t, nb);
            if (xform_dot(na, na) > 0 && xform_dot(na, nb) <= 0)
                fail_msg("mesh %s, triangle %u faces the other way", ma->name, t);
        }
        if (ma->light >= 0)
            assert_vec3(s->lights[mb->light].emission, mitsuba->lights[ma->light].emission[0],
                        mitsuba->lights[ma->light].emission[1],
                        mitsuba->lights[ma->light].emission[2], 1e-5);
    }
    scene_free(s);
    scene_free(mitsuba);
}

/* ---------------------------------------------------------------------------------------- */
/* Device: idmr reduce of the coffee maker                                                  */

static void test_reduce_coffee(void **state)
{
    require_shared_data();
    scene *s = load_quiet(COFFEE);
    if (!s)
        fail_msg("%s", error_message());
    reduce_options o;
    reduce_options_default(&o);
    o.target = 0.2;
    o.importance.sppm.iterations = 2;
    o.importance.sppm.photons = 20000;
    o.importance.sppm.progress = 0;
    o.threads = 2;
    char dir[64];
    snprintf(dir, sizeof dir, "/tmp/idmr-test-pbrt-reduce-XXXXXX");
    assert_non_null(mkdtemp(dir));
    char out[PATH_MAX];
    snprintf(out, sizeof out, "%s/out", dir);
    warn_silence(1);
    int status = reduce_run(device_test_device(), s, out, &o);
    warn_silence(0);
    if (status)
        fail_msg("reduce: %s", error_message());
    scene *back = load_quiet(path_in(out, "scene.pbrt"));
    if (!back)
        fail_msg("reading the reduced scene: %s", error_message());
    assert_int_equal(back->mesh_count, s->mesh_count);
    assert_true(back->triangle_count < s->triangle_count / 2);
    size_t replaced = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *a = &s->meshes[m], *b = &back->meshes[m];
        assert_string_equal(a->name, b->name);
        assert_true(b->triangle_count <= a->triangle_count);
        replaced += b->file && strstr(b->file, "/meshes/") != NULL;
        assert_int_equal(back->materials[b->material].kind, s->materials[a->material].kind);
        assert_memory_equal(&back->materials[b->material], &s->materials[a->material],
                            sizeof(idmr_material));
        assert_int_equal(b->light >= 0, a->light >= 0);
        float lo_a[3], hi_a[3], lo_b[3], hi_b[3];
        mesh_bbox(a, lo_a, hi_a);
        mesh_bbox(b, lo_b, hi_b);
        for (int k = 0; k < 3; k++) /* in place: within the mesh's own extent */
            assert_true(lo_b[k] >= lo_a[k] - 1e-3f && hi_b[k] <= hi_a[k] + 1e-3f);
    }
    assert_true(replaced >= 10);
    assert_int_equal(back->light_count, s->light_count);
    assert_memory_equal(&back->camera, &s->camera, sizeof s->camera);
    /* Every statement but the replaced shapes is as written: the first line and the lights. */
    char *text = read_all(path_in(out, "scene.pbrt"), NULL);
    assert_non_null(strstr(text, "Integrator \"path\"\n    \"integer maxdepth\" [ 17 ]\n"));
    assert_non_null(strstr(text, "AreaLightSource \"diffuse\"\n        \"rgb L\" [ 2 2 2 ]"));
    free(text);
    scene_free(back);
    scene_free(s);
    char command[256];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    assert_int_equal(system(command), 0);
}

int main(void)
{
    static struct CMUnitTest tests[128];
    size_t count = 0;
    static const struct CMUnitTest single[] = {
        cmocka_unit_test(test_lexer_tokens),
        cmocka_unit_test(test_lexer_unterminated_string),
        cmocka_unit_test(test_params_read),
        cmocka_unit_test(test_camera_ray),
        cmocka_unit_test(test_camera_portrait),
        cmocka_unit_test(test_camera_mirrored),
        cmocka_unit_test(test_material_named_and_mix),
        cmocka_unit_test(test_material_texture),
        cmocka_unit_test(test_lights),
        cmocka_unit_test(test_infinite_image),
        cmocka_unit_test(test_gzipped_plymesh),
        cmocka_unit_test(test_shapes_tessellated),
        cmocka_unit_test(test_instances_held_once),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_writer_round_trip),
        cmocka_unit_test(test_writer_unknown_offset),
        cmocka_unit_test(test_coffee),
        cmocka_unit_test(test_convert_round_trip),
    };
    for (size_t i = 0; i < ARRAY_COUNT(single); i++)
        tests[count++] = single[i];
    ADD_CASE_TESTS(tests, count, run_param_error_case, param_error_cases);
    ADD_CASE_TESTS(tests, count, run_transform_case, transform_cases);
    ADD_CASE_TESTS(tests, count, run_material_case, material_cases);
    ADD_CASE_TESTS(tests, count, run_orientation_case, orientation_cases);
    ADD_CASE_TESTS(tests, count, run_error_case, error_cases);
    static const struct CMUnitTest device_tests[] = {
        cmocka_unit_test(test_reduce_coffee),
    };
    if (temp_dir_make(temp_dir, "pbrt"))
        return 1;
    int status = device_test_main("pbrt", tests, count, device_tests, ARRAY_COUNT(device_tests),
                                  NULL, NULL);
    temp_dir_remove(temp_dir);
    return status;
}
