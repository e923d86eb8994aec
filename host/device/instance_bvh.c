/* instance_bvh.c — the two-level BVH of an instanced scene (see instance_bvh.h).
 *
 * Steps: check every placement (a prototype that exists, a finite, invertible transform; its
 * largest stretch, offset_scale);
 * build each prototype's flat BVH and append its nodes and packets to the shared arrays
 * (append_prototypes); write each instance's record, its inverse transform computed in double
 * (set_instance), and its world box, the eight corners of its prototype's box carried to the
 * world and padded for rounding (instance_world_box); build the top level over those boxes. */
#include "device/instance_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"

/* A transform whose 3x3 part's volume is below this share of its columns' lengths' product
 * flattens space: refused (float rays through its inverse would lose every digit). */
#define SINGULAR_VOLUME 1e-6

void instance_placement_apply(const instance_placement *p, const float position[3],
                              float world[3])
{
    const float *m = p->object_to_world;
    for (int r = 0; r < 3; r++)
        world[r] = (float)((double)m[4 * r] * position[0] + (double)m[4 * r + 1] * position[1] +
                           (double)m[4 * r + 2] * position[2] + (double)m[4 * r + 3]);
}

/* Checks placement i; writes its world-to-object transform (3x4 row-major) into inverse[].
 * Returns 0, or -1 with the error set. */
static int invert_placement(const instanced_scene *s, size_t i, float inverse[12])
{
    const instance_placement *p = &s->instances[i];
    if (p->prototype >= s->prototype_count)
        return error_set(IDMR_EXIT_INPUT, "instance %zu: prototype %u does not exist (%zu "
                                          "prototypes)", i, p->prototype, s->prototype_count);
    double m[3][4];
    for (int k = 0; k < 12; k++) {
        if (!isfinite(p->object_to_world[k]))
            return error_set(IDMR_EXIT_INPUT, "instance %zu: transform entry %d is not finite",
                             i, k);
        m[k / 4][k % 4] = p->object_to_world[k];
    }
    /* adjugate / det; columns' lengths for the volume test */
    double adj[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
            adj[r][c] = m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1];
        }
    double det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
    double column_product = 1.0;
    for (int c = 0; c < 3; c++)
        column_product *= sqrt(m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]);
    if (!(fabs(det) > SINGULAR_VOLUME * column_product) || !isfinite(1.0 / det))
        return error_set(IDMR_EXIT_INPUT, "instance %zu: singular transform (det %.3g, columns' "
                                          "lengths' product %.3g): it cannot be inverted", i,
                         det, column_product);
    for (int r = 0; r < 3; r++) {
        double translation = 0.0;
        for (int c = 0; c < 3; c++) {
            double w = adj[r][c] / det;
            inverse[4 * r + c] = (float)w;
            translation -= w * m[c][3];
        }
        inverse[4 * r + 3] = (float)translation;
    }
    for (int k = 0; k < 12; k++)
        if (!isfinite(inverse[k]))
            return error_set(IDMR_EXIT_INPUT, "instance %zu: the inverse transform overflows a "
                                              "float", i);
    return 0;
}

/* Builds each prototype's BVH and appends it to out's nodes and leaves; node_offset[p] and
 * leaf_offset[p] get where prototype p starts, box[p] its object-space box. */
