/* test_importance_camera.c — the importance pass's camera pass (kernels/lib/paths.h,
 * host/passes/importance.c): Eq. 2 on the host, and per-triangle Eq. 2 sums and hit points on
 * the device against the same jittered camera rays recomputed on the host (a quad seen head-on,
 * a scene against Embree's rtcIntersect1, a view through a mirror), and the light seen in a
 * mirror against its formula (passes/importance.h, light(T)).
 *
 * Each device test checks one formula on a run made once per device (imp_run) of a scene
 * built in code; the Eq. 2 tests are host-only and run once. */
#include "importance_common.h"

/* ---- Eq. 2 on the host: w = 1 - |n·d| / (|n||d|) ---- */

static void test_eq2_head_on_is_zero(void **state)
{
    assert_true(idmr_eq2_weight(0, 0, 1, 0, 0, -1) == 0.0f);
    assert_true(idmr_eq2_weight(0, 0, 1, 0, 0, 3) == 0.0f); /* from behind, unnormalised */
}

static void test_eq2_in_the_plane_is_one(void **state)
{
    assert_true(idmr_eq2_weight(0, 0, 1, 1, 0, 0) == 1.0f);
}

/* 1 - cos θ between: grazing (cos = 1e-4 / sqrt(1 + 1e-8)), 45°, and an oblique normal and
 * direction against the double formula. */
static void test_eq2_is_one_minus_cosine(void **state)
{
    assert_float_equal(idmr_eq2_weight(0, 0, 1, 1, 0, 1e-4f), 1.0 - 1e-4, 1e-6);
    assert_float_equal(idmr_eq2_weight(0, 1, 0, 1, -1, 0), 1.0 - cos(M_PI / 4), 1e-6);
    float n[3] = {0.3f, -0.5f, 0.8f}, d[3] = {-0.7f, 0.2f, 0.4f};
    double c = fabs(imp_dot(n, d)) / sqrt(imp_dot(n, n) * imp_dot(d, d));
    assert_float_equal(idmr_eq2_weight(n[0], n[1], n[2], d[0], d[1], d[2]), 1.0 - c, 1e-6);
}

/* No direction — a NaN component, a zero segment, a zero normal, an infinite component — adds
 * 0, never NaN. */
static void test_eq2_without_direction_is_zero(void **state)
{
    assert_true(idmr_eq2_weight(NAN, 0.0f, 1.0f, 0.0f, 0.0f, 1.0f) == 0.0f);
    assert_true(idmr_eq2_weight(0.0f, 0.0f, 1.0f, 0.0f, NAN, 1.0f) == 0.0f);
    assert_true(idmr_eq2_weight(0, 0, 1, 0, 0, 0) == 0.0f);
    assert_true(idmr_eq2_weight(0, 0, 0, 1, 2, 3) == 0.0f);
    assert_true(idmr_eq2_weight(0, 0, 0, 0, 0, 0) == 0.0f);
    assert_true(idmr_eq2_weight(0, 0, 1, INFINITY, 0, 1) == 0.0f);
}

/* Scaling either vector changes nothing: huge, tiny and subnormal vectors give the weight of
 * the vectors as passed (rounded after scaling), computed in double. */
static void test_eq2_ignores_scale(void **state)
{
    const float n[3] = {0.3f, -0.5f, 0.8f}, d[3] = {-0.7f, 0.2f, 0.4f};
    const float scales[] = {1e30f, 1e-30f, 1e-40f, 3e38f};
    const double w45 = 1.0 - cos(M_PI / 4);
    for (int i = 0; i < 4; i++) {
        float s = scales[i], ns[3], ds[3];
        for (int k = 0; k < 3; k++) {
            ns[k] = n[k] * s;
            ds[k] = d[k] * s;
        }
        double cs = fabs(imp_dot(ns, ds)) / (sqrt(imp_dot(ns, ns)) * sqrt(imp_dot(ds, ds)));
        float a = idmr_eq2_weight(0, 0, s, s, 0, s);
        float b = idmr_eq2_weight(ns[0], ns[1], ns[2], ds[0], ds[1], ds[2]);
        assert_true(isfinite(a) && isfinite(b));
        assert_float_equal(a, w45, 1e-6);
        assert_float_equal(b, 1.0 - cs, 1e-6);
        assert_true(idmr_eq2_weight(0, s, 0, 0, -s, 0) == 0.0f); /* head-on */
        /* normal huge, direction tiny and the other way round */
        assert_float_equal(idmr_eq2_weight(0, 0, s, 1e-30f, 0, 1e-30f), w45, 1e-6);
        assert_float_equal(idmr_eq2_weight(0, 0, 1e-30f, s, 0, s), w45, 1e-6);
    }
}

