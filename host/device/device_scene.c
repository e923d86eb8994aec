/* device_scene.c — uploads a scene for the light transport kernels (see device_scene.h). */
#include "device/device_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "idmr/environment.h"
#include "idmr/normal_packing.h"
#include "idmr/ray.h"

/* The offset of rays leaving triangle (a, b, c) (idmr/ray.h), from the largest coordinate
 * magnitude of its vertices (for a ray that arrived, the kernels also weigh its origin). */
static float triangle_ray_offset(const float *a, const float *b, const float *c)
{
    float largest = 0.0f;
    for (int k = 0; k < 3; k++)
        largest = fmaxf(largest, fmaxf(fabsf(a[k]), fmaxf(fabsf(b[k]), fabsf(c[k]))));
    return fmaxf(IDMR_RAY_OFFSET_MIN, IDMR_RAY_OFFSET_SCALE * largest);
}

/* Triangle t's shading normals: its corners' vertex normals packed (idmr/normal_packing.h)
 * with w = 1, or w = 0 (shaded flat) when the mesh has none or one of them is zero. */
static void shading_corners(const scene_mesh *mesh, uint32_t t, uint32_t out[4])
{
    memset(out, 0, 4 * sizeof *out);
    if (!mesh->normals)
        return;
    for (int corner = 0; corner < 3; corner++) {
        const float *n = &mesh->normals[3 * (size_t)mesh->indices[3 * (size_t)t + corner]];
        if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.0f))
            return;
        out[corner] = idmr_pack_unit_vector(n[0], n[1], n[2]);
    }
    out[3] = 1u;
}

/* Per-triangle unit normals (w = the ray offset), shading normals and material indices. A
 * degenerate triangle gets a zero normal (the traversal never returns it). A later copy of an
 * instanced shape is skipped: its triangles are its representative's. */
static void triangle_data(const scene *s, float *normals, uint32_t *shading,
                          uint32_t *material_of)
{
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (scene_mesh_is_later_copy(s, m))
            continue;
        const scene_mesh *mesh = &s->meshes[m];
        for (uint32_t t = 0; t < mesh->triangle_count; t++) {
            const uint32_t *ix = &mesh->indices[3 * (size_t)t];
            const float *a = &mesh->positions[3 * (size_t)ix[0]];
            const float *b = &mesh->positions[3 * (size_t)ix[1]];
            const float *c = &mesh->positions[3 * (size_t)ix[2]];
            double e1[3], e2[3];
            for (int k = 0; k < 3; k++) {
                e1[k] = (double)b[k] - a[k];
                e2[k] = (double)c[k] - a[k];
            }
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
            double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            float *out = &normals[4 * ((size_t)mesh->first_triangle + t)];
            for (int k = 0; k < 3; k++)
                out[k] = length > 0 ? (float)(n[k] / length) : 0.0f;
            out[3] = triangle_ray_offset(a, b, c);
            shading_corners(mesh, t, &shading[4 * ((size_t)mesh->first_triangle + t)]);
            material_of[mesh->first_triangle + t] = mesh->material;
        }
    }
}

/* The BVH's nodes and leaf triangles (an empty scene still binds a leaf buffer), and a
 * two-level BVH's top nodes and instances (a flat one binds device_buffer's 16-byte placeholder
 * for each: its program never reads them). */
static int upload_bvh(device *d, const bvh *b, device_scene *out)
{
    idmr_triangle4 empty_leaf;
    memset(&empty_leaf, 0, sizeof empty_leaf);
    return device_buffer(d, CL_MEM_READ_ONLY, b->node_count * sizeof(idmr_bvh_node), b->nodes,
                         "BVH nodes", &out->nodes) ||
                   device_buffer(d, CL_MEM_READ_ONLY,
                                 (b->leaf_count ? b->leaf_count : 1) * sizeof(idmr_triangle4),
                                 b->leaf_count ? (void *)b->leaves : &empty_leaf, "BVH leaves",
                                 &out->leaves) ||
                   device_buffer(d, CL_MEM_READ_ONLY, b->top_node_count * sizeof(idmr_bvh_node),
                                 b->top_nodes, "BVH top nodes", &out->top_nodes) ||
                   device_buffer(d, CL_MEM_READ_ONLY, b->instance_count * sizeof(idmr_instance),
                                 b->instances, "BVH instances", &out->instances)
               ? -1
               : 0;
}

