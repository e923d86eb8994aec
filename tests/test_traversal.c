/* test_traversal.c — the OpenCL BVH traversal (kernels/lib/traverse.h, kernels/trace.cl) against
 * Embree, and the BVH it walks (host/device/bvh.c).
 *
 * Closest hit must find the same triangle as rtcIntersect1, or — where two triangles tie on
 * a shared edge or vertex — a hit at the same distance within 1e-4 relative. Any hit must agree
 * with rtcOccluded1. Real meshes: the Stanford dragon (resolutions 2, 3, 4) and the living room,
 * with incoherent rays and camera rays; plus hand-made cases whose answer is known on paper: a
 * quad of two triangles,
 *
 *     3 ------ 2      (-1, -1, 0) .. (1, 1, 0), normal +z:
 *     |  1  /  |      triangle 0 = (0, 1, 2), triangle 1 = (0, 2, 3)
 *     |  /  0  |      (and, for the degenerate case, triangle 2 = (4, 5, 4) above it)
 *     0 ------ 1
 *
 * The BVH tests are host-only and run once; the traversal tests run on every device
 * (tests/device_test.h), with the trace program built once per device. */
#include "importance_common.h"

/* Per device: the trace program, and the living room once loaded. */
static trace_device tdev;
static scene *living_room;

static int group_setup(void **state)
{
    return trace_device_open_reporting(&tdev, device_test_device());
}

static int group_teardown(void **state)
{
    if (living_room)
        scene_free(living_room);
    living_room = NULL;
    trace_device_close(&tdev);
    return 0;
}

/* A scene of one mesh file, or the test fails. */
static scene *mesh_scene(const char *path)
{
    scene *s = trace_scene_from_mesh(path);
    if (!s)
        fail_msg("loading %s failed: %s", path, error_message());
    return s;
}

/* ---- against Embree ---- */

typedef struct comparison {
    size_t rays;
    size_t hits;
    size_t same_triangle;
    size_t tied_distance;
    size_t mismatches;
    size_t occlusion_mismatches;
    size_t distance_errors;      /* same triangle, distance off by more than the bound */
    double worst_distance_error; /* |t - t_embree| / (1e-4 t + 1e-6 diagonal), worst ray */
} comparison;

/* |cos| of the angle between the ray and the normal of scene triangle `t`. */
static double incidence_cosine(const scene *s, uint32_t t, const idmr_ray *ray)
{
    float n[3];
    imp_triangle_normal(s, t, n);
    return fabs(imp_dot(n, ray->direction)) / sqrt(imp_dot(ray->direction, ray->direction));
}

/* Closest hits of `rays` on the device against Embree's, into c. */
static void compare_closest(const scene *s, const trace_geometry *g, RTCScene es,
                            const idmr_ray *rays, idmr_hit *embree_hits, comparison *c)
{
    idmr_hit *device_hits = calloc(c->rays, sizeof *device_hits);
    if (trace_device_run(&tdev, g, rays, device_hits, c->rays, 0, 0, NULL))
        fail_msg("%s", error_message());
    double diagonal = scene_diagonal(s);
    for (size_t i = 0; i < c->rays; i++) {
        trace_embree_closest(es, &rays[i], &embree_hits[i]);
        const idmr_hit *d = &device_hits[i], *e = &embree_hits[i];
        c->hits += e->triangle != IDMR_NO_HIT;
        if (d->triangle == e->triangle) {
            c->same_triangle++;
            if (d->triangle == IDMR_NO_HIT)
                continue;
            /* Float distances are exact to about an ulp of the scene's coordinates. */
            double error = fabs((double)d->t - e->t) / (1e-4 * fabs(e->t) + 1e-6 * diagonal);
            c->worst_distance_error = fmax(c->worst_distance_error, error);
            if (error > 1.0 && c->distance_errors++ < 5)
                print_message("  distance ray %zu: tri %u t=%.9g embree t=%.9g cos=%.3g\n", i,
                              d->triangle, d->t, e->t,
                              incidence_cosine(s, d->triangle, &rays[i]));
        } else if (d->triangle != IDMR_NO_HIT && e->triangle != IDMR_NO_HIT &&
                   fabsf(d->t - e->t) <= 1e-4f * fmaxf(fabsf(e->t), 1e-30f)) {
            c->tied_distance++;
        } else if (c->mismatches++ < 5) {
            print_message("  mismatch ray %zu: device tri %u t=%.9g, embree tri %u t=%.9g\n", i,
                          d->triangle, d->t, e->triangle, e->t);
        }
    }
    free(device_hits);
}

