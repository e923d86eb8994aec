/* gltf_write.c — the reduced glTF scene (io/gltf/gltf.h: gltf_write_reduced), written by rewriting
 * the input's own JSON document (io/gltf/gltf_document.h), not through Assimp's exporter: every
 * node, camera, light, material, texture, sampler, animation, extension and extras of the input
 * comes out as it went in, and only the geometry of the replaced mesh primitives changes.
 *
 * Instances. gltf_load numbers the triangle-mesh instances as Assimp imports them: a
 * depth-first walk of the default scene ("scene", else 0) from its root nodes in order, a node
 * before its children; at each node with a mesh, each of the mesh's primitives whose mode is
 * triangles, a strip or a fan (Assimp makes one aiMesh per primitive, and points and lines are
 * no triangle meshes). walk() makes the same list, with each node's world transform (matrix,
 * else translation × rotation × scale).
 *
 * Meshes. A replaced primitive gets new accessors for POSITION (with min and max), NORMAL and
 * TEXCOORD_0 where the reduced mesh has them, and indices (unsigned short below 65,536
 * vertices), in the node's local space (the inverse of its world transform; normals by the
 * transpose of its linear part; the winding turned back where the transform mirrors); its mode
 * becomes triangles, and what no longer matches its vertices goes (other attributes, Draco
 * data; morph targets keep their number but move nothing, so the mesh's weights and
 * animations stay valid; the node's skin: warned). The data is written as the host holds it,
 * little-endian as glTF's. A glTF mesh is shared by every node that names it, so a node with
 * replaced instances writes into the mesh itself only when every node that names the mesh has
 * replaced instances (the first of them); the others get a copy of their own, so a node left
 * alone keeps the original and two nodes reduced differently do not overwrite each other (a
 * node the walk reaches twice, which glTF forbids, cannot be given two meshes: refused). A node
 * whose replacements are all shared (copies of one reduction) names the mesh of the node that
 * writes that reduction, so the nodes keep sharing one mesh.
 *
 * Binary data. When every extension the document uses is one whose references the writer
 * knows (lights, materials, texture transforms and formats, mesh quantization, XMP, animation
 * pointers), accessors and bufferViews no longer referenced are dropped, the rest renumbered,
 * and all bytes still used go into one new buffer: outdir/scene.bin beside scene.gltf, or the
 * BIN chunk of scene.glb. With any other extension (its references unknown: Draco, meshopt,
 * GPU instancing, a vendor's), or a reference to an index that does not exist, nothing is
 * renumbered: the input's buffers stay (a .glb's BIN chunk copied, external files named from
 * outdir) and the new data is appended.
 *
 * Paths. URIs that name files relative to the input (images', kept buffers', an extension's;
 * none in extras) are rewritten relative to outdir (absolute where no relative path exists)
 * or, with bundle, to copies under outdir/assets/ (one per file, base names made unique with
 * -2, -3, ...); data: URIs and other schemes are left as they are. */
#include "io/gltf/gltf.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "core/json.h"
#include "io/gltf/gltf_accessor.h"
#include "io/gltf/gltf_document.h"
#include "io/mitsuba_paths.h"
#include "core/xform.h"

enum {
    TARGET_ARRAY_BUFFER = 34962,
    TARGET_ELEMENT_ARRAY_BUFFER = 34963,
    MODE_TRIANGLES = 4,
    MODE_TRIANGLE_STRIP = 5,
    MODE_TRIANGLE_FAN = 6,
};

/* One node's use of one triangle primitive of its mesh (see the top of the file). */
typedef struct instance {
    int node;
    int primitive;
    xform world;
} instance;

/* A bundled copy: the file it copies and its name in outdir. */
typedef struct copy {
    char *source;
    char *name;
} copy;

typedef struct writer {
    const char *scene_file;
    const char *outdir;
    int bundle;
    gltf_document doc;
    cJSON **nodes; /* the document's nodes and meshes arrays, indexable */
    int node_count;
    cJSON **meshes;
    int mesh_count;
    instance *instances;
    size_t instance_count;
    int *visits; /* per node: how often the walk reached it */
    /* the new binary data: the buffer new bufferViews point to */
    unsigned char *bin;
    size_t bin_size, bin_capacity;
    int out_buffer;
    int keep_indices;   /* an extension with unknown references: nothing renumbered */
    int original_views; /* bufferViews before the new ones */
    int view_count;     /* bufferViews and accessors now (cJSON counts by walking its list) */
    int accessor_count;
    char dropped[16][48]; /* what replaced primitives lost, for one warning */
    int dropped_count;
    char *input_dir; /* the input's directory, absolute */
    char *outdir_real;
    copy *copies;
    size_t copy_count;
} writer;

/* ---- the document ---- */

/* A reference as an index into an array of `count`: an integer in [0, count), else -1. */
static int reference_index(const cJSON *reference, int count)
{
    double value = cJSON_IsNumber(reference) ? reference->valuedouble : -1;
    return value >= 0 && value < count && value == floor(value) ? (int)value : -1;
}

/* object[name] as an index (reference_index). */
static int index_of(const cJSON *object, const char *name, int count)
{
    return reference_index(cJSON_GetObjectItemCaseSensitive(object, name), count);
}

/* root[name] as a table of its items (NULL, 0 when it is no array). */
static cJSON **table_of(cJSON *root, const char *name, int *count)
{
    cJSON *array = cJSON_GetObjectItemCaseSensitive(root, name);
    *count = cJSON_IsArray(array) ? cJSON_GetArraySize(array) : 0;
    cJSON **items = xcalloc((size_t)*count + 1, sizeof *items);
    int i = 0;
    cJSON *item;
    if (*count)
        cJSON_ArrayForEach(item, array) items[i++] = item;
    return items;
}

