/* reduce_report.c — the report stage of `idmr reduce` (see reduce_stages.h): report.json (see
 * reduce.h for the keys), with the importance outputs beside it for the methods with importance
 * (passes/importance_outputs.h), and the closing line. report.json is the importance report's
 * object (method importance) or a bare one with the scene, meshes and seconds, to which the
 * reduction adds its options, vertex totals, stage seconds and per-mesh figures. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <sys/resource.h>

#include "core/json.h"
#include "io/gltf/gltf.h"
#include "io/scene_load.h"
#include "reduce/reduce_stages.h"

#include "passes/importance_outputs.h"

/* The keys the importance report would have given: the scene and empty meshes and seconds. */
static cJSON *report_without_importance(const scene *s)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddItemToObject(root, "meshes", cJSON_CreateArray());
    cJSON_AddItemToObject(root, "seconds", cJSON_CreateObject());
    return root;
}

static void add_totals(cJSON *root, const reduce_state *st)
{
    const reduce_options *o = st->options;
    cJSON_AddNumberToObject(root, "target", st->target);
    cJSON_AddStringToObject(root, "method", reduce_method_name(o->method));
    cJSON_AddNumberToObject(root, "max_normal_angle", o->max_normal_angle);
    cJSON_AddNumberToObject(root, "uv_weight", o->uv_weight);
    cJSON_AddNumberToObject(root, "normal_weight", o->normal_weight);
    cJSON_AddStringToObject(root, "computed_normals",
                            o->recompute_normals ? "recomputed" : "carried");
    cJSON_AddNumberToObject(root, "min_vertices", (double)o->min_vertices);
    cJSON_AddNumberToObject(root, "vertices_before", (double)st->plan.total_before);
    cJSON_AddNumberToObject(root, "vertices_requested", (double)st->plan.total_requested);
    cJSON_AddNumberToObject(root, "vertices_planned", (double)st->plan.total_planned);
    cJSON_AddNumberToObject(root, "vertices_after", (double)st->vertices_after);
    /* With instances kept, vertices_after counts a prototype once (reduce_instances.c). */
    cJSON_AddNumberToObject(root, "vertices_rendered_after",
                            (double)reduce_instances_rendered_vertices(st));
    cJSON_AddNumberToObject(root, "vertices_missed",
                            (double)st->vertices_after - (double)st->plan.total_requested);
    cJSON_AddBoolToObject(root, "uniform_fallback", st->plan.uniform_fallback);
    cJSON_AddNumberToObject(root, "compensation_rounds", st->compensation_rounds);
    cJSON_AddNumberToObject(root, "boundary_locks_relaxed", st->locks_relaxed);
    cJSON_AddNumberToObject(root, "seams_freed", st->seams_freed);
}

static void add_seconds(cJSON *seconds, const reduce_state *st)
{
    cJSON_AddNumberToObject(seconds, "load", st->scene->load_seconds);
    cJSON_AddNumberToObject(seconds, "initial", st->seconds_initial);
    cJSON_AddNumberToObject(seconds, "importance", st->seconds_importance);
    cJSON_AddNumberToObject(seconds, "budget", st->seconds_budget);
    cJSON_AddNumberToObject(seconds, "decimation", st->seconds_decimation);
    cJSON_AddNumberToObject(seconds, "write", st->seconds_write);
    /* The decimation's parts, summed over the meshes' last decimations (thread-seconds: meshes
     * run side by side, so they may add up to more than the decimation's wall time). */
    double weld = 0, collapse = 0, output = 0;
    for (size_t m = 0; m < st->count; m++)
        if (st->plan.decimate && st->plan.decimate[m]) {
            weld += st->output[m].seconds_weld;
            collapse += st->output[m].seconds_collapse;
            output += st->output[m].seconds_output;
        }
    cJSON *parts = cJSON_AddObjectToObject(seconds, "decimation_parts");
    cJSON_AddNumberToObject(parts, "weld", weld);
    cJSON_AddNumberToObject(parts, "collapse", collapse);
    cJSON_AddNumberToObject(parts, "output", output);
}

