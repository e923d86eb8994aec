/* reduce.c — the reduction pipeline behind `idmr reduce` (see reduce.h): reduce_run() runs its
 * stages in order over one reduce_state (reduce_stages.h lists them and what each leaves in the
 * state); this file holds the pipeline and the option, importance, budget and writing stages. */
#include "reduce/reduce.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "core/json.h"
#include "core/progress.h"
#include "io/mesh_io.h"
#include "io/gltf.h"
#include "io/mitsuba_write.h"
#include "io/ply_check.h"
#include "io/scene_load.h"
#include "passes/importance_file.h"
#include "passes/importance_outputs.h"
#include "reduce/reduce_stages.h"

/* ---- stages ---- */

/* --target and --initial in (0, 1], --passes in 1 .. REDUCE_MAX_PASSES and only with a method
 * that has an importance pass (and not with --simulation, a pass of the whole scene); every
 * --keep name is a mesh of the scene. */
static int check_options(const reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    if (!(o->target > 0 && o->target <= 1))
        return error_set(IDMR_EXIT_INPUT, "--target must be in (0, 1], not %g", o->target);
    if (!(o->initial > 0 && o->initial <= 1))
        return error_set(IDMR_EXIT_INPUT, "--initial must be in (0, 1], not %g", o->initial);
    if (o->passes < 1 || o->passes > REDUCE_MAX_PASSES)
        return error_set(IDMR_EXIT_INPUT, "--passes must be 1 to %u, not %u", REDUCE_MAX_PASSES,
                         o->passes);
    int staged = o->initial < 1 || o->passes > 1;
    if (staged && !reduce_method_uses_importance(o->method))
        return error_set(IDMR_EXIT_INPUT, "--initial and --passes are for the methods with an "
                                          "importance pass, not '%s'",
                         reduce_method_name(o->method));
    if ((staged || o->memory_budget) && o->simulation)
        return error_set(IDMR_EXIT_INPUT, "--simulation is a pass over the whole scene: it "
                                          "cannot be combined with --initial, --passes or "
                                          "--memory-budget");
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

/* Mesh m as the plan of Eq. 3 sees it: its vertices as the scene holds them (so the totals
 * match what `idmr info` says of the input and of the reduced scene), and its importance sum
 * from `r` (methods with the importance pass), or equal importance for all, which gives the
 * uniform D of the quadric baseline. */
static budget_mesh budget_entry(const reduce_state *st, const importance_result *r, size_t m)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    /* The importance sum of a mesh does not depend on how finely it is meshed: the simulated
     * scene's sum stands for the original's. */
    importance_weights weights = importance_weights_of(&o->importance);
    budget_mesh entry = {.name = s->meshes[m].name,
                         .vertices = s->meshes[m].vertex_count,
                         .pinned = reduce_mesh_pinned(o, &s->meshes[m]),
                         .importance = 1.0};
    if (reduce_method_uses_importance(o->method))
        entry.importance = importance_mesh_sums(r, st->simulated, m, &weights).amount;
    return entry;
}

int reduce_decimatable(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    return !reduce_mesh_pinned(st->options, mesh) &&
           mesh->vertex_count > st->options->min_vertices;
}

/* The ranking change is taken over at most this many vertices (an even spread of them). */
#define RANKING_SAMPLE (1u << 20)

/* The stop rule while the pass runs (factor_stop.h). */
typedef struct checkpoint_state {
    reduce_state *st;
    factor_stop rule;
    budget_mesh *budget;
    uint64_t *previous_target; /* the last checkpoint's plan; NULL before the first */
    double *sampled_importance;         /* per-vertex importance of the sampled vertices */
    double *previous_ranking, *ranking; /* their ranks (mean_ranks) at the last checkpoint, now */
    size_t sampled, stride;
    double *vertex_scratch; /* one mesh's per-vertex importance */
} checkpoint_state;

/* The sampled vertices' importance now, into c->sampled_importance, and its ranks into
 * c->ranking. */
