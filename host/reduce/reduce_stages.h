/* reduce_stages.h — internal to host/reduce/reduce*.c: the state that the stages of
 * reduce_run() share, and the stages, each in a file of its own.
 *
 * reduce_run() (reduce.c) runs the stages in order, each filling its part of the state and
 * reusing what the earlier ones left there, and stops at the first that fails; it decides every
 * loop back, and no stage calls into reduce.c:
 *
 *   options      --target in (0, 1], every --keep name a mesh of the scene (reduce_options.c)
 *   outdir       OUTDIR checked (empty unless forced, holding no input) and its staging
 *                directory made beside it, where every later stage writes; published as OUTDIR
 *                when all succeeded (refused if another run filled OUTDIR meanwhile), removed
 *                otherwise, on an exit or on a signal: staging (reduce_outdir.c, core/files.h)
 *   memory plan  with --memory-budget: the target (and, without --initial, the initial D0) that
 *                the budget allows, from the device memory of the render and importance passes
 *                (passes/sppm.h: sppm_memory_of) as a line in the triangles that may be
 *                decimated: target, initial, render_fixed_bytes (reduce_memory.c); where the
 *                budget leaves nothing to remove, reduce_run() writes the scene as it is
 *                (quadric, one pass, no initial reduction)
 *   initial      with --initial D0: the scene quadric-reduced to D0, its collapse history, and
 *                the view of it the first importance pass simulates: history, view, simulated
 *                (reduce_passes.c)
 *   importance   the importance pass (methods with importance), stopped once the decimation
 *                factors settle (factor_stop.h), or the saved pass --simulation names
 *                (passes/importance_file.h), and per-vertex importance of every mesh,
 *                computed once for the decimation and the importance outputs: importance,
 *                checkpoints, stopped_at, vertex_importance (reduce_importance.c); with a
 *                history, that importance copied back to the original vertices: remapped,
 *                distance (reduce_passes.c: reduce_remap)
 *   budget       decimation inputs and the plan of Eq. 3: input, budget, plan (reduce_budget.c)
 *   decimation   the planned meshes, then rounds that plan again with the floors meshes
 *                reached and relax locks: output, not_reduced, compensation_rounds,
 *                vertices_after (reduce_decimation.c)
 *   next pass    with --passes K, between passes: reduce_run() has the importance, budget and
 *                decimation stages forget what they left, and hands this pass's output on as
 *                the history, whose view the next pass simulates (reduce_passes.c)
 *   memory fit   with --memory-budget: the reduced scene's exact render memory (its BVH built);
 *                above the budget, the target is lowered: render_memory, fit_rounds, target; on
 *                a device sharing the host's memory the remapped importance waits on disk
 *                meanwhile (reduce_memory.c; reduce_run() spills and restores it with
 *                reduce_passes.c's reduce_remapped_spill and reduce_remapped_restore);
 *                reduce_run() then forgets the budget and decimation and runs them again, and
 *                the fit after them; last, the run's peak memory checked against the budget
 *   error budget with --max-error, in place of budget and decimation: the original rendered
 *                with two seeds, then budget and decimation again at each D the search
 *                (error_search.h) measures, the reduced scene rendered in memory; left
 *                decimated at the D found: error_search (reduce_error_budget.c)
 *   refine       with --refine N, after the reduction at D: the per-pixel change of the check
 *                renders, as pixel weights, drives an importance pass on the original (the
 *                error importance), mixed into the importance; decimated again at the same D
 *                and measured, kept while the error falls: refine (reduce_refine.c)
 *   write        meshes/NAME.ply and scene.xml: ply, meshes_written (reduce_write.c)
 *   report       report.json (with the importance outputs) and the closing line
 *                (reduce_report.c)
 *
 * What the stages ask of each mesh (pinned, decimatable, the attributes it carries, the
 * decimate_input it is decimated from) is in reduce_inputs.c; every decision that reads
 * --memory-budget is in reduce_memory.c.
 *
 * Who writes what: each group of reduce_state's fields below is written by the stage it is
 * named after, in its file (or by reduce_run(): what the run was given, and the pass records),
 * and read by the later ones. On purpose, one pair shares: the decimation plans again on the
 * budget stage's plan, in place (the floors it learns in budget, the targets and factors that
 * move and the meshes it keeps whole in plan, the locks it relaxes in input), so what report.json
 * gives per mesh is the plan as the decimation left it; reduce_run() runs the two together and
 * has them forget together. The scene's released meshes (core/scene.h: streaming) are read
 * again and released by every stage that needs their geometry: they are the input, no stage's
 * result.
 * Per-mesh arrays are indexed like s->meshes and hold mesh_count entries. */