static int append_prototypes(const instanced_scene *s, instance_bvh *out, size_t *node_offset,
                             size_t *leaf_offset, bvh_box *box)
{
    for (size_t p = 0; p < s->prototype_count; p++) {
        const instance_prototype *proto = &s->prototypes[p];
        bvh_mesh mesh = {proto->positions, proto->indices, proto->triangle_count, 0};
        bvh b;
        if (proto->part_count ? bvh_build_meshes(proto->parts, proto->part_count, &b)
                              : bvh_build_meshes(&mesh, 1, &b))
            return error_prefix("prototype %zu", p);
        out->reference_count += b.reference_count;
        out->degenerate_count += b.degenerate_count;
        node_offset[p] = out->node_count;
        leaf_offset[p] = out->leaf_count;
        out->nodes = xrealloc(out->nodes, (out->node_count + b.node_count) * sizeof *out->nodes);
        memcpy(out->nodes + out->node_count, b.nodes, b.node_count * sizeof *b.nodes);
        out->node_count += b.node_count;
        out->leaves = xrealloc(out->leaves,
                               (out->leaf_count + b.leaf_count) * sizeof *out->leaves + 1);
        if (b.leaf_count > 0) /* an empty prototype has no leaves array */
            memcpy(out->leaves + out->leaf_count, b.leaves, b.leaf_count * sizeof *b.leaves);
        out->leaf_count += b.leaf_count;
        if (b.depth > out->prototype_depth)
            out->prototype_depth = b.depth;
        /* the root's slots bound every triangle (empty slots are inverted boxes) */
        const idmr_bvh_node *root = &b.nodes[0];
        box[p] = (bvh_box){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        for (int k = 0; k < IDMR_BVH_WIDTH; k++) {
            const float lo[3] = {root->min_x[k], root->min_y[k], root->min_z[k]};
            const float hi[3] = {root->max_x[k], root->max_y[k], root->max_z[k]};
            for (int a = 0; a < 3; a++) {
                box[p].min[a] = fminf(box[p].min[a], lo[a]);
                box[p].max[a] = fmaxf(box[p].max[a], hi[a]);
            }
        }
        bvh_free(&b);
    }
    if (out->node_count > (size_t)INT32_MAX || out->leaf_count > (size_t)INT32_MAX)
        return error_set(IDMR_EXIT_INPUT, "the prototypes need %zu nodes and %zu leaves; the "
                                          "kernels address %d", out->node_count, out->leaf_count,
                         INT32_MAX);
    return 0;
}

/* The most placement p stretches a coordinate's magnitude: max_r sum_c |M[r][c]| (so that
 * |world|_max <= this × |object|_max + |m|_max); the kernels scale a prototype triangle's ray
 * offset by it (kernels/lib/surface.h). */
static float placement_offset_scale(const instance_placement *p)
{
    double largest = 0.0;
    for (int r = 0; r < 3; r++)
        largest = fmax(largest, fabs((double)p->object_to_world[4 * r]) +
                                    fabs((double)p->object_to_world[4 * r + 1]) +
                                    fabs((double)p->object_to_world[4 * r + 2]));
    return (float)largest;
}

/* The world box of placement p of a prototype whose object box is `object`: its eight corners
 * carried to the world, grown by 2^-20 of the largest coordinate magnitude on each side (the
 * kernel moves the ray, not the box, into object space, and both roundings must stay inside).
 * An empty object box stays empty. */
static bvh_box instance_world_box(const instance_placement *p, const bvh_box *object)
{
    bvh_box world = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    if (!(object->min[0] <= object->max[0]))
        return world;
    for (int corner = 0; corner < 8; corner++) {
        const float v[3] = {(corner & 1) ? object->max[0] : object->min[0],
                            (corner & 2) ? object->max[1] : object->min[1],
                            (corner & 4) ? object->max[2] : object->min[2]};
        float w[3];
        instance_placement_apply(p, v, w);
        for (int a = 0; a < 3; a++) {
            world.min[a] = fminf(world.min[a], w[a]);
            world.max[a] = fmaxf(world.max[a], w[a]);
        }
    }
    for (int a = 0; a < 3; a++) {
        float pad = 0x1p-20f * fmaxf(fabsf(world.min[a]), fabsf(world.max[a]));
        world.min[a] -= pad;
        world.max[a] += pad;
    }
    return world;
}

int instance_bvh_build(const instanced_scene *s, instance_bvh *out)
{
    memset(out, 0, sizeof *out);
    double start = monotonic_seconds();
    size_t *node_offset = xmalloc(s->prototype_count * sizeof *node_offset + 1);
    size_t *leaf_offset = xmalloc(s->prototype_count * sizeof *leaf_offset + 1);
    bvh_box *object_box = xmalloc(s->prototype_count * sizeof *object_box + 1);
    bvh_box *world_box = xmalloc(s->instance_count * sizeof *world_box + 1);
    out->instances = xcalloc(s->instance_count + 1, sizeof *out->instances);
    out->instance_count = s->instance_count;
    for (int a = 0; a < 3; a++) {
        out->bounds_min[a] = INFINITY;
        out->bounds_max[a] = -INFINITY;
    }
    int status = 0;
    for (size_t i = 0; i < s->instance_count && status == 0; i++)
        status = invert_placement(s, i, out->instances[i].world_to_object);
    if (status == 0)
        status = append_prototypes(s, out, node_offset, leaf_offset, object_box);
    for (size_t i = 0; i < s->instance_count && status == 0; i++) {
        const instance_placement *p = &s->instances[i];
        idmr_instance *record = &out->instances[i];
        record->node_offset = (int)node_offset[p->prototype];
        record->leaf_offset = (int)leaf_offset[p->prototype];
        record->prototype = p->prototype;
        record->offset_scale = placement_offset_scale(p);
        world_box[i] = instance_world_box(p, &object_box[p->prototype]);
        for (int a = 0; a < 3; a++) {
            out->bounds_min[a] = fminf(out->bounds_min[a], world_box[i].min[a]);
            out->bounds_max[a] = fmaxf(out->bounds_max[a], world_box[i].max[a]);
        }
    }
    bvh top;
    if (status == 0 && bvh_build_boxes(world_box, s->instance_count, &top) == 0) {
        out->top_nodes = top.nodes;
        out->top_node_count = top.node_count;
        out->top_depth = top.depth;
    } else if (status == 0) {
        status = error_prefix("top level over %zu instances", s->instance_count);
    }
    free(node_offset);
    free(leaf_offset);
    free(object_box);
    free(world_box);
    if (status) {
        instance_bvh_free(out);
        return -1;
    }
    out->build_seconds = monotonic_seconds() - start;
    log_verbose("instanced BVH: %zu instances of %zu prototypes; %zu top nodes (depth %d), "
                "%zu prototype nodes, %zu leaves (depth <= %d), %.2f s",
                out->instance_count, s->prototype_count, out->top_node_count, out->top_depth,
                out->node_count, out->leaf_count, out->prototype_depth, out->build_seconds);
    return 0;
}

void instance_bvh_free(instance_bvh *b)
{
    free(b->top_nodes);
    free(b->instances);
    free(b->nodes);
    free(b->leaves);
    memset(b, 0, sizeof *b);
}

uint64_t instance_bvh_device_bytes(const instance_bvh *b)
{
    return (uint64_t)b->top_node_count * sizeof(idmr_bvh_node) +
           (uint64_t)b->instance_count * sizeof(idmr_instance) +
           (uint64_t)b->node_count * sizeof(idmr_bvh_node) +
           (uint64_t)b->leaf_count * sizeof(idmr_triangle4);
}
