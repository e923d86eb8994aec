/* test_instanced_traversal.c — the instanced traversal (kernels/lib/traverse_instanced.h,
 * kernels/trace.cl: trace_instanced_closest/any) and the two-level BVH it walks
 * (host/device/instance_bvh.c), against Embree's own instancing and against the flat traversal
 * of the same instances flattened.
 *
 * The scene: the Stanford dragon at resolution 3 (48k triangles) placed 50 times with random
 * rotations and scales, one of them mirrored and one stretched non-uniformly
 * (instance_random_placements); plus scaled sets (every instance 1e4 and 1e-3 times its size
 * about a far-off origin) and a mixed set (one instance grown 1000 times about its centre, around
 * the others, and instances of an empty prototype).
 *
 * Closest hit must find the same (instance, triangle) as the reference — rtcIntersect1 on
 * Embree's two-level scene (RTC_GEOMETRY_TYPE_INSTANCE), or the flat trace kernel on the
 * flattened copies — with t within the distance bound: 1e-4 relative plus 1e-6 of the scene
 * diagonal (test_traversal's), plus the rounding of the ray's move into object space. That move
 * rounds the object-space origin by an ulp or so of its largest term (|W o| or |w|: far from
 * the world origin, as large as the world coordinates themselves), which the two sides round
 * differently (Embree inverts the transform in float, idmr in double; the flat copies round the
 * vertices instead); an error e across the surface is e / |cos| along a ray at incidence cos,
 * so the bound adds 8 ulps of that term over |cos| (transform_slack). Allowed, and counted
 * apart:
 *   - a tie: both hit, at the same t within the distance bound (a ray through an edge or
 *     vertex shared by two triangles: either is right, as in test_traversal);
 *   - an edge graze: the nearer of the two hits lies within 1e-3 (barycentric) of its
 *     triangle's edge, so that the two sides' different roundings of the ray (Embree inverts
 *     the transform in float, idmr in double; the flat copies round the vertices instead of
 *     the ray) put it on either side of a silhouette edge. At most 1 in 10,000 rays.
 * Any hit must agree with rtcOccluded1 (or the flat any-hit kernel) on every ray but the
 * grazes, with tmax before or beyond the reference's closest hit by 1% (as test_traversal).
 * A wrong transform (the forward one instead of its inverse, a dropped translation, a
 * renormalised direction) makes nearly every hit a mismatch or a distance error:
 * assert_int_equal(c.mismatches, 0) and assert_int_equal(c.distance_errors, 0) in
 * expect_agreement catch it, and test_on_paper's asserts name the instance, triangle and t
 * worked out by hand.
 *
 * Host tests (once): a singular transform and a missing prototype are refused with their
 * instance named; device memory counts each prototype once. Device tests: every OpenCL device
 * (tests/device_test.h), the trace program built once per device. */
#include "importance_common.h"
#include "instance_common.h"

#define DRAGON SHARED_DATA "/models/dragon_vrip_res3.ply"
#define INSTANCES 50
#define GRAZE_BARYCENTRIC 1e-3f
#define MAX_GRAZE_SHARE 1e-4

static trace_device tdev;
static mesh_data dragon; /* loaded once per device group */

static int group_setup(void **state)
{
    if (mesh_io_read(DRAGON, &dragon)) {
        fprintf(stderr, "loading %s: %s\n", DRAGON, error_message());
        return -1;
    }
    return trace_device_open_reporting(&tdev, device_test_device());
}

static int group_teardown(void **state)
{
    mesh_data_free(&dragon);
    trace_device_close(&tdev);
    return 0;
}

/* ---- scenes ---- */

/* Prototype 0 the dragon, prototype 1 empty; the caller fills the placements. */
typedef struct test_scene {
    instance_prototype prototypes[2];
    instance_placement *placements;
    instanced_scene s;
} test_scene;

static void test_scene_init(test_scene *t, size_t count)
{
    t->prototypes[0] = instance_prototype_of_mesh(&dragon);
    t->prototypes[1] = (instance_prototype){.positions = NULL};
    t->placements = calloc(count, sizeof *t->placements);
    t->s = (instanced_scene){t->prototypes, 2, t->placements, count};
}

/* The 50 dragons of the file's comment. */
static void dragons(test_scene *t, unsigned int seed)
{
    test_scene_init(t, INSTANCES);
    bvh_box box = instance_prototype_box(&t->prototypes[0]);
    instance_random_placements(&box, INSTANCES, seed, t->placements);
}

