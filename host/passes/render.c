/* render.c — the renderer on the SPPM core (see render.h): its buffers, the gather that adds
 * every photon's contribution to the pixels of the hit points that reach it (render_gather in
 * kernels/sppm.cl), the fixed-point scale, and the mean of the iterations' estimates; then the
 * image files and the report. */
#include "passes/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image.h"
#include "core/spectrum.h"

void render_options_default(render_options *o)
{
    memset(o, 0, sizeof *o);
    sppm_options_default(&o->sppm, 64);
    o->sppm.max_depth = IDMR_RENDER_DEPTH;
}

void render_snapshot_free(render_snapshot *snapshot)
{
    sppm_snapshot_free(&snapshot->core);
    memset(snapshot, 0, sizeof *snapshot);
}

/* The pass's part while the core runs. */
typedef struct render_pass {
    const render_options *options;
    render_result *result;
    cl_kernel gather;
    cl_mem render_hits, pixel_radiance;
    double *sum;              /* per pixel and channel: the sum of the iterations' estimates */
    uint64_t *units;          /* a read-back of pixel_radiance */
    idmr_render_hit *hits;    /* a read-back of render_hits */
} render_pass;

/* Fixed-point units per unit of (throughput × BRDF × flux): one photon of the brightest light
 * (the largest flux a photon starts with) on a white diffuse surface, whose contribution is
 * Φ_max / π before the 1/(π r²) the host divides by, becomes IDMR_RENDER_PHOTON_UNITS. Light
 * probabilities are in proportion to power, as the light CDF holds them. 0 if no light emits. */
static double fixed_scale(const scene *s, float scene_radius, unsigned int photons)
{
    double total_power = 0, brightest = 0;
    for (size_t i = 0; i < s->light_count; i++)
        total_power += s->lights[i].power > 0 ? s->lights[i].power : 0;
    for (size_t i = 0; i < s->light_count && total_power > 0; i++) {
        const idmr_light *l = &s->lights[i];
        double probability = (l->power > 0 ? l->power : 0) / total_power;
        if (!(probability > 0))
            continue;
        double emission = fmax(l->emission[0], fmax(l->emission[1], l->emission[2]));
        double flux = emission * idmr_light_sample_factor(l->kind, l->area, l->cos_cutoff,
                                                          scene_radius) /
                      (probability * photons);
        brightest = fmax(brightest, flux);
    }
    return brightest > 0 && isfinite(brightest) ? IDMR_RENDER_PHOTON_UNITS * M_PI / brightest : 0;
}

/* The sizes of the pass's buffers: per pixel its hit point's throughput and its radiance sums
 * (three 64-bit words): one place for prepare() and pass_bytes(). */
static void pass_sizes(unsigned int pixels, size_t bytes[2])
{
    bytes[0] = (size_t)pixels * sizeof(idmr_render_hit);
    bytes[1] = (size_t)pixels * 3 * sizeof(cl_ulong);
}

static uint64_t pass_bytes(const scene *s, unsigned int pixels, size_t slots)
{
    (void)s;
    (void)slots;
    size_t bytes[2];
    pass_sizes(pixels, bytes);
    return (uint64_t)bytes[0] + bytes[1];
}

static int prepare(sppm *core, void *state)
{
    render_pass *p = state;
    const scene *s = core->scene;
    core->params.fixed_scale =
        (float)fixed_scale(s, core->params.scene_radius, core->params.path_count);
    if (!(core->params.fixed_scale > 0) || !isfinite(core->params.fixed_scale))
        return error_set(IDMR_EXIT_INPUT, "%s: no light emits any power: the image would be black",
                         s->file);
    size_t pixels = core->pixels, bytes[2];
    pass_sizes(core->pixels, bytes);
    const device_buffer_request buffers[] = {
        {&p->render_hits, bytes[0], "hit point throughputs"},
        {&p->pixel_radiance, bytes[1], "pixel radiance"},
    };
    p->sum = xcalloc(pixels * 3, sizeof *p->sum);
    p->units = xmalloc(pixels * 3 * sizeof *p->units);
    p->hits = xmalloc(pixels * sizeof *p->hits);
    return device_create_kernel(core->program, "render_gather", &p->gather) ||
                   device_buffers(core->dev, buffers, sizeof buffers / sizeof *buffers,
                                  &core->buffer_bytes) ||
                   device_clear(core->dev, p->pixel_radiance, pixels * 3 * sizeof(cl_ulong),
                                "pixel radiance") ||
                   DEVICE_SET_ARG(core->camera_paths, "camera_paths", core->camera_pass_argument,
                                  p->render_hits)
               ? -1
               : 0;
}

