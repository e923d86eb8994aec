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

/* A ray leaving a surface starts this far off it, along the normal: IDMR_RAY_OFFSET_SCALE
 * (2^-20: eight float steps) of the largest coordinate magnitude that went into the point — the
 * vertices of its triangle and the origin of the ray that found it, whose rounding decides how
 * far from the true surface the point can lie — and at least IDMR_RAY_OFFSET_MIN. It scales
 * with the geometry at hand, not with the scene: a speck beside a ground plane 1e5 wide gets the
 * speck's offset. */
#define IDMR_RAY_OFFSET_SCALE 0x1p-20f
#define IDMR_RAY_OFFSET_MIN 1e-30f

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
