/* test_decimate_weld.c — welding in the decimation bridge: the flat weld and its manifold
 * check (host/reduce/weld.c), and, where that check fails, the OpenMesh rebuild
 * (host/reduce/decimate_weld.cc): vertices at one position welded, faces that cannot attach
 * patched onto copies or left loose and locked, faces that weld into zero area dropped; the
 * accounting of all that checked from outside. One case a test; the helpers are in
 * decimate_common.h.
 *
 *   flat weld    the bunny and the dragon at resolution 4 welded flat: the bunny is manifold
 *                (the fast path), the fin, the two tetrahedra and a bowtie are not (each found
 *                at the vertex where it fails), and the flat weld's counts are decimate_measure's
 *   threads      the bunny with a triangle that welds into two vertices after every 1,000th,
 *                with normals, welded on 1, 2, 3 and 5 threads: the same arrays byte for byte
 *
 *   dragon       the dragon at resolution 2 (100,250 vertices, not manifold everywhere), decimated
 *                to 10 %
 *   fin          three triangles on one edge
 *   tetrahedra   two tetrahedra touching at a vertex
 *   seam         a square whose diagonal's ends are duplicated
 *   turned half  a grid whose right half is wound the other way: turned for the engine, back
 *                in the output, no copies
 *   double-sided a grid with every triangle again reversed: one layer decimated, twins kept */
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
#include "reduce/weld.h"


/* Faces whose corners fall on fewer than three distinct positions (welding drops them). */
static uint32_t faces_on_repeated_positions(const mesh_data *m)
{
    uint32_t count = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = &m->positions[3 * (size_t)m->indices[3 * t + k]];
        int same = 0;
        for (int k = 0; k < 3; k++)
            same |= p[k][0] + 0.0f == p[(k + 1) % 3][0] + 0.0f &&
                    p[k][1] + 0.0f == p[(k + 1) % 3][1] + 0.0f &&
                    p[k][2] + 0.0f == p[(k + 1) % 3][2] + 0.0f;
        count += same;
    }
    return count;
}

static uint32_t distinct_positions(const mesh_data *m)
{
    float *p = malloc(3 * sizeof(float) * (m->vertex_count + 1));
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; i++)
        p[i] = m->positions[i] + 0.0f;
    qsort(p, m->vertex_count, 3 * sizeof(float), compare_xyz);
    uint32_t count = m->vertex_count ? 1 : 0;
    for (uint32_t v = 1; v < m->vertex_count; v++)
        count += compare_xyz(&p[3 * (v - 1)], &p[3 * v]) != 0;
    free(p);
    return count;
}

/* The accounting of welding and patching, from outside: the decimater starts from the distinct
 * positions that attached faces use, plus patch copies, plus 3 per loose face; no vertex is left
 * without a face; no decimation keeps every face that did not weld into zero area. */
static void check_accounting(const char *name, const mesh_data *m, const double *importance,
                             decimate_output *full)
{
    decimate_input in = input_of(name, m, importance, 0);
    uint32_t measured, uncollapsible;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    in.target_vertices = measured;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, full), 0);
    assert_int_equal(full->collapses, 0);
    assert_int_equal(full->vertices_welded, measured);
    assert_int_equal(full->vertices_uncollapsible, uncollapsible);
    assert_int_equal(uncollapsible, 3 * full->faces_loose);
    assert_int_equal(full->faces_dropped, faces_on_repeated_positions(m));
    assert_int_equal(full->mesh.vertex_count, measured);
    assert_int_equal(full->mesh.triangle_count, m->triangle_count - full->faces_dropped);
    assert_int_equal(unreferenced_vertices(&full->mesh), 0);
    uint32_t distinct = distinct_positions(m);
    /* Patch copies are at most three per patched face; the welded originals at most all the
     * distinct positions. */
    assert_true(measured <= distinct + 3 * full->faces_patched + uncollapsible);
    if (!full->faces_patched && !full->faces_loose)
        assert_true(measured <= distinct);
    check_indices(&full->mesh);
}


