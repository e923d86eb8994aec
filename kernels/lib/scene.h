/* scene.h — device-side scene access and the light transport building blocks shared by the
 * importance pass (importance.cl) and the renderer: per-triangle data, frames, material
 * scattering, light emission.
 *
 * Per-triangle data is indexed by the scene-global triangle index the traversal returns:
 *   triangle_normals[t]   float4: unit geometric normal (winding order), w = area
 *   triangle_materials[t] index into materials[]
 * A surface's "front" is the side its winding normal points to (Mitsuba's convention for area
 * lights and one-sided bsdfs).
 *
 * Feature bits (IDMR_FEATURES, idmr/features.h) compile out the branches of material and light
 * kinds the scene does not have. */
#ifndef IDMR_KERNEL_SCENE_H
#define IDMR_KERNEL_SCENE_H

#include "idmr/camera.h"
#include "idmr/features.h"
#include "idmr/light.h"
#include "idmr/material.h"
#include "idmr/rng.h"
#include "idmr/weight.h"

#ifndef IDMR_FEATURES
#error "IDMR_FEATURES must be defined by the host (device_build_options)"
#endif
#define HAS_FEATURE(bit) ((IDMR_FEATURES & (bit)) != 0u)
#if (IDMR_FEATURES & ~IDMR_FEATURES_ALL) != 0u
#error "IDMR_FEATURES has bits no feature defines (idmr/features.h)"
#endif
#if !HAS_FEATURE(IDMR_FEATURES_LIGHTS)
#error "no light kind in IDMR_FEATURES: photon paths need an emitter"
#endif
#if HAS_FEATURE(IDMR_FEATURE_TEXTURED) && !HAS_FEATURE(IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_GLOSSY)
#error "a texture without a diffuse or glossy material to carry it"
#endif

#define PI_F 3.14159265358979f

inline float3 load3(global const float *v)
{
    return (float3)(v[0], v[1], v[2]);
}

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

/* Unpolarised Fresnel reflectance of a dielectric interface; eta = n_incident / n_transmitted,
 * cos_i > 0. Total internal reflection returns 1. */
