/* hit_point_grid.h — the hash grid over one iteration's hit points, shared by both passes of the
 * SPPM core: a counting sort of hit point indices by the hashed cell of their position (the
 * kernels grid_count, scan_chunks, scan_chunk_sums, scan_apply and grid_scatter in
 * kernels/sppm.cl are built from these functions), and the one test of which hit points a photon
 * reaches.
 *
 *   grid_count       hit points per bucket (cell_counts, cleared by the host)
 *   scan_chunks, scan_chunk_sums, scan_apply
 *                    cell_start = prefix sums of the counts, in three steps
 *   grid_scatter     grid_hits: copies of the hit points sorted by bucket, so that a gather
 *                    reads each bucket's hit points one after the other (their `pixel` says
 *                    whose they are)
 * The cell size is at least twice the gather radius (the host sets it, rounding included), so a
 * ball of that radius touches at most 2 x 2 x 2 cells; grid_buckets_near() lists their buckets
 * once each (two cells may hash to one bucket). Host side: host/passes/hit_point_grid.c. */
#ifndef IDMR_KERNEL_HIT_POINT_GRID_H
#define IDMR_KERNEL_HIT_POINT_GRID_H

#include "idmr/sppm_layout.h"

/* The cell of point p: its coordinates over the cell size, rounded down, in 64 bits, counted
 * from the world origin (where positions have their finest floats). The host sizes the cells so
 * that no point of the scene is more than 2^60 cells out (hit_point_grid.c): the conversion
 * never saturates, and distinct cells never merge. */
inline long3 grid_cell(float3 p, const idmr_sppm_params *params)
{
    return convert_long3_sat_rtn(p / params->cell_size);
}

inline uint grid_hash(long3 c, uint cell_count)
{
    ulong h = ((ulong)c.x * 73856093ul) ^ ((ulong)c.y * 19349663ul) ^ ((ulong)c.z * 83492791ul);
    return (uint)(h ^ (h >> 32)) & (cell_count - 1u);
}

/* The bucket of hit point hp (valid ones only are sorted into the grid). */
inline uint grid_bucket(global const idmr_hit_point *hp, const idmr_sppm_params *params)
{
    return grid_hash(grid_cell(vload3(0, hp->position), params), params->cell_count);
}

/* The cells of prefix-sum chunk `chunk`: [*begin, *end) of cell_count; false past the last. */
inline bool scan_chunk_cells(uint chunk, uint cell_count, uint *begin, uint *end)
{
    *begin = chunk * IDMR_SCAN_CHUNK;
    *end = min(*begin + IDMR_SCAN_CHUNK, cell_count);
    return *begin < cell_count;
}

/* The exclusive prefix sum of values[0 .. count) in place (one work-item: chunks are few). */
inline void exclusive_scan(global uint *values, uint count)
{
    uint running = 0;
    for (uint i = 0; i < count; i++) {
        uint value = values[i];
        values[i] = running;
        running += value;
    }
}

/* The distinct buckets of the cells that the ball of radius params->radius around p touches,
 * into buckets[8]; returns how many. Along each axis the ball reaches the cell of p - r and that
 * of p + r and none between: a hit point that gathers p is closer than r on every axis, and
 * rounding is monotonic, so its cell lies between those two; and the host makes a cell wider
 * than the ball by more than the rounding of p ± r and of their quotients by the cell, so the
 * two are the same cell or neighbours. */
inline uint grid_buckets_near(float3 p, const idmr_sppm_params *params, uint buckets[8])
{
    float r = params->radius;
    long3 lo = grid_cell(p - r, params), hi = grid_cell(p + r, params);
    uint count = 0;
    for (uint corner = 0; corner < 8u; corner++) {
        long3 c = (long3)(corner & 1u ? hi.x : lo.x, corner & 2u ? hi.y : lo.y,
                          corner & 4u ? hi.z : lo.z);
        uint h = grid_hash(c, params->cell_count);
        bool seen = false;
        for (uint k = 0; k < count; k++)
            seen = seen || buckets[k] == h;
        if (!seen)
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
    return (dot(delta, delta) < r2) & (dot(vload3(0, hp->normal), side) > 1e-3f); /* no branch */
}

#endif
