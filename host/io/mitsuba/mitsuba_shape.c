/* mitsuba_shape.c — <shape> elements → world-space meshes: mesh files (obj, ply, off, stl,
 * read through OpenMesh, oriented by their normals unless face_normals is set) and built-in
 * shapes (rectangle, cube, disk, sphere, tessellated by host/core/shapes.h); to_world and
 * flip_normals; a bsdf by <ref> or inline (none: Mitsuba's diffuse 0.5); an area emitter inline
 * or by <ref>. A mesh is named by its id, else its file's stem, else its type.
 *
 * Instancing (Mitsuba 3 and 0.5 alike): a <shape type="shapegroup" id=...> holds shapes and
 * makes no geometry itself; a <shape type="instance"> naming it by <ref id=...> places a copy of
 * each of its shapes: the shape as it would be read at the top level (by its own to_world),
 * then moved as Mitsuba 3 moves an instance's geometry: points by the instance's to_world,
 * normals by its inverse transpose, and the winding flipped under a mirror, so that the surface
 * keeps its side (a mesh file under a mirroring to_world of its own does not: Mitsuba takes its
 * front from the world-space winding). Each group shape is held once (core/scene.h:
 * instanced): the first instance's copy is read and placed so, and holds the geometry; every
 * later instance's copy is a scene mesh without geometry of its own (scene_add_instance_copy),
 * its triangles the first's, placed from it. Each copy is named "<instance id, else group
 * id>/<shape name>" (the scene numbers repeats: "G/leaf.2") and remembers its instance element
 * (scene_mesh.instance_xml_file/line) and its instance's to_world; `idmr reduce` reduces and
 * writes the shape once (reduce/reduce_instances.c). As in Mitsuba 3, a shapegroup may not hold
 * a shapegroup or an instance, nor a shape with an area emitter. */
#include "io/mitsuba/mitsuba_loader.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"
#include "io/mesh/mesh_io.h"
#include "core/shapes.h"

static int is_mesh_file_type(const char *type)
{
    return strcmp(type, "obj") == 0 || strcmp(type, "ply") == 0 || strcmp(type, "off") == 0 ||
           strcmp(type, "stl") == 0;
}

/* What a mesh file shape is made from: the file and the properties that turn it into the
 * world-space mesh, kept with the scene mesh so its geometry can be read again
 * (scene_mesh_restore) exactly as the load read it. */
struct scene_mesh_source {
    char *file;          /* resolved */
    xform to_world;
    int instanced;       /* a copy an instance placed, under instance_to_world */
    xform instance_to_world;
    int face_normals;    /* the shape's face_normals: no shading normals */
    int flip_tex_coords; /* an OBJ's v turned as Mitsuba turns it (v -> 1 - v) */
    int flip_normals;
};

static void source_free(scene_mesh_source *source)
{
    if (source)
        free(source->file);
    free(source);
}

/* The source of a mesh file shape from its properties (placed by instance_to_world, NULL when
 * not an instance's copy); *written gets the path as in the file. NULL with the error set. */
static scene_mesh_source *shape_source(loader *ld, xmlNodePtr node,
                                       const xform *instance_to_world, const char **written)
{
    scene_mesh_source *source = xcalloc(1, sizeof *source);
    if (mitsuba_prop_string(node, "filename", NULL, written))
        goto fail;
    if (!*written) {
        mitsuba_fail(node, "missing <string name=\"filename\">");
        goto fail;
    }
    source->file = mitsuba_resolve_path(ld, mitsuba_prop_find(node, "filename"), *written);
    if (access(source->file, R_OK) != 0) {
        mitsuba_fail(node, "cannot read '%s' (%s): %s", *written, source->file, strerror(errno));
        goto fail;
    }
    /* Mitsuba's front side comes from the file's normals unless face_normals is set. */
    source->instanced = instance_to_world != NULL;
    if (instance_to_world)
        source->instance_to_world = *instance_to_world;
    if (mitsuba_prop_bool(node, "face_normals", 0, &source->face_normals) ||
        mitsuba_prop_transform(node, "to_world", &source->to_world) ||
        mitsuba_prop_bool(node, "flip_normals", 0, &source->flip_normals) ||
        (strcmp(mitsuba_attr(node, "type"), "obj") == 0 &&
         mitsuba_prop_bool(node, "flip_tex_coords", 1, &source->flip_tex_coords)))
        goto fail;
    return source;
fail:
    source_free(source);
    return NULL;
}

