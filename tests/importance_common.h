/* importance_common.h — scenes built in code and host references for the importance pass and
 * renderer tests (tests/test_importance.c, tests/test_render.c). Header-only (static functions): each program includes it once.
 *
 * Scenes: quads (two triangles, wound so that the normal is u × v), boxes and UV spheres
 * (host/shapes.h), diffuse / glossy / mirror / dielectric materials, point and area lights,
 * and a look-at pinhole camera (right = forward × up, up = right × forward, as
 * trace_overview_camera). Host references: the camera pass's jittered direction (the same rng
 * stream and float formula as camera_direction in kernels/scene.h) and per-triangle unit
 * normals computed as host/device_scene.c does (double cross product, cast to float). */
#ifndef IDMR_TESTS_IMPORTANCE_COMMON_H
#define IDMR_TESTS_IMPORTANCE_COMMON_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "idmr/camera.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "idmr/light.h"
#include "idmr/material.h"
#include "idmr/rng.h"
#include "idmr/weight.h"
#include "io/mesh_io.h"
#include "core/scene.h"
#include "io/shapes.h"

/* ---- small vector helpers (float[3]) ---- */

static inline void imp_cross(const float a[3], const float b[3], float out[3])
{
    float c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(out, c, sizeof c);
}

static inline void imp_normalize(float v[3])
{
    float n = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++)
        v[k] /= n;
}

