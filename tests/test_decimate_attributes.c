/* test_decimate_attributes.c — texture coordinates and normals through the reduction
 * (decimate.h, "Attributes"), on meshes whose right answer is known:
 *   - a flat grid with two texture charts that meet in a seam down its middle (the seam's
 *     vertices are split, one copy per chart, as an OBJ gives them): decimated with the seam
 *     kept, every corner's uv is still its chart's exact function of its position (nothing
 *     slid), no triangle mixes the charts, the seam stays a straight line split at every
 *     vertex, and the counts are per wedge; with the seam free the grid goes further;
 *   - a cube split at every edge to carry face normals (24 vertices) keeps all 24, each with its
 *     face's normal, and shapes_normals_flat() says it is flat (a sphere's radial normals: not);
 *   - a sphere with radial normals cut to a handful of vertices leaves every corner's normal on
 *     its triangle's front side (a renderer's interpolated normal never vanishes);
 *   - a PLY written with uv and normals reads back with the same values;
 *   - the attribute error term: on a flat grid whose texture map (or shading normals) bends in
 *     one half and is affine (constant) in the other, the combined method with the term keeps
 *     the bent half's vertices and slides the texture (bends the shading) less than half as much
 *     as without it, measured by interpolating the reduced mesh at the original faces' centres;
 *     on the seamed grid's affine charts nothing slides with the term either. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <unistd.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "core/shapes.h"

#define GRID 11       /* vertices per side of the grid */
#define SEAM_X 5.0f   /* the seam's line */
#define CHART_SHIFT 0.5f /* the right chart's u starts here */

/* The chart's uv at (x, y): left u = x / 20, right u = x / 20 + CHART_SHIFT; v = y / 20. */
static void chart_uv(int right, float x, float y, float uv[2])
{
    uv[0] = x / 20.0f + (right ? CHART_SHIFT : 0.0f);
    uv[1] = y / 20.0f;
}

/* The GRID x GRID unit grid in z = 0 with the column x = SEAM_X split: the faces left of it
 * use the left copies (left chart), the faces right of it the right copies. */
static void make_seamed_grid(mesh_data *m)
{
    memset(m, 0, sizeof *m);
    uint32_t count = GRID * GRID + GRID;
    m->positions = malloc(sizeof(float) * 3 * count);
    m->texcoords = malloc(sizeof(float) * 2 * count);
    m->indices = malloc(sizeof(uint32_t) * 6 * (GRID - 1) * (GRID - 1));
    uint32_t left_of[GRID * GRID], right_of[GRID * GRID];
    for (uint32_t g = 0; g < GRID * GRID; g++) {
        float x = (float)(g % GRID), y = (float)(g / GRID);
        for (int right = 0; right < 2; right++) {
            if (right && x != SEAM_X) {
                right_of[g] = left_of[g];
                continue;
            }
            uint32_t v = m->vertex_count++;
            m->positions[3 * v] = x, m->positions[3 * v + 1] = y, m->positions[3 * v + 2] = 0;
            chart_uv(right || x > SEAM_X, x, y, &m->texcoords[2 * v]);
            *(right ? &right_of[g] : &left_of[g]) = v;
        }
    }
    for (uint32_t j = 0; j + 1 < GRID; j++)
        for (uint32_t i = 0; i + 1 < GRID; i++) {
            const uint32_t *copy = (float)i >= SEAM_X ? right_of : left_of;
            uint32_t a = copy[j * GRID + i], b = copy[j * GRID + i + 1],
                     c = copy[(j + 1) * GRID + i + 1], d = copy[(j + 1) * GRID + i];
            uint32_t *ix = &m->indices[3 * (size_t)m->triangle_count];
            ix[0] = a, ix[1] = b, ix[2] = c, ix[3] = a, ix[4] = c, ix[5] = d;
            m->triangle_count += 2;
        }
}

