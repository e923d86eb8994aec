/* weld.c — weld_flat() (weld.h): positions welded through an open-addressing table of welded
 * indices, attribute sets numbered through a second one, degenerate triangles dropped, and the
 * manifold check on a counting-sorted vertex -> triangle adjacency. */
#include "reduce/weld.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"

#define EMPTY 0xffffffffu
#define MAX_ATTRIBUTE_FLOATS 5

static uint32_t mix(uint32_t h, uint32_t word)
{
    h ^= word;
    h *= 0x9e3779b1u;
    return h ^ (h >> 15);
}

/* A table size: a power of two at least twice the count. */
static size_t table_size(size_t count)
{
    size_t size = 16;
    while (size < 2 * count)
        size *= 2;
    return size;
}

/* The position's bits, -0 folded into 0. */
static void position_bits(const float *p, uint32_t bits[3])
{
    for (int k = 0; k < 3; k++) {
        float folded = p[k] + 0.0f;
        memcpy(&bits[k], &folded, sizeof bits[k]);
    }
}

static void weld_positions(const decimate_input *in, weld_result *out)
{
    size_t size = table_size(in->vertex_count), mask = size - 1;
    uint32_t *table = xmalloc(sizeof(uint32_t) * size);
    memset(table, 0xff, sizeof(uint32_t) * size);
    out->welded_of = xmalloc(sizeof(uint32_t) * ((size_t)in->vertex_count + 1));
    out->positions = xmalloc(3 * sizeof(float) * ((size_t)in->vertex_count + 1));
    out->importance = xmalloc(sizeof(double) * ((size_t)in->vertex_count + 1));
    uint32_t count = 0;
    for (uint32_t v = 0; v < in->vertex_count; v++) {
        uint32_t bits[3];
        position_bits(&in->positions[3 * (size_t)v], bits);
        size_t slot = mix(mix(mix(0, bits[0]), bits[1]), bits[2]) & mask;
        double value = in->vertex_importance ? in->vertex_importance[v] : 0.0;
        for (;; slot = (slot + 1) & mask) {
            uint32_t w = table[slot];
            if (w == EMPTY) {
                table[slot] = count;
                memcpy(&out->positions[3 * (size_t)count], bits, sizeof bits);
                out->importance[count] = value;
                out->welded_of[v] = count++;
                break;
            }
            if (memcmp(&out->positions[3 * (size_t)w], bits, sizeof bits) == 0) {
                out->welded_of[v] = w;
                if (value > out->importance[w])
                    out->importance[w] = value;
                break;
            }
        }
    }
    out->vertex_count = count;
    free(table);
}

/* Per input vertex its attribute id: one per welded vertex and bit-distinct (uv, normal). */
static uint32_t *number_attributes(const decimate_input *in, weld_result *out)
{
    int floats = (in->texcoords ? 2 : 0) + (in->normals ? 3 : 0);
    out->uv_floats = in->texcoords ? 2 : 0;
    out->normal_floats = in->normals ? 3 : 0;
    if (!floats)
        return NULL;
    size_t size = table_size(in->vertex_count), mask = size - 1;
    uint32_t *table = xmalloc(sizeof(uint32_t) * size);
    memset(table, 0xff, sizeof(uint32_t) * size);
    uint32_t *id_of = xmalloc(sizeof(uint32_t) * ((size_t)in->vertex_count + 1));
    uint32_t *welded_of_id = xmalloc(sizeof(uint32_t) * ((size_t)in->vertex_count + 1));
    out->attributes = xmalloc(sizeof(float) * floats * ((size_t)in->vertex_count + 1));
    uint32_t count = 0;
    for (uint32_t v = 0; v < in->vertex_count; v++) {
        float value[MAX_ATTRIBUTE_FLOATS];
        int n = 0;
        for (int k = 0; k < out->uv_floats; k++)
            value[n++] = in->texcoords[2 * (size_t)v + k] + 0.0f;
        for (int k = 0; k < out->normal_floats; k++)
            value[n++] = in->normals[3 * (size_t)v + k] + 0.0f;
        uint32_t welded = out->welded_of[v], h = mix(0, welded);
        for (int k = 0; k < n; k++) {
            uint32_t bits;
            memcpy(&bits, &value[k], sizeof bits);
            h = mix(h, bits);
        }
        for (size_t slot = h & mask;; slot = (slot + 1) & mask) {
            uint32_t id = table[slot];
            if (id == EMPTY) {
                table[slot] = count;
                welded_of_id[count] = welded;
                memcpy(&out->attributes[(size_t)floats * count], value, sizeof(float) * n);
                id_of[v] = count++;
                break;
            }
            if (welded_of_id[id] == welded &&
                memcmp(&out->attributes[(size_t)floats * id], value, sizeof(float) * n) == 0) {
                id_of[v] = id;
                break;
            }
        }
    }
    out->attribute_count = count;
    free(welded_of_id);
    free(table);
    return id_of;
}