/* Floats of the environment buffer (idmr/environment.h): a header alone without a map. */
static size_t environment_floats(const scene *s)
{
    const scene_environment *e = &s->environment;
    return e->width ? (size_t)idmr_env_floats((unsigned int)e->width, (unsigned int)e->height)
                    : IDMR_ENV_HEADER;
}

uint64_t device_scene_geometry_bytes(const scene *s)
{
    uint64_t triangles = s->triangle_count ? s->triangle_count : 1;
    uint64_t lights = s->light_count ? s->light_count : 1, emitters = 0;
    for (size_t i = 0; i < s->light_count; i++)
        if (s->lights[i].kind == IDMR_LIGHT_AREA)
            emitters += s->lights[i].triangle_count;
    /* Per triangle a float4 normal, a uint4 of shading normals and a material index; per
     * light its struct and CDF entry; per emitter triangle a CDF entry and three float4. */
    return triangles * (4 * sizeof(float) + 4 * sizeof(uint32_t) + sizeof(uint32_t)) +
           (s->material_count ? s->material_count : 1) * sizeof(idmr_material) +
           lights * (sizeof(idmr_light) + sizeof(float)) +
           (emitters ? emitters : 1) * (sizeof(float) + 12 * sizeof(float)) +
           environment_floats(s) * sizeof(float);
}

/* The environment buffer (idmr/environment.h): header, the CDFs of the pixel weights
 * Y(L) × ΔΩ (summed in double), the radiance. A row without light gets a uniform CDF it is
 * never chosen by. */
static float *environment_build(const scene *s)
{
    const scene_environment *e = &s->environment;
    float *out = xcalloc(environment_floats(s), sizeof *out);
    if (!e->width)
        return out;
    unsigned int width = (unsigned int)e->width, height = (unsigned int)e->height;
    for (int k = 0; k < 9; k++) {
        out[IDMR_ENV_TO_WORLD + k] = (float)e->to_world[k];
        out[IDMR_ENV_TO_MAP + k] = (float)e->to_map[k];
    }
    out[IDMR_ENV_INTEGRAL] = (float)e->luminance_integral;
    out[IDMR_ENV_WIDTH] = (float)width;
    out[IDMR_ENV_HEIGHT] = (float)height;
    float *marginal = out + idmr_env_marginal(), *conditional = out + idmr_env_conditional(height);
    double *row_weight = xcalloc(height, sizeof *row_weight), total = 0;
    for (unsigned int y = 0; y < height; y++) {
        const float *row = e->rgb + 3 * (size_t)y * width;
        float *cdf = conditional + (size_t)y * width;
        double running = 0;
        for (unsigned int x = 0; x < width; x++) {
            running += idmr_luminance(row[3 * x], row[3 * x + 1], row[3 * x + 2]);
            cdf[x] = (float)running;
        }
        for (unsigned int x = 0; x < width; x++)
            cdf[x] = running > 0 ? (float)(cdf[x] / running) : (float)(x + 1) / (float)width;
        cdf[width - 1] = 1.0f;
        row_weight[y] = running * scene_environment_pixel_solid_angle(e->width, e->height, (int)y);
        total += row_weight[y];
    }
    double running = 0;
    for (unsigned int y = 0; y < height; y++) {
        running += row_weight[y];
        marginal[y] = total > 0 ? (float)(running / total) : (float)(y + 1) / (float)height;
    }
    marginal[height - 1] = 1.0f;
    free(row_weight);
    memcpy(out + idmr_env_radiance(width, height), e->rgb, 3 * sizeof(float) * width * height);
    return out;
}

/* What the upload copies to the device, built on the host; counts are at least 1 (a buffer
 * of zero bytes is invalid, kernels never read the unused entry). */
typedef struct upload_arrays {
    size_t triangles, lights, emitters;
    float *normals;           /* 4 per triangle */
    uint32_t *shading;        /* 4 per triangle */
    uint32_t *material_of;    /* per triangle */
    idmr_light *light;        /* the scene's lights with cdf_offset filled */
    float *light_cdf;         /* per light */
    float *emitter_cdf;       /* per emitter triangle */
    float *emitter_triangles; /* 12 per emitter triangle */
    float *environment;       /* idmr/environment.h */
} upload_arrays;