#ifndef IDMR_REDUCE_STAGES_H
#define IDMR_REDUCE_STAGES_H

#include <stdio.h>

#include <cjson/cJSON.h>

#include "reduce/budget.h"
#include "reduce/error_search.h"
#include "reduce/factor_stop.h"
#include "reduce/reduce.h"

/* One checkpoint of the stop rule (factor_stop.h); the changes are negative at the first. */
typedef struct factor_checkpoint {
    unsigned int iteration;
    double factor_change, ranking_change;
} factor_checkpoint;

/* The memory plan's estimate of the BVH's device bytes per triangle (reduce_memory.c): a little
 * above the largest measured, so the plan errs on the small side; the fit corrects it. */
#define REDUCE_BVH_BYTES_PER_TRIANGLE 100.0

/* What the error-budget stage found (reduce_error_budget.c; report.json: error_budget). */
typedef struct reduce_error_state {
    double max_error;          /* E in the units of the paired error (the relative bound times
                                  mean_radiance) */
    double mean_radiance;      /* of the original's check renders, over pixels and channels */
    double floor;              /* the smallest D the plan can ask for */
    double radius;             /* the first gather radius every check render shares */
    unsigned int width, height; /* the check renders' film */
    error_search_result result; /* the curve walked and the D chosen */
    unsigned int noise_decided; /* steps below the D found that failed by their standard error
                                   alone (error <= E < error + standard error): a warning */
    double seconds_originals;  /* the original's two renders */
    error_search_seconds originals_stages; /* and where they went (BVH, renders' stages) */
    bvh original_bvh;          /* the scene's BVH, kept from the importance pass for the
                                  originals' renders (freed after them) */
    int has_original_bvh;
    double seconds_search;     /* the whole stage: originals, steps and the final decimation */
    double seconds_final_decimation; /* putting the chosen D's decimation back (or making it,
                                        where no step kept one: D = 1) */
} reduce_error_state;

/* One round of --refine (reduce_refine.c; report.json: refine.rounds). Round 0 is the reduction
 * refinement starts from. */
typedef struct reduce_refine_round {
    double mix;            /* λ: the error importance's weight against the importance (0: none) */
    double error, standard_error; /* paired reduction error of the check renders */
    uint64_t vertices;     /* of the reduced scene */
    uint64_t weighted_pixels; /* pixels with a weight above 0 behind this round's error
                                 importance (0 for round 0) */
    double seconds;        /* error importance pass (when run), decimation and check renders */
    int kept;              /* its error + standard error fell below the best error so far: the
                              reduction goes on from it */
} reduce_refine_round;

/* What --refine did (reduce_refine.c; report.json: refine). */
typedef struct reduce_refine_state {
    reduce_refine_round *rounds; /* round_count of them, round 0 first */
    unsigned int round_count;
    unsigned int chosen;   /* the round whose reduction is written */
    unsigned int error_passes; /* error importance passes run */
    double seconds;        /* the whole stage */
} reduce_refine_state;

/* What one importance pass and the reduction after it did (report.json: passes). */
typedef struct reduce_pass_record {
    double seconds_importance, seconds_reduction; /* reduction: budget and decimation */
    uint64_t vertices_simulated; /* of the scene the importance pass ran on */
    uint64_t vertices_after;     /* of the reduced scene after it */
    uint64_t device_bytes;       /* the importance pass's device memory (0: --simulation) */
    unsigned int iterations;
} reduce_pass_record;