static void keep_triangles(const decimate_input *in, const uint32_t *id_of, weld_result *out)
{
    out->triangles = xmalloc(3 * sizeof(uint32_t) * ((size_t)in->triangle_count + 1));
    if (id_of)
        out->corner_ids = xmalloc(3 * sizeof(uint32_t) * ((size_t)in->triangle_count + 1));
    uint32_t kept = 0;
    for (uint32_t t = 0; t < in->triangle_count; t++) {
        const uint32_t *ix = &in->indices[3 * (size_t)t];
        uint32_t a = out->welded_of[ix[0]], b = out->welded_of[ix[1]], c = out->welded_of[ix[2]];
        if (a == b || b == c || a == c) {
            out->triangles_dropped++;
            continue;
        }
        uint32_t *corner = &out->triangles[3 * (size_t)kept];
        corner[0] = a, corner[1] = b, corner[2] = c;
        if (id_of)
            for (int k = 0; k < 3; k++)
                out->corner_ids[3 * (size_t)kept + k] = id_of[ix[k]];
        kept++;
    }
    out->triangle_count = kept;
}

/* Whether v's triangles (their corners after v: next[i], before v: previous[i]) are one fan with
 * every directed edge from v once: each next and each previous distinct, and one walk from the
 * open end (or anywhere, when closed) meets them all. */
static int one_fan(const uint32_t *next, const uint32_t *previous, uint32_t count)
{
    uint32_t open_ends = 0, start = 0;
    for (uint32_t i = 0; i < count; i++) {
        int preceded = 0;
        for (uint32_t j = 0; j < count; j++) {
            if (j != i && (next[j] == next[i] || previous[j] == previous[i]))
                return 0;
            preceded |= previous[j] == next[i];
        }
        if (!preceded) {
            open_ends++;
            start = i;
        }
    }
    if (open_ends > 1)
        return 0;
    uint32_t at = start, steps = 1;
    for (; steps < count; steps++) {
        uint32_t following = count;
        for (uint32_t j = 0; j < count; j++)
            if (next[j] == previous[at]) {
                following = j;
                break;
            }
        if (following == count || following == start)
            break;
        at = following;
    }
    return steps == count;
}

/* The manifold check and the wedge count, on a vertex -> triangle adjacency. */
static void check_manifold(weld_result *out)
{
    uint32_t n = out->vertex_count;
    uint32_t *start = xcalloc((size_t)n + 2, sizeof(uint32_t));
    for (size_t c = 0; c < 3 * (size_t)out->triangle_count; c++)
        start[out->triangles[c] + 1]++;
    uint32_t largest = 0;
    for (uint32_t v = 0; v < n; v++) {
        if (start[v + 1] > largest)
            largest = start[v + 1];
        start[v + 1] += start[v];
    }
    uint32_t *corner_of = xmalloc(sizeof(uint32_t) * (3 * (size_t)out->triangle_count + 1));
    uint32_t *fill = xmalloc(sizeof(uint32_t) * ((size_t)n + 1));
    memcpy(fill, start, sizeof(uint32_t) * n);
    for (size_t c = 0; c < 3 * (size_t)out->triangle_count; c++)
        corner_of[fill[out->triangles[c]]++] = (uint32_t)c;
    uint32_t *next = xmalloc(sizeof(uint32_t) * (2 * (size_t)largest + 1)), *previous = next + largest;
    for (uint32_t v = 0; v < n; v++) {
        uint32_t count = start[v + 1] - start[v];
        if (!count)
            continue;
        uint32_t wedges = 0;
        for (uint32_t i = 0; i < count; i++) {
            uint32_t c = corner_of[start[v] + i], t = c / 3, k = c % 3;
            next[i] = out->triangles[3 * t + (k + 1) % 3];
            previous[i] = out->triangles[3 * t + (k + 2) % 3];
            if (out->corner_ids) {
                uint32_t id = out->corner_ids[c], seen = 0;
                for (uint32_t j = 0; j < i && !seen; j++)
                    seen = out->corner_ids[corner_of[start[v] + j]] == id;
                wedges += !seen;
            }
        }
        out->vertices_counted += out->corner_ids ? wedges : 1;
        if (!one_fan(next, previous, count))
            out->non_manifold_vertices++;
    }
    free(next);
    free(fill);
    free(corner_of);
    free(start);
}

int weld_flat(const decimate_input *in, weld_result *out)
{
    memset(out, 0, sizeof *out);
    weld_positions(in, out);
    uint32_t *id_of = number_attributes(in, out);
    keep_triangles(in, id_of, out);
    free(id_of);
    check_manifold(out);
    return 0;
}

void weld_result_free(weld_result *out)
{
    free(out->positions);
    free(out->importance);
    free(out->welded_of);
    free(out->triangles);
    free(out->corner_ids);
    free(out->attributes);
    free(out->locked);
    memset(out, 0, sizeof *out);
}
