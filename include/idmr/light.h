/* idmr/light.h — one emitter (80 bytes).
 *
 *   AREA         radiance [W/(m² sr)] leaving the front side of every triangle of one mesh:
 *                scene triangles first_triangle .. first_triangle + triangle_count, total area
 *   POINT        intensity [W/sr] at position
 *   SPOT         intensity on the axis `direction`; full inside cos_falloff_start (the beam
 *                width), smooth falloff to zero at cos_cutoff (the cutoff angle)
 *   DIRECTIONAL  irradiance [W/m²] travelling along `direction`
 *   ENVIRONMENT  radiance [W/(m² sr)] arriving from every direction, by the scene's
 *                environment map (Mitsuba's `envmap`; `constant` is a 1 × 1 map: see
 *                idmr/environment.h); `emission` holds the map's mean radiance (reports)
 * `emission` holds radiance, intensity or irradiance by kind; `power` is the total emitted
 * power (luminance-weighted), used to choose lights in proportion to power. An area light's
 * triangles are chosen by area through its stretch of the emitter CDF, which starts at
 * entry cdf_offset (filled by the scene upload, host/device/device_scene.c). */
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

/* The power, per unit of `emission`, of the space a light's photons are sampled from (the
 * kernels' emit()): π × area (cosine-weighted from an area light's front), 4π (a point light's
 * sphere), 2π (1 - cos_cutoff) (a spot's cutoff cone; samples outside its smooth falloff are
 * rejected, which is how the falloff lowers the power), π R² (a directional light's disc over
 * the bounding sphere of radius R) and 4π × π R² (an environment: every direction, each through
 * that disc; the kernels sample an environment by its map instead, idmr/environment.h). A
 * photon of light l, chosen with probability p_l among N photons, carries
 * emission × factor / (p_l N); summed over the photons that are not rejected this is the
 * light's power in expectation (exactly, for every kind but the spot). */
IDMR_INLINE float idmr_light_sample_factor(unsigned int kind, float area, float cos_cutoff,
                                           float scene_radius)
{
    const float pi = 3.14159265358979f;
    float disc = pi * scene_radius * scene_radius;
    switch (kind) {
    case IDMR_LIGHT_AREA:
        return pi * area;
    case IDMR_LIGHT_POINT:
        return 4.0f * pi;
    case IDMR_LIGHT_SPOT:
        return 2.0f * pi * (1.0f - cos_cutoff);
    case IDMR_LIGHT_DIRECTIONAL:
        return disc;
    default: /* IDMR_LIGHT_ENVIRONMENT */
        return 4.0f * pi * disc;
    }
}

/* Rec. 709 / sRGB luminance of linear RGB: lights are chosen, and environment maps sampled, by
 * luminous power. */
IDMR_INLINE float idmr_luminance(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

#endif
