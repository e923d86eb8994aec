/* reduce_instances.c — a scene's instances kept through `idmr reduce` (see reduce_stages.h):
 * a Mitsuba shapegroup placed by instances, a pbrt-v4 object placed by ObjectInstances, a glTF
 * mesh that several nodes name.
 *
 * The loaders flatten every instance into world-space copies and chain the copies of one shape
 * (core/scene.h: instanced), so the importance pass sees each copy where it stands. The
 * reduction folds the copies of one shape back into one prototype, which the reduced scene
 * stores once:
 *
 *   plan          the prototype is planned once (Eq. 3), through its first copy, the
 *                 representative: its vertices counted once (what the written scene stores,
 *                 so D is a fraction of the stored vertices) and its importance summed over
 *                 every copy; the other copies (followers) have no vertices of their own in
 *                 the plan, and --keep on any copy keeps the prototype whole
 *   decimation    the representative is decimated in its own world space with the importance
 *                 summed per vertex over the copies (vertex v of every copy is the
 *                 prototype's vertex v: the loader makes them so)
 *   followers     each follower's reduced mesh is the representative's moved by
 *                 T_f T_r^-1 (T: an instance's to_world, the winding kept on its side as the
 *                 loader keeps it), so every later stage (the next pass's view, the memory
 *                 fit, the error budget's check renders) sees the reduced scene flattened; the
 *                 initial reduction (--initial) reduces each prototype once so too
 *   write         Mitsuba: the shapegroup's shape points to the reduced prototype in the
 *                 group's own space (T_r^-1 of the representative's), the shapegroup and its
 *                 instances as written; pbrt-v4: the object's Shape, in its own space, once;
 *                 glTF: the primitive once, every node naming the one mesh (reduce_write.c)
 *
 * So a prototype whose copies differ in importance gets the detail its most important copies
 * need, everywhere; vertices_after counts it once, and report.json's vertices_rendered_after
 * counts every copy. */
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/shapes.h"
#include "core/xform.h"
#include "reduce/reduce_stages.h"

size_t reduce_instance_representative(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    return mesh->instanced ? mesh->instance_first : m;
}

int reduce_instance_follower(const reduce_state *st, size_t m)
{
    return reduce_instance_representative(st, m) != m;
}

size_t reduce_instance_next_copy(const reduce_state *st, size_t c)
{
    const scene_mesh *mesh = &st->scene->meshes[c];
    return mesh->instanced && mesh->instance_next ? mesh->instance_next : st->count;
}

int reduce_instance_has_followers(const reduce_state *st, size_t m)
{
    return reduce_instance_next_copy(st, m) < st->count;
}

int reduce_instance_named_by_keep(const reduce_state *st, size_t m)
{
    for (size_t c = m; c < st->count; c = reduce_instance_next_copy(st, c))
        if (reduce_mesh_named_by_keep(st->options, &st->scene->meshes[c]))
            return 1;
    return 0;
}

int reduce_instance_pinned(const reduce_state *st, size_t m)
{
    for (size_t c = m; c < st->count; c = reduce_instance_next_copy(st, c))
        if (reduce_mesh_pinned(st->options, &st->scene->meshes[c]))
            return 1;
    return 0;
}

/* Whether copy c has the representative r's vertex and triangle counts (the loader makes every
 * copy so; a mesh file changed between reads would not be). 0, or -1 with the error set. */
static int check_copy(const reduce_state *st, size_t r, size_t c)
{
    const scene_mesh *a = &st->scene->meshes[r], *b = &st->scene->meshes[c];
    if (a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count)
        return 0;
    return error_set(IDMR_EXIT_INPUT,
                     "mesh '%s' (%u vertices, %u triangles) and mesh '%s' (%u, %u) are copies of "
                     "one shapegroup shape (%s:%d) but differ",
                     a->name, a->vertex_count, a->triangle_count, b->name, b->vertex_count,
                     b->triangle_count, a->xml_file ? a->xml_file : st->scene->file, a->xml_line);
}

double reduce_instance_importance(const reduce_state *st, const importance_result *r, size_t m,
                                  const importance_weights *weights)
{
    double sum = 0.0;
    for (size_t c = m; c < st->count; c = reduce_instance_next_copy(st, c))
        sum += importance_mesh_sums(r, st->simulated, c, weights).amount;
    return sum;
}

