/* trace_common.h — rays, cameras and the Embree reference, shared by the traversal test and
 * benchmark, the importance tests (camera rays, Embree) and bench_decimation (timing): scenes
 * from single mesh files; ray sets (incoherent, and camera rays through the project's one
 * camera formula, idmr/camera.h) drawn from the project's one generator (idmr/rng.h, stream
 * IDMR_STREAM_TEST); the OpenCL trace kernels on a device the caller opened; Embree's
 * rtcIntersect1/rtcOccluded1 as the reference. Header-only (static inline functions); no
 * cmocka, so that the benchmarks can use it. */
#ifndef IDMR_TESTS_TRACE_COMMON_H
#define IDMR_TESTS_TRACE_COMMON_H

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "device/bvh.h"
#include "device/device.h"
#include "device/program.h"
#include "core/error.h"
#include "idmr/camera.h"
#include "idmr/ray.h"
#include "idmr/rng.h"
#include "io/mesh/mesh_io.h"
#include "core/scene.h"

#define SHARED_DATA "../shared/data"

static inline double trace_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A scene holding one mesh file (one diffuse material), or NULL with the error set. */
static inline scene *trace_scene_from_mesh(const char *path)
{
    mesh_data mesh;
    if (mesh_io_read(path, &mesh))
        return NULL;
    scene *s = scene_create(path);
    idmr_material white = {{0.8f, 0.8f, 0.8f}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1, -1, 0};
    uint32_t material = scene_add_material(s, "white", "diffuse", &white);
    scene_mesh *m = scene_add_mesh(s, "mesh", "ply", path, 0, mesh.vertex_count, mesh.positions,
                                   mesh.triangle_count, mesh.indices, mesh.texcoords);
    m->material = material;
    if (scene_finalize(s)) {
        scene_free(s);
        return NULL;
    }
    return s;
}

/* Embree scene over all meshes as one geometry whose primID is the scene triangle index. */
static inline RTCScene trace_embree_scene(const scene *s)
{
    RTCDevice embree = bvh_embree_device();
    RTCScene es = rtcNewScene(embree);
    rtcSetSceneBuildQuality(es, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(es, RTC_SCENE_FLAG_ROBUST); /* watertight, like the kernels */
    RTCGeometry g = rtcNewGeometry(embree, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), s->vertex_count + 1);
    unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), s->triangle_count);
    size_t vbase = 0, t = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        memcpy(v + 3 * vbase, mesh->positions, 3 * sizeof(float) * mesh->vertex_count);
        for (uint32_t i = 0; i < 3 * mesh->triangle_count; i++)
            ix[3 * t + i] = (unsigned)(vbase + mesh->indices[i]);
        t += mesh->triangle_count;
        vbase += mesh->vertex_count;
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(es, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(es);
    return es;
}

static inline void trace_set_ray(idmr_ray *r, const float o[3], const float d[3], float tmin,
                                 float tmax)
{
    memcpy(r->origin, o, sizeof r->origin);
    memcpy(r->direction, d, sizeof r->direction);
    r->tmin = tmin;
    r->tmax = tmax;
}

/* Incoherent rays: origins uniform in the box (lo, hi) grown by 5% on each side, directions
 * uniform on the sphere; ray i draws from the stream (seed, 0, IDMR_STREAM_TEST, i) of
 * idmr/rng.h. */
static inline void trace_random_rays_in_box(const float lo[3], const float hi[3], idmr_ray *rays,
                                            size_t count, unsigned int seed)
{
    for (size_t i = 0; i < count; i++) {
        idmr_rng rng = idmr_rng_init(seed, 0, IDMR_STREAM_TEST, (unsigned int)i);
        float o[3], d[3];
        for (int k = 0; k < 3; k++) {
            float extent = hi[k] - lo[k];
            o[k] = lo[k] - 0.05f * extent + 1.1f * extent * idmr_rng_float(&rng);
        }
        float z = 1.0f - 2.0f * idmr_rng_float(&rng);
        float phi = 6.2831853f * idmr_rng_float(&rng);
        float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        d[0] = r * cosf(phi);
        d[1] = r * sinf(phi);
        d[2] = z;
        trace_set_ray(&rays[i], o, d, 0.0f, INFINITY);
    }
}

