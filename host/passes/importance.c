/* importance.c — the importance pass on the SPPM core (see importance.h): its buffers and
 * kernels (gather_count, path_importance, shadow_rays, pixel_centre_hits in kernels/sppm.cl),
 * reading the fixed-point accumulators into double sums every iteration, the convergence
 * measure and its stop rule, and the importance per triangle, vertex, mesh and instance copy.
 *
 * An accumulator holds one word per scene triangle and, in an instanced scene, one more per
 * instance of the two-level BVH after them (idmr/importance_layout.h): read back, added over
 * devices and ranks and checked together, then converted into the per-triangle sums and each
 * copy's totals. */
#include "passes/importance.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "core/ranks.h"
#include "device/bvh.h"
#include "device/program.h"

#define STOP_AFTER_CALM_ITERATIONS 3
#define PER_MILLION_SAMPLES 1e6

void importance_options_default(importance_options *o)
{
    memset(o, 0, sizeof *o);
    sppm_options_default(&o->sppm, 100);
    o->gamma = 1.0f;
    o->shadow_weight = 1.0f;
    o->tolerance = 0.0;
    o->accumulate_importance = 1;
}

void importance_defines(int accumulate_importance, int camera_importance, int shadows, char *out,
                        size_t size)
{
    snprintf(out, size,
             "-D IDMR_ACCUMULATE_IMPORTANCE=%d -D IDMR_CAMERA_IMPORTANCE=%d "
             "-D IDMR_SHADOW_IMPORTANCE=%d",
             accumulate_importance ? 1 : 0, camera_importance ? 1 : 0, shadows ? 1 : 0);
}

importance_weights importance_weights_of(const importance_options *o)
{
    importance_weights w = {o->gamma, o->shadow_weight};
    return w;
}

/* The accumulators of the pass: the three of importance_result's sums, in their order, and the
 * light camera paths see through specular surfaces, which is added to light importance. */
enum { CAMERA, LIGHT, SHADOW, SEEN_LIGHT, KINDS };
static const char *const KIND_NAMES[KINDS] = {"camera importance", "light importance",
                                              "shadow importance", "seen light"};

/* path_importance's arguments before an instanced scene's record instances (prepare binds
 * those, gather the others). */
#define PATH_IMPORTANCE_ARGUMENTS 6

/* The pass's kernels and buffers on one device of the run. Camera importance, shadow
 * importance and seen light are added on the first device only (sppm.h); every device adds
 * light importance for its own photon paths. */
typedef struct importance_device {
    cl_kernel gather, path, shadow, centre_hits;
    cl_mem gathered, accumulators[KINDS];
    cl_mem pixel_weights; /* options' pixel weights (unweighted: not read) */
    cl_mem record_instances; /* an instanced scene: the instance of each photon record */
    double path_seconds;   /* its path walks, summed */
    double shadow_seconds; /* its shadow rays, summed */
} importance_device;

/* The pass's part while the core runs. */
typedef struct importance_pass {
    const importance_options *options;
    importance_result *result;
    int shadows; /* σ > 0: shadow rays */
    double total_power; /* Σ of the lights' luminous power (scene_finalize) */
    importance_device device[SPPM_MAX_DEVICES]; /* by sppm.index */
    size_t words;     /* accumulator words allocated: pass_sizes.words */
    size_t triangles; /* scene triangles: the accumulators' first words */
    size_t instances; /* instances of the two-level BVH, a word each after them (0: flat) */
    size_t *instance_mesh; /* per instance, the scene mesh it places (bvh_scene_instances) */
    double *instance_sums[SHADOW + 1]; /* per instance, its totals of camera, light (the
                                          seen light included) and shadow importance */
    uint64_t *read_back[SPPM_MAX_DEVICES]; /* each device's accumulator of one kind, read back */
    uint64_t *combined[KINDS]; /* each kind's words, the devices' (and ranks') added */
    double *previous;  /* each triangle's weighted sum before this iteration */
    unsigned int calm; /* iterations in a row with Δ below the tolerance */
} importance_pass;

/* The result's sums of kind k. */
static double *sums_of(const importance_result *r, int k)
{
    return k == CAMERA ? r->camera : k == LIGHT ? r->light : r->shadow;
}

/* The largest luminance a camera path can see on an emitter: an area light's, the environment
 * map's brightest texel (point, spot and directional lights cannot be seen). */