/* ---- a quad filling the view head-on ---- */

/* The quad z = 0, 20 x 20 (normal +z), seen from (0, 0, 5) at 64 x 48; one iteration. */
static scene *head_on_scene(void)
{
    scene *s = scene_create("head-on.xml");
    imp_add_quad(s, "quad", imp_diffuse(s, "white", 0.8f, 0), V3(0, 0, 0), V3(10, 0, 0),
                 V3(0, 10, 0));
    imp_point_light(s, V3(0, 0, 3), 1.0f);
    imp_look_at(s, V3(0, 0, 5), V3(0, 0, 0), V3(0, 1, 0), 64, 48, 0.5f);
    return test_finalize_scene(s);
}

static imp_case head_on = {.make = head_on_scene, .iterations = 1, .photons = 20000};

/* Where pixel p's jittered ray meets the plane z = 0, and its direction. */
static void head_on_ray(const imp_case *run, unsigned int p, double *x, double *y, float d[3])
{
    imp_camera_direction(&run->s->camera, 64, 48, run->options.sppm.seed, 0, p, d);
    double t = -5.0 / d[2];
    *x = t * d[0];
    *y = t * d[1];
}

/* Every pixel's hit point lies where its ray meets the quad, and a ray leaving it starts 2^-20
 * of the quad's largest coordinate (10) off it: more than 2^-20 of the camera's (5). */
static void test_head_on_hit_points_on_the_quad(void **state)
{
    const imp_case *run = imp_run(&head_on);
    for (unsigned int p = 0; p < 64 * 48; p++) {
        double x, y;
        float d[3];
        head_on_ray(run, p, &x, &y, d);
        const idmr_hit_point *hp = &run->snapshot.core.hit_points[p];
        if (hp->offset != 10.0f * IDMR_RAY_OFFSET_SCALE)
            fail_msg("pixel %u: offset %g, expected 10 * 2^-20", p, hp->offset);
        assert_float_equal(hp->position[0], x, 1e-4);
        assert_float_equal(hp->position[1], y, 1e-4);
    }
}

/* Each pixel adds 1 - |cos| of its ray with the quad's normal to the triangle it hits; the
 * sums agree to the fixed-point rounding (2^-21 per pixel) and float rounding of the
 * directions. Pixels whose hit lies within 1e-4 of the quad's diagonal may go either way. */
static void test_head_on_sums_are_eq2(void **state)
{
    const imp_case *run = imp_run(&head_on);
    const unsigned int pixels = 64 * 48;
    const float n[3] = {0, 0, 1};
    double expected[2] = {0, 0}, ambiguous = 0;
    for (unsigned int p = 0; p < pixels; p++) {
        double x, y;
        float d[3];
        head_on_ray(run, p, &x, &y, d);
        double w = idmr_eq2_weight(n[0], n[1], n[2], d[0], d[1], d[2]);
        expected[y < x ? 0 : 1] += w; /* triangle 0 = (c-u-v, c+u-v, c+u+v) holds y < x */
        if (fabs(x - y) < 1e-4)
            ambiguous += w;
    }
    double bound = pixels * (0.5 * IMP_FIXED_UNIT + 1e-6) + ambiguous;
    for (int t = 0; t < 2; t++) {
        double on_device = (double)run->snapshot.camera_fixed[t] * IMP_FIXED_UNIT;
        print_message("  triangle %d: device %.6f, host %.6f, |diff| %.2e (bound %.2e)\n", t,
                      on_device, expected[t], fabs(on_device - expected[t]), bound);
        assert_true(fabs(on_device - expected[t]) <= bound);
    }
    assert_true(expected[0] > 10 && expected[1] > 10); /* the weights are not all 0 */
}

/* One iteration: the result's sums are the accumulators. */
static void test_head_on_result_is_the_accumulators(void **state)
{
    const imp_case *run = imp_run(&head_on);
    for (int t = 0; t < 2; t++)
        assert_true(run->r.camera[t] == (double)run->snapshot.camera_fixed[t] * IMP_FIXED_UNIT);
}

/* ---- against Embree ---- */

