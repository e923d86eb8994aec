/* test_mesh_inputs.c — mesh files as real exporters write them, through mesh_io_read() and
 * bin/idmr, on files written here. One case a test:
 *
 *   repeated vertex  a triangle that names one vertex twice (an OBJ's "f 1 2 1", an OFF or PLY
 *                    face "3 0 1 0", a polygon that repeats a corner, an STL facet with two
 *                    corners at one position) is dropped on load and counted
 *                    (mesh_data.triangles_dropped); a vertex only it used goes with it;
 *                    scene_add_mesh() (the glTF loader's way in) drops them too;
 *                    mesh_io_write_ply() refuses one (OpenMesh's add_face aborted on it);
 *                    `idmr info` counts them, and `idmr importance` on such a scene (which
 *                    aborted writing the per-mesh importance PLY) runs, its PLY holding the
 *                    triangles that remain; the same for a glTF triangle strip
 *   STL              ascii and binary through idmr's reader: corners welded by position, no
 *                    texture coordinates or normals (OpenMesh left uninitialised ones, which
 *                    stalled the reduction and came out as NaN uv that idmr refused to read);
 *                    `idmr reduce` of an STL scene writes a PLY idmr reads back
 *   damaged STL      an ascii file cut inside a facet, inside a line, or before "endsolid",
 *                    and a binary file whose facet count disagrees with its size (OpenMesh
 *                    loaded the facets before the cut without a word, and called the binary
 *                    file one with "no faces"), a coordinate that is not finite: refused, the
 *                    message naming the file and the line or the byte counts
 *   PLY              read exactly: a double-sided square keeps its 4 vertices (OpenMesh split
 *                    them into copies, whose normals it left uninitialised), a second face list
 *                    or a scalar before vertex_indices loses no triangle; written exactly, a
 *                    double-sided mesh with its own vertices (OpenMesh's writer copied them) */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "command_common.h"
#include "mitsuba_common.h"

#include "io/mesh/mesh_io.h"

static char temp_dir[64];

static int make_temp(void **state)
{
    make_temp_dir(temp_dir, "idmr-test-mesh-inputs");
    return 0;
}

static int remove_temp(void **state)
{
    remove_tree(temp_dir);
    return 0;
}

/* Reads temp_dir/name (written by the caller); fails the test when the read fails. */
static void read_ok_path(const char *path, mesh_data *mesh)
{
    error_clear();
    if (mesh_io_read(path, mesh))
        fail_msg("reading %s failed: %s", path, error_message());
}

static void read_ok(const char *name, const char *text, mesh_data *mesh)
{
    read_ok_path(write_text(temp_dir, name, text), mesh);
}

/* Reading temp_dir/name fails with an input error whose message names the file and holds each
 * of the fragments (NULL-terminated). */
