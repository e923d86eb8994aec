/* test_render.c — the SPPM renderer (kernels/sppm.cl, host/passes/render.c) against exact formulas.
 *
 *   point light on a plane   radiance ρ/π · I cosθ / d² at every pixel, and the error falls
 *                            as iterations grow (4, 16, 64)
 *   light power              the photons' first-hit flux sums to the power of each light kind:
 *                            area π L A, point 4π I, spot 2π I ∫ falloff, directional E × the
 *                            lit area, environment π L A on a plane's front
 *   furnace                  inside an emitting, reflecting sphere the radiance is
 *                            L_e Σ_{k≤8} ρ^k everywhere (8 stored photons per path), at radius
 *                            1, 1e-3 and 1e4
 *   caustic                  a glass ball focuses a point light: the floor under it is brighter
 *                            than the floor around its shadow
 *   glossy                   against GGX written out here from the textbook formulas: a glossy
 *                            plane under a point light (the BRDF the gather evaluates), and the
 *                            flux a photon keeps after scattering off it against the lobe's
 *                            directional albedo by quadrature (the weights scatter() samples)
 *   invariants               bit-identical images for any work-group size; finite values;
 *                            missing camera or light is an input error
 *
 * Scenes are built in code (tests/importance_common.h); one OpenCL device for the file;
 * render_run() builds sppm.cl once and later runs load it from the program cache. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#include <cmocka.h>

#include "device/bvh.h"
#include "core/error.h"
#include "importance_common.h"
#include "passes/render.h"

static device dev;

static int group_setup(void **state)
{
    (void)state;
    if (device_open(&dev, -1)) {
        fprintf(stderr, "test_render: %s\n", error_message());
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    device_close(&dev);
    return 0;
}

static void finalize_or_fail(scene *s)
{
    if (scene_finalize(s))
        fail_msg("scene_finalize: %s", error_message());
}

static void render_or_fail(const scene *s, unsigned int iterations, unsigned int photons,
                           render_snapshot *snapshot, size_t local_size, render_result *r)
{
    render_options o;
    render_options_default(&o);
    o.sppm.iterations = iterations;
    o.sppm.photons = photons;
    o.snapshot = snapshot;
    o.sppm.local_size = local_size;
    bvh b;
    if (bvh_build(s, &b))
        fail_msg("bvh_build: %s", error_message());
    int status = render_run(&dev, s, &b, &o, r);
    bvh_free(&b);
    if (status)
        fail_msg("render_run: %s", error_message());
    for (size_t i = 0; i < (size_t)r->sppm.width * r->sppm.height * 3; i++)
        if (!isfinite(r->image[i]) || r->image[i] < 0)
            fail_msg("pixel value %zu is %g", i / 3, r->image[i]);
}

/* Mean of the three channels of pixel p. */
static double pixel_mean(const render_result *r, size_t p)
{
    return (r->image[3 * p] + r->image[3 * p + 1] + r->image[3 * p + 2]) / 3.0;
}

/* ---- 1. a point light over a diffuse plane ---- */

#define PLANE_ALBEDO 0.5f
#define PLANE_LIGHT_HEIGHT 2.0f
#define PLANE_INTENSITY 10.0f

/* The plane z = 0 (10 x 10, front up, albedo 0.5) under a point light at height 2, seen from
 * above at an angle, 128 x 96. */
static scene *plane_scene(void)
{
    scene *s = scene_create("point-light-plane.xml");
    uint32_t white = imp_diffuse(s, "white", PLANE_ALBEDO, 0);
    const float c[3] = {0, 0, 0}, u[3] = {5, 0, 0}, v[3] = {0, 5, 0};
    imp_add_quad(s, "plane", white, c, u, v);
    const float light[3] = {0, 0, PLANE_LIGHT_HEIGHT}, eye[3] = {0, -3, 4}, target[3] = {0, 0, 0},
                up[3] = {0, 0, 1};
    imp_point_light(s, light, PLANE_INTENSITY);
    imp_look_at(s, eye, target, up, 128, 96, 0.5f);
    finalize_or_fail(s);
    return s;
}