static decimate_output decimate_grid(const mesh_data *grid, uint64_t target, int seams_free)
{
    double *importance = random_importance(grid->vertex_count, 3);
    decimate_input in = input_of("seamed grid", grid, importance, target);
    in.texcoords = grid->texcoords;
    in.seams_free = seams_free;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
    free(importance);
    return out;
}

/* Checks that every face lies on one side of the seam and each corner has its chart's uv. */
static void check_charts_intact(const mesh_data *m)
{
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        double centroid_x = 0;
        for (int k = 0; k < 3; k++)
            centroid_x += m->positions[3 * (size_t)ix[k]] / 3.0;
        int right = centroid_x > SEAM_X;
        for (int k = 0; k < 3; k++) {
            const float *p = &m->positions[3 * (size_t)ix[k]];
            float expected[2];
            chart_uv(right, p[0], p[1], expected);
            if (right ? p[0] < SEAM_X : p[0] > SEAM_X)
                fail_msg("triangle %u crosses the seam", t);
            if (fabsf(m->texcoords[2 * (size_t)ix[k]] - expected[0]) > 1e-6f ||
                fabsf(m->texcoords[2 * (size_t)ix[k] + 1] - expected[1]) > 1e-6f)
                fail_msg("triangle %u, corner %d at (%g, %g): uv (%g, %g), its chart's is "
                         "(%g, %g)",
                         t, k, p[0], p[1], m->texcoords[2 * (size_t)ix[k]],
                         m->texcoords[2 * (size_t)ix[k] + 1], expected[0], expected[1]);
        }
    }
}

/* Output vertices on the seam's line, and how many of them have a copy with the other chart's
 * uv at the same position. */
static void count_seam_copies(const mesh_data *m, uint32_t *on_seam, uint32_t *paired)
{
    *on_seam = *paired = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *p = &m->positions[3 * (size_t)v];
        if (p[0] != SEAM_X)
            continue;
        (*on_seam)++;
        for (uint32_t w = 0; w < m->vertex_count; w++)
            if (w != v && memcmp(p, &m->positions[3 * (size_t)w], 3 * sizeof(float)) == 0 &&
                m->texcoords[2 * (size_t)w] != m->texcoords[2 * (size_t)v])
                (*paired)++;
    }
}

