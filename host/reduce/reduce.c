/* reduce.c — the reduction pipeline behind `idmr reduce` (see reduce.h): reduce_run() runs its
 * stages in order over one reduce_state (reduce_stages.h lists them and what each leaves in the
 * state); this file holds the pipeline and the option, importance, budget and writing stages. */
#include "reduce/reduce.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/json.h"
#include "core/progress.h"
#include "io/mesh_io.h"
#include "io/mitsuba_write.h"
#include "passes/importance_outputs.h"
#include "reduce/reduce_stages.h"

/* ---- stages ---- */

/* --target in (0, 1]; every --keep name is a mesh of the scene. */
static int check_options(const reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    if (!(o->target > 0 && o->target <= 1))
        return error_set(IDMR_EXIT_INPUT, "--target must be in (0, 1], not %g", o->target);
    for (size_t k = 0; k < o->keep_count; k++) {
        size_t m = 0;
        while (m < s->mesh_count && strcmp(s->meshes[m].name, o->keep[k]))
            m++;
        if (m == s->mesh_count)
            return error_set(IDMR_EXIT_INPUT, "--keep %s: the scene has no mesh of that name "
                                              "(see `idmr info`)", o->keep[k]);
    }
    return 0;
}

/* Method importance: the importance pass (on a BVH built for it), and each mesh's per-vertex
 * importance, computed once for the decimation and the importance outputs. */
static int run_importance(reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    double start = monotonic_seconds();
    int status = 0;
    if (reduce_method_uses_importance(o->method)) {
        importance_weights weights = importance_weights_of(&o->importance);
        bvh b;
        status = bvh_build(s, &b);
        if (!status) {
            status = importance_run(st->device, s, &b, &o->importance, &st->importance);
            bvh_free(&b);
        }
        if (!status)
            st->vertex_importance = importance_vertex_values(&st->importance, s, &weights);
    }
    st->seconds_importance = monotonic_seconds() - start;
    return status;
}

/* What mesh m is decimated from: the scene's mesh, its texture coordinates, its normals where
 * they are its file's own and not flat (computed ones are not written: the reader of the output
 * computes them again; flat ones become face_normals), and its per-vertex importance. */
static decimate_input decimation_input(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    decimate_input in;
    memset(&in, 0, sizeof in);
    in.name = mesh->name;
    in.positions = mesh->positions;
    in.vertex_count = mesh->vertex_count;
    in.indices = mesh->indices;
    in.triangle_count = mesh->triangle_count;
    in.texcoords = mesh->texcoords;
    in.normals = mesh->file_normals && !mesh->flat_normals ? mesh->normals : NULL;
    in.vertex_importance = st->vertex_importance ? st->vertex_importance[m] : NULL;
    in.max_normal_angle = st->options->max_normal_angle;
    return in;
}

/* The decimation inputs and the plan: importance sums set the factors (method importance), or
 * equal importance gives the uniform D of the quadric baseline. */
static int plan_budget(reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    double start = monotonic_seconds();
    st->input = xcalloc(st->count + 1, sizeof *st->input);
    budget_mesh *budget = st->budget = xcalloc(st->count + 1, sizeof *budget);
    importance_weights weights = importance_weights_of(&o->importance);
    for (size_t m = 0; m < st->count; m++) {
        st->input[m] = decimation_input(st, m);
        budget[m].name = s->meshes[m].name;
        /* Counted as the scene holds them, so the totals match what `idmr info` says of the
         * input and of the reduced scene. */
        budget[m].vertices = s->meshes[m].vertex_count;
        budget[m].pinned = reduce_mesh_pinned(o, &s->meshes[m]);
        if (reduce_method_uses_importance(o->method)) {
            budget[m].importance = importance_mesh_sums(&st->importance, s, m, &weights).amount;
        } else {
            budget[m].importance = 1.0; /* equal factors: the uniform D of the baseline */
        }
    }
    int status = budget_distribute(budget, st->count, o->target, o->min_vertices, &st->plan);
    /* Nothing to remove (D = 1): every mesh that could be decimated is still rewritten, as its
     * PLY without a collapse, so the output is the scene converted (and a check of the writer:
     * another renderer must show it as the input). */
    if (!status && st->plan.total_requested == st->plan.total_before)
        for (size_t m = 0; m < st->count; m++)
            if (!budget[m].pinned && budget[m].vertices > o->min_vertices)
                st->plan.decimate[m] = 1;
    st->seconds_budget = monotonic_seconds() - start;
    return status;
}

