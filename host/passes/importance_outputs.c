/* importance_outputs.c — the files of an importance pass (see importance_outputs.h). */
#include "passes/importance_outputs.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "core/json.h"
#include "core/ranks.h"
#include "io/image.h"
#include "io/mesh/mesh_io.h"
#include "io/mesh/ply_check.h"

void importance_file_name(const char *mesh_name, char *out, size_t size)
{
    size_t n = 0;
    for (const char *c = mesh_name; *c && n + 1 < size; c++) {
        int keep = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                   (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' || (*c == '.' && n > 0);
        out[n++] = keep ? *c : '_';
    }
    out[n] = '\0';
    if (n == 0)
        snprintf(out, size, "mesh");
}

cJSON *importance_report_json(const scene *s, const device *d, const importance_options *o,
                              const importance_result *r)
{
    const sppm_summary *run = &r->sppm;
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddStringToObject(root, "device", d->info.name);
    cJSON_AddNumberToObject(root, "iterations", run->iterations);
    cJSON_AddNumberToObject(root, "iterations_requested", o->sppm.iterations);
    cJSON_AddNumberToObject(root, "tolerance", o->tolerance);
    cJSON_AddNumberToObject(root, "photons_per_iteration", run->photons);
    cJSON_AddNumberToObject(root, "gamma", o->gamma);
    cJSON_AddNumberToObject(root, "shadow_weight", o->shadow_weight);
    cJSON_AddNumberToObject(root, "seed", o->sppm.seed);
    cJSON_AddNumberToObject(root, "alpha", o->sppm.alpha);
    cJSON *film = cJSON_AddArrayToObject(root, "hit_point_image");
    cJSON_AddItemToArray(film, cJSON_CreateNumber(run->width));
    cJSON_AddItemToArray(film, cJSON_CreateNumber(run->height));
    cJSON_AddNumberToObject(root, "initial_radius", run->iterations ? run->radius[0] : 0);
    cJSON_AddNumberToObject(root, "final_radius",
                            run->iterations ? run->radius[run->iterations - 1] : 0);
    cJSON_AddStringToObject(root, "build_options", run->build_options ? run->build_options : "");
    cJSON_AddNumberToObject(root, "device_bytes",
                            (double)(run->geometry_bytes + run->bvh_bytes + run->buffer_bytes));
    /* Every device the pass ran on, and the photon paths it traced (sppm.h: split, rebalanced) */
    cJSON *devices = cJSON_AddArrayToObject(root, "devices");
    for (unsigned int k = 0; k < run->devices; k++) {
        const sppm_device_share *share = run->device + k;
        cJSON *each = cJSON_CreateObject();
        cJSON_AddNumberToObject(each, "index", share->index);
        cJSON_AddStringToObject(each, "name", share->name);
        cJSON_AddNumberToObject(each, "paths", (double)share->paths);
        cJSON_AddNumberToObject(each, "paths_last_iteration", share->last_paths);
        cJSON_AddNumberToObject(each, "path_capacity", share->capacity);
        cJSON_AddNumberToObject(each, "photon_seconds", share->photon_seconds);
        cJSON_AddNumberToObject(each, "device_bytes", (double)share->bytes);
        cJSON_AddItemToArray(devices, each);
    }
    /* Under mpirun (core/ranks.h): the ranks that shared the photon paths; `devices` is then
     * rank 0's, with its own share of the paths. */
    if (ranks_count() > 1)
        cJSON_AddNumberToObject(root, "ranks", ranks_count());
    cJSON *first = cJSON_AddObjectToObject(root, "first_iteration");
    cJSON_AddNumberToObject(first, "hit_points", (double)run->hit_points);
    cJSON_AddNumberToObject(first, "photon_vertices", (double)run->photon_records);
    cJSON_AddNumberToObject(first, "gathered", (double)r->gathered);
    double light = 0;
    for (size_t t = 0; t < r->triangle_count; t++)
        light += r->light[t];
    cJSON_AddNumberToObject(root, "seen_light_share", light > 0 ? r->seen_light / light : 0.0);

    cJSON *seconds = cJSON_AddObjectToObject(root, "seconds");
    cJSON_AddNumberToObject(seconds, "build", run->seconds.build);
    cJSON_AddNumberToObject(seconds, "camera", run->seconds.camera);
    cJSON_AddNumberToObject(seconds, "photon", run->seconds.photon);
    cJSON_AddNumberToObject(seconds, "grid", run->seconds.grid);
    cJSON_AddNumberToObject(seconds, "shadow", r->shadow_seconds);
    cJSON_AddNumberToObject(seconds, "gather",
                            run->seconds.gather - r->path_seconds - r->shadow_seconds);
    cJSON_AddNumberToObject(seconds, "path", r->path_seconds);
    cJSON_AddNumberToObject(seconds, "readback", run->seconds.collect);
    cJSON_AddNumberToObject(seconds, "total", run->seconds.total);

    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    importance_weights weights = importance_weights_of(o);
    for (size_t m = 0; m < s->mesh_count; m++) {
        cJSON *mesh = cJSON_CreateObject();
        cJSON_AddStringToObject(mesh, "name", s->meshes[m].name);
        cJSON_AddNumberToObject(mesh, "vertices", s->meshes[m].vertex_count);
        cJSON_AddNumberToObject(mesh, "triangles", s->meshes[m].triangle_count);
        cJSON_AddItemToArray(meshes, mesh);
        if (scene_mesh_is_later_copy(s, m)) {
            /* its triangles are its prototype's: the sums stand on the first copy, over all */
            cJSON_AddStringToObject(mesh, "instance_of",
                                    s->meshes[s->meshes[m].instance_first].name);
        } else {
            importance_sums sums = importance_mesh_sums(r, s, m, &weights);
            cJSON_AddNumberToObject(mesh, "importance_sum", sums.amount);
            cJSON_AddNumberToObject(mesh, "camera_sum", sums.camera);
            cJSON_AddNumberToObject(mesh, "light_sum", sums.light);
            cJSON_AddNumberToObject(mesh, "shadow_sum", sums.shadow);
        }
        if (s->meshes[m].instanced) { /* this copy's own, of the sums above over all copies */
            importance_sums own = importance_copy_sums(r, s, m, &weights);
            cJSON_AddNumberToObject(mesh, "copy_importance_sum", own.amount);
            cJSON_AddNumberToObject(mesh, "copy_camera_sum", own.camera);
            cJSON_AddNumberToObject(mesh, "copy_light_sum", own.light);
            cJSON_AddNumberToObject(mesh, "copy_shadow_sum", own.shadow);
        }
    }
    cJSON_AddItemToObject(root, "convergence",
                          cJSON_CreateDoubleArray(r->convergence, (int)run->iterations));
    return root;
}

double **importance_vertex_values(const importance_result *r, const scene *s,
                                  const importance_weights *w)
{
    double **values = xcalloc(s->mesh_count + 1, sizeof *values);
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (scene_mesh_is_later_copy(s, m))
            continue; /* no vertices of its own: its representative's are the prototype's */
        values[m] = xmalloc((s->meshes[m].vertex_count + 1) * sizeof **values);
        importance_mesh_vertices(r, s, m, w, values[m]);
    }
    return values;
}