/* The reduction's figures of mesh m, added to its entry (created when the report has none). */
static void add_mesh(cJSON *meshes, const reduce_state *st, size_t m)
{
    const scene_mesh *in = &st->scene->meshes[m];
    cJSON *mesh = cJSON_GetArrayItem(meshes, (int)m);
    if (!mesh) {
        mesh = cJSON_CreateObject();
        cJSON_AddStringToObject(mesh, "name", in->name);
        cJSON_AddNumberToObject(mesh, "vertices", in->vertex_count);
        cJSON_AddNumberToObject(mesh, "triangles", in->triangle_count);
        cJSON_AddItemToArray(meshes, mesh);
    }
    int decimated = st->plan.decimate[m];
    const decimate_output *out = &st->output[m];
    cJSON_AddNumberToObject(mesh, "factor", st->plan.factor[m]);
    cJSON_AddBoolToObject(mesh, "decimated", decimated);
    cJSON_AddNumberToObject(mesh, "vertices_before", in->vertex_count);
    cJSON_AddNumberToObject(mesh, "vertices_target", (double)st->plan.target[m]);
    /* An instance's copy after its shape's first is the first's decimation, placed. */
    const decimate_output *placed = &st->output[reduce_instance_representative(st, m)];
    int holds = placed->mesh.positions != NULL;
    cJSON_AddNumberToObject(mesh, "vertices_after",
                            holds ? placed->mesh.vertex_count : in->vertex_count);
    cJSON_AddNumberToObject(mesh, "triangles_after",
                            holds ? placed->mesh.triangle_count : in->triangle_count);
    int not_reduced = st->not_reduced && st->not_reduced[m];
    if ((decimated || not_reduced) && st->budget[m].floor > 0)
        cJSON_AddNumberToObject(mesh, "vertices_floor", (double)st->budget[m].floor);
    if (decimated && st->options->method == REDUCE_COMBINED) {
        double set = st->input[m].boundary_tolerance;
        double tolerance = set > 0 ? set : DECIMATE_BOUNDARY_TOLERANCE;
        if (isinf(tolerance))
            cJSON_AddNullToObject(mesh, "boundary_tolerance");
        else
            cJSON_AddNumberToObject(mesh, "boundary_tolerance", tolerance);
    }
    const decimate_input *decimated_from = &st->input[m];
    int texcoords, normals;
    reduce_mesh_attributes(st, m, &texcoords, &normals);
    if (decimated && (texcoords || normals)) {
        cJSON_AddBoolToObject(mesh, "texcoords", texcoords);
        cJSON_AddBoolToObject(mesh, "normals", normals);
        cJSON_AddStringToObject(mesh, "seams", decimated_from->seams_free ? "free" : "kept");
    }
    if (decimated) {
        cJSON_AddNumberToObject(mesh, "passes", out->passes);
        cJSON_AddNumberToObject(mesh, "decimation_seconds",
                                out->seconds_weld + out->seconds_collapse + out->seconds_output);
        cJSON_AddNumberToObject(mesh, "vertices_welded", out->vertices_welded);
        cJSON_AddNumberToObject(mesh, "vertices_uncollapsible", out->vertices_uncollapsible);
        cJSON_AddNumberToObject(mesh, "faces_patched", out->faces_patched);
        cJSON_AddNumberToObject(mesh, "faces_loose", out->faces_loose);
        if (st->ply && st->ply[m])
            cJSON_AddStringToObject(mesh, "file", st->ply[m]);
        else /* a glTF scene: the mesh is in the written file, by its instance number */
            cJSON_AddNumberToObject(mesh, "gltf_instance", in->xml_line);
    }
    cJSON_AddBoolToObject(mesh, "pinned", reduce_instance_pinned(st, m));
    if (reduce_instance_follower(st, m)) /* reduced as that copy is, moved to its place */
        cJSON_AddStringToObject(mesh, "instance_of",
                                st->scene->meshes[reduce_instance_representative(st, m)].name);
    if (not_reduced)
        cJSON_AddStringToObject(mesh, "not_reduced", st->not_reduced[m]);
    if (in->triangles_dropped)
        cJSON_AddNumberToObject(mesh, "triangles_dropped", in->triangles_dropped);
}

