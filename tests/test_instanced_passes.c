/* test_instanced_passes.c — the passes on the two-level BVH (host/device/bvh.h,
 * kernels/lib/surface.h): an instanced scene is simulated as the same scene written flat is,
 * while the device holds each prototype once. The scenes: instanced_cornell.h (the Cornell box's
 * knot placed three times, one copy turned, one mirrored with a non-uniform scale).
 *
 *   two-level BVH   bvh_build() gives the instanced scene a top level over four instances (the
 *                   meshes that are not instanced, and the knot's three copies of one
 *                   prototype), leaf lanes with scene-global triangle numbers, every knot
 *                   triangle stored once; the flat scene keeps its flat BVH
 *   device bytes    the instanced scene's device memory (geometry, BVH) is below the flat
 *                   scene's: the per-triangle buffers hold the knot once (exactly two knots'
 *                   triangles fewer), its BVH once
 *   render          the same seed renders the same image: the RMSE between the two is below a
 *                   tenth of the RMSE between two seeds of the flat scene (the Monte Carlo
 *                   error), and every channel's mean agrees within 0.5 %; so do the two with
 *                   the whole scene scaled by 1e4 and by 1e-3, and the instanced one with its
 *                   unscaled image
 *   importance      camera, light and shadow importance per mesh (the knot's prototype against
 *                   the sum of its three flat copies) agree within 1 %, and per knot triangle
 *                   the summed L1 difference is below half the one between two seeds */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "device/device_scene.h"
#include "instanced_cornell.h"
#include "test_support.h"

/* The two scenes, loaded and finalised (scene_load finalises), in a fresh directory. */
typedef struct scene_pair {
    char dir[64];
    scene *instanced, *flat;
} scene_pair;

static scene_pair pair;

static int group_setup(void **state)
{
    char path[4200];
    snprintf(pair.dir, sizeof pair.dir, "/tmp/idmr-instanced-XXXXXX");
    test_make_directory(pair.dir);
    if (instanced_cornell_write(pair.dir, 0, 1.0, path, sizeof path))
        return -1;
    pair.instanced = test_load_scene(path);
    if (instanced_cornell_write(pair.dir, 1, 1.0, path, sizeof path))
        return -1;
    pair.flat = test_load_scene(path);
    return 0;
}

static int group_teardown(void **state)
{
    scene_free(pair.instanced);
    scene_free(pair.flat);
    test_remove_directory(pair.dir);
    return 0;
}

/* The knot's representative in the instanced scene, and its copy k in the flat one. */
static const scene_mesh *instanced_knot(void) { return test_find_mesh(pair.instanced, "seen/knot"); }

static const scene_mesh *flat_knot(int k)
{
    char name[64];
    snprintf(name, sizeof name, "%s_knot", instanced_cornell_copies[k]);
    return test_find_mesh(pair.flat, name);
}

static void test_two_level_bvh(void **state)
{
    const scene *s = pair.instanced;
    assert_true(s->features & IDMR_FEATURE_INSTANCES);
    assert_false(pair.flat->features & IDMR_FEATURE_INSTANCES);
    const scene_mesh *knot = instanced_knot();
    assert_int_equal(s->triangle_count + 2 * (uint64_t)knot->triangle_count,
                     pair.flat->triangle_count);
    bvh b, flat;
    test_build_bvh(s, &b);
    test_build_bvh(pair.flat, &flat);
    assert_null(flat.top_nodes);
    assert_int_equal(flat.instance_count, 0);
    assert_non_null(b.top_nodes);
    assert_int_equal(b.instance_count, 4); /* the box's own meshes, three knots */
    assert_int_equal(b.instances[1].prototype, b.instances[2].prototype);
    assert_int_equal(b.instances[1].prototype, b.instances[3].prototype);
    assert_int_equal(b.instances[1].node_offset, b.instances[3].node_offset);
    /* the mirrored copy's world-to-object transform reverses orientation */
    const float *w = b.instances[3].world_to_object;
    double det = w[0] * ((double)w[5] * w[10] - (double)w[6] * w[9]) -
                 w[1] * ((double)w[4] * w[10] - (double)w[6] * w[8]) +
                 w[2] * ((double)w[4] * w[9] - (double)w[5] * w[8]);
    assert_true(det < 0);
    assert_true(fabsf(b.instances[1].offset_scale - 1.0f) < 1e-6f);
    /* leaf lanes: scene-global triangles, every knot triangle stored (once per prototype) */
    uint8_t *seen = calloc(s->triangle_count, 1);
    for (size_t l = 0; l < b.leaf_count; l++)
        for (int lane = 0; lane < 4; lane++) {
            uint32_t t = b.leaves[l].triangle[lane];
            if (t == IDMR_BVH_NO_TRIANGLE)
                continue;
            assert_true(t < s->triangle_count);
            seen[t] = 1;
        }
    size_t knot_seen = 0;
    for (uint32_t t = 0; t < knot->triangle_count; t++)
        knot_seen += seen[knot->first_triangle + t];
    assert_int_equal(knot_seen + b.degenerate_count, knot->triangle_count);
    free(seen);
    print_message("  instanced BVH %.2f MiB (%zu top nodes, %zu instances), flat %.2f MiB\n",
                  bvh_device_bytes(&b) / 1048576.0, b.top_node_count, b.instance_count,
                  bvh_device_bytes(&flat) / 1048576.0);
    assert_true(bvh_device_bytes(&b) < bvh_device_bytes(&flat) / 2);
    bvh_free(&b);
    bvh_free(&flat);
}

