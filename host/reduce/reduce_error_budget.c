/* reduce_error_budget.c — the error-budget stage of `idmr reduce --max-error E` (see
 * reduce_stages.h): after the one importance pass, the smallest target D whose reduced scene's
 * reduction error is at most E, found by error_search.h over decimations in memory, each
 * measured by rendering it; the state is left decimated at that D, so the write and report
 * stages write it exactly as `reduce --target D` would from the same importance.
 *
 * The measure (idmr compare --paired's, io/image_compare.h): the original (A) is rendered once
 * per seed, seeds 1 and 2, and kept; every reduced scene (B) is rendered with the same two seeds
 * and the same settings, and
 *     error = sqrt(max(0, mean((A1 - B1)(A2 - B2))))
 * with its standard error. Correlated sampling: A1 and B1 draw the same random numbers (the
 * generator is keyed by seed, iteration, pass and pixel or path, idmr/rng.h), so where the
 * geometry did not change their paths and noise are the same and cancel in A1 - B1; seed 2 is
 * independent of seed 1, so E[(A1 - B1)(A2 - B2)] = E[A1 - B1] E[A2 - B2] = (E[A] - E[B])²
 * still holds exactly: the correlation lowers the estimate's variance, never its mean. Every
 * render shares one first gather radius (the original's with seed 1), so a reduced geometry or
 * a seed cannot change the renderer's bias; only the scene differs between A and B.
 *
 * Check renders: the hit-point film at --check-resolution (default 0.25) of the scene's,
 * --check-iterations (16) of --check-photons (50,000) photon paths: sized for a CPU; the error
 * they measure is the change at that film size (the same at any size for what covers many
 * pixels; a change of a pixel or two is averaged into the larger pixels). They run on the first
 * device (st->device) whatever devices the importance pass shares. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "device/bvh.h"
#include "io/image_compare.h"
#include "passes/render.h"
#include "reduce/reduce_stages.h"

/* The seeds of the two renders of each scene. */
static const unsigned int CHECK_SEEDS[2] = {1, 2};

/* What the measure keeps across the steps. */
typedef struct search_context {
    reduce_state *st;
    float *original[2];    /* A1, A2 */
    double seconds_decimation; /* the last decimation's (budget and decimation) */
    reduce_held_decimation smallest_passing; /* the plan and decimation of the smallest D */
    double smallest_passing_target;          /* measured to pass (0: none yet) */
} search_context;

/* The check render's options for seed index k. */
static render_options check_options(const reduce_state *st, unsigned int k)
{
    const reduce_options *o = st->options;
    render_options r;
    render_options_default(&r);
    r.sppm.iterations = o->error.iterations;
    r.sppm.photons = o->error.photons;
    r.sppm.resolution = (float)o->error.resolution;
    r.sppm.seed = CHECK_SEEDS[k];
    r.sppm.radius = st->error_search.radius;
    r.sppm.local_size = o->importance.sppm.local_size;
    r.sppm.generic = o->importance.sppm.generic;
    r.sppm.progress = 0;
    return r;
}

int reduce_check_render_pair(reduce_state *st, const scene *s, const bvh *built,
                             float *images[2], error_search_seconds *stages)
{
    bvh own = {0};
    double start = monotonic_seconds();
    if (!built && bvh_build(s, &own))
        return -1;
    const bvh *b = built ? built : &own;
    stages->bvh += monotonic_seconds() - start;
    int status = 0;
    for (unsigned int k = 0; k < 2 && !status; k++) {
        render_options options = check_options(st, k);
        render_result r;
        double render_start = monotonic_seconds();
        status = render_run(st->device, s, b, &options, &r);
        double render_seconds = monotonic_seconds() - render_start;
        stages->program += r.sppm.seconds.build;
        stages->iterations += r.sppm.seconds.total;
        stages->setup += fmax(0.0, render_seconds - r.sppm.seconds.build - r.sppm.seconds.total);
        reduce_error_state *e = &st->error_search;
        if (!status && e->width && (r.sppm.width != e->width || r.sppm.height != e->height))
            status = error_set(IDMR_EXIT_FAILURE, "--max-error: a check render of the reduced "
                                                  "scene is %ux%u, the original's %ux%u",
                               r.sppm.width, r.sppm.height, e->width, e->height);
        if (!status) {
            if (!(e->radius > 0))
                e->radius = r.sppm.radius[0];
            e->width = r.sppm.width;
            e->height = r.sppm.height;
            images[k] = r.image;
            r.image = NULL;
        }
        render_result_free(&r);
    }
    bvh_free(&own);
    return status;
}

