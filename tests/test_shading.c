/* test_shading.c — shading normals: where they come from (the loader, host/core/shapes.c), how
 * they travel (idmr/normal_packing.h) and what the kernels make of them at a hit
 * (kernels/lib/shading.h through the hit_shading_normals kernel of kernels/trace.cl).
 *
 * Host tests: the packing's angular error over many directions; a cube from an OBJ without
 * normals gets the corner directions (angle weighting does not depend on how the faces are
 * triangulated), flat under face_normals; a file's own normals are transformed as normals (by
 * the inverse transpose); the sphere's are radial.
 * Device test: on a non-uniformly scaled sphere over a flat floor, the kernel's shading normal
 * at every hit equals the host's interpolation of the mesh's normals with the hit's
 * barycentrics (turned to the geometric side), within the packing's error, and the floor's is
 * its geometric normal. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "device_test.h"
#include "mitsuba_common.h"
#include "trace_common.h"

#include "device/device_scene.h"
#include "idmr/normal_packing.h"
#include "core/shapes.h"

#define DEGREES (180.0 / M_PI)

static char temp_dir[64];

static double angle_degrees(const double a[3], const double b[3])
{
    double cross[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
    double sine = sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
    return atan2(sine, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * DEGREES;
}

static void normalise(double v[3])
{
    double length = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++)
        v[k] /= length;
}

/* Mesh m's normal at vertex v is within `degrees` of the direction `expected` (any length). */
static void assert_normal_near(const scene_mesh *m, uint32_t v, double expected[3],
                               double degrees)
{
    double n[3] = {m->normals[3 * v], m->normals[3 * v + 1], m->normals[3 * v + 2]};
    normalise(expected);
    if (!(angle_degrees(expected, n) < degrees))
        fail_msg("vertex %u: normal (%g, %g, %g) is %g degrees from (%g, %g, %g)", v, n[0], n[1],
                 n[2], angle_degrees(expected, n), expected[0], expected[1], expected[2]);
}

/* ---- packing ---- */

static void test_packing_keeps_directions_within_0_01_degrees(void **state)
{
    double worst = 0;
    for (unsigned int i = 0; i < 100000; i++) {
        idmr_rng rng = idmr_rng_init(7, 0, IDMR_STREAM_TEST, i);
        float z = 1.0f - 2.0f * idmr_rng_float(&rng), phi = 6.2831853f * idmr_rng_float(&rng);
        float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        float v[3] = {r * cosf(phi), r * sinf(phi), z}, out[3];
        idmr_unpack_unit_vector(idmr_pack_unit_vector(v[0], v[1], v[2]), out);
        double a[3] = {v[0], v[1], v[2]}, b[3] = {out[0], out[1], out[2]};
        normalise(b);
        worst = fmax(worst, angle_degrees(a, b));
    }
    assert_true(worst < 0.01);
    /* the axes come back exactly, the lower hemisphere included */
    const float axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int i = 0; i < 6; i++) {
        float out[3];
        idmr_unpack_unit_vector(idmr_pack_unit_vector(axes[i][0], axes[i][1], axes[i][2]), out);
        for (int k = 0; k < 3; k++)
            assert_float_equal(out[k], axes[i][k], 0.0f);
    }
}

/* ---- the loader ---- */

/* The unit cube [0,1]^3 as an OBJ without normals, its faces split along different
 * diagonals, wound outward. */
static const char *const cube_obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                    "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                    "f 1 3 2\nf 1 4 3\n"  /* z = 0 */
                                    "f 5 6 7\nf 5 7 8\n"  /* z = 1 */
                                    "f 1 2 6\nf 1 6 5\n"  /* y = 0 */
                                    "f 4 8 7\nf 4 7 3\n"  /* y = 1 */
                                    "f 1 5 8\nf 1 8 4\n"  /* x = 0 */
                                    "f 2 3 7\nf 2 7 6\n"; /* x = 1 */

static scene *load_shape(const char *shape_body)
{
    char xml[2048];
    snprintf(xml, sizeof xml, "<scene version=\"3.0.0\">\n%s</scene>\n", shape_body);
    return test_load_scene(write_text(temp_dir, "scene.xml", xml));
}

static void test_cube_without_normals_gets_its_corner_directions(void **state)
{
    write_text(temp_dir, "cube.obj", cube_obj);
    scene *s = load_shape("<shape type=\"obj\"><string name=\"filename\" value=\"cube.obj\"/>"
                          "<transform name=\"to_world\"><scale value=\"2, 1, 3\"/></transform>"
                          "</shape>\n");
    const scene_mesh *m = &s->meshes[0];
    assert_non_null(m->normals);
    double centre[3] = {1.0, 0.5, 1.5};
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double corner[3];
        for (int k = 0; k < 3; k++)
            corner[k] = m->positions[3 * v + k] > centre[k] ? 1.0 : -1.0;
        assert_normal_near(m, v, corner, 1e-4);
    }
    scene_free(s);
}