static void rank_vertex_importance(checkpoint_state *c, const importance_result *r)
{
    const scene *s = c->st->simulated;
    importance_weights weights = importance_weights_of(&c->st->options->importance);
    size_t global = 0, k = 0;
    for (size_t m = 0; m < c->st->count; m++) {
        if (!reduce_decimatable(c->st, m))
            continue;
        importance_mesh_vertices(r, s, m, &weights, c->vertex_scratch);
        for (uint32_t v = 0; v < s->meshes[m].vertex_count; v++, global++)
            if (global % c->stride == 0 && k < c->sampled)
                c->sampled_importance[k++] = c->vertex_scratch[v];
    }
    mean_ranks(c->sampled_importance, c->sampled, c->ranking);
}

/* Every FACTOR_STOP_EVERY iterations: the plan from the importance so far against the last
 * checkpoint's, recorded in the state; stops the pass when the rule says so. */
static int checkpoint(void *context, const importance_result *r, int *stop, char *detail,
                      size_t detail_size)
{
    checkpoint_state *c = context;
    reduce_state *st = c->st;
    unsigned int iteration = r->sppm.iterations;
    if (iteration % FACTOR_STOP_EVERY)
        return 0;
    double total_importance = 0;
    for (size_t m = 0; m < st->count; m++) {
        c->budget[m] = budget_entry(st, r, m);
        total_importance += c->budget[m].pinned ? 0.0 : c->budget[m].importance;
    }
    factor_checkpoint *record = &st->checkpoints[st->checkpoint_count++];
    *record = (factor_checkpoint){iteration, -1.0, -1.0};
    /* No importance yet: no plan to compare (and the budget's warning is for the real plan). */
    if (!(total_importance > 0)) {
        factor_stop_update(&c->rule, -1.0, -1.0);
        return 0;
    }
    budget_plan plan;
    if (budget_distribute(c->budget, st->count, st->target, st->options->min_vertices,
                          &plan))
        return -1;
    rank_vertex_importance(c, r);
    if (c->previous_target) {
        record->factor_change = factor_change(c->previous_target, plan.target, st->count);
        record->ranking_change = ranking_change(c->previous_ranking, c->ranking, c->sampled);
        snprintf(detail, detail_size, ", factors %.1e, ranking %.1e", record->factor_change,
                 record->ranking_change);
    } else {
        c->previous_target = xcalloc(st->count + 1, sizeof *c->previous_target);
    }
    memcpy(c->previous_target, plan.target, st->count * sizeof *plan.target);
    double *swap = c->previous_ranking;
    c->previous_ranking = c->ranking;
    c->ranking = swap;
    budget_plan_free(&plan);
    if (factor_stop_update(&c->rule, record->factor_change, record->ranking_change)) {
        *stop = 1;
        st->stopped_at = iteration;
    }
    return 0;
}

/* The importance pass with the stop rule on the decimation factors, on a BVH built for it. */
static int importance_with_stop_rule(reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->simulated;
    /* The ranking matters where the collapses follow the vertex importance. */
    int ranked = reduce_method_collapses(o->method) != DECIMATE_QUADRIC;
    checkpoint_state c = {.st = st,
                          .rule = {.tolerance = o->factor_tolerance,
                                   .ranking_tolerance = ranked ? o->ranking_tolerance : 0.0},
                          .stride = 1};
    size_t largest = 0, candidates = 0;
    for (size_t m = 0; m < st->count; m++)
        if (reduce_decimatable(st, m)) {
            candidates += s->meshes[m].vertex_count;
            if (s->meshes[m].vertex_count > largest)
                largest = s->meshes[m].vertex_count;
        }
    c.stride = candidates > RANKING_SAMPLE ? (candidates + RANKING_SAMPLE - 1) / RANKING_SAMPLE
                                           : 1;
    c.sampled = (candidates + c.stride - 1) / c.stride;
    c.budget = xcalloc(st->count + 1, sizeof *c.budget);
    c.sampled_importance = xcalloc(c.sampled + 1, sizeof *c.sampled_importance);
    c.ranking = xcalloc(c.sampled + 1, sizeof *c.ranking);
    c.previous_ranking = xcalloc(c.sampled + 1, sizeof *c.previous_ranking);
    c.vertex_scratch = xcalloc(largest + 1, sizeof *c.vertex_scratch);
    free(st->checkpoints);
    st->checkpoint_count = 0;
    st->checkpoints = xcalloc(o->importance.sppm.iterations / FACTOR_STOP_EVERY + 1,
                              sizeof *st->checkpoints);
    importance_options options = o->importance;
    options.checkpoint = checkpoint;
    options.sppm.device_budget = o->memory_budget;
    options.checkpoint_context = &c;
    bvh b;
    int status = bvh_build(s, &b);
    options.sppm.release_bvh = &b; /* the host's copy is not needed once uploaded */
    if (!status) {
        status = importance_run(st->device, s, &b, &options, &st->importance);
        bvh_free(&b);
    }
    free(c.budget);
    free(c.previous_target);
    free(c.sampled_importance);
    free(c.ranking);
    free(c.previous_ranking);
    free(c.vertex_scratch);
    return status;
}

