/* idmr/importance.h — what the importance pass keeps on the device (kernels/importance.cl).
 *
 *   idmr_hit_point       hit_points[pixels]       one slot per pixel; valid = 0 when the camera
 *                                                  path found no non-specular surface
 *   idmr_photon_vertex   vertices[paths * 8]      path p's vertex j at p * 8 + j: a path is
 *                                                  consecutive in memory; path_length[p] of its
 *                                                  slots are used
 *   unsigned int         gathered[paths * 8]       hit points within the radius of each vertex
 *   idmr_fixed           camera_importance[tris]  Eq. 2 weights, 64-bit fixed point
 *   idmr_fixed           light_importance[tris]
 * The hash grid over hit points: cell_start[cells + 1] (prefix sums of the counts) and
 * grid_points[pixels] (hit point indices sorted by cell).
 *
 * Fixed point: a weight w in [0, 1] is added as round(w * 2^20) (IDMR_FIXED_SCALE). Buffers
 * are cleared every iteration and summed on the host in double, so one iteration must stay
 * below 2^63: 2^43 ≈ 8.8e12 units of weight on one triangle, against at most
 * (pixels × 16) camera weights and (paths × 8 × gathered) light weights. The host checks
 * every value against IDMR_FIXED_SATURATION after each iteration and stops with an error if
 * one comes near. */
#ifndef IDMR_IMPORTANCE_TYPES_H
#define IDMR_IMPORTANCE_TYPES_H

#include "idmr/layout.h"

#define IDMR_PATH_VERTICES 8        /* photon path slot: vertices per path (paper: 8) */
#define IDMR_CAMERA_DEPTH 16        /* camera path: surface interactions (paper: 16) */
#define IDMR_FIXED_SCALE 1048576.0f /* 2^20 */
#define IDMR_FIXED_SATURATION (1ull << 62)
#define IDMR_SCAN_CHUNK 256         /* grid prefix sum: cells per work-item */

typedef struct idmr_hit_point {
    float position[3];
    unsigned int pixel;
    float normal[3]; /* geometric, facing the camera path that arrived */
    unsigned int valid;
} idmr_hit_point;

IDMR_STATIC_ASSERT(sizeof(idmr_hit_point) == 32, "idmr_hit_point must be 32 bytes");
IDMR_OFFSET_ASSERT(idmr_hit_point, normal, 16);

typedef struct idmr_photon_vertex {
    float position[3];
    unsigned int triangle; /* scene-global */
    float normal[3];       /* geometric, facing the side the photon arrived from */
    float weight;          /* Eq. 2: 1 - |n · d| */
} idmr_photon_vertex;

IDMR_STATIC_ASSERT(sizeof(idmr_photon_vertex) == 32, "idmr_photon_vertex must be 32 bytes");
IDMR_OFFSET_ASSERT(idmr_photon_vertex, normal, 16);
IDMR_OFFSET_ASSERT(idmr_photon_vertex, weight, 28);

/* Per-iteration constants, passed by value to every kernel of the importance pass and of the
 * renderer (kernels/render.cl, which shares the hit points and their grid). */
typedef struct idmr_pass_params {
    unsigned int seed;
    unsigned int iteration;
    unsigned int width; /* hit-point image: one camera path per pixel */
    unsigned int height;

    unsigned int path_count; /* photon paths this iteration */
    unsigned int light_count;
    unsigned int cell_count; /* hash-grid buckets (a power of two) */
    unsigned int triangle_count;

    float grid_origin[3];
    float radius; /* gather radius this iteration */

    float scene_center[3];
    float scene_radius; /* bounding sphere: directional lights start outside it */

    float ray_epsilon; /* origin offset of secondary rays, along the normal */
    float cell_size;
    float fixed_scale; /* renderer: fixed-point units per unit of pixel radiance */
    float pad;
} idmr_pass_params;

IDMR_STATIC_ASSERT(sizeof(idmr_pass_params) == 80, "idmr_pass_params is 80 bytes");
IDMR_OFFSET_ASSERT(idmr_pass_params, grid_origin, 32);
IDMR_OFFSET_ASSERT(idmr_pass_params, scene_center, 48);
IDMR_OFFSET_ASSERT(idmr_pass_params, ray_epsilon, 64);

#endif
