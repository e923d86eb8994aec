/* test_decimate.c — the OpenMesh decimation bridge (host/decimate.cc): the importance module,
 * our collapse loop, the normal limit, the collapse history, the quadric baseline, welding and
 * patching of non-manifold input, bad input and the thread pool.
 *
 *   order        a flat 7 x 7 grid with hand-set importance: the first collapse removes the
 *                vertex of least one-ring sum (centre included) into its least important
 *                neighbour; the second collapse shows that the kept vertex's neighbours were
 *                re-scored (the stale-ring bug of OpenMesh's DecimaterT picks another vertex)
 *   heap         after every collapse on the dragon (res4) no heap entry is stale; the
 *                DecimaterT re-scoring leaves stale entries (so the check can fail)
 *   normal limit a spike whose every collapse turns faces by ~72-77 degrees: rejected at 60,
 *                done at 179; on a sphere, collapse by collapse (decimating to n - k and to
 *                n - k - 1 differ by one collapse), no changed face turns by more than the limit
 *                or degenerates; the quadric method keeps every face of a sphere outward
 *   history      collapse chains end in survivors, survivors are the output vertices
 *   non-manifold the dragon at resolution 2 (OpenMesh splits it to 112,484 vertices), three
 *                triangles on one edge, two tetrahedra touching at a vertex
 *   bad input    no importance, no triangles, no vertices
 *   threads      decimate_many on 2 threads == one by one
 *
 * The grid answers are worked out in the comments; the test recomputes the ring sums from the
 * triangle list and checks that the paper's rule and the two wrong rules (ring without its
 * centre, the vertex's own importance) disagree on them, so the test can tell them apart.
 * Real meshes come from ../shared/data (via IDMR_ROOT); a missing file fails the test. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "reduce/decimate.h"
#include "core/error.h"
#include "io/mesh_io.h"
#include "io/shapes.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define MODELS IDMR_ROOT "/../shared/data/models"

/* ---- helpers ---- */

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double random_unit(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static double *random_importance(uint32_t count, uint64_t seed)
{
    rng_state = seed * 0x9e3779b97f4a7c15ull + 1;
    double *importance = malloc(sizeof(double) * (count + 1));
    for (uint32_t v = 0; v < count; v++)
        importance[v] = random_unit();
    return importance;
}

static decimate_input input_of(const char *name, const mesh_data *m, const double *importance,
                               uint64_t target)
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

static void read_model(const char *file, mesh_data *m)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", MODELS, file);
    if (mesh_io_read(path, m))
        fail_msg("%s (the real-mesh tests need ../shared/data, see DESIGN.md)", error_message());
}

/* Face normal (not normalised) of triangle t, in double. */
static void face_normal(const mesh_data *m, uint32_t t, double n[3])
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

static uint32_t degenerate_faces(const mesh_data *m)
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
static uint32_t unreferenced_vertices(const mesh_data *m)
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
static void check_indices(const mesh_data *m)
{
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        assert_true(m->indices[i] < m->vertex_count);
}

static int compare_xyz(const void *a, const void *b)
{
    return memcmp(a, b, 3 * sizeof(float));
}

/* The positions of the welded vertices that survive (collapsed_into[v] == v) are the output's
 * positions, as multisets; welded vertex w sits at the position of any input vertex welded to
 * it (meshes without copies: every welded vertex has an input vertex). */
static void check_survivor_positions(const decimate_input *in, const decimate_output *out)
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
static void check_history(const decimate_output *out)
{
    uint32_t n = out->vertices_welded, survivors = 0, longest = 0;
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
        survivors += steps == 0;
    }
    assert_int_equal(survivors, out->mesh.vertex_count);
    assert_int_equal(n - survivors, out->collapses);
    print_message("  history: %u welded, %u survive, longest chain %u\n", n, survivors, longest);
}

/* ---- 1. importance module order on a flat grid ---- */

