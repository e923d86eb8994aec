/* error_search.h — the search behind `idmr reduce --max-error E`: the smallest vertex fraction D
 * whose reduced scene changes the image by at most E, from a measure that a caller supplies (the
 * reduction stage decimates to D and renders: reduce_error_budget.c). Pure logic, no rendering,
 * so a test can drive it with a curve written by hand.
 *
 * The error falls, roughly, as D grows, and is 0 at D = 1 (nothing removed: no measure is made
 * there). A step *passes* when its error plus its standard error is at most E: a measured error
 * that is only within E by its noise does not count, so the result errs on the side of more
 * vertices.
 *
 * The search measures the verdict's value u = error + standard error and models it between two
 * measured steps as a line in (log D, log u) (the error falls roughly as a power of D), or in
 * (log D, u) where one end is D = 1 (u = 0):
 *
 *   bracket   from hi = 1 down while the steps pass, to the floor at most: the first step to
 *             hi / ERROR_SEARCH_BRACKET, each later one to half a step below where the line
 *             through the last two passing steps (D = 1 among them) crosses E, so that a failure
 *             there brackets the crossing within about a step; at most ERROR_SEARCH_FIRST_JUMP
 *             down on the line from D = 1 (linear in u, which a power law outruns: it aims too
 *             deep) and ERROR_SEARCH_LONGEST_JUMP on the others, and at least a step down,
 *             doubled (in log D) by each pass, so that a line that keeps stopping short gallops
 *             (ERROR_SEARCH_BRACKET down, within those bounds, where the line does not fall). A
 *             deep step costs more than a shallow one (the decimation takes more collapses, and
 *             meshes meeting their floors start rounds that plan again), so the bracket does not
 *             go deeper than the line asks. The first step that fails is lo. A floor that passes
 *             ends the search there (a huge E).
 *   narrow    on log D between lo and hi: half a step above where the line through lo and hi
 *             crosses E (a pass there, then a failure a step below, end the search), kept
 *             (nearly) a step inside both ends; the geometric mean sqrt(lo · hi) instead where
 *             that line does not fall, where the bracket is within two steps, and where the
 *             last two steps did not halve it (so it halves at least every three steps). A
 *             pass lowers hi, a failure raises lo, until hi / lo <= 1 + step.
 *
 * Where each step goes changes only how many steps are measured, not what the result means:
 * it is hi, the smallest D measured to pass, with a failing D below it within one step (or the
 * floor, or 1 when every measured D failed). The error need not fall monotonically (noise, a
 * budget that moves a glint): the search trusts the bracket it holds, as any bisection does,
 * and every step it measured is in the curve. */
#ifndef IDMR_ERROR_SEARCH_H
#define IDMR_ERROR_SEARCH_H

#include <stddef.h>
#include <stdint.h>

/* How far each bracketing step goes down in D. */
#define ERROR_SEARCH_BRACKET 4.0
/* The most a bracketing step goes down from the smallest passing D: on the line from D = 1
 * (linear in u, which a power law outruns, so the line overshoots), and on the others. */
#define ERROR_SEARCH_FIRST_JUMP 16.0
#define ERROR_SEARCH_LONGEST_JUMP 64.0
/* The most steps measured; bracketing and bisection within 10 % from 1 to 1e-9 take 31. */
#define ERROR_SEARCH_MAX_STEPS 64

/* Where a measure's seconds went (the check renders' two seeds added up). */
typedef struct error_search_seconds {
    double decimation; /* the plan (Eq. 3) and the decimation at D */
    double bvh;        /* the BVH of the scene rendered */
    double program;    /* the renders' program builds (or program cache loads) */
    double setup;      /* the rest of the renders outside their iterations: upload, buffers */
    double iterations; /* the renders' iterations */
    double compare;    /* the paired error of the images */
} error_search_seconds;

/* One point of the curve walked. */
typedef struct error_search_step {
    double target;         /* D */
    uint64_t vertices;     /* of the reduced scene (the measure fills it) */
    double error;          /* reduction RMSE, noise cancelled (0 at D = 1) */
    double standard_error; /* its standard error */
    double mse, mse_standard_error; /* the mean squared change behind it (may be < 0) */
    double seconds;        /* the measure's: decimation and renders */
    error_search_seconds stages; /* seconds by stage (the measure fills it; may stay 0) */
    int measured;          /* 0 for D = 1, which needs no render */
    int passes;            /* error + standard_error <= max_error */
} error_search_step;

/* Measures the reduced scene at fraction `target`: fills step->vertices, error, standard_error,
 * mse, mse_standard_error, seconds (the search sets target, measured and passes). 0, or -1 with
 * the error set (the search stops and returns -1). */
typedef int (*error_search_measure)(double target, error_search_step *step, void *context);

typedef struct error_search_result {
    double target;            /* the D found */
    size_t chosen;            /* its index in steps */
    error_search_step *steps; /* in the order measured; steps[0] is D = 1 */
    size_t count;
} error_search_result;

/* Searches D in [floor, 1] for the bound max_error (>= 0) to within `step` (> 0: a ratio of
 * 1 + step between the failing and the passing D at the end). floor >= 1 ends at D = 1 without
 * a measure. Returns 0 with *out filled (free with error_search_result_free()), or -1 with the
 * error set: IDMR_EXIT_INPUT for a bad max_error, step or floor (negative, NaN), or the
 * measure's failure. */
int error_search_run(double max_error, double step, double floor, error_search_measure measure,
                     void *context, error_search_result *out);
void error_search_result_free(error_search_result *r);

#endif
