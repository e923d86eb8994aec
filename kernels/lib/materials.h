/* materials.h — how the four material kinds (idmr/material.h) scatter light: Fresnel, the
 * specular continuation of camera and photon paths, sampling a scattering event with Russian
 * roulette, and the BRDF of non-specular surfaces. Branches of kinds the scene does not have are
 * compiled out (features.h).
 *
 * Conventions: n is a triangle's unit winding normal (its "front" side, Mitsuba's convention
 * for one-sided bsdfs); ns the shading normal there (lib/shading.h: in n's hemisphere); d is
 * the unit direction a path travels; n_side is ns turned to face the side a path arrives
 * from. Which side a path is on, and so whether it enters a dielectric or meets
 * a one-sided surface's back, is the geometric normal's business; directions and lobes are
 * the shading normal's, as in Mitsuba. */
#ifndef IDMR_KERNEL_MATERIALS_H
#define IDMR_KERNEL_MATERIALS_H

#include "idmr/material.h"
#include "lib/features.h"
#include "lib/sampling.h"

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

/* A plastic's relative index of refraction int_ior / ext_ior, 1 (no interface) where either is
 * not positive, so that no Fresnel factor becomes NaN. */
inline float plastic_eta(const global idmr_material *m)
{
    float eta = m->int_ior / m->ext_ior;
    return m->int_ior > 0.0f && m->ext_ior > 0.0f && isfinite(eta) ? eta : 1.0f;
}

/* 1 - F_dr,ext(eta): the part of uniform diffuse (cosine-weighted) light from outside that a
 * smooth interface of relative index eta = int_ior / ext_ior transmits, F_dr,ext =
 * 2 ∫_0^1 F(μ) μ dμ. Polynomial fits in eta (Egan & Hilgeman 1973 below 1, d'Eon & Irving 2011
 * above): within 3e-5 relative of a 4000-point Gauss-Legendre quadrature of
 * fresnel_dielectric for 1.01 <= eta <= 2.4, 5e-4 at 3, 2e-3 at 4, 1.2e-3 for 0.5 <= eta < 1.
 * By reciprocity it equals eta² (1 - F_dr,int), the factor Mitsuba's plastic divides by. */