static void test_non_manifold_dragon(void **state)
{
    model_fixture dragon;
    model_open(&dragon, "dragon_vrip_res2.ply", 6);
    assert_int_equal(dragon.mesh.vertex_count, 100250);
    decimate_output full;
    check_accounting("dragon_res2", &dragon.mesh, dragon.importance, &full);
    uint32_t measured = full.vertices_welded, uncollapsible = full.vertices_uncollapsible;
    uint32_t patched = full.faces_patched, loose = full.faces_loose, dropped = full.faces_dropped;
    decimate_output_free(&full);

    dragon.in.target_vertices = (uint64_t)(0.1 * measured + 0.5);
    decimate_output out;
    assert_int_equal(decimate_mesh(&dragon.in, DECIMATE_IMPORTANCE, &out), 0);
    print_message("  dragon res2: %u read, %u distinct positions, %u start (welded + copies), %u "
                  "uncollapsible; faces: %u read, %u patched, %u loose, %u dropped; target %llu, "
                  "output %u vertices (%+lld, %u used by no face), %u faces, %u collapses\n",
                  dragon.mesh.vertex_count, distinct_positions(&dragon.mesh), measured,
                  uncollapsible, dragon.mesh.triangle_count, patched, loose, dropped,
                  (unsigned long long)dragon.in.target_vertices, out.mesh.vertex_count,
                  (long long)out.mesh.vertex_count - (long long)dragon.in.target_vertices,
                  unreferenced_vertices(&out.mesh), out.mesh.triangle_count, out.collapses);
    assert_true(out.mesh.vertex_count >= dragon.in.target_vertices);
    assert_true(out.mesh.vertex_count <= dragon.in.target_vertices + uncollapsible);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    decimate_output_free(&out);
    model_close(&dragon);
}

static void decimate_all_the_way(const char *name, const mesh_data *m, const double *importance)
{
    decimate_input in = input_of(name, m, importance, 1);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    print_message("  %s: %u welded -> %u vertices (%u used by no face), %u faces\n", name,
                  out.vertices_welded, out.mesh.vertex_count, unreferenced_vertices(&out.mesh),
                  out.mesh.triangle_count);
    decimate_output_free(&out);
}


/* Three triangles on the edge a-b (a fin): the third cannot attach (a->b is taken) and gets a
 * patch of its own three copies. 5 positions + 3 patch copies, less vertex 4, which only the
 * patched face used (the patch has its own copy of it): 7. */
static void test_non_manifold_fin(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
    uint32_t indices[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    mesh_data fin = {5, 3, positions, indices, NULL, NULL, 0};
    double importance[5] = {1, 2, 3, 4, 5};
    decimate_output full;
    check_accounting("fin", &fin, importance, &full);
    assert_int_equal(full.vertices_welded, 7);
    assert_int_equal(full.faces_patched, 1);
    assert_int_equal(full.faces_loose, 0);
    decimate_output_free(&full);
    decimate_all_the_way("fin", &fin, importance);
}

/* Two tetrahedra touching at vertex 0: once the first is closed, vertex 0 is interior and the
 * second's three faces at it cannot attach: they get a patch of copies. */
static void test_non_manifold_tetrahedra(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    uint32_t indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
    mesh_data tetra = {7, 8, positions, indices, NULL, NULL, 0};
    double importance[7] = {1, 2, 3, 4, 5, 6, 7};
    decimate_output full;
    check_accounting("tetrahedra", &tetra, importance, &full);
    print_message("  two tetrahedra: %u welded, %u patched, %u loose\n", full.vertices_welded,
                  full.faces_patched, full.faces_loose);
    assert_int_equal(full.faces_patched + full.faces_loose, 3);
    decimate_output_free(&full);
    decimate_all_the_way("tetrahedra", &tetra, importance);
}

/* Duplicated positions (a split seam): welded into one surface, and the history is kept in
 * welded indices. Two triangles of the unit square with the diagonal's ends duplicated. */
static void test_non_manifold_seam(void **state)
{
    float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0};
    uint32_t indices[] = {0, 1, 2, 3, 4, 5};
    mesh_data seam = {6, 2, positions, indices, NULL, NULL, 0};
    double importance[6] = {1, 1, 1, 1, 1, 1};
    decimate_output full;
    check_accounting("seam", &seam, importance, &full);
    assert_int_equal(full.vertices_welded, 4);
    assert_int_equal(full.welded_of[3], full.welded_of[0]);
    assert_int_equal(full.welded_of[4], full.welded_of[2]);
    decimate_output_free(&full);
}