void importance_vertex_values_free(double **values, const scene *s)
{
    for (size_t m = 0; values && m < s->mesh_count; m++)
        free(values[m]);
    free(values);
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The 99th percentile of the non-zero values (0 if there are none). */
static double percentile99(const double *values, size_t count)
{
    double *nonzero = xmalloc((count ? count : 1) * sizeof *nonzero);
    size_t n = 0;
    for (size_t i = 0; i < count; i++)
        if (values[i] > 0)
            nonzero[n++] = values[i];
    double result = 0;
    if (n) {
        qsort(nonzero, n, sizeof *nonzero, compare_doubles);
        result = nonzero[(size_t)(0.99 * (double)(n - 1))];
    }
    free(nonzero);
    return result;
}

static float colour_position(double value, double top)
{
    if (!(value > 0) || !(top > 0))
        return 0.0f;
    return (float)((log10(value) - (log10(top) - 3.0)) / 3.0);
}

static int write_convergence_csv(const char *path, const importance_result *r)
{
    unsigned int iterations = r->sppm.iterations;
    size_t size = 64 + 64 * (size_t)iterations, length = 0;
    char *text = xmalloc(size);
    length += (size_t)snprintf(text, size, "iteration,change,radius\n");
    for (unsigned int n = 0; n < iterations; n++)
        length += (size_t)snprintf(text + length, size - length, "%u,%.9g,%.9g\n", n + 1,
                                   r->convergence[n], r->sppm.radius[n]);
    int status = files_write_atomic(path, text, length);
    free(text);
    return status;
}

/* The 99th percentile of the non-zero per-vertex importance of all meshes. */
static double vertex_percentile99(const scene *s, double *const *values)
{
    size_t total = 0;
    for (size_t m = 0; m < s->mesh_count; m++)
        total += values[m] ? s->meshes[m].vertex_count : 0;
    double *all = xmalloc((total + 1) * sizeof *all);
    size_t at = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (!values[m])
            continue;
        memcpy(all + at, values[m], s->meshes[m].vertex_count * sizeof *all);
        at += s->meshes[m].vertex_count;
    }
    double top = percentile99(all, total);
    free(all);
    return top;
}

