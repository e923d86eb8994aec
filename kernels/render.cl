/* render.cl — one iteration of the stochastic progressive photon mapping renderer (`idmr
 * render`): an independent photon-mapping estimate of every pixel at this iteration's radius;
 * the host averages the iterations (host/render.c).
 *
 *   render_camera   one path per pixel, jittered within it: through mirrors and dielectrics
 *                   (their weights into the throughput) to the first non-specular surface,
 *                   where it leaves a hit point; emitters it sees on the way (an area light's
 *                   front, the environment when it leaves the scene) go into emitted[pixel]
 *   render_photon   one photon path per work-item, from a light chosen by power, with flux;
 *                   a photon is stored at every non-specular surface it reaches (on a side
 *                   that reflects), up to IDMR_PATH_VERTICES per path
 *   grid_*, scan_*  the hash grid over the hit points (hit_point_grid.h)
 *   render_gather   per stored photon: every hit point within the radius on the same side
 *                   gets throughput × BRDF × flux / (π r²), added in fixed point to its pixel
 *
 * The same materials and lights as the importance pass, through the same building blocks
 * (scene.h), compiled for the scene's feature bits. Layouts: idmr/importance.h (hit points,
 * params), idmr/render.h (the renderer's own buffers). */
#pragma OPENCL FP_CONTRACT OFF
#include "lib/fixed_point.h"
#include "lib/hit_point_grid.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "idmr/render_layout.h"
#include "lib/scene.h"
#include "lib/traverse.h"

/* Radiance leaving emitter surface `triangle` towards direction -d: an area light's emission
 * on its front side, else zero. */
inline float3 surface_emission(global const idmr_light *lights, uint light_count, uint triangle,
                               float3 d, float3 n)
{
    float3 radiance = (float3)(0.0f);
#if HAS_FEATURE(IDMR_FEATURE_AREA)
    if (dot(d, n) < 0.0f)
        for (uint i = 0; i < light_count; i++)
            if (lights[i].kind == IDMR_LIGHT_AREA && triangle - lights[i].first_triangle <
                                                         lights[i].triangle_count)
                radiance += vload3(0, lights[i].emission);
#endif
    return radiance;
}

/* Radiance arriving from outside the scene (environment lights; zero without them). */
inline float3 environment_radiance(global const idmr_light *lights, uint light_count)
{
    float3 radiance = (float3)(0.0f);
#if HAS_FEATURE(IDMR_FEATURE_ENVIRONMENT)
    for (uint i = 0; i < light_count; i++)
        if (lights[i].kind == IDMR_LIGHT_ENVIRONMENT)
            radiance += vload3(0, lights[i].emission);
#endif
    return radiance;
}

kernel void render_camera(idmr_sppm_params params, idmr_camera camera,
                          global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,
                          global const float4 *triangle_normals,
                          global const uint *triangle_materials,
                          global const idmr_material *materials, global const idmr_light *lights,
                          global idmr_hit_point *hit_points, global idmr_render_hit *render_hits)
{
    uint pixel = get_global_id(0);
    if (pixel >= params.width * params.height)
        return;
    idmr_rng rng = idmr_rng_init(params.seed, params.iteration, IDMR_PASS_RENDER_CAMERA, pixel);
    camera.width = params.width; /* the film may be scaled (--resolution) */
    camera.height = params.height;
    float3 origin = vload3(0, camera.origin);
    float3 d = camera_direction(&camera, pixel % params.width, pixel / params.width, &rng);
    float3 throughput = (float3)(1.0f), radiance = (float3)(0.0f);
    idmr_hit_point hp;
    hp.valid = 0u;
    hp.pixel = pixel;
    idmr_render_hit rh; /* zero where there is no hit point */
    vstore3((float3)(0.0f), 0, rh.throughput);
    vstore3((float3)(0.0f), 0, rh.outgoing);
    rh.material = 0u;
    rh.pad = 0.0f;
    rh.pad2 = 0.0f;
    for (int depth = 0; depth < IDMR_CAMERA_DEPTH; depth++) {
        idmr_hit hit = traverse_closest(nodes, leaves, origin, d, 0.0f, INFINITY);
        if (hit.triangle == IDMR_NO_HIT) {
            radiance += throughput * environment_radiance(lights, params.light_count);
            break;
        }
        float3 n = triangle_normals[hit.triangle].xyz;
        float3 p = origin + hit.t * d;
        radiance += throughput * surface_emission(lights, params.light_count, hit.triangle, d, n);
        global const idmr_material *m = materials + triangle_materials[hit.triangle];
        if (!side_reflects(m, d, n))
            break;
        float3 n_side = dot(d, n) < 0.0f ? n : -n;
        if (!material_is_specular(m)) {
            vstore3(p, 0, hp.position);
            vstore3(n_side, 0, hp.normal);
            hp.valid = 1u;
            vstore3(throughput, 0, rh.throughput);
            rh.material = triangle_materials[hit.triangle];
            vstore3(-d, 0, rh.outgoing);
            break;
        }
#if HAS_FEATURE(IDMR_FEATURES_SPECULAR)
        if (m->kind == IDMR_MATERIAL_MIRROR)
            throughput *= vload3(0, m->specular);
        d = scatter_specular(m, d, n, &rng);
        origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, params.ray_epsilon);
#endif
    }
    hit_points[pixel] = hp;
    vstore3(radiance, 0, rh.emitted);
    render_hits[pixel] = rh;
}

