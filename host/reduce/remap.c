/* remap.c — values of a reduced mesh copied back along the collapse chains (see remap.h). */
#include "reduce/remap.h"

#include <stdlib.h>

#include "core/error.h"

/* Marks a decimater vertex whose chain has not been followed yet. */
#define UNRESOLVED 0xffffffffu

void remap_values(const decimate_output *history, uint32_t original_count,
                  const double *reduced_values, double *values, uint32_t *distance)
{
    uint32_t n = history->history_count;
    /* Per decimater vertex: the survivor its chain ends in, and the collapses to it. */
    uint32_t *root = xmalloc(((size_t)n + 1) * sizeof *root);
    uint32_t *hops = xmalloc(((size_t)n + 1) * sizeof *hops);
    uint32_t *path = xmalloc(((size_t)n + 1) * sizeof *path);
    for (uint32_t v = 0; v < n; v++) {
        root[v] = history->collapsed_into[v] == v ? v : UNRESOLVED;
        hops[v] = 0;
    }
    for (uint32_t v = 0; v < n; v++) {
        /* Walk up to a vertex already resolved, remembering the way, then resolve it backwards:
         * each vertex is on one walk only. */
        size_t length = 0;
        uint32_t w = v;
        while (root[w] == UNRESOLVED) {
            path[length++] = w;
            w = history->collapsed_into[w];
        }
        while (length > 0) {
            uint32_t u = path[--length];
            root[u] = root[w];
            hops[u] = hops[w] + 1;
            w = u;
        }
    }
    for (uint32_t i = 0; i < original_count; i++) {
        uint32_t w = history->welded_of[i];
        uint32_t survivor = root[w];
        uint32_t index = history->output_index[survivor];
        values[i] = index == DECIMATE_REMOVED ? 0.0 : reduced_values[index];
        distance[i] = index == DECIMATE_REMOVED ? 0 : hops[w];
    }
    free(root);
    free(hops);
    free(path);
}