/* Every placement scaled by `scale` about the world origin, then moved by 3 * scale. */
static void scale_placements(test_scene *t, float scale)
{
    for (size_t i = 0; i < t->s.instance_count; i++)
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 4; c++)
                t->placements[i].object_to_world[4 * r + c] *= scale;
            t->placements[i].object_to_world[4 * r + 3] += 3.0f * scale;
        }
}

static double box_diagonal(const float lo[3], const float hi[3])
{
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    return sqrt(d2);
}

/* ---- comparison ---- */

typedef struct comparison {
    size_t rays;
    size_t hits;
    size_t same;
    size_t tied_distance;
    size_t edge_grazes;
    size_t mismatches;
    size_t occlusion_mismatches;
    size_t distance_errors;
    double worst_distance_error; /* |t - t_ref| / the distance bound, worst ray */
    unsigned char *grazed;       /* per ray: an edge graze (its occlusion may differ) */
} comparison;

static float edge_distance(const idmr_instance_hit *h)
{
    return fminf(fminf(h->u, h->v), 1.0f - h->u - h->v);
}

/* The distance error (in t) that rounding the ray into hit h's object space may cause (see the
 * top of the file): 8 ulps of the largest term of the object-space origin, over |cos| between
 * the object-space direction and the triangle's normal, over the object-space direction's
 * length (t is counted in it). Zero for no hit. */
static double transform_slack(const instanced_scene *s, const instance_bvh *b,
                              const idmr_ray *ray, const idmr_instance_hit *h)
{
    if (h->triangle == IDMR_NO_HIT)
        return 0.0;
    const float *w = b->instances[h->instance].world_to_object;
    const instance_prototype *proto = &s->prototypes[s->instances[h->instance].prototype];
    double largest = 0.0, d[3];
    for (int r = 0; r < 3; r++) {
        double term = fabs((double)w[4 * r + 3]);
        d[r] = 0.0;
        for (int c = 0; c < 3; c++) {
            term += fabs((double)w[4 * r + c] * ray->origin[c]);
            d[r] += (double)w[4 * r + c] * ray->direction[c];
        }
        largest = fmax(largest, term);
    }
    const uint32_t *ix = &proto->indices[3 * (size_t)h->triangle];
    const float *v0 = &proto->positions[3 * (size_t)ix[0]], *v1 = &proto->positions[3 * (size_t)ix[1]];
    const float *v2 = &proto->positions[3 * (size_t)ix[2]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)v1[k] - v0[k];
        e2[k] = (double)v2[k] - v0[k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]); /* t's unit in object space */
    double cosine = fabs(n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) /
                    (sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * length);
    return 8.0 * 0x1p-24 * largest / (fmax(cosine, 1e-6) * length);
}

/* Closest hits `got` against the reference `want` on `rays` in scene s (its two-level BVH b),
 * into c. */
static void compare_closest(const instanced_scene *s, const instance_bvh *b,
                            const idmr_ray *rays, const idmr_instance_hit *got,
                            const idmr_instance_hit *want, comparison *c)
{
    double diagonal = box_diagonal(b->bounds_min, b->bounds_max);
    for (size_t i = 0; i < c->rays; i++) {
        const idmr_instance_hit *d = &got[i], *e = &want[i];
        c->hits += e->triangle != IDMR_NO_HIT;
        double bound = 1e-4 * fabs(e->t) + 1e-6 * diagonal +
                       fmax(transform_slack(s, b, &rays[i], d), transform_slack(s, b, &rays[i], e));
        if (d->triangle == e->triangle && d->instance == e->instance) {
            c->same++;
            if (d->triangle == IDMR_NO_HIT)
                continue;
            double error = fabs((double)d->t - e->t) / bound;
            c->worst_distance_error = fmax(c->worst_distance_error, error);
            if (error > 1.0 && c->distance_errors++ < 5)
                print_message("  distance ray %zu: instance %u tri %u t=%.9g reference t=%.9g\n",
                              i, d->instance, d->triangle, d->t, e->t);
            continue;
        }
        int both_hit = d->triangle != IDMR_NO_HIT && e->triangle != IDMR_NO_HIT;
        const idmr_instance_hit *nearer =
            e->triangle == IDMR_NO_HIT || (d->triangle != IDMR_NO_HIT && d->t < e->t) ? d : e;
        if (both_hit && fabs((double)d->t - e->t) <= bound) {
            c->tied_distance++;
        } else if (edge_distance(nearer) < GRAZE_BARYCENTRIC) {
            c->edge_grazes++;
            c->grazed[i] = 1;
        } else if (c->mismatches++ < 5) {
            print_message("  mismatch ray %zu: instance %u tri %u t=%.9g, reference instance %u "
                          "tri %u t=%.9g\n", i, d->instance, d->triangle, d->t, e->instance,
                          e->triangle, e->t);
        }
    }
}

