/* reduce.h — `idmr reduce`: the importance pass, the decimation factors across meshes
 * (reduce/budget.h, paper Eq. 3), the decimation (reduce/decimate.h), and the reduced scene:
 *
 *   OUTDIR/scene.xml         the input XML, decimated shapes pointing to meshes/<name>.ply
 *   OUTDIR/meshes/NAME.ply   the decimated meshes (world space)
 *   OUTDIR/report.json       the importance report's keys, plus target, method, per mesh
 *                            factor / vertices_before / vertices_after, per-stage seconds
 *   OUTDIR/importance.png, importance/, convergence.csv   (method importance)
 *
 * Methods: "importance" (ours, the paper's: importance sets each mesh's budget, Eq. 3, and the
 * order of collapses within it, 3.4), "quadric" (OpenMesh's quadric decimation at the uniform
 * factor D, the view-independent baseline; no importance pass) and "importance-quadric"
 * (importance sets each mesh's budget, quadric error metrics choose the collapses: the paper
 * leaves combining the two open, 3.4; this is the combination that needs no weighting).
 * Emitters and meshes named with --keep are never decimated; meshes with at most min_vertices
 * vertices neither. OUTDIR must not exist or be empty unless force is set, and must not be the
 * scene's own directory.
 *
 * Files: reduce.c (the pipeline and its option, importance, budget and writing stages),
 * reduce_outdir.c, reduce_decimation.c (with the compensation rounds), reduce_report.c; the
 * stages share the reduce_state of reduce_stages.h. */
#ifndef IDMR_REDUCE_H
#define IDMR_REDUCE_H

#include "reduce/decimate.h"
#include "device/device.h"
#include "passes/importance.h"
#include "core/scene.h"

typedef struct reduce_options {
    importance_options importance;
    double target;           /* D: fraction of all vertices to keep, (0, 1] */
    decimate_method method;  /* DECIMATE_IMPORTANCE: importance budget; QUADRIC: uniform */
    int quadric_collapses;   /* with DECIMATE_IMPORTANCE: collapse by quadrics ("importance-quadric") */
    unsigned long min_vertices; /* default 16 */
    double max_normal_angle; /* degrees, default 60 */
    const char **keep;       /* mesh names never decimated */
    size_t keep_count;
    int force;               /* allow a non-empty OUTDIR */
    unsigned int threads;    /* decimation threads; 0: all cores */
} reduce_options;

void reduce_options_default(reduce_options *o);

/* "importance", "quadric" or "importance-quadric", as --method names them. */
const char *reduce_method_name(const reduce_options *o);

/* Runs the whole reduction of scene `s` (loaded from its file) into outdir. Returns 0, or -1
 * with the error set. */
int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o);

#endif
