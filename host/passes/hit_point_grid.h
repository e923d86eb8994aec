/* hit_point_grid.h — the hash grid over an iteration's hit points (kernels/lib/hit_point_grid.h),
 * built on the device by counting sort: cell counts with atomics, a three-step prefix sum, a
 * scatter of copies of the hit points by cell (a gather reads a cell's hit points in a row). Part of the SPPM core (passes/sppm.h).
 *
 * The cells are 2r (and a little more, for rounding where floats are coarse) wide for the
 * gather radius r, so a gather ball touches at most 2 x 2 x 2 of them, and they are counted in 64 bits from the world origin: where the
 * scene reaches farther than HIT_POINT_GRID_MAX_CELL cells of that size (a small radius in a
 * vast scene), the cells grow to keep every cell number in range. Buckets are a power of two,
 * at least twice the hit points, at least 1024. */
#ifndef IDMR_HIT_POINT_GRID_H
#define IDMR_HIT_POINT_GRID_H

#include <stdint.h>

#include "core/scene.h"
#include "device/device.h"
#include "idmr/sppm_layout.h"

/* The largest cell number along an axis: 2^60 (a 64-bit cell number with room to spare). */
#define HIT_POINT_GRID_MAX_CELL 1152921504606846976.0

typedef struct hit_point_grid {
    cl_kernel count, scan_chunks, scan_chunk_sums, scan_apply, scatter;
    cl_mem cell_counts, cell_start, cell_cursor, chunk_sums, grid_hits;
    unsigned int hit_points, cells, chunks;
    uint64_t bytes; /* device memory of the grid's buffers */
} hit_point_grid;

/* Creates the grid kernels from `program` (built from kernels/sppm.cl) and the buffers for
 * `hit_points` hit points. Returns 0, or -1 with the error set; release either way. */
int hit_point_grid_create(device *d, cl_program program, unsigned int hit_points,
                          hit_point_grid *g);
void hit_point_grid_release(hit_point_grid *g);

/* Device memory of the grid's buffers for `hit_points`, as hit_point_grid_create() allocates
 * them. */
uint64_t hit_point_grid_bytes(unsigned int hit_points);

/* Sets params' radius, cell size and cell count for gather radius² `radius2` in scene s. */
void hit_point_grid_place(const hit_point_grid *g, const scene *s, double radius2,
                          idmr_sppm_params *params);

/* Sorts the hit points into the grid for this iteration's params (placed with
 * hit_point_grid_place). Returns 0 or -1. */
int hit_point_grid_build(device *d, hit_point_grid *g, const idmr_sppm_params *params,
                         cl_mem hit_points, size_t local_size);

#endif
