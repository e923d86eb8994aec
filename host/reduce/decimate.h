/* decimate.h — the OpenMesh bridge for the reduction: one mesh in, its decimated copy out.
 *
 * Methods:
 *   DECIMATE_IMPORTANCE  our importance module (paper 3.4): a vertex's collapse priority is
 *                        the sum of importance over its one-ring, centre included; its target is
 *                        the least important neighbour among legal collapses; after a collapse
 *                        the removed vertex's importance is added to the kept one
 *   DECIMATE_QUADRIC     OpenMesh's ModQuadricT (Garland-Heckbert), the view-independent baseline
 *   DECIMATE_COMBINED    our weighted quadric module: the Garland-Heckbert error with each face's
 *                        plane weighted by its area × (its importance + a floor), and a plane
 *                        across every open boundary edge, so the image's important parts keep
 *                        their geometry; and our boundary lock: a boundary vertex is removed
 *                        only where the outline stays within 1 % of the new edge's length
 *                        (boundary_tolerance), so openings keep their outline and no hole
 *                        closes, even where the mesh then misses its target; reduce relaxes it
 *                        only where the scene's total cannot be met otherwise
 *                        (decimate_modules.hh, reduce_decimation.c)
 * Both run with our normal-limit module (a collapse may not turn any remaining face's normal by
 * more than max_normal_angle degrees, nor create a zero-area face) and our history module (for
 * each removed vertex, the vertex it went into). We use our own normal limit rather than
 * OpenMesh's ModNormalFlippingT because that one compares against stored face normals, which
 * must be refreshed after every collapse, and normalises zero-area faces into NaN; ours computes
 * both normals from the current positions and rejects degenerate results. The limit holds per
 * collapse, as in the paper; rotations can add up over many collapses (a sphere decimated by
 * importance to 20 % ended with one inward face in 5 of 20 random importance fields).
 *
 * The collapses run on our engine (collapse.h): passes over flat arrays, each scoring every
 * vertex's best collapse in parallel, ranking them, and taking them greedily in that order, each
 * judged on the mesh as it is when taken; the result does not depend on the thread count. The
 * engine enforces every rule above. The previous implementation, OpenMesh's BaseDecimaterT
 * running our modules under a heap that re-scores the kept vertex's whole one-ring after each
 * collapse (decimate_reference_mesh), stays as the reference the tests compare the engine with;
 * it takes one collapse at a time, about 30 times slower on the full dragon.
 *
 * Welding: the input is welded on flat arrays first (weld.h); a manifold result goes to the
 * engine as it is. Where it is not, twins (a triangle again on the same vertices: a double-sided
 * sheet) are set aside and repeated in the output after their triangle, and triangles wound
 * against their neighbours are turned for the engine and back in the output (weld.h), so
 * neither costs copied vertices. Non-manifold input: a half-edge mesh splits vertices where the
 * surface is not manifold and adds faces it cannot attach as loose triangles with copied
 * vertices. Here the mesh is rebuilt (with OpenMesh, where the repaired weld is still
 * non-manifold):
 * vertices at identical positions are welded, faces are attached in order and those that fail
 * are retried until no more attach; faces that still cannot be attached keep copied vertices,
 * which are locked (they cannot be collapsed) and counted apart, so the collapsible surface
 * gets the budget that remains after them. Faces that weld into zero area are dropped.
 *
 * Attributes (texture coordinates, shading normals): where the input gives them, they are kept
 * per triangle corner, so a vertex split in the input (a UV seam, a normal crease: input
 * vertices at one position with different attributes) is welded for the topology but keeps one
 * attribute set per wedge (the corners around it that share one). A collapse moves the removed
 * vertex's corners onto the kept vertex's corner in the same wedge, so every corner keeps an
 * attribute set that belongs to its position; the output splits each vertex again, once per
 * wedge. With seams kept (the default), a vertex of one wedge may go into a neighbour only
 * where the two triangles of the edge share the neighbour's wedge, a vertex of two wedges only
 * along the seam (into a vertex that continues it), and a vertex where three or more wedges
 * meet (a seam junction, a cube's corner) not at all: seams and creases stay where they are or
 * move along themselves, and a mesh flat-shaded by split vertices stays flat. With seams free,
 * any collapse is legal as far as seams go, and corners take the nearest wedge of the kept
 * vertex (reduce frees seams only where the scene's total cannot be met otherwise). With
 * normals, always, no collapse may leave a corner's normal behind its moved triangle (a
 * non-positive dot with the triangle's geometric normal): a renderer interpolating them would
 * find a zero or backward shading normal (Mitsuba 3: NaN samples). Vertex counts (targets, the
 * counts reported) count a vertex once per wedge, as the output holds them.
 *
 * The attribute error term (COMBINED): the legality rules keep seams and creases, but inside a
 * wedge a collapse still replaces the removed corner's uv and normal by the kept one's, which
 * slides the texture where the map is not affine and bends the shading where the surface
 * curves. So the weighted quadric has an attribute part (Hoppe's attribute quadrics, per wedge):
 * each face's linear interpolation of every attribute channel over its plane, and a collapse
 * costs the squared distance between the kept corner's attributes and what the faces around the
 * removed vertex showed at the kept position, in lengths: a uv difference of 1 as uv_weight ×
 * the mesh's extent (its bounding box's longest side), a normal's as normal_weight × the extent
 * (meshoptimizer's scale for attribute weights, whose users pick about 10-100 for uv and 0.5-1
 * for normals), under the same importance and area weights as the geometry. Where the map is
 * affine and the normals follow the planes (a textured wall), the term is zero. IMPORTANCE keeps
 * the paper's order and QUADRIC stays OpenMesh's geometric baseline; both have no such term.
 *
 * Files: collapse.h/.c (the engine, C), weld.h/.c (the flat weld, C); the C++ files share
 * decimate_openmesh.hh: decimate.cc (decimate_mesh, decimate_measure: the weld handed to the
 * engine),
 * decimate_weld.cc (the welded rebuild), decimate_parallel.cc (decimate_many),
 * decimate_stock.cc (decimate_stock_quadric), and the reference: decimate_reference.cc
 * (decimate_reference_mesh), decimate_modules.hh (its modules), decimate_attributes.hh (the
 * wedges, their module and the attribute quadrics), decimate_collapse.cc/.hh (its heap loop). */