static inline double imp_dot(const float a[3], const float b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* ---- materials ---- */

static inline uint32_t imp_diffuse(scene *s, const char *name, float albedo, unsigned int flags)
{
    idmr_material m = {{albedo, albedo, albedo}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1, -1,
                       flags};
    return scene_add_material(s, name, "diffuse", &m);
}

static inline uint32_t imp_glossy(scene *s, const char *name)
{
    idmr_material m = {{0.5f, 0.5f, 0.5f}, IDMR_MATERIAL_GLOSSY, {0.9f, 0.9f, 0.9f}, 0.2f, 1.5f,
                       1.0f, -1, 0};
    return scene_add_material(s, name, "roughplastic", &m);
}

static inline uint32_t imp_mirror(scene *s, const char *name)
{
    idmr_material m = {{0, 0, 0}, IDMR_MATERIAL_MIRROR, {0.9f, 0.9f, 0.9f}, 0, 1, 1, -1, 0};
    return scene_add_material(s, name, "conductor", &m);
}

static inline uint32_t imp_glass(scene *s, const char *name)
{
    idmr_material m = {{0, 0, 0}, IDMR_MATERIAL_DIELECTRIC, {1, 1, 1}, 0, 1.5f, 1.0f, -1, 0};
    return scene_add_material(s, name, "dielectric", &m);
}

/* ---- shapes ---- */

static inline scene_mesh *imp_add_mesh_data(scene *s, const char *name, const char *type,
                                            uint32_t material, mesh_data *mesh)
{
    scene_mesh *m = scene_add_mesh(s, name, type, NULL, 0, mesh->vertex_count, mesh->positions,
                                   mesh->triangle_count, mesh->indices, mesh->texcoords);
    m->material = material;
    return m;
}

/* The parallelogram with corners c ± u ± v: vertices c-u-v, c+u-v, c+u+v, c-u+v, triangles
 * (0, 1, 2) and (0, 2, 3); its normal points along u × v. */
static inline scene_mesh *imp_add_quad(scene *s, const char *name, uint32_t material,
                                       const float c[3], const float u[3], const float v[3])
{
    float *p = malloc(12 * sizeof *p);
    const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = c[k] + su[i] * u[k] + sv[i] * v[k];
    uint32_t *ix = malloc(6 * sizeof *ix);
    const uint32_t quad[6] = {0, 1, 2, 0, 2, 3};
    memcpy(ix, quad, sizeof quad);
    mesh_data mesh = {4, 2, p, ix, NULL};
    return imp_add_mesh_data(s, name, "rectangle", material, &mesh);
}

/* An axis-aligned box [lo, hi], wound outward (shapes_cube scaled and moved). */
static inline scene_mesh *imp_add_box(scene *s, const char *name, uint32_t material,
                                      const float lo[3], const float hi[3])
{
    mesh_data mesh;
    shapes_cube(&mesh);
    for (uint32_t i = 0; i < mesh.vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float x = mesh.positions[3 * i + k]; /* -1 or 1 */
            mesh.positions[3 * i + k] = x < 0 ? lo[k] : hi[k];
        }
    return imp_add_mesh_data(s, name, "cube", material, &mesh);
}

static inline scene_mesh *imp_add_sphere(scene *s, const char *name, uint32_t material,
                                         const float center[3], float radius)
{
    mesh_data mesh;
    const double c[3] = {center[0], center[1], center[2]};
    shapes_sphere(c, radius, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, &mesh);
    return imp_add_mesh_data(s, name, "sphere", material, &mesh);
}

/* ---- lights ---- */

static inline void imp_point_light(scene *s, const float position[3], float intensity)
{
    idmr_light l;
    memset(&l, 0, sizeof l);
    l.kind = IDMR_LIGHT_POINT;
    memcpy(l.position, position, sizeof l.position);
    l.emission[0] = l.emission[1] = l.emission[2] = intensity;
    scene_add_light(s, &l);
}

/* Makes mesh `m` an area emitter (front side, along its winding normal). */
static inline void imp_area_light(scene *s, scene_mesh *m, float radiance)
{
    idmr_light l;
    memset(&l, 0, sizeof l);
    l.kind = IDMR_LIGHT_AREA;
    l.emission[0] = l.emission[1] = l.emission[2] = radiance;
    m->light = scene_add_light(s, &l);
}

/* ---- camera ---- */

/* A pinhole at `origin` looking at `target`; tan_half_y follows from the aspect ratio. */
static inline void imp_look_at(scene *s, const float origin[3], const float target[3],
                               const float up_hint[3], unsigned int width, unsigned int height,
                               float tan_half_x)
{
    idmr_camera *c = &s->camera;
    memset(c, 0, sizeof *c);
    memcpy(c->origin, origin, sizeof c->origin);
    for (int k = 0; k < 3; k++)
        c->forward[k] = target[k] - origin[k];
    imp_normalize(c->forward);
    imp_cross(c->forward, up_hint, c->right);
    imp_normalize(c->right);
    imp_cross(c->right, c->forward, c->up);
    imp_normalize(c->up);
    c->width = width;
    c->height = height;
    c->tan_half_x = tan_half_x;
    c->tan_half_y = tan_half_x * (float)height / (float)width;
    s->has_camera = 1;
}

/* The camera pass's ray direction for pixel `pixel` of a width x height hit-point image, from
 * the same rng stream (x jitter, then y jitter) and the shared formula idmr_camera_direction()
 * (include/idmr/camera.h), as camera_ray() in kernels/lib/paths.h takes them. */
static inline void imp_camera_direction(const idmr_camera *c, unsigned int width,
                                        unsigned int height, unsigned int seed,
                                        unsigned int iteration, unsigned int pixel, float d[3])
{
    idmr_rng rng = idmr_rng_init(seed, iteration, IDMR_STREAM_IMPORTANCE_CAMERA, pixel);
    idmr_camera film = *c;
    film.width = width;
    film.height = height;
    float film_x = (float)(pixel % width) + idmr_rng_float(&rng);
    float film_y = (float)(pixel / width) + idmr_rng_float(&rng);
    idmr_camera_direction(&film, film_x, film_y, d);
    imp_normalize(d);
}

/* ---- per-triangle geometry ---- */

/* Unit winding normal of scene triangle t as the kernels get it (0 for degenerate ones). */
static inline void imp_triangle_normal(const scene *s, uint64_t t, float n[3])
{
    const scene_mesh *m = &s->meshes[scene_mesh_of_triangle(s, t)];
    const uint32_t *ix = &m->indices[3 * (size_t)(t - m->first_triangle)];
    const float *a = &m->positions[3 * (size_t)ix[0]];
    const float *b = &m->positions[3 * (size_t)ix[1]];
    const float *c = &m->positions[3 * (size_t)ix[2]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    double x[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double length = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (int k = 0; k < 3; k++)
        n[k] = length > 0 ? (float)(x[k] / length) : 0.0f;
}

/* Signed distance of point p from the plane of scene triangle t (along its unit normal). */
static inline double imp_plane_distance(const scene *s, uint64_t t, const float p[3])
{
    const scene_mesh *m = &s->meshes[scene_mesh_of_triangle(s, t)];
    const float *a = &m->positions[3 * (size_t)m->indices[3 * (size_t)(t - m->first_triangle)]];
    float n[3];
    imp_triangle_normal(s, t, n);
    return ((double)p[0] - a[0]) * n[0] + ((double)p[1] - a[1]) * n[1] + ((double)p[2] - a[2]) * n[2];
}

static inline double imp_scene_diagonal(const scene *s)
{
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double e = (double)s->bbox_max[k] - s->bbox_min[k];
        d2 += e * e;
    }
    return sqrt(d2);
}

/* Index of mesh `name` in s, or -1. */
static inline int imp_mesh_index(const scene *s, const char *name)
{
    for (size_t m = 0; m < s->mesh_count; m++)
        if (strcmp(s->meshes[m].name, name) == 0)
            return (int)m;
    return -1;
}

/* Σ of a per-triangle array over mesh m. */
static inline double imp_mesh_total(const scene *s, size_t m, const double *per_triangle)
{
    double sum = 0;
    for (uint32_t t = 0; t < s->meshes[m].triangle_count; t++)
        sum += per_triangle[(size_t)s->meshes[m].first_triangle + t];
    return sum;
}

#endif
