/* importance_report.c — the files of an importance pass (see importance_report.h). */
#include "passes/importance_report.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "device/device_scene.h"
#include "core/error.h"
#include "idmr/ray.h"
#include "io/image.h"
#include "io/mesh_io.h"
#include "core/files.h"
#include "core/json.h"

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
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddStringToObject(root, "device", d->info.name);
    cJSON_AddNumberToObject(root, "iterations", r->iterations);
    cJSON_AddNumberToObject(root, "iterations_requested", o->sppm.iterations);
    cJSON_AddNumberToObject(root, "tolerance", o->tolerance);
    cJSON_AddNumberToObject(root, "photons_per_iteration", r->photons);
    cJSON_AddNumberToObject(root, "gamma", o->gamma);
    cJSON_AddNumberToObject(root, "seed", o->sppm.seed);
    cJSON_AddNumberToObject(root, "alpha", o->sppm.alpha);
    cJSON *film = cJSON_AddArrayToObject(root, "hit_point_image");
    cJSON_AddItemToArray(film, cJSON_CreateNumber(r->width));
    cJSON_AddItemToArray(film, cJSON_CreateNumber(r->height));
    cJSON_AddNumberToObject(root, "initial_radius", r->iterations ? r->radius[0] : 0);
    cJSON_AddNumberToObject(root, "final_radius", r->iterations ? r->radius[r->iterations - 1] : 0);
    cJSON_AddStringToObject(root, "build_options", r->build_options ? r->build_options : "");
    cJSON_AddNumberToObject(root, "device_bytes", (double)r->device_bytes);
    cJSON *first = cJSON_AddObjectToObject(root, "first_iteration");
    cJSON_AddNumberToObject(first, "hit_points", (double)r->hit_points);
    cJSON_AddNumberToObject(first, "photon_vertices", (double)r->photon_vertices);
    cJSON_AddNumberToObject(first, "gathered", (double)r->gathered);

    cJSON *seconds = cJSON_AddObjectToObject(root, "seconds");
    cJSON_AddNumberToObject(seconds, "build", r->seconds.build);
    cJSON_AddNumberToObject(seconds, "camera", r->seconds.camera);
    cJSON_AddNumberToObject(seconds, "photon", r->seconds.photon);
    cJSON_AddNumberToObject(seconds, "grid", r->seconds.grid);
    cJSON_AddNumberToObject(seconds, "gather", r->seconds.gather);
    cJSON_AddNumberToObject(seconds, "path", r->seconds.path);
    cJSON_AddNumberToObject(seconds, "readback", r->seconds.readback);
    cJSON_AddNumberToObject(seconds, "total", r->seconds.total);

    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    for (size_t m = 0; m < s->mesh_count; m++) {
        double sum, camera, light;
        importance_mesh_sums(r, s, m, o->gamma, &sum, &camera, &light);
        cJSON *mesh = cJSON_CreateObject();
        cJSON_AddStringToObject(mesh, "name", s->meshes[m].name);
        cJSON_AddNumberToObject(mesh, "vertices", s->meshes[m].vertex_count);
        cJSON_AddNumberToObject(mesh, "triangles", s->meshes[m].triangle_count);
        cJSON_AddNumberToObject(mesh, "importance_sum", sum);
        cJSON_AddNumberToObject(mesh, "camera_sum", camera);
        cJSON_AddNumberToObject(mesh, "light_sum", light);
        cJSON_AddItemToArray(meshes, mesh);
    }
    cJSON_AddItemToObject(root, "convergence",
                          cJSON_CreateDoubleArray(r->convergence, (int)r->iterations));
    return root;
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
    size_t size = 64 + 64 * (size_t)r->iterations, length = 0;
    char *text = xmalloc(size);
    length += (size_t)snprintf(text, size, "iteration,change,radius\n");
    for (unsigned int n = 0; n < r->iterations; n++)
        length += (size_t)snprintf(text + length, size - length, "%u,%.9g,%.9g\n", n + 1,
                                   r->convergence[n], r->radius[n]);
    int status = files_write_atomic(path, text, length);
    free(text);
    return status;
}

