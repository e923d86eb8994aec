/* importance_outputs.h — what `idmr importance` and `idmr reduce` write of an importance pass:
 *
 *   DIR/report.json          options, per-stage seconds, per-mesh sums, convergence, counts;
 *                            an instanced shape's copies: the sums on the representative are
 *                            the prototype's, over all copies (importance_sum, ...), and every
 *                            copy, the representative too, has its own (copy_importance_sum,
 *                            copy_camera_sum, copy_light_sum, copy_shadow_sum:
 *                            importance_copy_sums), which over the copies add up to those
 *   DIR/convergence.csv      iteration, change Δ, gather radius
 *   DIR/importance/<m>.ply   each mesh (world space) with a per-vertex `importance` property
 *                            and false-colour vertex colours
 *   DIR/importance.png       the importance of what the scene camera sees, per triangle, in
 *                            false colour (the paper's Fig. 3)
 * Colours map log10(I) over three decades below the 99th percentile of the scene's non-zero
 * values to the ramp of image_false_colour(); zero importance is black. Every file is written
 * under a temporary name and renamed. */
#ifndef IDMR_IMPORTANCE_OUTPUTS_H
#define IDMR_IMPORTANCE_OUTPUTS_H

#include <cjson/cJSON.h>

#include "device/device.h"
#include "passes/importance.h"
#include "core/scene.h"

/* The report as a JSON object (the caller adds keys and deletes it). */
cJSON *importance_report_json(const scene *s, const device *d, const importance_options *o,
                              const importance_result *r);

/* Per-vertex importance of every mesh (importance_mesh_vertices), as one array per mesh:
 * computed once, for the outputs and the decimation. Free with importance_vertex_values_free(). */
double **importance_vertex_values(const importance_result *r, const scene *s,
                                  const importance_weights *w);
void importance_vertex_values_free(double **values, const scene *s);

/* Writes report.json (from `report`), convergence.csv, importance/ and importance.png, with the
 * per-vertex importance `vertex_values` (importance_vertex_values()). */
int importance_write_outputs(const char *dir, const cJSON *report, const scene *s,
                             const importance_options *o, const importance_result *r,
                             double *const *vertex_values);

/* A file name made from a mesh name: letters, digits, '-', '_' and '.' kept, others '_'. */
void importance_file_name(const char *mesh_name, char *out, size_t size);

#endif