/* A mesh file shape's world-space geometry from its source, with Mitsuba's shading normals: the
 * file's own, smooth vertex normals where it has none, none under face_normals. *file_normals
 * says whether the normals are the file's own, *flat_normals whether those shade it flat
 * (shapes_normals_flat). 0, or -1 with the error set (naming the file). */
static int source_geometry(const scene_mesh_source *source, mesh_data *mesh, int *file_normals,
                           int *flat_normals)
{
    memset(mesh, 0, sizeof *mesh);
    if (mesh_io_read_oriented(source->file, mesh, !source->face_normals, NULL))
        return -1;
    if (source->flip_tex_coords && mesh->texcoords)
        for (uint32_t v = 0; v < mesh->vertex_count; v++)
            mesh->texcoords[2 * (size_t)v + 1] = 1.0f - mesh->texcoords[2 * (size_t)v + 1];
    if (source->face_normals) {
        free(mesh->normals);
        mesh->normals = NULL;
    }
    shapes_transform(mesh, &source->to_world);
    *file_normals = mesh->normals != NULL;
    *flat_normals = *file_normals && shapes_normals_flat(mesh);
    if (!source->face_normals && !mesh->normals)
        shapes_smooth_normals(mesh);
    if (source->flip_normals)
        shapes_flip_winding(mesh);
    if (source->instanced)
        shapes_transform_keeping_side(mesh, &source->instance_to_world);
    return 0;
}

/* scene_mesh_restore_fn: the geometry read again into the scene mesh (which takes it over). */
static int source_restore(const scene_mesh_source *source, scene_mesh *mesh)
{
    mesh_data data;
    int file_normals, flat_normals;
    if (source_geometry(source, &data, &file_normals, &flat_normals)) {
        mesh_data_free(&data);
        return -1;
    }
    scene_mesh_set_geometry(mesh, data.vertex_count, data.positions, data.triangle_count,
                            data.indices, data.texcoords, data.normals);
    return 0;
}

static int shape_sphere(xmlNodePtr node, mesh_data *mesh)
{
    double center[3] = {0, 0, 0}, radius;
    int found;
    if (mitsuba_prop_vector(node, "center", center, &found) ||
        mitsuba_prop_float(node, "radius", 1.0, &radius))
        return -1;
    if (radius <= 0.0)
        return mitsuba_fail(node, "the radius must be positive");
    shapes_sphere(center, radius, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, mesh);
    return 0;
}

/* Tessellates a built-in shape; returns 1 if `type` is not one. */
static int shape_builtin(xmlNodePtr node, const char *type, mesh_data *mesh)
{
    if (strcmp(type, "rectangle") == 0)
        shapes_rectangle(mesh);
    else if (strcmp(type, "cube") == 0)
        shapes_cube(mesh);
    else if (strcmp(type, "disk") == 0)
        shapes_disk(SHAPES_DISK_SEGMENTS, mesh);
    else if (strcmp(type, "sphere") == 0)
        return shape_sphere(node, mesh);
    else
        return 1;
    return 0;
}

/* The shape's geometry in world space (placed by instance_to_world, NULL when not an instance's
 * copy), with Mitsuba's shading normals: a mesh file's from its source (source_geometry;
 * *source gets it), a built-in shape's from shapes.h (their normals; *source NULL).
 * *file_normals says whether the normals are the mesh file's own, and *flat_normals whether
 * those shade the mesh flat (shapes_normals_flat). */
