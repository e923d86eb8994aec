/* importance_common.h — scenes built in code and host references for the importance pass and
 * renderer tests (tests/test_importance_*.c, tests/test_render.c). Header-only (static inline
 * functions).
 *
 * Scenes: quads (two triangles, wound so that the normal is u × v), boxes and UV spheres
 * (host/core/shapes.h), diffuse / glossy / mirror / dielectric materials, point and area lights,
 * and a look-at pinhole camera (trace_look_at: right = forward × up, up = right × forward).
 * Host references: the camera pass's jittered direction (the same rng stream and the shared
 * formula of idmr/camera.h, through trace_common.h) and per-triangle unit normals computed as
 * host/device/device_scene.c does (double cross product, cast to float). Cases (imp_case): a
 * scene and one small run of the importance pass on it, made once per device and shared by
 * the small tests that each check one formula on it. */
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
#include "io/mesh/mesh_io.h"
#include "core/scene.h"
#include "core/shapes.h"
#include "test_support.h"
#include "trace_common.h"

/* One unit of the fixed-point accumulators (kernels/lib/fixed_point.h), in weight. */
#define IMP_FIXED_UNIT (1.0 / 1048576.0)

/* ---- small vector helpers ---- */

/* A float[3] literal: imp_point_light(s, V3(0, 2, 0), 1.0f). */
#define V3(x, y, z) ((const float[3]){(x), (y), (z)})

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
    free(mesh->normals); /* shaded flat, as these scenes were worked out */
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
    mesh_data mesh = {4, 2, p, ix, NULL, NULL, 0};
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

/* The environment light of a width x height map (rgb copied) in the frame to_world (NULL: the
 * identity). */
static inline void imp_environment(scene *s, int width, int height, const float *rgb,
                                   const double *to_world)
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    float *copy = malloc(3 * sizeof *copy * (size_t)width * height);
    memcpy(copy, rgb, 3 * sizeof *copy * (size_t)width * height);
    if (scene_add_environment(s, NULL, width, height, copy, to_world ? to_world : identity) < 0)
        fail_msg("scene_add_environment: %s", error_message());
}

/* ---- camera ---- */

/* The scene's camera: a pinhole at `origin` looking at `target` (trace_look_at). */
static inline void imp_look_at(scene *s, const float origin[3], const float target[3],
                               const float up_hint[3], unsigned int width, unsigned int height,
                               float tan_half_x)
{
    s->camera = trace_look_at(origin, target, up_hint, width, height, tan_half_x);
    s->has_camera = 1;
}

/* The importance pass's camera ray direction (unit) for pixel `pixel` of a width x height
 * hit-point image: the stream IDMR_STREAM_IMPORTANCE_CAMERA, as camera_ray() in
 * kernels/lib/paths.h draws it. */
static inline void imp_camera_direction(const idmr_camera *c, unsigned int width,
                                        unsigned int height, unsigned int seed,
                                        unsigned int iteration, unsigned int pixel, float d[3])
{
    trace_jittered_direction(c, width, height, seed, iteration, IDMR_STREAM_IMPORTANCE_CAMERA,
                             pixel, d);
}

/* ---- the gather radius ---- */

static inline int imp_compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The first gather radius the SPPM core should choose from these hit points (host/passes/
 * sppm.h): 2.5 pixel footprints at their median distance from the camera, a pixel spanning
 * 2 tan_half_x / width. Written out here independently of sppm.c. */