/* The initial reduction (null without one) and one entry per importance pass: its seconds, the
 * vertices it simulated and those the reduction after it kept, its device memory. */
static void add_passes(cJSON *root, const reduce_state *st)
{
    const reduce_options *o = st->options;
    if (st->initial < 1) {
        cJSON *initial = cJSON_AddObjectToObject(root, "initial");
        cJSON_AddNumberToObject(initial, "target", st->initial);
        cJSON_AddBoolToObject(initial, "chosen_for_budget", !(o->initial < 1));
        cJSON_AddNumberToObject(initial, "vertex_floor", REDUCE_INITIAL_FLOOR);
        cJSON_AddNumberToObject(initial, "vertices_after", (double)st->vertices_initial);
        cJSON_AddNumberToObject(initial, "seconds", st->seconds_initial);
    } else {
        cJSON_AddNullToObject(root, "initial");
    }
    cJSON *list = cJSON_AddArrayToObject(root, "passes");
    for (unsigned int k = 0; k < st->pass_count; k++) {
        const reduce_pass_record *p = &st->passes[k];
        cJSON *item = cJSON_CreateObject();
        cJSON_AddNumberToObject(item, "pass", k + 1);
        cJSON_AddNumberToObject(item, "iterations", p->iterations);
        cJSON_AddNumberToObject(item, "vertices_simulated", (double)p->vertices_simulated);
        cJSON_AddNumberToObject(item, "vertices_after", (double)p->vertices_after);
        cJSON_AddNumberToObject(item, "device_bytes", (double)p->device_bytes);
        cJSON_AddNumberToObject(item, "importance_seconds", p->seconds_importance);
        cJSON_AddNumberToObject(item, "reduction_seconds", p->seconds_reduction);
        cJSON_AddItemToArray(list, item);
    }
}

/* The memory budget's figures (null without one): the budget, the target asked for, the
 * plan's BVH estimate, the reduced scene's exact render memory by part and the decimations run
 * again to fit. */
static void add_memory(cJSON *root, const reduce_state *st)
{
    const reduce_options *o = st->options;
    if (!o->memory_budget) {
        cJSON_AddNullToObject(root, "memory_budget");
        return;
    }
    cJSON *memory = cJSON_AddObjectToObject(root, "memory_budget");
    cJSON_AddNumberToObject(memory, "bytes", (double)o->memory_budget);
    /* The device's buffers are the host's memory: the budget bounds the whole process. */
    cJSON_AddBoolToObject(memory, "host_memory_counted", st->device->info.host_unified);
    cJSON_AddNumberToObject(memory, "target_requested", o->target);
    cJSON_AddNumberToObject(memory, "bvh_bytes_per_triangle_estimate",
                            REDUCE_BVH_BYTES_PER_TRIANGLE);
    const sppm_memory *m = &st->render_memory;
    cJSON *render = cJSON_AddObjectToObject(memory, "render_device_bytes");
    cJSON_AddNumberToObject(render, "total", (double)sppm_memory_total(m));
    cJSON_AddNumberToObject(render, "geometry", (double)m->geometry);
    cJSON_AddNumberToObject(render, "bvh", (double)m->bvh);
    cJSON_AddNumberToObject(render, "buffers", (double)(m->core + m->pass));
    cJSON_AddNumberToObject(memory, "fit_rounds", st->fit_rounds);
}

/* A measure's seconds by stage, as an object named `name` of parent. */
static void add_search_seconds(cJSON *parent, const char *name, const error_search_seconds *t)
{
    cJSON *stages = cJSON_AddObjectToObject(parent, name);
    cJSON_AddNumberToObject(stages, "decimation", t->decimation);
    cJSON_AddNumberToObject(stages, "bvh", t->bvh);
    cJSON_AddNumberToObject(stages, "program", t->program);
    cJSON_AddNumberToObject(stages, "setup", t->setup);
    cJSON_AddNumberToObject(stages, "iterations", t->iterations);
    cJSON_AddNumberToObject(stages, "compare", t->compare);
}

