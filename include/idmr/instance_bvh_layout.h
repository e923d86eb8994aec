/* idmr/instance_bvh_layout.h — the two-level BVH of an instanced scene: prototypes (triangle
 * meshes in their own object space) placed by instances (affine object-to-world transforms),
 * as the kernels traverse it (kernels/lib/traverse_instanced.h).
 *
 * Built on the host by host/device/instance_bvh.c and uploaded as four arrays:
 *
 *   idmr_bvh_node     top_nodes[]   the top level over the instances' world boxes; node 0 is
 *                                   the root. Same 128-byte nodes as idmr/bvh_layout.h, but a
 *                                   child reference < 0 is an instance, instances[~child].
 *   idmr_instance     instances[]   one 64-byte record per instance (below).
 *   idmr_bvh_node     nodes[]       every prototype's flat BVH (idmr/bvh_layout.h), one after
 *                                   the other; each prototype is stored once, however many
 *                                   instances place it.
 *   idmr_triangle4    leaves[]      every prototype's leaf packets, one after the other.
 *
 * A prototype's own references are local: its root is node 0 and its leaf ~ref is packet
 * ~ref, counted from its instance's node_offset and leaf_offset, so a kernel passes
 * nodes + node_offset and leaves + leaf_offset to the flat traversal's node and leaf tests.
 * Leaf lanes carry the triangle numbers the prototype was built with: its own index (0 .. its
 * triangle count - 1), or, for a scene's BVH (host/device/bvh.h), the scene-global number of
 * the triangle (its representative's: every placement of a prototype shares its triangles).
 *
 * An instance record holds the inverse of its object-to-world transform: the kernel moves the
 * ray into object space, origin' = W origin + w, direction' = W direction, without normalising
 * the direction, so a hit's t is the world-space t (o + t d in the world is o' + t d' in the
 * object) and hits of different instances compare directly. World-space normals need no
 * second matrix: a normal goes to the world by the transpose of W's 3x3 part. An instance
 * whose prototype has no triangles is left out of the top level (it can never be hit).
 * A top level with no instances is one node with four empty slots. */
#ifndef IDMR_INSTANCE_BVH_LAYOUT_H
#define IDMR_INSTANCE_BVH_LAYOUT_H

#include "idmr/bvh_layout.h"

/* Traversal stack entries of the instanced traversal: one stack shared by the two levels;
 * the top level leaves at most (width - 1) siblings per level pending while a prototype's
 * traversal runs above them with the flat traversal's bound. */
#define IDMR_INSTANCE_STACK_SIZE (IDMR_BVH_MAX_DEPTH * (IDMR_BVH_WIDTH - 1) + IDMR_BVH_STACK_SIZE)

typedef struct idmr_instance {
    /* The world-to-object transform, 3x4 row-major: row r is (W[r][0], W[r][1], W[r][2], w[r]),
     * object coordinate r = W[r] . world + w[r]. */
    float world_to_object[12];
    int node_offset;       /* the prototype's root in nodes[] */
    int leaf_offset;       /* the prototype's first packet in leaves[] */
    unsigned int prototype;
    /* The most the object-to-world transform stretches a coordinate's magnitude (the largest
     * row sum of |M|'s 3x3 part): a prototype triangle's ray offset times this bounds the
     * world offset (kernels/lib/surface.h). */
    float offset_scale;
} idmr_instance;

IDMR_STATIC_ASSERT(sizeof(idmr_instance) == 64, "idmr_instance must be 64 bytes");
IDMR_OFFSET_ASSERT(idmr_instance, node_offset, 48);
IDMR_OFFSET_ASSERT(idmr_instance, offset_scale, 60);

/* A closest hit of the instanced traversal: t along the world ray, barycentrics (u, v) of
 * v1 and v2, the prototype's triangle and the instance, or triangle == instance ==
 * IDMR_NO_HIT. Any hit: triangle is 1 (occluded) or IDMR_NO_HIT, instance IDMR_NO_HIT. */
typedef struct idmr_instance_hit {
    float t;
    float u;
    float v;
    unsigned int triangle;
    unsigned int instance;
    unsigned int reserved[3];
} idmr_instance_hit;

IDMR_STATIC_ASSERT(sizeof(idmr_instance_hit) == 32, "idmr_instance_hit must be 32 bytes");

#endif
