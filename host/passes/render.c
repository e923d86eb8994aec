/* render.c — drives kernels/render.cl iteration by iteration and averages the iterations'
 * estimates into the image (see render.h).
 *
 * Each iteration: render_camera → render_photon → grid (pass_grid.c) → render_gather; then the
 * fixed-point pixel radiance and the directly seen emission are read back, added to the double
 * sum on the host, and the accumulators cleared. */
#include "passes/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/device_scene.h"
#include "core/error.h"
#include "io/image.h"
#include "passes/importance.h"
#include "passes/pass_grid.h"
#include "core/progress.h"
#include "io/spectrum.h"

void render_options_default(render_options *o)
{
    memset(o, 0, sizeof *o);
    sppm_options_default(&o->sppm, 64);
}

void render_snapshot_free(render_snapshot *snapshot)
{
    free(snapshot->hit_points);
    free(snapshot->photons);
    free(snapshot->path_length);
    memset(snapshot, 0, sizeof *snapshot);
}

/* The renderer's kernels and buffers. */
typedef struct renderer {
    device *dev;
    cl_program program;
    cl_kernel camera, photon, gather;
    cl_mem hit_points, render_hits, photons, path_length, pixel_radiance;
    device_scene scene;
    pass_grid grid;
    unsigned int pixels;
    uint64_t sppm_bytes;
} renderer;

static void renderer_release(renderer *p)
{
    cl_kernel kernels[] = {p->camera, p->photon, p->gather};
    device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
    cl_mem buffers[] = {p->hit_points, p->render_hits,
                        p->photons,    p->path_length, p->pixel_radiance};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    pass_grid_release(&p->grid);
    if (p->program)
        clReleaseProgram(p->program);
    device_scene_release(&p->scene);
}

static int renderer_build(renderer *p, const scene *s, const render_options *o, render_result *r)
{
    double start = monotonic_seconds();
    r->build_options = device_build_options(p->dev, o->sppm.generic ? IDMR_FEATURES_ALL : s->features,
                                            NULL);
    if (device_build_program(p->dev, "render.cl", r->build_options, &p->program) ||
        device_create_kernel(p->program, "render_camera", &p->camera) ||
        device_create_kernel(p->program, "render_photon", &p->photon) ||
        device_create_kernel(p->program, "render_gather", &p->gather))
        return -1;
    r->seconds.build = monotonic_seconds() - start;
    return 0;
}

static int renderer_allocate(renderer *p, unsigned int photons)
{
    if (pass_grid_create(p->dev, p->program, p->pixels, &p->grid))
        return -1;
    size_t slots = (size_t)photons * IDMR_PATH_VERTICES;
    const device_buffer_request buffers[] = {
        {&p->hit_points, p->pixels * sizeof(idmr_hit_point), "hit points"},
        {&p->render_hits, p->pixels * sizeof(idmr_render_hit), "hit point throughputs"},
        {&p->photons, slots * sizeof(idmr_render_photon), "photons"},
        {&p->path_length, photons * sizeof(cl_uint), "photon path lengths"},
        {&p->pixel_radiance, p->pixels * 3 * sizeof(cl_ulong), "pixel radiance"},
    };
    p->sppm_bytes = p->grid.bytes;
    if (device_buffers(p->dev, buffers, sizeof buffers / sizeof *buffers, &p->sppm_bytes))
        return -1;
    return device_clear(p->dev, p->pixel_radiance, p->pixels * 3 * sizeof(cl_ulong),
                        "pixel radiance");
}

/* Fixed-point units per unit of (throughput × BRDF × flux): one photon of the brightest light
 * (the largest flux a photon starts with) on a white diffuse surface, whose contribution is
 * Φ_max / π before the 1/(π r²) the host divides by, becomes IDMR_RENDER_PHOTON_UNITS. Light
 * probabilities are the differences of the light CDF, as the kernel takes them. 0 if no light
 * emits. */
static double fixed_scale(const scene *s, const device_scene *ds, unsigned int photons)
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
                                                          ds->radius) /
                      (probability * photons);
        brightest = fmax(brightest, flux);
    }
    return brightest > 0 && isfinite(brightest) ? IDMR_RENDER_PHOTON_UNITS * M_PI / brightest : 0;
}