/* The rays' tmax set before (odd rays) or beyond (even rays) the reference's closest hit, by
 * 1% of the distance and 1e-5 of the diagonal (test_traversal's compare_occlusion). */
static void set_occlusion_tmax(idmr_ray *rays, const idmr_instance_hit *want, size_t count,
                               double diagonal)
{
    double margin = 1e-5 * diagonal;
    for (size_t i = 0; i < count; i++) {
        double t = want[i].triangle == IDMR_NO_HIT ? 10.0 * diagonal : want[i].t;
        idmr_rng rng = idmr_rng_init(77, 0, IDMR_STREAM_TEST, (unsigned int)i);
        double before = fmin(t * (0.5 + 0.49 * idmr_rng_float(&rng)), t - margin);
        double beyond = fmax(t * 1.01, t + margin);
        rays[i].tmax = (float)((i & 1) ? fmax(before, 0.0) : beyond);
    }
}

static void compare_occlusion(const idmr_instance_hit *got, const int *want, comparison *c)
{
    for (size_t i = 0; i < c->rays; i++) {
        int occluded = got[i].triangle != IDMR_NO_HIT;
        if (occluded != want[i] && !c->grazed[i] && c->occlusion_mismatches++ < 5)
            print_message("  occlusion mismatch ray %zu: device %d reference %d\n", i, occluded,
                          want[i]);
    }
}

static void expect_comparison(const comparison *c, const char *reference)
{
    print_message("  %zu rays against %s, %zu hits: %zu same, %zu tied on an edge, %zu edge "
                  "grazes, %zu mismatches, %zu occlusion mismatches, %zu distance errors (worst "
                  "%.3f of the bound)\n",
                  c->rays, reference, c->hits, c->same, c->tied_distance, c->edge_grazes,
                  c->mismatches, c->occlusion_mismatches, c->distance_errors,
                  c->worst_distance_error);
    assert_true(c->hits > c->rays / 10);
    assert_int_equal(c->mismatches, 0);
    assert_int_equal(c->occlusion_mismatches, 0);
    assert_int_equal(c->distance_errors, 0);
    assert_true((double)c->edge_grazes <= MAX_GRAZE_SHARE * (double)c->rays);
}

/* The instanced traversal's closest (any = 0) or any hits of `rays`, or the test fails. */
static void trace_instanced(const instance_geometry *g, const idmr_ray *rays, size_t count,
                            idmr_instance_hit *hits, int any)
{
    if (instance_trace_run(&tdev, g, rays, hits, count, any, 0, NULL))
        fail_msg("%s", error_message());
}

/* The instanced traversal against Embree's two-level scene on `rays`. */
static void expect_embree_agreement(const instanced_scene *s, idmr_ray *rays, size_t count)
{
    instance_geometry g;
    if (instance_geometry_upload(&tdev, s, &g))
        fail_msg("%s", error_message());
    double diagonal = box_diagonal(g.tree.bounds_min, g.tree.bounds_max);
    RTCScene es = instance_embree_scene(s);
    idmr_instance_hit *got = calloc(count, sizeof *got), *want = calloc(count, sizeof *want);
    int *occluded = calloc(count, sizeof *occluded);
    comparison c = {.rays = count, .grazed = calloc(count, 1)};

    trace_instanced(&g, rays, count, got, 0);
    for (size_t i = 0; i < count; i++)
        want[i] = instance_embree_closest(es, &rays[i]);
    compare_closest(s, &g.tree, rays, got, want, &c);
    set_occlusion_tmax(rays, want, count, diagonal);
    trace_instanced(&g, rays, count, got, 1);
    for (size_t i = 0; i < count; i++)
        occluded[i] = trace_embree_occluded(es, &rays[i]);
    compare_occlusion(got, occluded, &c);

    rtcReleaseScene(es);
    instance_geometry_release(&g);
    free(got);
    free(want);
    free(occluded);
    free(c.grazed);
    expect_comparison(&c, "Embree's instancing");
}

