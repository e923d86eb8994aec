/* test_collapse.c — the collapse engine (host/reduce/collapse.h) on its own and against the
 * reference (decimate_reference_mesh, OpenMesh's decimater under our heap):
 *
 *   rules      collapse_evaluate on hand-drawn meshes, each answer worked out below:
 *              a flat fan (the centre's collapse costs 0, its ring sum is known), a spike (the
 *              normal limit), a boundary vertex into an inner one, a tetrahedron (the two
 *              joined valence-3 vertices), a locked vertex, the boundary lock, a fan of 100
 *              triangles (its centre's ring), a seam that ends at the centre; a triangle
 *              naming a vertex twice refused
 *   fans       collapse_one_fan on hand-drawn corners (a closed and an open fan in any order,
 *              two fans, a directed edge twice) and against its definition on random ones, and
 *              the engine given fans it must check: it
 *              stops before any collapse on two tetrahedra sharing a vertex, and takes the
 *              same collapses as with fans checked on the bunny
 *   threads    the dragon (res 2) decimated on 1, 2 and 7 threads, with and without normals:
 *              the same bytes
 *   reference  the bunny to 10 % by engine and reference, quadric and combined: the mean
 *              distance from the original vertices to the reduced surface within 1.25 x the
 *              reference's (the engine takes collapses in passes, not one at a time, so it may
 *              differ a little, and must not be worse than that) */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "reduce/collapse.h"
#include "reduce/weld.h"

/* ---- hand-drawn meshes ---- */

/* A fan: centre 0 at the origin, six rim vertices 1..6 on the unit circle at 60° steps, six
 * triangles (0, k, k+1), counter-clockwise seen from +z. The centre's ring holds all six. */
static float fan_positions[7 * 3];
static uint32_t fan_triangles[6 * 3];

static void make_fan(float centre_height)
{
    fan_positions[0] = fan_positions[1] = 0;
    fan_positions[2] = centre_height;
    for (int k = 0; k < 6; k++) {
        fan_positions[3 * (k + 1) + 0] = (float)cos(k * M_PI / 3);
        fan_positions[3 * (k + 1) + 1] = (float)sin(k * M_PI / 3);
        fan_positions[3 * (k + 1) + 2] = 0;
        fan_triangles[3 * k + 0] = 0;
        fan_triangles[3 * k + 1] = 1 + k;
        fan_triangles[3 * k + 2] = 1 + (k + 1) % 6;
    }
}

/* A mesh of these vertices and triangles, nothing else set. */
static collapse_mesh mesh_of(uint32_t vertex_count, const float *positions,
                             uint32_t triangle_count, uint32_t *triangles)
{
    collapse_mesh m;
    memset(&m, 0, sizeof m);
    m.vertex_count = vertex_count;
    m.positions = positions;
    m.triangle_count = triangle_count;
    m.triangles = triangles;
    return m;
}

static collapse_mesh fan_mesh(const double *importance, const uint8_t *locked)
{
    collapse_mesh m = mesh_of(7, fan_positions, 6, fan_triangles);
    m.importance = importance;
    m.locked = locked;
    return m;
}

static collapse_options options_of(decimate_method method)
{
    collapse_options o;
    memset(&o, 0, sizeof o);
    o.method = method;
    o.max_normal_angle = 60;
    o.boundary_tolerance = DECIMATE_BOUNDARY_TOLERANCE;
    o.threads = 1;
    return o;
}

/* Evaluates v0 -> v1; expects `legal`, and when it is not, the rule named. */
static double expect(const collapse_mesh *m, decimate_method method, uint32_t v0, uint32_t v1,
                     int legal, const char *rule)
{
    collapse_options o = options_of(method);
    double cost = -1;
    const char *why = NULL;
    int status = collapse_evaluate(m, &o, v0, v1, &cost, &why);
    if (status != legal)
        fail_msg("%u -> %u: expected %s, got %s (%s)", v0, v1, legal ? "legal" : "illegal",
                 status == 1 ? "legal" : status == 0 ? "illegal" : "an error",
                 why ? why : error_message());
    if (!legal && rule && strcmp(why, rule) != 0)
        fail_msg("%u -> %u: expected rule '%s', got '%s'", v0, v1, rule, why);
    return cost;
}

