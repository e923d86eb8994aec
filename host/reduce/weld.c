/* weld.c — weld_flat() (weld.h): positions welded through an open-addressing table of welded
 * indices, attribute sets numbered through a second one, degenerate triangles dropped, and the
 * manifold check on a counting-sorted vertex -> triangle adjacency; where it fails, twins found
 * through a table of vertex triples and windings made to agree by a walk across the edges of
 * two triangles, and the check again. */
#include "reduce/weld.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "reduce/collapse.h"

#define EMPTY 0xffffffffu
#define MAX_ATTRIBUTE_FLOATS 5
#define WELD_THREADS 64   /* the most the triangles' weld and the manifold check start */
#define WELD_BLOCK 16384  /* triangles or vertices a thread of theirs takes at the least */

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

/* How many threads share `count` items: `threads` (at least 1), at most WELD_THREADS, and no
 * more than blocks of WELD_BLOCK items (a few items are done sooner than a thread starts). */
static unsigned int weld_threads(unsigned int threads, size_t count)
{
    if (threads < 1)
        threads = 1;
    if (threads > WELD_THREADS)
        threads = WELD_THREADS;
    while (threads > 1 && (size_t)(threads - 1) * WELD_BLOCK >= count)
        threads--;
    return threads;
}

/* run(part) for each of `count` parts (parts: an array of `size`-byte records), part 0 on the
 * calling thread and the others on threads of their own; where a thread cannot be started, the
 * caller runs its part. */
