/* surface.h — what a ray finds in the scene: the closest hit and the surface there, in world
 * space. The one place the light transport kernels trace (lib/paths.h: camera and photon paths,
 * lib/shadows.h: shadow rays, kernels/sppm.cl: pixel centres), so that a flat and an instanced
 * scene differ only here.
 *
 *   flat scene         traverse_closest() on the BVH (lib/traverse.h); the per-triangle
 *                      buffers hold world-space data, read as they are.
 *   instanced scene    (IDMR_FEATURE_INSTANCES) traverse_instanced_closest() on the two-level
 *                      BVH (lib/traverse_instanced.h): the scene-global triangle of the
 *                      prototype (a later copy's triangles are its representative's) and the
 *                      instance hit (surface.instance: which copy, for the importance pass's
 *                      per-instance totals, lib/paths.h). The per-triangle buffers hold the
 *                      representative's world-space data, the prototype's object space, which
 *                      the instance's placement M (world = M object + m) carries to the copy:
 *     normal           normalize(M^-T n) = normalize(W^T n), W the instance's world_to_object
 *                      3x3 (no second matrix). The loaders reverse a mirrored copy's winding, so
 *                      its winding normal is +M^-T n, not det(M) M^-T n;
 *     shading normal   each corner carried the same way and normalised (as the loaders carry a
 *                      copy's vertex normals), then interpolated as in a flat scene;
 *     ray offset       idmr/ray.h: 2^-20 of the largest coordinate magnitude of the copy's
 *                      vertices, v_copy = M v + m, whose bound |v_copy| <= 2 S |v| + |p| (S the
 *                      instance's offset_scale, p the hit point, inside the triangle, so
 *                      |m| <= |p| + S |v|) gives offset <= 2 S offset_prototype + 2^-20 |p|:
 *                      that bound is used, at least what the flat copy would get.
 *                      Vectors are scaled to their largest component before normalising, so
 *                      that a transform of tiny or huge scale neither overflows nor underflows
 *                      the squared length.
 *
 * Eq. 2's weight, the side a path is on and scattering all take the world normal and the world
 * direction, as in a flat scene (the cosine between them is the same in any space where both
 * are carried correctly: world is where the camera and the lights are). */
#ifndef IDMR_KERNEL_SURFACE_H
#define IDMR_KERNEL_SURFACE_H

#include "lib/features.h"
#include "lib/scene.h"
#include "lib/shading.h"
#include "lib/traverse.h"
#if HAS_FEATURE(IDMR_FEATURE_INSTANCES)
#include "lib/traverse_instanced.h"
#endif

/* A ray's closest hit and the surface there. */
typedef struct surface {
    idmr_hit hit;   /* t along the ray, barycentrics, the scene triangle or IDMR_NO_HIT */
    float3 position; /* origin + t d */
    float3 normal;   /* unit winding normal */
    float3 shading;  /* shading normal, in normal's hemisphere (lib/shading.h) */
    float offset;    /* how far rays leaving it start off it (idmr/ray.h) */
    uint instance;   /* the instance hit (instances[] of the two-level BVH); 0 in a flat scene */
} surface;

#if HAS_FEATURE(IDMR_FEATURE_INSTANCES)
/* An object-space normal of instance `inst` in the world: W^T n, normalised. */
inline float3 instance_normal_to_world(global const idmr_instance *inst, float3 n)
{
    global const float *w = inst->world_to_object;
    float3 v = (float3)(w[0] * n.x + w[4] * n.y + w[8] * n.z,
                        w[1] * n.x + w[5] * n.y + w[9] * n.z,
                        w[2] * n.x + w[6] * n.y + w[10] * n.z);
    float3 a = fabs(v);
    float largest = fmax(a.x, fmax(a.y, a.z));
    return largest > 0.0f ? normalize(v / largest) : v;
}

/* The shading normal at a hit of instance `inst` whose world winding normal is n
 * (lib/shading.h, its corners carried to the world first). */
inline float3 instance_shading_normal(global const uint4 *triangle_shading,
                                      global const idmr_instance *inst, idmr_hit hit, float3 n)
{
    uint4 packed = triangle_shading[hit.triangle];
    if (packed.w == 0u)
        return n;
    return shading_interpolate(instance_normal_to_world(inst, unpack_normal(packed.x)),
                               instance_normal_to_world(inst, unpack_normal(packed.y)),
                               instance_normal_to_world(inst, unpack_normal(packed.z)), hit, n);
}

/* The largest coordinate magnitude of v. */
inline float largest_magnitude(float3 v)
{
    float3 a = fabs(v);
    return fmax(a.x, fmax(a.y, a.z));
}
#endif

/* The closest hit along origin + t d, t in (0, tmax), and the surface there; only `hit` is set
 * (triangle IDMR_NO_HIT) when nothing is hit. */
inline surface trace_surface(const scene_view *scene, float3 origin, float3 d, float tmax)
{
    surface s;
#if HAS_FEATURE(IDMR_FEATURE_INSTANCES)
    idmr_instance_hit ih = traverse_instanced_closest(scene->top_nodes, scene->instances,
                                                      scene->nodes, scene->leaves, origin, d,
                                                      0.0f, tmax);
    s.hit.t = ih.t;
    s.hit.u = ih.u;
    s.hit.v = ih.v;
    s.hit.triangle = ih.triangle;
    if (ih.triangle == IDMR_NO_HIT)
        return s;
    s.instance = ih.instance;
    global const idmr_instance *inst = scene->instances + ih.instance;
    float4 prototype = scene->triangle_normals[ih.triangle];
    s.normal = instance_normal_to_world(inst, prototype.xyz);
    s.shading = instance_shading_normal(scene->triangle_shading, inst, s.hit, s.normal);
    s.position = origin + s.hit.t * d;
    s.offset = fmax(2.0f * inst->offset_scale * prototype.w +
                        IDMR_RAY_OFFSET_SCALE * largest_magnitude(s.position),
                    IDMR_RAY_OFFSET_SCALE * largest_magnitude(origin));
#else
    s.hit = traverse_closest(scene->nodes, scene->leaves, origin, d, 0.0f, tmax);
    if (s.hit.triangle == IDMR_NO_HIT)
        return s;
    s.normal = scene->triangle_normals[s.hit.triangle].xyz;
    s.shading = shading_normal(scene->triangle_shading, s.hit, s.normal);
    s.position = origin + s.hit.t * d;
    s.offset = surface_offset(scene, s.hit.triangle, origin);
    s.instance = 0u;
#endif
    return s;
}

#endif
