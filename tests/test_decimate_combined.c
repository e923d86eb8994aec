/* test_decimate_combined.c — the combined method's own checks (DECIMATE_COMBINED, the weighted
 * quadric module of decimate_modules.hh), on meshes whose right answer is known:
 *   - a flat picture frame (a square with a square opening) cut to a few per cent of its
 *     vertices keeps its outline and its opening: every boundary edge still lies on one of the
 *     eight sides, the eight corners survive, the area is the frame's, the opening stays open
 *     and the frame stays covered (what the living room's walls and frames lost, issue 11),
 *     and asked for fewer vertices than its corners it stops there;
 *   - importance decides where the detail goes: on a bumpy sheet with all importance on one
 *     half, that half keeps most of the vertices; with uniform importance the split is even. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "decimate_common.h"

/* A frame in the plane z = 0: the grid [0, size-1]^2 of unit cells without the cells of the
 * opening [lo, hi]^2. Vertices no face uses are left out. */
static void make_frame(unsigned int size, unsigned int lo, unsigned int hi, mesh_data *m)
{
    memset(m, 0, sizeof *m);
    uint32_t *index_of = malloc(sizeof(uint32_t) * size * size);
    for (unsigned int v = 0; v < size * size; v++)
        index_of[v] = UINT32_MAX;
    m->positions = malloc(sizeof(float) * 3 * size * size);
    m->indices = malloc(sizeof(uint32_t) * 6 * (size - 1) * (size - 1));
    for (unsigned int j = 0; j + 1 < size; j++)
        for (unsigned int i = 0; i + 1 < size; i++) {
            if (i >= lo && i < hi && j >= lo && j < hi)
                continue;
            uint32_t corner[4] = {j * size + i, j * size + i + 1, (j + 1) * size + i + 1,
                                  (j + 1) * size + i};
            for (int k = 0; k < 4; k++) {
                uint32_t g = corner[k];
                if (index_of[g] == UINT32_MAX) {
                    float *p = &m->positions[3 * (size_t)m->vertex_count];
                    p[0] = (float)(g % size), p[1] = (float)(g / size), p[2] = 0;
                    index_of[g] = m->vertex_count++;
                }
                corner[k] = index_of[g];
            }
            uint32_t *ix = &m->indices[3 * (size_t)m->triangle_count];
            ix[0] = corner[0], ix[1] = corner[1], ix[2] = corner[2];
            ix[3] = corner[0], ix[4] = corner[2], ix[5] = corner[3];
            m->triangle_count += 2;
        }
    free(index_of);
}