/* A 7 x 7 grid in z = 0, vertex (i, j) = j * 7 + i at (i, j, 0); cell (i, j) is split along
 * (i, j)-(i+1, j+1), so an interior vertex has the six neighbours (i±1, j), (i, j±1),
 * (i+1, j+1), (i-1, j-1) around a convex hexagon: every collapse of an interior vertex is
 * legal (no fold, no degenerate face, the link condition holds). */
#define GRID 7
#define AT(i, j) ((j) * GRID + (i))

static void make_grid(unsigned int size, double spike, mesh_data *m)
{
    m->vertex_count = size * size;
    m->triangle_count = 2 * (size - 1) * (size - 1);
    m->positions = malloc(sizeof(float) * 3 * m->vertex_count);
    m->indices = malloc(sizeof(uint32_t) * 3 * m->triangle_count);
    m->texcoords = NULL;
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

static void test_importance_order(void **state)
{
    mesh_data grid;
    make_grid(GRID, 0, &grid);
    assert_int_equal(grid.triangle_count, 72);
    double importance[GRID * GRID], with[GRID * GRID], without[GRID * GRID];
    grid_importance_flat(importance);
    ring_sums(&grid, importance, with, without);
    const uint32_t X = AT(2, 3), T = AT(2, 2), W = AT(4, 2), Z = AT(3, 2), WT = AT(3, 1);
    /* The worked numbers, and that the wrong rules would choose differently. */
    assert_true(with[X] == 105 && with[Z] == 116 && with[W] == 128);
    assert_int_equal(argmin(with, GRID * GRID), X);
    assert_int_equal(argmin(without, GRID * GRID), Z);
    assert_int_equal(argmin(importance, GRID * GRID), T);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        if (v != X)
            assert_true(with[v] > with[X]);

    /* One collapse. */
    decimate_input in = input_of("grid", &grid, importance, GRID * GRID - 1);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.vertices_welded, GRID * GRID);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        assert_int_equal(out.welded_of[v], v);
    assert_int_equal(out.collapses, 1);
    assert_int_equal(out.mesh.vertex_count, GRID * GRID - 1);
    assert_int_equal(out.mesh.triangle_count, 70);
    assert_int_equal(out.collapsed_into[X], T);
    for (uint32_t v = 0; v < GRID * GRID; v++)
        if (v != X)
            assert_int_equal(out.collapsed_into[v], v);
    /* T stays where it was; X's position is gone; the rest is the input's. */
    check_survivor_positions(&in, &out);
    int found_t = 0;
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++) {
        const float *p = &out.mesh.positions[3 * v];
        assert_false(p[0] == 2.0f && p[1] == 3.0f);
        found_t += p[0] == 2.0f && p[1] == 2.0f && p[2] == 0.0f;
    }
    assert_int_equal(found_t, 1);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);

    /* Two collapses: the second is W into (3,1), because T's neighbour Z was re-scored. */
    in.target_vertices = GRID * GRID - 2;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 2);
    assert_int_equal(out.collapsed_into[X], T);
    assert_int_equal(out.collapsed_into[W], WT);
    assert_int_equal(out.collapsed_into[Z], Z);
    decimate_output_free(&out);

    /* The same with DecimaterT's re-scoring: Z keeps its stale entry (116, into T) and goes
     * second, into T. */
    in.reheap_removed_ring_only = 1;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 2);
    assert_int_equal(out.collapsed_into[X], T);
    assert_int_equal(out.collapsed_into[Z], T); /* its stale target: T held 0 */
    assert_int_equal(out.collapsed_into[W], W);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

/* ---- 2. heap order after collapses ---- */

