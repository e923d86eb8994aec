/* paths.h — the one camera path and the one photon path of the SPPM core, shared by both passes
 * (kernels/sppm.cl). The pass the program is built for (IDMR_SPPM_PASS, features.h) decides
 * what a path records on its way; where the two differ it is marked with #if:
 *
 *   camera path   one per pixel, jittered within it, through mirrors and dielectrics (Fresnel
 *                 chooses reflection or refraction) to the first non-specular surface, where it
 *                 leaves a hit point; at most params->camera_depth surface interactions.
 *     importance  adds the Eq. 2 weight 1 - |n·d| of every surface it hits to that triangle's
 *                 camera importance (unless IDMR_CAMERA_IMPORTANCE or IDMR_ACCUMULATE_IMPORTANCE
 *                 is 0);
 *                 where it reaches an emitter (an area light's front, the environment) through
 *                 mirrors and dielectrics, it adds Eq. 2 weight × the luminance it sees there
 *                 (the emission × the mirrors' colours) to the seen-light sum of every specular
 *                 triangle on the way, the first IDMR_SEEN_LIGHT_CHAIN of them: the light a
 *                 camera sees in a glint or through glass, which no photon gather records
 *                 (importance.h turns it into gathers); both only where params->camera_sums
 *                 (the first device of a run: the others' camera paths leave hit points only);
 *                 each times the pixel's weight (pixel_weight: 1 unless the pass is weighted)
 *     render      carries the specular throughput (a mirror's colour), adds the emission it
 *                 sees (an area light's front, the environment once it leaves the scene) and
 *                 ends at the back of a one-sided surface (black, no hit point); from
 *                 IDMR_CAMERA_RR_DEPTH interactions on, Russian roulette continues it with
 *                 probability min(0.95, largest throughput channel), dividing by it, so that
 *                 deep glass costs little and stays unbiased up to camera_depth
 *   photon path   one per work-item, emitted by a light chosen in proportion to power, scattered
 *                 with Russian roulette at every surface (materials.h), at most
 *                 IDMR_PHOTON_BOUNCES interactions and IDMR_PATH_VERTICES records, each
 *                 appended to the dense list of records where an atomic add puts it, its place
 *                 noted in the path's slot of record_index (path p's record j at
 *                 records[record_index[p * IDMR_PATH_VERTICES + j]]).
 *     importance  records a vertex (triangle, side normal, Eq. 2 weight) at every surface,
 *                 specular ones too; paths carry no flux
 *     render      records a photon (flux, direction, side normal) at every non-specular surface
 *                 on a side that reflects; flux is multiplied by each scattering weight
 *
 * Importance per instance (INSTANCE_TOTALS: the importance pass on an instanced scene): every
 * amount added to a triangle's word (importance_add) is added to the total of the instance the
 * path met the triangle on as well, so that each copy of a prototype keeps its own total and the
 * copies' totals add up to the prototype's triangles' sums (idmr/importance_layout.h). Photon
 * vertices carry their instance in a side array parallel to the records (the path_record_list's
 * `instances`), which keeps idmr_photon_vertex 32 bytes; a flat scene's program has neither. */
#ifndef IDMR_KERNEL_PATHS_H
#define IDMR_KERNEL_PATHS_H

#include "idmr/camera.h"
#include "idmr/importance_layout.h"
#include "idmr/render_layout.h"
#include "idmr/weight.h"
#include "lib/features.h"
#include "lib/fixed_point.h"
#include "lib/lights.h"
#include "lib/materials.h"
#include "lib/scene.h"
#include "lib/shading.h"
#include "lib/surface.h"

#ifndef IDMR_SPPM_PASS
#error "paths.h is for the SPPM kernels: IDMR_SPPM_PASS must be defined"
#endif
#ifndef IDMR_ACCUMULATE_IMPORTANCE
#define IDMR_ACCUMULATE_IMPORTANCE 1 /* 0: the importance accumulation compiled out (make bench) */
#endif
#ifndef IDMR_CAMERA_IMPORTANCE
#define IDMR_CAMERA_IMPORTANCE 1 /* 0 when γ = 0: camera importance would be multiplied by 0 */
#endif
#define INSTANCE_TOTALS (PASS_IMPORTANCE && HAS_FEATURE(IDMR_FEATURE_INSTANCES))