/* Signed area of triangle t in the xy plane. */
static double signed_area_xy(const mesh_data *m, uint32_t t)
{
    const uint32_t *ix = &m->indices[3 * (size_t)t];
    const float *a = &m->positions[3 * (size_t)ix[0]], *b = &m->positions[3 * (size_t)ix[1]],
                *c = &m->positions[3 * (size_t)ix[2]];
    return 0.5 * (((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                  ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
}

/* Whether some triangle of m covers the point (x, y) (inside or on its edges). */
static int covered(const mesh_data *m, double x, double y)
{
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        double s[3];
        for (int k = 0; k < 3; k++) {
            const float *a = &m->positions[3 * (size_t)ix[k]];
            const float *b = &m->positions[3 * (size_t)ix[(k + 1) % 3]];
            s[k] = ((double)b[0] - a[0]) * (y - a[1]) - ((double)b[1] - a[1]) * (x - a[0]);
        }
        if ((s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0))
            return 1;
    }
    return 0;
}

/* The side of the frame (0..3 outer: x = 0, x = e, y = 0, y = e; 4..7 the opening's: x = lo,
 * x = hi, y = lo, y = hi) that both points lie on, or -1. */
static int shared_side(const float *a, const float *b, float e, float lo, float hi)
{
    const float line[8] = {0, e, 0, e, lo, hi, lo, hi};
    for (int k = 0; k < 8; k++) {
        int axis = k % 4 < 2 ? 0 : 1;
        float other_lo = k < 4 ? 0 : lo, other_hi = k < 4 ? e : hi;
        int on = 1;
        for (const float *p = a; on && p; p = p == a ? b : NULL)
            on = p[axis] == line[k] && p[1 - axis] >= other_lo && p[1 - axis] <= other_hi;
        if (on)
            return k;
    }
    return -1;
}

/* Edges used by exactly one triangle, as vertex pairs into *pairs (malloc'd); their count. */
static size_t boundary_edges(const mesh_data *m, uint32_t **pairs)
{
    size_t corners = 3 * (size_t)m->triangle_count, count = 0;
    *pairs = malloc(sizeof(uint32_t) * 2 * (corners + 1));
    for (size_t c = 0; c < corners; c++) {
        uint32_t a = m->indices[c], b = m->indices[c - c % 3 + (c % 3 + 1) % 3];
        int uses = 0;
        for (size_t d = 0; d < corners; d++) {
            uint32_t p = m->indices[d], q = m->indices[d - d % 3 + (d % 3 + 1) % 3];
            uses += (p == a && q == b) || (p == b && q == a);
        }
        if (uses == 1) {
            (*pairs)[2 * count] = a;
            (*pairs)[2 * count + 1] = b;
            count++;
        }
    }
    return count;
}

/* The frame decimated by `method` with uniform importance to `target` vertices, the boundary
 * lock at `tolerance` (0: the default). */
static void decimate_frame_locked(decimate_method method, uint64_t target, double tolerance,
                                  mesh_data *frame, decimate_output *out)
{
    make_frame(33, 10, 22, frame);
    double *importance = malloc(sizeof(double) * frame->vertex_count);
    for (uint32_t v = 0; v < frame->vertex_count; v++)
        importance[v] = 1.0;
    decimate_input in = input_of("frame", frame, importance, target);
    in.boundary_tolerance = tolerance;
    assert_int_equal(decimate_mesh(&in, method, out), 0);
    free(importance);
}

static void decimate_frame(decimate_method method, uint64_t target, mesh_data *frame,
                           decimate_output *out)
{
    decimate_frame_locked(method, target, 0, frame, out);
}

/* The frame cut from 968 vertices towards `target` keeps its outline, its area and its
 * opening, and ends with between `fewest` and `most` vertices. */
static void check_frame(uint64_t target, uint32_t fewest, uint32_t most)
{
    mesh_data frame;
    decimate_output out;
    decimate_frame(DECIMATE_COMBINED, target, &frame, &out);
    const mesh_data *m = &out.mesh;
    print_message("asked for %u vertices: %u\n", (unsigned)target, m->vertex_count);
    assert_true(m->vertex_count >= fewest && m->vertex_count <= most);
    assert_int_equal(degenerate_faces(m), 0);

    double area = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double a = signed_area_xy(m, t);
        assert_true(a > 0); /* none turned over */
        area += a;
    }
    assert_float_equal(area, 32.0 * 32.0 - 12.0 * 12.0, 1e-3);

    uint32_t *pairs;
    size_t edges = boundary_edges(m, &pairs);
    for (size_t e = 0; e < edges; e++) {
        const float *a = &m->positions[3 * (size_t)pairs[2 * e]];
        const float *b = &m->positions[3 * (size_t)pairs[2 * e + 1]];
        if (shared_side(a, b, 32, 10, 22) < 0)
            fail_msg("boundary edge (%g, %g)-(%g, %g) left the frame's outline", a[0], a[1], b[0],
                     b[1]);
    }
    free(pairs);

    const float corner[8][2] = {{0, 0}, {32, 0}, {0, 32}, {32, 32},
                                {10, 10}, {22, 10}, {10, 22}, {22, 22}};
    for (int k = 0; k < 8; k++) {
        int found = 0;
        for (uint32_t v = 0; v < m->vertex_count; v++)
            found |= m->positions[3 * v] == corner[k][0] && m->positions[3 * v + 1] == corner[k][1];
        if (!found)
            fail_msg("corner (%g, %g) was collapsed", corner[k][0], corner[k][1]);
    }

    /* The opening stays open right up to its sides; the frame stays covered next to them. */
    const double open[] = {16, 16, 10.05, 10.05, 21.95, 16, 16, 21.95};
    const double solid[] = {9.95, 16, 16, 22.05, 0.05, 0.05, 31.95, 31.95, 9.95, 9.95};
    for (size_t k = 0; k < sizeof open / sizeof open[0]; k += 2)
        assert_false(covered(m, open[k], open[k + 1]));
    for (size_t k = 0; k < sizeof solid / sizeof solid[0]; k += 2)
        assert_true(covered(m, solid[k], solid[k + 1]));
    decimate_output_free(&out);
    mesh_data_free(&frame);
}

/* Cut to 24 vertices (the eight corners and a few more), the frame keeps its outline, its area
 * and its opening. */
static void test_frame_keeps_outline_and_opening(void **state) { check_frame(24, 8, 24); }

/* Asked for 4 vertices, fewer than its eight corners, it stops where the outline would break
 * (the boundary lock) rather than cut a corner or cover the opening. */
static void test_frame_stops_at_its_corners(void **state) { check_frame(4, 8, 16); }

/* With the lock off (infinite tolerance, what reduce comes to when a scene's total cannot be met
 * otherwise), the frame goes below its corners. */
static void test_frame_unlocked_goes_below_its_corners(void **state)
{
    mesh_data frame;
    decimate_output out;
    decimate_frame_locked(DECIMATE_COMBINED, 6, INFINITY, &frame, &out);
    print_message("unlocked, asked for 6: %u\n", out.mesh.vertex_count);
    assert_true(out.mesh.vertex_count < 8);
    decimate_output_free(&out);
    mesh_data_free(&frame);
}

/* A sheet 41 x 41 with bumps on every inner vertex (so every collapse costs something) and a
 * straight, flat outline (which the boundary lock lets thin out), and the number of decimated
 * vertices left of x = 20 and right of it. */
static void split_after_decimation(double left_importance, double right_importance,
                                   uint32_t *left, uint32_t *right)
{
    mesh_data sheet;
    make_grid(41, 0, &sheet);
    double *importance = malloc(sizeof(double) * sheet.vertex_count);
    for (uint32_t v = 0; v < sheet.vertex_count; v++) {
        float *p = &sheet.positions[3 * v];
        int border = p[0] == 0 || p[0] == 40 || p[1] == 0 || p[1] == 40;
        p[2] = border ? 0.0f : (float)(0.3 * sin(1.3 * p[0]) * cos(0.9 * p[1]));
        importance[v] = p[0] < 20   ? left_importance
                        : p[0] > 20 ? right_importance
                                    : 0.5 * (left_importance + right_importance);
    }
    decimate_input in = input_of("sheet", &sheet, importance, sheet.vertex_count / 8);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    *left = *right = 0;
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++) {
        float x = out.mesh.positions[3 * v];
        *left += x < 20;
        *right += x > 20;
    }
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&sheet);
}

/* All importance on the left half: the left keeps at least three times the right's vertices.
 * Uniform importance: the halves keep the same within 25 %. */
static void test_importance_decides_where_detail_stays(void **state)
{
    (void)state;
    uint32_t left, right;
    split_after_decimation(1.0, 0.0, &left, &right);
    print_message("importance on the left: %u left, %u right\n", left, right);
    assert_true(left >= 3 * right);
    split_after_decimation(1.0, 1.0, &left, &right);
    print_message("uniform importance: %u left, %u right\n", left, right);
    assert_true(fabs((double)left - right) <= 0.25 * (left + right) / 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_keeps_outline_and_opening),
        cmocka_unit_test(test_frame_stops_at_its_corners),
        cmocka_unit_test(test_frame_unlocked_goes_below_its_corners),
        cmocka_unit_test(test_importance_decides_where_detail_stays),
    };
    return cmocka_run_group_tests_name("decimate_combined", tests, NULL, NULL);
}
