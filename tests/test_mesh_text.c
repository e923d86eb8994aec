/* test_mesh_text.c — the strict OBJ and OFF readers (host/io/mesh/mesh_text.h) through
 * mesh_io_read(), on files written here: what a well-formed file gives (fan-triangulated
 * polygons, negative indices, one vertex per distinct OBJ corner, attributes where the file has
 * them) and that every malformed file OpenMesh used to read wrongly without a word (a NaN
 * vertex, an index out of range, an OFF header that claims more than the file holds) is an
 * input error naming the file and line. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "io/mesh/mesh_io.h"

static char temp_dir[64];

static int make_temp_dir(void **state)
{
    return temp_dir_make(temp_dir, "mesh-text");
}

static int remove_temp_dir(void **state)
{
    return temp_dir_remove(temp_dir);
}

/* Reads `text` written as temp_dir/name; fails the test when the read fails. */
static void read_ok(const char *name, const char *text, mesh_data *mesh)
{
    const char *path = write_text(temp_dir, name, text);
    error_clear();
    if (mesh_io_read(path, mesh))
        fail_msg("reading %s failed: %s", name, error_message());
}

/* Reading `text` as temp_dir/name fails with an input error whose message names the file and
 * holds `what` (and `line`, e.g. "line 3", when not NULL). */
static void read_fails(const char *name, const char *text, const char *line, const char *what)
{
    mesh_data mesh;
    const char *path = write_text(temp_dir, name, text);
    error_clear();
    assert_int_equal(mesh_io_read(path, &mesh), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    const char *message = error_message();
    if (!strstr(message, name) || !strstr(message, what) || (line && !strstr(message, line)))
        fail_msg("message '%s' lacks the file, '%s' or '%s'", message, what, line ? line : "");
    assert_null(mesh.positions);
}

/* ---- OBJ ---- */

/* A quad and a pentagon (negative indices) are fan-triangulated: 2 + 3 triangles, the
 * pentagon's around its first corner. */
static void test_obj_polygons_and_negative_indices(void **state)
{
    mesh_data m;
    read_ok("polygons.obj",
            "# two polygons\n"
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
            "f 1 2 3 4\n"
            "v 2 0 0\nv 3 0 0\nv 3 1 0\nv 2.5 2 0\nv 2 1 0\n"
            "f -5 -4 -3 -2 -1\n",
            &m);
    assert_int_equal(m.triangle_count, 5);
    assert_int_equal(m.vertex_count, 9);
    static const uint32_t expected[15] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7, 4, 7, 8};
    assert_memory_equal(m.indices, expected, sizeof expected);
    assert_float_equal(m.positions[3 * 7], 2.5f, 0);
    assert_float_equal(m.positions[3 * 7 + 1], 2.0f, 0);
    assert_null(m.texcoords);
    assert_null(m.normals);
    mesh_data_free(&m);
}

/* A vertex with two texture coordinates (a seam) becomes two vertices; a corner repeated with
 * the same (v, vt, vn) stays one. Corners without a normal, in a file that has normals, get a
 * zero normal; vt's third value is ignored. */
static void test_obj_one_vertex_per_distinct_corner(void **state)
{
    mesh_data m;
    read_ok("seam.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
            "vt 0 0\nvt 1 0\nvt 0 1 0.5\nvt 0.5 0.5\n"
            "vn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1\n"
            "f 2/4 4/2 3/3\n",
            &m);
    assert_int_equal(m.triangle_count, 2);
    /* Corners: (1,1,1) (2,2,1) (3,3,1) (2,4,-) (4,2,-) (3,3,-): six distinct. */
    assert_int_equal(m.vertex_count, 6);
    assert_non_null(m.texcoords);
    assert_non_null(m.normals);
    assert_float_equal(m.texcoords[2 * 3], 0.5f, 0); /* vertex 2's second corner: vt 4 */
    assert_float_equal(m.normals[3 * 0 + 2], 1.0f, 0);
    assert_float_equal(m.normals[3 * 3 + 2], 0.0f, 0); /* no vn given there */
    for (int k = 0; k < 3; k++)
        assert_float_equal(m.positions[3 * 3 + k], m.positions[3 * 1 + k], 0);
    mesh_data_free(&m);

    read_ok("shared.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n", &m);
    assert_int_equal(m.vertex_count, 4);
    mesh_data_free(&m);
}