static double brightest_visible_luminance(const scene *s)
{
    double brightest = 0;
    for (size_t i = 0; i < s->light_count; i++)
        if (s->lights[i].kind == IDMR_LIGHT_AREA) {
            const float *e = s->lights[i].emission;
            brightest = fmax(brightest, idmr_luminance(e[0], e[1], e[2]));
        }
    const scene_environment *env = &s->environment;
    for (size_t i = 0; i < (size_t)env->width * (size_t)env->height; i++) {
        const float *e = env->rgb + 3 * i;
        brightest = fmax(brightest, idmr_luminance(e[0], e[1], e[2]));
    }
    return isfinite(brightest) ? brightest : 0;
}

/* The sizes of the pass's buffers: per photon slot a gather count, per kind an accumulator word
 * per scene triangle and per instance (one at least), an instanced scene's instance per photon
 * slot, and (finish) the triangle seen through each pixel: one place for prepare(), finish()
 * and pass_bytes(). */
typedef struct pass_sizes {
    size_t words; /* accumulator words per kind */
    size_t gathered, accumulator, record_instances, pixel_triangles, pixel_weights; /* bytes */
} pass_sizes;

static pass_sizes sizes_of(const scene *s, unsigned int pixels, size_t slots)
{
    pass_sizes z;
    size_t instances = bvh_scene_instances(s, NULL);
    z.words = (size_t)s->triangle_count + instances;
    if (z.words == 0)
        z.words = 1;
    z.gathered = slots * sizeof(cl_uint);
    z.accumulator = z.words * sizeof(cl_ulong);
    z.record_instances = instances ? slots * sizeof(cl_uint) : 0;
    z.pixel_triangles = (size_t)pixels * sizeof(cl_uint);
    z.pixel_weights = (size_t)pixels * sizeof(cl_uint);
    return z;
}

static uint64_t pass_bytes(const scene *s, unsigned int pixels, size_t slots)
{
    pass_sizes z = sizes_of(s, pixels, slots);
    return (uint64_t)z.gathered + KINDS * (uint64_t)z.accumulator + z.record_instances +
           z.pixel_triangles + z.pixel_weights;
}

static int prepare(sppm *core, void *state)
{
    importance_pass *p = state;
    importance_device *d = p->device + core->index;
    /* Seen light in fixed point: the brightest emitter seen head-on through one specular
     * surface is IDMR_FIXED_SCALE units, as the largest Eq. 2 weight is; 0: nothing to see. */
    double brightest = brightest_visible_luminance(core->scene);
    core->params.fixed_scale = brightest > 0 ? (float)(IDMR_FIXED_SCALE / brightest) : 0.0f;
    pass_sizes z = sizes_of(core->scene, core->pixels, core->slots);
    p->words = z.words;
    const device_buffer_request buffers[] = {
        {&d->gathered, z.gathered, "gather counts"},
        {&d->accumulators[CAMERA], z.accumulator, KIND_NAMES[CAMERA]},
        {&d->accumulators[LIGHT], z.accumulator, KIND_NAMES[LIGHT]},
        {&d->accumulators[SHADOW], z.accumulator, KIND_NAMES[SHADOW]},
        {&d->accumulators[SEEN_LIGHT], z.accumulator, KIND_NAMES[SEEN_LIGHT]},
    };
    if (!p->previous)
        p->previous = xcalloc(p->words, sizeof *p->previous);
    const importance_options *o = p->options;
    if (o->pixel_weights && (o->pixel_weights_width != core->params.width ||
                             o->pixel_weights_height != core->params.height))
        return error_set(IDMR_EXIT_FAILURE,
                         "importance: pixel weights are %ux%u, the pass's film %ux%u",
                         o->pixel_weights_width, o->pixel_weights_height, core->params.width,
                         core->params.height);
    /* Unweighted, the buffer is allocated (so that the memory is the same either way) but
     * neither written nor read. */
    core->params.pixel_weighted = o->pixel_weights != NULL;
    if (device_buffer(core->dev, CL_MEM_READ_ONLY, z.pixel_weights, o->pixel_weights,
                      "pixel weights", &d->pixel_weights))
        return -1;
    core->buffer_bytes += z.pixel_weights;
    if (device_create_kernel(core->program, "gather_count", &d->gather) ||
        device_create_kernel(core->program, "path_importance", &d->path) ||
        device_create_kernel(core->program, "pixel_centre_hits", &d->centre_hits) ||
        (p->shadows && device_create_kernel(core->program, "shadow_rays", &d->shadow)) ||
        device_buffers(core->dev, buffers, sizeof buffers / sizeof *buffers,
                       &core->buffer_bytes))
        return -1;
    for (int k = 0; k < KINDS; k++)
        if (device_clear(core->dev, d->accumulators[k], p->words * sizeof(cl_ulong),
                         KIND_NAMES[k]))
            return -1;
    /* An instanced scene: photon_paths writes each record's instance, path_importance reads
     * it (kernels/sppm.cl, after their other arguments). */
    if (p->instances &&
        (device_buffer(core->dev, CL_MEM_READ_WRITE, z.record_instances, NULL,
                       "photon record instances", &d->record_instances) ||
         DEVICE_SET_ARG(core->photon_paths, "photon_paths", core->photon_pass_argument,
                        d->record_instances) ||
         DEVICE_SET_ARG(d->path, "path_importance", PATH_IMPORTANCE_ARGUMENTS,
                        d->record_instances)))
        return -1;
    core->buffer_bytes += z.record_instances;
    return DEVICE_SET_ARGS_FROM(core->camera_paths, "camera_paths", core->camera_pass_argument,
                                DEVICE_ARG(d->accumulators[CAMERA]),
                                DEVICE_ARG(d->accumulators[SEEN_LIGHT]),
                                DEVICE_ARG(d->pixel_weights));
}