/* A diffuse floor (wound facing down, so the camera sees its back), a glossy sphere and a
 * diffuse box under a point light, seen from a camera with background on three sides; the
 * film is scaled by 0.5 (192 x 128 -> 96 x 64). */
static scene *embree_scene(void)
{
    scene *s = scene_create("camera-vs-embree.xml");
    uint32_t white = imp_diffuse(s, "white", 0.8f, 0);
    /* wound facing down: seen from its back */
    imp_add_quad(s, "floor", white, V3(0, 0, 0), V3(2, 0, 0), V3(0, 0, 2));
    imp_add_sphere(s, "sphere", imp_glossy(s, "glossy"), V3(0.6f, 0.5f, 0.0f), 0.5f);
    imp_add_box(s, "box", white, V3(-1.2f, 0.0f, -0.6f), V3(-0.4f, 0.8f, 0.2f));
    imp_point_light(s, V3(0, 3, 1), 5.0f);
    imp_look_at(s, V3(0, 1.6f, 4), V3(0, 0.3f, 0), V3(0, 1, 0), 192, 128, 0.6f);
    return test_finalize_scene(s);
}

#define EMBREE_WIDTH 96
#define EMBREE_HEIGHT 64
#define EMBREE_PIXELS (EMBREE_WIDTH * EMBREE_HEIGHT)

static imp_case embree = {
    .make = embree_scene, .iterations = 1, .photons = 20000, .resolution = 0.5f};
static float embree_d[EMBREE_PIXELS][3]; /* each pixel's jittered ray direction */
static idmr_hit embree_hit[EMBREE_PIXELS]; /* and its hit, by Embree */

/* The run, with embree_d[] and embree_hit[] filled. */
static const imp_case *embree_traced(void)
{
    const imp_case *run = imp_run(&embree);
    RTCScene es = trace_embree_scene(run->s);
    for (unsigned int p = 0; p < EMBREE_PIXELS; p++) {
        imp_camera_direction(&run->s->camera, EMBREE_WIDTH, EMBREE_HEIGHT, run->options.sppm.seed, 0,
                             p, embree_d[p]);
        idmr_ray ray;
        trace_set_ray(&ray, run->s->camera.origin, embree_d[p], 0.0f, INFINITY);
        trace_embree_closest(es, &ray, &embree_hit[p]);
    }
    rtcReleaseScene(es);
    return run;
}

static void test_embree_scene_film_is_scaled(void **state)
{
    const imp_case *run = embree_traced();
    assert_int_equal(run->r.sppm.width, EMBREE_WIDTH);
    assert_int_equal(run->r.sppm.height, EMBREE_HEIGHT);
    assert_int_equal(run->snapshot.core.params.width, EMBREE_WIDTH);
}

/* Per triangle, Σ Eq. 2 over the pixels whose ray Embree finds on it (expected[]) and how many
 * (hit_count[]); *ambiguous gets the weight of the rays within 1e-5 of a triangle edge (in
 * barycentrics), which may go to the neighbour. Returns the rays that hit. */
static size_t embree_sums(const scene *s, double *expected, unsigned int *hit_count,
                          double *ambiguous)
{
    size_t embree_hits = 0;
    *ambiguous = 0;
    for (unsigned int p = 0; p < EMBREE_PIXELS; p++) {
        const idmr_hit *hit = &embree_hit[p];
        const float *d = embree_d[p];
        if (hit->triangle == IDMR_NO_HIT)
            continue;
        embree_hits++;
        float n[3];
        imp_triangle_normal(s, hit->triangle, n);
        double w = idmr_eq2_weight(n[0], n[1], n[2], d[0], d[1], d[2]);
        expected[hit->triangle] += w;
        hit_count[hit->triangle]++;
        if (fminf(fminf(hit->u, hit->v), 1.0f - hit->u - hit->v) < 1e-5f)
            *ambiguous += w;
    }
    return embree_hits;
}

/* Per triangle, the device's camera importance of one iteration equals the sum of Eq. 2
 * weights over the same rays traced by Embree, within 2^-20 per hit plus 1e-4 relative plus
 * the ambiguous rays' weight; Σ|error| is within the bounds with that weight counted twice (a
 * ray at an edge moves its weight once); a triangle Embree never hits gets exactly 0 when no
 * ray is ambiguous. */