static void test_seam_kept_charts_intact(void **state)
{
    (void)state;
    mesh_data grid;
    make_seamed_grid(&grid);
    assert_int_equal(grid.vertex_count, GRID * GRID + GRID);
    decimate_output out = decimate_grid(&grid, 30, 0);
    /* Counted per wedge: the seam's 11 positions twice. */
    assert_int_equal(out.vertices_welded, GRID * GRID + GRID);
    assert_non_null(out.mesh.texcoords);
    assert_null(out.mesh.normals);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    assert_int_equal(unreferenced_vertices(&out.mesh), 0);
    check_charts_intact(&out.mesh);
    uint32_t on_seam, paired;
    count_seam_copies(&out.mesh, &on_seam, &paired);
    print_message("seam kept, target 30: %u vertices, %u on the seam (%u with their twin)\n",
                  out.mesh.vertex_count, on_seam, paired);
    assert_true(on_seam >= 4); /* both ends, once per chart */
    assert_int_equal(paired, on_seam);
    assert_true(out.mesh.vertex_count <= 30);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

static void test_seam_kept_stops_where_free_goes_on(void **state)
{
    (void)state;
    mesh_data grid;
    make_seamed_grid(&grid);
    decimate_output kept = decimate_grid(&grid, 4, 0);
    decimate_output free_seams = decimate_grid(&grid, 4, 1);
    check_charts_intact(&kept.mesh);
    uint32_t on_seam, paired;
    count_seam_copies(&kept.mesh, &on_seam, &paired);
    print_message("target 4: seam kept %u vertices (%u on the seam), seam free %u\n",
                  kept.mesh.vertex_count, on_seam, free_seams.mesh.vertex_count);
    /* The grid's 4 corners and the seam's two ends, once per chart, stay. */
    assert_true(kept.mesh.vertex_count >= 8);
    assert_int_equal(paired, on_seam);
    assert_true(free_seams.mesh.vertex_count < kept.mesh.vertex_count);
    assert_int_equal(degenerate_faces(&free_seams.mesh), 0);
    decimate_output_free(&kept);
    decimate_output_free(&free_seams);
    mesh_data_free(&grid);
}

/* The cube [-1,1]^3 with 4 vertices per face, each carrying the face's normal. */
static void make_flat_cube(mesh_data *m)
{
    memset(m, 0, sizeof *m);
    m->vertex_count = 24, m->triangle_count = 12;
    m->positions = malloc(sizeof(float) * 72);
    m->normals = malloc(sizeof(float) * 72);
    m->indices = malloc(sizeof(uint32_t) * 36);
    for (int face = 0; face < 6; face++) {
        int axis = face / 2;
        float sign = face % 2 ? -1.0f : 1.0f;
        int u = (axis + 1) % 3, w = (axis + 2) % 3;
        static const float square[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int c = 0; c < 4; c++) {
            float *p = &m->positions[3 * (4 * face + c)], *n = &m->normals[3 * (4 * face + c)];
            p[axis] = sign, p[u] = square[c][0], p[w] = sign * square[c][1];
            n[axis] = sign, n[u] = 0, n[w] = 0;
        }
        uint32_t *ix = &m->indices[6 * face], base = 4 * (uint32_t)face;
        ix[0] = base, ix[1] = base + 1, ix[2] = base + 2;
        ix[3] = base, ix[4] = base + 2, ix[5] = base + 3;
    }
}

static void test_flat_cube_stays_flat(void **state)
{
    (void)state;
    mesh_data cube;
    make_flat_cube(&cube);
    assert_true(shapes_signed_volume(&cube) > 7.99);
    assert_int_equal(shapes_normals_flat(&cube), 1);
    double *importance = random_importance(cube.vertex_count, 5);
    decimate_input in = input_of("flat cube", &cube, importance, 8);
    in.normals = cube.normals;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
    /* Every corner is where three faces (wedges) meet: nothing may go. */
    assert_int_equal(out.mesh.vertex_count, 24);
    assert_int_equal(out.mesh.triangle_count, 12);
    assert_int_equal(shapes_normals_flat(&out.mesh), 1);
    decimate_output_free(&out);
    free(importance);

    mesh_data sphere;
    double center[3] = {0, 0, 0};
    shapes_sphere(center, 1.0, 8, 8, &sphere);
    assert_int_equal(shapes_normals_flat(&sphere), 0);
    mesh_data_free(&sphere);
    mesh_data_free(&cube);
}

/* Corners whose normal has a non-positive dot with their triangle's geometric normal. */
static uint32_t normals_behind(const mesh_data *m)
{
    uint32_t behind = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double g[3];
        face_normal(m, t, g);
        for (int k = 0; k < 3; k++) {
            const float *n = &m->normals[3 * (size_t)m->indices[3 * (size_t)t + k]];
            behind += !(g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0);
        }
    }
    return behind;
}

static void test_coarse_sphere_normals_face_out(void **state)
{
    (void)state;
    mesh_data sphere;
    double center[3] = {0, 0, 0};
    shapes_sphere(center, 1.0, 16, 16, &sphere);
    uint32_t worst = 0;
    for (unsigned int seed = 1; seed <= 10; seed++) {
        double *importance = random_importance(sphere.vertex_count, seed);
        decimate_input in = input_of("sphere", &sphere, importance, 5);
        in.normals = sphere.normals;
        in.max_normal_angle = 179.0;
        decimate_output out;
        assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
        assert_non_null(out.mesh.normals);
        uint32_t behind = normals_behind(&out.mesh);
        worst = behind > worst ? behind : worst;
        decimate_output_free(&out);
        free(importance);
    }
    print_message("sphere of %u vertices cut to 5, 10 importance fields: at most %u corner "
                  "normals behind their triangle\n",
                  sphere.vertex_count, worst);
    assert_int_equal(worst, 0);
    mesh_data_free(&sphere);
}

