/* instance_common.h — instanced scenes for the instanced traversal's test and benchmark:
 * prototypes from mesh files, random placements (rotations, scales, a mirror, a non-uniform
 * scale), the two-level BVH (host/device/instance_bvh.h) uploaded and traced with the trace
 * kernels (kernels/trace.cl: trace_instanced_closest/any), the same scene flattened into
 * world-space copies (the flat BVH's input, bvh_build_meshes), and Embree's own two-level
 * scene (RTC_GEOMETRY_TYPE_INSTANCE) as the reference. Header-only, no cmocka (the benchmark
 * uses it), on top of trace_common.h. */
#ifndef IDMR_TESTS_INSTANCE_COMMON_H
#define IDMR_TESTS_INSTANCE_COMMON_H

#include "device/instance_bvh.h"
#include "idmr/instance_bvh_layout.h"
#include "trace_common.h"

/* ---- placements ---- */

/* The object box of a prototype's vertices (min > max: no vertices). */
static inline bvh_box instance_prototype_box(const instance_prototype *p)
{
    bvh_box box = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (uint32_t v = 0; v < p->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            box.min[a] = fminf(box.min[a], p->positions[3 * (size_t)v + a]);
            box.max[a] = fmaxf(box.max[a], p->positions[3 * (size_t)v + a]);
        }
    return box;
}

/* Placement: world = R diag(scale) (object - centre) + position, R the rotation of the unit
 * quaternion q = (w, x, y, z). */
static inline instance_placement instance_place(uint32_t prototype, const float q[4],
                                                const float scale[3], const float centre[3],
                                                const float position[3])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    instance_placement p = {.prototype = prototype};
    for (int row = 0; row < 3; row++) {
        double translation = position[row];
        for (int c = 0; c < 3; c++) {
            double m = r[row][c] * scale[c];
            p.object_to_world[4 * row + c] = (float)m;
            translation -= m * centre[c];
        }
        p.object_to_world[4 * row + 3] = (float)translation;
    }
    return p;
}

/* `count` placements of prototype 0, whose box is `box`: random rotations (unit quaternions
 * from four near-Gaussian components), uniform scales in [0.6, 1.4], centres uniform in a cube 0.6 * cbrt(count) prototype diagonals wide
 * (their boxes overlap: a crowd, not a sparse scatter); placement 0 mirrors x (scale (-1, 1, 1)) and placement 1 is
 * stretched (scale (1, 2.5, 0.4)). Draws from the stream (seed, 0, IDMR_STREAM_TEST, i). */
static inline void instance_random_placements(const bvh_box *box, size_t count, unsigned int seed,
                                              instance_placement *out)
{
    float centre[3], diagonal = 0.0f;
    for (int a = 0; a < 3; a++) {
        centre[a] = 0.5f * (box->min[a] + box->max[a]);
        diagonal += (box->max[a] - box->min[a]) * (box->max[a] - box->min[a]);
    }
    diagonal = sqrtf(diagonal);
    float extent = 0.6f * cbrtf((float)count) * diagonal;
    for (size_t i = 0; i < count; i++) {
        idmr_rng rng = idmr_rng_init(seed, 0, IDMR_STREAM_TEST, (unsigned int)i);
        float q[4], norm = 0.0f;
        for (int k = 0; k < 4; k++) { /* a sum of three uniforms: near-Gaussian */
            q[k] = idmr_rng_float(&rng) + idmr_rng_float(&rng) + idmr_rng_float(&rng) - 1.5f;
            norm += q[k] * q[k];
        }
        for (int k = 0; k < 4; k++)
            q[k] /= sqrtf(norm);
        float s = 0.6f + 0.8f * idmr_rng_float(&rng);
        float scale[3] = {s, s, s}, position[3];
        if (i == 0)
            scale[0] = -1.0f, scale[1] = scale[2] = 1.0f;
        if (i == 1)
            scale[0] = 1.0f, scale[1] = 2.5f, scale[2] = 0.4f;
        for (int a = 0; a < 3; a++)
            position[a] = extent * (idmr_rng_float(&rng) - 0.5f);
        out[i] = instance_place(0, q, scale, centre, position);
    }
}