/* Occlusion: every other ray ends before Embree's closest hit, the others beyond it, by at
 * least 1% of the distance and 1e-5 of the scene diagonal (the distance's precision, above);
 * the device's any-hit kernel against rtcOccluded1. Changes the rays' tmax. */
static void compare_occlusion(const scene *s, const trace_geometry *g, RTCScene es,
                              idmr_ray *rays, const idmr_hit *embree_hits, comparison *c)
{
    double diagonal = scene_diagonal(s), margin = 1e-5 * diagonal;
    for (size_t i = 0; i < c->rays; i++) {
        double t = embree_hits[i].triangle == IDMR_NO_HIT ? 10.0 * diagonal : embree_hits[i].t;
        idmr_rng rng = idmr_rng_init(77, 0, IDMR_STREAM_TEST, (unsigned int)i);
        double before = fmin(t * (0.5 + 0.49 * idmr_rng_float(&rng)), t - margin);
        double beyond = fmax(t * 1.01, t + margin);
        rays[i].tmax = (float)((i & 1) ? fmax(before, 0.0) : beyond);
    }
    idmr_hit *device_hits = calloc(c->rays, sizeof *device_hits);
    if (trace_device_run(&tdev, g, rays, device_hits, c->rays, 1, 0, NULL))
        fail_msg("%s", error_message());
    for (size_t i = 0; i < c->rays; i++) {
        int device_occluded = device_hits[i].triangle != IDMR_NO_HIT;
        if (device_occluded != trace_embree_occluded(es, &rays[i]) &&
            c->occlusion_mismatches++ < 5)
            print_message("  occlusion mismatch ray %zu: device %d tmax %.9g\n", i,
                          device_occluded, rays[i].tmax);
    }
    free(device_hits);
}

/* Traces `count` rays on the device (closest, then any hit) and compares with Embree: the rays
 * must exercise the geometry (more than a tenth hit) and agree on every ray. */
static void expect_agreement(const scene *s, idmr_ray *rays, size_t count)
{
    comparison c = {.rays = count};
    trace_geometry g;
    if (trace_geometry_upload(&tdev, s, &g))
        fail_msg("%s", error_message());
    RTCScene es = trace_embree_scene(s);
    idmr_hit *embree_hits = calloc(count, sizeof *embree_hits);
    compare_closest(s, &g, es, rays, embree_hits, &c);
    compare_occlusion(s, &g, es, rays, embree_hits, &c);
    free(embree_hits);
    rtcReleaseScene(es);
    trace_geometry_release(&g);
    print_message("  %zu rays, %zu hits: %zu same triangle, %zu tied on an edge, %zu mismatches, "
                  "%zu occlusion mismatches, %zu distance errors (worst %.3f of the bound)\n",
                  c.rays, c.hits, c.same_triangle, c.tied_distance, c.mismatches,
                  c.occlusion_mismatches, c.distance_errors, c.worst_distance_error);
    assert_true(c.hits > count / 10);
    assert_int_equal(c.mismatches, 0);
    assert_int_equal(c.occlusion_mismatches, 0);
    assert_int_equal(c.distance_errors, 0);
}

/* 100k incoherent rays (trace_random_rays) with `seed`, or a camera's jittered rays. */
static void expect_incoherent_agreement(const scene *s, size_t count, unsigned int seed)
{
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays(s, rays, count, seed);
    expect_agreement(s, rays, count);
    free(rays);
}

static void expect_camera_agreement(const scene *s, const idmr_camera *c, unsigned int width,
                                    unsigned int height, unsigned int seed)
{
    size_t count = (size_t)width * height;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_camera_rays(c, rays, width, height, seed);
    expect_agreement(s, rays, count);
    free(rays);
}

static void test_dragon_incoherent(void **state)
{
    scene *s = mesh_scene(SHARED_DATA "/models/dragon_vrip_res2.ply");
    expect_incoherent_agreement(s, 100000, 1);
    scene_free(s);
}

