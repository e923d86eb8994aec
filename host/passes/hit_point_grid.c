/* hit_point_grid.c — the hash grid over an iteration's hit points (see hit_point_grid.h). */
#include "passes/hit_point_grid.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "core/error.h"

/* The grid's buckets and scan chunks for `hit_points`, and its five buffers' sizes in the order
 * of hit_point_grid_create(): one place for the allocation and hit_point_grid_bytes(). */
static void grid_sizes(unsigned int hit_points, unsigned int *cells, unsigned int *chunks,
                       size_t bytes[5])
{
    *cells = 1024;
    while (*cells < 2u * hit_points)
        *cells *= 2;
    *chunks = (*cells + IDMR_SCAN_CHUNK - 1) / IDMR_SCAN_CHUNK;
    bytes[0] = *cells * sizeof(cl_uint);
    bytes[1] = (*cells + 1) * sizeof(cl_uint);
    bytes[2] = *cells * sizeof(cl_uint);
    bytes[3] = *chunks * sizeof(cl_uint);
    bytes[4] = (hit_points ? hit_points : 1) * sizeof(idmr_hit_point);
}

uint64_t hit_point_grid_bytes(unsigned int hit_points)
{
    unsigned int cells, chunks;
    size_t bytes[5];
    grid_sizes(hit_points, &cells, &chunks, bytes);
    return (uint64_t)bytes[0] + bytes[1] + bytes[2] + bytes[3] + bytes[4];
}

int hit_point_grid_create(device *d, cl_program program, unsigned int hit_points,
                          hit_point_grid *g)
{
    memset(g, 0, sizeof *g);
    g->hit_points = hit_points;
    size_t bytes[5];
    grid_sizes(hit_points, &g->cells, &g->chunks, bytes);
    if (device_create_kernel(program, "grid_count", &g->count) ||
        device_create_kernel(program, "scan_chunks", &g->scan_chunks) ||
        device_create_kernel(program, "scan_chunk_sums", &g->scan_chunk_sums) ||
        device_create_kernel(program, "scan_apply", &g->scan_apply) ||
        device_create_kernel(program, "grid_scatter", &g->scatter))
        return -1;
    const device_buffer_request buffers[] = {
        {&g->cell_counts, bytes[0], "grid cell counts"},
        {&g->cell_start, bytes[1], "grid cell starts"},
        {&g->cell_cursor, bytes[2], "grid cursors"},
        {&g->chunk_sums, bytes[3], "grid prefix sums"},
        {&g->grid_hits, bytes[4], "grid hit points"},
    };
    return device_buffers(d, buffers, sizeof buffers / sizeof *buffers, &g->bytes);
}

void hit_point_grid_release(hit_point_grid *g)
{
    cl_kernel kernels[] = {g->count, g->scan_chunks, g->scan_chunk_sums, g->scan_apply,
                           g->scatter};
    device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
    cl_mem buffers[] = {g->cell_counts, g->cell_start, g->cell_cursor, g->chunk_sums,
                        g->grid_hits};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    memset(g, 0, sizeof *g);
}

int hit_point_grid_build(device *d, hit_point_grid *g, const idmr_sppm_params *params,
                         cl_mem hit_points, size_t local_size)
{
    cl_uint cells = g->cells, chunks = g->chunks;
    return device_clear(d, g->cell_counts, g->cells * sizeof(cl_uint), "grid cell counts") ||
                   DEVICE_SET_ARGS(g->count, "grid_count", DEVICE_ARG(*params),
                                   DEVICE_ARG(hit_points), DEVICE_ARG(g->cell_counts)) ||
                   device_run(d, g->count, "grid_count", g->hit_points, local_size) ||
                   DEVICE_SET_ARGS(g->scan_chunks, "scan_chunks", DEVICE_ARG(g->cell_counts),
                                   DEVICE_ARG(cells), DEVICE_ARG(g->chunk_sums)) ||
                   device_run(d, g->scan_chunks, "scan_chunks", g->chunks, 0) ||
                   DEVICE_SET_ARGS(g->scan_chunk_sums, "scan_chunk_sums",
                                   DEVICE_ARG(g->chunk_sums), DEVICE_ARG(chunks)) ||
                   device_run(d, g->scan_chunk_sums, "scan_chunk_sums", 1, 0) ||
                   DEVICE_SET_ARGS(g->scan_apply, "scan_apply", DEVICE_ARG(g->cell_counts),
                                   DEVICE_ARG(cells), DEVICE_ARG(g->chunk_sums),
                                   DEVICE_ARG(g->cell_start), DEVICE_ARG(g->cell_cursor)) ||
                   device_run(d, g->scan_apply, "scan_apply", g->chunks, 0) ||
                   DEVICE_SET_ARGS(g->scatter, "grid_scatter", DEVICE_ARG(*params),
                                   DEVICE_ARG(hit_points), DEVICE_ARG(g->cell_cursor),
                                   DEVICE_ARG(g->grid_hits)) ||
                   device_run(d, g->scatter, "grid_scatter", g->hit_points, local_size)
               ? -1
               : 0;
}

void hit_point_grid_place(const hit_point_grid *g, const scene *s, double radius2,
                          idmr_sppm_params *params)
{
    params->radius = (float)sqrt(radius2);
    double farthest = 0; /* the largest coordinate a gather ball reaches */
    for (int k = 0; k < 3; k++)
        farthest = fmax(farthest, fmax(fabs(s->bbox_min[k]), fabs(s->bbox_max[k])));
    farthest += params->radius;
    /* A gather reads the cells of p - r and p + r (kernels/lib/hit_point_grid.h); they must be
     * the same or neighbours, and the kernel's p ± r and their quotients by the cell each round
     * by up to 2^-24 of `farthest`: so the cell exceeds 2r + 2^-22 farthest. */
    double cell_size = fmax((2.0 * params->radius + ldexp(farthest, -22)) * 1.0001,
                            farthest / HIT_POINT_GRID_MAX_CELL);
    params->cell_size = (float)cell_size * (1.0f + FLT_EPSILON);
    params->cell_count = g->cells;
}