/* Lights are chosen in proportion to power (uniformly if none has any): their CDF. */
static void fill_light_cdf(const scene *s, upload_arrays *a)
{
    double total_power = 0, running = 0;
    for (size_t i = 0; i < s->light_count; i++)
        total_power += s->lights[i].power > 0 ? s->lights[i].power : 0;
    for (size_t i = 0; i < s->light_count; i++) {
        running += s->lights[i].power > 0 ? s->lights[i].power : 0;
        a->light_cdf[i] = total_power > 0 ? (float)(running / total_power)
                                          : (float)(i + 1) / (float)s->light_count;
    }
    if (s->light_count)
        a->light_cdf[s->light_count - 1] = 1.0f;
}

/* Area light l's triangles from entry `at` on: v0 (w: the offset of rays leaving it),
 * v1 - v0, v2 - v0, and the CDF of their areas (each light's stretch ends at 1). Returns the
 * entry after them. */
static size_t fill_emitter(const scene *s, idmr_light *l, size_t at, upload_arrays *a)
{
    l->cdf_offset = (unsigned int)at;
    /* An area light is one mesh's triangles; its total area is l->area (scene_finalize). */
    const scene_mesh *mesh = &s->meshes[scene_mesh_of_triangle(s, l->first_triangle)];
    uint32_t first = (uint32_t)(l->first_triangle - mesh->first_triangle);
    double area_running = 0;
    for (uint32_t t = 0; t < l->triangle_count; t++, at++) {
        const uint32_t *ix = &mesh->indices[3 * (size_t)(first + t)];
        const float *v0 = &mesh->positions[3 * (size_t)ix[0]];
        const float *v1 = &mesh->positions[3 * (size_t)ix[1]];
        const float *v2 = &mesh->positions[3 * (size_t)ix[2]];
        for (int k = 0; k < 3; k++) {
            a->emitter_triangles[12 * at + k] = v0[k];
            a->emitter_triangles[12 * at + 4 + k] = v1[k] - v0[k];
            a->emitter_triangles[12 * at + 8 + k] = v2[k] - v0[k];
        }
        a->emitter_triangles[12 * at + 3] = triangle_ray_offset(v0, v1, v2);
        area_running += scene_mesh_triangle_area(mesh, first + t);
        a->emitter_cdf[at] = l->area > 0 ? (float)(area_running / l->area)
                                         : (float)(t + 1) / (float)l->triangle_count;
    }
    if (l->triangle_count)
        a->emitter_cdf[at - 1] = 1.0f;
    return at;
}

static void arrays_build(const scene *s, upload_arrays *a)
{
    memset(a, 0, sizeof *a);
    a->triangles = s->triangle_count ? (size_t)s->triangle_count : 1;
    a->lights = s->light_count ? s->light_count : 1;
    for (size_t i = 0; i < s->light_count; i++)
        if (s->lights[i].kind == IDMR_LIGHT_AREA)
            a->emitters += s->lights[i].triangle_count;
    a->emitters = a->emitters ? a->emitters : 1;
    a->normals = xcalloc(4 * a->triangles, sizeof *a->normals);
    a->shading = xcalloc(4 * a->triangles, sizeof *a->shading);
    a->material_of = xcalloc(a->triangles, sizeof *a->material_of);
    triangle_data(s, a->normals, a->shading, a->material_of);
    a->light = xcalloc(a->lights, sizeof *a->light);
    if (s->light_count) /* a scene without lights has no array to copy from */
        memcpy(a->light, s->lights, s->light_count * sizeof *a->light);
    a->light_cdf = xcalloc(a->lights, sizeof *a->light_cdf);
    fill_light_cdf(s, a);
    a->emitter_cdf = xcalloc(a->emitters, sizeof *a->emitter_cdf);
    a->emitter_triangles = xcalloc(12 * a->emitters, sizeof *a->emitter_triangles);
    size_t at = 0;
    for (size_t i = 0; i < s->light_count; i++)
        if (a->light[i].kind == IDMR_LIGHT_AREA)
            at = fill_emitter(s, &a->light[i], at, a);
    a->environment = environment_build(s);
}

static void arrays_free(upload_arrays *a)
{
    free(a->normals);
    free(a->shading);
    free(a->material_of);
    free(a->light);
    free(a->light_cdf);
    free(a->emitter_cdf);
    free(a->emitter_triangles);
    free(a->environment);
}