static void read_fails_path(const char *name, ...)
{
    mesh_data mesh;
    error_clear();
    assert_int_equal(mesh_io_read(path_in(temp_dir, name), &mesh), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    const char *message = error_message();
    print_message("  %s\n", message);
    if (!strstr(message, name))
        fail_msg("message '%s' does not name %s", message, name);
    va_list fragments;
    va_start(fragments, name);
    for (const char *what; (what = va_arg(fragments, const char *));)
        if (!strstr(message, what))
            fail_msg("message '%s' lacks '%s'", message, what);
    va_end(fragments);
    assert_null(mesh.positions);
}

static void write_bytes(const char *name, const void *bytes, size_t size)
{
    FILE *f = fopen(path_in(temp_dir, name), "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

static void assert_indices(const mesh_data *m, const uint32_t *expected, uint32_t triangles)
{
    assert_int_equal(m->triangle_count, triangles);
    assert_memory_equal(m->indices, expected, 3 * sizeof(uint32_t) * triangles);
}

/* ---- repeated vertex ---- */

/* "f 1 5 1" goes, and vertex 5 with it (no other face uses it); the quad "f 1 2 2 4" keeps the
 * half that has area. */
static void test_obj_repeated_vertex(void **state)
{
    mesh_data m;
    read_ok("repeat.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 5 5 5\n"
            "f 1 2 3\nf 1 5 1\nf 2 4 3\nf 1 2 2 4\n",
            &m);
    static const uint32_t expected[] = {0, 1, 2, 1, 3, 2, 0, 1, 3};
    assert_indices(&m, expected, 3);
    assert_int_equal(m.triangles_dropped, 2);
    assert_int_equal(m.vertex_count, 4);
    assert_float_equal(m.positions[3 * 3], 1.0f, 0);
    assert_float_equal(m.positions[3 * 3 + 1], 1.0f, 0);
    mesh_data_free(&m);
}

static void test_off_and_ply_repeated_vertex(void **state)
{
    mesh_data m;
    static const uint32_t expected[] = {0, 1, 2, 1, 3, 2};
    read_ok("repeat.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 0\n3 0 1 2\n4 1 3 3 2\n",
            &m);
    assert_indices(&m, expected, 2);
    assert_int_equal(m.triangles_dropped, 2);
    mesh_data_free(&m);
    /* A vertex no face ever used (4) stays, as the file has it. */
    read_ok("repeat.ply",
            "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
            "property float z\nelement face 3\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 2 2\n3 0 1 0\n3 0 1 2\n4 1 3 3 2\n",
            &m);
    assert_indices(&m, expected, 2);
    assert_int_equal(m.triangles_dropped, 2);
    assert_int_equal(m.vertex_count, 5);
    mesh_data_free(&m);
    write_text(temp_dir, "only.obj", "v 0 0 0\nv 1 0 0\nf 1 2 1\nf 2 2 2\n");
    read_fails_path("only.obj", "has no faces", "each of its 2 triangles repeats a vertex", NULL);
}

/* The glTF loader hands its triangles to scene_add_mesh(), which drops the same. */
static void test_scene_add_mesh_drops(void **state)
{
    scene *s = scene_create("in-memory");
    float *positions = malloc(3 * 4 * sizeof(float));
    for (int i = 0; i < 12; i++)
        positions[i] = (float)(i % 5);
    uint32_t *indices = malloc(9 * sizeof(uint32_t));
    static const uint32_t given[] = {0, 1, 2, 2, 2, 3, 1, 3, 2};
    memcpy(indices, given, sizeof given);
    scene_mesh *m = scene_add_mesh(s, "strip", "gltf", NULL, 1, 4, positions, 3, indices, NULL);
    assert_int_equal(m->triangle_count, 2);
    assert_int_equal(m->triangles_dropped, 1);
    assert_int_equal(m->indices[3], 1);
    assert_int_equal(m->vertex_count, 4);
    scene_free(s);
}

/* The writer never hands such a triangle to anyone: an error, no file. */
static void test_write_refuses_repeated_vertex(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t indices[] = {0, 1, 2, 0, 2, 2};
    mesh_data m = {3, 2, positions, indices, NULL, NULL, 0};
    const char *path = path_in(temp_dir, "refused.ply");
    error_clear();
    assert_int_equal(mesh_io_write_ply(path, &m, NULL, NULL, NULL), -1);
    assert_non_null(strstr(error_message(), "triangle 1 repeats a vertex"));
    assert_false(file_exists(path));
    indices[5] = 7;
    assert_int_equal(mesh_io_write_ply(path, &m, NULL, NULL, NULL), -1);
    assert_non_null(strstr(error_message(), "vertex 7 of 3"));
}

/* ---- STL ---- */

static const char STL_ASCII[] = "solid square\n"
                                "  facet normal 0 0 1\n    outer loop\n"
                                "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
                                "    endloop\n  endfacet\n"
                                "  facet normal nan nan nan\n    outer loop\n"
                                "      vertex 1 0 0\n      vertex 1 1 0\n      vertex 1 0 0\n"
                                "    endloop\n  endfacet\n"
                                "  FACET NORMAL 0 0 1\n    OUTER LOOP\n"
                                "      VERTEX 0 0 0\n      VERTEX 1 1 0\n      VERTEX -0 1 0\n"
                                "    ENDLOOP\n  ENDFACET\n"
                                "endsolid square\n";

/* The square of two facets and a facet with two corners at one position (dropped): four
 * vertices, -0 welded to 0, no texture coordinates, no normals. */
static void check_stl_square(const mesh_data *m)
{
    static const uint32_t expected[] = {0, 1, 2, 0, 2, 3};
    assert_indices(m, expected, 2);
    assert_int_equal(m->vertex_count, 4);
    assert_int_equal(m->triangles_dropped, 1);
    assert_null(m->texcoords);
    assert_null(m->normals);
    assert_float_equal(m->positions[3 * 3 + 1], 1.0f, 0);
}

static void test_stl_ascii(void **state)
{
    mesh_data m;
    read_ok("square.stl", STL_ASCII, &m);
    check_stl_square(&m);
    mesh_data_free(&m);
}

/* A binary STL of `facets` (9 floats each), its header saying `count` facets; `header` starts
 * its 80 bytes. Returns the size written. */
static size_t write_binary_stl(const char *name, const char *header, uint32_t count,
                               const float *corners, uint32_t facets)
{
    unsigned char bytes[84 + 50 * 8] = {0};
    assert_true(facets <= 8);
    memcpy(bytes, header, strlen(header));
    memcpy(bytes + 80, &count, 4); /* little-endian hosts only, as the test machines are */
    for (uint32_t f = 0; f < facets; f++) {
        float normal[3] = {0, 0, 1};
        memcpy(bytes + 84 + 50 * f, normal, 12);
        memcpy(bytes + 84 + 50 * f + 12, &corners[9 * f], 36);
    }
    write_bytes(name, bytes, 84 + 50 * (size_t)facets);
    return 84 + 50 * (size_t)facets;
}

static const float SQUARE[27] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 1, 0, 0, 1, 1,
                                 0, 1, 0, 0, 0, 0, 0, 1, 1, 0, -0.0f, 1, 0};

/* Binary, also with a header that starts "solid" (some exporters write one). */
static void test_stl_binary(void **state)
{
    mesh_data m;
    write_binary_stl("binary.stl", "binary", 3, SQUARE, 3);
    read_ok_path(path_in(temp_dir, "binary.stl"), &m);
    check_stl_square(&m);
    mesh_data_free(&m);
    write_binary_stl("solid.stl", "solid exported by a binary writer", 3, SQUARE, 3);
    read_ok_path(path_in(temp_dir, "solid.stl"), &m);
    check_stl_square(&m);
    mesh_data_free(&m);
}

static void test_stl_damaged(void **state)
{
    /* Cut inside the third facet, after its first vertex (line 18). */
    char text[sizeof STL_ASCII];
    const char *cut = strstr(STL_ASCII, "      VERTEX 1 1 0");
    snprintf(text, sizeof text, "%.*s", (int)(cut - STL_ASCII), STL_ASCII);
    write_text(temp_dir, "cut.stl", text);
    read_fails_path("cut.stl", "ends at line 18 inside facet 3", "cut short", NULL);
    /* Cut in the middle of a line: "      VERTEX 1 1". */
    snprintf(text, sizeof text, "%.*s", (int)(cut - STL_ASCII) + 16, STL_ASCII);
    write_text(temp_dir, "midline.stl", text);
    read_fails_path("midline.stl", "ends in the middle of line 19, inside facet 3", NULL);
    /* Whole facets, but no "endsolid". */
    cut = strstr(STL_ASCII, "endsolid");
    snprintf(text, sizeof text, "%.*s", (int)(cut - STL_ASCII), STL_ASCII);
    write_text(temp_dir, "open.stl", text);
    read_fails_path("open.stl", "without 'endsolid'", "after 3 complete facets", NULL);
    write_text(temp_dir, "nan.stl",
               "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\n"
               "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n");
    read_fails_path("nan.stl", "line 5", "'nan' is not a finite number", NULL);
    write_text(temp_dir, "keyword.stl", "solid x\nfacet normal 0 0 1\nvertex 0 0 0\n");
    read_fails_path("keyword.stl", "line 3", "expected 'outer loop', found 'vertex'", NULL);

    /* Binary: the header promises 5 facets, the file holds 3 (cut short), or 2 (one more). */
    write_binary_stl("short.stl", "binary", 5, SQUARE, 3);
    read_fails_path("short.stl", "says 5 facets (84 + 50 x 5 = 334 bytes)", "has 234 bytes",
                    "cut short", NULL);
    write_binary_stl("long.stl", "binary", 2, SQUARE, 3);
    read_fails_path("long.stl", "says 2 facets (84 + 50 x 2 = 184 bytes)", "has 234 bytes",
                    "bytes after the last facet", NULL);
    float corners[27];
    memcpy(corners, SQUARE, sizeof corners);
    corners[9 + 4] = INFINITY;
    write_binary_stl("inf.stl", "binary", 3, corners, 3);
    read_fails_path("inf.stl", "facet 2 (byte 158): vertex 2", "not a finite point", NULL);
    write_bytes("tiny.stl", "\x01\x02\x03", 3);
    read_fails_path("tiny.stl", "not an STL file", NULL);
}

/* ---- PLY read and written exactly ---- */

static const char PLY_DOUBLE_SIDED[] =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n"
    "3 0 1 2\n3 0 2 3\n3 0 2 1\n3 0 3 2\n";

/* A double-sided square: 4 vertices as the file has them, every normal the file's. */
static void test_ply_double_sided(void **state)
{
    mesh_data m;
    read_ok("double.ply", PLY_DOUBLE_SIDED, &m);
    assert_int_equal(m.vertex_count, 4);
    assert_int_equal(m.triangle_count, 4);
    assert_non_null(m.normals);
    for (uint32_t v = 0; v < 4; v++)
        assert_float_equal(m.normals[3 * v + 2], 1.0f, 0);
    static const uint32_t expected[] = {0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2};
    assert_memory_equal(m.indices, expected, sizeof expected);

    /* Written and read again: the same 4 vertices and 4 triangles. */
    const char *path = path_in(temp_dir, "written.ply");
    assert_int_equal(mesh_io_write_ply(path, &m, NULL, NULL, NULL), 0);
    mesh_data back;
    read_ok_path(path, &back);
    assert_int_equal(back.vertex_count, 4);
    assert_int_equal(back.triangle_count, 4);
    assert_memory_equal(back.indices, expected, sizeof expected);
    assert_memory_equal(back.normals, m.normals, 12 * sizeof(float));
    mesh_data_free(&back);
    mesh_data_free(&m);
}

/* Faces with more than one property: every triangle kept. */
static void test_ply_face_properties(void **state)
{
    mesh_data m;
    read_ok("faces.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty float s\nproperty float t\nelement face 2\n"
            "property uchar flags\nproperty list uchar int vertex_indices\n"
            "property list uchar float texcoord\nend_header\n"
            "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n"
            "7 3 0 1 2 6 0 0 1 0 1 1\n7 3 0 2 3 6 0 0 1 1 0 1\n",
            &m);
    static const uint32_t expected[] = {0, 1, 2, 0, 2, 3};
    assert_indices(&m, expected, 2);
    assert_non_null(m.texcoords);
    assert_float_equal(m.texcoords[2 * 2 + 1], 1.0f, 0);
    assert_null(m.normals);
    mesh_data_free(&m);
}

/* A face list named otherwise (vertex_ids), with ushort counts, ascii and binary: the face
 * element's one list of integers holds the corners. Two such lists, neither named as usual: an
 * error that says so. */
static void test_ply_face_list_named_otherwise(void **state)
{
    mesh_data m;
    static const uint32_t expected[] = {0, 1, 2, 0, 2, 3};
    read_ok("ids.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 2\nproperty list ushort int vertex_ids\nend_header\n"
            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
            &m);
    assert_indices(&m, expected, 2);
    mesh_data_free(&m);

    unsigned char binary[512];
    const char *header = "ply\nformat binary_little_endian 1.0\nelement vertex 4\n"
                         "property float x\nproperty float y\nproperty float z\nelement face 2\n"
                         "property uchar flags\nproperty list ushort uint indices\nend_header\n";
    size_t n = strlen(header);
    memcpy(binary, header, n);
    static const float corners[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    memcpy(binary + n, corners, sizeof corners);
    n += sizeof corners;
    for (int f = 0; f < 2; f++) {
        uint8_t flags = 7;
        uint16_t count = 3;
        uint32_t face[3] = {0, (uint32_t)(1 + f), (uint32_t)(2 + f)};
        memcpy(binary + n, &flags, 1);
        memcpy(binary + n + 1, &count, 2);
        memcpy(binary + n + 3, face, sizeof face);
        n += 3 + sizeof face;
    }
    write_bytes("indices.ply", binary, n);
    read_ok_path(path_in(temp_dir, "indices.ply"), &m);
    assert_indices(&m, expected, 2);
    mesh_data_free(&m);

    FILE *f = fopen(path_in(temp_dir, "two-lists.ply"), "w");
    assert_non_null(f);
    fputs("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int a\n"
          "property list uchar int b\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 3 0 1 2\n",
          f);
    assert_int_equal(fclose(f), 0);
    read_fails_path("two-lists.ply", "several lists", NULL);
}

/* ---- bin/idmr ---- */

/* DIR/scene.xml: a camera, a light, a floor and the shape of `type` reading `file`. */
static const char *write_scene(const char *name, const char *type, const char *file)
{
    char xml[4096];
    snprintf(xml, sizeof xml,
             "<scene version=\"3.0.0\">\n"
             "  <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\n"
             "    <transform name=\"to_world\"><lookat origin=\"0, 0, 4\" target=\"0, 0, 0\" "
             "up=\"0, 1, 0\"/></transform>\n"
             "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/>"
             "<integer name=\"height\" value=\"32\"/></film></sensor>\n"
             "  <bsdf type=\"diffuse\" id=\"white\"/>\n"
             "  <shape type=\"rectangle\" id=\"light\"><transform name=\"to_world\">"
             "<scale x=\"0.3\" y=\"0.3\"/><rotate x=\"1\" angle=\"180\"/><translate z=\"2\"/>"
             "</transform>\n"
             "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"10, 10, 10\"/></emitter>"
             "</shape>\n"
             "  <shape type=\"%s\" id=\"mesh\"><string name=\"filename\" value=\"%s\"/>"
             "<ref id=\"white\"/></shape>\n"
             "</scene>\n",
             type, file);
    return write_text(temp_dir, name, xml);
}

/* A 9 x 9 grid facing the camera as an OBJ, with `extra` (faces) appended. */
static void write_grid_obj(const char *name, const char *extra)
{
    char *text = malloc(1 << 16);
    size_t at = 0;
    for (int j = 0; j < 9; j++)
        for (int i = 0; i < 9; i++)
            at += (size_t)sprintf(text + at, "v %g %g 0\n", i / 4.0 - 1, j / 4.0 - 1);
    at += (size_t)sprintf(text + at, "%s", extra);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 8; i++) {
            int a = j * 9 + i + 1, b = a + 1, c = a + 9, d = c + 1;
            at += (size_t)sprintf(text + at, "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c);
        }
    at += (size_t)sprintf(text + at, "%s", extra);
    write_text(temp_dir, name, text);
    free(text);
}

static cJSON *parse_or_fail(const char *text)
{
    cJSON *json = cJSON_Parse(text);
    if (!json)
        fail_msg("not JSON: %.200s", text);
    return json;
}

static const cJSON *mesh_named(const cJSON *info, const char *name)
{
    const cJSON *mesh;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItemCaseSensitive(info, "meshes"))
    {
        if (!strcmp(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(mesh, "name")), name))
            return mesh;
    }
    fail_msg("no mesh '%s'", name);
    return NULL;
}

static double number_of(const cJSON *object, const char *key)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, key);
    if (!cJSON_IsNumber(item))
        fail_msg("no number '%s'", key);
    return item->valuedouble;
}

