/* idmr/sppm_layout.h — what the SPPM core keeps on the device for both passes (the importance
 * pass and the renderer: host/passes/sppm.c, kernels/sppm.cl):
 *
 *   idmr_sppm_params   per-iteration constants, passed by value to every kernel
 *   idmr_hit_point     hit_points[pixels]: one slot per pixel of the hit-point image; valid = 0
 *                      when the camera path found no non-specular surface
 *   record             records[stored_count]: the records of all photon paths in one dense list,
 *                      each put where an atomic add placed it (at most
 *                      paths * IDMR_PATH_VERTICES); the gathers run over it; what a record
 *                      holds is the pass's (idmr/importance_layout.h, idmr/render_layout.h)
 *   uint               path_length[paths], record_index[paths * IDMR_PATH_VERTICES]: path p's
 *                      record j is records[record_index[p * IDMR_PATH_VERTICES + j]], for
 *                      j < path_length[p]
 * The hash grid over hit points: cell_start[cells + 1] (prefix sums of the counts, computed in
 * chunks of IDMR_SCAN_CHUNK cells) and grid_hits[pixels] (copies of the hit points sorted by
 * cell).
 *
 * Both passes sum into 64-bit fixed-point words with integer atomics (kernels/lib/fixed_point.h),
 * cleared every iteration; the host stops with an error when a word reaches
 * IDMR_FIXED_SATURATION, a factor 2 below overflow. */
#ifndef IDMR_SPPM_LAYOUT_H
#define IDMR_SPPM_LAYOUT_H

#include "idmr/layout.h"

#define IDMR_PATH_VERTICES 8     /* records per photon path slot (paper: 8) */
#define IDMR_CAMERA_DEPTH 16     /* camera path: surface interactions by default (paper: 16) */
#define IDMR_RENDER_DEPTH 64     /* the renderer's default: deep glass (ice in water) lit */
#define IDMR_CAMERA_RR_DEPTH 16  /* renderer: Russian roulette on camera paths from here */
#define IDMR_PHOTON_BOUNCES 32   /* photon path: surface interactions, at most */
#define IDMR_SCAN_CHUNK 256      /* grid prefix sum: cells per work-item */
#define IDMR_FIXED_SATURATION (1ull << 62)

/* The two passes on the SPPM core, as the kernels' IDMR_SPPM_PASS build option names them. */
#define IDMR_SPPM_IMPORTANCE 1
#define IDMR_SPPM_RENDER 2

typedef struct idmr_hit_point {
    float position[3];
    unsigned int pixel;
    float normal[3]; /* geometric, facing the camera path that arrived */
    float offset;    /* > 0: a ray leaving it starts this far off (idmr/ray.h); 0: no hit point */
} idmr_hit_point;

IDMR_STATIC_ASSERT(sizeof(idmr_hit_point) == 32, "idmr_hit_point must be 32 bytes");
IDMR_OFFSET_ASSERT(idmr_hit_point, normal, 16);

typedef struct idmr_sppm_params {
    unsigned int seed;
    unsigned int iteration;
    unsigned int width; /* hit-point image: one camera path per pixel */
    unsigned int height;

    unsigned int path_count; /* photon paths this iteration, on all devices together */
    unsigned int light_count;
    unsigned int cell_count; /* hash-grid buckets (a power of two) */
    unsigned int triangle_count;

    float radius;              /* gather radius this iteration */
    float cell_size;           /* hash-grid cell edge: at least 2 radius (hit_point_grid.h) */
    float fixed_scale;         /* fixed-point units per unit of pixel radiance (render), of
                                  luminance seen through specular surfaces (importance) */
    unsigned int camera_depth; /* camera path: surface interactions at most */

    float scene_center[3];
    float scene_radius; /* bounding sphere: directional lights start outside it */

    /* The photon paths this device traces: [path_first, path_first + device_paths) of the
     * path_count, into its slots from 0 (path path_first + i in slot i); one device: 0 and
     * path_count. Path p draws from the stream keyed by p wherever it runs. */
    unsigned int path_first;
    unsigned int device_paths;
    unsigned int camera_sums; /* 1: camera paths add what the pass records (the first device);
                                 0: they leave only hit points (the others: counted once) */
    unsigned int pixel_weighted; /* importance: 1: each hit point counts its pixel's weight
                                    (pixel_weights, passes/importance.h); 0: 1 each */
} idmr_sppm_params;

IDMR_STATIC_ASSERT(sizeof(idmr_sppm_params) == 80, "idmr_sppm_params is 80 bytes");
IDMR_OFFSET_ASSERT(idmr_sppm_params, radius, 32);
IDMR_OFFSET_ASSERT(idmr_sppm_params, scene_center, 48);
IDMR_OFFSET_ASSERT(idmr_sppm_params, path_first, 64);
IDMR_OFFSET_ASSERT(idmr_sppm_params, camera_sums, 72);

#endif
