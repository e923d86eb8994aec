/* pass_grid.h — what the importance pass and the renderer share on the host: the hash grid
 * over an iteration's hit points (kernels/hit_point_grid.h) and the gather radius schedule.
 *
 * Radius: r_1 = 5 × |scene box diagonal| / (width + height) of the hit-point image, and
 * r_{n+1}² = r_n² (n + α) / (n + 1) — the SPPM schedule with one global radius (Knaus and
 * Zwicker's probabilistic formulation), so every iteration is an independent estimate at its
 * own radius. The grid cells are 2r (and a little more) wide, so a gather ball touches at most
 * 2 x 2 x 2 of them; buckets are a power of two, at least twice the hit points. */
#ifndef IDMR_PASS_GRID_H
#define IDMR_PASS_GRID_H

#include <stdint.h>

#include "device/device.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "core/scene.h"

typedef struct pass_grid {
    cl_kernel count, scan_chunks, scan_chunk_sums, scan_apply, scatter;
    cl_mem cell_counts, cell_start, cell_cursor, chunk_sums, grid_points;
    unsigned int hit_points, cells, chunks;
    uint64_t bytes; /* device memory of the grid's buffers */
} pass_grid;

/* Creates the grid kernels from `program` (which includes hit_point_grid.h) and the buffers
 * for `hit_points` hit points. Returns 0, or -1 with the error set; release either way. */
int pass_grid_create(device *d, cl_program program, unsigned int hit_points, pass_grid *g);
void pass_grid_release(pass_grid *g);

/* Sorts the hit points into the grid for this iteration's params (radius, cell size, origin
 * and cell_count set by pass_grid_place). Returns 0 or -1. */
int pass_grid_build(device *d, pass_grid *g, const idmr_sppm_params *params, cl_mem hit_points,
                    size_t local_size);

/* r_1² for a scene and hit-point image (a tiny positive value for a scene of one point). */
double pass_initial_radius2(const scene *s, unsigned int width, unsigned int height);

/* r_{n+1}² from r_n² after iteration n (counted from 0). */
double pass_next_radius2(double radius2, unsigned int n, float alpha);

/* Sets params' radius, cell size, grid origin and cell count for radius² `radius2`. */
void pass_grid_place(const pass_grid *g, const scene *s, double radius2, idmr_sppm_params *params);

#endif
