/* reduce_refine.c — the refine stage of `idmr reduce --refine N` (see reduce_stages.h):
 * error-driven refinement of a reduction at its target D.
 *
 * The importance pass spends vertices where the camera and the light paths it sees meet; it does
 * not know where removing them changes the image. After the first reduction (round 0) the check
 * renders of reduce_error_budget.c say where it did: the original (A) and the reduced scene (B),
 * seeds 1 and 2, correlated (the same random numbers for A1 and B1), per pixel the paired change
 * (A1 - B1)(A2 - B2), noise-cancelled, tile-averaged and clamped into integer pixel weights
 * (refine_weights.h). With them as its pixel weights the importance pass runs again on the
 * original scene, at the check renders' film (passes/importance.h: pixel_weights): only hit
 * points of changed pixels count, for their camera importance and for the photons they gather,
 * so the triangles that caused the change get importance whether the camera sees them or they
 * light what it sees (caustics, indirect light). That error importance E(T) is mixed into the
 * importance A(T) that round 0 was decimated from:
 *     A'(T) = A(T) + λ (Σ A / Σ E) E(T)       (sums over the meshes that may be decimated)
 * so that at λ = 1 the error importance would carry as much as the importance did (the first
 * round takes λ = REFINE_MIX, a fifth of the budget following E); the budget of
 * Eq. 3 and the per-vertex importance move with it. The scene is decimated again at the same D
 * and measured. A round whose error is below the best so far by more than its standard error
 * (error + standard error < the best's error: the check renders' noise alone does not choose)
 * is kept, and the next round takes its weights from its change; a round that is not kept
 * halves λ and tries again from the best (its error importance reused). After N rounds (or once
 * no pixel's change stands above the noise) the best round's decimation, kept aside while later
 * rounds decimate (reduce_held_decimation), is put back, so the result's measured error is never
 * above round 0's. The error importance goes into the light importance sums (report.json's
 * importance outputs show the mixed importance). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "device/bvh.h"
#include "io/image_compare.h"
#include "passes/importance_outputs.h"
#include "reduce/reduce_stages.h"
#include "reduce/refine_weights.h"

/* The first round's λ. At 1 (half the budget following the error importance, which is measured
 * only where the check renders saw a change) the living room's check error doubled (D = 0.03)
 * and the three dragons' rose (D = 0.01); at 0.25 the living room's fell, the three dragons'
 * rose least, and the dragon box, which gained most at 1, still gained (README, "Refining a
 * reduction by its measured change"). */
#define REFINE_MIX 0.25
/* Round 0's check renders see the change too faintly to refine by when its standard error is
 * above this share of the error: a warning names the options that sharpen them. */
#define REFINE_FAINT_SHARE 0.5
/* The change is averaged over tiles of this many pixels across (at the check film). */
#define REFINE_TILE 4u
/* The largest pixel weight (at most IMPORTANCE_PIXEL_WEIGHT_MAX). */
#define REFINE_MAX_WEIGHT 64u

typedef struct refine_context {
    reduce_state *st;
    bvh original_bvh;
    float *original[2];  /* A1, A2 */
    float *best[2];      /* B1, B2 of the best round */
    double *best_light;  /* the light importance sums the best round was decimated from */
    importance_result error_importance; /* of the best round's change */
    int has_error_importance;
    reduce_held_decimation best_decimation; /* the best round's plan and decimation */
} refine_context;

/* The state's reduction rendered with both seeds and measured against the originals into
 * *round; its images into images[0..1]. */
static int measure(refine_context *c, reduce_refine_round *round, float *images[2])
{
    reduce_state *st = c->st;
    error_search_seconds stages = {0};
    scene *reduced = reduce_view_of(st, st->output);
    if (!reduced)
        return -1;
    int status = reduce_check_render_pair(st, reduced, NULL, images, &stages);
    scene_view_free(reduced);
    if (status)
        return -1;
    image_paired_error paired;
    image_paired_error_of(c->original[0], c->original[1], images[0], images[1],
                          (int)st->error_search.width, (int)st->error_search.height, 0, &paired);
    round->error = paired.rmse;
    round->standard_error = paired.rmse_standard_error;
    round->vertices = st->vertices_after;
    return 0;
}

/* The importance pass on the original with the best round's change as pixel weights; *weighted:
 * the pixels with a weight (0: nothing to attribute, no pass run). */
