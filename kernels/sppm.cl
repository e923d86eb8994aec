/* sppm.cl — the kernels of one iteration of the SPPM core (host/passes/sppm.c), built for one
 * pass (IDMR_SPPM_PASS, lib/features.h). Entry points only: the work is in lib/.
 *
 *   camera_paths      one camera path per pixel (lib/paths.h): hit points, and what the pass
 *                     records (importance: camera importance, then the light seen through
 *                     specular surfaces; render: throughput and emission)
 *   photon_paths      one photon path per work-item (lib/paths.h), its records appended to
 *                     the dense list of records and their places noted in the path's slot of
 *                     record_index; work-item i traces path params.path_first + i (several
 *                     devices: each its range, host/passes/sppm.h) into slot i
 *   grid_count, scan_chunks, scan_chunk_sums, scan_apply, grid_scatter
 *                     the hash grid over the hit points by counting sort (lib/hit_point_grid.h)
 * importance pass (paper 3.2, 3.3, 4.1; host/passes/importance.c):
 *   gather_count      per photon vertex of the dense list: the hit points that gather it
 *                     (each counting its pixel's weight where the pass is pixel-weighted)
 *   path_importance   per path, from its last vertex back: running sum s of gather counts;
 *                     vertex j adds weight_j × s to its triangle's light importance
 *                     (an instanced scene: to its instance's total too, lib/paths.h)
 *   shadow_rays       per hit point, one shadow ray: its occluder gets shadow importance
 *                     (lib/shadows.h; built with IDMR_SHADOW_IMPORTANCE=1)
 *   pixel_centre_hits the triangle seen through each pixel centre (the importance image)
 * render pass (host/passes/render.c):
 *   render_gather     per photon of the dense list: every hit point that gathers it gets
 *                     throughput × BRDF × flux, added in fixed point to its pixel
 *
 * Argument order: params first, then (for path kernels) the camera and SCENE_BUFFERS
 * (lib/scene.h), then the core's buffers, then the pass's; host/passes/sppm.c binds them. */
#pragma OPENCL FP_CONTRACT OFF
#include "lib/hit_point_grid.h"
#include "lib/paths.h"
#include "lib/shadows.h"

#ifndef IDMR_SHADOW_IMPORTANCE
#define IDMR_SHADOW_IMPORTANCE 0 /* 1: the importance pass casts shadow rays */
#endif

#if PASS_IMPORTANCE
#define CAMERA_PASS_PARAMETERS                                                                  \
    , volatile global fixed_word *seen_light, global const uint *pixel_weights
#define SEEN_LIGHT_ARGUMENT , seen_light, pixel_weight(&params, pixel_weights, pixel)
#else
#define CAMERA_PASS_PARAMETERS
#define SEEN_LIGHT_ARGUMENT
#endif

/* With INSTANCE_TOTALS (lib/paths.h) photon_paths writes each record's instance to a side array
 * parallel to the records, and path_importance reads it. */
#if INSTANCE_TOTALS
#define PHOTON_PASS_PARAMETERS , global uint *record_instances
#define RECORD_INSTANCES , record_instances
#else
#define PHOTON_PASS_PARAMETERS
#define RECORD_INSTANCES
#endif

kernel void camera_paths(idmr_sppm_params params, idmr_camera camera, SCENE_BUFFERS,
                         global idmr_hit_point *hit_points,
                         camera_records records CAMERA_PASS_PARAMETERS)
{
    uint pixel = get_global_id(0);
    if (pixel >= params.width * params.height)
        return;
    scene_view scene = SCENE_VIEW();
    camera_path(&scene, &params, camera, pixel, hit_points, records SEEN_LIGHT_ARGUMENT);
}

/* The records of all paths, one after the other (stored_count of them), so that the gathers
 * take one work-item per record and read the records in a row: a fixed slot of
 * IDMR_PATH_VERTICES records per path, about 1.7 of them used, left a gather reading one cache
 * line per record from memory. A record goes where an atomic add puts it, so the list's order
 * changes from run to run; what the gathers add per record does not depend on it, and their
 * sums are integers, so results stay the same bit for bit. */
