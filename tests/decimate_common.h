/* decimate_common.h — shared by the decimation tests (test_decimate.c, the collapse loop;
 * test_decimate_normal_limit.c; test_decimate_weld.c): decimation inputs, random importance
 * fields from the project's generator (idmr/rng.h), real meshes from ../shared/data/models (via
 * IDMR_ROOT; a missing file fails the test), a flat grid, smooth normals for a mesh without
 * them, and the checks every decimation must pass (sound faces, a complete history, survivors
 * at input positions). Header-only (static functions): each program includes it once, after
 * cmocka.h. */
#ifndef IDMR_TESTS_DECIMATE_COMMON_H
#define IDMR_TESTS_DECIMATE_COMMON_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "idmr/rng.h"
#include "io/mesh/mesh_io.h"
#include "reduce/decimate.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define MODELS IDMR_ROOT "/../shared/data/models"
#define DRAGON_RES4 "dragon_vrip_res4.ply"

/* Importance uniform in [0, 1) per vertex, from stream `seed` of idmr/rng.h. */
static inline double *random_importance(uint32_t count, unsigned int seed)
{
    idmr_rng rng = idmr_rng_init(seed, 0, 0, 0);
    double *importance = malloc(sizeof(double) * (count + 1));
    for (uint32_t v = 0; v < count; v++)
        importance[v] = idmr_rng_float(&rng);
    return importance;
}

static inline decimate_input input_of(const char *name, const mesh_data *m,
                                      const double *importance, uint64_t target)
{
    decimate_input in;
    memset(&in, 0, sizeof in);
    in.name = name;
    in.positions = m->positions;
    in.vertex_count = m->vertex_count;
    in.indices = m->indices;
    in.triangle_count = m->triangle_count;
    in.vertex_importance = importance;
    in.target_vertices = target;
    in.max_normal_angle = 60.0;
    return in;
}

static inline void read_model(const char *file, mesh_data *m)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", MODELS, file);
    if (mesh_io_read(path, m))
        fail_msg("%s (the real-mesh tests need ../shared/data, see DESIGN.md)", error_message());
}

/* Face normal (not normalised) of triangle t, in double. */
static inline void face_normal(const mesh_data *m, uint32_t t, double n[3])
{
    const uint32_t *ix = &m->indices[3 * (size_t)t];
    const float *a = &m->positions[3 * (size_t)ix[0]], *b = &m->positions[3 * (size_t)ix[1]],
                *c = &m->positions[3 * (size_t)ix[2]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* Smooth normals for a mesh without them: per vertex the sum of its faces' (area-weighted)
 * normals, as a loader computes them (not normalised). */
static inline float *smooth_normals(const mesh_data *m)
{
    float *normals = calloc(3 * (size_t)m->vertex_count + 3, sizeof(float));
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double n[3];
        face_normal(m, t, n);
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                normals[3 * (size_t)m->indices[3 * t + k] + c] += (float)n[c];
    }
    return normals;
}

static inline uint32_t degenerate_faces(const mesh_data *m)
{
    uint32_t degenerate = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double n[3];
        face_normal(m, t, n);
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0) || ix[0] == ix[1] || ix[1] == ix[2] ||
            ix[0] == ix[2])
            degenerate++;
    }
    return degenerate;
}

/* Output vertices no face uses (the decimater drops them: asserted in check_accounting). */
static inline uint32_t unreferenced_vertices(const mesh_data *m)
{
    char *used = calloc(m->vertex_count + 1, 1);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        used[m->indices[i]] = 1;
    uint32_t count = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        count += !used[v];
    free(used);
    return count;
}

/* Every index in range. */
static inline void check_indices(const mesh_data *m)
{
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        assert_true(m->indices[i] < m->vertex_count);
}

static inline int compare_xyz(const void *a, const void *b)
{
    return memcmp(a, b, 3 * sizeof(float));
}

/* The positions of the welded vertices that survive (collapsed_into[v] == v) are the output's
 * positions, as multisets; welded vertex w sits at the position of any input vertex welded to
 * it (meshes without copies: every welded vertex has an input vertex). */