static int gather(sppm *core, void *state)
{
    render_pass *p = state;
        return DEVICE_SET_ARGS(p->gather, "render_gather", DEVICE_ARG(core->params),
                           DEVICE_ARG(core->photon_records), DEVICE_ARG(core->stored_count),
                           DEVICE_ARG(p->render_hits),
                           DEVICE_ARG(core->uploaded.materials),
                           DEVICE_ARG(core->grid.cell_start), DEVICE_ARG(core->grid.grid_hits),
                           DEVICE_ARG(p->pixel_radiance)) ||
                   (core->stored && device_run(core->dev, p->gather, "render_gather",
                                               core->stored, core->options->local_size))
               ? -1
               : 0;
}

/* Adds this iteration's estimate to the sum: the emission seen directly plus the photon
 * estimate, units / (fixed_scale π r²). Checks saturation; clears the accumulators. The
 * renderer runs on one device (render_run): `cores` is that device's core. */
static int collect(sppm *cores, unsigned int count, void *state, unsigned int n, int *stop,
                   char *detail, size_t detail_size)
{
    (void)count;
    sppm *core = cores;
    render_pass *p = state;
    size_t pixels = core->pixels;
    const idmr_sppm_params *params = &core->params;
    if (device_read(core->dev, p->pixel_radiance, pixels * 3 * sizeof *p->units, p->units,
                    "pixel radiance") ||
        device_read(core->dev, p->render_hits, pixels * sizeof *p->hits, p->hits,
                    "directly seen emission"))
        return -1;
    double per_unit = 1.0 / ((double)params->fixed_scale * M_PI * (double)params->radius *
                             (double)params->radius);
    for (size_t i = 0; i < pixels; i++)
        for (int c = 0; c < 3; c++) {
            uint64_t u = p->units[3 * i + c];
            if (u >= IDMR_FIXED_SATURATION)
                return error_set(IDMR_EXIT_FAILURE,
                                 "the radiance of pixel (%zu, %zu) came within a factor 2 of the "
                                 "64-bit fixed-point limit in one iteration; use fewer photons "
                                 "per iteration",
                                 i % params->width, i / params->width);
            double e = p->hits[i].emitted[c];
            p->sum[3 * i + c] += (isfinite(e) ? e : 0.0) + (double)u * per_unit;
            CHECK_FINITE(p->sum[3 * i + c], "pixel radiance");
        }
    double elapsed = core->summary->seconds.camera + core->summary->seconds.photon +
                     core->summary->seconds.grid + core->summary->seconds.gather +
                     core->summary->seconds.collect;
    snprintf(detail, detail_size, "%.2f s/iteration", elapsed / (n + 1));
    *stop = 0;
    return device_clear(core->dev, p->pixel_radiance, pixels * 3 * sizeof *p->units,
                        "pixel radiance");
}

/* The image: the mean of the iterations' estimates. */
static int finish(sppm *core, void *state)
{
    render_pass *p = state;
    size_t values = (size_t)core->pixels * 3;
    unsigned int iterations = core->summary->iterations;
    p->result->image = xmalloc(values * sizeof *p->result->image);
    for (size_t i = 0; i < values; i++)
        p->result->image[i] = (float)(p->sum[i] / iterations);
    return 0;
}

static void release(void *state)
{
    render_pass *p = state;
    device_release_kernels(&p->gather, 1);
    cl_mem buffers[] = {p->render_hits, p->pixel_radiance};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    free(p->sum);
    free(p->units);
    free(p->hits);
}

/* The pass as the core sees it, before its state and hooks: what sizes its memory. */
static sppm_pass pass_on_core(void)
{
    return (sppm_pass){.name = "render",
                       .pass = IDMR_SPPM_RENDER,
                       .photon_record_bytes = sizeof(idmr_render_photon),
                       .pass_bytes = pass_bytes};
}

int render_memory(const device *d, const scene *s, uint64_t bvh_bytes, const render_options *o,
                  sppm_memory *m)
{
    sppm_pass pass = pass_on_core();
    return sppm_memory_of(d, s, bvh_bytes, &o->sppm, &pass, m);
}

