/* test_remap.c — importance of a reduced mesh copied back to the original's vertices along the
 * collapse chains (host/reduce/remap.c, paper 3.5), and the tie rule the decimation of the
 * original then follows (decimate.h, "Remapped importance"). Host only, no device.
 *
 *   by hand     a history written out by hand (a weld, chains of one and two collapses, a
 *               survivor whose output index is not its own, a position left without faces):
 *               every value and distance worked out below
 *   real        a history from real decimations (a grid and the dragon, quadric): survivors keep
 *               their own value at distance 0, every other vertex takes the value of the
 *               survivor its chain ends in, at the chain's length, both found here by walking
 *               each chain step by step (the library resolves each chain once)
 *   ties        a torus of equal importance, where every ring sum ties: without distances the
 *               lowest index goes first (vertex 0 is removed first); with vertex 0 at distance 0
 *               and the others at 1, the first collapse removes another vertex into vertex 0
 *               (among equal priorities, the collapse into the target closest to its source),
 *               and vertex 0 survives a reduction to half
 *   spill       the remapped importance moved out of memory while the memory fit builds its
 *               BVH (reduce_memory.c) and read back: every value and distance bit for bit, a
 *               mesh without any still without, and no file left in the staging directory */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <dirent.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "reduce/reduce_stages.h"
#include "reduce/remap.h"

/* ---- 1. a history by hand ---- */

/* Seven input vertices; 5 sits where 4 does (welded into decimater vertex 4); 6 is decimater
 * vertex 5, a position without faces. Collapses: 3 -> 2, 2 -> 1, 4 -> 0. Survivors 0 and 1 are
 * output vertices 1 and 0. Reduced values: output 0 = 10, output 1 = 20. So:
 *   input 0: survivor 0 = output 1: 20 at 0      input 4: 4 -> 0: 20 at 1
 *   input 1: survivor 1 = output 0: 10 at 0      input 5: welded into 4: 20 at 1
 *   input 2: 2 -> 1: 10 at 1                     input 6: no faces: 0 at 0
 *   input 3: 3 -> 2 -> 1: 10 at 2 */
static void test_by_hand(void **state)
{
    (void)state;
    uint32_t welded_of[7] = {0, 1, 2, 3, 4, 4, 5};
    uint32_t collapsed_into[6] = {0, 1, 1, 2, 0, 5};
    uint32_t output_index[6] = {1, 0, DECIMATE_REMOVED, DECIMATE_REMOVED, DECIMATE_REMOVED,
                                DECIMATE_REMOVED};
    decimate_output history;
    memset(&history, 0, sizeof history);
    history.history_count = 6;
    history.welded_of = welded_of;
    history.collapsed_into = collapsed_into;
    history.output_index = output_index;
    const double reduced[2] = {10, 20};
    const double expect_value[7] = {20, 10, 10, 10, 20, 20, 0};
    const uint32_t expect_distance[7] = {0, 0, 1, 2, 1, 1, 0};
    double values[7];
    uint32_t distance[7];
    remap_values(&history, 7, reduced, values, distance);
    for (int i = 0; i < 7; i++) {
        assert_true(values[i] == expect_value[i]);
        assert_int_equal(distance[i], expect_distance[i]);
    }
}

/* ---- 2. histories of real decimations ---- */

/* remap_values() on a decimation's history, with output vertex k worth k + 0.5, against each
 * chain walked step by step. */
static void check_remap(const decimate_input *in, const decimate_output *out)
{
    uint32_t n = in->vertex_count;
    double *reduced = malloc(sizeof(double) * (out->mesh.vertex_count + 1));
    for (uint32_t k = 0; k < out->mesh.vertex_count; k++)
        reduced[k] = k + 0.5;
    double *values = malloc(sizeof(double) * (n + 1));
    uint32_t *distance = malloc(sizeof(uint32_t) * (n + 1));
    remap_values(out, n, reduced, values, distance);
    uint32_t survivors = 0, longest = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t at = out->welded_of[i], steps = 0;
        while (out->collapsed_into[at] != at) {
            at = out->collapsed_into[at];
            steps++;
        }
        uint32_t index = out->output_index[at];
        double expected = index == DECIMATE_REMOVED ? 0.0 : reduced[index];
        if (values[i] != expected || distance[i] != steps)
            fail_msg("input vertex %u: remapped %g at %u, its chain ends in %g at %u", i,
                     values[i], distance[i], expected, steps);
        if (steps == 0 && index != DECIMATE_REMOVED) {
            survivors++;
            /* A survivor keeps its own output vertex's value. */
            assert_true(values[i] == reduced[out->output_index[out->welded_of[i]]]);
        }
        if (steps > longest)
            longest = steps;
    }
    assert_true(survivors > 0);
    assert_true(longest > 1); /* the chains are longer than one collapse: the walk is tested */
    print_message("  %s: %u vertices -> %u, longest chain %u\n", in->name, n,
                  out->mesh.vertex_count, longest);
    free(reduced);
    free(values);
    free(distance);
}