static int run_error_importance(refine_context *c, uint64_t *weighted)
{
    reduce_state *st = c->st;
    const reduce_options *o = st->options;
    unsigned int w = st->error_search.width, h = st->error_search.height;
    uint32_t *weights = xmalloc(((size_t)w * h + 1) * sizeof *weights);
    *weighted = refine_pixel_weights(c->original[0], c->original[1], c->best[0], c->best[1], w, h,
                                     REFINE_TILE, REFINE_MAX_WEIGHT, weights);
    importance_result_free(&c->error_importance);
    c->has_error_importance = 0;
    int status = 0;
    if (*weighted) {
        importance_options options = o->importance;
        options.sppm.resolution = (float)o->error.resolution;
        /* as many iterations as the importance pass ran (its stop rule's) */
        options.sppm.iterations = st->importance.sppm.iterations ? st->importance.sppm.iterations
                                                                  : options.sppm.iterations;
        options.sppm.release_bvh = NULL;
        options.sppm.device_budget = reduce_memory_device_limit(st);
        options.sppm.progress = 0;
        options.tolerance = 0;
        options.checkpoint = NULL;
        options.checkpoint_context = NULL;
        options.snapshot = NULL;
        options.pixel_weights = weights;
        options.pixel_weights_width = w;
        options.pixel_weights_height = h;
        status = importance_run_devices(st->device, st->device_count, st->scene, &c->original_bvh,
                                        &options, &c->error_importance);
        if (!status) {
            c->has_error_importance = 1;
            st->refine.error_passes++;
        }
    }
    free(weights);
    return status;
}

/* The state's importance set to the best round's with λ × the error importance added (above),
 * the per-vertex importance computed again. */
static void mix_importance(refine_context *c, double mix)
{
    reduce_state *st = c->st;
    const scene *s = st->scene;
    importance_result *r = &st->importance;
    importance_weights w = importance_weights_of(&st->options->importance);
    memcpy(r->light, c->best_light, r->triangle_count * sizeof *r->light);
    if (mix > 0 && c->has_error_importance) {
        double total = 0, total_error = 0;
        for (size_t m = 0; m < st->count; m++) {
            if (!reduce_decimatable(st, m))
                continue;
            const scene_mesh *mesh = &s->meshes[m];
            for (uint32_t t = 0; t < mesh->triangle_count; t++) {
                uint64_t global = (uint64_t)mesh->first_triangle + t;
                total += importance_amount(r, &w, global);
                total_error += importance_amount(&c->error_importance, &w, global);
            }
        }
        /* A(T) grows by Δ when light(T) grows by Δ × iterations × photons / 1e6 (importance.h) */
        double scale = total_error > 0 ? mix * total / total_error : 0.0;
        double to_light = (double)r->sppm.iterations * r->sppm.photons / 1e6;
        for (size_t t = 0; t < r->triangle_count; t++)
            r->light[t] += scale * importance_amount(&c->error_importance, &w, t) * to_light;
    }
    importance_vertex_values_free(st->vertex_importance, st->simulated);
    st->vertex_importance = importance_vertex_values(r, st->simulated, &w);
}

/* The budget and the decimation again at st->target from the state's importance. */
static int decimate_again(reduce_state *st)
{
    reduce_decimation_forget(st);
    reduce_budget_forget(st);
    return reduce_plan_budget(st) || reduce_decimation(st);
}

static void report_round(const reduce_state *st, unsigned int k)
{
    const reduce_refine_round *r = &st->refine.rounds[k];
    if (!st->options->importance.sppm.progress)
        return;
    if (k == 0)
        fprintf(stderr, "idmr: refine: round 0 (importance only): error=%.4g \u00b1 %.2g, %llu "
                        "vertices\n",
                r->error, r->standard_error, (unsigned long long)r->vertices);
    else
        fprintf(stderr, "idmr: refine: round %u: \u03bb=%.3g from %llu changed pixels: error=%.4g "
                        "\u00b1 %.2g, %llu vertices, %s (%.1f s)\n",
                k, r->mix, (unsigned long long)r->weighted_pixels, r->error, r->standard_error,
                (unsigned long long)r->vertices, r->kept ? "kept" : "not kept", r->seconds);
}

static void free_images(float *images[2])
{
    free(images[0]);
    free(images[1]);
    images[0] = images[1] = NULL;
}