static void test_face_normals_shade_flat(void **state)
{
    write_text(temp_dir, "cube.obj", cube_obj);
    scene *s = load_shape("<shape type=\"obj\"><string name=\"filename\" value=\"cube.obj\"/>"
                          "<boolean name=\"face_normals\" value=\"true\"/></shape>\n");
    assert_null(s->meshes[0].normals);
    scene_free(s);
}

static void test_file_normals_transform_as_normals(void **state)
{
    /* A triangle in the plane x + z = 1 with its normal (1, 0, 1)/sqrt(2) at every vertex;
     * scaled by (2, 1, 1) the plane becomes x/2 + z = 1, normal (1/2, 0, 1) normalised. */
    write_text(temp_dir, "slope.obj",
               "v 1 0 0\nv 0 0 1\nv 1 1 0\nvn 0.7071068 0 0.7071068\n"
               "f 1//1 3//1 2//1\n");
    scene *s = load_shape("<shape type=\"obj\"><string name=\"filename\" value=\"slope.obj\"/>"
                          "<transform name=\"to_world\"><scale value=\"2, 1, 1\"/></transform>"
                          "</shape>\n");
    const scene_mesh *m = &s->meshes[0];
    assert_non_null(m->normals);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double expected[3] = {0.5, 0.0, 1.0};
        assert_normal_near(m, v, expected, 1e-4);
    }
    scene_free(s);
}

static void test_sphere_normals_are_radial(void **state)
{
    scene *s = load_shape("<shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"2\" z=\"3\"/>"
                          "<float name=\"radius\" value=\"0.5\"/></shape>\n");
    const scene_mesh *m = &s->meshes[0];
    assert_non_null(m->normals);
    const double centre[3] = {1, 2, 3};
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double radial[3];
        for (int k = 0; k < 3; k++)
            radial[k] = m->positions[3 * v + k] - centre[k];
        assert_normal_near(m, v, radial, 1e-3);
    }
    scene_free(s);
}

/* ---- the kernel ---- */

static trace_device tdev;

static int group_setup(void **state)
{
    return trace_device_open_reporting(&tdev, device_test_device());
}

static int group_teardown(void **state)
{
    trace_device_close(&tdev);
    return 0;
}

/* A coarse sphere (8 rings, 12 segments) scaled by (1, 2, 0.5), with its radial normals
 * transformed, above a flat floor without normals. */
static scene *sphere_over_floor(void)
{
    scene *s = scene_create("sphere-over-floor");
    idmr_material white = {{0.8f, 0.8f, 0.8f}, IDMR_MATERIAL_DIFFUSE, {0, 0, 0}, 0, 1, 1, -1, 0};
    uint32_t material = scene_add_material(s, "white", "diffuse", &white);
    mesh_data mesh;
    const double centre[3] = {0, 0, 0};
    shapes_sphere(centre, 1.0, 8, 12, &mesh);
    xform scale = xform_scale(1, 2, 0.5);
    shapes_transform(&mesh, &scale);
    scene_mesh *sphere = scene_add_mesh(s, "sphere", "sphere", NULL, 0, mesh.vertex_count,
                                        mesh.positions, mesh.triangle_count, mesh.indices, NULL);
    sphere->normals = mesh.normals;
    sphere->material = material;
    shapes_rectangle(&mesh);
    xform floor = xform_translate(0, 0, -1);
    xform grow = xform_scale(3, 3, 1);
    floor = xform_multiply(&floor, &grow);
    shapes_transform(&mesh, &floor);
    scene_add_mesh(s, "floor", "rectangle", NULL, 0, mesh.vertex_count, mesh.positions,
                   mesh.triangle_count, mesh.indices, mesh.texcoords)
        ->material = material;
    if (scene_finalize(s))
        fail_msg("scene_finalize: %s", error_message());
    return s;
}

/* The unit winding normal of the triangle a hit is on; *mesh gets its mesh. */
static void host_geometric_normal(const scene *s, const idmr_hit *hit, double n[3],
                                  const scene_mesh **mesh)
{
    const scene_mesh *m = &s->meshes[scene_mesh_of_triangle(s, hit->triangle)];
    const uint32_t *ix = &m->indices[3 * (size_t)(hit->triangle - m->first_triangle)];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)m->positions[3 * ix[1] + k] - m->positions[3 * ix[0] + k];
        e2[k] = (double)m->positions[3 * ix[2] + k] - m->positions[3 * ix[0] + k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    normalise(n);
    *mesh = m;
}

/* The host's shading normal at a hit: the corners' normals interpolated, normalised, turned
 * to the side of the geometric normal n; n where the mesh has none. */
