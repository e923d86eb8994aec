/* reduce_budget.c — the budget stage of `idmr reduce` (see reduce_stages.h): what each mesh is
 * decimated from, and the plan of Eq. 3 (budget.h) for st->target, from each mesh's vertices and
 * importance sum (methods with importance) or equal importance (the quadric baseline's uniform
 * D). The importance pass's stop rule makes its trial plans from the same entries
 * (reduce_budget_entry). */
#include <stdlib.h>

#include "core/error.h"
#include "core/progress.h"
#include "reduce/reduce_stages.h"

/* Mesh m as the plan of Eq. 3 sees it: its vertices as the scene holds them (so the totals
 * match what `idmr info` says of the input and of the reduced scene), and its importance sum
 * from `r` (methods with the importance pass), or equal importance for all, which gives the
 * uniform D of the quadric baseline. */
budget_mesh reduce_budget_entry(const reduce_state *st, const importance_result *r, size_t m)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    /* The importance sum of a mesh does not depend on how finely it is meshed: the simulated
     * scene's sum stands for the original's. */
    importance_weights weights = importance_weights_of(&o->importance);
    budget_mesh entry = {.name = s->meshes[m].name,
                         .vertices = s->meshes[m].vertex_count,
                         .pinned = reduce_instance_pinned(st, m),
                         .importance = 1.0};
    /* An instance's copy after its shape's first is planned through the first, with its
     * importance (reduce_instances.c): the written scene stores the prototype once. */
    if (reduce_instance_follower(st, m)) {
        entry.vertices = 0;
        entry.pinned = 0;
        entry.importance = 0.0;
    } else if (reduce_method_uses_importance(o->method)) {
        /* a representative's triangles are its prototype's: every copy's importance */
        entry.importance = importance_mesh_sums(r, st->simulated, m, &weights).amount;
    }
    return entry;
}

int reduce_plan_budget(reduce_state *st)
{
    const reduce_options *o = st->options;
    double start = monotonic_seconds();
    st->input = xcalloc(st->count + 1, sizeof *st->input);
    budget_mesh *budget = st->budget = xcalloc(st->count + 1, sizeof *budget);
    for (size_t m = 0; m < st->count; m++) {
        st->input[m] = reduce_decimation_input(st, m);
        budget[m] = reduce_budget_entry(st, &st->importance, m);
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

void reduce_budget_forget(reduce_state *st)
{
    free(st->input);
    free(st->budget);
    st->input = NULL;
    st->budget = NULL;
    budget_plan_free(&st->plan);
}

void reduce_budget_swap(reduce_state *st, reduce_held_decimation *held)
{
    REDUCE_SWAP(st->input, held->input);
    REDUCE_SWAP(st->budget, held->budget);
    REDUCE_SWAP(st->plan, held->plan);
}
