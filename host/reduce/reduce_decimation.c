/* reduce_decimation.c — the decimation stage of `idmr reduce` (see reduce_stages.h): the meshes
 * the plan decimates, in parallel, largest first; then up to COMPENSATION_ROUNDS rounds that take
 * what meshes could not give up (too few legal collapses) from the meshes that met their targets
 * and have room above the floor (min_vertices), in proportion to that room. A round lowers those
 * meshes' targets in st->plan and decimates them again from their inputs. When no mesh has room
 * left and the total is still above the request, the meshes that missed their targets most, as
 * many as cover the excess, have their locks relaxed one step and are decimated again: first
 * their attribute seams are freed (decimate.h, "Attributes"; only meshes with attributes have
 * that step), then, with the combined method, their boundary lock goes from 1 % to 5 %, 25 % and
 * none (LOCK_STEPS): textures and creases, then outlines, give way only as far as the budget
 * demands.
 * Where that leaves the total below the request (the meshes that compensated gave for meshes
 * that then reached their targets after all), the shortfall goes back to those meshes. */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>

#include "core/error.h"
#include "core/progress.h"
#include "reduce/reduce_stages.h"

#define COMPENSATION_ROUNDS 3

/* The locks of a mesh, step by step: its attribute seams, then (combined) the boundary lock's
 * tolerance (decimate.h, seams_free and boundary_tolerance). */
typedef struct lock_step {
    int seams_free;
    double boundary_tolerance;
} lock_step;
static const lock_step LOCK_STEPS[] = {
    {0, DECIMATE_BOUNDARY_TOLERANCE}, {1, DECIMATE_BOUNDARY_TOLERANCE}, {1, 0.05}, {1, 0.25},
    {1, INFINITY},
};
#define LOCK_STEP_COUNT (sizeof LOCK_STEPS / sizeof *LOCK_STEPS)
/* Rounds of relaxing: each moves the meshes that missed most one step, only as many as cover
 * the excess, so meshes take turns; three turns per step. */
#define RELAX_ROUNDS (3 * (LOCK_STEP_COUNT - 1))

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

/* Vertices mesh m keeps above its target (0 when it met it or is not decimated). */
static uint64_t missed_by(const reduce_state *st, size_t m)
{
    uint64_t after = st->output[m].mesh.vertex_count, target = st->plan.target[m];
    return st->plan.decimate[m] && after > target ? after - target : 0;
}

/* Whether step s (> 0) of the ladder changes anything for mesh m: freeing seams only where the
 * mesh has attributes, a boundary tolerance only under the combined method. */
static int lock_step_applies(const reduce_state *st, size_t m, size_t s, decimate_method method)
{
    const decimate_input *in = &st->input[m];
    int frees_seams = LOCK_STEPS[s].seams_free != LOCK_STEPS[s - 1].seams_free;
    int moves_boundary =
        LOCK_STEPS[s].boundary_tolerance != LOCK_STEPS[s - 1].boundary_tolerance;
    return (frees_seams && (in->texcoords || in->normals)) ||
           (moves_boundary && method == DECIMATE_COMBINED);
}

/* The next step of mesh m's locks that changes anything, or LOCK_STEP_COUNT when none is left. */
static size_t next_lock_step(const reduce_state *st, size_t m, decimate_method method)
{
    const decimate_input *in = &st->input[m];
    double tolerance =
        in->boundary_tolerance > 0 ? in->boundary_tolerance : LOCK_STEPS[0].boundary_tolerance;
    size_t step = 0;
    while (step < LOCK_STEP_COUNT && LOCK_STEPS[step].seams_free <= in->seams_free &&
           LOCK_STEPS[step].boundary_tolerance <= tolerance)
        step++;
    while (step < LOCK_STEP_COUNT && !lock_step_applies(st, m, step, method))
        step++;
    return step;
}

/* Relaxes the locks one step for the meshes that missed their targets, those that missed most
 * first, until their misses cover `excess`, and flags them in `redo`; counts the meshes whose
 * seams are freed in st->seams_freed and those whose boundary lock is relaxed for the first
 * time in st->locks_relaxed. False if none could be relaxed. */
