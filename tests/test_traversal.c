/* test_traversal.c — the OpenCL BVH traversal (kernels/traverse.h) against Embree.
 *
 * Closest hit must find the same triangle as rtcIntersect1, or — where two triangles tie on
 * a shared edge or vertex — a hit at the same distance within 1e-4 relative. Any hit must agree
 * with rtcOccluded1. Real meshes: the Stanford dragon (resolution 2) and the living room, with
 * incoherent rays and camera rays; plus hand-made cases whose answer is known on paper. One
 * OpenCL program is built for the whole file. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "io/mitsuba.h"
#include "trace_common.h"

static trace_device tdev;

static int group_setup(void **state)
{
    if (trace_device_open(&tdev)) {
        fprintf(stderr, "test_traversal: %s\n", error_message());
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    trace_device_close(&tdev);
    return 0;
}

static scene *load_or_fail(scene *s)
{
    if (!s)
        fail_msg("loading failed: %s", error_message());
    return s;
}

typedef struct comparison {
    size_t rays;
    size_t hits;
    size_t same_triangle;
    size_t tied_distance;
    size_t mismatches;
    size_t occlusion_mismatches;
    size_t distance_errors;  /* same triangle, distance off by more than the bound */
    double worst_distance_error; /* |t - t_embree| / (1e-4 t + 1e-6 diagonal), worst ray */
} comparison;