static int shape_geometry(loader *ld, xmlNodePtr node, const char *type,
                          const xform *instance_to_world, mesh_data *mesh,
                          scene_mesh_source **source, const char **written, int *file_normals,
                          int *flat_normals)
{
    memset(mesh, 0, sizeof *mesh);
    *source = NULL;
    *file_normals = *flat_normals = 0;
    if (strcmp(type, "serialized") == 0)
        return mitsuba_fail(node,
                            "unsupported shape type 'serialized' (convert the mesh to PLY or OBJ)");
    if (is_mesh_file_type(type)) {
        *source = shape_source(ld, node, instance_to_world, written);
        if (!*source)
            return -1;
        return source_geometry(*source, mesh, file_normals, flat_normals)
                   ? mitsuba_fail_prefix(node)
                   : 0;
    }
    xform to_world;
    int flip;
    if (mitsuba_prop_transform(node, "to_world", &to_world) ||
        mitsuba_prop_bool(node, "flip_normals", 0, &flip))
        return -1;
    int status = shape_builtin(node, type, mesh);
    if (status > 0)
        return mitsuba_fail(node, "unsupported shape type '%s'", type);
    if (status < 0)
        return -1;
    /* A built-in shape's normal is transformed as a normal (Mitsuba: the inverse transpose,
     * which keeps a sphere's outside out). */
    shapes_transform_keeping_side(mesh, &to_world);
    if (flip)
        shapes_flip_winding(mesh);
    if (instance_to_world)
        shapes_transform_keeping_side(mesh, instance_to_world);
    return 0;
}

/* The bsdf and area emitter of a shape: element nodes (inline or referenced; NULL if none),
 * and the id entry of a referenced bsdf. */
typedef struct shape_parts {
    xmlNodePtr bsdf;
    mitsuba_id *bsdf_entry;
    xmlNodePtr emitter;
} shape_parts;

static int shape_find_parts(loader *ld, xmlNodePtr node, shape_parts *parts)
{
    memset(parts, 0, sizeof *parts);
    MITSUBA_FOR_EACH_ELEMENT(child, node)
    {
        xmlNodePtr target = child;
        mitsuba_id *entry = NULL;
        if (mitsuba_is_tag(child, "ref") || mitsuba_is_tag(child, "bsdf") ||
            mitsuba_is_tag(child, "emitter"))
            mitsuba_mark_read(child);
        if (mitsuba_is_tag(child, "ref")) {
            if (!(entry = mitsuba_ref_resolve(ld, child)))
                return -1;
            target = entry->node;
        }
        int is_bsdf = mitsuba_is_tag(target, "bsdf");
        int is_emitter = mitsuba_is_tag(target, "emitter");
        if (is_bsdf && !parts->bsdf) {
            parts->bsdf = target;
            parts->bsdf_entry = entry;
        } else if (is_emitter && !parts->emitter) {
            parts->emitter = target;
        } else if (entry && !is_bsdf && !is_emitter) {
            return mitsuba_fail(child, "'%s' is neither a bsdf nor an emitter", entry->id);
        }
    }
    const char *emitter_type = parts->emitter ? mitsuba_attr(parts->emitter, "type") : NULL;
    if (parts->emitter && (!emitter_type || strcmp(emitter_type, "area") != 0))
        return mitsuba_fail(parts->emitter, "only area emitters can be attached to a shape");
    return 0;
}

/* The shape's name: its id, else the mesh file's stem, else its type. */
static void shape_name(xmlNodePtr node, const char *type, const char *written, char *out,
                       size_t size)
{
    const char *id = mitsuba_attr(node, "id");
    if (id && id[0]) {
        snprintf(out, size, "%s", id);
        return;
    }
    if (!written) {
        snprintf(out, size, "%s", type);
        return;
    }
    const char *base = strrchr(written, '/') ? strrchr(written, '/') + 1 : written;
    const char *dot = strrchr(base, '.');
    int length = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(out, size, "%.*s", length, base);
}

/* The material for a shape: its referenced bsdf, its inline one (already parsed), or the
 * default. */
static int shape_material(loader *ld, const bsdf_parsed *inline_bsdf, mitsuba_id *entry,
                          const char *mesh_name)
{
    if (entry)
        return mitsuba_bsdf_by_id(ld, entry);
    if (!inline_bsdf)
        return mitsuba_bsdf_default(ld);
    char name[512];
    snprintf(name, sizeof name, "%s/bsdf", mesh_name);
    return mitsuba_bsdf_add(ld, inline_bsdf, name);
}

/* Where a shape is put: a top-level shape by its own to_world (instance NULL); a shapegroup's
 * shape once per instance, under instance_to_world and named after name_prefix. */
typedef struct shape_placement {
    xmlNodePtr instance;
    xform instance_to_world;
    const char *name_prefix; /* the instance's id, else the group's */
} shape_placement;