/* root[name], an array made when missing. */
static cJSON *array_of(cJSON *root, const char *name)
{
    cJSON *array = cJSON_GetObjectItemCaseSensitive(root, name);
    if (!cJSON_IsArray(array)) {
        cJSON_DeleteItemFromObjectCaseSensitive(root, name);
        array = cJSON_AddArrayToObject(root, name);
    }
    return array;
}

/* Sets object[name] to the number `value` (replacing what was there). */
static void set_number(cJSON *object, const char *name, double value)
{
    cJSON *item = cJSON_GetObjectItemCaseSensitive(object, name);
    if (cJSON_IsNumber(item))
        cJSON_SetNumberValue(item, value);
    else if (item)
        cJSON_ReplaceItemInObjectCaseSensitive(object, name, cJSON_CreateNumber(value));
    else
        cJSON_AddNumberToObject(object, name, value);
}

static int is_triangle_mode(const cJSON *primitive)
{
    const cJSON *mode = cJSON_GetObjectItemCaseSensitive(primitive, "mode");
    double value = cJSON_IsNumber(mode) ? mode->valuedouble : MODE_TRIANGLES;
    return value == MODE_TRIANGLES || value == MODE_TRIANGLE_STRIP || value == MODE_TRIANGLE_FAN;
}

/* Adds node `node`'s instances, then its children's (see the top of the file). */
static int walk(writer *w, int node, const xform *parent, int depth, size_t *capacity)
{
    if (depth > w->node_count)
        return error_set(IDMR_EXIT_INPUT, "%s: nodes[%d]: the node hierarchy has a cycle",
                         w->scene_file, node);
    const cJSON *n = w->nodes[node];
    xform local = gltf_node_transform(n), world = xform_multiply(parent, &local);
    w->visits[node]++;
    int mesh = index_of(n, "mesh", w->mesh_count);
    const cJSON *primitives =
        cJSON_GetObjectItemCaseSensitive(w->meshes[mesh < 0 ? 0 : mesh], "primitives");
    const cJSON *item;
    int p = 0;
    if (mesh >= 0 && cJSON_IsArray(primitives))
        cJSON_ArrayForEach(item, primitives)
        {
            if (is_triangle_mode(item)) {
                if (w->instance_count == *capacity) {
                    *capacity = *capacity ? 2 * *capacity : 64;
                    w->instances = xrealloc(w->instances, *capacity * sizeof *w->instances);
                }
                w->instances[w->instance_count++] = (instance){node, p, world};
            }
            p++;
        }
    const cJSON *children = cJSON_GetObjectItemCaseSensitive(n, "children");
    if (cJSON_IsArray(children))
        cJSON_ArrayForEach(item, children)
        {
            int child = reference_index(item, w->node_count);
            if (child >= 0 && walk(w, child, &world, depth + 1, capacity))
                return -1;
        }
    return 0;
}

/* The instances of the default scene, in gltf_load's order. */
static int collect_instances(writer *w)
{
    cJSON *root = w->doc.json;
    w->nodes = table_of(root, "nodes", &w->node_count);
    w->meshes = table_of(root, "meshes", &w->mesh_count);
    w->visits = xcalloc((size_t)w->node_count + 1, sizeof *w->visits);
    int scene_count;
    cJSON **scenes = table_of(root, "scenes", &scene_count);
    const cJSON *scene_index = cJSON_GetObjectItemCaseSensitive(root, "scene");
    int chosen = cJSON_IsNumber(scene_index) ? index_of(root, "scene", scene_count) : 0;
    const cJSON *roots = chosen >= 0 && chosen < scene_count
                             ? cJSON_GetObjectItemCaseSensitive(scenes[chosen], "nodes")
                             : NULL;
    free(scenes);
    xform identity = xform_identity();
    size_t capacity = 0;
    const cJSON *item;
    if (cJSON_IsArray(roots))
        cJSON_ArrayForEach(item, roots)
        {
            int node = reference_index(item, w->node_count);
            if (node >= 0 && walk(w, node, &identity, 0, &capacity))
                return -1;
        }
    return 0;
}

/* ---- references between accessors, bufferViews and buffers ---- */

typedef void (*visit_fn)(cJSON *reference, void *context);

static void visit_members(cJSON *object, visit_fn visit, void *context)
{
    cJSON *item;
    if (cJSON_IsObject(object))
        cJSON_ArrayForEach(item, object) visit(item, context);
}

static void visit_member(cJSON *object, const char *name, visit_fn visit, void *context)
{
    cJSON *item = cJSON_GetObjectItemCaseSensitive(object, name);
    if (item)
        visit(item, context);
}

/* Every reference to an accessor in the core specification: primitives' attributes, indices
 * and morph targets, skins' inverse bind matrices, animation samplers' input and output. */
static void visit_accessor_references(cJSON *root, visit_fn visit, void *context)
{
    cJSON *mesh, *primitive, *target, *skin, *animation, *sampler;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItemCaseSensitive(root, "meshes"))
    {
        cJSON_ArrayForEach(primitive, cJSON_GetObjectItemCaseSensitive(mesh, "primitives"))
        {
            visit_members(cJSON_GetObjectItemCaseSensitive(primitive, "attributes"), visit,
                          context);
            visit_member(primitive, "indices", visit, context);
            cJSON_ArrayForEach(target, cJSON_GetObjectItemCaseSensitive(primitive, "targets"))
                visit_members(target, visit, context);
        }
    }
    cJSON_ArrayForEach(skin, cJSON_GetObjectItemCaseSensitive(root, "skins"))
        visit_member(skin, "inverseBindMatrices", visit, context);
    cJSON_ArrayForEach(animation, cJSON_GetObjectItemCaseSensitive(root, "animations"))
    {
        cJSON_ArrayForEach(sampler, cJSON_GetObjectItemCaseSensitive(animation, "samplers"))
        {
            visit_member(sampler, "input", visit, context);
            visit_member(sampler, "output", visit, context);
        }
    }
}