/* Flat fan: the centre moves onto rim vertex 1 without leaving the plane, so every plane
 * quadric gives 0; the ring sum is 1 + 2 + ... + 7 = 28 with importance k + 1 at vertex k. A rim
 * vertex may go along the rim (rim 1 -> rim 2) but not into the centre (a boundary vertex off
 * the boundary). */
static void test_flat_fan(void **state)
{
    make_fan(0);
    double importance[7] = {1, 2, 3, 4, 5, 6, 7};
    collapse_mesh m = fan_mesh(importance, NULL);
    assert_true(expect(&m, DECIMATE_QUADRIC, 0, 1, 1, NULL) == 0.0);
    assert_true(fabs(expect(&m, DECIMATE_COMBINED, 0, 1, 1, NULL)) < 1e-12);
    assert_true(expect(&m, DECIMATE_IMPORTANCE, 0, 1, 1, NULL) == 28.0);
    expect(&m, DECIMATE_QUADRIC, 1, 0, 0, "boundary vertex off the boundary");
    expect(&m, DECIMATE_QUADRIC, 0, 0, 0, "not an edge");
    /* Rim vertex 1 -> 2 along the rim: legal for QUADRIC (the outline changes) ... */
    expect(&m, DECIMATE_QUADRIC, 1, 2, 1, NULL);
    /* ... but COMBINED's boundary lock keeps the outline: vertex 1 lies 0.5 from the chord
     * 6-2 (length sqrt(3)), far beyond 1 %. */
    expect(&m, DECIMATE_COMBINED, 1, 2, 0, "boundary lock");
    uint8_t locked[7] = {1, 0, 0, 0, 0, 0, 0};
    collapse_mesh held = fan_mesh(importance, locked);
    expect(&held, DECIMATE_QUADRIC, 0, 1, 0, "locked");
}

/* A spike: the centre raised to height h. Moving it onto rim vertex 1 lays triangle (0, 3, 4)
 * (the one opposite) flat: its normal turns from (its tilt) to +z. The tilt of a face whose
 * outer edge is at distance cos 30° from the centre's foot is atan(h / cos 30°): at h = 2 it is
 * 66.6°, beyond the 60° limit; at h = 0.1 it is 6.6°, within it. The quadric cost at h = 0.1:
 * each face's plane weighted by its area, evaluated at rim vertex 1, which lies on the planes
 * of faces 0 and 5 (its own) and off the other four. */
static void test_spike(void **state)
{
    make_fan(2.0f);
    collapse_mesh m = fan_mesh(NULL, NULL);
    expect(&m, DECIMATE_QUADRIC, 0, 1, 0, "normal limit");
    make_fan(0.1f);
    double cost = expect(&m, DECIMATE_QUADRIC, 0, 1, 1, NULL);
    /* The same sum, by hand: sum over faces of area x (n . p1 + d)^2. */
    double expected = 0;
    for (int k = 0; k < 6; k++) {
        const float *a = &fan_positions[3 * fan_triangles[3 * k]],
                    *b = &fan_positions[3 * fan_triangles[3 * k + 1]],
                    *c = &fan_positions[3 * fan_triangles[3 * k + 2]];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
               e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const float *p = &fan_positions[3];
        double distance =
            (n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) + n[2] * (p[2] - a[2])) / length;
        expected += 0.5 * length * distance * distance;
    }
    assert_true(expected > 0);
    assert_true(fabs(cost - expected) <= 1e-9 * expected);
}

