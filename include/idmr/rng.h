/* idmr/rng.h — counter-based random numbers, the same on the host, in the kernels and in the
 * tests (the project's one generator).
 *
 * A stream is keyed by (seed, iteration, stream family, index) — index is the pixel or photon
 * path — and its draws are numbered, so a number depends on nothing but those five values: not
 * on the work-group size, the device, or the order work-items run in. The mixing function is
 * Chris Wellons' "lowbias32" integer hash (32-bit multiplies and shifts only: cheap on GPUs
 * and CPUs alike); keys are chained through it, and draw k of a stream is hash(key ^ hash(k)).
 * Floats take the top 24 bits, so they lie in [0, 1) exactly. */
#ifndef IDMR_RNG_H
#define IDMR_RNG_H

#include "idmr/layout.h"

/* Stream families: one per kind of path and pass, so the importance pass and the renderer never
 * share random numbers for the same seed. Tests key their own data with IDMR_STREAM_TEST. */
#define IDMR_STREAM_IMPORTANCE_CAMERA 1u
#define IDMR_STREAM_IMPORTANCE_PHOTON 2u
#define IDMR_STREAM_RENDER_CAMERA 3u
#define IDMR_STREAM_RENDER_PHOTON 4u
#define IDMR_STREAM_TEST 5u
#define IDMR_STREAM_IMPORTANCE_SHADOW 6u

typedef struct idmr_rng {
    unsigned int key;
    unsigned int counter;
} idmr_rng;

IDMR_INLINE unsigned int idmr_hash(unsigned int x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

IDMR_INLINE idmr_rng idmr_rng_init(unsigned int seed, unsigned int iteration,
                                   unsigned int stream, unsigned int index)
{
    idmr_rng r;
    unsigned int key = idmr_hash(seed ^ 0x9e3779b9u);
    key = idmr_hash(key ^ iteration);
    key = idmr_hash(key ^ (stream * 0x85ebca6bu));
    key = idmr_hash(key ^ index);
    r.key = key;
    r.counter = 0u;
    return r;
}

IDMR_INLINE unsigned int idmr_rng_next(idmr_rng *r)
{
    unsigned int k = r->counter++;
    return idmr_hash(r->key ^ idmr_hash(k + 0x68e31da4u));
}

/* Uniform in [0, 1). */
IDMR_INLINE float idmr_rng_float(idmr_rng *r)
{
    return (float)(idmr_rng_next(r) >> 8) * (1.0f / 16777216.0f);
}

#endif
