/* trace_common.h — shared by the traversal test and benchmark (and used by test_importance and
 * bench_decimation for the Embree reference and timing): scenes from
 * single mesh files, ray sets (incoherent and camera), the OpenCL trace kernels, and Embree's
 * rtcIntersect1/rtcOccluded1 as the reference. Header-only (static functions): each program
 * includes it once. */
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
#include "idmr/ray.h"
#include "io/mesh_io.h"
#include "core/scene.h"

#define SHARED_DATA "../shared/data"

static inline double trace_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* splitmix64: a reproducible stream of uniform floats in [0, 1). */
static inline float trace_random(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (float)(z >> 40) * (1.0f / 16777216.0f);
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

static inline void trace_set_ray(idmr_ray *r, const float o[3], const float d[3], float tmin, float tmax)
{
    memcpy(r->origin, o, sizeof r->origin);
    memcpy(r->direction, d, sizeof r->direction);
    r->tmin = tmin;
    r->tmax = tmax;
}

/* Incoherent rays: origins uniform in the (slightly grown) scene box, directions uniform on
 * the sphere. */
static inline void trace_random_rays(const scene *s, idmr_ray *rays, size_t count, uint64_t seed)
{
    uint64_t state = seed;
    for (size_t i = 0; i < count; i++) {
        float o[3], d[3];
        for (int k = 0; k < 3; k++) {
            float extent = s->bbox_max[k] - s->bbox_min[k];
            o[k] = s->bbox_min[k] - 0.05f * extent + 1.1f * extent * trace_random(&state);
        }
        float z = 1.0f - 2.0f * trace_random(&state);
        float phi = 6.2831853f * trace_random(&state);
        float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        d[0] = r * cosf(phi);
        d[1] = r * sinf(phi);
        d[2] = z;
        trace_set_ray(&rays[i], o, d, 0.0f, INFINITY);
    }
}

/* Camera rays of a width x height image, row by row, one jittered ray per pixel. */
static inline void trace_camera_rays(const idmr_camera *c, idmr_ray *rays, unsigned width,
                              unsigned height, uint64_t seed)
{
    uint64_t state = seed;
    for (unsigned y = 0; y < height; y++)
        for (unsigned x = 0; x < width; x++) {
            float sx = (2.0f * (x + trace_random(&state)) / width - 1.0f) * c->tan_half_x;
            float sy = (1.0f - 2.0f * (y + trace_random(&state)) / height) * c->tan_half_y;
            float d[3];
            for (int k = 0; k < 3; k++)
                d[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
            float n = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int k = 0; k < 3; k++)
                d[k] /= n;
            trace_set_ray(&rays[(size_t)y * width + x], c->origin, d, 0.0f, INFINITY);
        }
}

/* A camera outside the scene box looking at its centre from direction (1, 0.6, 1.6). */
static inline idmr_camera trace_overview_camera(const scene *s, unsigned width, unsigned height)
{
    idmr_camera c;
    memset(&c, 0, sizeof c);
    float center[3], diag = 0;
    for (int k = 0; k < 3; k++) {
        center[k] = 0.5f * (s->bbox_min[k] + s->bbox_max[k]);
        float e = s->bbox_max[k] - s->bbox_min[k];
        diag += e * e;
    }
    diag = sqrtf(diag);
    float away[3] = {1.0f, 0.6f, 1.6f};
    float n = sqrtf(away[0] * away[0] + away[1] * away[1] + away[2] * away[2]);
    for (int k = 0; k < 3; k++) {
        c.origin[k] = center[k] + 1.2f * diag * away[k] / n;
        c.forward[k] = -away[k] / n;
    }
    float up[3] = {0, 1, 0};
    /* right = forward x up, up = right x forward */
    c.right[0] = c.forward[1] * up[2] - c.forward[2] * up[1];
    c.right[1] = c.forward[2] * up[0] - c.forward[0] * up[2];
    c.right[2] = c.forward[0] * up[1] - c.forward[1] * up[0];
    n = sqrtf(c.right[0] * c.right[0] + c.right[1] * c.right[1] + c.right[2] * c.right[2]);
    for (int k = 0; k < 3; k++)
        c.right[k] /= n;
    c.up[0] = c.right[1] * c.forward[2] - c.right[2] * c.forward[1];
    c.up[1] = c.right[2] * c.forward[0] - c.right[0] * c.forward[2];
    c.up[2] = c.right[0] * c.forward[1] - c.right[1] * c.forward[0];
    c.width = width;
    c.height = height;
    c.tan_half_x = 0.45f;
    c.tan_half_y = 0.45f * height / width;
    return c;
}

/* ---- OpenCL side ---- */

typedef struct trace_device {
    device dev;
    cl_program program;
    cl_kernel closest;
    cl_kernel any;
} trace_device;

static inline int trace_device_open(trace_device *t)
{
    memset(t, 0, sizeof *t);
    if (device_open(&t->dev, -1))
        return -1;
    char *options = device_build_options(&t->dev, 0, NULL);
    int status = device_build_program(&t->dev, "trace.cl", options, &t->program);
    free(options);
    if (status)
        return -1;
    if (device_create_kernel(t->program, "trace_closest", &t->closest) ||
        device_create_kernel(t->program, "trace_any", &t->any))
        return -1;
    return 0;
}

static inline void trace_device_close(trace_device *t)
{
    if (t->closest)
        clReleaseKernel(t->closest);
    if (t->any)
        clReleaseKernel(t->any);
    if (t->program)
        clReleaseProgram(t->program);
    device_close(&t->dev);
}

/* The BVH of one scene, uploaded. */
typedef struct trace_geometry {
    bvh tree;
    cl_mem nodes;
    cl_mem leaves;
} trace_geometry;

static inline int trace_geometry_upload(trace_device *t, const scene *s, trace_geometry *g)
{
    memset(g, 0, sizeof *g);
    if (bvh_build(s, &g->tree))
        return -1;
    if (device_buffer(&t->dev, CL_MEM_READ_ONLY, g->tree.node_count * sizeof(idmr_bvh_node),
                      g->tree.nodes, "BVH nodes", &g->nodes) ||
        device_buffer(&t->dev, CL_MEM_READ_ONLY, g->tree.leaf_count * sizeof(idmr_triangle4),
                      g->tree.leaves, "BVH leaves", &g->leaves))
        return -1;
    return 0;
}

static inline void trace_geometry_release(trace_geometry *g)
{
    if (g->nodes)
        clReleaseMemObject(g->nodes);
    if (g->leaves)
        clReleaseMemObject(g->leaves);
    bvh_free(&g->tree);
}

/* Traces `count` rays with the closest (any = 0) or any-hit kernel; *seconds gets the kernel
 * time (upload and download excluded) when not NULL. */
static inline int trace_device_run(trace_device *t, const trace_geometry *g, const idmr_ray *rays,
                            idmr_hit *hits, size_t count, int any, size_t local, double *seconds)
{
    cl_mem ray_buffer, hit_buffer;
    if (device_buffer(&t->dev, CL_MEM_READ_ONLY, count * sizeof *rays, rays, "rays", &ray_buffer))
        return -1;
    if (device_buffer(&t->dev, CL_MEM_WRITE_ONLY, count * sizeof *hits, NULL, "hits", &hit_buffer)) {
        clReleaseMemObject(ray_buffer);
        return -1;
    }
    cl_kernel k = any ? t->any : t->closest;
    const char *name = any ? "trace_any" : "trace_closest";
    cl_uint n = (cl_uint)count;
    int status = DEVICE_SET_ARGS(k, name, DEVICE_ARG(ray_buffer), DEVICE_ARG(hit_buffer),
                                 DEVICE_ARG(n), DEVICE_ARG(g->nodes), DEVICE_ARG(g->leaves));
    double start = trace_seconds();
    if (!status)
        status = device_run(&t->dev, k, name, count, local);
    if (seconds)
        *seconds = trace_seconds() - start;
    if (!status)
        status = device_read(&t->dev, hit_buffer, count * sizeof *hits, hits, "hits");
    clReleaseMemObject(ray_buffer);
    clReleaseMemObject(hit_buffer);
    return status;
}

/* ---- Embree reference ---- */

static inline void trace_embree_closest(RTCScene es, const idmr_ray *ray, idmr_hit *hit)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh;
    rh.ray.org_x = ray->origin[0];
    rh.ray.org_y = ray->origin[1];
    rh.ray.org_z = ray->origin[2];
    rh.ray.dir_x = ray->direction[0];
    rh.ray.dir_y = ray->direction[1];
    rh.ray.dir_z = ray->direction[2];
    rh.ray.tnear = ray->tmin;
    rh.ray.tfar = ray->tmax;
    rh.ray.mask = 0xffffffffu;
    rh.ray.flags = 0;
    rh.ray.time = 0;
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
static inline double trace_embree_batch(RTCScene es, const idmr_ray *rays, idmr_hit *hits, size_t count,
                                 int threads)
{
    pthread_t tid[64];
    trace_embree_job jobs[64];
    if (threads > 64)
        threads = 64;
    double start = trace_seconds();
    for (int i = 0; i < threads; i++) {
        jobs[i] = (trace_embree_job){es, rays, hits, count * i / threads, count * (i + 1) / threads};
        pthread_create(&tid[i], NULL, trace_embree_worker, &jobs[i]);
    }
    for (int i = 0; i < threads; i++)
        pthread_join(tid[i], NULL);
    return trace_seconds() - start;
}

#endif