/* Where the ray through the centre of pixel (x, y) meets the plane z = 0; 0 if it does not. */
static int pixel_centre_on_floor(const idmr_camera *c, unsigned int width, unsigned int height,
                                 unsigned int x, unsigned int y, double p[3])
{
    double sx = (2.0 * (x + 0.5) / width - 1.0) * c->tan_half_x;
    double sy = (1.0 - 2.0 * (y + 0.5) / height) * c->tan_half_y;
    double d[3];
    for (int k = 0; k < 3; k++)
        d[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
    if (d[2] >= 0)
        return 0;
    double t = -c->origin[2] / d[2];
    for (int k = 0; k < 3; k++)
        p[k] = c->origin[k] + t * d[k];
    p[2] = 0;
    return 1;
}

/* RMS of the relative error against ρ/π · I cosθ / d² over the pixels whose centre ray meets
 * the plane within 1.5 of the point under the light; also the ratio of the sums there. */
static double plane_error(const scene *s, const render_result *r, double *sum_ratio)
{
    double squares = 0, rendered = 0, exact = 0;
    size_t count = 0;
    const idmr_camera *c = &s->camera;
    for (unsigned int y = 0; y < r->sppm.height; y++)
        for (unsigned int x = 0; x < r->sppm.width; x++) {
            double p[3];
            if (!pixel_centre_on_floor(c, r->sppm.width, r->sppm.height, x, y, p))
                continue;
            double rho2 = p[0] * p[0] + p[1] * p[1];
            if (rho2 > 1.5 * 1.5)
                continue;
            double h = PLANE_LIGHT_HEIGHT, dist2 = rho2 + h * h;
            double expected = PLANE_ALBEDO / M_PI * PLANE_INTENSITY * (h / sqrt(dist2)) / dist2;
            double value = pixel_mean(r, (size_t)y * r->sppm.width + x);
            squares += (value - expected) * (value - expected) / (expected * expected);
            rendered += value;
            exact += expected;
            count++;
        }
    assert_true(count > 1000);
    *sum_ratio = rendered / exact;
    return sqrt(squares / count);
}

static void test_point_light_on_plane_and_convergence(void **state)
{
    (void)state;
    scene *s = plane_scene();
    const unsigned int iterations[3] = {4, 16, 64};
    double errors[3];
    for (int i = 0; i < 3; i++) {
        render_result r;
        render_or_fail(s, iterations[i], 50000, NULL, 0, &r);
        double ratio;
        errors[i] = plane_error(s, &r, &ratio);
        print_message("  %2u iterations: RMS relative error %.4f, rendered / exact over the lit "
                      "disc %.4f (radius %.3f -> %.3f)\n",
                      iterations[i], errors[i], ratio, r.sppm.radius[0],
                      r.sppm.radius[r.sppm.iterations - 1]);
        if (i == 2) {
            assert_true(fabs(ratio - 1.0) < 0.01);
            assert_true(errors[i] < 0.05);
        }
        render_result_free(&r);
    }
    assert_true(errors[1] < 0.9 * errors[0]);
    assert_true(errors[2] < 0.9 * errors[1]);
    scene_free(s);
}

/* ---- 2. emitted power of each light kind ---- */

/* Σ of the flux (R, G, B mean) of every path's first stored photon. */
static double first_photon_flux(const render_snapshot *snap)
{
    double sum = 0;
    for (size_t p = 0; p < snap->core.params.path_count; p++)
        if (snap->core.path_length[p] > 0) {
            const idmr_render_photon *ph = &snap->photons[p * IDMR_PATH_VERTICES];
            sum += ((double)ph->flux_r + ph->flux_g + ph->flux_b) / 3.0;
        }
    return sum;
}

/* Renders one iteration of `photons` paths and compares the first-hit flux with `power`,
 * within `tolerance` (relative). */
static void expect_power(const char *what, scene *s, double power, double tolerance)
{
    const float eye[3] = {0, 0, 0.5f}, target[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    if (!s->has_camera)
        imp_look_at(s, eye, target, up, 8, 8, 0.5f);
    finalize_or_fail(s);
    render_snapshot snap = {0};
    render_result r;
    render_or_fail(s, 1, 200000, &snap, 0, &r);
    double flux = first_photon_flux(&snap);
    print_message("  %-12s photon flux %.6g, power %.6g, ratio %.5f (tolerance %.4f)\n", what, flux,
                  power, flux / power, tolerance);
    assert_true(fabs(flux / power - 1.0) <= tolerance);
    render_snapshot_free(&snap);
    render_result_free(&r);
    scene_free(s);
}

/* A black two-sided box around the origin, [-2, 2]³: every photon from inside lands on it and
 * is absorbed there, so each path stores exactly its first hit. */
static scene *black_box_scene(const char *name)
{
    scene *s = scene_create(name);
    uint32_t black = imp_diffuse(s, "black", 0.0f, IDMR_MATERIAL_TWOSIDED);
    const float lo[3] = {-2, -2, -2}, hi[3] = {2, 2, 2};
    imp_add_box(s, "box", black, lo, hi);
    return s;
}

static void test_light_power_of_each_kind(void **state)
{
    (void)state;
    /* Point: every photon carries 4πI / N; the sum is exact up to float rounding. */
    scene *s = black_box_scene("point.xml");
    const float origin[3] = {0.1f, -0.2f, 0.3f};
    imp_point_light(s, origin, 3.0f);
    expect_power("point", s, 4 * M_PI * 3.0, 1e-4);

    /* Area: a 1 x 0.5 quad facing down with radiance 2: π L A = π. */
    s = black_box_scene("area.xml");
    uint32_t black = 0; /* black_box_scene's one material */
    const float qc[3] = {0, 0, 1}, qu[3] = {0.5f, 0, 0}, qv[3] = {0, -0.25f, 0};
    imp_area_light(s, imp_add_quad(s, "emitter", black, qc, qu, qv), 2.0f);
    expect_power("area", s, M_PI * 2.0 * 0.5, 1e-4);

    /* Spot: intensity 5, beam width 20°, cutoff 30°. Exact power 2π I ∫ smoothstep(cos 30°,
     * cos 20°, μ) dμ over μ in [cos 30°, 1], by the midpoint rule; the kernel rejects samples
     * outside the falloff, so the sum is binomial: 5 standard deviations. */
    s = black_box_scene("spot.xml");
    idmr_light spot;
    memset(&spot, 0, sizeof spot);
    spot.kind = IDMR_LIGHT_SPOT;
    spot.direction[2] = -1;
    spot.cos_cutoff = (float)cos(30 * M_PI / 180);
    spot.cos_falloff_start = (float)cos(20 * M_PI / 180);
    spot.emission[0] = spot.emission[1] = spot.emission[2] = 5.0f;
    scene_add_light(s, &spot);
    double integral = 0, lo = spot.cos_cutoff, hi = spot.cos_falloff_start;
    const int steps = 100000;
    double accepted = 0;
    for (int i = 0; i < steps; i++) {
        double mu = lo + (1.0 - lo) * (i + 0.5) / steps;
        double t = fmin(1.0, fmax(0.0, (mu - lo) / (hi - lo)));
        double keep = t * t * (3 - 2 * t);
        integral += keep * (1.0 - lo) / steps;
        accepted += keep / steps;
    }
    double sigma = sqrt((1 - accepted) / (accepted * 200000.0));
    expect_power("spot", s, 2 * M_PI * 5.0 * integral, 5 * sigma);

    /* Directional: irradiance 4 straight down onto a 2 x 2 plane: E × A = 16. Photons start on
     * a disc over the scene's bounding sphere (radius √2), of which the plane covers 2/π. */
    s = scene_create("directional.xml");
    black = imp_diffuse(s, "black", 0.0f, IDMR_MATERIAL_TWOSIDED);
    const float pc[3] = {0, 0, 0}, pu[3] = {1, 0, 0}, pv[3] = {0, 1, 0};
    imp_add_quad(s, "plane", black, pc, pu, pv);
    idmr_light sun;
    memset(&sun, 0, sizeof sun);
    sun.kind = IDMR_LIGHT_DIRECTIONAL;
    sun.direction[2] = -1;
    sun.emission[0] = sun.emission[1] = sun.emission[2] = 4.0f;
    scene_add_light(s, &sun);
    const float high_eye[3] = {0, -0.5f, 3}, centre[3] = {0, 0, 0}, y_up[3] = {0, 1, 0};
    imp_look_at(s, high_eye, centre, y_up, 8, 8, 0.5f);
    double hit_fraction = 2 / M_PI;
    expect_power("directional", s, 4.0 * 4.0,
                 5 * sqrt((1 - hit_fraction) / (hit_fraction * 200000.0)));

    /* Environment: radiance 0.5 from every direction onto the front of a one-sided 2 x 2 plane:
     * π L A = 2π. The back absorbs without storing. The fraction of photons that hit the front
     * is A / (4π R²) with R = √2, R² = 2. */
    s = scene_create("environment.xml");
    uint32_t one_sided = imp_diffuse(s, "black", 0.0f, 0);
    imp_add_quad(s, "plane", one_sided, pc, pu, pv);
    idmr_light sky;
    memset(&sky, 0, sizeof sky);
    sky.kind = IDMR_LIGHT_ENVIRONMENT;
    sky.emission[0] = sky.emission[1] = sky.emission[2] = 0.5f;
    scene_add_light(s, &sky);
    imp_look_at(s, high_eye, centre, y_up, 8, 8, 0.5f);
    hit_fraction = 4.0 / (4 * M_PI * 2.0);
    expect_power("environment", s, M_PI * 0.5 * 4.0,
                 5 * sqrt((1 - hit_fraction) / (hit_fraction * 200000.0)));
}

/* ---- 3. furnace ---- */

/* Inside a sphere of radius `radius` that emits 1 and reflects half of what arrives, wound
 * inward, seen from its centre: the radiance is L_e Σ_{k=0}^{8} ρ^k everywhere (photons add
 * the reflections after 0..7 bounces), whatever the scale. */
static void expect_furnace(float radius)
{
    const float albedo = 0.5f, emitted = 1.0f;
    scene *s = scene_create("furnace.xml");
    uint32_t grey = imp_diffuse(s, "grey", albedo, 0);
    const float centre[3] = {0, 0, 0};
    scene_mesh *sphere = imp_add_sphere(s, "sphere", grey, centre, radius);
    for (uint32_t t = 0; t < sphere->triangle_count; t++) {
        uint32_t *ix = &sphere->indices[3 * (size_t)t];
        uint32_t swap = ix[1];
        ix[1] = ix[2];
        ix[2] = swap;
    }
    imp_area_light(s, sphere, emitted);
    const float target[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    imp_look_at(s, centre, target, up, 48, 48, 1.0f);
    finalize_or_fail(s);
    render_result r;
    render_or_fail(s, 16, 50000, NULL, 0, &r);
    double expected = 0;
    for (int k = 0; k <= IDMR_PATH_VERTICES; k++)
        expected += emitted * pow(albedo, k);
    double sum = 0, squares = 0;
    size_t pixels = (size_t)r.sppm.width * r.sppm.height;
    for (size_t p = 0; p < pixels; p++) {
        double value = pixel_mean(&r, p);
        sum += value;
        squares += (value - expected) * (value - expected);
    }
    double mean = sum / pixels, rms = sqrt(squares / pixels) / expected;
    print_message("  radius %g: mean radiance %.5f, exact %.5f (ratio %.5f), RMS relative error "
                  "%.4f\n",
                  radius, mean, expected, mean / expected, rms);
    assert_true(fabs(mean / expected - 1) < 0.01);
    assert_true(rms < 0.05);
    render_result_free(&r);
    scene_free(s);
}

static void test_furnace_at_any_scale(void **state)
{
    (void)state;
    expect_furnace(1.0f);
    expect_furnace(1e-3f);
    expect_furnace(1e4f);
}

/* ---- 4. a caustic under a glass ball ---- */

static void test_glass_ball_caustic(void **state)
{
    (void)state;
    scene *s = scene_create("caustic.xml");
    uint32_t white = imp_diffuse(s, "white", 0.8f, 0), glass = imp_glass(s, "glass");
    const float c[3] = {0, 0, 0}, u[3] = {3, 0, 0}, v[3] = {0, 3, 0};
    imp_add_quad(s, "floor", white, c, u, v);
    const float ball[3] = {0, 0, 1};
    imp_add_sphere(s, "ball", glass, ball, 0.5f);
    const float light[3] = {0, 0, 8}, eye[3] = {0, -3, 2}, target[3] = {0, 0, 0},
                up[3] = {0, 0, 1};
    imp_point_light(s, light, 50.0f);
    imp_look_at(s, eye, target, up, 128, 96, 0.4f); /* sees the floor under the ball */
    finalize_or_fail(s);
    render_snapshot snap = {0};
    render_result r;
    render_or_fail(s, 8, 100000, &snap, 0, &r);
    /* Pixels by where their (last iteration's) hit point lies on the floor. */
    double focus = 0, around = 0;
    size_t focus_count = 0, around_count = 0;
    for (size_t p = 0; p < (size_t)r.sppm.width * r.sppm.height; p++) {
        const idmr_hit_point *hp = &snap.core.hit_points[p];
        if (!hp->valid || fabsf(hp->position[2]) > 1e-3f)
            continue;
        double rho = hypot(hp->position[0], hp->position[1]);
        if (rho < 0.08) {
            focus += pixel_mean(&r, p);
            focus_count++;
        } else if (rho > 1.0 && rho < 1.5) {
            around += pixel_mean(&r, p);
            around_count++;
        }
    }
    print_message("  %zu pixels see the floor under the ball, %zu around its shadow\n", focus_count,
                  around_count);
    assert_true(focus_count >= 4 && around_count >= 100);
    focus /= focus_count;
    around /= around_count;
    print_message("  floor under the ball %.4g (%zu pixels), around its shadow %.4g (%zu pixels): "
                  "%.1fx brighter\n",
                  focus, focus_count, around, around_count, focus / around);
    assert_true(focus > 2 * around);
    render_snapshot_free(&snap);
    render_result_free(&r);
    scene_free(s);
}

/* ---- 5. glossy lobes against the textbook GGX ---- */

#define GLOSSY_ROUGHNESS 0.3
#define GLOSSY_SPECULAR 0.8f

static double ggx_distribution(double cos_h, double alpha)
{
    double a2 = alpha * alpha, c2 = cos_h * cos_h;
    double d = c2 * (a2 - 1) + 1;
    return cos_h > 0 ? a2 / (M_PI * d * d) : 0;
}

static double smith_g1(double cos_v, double alpha)
{
    double tan2 = (1 - cos_v * cos_v) / (cos_v * cos_v);
    return 2 / (1 + sqrt(1 + alpha * alpha * tan2));
}

static double fresnel(double cos_i, double eta)
{
    double sin2_t = eta * eta * (1 - cos_i * cos_i);
    if (sin2_t >= 1)
        return 1;
    double cos_t = sqrt(1 - sin2_t);
    double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    double rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

/* f(i, o) of a glossy material for unit directions towards the light (l) and the viewer (v)
 * above a surface with normal +z: metal (diffuse 0) spec D G / (4 cos_i cos_o); plastic adds
 * Fresnel(cos_i) to the coating and (1 - Fresnel(cos_i)) ρ/π. */
static double glossy_brdf(const double l[3], const double v[3], double diffuse, double eta)
{
    if (l[2] <= 0 || v[2] <= 0)
        return 0;
    double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
    double length = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double cos_h = h[2] / length;
    double f = diffuse > 0 ? fresnel(l[2], eta) : 1.0;
    double coat = GLOSSY_SPECULAR * ggx_distribution(cos_h, GLOSSY_ROUGHNESS) *
                  smith_g1(l[2], GLOSSY_ROUGHNESS) * smith_g1(v[2], GLOSSY_ROUGHNESS) /
                  (4 * l[2] * v[2]);
    return f * coat + (1 - f) * diffuse / M_PI;
}

/* ∫ f(i, o) cos_o dω_o over the hemisphere, light at cosine cos_i (midpoint rule in cos θ_o
 * and φ; the lobe is smooth at this roughness). */
static double directional_albedo(double cos_i, double diffuse, double eta)
{
    const int n_theta = 300, n_phi = 300;
    double l[3] = {sqrt(fmax(0, 1 - cos_i * cos_i)), 0, cos_i}, sum = 0;
    for (int a = 0; a < n_theta; a++) {
        double mu = (a + 0.5) / n_theta, sin_o = sqrt(1 - mu * mu);
        for (int b = 0; b < n_phi; b++) {
            double phi = 2 * M_PI * (b + 0.5) / n_phi;
            double v[3] = {sin_o * cos(phi), sin_o * sin(phi), mu};
            sum += glossy_brdf(l, v, diffuse, eta) * mu;
        }
    }
    return sum * (1.0 / n_theta) * (2 * M_PI / n_phi);
}

static uint32_t glossy_material(scene *s, double diffuse)
{
    float d = (float)diffuse;
    idmr_material m = {{d, d, d}, IDMR_MATERIAL_GLOSSY,
                       {GLOSSY_SPECULAR, GLOSSY_SPECULAR, GLOSSY_SPECULAR},
                       (float)GLOSSY_ROUGHNESS, 1.5f, 1.0f, -1, 0};
    return scene_add_material(s, diffuse > 0 ? "plastic" : "metal",
                              diffuse > 0 ? "roughplastic" : "roughconductor", &m);
}

/* A glossy metal plane under a point light, seen at an angle through its highlight: every
 * pixel against f · I cos_i / d². */
static void test_glossy_plane_under_point_light(void **state)
{
    (void)state;
    scene *s = scene_create("glossy-plane.xml");
    uint32_t metal = glossy_material(s, 0.0);
    const float c[3] = {0, 0, 0}, u[3] = {5, 0, 0}, v[3] = {0, 5, 0};
    imp_add_quad(s, "plane", metal, c, u, v);
    const float light[3] = {0, 0.8f, 2}, eye[3] = {0, -3, 3}, target[3] = {0, 0, 0},
                up[3] = {0, 0, 1};
    imp_point_light(s, light, PLANE_INTENSITY);
    imp_look_at(s, eye, target, up, 128, 96, 0.5f);
    finalize_or_fail(s);
    render_result r;
    render_or_fail(s, 64, 50000, NULL, 0, &r);
    const idmr_camera *cam = &s->camera;
    double rendered = 0, exact = 0, squares = 0, peak = 0;
    size_t count = 0;
    for (unsigned int y = 0; y < r.sppm.height; y++)
        for (unsigned int x = 0; x < r.sppm.width; x++) {
            double p[3];
            if (!pixel_centre_on_floor(cam, r.sppm.width, r.sppm.height, x, y, p))
                continue;
            if (fabs(p[0]) > 1.5 || fabs(p[1]) > 1.5)
                continue;
            double l[3], view[3], dist2 = 0, view2 = 0;
            for (int k = 0; k < 3; k++) {
                l[k] = light[k] - p[k];
                view[k] = cam->origin[k] - p[k];
                dist2 += l[k] * l[k];
                view2 += view[k] * view[k];
            }
            for (int k = 0; k < 3; k++) {
                l[k] /= sqrt(dist2);
                view[k] /= sqrt(view2);
            }
            double expected = glossy_brdf(l, view, 0, 1) * PLANE_INTENSITY * l[2] / dist2;
            double value = pixel_mean(&r, (size_t)y * r.sppm.width + x);
            rendered += value;
            exact += expected;
            squares += (value - expected) * (value - expected);
            peak = fmax(peak, expected);
            count++;
        }
    double rms = sqrt(squares / count) / (exact / count);
    print_message("  %zu pixels: rendered / exact %.4f, RMS error %.4f of the mean (peak %.3g, "
                  "mean %.3g)\n",
                  count, rendered / exact, rms, peak, exact / count);
    assert_true(count > 3000);
    assert_true(fabs(rendered / exact - 1) < 0.02);
    assert_true(rms < 0.1);
    render_result_free(&r);
    scene_free(s);
}

/* Photons from a point light hit a glossy plane, scatter once and land on a black box around
 * it: per photon, the flux it lands with (0 if absorbed) estimates its flux on the plane times
 * the lobe's directional albedo at its angle of incidence. Summed over the photons, within 5
 * standard deviations of that sum, plus 0.5 % for the quadrature. Metal and plastic. */
static void test_glossy_scattering_keeps_the_albedo(void **state)
{
    (void)state;
    for (int plastic = 0; plastic < 2; plastic++) {
        double diffuse = plastic ? 0.5 : 0.0;
        scene *s = black_box_scene(plastic ? "plastic.xml" : "metal.xml");
        uint32_t glossy = glossy_material(s, diffuse);
        const float c[3] = {0, 0, -1}, u[3] = {1.5f, 0, 0}, v[3] = {0, 1.5f, 0};
        imp_add_quad(s, "plane", glossy, c, u, v);
        const float light[3] = {0.3f, 0, 0.5f};
        imp_point_light(s, light, 1.0f);
        const float eye[3] = {0, 0, 0.5f}, target[3] = {0, 0, -1}, up[3] = {0, 1, 0};
        imp_look_at(s, eye, target, up, 8, 8, 0.5f);
        finalize_or_fail(s);
        double albedo[91];
        for (int i = 0; i <= 90; i++)
            albedo[i] = directional_albedo(fmax(1e-3, i / 90.0), diffuse, 1 / 1.5);
        render_snapshot snap = {0};
        render_result r;
        render_or_fail(s, 1, 200000, &snap, 0, &r);
        double landed = 0, expected = 0, variance = 0;
        size_t on_plane = 0;
        for (size_t p = 0; p < snap.core.params.path_count; p++) {
            const idmr_render_photon *first = &snap.photons[p * IDMR_PATH_VERTICES];
            if (snap.core.path_length[p] == 0 || fabsf(first->position[2] + 1) > 1e-4f)
                continue;
            on_plane++;
            double flux = (first->flux_r + first->flux_g + first->flux_b) / 3.0;
            double cos_i = -first->direction[2], at = cos_i * 90, whole = floor(at);
            int k = (int)fmin(89, whole);
            double a = albedo[k] + (at - k) * (albedo[k + 1] - albedo[k]);
            double after = 0;
            if (snap.core.path_length[p] > 1) {
                const idmr_render_photon *second = first + 1;
                after = (second->flux_r + second->flux_g + second->flux_b) / 3.0;
            }
            landed += after;
            expected += flux * a;
            variance += (after - flux * a) * (after - flux * a);
        }
        double sigma = sqrt(variance);
        print_message("  %s: %zu photons on the plane; flux after scattering %.5g, expected "
                      "%.5g (ratio %.4f, 5 sigma %.4f)\n",
                      plastic ? "plastic" : "metal", on_plane, landed, expected,
                      landed / expected, 5 * sigma / expected);
        assert_true(on_plane > 10000);
        assert_true(fabs(landed - expected) <= 5 * sigma + 0.005 * expected);
        render_snapshot_free(&snap);
        render_result_free(&r);
        scene_free(s);
    }
}

/* ---- 6. invariants ---- */

static void test_same_image_for_any_local_size(void **state)
{
    (void)state;
    scene *s = plane_scene();
    render_result a, b;
    render_or_fail(s, 2, 20000, NULL, 0, &a);
    render_or_fail(s, 2, 20000, NULL, 1, &b);
    size_t bytes = (size_t)a.sppm.width * a.sppm.height * 3 * sizeof(float);
    assert_int_equal(a.sppm.width, b.sppm.width);
    assert_memory_equal(a.image, b.image, bytes);
    render_result_free(&b);
    render_or_fail(s, 2, 20000, NULL, 64, &b);
    assert_memory_equal(a.image, b.image, bytes);
    render_result_free(&a);
    render_result_free(&b);
    scene_free(s);
}

static void test_missing_camera_or_light_is_an_input_error(void **state)
{
    (void)state;
    scene *s = scene_create("no-light.xml");
    uint32_t white = imp_diffuse(s, "white", 0.5f, 0);
    const float c[3] = {0, 0, 0}, u[3] = {1, 0, 0}, v[3] = {0, 1, 0};
    imp_add_quad(s, "plane", white, c, u, v);
    const float eye[3] = {0, 0, 2}, target[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    imp_look_at(s, eye, target, up, 8, 8, 0.5f);
    finalize_or_fail(s);
    bvh b;
    assert_int_equal(bvh_build(s, &b), 0);
    render_options o;
    render_options_default(&o);
    render_result r;
    assert_int_equal(render_run(&dev, s, &b, &o, &r), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    print_message("  %s\n", error_message());
    assert_non_null(strstr(error_message(), "no-light.xml"));
    render_result_free(&r);
    bvh_free(&b);
    scene_free(s);

    /* With a light but without a camera. */
    s = scene_create("no-camera.xml");
    white = imp_diffuse(s, "white", 0.5f, 0);
    imp_add_quad(s, "plane", white, c, u, v);
    const float light[3] = {0, 0, 1};
    imp_point_light(s, light, 1.0f);
    finalize_or_fail(s);
    assert_int_equal(bvh_build(s, &b), 0);
    error_clear();
    assert_int_equal(render_run(&dev, s, &b, &o, &r), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    print_message("  %s\n", error_message());
    assert_non_null(strstr(error_message(), "no sensor"));
    render_result_free(&r);
    bvh_free(&b);
    scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light_on_plane_and_convergence),
        cmocka_unit_test(test_light_power_of_each_kind),
        cmocka_unit_test(test_furnace_at_any_scale),
        cmocka_unit_test(test_glass_ball_caustic),
        cmocka_unit_test(test_glossy_plane_under_point_light),
        cmocka_unit_test(test_glossy_scattering_keeps_the_albedo),
        cmocka_unit_test(test_same_image_for_any_local_size),
        cmocka_unit_test(test_missing_camera_or_light_is_an_input_error),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
