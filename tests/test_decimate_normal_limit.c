/* test_decimate_normal_limit.c — the normal-limit module of the decimation bridge
 * (host/reduce/decimate_modules.hh), with the importance module and with OpenMesh's quadric one.
 * One case a test; the helpers are in decimate_common.h.
 *
 *   spike        a spike whose every collapse turns faces by ~72-77 degrees: rejected at 60, done
 *                at 179; the quadric method cannot remove it at 60 either
 *   each collapse on a sphere, collapse by collapse (decimating to n - k and to n - k - 1 differ
 *                by one collapse), no changed face turns by more than the limit or degenerates
 *   spheres      decimated by importance, inward faces are reported (turns add up over
 *                collapses); the quadric method keeps every face of a sphere outward */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "core/shapes.h"

/* ---- spike ---- */

/* A 5 x 5 grid with its centre (2,2) raised to z = 3: the six faces around it are tilted by
 * atan(3 / d) from +z, d in {1, 1/√2} the distance of their base edge from the centre, so 71.6
 * or 76.7 degrees. Collapsing the spike into any neighbour lays its four remaining faces flat
 * (normal +z, none degenerate: no three hexagon corners are collinear): illegal at 60 degrees,
 * legal at 179. Importance 0 at the spike, 1..6 on its ring, 50 elsewhere: the spike has the
 * least ring sum (21; every other vertex has more than 150). */
enum { SPIKE = 12 };
/* (3,2) (3,3) (2,3) (1,2) (1,1) (2,1) */
static const uint32_t spike_ring[6] = {13, 18, 17, 11, 6, 7};

/* The spike grid decimated by one vertex with the normal limit max_angle. */
static void decimate_spike(double max_angle, decimate_output *out)
{
    mesh_data spike;
    make_grid(5, 3.0, &spike);
    double importance[25];
    for (int v = 0; v < 25; v++)
        importance[v] = 50;
    importance[SPIKE] = 0;
    for (int k = 0; k < 6; k++)
        importance[spike_ring[k]] = 1 + k;
    decimate_input in = input_of("spike", &spike, importance, 24);
    in.max_normal_angle = max_angle;
    assert_int_equal(decimate_mesh(&in, DECIMATE_IMPORTANCE, out), 0);
    assert_int_equal(out->collapses, 1);
    mesh_data_free(&spike);
}

static void test_normal_limit_spike_allowed(void **state)
{
    decimate_output out;
    decimate_spike(179, &out);
    assert_int_equal(out.collapsed_into[SPIKE], spike_ring[0]);
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++)
        assert_true(out.mesh.positions[3 * v + 2] == 0.0f); /* the spike is gone */
    decimate_output_free(&out);
}

/* At 60 degrees another vertex goes; the spike stays. */
static void test_normal_limit_spike_rejected(void **state)
{
    decimate_output out;
    decimate_spike(60, &out);
    assert_int_equal(out.mesh.vertex_count, 24);
    assert_int_equal(out.collapsed_into[SPIKE], SPIKE);
    int spike_kept = 0;
    for (uint32_t v = 0; v < out.mesh.vertex_count; v++)
        spike_kept += out.mesh.positions[3 * v + 2] == 3.0f;
    assert_int_equal(spike_kept, 1);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);
}

/* ---- spheres and each collapse ---- */

/* A sphere decimated to `fraction`: closed genus 0 (F = 2V - 4), no degenerate face, a complete
 * history; returns how many faces point towards the centre
 * (dot(normal, centroid - centre) <= 0). */
static const double sphere_centre[3] = {0.3, -0.2, 0.1};