/* One shadow ray per hit point (kernels/lib/shadows.h). */
static int cast_shadow_rays(sppm *core, importance_device *p)
{
    idmr_camera camera = core->scene->camera;
    cl_uint after_scene = 2 + DEVICE_SCENE_BUFFERS;
    return DEVICE_SET_ARGS(p->shadow, "shadow_rays", DEVICE_ARG(core->params),
                           DEVICE_ARG(camera)) ||
                   device_scene_set_args(&core->uploaded, p->shadow, "shadow_rays", 2) ||
                   DEVICE_SET_ARGS_FROM(p->shadow, "shadow_rays", after_scene,
                                        DEVICE_ARG(core->hit_points),
                                        DEVICE_ARG(p->accumulators[SHADOW]),
                                        DEVICE_ARG(p->pixel_weights)) ||
                   device_run(core->dev, p->shadow, "shadow_rays", core->pixels,
                              core->options->local_size)
               ? -1
               : 0;
}

/* The shadow rays (first device only: their sum is counted once), gather_count, then (when
 * importance accumulates) the reverse path walk of this device's paths. Runs on every device at
 * once: it touches only the device's own part of the state. */
static int gather(sppm *core, void *state)
{
    importance_pass *p = state;
    importance_device *d = p->device + core->index;
    size_t local = core->options->local_size;
    double shadows_start = monotonic_seconds();
    if (p->shadows && core->params.camera_sums && cast_shadow_rays(core, d))
        return -1;
    d->shadow_seconds += monotonic_seconds() - shadows_start;
    if (DEVICE_SET_ARGS(d->gather, "gather_count", DEVICE_ARG(core->params),
                        DEVICE_ARG(core->photon_records), DEVICE_ARG(core->stored_count),
                        DEVICE_ARG(core->grid.cell_start), DEVICE_ARG(core->grid.grid_hits),
                        DEVICE_ARG(d->gathered), DEVICE_ARG(d->pixel_weights)) ||
        (core->stored &&
         device_run(core->dev, d->gather, "gather_count", core->stored, local)))
        return -1;
    if (!p->options->accumulate_importance)
        return 0;
    double start = monotonic_seconds();
    if (DEVICE_SET_ARGS(d->path, "path_importance", DEVICE_ARG(core->params),
                        DEVICE_ARG(core->photon_records), DEVICE_ARG(core->path_length),
                        DEVICE_ARG(core->record_index), DEVICE_ARG(d->gathered),
                        DEVICE_ARG(d->accumulators[LIGHT])) ||
        (core->params.device_paths &&
         device_run(core->dev, d->path, "path_importance", core->params.device_paths, local)))
        return -1;
    d->path_seconds += monotonic_seconds() - start;
    return 0;
}

int importance_add_words(double *sums, const uint64_t *const *words, unsigned int count,
                         size_t n, double scale, const char *what, const char *remedy,
                         double *added)
{
    double total = 0;
    for (size_t t = 0; t < n; t++) {
        /* each word and each partial sum below the saturation limit (2^62): no overflow */
        uint64_t sum = 0;
        for (unsigned int j = 0; j < count; j++)
            if (words[j][t] >= IDMR_FIXED_SATURATION ||
                (sum += words[j][t]) >= IDMR_FIXED_SATURATION)
                return error_set(IDMR_EXIT_FAILURE,
                                 "%s of triangle %zu came within a factor 2 of the 64-bit "
                                 "fixed-point limit in one iteration; use %s",
                                 what, t, remedy);
        double value = scale * (double)sum; /* the one conversion */
        sums[t] += value;
        total += value;
        CHECK_FINITE(sums[t], what);
    }
    if (added)
        *added += total;
    return 0;
}

