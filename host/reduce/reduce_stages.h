/* reduce_stages.h — internal to host/reduce/reduce*.c: the state that the stages of
 * reduce_run() share, and the stages that live in files of their own.
 *
 * reduce_run() (reduce.c) runs the stages in order, each filling its part of the state and
 * reusing what the earlier ones left there, and stops at the first that fails:
 *
 *   options      --target in (0, 1], every --keep name a mesh of the scene (reduce.c)
 *   outdir       OUTDIR checked (empty unless forced, holding no input) and its staging
 *                directory made beside it, where every later stage writes; published as OUTDIR
 *                when all succeeded (refused if another run filled OUTDIR meanwhile), removed
 *                otherwise, on an exit or on a signal (reduce_outdir.c, core/files.h)
 *   memory plan  with --memory-budget: the target (and, without --initial, the initial D0) that
 *                the budget allows, from the device memory of the render and importance passes
 *                (passes/sppm.h: sppm_memory_of) as a line in the triangles that may be
 *                decimated: target, initial, the line (reduce_memory.c)
 *   initial      with --initial D0: the scene quadric-reduced to D0, its collapse history, and
 *                the view of it the first importance pass simulates: history, view, simulated
 *                (reduce_passes.c)
 *   importance   the importance pass (methods with importance), stopped once the decimation
 *                factors settle (factor_stop.h), or the saved pass --simulation names
 *                (passes/importance_file.h), and per-vertex importance of every mesh,
 *                computed once for the decimation and the importance outputs: importance,
 *                checkpoints, stopped_at, vertex_importance (reduce.c); with a history, that
 *                importance copied back to the original vertices: remapped, distance
 *                (reduce_passes.c)
 *   budget       decimation inputs and the plan of Eq. 3: input, plan (reduce.c)
 *   decimation   the planned meshes, then rounds that plan again with the floors meshes
 *                reached and relax locks: output, budget floors, compensation_rounds,
 *                vertices_after (reduce_decimation.c)
 *   next pass    with --passes K, between passes: this pass's output becomes the history and
 *                the view the next pass simulates; the per-pass state is reset (reduce_passes.c)
 *   memory fit   with --memory-budget: the reduced scene's exact render memory (its BVH built);
 *                above the budget, the target is lowered: render_bytes, fit_rounds, target; on
 *                a device sharing the host's memory the remapped importance waits on disk
 *                meanwhile: spill (reduce_memory.c); reduce_run() then forgets the decimation
 *                and runs the budget and decimation stages again, and the fit after them
 *   write        meshes/NAME.ply and scene.xml: ply, meshes_written (reduce.c)
 *   report       report.json (with the importance outputs) and the closing line (reduce.c; the
 *                JSON is built in reduce_report.c)
 * Per-mesh arrays are indexed like s->meshes and hold mesh_count entries. */
#ifndef IDMR_REDUCE_STAGES_H
#define IDMR_REDUCE_STAGES_H

#include <stdio.h>

#include <cjson/cJSON.h>

#include "reduce/budget.h"
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

/* What one importance pass and the reduction after it did (report.json: passes). */
typedef struct reduce_pass_record {
    double seconds_importance, seconds_reduction; /* reduction: budget and decimation */
    uint64_t vertices_simulated; /* of the scene the importance pass ran on */
    uint64_t vertices_after;     /* of the reduced scene after it */
    uint64_t device_bytes;       /* the importance pass's device memory (0: --simulation) */
    unsigned int iterations;
} reduce_pass_record;

