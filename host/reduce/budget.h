/* budget.h — decimation factors across meshes (paper section 3.6, Eq. 3): how many vertices
 * each mesh keeps so that the scene as a whole keeps the fraction D of its vertices, and the
 * meshes with more (unnormalised) importance keep more of theirs.
 *
 * The plan, for meshes i with v_i vertices and importance sums I_i:
 *
 *   V_D = round(D · Σ v_i)                                        the requested total
 *
 *   Fixed meshes keep all their vertices and their count is taken from the budget: pinned ones
 *   (emitters, meshes the user keeps), those with v_i <= min_vertices (this includes empty
 *   meshes) and those whose own floor is v_i or more. The other meshes are free; each has the
 *   floor f_i = max(min_vertices, its own floor) and the ceiling v_i. A mesh's own floor is
 *   what the caller knows it cannot go below (the reduction learns it from a decimation that
 *   ran out of legal collapses), so the budget such a mesh cannot use goes to the others, by
 *   importance.
 *
 *   Continuous factors (Eq. 3 with clamping, "clamp and renormalise"): the free meshes start
 *   with d_i = I_i and are scaled by one factor so that Σ v_i d_i = V_D - Σ fixed (the
 *   remaining budget). A mesh with d_i > 1 is clamped to 1, one planned below its floor is
 *   raised to it; either way it becomes fixed, and the rest are renormalised; repeat until no
 *   mesh is out of bounds. When a round has meshes out of bounds on both sides, only one side
 *   is fixed: the one with the larger total violation (both if equal). Fixing that side is
 *   always right (the others move back towards their bounds), so the result is the unique
 *   d_i = clamp(λ I_i, f_i / v_i, 1) with Σ v_i d_i equal to the remaining budget, and
 *   there are at most as many rounds as free meshes. With min_vertices == 0 this is exactly
 *   the paper's procedure (only clamps at 1).
 *
 *   Zero importance: if the free meshes have no importance at all, every free mesh gets the
 *   same factor (uniform D over what the fixed meshes leave), uniform_fallback is set and one
 *   warning is printed. Otherwise a mesh with I_i == 0 goes to its floor; only if the meshes
 *   with importance are all clamped to 1 and budget is still left do the zero-importance meshes
 *   share it with equal factors (no warning: nothing is wrong then).
 *
 *   Integer targets: the remaining budget is split over the free meshes by the largest
 *   remainder method (each gets floor(v_i d_i); the leftover vertices go one each to the
 *   largest fractional parts, ties to the lower index), so Σ target == V_D exactly whenever
 *   that is feasible, i.e. Σ fixed + Σ f_i <= V_D (V_D <= Σ v_i always holds). When it is
 *   not (D near 0 with large pinned meshes), every free mesh is planned at its floor, the
 *   closest possible plan, and total_planned > total_requested says by how much it misses;
 *   no warning is printed (the caller reports it).
 *
 *   If V_D == Σ v_i (D == 1, or D so close to 1 that it rounds there), nothing is decimated.
 *
 * Everything is computed in double and uint64_t; importance is scaled by its maximum first, so
 * no value overflows and none is NaN. Cost: O(n) per round, at most n rounds, one sort. */
#ifndef IDMR_BUDGET_H
#define IDMR_BUDGET_H

#include <stddef.h>
#include <stdint.h>

typedef struct budget_mesh {
    const char *name;  /* for messages; may be NULL */
    uint64_t vertices; /* v_i */
    double importance; /* unnormalised importance sum of the mesh (>= 0, finite) */
    int pinned;        /* never decimated: emitters, meshes the user keeps (--keep NAME) */
    uint64_t floor;    /* vertices the mesh cannot go below (0: only min_vertices applies) */
} budget_mesh;

typedef struct budget_plan {
    uint64_t *target;         /* per mesh: vertices to keep (== vertices when not decimated) */
    double *factor;           /* per mesh: target / vertices (1 when not decimated or empty) */
    int *decimate;            /* per mesh: 1 if it is to be decimated (target < vertices) */
    uint64_t total_before;    /* Σ v_i */
    uint64_t total_requested; /* V_D = round(D · Σ v_i) */
    uint64_t total_planned;   /* Σ target; != total_requested only when infeasible */
    int uniform_fallback;     /* the free meshes had zero total importance: uniform factors used */
    unsigned int rounds;      /* normalisations (Eq. 3) done; 0 when nothing was to be decimated */
} budget_plan;

/* Plans the vertex targets of `count` meshes for the scene fraction target_fraction (D, in
 * (0, 1]) with the floor min_vertices for every mesh and each mesh's own (see above). meshes
 * may be NULL if count is 0.
 * Returns 0 with *plan filled (free it with budget_plan_free()), or -1 with the error set
 * (IDMR_EXIT_INPUT) for bad arguments: D outside (0, 1] or NaN, an importance that is NaN,
 * infinite or negative, a vertex total that overflows 64 bits. On failure *plan is zeroed. */
int budget_distribute(const budget_mesh *meshes, size_t count, double target_fraction,
                      uint64_t min_vertices, budget_plan *plan);

/* Frees the arrays of a plan and zeroes it; a zeroed plan or NULL is fine. */
void budget_plan_free(budget_plan *plan);

#endif
