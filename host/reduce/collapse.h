/* collapse.h — the collapse engine: one welded triangle mesh on flat arrays in, its reduced
 * triangles and collapse history out, for all three methods (decimate.h says what each method
 * keeps). No priority queue: the engine works in passes, as meshoptimizer's simplifier does.
 *
 * One pass:
 *   1. adjacency   per vertex, its live triangles (a counting sort of the triangle list)
 *   2. score       every free vertex whose neighbourhood changed picks its best legal
 *                  collapse (cost, then ties) into a neighbour; in parallel, each vertex on its
 *                  own, so the result does not depend on the thread count. With the cost methods
 *                  (QUADRIC, COMBINED) only where its cheapest collapse costs no more than the
 *                  pass is likely to reach (a guess from the last pass); the others are scored
 *                  by their cheapest collapse, unchecked
 *   3. rank        the candidates sorted by cost (ties broken by a total order, so the order is
 *                  the same on any run); then, from the cheapest, the unchecked candidates are
 *                  checked against the rules until the pass's limit (below) lies under the
 *                  cheapest cost left unchecked: a pass reaches a quarter to a half of its
 *                  ranking, so most of the rules' work on the rest is never done. A candidate
 *                  whose cheapest collapse breaks a rule moves to its best legal one, at its own
 *                  cost. The collapses taken are those of step 2 done for every vertex, byte for
 *                  byte, whatever the guess (tests/test_collapse_checking.c)
 *   4. apply       in that order, greedily, in chunks of 1,024 candidates: the chunk's candidates
 *                  are judged side by side on the mesh as the chunk found it (skipped where an end
 *                  was already taken in this pass; legal as scored where no collapse taken has
 *                  touched the triangles of v0, v1, vl or vr; otherwise judged again by the
 *                  rules that read what was touched, on the rings gathered anew); then, in
 *                  order, each is accepted as judged unless a collapse accepted earlier in the
 *                  chunk wrote a vertex its verdict read (v0, v1, vl, vr): that one waits for
 *                  the next chunk and is judged again. (An
 *                  unchecked candidate, reached only where nothing under the limit could be
 *                  taken, is checked there; one whose cheapest collapse breaks a rule waits at
 *                  its best legal one's cost, and the chunk's costlier ones wait with it.)
 *                  The accepted collapses write disjoint triangles and vertices and are taken
 *                  side by side. So every collapse is legal on the mesh it is applied to, and
 *                  which are taken depends on the ranking and the chunks, never on the threads.
 *                  The pass stops at the target, or at 1.5 x the cost of the candidate ranked
 *                  at a quarter of the list (the vertices with no legal collapse counted, as
 *                  the last; after meshoptimizer's rule, which ranks at the
 *                  target: cheap collapses left for the next pass are cheaper than expensive
 *                  ones taken now; a quarter keeps a cheap region from being outrun by an
 *                  expensive one, as the reference's heap would not). The target only stops
 *                  passes, it does not shape them: reducing to one vertex fewer takes the same
 *                  collapses and one more.
 * Passes repeat until the target is met or no vertex has a legal collapse. Once the collapses
 * taken leave fewer than half of the vertices, the next pass starts on the mesh made compact:
 * the live triangles at the front of the triangle list and their vertices numbered anew, both in
 * their order, so that nothing compared changes (the same collapses, byte for byte) while the
 * late passes read fewer cache lines.
 *
 * The rules (each is collapse_legal's, on the current mesh; v0 is removed into its neighbour v1;
 * fl, fr the triangles on the edge with vl, vr their third vertices):
 *   - v0 and v1 are free: not locked by the caller, not complex (a vertex whose triangles form
 *     more than one fan, or with an edge of more than two triangles);
 *   - the link condition: the one-rings of v0 and v1 share no vertex but vl and vr;
 *   - no triangle of the edge whose other two edges are both open (it would leave a dangling
 *     edge); vl != vr; no interior edge between two boundary vertices; a boundary v0 only into a
 *     boundary v1 along an open edge; v0 keeps more than two neighbours; vl and vr not both of
 *     valence 3 when joined by an edge (the collapse would fold a tetrahedron flat);
 *   - the normal limit: no triangle that moves turns by more than max_normal_angle or becomes
 *     degenerate;
 *   - COMBINED: the boundary lock (a boundary vertex goes only where the outline stays within
 *     boundary_tolerance of the new edge's length);
 *   - with attributes: the seam rules and normals on the front side (decimate.h, "Attributes").
 * The costs: QUADRIC, the plane quadrics of the faces (unweighted, as OpenMesh's ModQuadricT);
 * COMBINED, each face's plane weighted by area x (importance + floor), planes across open edges
 * and the attribute quadrics; IMPORTANCE, the importance of v0's one-ring, centre included, into
 * the least important neighbour. After a collapse v1 holds v0's quadric (or importance).
 *
 * Memory: collapse_memory() says it (per vertex: flags, the quadric and its own error, the
 * importance, the scores, the ranking's keys, the donor, room for the candidates that move when
 * checked, the acceptance's marks; per triangle corner: the adjacency and a ring slot of 16
 * bytes; per triangle: its place in the live list and, compacted, the caller's number; the
 * ranking's radix sort's counts, at most 2 MiB; per vertex the compacted mesh keeps, at most half
 * of them, its position and the caller's number), 342 bytes per vertex of the dragon with the
 * quadric methods, 254 with IMPORTANCE;
 * COMBINED adds its attribute quadrics per attribute set.
 * The caller's arrays are used in place: the triangles and corner ids are rewritten, nothing
 * else (a removed triangle's corner ids are left as they fall). */
