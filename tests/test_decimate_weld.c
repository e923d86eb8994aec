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
 *
 *   dragon       the dragon at resolution 2 (OpenMesh splits it to 112,484 vertices), decimated
 *                to 10 %
 *   fin          three triangles on one edge
 *   tetrahedra   two tetrahedra touching at a vertex
 *   seam         a square whose diagonal's ends are duplicated */
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
    assert_int_equal(dragon.mesh.vertex_count, 112484);
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
    mesh_data fin = {5, 3, positions, indices, NULL, NULL};
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
    mesh_data tetra = {7, 8, positions, indices, NULL, NULL};
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
    mesh_data seam = {6, 2, positions, indices, NULL, NULL};
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
    assert_int_equal(weld_flat(&in, w), 0);
    return w->non_manifold_vertices;
}

/* A manifold mesh takes the fast path: its welded count is decimate_measure's, nothing is
 * dropped that the OpenMesh rebuild keeps. Non-manifold meshes are found: the fin (its edge has
 * three triangles: both its ends), two tetrahedra on one vertex (two closed fans there), a bowtie
 * (two triangles on one vertex: two open fans), a triangle flipped against its neighbour (an
 * edge twice in one direction). */
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
    mesh_data fin = {5, 3, fin_positions, fin_indices, NULL, NULL};
    assert_int_equal(non_manifold(&fin, &w), 2);
    weld_result_free(&w);

    float tetra_positions[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    uint32_t tetra_indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,
                                0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
    mesh_data tetra = {7, 8, tetra_positions, tetra_indices, NULL, NULL};
    assert_int_equal(non_manifold(&tetra, &w), 1);
    weld_result_free(&w);

    float bowtie_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0};
    uint32_t bowtie_indices[] = {0, 1, 2, 0, 3, 4};
    mesh_data bowtie = {5, 2, bowtie_positions, bowtie_indices, NULL, NULL};
    assert_int_equal(non_manifold(&bowtie, &w), 1);
    weld_result_free(&w);

    float square_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    uint32_t flipped_indices[] = {0, 1, 2, 0, 2, 3, 0, 3, 2};
    mesh_data flipped = {4, 3, square_positions, flipped_indices, NULL, NULL};
    assert_true(non_manifold(&flipped, &w) > 0);
    weld_result_free(&w);
    uint32_t square_indices[] = {0, 1, 2, 0, 2, 3};
    mesh_data square = {4, 2, square_positions, square_indices, NULL, NULL};
    assert_int_equal(non_manifold(&square, &w), 0);
    weld_result_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_weld),
        cmocka_unit_test(test_non_manifold_dragon),
        cmocka_unit_test(test_non_manifold_fin),
        cmocka_unit_test(test_non_manifold_tetrahedra),
        cmocka_unit_test(test_non_manifold_seam),
    };
    return cmocka_run_group_tests_name("decimate_weld", tests, NULL, NULL);
}