typedef struct reduce_state {
    /* reduce_run(): what the run was given (options: replaced where the memory budget leaves
     * nothing to remove), and a record per importance pass */
    device *device;       /* the first of the devices: budgets and memory plans are its */
    unsigned int device_count; /* the importance pass runs on device[0 .. device_count) */
    scene *scene;
    const char *outdir;   /* OUTDIR as given: what messages name */
    const reduce_options *options;
    size_t count; /* meshes in the scene */
    reduce_pass_record *passes; /* one per pass run */
    unsigned int pass_count;

    /* outdir: */
    char staging[2048];   /* where the stages write (files_stage_begin) */

    /* memory plan, memory fit (reduce_run() sets target and initial from the options first): */
    double target;  /* D the plan aims at: --target, or less where the memory budget says so */
    double initial; /* D0 of the initial reduction: --initial, or chosen for the budget; 1: none */
    double render_fixed_bytes;     /* render memory without the triangles that may go */
    sppm_memory render_memory;     /* memory fit: rendering the reduced scene, exactly */
    unsigned int fit_rounds;       /* decimations run again to fit the budget */

    /* initial, next pass, and the remapping after each importance pass (reduce_passes.c): */
    scene *simulated;       /* the scene the importance pass runs on: `scene`, or `view` */
    scene *view;            /* the scene with the meshes of `history` */
    decimate_output *history; /* per mesh, the decimation `view` holds (no mesh: the mesh as it
                                 is); its collapse history is freed once remapped; NULL: none */
    double seconds_initial;
    uint64_t vertices_initial; /* vertices of the initially reduced scene */
    double **remapped;             /* with a history, per mesh whose history has collapses, the
                                      importance per original vertex (remap.h); else NULL */
    uint32_t **distance;           /* and each one's distance from its source */
    FILE *spill;                   /* the remapped importance, while the memory fit has it out
                                      of memory (reduce_remapped_spill); NULL otherwise */

    /* importance: */
    importance_result importance;  /* per triangle of `simulated` */
    factor_checkpoint *checkpoints; /* the stop rule's checkpoints (factor_stop.h) */
    size_t checkpoint_count;
    unsigned int stopped_at;       /* the iteration the stop rule ended the pass after; 0 when
                                      it ran to --iterations or --tolerance */
    double **vertex_importance;    /* per mesh, per vertex of `simulated`; NULL without the
                                      pass */
    double seconds_importance;

    /* budget (and the decimation's plan made again, above): */
    decimate_input *input;         /* what each mesh is decimated from */
    budget_mesh *budget;           /* what the plan was made from, with the decimation's floors */
    budget_plan plan;              /* targets and factors */
    double seconds_budget;

    /* decimation: */
    decimate_output *output;       /* per mesh the plan decimates */
    char **not_reduced;            /* per mesh, NULL, or why the plan decimated it but its input
                                      is kept (its decimation was not smaller); such a mesh is
                                      no longer flagged in plan.decimate */
    unsigned int compensation_rounds;
    unsigned int locks_relaxed;     /* meshes whose boundary lock was relaxed */
    unsigned int seams_freed;       /* meshes whose attribute seams were freed */
    uint64_t vertices_after;       /* vertices of the reduced scene */
    double seconds_decimation;

    /* error budget (with --max-error; reduce_error_budget.c): */
    reduce_error_state error_search;

    /* refine (with --refine; reduce_refine.c): */
    reduce_refine_state refine;

    /* write: */
    char **ply;                    /* per decimated mesh, its file relative to outdir */
    size_t meshes_written;
    double seconds_write;
} reduce_state;

/* ---- what every stage asks of a mesh (reduce_inputs.c) ---- */

/* Whether --keep names the mesh. */
int reduce_mesh_named_by_keep(const reduce_options *o, const scene_mesh *mesh);

/* Emitters, meshes named with --keep and meshes without area (every triangle degenerate: all
 * its points coincide or lie on a line) are never decimated. */
int reduce_mesh_pinned(const reduce_options *o, const scene_mesh *mesh);

/* Whether mesh m can be decimated at all: not pinned, above --min-vertices. */
int reduce_decimatable(const reduce_state *st, size_t m);

/* Whether mesh m is decimated with texture coordinates and with shading normals (the rules of
 * reduce_decimation_input), whether its geometry is in memory or released. */
void reduce_mesh_attributes(const reduce_state *st, size_t m, int *texcoords, int *normals);

/* What mesh m is decimated from: the scene's mesh, its attributes as reduce.h says, and its
 * per-vertex importance (remapped where there is a history). A released mesh (core/scene.h:
 * streaming) gives no geometry: reduce_decimate_meshes() reads it again first. */