static void test_device_bytes(void **state)
{
    render_options o;
    test_render_options(&o, 1, 1000);
    o.sppm.resolution = 0.25f;
    render_result a, b;
    test_run_render(pair.instanced, NULL, &o, &a);
    test_run_render(pair.flat, NULL, &o, &b);
    /* per triangle: a float4 normal, a uint4 of shading normals, a material index */
    uint64_t per_triangle = 4 * sizeof(float) + 4 * sizeof(uint32_t) + sizeof(uint32_t);
    print_message("  device: instanced geometry %.2f MiB + BVH %.2f MiB, flat %.2f + %.2f MiB\n",
                  a.sppm.geometry_bytes / 1048576.0, a.sppm.bvh_bytes / 1048576.0,
                  b.sppm.geometry_bytes / 1048576.0, b.sppm.bvh_bytes / 1048576.0);
    assert_int_equal(b.sppm.geometry_bytes - a.sppm.geometry_bytes,
                     2 * (uint64_t)instanced_knot()->triangle_count * per_triangle);
    assert_int_equal(a.sppm.geometry_bytes, device_scene_geometry_bytes(pair.instanced));
    assert_true(a.sppm.bvh_bytes < b.sppm.bvh_bytes / 2);
    assert_true(a.sppm.geometry_bytes + a.sppm.bvh_bytes <
                (b.sppm.geometry_bytes + b.sppm.bvh_bytes) / 2);
    render_result_free(&a);
    render_result_free(&b);
}

static double image_rmse(const render_result *a, const render_result *b)
{
    size_t n = 3 * (size_t)a->sppm.width * a->sppm.height;
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        sum += ((double)a->image[i] - b->image[i]) * ((double)a->image[i] - b->image[i]);
    return sqrt(sum / (double)n);
}

static double channel_mean(const render_result *r, int c)
{
    size_t pixels = (size_t)r->sppm.width * r->sppm.height;
    double sum = 0;
    for (size_t p = 0; p < pixels; p++)
        sum += r->image[3 * p + c];
    return sum / (double)pixels;
}

/* The scenes scaled by `scale` as a whole, loaded (the caller frees them). */
static void load_scaled(double scale, scene **instanced, scene **flat)
{
    char path[4200];
    assert_int_equal(instanced_cornell_write(pair.dir, 0, scale, path, sizeof path), 0);
    *instanced = test_load_scene(path);
    assert_int_equal(instanced_cornell_write(pair.dir, 1, scale, path, sizeof path), 0);
    *flat = test_load_scene(path);
}

