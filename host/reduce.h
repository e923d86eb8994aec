/* reduce.h — `idmr reduce`: the importance pass, the decimation factors across meshes
 * (host/budget.h, paper Eq. 3), the decimation (host/decimate.h), and the reduced scene:
 *
 *   OUTDIR/scene.xml         the input XML, decimated shapes pointing to meshes/<name>.ply
 *   OUTDIR/meshes/NAME.ply   the decimated meshes (world space)
 *   OUTDIR/report.json       the importance report's keys, plus target, method, per mesh
 *                            factor / vertices_before / vertices_after, per-stage seconds
 *   OUTDIR/importance.png, importance/, convergence.csv   (method importance)
 *
 * Methods: "importance" (ours) and "quadric" (OpenMesh's quadric decimation at the uniform
 * factor D, the view-independent baseline; no importance pass). Emitters and meshes named with
 * --keep are never decimated; meshes with at most min_vertices vertices neither. OUTDIR must not
 * exist or be empty unless force is set, and must not be the scene's own directory. */
#ifndef IDMR_REDUCE_H
#define IDMR_REDUCE_H

#include "decimate.h"
#include "device.h"
#include "importance.h"
#include "scene.h"

typedef struct reduce_options {
    importance_options importance;
    double target;           /* D: fraction of all vertices to keep, (0, 1] */
    decimate_method method;
    unsigned long min_vertices; /* default 16 */
    double max_normal_angle; /* degrees, default 60 */
    const char **keep;       /* mesh names never decimated */
    size_t keep_count;
    int force;               /* allow a non-empty OUTDIR */
    unsigned int threads;    /* decimation threads; 0: all cores */
} reduce_options;

void reduce_options_default(reduce_options *o);

/* Runs the whole reduction of scene `s` (loaded from its file) into outdir. Returns 0, or -1
 * with the error set. */
int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o);

#endif
