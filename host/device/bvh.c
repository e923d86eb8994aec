/* bvh.c — rtcBuildBVH callbacks, spatial splits of triangles, and flattening (see bvh.h).
 *
 * Embree calls the callbacks from its worker threads and builds a pointer tree in its own
 * thread-local memory: inner nodes (build_node) with up to four children and their boxes, and
 * leaves (build_leaf) listing primitive ids. bvh_build_meshes() gathers the non-degenerate
 * triangles as build primitives (build_input), runs the build (build_tree), then walks that
 * tree depth-first and writes the flat arrays: nodes in depth-first order, each leaf as one
 * triangle packet. bvh_build_boxes() runs the same steps on plain boxes, each leaf one box
 * whose reference is written into its parent's slot (no packet). */
#include "device/bvh.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/error.h"
#include "core/progress.h"
#include "device/instance_bvh.h"

enum { BUILD_NODE, BUILD_LEAF };

typedef struct build_node {
    int type;
    unsigned int child_count;
    void *children[IDMR_BVH_WIDTH];
    struct RTCBounds bounds[IDMR_BVH_WIDTH];
} build_node;

typedef struct build_leaf {
    int type;
    unsigned int count;
    unsigned int primitives[]; /* primIDs: indices into the builder's triangle list, or boxes */
} build_leaf;

typedef struct builder builder;

struct builder {
    const float (*vertices)[3][3]; /* per build primitive: its three vertices; NULL: boxes */
    const uint32_t *scene_triangle;  /* per build primitive: its leaf-lane triangle index */
    /* The reference a parent's slot gets for a leaf: a triangle packet (append_leaf), or the
     * box itself (box_leaf). */
    int (*leaf_reference)(builder *b, const build_leaf *leaf);
    int overfull_leaf; /* box_leaf met a leaf of more than one box */
    idmr_bvh_node *nodes;
    size_t node_count, node_capacity;
    idmr_triangle4 *leaves;
    size_t leaf_count, leaf_capacity;
    size_t reference_count;
    int depth;
};

/* ---- Embree device ---- */

static RTCDevice embree_device;
static pthread_once_t embree_once = PTHREAD_ONCE_INIT;

static void embree_error(void *user, enum RTCError code, const char *message)
{
    error_set(IDMR_EXIT_FAILURE, "Embree error %d: %s", (int)code, message ? message : "");
}

static void embree_create(void)
{
    embree_device = rtcNewDevice(NULL);
    if (embree_device)
        rtcSetDeviceErrorFunction(embree_device, embree_error, NULL);
}

struct RTCDeviceTy *bvh_embree_device(void)
{
    pthread_once(&embree_once, embree_create);
    return embree_device;
}

/* ---- rtcBuildBVH callbacks ---- */

static void *create_node(RTCThreadLocalAllocator alloc, unsigned int child_count, void *user)
{
    build_node *node = rtcThreadLocalAlloc(alloc, sizeof *node, 16);
    memset(node, 0, sizeof *node);
    node->type = BUILD_NODE;
    node->child_count = child_count;
    return node;
}

static void set_children(void *node_ptr, void **children, unsigned int count, void *user)
{
    build_node *node = node_ptr;
    for (unsigned int i = 0; i < count; i++)
        node->children[i] = children[i];
}

static void set_bounds(void *node_ptr, const struct RTCBounds **bounds, unsigned int count,
                       void *user)
{
    build_node *node = node_ptr;
    for (unsigned int i = 0; i < count; i++)
        node->bounds[i] = *bounds[i];
}

static void *create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *prims,
                         size_t count, void *user)
{
    build_leaf *leaf = rtcThreadLocalAlloc(alloc, sizeof *leaf + count * sizeof(unsigned int), 16);
    leaf->type = BUILD_LEAF;
    leaf->count = (unsigned int)count;
    for (size_t i = 0; i < count; i++)
        leaf->primitives[i] = prims[i].primID;
    return leaf;
}

