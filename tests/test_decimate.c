/* test_decimate.c — the order of collapses, on the collapse engine (decimate_mesh, collapse.h)
 * and on the reference (decimate_reference_mesh: OpenMesh's decimater under our heap): the order
 * under the importance rule, the reference's heap, the collapse history, bad input and the
 * thread pool. One case a test; the normal limit and the welding of non-manifold input
 * have programs of their own (test_decimate_normal_limit.c, test_decimate_weld.c), the helpers
 * are in decimate_common.h.
 *
 *   order        a flat 7 x 7 grid with hand-set importance: the first collapse removes the
 *                vertex of least one-ring sum (centre included) into its least important
 *                neighbour; the second collapse shows that the kept vertex's neighbours were
 *                re-scored (the reference) or not taken in the same pass (the engine: the kept
 *                vertex is touched), where the stale-ring bug of OpenMesh's DecimaterT picks
 *                another vertex
 *   heap         (reference) after every collapse on the dragon (res4) no heap entry is stale;
 *                the DecimaterT re-scoring leaves stale entries (so the check can fail)
 *   history      collapse chains end in survivors, survivors are the output vertices (importance
 *                and quadric)
 *   bad input    no importance, no triangles, no vertices, a target above the vertex count
 *   threads      decimate_many on 2 threads == one by one; a failing mesh among them
 *
 * The grid answers are worked out in the comments; the test recomputes the ring sums from the
 * triangle list and checks that the paper's rule and the two wrong rules (ring without its
 * centre, the vertex's own importance) disagree on them, so the test can tell them apart. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "core/shapes.h"

/* ---- 1. importance module order on a flat grid ---- */

/* A 7 x 7 grid (make_grid): every collapse of an interior vertex is legal (no fold, no
 * degenerate face, the link condition holds). */
#define GRID 7
#define AT(i, j) ((j) * GRID + (i))

/* Importance, row j from top to bottom as printed (boundary 100). One-ring sums, centre
 * included (rows j = 0..6):
 *     333 357 329 318 349 436 300
 *     334 358 297 288 302 486 436
 *     315 270 136 116 128 304 373
 *     335 297 105 144 170 313 344
 *     338 320 145 156 173 335 345
 *     417 467 318 304 306 424 370
 *     300 417 346 341 328 348 332
 * First collapse: X = (2,3), ring 22 + 21 + 8 + 39 + 14 + 1 + 0 = 105, the least; into its
 * least important neighbour T = (2,2) (importance 0). Wrong rules pick other vertices: the ring
 * without its centre is least at Z = (3,2) (116 - 35 = 81 < 105 - 22 = 83), the lowest
 * importance is T itself (the test recomputes these from the triangle list).
 * Then T holds 0 + 22 = 22, so its neighbour Z = (3,2), ring 116 before, has 138 now; the
 * second collapse is W = (4,2) (ring 128, untouched) into (3,1) (importance 5). Re-scoring only
 * X's former ring (OpenMesh's DecimaterT) leaves Z at 116: it would go second, into (3,1). */
static const double grid_importance[GRID][GRID] = {
    {100, 100, 100, 100, 100, 100, 100}, {100, 33, 24, 5, 13, 36, 100},
    {100, 1, 0, 35, 11, 37, 100},        {100, 14, 22, 21, 20, 7, 100},
    {100, 21, 39, 8, 38, 38, 100},       {100, 17, 29, 12, 16, 32, 100},
    {100, 100, 100, 100, 100, 100, 100},
};

static void grid_importance_flat(double *importance)
{
    for (unsigned int j = 0; j < GRID; j++)
        for (unsigned int i = 0; i < GRID; i++)
            importance[AT(i, j)] = grid_importance[j][i];
}

/* Ring sums recomputed from the triangle list: with and without the centre. */
static void ring_sums(const mesh_data *m, const double *importance, double *with_centre,
                      double *without_centre)
{
    uint32_t n = m->vertex_count;
    char *adjacent = calloc((size_t)n * n, 1);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = m->indices[3 * t + k], b = m->indices[3 * t + (k + 1) % 3];
            adjacent[(size_t)a * n + b] = adjacent[(size_t)b * n + a] = 1;
        }
    for (uint32_t v = 0; v < n; v++) {
        double sum = 0;
        for (uint32_t w = 0; w < n; w++)
            if (adjacent[(size_t)v * n + w])
                sum += importance[w];
        without_centre[v] = sum;
        with_centre[v] = sum + importance[v];
    }
    free(adjacent);
}

