/* reduce_stages.h — internal to host/reduce/reduce*.c: the state that the stages of
 * reduce_run() share, and the stages that live in files of their own.
 *
 * reduce_run() (reduce.c) runs the stages in order, each filling its part of the state and
 * reusing what the earlier ones left there, and stops at the first that fails:
 *
 *   options      --target in (0, 1], every --keep name a mesh of the scene (reduce.c)
 *   outdir       OUTDIR checked (empty unless forced, holding no input) and its staging
 *                directory made beside it, where every later stage writes; published as OUTDIR
 *                when all succeeded, removed otherwise or on an interrupt (reduce_outdir.c)
 *   importance   the importance pass (methods with importance), stopped once the decimation
 *                factors settle (factor_stop.h), or the saved pass --simulation names
 *                (passes/importance_file.h), and per-vertex importance of every mesh,
 *                computed once for the decimation and the importance outputs: importance,
 *                checkpoints, stopped_at, vertex_importance (reduce.c)
 *   budget       decimation inputs and the plan of Eq. 3: input, plan (reduce.c)
 *   decimation   the planned meshes, then rounds that plan again with the floors meshes
 *                reached and relax locks: output, budget floors, compensation_rounds,
 *                vertices_after (reduce_decimation.c)
 *   write        meshes/NAME.ply and scene.xml: ply, meshes_written (reduce.c)
 *   report       report.json (with the importance outputs) and the closing line (reduce.c; the
 *                JSON is built in reduce_report.c)
 * Per-mesh arrays are indexed like s->meshes and hold mesh_count entries. */
#ifndef IDMR_REDUCE_STAGES_H
#define IDMR_REDUCE_STAGES_H

#include <cjson/cJSON.h>

#include "reduce/budget.h"
#include "reduce/factor_stop.h"
#include "reduce/reduce.h"

/* One checkpoint of the stop rule (factor_stop.h); the changes are negative at the first. */
typedef struct factor_checkpoint {
    unsigned int iteration;
    double factor_change, ranking_change;
} factor_checkpoint;

typedef struct reduce_state {
    device *device;
    scene *scene;
    const char *outdir;   /* OUTDIR as given: what messages name */
    char staging[2048];   /* where the stages write (files_stage_begin) */
    const reduce_options *options;
    size_t count; /* meshes in the scene */

    importance_result importance;  /* importance: per scene triangle */
    factor_checkpoint *checkpoints; /* importance: the stop rule's checkpoints (factor_stop.h) */
    size_t checkpoint_count;
    unsigned int stopped_at;       /* importance: the iteration the stop rule ended the pass
                                      after; 0 when it ran to --iterations or --tolerance */
    double **vertex_importance;    /* importance: per mesh, per vertex; NULL without the pass */
    decimate_input *input;         /* budget: what each mesh is decimated from */
    budget_mesh *budget;           /* budget: what the plan was made from; the decimation adds
                                      the floors it learns */
    budget_plan plan;              /* budget: targets and factors; the decimation plans again
                                      with the floors it learns */
    decimate_output *output;       /* decimation: per mesh the plan decimates */
    unsigned int compensation_rounds;
    unsigned int locks_relaxed;     /* decimation: meshes whose boundary lock was relaxed */
    unsigned int seams_freed;       /* decimation: meshes whose attribute seams were freed */
    uint64_t vertices_after;       /* decimation: vertices of the reduced scene */
    char **ply;                    /* write: per decimated mesh, its file relative to outdir */
    size_t meshes_written;

    double seconds_importance, seconds_budget, seconds_decimation, seconds_write;
} reduce_state;

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
 * floors meshes reached and relaxes locks where the request cannot be met otherwise. Returns 0,
 * or -1 with the error set. */
int reduce_decimation(reduce_state *st);

/* report.json's content: the importance report's keys (method importance) or the scene name,
 * then the reduction's options, totals, seconds and per-mesh figures. The caller deletes it. */
cJSON *reduce_report_json(const reduce_state *st);

#endif