static uint32_t check_sphere(decimate_method method, double fraction)
{
    mesh_data sphere;
    shapes_sphere(sphere_centre, 1.5, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, &sphere);
    double *importance = random_importance(sphere.vertex_count, 3);
    uint64_t target = (uint64_t)(fraction * sphere.vertex_count);
    decimate_input in = input_of("sphere", &sphere, importance, target);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, method, &out), 0);
    assert_int_equal(out.mesh.vertex_count, target);
    assert_int_equal(out.mesh.triangle_count, 2 * target - 4);
    check_indices(&out.mesh);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    uint32_t inward = 0;
    for (uint32_t t = 0; t < out.mesh.triangle_count; t++) {
        double n[3], c[3] = {0, 0, 0};
        face_normal(&out.mesh, t, n);
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                c[j] += out.mesh.positions[3 * (size_t)out.mesh.indices[3 * t + k] + j] / 3.0;
        double dot = 0;
        for (int j = 0; j < 3; j++)
            dot += n[j] * (c[j] - sphere_centre[j]);
        inward += !(dot > 0);
    }
    print_message("  sphere %s to %llu of %u vertices: %u faces, %u facing inward\n",
                  method == DECIMATE_IMPORTANCE ? "importance" : "quadric",
                  (unsigned long long)target, sphere.vertex_count, out.mesh.triangle_count, inward);
    check_history(&out);
    check_survivor_positions(&in, &out);
    decimate_output_free(&out);
    free(importance);
    mesh_data_free(&sphere);
    return inward;
}

/* Faces as triples of input indices, rotated so the least comes first (winding kept), sorted. */
typedef struct position_index {
    float p[3];
    uint32_t index;
} position_index;

static int compare_position_index(const void *a, const void *b)
{
    const position_index *x = a, *y = b;
    return memcmp(x->p, y->p, sizeof x->p);
}

static int compare_face(const void *a, const void *b)
{
    const uint32_t *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

static void face_key(const uint32_t in[3], uint32_t out[3])
{
    int first = in[0] < in[1] ? (in[0] < in[2] ? 0 : 2) : (in[1] < in[2] ? 1 : 2);
    for (int k = 0; k < 3; k++)
        out[k] = in[(first + k) % 3];
}

/* The output's faces in input indices (the input has distinct positions). */
static uint32_t *faces_in_input_indices(const mesh_data *out, const position_index *sorted,
                                        uint32_t count)
{
    uint32_t *faces = malloc(sizeof(uint32_t) * 3 * (out->triangle_count + 1));
    for (uint32_t t = 0; t < out->triangle_count; t++) {
        uint32_t ix[3];
        for (int k = 0; k < 3; k++) {
            position_index key;
            memcpy(key.p, &out->positions[3 * (size_t)out->indices[3 * t + k]], sizeof key.p);
            const position_index *found =
                bsearch(&key, sorted, count, sizeof *sorted, compare_position_index);
            assert_non_null(found);
            ix[k] = found->index;
        }
        face_key(ix, &faces[3 * (size_t)t]);
    }
    qsort(faces, out->triangle_count, 3 * sizeof(uint32_t), compare_face);
    return faces;
}

/* The input's positions sorted, with their indices; the positions must be distinct. */
static position_index *sorted_positions(const mesh_data *m)
{
    position_index *sorted = malloc(sizeof *sorted * m->vertex_count);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        memcpy(sorted[v].p, &m->positions[3 * (size_t)v], sizeof sorted[v].p);
        sorted[v].index = v;
    }
    qsort(sorted, m->vertex_count, sizeof *sorted, compare_position_index);
    for (uint32_t v = 1; v < m->vertex_count; v++)
        assert_true(compare_position_index(&sorted[v - 1], &sorted[v]) != 0);
    return sorted;
}

/* The one vertex whose collapse is in `current` but not in `previous` (a survivor there). */
static uint32_t extra_collapse(const decimate_output *previous, const decimate_output *current,
                               uint32_t vertex_count)
{
    uint32_t removed = UINT32_MAX;
    for (uint32_t v = 0; v < vertex_count; v++)
        if (current->collapsed_into[v] != previous->collapsed_into[v]) {
            assert_int_equal(previous->collapsed_into[v], v);
            assert_int_equal(removed, UINT32_MAX); /* one collapse more */
            removed = v;
        }
    assert_true(removed != UINT32_MAX);
    return removed;
}

/* One step of the collapse-by-collapse check, in input indices. */
typedef struct collapse_step {
    const mesh_data *input;
    uint32_t removed, kept;
    const uint32_t *previous_faces; /* face keys of the output one collapse earlier, sorted */
    uint32_t previous_count;
    double max_angle, min_cos; /* the limit in degrees, and its cosine */
} collapse_step;

/* Face f (input indices) of the output after the step, absent before it: it holds the kept
 * vertex, the same face with the removed vertex was there before, it is not degenerate and it
 * turned by at most the limit. Returns the turn in degrees (0 if it was degenerate before). */
