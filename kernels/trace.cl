/* trace.cl — ray batches through the BVH: closest hit and any hit (occlusion).
 * Used by the traversal tests (against Embree) and the traversal benchmark; the light
 * transport kernels call traverse_closest()/traverse_any() from traverse.h directly. */
#include "lib/traverse.h"

kernel void trace_closest(global const idmr_ray *rays, global idmr_hit *hits, uint ray_count,
                          global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves)
{
    uint i = get_global_id(0);
    if (i >= ray_count)
        return;
    global const idmr_ray *ray = rays + i;
    float4 o = vload4(0, ray->origin);
    float4 d = vload4(0, ray->direction);
    hits[i] = traverse_closest(nodes, leaves, o.xyz, d.xyz, o.w, d.w);
}

kernel void trace_any(global const idmr_ray *rays, global idmr_hit *hits, uint ray_count,
                      global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves)
{
    uint i = get_global_id(0);
    if (i >= ray_count)
        return;
    global const idmr_ray *ray = rays + i;
    float4 o = vload4(0, ray->origin);
    float4 d = vload4(0, ray->direction);
    idmr_hit hit;
    hit.t = d.w;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.triangle = traverse_any(nodes, leaves, o.xyz, d.xyz, o.w, d.w) ? 1u : IDMR_NO_HIT;
    hits[i] = hit;
}