static int write_mesh_files(const char *dir, const scene *s, const importance_options *o,
                            const importance_result *r)
{
    double **values = xcalloc(s->mesh_count + 1, sizeof *values);
    size_t total = 0;
    for (size_t m = 0; m < s->mesh_count; m++) {
        values[m] = xmalloc((s->meshes[m].vertex_count + 1) * sizeof **values);
        importance_mesh_vertices(r, s, m, o->gamma, values[m]);
        total += s->meshes[m].vertex_count;
    }
    double *all = xmalloc((total + 1) * sizeof *all);
    size_t at = 0;
    for (size_t m = 0; m < s->mesh_count; m++)
        for (uint32_t v = 0; v < s->meshes[m].vertex_count; v++)
            all[at++] = values[m][v];
    double top = percentile99(all, total);
    free(all);

    int status = 0;
    for (size_t m = 0; m < s->mesh_count && !status; m++) {
        const scene_mesh *mesh = &s->meshes[m];
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
                          mesh->indices, NULL};
        status = mesh_io_write_ply(path, &data, property, "importance", colours);
        free(property);
        free(colours);
    }
    for (size_t m = 0; m < s->mesh_count; m++)
        free(values[m]);
    free(values);
    return status;
}

/* Traces one ray through each pixel centre of the hit-point image and colours the pixel by the
 * importance of the triangle it sees. */
static int write_importance_image(const char *path, const scene *s, const bvh *b, device *d,
                                  const importance_options *o, const importance_result *r)
{
    unsigned int width = r->width, height = r->height;
    size_t pixels = (size_t)width * height;
    idmr_ray *rays = xmalloc(pixels * sizeof *rays);
    idmr_hit *hits = xmalloc(pixels * sizeof *hits);
    const idmr_camera *c = &s->camera;
    for (unsigned int y = 0; y < height; y++)
        for (unsigned int x = 0; x < width; x++) {
            float sx = (2.0f * (x + 0.5f) / width - 1.0f) * c->tan_half_x;
            float sy = (1.0f - 2.0f * (y + 0.5f) / height) * c->tan_half_y;
            idmr_ray *ray = &rays[(size_t)y * width + x];
            for (int k = 0; k < 3; k++) {
                ray->origin[k] = c->origin[k];
                ray->direction[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
            }
            ray->tmin = 0.0f;
            ray->tmax = INFINITY;
        }
    cl_program program = NULL;
    cl_kernel kernel = NULL;
    cl_mem nodes = NULL, leaves = NULL, ray_buffer = NULL, hit_buffer = NULL;
    char *options = device_build_options(d, s->features, NULL);
    cl_uint count = (cl_uint)pixels;
    int status =
        device_build_program(d, "trace.cl", options, &program) ||
        device_create_kernel(program, "trace_closest", &kernel) ||
        device_scene_upload_bvh(d, b, &nodes, &leaves) ||
        device_buffer(d, CL_MEM_READ_ONLY, pixels * sizeof *rays, rays, "image rays", &ray_buffer) ||
        device_buffer(d, CL_MEM_WRITE_ONLY, pixels * sizeof *hits, NULL, "image hits",
                      &hit_buffer) ||
        DEVICE_SET_ARGS(kernel, "trace_closest", DEVICE_ARG(ray_buffer), DEVICE_ARG(hit_buffer),
                        DEVICE_ARG(count), DEVICE_ARG(nodes), DEVICE_ARG(leaves)) ||
        device_run(d, kernel, "trace_closest", pixels, 0) ||
        device_read(d, hit_buffer, pixels * sizeof *hits, hits, "image hits");
    free(options);
    cl_mem buffers[] = {nodes, leaves, ray_buffer, hit_buffer};
    device_release_buffers(buffers, sizeof buffers / sizeof *buffers);
    device_release_kernels(&kernel, 1);
    if (program)
        clReleaseProgram(program);
    if (!status) {
        double *triangle = xmalloc((r->triangle_count + 1) * sizeof *triangle);
        for (size_t t = 0; t < r->triangle_count; t++)
            triangle[t] = importance_triangle(r, s, o->gamma, t);
        double top = percentile99(triangle, r->triangle_count);
        unsigned char *rgb = xmalloc(3 * pixels);
        for (size_t i = 0; i < pixels; i++) {
            double value = hits[i].triangle == IDMR_NO_HIT ? 0 : triangle[hits[i].triangle];
            image_false_colour(colour_position(value, top), &rgb[3 * i]);
        }
        status = image_write_rgb8(path, (int)width, (int)height, rgb);
        free(rgb);
        free(triangle);
    }
    free(rays);
    free(hits);
    return status ? -1 : 0;
}

int importance_write_outputs(const char *dir, const cJSON *report, const scene *s, const bvh *b,
                             device *d, const importance_options *o, const importance_result *r)
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
    if (write_mesh_files(dir, s, o, r))
        return -1;
    snprintf(path, sizeof path, "%s/importance.png", dir);
    return write_importance_image(path, s, b, d, o, r);
}
