/* bench_traversal.c — `make bench`: OpenCL BVH traversal vs Embree rtcIntersect1 on the full
 * Stanford dragon (../shared/data/models/dragon_vrip.ply), same rays, same thread count
 * (PoCL runs on all cores; Embree gets as many pthreads).
 *
 * Prints per ray set:
 *   traversal: rays=<set> count=<n> opencl=<Mrays/s> embree=<Mrays/s> ratio=<opencl/embree>
 * Then the instanced traversal (kernels/lib/traverse_instanced.h) against the flat traversal of
 * the same scene flattened: the dragon at resolution 3 placed INSTANCES times
 * (instance_random_placements), 1M incoherent rays, both measured in this run:
 *   traversal: rays=incoherent instanced instances=<n> opencl=<Mrays/s> flat=<Mrays/s>
 *              ratio=<instanced/flat> memory_ratio=<instanced bytes / flat bytes>
 * (one line; the bytes are the BVHs' device arrays, instance_bvh_device_bytes and
 * bvh_device_bytes).
 * Each side runs once to warm up, then REPEATS times; the best time counts (the machines are
 * shared and noisy: the best run is the one least disturbed). Kernel time only: ray upload
 * and hit download are excluded on the OpenCL side, as Embree has no such copies. */
#include <unistd.h>

#include "instance_common.h"

#define REPEATS 5
#define INSTANCES 50

/* The best closest-hit kernel time over REPEATS runs (after one warm-up) through the flat BVH
 * g, or, when g is NULL, the two-level BVH `instanced` (hits then idmr_instance_hit). */
static double best_opencl(trace_device *t, const trace_geometry *g,
                          const instance_geometry *instanced, const idmr_ray *rays, void *hits,
                          size_t count)
{
    double best = 1e30;
    for (int r = 0; r <= REPEATS; r++) {
        double seconds;
        if (g ? trace_device_run(t, g, rays, hits, count, 0, 0, &seconds)
              : instance_trace_run(t, instanced, rays, hits, count, 0, 0, &seconds)) {
            fprintf(stderr, "bench_traversal: %s\n", error_message());
            exit(1);
        }
        if (r > 0 && seconds < best)
            best = seconds;
    }
    return best;
}

static double best_embree(RTCScene es, const idmr_ray *rays, idmr_hit *hits, size_t count,
                          int threads)
{
    double best = 1e30;
    for (int r = 0; r <= REPEATS; r++) {
        double seconds = trace_embree_batch(es, rays, hits, count, threads);
        if (r > 0 && seconds < best)
            best = seconds;
    }
    return best;
}

static void bench_rays(const char *name, trace_device *t, const trace_geometry *g, RTCScene es,
                       const idmr_ray *rays, size_t count, int threads)
{
    idmr_hit *hits = malloc(count * sizeof *hits);
    idmr_hit *reference = malloc(count * sizeof *reference);
    double opencl = best_opencl(t, g, NULL, rays, hits, count);
    double embree = best_embree(es, rays, reference, count, threads);
    size_t differ = 0;
    for (size_t i = 0; i < count; i++)
        differ += hits[i].triangle != reference[i].triangle &&
                  fabsf(hits[i].t - reference[i].t) > 1e-4f * fabsf(reference[i].t);
    double opencl_mrays = count / opencl * 1e-6, embree_mrays = count / embree * 1e-6;
    printf("traversal: rays=%s count=%zu opencl=%.2f embree=%.2f ratio=%.2f threads=%d "
           "disagreements=%zu\n",
           name, count, opencl_mrays, embree_mrays, opencl_mrays / embree_mrays, threads, differ);
    fflush(stdout);
    free(hits);
    free(reference);
}

