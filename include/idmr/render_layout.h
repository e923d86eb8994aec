/* idmr/render_layout.h — what the renderer adds on the device to the SPPM core's buffers
 * (idmr/sppm_layout.h):
 *
 *   idmr_render_hit     render_hits[pixels]        beside hit_points[pixel]: what the radiance
 *                                                  estimate at the hit point needs, and the
 *                                                  radiance of emitters the camera path saw
 *                                                  directly (or through specular surfaces)
 *   idmr_render_photon  the photon records (idmr/sppm_layout.h): one photon per
 *                                                  non-specular surface a path reached, on a
 *                                                  side that reflects
 *   fixed_word          pixel_radiance[pixels * 3] this iteration's photon estimate per pixel
 *                                                  and channel, 64-bit fixed point
 *
 * Fixed point: a radiance contribution c is added as round(c × fixed_scale) (idmr_sppm_params),
 * one word per pixel and channel, so the sum is exact and independent of the order photons
 * are gathered in. The host picks fixed_scale so that one photon of the brightest light on a
 * white diffuse surface is 2^32 units; a single contribution is clamped to 2^40 units (256 such
 * photons: only a pathological glossy peak reaches it), and the host checks each word against
 * IDMR_FIXED_SATURATION. */
#ifndef IDMR_RENDER_LAYOUT_H
#define IDMR_RENDER_LAYOUT_H

#include "idmr/layout.h"

#define IDMR_RENDER_PHOTON_UNITS 4294967296.0           /* 2^32: one reference photon */
#define IDMR_RENDER_CONTRIBUTION_LIMIT 1099511627776.0f /* 2^40 units */

typedef struct idmr_render_hit {
    float throughput[3];   /* product of the specular weights along the camera path */
    unsigned int material; /* of the surface the hit point lies on */
    float outgoing[3];     /* unit: from the hit point back along the camera path */
    unsigned int shading_normal; /* packed (idmr/normal_packing.h), facing the camera path */
    float emitted[3];      /* radiance of the emitters the camera path saw */
    float pad2;
} idmr_render_hit;

IDMR_STATIC_ASSERT(sizeof(idmr_render_hit) == 48, "idmr_render_hit must be 48 bytes");
IDMR_OFFSET_ASSERT(idmr_render_hit, outgoing, 16);
IDMR_OFFSET_ASSERT(idmr_render_hit, emitted, 32);

typedef struct idmr_render_photon {
    float position[3];
    float flux_r;
    float direction[3]; /* unit direction of travel as it arrived */
    float flux_g;
    float normal[3]; /* geometric, facing the side the photon arrived from */
    float flux_b;
} idmr_render_photon;

IDMR_STATIC_ASSERT(sizeof(idmr_render_photon) == 48, "idmr_render_photon must be 48 bytes");
IDMR_OFFSET_ASSERT(idmr_render_photon, direction, 16);
IDMR_OFFSET_ASSERT(idmr_render_photon, normal, 32);

#endif
