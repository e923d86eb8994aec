/* weld.h — the decimation input welded on flat arrays: the fast path to the collapse engine.
 *
 * weld_flat() welds input vertices at bit-identical positions (-0 folded into 0) in order of first
 * appearance, keeps the largest importance of the vertices welded into one, numbers the attribute
 * sets per welded vertex (bit-identical uv and normal share an id) and drops the triangles whose
 * corners weld into fewer than three vertices: exactly what the OpenMesh rebuild
 * (decimate_weld.cc) does before it attaches faces. Then it checks that the welded triangles form
 * a manifold: every directed edge in one triangle at most (so an edge has at most two, oriented
 * against each other) and every vertex's triangles one fan, closed or open. Where that holds,
 * OpenMesh would attach every face and patch nothing, and the flat arrays are what the engine
 * takes; where it does not, decimate_mesh() builds the OpenMesh rebuild instead, which splits the
 * non-manifold parts (decimate.h, "Non-manifold input").
 *
 * No per-element allocation: open-addressing tables and a counting sort. */
#ifndef IDMR_WELD_H
#define IDMR_WELD_H

#include <stdint.h>

#include "reduce/decimate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct weld_result {
    uint32_t vertex_count;     /* welded vertices */
    float *positions;          /* 3 per welded vertex */
    double *importance;        /* per welded vertex (0 without input importance) */
    uint32_t *welded_of;       /* per input vertex */
    uint32_t triangle_count;   /* triangles kept, in input order */
    uint32_t *triangles;       /* 3 welded vertices per kept triangle */
    uint32_t triangles_dropped; /* welded into fewer than three vertices */
    uint32_t *corner_ids;      /* attribute id per kept corner; NULL without attributes */
    uint32_t attribute_count;
    float *attributes;         /* uv_floats + normal_floats per id */
    int uv_floats, normal_floats;
    uint8_t *locked;           /* per welded vertex, or NULL: never moved (decimate.cc fills it
                                  for the OpenMesh rebuild's loose copies) */
    uint32_t non_manifold_vertices; /* vertices where the check failed (0: manifold) */
    uint32_t vertices_counted; /* vertices with triangles, once per wedge */
} weld_result;

/* Welds `in` and checks the result (see above). Returns 0 (allocation failure exits, as xmalloc
 * does). */
int weld_flat(const decimate_input *in, weld_result *out);
/* Frees every array of the result (welded_of too, unless the caller took it and set it NULL). */
void weld_result_free(weld_result *out);

#ifdef __cplusplus
}
#endif

#endif
