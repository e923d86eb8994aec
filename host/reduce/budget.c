/* budget.c — decimation factors across meshes (paper Eq. 3); the semantics are in budget.h.
 *
 * Working data: the free meshes (not pinned, more vertices than their floor) are listed in
 * free_meshes.index[] (free_index[] in the steps), with their floors f_i in floor_of[] (indexed
 * by mesh); the first active_count entries of active[] are those still being scaled, each with
 * its weight (importance / maximum importance, or 1 for equal factors) and its real-valued
 * planned count x = λ · weight · v. A mesh leaves active[] when it is fixed at its ceiling v or
 * its floor f_i; settled is the sum of the targets of every mesh no longer active.
 *
 * budget_distribute(): check the arguments, V_D, the free meshes, then either nothing to do,
 * every free mesh at its floor (infeasible), or weights → solve_factors() → round_targets();
 * finally decimate and factor per mesh. */
#include "reduce/budget.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

static const char *mesh_name(const budget_mesh *mesh)
{
    return mesh->name ? mesh->name : "(unnamed)";
}

/* One free mesh during the integer step: its real-valued count and the index it came from. */
typedef struct budget_share {
    double remainder; /* x - floor(x) */
    size_t mesh;
} budget_share;

/* Largest remainder first; equal remainders in mesh order, so the plan is deterministic. */
static int compare_shares(const void *a, const void *b)
{
    const budget_share *sa = a, *sb = b;
    if (sa->remainder != sb->remainder)
        return sa->remainder > sb->remainder ? -1 : 1;
    return sa->mesh < sb->mesh ? -1 : sa->mesh > sb->mesh;
}

void budget_plan_free(budget_plan *plan)
{
    if (!plan)
        return;
    free(plan->target);
    free(plan->factor);
    free(plan->decimate);
    memset(plan, 0, sizeof *plan);
}

/* Runs the clamp-and-renormalise rounds over the free meshes; fills x[] (indexed by mesh) with
 * the real-valued planned count of every free mesh. */
static void solve_factors(const budget_mesh *meshes, const size_t *free_index, size_t free_count,
                          double *weight, double *x, uint64_t requested, uint64_t settled,
                          const uint64_t *floor_of, budget_plan *plan)
{
    size_t *active = xmalloc(free_count * sizeof *active);
    memcpy(active, free_index, free_count * sizeof *active);
    size_t active_count = free_count;

    while (active_count > 0) {
        double budget = settled < requested ? (double)(requested - settled) : 0.0;
        double weighted = 0.0;
        for (size_t k = 0; k < active_count; k++)
            weighted += weight[active[k]] * (double)meshes[active[k]].vertices;
        if (weighted == 0.0) {
            /* The meshes with importance are all at their ceilings and budget is left: the
             * zero-importance ones share it with equal factors. */
            for (size_t k = 0; k < active_count; k++) {
                weight[active[k]] = 1.0;
                weighted += (double)meshes[active[k]].vertices;
            }
        }
        plan->rounds++;
        double lambda = budget / weighted;

        double excess = 0.0, deficit = 0.0;
        for (size_t k = 0; k < active_count; k++) {
            size_t i = active[k];
            double ceiling = (double)meshes[i].vertices;
            x[i] = lambda * weight[i] * ceiling;
            if (x[i] > ceiling)
                excess += x[i] - ceiling;
            else if (x[i] < (double)floor_of[i])
                deficit += (double)floor_of[i] - x[i];
        }
        if (excess == 0.0 && deficit == 0.0)
            break;

        /* Fix the side with the larger violation: if the ceilings overshoot more than the
         * floors undershoot, the final scale is larger than this one and those meshes stay at
         * their ceilings; otherwise it is smaller and the others stay at their floors. */
        int fix_ceiling = excess >= deficit, fix_floor = deficit >= excess;
        size_t kept = 0;
        for (size_t k = 0; k < active_count; k++) {
            size_t i = active[k];
            double ceiling = (double)meshes[i].vertices;
            if (fix_ceiling && x[i] > ceiling) {
                x[i] = ceiling;
                settled += meshes[i].vertices;
            } else if (fix_floor && x[i] < (double)floor_of[i]) {
                x[i] = (double)floor_of[i];
                settled += floor_of[i];
            } else {
                active[kept++] = i;
            }
        }
        active_count = kept;
    }
    free(active);
}

/* Turns the real-valued counts x[] of the free meshes into integer targets whose sum, with
 * `settled` (the fixed meshes), is `requested` when the bounds allow it. */