static void test_embree_triangle_sums_are_eq2(void **state)
{
    const imp_case *run = embree_traced();
    size_t triangles = (size_t)run->s->triangle_count, triangle_errors = 0, triangles_hit = 0;
    double *expected = calloc(triangles, sizeof *expected), ambiguous;
    unsigned int *hit_count = calloc(triangles, sizeof *hit_count);
    size_t embree_hits = embree_sums(run->s, expected, hit_count, &ambiguous);
    double worst = 0, total_error = 0, total_bound = 2 * ambiguous;
    for (size_t t = 0; t < triangles; t++) {
        double on_device = (double)run->snapshot.camera_fixed[t] * IMP_FIXED_UNIT;
        double bound = hit_count[t] * IMP_FIXED_UNIT + 1e-4 * expected[t] + ambiguous;
        double error = fabs(on_device - expected[t]);
        triangles_hit += hit_count[t] > 0;
        total_error += error;
        total_bound += bound - ambiguous;
        worst = bound > 0 ? fmax(worst, error / bound) : worst;
        if (error > bound && triangle_errors++ < 5)
            print_message("  triangle %zu: device %.7f, host %.7f (%u hits)\n", t, on_device,
                          expected[t], hit_count[t]);
        if (hit_count[t] == 0 && run->snapshot.camera_fixed[t] != 0 && ambiguous == 0)
            triangle_errors++;
    }
    print_message("  %d pixels, %zu Embree hits on %zu triangles; %zu triangle sums off (worst "
                  "%.3f of the bound; ambiguous weight %.2e); Σ|error| %.2e (bound %.2e)\n",
                  EMBREE_PIXELS, embree_hits, triangles_hit, triangle_errors, worst, ambiguous,
                  total_error, total_bound);
    free(expected);
    free(hit_count);
    assert_true(total_error <= total_bound);
    assert_true(embree_hits > EMBREE_PIXELS / 2 && embree_hits < EMBREE_PIXELS);
    assert_true(triangles_hit > 200); /* the sphere's triangles are exercised */
    assert_int_equal(triangle_errors, 0);
}

/* A pixel has a hit point exactly where Embree hits (no specular surface here). */
static void test_embree_hit_points_where_embree_hits(void **state)
{
    const imp_case *run = embree_traced();
    size_t mismatches = 0;
    for (unsigned int p = 0; p < EMBREE_PIXELS; p++)
        mismatches += (embree_hit[p].triangle != IDMR_NO_HIT) !=
                      (run->snapshot.core.hit_points[p].offset > 0.0f);
    assert_int_equal(mismatches, 0);
}

/* Each hit point lies at Embree's hit position within 1e-4 of the scene diagonal, with the
 * normal of the side the camera sees. */
static void test_embree_hit_point_positions_and_sides(void **state)
{
    const imp_case *run = embree_traced();
    double diagonal = scene_diagonal(run->s), worst = 0;
    size_t checked = 0, position_errors = 0;
    for (unsigned int p = 0; p < EMBREE_PIXELS; p++) {
        const idmr_hit_point *hp = &run->snapshot.core.hit_points[p];
        if (embree_hit[p].triangle == IDMR_NO_HIT || !(hp->offset > 0.0f))
            continue;
        double error = 0;
        for (int k = 0; k < 3; k++)
            error = fmax(error, fabs(hp->position[k] - ((double)run->s->camera.origin[k] +
                                                        (double)embree_hit[p].t * embree_d[p][k])));
        worst = fmax(worst, error / diagonal);
        position_errors += error > 1e-4 * diagonal;
        assert_true(imp_dot(hp->normal, embree_d[p]) < 0); /* faces the camera */
        checked++;
    }
    print_message("  %zu hit points, %zu position errors (worst %.2e of the diagonal)\n", checked,
                  position_errors, worst);
    assert_true(checked > EMBREE_PIXELS / 2);
    assert_int_equal(position_errors, 0);
}

/* ---- through a mirror ---- */

/* The camera looks down -z at a mirror tilted 45° about y (normal (1, 0, 1)/√2), which sends
 * its rays along +x to a diffuse wall at x = 3 facing -x; the wall is outside the camera's
 * cone (|x/z| <= 0.2 there, >= 0.75 at the wall). 48 x 40 pixels. */