#ifndef IDMR_COLLAPSE_H
#define IDMR_COLLAPSE_H

#include <stddef.h>
#include <stdint.h>

#include "reduce/decimate.h"

#ifdef __cplusplus
extern "C" {
#endif

#define COLLAPSE_NONE 0xffffffffu

/* A welded mesh. Vertices without live triangles are ignored. */
typedef struct collapse_mesh {
    uint32_t vertex_count;
    const float *positions; /* 3 per vertex */
    uint32_t triangle_count;
    uint32_t *triangles;    /* 3 distinct vertex indices per triangle, counter-clockwise; the
                               engine rewrites them: a removed triangle gets COLLAPSE_NONE in
                               all three */
    uint32_t *corner_ids;   /* attribute id per corner (3 per triangle), rewritten with the
                               triangles; NULL: no attributes. An id belongs to one vertex: the
                               corners of one vertex only (collapse_run refuses other input) */
    const float *attributes; /* attribute_stride floats per id: uv (2) then normal (3), as
                                uv_floats and normal_floats say */
    uint32_t attribute_count;
    int uv_floats, normal_floats;
    const uint8_t *locked;   /* per vertex, or NULL: locked vertices never move */
    const double *importance; /* per vertex; IMPORTANCE and COMBINED */
    const uint32_t *distance; /* per vertex, or NULL: remap distance, for ties (decimate.h) */
    int fans_unchecked; /* the caller has not checked that each vertex's triangles are one fan
                           (collapse_one_fan): the engine checks it while it sets up, and where a
                           vertex's are not, stops before any collapse and says how many
                           (collapse_result.non_manifold_vertices) */
} collapse_mesh;

typedef struct collapse_options {
    decimate_method method;
    uint64_t target_vertices;  /* counted once per wedge (distinct corner id) */
    double max_normal_angle;   /* degrees, > 0 */
    double boundary_tolerance; /* COMBINED; infinite: no boundary lock */
    int seams_free;
    double uv_weight, normal_weight; /* COMBINED's attribute term (decimate.h) */
    unsigned int threads;            /* 1 or more: the result does not depend on it */
} collapse_options;

typedef struct collapse_result {
    uint32_t *collapsed_into; /* caller's array of vertex_count: filled with the vertex each
                                 removed vertex went into, itself for the others */
    uint64_t vertices_before, vertices_after; /* counted once per wedge */
    uint32_t collapses;
    uint32_t passes;
    uint32_t non_manifold_vertices; /* fans_unchecked: the vertices whose triangles are not one
                                       fan (nothing collapsed where there are any) */
} collapse_result;

/* A triangle at a vertex, as its corners after and before the vertex (counter-clockwise). */
typedef struct collapse_half_edge {
    uint32_t next, previous;
} collapse_half_edge;

/* Whether a vertex's triangles (corners[0 .. count), in any order) are one fan, closed or open,
 * with every directed edge from the vertex once: each next and each previous distinct, and one
 * walk from the open end (or anywhere, when closed) across the shared edges meets them all. */
int collapse_one_fan(const collapse_half_edge *corners, uint32_t count);

/* Reduces the mesh in place. Returns 0, or -1 with the error set (no memory, bad input). */
int collapse_run(collapse_mesh *mesh, const collapse_options *options, collapse_result *result);

/* The bytes collapse_run() allocates for a mesh of this size (without attributes). */
size_t collapse_memory(uint32_t vertex_count, uint32_t triangle_count, decimate_method method);

/* One collapse judged on the unreduced mesh, as the first pass judges it: returns 1 and its
 * cost in *cost when v0 -> v1 is legal, 0 when a rule forbids it (*rule then names the rule),
 * -1 with the error set on bad input. For tests on hand-drawn meshes. */
int collapse_evaluate(const collapse_mesh *mesh, const collapse_options *options, uint32_t v0,
                      uint32_t v1, double *cost, const char **rule);

#ifdef __cplusplus
}
#endif

#endif