static void test_render_as_flattened(void **state)
{
    render_options o;
    test_render_options(&o, 4, 100000);
    o.sppm.resolution = 0.5f;
    render_result instanced, flat, flat_seed2;
    test_run_render(pair.instanced, NULL, &o, &instanced);
    test_run_render(pair.flat, NULL, &o, &flat);
    o.sppm.seed = 2;
    test_run_render(pair.flat, NULL, &o, &flat_seed2);
    double difference = image_rmse(&instanced, &flat), noise = image_rmse(&flat, &flat_seed2);
    print_message("  RMSE instanced/flat %.3g, flat seed 1/seed 2 %.3g\n", difference, noise);
    assert_true(noise > 0 && difference < 0.1 * noise);
    for (int c = 0; c < 3; c++) {
        double x = channel_mean(&instanced, c), y = channel_mean(&flat, c);
        print_message("  channel %d mean: instanced %.6g, flat %.6g\n", c, x, y);
        assert_true(fabs(x - y) <= 0.005 * y);
    }
    /* Far from the unit scale (ray offsets, the normals' transform, the move into object
     * space): the same agreement, against the same noise (the image does not change). */
    const double scales[2] = {1e4, 1e-3};
    o.sppm.seed = 1;
    for (int k = 0; k < 2; k++) {
        scene *a, *b;
        load_scaled(scales[k], &a, &b);
        render_result ra, rb;
        test_run_render(a, NULL, &o, &ra);
        test_run_render(b, NULL, &o, &rb);
        double scaled = image_rmse(&ra, &rb), moved = image_rmse(&ra, &instanced);
        print_message("  scale %g: RMSE instanced/flat %.3g, instanced/unscaled %.3g\n",
                      scales[k], scaled, moved);
        assert_true(scaled < 0.1 * noise && moved < 0.1 * noise);
        render_result_free(&ra);
        render_result_free(&rb);
        scene_free(a);
        scene_free(b);
    }
    render_result_free(&instanced);
    render_result_free(&flat);
    render_result_free(&flat_seed2);
}

/* Σ over mesh m's triangles of a per-triangle sum. */
static double mesh_sum(const scene_mesh *m, const double *per_triangle)
{
    double sum = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        sum += per_triangle[m->first_triangle + t];
    return sum;
}

/* Knot triangle t's sum in the flat scene: its three copies'. */
static double flat_knot_triangle(const double *per_triangle, uint32_t t)
{
    double sum = 0;
    for (int k = 0; k < INSTANCED_CORNELL_COPIES; k++)
        sum += per_triangle[flat_knot(k)->first_triangle + t];
    return sum;
}

static void test_importance_as_flattened(void **state)
{
    importance_options o;
    test_importance_options(&o, 4, 100000);
    o.sppm.resolution = 0.5f;
    importance_result instanced, flat, flat_seed2;
    test_run_importance(pair.instanced, NULL, &o, &instanced);
    test_run_importance(pair.flat, NULL, &o, &flat);
    o.sppm.seed = 2;
    test_run_importance(pair.flat, NULL, &o, &flat_seed2);
    const char *kinds[3] = {"camera", "light", "shadow"};
    const double *a[3] = {instanced.camera, instanced.light, instanced.shadow};
    const double *b[3] = {flat.camera, flat.light, flat.shadow};
    const double *c[3] = {flat_seed2.camera, flat_seed2.light, flat_seed2.shadow};
    const scene_mesh *knot = instanced_knot();
    for (int k = 0; k < 3; k++) {
        /* every mesh but the knot one to one, then the knot's prototype against its copies */
        for (size_t m = 0; m < pair.instanced->mesh_count; m++) {
            const scene_mesh *mesh = &pair.instanced->meshes[m];
            if (mesh->instanced)
                continue;
            double x = mesh_sum(mesh, a[k]), y = mesh_sum(test_find_mesh(pair.flat, mesh->name), b[k]);
            assert_true(fabs(x - y) <= 0.01 * fmax(x, y) + 1e-9);
        }
        double x = mesh_sum(knot, a[k]), y = 0;
        for (int copy = 0; copy < INSTANCED_CORNELL_COPIES; copy++)
            y += mesh_sum(flat_knot(copy), b[k]);
        double l1 = 0, l1_seeds = 0;
        for (uint32_t t = 0; t < knot->triangle_count; t++) {
            double flat_t = flat_knot_triangle(b[k], t);
            l1 += fabs(a[k][knot->first_triangle + t] - flat_t);
            l1_seeds += fabs(flat_knot_triangle(c[k], t) - flat_t);
        }
        print_message("  knot %s: instanced %.6g, flat %.6g; per triangle L1 %.4g, between seeds "
                      "%.4g\n", kinds[k], x, y, l1, l1_seeds);
        assert_true(x > 0 && fabs(x - y) <= 0.01 * fmax(x, y));
        assert_true(l1 < 0.5 * l1_seeds);
    }
    importance_result_free(&instanced);
    importance_result_free(&flat);
    importance_result_free(&flat_seed2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_level_bvh),
        cmocka_unit_test(test_device_bytes),
        cmocka_unit_test(test_render_as_flattened),
        cmocka_unit_test(test_importance_as_flattened),
    };
    return DEVICE_TEST_RUN("instanced passes", tests, group_setup, group_teardown) != 0;
}