/* Incoherent rays in the scene's box (trace_random_rays_in_box). */
static inline void trace_random_rays(const scene *s, idmr_ray *rays, size_t count,
                                     unsigned int seed)
{
    trace_random_rays_in_box(s->bbox_min, s->bbox_max, rays, count, seed);
}

/* ---- cameras: the project's one camera-ray formula (idmr/camera.h) ---- */

static inline void trace_normalize(float v[3])
{
    float n = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++)
        v[k] /= n;
}

static inline void trace_cross(const float a[3], const float b[3], float out[3])
{
    float c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(out, c, sizeof c);
}

/* A pinhole at `origin` looking at `target`: right = forward × up_hint, up = right × forward
 * (all unit); tan_half_y follows from the aspect ratio. */
static inline idmr_camera trace_look_at(const float origin[3], const float target[3],
                                        const float up_hint[3], unsigned int width,
                                        unsigned int height, float tan_half_x)
{
    idmr_camera c;
    memset(&c, 0, sizeof c);
    memcpy(c.origin, origin, sizeof c.origin);
    for (int k = 0; k < 3; k++)
        c.forward[k] = target[k] - origin[k];
    trace_normalize(c.forward);
    trace_cross(c.forward, up_hint, c.right);
    trace_normalize(c.right);
    trace_cross(c.right, c.forward, c.up);
    trace_normalize(c.up);
    c.width = width;
    c.height = height;
    c.tan_half_x = tan_half_x;
    c.tan_half_y = tan_half_x * (float)height / (float)width;
    return c;
}

/* The unit direction of the ray through film position (film_x, film_y) of a width x height
 * image of camera c: idmr_camera_direction() on c with its film size replaced. The centre of
 * pixel (x, y) is (x + 0.5, y + 0.5). */
static inline void trace_film_direction(const idmr_camera *c, unsigned int width,
                                        unsigned int height, float film_x, float film_y,
                                        float d[3])
{
    idmr_camera film = *c;
    film.width = width;
    film.height = height;
    idmr_camera_direction(&film, film_x, film_y, d);
    trace_normalize(d);
}

/* The jittered ray of pixel `pixel` (row by row) of that image as the kernels' camera paths
 * draw it: x jitter, then y jitter, from the stream (seed, iteration, stream, pixel). */
static inline void trace_jittered_direction(const idmr_camera *c, unsigned int width,
                                            unsigned int height, unsigned int seed,
                                            unsigned int iteration, unsigned int stream,
                                            unsigned int pixel, float d[3])
{
    idmr_rng rng = idmr_rng_init(seed, iteration, stream, pixel);
    float film_x = (float)(pixel % width) + idmr_rng_float(&rng);
    float film_y = (float)(pixel / width) + idmr_rng_float(&rng);
    trace_film_direction(c, width, height, film_x, film_y, d);
}

/* Camera rays of a width x height image, row by row, one jittered ray per pixel (stream
 * IDMR_STREAM_TEST). */
static inline void trace_camera_rays(const idmr_camera *c, idmr_ray *rays, unsigned int width,
                                     unsigned int height, unsigned int seed)
{
    for (unsigned int p = 0; p < width * height; p++) {
        float d[3];
        trace_jittered_direction(c, width, height, seed, 0, IDMR_STREAM_TEST, p, d);
        trace_set_ray(&rays[p], c->origin, d, 0.0f, INFINITY);
    }
}

/* A camera outside the box (lo, hi) looking at its centre from direction (1, 0.6, 1.6). */
static inline idmr_camera trace_overview_camera_of_box(const float lo[3], const float hi[3],
                                                       unsigned int width, unsigned int height)
{
    float center[3], away[3] = {1.0f, 0.6f, 1.6f}, origin[3];
    const float up[3] = {0, 1, 0};
    trace_normalize(away);
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += hi[k] > lo[k] ? ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]) : 0;
    float diagonal = (float)sqrt(d2);
    for (int k = 0; k < 3; k++) {
        center[k] = 0.5f * (lo[k] + hi[k]);
        origin[k] = center[k] + 1.2f * diagonal * away[k];
    }
    return trace_look_at(origin, center, up, width, height, 0.45f);
}