static void bounds_extend(float lo[3], float hi[3], const float p[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = fminf(lo[k], p[k]);
        hi[k] = fmaxf(hi[k], p[k]);
    }
}

/* Splits a (possibly already clipped) triangle reference at plane `axis` = `position`: each
 * side's box is the box of the triangle's part on that side (its vertices there plus the edge
 * crossings), clipped to the reference's current box. */
static void split_primitive(const struct RTCBuildPrimitive *prim, unsigned int axis,
                            float position, struct RTCBounds *left, struct RTCBounds *right,
                            void *user)
{
    const builder *b = user;
    const float(*v)[3] = b->vertices[prim->primID];
    float left_lo[3] = {INFINITY, INFINITY, INFINITY}, left_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float right_lo[3] = {INFINITY, INFINITY, INFINITY}, right_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 3; i++) {
        const float *p = v[i], *q = v[(i + 1) % 3];
        if (p[axis] <= position)
            bounds_extend(left_lo, left_hi, p);
        if (p[axis] >= position)
            bounds_extend(right_lo, right_hi, p);
        if ((p[axis] < position && q[axis] > position) || (p[axis] > position && q[axis] < position)) {
            float t = (position - p[axis]) / (q[axis] - p[axis]);
            float crossing[3];
            for (int k = 0; k < 3; k++)
                crossing[k] = p[k] + t * (q[k] - p[k]);
            crossing[axis] = position;
            bounds_extend(left_lo, left_hi, crossing);
            bounds_extend(right_lo, right_hi, crossing);
        }
    }
    const float prim_lo[3] = {prim->lower_x, prim->lower_y, prim->lower_z};
    const float prim_hi[3] = {prim->upper_x, prim->upper_y, prim->upper_z};
    float *out[4][3] = {{&left->lower_x, &left->lower_y, &left->lower_z},
                        {&left->upper_x, &left->upper_y, &left->upper_z},
                        {&right->lower_x, &right->lower_y, &right->lower_z},
                        {&right->upper_x, &right->upper_y, &right->upper_z}};
    for (int k = 0; k < 3; k++) {
        *out[0][k] = fmaxf(left_lo[k], prim_lo[k]);
        *out[1][k] = fminf(left_hi[k], prim_hi[k]);
        *out[2][k] = fmaxf(right_lo[k], prim_lo[k]);
        *out[3][k] = fminf(right_hi[k], prim_hi[k]);
    }
    *out[1][axis] = fminf(*out[1][axis], position);
    *out[2][axis] = fmaxf(*out[2][axis], position);
}

/* ---- flattening ---- */

static void set_empty_slot(idmr_bvh_node *node, int slot)
{
    node->min_x[slot] = node->min_y[slot] = node->min_z[slot] = INFINITY;
    node->max_x[slot] = node->max_y[slot] = node->max_z[slot] = -INFINITY;
    node->child[slot] = IDMR_BVH_EMPTY;
}

static size_t append_node(builder *b)
{
    if (b->node_count == b->node_capacity) {
        b->node_capacity = b->node_capacity ? 2 * b->node_capacity : 1024;
        b->nodes = xrealloc(b->nodes, b->node_capacity * sizeof *b->nodes);
    }
    idmr_bvh_node *node = &b->nodes[b->node_count];
    memset(node, 0, sizeof *node); /* reserved words too: the upload is deterministic */
    for (int slot = 0; slot < IDMR_BVH_WIDTH; slot++)
        set_empty_slot(node, slot);
    return b->node_count++;
}