static void round_targets(const budget_mesh *meshes, const size_t *free_index, size_t free_count,
                          const double *x, const uint64_t *floor_of, uint64_t requested,
                          uint64_t settled, uint64_t *target)
{
    budget_share *shares = xmalloc(free_count * sizeof *shares);
    uint64_t planned = settled;
    for (size_t k = 0; k < free_count; k++) {
        size_t i = free_index[k];
        uint64_t ceiling = meshes[i].vertices;
        double whole = floor(x[i]);
        uint64_t t;
        if (!(whole >= (double)floor_of[i]))
            t = floor_of[i];
        else if (whole >= (double)ceiling)
            t = ceiling;
        else
            t = (uint64_t)whole;
        target[i] = t;
        planned += t;
        double remainder = x[i] - whole;
        shares[k].remainder = remainder > 0.0 && remainder < 1.0 ? remainder : 0.0;
        shares[k].mesh = i;
    }
    qsort(shares, free_count, sizeof *shares, compare_shares);

    /* One vertex each to the largest remainders; a second pass takes up whatever rounding of
     * large counts in double left over (never more than a few vertices in practice). */
    for (int pass = 0; pass < 2 && planned < requested; pass++) {
        for (size_t k = 0; k < free_count && planned < requested; k++) {
            size_t i = shares[k].mesh;
            uint64_t room = meshes[i].vertices - target[i];
            uint64_t give = pass == 0 ? (room > 0) : (room < requested - planned ? room : requested - planned);
            target[i] += give;
            planned += give;
        }
    }
    for (int pass = 0; pass < 2 && planned > requested; pass++) {
        for (size_t k = free_count; k-- > 0 && planned > requested;) {
            size_t i = shares[k].mesh;
            uint64_t room = target[i] - floor_of[i];
            uint64_t take = pass == 0 ? (room > 0) : (room < planned - requested ? room : planned - requested);
            target[i] -= take;
            planned -= take;
        }
    }
    free(shares);
}

/* The free meshes (not pinned, more vertices than their floor): their indices, their floors
 * (floor_of, indexed by mesh), the sum of those floors, the vertices of the fixed ones (settled)
 * and the largest free importance. */
typedef struct free_meshes {
    size_t *index;
    uint64_t *floor_of;
    size_t count;
    uint64_t floors;
    uint64_t settled;
    double max_importance;
} free_meshes;

/* Checks the arguments after the plan pointer; *total = Σ v. */
static int check_meshes(const budget_mesh *meshes, size_t count, double target_fraction,
                        uint64_t *total)
{
    if (count > 0 && !meshes)
        return error_set(IDMR_EXIT_INPUT, "budget: %zu meshes given but no mesh array", count);
    if (!(target_fraction > 0.0 && target_fraction <= 1.0))
        return error_set(IDMR_EXIT_INPUT,
                         "budget: the decimation factor D = %g is outside (0, 1]", target_fraction);
    uint64_t sum = 0;
    for (size_t i = 0; i < count; i++) {
        double importance = meshes[i].importance;
        if (!isfinite(importance) || importance < 0.0)
            return error_set(IDMR_EXIT_INPUT,
                             "budget: mesh '%s' (index %zu) has importance %g; it must be "
                             "finite and >= 0", mesh_name(&meshes[i]), i, importance);
        if (meshes[i].vertices > UINT64_MAX - sum)
            return error_set(IDMR_EXIT_INPUT,
                             "budget: the vertex count overflows 64 bits at mesh '%s' (index %zu)",
                             mesh_name(&meshes[i]), i);
        sum += meshes[i].vertices;
    }
    *total = sum;
    return 0;
}

/* V_D = round(D · Σ v); D <= 1, but the product of large totals may round above Σ v. */
static uint64_t requested_vertices(double target_fraction, uint64_t total)
{
    double product = floor(target_fraction * (double)total + 0.5);
    if (product >= (double)total)
        return total;
    return (uint64_t)product;
}

static free_meshes collect_free_meshes(const budget_mesh *meshes, size_t count,
                                       uint64_t min_vertices)
{
    free_meshes free_set = {xmalloc((count + 1) * sizeof *free_set.index),
                            xcalloc(count + 1, sizeof *free_set.floor_of), 0, 0, 0, 0.0};
    for (size_t i = 0; i < count; i++) {
        uint64_t floor = meshes[i].floor > min_vertices ? meshes[i].floor : min_vertices;
        if (meshes[i].pinned || meshes[i].vertices <= floor) {
            free_set.settled += meshes[i].vertices;
            continue;
        }
        free_set.index[free_set.count++] = i;
        free_set.floor_of[i] = floor;
        free_set.floors += floor; /* each below its mesh's count: no overflow */
        if (meshes[i].importance > free_set.max_importance)
            free_set.max_importance = meshes[i].importance;
    }
    return free_set;
}

