/* reduce_instances.c — a scene's instances kept through `idmr reduce` (see reduce_stages.h):
 * a Mitsuba shapegroup placed by instances, a pbrt-v4 object placed by ObjectInstances, a glTF
 * mesh that several nodes name.
 *
 * The loaders hold an instanced shape once (core/scene.h: instanced): its first copy, the
 * representative, holds the geometry in its own world space; the later copies hold none and
 * share its triangles, so the passes (on the two-level BVH) add every copy's importance to
 * the prototype's triangles. The reduction reduces the prototype once:
 *
 *   plan          the prototype is planned once (Eq. 3), through the representative: its
 *                 vertices counted once (what the written scene stores, so D is a fraction of
 *                 the stored vertices) and its importance, which sums every copy's; the later
 *                 copies have no vertices of their own in the plan, and --keep on any copy
 *                 keeps the prototype whole
 *   decimation    the representative is decimated in its own world space with that importance;
 *                 a later copy has no decimation of its own: a view of the reduced scene (the
 *                 next pass, the memory fit, the error budget's check renders) places the
 *                 representative's reduction at every copy (core/scene.h), and so does the
 *                 initial reduction (--initial)
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
#include "core/shapes.h"
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

/* A copy of the mesh `from` into `to`. */
static void copy_mesh(const mesh_data *from, mesh_data *to)
{
    *to = *from;
    size_t v = from->vertex_count, t = from->triangle_count;
    to->positions = xmemdup(from->positions, 3 * v * sizeof *from->positions);
    to->indices = xmemdup(from->indices, 3 * t * sizeof *from->indices);
    to->texcoords = xmemdup(from->texcoords, 2 * v * sizeof *from->texcoords);
    to->normals = xmemdup(from->normals, 3 * v * sizeof *from->normals);
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

uint64_t reduce_instances_rendered_vertices(const reduce_state *st)
{
    uint64_t vertices = 0;
    for (size_t m = 0; m < st->count; m++) {
        const decimate_output *reduced = &st->output[reduce_instance_representative(st, m)];
        vertices += reduced->mesh.positions ? reduced->mesh.vertex_count
                                            : st->scene->meshes[m].vertex_count;
    }
    return vertices;
}