/* Appends the packet of a leaf's triangles; returns the leaf's reference. */
static int append_leaf(builder *b, const build_leaf *leaf)
{
    if (b->leaf_count == b->leaf_capacity) {
        b->leaf_capacity = b->leaf_capacity ? 2 * b->leaf_capacity : 1024;
        b->leaves = xrealloc(b->leaves, b->leaf_capacity * sizeof *b->leaves);
    }
    idmr_triangle4 *packet = &b->leaves[b->leaf_count];
    memset(packet, 0, sizeof *packet);
    for (int lane = 0; lane < 4; lane++)
        packet->triangle[lane] = IDMR_BVH_NO_TRIANGLE;
    for (unsigned int lane = 0; lane < leaf->count; lane++) {
        unsigned int prim = leaf->primitives[lane];
        for (int axis = 0; axis < 3; axis++) {
            packet->v0[4 * axis + lane] = b->vertices[prim][0][axis];
            packet->v1[4 * axis + lane] = b->vertices[prim][1][axis];
            packet->v2[4 * axis + lane] = b->vertices[prim][2][axis];
        }
        packet->triangle[lane] = b->scene_triangle[prim];
    }
    b->reference_count += leaf->count;
    return ~(int)b->leaf_count++;
}

/* A leaf of bvh_build_boxes() is its one box: ~box index. */
static int box_leaf(builder *b, const build_leaf *leaf)
{
    b->overfull_leaf |= leaf->count != 1;
    b->reference_count += leaf->count;
    return ~(int)leaf->primitives[0];
}

static void set_slot_bounds(idmr_bvh_node *node, int slot, const struct RTCBounds *box)
{
    node->min_x[slot] = box->lower_x;
    node->min_y[slot] = box->lower_y;
    node->min_z[slot] = box->lower_z;
    node->max_x[slot] = box->upper_x;
    node->max_y[slot] = box->upper_y;
    node->max_z[slot] = box->upper_z;
}

/* Writes build node `src` as flat node `index`, depth-first (children follow their parent). */
static void flatten(builder *b, const build_node *src, size_t index, int depth)
{
    if (depth > b->depth)
        b->depth = depth;
    for (unsigned int slot = 0; slot < src->child_count; slot++) {
        const int *type = src->children[slot];
        if (*type == BUILD_LEAF) {
            int ref = b->leaf_reference(b, src->children[slot]);
            b->nodes[index].child[slot] = ref;
            set_slot_bounds(&b->nodes[index], (int)slot, &src->bounds[slot]);
        } else {
            size_t child = append_node(b); /* may move b->nodes: index, not pointers */
            b->nodes[index].child[slot] = (int)child;
            set_slot_bounds(&b->nodes[index], (int)slot, &src->bounds[slot]);
            flatten(b, src->children[slot], child, depth + 1);
        }
    }
}

/* ---- the build ---- */

/* The build primitives: one per non-degenerate triangle, with room for the references that
 * spatial splits add; vertices[] and scene_triangle[] are indexed by primID. Or one per
 * non-empty box (bvh_build_boxes), primID the box index, no vertices. */
typedef struct build_input {
    float (*vertices)[3][3];
    uint32_t *scene_triangle;
    struct RTCBuildPrimitive *prims;
    size_t count, capacity;
} build_input;

/* The box of one triangle as a build primitive. */
static void set_primitive(struct RTCBuildPrimitive *p, const float v[3][3], unsigned int id)
{
    p->lower_x = fminf(fminf(v[0][0], v[1][0]), v[2][0]);
    p->lower_y = fminf(fminf(v[0][1], v[1][1]), v[2][1]);
    p->lower_z = fminf(fminf(v[0][2], v[1][2]), v[2][2]);
    p->upper_x = fmaxf(fmaxf(v[0][0], v[1][0]), v[2][0]);
    p->upper_y = fmaxf(fmaxf(v[0][1], v[1][1]), v[2][1]);
    p->upper_z = fmaxf(fmaxf(v[0][2], v[1][2]), v[2][2]);
    p->geomID = 0;
    p->primID = id;
}

/* True when the triangle has no area (core/scene.h, triangle_area). */
static int triangle_is_degenerate(const float v[3][3])
{
    return triangle_area(v[0], v[1], v[2]) == 0.0;
}

