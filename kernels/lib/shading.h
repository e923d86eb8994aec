/* shading.h — shading normals: the vertex normals a mesh brings (or the loader computes),
 * interpolated at a hit. The kernels bend specular paths and orient scattering lobes with them
 * while the geometric (winding) normal decides which side of a surface a path is on, as
 * Mitsuba does; the radiance estimate then weights each photon by shading_correction().
 * The buffer: uint4 per scene triangle, its corners' normals packed (idmr/normal_packing.h)
 * and w = 1; w = 0 where the triangle is shaded flat. */
#ifndef IDMR_KERNEL_SHADING_H
#define IDMR_KERNEL_SHADING_H

#include "idmr/normal_packing.h"
#include "idmr/ray.h"

/* A packed normal as a unit vector. */
inline float3 unpack_normal(uint packed)
{
    float xyz[3];
    idmr_unpack_unit_vector(packed, xyz);
    return normalize((float3)(xyz[0], xyz[1], xyz[2]));
}

/* The corners' unit normals c0, c1, c2 interpolated at `hit`'s barycentrics and normalised,
 * turned into the hemisphere of the unit winding normal n (so that the side a path is on stays
 * the geometric one); n itself where the interpolation vanishes. */
inline float3 shading_interpolate(float3 c0, float3 c1, float3 c2, idmr_hit hit, float3 n)
{
    float3 s = (1.0f - hit.u - hit.v) * c0 + hit.u * c1 + hit.v * c2;
    float length2 = dot(s, s);
    if (!(length2 > 1e-12f))
        return n;
    s *= rsqrt(length2);
    return dot(s, n) < 0.0f ? -s : s;
}

/* The shading normal at `hit` on a triangle with unit winding normal n: its corners' normals
 * interpolated (shading_interpolate); n itself where the triangle is shaded flat. */
inline float3 shading_normal(global const uint4 *triangle_shading, idmr_hit hit, float3 n)
{
    uint4 packed = triangle_shading[hit.triangle];
    if (packed.w == 0u)
        return n;
    return shading_interpolate(unpack_normal(packed.x), unpack_normal(packed.y),
                               unpack_normal(packed.z), hit, n);
}

/* Photons arrive with a density in proportion to |incoming·n| (the geometric normal); the
 * radiance a shading normal ns reflects is in proportion to |incoming·ns| (Veach 1997, §5.3),
 * so each photon counts |incoming·ns| / |incoming·n|. Limited to
 * IDMR_SHADING_CORRECTION_LIMIT, since a photon grazing a facet that the shading normal faces
 * would otherwise carry a weight without bound (a small bias instead of fireflies); 1 where
 * ns = n. */
#define IDMR_SHADING_CORRECTION_LIMIT 10.0f
inline float shading_correction(float3 incoming, float3 ns, float3 n)
{
    float cos_geometric = fabs(dot(incoming, n));
    float cos_shading = fabs(dot(incoming, ns));
    return cos_shading < IDMR_SHADING_CORRECTION_LIMIT * cos_geometric
               ? cos_shading / cos_geometric
               : IDMR_SHADING_CORRECTION_LIMIT;
}

#endif