/* The remedy a saturation error of kind k names. */
static const char *remedy_of(int k)
{
    return k == LIGHT ? "fewer photons per iteration" : "a smaller --resolution";
}

/* Accumulator word t's name in a message: its triangle's, or its instance's and mesh's. */
static void word_name(const importance_pass *p, const scene *s, size_t t, char *out,
                      size_t size)
{
    size_t i = t - p->triangles, m = t < p->triangles ? 0 : p->instance_mesh[i];
    if (t < p->triangles)
        snprintf(out, size, "triangle %zu", t);
    else if (m == BVH_NO_MESH)
        snprintf(out, size, "the total of instance %zu (the meshes that are not instanced)", i);
    else
        snprintf(out, size, "the total of instance %zu (mesh '%s')", i, s->meshes[m].name);
}

/* Reads accumulator k of the first `count` devices back, clears them, and adds their words as
 * integers into p->combined[k] (importance_add_words' checks: no word or partial sum at the
 * saturation limit). */
static int read_accumulator(sppm *cores, unsigned int count, importance_pass *p, int k)
{
    size_t n = p->triangles + p->instances;
    for (unsigned int j = 0; j < count; j++) {
        cl_mem accumulator = p->device[j].accumulators[k];
        if (!p->read_back[j])
            p->read_back[j] = xmalloc(p->words * sizeof *p->read_back[j]);
        if ((n && device_read(cores[j].dev, accumulator, n * sizeof(cl_ulong), p->read_back[j],
                              KIND_NAMES[k])) ||
            device_clear(cores[j].dev, accumulator, p->words * sizeof(cl_ulong), KIND_NAMES[k]))
            return count > 1 ? error_prefix("device %d (%s)", cores[j].dev->info.index,
                                            cores[j].dev->info.name)
                             : -1;
    }
    if (!p->combined[k])
        p->combined[k] = xmalloc(p->words * sizeof *p->combined[k]);
    uint64_t *sum = p->combined[k];
    for (size_t t = 0; t < n; t++) {
        sum[t] = 0;
        for (unsigned int j = 0; j < count; j++)
            if (p->read_back[j][t] >= IDMR_FIXED_SATURATION ||
                (sum[t] += p->read_back[j][t]) >= IDMR_FIXED_SATURATION) {
                char name[256];
                word_name(p, cores->scene, t, name, sizeof name);
                return error_set(IDMR_EXIT_FAILURE,
                                 "%s of %s came within a factor 2 of the 64-bit fixed-point "
                                 "limit in one iteration; use %s",
                                 KIND_NAMES[k], name, remedy_of(k));
            }
    }
    return 0;
}

/* p->combined[k] (every device's and rank's words) added to the per-triangle `sums` and, in an
 * instanced scene, its instance words to the instances' totals of kind `into` (importance_add_words:
 * × scale per fixed-point unit, the one conversion); adds the triangles' total it added to
 * *added where that is not NULL. */
static int add_combined(importance_pass *p, int k, int into, double *sums, double scale,
                        double *added)
{
    const uint64_t *words[1] = {p->combined[k]}, *instance_words[1] = {words[0] + p->triangles};
    return importance_add_words(sums, words, 1, p->triangles, scale, KIND_NAMES[k], remedy_of(k),
                                added) ||
                   (p->instances &&
                    importance_add_words(p->instance_sums[into], instance_words, 1, p->instances,
                                         scale, KIND_NAMES[k], remedy_of(k), NULL))
               ? -1
               : 0;
}

/* The result's copy totals from the instances' (each instance but prototype 0's places one
 * mesh). */
static void set_copy_totals(const importance_pass *p, importance_result *r)
{
    double *copies[SHADOW + 1] = {r->copy_camera, r->copy_light, r->copy_shadow};
    for (size_t i = 0; i < p->instances; i++)
        if (p->instance_mesh[i] != BVH_NO_MESH)
            for (int k = CAMERA; k <= SHADOW; k++)
                copies[k][p->instance_mesh[i]] = p->instance_sums[k][i];
}

/* Hit points found by the first iteration's photon vertices on one device, for the report:
 * the gather counts of its list of records. */