#ifndef IDMR_DECIMATE_H
#define IDMR_DECIMATE_H

#include <stddef.h>
#include <stdint.h>

#include "core/progress.h"
#include "io/mesh/mesh_io.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum decimate_method {
    DECIMATE_IMPORTANCE, /* the paper's: ring importance, least important target */
    DECIMATE_QUADRIC,    /* OpenMesh's quadric error metric: geometry alone */
    DECIMATE_COMBINED,   /* quadric error weighted by importance, open boundaries locked */
} decimate_method;

typedef struct decimate_input {
    const char *name; /* for messages */
    const float *positions;
    uint32_t vertex_count;
    const uint32_t *indices;
    uint32_t triangle_count;
    const float *texcoords; /* uv per input vertex, or NULL */
    const float *normals;   /* shading normal per input vertex, or NULL */
    const double *vertex_importance; /* per input vertex; needed by IMPORTANCE and COMBINED */
    const uint32_t *vertex_distance; /* per input vertex, or NULL: the collapses between it and
                                        the vertex its importance was remapped from
                                        (reduce/remap.h); only breaks ties, see "Remapped
                                        importance" above */
    uint64_t target_vertices;        /* vertices to keep; where welding leaves fewer, fewer */
    double max_normal_angle;         /* degrees; default 60 (the paper's α_max) */
    double boundary_tolerance; /* COMBINED: the boundary lock's limit, as a share of the new
                                  edge's length; 0: DECIMATE_BOUNDARY_TOLERANCE; infinite: no
                                  lock */
    int seams_free; /* attribute seams may be collapsed across (see "Attributes" above) */
    double uv_weight;     /* COMBINED: the attribute error term's weight of texture coordinates
                             and of normals (see "Attributes" above); 0: no term. reduce uses */
    double normal_weight; /* DECIMATE_UV_WEIGHT and DECIMATE_NORMAL_WEIGHT unless told */
    unsigned int threads; /* threads inside this mesh (0: 1); the result is the same for any */
    /* decimate_reference_mesh only (tests): */
    int verify_heap;  /* after every collapse, count heap entries whose stored priority or
                         target differs from a fresh evaluation (heap_violations) */
    int reheap_removed_ring_only; /* re-score as OpenMesh's DecimaterT does */
} decimate_input;

