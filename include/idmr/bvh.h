/* idmr/bvh.h — the flat 4-wide BVH and the triangle records that the kernels traverse.
 *
 * Built on the host by Embree's rtcBuildBVH (host/bvh.c) and uploaded as two arrays:
 *
 *   idmr_bvh_node nodes[]      node 0 is the root; 128 bytes each.
 *   idmr_triangle triangles[]  in leaf order; a leaf is a contiguous range of it. With spatial
 *                              splits one scene triangle may appear in several leaves, so this
 *                              array can be longer than the scene's triangle list; every record
 *                              carries the scene-global triangle index it came from.
 *
 * A node stores the boxes of its (up to) four children as structure-of-arrays, one float[4]
 * per bound and axis, so that a kernel tests all four children with float4 operations from
 * one vload4 each. Child slot k is:
 *   count[k] == 0            inner node: child[k] is its index in nodes[]
 *   count[k] >  0            leaf: triangles[child[k] .. child[k] + count[k])
 *   count[k] == 0, child < 0 empty slot: its box is inverted (min = +inf, max = -inf), so
 *                            the slab test, which picks near/far planes by the ray's sign,
 *                            never hits it.
 * A scene with no triangles uploads one node with four empty slots. */
#ifndef IDMR_BVH_H
#define IDMR_BVH_H

#include "idmr/layout.h"

#define IDMR_BVH_WIDTH 4
#define IDMR_BVH_MAX_LEAF_SIZE 4
#define IDMR_BVH_MAX_DEPTH 32
/* Traversal stack entries: at most (width - 1) siblings are pushed per level. */
#define IDMR_BVH_STACK_SIZE (IDMR_BVH_MAX_DEPTH * (IDMR_BVH_WIDTH - 1) + 1)

typedef struct idmr_bvh_node {
    float min_x[4];
    float max_x[4];
    float min_y[4];
    float max_y[4];
    float min_z[4];
    float max_z[4];
    int child[4];
    unsigned int count[4];
} idmr_bvh_node;

IDMR_STATIC_ASSERT(sizeof(idmr_bvh_node) == 128, "idmr_bvh_node must be 128 bytes");
IDMR_OFFSET_ASSERT(idmr_bvh_node, min_y, 32);
IDMR_OFFSET_ASSERT(idmr_bvh_node, min_z, 64);
IDMR_OFFSET_ASSERT(idmr_bvh_node, child, 96);
IDMR_OFFSET_ASSERT(idmr_bvh_node, count, 112);

/* One triangle as the intersection test reads it: three world-space vertices. */
typedef struct idmr_triangle {
    float v0[3];
    unsigned int triangle; /* scene-global triangle index (see scene_mesh.first_triangle) */
    float v1[3];
    unsigned int pad0;
    float v2[3];
    unsigned int pad1;
} idmr_triangle;

IDMR_STATIC_ASSERT(sizeof(idmr_triangle) == 48, "idmr_triangle must be 48 bytes");
IDMR_OFFSET_ASSERT(idmr_triangle, triangle, 12);
IDMR_OFFSET_ASSERT(idmr_triangle, v1, 16);
IDMR_OFFSET_ASSERT(idmr_triangle, v2, 32);

#endif