static int relax_locks(reduce_state *st, uint64_t excess, decimate_method method,
                       unsigned char *redo)
{
    uint64_t covered = 0;
    int any = 0;
    for (size_t m = 0; m < st->count; m++)
        redo[m] = 0;
    while (covered < excess) {
        size_t worst = st->count;
        for (size_t m = 0; m < st->count; m++)
            if (!redo[m] && missed_by(st, m) > 0 &&
                next_lock_step(st, m, method) < LOCK_STEP_COUNT &&
                (worst == st->count || missed_by(st, m) > missed_by(st, worst)))
                worst = m;
        if (worst == st->count)
            break;
        size_t step = next_lock_step(st, worst, method);
        decimate_input *in = &st->input[worst];
        if (LOCK_STEPS[step].seams_free && !in->seams_free)
            st->seams_freed++;
        if (method == DECIMATE_COMBINED &&
            LOCK_STEPS[step].boundary_tolerance > LOCK_STEPS[0].boundary_tolerance &&
            !(in->boundary_tolerance > LOCK_STEPS[0].boundary_tolerance))
            st->locks_relaxed++;
        in->seams_free = LOCK_STEPS[step].seams_free;
        in->boundary_tolerance = LOCK_STEPS[step].boundary_tolerance;
        covered += missed_by(st, worst);
        redo[worst] = 1;
        any = 1;
    }
    return any;
}

/* Whether mesh m gave up vertices for others (its target is below the planned one) and met its
 * target, so that a higher target keeps more (a mesh that missed a lowered target would not). */
static int can_take_back(const reduce_state *st, size_t m, const uint64_t *planned)
{
    return st->plan.decimate[m] && st->plan.target[m] < planned[m] &&
           st->output[m].mesh.vertex_count <= st->plan.target[m];
}

/* After relaxed locks let meshes reach their targets, the meshes that gave up vertices for them
 * (compensation) may have given too many: hands the shortfall back to those that can take it,
 * in proportion to what they gave, up to their planned targets (`planned`), and flags them in
 * `redo`. False if there is nothing to hand back. */
static int give_back(reduce_state *st, uint64_t shortfall, const uint64_t *planned,
                     unsigned char *redo)
{
    uint64_t given = 0;
    for (size_t m = 0; m < st->count; m++) {
        redo[m] = 0;
        if (can_take_back(st, m, planned))
            given += planned[m] - st->plan.target[m];
    }
    if (given == 0 || shortfall == 0)
        return 0;
    uint64_t returned = 0;
    for (size_t m = 0; m < st->count && returned < shortfall; m++) {
        if (!can_take_back(st, m, planned))
            continue;
        uint64_t room = planned[m] - st->plan.target[m];
        uint64_t share = (uint64_t)floor((double)shortfall * room / given);
        if (share > room)
            share = room;
        if (share > shortfall - returned)
            share = shortfall - returned;
        if (share == 0)
            continue;
        st->plan.target[m] += share;
        st->plan.factor[m] = (double)st->plan.target[m] / st->scene->meshes[m].vertex_count;
        returned += share;
        redo[m] = 1;
    }
    return returned > 0;
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
    unsigned int rounds = 0, last = COMPENSATION_ROUNDS + RELAX_ROUNDS;
    progress_begin(&bar, "decimation", last + 2, o->importance.sppm.progress);
    uint64_t *planned = xcalloc(st->count + 1, sizeof *planned);
    for (size_t m = 0; m < st->count; m++)
        planned[m] = st->plan.target[m];
    int status = 0, relaxed = 0;
    for (unsigned int round = 0; !status && round <= last; round++) {
        status = decimate_selected(st, method, threads, redo);
        progress_update(&bar, round + 1, NULL);
        st->vertices_after = vertices_after(st);
        uint64_t requested = st->plan.total_requested;
        if (status || st->vertices_after <= requested || round == last)
            break;
        if (rounds < COMPENSATION_ROUNDS &&
            compensate(st, st->vertices_after - requested, o->min_vertices, redo)) {
            st->compensation_rounds = ++rounds;
            continue;
        }
        if (!relax_locks(st, st->vertices_after - requested, method, redo))
            break;
        relaxed = 1;
    }
    uint64_t requested = st->plan.total_requested;
    if (!status && relaxed && st->vertices_after < requested &&
        give_back(st, requested - st->vertices_after, planned, redo)) {
        status = decimate_selected(st, method, threads, redo);
        st->vertices_after = vertices_after(st);
    }
    progress_update(&bar, last + 2, NULL);
    free(planned);
    progress_end(&bar);
    free(redo);
    st->seconds_decimation = monotonic_seconds() - start;
    return status;
}
