/* idmr/bvh_layout.h — the flat 4-wide BVH and the triangle packets that the kernels traverse.
 *
 * Built on the host by Embree's rtcBuildBVH (host/device/bvh.c) and uploaded as two arrays:
 *
 *   idmr_bvh_node     nodes[]    node 0 is the root; 128 bytes each.
 *   idmr_triangle4    leaves[]   one packet of up to four triangles per leaf; 160 bytes each.
 *
 * A node stores the boxes of its (up to) four children as structure-of-arrays, one float[4]
 * per bound and axis, so that a kernel tests all four children with float4 operations from
 * one vload4 each. child[k] is a reference:
 *   child[k] >= 0   an inner node: its index in nodes[]
 *   child[k] <  0   a leaf: the packet leaves[~child[k]]
 * An empty slot has an inverted box (min = +inf, max = -inf), which the slab test (near and
 * far planes picked by the ray's sign) never hits; its child is IDMR_BVH_EMPTY.
 * A scene with no triangles uploads one node with four empty slots.
 *
 * A leaf packet holds its triangles as structure-of-arrays too: v0[4 * axis + lane] is
 * coordinate `axis` of vertex 0 of triangle `lane`, so one vload4(axis, v0) gives that
 * coordinate for all four, and a kernel tests the four triangles at once. Lanes past the
 * leaf's size are zero triangles (never hit) with triangle index IDMR_BVH_NO_TRIANGLE. With
 * spatial splits one scene triangle may sit in several leaves; every lane carries the
 * scene-global triangle index it came from (see scene_mesh.first_triangle). */
#ifndef IDMR_BVH_LAYOUT_H
#define IDMR_BVH_LAYOUT_H

#include "idmr/layout.h"

#define IDMR_BVH_WIDTH 4
#define IDMR_BVH_MAX_LEAF_SIZE 4 /* one packet */
#define IDMR_BVH_MAX_DEPTH 32
/* Traversal stack entries: at most (width - 1) siblings are pushed per level. */
#define IDMR_BVH_STACK_SIZE (IDMR_BVH_MAX_DEPTH * (IDMR_BVH_WIDTH - 1) + 1)
#define IDMR_BVH_EMPTY (-1) /* leaf packet 0, but an empty slot's box is never hit */
#define IDMR_BVH_NO_TRIANGLE 0xffffffffu

typedef struct idmr_bvh_node {
    float min_x[4];
    float max_x[4];
    float min_y[4];
    float max_y[4];
    float min_z[4];
    float max_z[4];
    int child[4];
    unsigned int reserved[4];
} idmr_bvh_node;

IDMR_STATIC_ASSERT(sizeof(idmr_bvh_node) == 128, "idmr_bvh_node must be 128 bytes");
IDMR_OFFSET_ASSERT(idmr_bvh_node, min_y, 32);
IDMR_OFFSET_ASSERT(idmr_bvh_node, min_z, 64);
IDMR_OFFSET_ASSERT(idmr_bvh_node, child, 96);

typedef struct idmr_triangle4 {
    float v0[12]; /* x[4], y[4], z[4] */
    float v1[12];
    float v2[12];
    unsigned int triangle[4]; /* scene-global triangle index per lane */
} idmr_triangle4;

IDMR_STATIC_ASSERT(sizeof(idmr_triangle4) == 160, "idmr_triangle4 must be 160 bytes");
IDMR_OFFSET_ASSERT(idmr_triangle4, v1, 48);
IDMR_OFFSET_ASSERT(idmr_triangle4, v2, 96);
IDMR_OFFSET_ASSERT(idmr_triangle4, triangle, 144);

#endif