/* Room for `capacity` build primitives, aligned as Embree wants them. */
static struct RTCBuildPrimitive *allocate_primitives(size_t capacity)
{
    struct RTCBuildPrimitive *prims = aligned_alloc(32, capacity * sizeof *prims);
    if (!prims) {
        fprintf(stderr, "idmr: out of memory (BVH build primitives)\n");
        exit(IDMR_EXIT_FAILURE);
    }
    return prims;
}

/* Gathers the non-degenerate triangles of the meshes; counts the others in *degenerate. */
static void gather_primitives(const bvh_mesh *meshes, size_t mesh_count, build_input *in,
                              size_t *degenerate)
{
    size_t triangle_count = 0;
    for (size_t m = 0; m < mesh_count; m++)
        triangle_count += meshes[m].triangle_count;
    in->capacity = 2 * triangle_count + 16; /* room for spatial-split references */
    in->vertices = xmalloc(triangle_count * sizeof *in->vertices + 1);
    in->scene_triangle = xmalloc(triangle_count * sizeof *in->scene_triangle + 1);
    in->prims = allocate_primitives(in->capacity);
    in->count = 0;
    for (size_t m = 0; m < mesh_count; m++) {
        const bvh_mesh *mesh = &meshes[m];
        for (uint32_t t = 0; t < mesh->triangle_count; t++) {
            float(*v)[3] = in->vertices[in->count];
            for (int k = 0; k < 3; k++)
                memcpy(v[k], &mesh->positions[3 * (size_t)mesh->indices[3 * (size_t)t + k]],
                       sizeof v[k]);
            if (triangle_is_degenerate((const float(*)[3])v)) {
                (*degenerate)++;
                continue;
            }
            set_primitive(&in->prims[in->count], (const float(*)[3])v, (unsigned int)in->count);
            in->scene_triangle[in->count] = mesh->first_triangle + t;
            in->count++;
        }
    }
}

/* Gathers the non-empty boxes; counts the empty ones in *empty. */
static void gather_boxes(const bvh_box *boxes, size_t count, build_input *in, size_t *empty)
{
    memset(in, 0, sizeof *in);
    in->capacity = count + 1;
    in->prims = allocate_primitives(in->capacity);
    for (size_t i = 0; i < count; i++) {
        const bvh_box *box = &boxes[i];
        if (!(box->min[0] <= box->max[0] && box->min[1] <= box->max[1] &&
              box->min[2] <= box->max[2])) {
            (*empty)++;
            continue;
        }
        struct RTCBuildPrimitive *p = &in->prims[in->count++];
        p->lower_x = box->min[0];
        p->lower_y = box->min[1];
        p->lower_z = box->min[2];
        p->upper_x = box->max[0];
        p->upper_y = box->max[1];
        p->upper_z = box->max[2];
        p->geomID = 0;
        p->primID = (unsigned int)i;
    }
}

static void free_primitives(build_input *in)
{
    free(in->prims);
    free(in->vertices);
    free(in->scene_triangle);
}

/* rtcBuildBVH's arguments: our width and depth, and the callbacks that build into `b`. Triangles
 * (b->vertices set): high quality (spatial splits) and packets of up to four; boxes: binned SAH
 * (a box cannot be split) and one box per leaf. */
