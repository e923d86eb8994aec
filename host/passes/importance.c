/* importance.c — drives kernels/importance.cl iteration by iteration and turns its per-triangle
 * sums into importance per triangle, vertex and mesh (see importance.h).
 *
 * Each iteration: camera_pass → photon_pass → grid (count, three-step prefix sum, scatter)
 * → gather_count → path_importance; then the two fixed-point accumulators are read back, added
 * to double sums on the host, checked for saturation, and cleared. */
#include "passes/importance.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "device/device_scene.h"
#include "core/error.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "passes/pass_grid.h"
#include "core/progress.h"

#define STOP_AFTER_CALM_ITERATIONS 3

void importance_options_default(importance_options *o)
{
    memset(o, 0, sizeof *o);
    sppm_options_default(&o->sppm, 100);
    o->gamma = 1.0f;
    o->tolerance = 0.0;
    o->bookkeeping = 1;
}

void sppm_options_default(sppm_options *o, unsigned int iterations)
{
    memset(o, 0, sizeof *o);
    o->iterations = iterations;
    o->seed = 1;
    o->alpha = 0.7f;
    o->resolution = 1.0f;
}

unsigned int sppm_default_photons(const device *d)
{
    return strcmp(d->info.kind, "gpu") == 0 ? 1000000u : 500000u;
}

/* The pass's kernels and buffers. */
typedef struct pass {
    device *dev;
    cl_program program;
    cl_kernel camera, photon, gather, path;
    cl_mem hit_points, vertices, path_length, gathered;
    cl_mem camera_importance, light_importance;
    device_scene scene;
    pass_grid grid;
    unsigned int pixels;
    uint64_t bytes;
} pass;

static void pass_release(pass *p)
{
    cl_kernel kernels[] = {p->camera, p->photon, p->gather, p->path};
    device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
    cl_mem buffers[] = {p->hit_points, p->vertices,          p->path_length,
                        p->gathered,   p->camera_importance, p->light_importance};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    pass_grid_release(&p->grid);
    if (p->program)
        clReleaseProgram(p->program);
    device_scene_release(&p->scene);
}

static int pass_build(pass *p, const scene *s, const importance_options *o, importance_result *r)
{
    double start = monotonic_seconds();
    char extra[96];
    snprintf(extra, sizeof extra, "-D IDMR_BOOKKEEPING=%d -D IDMR_CAMERA_IMPORTANCE=%d",
             o->bookkeeping ? 1 : 0, o->gamma > 0 ? 1 : 0);
    r->build_options =
        device_build_options(p->dev, o->sppm.generic ? IDMR_FEATURES_ALL : s->features, extra);
    if (device_build_program(p->dev, "importance.cl", r->build_options, &p->program))
        return -1;
    struct {
        cl_kernel *kernel;
        const char *name;
    } kernels[] = {{&p->camera, "camera_pass"},
                   {&p->photon, "photon_pass"},
                   {&p->gather, "gather_count"},
                   {&p->path, "path_importance"}};
    for (size_t i = 0; i < sizeof kernels / sizeof *kernels; i++)
        if (device_create_kernel(p->program, kernels[i].name, kernels[i].kernel))
            return -1;
    r->seconds.build = monotonic_seconds() - start;
    return 0;
}

static int pass_allocate(pass *p, const scene *s, unsigned int photons)
{
    size_t triangles = s->triangle_count ? (size_t)s->triangle_count : 1;
    size_t slots = (size_t)photons * IDMR_PATH_VERTICES;
    if (pass_grid_create(p->dev, p->program, p->pixels, &p->grid))
        return -1;
    const device_buffer_request buffers[] = {
        {&p->hit_points, p->pixels * sizeof(idmr_hit_point), "hit points"},
        {&p->vertices, slots * sizeof(idmr_photon_vertex), "photon paths"},
        {&p->path_length, photons * sizeof(cl_uint), "photon path lengths"},
        {&p->gathered, slots * sizeof(cl_uint), "gather counts"},
        {&p->camera_importance, triangles * sizeof(cl_ulong), "camera importance"},
        {&p->light_importance, triangles * sizeof(cl_ulong), "light importance"},
    };
    p->bytes = p->scene.bytes + p->grid.bytes;
    return device_buffers(p->dev, buffers, sizeof buffers / sizeof *buffers, &p->bytes);
}

