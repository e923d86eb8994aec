/* idmr/light.h — one emitter (80 bytes).
 *
 *   AREA         radiance [W/(m² sr)] leaving the front side of every triangle of one mesh:
 *                scene triangles first_triangle .. first_triangle + triangle_count, total area
 *   POINT        intensity [W/sr] at position
 *   SPOT         intensity on the axis `direction`; full inside cos_falloff_start (the beam
 *                width), smooth falloff to zero at cos_cutoff (the cutoff angle)
 *   DIRECTIONAL  irradiance [W/m²] travelling along `direction`
 *   ENVIRONMENT  radiance [W/(m² sr)] arriving from every direction: Mitsuba's `constant`, and
 *                its `envmap` by the map's mean radiance (the map's directional structure is
 *                not simulated)
 * `emission` holds radiance, intensity or irradiance by kind; `power` is the total emitted
 * power (luminance-weighted), used to choose lights in proportion to power. An area light's
 * triangles are chosen by area through its stretch of the emitter CDF, which starts at
 * entry cdf_offset (filled by the importance pass). */
#ifndef IDMR_LIGHT_H
#define IDMR_LIGHT_H

#include "idmr/layout.h"

#define IDMR_LIGHT_AREA 0u
#define IDMR_LIGHT_POINT 1u
#define IDMR_LIGHT_SPOT 2u
#define IDMR_LIGHT_DIRECTIONAL 3u
#define IDMR_LIGHT_ENVIRONMENT 4u
#define IDMR_LIGHT_KIND_COUNT 5u

typedef struct idmr_light {
    float position[3];
    unsigned int kind;
    float direction[3]; /* unit; spot axis or direction of travel */
    float cos_cutoff;
    float emission[3];
    float cos_falloff_start;
    unsigned int first_triangle;
    unsigned int triangle_count;
    float area;
    float power;
    unsigned int cdf_offset;
    unsigned int pad[3];
} idmr_light;

IDMR_STATIC_ASSERT(sizeof(idmr_light) == 80, "idmr_light must be 80 bytes");
IDMR_OFFSET_ASSERT(idmr_light, direction, 16);
IDMR_OFFSET_ASSERT(idmr_light, emission, 32);
IDMR_OFFSET_ASSERT(idmr_light, first_triangle, 48);
IDMR_OFFSET_ASSERT(idmr_light, cdf_offset, 64);

#endif