/* ---- the scene flattened: one world-space copy per instance ---- */

/* Copy i's triangles are numbered from first_triangle[i]; flat triangle f belongs to the last
 * copy whose first_triangle is <= f. */
typedef struct instance_flat {
    bvh_mesh *meshes; /* one per instance */
    float **positions;
    size_t count;
} instance_flat;

static inline void instance_flatten(const instanced_scene *s, instance_flat *out)
{
    out->count = s->instance_count;
    out->meshes = calloc(s->instance_count + 1, sizeof *out->meshes);
    out->positions = calloc(s->instance_count + 1, sizeof *out->positions);
    uint32_t first = 0;
    for (size_t i = 0; i < s->instance_count; i++) {
        const instance_placement *p = &s->instances[i];
        const instance_prototype *proto = &s->prototypes[p->prototype];
        float *world = malloc(3 * (size_t)proto->vertex_count * sizeof *world + 1);
        for (uint32_t v = 0; v < proto->vertex_count; v++)
            instance_placement_apply(p, &proto->positions[3 * (size_t)v], &world[3 * (size_t)v]);
        out->positions[i] = world;
        out->meshes[i] = (bvh_mesh){world, proto->indices, proto->triangle_count, first};
        first += proto->triangle_count;
    }
}

static inline void instance_flat_free(instance_flat *f)
{
    for (size_t i = 0; i < f->count; i++)
        free(f->positions[i]);
    free(f->positions);
    free(f->meshes);
    memset(f, 0, sizeof *f);
}

/* A flat hit as an instanced one: (copy, triangle in its prototype). */
static inline idmr_instance_hit instance_flat_hit(const instance_flat *f, const idmr_hit *hit)
{
    idmr_instance_hit out = {hit->t, hit->u, hit->v, IDMR_NO_HIT, IDMR_NO_HIT, {0, 0, 0}};
    if (hit->triangle == IDMR_NO_HIT)
        return out;
    size_t lo = 0, hi = f->count; /* the last copy with first_triangle <= triangle */
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (f->meshes[mid].first_triangle <= hit->triangle)
            lo = mid;
        else
            hi = mid;
    }
    while (lo > 0 && f->meshes[lo].triangle_count == 0) /* empty copies share a first */
        lo--;
    out.instance = (unsigned int)lo;
    out.triangle = hit->triangle - f->meshes[lo].first_triangle;
    return out;
}

/* ---- the two-level BVH on the device ---- */

typedef struct instance_geometry {
    instance_bvh tree;
    cl_mem top_nodes, instances, nodes, leaves;
} instance_geometry;

static inline void instance_geometry_release(instance_geometry *g)
{
    cl_mem buffers[] = {g->top_nodes, g->instances, g->nodes, g->leaves};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++)
        if (buffers[i])
            clReleaseMemObject(buffers[i]);
    instance_bvh_free(&g->tree);
    memset(g, 0, sizeof *g);
}

/* Builds and uploads the two-level BVH of s. Returns 0, or -1 with the error set. */
static inline int instance_geometry_upload(trace_device *t, const instanced_scene *s,
                                           instance_geometry *g)
{
    memset(g, 0, sizeof *g);
    if (instance_bvh_build(s, &g->tree))
        return -1;
    const instance_bvh *b = &g->tree;
    if (device_buffer(t->dev, CL_MEM_READ_ONLY, b->top_node_count * sizeof *b->top_nodes,
                      b->top_nodes, "top-level nodes", &g->top_nodes) ||
        device_buffer(t->dev, CL_MEM_READ_ONLY, (b->instance_count + 1) * sizeof *b->instances,
                      b->instances, "instances", &g->instances) ||
        /* no nodes or packets (no prototype triangles): a placeholder, never read */
        device_buffer(t->dev, CL_MEM_READ_ONLY, b->node_count * sizeof *b->nodes,
                      b->node_count ? b->nodes : NULL, "prototype nodes", &g->nodes) ||
        device_buffer(t->dev, CL_MEM_READ_ONLY, b->leaf_count * sizeof *b->leaves,
                      b->leaf_count ? b->leaves : NULL, "prototype leaves", &g->leaves)) {
        instance_geometry_release(g);
        return -1;
    }
    return 0;
}