/* A camera outside the scene box looking at its centre (trace_overview_camera_of_box). */
static inline idmr_camera trace_overview_camera(const scene *s, unsigned int width,
                                                unsigned int height)
{
    return trace_overview_camera_of_box(s->bbox_min, s->bbox_max, width, height);
}

/* ---- OpenCL side ---- */

/* The trace kernels (kernels/trace.cl) built on a device that the caller opened. */
typedef struct trace_device {
    device *dev;
    cl_program program;
    cl_kernel closest;
    cl_kernel any;
    cl_kernel instanced_closest; /* the two-level BVH (instance_common.h) */
    cl_kernel instanced_any;
} trace_device;

static inline void trace_device_close(trace_device *t)
{
    cl_kernel kernels[] = {t->closest, t->any, t->instanced_closest, t->instanced_any};
    for (size_t i = 0; i < sizeof kernels / sizeof kernels[0]; i++)
        if (kernels[i])
            clReleaseKernel(kernels[i]);
    if (t->program)
        clReleaseProgram(t->program);
    memset(t, 0, sizeof *t);
}

/* Builds the trace program on d (from idmr's program cache after the first build). Returns 0,
 * or -1 with the error set and nothing left to release. */
static inline int trace_device_open(trace_device *t, device *d)
{
    memset(t, 0, sizeof *t);
    t->dev = d;
    char *options = device_build_options(d, 0, NULL);
    int status = device_build_program(d, "trace.cl", options, &t->program);
    free(options);
    if (status || device_create_kernel(t->program, "trace_closest", &t->closest) ||
        device_create_kernel(t->program, "trace_any", &t->any) ||
        device_create_kernel(t->program, "trace_instanced_closest", &t->instanced_closest) ||
        device_create_kernel(t->program, "trace_instanced_any", &t->instanced_any)) {
        trace_device_close(t);
        return -1;
    }
    return 0;
}

/* trace_device_open(), saying on stderr why it failed (a test group's setup). */
static inline int trace_device_open_reporting(trace_device *t, device *d)
{
    if (trace_device_open(t, d) == 0)
        return 0;
    fprintf(stderr, "trace_device_open: %s\n", error_message());
    return -1;
}

/* The BVH of one scene, uploaded. */
typedef struct trace_geometry {
    bvh tree;
    cl_mem nodes;
    cl_mem leaves;
} trace_geometry;

/* Uploads the BVH already built in g->tree. */
static inline int trace_geometry_upload_tree(trace_device *t, trace_geometry *g)
{
    if (device_buffer(t->dev, CL_MEM_READ_ONLY, g->tree.node_count * sizeof(idmr_bvh_node),
                      g->tree.nodes, "BVH nodes", &g->nodes) ||
        device_buffer(t->dev, CL_MEM_READ_ONLY, g->tree.leaf_count * sizeof(idmr_triangle4),
                      g->tree.leaves, "BVH leaves", &g->leaves))
        return -1;
    return 0;
}

static inline int trace_geometry_upload(trace_device *t, const scene *s, trace_geometry *g)
{
    memset(g, 0, sizeof *g);
    if (bvh_build(s, &g->tree))
        return -1;
    return trace_geometry_upload_tree(t, g);
}

static inline void trace_geometry_release(trace_geometry *g)
{
    if (g->nodes)
        clReleaseMemObject(g->nodes);
    if (g->leaves)
        clReleaseMemObject(g->leaves);
    bvh_free(&g->tree);
}

/* Runs trace kernel k (rays, hits, ray count, then its geometry, which the caller has set from
 * argument 3 on) over `count` rays into hits of `hit_size` bytes each; *seconds gets the kernel
 * time (upload and download excluded) when not NULL. */
