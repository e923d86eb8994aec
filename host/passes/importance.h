/* importance.h — the importance pass (paper sections 3.2, 3.3, 4.1) on the SPPM core
 * (passes/sppm.h): camera paths add Eq. 2 weights to the triangles they see, photon paths store
 * a vertex at every surface, and after the grid each path is walked back from its last vertex,
 * every vertex adding weight × (hit points gathered by it and the vertices after it) to its
 * triangle (kernels/sppm.cl). Then the host turns the per-triangle sums into importance per
 * triangle, vertex and mesh.
 *
 * What is accumulated, per scene triangle T, kept apart so that the weights are applied
 * afterwards and a sweep over them needs no new simulation:
 *   camera(T)  Σ Eq. 2 weights of the camera path vertices on T
 *   light(T)   Σ over photon vertices on T of weight × (the number of hit points gathered by
 *              that vertex and the vertices after it on its path), plus the light the camera
 *              sees through T: where a camera path reaches an emitter (an area light's front,
 *              the environment) through mirrors and dielectrics — a glint, a window, a light
 *              behind glass — no photon is gathered for that pixel, though the light that
 *              reaches it runs along the specular triangles the path passed. Each of them
 *              (the first 16) gets weight × the gathers that light is worth: ten times as
 *              many as a white diffuse surface showing the same luminance Y would gather,
 *              10 Y π² r² N / Φ (irradiance π Y on a disc of the gather radius r, N photon paths
 *              carrying the lights' luminous power Φ; IMPORTANCE_SEEN_LIGHT_WEIGHT below). It
 *              scales with r² like every gather, so it keeps its share as the radius shrinks
 *   shadow(T)  Σ shadow weights of the shadow rays T stops (kernels/lib/shadows.h): the
 *              triangles that cast the shadows the camera sees, most where they outline a sharp
 *              one (only with shadow weight σ > 0)
 * Each is taken per million of its samples — camera paths and shadow rays per pixel of the
 * hit-point image, photon paths per path — so that γ and σ weigh the same at any resolution and
 * photon count (the paper had to adjust γ to both by hand, 5.2). A triangle's importance amount
 * per iteration is
 *   A(T)       = 1e6 (γ camera(T) / pixels + light(T) / photons + σ shadow(T) / pixels)
 *                / iterations
 * and from it:
 *   I(T)       = A(T) / area(T)   (0 for zero area)
 *   I(vertex)  = Σ A / Σ area over the triangles around it (an area-weighted mean of I(T); 0 if
 *                all of them have zero area)
 *   mesh sum   = Σ A over its triangles (unnormalised: no area division, for the budget, Eq. 3)
 *
 * Kernels are built for the scene's feature bits (idmr/features.h); with γ = 0 the camera
 * importance atomics are left out (camera importance is then 0: it would be multiplied by γ = 0
 * anyway), and with σ = 0 the shadow rays.
 *
 * Copies: in an instanced scene (core/scene.h: a prototype's triangles are its representative's,
 * shared by every later copy) each sum above is the prototype's, over all its copies. Each copy
 * (the representative and every later copy) keeps its own totals besides: whatever a camera path
 * hit, a photon vertex gathered or a shadow ray stopped on that copy adds to a triangle is added
 * to the copy's camera, light or shadow total too, in the same fixed-point units and weights
 * (kernels/lib/paths.h, one more word per instance in each accumulator), so that a prototype's
 * copies' totals add up to the sums over its triangles (up to the rounding of the double sums).
 * importance_copy_sums() weighs them as importance_mesh_sums() weighs a mesh's.
 *
 * Convergence after iteration n: Δ_n = Σ_T (I_n(T) - I_{n-1}(T))² / Σ_T I_n(T)², with I_n the
 * per-triangle importance after n iterations; Δ_1 = 1. It is scale-free. With
 * a tolerance E > 0 the pass stops once Δ stays below E for 3 iterations in a row. A caller
 * can add its own rule (the checkpoint hook below: `idmr reduce` stops once the decimation
 * factors settle, reduce/factor_stop.h). */
#ifndef IDMR_IMPORTANCE_H
#define IDMR_IMPORTANCE_H

