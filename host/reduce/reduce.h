/* reduce.h — `idmr reduce`: the importance pass, the decimation factors across meshes
 * (reduce/budget.h, paper Eq. 3), the decimation (reduce/decimate.h), and the reduced scene:
 *
 *   OUTDIR/scene.xml         the input XML, decimated shapes pointing to meshes/<name>.ply
 *   OUTDIR/meshes/NAME.ply   the decimated meshes (world space)
 *   (a glTF scene instead: OUTDIR/scene.gltf + scene.bin, or scene.glb, io/gltf/gltf.h)
 *   OUTDIR/report.json       the importance report's keys, plus target, method, per mesh
 *                            factor / vertices_before / vertices_after, per-stage seconds;
 *                            with --max-error, error_budget: the curve the search walked;
 *                            with --refine, refine: the rounds of error-driven refinement
 *   OUTDIR/importance.png, importance/, convergence.csv   (method importance)
 *
 * Methods (reduce_method): "importance" (the paper's: importance sets each mesh's budget, Eq. 3,
 * and the order of collapses within it, 3.4), "quadric" (OpenMesh's quadric decimation at the
 * uniform factor D, the view-independent baseline; no importance pass), "importance-quadric"
 * (importance sets each mesh's budget, quadric error metrics choose the collapses) and
 * "combined" (importance sets each mesh's budget, and the collapses follow the quadric error
 * weighted by importance, open boundaries locked: decimate.h, DECIMATE_COMBINED), the default:
 * it changes the rendered image least on the evaluation scenes (README, Evaluation).
 * Emitters and meshes named with --keep are never decimated; meshes with at most min_vertices
 * vertices neither. OUTDIR must not exist or be empty unless force is set, and must not be the
 * scene's own directory. The paths OUTDIR/scene.xml names are relative to OUTDIR; with bundle,
 * every file it names is copied under OUTDIR (io/mitsuba/mitsuba_write.h).
 *
 * Multiple passes and the initial reduction (paper 3.5, options initial and passes): the first
 * importance pass runs on the scene quadric-reduced to D0 (or on the scene itself), each later
 * one on the previous pass's result; every pass's importance is copied back to the original
 * vertices along the collapse chains (remap.h) and the originals are decimated from it.
 *
 * Streaming: a scene loaded with its large meshes released (io/scene_load.h,
 * scene_load_streaming; `idmr reduce --memory-budget` loads so) is reduced with each released
 * mesh read again only while it is decimated, `threads` at a time, and released after, so host
 * memory holds the meshes in flight, the reduced copies and the per-vertex importance, not the
 * whole scene. Meshes the initial reduction leaves whole are read again and kept; without an
 * initial reduction the importance pass needs the whole scene, and all are read again.
 *
 * Files: reduce.c (the pipeline: the stages in order and every loop back), one file per stage:
 * reduce_options.c, reduce_outdir.c, reduce_memory.c (the memory budget's whole policy: the
 * target and initial reduction it asks for, and the check that the reduced scene fits it),
 * reduce_passes.c (the initial reduction, the scene each pass simulates, the remapping),
 * reduce_importance.c (the importance pass, with factor_stop.c saying when it has learnt
 * enough), reduce_budget.c (the plan of Eq. 3), reduce_decimation.c (with the compensation
 * rounds), reduce_error_budget.c (--max-error: the target searched for by rendering each
 * reduction, error_search.h), reduce_refine.c (--refine: the reduction refined by where its
 * check renders changed, refine_weights.h), reduce_write.c and reduce_report.c; and reduce_inputs.c (what the stages ask of each
 * mesh). The stages share the reduce_state of reduce_stages.h. */
#ifndef IDMR_REDUCE_H
#define IDMR_REDUCE_H

#include "reduce/decimate.h"
#include "device/device.h"
#include "passes/importance.h"
#include "core/scene.h"

/* Meshes with fewer vertices are left whole by the initial reduction (paper 5: the Cornell
 * box's walls), whatever D0: it would only take their shape, and they are small. */
#define REDUCE_INITIAL_FLOOR 1024u
/* The most rounds --refine may ask for. */
#define REDUCE_MAX_REFINE 16u

/* The most importance passes --passes may ask for. */
#define REDUCE_MAX_PASSES 16u
/* The share of a --memory-budget the plan aims at (reduce_memory.c): room for its estimates. */
#define REDUCE_MEMORY_MARGIN 0.95
/* The host memory one mesh takes while it is decimated, per input vertex: read again, welded,
 * the collapse engine's arrays, the output. Measured on the full dragon (437,645 vertices) with
 * the engine (decimate_mesh, two threads): 347 bytes with the combined method, 571 with its
 * computed normals carried (their attribute quadrics), 387 with quadric and normals; with
 * OpenMesh's decimater before it, 500 and 640. On a device that shares the host's memory the
 * plan refuses a budget that cannot hold the largest such mesh beside what the process holds. */
#define REDUCE_IN_FLIGHT_BYTES_PER_VERTEX 700.0