/* `count` incoherent rays in the scene's world box, against Embree. */
static void expect_incoherent_agreement(const instanced_scene *s, size_t count, unsigned int seed)
{
    instance_bvh b;
    if (instance_bvh_build(s, &b))
        fail_msg("%s", error_message());
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays_in_box(b.bounds_min, b.bounds_max, rays, count, seed);
    instance_bvh_free(&b);
    expect_embree_agreement(s, rays, count);
    free(rays);
}

static void test_dragons_incoherent(void **state)
{
    test_scene t;
    dragons(&t, 1);
    expect_incoherent_agreement(&t.s, 100000, 2);
    free(t.placements);
}

static void test_dragons_camera(void **state)
{
    test_scene t;
    dragons(&t, 1);
    instance_bvh b;
    if (instance_bvh_build(&t.s, &b))
        fail_msg("%s", error_message());
    idmr_camera cam = trace_overview_camera_of_box(b.bounds_min, b.bounds_max, 400, 250);
    instance_bvh_free(&b);
    size_t count = (size_t)cam.width * cam.height;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_camera_rays(&cam, rays, cam.width, cam.height, 3);
    expect_embree_agreement(&t.s, rays, count);
    free(rays);
    free(t.placements);
}

/* Ten dragons, every one 1e4 (then 1e-3) times its size about a far-off origin: 30k rays. */
static void expect_scaled_agreement(float scale, unsigned int seed)
{
    test_scene t;
    test_scene_init(&t, 10);
    bvh_box box = instance_prototype_box(&t.prototypes[0]);
    instance_random_placements(&box, 10, seed, t.placements);
    scale_placements(&t, scale);
    expect_incoherent_agreement(&t.s, 30000, seed);
    free(t.placements);
}

static void test_dragons_scaled_by_1e4(void **state)
{
    expect_scaled_agreement(1e4f, 4);
}

static void test_dragons_scaled_by_1e_3(void **state)
{
    expect_scaled_agreement(1e-3f, 5);
}

/* Placement i grown `scale` times about the world position of the prototype box's centre. */
static void grow_placement(test_scene *t, size_t i, float scale)
{
    bvh_box box = instance_prototype_box(&t->prototypes[t->placements[i].prototype]);
    float centre[3], world[3];
    for (int a = 0; a < 3; a++)
        centre[a] = 0.5f * (box.min[a] + box.max[a]);
    instance_placement_apply(&t->placements[i], centre, world);
    float *m = t->placements[i].object_to_world;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            m[4 * r + c] *= scale;
        m[4 * r + 3] = world[r] + scale * (m[4 * r + 3] - world[r]);
    }
}

/* Twelve dragons, one of them grown 1000 times about its centre (around the others), and four
 * instances of the empty prototype among them: 20k rays in the whole scene, 20k among nine
 * dragons of normal size (which sit inside the grown one's box). */
static void test_mixed_scales_and_empty_prototype(void **state)
{
    test_scene t;
    test_scene_init(&t, 16);
    bvh_box box = instance_prototype_box(&t.prototypes[0]);
    instance_random_placements(&box, 16, 6, t.placements);
    for (size_t i = 12; i < 16; i++)
        t.placements[i].prototype = 1;
    test_scene normal = t; /* nine of normal size: placements 3 .. 11 */
    normal.s.instances = t.placements + 3;
    normal.s.instance_count = 9;
    instance_bvh b;
    if (instance_bvh_build(&normal.s, &b))
        fail_msg("%s", error_message());
    size_t count = 40000;
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays_in_box(b.bounds_min, b.bounds_max, rays + count / 2, count / 2, 7);
    instance_bvh_free(&b);
    grow_placement(&t, 2, 1000.0f);
    if (instance_bvh_build(&t.s, &b))
        fail_msg("%s", error_message());
    trace_random_rays_in_box(b.bounds_min, b.bounds_max, rays, count / 2, 6);
    instance_bvh_free(&b);
    expect_embree_agreement(&t.s, rays, count);
    free(rays);
    free(t.placements);
}

/* The first FLATTENED of the 50 dragons (the mirrored and the stretched one among them)
 * instanced against the same flattened into world-space copies (the flat BVH and traversal:
 * its spatial-split build of the copies is what takes the time here): 100k incoherent rays,
 * closest and any hit. */