/* Each free mesh's weight: its importance over the largest, or 1 for all (with one warning)
 * when the free meshes have no importance at all. */
static void free_weights(const budget_mesh *meshes, const free_meshes *free_set, uint64_t total,
                         uint64_t requested, double *weight, budget_plan *plan)
{
    if (free_set->max_importance > 0.0) {
        for (size_t k = 0; k < free_set->count; k++) {
            size_t i = free_set->index[k];
            weight[i] = meshes[i].importance / free_set->max_importance;
        }
        return;
    }
    for (size_t k = 0; k < free_set->count; k++)
        weight[free_set->index[k]] = 1.0;
    plan->uniform_fallback = 1;
    uint64_t free_vertices = total - free_set->settled;
    warn("the %zu meshes to decimate have zero total importance; decimating them "
         "uniformly (factor %.4g) instead of by importance",
         free_set->count, (double)(requested - free_set->settled) / (double)free_vertices);
}

/* The targets of the free meshes when the budget is feasible: clamp-and-renormalise factors,
 * then whole vertices by the largest remainder. */
static void plan_free_meshes(const budget_mesh *meshes, size_t count, const free_meshes *free_set,
                             uint64_t total, uint64_t requested, budget_plan *plan)
{
    double *weight = xmalloc(count * sizeof *weight);
    double *x = xmalloc(count * sizeof *x);
    free_weights(meshes, free_set, total, requested, weight, plan);
    solve_factors(meshes, free_set->index, free_set->count, weight, x, requested,
                  free_set->settled, free_set->floor_of, plan);
    round_targets(meshes, free_set->index, free_set->count, x, free_set->floor_of, requested,
                  free_set->settled, plan->target);
    free(x);
    free(weight);
}

/* decimate, factor and total_planned from the targets. */
static void finish_plan(const budget_mesh *meshes, size_t count, budget_plan *plan)
{
    uint64_t planned = 0;
    for (size_t i = 0; i < count; i++) {
        uint64_t v = meshes[i].vertices;
        planned += plan->target[i];
        plan->decimate[i] = plan->target[i] < v;
        plan->factor[i] = plan->decimate[i] ? (double)plan->target[i] / (double)v : 1.0;
        CHECK_FINITE(plan->factor[i], "decimation factor");
    }
    plan->total_planned = planned;
}

int budget_distribute(const budget_mesh *meshes, size_t count, double target_fraction,
                      uint64_t min_vertices, budget_plan *plan)
{
    if (!plan)
        return error_set(IDMR_EXIT_INPUT, "budget: no plan to fill");
    memset(plan, 0, sizeof *plan);
    uint64_t total = 0;
    if (check_meshes(meshes, count, target_fraction, &total))
        return -1;
    uint64_t requested = requested_vertices(target_fraction, total);
    plan->target = xcalloc(count, sizeof *plan->target);
    plan->factor = xcalloc(count, sizeof *plan->factor);
    plan->decimate = xcalloc(count, sizeof *plan->decimate);
    plan->total_before = total;
    plan->total_requested = requested;
    for (size_t i = 0; i < count; i++)
        plan->target[i] = meshes[i].vertices;

    free_meshes free_set = collect_free_meshes(meshes, count, min_vertices);
    if (requested == total || free_set.count == 0) {
        /* Nothing to decimate: every mesh keeps its vertices. */
    } else if (free_set.settled + free_set.floors >= requested) {
        /* Infeasible (or exactly at the floors): every free mesh at its floor. */
        for (size_t k = 0; k < free_set.count; k++)
            plan->target[free_set.index[k]] = free_set.floor_of[free_set.index[k]];
    } else {
        plan_free_meshes(meshes, count, &free_set, total, requested, plan);
    }
    free(free_set.index);
    free(free_set.floor_of);

    finish_plan(meshes, count, plan);
    log_verbose("budget: %zu meshes, %zu free, %llu of %llu vertices requested, %llu planned "
                "(%u rounds%s)", count, free_set.count, (unsigned long long)requested,
                (unsigned long long)total, (unsigned long long)plan->total_planned, plan->rounds,
                plan->uniform_fallback ? ", uniform fallback" : "");
    return 0;
}