static void test_grid_history(void **state)
{
    (void)state;
    mesh_data grid;
    make_grid(20, 3.0, &grid);
    decimate_input in = input_of("grid", &grid, NULL, 40);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    check_remap(&in, &out);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

static void test_dragon_history(void **state)
{
    (void)state;
    model_fixture f;
    model_open(&f, DRAGON_RES4, 0);
    f.in.target_vertices = f.mesh.vertex_count / 10;
    decimate_output out;
    assert_int_equal(decimate_mesh(&f.in, DECIMATE_QUADRIC, &out), 0);
    check_remap(&f.in, &out);
    decimate_output_free(&out);
    model_close(&f);
}

/* ---- 3. the tie rule ---- */

#define TORUS 12 /* vertices around each of the two circles */

/* A TORUS x TORUS torus (radii 3 and 1): vertex (i, j) = j * TORUS + i; cell (i, j) split along
 * (i, j)-(i+1, j+1), so every vertex has six neighbours and, under equal importance, the same
 * one-ring sum. Vertex 0's neighbours include vertex 1. */
static void make_torus(mesh_data *m)
{
    memset(m, 0, sizeof *m);
    m->vertex_count = TORUS * TORUS;
    m->triangle_count = 2 * TORUS * TORUS;
    m->positions = malloc(sizeof(float) * 3 * m->vertex_count);
    m->indices = malloc(sizeof(uint32_t) * 3 * m->triangle_count);
    for (unsigned int j = 0; j < TORUS; j++)
        for (unsigned int i = 0; i < TORUS; i++) {
            double u = 2 * M_PI * i / TORUS, v = 2 * M_PI * j / TORUS;
            float *p = &m->positions[3 * (j * TORUS + i)];
            p[0] = (float)((3 + cos(v)) * cos(u));
            p[1] = (float)((3 + cos(v)) * sin(u));
            p[2] = (float)sin(v);
        }
    uint32_t *ix = m->indices;
    for (unsigned int j = 0; j < TORUS; j++)
        for (unsigned int i = 0; i < TORUS; i++) {
            uint32_t a = j * TORUS + i, b = j * TORUS + (i + 1) % TORUS;
            uint32_t c = ((j + 1) % TORUS) * TORUS + (i + 1) % TORUS;
            uint32_t d = ((j + 1) % TORUS) * TORUS + i;
            *ix++ = a, *ix++ = b, *ix++ = c;
            *ix++ = a, *ix++ = c, *ix++ = d;
        }
}

/* The torus under equal importance decimated to `target` by the importance module, with vertex
 * 0 at distance 0 and the others at 1 when `distances`, or no distances. */
static void decimate_torus(int distances, uint64_t target, decimate_output *out)
{
    mesh_data torus;
    make_torus(&torus);
    double importance[TORUS * TORUS];
    uint32_t distance[TORUS * TORUS];
    for (uint32_t v = 0; v < TORUS * TORUS; v++) {
        importance[v] = 1.0;
        distance[v] = v == 0 ? 0 : 1;
    }
    decimate_input in = input_of("torus", &torus, importance, target);
    in.vertex_distance = distances ? distance : NULL;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, out), 0);
    for (uint32_t v = 0; v < TORUS * TORUS; v++)
        assert_int_equal(out->welded_of[v], v); /* no weld: decimater vertices are inputs */
    mesh_data_free(&torus);
}