/* What a pass's paths record into: camera_records, the camera paths' buffer (importance: camera
 * importance per triangle; render: one record per pixel), and photon_record, a photon path's
 * record. */
#if PASS_IMPORTANCE
#define CAMERA_STREAM IDMR_STREAM_IMPORTANCE_CAMERA
#define PHOTON_STREAM IDMR_STREAM_IMPORTANCE_PHOTON
typedef volatile global fixed_word *camera_records;
typedef idmr_photon_vertex photon_record;
#define IDMR_SEEN_LIGHT_CHAIN 16 /* specular triangles credited with the light a path sees */
#else
#define CAMERA_STREAM IDMR_STREAM_RENDER_CAMERA
#define PHOTON_STREAM IDMR_STREAM_RENDER_PHOTON
typedef global idmr_render_hit *camera_records;
typedef idmr_render_photon photon_record;
#endif

/* Fixed-point units of an Eq. 2 weight (idmr/importance_layout.h). */
inline ulong weight_units(float weight)
{
    return (ulong)(weight * IDMR_FIXED_SCALE + 0.5f);
}

/* The unit direction of the camera ray through pixel `pixel` of the params' hit-point image,
 * jittered within the pixel (x jitter, then y jitter, from the path's stream). The film may be
 * scaled (--resolution): rays follow the scene camera's frame at the params' size. */
inline float3 camera_ray(idmr_camera camera, const idmr_sppm_params *params, uint pixel,
                         idmr_rng *rng)
{
    camera.width = params->width;
    camera.height = params->height;
    float film_x = (float)(pixel % params->width) + idmr_rng_float(rng);
    float film_y = (float)(pixel / params->width) + idmr_rng_float(rng);
    float d[3];
    idmr_camera_direction(&camera, film_x, film_y, d);
    return normalize(vload3(0, d));
}

#if PASS_IMPORTANCE
/* Adds `units` to the word of scene triangle `triangle` and, with INSTANCE_TOTALS, to the total
 * of `instance`, the instance the path met the triangle on: word params->triangle_count +
 * instance of the same accumulator (idmr/importance_layout.h). */
inline void importance_add(volatile global fixed_word *words, const idmr_sppm_params *params,
                           uint triangle, uint instance, ulong units)
{
    fixed_add(words, triangle, units);
#if INSTANCE_TOTALS
    fixed_add(words, params->triangle_count + instance, units);
#endif
}

/* The specular triangles a camera path has passed (the first IDMR_SEEN_LIGHT_CHAIN), their
 * Eq. 2 weights (and with INSTANCE_TOTALS the instances they were met on), and the mirrors'
 * colour so far. */
typedef struct specular_chain {
    uint triangles[IDMR_SEEN_LIGHT_CHAIN];
    float weights[IDMR_SEEN_LIGHT_CHAIN];
#if INSTANCE_TOTALS
    uint instances[IDMR_SEEN_LIGHT_CHAIN];
#endif
    uint length;
    float3 colour;
} specular_chain;

/* The instance chain entry k was met on (0 in a flat scene, where it is not kept). */
inline uint chain_instance(const specular_chain *chain, uint k)
{
#if INSTANCE_TOTALS
    return chain->instances[k];
#else
    return 0u;
#endif
}

/* Adds weight × the luminance of `emitted` (× the chain's colour) to the seen-light sum of every
 * triangle of the chain, in params->fixed_scale units per unit of luminance, times the pixel's
 * weight (1 unless the pass is pixel-weighted). */
inline void credit_seen_light(const idmr_sppm_params *params, const specular_chain *chain,
                              float3 emitted, volatile global fixed_word *seen_light,
                              uint pixel_weight)
{
    if (!params->camera_sums)
        return; /* another device counts them */
    float3 seen = chain->colour * emitted;
    float units = idmr_luminance(seen.x, seen.y, seen.z) * params->fixed_scale;
    if (!(units > 0.0f))
        return;
    for (uint k = 0; k < chain->length; k++)
        importance_add(seen_light, params, chain->triangles[k], chain_instance(chain, k),
                       (ulong)(chain->weights[k] * units + 0.5f) * pixel_weight);
}