int reduce_refine(reduce_state *st)
{
    const reduce_options *o = st->options;
    reduce_refine_state *rf = &st->refine;
    if (!o->refine)
        return 0;
    double start = monotonic_seconds();
    refine_context c = {.st = st};
    rf->rounds = xcalloc(o->refine + 1, sizeof *rf->rounds);
    rf->round_count = 0;
    rf->chosen = 0;
    error_search_seconds stages = {0};
    if (o->importance.sppm.progress)
        fprintf(stderr, "idmr: refine: rendering the original (seeds 1 and 2, %u iterations of "
                        "%u photon paths, film scale %g)\n",
                o->error.iterations, o->error.photons, o->error.resolution);
    int status = bvh_build(st->scene, &c.original_bvh);
    int built = !status;
    status = status ||
             reduce_check_render_pair(st, st->scene, &c.original_bvh, c.original, &stages);
    reduce_refine_round *round = rf->rounds;
    if (!status) {
        double round_start = monotonic_seconds();
        status = measure(&c, round, c.best);
        reduce_hold_decimation(st, &c.best_decimation);
        round->kept = 1;
        round->seconds = monotonic_seconds() - round_start;
        rf->round_count = 1;
        report_round(st, 0);
        if (!(round->standard_error <= REFINE_FAINT_SHARE * round->error))
            warn("refine: the check renders measure the change as %.4g \u00b1 %.2g, too "
                 "faintly to tell a better round from noise; more --check-iterations and "
                 "--check-photons sharpen them",
                 round->error, round->standard_error);
    }
    size_t n = st->importance.triangle_count;
    c.best_light = xmalloc((n + 1) * sizeof *c.best_light);
    if (n)
        memcpy(c.best_light, st->importance.light, n * sizeof *c.best_light);
    double best_error = round->error, mix = REFINE_MIX;
    unsigned int decimated = 0; /* the round whose importance the state holds */
    int need_weights = 1;
    for (unsigned int k = 1; !status && k <= o->refine; k++) {
        double round_start = monotonic_seconds();
        uint64_t weighted = 0;
        if (need_weights) {
            status = run_error_importance(&c, &weighted);
            if (status)
                break;
            if (!weighted) {
                if (o->importance.sppm.progress)
                    fprintf(stderr, "idmr: refine: no pixel changed beyond the noise: done\n");
                break;
            }
        }
        round = rf->rounds + k;
        round->mix = mix;
        round->weighted_pixels = weighted ? weighted : rf->rounds[k - 1].weighted_pixels;
        mix_importance(&c, mix);
        float *images[2] = {NULL, NULL};
        status = decimate_again(st) || measure(&c, round, images);
        decimated = k;
        rf->round_count = k + 1;
        round->seconds = monotonic_seconds() - round_start;
        if (!status && round->error + round->standard_error < best_error) {
            round->kept = 1;
            best_error = round->error;
            rf->chosen = k;
            if (n)
                memcpy(c.best_light, st->importance.light, n * sizeof *c.best_light);
            free_images(c.best);
            c.best[0] = images[0];
            c.best[1] = images[1];
            images[0] = images[1] = NULL;
            reduce_hold_decimation(st, &c.best_decimation);
            need_weights = 1;
        } else {
            mix *= 0.5;
            need_weights = 0;
        }
        free_images(images);
        if (!status)
            report_round(st, k);
    }
    /* The best round's decimation back in the state, with the importance it was made from. */
    if (!status) {
        reduce_restore_decimation(st, &c.best_decimation);
        if (decimated != rf->chosen)
            mix_importance(&c, 0.0);
    }
    reduce_held_decimation_free(st, &c.best_decimation);
    if (!status && o->importance.sppm.progress) {
        const reduce_refine_round *chosen = rf->rounds + rf->chosen;
        fprintf(stderr, "idmr: refine: round %u chosen: error %.4g \u00b1 %.2g against %.4g "
                        "\u00b1 %.2g of the importance-only reduction (ratio %.3f)\n",
                rf->chosen, chosen->error, chosen->standard_error, rf->rounds[0].error,
                rf->rounds[0].standard_error,
                rf->rounds[0].error > 0 ? chosen->error / rf->rounds[0].error : 1.0);
    }
    if (built)
        bvh_free(&c.original_bvh);
    free_images(c.original);
    free_images(c.best);
    free(c.best_light);
    importance_result_free(&c.error_importance);
    rf->seconds = monotonic_seconds() - start;
    return status;
}

void reduce_refine_free(reduce_state *st)
{
    free(st->refine.rounds);
    memset(&st->refine, 0, sizeof st->refine);
}