static void host_shading_normal(const scene *s, const idmr_hit *hit, const double n[3],
                                double out[3])
{
    const scene_mesh *m = &s->meshes[scene_mesh_of_triangle(s, hit->triangle)];
    const uint32_t *ix = &m->indices[3 * (size_t)(hit->triangle - m->first_triangle)];
    if (!m->normals) {
        memcpy(out, n, 3 * sizeof *n);
        return;
    }
    double w[3] = {1.0 - hit->u - hit->v, hit->u, hit->v};
    for (int k = 0; k < 3; k++)
        out[k] = 0;
    for (int corner = 0; corner < 3; corner++) {
        double c[3];
        for (int k = 0; k < 3; k++)
            c[k] = m->normals[3 * ix[corner] + k];
        normalise(c);
        for (int k = 0; k < 3; k++)
            out[k] += w[corner] * c[k];
    }
    normalise(out);
    if (out[0] * n[0] + out[1] * n[1] + out[2] * n[2] < 0)
        for (int k = 0; k < 3; k++)
            out[k] = -out[k];
}

static void test_kernel_interpolates_shading_normals(void **state)
{
    scene *s = sphere_over_floor();
    trace_geometry g;
    device_scene ds;
    if (trace_geometry_upload(&tdev, s, &g) || device_scene_upload(tdev.dev, s, &g.tree, &ds))
        fail_msg("upload: %s", error_message());
    enum { RAYS = 20000 };
    idmr_ray *rays = calloc(RAYS, sizeof *rays);
    idmr_hit *hits = calloc(RAYS, sizeof *hits);
    float *normals = calloc(4 * RAYS, sizeof *normals);
    trace_random_rays(s, rays, RAYS, 3);
    assert_int_equal(trace_device_run(&tdev, &g, rays, hits, RAYS, 0, 0, NULL), 0);

    cl_kernel kernel;
    cl_mem hit_buffer, normal_buffer;
    cl_uint count = RAYS;
    assert_int_equal(device_create_kernel(tdev.program, "hit_shading_normals", &kernel), 0);
    assert_int_equal(device_buffer(tdev.dev, CL_MEM_READ_ONLY, RAYS * sizeof *hits, hits,
                                   "hits", &hit_buffer),
                     0);
    assert_int_equal(device_buffer(tdev.dev, CL_MEM_WRITE_ONLY, 4 * RAYS * sizeof *normals, NULL,
                                   "shading normals", &normal_buffer),
                     0);
    assert_int_equal(DEVICE_SET_ARGS(kernel, "hit_shading_normals", DEVICE_ARG(hit_buffer),
                                     DEVICE_ARG(count), DEVICE_ARG(ds.triangle_normals),
                                     DEVICE_ARG(ds.triangle_shading), DEVICE_ARG(normal_buffer)),
                     0);
    assert_int_equal(device_run(tdev.dev, kernel, "hit_shading_normals", RAYS, 0), 0);
    assert_int_equal(device_read(tdev.dev, normal_buffer, 4 * RAYS * sizeof *normals, normals,
                                 "shading normals"),
                     0);

    size_t sphere_hits = 0, floor_hits = 0;
    double worst = 0, sum_off_geometric = 0;
    for (size_t i = 0; i < RAYS; i++) {
        if (hits[i].triangle == IDMR_NO_HIT)
            continue;
        double geometric[3], expected[3];
        double got[3] = {normals[4 * i], normals[4 * i + 1], normals[4 * i + 2]};
        const scene_mesh *m;
        host_geometric_normal(s, &hits[i], geometric, &m);
        host_shading_normal(s, &hits[i], geometric, expected);
        worst = fmax(worst, angle_degrees(expected, got));
        if (m->normals) {
            sphere_hits++;
            sum_off_geometric += angle_degrees(geometric, got);
        } else {
            floor_hits++;
        }
    }
    assert_true(sphere_hits > 1000 && floor_hits > 1000);
    assert_true(worst < 0.02); /* three packed corners, each within 0.005 degrees */
    /* a 12-segment sphere's facets are far from its normals: the test sees interpolation */
    assert_true(sum_off_geometric / sphere_hits > 3.0);

    clReleaseKernel(kernel);
    clReleaseMemObject(hit_buffer);
    clReleaseMemObject(normal_buffer);
    free(rays);
    free(hits);
    free(normals);
    device_scene_release(&ds);
    trace_geometry_release(&g);
    scene_free(s);
}

static int make_temp(void **state)
{
    return temp_dir_make(temp_dir, "shading");
}

static int remove_temp(void **state)
{
    return temp_dir_remove(temp_dir);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_packing_keeps_directions_within_0_01_degrees),
        cmocka_unit_test_setup_teardown(test_cube_without_normals_gets_its_corner_directions,
                                        make_temp, remove_temp),
        cmocka_unit_test_setup_teardown(test_face_normals_shade_flat, make_temp, remove_temp),
        cmocka_unit_test_setup_teardown(test_file_normals_transform_as_normals, make_temp,
                                        remove_temp),
        cmocka_unit_test_setup_teardown(test_sphere_normals_are_radial, make_temp, remove_temp),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kernel_interpolates_shading_normals),
    };
    return DEVICE_TEST_MAIN("shading", host_tests, tests, group_setup, group_teardown);
}
