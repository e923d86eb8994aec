/* sppm.c — the SPPM core under both passes (see sppm.h): upload, program, the core's buffers,
 * per-iteration parameters, the radius schedule, the iteration loop, progress, timings and
 * snapshots; with several devices one core each, driven at once by one host thread each, and
 * the split of the photon paths between them (sppm_split_paths, rebalance). A pass adds its
 * work through the hooks of its sppm_pass. */
#include "device/program.h"
#include "passes/sppm.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/hash.h"
#include "core/progress.h"
#include "core/ranks.h"

#define MAX_PIXELS (1u << 26)
#define SPPM_MAX_DEVICES_TEXT "16" /* SPPM_MAX_DEVICES, for messages */

/* The initial gather radius in pixel footprints (sppm.h). */
#define SPPM_RADIUS_FOOTPRINTS 2.5

void sppm_options_default(sppm_options *o, unsigned int iterations)
{
    memset(o, 0, sizeof *o);
    o->iterations = iterations;
    o->seed = 1;
    o->alpha = 0.7f;
    o->resolution = 1.0f;
    o->max_depth = IDMR_CAMERA_DEPTH;
}

unsigned int sppm_default_photons(const device *d)
{
    return strcmp(d->info.kind, "gpu") == 0 ? 1000000u : 500000u;
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

double sppm_initial_radius2(const scene *s, unsigned int width, const idmr_hit_point *hit_points,
                            size_t count)
{
    float *distance = xmalloc((count ? count : 1) * sizeof *distance);
    size_t valid = 0;
    for (size_t i = 0; i < count; i++) {
        if (!(hit_points[i].offset > 0.0f))
            continue;
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double delta = (double)hit_points[i].position[k] - s->camera.origin[k];
            d2 += delta * delta;
        }
        if (isfinite(d2) && d2 > 0)
            distance[valid++] = (float)sqrt(d2);
    }
    double pixel_angle = 2.0 * s->camera.tan_half_x / width;
    qsort(distance, valid, sizeof *distance, compare_floats);
    double radius = valid ? SPPM_RADIUS_FOOTPRINTS * distance[valid / 2] * pixel_angle
                          : 5.0 * scene_diagonal(s) / width; /* the camera sees nothing */
    free(distance);
    double radius2 = radius * radius;
    return radius2 > 0 && isfinite(radius2) ? radius2 : 1e-12;
}

double sppm_next_radius2(double radius2, unsigned int n, float alpha)
{
    return radius2 * (n + 1 + alpha) / (n + 2.0);
}

void sppm_summary_free(sppm_summary *summary)
{
    free(summary->radius);
    free(summary->build_options);
    memset(summary, 0, sizeof *summary);
}

void sppm_snapshot_free(sppm_snapshot *snapshot)
{
    free(snapshot->hit_points);
    free(snapshot->photon_records);
    free(snapshot->path_length);
    free(snapshot->record_index);
    memset(snapshot, 0, sizeof *snapshot);
}

void *sppm_snapshot_by_slot(const sppm_snapshot *snapshot, const void *list, size_t bytes)
{
    size_t paths = snapshot->params.device_paths;
    unsigned char *out = xcalloc(paths * IDMR_PATH_VERTICES + 1, bytes);
    for (size_t p = 0; p < paths; p++)
        for (size_t j = 0; j < snapshot->path_length[p]; j++) {
            size_t slot = p * IDMR_PATH_VERTICES + j;
            memcpy(out + slot * bytes,
                   (const unsigned char *)list + snapshot->record_index[slot] * bytes, bytes);
        }
    return out;
}

