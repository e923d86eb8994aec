/* idmr/importance_layout.h — what the importance pass adds on the device to the SPPM core's
 * buffers (idmr/sppm_layout.h):
 *
 *   idmr_photon_vertex   the photon records (idmr/sppm_layout.h): a vertex at every surface
 *                        interaction of a photon path, specular ones too
 *   uint                 gathered[stored_count]: hit points within the radius of each vertex,
 *                        in the records' order
 *   fixed_word           camera_importance[words], light_importance[words], and the same for
 *                        shadow importance and seen light: Eq. 2 weights in 64-bit fixed point
 *                        (kernels/lib/fixed_point.h); words = triangles, then in an instanced
 *                        scene (IDMR_FEATURE_INSTANCES) one per instance of the two-level BVH:
 *                        word triangles + i is instance i's total, all that the paths that met
 *                        that instance added to triangles (kernels/lib/paths.h, importance_add)
 *   uint                 record_instances[stored_count], instanced scenes only: the instance of
 *                        each photon record, parallel to the records (so that a record stays 32
 *                        bytes, and a flat scene's 32 bytes are all it pays)
 *
 * Fixed point: a weight w in [0, 1] is added as round(w * 2^20) (IDMR_FIXED_SCALE). The words
 * are cleared every iteration and summed on the host in double, so one iteration must stay
 * below IDMR_FIXED_SATURATION: 2^42 ≈ 4.4e12 units of weight on one triangle (or instance total),
 * against at most (pixels × 16) camera weights and (paths × 8 × gathered) light weights. */
#ifndef IDMR_IMPORTANCE_LAYOUT_H
#define IDMR_IMPORTANCE_LAYOUT_H

#include "idmr/layout.h"

#define IDMR_FIXED_SCALE 1048576.0f /* 2^20 */

typedef struct idmr_photon_vertex {
    float position[3];
    unsigned int triangle; /* scene-global */
    float normal[3];       /* geometric, facing the side the photon arrived from */
    float weight;          /* Eq. 2: 1 - |n · d| */
} idmr_photon_vertex;

IDMR_STATIC_ASSERT(sizeof(idmr_photon_vertex) == 32, "idmr_photon_vertex must be 32 bytes");
IDMR_OFFSET_ASSERT(idmr_photon_vertex, normal, 16);
IDMR_OFFSET_ASSERT(idmr_photon_vertex, weight, 28);

#endif