/* A grid whose faces begin and end with "f 1 2 1" (the first face OpenMesh's add_face was
 * given, so it aborted): `info` counts both, `importance` runs (it aborted, exit 134) and its
 * importance PLY of the grid holds the 128 triangles that remain. */
static void test_importance_with_repeated_vertex(void **state)
{
    write_grid_obj("repeat-grid.obj", "f 1 2 1\n");
    const char *scene_path = write_scene("repeat.xml", "obj", "repeat-grid.obj");
    run_result r = run("bin/idmr info --json --no-bvh %s", scene_path);
    assert_succeeded(&r);
    cJSON *info = parse_or_fail(r.out);
    const cJSON *mesh = mesh_named(info, "mesh");
    assert_true(number_of(mesh, "triangles") == 128);
    assert_true(number_of(mesh, "triangles_dropped") == 2);
    assert_true(number_of(info, "triangles_dropped") == 2);
    cJSON_Delete(info);
    run_free(&r);
    r = run("bin/idmr info --no-bvh %s", scene_path);
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "2 triangles dropped (a repeated vertex)"));
    run_free(&r);

    char out[PATH_MAX];
    snprintf(out, sizeof out, "%s", path_in(temp_dir, "importance-out"));
    r = run("bin/idmr importance %s -o %s --iterations 1 --photons 2000 --quiet", scene_path,
            out);
    assert_succeeded(&r);
    run_free(&r);
    mesh_data m;
    read_ok_path(path_in(out, "importance/mesh.ply"), &m);
    assert_int_equal(m.triangle_count, 128);
    assert_int_equal(m.vertex_count, 81);
    mesh_data_free(&m);
}