static void test_dragon_camera(void **state)
{
    scene *s = mesh_scene(SHARED_DATA "/models/dragon_vrip_res2.ply");
    idmr_camera cam = trace_overview_camera(s, 400, 250);
    expect_camera_agreement(s, &cam, cam.width, cam.height, 2);
    scene_free(s);
}

/* The living room (its Mitsuba scene), loaded once per device. */
static const scene *load_living_room(void)
{
    if (!living_room)
        living_room = test_load_scene(SHARED_DATA "/scenes/living-room/scene.xml");
    assert_true(living_room->has_camera);
    return living_room;
}

static void test_living_room_incoherent(void **state)
{
    expect_incoherent_agreement(load_living_room(), 100000, 3);
}

/* Its camera's rays at a quarter of the film's width and half its height. */
static void test_living_room_camera(void **state)
{
    const scene *s = load_living_room();
    expect_camera_agreement(s, &s->camera, s->camera.width / 4, s->camera.height / 2, 4);
}

/* The dragon at resolution 4 scaled by `scale` about a far-off origin: 30k incoherent rays. */
static void expect_scaled_agreement(float scale, unsigned int seed)
{
    scene *s = mesh_scene(SHARED_DATA "/models/dragon_vrip_res4.ply");
    scene_mesh *m = &s->meshes[0];
    for (size_t v = 0; v < 3 * (size_t)m->vertex_count; v++)
        m->positions[v] = m->positions[v] * scale + 3.0f * scale;
    test_finalize_scene(s);
    expect_incoherent_agreement(s, 30000, seed);
    scene_free(s);
}

static void test_dragon_scaled_by_1e_3(void **state)
{
    expect_scaled_agreement(1e-3f, 5);
}

static void test_dragon_scaled_by_1e4(void **state)
{
    expect_scaled_agreement(1e4f, 6);
}

/* The same hits, to the bit, with this work-group size as with the runtime's choice: the
 * dragon at resolution 4, 30k incoherent rays. */
static void test_same_hits_for_any_local_size(void **state)
{
    scene *s = mesh_scene(SHARED_DATA "/models/dragon_vrip_res4.ply");
    size_t count = 30000, hits = 0;
    idmr_ray *rays = malloc(count * sizeof *rays);
    idmr_hit *a = calloc(count, sizeof *a), *b = calloc(count, sizeof *b);
    trace_random_rays(s, rays, count, 7);
    size_t local = device_test_local_size(state);
    trace_geometry g;
    int status = trace_geometry_upload(&tdev, s, &g) ||
                 trace_device_run(&tdev, &g, rays, a, count, 0, 0, NULL) ||
                 trace_device_run(&tdev, &g, rays, b, count, 0, local, NULL);
    trace_geometry_release(&g);
    for (size_t i = 0; i < count; i++)
        hits += a[i].triangle != IDMR_NO_HIT;
    int same = memcmp(a, b, count * sizeof *a) == 0;
    free(rays);
    free(a);
    free(b);
    scene_free(s);
    if (status)
        fail_msg("%s", error_message());
    assert_true(hits > count / 10);
    assert_true(same);
}

/* ---- hand-made cases ---- */

/* The quad of the drawing at height z; with_degenerate adds triangle 2 = (4, 5, 4), two
 * vertices at (0, 0, z + 1): zero area. */
static scene *quad_scene(float z, int with_degenerate)
{
    scene *s = scene_create("quad");
    uint32_t white = imp_diffuse(s, "white", 0.8f, 0);
    imp_add_quad(s, "quad", white, V3(0, 0, z), V3(1, 0, 0), V3(0, 1, 0));
    if (with_degenerate) {
        float *p = calloc(6, sizeof *p);
        uint32_t *ix = malloc(3 * sizeof *ix);
        p[2] = p[5] = z + 1;
        ix[0] = ix[2] = 0;
        ix[1] = 1;
        /* Set directly: scene_add_mesh() drops a triangle that repeats a vertex, and what is
         * tested is that the traversal and the BVH leave one out whatever lets it in. */
        scene_mesh *m = scene_add_mesh(s, "degenerate", "ply", NULL, 0, 0, NULL, 0, NULL, NULL);
        scene_mesh_set_geometry(m, 2, p, 1, ix, NULL, NULL);
        m->material = white;
    }
    return test_finalize_scene(s);
}