/* A wide flat fan: centre 0 and WIDE_RIM rim vertices, more than a ring is built from on the
 * stack (build_ring copies a vertex's half-edges aside first, beyond 64 into its scratch). The
 * centre's ring must hold every rim vertex once: the ring sum with importance k + 1 at vertex k
 * is 1 + 2 + ... + (WIDE_RIM + 1), and the flat collapse costs 0. */
#define WIDE_RIM 100
static void test_wide_fan(void **state)
{
    float positions[3 * (WIDE_RIM + 1)] = {0};
    uint32_t triangles[3 * WIDE_RIM];
    double importance[WIDE_RIM + 1];
    for (int k = 0; k <= WIDE_RIM; k++)
        importance[k] = k + 1;
    for (int k = 0; k < WIDE_RIM; k++) {
        positions[3 * (k + 1) + 0] = (float)cos(2 * M_PI * k / WIDE_RIM);
        positions[3 * (k + 1) + 1] = (float)sin(2 * M_PI * k / WIDE_RIM);
        triangles[3 * k + 0] = 0;
        triangles[3 * k + 1] = 1 + k;
        triangles[3 * k + 2] = 1 + (k + 1) % WIDE_RIM;
    }
    collapse_mesh m = mesh_of(WIDE_RIM + 1, positions, WIDE_RIM, triangles);
    m.importance = importance;
    assert_true(expect(&m, DECIMATE_IMPORTANCE, 0, 1, 1, NULL) ==
                (WIDE_RIM + 1) * (WIDE_RIM + 2) / 2.0);
    assert_true(expect(&m, DECIMATE_QUADRIC, 0, WIDE_RIM / 2, 1, NULL) == 0.0);
    expect(&m, DECIMATE_QUADRIC, 1, 0, 0, "boundary vertex off the boundary");
}

/* A tetrahedron: every vertex has valence 3 and every collapse would fold it flat. Collapsing 0
 * into 1: the opposite vertices 2 and 3 are joined and both of valence 3. */