/* The flat weld of a mesh: how many vertices fail the manifold check. */
static uint32_t non_manifold(const mesh_data *m, weld_result *w)
{
    decimate_input in = input_of("flat", m, NULL, 0);
    assert_int_equal(weld_flat(&in, 1, w), 0);
    return w->non_manifold_vertices;
}

/* A manifold mesh takes the fast path: its welded count is decimate_measure's, nothing is
 * dropped that the OpenMesh rebuild keeps. Non-manifold meshes are found: the fin (its edge has
 * three triangles: both its ends), two tetrahedra on one vertex (two closed fans there), a bowtie
 * (two triangles on one vertex: two open fans), a Moebius band (no winding agrees); a triangle
 * flipped against its neighbour and a double-sided square are repaired into manifolds. */
static void test_flat_weld(void **state)
{
    model_fixture bunny;
    model_open(&bunny, "bunny.ply", 0);
    weld_result w;
    assert_int_equal(non_manifold(&bunny.mesh, &w), 0);
    assert_int_equal(w.vertices_counted, bunny.measured);
    assert_int_equal(w.triangle_count + w.triangles_dropped, bunny.mesh.triangle_count);
    print_message("  bunny: %u vertices welded to %u, %u triangles, manifold\n",
                  bunny.mesh.vertex_count, w.vertex_count, w.triangle_count);
    weld_result_free(&w);
    model_close(&bunny);

    float fin_positions[] = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
    uint32_t fin_indices[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    mesh_data fin = {5, 3, fin_positions, fin_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&fin, &w), 2);
    weld_result_free(&w);

    float tetra_positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    uint32_t tetra_indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,
                                0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
    mesh_data tetra = {7, 8, tetra_positions, tetra_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&tetra, &w), 1);
    weld_result_free(&w);

    float bowtie_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0};
    uint32_t bowtie_indices[] = {0, 1, 2, 0, 3, 4};
    mesh_data bowtie = {5, 2, bowtie_positions, bowtie_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&bowtie, &w), 1);
    weld_result_free(&w);

    /* Repaired (weld.h): a triangle flipped against its neighbour (an edge twice in one
     * direction) is turned for the engine; triangles on the vertices of another (a
     * double-sided square) are set aside as its twins. A Moebius band cannot agree. */
    float square_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    uint32_t flipped_indices[] = {0, 1, 2, 0, 3, 2};
    mesh_data flipped = {4, 2, square_positions, flipped_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&flipped, &w), 0);
    assert_int_equal(w.triangles_turned, 1);
    assert_true(w.turned && !w.turned[0] && w.turned[1]);
    assert_int_equal(w.triangles[3 + 1], 2); /* (0 3 2) as the engine holds it: (0 2 3) */
    weld_result_free(&w);
    uint32_t twin_indices[] = {0, 1, 2, 0, 2, 3, 0, 3, 2, 2, 1, 0};
    mesh_data twins = {4, 4, square_positions, twin_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&twins, &w), 0);
    assert_int_equal(w.triangle_count, 2);
    assert_int_equal(w.twin_count, 2);
    assert_int_equal(w.triangles_turned, 0);
    /* (0 3 2) is (0 2 3)'s corners 0, 2, 1; (2 1 0) is (0 1 2)'s 2, 1, 0. */
    assert_int_equal(w.twins[0].primary, 1);
    assert_int_equal(w.twins[0].source, 2);
    assert_true(w.twins[0].corner[0] == 0 && w.twins[0].corner[1] == 2 &&
                w.twins[0].corner[2] == 1);
    assert_int_equal(w.twins[1].primary, 0);
    assert_true(w.twins[1].corner[0] == 2 && w.twins[1].corner[1] == 1 &&
                w.twins[1].corner[2] == 0);
    weld_result_free(&w);
    float band_positions[] = {1, 0, 0, 0.3f, 1, 0.2f, -0.8f, 0.6f, -0.2f, -0.8f, -0.6f, 0.2f,
                              0.3f, -1, -0.2f};
    uint32_t band_indices[] = {0, 1, 2, 1, 2, 3, 2, 3, 4, 3, 4, 0, 4, 0, 1};
    mesh_data band = {5, 5, band_positions, band_indices, NULL, NULL, 0};
    assert_true(non_manifold(&band, &w) > 0);
    weld_result_free(&w);
    uint32_t square_indices[] = {0, 1, 2, 0, 2, 3};
    mesh_data square = {4, 2, square_positions, square_indices, NULL, NULL, 0};
    assert_int_equal(non_manifold(&square, &w), 0);
    weld_result_free(&w);
}

