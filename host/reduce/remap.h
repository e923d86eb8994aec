/* remap.h — importance computed on a reduced mesh, copied back to the original's vertices
 * through the reduction's collapse history (paper 3.5).
 *
 * The history of a decimation (decimate.h: welded_of, collapsed_into, output_index) links every
 * original vertex to the vertex of the reduced mesh it ended in: the input vertex's decimater
 * vertex, then the vertex that one was collapsed into, and so on, until a vertex that was not
 * collapsed (a survivor). The original vertex takes the survivor's value, and its distance is the
 * number of collapses on the way (0 for a survivor itself). A survivor split into several output
 * vertices (one per attribute wedge) gives the value of its first. A vertex whose chain ends in
 * a vertex without faces (removed without a collapse) gets 0 at distance 0.
 *
 * The decimation of the original uses the distances to break ties among the regions that now
 * share one value (decimate.h, "Remapped importance"). */
#ifndef IDMR_REMAP_H
#define IDMR_REMAP_H

#include <stdint.h>

#include "reduce/decimate.h"

/* For each of the history's original_count input vertices: values[i] = the value of the
 * reduced mesh's vertex (reduced_values, indexed like history->mesh) its chain ends in, and
 * distance[i] the collapses on the way. Runs in time linear in the vertices (each chain is
 * followed once). */
void remap_values(const decimate_output *history, uint32_t original_count,
                  const double *reduced_values, double *values, uint32_t *distance);

#endif
