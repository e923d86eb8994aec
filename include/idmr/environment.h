/* idmr/environment.h — the environment light's map on the device (one float buffer, the
 * `environment` of SCENE_BUFFERS), built by host/device/device_scene.c from the scene's
 * scene_environment and read by kernels/lib/lights.h.
 *
 * The map is equirectangular in Mitsuba 3's frame: its +y is up, pixel row 0 at θ = 0, and a
 * direction d (pointing to the environment) has u = atan2(d.x, -d.z) / 2π (wrapped to [0, 1)),
 * v = acos(d.y) / π; its radiance is the pixel's value (piecewise constant; Mitsuba filters
 * bilinearly). A constant environment is a 1 × 1 map. Layout, in floats:
 *
 *   [0, 9)        to_world: the map frame's rotation into the world, row-major
 *   [9, 18)       to_map: its inverse
 *   18            ∫ Y(L(ω)) dω over the sphere (Y: luminance, idmr_luminance), > 0
 *   19, 20        width W, height H (whole numbers)
 *   [24, 24+H)    marginal CDF over rows of the pixel weights Y(L) × ΔΩ_row (last entry 1)
 *   [24+H, ...)   H × W: per row, the CDF over its pixels of Y(L) (last entry 1)
 *   then          3 × W × H: the radiance, RGB per pixel, top row first
 * with ΔΩ_row = (2π / W)(cos θ_top − cos θ_bottom) the solid angle of a pixel of that row.
 * Sampling a pixel by these CDFs, then a direction uniform in solid angle within it (φ uniform,
 * cos θ uniform), gives the density pdf(ω) = Y(L(ω)) / ∫ Y(L) dω: each photon carries the same
 * luminance. A scene without an environment binds a buffer of one unused header. */
#ifndef IDMR_ENVIRONMENT_H
#define IDMR_ENVIRONMENT_H

#include "idmr/layout.h"

#define IDMR_ENV_TO_WORLD 0
#define IDMR_ENV_TO_MAP 9
#define IDMR_ENV_INTEGRAL 18
#define IDMR_ENV_WIDTH 19
#define IDMR_ENV_HEIGHT 20
#define IDMR_ENV_HEADER 24

/* Where the parts of a W × H map start in the buffer. */
IDMR_INLINE unsigned int idmr_env_marginal(void)
{
    return IDMR_ENV_HEADER;
}

IDMR_INLINE unsigned int idmr_env_conditional(unsigned int height)
{
    return IDMR_ENV_HEADER + height;
}

IDMR_INLINE unsigned int idmr_env_radiance(unsigned int width, unsigned int height)
{
    return IDMR_ENV_HEADER + height + width * height;
}

/* The number of floats of the buffer for a W × H map. */
IDMR_INLINE unsigned long idmr_env_floats(unsigned int width, unsigned int height)
{
    return IDMR_ENV_HEADER + (unsigned long)height + 4ul * width * height;
}

#endif
