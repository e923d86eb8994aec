/* reduce_decimation.c — the decimation stage of `idmr reduce` (see reduce_stages.h): the meshes
 * the plan decimates, in parallel, largest first; then up to COMPENSATION_ROUNDS rounds that take
 * what meshes could not give up (too few legal collapses) from the meshes that met their targets
 * and have room above the floor (min_vertices), in proportion to that room. A round lowers those
 * meshes' targets in st->plan and decimates them again from their inputs. */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "core/error.h"
#include "core/progress.h"
#include "reduce/reduce_stages.h"

#define COMPENSATION_ROUNDS 3

/* Decimates the meshes flagged in `redo` to st->plan.target, replacing earlier outputs. */
static int decimate_selected(reduce_state *st, decimate_method method, unsigned int threads,
                             const unsigned char *redo)
{
    decimate_input *jobs = xcalloc(st->count + 1, sizeof *jobs);
    decimate_output *results = xcalloc(st->count + 1, sizeof *results);
    int *job_status = xcalloc(st->count + 1, sizeof *job_status);
    char(*job_messages)[512] = xcalloc(st->count + 1, sizeof *job_messages);
    size_t *job_mesh = xcalloc(st->count + 1, sizeof *job_mesh);
    size_t n = 0;
    for (size_t m = 0; m < st->count; m++)
        if (redo[m]) {
            jobs[n] = st->input[m];
            jobs[n].target_vertices = st->plan.target[m];
            job_mesh[n++] = m;
        }
    decimate_many(jobs, results, job_status, job_messages, n, method, threads);
    int status = 0;
    for (size_t j = 0; j < n; j++) {
        decimate_output_free(&st->output[job_mesh[j]]);
        st->output[job_mesh[j]] = results[j];
        if (job_status[j] && !status)
            status = error_set(IDMR_EXIT_FAILURE, "%s", job_messages[j]);
    }
    free(jobs);
    free(results);
    free(job_status);
    free(job_messages);
    free(job_mesh);
    return status;
}

/* Whether mesh m is decimated, met its target and has room above the floor. */
static int can_give_more(const reduce_state *st, size_t m, uint64_t floor_vertices)
{
    uint64_t target = st->plan.target[m];
    return st->plan.decimate[m] && st->output[m].mesh.vertex_count <= target &&
           target > floor_vertices;
}

/* Lowers the targets of the decimated meshes that met theirs by `excess` vertices in all, in
 * proportion to their room above the floor, and flags them in `redo`. False if none has room. */
static int compensate(reduce_state *st, uint64_t excess, uint64_t floor_vertices,
                      unsigned char *redo)
{
    uint64_t room = 0;
    for (size_t m = 0; m < st->count; m++) {
        redo[m] = 0;
        if (can_give_more(st, m, floor_vertices))
            room += st->plan.target[m] - floor_vertices;
    }
    if (room == 0)
        return 0;
    uint64_t taken = 0;
    for (size_t m = 0; m < st->count && taken < excess; m++) {
        if (!can_give_more(st, m, floor_vertices))
            continue;
        uint64_t target = st->plan.target[m];
        uint64_t share = (uint64_t)ceil((double)excess * (target - floor_vertices) / room);
        if (share > target - floor_vertices)
            share = target - floor_vertices;
        if (share > excess - taken)
            share = excess - taken;
        if (share == 0)
            continue;
        st->plan.target[m] = target - share;
        st->plan.factor[m] = (double)st->plan.target[m] / st->scene->meshes[m].vertex_count;
        taken += share;
        redo[m] = 1;
    }
    return taken > 0;
}

/* Vertices of the reduced scene: the decimated meshes' outputs and the others as they are. */
static uint64_t vertices_after(const reduce_state *st)
{
    uint64_t after = 0;
    for (size_t m = 0; m < st->count; m++)
        after += st->plan.decimate[m] ? st->output[m].mesh.vertex_count
                                      : st->scene->meshes[m].vertex_count;
    return after;
}

int reduce_decimation(reduce_state *st)
{
    const reduce_options *o = st->options;
    double start = monotonic_seconds();
    decimate_method method = reduce_method_collapses(o->method);
    unsigned int threads = o->threads ? o->threads : (unsigned int)sysconf(_SC_NPROCESSORS_ONLN);
    st->output = xcalloc(st->count + 1, sizeof *st->output);
    unsigned char *redo = xcalloc(st->count + 1, 1);
    for (size_t m = 0; m < st->count; m++)
        redo[m] = (unsigned char)st->plan.decimate[m];
    progress bar;
    progress_begin(&bar, "decimation", COMPENSATION_ROUNDS + 1, o->importance.sppm.progress);
    int status = 0;
    for (unsigned int round = 0; !status && round <= COMPENSATION_ROUNDS; round++) {
        status = decimate_selected(st, method, threads, redo);
        progress_update(&bar, round + 1, NULL);
        st->vertices_after = vertices_after(st);
        uint64_t requested = st->plan.total_requested;
        if (status || st->vertices_after <= requested || round == COMPENSATION_ROUNDS ||
            !compensate(st, st->vertices_after - requested, o->min_vertices, redo))
            break;
        st->compensation_rounds = round + 1;
    }
    progress_end(&bar);
    free(redo);
    st->seconds_decimation = monotonic_seconds() - start;
    return status;
}
