/* traverse.h — ray traversal of the 4-wide BVH (include/idmr/bvh_layout.h) with a watertight
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
 * Traversal works on references (idmr/bvh_layout.h: >= 0 a node, < 0 a leaf). At a node the hit
 * children are taken in slot order with a bit scan; one hit is followed at once, two are
 * ordered by entry distance (the far one pushed), three or four go through a sorting network
 * and all but the nearest are pushed (traverse_order_children, which the instanced traversal
 * of traverse_instanced.h shares, as it shares the node and leaf tests). A popped reference that starts beyond the current hit
 * is skipped. Any hit stops at the first intersection. The stack holds at most
 * 3 * IDMR_BVH_MAX_DEPTH + 1 entries (the builder enforces the depth). */
#ifndef IDMR_TRAVERSE_H
#define IDMR_TRAVERSE_H

#include "idmr/bvh_layout.h"
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
    float ox, oy, oz; /* origin in the permuted frame */
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
    r.ox = component(origin, r.kx);
    r.oy = component(origin, r.ky);
    r.oz = component(origin, r.kz);
    float dz = component(direction, r.kz);
    r.sx = component(direction, r.kx) / dz;
    r.sy = component(direction, r.ky) / dz;
    return r;
}

/* Index of the lowest set bit (OpenCL C 1.2 has clz but no ctz). */
inline int traverse_lowest_bit(int mask)
{
    return 31 - clz(mask & -mask);
}

/* Tests the four triangles of a leaf packet at once. Inside/outside is decided by the
 * watertight test, in the ray's sheared frame; the distance of a triangle found inside is
 * then computed in its own frame, t = e2·((o - v0) × e1) / e1·(d × e2), which stays accurate
 * for long thin triangles, where the sheared-frame distance of the watertight paper loses
 * digits. Returns the lanes hit within (tmin, tmax) as a mask and their distances. */
inline int traverse_packet(const traverse_ray *r, global const idmr_triangle4 *p, float tmin,
                           float tmax, float4 *t_out, float4 *det_out, float4 *e1_out,
                           float4 *e2_out)
{
    /* vload4(axis, v) is coordinate `axis` of the four triangles: the permutation is a choice
     * of rows, no shuffles. */
    float4 az = vload4(r->kz, p->v0) - r->oz;
    float4 bz = vload4(r->kz, p->v1) - r->oz;
    float4 cz = vload4(r->kz, p->v2) - r->oz;
    float4 ax = (vload4(r->kx, p->v0) - r->ox) - r->sx * az;
    float4 ay = (vload4(r->ky, p->v0) - r->oy) - r->sy * az;
    float4 bx = (vload4(r->kx, p->v1) - r->ox) - r->sx * bz;
    float4 by = (vload4(r->ky, p->v1) - r->oy) - r->sy * bz;
    float4 cx = (vload4(r->kx, p->v2) - r->ox) - r->sx * cz;
    float4 cy = (vload4(r->ky, p->v2) - r->oy) - r->sy * cz;
    float4 e0 = cx * by - cy * bx;
    float4 e1 = ax * cy - ay * cx;
    float4 e2 = bx * ay - by * ax;
    float4 zero = (float4)(0.0f);
    int4 negative = e0 < zero || e1 < zero || e2 < zero;
    int4 positive = e0 > zero || e1 > zero || e2 > zero;
    float4 det = e0 + e1 + e2;
    int4 inside = !(negative && positive) && det != zero;
    if (!any(inside))
        return 0;

    float4 v0x = vload4(0, p->v0), v0y = vload4(1, p->v0), v0z = vload4(2, p->v0);
    float4 f1x = vload4(0, p->v1) - v0x, f1y = vload4(1, p->v1) - v0y, f1z = vload4(2, p->v1) - v0z;
    float4 f2x = vload4(0, p->v2) - v0x, f2y = vload4(1, p->v2) - v0y, f2z = vload4(2, p->v2) - v0z;
    float4 dx = (float4)(r->direction.x), dy = (float4)(r->direction.y), dz = (float4)(r->direction.z);
    /* pvec = d x f2, qvec = (o - v0) x f1 */
    float4 px = dy * f2z - dz * f2y, py = dz * f2x - dx * f2z, pz = dx * f2y - dy * f2x;
    float4 plane_det = f1x * px + f1y * py + f1z * pz;
    float4 tx = r->origin.x - v0x, ty = r->origin.y - v0y, tz = r->origin.z - v0z;
    float4 qx = ty * f1z - tz * f1y, qy = tz * f1x - tx * f1z, qz = tx * f1y - ty * f1x;
    float4 t = (f2x * qx + f2y * qy + f2z * qz) / plane_det;
    int4 hit = inside && plane_det != zero && t > (float4)(tmin) && t < (float4)(tmax);
    *t_out = t;
    *det_out = det;
    *e1_out = e1;
    *e2_out = e2;
    return (hit.x & 1) | (hit.y & 2) | (hit.z & 4) | (hit.w & 8);
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
    /* min/max, not fmin/fmax: no operand is NaN (no zero direction, no 0 * inf), and the
     * IEEE NaN rules of fmin/fmax cost two extra instructions each on a CPU. */
    float4 t_enter = max(max(t0x, t0y), max(t0z, (float4)(tmin)));
    float4 t_exit = min(min(t1x, t1y), min(t1z, (float4)(tmax)));
    t_exit *= 1.0f + 4.0f * FLT_EPSILON;
    int4 hit = t_enter <= t_exit;
    *hit_mask = (hit.x & 1) | (hit.y & 2) | (hit.z & 4) | (hit.w & 8);
    return t_enter;
}