/* The check renders (reduce_error_budget.c) as `check_render` of parent: iterations, photons,
 * film scale and size, the first gather radius every render shares, the seeds. */
static void add_check_render(cJSON *parent, const reduce_state *st)
{
    const reduce_error_options *o = &st->options->error;
    cJSON *check = cJSON_AddObjectToObject(parent, "check_render");
    cJSON_AddNumberToObject(check, "iterations", o->iterations);
    cJSON_AddNumberToObject(check, "photons", o->photons);
    cJSON_AddNumberToObject(check, "resolution", o->resolution);
    cJSON_AddNumberToObject(check, "width", st->error_search.width);
    cJSON_AddNumberToObject(check, "height", st->error_search.height);
    cJSON_AddNumberToObject(check, "first_radius", st->error_search.radius);
    cJSON *seeds = cJSON_AddArrayToObject(check, "seeds");
    cJSON_AddItemToArray(seeds, cJSON_CreateNumber(1));
    cJSON_AddItemToArray(seeds, cJSON_CreateNumber(2));
}

/* The refinement (null without --refine): each round's mix λ, pixels weighted, paired error
 * and standard error of the check renders, vertices, seconds and whether it was kept; the round
 * written, and its error over round 0's (the importance-only reduction at the same D). */
static void add_refine(cJSON *root, const reduce_state *st)
{
    const reduce_refine_state *rf = &st->refine;
    if (!st->options->refine || !rf->round_count) {
        cJSON_AddNullToObject(root, "refine");
        return;
    }
    cJSON *refine = cJSON_AddObjectToObject(root, "refine");
    cJSON_AddNumberToObject(refine, "rounds_asked", st->options->refine);
    cJSON_AddNumberToObject(refine, "target", st->target);
    cJSON_AddNumberToObject(refine, "error_importance_passes", rf->error_passes);
    add_check_render(refine, st);
    cJSON *rounds = cJSON_AddArrayToObject(refine, "rounds");
    for (unsigned int k = 0; k < rf->round_count; k++) {
        const reduce_refine_round *r = &rf->rounds[k];
        cJSON *item = cJSON_CreateObject();
        cJSON_AddNumberToObject(item, "round", k);
        cJSON_AddNumberToObject(item, "mix", r->mix);
        cJSON_AddNumberToObject(item, "weighted_pixels", (double)r->weighted_pixels);
        cJSON_AddNumberToObject(item, "error", r->error);
        cJSON_AddNumberToObject(item, "standard_error", r->standard_error);
        cJSON_AddNumberToObject(item, "vertices", (double)r->vertices);
        cJSON_AddBoolToObject(item, "kept", r->kept);
        cJSON_AddNumberToObject(item, "seconds", r->seconds);
        cJSON_AddItemToArray(rounds, item);
    }
    const reduce_refine_round *chosen = &rf->rounds[rf->chosen], *first = &rf->rounds[0];
    cJSON_AddNumberToObject(refine, "chosen", rf->chosen);
    cJSON_AddNumberToObject(refine, "error", chosen->error);
    cJSON_AddNumberToObject(refine, "importance_only_error", first->error);
    if (first->error > 0)
        cJSON_AddNumberToObject(refine, "refined_over_importance", chosen->error / first->error);
    else
        cJSON_AddNullToObject(refine, "refined_over_importance");
    cJSON_AddNumberToObject(refine, "seconds", rf->seconds);
}

/* The error budget's search (null without --max-error): the bound, the check renders, the curve
 * walked (each step's D, vertices, paired error and standard error, seconds), the D chosen, and
 * the seconds of the search against those of the plain reduce at that D. */