/* The bufferView references of one accessor (its data, a sparse accessor's indices and
 * values). */
static void visit_accessor_views(cJSON *accessor, visit_fn visit, void *context)
{
    visit_member(accessor, "bufferView", visit, context);
    cJSON *sparse = cJSON_GetObjectItemCaseSensitive(accessor, "sparse");
    visit_member(cJSON_GetObjectItemCaseSensitive(sparse, "indices"), "bufferView", visit, context);
    visit_member(cJSON_GetObjectItemCaseSensitive(sparse, "values"), "bufferView", visit, context);
}

/* Every reference to a bufferView: accessors' and images'. */
static void visit_view_references(cJSON *root, visit_fn visit, void *context)
{
    cJSON *accessor, *image;
    cJSON_ArrayForEach(accessor, cJSON_GetObjectItemCaseSensitive(root, "accessors"))
        visit_accessor_views(accessor, visit, context);
    cJSON_ArrayForEach(image, cJSON_GetObjectItemCaseSensitive(root, "images"))
        visit_member(image, "bufferView", visit, context);
}

static void visit_buffer_references(cJSON *root, visit_fn visit, void *context)
{
    cJSON *view;
    cJSON_ArrayForEach(view, cJSON_GetObjectItemCaseSensitive(root, "bufferViews"))
        visit_member(view, "buffer", visit, context);
}

typedef struct reference_check {
    int count;
    int bad;
} reference_check;

static void check_reference(cJSON *reference, void *context)
{
    reference_check *check = context;
    check->bad |= reference_index(reference, check->count) < 0;
}

static int array_size(cJSON *root, const char *name)
{
    cJSON *array = cJSON_GetObjectItemCaseSensitive(root, name);
    return cJSON_IsArray(array) ? cJSON_GetArraySize(array) : 0;
}

/* Whether every accessor, bufferView and buffer reference is an index that exists. */
static int references_valid(cJSON *root)
{
    reference_check accessors = {array_size(root, "accessors"), 0};
    reference_check views = {array_size(root, "bufferViews"), 0};
    reference_check buffers = {array_size(root, "buffers"), 0};
    visit_accessor_references(root, check_reference, &accessors);
    visit_view_references(root, check_reference, &views);
    visit_buffer_references(root, check_reference, &buffers);
    return !accessors.bad && !views.bad && !buffers.bad;
}

/* Extensions whose references to accessors, bufferViews and buffers the writer knows: none
 * (they name textures, images, materials, lights, or JSON pointers into objects that keep
 * their indices). */
static int extension_known(const char *name)
{
    static const char *const prefixes[] = {"KHR_materials_", "KHR_texture_", "EXT_texture_"};
    static const char *const names[] = {"KHR_lights_punctual", "KHR_mesh_quantization",
                                        "KHR_xmp_json_ld", "KHR_animation_pointer"};
    for (size_t i = 0; i < sizeof prefixes / sizeof *prefixes; i++)
        if (strncmp(name, prefixes[i], strlen(prefixes[i])) == 0)
            return 1;
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        if (strcmp(name, names[i]) == 0)
            return 1;
    return 0;
}

/* Whether any "extensions" object anywhere in `item`, or extensionsUsed, names an extension
 * extension_known() does not know. */
static int has_unknown_extension(const cJSON *item)
{
    const cJSON *child;
    const cJSON *extensions = cJSON_GetObjectItemCaseSensitive(item, "extensions");
    if (cJSON_IsObject(item) && cJSON_IsObject(extensions))
        cJSON_ArrayForEach(child, extensions)
        {
            if (!extension_known(child->string))
                return 1;
        }
    const cJSON *used = cJSON_GetObjectItemCaseSensitive(item, "extensionsUsed");
    if (cJSON_IsObject(item) && cJSON_IsArray(used))
        cJSON_ArrayForEach(child, used)
        {
            if (cJSON_IsString(child) && !extension_known(child->valuestring))
                return 1;
        }
    if (cJSON_IsObject(item) || cJSON_IsArray(item))
        cJSON_ArrayForEach(child, item)
        {
            if (has_unknown_extension(child))
                return 1;
        }
    return 0;
}

/* ---- the new binary data ---- */

/* Appends `size` bytes at a 4-byte boundary; returns their offset. */
static size_t append_bytes(writer *w, const void *bytes, size_t size)
{
    size_t offset = (w->bin_size + 3) & ~(size_t)3;
    if (offset + size > w->bin_capacity) {
        w->bin_capacity = 2 * (offset + size) + 1024;
        w->bin = xrealloc(w->bin, w->bin_capacity);
    }
    memset(w->bin + w->bin_size, 0, offset - w->bin_size);
    memcpy(w->bin + offset, bytes, size);
    w->bin_size = offset + size;
    return offset;
}

/* A new bufferView over `size` new bytes and an accessor of `count` elements over it; returns
 * the accessor's index, and the accessor in *made (may be NULL). */