static void test_tetrahedron(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t triangles[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    collapse_mesh m = mesh_of(4, positions, 4, triangles);
    expect(&m, DECIMATE_QUADRIC, 0, 1, 0, "two joined valence-3 vertices");
    /* The engine takes none of them: the mesh stays whole. */
    collapse_options o = options_of(DECIMATE_QUADRIC);
    uint32_t history[4];
    collapse_result r = {.collapsed_into = history};
    assert_int_equal(collapse_run(&m, &o, &r), 0);
    assert_int_equal(r.collapses, 0);
    assert_int_equal(r.vertices_after, 4);
}

/* The seam rule where a seam ends: the flat fan with texture coordinates, the centre's corners
 * all of one id (0), each rim vertex k's of id k, except rim vertex 1's corner in triangle
 * (0, 6, 1), which has id 7 (other coordinates): a seam along the edge 0-1 that ends at the
 * centre. The centre may go into rim vertex 2 (both triangles of the edge have id 2 there) but
 * not into rim vertex 1 (the edge's triangles have ids 1 and 7 there: the seam's end would
 * move). */
static void test_seam_end(void **state)
{
    make_fan(0);
    uint32_t ids[6 * 3];
    float uv[8 * 2] = {0, 0};
    for (uint32_t k = 0; k < 6; k++) {
        ids[3 * k] = 0;
        ids[3 * k + 1] = 1 + k;
        ids[3 * k + 2] = 1 + (k + 1) % 6;
        uv[2 * (1 + k)] = fan_positions[3 * (1 + k)];
        uv[2 * (1 + k) + 1] = fan_positions[3 * (1 + k) + 1];
    }
    ids[3 * 5 + 2] = 7; /* rim vertex 1 in triangle (0, 6, 1) */
    uv[2 * 7] = uv[2 * 7 + 1] = 5;
    collapse_mesh m = mesh_of(7, fan_positions, 6, fan_triangles);
    m.corner_ids = ids;
    m.attributes = uv;
    m.attribute_count = 8;
    m.uv_floats = 2;
    expect(&m, DECIMATE_QUADRIC, 0, 2, 1, NULL);
    expect(&m, DECIMATE_QUADRIC, 0, 1, 0, "seam");
}

/* A triangle that names one vertex twice (which the weld drops) is refused, by name. */
static void test_triangle_with_a_vertex_twice(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t triangles[] = {0, 2, 1, 0, 1, 3, 3, 2, 3};
    collapse_mesh m = mesh_of(4, positions, 3, triangles);
    collapse_options o = options_of(DECIMATE_QUADRIC);
    uint32_t history[4];
    collapse_result r = {.collapsed_into = history};
    assert_int_equal(collapse_run(&m, &o, &r), -1);
    assert_non_null(strstr(error_message(), "triangle 2 names a vertex twice"));
}

/* ---- fans ---- */

/* collapse_one_fan, each case worked out by hand: the centre's corners (next, previous) of the
 * flat fan's six triangles (1..6 closed around it), in and out of order; the fan opened (one
 * triangle fewer); two closed fans (a second ring 11..13 around the same vertex); two open fans
 * (a bowtie); an edge wound the same way twice (one next repeated); one triangle. */
static void test_one_fan(void **state)
{
    collapse_half_edge closed[6], shuffled[6];
    for (uint32_t k = 0; k < 6; k++)
        closed[k] = (collapse_half_edge){1 + k, 1 + (k + 1) % 6};
    static const int order[6] = {3, 0, 5, 1, 4, 2};
    for (int k = 0; k < 6; k++)
        shuffled[k] = closed[order[k]];
    assert_true(collapse_one_fan(closed, 6));
    assert_true(collapse_one_fan(shuffled, 6));
    assert_true(collapse_one_fan(closed, 5)); /* (1,2) .. (5,6): open from 1 to 6 */
    assert_true(collapse_one_fan(shuffled + 1, 5));
    collapse_half_edge two_closed[9];
    memcpy(two_closed, closed, sizeof closed);
    for (uint32_t k = 0; k < 3; k++)
        two_closed[6 + k] = (collapse_half_edge){11 + k, 11 + (k + 1) % 3};
    assert_false(collapse_one_fan(two_closed, 9));
    collapse_half_edge bowtie[2] = {{1, 2}, {3, 4}};
    assert_false(collapse_one_fan(bowtie, 2));
    collapse_half_edge twice[3] = {{1, 2}, {2, 3}, {1, 4}};
    assert_false(collapse_one_fan(twice, 3));
    assert_true(collapse_one_fan(bowtie, 1));
}

/* collapse_one_fan's definition, plainly: distinct nexts and previouses, at most one corner
 * whose next no corner has as its previous, and a walk from it (or from the first, when none)
 * that meets every corner. */
static int one_fan_by_definition(const collapse_half_edge *c, uint32_t count)
{
    uint32_t open_ends = 0, start = 0;
    for (uint32_t i = 0; i < count; i++) {
        int preceded = 0;
        for (uint32_t j = 0; j < count; j++) {
            if (j != i && (c[j].next == c[i].next || c[j].previous == c[i].previous))
                return 0;
            preceded |= c[j].previous == c[i].next;
        }
        if (!preceded)
            open_ends++, start = i;
    }
    if (open_ends > 1)
        return 0;
    uint32_t at = start, steps = 1;
    for (; steps < count; steps++) {
        uint32_t following = count;
        for (uint32_t j = 0; j < count && following == count; j++)
            if (c[j].next == c[at].previous)
                following = j;
        if (following == count || following == start)
            break;
        at = following;
    }
    return steps == count;
}

/* collapse_one_fan (which indexes the corners by hashed bits) against its definition on 200,000
 * random corner sets: real fans, closed and open, shuffled and with one corner changed, up to
 * 70 corners (beyond the index's 64 bits), and arbitrary ones from a few values (many
 * repeats). */
static void test_one_fan_random(void **state)
{
    srand(31);
    collapse_half_edge c[70];
    uint32_t fans = 0;
    for (int round = 0; round < 200000; round++) {
        uint32_t n = 1 + (uint32_t)rand() % (round % 10 == 0 ? 70 : 9);
        int kind = rand() % 3;
        if (kind == 0)
            for (uint32_t i = 0; i < n; i++)
                c[i] = (collapse_half_edge){(uint32_t)rand() % (n + 2), (uint32_t)rand() % (n + 2)};
        else {
            uint32_t base = (uint32_t)rand(), step = 1 + (uint32_t)rand() % 100000;
            int closed = rand() % 2;
            for (uint32_t i = 0; i < n; i++)
                c[i] = (collapse_half_edge){base + step * i,
                                            base + step * (closed ? (i + 1) % n : i + 1)};
            for (uint32_t i = n - 1; i > 0; i--) {
                uint32_t j = (uint32_t)rand() % (i + 1);
                collapse_half_edge swap = c[i];
                c[i] = c[j];
                c[j] = swap;
            }
            if (kind == 2) {
                uint32_t k = (uint32_t)rand() % n;
                if (rand() % 2)
                    c[k].next = c[(uint32_t)rand() % n].next;
                else
                    c[k].previous = base + step * ((uint32_t)rand() % (n + 1));
            }
        }
        int expected = one_fan_by_definition(c, n);
        fans += expected;
        if (collapse_one_fan(c, n) != expected)
            fail_msg("round %d, %u corners: expected %d", round, n, expected);
    }
    print_message("  200000 corner sets, %u of them one fan: as defined\n", fans);
    assert_true(fans > 50000 && fans < 150000);
}

/* The engine given fans to check (collapse_mesh.fans_unchecked): two tetrahedra sharing vertex 0
 * (two closed fans there) stop it before any collapse, with that one vertex counted; a manifold
 * mesh (the bunny, welded as decimate_mesh welds it) is reduced exactly as with its fans
 * checked. */
static void test_fans_unchecked(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    uint32_t triangles[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,
                            0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6};
    collapse_mesh m = mesh_of(7, positions, 8, triangles);
    m.fans_unchecked = 1;
    collapse_options o = options_of(DECIMATE_QUADRIC);
    o.target_vertices = 4;
    uint32_t history[7];
    collapse_result r = {.collapsed_into = history};
    assert_int_equal(collapse_run(&m, &o, &r), 0);
    assert_int_equal(r.non_manifold_vertices, 1);
    assert_int_equal(r.collapses, 0);
    assert_int_equal(r.vertices_after, 7);
    for (uint32_t v = 0; v < 7; v++)
        assert_int_equal(history[v], v);

    model_fixture bunny;
    model_open(&bunny, "bunny.ply", 0);
    weld_result welded[2];
    collapse_result result[2];
    for (int unchecked = 0; unchecked < 2; unchecked++) {
        weld_result *w = &welded[unchecked];
        assert_int_equal(weld_flat(&bunny.in, 1, w), 0);
        assert_int_equal(w->non_manifold_vertices, 0);
        collapse_mesh b = mesh_of(w->vertex_count, w->positions, w->triangle_count, w->triangles);
        b.fans_unchecked = unchecked;
        collapse_options bo = options_of(DECIMATE_QUADRIC);
        bo.target_vertices = w->vertices_counted / 10;
        bo.threads = 2;
        result[unchecked].collapsed_into = xmalloc(sizeof(uint32_t) * w->vertex_count);
        assert_int_equal(collapse_run(&b, &bo, &result[unchecked]), 0);
        assert_int_equal(result[unchecked].non_manifold_vertices, 0);
        assert_int_equal(result[unchecked].vertices_before, w->vertices_counted);
    }
    assert_int_equal(result[0].collapses, result[1].collapses);
    assert_true(result[0].collapses > 0);
    assert_memory_equal(welded[0].triangles, welded[1].triangles,
                        3 * sizeof(uint32_t) * welded[0].triangle_count);
    assert_memory_equal(result[0].collapsed_into, result[1].collapsed_into,
                        sizeof(uint32_t) * welded[0].vertex_count);
    for (int k = 0; k < 2; k++) {
        free(result[k].collapsed_into);
        weld_result_free(&welded[k]);
    }
    model_close(&bunny);
}

/* ---- thread counts ---- */

static void decimate_with_threads(model_fixture *f, unsigned int threads, decimate_method method,
                                  decimate_output *out)
{
    f->in.threads = threads;
    assert_int_equal(decimate_mesh(&f->in, method, out), 0);
}

/* The dragon at resolution 2 (non-manifold: the OpenMesh rebuild's input) with combined and
 * importance, and again with smooth normals (attribute sets, seams and the attribute quadrics)
 * with combined: the same bytes on 1, 2 and 7 threads. */
static void test_same_result_on_any_thread_count(void **state)
{
    model_fixture dragon;
    model_open(&dragon, "dragon_vrip_res2.ply", 5);
    dragon.in.target_vertices = dragon.measured / 10;
    float *normals = smooth_normals(&dragon.mesh);
    const decimate_method methods[3] = {DECIMATE_COMBINED, DECIMATE_IMPORTANCE,
                                        DECIMATE_COMBINED};
    for (int i = 0; i < 3; i++) {
        if (i == 2) {
            dragon.in.normals = normals;
            dragon.in.uv_weight = DECIMATE_UV_WEIGHT;
            dragon.in.normal_weight = DECIMATE_NORMAL_WEIGHT;
        }
        decimate_output one, other;
        decimate_with_threads(&dragon, 1, methods[i], &one);
        const unsigned int threads[2] = {2, 7};
        for (int k = 0; k < 2; k++) {
            decimate_with_threads(&dragon, threads[k], methods[i], &other);
            assert_int_equal(other.mesh.vertex_count, one.mesh.vertex_count);
            assert_int_equal(other.mesh.triangle_count, one.mesh.triangle_count);
            assert_memory_equal(other.mesh.positions, one.mesh.positions,
                                3 * sizeof(float) * one.mesh.vertex_count);
            assert_memory_equal(other.mesh.indices, one.mesh.indices,
                                3 * sizeof(uint32_t) * one.mesh.triangle_count);
            assert_memory_equal(other.collapsed_into, one.collapsed_into,
                                sizeof(uint32_t) * one.history_count);
            if (one.mesh.normals)
                assert_memory_equal(other.mesh.normals, one.mesh.normals,
                                    3 * sizeof(float) * one.mesh.vertex_count);
            decimate_output_free(&other);
        }
        print_message("  dragon res2, method %d%s: %u -> %u vertices in %u passes, the same on "
                      "1, 2 and 7 threads\n",
                      methods[i], i == 2 ? " with normals" : "", one.vertices_welded,
                      one.mesh.vertex_count, one.passes);
        if (i < 2) /* check_history counts a vertex once, as a mesh without attributes has it */
            check_history(&one);
        decimate_output_free(&one);
    }
    free(normals);
    model_close(&dragon);
}

/* ---- against the reference ---- */

/* The squared distance from p to triangle abc (the closest point by regions, Ericson's
 * "Real-Time Collision Detection" 5.1.5). */
static double point_triangle_distance2(const double p[3], const float *a, const float *b,
                                       const float *c)
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = (double)b[k] - a[k];
        ac[k] = (double)c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
#define DOT(x, y) ((x)[0] * (y)[0] + (x)[1] * (y)[1] + (x)[2] * (y)[2])
    double d1 = DOT(ab, ap), d2 = DOT(ac, ap), q[3];
    double bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    double cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
#undef DOT
    double s = 0, t = 0;
    if (d1 <= 0 && d2 <= 0)
        s = 0, t = 0;
    else if (d3 >= 0 && d4 <= d3)
        s = 1, t = 0;
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        s = d1 / (d1 - d3), t = 0;
    else if (d6 >= 0 && d5 <= d6)
        s = 0, t = 1;
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        s = 0, t = d2 / (d2 - d6);
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        s = 1 - w, t = w;
    } else {
        double denominator = 1.0 / (va + vb + vc);
        s = vb * denominator, t = vc * denominator;
    }
    double d2sum = 0;
    for (int k = 0; k < 3; k++) {
        q[k] = a[k] + s * ab[k] + t * ac[k];
        d2sum += (p[k] - q[k]) * (p[k] - q[k]);
    }
    return d2sum;
}