static double check_moved_face(const collapse_step *step, const uint32_t f[3], uint32_t k)
{
    uint32_t before[3], key[3];
    int corner = -1;
    for (int c = 0; c < 3; c++) {
        before[c] = f[c] == step->kept ? step->removed : f[c];
        if (f[c] == step->kept)
            corner = c;
    }
    assert_true(corner >= 0); /* a changed face holds the kept vertex */
    face_key(before, key);
    assert_non_null(bsearch(key, step->previous_faces, step->previous_count, 3 * sizeof(uint32_t),
                            compare_face));
    double a[3], b[3];
    mesh_data one = {step->input->vertex_count, 1, step->input->positions, (uint32_t *)f, NULL, NULL, 0};
    face_normal(&one, 0, a);
    one.indices = before;
    face_normal(&one, 0, b);
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    assert_true(la > 0);
    if (!(lb > 0))
        return 0;
    double angle = acos(fmax(-1.0, fmin(1.0, dot / (la * lb)))) * 180.0 / M_PI;
    if (!(dot >= step->min_cos * la * lb * (1 - 1e-12)))
        fail_msg("collapse %u (%u into %u) turns a face by %.3f degrees (limit %g)", k,
                 step->removed, step->kept, angle, step->max_angle);
    return angle;
}

/* The normal limit, collapse by collapse: decimating to n - k - 1 vertices does the collapses of
 * n - k and one more (the loop is deterministic). Each face the extra collapse changed (the
 * kept vertex in place of the removed one) may turn by at most max_angle degrees and may not be
 * degenerate; every other face is unchanged; two faces go. */
static void check_each_collapse(const mesh_data *m, const double *importance,
                                decimate_method method, double max_angle, uint32_t steps)
{
    position_index *sorted = sorted_positions(m);
    collapse_step step = {m, 0, 0, NULL, 0, max_angle, cos(max_angle * M_PI / 180.0)};
    double worst = 0;
    decimate_input in = input_of("steps", m, importance, m->vertex_count);
    in.max_normal_angle = max_angle;
    decimate_output previous, current;
    assert_int_equal(decimate_mesh(&in, method, &previous), 0);
    uint32_t *previous_faces = faces_in_input_indices(&previous.mesh, sorted, m->vertex_count);
    uint32_t moved_faces = 0;
    for (uint32_t k = 0; k < steps; k++) {
        in.target_vertices = m->vertex_count - k - 1;
        assert_int_equal(decimate_mesh(&in, method, &current), 0);
        assert_int_equal(current.collapses, k + 1);
        assert_int_equal(current.mesh.triangle_count + 2, previous.mesh.triangle_count);
        step.removed = extra_collapse(&previous, &current, m->vertex_count);
        step.kept = current.collapsed_into[step.removed];
        step.previous_faces = previous_faces;
        step.previous_count = previous.mesh.triangle_count;
        uint32_t *faces = faces_in_input_indices(&current.mesh, sorted, m->vertex_count);
        for (uint32_t t = 0; t < current.mesh.triangle_count; t++) {
            const uint32_t *f = &faces[3 * (size_t)t];
            if (bsearch(f, previous_faces, previous.mesh.triangle_count, 3 * sizeof(uint32_t),
                        compare_face))
                continue;
            worst = fmax(worst, check_moved_face(&step, f, k + 1));
            moved_faces++;
        }
        decimate_output_free(&previous);
        free(previous_faces);
        previous = current;
        previous_faces = faces;
    }
    print_message("  %u collapses one by one (%s, limit %g): %u moved faces, largest turn %.2f "
                  "degrees\n",
                  steps, method == DECIMATE_IMPORTANCE ? "importance" : "quadric", max_angle,
                  moved_faces, worst);
    assert_true(moved_faces > 0);
    decimate_output_free(&previous);
    free(previous_faces);
    free(sorted);
}

/* The normal limit bounds each collapse (paper 3.4: "prohibits collapses that lead to a rotation
 * of triangle normals of more than a given angle"), at 60 and at 20 degrees. */
static void test_normal_limit_each_collapse(void **state)
{
    mesh_data sphere;
    shapes_sphere(sphere_centre, 1.5, 16, 24, &sphere);
    double *importance = random_importance(sphere.vertex_count, 3);
    check_each_collapse(&sphere, importance, DECIMATE_IMPORTANCE, 60, sphere.vertex_count * 4 / 5);
    check_each_collapse(&sphere, importance, DECIMATE_IMPORTANCE, 20, sphere.vertex_count / 2);
    free(importance);
    mesh_data_free(&sphere);
}