static void test_heap_order(void **state)
{
    mesh_data dragon;
    read_model("dragon_vrip_res4.ply", &dragon);
    double *importance = random_importance(dragon.vertex_count, 2);
    /* Checking every heap entry after every collapse is quadratic: 250 collapses. */
    decimate_input in = input_of("dragon_res4", &dragon, importance, 0);
    uint32_t measured, uncollapsible;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    in.target_vertices = measured - 250;
    in.verify_heap = 1;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 250);
    assert_int_equal(out.mesh.vertex_count, measured - 250);
    uint64_t ours = out.heap_violations;
    decimate_output_free(&out);

    in.reheap_removed_ring_only = 1;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    uint64_t stale = out.heap_violations;
    decimate_output_free(&out);
    print_message("  dragon res4: %u vertices, 250 collapses: %llu stale entries (ours), %llu "
                  "(re-scoring the removed vertex's ring only)\n",
                  measured, (unsigned long long)ours, (unsigned long long)stale);
    assert_true(stale > 0);
    assert_int_equal(ours, 0);
    free(importance);
    mesh_data_free(&dragon);
}

/* ---- 3. normal limit ---- */

/* A 5 x 5 grid with its centre (2,2) raised to z = 3: the six faces around it are tilted by
 * atan(3 / d) from +z, d in {1, 1/√2} the distance of their base edge from the centre, so 71.6
 * or 76.7 degrees. Collapsing the spike into any neighbour lays its four remaining faces flat
 * (normal +z, none degenerate: no three hexagon corners are collinear): illegal at 60 degrees,
 * legal at 179. Importance 0 at the spike, 1..6 on its ring, 50 elsewhere: the spike has the
 * least ring sum (21; every other vertex has more than 150). */
static void test_normal_limit_spike(void **state)
{
    mesh_data spike;
    make_grid(5, 3.0, &spike);
    double importance[25];
    for (int v = 0; v < 25; v++)
        importance[v] = 50;
    const uint32_t centre = 12;
    importance[centre] = 0;
    const uint32_t ring[6] = {13, 18, 17, 11, 6, 7}; /* (3,2) (3,3) (2,3) (1,2) (1,1) (2,1) */
    for (int k = 0; k < 6; k++)
        importance[ring[k]] = 1 + k;

    decimate_input in = input_of("spike", &spike, importance, 24);
    in.max_normal_angle = 179;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 1);
    assert_int_equal(out.collapsed_into[centre], ring[0]);
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++)
        assert_true(out.mesh.positions[3 * v + 2] == 0.0f); /* the spike is gone */
    decimate_output_free(&out);

    in.max_normal_angle = 60;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 1);
    assert_int_equal(out.mesh.vertex_count, 24);
    assert_int_equal(out.collapsed_into[centre], centre);
    int spike_kept = 0;
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++)
        spike_kept += out.mesh.positions[3 * v + 2] == 3.0f;
    assert_int_equal(spike_kept, 1);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);
    mesh_data_free(&spike);
}

/* A sphere decimated to `fraction`: closed genus 0 (F = 2V - 4), no degenerate face, a complete
 * history; returns how many faces point towards the centre (dot(normal, centroid - centre) <= 0). */
static const double sphere_centre[3] = {0.3, -0.2, 0.1};

static uint32_t check_sphere(decimate_method method, double fraction)
{
    mesh_data sphere;
    shapes_sphere(sphere_centre, 1.5, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, &sphere);
    double *importance = random_importance(sphere.vertex_count, 3);
    uint64_t target = (uint64_t)(fraction * sphere.vertex_count);
    decimate_input in = input_of("sphere", &sphere, importance, target);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, method, &out), 0);
    assert_int_equal(out.mesh.vertex_count, target);
    assert_int_equal(out.mesh.triangle_count, 2 * target - 4);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    uint32_t inward = 0;
    for (uint32_t t = 0; t < out.mesh.triangle_count; t++) {
        double n[3], c[3] = {0, 0, 0};
        face_normal(&out.mesh, t, n);
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                c[j] += out.mesh.positions[3 * (size_t)out.mesh.indices[3 * t + k] + j] / 3.0;
        double dot = 0;
        for (int j = 0; j < 3; j++)
            dot += n[j] * (c[j] - sphere_centre[j]);
        inward += !(dot > 0);
    }
    print_message("  sphere %s to %llu of %u vertices: %u faces, %u facing inward\n",
                  method == DECIMATE_IMPORTANCE ? "importance" : "quadric",
                  (unsigned long long)target, sphere.vertex_count, out.mesh.triangle_count, inward);
    check_history(&out);
    check_survivor_positions(&in, &out);
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&sphere);
    return inward;
}