kernel void render_photon(idmr_sppm_params params, global const idmr_light *lights,
                          global const float *light_cdf, global const float *emitter_cdf,
                          global const float4 *emitter_triangles,
                          global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,
                          global const float4 *triangle_normals,
                          global const uint *triangle_materials,
                          global const idmr_material *materials,
                          global idmr_render_photon *photons, global uint *path_length)
{
    uint path = get_global_id(0);
    if (path >= params.path_count)
        return;
    idmr_rng rng = idmr_rng_init(params.seed, params.iteration, IDMR_PASS_RENDER_PHOTON, path);
    float3 origin, d;
    uint stored = 0, light_index;
    if (emit(lights, light_cdf, params.light_count, emitter_cdf, emitter_triangles,
             vload3(0, params.scene_center), params.scene_radius, params.ray_epsilon, &rng,
             &origin, &d, &light_index)) {
        global const idmr_light *light = lights + light_index;
        float probability = light_cdf[light_index] - (light_index ? light_cdf[light_index - 1] : 0.0f);
        float3 flux = vload3(0, light->emission) *
                      (idmr_light_sample_factor(light->kind, light->area, light->cos_cutoff,
                                                params.scene_radius) /
                       (probability * (float)params.path_count));
        global idmr_render_photon *slot = photons + (size_t)path * IDMR_PATH_VERTICES;
        for (int bounce = 0; bounce < IDMR_PHOTON_BOUNCES && stored < IDMR_PATH_VERTICES;
             bounce++) {
            idmr_hit hit = traverse_closest(nodes, leaves, origin, d, 0.0f, INFINITY);
            if (hit.triangle == IDMR_NO_HIT)
                break;
            float3 n = triangle_normals[hit.triangle].xyz;
            float3 p = origin + hit.t * d;
            float3 n_side = dot(d, n) < 0.0f ? n : -n;
            global const idmr_material *m = materials + triangle_materials[hit.triangle];
            if (!material_is_specular(m) && side_reflects(m, d, n)) {
                idmr_render_photon photon;
                vstore3(p, 0, photon.position);
                vstore3(d, 0, photon.direction);
                vstore3(n_side, 0, photon.normal);
                photon.flux_r = flux.x;
                photon.flux_g = flux.y;
                photon.flux_b = flux.z;
                slot[stored++] = photon;
            }
            float3 weight;
            if (scatter(m, &d, n, &rng, &weight) == SCATTER_ABSORBED)
                break;
            flux *= weight;
            origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, params.ray_epsilon);
        }
    }
    path_length[path] = stored;
}

/* round(c × scale) as fixed-point units, for a contribution c >= 0; clamped to
 * IDMR_RENDER_CONTRIBUTION_LIMIT, and 0 for NaN. */
inline ulong radiance_units(float c, float scale)
{
    float units = c * scale;
    return units > 0.0f ? (ulong)(fmin(units, IDMR_RENDER_CONTRIBUTION_LIMIT) + 0.5f) : 0ul;
}

kernel void render_gather(idmr_sppm_params params, global const idmr_render_photon *photons,
                          global const uint *path_length, global const idmr_hit_point *hit_points,
                          global const idmr_render_hit *render_hits,
                          global const idmr_material *materials, global const uint *cell_start,
                          global const uint *grid_points,
                          volatile global fixed_word *pixel_radiance)
{
    uint slot = get_global_id(0);
    if (slot >= params.path_count * IDMR_PATH_VERTICES ||
        slot % IDMR_PATH_VERTICES >= path_length[slot / IDMR_PATH_VERTICES])
        return;
    global const idmr_render_photon *photon = photons + slot;
    float3 p = vload3(0, photon->position), side = vload3(0, photon->normal);
    float3 incoming = vload3(0, photon->direction);
    float3 flux = (float3)(photon->flux_r, photon->flux_g, photon->flux_b);
    float r2 = params.radius * params.radius;
    uint buckets[8];
    uint bucket_count = grid_buckets_near(p, &params, buckets);
    for (uint b = 0; b < bucket_count; b++)
        for (uint i = cell_start[buckets[b]]; i < cell_start[buckets[b] + 1]; i++) {
            uint index = grid_points[i];
            global const idmr_hit_point *hp = hit_points + index;
            float3 delta = vload3(0, hp->position) - p;
            float3 normal = vload3(0, hp->normal);
            if (!(dot(delta, delta) < r2 && dot(normal, side) > 1e-3f))
                continue;
            global const idmr_render_hit *rh = render_hits + index;
            float3 c = vload3(0, rh->throughput) * flux *
                       brdf(materials + rh->material, incoming, vload3(0, rh->outgoing), normal);
            fixed_add(pixel_radiance, 3 * hp->pixel, radiance_units(c.x, params.fixed_scale));
            fixed_add(pixel_radiance, 3 * hp->pixel + 1, radiance_units(c.y, params.fixed_scale));
            fixed_add(pixel_radiance, 3 * hp->pixel + 2, radiance_units(c.z, params.fixed_scale));
        }
}
