/* test_collapse_checking.c — the collapse engine's check of its ranking (host/reduce/collapse.c,
 * check_ranking). With the cost methods a vertex is scored by its cheapest collapse, and the
 * rules are applied only to the candidates a pass may reach, where its scoring cannot see them
 * coming; the engine promises the meshes that applying the rules to every vertex while scoring
 * gives. How far the scoring applies them is a guess from the last pass (predict_limit), so that
 * guess must not change a byte either.
 *
 * This file builds a second copy of the engine (collapse.c included, its entry points renamed)
 * whose scoring applies the rules up to a fixed cost in every pass (COLLAPSE_SCORE_RULES_FIXED):
 * to every candidate (infinity: each vertex scored with the rules, every check of the ranking
 * finds nothing to do) or to none (0: every candidate the pass reaches is checked in the
 * ranking, and those whose cheapest collapse breaks a rule move). Both must give the engine's
 * own result, triangle for triangle and collapse for collapse, on the bunny and the dragon (res
 * 2, non-manifold), with quadric and combined, and combined again with a normal per vertex (the
 * attribute quadrics), with seams (the triangles on one side of a plane given their own ids of
 * the same normals), and with locked vertices and remap distances (the ties of a later pass;
 * with importance, in four levels, ties everywhere).
 *
 * The copy also does in full what the engine shortcuts (COLLAPSE_WITHOUT_SHORTCUTS): it counts
 * the wedges a collapse removes from the triangles every time, evaluates every attribute quadric
 * afresh, and never compacts the mesh between passes, so the same comparison checks the
 * engine's per-vertex wedge counts, its per-id attribute errors and its compaction (the
 * importance method too, whose scoring the fixed cost does not change). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "decimate_common.h"
#include "reduce/collapse.h"

#define COLLAPSE_SCORE_RULES_FIXED 1
#define COLLAPSE_WITHOUT_SHORTCUTS 1
#define collapse_run collapse_run_fixed
#define collapse_memory collapse_memory_fixed
#define collapse_evaluate collapse_evaluate_fixed
#define collapse_one_fan collapse_one_fan_fixed
#include "reduce/collapse.c"
#undef collapse_run
#undef collapse_memory
#undef collapse_evaluate
#undef collapse_one_fan

/* The middle of the mesh's x extent (seams). */
static float middle_x(const mesh_data *mesh)
{
    float low = INFINITY, high = -INFINITY;
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        low = fminf(low, mesh->positions[3 * (size_t)v]);
        high = fmaxf(high, mesh->positions[3 * (size_t)v]);
    }
    return 0.5f * (low + high);
}

/* Whether triangle t's centroid lies past x = middle. */
static int past_middle(const mesh_data *mesh, uint32_t t, float middle)
{
    float centroid = 0;
    for (int k = 0; k < 3; k++)
        centroid += mesh->positions[3 * (size_t)mesh->indices[3 * (size_t)t + k]] / 3;
    return centroid > middle;
}

/* One reduction of `mesh` to a tenth: by the engine (fixed < 0) or by the copy whose scoring
 * applies the rules up to `fixed`. With normals, one attribute set per vertex (its normal); with
 * seams as well, normals holds them twice and the triangles past the middle take the second
 * copy's ids, so the vertices where the two halves meet have two. With constraints, every 29th
 * vertex locked and each a remap distance of 0 to 3. Its triangles, history and counts. */
typedef struct reduction {
    uint32_t *triangles, *history;
    collapse_result result;
} reduction;

static void reduce_once(const mesh_data *mesh, const double *importance, const float *normals,
                        int seams, int constraints, decimate_method method, float fixed,
                        reduction *out)
{
    size_t corners = 3 * (size_t)mesh->triangle_count;
    uint8_t *locked = NULL;
    uint32_t *distance = NULL;
    if (constraints) {
        locked = malloc(mesh->vertex_count + 1);
        distance = malloc(sizeof(uint32_t) * mesh->vertex_count + 1);
        for (uint32_t v = 0; v < mesh->vertex_count; v++) {
            locked[v] = v % 29 == 0;
            distance[v] = (v * 2654435761u) >> 30;
        }
    }
    out->triangles = malloc(sizeof(uint32_t) * corners + 1);
    memcpy(out->triangles, mesh->indices, sizeof(uint32_t) * corners);
    uint32_t *ids = NULL;
    collapse_mesh m = {.vertex_count = mesh->vertex_count,
                       .positions = mesh->positions,
                       .triangle_count = mesh->triangle_count,
                       .triangles = out->triangles,
                       .importance = importance,
                       .locked = locked,
                       .distance = distance};
    if (normals) {
        ids = malloc(sizeof(uint32_t) * corners + 1);
        memcpy(ids, mesh->indices, sizeof(uint32_t) * corners);
        float middle = seams ? middle_x(mesh) : 0;
        for (uint32_t t = 0; seams && t < mesh->triangle_count; t++)
            if (past_middle(mesh, t, middle))
                for (int k = 0; k < 3; k++)
                    ids[3 * (size_t)t + k] += mesh->vertex_count;
        m.corner_ids = ids;
        m.attributes = normals;
        m.attribute_count = (seams ? 2 : 1) * mesh->vertex_count;
        m.normal_floats = 3;
    }
    collapse_options o = {.method = method,
                          .target_vertices = mesh->vertex_count / 10,
                          .max_normal_angle = 60,
                          .boundary_tolerance = DECIMATE_BOUNDARY_TOLERANCE,
                          .uv_weight = DECIMATE_UV_WEIGHT,
                          .normal_weight = DECIMATE_NORMAL_WEIGHT,
                          .threads = 2};
    out->history = malloc(sizeof(uint32_t) * mesh->vertex_count + 1);
    out->result = (collapse_result){.collapsed_into = out->history};
    collapse_score_rules_fixed = fixed;
    int status = fixed < 0 ? collapse_run(&m, &o, &out->result)
                           : collapse_run_fixed(&m, &o, &out->result);
    assert_int_equal(status, 0);
    free(ids);
    free(locked);
    free(distance);
}