#define FLATTENED 16
static void test_same_hits_as_flattened_copies(void **state)
{
    test_scene t;
    dragons(&t, 1);
    t.s.instance_count = FLATTENED;
    size_t count = 100000;
    instance_geometry g;
    trace_geometry flat = {0};
    instance_flat copies;
    instance_flatten(&t.s, &copies);
    if (instance_geometry_upload(&tdev, &t.s, &g) ||
        bvh_build_meshes(copies.meshes, copies.count, &flat.tree) ||
        trace_geometry_upload_tree(&tdev, &flat))
        fail_msg("%s", error_message());
    double diagonal = box_diagonal(g.tree.bounds_min, g.tree.bounds_max);
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays_in_box(g.tree.bounds_min, g.tree.bounds_max, rays, count, 7);
    idmr_instance_hit *got = calloc(count, sizeof *got), *want = calloc(count, sizeof *want);
    idmr_hit *flat_hits = calloc(count, sizeof *flat_hits);
    int *occluded = calloc(count, sizeof *occluded);
    comparison c = {.rays = count, .grazed = calloc(count, 1)};

    trace_instanced(&g, rays, count, got, 0);
    if (trace_device_run(&tdev, &flat, rays, flat_hits, count, 0, 0, NULL))
        fail_msg("%s", error_message());
    for (size_t i = 0; i < count; i++)
        want[i] = instance_flat_hit(&copies, &flat_hits[i]);
    compare_closest(&t.s, &g.tree, rays, got, want, &c);
    set_occlusion_tmax(rays, want, count, diagonal);
    trace_instanced(&g, rays, count, got, 1);
    if (trace_device_run(&tdev, &flat, rays, flat_hits, count, 1, 0, NULL))
        fail_msg("%s", error_message());
    for (size_t i = 0; i < count; i++)
        occluded[i] = flat_hits[i].triangle != IDMR_NO_HIT;
    compare_occlusion(got, occluded, &c);

    free(rays);
    free(got);
    free(want);
    free(flat_hits);
    free(occluded);
    free(c.grazed);
    trace_geometry_release(&flat);
    instance_geometry_release(&g);
    instance_flat_free(&copies);
    free(t.placements);
    expect_comparison(&c, "the flattened copies");
}

/* The same hits, to the bit, with this work-group size as with the runtime's choice. */
static void test_same_hits_for_any_local_size(void **state)
{
    test_scene t;
    dragons(&t, 1);
    size_t count = 30000, hits = 0;
    instance_geometry g;
    if (instance_geometry_upload(&tdev, &t.s, &g))
        fail_msg("%s", error_message());
    idmr_ray *rays = malloc(count * sizeof *rays);
    trace_random_rays_in_box(g.tree.bounds_min, g.tree.bounds_max, rays, count, 8);
    idmr_instance_hit *a = calloc(count, sizeof *a), *b = calloc(count, sizeof *b);
    int status = instance_trace_run(&tdev, &g, rays, a, count, 0, 0, NULL) ||
                 instance_trace_run(&tdev, &g, rays, b, count, 0, device_test_local_size(state),
                                    NULL);
    for (size_t i = 0; i < count; i++)
        hits += a[i].triangle != IDMR_NO_HIT;
    int same = memcmp(a, b, count * sizeof *a) == 0;
    instance_geometry_release(&g);
    free(rays);
    free(a);
    free(b);
    free(t.placements);
    if (status)
        fail_msg("%s", error_message());
    assert_true(hits > count / 10);
    assert_true(same);
}

/* ---- on paper ----
 *
 * The prototype is test_traversal's quad, (-1, -1, 0) .. (1, 1, 0):
 *
 *     3 ------ 2      triangle 0 = (0, 1, 2): below the diagonal (y < x)
 *     |  1  /  |      triangle 1 = (0, 2, 3): above it
 *     |  /  0  |
 *     0 ------ 1
 *
 * Instance 0 is the identity; instance 1 mirrors x, scales by 2 and lifts by 3:
 * world = (-2x, 2y, 2z + 3). A ray straight down from (0.5, -0.25, 10) meets instance 1 at
 * world z = 3 (t = 7), at object (-0.25, -0.125): above the diagonal, triangle 1; then
 * instance 0 at t = 10, at (0.5, -0.25): triangle 0. A forward transform in place of its
 * inverse, or a lost translation, or the mirror dropped, changes the instance, the triangle or
 * t asserted below. */