static void run_parts(void *(*run)(void *), void *parts, size_t size, unsigned int count)
{
    pthread_t thread[WELD_THREADS];
    int started[WELD_THREADS] = {0};
    for (unsigned int i = 1; i < count; i++)
        started[i] = pthread_create(&thread[i], NULL, run, (char *)parts + i * size) == 0;
    run(parts);
    for (unsigned int i = 1; i < count; i++) {
        if (started[i])
            pthread_join(thread[i], NULL);
        else
            run((char *)parts + i * size);
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

/* The input triangles [first, end) welded (keep_triangles): the kept ones written from place
 * `first` of the kept arrays on, in order; `kept` of them. */
typedef struct triangle_part {
    const decimate_input *in;
    const uint32_t *id_of;
    weld_result *out;
    uint32_t first, end, kept;
} triangle_part;

static void *keep_part(void *arg)
{
    triangle_part *part = arg;
    const decimate_input *in = part->in;
    const uint32_t *id_of = part->id_of;
    weld_result *out = part->out;
    uint32_t kept = part->first;
    for (uint32_t t = part->first; t < part->end; t++) {
        const uint32_t *ix = &in->indices[3 * (size_t)t];
        uint32_t a = out->welded_of[ix[0]], b = out->welded_of[ix[1]], c = out->welded_of[ix[2]];
        if (a == b || b == c || a == c)
            continue;
        uint32_t *corner = &out->triangles[3 * (size_t)kept];
        corner[0] = a, corner[1] = b, corner[2] = c;
        if (id_of)
            for (int k = 0; k < 3; k++)
                out->corner_ids[3 * (size_t)kept + k] = id_of[ix[k]];
        out->kept_from[kept] = t;
        kept++;
    }
    part->kept = kept - part->first;
    return NULL;
}

/* The input triangles welded, those that weld into fewer than three vertices dropped: the
 * triangles cut into one part per thread (weld_threads), each part's kept ones moved up behind
 * the last part's, so the result is the same for any number of threads. */
static void keep_triangles(const decimate_input *in, const uint32_t *id_of, weld_result *out)
{
    out->kept_from = xmalloc(sizeof(uint32_t) * ((size_t)in->triangle_count + 1));
    out->triangles = xmalloc(3 * sizeof(uint32_t) * ((size_t)in->triangle_count + 1));
    if (id_of)
        out->corner_ids = xmalloc(3 * sizeof(uint32_t) * ((size_t)in->triangle_count + 1));
    unsigned int threads = weld_threads(in->threads, in->triangle_count);
    triangle_part part[WELD_THREADS];
    for (unsigned int i = 0; i < threads; i++)
        part[i] = (triangle_part){in, id_of, out,
                                  (uint32_t)((uint64_t)in->triangle_count * i / threads),
                                  (uint32_t)((uint64_t)in->triangle_count * (i + 1) / threads), 0};
    run_parts(keep_part, part, sizeof part[0], threads);
    uint32_t kept = 0;
    for (unsigned int i = 0; i < threads; i++) {
        if (kept != part[i].first) {
            memmove(&out->triangles[3 * (size_t)kept], &out->triangles[3 * (size_t)part[i].first],
                    3 * sizeof(uint32_t) * part[i].kept);
            memmove(&out->kept_from[kept], &out->kept_from[part[i].first],
                    sizeof(uint32_t) * part[i].kept);
            if (id_of)
                memmove(&out->corner_ids[3 * (size_t)kept],
                        &out->corner_ids[3 * (size_t)part[i].first],
                        3 * sizeof(uint32_t) * part[i].kept);
        }
        kept += part[i].kept;
    }
    out->triangle_count = kept;
    out->triangles_dropped = in->triangle_count - kept;
}

/* Per vertex its corners (c = 3 t + k), as a counting sort of the triangle list: vertex v's are
 * corner_of[start[v] .. start[v + 1]); *largest gets the most any vertex has. */
typedef struct vertex_corners {
    uint32_t *start, *corner_of;
    uint32_t largest;
} vertex_corners;

static void vertex_corners_build(const weld_result *out, vertex_corners *vc)
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
    free(fill);
    vc->start = start;
    vc->corner_of = corner_of;
    vc->largest = largest;
}

static void vertex_corners_free(vertex_corners *vc)
{
    free(vc->start);
    free(vc->corner_of);
}

/* The manifold check and the wedge count of the vertices [first, end), on a vertex -> triangle
 * adjacency; one range per thread (check_manifold). */
typedef struct manifold_range {
    const weld_result *out;
    const vertex_corners *vc;
    uint32_t first, end;
    uint32_t non_manifold, counted;
} manifold_range;

static void *check_range(void *arg)
{
    manifold_range *r = arg;
    const weld_result *out = r->out;
    const uint32_t *start = r->vc->start, *corner_of = r->vc->corner_of;
    uint32_t largest = r->vc->largest;
    collapse_half_edge *fan = xmalloc(sizeof(collapse_half_edge) * ((size_t)largest + 1));
    for (uint32_t v = r->first; v < r->end; v++) {
        uint32_t count = start[v + 1] - start[v];
        if (!count)
            continue;
        uint32_t wedges = 0;
        for (uint32_t i = 0; i < count; i++) {
            uint32_t c = corner_of[start[v] + i], t = c / 3, k = c % 3;
            fan[i].next = out->triangles[3 * t + (k + 1) % 3];
            fan[i].previous = out->triangles[3 * t + (k + 2) % 3];
            if (out->corner_ids) {
                uint32_t id = out->corner_ids[c], seen = 0;
                for (uint32_t j = 0; j < i && !seen; j++)
                    seen = out->corner_ids[corner_of[start[v] + j]] == id;
                wedges += !seen;
            }
        }
        r->counted += out->corner_ids ? wedges : 1;
        if (!collapse_one_fan(fan, count))
            r->non_manifold++;
    }
    free(fan);
    return NULL;
}

/* The manifold check and the wedge count, the vertices cut into one range per thread
 * (weld_threads, run_parts). */
static void check_manifold(weld_result *out, unsigned int threads)
{
    vertex_corners vc;
    vertex_corners_build(out, &vc);
    threads = weld_threads(threads, out->vertex_count);
    manifold_range range[WELD_THREADS];
    for (unsigned int i = 0; i < threads; i++)
        range[i] = (manifold_range){out, &vc, (uint32_t)((uint64_t)out->vertex_count * i / threads),
                                    (uint32_t)((uint64_t)out->vertex_count * (i + 1) / threads),
                                    0, 0};
    run_parts(check_range, range, sizeof range[0], threads);
    out->non_manifold_vertices = out->vertices_counted = 0;
    for (unsigned int i = 0; i < threads; i++) {
        out->non_manifold_vertices += range[i].non_manifold;
        out->vertices_counted += range[i].counted;
    }
    vertex_corners_free(&vc);
}

/* ---- repairs (weld.h): twins, orientation ---- */

/* The triangle's welded vertices in increasing order. */
static void sorted_corners(const uint32_t *corner, uint32_t sorted[3])
{
    uint32_t a = corner[0], b = corner[1], c = corner[2], t;
    if (a > b) t = a, a = b, b = t;
    if (b > c) t = b, b = c, c = t;
    if (a > b) t = a, a = b, b = t;
    sorted[0] = a, sorted[1] = b, sorted[2] = c;
}

/* Whether kept triangle t can be the twin of kept triangle p (same welded vertices): each corner
 * has the attribute id that p has at its vertex; fills the corner map. */
static int twin_of(const weld_result *out, uint32_t t, uint32_t p, uint8_t corner[3])
{
    const uint32_t *tc = &out->triangles[3 * (size_t)t], *pc = &out->triangles[3 * (size_t)p];
    for (int k = 0; k < 3; k++) {
        int j = 0;
        while (j < 3 && pc[j] != tc[k])
            j++;
        if (j == 3)
            return 0;
        if (out->corner_ids &&
            out->corner_ids[3 * (size_t)t + k] != out->corner_ids[3 * (size_t)p + j])
            return 0;
        corner[k] = (uint8_t)j;
    }
    return 1;
}

/* Sets aside every kept triangle that is the twin of an earlier one (weld.h), compacting the
 * kept triangles, their corner ids and sources in order. */
static void set_aside_twins(weld_result *out)
{
    size_t size = table_size(out->triangle_count), mask = size - 1;
    uint32_t *table = xmalloc(sizeof(uint32_t) * size);
    memset(table, 0xff, sizeof(uint32_t) * size);
    out->twins = xmalloc(sizeof(weld_twin) * ((size_t)out->triangle_count + 1));
    uint32_t kept = 0;
    for (uint32_t t = 0; t < out->triangle_count; t++) {
        /* Move t to its place first: what the table names lies before `kept`, already final. */
        if (kept != t) {
            memmove(&out->triangles[3 * (size_t)kept], &out->triangles[3 * (size_t)t],
                    3 * sizeof(uint32_t));
            if (out->corner_ids)
                memmove(&out->corner_ids[3 * (size_t)kept], &out->corner_ids[3 * (size_t)t],
                        3 * sizeof(uint32_t));
            out->kept_from[kept] = out->kept_from[t];
        }
        uint32_t key[3], other[3];
        sorted_corners(&out->triangles[3 * (size_t)kept], key);
        size_t slot = mix(mix(mix(0, key[0]), key[1]), key[2]) & mask;
        int twin = 0, known = 0;
        for (; table[slot] != EMPTY; slot = (slot + 1) & mask) {
            sorted_corners(&out->triangles[3 * (size_t)table[slot]], other);
            if (memcmp(key, other, sizeof key) == 0) {
                weld_twin *w = &out->twins[out->twin_count];
                known = 1;
                if ((twin = twin_of(out, kept, table[slot], w->corner))) {
                    w->primary = table[slot];
                    w->source = out->kept_from[kept];
                    out->twin_count++;
                }
                break;
            }
        }
        if (twin)
            continue;
        if (!known)
            table[slot] = kept;
        kept++;
    }
    out->triangle_count = kept;
    free(table);
}

/* The kept triangle other than t on the edge a -> b or b -> a of t, when exactly one is there:
 * it, with *same set when it runs a -> b too; EMPTY otherwise. */
static uint32_t edge_neighbour(const weld_result *out, const vertex_corners *vc, uint32_t t,
                               uint32_t a, uint32_t b, int *same)
{
    uint32_t found = EMPTY;
    for (uint32_t i = vc->start[a]; i < vc->start[a + 1]; i++) {
        uint32_t c = vc->corner_of[i], u = c / 3, k = c % 3;
        if (u == t)
            continue;
        const uint32_t *corner = &out->triangles[3 * (size_t)u];
        int forward = corner[(k + 1) % 3] == b, backward = corner[(k + 2) % 3] == b;
        if (!forward && !backward)
            continue;
        if (found != EMPTY)
            return EMPTY; /* an edge of three or more triangles: not crossed */
        found = u;
        *same = forward;
    }
    return found;
}

/* Turns kept triangles to agree with their neighbours (weld.h), each piece after its first
 * triangle; where a piece cannot agree (a Moebius band) the walk leaves what it met. */
static void orient(weld_result *out)
{
    uint32_t n = out->triangle_count;
    vertex_corners vc;
    vertex_corners_build(out, &vc);
    uint8_t *turn = xcalloc((size_t)n + 1, 1), *seen = xcalloc((size_t)n + 1, 1);
    uint32_t *queue = xmalloc(sizeof(uint32_t) * ((size_t)n + 1));
    for (uint32_t seed = 0; seed < n; seed++) {
        if (seen[seed])
            continue;
        seen[seed] = 1;
        size_t head = 0, tail = 0;
        queue[tail++] = seed;
        while (head < tail) {
            uint32_t t = queue[head++];
            const uint32_t *corner = &out->triangles[3 * (size_t)t];
            for (int k = 0; k < 3; k++) {
                int same = 0;
                uint32_t u = edge_neighbour(out, &vc, t, corner[k], corner[(k + 1) % 3], &same);
                if (u == EMPTY || seen[u])
                    continue;
                seen[u] = 1;
                turn[u] = (uint8_t)(turn[t] ^ same);
                queue[tail++] = u;
            }
        }
    }
    for (uint32_t t = 0; t < n; t++) {
        if (!turn[t])
            continue;
        uint32_t *corner = &out->triangles[3 * (size_t)t], swap = corner[1];
        corner[1] = corner[2], corner[2] = swap;
        if (out->corner_ids) {
            uint32_t *id = &out->corner_ids[3 * (size_t)t];
            swap = id[1], id[1] = id[2], id[2] = swap;
        }
        out->triangles_turned++;
    }
    for (uint32_t i = 0; i < out->twin_count; i++)
        if (turn[out->twins[i].primary])
            for (int k = 0; k < 3; k++)
                if (out->twins[i].corner[k])
                    out->twins[i].corner[k] = (uint8_t)(3 - out->twins[i].corner[k]);
    if (out->triangles_turned)
        out->turned = turn;
    else
        free(turn);
    free(seen);
    free(queue);
    vertex_corners_free(&vc);
}

int weld_flat(const decimate_input *in, int check, weld_result *out)
{
    memset(out, 0, sizeof *out);
    weld_positions(in, out);
    uint32_t *id_of = number_attributes(in, out);
    keep_triangles(in, id_of, out);
    free(id_of);
    if (!check)
        return 0;
    check_manifold(out, in->threads);
    if (out->non_manifold_vertices) {
        set_aside_twins(out);
        orient(out);
        check_manifold(out, in->threads);
    }
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
    free(out->kept_from);
    free(out->turned);
    free(out->twins);
    memset(out, 0, sizeof *out);
}
