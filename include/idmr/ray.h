/* idmr/ray.h — a ray and a hit record as exchanged between host and kernels
 * (the trace kernels of kernels/trace.cl read rays[] and write hits[]). */
#ifndef IDMR_RAY_H
#define IDMR_RAY_H

#include "idmr/layout.h"

typedef struct idmr_ray {
    float origin[3];
    float tmin;
    float direction[3]; /* need not be unit length; t is in units of |direction| */
    float tmax;
} idmr_ray;

IDMR_STATIC_ASSERT(sizeof(idmr_ray) == 32, "idmr_ray must be 32 bytes");
IDMR_OFFSET_ASSERT(idmr_ray, direction, 16);

#define IDMR_NO_HIT 0xffffffffu

/* Closest hit: t along the ray, barycentrics (u, v) of v1 and v2, the scene-global triangle
 * index, or triangle == IDMR_NO_HIT. Any hit: triangle is 1 (occluded) or IDMR_NO_HIT. */
typedef struct idmr_hit {
    float t;
    float u;
    float v;
    unsigned int triangle;
} idmr_hit;

IDMR_STATIC_ASSERT(sizeof(idmr_hit) == 16, "idmr_hit must be 16 bytes");

#endif