int render_run(device *d, const scene *s, const bvh *b, const render_options *o,
               render_result *r)
{
    memset(r, 0, sizeof *r);
    render_pass state;
    memset(&state, 0, sizeof state);
    state.options = o;
    state.result = r;
    sppm_pass pass = pass_on_core();
    pass.state = &state;
    pass.prepare = prepare;
    pass.gather = gather;
    pass.collect = collect;
    pass.finish = finish;
    pass.release = release;
    int status =
        sppm_run(d, s, b, &o->sppm, &pass, &r->sppm, o->snapshot ? &o->snapshot->core : NULL);
    if (o->snapshot)
        o->snapshot->photons = o->snapshot->core.photon_records;
    return status;
}

void render_result_free(render_result *r)
{
    free(r->image);
    sppm_summary_free(&r->sppm);
    memset(r, 0, sizeof *r);
}

int render_write_images(const render_result *r, const char *exr_path, const char *png_path,
                        double ev)
{
    if (exr_path &&
        image_write_rgb_float(exr_path, (int)r->sppm.width, (int)r->sppm.height, r->image))
        return -1;
    if (!png_path)
        return 0;
    size_t values = (size_t)r->sppm.width * r->sppm.height * 3;
    unsigned char *bytes = xmalloc(values);
    float exposure = (float)pow(2.0, ev);
    for (size_t i = 0; i < values; i++) {
        float encoded = spectrum_linear_to_srgb(r->image[i] * exposure);
        bytes[i] = (unsigned char)(fminf(encoded, 1.0f) * 255.0f + 0.5f);
    }
    int status = image_write_rgb8(png_path, (int)r->sppm.width, (int)r->sppm.height, bytes);
    free(bytes);
    return status;
}

cJSON *render_report_json(const scene *s, const device *d, const render_options *o,
                          const render_result *r)
{
    const sppm_summary *run = &r->sppm;
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddStringToObject(root, "device", d->info.name);
    cJSON_AddNumberToObject(root, "width", run->width);
    cJSON_AddNumberToObject(root, "height", run->height);
    cJSON_AddNumberToObject(root, "iterations", run->iterations);
    cJSON_AddNumberToObject(root, "photons_per_iteration", run->photons);
    cJSON_AddNumberToObject(root, "photons_stored_first_iteration", (double)run->photon_records);
    cJSON_AddNumberToObject(root, "seed", o->sppm.seed);
    cJSON_AddNumberToObject(root, "alpha", o->sppm.alpha);
    cJSON_AddNumberToObject(root, "max_depth", o->sppm.max_depth);
    cJSON_AddNumberToObject(root, "first_radius", run->iterations ? run->radius[0] : 0);
    cJSON_AddNumberToObject(root, "last_radius",
                            run->iterations ? run->radius[run->iterations - 1] : 0);
    cJSON_AddNumberToObject(root, "triangles", (double)s->rendered_triangle_count);
    cJSON_AddNumberToObject(root, "vertices", (double)s->rendered_vertex_count);
    cJSON *seconds = cJSON_AddObjectToObject(root, "seconds");
    double n = run->iterations ? run->iterations : 1;
    cJSON_AddNumberToObject(seconds, "build", run->seconds.build);
    cJSON_AddNumberToObject(seconds, "total", run->seconds.total);
    cJSON_AddNumberToObject(seconds, "per_iteration", run->seconds.total / n);
    cJSON *stages = cJSON_AddObjectToObject(seconds, "per_iteration_by_stage");
    cJSON_AddNumberToObject(stages, "camera", run->seconds.camera / n);
    cJSON_AddNumberToObject(stages, "photon", run->seconds.photon / n);
    cJSON_AddNumberToObject(stages, "grid", run->seconds.grid / n);
    cJSON_AddNumberToObject(stages, "gather", run->seconds.gather / n);
    cJSON_AddNumberToObject(stages, "readback", run->seconds.collect / n);
    cJSON *memory = cJSON_AddObjectToObject(root, "device_bytes");
    cJSON_AddNumberToObject(memory, "geometry", (double)run->geometry_bytes);
    cJSON_AddNumberToObject(memory, "bvh", (double)run->bvh_bytes);
    cJSON_AddNumberToObject(memory, "sppm", (double)run->buffer_bytes);
    cJSON_AddNumberToObject(memory, "total",
                            (double)(run->geometry_bytes + run->bvh_bytes + run->buffer_bytes));
    cJSON_AddStringToObject(root, "build_options", run->build_options ? run->build_options : "");
    return root;
}