/* The weight of pixel `pixel`'s hit point (passes/importance.h: pixel weights): what its camera
 * importance, seen light and shadow ray are multiplied by, and what it counts for in a photon
 * vertex's gather count. 1 unless params->pixel_weighted (then bit for bit today's pass). */
inline uint pixel_weight(const idmr_sppm_params *params, global const uint *pixel_weights,
                         uint pixel)
{
    return params->pixel_weighted ? pixel_weights[pixel] : 1u;
}
#define SEEN_LIGHT_PARAMETER , volatile global fixed_word *seen_light, uint pixel_weight
#else
#define SEEN_LIGHT_PARAMETER
#endif

/* Traces pixel `pixel`'s camera path and writes its hit point and what the pass records. */
inline void camera_path(const scene_view *scene, const idmr_sppm_params *params,
                        idmr_camera camera, uint pixel, global idmr_hit_point *hit_points,
                        camera_records records SEEN_LIGHT_PARAMETER)
{
    idmr_rng rng = idmr_rng_init(params->seed, params->iteration, CAMERA_STREAM, pixel);
    float3 origin = vload3(0, camera.origin);
    float3 d = camera_ray(camera, params, pixel, &rng);
    idmr_hit_point hp = {{0.0f, 0.0f, 0.0f}, pixel, {0.0f, 0.0f, 0.0f}, 0.0f}; /* none yet */
#if PASS_IMPORTANCE && IDMR_ACCUMULATE_IMPORTANCE
    specular_chain chain;
    chain.length = 0;
    chain.colour = (float3)(1.0f);
#endif
#if PASS_RENDER
    float3 throughput = (float3)(1.0f), radiance = (float3)(0.0f);
    idmr_render_hit rh = {{0.0f, 0.0f, 0.0f}, 0u, {0.0f, 0.0f, 0.0f}, 0u,
                          {0.0f, 0.0f, 0.0f}, 0.0f}; /* zero where there is no hit point */
#endif
    for (uint depth = 0; depth < params->camera_depth; depth++) {
        surface found = trace_surface(scene, origin, d, INFINITY);
        idmr_hit hit = found.hit;
        if (hit.triangle == IDMR_NO_HIT) {
#if PASS_RENDER
            radiance += throughput * environment_radiance(scene, d);
#elif IDMR_ACCUMULATE_IMPORTANCE
            if (chain.length > 0)
                credit_seen_light(params, &chain, environment_radiance(scene, d), seen_light,
                                  pixel_weight);
#endif
            break;
        }
        float3 n = found.normal, ns = found.shading, p = found.position;
        float offset = found.offset;
        global const idmr_material *m = triangle_material(scene, hit.triangle);
#if PASS_IMPORTANCE && IDMR_ACCUMULATE_IMPORTANCE && IDMR_CAMERA_IMPORTANCE
        if (params->camera_sums)
            importance_add(records, params, hit.triangle, found.instance,
                           weight_units(idmr_eq2_weight(n.x, n.y, n.z, d.x, d.y, d.z)) *
                               pixel_weight);
#endif
#if PASS_RENDER
        radiance += throughput * surface_emission(scene, params->light_count, hit.triangle, d, n);
        if (!side_reflects(m, d, n))
            break;
#elif IDMR_ACCUMULATE_IMPORTANCE
        if (chain.length > 0)
            credit_seen_light(params, &chain,
                              surface_emission(scene, params->light_count, hit.triangle, d, n),
                              seen_light, pixel_weight);
#endif
        float3 n_side = dot(d, n) < 0.0f ? n : -n;
        if (!material_is_specular(m)) {
            vstore3(p, 0, hp.position);
            vstore3(n_side, 0, hp.normal);
            hp.offset = offset;
#if PASS_RENDER
            vstore3(throughput, 0, rh.throughput);
            rh.material = scene->triangle_materials[hit.triangle];
            float3 ns_side = dot(d, n) < 0.0f ? ns : -ns;
            rh.shading_normal = idmr_pack_unit_vector(ns_side.x, ns_side.y, ns_side.z);
            vstore3(-d, 0, rh.outgoing);
#endif
            break;
        }
#if HAS_FEATURE(IDMR_FEATURES_SPECULAR)
#if PASS_IMPORTANCE && IDMR_ACCUMULATE_IMPORTANCE
        if (chain.length < IDMR_SEEN_LIGHT_CHAIN) {
            chain.triangles[chain.length] = hit.triangle;
#if INSTANCE_TOTALS
            chain.instances[chain.length] = found.instance;
#endif
            chain.weights[chain.length++] = idmr_eq2_weight(n.x, n.y, n.z, d.x, d.y, d.z);
        }
        if (m->kind == IDMR_MATERIAL_MIRROR)
            chain.colour *= vload3(0, m->specular);
#endif
#if PASS_RENDER
        if (m->kind == IDMR_MATERIAL_MIRROR)
            throughput *= vload3(0, m->specular);
        if (depth + 1 >= IDMR_CAMERA_RR_DEPTH) {
            float survive = fmin(0.95f, fmax(throughput.x, fmax(throughput.y, throughput.z)));
            if (idmr_rng_float(&rng) >= survive)
                break;
            throughput /= survive;
        }
#endif
        d = scatter_specular(m, d, n, ns, &rng);
        origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, offset);
#endif
    }
    hit_points[pixel] = hp;