/* Runs one iteration's kernels, timing each stage (the queue is drained between stages). */
static int pass_iterate(pass *p, const scene *s, const importance_options *o,
                        idmr_sppm_params *params, importance_result *r)
{
    size_t local = o->sppm.local_size;
    double t0 = monotonic_seconds();
    idmr_camera camera = s->camera;
    if (DEVICE_SET_ARGS(p->camera, "camera_pass", DEVICE_ARG(*params), DEVICE_ARG(camera),
                        DEVICE_ARG(p->scene.nodes), DEVICE_ARG(p->scene.leaves),
                        DEVICE_ARG(p->scene.triangle_normals),
                        DEVICE_ARG(p->scene.triangle_materials), DEVICE_ARG(p->scene.materials),
                        DEVICE_ARG(p->hit_points), DEVICE_ARG(p->camera_importance)) ||
        device_run(p->dev, p->camera, "camera_pass", p->pixels, local))
        return -1;
    double t1 = monotonic_seconds();
    if (DEVICE_SET_ARGS(p->photon, "photon_pass", DEVICE_ARG(*params), DEVICE_ARG(p->scene.lights),
                        DEVICE_ARG(p->scene.light_cdf), DEVICE_ARG(p->scene.emitter_cdf),
                        DEVICE_ARG(p->scene.emitter_triangles), DEVICE_ARG(p->scene.nodes),
                        DEVICE_ARG(p->scene.leaves), DEVICE_ARG(p->scene.triangle_normals),
                        DEVICE_ARG(p->scene.triangle_materials), DEVICE_ARG(p->scene.materials),
                        DEVICE_ARG(p->vertices), DEVICE_ARG(p->path_length)) ||
        device_run(p->dev, p->photon, "photon_pass", params->path_count, local))
        return -1;
    double t2 = monotonic_seconds();
    if (pass_grid_build(p->dev, &p->grid, params, p->hit_points, local))
        return -1;
    double t3 = monotonic_seconds();
    size_t slots = (size_t)params->path_count * IDMR_PATH_VERTICES;
    if (DEVICE_SET_ARGS(p->gather, "gather_count", DEVICE_ARG(*params), DEVICE_ARG(p->vertices),
                        DEVICE_ARG(p->path_length), DEVICE_ARG(p->hit_points),
                        DEVICE_ARG(p->grid.cell_start), DEVICE_ARG(p->grid.grid_points),
                        DEVICE_ARG(p->gathered)) ||
        device_run(p->dev, p->gather, "gather_count", slots, local))
        return -1;
    double t4 = monotonic_seconds();
    if (o->bookkeeping &&
        (DEVICE_SET_ARGS(p->path, "path_importance", DEVICE_ARG(*params), DEVICE_ARG(p->vertices),
                         DEVICE_ARG(p->path_length), DEVICE_ARG(p->gathered),
                         DEVICE_ARG(p->light_importance)) ||
         device_run(p->dev, p->path, "path_importance", params->path_count, local)))
        return -1;
    double t5 = monotonic_seconds();
    r->seconds.camera += t1 - t0;
    r->seconds.photon += t2 - t1;
    r->seconds.grid += t3 - t2;
    r->seconds.gather += t4 - t3;
    r->seconds.path += t5 - t4;
    return 0;
}

void importance_snapshot_free(importance_snapshot *snapshot)
{
    free(snapshot->hit_points);
    free(snapshot->vertices);
    free(snapshot->path_length);
    free(snapshot->gathered);
    free(snapshot->camera_fixed);
    free(snapshot->light_fixed);
    memset(snapshot, 0, sizeof *snapshot);
}