static int count_gathered(sppm *core, importance_pass *p, uint64_t *found)
{
    const importance_device *d = p->device + core->index;
    uint32_t *gathered = xmalloc((core->stored + 1) * sizeof *gathered);
    int status = core->stored && device_read(core->dev, d->gathered,
                                             core->stored * sizeof *gathered, gathered,
                                             "gather counts");
    for (size_t i = 0; i < core->stored && !status; i++)
        *found += gathered[i];
    free(gathered);
    return status;
}

/* A sum of kind k over the iterations so far (a triangle's, a copy's), per million of its
 * samples (photon paths for light importance, pixels of the hit-point image for the others). */
static double per_million(const importance_result *r, int k, double sum)
{
    double samples = k == LIGHT ? r->sppm.photons : (double)r->sppm.width * r->sppm.height;
    return samples > 0 ? PER_MILLION_SAMPLES * sum / samples : 0.0;
}

/* The weighted sum of a triangle's or a copy's sums over the iterations so far: A(T)
 * (importance.h) times iterations. */
static double weighted(const importance_result *r, const importance_weights *w, double camera,
                       double light, double shadow)
{
    return w->gamma * per_million(r, CAMERA, camera) + per_million(r, LIGHT, light) +
           w->shadow * per_million(r, SHADOW, shadow);
}

/* Triangle t's weighted sum (above). */
static double weighted_sum(const importance_result *r, const importance_weights *w, uint64_t t)
{
    return weighted(r, w, r->camera[t], r->light[t], r->shadow[t]);
}

/* Δ_n (importance.h) from the sums after n iterations and the ones before (p->previous), which
 * it then replaces. */
static double convergence_change(importance_pass *p, const scene *s, unsigned int n)
{
    const importance_result *r = p->result;
    importance_weights w = importance_weights_of(p->options);
    double change = 0, magnitude = 0;
    for (size_t t = 0; t < r->triangle_count; t++) {
        double area = scene_triangle_area(s, t), sum = weighted_sum(r, &w, t);
        double before = p->previous[t];
        p->previous[t] = sum;
        if (!(area > 0))
            continue;
        double now_per_area = sum / (n * area);
        double before_per_area = n > 1 ? before / ((n - 1) * area) : 0.0;
        change += (now_per_area - before_per_area) * (now_per_area - before_per_area);
        magnitude += now_per_area * now_per_area;
    }
    return magnitude > 0 ? change / magnitude : 0.0;
}

/* The gathers a unit of seen light counts as this iteration (importance.h): a white diffuse
 * surface showing luminance Y receives irradiance π Y, and its hit point gathers that times
 * π r² over the photon's share of the power, Φ / photons; times IMPORTANCE_SEEN_LIGHT_WEIGHT. */
static double seen_light_gathers(const sppm *core, const importance_pass *p)
{
    double r = core->params.radius;
    return p->total_power > 0 ? IMPORTANCE_SEEN_LIGHT_WEIGHT * M_PI * M_PI * r * r *
                                    (double)core->params.path_count / p->total_power
                              : 0.0;
}

/* Whether the pass has accumulator k this run (camera and light always; shadow importance
 * with shadow rays; seen light where an emitter can be seen). */
static int has_kind(const sppm *core, const importance_pass *p, int k)
{
    return k == SHADOW ? p->shadows : k == SEEN_LIGHT ? core->params.fixed_scale > 0 : 1;
}

/* Light importance from every device's photon paths; camera importance, shadow importance and
 * seen light from the first device's alone (the others' camera paths add nothing, and they
 * cast no shadow rays). Under mpirun the same on every rank, then the light words are added
 * over the ranks (exact: integers) and the camera-side words (rank 0's alone: zero on the
 * others) copied from rank 0, before the one conversion. */