decimate_input reduce_decimation_input(const reduce_state *st, size_t m);

/* A finalised view of the scene (core/scene.h, scene_view) in which every mesh that `meshes`
 * holds a decimation of (collapsed_into set) is that decimation, and every other mesh is the
 * scene's (read again, and kept, where it was released); NULL with the error set. */
scene *reduce_view_of(reduce_state *st, const decimate_output *meshes);

/* ---- instances kept (reduce_instances.c) ---- */

/* The mesh that represents mesh m's prototype in the plan and the decimation: the first copy
 * of its shape (core/scene.h: instanced), or m itself for any other mesh. */
size_t reduce_instance_representative(const reduce_state *st, size_t m);
/* Whether mesh m is a copy other than its shape's first (a follower, the scene's later copy: no
 * vertices of its own in the plan, no decimation of its own; its reduction is the
 * representative's, placed where it stands). */
int reduce_instance_follower(const reduce_state *st, size_t m);
/* The copy after copy c of the same shape, or st->count after the last (and for any mesh not a
 * copy): for (c = m; c < st->count; c = reduce_instance_next_copy(st, c)). */
size_t reduce_instance_next_copy(const reduce_state *st, size_t c);
/* Whether --keep names mesh m or any copy after it. */
int reduce_instance_named_by_keep(const reduce_state *st, size_t m);
/* Whether any copy from mesh m on is pinned (reduce_mesh_pinned): it keeps the prototype whole. */
int reduce_instance_pinned(const reduce_state *st, size_t m);
/* The decimated representative m in its Mitsuba shapegroup's own space, for the writer (*out
 * malloc'd). 0, or -1 with the error set (a singular instance transform). */
int reduce_instance_prototype_mesh(const reduce_state *st, size_t m, mesh_data *out);
/* Vertices of the reduced scene with every copy counted (what a renderer holds flattened). */
uint64_t reduce_instances_rendered_vertices(const reduce_state *st);

/* ---- options (reduce_options.c) ---- */

/* The options stage: the options against each other and the scene. 0, or -1 with the error set
 * (IDMR_EXIT_INPUT). */
int reduce_options_check(const reduce_state *st);

/* ---- outdir (reduce_outdir.c) ---- */

/* OUTDIR checked: an existing non-empty one needs force; never a directory holding a file the
 * scene reads (scene_check_output_directory: inputs are never written). Then the staging
 * directory beside it into st->staging. Returns 0, or -1 with the error
 * set. reduce_outdir_finish() publishes the staging directory as OUTDIR when `success`, else
 * removes it. */
int reduce_outdir_prepare(reduce_state *st);
int reduce_outdir_finish(reduce_state *st, int success);

/* ---- the memory budget's policy (reduce_memory.c); without a budget each does nothing ---- */

/* The memory plan stage. 0, or -1 with the error set. */
int reduce_memory_plan(reduce_state *st);
/* Whether the budget leaves nothing to remove: the scene renders within it as it is. */
int reduce_memory_nothing_to_remove(const reduce_state *st);
/* The most device memory the importance pass may allocate (sppm_options.device_budget); 0: no
 * limit. */
uint64_t reduce_memory_device_limit(const reduce_state *st);
/* How many of the next meshes (their input vertices, largest first; `count` of them) one
 * streaming group decimates at once: all, but under a memory budget on a device that shares the
 * host's memory only as many as keep the process's resident memory with theirs in flight within
 * the budget, and at least one. */
size_t reduce_memory_meshes_in_flight(const reduce_state *st, const uint32_t *vertices,
                                      size_t count);
/* Whether the fit's BVH build is to be made with the remapped importance out of memory
 * (reduce_remapped_spill): under a budget on a device that shares the host's memory, where the
 * build (about 160 bytes per triangle while it runs) would sit beside it, and only a further
 * decimation needs it. */
int reduce_memory_fit_spills(const reduce_state *st);
/* The fit: the reduced scene's exact render memory; above the budget, a lower st->target and
 * *again set (reduce_run() decimates again); after FIT_ROUNDS such rounds, an error. */
int reduce_memory_fit(reduce_state *st, int *again);
/* On a device that shares the host's memory: an error when the process's resident memory
 * peaked above the budget during the run (from reduce_memory_plan() on). 0, or -1 with the
 * error set. */