/* Whether two welds kept the same triangles, in the same order, with the same ids. */
static int same_triangles(const weld_result *a, const weld_result *b)
{
    size_t corners = 3 * sizeof(uint32_t) * a->triangle_count;
    return a->triangle_count == b->triangle_count &&
           a->triangles_dropped == b->triangles_dropped &&
           memcmp(a->triangles, b->triangles, corners) == 0 &&
           memcmp(a->corner_ids, b->corner_ids, corners) == 0 &&
           memcmp(a->kept_from, b->kept_from, sizeof(uint32_t) * a->triangle_count) == 0;
}

/* The triangles are welded in parts, one per thread, each part's kept ones moved up behind the
 * last part's (weld.c, keep_triangles): the bunny (69,451 triangles, 69,520 with those added,
 * enough for 5 parts: weld_threads leaves 5 threads while 4 blocks of 16,384 are fewer) with a
 * triangle on two vertices after every 1,000th, which every part has to drop, and with normals
 * (the corner ids moved too), welds the same on 1, 2, 3 and 5 threads, and drops exactly the
 * triangles added. */
static void test_weld_threads(void **state)
{
    (void)state;
    mesh_data bunny;
    read_model("bunny.ply", &bunny);
    uint32_t added = bunny.triangle_count / 1000, count = bunny.triangle_count + added;
    uint32_t *indices = malloc(3 * sizeof(uint32_t) * count);
    uint32_t *kept_input = malloc(sizeof(uint32_t) * bunny.triangle_count);
    uint32_t t = 0, kept = 0;
    for (uint32_t u = 0; u < bunny.triangle_count; u++) {
        memcpy(&indices[3 * (size_t)t], &bunny.indices[3 * (size_t)u], 3 * sizeof(uint32_t));
        kept_input[kept++] = t++;
        if (u % 1000 == 999) { /* (a, a, b): two vertices */
            uint32_t *c = &indices[3 * (size_t)t++];
            c[0] = c[1] = bunny.indices[3 * (size_t)u];
            c[2] = bunny.indices[3 * (size_t)u + 1];
        }
    }
    float *normals = malloc(3 * sizeof(float) * bunny.vertex_count);
    for (uint32_t v = 0; v < bunny.vertex_count; v++)
        for (int k = 0; k < 3; k++) /* (two values: vertices share ids only where welded) */
            normals[3 * (size_t)v + k] = k == 2 ? 1.0f : (float)(v % 2);
    mesh_data with = bunny;
    with.indices = indices;
    with.triangle_count = count;
    decimate_input in = input_of("bunny with dropped triangles", &with, NULL, 0);
    in.normals = normals;
    weld_result one, several;
    in.threads = 1;
    assert_int_equal(weld_flat(&in, 0, &one), 0);
    assert_int_equal(one.triangles_dropped, added);
    assert_int_equal(one.triangle_count, bunny.triangle_count);
    assert_memory_equal(one.kept_from, kept_input, sizeof(uint32_t) * kept);
    assert_non_null(one.corner_ids);
    static const unsigned int thread_counts[] = {2, 3, 5};
    for (size_t i = 0; i < sizeof thread_counts / sizeof thread_counts[0]; i++) {
        in.threads = thread_counts[i];
        assert_int_equal(weld_flat(&in, 0, &several), 0);
        if (!same_triangles(&one, &several))
            fail_msg("the weld on %u threads differs from the weld on one", in.threads);
        weld_result_free(&several);
    }
    weld_result_free(&one);
    free(normals);
    free(kept_input);
    free(indices);
    mesh_data_free(&bunny);
}