kernel void photon_paths(idmr_sppm_params params, SCENE_BUFFERS, global uint *path_length,
                         global photon_record *records, volatile global uint *stored_count,
                         global uint *record_index PHOTON_PASS_PARAMETERS)
{
    uint slot = get_global_id(0); /* this device's path slot: path path_first + slot */
    if (slot >= params.device_paths)
        return;
    scene_view scene = SCENE_VIEW();
    path_record_list list = {records, stored_count,
                             record_index + (size_t)slot * IDMR_PATH_VERTICES RECORD_INSTANCES};
    path_length[slot] = photon_path(&scene, &params, params.path_first + slot, list);
}

kernel void grid_count(idmr_sppm_params params, global const idmr_hit_point *hit_points,
                       volatile global uint *cell_counts)
{
    uint i = get_global_id(0);
    if (i < params.width * params.height && hit_points[i].offset > 0.0f)
        atomic_inc(cell_counts + grid_bucket(hit_points + i, &params));
}

/* cell_start = prefix sums of the cell counts in three steps: the sum of each chunk of
 * IDMR_SCAN_CHUNK cells, an exclusive scan of those sums, then each chunk scanned from its
 * offset (cell_start[cell_count] = all hit points; cell_cursor a copy, for grid_scatter). */
kernel void scan_chunks(global const uint *cell_counts, uint cell_count, global uint *chunk_sums)
{
    uint begin, end, sum = 0;
    if (!scan_chunk_cells(get_global_id(0), cell_count, &begin, &end))
        return;
    for (uint i = begin; i < end; i++)
        sum += cell_counts[i];
    chunk_sums[get_global_id(0)] = sum;
}

kernel void scan_chunk_sums(global uint *chunk_sums, uint chunk_count)
{
    if (get_global_id(0) == 0)
        exclusive_scan(chunk_sums, chunk_count);
}

kernel void scan_apply(global const uint *cell_counts, uint cell_count,
                       global const uint *chunk_offsets, global uint *cell_start,
                       global uint *cell_cursor)
{
    uint begin, end;
    if (!scan_chunk_cells(get_global_id(0), cell_count, &begin, &end))
        return;
    uint running = chunk_offsets[get_global_id(0)];
    for (uint i = begin; i < end; i++) {
        cell_start[i] = running;
        cell_cursor[i] = running;
        running += cell_counts[i];
    }
    if (end == cell_count)
        cell_start[cell_count] = running;
}

kernel void grid_scatter(idmr_sppm_params params, global const idmr_hit_point *hit_points,
                         volatile global uint *cell_cursor, global idmr_hit_point *grid_hits)
{
    uint i = get_global_id(0);
    if (i < params.width * params.height && hit_points[i].offset > 0.0f)
        grid_hits[atomic_inc(cell_cursor + grid_bucket(hit_points + i, &params))] = hit_points[i];
}

#if PASS_IMPORTANCE

/* gathered[v] for each record v of the list: each hit point that gathers it counts its pixel's
 * weight (1 unless the pass is pixel-weighted). */
kernel void gather_count(idmr_sppm_params params, global const idmr_photon_vertex *vertices,
                         global const uint *stored_count, global const uint *cell_start,
                         global const idmr_hit_point *grid_hits, global uint *gathered,
                         global const uint *pixel_weights)
{
    uint v = get_global_id(0), count = 0;
    if (v >= *stored_count)
        return;
    float3 p = vload3(0, vertices[v].position), side = vload3(0, vertices[v].normal);
    float r2 = params.radius * params.radius;
    uint buckets[8];
    uint bucket_count = grid_buckets_near(p, &params, buckets);
    for (uint b = 0; b < bucket_count; b++)
        for (uint i = cell_start[buckets[b]]; i < cell_start[buckets[b] + 1]; i++)
            count += (uint)hit_point_gathers(grid_hits + i, p, side, r2) *
                     pixel_weight(&params, pixel_weights, grid_hits[i].pixel);
    gathered[v] = count;
}

kernel void path_importance(idmr_sppm_params params, global const idmr_photon_vertex *vertices,
                            global const uint *path_length, global const uint *record_index,
                            global const uint *gathered,
                            volatile global fixed_word *light_importance PHOTON_PASS_PARAMETERS)
{
    uint path = get_global_id(0); /* this device's path slot */
    if (path >= params.device_paths)
        return;
    global const uint *index = record_index + (size_t)path * IDMR_PATH_VERTICES;
    ulong running = 0;
    for (int j = (int)path_length[path] - 1; j >= 0; j--) {
        uint v = index[j];
        running += gathered[v];
#if INSTANCE_TOTALS
        uint instance = record_instances[v];
#else
        uint instance = 0u;
#endif
        if (running != 0ul)
            importance_add(light_importance, &params, vertices[v].triangle, instance,
                           weight_units(vertices[v].weight) * running);
    }
}

