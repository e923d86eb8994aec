/* idmr/camera.h — a pinhole camera (64 bytes).
 *
 * The ray through pixel (x, y) with sub-pixel offset (jx, jy) in [0,1)² is
 *   d = forward + ((2(x + jx)/width - 1) * tan_half_x) * right
 *               + ((1 - 2(y + jy)/height) * tan_half_y) * up
 * with y = 0 the top row. right/up/forward form an orthonormal frame in world space, built
 * from the sensor's to_world transform (Mitsuba looks down +z of camera space, x to the left). */
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

#endif
