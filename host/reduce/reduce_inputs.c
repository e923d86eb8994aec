/* reduce_inputs.c — per mesh of the scene, what every stage of `idmr reduce` asks of it (see
 * reduce_stages.h): whether it is pinned (never decimated) or may be decimated at all, which
 * attributes it carries through the decimation, and the decimate_input it is decimated from;
 * and the view of the scene with some of its meshes decimated (the scene a later pass
 * simulates, the reduced scene the memory fit measures). */
#include <string.h>

#include "reduce/reduce_stages.h"

int reduce_mesh_named_by_keep(const reduce_options *o, const scene_mesh *mesh)
{
    for (size_t i = 0; i < o->keep_count; i++)
        if (strcmp(o->keep[i], mesh->name) == 0)
            return 1;
    return 0;
}

/* Whether every triangle of the mesh is degenerate (zero area): welded, it has no surface to
 * decimate, and its collapses would leave a mesh without faces that no reader loads. */
static int has_no_area(const scene_mesh *mesh)
{
    for (uint32_t t = 0; t < mesh->triangle_count; t++)
        if (scene_mesh_triangle_area(mesh, t) > 0.0)
            return 0;
    return 1;
}

int reduce_mesh_pinned(const reduce_options *o, const scene_mesh *mesh)
{
    return mesh->light >= 0 || reduce_mesh_named_by_keep(o, mesh) ||
           (mesh->released ? mesh->no_area : has_no_area(mesh));
}

int reduce_decimatable(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    return !reduce_instance_follower(st, m) && !reduce_instance_pinned(st, m) &&
           mesh->vertex_count > st->options->min_vertices;
}

/* What mesh m is decimated from: the scene's mesh, its texture coordinates, its normals unless
 * they are flat (flat ones become face_normals) or were computed by the loader and are to be
 * computed again by the reader (recompute_normals), and its per-vertex importance (remapped, with
 * each vertex's distance from its source, where it was computed on a reduced mesh). Computed
 * normals are carried by default: the reader would compute them from the reduced mesh, whose
 * larger faces average the original's curvature away (a glass surface then shows the light in
 * other places; see README, "Attributes through the reduction"). */
void reduce_mesh_attributes(const reduce_state *st, size_t m, int *texcoords, int *normals)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    int carried = mesh->file_normals || !st->options->recompute_normals;
    *texcoords = mesh->released ? mesh->had_texcoords : mesh->texcoords != NULL;
    *normals = carried && !mesh->flat_normals &&
               (mesh->released ? mesh->had_normals : mesh->normals != NULL);
}

decimate_input reduce_decimation_input(const reduce_state *st, size_t m)
{
    const scene_mesh *mesh = &st->scene->meshes[m];
    decimate_input in;
    memset(&in, 0, sizeof in);
    in.name = mesh->name;
    in.positions = mesh->positions;
    in.vertex_count = mesh->vertex_count;
    in.indices = mesh->indices;
    in.triangle_count = mesh->triangle_count;
    int texcoords, normals;
    reduce_mesh_attributes(st, m, &texcoords, &normals);
    in.texcoords = texcoords ? mesh->texcoords : NULL;
    in.normals = normals ? mesh->normals : NULL;
    in.vertex_importance = st->vertex_importance ? st->vertex_importance[m] : NULL;
    if (st->remapped && st->remapped[m]) {
        in.vertex_importance = st->remapped[m];
        in.vertex_distance = st->distance[m];
    }
    in.max_normal_angle = st->options->max_normal_angle;
    in.uv_weight = st->options->uv_weight;
    in.normal_weight = st->options->normal_weight;
    return in;
}

/* Whether `o` holds a decimated mesh (its history may be freed already). */
static int holds_decimation(const decimate_output *o)
{
    return o->mesh.positions != NULL;
}

scene *reduce_view_of(reduce_state *st, const decimate_output *meshes)
{
    /* A released mesh without a decimation here is shown as it is: read again (and kept). A
     * later copy of an instanced shape holds no geometry: the view places its representative's. */
    for (size_t m = 0; m < st->count; m++)
        if (!holds_decimation(&meshes[m]) && !scene_mesh_is_later_copy(st->scene, m) &&
            scene_mesh_restore(st->scene, m))
            return NULL;
    scene *view = scene_view(st->scene);
    for (size_t m = 0; m < st->count; m++) {
        const decimate_output *h = &meshes[m];
        if (!holds_decimation(h))
            continue;
        /* The view's mesh is the decimation, in memory (shared: the output owns it). */
        scene_mesh_set_geometry(&view->meshes[m], h->mesh.vertex_count, h->mesh.positions,
                                h->mesh.triangle_count, h->mesh.indices, h->mesh.texcoords,
                                h->mesh.normals);
    }
    if (scene_finalize(view)) {
        scene_view_free(view);
        return NULL;
    }
    return view;
}