static inline void check_survivor_positions(const decimate_input *in, const decimate_output *out)
{
    uint32_t n = out->vertices_welded;
    float *welded = calloc(3 * (size_t)n + 3, sizeof(float));
    char *seen = calloc(n + 1, 1);
    for (uint32_t v = 0; v < in->vertex_count; v++) {
        uint32_t w = out->welded_of[v];
        assert_true(w < n);
        if (seen[w])
            assert_memory_equal(&welded[3 * (size_t)w], &in->positions[3 * (size_t)v],
                                3 * sizeof(float));
        memcpy(&welded[3 * (size_t)w], &in->positions[3 * (size_t)v], 3 * sizeof(float));
        seen[w] = 1;
    }
    float *survivors = calloc(3 * (size_t)n + 3, sizeof(float));
    uint32_t count = 0;
    for (uint32_t w = 0; w < n; w++)
        if (out->collapsed_into[w] == w) {
            assert_true(seen[w]);
            memcpy(&survivors[3 * (size_t)count++], &welded[3 * (size_t)w], 3 * sizeof(float));
        }
    assert_int_equal(count, out->mesh.vertex_count);
    float *output = calloc(3 * (size_t)count + 3, sizeof(float));
    memcpy(output, out->mesh.positions, 3 * sizeof(float) * count);
    qsort(survivors, count, 3 * sizeof(float), compare_xyz);
    qsort(output, count, 3 * sizeof(float), compare_xyz);
    assert_memory_equal(survivors, output, 3 * sizeof(float) * count);
    free(output);
    free(survivors);
    free(seen);
    free(welded);
}

/* Every removed welded vertex reaches a survivor (a fixed point) in at most n steps;
 * survivors map to themselves; their number is the output's vertex count. */
static inline void check_history(const decimate_output *out)
{
    uint32_t n = out->history_count, survivors = 0, unused = 0, longest = 0;
    for (uint32_t v = 0; v < n; v++) {
        uint32_t at = v, steps = 0;
        while (out->collapsed_into[at] != at) {
            at = out->collapsed_into[at];
            assert_true(at < n);
            steps++;
            if (steps > n)
                fail_msg("vertex %u: collapse chain longer than %u (a cycle)", v, n);
        }
        if (steps > longest)
            longest = steps;
        /* Every chain ends in a vertex of the output, or in a position left without faces. */
        if (out->output_index[at] == DECIMATE_REMOVED)
            assert_int_equal(steps, 0);
        if (steps == 0) {
            survivors += out->output_index[v] != DECIMATE_REMOVED;
            unused += out->output_index[v] == DECIMATE_REMOVED;
        }
    }
    assert_int_equal(survivors, out->mesh.vertex_count);
    assert_int_equal(n - survivors - unused, out->collapses);
    assert_int_equal(n - unused, out->vertices_welded);
    print_message("  history: %u welded, %u survive, longest chain %u\n", n - unused, survivors,
                  longest);
}

/* A real mesh from ../shared/data/models with a random importance field (none for seed 0), its
 * decimation input (target 0: set it), and the vertices the decimater starts from. */
typedef struct model_fixture {
    mesh_data mesh;
    double *importance;
    decimate_input in;
    uint32_t measured, uncollapsible;
} model_fixture;

static inline void model_open(model_fixture *f, const char *file, unsigned int seed)
{
    read_model(file, &f->mesh);
    f->importance = seed ? random_importance(f->mesh.vertex_count, seed) : NULL;
    f->in = input_of(file, &f->mesh, f->importance, 0);
    assert_int_equal(decimate_measure(&f->in, &f->measured, &f->uncollapsible), 0);
}

static inline void model_close(model_fixture *f)
{
    free(f->importance);
    mesh_data_free(&f->mesh);
}

/* A size x size grid in z = 0, vertex (i, j) = j * size + i at (i, j, 0), its centre raised to
 * z = spike; cell (i, j) is split along (i, j)-(i+1, j+1), so an interior vertex has the six
 * neighbours (i±1, j), (i, j±1), (i+1, j+1), (i-1, j-1) around a convex hexagon. */
static inline void make_grid(unsigned int size, double spike, mesh_data *m)
{
    memset(m, 0, sizeof *m);
    m->vertex_count = size * size;
    m->triangle_count = 2 * (size - 1) * (size - 1);
    m->positions = malloc(sizeof(float) * 3 * m->vertex_count);
    m->indices = malloc(sizeof(uint32_t) * 3 * m->triangle_count);
    for (unsigned int j = 0; j < size; j++)
        for (unsigned int i = 0; i < size; i++) {
            float *p = &m->positions[3 * (j * size + i)];
            p[0] = (float)i;
            p[1] = (float)j;
            p[2] = 0;
        }
    if (spike != 0)
        m->positions[3 * ((size / 2) * size + size / 2) + 2] = (float)spike;
    uint32_t *ix = m->indices;
    for (unsigned int j = 0; j + 1 < size; j++)
        for (unsigned int i = 0; i + 1 < size; i++) {
            uint32_t a = j * size + i, b = a + 1, c = a + size + 1, d = a + size;
            *ix++ = a, *ix++ = b, *ix++ = c;
            *ix++ = a, *ix++ = c, *ix++ = d;
        }
}

#endif
