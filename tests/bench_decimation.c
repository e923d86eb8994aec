/* bench_decimation.c — `make bench`: decimation of the full Stanford dragon
 * (../shared/data/models/dragon_vrip.ply, 437,645 vertices) to 10 %, every method on the
 * collapse engine (host/reduce/collapse.h) beside stock OpenMesh and meshoptimizer, in one run:
 *
 *   decimation: mesh=dragon target=0.1 threads=<1, then 2> combined=<s> importance=<s>
 *               quadric=<s> openmesh=<s> meshopt=<s> combined/meshopt=<r> quadric/meshopt=<r>
 *   decimation-parallel: mesh=dragon threads=2 method=combined one=<s> two=<s> speedup=<x>
 *   decimation-memory: mesh=dragon quadric=<bytes per vertex> importance=<bytes per vertex>
 *
 * combined, importance: a synthetic importance field (high on one side of the dragon); openmesh:
 * stock DecimaterT + ModQuadricT as Debian ships it (one run, 20-40 s); meshopt: meshoptimizer's
 * meshopt_simplify to 10 % of the triangles, one thread. Each engine figure is decimate_mesh()
 * whole (the welded rebuild, the engine, the output), the best of ROUNDS rounds that run every
 * figure once, meshoptimizer's too. The memory is what the engine allocates (collapse_memory())
 * per vertex of the dragon, with the quadric methods (COMBINED's without attributes, which the
 * dragon has none of) and with importance. And the parallel
 * decimation of the living room's meshes (meshes on threads):
 *
 *   decimation-parallel: scene=living-room meshes=<n> one=<s> two=<s> speedup=<one/two>
 *
 * And the dragon as most scenes give their meshes, with shading normals (here computed, area
 * weighted, from its triangles): `combined` keeps them per corner and weighs them in its cost
 * (decimate.h, "Attributes"), the path every mesh with normals or texture coordinates takes,
 * against the same method on the bare dragon in the same run (best of ATTRIBUTE_ROUNDS):
 *
 *   decimation-attributes: mesh=dragon normals=computed method=combined one=<s> two=<s>
 *                          speedup=<one/two> bare_one=<s> attributes/bare=<one/bare_one>
 */
#include <math.h>
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>

#include "reduce/collapse.h"
#include "reduce/decimate.h"
#include "io/mitsuba/mitsuba.h"
#include "trace_common.h"

/* Rounds of the dragon's measurements: each round runs every method on one and two threads and
 * meshoptimizer once, and each figure is the best of its rounds, so that a spell of noise on
 * the machine costs one round of every figure rather than every round of one. */
#define ROUNDS 5
/* Rounds of the attribute path's figures (each about 4 s on one thread). */
#define ATTRIBUTE_ROUNDS 2

static double best_of(double a, double b) { return a < b ? a : b; }

/* One run of decimate_mesh, its seconds; the output's vertex count into *vertices. */
static double time_engine(decimate_input in, decimate_method method, unsigned int threads,
                          uint32_t *vertices)
{
    in.threads = threads;
    decimate_output out;
    double t0 = trace_seconds();
    if (decimate_mesh(&in, method, &out)) {
        fprintf(stderr, "bench_decimation: %s\n", error_message());
        exit(1);
    }
    double seconds = trace_seconds() - t0;
    *vertices = out.mesh.vertex_count;
    decimate_output_free(&out);
    return seconds;
}

/* The decimation-attributes line: `in` (the bare dragon) with area-weighted vertex normals. */
static void bench_attributes(decimate_input in, const mesh_data *mesh)
{
    float *normals = calloc(3 * (size_t)mesh->vertex_count + 1, sizeof *normals);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *c = &mesh->indices[3 * (size_t)t];
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = &mesh->positions[3 * (size_t)c[k]];
        float e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                normals[3 * (size_t)c[k] + j] += n[j];
    }
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        float *n = &normals[3 * (size_t)v];
        float length = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (length > 0)
            for (int j = 0; j < 3; j++)
                n[j] /= length;
        else
            n[2] = 1.0f; /* a vertex of no area: any unit normal */
    }
    decimate_input with = in;
    with.normals = normals;
    double seconds[2] = {1e30, 1e30}, bare = 1e30;
    uint32_t vertices;
    for (int round = 0; round < ATTRIBUTE_ROUNDS; round++) {
        for (int t = 0; t < 2; t++)
            seconds[t] = best_of(seconds[t], time_engine(with, DECIMATE_COMBINED, t + 1, &vertices));
        bare = best_of(bare, time_engine(in, DECIMATE_COMBINED, 1, &vertices));
    }
    printf("decimation-attributes: mesh=dragon normals=computed method=combined one=%.3f two=%.3f "
           "speedup=%.2f bare_one=%.3f attributes/bare=%.2f\n",
           seconds[0], seconds[1], seconds[0] / seconds[1], bare, seconds[0] / bare);
    fflush(stdout);
    free(normals);
}

