/* lights.h — the emitters (idmr/light.h) as the kernels see them: emitting a photon path, the
 * flux a photon starts with, and the radiance an emitter shows a camera path. Branches of light
 * kinds the scene does not have are compiled out (features.h). */
#ifndef IDMR_KERNEL_LIGHTS_H
#define IDMR_KERNEL_LIGHTS_H

#include "idmr/environment.h"
#include "idmr/light.h"
#include "idmr/sppm_layout.h"
#include "lib/features.h"
#include "lib/sampling.h"
#include "lib/scene.h"

#if HAS_FEATURE(IDMR_FEATURE_AREA)
/* A point of area light `light`, uniform over its area (a triangle chosen by area, then a point
 * in it), that triangle's unit front normal, and the offset of a ray leaving it (idmr/ray.h). */
inline void sample_area_point(const scene_view *scene, global const idmr_light *light,
                              idmr_rng *rng, float3 *p, float3 *n, float *offset)
{
    uint t = light->cdf_offset + sample_cdf(scene->emitter_cdf + light->cdf_offset,
                                            light->triangle_count, idmr_rng_float(rng));
    float4 v0_offset = scene->emitter_triangles[3 * t];
    float3 v0 = v0_offset.xyz;
    float3 e1 = scene->emitter_triangles[3 * t + 1].xyz;
    float3 e2 = scene->emitter_triangles[3 * t + 2].xyz;
    float su = sqrt(idmr_rng_float(rng)), v = idmr_rng_float(rng);
    *p = v0 + (1.0f - v) * su * e1 + v * su * e2;
    *n = normalize(cross(e1, e2));
    *offset = v0_offset.w;
}
#endif