static uint32_t argmin(const double *values, uint32_t count)
{
    uint32_t best = 0;
    for (uint32_t v = 1; v < count; v++)
        if (values[v] < values[best])
            best = v;
    return best;
}

/* The vertices of the worked answer: X goes first, into T; then W, into WT; Z is the vertex the
 * wrong rules pick (and the stale re-scoring sends second, into T). */
enum { X = AT(2, 3), T = AT(2, 2), W = AT(4, 2), Z = AT(3, 2), WT = AT(3, 1) };

typedef int (*decimate_function)(const decimate_input *, decimate_method, decimate_output *);

/* The grid with its importance, decimated by `collapses` collapses. */
typedef struct grid_fixture {
    mesh_data mesh;
    double importance[GRID * GRID];
    decimate_input in;
} grid_fixture;

static void grid_decimate(grid_fixture *g, decimate_function decimate, uint32_t collapses,
                          int removed_ring_only, decimate_output *out)
{
    make_grid(GRID, 0, &g->mesh);
    grid_importance_flat(g->importance);
    g->in = input_of("grid", &g->mesh, g->importance, GRID * GRID - collapses);
    g->in.reheap_removed_ring_only = removed_ring_only;
    assert_int_equal(decimate(&g->in, DECIMATE_IMPORTANCE, out), 0);
    assert_int_equal(out->collapses, collapses);
}

/* The worked numbers, and that the wrong rules would choose differently. */
static void test_grid_ring_sums(void **state)
{
    mesh_data grid;
    make_grid(GRID, 0, &grid);
    assert_int_equal(grid.triangle_count, 72);
    double importance[GRID * GRID], with[GRID * GRID], without[GRID * GRID];
    grid_importance_flat(importance);
    ring_sums(&grid, importance, with, without);
    assert_true(with[X] == 105 && with[Z] == 116 && with[W] == 128);
    assert_int_equal(argmin(with, GRID * GRID), X);
    assert_int_equal(argmin(without, GRID * GRID), Z);
    assert_int_equal(argmin(importance, GRID * GRID), T);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        if (v != X)
            assert_true(with[v] > with[X]);
    mesh_data_free(&grid);
}

/* One collapse: X into T. T stays where it was; X's position is gone; the rest is the input's. */
static void check_first_collapse(decimate_function decimate)
{
    grid_fixture g;
    decimate_output out;
    grid_decimate(&g, decimate, 1, 0, &out);
    assert_int_equal(out.vertices_welded, GRID * GRID);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        assert_int_equal(out.welded_of[v], v);
    assert_int_equal(out.mesh.vertex_count, GRID * GRID - 1);
    assert_int_equal(out.mesh.triangle_count, 70);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        assert_int_equal(out.collapsed_into[v], v == X ? T : v);
    check_survivor_positions(&g.in, &out);
    int found_t = 0;
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++) {
        const float *p = &out.mesh.positions[3 * v];
        assert_false(p[0] == 2.0f && p[1] == 3.0f);
        found_t += p[0] == 2.0f && p[1] == 2.0f && p[2] == 0.0f;
    }
    assert_int_equal(found_t, 1);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);
    mesh_data_free(&g.mesh);
}

static void test_grid_first_collapse(void **state) { check_first_collapse(decimate_mesh); }
static void test_grid_first_collapse_reference(void **state)
{
    check_first_collapse(decimate_reference_mesh);
}

/* Two collapses: X into T first; where W and Z went shows how the second was chosen. */
static void check_two_collapses(decimate_function decimate, int removed_ring_only,
                                uint32_t w_into, uint32_t z_into)
{
    grid_fixture g;
    decimate_output out;
    grid_decimate(&g, decimate, 2, removed_ring_only, &out);
    assert_int_equal(out.collapsed_into[X], T);
    assert_int_equal(out.collapsed_into[W], w_into);
    assert_int_equal(out.collapsed_into[Z], z_into);
    decimate_output_free(&out);
    mesh_data_free(&g.mesh);
}