static void test_ties_without_distances(void **state)
{
    (void)state;
    decimate_output out;
    decimate_torus(0, TORUS * TORUS - 1, &out);
    assert_int_equal(out.collapses, 1);
    assert_true(out.collapsed_into[0] != 0); /* the lowest index went first */
    decimate_output_free(&out);
}

static void test_ties_follow_distances(void **state)
{
    (void)state;
    decimate_output out;
    decimate_torus(1, TORUS * TORUS - 1, &out);
    assert_int_equal(out.collapses, 1);
    assert_int_equal(out.collapsed_into[0], 0);
    uint32_t into_zero = 0; /* the first collapse goes into vertex 0, the closest target */
    for (uint32_t v = 1; v < TORUS * TORUS; v++)
        into_zero += out.collapsed_into[v] == 0;
    assert_int_equal(into_zero, 1);
    decimate_output_free(&out);
    decimate_torus(1, TORUS * TORUS / 2, &out);
    assert_true(out.collapses >= TORUS * TORUS / 4);
    assert_int_equal(out.collapsed_into[0], 0);
    assert_true(out.output_index[0] != DECIMATE_REMOVED);
    decimate_output_free(&out);
}

/* ---- 4. the remapped importance out of memory and back ---- */

/* Entries of directory `path` other than . and .. */
static int entries_in(const char *path)
{
    DIR *d = opendir(path);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d));)
        count += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return count;
}

static void test_spill_and_restore(void **state)
{
    (void)state;
    char staging[] = "/tmp/test_remap.XXXXXX";
    assert_non_null(mkdtemp(staging));
    /* Mesh 1 was simulated as it is: it has no remapped importance. */
    scene_mesh meshes[3];
    memset(meshes, 0, sizeof meshes);
    const uint32_t counts[3] = {1000, 5, 70001};
    scene s;
    memset(&s, 0, sizeof s);
    s.meshes = meshes;
    s.mesh_count = 3;
    reduce_state st;
    memset(&st, 0, sizeof st);
    st.scene = st.simulated = &s;
    st.count = 3;
    snprintf(st.staging, sizeof st.staging, "%s", staging);
    st.remapped = xcalloc(4, sizeof *st.remapped);
    st.distance = xcalloc(4, sizeof *st.distance);
    for (size_t m = 0; m < 3; m++) {
        meshes[m].vertex_count = counts[m];
        if (m == 1)
            continue;
        st.remapped[m] = xcalloc(counts[m], sizeof *st.remapped[m]);
        st.distance[m] = xcalloc(counts[m], sizeof *st.distance[m]);
        for (uint32_t i = 0; i < counts[m]; i++) {
            st.remapped[m][i] = ldexp(1.0 + (double)i / 3.0, (int)(i % 40) - 20) + (double)m;
            st.distance[m][i] = i * 7u + (uint32_t)m;
        }
    }
    assert_int_equal(reduce_remapped_spill(&st), 0);
    for (size_t m = 0; m < 3; m++) {
        assert_null(st.remapped[m]);
        assert_null(st.distance[m]);
    }
    assert_int_equal(entries_in(staging), 0);
    assert_int_equal(reduce_remapped_restore(&st), 0);
    assert_null(st.spill);
    assert_null(st.remapped[1]);
    for (size_t m = 0; m < 3; m += 2)
        for (uint32_t i = 0; i < counts[m]; i++) {
            double expected = ldexp(1.0 + (double)i / 3.0, (int)(i % 40) - 20) + (double)m;
            assert_memory_equal(&st.remapped[m][i], &expected, sizeof expected);
            assert_int_equal(st.distance[m][i], i * 7u + (uint32_t)m);
        }
    /* Nothing spilled: nothing to read back. */
    assert_int_equal(reduce_remapped_restore(&st), 0);
    reduce_passes_free(&st);
    assert_int_equal(entries_in(staging), 0);
    assert_int_equal(rmdir(staging), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_by_hand),
        cmocka_unit_test(test_grid_history),
        cmocka_unit_test(test_dragon_history),
        cmocka_unit_test(test_ties_without_distances),
        cmocka_unit_test(test_ties_follow_distances),
        cmocka_unit_test(test_spill_and_restore),
    };
    return cmocka_run_group_tests_name("remap", tests, NULL, NULL);
}
