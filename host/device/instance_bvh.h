/* instance_bvh.h — the two-level BVH of an instanced scene (include/idmr/instance_bvh_layout.h):
 * one flat BVH per prototype (bvh_build_meshes, the builder of the flat scene BVH) and a top
 * level over the instances' world boxes (bvh_build_boxes), for the instanced traversal of
 * kernels/lib/traverse_instanced.h.
 *
 * bvh_build() (device/bvh.h) builds a scene with later copies of instanced shapes this way, each
 * prototype given as `parts` (a scene's meshes numbering their triangles scene-globally); the
 * traversal tests and benchmark build their own instanced_scene from a mesh file.
 *
 *     instance_prototype bunny = {positions, vertex_count, indices, triangle_count};
 *     instance_placement placed[2] = {{0, {1,0,0,0, 0,1,0,0, 0,0,1,0}},   // identity
 *                                     {0, {2,0,0,5, 0,2,0,0, 0,0,2,0}}};  // scale 2, x + 5
 *     instanced_scene s = {&bunny, 1, placed, 2};
 *     instance_bvh b;
 *     if (instance_bvh_build(&s, &b)) ...error_message()...
 *     ... upload b.top_nodes, b.instances, b.nodes, b.leaves ...
 *     instance_bvh_free(&b); */
#ifndef IDMR_INSTANCE_BVH_HOST_H
#define IDMR_INSTANCE_BVH_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "device/bvh.h"
#include "idmr/instance_bvh_layout.h"

/* A triangle mesh in its own object space, its leaf lanes numbering triangle t as t; or, where
 * part_count > 0, the meshes `parts` together (positions, indices and counts unused), each
 * numbering its triangles from its bvh_mesh.first_triangle (bvh_build: scene-global numbers).
 * The caller owns the arrays. */
typedef struct instance_prototype {
    const float *positions; /* xyz per vertex */
    uint32_t vertex_count;
    const uint32_t *indices; /* three vertex indices per triangle */
    uint32_t triangle_count;
    const bvh_mesh *parts;
    size_t part_count;
} instance_prototype;

/* One placement of a prototype: world = M object + m, as 3x4 row-major
 * (M[0][0], M[0][1], M[0][2], m[0], M[1][0], ...): the first three rows of a 4x4 affine
 * transform (its last row must be 0 0 0 1). */
typedef struct instance_placement {
    uint32_t prototype;
    float object_to_world[12];
} instance_placement;

/* The scene: prototypes and their placements; the caller owns the arrays. */
typedef struct instanced_scene {
    const instance_prototype *prototypes;
    size_t prototype_count;
    const instance_placement *instances;
    size_t instance_count;
} instanced_scene;

typedef struct instance_bvh {
    idmr_bvh_node *top_nodes; /* child < 0: instance ~child */
    size_t top_node_count;
    idmr_instance *instances;
    size_t instance_count;
    idmr_bvh_node *nodes; /* every prototype's nodes, one after the other */
    size_t node_count;
    idmr_triangle4 *leaves; /* every prototype's packets, one after the other */
    size_t leaf_count;
    size_t reference_count;  /* triangles in all prototypes' leaves (bvh.h) */
    size_t degenerate_count; /* prototypes' triangles left out (bvh.h) */
    float bounds_min[3], bounds_max[3]; /* the world box of all instances (min > max: none) */
    int top_depth;       /* levels of top nodes */
    int prototype_depth; /* the deepest prototype's levels */
    double build_seconds;
} instance_bvh;

/* Builds the two-level BVH of s. Returns 0, or -1 with the error set: an instance naming a
 * prototype that does not exist, a transform that is not finite or is singular (its 3x3 part
 * flattens space: |det M| <= 1e-6 |M col 0| |M col 1| |M col 2|, whatever the scale), or an
 * error of the builder (bvh_build_meshes, bvh_build_boxes). */
int instance_bvh_build(const instanced_scene *s, instance_bvh *out);
void instance_bvh_free(instance_bvh *b);

/* Bytes the four arrays take on the device: each prototype counted once. */
uint64_t instance_bvh_device_bytes(const instance_bvh *b);

/* The world-space position of vertex `position` (xyz) under placement p. */
void instance_placement_apply(const instance_placement *p, const float position[3],
                              float world[3]);

#endif