inline float plastic_diffuse_transmittance(float eta)
{
    float f;
    if (eta < 1.0f) {
        f = -1.4399f * eta * eta + 0.7099f * eta + 0.6681f + 0.0636f / eta;
    } else {
        float r = 1.0f / eta;
        f = 0.919317f +
            r * (-3.4793f + r * (6.75335f + r * (-7.80989f + r * (4.98554f - 1.36881f * r))));
    }
    return 1.0f - clamp(f, 0.0f, 0.999f);
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
 * normal (it says whether the path enters), ns the shading normal (it bends the path),
 * d the unit incoming direction. */
inline float3 scatter_specular(const global idmr_material *m, float3 d, float3 n, float3 ns,
                               idmr_rng *rng)
{
    float cos_ds = dot(d, ns);
    float3 n_side = cos_ds < 0.0f ? ns : -ns; /* faces the incoming direction */
#if HAS_FEATURE(IDMR_FEATURE_DIELECTRIC)
    if (m->kind == IDMR_MATERIAL_DIELECTRIC) {
        bool entering = dot(d, n) < 0.0f;
        float eta = entering ? m->ext_ior / m->int_ior : m->int_ior / m->ext_ior;
        float cos_i = fabs(cos_ds);
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
 * Shading normals need no correction here: the adjoint BSDF's factor |o·ns| / |o·n| (Veach
 * 1997, §5.3) times the geometric cosine |o·n| of the next vertex leaves |o·ns|, which sampling
 * around ns divides out; the radiance estimate applies the other half (sppm.cl: render_gather).
 *
 * Glossy lobes (GGX): the microfacet normal h is sampled in proportion to D(h) cos θ_h, so the
 * weight of the reflection is the lobe colour × G(i, o) |i·h| / (cos_i cos θ_h). A plastic
 * chooses its coating with probability Fresnel(cos_i), which the lobe's Fresnel factor cancels;
 * otherwise its diffuse base, sampled cosine-weighted, weighs ρ (1 - F(cos_o)) / (1 - F_dr,ext):
 * the light leaving through the coating (see brdf()). That factor has mean 1 over the cosine
 * lobe. The roulette runs after the direction is drawn, with survival
 * min(1, max3(ρ (1 - F_o) / (1 - F_dr))) <= 1, and the weight is divided by it, so the estimate
 * stays unbiased; the weight's largest channel is 1, or at most max3(ρ) / (1 - F_dr) where the
 * survival is 1.
 * Roughness is at least IDMR_MIN_GLOSSY_ROUGHNESS (idmr/material.h), so that a glossy lobe is
 * never a delta the renderer's density estimate cannot see. */
inline int scatter(const global idmr_material *m, float3 *d, float3 n, float3 ns, idmr_rng *rng,
                   float3 *weight)
{
    float3 n_side = dot(*d, n) < 0.0f ? ns : -ns;
    if (material_is_specular(m)) {
        float3 colour = m->kind == IDMR_MATERIAL_MIRROR ? vload3(0, m->specular) : (float3)(1.0f);
        float survival = max3(colour);
        if (!side_reflects(m, *d, n))
            return SCATTER_ABSORBED;
        if (idmr_rng_float(rng) >= survival)
            return SCATTER_ABSORBED;
        *d = scatter_specular(m, *d, n, ns, rng);
        *weight = colour / survival;
        return SCATTER_SPECULAR;
    }
    if (!side_reflects(m, *d, n))
        return SCATTER_ABSORBED;
    float3 diffuse = vload3(0, m->reflectance);
#if HAS_FEATURE(IDMR_FEATURE_GLOSSY)
    if (m->kind == IDMR_MATERIAL_GLOSSY) {
        bool metal = max3(diffuse) <= 0.0f;
        float cos_i = fmax(0.0f, -dot(*d, n_side));
        float eta = plastic_eta(m);
        /* A plastic's coating reflects with Fresnel probability, a metal always. */
        float f = metal ? 1.0f : fresnel_dielectric(cos_i, 1.0f / eta);
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
        /* The diffuse base under the coating. */
        float3 out = sample_cosine(n_side, rng);
        float cos_o = dot(out, n_side);
        if (cos_o <= 0.0f)
            return SCATTER_ABSORBED;
        float3 base = diffuse * ((1.0f - fresnel_dielectric(cos_o, 1.0f / eta)) /
                                 plastic_diffuse_transmittance(eta));
        float survival = fmin(1.0f, max3(base));
        if (idmr_rng_float(rng) >= survival)
            return SCATTER_ABSORBED;
        *d = out;
        *weight = base / survival;
        return SCATTER_DIFFUSE;
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
 *     ρ/π (1 - F(cos_i)) (1 - F(cos_o)) / (1 - F_dr,ext(η)),   η = int_ior / ext_ior:
 * light enters through the coating, scatters diffusely under it (internal reflections
 * included) and leaves through it again (Mitsuba 3's plastic, whose η² (1 - F_dr,int) equals
 * 1 - F_dr,ext by reciprocity). The base's directional albedo stays ρ (1 - F(cos_i)). The
 * Fresnel factors are the smooth interface's, rough plastics included (Mitsuba uses the rough
 * interface's transmittance there). Zero when either direction is below the surface. */
inline float3 brdf(const global idmr_material *m, float3 incoming, float3 outgoing, float3 n_side)
{
    float cos_i = -dot(incoming, n_side), cos_o = dot(outgoing, n_side);
    if (cos_i <= 0.0f || cos_o <= 0.0f)
        return (float3)(0.0f);
    float3 diffuse = vload3(0, m->reflectance) * (1.0f / PI_F);
#if HAS_FEATURE(IDMR_FEATURE_GLOSSY)
    if (m->kind == IDMR_MATERIAL_GLOSSY) {
        bool metal = max3(diffuse) <= 0.0f;
        float eta = plastic_eta(m);
        float f = metal ? 1.0f : fresnel_dielectric(cos_i, 1.0f / eta);
        float base = metal ? 0.0f
                           : (1.0f - f) * (1.0f - fresnel_dielectric(cos_o, 1.0f / eta)) /
                                 plastic_diffuse_transmittance(eta);
        float alpha = fmax(m->roughness, IDMR_MIN_GLOSSY_ROUGHNESS);
        float3 h = normalize(outgoing - incoming);
        float cos_h = dot(h, n_side);
        float a2 = alpha * alpha;
        float denominator = cos_h * cos_h * (a2 - 1.0f) + 1.0f;
        float distribution = cos_h > 0.0f ? a2 / (PI_F * denominator * denominator) : 0.0f;
        float shadowing = ggx_g1(cos_i, alpha) * ggx_g1(cos_o, alpha);
        return f * vload3(0, m->specular) * (distribution * shadowing / (4.0f * cos_i * cos_o)) +
               base * diffuse;
    }
#endif
    return diffuse;
}

#endif