/* The corners of output triangle t of m and of input triangle u of `in` are at the same
 * positions, in the same order (the same winding). */
static int same_triangle(const mesh_data *m, uint32_t t, const mesh_data *in, uint32_t u)
{
    for (int k = 0; k < 3; k++)
        if (memcmp(&m->positions[3 * (size_t)m->indices[3 * t + k]],
                   &in->positions[3 * (size_t)in->indices[3 * u + k]], 3 * sizeof(float)) != 0)
            return 0;
    return 1;
}

/* Whether m holds input triangle u of `in`: a triangle on its corners' positions, in the same
 * cyclic order (the same winding). */
static int holds_triangle(const mesh_data *m, const mesh_data *in, uint32_t u)
{
    for (uint32_t t = 0; t < m->triangle_count; t++)
        for (int r = 0; r < 3; r++) {
            int all = 1;
            for (int k = 0; k < 3 && all; k++)
                all = memcmp(&m->positions[3 * (size_t)m->indices[3 * t + (k + r) % 3]],
                             &in->positions[3 * (size_t)in->indices[3 * u + k]],
                             3 * sizeof(float)) == 0;
            if (all)
                return 1;
        }
    return 0;
}

/* Whether m holds the triangle with t's corners in the other winding. */
static int has_reverse(const mesh_data *m, uint32_t t)
{
    const uint32_t *ix = &m->indices[3 * (size_t)t];
    for (uint32_t u = 0; u < m->triangle_count; u++) {
        const uint32_t *other = &m->indices[3 * (size_t)u];
        for (int r = 0; r < 3; r++)
            if (other[r] == ix[0] && other[(r + 1) % 3] == ix[2] && other[(r + 2) % 3] == ix[1])
                return 1;
    }
    return 0;
}

/* A 9 x 9 grid whose right half (x > 4) is wound the other way: the weld turns that half for the
 * engine, so nothing is patched onto copies; with nothing to remove every triangle comes out as
 * it went in, winding included, and at 20 vertices the grid meets its target. (The OpenMesh
 * rebuild patched the turned half onto copies: more vertices than the grid has.) */