/* Faces as triples of input indices, rotated so the least comes first (winding kept), sorted. */
typedef struct position_index {
    float p[3];
    uint32_t index;
} position_index;

static int compare_position_index(const void *a, const void *b)
{
    return memcmp(((const position_index *)a)->p, ((const position_index *)b)->p, sizeof(float) * 3);
}

static int compare_face(const void *a, const void *b)
{
    const uint32_t *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

static void face_key(const uint32_t in[3], uint32_t out[3])
{
    int first = in[0] < in[1] ? (in[0] < in[2] ? 0 : 2) : (in[1] < in[2] ? 1 : 2);
    for (int k = 0; k < 3; k++)
        out[k] = in[(first + k) % 3];
}

/* The output's faces in input indices (the input has distinct positions). */
static uint32_t *faces_in_input_indices(const mesh_data *out, const position_index *sorted,
                                        uint32_t count)
{
    uint32_t *faces = malloc(sizeof(uint32_t) * 3 * (out->triangle_count + 1));
    for (uint32_t t = 0; t < out->triangle_count; t++) {
        uint32_t ix[3];
        for (int k = 0; k < 3; k++) {
            position_index key;
            memcpy(key.p, &out->positions[3 * (size_t)out->indices[3 * t + k]], sizeof key.p);
            const position_index *found =
                bsearch(&key, sorted, count, sizeof *sorted, compare_position_index);
            assert_non_null(found);
            ix[k] = found->index;
        }
        face_key(ix, &faces[3 * (size_t)t]);
    }
    qsort(faces, out->triangle_count, 3 * sizeof(uint32_t), compare_face);
    return faces;
}

/* The normal limit, collapse by collapse: decimating to n - k - 1 vertices does the collapses of
 * n - k and one more (the loop is deterministic). Each face the extra collapse changed (the
 * kept vertex in place of the removed one) may turn by at most max_angle degrees and may not be
 * degenerate; every other face is unchanged; two faces go. */
static void check_each_collapse(const mesh_data *m, const double *importance, decimate_method method,
                                double max_angle, uint32_t steps)
{
    position_index *sorted = malloc(sizeof *sorted * m->vertex_count);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        memcpy(sorted[v].p, &m->positions[3 * (size_t)v], sizeof sorted[v].p);
        sorted[v].index = v;
    }
    qsort(sorted, m->vertex_count, sizeof *sorted, compare_position_index);
    for (uint32_t v = 1; v < m->vertex_count; v++)
        assert_true(compare_position_index(&sorted[v - 1], &sorted[v]) != 0);
    double min_cos = cos(max_angle * M_PI / 180.0), worst = 0;
    decimate_input in = input_of("steps", m, importance, m->vertex_count);
    in.max_normal_angle = max_angle;
    decimate_output previous, current;
    assert_int_equal(decimate_mesh(&in, method, &previous), 0);
    uint32_t *previous_faces = faces_in_input_indices(&previous.mesh, sorted, m->vertex_count);
    uint32_t moved_faces = 0;
    for (uint32_t k = 0; k < steps; k++) {
        in.target_vertices = m->vertex_count - k - 1;
        assert_int_equal(decimate_mesh(&in, method, &current), 0);
        assert_int_equal(current.collapses, k + 1);
        assert_int_equal(current.mesh.triangle_count + 2, previous.mesh.triangle_count);
        uint32_t removed = UINT32_MAX;
        for (uint32_t v = 0; v < m->vertex_count; v++)
            if (current.collapsed_into[v] != previous.collapsed_into[v]) {
                assert_int_equal(previous.collapsed_into[v], v);
                assert_int_equal(removed, UINT32_MAX); /* one collapse more */
                removed = v;
            }
        assert_true(removed != UINT32_MAX);
        uint32_t kept = current.collapsed_into[removed];
        uint32_t *faces = faces_in_input_indices(&current.mesh, sorted, m->vertex_count);
        for (uint32_t t = 0; t < current.mesh.triangle_count; t++) {
            const uint32_t *f = &faces[3 * (size_t)t];
            if (bsearch(f, previous_faces, previous.mesh.triangle_count, 3 * sizeof(uint32_t),
                        compare_face))
                continue;
            uint32_t before[3], key[3];
            int corner = -1;
            for (int c = 0; c < 3; c++) {
                before[c] = f[c] == kept ? removed : f[c];
                if (f[c] == kept)
                    corner = c;
            }
            assert_true(corner >= 0); /* a changed face holds the kept vertex */
            face_key(before, key);
            assert_non_null(bsearch(key, previous_faces, previous.mesh.triangle_count,
                                    3 * sizeof(uint32_t), compare_face));
            double a[3], b[3];
            mesh_data one = {m->vertex_count, 1, m->positions, (uint32_t *)f, NULL};
            face_normal(&one, 0, a);
            one.indices = before;
            face_normal(&one, 0, b);
            double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
            double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            assert_true(la > 0);
            if (lb > 0) {
                double angle = acos(fmax(-1.0, fmin(1.0, dot / (la * lb)))) * 180.0 / M_PI;
                if (angle > worst)
                    worst = angle;
                if (!(dot >= min_cos * la * lb * (1 - 1e-12)))
                    fail_msg("collapse %u (%u into %u) turns a face by %.3f degrees (limit %g)",
                             k + 1, removed, kept, angle, max_angle);
            }
            moved_faces++;
        }
        decimate_output_free(&previous);
        free(previous_faces);
        previous = current;
        previous_faces = faces;
    }
    print_message("  %u collapses one by one (%s, limit %g): %u moved faces, largest turn %.2f "
                  "degrees\n",
                  steps, method == DECIMATE_IMPORTANCE ? "importance" : "quadric", max_angle,
                  moved_faces, worst);
    assert_true(moved_faces > 0);
    decimate_output_free(&previous);
    free(previous_faces);
    free(sorted);
}

