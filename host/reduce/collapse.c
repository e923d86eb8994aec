/* collapse.c — the collapse engine (collapse.h): passes of adjacency, scoring, ranking and greedy
 * application over flat arrays.
 *
 * State, per vertex: flags (locked by the caller, removed, touched or an end of a collapse taken
 * in this pass, to be scored again, its candidate not yet checked against the rules, moved when
 * checked, or with no legal collapse) and the acceptance's marks (written by a collapse accepted
 * in this chunk; touched by how many collapses of this pass), the plane quadric (10 doubles: the
 * upper triangle of A, then b, then c, for p'Ap + 2b'p + c) and its error at the vertex itself,
 * the importance, the best collapse the scoring found (target, cost, tie keys) and the donor
 * (the vertex that went into it in this pass). Per triangle: its three vertices and corner ids
 * (the caller's arrays, rewritten). Per attribute id (COMBINED with attributes): its attribute
 * quadric (see "Attribute quadrics" below). At the start of each pass the adjacency
 * (adjacency[adjacency_start[v] ..]: the live triangles at v) and the rings (ring_of: a 16-byte
 * record per neighbour, built from the half-edges the adjacency leaves in them) are built again.
 *
 * Why a vertex's pass-start triangles stay exact until it is touched: a triangle changes only
 * when one of its vertices is removed (it then moves to the kept vertex, or dies with the edge),
 * and every vertex of the removed vertex's triangles is touched. The current triangles of a
 * touched vertex are its pass-start ones plus its donor's (current_fan); a vertex receives at
 * most once in a pass, as an end of a taken collapse is not taken again.
 *
 * Threads: one pool per run (worker_pool) takes the steps (vertex_step): the adjacency by parts
 * of the triangle list (build_adjacency), the per-vertex rings, quadrics, scores and checks
 * (check_ranking), the ranking's listing by ranges and its radix sort by parts of the keys and
 * intervals of the buckets, and the chunks' judging and taking (take_in_chunks); each writes
 * only its own vertex's, range's, part's, interval's or collapse's records (and a check its
 * thread's list of moved candidates, whose order does not matter; a part of the adjacency the
 * stale bit of any vertex, which every part sets alike), so the result is the same on any
 * number of threads. */
#include "reduce/collapse.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "core/error.h"

enum {
    FLAG_LOCKED = 1,  /* the caller's lock: never removed */
    FLAG_REMOVED = 2, /* collapsed into another vertex */
    FLAG_TOUCHED = 4, /* a collapse taken in this pass changed its triangles */
    FLAG_STALE = 8,   /* its score must be computed again (it or a neighbour was touched) */
    FLAG_TAKEN = 16,  /* an end of a collapse taken in this pass */
    FLAG_UNCHECKED = 32, /* its candidate is its cheapest collapse, the rules not yet applied */
    FLAG_MOVED = 64, /* checked, its candidate moved: its ranking key is stale (check_ranking) */
    FLAG_NO_LEGAL = 128, /* scored: it has targets, but no collapse into one is legal */
};

/* What the engine keeps to skip work (a removed wedge count from per-vertex counts instead of
 * the triangles, each id's own attribute error) and the mesh it compacts between passes give
 * the same bytes as the work on the mesh as it is: a test's copy of the engine
 * (tests/test_collapse_checking.c) does the work every time, never compacts, and compares. */
#ifdef COLLAPSE_WITHOUT_SHORTCUTS
#define SHORTCUTS 0
#else
#define SHORTCUTS 1
#endif

/* A vertex's flags (FLAG_...). */
typedef uint8_t vertex_flags;

#define BOUNDARY_WEIGHT 10.0 /* COMBINED: an open edge's plane, per length² (decimate_modules) */
#define FLOOR_SHARE 0.01     /* COMBINED: the importance floor, a share of the mean */
#define PASS_COST_FACTOR 1.5f /* a pass stops at this x the cost of the candidate ranked at a
                                 quarter of the list */
#define MAX_CHANNELS 5 /* uv and normal */
#define SCORE_BLOCK 512 /* vertices a thread takes at a time */
#define MAX_THREADS 64
#define CHUNK 1024 /* candidates judged at a time when taking collapses */
#define JUDGE_BLOCK 32 /* candidates a thread judges at a time (fewer claims to share a chunk) */
#define APPLY_BLOCK 16 /* collapses a thread takes at a time */
#define PREFETCH_AHEAD 4 /* collapses ahead whose reads are asked for while one is taken */
#define JUDGE_AHEAD 8    /* candidates ahead whose reads are asked for while one is judged */
#define ACCEPT_AHEAD 8   /* judged candidates ahead whose marks are asked for while one is
                            accepted */
#define SPIN_LIMIT 4000 /* pauses (about 0.1 ms) a thread spins before it sleeps or yields */
#define FRESH_ARRAYS 4  /* the engine's large arrays: adjacency, rings, scores, quadrics */
#define ADJACENCY_PARTS 5 /* at most, parts of the live triangles build_adjacency counts apart:
                             its counters are adjacency_start and the ranking's two key arrays
                             (two counters in each) */
#define RADIX_BUCKETS 65536 /* the ranking's radix sort: two digits of the cost's bits, 16 each */
#define RADIX_PARTS 8 /* at most, parts of the keys the radix sort counts and moves apart (each
                         part has its row of RADIX_BUCKETS counters) */
#define RADIX_PART_KEYS 32768 /* at least, keys a part of the radix sort takes: with fewer, the
                                 sweeps over the buckets outweigh what the parts share (the
                                 bunny on two threads, parts of any size: 0.039 -> 0.042 s) */
#define HALF_EDGES_AT_HAND 64 /* a vertex's half-edges build_ring copies onto the stack */
#define TOUCHES_KNOWN 255 /* a vertex's touch count (vertex_marks) is exact below this */

typedef struct worker_pool worker_pool;

/* The steps the pool's threads take, each over its items (vertices, ranges of vertices, or a
 * chunk's candidates). Each item's step writes only that item's records, so the items may go to
 * any thread and the result does not depend on which. */
typedef enum vertex_step {
    STEP_START_VERTICES, /* per range of vertices (engine_init) */
    STEP_FIRST_TOUCH,   /* per 2 MiB page of the large arrays */
    STEP_COUNT_CORNERS, /* per part of the live triangles (build_adjacency) */
    STEP_SUM_CORNERS,   /* per range of vertices */
    STEP_PLACE_CORNERS, /* per range of vertices */
    STEP_FILL_CORNERS,  /* per part of the live triangles */
    STEP_WEIGH_FACES, /* per triangle (importance_floor) */
    STEP_CLEAR_ATTRIBUTE_TERMS, /* per range of attribute ids (start_attribute_quadrics) */
    STEP_FIRST_RINGS, /* per vertex: its ring, its fan checked, its wedges (engine_init) */
    STEP_QUADRICS,    /* per range of vertices (engine_init) */
    STEP_RINGS,       /* per vertex */
    STEP_SCORES,
    STEP_COUNT_CANDIDATES, /* per range of vertices (rank_candidates) */
    STEP_WRITE_KEYS,
    STEP_COUNT_DIGITS,  /* per part of the keys (rank_candidates' radix sort) */
    STEP_SUM_BUCKETS,   /* per interval of the buckets */
    STEP_PLACE_BUCKETS, /* per interval of the buckets */
    STEP_MOVE_KEYS,     /* per part of the keys */
    STEP_CHECK_CANDIDATES, /* per 64 vertices: the candidates due checked (check_ranking) */
    STEP_JUDGE, /* per candidate of a chunk (take_in_chunks) */
    STEP_APPLY,
    STEP_COMPACT /* per array (compact_array) */
} vertex_step;

/* compact's items: the arrays compacted side by side (compact_array). */
enum {
    COMPACT_TRIANGLES, /* the triangles, their corner ids and caller's numbers */
    COMPACT_QUADRICS,  /* the quadrics and their own errors */
    COMPACT_SCORES,    /* best and best_target */
    COMPACT_CALLERS,   /* the caller's numbers, positions, distances and locks */
    COMPACT_VERTICES,  /* flags, marks, importance, donors */
    COMPACT_ARRAYS
};

/* One neighbour w of a vertex v in v's one-ring: how many live triangles hold the edge to it (at
 * most 255 counted), and the third corners of those triangles: left of the triangle (v, vertex,
 * left), right of (v, right, vertex), counter-clockwise (COLLAPSE_NONE: none). For the collapse
 * v -> vertex, left and right are vl and vr, and the pairs (vertex, left) are v's triangles.
 * One record of 16 bytes per neighbour: a ring's records share one or two cache lines, which
 * the rules read at random vertices. */
typedef struct ring_entry {
    uint32_t vertex, left, right;
    uint32_t count;
} ring_entry;

/* A vertex's one-ring: a view into ring records (the pass's or a scratch's). */
typedef struct ring {
    const ring_entry *entry;
    uint32_t size;
} ring;

/* The live triangles at a vertex: its slice of the pass's adjacency while it is untouched, or
 * a list gathered from its current triangles (current_fan). */
typedef struct fan {
    const uint32_t *triangle;
    uint32_t count;
} fan;

/* Where current_fan and current_ring write: one slot for each end of a collapse. */
enum { SLOT_V0, SLOT_V1, SLOTS };

/* What a thread needs while it judges collapses. */
typedef struct scratch {
    uint32_t *fan_triangle[SLOTS];
    ring_entry *rings[SLOTS];
    size_t fan_capacity[SLOTS], ring_capacity[SLOTS];
    uint32_t *ids, *mapped; /* the removed vertex's distinct corner ids and their images */
    size_t ids_capacity;
    uint32_t *ids_before; /* a kept vertex's distinct corner ids before a collapse */
    size_t ids_before_capacity;
    struct target_key *targets;
    struct edge_sides *sides; /* per target: the sides of the edge to it (ring_sides) */
    size_t targets_capacity;
    collapse_half_edge *half_edges; /* a copy of a vertex's half-edges (build_ring) */
    size_t half_edges_capacity;
    struct rank_key *moved; /* the keys of the candidates that moved in a check (check_vertex) */
    size_t moved_count, moved_capacity;
    uint32_t step_items; /* the items of the running step published when its block was claimed */
    uint32_t not_one_fan; /* vertices whose triangles the first rings found not one fan */
    uint64_t wedges;      /* the first rings' vertices' wedges (first_ring) */
} scratch;

/* One candidate target of a vertex, for ordering them. */
typedef struct target_key {
    double key; /* the cost (QUADRIC, COMBINED) or the target's importance (IMPORTANCE) */
    uint32_t distance, vertex;
} target_key;

/* A vertex's best collapse, for ranking. */
typedef struct candidate {
    float cost;
    uint32_t distance; /* the removed vertex's */
    double target_importance;
    uint32_t target_distance;
    uint32_t vertex;
} candidate;

/* A candidate's place in the ranking (rank_candidates): its cost's bits and its vertex (the
 * rest of its record is best[vertex]). */
typedef struct rank_key {
    uint32_t cost_bits, vertex;
} rank_key;

static float key_cost(const rank_key *key)
{
    float cost;
    memcpy(&cost, &key->cost_bits, sizeof cost);
    return cost;
}

/* A candidate judged on the mesh as it is, ahead of taking it (judge): its verdict, the
 * vertices its verdict read (v0, v1, vl, vr) and those taking it writes (v0 and its ring; more
 * than WRITES_MAX: the ring is gathered again when needed), and the vertices it removes. */
#define WRITES_MAX 30
enum { VERDICT_SKIP, VERDICT_ILLEGAL, VERDICT_LEGAL };
typedef struct judgement {
    uint32_t v0, v1, vl, vr;
    uint8_t verdict, write_count; /* write_count > WRITES_MAX: too many to hold */
    uint64_t removes;
    uint32_t writes[WRITES_MAX];
} judgement;

/* Where the corners of the removed vertex go (decimate_attributes.hh, CollapseMapping). */
typedef struct mapping {
    uint32_t left_from, left_to, right_from, right_to, nearest_to;
} mapping;

/* The edge v0 -> v1 in v0's triangles. */
typedef struct edge_sides {
    uint32_t fl, fr; /* triangles, or COLLAPSE_NONE */
    uint32_t vl, vr; /* their third vertices */
} edge_sides;

/* What the acceptance of the chunks (take_in_chunks) marks at a vertex: `chunk` is the engine's
 * chunk_mark where a collapse accepted in this chunk writes it (written), and `touches` counts
 * the accepted collapses of this pass whose ring held it (from TOUCHES_KNOWN on: not known), for
 * valence_three. Written by the acceptance alone, on the calling thread, so that the flags,
 * which the other threads write, are not written there; the touches cleared where the scoring
 * clears the flags (settle_vertex). */
typedef struct vertex_marks {
    uint8_t chunk, touches;
} vertex_marks;

typedef struct engine {
    collapse_mesh *m;
    const collapse_options *o;
    uint32_t n, t;
    vertex_flags *flags;
    uint32_t *adjacency_start, *adjacency;
    uint32_t *live, live_count; /* the triangles live at the last adjacency, in order */
    int live_all; /* the list not yet written: every triangle, in order (the first adjacency) */
    /* the adjacency's parts of the live triangles (build_adjacency): where each starts in the
     * list (parts + 1 of them), its live triangles, and its counters per vertex */
    uint32_t parts, part_first[ADJACENCY_PARTS + 1], part_live[ADJACENCY_PARTS];
    uint32_t *part_counts[ADJACENCY_PARTS];
    uint32_t not_one_fan; /* the caller's fans unchecked: the vertices found not one fan */
    uint8_t *open_at; /* COMBINED's setup: per vertex, whether it has an open edge (its first
                         ring; for sum_quadrics, which reads the ring only there) */
    /* the rings of this pass: v's from slot adjacency_start[v] + v on (room for one neighbour
     * more than its triangles, as many as a vertex of one fan has), ring_size[v] long */
    ring_entry *rings;
    uint32_t *ring_size;
    /* with attributes, per vertex: the one corner id its pass-start triangles have at it, or
     * COLLAPSE_NONE where they have several (build_ring; for the scoring, target_keys, and for
     * collapse_removes: known_wedge), and how many live triangles it has (the pass-start count,
     * less those the collapses taken removed, plus those a kept end received) */
    uint32_t *wedge_id;
    uint32_t *live_degree;
    int rings_current; /* the adjacency and rings are the mesh's as it is (after engine_init) */
    double *quadric;
    double *self_error; /* per vertex: its quadric at its own position (the quadric methods; set
                           where the quadric is built or receives a donor's) */
    double *importance;
    uint32_t *donor; /* valid where the vertex kept a collapse taken in this pass (donor_of) */
    /* the scoring's results, per vertex */
    uint32_t *best_target;
    candidate *best;
    /* attribute quadrics (COMBINED with attributes) */
    int attributes_weighted, channels;
    double uv_scale, normal_scale, centre[3];
    double *attribute_terms;
    /* per attribute id: its terms' error at its vertex with its own values (attribute_error), or
     * NaN where not known since its terms last changed (own_attribute_error) */
    double *own_attribute_error;
    double min_cos, boundary_tolerance;
    double importance_floor; /* COMBINED (importance_floor()) */
    uint64_t alive;
    worker_pool *pool;
    unsigned int threads; /* the pool's, the caller's included */
    /* the ranking (rank_candidates): per range of vertices the offset of its candidates; the
     * keys sorted, `ranked` of them (and their spare) */
    uint32_t range_offset[MAX_THREADS + 1];
    /* the adjacency (build_adjacency): per range of vertices its corners, and where they start
     * (ranges > 1) */
    uint32_t range_corners[MAX_THREADS], corner_offset[MAX_THREADS + 1];
    uint32_t range_no_legal[MAX_THREADS]; /* per range: its vertices with no legal collapse */
    size_t no_legal;                      /* theirs summed: counted last in the pass's quarter */
    rank_key *keys, *spare_keys;
    size_t ranked;
    /* the ranking's radix sort (rank_candidates): the digit it sorts by, this pass's parts of
     * the keys (as many as its intervals of the buckets), per part a row of counts per bucket,
     * then of where the part's keys of each bucket go (with one part, rows 0 and 1: both
     * digits' counts), and per interval of the buckets its keys, then where they start */
    int sort_digit;
    uint32_t sort_parts;
    uint32_t *digit_counts;
    uint32_t interval_start[RADIX_PARTS];
    /* taking collapses in chunks (take_in_chunks) */
    rank_key *chunk;                /* the chunk's candidates, in ranking order */
    uint32_t chunk_size;            /* its items */
    struct judgement *judgements;   /* per item of the chunk */
    uint32_t *accepted;             /* the chunk's items taken */
    size_t waiting; /* candidates deferred, or moved when checked (in spare_keys, a heap) */
    /* the ranking's check against the rules (check_ranking) */
    float check_up_to;     /* the candidates costing at most this are checked (-1: none yet) */
    uint64_t *due;         /* a bit per vertex: its candidate is to be checked in this round */
    float score_rules_up_to; /* the cost methods' scoring applies the rules up to this cost */
    float last_limit;        /* the last pass's cost limit */
    uint32_t *moved_costs; /* the checked candidates that moved: their new costs' bits */
    uint32_t *moved_from;  /* and their keys' (those with no legal collapse too) */
    size_t moved_count, moved_from_count, moved_capacity, moved_from_capacity;
    uint32_t *sort_spare; /* room for sort_cost_bits */
    size_t sort_spare_capacity;
    vertex_marks *marks; /* per vertex (take_in_chunks) */
    uint8_t chunk_mark;
    uint32_t *history; /* the caller's collapsed_into: in the caller's vertex numbers */
    /* compaction (compact): the caller's mesh, and once compacted, the mesh the engine works on
     * (`m` points to it): the live triangles at the front of the caller's triangle list, the
     * vertices they use numbered anew, both in their order, with the caller's numbers of each
     * (vertex_of, triangle_of; NULL before the first) and the per-vertex arrays of the caller
     * it reads, compacted (positions, distance, locked) */
    collapse_mesh *caller, compacted;
    uint32_t *vertex_of, *triangle_of;
    float *positions;
    uint32_t *distance;
    uint8_t *locked;
    uint32_t removed_since_compacted; /* the collapses taken since (or since the start) */
    int compacting_first;             /* compact's: the first compaction */
    uint32_t compacted_triangles;     /* compact's: the live triangles (compact_array) */
    /* the arrays of large_array, whole 2 MiB pages each (first_touch) */
    struct {
        void *array;
        size_t pages;
    } fresh[FRESH_ARRAYS];
    size_t fresh_count;
} engine;

/* ---- small helpers ---- */

/* Vertex v's number in the caller's mesh (compact). */
static uint32_t caller_vertex(const engine *e, uint32_t v)
{
    return e->vertex_of ? e->vertex_of[v] : v;
}

#define HUGE_PAGE ((size_t)2 << 20)

/* An array of the engine's that the steps read at random places (rings, quadrics, adjacency,
 * scores): from `bytes` of 8 MiB on, aligned to 2 MiB, rounded up to whole 2 MiB (at most 2 MiB
 * more) and marked for the kernel's transparent huge pages, so that random reads over a large
 * mesh's arrays miss the TLB far less than with 4 KiB pages (where the kernel has them only on
 * request). Only speed depends on it. Such an array allocated with the engine is listed in its
 * fresh arrays, whose pages engine_init has the kernel give before the first parallel step
 * (first_touch); one allocated later (the attribute terms) is written first by a step of its
 * own. Released with free(). */
