/* traverse.h — ray traversal of the 4-wide BVH (include/idmr/bvh.h) with a watertight
 * ray/triangle test.
 *
 * Robustness: the triangle test is the watertight one of Woop, Benthin and Wald (JCGT 2013):
 * the ray is sheared onto +z, and edge functions are evaluated in that frame, so a ray through
 * a shared edge or vertex hits at least one of the adjacent triangles, at any scene scale
 * (no epsilon in world units). Zero direction components are replaced by ±1e-18 for the
 * slab test, and the box exit distance is widened by 4 ulp, so axis-aligned triangles lying in
 * a box face are not culled by rounding. Self-intersection of secondary rays is the caller's
 * business: start them with tmin > 0 or an offset origin.
 *
 * Closest hit visits hit children nearest first: leaves are intersected at once (shrinking
 * tmax), inner nodes are pushed far-to-near with their entry distance, and a popped node
 * that starts beyond the current tmax is skipped. Any hit stops at the first intersection. */
#ifndef IDMR_TRAVERSE_H
#define IDMR_TRAVERSE_H

#include "idmr/bvh.h"
#include "idmr/ray.h"

/* Watertightness needs every edge function rounded the same way in both triangles that share
 * the edge; a fused multiply-add in one of them breaks that, so no contraction here. */
#pragma OPENCL FP_CONTRACT OFF

typedef struct traverse_ray {
    float3 origin;
    float3 direction;
    float3 inv_direction;
    int near_x, near_y, near_z; /* 1 when the direction component is negative */
    /* watertight test: permutation and shear */
    int kx, ky, kz;
    uint4 permutation; /* (kx, ky, kz, 3) */
    float sx, sy;
} traverse_ray;

inline float component(float3 v, int k)
{
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

inline traverse_ray traverse_setup(float3 origin, float3 direction)
{
    traverse_ray r;
    r.origin = origin;
    r.direction = direction;
    float3 d = direction;
    const float tiny = 1e-18f;
    d.x = fabs(d.x) < tiny ? copysign(tiny, d.x) : d.x;
    d.y = fabs(d.y) < tiny ? copysign(tiny, d.y) : d.y;
    d.z = fabs(d.z) < tiny ? copysign(tiny, d.z) : d.z;
    r.inv_direction = 1.0f / d;
    r.near_x = d.x < 0.0f;
    r.near_y = d.y < 0.0f;
    r.near_z = d.z < 0.0f;

    float3 a = fabs(direction);
    r.kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    if (component(direction, r.kz) < 0.0f) {
        int swap = r.kx;
        r.kx = r.ky;
        r.ky = swap;
    }
    r.permutation = (uint4)(r.kx, r.ky, r.kz, 3);
    float dz = component(direction, r.kz);
    r.sx = component(direction, r.kx) / dz;
    r.sy = component(direction, r.ky) / dz;
    return r;
}

/* On a hit inside (tmin, *tmax) updates *tmax, *u, *v (barycentrics of v1 and v2).
 * Inside/outside is decided by the watertight test; the distance is then computed in the
 * triangle's own frame, t = e2·((o - v0) × e1) / e1·(d × e2), which stays accurate for long
 * thin triangles, where the sheared-frame distance of the watertight paper loses digits. */
inline bool traverse_triangle(const traverse_ray *r, global const idmr_triangle *tri, float tmin,
                              float *tmax, float *u, float *v)
{
    float4 o4 = (float4)(r->origin, 0.0f);
    float4 v0 = vload4(0, tri->v0), v1 = vload4(0, tri->v1), v2 = vload4(0, tri->v2);
    float4 a = shuffle(v0 - o4, r->permutation);
    float4 b = shuffle(v1 - o4, r->permutation);
    float4 c = shuffle(v2 - o4, r->permutation);
    float ax = a.x - r->sx * a.z, ay = a.y - r->sy * a.z;
    float bx = b.x - r->sx * b.z, by = b.y - r->sy * b.z;
    float cx = c.x - r->sx * c.z, cy = c.y - r->sy * c.z;
    float e0 = cx * by - cy * bx;
    float e1 = ax * cy - ay * cx;
    float e2 = bx * ay - by * ax;
    if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f))
        return false;
    float det = e0 + e1 + e2;
    if (det == 0.0f)
        return false;
    float3 edge1 = v1.xyz - v0.xyz, edge2 = v2.xyz - v0.xyz;
    float3 to_origin = r->origin - v0.xyz;
    float plane_det = dot(edge1, cross(r->direction, edge2));
    if (plane_det == 0.0f)
        return false;
    float t = dot(edge2, cross(to_origin, edge1)) / plane_det;
    if (!(t > tmin && t < *tmax))
        return false;
    float inv_det = 1.0f / det;
    *tmax = t;
    *u = e1 * inv_det;
    *v = e2 * inv_det;
    return true;
}

/* Slab test of a node's four child boxes; returns the entry distances, and in *hit_mask
 * bit k set when child k is hit within [tmin, tmax]. */