static void add_error_budget(cJSON *root, const reduce_state *st)
{
    const reduce_error_options *o = &st->options->error;
    const reduce_error_state *e = &st->error_search;
    if (o->bound == REDUCE_ERROR_NONE) {
        cJSON_AddNullToObject(root, "error_budget");
        return;
    }
    cJSON *budget = cJSON_AddObjectToObject(root, "error_budget");
    cJSON_AddNumberToObject(budget, "max_error", e->max_error);
    if (o->bound == REDUCE_ERROR_RELATIVE)
        cJSON_AddNumberToObject(budget, "max_error_relative", o->max_error);
    else
        cJSON_AddNullToObject(budget, "max_error_relative");
    cJSON_AddNumberToObject(budget, "mean_radiance", e->mean_radiance);
    cJSON_AddStringToObject(budget, "criterion", "error + standard_error <= max_error");
    cJSON_AddNumberToObject(budget, "step", o->step);
    cJSON_AddNumberToObject(budget, "floor", e->floor);
    cJSON_AddNumberToObject(budget, "steps_failed_by_noise", e->noise_decided);
    add_check_render(budget, st);
    cJSON *curve = cJSON_AddArrayToObject(budget, "curve");
    error_search_seconds steps_total = {0};
    for (size_t k = 0; k < e->result.count; k++) {
        const error_search_step *s = &e->result.steps[k];
        steps_total.decimation += s->stages.decimation;
        steps_total.bvh += s->stages.bvh;
        steps_total.program += s->stages.program;
        steps_total.setup += s->stages.setup;
        steps_total.iterations += s->stages.iterations;
        steps_total.compare += s->stages.compare;
        cJSON *item = cJSON_CreateObject();
        cJSON_AddNumberToObject(item, "target", s->target);
        cJSON_AddNumberToObject(item, "vertices", (double)s->vertices);
        cJSON_AddNumberToObject(item, "error", s->error);
        cJSON_AddNumberToObject(item, "standard_error", s->standard_error);
        cJSON_AddNumberToObject(item, "mse", s->mse);
        cJSON_AddNumberToObject(item, "mse_standard_error", s->mse_standard_error);
        cJSON_AddBoolToObject(item, "measured", s->measured);
        cJSON_AddBoolToObject(item, "within", s->passes);
        cJSON_AddNumberToObject(item, "seconds", s->seconds);
        add_search_seconds(item, "seconds_by_stage", &s->stages);
        cJSON_AddItemToArray(curve, item);
    }
    const error_search_step *chosen = &e->result.steps[e->result.chosen];
    cJSON *result = cJSON_AddObjectToObject(budget, "chosen");
    cJSON_AddNumberToObject(result, "target", e->result.target);
    cJSON_AddNumberToObject(result, "vertices", (double)st->vertices_after);
    cJSON_AddNumberToObject(result, "error", chosen->error);
    cJSON_AddNumberToObject(result, "standard_error", chosen->standard_error);
    cJSON *seconds = cJSON_AddObjectToObject(budget, "seconds");
    cJSON_AddNumberToObject(seconds, "originals", e->seconds_originals);
    add_search_seconds(seconds, "originals_by_stage", &e->originals_stages);
    add_search_seconds(seconds, "steps_by_stage", &steps_total);
    cJSON_AddNumberToObject(seconds, "final_decimation", e->seconds_final_decimation);
    cJSON_AddNumberToObject(seconds, "search", e->seconds_search);
    /* What `reduce --target D` at the D found takes: the importance pass, one plan and
     * decimation (the chosen step's; at D = 1, measured by no step, the final one), the
     * writing. */
    double decimation = e->result.chosen ? chosen->stages.decimation : e->seconds_final_decimation;
    cJSON_AddNumberToObject(seconds, "plain_reduce",
                            st->seconds_importance + decimation + st->seconds_write);
}

/* The peaks of the run: the most device memory a pass allocated, and the process's resident
 * set (getrusage: the largest it has been). */
static void add_peaks(cJSON *root, const reduce_state *st)
{
    uint64_t device_peak = 0;
    for (unsigned int k = 0; k < st->pass_count; k++)
        if (st->passes[k].device_bytes > device_peak)
            device_peak = st->passes[k].device_bytes;
    struct rusage usage;
    double rss = getrusage(RUSAGE_SELF, &usage) == 0 ? (double)usage.ru_maxrss * 1024.0 : 0.0;
    cJSON_AddNumberToObject(root, "device_peak_bytes", (double)device_peak);
    cJSON_AddNumberToObject(root, "peak_rss_bytes", rss);
}