static struct RTCBuildArguments build_arguments(RTCBVH tree, build_input *in, builder *b)
{
    struct RTCBuildArguments args = rtcDefaultBuildArguments();
    int triangles = b->vertices != NULL;
    args.buildQuality = triangles ? RTC_BUILD_QUALITY_HIGH /* enables spatial splits */
                                  : RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = IDMR_BVH_WIDTH;
    args.maxDepth = IDMR_BVH_MAX_DEPTH;
    /* Leaves are tested as packets of four: the SAH counts triangles in blocks of four, and a
     * packet test costs about two box tests of a node (measured, make bench). */
    args.sahBlockSize = triangles ? IDMR_BVH_MAX_LEAF_SIZE : 1;
    args.minLeafSize = 1;
    args.maxLeafSize = triangles ? IDMR_BVH_MAX_LEAF_SIZE : 1;
    args.traversalCost = 1.0f;
    args.intersectionCost = 2.0f;
    args.bvh = tree;
    args.primitives = in->prims;
    args.primitiveCount = in->count;
    args.primitiveArrayCapacity = in->capacity;
    args.createNode = create_node;
    args.setNodeChildren = set_children;
    args.setNodeBounds = set_bounds;
    args.createLeaf = create_leaf;
    args.splitPrimitive = triangles ? split_primitive : NULL;
    args.userPtr = b;
    return args;
}

/* A tiny input whose root is one leaf: hang it under the root node, boxed by all primitives. */
static void hang_root_leaf(builder *b, size_t root, const build_leaf *leaf, const build_input *in)
{
    b->nodes[root].child[0] = b->leaf_reference(b, leaf);
    struct RTCBounds all = {INFINITY, INFINITY, INFINITY, 0, -INFINITY, -INFINITY, -INFINITY, 0};
    for (size_t i = 0; i < in->count; i++) {
        all.lower_x = fminf(all.lower_x, in->prims[i].lower_x);
        all.lower_y = fminf(all.lower_y, in->prims[i].lower_y);
        all.lower_z = fminf(all.lower_z, in->prims[i].lower_z);
        all.upper_x = fmaxf(all.upper_x, in->prims[i].upper_x);
        all.upper_y = fmaxf(all.upper_y, in->prims[i].upper_y);
        all.upper_z = fmaxf(all.upper_z, in->prims[i].upper_z);
    }
    set_slot_bounds(&b->nodes[root], 0, &all);
    b->depth = 1;
}

/* Builds the tree of the gathered primitives under flat node `root` (no primitives leave the
 * root's slots empty). Returns 0, or -1 with the error set. */
static int build_tree(RTCDevice device, build_input *in, builder *b, size_t root)
{
    if (in->count == 0) {
        b->depth = 1;
        return 0;
    }
    RTCBVH tree = rtcNewBVH(device);
    struct RTCBuildArguments args = build_arguments(tree, in, b);
    error_clear();
    void *top = rtcBuildBVH(&args);
    int status = 0;
    if (!top) {
        if (!*error_message())
            error_set(IDMR_EXIT_FAILURE, "rtcBuildBVH failed on %zu %s", in->count,
                      b->vertices ? "triangles" : "boxes");
        status = -1;
    } else if (*(const int *)top == BUILD_LEAF) {
        hang_root_leaf(b, root, top, in);
    } else {
        /* The build is done with the primitives (the leaves hold their ids): their 64 bytes per
         * triangle go before the flat arrays grow beside Embree's nodes. */
        free(in->prims);
        in->prims = NULL;
        flatten(b, top, root, 1);
    }
    rtcReleaseBVH(tree);
    return status;
}

/* What the kernels can address and traverse. */
static int check_limits(const builder *b)
{
    if (b->leaf_count > (size_t)INT32_MAX)
        return error_set(IDMR_EXIT_INPUT, "the BVH needs %zu leaves; the kernels address %d",
                         b->leaf_count, INT32_MAX);
    if (b->depth > IDMR_BVH_MAX_DEPTH)
        return error_set(IDMR_EXIT_FAILURE, "BVH depth %d exceeds the traversal stack's limit %d",
                         b->depth, IDMR_BVH_MAX_DEPTH);
    if (b->overfull_leaf)
        return error_set(IDMR_EXIT_FAILURE, "rtcBuildBVH made a leaf of several boxes (one asked)");
    return 0;
}

/* Builds the gathered primitives `in` (freed here) into out. Returns 0, or -1 with the error
 * set and nothing to free. */