/* What seen light weighs against a diffuse surface showing the same luminance (above). A glint,
 * the light seen in a curved glass or mirror surface, moves as a whole with the surface's normal,
 * where a diffuse surface's brightness changes only with its irradiance: weighted like that
 * surface (1), glints got too few vertices. On the dragon Cornell box (Mitsuba 3 at 256 × 256,
 * D = 0.1, 30-iteration importance passes with seeds 1, 2, 3) 10 took combined's reduction error
 * from 0.0283, 0.0312, 0.0192 to 0.0179, 0.0168, 0.0176; at D = 0.03, where the glints take
 * vertices the outline needs, it costs (seed 1: 0.0321 to 0.0487; README, "Evaluation"). */
#define IMPORTANCE_SEEN_LIGHT_WEIGHT 10.0

/* The largest pixel weight (importance_options.pixel_weights). */
#define IMPORTANCE_PIXEL_WEIGHT_MAX 255u

#include <stddef.h>
#include <stdint.h>

#include "core/scene.h"
#include "device/bvh.h"
#include "device/device.h"
#include "idmr/importance_layout.h"
#include "passes/sppm.h"

/* Copies of the last iteration's buffers, for tests and debugging. */
typedef struct importance_snapshot {
    sppm_snapshot core;             /* hit points, path lengths, params, photon records */
    const idmr_photon_vertex *vertices; /* core.photon_records as the pass's records */
    uint32_t *gathered;             /* gather counts by slot, as core.photon_records */
    uint64_t *camera_fixed;         /* this iteration's accumulators, fixed point: a word per
                                       scene triangle, then (an instanced scene) one per
                                       instance, its total (bvh_scene_instances' order) */
    uint64_t *light_fixed;
    uint64_t *shadow_fixed;         /* zero without shadow rays */
    uint64_t *seen_light_fixed;     /* the light camera paths saw through specular surfaces */
} importance_snapshot;

void importance_snapshot_free(importance_snapshot *snapshot);

typedef struct importance_result importance_result;

typedef struct importance_options {
    sppm_options sppm;       /* iterations default to 100 */
    float gamma;             /* hit point importance factor γ (default 1) */
    float shadow_weight;     /* shadow importance factor σ (default 1; 0: no shadow rays) */
    double tolerance;        /* stop once Δ stays below it; 0: run all iterations */
    int accumulate_importance; /* 1; 0 compiles the importance accumulation out (benchmark) */
    importance_snapshot *snapshot; /* when not NULL, receives the last iteration's buffers */
    /* Pixel weights (the error importance of `idmr reduce --refine`): when not NULL, one per
     * pixel of the hit-point image (pixel_weights_width × pixel_weights_height, which must be
     * the pass's film), row by row; each hit point's camera importance, seen light and shadow
     * ray are multiplied by its pixel's weight, and it counts for that weight, not 1, in the
     * gather count of every photon vertex it gathers, so that light importance too comes from
     * the weighted pixels alone (through the paths that light them). All ones is today's pass,
     * bit for bit; NULL is all ones. Keep Σ weights × gathers within 32 bits: weights of at most
     * IMPORTANCE_PIXEL_WEIGHT_MAX. */
    const uint32_t *pixel_weights;
    unsigned int pixel_weights_width, pixel_weights_height;
    /* When set, called after every iteration with the sums so far (r->sppm.iterations is the
     * count run): it may set *stop to end the pass there, and put a few words for the progress
     * line into detail. Returns 0, or -1 with the error set (the pass then fails). */
    int (*checkpoint)(void *context, const importance_result *r, int *stop, char *detail,
                      size_t detail_size);
    void *checkpoint_context;
} importance_options;

struct importance_result {
    size_t triangle_count;
    double *camera;          /* per scene triangle, summed over iterations, in weight units */
    double *light;
    double *shadow;          /* zero without shadow rays */
    /* Each copy's own totals (below, "Copies"), per scene mesh (mesh_count of them), in the
     * units of the per-triangle sums; 0 for a mesh that is not instanced. */
    size_t mesh_count;
    double *copy_camera, *copy_light, *copy_shadow;
    double *convergence;     /* Δ per iteration run */
    uint32_t *pixel_triangle; /* per pixel of the hit-point image, the scene triangle seen
                                 through its centre (IDMR_NO_HIT: none): the importance image */
    uint64_t gathered;       /* hit points found by photon vertices, first iteration */
    double seen_light;       /* the part of Σ_T light(T) that is light seen through specular
                                surfaces, as gathers (above) */
    double path_seconds;     /* the path walk, part of sppm.seconds.gather (several devices:
                                the most any device spent) */
    double shadow_seconds;   /* the shadow rays, part of sppm.seconds.gather (the same) */
    sppm_summary sppm;       /* iterations, radii, image size, photons, bytes, timings */
};

