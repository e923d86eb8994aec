/* importance.c — the importance pass on the SPPM core (see importance.h): its buffers and
 * kernels (gather_count, path_importance, pixel_centre_hits in kernels/sppm.cl), reading the
 * fixed-point accumulators into double sums every iteration, the convergence measure and its
 * stop rule, and the importance per triangle, vertex and mesh. */
#include "passes/importance.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"

#define STOP_AFTER_CALM_ITERATIONS 3

void importance_options_default(importance_options *o)
{
    memset(o, 0, sizeof *o);
    sppm_options_default(&o->sppm, 100);
    o->gamma = 1.0f;
    o->tolerance = 0.0;
    o->accumulate_importance = 1;
}

void importance_defines(int accumulate_importance, int camera_importance, char *out, size_t size)
{
    snprintf(out, size, "-D IDMR_ACCUMULATE_IMPORTANCE=%d -D IDMR_CAMERA_IMPORTANCE=%d",
             accumulate_importance ? 1 : 0, camera_importance ? 1 : 0);
}

/* The pass's part while the core runs. */
typedef struct importance_pass {
    const importance_options *options;
    importance_result *result;
    cl_kernel gather, path, centre_hits;
    cl_mem gathered, camera_importance, light_importance;
    size_t words;     /* accumulator words: one per triangle (at least one) */
    uint64_t *scratch; /* a read-back accumulator */
    double *previous_camera, *previous_light; /* the sums before this iteration */
    unsigned int calm; /* iterations in a row with Δ below the tolerance */
} importance_pass;

static int prepare(sppm *core, void *state)
{
    importance_pass *p = state;
        p->words = core->scene->triangle_count ? (size_t)core->scene->triangle_count : 1;
    const device_buffer_request buffers[] = {
        {&p->gathered, core->slots * sizeof(cl_uint), "gather counts"},
        {&p->camera_importance, p->words * sizeof(cl_ulong), "camera importance"},
        {&p->light_importance, p->words * sizeof(cl_ulong), "light importance"},
    };
    p->scratch = xmalloc(p->words * sizeof *p->scratch);
    p->previous_camera = xcalloc(p->words, sizeof *p->previous_camera);
    p->previous_light = xcalloc(p->words, sizeof *p->previous_light);
    return device_create_kernel(core->program, "gather_count", &p->gather) ||
                   device_create_kernel(core->program, "path_importance", &p->path) ||
                   device_create_kernel(core->program, "pixel_centre_hits", &p->centre_hits) ||
                   device_buffers(core->dev, buffers, sizeof buffers / sizeof *buffers,
                                  &core->summary->buffer_bytes) ||
                   device_clear(core->dev, p->camera_importance, p->words * sizeof(cl_ulong),
                                "camera importance") ||
                   device_clear(core->dev, p->light_importance, p->words * sizeof(cl_ulong),
                                "light importance") ||
                   DEVICE_SET_ARG(core->camera_paths, "camera_paths", core->camera_pass_argument,
                                  p->camera_importance)
               ? -1
               : 0;
}

/* gather_count, then (when importance accumulates) the reverse path walk. */
static int gather(sppm *core, void *state)
{
    importance_pass *p = state;
    size_t local = core->options->local_size;
        if (DEVICE_SET_ARGS(p->gather, "gather_count", DEVICE_ARG(core->params),
                        DEVICE_ARG(core->photon_records), DEVICE_ARG(core->path_length),
                        DEVICE_ARG(core->hit_points), DEVICE_ARG(core->grid.cell_start),
                        DEVICE_ARG(core->grid.grid_points), DEVICE_ARG(p->gathered)) ||
        device_run(core->dev, p->gather, "gather_count", core->slots, local))
        return -1;
    if (!p->options->accumulate_importance)
        return 0;
    double start = monotonic_seconds();
    if (DEVICE_SET_ARGS(p->path, "path_importance", DEVICE_ARG(core->params),
                        DEVICE_ARG(core->photon_records), DEVICE_ARG(core->path_length),
                        DEVICE_ARG(p->gathered), DEVICE_ARG(p->light_importance)) ||
        device_run(core->dev, p->path, "path_importance", core->params.path_count, local))
        return -1;
    p->result->path_seconds += monotonic_seconds() - start;
    return 0;
}