/* A glTF triangle strip 0 1 2 2 3 4 5 over six vertices: Assimp gives its five triangles, two
 * of which repeat vertex 2; the scene keeps the other three (scene_add_mesh), `info` counts
 * the two, and the importance PLY holds the three. The file is written here, its buffer inline
 * (base64 of six float positions and seven uint16 indices). */
static void test_gltf_strip(void **state)
{
    const char *path = write_text(
        temp_dir, "strip.gltf",
        "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1]}],\n"
        " \"nodes\": [{\"mesh\": 0}, {\"camera\": 0, \"translation\": [0, 0, 4]}],\n"
        " \"cameras\": [{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.8, "
        "\"znear\": 0.1, \"aspectRatio\": 1}}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, "
        "\"mode\": 5}]}],\n"
        " \"buffers\": [{\"byteLength\": 88, \"uri\": \"data:application/octet-stream;base64,"
        "AACAvwAAgL8AAAAAAACAvwAAgD8AAAAAAAAAAAAAgL8AAAAAAAAAAAAAgD8AAAAAAACAPwAAgL8AAAAAAACAPwAA"
        "gD8AAAAAAAABAAIAAgADAAQABQAAAA==\"}],\n"
        " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 72}, "
        "{\"buffer\": 0, \"byteOffset\": 72, \"byteLength\": 14}],\n"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 6, "
        "\"type\": \"VEC3\", \"min\": [-1, -1, 0], \"max\": [1, 1, 0]}, "
        "{\"bufferView\": 1, \"componentType\": 5123, \"count\": 7, \"type\": \"SCALAR\"}]}\n");
    char gltf[PATH_MAX], out[PATH_MAX / 2];
    snprintf(gltf, sizeof gltf, "%s", path);
    snprintf(out, sizeof out, "%s", path_in(temp_dir, "strip-out"));
    run_result r = run("bin/idmr info --json --no-bvh %s", gltf);
    assert_succeeded(&r);
    cJSON *info = parse_or_fail(r.out);
    const cJSON *mesh = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(info, "meshes"), 0);
    assert_true(number_of(mesh, "triangles") == 3);
    assert_true(number_of(mesh, "triangles_dropped") == 2);
    cJSON_Delete(info);
    run_free(&r);
    r = run("bin/idmr importance %s -o %s --iterations 1 --photons 1000 --quiet", gltf, out);
    assert_succeeded(&r);
    run_free(&r);
    mesh_data m;
    read_ok_path(path_in(out, "importance/nodes_0__meshes_0_.ply"), &m);
    assert_int_equal(m.triangle_count, 3);
    mesh_data_free(&m);
}