typedef struct reduce_state {
    device *device;
    scene *scene;
    const char *outdir;   /* OUTDIR as given: what messages name */
    char staging[2048];   /* where the stages write (files_stage_begin) */
    const reduce_options *options;
    size_t count; /* meshes in the scene */
    double target;  /* D the plan aims at: --target, or less where the memory budget says so */
    double initial; /* D0 of the initial reduction: --initial, or chosen for the budget; 1: none */

    /* memory plan, memory fit (with --memory-budget): */
    double render_fixed_bytes;     /* render memory without the triangles that may go */
    sppm_memory render_memory;     /* memory fit: rendering the reduced scene, exactly */
    unsigned int fit_rounds;       /* decimations run again to fit the budget */

    scene *simulated;       /* the scene the importance pass runs on: `scene`, or `view` */
    scene *view;            /* initial, next pass: the scene with the meshes of `history` */
    decimate_output *history; /* initial, next pass: per mesh, the decimation `view` holds
                                 (no mesh: the mesh as it is); its collapse history is freed
                                 once remapped; NULL: none */
    double seconds_initial;
    uint64_t vertices_initial; /* vertices of the initially reduced scene */
    reduce_pass_record *passes; /* one per pass run */
    unsigned int pass_count;

    importance_result importance;  /* importance: per triangle of `simulated` */
    factor_checkpoint *checkpoints; /* importance: the stop rule's checkpoints (factor_stop.h) */
    size_t checkpoint_count;
    unsigned int stopped_at;       /* importance: the iteration the stop rule ended the pass
                                      after; 0 when it ran to --iterations or --tolerance */
    double **vertex_importance;    /* importance: per mesh, per vertex of `simulated`; NULL
                                      without the pass */
    double **remapped;             /* importance: with a history, per mesh whose history has
                                      collapses, per original vertex (remap.h); else NULL */
    uint32_t **distance;           /*             and each one's distance from its source */
    FILE *spill;                   /* memory fit: the remapped importance, while it is out of
                                      memory (reduce_remapped_spill); NULL otherwise */
    decimate_input *input;         /* budget: what each mesh is decimated from */
    budget_mesh *budget;           /* budget: what the plan was made from; the decimation adds
                                      the floors it learns */
    budget_plan plan;              /* budget: targets and factors; the decimation plans again
                                      with the floors it learns */
    decimate_output *output;       /* decimation: per mesh the plan decimates */
    char **not_reduced;            /* decimation: per mesh, NULL, or why the plan decimated it
                                      but its input is kept (its decimation was not smaller);
                                      such a mesh is no longer flagged in plan.decimate */
    unsigned int compensation_rounds;
    unsigned int locks_relaxed;     /* decimation: meshes whose boundary lock was relaxed */
    unsigned int seams_freed;       /* decimation: meshes whose attribute seams were freed */
    uint64_t vertices_after;       /* decimation: vertices of the reduced scene */
    char **ply;                    /* write: per decimated mesh, its file relative to outdir */
    size_t meshes_written;

    double seconds_importance, seconds_budget, seconds_decimation, seconds_write;
} reduce_state;

/* Whether mesh m can be decimated at all: not pinned, above --min-vertices. */
int reduce_decimatable(const reduce_state *st, size_t m);

/* The decimation inputs and the plan of Eq. 3 for st->target (reduce.c): importance sums set the
 * factors (methods with importance), or equal importance gives the uniform D of the quadric
 * baseline. Returns 0, or -1 with the error set. */
int reduce_plan_budget(reduce_state *st);

/* A finalised view of the scene (core/scene.h, scene_view) in which every mesh that `meshes`
 * holds a decimation of (collapsed_into set) is that decimation, and every other mesh is the
 * scene's (read again, and kept, where it was released); NULL with the error set. */
scene *reduce_view_of(reduce_state *st, const decimate_output *meshes);

/* Every released mesh (core/scene.h: streaming) read again (reduce_passes.c). 0, or -1 with the
 * error set. */
int reduce_restore_all(reduce_state *st);

/* Decimates every mesh m flagged in `selected` from inputs[m] to targets[m], in parallel
 * (decimate_many: st->options->threads), largest first, into outputs[m] (an earlier output
 * there is freed), with a progress bar named `label` over their vertices (reduce_decimation.c).
 * Released meshes (streaming) go `threads` at a time, or fewer where a budget bounds the host
 * (reduce_memory.c: a device sharing its memory): read again, decimated, released. Without
 * `keep_history` each output's collapse history is freed as soon as it is made. Returns 0, or
 * -1 with the first failure's error set. */