static int add_accessor(writer *w, const void *bytes, size_t size, int target, int component,
                        int count, const char *type, cJSON **made)
{
    cJSON *accessors = array_of(w->doc.json, "accessors");
    cJSON *accessor = cJSON_CreateObject();
    cJSON *views = array_of(w->doc.json, "bufferViews");
    cJSON *view = cJSON_CreateObject();
    cJSON_AddNumberToObject(view, "buffer", w->out_buffer);
    cJSON_AddNumberToObject(view, "byteOffset", (double)append_bytes(w, bytes, size));
    cJSON_AddNumberToObject(view, "byteLength", (double)size);
    cJSON_AddNumberToObject(view, "target", target);
    cJSON_AddItemToArray(views, view);
    cJSON_AddNumberToObject(accessor, "bufferView", w->view_count++);
    cJSON_AddNumberToObject(accessor, "componentType", component);
    cJSON_AddNumberToObject(accessor, "count", count);
    cJSON_AddStringToObject(accessor, "type", type);
    cJSON_AddItemToArray(accessors, accessor);
    if (made)
        *made = accessor;
    return w->accessor_count++;
}

/* Adds `what` to the list of things replaced primitives lost, once; past 15 of them, the
 * list ends in "...". */
static void note_dropped(writer *w, const char *what)
{
    int max = (int)(sizeof w->dropped / sizeof *w->dropped);
    for (int i = 0; i < w->dropped_count; i++)
        if (strcmp(w->dropped[i], what) == 0)
            return;
    if (w->dropped_count < max) {
        snprintf(w->dropped[w->dropped_count], sizeof w->dropped[0], "%s",
                 w->dropped_count == max - 1 ? "..." : what);
        w->dropped_count++;
    }
}

/* ---- replacing primitives ---- */

/* Writes `reduced` (world space) into `primitive` in the space of instance `in`'s node. */
static int replace_primitive(writer *w, cJSON *primitive, const instance *in,
                             const mesh_data *reduced, int number)
{
    uint32_t n = reduced->vertex_count, t = reduced->triangle_count;
    if (n == 0 || t == 0)
        return error_set(IDMR_EXIT_FAILURE, "%s: mesh instance %d: the reduced mesh is empty",
                         w->scene_file, number);
    xform to_local;
    if (xform_invert_affine(&in->world, &to_local))
        return error_set(IDMR_EXIT_INPUT,
                         "%s: nodes[%d]: its world transform is singular: its mesh cannot be "
                         "written back in its space",
                         w->scene_file, in->node);
    const double *m = in->world.m;
    int mirrored = xform_determinant3(&in->world) < 0;
    float *values = xmalloc(sizeof(float) * 3 * (size_t)n);
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < n; v++) {
        const float *p = &reduced->positions[3 * (size_t)v];
        double world[3] = {p[0], p[1], p[2]}, local[3];
        xform_apply_point(&to_local, world, local);
        for (int k = 0; k < 3; k++) {
            float value = (float)local[k];
            values[3 * (size_t)v + k] = value;
            low[k] = fmin(low[k], value), high[k] = fmax(high[k], value);
        }
    }
    if (!(isfinite(low[0]) && isfinite(low[1]) && isfinite(low[2]) && isfinite(high[0]) &&
          isfinite(high[1]) && isfinite(high[2]))) {
        free(values);
        return error_set(IDMR_EXIT_FAILURE,
                         "%s: mesh instance %d: the reduced mesh has a position that is not "
                         "finite",
                         w->scene_file, number);
    }
    cJSON *attributes = cJSON_CreateObject();
    cJSON *accessor;
    int position = add_accessor(w, values, sizeof(float) * 3 * n, TARGET_ARRAY_BUFFER,
                                GLTF_FLOAT, (int)n, "VEC3", &accessor);
    cJSON_AddItemToObject(accessor, "min", cJSON_CreateDoubleArray(low, 3));
    cJSON_AddItemToObject(accessor, "max", cJSON_CreateDoubleArray(high, 3));
    cJSON_AddNumberToObject(attributes, "POSITION", position);
    if (reduced->normals) {
        /* world normals are the inverse transpose of the linear part L times the local ones:
         * local = Lᵀ world, normalised */
        for (uint32_t v = 0; v < n; v++) {
            const float *q = &reduced->normals[3 * (size_t)v];
            double local[3];
            for (int k = 0; k < 3; k++)
                local[k] = m[k] * q[0] + m[4 + k] * q[1] + m[8 + k] * q[2];
            if (!(xform_normalize(local) > 0 && isfinite(local[0] + local[1] + local[2])))
                local[0] = 0, local[1] = 0, local[2] = 1; /* a unit vector, as glTF asks */
            for (int k = 0; k < 3; k++)
                values[3 * (size_t)v + k] = (float)local[k];
        }
        cJSON_AddNumberToObject(attributes, "NORMAL",
                                add_accessor(w, values, sizeof(float) * 3 * n, TARGET_ARRAY_BUFFER,
                                             GLTF_FLOAT, (int)n, "VEC3", NULL));
    }
    free(values);
    if (reduced->texcoords)
        cJSON_AddNumberToObject(attributes, "TEXCOORD_0",
                                add_accessor(w, reduced->texcoords, sizeof(float) * 2 * n,
                                             TARGET_ARRAY_BUFFER, GLTF_FLOAT, (int)n, "VEC2",
                                             NULL));
    /* indices: unsigned short while every index is below 65,535 (glTF reserves the largest
     * value of the type) */
    int wide = n > 65535;
    size_t index_size = wide ? 4 : 2;
    unsigned char *indices = xmalloc(index_size * 3 * (size_t)t);
    for (uint32_t k = 0; k < 3 * t; k++) {
        uint32_t corner = k % 3 == 0 || !mirrored ? k : k % 3 == 1 ? k + 1 : k - 1;
        uint32_t index = reduced->indices[corner];
        if (wide)
            memcpy(indices + 4 * (size_t)k, &index, 4);
        else
            memcpy(indices + 2 * (size_t)k, &(uint16_t){(uint16_t)index}, 2);
    }
    int index_accessor = add_accessor(w, indices, index_size * 3 * t, TARGET_ELEMENT_ARRAY_BUFFER,
                                      wide ? GLTF_UNSIGNED_INT : GLTF_UNSIGNED_SHORT,
                                      (int)(3 * t), "SCALAR", NULL);
    free(indices);
    /* what the primitive had that no longer matches its vertices */
    const cJSON *old = cJSON_GetObjectItemCaseSensitive(primitive, "attributes"), *item;
    cJSON_ArrayForEach(
        item, old) if (strcmp(item->string, "POSITION") && strcmp(item->string, "NORMAL") &&
                       strcmp(item->string, "TEXCOORD_0")) note_dropped(w, item->string);
    cJSON *targets = cJSON_GetObjectItemCaseSensitive(primitive, "targets");
    if (cJSON_IsArray(targets) && cJSON_GetArraySize(targets) > 0) {
        /* as many targets as before (the mesh's other primitives, its weights and animations
         * count them), each moving nothing: zero displacements, written out (an accessor
         * without a bufferView is zeros too, but Assimp 5.2 refuses to read one) */
        note_dropped(w, "morph target displacements");
        cJSON *zeros;
        float *nothing = xcalloc(3 * (size_t)n, sizeof(float));
        int zero = add_accessor(w, nothing, sizeof(float) * 3 * n, TARGET_ARRAY_BUFFER,
                                GLTF_FLOAT, (int)n, "VEC3", &zeros);
        free(nothing);
        const double origin[3] = {0, 0, 0};
        cJSON_AddItemToObject(zeros, "min", cJSON_CreateDoubleArray(origin, 3));
        cJSON_AddItemToObject(zeros, "max", cJSON_CreateDoubleArray(origin, 3));
        cJSON *still = cJSON_CreateArray();
        for (int i = cJSON_GetArraySize(targets); i > 0; i--) {
            cJSON *target = cJSON_CreateObject();
            cJSON_AddNumberToObject(target, "POSITION", zero);
            cJSON_AddItemToArray(still, target);
        }
        cJSON_ReplaceItemInObjectCaseSensitive(primitive, "targets", still);
    }
    cJSON *extensions = cJSON_GetObjectItemCaseSensitive(primitive, "extensions");
    if (cJSON_GetObjectItemCaseSensitive(extensions, "KHR_draco_mesh_compression")) {
        note_dropped(w, "Draco data");
        cJSON_DeleteItemFromObjectCaseSensitive(extensions, "KHR_draco_mesh_compression");
        if (!extensions->child)
            cJSON_DeleteItemFromObjectCaseSensitive(primitive, "extensions");
    }
    if (cJSON_GetObjectItemCaseSensitive(primitive, "attributes"))
        cJSON_ReplaceItemInObjectCaseSensitive(primitive, "attributes", attributes);
    else
        cJSON_AddItemToObject(primitive, "attributes", attributes);
    set_number(primitive, "indices", index_accessor);
    cJSON_DeleteItemFromObjectCaseSensitive(primitive, "mode");
    return 0;
}