/* The mesh index of the first copy of shapegroup shape `node`, or -1 when none was made yet. */
static long first_copy_of(const loader *ld, xmlNodePtr node)
{
    for (size_t g = 0; g < ld->group_shape_count; g++)
        if (ld->group_shapes[g].shape == node)
            return (long)ld->group_shapes[g].first_copy;
    return -1;
}

/* The scene's last mesh, the first copy of the shapegroup shape `node`, placed by
 * `instance_to_world`: made the representative of that shape's copies (core/scene.h). */
static void mark_first_copy(loader *ld, xmlNodePtr node, const xform *instance_to_world)
{
    size_t copy = ld->s->mesh_count - 1;
    scene_mesh *mesh = &ld->s->meshes[copy];
    mesh->instanced = 1;
    mesh->instance_first = copy;
    memcpy(mesh->instance_to_world, instance_to_world->m, sizeof mesh->instance_to_world);
    ld->group_shapes =
        xrealloc(ld->group_shapes, (ld->group_shape_count + 1) * sizeof *ld->group_shapes);
    ld->group_shapes[ld->group_shape_count++] = (struct group_shape_copies){node, copy};
}

/* A later copy of the shapegroup shape `node`, whose first copy is mesh `first`: no geometry
 * of its own (core/scene.h: scene_add_instance_copy), named and placed by `placement`. */
static int add_later_copy(loader *ld, xmlNodePtr node, size_t first,
                          const shape_placement *placement)
{
    const char *type = mitsuba_attr(node, "type"), *written = NULL;
    char name[520], shape_own_name[256];
    if (ld->s->meshes[first].file)
        written = ld->s->meshes[first].file;
    shape_name(node, type, written, shape_own_name, sizeof shape_own_name);
    snprintf(name, sizeof name, "%s/%s", placement->name_prefix, shape_own_name);
    scene_mesh *copy = scene_add_instance_copy(ld->s, first, name, placement->instance_to_world.m);
    if (!copy)
        return mitsuba_fail(placement->instance, "%s", error_message());
    copy->instance_xml_file = xstrdup(mitsuba_node_file(placement->instance));
    copy->instance_xml_line = (int)xmlGetLineNo(placement->instance);
    return 0;
}

/* Reads the shape `node` into a world-space scene mesh (placement: NULL, or the instance that
 * puts a copy of it). */
static int load_placed_shape(loader *ld, xmlNodePtr node, const shape_placement *placement)
{
    const char *type, *written = NULL;
    shape_parts parts;
    idmr_light light;
    bsdf_parsed inline_bsdf;
    mesh_data mesh;
    scene_mesh_source *source = NULL;
    char name[520], shape_own_name[256];
    memset(&light, 0, sizeof light);
    long first = placement ? first_copy_of(ld, node) : -1;
    if (first >= 0)
        return add_later_copy(ld, node, (size_t)first, placement);
    if (mitsuba_require_attr(node, "type", &type) || shape_find_parts(ld, node, &parts))
        return -1;
    /* Parse an inline bsdf (a referenced one was parsed at its declaration) and the emitter
     * before the (possibly slow) mesh read. */
    int has_inline_bsdf = parts.bsdf && !parts.bsdf_entry;
    if ((has_inline_bsdf && mitsuba_parse_bsdf(ld, parts.bsdf, 0, &inline_bsdf)) ||
        (parts.emitter && mitsuba_emitter_area(ld, parts.emitter, &light)))
        return -1;
    int file_normals = 0, flat_normals = 0;
    if (shape_geometry(ld, node, type, placement ? &placement->instance_to_world : NULL, &mesh,
                       &source, &written, &file_normals, &flat_normals)) {
        mesh_data_free(&mesh);
        source_free(source);
        return -1;
    }
    shape_name(node, type, written, shape_own_name, sizeof shape_own_name);
    if (placement)
        snprintf(name, sizeof name, "%s/%s", placement->name_prefix, shape_own_name);
    else
        snprintf(name, sizeof name, "%s", shape_own_name);
    scene_mesh *added = scene_add_mesh(ld->s, name, type, source ? source->file : NULL,
                                       (int)xmlGetLineNo(node), mesh.vertex_count, mesh.positions,
                                       mesh.triangle_count, mesh.indices, mesh.texcoords);
    added->normals = mesh.normals;
    added->triangles_dropped += mesh.triangles_dropped;
    added->file_normals = file_normals;
    added->flat_normals = flat_normals;
    added->source = source; /* the scene frees it (scene_mesh_release can read it again) */
    ld->s->restore_mesh = source_restore;
    ld->s->free_mesh_source = source_free;
    int material = shape_material(ld, has_inline_bsdf ? &inline_bsdf : NULL, parts.bsdf_entry,
                                  added->name);
    if (material < 0)
        return -1;
    added->material = (uint32_t)material;
    added->xml_file = xstrdup(mitsuba_node_file(node));
    if (placement) {
        added->instance_xml_file = xstrdup(mitsuba_node_file(placement->instance));
        added->instance_xml_line = (int)xmlGetLineNo(placement->instance);
        mark_first_copy(ld, node, &placement->instance_to_world);
    }
    added->light = parts.emitter ? scene_add_light(ld->s, &light) : -1;
    if (ld->release_from && added->vertex_count >= ld->release_from)
        scene_mesh_release(ld->s, ld->s->mesh_count - 1);
    return 0;
}