static int renderer_iterate(renderer *p, const scene *s, const render_options *o,
                            const idmr_sppm_params *params, render_result *r)
{
    size_t local = o->sppm.local_size;
    double t0 = monotonic_seconds();
    idmr_camera camera = s->camera;
    if (DEVICE_SET_ARGS(p->camera, "render_camera", DEVICE_ARG(*params), DEVICE_ARG(camera),
                        DEVICE_ARG(p->scene.nodes), DEVICE_ARG(p->scene.leaves),
                        DEVICE_ARG(p->scene.triangle_normals),
                        DEVICE_ARG(p->scene.triangle_materials), DEVICE_ARG(p->scene.materials),
                        DEVICE_ARG(p->scene.lights), DEVICE_ARG(p->hit_points),
                        DEVICE_ARG(p->render_hits)) ||
        device_run(p->dev, p->camera, "render_camera", p->pixels, local))
        return -1;
    double t1 = monotonic_seconds();
    if (DEVICE_SET_ARGS(p->photon, "render_photon", DEVICE_ARG(*params),
                        DEVICE_ARG(p->scene.lights), DEVICE_ARG(p->scene.light_cdf),
                        DEVICE_ARG(p->scene.emitter_cdf), DEVICE_ARG(p->scene.emitter_triangles),
                        DEVICE_ARG(p->scene.nodes), DEVICE_ARG(p->scene.leaves),
                        DEVICE_ARG(p->scene.triangle_normals),
                        DEVICE_ARG(p->scene.triangle_materials), DEVICE_ARG(p->scene.materials),
                        DEVICE_ARG(p->photons), DEVICE_ARG(p->path_length)) ||
        device_run(p->dev, p->photon, "render_photon", params->path_count, local))
        return -1;
    double t2 = monotonic_seconds();
    if (pass_grid_build(p->dev, &p->grid, params, p->hit_points, local))
        return -1;
    double t3 = monotonic_seconds();
    size_t slots = (size_t)params->path_count * IDMR_PATH_VERTICES;
    if (DEVICE_SET_ARGS(p->gather, "render_gather", DEVICE_ARG(*params), DEVICE_ARG(p->photons),
                        DEVICE_ARG(p->path_length), DEVICE_ARG(p->hit_points),
                        DEVICE_ARG(p->render_hits), DEVICE_ARG(p->scene.materials),
                        DEVICE_ARG(p->grid.cell_start), DEVICE_ARG(p->grid.grid_points),
                        DEVICE_ARG(p->pixel_radiance)) ||
        device_run(p->dev, p->gather, "render_gather", slots, local))
        return -1;
    double t4 = monotonic_seconds();
    r->seconds.camera += t1 - t0;
    r->seconds.photon += t2 - t1;
    r->seconds.grid += t3 - t2;
    r->seconds.gather += t4 - t3;
    return 0;
}

/* Adds this iteration's estimate to `sum` (double, 3 per pixel): emission seen directly plus
 * the photon estimate, units / (fixed_scale π r²). Checks saturation; clears the accumulators. */
static int renderer_collect(renderer *p, const idmr_sppm_params *params, double *sum,
                            uint64_t *units, idmr_render_hit *hits, render_result *r)
{
    double start = monotonic_seconds();
    size_t pixels = p->pixels;
    if (device_read(p->dev, p->pixel_radiance, pixels * 3 * sizeof *units, units,
                    "pixel radiance") ||
        device_read(p->dev, p->render_hits, pixels * sizeof *hits, hits,
                    "directly seen emission"))
        return -1;
    double per_unit = 1.0 / ((double)params->fixed_scale * M_PI * (double)params->radius *
                             (double)params->radius);
    for (size_t i = 0; i < pixels; i++)
        for (int c = 0; c < 3; c++) {
            uint64_t u = units[3 * i + c];
            if (u >= IDMR_FIXED_SATURATION)
                return error_set(IDMR_EXIT_FAILURE,
                                 "the radiance of pixel (%zu, %zu) came within a factor 2 of the "
                                 "64-bit fixed-point limit in one iteration; use fewer photons "
                                 "per iteration",
                                 i % r->width, i / r->width);
            double e = hits[i].emitted[c];
            sum[3 * i + c] += (isfinite(e) ? e : 0.0) + (double)u * per_unit;
        }
    if (device_clear(p->dev, p->pixel_radiance, pixels * 3 * sizeof *units, "pixel radiance"))
        return -1;
    r->seconds.readback += monotonic_seconds() - start;
    return 0;
}

static int renderer_snapshot(renderer *p, const idmr_sppm_params *params, render_snapshot *out)
{
    render_snapshot_free(out);
    out->params = *params;
    size_t slots = (size_t)params->path_count * IDMR_PATH_VERTICES;
    out->hit_points = xmalloc(p->pixels * sizeof *out->hit_points);
    out->photons = xmalloc(slots * sizeof *out->photons);
    out->path_length = xmalloc(params->path_count * sizeof *out->path_length);
    return device_read(p->dev, p->hit_points, p->pixels * sizeof *out->hit_points,
                       out->hit_points, "hit points") ||
                   device_read(p->dev, p->photons, slots * sizeof *out->photons, out->photons,
                               "photons") ||
                   device_read(p->dev, p->path_length, params->path_count * sizeof(uint32_t),
                               out->path_length, "photon path lengths")
               ? -1
               : 0;
}