/* Whether any mesh primitive still names extension `name`. */
static int primitives_use(cJSON *root, const char *name)
{
    cJSON *mesh, *primitive;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItemCaseSensitive(root, "meshes"))
    {
        cJSON_ArrayForEach(primitive, cJSON_GetObjectItemCaseSensitive(mesh, "primitives"))
        {
            cJSON *extensions = cJSON_GetObjectItemCaseSensitive(primitive, "extensions");
            if (cJSON_GetObjectItemCaseSensitive(extensions, name))
                return 1;
        }
    }
    return 0;
}

/* Removes `name` from extensionsUsed and extensionsRequired (an empty list with it). */
static void unlist_extension(cJSON *root, const char *name)
{
    const char *lists[2] = {"extensionsUsed", "extensionsRequired"};
    for (int l = 0; l < 2; l++) {
        cJSON *list = cJSON_GetObjectItemCaseSensitive(root, lists[l]), *item = NULL;
        cJSON_ArrayForEach(item, list)
        {
            if (cJSON_IsString(item) && strcmp(item->valuestring, name) == 0)
                break;
        }
        if (item)
            cJSON_Delete(cJSON_DetachItemViaPointer(list, item));
        if (list && !list->child)
            cJSON_DeleteItemFromObjectCaseSensitive(root, lists[l]);
    }
}

/* Gives each node with replaced instances the mesh it writes into (see the top of the file),
 * then writes each replacement. */