static void test_ply_keeps_uv_and_normals(void **state)
{
    (void)state;
    mesh_data cube;
    make_flat_cube(&cube);
    cube.texcoords = malloc(sizeof(float) * 48);
    for (int i = 0; i < 48; i++)
        cube.texcoords[i] = (float)i / 47.0f;
    char path[] = "/tmp/idmr-test-attributes-XXXXXX.ply";
    int fd = mkstemps(path, 4);
    assert_true(fd >= 0);
    close(fd);
    assert_int_equal(mesh_io_write_ply(path, &cube, NULL, NULL, NULL), 0);
    mesh_data back;
    assert_int_equal(mesh_io_read(path, &back), 0);
    unlink(path);
    assert_int_equal(back.vertex_count, 24);
    assert_non_null(back.texcoords);
    assert_non_null(back.normals);
    for (uint32_t v = 0; v < 24; v++) {
        for (int k = 0; k < 2; k++)
            assert_true(back.texcoords[2 * v + k] == cube.texcoords[2 * v + k]);
        for (int k = 0; k < 3; k++)
            assert_true(back.normals[3 * v + k] == cube.normals[3 * v + k]);
    }
    mesh_data_free(&back);
    mesh_data_free(&cube);
}

/* The attribute term's grid: TERM_GRID x TERM_GRID vertices at integer (x, y), z = 0. Left of
 * x = TERM_BEND the attributes bend (u gets, the normals tilt by, a sine in x times one in y),
 * right of it they are affine (the normals constant). */
#define TERM_GRID 21
#define TERM_BEND 10.0

static double bend(double x, double y)
{
    return x < TERM_BEND ? sin(M_PI * x / (TERM_BEND / 2)) * sin(M_PI * y / 10) : 0.0;
}

static void bent_uv(double x, double y, float uv[2])
{
    uv[0] = (float)(x / 20.0 + 0.04 * bend(x, y));
    uv[1] = (float)(y / 20.0);
}

static void bent_normal(double x, double y, float n[3])
{
    double tilt = 0.4 * bend(x, y), length = sqrt(1.0 + tilt * tilt);
    n[0] = (float)(tilt / length), n[1] = 0, n[2] = (float)(1.0 / length);
}

/* The attribute (`floats` per vertex) the flat mesh m shows at (x, y): barycentric
 * interpolation in the triangle holding the point. Fails when none does. */
static void interpolate_at(const mesh_data *m, const float *values, int floats, double x,
                           double y, double *out)
{
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        const float *a = &m->positions[3 * ix[0]], *b = &m->positions[3 * ix[1]],
                    *c = &m->positions[3 * ix[2]];
        double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if (det == 0)
            continue;
        double l1 = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
        double l2 = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
        double l0 = 1 - l1 - l2;
        if (l0 < -1e-9 || l1 < -1e-9 || l2 < -1e-9)
            continue;
        for (int k = 0; k < floats; k++)
            out[k] = l0 * values[floats * ix[0] + k] + l1 * values[floats * ix[1] + k] +
                     l2 * values[floats * ix[2] + k];
        return;
    }
    fail_msg("(%g, %g) lies in no triangle of the reduced grid", x, y);
}

typedef struct term_result {
    double rms_change;      /* of the attribute at the original faces' centres */
    uint32_t bent_vertices; /* output vertices with x < TERM_BEND */
} term_result;

/* Decimates the grid with uv (uv = 1) or normals (uv = 0) to a quarter of its vertices,
 * combined, importance uniform, with the attribute weight `weight`; measures what changed. */
