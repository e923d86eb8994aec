/* factor_stop.h — when the importance pass of `idmr reduce` has learnt enough: once the
 * reduction it leads to has stopped changing, not when the importance itself has (that keeps
 * changing in triangles no decision depends on).
 *
 * Every FACTOR_STOP_EVERY iterations (a checkpoint) the reduction plans its budget (Eq. 3,
 * budget.h) from the importance so far, and compares it with the previous checkpoint's plan:
 *
 *   factor change   Σ_m |t_m − t'_m| / Σ_m t'_m      t_m: vertices planned for mesh m now,
 *                                                    t'_m: at the previous checkpoint
 *   the share of the vertex budget that moved between meshes (0: the same plan; at most 2).
 *   ranking change  1 − ρ, ρ Spearman's rank correlation of the per-vertex importance now and at
 *                   the previous checkpoint, over the vertices of the meshes the plan decimates
 *                   (ties take their mean rank; 0: the same order of collapses within meshes)
 *
 * The pass stops at the checkpoint where, at FACTOR_STOP_CALM checkpoints in a row, the factor
 * change has been below its tolerance (--factor-tolerance, default FACTOR_STOP_TOLERANCE: 1 % of
 * the budget) and, for the methods whose collapses follow the vertex importance (importance,
 * combined), the ranking change below its own (--ranking-tolerance, default
 * FACTOR_STOP_RANKING_TOLERANCE: ρ > 0.95). So it never stops before iteration
 * FACTOR_STOP_EVERY · (FACTOR_STOP_CALM + 1); --iterations is the cap. Both changes shrink as
 * the sums converge (about as 1/n between checkpoints a fixed number of iterations apart), so
 * the rule ends every pass. A factor tolerance of 0 turns the rule off; a ranking tolerance of 0
 * leaves the ranking out of it. */
#ifndef IDMR_FACTOR_STOP_H
#define IDMR_FACTOR_STOP_H

#include <stddef.h>
#include <stdint.h>

#define FACTOR_STOP_EVERY 5
#define FACTOR_STOP_CALM 2
#define FACTOR_STOP_TOLERANCE 0.01
#define FACTOR_STOP_RANKING_TOLERANCE 0.05

/* The factor change above between two plans of `count` meshes (before: t', after: t); 0 when
 * the earlier plan keeps no vertex. */
double factor_change(const uint64_t *before, const uint64_t *after, size_t count);

/* Ranks 1..n of `values` into `ranks`, ties at their mean rank. A checkpoint ranks its values
 * once and keeps the ranks for the next one to compare with. */
void mean_ranks(const double *values, size_t n, double *ranks);

/* The ranking change above between two rank lists of length n (mean_ranks()): 1 − Spearman's
 * ρ, in [0, 2]. 0 when n < 2 or when either list is all ties (no order to change). */
double ranking_change(const double *ranks_before, const double *ranks_after, size_t n);

/* The rule's state over the checkpoints of one pass. */
typedef struct factor_stop {
    double tolerance;         /* of the factor change; 0: never stops */
    double ranking_tolerance; /* of the ranking change; 0: not part of the rule */
    unsigned int calm;        /* checkpoints in a row below the tolerances */
    unsigned int checkpoints;
} factor_stop;

/* Records a checkpoint's changes; returns 1 when the pass should stop there. The first
 * checkpoint has nothing to compare with: pass negative changes for it (never calm). */
int factor_stop_update(factor_stop *rule, double factor_change, double ranking_change);

#endif