/* Traces `count` rays through the two-level BVH, closest hit (any = 0) or any hit. */
static inline int instance_trace_run(trace_device *t, const instance_geometry *g,
                                     const idmr_ray *rays, idmr_instance_hit *hits, size_t count,
                                     int any, size_t local, double *seconds)
{
    cl_kernel k = any ? t->instanced_any : t->instanced_closest;
    const char *name = any ? "trace_instanced_any" : "trace_instanced_closest";
    if (DEVICE_SET_ARGS_FROM(k, name, 3, DEVICE_ARG(g->top_nodes), DEVICE_ARG(g->instances),
                             DEVICE_ARG(g->nodes), DEVICE_ARG(g->leaves)))
        return -1;
    return trace_kernel_run(t, k, name, rays, hits, sizeof *hits, count, local, seconds);
}

/* ---- Embree's two-level scene ---- */

/* One Embree scene per prototype (one triangle geometry, primID = its triangle), placed by
 * instance geometries whose geomID is the instance's index: rtcIntersect1's instID[0] and
 * primID are the instance and the prototype's triangle. Robust (watertight), like the kernels. */
static inline RTCScene instance_embree_scene(const instanced_scene *s)
{
    RTCDevice embree = bvh_embree_device();
    RTCScene *prototypes = calloc(s->prototype_count + 1, sizeof *prototypes);
    for (size_t p = 0; p < s->prototype_count; p++) {
        const instance_prototype *proto = &s->prototypes[p];
        prototypes[p] = rtcNewScene(embree);
        rtcSetSceneBuildQuality(prototypes[p], RTC_BUILD_QUALITY_HIGH);
        rtcSetSceneFlags(prototypes[p], RTC_SCENE_FLAG_ROBUST);
        if (proto->triangle_count > 0) {
            RTCGeometry g = rtcNewGeometry(embree, RTC_GEOMETRY_TYPE_TRIANGLE);
            rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       proto->positions, 0, 3 * sizeof(float),
                                       proto->vertex_count);
            rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                       proto->indices, 0, 3 * sizeof(uint32_t),
                                       proto->triangle_count);
            rtcCommitGeometry(g);
            rtcAttachGeometry(prototypes[p], g);
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(prototypes[p]);
    }
    RTCScene top = rtcNewScene(embree);
    rtcSetSceneBuildQuality(top, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(top, RTC_SCENE_FLAG_ROBUST);
    for (size_t i = 0; i < s->instance_count; i++) {
        const instance_placement *placement = &s->instances[i];
        RTCGeometry g = rtcNewGeometry(embree, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, prototypes[placement->prototype]);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, placement->object_to_world);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(top, g, (unsigned int)i);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(top);
    for (size_t p = 0; p < s->prototype_count; p++)
        rtcReleaseScene(prototypes[p]); /* the instances hold them */
    free(prototypes);
    return top;
}

static inline idmr_instance_hit instance_embree_closest(RTCScene es, const idmr_ray *ray)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh;
    rh.ray = trace_embree_ray(ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(es, &context, &rh);
    int hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    idmr_instance_hit out = {rh.ray.tfar, rh.hit.u, rh.hit.v, hit ? rh.hit.primID : IDMR_NO_HIT,
                             hit ? rh.hit.instID[0] : IDMR_NO_HIT, {0, 0, 0}};
    return out;
}

/* ---- prototypes from files ---- */

/* A prototype holding a mesh file's triangles (the mesh_data stays the caller's to free). */
static inline instance_prototype instance_prototype_of_mesh(const mesh_data *m)
{
    return (instance_prototype){.positions = m->positions, .vertex_count = m->vertex_count,
                                .indices = m->indices, .triangle_count = m->triangle_count};
}

#endif