/* The normal limit bounds each collapse (paper 3.4: "prohibits collapses that lead to a rotation
 * of triangle normals of more than a given angle"); on a sphere decimated by importance alone
 * the turns add up over collapses, so faces facing inward are reported, not forbidden (the
 * quadric method, which follows the geometry, must keep them all outward: test_quadric). */
static void test_normal_limit_sphere(void **state)
{
    mesh_data sphere;
    shapes_sphere(sphere_centre, 1.5, 16, 24, &sphere);
    double *importance = random_importance(sphere.vertex_count, 3);
    check_each_collapse(&sphere, importance, DECIMATE_IMPORTANCE, 60, sphere.vertex_count * 4 / 5);
    check_each_collapse(&sphere, importance, DECIMATE_IMPORTANCE, 20, sphere.vertex_count / 2);
    free(importance);
    mesh_data_free(&sphere);
    check_sphere(DECIMATE_IMPORTANCE, 0.2);
    check_sphere(DECIMATE_IMPORTANCE, 0.05);
}

/* ---- 4. history ---- */

static void test_history(void **state)
{
    mesh_data dragon;
    read_model("dragon_vrip_res4.ply", &dragon);
    double *importance = random_importance(dragon.vertex_count, 4);
    decimate_input in = input_of("dragon_res4", &dragon, importance, 0);
    uint32_t measured, uncollapsible;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    in.target_vertices = measured / 5;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.vertices_welded, measured);
    /* The resolution-4 dragon is mostly non-manifold scraps (patches of a few faces, which run
     * out of legal collapses): the target is not reached, and is not claimed to be. */
    assert_true(out.mesh.vertex_count >= in.target_vertices);
    assert_true(out.mesh.vertex_count < measured / 2);
    assert_int_equal(out.mesh.vertex_count, measured - out.collapses);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    /* Every input vertex maps to a welded vertex; where no face needed copied vertices, the
     * survivors also keep input positions (check_survivor_positions). */
    for (uint32_t v = 0; v < dragon.vertex_count; v++)
        assert_true(out.welded_of[v] < out.vertices_welded);
    if (out.faces_patched == 0 && out.faces_loose == 0)
        check_survivor_positions(&in, &out);
    print_message("  dragon res4: %u read, %u welded, %u uncollapsible, %u patched, %u loose, %u "
                  "dropped faces; %u -> %u vertices (target %llu)\n",
                  dragon.vertex_count, measured, uncollapsible, out.faces_patched, out.faces_loose,
                  out.faces_dropped, measured, out.mesh.vertex_count,
                  (unsigned long long)in.target_vertices);
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&dragon);
}