/* |cos| of the angle between the ray and the normal of scene triangle `t`. */
static double incidence_cosine(const scene *s, uint32_t t, const idmr_ray *ray)
{
    const scene_mesh *m = &s->meshes[scene_mesh_of_triangle(s, t)];
    const uint32_t *ix = &m->indices[3 * (size_t)(t - m->first_triangle)];
    const float *v0 = &m->positions[3 * ix[0]], *v1 = &m->positions[3 * ix[1]],
                *v2 = &m->positions[3 * ix[2]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)v1[k] - v0[k];
        e2[k] = (double)v2[k] - v0[k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    const float *d = ray->direction;
    double nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double dd = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    return fabs(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / (nn * dd);
}

/* Traces `rays` on the device (closest and any hit with tmax set to a random fraction of
 * Embree's hit distance or a finite bound) and compares with Embree. */
static comparison compare_with_embree(const scene *s, idmr_ray *rays, size_t count)
{
    comparison c = {.rays = count};
    trace_geometry g;
    if (trace_geometry_upload(&tdev, s, &g))
        fail_msg("%s", error_message());
    RTCScene es = trace_embree_scene(s);
    double diagonal = scene_diagonal(s);
    idmr_hit *device_hits = calloc(count, sizeof *device_hits);
    idmr_hit *embree_hits = calloc(count, sizeof *embree_hits);
    if (trace_device_run(&tdev, &g, rays, device_hits, count, 0, 0, NULL))
        fail_msg("%s", error_message());
    for (size_t i = 0; i < count; i++) {
        trace_embree_closest(es, &rays[i], &embree_hits[i]);
        const idmr_hit *d = &device_hits[i], *e = &embree_hits[i];
        if (e->triangle != IDMR_NO_HIT)
            c.hits++;
        if (d->triangle == e->triangle) {
            c.same_triangle++;
            if (d->triangle != IDMR_NO_HIT) {
                /* Float distances are exact to about an ulp of the scene's coordinates. */
                double bound = 1e-4 * fabs(e->t) + 1e-6 * diagonal;
                double error = fabs((double)d->t - e->t) / bound;
                if (error > c.worst_distance_error)
                    c.worst_distance_error = error;
                if (error > 1.0 && c.distance_errors++ < 5)
                    print_message("  distance ray %zu: tri %u t=%.9g embree t=%.9g cos=%.3g\n", i,
                                  d->triangle, d->t, e->t, incidence_cosine(s, d->triangle, &rays[i]));
            }
        } else if (d->triangle != IDMR_NO_HIT && e->triangle != IDMR_NO_HIT &&
                   fabsf(d->t - e->t) <= 1e-4f * fmaxf(fabsf(e->t), 1e-30f)) {
            c.tied_distance++;
        } else {
            if (c.mismatches < 5)
                print_message("  mismatch ray %zu: device tri %u t=%.9g, embree tri %u t=%.9g\n", i,
                              d->triangle, d->t, e->triangle, e->t);
            c.mismatches++;
        }
    }
    /* Occlusion: every other ray ends before Embree's hit, the others beyond it, by at least
     * 1% of the distance and 1e-5 of the scene diagonal (the distance's precision, above). */
    uint64_t state = 77;
    double margin = 1e-5 * diagonal;
    for (size_t i = 0; i < count; i++) {
        double t = embree_hits[i].triangle == IDMR_NO_HIT ? 10.0 * diagonal : embree_hits[i].t;
        double before = fmin(t * (0.5 + 0.49 * trace_random(&state)), t - margin);
        double beyond = fmax(t * 1.01, t + margin);
        rays[i].tmax = (float)((i & 1) ? fmax(before, 0.0) : beyond);
    }
    if (trace_device_run(&tdev, &g, rays, device_hits, count, 1, 0, NULL))
        fail_msg("%s", error_message());
    for (size_t i = 0; i < count; i++) {
        int device_occluded = device_hits[i].triangle != IDMR_NO_HIT;
        if (device_occluded != trace_embree_occluded(es, &rays[i])) {
            if (c.occlusion_mismatches < 5)
                print_message("  occlusion mismatch ray %zu: device %d tmax %.9g\n", i,
                              device_occluded, rays[i].tmax);
            c.occlusion_mismatches++;
        }
    }
    print_message("  %zu rays, %zu hits: %zu same triangle, %zu tied on an edge, %zu mismatches, "
                  "%zu occlusion mismatches, %zu distance errors (worst %.3f of the bound)\n",
                  c.rays, c.hits, c.same_triangle, c.tied_distance, c.mismatches,
                  c.occlusion_mismatches, c.distance_errors, c.worst_distance_error);
    free(device_hits);
    free(embree_hits);
    rtcReleaseScene(es);
    trace_geometry_release(&g);
    return c;
}

static void expect_agreement(const scene *s, idmr_ray *rays, size_t count)
{
    comparison c = compare_with_embree(s, rays, count);
    assert_true(c.hits > count / 10); /* the rays must actually exercise the geometry */
    assert_int_equal(c.mismatches, 0);
    assert_int_equal(c.occlusion_mismatches, 0);
    assert_int_equal(c.distance_errors, 0);
}

static void test_dragon_incoherent(void **state)
{
    scene *s = load_or_fail(trace_scene_from_mesh(SHARED_DATA "/models/dragon_vrip_res2.ply"));
    size_t count = 100000;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays(s, rays, count, 1);
    expect_agreement(s, rays, count);
    free(rays);
    scene_free(s);
}

static void test_dragon_camera(void **state)
{
    scene *s = load_or_fail(trace_scene_from_mesh(SHARED_DATA "/models/dragon_vrip_res2.ply"));
    idmr_camera cam = trace_overview_camera(s, 400, 250);
    size_t count = (size_t)cam.width * cam.height;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_camera_rays(&cam, rays, cam.width, cam.height, 2);
    expect_agreement(s, rays, count);
    free(rays);
    scene_free(s);
}

static void test_living_room(void **state)
{
    warn_silence(1);
    scene *s = load_or_fail(mitsuba_load(SHARED_DATA "/scenes/living-room/scene.xml"));
    warn_silence(0);
    assert_true(s->has_camera);
    size_t camera_count = (size_t)s->camera.width * s->camera.height / 8;
    unsigned width = s->camera.width / 4, height = s->camera.height / 2;
    camera_count = (size_t)width * height;
    size_t random_count = 100000;
    idmr_ray *rays = malloc((random_count + camera_count) * sizeof *rays);
    trace_random_rays(s, rays, random_count, 3);
    trace_camera_rays(&s->camera, rays + random_count, width, height, 4);
    expect_agreement(s, rays, random_count + camera_count);
    free(rays);
    scene_free(s);
}

/* The dragon at resolution 4 scaled by 1e-3 and by 1e4 about a far-off origin. */
static void test_scales(void **state)
{
    const float scales[] = {1e-3f, 1e4f};
    for (int i = 0; i < 2; i++) {
        scene *s = load_or_fail(trace_scene_from_mesh(SHARED_DATA "/models/dragon_vrip_res4.ply"));
        scene_mesh *m = &s->meshes[0];
        for (size_t v = 0; v < 3 * (size_t)m->vertex_count; v++)
            m->positions[v] = m->positions[v] * scales[i] + 3.0f * scales[i];
        assert_int_equal(scene_finalize(s), 0);
        size_t count = 30000;
        idmr_ray *rays = malloc(count * sizeof *rays);
        trace_random_rays(s, rays, count, 5 + i);
        print_message("  scale %g\n", scales[i]);
        expect_agreement(s, rays, count);
        free(rays);
        scene_free(s);
    }
}

/* ---- hand-made cases ---- */

static scene *quad_scene(float z, int with_degenerate)
{
    scene *s = scene_create("quad");
    idmr_material white = {{0.8f, 0.8f, 0.8f}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1, -1, 0};
    uint32_t material = scene_add_material(s, "white", "diffuse", &white);
    float p[] = {-1, -1, z, 1, -1, z, 1, 1, z, -1, 1, z, 0, 0, z + 1, 0, 0, z + 1};
    uint32_t ix[] = {0, 1, 2, 0, 2, 3, 4, 5, 4};
    float *positions = malloc(sizeof p);
    uint32_t *indices = malloc(sizeof ix);
    memcpy(positions, p, sizeof p);
    memcpy(indices, ix, sizeof ix);
    scene_mesh *m = scene_add_mesh(s, "quad", "rectangle", NULL, 0, with_degenerate ? 6 : 4,
                                   positions, with_degenerate ? 3 : 2, indices, NULL);
    m->material = material;
    assert_int_equal(scene_finalize(s), 0);
    return s;
}

static void trace_one(const scene *s, const idmr_ray *ray, int any, idmr_hit *hit)
{
    trace_geometry g;
    if (trace_geometry_upload(&tdev, s, &g))
        fail_msg("%s", error_message());
    if (trace_device_run(&tdev, &g, ray, hit, 1, any, 0, NULL))
        fail_msg("%s", error_message());
    trace_geometry_release(&g);
}

static void test_axis_aligned_ray(void **state)
{
    scene *s = quad_scene(0.0f, 0);
    idmr_ray ray = {{0.25f, -0.5f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    idmr_hit hit;
    trace_one(s, &ray, 0, &hit);
    assert_int_equal(hit.triangle, 0); /* (0.25, -0.5) lies in triangle 0 = (0, 1, 2) */
    assert_float_equal(hit.t, 2.0f, 1e-6f);
    ray.tmax = 1.5f; /* the quad is beyond tmax */
    trace_one(s, &ray, 0, &hit);
    assert_int_equal(hit.triangle, IDMR_NO_HIT);
    trace_one(s, &ray, 1, &hit);
    assert_int_equal(hit.triangle, IDMR_NO_HIT);
    ray.tmax = 2.5f;
    trace_one(s, &ray, 1, &hit);
    assert_int_equal(hit.triangle, 1u);
    scene_free(s);
}

/* A ray exactly through the shared diagonal must hit one of the two triangles (watertight). */
static void test_shared_edge_is_watertight(void **state)
{
    scene *s = quad_scene(0.0f, 0);
    const float points[][2] = {{0.0f, 0.0f}, {0.5f, 0.5f}, {-0.3f, -0.3f}, {0.9f, 0.9f}};
    for (int i = 0; i < 4; i++) {
        idmr_ray ray = {{points[i][0], points[i][1], 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
        idmr_hit hit;
        trace_one(s, &ray, 0, &hit);
        assert_true(hit.triangle == 0 || hit.triangle == 1);
        assert_float_equal(hit.t, 1.0f, 1e-6f);
        /* The same through a slanted ray. */
        idmr_ray slanted = {{points[i][0] - 0.3f, points[i][1] - 0.7f, 1.0f}, 0.0f,
                            {0.3f, 0.7f, -1.0f}, INFINITY};
        trace_one(s, &slanted, 0, &hit);
        assert_true(hit.triangle == 0 || hit.triangle == 1);
    }
    scene_free(s);
}

/* Zero-area triangles are left out of the BVH and never hit. */
static void test_degenerate_triangle(void **state)
{
    scene *s = quad_scene(0.0f, 1);
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    assert_int_equal(b.degenerate_count, 1);
    assert_int_equal(b.reference_count, 2);
    bvh_free(&b);
    idmr_ray ray = {{0.0f, 0.0f, 1.0f + 0.5f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    idmr_hit hit;
    trace_one(s, &ray, 0, &hit);
    assert_true(hit.triangle == 0 || hit.triangle == 1);
    assert_float_equal(hit.t, 1.5f, 1e-6f);
    scene_free(s);
}

static void test_empty_scene(void **state)
{
    scene *s = scene_create("empty");
    assert_int_equal(scene_finalize(s), 0);
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    assert_int_equal(b.node_count, 1);
    assert_int_equal(b.leaf_count, 0);
    bvh_free(&b);
    idmr_ray ray = {{0, 0, 0}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    idmr_hit hit;
    trace_one(s, &ray, 0, &hit);
    assert_int_equal(hit.triangle, IDMR_NO_HIT);
    trace_one(s, &ray, 1, &hit);
    assert_int_equal(hit.triangle, IDMR_NO_HIT);
    scene_free(s);
}

/* Every scene triangle appears in the BVH's leaves at least once, and leaf ranges are valid. */
static void test_bvh_covers_every_triangle(void **state)
{
    scene *s = load_or_fail(trace_scene_from_mesh(SHARED_DATA "/models/dragon_vrip_res3.ply"));
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    unsigned char *seen = calloc(s->triangle_count, 1);
    size_t references = 0;
    for (size_t n = 0; n < b.node_count; n++)
        for (int k = 0; k < 4; k++) {
            const idmr_bvh_node *node = &b.nodes[n];
            int ref = node->child[k];
            if (node->min_x[k] > node->max_x[k]) { /* empty slot */
                assert_int_equal(ref, IDMR_BVH_EMPTY);
                continue;
            }
            if (ref >= 0) { /* inner: stored after its parent (depth-first order) */
                assert_true((size_t)ref > n && (size_t)ref < b.node_count);
                continue;
            }
            assert_true((size_t)~ref < b.leaf_count);
            const idmr_triangle4 *packet = &b.leaves[~ref];
            unsigned lanes = 0;
            for (unsigned lane = 0; lane < 4; lane++) {
                unsigned t = packet->triangle[lane];
                if (t == IDMR_BVH_NO_TRIANGLE)
                    continue;
                lanes++;
                assert_true(t < s->triangle_count);
                seen[t] = 1;
                /* the leaf's box holds the triangle's part in it: at least overlaps its box */
                const float *x0 = packet->v0, *x1 = packet->v1, *x2 = packet->v2;
                float lo = fminf(fminf(x0[lane], x1[lane]), x2[lane]);
                float hi = fmaxf(fmaxf(x0[lane], x1[lane]), x2[lane]);
                assert_true(node->min_x[k] <= hi && node->max_x[k] >= lo);
            }
            assert_true(lanes >= 1);
            references += lanes;
        }
    assert_int_equal(references, b.reference_count);
    size_t missing = 0;
    for (size_t t = 0; t < s->triangle_count; t++)
        missing += !seen[t] && scene_triangle_area(s, t) > 0;
    assert_int_equal(missing, 0);
    print_message("  %zu nodes, %zu leaves, %zu references for %llu triangles, depth %d\n",
                  b.node_count, b.leaf_count, b.reference_count, (unsigned long long)s->triangle_count, b.depth);
    free(seen);
    bvh_free(&b);
    scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_axis_aligned_ray),
        cmocka_unit_test(test_shared_edge_is_watertight),
        cmocka_unit_test(test_degenerate_triangle),
        cmocka_unit_test(test_empty_scene),
        cmocka_unit_test(test_bvh_covers_every_triangle),
        cmocka_unit_test(test_dragon_incoherent),
        cmocka_unit_test(test_dragon_camera),
        cmocka_unit_test(test_scales),
        cmocka_unit_test(test_living_room),
    };
    return cmocka_run_group_tests_name("traversal", tests, group_setup, group_teardown);
}