static inline int trace_kernel_run(trace_device *t, cl_kernel k, const char *name,
                                   const idmr_ray *rays, void *hits, size_t hit_size, size_t count,
                                   size_t local, double *seconds)
{
    cl_mem ray_buffer, hit_buffer;
    if (device_buffer(t->dev, CL_MEM_READ_ONLY, count * sizeof *rays, rays, "rays", &ray_buffer))
        return -1;
    if (device_buffer(t->dev, CL_MEM_WRITE_ONLY, count * hit_size, NULL, "hits", &hit_buffer)) {
        clReleaseMemObject(ray_buffer);
        return -1;
    }
    cl_uint n = (cl_uint)count;
    int status = DEVICE_SET_ARGS(k, name, DEVICE_ARG(ray_buffer), DEVICE_ARG(hit_buffer),
                                 DEVICE_ARG(n));
    double start = trace_seconds();
    if (!status)
        status = device_run(t->dev, k, name, count, local);
    if (seconds)
        *seconds = trace_seconds() - start;
    if (!status)
        status = device_read(t->dev, hit_buffer, count * hit_size, hits, "hits");
    clReleaseMemObject(ray_buffer);
    clReleaseMemObject(hit_buffer);
    return status;
}

/* Traces `count` rays with the closest (any = 0) or any-hit kernel; *seconds gets the kernel
 * time (upload and download excluded) when not NULL. */
static inline int trace_device_run(trace_device *t, const trace_geometry *g,
                                   const idmr_ray *rays, idmr_hit *hits, size_t count, int any,
                                   size_t local, double *seconds)
{
    cl_kernel k = any ? t->any : t->closest;
    const char *name = any ? "trace_any" : "trace_closest";
    if (DEVICE_SET_ARGS_FROM(k, name, 3, DEVICE_ARG(g->nodes), DEVICE_ARG(g->leaves)))
        return -1;
    return trace_kernel_run(t, k, name, rays, hits, sizeof *hits, count, local, seconds);
}

/* ---- Embree reference ---- */

/* Embree's form of a ray. */
static inline struct RTCRay trace_embree_ray(const idmr_ray *ray)
{
    struct RTCRay r;
    r.org_x = ray->origin[0];
    r.org_y = ray->origin[1];
    r.org_z = ray->origin[2];
    r.dir_x = ray->direction[0];
    r.dir_y = ray->direction[1];
    r.dir_z = ray->direction[2];
    r.tnear = ray->tmin;
    r.tfar = ray->tmax;
    r.mask = 0xffffffffu;
    r.flags = 0;
    r.time = 0;
    r.id = 0;
    return r;
}

static inline void trace_embree_closest(RTCScene es, const idmr_ray *ray, idmr_hit *hit)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh;
    rh.ray = trace_embree_ray(ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(es, &context, &rh);
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->triangle = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? IDMR_NO_HIT : rh.hit.primID;
}

static inline int trace_embree_occluded(RTCScene es, const idmr_ray *ray)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRay r = trace_embree_ray(ray);
    rtcOccluded1(es, &context, &r);
    return r.tfar < 0.0f; /* Embree sets tfar to -inf when occluded */
}

typedef struct trace_embree_job {
    RTCScene scene;
    const idmr_ray *rays;
    idmr_hit *hits;
    size_t begin, end;
} trace_embree_job;

static inline void *trace_embree_worker(void *arg)
{
    trace_embree_job *job = arg;
    for (size_t i = job->begin; i < job->end; i++)
        trace_embree_closest(job->scene, &job->rays[i], &job->hits[i]);
    return NULL;
}

/* rtcIntersect1 over all rays on `threads` threads (contiguous chunks); returns seconds. */
static inline double trace_embree_batch(RTCScene es, const idmr_ray *rays, idmr_hit *hits,
                                        size_t count, int threads)
{
    pthread_t tid[64];
    trace_embree_job jobs[64];
    if (threads > 64)
        threads = 64;
    double start = trace_seconds();
    for (int i = 0; i < threads; i++) {
        jobs[i] = (trace_embree_job){es, rays, hits, count * i / threads,
                                     count * (i + 1) / threads};
        pthread_create(&tid[i], NULL, trace_embree_worker, &jobs[i]);
    }
    for (int i = 0; i < threads; i++)
        pthread_join(tid[i], NULL);
    return trace_seconds() - start;
}

#endif