static int pass_snapshot(pass *p, const idmr_sppm_params *params, size_t triangles,
                         importance_snapshot *out)
{
    importance_snapshot_free(out);
    out->params = *params;
    size_t slots = (size_t)params->path_count * IDMR_PATH_VERTICES;
    size_t t = triangles ? triangles : 1;
    out->hit_points = xmalloc(p->pixels * sizeof *out->hit_points);
    out->vertices = xmalloc(slots * sizeof *out->vertices);
    out->path_length = xmalloc(params->path_count * sizeof *out->path_length);
    out->gathered = xmalloc(slots * sizeof *out->gathered);
    out->camera_fixed = xmalloc(t * sizeof *out->camera_fixed);
    out->light_fixed = xmalloc(t * sizeof *out->light_fixed);
    return device_read(p->dev, p->hit_points, p->pixels * sizeof *out->hit_points,
                       out->hit_points, "hit points") ||
                   device_read(p->dev, p->vertices, slots * sizeof *out->vertices, out->vertices,
                               "photon paths") ||
                   device_read(p->dev, p->path_length, params->path_count * sizeof(uint32_t),
                               out->path_length, "path lengths") ||
                   device_read(p->dev, p->gathered, slots * sizeof(uint32_t), out->gathered,
                               "gather counts") ||
                   device_read(p->dev, p->camera_importance, t * 8, out->camera_fixed,
                               "camera importance") ||
                   device_read(p->dev, p->light_importance, t * 8, out->light_fixed,
                               "light importance")
               ? -1
               : 0;
}

/* Reads the fixed-point accumulators into the double sums, checks saturation, clears them. */
static int pass_collect(pass *p, const scene *s, importance_result *r, uint64_t *scratch)
{
    size_t n = (size_t)s->triangle_count;
    double start = monotonic_seconds();
    cl_mem buffers[2] = {p->camera_importance, p->light_importance};
    double *sums[2] = {r->camera, r->light};
    const char *names[2] = {"camera importance", "light importance"};
    for (int b = 0; b < 2; b++) {
        if (n && device_read(p->dev, buffers[b], n * sizeof(uint64_t), scratch, names[b]))
            return -1;
        for (size_t t = 0; t < n; t++) {
            if (scratch[t] >= IDMR_FIXED_SATURATION)
                return error_set(IDMR_EXIT_FAILURE,
                                 "%s of triangle %zu came within a factor 2 of the 64-bit "
                                 "fixed-point limit in one iteration; use fewer photons per "
                                 "iteration",
                                 names[b], t);
            sums[b][t] += (double)scratch[t] / IDMR_FIXED_SCALE;
        }
        if (device_clear(p->dev, buffers[b], (n ? n : 1) * sizeof(uint64_t), names[b]))
            return -1;
    }
    r->seconds.readback += monotonic_seconds() - start;
    return 0;
}

/* Δ_n (importance.h) from the sums after n and n - 1 iterations. */
static double convergence_change(const importance_result *r, const scene *s, float gamma,
                                 const double *previous_camera, const double *previous_light,
                                 unsigned int n)
{
    double change = 0, magnitude = 0;
    for (size_t t = 0; t < r->triangle_count; t++) {
        double area = scene_triangle_area(s, t);
        if (!(area > 0))
            continue;
        double now = (gamma * r->camera[t] + r->light[t]) / (n * area);
        double before = n > 1 ? (gamma * previous_camera[t] + previous_light[t]) / ((n - 1) * area)
                              : 0.0;
        change += (now - before) * (now - before);
        magnitude += now * now;
    }
    return magnitude > 0 ? change / magnitude : 0.0;
}

/* Counts of the first iteration's hit points, stored vertices and gathers, for the report
 * (read back once: they change little between iterations). */