/* The budget and the decimation at fraction D, what they left before forgotten. */
static int decimate_at(search_context *c, double target)
{
    reduce_state *st = c->st;
    double before = st->seconds_budget + st->seconds_decimation;
    reduce_decimation_forget(st);
    reduce_budget_forget(st);
    st->target = target;
    if (reduce_plan_budget(st) || reduce_decimation(st))
        return -1;
    c->seconds_decimation = st->seconds_budget + st->seconds_decimation - before;
    return 0;
}

/* error_search_measure: the scene decimated to D, rendered with both seeds, against the
 * original's renders. */
static int measure(double target, error_search_step *step, void *context)
{
    search_context *c = context;
    reduce_state *st = c->st;
    double start = monotonic_seconds();
    if (decimate_at(c, target))
        return -1;
    step->stages.decimation = c->seconds_decimation;
    scene *reduced = reduce_view_of(st, st->output);
    if (!reduced)
        return -1;
    float *images[2] = {NULL, NULL};
    int status = reduce_check_render_pair(st, reduced, NULL, images, &step->stages);
    scene_view_free(reduced);
    if (!status) {
        double compare_start = monotonic_seconds();
        image_paired_error paired;
        image_paired_error_of(c->original[0], c->original[1], images[0], images[1],
                              (int)st->error_search.width, (int)st->error_search.height, 0,
                              &paired);
        step->vertices = st->vertices_after;
        step->error = paired.rmse;
        step->standard_error = paired.rmse_standard_error;
        step->mse = paired.mse;
        step->mse_standard_error = paired.mse_standard_error;
        step->stages.compare = monotonic_seconds() - compare_start;
    }
    free(images[0]);
    free(images[1]);
    step->seconds = monotonic_seconds() - start;
    int passes = step->error + step->standard_error <= st->error_search.max_error;
    /* The search's answer is its smallest passing D: that one's plan and decimation are kept
     * (deterministic: what decimating at that D again would give), not made again at the end. */
    if (!status && passes &&
        (!c->smallest_passing_target || target < c->smallest_passing_target)) {
        reduce_hold_decimation(st, &c->smallest_passing);
        c->smallest_passing_target = target;
    }
    if (!status && st->options->importance.sppm.progress) {
        fprintf(stderr, "idmr: max-error: D=%.4g (%llu vertices) error=%.4g \u00b1 %.2g (%s E "
                        "%.4g) %.1f s\n",
                target, (unsigned long long)step->vertices, step->error, step->standard_error,
                passes ? "\u2264" : ">", st->error_search.max_error, step->seconds);
    }
    return status;
}

/* The smallest D the plan can ask for: every mesh that can be decimated at --min-vertices,
 * the others whole. */
static double search_floor(const reduce_state *st)
{
    double total = 0, least = 0;
    for (size_t m = 0; m < st->count; m++) {
        if (reduce_instance_follower(st, m))
            continue; /* the plan counts a prototype once (reduce_instances.c) */
        double v = (double)st->scene->meshes[m].vertex_count;
        total += v;
        least += reduce_decimatable(st, m) ? fmin(v, (double)st->options->min_vertices) : v;
    }
    return total > 0 ? fmin(1.0, fmax(least, 1.0) / total) : 1.0;
}

/* The steps below the D found whose error alone is within E but error + standard error is
 * not: the noise of the check renders, not the change, failed them, and kept vertices. */