static int build_flat(build_input *in, builder *b, bvh *out, double start)
{
    RTCDevice device = bvh_embree_device();
    int status = -1;
    if (!device)
        error_set(IDMR_EXIT_FAILURE, "rtcNewDevice failed: Embree could not start");
    else {
        size_t root = append_node(b);
        status = build_tree(device, in, b, root);
    }
    free_primitives(in);
    if (status == 0)
        status = check_limits(b);
    if (status != 0) {
        free(b->nodes);
        free(b->leaves);
        return -1;
    }
    out->nodes = b->nodes;
    out->node_count = b->node_count;
    out->leaves = b->leaves;
    out->leaf_count = b->leaf_count;
    out->reference_count = b->reference_count;
    out->depth = b->depth;
    out->build_seconds = monotonic_seconds() - start;
    return 0;
}

int bvh_build_meshes(const bvh_mesh *meshes, size_t mesh_count, bvh *out)
{
    memset(out, 0, sizeof *out);
    double start = monotonic_seconds();
    build_input in;
    gather_primitives(meshes, mesh_count, &in, &out->degenerate_count);
    builder b = {.vertices = (const float(*)[3][3])in.vertices,
                 .scene_triangle = in.scene_triangle,
                 .leaf_reference = append_leaf};
    return build_flat(&in, &b, out, start);
}

int bvh_build_boxes(const bvh_box *boxes, size_t count, bvh *out)
{
    memset(out, 0, sizeof *out);
    double start = monotonic_seconds();
    if (count > (size_t)INT32_MAX)
        return error_set(IDMR_EXIT_INPUT, "%zu boxes for a BVH; the kernels address %d", count,
                         INT32_MAX);
    build_input in;
    gather_boxes(boxes, count, &in, &out->degenerate_count);
    builder b = {.leaf_reference = box_leaf};
    return build_flat(&in, &b, out, start);
}

/* Mesh m's triangles as the builder's input, numbered scene-globally. */
static bvh_mesh scene_part(const scene *s, size_t m)
{
    const scene_mesh *mesh = &s->meshes[m];
    return (bvh_mesh){mesh->positions, mesh->indices, mesh->triangle_count, mesh->first_triangle};
}

/* Placement of mesh m (scene_instance_placement: the identity for any mesh but a later copy)
 * as the instance of prototype p. Returns 0, or -1 with the error set. */
static int scene_placement(const scene *s, size_t m, uint32_t p, instance_placement *out)
{
    double object_to_world[16];
    if (scene_instance_placement(s, m, object_to_world))
        return error_prefix("mesh '%s'", s->meshes[m].name);
    out->prototype = p;
    for (int k = 0; k < 12; k++)
        out->object_to_world[k] = (float)object_to_world[k];
    return 0;
}

size_t bvh_scene_instances(const scene *s, size_t *mesh_of_instance)
{
    if (!(s->features & IDMR_FEATURE_INSTANCES))
        return 0;
    size_t count = 0;
    for (size_t m = 0; m < s->mesh_count; m++)
        if (!s->meshes[m].instanced) {
            if (mesh_of_instance)
                mesh_of_instance[count] = BVH_NO_MESH;
            count++;
            break;
        }
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (!s->meshes[m].instanced || s->meshes[m].instance_first != m)
            continue;
        for (size_t copy = m;; copy = s->meshes[copy].instance_next) {
            if (mesh_of_instance)
                mesh_of_instance[count] = copy;
            count++;
            if (s->meshes[copy].instance_next == 0)
                break;
        }
    }
    return count;
}

/* The two-level BVH of a scene with later copies (bvh.h): prototype 0 the meshes that are not
 * instanced, placed by the identity (when there are any), then one prototype per representative,
 * placed by each copy of its chain (itself first), in bvh_scene_instances()' order. Returns 0,
 * or -1 with the error set. */