#if PASS_RENDER
    vstore3(radiance, 0, rh.emitted);
    records[pixel] = rh;
#endif
}

/* Where a photon path's records go: the dense list of all paths' records, its length, and the
 * path's slot of record_index (idmr/sppm_layout.h); with INSTANCE_TOTALS, the list's instances
 * (above). */
typedef struct path_record_list {
    global photon_record *records;
    volatile global uint *count;
    global uint *index; /* IDMR_PATH_VERTICES entries */
#if INSTANCE_TOTALS
    global uint *instances; /* per record of the list, in its order: the instance it is on */
#endif
} path_record_list;

/* Appends record r as the path's record `j`; returns its place in the list. */
inline uint append_record(path_record_list list, uint j, photon_record r)
{
    uint at = atomic_inc(list.count);
    list.records[at] = r;
    list.index[j] = at;
    return at;
}

/* Traces photon path `path` into the list; returns how many records it stored. */
inline uint photon_path(const scene_view *scene, const idmr_sppm_params *params, uint path,
                        path_record_list list)
{
    idmr_rng rng = idmr_rng_init(params->seed, params->iteration, PHOTON_STREAM, path);
    float3 origin, d, emitted;
    uint light_index;
    if (!emit(scene, params, &rng, &origin, &d, &light_index, &emitted))
        return 0;
#if PASS_RENDER
    float3 flux = photon_initial_flux(scene, params, light_index, emitted);
#endif
    uint stored = 0;
    for (int bounce = 0; bounce < IDMR_PHOTON_BOUNCES && stored < IDMR_PATH_VERTICES; bounce++) {
        surface found = trace_surface(scene, origin, d, INFINITY);
        idmr_hit hit = found.hit;
        if (hit.triangle == IDMR_NO_HIT)
            break;
        float3 n = found.normal, ns = found.shading, p = found.position;
        float offset = found.offset;
        float3 n_side = dot(d, n) < 0.0f ? n : -n;
        global const idmr_material *m = triangle_material(scene, hit.triangle);
#if PASS_IMPORTANCE
        idmr_photon_vertex v;
        vstore3(p, 0, v.position);
        v.triangle = hit.triangle;
        vstore3(n_side, 0, v.normal);
        v.weight = idmr_eq2_weight(n.x, n.y, n.z, d.x, d.y, d.z);
#if INSTANCE_TOTALS
        list.instances[append_record(list, stored++, v)] = found.instance;
#else
        append_record(list, stored++, v);
#endif
#else
        if (!material_is_specular(m) && side_reflects(m, d, n)) {
            idmr_render_photon photon;
            vstore3(p, 0, photon.position);
            vstore3(d, 0, photon.direction);
            vstore3(n_side, 0, photon.normal);
            photon.flux_r = flux.x;
            photon.flux_g = flux.y;
            photon.flux_b = flux.z;
            append_record(list, stored++, photon);
        }
#endif
        float3 weight;
        if (scatter(m, &d, n, ns, &rng, &weight) == SCATTER_ABSORBED)
            break;
#if PASS_RENDER
        flux *= weight;
#endif
        origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, offset);
    }
    return stored;
}

#endif
