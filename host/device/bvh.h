/* bvh.h — the scene's 4-wide BVH, built by Embree's rtcBuildBVH (high quality: SAH with
 * spatial splits, the SBVH of the paper) and flattened into the node and triangle arrays of
 * include/idmr/bvh_layout.h that the kernels traverse.
 *
 * Leaf packets carry the scene-global index of each triangle; scene_mesh_of_triangle() maps
 * that to (mesh, triangle in mesh). Degenerate (zero-area) triangles are left out: no ray can
 * hit them. */
#ifndef IDMR_BVH_HOST_H
#define IDMR_BVH_HOST_H

#include <stddef.h>
#include <stdint.h>

#include "idmr/bvh_layout.h"
#include "core/scene.h"

typedef struct bvh {
    idmr_bvh_node *nodes;
    size_t node_count;
    idmr_triangle4 *leaves; /* one packet per leaf */
    size_t leaf_count;
    size_t reference_count;  /* triangles in all leaves: may repeat one (spatial splits) */
    size_t degenerate_count; /* scene triangles left out */
    int depth;               /* levels of nodes, root = 1 */
    double build_seconds;
} bvh;

/* Builds the BVH of a finalised scene. Returns 0, or -1 with the error set (an Embree error,
 * or a tree deeper than the kernels' traversal stack allows). */
int bvh_build(const scene *s, bvh *out);
void bvh_free(bvh *b);

/* Bytes the node and leaf arrays take on the device. */
uint64_t bvh_device_bytes(const bvh *b);

/* The process-wide Embree device (created on first use, with the error callback that feeds
 * error.h); tests use it for reference intersections. */
struct RTCDeviceTy *bvh_embree_device(void);

#endif