static int collect(sppm *cores, unsigned int count, void *state, unsigned int n, int *stop,
                   char *detail, size_t detail_size)
{
    importance_pass *p = state;
    importance_result *r = p->result;
    sppm *core = cores;
    int status = 0;
    for (int k = 0; k < KINDS && !status; k++)
        if (has_kind(core, p, k))
            status = read_accumulator(cores, k == LIGHT ? count : 1, p, k);
    uint64_t gathered = 0;
    for (unsigned int j = 0; j < count && n == 0 && !status; j++)
        status = count_gathered(cores + j, p, &gathered);
    if (ranks_sync(status, NULL))
        return -1;
    /* light importance from every rank's paths: summed; the camera side is rank 0's alone
     * (zero elsewhere): copied from it, which is the same sum at less cost */
    size_t n_words = p->triangles + p->instances;
    for (int k = 0; k < KINDS; k++)
        if (has_kind(core, p, k) && k == LIGHT)
            ranks_sum_words(p->combined[k], n_words);
        else if (has_kind(core, p, k))
            ranks_broadcast(p->combined[k], n_words * sizeof *p->combined[k]);
    if (n == 0) {
        ranks_sum_words(&gathered, 1);
        r->gathered = gathered;
    }
    for (int k = CAMERA; k <= SHADOW; k++)
        if (has_kind(core, p, k) &&
            add_combined(p, k, k, sums_of(r, k), 1.0 / IDMR_FIXED_SCALE, NULL))
            return -1;
    if (has_kind(core, p, SEEN_LIGHT) &&
        add_combined(p, SEEN_LIGHT, LIGHT, r->light,
                     seen_light_gathers(core, p) / core->params.fixed_scale, &r->seen_light))
        return -1;
    set_copy_totals(p, r);
    for (unsigned int j = 0; j < count; j++) {
        r->path_seconds = fmax(r->path_seconds, p->device[j].path_seconds);
        r->shadow_seconds = fmax(r->shadow_seconds, p->device[j].shadow_seconds);
    }
    r->convergence[n] = convergence_change(p, core->scene, n + 1);
    snprintf(detail, detail_size, "change %.2e", r->convergence[n]);
    double tolerance = p->options->tolerance;
    p->calm = tolerance > 0 && r->convergence[n] < tolerance ? p->calm + 1 : 0;
    *stop = p->calm >= STOP_AFTER_CALM_ITERATIONS;
    const importance_options *o = p->options;
    if (*stop || !o->checkpoint)
        return 0;
    r->sppm.iterations = n + 1; /* the core counts this iteration only after collect() */
    size_t used = strlen(detail);
    return o->checkpoint(o->checkpoint_context, r, stop, detail + used, detail_size - used);
}

static int snapshot(sppm *core, void *state)
{
    importance_pass *p = state;
    const importance_device *d = p->device; /* snapshots are taken on one device */
    importance_snapshot *out = p->options->snapshot;
    uint64_t **fixed[KINDS] = {&out->camera_fixed, &out->light_fixed, &out->shadow_fixed,
                               &out->seen_light_fixed};
    free(out->gathered);
    out->gathered = NULL;
    uint32_t *list = xmalloc((core->stored + 1) * sizeof *list);
    if (core->stored && device_read(core->dev, d->gathered, core->stored * sizeof *list, list,
                                    "gather counts")) {
        free(list);
        return -1;
    }
    out->gathered = sppm_snapshot_by_slot(&out->core, list, sizeof *list);
    free(list);
    for (int k = 0; k < KINDS; k++) {
        free(*fixed[k]);
        *fixed[k] = xmalloc(p->words * sizeof **fixed[k]);
        if (device_read(core->dev, d->accumulators[k], p->words * sizeof(cl_ulong), *fixed[k],
                        KIND_NAMES[k]))
            return -1;
    }
    return 0;
}

/* The triangle seen through each pixel centre of the hit-point image, for the importance
 * image: one more kernel on the (first device's) core's upload, not a second program or BVH. */
static int finish(sppm *core, void *state)
{
    importance_pass *state_pass = state;
    importance_device *p = state_pass->device + core->index;
    importance_result *r = state_pass->result;
    size_t pixels = core->pixels;
    idmr_camera camera = core->scene->camera;
    cl_mem triangles = NULL;
    r->pixel_triangle = xmalloc(pixels * sizeof *r->pixel_triangle);
    size_t bytes = sizes_of(core->scene, core->pixels, core->slots).pixel_triangles;
    core->buffer_bytes += bytes;
    int status =
        device_buffer(core->dev, CL_MEM_WRITE_ONLY, bytes, NULL, "pixel triangles",
                      &triangles) ||
        DEVICE_SET_ARGS(p->centre_hits, "pixel_centre_hits", DEVICE_ARG(core->params),
                        DEVICE_ARG(camera)) ||
        device_scene_set_args(&core->uploaded, p->centre_hits, "pixel_centre_hits", 2) ||
        DEVICE_SET_ARG(p->centre_hits, "pixel_centre_hits", 2 + DEVICE_SCENE_BUFFERS,
                       triangles) ||
        device_run(core->dev, p->centre_hits, "pixel_centre_hits", pixels, 0) ||
        device_read(core->dev, triangles, pixels * sizeof(cl_uint), r->pixel_triangle,
                    "pixel triangles");
    device_release_buffers(&triangles, 1);
    return status ? -1 : 0;
}