inline float4 traverse_node_boxes(const traverse_ray *r, global const idmr_bvh_node *node,
                                  float tmin, float tmax, int *hit_mask)
{
    float4 lo_x = vload4(0, node->min_x), hi_x = vload4(0, node->max_x);
    float4 lo_y = vload4(0, node->min_y), hi_y = vload4(0, node->max_y);
    float4 lo_z = vload4(0, node->min_z), hi_z = vload4(0, node->max_z);
    float4 near_x = r->near_x ? hi_x : lo_x, far_x = r->near_x ? lo_x : hi_x;
    float4 near_y = r->near_y ? hi_y : lo_y, far_y = r->near_y ? lo_y : hi_y;
    float4 near_z = r->near_z ? hi_z : lo_z, far_z = r->near_z ? lo_z : hi_z;
    /* (plane - origin) * inv, not plane * inv - origin * inv: the subtraction is exact for
     * nearby values, so short rays far from the world origin keep their relative precision. */
    float3 inv = r->inv_direction, o = r->origin;
    float4 t0x = (near_x - o.x) * inv.x, t1x = (far_x - o.x) * inv.x;
    float4 t0y = (near_y - o.y) * inv.y, t1y = (far_y - o.y) * inv.y;
    float4 t0z = (near_z - o.z) * inv.z, t1z = (far_z - o.z) * inv.z;
    float4 t_enter = fmax(fmax(t0x, t0y), fmax(t0z, (float4)(tmin)));
    float4 t_exit = fmin(fmin(t1x, t1y), fmin(t1z, (float4)(tmax)));
    t_exit *= 1.0f + 4.0f * FLT_EPSILON;
    int4 hit = t_enter <= t_exit;
    *hit_mask = (hit.x & 1) | (hit.y & 2) | (hit.z & 4) | (hit.w & 8);
    return t_enter;
}

/* Closest hit along origin + t*direction, t in (tmin, tmax). */
inline idmr_hit traverse_closest(global const idmr_bvh_node *nodes,
                                 global const idmr_triangle *triangles, float3 origin,
                                 float3 direction, float tmin, float tmax)
{
    traverse_ray r = traverse_setup(origin, direction);
    idmr_hit hit;
    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.triangle = IDMR_NO_HIT;

    int stack_node[IDMR_BVH_STACK_SIZE];
    float stack_t[IDMR_BVH_STACK_SIZE];
    int top = 0;
    int node_index = 0;
    for (;;) {
        global const idmr_bvh_node *node = nodes + node_index;
        int mask;
        float4 t_enter = traverse_node_boxes(&r, node, tmin, hit.t, &mask);
        float entry[4] = {t_enter.x, t_enter.y, t_enter.z, t_enter.w};
        /* Order the hit children by entry distance (insertion sort of at most four). */
        int order[4];
        int n = 0;
        for (int k = 0; k < 4; k++) {
            if (!(mask & (1 << k)))
                continue;
            int j = n++;
            while (j > 0 && entry[order[j - 1]] > entry[k]) {
                order[j] = order[j - 1];
                j--;
            }
            order[j] = k;
        }
        /* Leaves now, nearest first; inner nodes collected for the stack. */
        int inner[4];
        int inner_count = 0;
        for (int i = 0; i < n; i++) {
            int k = order[i];
            if (entry[k] > hit.t)
                break;
            unsigned int count = node->count[k];
            int child = node->child[k];
            if (count == 0) {
                inner[inner_count++] = k;
                continue;
            }
            for (unsigned int j = 0; j < count; j++) {
                global const idmr_triangle *tri = triangles + child + j;
                if (traverse_triangle(&r, tri, tmin, &hit.t, &hit.u, &hit.v))
                    hit.triangle = tri->triangle;
            }
        }
        for (int i = inner_count - 1; i >= 1; i--) {
            stack_node[top] = node->child[inner[i]];
            stack_t[top] = entry[inner[i]];
            top++;
        }
        if (inner_count > 0 && entry[inner[0]] <= hit.t) {
            node_index = node->child[inner[0]];
            continue;
        }
        /* Pop the next node that can still hold a closer hit. */
        node_index = -1;
        while (top > 0) {
            top--;
            if (stack_t[top] <= hit.t) {
                node_index = stack_node[top];
                break;
            }
        }
        if (node_index < 0)
            break;
    }
    return hit;
}

/* True when anything lies along the ray within (tmin, tmax). */
inline bool traverse_any(global const idmr_bvh_node *nodes, global const idmr_triangle *triangles,
                         float3 origin, float3 direction, float tmin, float tmax)
{
    traverse_ray r = traverse_setup(origin, direction);
    int stack_node[IDMR_BVH_STACK_SIZE];
    int top = 0;
    int node_index = 0;
    for (;;) {
        global const idmr_bvh_node *node = nodes + node_index;
        int mask;
        traverse_node_boxes(&r, node, tmin, tmax, &mask);
        for (int k = 0; k < 4; k++) {
            if (!(mask & (1 << k)))
                continue;
            unsigned int count = node->count[k];
            int child = node->child[k];
            if (count == 0) {
                stack_node[top++] = child;
                continue;
            }
            for (unsigned int j = 0; j < count; j++) {
                float t = tmax, u, v;
                if (traverse_triangle(&r, triangles + child + j, tmin, &t, &u, &v))
                    return true;
            }
        }
        if (top == 0)
            return false;
        node_index = stack_node[--top];
    }
}

#endif