int reduce_memory_check_peak(const reduce_state *st);

/* ---- initial, next pass, remapping (reduce_passes.c) ---- */

/* The initial reduction (with --initial; nothing otherwise). 0, or -1 with the error set. */
int reduce_initial(reduce_state *st);

/* The next pass: `output`, the last pass's decimation (whose ownership passes to the state),
 * becomes the history, and its view the scene the next importance pass simulates; the last
 * remapped importance, history and view are freed. 0, or -1 with the error set. */
int reduce_next_pass(reduce_state *st, decimate_output *output);

/* After the importance pass: with a history, the importance per vertex of the simulated scene
 * copied back to the originals into st->remapped and st->distance. */
void reduce_remap(reduce_state *st);

/* The remapped importance moved into an unnamed file in the staging directory, out of memory,
 * and read back (for the memory fit: while it builds the reduced scene's BVH on a device that
 * shares the host's memory, only a further decimation needs it). Each 0 (nothing to do without
 * a remapped importance, or none spilled), or -1 with the error set. */
int reduce_remapped_spill(reduce_state *st);
int reduce_remapped_restore(reduce_state *st);

/* Frees what reduce_initial(), reduce_next_pass() and reduce_remap() left in the state. */
void reduce_passes_free(reduce_state *st);

/* ---- importance (reduce_importance.c) ---- */

/* The importance stage (methods with importance; nothing otherwise). 0, or -1 with the error
 * set. */
int reduce_importance(reduce_state *st);
/* Frees what the importance stage left, so that it can run again (the next pass). */
void reduce_importance_forget(reduce_state *st);

/* ---- budget (reduce_budget.c) ---- */

/* Mesh m as the plan of Eq. 3 sees it, with the importance of `r` (the budget stage's, or the
 * stop rule's so far). */
budget_mesh reduce_budget_entry(const reduce_state *st, const importance_result *r, size_t m);

/* The decimation inputs and the plan of Eq. 3 for st->target: importance sums set the factors
 * (methods with importance), or equal importance gives the uniform D of the quadric baseline.
 * Returns 0, or -1 with the error set. */
int reduce_plan_budget(reduce_state *st);
/* Frees what the budget stage left (inputs, entries, plan), so that it can run again. */
void reduce_budget_forget(reduce_state *st);

/* Exchanges two lvalues of one type. */
#define REDUCE_SWAP(a, b)                                                                          \
    do {                                                                                           \
        __typeof__(a) swapped_value = (a);                                                         \
        (a) = (b);                                                                                 \
        (b) = swapped_value;                                                                       \
    } while (0)

/* A plan and its decimation held aside: what the budget and decimation stages leave, moved out of
 * the state whole, so that a stage which plans and decimates at several D (the error budget's
 * search, the refinement's rounds) keeps its best instead of decimating it again. Zeroed: holds
 * nothing. */
typedef struct reduce_held_decimation {
    decimate_input *input; /* the budget stage's */
    budget_mesh *budget;
    budget_plan plan;
    decimate_output *output; /* the decimation stage's */
    char **not_reduced;
    unsigned int compensation_rounds, locks_relaxed, seams_freed;
    uint64_t vertices_after;
} reduce_held_decimation;
/* Exchanges the budget stage's results in the state with those in `held`. */
void reduce_budget_swap(reduce_state *st, reduce_held_decimation *held);

/* ---- decimation (reduce_decimation.c) ---- */

/* Decimates every mesh m flagged in `selected` from inputs[m] to targets[m], in parallel
 * (decimate_many: st->options->threads), largest first, into outputs[m] (an earlier output
 * there is freed), with a progress bar named `label` over their vertices. Released meshes
 * (streaming) go `threads` at a time, or fewer where a budget bounds the host
 * (reduce_memory_meshes_in_flight): read again, decimated, released. Without `keep_history`
 * each output's collapse history is freed as soon as it is made. Returns 0, or -1 with the
 * first failure's error set. */
int reduce_decimate_meshes(reduce_state *st, const decimate_input *inputs,
                           const uint64_t *targets, const unsigned char *selected,
                           decimate_method method, const char *label, int keep_history,
                           decimate_output *outputs);

/* ---- ranks (reduce_ranks.c) ---- */