static inline double imp_expected_first_radius(const scene *s, const idmr_hit_point *hit_points,
                                               size_t count, unsigned int width)
{
    double *distance = malloc((count ? count : 1) * sizeof *distance);
    size_t valid = 0;
    for (size_t i = 0; i < count; i++)
        if (hit_points[i].offset > 0.0f) {
            double d2 = 0;
            for (int k = 0; k < 3; k++)
                d2 += pow((double)hit_points[i].position[k] - s->camera.origin[k], 2);
            distance[valid++] = sqrt(d2);
        }
    assert_true(valid > 0);
    qsort(distance, valid, sizeof *distance, imp_compare_doubles);
    double radius = 2.5 * distance[valid / 2] * 2.0 * s->camera.tan_half_x / width;
    free(distance);
    return radius;
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
    return ((double)p[0] - a[0]) * n[0] + ((double)p[1] - a[1]) * n[1] +
           ((double)p[2] - a[2]) * n[2];
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

/* ---- cases: a scene and a small run of the pass, made once per device ---- */

/* The importance tests' small run: `iterations` of `photons` paths, seed 7. */
static inline void imp_small_options(importance_options *o, unsigned int iterations,
                                     unsigned int photons)
{
    test_importance_options(o, iterations, photons);
    o->sppm.seed = 7;
}

/* A scene and the run of the pass on it, with its snapshot. The first fields say what to run:
 *     static imp_case head_on = {.make = head_on_scene, .iterations = 1, .photons = 20000};
 * imp_run() makes the run on first use by the tests of one device — several small tests each
 * check one formula on it — and imp_teardown(), the group teardown, frees every case run. */
typedef struct imp_case {
    scene *(*make)(void);             /* builds or loads the scene */
    unsigned int iterations, photons; /* imp_small_options() */
    float resolution;                 /* of the hit-point image; 0: the film's */
    double tolerance;                 /* the early stop; 0: none */
    int without_shadows;              /* shadow weight 0: no shadow rays */
    scene *s;
    importance_options options;
    importance_snapshot snapshot;
    importance_result r;
    int ready;
} imp_case;

/* A test of a case: the cmocka entry of test f with case c as its state, named "f(c)". */
#define IMP_CASE_TEST(f, c) {#f "(" #c ")", f, NULL, NULL, &(c)}

static inline void imp_case_free(imp_case *c)
{
    importance_result_free(&c->r);
    importance_snapshot_free(&c->snapshot);
    if (c->s)
        scene_free(c->s);
    c->s = NULL;
    c->ready = 0;
}

/* Every sum is finite and >= 0 (checked once per run). */
static inline void imp_expect_all_finite(const scene *s, const importance_result *r)
{
    for (size_t t = 0; t < r->triangle_count; t++)
        if (!(isfinite(r->camera[t]) && r->camera[t] >= 0 && isfinite(r->light[t]) &&
              r->light[t] >= 0 && isfinite(r->shadow[t]) && r->shadow[t] >= 0))
            fail_msg("%s: triangle %zu has camera importance %g, light importance %g, shadow "
                     "importance %g", s->file, t, r->camera[t], r->light[t], r->shadow[t]);
}

/* A(T) of triangle t by the formula of passes/importance.h, from the raw sums. */
static inline double imp_expected_amount(const importance_result *r, double gamma, double sigma,
                                         size_t t)
{
    double pixels = (double)r->sppm.width * r->sppm.height, photons = r->sppm.photons;
    return 1e6 * (gamma * r->camera[t] / pixels + r->light[t] / photons +
                  sigma * r->shadow[t] / pixels) / r->sppm.iterations;
}

/* The cases run on this device, for imp_teardown(). */
static imp_case *imp_cases_run[32];
static size_t imp_cases_run_count;

/* Case c, run (once). */
static inline const imp_case *imp_run(imp_case *c)
{
    if (c->ready)
        return c;
    imp_case_free(c); /* what an earlier, failed run left */
    size_t i = 0;
    while (i < imp_cases_run_count && imp_cases_run[i] != c)
        i++;
    if (i == sizeof imp_cases_run / sizeof *imp_cases_run)
        fail_msg("imp_run: more than %zu cases", i);
    if (i == imp_cases_run_count)
        imp_cases_run[imp_cases_run_count++] = c;
    c->s = c->make();
    imp_small_options(&c->options, c->iterations, c->photons);
    if (c->resolution > 0)
        c->options.sppm.resolution = c->resolution;
    c->options.tolerance = c->tolerance;
    if (c->without_shadows)
        c->options.shadow_weight = 0.0f;
    c->options.snapshot = &c->snapshot;
    test_run_importance(c->s, NULL, &c->options, &c->r);
    imp_expect_all_finite(c->s, &c->r);
    c->ready = 1;
    return c;
}

/* Group teardown: frees every case run on the device. */
static inline int imp_teardown(void **state)
{
    for (size_t i = 0; i < imp_cases_run_count; i++)
        imp_case_free(imp_cases_run[i]);
    imp_cases_run_count = 0;
    return 0;
}

/* The case of an IMP_CASE_TEST, run. */
static inline const imp_case *imp_run_state(void **state)
{
    return imp_run(*state);
}

/* ---- scenes shared by several test programs ---- */

/* A floor seen by the camera, a point light over it, and a wall behind the camera (z = 6,
 * facing the light and the floor, outside the camera's cone) of albedo `wall_albedo`. */
static inline scene *imp_hidden_wall_scene(float wall_albedo)
{
    scene *s = scene_create("hidden-wall.xml");
    uint32_t white = imp_diffuse(s, "white", 0.8f, 0);
    uint32_t wall = imp_diffuse(s, "wall", wall_albedo, 0);
    const float fc[3] = {0, 0, 0}, fu[3] = {0, 0, 2}, fv[3] = {2, 0, 0};
    imp_add_quad(s, "floor", white, fc, fu, fv); /* normal +y */
    const float wc[3] = {0, 1.5f, 6}, wu[3] = {0, 1.5f, 0}, wv[3] = {2, 0, 0};
    imp_add_quad(s, "wall", wall, wc, wu, wv); /* normal -z */
    const float light[3] = {0, 2, 0}, eye[3] = {0, 3, 4}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    imp_point_light(s, light, 1.0f);
    imp_look_at(s, eye, target, up, 64, 48, 0.5f);
    return test_finalize_scene(s);
}

#endif