/* Intersects the leaf packet of reference `ref`, keeping the nearest hit; true if any. */
inline bool traverse_leaf(const traverse_ray *r, global const idmr_triangle4 *leaves, int ref,
                          float tmin, idmr_hit *hit)
{
    global const idmr_triangle4 *p = leaves + ~ref;
    float4 t, det, e1, e2;
    int mask = traverse_packet(r, p, tmin, hit->t, &t, &det, &e1, &e2);
    if (mask == 0)
        return false;
    float lane_t[4] = {t.x, t.y, t.z, t.w};
    int best = traverse_lowest_bit(mask);
    for (mask &= mask - 1; mask != 0; mask &= mask - 1) {
        int lane = traverse_lowest_bit(mask);
        if (lane_t[lane] < lane_t[best])
            best = lane;
    }
    float lane_det[4] = {det.x, det.y, det.z, det.w};
    float lane_e1[4] = {e1.x, e1.y, e1.z, e1.w};
    float lane_e2[4] = {e2.x, e2.y, e2.z, e2.w};
    float inv_det = 1.0f / lane_det[best];
    hit->t = lane_t[best];
    hit->u = lane_e1[best] * inv_det;
    hit->v = lane_e2[best] * inv_det;
    hit->triangle = p->triangle[best];
    return true;
}

/* True if any triangle of the leaf packet lies within (tmin, tmax). */
inline bool traverse_leaf_any(const traverse_ray *r, global const idmr_triangle4 *leaves, int ref,
                              float tmin, float tmax)
{
    float4 t, det, e1, e2;
    return traverse_packet(r, leaves + ~ref, tmin, tmax, &t, &det, &e1, &e2) != 0;
}

/* Orders two (distance, reference) pairs so that the nearer comes first; no branches. */
#define TRAVERSE_ORDER(ta, ra, tb, rb)                                                      \
    do {                                                                                     \
        bool swap_ = (tb) < (ta);                                                            \
        float t_ = swap_ ? (tb) : (ta);                                                      \
        int r_ = swap_ ? (rb) : (ra);                                                        \
        (tb) = swap_ ? (ta) : (tb);                                                          \
        (rb) = swap_ ? (ra) : (rb);                                                          \
        (ta) = t_;                                                                           \
        (ra) = r_;                                                                           \
    } while (0)

/* Of a node's hit children (mask != 0, entry distances t4): returns the nearest one's
 * reference and pushes the others' on the stack, farthest deepest. One hit child is returned
 * at once, two are ordered by entry distance, three or four go through a sorting network. */
