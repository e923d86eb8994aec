/* idmr/camera.h — a pinhole camera (64 bytes) and the one formula for its rays, shared by the
 * kernels (camera paths), the host (the importance image) and the tests' references.
 *
 * right/up/forward form an orthonormal frame in world space, built from the sensor's to_world
 * transform (Mitsuba looks down +z of camera space, x to the left); width and height are the
 * film's pixels, tan_half_x and tan_half_y the tangents of half the field of view. */
#ifndef IDMR_CAMERA_H
#define IDMR_CAMERA_H

#include "idmr/layout.h"

typedef struct idmr_camera {
    float origin[3];
    unsigned int width;
    float forward[3];
    unsigned int height;
    float right[3];
    float tan_half_x;
    float up[3];
    float tan_half_y;
} idmr_camera;

IDMR_STATIC_ASSERT(sizeof(idmr_camera) == 64, "idmr_camera must be 64 bytes");
IDMR_OFFSET_ASSERT(idmr_camera, forward, 16);
IDMR_OFFSET_ASSERT(idmr_camera, right, 32);
IDMR_OFFSET_ASSERT(idmr_camera, up, 48);

/* The (unnormalised) direction of the ray through film position (film_x, film_y), in pixels
 * from the film's top-left corner (pixel (x, y) spans [x, x + 1) × [y, y + 1); y = 0 is the
 * top row):
 *   d = forward + ((2 film_x / width - 1) tan_half_x) right + ((1 - 2 film_y / height) tan_half_y) up
 * Evaluated in this order everywhere, so host references reproduce the kernels' rays. */
IDMR_INLINE void idmr_camera_direction(const idmr_camera *c, float film_x, float film_y,
                                       float direction[3])
{
    float sx = (2.0f * film_x / (float)c->width - 1.0f) * c->tan_half_x;
    float sy = (1.0f - 2.0f * film_y / (float)c->height) * c->tan_half_y;
    for (int k = 0; k < 3; k++)
        direction[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
}

#endif