int reduce_decimate_meshes(reduce_state *st, const decimate_input *inputs,
                           const uint64_t *targets, const unsigned char *selected,
                           decimate_method method, const char *label, int keep_history,
                           decimate_output *outputs);

/* The memory plan and fit stages (reduce_memory.c); nothing without a budget. 0, or -1 with the
 * error set. */
int reduce_memory_plan(reduce_state *st);
/* How many of the next meshes (their input vertices, largest first; `count` of them) one
 * streaming group decimates at once: all, but under a memory budget on a device that shares the
 * host's memory only as many as keep the process's resident memory with theirs in flight within
 * the budget, and at least one. */
size_t reduce_memory_meshes_in_flight(const reduce_state *st, const uint32_t *vertices,
                                      size_t count);
/* The fit: the reduced scene's exact render memory; above the budget, a lower st->target and
 * *again set (the remapped importance read back: reduce_run() decimates again); after
 * FIT_ROUNDS such rounds, an error. */
int reduce_memory_fit(reduce_state *st, int *again);

/* What mesh m is decimated from (reduce.c): the scene's mesh, its attributes as reduce.h says,
 * and its per-vertex importance (remapped where there is a history). A released mesh (core/
 * scene.h: streaming) gives no geometry: reduce_decimate_meshes() reads it again first. */
decimate_input reduce_decimation_input(const reduce_state *st, size_t m);

/* Whether mesh m is decimated with texture coordinates and with shading normals (the rules of
 * reduce_decimation_input), whether its geometry is in memory or released. */
void reduce_mesh_attributes(const reduce_state *st, size_t m, int *texcoords, int *normals);

/* The initial reduction (with --initial; nothing otherwise), and the change from one pass to the
 * next (reduce_passes.c). Return 0, or -1 with the error set. */
int reduce_initial(reduce_state *st);
int reduce_next_pass(reduce_state *st);

/* After the importance pass: with a history, the importance per vertex of the simulated scene
 * copied back to the originals into st->remapped and st->distance (reduce_passes.c). */
void reduce_remap(reduce_state *st);

/* The remapped importance moved into an unnamed file in the staging directory, out of memory,
 * and read back (reduce_memory.c: while the fit builds the reduced scene's BVH on a device that
 * shares the host's memory, only a further decimation needs it). Each 0 (nothing to do without
 * a remapped importance, or none spilled), or -1 with the error set. */
int reduce_remapped_spill(reduce_state *st);
int reduce_remapped_restore(reduce_state *st);

/* Frees what reduce_initial(), reduce_next_pass() and reduce_remap() left in the state. */
void reduce_passes_free(reduce_state *st);

/* Emitters, meshes named with --keep and meshes without area (every triangle degenerate: all
 * its points coincide or lie on a line) are never decimated. */
int reduce_mesh_pinned(const reduce_options *o, const scene_mesh *mesh);

/* OUTDIR checked: an existing non-empty one needs force; never a directory holding a file the
 * scene reads (scene_check_output_directory: inputs are never written). Then the staging
 * directory beside it into st->staging. Returns 0, or -1 with the error
 * set. reduce_outdir_finish() publishes the staging directory as OUTDIR when `success`, else
 * removes it. */
int reduce_outdir_prepare(reduce_state *st);
int reduce_outdir_finish(reduce_state *st, int success);

/* Decimates the meshes the plan decimates, in parallel, largest first, then plans again with the
 * floors meshes reached and relaxes locks where the request cannot be met otherwise. A mesh
 * whose decimation keeps at least as many vertices as it has (below a target under its count)
 * keeps its input instead, with the reason in st->not_reduced and a warning: a reduction never
 * makes a mesh larger. Returns 0, or -1 with the error set. */
int reduce_decimation(reduce_state *st);
/* Frees what the budget and decimation stages left (inputs, plan, outputs, their counts), so
 * that they can run again. */
void reduce_decimation_forget(reduce_state *st);

/* report.json's content: the importance report's keys (method importance) or the scene name,
 * then the reduction's options, totals, seconds and per-mesh figures. The caller deletes it. */
cJSON *reduce_report_json(const reduce_state *st);

#endif