static int pass_statistics(pass *p, unsigned int photons, importance_result *r)
{
    idmr_hit_point *hit_points = xmalloc(p->pixels * sizeof *hit_points);
    cl_uint *lengths = xmalloc(photons * sizeof *lengths);
    cl_uint *gathered = xmalloc((size_t)photons * IDMR_PATH_VERTICES * sizeof *gathered);
    int status =
        device_read(p->dev, p->hit_points, p->pixels * sizeof *hit_points, hit_points,
                    "hit points") ||
        device_read(p->dev, p->path_length, photons * sizeof *lengths, lengths, "path lengths") ||
        device_read(p->dev, p->gathered, (size_t)photons * IDMR_PATH_VERTICES * sizeof *gathered,
                    gathered, "gather counts");
    if (!status) {
        for (unsigned int i = 0; i < p->pixels; i++)
            r->hit_points += hit_points[i].valid;
        for (unsigned int i = 0; i < photons; i++)
            r->photon_vertices += lengths[i];
        for (size_t i = 0; i < (size_t)photons * IDMR_PATH_VERTICES; i++)
            r->gathered += gathered[i];
    }
    free(hit_points);
    free(lengths);
    free(gathered);
    return status ? -1 : 0;
}

int importance_run(device *d, const scene *s, const bvh *b, const importance_options *o,
                   importance_result *r)
{
    memset(r, 0, sizeof *r);
    if (!s->has_camera)
        return error_set(IDMR_EXIT_INPUT, "%s: the scene has no sensor: the importance pass "
                                          "needs a camera", s->file);
    if (s->light_count == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: the scene has no emitter that idmr simulates (area, point, spot, "
                         "directional): no light can reach the camera",
                         s->file);
    if (o->sppm.iterations == 0)
        return error_set(IDMR_EXIT_INPUT, "the importance pass needs at least one iteration");
    if (!(o->sppm.resolution > 0) || !(o->sppm.alpha > 0 && o->sppm.alpha <= 1) || !(o->gamma >= 0))
        return error_set(IDMR_EXIT_INPUT, "resolution must be > 0, alpha in (0, 1], gamma >= 0");

    r->triangle_count = (size_t)s->triangle_count;
    r->camera = xcalloc(r->triangle_count + 1, sizeof *r->camera);
    r->light = xcalloc(r->triangle_count + 1, sizeof *r->light);
    r->convergence = xcalloc(o->sppm.iterations, sizeof *r->convergence);
    r->radius = xcalloc(o->sppm.iterations, sizeof *r->radius);
    r->photons = o->sppm.photons ? o->sppm.photons : sppm_default_photons(d);
    double w = fmax(1.0, floor(s->camera.width * o->sppm.resolution + 0.5));
    double h = fmax(1.0, floor(s->camera.height * o->sppm.resolution + 0.5));
    if (w * h > 1 << 26)
        return error_set(IDMR_EXIT_INPUT, "hit-point image %gx%g is too large", w, h);
    r->width = (unsigned int)w;
    r->height = (unsigned int)h;

    pass p;
    memset(&p, 0, sizeof p);
    p.dev = d;
    p.pixels = r->width * r->height;
    int status = device_scene_upload(d, s, b, &p.scene) || pass_build(&p, s, o, r) ||
                 pass_allocate(&p, s, r->photons);
    if (status) {
        pass_release(&p);
        return -1;
    }
    r->device_bytes = p.bytes;
    status = device_clear(p.dev, p.camera_importance, (r->triangle_count ? r->triangle_count : 1) * 8,
                          "camera importance") ||
             device_clear(p.dev, p.light_importance, (r->triangle_count ? r->triangle_count : 1) * 8,
                          "light importance");

    double radius2 = pass_initial_radius2(s, r->width, r->height);
    idmr_sppm_params params;
    memset(&params, 0, sizeof params);
    params.seed = o->sppm.seed;
    params.width = r->width;
    params.height = r->height;
    params.path_count = r->photons;
    params.light_count = p.scene.light_count;
    params.triangle_count = (unsigned int)r->triangle_count;
    memcpy(params.scene_center, p.scene.center, sizeof params.scene_center);
    params.scene_radius = p.scene.radius;
    params.ray_epsilon = p.scene.ray_epsilon;

    double *previous_camera = xcalloc(r->triangle_count + 1, sizeof *previous_camera);
    double *previous_light = xcalloc(r->triangle_count + 1, sizeof *previous_light);
    uint64_t *scratch = xmalloc((r->triangle_count + 1) * sizeof *scratch);
    progress bar;
    progress_begin(&bar, "importance", o->sppm.iterations, o->sppm.progress);
    double start = monotonic_seconds();
    unsigned int calm = 0;
    for (unsigned int n = 0; n < o->sppm.iterations && !status; n++) {
        params.iteration = n;
        pass_grid_place(&p.grid, s, radius2, &params);
        r->radius[n] = params.radius;
        memcpy(previous_camera, r->camera, r->triangle_count * sizeof *r->camera);
        memcpy(previous_light, r->light, r->triangle_count * sizeof *r->light);
        if (pass_iterate(&p, s, o, &params, r) ||
            (o->snapshot && pass_snapshot(&p, &params, r->triangle_count, o->snapshot)) ||
            pass_collect(&p, s, r, scratch) ||
            (n == 0 && pass_statistics(&p, r->photons, r))) {
            status = -1;
            break;
        }
        r->iterations = n + 1;
        r->convergence[n] =
            convergence_change(r, s, o->gamma, previous_camera, previous_light, n + 1);
        char detail[64];
        snprintf(detail, sizeof detail, "change %.2e", r->convergence[n]);
        progress_update(&bar, n + 1, detail);
        radius2 = pass_next_radius2(radius2, n, o->sppm.alpha);
        calm = (o->tolerance > 0 && r->convergence[n] < o->tolerance) ? calm + 1 : 0;
        if (calm >= STOP_AFTER_CALM_ITERATIONS)
            break;
    }
    progress_end(&bar);
    r->seconds.total = monotonic_seconds() - start;
    free(previous_camera);
    free(previous_light);
    free(scratch);
    pass_release(&p);
    return status ? -1 : 0;
}

void importance_result_free(importance_result *r)
{
    free(r->camera);
    free(r->light);
    free(r->convergence);
    free(r->radius);
    free(r->build_options);
    memset(r, 0, sizeof *r);
}

double importance_triangle(const importance_result *r, const scene *s, float gamma, uint64_t t)
{
    double area = scene_triangle_area(s, t);
    if (!(area > 0) || r->iterations == 0)
        return 0.0;
    return (gamma * r->camera[t] + r->light[t]) / (r->iterations * area);
}

void importance_mesh_vertices(const importance_result *r, const scene *s, size_t m, float gamma,
                              double *vertex_importance)
{
    const scene_mesh *mesh = &s->meshes[m];
    double *area = xcalloc(mesh->vertex_count + 1, sizeof *area);
    memset(vertex_importance, 0, mesh->vertex_count * sizeof *vertex_importance);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        uint64_t global = (uint64_t)mesh->first_triangle + t;
        double a = scene_mesh_triangle_area(mesh, t);
        double value = gamma * r->camera[global] + r->light[global];
        for (int k = 0; k < 3; k++) {
            uint32_t v = mesh->indices[3 * (size_t)t + k];
            vertex_importance[v] += value;
            area[v] += a;
        }
    }
    for (uint32_t v = 0; v < mesh->vertex_count; v++)
        vertex_importance[v] = area[v] > 0 && r->iterations
                                   ? vertex_importance[v] / (r->iterations * area[v])
                                   : 0.0;
    free(area);
}

void importance_mesh_sums(const importance_result *r, const scene *s, size_t m, float gamma,
                          double *importance_sum, double *camera_sum, double *light_sum)
{
    const scene_mesh *mesh = &s->meshes[m];
    double camera = 0, light = 0;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        camera += r->camera[(uint64_t)mesh->first_triangle + t];
        light += r->light[(uint64_t)mesh->first_triangle + t];
    }
    double n = r->iterations ? r->iterations : 1;
    *camera_sum = camera / n;
    *light_sum = light / n;
    *importance_sum = (gamma * camera + light) / n;
}