static int is_shape_of_type(xmlNodePtr node, const char *type)
{
    const char *written = mitsuba_attr(node, "type");
    return mitsuba_is_tag(node, "shape") && written && strcmp(written, type) == 0;
}

/* A <shape type="shapegroup">: its shapes are checked (no nested instancing, no emitters, as
 * in Mitsuba 3) and it is registered under its id for the instances; no geometry yet. */
static int load_shapegroup(loader *ld, xmlNodePtr node)
{
    if (!mitsuba_attr(node, "id"))
        return mitsuba_fail(node, "a shapegroup needs an id (instances name it by <ref id=...>)");
    MITSUBA_FOR_EACH_ELEMENT(child, node)
    {
        if (!mitsuba_is_tag(child, "shape"))
            continue;
        shape_parts parts;
        if (is_shape_of_type(child, "shapegroup") || is_shape_of_type(child, "instance"))
            return mitsuba_fail(child, "nested instancing is not allowed: a shapegroup cannot "
                                       "hold a shapegroup or an instance (Mitsuba 3)");
        if (shape_find_parts(ld, child, &parts))
            return -1;
        if (parts.emitter)
            return mitsuba_fail(child, "an area emitter inside a shapegroup is not allowed "
                                       "(Mitsuba 3 does not instance emitters)");
    }
    return mitsuba_id_register(ld, node);
}

/* A <shape type="instance">: a world-space copy of each shape of the shapegroup its <ref>
 * names, under its to_world. */
static int load_instance(loader *ld, xmlNodePtr node)
{
    xmlNodePtr ref = NULL;
    MITSUBA_FOR_EACH_ELEMENT(child, node)
    {
        if (mitsuba_is_tag(child, "ref") && !ref)
            ref = child;
    }
    if (!ref)
        return mitsuba_fail(node, "an instance needs a <ref id=\"...\"/> naming a shapegroup");
    mitsuba_mark_read(ref);
    mitsuba_id *entry = mitsuba_ref_resolve(ld, ref);
    if (!entry)
        return -1;
    if (!is_shape_of_type(entry->node, "shapegroup"))
        return mitsuba_fail(ref, "'%s' is not a shapegroup (an instance places a shapegroup)",
                            entry->id);
    shape_placement placement = {node, xform_identity(), NULL};
    if (mitsuba_prop_transform(node, "to_world", &placement.instance_to_world))
        return -1;
    const char *id = mitsuba_attr(node, "id");
    placement.name_prefix = id && id[0] ? id : entry->id;
    MITSUBA_FOR_EACH_ELEMENT(child, entry->node)
    {
        if (!mitsuba_is_tag(child, "shape"))
            continue;
        mitsuba_mark_read(child);
        if (load_placed_shape(ld, child, &placement))
            return mitsuba_fail_prefix(node);
    }
    return 0;
}

int mitsuba_load_shape(loader *ld, xmlNodePtr node)
{
    const char *type;
    if (mitsuba_require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "shapegroup") == 0)
        return load_shapegroup(ld, node);
    if (strcmp(type, "instance") == 0)
        return load_instance(ld, node);
    return load_placed_shape(ld, node, NULL);
}
