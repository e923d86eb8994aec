/* trace.cl — ray batches through the BVH: closest hit and any hit (occlusion), through the
 * flat BVH and through the two-level BVH of an instanced scene.
 * Used by the traversal tests (against Embree), the shading tests and the traversal
 * benchmark; the light transport kernels trace through lib/surface.h, which calls the same
 * traverse_closest() or, for an instanced scene, traverse_instanced_closest(). */
#include "lib/shading.h"
#include "lib/traverse.h"
#include "lib/traverse_instanced.h"

/* Ray i (of ray_count) as origin (xyz) with tmin (w) and direction (xyz) with tmax (w); false
 * past the last ray. */
inline bool load_ray(global const idmr_ray *rays, uint ray_count, uint i, float4 *o, float4 *d)
{
    if (i >= ray_count)
        return false;
    *o = vload4(0, rays[i].origin);
    *d = vload4(0, rays[i].direction);
    return true;
}

/* The hit record of an any-hit query: triangle 1 when occluded, t = tmax. */
inline idmr_hit occlusion_hit(bool occluded, float tmax)
{
    idmr_hit hit = {tmax, 0.0f, 0.0f, occluded ? 1u : IDMR_NO_HIT};
    return hit;
}

kernel void trace_closest(global const idmr_ray *rays, global idmr_hit *hits, uint ray_count,
                          global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves)
{
    float4 o, d;
    if (load_ray(rays, ray_count, get_global_id(0), &o, &d))
        hits[get_global_id(0)] = traverse_closest(nodes, leaves, o.xyz, d.xyz, o.w, d.w);
}

kernel void trace_any(global const idmr_ray *rays, global idmr_hit *hits, uint ray_count,
                      global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves)
{
    float4 o, d;
    if (load_ray(rays, ray_count, get_global_id(0), &o, &d))
        hits[get_global_id(0)] =
            occlusion_hit(traverse_any(nodes, leaves, o.xyz, d.xyz, o.w, d.w), d.w);
}

kernel void trace_instanced_closest(global const idmr_ray *rays, global idmr_instance_hit *hits,
                                    uint ray_count, global const idmr_bvh_node *top_nodes,
                                    global const idmr_instance *instances,
                                    global const idmr_bvh_node *nodes,
                                    global const idmr_triangle4 *leaves)
{
    float4 o, d;
    if (load_ray(rays, ray_count, get_global_id(0), &o, &d))
        hits[get_global_id(0)] = traverse_instanced_closest(top_nodes, instances, nodes, leaves,
                                                            o.xyz, d.xyz, o.w, d.w);
}

/* Any hit: triangle 1 when occluded, t = tmax, instance IDMR_NO_HIT. */
kernel void trace_instanced_any(global const idmr_ray *rays, global idmr_instance_hit *hits,
                                uint ray_count, global const idmr_bvh_node *top_nodes,
                                global const idmr_instance *instances,
                                global const idmr_bvh_node *nodes,
                                global const idmr_triangle4 *leaves)
{
    float4 o, d;
    if (!load_ray(rays, ray_count, get_global_id(0), &o, &d))
        return;
    idmr_hit any = occlusion_hit(
        traverse_instanced_any(top_nodes, instances, nodes, leaves, o.xyz, d.xyz, o.w, d.w), d.w);
    idmr_instance_hit out = {any.t, any.u, any.v, any.triangle, IDMR_NO_HIT, {0, 0, 0}};
    hits[get_global_id(0)] = out;
}

/* The shading normal (lib/shading.h) at each closest hit; zero where a ray hit nothing. For the
 * shading tests, against the host's interpolation of the mesh's normals. */
kernel void hit_shading_normals(global const idmr_hit *hits, uint hit_count,
                                global const float4 *triangle_normals,
                                global const uint4 *triangle_shading, global float4 *normals)
{
    uint i = get_global_id(0);
    if (i >= hit_count)
        return;
    idmr_hit hit = hits[i];
    float3 n = (float3)(0.0f);
    if (hit.triangle != IDMR_NO_HIT)
        n = shading_normal(triangle_shading, hit, triangle_normals[hit.triangle].xyz);
    normals[i] = (float4)(n, 0.0f);
}