static int arrays_upload(device *d, const scene *s, const upload_arrays *a, device_scene *out)
{
    idmr_material no_material; /* a scene without materials still binds the buffer */
    memset(&no_material, 0, sizeof no_material);
    size_t materials = s->material_count ? s->material_count : 1;
    const void *material_data = s->material_count ? (const void *)s->materials : &no_material;
    cl_mem_flags read = CL_MEM_READ_ONLY;
    return device_buffer(d, read, 4 * sizeof(float) * a->triangles, a->normals,
                         "triangle normals", &out->triangle_normals) ||
                   device_buffer(d, read, 4 * sizeof(uint32_t) * a->triangles, a->shading,
                                 "shading normals", &out->triangle_shading) ||
                   device_buffer(d, read, sizeof(uint32_t) * a->triangles, a->material_of,
                                 "triangle materials", &out->triangle_materials) ||
                   device_buffer(d, read, sizeof(idmr_material) * materials, material_data,
                                 "materials", &out->materials) ||
                   device_buffer(d, read, sizeof(idmr_light) * a->lights, a->light, "lights",
                                 &out->lights) ||
                   device_buffer(d, read, sizeof(float) * a->lights, a->light_cdf, "light CDF",
                                 &out->light_cdf) ||
                   device_buffer(d, read, sizeof(float) * a->emitters, a->emitter_cdf,
                                 "emitter CDF", &out->emitter_cdf) ||
                   device_buffer(d, read, 12 * sizeof(float) * a->emitters, a->emitter_triangles,
                                 "emitter triangles", &out->emitter_triangles) ||
                   device_buffer(d, read, sizeof(float) * environment_floats(s), a->environment,
                                 "environment map", &out->environment)
               ? -1
               : 0;
}

int device_scene_upload(device *d, const scene *s, const bvh *b, device_scene *out)
{
    memset(out, 0, sizeof *out);
    for (int k = 0; k < 3; k++)
        out->center[k] = 0.5f * (s->bbox_min[k] + s->bbox_max[k]);
    out->radius = (float)(0.5 * scene_diagonal(s));
    out->light_count = (unsigned int)s->light_count;
    out->instanced = b->top_nodes != NULL;
    if (out->instanced != ((s->features & IDMR_FEATURE_INSTANCES) != 0))
        return error_set(IDMR_EXIT_FAILURE, "device_scene_upload: a %s BVH for a scene %s "
                                            "instanced shapes' later copies",
                         out->instanced ? "two-level" : "flat",
                         out->instanced ? "without" : "with");
    out->bvh_bytes = bvh_device_bytes(b);
    out->bytes = out->bvh_bytes + device_scene_geometry_bytes(s);
    upload_arrays arrays;
    arrays_build(s, &arrays);
    int status = upload_bvh(d, b, out) || arrays_upload(d, s, &arrays, out);
    arrays_free(&arrays);
    if (status)
        device_scene_release(out);
    return status ? -1 : 0;
}

/* The buffers in SCENE_BUFFERS order (kernels/lib/scene.h). */
#define SCENE_BUFFER_LIST(ds)                                                                \
    {&(ds)->nodes,           &(ds)->leaves,          &(ds)->top_nodes,                         \
     &(ds)->instances,       &(ds)->triangle_normals, &(ds)->triangle_shading,                 \
     &(ds)->triangle_materials, &(ds)->materials,    &(ds)->lights,                            \
     &(ds)->light_cdf,       &(ds)->emitter_cdf,     &(ds)->emitter_triangles,                 \
     &(ds)->environment}

void device_scene_release(device_scene *ds)
{
    cl_mem *buffers[DEVICE_SCENE_BUFFERS] = SCENE_BUFFER_LIST(ds);
    for (size_t i = 0; i < DEVICE_SCENE_BUFFERS; i++)
        if (*buffers[i]) {
            clReleaseMemObject(*buffers[i]);
            *buffers[i] = NULL;
        }
}

int device_scene_set_args(const device_scene *ds, cl_kernel kernel, const char *kernel_name,
                          unsigned int first)
{
    cl_mem *const buffers[DEVICE_SCENE_BUFFERS] = SCENE_BUFFER_LIST((device_scene *)ds);
    for (unsigned int i = 0; i < DEVICE_SCENE_BUFFERS; i++)
        if (DEVICE_SET_ARG(kernel, kernel_name, first + i, *buffers[i]))
            return -1;
    return 0;
}
