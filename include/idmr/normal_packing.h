/* idmr/normal_packing.h — a unit vector in 32 bits, shared by the host that packs shading
 * normals (host/device/device_scene.c) and the kernels that unpack them (kernels/lib/scene.h).
 *
 * Octahedral mapping (Cigolle et al., "A Survey of Efficient Representations for Independent
 * Unit Vectors", JCGT 2014): the vector is projected onto the octahedron |x| + |y| + |z| = 1,
 * the lower half folded over the upper, and the two coordinates stored as 16-bit signed
 * normalised integers (low half x, high half y). The worst angular error is about 0.005°. */
#ifndef IDMR_NORMAL_PACKING_H
#define IDMR_NORMAL_PACKING_H

#include "idmr/layout.h"

IDMR_INLINE float idmr_packing_abs(float x)
{
    return x < 0.0f ? -x : x;
}

IDMR_INLINE float idmr_packing_sign(float x)
{
    return x < 0.0f ? -1.0f : 1.0f;
}

/* x in [-1, 1] as a 16-bit two's complement signed normalised integer. */
IDMR_INLINE unsigned int idmr_snorm16(float x)
{
    float clamped = x < -1.0f ? -1.0f : (x > 1.0f ? 1.0f : x);
    int q = (int)(clamped * 32767.0f + (clamped < 0.0f ? -0.5f : 0.5f));
    return (unsigned int)q & 0xffffu;
}

IDMR_INLINE float idmr_unsnorm16(unsigned int bits)
{
    int q = (int)((bits & 0xffffu) ^ 0x8000u) - 0x8000;
    float x = (float)q * (1.0f / 32767.0f);
    return x < -1.0f ? -1.0f : x;
}

/* Packs (x, y, z), any length > 0 (the zero vector packs as +z). */
IDMR_INLINE unsigned int idmr_pack_unit_vector(float x, float y, float z)
{
    float l1 = idmr_packing_abs(x) + idmr_packing_abs(y) + idmr_packing_abs(z);
    if (!(l1 > 0.0f))
        return 0u;
    float u = x / l1, v = y / l1;
    if (z < 0.0f) {
        float folded_u = (1.0f - idmr_packing_abs(v)) * idmr_packing_sign(u);
        float folded_v = (1.0f - idmr_packing_abs(u)) * idmr_packing_sign(v);
        u = folded_u;
        v = folded_v;
    }
    return idmr_snorm16(u) | (idmr_snorm16(v) << 16);
}

/* The packed vector, not normalised (its length lies in [1/sqrt(3), 1]): out[0..2]. */
IDMR_INLINE void idmr_unpack_unit_vector(unsigned int packed, float *out)
{
    float u = idmr_unsnorm16(packed), v = idmr_unsnorm16(packed >> 16);
    float z = 1.0f - idmr_packing_abs(u) - idmr_packing_abs(v);
    if (z < 0.0f) {
        float unfolded_u = (1.0f - idmr_packing_abs(v)) * idmr_packing_sign(u);
        float unfolded_v = (1.0f - idmr_packing_abs(u)) * idmr_packing_sign(v);
        u = unfolded_u;
        v = unfolded_v;
    }
    out[0] = u;
    out[1] = v;
    out[2] = z;
}

#endif
