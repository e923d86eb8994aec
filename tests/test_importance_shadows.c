/* test_importance_shadows.c — shadow importance (kernels/lib/shadows.h): the triangles that cast
 * the shadows the camera sees get importance, even when the camera does not see them.
 *
 * The scene: a 10 x 10 floor, a black sphere (radius 0.5, centre 1.5 above the floor: it absorbs
 * every photon, so no light path continues from it) and a light 4 above the floor; the camera,
 * 0.9 above the floor looking straight down with a 90-degree view, sees the sphere's shadow and
 * the lit floor around it, and nothing of the sphere, which is above and behind it.
 *
 *   without shadow rays   the sphere's importance is exactly 0: no camera path and no gathered
 *                         photon path touches it
 *   with shadow rays      it is > 0, all of it shadow importance
 *   silhouette            per area, the ring that grazes the light's view of the sphere
 *                         (|n · l| < 0.25) holds more than 3 x what the bottom cap facing the
 *                         floor holds (n · l < -0.75), and the half facing the light (n · l > 0),
 *                         which no shadow ray reaches first, holds none
 *   sharpness             a point light's shadow outweighs the soft shadow of a 4 x 4 area light
 *                         at the same place by more than 5 x (its penumbra is ~30 pixels wide) */
#include "importance_common.h"

static scene *shadow_scene(int area_light)
{
    scene *s = scene_create(area_light ? "area-shadow" : "point-shadow");
    const float centre[3] = {0, 0, 0}, u[3] = {5, 0, 0}, v[3] = {0, 0, -5};
    imp_add_quad(s, "floor", imp_diffuse(s, "grey", 0.5f, 0), centre, u, v); /* normal +y */
    const float sphere[3] = {0, 1.5f, 0};
    imp_add_sphere(s, "sphere", imp_diffuse(s, "black", 0.0f, 0), sphere, 0.5f);
    const float light[3] = {0, 4, 0};
    if (area_light) {
        const float lu[3] = {2, 0, 0}, lv[3] = {0, 0, 2}; /* normal -y: facing the floor */
        imp_area_light(s, imp_add_quad(s, "lamp", imp_diffuse(s, "lamp", 0.0f, 0), light, lu, lv),
                       2.0f);
    } else {
        imp_point_light(s, light, 30.0f);
    }
    const float eye[3] = {0, 0.9f, 0}, up[3] = {0, 0, -1};
    imp_look_at(s, eye, centre, up, 64, 64, 1.0f);
    return test_finalize_scene(s);
}

static scene *point_shadow_scene(void) { return shadow_scene(0); }
static scene *area_shadow_scene(void) { return shadow_scene(1); }

static imp_case point_light = {.make = point_shadow_scene, .iterations = 4, .photons = 20000};
static imp_case no_shadow_rays = {
    .make = point_shadow_scene, .iterations = 4, .photons = 20000, .without_shadows = 1};
static imp_case area_light = {.make = area_shadow_scene, .iterations = 4, .photons = 20000};

static double mesh_sum(const imp_case *run, const double *per_triangle)
{
    return imp_mesh_total(run->s, (size_t)imp_mesh_index(run->s, "sphere"), per_triangle);
}

static void test_sphere_unseen_without_shadow_rays(void **state)
{
    const imp_case *run = imp_run(&no_shadow_rays);
    assert_true(run->r.sppm.hit_points > 0);
    assert_true(mesh_sum(run, run->r.camera) == 0.0);
    assert_true(mesh_sum(run, run->r.light) == 0.0);
    assert_true(mesh_sum(run, run->r.shadow) == 0.0);
}

static void test_sphere_gets_shadow_importance(void **state)
{
    const imp_case *run = imp_run(&point_light);
    print_message("  sphere: shadow importance %.4g\n", mesh_sum(run, run->r.shadow));
    assert_true(mesh_sum(run, run->r.camera) == 0.0);
    assert_true(mesh_sum(run, run->r.light) == 0.0);
    assert_true(mesh_sum(run, run->r.shadow) > 0.0);
    importance_weights w = {1.0f, 1.0f};
    importance_sums sums =
        importance_mesh_sums(&run->r, run->s, (size_t)imp_mesh_index(run->s, "sphere"), &w);
    assert_true(sums.amount > 0 && sums.amount == sums.shadow);
}

/* Shadow importance per area of the sphere's triangles in three bands of n · l, l the unit
 * direction from a triangle's centre to the light. */
static void test_silhouette_ring_is_most_important(void **state)
{
    const imp_case *run = imp_run(&point_light);
    const scene_mesh *m = &run->s->meshes[imp_mesh_index(run->s, "sphere")];
    double importance[3] = {0, 0, 0}, area[3] = {0, 0, 0}; /* ring, bottom cap, lit half */
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        float n[3], c[3] = {0, 0, 0};
        uint64_t global = (uint64_t)m->first_triangle + t;
        imp_triangle_normal(run->s, global, n);
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                c[i] += m->positions[3 * (size_t)m->indices[3 * (size_t)t + k] + i] / 3.0f;
        float l[3] = {-c[0], 4.0f - c[1], -c[2]};
        trace_normalize(l);
        double cosine = imp_dot(n, l);
        int band = fabs(cosine) < 0.25 ? 0 : cosine < -0.75 ? 1 : cosine > 0 ? 2 : -1;
        if (band < 0)
            continue;
        importance[band] += run->r.shadow[global];
        area[band] += scene_triangle_area(run->s, global);
    }
    double ring = importance[0] / area[0], bottom = importance[1] / area[1];
    print_message("  per area: silhouette ring %.4g, bottom cap %.4g, lit half %.4g\n", ring,
                  bottom, importance[2] / area[2]);
    assert_true(ring > 3.0 * bottom);
    assert_true(importance[2] == 0.0);
}

static void test_sharp_shadows_outweigh_soft_ones(void **state)
{
    const imp_case *point = imp_run(&point_light), *area = imp_run(&area_light);
    double sharp = mesh_sum(point, point->r.shadow), soft = mesh_sum(area, area->r.shadow);
    print_message("  sphere shadow importance: point light %.4g, 4 x 4 area light %.4g\n", sharp,
                  soft);
    assert_true(soft > 0.0);
    assert_true(sharp > 5.0 * soft);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_unseen_without_shadow_rays),
        cmocka_unit_test(test_sphere_gets_shadow_importance),
        cmocka_unit_test(test_silhouette_ring_is_most_important),
        cmocka_unit_test(test_sharp_shadows_outweigh_soft_ones),
    };
    return DEVICE_TEST_RUN("importance_shadows", tests, NULL, imp_teardown) != 0;
}