static unsigned int noise_decided(const error_search_result *r, double max_error)
{
    unsigned int count = 0;
    for (size_t k = 1; k < r->count; k++) {
        const error_search_step *s = &r->steps[k];
        count += !s->passes && s->error <= max_error && s->target < r->target;
    }
    return count;
}

/* The mean of the original's two renders over pixels and channels. */
static double mean_radiance(const search_context *c, size_t values)
{
    double sum = 0;
    for (size_t i = 0; i < values; i++)
        sum += 0.5 * ((double)c->original[0][i] + (double)c->original[1][i]);
    return values ? sum / (double)values : 0.0;
}

/* The BVH kept from the importance pass for the originals, freed. */
static void forget_original_bvh(reduce_state *st)
{
    if (st->error_search.has_original_bvh)
        bvh_free(&st->error_search.original_bvh);
    st->error_search.has_original_bvh = 0;
}

int reduce_error_budget(reduce_state *st)
{
    const reduce_options *o = st->options;
    reduce_error_state *e = &st->error_search;
    double start = monotonic_seconds();
    search_context c = {.st = st};
    memset(&e->originals_stages, 0, sizeof e->originals_stages);
    int verbose = o->importance.sppm.progress;
    if (verbose)
        fprintf(stderr, "idmr: max-error: rendering the original (seeds 1 and 2, %u iterations "
                        "of %u photon paths, film scale %g)\n",
                o->error.iterations, o->error.photons, o->error.resolution);
    int status = reduce_check_render_pair(st, st->scene, e->has_original_bvh ? &e->original_bvh : NULL,
                             c.original, &e->originals_stages);
    forget_original_bvh(st);
    e->seconds_originals = monotonic_seconds() - start;
    if (!status) {
        size_t values = 3 * (size_t)e->width * e->height;
        e->mean_radiance = mean_radiance(&c, values);
        e->max_error = o->error.bound == REDUCE_ERROR_RELATIVE
                           ? o->error.max_error * e->mean_radiance
                           : o->error.max_error;
        e->floor = search_floor(st);
        status = error_search_run(e->max_error, o->error.step, e->floor, measure, &c,
                                  &e->result);
    }
    /* The state decimated at the D found, what the write stage writes as `reduce --target D`
     * would: the kept decimation of the smallest passing step, or (D = 1, no step passed) a
     * decimation made now. */
    double final_start = monotonic_seconds();
    if (!status && c.smallest_passing_target == e->result.target) {
        reduce_restore_decimation(st, &c.smallest_passing);
        st->target = e->result.target;
    } else if (!status) {
        status = decimate_at(&c, e->result.target);
    }
    double final_seconds = monotonic_seconds() - final_start;
    reduce_held_decimation_free(st, &c.smallest_passing);
    if (!status) {
        e->result.steps[0].vertices = st->plan.total_before;
        e->noise_decided = noise_decided(&e->result, e->max_error);
        if (e->noise_decided && e->max_error > 0) /* at E = 0 only no change passes */
            warn("--max-error: %u of %zu steps below the D found failed by their standard "
                 "error alone (error within E %.4g, error + standard error above it): the "
                 "check renders' noise, not the change, kept vertices; more "
                 "--check-iterations or --check-photons may allow fewer",
                 e->noise_decided, e->result.count - 1, e->max_error);
        e->seconds_final_decimation = final_seconds;
        if (verbose) {
            const error_search_step *chosen = &e->result.steps[e->result.chosen];
            fprintf(stderr, "idmr: max-error: D=%.4g (%llu vertices) is the smallest within E "
                            "%.4g after %zu steps (error %.4g \u00b1 %.2g)\n",
                    e->result.target, (unsigned long long)st->vertices_after, e->max_error,
                    e->result.count - 1, chosen->error, chosen->standard_error);
        }
    }
    free(c.original[0]);
    free(c.original[1]);
    e->seconds_search = monotonic_seconds() - start;
    return status;
}

void reduce_error_budget_free(reduce_state *st)
{
    forget_original_bvh(st);
    error_search_result_free(&st->error_search.result);
}