/* What the core needs of the scene and the options; sets the summary's image and photons. */
static int check_inputs(const device *d, const scene *s, const sppm_options *o,
                        const sppm_pass *pass, sppm_summary *summary)
{
    if (!s->has_camera)
        return error_set(IDMR_EXIT_INPUT, "%s: the scene has no sensor: the %s pass needs a camera",
                         s->file, pass->name);
    if (s->light_count == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: the scene has no emitter that idmr simulates (area, point, spot, "
                         "directional, constant, envmap): no light can reach the camera",
                         s->file);
    if (o->iterations == 0)
        return error_set(IDMR_EXIT_INPUT, "%s: at least one iteration is needed", pass->name);
    if (!(o->resolution > 0) || !(o->alpha > 0 && o->alpha <= 1) || !(o->radius >= 0))
        return error_set(IDMR_EXIT_INPUT,
                         "%s: resolution must be > 0, alpha in (0, 1] and radius >= 0",
                         pass->name);
    double w = fmax(1.0, floor(s->camera.width * o->resolution + 0.5));
    double h = fmax(1.0, floor(s->camera.height * o->resolution + 0.5));
    if (w * h > MAX_PIXELS)
        return error_set(IDMR_EXIT_INPUT, "%s: the hit-point image %gx%g is too large (at most "
                                          "%u pixels)", pass->name, w, h, MAX_PIXELS);
    summary->width = (unsigned int)w;
    summary->height = (unsigned int)h;
    summary->photons = o->photons ? o->photons : sppm_default_photons(d);
    if ((uint64_t)summary->photons * IDMR_PATH_VERTICES > 0xffffffffu)
        return error_set(IDMR_EXIT_INPUT, "%s: %u photon paths per iteration are too many",
                         pass->name, summary->photons);
    return 0;
}

char *sppm_build_options(const device *d, unsigned int features, int pass,
                         const char *pass_defines)
{
    char defines[256];
    snprintf(defines, sizeof defines, "-D IDMR_SPPM_PASS=%d%s%s", pass,
             pass_defines ? " " : "", pass_defines ? pass_defines : "");
    return device_build_options(d, features, defines);
}

/* The program and the core's kernels on the core's device; the first device's build options
 * are the summary's, and the build seconds of all of them are added up. --generic builds every
 * material and light kind in, but IDMR_FEATURE_INSTANCES is the scene's either way: it says
 * which BVH the scene was uploaded with (device/bvh.h), not what the program can shade. */
unsigned int sppm_program_features(const scene *s, const sppm_options *o)
{
    return (o->generic ? IDMR_FEATURES_ALL : s->features & IDMR_FEATURES_ALL) |
           (s->features & IDMR_FEATURE_INSTANCES);
}

static int build_program(sppm *core, const sppm_pass *pass)
{
    double start = monotonic_seconds();
    unsigned int features = sppm_program_features(core->scene, core->options);
    char *options = sppm_build_options(core->dev, features, pass->pass, pass->defines);
    int status =
        device_build_program(core->dev, "sppm.cl", options, &core->program) ||
        device_create_kernel(core->program, "camera_paths", &core->camera_paths) ||
        device_create_kernel(core->program, "photon_paths", &core->photon_paths);
    if (core->index == 0)
        core->summary->build_options = options;
    else
        free(options);
    core->summary->seconds.build += monotonic_seconds() - start;
    return status ? -1 : 0;
}

/* The sizes of the core's own buffers (hit points, photon path lengths, the list of photon
 * records, its length, the record index), in allocate()'s order: one place for the allocation
 * and sppm_memory_of(). */
#define CORE_BUFFERS 5
static void core_sizes(unsigned int pixels, unsigned int photons, size_t record_bytes,
                       size_t bytes[CORE_BUFFERS])
{
    bytes[0] = (size_t)pixels * sizeof(idmr_hit_point);
    bytes[1] = (size_t)photons * sizeof(cl_uint);
    bytes[2] = (size_t)photons * IDMR_PATH_VERTICES * record_bytes;
    bytes[3] = sizeof(cl_uint);
    bytes[4] = (size_t)photons * IDMR_PATH_VERTICES * sizeof(cl_uint);
}

/* The memory of one device's core whose slots hold `capacity` photon paths. */
static void memory_of_capacity(const scene *s, uint64_t bvh_bytes, unsigned int pixels,
                               unsigned int capacity, const sppm_pass *pass, sppm_memory *m)
{
    size_t bytes[CORE_BUFFERS];
    core_sizes(pixels, capacity, pass->photon_record_bytes, bytes);
    m->geometry = device_scene_geometry_bytes(s);
    m->bvh = bvh_bytes;
    m->core = hit_point_grid_bytes(pixels);
    for (int k = 0; k < CORE_BUFFERS; k++)
        m->core += bytes[k];
    m->pass = pass->pass_bytes
                  ? pass->pass_bytes(s, pixels, (size_t)capacity * IDMR_PATH_VERTICES)
                  : 0;
}

int sppm_memory_of(const device *d, const scene *s, uint64_t bvh_bytes, const sppm_options *o,
                   const sppm_pass *pass, sppm_memory *m)
{
    sppm_summary film;
    memset(&film, 0, sizeof film);
    if (check_inputs(d, s, o, pass, &film))
        return -1;
    memory_of_capacity(s, bvh_bytes, film.width * film.height, film.photons, pass, m);
    return 0;
}

uint64_t sppm_memory_total(const sppm_memory *m)
{
    return m->geometry + m->bvh + m->core + m->pass;
}

/* The run's device memory against the budget it was given and the device's global memory. */
static int check_memory(const device *d, const sppm_options *o, const sppm_pass *pass,
                        const sppm_memory *m)
{
    const double mib = 1048576.0;
    uint64_t total = sppm_memory_total(m);
    char parts[160];
    snprintf(parts, sizeof parts, "geometry %.1f, BVH %.1f, buffers %.1f MiB", m->geometry / mib,
             m->bvh / mib, (m->core + m->pass) / mib);
    if (o->device_budget && total > o->device_budget)
        return error_set(IDMR_EXIT_INPUT,
                         "the %s pass needs %.1f MiB of device memory (%s; %llu bytes), more "
                         "than the memory budget of %.1f MiB (%llu bytes)",
                         pass->name, total / mib, parts, (unsigned long long)total,
                         o->device_budget / mib, (unsigned long long)o->device_budget);
    if (total > d->info.global_memory)
        return error_set(IDMR_EXIT_FAILURE,
                         "the %s pass needs %.1f MiB of device memory (%s), more than device "
                         "'%s' has (%.1f MiB): reduce the scene first (idmr reduce "
                         "--memory-budget), or lower --photons or --resolution",
                         pass->name, total / mib, parts, d->info.name,
                         d->info.global_memory / mib);
    return 0;
}

/* The core's buffers, and the arguments of camera_paths (params, camera, the scene's buffers,
 * hit points, then the pass's records) and photon_paths (params, the scene's buffers, path
 * lengths, records) that do not change, bound in order. */
static int allocate(sppm *core, const sppm_pass *pass)
{
    core->slots = (size_t)core->capacity * IDMR_PATH_VERTICES;
    if (hit_point_grid_create(core->dev, core->program, core->pixels, &core->grid))
        return -1;
    size_t bytes[CORE_BUFFERS];
    core_sizes(core->pixels, core->capacity, pass->photon_record_bytes, bytes);
    const device_buffer_request buffers[CORE_BUFFERS] = {
        {&core->hit_points, bytes[0], "hit points"},
        {&core->path_length, bytes[1], "photon path lengths"},
        {&core->photon_records, bytes[2], "photon records"},
        {&core->stored_count, bytes[3], "photon record count"},
        {&core->record_index, bytes[4], "photon record index"},
    };
    core->buffer_bytes = core->grid.bytes;
    if (device_buffers(core->dev, buffers, sizeof buffers / sizeof *buffers,
                       &core->buffer_bytes))
        return -1;
    idmr_camera camera = core->scene->camera;
    cl_uint scene_first = 2, after_scene = scene_first + DEVICE_SCENE_BUFFERS;
    core->camera_pass_argument = after_scene + 1;
    core->photon_pass_argument = 1 + DEVICE_SCENE_BUFFERS + 4; /* after record_index */
    return DEVICE_SET_ARG(core->camera_paths, "camera_paths", 1, camera) ||
                   device_scene_set_args(&core->uploaded, core->camera_paths, "camera_paths",
                                         scene_first) ||
                   DEVICE_SET_ARG(core->camera_paths, "camera_paths", after_scene,
                                  core->hit_points) ||
                   device_scene_set_args(&core->uploaded, core->photon_paths, "photon_paths",
                                         1) ||
                   DEVICE_SET_ARGS_FROM(core->photon_paths, "photon_paths",
                                        1 + DEVICE_SCENE_BUFFERS, DEVICE_ARG(core->path_length),
                                        DEVICE_ARG(core->photon_records),
                                        DEVICE_ARG(core->stored_count),
                                        DEVICE_ARG(core->record_index))
               ? -1
               : 0;
}

static void release(sppm *core)
{
    cl_kernel kernels[] = {core->camera_paths, core->photon_paths};
    device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
    cl_mem buffers[] = {core->hit_points, core->path_length, core->photon_records,
                        core->stored_count, core->record_index};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    hit_point_grid_release(&core->grid);
    if (core->program)
        clReleaseProgram(core->program);
    core->program = NULL;
    device_scene_release(&core->uploaded);
}

/* The parameters that stay the same over the iterations. */
static void params_begin(sppm *core)
{
    idmr_sppm_params *params = &core->params;
    memset(params, 0, sizeof *params);
    params->seed = core->options->seed;
    params->width = core->summary->width;
    params->height = core->summary->height;
    params->path_count = core->summary->photons;
    params->light_count = core->uploaded.light_count;
    params->triangle_count = (unsigned int)core->scene->triangle_count;
    memcpy(params->scene_center, core->uploaded.center, sizeof params->scene_center);
    params->scene_radius = core->uploaded.radius;
    params->camera_depth = core->options->max_depth;
    params->path_first = core->rank_first;
    params->device_paths = core->rank_paths;
    params->camera_sums = core->index == 0 && ranks_rank() == 0;
}

/* What the first iteration's paths decide, read back once from the first device: the initial
 * gather radius² (from the hit points, sppm_initial_radius2) and, for the reports, the valid
 * hit points. */
static int first_iteration(sppm *core, double *radius2)
{
    idmr_hit_point *hit_points = xmalloc(core->pixels * sizeof *hit_points);
    int status = device_read(core->dev, core->hit_points, core->pixels * sizeof *hit_points,
                             hit_points, "hit points");
    for (size_t i = 0; i < core->pixels && !status; i++)
        core->summary->hit_points += hit_points[i].offset > 0.0f;
    double pinned = core->options->radius;
    if (!status)
        *radius2 = pinned > 0 ? pinned * pinned
                              : sppm_initial_radius2(core->scene, core->params.width, hit_points,
                                                     core->pixels);
    free(hit_points);
    return status ? -1 : 0;
}

/* One step of an iteration on one device's core. */
typedef int (*core_step)(sppm *core, sppm_pass *pass);

/* Camera paths, then this device's photon paths and the length of its stored-vertex list, each
 * stage timed (the queue is drained between stages). */
static int trace_paths(sppm *core, sppm_pass *pass)
{
    (void)pass;
    size_t local = core->options->local_size;
    double t0 = monotonic_seconds();
    if (DEVICE_SET_ARG(core->camera_paths, "camera_paths", 0, core->params) ||
        device_run(core->dev, core->camera_paths, "camera_paths", core->pixels, local))
        return -1;
    double t1 = monotonic_seconds();
    cl_uint stored = 0;
    if (device_clear(core->dev, core->stored_count, sizeof(cl_uint), "photon record count") ||
        DEVICE_SET_ARG(core->photon_paths, "photon_paths", 0, core->params) ||
        (core->params.device_paths &&
         device_run(core->dev, core->photon_paths, "photon_paths", core->params.device_paths,
                    local)) ||
        device_read(core->dev, core->stored_count, sizeof stored, &stored, "photon record count"))
        return -1;
    core->stored = stored;
    double t2 = monotonic_seconds();
    core->seconds.camera += t1 - t0;
    core->seconds.photon += t2 - t1;
    core->photon_pass_seconds = t2 - t1;
    return 0;
}

/* The grid over the hit points for radius² core->radius2, then the pass's gather. */
static int gather_photons(sppm *core, sppm_pass *pass)
{
    hit_point_grid_place(&core->grid, core->scene, core->radius2, &core->params);
    double t0 = monotonic_seconds();
    if (hit_point_grid_build(core->dev, &core->grid, &core->params, core->hit_points,
                             core->options->local_size))
        return -1;
    double t1 = monotonic_seconds();
    if (pass->gather(core, pass->state))
        return -1;
    core->seconds.grid += t1 - t0;
    core->seconds.gather += monotonic_seconds() - t1;
    return 0;
}

/* A step on one core in a thread of its own, its error kept for the thread that waits. */
typedef struct core_job {
    sppm *core;
    sppm_pass *pass;
    core_step step;
    int status, code;
    char message[2048];
} core_job;

static void *run_core_job(void *argument)
{
    core_job *job = argument;
    job->status = job->step(job->core, job->pass);
    if (job->status) {
        job->code = error_code();
        snprintf(job->message, sizeof job->message, "%s", error_message());
    }
    return NULL;
}

/* `step` on every core at once, one host thread each (on this thread alone for one device);
 * the first failure's error is set, naming its device. */
static int on_every_core(sppm *cores, unsigned int count, sppm_pass *pass, core_step step)
{
    if (count == 1)
        return step(cores, pass);
    core_job jobs[SPPM_MAX_DEVICES];
    pthread_t threads[SPPM_MAX_DEVICES];
    int started[SPPM_MAX_DEVICES];
    for (unsigned int k = 0; k < count; k++) {
        jobs[k] = (core_job){.core = cores + k, .pass = pass, .step = step};
        started[k] = pthread_create(threads + k, NULL, run_core_job, jobs + k) == 0;
        if (!started[k])
            run_core_job(jobs + k); /* no thread to be had: in turn, on this one */
    }
    for (unsigned int k = 0; k < count; k++)
        if (started[k])
            pthread_join(threads[k], NULL);
    for (unsigned int k = 0; k < count; k++)
        if (jobs[k].status)
            return error_set(jobs[k].code ? jobs[k].code : IDMR_EXIT_FAILURE,
                             "device %d (%s): %s", cores[k].dev->info.index,
                             cores[k].dev->info.name, jobs[k].message);
    return 0;
}

/* One iteration on every device: paths, then (the first device deciding the radius after the
 * first iteration's paths, not timed as a stage) grid and gather; the summary's stage seconds
 * become the most any device has spent in each. */
static int iterate(sppm *cores, unsigned int count, sppm_pass *pass, unsigned int n,
                   double *radius2)
{
    sppm_summary *summary = cores->summary;
    int status = on_every_core(cores, count, pass, trace_paths);
    if (n == 0) {
        /* Under mpirun, rank 0's radius rules, and the stored records are all ranks'. */
        status = status || first_iteration(cores, radius2);
        if (ranks_sync(status, NULL))
            return -1;
        ranks_broadcast(radius2, sizeof *radius2);
        uint64_t stored = 0;
        for (unsigned int k = 0; k < count; k++)
            stored += cores[k].stored;
        if (pass->ranks)
            ranks_sum_words(&stored, 1);
        summary->photon_records = stored;
    }
    if (status)
        return -1;
    for (unsigned int k = 0; k < count; k++)
        cores[k].radius2 = *radius2;
    if (on_every_core(cores, count, pass, gather_photons))
        return -1;
    summary->radius[n] = cores->params.radius;
    sppm_seconds *most = &summary->seconds;
    for (unsigned int k = 0; k < count; k++) {
        const sppm_seconds *each = &cores[k].seconds;
        most->camera = fmax(most->camera, each->camera);
        most->photon = fmax(most->photon, each->photon);
        most->grid = fmax(most->grid, each->grid);
        most->gather = fmax(most->gather, each->gather);
        sppm_device_share *share = summary->device + k;
        share->last_paths = cores[k].params.device_paths;
        share->paths += cores[k].params.device_paths;
        share->photon_seconds += cores[k].photon_pass_seconds;
    }
    return 0;
}

void sppm_split_paths(unsigned int total, unsigned int count, const double *weight,
                      const unsigned int *capacity, unsigned int *counts)
{
    /* Water-filling: shares in proportion to the weights among the devices not yet full; a
     * device whose share passes its capacity is filled and leaves; the rest is shared again. */
    int full[SPPM_MAX_DEVICES] = {0};
    double share[SPPM_MAX_DEVICES];
    double left = total;
    for (int changed = 1; changed;) {
        changed = 0;
        double weights = 0;
        for (unsigned int k = 0; k < count; k++)
            if (!full[k])
                weights += weight[k];
        for (unsigned int k = 0; k < count; k++)
            if (!full[k])
                share[k] = weights > 0 ? left * weight[k] / weights : 0;
        for (unsigned int k = 0; k < count; k++)
            if (!full[k] && share[k] > capacity[k]) {
                full[k] = 1;
                share[k] = capacity[k];
                left -= capacity[k];
                changed = 1;
            }
    }
    /* Whole paths: each device its share rounded down, then the paths left over one at a time
     * to the devices in order that have room. */
    unsigned int given = 0;
    for (unsigned int k = 0; k < count; k++) {
        double whole = floor(share[k]);
        counts[k] = whole > 0 ? (unsigned int)fmin(whole, capacity[k]) : 0;
        given += counts[k];
    }
    for (unsigned int k = 0; given < total; k = (k + 1) % count)
        if (counts[k] < capacity[k])
            counts[k]++, given++;
}

/* Sets each device's range of the photon paths from `counts`. */
static void set_ranges(sppm *cores, unsigned int count, const unsigned int *counts)
{
    unsigned int first = cores->rank_first;
    for (unsigned int k = 0; k < count; k++) {
        cores[k].params.path_first = first;
        cores[k].params.device_paths = counts[k];
        first += counts[k];
    }
}

/* The split after a measured iteration: each device's weight its paths per photon pass
 * second (where it traced none or took no time, its share so far). */
static void rebalance(sppm *cores, unsigned int count)
{
    double weight[SPPM_MAX_DEVICES];
    unsigned int capacity[SPPM_MAX_DEVICES], counts[SPPM_MAX_DEVICES];
    for (unsigned int k = 0; k < count; k++) {
        double paths = cores[k].params.device_paths, seconds = cores[k].photon_pass_seconds;
        weight[k] = paths > 0 && seconds > 0 ? paths / seconds : fmax(paths, 1.0);
        capacity[k] = cores[k].capacity;
    }
    double slowest = weight[0];
    for (unsigned int k = 1; k < count; k++)
        slowest = fmin(slowest, weight[k]);
    for (unsigned int k = 0; k < count; k++)
        weight[k] /= slowest > 0 ? slowest : 1.0;
    sppm_split_paths(cores->rank_paths, count, weight, capacity, counts);
    set_ranges(cores, count, counts);
}

static int take_snapshot(sppm *core, size_t record_bytes, sppm_snapshot *out)
{
    sppm_snapshot_free(out);
    out->params = core->params;
    size_t paths = core->params.device_paths, slots = core->slots;
    out->hit_points = xmalloc(core->pixels * sizeof *out->hit_points);
    out->path_length = xmalloc((paths + 1) * sizeof *out->path_length);
    out->record_index = xmalloc(slots * sizeof *out->record_index);
    out->stored = core->stored;
    void *list = xmalloc((core->stored + 1) * record_bytes);
    int status =
        device_read(core->dev, core->hit_points, core->pixels * sizeof *out->hit_points,
                    out->hit_points, "hit points") ||
        (paths && device_read(core->dev, core->path_length, paths * sizeof *out->path_length,
                              out->path_length, "photon path lengths")) ||
        device_read(core->dev, core->record_index, slots * sizeof *out->record_index,
                    out->record_index, "photon record index") ||
        (core->stored && device_read(core->dev, core->photon_records,
                                     core->stored * record_bytes, list, "photon records"));
    if (!status)
        out->photon_records = sppm_snapshot_by_slot(out, list, record_bytes);
    free(list);
    return status ? -1 : 0;
}

/* The iterations, until one of the stop rules (sppm.h) ends them. */
static int run_iterations(sppm *cores, unsigned int count, sppm_pass *pass,
                          sppm_snapshot *snapshot)
{
    const sppm_options *o = cores->options;
    sppm_summary *summary = cores->summary;
    summary->radius = xcalloc(o->iterations, sizeof *summary->radius);
    double radius2 = 0; /* set after the first iteration's camera paths */
    progress bar;
    progress_begin(&bar, pass->name, o->iterations, o->progress);
    double start = monotonic_seconds();
    int status = 0, stop = 0;
    for (unsigned int n = 0; n < o->iterations && !status && !stop; n++) {
        for (unsigned int k = 0; k < count; k++)
            cores[k].params.iteration = n;
        status = iterate(cores, count, pass, n, &radius2) ||
                 (snapshot && (take_snapshot(cores, pass->photon_record_bytes, snapshot) ||
                               (pass->snapshot && pass->snapshot(cores, pass->state))));
        if (status)
            break;
        char detail[64] = "";
        double collect_start = monotonic_seconds();
        status = pass->collect(cores, count, pass->state, n, &stop, detail, sizeof detail);
        if (status)
            break;
        summary->seconds.collect += monotonic_seconds() - collect_start;
        summary->iterations = n + 1;
        progress_update(&bar, n + 1, detail);
        radius2 = sppm_next_radius2(radius2, n, o->alpha);
        CHECK_FINITE(radius2, "gather radius²");
        if (count > 1 && !o->fixed_split && n >= 1 && n <= SPPM_REBALANCE_ITERATIONS)
            rebalance(cores, count);
        if (o->time_limit > 0 && monotonic_seconds() - start >= o->time_limit)
            stop = 1;
        /* Under mpirun every rank stops after the same iteration: when any says stop (the
         * collect hook's rules decide alike on the ranks' common sums; the time limit on
         * each rank's clock). */
        status = ranks_sync(0, &stop);
    }
    progress_end(&bar);
    summary->seconds.total = monotonic_seconds() - start;
    return status ? -1 : 0;
}

/* The first split (options' weights, else compute units) and each device's capacity. */
static void first_split(const sppm_options *o, device *devices, unsigned int count,
                        unsigned int photons, unsigned int *counts, unsigned int *capacity)
{
    double weight[SPPM_MAX_DEVICES];
    unsigned int all[SPPM_MAX_DEVICES];
    for (unsigned int k = 0; k < count; k++) {
        double w = o->split ? o->split[k] : (double)devices[k].info.compute_units;
        weight[k] = w > 0 && isfinite(w) ? w : 1.0;
        all[k] = photons;
    }
    sppm_split_paths(photons, count, weight, all, counts);
    for (unsigned int k = 0; k < count; k++) {
        double room = count == 1 ? photons : ceil(counts[k] * SPPM_SHARE_HEADROOM);
        capacity[k] = (unsigned int)fmax(1.0, fmin(room, photons));
    }
}

/* A device's memory, checked; with several devices the error names it. */
static int check_device_memory(const device *d, unsigned int count, const sppm_options *o,
                               const sppm_pass *pass, const sppm_memory *m)
{
    if (!check_memory(d, o, pass, m))
        return 0;
    return count > 1 ? error_prefix("device %d (%s)", d->info.index, d->info.name) : -1;
}

/* What every rank of a run must share: the pass, the options that change its numbers and the
 * scene's shape (its counts, mesh by mesh). */
static uint64_t run_fingerprint(const scene *s, const sppm_options *o, const sppm_pass *pass,
                                const sppm_summary *summary)
{
    const double numbers[] = {pass->pass, o->iterations, summary->photons, o->seed, o->alpha,
                              summary->width, summary->height, o->max_depth, o->radius,
                              o->generic, (double)s->triangle_count, (double)s->light_count,
                              (double)s->mesh_count, (double)s->features};
    uint64_t hash = hash_fnv1a(HASH_FNV1A_START, numbers, sizeof numbers);
    if (pass->defines)
        hash = hash_fnv1a(hash, pass->defines, strlen(pass->defines));
    for (size_t m = 0; m < s->mesh_count; m++) {
        const uint32_t counts[2] = {s->meshes[m].vertex_count, s->meshes[m].triangle_count};
        hash = hash_fnv1a(hash, counts, sizeof counts);
    }
    return hash;
}

/* Under mpirun: every rank runs the same pass on the same scene (a rank with another scene or
 * other options would add sums of another simulation); the first meeting of the ranks in a
 * run, so a rank that failed before it stops the others here. */
static int check_ranks_agree(const scene *s, const sppm_options *o, const sppm_pass *pass,
                             const sppm_summary *summary)
{
    if (ranks_count() == 1)
        return 0;
    if (ranks_sync(0, NULL))
        return -1;
    uint64_t mine = run_fingerprint(s, o, pass, summary), first = mine;
    ranks_broadcast(&first, sizeof first);
    if (first != mine)
        return error_set(IDMR_EXIT_INPUT,
                         "the %s pass has another scene or other options than on rank 0: every "
                         "rank must run the same command on the same scene",
                         pass->name);
    return 0;
}

int sppm_run_devices(device *devices, unsigned int count, const scene *s, const bvh *b,
                     const sppm_options *o, sppm_pass *pass, sppm_summary *summary,
                     sppm_snapshot *snapshot)
{
    memset(summary, 0, sizeof *summary);
    if (count == 0 || count > SPPM_MAX_DEVICES || (snapshot && count > 1)) {
        pass->release(pass->state);
        return error_set(IDMR_EXIT_INPUT,
                         count > 1 && count <= SPPM_MAX_DEVICES
                             ? "%s: snapshots are taken on one device (asked for %u)"
                             : "%s: a run takes 1 to " SPPM_MAX_DEVICES_TEXT " devices (asked for %u)",
                         pass->name, count);
    }
    unsigned int counts[SPPM_MAX_DEVICES], capacity[SPPM_MAX_DEVICES];
    sppm_memory memory[SPPM_MAX_DEVICES];
    unsigned int rank_first = 0, rank_paths = 0;
    int status = check_inputs(devices, s, o, pass, summary);
    if (!status) {
        /* this rank's photon paths (all of them in one process, or for a pass that does not
         * add its sums over ranks) */
        rank_paths = summary->photons;
        if (pass->ranks)
            ranks_split(summary->photons, &rank_first, &rank_paths);
        first_split(o, devices, count, rank_paths, counts, capacity);
        for (unsigned int k = 0; k < count && !status; k++) {
            memory_of_capacity(s, bvh_device_bytes(b), summary->width * summary->height,
                               capacity[k], pass, memory + k);
            status = check_device_memory(devices + k, count, o, pass, memory + k);
        }
    }
    status = status || check_ranks_agree(s, o, pass, summary);
    if (status) {
        pass->release(pass->state);
        return -1;
    }
    summary->devices = count;
    sppm cores[SPPM_MAX_DEVICES];
    memset(cores, 0, sizeof cores);
    for (unsigned int k = 0; k < count; k++) {
        cores[k] = (sppm){.dev = devices + k, .index = k, .scene = s, .options = o,
                          .summary = summary, .pixels = summary->width * summary->height,
                          .capacity = capacity[k], .rank_first = rank_first,
                          .rank_paths = rank_paths};
        sppm_device_share *share = summary->device + k;
        share->index = devices[k].info.index;
        snprintf(share->name, sizeof share->name, "%s", devices[k].info.name);
        share->capacity = capacity[k];
    }
    unsigned int uploaded = 0;
    for (; uploaded < count && !status; uploaded++) {
        status = device_scene_upload(devices + uploaded, s, b, &cores[uploaded].uploaded);
        if (status && count > 1)
            error_prefix("device %d (%s)", devices[uploaded].info.index,
                         devices[uploaded].info.name);
    }
    if (o->release_bvh)
        bvh_free(o->release_bvh);
    for (unsigned int k = 0; k < count && !status; k++) {
        params_begin(cores + k);
        status = build_program(cores + k, pass) || allocate(cores + k, pass) ||
                 pass->prepare(cores + k, pass->state);
        if (status && count > 1)
            error_prefix("device %d (%s)", devices[k].info.index, devices[k].info.name);
    }
    if (!status) {
        summary->bvh_bytes = cores[0].uploaded.bvh_bytes;
        summary->geometry_bytes = cores[0].uploaded.bytes - cores[0].uploaded.bvh_bytes;
        set_ranges(cores, count, counts);
        status = run_iterations(cores, count, pass, snapshot) ||
                 (pass->finish && pass->finish(cores, pass->state));
    }
    pass->release(pass->state);
    for (unsigned int k = 0; k < count; k++) {
        summary->device[k].bytes = cores[k].uploaded.bytes + cores[k].buffer_bytes;
        release(cores + k);
    }
    summary->buffer_bytes = cores[0].buffer_bytes;
    /* What was allocated is what sppm_memory_of() says a run allocates: budgets rely on it.
     * (The pass's finish hook runs on the first device alone: the others may allocate less.) */
    for (unsigned int k = 0; k < count && !status; k++)
        if (k == 0 ? summary->device[k].bytes != sppm_memory_total(memory + k)
                   : summary->device[k].bytes > sppm_memory_total(memory + k))
            status = error_set(IDMR_EXIT_FAILURE,
                               "internal error: the %s pass allocated %llu bytes on device %d, "
                               "but sppm_memory_of() says %llu",
                               pass->name, (unsigned long long)summary->device[k].bytes,
                               devices[k].info.index,
                               (unsigned long long)sppm_memory_total(memory + k));
    return status ? -1 : 0;
}

int sppm_run(device *d, const scene *s, const bvh *b, const sppm_options *o, sppm_pass *pass,
             sppm_summary *summary, sppm_snapshot *snapshot)
{
    return sppm_run_devices(d, 1, s, b, o, pass, summary, snapshot);
}