#define DECIMATE_BOUNDARY_TOLERANCE 0.01 /* the boundary lock's default limit: 1 % */
#define DECIMATE_UV_WEIGHT 10.0   /* a uv difference of 1 counts as 10 × the mesh's extent */
#define DECIMATE_NORMAL_WEIGHT 0.5 /* a unit normal difference as 0.5 × the extent */
#define DECIMATE_REMOVED 0xffffffffu /* output_index of a vertex that is not in the output */

typedef struct decimate_output {
    mesh_data mesh; /* the decimated mesh (positions as the input's), with texcoords and normals
                       where the input has them, a vertex split once per wedge */
    uint32_t vertices_welded;        /* after welding and copying (the mesh decimated), a
                                        vertex counted once per wedge */
    uint32_t vertices_uncollapsible; /* copies in faces that could not be attached */
    uint32_t faces_patched;          /* faces attached to a separate patch of copied vertices */
    uint32_t faces_loose;            /* faces that could not be attached at all */
    uint32_t faces_dropped;          /* faces that welded into zero area */
    uint32_t collapses;
    uint32_t passes; /* the engine's passes (0 for the reference) */
    /* Where decimate_mesh's time went (0 for the reference): welding (and, where the engine
     * found the surface non-manifold, welding again with the check and the OpenMesh rebuild),
     * the engine (its stopped first setup included), the output. */
    double seconds_weld, seconds_collapse, seconds_output;
    /* The collapse history, over the decimater's history_count vertices (the welded ones, the
     * copies of patched and loose faces, and positions left without faces, which are removed
     * without a collapse). welded_of maps input vertices to them. */
    uint32_t history_count;
    uint32_t *welded_of;      /* per input vertex: its decimater vertex */
    uint32_t *collapsed_into; /* per decimater vertex: the vertex it was collapsed into, or itself
                                 (a survivor, or a removed vertex without faces) */
    uint32_t *output_index;   /* per decimater vertex: its (first) index in `mesh`, or
                                 DECIMATE_REMOVED */
    uint64_t heap_violations;
} decimate_output;

/* The vertices the decimater starts from (welded, plus the copies of faces that cannot be
 * attached) and how many of those are uncollapsible copies, without decimating: the figures
 * decimate_mesh() reports as vertices_welded and vertices_uncollapsible. */
int decimate_measure(const decimate_input *in, uint32_t *vertices, uint32_t *uncollapsible);

/* Decimates one mesh. Returns 0, or -1 with the error set (OpenMesh failure, such as a
 * decimater that does not initialise). The target may not be reached when collapses run out
 * (out->mesh.vertex_count says what was). */
int decimate_mesh(const decimate_input *in, decimate_method method, decimate_output *out);
void decimate_output_free(decimate_output *out);

/* The reference the engine is tested against: the same welded rebuild and rules on OpenMesh's
 * decimater, one collapse at a time in heap order (decimate_reference.cc). Same contract as
 * decimate_mesh(); in->threads is ignored. */
int decimate_reference_mesh(const decimate_input *in, decimate_method method,
                            decimate_output *out);
/* Frees the collapse history alone (welded_of, collapsed_into, output_index: 12 bytes per input
 * vertex), keeping the decimated mesh, once nothing will follow the chains again. */
void decimate_output_free_history(decimate_output *out);

/* The benchmark's baseline: stock OpenMesh (DecimaterT with ModQuadricT, nothing else) on the
 * mesh as OpenMesh builds it, to target_vertices of in->vertex_count. Returns the output vertex
 * count, or -1 with the error set. */
long decimate_stock_quadric(const decimate_input *in);

/* Decimates `count` meshes on `threads` threads, largest first; where there are fewer meshes than
 * threads, each mesh gets a share of the threads inside it (in[i].threads is overridden). status[i] is 0 or -1;
 * messages[i] (may be NULL) gets the error of a failed mesh. `bar` (may be NULL) advances by
 * each mesh's input vertices when it is done (progress_advance). Returns the number that
 * failed. */
size_t decimate_many(const decimate_input *in, decimate_output *out, int *status,
                     char (*messages)[512], size_t count, decimate_method method,
                     unsigned int threads, progress *bar);

#ifdef __cplusplus
}
#endif

#endif