/* The second collapse is W into (3,1): the reference re-scored T's neighbour Z (138 now); the
 * engine ranked Z first on its pass-start score (116) but T, its target, was touched by X's
 * collapse, so Z waits for the next pass. */
static void test_grid_second_collapse(void **state)
{
    check_two_collapses(decimate_mesh, 0, WT, Z);
}
static void test_grid_second_collapse_reference(void **state)
{
    check_two_collapses(decimate_reference_mesh, 0, WT, Z);
}

/* The reference with DecimaterT's re-scoring: Z keeps its stale entry (116, into T) and goes
 * second, into T (its stale target: T held 0); W stays. */
static void test_grid_second_collapse_stale(void **state)
{
    check_two_collapses(decimate_reference_mesh, 1, W, T);
}

/* ---- 2. heap order after collapses ---- */

static void test_heap_order(void **state)
{
    model_fixture dragon;
    model_open(&dragon, DRAGON_RES4, 2);
    /* Checking every heap entry after every collapse is quadratic: 250 collapses. */
    dragon.in.target_vertices = dragon.measured - 250;
    dragon.in.verify_heap = 1;
    decimate_output out;
    assert_int_equal(decimate_reference_mesh(&dragon.in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 250);
    assert_int_equal(out.mesh.vertex_count, dragon.measured - 250);
    uint64_t ours = out.heap_violations;
    decimate_output_free(&out);

    dragon.in.reheap_removed_ring_only = 1;
    assert_int_equal(decimate_reference_mesh(&dragon.in, DECIMATE_IMPORTANCE, &out), 0);
    uint64_t stale = out.heap_violations;
    decimate_output_free(&out);
    print_message("  dragon res4: %u vertices, 250 collapses: %llu stale entries (ours), %llu "
                  "(re-scoring the removed vertex's ring only)\n",
                  dragon.measured, (unsigned long long)ours, (unsigned long long)stale);
    assert_true(stale > 0);
    assert_int_equal(ours, 0);
    model_close(&dragon);
}

/* ---- 3. history ---- */

/* Decimates the resolution-4 dragon to a fifth of its vertices. It is mostly non-manifold scraps
 * (patches of a few faces, which run out of legal collapses): the target is not reached, and is
 * not claimed to be, but more than half the vertices go; the output is sound and its history
 * complete. */
static void decimate_dragon_to_a_fifth(model_fixture *f, decimate_method method,
                                       decimate_output *out)
{
    f->in.target_vertices = f->measured / 5;
    assert_int_equal(decimate_mesh(&f->in, method, out), 0);
    assert_int_equal(out->vertices_welded, f->measured);
    assert_true(out->mesh.vertex_count >= f->in.target_vertices);
    assert_true(out->mesh.vertex_count < f->measured / 2);
    assert_int_equal(out->mesh.vertex_count, f->measured - out->collapses);
    check_indices(&out->mesh);
    assert_int_equal(degenerate_faces(&out->mesh), 0);
    check_history(out);
}

static void test_history(void **state)
{
    model_fixture dragon;
    model_open(&dragon, DRAGON_RES4, 4);
    decimate_output out;
    decimate_dragon_to_a_fifth(&dragon, DECIMATE_IMPORTANCE, &out);
    /* Every input vertex maps to a welded vertex; where no face needed copied vertices, the
     * survivors also keep input positions (check_survivor_positions). */
    for (uint32_t v = 0; v < dragon.mesh.vertex_count; v++)
        assert_true(out.welded_of[v] < out.vertices_welded);
    if (out.faces_patched == 0 && out.faces_loose == 0)
        check_survivor_positions(&dragon.in, &out);
    print_message("  dragon res4: %u read, %u welded, %u uncollapsible, %u patched, %u loose, %u "
                  "dropped faces; %u -> %u vertices (target %llu)\n",
                  dragon.mesh.vertex_count, dragon.measured, dragon.uncollapsible,
                  out.faces_patched, out.faces_loose, out.faces_dropped, dragon.measured,
                  out.mesh.vertex_count, (unsigned long long)dragon.in.target_vertices);
    decimate_output_free(&out);
    model_close(&dragon);
}

static void test_quadric_dragon(void **state)
{
    model_fixture dragon;
    model_open(&dragon, DRAGON_RES4, 0);
    decimate_output out;
    decimate_dragon_to_a_fifth(&dragon, DECIMATE_QUADRIC, &out);
    print_message("  quadric, dragon res4: %u -> %u vertices (target %llu)\n", dragon.measured,
                  out.mesh.vertex_count, (unsigned long long)dragon.in.target_vertices);
    decimate_output_free(&out);
    model_close(&dragon);
}

/* ---- 4. bad input ---- */

/* Decimates the 3 x 3 grid (9 vertices; of its 8 triangles only the first `triangles` given) to
 * `target`; returns decimate_mesh's status. */
static int decimate_small_grid(const char *name, const double *importance, uint64_t target,
                               uint32_t triangles, decimate_method method, decimate_output *out)
{
    mesh_data grid;
    make_grid(3, 0, &grid);
    decimate_input in = input_of(name, &grid, importance, target);
    in.triangle_count = triangles;
    int status = decimate_mesh(&in, method, out);
    mesh_data_free(&grid);
    return status;
}

/* Importance decimation without importance: an error naming the mesh, a zeroed output. */
static void test_no_importance(void **state)
{
    decimate_output out;
    error_clear();
    assert_int_equal(decimate_small_grid("the_mesh_without_importance", NULL, 4, 8,
                                         DECIMATE_IMPORTANCE, &out),
                     -1);
    assert_non_null(strstr(error_message(), "the_mesh_without_importance"));
    assert_null(out.mesh.positions);
    decimate_output_free(&out); /* harmless on a failed, zeroed output */
}

/* Grids on which nothing collapses, by either method. */
typedef struct no_collapse_case {
    const char *name;
    uint64_t target;
    uint32_t triangles; /* given of the grid's 8 */
    uint32_t vertices_after, triangles_after;
} no_collapse_case;

static const no_collapse_case no_collapse_cases[] = {
    /* Vertices but no triangles: vertices without faces are dropped. */
    {"no triangles", 2, 0, 0, 0},
    /* A target above the vertex count. */
    {"target above the vertex count", 100, 8, 9, 8},
};

static void test_no_collapse(void **state)
{
    const no_collapse_case *c = *state;
    const double importance[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    for (decimate_method method = DECIMATE_IMPORTANCE; method <= DECIMATE_QUADRIC; method++) {
        decimate_output out;
        assert_int_equal(
            decimate_small_grid(c->name, importance, c->target, c->triangles, method, &out), 0);
        assert_int_equal(out.collapses, 0);
        assert_int_equal(out.mesh.vertex_count, c->vertices_after);
        assert_int_equal(out.mesh.triangle_count, c->triangles_after);
        decimate_output_free(&out);
    }
}

/* Nothing at all. */
static void test_no_vertices(void **state)
{
    mesh_data empty = {0, 0, NULL, NULL, NULL, NULL, 0};
    double importance[1] = {0};
    decimate_input in = input_of("empty", &empty, importance, 0);
    uint32_t measured = 7, uncollapsible = 7;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    assert_int_equal(measured, 0);
    assert_int_equal(uncollapsible, 0);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.mesh.vertex_count, 0);
    assert_int_equal(out.mesh.triangle_count, 0);
    decimate_output_free(&out);
}

/* ---- 5. threads ---- */

static void assert_same_output(const decimate_output *a, const decimate_output *b)
{
    assert_int_equal(a->mesh.vertex_count, b->mesh.vertex_count);
    assert_int_equal(a->mesh.triangle_count, b->mesh.triangle_count);
    assert_int_equal(a->vertices_welded, b->vertices_welded);
    assert_int_equal(a->collapses, b->collapses);
    assert_memory_equal(a->mesh.positions, b->mesh.positions,
                        3 * sizeof(float) * a->mesh.vertex_count);
    assert_memory_equal(a->mesh.indices, b->mesh.indices,
                        3 * sizeof(uint32_t) * a->mesh.triangle_count);
    assert_memory_equal(a->collapsed_into, b->collapsed_into,
                        sizeof(uint32_t) * a->vertices_welded);
}


/* Five meshes of different sizes for the thread pool, each with a random importance field and a
 * target of a (3 + i)-th of its vertices. */
enum { POOL_MESHES = 5 };
typedef struct pool_fixture {
    mesh_data meshes[POOL_MESHES];
    double *importance[POOL_MESHES];
    decimate_input in[POOL_MESHES];
} pool_fixture;

static void pool_open(pool_fixture *p)
{
    memset(p, 0, sizeof *p);
    read_model(DRAGON_RES4, &p->meshes[0]);
    const double centre[3] = {0, 0, 0};
    shapes_sphere(centre, 1, 32, 32, &p->meshes[1]);
    shapes_sphere(centre, 2, 12, 16, &p->meshes[2]);
    make_grid(GRID, 0, &p->meshes[3]);
    make_grid(9, 2.0, &p->meshes[4]);
    for (unsigned int i = 0; i < POOL_MESHES; i++) {
        p->importance[i] = random_importance(p->meshes[i].vertex_count, 10 + i);
        p->in[i] = input_of("mesh", &p->meshes[i], p->importance[i],
                            p->meshes[i].vertex_count / (3 + i));
    }
}

static void pool_close(pool_fixture *p)
{
    for (int i = 0; i < POOL_MESHES; i++) {
        free(p->importance[i]);
        mesh_data_free(&p->meshes[i]);
    }
}

/* decimate_many on two threads gives what decimate_mesh gives one by one, for both methods. */
static void test_many_threads_same_output(void **state)
{
    pool_fixture p;
    pool_open(&p);
    for (decimate_method method = DECIMATE_IMPORTANCE; method <= DECIMATE_QUADRIC; method++) {
        decimate_output one[POOL_MESHES], many[POOL_MESHES];
        int status[POOL_MESHES];
        char messages[POOL_MESHES][512];
        for (int i = 0; i < POOL_MESHES; i++)
            assert_int_equal(decimate_mesh(&p.in[i], method, &one[i]), 0);
        assert_int_equal(decimate_many(p.in, many, status, messages, POOL_MESHES, method, 2, NULL), 0);
        for (int i = 0; i < POOL_MESHES; i++) {
            assert_int_equal(status[i], 0);
            assert_same_output(&one[i], &many[i]);
            decimate_output_free(&one[i]);
            decimate_output_free(&many[i]);
        }
    }
    pool_close(&p);
}

/* A failing mesh among them: its status and message, the others unharmed. */
static void test_many_threads_failing_mesh(void **state)
{
    pool_fixture p;
    pool_open(&p);
    p.in[2].vertex_importance = NULL;
    p.in[2].name = "no_importance_here";
    decimate_output many[POOL_MESHES];
    int status[POOL_MESHES];
    char messages[POOL_MESHES][512];
    assert_int_equal(
        decimate_many(p.in, many, status, messages, POOL_MESHES, DECIMATE_IMPORTANCE, 2, NULL),
        1);
    for (int i = 0; i < POOL_MESHES; i++) {
        assert_int_equal(status[i], i == 2 ? -1 : 0);
        if (i != 2)
            assert_true(many[i].mesh.vertex_count > 0);
        decimate_output_free(&many[i]);
    }
    assert_non_null(strstr(messages[2], "no_importance_here"));
    pool_close(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_ring_sums),
        cmocka_unit_test(test_grid_first_collapse),
        cmocka_unit_test(test_grid_first_collapse_reference),
        cmocka_unit_test(test_grid_second_collapse),
        cmocka_unit_test(test_grid_second_collapse_reference),
        cmocka_unit_test(test_grid_second_collapse_stale),
        cmocka_unit_test(test_heap_order),
        cmocka_unit_test(test_history),
        cmocka_unit_test(test_quadric_dragon),
        cmocka_unit_test(test_no_importance),
        {"no collapse: no triangles", test_no_collapse, NULL, NULL, (void *)&no_collapse_cases[0]},
        {"no collapse: target above the vertex count", test_no_collapse, NULL, NULL,
         (void *)&no_collapse_cases[1]},
        cmocka_unit_test(test_no_vertices),
        cmocka_unit_test(test_many_threads_same_output),
        cmocka_unit_test(test_many_threads_failing_mesh),
    };
    return cmocka_run_group_tests_name("decimate", tests, NULL, NULL);
}