/* Adds one accumulator to `sums` (checking saturation) and clears it. */
static int add_accumulator(sppm *core, importance_pass *p, cl_mem words, const char *name,
                           double *sums)
{
    size_t n = (size_t)core->scene->triangle_count;
    if (n && device_read(core->dev, words, n * sizeof *p->scratch, p->scratch, name))
        return -1;
    for (size_t t = 0; t < n; t++) {
        if (p->scratch[t] >= IDMR_FIXED_SATURATION)
            return error_set(IDMR_EXIT_FAILURE,
                             "%s of triangle %zu came within a factor 2 of the 64-bit fixed-point "
                             "limit in one iteration; use fewer photons per iteration",
                             name, t);
        sums[t] += (double)p->scratch[t] / IDMR_FIXED_SCALE;
    }
    return device_clear(core->dev, words, p->words * sizeof(cl_ulong), name);
}

/* Hit points found by the first iteration's photon vertices, for the report. */
static int count_gathered(sppm *core, importance_pass *p)
{
    uint32_t *gathered = xmalloc(core->slots * sizeof *gathered);
    int status = device_read(core->dev, p->gathered, core->slots * sizeof *gathered, gathered,
                             "gather counts");
    for (size_t i = 0; i < core->slots && !status; i++)
        p->result->gathered += gathered[i];
    free(gathered);
    return status;
}

/* Δ_n (importance.h) from the sums after n iterations and the ones before. */
static double convergence_change(const importance_pass *p, const scene *s, unsigned int n)
{
    const importance_result *r = p->result;
    float gamma = p->options->gamma;
    double change = 0, magnitude = 0;
    for (size_t t = 0; t < r->triangle_count; t++) {
        double area = scene_triangle_area(s, t);
        if (!(area > 0))
            continue;
        double now = (gamma * r->camera[t] + r->light[t]) / (n * area);
        double before =
            n > 1 ? (gamma * p->previous_camera[t] + p->previous_light[t]) / ((n - 1) * area)
                  : 0.0;
        change += (now - before) * (now - before);
        magnitude += now * now;
    }
    return magnitude > 0 ? change / magnitude : 0.0;
}

static int collect(sppm *core, void *state, unsigned int n, int *stop, char *detail,
                   size_t detail_size)
{
    importance_pass *p = state;
    importance_result *r = p->result;
    memcpy(p->previous_camera, r->camera, r->triangle_count * sizeof *r->camera);
    memcpy(p->previous_light, r->light, r->triangle_count * sizeof *r->light);
    if (add_accumulator(core, p, p->camera_importance, "camera importance", r->camera) ||
        add_accumulator(core, p, p->light_importance, "light importance", r->light) ||
        (n == 0 && count_gathered(core, p)))
        return -1;
    r->convergence[n] = convergence_change(p, core->scene, n + 1);
    snprintf(detail, detail_size, "change %.2e", r->convergence[n]);
    double tolerance = p->options->tolerance;
    p->calm = tolerance > 0 && r->convergence[n] < tolerance ? p->calm + 1 : 0;
    *stop = p->calm >= STOP_AFTER_CALM_ITERATIONS;
    return 0;
}

static int snapshot(sppm *core, void *state)
{
    importance_pass *p = state;
    importance_snapshot *out = p->options->snapshot;
        free(out->gathered);
    free(out->camera_fixed);
    free(out->light_fixed);
    out->gathered = xmalloc(core->slots * sizeof *out->gathered);
    out->camera_fixed = xmalloc(p->words * sizeof *out->camera_fixed);
    out->light_fixed = xmalloc(p->words * sizeof *out->light_fixed);
    return device_read(core->dev, p->gathered, core->slots * sizeof *out->gathered, out->gathered,
                       "gather counts") ||
                   device_read(core->dev, p->camera_importance, p->words * sizeof(cl_ulong),
                               out->camera_fixed, "camera importance") ||
                   device_read(core->dev, p->light_importance, p->words * sizeof(cl_ulong),
                               out->light_fixed, "light importance")
               ? -1
               : 0;
}