static int replace_instances(writer *w, const gltf_replacement *replacements, size_t count)
{
    int *replaced = xcalloc((size_t)w->node_count + 1, sizeof *replaced);
    int *shared = xcalloc((size_t)w->node_count + 1, sizeof *shared);
    int *target_index = xcalloc((size_t)w->node_count + 1, sizeof *target_index);
    int *named = xcalloc((size_t)w->node_count + 1, sizeof *named); /* its mesh in the input */
    int *users = xcalloc((size_t)w->mesh_count + 1, sizeof *users);
    int *replaced_users = xcalloc((size_t)w->mesh_count + 1, sizeof *replaced_users);
    char *claimed = xcalloc((size_t)w->mesh_count + 1, 1);
    cJSON **target = xcalloc((size_t)w->node_count + 1, sizeof *target);
    int status = 0;
    for (size_t r = 0; r < count; r++) {
        replaced[w->instances[replacements[r].instance].node]++;
        shared[w->instances[replacements[r].instance].node] += replacements[r].shared != 0;
    }
    for (int node = 0; node < w->node_count; node++) {
        int mesh = named[node] = index_of(w->nodes[node], "mesh", w->mesh_count);
        if (mesh < 0)
            continue;
        users[mesh]++;
        replaced_users[mesh] += replaced[node] > 0;
        if (replaced[node] && w->visits[node] > 1 && !status)
            status = error_set(IDMR_EXIT_INPUT,
                               "%s: nodes[%d] is reached %d times from the scene's roots (a "
                               "node may have one parent): its reduced meshes cannot be "
                               "written",
                               w->scene_file, node, w->visits[node]);
    }
    /* copies first, all of unchanged meshes */
    cJSON *meshes = cJSON_GetObjectItemCaseSensitive(w->doc.json, "meshes");
    int mesh_count = w->mesh_count;
    for (int node = 0; node < w->node_count && !status; node++) {
        if (!replaced[node] || shared[node] == replaced[node])
            continue;
        int mesh = index_of(w->nodes[node], "mesh", w->mesh_count);
        if (replaced_users[mesh] == users[mesh] && !claimed[mesh]) {
            claimed[mesh] = 1;
            target[node] = w->meshes[mesh];
            target_index[node] = mesh;
        } else {
            target[node] = cJSON_Duplicate(w->meshes[mesh], 1);
            cJSON_AddItemToArray(meshes, target[node]);
            target_index[node] = mesh_count;
            set_number(w->nodes[node], "mesh", mesh_count++);
        }
    }
    /* nodes whose replacements are all shared: the mesh of the node naming the same mesh that
     * writes the reduction */
    for (int node = 0; node < w->node_count && !status; node++) {
        if (!replaced[node] || shared[node] != replaced[node])
            continue;
        int mesh = named[node], writer_node = -1;
        for (int other = 0; other < w->node_count && writer_node < 0; other++)
            if (target[other] && shared[other] != replaced[other] && named[other] == mesh)
                writer_node = other;
        if (writer_node < 0)
            status = error_set(IDMR_EXIT_FAILURE,
                               "%s: nodes[%d]: its meshes[%d] is shared with a reduction no "
                               "other node writes",
                               w->scene_file, node, mesh);
        else
            set_number(w->nodes[node], "mesh", target_index[writer_node]);
    }
    for (size_t r = 0; r < count && !status; r++) {
        if (replacements[r].shared)
            continue;
        const instance *in = &w->instances[replacements[r].instance];
        cJSON *primitive = cJSON_GetArrayItem(
            cJSON_GetObjectItemCaseSensitive(target[in->node], "primitives"), in->primitive);
        status =
            replace_primitive(w, primitive, in, replacements[r].mesh, replacements[r].instance);
    }
    /* Draco data went with the primitives replaced: once none is left, no reader needs it */
    if (!status && !primitives_use(w->doc.json, "KHR_draco_mesh_compression"))
        unlist_extension(w->doc.json, "KHR_draco_mesh_compression");
    for (int node = 0; node < w->node_count && !status; node++) {
        if (!replaced[node])
            continue;
        if (cJSON_GetObjectItemCaseSensitive(w->nodes[node], "skin")) {
            note_dropped(w, "skins");
            cJSON_DeleteItemFromObjectCaseSensitive(w->nodes[node], "skin");
        }
    }
    free(target);
    free(target_index);
    free(named);
    free(shared);
    free(claimed);
    free(replaced_users);
    free(users);
    free(replaced);
    return status;
}

/* ---- dropping what is no longer used ---- */

typedef struct index_map {
    int count;
    int *used; /* per old index: referenced; then its new index, or -1 */
} index_map;

static void mark_reference(cJSON *reference, void *context)
{
    index_map *map = context;
    int index = reference_index(reference, map->count);
    if (index >= 0)
        map->used[index] = 1;
}

static void renumber_reference(cJSON *reference, void *context)
{
    index_map *map = context;
    int index = reference_index(reference, map->count);
    if (index >= 0)
        cJSON_SetNumberValue(reference, map->used[index]);
}

/* map->used: 1 for kept, 0 for dropped → the new index of each kept one, -1 for the others;
 * the array root[name] keeps only the kept items. */
static void drop_unused(cJSON *root, const char *name, index_map *map)
{
    cJSON *array = cJSON_GetObjectItemCaseSensitive(root, name);
    cJSON *kept = cJSON_CreateArray();
    int next = 0;
    for (int i = 0; i < map->count; i++) {
        cJSON *item = cJSON_DetachItemFromArray(array, 0);
        if (map->used[i]) {
            map->used[i] = next++;
            cJSON_AddItemToArray(kept, item);
        } else {
            map->used[i] = -1;
            cJSON_Delete(item);
        }
    }
    if (next)
        cJSON_ReplaceItemInObjectCaseSensitive(root, name, kept);
    else {
        cJSON_Delete(kept);
        cJSON_DeleteItemFromObjectCaseSensitive(root, name);
    }
}

/* Drops the accessors and bufferViews nothing references and moves the bytes of the kept
 * views of the input into the new buffer (after the new data), which becomes the only one. */
