/* sampling.h — small sampling and vector helpers of the light transport kernels: orthonormal
 * frames, cosine-weighted and uniform directions, reflection, and sampling a discrete CDF. */
#ifndef IDMR_KERNEL_SAMPLING_H
#define IDMR_KERNEL_SAMPLING_H

#include "idmr/rng.h"

#define PI_F 3.14159265358979f

inline float max3(float3 v)
{
    return fmax(v.x, fmax(v.y, v.z));
}

/* An orthonormal frame (t, b) around unit n (Duff et al. 2017, branch-free). */
inline void frame_around(float3 n, float3 *t, float3 *b)
{
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

/* Cosine-weighted direction around unit n. */
inline float3 sample_cosine(float3 n, idmr_rng *rng)
{
    float u1 = idmr_rng_float(rng), u2 = idmr_rng_float(rng);
    float r = sqrt(u1), phi = 2.0f * PI_F * u2;
    float3 t, b;
    frame_around(n, &t, &b);
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(fmax(0.0f, 1.0f - u1)) * n);
}

inline float3 sample_sphere(idmr_rng *rng)
{
    float z = 1.0f - 2.0f * idmr_rng_float(rng);
    float phi = 2.0f * PI_F * idmr_rng_float(rng);
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    return (float3)(r * cos(phi), r * sin(phi), z);
}

inline float3 reflect_about(float3 d, float3 n)
{
    return d - 2.0f * dot(d, n) * n;
}

/* Index of the first entry of cdf[0 .. count) greater than u (the last one if none is). */
inline uint sample_cdf(global const float *cdf, uint count, float u)
{
    uint lo = 0, hi = count - 1;
    while (lo < hi) {
        uint mid = (lo + hi) / 2;
        if (cdf[mid] > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

#endif