/* Methods with importance: the importance pass on the simulated scene (or the saved one
 * --simulation names), and each mesh's per-vertex importance, computed once for the decimation
 * and the importance outputs, and copied back to the originals where the simulated scene is a
 * reduced one. */
static int run_importance(reduce_state *st)
{
    const reduce_options *o = st->options;
    double start = monotonic_seconds();
    int status = 0;
    if (reduce_method_uses_importance(o->method)) {
        importance_weights weights = importance_weights_of(&o->importance);
        status = o->simulation ? importance_file_read(o->simulation, st->scene, &o->importance,
                                                      &st->importance)
                               : importance_with_stop_rule(st);
        if (!status) {
            st->vertex_importance = importance_vertex_values(&st->importance, st->simulated,
                                                             &weights);
            reduce_remap(st);
        }
    }
    st->seconds_importance += monotonic_seconds() - start;
    return status;
}

/* What mesh m is decimated from: the scene's mesh, its texture coordinates, its normals unless
 * they are flat (flat ones become face_normals) or were computed by the loader and are to be
 * computed again by the reader (recompute_normals), and its per-vertex importance (remapped, with
 * each vertex's distance from its source, where it was computed on a reduced mesh). Computed
 * normals are carried by default: the reader would compute them from the reduced mesh, whose
 * larger faces average the original's curvature away (a glass surface then shows the light in
 * other places; see README, "Attributes through the reduction"). */
void reduce_mesh_attributes(const reduce_state *st, size_t m, int *texcoords, int *normals)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    int carried = mesh->file_normals || !st->options->recompute_normals;
    *texcoords = mesh->released ? mesh->had_texcoords : mesh->texcoords != NULL;
    *normals = carried && !mesh->flat_normals &&
               (mesh->released ? mesh->had_normals : mesh->normals != NULL);
}

decimate_input reduce_decimation_input(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    decimate_input in;
    memset(&in, 0, sizeof in);
    in.name = mesh->name;
    in.positions = mesh->positions;
    in.vertex_count = mesh->vertex_count;
    in.indices = mesh->indices;
    in.triangle_count = mesh->triangle_count;
    int texcoords, normals;
    reduce_mesh_attributes(st, m, &texcoords, &normals);
    in.texcoords = texcoords ? mesh->texcoords : NULL;
    in.normals = normals ? mesh->normals : NULL;
    in.vertex_importance = st->vertex_importance ? st->vertex_importance[m] : NULL;
    if (st->remapped && st->remapped[m]) {
        in.vertex_importance = st->remapped[m];
        in.vertex_distance = st->distance[m];
    }
    in.max_normal_angle = st->options->max_normal_angle;
    in.uv_weight = st->options->uv_weight;
    in.normal_weight = st->options->normal_weight;
    return in;
}

