/* reduce_ranks.c — decimation shared by MPI ranks (see reduce_stages.h, core/ranks.h): which
 * rank decimates which mesh, and the decimated meshes copied to every rank afterwards, so that
 * every rank holds the outputs one process would have made and the stages after (the plan made
 * again with the floors reached, the next pass, rank 0's writing) decide alike everywhere.
 *
 * One mesh's output travels as one block: a header of counts and figures, then the arrays in
 * this order — positions (3 floats per vertex), indices (3 per triangle), texcoords (2 per
 * vertex, when present), normals (3 per vertex, when present), and with a history welded_of
 * (one per input vertex), collapsed_into and output_index (one per decimater vertex). */
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/ranks.h"
#include "reduce/reduce_stages.h"

void reduce_ranks_assign(const uint32_t *vertices, size_t n, int *owner)
{
    int count = ranks_count();
    uint64_t *load = xcalloc((size_t)count, sizeof *load);
    for (size_t i = 0; i < n; i++) {
        int least = 0;
        for (int r = 1; r < count; r++)
            if (load[r] < load[least])
                least = r;
        owner[i] = least;
        load[least] += vertices[i] ? vertices[i] : 1;
    }
    free(load);
}

typedef struct packed_header {
    uint32_t vertex_count, triangle_count, has_texcoords, has_normals, triangles_dropped;
    uint32_t vertices_welded, vertices_uncollapsible, faces_patched, faces_loose,
        faces_dropped, collapses, passes, history_count, welded_count, has_history, padding;
    uint64_t heap_violations;
    double seconds_weld, seconds_collapse, seconds_output;
} packed_header;

/* The arrays of a block, in their order: where each lives in `out` and its bytes. */
#define PACKED_ARRAYS 7
static void arrays_of(decimate_output *out, const packed_header *h, void ***where,
                      size_t *bytes)
{
    where[0] = (void **)&out->mesh.positions;
    where[1] = (void **)&out->mesh.indices;
    where[2] = (void **)&out->mesh.texcoords;
    where[3] = (void **)&out->mesh.normals;
    where[4] = (void **)&out->welded_of;
    where[5] = (void **)&out->collapsed_into;
    where[6] = (void **)&out->output_index;
    size_t v = h->vertex_count, history = h->has_history ? h->history_count : 0;
    bytes[0] = 3 * v * sizeof(float);
    bytes[1] = 3 * (size_t)h->triangle_count * sizeof(uint32_t);
    bytes[2] = h->has_texcoords ? 2 * v * sizeof(float) : 0;
    bytes[3] = h->has_normals ? 3 * v * sizeof(float) : 0;
    bytes[4] = h->has_history ? (size_t)h->welded_count * sizeof(uint32_t) : 0;
    bytes[5] = history * sizeof(uint32_t);
    bytes[6] = history * sizeof(uint32_t);
}

/* `out` (of a mesh with `input_vertices` vertices) as one malloc'd block of *size bytes. */
static char *pack(decimate_output *out, uint32_t input_vertices, size_t *size)
{
    packed_header h = {
        .vertex_count = out->mesh.vertex_count,
        .triangle_count = out->mesh.triangle_count,
        .has_texcoords = out->mesh.texcoords != NULL,
        .has_normals = out->mesh.normals != NULL,
        .triangles_dropped = out->mesh.triangles_dropped,
        .vertices_welded = out->vertices_welded,
        .vertices_uncollapsible = out->vertices_uncollapsible,
        .faces_patched = out->faces_patched,
        .faces_loose = out->faces_loose,
        .faces_dropped = out->faces_dropped,
        .collapses = out->collapses,
        .passes = out->passes,
        .history_count = out->history_count,
        .welded_count = input_vertices,
        .has_history = out->welded_of != NULL,
        .heap_violations = out->heap_violations,
        .seconds_weld = out->seconds_weld,
        .seconds_collapse = out->seconds_collapse,
        .seconds_output = out->seconds_output};
    void **where[PACKED_ARRAYS];
    size_t bytes[PACKED_ARRAYS];
    arrays_of(out, &h, where, bytes);
    *size = sizeof h;
    for (int k = 0; k < PACKED_ARRAYS; k++)
        *size += bytes[k];
    char *block = xmalloc(*size);
    memcpy(block, &h, sizeof h);
    size_t at = sizeof h;
    for (int k = 0; k < PACKED_ARRAYS; at += bytes[k], k++)
        if (bytes[k])
            memcpy(block + at, *where[k], bytes[k]);
    return block;
}

/* The output a block holds, into `out` (freed first). */
static void unpack(const char *block, decimate_output *out)
{
    packed_header h;
    memcpy(&h, block, sizeof h);
    decimate_output_free(out);
    out->mesh.vertex_count = h.vertex_count;
    out->mesh.triangle_count = h.triangle_count;
    out->mesh.triangles_dropped = h.triangles_dropped;
    out->vertices_welded = h.vertices_welded;
    out->vertices_uncollapsible = h.vertices_uncollapsible;
    out->faces_patched = h.faces_patched;
    out->faces_loose = h.faces_loose;
    out->faces_dropped = h.faces_dropped;
    out->collapses = h.collapses;
    out->passes = h.passes;
    out->history_count = h.has_history ? h.history_count : 0;
    out->heap_violations = h.heap_violations;
    out->seconds_weld = h.seconds_weld;
    out->seconds_collapse = h.seconds_collapse;
    out->seconds_output = h.seconds_output;
    void **where[PACKED_ARRAYS];
    size_t bytes[PACKED_ARRAYS];
    arrays_of(out, &h, where, bytes);
    size_t at = sizeof h;
    for (int k = 0; k < PACKED_ARRAYS; at += bytes[k], k++) {
        int present = k == 2 ? (int)h.has_texcoords
                    : k == 3 ? (int)h.has_normals
                    : k >= 4 ? (int)h.has_history
                             : 1;
        if (!present)
            continue;
        *where[k] = xmalloc(bytes[k] ? bytes[k] : 1);
        memcpy(*where[k], block + at, bytes[k]);
    }
}

int reduce_ranks_share(int status, const size_t *meshes, const int *owner, size_t n,
                       const decimate_input *inputs, decimate_output *outputs)
{
    if (ranks_count() == 1)
        return status ? -1 : 0;
    if (ranks_sync(status, NULL))
        return -1;
    for (size_t i = 0; i < n; i++) {
        size_t m = meshes[i];
        uint64_t size = 0;
        char *block = NULL;
        if (owner[i] == ranks_rank()) {
            size_t bytes;
            block = pack(&outputs[m], inputs[m].vertex_count, &bytes);
            size = bytes;
        }
        ranks_broadcast_from(&size, sizeof size, owner[i]);
        if (owner[i] != ranks_rank())
            block = xmalloc((size_t)size);
        ranks_broadcast_from(block, (size_t)size, owner[i]);
        if (owner[i] != ranks_rank())
            unpack(block, &outputs[m]);
        free(block);
    }
    return 0;
}
