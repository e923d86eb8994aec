/* weld.h — the decimation input welded on flat arrays: the fast path to the collapse engine.
 *
 * weld_flat() welds input vertices at bit-identical positions (-0 folded into 0) in order of first
 * appearance, keeps the largest importance of the vertices welded into one, numbers the attribute
 * sets per welded vertex (bit-identical uv and normal share an id) and drops the triangles whose
 * corners weld into fewer than three vertices: exactly what the OpenMesh rebuild
 * (decimate_weld.cc) does before it attaches faces. Then, when asked, it checks that the welded
 * triangles form a manifold: every directed edge in one triangle at most (so an edge has at most
 * two, oriented against each other) and every vertex's triangles one fan, closed or open
 * (collapse_one_fan). Where that holds, OpenMesh would attach every face and patch nothing, and
 * the flat arrays are what the engine takes; where it does not, decimate_mesh() builds the
 * OpenMesh rebuild instead, which splits the non-manifold parts (decimate.h, "Non-manifold
 * input"). decimate_mesh() welds without the check first and has the engine check the fans as it
 * sets up (collapse_mesh.fans_unchecked); only where the engine finds a vertex that is not one fan
 * does it weld again with the check.
 *
 * Two causes of a failed check are repaired first, because the rebuild answers both with copies
 * of whole layers (a double-sided sheet of 169 vertices became 338, and its reduction more
 * vertices than its input):
 *   twins        a triangle on the same three welded vertices as an earlier one (a double-sided
 *                sheet: every face again, reversed), with the same attribute ids at them, is set
 *                aside: the engine decimates one layer, and the output repeats each surviving
 *                triangle for its twins, in the twin's winding (decimate.cc)
 *   orientation  triangles wound against their neighbours (a strip converted without turning
 *                every other triangle) are turned, for the engine only, to agree with the first
 *                triangle of their piece, across every edge of exactly two triangles; the output
 *                turns them back, so every triangle keeps the winding it had (its front side)
 * What still fails the check after that goes to the rebuild, twins and turns included.
 *
 * No per-element allocation: open-addressing tables and a counting sort. The triangles are welded
 * on in->threads threads, each over a part of them, and the manifold check runs on as many, each
 * over a range of the vertices; the result is the same for any. */
#ifndef IDMR_WELD_H
#define IDMR_WELD_H

#include <stdint.h>

#include "reduce/decimate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle set aside as the twin of a kept one: its corner k is the kept triangle's corner
 * corner[k] (as the engine holds it, turned or not). */
typedef struct weld_twin {
    uint32_t primary; /* the kept triangle */
    uint32_t source;  /* the input triangle */
    uint8_t corner[3];
} weld_twin;

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
    uint32_t non_manifold_vertices; /* vertices where the check failed (0: manifold or unchecked) */
    uint32_t vertices_counted; /* vertices with triangles, once per wedge (0: unchecked) */
    uint32_t *kept_from;       /* per kept triangle: its input triangle */
    uint8_t *turned;           /* per kept triangle: wound the other way for the engine (corners
                                  1 and 2 swapped, their ids too); NULL when none is */
    uint32_t triangles_turned;
    weld_twin *twins;          /* triangles set aside as twins of kept ones, in input order */
    uint32_t twin_count;
} weld_result;

/* Welds `in` and, with `check`, checks the result (see above). Without it, the weld stops before
 * the check (and the repairs): the caller has the engine check the fans while it sets up
 * (collapse_mesh.fans_unchecked), as it builds the same vertex -> triangle adjacency anyway, and
 * welds again with the check where they fail. Returns 0 (allocation failure exits, as xmalloc
 * does). */
int weld_flat(const decimate_input *in, int check, weld_result *out);
/* Frees every array of the result (welded_of too, unless the caller took it and set it NULL). */
void weld_result_free(weld_result *out);

#ifdef __cplusplus
}
#endif

#endif