/* ---- 5. quadric ---- */

static void test_quadric(void **state)
{
    assert_int_equal(check_sphere(DECIMATE_QUADRIC, 0.2), 0);
    assert_int_equal(check_sphere(DECIMATE_QUADRIC, 0.05), 0);
    {
        mesh_data sphere;
        shapes_sphere(sphere_centre, 1.5, 12, 16, &sphere);
        check_each_collapse(&sphere, NULL, DECIMATE_QUADRIC, 60, sphere.vertex_count - 20);
        mesh_data_free(&sphere);
    }

    mesh_data dragon;
    read_model("dragon_vrip_res4.ply", &dragon);
    decimate_input in = input_of("dragon_res4", &dragon, NULL, 0);
    uint32_t measured, uncollapsible;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    in.target_vertices = measured / 5;
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_true(out.mesh.vertex_count >= in.target_vertices);
    assert_true(out.mesh.vertex_count < measured / 2);
    assert_int_equal(out.mesh.vertex_count, measured - out.collapses);
    print_message("  quadric, dragon res4: %u -> %u vertices (target %llu)\n", measured,
                  out.mesh.vertex_count, (unsigned long long)in.target_vertices);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    decimate_output_free(&out);

    /* The normal limit binds the quadric method too: the spike cannot go at 60 degrees even
     * when everything else has gone that can. */
    mesh_data spike;
    make_grid(5, 3.0, &spike);
    in = input_of("spike", &spike, NULL, 1);
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.collapsed_into[12], 12);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);
    mesh_data_free(&spike);
    mesh_data_free(&dragon);
}

/* ---- 6. non-manifold input ---- */

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
    mesh_data dragon;
    read_model("dragon_vrip_res2.ply", &dragon);
    assert_int_equal(dragon.vertex_count, 112484);
    double *importance = random_importance(dragon.vertex_count, 6);
    decimate_output full;
    check_accounting("dragon_res2", &dragon, importance, &full);
    uint32_t measured = full.vertices_welded, uncollapsible = full.vertices_uncollapsible;
    uint32_t patched = full.faces_patched, loose = full.faces_loose, dropped = full.faces_dropped;
    decimate_output_free(&full);

    decimate_input in = input_of("dragon_res2", &dragon, importance, (uint64_t)(0.1 * measured + 0.5));
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    print_message("  dragon res2: %u read, %u distinct positions, %u start (welded + copies), %u "
                  "uncollapsible; faces: %u read, %u patched, %u loose, %u dropped; target %llu, "
                  "output %u vertices (%+lld, %u used by no face), %u faces, %u collapses\n",
                  dragon.vertex_count, distinct_positions(&dragon), measured, uncollapsible,
                  dragon.triangle_count, patched, loose, dropped,
                  (unsigned long long)in.target_vertices, out.mesh.vertex_count,
                  (long long)out.mesh.vertex_count - (long long)in.target_vertices,
                  unreferenced_vertices(&out.mesh), out.mesh.triangle_count, out.collapses);
    assert_true(out.mesh.vertex_count >= in.target_vertices);
    assert_true(out.mesh.vertex_count <= in.target_vertices + uncollapsible);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    check_history(&out);
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&dragon);
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