static void bench_dragon(void)
{
    mesh_data mesh;
    if (mesh_io_read(SHARED_DATA "/models/dragon_vrip.ply", &mesh)) {
        fprintf(stderr, "bench_decimation: %s\n", error_message());
        exit(1);
    }
    double *importance = malloc(mesh.vertex_count * sizeof *importance);
    for (uint32_t v = 0; v < mesh.vertex_count; v++)
        importance[v] = mesh.positions[3 * (size_t)v] > 0.0f ? 10.0 : 0.5;
    decimate_input in = {.name = "dragon",
                         .positions = mesh.positions,
                         .vertex_count = mesh.vertex_count,
                         .indices = mesh.indices,
                         .triangle_count = mesh.triangle_count,
                         .vertex_importance = importance,
                         .max_normal_angle = 60.0,
                         .uv_weight = DECIMATE_UV_WEIGHT,
                         .normal_weight = DECIMATE_NORMAL_WEIGHT};
    uint32_t start, uncollapsible;
    if (decimate_measure(&in, &start, &uncollapsible)) {
        fprintf(stderr, "bench_decimation: %s\n", error_message());
        exit(1);
    }
    in.target_vertices = start / 10;
    /* per method (combined, importance, quadric) and thread count (1, 2) */
    static const decimate_method methods[3] = {DECIMATE_COMBINED, DECIMATE_IMPORTANCE,
                                               DECIMATE_QUADRIC};
    double seconds[3][2] = {{1e30, 1e30}, {1e30, 1e30}, {1e30, 1e30}};
    uint32_t vertices[3][2];
    double meshopt = 1e30;
    size_t meshopt_triangles = 0;
    unsigned int *destination = malloc(3 * sizeof(unsigned int) * mesh.triangle_count);
    for (int round = 0; round < ROUNDS; round++) {
        for (int t = 0; t < 2; t++)
            for (int k = 0; k < 3; k++)
                seconds[k][t] =
                    best_of(seconds[k][t], time_engine(in, methods[k], t + 1, &vertices[k][t]));
        double t0 = trace_seconds();
        meshopt_triangles =
            meshopt_simplify(destination, mesh.indices, 3 * (size_t)mesh.triangle_count,
                             mesh.positions, mesh.vertex_count, 3 * sizeof(float),
                             3 * (size_t)(mesh.triangle_count / 10), 1.0f, 0, NULL) / 3;
        meshopt = best_of(meshopt, trace_seconds() - t0);
    }
    decimate_input stock_in = in;
    stock_in.target_vertices = mesh.vertex_count / 10;
    double t0 = trace_seconds();
    long stock_vertices = decimate_stock_quadric(&stock_in);
    double stock = trace_seconds() - t0;

    for (int t = 0; t < 2; t++)
        printf("decimation: mesh=dragon target=0.1 threads=%d combined=%.3f importance=%.3f "
               "quadric=%.3f openmesh=%.2f meshopt=%.3f combined/meshopt=%.2f "
               "quadric/meshopt=%.2f vertices=%u target_vertices=%llu combined_vertices=%u "
               "importance_vertices=%u quadric_vertices=%u openmesh_vertices=%ld "
               "meshopt_triangles=%zu\n",
               t + 1, seconds[0][t], seconds[1][t], seconds[2][t], stock, meshopt,
               seconds[0][t] / meshopt, seconds[2][t] / meshopt, mesh.vertex_count,
               (unsigned long long)in.target_vertices, vertices[0][t], vertices[1][t],
               vertices[2][t], stock_vertices, meshopt_triangles);
    printf("decimation-parallel: mesh=dragon threads=2 method=combined one=%.3f two=%.3f "
           "speedup=%.2f\n",
           seconds[0][0], seconds[0][1], seconds[0][0] / seconds[0][1]);
    printf("decimation-memory: mesh=dragon quadric=%.0f importance=%.0f\n",
           (double)collapse_memory(mesh.vertex_count, mesh.triangle_count, DECIMATE_QUADRIC) /
               mesh.vertex_count,
           (double)collapse_memory(mesh.vertex_count, mesh.triangle_count, DECIMATE_IMPORTANCE) /
               mesh.vertex_count);
    fflush(stdout);
    free(destination);
    bench_attributes(in, &mesh);
    free(importance);
    mesh_data_free(&mesh);
}

static void bench_parallel(void)
{
    warn_silence(1);
    scene *s = mitsuba_load(SHARED_DATA "/scenes/living-room/scene.xml");
    warn_silence(0);
    if (!s) {
        fprintf(stderr, "bench_decimation: %s\n", error_message());
        exit(1);
    }
    size_t n = s->mesh_count;
    decimate_input *in = calloc(n, sizeof *in);
    decimate_output *out = calloc(n, sizeof *out);
    int *status = calloc(n, sizeof *status);
    for (size_t m = 0; m < n; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        in[m] = (decimate_input){.name = mesh->name,
                                 .positions = mesh->positions,
                                 .vertex_count = mesh->vertex_count,
                                 .indices = mesh->indices,
                                 .triangle_count = mesh->triangle_count,
                                 .target_vertices = mesh->vertex_count / 10,
                                 .max_normal_angle = 60.0};
    }
    double seconds[2] = {1e30, 1e30};
    for (int round = 0; round < 2; round++)
        for (unsigned int threads = 1; threads <= 2; threads++) {
            double t0 = trace_seconds();
            if (decimate_many(in, out, status, NULL, n, DECIMATE_QUADRIC, threads, NULL)) {
                fprintf(stderr, "bench_decimation: a living-room mesh failed\n");
                exit(1);
            }
            seconds[threads - 1] = best_of(seconds[threads - 1], trace_seconds() - t0);
            for (size_t m = 0; m < n; m++)
                decimate_output_free(&out[m]);
        }
    printf("decimation-parallel: scene=living-room meshes=%zu one=%.2f two=%.2f speedup=%.2f\n", n,
           seconds[0], seconds[1], seconds[0] / seconds[1]);
    free(in);
    free(out);
    free(status);
    scene_free(s);
}

int main(void)
{
    bench_dragon();
    bench_parallel();
    return 0;
}