static scene *mirror_scene(void)
{
    scene *s = scene_create("mirror.xml");
    const float r2 = 0.70710678f;
    imp_add_quad(s, "mirror", imp_mirror(s, "mirror"), V3(0, 0, -2), V3(0, 1, 0),
                 V3(-r2, 0, r2)); /* triangles 0, 1 */
    imp_add_quad(s, "wall", imp_diffuse(s, "white", 0.8f, 0), V3(3, 0, -2), V3(0, 0, 2),
                 V3(0, 2, 0)); /* triangles 2, 3; normal -x */
    imp_point_light(s, V3(1.5f, 1.5f, -1), 1.0f);
    imp_look_at(s, V3(0, 0, 0), V3(0, 0, -1), V3(0, 1, 0), 48, 40, 0.2f);
    return test_finalize_scene(s);
}

#define MIRROR_PIXELS (48 * 40)

static imp_case mirror = {.make = mirror_scene, .iterations = 1, .photons = 20000};

/* Pixel p's ray: its direction d, where it meets the mirror plane x + z = -2 (at) and its
 * reflection about the mirror's normal nm (out), in float as the kernels do. */
static void mirror_ray(const imp_case *run, unsigned int p, float d[3], float at[3], float out[3])
{
    float nm[3];
    imp_triangle_normal(run->s, 0, nm);
    imp_camera_direction(&run->s->camera, 48, 40, run->options.sppm.seed, 0, p, d);
    double t = -2.0 / (d[0] + d[2]);
    float dn = (float)imp_dot(d, nm);
    for (int k = 0; k < 3; k++) {
        out[k] = d[k] - 2.0f * dn * nm[k];
        at[k] = (float)(t * d[k]);
    }
}

/* Every hit point lies on the wall (none on the mirror) where the reflected ray meets it, with
 * the normal of the wall's side facing the path. */
static void test_mirror_hit_points_on_the_wall(void **state)
{
    const imp_case *run = imp_run(&mirror);
    double worst = 0;
    for (unsigned int p = 0; p < MIRROR_PIXELS; p++) {
        float d[3], at[3], out[3];
        mirror_ray(run, p, d, at, out);
        const idmr_hit_point *hp = &run->snapshot.core.hit_points[p];
        assert_true(hp->offset > 0.0f);
        double t2 = (3.0 - at[0]) / out[0];
        for (int k = 0; k < 3; k++)
            worst = fmax(worst, fabs(hp->position[k] - (at[k] + t2 * out[k])));
        assert_float_equal(hp->position[0], 3.0, 1e-4);
        assert_true(hp->normal[0] < -0.999f);
    }
    print_message("  worst hit point position error %.2e\n", worst);
    assert_true(worst < 1e-3);
}

/* Camera importance of mesh `first` (its two triangles) against Σ Eq. 2 over the pixels of
 * `which` ray (0: the camera ray at the mirror, 1: the reflected ray at the wall), within the
 * fixed-point rounding plus 1e-4 relative. */
static void expect_mirror_sum(unsigned int first, int which)
{
    const imp_case *run = imp_run(&mirror);
    float n[3];
    imp_triangle_normal(run->s, first, n);
    double expected = 0;
    for (unsigned int p = 0; p < MIRROR_PIXELS; p++) {
        float d[3], at[3], out[3];
        mirror_ray(run, p, d, at, out);
        const float *ray = which ? out : d;
        expected += idmr_eq2_weight(n[0], n[1], n[2], ray[0], ray[1], ray[2]);
    }
    const uint64_t *fixed = run->snapshot.camera_fixed;
    double on_device = (double)(fixed[first] + fixed[first + 1]) * IMP_FIXED_UNIT;
    print_message("  camera importance %.4f, host %.4f\n", on_device, expected);
    assert_true(on_device > 0);
    double bound = MIRROR_PIXELS * 0.5 * IMP_FIXED_UNIT + 1e-4 * expected;
    assert_true(fabs(on_device - expected) <= bound);
}

static void test_mirror_adds_eq2_of_the_camera_ray(void **state)
{
    expect_mirror_sum(0, 0);
}

static void test_wall_adds_eq2_of_the_reflected_ray(void **state)
{
    expect_mirror_sum(2, 1);
}

/* ---- a light seen in the mirror ---- */

#define SEEN_RADIANCE 2.0f

/* The mirror scene with the wall an area light of radiance 2 facing the mirror: every camera
 * path sees the light in the mirror. */
static scene *seen_light_scene(void)
{
    scene *s = scene_create("seen-light.xml");
    const float r2 = 0.70710678f;
    imp_add_quad(s, "mirror", imp_mirror(s, "mirror"), V3(0, 0, -2), V3(0, 1, 0),
                 V3(-r2, 0, r2));
    scene_mesh *wall = imp_add_quad(s, "wall", imp_diffuse(s, "white", 0.8f, 0), V3(3, 0, -2),
                                    V3(0, 0, 2), V3(0, 2, 0));
    imp_area_light(s, wall, SEEN_RADIANCE);
    imp_look_at(s, V3(0, 0, 0), V3(0, 0, -1), V3(0, 1, 0), 48, 40, 0.2f);
    return test_finalize_scene(s);
}

