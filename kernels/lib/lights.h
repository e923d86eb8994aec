/* lights.h — the emitters (idmr/light.h) as the kernels see them: emitting a photon path, the
 * flux a photon starts with, and the radiance an emitter shows a camera path. Branches of light
 * kinds the scene does not have are compiled out (features.h). */
#ifndef IDMR_KERNEL_LIGHTS_H
#define IDMR_KERNEL_LIGHTS_H

#include "idmr/light.h"
#include "idmr/sppm_layout.h"
#include "lib/features.h"
#include "lib/sampling.h"
#include "lib/scene.h"

#if HAS_FEATURE(IDMR_FEATURE_AREA)
/* A point of area light `light`, uniform over its area (a triangle chosen by area, then a point
 * in it), and that triangle's unit front normal. */
inline void sample_area_point(const scene_view *scene, global const idmr_light *light,
                              idmr_rng *rng, float3 *p, float3 *n)
{
    uint t = light->cdf_offset + sample_cdf(scene->emitter_cdf + light->cdf_offset,
                                            light->triangle_count, idmr_rng_float(rng));
    float3 v0 = scene->emitter_triangles[3 * t].xyz;
    float3 e1 = scene->emitter_triangles[3 * t + 1].xyz;
    float3 e2 = scene->emitter_triangles[3 * t + 2].xyz;
    float su = sqrt(idmr_rng_float(rng)), v = idmr_rng_float(rng);
    *p = v0 + (1.0f - v) * su * e1 + v * su * e2;
    *n = normalize(cross(e1, e2));
}
#endif

/* Emission of one photon path: a light chosen in proportion to power, then a position and a
 * direction by the light's kind. Returns false if the sample is rejected (outside a spot's
 * smooth falloff), in which case the path stays empty. *light_index is the light chosen. */
inline bool emit(const scene_view *scene, const idmr_sppm_params *params, idmr_rng *rng,
                 float3 *origin, float3 *direction, uint *light_index)
{
    uint index = sample_cdf(scene->light_cdf, params->light_count, idmr_rng_float(rng));
    *light_index = index;
    global const idmr_light *light = scene->lights + index;
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (light->kind == IDMR_LIGHT_AREA) {
        float3 p, n;
        sample_area_point(scene, light, rng, &p, &n);
        *origin = offset_origin(p, n, params->ray_epsilon);
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
        float scene_radius = params->scene_radius;
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
        sample_area_point(scene, light, rng, &target, &n);
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

/* The flux a photon of light `light_index` starts with: emission × the light's sample factor
 * (idmr_light_sample_factor) / (p_light × photons), with p_light the light's probability in the
 * power CDF, as emit() chose it. */
inline float3 photon_initial_flux(const scene_view *scene, const idmr_sppm_params *params,
                                  uint light_index)
{
    global const idmr_light *light = scene->lights + light_index;
    float probability =
        scene->light_cdf[light_index] - (light_index ? scene->light_cdf[light_index - 1] : 0.0f);
    return vload3(0, light->emission) *
           (idmr_light_sample_factor(light->kind, light->area, light->cos_cutoff,
                                     params->scene_radius) /
            (probability * (float)params->path_count));
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

/* Radiance arriving from outside the scene (environment lights; zero without them). */
inline float3 environment_radiance(const scene_view *scene, uint light_count)
{
    float3 radiance = (float3)(0.0f);
#if HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
    for (uint i = 0; i < light_count; i++)
        if (scene->lights[i].kind == IDMR_LIGHT_ENVIRONMENT)
            radiance += vload3(0, scene->lights[i].emission);
#endif
    return radiance;
}

#endif