static int build_instanced(const scene *s, bvh *out)
{
    memset(out, 0, sizeof *out); /* nothing to free on failure, as bvh_build_meshes leaves it */
    bvh_mesh *parts = xmalloc(s->mesh_count * sizeof *parts + 1);
    instance_prototype *prototypes = xcalloc(s->mesh_count + 1, sizeof *prototypes);
    instance_placement *placements = xcalloc(s->mesh_count + 1, sizeof *placements);
    size_t *placed = xmalloc((s->mesh_count + 1) * sizeof *placed);
    size_t part_count = 0, prototype_count = 1;
    size_t placement_count = bvh_scene_instances(s, placed);
    for (size_t m = 0; m < s->mesh_count; m++)
        if (!s->meshes[m].instanced)
            parts[part_count++] = scene_part(s, m);
    prototypes[0] = (instance_prototype){.parts = parts, .part_count = part_count};
    int status = 0;
    uint32_t p = 0; /* the prototype of the chain being placed */
    for (size_t i = 0; i < placement_count && status == 0; i++) {
        size_t m = placed[i];
        if (m == BVH_NO_MESH) { /* prototype 0, by the identity (mesh 0 is never a later copy) */
            status = scene_placement(s, 0, 0, &placements[i]);
            continue;
        }
        if (s->meshes[m].instance_first == m) { /* a representative: its prototype */
            p = (uint32_t)prototype_count++;
            parts[part_count] = scene_part(s, m);
            prototypes[p] = (instance_prototype){.parts = &parts[part_count++], .part_count = 1};
        }
        status = scene_placement(s, m, p, &placements[i]);
    }
    instanced_scene input = {prototypes, prototype_count, placements, placement_count};
    instance_bvh two_level;
    if (status == 0 && instance_bvh_build(&input, &two_level) == 0) {
        *out = (bvh){.nodes = two_level.nodes,
                     .node_count = two_level.node_count,
                     .leaves = two_level.leaves,
                     .leaf_count = two_level.leaf_count,
                     .reference_count = two_level.reference_count,
                     .degenerate_count = two_level.degenerate_count,
                     .depth = two_level.prototype_depth,
                     .build_seconds = two_level.build_seconds,
                     .top_nodes = two_level.top_nodes,
                     .top_node_count = two_level.top_node_count,
                     .instances = two_level.instances,
                     .instance_count = two_level.instance_count,
                     .top_depth = two_level.top_depth};
    } else {
        status = error_prefix("the scene's two-level BVH");
    }
    free(parts);
    free(prototypes);
    free(placements);
    free(placed);
    return status ? -1 : 0; /* instance_bvh_build logged the build */
}

int bvh_build(const scene *s, bvh *out)
{
    if (s->features & IDMR_FEATURE_INSTANCES)
        return build_instanced(s, out);
    bvh_mesh *meshes = xmalloc(s->mesh_count * sizeof *meshes + 1);
    for (size_t m = 0; m < s->mesh_count; m++)
        meshes[m] = scene_part(s, m);
    int status = bvh_build_meshes(meshes, s->mesh_count, out);
    free(meshes);
    if (status)
        return -1;
    log_verbose("BVH: %zu nodes, %zu leaves, %zu triangle references (%zu degenerate triangles "
                "left out), depth %d, %.2f s",
                out->node_count, out->leaf_count, out->reference_count, out->degenerate_count,
                out->depth, out->build_seconds);
    return 0;
}

void bvh_free(bvh *b)
{
    free(b->nodes);
    free(b->leaves);
    free(b->top_nodes);
    free(b->instances);
    memset(b, 0, sizeof *b);
}

uint64_t bvh_device_bytes(const bvh *b)
{
    return (uint64_t)b->node_count * sizeof(idmr_bvh_node) +
           (uint64_t)b->leaf_count * sizeof(idmr_triangle4) +
           (uint64_t)b->top_node_count * sizeof(idmr_bvh_node) +
           (uint64_t)b->instance_count * sizeof(idmr_instance);
}