int reduce_plan_budget(reduce_state *st)
{
    const reduce_options *o = st->options;
    double start = monotonic_seconds();
    st->input = xcalloc(st->count + 1, sizeof *st->input);
    budget_mesh *budget = st->budget = xcalloc(st->count + 1, sizeof *budget);
    for (size_t m = 0; m < st->count; m++) {
        st->input[m] = reduce_decimation_input(st, m);
        budget[m] = budget_entry(st, &st->importance, m);
    }
    int status = budget_distribute(budget, st->count, st->target, o->min_vertices, &st->plan);
    /* Nothing to remove (D = 1): every mesh that could be decimated is still rewritten, as its
     * PLY without a collapse, so the output is the scene converted (and a check of the writer:
     * another renderer must show it as the input). */
    if (!status && st->plan.total_requested == st->plan.total_before)
        for (size_t m = 0; m < st->count; m++)
            if (reduce_decimatable(st, m))
                st->plan.decimate[m] = 1;
    st->seconds_budget += monotonic_seconds() - start;
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

/* A glTF scene: OUTDIR/scene.gltf or scene.glb with the decimated meshes in it (io/gltf.h). */
static int write_reduced_gltf(reduce_state *st)
{
    const scene *s = st->scene;
    gltf_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    for (size_t m = 0; m < st->count; m++)
        if (st->plan.decimate[m])
            replacements[st->meshes_written++] =
                (gltf_replacement){s->meshes[m].xml_line, &st->output[m].mesh};
    int status = gltf_write_reduced(s->file, st->staging, replacements, st->meshes_written,
                                    st->options->bundle);
    free(replacements);
    return status;
}

/* OUTDIR/meshes/NAME.ply for every decimated mesh, then OUTDIR/scene.xml pointing to them; or,
 * for a glTF scene, OUTDIR/scene.gltf (.glb). */
static int write_reduced_scene(reduce_state *st)
{
    const scene *s = st->scene;
    double start = monotonic_seconds();
    if (scene_is_gltf(s)) {
        int status = write_reduced_gltf(st);
        st->seconds_write = monotonic_seconds() - start;
        return status;
    }
    char meshes[PATH_MAX];
    snprintf(meshes, sizeof meshes, "%s/meshes", st->staging);
    int status = files_make_directory(meshes);
    st->ply = xcalloc(st->count + 1, sizeof *st->ply);
    mitsuba_replacement *replacements = xcalloc(st->count + 1, sizeof *replacements);
    for (size_t m = 0; m < st->count && !status; m++) {
        if (!st->plan.decimate[m])
            continue;
        char path[PATH_MAX];
        name_ply(st, m);
        snprintf(path, sizeof path, "%s/%s", st->staging, st->ply[m]);
        status = mesh_io_write_ply(path, &st->output[m].mesh, NULL, NULL, NULL) ||
                 ply_check_written(path);
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
        status = importance_write_outputs(st->staging, report, st->simulated, &o->importance,
                                          &st->importance, st->vertex_importance);
    } else {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/report.json", st->staging);
        status = json_write(report, path);
    }
    cJSON_Delete(report);
    return status;
}

/* The reduced scene's file name in OUTDIR. */
static const char *reduced_scene_name(const scene *s)
{
    return scene_is_gltf(s) ? gltf_output_name(s->file) : "scene.xml";
}

/* The closing line. */
static void print_summary(const reduce_state *st)
{
    fprintf(stderr,
            "idmr: %llu -> %llu vertices (target %.4g: %llu), %zu of %zu meshes rewritten; "
            "reduced scene in %s/%s\n",
            (unsigned long long)st->plan.total_before, (unsigned long long)st->vertices_after,
            st->target, (unsigned long long)st->plan.total_requested, st->meshes_written,
            st->count, st->outdir, reduced_scene_name(st->scene));
}

/* ---- pipeline ---- */

static void state_free(reduce_state *st)
{
    importance_vertex_values_free(st->vertex_importance, st->simulated);
    for (size_t m = 0; st->ply && m < st->count; m++)
        free(st->ply[m]);
    free(st->ply);
    free(st->checkpoints);
    reduce_decimation_forget(st);
    importance_result_free(&st->importance);
    reduce_passes_free(st);
}

/* The record of the pass that just ended (report.json: passes). */
static int record_pass(reduce_state *st, double seconds_importance, double seconds_reduction)
{
    const sppm_summary *run = &st->importance.sppm;
    reduce_pass_record *p = &st->passes[st->pass_count++];
    p->seconds_importance = st->seconds_importance - seconds_importance;
    p->seconds_reduction = st->seconds_budget + st->seconds_decimation - seconds_reduction;
    p->vertices_simulated = st->simulated->vertex_count;
    p->vertices_after = st->vertices_after;
    p->device_bytes = st->options->simulation
                          ? 0
                          : run->geometry_bytes + run->bvh_bytes + run->buffer_bytes;
    p->iterations = run->iterations;
    return 0;
}

/* One importance pass and the reduction of the originals after it; from the second on, the
 * importance pass runs on the last one's result. */
static int run_pass(reduce_state *st, unsigned int pass)
{
    double importance_before = st->seconds_importance;
    double reduction_before = st->seconds_budget + st->seconds_decimation;
    if (pass > 1 && reduce_next_pass(st))
        return -1;
    if (st->options->passes > 1 && st->options->importance.sppm.progress)
        fprintf(stderr, "idmr: pass %u of %u: importance on %llu vertices\n", pass,
                st->options->passes, (unsigned long long)st->simulated->vertex_count);
    return run_importance(st) || reduce_plan_budget(st) || reduce_decimation(st) ||
           record_pass(st, importance_before, reduction_before);
}

/* The process's peak resident memory since the last reset_peak_resident() (VmHWM), in bytes;
 * 0 where the system does not say. */
static double peak_resident_bytes(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    double kib = 0;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %lf kB", &kib) == 1)
            break;
    if (f)
        fclose(f);
    return kib * 1024.0;
}

/* Starts the peak over (Linux: "5" into clear_refs), so a run measures its own peak, not an
 * earlier one of the same process (a test). */
static void reset_peak_resident(void)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (f) {
        fputs("5", f);
        fclose(f);
    }
}