int reduce_instances_sum_vertex_importance(reduce_state *st)
{
    for (size_t m = 0; m < st->count; m++) {
        if (reduce_instance_follower(st, m) || !reduce_instance_has_followers(st, m) ||
            !st->input[m].vertex_importance)
            continue;
        uint32_t n = st->scene->meshes[m].vertex_count;
        if (!st->instance_importance)
            st->instance_importance = xcalloc(st->count + 1, sizeof *st->instance_importance);
        double *sum = st->instance_importance[m] = xcalloc((size_t)n + 1, sizeof *sum);
        for (size_t c = m; c < st->count; c = reduce_instance_next_copy(st, c)) {
            if (check_copy(st, m, c))
                return -1;
            const double *own = reduce_decimation_input(st, c).vertex_importance;
            for (uint32_t v = 0; own && v < n; v++)
                sum[v] += own[v];
        }
        st->input[m].vertex_importance = sum;
    }
    return 0;
}

void reduce_instances_forget(reduce_state *st)
{
    for (size_t m = 0; st->instance_importance && m < st->count; m++)
        free(st->instance_importance[m]);
    free(st->instance_importance);
    st->instance_importance = NULL;
}

/* A malloc'd copy of `bytes` at `from`, or NULL for NULL. */
static void *duplicate(const void *from, size_t bytes)
{
    if (!from)
        return NULL;
    void *to = xmalloc(bytes ? bytes : 1);
    memcpy(to, from, bytes);
    return to;
}

/* A copy of the mesh `from` into `to`. */
static void copy_mesh(const mesh_data *from, mesh_data *to)
{
    *to = *from;
    size_t v = from->vertex_count, t = from->triangle_count;
    to->positions = duplicate(from->positions, 3 * v * sizeof *from->positions);
    to->indices = duplicate(from->indices, 3 * t * sizeof *from->indices);
    to->texcoords = duplicate(from->texcoords, 2 * v * sizeof *from->texcoords);
    to->normals = duplicate(from->normals, 3 * v * sizeof *from->normals);
}

/* A copy of `from`, the decimation of a mesh of `input_vertices` vertices (its history too,
 * where it has one). */
static void copy_output(const decimate_output *from, uint32_t input_vertices, decimate_output *to)
{
    *to = *from;
    copy_mesh(&from->mesh, &to->mesh);
    size_t h = from->history_count;
    to->collapsed_into = duplicate(from->collapsed_into, h * sizeof *from->collapsed_into);
    to->output_index = duplicate(from->output_index, h * sizeof *from->output_index);
    to->welded_of = duplicate(from->welded_of, input_vertices * sizeof *from->welded_of);
}

/* Copy c's instance transform and its inverse; 0, or -1 with the error set (a singular one). */
static int instance_transforms(const reduce_state *st, size_t c, xform *to_world,
                               xform *to_object)
{
    const scene_mesh *mesh = &st->scene->meshes[c];
    *to_world = xform_from_rows(mesh->instance_to_world);
    if (!xform_invert_affine(to_world, to_object))
        return 0;
    return error_set(IDMR_EXIT_INPUT,
                     "%s:%d: the instance's to_world is singular: mesh '%s', a copy of its "
                     "shapegroup's shape, cannot be written in the group's own space",
                     mesh->instance_xml_file, mesh->instance_xml_line, mesh->name);
}

int reduce_instance_prototype_mesh(const reduce_state *st, size_t m, mesh_data *out)
{
    xform to_world, to_object;
    memset(out, 0, sizeof *out);
    if (instance_transforms(st, m, &to_world, &to_object))
        return -1;
    copy_mesh(&st->output[m].mesh, out);
    shapes_transform_keeping_side(out, &to_object);
    return 0;
}

int reduce_instances_derive(reduce_state *st, decimate_output *outputs)
{
    for (size_t f = 0; f < st->count; f++) {
        if (!reduce_instance_follower(st, f))
            continue;
        size_t r = reduce_instance_representative(st, f);
        decimate_output_free(&outputs[f]);
        if (!outputs[r].mesh.positions)
            continue;
        xform representative_world, representative_object, follower_world, follower_object;
        if (check_copy(st, r, f) ||
            instance_transforms(st, r, &representative_world, &representative_object) ||
            instance_transforms(st, f, &follower_world, &follower_object))
            return -1;
        copy_output(&outputs[r], st->scene->meshes[r].vertex_count, &outputs[f]);
        shapes_transform_keeping_side(&outputs[f].mesh, &representative_object);
        shapes_transform_keeping_side(&outputs[f].mesh, &follower_world);
    }
    return 0;
}

uint64_t reduce_instances_rendered_vertices(const reduce_state *st)
{
    uint64_t vertices = 0;
    for (size_t m = 0; m < st->count; m++)
        vertices += st->output[m].mesh.positions ? st->output[m].mesh.vertex_count
                                                 : st->scene->meshes[m].vertex_count;
    return vertices;
}
