/* importance.cl — one iteration of the importance pass (paper sections 3.2, 3.3, 4.1).
 *
 *   camera_pass      one path per pixel: Eq. 2 weight into camera importance at every surface
 *                    hit, through mirrors and dielectrics, until the first non-specular surface,
 *                    where it leaves a hit point
 *   photon_pass      one path per work-item: a vertex at every surface interaction, in the
 *                    path's fixed slot of IDMR_PATH_VERTICES
 *   grid_count, scan_chunks, scan_chunk_sums, scan_apply, grid_scatter
 *                    a hash grid over the hit points by counting sort (hit_point_grid.h)
 *   gather_count     per photon vertex: hit points within the radius, on the same side
 *   path_importance  per path, from its last vertex back: running sum s of gather counts;
 *                    vertex j adds weight_j * s to its triangle's light importance
 *
 * Build options (host/device.c, host/importance.c): IDMR_FEATURES, IDMR_INT64_ATOMICS,
 * IDMR_BOOKKEEPING (0 compiles the importance accumulation out: the "plain" variant that
 * `make bench` compares against) and IDMR_CAMERA_IMPORTANCE (0 when γ = 0: camera importance
 * would be multiplied by zero, so its atomics are compiled out). Layouts: idmr/importance.h. */
#include "idmr/camera.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "lib/fixed_point.h"
#include "lib/hit_point_grid.h"
#include "lib/scene.h"
#include "lib/traverse.h"

#ifndef IDMR_BOOKKEEPING
#define IDMR_BOOKKEEPING 1
#endif
#ifndef IDMR_CAMERA_IMPORTANCE
#define IDMR_CAMERA_IMPORTANCE 1
#endif

inline ulong fixed_units(float weight)
{
    return (ulong)(weight * IDMR_FIXED_SCALE + 0.5f);
}

kernel void camera_pass(idmr_sppm_params params, idmr_camera camera,
                        global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,
                        global const float4 *triangle_normals,
                        global const uint *triangle_materials,
                        global const idmr_material *materials, global idmr_hit_point *hit_points,
                        volatile global fixed_word *camera_importance)
{
    uint pixel = get_global_id(0);
    if (pixel >= params.width * params.height)
        return;
    idmr_rng rng = idmr_rng_init(params.seed, params.iteration, IDMR_PASS_CAMERA, pixel);
    /* The film may be scaled (--resolution): rays follow the scene camera's frame. */
    camera.width = params.width;
    camera.height = params.height;
    float3 origin = vload3(0, camera.origin);
    float3 d = camera_direction(&camera, pixel % params.width, pixel / params.width, &rng);
    idmr_hit_point hp;
    hp.valid = 0u;
    hp.pixel = pixel;
    for (int depth = 0; depth < IDMR_CAMERA_DEPTH; depth++) {
        idmr_hit hit = traverse_closest(nodes, leaves, origin, d, 0.0f, INFINITY);
        if (hit.triangle == IDMR_NO_HIT)
            break;
        float4 nw = triangle_normals[hit.triangle];
        float3 n = nw.xyz;
#if IDMR_BOOKKEEPING && IDMR_CAMERA_IMPORTANCE
        fixed_add(camera_importance, hit.triangle,
                  fixed_units(idmr_eq2_weight(n.x, n.y, n.z, d.x, d.y, d.z)));
#endif
        float3 p = origin + hit.t * d;
        global const idmr_material *m = materials + triangle_materials[hit.triangle];
        float3 n_side = dot(d, n) < 0.0f ? n : -n;
        if (!material_is_specular(m)) {
            vstore3(p, 0, hp.position);
            vstore3(n_side, 0, hp.normal);
            hp.valid = 1u;
            break;
        }
#if HAS_FEATURE(IDMR_FEATURES_SPECULAR)
        d = scatter_specular(m, d, n, &rng);
        origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, params.ray_epsilon);
#endif
    }
    hit_points[pixel] = hp;
}