static const float quad_positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
static const uint32_t quad_indices[] = {0, 1, 2, 0, 2, 3};

static instance_prototype quad_prototype(void)
{
    return (instance_prototype){.positions = quad_positions, .vertex_count = 4,
                                .indices = quad_indices, .triangle_count = 2};
}

static instance_geometry quad_geometry(const instance_placement *placements, size_t count)
{
    instance_prototype quad = quad_prototype();
    instanced_scene s = {&quad, 1, placements, count};
    instance_geometry g;
    if (instance_geometry_upload(&tdev, &s, &g))
        fail_msg("%s", error_message());
    return g;
}

static const instance_placement paper_placements[2] = {
    {0, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}},
    {0, {-2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 3}},
};

static idmr_instance_hit trace_paper(idmr_ray ray, int any)
{
    instance_geometry g = quad_geometry(paper_placements, 2);
    idmr_instance_hit hit;
    int status = instance_trace_run(&tdev, &g, &ray, &hit, 1, any, 0, NULL);
    instance_geometry_release(&g);
    if (status)
        fail_msg("%s", error_message());
    return hit;
}

#define PAPER_RAY(tmin, tmax) ((idmr_ray){{0.5f, -0.25f, 10.0f}, (tmin), {0, 0, -1.0f}, (tmax)})

static void test_on_paper(void **state)
{
    idmr_instance_hit hit = trace_paper(PAPER_RAY(0.0f, INFINITY), 0);
    assert_int_equal(hit.instance, 1);
    assert_int_equal(hit.triangle, 1);
    assert_float_equal(hit.t, 7.0f, 1e-6f);
    /* past instance 1: instance 0, triangle 0, t = 10; u, v at (0.5, -0.25) of (v0, v1, v2) =
     * ((-1,-1), (1,-1), (1,1)): v = (y + 1) / 2 = 0.375, u = (x + 1) / 2 - v = 0.375 */
    hit = trace_paper(PAPER_RAY(7.5f, INFINITY), 0);
    assert_int_equal(hit.instance, 0);
    assert_int_equal(hit.triangle, 0);
    assert_float_equal(hit.t, 10.0f, 1e-6f);
    assert_float_equal(hit.u, 0.375f, 1e-6f);
    assert_float_equal(hit.v, 0.375f, 1e-6f);
    /* t is the world t for a direction of any length: twice as long, half the t */
    hit = trace_paper((idmr_ray){{0.5f, -0.25f, 10.0f}, 0.0f, {0, 0, -2.0f}, INFINITY}, 0);
    assert_int_equal(hit.instance, 1);
    assert_float_equal(hit.t, 3.5f, 1e-6f);
    /* any hit ends at tmax */
    assert_int_equal(trace_paper(PAPER_RAY(0.0f, 6.9f), 1).triangle, IDMR_NO_HIT);
    assert_int_equal(trace_paper(PAPER_RAY(0.0f, 7.1f), 1).triangle, 1u);
    assert_int_equal(trace_paper(PAPER_RAY(7.5f, 9.9f), 1).triangle, IDMR_NO_HIT);
    assert_int_equal(trace_paper(PAPER_RAY(0.0f, 6.9f), 0).triangle, IDMR_NO_HIT);
}

