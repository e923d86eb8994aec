/* reduce_importance.c — the importance stage of `idmr reduce` (see reduce_stages.h): the
 * importance pass on the simulated scene, stopped once the decimation factors (and, where the
 * collapses follow importance, the vertex ranking) settle (factor_stop.h), or the saved pass
 * --simulation names (passes/importance_file.h); then each mesh's per-vertex importance, and,
 * with a collapse history, that importance copied back to the original vertices (reduce_remap).
 *
 * The stop rule's checkpoints make the plan of Eq. 3 from the importance so far, from the same
 * entries as the budget stage (reduce_budget_entry), and compare it with the last checkpoint's;
 * each is recorded in st->checkpoints for report.json. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "device/bvh.h"
#include "passes/importance_file.h"
#include "passes/importance_outputs.h"
#include "reduce/reduce_stages.h"

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
        c->budget[m] = reduce_budget_entry(st, r, m);
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
    options.sppm.device_budget = reduce_memory_device_limit(st);
    options.checkpoint_context = &c;
    bvh b;
    int status = bvh_build(s, &b);
    /* The host's copy is not needed once uploaded, unless --max-error renders this scene again
     * (the originals of its check renders: reduce_error_budget.c) */
    int keep = o->error.bound != REDUCE_ERROR_NONE && s == st->scene;
    options.sppm.release_bvh = keep ? NULL : &b;
    if (!status) {
        status = importance_run_devices(st->device, st->device_count, s, &b, &options,
                                        &st->importance);
        if (!status && keep && !st->error_search.has_original_bvh) {
            st->error_search.original_bvh = b;
            st->error_search.has_original_bvh = 1;
        } else {
            bvh_free(&b);
        }
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
int reduce_importance(reduce_state *st)
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

void reduce_importance_forget(reduce_state *st)
{
    importance_vertex_values_free(st->vertex_importance, st->simulated);
    st->vertex_importance = NULL;
    importance_result_free(&st->importance);
    free(st->checkpoints);
    st->checkpoints = NULL;
    st->checkpoint_count = 0;
    st->stopped_at = 0;
}