#if IDMR_SHADOW_IMPORTANCE
kernel void shadow_rays(idmr_sppm_params params, idmr_camera camera, SCENE_BUFFERS,
                        global const idmr_hit_point *hit_points,
                        volatile global fixed_word *shadow_importance,
                        global const uint *pixel_weights)
{
    uint pixel = get_global_id(0);
    if (pixel >= params.width * params.height || !(hit_points[pixel].offset > 0.0f))
        return;
    scene_view scene = SCENE_VIEW();
    idmr_rng rng =
        idmr_rng_init(params.seed, params.iteration, IDMR_STREAM_IMPORTANCE_SHADOW, pixel);
    camera.width = params.width;
    uint occluder, instance;
    float weight = shadow_occluder_weight(&scene, &params, &camera, hit_points + pixel, &rng,
                                          &occluder, &instance);
    if (weight > 0.0f)
        importance_add(shadow_importance, &params, occluder, instance,
                       weight_units(weight) * pixel_weight(&params, pixel_weights, pixel));
}
#endif

kernel void pixel_centre_hits(idmr_sppm_params params, idmr_camera camera, SCENE_BUFFERS,
                              global uint *triangles)
{
    uint pixel = get_global_id(0);
    if (pixel >= params.width * params.height)
        return;
    camera.width = params.width;
    camera.height = params.height;
    float d[3];
    idmr_camera_direction(&camera, (float)(pixel % params.width) + 0.5f,
                          (float)(pixel / params.width) + 0.5f, d);
    scene_view scene = SCENE_VIEW();
    triangles[pixel] =
        trace_surface(&scene, vload3(0, camera.origin), vload3(0, d), INFINITY).hit.triangle;
}

#else

/* round(c × scale) as fixed-point units, for a contribution c >= 0; clamped to
 * IDMR_RENDER_CONTRIBUTION_LIMIT, and 0 for NaN. */
inline ulong radiance_units(float c, float scale)
{
    float units = c * scale;
    return units > 0.0f ? (ulong)(fmin(units, IDMR_RENDER_CONTRIBUTION_LIMIT) + 0.5f) : 0ul;
}

kernel void render_gather(idmr_sppm_params params, global const idmr_render_photon *photons,
                          global const uint *stored_count,
                          global const idmr_render_hit *render_hits,
                          global const idmr_material *materials, global const uint *cell_start,
                          global const idmr_hit_point *grid_hits,
                          volatile global fixed_word *pixel_radiance)
{
    if (get_global_id(0) >= *stored_count)
        return;
    global const idmr_render_photon *photon = photons + get_global_id(0);
    float3 p = vload3(0, photon->position), side = vload3(0, photon->normal);
    float3 incoming = vload3(0, photon->direction);
    float3 flux = (float3)(photon->flux_r, photon->flux_g, photon->flux_b);
    float r2 = params.radius * params.radius;
    uint buckets[8];
    uint bucket_count = grid_buckets_near(p, &params, buckets);
    for (uint b = 0; b < bucket_count; b++)
        for (uint i = cell_start[buckets[b]]; i < cell_start[buckets[b] + 1]; i++) {
            global const idmr_hit_point *hp = grid_hits + i;
            if (!hit_point_gathers(hp, p, side, r2))
                continue;
            global const idmr_render_hit *rh = render_hits + hp->pixel;
            float3 ns = unpack_normal(rh->shading_normal);
            float3 c = vload3(0, rh->throughput) * flux *
                       brdf(materials + rh->material, incoming, vload3(0, rh->outgoing), ns) *
                       shading_correction(incoming, ns, vload3(0, hp->normal));
            fixed_add(pixel_radiance, 3 * hp->pixel, radiance_units(c.x, params.fixed_scale));
            fixed_add(pixel_radiance, 3 * hp->pixel + 1, radiance_units(c.y, params.fixed_scale));
            fixed_add(pixel_radiance, 3 * hp->pixel + 2, radiance_units(c.z, params.fixed_scale));
        }
}

#endif