inline int traverse_order_children(global const idmr_bvh_node *node, float4 t4, int mask,
                                   int *stack_ref, float *stack_t, int *top)
{
    float entry[4] = {t4.x, t4.y, t4.z, t4.w};
    int k0 = traverse_lowest_bit(mask);
    mask &= mask - 1;
    int r0 = node->child[k0];
    if (mask == 0)
        return r0;
    float t0 = entry[k0];
    int k1 = traverse_lowest_bit(mask);
    mask &= mask - 1;
    int r1 = node->child[k1];
    float t1 = entry[k1];
    if (mask == 0) {
        TRAVERSE_ORDER(t0, r0, t1, r1);
        stack_ref[*top] = r1;
        stack_t[(*top)++] = t1;
        return r0;
    }
    int k2 = traverse_lowest_bit(mask);
    mask &= mask - 1;
    int r2 = node->child[k2];
    float t2 = entry[k2];
    int r3 = 0;
    float t3 = INFINITY;
    if (mask != 0) {
        int k3 = traverse_lowest_bit(mask);
        r3 = node->child[k3];
        t3 = entry[k3];
    }
    TRAVERSE_ORDER(t0, r0, t1, r1);
    TRAVERSE_ORDER(t2, r2, t3, r3);
    TRAVERSE_ORDER(t0, r0, t2, r2);
    TRAVERSE_ORDER(t1, r1, t3, r3);
    TRAVERSE_ORDER(t1, r1, t2, r2);
    if (t3 != INFINITY) {
        stack_ref[*top] = r3;
        stack_t[(*top)++] = t3;
    }
    stack_ref[*top] = r2;
    stack_t[(*top)++] = t2;
    stack_ref[*top] = r1;
    stack_t[(*top)++] = t1;
    return r0;
}

/* Of a node's hit children (mask != 0), in slot order: returns the first one's reference and
 * pushes the others' (any hit: no order). */
inline int traverse_push_children(global const idmr_bvh_node *node, int mask, int *stack_ref,
                                  int *top)
{
    int first = node->child[traverse_lowest_bit(mask)];
    mask &= mask - 1;
    while (mask != 0) {
        stack_ref[(*top)++] = node->child[traverse_lowest_bit(mask)];
        mask &= mask - 1;
    }
    return first;
}

/* A hit record with no hit yet: t = tmax. */
inline idmr_hit traverse_no_hit(float tmax)
{
    idmr_hit hit;
    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.triangle = IDMR_NO_HIT;
    return hit;
}

/* Closest hit along origin + t*direction, t in (tmin, tmax). */
inline idmr_hit traverse_closest(global const idmr_bvh_node *nodes,
                                 global const idmr_triangle4 *leaves, float3 origin,
                                 float3 direction, float tmin, float tmax)
{
    traverse_ray r = traverse_setup(origin, direction);
    idmr_hit hit = traverse_no_hit(tmax);

    int stack_ref[IDMR_BVH_STACK_SIZE];
    float stack_t[IDMR_BVH_STACK_SIZE];
    int top = 0;
    int ref = 0;
    for (;;) {
        if (ref >= 0) {
            global const idmr_bvh_node *node = nodes + ref;
            int mask;
            float4 t4 = traverse_node_boxes(&r, node, tmin, hit.t, &mask);
            if (mask != 0) {
                ref = traverse_order_children(node, t4, mask, stack_ref, stack_t, &top);
                continue;
            }
        } else {
            traverse_leaf(&r, leaves, ref, tmin, &hit);
        }
        /* Pop the next reference that can still hold a closer hit. */
        for (;;) {
            if (top == 0)
                return hit;
            top--;
            if (stack_t[top] <= hit.t) {
                ref = stack_ref[top];
                break;
            }
        }
    }
}

/* True when anything lies along the ray within (tmin, tmax). */
inline bool traverse_any(global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,
                         float3 origin, float3 direction, float tmin, float tmax)
{
    traverse_ray r = traverse_setup(origin, direction);
    int stack_ref[IDMR_BVH_STACK_SIZE];
    int top = 0;
    int ref = 0;
    for (;;) {
        if (ref >= 0) {
            global const idmr_bvh_node *node = nodes + ref;
            int mask;
            traverse_node_boxes(&r, node, tmin, tmax, &mask);
            if (mask != 0) {
                ref = traverse_push_children(node, mask, stack_ref, &top);
                continue;
            }
        } else {
            if (traverse_leaf_any(&r, leaves, ref, tmin, tmax))
                return true;
        }
        if (top == 0)
            return false;
        ref = stack_ref[--top];
    }
}

#endif