void importance_options_default(importance_options *o);

/* The importance pass's own build defines (IDMR_ACCUMULATE_IMPORTANCE, IDMR_CAMERA_IMPORTANCE,
 * IDMR_SHADOW_IMPORTANCE) into out. */
void importance_defines(int accumulate_importance, int camera_importance, int shadows, char *out,
                        size_t size);

/* The weights the kinds of importance are summed with (above): γ and σ. */
typedef struct importance_weights {
    float gamma;
    float shadow;
} importance_weights;

importance_weights importance_weights_of(const importance_options *o);

/* Builds the pass's program for scene s on device d, as a run would, and lets it go: the
 * build (PoCL compiles a program it has not cached inside the process, with a passing peak of
 * resident memory) then happens now, not in the middle of a run whose memory is planned
 * (reduce/reduce_memory.c); the run's own build then comes from the cache. 0, or -1 with the
 * error set (the build log). */
int importance_build_program(device *d, const scene *s, const importance_options *o);

/* The device memory a run of the pass on scene s allocates, with a BVH of bvh_bytes
 * (passes/sppm.h, sppm_memory_of). 0, or -1 with the error set. */
int importance_memory(const device *d, const scene *s, uint64_t bvh_bytes,
                      const importance_options *o, sppm_memory *m);

/* Runs the pass. The scene needs a camera and at least one light. Returns 0, or -1 with the
 * error set. `r` is freed with importance_result_free() either way. */
int importance_run(device *d, const scene *s, const bvh *b, const importance_options *o,
                   importance_result *r);

/* importance_run() on the `count` devices of `devices` at once (passes/sppm.h): the photon
 * paths split between them, camera-side sums from the first, the per-triangle integer sums
 * added before their conversion, so that the result is a single device's bit for bit. */
int importance_run_devices(device *devices, unsigned int count, const scene *s, const bvh *b,
                           const importance_options *o, importance_result *r);
void importance_result_free(importance_result *r);

/* sums[t] += scale × Σ_j words[j][t] for t < n: the `count` devices' fixed-point words of one
 * kind in one iteration, added as integers and converted to double once, so that the result is
 * a single device's bit for bit whatever the split (converting each device's words and adding
 * the doubles would round twice once a word passes 2^53). Adds the total it added to *added
 * (may be NULL). Returns 0, or -1 with an error naming `what` and the triangle and suggesting
 * `remedy` when a word or a sum reaches IDMR_FIXED_SATURATION. */
int importance_add_words(double *sums, const uint64_t *const *words, unsigned int count,
                         size_t n, double scale, const char *what, const char *remedy,
                         double *added);

/* A(T) of scene triangle t (above): its importance amount per iteration. */
double importance_amount(const importance_result *r, const importance_weights *w, uint64_t t);

/* I(T) for scene triangle t (above). */
double importance_triangle(const importance_result *r, const scene *s,
                           const importance_weights *w, uint64_t t);

/* I per vertex of mesh m into vertex_importance[vertex_count]. */
void importance_mesh_vertices(const importance_result *r, const scene *s, size_t m,
                              const importance_weights *w, double *vertex_importance);

/* Sums over mesh m, each per iteration and per million samples (above): the amount Σ A, and
 * its parts Σ camera, Σ light, Σ shadow, unweighted. */
typedef struct importance_sums {
    double amount, camera, light, shadow;
} importance_sums;

importance_sums importance_mesh_sums(const importance_result *r, const scene *s, size_t m,
                                     const importance_weights *w);

/* The same sums of mesh m's own copy totals (above, "Copies"): what the paths that met that copy
 * added. All 0 for a mesh that is not instanced. Over an instanced shape's copies they add up to
 * importance_mesh_sums() of its representative (which sums the prototype's triangles). */
importance_sums importance_copy_sums(const importance_result *r, const scene *s, size_t m,
                                     const importance_weights *w);

#endif