static imp_case seen_light = {.make = seen_light_scene, .iterations = 1, .photons = 20000};

/* The mirror's seen light: Σ over the pixels of Eq. 2 of the camera ray × the luminance it sees
 * (the mirror's 0.9 × the light's 2), in units of 2^20 per the brightest luminance (2), within
 * the rounding; the wall, which is not specular, gets none. */
static void test_mirror_sums_the_light_it_shows(void **state)
{
    const imp_case *run = imp_run(&seen_light);
    float n[3];
    imp_triangle_normal(run->s, 0, n);
    double expected = 0;
    for (unsigned int p = 0; p < MIRROR_PIXELS; p++) {
        float d[3], at[3], out[3];
        mirror_ray(run, p, d, at, out);
        expected += idmr_eq2_weight(n[0], n[1], n[2], d[0], d[1], d[2]) * 0.9 * SEEN_RADIANCE;
    }
    const uint64_t *fixed = run->snapshot.seen_light_fixed;
    double unit = SEEN_RADIANCE * IMP_FIXED_UNIT; /* luminance per fixed-point unit */
    assert_float_equal(run->snapshot.core.params.fixed_scale, 1.0 / unit, 1e-3);
    double on_device = (double)(fixed[0] + fixed[1]) * unit;
    print_message("  seen light %.4f, host %.4f\n", on_device, expected);
    assert_true(expected > 0);
    assert_true(fabs(on_device - expected) <= MIRROR_PIXELS * 0.5 * unit + 1e-4 * expected);
    assert_true(fixed[2] == 0 && fixed[3] == 0);
}

/* The result's light importance is the photons' gathers plus the seen light as gathers:
 * 10 Y π² r² N / Φ per unit of luminance Y, Φ = π × area × radiance for the 4 x 4 light. */
static void test_seen_light_counts_as_gathers(void **state)
{
    const imp_case *run = imp_run(&seen_light);
    const idmr_sppm_params *params = &run->snapshot.core.params;
    double r = params->radius, power = M_PI * 16.0 * SEEN_RADIANCE;
    double gathers = 10.0 * M_PI * M_PI * r * r * params->path_count / power;
    assert_true(r > 0);
    for (size_t t = 0; t < 4; t++) {
        double expected = (double)run->snapshot.light_fixed[t] * IMP_FIXED_UNIT +
                          (double)run->snapshot.seen_light_fixed[t] * SEEN_RADIANCE *
                              IMP_FIXED_UNIT * gathers;
        assert_float_equal(run->r.light[t], expected, 1e-9 * expected + 1e-12);
    }
    assert_true(run->r.light[0] + run->r.light[1] >
                (double)(run->snapshot.light_fixed[0] + run->snapshot.light_fixed[1]) *
                    IMP_FIXED_UNIT);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_eq2_head_on_is_zero),
        cmocka_unit_test(test_eq2_in_the_plane_is_one),
        cmocka_unit_test(test_eq2_is_one_minus_cosine),
        cmocka_unit_test(test_eq2_without_direction_is_zero),
        cmocka_unit_test(test_eq2_ignores_scale),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_head_on_hit_points_on_the_quad),
        cmocka_unit_test(test_head_on_sums_are_eq2),
        cmocka_unit_test(test_head_on_result_is_the_accumulators),
        cmocka_unit_test(test_embree_scene_film_is_scaled),
        cmocka_unit_test(test_embree_triangle_sums_are_eq2),
        cmocka_unit_test(test_embree_hit_points_where_embree_hits),
        cmocka_unit_test(test_embree_hit_point_positions_and_sides),
        cmocka_unit_test(test_mirror_hit_points_on_the_wall),
        cmocka_unit_test(test_mirror_adds_eq2_of_the_camera_ray),
        cmocka_unit_test(test_wall_adds_eq2_of_the_reflected_ray),
        cmocka_unit_test(test_mirror_sums_the_light_it_shows),
        cmocka_unit_test(test_seen_light_counts_as_gathers),
    };
    return DEVICE_TEST_MAIN("importance camera", host_tests, tests, NULL, imp_teardown);
}