/* Whether an earlier mesh's PLY has the name mesh m's would get. */
static int ply_name_taken(const reduce_state *st, size_t m)
{
    for (size_t k = 0; k < m; k++)
        if (st->ply[k] && strcmp(st->ply[k], st->ply[m]) == 0)
            return 1;
    return 0;
}

/* st->ply[m] = "meshes/NAME.ply"; two mesh names can make the same file name ("a/b", "a_b"):
 * the later ones are numbered ("meshes/NAME.2.ply"). */
static void name_ply(reduce_state *st, size_t m)
{
    char name[256];
    importance_file_name(st->scene->meshes[m].name, name, sizeof name);
    size_t length = strlen(name) + 32;
    st->ply[m] = xmalloc(length);
    snprintf(st->ply[m], length, "meshes/%s.ply", name);
    for (unsigned int suffix = 2; ply_name_taken(st, m); suffix++)
        snprintf(st->ply[m], length, "meshes/%s.%u.ply", name, suffix);
}

/* OUTDIR/meshes/NAME.ply for every decimated mesh, then OUTDIR/scene.xml pointing to them. */
static int write_reduced_scene(reduce_state *st)
{
    const scene *s = st->scene;
    double start = monotonic_seconds();
    st->ply = xcalloc(st->count + 1, sizeof *st->ply);
    mitsuba_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    int status = 0;
    for (size_t m = 0; m < st->count && !status; m++) {
        if (!st->plan.decimate[m])
            continue;
        char path[PATH_MAX];
        name_ply(st, m);
        snprintf(path, sizeof path, "%s/%s", st->staging, st->ply[m]);
        status = mesh_io_write_ply(path, &st->output[m].mesh, NULL, NULL, NULL);
        replacements[st->meshes_written++] = (mitsuba_replacement){
            s->meshes[m].xml_file, s->meshes[m].xml_line, st->ply[m], s->meshes[m].flat_normals};
    }
    if (!status)
        status = mitsuba_write_reduced(s->file, st->staging, replacements, st->meshes_written,
                                       st->options->bundle);
    free(replacements);
    st->seconds_write = monotonic_seconds() - start;
    return status;
}

/* report.json (with the importance outputs for method importance). */
static int write_report(reduce_state *st)
{
    const reduce_options *o = st->options;
    cJSON *report = reduce_report_json(st);
    int status;
    if (reduce_method_uses_importance(o->method)) {
        status = importance_write_outputs(st->staging, report, st->scene, &o->importance,
                                          &st->importance, st->vertex_importance);
    } else {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/report.json", st->staging);
        status = json_write(report, path);
    }
    cJSON_Delete(report);
    return status;
}

/* The closing line. */
static void print_summary(const reduce_state *st)
{
    const reduce_options *o = st->options;
    fprintf(stderr,
            "idmr: %llu -> %llu vertices (target %.4g: %llu), %zu of %zu meshes rewritten; "
            "reduced scene in %s/scene.xml\n",
            (unsigned long long)st->plan.total_before, (unsigned long long)st->vertices_after,
            o->target, (unsigned long long)st->plan.total_requested, st->meshes_written,
            st->count, st->outdir);
}

/* ---- pipeline ---- */

static void state_free(reduce_state *st)
{
    importance_vertex_values_free(st->vertex_importance, st->scene);
    for (size_t m = 0; m < st->count; m++) {
        if (st->output)
            decimate_output_free(&st->output[m]);
        free(st->ply ? st->ply[m] : NULL);
    }
    free(st->input);
    free(st->budget);
    free(st->output);
    free(st->ply);
    budget_plan_free(&st->plan);
    importance_result_free(&st->importance);
}

int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o)
{
    reduce_state st = {.device = d, .scene = s, .outdir = outdir, .options = o,
                       .count = s->mesh_count};
    int status = check_options(&st) || reduce_outdir_prepare(&st) || run_importance(&st) ||
                 plan_budget(&st) || reduce_decimation(&st) || write_reduced_scene(&st) ||
                 write_report(&st);
    status = reduce_outdir_finish(&st, !status);
    if (!status)
        print_summary(&st);
    state_free(&st);
    return status ? -1 : 0;
}