static void test_non_manifold_small(void **state)
{
    /* Three triangles on the edge a-b (a fin): the third cannot attach (a->b is taken) and gets
     * a patch of its own three copies. */
    float fin_positions[] = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
    uint32_t fin_indices[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    mesh_data fin = {5, 3, fin_positions, fin_indices, NULL};
    double fin_importance[5] = {1, 2, 3, 4, 5};
    decimate_output full;
    check_accounting("fin", &fin, fin_importance, &full);
    /* 5 positions + 3 patch copies, less vertex 4, which only the patched face used (the patch
     * has its own copy of it): 7 */
    assert_int_equal(full.vertices_welded, 7);
    assert_int_equal(full.faces_patched, 1);
    assert_int_equal(full.faces_loose, 0);
    decimate_output_free(&full);
    decimate_all_the_way("fin", &fin, fin_importance);

    /* Two tetrahedra touching at vertex 0: once the first is closed, vertex 0 is interior and
     * the second's three faces at it cannot attach: they get a patch of copies. */
    float tetra_positions[] = {0, 0, 0,  1,  0, 0,  0,  1, 0,  0,  0, 1,
                               -1, 0, 0, 0, -1, 0,  0, 0, -1};
    uint32_t tetra_indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,
                                0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
    mesh_data tetra = {7, 8, tetra_positions, tetra_indices, NULL};
    double tetra_importance[7] = {1, 2, 3, 4, 5, 6, 7};
    check_accounting("tetrahedra", &tetra, tetra_importance, &full);
    print_message("  two tetrahedra: %u welded, %u patched, %u loose\n", full.vertices_welded,
                  full.faces_patched, full.faces_loose);
    assert_int_equal(full.faces_patched + full.faces_loose, 3);
    decimate_output_free(&full);
    decimate_all_the_way("tetrahedra", &tetra, tetra_importance);

    /* Duplicated positions (a split seam): welded into one surface, and the history is kept in
     * welded indices. Two triangles of the unit square with the diagonal's ends duplicated. */
    float seam_positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0};
    uint32_t seam_indices[] = {0, 1, 2, 3, 4, 5};
    mesh_data seam = {6, 2, seam_positions, seam_indices, NULL};
    double seam_importance[6] = {1, 1, 1, 1, 1, 1};
    check_accounting("seam", &seam, seam_importance, &full);
    assert_int_equal(full.vertices_welded, 4);
    assert_int_equal(full.welded_of[3], full.welded_of[0]);
    assert_int_equal(full.welded_of[4], full.welded_of[2]);
    decimate_output_free(&full);
}

/* ---- 7. bad input ---- */