static int collect_garbage(writer *w)
{
    cJSON *root = w->doc.json;
    index_map accessors = {array_size(root, "accessors"), NULL};
    accessors.used = xcalloc((size_t)accessors.count + 1, sizeof *accessors.used);
    visit_accessor_references(root, mark_reference, &accessors);
    index_map views = {array_size(root, "bufferViews"), NULL};
    views.used = xcalloc((size_t)views.count + 1, sizeof *views.used);
    cJSON *accessor, *image, *view;
    int i = 0;
    cJSON_ArrayForEach(accessor, cJSON_GetObjectItemCaseSensitive(root, "accessors"))
    {
        if (accessors.used[i++])
            visit_accessor_views(accessor, mark_reference, &views);
    }
    cJSON_ArrayForEach(image, cJSON_GetObjectItemCaseSensitive(root, "images"))
        visit_member(image, "bufferView", mark_reference, &views);
    cJSON *buffers = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    int status = 0;
    i = 0;
    cJSON_ArrayForEach(view, cJSON_GetObjectItemCaseSensitive(root, "bufferViews"))
    {
        if (!views.used[i] || i >= w->original_views) {
            i++;
            continue;
        }
        int buffer = index_of(view, "buffer", w->doc.buffer_count);
        const gltf_bytes *bytes =
            gltf_document_buffer(&w->doc, buffer, cJSON_GetArrayItem(buffers, buffer));
        const cJSON *offset_item = cJSON_GetObjectItemCaseSensitive(view, "byteOffset");
        const cJSON *length_item = cJSON_GetObjectItemCaseSensitive(view, "byteLength");
        double offset = cJSON_IsNumber(offset_item) ? offset_item->valuedouble : 0;
        double length = cJSON_IsNumber(length_item) ? length_item->valuedouble : -1;
        if (!bytes) {
            status = -1;
            break;
        }
        if (!(offset >= 0 && length >= 0 && offset + length <= (double)bytes->size)) {
            status = error_set(IDMR_EXIT_INPUT,
                               "%s: bufferViews[%d]: bytes %.0f to %.0f lie outside its buffer "
                               "(%zu bytes)",
                               w->scene_file, i, offset, offset + length, bytes->size);
            break;
        }
        set_number(view, "byteOffset",
                   (double)append_bytes(w, bytes->data + (size_t)offset, (size_t)length));
        set_number(view, "buffer", 0);
        i++;
    }
    if (!status) {
        drop_unused(root, "accessors", &accessors);
        drop_unused(root, "bufferViews", &views);
        visit_accessor_references(root, renumber_reference, &accessors);
        visit_view_references(root, renumber_reference, &views);
        cJSON_DeleteItemFromObjectCaseSensitive(root, "buffers");
        if (w->bin_size) {
            cJSON *buffer = cJSON_CreateObject();
            cJSON_AddNumberToObject(buffer, "byteLength", (double)w->bin_size);
            cJSON_AddItemToArray(cJSON_AddArrayToObject(root, "buffers"), buffer);
        }
    }
    free(views.used);
    free(accessors.used);
    return status;
}

/* ---- paths ---- */

static int copy_name_taken(const char *name, const void *context)
{
    const writer *w = context;
    for (size_t i = 0; i < w->copy_count; i++)
        if (strcmp(w->copies[i].name, name) == 0)
            return 1;
    return 0;
}

/* object.uri, a file relative to the input, rewritten (see the top of the file). */
static int rewrite_uri(writer *w, cJSON *object)
{
    cJSON *uri = cJSON_GetObjectItemCaseSensitive(object, "uri");
    if (!cJSON_IsString(uri) || gltf_uri_has_scheme(uri->valuestring))
        return 0;
    char *decoded = gltf_uri_decode(uri->valuestring);
    if (!w->bundle && decoded[0] == '/') {
        free(decoded);
        return 0;
    }
    char *joined = mitsuba_path_join(w->input_dir, decoded);
    char *real = mitsuba_path_real(joined);
    char *source = real ? real : joined, *name = NULL;
    int status = 0;
    if (w->bundle) {
        for (size_t i = 0; i < w->copy_count && !name; i++)
            if (strcmp(w->copies[i].source, source) == 0)
                name = xstrdup(w->copies[i].name);
        if (!name) {
            name = mitsuba_path_unique("assets", source, copy_name_taken, w);
            size_t size = strlen(w->outdir) + strlen(name) + 16;
            char *assets = xmalloc(size), *target = xmalloc(size);
            snprintf(assets, size, "%s/assets", w->outdir);
            snprintf(target, size, "%s/%s", w->outdir, name);
            status = files_make_directory(assets);
            if (!status)
                status = files_copy_atomic(source, target);
            free(target);
            free(assets);
            w->copies = xrealloc(w->copies, (w->copy_count + 1) * sizeof *w->copies);
            w->copies[w->copy_count++] = (copy){xstrdup(source), xstrdup(name)};
        }
    } else {
        name = w->outdir_real ? mitsuba_path_relative(w->outdir_real, source) : NULL;
        if (!name)
            name = xstrdup(source);
    }
    char *encoded = gltf_uri_encode(name);
    cJSON_ReplaceItemInObjectCaseSensitive(object, "uri", cJSON_CreateString(encoded));
    free(encoded);
    free(name);
    free(real);
    free(joined);
    free(decoded);
    return status;
}

/* Every uri in `item` (images', kept buffers', those of extensions such as shaders' or audio
 * sources'), none inside extras, which are the application's own. */
static int rewrite_uris(writer *w, cJSON *item)
{
    cJSON *child;
    if (cJSON_IsObject(item) && cJSON_IsString(cJSON_GetObjectItemCaseSensitive(item, "uri")) &&
        rewrite_uri(w, item))
        return -1;
    if (cJSON_IsObject(item) || cJSON_IsArray(item))
        cJSON_ArrayForEach(child, item)
        {
            if (!(child->string && strcmp(child->string, "extras") == 0) && rewrite_uris(w, child))
                return -1;
        }
    return 0;
}