/* An STL grid reduced: the report gives it no texture coordinates, it meets its target, and
 * the reduced scene loads (the written PLY held NaN uv, which idmr refused to read). */
static void test_reduce_stl(void **state)
{
    FILE *f = fopen(path_in(temp_dir, "grid.stl"), "w");
    assert_non_null(f);
    fprintf(f, "solid grid\n");
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 8; i++) {
            double x0 = i / 4.0 - 1, y0 = j / 4.0 - 1, x1 = x0 + 0.25, y1 = y0 + 0.25;
            double z[4] = {0.05 * ((i + j) % 3), 0.05 * ((i + 1 + j) % 3),
                           0.05 * ((i + j + 2) % 3), 0.05 * ((i + j + 1) % 3)};
            fprintf(f, "facet normal 0 0 1\nouter loop\nvertex %g %g %g\nvertex %g %g %g\n"
                       "vertex %g %g %g\nendloop\nendfacet\n",
                    x0, y0, z[0], x1, y0, z[1], x1, y1, z[2]);
            fprintf(f, "facet normal 0 0 1\nouter loop\nvertex %g %g %g\nvertex %g %g %g\n"
                       "vertex %g %g %g\nendloop\nendfacet\n",
                    x0, y0, z[0], x1, y1, z[2], x0, y1, z[3]);
        }
    fprintf(f, "endsolid grid\n");
    assert_int_equal(fclose(f), 0);
    const char *scene_path = write_scene("stl.xml", "stl", "grid.stl");
    char out[PATH_MAX];
    snprintf(out, sizeof out, "%s", path_in(temp_dir, "stl-out"));
    run_result r = run("bin/idmr reduce %s --method quadric --target 0.5 -o %s --quiet",
                       scene_path, out);
    assert_succeeded(&r);
    run_free(&r);
    size_t size;
    char *text = read_all(path_in(out, "report.json"), &size);
    assert_non_null(text);
    cJSON *report = parse_or_fail(text);
    free(text);
    const cJSON *mesh = mesh_named(report, "mesh");
    print_message("  grid.stl: %g -> %g vertices (target %g)\n", number_of(mesh, "vertices"),
                  number_of(mesh, "vertices_after"), number_of(mesh, "vertices_target"));
    assert_false(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(mesh, "texcoords")));
    assert_true(number_of(mesh, "vertices") == 81);
    assert_true(number_of(mesh, "vertices_after") <= number_of(mesh, "vertices_target"));
    cJSON_Delete(report);
    r = run("bin/idmr info --no-bvh %s/scene.xml", out);
    assert_succeeded(&r);
    run_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_repeated_vertex),
        cmocka_unit_test(test_off_and_ply_repeated_vertex),
        cmocka_unit_test(test_scene_add_mesh_drops),
        cmocka_unit_test(test_write_refuses_repeated_vertex),
        cmocka_unit_test(test_stl_ascii),
        cmocka_unit_test(test_stl_binary),
        cmocka_unit_test(test_stl_damaged),
        cmocka_unit_test(test_ply_double_sided),
        cmocka_unit_test(test_ply_face_properties),
        cmocka_unit_test(test_ply_face_list_named_otherwise),
        cmocka_unit_test(test_importance_with_repeated_vertex),
        cmocka_unit_test(test_gltf_strip),
        cmocka_unit_test(test_reduce_stl),
    };
    return cmocka_run_group_tests_name("mesh_inputs", tests, make_temp, remove_temp);
}