inline float fresnel_dielectric(float cos_i, float eta)
{
    float sin2_t = eta * eta * fmax(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f)
        return 1.0f;
    float cos_t = sqrt(1.0f - sin2_t);
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

/* Offsets a surface point to the side `side` (a unit normal) points to, so that a ray leaving
 * it does not hit the same surface again. */
inline float3 offset_origin(float3 p, float3 side, float epsilon)
{
    return p + side * epsilon;
}

/* The outcome of one scattering event. */
#define SCATTER_ABSORBED 0
#define SCATTER_DIFFUSE 1  /* a non-specular lobe: camera paths end here */
#define SCATTER_SPECULAR 2 /* mirror reflection or dielectric reflection/refraction */

inline bool material_is_specular(const global idmr_material *m)
{
#if HAS_FEATURE(IDMR_FEATURES_SPECULAR)
    return m->kind == IDMR_MATERIAL_MIRROR || m->kind == IDMR_MATERIAL_DIELECTRIC;
#else
    return false;
#endif
}

/* Whether the side of a surface with winding normal n that direction d arrives on scatters
 * light: the front always, the back only for two-sided materials (and dielectrics). */
inline bool side_reflects(const global idmr_material *m, float3 d, float3 n)
{
    return dot(d, n) <= 0.0f || (m->flags & IDMR_MATERIAL_TWOSIDED) ||
           m->kind == IDMR_MATERIAL_DIELECTRIC;
}

/* Smooth specular continuation (mirror, dielectric): the direction after the interface, the
 * choice between reflection and refraction made with probability Fresnel. n is the winding
 * normal, d the unit incoming direction. */
inline float3 scatter_specular(const global idmr_material *m, float3 d, float3 n, idmr_rng *rng)
{
    float cos_dn = dot(d, n);
    float3 n_side = cos_dn < 0.0f ? n : -n; /* faces the incoming side */
#if HAS_FEATURE(IDMR_FEATURE_DIELECTRIC)
    if (m->kind == IDMR_MATERIAL_DIELECTRIC) {
        bool entering = cos_dn < 0.0f;
        float eta = entering ? m->ext_ior / m->int_ior : m->int_ior / m->ext_ior;
        float cos_i = fabs(cos_dn);
        float f = fresnel_dielectric(cos_i, eta);
        if (m->flags & IDMR_MATERIAL_THIN) {
            /* A thin slab: multiple internal reflections, no refraction of the direction. */
            float reflect_probability = 2.0f * f / (1.0f + f);
            return idmr_rng_float(rng) < reflect_probability ? reflect_about(d, n_side) : d;
        }
        if (idmr_rng_float(rng) < f)
            return reflect_about(d, n_side);
        float sin2_t = eta * eta * fmax(0.0f, 1.0f - cos_i * cos_i);
        float cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
        return normalize(eta * d + (eta * cos_i - cos_t) * n_side);
    }
#endif
    return reflect_about(d, n_side);
}

/* GGX (Trowbridge-Reitz) microfacet normal around n_side with roughness alpha, sampled in
 * proportion to D(h) cos(theta_h). */
inline float3 sample_ggx_normal(float3 n_side, float alpha, idmr_rng *rng)
{
    float u1 = idmr_rng_float(rng), u2 = idmr_rng_float(rng);
    float tan2 = alpha * alpha * u1 / fmax(1e-7f, 1.0f - u1);
    float cos_theta = 1.0f / sqrt(1.0f + tan2);
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float phi = 2.0f * PI_F * u2;
    float3 t, b;
    frame_around(n_side, &t, &b);
    return normalize(sin_theta * cos(phi) * t + sin_theta * sin(phi) * b + cos_theta * n_side);
}

/* Smith's shadowing-masking term of GGX for one direction at cosine cos_v to the normal. */
inline float ggx_g1(float cos_v, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0f * cos_v / (cos_v + sqrt(a2 + (1.0f - a2) * cos_v * cos_v));
}

/* Scatters a path at a surface: *d becomes the new direction and *weight the factor the
 * path's flux (or a camera path's throughput) is multiplied by — f cos / pdf divided by the
 * survival probability, per RGB channel. Absorption is Russian roulette with survival
 * probability equal to the largest channel of the chosen lobe's albedo, at every bounce:
 * importance paths carry no flux, so the roulette is their only absorption. A one-sided
 * surface absorbs what arrives at its back.
 *
 * Glossy lobes (GGX): the microfacet normal h is sampled in proportion to D(h) cos θ_h, so the
 * weight of the reflection is the lobe colour × G(i, o) |i·h| / (cos_i cos θ_h). A plastic
 * chooses its coating with probability Fresnel(cos_i), which the lobe's Fresnel factor cancels.
 * Roughness is at least IDMR_MIN_GLOSSY_ROUGHNESS, so that a glossy lobe is never a delta the
 * renderer's density estimate cannot see. */
#define IDMR_MIN_GLOSSY_ROUGHNESS 0.05f
inline int scatter(const global idmr_material *m, float3 *d, float3 n, idmr_rng *rng,
                   float3 *weight)
{
    float cos_dn = dot(*d, n);
    float3 n_side = cos_dn < 0.0f ? n : -n;
    if (material_is_specular(m)) {
        float3 colour = m->kind == IDMR_MATERIAL_MIRROR ? vload3(0, m->specular) : (float3)(1.0f);
        float survival = max3(colour);
        if (!side_reflects(m, *d, n))
            return SCATTER_ABSORBED;
        if (idmr_rng_float(rng) >= survival)
            return SCATTER_ABSORBED;
        *d = scatter_specular(m, *d, n, rng);
        *weight = colour / survival;
        return SCATTER_SPECULAR;
    }
    if (!side_reflects(m, *d, n))
        return SCATTER_ABSORBED;
    float3 diffuse = vload3(0, m->reflectance);
#if HAS_FEATURE(IDMR_FEATURE_GLOSSY)
    if (m->kind == IDMR_MATERIAL_GLOSSY) {
        bool metal = max3(diffuse) <= 0.0f;
        float cos_i = -dot(*d, n_side);
        /* A plastic's coating reflects with Fresnel probability, a metal always. */
        float f = metal ? 1.0f : fresnel_dielectric(cos_i, m->ext_ior / m->int_ior);
        if (idmr_rng_float(rng) < f) {
            float3 colour = vload3(0, m->specular);
            float survival = max3(colour);
            if (idmr_rng_float(rng) >= survival)
                return SCATTER_ABSORBED;
            float alpha = fmax(m->roughness, IDMR_MIN_GLOSSY_ROUGHNESS);
            float3 h = sample_ggx_normal(n_side, alpha, rng);
            float3 out = reflect_about(*d, h);
            float cos_o = dot(out, n_side);
            if (cos_o <= 0.0f)
                return SCATTER_ABSORBED;
            float cos_h = dot(h, n_side);
            float shadowing = ggx_g1(fmax(cos_i, 1e-6f), alpha) * ggx_g1(cos_o, alpha);
            *weight = colour / survival *
                      (shadowing * fabs(dot(out, h)) / fmax(cos_i * cos_h, 1e-6f));
            *d = out;
            return SCATTER_DIFFUSE;
        }
    }
#endif
    float survival = max3(diffuse);
    if (idmr_rng_float(rng) >= survival)
        return SCATTER_ABSORBED;
    *d = sample_cosine(n_side, rng);
    *weight = diffuse / survival;
    return SCATTER_DIFFUSE;
}

/* The BRDF of a non-specular surface for light arriving along direction `incoming` (towards
 * the surface) and leaving along `outgoing` (away from it), on the side n_side faces (the
 * caller makes sure that side reflects: the front, or either side of a two-sided material).
 * It matches what scatter() samples: Lambert ρ/π; a metal's GGX lobe colour × D G /
 * (4 cos_i cos_o); a plastic's coating weighted by Fresnel(cos_i) over its diffuse base
 * weighted by 1 - Fresnel(cos_i). Zero when either direction is below the surface. */
inline float3 brdf(const global idmr_material *m, float3 incoming, float3 outgoing, float3 n_side)
{
    float cos_i = -dot(incoming, n_side), cos_o = dot(outgoing, n_side);
    if (cos_i <= 0.0f || cos_o <= 0.0f)
        return (float3)(0.0f);
    float3 diffuse = vload3(0, m->reflectance) * (1.0f / PI_F);
#if HAS_FEATURE(IDMR_FEATURE_GLOSSY)
    if (m->kind == IDMR_MATERIAL_GLOSSY) {
        bool metal = max3(diffuse) <= 0.0f;
        float f = metal ? 1.0f : fresnel_dielectric(cos_i, m->ext_ior / m->int_ior);
        float alpha = fmax(m->roughness, IDMR_MIN_GLOSSY_ROUGHNESS);
        float3 h = normalize(outgoing - incoming);
        float cos_h = dot(h, n_side);
        float a2 = alpha * alpha;
        float denominator = cos_h * cos_h * (a2 - 1.0f) + 1.0f;
        float distribution = cos_h > 0.0f ? a2 / (PI_F * denominator * denominator) : 0.0f;
        float shadowing = ggx_g1(cos_i, alpha) * ggx_g1(cos_o, alpha);
        return f * vload3(0, m->specular) * (distribution * shadowing / (4.0f * cos_i * cos_o)) +
               (1.0f - f) * diffuse;
    }
#endif
    return diffuse;
}

/* The camera ray through pixel (x, y), jittered within the pixel. */
inline float3 camera_direction(const idmr_camera *c, uint x, uint y, idmr_rng *rng)
{
    float sx = (2.0f * ((float)x + idmr_rng_float(rng)) / (float)c->width - 1.0f) * c->tan_half_x;
    float sy = (1.0f - 2.0f * ((float)y + idmr_rng_float(rng)) / (float)c->height) * c->tan_half_y;
    return normalize(vload3(0, c->forward) + sx * vload3(0, c->right) + sy * vload3(0, c->up));
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

/* Emission of one photon path: a light chosen in proportion to power, then a position and a
 * direction by the light's kind. Returns false if the sample is rejected (outside a spot's
 * smooth falloff), in which case the path stays empty. *light_index is the light chosen. */
inline bool emit(global const idmr_light *lights, global const float *light_cdf, uint light_count,
                 global const float *emitter_cdf, global const float4 *emitter_triangles,
                 float3 scene_center, float scene_radius, float epsilon, idmr_rng *rng,
                 float3 *origin, float3 *direction, uint *light_index)
{
    uint index = sample_cdf(light_cdf, light_count, idmr_rng_float(rng));
    *light_index = index;
    global const idmr_light *light = lights + index;
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (light->kind == IDMR_LIGHT_AREA) {
        uint t = light->cdf_offset +
                 sample_cdf(emitter_cdf + light->cdf_offset, light->triangle_count,
                            idmr_rng_float(rng));
        float3 v0 = emitter_triangles[3 * t].xyz;
        float3 e1 = emitter_triangles[3 * t + 1].xyz;
        float3 e2 = emitter_triangles[3 * t + 2].xyz;
        float su = sqrt(idmr_rng_float(rng)), v = idmr_rng_float(rng);
        float3 p = v0 + (1.0f - v) * su * e1 + v * su * e2;
        float3 n = normalize(cross(e1, e2));
        *origin = offset_origin(p, n, epsilon);
        *direction = sample_cosine(n, rng);
        return true;
    }
#endif
#if HAS_FEATURE(IDMR_FEATURE_POINT)
    if (light->kind == IDMR_LIGHT_POINT) {
        *origin = vload3(0, light->position);
        *direction = sample_sphere(rng);
        return true;
    }
#endif
#if HAS_FEATURE(IDMR_FEATURE_SPOT)
    if (light->kind == IDMR_LIGHT_SPOT) {
        /* Uniform in the cutoff cone, then kept with the smooth falloff's probability. */
        float3 axis = vload3(0, light->direction);
        float cos_theta = 1.0f - idmr_rng_float(rng) * (1.0f - light->cos_cutoff);
        float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
        float phi = 2.0f * PI_F * idmr_rng_float(rng);
        float3 t, b;
        frame_around(axis, &t, &b);
        *origin = vload3(0, light->position);
        *direction = normalize(sin_theta * cos(phi) * t + sin_theta * sin(phi) * b + cos_theta * axis);
        float keep = smoothstep(light->cos_cutoff, light->cos_falloff_start, cos_theta);
        return idmr_rng_float(rng) < keep;
    }
#endif
#if HAS_FEATURE(IDMR_FEATURE_DIRECTIONAL) || HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
    if (light->kind == IDMR_LIGHT_DIRECTIONAL || light->kind == IDMR_LIGHT_ENVIRONMENT) {
        /* Parallel light from a disc covering the scene's bounding sphere, outside it; an
         * environment's direction is uniform over the sphere. */
        float3 d = light->kind == IDMR_LIGHT_DIRECTIONAL ? vload3(0, light->direction)
                                                         : sample_sphere(rng);
        float3 t, b;
        frame_around(d, &t, &b);
        float r = scene_radius * sqrt(idmr_rng_float(rng));
        float phi = 2.0f * PI_F * idmr_rng_float(rng);
        *origin = scene_center - 1.01f * scene_radius * d + r * cos(phi) * t + r * sin(phi) * b;
        *direction = d;
        return true;
    }
#endif
    return false;
}

#endif