/* Where the device shares the host's memory the budget bounds the whole process: a run that
 * went above it (the plan's estimates missed) is an error, not a result. */
static int check_peak_within_budget(const reduce_state *st)
{
    uint64_t budget = st->options->memory_budget;
    double peak = peak_resident_bytes();
    if (!budget || !st->device->info.host_unified || peak <= (double)budget)
        return 0;
    return error_set(IDMR_EXIT_FAILURE,
                     "--memory-budget %.1f MiB: the process peaked at %.1f MiB (device '%s' "
                     "shares the host's memory, so the budget bounds the whole process); the "
                     "reduced scene is not written: raise the budget or lower --target",
                     (double)budget / 1048576.0, peak / 1048576.0, st->device->info.name);
}

int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o)
{
    reduce_state st = {.device = d, .scene = s, .simulated = s, .outdir = outdir, .options = o,
                       .count = s->mesh_count, .target = o->target, .initial = o->initial};
    st.passes = xcalloc(REDUCE_MAX_PASSES + 1, sizeof *st.passes);
    if (o->memory_budget)
        reset_peak_resident();
    int status = check_options(&st) || reduce_memory_plan(&st);
    /* The budget leaves nothing to remove (the scene renders within it as it is): the scene is
     * written as it is, without an initial reduction or an importance pass to find that out. */
    reduce_options as_is;
    if (!status && o->memory_budget && !(st.target < 1) &&
        reduce_method_uses_importance(o->method)) {
        as_is = *o;
        as_is.method = REDUCE_QUADRIC;
        as_is.passes = 1;
        as_is.initial = 1.0;
        st.options = o = &as_is;
        st.initial = 1.0;
    }
    status = status || reduce_outdir_prepare(&st) || reduce_initial(&st);
    for (unsigned int pass = 1; !status && pass <= o->passes; pass++)
        status = run_pass(&st, pass);
    /* Under a memory budget, the reduced scene decimated again at a lower target while its
     * render does not fit (the fit says so). */
    for (int again = 1; !status && again;) {
        status = reduce_memory_fit(&st, &again);
        if (status || !again)
            break;
        reduce_decimation_forget(&st);
        status = reduce_plan_budget(&st) || reduce_decimation(&st);
        if (!status && st.pass_count) /* the last pass's reduction is this one now */
            st.passes[st.pass_count - 1].vertices_after = st.vertices_after;
    }
    status = status || write_reduced_scene(&st) || write_report(&st) ||
             check_peak_within_budget(&st);
    status = reduce_outdir_finish(&st, !status);
    if (!status)
        print_summary(&st);
    state_free(&st);
    return status ? -1 : 0;
}