kernel void photon_pass(idmr_sppm_params params, global const idmr_light *lights,
                        global const float *light_cdf, global const float *emitter_cdf,
                        global const float4 *emitter_triangles,
                        global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,
                        global const float4 *triangle_normals,
                        global const uint *triangle_materials,
                        global const idmr_material *materials,
                        global idmr_photon_vertex *vertices, global uint *path_length)
{
    uint path = get_global_id(0);
    if (path >= params.path_count)
        return;
    idmr_rng rng = idmr_rng_init(params.seed, params.iteration, IDMR_PASS_PHOTON, path);
    float3 origin, d;
    uint length = 0, light_index;
    if (emit(lights, light_cdf, params.light_count, emitter_cdf, emitter_triangles,
             vload3(0, params.scene_center), params.scene_radius, params.ray_epsilon, &rng,
             &origin, &d, &light_index)) {
        global idmr_photon_vertex *slot = vertices + (size_t)path * IDMR_PATH_VERTICES;
        while (length < IDMR_PATH_VERTICES) {
            idmr_hit hit = traverse_closest(nodes, leaves, origin, d, 0.0f, INFINITY);
            if (hit.triangle == IDMR_NO_HIT)
                break;
            float3 n = triangle_normals[hit.triangle].xyz;
            float3 p = origin + hit.t * d;
            float3 n_side = dot(d, n) < 0.0f ? n : -n;
            idmr_photon_vertex v;
            vstore3(p, 0, v.position);
            v.triangle = hit.triangle;
            vstore3(n_side, 0, v.normal);
            v.weight = idmr_eq2_weight(n.x, n.y, n.z, d.x, d.y, d.z);
            slot[length++] = v;
            global const idmr_material *m = materials + triangle_materials[hit.triangle];
            float3 unused_weight; /* importance paths carry no flux */
            if (scatter(m, &d, n, &rng, &unused_weight) == SCATTER_ABSORBED)
                break;
            origin = offset_origin(p, dot(d, n_side) > 0.0f ? n_side : -n_side, params.ray_epsilon);
        }
    }
    path_length[path] = length;
}

/* Hit points within the radius of point p whose normal faces the same side as `side` (cosine
 * above 1e-3, so that faces meeting at a right angle never gather each other's hit points on
 * the sign of a rounding error: that made the result depend on the scene's scale). */
inline uint count_hit_points_near(float3 p, float3 side, const idmr_sppm_params *params,
                                  global const idmr_hit_point *hit_points,
                                  global const uint *cell_start, global const uint *grid_points)
{
    float r2 = params->radius * params->radius;
    uint buckets[8];
    uint bucket_count = grid_buckets_near(p, params, buckets);
    uint count = 0;
    for (uint b = 0; b < bucket_count; b++)
        for (uint i = cell_start[buckets[b]]; i < cell_start[buckets[b] + 1]; i++) {
            global const idmr_hit_point *hp = hit_points + grid_points[i];
            float3 delta = vload3(0, hp->position) - p;
            if (dot(delta, delta) < r2 && dot(vload3(0, hp->normal), side) > 1e-3f)
                count++;
        }
    return count;
}

kernel void gather_count(idmr_sppm_params params, global const idmr_photon_vertex *vertices,
                         global const uint *path_length, global const idmr_hit_point *hit_points,
                         global const uint *cell_start, global const uint *grid_points,
                         global uint *gathered)
{
    uint v = get_global_id(0);
    if (v >= params.path_count * IDMR_PATH_VERTICES)
        return;
    uint path = v / IDMR_PATH_VERTICES, j = v % IDMR_PATH_VERTICES;
    if (j >= path_length[path]) {
        gathered[v] = 0u;
        return;
    }
    global const idmr_photon_vertex *vertex = vertices + v;
    gathered[v] = count_hit_points_near(vload3(0, vertex->position), vload3(0, vertex->normal),
                                        &params, hit_points, cell_start, grid_points);
}

kernel void path_importance(idmr_sppm_params params,
                            global const idmr_photon_vertex *vertices,
                            global const uint *path_length, global const uint *gathered,
                            volatile global fixed_word *light_importance)
{
    uint path = get_global_id(0);
    if (path >= params.path_count)
        return;
    uint base = path * IDMR_PATH_VERTICES;
    ulong running = 0;
    for (int j = (int)path_length[path] - 1; j >= 0; j--) {
        running += gathered[base + j];
        if (running != 0ul)
            fixed_add(light_importance, vertices[base + j].triangle,
                      fixed_units(vertices[base + j].weight) * running);
    }
}
