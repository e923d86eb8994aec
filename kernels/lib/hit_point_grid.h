/* hit_point_grid.h — the hash grid over one iteration's hit points, shared by both passes of the
 * SPPM core (kernels/sppm.cl): a counting sort of hit point indices by the hashed cell of their
 * position, and the one test of which hit points a photon reaches.
 *
 *   grid_count       hit points per bucket (cell_counts, cleared by the host)
 *   scan_chunks, scan_chunk_sums, scan_apply
 *                    cell_start = prefix sums of the counts, in three steps
 *   grid_scatter     grid_points: hit point indices sorted by bucket
 * The cell size is at least twice the gather radius (the host sets it), so a ball of that
 * radius touches at most 2 x 2 x 2 cells; grid_buckets_near() lists their buckets once each
 * (two cells may hash to one bucket). Host side: host/passes/hit_point_grid.c. */
#ifndef IDMR_KERNEL_HIT_POINT_GRID_H
#define IDMR_KERNEL_HIT_POINT_GRID_H

#include "idmr/sppm_layout.h"

inline int3 grid_cell(float3 p, const idmr_sppm_params *params)
{
    return convert_int3_rtn((p - vload3(0, params->grid_origin)) / params->cell_size);
}

inline uint grid_hash(int3 c, uint cell_count)
{
    return (((uint)c.x * 73856093u) ^ ((uint)c.y * 19349663u) ^ ((uint)c.z * 83492791u)) &
           (cell_count - 1u);
}

kernel void grid_count(idmr_sppm_params params, global const idmr_hit_point *hit_points,
                       volatile global uint *cell_counts)
{
    uint i = get_global_id(0);
    if (i >= params.width * params.height || !hit_points[i].valid)
        return;
    uint h = grid_hash(grid_cell(vload3(0, hit_points[i].position), &params), params.cell_count);
    atomic_inc(cell_counts + h);
}

/* Prefix sums in three steps: sums of chunks of IDMR_SCAN_CHUNK cells, an exclusive scan of
 * those sums (one work-item: there are few), then each chunk scanned from its offset. */
kernel void scan_chunks(global const uint *cell_counts, uint cell_count, global uint *chunk_sums)
{
    uint chunk = get_global_id(0);
    uint begin = chunk * IDMR_SCAN_CHUNK;
    if (begin >= cell_count)
        return;
    uint end = min(begin + IDMR_SCAN_CHUNK, cell_count);
    uint sum = 0;
    for (uint i = begin; i < end; i++)
        sum += cell_counts[i];
    chunk_sums[chunk] = sum;
}

kernel void scan_chunk_sums(global uint *chunk_sums, uint chunk_count)
{
    if (get_global_id(0) != 0)
        return;
    uint running = 0;
    for (uint i = 0; i < chunk_count; i++) {
        uint value = chunk_sums[i];
        chunk_sums[i] = running;
        running += value;
    }
}

/* cell_start[i] = hit points in cells before i; cell_start[cell_count] = all of them.
 * cell_cursor starts as a copy, for grid_scatter. */
kernel void scan_apply(global const uint *cell_counts, uint cell_count,
                       global const uint *chunk_offsets, global uint *cell_start,
                       global uint *cell_cursor)
{
    uint chunk = get_global_id(0);
    uint begin = chunk * IDMR_SCAN_CHUNK;
    if (begin >= cell_count)
        return;
    uint end = min(begin + IDMR_SCAN_CHUNK, cell_count);
    uint running = chunk_offsets[chunk];
    for (uint i = begin; i < end; i++) {
        cell_start[i] = running;
        cell_cursor[i] = running;
        running += cell_counts[i];
    }
    if (end == cell_count)
        cell_start[cell_count] = running;
}

kernel void grid_scatter(idmr_sppm_params params, global const idmr_hit_point *hit_points,
                         volatile global uint *cell_cursor, global uint *grid_points)
{
    uint i = get_global_id(0);
    if (i >= params.width * params.height || !hit_points[i].valid)
        return;
    uint h = grid_hash(grid_cell(vload3(0, hit_points[i].position), &params), params.cell_count);
    grid_points[atomic_inc(cell_cursor + h)] = i;
}

/* The distinct buckets of the cells that the ball of radius params->radius around p touches,
 * into buckets[8]; returns how many. */
inline uint grid_buckets_near(float3 p, const idmr_sppm_params *params, uint buckets[8])
{
    float r = params->radius;
    int3 lo = grid_cell(p - r, params), hi = grid_cell(p + r, params);
    uint count = 0;
    for (int z = lo.z; z <= hi.z; z++)
        for (int y = lo.y; y <= hi.y; y++)
            for (int x = lo.x; x <= hi.x; x++) {
                uint h = grid_hash((int3)(x, y, z), params->cell_count);
                bool seen = false;
                for (uint k = 0; k < count; k++)
                    seen = seen || buckets[k] == h;
                if (!seen && count < 8u)
                    buckets[count++] = h;
            }
    return count;
}

/* Whether hit point hp gathers a photon (or photon vertex) at p arriving on the side `side`
 * faces: closer than the radius (r2 = radius²), and facing the same side with a cosine above
 * 1e-3, so that faces meeting at a right angle never gather each other's photons on the sign of
 * a rounding error (that made results depend on the scene's scale). */
inline bool hit_point_gathers(global const idmr_hit_point *hp, float3 p, float3 side, float r2)
{
    float3 delta = vload3(0, hp->position) - p;
    return dot(delta, delta) < r2 && dot(vload3(0, hp->normal), side) > 1e-3f;
}

#endif