static void release(void *state)
{
    importance_pass *p = state;
    for (unsigned int j = 0; j < SPPM_MAX_DEVICES; j++) {
        importance_device *d = p->device + j;
        cl_kernel kernels[] = {d->gather, d->path, d->shadow, d->centre_hits};
        device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
        device_release_buffers(&d->gathered, 1);
        device_release_buffers(d->accumulators, KINDS);
        device_release_buffers(&d->pixel_weights, 1);
        device_release_buffers(&d->record_instances, 1);
    }
    for (unsigned int j = 0; j < SPPM_MAX_DEVICES; j++)
        free(p->read_back[j]);
    for (int k = 0; k < KINDS; k++)
        free(p->combined[k]);
    for (int k = CAMERA; k <= SHADOW; k++)
        free(p->instance_sums[k]);
    free(p->instance_mesh);
    free(p->previous);
}

void importance_snapshot_free(importance_snapshot *snapshot)
{
    sppm_snapshot_free(&snapshot->core);
    free(snapshot->gathered);
    free(snapshot->camera_fixed);
    free(snapshot->light_fixed);
    free(snapshot->shadow_fixed);
    free(snapshot->seen_light_fixed);
    memset(snapshot, 0, sizeof *snapshot);
}

/* The pass as the core sees it, before its state and hooks: what sizes its memory. */
static sppm_pass pass_on_core(void)
{
    return (sppm_pass){.name = "importance",
                       .pass = IDMR_SPPM_IMPORTANCE,
                       .photon_record_bytes = sizeof(idmr_photon_vertex),
                       .ranks = 1,
                       .pass_bytes = pass_bytes};
}

int importance_memory(const device *d, const scene *s, uint64_t bvh_bytes,
                      const importance_options *o, sppm_memory *m)
{
    sppm_pass pass = pass_on_core();
    return sppm_memory_of(d, s, bvh_bytes, &o->sppm, &pass, m);
}

int importance_build_program(device *d, const scene *s, const importance_options *o)
{
    char defines[128];
    importance_defines(o->accumulate_importance, o->gamma > 0, o->shadow_weight > 0, defines,
                       sizeof defines);
    char *options = sppm_build_options(d, sppm_program_features(s, &o->sppm),
                                       IDMR_SPPM_IMPORTANCE, defines);
    cl_program program;
    int status = device_build_program(d, "sppm.cl", options, &program);
    free(options);
    if (!status)
        clReleaseProgram(program);
    return status;
}

int importance_run(device *d, const scene *s, const bvh *b, const importance_options *o,
                   importance_result *r)
{
    return importance_run_devices(d, 1, s, b, o, r);
}

int importance_run_devices(device *devices, unsigned int count, const scene *s, const bvh *b,
                           const importance_options *o, importance_result *r)
{
    memset(r, 0, sizeof *r);
    if (!(o->gamma >= 0) || !(o->shadow_weight >= 0))
        return error_set(IDMR_EXIT_INPUT, "importance: gamma and the shadow weight must be >= 0");
    double total_power = 0;
    for (size_t i = 0; i < s->light_count; i++)
        total_power += s->lights[i].power > 0 ? s->lights[i].power : 0;
    if (!(total_power > 0))
        warn("%s: no light emits any power: light and shadow importance stay zero, importance "
             "comes from camera paths alone",
             s->file);
    r->triangle_count = (size_t)s->triangle_count;
    r->camera = xcalloc(r->triangle_count + 1, sizeof *r->camera);
    r->light = xcalloc(r->triangle_count + 1, sizeof *r->light);
    r->shadow = xcalloc(r->triangle_count + 1, sizeof *r->shadow);
    r->mesh_count = s->mesh_count;
    r->copy_camera = xcalloc(r->mesh_count + 1, sizeof *r->copy_camera);
    r->copy_light = xcalloc(r->mesh_count + 1, sizeof *r->copy_light);
    r->copy_shadow = xcalloc(r->mesh_count + 1, sizeof *r->copy_shadow);
    r->convergence = xcalloc(o->sppm.iterations + 1, sizeof *r->convergence);
    importance_pass state = {.options = o,
                             .result = r,
                             .shadows = o->shadow_weight > 0,
                             .total_power = total_power,
                             .triangles = (size_t)s->triangle_count};
    /* the instances in the order of the two-level BVH's records, which the kernels number */
    state.instance_mesh = xmalloc((s->mesh_count + 1) * sizeof *state.instance_mesh);
    state.instances = bvh_scene_instances(s, state.instance_mesh);
    if (state.instances != b->instance_count) {
        free(state.instance_mesh);
        return error_set(IDMR_EXIT_FAILURE,
                         "importance: the BVH has %zu instances, the scene %zu (a BVH of "
                         "another scene?)",
                         b->instance_count, state.instances);
    }
    for (int k = CAMERA; k <= SHADOW; k++)
        state.instance_sums[k] = xcalloc(state.instances + 1, sizeof *state.instance_sums[k]);
    char defines[128];
    importance_defines(o->accumulate_importance, o->gamma > 0, state.shadows, defines,
                       sizeof defines);
    sppm_pass pass = pass_on_core();
    pass.defines = defines;
    pass.state = &state;
    pass.prepare = prepare;
    pass.gather = gather;
    pass.collect = collect;
    pass.snapshot = o->snapshot ? snapshot : NULL;
    pass.finish = finish;
    pass.release = release;
    int status = sppm_run_devices(devices, count, s, b, &o->sppm, &pass, &r->sppm,
                                  o->snapshot ? &o->snapshot->core : NULL);
    if (o->snapshot)
        o->snapshot->vertices = o->snapshot->core.photon_records;
    return status;
}