/* A vertex that is used by no face is not part of the mesh (Mitsuba 3 drops it too). */
static void test_obj_unused_vertices_dropped(void **state)
{
    mesh_data m;
    read_ok("unused.obj", "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 2 3 4\n", &m);
    assert_int_equal(m.vertex_count, 3);
    assert_float_equal(m.positions[0], 0.0f, 0);
    mesh_data_free(&m);
}

/* OpenMesh skipped a NaN vertex line, so later indices named the wrong vertices. */
static void test_obj_nan_vertex_is_an_error(void **state)
{
    read_fails("nan.obj", "v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 4\n", "line 2",
               "'nan' is not a finite number");
    read_fails("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n", "line 3", "not a finite");
    read_fails("word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n", "line 3", "'x'");
}

/* Indices out of range (too large, 0, a forward reference) were dropped without a word. */
static void test_obj_index_errors(void **state)
{
    read_fails("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n", "line 5",
               "vertex index 7 is out of range (3 defined");
    read_fails("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4", "index 0");
    read_fails("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "line 4",
               "index -4");
    read_fails("forward.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", "line 3",
               "index 3 is out of range (2 defined");
    read_fails("texcoord.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", "line 5",
               "texture coordinate index 2");
    read_fails("letters.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n", "line 4",
               "not a vertex index");
}

static void test_obj_malformed_statements(void **state)
{
    read_fails("short.obj", "v 0 0\n", "line 1", "a vertex (v) needs 3 numbers");
    read_fails("two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4", "has 2");
    read_fails("empty.obj", "# nothing\nv 0 0 0\n", NULL, "has no faces");
}

/* A UTF-8 byte-order mark before the first statement (as editors on Windows write it) is not
 * part of the statement: it once made "v" an unknown keyword and the faces' indices errors. */
static void test_byte_order_mark(void **state)
{
    mesh_data m;
    read_ok("bom.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &m);
    assert_int_equal(m.vertex_count, 3);
    assert_int_equal(m.triangle_count, 1);
    mesh_data_free(&m);
    read_ok("bom.off", "\xEF\xBB\xBFOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", &m);
    assert_int_equal(m.triangle_count, 1);
    mesh_data_free(&m);
    read_fails("bom-later.obj", "v 0 0 0\n\xEF\xBB\xBFv 1 0 0\n", "line 2", "");
}

/* ---- OFF ---- */

/* Counts on the header's line or the next, comments, a quad, COFF's colours ignored. */
static void test_off_reads(void **state)
{
    mesh_data m;
    read_ok("quad.off",
            "OFF\n# a quad and a triangle\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 0\n"
            "4 0 1 2 3\n3 1 4 2\n",
            &m);
    assert_int_equal(m.vertex_count, 5);
    assert_int_equal(m.triangle_count, 3);
    static const uint32_t expected[9] = {0, 1, 2, 0, 2, 3, 1, 4, 2};
    assert_memory_equal(m.indices, expected, sizeof expected);
    mesh_data_free(&m);

    read_ok("colour.off", "COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
                          "3 0 1 2 200 200 200\n",
            &m);
    assert_int_equal(m.triangle_count, 1);
    assert_float_equal(m.positions[3], 1.0f, 0);
    mesh_data_free(&m);
}

/* OpenMesh believed a header that claimed 1.2 million faces for a file holding 2. */
static void test_off_errors(void **state)
{
    read_fails("claims.off", "OFF\n4 1200000 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n",
               NULL, "its header says 1200000 faces, the file holds 2");
    read_fails("vertices.off", "OFF\n5 1 0\n0 0 0\n1 0 0\n", NULL,
               "its header says 5 vertices, the file holds 2");
    read_fails("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6",
               "not a vertex index from 0 to 2");
    read_fails("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "line 4",
               "not a finite number");
    read_fails("header.off", "PLY\n3 1 0\n", NULL, "not an OFF file");
    read_fails("counts.off", "OFF\n3.5 1 0\n", "line 2", "whole numbers");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_polygons_and_negative_indices),
        cmocka_unit_test(test_obj_one_vertex_per_distinct_corner),
        cmocka_unit_test(test_obj_unused_vertices_dropped),
        cmocka_unit_test(test_obj_nan_vertex_is_an_error),
        cmocka_unit_test(test_obj_index_errors),
        cmocka_unit_test(test_obj_malformed_statements),
        cmocka_unit_test(test_byte_order_mark),
        cmocka_unit_test(test_off_reads),
        cmocka_unit_test(test_off_errors),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