static void test_turned_half(void **state)
{
    mesh_data grid;
    make_grid(9, 0, &grid);
    for (uint32_t t = 0; t < grid.triangle_count; t++) {
        uint32_t *ix = &grid.indices[3 * (size_t)t];
        float x = grid.positions[3 * ix[0]] + grid.positions[3 * ix[1]] + grid.positions[3 * ix[2]];
        if (x > 12) {
            uint32_t swap = ix[1];
            ix[1] = ix[2], ix[2] = swap;
        }
    }
    decimate_input in = input_of("turned half", &grid, NULL, grid.vertex_count);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.faces_patched + out.faces_loose, 0);
    assert_int_equal(out.mesh.vertex_count, 81);
    assert_int_equal(out.mesh.triangle_count, grid.triangle_count);
    for (uint32_t t = 0; t < grid.triangle_count; t++)
        if (!same_triangle(&out.mesh, t, &grid, t))
            fail_msg("triangle %u changed its corners or winding", t);
    decimate_output_free(&out);
    /* The reference (OpenMesh's decimater) starts from the same repaired mesh. */
    assert_int_equal(decimate_reference_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.mesh.vertex_count, 81);
    assert_int_equal(out.mesh.triangle_count, grid.triangle_count);
    for (uint32_t t = 0; t < grid.triangle_count; t++)
        if (!holds_triangle(&out.mesh, &grid, t))
            fail_msg("the reference lost triangle %u or its winding", t);
    decimate_output_free(&out);

    in.target_vertices = 20;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    print_message("  turned half: 81 -> %u vertices, %u triangles\n", out.mesh.vertex_count,
                  out.mesh.triangle_count);
    assert_int_equal(out.mesh.vertex_count, 20);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

/* A double-sided 9 x 9 grid (every triangle again, reversed): one layer is decimated and every
 * surviving triangle comes out with its twin, on the same 81 vertices at most, never the 162 of
 * a second layer of copies. */
static void test_double_sided(void **state)
{
    mesh_data grid;
    make_grid(9, 0, &grid);
    uint32_t n = grid.triangle_count;
    grid.indices = realloc(grid.indices, 2 * 3 * sizeof(uint32_t) * n);
    for (uint32_t t = 0; t < n; t++) {
        const uint32_t *ix = &grid.indices[3 * (size_t)t];
        uint32_t *twin = &grid.indices[3 * (size_t)(n + t)];
        twin[0] = ix[0], twin[1] = ix[2], twin[2] = ix[1];
    }
    grid.triangle_count = 2 * n;
    decimate_input in = input_of("double-sided", &grid, NULL, grid.vertex_count);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.vertices_welded, 81);
    assert_int_equal(out.mesh.vertex_count, 81);
    assert_int_equal(out.mesh.triangle_count, 2 * n);
    for (uint32_t t = 0; t < n; t++)
        if (!same_triangle(&out.mesh, t, &grid, t) || !same_triangle(&out.mesh, n + t, &grid, n + t))
            fail_msg("triangle %u or its twin changed", t);
    decimate_output_free(&out);
    assert_int_equal(decimate_reference_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.mesh.vertex_count, 81);
    assert_int_equal(out.mesh.triangle_count, 2 * n);
    for (uint32_t t = 0; t < 2 * n; t++)
        if (!holds_triangle(&out.mesh, &grid, t))
            fail_msg("the reference lost triangle %u or its winding", t);
    decimate_output_free(&out);

    in.target_vertices = 20;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    print_message("  double-sided: 81 -> %u vertices, %u triangles\n", out.mesh.vertex_count,
                  out.mesh.triangle_count);
    assert_int_equal(out.mesh.vertex_count, 20);
    assert_int_equal(out.mesh.triangle_count % 2, 0);
    for (uint32_t t = 0; t < out.mesh.triangle_count; t++)
        if (!has_reverse(&out.mesh, t))
            fail_msg("output triangle %u has no twin", t);
    check_indices(&out.mesh);
    check_history(&out);
    decimate_output_free(&out);
    assert_int_equal(decimate_reference_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.mesh.vertex_count, 20);
    for (uint32_t t = 0; t < out.mesh.triangle_count; t++)
        if (!has_reverse(&out.mesh, t))
            fail_msg("reference output triangle %u has no twin", t);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_weld),
        cmocka_unit_test(test_weld_threads),
        cmocka_unit_test(test_non_manifold_dragon),
        cmocka_unit_test(test_non_manifold_fin),
        cmocka_unit_test(test_non_manifold_tetrahedra),
        cmocka_unit_test(test_non_manifold_seam),
        cmocka_unit_test(test_turned_half),
        cmocka_unit_test(test_double_sided),
    };
    return cmocka_run_group_tests_name("decimate_weld", tests, NULL, NULL);
}