static term_result reduce_bent_grid(int uv, double weight)
{
    mesh_data grid;
    make_grid(TERM_GRID, 0, &grid);
    int floats = uv ? 2 : 3;
    float *values = malloc(sizeof(float) * floats * grid.vertex_count);
    double *importance = malloc(sizeof(double) * grid.vertex_count);
    for (uint32_t v = 0; v < grid.vertex_count; v++) {
        const float *p = &grid.positions[3 * v];
        if (uv)
            bent_uv(p[0], p[1], &values[2 * v]);
        else
            bent_normal(p[0], p[1], &values[3 * v]);
        importance[v] = 1.0;
    }
    decimate_input in = input_of("bent grid", &grid, importance, grid.vertex_count / 4);
    if (uv) {
        in.texcoords = values;
        in.uv_weight = weight;
    } else {
        in.normals = values;
        in.normal_weight = weight;
    }
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
    assert_true(out.mesh.vertex_count <= grid.vertex_count / 4);
    const float *reduced = uv ? out.mesh.texcoords : out.mesh.normals;
    assert_non_null(reduced);
    term_result r = {0, 0};
    for (uint32_t t = 0; t < grid.triangle_count; t++) {
        const uint32_t *ix = &grid.indices[3 * (size_t)t];
        double x = 0, y = 0, before[3] = {0}, after[3];
        for (int c = 0; c < 3; c++) {
            x += grid.positions[3 * ix[c]] / 3.0, y += grid.positions[3 * ix[c] + 1] / 3.0;
            for (int k = 0; k < floats; k++)
                before[k] += values[floats * ix[c] + k] / 3.0;
        }
        interpolate_at(&out.mesh, reduced, floats, x, y, after);
        for (int k = 0; k < floats; k++)
            r.rms_change += (after[k] - before[k]) * (after[k] - before[k]);
    }
    r.rms_change = sqrt(r.rms_change / grid.triangle_count);
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++)
        r.bent_vertices += out.mesh.positions[3 * v] < TERM_BEND;
    decimate_output_free(&out);
    free(importance);
    free(values);
    mesh_data_free(&grid);
    return r;
}

static void check_term_helps(int uv, double weight)
{
    term_result without = reduce_bent_grid(uv, 0), with = reduce_bent_grid(uv, weight);
    printf("%s: change %.5f without the term, %.5f with it (weight %g); vertices left of the "
           "bend %u and %u\n",
           uv ? "uv" : "normals", without.rms_change, with.rms_change, weight,
           without.bent_vertices, with.bent_vertices);
    assert_true(with.rms_change < 0.5 * without.rms_change);
    assert_true(with.bent_vertices > without.bent_vertices);
}

static void test_uv_term_keeps_texture_in_place(void **state)
{
    (void)state;
    check_term_helps(1, DECIMATE_UV_WEIGHT);
}

static void test_normal_term_keeps_shading(void **state)
{
    (void)state;
    check_term_helps(0, DECIMATE_NORMAL_WEIGHT);
}

/* The seamed grid's charts are affine: with the term, nothing slides there either. */
static void test_uv_term_zero_on_affine_charts(void **state)
{
    (void)state;
    mesh_data grid;
    make_seamed_grid(&grid);
    double *importance = random_importance(grid.vertex_count, 3);
    decimate_input in = input_of("seamed grid", &grid, importance, grid.vertex_count / 2);
    in.texcoords = grid.texcoords;
    in.uv_weight = DECIMATE_UV_WEIGHT;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_COMBINED, &out), 0);
    assert_true(out.mesh.vertex_count <= grid.vertex_count / 2);
    check_charts_intact(&out.mesh);
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&grid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seam_kept_charts_intact),
        cmocka_unit_test(test_seam_kept_stops_where_free_goes_on),
        cmocka_unit_test(test_flat_cube_stays_flat),
        cmocka_unit_test(test_coarse_sphere_normals_face_out),
        cmocka_unit_test(test_ply_keeps_uv_and_normals),
        cmocka_unit_test(test_uv_term_keeps_texture_in_place),
        cmocka_unit_test(test_normal_term_keeps_shading),
        cmocka_unit_test(test_uv_term_zero_on_affine_charts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