static void *large_array(engine *e, size_t bytes)
{
    if (bytes < 4 * HUGE_PAGE)
        return xmalloc(bytes);
    size_t rounded = (bytes + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
    void *array = aligned_alloc(HUGE_PAGE, rounded);
    if (!array)
        return xmalloc(bytes);
#ifdef MADV_HUGEPAGE
    madvise(array, rounded, MADV_HUGEPAGE);
#endif
    if (e->fresh_count < FRESH_ARRAYS) { /* (one more would only be touched later) */
        e->fresh[e->fresh_count].array = array;
        e->fresh[e->fresh_count].pages = rounded / HUGE_PAGE;
        e->fresh_count++;
    }
    return array;
}

/* Page `page` of the fresh large arrays (counted through them in order) written, a byte per 4 KiB,
 * so that the kernel gives it now (a huge page, or its small pages where it has none). The
 * first parallel step would otherwise take the pages' faults side by side, and they wait on each
 * other: on the dragon with two threads, the first rings and quadrics took 0.10 s that way, 0.06 s
 * after this step (which costs about 0.01 s). With one thread there is nothing to gain, and
 * engine_init does not run it. */
static void first_touch(engine *e, uint32_t page)
{
    size_t a = 0, first = page;
    while (first >= e->fresh[a].pages)
        first -= e->fresh[a++].pages;
    char *bytes = (char *)e->fresh[a].array + first * HUGE_PAGE;
    for (size_t offset = 0; offset < HUGE_PAGE; offset += 4096)
        bytes[offset] = 0;
}

/* The slot of neighbour w in the ring, or r->size. */
static uint32_t ring_find(const ring *r, uint32_t w)
{
    uint32_t i = 0;
    while (i < r->size && r->entry[i].vertex != w)
        i++;
    return i;
}

/* How many triangles hold the edge to w (0: w is not a neighbour). */
static uint32_t ring_count(const ring *r, uint32_t w)
{
    uint32_t i = ring_find(r, w);
    return i < r->size ? r->entry[i].count : 0;
}

/* A ring's vertices summarised in 64 bits, one bit set per vertex (by a hash of it): a vertex
 * whose bit is clear is not in the ring. The link condition asks for each neighbour of v0
 * whether v1's ring holds it, and most are not there: the summary answers them without a scan. */
static uint32_t summary_bit(uint32_t w) { return (w * 0x9e3779b1u) >> 26; }

/* Whether w is in the ring (summary: the bits of its vertices, as target_rules_kept sums them). */
static int ring_holds(const ring *r, uint64_t summary, uint32_t w)
{
    return (summary >> summary_bit(w) & 1) && ring_find(r, w) < r->size;
}

static void scratch_free(scratch *s)
{
    for (int k = 0; k < SLOTS; k++) {
        free(s->fan_triangle[k]);
        free(s->rings[k]);
    }
    free(s->ids);
    free(s->mapped);
    free(s->ids_before);
    free(s->targets);
    free(s->sides);
    free(s->moved);
    free(s->half_edges);
}

static const float *position(const engine *e, uint32_t v) { return &e->m->positions[3 * (size_t)v]; }

static uint32_t *corners(const engine *e, uint32_t t) { return &e->m->triangles[3 * (size_t)t]; }

/* The corner of triangle t at v (0..2), or 3. */
static int corner_at(const engine *e, uint32_t t, uint32_t v)
{
    const uint32_t *c = corners(e, t);
    return c[0] == v ? 0 : c[1] == v ? 1 : c[2] == v ? 2 : 3;
}

static uint32_t id_at(const engine *e, uint32_t t, uint32_t v)
{
    return e->m->corner_ids[3 * (size_t)t + corner_at(e, t, v)];
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void difference(const float *a, const float *b, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = (double)a[k] - (double)b[k];
}

/* Triangle normal (not normalised) with corner positions p[3]. */
static void normal_of(const float *p[3], double n[3])
{
    double e1[3], e2[3];
    difference(p[1], p[0], e1);
    difference(p[2], p[0], e2);
    cross(e1, e2, n);
}

/* A position as doubles. */
static void widen(const float *p, double out[3])
{
    out[0] = p[0];
    out[1] = p[1];
    out[2] = p[2];
}

/* The normal (not normalised) of the triangle with corners p0, p1, p2 as doubles: normal_of's
 * value. */
static void normal_from(const double p0[3], const double p1[3], const double p2[3], double n[3])
{
    double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    cross(e1, e2, n);
}

/* q(p) */
static inline __attribute__((always_inline)) double quadric_error(const double *q, const float *point)
{
    double x = point[0], y = point[1], z = point[2];
    return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + q[3] * y * y + 2 * q[4] * y * z +
           q[5] * z * z + 2 * (q[6] * x + q[7] * y + q[8] * z) + q[9];
}

/* ---- adjacency and rings ---- */

/* The live triangles at each vertex, in triangle order (adjacency[adjacency_start[v] ..]): a
 * counting sort over the list of live triangles, which it keeps (the triangles that died in the
 * last pass dropped from it, in place: a pass sweeps the triangles that remain, not all). On the
 * way, the corners of every triangle a collapse of the last pass touched are marked stale: a
 * vertex's score depends on its triangles, its neighbours' triangles, quadrics and importance,
 * so the touched vertices and their neighbours are scored again and the rest keep their scores
 * (the scoring step clears the marks: settle_vertex). The list is split into parts, one per
 * thread (at most ADJACENCY_PARTS): each part drops its dead triangles and counts its corners
 * per vertex (count_corners), the parts' places in the list are closed up, each range of
 * vertices gets its slots, part 0's corners first, then part 1's and so on (sum_corners,
 * place_corners), and each part fills its own slots (fill_corners), so each vertex's triangles
 * come in list order on any number of threads. The filling also leaves each vertex's half-edges
 * in its ring records, from which the ring step builds its ring (build_ring): the triangles are
 * read here in list order, not again at random for each of their corners. */
static void run_on_pool(engine *e, vertex_step step, uint32_t items, uint32_t block);

static void build_adjacency(engine *e)
{
    uint32_t parts = e->threads < ADJACENCY_PARTS ? e->threads : ADJACENCY_PARTS;
    e->parts = parts;
    for (uint32_t p = 0; p <= parts; p++)
        e->part_first[p] = (uint32_t)((uint64_t)e->live_count * p / parts);
    e->part_counts[0] = e->adjacency_start;
    for (uint32_t p = 1; p < parts; p++) /* (the keys are free until the pass ranks) */
        e->part_counts[p] = (uint32_t *)(p <= 2 ? e->keys : e->spare_keys) +
                            (p % 2 ? 0 : (size_t)e->n + 1);
    run_on_pool(e, STEP_COUNT_CORNERS, parts, 1);
    uint32_t live = 0; /* each part's live triangles moved down behind the last part's */
    for (uint32_t p = 0; p < parts; p++) {
        if (live != e->part_first[p])
            memmove(&e->live[live], &e->live[e->part_first[p]],
                    sizeof(uint32_t) * e->part_live[p]);
        e->part_first[p] = live;
        live += e->part_live[p];
    }
    e->part_first[parts] = e->live_count = live;
    e->live_all = 0;
    e->corner_offset[0] = 0;
    if (e->threads > 1) {
        run_on_pool(e, STEP_SUM_CORNERS, e->threads, 1);
        for (uint32_t r = 0; r < e->threads; r++)
            e->corner_offset[r + 1] = e->corner_offset[r] + e->range_corners[r];
    }
    e->adjacency_start[e->n] = 3 * live;
    run_on_pool(e, STEP_PLACE_CORNERS, e->threads, 1);
    run_on_pool(e, STEP_FILL_CORNERS, parts, 1);
}

/* The vertices of range `range` of as many as the pool has threads: [*first, *end). */
static void vertex_range(const engine *e, uint32_t range, uint32_t *first, uint32_t *end)
{
    uint64_t ranges = e->threads;
    *first = (uint32_t)((uint64_t)e->n * range / ranges);
    *end = (uint32_t)((uint64_t)e->n * (range + 1) / ranges);
}

/* The per-vertex records of one range of vertices as the passes start from them: each vertex
 * stale, no donor, no candidate, nothing marked, no ring yet; its lock and its importance the
 * caller's. Written on the pool, so that the threads take the fresh pages' faults side by
 * side. */
static void start_vertices(engine *e, uint32_t range)
{
    const collapse_mesh *m = e->m;
    uint32_t first, end;
    vertex_range(e, range, &first, &end);
    for (uint32_t v = first; v < end; v++) {
        e->donor[v] = COLLAPSE_NONE;
        e->best_target[v] = COLLAPSE_NONE;
        e->flags[v] = FLAG_STALE | (m->locked && m->locked[v] ? FLAG_LOCKED : 0);
        e->ring_size[v] = 0;
        e->marks[v] = (vertex_marks){0, 0};
        e->importance[v] = m->importance ? m->importance[v] : 0;
    }
}

/* build_adjacency's count for one part of the live list: its live triangles moved to the
 * front of its place in the list (part_live[part] of them), their corners counted per vertex
 * (part_counts[part]), and the corners of touched triangles marked stale (by any part: each
 * writes the same bit only). */
static void count_corners(engine *e, uint32_t part)
{
    const uint32_t *triangles = e->m->triangles;
    uint32_t *live = e->live, *count = e->part_counts[part];
    uint32_t first = e->part_first[part], end = e->part_first[part + 1], kept = first;
    vertex_flags *flags = e->flags;
    int live_all = e->live_all;
    memset(count, 0, sizeof(uint32_t) * e->n);
    for (uint32_t i = first; i < end; i++) {
        uint32_t t = live_all ? i : live[i];
        const uint32_t *c = &triangles[3 * (size_t)t];
        if (c[0] == COLLAPSE_NONE)
            continue;
        live[kept++] = t;
        vertex_flags f[3];
        for (int k = 0; k < 3; k++)
            f[k] = __atomic_load_n(&flags[c[k]], __ATOMIC_RELAXED); /* (parts mark side by side) */
        int touched = (f[0] | f[1] | f[2]) & FLAG_TOUCHED;
        for (int k = 0; k < 3; k++) {
            count[c[k]]++;
            if (touched && !(f[k] & FLAG_STALE))
                __atomic_store_n(&flags[c[k]], (vertex_flags)(f[k] | FLAG_STALE),
                                 __ATOMIC_RELAXED);
        }
    }
    e->part_live[part] = kept - first;
}

/* build_adjacency's corners of one range of vertices, every part's counted, into
 * range_corners[range]. */
static void sum_corners(engine *e, uint32_t range)
{
    uint32_t first, end, sum = 0;
    vertex_range(e, range, &first, &end);
    for (uint32_t p = 0; p < e->parts; p++)
        for (uint32_t v = first; v < end; v++)
            sum += e->part_counts[p][v];
    e->range_corners[range] = sum;
}

/* build_adjacency's slots of one range of vertices (the range's first at corner_offset[range]):
 * a vertex's slots are part 0's corners at it, then part 1's and so on. adjacency_start[v] (part
 * 0's count) is made the end of part 0's slots, which fill_corners fills from the end; another
 * part's count is made the first of its slots, which it fills from the first. */
static void place_corners(engine *e, uint32_t range)
{
    uint32_t first, end, slot = e->corner_offset[range];
    vertex_range(e, range, &first, &end);
    for (uint32_t v = first; v < end; v++) {
        e->adjacency_start[v] = slot += e->adjacency_start[v];
        for (uint32_t p = 1; p < e->parts; p++) {
            uint32_t count = e->part_counts[p][v];
            e->part_counts[p][v] = slot;
            slot += count;
        }
    }
}

/* build_adjacency's fill for one part of the live list (its place in the list moved, its slots
 * placed): part 0 from the last of its triangles to the first, into the last free slot of each
 * corner, which leaves adjacency_start[v] the first of v's slots; another part from the first,
 * into the first free slot. A corner's half-edge goes into the first bytes of ring record
 * slot + v: v's ring records (pass_ring_entries) start at adjacency_start[v] + v, so v's i-th
 * triangle leaves its half-edge in v's i-th record, and with attributes its corner id at v
 * after it (build_ring). */
static void fill_corners(engine *e, uint32_t part)
{
    const uint32_t *live = e->live, *triangles = e->m->triangles, *ids = e->m->corner_ids;
    uint32_t first = e->part_first[part], end = e->part_first[part + 1], *adjacency = e->adjacency;
    uint32_t *next = e->part_counts[part]; /* part 0: adjacency_start, the ends of its slots */
    ring_entry *rings = e->rings;
    for (uint32_t i = first; i < end; i++) {
        uint32_t t = part == 0 ? live[first + end - 1 - i] : live[i];
        const uint32_t *c = &triangles[3 * (size_t)t];
        for (int k = 0; k < 3; k++) {
            uint32_t slot = part == 0 ? --next[c[k]] : next[c[k]]++;
            adjacency[slot] = t;
            collapse_half_edge h = {c[(k + 1) % 3], c[(k + 2) % 3]};
            memcpy(&rings[(size_t)slot + c[k]], &h, sizeof h);
            if (ids)
                memcpy((char *)&rings[(size_t)slot + c[k]] + sizeof h, &ids[3 * (size_t)t + k],
                       sizeof(uint32_t));
        }
    }
}

/* v's triangles in this pass's adjacency: all live and current while v is untouched. */
static fan pass_fan(const engine *e, uint32_t v)
{
    fan f = {&e->adjacency[e->adjacency_start[v]],
             e->adjacency_start[v + 1] - e->adjacency_start[v]};
    return f;
}

static void reserve(void **buffer, size_t *capacity, size_t count, size_t size)
{
    if (*capacity >= count)
        return;
    *capacity = 2 * count + 16;
    *buffer = xrealloc(*buffer, size * *capacity);
}

/* The vertex that went into v in this pass, or COLLAPSE_NONE: only the kept end of a collapse
 * taken receives, so the flags (read already where this is asked, and smaller) answer for the
 * rest without a read of donor[]. */
static uint32_t donor_of(const engine *e, uint32_t v)
{
    return (e->flags[v] & (FLAG_TAKEN | FLAG_REMOVED)) == FLAG_TAKEN ? e->donor[v] : COLLAPSE_NONE;
}

/* v's live triangles now, into slot `slot` of the scratch: those of its pass-start adjacency
 * and its donor's that still hold it (a vertex receives at most once in a pass). */
static fan current_fan(const engine *e, uint32_t v, scratch *s, int slot)
{
    uint32_t sources[2] = {v, donor_of(e, v)}, count = 0;
    for (int k = 0; k < 2; k++) {
        if (sources[k] == COLLAPSE_NONE)
            continue;
        fan from = pass_fan(e, sources[k]);
        reserve((void **)&s->fan_triangle[slot], &s->fan_capacity[slot], count + from.count,
                sizeof(uint32_t));
        for (uint32_t i = 0; i < from.count; i++) {
            uint32_t t = from.triangle[i];
            if (corners(e, t)[0] != COLLAPSE_NONE && corner_at(e, t, v) < 3)
                s->fan_triangle[slot][count++] = t;
        }
    }
    fan f = {s->fan_triangle[slot], count};
    return f;
}

/* Where a ring being written holds its vertices: per summary bit (summary_bit) that is set,
 * the slot of the first vertex added with it. A neighbour whose bit is clear is new (half of
 * them come new), and one whose bit is set is most often at that slot: few are searched for. */
typedef struct ring_index {
    uint64_t summary;
    uint32_t slot[64]; /* valid where the summary's bit is set */
} ring_index;

/* Adds neighbour w to the ring being written (size so far *size, room for `capacity`, `index`
 * kept up to date); its slot. A ring that would outgrow its room is marked complex (an edge
 * counted 255 times): only a vertex of more than one fan has more neighbours than triangles
 * plus one. */
static inline __attribute__((always_inline)) uint32_t
ring_add(ring_entry *r, uint32_t *size, uint32_t capacity, ring_index *index, uint32_t w)
{
    uint32_t b = summary_bit(w), j = *size;
    if (index->summary >> b & 1) {
        j = index->slot[b];
        if (r[j].vertex != w) /* another vertex with its bit: search */
            for (j = 0; j < *size && r[j].vertex != w;)
                j++;
    }
    if (j < *size) {
        if (r[j].count < 255)
            r[j].count++;
        return j;
    }
    if (*size == capacity) {
        r[0].count = 255;
        return 0;
    }
    r[j] = (ring_entry){w, COLLAPSE_NONE, COLLAPSE_NONE, 1};
    (*size)++;
    if (!(index->summary >> b & 1)) {
        index->summary |= (uint64_t)1 << b;
        index->slot[b] = j;
    }
    return j;
}

/* Adds a triangle of the vertex whose ring is being written (its corners after and before the
 * vertex: h) to the ring (as ring_add). */
static inline __attribute__((always_inline)) void
ring_add_triangle(ring_entry *r, uint32_t *size, uint32_t capacity, ring_index *index,
                  collapse_half_edge h)
{
    r[ring_add(r, size, capacity, index, h.next)].left = h.previous;
    r[ring_add(r, size, capacity, index, h.previous)].right = h.next;
}

/* Writes v's one-ring from the triangles of fan f (room for `capacity` neighbours); returns its
 * size. */
static uint32_t fill_ring(const engine *e, uint32_t v, fan f, ring_entry *r, uint32_t capacity)
{
    uint32_t size = 0;
    ring_index index;
    index.summary = 0;
    for (uint32_t i = 0; i < f.count; i++) {
        uint32_t t = f.triangle[i];
        const uint32_t *c = corners(e, t);
        int k = corner_at(e, t, v);
        collapse_half_edge h = {c[(k + 1) % 3], c[(k + 2) % 3]};
        ring_add_triangle(r, &size, capacity, &index, h);
    }
    return size;
}

static uint32_t corner_field(const collapse_half_edge *corner, int previous)
{
    return previous ? corner->previous : corner->next;
}

/* The corner of corners[0 .. count) whose field is w, or count, through an index of them by that
 * field (a ring_index: per summary bit, the first corner whose value has it). The lookup reads
 * the corner its value's bit names, and searches them all only where another value has the bit. */
static uint32_t corner_lookup(const ring_index *index, const collapse_half_edge *corners,
                              uint32_t count, int previous, uint32_t w)
{
    uint32_t b = summary_bit(w);
    if (!(index->summary >> b & 1))
        return count;
    uint32_t j = index->slot[b];
    if (corner_field(&corners[j], previous) == w)
        return j;
    for (j = 0; j < count && corner_field(&corners[j], previous) != w;)
        j++;
    return j;
}

/* Indexes corners[0 .. count) by one field; 0 where two share a value. */
static int index_corners(ring_index *index, const collapse_half_edge *corners, uint32_t count,
                         int previous)
{
    index->summary = 0;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t w = corner_field(&corners[i], previous), b = summary_bit(w);
        if (index->summary >> b & 1) {
            if (corner_lookup(index, corners, i, previous, w) < i)
                return 0;
            continue;
        }
        index->summary |= (uint64_t)1 << b;
        index->slot[b] = i;
    }
    return 1;
}

int collapse_one_fan(const collapse_half_edge *corners, uint32_t count)
{
    ring_index by_next, by_previous;
    if (!index_corners(&by_next, corners, count, 0) ||
        !index_corners(&by_previous, corners, count, 1))
        return 0; /* a directed edge from the vertex twice */
    uint32_t open_ends = 0, start = 0;
    for (uint32_t i = 0; i < count; i++)
        if (corner_lookup(&by_previous, corners, count, 1, corners[i].next) == count) {
            open_ends++; /* no triangle before it around the vertex */
            start = i;
        }
    if (open_ends > 1)
        return 0;
    uint32_t at = start, steps = 1;
    for (; steps < count; steps++) {
        uint32_t following = corner_lookup(&by_next, corners, count, 0, corners[at].previous);
        if (following == count || following == start)
            break;
        at = following;
    }
    return steps == count;
}

/* The same from v's half-edges, one in the first bytes of each of r[0 .. count) (its triangles'
 * corners after and before v, in fan order): they are copied out first, and where one_fan is
 * not NULL, it gets whether they are one fan (collapse_one_fan). */
static uint32_t fill_ring_from_half_edges(uint32_t count, ring_entry *r, uint32_t capacity,
                                          scratch *s, int *one_fan)
{
    collapse_half_edge local[HALF_EDGES_AT_HAND], *copy = local;
    if (count == 0)
        return 0;
    if (count > HALF_EDGES_AT_HAND) {
        reserve((void **)&s->half_edges, &s->half_edges_capacity, count,
                sizeof(collapse_half_edge));
        copy = s->half_edges;
    }
    for (uint32_t i = 0; i < count; i++)
        memcpy(&copy[i], &r[i], sizeof(collapse_half_edge));
    if (one_fan)
        *one_fan = collapse_one_fan(copy, count);
    uint32_t size = 0;
    ring_index index;
    index.summary = 0;
    for (uint32_t i = 0; i < count; i++)
        ring_add_triangle(r, &size, capacity, &index, copy[i]);
    return size;
}

/* v's records in the pass's rings. */
static ring_entry *pass_ring_entries(const engine *e, uint32_t v)
{
    return &e->rings[(size_t)e->adjacency_start[v] + v];
}

/* The one corner id that the first `count` ring records hold after their half-edges
 * (fill_corners), or COLLAPSE_NONE where they hold several or none. */
static uint32_t records_one_id(const ring_entry *r, uint32_t count)
{
    uint32_t first, id;
    if (count == 0)
        return COLLAPSE_NONE;
    memcpy(&first, (const char *)&r[0] + sizeof(collapse_half_edge), sizeof first);
    for (uint32_t i = 1; i < count; i++) {
        memcpy(&id, (const char *)&r[i] + sizeof(collapse_half_edge), sizeof id);
        if (id != first)
            return COLLAPSE_NONE;
    }
    return first;
}

/* Builds v's one-ring from its pass-start triangles into the pass's ring records, from the
 * half-edges the adjacency left there (fill_corners). From the triangles, read again at random,
 * the rings of the dragon's run took 0.16 s on one thread; from the half-edges 0.09 s, for 0.04 s
 * more in the adjacency, which writes them. With check_fan, a vertex with triangles that are not
 * one fan is counted in the scratch (the caller's fans unchecked). */
static void build_ring(engine *e, uint32_t v, scratch *s, int check_fan)
{
    uint32_t degree = e->adjacency_start[v + 1] - e->adjacency_start[v];
    ring_entry *r = pass_ring_entries(e, v);
    if (e->wedge_id) { /* (the records' corner ids, before the ring overwrites them) */
        e->wedge_id[v] = records_one_id(r, degree);
        e->live_degree[v] = degree;
    }
    int one_fan = 1;
    uint32_t size = e->ring_size[v] =
        fill_ring_from_half_edges(degree, r, degree + 1, s, check_fan ? &one_fan : NULL);
    s->not_one_fan += !one_fan;
    if (e->open_at) {
        int open = 0;
        for (uint32_t i = 0; i < size; i++)
            open |= r[i].count == 1;
        e->open_at[v] = (uint8_t)open;
    }
}

/* v's one-ring now, into slot `slot` of the scratch (its fan too). */
static ring current_ring(const engine *e, uint32_t v, scratch *s, int slot, fan *f)
{
    *f = current_fan(e, v, s, slot);
    size_t capacity = 2 * (size_t)f->count + 1;
    if (s->ring_capacity[slot] < capacity) {
        s->ring_capacity[slot] = 2 * capacity;
        s->rings[slot] = xrealloc(s->rings[slot], sizeof(ring_entry) * s->ring_capacity[slot]);
    }
    ring r = {s->rings[slot], fill_ring(e, v, *f, s->rings[slot], (uint32_t)capacity)};
    return r;
}

/* The one-ring of v in this pass (built by build_ring). */
static ring ring_of(const engine *e, uint32_t v)
{
    ring r = {pass_ring_entries(e, v), e->ring_size[v]};
    return r;
}

/* Whether the ring can be one fan of manifold edges: every edge in at most two triangles and at
 * most two open edges (two closed fans on one vertex pass this, but neither the weld nor the
 * OpenMesh rebuild gives one, and the link condition makes none). Also gives whether it has an
 * open edge. */
static int ring_simple(const ring *r, int *boundary)
{
    int open = 0;
    for (uint32_t i = 0; i < r->size; i++) {
        if (r->entry[i].count > 2)
            return 0;
        open += r->entry[i].count == 1;
    }
    *boundary = open > 0;
    return open <= 2;
}

/* A fan of one vertex: the triangles at v around it, for the seam rule. Counts how often the
 * corner id at v changes between triangles that follow each other around v (cyclically for an
 * inner vertex). v's triangles form one fan (a free vertex). */
static unsigned seam_changes(const engine *e, fan f, uint32_t v, int inner)
{
    /* Start: for a boundary vertex the triangle whose first edge from v (to its next corner) no
     * other triangle closes; for an inner one, any. */
    uint32_t start = f.triangle[0];
    if (!inner)
        for (uint32_t i = 0; i < f.count; i++) {
            uint32_t t = f.triangle[i];
            const uint32_t *c = corners(e, t);
            uint32_t next = c[(corner_at(e, t, v) + 1) % 3];
            int closed = 0;
            for (uint32_t j = 0; j < f.count && !closed; j++) {
                uint32_t other = f.triangle[j];
                const uint32_t *d = corners(e, other);
                closed = other != t && d[(corner_at(e, other, v) + 2) % 3] == next;
            }
            if (!closed) {
                start = t;
                break;
            }
        }
    unsigned changes = 0;
    uint32_t t = start, first_id = id_at(e, start, v), previous = first_id;
    for (uint32_t step = 1; step < f.count; step++) {
        const uint32_t *c = corners(e, t);
        uint32_t far = c[(corner_at(e, t, v) + 2) % 3], following = COLLAPSE_NONE;
        for (uint32_t j = 0; j < f.count; j++) {
            uint32_t other = f.triangle[j];
            const uint32_t *d = corners(e, other);
            if (d[(corner_at(e, other, v) + 1) % 3] == far) {
                following = other;
                break;
            }
        }
        if (following == COLLAPSE_NONE)
            break;
        uint32_t id = id_at(e, following, v);
        changes += id != previous;
        previous = id;
        t = following;
    }
    if (inner && previous != first_id)
        changes++;
    return changes;
}

/* Room for `count` ids in the scratch's ids and their images. */
static void reserve_ids(scratch *s, size_t count)
{
    if (s->ids_capacity < count) {
        s->ids_capacity = 2 * count;
        s->ids = xrealloc(s->ids, sizeof(uint32_t) * s->ids_capacity);
        s->mapped = xrealloc(s->mapped, sizeof(uint32_t) * s->ids_capacity);
    }
}

/* The distinct corner ids at v among the triangles of its fan (in fan order). */
static size_t ids_of(const engine *e, fan f, uint32_t v, scratch *s)
{
    size_t count = 0;
    reserve_ids(s, f.count);
    for (uint32_t i = 0; i < f.count; i++) {
        uint32_t id = id_at(e, f.triangle[i], v);
        size_t k = 0;
        while (k < count && s->ids[k] != id)
            k++;
        if (k == count)
            s->ids[count++] = id;
    }
    return count;
}

/* ids_of(f, v), where v's one id `wedge` (known_wedge) saves reading its triangles if known. */
static size_t ids_at(const engine *e, fan f, uint32_t v, uint32_t wedge, scratch *s)
{
    if (wedge == COLLAPSE_NONE)
        return ids_of(e, f, v, s);
    reserve_ids(s, 1);
    s->ids[0] = wedge;
    return 1;
}

static edge_sides sides_of(const engine *e, fan f0, uint32_t v0, uint32_t v1)
{
    edge_sides sides = {COLLAPSE_NONE, COLLAPSE_NONE, COLLAPSE_NONE, COLLAPSE_NONE};
    for (uint32_t i = 0; i < f0.count; i++) {
        uint32_t t = f0.triangle[i];
        const uint32_t *c = corners(e, t);
        int k = corner_at(e, t, v0);
        if (c[(k + 1) % 3] == v1) {
            sides.fl = t;
            sides.vl = c[(k + 2) % 3];
        } else if (c[(k + 2) % 3] == v1) {
            sides.fr = t;
            sides.vr = c[(k + 1) % 3];
        }
    }
    return sides;
}

/* sides_of() for every edge of v0 at once: sides[i] for the edge to r0's vertex i (r0 v0's ring,
 * built from the fan f0), in one sweep of the fan; as sides_of, the last triangle of the fan on
 * each side counts. */
static void ring_sides(const engine *e, fan f0, uint32_t v0, const ring *r0, edge_sides *sides)
{
    for (uint32_t i = 0; i < r0->size; i++)
        sides[i] = (edge_sides){COLLAPSE_NONE, COLLAPSE_NONE, COLLAPSE_NONE, COLLAPSE_NONE};
    for (uint32_t i = 0; i < f0.count; i++) {
        uint32_t t = f0.triangle[i];
        const uint32_t *c = corners(e, t);
        int k = corner_at(e, t, v0);
        uint32_t next = c[(k + 1) % 3], previous = c[(k + 2) % 3];
        uint32_t left = ring_find(r0, next), right = ring_find(r0, previous);
        if (left < r0->size) {
            sides[left].fl = t;
            sides[left].vl = previous;
        }
        if (right < r0->size && previous != next) {
            sides[right].fr = t;
            sides[right].vr = next;
        }
    }
}

static mapping mapping_of(const engine *e, uint32_t v0, uint32_t v1, const edge_sides *sides)
{
    mapping m;
    m.left_from = m.right_from = COLLAPSE_NONE;
    uint32_t side = sides->fl != COLLAPSE_NONE ? sides->fl : sides->fr;
    m.nearest_to = id_at(e, side, v1);
    m.left_to = m.right_to = m.nearest_to;
    if (sides->fl != COLLAPSE_NONE) {
        m.left_from = id_at(e, sides->fl, v0);
        m.left_to = id_at(e, sides->fl, v1);
    }
    if (sides->fr != COLLAPSE_NONE) {
        m.right_from = id_at(e, sides->fr, v0);
        m.right_to = id_at(e, sides->fr, v1);
    }
    return m;
}

/* mapping_of where v1's triangles have one id at v1, `wedge`: every id of v0 goes into it. */
static mapping mapping_into(uint32_t wedge)
{
    mapping m = {COLLAPSE_NONE, wedge, COLLAPSE_NONE, wedge, wedge};
    return m;
}

static uint32_t mapped_id(const mapping *m, uint32_t id)
{
    return id == m->left_from ? m->left_to : id == m->right_from ? m->right_to : m->nearest_to;
}

/* ---- quadrics ---- */

static void quadric_add_plane(double *q, const double n[3], double d, double weight)
{
    q[0] += weight * n[0] * n[0];
    q[1] += weight * n[0] * n[1];
    q[2] += weight * n[0] * n[2];
    q[3] += weight * n[1] * n[1];
    q[4] += weight * n[1] * n[2];
    q[5] += weight * n[2] * n[2];
    q[6] += weight * n[0] * d;
    q[7] += weight * n[1] * d;
    q[8] += weight * n[2] * d;
    q[9] += weight * d * d;
}

/* Attribute quadrics (decimate_attributes.hh, AttributeQuadrics): per id, the upper triangle of
 * sum w g g' (6), per channel sum w g (3 each), sum w (1), sum over channels of w d g (3), per
 * channel sum w d (1 each), sum of w d² (1); positions relative to the mesh's centre. */
static int attribute_stride(int channels) { return 6 + 3 * channels + 1 + 3 + channels + 1; }

static double attribute_value(const engine *e, uint32_t id, int channel)
{
    double v = e->m->attributes[(size_t)e->channels * id + channel];
    return v * (channel < e->m->uv_floats ? e->uv_scale : e->normal_scale);
}

/* The terms one face with corners at p[k] and ids id[k], weighted w, adds to the attribute
 * quadric of each of its corners' ids, into face[]; 0 for a degenerate face. */
static int attribute_face_terms(const engine *e, const float *p[3], const uint32_t id[3],
                                double w, double *face)
{
    double e1[3], e2[3], n[3];
    difference(p[1], p[0], e1);
    difference(p[2], p[0], e2);
    cross(e1, e2, n);
    double n2 = dot(n, n);
    if (!(n2 > 0) || !(w > 0))
        return 0;
    double dual1[3], dual2[3], p0[3];
    cross(e2, n, dual1);
    cross(n, e1, dual2);
    for (int k = 0; k < 3; k++) {
        dual1[k] /= n2;
        dual2[k] /= n2;
        p0[k] = p[0][k] - e->centre[k];
    }
    int channels = e->channels;
    memset(face, 0, sizeof(double) * attribute_stride(channels));
    double *matrix = face, *gradient = face + 6, *weight = gradient + 3 * channels,
           *linear = weight + 1, *offset = linear + 3, *constant = offset + channels;
    *weight = w;
    for (int ch = 0; ch < channels; ch++) {
        double s0 = attribute_value(e, id[0], ch), s1 = attribute_value(e, id[1], ch),
               s2 = attribute_value(e, id[2], ch), g[3];
        for (int k = 0; k < 3; k++)
            g[k] = dual1[k] * (s1 - s0) + dual2[k] * (s2 - s0);
        double d = s0 - dot(g, p0);
        for (int i = 0, k = 0; i < 3; i++)
            for (int j = i; j < 3; j++)
                matrix[k++] += w * g[i] * g[j];
        for (int k = 0; k < 3; k++) {
            gradient[3 * ch + k] += w * g[k];
            linear[k] += w * d * g[k];
        }
        offset[ch] += w * d;
        *constant += w * d * d;
    }
    return 1;
}

/* E_id at `point` with the attribute values of id `at`. */
static double attribute_error(const engine *e, uint32_t id, const float *point, uint32_t at)
{
    int channels = e->channels;
    const double *q = &e->attribute_terms[(size_t)id * attribute_stride(channels)];
    const double *m = q, *gradient = q + 6, *weight = gradient + 3 * channels,
                 *linear = weight + 1, *offset = linear + 3, *constant = offset + channels;
    double p[3];
    for (int k = 0; k < 3; k++)
        p[k] = point[k] - e->centre[k];
    double error = m[0] * p[0] * p[0] + m[3] * p[1] * p[1] + m[5] * p[2] * p[2] +
                   2 * (m[1] * p[0] * p[1] + m[2] * p[0] * p[2] + m[4] * p[1] * p[2]) +
                   2 * dot(linear, p) + *constant;
    for (int ch = 0; ch < channels; ch++) {
        double s = attribute_value(e, at, ch), gp = dot(&gradient[3 * ch], p);
        error += *weight * s * s - 2 * s * gp - 2 * offset[ch] * s;
    }
    return error > 0 ? error : 0.0;
}

/* attribute_error(id, point, id) for an id of the vertex at `point`: kept per id from its first
 * asking until its terms change (a collapse merges into them, attribute_merge), since a vertex
 * does not move and a collapse maps every id of v0 into one of v1. Threads that score side by
 * side may store one id's, the same value. The scoring asks for it for every target of every
 * vertex scored, and evaluated, it reads the target's terms at random: the dragon with normals
 * took 3.02-3.22 s on one thread that way, 2.83-2.95 s kept. */
static double own_attribute_error(const engine *e, uint32_t id, const float *point)
{
    if (!SHORTCUTS)
        return attribute_error(e, id, point, id);
    double known;
    __atomic_load(&e->own_attribute_error[id], &known, __ATOMIC_RELAXED);
    if (known == known) /* (not NaN: attribute_error never gives it) */
        return known;
    double error = attribute_error(e, id, point, id);
    __atomic_store(&e->own_attribute_error[id], &error, __ATOMIC_RELAXED);
    return error;
}

static void attribute_merge(engine *e, uint32_t from, uint32_t into)
{
    if (from == into)
        return;
    int stride = attribute_stride(e->channels);
    const double *f = &e->attribute_terms[(size_t)from * stride];
    double *t = &e->attribute_terms[(size_t)into * stride];
    for (int k = 0; k < stride; k++)
        t[k] += f[k];
    e->own_attribute_error[into] = NAN;
}

/* A triangle's corner positions into p. */
static void triangle_positions(const engine *e, uint32_t t, const float *p[3])
{
    const uint32_t *c = corners(e, t);
    for (int k = 0; k < 3; k++)
        p[k] = position(e, c[k]);
}

/* The mean of a triangle's vertex importance, and its corner positions into p. */
static double triangle_points(const engine *e, uint32_t t, const float *p[3])
{
    const uint32_t *c = corners(e, t);
    triangle_positions(e, t, p);
    double sum = 0;
    for (int k = 0; k < 3; k++)
        sum += e->importance[c[k]];
    return sum / 3.0;
}

/* COMBINED's attribute quadrics, where the mesh has an attribute with a weight. */
static void start_attribute_quadrics(engine *e)
{
    const collapse_mesh *m = e->m;
    e->channels = m->uv_floats + m->normal_floats;
    e->attributes_weighted = m->corner_ids && e->channels > 0 &&
                             ((m->uv_floats && e->o->uv_weight > 0) ||
                              (m->normal_floats && e->o->normal_weight > 0));
    if (!e->attributes_weighted)
        return;
    double low[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, high[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (uint32_t v = 0; v < e->n; v++) {
        if (e->adjacency_start[v] == e->adjacency_start[v + 1])
            continue;
        for (int k = 0; k < 3; k++) {
            low[k] = fmin(low[k], position(e, v)[k]);
            high[k] = fmax(high[k], position(e, v)[k]);
        }
    }
    double extent = fmax(high[0] - low[0], fmax(high[1] - low[1], high[2] - low[2]));
    if (!(extent > 0) || !isfinite(extent)) {
        e->attributes_weighted = 0;
        return;
    }
    e->uv_scale = e->o->uv_weight * extent;
    e->normal_scale = e->o->normal_weight * extent;
    for (int k = 0; k < 3; k++)
        e->centre[k] = 0.5 * (low[k] + high[k]);
    e->attribute_terms = large_array(
        e, sizeof(double) * ((size_t)m->attribute_count * attribute_stride(e->channels) + 1));
    e->own_attribute_error = xmalloc(sizeof(double) * ((size_t)m->attribute_count + 1));
    run_on_pool(e, STEP_CLEAR_ATTRIBUTE_TERMS, e->threads, 1);
}

/* One range of the attribute terms, of as many as the pool has threads, zeroed, and one of the
 * ids' own errors, not known. On the pool, before the quadrics' step, so that the threads take
 * the terms' page faults in a step of their own. The dragon with normals has 80 MiB of terms:
 * faulted in the middle of the quadrics' sums (a calloc'd array), they took that step from
 * 0.21 s on one thread to 0.26 s on two, each thread faulting at random places; with this step,
 * 0.08-0.13 s on two. */
static void clear_attribute_terms(engine *e, uint32_t range)
{
    size_t count = (size_t)e->m->attribute_count * attribute_stride(e->channels) + 1;
    size_t first = count * range / e->threads, end = count * (range + 1) / e->threads;
    memset(&e->attribute_terms[first], 0, sizeof(double) * (end - first));
    size_t ids = (size_t)e->m->attribute_count + 1;
    for (size_t id = ids * range / e->threads; id < ids * (range + 1) / e->threads; id++)
        e->own_attribute_error[id] = NAN;
}

/* Where importance_floor's step writes triangle t's area and its area x importance: the pass's
 * ring records, which the first adjacency writes only after (room for 3 t + n records of 16
 * bytes, 16 bytes per triangle taken). */
static double *face_weights(const engine *e, uint32_t t) { return (double *)&e->rings[t]; }

/* Triangle t's area and its area x importance (the mean of its vertices'), for
 * importance_floor; zeros for a dead one. */
static void weigh_face(engine *e, uint32_t t)
{
    if (corners(e, t)[0] == COLLAPSE_NONE) {
        face_weights(e, t)[0] = face_weights(e, t)[1] = 0;
        return;
    }
    const float *p[3];
    double face_importance = triangle_points(e, t, p), n[3];
    normal_of(p, n);
    double a = 0.5 * sqrt(dot(n, n));
    face_weights(e, t)[0] = a;
    face_weights(e, t)[1] = a * face_importance;
}

/* COMBINED's importance floor: FLOOR_SHARE of the area-weighted mean importance of the faces (a
 * face's the mean of its vertices'), 1 when the mesh has none. The faces are weighed on the pool
 * (weigh_face) and summed here in triangle order, so the floor is the same on any number of
 * threads (weighed here as well, it took the dragon 0.016 s on one thread alone). */
static double importance_floor(engine *e)
{
    run_on_pool(e, STEP_WEIGH_FACES, e->t, SCORE_BLOCK);
    double weighted = 0, area = 0;
    for (uint32_t t = 0; t < e->t; t++) { /* (a dead face adds zeros: the same sums) */
        weighted += face_weights(e, t)[1];
        area += face_weights(e, t)[0];
    }
    double mean = area > 0 ? weighted / area : 0;
    return mean > 0 && isfinite(mean) ? FLOOR_SHARE * mean : 1.0;
}

/* COMBINED: the planes across the open edges of face t at v (n the face's unit normal), each
 * weighted by its length squared x the face's importance, into v's quadric q (v with an open
 * edge: open_at). */
static void add_open_edge_planes(const engine *e, uint32_t t, uint32_t v, const double n[3],
                                 double face_importance, double *q)
{
    ring r = ring_of(e, v);
    const uint32_t *c = corners(e, t);
    for (int k = 0; k < 3; k++) {
        uint32_t a = c[k], b = c[(k + 1) % 3];
        if ((a != v && b != v) || ring_count(&r, a == v ? b : a) != 1)
            continue; /* not an edge at v, or not open */
        double edge[3], across[3];
        difference(position(e, b), position(e, a), edge);
        cross(edge, n, across);
        double length = sqrt(dot(across, across));
        if (!(length > 0))
            continue;
        for (int m = 0; m < 3; m++)
            across[m] /= length;
        const float *pa = position(e, a);
        double da = -(across[0] * pa[0] + across[1] * pa[1] + across[2] * pa[2]);
        quadric_add_plane(q, across, da, BOUNDARY_WEIGHT * dot(edge, edge) * face_importance);
    }
}

/* The plane quadrics of one range of vertices (and, COMBINED with attributes, the attribute
 * quadrics of their corner ids), from their triangles: QUADRIC, each face's plane weighted by its
 * area (OpenMesh's ModQuadricT); COMBINED, weighted by area x (importance + floor), with the
 * plane across each open edge of the face at the vertex (the rings built). One sweep over the
 * live triangles in list order computes each face's terms once, for the range's corners of it
 * (a face across two ranges is computed in both): each vertex's sums are taken in the order of
 * its triangles, as a loop over its own would take them, on any number of threads. */
static void sum_quadrics(engine *e, uint32_t range)
{
    int combined = e->o->method == DECIMATE_COMBINED;
    uint32_t first, end;
    vertex_range(e, range, &first, &end);
    memset(&e->quadric[10 * (size_t)first], 0, sizeof(double) * 10 * (end - first));
    for (uint32_t i = 0; i < e->live_count; i++) {
        uint32_t t = e->live[i];
        const uint32_t *c = corners(e, t);
        int mine[3], any = 0;
        for (int k = 0; k < 3; k++)
            any |= mine[k] = c[k] - first < end - first;
        if (!any)
            continue;
        const float *p[3];
        double face_importance = 1.0, n[3]; /* QUADRIC: the planes unweighted by importance */
        if (combined)
            face_importance = triangle_points(e, t, p) + e->importance_floor;
        else
            triangle_positions(e, t, p);
        normal_of(p, n);
        double twice_area = sqrt(dot(n, n));
        if (!(twice_area > 0))
            continue;
        for (int k = 0; k < 3; k++)
            n[k] /= twice_area;
        double d = -(n[0] * p[0][0] + n[1] * p[0][1] + n[2] * p[0][2]);
        double weight = 0.5 * twice_area * face_importance;
        double plane[10] = {0};
        quadric_add_plane(plane, n, d, weight); /* (0 + each term: as a sum from zero) */
        double face[6 + 3 * MAX_CHANNELS + 1 + 3 + MAX_CHANNELS + 1];
        int attribute_terms = e->attributes_weighted &&
                              attribute_face_terms(e, p, &e->m->corner_ids[3 * (size_t)t], weight,
                                                   face);
        for (int corner = 0; corner < 3; corner++) {
            if (!mine[corner])
                continue;
            uint32_t v = c[corner];
            double *q = &e->quadric[10 * (size_t)v];
            for (int m = 0; m < 10; m++)
                q[m] += plane[m];
            if (combined && e->open_at[v])
                add_open_edge_planes(e, t, v, n, face_importance, q);
            if (attribute_terms) {
                int stride = attribute_stride(e->channels);
                uint32_t id = e->m->corner_ids[3 * (size_t)t + corner];
                double *terms = &e->attribute_terms[(size_t)id * stride];
                for (int m = 0; m < stride; m++)
                    terms[m] += face[m];
            }
        }
    }
    for (uint32_t v = first; v < end; v++)
        e->self_error[v] = quadric_error(&e->quadric[10 * (size_t)v], position(e, v));
}

/* ---- the rules ---- */

/* No triangle of v0 that moves (one without v1) turns by more than the limit or degenerates. */
static int normals_kept(const engine *e, const ring *r0, uint32_t v0, uint32_t v1)
{
    /* normal_of's arithmetic, the points widened once (exact) instead of in every difference */
    double p0[3], p1[3];
    widen(position(e, v0), p0);
    widen(position(e, v1), p1);
    for (uint32_t i = 0; i < r0->size; i++) { /* v0's triangles: (v0, vertex[i], left[i]) */
        uint32_t a = r0->entry[i].vertex, b = r0->entry[i].left;
        if (b == COLLAPSE_NONE || a == v1 || b == v1)
            continue;
        double pa[3], pb[3], nb[3], na[3];
        widen(position(e, a), pa);
        widen(position(e, b), pb);
        normal_from(p0, pa, pb, nb); /* before */
        normal_from(p1, pa, pb, na); /* after */
        /* cos(turn) >= min_cos, without square roots: dot >= min_cos |nb| |na| */
        double lb2 = dot(nb, nb), la2 = dot(na, na), d = dot(nb, na);
        if (!(la2 > 0))
            return 0;
        if (!(lb2 > 0))
            continue; /* already degenerate: any direction is an improvement */
        double bound2 = e->min_cos * e->min_cos * lb2 * la2;
        if (e->min_cos >= 0 ? (d < 0 || d * d < bound2) : (d < 0 && d * d > bound2))
            return 0;
    }
    return 1;
}

/* COMBINED: a boundary v0 goes into one of its two boundary neighbours only where it lies within
 * the tolerance x |u - v1| of the new outline u - v1 (u its other boundary neighbour). */
static int outline_kept(const engine *e, uint32_t v0, uint32_t v1, const ring *r0)
{
    uint32_t open[2], count = 0;
    for (uint32_t i = 0; i < r0->size; i++)
        if (r0->entry[i].count == 1 && count < 2)
            open[count++] = r0->entry[i].vertex;
    if (count != 2 || (open[0] != v1 && open[1] != v1))
        return 0;
    uint32_t u = open[0] == v1 ? open[1] : open[0];
    double chord[3], to_p[3];
    difference(position(e, v1), position(e, u), chord);
    difference(position(e, v0), position(e, u), to_p);
    double length2 = dot(chord, chord);
    double s = length2 > 0 ? fmin(1.0, fmax(0.0, dot(to_p, chord) / length2)) : 0.0;
    double deviation2 = 0;
    for (int k = 0; k < 3; k++) {
        double d = to_p[k] - chord[k] * s;
        deviation2 += d * d;
    }
    return deviation2 <= e->boundary_tolerance * e->boundary_tolerance * length2;
}

/* The one corner id that v's live triangles have at it, where that is known without reading
 * them (with attributes), or COLLAPSE_NONE: v's pass-start one (wedge_id) on the mesh as the
 * pass found it, or with `current` on the mesh as it is, v not removed. A collapse taken does
 * not change it: its other vertices only lose triangles (counted in live_degree) or see v0
 * replaced by v1 in theirs, and where the kept end v1 has one id, every corner of v0 goes into
 * it (mapping_into), its triangles counted in (apply_collapse). */
static uint32_t known_wedge(const engine *e, uint32_t v, int current)
{
    if (!SHORTCUTS || (current && (e->flags[v] & FLAG_REMOVED)))
        return COLLAPSE_NONE;
    return e->wedge_id[v];
}

/* The seam rules of decimate.h ("Attributes"), on the mesh as the pass found it or with
 * `current` as it is. */
static int seams_kept(const engine *e, fan f0, uint32_t v0, uint32_t v1,
                      const edge_sides *sides, int inner, int current, scratch *s)
{
    if (e->o->seams_free)
        return 1;
    size_t wedges = ids_at(e, f0, v0, known_wedge(e, v0, current), s);
    int left = sides->fl != COLLAPSE_NONE, right = sides->fr != COLLAPSE_NONE;
    if (wedges == 1) /* (both sides have v1's one id at v1, where it has one) */
        return !(left && right && known_wedge(e, v1, current) == COLLAPSE_NONE &&
                 id_at(e, sides->fl, v1) != id_at(e, sides->fr, v1));
    if (wedges != 2 || !left || !right || seam_changes(e, f0, v0, inner) != 2)
        return 0;
    return id_at(e, sides->fl, v0) != id_at(e, sides->fr, v0) &&
           id_at(e, sides->fl, v1) != id_at(e, sides->fr, v1);
}

/* With normals: every moved triangle keeps each corner's normal on its front side. */
static int normals_face_out(const engine *e, fan f0, uint32_t v0, uint32_t v1,
                            const mapping *map)
{
    const collapse_mesh *m = e->m;
    if (!m->normal_floats)
        return 1;
    int stride = m->uv_floats + m->normal_floats;
    for (uint32_t i = 0; i < f0.count; i++) {
        uint32_t t = f0.triangle[i];
        if (corner_at(e, t, v1) < 3)
            continue;
        const uint32_t *c = corners(e, t);
        const float *p[3];
        uint32_t id[3];
        for (int k = 0; k < 3; k++) {
            int moved = c[k] == v0;
            p[k] = position(e, moved ? v1 : c[k]);
            id[k] = m->corner_ids[3 * (size_t)t + k];
            if (moved)
                id[k] = mapped_id(map, id[k]);
        }
        double g[3];
        normal_of(p, g);
        for (int k = 0; k < 3; k++) {
            const float *n = &m->attributes[(size_t)stride * id[k] + m->uv_floats];
            if (!(g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0))
                return 0;
        }
    }
    return 1;
}

/* The ring of v (not v0) for collapse_legal: the pass's, which stays exact while v is untouched,
 * or v's ring now in `slot`. */
static ring ring_for(const engine *e, uint32_t v, int current, scratch *s, int slot)
{
    if (!current || !(e->flags[v] & FLAG_TOUCHED))
        return ring_of(e, v);
    fan f;
    return current_ring(e, v, s, slot, &f);
}

/* Whether v has exactly three neighbours, `holding` among them unless COLLAPSE_NONE (the mesh as
 * the pass found it, or with `current` as it is now). The valence-3 rule asks this of vl and vr
 * for every judged collapse; for a touched vertex the neighbours are counted from its live
 * triangles, stopping at a fourth, without gathering its ring. */
static int valence_three(const engine *e, uint32_t v, int current, uint32_t holding)
{
    if (!current || !(e->flags[v] & FLAG_TOUCHED)) {
        if (e->ring_size[v] != 3) /* most are not: their ring is not looked at */
            return 0;
        ring r = ring_of(e, v);
        return holding == COLLAPSE_NONE || ring_count(&r, holding);
    }
    /* Each collapse that touched v took at most one neighbour from it (v0 from a side or from
     * v1, whose other neighbours stay or come in; v0 from the rest of v0's ring, which gets v1
     * instead), so v has at least its pass-start neighbours less its touches: most have more
     * than three, and their triangles are not read. */
    uint8_t touches = e->marks[v].touches;
    if (touches < TOUCHES_KNOWN && e->ring_size[v] > 3u + touches)
        return 0;
    uint32_t seen[3], count = 0, sources[2] = {v, donor_of(e, v)};
    for (int k = 0; k < 2; k++) {
        if (sources[k] == COLLAPSE_NONE)
            continue;
        fan from = pass_fan(e, sources[k]);
        for (uint32_t i = 0; i < from.count; i++) {
            const uint32_t *c = corners(e, from.triangle[i]);
            if (c[0] == COLLAPSE_NONE || corner_at(e, from.triangle[i], v) == 3)
                continue;
            for (int m = 0; m < 3; m++) {
                uint32_t j = 0;
                while (j < count && seen[j] != c[m])
                    j++;
                if (c[m] == v || j < count)
                    continue;
                if (count == 3)
                    return 0;
                seen[count++] = c[m];
            }
        }
    }
    if (count != 3)
        return 0;
    return holding == COLLAPSE_NONE || seen[0] == holding || seen[1] == holding ||
           seen[2] == holding;
}

/* The rules of v0 -> v1 that read v1's ring r1 (and the edge's sides vl and vr, v0's ring r0):
 * neither vertex complex, no dangling edge, no fold of boundaries, the link condition.
 * *rule names the first that forbids it. */
static int target_rules_kept(uint32_t v1, const ring *r0, uint32_t slot, int boundary0,
                             const ring *r1, const char **rule)
{
    uint32_t vl = r0->entry[slot].left, vr = r0->entry[slot].right, held = r0->entry[slot].count;
    /* r1 read once: what ring_simple and ring_count of vl and vr would give, and its summary */
    uint32_t open1 = 0, vl_count = 0, vr_count = 0, too_many = 0;
    uint64_t summary1 = 0;
    for (uint32_t i = 0; i < r1->size; i++) {
        const ring_entry *x = &r1->entry[i];
        too_many |= x->count > 2;
        open1 += x->count == 1;
        vl_count = x->vertex == vl ? x->count : vl_count;
        vr_count = x->vertex == vr ? x->count : vr_count;
        summary1 |= (uint64_t)1 << summary_bit(x->vertex);
    }
    if (too_many || open1 > 2)
        return *rule = "complex vertex", 0;
    int boundary1 = open1 > 0;
    /* A triangle of the edge whose other two edges are open would leave a dangling edge. */
    if (vl != COLLAPSE_NONE && vl_count == 1 && ring_count(r0, vl) == 1)
        return *rule = "dangling edge", 0;
    if (vr != COLLAPSE_NONE && vr_count == 1 && ring_count(r0, vr) == 1)
        return *rule = "dangling edge", 0;
    if (vl == vr)
        return *rule = "one opposite vertex", 0;
    int both_sides = vl != COLLAPSE_NONE && vr != COLLAPSE_NONE;
    if (boundary0 && boundary1 && held == 2)
        return *rule = "interior edge between boundaries", 0;
    if (boundary0 && (!boundary1 || both_sides))
        return *rule = "boundary vertex off the boundary", 0;
    for (uint32_t i = 0; i < r0->size; i++) {
        uint32_t w = r0->entry[i].vertex;
        if (w != v1 && w != vl && w != vr && ring_holds(r1, summary1, w))
            return *rule = "link condition", 0;
    }
    return 1;
}

/* The rule of v0 -> v1 that reads the rings of the edge's sides vl and vr: not both of valence
 * 3 (with `current`, as they are now). */
static int sides_rule_kept(const engine *e, uint32_t vl, uint32_t vr, int current,
                           const char **rule)
{
    if (vl != COLLAPSE_NONE && vr != COLLAPSE_NONE && valence_three(e, vl, current, vr) &&
        valence_three(e, vr, current, COLLAPSE_NONE))
        return *rule = "two joined valence-3 vertices", 0;
    return 1;
}

/* The rules of v0 -> v1 that read only v0's triangles (fan f0, ring r0) and the positions and
 * attributes: the normal limit, the boundary lock, the seams, the normals (on the mesh as the
 * pass found it, or with `current` as it is). */
static int own_rules_kept(const engine *e, uint32_t v0, uint32_t v1, fan f0, const ring *r0,
                          int boundary0, int current, scratch *s, const char **rule)
{
    if (!normals_kept(e, r0, v0, v1))
        return *rule = "normal limit", 0;
    if (e->o->method == DECIMATE_COMBINED && boundary0 && !isinf(e->boundary_tolerance) &&
        !outline_kept(e, v0, v1, r0))
        return *rule = "boundary lock", 0;
    if (e->m->corner_ids) {
        edge_sides sides = sides_of(e, f0, v0, v1);
        if (!seams_kept(e, f0, v0, v1, &sides, !boundary0, current, s))
            return *rule = "seam", 0;
        mapping map = mapping_of(e, v0, v1, &sides);
        if (!normals_face_out(e, f0, v0, v1, &map))
            return *rule = "normal behind its triangle", 0;
    }
    return 1;
}

/* Whether v0 -> v1 is legal; f0 and r0 are v0's fan and ring, v0 free and with more than two
 * neighbours. `current`: judge the mesh as it is now, in a pass where collapses were taken
 * (the other rings are gathered again), not as the pass found it. *rule names the first rule
 * that forbids it. */
static int collapse_legal(const engine *e, uint32_t v0, uint32_t v1, fan f0, const ring *r0,
                          int boundary0, int current, scratch *s, const char **rule)
{
    uint32_t slot = ring_find(r0, v1);
    if (slot == r0->size)
        return *rule = "not an edge", 0;
    if (e->m->locked && e->m->locked[v1]) /* the caller's (flags[v1] may be being rewritten) */
        return *rule = "locked", 0;
    ring r1 = ring_for(e, v1, current, s, SLOT_V1);
    return target_rules_kept(v1, r0, slot, boundary0, &r1, rule) &&
           sides_rule_kept(e, r0->entry[slot].left, r0->entry[slot].right, current, rule) &&
           own_rules_kept(e, v0, v1, f0, r0, boundary0, current, s, rule);
}

/* The cost of v0 -> v1 for QUADRIC and COMBINED. With attribute quadrics: s->ids[0 .. count)
 * are v0's distinct corner ids (ids_of), which every target of v0 shares, and the ids they map
 * to (mapping_of) are v1_wedge for all where v1's triangles have that one id at v1, otherwise
 * the mapping's of the edge's sides (sides_of). */
static inline __attribute__((always_inline)) double
collapse_cost(const engine *e, uint32_t v0, uint32_t v1, const edge_sides *sides, size_t count,
              uint32_t v1_wedge, scratch *s)
{
    const float *p1 = position(e, v1);
    /* (Q0 + Q1)(p1) = Q0(p1) + Q1(p1), the second v1's own error, kept per pass */
    double error = quadric_error(&e->quadric[10 * (size_t)v0], p1) + e->self_error[v1];
    if (e->attributes_weighted) {
        mapping map =
            v1_wedge != COLLAPSE_NONE ? mapping_into(v1_wedge) : mapping_of(e, v0, v1, sides);
        for (size_t k = 0; k < count; k++) {
            s->mapped[k] = mapped_id(&map, s->ids[k]);
            error += attribute_error(e, s->ids[k], p1, s->mapped[k]);
            size_t j = 0;
            while (j < k && s->mapped[j] != s->mapped[k])
                j++;
            if (j == k)
                error += own_attribute_error(e, s->mapped[k], p1);
        }
    }
    CHECK_FINITE(error, "collapse cost");
    return error >= 0.0 ? error : 0.0; /* fmax(error, 0.0), -0 and NaN alike, without a call */
}

static uint32_t distance_of(const engine *e, uint32_t v)
{
    return e->m->distance ? e->m->distance[v] : 0;
}

static int compare_targets(const void *a, const void *b)
{
    const target_key *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    if (x->distance != y->distance)
        return x->distance < y->distance ? -1 : 1;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

/* v's collapse targets (its ring's vertices; f0 and r0 its fan and ring) with their keys, into
 * s->targets; their count. Asked on the mesh as the pass found it (the scoring, and the
 * ranking's check, which runs before the pass takes a collapse), where wedge_id holds. With
 * attribute quadrics, v's ids and the ids they map to are read from the triangles only where v
 * or the target has more than one (wedge_id): the dragon with normals, whose vertices have one
 * each, scored in 0.91-0.92 s on one thread so, against 1.29-1.37 s reading them for all. */
static size_t target_keys(const engine *e, uint32_t v, fan f0, const ring *r0, scratch *s)
{
    if (s->targets_capacity < r0->size) {
        s->targets_capacity = 2 * (size_t)r0->size;
        s->targets = xrealloc(s->targets, sizeof(target_key) * s->targets_capacity);
        s->sides = xrealloc(s->sides, sizeof(edge_sides) * s->targets_capacity);
    }
    int by_importance = e->o->method == DECIMATE_IMPORTANCE;
    int attributes = !by_importance && e->attributes_weighted, sides_known = 0;
    size_t ids = attributes ? ids_at(e, f0, v, known_wedge(e, v, 0), s) : 0;
    for (uint32_t i = 0; i < r0->size; i++) {
        uint32_t u = r0->entry[i].vertex;
        s->targets[i].vertex = u;
        s->targets[i].distance = distance_of(e, u);
        if (by_importance) {
            s->targets[i].key = e->importance[u];
            continue;
        }
        uint32_t u_wedge = attributes ? known_wedge(e, u, 0) : COLLAPSE_NONE;
        if (attributes && u_wedge == COLLAPSE_NONE && !sides_known) {
            ring_sides(e, f0, v, r0, s->sides);
            sides_known = 1;
        }
        s->targets[i].key = collapse_cost(e, v, u, &s->sides[i], ids, u_wedge, s);
    }
    return r0->size;
}

/* A priority as the ranking's float: at most FLT_MAX / 2. */
static float rank_cost(double priority)
{
    double largest = (double)FLT_MAX / 2; /* fmin(priority, largest), without a call */
    return (float)(priority <= largest ? priority : largest);
}

/* v's candidate for collapsing into target t (r0 its ring): ranked by the cost (QUADRIC,
 * COMBINED) or by the importance of v and its ring (IMPORTANCE, the paper's ring sum). */
static void set_best(engine *e, uint32_t v, const ring *r0, const target_key *t)
{
    int by_importance = e->o->method == DECIMATE_IMPORTANCE;
    double priority = t->key;
    if (by_importance) {
        priority = e->importance[v];
        for (uint32_t k = 0; k < r0->size; k++)
            priority += e->importance[r0->entry[k].vertex];
        CHECK_FINITE(priority, "ring importance");
    }
    e->best_target[v] = t->vertex;
    e->best[v] = (candidate){rank_cost(priority), distance_of(e, v),
                             by_importance ? e->importance[t->vertex] : 0.0, t->distance, v};
}

/* Whether v may be removed at all: free, one fan, more than two neighbours (r0 its ring). */
static int removable(const engine *e, uint32_t v, const ring *r0, int *boundary0)
{
    return !(e->flags[v] & (FLAG_LOCKED | FLAG_REMOVED)) && r0->size > 2 &&
           ring_simple(r0, boundary0);
}

/* Sorts v's targets s->targets[0 .. count) (target_keys') by the method's order. */
static void sort_targets(size_t count, scratch *s)
{
    for (size_t i = 1; i < count; i++) { /* an insertion sort: a ring is short */
        target_key key = s->targets[i];
        size_t j = i;
        while (j > 0 && compare_targets(&key, &s->targets[j - 1]) < 0) {
            s->targets[j] = s->targets[j - 1];
            j--;
        }
        s->targets[j] = key;
    }
}

/* The first of v's targets s->targets[0 .. count) by the method's order. */
static size_t cheapest_target(size_t count, const scratch *s)
{
    size_t cheapest = 0;
    for (size_t i = 1; i < count; i++)
        if (compare_targets(&s->targets[i], &s->targets[cheapest]) < 0)
            cheapest = i;
    return cheapest;
}

/* v's best legal collapse on the mesh as the pass found it, into best[v] and best_target[v]
 * (COLLAPSE_NONE and FLAG_NO_LEGAL: none): the targets s->targets[0 .. count) (target_keys')
 * sorted by the method's order and tried in order after the first, which broke a rule (f0, r0
 * and boundary0 v's fan, ring and boundary flag). */
static void set_best_after_cheapest(engine *e, uint32_t v, fan f0, const ring *r0, int boundary0,
                                    size_t count, scratch *s)
{
    const char *rule;
    sort_targets(count, s);
    for (size_t i = 1; i < count; i++) /* targets[0] is the cheapest */
        if (collapse_legal(e, v, s->targets[i].vertex, f0, r0, boundary0, 0, s, &rule)) {
            set_best(e, v, r0, &s->targets[i]);
            return;
        }
    e->best_target[v] = COLLAPSE_NONE;
    e->flags[v] |= FLAG_NO_LEGAL;
}

/* Scores v into best[v] and best_target[v] (COLLAPSE_NONE: none): its best legal collapse, the
 * cheapest target by the method's order if legal (as it is for most vertices), otherwise the
 * targets sorted and tried in order. With the cost methods (QUADRIC, COMBINED) a pass reaches
 * only the first third or so of its ranking, so a vertex whose cheapest collapse costs more than
 * the pass will likely reach (score_rules_up_to) is scored by that collapse alone, unchecked
 * (FLAG_UNCHECKED): the ranking applies the rules to those the pass may reach (check_ranking),
 * as this would have. */
static void score_vertex(engine *e, uint32_t v, scratch *s)
{
    e->best_target[v] = COLLAPSE_NONE;
    e->flags[v] &= (vertex_flags) ~(FLAG_UNCHECKED | FLAG_NO_LEGAL);
    ring r0 = ring_of(e, v);
    fan f0 = pass_fan(e, v);
    int boundary0;
    if (!removable(e, v, &r0, &boundary0))
        return;
    size_t count = target_keys(e, v, f0, &r0, s);
    size_t cheapest = cheapest_target(count, s);
    set_best(e, v, &r0, &s->targets[cheapest]);
    if (e->o->method != DECIMATE_IMPORTANCE && !(e->best[v].cost <= e->score_rules_up_to)) {
        e->flags[v] |= FLAG_UNCHECKED;
        return;
    }
    const char *rule;
    if (!collapse_legal(e, v, s->targets[cheapest].vertex, f0, &r0, boundary0, 0, s, &rule))
        set_best_after_cheapest(e, v, f0, &r0, boundary0, count, s);
}

/* The scoring step's work on v at the start of a pass: scored again where the last pass made it
 * stale (its score dropped where it was removed), and the last pass's marks cleared. */
static void settle_vertex(engine *e, uint32_t v, scratch *s)
{
    vertex_flags flags = e->flags[v];
    if (flags & FLAG_REMOVED) {
        e->best_target[v] = COLLAPSE_NONE;
        e->flags[v] &= (vertex_flags)~FLAG_NO_LEGAL;
    } else if (flags & FLAG_STALE)
        score_vertex(e, v, s);
    e->flags[v] &= (vertex_flags) ~(FLAG_STALE | FLAG_TOUCHED | FLAG_TAKEN | FLAG_MOVED);
    e->marks[v].touches = 0;
}

/* ---- the per-vertex steps, in parallel ---- */

/* The engine's threads: started once per run, each with its own scratch, handed one step
 * (vertex_step) at a time. */
typedef struct worker_start {
    worker_pool *pool;
    unsigned int index;
} worker_start;

/* What one step is: set before its generation is published, read by the threads that claim its
 * items. Two, by the generation's parity: a thread that wakes late reads the parameters of a
 * step already over, but can no longer claim any of its items. A step whose items are still
 * being listed (pool_open) is open: its count grows as the caller publishes more, and the
 * threads that have claimed all of them wait for more until the caller closes it (pool_close). */
typedef struct step_parameters {
    atomic_uint step, items, block;
    atomic_uint closed; /* whether `items` is final */
} step_parameters;

/* A step runs as its items are claimed, `block` at a time, from `claim` (the generation in the
 * upper 32 bits, the next item in the lower): a thread claims only within the generation whose
 * parameters it read. The caller waits until every item is done (`done`), not for every worker:
 * one that is not running (the machine is busy) or wakes after the items are gone costs
 * nothing. */
struct worker_pool {
    engine *e;
    pthread_t thread[MAX_THREADS];
    worker_start start[MAX_THREADS];
    scratch scratch[MAX_THREADS + 1]; /* [0]: the calling thread's */
    unsigned int count;               /* threads started besides the caller */
    pthread_mutex_t lock; /* with `wake`: for the workers that sleep between steps */
    pthread_cond_t wake;
    unsigned int sleepers;
    atomic_uint generation;
    atomic_int quit;
    step_parameters parameters[2];
    _Atomic uint64_t claim;
    atomic_uint done;
};

static void count_candidates(engine *e, uint32_t range);
static void write_keys(engine *e, uint32_t range);
static void count_digits(engine *e, uint32_t part);
static void sum_buckets(engine *e, uint32_t interval);
static void place_buckets(engine *e, uint32_t interval);
static void move_keys(engine *e, uint32_t part);
static void check_due(engine *e, uint32_t word, scratch *s);
static void first_ring(engine *e, uint32_t v, scratch *s);
static void judge_item(engine *e, uint32_t item, scratch *s);
static void apply_item(engine *e, uint32_t item, scratch *s);
static void compact_array(engine *e, uint32_t item);

static void run_item(engine *e, vertex_step step, uint32_t i, scratch *s)
{
    switch (step) {
    case STEP_START_VERTICES:
        start_vertices(e, i);
        break;
    case STEP_FIRST_TOUCH:
        first_touch(e, i);
        break;
    case STEP_COUNT_CORNERS:
        count_corners(e, i);
        break;
    case STEP_SUM_CORNERS:
        sum_corners(e, i);
        break;
    case STEP_PLACE_CORNERS:
        place_corners(e, i);
        break;
    case STEP_FILL_CORNERS:
        fill_corners(e, i);
        break;
    case STEP_WEIGH_FACES:
        weigh_face(e, i);
        break;
    case STEP_FIRST_RINGS:
        first_ring(e, i, s);
        break;
    case STEP_RINGS:
        build_ring(e, i, s, 0);
        break;
    case STEP_CLEAR_ATTRIBUTE_TERMS:
        clear_attribute_terms(e, i);
        break;
    case STEP_QUADRICS:
        sum_quadrics(e, i);
        break;
    case STEP_SCORES:
        settle_vertex(e, i, s);
        break;
    case STEP_COUNT_CANDIDATES:
        count_candidates(e, i);
        break;
    case STEP_WRITE_KEYS:
        write_keys(e, i);
        break;
    case STEP_COUNT_DIGITS:
        count_digits(e, i);
        break;
    case STEP_SUM_BUCKETS:
        sum_buckets(e, i);
        break;
    case STEP_PLACE_BUCKETS:
        place_buckets(e, i);
        break;
    case STEP_MOVE_KEYS:
        move_keys(e, i);
        break;
    case STEP_CHECK_CANDIDATES:
        check_due(e, i, s);
        break;
    case STEP_JUDGE:
        judge_item(e, i, s);
        break;
    case STEP_APPLY:
        apply_item(e, i, s);
        break;
    case STEP_COMPACT:
        compact_array(e, i);
        break;
    }
}

/* A short wait in a spin loop. */
static void spin_pause(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
}

/* Claims blocks of the items of step `generation` (vertices, or a chunk's candidates) and runs
 * them, until none is left or the step is over. */
static void run_step(worker_pool *pool, scratch *s, unsigned int generation)
{
    const step_parameters *parameters = &pool->parameters[generation & 1];
    for (;;) {
        uint64_t claim = atomic_load_explicit(&pool->claim, memory_order_acquire);
        if ((uint32_t)(claim >> 32) != generation)
            return;
        uint32_t begin = (uint32_t)claim;
        /* (closed read first: once it is set, `items` is final) */
        unsigned int closed = atomic_load_explicit(&parameters->closed, memory_order_acquire);
        uint32_t items = atomic_load_explicit(&parameters->items, memory_order_acquire);
        uint32_t block = atomic_load_explicit(&parameters->block, memory_order_relaxed);
        if (begin >= items) {
            if (closed)
                return;
            spin_pause(); /* an open step: the caller is listing more */
            continue;
        }
        uint32_t end = items - begin > block ? begin + block : items;
        if (!atomic_compare_exchange_weak_explicit(&pool->claim, &claim,
                                                   (uint64_t)generation << 32 | end,
                                                   memory_order_acquire, memory_order_relaxed))
            continue;
        /* claimed: the step cannot end, nor its parameters change, before these are done */
        vertex_step step = atomic_load_explicit(&parameters->step, memory_order_relaxed);
        s->step_items = items;
        for (uint32_t i = begin; i < end; i++)
            run_item(pool->e, step, i, s);
        atomic_fetch_add_explicit(&pool->done, end - begin, memory_order_release);
    }
}

static void *worker_main(void *arg)
{
    worker_pool *pool = ((worker_start *)arg)->pool;
    scratch *s = &pool->scratch[((worker_start *)arg)->index + 1];
    unsigned int seen = 0;
    for (;;) {
        /* Spin a while for the next step (the chunks of a pass follow each other within
         * microseconds), then sleep until woken. */
        unsigned int generation;
        for (unsigned int spins = 0;
             (generation = atomic_load_explicit(&pool->generation, memory_order_acquire)) == seen &&
             !atomic_load(&pool->quit);
             spins++) {
            if (spins < SPIN_LIMIT) {
                spin_pause();
                continue;
            }
            pthread_mutex_lock(&pool->lock);
            pool->sleepers++;
            while (atomic_load(&pool->generation) == seen && !atomic_load(&pool->quit))
                pthread_cond_wait(&pool->wake, &pool->lock);
            pool->sleepers--;
            pthread_mutex_unlock(&pool->lock);
        }
        if (atomic_load(&pool->quit))
            return NULL;
        seen = generation;
        run_step(pool, s, generation);
    }
}

static void pool_start(worker_pool *pool, engine *e, unsigned int threads)
{
    memset(pool, 0, sizeof *pool);
    pool->e = e;
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->wake, NULL);
    atomic_init(&pool->generation, 0);
    atomic_init(&pool->quit, 0);
    atomic_init(&pool->claim, 0);
    atomic_init(&pool->done, 0);
    for (int k = 0; k < 2; k++) {
        atomic_init(&pool->parameters[k].step, 0);
        atomic_init(&pool->parameters[k].items, 0);
        atomic_init(&pool->parameters[k].block, 1);
        atomic_init(&pool->parameters[k].closed, 1);
    }
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    /* No more threads than blocks of vertices to share. */
    while (threads > 1 && (size_t)(threads - 1) * SCORE_BLOCK >= e->n)
        threads--;
    for (unsigned int i = 0; i + 1 < threads; i++) {
        pool->start[i] = (worker_start){pool, i};
        if (pthread_create(&pool->thread[i], NULL, worker_main, &pool->start[i]) != 0)
            break; /* fewer threads: the same result, later */
        pool->count++;
    }
}

/* Publishes a step of `items` items (the first of them, where it is open) to the pool's
 * threads. */
static void pool_open(engine *e, vertex_step step, uint32_t items, uint32_t block, int open)
{
    worker_pool *pool = e->pool;
    unsigned int generation = atomic_load_explicit(&pool->generation, memory_order_relaxed) + 1;
    step_parameters *parameters = &pool->parameters[generation & 1];
    atomic_store_explicit(&parameters->step, step, memory_order_relaxed);
    atomic_store_explicit(&parameters->items, items, memory_order_relaxed);
    atomic_store_explicit(&parameters->block, block, memory_order_relaxed);
    atomic_store_explicit(&parameters->closed, !open, memory_order_relaxed);
    atomic_store_explicit(&pool->done, 0, memory_order_relaxed);
    atomic_store_explicit(&pool->claim, (uint64_t)generation << 32, memory_order_release);
    atomic_store_explicit(&pool->generation, generation, memory_order_release);
    pthread_mutex_lock(&pool->lock);
    if (pool->sleepers)
        pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
}

/* The open step's items now number `items` (what they read written before this). */
static void pool_publish(engine *e, uint32_t items)
{
    worker_pool *pool = e->pool;
    unsigned int generation = atomic_load_explicit(&pool->generation, memory_order_relaxed);
    atomic_store_explicit(&pool->parameters[generation & 1].items, items, memory_order_release);
}

/* The step's items, `items` in all, run on the pool's threads and the caller's (the open step
 * closed); returns when all are done. */
static void pool_close(engine *e, uint32_t items)
{
    worker_pool *pool = e->pool;
    unsigned int generation = atomic_load_explicit(&pool->generation, memory_order_relaxed);
    step_parameters *parameters = &pool->parameters[generation & 1];
    atomic_store_explicit(&parameters->items, items, memory_order_release);
    atomic_store_explicit(&parameters->closed, 1, memory_order_release);
    run_step(pool, &pool->scratch[0], generation);
    for (unsigned int spins = 0;
         atomic_load_explicit(&pool->done, memory_order_acquire) < items; spins++)
        if (spins < SPIN_LIMIT)
            spin_pause();
        else
            sched_yield(); /* a worker holding a block is off its core: let it run */
}

/* Runs one step over its items on the pool's threads and the caller's; returns when all are
 * done. */
static void run_on_pool(engine *e, vertex_step step, uint32_t items, uint32_t block)
{
    pool_open(e, step, items, block, 0);
    pool_close(e, items);
}

static void pool_stop(worker_pool *pool)
{
    pthread_mutex_lock(&pool->lock);
    atomic_store(&pool->quit, 1);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    for (unsigned int i = 0; i < pool->count; i++)
        pthread_join(pool->thread[i], NULL);
    for (unsigned int i = 0; i <= MAX_THREADS; i++)
        scratch_free(&pool->scratch[i]);
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->wake);
}

static void for_each_vertex(engine *e, vertex_step step) { run_on_pool(e, step, e->n, SCORE_BLOCK); }

/* ---- ranking ---- */

/* The full order of candidates: cost, then the removed vertex farthest from its importance
 * source, then the least important target, then the target closest to its source, then the
 * lower vertex. */
static int compare_candidates(const void *a, const void *b)
{
    const candidate *x = a, *y = b;
    if (x->cost != y->cost)
        return x->cost < y->cost ? -1 : 1;
    if (x->distance != y->distance)
        return x->distance > y->distance ? -1 : 1;
    if (x->target_importance != y->target_importance)
        return x->target_importance < y->target_importance ? -1 : 1;
    if (x->target_distance != y->target_distance)
        return x->target_distance < y->target_distance ? -1 : 1;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

/* Lists the candidates of the vertices of one range (vertex_range) as ranking keys, in vertex
 * order, at the range's offset: counted first (count_candidates), the offsets summed, then
 * written (write_keys). */
static void count_candidates(engine *e, uint32_t range)
{
    uint32_t first, end, count = 0, no_legal = 0;
    vertex_range(e, range, &first, &end);
    for (uint32_t v = first; v < end; v++) {
        count += e->best_target[v] != COLLAPSE_NONE;
        no_legal += (e->flags[v] & FLAG_NO_LEGAL) != 0;
    }
    e->range_offset[range + 1] = count;
    e->range_no_legal[range] = no_legal;
}

static void write_keys(engine *e, uint32_t range)
{
    uint32_t first, end;
    vertex_range(e, range, &first, &end);
    rank_key *key = &e->keys[e->range_offset[range]];
    for (uint32_t v = first; v < end; v++)
        if (e->best_target[v] != COLLAPSE_NONE) {
            uint32_t bits;
            memcpy(&bits, &e->best[v].cost, sizeof bits);
            *key++ = (rank_key){bits, v};
        }
}

/* Sorts keys[0 .. count) by the full order of their candidates (compare_candidates on best[]),
 * with spare[0 .. count) as room: a merge sort, as qsort takes no context. The order is total,
 * so the result is the one any sort gives. */
static void sort_ties(const engine *e, rank_key *keys, rank_key *spare, size_t count)
{
    for (size_t width = 1; width < count; width *= 2) {
        for (size_t low = 0; low < count; low += 2 * width) {
            size_t middle = low + width < count ? low + width : count;
            size_t high = low + 2 * width < count ? low + 2 * width : count;
            size_t a = low, b = middle, k = low;
            while (a < middle && b < high)
                spare[k++] = compare_candidates(&e->best[keys[b].vertex],
                                                &e->best[keys[a].vertex]) < 0
                                 ? keys[b++]
                                 : keys[a++];
            while (a < middle)
                spare[k++] = keys[a++];
            while (b < high)
                spare[k++] = keys[b++];
        }
        memcpy(keys, spare, sizeof(rank_key) * count);
    }
}

/* The ranking's radix sort: stable, by the cost's bits, the low digit first (keys -> spare_keys),
 * then the high (back), in parts of the keys (one per thread, at most RADIX_PARTS, each of at
 * least RADIX_PART_KEYS keys). Each digit's round: the keys of each part counted per bucket
 * (count_digits), the counts summed per interval of the buckets (sum_buckets) and the intervals'
 * starts summed from those, then each part's place per bucket written (place_buckets: the
 * buckets in order, in each the parts in order), then each part's keys moved there in their
 * order (move_keys). That order is the one a sort on one thread gives, on any number of parts.
 * With one part, the first count counts both digits. */

/* The digit `digit` (0: low, 1: high) of a key's cost bits. */
static uint32_t key_digit(rank_key key, int digit) { return key.cost_bits >> (16 * digit) & 0xffff; }

/* Part `part` of the keys being sorted: its first key and the one past its last. */
static void sort_part(const engine *e, uint32_t part, size_t *first, size_t *end)
{
    *first = e->ranked * part / e->sort_parts;
    *end = e->ranked * (part + 1) / e->sort_parts;
}

/* The row of counts of part `part` for the digit sorted by. */
static uint32_t *digit_row(const engine *e, uint32_t part)
{
    return &e->digit_counts[(size_t)(e->sort_parts > 1 ? part : (uint32_t)e->sort_digit) *
                            RADIX_BUCKETS];
}

static void count_digits(engine *e, uint32_t part)
{
    size_t first, end;
    sort_part(e, part, &first, &end);
    const rank_key *from = e->sort_digit ? e->spare_keys : e->keys;
    uint32_t *row = digit_row(e, part);
    if (e->sort_parts == 1) { /* (rows 0 and 1) */
        memset(row, 0, 2 * RADIX_BUCKETS * sizeof *row);
        for (size_t i = first; i < end; i++) {
            row[key_digit(from[i], 0)]++;
            row[RADIX_BUCKETS + key_digit(from[i], 1)]++;
        }
        return;
    }
    int digit = e->sort_digit;
    memset(row, 0, RADIX_BUCKETS * sizeof *row);
    for (size_t i = first; i < end; i++)
        row[key_digit(from[i], digit)]++;
}

/* Interval `interval` of the buckets: its first bucket and the one past its last. */
static void bucket_interval(const engine *e, uint32_t interval, uint32_t *first, uint32_t *end)
{
    *first = RADIX_BUCKETS / e->sort_parts * interval;
    *end = interval + 1 == e->sort_parts ? RADIX_BUCKETS : *first + RADIX_BUCKETS / e->sort_parts;
}

static void sum_buckets(engine *e, uint32_t interval)
{
    uint32_t first, end, keys = 0;
    bucket_interval(e, interval, &first, &end);
    for (uint32_t part = 0; part < e->sort_parts; part++) {
        const uint32_t *row = digit_row(e, part);
        for (uint32_t b = first; b < end; b++)
            keys += row[b];
    }
    e->interval_start[interval] = keys;
}

static void place_buckets(engine *e, uint32_t interval)
{
    uint32_t first, end, place = e->interval_start[interval];
    bucket_interval(e, interval, &first, &end);
    uint32_t *rows[RADIX_PARTS];
    for (uint32_t part = 0; part < e->sort_parts; part++)
        rows[part] = digit_row(e, part);
    for (uint32_t b = first; b < end; b++)
        for (uint32_t part = 0; part < e->sort_parts; part++) {
            uint32_t keys = rows[part][b];
            rows[part][b] = place;
            place += keys;
        }
}

static void move_keys(engine *e, uint32_t part)
{
    size_t first, end;
    sort_part(e, part, &first, &end);
    int digit = e->sort_digit;
    const rank_key *from = digit ? e->spare_keys : e->keys;
    rank_key *to = digit ? e->keys : e->spare_keys;
    uint32_t *place = digit_row(e, part);
    for (size_t i = first; i < end; i++)
        to[place[key_digit(from[i], digit)]++] = from[i];
}

/* Ranks the candidates into e->keys (e->ranked of them): their keys (the cost's bits and the
 * vertex) listed in vertex order, the radix sort above on the cost's bits (costs are not
 * negative, so their bits order as the costs do), stable, so equal costs stay in vertex order;
 * then runs of equal cost sorted by the full order where the ties have keys beyond the vertex.
 * The ranking is of keys alone: the judging reads a candidate's vertex and the taking its cost,
 * both in its key, so the records are not gathered into the ranked order. */
static void rank_candidates(engine *e, int full_ties)
{
    uint32_t ranges = e->threads;
    e->range_offset[0] = 0;
    run_on_pool(e, STEP_COUNT_CANDIDATES, ranges, 1);
    e->no_legal = 0;
    for (uint32_t r = 0; r < ranges; r++) {
        e->range_offset[r + 1] += e->range_offset[r];
        e->no_legal += e->range_no_legal[r];
    }
    size_t count = e->range_offset[ranges];
    e->ranked = count;
    if (!count)
        return;
    run_on_pool(e, STEP_WRITE_KEYS, ranges, 1);
    size_t parts_for_keys = count / RADIX_PART_KEYS;
    uint32_t parts = e->threads < RADIX_PARTS ? e->threads : RADIX_PARTS;
    if (parts > parts_for_keys)
        parts = parts_for_keys > 1 ? (uint32_t)parts_for_keys : 1;
    e->sort_parts = parts;
    for (int digit = 0; digit < 2; digit++) {
        e->sort_digit = digit;
        if (digit == 0 || parts > 1)
            run_on_pool(e, STEP_COUNT_DIGITS, parts, 1);
        e->interval_start[0] = 0;
        if (parts > 1) {
            run_on_pool(e, STEP_SUM_BUCKETS, parts, 1);
            uint32_t start = 0;
            for (uint32_t interval = 0; interval < parts; interval++) {
                uint32_t keys = e->interval_start[interval];
                e->interval_start[interval] = start;
                start += keys;
            }
        }
        run_on_pool(e, STEP_PLACE_BUCKETS, parts, 1);
        run_on_pool(e, STEP_MOVE_KEYS, parts, 1);
    }
    if (!full_ties)
        return;
    rank_key *keys = e->keys;
    for (size_t i = 0; i < count;) {
        size_t j = i + 1;
        while (j < count && key_cost(&keys[j]) == key_cost(&keys[i]))
            j++;
        if (j - i > 1)
            sort_ties(e, &keys[i], &e->spare_keys[i], j - i);
        i = j;
    }
}

/* ---- the ranking checked against the rules ---- */

/* Checks v's candidate against the rules on the mesh as the pass found it (v due: unchecked,
 * its cheapest collapse costing at most check_up_to): its cheapest collapse stands where legal;
 * otherwise its best legal one (set_best_after_cheapest) replaces it, v is marked FLAG_MOVED and
 * its key (stale now) listed in the scratch. */
static void check_vertex(engine *e, uint32_t v, scratch *s)
{
    e->flags[v] &= (vertex_flags)~FLAG_UNCHECKED;
    ring r0 = ring_of(e, v);
    fan f0 = pass_fan(e, v);
    int boundary0 = 0;
    ring_simple(&r0, &boundary0); /* (one fan, as it was when scored) */
    const char *rule;
    if (collapse_legal(e, v, e->best_target[v], f0, &r0, boundary0, 0, s, &rule))
        return;
    rank_key key = {0, v};
    memcpy(&key.cost_bits, &e->best[v].cost, sizeof key.cost_bits);
    size_t count = target_keys(e, v, f0, &r0, s);
    set_best_after_cheapest(e, v, f0, &r0, boundary0, count, s);
    e->flags[v] |= FLAG_MOVED;
    reserve((void **)&s->moved, &s->moved_capacity, s->moved_count + 1, sizeof(rank_key));
    s->moved[s->moved_count++] = key;
}

/* Checks the candidates of the vertices due in word `word` of the due bits (64 vertices), in
 * vertex order, and clears the word. */
static void check_due(engine *e, uint32_t word, scratch *s)
{
    uint64_t due = e->due[word];
    e->due[word] = 0;
    while (due) {
        check_vertex(e, 64 * word + (uint32_t)__builtin_ctzll(due), s);
        due &= due - 1;
    }
}

/* Whether the ranking key's candidate moved when checked (its key is stale). */
static int key_moved(const engine *e, rank_key key)
{
    return (e->flags[key.vertex] & FLAG_MOVED) != 0;
}

/* Sorts the costs' bits values[0 .. count) into increasing order, as unsigned numbers: a radix
 * sort, three digits of 11 bits (all 32) from the lowest, through e->sort_spare (with qsort's
 * comparisons, the lists of moved candidates took 0.005 s of serial work a run on the dragon). */
static void sort_cost_bits(engine *e, uint32_t *values, size_t count)
{
    enum { BITS = 11, BUCKETS = 1 << BITS, DIGITS = 3 };
    if (count < 2)
        return;
    reserve((void **)&e->sort_spare, &e->sort_spare_capacity, count, sizeof(uint32_t));
    uint32_t place[DIGITS][BUCKETS];
    memset(place, 0, sizeof place);
    for (size_t i = 0; i < count; i++)
        for (int d = 0; d < DIGITS; d++)
            place[d][values[i] >> (BITS * d) & (BUCKETS - 1)]++;
    uint32_t *from = values, *to = e->sort_spare;
    for (int d = 0; d < DIGITS; d++) {
        uint32_t sum = 0;
        for (uint32_t b = 0; b < BUCKETS; b++) {
            uint32_t in_bucket = place[d][b];
            place[d][b] = sum;
            sum += in_bucket;
        }
        for (size_t i = 0; i < count; i++)
            to[place[d][from[i] >> (BITS * d) & (BUCKETS - 1)]++] = from[i];
        uint32_t *sorted = to;
        to = from;
        from = sorted;
    }
    if (from != values) /* (an odd number of digits leaves them in the spare) */
        memcpy(values, from, sizeof(uint32_t) * count);
}

static void wait_push(engine *e, rank_key key);

/* How many of the sorted bits[0 .. count) are at most `bits`. */
static size_t count_at_most(const uint32_t *sorted, size_t count, uint32_t bits)
{
    size_t low = 0, high = count;
    while (low < high) {
        size_t middle = low + (high - low) / 2;
        if (sorted[middle] <= bits)
            low = middle + 1;
        else
            high = middle;
    }
    return low;
}

/* How many keys (sorted by cost) cost at most `bits`. */
static size_t keys_at_most(const engine *e, uint32_t bits)
{
    size_t low = 0, high = e->ranked;
    while (low < high) {
        size_t middle = low + (high - low) / 2;
        if (e->keys[middle].cost_bits <= bits)
            low = middle + 1;
        else
            high = middle;
    }
    return low;
}

/* How many candidates of the ranking as checked cost at most `bits`: the keys, less those that
 * moved, plus the moved ones' new costs (moved_from and moved_costs sorted). */
static size_t checked_at_most(const engine *e, uint32_t bits)
{
    return keys_at_most(e, bits) - count_at_most(e->moved_from, e->moved_from_count, bits) +
           count_at_most(e->moved_costs, e->moved_count, bits);
}

/* The cost at 0-based place `place` of the ranking as checked (the last where there are fewer
 * candidates): the least cost with more than `place` candidates at most it, found by bisecting
 * the costs' bits (which order as the costs do: none is negative or NaN); *known: whether it is
 * certain, i.e. at most check_up_to (an unchecked candidate costs more: its best legal collapse
 * costs at least its cheapest). */
static float checked_cost_at(const engine *e, size_t place, int *known)
{
    size_t total = e->ranked - e->moved_from_count + e->moved_count;
    if (place >= total)
        place = total ? total - 1 : 0;
    uint32_t low = 0, high = 0x7f800000u; /* +infinity's bits: above every cost */
    while (low < high) {
        uint32_t middle = low + (high - low) / 2;
        if (checked_at_most(e, middle) > place)
            high = middle;
        else
            low = middle + 1;
    }
    float cost = 0;
    if (total)
        memcpy(&cost, &low, sizeof cost);
    *known = cost <= e->check_up_to;
    return cost;
}

/* Checks the unchecked candidates costing at most `bound` (check_vertex, on the pool); those
 * that moved wait at their own keys (wait_push), their new costs and their stale keys' listed in
 * moved_costs and moved_from, sorted. The unchecked ones cost more than the last bound (those
 * below it were checked): their keys, a stretch of the ranking, mark their vertices due (a bit
 * each), and the pool checks the due bits 64 vertices at a time, in vertex order, where their
 * neighbourhoods are near each other (a sweep of every vertex's flags and cost took a fifth of
 * the check's time on the dragon). */
static void check_candidates_up_to(engine *e, float bound)
{
    /* the keys costing more than the last bound and at most this one */
    uint32_t bits;
    size_t from = 0, to = e->ranked;
    if (e->check_up_to >= 0) {
        memcpy(&bits, &e->check_up_to, sizeof bits);
        from = keys_at_most(e, bits);
    }
    if (bound < INFINITY) {
        memcpy(&bits, &bound, sizeof bits);
        to = keys_at_most(e, bits);
    }
    e->check_up_to = bound;
    for (size_t i = from; i < to; i++) { /* an unchecked vertex's key is its candidate's */
        uint32_t v = e->keys[i].vertex;
        if (e->flags[v] & FLAG_UNCHECKED)
            e->due[v / 64] |= (uint64_t)1 << (v % 64);
    }
    worker_pool *pool = e->pool;
    for (unsigned int t = 0; t <= pool->count; t++)
        pool->scratch[t].moved_count = 0;
    run_on_pool(e, STEP_CHECK_CANDIDATES, e->n / 64 + 1, SCORE_BLOCK / 64);
    for (unsigned int t = 0; t <= pool->count; t++) {
        const scratch *moved = &pool->scratch[t];
        for (size_t k = 0; k < moved->moved_count; k++) {
            uint32_t v = moved->moved[k].vertex;
            reserve((void **)&e->moved_from, &e->moved_from_capacity, e->moved_from_count + 1,
                    sizeof(uint32_t));
            e->moved_from[e->moved_from_count++] = moved->moved[k].cost_bits;
            if (e->best_target[v] == COLLAPSE_NONE)
                continue; /* no legal collapse */
            rank_key key = {0, v};
            memcpy(&key.cost_bits, &e->best[v].cost, sizeof key.cost_bits);
            wait_push(e, key);
            reserve((void **)&e->moved_costs, &e->moved_capacity, e->moved_count + 1,
                    sizeof(uint32_t));
            e->moved_costs[e->moved_count++] = key.cost_bits;
        }
    }
    sort_cost_bits(e, e->moved_costs, e->moved_count); /* (an empty list may be no array) */
    sort_cost_bits(e, e->moved_from, e->moved_from_count);
}

/* The rules applied to the ranking (the cost methods, whose scores are unchecked), as far as the
 * pass may reach, and the pass's cost limit: PASS_COST_FACTOR x the cost a quarter down the
 * ranking of best legal collapses. The candidates costing up to the cost at 3/8 of the ranking
 * are checked (check_vertex, on the pool, in vertex order, where their neighbourhoods are at
 * hand), then up to 4/8, and so on, until the limit is at most that cost: every candidate the
 * pass may take is then ranked at its best legal collapse, as if scored with the rules, and the
 * limit is the one that ranking gives. Those that moved wait at their own keys (wait_push). A
 * pass reaches a quarter to a half of its ranking, so most candidates are never checked. */
static float check_ranking(engine *e)
{
    size_t ranked = e->ranked;
    e->moved_count = e->moved_from_count = 0;
    e->check_up_to = -1.0f; /* nothing checked yet in this pass */
    if (e->o->method == DECIMATE_IMPORTANCE) { /* scored with the rules */
        e->check_up_to = INFINITY;
        return key_cost(&e->keys[ranked / 4]) * PASS_COST_FACTOR;
    }
    size_t share = ranked / 8 > CHUNK ? ranked / 8 : CHUNK;
    for (size_t end = 3 * share;; end += share) {
        check_candidates_up_to(e, end < ranked ? key_cost(&e->keys[end - 1]) : INFINITY);
        int known;
        /* a quarter down the candidates, counting those with no legal collapse (as the last) */
        float limit = checked_cost_at(e, (ranked + e->no_legal) / 4, &known) * PASS_COST_FACTOR;
        if (end >= ranked || (known && limit <= e->check_up_to))
            return limit;
    }
}

/* ---- applying collapses ---- */

/* Adds id to the distinct ids s->ids[0 .. count); returns the new count. */
static size_t add_id(scratch *s, size_t count, uint32_t id)
{
    for (size_t j = 0; j < count; j++)
        if (s->ids[j] == id)
            return count;
    if (count == s->ids_capacity) {
        s->ids_capacity = s->ids_capacity ? 2 * s->ids_capacity : 32;
        s->ids = xrealloc(s->ids, sizeof(uint32_t) * s->ids_capacity);
        s->mapped = xrealloc(s->mapped, sizeof(uint32_t) * s->ids_capacity);
    }
    s->ids[count] = id;
    return count + 1;
}

/* v's wedge count now: its distinct corner ids among its current triangles (its pass-start ones
 * and its donor's), into s->ids; 1 without attributes (or without triangles). */
static uint64_t current_wedges(const engine *e, uint32_t v, scratch *s)
{
    if (!e->m->corner_ids)
        return 1;
    uint32_t sources[2] = {v, donor_of(e, v)};
    size_t count = 0;
    for (int k = 0; k < 2; k++) {
        if (sources[k] == COLLAPSE_NONE)
            continue;
        fan f = pass_fan(e, sources[k]);
        for (uint32_t i = 0; i < f.count; i++) {
            uint32_t t = f.triangle[i];
            if (corners(e, t)[0] != COLLAPSE_NONE && corner_at(e, t, v) != 3)
                count = add_id(s, count, id_at(e, t, v));
        }
    }
    return count ? count : 1;
}

/* current_wedges(v), and v's distinct corner ids without triangles without_a and without_b
 * (into s->ids, their count into *after), in one sweep of v's triangles. */
static uint64_t current_wedges_and_ids(const engine *e, uint32_t v, uint32_t without_a,
                                       uint32_t without_b, scratch *s, size_t *after)
{
    uint32_t sources[2] = {v, donor_of(e, v)};
    size_t before = 0, kept = 0;
    for (int k = 0; k < 2; k++) {
        if (sources[k] == COLLAPSE_NONE)
            continue;
        fan f = pass_fan(e, sources[k]);
        for (uint32_t i = 0; i < f.count; i++) {
            uint32_t t = f.triangle[i];
            if (corners(e, t)[0] == COLLAPSE_NONE || corner_at(e, t, v) == 3)
                continue;
            uint32_t id = id_at(e, t, v);
            size_t j = 0;
            while (j < before && s->ids_before[j] != id)
                j++;
            if (j == before) {
                reserve((void **)&s->ids_before, &s->ids_before_capacity, before + 1,
                        sizeof(uint32_t));
                s->ids_before[before++] = id;
            }
            if (t != without_a && t != without_b)
                kept = add_id(s, kept, id);
        }
    }
    *after = kept;
    return before ? before : 1;
}

/* Whether w's live triangles are of one corner id at it and live_degree[w] counts them
 * (known_wedge on the mesh as it is). */
static int one_wedge_now(const engine *e, uint32_t w)
{
    return known_wedge(e, w, 1) != COLLAPSE_NONE;
}

/* What collapse_removes' sweeps count where v0, v1 and the edge's sides vl and vr (other
 * vertices, from v0's ring: those of sides_of) are each of one wedge (one_wedge_now), without
 * reading their triangles: v0's wedge, and each kept vertex's where it keeps no triangle (the
 * edge's triangles are v0's, v1's and one side's, or both where vl is vr; v1 keeps a wedge
 * while it or v0 keeps a triangle, as v0's go to v1). 0 where that does not hold. The dragon
 * with normals: 99 % of the legal collapses judged are counted here (69 % while a side that was
 * the kept end of a collapse taken earlier in the pass was swept), and the judging took
 * 0.31-0.35 s on one thread, against 0.81-0.86 s with the sweeps for all. */
static uint64_t removes_of_one_wedges(const engine *e, uint32_t v0, uint32_t v1, uint32_t vl,
                                      uint32_t vr)
{
    uint32_t side[2] = {vl, vr};
    if (!one_wedge_now(e, v0) || !one_wedge_now(e, v1))
        return 0;
    for (int k = 0; k < 2; k++)
        if (side[k] != COLLAPSE_NONE &&
            (side[k] == v0 || side[k] == v1 || !one_wedge_now(e, side[k])))
            return 0;
    uint32_t edge_triangles = (vl != COLLAPSE_NONE) + (vr != COLLAPSE_NONE);
    uint64_t removes = 1;
    if (e->live_degree[v1] == edge_triangles && e->live_degree[v0] == edge_triangles)
        removes++;
    for (int k = 0; k < 2; k++)
        if (side[k] != COLLAPSE_NONE && e->live_degree[side[k]] == 1u + (side[0] == side[1]))
            removes++;
    return removes;
}

/* The vertices (counted once per wedge) that taking v0 -> v1 would remove, the mesh as it is:
 * v0's wedges, and those that v1, vl and vr (the edge's sides in v0's ring) lose with the two
 * triangles of the edge (v0's corners go into wedges v1 has). Without attributes, 1. */
static uint64_t collapse_removes(const engine *e, fan f0, uint32_t v0, uint32_t v1, uint32_t vl,
                                 uint32_t vr, scratch *s)
{
    if (!e->m->corner_ids)
        return 1;
    uint64_t found = SHORTCUTS ? removes_of_one_wedges(e, v0, v1, vl, vr) : 0;
    if (found)
        return found;
    edge_sides sides = sides_of(e, f0, v0, v1);
    mapping map = mapping_of(e, v0, v1, &sides);
    uint64_t removed = current_wedges(e, v0, s);
    uint32_t kept[3] = {v1, sides.vl, sides.vr};
    for (int k = 0; k < 3; k++) {
        if (kept[k] == COLLAPSE_NONE)
            continue;
        size_t after;
        uint64_t before = current_wedges_and_ids(e, kept[k], sides.fl, sides.fr, s, &after);
        if (k == 0) /* v1 also gets v0's corners, in the wedges they map to */
            for (uint32_t i = 0; i < f0.count; i++) {
                uint32_t t = f0.triangle[i];
                if (t != sides.fl && t != sides.fr)
                    after = add_id(s, after, mapped_id(&map, id_at(e, t, v0)));
            }
        removed += before > after ? before - after : 0;
    }
    return removed;
}

/* Sets bits of a vertex's flags; atomic, as collapses taken side by side may touch one vertex. */
static void flag(engine *e, uint32_t v, vertex_flags bits)
{
    /* most corners are flagged twice or more: the locked read-modify-write only where needed */
    if ((__atomic_load_n(&e->flags[v], __ATOMIC_RELAXED) & bits) != bits)
        __atomic_fetch_or(&e->flags[v], bits, __ATOMIC_RELAXED);
}

/* Takes v0 -> v1 (neither an end of a collapse taken in this pass; f0 holds v0's live
 * triangles): moves v0's triangles onto v1, removes the two of the edge, merges the quadrics (or
 * the importance), records the history and touches v0's ring. */
static void apply_collapse(engine *e, fan f0, uint32_t v0, uint32_t v1, uint32_t *history,
                           scratch *s)
{
    edge_sides sides = sides_of(e, f0, v0, v1);
    int attributes = e->m->corner_ids != NULL;
    mapping map = {0, 0, 0, 0, 0};
    if (attributes) {
        /* (v0 and v1 are no end of a collapse taken in this pass: their pass-start wedges hold,
         * known without reading their flags, which collapses taken beside this one write) */
        uint32_t wedge0 = known_wedge(e, v0, 0), wedge1 = known_wedge(e, v1, 0);
        map = wedge1 != COLLAPSE_NONE ? mapping_into(wedge1) : mapping_of(e, v0, v1, &sides);
        if (e->attributes_weighted) {
            size_t count = ids_at(e, f0, v0, wedge0, s);
            for (size_t k = 0; k < count; k++)
                attribute_merge(e, s->ids[k], mapped_id(&map, s->ids[k]));
        }
    }
    for (uint32_t i = 0; i < f0.count; i++) {
        uint32_t t = f0.triangle[i];
        uint32_t *c = corners(e, t);
        for (int k = 0; k < 3; k++)
            flag(e, c[k], FLAG_TOUCHED);
        if (t == sides.fl || t == sides.fr) {
            c[0] = c[1] = c[2] = COLLAPSE_NONE;
            /* (v1 and the sides are written by no other collapse taken beside this) */
            if (e->live_degree) {
                e->live_degree[t == sides.fl ? sides.vl : sides.vr]--;
                e->live_degree[v1]--;
            }
            continue;
        }
        if (e->live_degree)
            e->live_degree[v1]++;
        int k = corner_at(e, t, v0);
        c[k] = v1;
        if (attributes)
            e->m->corner_ids[3 * (size_t)t + k] =
                mapped_id(&map, e->m->corner_ids[3 * (size_t)t + k]);
    }
    if (e->quadric) {
        double *q1 = &e->quadric[10 * (size_t)v1];
        for (int k = 0; k < 10; k++)
            q1[k] += e->quadric[10 * (size_t)v0 + k];
        e->self_error[v1] = quadric_error(q1, position(e, v1));
    }
    if (e->o->method == DECIMATE_IMPORTANCE)
        e->importance[v1] += e->importance[v0];
    flag(e, v0, FLAG_REMOVED | FLAG_TAKEN);
    flag(e, v1, FLAG_TAKEN);
    e->donor[v1] = v0;
    history[caller_vertex(e, v0)] = caller_vertex(e, v1);
}

/* Whether a collapse taken earlier in this pass changed the triangles that v0 -> v1 was judged
 * on: those of v0, v1, vl and vr. */
static int neighbourhood_touched(const engine *e, const judgement *j)
{
    if ((e->flags[j->v0] | e->flags[j->v1]) & FLAG_TOUCHED)
        return 1;
    return (j->vl != COLLAPSE_NONE && (e->flags[j->vl] & FLAG_TOUCHED)) ||
           (j->vr != COLLAPSE_NONE && (e->flags[j->vr] & FLAG_TOUCHED));
}

/* A checked candidate v0 -> v1 whose v0 is untouched (its triangles, fan and ring r0 as the pass
 * found them) but whose target or sides were touched: whether the rules that read those still
 * hold (target_rules_kept, sides_rule_kept; own_rules_kept reads v0's triangles alone, and holds
 * as checked). */
static int changed_rules_kept(const engine *e, const judgement *j, const ring *r0, uint32_t slot,
                              scratch *s)
{
    const char *rule;
    int boundary0 = 0;
    ring_simple(r0, &boundary0); /* (one fan, as when checked) */
    if (e->flags[j->v1] & FLAG_TOUCHED) {
        ring r1 = ring_for(e, j->v1, 1, s, SLOT_V1);
        if (!target_rules_kept(j->v1, r0, slot, boundary0, &r1, &rule))
            return 0;
    }
    int sides_touched = (j->vl != COLLAPSE_NONE && (e->flags[j->vl] & FLAG_TOUCHED)) ||
                        (j->vr != COLLAPSE_NONE && (e->flags[j->vr] & FLAG_TOUCHED));
    return !sides_touched || sides_rule_kept(e, j->vl, j->vr, 1, &rule);
}

/* Judges v0 -> v1 on the mesh as it is, as the pass's greedy order would when it comes to it:
 * skipped where an end was taken in this pass; legal as scored where no collapse taken touched
 * its neighbourhood; otherwise judged again by the rules that read what was touched, on the
 * rings gathered anew (the cost stands: v0 and v1 received nothing, so their quadrics are as
 * scored). A candidate not checked against the rules (check_ranking) is illegal here: it costs
 * more than the pass's limit, which stops the pass before it or checks it first. */
static void judge(const engine *e, uint32_t v0, uint32_t v1, scratch *s, judgement *j)
{
    j->v0 = v0, j->v1 = v1, j->vl = j->vr = COLLAPSE_NONE;
    j->write_count = 0;
    j->removes = 0;
    j->verdict = VERDICT_SKIP;
    if ((e->flags[v0] | e->flags[v1]) & FLAG_TAKEN)
        return;
    fan f0 = pass_fan(e, v0);
    ring r0 = e->flags[v0] & FLAG_TOUCHED ? current_ring(e, v0, s, SLOT_V0, &f0) : ring_of(e, v0);
    uint32_t slot = ring_find(&r0, v1);
    j->verdict = VERDICT_ILLEGAL;
    if (slot == r0.size)
        return; /* no longer neighbours */
    j->vl = r0.entry[slot].left, j->vr = r0.entry[slot].right;
    if (e->flags[v0] & FLAG_UNCHECKED)
        return;
    if (e->flags[v0] & FLAG_TOUCHED) {
        const char *rule;
        int boundary0;
        if (!ring_simple(&r0, &boundary0) || r0.size <= 2 ||
            !collapse_legal(e, v0, v1, f0, &r0, boundary0, 1, s, &rule))
            return;
    } else if (neighbourhood_touched(e, j) && !changed_rules_kept(e, j, &r0, slot, s))
        return;
    j->verdict = VERDICT_LEGAL;
    j->removes = collapse_removes(e, f0, v0, v1, j->vl, j->vr, s);
    j->writes[0] = v0;
    j->write_count = r0.size + 1 <= WRITES_MAX ? (uint8_t)(r0.size + 1) : WRITES_MAX + 1;
    for (uint32_t i = 0; i < r0.size && i + 1 < WRITES_MAX; i++)
        j->writes[i + 1] = r0.entry[i].vertex;
}

/* Takes a judged collapse (no collapse taken since touched v0's triangles): apply_collapse on
 * v0's live triangles, the pass's while v0 is untouched. */
static void take(engine *e, const judgement *j, scratch *s)
{
    fan f0 = e->flags[j->v0] & FLAG_TOUCHED ? current_fan(e, j->v0, s, SLOT_V0)
                                             : pass_fan(e, j->v0);
    apply_collapse(e, f0, j->v0, j->v1, e->history, s);
}

/* Judging and taking read at random vertices (the ranking is by cost, not by place): each
 * collapse's reads wait on each other (a vertex's flags, then its adjacency, then its ring or
 * triangles), and a step is too long for the processor to start the next item's reads by
 * itself. The items ahead are known, so their reads are asked for early, each link of a chain
 * a few items before the next: prefetches, which change no result. */

/* v's pass-start triangles asked for. */
static void prefetch_fan(const engine *e, uint32_t v)
{
    fan f = pass_fan(e, v);
    for (uint32_t i = 0; i < f.count; i++)
        __builtin_prefetch(corners(e, f.triangle[i]));
}

/* The reads of judge(), by how far ahead the candidate is:
 * - JUDGE_AHEAD: v0's flags, adjacency start and ring size, and its target;
 * - half as far: v0's ring (or, where v0 was touched, its adjacency, as judge gathers its ring
 *   from its triangles), and v1's flags, adjacency start and ring size;
 * - 2: a touched v0's triangles; v1's ring, or its adjacency where touched; the flags,
 *   adjacency starts and ring sizes of the edge's sides vl and vr, where v0's ring (untouched)
 *   gives them;
 * - 1: a touched v1's triangles.
 * Judging the dragon to 10 % (722,000 candidates, a sixth with v0 touched) took 0.34 s on one
 * thread with only the first two, 0.22 s with all four. */
static void prefetch_judging(const engine *e, uint32_t item)
{
    uint32_t size = e->chunk_size;
    if (item + JUDGE_AHEAD < size) {
        uint32_t v0 = e->chunk[item + JUDGE_AHEAD].vertex;
        __builtin_prefetch(&e->best_target[v0]);
        __builtin_prefetch(&e->flags[v0]);
        __builtin_prefetch(&e->adjacency_start[v0]);
        __builtin_prefetch(&e->ring_size[v0]);
    }
    if (item + JUDGE_AHEAD / 2 < size) {
        uint32_t v0 = e->chunk[item + JUDGE_AHEAD / 2].vertex;
        uint32_t v1 = e->best_target[v0];
        __builtin_prefetch(pass_ring_entries(e, v0));
        if (e->flags[v0] & FLAG_TOUCHED)
            __builtin_prefetch(&e->adjacency[e->adjacency_start[v0]]);
        __builtin_prefetch(&e->flags[v1]);
        __builtin_prefetch(&e->adjacency_start[v1]);
        __builtin_prefetch(&e->ring_size[v1]);
    }
    if (item + 2 < size) {
        uint32_t v0 = e->chunk[item + 2].vertex;
        uint32_t v1 = e->best_target[v0];
        if (e->flags[v0] & FLAG_TOUCHED) {
            prefetch_fan(e, v0);
        } else {
            ring r0 = ring_of(e, v0);
            uint32_t slot = ring_find(&r0, v1);
            uint32_t sides[2] = {slot < r0.size ? r0.entry[slot].left : COLLAPSE_NONE,
                                 slot < r0.size ? r0.entry[slot].right : COLLAPSE_NONE};
            for (int k = 0; k < 2; k++)
                if (sides[k] != COLLAPSE_NONE) {
                    __builtin_prefetch(&e->flags[sides[k]]);
                    __builtin_prefetch(&e->adjacency_start[sides[k]]);
                    __builtin_prefetch(&e->ring_size[sides[k]]);
                }
        }
        if (e->flags[v1] & FLAG_TOUCHED)
            __builtin_prefetch(&e->adjacency[e->adjacency_start[v1]]);
        else
            __builtin_prefetch(pass_ring_entries(e, v1));
    }
    if (item + 1 < size) {
        uint32_t v1 = e->best_target[e->chunk[item + 1].vertex];
        if (e->flags[v1] & FLAG_TOUCHED)
            prefetch_fan(e, v1);
    }
}

/* For the collapse PREFETCH_AHEAD accepted ones on, where it is listed yet (`listed`): the
 * quadrics it merges, v1's records it writes and v0's triangles it moves. */
static void prefetch_taking(const engine *e, uint32_t item, uint32_t listed)
{
    if (item + PREFETCH_AHEAD >= listed)
        return;
    const judgement *j = &e->judgements[e->accepted[item + PREFETCH_AHEAD]];
    if (e->quadric) { /* 80 bytes each: two cache lines */
        const double *q0 = &e->quadric[10 * (size_t)j->v0], *q1 = &e->quadric[10 * (size_t)j->v1];
        __builtin_prefetch(q0);
        __builtin_prefetch(q0 + 9);
        __builtin_prefetch(q1, 1);
        __builtin_prefetch(q1 + 9, 1);
        __builtin_prefetch(&e->self_error[j->v1], 1);
    }
    __builtin_prefetch(&e->donor[j->v1], 1);
    if (!e->vertex_of)
        __builtin_prefetch(&e->history[j->v0], 1);
    fan f0 = pass_fan(e, j->v0);
    for (uint32_t i = 0; i < f0.count; i++)
        __builtin_prefetch(corners(e, f0.triangle[i]), 1);
}

/* The acceptance of a chunk's candidates reads the marks of each judged candidate's ends and
 * writes those of its ring, at random vertices: those of the one ACCEPT_AHEAD ahead are asked
 * for (on the dragon, the acceptance took 0.020 s on one thread without, 0.015 s with). */
static void prefetch_acceptance(const engine *e, uint32_t item)
{
    if (item + ACCEPT_AHEAD >= e->chunk_size)
        return;
    const judgement *j = &e->judgements[item + ACCEPT_AHEAD];
    __builtin_prefetch(&e->marks[j->v0], 1);
    __builtin_prefetch(&e->marks[j->v1]);
    if (j->write_count <= WRITES_MAX)
        for (uint32_t i = 1; i < j->write_count; i++) /* (writes[0] is v0) */
            __builtin_prefetch(&e->marks[j->writes[i]], 1);
}

static void judge_item(engine *e, uint32_t item, scratch *s)
{
    prefetch_judging(e, item);
    uint32_t v0 = e->chunk[item].vertex;
    judge(e, v0, e->best_target[v0], s, &e->judgements[item]);
}

static void apply_item(engine *e, uint32_t item, scratch *s)
{
    prefetch_taking(e, item, s->step_items);
    take(e, &e->judgements[e->accepted[item]], s);
}

/* engine_init's first ring of v (build_ring, the fan checked where the caller did not), and v's
 * wedges (current_wedges), where it has triangles, counted in the thread's scratch: the sum
 * over the threads is the mesh's vertex count as the target counts it. */
static void first_ring(engine *e, uint32_t v, scratch *s)
{
    build_ring(e, v, s, e->m->fans_unchecked);
    if (e->adjacency_start[v] < e->adjacency_start[v + 1])
        s->wedges += current_wedges(e, v, s);
}

/* Whether a collapse accepted earlier in this chunk writes vertex v. */
static int written(const engine *e, uint32_t v)
{
    return v != COLLAPSE_NONE && e->marks[v].chunk == e->chunk_mark;
}

/* Marks v written in this chunk. */
static void mark_written(engine *e, uint32_t v) { e->marks[v].chunk = e->chunk_mark; }

/* Marks v written in this chunk, and touched once more in this pass. */
static void mark_touched(engine *e, uint32_t v)
{
    mark_written(e, v);
    if (e->marks[v].touches < TOUCHES_KNOWN)
        e->marks[v].touches++;
}

/* The marks of the next chunk: the next value (none is written with it yet), all cleared where
 * the values wrap (once in 255 chunks). */
static void next_chunk_mark(engine *e)
{
    if (++e->chunk_mark == 0) {
        for (uint32_t v = 0; v <= e->n; v++)
            e->marks[v].chunk = 0;
        e->chunk_mark = 1;
    }
}

/* Marks what taking the judged collapse writes: v0 and its ring, which it touches. */
static void mark_writes(engine *e, const judgement *j, scratch *s)
{
    mark_written(e, j->v0);
    if (j->write_count <= WRITES_MAX) {
        for (uint32_t i = 1; i < j->write_count; i++) /* (writes[0] is v0) */
            mark_touched(e, j->writes[i]);
        return;
    }
    fan f0;
    ring r0 = current_ring(e, j->v0, s, SLOT_V0, &f0);
    for (uint32_t i = 0; i < r0.size; i++)
        mark_touched(e, r0.entry[i].vertex);
}

/* Whether candidate a comes before candidate b in the ranking: by cost, then compare_candidates
 * on the records of best[] (the ranking's order with or without the full ties, as the keys are
 * sorted by cost, then in vertex order). */
static int ranks_before(const engine *e, rank_key a, rank_key b)
{
    if (a.cost_bits != b.cost_bits)
        return a.cost_bits < b.cost_bits;
    return compare_candidates(&e->best[a.vertex], &e->best[b.vertex]) < 0;
}

/* The candidates waiting in this pass (deferred, or moved when checked): a binary heap in ranking
 * order over spare_keys[0 .. waiting), free once the ranking is sorted (a vertex is one
 * candidate: in the ranking still to come, in the chunk, or here). */
static void wait_push(engine *e, rank_key key)
{
    rank_key *heap = e->spare_keys;
    size_t i = e->waiting++;
    while (i > 0 && ranks_before(e, key, heap[(i - 1) / 2])) {
        heap[i] = heap[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    heap[i] = key;
}

static rank_key wait_pop(engine *e)
{
    rank_key *heap = e->spare_keys, top = heap[0], last = heap[--e->waiting];
    size_t i = 0, n = e->waiting;
    for (;;) {
        size_t child = 2 * i + 1;
        if (child >= n)
            break;
        if (child + 1 < n && ranks_before(e, heap[child + 1], heap[child]))
            child++;
        if (!ranks_before(e, heap[child], last))
            break;
        heap[i] = heap[child];
        i = child;
    }
    heap[i] = last;
    return top;
}

/* Takes the ranked candidates keys[0 .. count) in order, greedily, in chunks of CHUNK
 * candidates whose judging and taking run on the pool's threads. A chunk's candidates are judged
 * side by side on the mesh as the chunk found it (judge). Then, in order, each is accepted as
 * judged, unless an earlier one accepted in the chunk wrote a vertex its verdict read: that one
 * waits, to be judged again in the next chunk (the chunks take the ranking and the waiting
 * candidates, which include those that moved when checked, in ranking order). The pass stops at
 * the first candidate costing more than cost_limit once it has taken a collapse; where nothing
 * under the limit could be taken, every candidate is checked against the rules first and the
 * pass goes on to the first it can take (a guard: the pass's first candidate is checked, costs
 * no more than the limit and, nothing being taken yet, is legal as checked). The accepted ones
 * write disjoint triangles and vertices (apply_collapse: v0's triangles, v0's ring's flags, v1's
 * quadric) and are taken side by side, while the acceptance goes on: the pool's threads take
 * them as they are listed (pool_open, pool_publish), a block at a time. The acceptance reads the
 * mesh only to gather a long ring (mark_writes), and that of a v0 no accepted collapse wrote: one
 * that moves a triangle at v0 marks v0, and the candidate waits. Every collapse taken is legal on
 * the mesh it is applied to, and which ones are taken depends only on the ranking and the
 * chunks, never on the threads: the same bytes on any number of them. Against the strict order,
 * a deferred candidate may come after costlier ones of its chunk (a relaxed order, as a relaxed
 * priority queue's). Returns the collapses taken. */
static uint32_t take_in_chunks(engine *e, const rank_key *keys, size_t count, float cost_limit,
                               scratch *s)
{
    uint32_t taken = 0;
    rank_key *items = e->chunk;
    size_t next = 0;
    int stop = 0;
    while (!stop && (next < count || e->waiting) && e->alive > e->o->target_vertices) {
        uint32_t n = 0;
        for (;;) {
            while (next < count && key_moved(e, keys[next]))
                next++;
            if (n == CHUNK || (next == count && !e->waiting))
                break;
            items[n++] = next < count && (!e->waiting || ranks_before(e, keys[next],
                                                                      e->spare_keys[0]))
                             ? keys[next++]
                             : wait_pop(e);
        }
        e->chunk_size = n;
        run_on_pool(e, STEP_JUDGE, n, JUDGE_BLOCK);
        uint32_t accepted = 0;
        for (uint32_t i = 0; i < n; i++) {
            const judgement *j = &e->judgements[i];
            prefetch_acceptance(e, i);
            if (key_cost(&items[i]) > cost_limit && taken > 0) {
                stop = 1;
                break;
            }
            if (key_cost(&items[i]) > cost_limit && e->check_up_to < INFINITY) {
                /* nothing under the limit could be taken: the rest checked, then judged again */
                check_candidates_up_to(e, INFINITY);
                for (uint32_t k = i; k < n; k++)
                    if (!key_moved(e, items[k]))
                        wait_push(e, items[k]);
                break;
            }
            if (written(e, j->v0) || written(e, j->v1) || written(e, j->vl) ||
                written(e, j->vr)) {
                wait_push(e, items[i]);
                continue;
            }
            if (j->verdict != VERDICT_LEGAL)
                continue;
            mark_writes(e, j, s);
            e->accepted[accepted++] = i;
            if (accepted == 1)
                pool_open(e, STEP_APPLY, 1, APPLY_BLOCK, 1);
            else if (accepted % APPLY_BLOCK == 0)
                pool_publish(e, accepted);
            e->alive = e->alive > j->removes ? e->alive - j->removes : 0;
            taken++;
            if (e->alive <= e->o->target_vertices) {
                stop = 1;
                break;
            }
        }
        if (accepted)
            pool_close(e, accepted);
        next_chunk_mark(e);
    }
    return taken;
}

#ifdef COLLAPSE_SCORE_RULES_FIXED
/* A test's copy of the engine (tests/test_collapse_checking.c): its scoring applies the rules up
 * to this cost in every pass. */
static float collapse_score_rules_fixed;
#endif

/* Up to which cost the scoring applies the rules: `predicted`, or a test's fixed bound. The
 * meshes do not depend on it, only the time. */
static float score_rules_bound(float predicted)
{
#ifdef COLLAPSE_SCORE_RULES_FIXED
    (void)predicted;
    return collapse_score_rules_fixed;
#else
    return predicted;
#endif
}

/* The cost methods: up to which cost the next pass's scoring applies the rules (where a vertex's
 * neighbourhood is at hand, as it is not when the ranking is checked), from this pass's cost
 * limit and the growth since the last pass's (2 to 8 x; 4 x after the first pass, whose scoring
 * applies none). Guessed too low, the ranking's check does the rest; too high, more vertices
 * are checked than the pass reaches. */
static void predict_limit(engine *e, float limit)
{
    float growth = 4.0f;
    if (e->last_limit > 0)
        growth = fminf(8.0f, fmaxf(2.0f, limit / e->last_limit));
    e->last_limit = limit;
    e->score_rules_up_to = score_rules_bound(limit * growth);
}

/* ---- compaction ---- */

/* The mesh made compact between two passes: the live triangles moved to the front of the
 * triangle list and the vertices they use numbered anew from 0, both in the order they had, and
 * every record the engine keeps across passes moved with its vertex. Late passes otherwise read
 * a few live vertices per cache line, spread over the whole of the first pass's arrays: on the
 * dragon (make bench, twelve runs), `quadric` on one thread took 0.98-1.05 s without, 0.91-1.02 s
 * with.
 *
 * The order is kept, so every comparison of vertex or triangle numbers (the ties, the ranking,
 * the adjacency's order, and so the rings') comes out as before: the same collapses, byte for
 * byte. Each array is compacted in place, its records moving down only, one array per item of
 * the pool (compact_array). The caller's numbers are kept (vertex_of, triangle_of): the history
 * is written in them, and restore_caller_mesh writes the triangles back in them at the end. */
static void compact(engine *e)
{
    /* the vertices kept: those not removed that had triangles when the last pass started (a
     * vertex gains triangles only where it has some: every corner of a live triangle is kept) */
    uint32_t *number = (uint32_t *)e->keys; /* (free until the ranking: 2 (n + 1) words) */
    uint32_t kept = 0;
    for (uint32_t v = 0; v < e->n; v++)
        number[v] = e->ring_size[v] && !(e->flags[v] & FLAG_REMOVED) ? kept++ : COLLAPSE_NONE;
    e->compacting_first = !e->vertex_of;
    if (e->compacting_first) { /* arrays of its own for what the caller's mesh holds */
        const collapse_mesh *m = e->m;
        e->vertex_of = xmalloc(sizeof(uint32_t) * ((size_t)kept + 1));
        e->triangle_of = xmalloc(sizeof(uint32_t) * ((size_t)e->t + 1));
        e->positions = xmalloc(sizeof(float) * 3 * ((size_t)kept + 1));
        if (m->distance)
            e->distance = xmalloc(sizeof(uint32_t) * ((size_t)kept + 1));
        if (m->locked)
            e->locked = xmalloc((size_t)kept + 1);
    }
    run_on_pool(e, STEP_COMPACT, COMPACT_ARRAYS, 1);
    uint32_t live = e->compacted_triangles;
    e->compacted = *e->caller;
    e->compacted.vertex_count = kept;
    e->compacted.triangle_count = live;
    e->compacted.positions = e->positions;
    e->compacted.distance = e->distance;
    e->compacted.locked = e->locked;
    e->compacted.importance = NULL; /* (read by engine_init alone) */
    e->m = &e->compacted;
    e->n = kept;
    e->t = e->live_count = live;
    e->live_all = 1;
    e->flags[kept] = 0; /* (the records one past the last vertex) */
    e->ring_size[kept] = 0;
    e->marks[kept] = (vertex_marks){0, 0};
    e->importance[kept] = 0;
    if (e->wedge_id) {
        e->wedge_id[kept] = COLLAPSE_NONE;
        e->live_degree[kept] = 0;
    }
    e->removed_since_compacted = 0;
}

/* Moves `size` bytes from record `from` to record `to` (to <= from) of `array`. */
static void move_record(void *array, size_t size, uint32_t from, uint32_t to)
{
    if (from != to)
        memcpy((char *)array + size * to, (const char *)array + size * from, size);
}

/* compact's item `item`: one array (or a few small ones) compacted, by the new numbers of the
 * vertices (those of compact(), in the keys) or, for the triangles, in their order. Still in
 * the mesh as the last pass left it: e->m, e->n and e->t are the old ones. */
static void compact_array(engine *e, uint32_t item)
{
    const collapse_mesh *m = e->m;
    const uint32_t *number = (const uint32_t *)e->keys;
    int first = e->compacting_first;
    if (item == COMPACT_TRIANGLES) {
        uint32_t *triangles = m->triangles, *ids = m->corner_ids, j = 0;
        for (uint32_t i = 0; i < e->t; i++) {
            const uint32_t *c = &triangles[3 * (size_t)i];
            if (c[0] == COLLAPSE_NONE)
                continue;
            e->triangle_of[j] = first ? i : e->triangle_of[i];
            for (int k = 0; k < 3; k++)
                triangles[3 * (size_t)j + k] = number[c[k]];
            if (ids && j != i)
                memcpy(&ids[3 * (size_t)j], &ids[3 * (size_t)i], 3 * sizeof(uint32_t));
            j++;
        }
        e->compacted_triangles = j;
        return;
    }
    for (uint32_t v = 0; v < e->n; v++) {
        uint32_t w = number[v];
        if (w == COLLAPSE_NONE)
            continue;
        switch (item) {
        case COMPACT_QUADRICS:
            if (e->quadric) {
                move_record(e->quadric, 10 * sizeof *e->quadric, v, w);
                move_record(e->self_error, sizeof *e->self_error, v, w);
            }
            break;
        case COMPACT_SCORES: {
            /* (read before the scoring writes them only where the vertex is not stale, and then
             * naming a live target) */
            move_record(e->best, sizeof *e->best, v, w);
            e->best[w].vertex = w;
            uint32_t target = e->best_target[v];
            e->best_target[w] = target == COLLAPSE_NONE ? COLLAPSE_NONE : number[target];
            break;
        }
        case COMPACT_CALLERS:
            e->vertex_of[w] = first ? v : e->vertex_of[v];
            memmove(&e->positions[3 * (size_t)w], position(e, v), 3 * sizeof(float));
            if (m->distance)
                e->distance[w] = m->distance[v];
            if (m->locked)
                e->locked[w] = m->locked[v];
            break;
        default: /* COMPACT_VERTICES */
            move_record(e->flags, sizeof *e->flags, v, w);
            move_record(e->marks, sizeof *e->marks, v, w);
            move_record(e->importance, sizeof *e->importance, v, w);
            /* (a donor is read only where the vertex was taken in the pass, whose flag the
             * scoring clears) */
            e->donor[w] = COLLAPSE_NONE;
            break;
        }
    }
}

/* Whether the next pass starts on a compacted mesh: once the collapses taken leave fewer than
 * half of the vertices the engine numbers. */
static int compaction_due(const engine *e)
{
    return SHORTCUTS && 2 * (uint64_t)e->removed_since_compacted > e->n;
}

/* The caller's triangles and corner ids after compaction, in its numbers: each compacted
 * triangle back in its own place (triangle_of), the others removed. Written from the last down,
 * as each goes to a place at or after its own. (A removed triangle's corner ids are left as
 * they fall.) */
static void restore_caller_mesh(engine *e)
{
    if (!e->triangle_of)
        return;
    uint32_t *triangles = e->caller->triangles, *ids = e->caller->corner_ids;
    uint32_t end = e->caller->triangle_count; /* the places above are done */
    for (uint32_t j = e->t; j-- > 0;) {
        uint32_t i = e->triangle_of[j];
        for (size_t k = 3 * (size_t)i + 3; k < 3 * (size_t)end; k++)
            triangles[k] = COLLAPSE_NONE;
        for (int k = 0; k < 3; k++) {
            uint32_t v = triangles[3 * (size_t)j + k];
            triangles[3 * (size_t)i + k] = v == COLLAPSE_NONE ? COLLAPSE_NONE : e->vertex_of[v];
        }
        if (ids && i != j)
            memcpy(&ids[3 * (size_t)i], &ids[3 * (size_t)j], 3 * sizeof(uint32_t));
        end = i;
    }
    for (size_t k = 0; k < 3 * (size_t)end; k++)
        triangles[k] = COLLAPSE_NONE;
}

/* One pass; returns the collapses it took. Every vertex whose neighbourhood changed is scored
 * (score_vertex), the candidates ranked, checked against the rules as far as the pass may
 * reach (check_ranking) and taken greedily, the pass stopping at PASS_COST_FACTOR x the cost of
 * the candidate a quarter down the ranking. */
static uint32_t run_pass(engine *e, scratch *s)
{
    if (!e->rings_current) { /* the first pass has those engine_init built */
        if (compaction_due(e))
            compact(e);
        build_adjacency(e);
        for_each_vertex(e, STEP_RINGS);
    }
    e->rings_current = 0;
    for_each_vertex(e, STEP_SCORES);
    rank_candidates(e, e->o->method == DECIMATE_IMPORTANCE || e->m->distance);
    if (!e->ranked)
        return 0;
    e->waiting = 0;
    float cost_limit = check_ranking(e);
    predict_limit(e, cost_limit);
    return take_in_chunks(e, e->keys, e->ranked, cost_limit, s);
}

/* ---- setup ---- */

static void engine_free(engine *e)
{
    if (e->pool) {
        pool_stop(e->pool);
        free(e->pool);
    }
    free(e->flags);
    free(e->adjacency_start);
    free(e->adjacency);
    free(e->live);
    free(e->open_at);
    free(e->rings);
    free(e->ring_size);
    free(e->wedge_id);
    free(e->live_degree);
    free(e->quadric);
    free(e->self_error);
    free(e->importance);
    free(e->donor);
    free(e->best_target);
    free(e->best);
    free(e->attribute_terms);
    free(e->own_attribute_error);
    free(e->keys);
    free(e->digit_counts);
    free(e->moved_costs);
    free(e->moved_from);
    free(e->sort_spare);
    free(e->spare_keys);
    free(e->judgements);
    free(e->chunk);
    free(e->accepted);
    free(e->marks);
    free(e->due);
    free(e->vertex_of);
    free(e->triangle_of);
    free(e->positions);
    free(e->distance);
    free(e->locked);
    memset(e, 0, sizeof *e);
}

/* Whether an attribute id is used by two vertices (an error set: each vertex's ids are its own,
 * collapse.h). */
static int attribute_ids_shared(const collapse_mesh *m)
{
    uint32_t *owner = xmalloc(sizeof(uint32_t) * ((size_t)m->attribute_count + 1));
    for (uint32_t id = 0; id < m->attribute_count; id++)
        owner[id] = COLLAPSE_NONE;
    int shared = 0;
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count && !shared; i++) {
        uint32_t v = m->triangles[i], id = m->corner_ids[i];
        if (v == COLLAPSE_NONE)
            continue;
        if (owner[id] == COLLAPSE_NONE)
            owner[id] = v;
        if (owner[id] != v)
            shared = error_set(IDMR_EXIT_FAILURE,
                               "collapse: attribute id %u is used by vertices %u and %u (each "
                               "vertex needs ids of its own)",
                               id, owner[id], v) != 0;
    }
    free(owner);
    return shared;
}

static int engine_init(engine *e, collapse_mesh *m, const collapse_options *o)
{
    memset(e, 0, sizeof *e);
    if (o->method != DECIMATE_QUADRIC && !m->importance && m->vertex_count)
        return error_set(IDMR_EXIT_FAILURE, "collapse: the %s method needs importance",
                         o->method == DECIMATE_IMPORTANCE ? "importance" : "combined");
    if (m->corner_ids && (m->uv_floats + m->normal_floats <= 0 ||
                          m->uv_floats + m->normal_floats > MAX_CHANNELS || !m->attributes))
        return error_set(IDMR_EXIT_FAILURE, "collapse: corner ids without an attribute table");
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = &m->triangles[3 * t];
        for (size_t i = 3 * t; i < 3 * t + 3; i++)
            if (m->triangles[i] != COLLAPSE_NONE &&
                (m->triangles[i] >= m->vertex_count ||
                 (m->corner_ids && m->corner_ids[i] >= m->attribute_count)))
                return error_set(IDMR_EXIT_FAILURE,
                                 "collapse: triangle %zu names vertex %u or attribute id %u, out "
                                 "of range",
                                 t, m->triangles[i], m->corner_ids ? m->corner_ids[i] : 0);
        /* (the weld drops such triangles; the rings and the edges' sides assume none) */
        if (c[0] != COLLAPSE_NONE && (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]))
            return error_set(IDMR_EXIT_FAILURE, "collapse: triangle %zu names a vertex twice", t);
    }
    if (m->corner_ids && attribute_ids_shared(m))
        return -1;
    e->m = e->caller = m;
    e->o = o;
    e->n = m->vertex_count;
    e->t = m->triangle_count;
    e->min_cos = cos((o->max_normal_angle > 0 ? o->max_normal_angle : 60.0) * M_PI / 180.0);
    e->boundary_tolerance =
        o->boundary_tolerance > 0 ? o->boundary_tolerance : DECIMATE_BOUNDARY_TOLERANCE;
    size_t n = (size_t)e->n + 1;
    e->flags = xmalloc(n * sizeof(vertex_flags));
    e->adjacency_start = xmalloc(sizeof(uint32_t) * (n + 1));
    e->adjacency = large_array(e, sizeof(uint32_t) * (3 * (size_t)e->t + 1));
    e->live = xmalloc(sizeof(uint32_t) * ((size_t)e->t + 1));
    e->live_count = e->t;
    e->live_all = 1;
    size_t ring_slots = 3 * (size_t)e->t + n;
    e->rings = large_array(e, sizeof(ring_entry) * ring_slots);
    e->ring_size = xmalloc(sizeof(uint32_t) * n);
    if (m->corner_ids) {
        e->wedge_id = xmalloc(sizeof(uint32_t) * n);
        e->wedge_id[e->n] = COLLAPSE_NONE;
        e->live_degree = xmalloc(sizeof(uint32_t) * n);
        e->live_degree[e->n] = 0;
    }
    e->donor = xmalloc(sizeof(uint32_t) * n);
    e->marks = xmalloc(sizeof(vertex_marks) * n);
    e->due = xcalloc(n / 64 + 2, sizeof(uint64_t));
    e->chunk_mark = 1;
    e->best_target = xmalloc(sizeof(uint32_t) * n);
    e->best = large_array(e, sizeof(candidate) * n);
    e->importance = xmalloc(sizeof(double) * n);
    e->keys = xmalloc(sizeof(rank_key) * n); /* (build_adjacency's counters till the ranking) */
    e->spare_keys = xmalloc(sizeof(rank_key) * n);
    if (o->method != DECIMATE_IMPORTANCE) {
        e->quadric = large_array(e, sizeof(double) * 10 * n); /* (zeroed by sum_quadrics) */
        e->self_error = xmalloc(sizeof(double) * n);
    }
    e->flags[e->n] = 0; /* (the records one past the last vertex) */
    e->ring_size[e->n] = 0;
    e->marks[e->n] = (vertex_marks){0, 0};
    e->importance[e->n] = 0;
    e->pool = xmalloc(sizeof *e->pool);
    pool_start(e->pool, e, o->threads ? o->threads : 1);
    e->threads = e->pool->count + 1;
    uint32_t rows = e->threads < RADIX_PARTS ? e->threads : RADIX_PARTS;
    e->digit_counts = xmalloc(sizeof(uint32_t) * RADIX_BUCKETS * (rows > 1 ? rows : 2));
    run_on_pool(e, STEP_START_VERTICES, e->threads, 1);
    if (e->threads > 1) {
        size_t pages = 0;
        for (size_t a = 0; a < e->fresh_count; a++)
            pages += e->fresh[a].pages;
        run_on_pool(e, STEP_FIRST_TOUCH, (uint32_t)pages, 1);
    }
    if (e->quadric && o->method == DECIMATE_COMBINED)
        e->importance_floor = importance_floor(e); /* before the adjacency: on its ring records */
    build_adjacency(e);
    if (e->quadric && o->method == DECIMATE_COMBINED) {
        start_attribute_quadrics(e);
        e->open_at = xmalloc(n);
    }
    for_each_vertex(e, STEP_FIRST_RINGS);
    for (unsigned int i = 0; i <= e->pool->count; i++) {
        e->not_one_fan += e->pool->scratch[i].not_one_fan;
        e->alive += e->pool->scratch[i].wedges;
    }
    if (e->not_one_fan)
        return 0; /* (collapse_run stops there: the caller rebuilds the mesh) */
    if (e->quadric)
        run_on_pool(e, STEP_QUADRICS, e->threads, 1); /* (the open edges read the rings) */
    free(e->open_at);
    e->open_at = NULL;
    e->rings_current = 1;
    return 0;
}

size_t collapse_memory(uint32_t vertex_count, uint32_t triangle_count, decimate_method method)
{
    /* flags, the acceptance's marks, adjacency_start, ring_size, donor, best_target, best,
     * importance, the ranking's keys (and their spare), at most the lists of candidates that
     * moved when checked (check_ranking: the threads' keys, their new and old costs, and the
     * room to sort the costs), the quadric and its own error; a ring slot (its ring_entry); the
     * due bits (check_candidates_up_to); per triangle its place in the live list; and the
     * ranking's radix sort's counts, at most RADIX_PARTS rows (2 MiB, on any number of threads) */
    size_t per_vertex = sizeof(vertex_flags) + sizeof(vertex_marks) + 4 + 4 + 4 + 4 +
                        sizeof(candidate) + sizeof(double) + 3 * sizeof(rank_key) +
                        3 * sizeof(uint32_t) +
                        (method != DECIMATE_IMPORTANCE ? 11 * sizeof(double) : 0);
    size_t ring_slot = sizeof(ring_entry);
    /* per corner: the adjacency and a ring slot */
    size_t per_corner = sizeof(uint32_t) + ring_slot;
    size_t due_bits = ((size_t)vertex_count / 64 + 2) * sizeof(uint64_t);
    size_t digit_counts = sizeof(uint32_t) * RADIX_BUCKETS * RADIX_PARTS;
    /* the compacted mesh (compact): for each vertex it keeps, fewer than half of them, the
     * caller's number, the position, the distance and the lock; per triangle the caller's
     * number */
    size_t compacted = (sizeof(uint32_t) + 3 * sizeof(float) + sizeof(uint32_t) + 1) *
                           ((size_t)vertex_count / 2 + 1) +
                       sizeof(uint32_t) * ((size_t)triangle_count + 1);
    return (per_vertex + ring_slot) * ((size_t)vertex_count + 1) + due_bits + digit_counts +
           compacted + (3 * per_corner + sizeof(uint32_t)) * (size_t)triangle_count;
}

int collapse_run(collapse_mesh *m, const collapse_options *o, collapse_result *result)
{
    engine e;
    if (engine_init(&e, m, o))
        return -1;
    for (uint32_t v = 0; v < e.n; v++)
        result->collapsed_into[v] = v;
    result->vertices_before = result->vertices_after = e.alive;
    result->collapses = 0;
    result->passes = 0;
    result->non_manifold_vertices = e.not_one_fan;
    if (e.not_one_fan) {
        engine_free(&e);
        return 0;
    }
    e.history = result->collapsed_into;
    e.score_rules_up_to = score_rules_bound(0); /* the first pass checks its ranking alone */
    e.judgements = xmalloc(sizeof(judgement) * CHUNK);
    e.chunk = xmalloc(sizeof(rank_key) * CHUNK);
    e.accepted = xmalloc(sizeof(uint32_t) * CHUNK);
    scratch s;
    memset(&s, 0, sizeof s);
    while (e.alive > o->target_vertices) {
        uint32_t taken = run_pass(&e, &s);
        if (!taken)
            break;
        result->collapses += taken;
        result->passes++;
        e.removed_since_compacted += taken;
    }
    restore_caller_mesh(&e);
    result->vertices_after = e.alive;
    scratch_free(&s);
    engine_free(&e);
    return 0;
}

int collapse_evaluate(const collapse_mesh *mesh, const collapse_options *options, uint32_t v0,
                      uint32_t v1, double *cost, const char **rule)
{
    collapse_mesh copy = *mesh;
    size_t corners_size = sizeof(uint32_t) * 3 * (size_t)mesh->triangle_count;
    copy.triangles = xmalloc(corners_size + 1);
    memcpy(copy.triangles, mesh->triangles, corners_size);
    if (mesh->corner_ids) {
        copy.corner_ids = xmalloc(corners_size + 1);
        memcpy(copy.corner_ids, mesh->corner_ids, corners_size);
    }
    engine e;
    int status = -1;
    if (engine_init(&e, &copy, options))
        goto free_copy;
    status = 0;
    *rule = NULL;
    if (v0 >= e.n || v1 >= e.n) {
        status = error_set(IDMR_EXIT_FAILURE, "collapse_evaluate: vertex out of range");
        goto free_engine;
    }
    scratch s;
    memset(&s, 0, sizeof s);
    ring r0 = ring_of(&e, v0);
    fan f0 = pass_fan(&e, v0);
    int boundary0;
    if (e.flags[v0] & FLAG_LOCKED)
        *rule = "locked";
    else if (!ring_simple(&r0, &boundary0))
        *rule = "complex vertex";
    else if (r0.size <= 2)
        *rule = "two neighbours";
    else if (collapse_legal(&e, v0, v1, f0, &r0, boundary0, 0, &s, rule)) {
        status = 1;
        if (options->method == DECIMATE_IMPORTANCE) {
            *cost = e.importance[v0];
            for (uint32_t k = 0; k < r0.size; k++)
                *cost += e.importance[r0.entry[k].vertex];
        } else {
            edge_sides sides = sides_of(&e, f0, v0, v1);
            *cost = collapse_cost(&e, v0, v1, &sides, e.m->corner_ids ? ids_of(&e, f0, v0, &s) : 0,
                                  COLLAPSE_NONE, &s);
        }
    }
    scratch_free(&s);
free_engine:
    engine_free(&e);
free_copy:
    free(copy.triangles);
    free(copy.corner_ids);
    return status;
}