/* ---- the writer ---- */

/* Where new data goes (see the top of the file): the new buffer 0 when unused data is dropped;
 * else the input .glb's BIN buffer, extended, or a new buffer after the input's. */
static int choose_output_buffer(writer *w)
{
    cJSON *root = w->doc.json;
    w->original_views = w->view_count = array_size(root, "bufferViews");
    w->accessor_count = array_size(root, "accessors");
    w->keep_indices = has_unknown_extension(root) || !references_valid(root);
    w->out_buffer = 0;
    if (!w->keep_indices)
        return 0;
    cJSON *buffers = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    cJSON *first = cJSON_GetArrayItem(buffers, 0);
    if (w->doc.binary && first && !cJSON_GetObjectItemCaseSensitive(first, "uri") &&
        w->doc.bin.data) {
        const gltf_bytes *bytes = gltf_document_buffer(&w->doc, 0, first);
        if (!bytes)
            return -1;
        append_bytes(w, bytes->data, bytes->size);
    } else {
        w->out_buffer = array_size(root, "buffers");
    }
    return 0;
}

/* The new data's buffer in the document: its byteLength, and a uri when it is not a .glb's
 * BIN chunk (then *external is set). */
static void finish_output_buffer(writer *w, const char *bin_name, int *external)
{
    cJSON *root = w->doc.json;
    *external = 0;
    if (!w->bin_size)
        return;
    cJSON *buffers = array_of(root, "buffers");
    cJSON *buffer = cJSON_GetArrayItem(buffers, w->out_buffer);
    if (!buffer) {
        buffer = cJSON_CreateObject();
        cJSON_AddItemToArray(buffers, buffer);
    }
    set_number(buffer, "byteLength", (double)w->bin_size);
    if (!w->doc.binary || w->out_buffer != 0) {
        *external = 1;
        cJSON_DeleteItemFromObjectCaseSensitive(buffer, "uri");
        cJSON_AddStringToObject(buffer, "uri", bin_name);
    }
}

static void warn_dropped(const writer *w)
{
    char list[1024] = "";
    for (int i = 0; i < w->dropped_count; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "",
                 w->dropped[i]);
    if (w->dropped_count)
        warn("%s: reduced meshes are written without their %s (they no longer match the "
             "vertices)",
             w->scene_file, list);
}

/* Checks the replacements against the instances: each one that exists, none twice. */
static int check_replacements(const writer *w, const gltf_replacement *replacements, size_t count)
{
    char *seen = xcalloc(w->instance_count + 1, 1);
    int status = 0;
    for (size_t r = 0; r < count && !status; r++) {
        int number = replacements[r].instance;
        if (number < 0 || (size_t)number >= w->instance_count || seen[number])
            status = error_set(IDMR_EXIT_INPUT,
                               "%s: mesh instance %d is not in the file, or replaced twice "
                               "(the file changed since it was read?)",
                               w->scene_file, number);
        else
            seen[number] = 1;
    }
    free(seen);
    return status;
}

static int write_outputs(writer *w)
{
    const char *output = gltf_output_name(w->scene_file);
    size_t size = strlen(w->outdir) + 32;
    char *path = xmalloc(size), *bin_path = xmalloc(size);
    snprintf(path, size, "%s/%s", w->outdir, output);
    snprintf(bin_path, size, "%s/scene.bin", w->outdir);
    int external, status;
    finish_output_buffer(w, "scene.bin", &external);
    gltf_numbers_exact(w->doc.json);
    status = external ? files_write_atomic(bin_path, w->bin, w->bin_size) : 0;
    if (!status)
        status = w->doc.binary
                     ? gltf_write_glb(path, w->doc.json, w->bin, external ? 0 : w->bin_size)
                     : json_write(w->doc.json, path);
    free(bin_path);
    free(path);
    return status;
}

int gltf_write_reduced(const char *scene_file, const char *outdir,
                       const gltf_replacement *replacements, size_t count, int bundle)
{
    writer w;
    memset(&w, 0, sizeof w);
    w.scene_file = scene_file;
    w.outdir = outdir;
    w.bundle = bundle;
    if (gltf_document_read(scene_file, &w.doc)) /* refuses a .glb that is none, and back */
        return -1;
    char *input_dir = mitsuba_path_directory(scene_file);
    w.input_dir = mitsuba_path_real(*input_dir ? input_dir : ".");
    if (!w.input_dir)
        w.input_dir = xstrdup(input_dir);
    free(input_dir);
    w.outdir_real = mitsuba_path_real(outdir);
    int status = collect_instances(&w);
    if (!status)
        status = check_replacements(&w, replacements, count);
    if (!status)
        status = choose_output_buffer(&w);
    if (!status)
        status = replace_instances(&w, replacements, count);
    if (!status && !w.keep_indices)
        status = collect_garbage(&w);
    if (!status)
        status = rewrite_uris(&w, w.doc.json);
    if (!status)
        status = write_outputs(&w);
    if (!status)
        warn_dropped(&w);
    for (size_t i = 0; i < w.copy_count; i++)
        free(w.copies[i].source), free(w.copies[i].name);
    free(w.copies);
    free(w.outdir_real);
    free(w.input_dir);
    free(w.bin);
    free(w.visits);
    free(w.instances);
    free(w.meshes);
    free(w.nodes);
    gltf_document_free(&w.doc);
    return status;
}