/* The instanced line (see the top of the file). */
static void bench_instanced(trace_device *t)
{
    const char *path = SHARED_DATA "/models/dragon_vrip_res3.ply";
    mesh_data dragon;
    if (mesh_io_read(path, &dragon)) {
        fprintf(stderr, "bench_traversal: %s\n", error_message());
        exit(1);
    }
    instance_prototype proto = instance_prototype_of_mesh(&dragon);
    instance_placement placements[INSTANCES];
    bvh_box box = instance_prototype_box(&proto);
    instance_random_placements(&box, INSTANCES, 1, placements);
    instanced_scene s = {&proto, 1, placements, INSTANCES};
    instance_geometry instanced;
    trace_geometry flat = {0};
    instance_flat copies;
    instance_flatten(&s, &copies);
    if (instance_geometry_upload(t, &s, &instanced) ||
        bvh_build_meshes(copies.meshes, copies.count, &flat.tree) ||
        trace_geometry_upload_tree(t, &flat)) {
        fprintf(stderr, "bench_traversal: %s\n", error_message());
        exit(1);
    }
    size_t count = 1u << 20;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays_in_box(instanced.tree.bounds_min, instanced.tree.bounds_max, rays, count, 13);
    idmr_instance_hit *instanced_hits = malloc(count * sizeof *instanced_hits);
    idmr_hit *flat_hits = malloc(count * sizeof *flat_hits);
    double instanced_seconds = best_opencl(t, NULL, &instanced, rays, instanced_hits, count);
    double flat_seconds = best_opencl(t, &flat, NULL, rays, flat_hits, count);
    double instanced_mrays = count / instanced_seconds * 1e-6, flat_mrays = count / flat_seconds * 1e-6;
    uint64_t instanced_bytes = instance_bvh_device_bytes(&instanced.tree);
    uint64_t flat_bytes = bvh_device_bytes(&flat.tree);
    printf("traversal: rays=incoherent instanced instances=%d opencl=%.2f flat=%.2f ratio=%.2f "
           "memory_ratio=%.4f instanced_bytes=%llu flat_bytes=%llu triangles=%u\n",
           INSTANCES, instanced_mrays, flat_mrays, instanced_mrays / flat_mrays,
           (double)instanced_bytes / (double)flat_bytes, (unsigned long long)instanced_bytes,
           (unsigned long long)flat_bytes, INSTANCES * dragon.triangle_count);
    fflush(stdout);
    free(rays);
    free(instanced_hits);
    free(flat_hits);
    trace_geometry_release(&flat);
    instance_geometry_release(&instanced);
    instance_flat_free(&copies);
    mesh_data_free(&dragon);
}

int main(void)
{
    const char *path = SHARED_DATA "/models/dragon_vrip.ply";
    scene *s = trace_scene_from_mesh(path);
    if (!s) {
        fprintf(stderr, "bench_traversal: %s\n", error_message());
        return 1;
    }
    device d;
    trace_device t;
    trace_geometry g;
    if (device_open(&d, -1) || trace_device_open(&t, &d) || trace_geometry_upload(&t, s, &g)) {
        fprintf(stderr, "bench_traversal: %s\n", error_message());
        return 1;
    }
    RTCScene es = trace_embree_scene(s);
    int threads = (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (threads < 1)
        threads = 1;
    printf("traversal: scene=%s triangles=%llu bvh_nodes=%zu bvh_leaves=%zu bvh_refs=%zu "
           "device=\"%s\"\n",
           path, (unsigned long long)s->triangle_count, g.tree.node_count, g.tree.leaf_count,
           g.tree.reference_count, d.info.name);

    size_t count = 1u << 20;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays(s, rays, count, 11);
    bench_rays("incoherent", &t, &g, es, rays, count, threads);

    idmr_camera cam = trace_overview_camera(s, 1024, 1024);
    trace_camera_rays(&cam, rays, cam.width, cam.height, 12);
    bench_rays("camera", &t, &g, es, rays, count, threads);
    bench_instanced(&t);

    free(rays);
    rtcReleaseScene(es);
    trace_geometry_release(&g);
    trace_device_close(&t);
    device_close(&d);
    scene_free(s);
    return 0;
}
