/* bvh.h — the scene's 4-wide BVH, built by Embree's rtcBuildBVH (high quality: SAH with
 * spatial splits, the SBVH of the paper) and flattened into the node and triangle arrays of
 * include/idmr/bvh_layout.h that the kernels traverse.
 *
 * Leaf packets carry the scene-global index of each triangle; scene_mesh_of_triangle() maps
 * that to (mesh, triangle in mesh). Degenerate (zero-area) triangles are left out: no ray can
 * hit them.
 *
 * A scene with later copies of instanced shapes (IDMR_FEATURE_INSTANCES, core/scene.h) gets the
 * two-level BVH instead (include/idmr/instance_bvh_layout.h, host/device/instance_bvh.h), each
 * prototype held once: prototype 0 is every mesh that is not instanced, together, placed once
 * by the identity; each instanced shape's representative (its world-space geometry) is a
 * prototype of its own, placed by the identity for itself and by scene_instance_placement()
 * for each later copy. Leaf lanes carry scene-global triangle numbers at both kinds of
 * prototype (a later copy's triangles are its representative's), so the kernels index every
 * per-triangle buffer with them as in a flat scene. `nodes` and `leaves` then hold every
 * prototype's, one after the other, and `top_nodes` and `instances` the top level.
 *
 * The same builder works on plain triangle arrays (bvh_build_meshes: a scene's meshes, or one
 * prototype of an instanced scene, host/device/instance_bvh.h) and on plain boxes
 * (bvh_build_boxes: the top level of an instanced scene, one box per leaf). */
#ifndef IDMR_BVH_HOST_H
#define IDMR_BVH_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "idmr/bvh_layout.h"
#include "idmr/instance_bvh_layout.h"
#include "core/scene.h"

typedef struct bvh {
    idmr_bvh_node *nodes;
    size_t node_count;
    idmr_triangle4 *leaves; /* one packet per leaf */
    size_t leaf_count;
    size_t reference_count;  /* triangles in all leaves: may repeat one (spatial splits) */
    size_t degenerate_count; /* scene triangles left out (bvh_build_boxes: empty boxes) */
    int depth;               /* levels of nodes, root = 1 (two-level: the deepest prototype's) */
    double build_seconds;
    /* The top level of a two-level BVH (above); NULL and 0 for a flat one. */
    idmr_bvh_node *top_nodes; /* child < 0: instances[~child] */
    size_t top_node_count;
    idmr_instance *instances;
    size_t instance_count;
    int top_depth;
} bvh;

/* Builds the BVH of a finalised scene: flat, or two-level where the scene has later copies
 * (above). Returns 0, or -1 with the error set (an Embree error, a tree deeper than the
 * kernels' traversal stack allows, a placement that cannot be inverted). */
int bvh_build(const scene *s, bvh *out);

/* What no mesh places: prototype 0's instance (every mesh that is not instanced, together). */
#define BVH_NO_MESH SIZE_MAX

/* The instances bvh_build() gives the two-level BVH of scene s (IDMR_FEATURE_INSTANCES), in
 * the order of bvh.instances: prototype 0's (BVH_NO_MESH) where some mesh is not instanced,
 * then each instanced shape's copies, its representative first, along its chain. Writes the
 * scene mesh each instance places into mesh_of_instance (may be NULL; room for
 * mesh_count + 1) and returns the count; 0 for a scene without later copies (a flat BVH).
 * The importance pass keeps each copy's totals by it (passes/importance.h). */
size_t bvh_scene_instances(const scene *s, size_t *mesh_of_instance);

/* One triangle mesh for bvh_build_meshes(): leaf lanes number its triangle t as
 * first_triangle + t. */
typedef struct bvh_mesh {
    const float *positions;  /* xyz per vertex */
    const uint32_t *indices; /* three vertex indices per triangle */
    uint32_t triangle_count;
    uint32_t first_triangle;
} bvh_mesh;

/* Builds the BVH of `mesh_count` meshes' triangles (bvh_build() is this on a scene's meshes).
 * Returns 0, or -1 with the error set, as bvh_build(). */
int bvh_build_meshes(const bvh_mesh *meshes, size_t mesh_count, bvh *out);

/* An axis-aligned box; min > max on an axis is an empty box. */
typedef struct bvh_box {
    float min[3];
    float max[3];
} bvh_box;

/* Builds a BVH over `count` boxes (binned SAH, no spatial splits) whose leaves are single
 * boxes: a node's child[k] < 0 is box ~child[k] itself (no leaf packets: leaf_count is 0,
 * reference_count counts the boxes placed). Empty boxes are left out (counted in
 * degenerate_count). Returns 0, or -1 with the error set. */
int bvh_build_boxes(const bvh_box *boxes, size_t count, bvh *out);

void bvh_free(bvh *b);

/* Bytes the node and leaf arrays (and a two-level BVH's top nodes and instance records) take on
 * the device: each prototype counted once. */
uint64_t bvh_device_bytes(const bvh *b);

/* The process-wide Embree device (created on first use, with the error callback that feeds
 * error.h); tests use it for reference intersections. */
struct RTCDeviceTy *bvh_embree_device(void);

#endif