#if HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
/* The rows of a 3x3 row-major matrix at m applied to v. */
inline float3 environment_rotate(global const float *m, float3 v)
{
    return (float3)(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                    m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

/* The radiance of the environment map (idmr/environment.h) arriving from world direction d
 * (pointing to the environment). */
inline float3 environment_lookup(global const float *env, float3 d)
{
    uint width = (uint)env[IDMR_ENV_WIDTH], height = (uint)env[IDMR_ENV_HEIGHT];
    float3 in_map = normalize(environment_rotate(env + IDMR_ENV_TO_MAP, d));
    float u = atan2(in_map.x, -in_map.z) * (0.5f / PI_F);
    u = u < 0.0f ? u + 1.0f : u;
    float v = acos(clamp(in_map.y, -1.0f, 1.0f)) * (1.0f / PI_F);
    uint x = min((uint)(u * (float)width), width - 1);
    uint y = min((uint)(v * (float)height), height - 1);
    return vload3(y * width + x, env + idmr_env_radiance(width, height));
}

/* A world direction towards the environment, drawn with density Y(L(ω)) / ∫ Y(L) dω: a pixel
 * by the map's CDFs, then uniformly in solid angle within it. *weight gets L(ω) / pdf(ω). */
inline float3 environment_sample(global const float *env, idmr_rng *rng, float3 *weight)
{
    uint width = (uint)env[IDMR_ENV_WIDTH], height = (uint)env[IDMR_ENV_HEIGHT];
    uint y = sample_cdf(env + idmr_env_marginal(), height, idmr_rng_float(rng));
    uint x = sample_cdf(env + idmr_env_conditional(height) + y * width, width,
                        idmr_rng_float(rng));
    float phi = 2.0f * PI_F * ((float)x + idmr_rng_float(rng)) / (float)width;
    float cos_top = cos(PI_F * (float)y / (float)height);
    float cos_bottom = cos(PI_F * (float)(y + 1) / (float)height);
    float cos_theta = mix(cos_top, cos_bottom, idmr_rng_float(rng));
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float3 in_map = (float3)(sin(phi) * sin_theta, cos_theta, -cos(phi) * sin_theta);
    float3 radiance = vload3(y * width + x, env + idmr_env_radiance(width, height));
    float luminance = idmr_luminance(radiance.x, radiance.y, radiance.z);
    *weight = luminance > 0.0f ? radiance * (env[IDMR_ENV_INTEGRAL] / luminance) : (float3)(0.0f);
    return normalize(environment_rotate(env + IDMR_ENV_TO_WORLD, in_map));
}
#endif

/* Emission of one photon path: a light chosen in proportion to power, then a position and a
 * direction by the light's kind. *emitted gets what the photon carries before the division by
 * the light's probability and the photon count (photon_initial_flux): emission × the light's
 * sample factor (idmr_light_sample_factor), or for an environment the sampled direction's
 * radiance / its density × the bounding disc's area. Returns false if the sample is rejected
 * (outside a spot's smooth falloff), in which case the path stays empty. *light_index is the
 * light chosen. */
inline bool emit(const scene_view *scene, const idmr_sppm_params *params, idmr_rng *rng,
                 float3 *origin, float3 *direction, uint *light_index, float3 *emitted)
{
    uint index = sample_cdf(scene->light_cdf, params->light_count, idmr_rng_float(rng));
    *light_index = index;
    global const idmr_light *light = scene->lights + index;
    *emitted = vload3(0, light->emission) *
               idmr_light_sample_factor(light->kind, light->area, light->cos_cutoff,
                                        params->scene_radius);
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (light->kind == IDMR_LIGHT_AREA) {
        float3 p, n;
        float offset;
        sample_area_point(scene, light, rng, &p, &n, &offset);
        *origin = offset_origin(p, n, offset);
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
         * environment's direction drawn from its map. */
        float3 d = vload3(0, light->direction);
        float scene_radius = params->scene_radius;
#if HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
        if (light->kind == IDMR_LIGHT_ENVIRONMENT) {
            float3 radiance_over_pdf;
            d = -environment_sample(scene->environment, rng, &radiance_over_pdf);
            *emitted = radiance_over_pdf * (PI_F * scene_radius * scene_radius);
        }
#endif
        float3 t, b;
        frame_around(d, &t, &b);
        float r = scene_radius * sqrt(idmr_rng_float(rng));
        float phi = 2.0f * PI_F * idmr_rng_float(rng);
        *origin = vload3(0, params->scene_center) - 1.01f * scene_radius * d + r * cos(phi) * t +
                  r * sin(phi) * b;
        *direction = d;
        return true;
    }
#endif
    return false;
}

/* Where a shadow ray from receiver point p goes (shadow importance, kernels/sppm.cl): a light
 * chosen in proportion to power and a point on it. Sets the unit direction towards it, the
 * distance (INFINITY for a directional light), the light's size (the width of an area light,
 * sqrt of its area; 0 for point-like lights, whose shadows are sharp) and the share of the light
 * that reaches p (a spot's falloff; 0 behind an area light or outside a spot's cone). Returns
 * false when the light is an environment (its shadows are too soft to draw an outline) or
 * reaches p not at all. */
inline bool shadow_light_sample(const scene_view *scene, const idmr_sppm_params *params,
                                float3 p, idmr_rng *rng, float3 *direction, float *distance,
                                float *size, float *reach)
{
    uint index = sample_cdf(scene->light_cdf, params->light_count, idmr_rng_float(rng));
    global const idmr_light *light = scene->lights + index;
    float3 target = vload3(0, light->position);
    *size = 0.0f;
    *reach = 1.0f;
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (light->kind == IDMR_LIGHT_AREA) {
        float3 n;
        float unused_offset;
        sample_area_point(scene, light, rng, &target, &n, &unused_offset);
        *size = sqrt(light->area);
        *reach = dot(p - target, n) > 0.0f ? 1.0f : 0.0f; /* in front of the emitting side */
    }
#endif
#if HAS_FEATURE(IDMR_FEATURE_DIRECTIONAL)
    if (light->kind == IDMR_LIGHT_DIRECTIONAL) {
        *direction = -vload3(0, light->direction);
        *distance = INFINITY;
        return true;
    }
#endif
    if (light->kind == IDMR_LIGHT_ENVIRONMENT)
        return false;
    float3 towards = target - p;
    *distance = length(towards);
    if (!(*distance > 0.0f))
        return false;
    *direction = towards / *distance;
#if HAS_FEATURE(IDMR_FEATURE_SPOT)
    if (light->kind == IDMR_LIGHT_SPOT)
        *reach = smoothstep(light->cos_cutoff, light->cos_falloff_start,
                            dot(-*direction, vload3(0, light->direction)));
#endif
    return *reach > 0.0f;
}

/* The flux a photon of light `light_index` starts with: what emit() said it emitted /
 * (p_light × photons), with p_light the light's probability in the power CDF, as emit() chose
 * it. */
inline float3 photon_initial_flux(const scene_view *scene, const idmr_sppm_params *params,
                                  uint light_index, float3 emitted)
{
    float probability =
        scene->light_cdf[light_index] - (light_index ? scene->light_cdf[light_index - 1] : 0.0f);
    return emitted / (probability * (float)params->path_count);
}

/* Radiance leaving emitter surface `triangle` towards direction -d: an area light's emission
 * on its front side, else zero. */
inline float3 surface_emission(const scene_view *scene, uint light_count, uint triangle, float3 d,
                               float3 n)
{
    float3 radiance = (float3)(0.0f);
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (dot(d, n) < 0.0f)
        for (uint i = 0; i < light_count; i++) {
            global const idmr_light *light = scene->lights + i;
            if (light->kind == IDMR_LIGHT_AREA &&
                triangle - light->first_triangle < light->triangle_count)
                radiance += vload3(0, light->emission);
        }
#endif
    return radiance;
}

/* Radiance arriving from outside the scene along -d (d: the direction of a ray that left it):
 * the environment map's, zero without one (its buffer's header then says width 0). */
inline float3 environment_radiance(const scene_view *scene, float3 d)
{
#if HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
    if (scene->environment[IDMR_ENV_WIDTH] > 0.0f)
        return environment_lookup(scene->environment, d);
#endif
    return (float3)(0.0f);
}

#endif