/* The mean distance from every 7th original vertex to the reduced surface (brute force). */
static double mean_distance(const mesh_data *original, const mesh_data *reduced)
{
    double sum = 0;
    uint32_t count = 0;
    for (uint32_t v = 0; v < original->vertex_count; v += 7) {
        const float *pf = &original->positions[3 * (size_t)v];
        double p[3] = {pf[0], pf[1], pf[2]}, best = INFINITY;
        for (uint32_t t = 0; t < reduced->triangle_count; t++) {
            const uint32_t *ix = &reduced->indices[3 * (size_t)t];
            double d = point_triangle_distance2(p, &reduced->positions[3 * (size_t)ix[0]],
                                                &reduced->positions[3 * (size_t)ix[1]],
                                                &reduced->positions[3 * (size_t)ix[2]]);
            if (d < best)
                best = d;
        }
        sum += sqrt(best);
        count++;
    }
    return sum / count;
}

static void compare_with_reference(decimate_method method, const char *name)
{
    model_fixture bunny;
    model_open(&bunny, "bunny.ply", 9);
    bunny.in.target_vertices = bunny.measured / 10;
    bunny.in.threads = 2;
    decimate_output engine, reference;
    assert_int_equal(decimate_mesh(&bunny.in, method, &engine), 0);
    assert_int_equal(decimate_reference_mesh(&bunny.in, method, &reference), 0);
    double ours = mean_distance(&bunny.mesh, &engine.mesh),
           theirs = mean_distance(&bunny.mesh, &reference.mesh);
    print_message("  bunny to 10 %% (%s): engine %u vertices, mean distance %.3g; reference %u "
                  "vertices, %.3g; ratio %.3f\n",
                  name, engine.mesh.vertex_count, ours, reference.mesh.vertex_count, theirs,
                  ours / theirs);
    assert_int_equal(engine.mesh.vertex_count, reference.mesh.vertex_count);
    assert_int_equal(degenerate_faces(&engine.mesh), 0);
    check_history(&engine);
    assert_true(ours <= 1.25 * theirs);
    decimate_output_free(&engine);
    decimate_output_free(&reference);
    model_close(&bunny);
}

static void test_quadric_against_reference(void **state)
{
    compare_with_reference(DECIMATE_QUADRIC, "quadric");
}

static void test_combined_against_reference(void **state)
{
    compare_with_reference(DECIMATE_COMBINED, "combined");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_fan),
        cmocka_unit_test(test_spike),
        cmocka_unit_test(test_wide_fan),
        cmocka_unit_test(test_tetrahedron),
        cmocka_unit_test(test_seam_end),
        cmocka_unit_test(test_triangle_with_a_vertex_twice),
        cmocka_unit_test(test_one_fan),
        cmocka_unit_test(test_one_fan_random),
        cmocka_unit_test(test_fans_unchecked),
        cmocka_unit_test(test_same_result_on_any_thread_count),
        cmocka_unit_test(test_quadric_against_reference),
        cmocka_unit_test(test_combined_against_reference),
    };
    return cmocka_run_group_tests_name("collapse", tests, NULL, NULL);
}