static int write_mesh_files(const char *dir, const scene *s, double *const *values)
{
    double top = vertex_percentile99(s, values);
    int status = 0;
    for (size_t m = 0; m < s->mesh_count && !status; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        if (!values[m])
            continue; /* a later copy of an instanced shape: its representative's file shows it */
        float *property = xmalloc((mesh->vertex_count + 1) * sizeof *property);
        unsigned char *colours = xmalloc(3 * ((size_t)mesh->vertex_count + 1));
        for (uint32_t v = 0; v < mesh->vertex_count; v++) {
            property[v] = (float)values[m][v];
            image_false_colour(colour_position(values[m][v], top), &colours[3 * (size_t)v]);
        }
        char name[256], path[4096];
        importance_file_name(mesh->name, name, sizeof name);
        snprintf(path, sizeof path, "%s/importance/%s.ply", dir, name);
        mesh_data data = {mesh->vertex_count, mesh->triangle_count, mesh->positions,
                          mesh->indices, NULL, NULL, 0};
        status = mesh_io_write_ply(path, &data, property, "importance", colours) ||
                 ply_check_written(path);
        free(property);
        free(colours);
    }
    return status;
}

/* Colours each pixel of the hit-point image by the importance of the triangle seen through its
 * centre (the pass's pixel_triangle). */
static int write_importance_image(const char *path, const scene *s, const importance_options *o,
                                  const importance_result *r)
{
    unsigned int width = r->sppm.width, height = r->sppm.height;
    size_t pixels = (size_t)width * height;
    importance_weights weights = importance_weights_of(o);
    double *triangle = xmalloc((r->triangle_count + 1) * sizeof *triangle);
    for (size_t t = 0; t < r->triangle_count; t++)
        triangle[t] = importance_triangle(r, s, &weights, t);
    double top = percentile99(triangle, r->triangle_count);
    unsigned char *rgb = xmalloc(3 * pixels);
    for (size_t i = 0; i < pixels; i++) {
        uint32_t seen = r->pixel_triangle[i];
        double value = seen < r->triangle_count ? triangle[seen] : 0;
        image_false_colour(colour_position(value, top), &rgb[3 * i]);
    }
    int status = image_write_rgb8(path, (int)width, (int)height, rgb);
    free(rgb);
    free(triangle);
    return status;
}

int importance_write_outputs(const char *dir, const cJSON *report, const scene *s,
                             const importance_options *o, const importance_result *r,
                             double *const *vertex_values)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/importance", dir);
    if (files_make_directory(dir) || files_make_directory(path))
        return -1;
    snprintf(path, sizeof path, "%s/report.json", dir);
    if (json_write(report, path))
        return -1;
    snprintf(path, sizeof path, "%s/convergence.csv", dir);
    if (write_convergence_csv(path, r))
        return -1;
    if (write_mesh_files(dir, s, vertex_values))
        return -1;
    snprintf(path, sizeof path, "%s/importance.png", dir);
    return write_importance_image(path, s, o, r);
}