/* The stop rule on the decimation factors (factor_stop.h): its settings, where it stopped the
 * pass (null: it did not) and its checkpoints (changes null at the first, or with no importance
 * yet to plan from). */
static void add_stop_rule(cJSON *root, const reduce_state *st)
{
    cJSON *rule = cJSON_AddObjectToObject(root, "stop_rule");
    cJSON_AddNumberToObject(rule, "factor_tolerance", st->options->factor_tolerance);
    cJSON_AddNumberToObject(rule, "ranking_tolerance",
                            reduce_method_collapses(st->options->method) != DECIMATE_QUADRIC
                                ? st->options->ranking_tolerance
                                : 0.0);
    cJSON_AddNumberToObject(rule, "checkpoint_every", FACTOR_STOP_EVERY);
    cJSON_AddNumberToObject(rule, "calm_checkpoints", FACTOR_STOP_CALM);
    if (st->stopped_at)
        cJSON_AddNumberToObject(rule, "stopped_at_iteration", st->stopped_at);
    else
        cJSON_AddNullToObject(rule, "stopped_at_iteration");
    cJSON *list = cJSON_AddArrayToObject(rule, "checkpoints");
    for (size_t k = 0; k < st->checkpoint_count; k++) {
        const factor_checkpoint *c = &st->checkpoints[k];
        cJSON *item = cJSON_CreateObject();
        cJSON_AddNumberToObject(item, "iteration", c->iteration);
        if (c->factor_change >= 0) {
            cJSON_AddNumberToObject(item, "factor_change", c->factor_change);
            cJSON_AddNumberToObject(item, "ranking_change", c->ranking_change);
        } else {
            cJSON_AddNullToObject(item, "factor_change");
            cJSON_AddNullToObject(item, "ranking_change");
        }
        cJSON_AddItemToArray(list, item);
    }
}

/* report.json's content: the importance report's keys (method importance) or the scene name,
 * then the reduction's options, totals, seconds and per-mesh figures. The caller deletes it. */
static cJSON *report_json(const reduce_state *st)
{
    const reduce_options *o = st->options;
    cJSON *root = reduce_method_uses_importance(o->method)
                      ? importance_report_json(st->simulated, st->device, &o->importance,
                                               &st->importance)
                      : report_without_importance(st->scene);
    add_totals(root, st);
    if (o->simulation)
        cJSON_AddStringToObject(root, "simulation", o->simulation);
    else if (reduce_method_uses_importance(o->method))
        add_stop_rule(root, st);
    if (reduce_method_uses_importance(o->method))
        add_passes(root, st);
    add_memory(root, st);
    add_error_budget(root, st);
    add_refine(root, st);
    add_peaks(root, st);
    add_seconds(cJSON_GetObjectItem(root, "seconds"), st);
    cJSON *meshes = cJSON_GetObjectItem(root, "meshes");
    for (size_t m = 0; m < st->scene->mesh_count; m++)
        add_mesh(meshes, st, m);
    return root;
}

int reduce_report_write(const reduce_state *st)
{
    const reduce_options *o = st->options;
    cJSON *report = report_json(st);
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
    if (scene_is_pbrt(s))
        return "scene.pbrt";
    return scene_is_gltf(s) ? gltf_output_name(s->file) : "scene.xml";
}

void reduce_report_summary(const reduce_state *st)
{
    fprintf(stderr,
            "idmr: %llu -> %llu vertices (target %.4g: %llu), %zu of %zu meshes rewritten; "
            "reduced scene in %s/%s\n",
            (unsigned long long)st->plan.total_before, (unsigned long long)st->vertices_after,
            st->target, (unsigned long long)st->plan.total_requested, st->meshes_written,
            st->count, st->outdir, reduced_scene_name(st->scene));
}