/* Traces one ray on the device (closest, or any hit). */
static idmr_hit trace_one(const scene *s, idmr_ray ray, int any)
{
    trace_geometry g;
    idmr_hit hit;
    int status = trace_geometry_upload(&tdev, s, &g) ||
                 trace_device_run(&tdev, &g, &ray, &hit, 1, any, 0, NULL);
    trace_geometry_release(&g);
    if (status)
        fail_msg("%s", error_message());
    return hit;
}

/* Straight down onto (0.25, -0.5), which lies in triangle 0, from height 2. */
#define DOWN_RAY(tmax) ((idmr_ray){{0.25f, -0.5f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, (tmax)})

static void test_closest_hit_straight_down(void **state)
{
    scene *s = quad_scene(0.0f, 0);
    idmr_hit hit = trace_one(s, DOWN_RAY(INFINITY), 0);
    scene_free(s);
    assert_int_equal(hit.triangle, 0);
    assert_float_equal(hit.t, 2.0f, 1e-6f);
}

/* The quad beyond tmax: no closest hit, no any hit; within tmax, an any hit (triangle 1). */
static void test_hits_end_at_tmax(void **state)
{
    scene *s = quad_scene(0.0f, 0);
    idmr_hit closest = trace_one(s, DOWN_RAY(1.5f), 0), any = trace_one(s, DOWN_RAY(1.5f), 1);
    idmr_hit any_within = trace_one(s, DOWN_RAY(2.5f), 1);
    scene_free(s);
    assert_int_equal(closest.triangle, IDMR_NO_HIT);
    assert_int_equal(any.triangle, IDMR_NO_HIT);
    assert_int_equal(any_within.triangle, 1u);
}

/* A ray exactly through the shared diagonal hits one of the two triangles (watertight), at
 * t = 1 straight down, and from a slant. */
static void test_shared_edge_is_watertight(void **state)
{
    scene *s = quad_scene(0.0f, 0);
    const float points[][2] = {{0.0f, 0.0f}, {0.5f, 0.5f}, {-0.3f, -0.3f}, {0.9f, 0.9f}};
    for (int i = 0; i < 4; i++) {
        float x = points[i][0], y = points[i][1];
        idmr_hit hit = trace_one(s, (idmr_ray){{x, y, 1.0f}, 0.0f, {0, 0, -1.0f}, INFINITY}, 0);
        assert_true(hit.triangle == 0 || hit.triangle == 1);
        assert_float_equal(hit.t, 1.0f, 1e-6f);
        hit = trace_one(s, (idmr_ray){{x - 0.3f, y - 0.7f, 1.0f}, 0.0f, {0.3f, 0.7f, -1.0f},
                                      INFINITY}, 0);
        assert_true(hit.triangle == 0 || hit.triangle == 1);
    }
    scene_free(s);
}

/* A ray through the degenerate triangle's point hits the quad below it. */
static void test_degenerate_triangle_is_never_hit(void **state)
{
    scene *s = quad_scene(0.0f, 1);
    idmr_hit hit = trace_one(s, (idmr_ray){{0, 0, 1.5f}, 0.0f, {0, 0, -1.0f}, INFINITY}, 0);
    scene_free(s);
    assert_true(hit.triangle == 0 || hit.triangle == 1);
    assert_float_equal(hit.t, 1.5f, 1e-6f);
}