void importance_result_free(importance_result *r)
{
    free(r->camera);
    free(r->light);
    free(r->shadow);
    free(r->copy_camera);
    free(r->copy_light);
    free(r->copy_shadow);
    free(r->convergence);
    free(r->pixel_triangle);
    sppm_summary_free(&r->sppm);
    memset(r, 0, sizeof *r);
}

double importance_amount(const importance_result *r, const importance_weights *w, uint64_t t)
{
    return r->sppm.iterations ? weighted_sum(r, w, t) / r->sppm.iterations : 0.0;
}

double importance_triangle(const importance_result *r, const scene *s,
                           const importance_weights *w, uint64_t t)
{
    double area = scene_triangle_area(s, t);
    return area > 0 ? importance_amount(r, w, t) / area : 0.0;
}

void importance_mesh_vertices(const importance_result *r, const scene *s, size_t m,
                              const importance_weights *w, double *vertex_importance)
{
    const scene_mesh *mesh = &s->meshes[m];
    double *area = xcalloc(mesh->vertex_count + 1, sizeof *area);
    memset(vertex_importance, 0, mesh->vertex_count * sizeof *vertex_importance);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        double a = scene_mesh_triangle_area(mesh, t);
        double amount = importance_amount(r, w, (uint64_t)mesh->first_triangle + t);
        for (int k = 0; k < 3; k++) {
            uint32_t v = mesh->indices[3 * (size_t)t + k];
            vertex_importance[v] += amount;
            area[v] += a;
        }
    }
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        vertex_importance[v] = area[v] > 0 ? vertex_importance[v] / area[v] : 0.0;
        CHECK_FINITE(vertex_importance[v], "vertex importance");
    }
    free(area);
}

importance_sums importance_mesh_sums(const importance_result *r, const scene *s, size_t m,
                                     const importance_weights *w)
{
    const scene_mesh *mesh = &s->meshes[m];
    importance_sums sums = {0, 0, 0, 0};
    double iterations = r->sppm.iterations;
    for (uint32_t t = 0; t < mesh->triangle_count && iterations > 0; t++) {
        uint64_t global = (uint64_t)mesh->first_triangle + t;
        sums.amount += weighted_sum(r, w, global) / iterations;
        sums.camera += per_million(r, CAMERA, r->camera[global]) / iterations;
        sums.light += per_million(r, LIGHT, r->light[global]) / iterations;
        sums.shadow += per_million(r, SHADOW, r->shadow[global]) / iterations;
    }
    return sums;
}

importance_sums importance_copy_sums(const importance_result *r, const scene *s, size_t m,
                                     const importance_weights *w)
{
    importance_sums sums = {0, 0, 0, 0};
    double iterations = r->sppm.iterations;
    if (!s->meshes[m].instanced || m >= r->mesh_count || !r->copy_camera || !(iterations > 0))
        return sums;
    double camera = r->copy_camera[m], light = r->copy_light[m], shadow = r->copy_shadow[m];
    sums.amount = weighted(r, w, camera, light, shadow) / iterations;
    sums.camera = per_million(r, CAMERA, camera) / iterations;
    sums.light = per_million(r, LIGHT, light) / iterations;
    sums.shadow = per_million(r, SHADOW, shadow) / iterations;
    return sums;
}