/* A scene of no instances, and one of empty prototypes only, is never hit. */
static void test_empty_scenes_are_never_hit(void **state)
{
    const idmr_ray ray = {{0, 0, 0}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    instance_prototype empty = {.positions = NULL};
    instance_placement identity = {0, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
    instanced_scene scenes[2] = {{&empty, 1, NULL, 0}, {&empty, 1, &identity, 1}};
    for (int k = 0; k < 2; k++)
        for (int any = 0; any < 2; any++) {
            instance_geometry g;
            idmr_instance_hit hit;
            idmr_ray r = ray;
            if (instance_geometry_upload(&tdev, &scenes[k], &g) ||
                instance_trace_run(&tdev, &g, &r, &hit, 1, any, 0, NULL))
                fail_msg("%s", error_message());
            instance_geometry_release(&g);
            assert_int_equal(hit.triangle, IDMR_NO_HIT);
            assert_int_equal(hit.instance, IDMR_NO_HIT);
        }
}

/* ---- the two-level BVH (host) ---- */

/* A transform that flattens space is refused, naming the instance; so is a tiny but regular
 * one accepted. */
static void test_singular_transform_is_refused(void **state)
{
    instance_prototype quad = quad_prototype();
    instance_placement placements[2] = {
        {0, {1e-6f, 0, 0, 0, 0, 1e-6f, 0, 0, 0, 0, 1e-6f, 0}},  /* tiny: fine */
        {0, {1, 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 5}},              /* rows 0, 1, 2: rank 2 */
    };
    instanced_scene s = {&quad, 1, placements, 1};
    instance_bvh b;
    assert_int_equal(instance_bvh_build(&s, &b), 0);
    instance_bvh_free(&b);
    s.instance_count = 2;
    assert_int_equal(instance_bvh_build(&s, &b), -1);
    print_message("  %s\n", error_message());
    assert_non_null(strstr(error_message(), "instance 1: singular transform"));
}

static void test_missing_prototype_is_refused(void **state)
{
    instance_prototype quad = quad_prototype();
    instance_placement placement = {1, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
    instanced_scene s = {&quad, 1, &placement, 1};
    instance_bvh b;
    assert_int_equal(instance_bvh_build(&s, &b), -1);
    assert_non_null(strstr(error_message(), "instance 0: prototype 1 does not exist"));
}

/* Each prototype's nodes and packets are stored once: 50 instances of the dragon hold the
 * dragon's BVH once, and the instanced scene's bytes are its BVH, 50 records and the top
 * level; the flattened copies take about 50 times the dragon's BVH. */
static void test_memory_counts_each_prototype_once(void **state)
{
    mesh_data m;
    if (mesh_io_read(DRAGON, &m))
        fail_msg("%s", error_message());
    test_scene t;
    instance_prototype proto = instance_prototype_of_mesh(&m);
    t.placements = calloc(INSTANCES, sizeof *t.placements);
    bvh_box box = instance_prototype_box(&proto);
    instance_random_placements(&box, INSTANCES, 1, t.placements);
    instanced_scene s = {&proto, 1, t.placements, INSTANCES};
    bvh_mesh mesh = {m.positions, m.indices, m.triangle_count, 0};
    instance_bvh b;
    bvh single;
    if (instance_bvh_build(&s, &b) || bvh_build_meshes(&mesh, 1, &single))
        fail_msg("%s", error_message());
    assert_int_equal(b.node_count, single.node_count);
    assert_int_equal(b.leaf_count, single.leaf_count);
    assert_int_equal(b.instance_count, INSTANCES);
    uint64_t expected = bvh_device_bytes(&single) + INSTANCES * sizeof(idmr_instance) +
                        b.top_node_count * sizeof(idmr_bvh_node);
    assert_int_equal(instance_bvh_device_bytes(&b), expected);
    /* every instance sits in exactly one top-level slot */
    int seen[INSTANCES] = {0};
    for (size_t n = 0; n < b.top_node_count; n++)
        for (int k = 0; k < 4; k++) {
            int ref = b.top_nodes[n].child[k];
            if (ref < 0 && b.top_nodes[n].min_x[k] <= b.top_nodes[n].max_x[k]) {
                assert_true(~ref < INSTANCES);
                seen[~ref]++;
            }
        }
    for (int i = 0; i < INSTANCES; i++)
        assert_int_equal(seen[i], 1);
    print_message("  %d instances: %llu bytes (the dragon's BVH %llu bytes once, top level %zu "
                  "nodes)\n", INSTANCES, (unsigned long long)instance_bvh_device_bytes(&b),
                  (unsigned long long)bvh_device_bytes(&single), b.top_node_count);
    bvh_free(&single);
    instance_bvh_free(&b);
    free(t.placements);
    mesh_data_free(&m);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_singular_transform_is_refused),
        cmocka_unit_test(test_missing_prototype_is_refused),
        cmocka_unit_test(test_memory_counts_each_prototype_once),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_on_paper),
        cmocka_unit_test(test_empty_scenes_are_never_hit),
        cmocka_unit_test(test_dragons_incoherent),
        cmocka_unit_test(test_dragons_camera),
        cmocka_unit_test(test_dragons_scaled_by_1e4),
        cmocka_unit_test(test_dragons_scaled_by_1e_3),
        cmocka_unit_test(test_mixed_scales_and_empty_prototype),
        cmocka_unit_test(test_same_hits_as_flattened_copies),
        DEVICE_TEST_SWEEP(test_same_hits_for_any_local_size),
    };
    return DEVICE_TEST_MAIN("instanced traversal", host_tests, tests, group_setup,
                            group_teardown);
}