/* The triangle seen through each pixel centre of the hit-point image, for the importance
 * image: one more kernel on the core's upload, not a second program or BVH. */
static int finish(sppm *core, void *state)
{
    importance_pass *p = state;
    importance_result *r = p->result;
    size_t pixels = core->pixels;
    idmr_camera camera = core->scene->camera;
    cl_mem triangles = NULL;
    r->pixel_triangle = xmalloc(pixels * sizeof *r->pixel_triangle);
    int status =
        device_buffer(core->dev, CL_MEM_WRITE_ONLY, pixels * sizeof(cl_uint), NULL,
                      "pixel triangles", &triangles) ||
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
    cl_kernel kernels[] = {p->gather, p->path, p->centre_hits};
    device_release_kernels(kernels, sizeof kernels / sizeof *kernels);
    cl_mem buffers[] = {p->gathered, p->camera_importance, p->light_importance};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    free(p->scratch);
    free(p->previous_camera);
    free(p->previous_light);
}

void importance_snapshot_free(importance_snapshot *snapshot)
{
    sppm_snapshot_free(&snapshot->core);
    free(snapshot->gathered);
    free(snapshot->camera_fixed);
    free(snapshot->light_fixed);
    memset(snapshot, 0, sizeof *snapshot);
}

int importance_run(device *d, const scene *s, const bvh *b, const importance_options *o,
                   importance_result *r)
{
    memset(r, 0, sizeof *r);
    if (!(o->gamma >= 0))
        return error_set(IDMR_EXIT_INPUT, "importance: gamma must be >= 0");
    r->triangle_count = (size_t)s->triangle_count;
    r->camera = xcalloc(r->triangle_count + 1, sizeof *r->camera);
    r->light = xcalloc(r->triangle_count + 1, sizeof *r->light);
    r->convergence = xcalloc(o->sppm.iterations + 1, sizeof *r->convergence);
    importance_pass state;
    memset(&state, 0, sizeof state);
    state.options = o;
    state.result = r;
    char defines[96];
    importance_defines(o->accumulate_importance, o->gamma > 0, defines, sizeof defines);
    sppm_pass pass = {.name = "importance",
                      .pass = IDMR_SPPM_IMPORTANCE,
                      .defines = defines,
                      .photon_record_bytes = sizeof(idmr_photon_vertex),
                      .state = &state,
                      .prepare = prepare,
                      .gather = gather,
                      .collect = collect,
                      .snapshot = o->snapshot ? snapshot : NULL,
                      .finish = finish,
                      .release = release};
    int status =
        sppm_run(d, s, b, &o->sppm, &pass, &r->sppm, o->snapshot ? &o->snapshot->core : NULL);
    if (o->snapshot)
        o->snapshot->vertices = o->snapshot->core.photon_records;
    return status;
}

void importance_result_free(importance_result *r)
{
    free(r->camera);
    free(r->light);
    free(r->convergence);
    free(r->pixel_triangle);
    sppm_summary_free(&r->sppm);
    memset(r, 0, sizeof *r);
}

double importance_triangle(const importance_result *r, const scene *s, float gamma, uint64_t t)
{
    double area = scene_triangle_area(s, t);
    if (!(area > 0) || r->sppm.iterations == 0)
        return 0.0;
    return (gamma * r->camera[t] + r->light[t]) / (r->sppm.iterations * area);
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
    unsigned int iterations = r->sppm.iterations;
    for (uint32_t v = 0; v < mesh->vertex_count; v++)
        vertex_importance[v] =
            area[v] > 0 && iterations ? vertex_importance[v] / (iterations * area[v]) : 0.0;
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
    double n = r->sppm.iterations ? r->sppm.iterations : 1;
    *camera_sum = camera / n;
    *light_sum = light / n;
    *importance_sum = (gamma * camera + light) / n;
}