static int count_stored_photons(renderer *p, unsigned int paths, render_result *r)
{
    uint32_t *lengths = xmalloc((paths ? paths : 1) * sizeof *lengths);
    int status = device_read(p->dev, p->path_length, paths * sizeof *lengths, lengths,
                             "photon path lengths");
    for (unsigned int i = 0; i < paths && !status; i++)
        r->photons_stored += lengths[i];
    free(lengths);
    return status;
}

int render_run(device *d, const scene *s, const bvh *b, const render_options *o,
               render_result *r)
{
    memset(r, 0, sizeof *r);
    if (!s->has_camera)
        return error_set(IDMR_EXIT_INPUT, "%s: the scene has no sensor: nothing to render from",
                         s->file);
    if (s->light_count == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: the scene has no emitter that idmr simulates (area, point, spot, "
                         "directional, constant, envmap): the image would be black",
                         s->file);
    if (o->sppm.iterations == 0)
        return error_set(IDMR_EXIT_INPUT, "render: at least one iteration is needed");
    if (!(o->sppm.resolution > 0) || !(o->sppm.alpha > 0 && o->sppm.alpha <= 1))
        return error_set(IDMR_EXIT_INPUT, "render: resolution must be > 0 and alpha in (0, 1]");
    double w = fmax(1.0, floor(s->camera.width * o->sppm.resolution + 0.5));
    double h = fmax(1.0, floor(s->camera.height * o->sppm.resolution + 0.5));
    if (w * h > (1 << 26))
        return error_set(IDMR_EXIT_INPUT, "render: image %gx%g is too large", w, h);
    r->width = (unsigned int)w;
    r->height = (unsigned int)h;
    r->photons = o->sppm.photons ? o->sppm.photons : sppm_default_photons(d);
    if ((uint64_t)r->photons * IDMR_PATH_VERTICES > 0xffffffffu)
        return error_set(IDMR_EXIT_INPUT, "render: %u photon paths per iteration are too many",
                         r->photons);

    renderer p;
    memset(&p, 0, sizeof p);
    p.dev = d;
    p.pixels = r->width * r->height;
    if (device_scene_upload(d, s, b, &p.scene) || renderer_build(&p, s, o, r) ||
        renderer_allocate(&p, r->photons)) {
        renderer_release(&p);
        return -1;
    }
    r->memory.bvh = p.scene.bvh_bytes;
    r->memory.geometry = p.scene.bytes - p.scene.bvh_bytes;
    r->memory.sppm = p.sppm_bytes;

    idmr_sppm_params params;
    memset(&params, 0, sizeof params);
    params.seed = o->sppm.seed;
    params.width = r->width;
    params.height = r->height;
    params.path_count = r->photons;
    params.light_count = p.scene.light_count;
    params.triangle_count = (unsigned int)s->triangle_count;
    memcpy(params.scene_center, p.scene.center, sizeof params.scene_center);
    params.scene_radius = p.scene.radius;
    params.ray_epsilon = p.scene.ray_epsilon;
    params.fixed_scale = (float)fixed_scale(s, &p.scene, r->photons);
    int status = 0;
    if (!(params.fixed_scale > 0) || !isfinite(params.fixed_scale))
        status = error_set(IDMR_EXIT_INPUT, "%s: no light emits any power: the image would be black",
                           s->file);

    double *sum = xcalloc((size_t)p.pixels * 3, sizeof *sum);
    uint64_t *units = xmalloc((size_t)p.pixels * 3 * sizeof *units);
    idmr_render_hit *hits = xmalloc((size_t)p.pixels * sizeof *hits);
    double radius2 = pass_initial_radius2(s, r->width, r->height);
    progress bar;
    progress_begin(&bar, "render", o->sppm.iterations, o->sppm.progress);
    double start = monotonic_seconds();
    for (unsigned int n = 0; n < o->sppm.iterations && !status; n++) {
        params.iteration = n;
        pass_grid_place(&p.grid, s, radius2, &params);
        if (n == 0)
            r->first_radius = params.radius;
        r->last_radius = params.radius;
        if (renderer_iterate(&p, s, o, &params, r) ||
            (o->snapshot && renderer_snapshot(&p, &params, o->snapshot)) ||
            (n == 0 && count_stored_photons(&p, r->photons, r)) ||
            renderer_collect(&p, &params, sum, units, hits, r)) {
            status = -1;
            break;
        }
        r->iterations = n + 1;
        double elapsed = monotonic_seconds() - start;
        char detail[64];
        snprintf(detail, sizeof detail, "%.2f s/iteration", elapsed / r->iterations);
        progress_update(&bar, n + 1, detail);
        radius2 = pass_next_radius2(radius2, n, o->sppm.alpha);
        if (o->sppm.time_limit > 0 && elapsed >= o->sppm.time_limit)
            break;
    }
    progress_end(&bar);
    r->seconds.total = monotonic_seconds() - start;
    if (!status) {
        r->image = xmalloc((size_t)p.pixels * 3 * sizeof *r->image);
        for (size_t i = 0; i < (size_t)p.pixels * 3; i++)
            r->image[i] = (float)(sum[i] / r->iterations);
    }
    free(sum);
    free(units);
    free(hits);
    renderer_release(&p);
    return status ? -1 : 0;
}

void render_result_free(render_result *r)
{
    free(r->image);
    free(r->build_options);
    memset(r, 0, sizeof *r);
}

int render_write_images(const render_result *r, const char *exr_path, const char *png_path,
                        double ev)
{
    if (exr_path &&
        image_write_rgb_float(exr_path, (int)r->width, (int)r->height, r->image))
        return -1;
    if (!png_path)
        return 0;
    size_t values = (size_t)r->width * r->height * 3;
    unsigned char *bytes = xmalloc(values);
    float exposure = (float)pow(2.0, ev);
    for (size_t i = 0; i < values; i++) {
        float encoded = spectrum_linear_to_srgb(r->image[i] * exposure);
        bytes[i] = (unsigned char)(fminf(encoded, 1.0f) * 255.0f + 0.5f);
    }
    int status = image_write_rgb8(png_path, (int)r->width, (int)r->height, bytes);
    free(bytes);
    return status;
}

cJSON *render_report_json(const scene *s, const device *d, const render_options *o,
                          const render_result *r)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddStringToObject(root, "device", d->info.name);
    cJSON_AddNumberToObject(root, "width", r->width);
    cJSON_AddNumberToObject(root, "height", r->height);
    cJSON_AddNumberToObject(root, "iterations", r->iterations);
    cJSON_AddNumberToObject(root, "photons_per_iteration", r->photons);
    cJSON_AddNumberToObject(root, "photons_stored_first_iteration", (double)r->photons_stored);
    cJSON_AddNumberToObject(root, "seed", o->sppm.seed);
    cJSON_AddNumberToObject(root, "alpha", o->sppm.alpha);
    cJSON_AddNumberToObject(root, "first_radius", r->first_radius);
    cJSON_AddNumberToObject(root, "last_radius", r->last_radius);
    cJSON_AddNumberToObject(root, "triangles", (double)s->triangle_count);
    cJSON_AddNumberToObject(root, "vertices", (double)s->vertex_count);
    cJSON *seconds = cJSON_AddObjectToObject(root, "seconds");
    double n = r->iterations ? r->iterations : 1;
    cJSON_AddNumberToObject(seconds, "build", r->seconds.build);
    cJSON_AddNumberToObject(seconds, "total", r->seconds.total);
    cJSON_AddNumberToObject(seconds, "per_iteration", r->seconds.total / n);
    cJSON *stages = cJSON_AddObjectToObject(seconds, "per_iteration_by_stage");
    cJSON_AddNumberToObject(stages, "camera", r->seconds.camera / n);
    cJSON_AddNumberToObject(stages, "photon", r->seconds.photon / n);
    cJSON_AddNumberToObject(stages, "grid", r->seconds.grid / n);
    cJSON_AddNumberToObject(stages, "gather", r->seconds.gather / n);
    cJSON_AddNumberToObject(stages, "readback", r->seconds.readback / n);
    cJSON *memory = cJSON_AddObjectToObject(root, "device_bytes");
    cJSON_AddNumberToObject(memory, "geometry", (double)r->memory.geometry);
    cJSON_AddNumberToObject(memory, "bvh", (double)r->memory.bvh);
    cJSON_AddNumberToObject(memory, "sppm", (double)r->memory.sppm);
    cJSON_AddNumberToObject(memory, "total",
                            (double)(r->memory.geometry + r->memory.bvh + r->memory.sppm));
    cJSON_AddStringToObject(root, "build_options", r->build_options ? r->build_options : "");
    return root;
}