static void reduction_free(reduction *r)
{
    free(r->triangles);
    free(r->history);
}

/* The cases compared: a method, and what the mesh carries beside its positions. */
typedef struct checked_case {
    decimate_method method;
    int normals, seams, constraints;
    int tied; /* the importance in four levels: ties everywhere, broken by the distances */
    const char *name;
} checked_case;

static const checked_case checked_cases[] = {
    {DECIMATE_QUADRIC, 0, 0, 0, 0, "quadric"},
    {DECIMATE_COMBINED, 0, 0, 0, 0, "combined"},
    {DECIMATE_COMBINED, 1, 0, 0, 0, "combined with normals"},
    {DECIMATE_COMBINED, 1, 1, 0, 0, "combined with normals and seams"},
    {DECIMATE_IMPORTANCE, 0, 0, 0, 0, "importance"},
    {DECIMATE_COMBINED, 0, 0, 1, 0, "combined with locks and distances"},
    {DECIMATE_IMPORTANCE, 0, 0, 1, 1, "importance in four levels, with locks and distances"},
};

static void same_as_engine(const char *file)
{
    mesh_data mesh;
    read_model(file, &mesh);
    double *importance = random_importance(mesh.vertex_count, 7);
    double *levels = malloc(sizeof(double) * (mesh.vertex_count + 1));
    for (uint32_t v = 0; v < mesh.vertex_count; v++)
        levels[v] = floor(4 * importance[v]);
    float *normals = smooth_normals(&mesh);
    size_t normal_floats = 3 * (size_t)mesh.vertex_count;
    float *twice = malloc(2 * sizeof(float) * normal_floats);
    memcpy(twice, normals, sizeof(float) * normal_floats);
    memcpy(twice + normal_floats, normals, sizeof(float) * normal_floats);
    const float fixed[2] = {INFINITY, 0};
    for (size_t i = 0; i < sizeof checked_cases / sizeof *checked_cases; i++) {
        const checked_case *c = &checked_cases[i];
        const float *with = c->seams ? twice : c->normals ? normals : NULL;
        const double *by = c->tied ? levels : importance;
        reduction own;
        reduce_once(&mesh, by, with, c->seams, c->constraints, c->method, -1, &own);
        assert_true(own.result.collapses > 0);
        for (int k = 0; k < 2; k++) {
            reduction copy;
            reduce_once(&mesh, by, with, c->seams, c->constraints, c->method, fixed[k], &copy);
            assert_int_equal(copy.result.collapses, own.result.collapses);
            assert_int_equal(copy.result.passes, own.result.passes);
            assert_int_equal(copy.result.vertices_after, own.result.vertices_after);
            assert_memory_equal(copy.triangles, own.triangles,
                                3 * sizeof(uint32_t) * mesh.triangle_count);
            assert_memory_equal(copy.history, own.history,
                                sizeof(uint32_t) * mesh.vertex_count);
            reduction_free(&copy);
        }
        print_message("  %s, %s: %u collapses in %u passes, the same with the rules applied "
                      "while scoring and with none\n",
                      file, c->name, own.result.collapses, own.result.passes);
        reduction_free(&own);
    }
    free(twice);
    free(normals);
    free(levels);
    free(importance);
    mesh_data_free(&mesh);
}

static void test_bunny(void **state) { same_as_engine("bunny.ply"); }

static void test_dragon(void **state) { same_as_engine("dragon_vrip_res2.ply"); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bunny),
        cmocka_unit_test(test_dragon),
    };
    return cmocka_run_group_tests_name("collapse_checking", tests, NULL, NULL);
}