/* Under mpirun: the owner rank of each of `n` meshes of `vertices` (largest first), each mesh in
 * turn to the rank with the fewest vertices so far (the lowest on a tie): the same on every
 * rank. */
void reduce_ranks_assign(const uint32_t *vertices, size_t n, int *owner);
/* Under mpirun, once each rank has decimated its meshes (status: its own success): agrees on
 * the status (ranks_sync), then copies the output of each meshes[i] from rank owner[i] into
 * outputs[meshes[i]] on every other rank, so every rank holds them all. One process: returns
 * status. Returns 0, or -1 with the error set (a failing rank's). */
int reduce_ranks_share(int status, const size_t *meshes, const int *owner, size_t n,
                       const decimate_input *inputs, decimate_output *outputs);

/* Decimates the meshes the plan decimates, in parallel, largest first, then plans again with the
 * floors meshes reached and relaxes locks where the request cannot be met otherwise. A mesh
 * whose decimation keeps at least as many vertices as it has (below a target under its count)
 * keeps its input instead, with the reason in st->not_reduced and a warning: a reduction never
 * makes a mesh larger. Returns 0, or -1 with the error set. */
int reduce_decimation(reduce_state *st);
/* The decimation's outputs, taken out of the state (the caller owns them; st->output NULL). */
decimate_output *reduce_decimation_take_output(reduce_state *st);
/* Frees what the decimation stage left (outputs, reasons, counts), so that it can run again. */
void reduce_decimation_forget(reduce_state *st);
/* Exchanges the decimation stage's results in the state with those in `held`. */
void reduce_decimation_swap(reduce_state *st, reduce_held_decimation *held);
/* Moves the state's plan and decimation into `held` (what it held freed first); the state then
 * holds none. */
void reduce_hold_decimation(reduce_state *st, reduce_held_decimation *held);
/* Puts the held plan and decimation back into the state (what the state held freed first);
 * `held` then holds none. */
void reduce_restore_decimation(reduce_state *st, reduce_held_decimation *held);
/* Frees what `held` holds. */
void reduce_held_decimation_free(reduce_state *st, reduce_held_decimation *held);

/* ---- error budget (reduce_error_budget.c) ---- */

/* With --max-error, in place of the budget and decimation stages: renders the original with
 * two seeds, searches the smallest D whose reduced scene is within the bound (error_search.h;
 * each step plans, decimates and renders the reduced scene in memory), and leaves the budget
 * and decimation stages' results at that D. 0, or -1 with the error set. */
int reduce_error_budget(reduce_state *st);
/* Frees what the error-budget stage left. */
void reduce_error_budget_free(reduce_state *st);
/* The check renders (--check-*): scene s rendered with seeds 1 and 2 into images[0..1]
 * (malloc'd, st->error_search.width × height × RGB), with its BVH `built` (NULL: built here),
 * adding the seconds of the BVH and the renders' stages to *stages; the first render (the
 * original's, seed 1) sets the gather radius every later one shares. 0, or -1 with the error
 * set. */
int reduce_check_render_pair(reduce_state *st, const scene *s, const bvh *built,
                             float *images[2], error_search_seconds *stages);

/* ---- refine (reduce_refine.c) ---- */

/* With --refine N, after the reduction (budget and decimation, or the error budget): the
 * error-driven refinement at the same target D (reduce_refine.c). Leaves the budget and
 * decimation stages' results at the round with the smallest measured error (round 0, the
 * reduction it was given, when none was smaller). 0, or -1 with the error set. */
int reduce_refine(reduce_state *st);
/* Frees what the refine stage left. */
void reduce_refine_free(reduce_state *st);

/* ---- write (reduce_write.c) ---- */

/* The write stage: the reduced scene in the staging directory. 0, or -1 with the error set. */
int reduce_write(reduce_state *st);
/* Frees what the write stage left. */
void reduce_write_free(reduce_state *st);

/* ---- report (reduce_report.c) ---- */

/* report.json in the staging directory (with the importance outputs for the methods with
 * importance). 0, or -1 with the error set. */
int reduce_report_write(const reduce_state *st);
/* The closing line on stderr: vertices before and after, the target, the meshes rewritten and
 * where the reduced scene is. */
void reduce_report_summary(const reduce_state *st);

#endif
