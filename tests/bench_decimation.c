/* bench_decimation.c — `make bench`: decimation of the full Stanford dragon
 * (../shared/data/models/dragon_vrip.ply, 437,645 vertices) to 10 %:
 *
 *   decimation: importance=<s> quadric=<s> ratio=<importance/quadric> meshopt=<s> ...
 *
 * importance: our decimation (host/decimate.h: importance module, normal limit, history, our
 * collapse loop), with a synthetic importance field (high on one side of the dragon);
 * quadric: stock OpenMesh DecimaterT + ModQuadricT as Debian ships it, the baseline;
 * meshopt: meshoptimizer's meshopt_simplify to 10 % of the triangles, the fastest widely used
 * simplifier, for reference. And the parallel decimation of the living room's meshes:
 *
 *   decimation-parallel: meshes=<n> one=<s> two=<s> speedup=<one/two>
 *
 * The dragon runs once (20-40 s a method); the parallel figures are the best of ROUNDS runs. */
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>

#include "reduce/decimate.h"
#include "io/mitsuba.h"
#include "trace_common.h"

#define DRAGON_ROUNDS 1 /* one run is 20-40 s */
#define ROUNDS 2

static double best_of(double a, double b) { return a < b ? a : b; }

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
                         .max_normal_angle = 60.0};
    uint32_t start, uncollapsible;
    if (decimate_measure(&in, &start, &uncollapsible)) {
        fprintf(stderr, "bench_decimation: %s\n", error_message());
        exit(1);
    }
    in.target_vertices = start / 10;
    double ours = 1e30, stock = 1e30, meshopt = 1e30;
    uint32_t ours_vertices = 0;
    long stock_vertices = 0;
    size_t meshopt_triangles = 0;
    unsigned int *destination = malloc(3 * sizeof(unsigned int) * mesh.triangle_count);
    for (int round = 0; round < DRAGON_ROUNDS; round++) {
        decimate_output out;
        double t0 = trace_seconds();
        if (decimate_mesh(&in, DECIMATE_IMPORTANCE, &out)) {
            fprintf(stderr, "bench_decimation: %s\n", error_message());
            exit(1);
        }
        ours = best_of(ours, trace_seconds() - t0);
        ours_vertices = out.mesh.vertex_count;
        decimate_output_free(&out);

        decimate_input stock_in = in;
        stock_in.target_vertices = mesh.vertex_count / 10;
        t0 = trace_seconds();
        stock_vertices = decimate_stock_quadric(&stock_in);
        stock = best_of(stock, trace_seconds() - t0);

        t0 = trace_seconds();
        meshopt_triangles =
            meshopt_simplify(destination, mesh.indices, 3 * (size_t)mesh.triangle_count,
                             mesh.positions, mesh.vertex_count, 3 * sizeof(float),
                             3 * (size_t)(mesh.triangle_count / 10), 1.0f, 0, NULL) / 3;
        meshopt = best_of(meshopt, trace_seconds() - t0);
    }
    printf("decimation: importance=%.2f quadric=%.2f ratio=%.2f meshopt=%.2f "
           "importance/meshopt=%.1f vertices=%u target=%llu importance_vertices=%u "
           "quadric_vertices=%ld meshopt_triangles=%zu\n",
           ours, stock, ours / stock, meshopt, ours / meshopt, mesh.vertex_count,
           (unsigned long long)in.target_vertices, ours_vertices, stock_vertices,
           meshopt_triangles);
    fflush(stdout);
    free(destination);
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
    for (int round = 0; round < ROUNDS; round++)
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