static void test_empty_scene_is_never_hit(void **state)
{
    scene *s = test_finalize_scene(scene_create("empty"));
    const idmr_ray ray = {{0, 0, 0}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    idmr_hit closest = trace_one(s, ray, 0), any = trace_one(s, ray, 1);
    scene_free(s);
    assert_int_equal(closest.triangle, IDMR_NO_HIT);
    assert_int_equal(any.triangle, IDMR_NO_HIT);
}

/* ---- the BVH (host) ---- */

/* The BVH of scene s (freed here), without its arrays: its counts. */
static bvh bvh_counts(scene *s)
{
    bvh b;
    test_build_bvh(s, &b);
    bvh counts = b;
    counts.nodes = NULL;
    counts.leaves = NULL;
    bvh_free(&b);
    scene_free(s);
    return counts;
}

/* Zero-area triangles are left out of the BVH. */
static void test_bvh_leaves_degenerate_triangles_out(void **state)
{
    bvh b = bvh_counts(quad_scene(0.0f, 1));
    assert_int_equal(b.degenerate_count, 1);
    assert_int_equal(b.reference_count, 2);
}

/* An empty scene has one (empty) node and no leaves. */
static void test_bvh_of_empty_scene(void **state)
{
    bvh b = bvh_counts(test_finalize_scene(scene_create("empty")));
    assert_int_equal(b.node_count, 1);
    assert_int_equal(b.leaf_count, 0);
}

/* One slot k of node n: an empty slot refers to nothing, an inner child is stored after its
 * parent (depth-first order), a leaf holds 1 to 4 valid triangles whose x extents overlap the
 * slot's box; the leaf's triangles are marked in seen[]. Returns the leaf's triangle count. */
static unsigned int check_slot(const scene *s, const bvh *b, size_t n, int k, unsigned char *seen)
{
    const idmr_bvh_node *node = &b->nodes[n];
    int ref = node->child[k];
    if (node->min_x[k] > node->max_x[k]) { /* empty slot */
        assert_int_equal(ref, IDMR_BVH_EMPTY);
        return 0;
    }
    if (ref >= 0) {
        assert_true((size_t)ref > n && (size_t)ref < b->node_count);
        return 0;
    }
    assert_true((size_t)~ref < b->leaf_count);
    const idmr_triangle4 *packet = &b->leaves[~ref];
    unsigned int lanes = 0;
    for (unsigned int lane = 0; lane < 4; lane++) {
        unsigned int t = packet->triangle[lane];
        if (t == IDMR_BVH_NO_TRIANGLE)
            continue;
        lanes++;
        assert_true(t < s->triangle_count);
        seen[t] = 1;
        const float *x0 = packet->v0, *x1 = packet->v1, *x2 = packet->v2;
        float lo = fminf(fminf(x0[lane], x1[lane]), x2[lane]);
        float hi = fmaxf(fmaxf(x0[lane], x1[lane]), x2[lane]);
        assert_true(node->min_x[k] <= hi && node->max_x[k] >= lo);
    }
    assert_true(lanes >= 1);
    return lanes;
}

/* Every scene triangle with area appears in the BVH's leaves of the dragon (resolution 3), and
 * the leaves hold as many references as the BVH counts. */
static void test_bvh_covers_every_triangle(void **state)
{
    scene *s = mesh_scene(SHARED_DATA "/models/dragon_vrip_res3.ply");
    bvh b;
    test_build_bvh(s, &b);
    unsigned char *seen = calloc(s->triangle_count, 1);
    size_t references = 0, missing = 0;
    for (size_t n = 0; n < b.node_count; n++)
        for (int k = 0; k < 4; k++)
            references += check_slot(s, &b, n, k, seen);
    for (size_t t = 0; t < s->triangle_count; t++)
        missing += !seen[t] && scene_triangle_area(s, t) > 0;
    print_message("  %zu nodes, %zu leaves, %zu references for %llu triangles, depth %d\n",
                  b.node_count, b.leaf_count, b.reference_count,
                  (unsigned long long)s->triangle_count, b.depth);
    assert_int_equal(references, b.reference_count);
    assert_int_equal(missing, 0);
    free(seen);
    bvh_free(&b);
    scene_free(s);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_bvh_leaves_degenerate_triangles_out),
        cmocka_unit_test(test_bvh_of_empty_scene),
        cmocka_unit_test(test_bvh_covers_every_triangle),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closest_hit_straight_down),
        cmocka_unit_test(test_hits_end_at_tmax),
        cmocka_unit_test(test_shared_edge_is_watertight),
        cmocka_unit_test(test_degenerate_triangle_is_never_hit),
        cmocka_unit_test(test_empty_scene_is_never_hit),
        cmocka_unit_test(test_dragon_incoherent),
        cmocka_unit_test(test_dragon_camera),
        cmocka_unit_test(test_dragon_scaled_by_1e_3),
        cmocka_unit_test(test_dragon_scaled_by_1e4),
        cmocka_unit_test(test_living_room_incoherent),
        cmocka_unit_test(test_living_room_camera),
        DEVICE_TEST_SWEEP(test_same_hits_for_any_local_size),
    };
    return DEVICE_TEST_MAIN("traversal", host_tests, tests, group_setup, group_teardown);
}