typedef enum reduce_method {
    REDUCE_IMPORTANCE,
    REDUCE_QUADRIC,
    REDUCE_IMPORTANCE_QUADRIC,
    REDUCE_COMBINED,
} reduce_method;

/* --max-error E or --max-error-relative F (reduce_error_budget.c, error_search.h): the target is
 * searched for instead of given. */
typedef enum reduce_error_bound {
    REDUCE_ERROR_NONE,     /* --target (or --memory-budget) sets D */
    REDUCE_ERROR_ABSOLUTE, /* max_error in the units of `idmr compare --paired` */
    REDUCE_ERROR_RELATIVE, /* max_error times the original render's mean radiance */
} reduce_error_bound;

typedef struct reduce_error_options {
    reduce_error_bound bound;
    double max_error;        /* E (>= 0), or the fraction F of the mean radiance */
    double step;             /* the search ends when the passing and failing D are within a
                                ratio of 1 + step (default 0.1) */
    unsigned int iterations; /* SPPM iterations of each check render (default 16) */
    double resolution;       /* scale of the scene's film for the check renders (default 0.25) */
    unsigned int photons;    /* photon paths per iteration of a check render (default 50,000;
                                0: the device's default) */
} reduce_error_options;

#define REDUCE_ERROR_STEP 0.1
#define REDUCE_ERROR_ITERATIONS 16u
#define REDUCE_ERROR_RESOLUTION 0.25
#define REDUCE_ERROR_PHOTONS 50000u

typedef struct reduce_options {
    importance_options importance;
    reduce_error_options error; /* --max-error: the target searched for (bound set) */
    double target;           /* D: fraction of all vertices to keep, (0, 1] */
    reduce_method method;
    double factor_tolerance; /* stop the importance pass once the decimation factors move less
                                than this share of the budget (factor_stop.h; default 0.01,
                                0: run every iteration) */
    double ranking_tolerance; /* ... and, for collapses by importance, the per-vertex importance
                                 ranks change less than this (1 - Spearman's rho; default
                                 0.05, 0: not part of the rule) */
    const char *simulation;  /* when set, no importance pass: this saved one is read
                                (passes/importance_file.h) and weighted by the options */
    double initial;          /* D0 of the initial reduction (paper 3.5), (0, 1]; 1: none. The
                                importance pass then runs on the scene quadric-reduced to D0
                                (meshes of fewer than REDUCE_INITIAL_FLOOR vertices left whole)
                                and its importance is remapped to the originals (remap.h) */
    unsigned int refine;     /* --refine N: rounds of error-driven refinement after the
                                reduction (reduce_refine.c), at most REDUCE_MAX_REFINE; 0: none */
    unsigned int passes;     /* importance passes, default 1: each further one runs on the
                                previous pass's result and is remapped to the originals again */
    uint64_t memory_budget;  /* device bytes the reduced scene may take when rendered (its
                                geometry, BVH and the renderer's buffers at the scene's film
                                size and importance.sppm.photons, or the device's default
                                photons without them; passes/sppm.h, sppm_memory_of),
                                and the most the importance pass may allocate; 0: none. The
                                target becomes the smaller of --target and what fits, and
                                without --initial an initial reduction is chosen when the whole
                                scene's importance pass would not fit (reduce_memory.c) */
    unsigned long min_vertices; /* default 16 */
    double max_normal_angle; /* degrees, default 60 */
    double uv_weight;        /* combined: the attribute error term's weights (decimate.h; */
    double normal_weight;    /* defaults DECIMATE_UV_WEIGHT, DECIMATE_NORMAL_WEIGHT; 0: none) */
    int recompute_normals;   /* a mesh whose normals the loader computed (a file without them)
                                is written without normals, for the reader to compute from the
                                reduced mesh; default 0: those of the original are carried
                                through the collapses and written, so it shades as it did */
    const char **keep;       /* mesh names never decimated */
    size_t keep_count;
    int force;               /* allow a non-empty OUTDIR */
    int bundle;              /* copy every file the scene reads into OUTDIR/assets/ */
    unsigned int threads;    /* decimation threads; 0: all cores */
} reduce_options;

void reduce_options_default(reduce_options *o);

/* The method as --method names it ("importance", "quadric", "importance-quadric",
 * "combined"), and back: 0, or -1 with the error set (IDMR_EXIT_INPUT) naming the choices. */
const char *reduce_method_name(reduce_method method);
int reduce_method_parse(const char *name, reduce_method *method);

/* Whether the method runs the importance pass (and budgets meshes by Eq. 3), and how its
 * collapses are chosen. */
int reduce_method_uses_importance(reduce_method method);
decimate_method reduce_method_collapses(reduce_method method);

/* Runs the whole reduction of scene `s` (loaded from its file) into outdir. Returns 0, or -1
 * with the error set. */
int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o);

/* reduce_run() with its importance passes on the `count` devices of `devices` at once
 * (importance_run_devices: the same importance bit for bit as on the first alone). A memory
 * budget plans for one device: with several, --memory-budget is refused. */
int reduce_run_devices(device *devices, unsigned int count, scene *s, const char *outdir,
                       const reduce_options *o);

#endif