/* On a sphere decimated by importance alone the turns add up over collapses, so faces facing
 * inward are reported, not forbidden (the quadric method, which follows the geometry, must keep
 * them all outward: test_quadric_sphere_outward). */
static void test_importance_sphere(void **state)
{
    check_sphere(DECIMATE_IMPORTANCE, 0.2);
    check_sphere(DECIMATE_IMPORTANCE, 0.05);
}

/* ---- quadric ---- */

static void test_quadric_sphere_outward(void **state)
{
    assert_int_equal(check_sphere(DECIMATE_QUADRIC, 0.2), 0);
    assert_int_equal(check_sphere(DECIMATE_QUADRIC, 0.05), 0);
}

static void test_quadric_each_collapse(void **state)
{
    mesh_data sphere;
    shapes_sphere(sphere_centre, 1.5, 12, 16, &sphere);
    check_each_collapse(&sphere, NULL, DECIMATE_QUADRIC, 60, sphere.vertex_count - 20);
    mesh_data_free(&sphere);
}

/* The normal limit binds the quadric method too: the spike cannot go at 60 degrees even when
 * everything else has gone that can. */
static void test_quadric_spike(void **state)
{
    mesh_data spike;
    make_grid(5, 3.0, &spike);
    decimate_input in = input_of("spike", &spike, NULL, 1);
    decimate_output out;
    assert_int_equal(decimate_mesh(&in, DECIMATE_QUADRIC, &out), 0);
    assert_int_equal(out.collapsed_into[SPIKE], SPIKE);
    assert_int_equal(degenerate_faces(&out.mesh), 0);
    decimate_output_free(&out);
    mesh_data_free(&spike);
}

/* A flat 9 x 9 grid turned into a tilted plane: in floats its faces' normals differ by
 * rounding, so the normal check sees dot products a hair above or below |a||b|. A limit of
 * 0.01° (far above that rounding, far below any real turn) must let every method reach what it
 * reaches with no limit (179°): the plane never turns. */
static void test_normal_limit_tilted_plane_rounding(void **state)
{
    mesh_data plane;
    make_grid(9, 0.0, &plane);
    const double a = 0.37, b = 1.13; /* about x, then about z */
    for (uint32_t v = 0; v < plane.vertex_count; v++) {
        float *p = &plane.positions[3 * v];
        double x = p[0], y = p[1] * cos(a), z = p[1] * sin(a);
        p[0] = (float)(x * cos(b) - y * sin(b));
        p[1] = (float)(x * sin(b) + y * cos(b));
        p[2] = (float)z;
    }
    double importance[81];
    for (int v = 0; v < 81; v++)
        importance[v] = 1.0 + (v % 7);
    const decimate_method methods[] = {DECIMATE_IMPORTANCE, DECIMATE_QUADRIC, DECIMATE_COMBINED};
    for (size_t m = 0; m < 3; m++) {
        uint32_t reached[2];
        const double limits[2] = {179.0, 0.01};
        for (int l = 0; l < 2; l++) {
            decimate_output out;
            decimate_input in = input_of("tilted", &plane, importance, 20);
            in.max_normal_angle = limits[l];
            assert_int_equal(decimate_mesh(&in, methods[m], &out), 0);
            reached[l] = out.mesh.vertex_count;
            assert_int_equal(degenerate_faces(&out.mesh), 0);
            decimate_output_free(&out);
        }
        print_message("  method %zu: %u vertices at 179°, %u at 0.01°\n", m, reached[0],
                      reached[1]);
        assert_int_equal(reached[1], reached[0]);
        assert_true(reached[0] < 81);
    }
    mesh_data_free(&plane);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normal_limit_spike_allowed),
        cmocka_unit_test(test_normal_limit_spike_rejected),
        cmocka_unit_test(test_normal_limit_each_collapse),
        cmocka_unit_test(test_importance_sphere),
        cmocka_unit_test(test_quadric_sphere_outward),
        cmocka_unit_test(test_quadric_each_collapse),
        cmocka_unit_test(test_quadric_spike),
        cmocka_unit_test(test_normal_limit_tilted_plane_rounding),
    };
    return cmocka_run_group_tests_name("decimate_normal_limit", tests, NULL, NULL);
}