static void test_bad_input(void **state)
{
    mesh_data grid;
    make_grid(3, 0, &grid);
    decimate_input in = input_of("the_mesh_without_importance", &grid, NULL, 4);
    decimate_output out;
    error_clear();
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), -1);
    assert_non_null(strstr(error_message(), "the_mesh_without_importance"));
    assert_null(out.mesh.positions);
    decimate_output_free(&out); /* harmless on a failed, zeroed output */

    /* Vertices but no triangles: nothing to collapse, and vertices without faces are dropped. */
    double importance[9] = {0};
    in = input_of("no_triangles", &grid, importance, 2);
    in.triangle_count = 0;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 0);
    assert_int_equal(out.mesh.triangle_count, 0);
    assert_int_equal(out.mesh.vertex_count, 0);
    decimate_output_free(&out);
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.mesh.triangle_count, 0);
    decimate_output_free(&out);

    /* Nothing at all. */
    mesh_data empty = {0, 0, NULL, NULL, NULL};
    in = input_of("empty", &empty, importance, 0);
    uint32_t measured = 7, uncollapsible = 7;
    assert_int_equal(decimate_measure(&in, &measured, &uncollapsible), 0);
    assert_int_equal(measured, 0);
    assert_int_equal(uncollapsible, 0);
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.mesh.vertex_count, 0);
    assert_int_equal(out.mesh.triangle_count, 0);
    decimate_output_free(&out);

    /* A target above the vertex count: nothing collapses. */
    double grid_imp[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    in = input_of("over", &grid, grid_imp, 100);
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, &out), 0);
    assert_int_equal(out.collapses, 0);
    assert_int_equal(out.mesh.vertex_count, 9);
    assert_int_equal(out.mesh.triangle_count, 8);
    decimate_output_free(&out);
    mesh_data_free(&grid);
}

/* ---- 8. threads ---- */

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

static void test_many_threads(void **state)
{
    enum { COUNT = 5 };
    mesh_data meshes[COUNT];
    memset(meshes, 0, sizeof meshes);
    read_model("dragon_vrip_res4.ply", &meshes[0]);
    const double centre[3] = {0, 0, 0};
    shapes_sphere(centre, 1, 32, 32, &meshes[1]);
    shapes_sphere(centre, 2, 12, 16, &meshes[2]);
    make_grid(GRID, 0, &meshes[3]);
    make_grid(9, 2.0, &meshes[4]);
    double *importance[COUNT];
    decimate_input in[COUNT];
    for (int i = 0; i < COUNT; i++) {
        importance[i] = random_importance(meshes[i].vertex_count, 10 + i);
        in[i] = input_of("mesh", &meshes[i], importance[i], meshes[i].vertex_count / (3 + i));
    }
    for (decimate_method method = DECIMATE_IMPORTANCE; method <= DECIMATE_QUADRIC; method++) {
        decimate_output one[COUNT], many[COUNT];
        int status[COUNT];
        char messages[COUNT][512];
        for (int i = 0; i < COUNT; i++)
            assert_int_equal(decimate_mesh(&in[i], method, &one[i]), 0);
        assert_int_equal(decimate_many(in, many, status, messages, COUNT, method, 2), 0);
        for (int i = 0; i < COUNT; i++) {
            assert_int_equal(status[i], 0);
            assert_same_output(&one[i], &many[i]);
            decimate_output_free(&one[i]);
            decimate_output_free(&many[i]);
        }
    }
    /* A failing mesh among them: its status and message, the others unharmed. */
    double *saved = importance[2];
    in[2].vertex_importance = NULL;
    in[2].name = "no_importance_here";
    decimate_output many[COUNT];
    int status[COUNT];
    char messages[COUNT][512];
    assert_int_equal(decimate_many(in, many, status, messages, COUNT, DECIMATE_IMPORTANCE, 2), 1);
    for (int i = 0; i < COUNT; i++) {
        assert_int_equal(status[i], i == 2 ? -1 : 0);
        if (i != 2)
            assert_true(many[i].mesh.vertex_count > 0);
        decimate_output_free(&many[i]);
    }
    assert_non_null(strstr(messages[2], "no_importance_here"));
    for (int i = 0; i < COUNT; i++) {
        free(i == 2 ? saved : importance[i]);
        mesh_data_free(&meshes[i]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_importance_order),
        cmocka_unit_test(test_heap_order),
        cmocka_unit_test(test_normal_limit_spike),
        cmocka_unit_test(test_normal_limit_sphere),
        cmocka_unit_test(test_history),
        cmocka_unit_test(test_quadric),
        cmocka_unit_test(test_non_manifold_dragon),
        cmocka_unit_test(test_non_manifold_small),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_many_threads),
    };
    return cmocka_run_group_tests_name("decimate", tests, NULL, NULL);
}
