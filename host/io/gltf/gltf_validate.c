/* gltf_validate.c — a glTF 2.0 document checked before Assimp reads it (see gltf_validate.h).
 *
 * The checks run in the order of the references: the document's shape and extensions, buffers,
 * bufferViews, accessors (each resolved to a gltf_accessor), then what refers to them: meshes
 * and their primitives (index values read), nodes and scenes, cameras, lights, materials,
 * skins and animations. Each check names the first fault it finds and stops. */
#include "io/gltf/gltf_validate.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"

enum { POINTER = 256 };

/* The top-level arrays of objects, indexable. */
typedef struct table {
    const char *name; /* as the document names the array */
    const char *what; /* its items, for messages ("meshes") */
    cJSON **items;
    int count;
} table;

enum {
    T_ACCESSORS,
    T_ANIMATIONS,
    T_BUFFERS,
    T_VIEWS,
    T_CAMERAS,
    T_IMAGES,
    T_MATERIALS,
    T_MESHES,
    T_NODES,
    T_SAMPLERS,
    T_SCENES,
    T_SKINS,
    T_TEXTURES,
    T_LIGHTS, /* extensions.KHR_lights_punctual.lights */
    TABLES
};

typedef struct checker {
    gltf_document *doc;
    const char *path;
    cJSON *root;
    table tables[TABLES];
    double *buffer_length; /* per buffer: its byteLength */
    gltf_accessor *accessors;
    int *parent; /* per node: its parent, -1 for none */
    progress *bar; /* may be NULL */
} checker;

/* One more unit of work done (`amount`: units). */
static void advance(const checker *c, unsigned amount)
{
    if (c->bar)
        progress_advance(c->bar, amount, NULL);
}

/* ---- messages ---- */

/* Sets the error "file: pointer: message"; returns -1. */
static int bad(const checker *c, const char *pointer, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int bad(const checker *c, const char *pointer, const char *fmt, ...)
{
    char message[1024];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    return error_set(IDMR_EXIT_INPUT, "%s: %s: %s", c->path, pointer, message);
}

/* Writes a JSON pointer into `out` (POINTER bytes); returns it. */
static const char *at(char *out, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static const char *at(char *out, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(out, POINTER, fmt, args);
    va_end(args);
    return out;
}

/* A JSON value in a few words, for messages: its text for numbers and short strings. */
static const char *shown(const cJSON *item, char *out, size_t size)
{
    if (!item)
        snprintf(out, size, "missing");
    else if (cJSON_IsNumber(item))
        snprintf(out, size, "%.17g", item->valuedouble);
    else if (cJSON_IsString(item))
        snprintf(out, size, "\"%.40s%s\"", item->valuestring,
                 strlen(item->valuestring) > 40 ? "..." : "");
    else
        snprintf(out, size, "%s",
                 cJSON_IsBool(item)     ? "a boolean"
                 : cJSON_IsNull(item)   ? "null"
                 : cJSON_IsArray(item)  ? "an array"
                 : cJSON_IsObject(item) ? "an object"
                                        : "not a value");
    return out;
}

/* ---- members ---- */

static cJSON *member(const cJSON *object, const char *name)
{
    return cJSON_IsObject(object) ? cJSON_GetObjectItemCaseSensitive(object, name) : NULL;
}

/* object[name] as an integer in [low, high]: *out, or `fallback` when absent and not
 * `required`. pointer: the object's. */
static int integer_member(const checker *c, const cJSON *object, const char *pointer,
                          const char *name, double low, double high, int required,
                          double fallback, double *out)
{
    const cJSON *item = member(object, name);
    char where[POINTER], text[64];
    *out = fallback;
    if (!item) {
        if (required)
            return bad(c, at(where, "%s/%s", pointer, name), "missing (it is required)");
        return 0;
    }
    double value = cJSON_IsNumber(item) ? item->valuedouble : NAN;
    if (!(value == floor(value) && value >= low && value <= high))
        return bad(c, at(where, "%s/%s", pointer, name), "%s is not an integer from %.0f to %.0f",
                   shown(item, text, sizeof text), low, high);
    *out = value;
    return 0;
}

/* object[name] as a reference into table `t`: its index in *out, or -1 when absent and not
 * `required`. */
static int reference_member(const checker *c, const cJSON *object, const char *pointer,
                            const char *name, int t, int required, int *out)
{
    const cJSON *item = member(object, name);
    const table *target = &c->tables[t];
    char where[POINTER], text[64];
    *out = -1;
    if (!item) {
        if (required)
            return bad(c, at(where, "%s/%s", pointer, name), "missing (it is required)");
        return 0;
    }
    double value = cJSON_IsNumber(item) ? item->valuedouble : NAN;
    if (!(value == floor(value) && value >= 0))
        return bad(c, at(where, "%s/%s", pointer, name), "%s is not an index into %s",
                   shown(item, text, sizeof text), target->name);
    if (value >= target->count)
        return bad(c, at(where, "%s/%s", pointer, name), "%.0f, but the file has %d %s", value,
                   target->count, target->what);
    *out = (int)value;
    return 0;
}

/* An array item as a reference into table `t` (its index in *out). */
static int reference_item(const checker *c, const cJSON *item, const char *pointer, int t,
                          int *out)
{
    const table *target = &c->tables[t];
    char text[64];
    double value = cJSON_IsNumber(item) ? item->valuedouble : NAN;
    if (!(value == floor(value) && value >= 0))
        return bad(c, pointer, "%s is not an index into %s", shown(item, text, sizeof text),
                   target->name);
    if (value >= target->count)
        return bad(c, pointer, "%.0f, but the file has %d %s", value, target->count,
                   target->what);
    *out = (int)value;
    return 0;
}

/* object[name] as a finite number (fallback when absent): *out. */
static int number_member(const checker *c, const cJSON *object, const char *pointer,
                         const char *name, double fallback, double *out)
{
    const cJSON *item = member(object, name);
    char where[POINTER], text[64];
    *out = fallback;
    if (!item)
        return 0;
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble))
        return bad(c, at(where, "%s/%s", pointer, name), "%s is not a number",
                   shown(item, text, sizeof text));
    *out = item->valuedouble;
    return 0;
}

/* object[name], when present, as exactly `count` finite numbers into values. *present says
 * whether it was there. */
static int numbers_member(const checker *c, const cJSON *object, const char *pointer,
                          const char *name, int count, double *values, int *present)
{
    const cJSON *array = member(object, name), *item;
    char where[POINTER];
    *present = array != NULL;
    if (!array)
        return 0;
    if (!cJSON_IsArray(array) || cJSON_GetArraySize(array) != count)
        return bad(c, at(where, "%s/%s", pointer, name), "not an array of %d numbers", count);
    int i = 0;
    cJSON_ArrayForEach(item, array)
    {
        if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble))
            return bad(c, at(where, "%s/%s/%d", pointer, name, i), "not a finite number");
        values[i++] = item->valuedouble;
    }
    return 0;
}

/* object[name], when present, must be a string: *out (NULL when absent). */
static int string_member(const checker *c, const cJSON *object, const char *pointer,
                         const char *name, const char **out)
{
    const cJSON *item = member(object, name);
    char where[POINTER];
    *out = NULL;
    if (!item)
        return 0;
    if (!cJSON_IsString(item))
        return bad(c, at(where, "%s/%s", pointer, name), "not a string");
    *out = item->valuestring;
    return 0;
}

/* object[name], when present, must be an object (or, with `array`, an array). */
static int shaped_member(const checker *c, const cJSON *object, const char *pointer,
                         const char *name, int array, cJSON **out)
{
    cJSON *item = member(object, name);
    char where[POINTER];
    *out = item;
    if (item && (array ? !cJSON_IsArray(item) : !cJSON_IsObject(item)))
        return bad(c, at(where, "%s/%s", pointer, name), "not an %s", array ? "array" : "object");
    return 0;
}

/* ---- the document's shape ---- */

/* Writes a member name into a JSON pointer (~ as ~0, / as ~1). */
static void pointer_append(char *pointer, const char *name)
{
    size_t length = strlen(pointer);
    if (length + 1 < POINTER)
        pointer[length++] = '/';
    for (const char *n = name; *n && length + 2 < POINTER; n++) {
        if (*n == '~' || *n == '/') {
            pointer[length++] = '~';
            pointer[length++] = *n == '~' ? '0' : '1';
        } else {
            pointer[length++] = *n;
        }
    }
    pointer[length] = '\0';
}

static int compare_names(const void *a, const void *b)
{
    return strcmp((*(cJSON *const *)a)->string, (*(cJSON *const *)b)->string);
}

/* No object anywhere in `item` (whose pointer is `pointer`) names a member twice (glTF: names
 * within an object are unique; readers would take either), and outside extras (the
 * application's own, `in_extras`) every "extensions" member is an object of objects. */
static int json_shape(const checker *c, const cJSON *item, char *pointer, int in_extras)
{
    size_t length = strlen(pointer);
    int count = 0, index = 0, status = 0;
    const cJSON *child;
    cJSON_ArrayForEach(child, item) count++;
    if (cJSON_IsObject(item) && count > 1) {
        cJSON **names = xmalloc(sizeof *names * (size_t)count);
        cJSON_ArrayForEach(child, item) names[index++] = (cJSON *)child;
        qsort(names, (size_t)count, sizeof *names, compare_names);
        for (int i = 1; i < count && !status; i++)
            if (strcmp(names[i - 1]->string, names[i]->string) == 0) {
                pointer_append(pointer, names[i]->string);
                status = bad(c, pointer, "a member named twice in one object");
            }
        free(names);
    }
    const cJSON *extensions = in_extras ? NULL : member(item, "extensions"), *extension;
    if (!status && extensions) {
        pointer_append(pointer, "extensions");
        if (!cJSON_IsObject(extensions))
            return bad(c, pointer, "not an object (extensions are objects by their names)");
        cJSON_ArrayForEach(extension, extensions)
        {
            if (!cJSON_IsObject(extension)) {
                pointer_append(pointer, extension->string);
                return bad(c, pointer, "not an object (each extension is one)");
            }
        }
        pointer[length] = '\0';
    }
    index = 0;
    if (cJSON_IsObject(item) || cJSON_IsArray(item))
        cJSON_ArrayForEach(child, item)
        {
            if (status)
                break;
            if (!child->child) { /* a number or a string: nothing inside */
                index++;
                continue;
            }
            if (cJSON_IsObject(item)) {
                pointer_append(pointer, child->string);
            } else {
                char number[16];
                snprintf(number, sizeof number, "%d", index);
                pointer_append(pointer, number);
            }
            int extras = in_extras || (cJSON_IsObject(item) && strcmp(child->string, "extras") == 0);
            status = json_shape(c, child, pointer, extras);
            if (!status)
                pointer[length] = '\0';
            index++;
        }
    return status;
}

/* Table t from root[name] (or, for lights, the KHR_lights_punctual extension): an array of
 * objects, or absent. */
static int read_table(checker *c, int t, const cJSON *parent, const char *parent_pointer)
{
    table *tb = &c->tables[t];
    const cJSON *array = member(parent, tb->name), *item;
    char where[POINTER];
    at(where, "%s/%s", parent_pointer, tb->name);
    if (!array)
        return 0;
    if (!cJSON_IsArray(array))
        return bad(c, where, "not an array");
    tb->count = cJSON_GetArraySize(array);
    tb->items = xcalloc((size_t)tb->count + 1, sizeof *tb->items);
    int i = 0;
    cJSON_ArrayForEach(item, array)
    {
        if (!cJSON_IsObject(item))
            return bad(c, at(where, "%s/%s/%d", parent_pointer, tb->name, i), "not an object");
        const cJSON *name = member(item, "name");
        if (name && !cJSON_IsString(name))
            return bad(c, at(where, "%s/%s/%d/name", parent_pointer, tb->name, i),
                       "not a string");
        tb->items[i++] = (cJSON *)item;
    }
    return 0;
}

static int check_asset(const checker *c)
{
    const cJSON *asset = member(c->root, "asset");
    const char *version, *min_version;
    if (!cJSON_IsObject(asset))
        return bad(c, "/asset", "%s (glTF asks for an object with the version)",
                   asset ? "not an object" : "missing");
    if (string_member(c, asset, "/asset", "version", &version) ||
        string_member(c, asset, "/asset", "minVersion", &min_version))
        return -1;
    if (!version)
        return bad(c, "/asset/version", "missing (it is required)");
    if (strncmp(version, "2.", 2) != 0)
        return bad(c, "/asset/version", "'%.20s': only glTF 2.x is read", version);
    if (min_version && strcmp(min_version, "2.0") != 0)
        return bad(c, "/asset/minVersion", "'%.20s': only glTF 2.0 is read", min_version);
    return 0;
}

/* ---- extensions ---- */

/* Why a required extension cannot be read, or NULL when idmr reads it (*warning: what it does
 * not read of it, or NULL). */
static const char *unreadable(const char *name, const char **warning)
{
    static const char *const prefixes[] = {"KHR_materials_"};
    static const char *const readable[] = {"KHR_draco_mesh_compression", "KHR_lights_punctual",
                                           "KHR_texture_transform", "KHR_xmp_json_ld"};
    static const char *const texture_formats[] = {"KHR_texture_basisu", "EXT_texture_webp",
                                                  "EXT_texture_avif"};
    static const char *const techniques[] = {"KHR_techniques_webgl", "KHR_technique_webgl"};
    for (size_t i = 0; i < sizeof techniques / sizeof *techniques; i++)
        if (strcmp(name, techniques[i]) == 0) {
            *warning = "its shaders are not run: materials are read from their glTF values";
            return NULL;
        }
    *warning = NULL;
    for (size_t i = 0; i < sizeof prefixes / sizeof *prefixes; i++)
        if (strncmp(name, prefixes[i], strlen(prefixes[i])) == 0)
            return NULL;
    for (size_t i = 0; i < sizeof readable / sizeof *readable; i++)
        if (strcmp(name, readable[i]) == 0)
            return NULL;
    for (size_t i = 0; i < sizeof texture_formats / sizeof *texture_formats; i++)
        if (strcmp(name, texture_formats[i]) == 0) {
            *warning = "textures in that format are not read: their materials use the base "
                       "colour factor";
            return NULL;
        }
    if (strcmp(name, "EXT_meshopt_compression") == 0 || strcmp(name, "KHR_meshopt_compression") == 0)
        return "meshopt-compressed buffer data, which Assimp 5.2 does not decode";
    if (strcmp(name, "KHR_mesh_quantization") == 0)
        return "quantized vertex data (integer positions and normals), which Assimp 5.2 reads "
               "as floats";
    if (strcmp(name, "KHR_animation_pointer") == 0)
        return "animation pointers, which Assimp 5.2 reads as translations of a node";
    if (strcmp(name, "EXT_mesh_gpu_instancing") == 0)
        return "GPU instancing, which Assimp 5.2 ignores: the instances would be missing";
    return "an extension idmr does not implement";
}

static int check_extensions(const checker *c)
{
    const char *lists[2] = {"extensionsUsed", "extensionsRequired"};
    char where[POINTER];
    for (int l = 0; l < 2; l++) {
        const cJSON *list = member(c->root, lists[l]), *item;
        if (!list)
            continue;
        if (!cJSON_IsArray(list))
            return bad(c, at(where, "/%s", lists[l]), "not an array");
        int i = 0;
        cJSON_ArrayForEach(item, list)
        {
            at(where, "/%s/%d", lists[l], i++);
            if (!cJSON_IsString(item))
                return bad(c, where, "not a string");
            if (l == 0)
                continue;
            const char *warning, *why = unreadable(item->valuestring, &warning);
            if (why)
                return bad(c, where,
                           "the file requires %s: %s; idmr cannot read this file (export it "
                           "without that extension)",
                           item->valuestring, why);
            if (warning)
                warn("%s: %s: the file requires %s: %s", c->path, where, item->valuestring,
                     warning);
        }
    }
    return 0;
}

/* ---- buffers and bufferViews ---- */

static int check_buffers(checker *c)
{
    const table *t = &c->tables[T_BUFFERS];
    char pointer[POINTER];
    c->buffer_length = xcalloc((size_t)t->count + 1, sizeof *c->buffer_length);
    for (int b = 0; b < t->count; b++) {
        const char *uri;
        at(pointer, "/buffers/%d", b);
        if (integer_member(c, t->items[b], pointer, "byteLength", 1, 1e15, 1, 0,
                           &c->buffer_length[b]) ||
            string_member(c, t->items[b], pointer, "uri", &uri))
            return -1;
        if (!gltf_document_buffer(c->doc, b, t->items[b]))
            return -1;
    }
    return 0;
}

static int check_views(checker *c)
{
    const table *t = &c->tables[T_VIEWS];
    char pointer[POINTER], where[POINTER];
    for (int v = 0; v < t->count; v++) {
        const cJSON *view = t->items[v];
        int buffer;
        double offset, length, stride, target;
        at(pointer, "/bufferViews/%d", v);
        if (reference_member(c, view, pointer, "buffer", T_BUFFERS, 1, &buffer) ||
            integer_member(c, view, pointer, "byteOffset", 0, 1e15, 0, 0, &offset) ||
            integer_member(c, view, pointer, "byteLength", 1, 1e15, 1, 0, &length) ||
            integer_member(c, view, pointer, "byteStride", 4, 252, 0, 0, &stride) ||
            integer_member(c, view, pointer, "target", 0, 1e9, 0, 0, &target))
            return -1;
        if (fmod(stride, 4) != 0)
            return bad(c, at(where, "%s/byteStride", pointer), "%.0f is not a multiple of 4",
                       stride);
        if (target != 0 && target != 34962 && target != 34963)
            return bad(c, at(where, "%s/target", pointer),
                       "%.0f is neither 34962 (vertex data) nor 34963 (indices)", target);
        if (offset + length > c->buffer_length[buffer])
            return bad(c, pointer,
                       "bytes %.0f to %.0f lie outside buffer %d (byteLength %.0f)", offset,
                       offset + length, buffer, c->buffer_length[buffer]);
    }
    return 0;
}

/* ---- accessors ---- */

static const struct {
    const char *name;
    int components, rows;
} ELEMENT_TYPES[] = {{"SCALAR", 1, 1}, {"VEC2", 2, 2}, {"VEC3", 3, 3}, {"VEC4", 4, 4},
                     {"MAT2", 4, 2},   {"MAT3", 9, 3}, {"MAT4", 16, 4}};

static const char *type_name(const gltf_accessor *a)
{
    for (size_t i = 0; i < sizeof ELEMENT_TYPES / sizeof *ELEMENT_TYPES; i++)
        if (ELEMENT_TYPES[i].components == a->components && ELEMENT_TYPES[i].rows == a->rows)
            return ELEMENT_TYPES[i].name;
    return "?";
}

/* A place `offset` bytes into bufferView `view`, `needed` bytes long, elements aligned to
 * `alignment`: *out. pointer: the accessor part that names the view. */
static int place_in_view(const checker *c, const char *pointer, int view, double offset,
                         double needed, size_t alignment, gltf_place *out)
{
    const cJSON *v = c->tables[T_VIEWS].items[view];
    const cJSON *view_offset = member(v, "byteOffset"), *view_length = member(v, "byteLength");
    double start = view_offset ? view_offset->valuedouble : 0, length = view_length->valuedouble;
    char where[POINTER];
    if (offset + needed > length)
        return bad(c, pointer, "its data takes bytes %.0f to %.0f of bufferView %d, which has %.0f",
                   offset, offset + needed, view, length);
    if (alignment > 1 && fmod(start + offset, (double)alignment) != 0)
        return bad(c, at(where, "%s/byteOffset", pointer),
                   "the data starts at byte %.0f of its buffer, not a multiple of %zu (the "
                   "size of its component type)",
                   start + offset, alignment);
    out->buffer = (int)member(v, "buffer")->valuedouble;
    out->offset = (size_t)(start + offset);
    return 0;
}

static int check_sparse(checker *c, const cJSON *sparse, const char *pointer, gltf_accessor *a)
{
    char where[POINTER], part[POINTER];
    double count, offset, index_type;
    int view;
    const cJSON *indices = member(sparse, "indices"), *values = member(sparse, "values");
    if (!cJSON_IsObject(sparse))
        return bad(c, pointer, "not an object");
    if (integer_member(c, sparse, pointer, "count", 1, a->count, 1, 0, &count))
        return -1;
    if (!cJSON_IsObject(indices) || !cJSON_IsObject(values))
        return bad(c, pointer, "needs the objects indices and values");
    a->sparse_count = (uint32_t)count;
    at(part, "%s/indices", pointer);
    if (reference_member(c, indices, part, "bufferView", T_VIEWS, 1, &view) ||
        integer_member(c, indices, part, "byteOffset", 0, 1e15, 0, 0, &offset) ||
        integer_member(c, indices, part, "componentType", 0, 1e9, 1, 0, &index_type))
        return -1;
    a->sparse_index_type = (int)index_type;
    if (index_type != GLTF_UNSIGNED_BYTE && index_type != GLTF_UNSIGNED_SHORT &&
        index_type != GLTF_UNSIGNED_INT)
        return bad(c, at(where, "%s/componentType", part),
                   "%.0f is not an unsigned integer type (5121, 5123, 5125)", index_type);
    size_t size = gltf_component_size(a->sparse_index_type);
    if (member(c->tables[T_VIEWS].items[view], "byteStride"))
        return bad(c, at(where, "%s/bufferView", part),
                   "bufferView %d has a byteStride: sparse indices are packed", view);
    if (place_in_view(c, part, view, offset, count * (double)size, size, &a->sparse_indices))
        return -1;
    at(part, "%s/values", pointer);
    if (reference_member(c, values, part, "bufferView", T_VIEWS, 1, &view) ||
        integer_member(c, values, part, "byteOffset", 0, 1e15, 0, 0, &offset))
        return -1;
    if (member(c->tables[T_VIEWS].items[view], "byteStride"))
        return bad(c, at(where, "%s/bufferView", part),
                   "bufferView %d has a byteStride: sparse values are packed", view);
    if (place_in_view(c, part, view, offset, count * (double)a->element_size,
                      gltf_component_size(a->component_type), &a->sparse_values))
        return -1;
    /* the element numbers: strictly increasing, each below count */
    uint32_t *numbers = xmalloc(sizeof(uint32_t) * a->sparse_count);
    gltf_accessor as_indices = *a;
    as_indices.component_type = a->sparse_index_type;
    as_indices.components = as_indices.rows = 1;
    as_indices.count = a->sparse_count;
    as_indices.data = a->sparse_indices;
    as_indices.stride = size;
    as_indices.sparse_count = 0;
    int status = gltf_accessor_read_indices(c->doc, &as_indices, numbers);
    for (uint32_t i = 0; i < a->sparse_count && !status; i++) {
        if (numbers[i] >= a->count)
            status = bad(c, at(where, "%s/indices", pointer),
                         "element %u replaces element %u, but the accessor has %u", i,
                         numbers[i], a->count);
        else if (i > 0 && numbers[i] <= numbers[i - 1])
            status = bad(c, at(where, "%s/indices", pointer),
                         "element %u replaces element %u after %u: they must increase", i,
                         numbers[i], numbers[i - 1]);
    }
    free(numbers);
    return status;
}

static int check_accessor(checker *c, int index)
{
    const cJSON *accessor = c->tables[T_ACCESSORS].items[index];
    gltf_accessor *a = &c->accessors[index];
    char pointer[POINTER], where[POINTER];
    double component, count, offset;
    const char *type;
    int view;
    at(pointer, "/accessors/%d", index);
    if (integer_member(c, accessor, pointer, "componentType", 0, 1e9, 1, 0, &component) ||
        integer_member(c, accessor, pointer, "count", 1, 4294967295.0, 1, 0, &count) ||
        integer_member(c, accessor, pointer, "byteOffset", 0, 1e15, 0, 0, &offset) ||
        reference_member(c, accessor, pointer, "bufferView", T_VIEWS, 0, &view) ||
        string_member(c, accessor, pointer, "type", &type))
        return -1;
    a->component_type = (int)component;
    a->count = (uint32_t)count;
    a->data.buffer = -1;
    if (!gltf_component_size(a->component_type))
        return bad(c, at(where, "%s/componentType", pointer),
                   "%.0f is no glTF component type (5120 to 5123, 5125, 5126)", component);
    if (!type)
        return bad(c, at(where, "%s/type", pointer), "missing (it is required)");
    for (size_t i = 0; i < sizeof ELEMENT_TYPES / sizeof *ELEMENT_TYPES; i++)
        if (strcmp(type, ELEMENT_TYPES[i].name) == 0)
            a->components = ELEMENT_TYPES[i].components, a->rows = ELEMENT_TYPES[i].rows;
    if (!a->components)
        return bad(c, at(where, "%s/type", pointer),
                   "'%.20s' is none of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4", type);
    const cJSON *normalized = member(accessor, "normalized");
    if (normalized && !cJSON_IsBool(normalized))
        return bad(c, at(where, "%s/normalized", pointer), "not a boolean");
    a->normalized = cJSON_IsTrue(normalized);
    if (a->normalized &&
        (a->component_type == GLTF_FLOAT || a->component_type == GLTF_UNSIGNED_INT))
        return bad(c, at(where, "%s/normalized", pointer),
                   "true for a %s accessor (only bytes and shorts are normalized)",
                   gltf_component_name(a->component_type));
    size_t size = gltf_component_size(a->component_type);
    a->element_size = gltf_element_size(a->component_type, a->components, a->rows);
    a->stride = a->element_size;
    if (view < 0 && member(accessor, "byteOffset"))
        return bad(c, at(where, "%s/byteOffset", pointer), "given without a bufferView");
    if (view >= 0) {
        double stride = 0;
        const cJSON *stride_item = member(c->tables[T_VIEWS].items[view], "byteStride");
        if (stride_item)
            stride = stride_item->valuedouble;
        if (stride && stride < (double)a->element_size)
            return bad(c, pointer,
                       "bufferView %d has a byteStride of %.0f bytes, less than one %s of %s "
                       "(%zu bytes): its elements would overlap",
                       view, stride, type, gltf_component_name(a->component_type),
                       a->element_size);
        if (stride && fmod(stride, (double)size) != 0)
            return bad(c, pointer,
                       "bufferView %d has a byteStride of %.0f bytes, not a multiple of %zu "
                       "(the size of %s)",
                       view, stride, size, gltf_component_name(a->component_type));
        if (stride)
            a->stride = (size_t)stride;
        if (fmod(offset, (double)size) != 0)
            return bad(c, at(where, "%s/byteOffset", pointer),
                       "%.0f is not a multiple of %zu (the size of %s)", offset, size,
                       gltf_component_name(a->component_type));
        double needed = (count - 1) * (double)a->stride + (double)a->element_size;
        if (place_in_view(c, pointer, view, offset, needed, size, &a->data))
            return -1;
    }
    const cJSON *sparse = member(accessor, "sparse");
    at(where, "%s/sparse", pointer);
    if (sparse && a->stride != a->element_size)
        return bad(c, where,
                   "a sparse accessor over bufferView %d, whose byteStride (%zu) interleaves "
                   "it: Assimp 5.2 reads such a base as if packed, past its end (store the "
                   "accessor packed)",
                   view, a->stride);
    return sparse ? check_sparse(c, sparse, where, a) : 0;
}

/* ---- meshes ---- */

enum { MODE_POINTS, MODE_LINES, MODE_LINE_LOOP, MODE_LINE_STRIP, MODE_TRIANGLES, MODE_STRIP, MODE_FAN };

/* Whether `a` is of one of the `types` component types (normalized as `normalized` asks for
 * integers: 1 must be, 0 must not be) and has `components` (or `other`) components. */
static int accessor_is(const gltf_accessor *a, int components, int other, const int *types,
                       int type_count, int normalized)
{
    if (a->components != components && a->components != other)
        return 0;
    if (a->components != a->rows) /* a matrix */
        return 0;
    for (int i = 0; i < type_count; i++)
        if (a->component_type == types[i])
            return a->component_type == GLTF_FLOAT || a->normalized == normalized;
    return 0;
}

/* Attribute `name` of a primitive uses accessor `a`: is it of a type glTF allows there? */
static int check_attribute(const checker *c, const char *pointer, const char *name, int index,
                           const gltf_accessor *a)
{
    static const int FLOAT_ONLY[] = {GLTF_FLOAT};
    static const int FLOAT_OR_UNORM[] = {GLTF_FLOAT, GLTF_UNSIGNED_BYTE, GLTF_UNSIGNED_SHORT};
    static const int UNSIGNED_SMALL[] = {GLTF_UNSIGNED_BYTE, GLTF_UNSIGNED_SHORT};
    const char *expected = NULL;
    if (strcmp(name, "POSITION") == 0) {
        if (!accessor_is(a, 3, 3, FLOAT_ONLY, 1, 0))
            expected = "VEC3 of FLOAT (quantized positions, KHR_mesh_quantization, are not read)";
    } else if (strcmp(name, "NORMAL") == 0) {
        if (!accessor_is(a, 3, 3, FLOAT_ONLY, 1, 0))
            expected = "VEC3 of FLOAT";
    } else if (strcmp(name, "TANGENT") == 0) {
        if (!accessor_is(a, 4, 4, FLOAT_ONLY, 1, 0))
            expected = "VEC4 of FLOAT";
    } else if (strncmp(name, "TEXCOORD_", 9) == 0) {
        if (!accessor_is(a, 2, 2, FLOAT_OR_UNORM, 3, 1))
            expected = "VEC2 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
    } else if (strncmp(name, "COLOR_", 6) == 0) {
        if (!accessor_is(a, 3, 4, FLOAT_OR_UNORM, 3, 1))
            expected = "VEC3 or VEC4 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
    } else if (strncmp(name, "JOINTS_", 7) == 0) {
        if (!accessor_is(a, 4, 4, UNSIGNED_SMALL, 2, 0))
            expected = "VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT (not normalized)";
    } else if (strncmp(name, "WEIGHTS_", 8) == 0) {
        if (!accessor_is(a, 4, 4, FLOAT_OR_UNORM, 3, 1))
            expected = "VEC4 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
    }
    if (expected)
        return bad(c, pointer, "accessor %d is %s of %s%s: glTF's %s is %s", index, type_name(a),
                   a->normalized ? "normalized " : "", gltf_component_name(a->component_type),
                   name, expected);
    return 0;
}

/* Accessor `index`, used at `pointer`, has data: a bufferView, or sparse values on zeros.
 * Without either all its elements are zero, as glTF says, but Assimp 5.2 refuses to read it
 * (and leaks on the way). */
static int check_data(const checker *c, const char *pointer, int index)
{
    const gltf_accessor *a = &c->accessors[index];
    if (a->data.buffer < 0 && !a->sparse_count)
        return bad(c, pointer,
                   "accessor %d has no bufferView (all its elements zero), which Assimp 5.2 "
                   "does not read: store its zeros in a bufferView",
                   index);
    return 0;
}

/* The attributes object at `pointer` (a primitive's, or a morph target's): references, types
 * and data (unless Draco `compressed` them); all of one count, *count (0 before the first). */
static int check_attributes(const checker *c, const cJSON *attributes, const char *pointer,
                            int target, int compressed, uint32_t *count)
{
    const cJSON *item;
    char where[POINTER];
    cJSON_ArrayForEach(item, attributes)
    {
        int index;
        at(where, "%s", pointer);
        pointer_append(where, item->string);
        if (reference_item(c, item, where, T_ACCESSORS, &index) ||
            (!compressed && check_data(c, where, index)))
            return -1;
        const gltf_accessor *a = &c->accessors[index];
        static const int FLOAT_ONLY[] = {GLTF_FLOAT};
        if (!target) {
            if (check_attribute(c, where, item->string, index, a))
                return -1;
        } else if ((strcmp(item->string, "POSITION") == 0 ||
                    strcmp(item->string, "NORMAL") == 0 ||
                    strcmp(item->string, "TANGENT") == 0) &&
                   !accessor_is(a, 3, 3, FLOAT_ONLY, 1, 0)) {
            /* a morph target holds displacements: of positions, normals and tangents, VEC3 */
            return bad(c, where, "accessor %d is %s of %s: a morph target's %s is VEC3 of FLOAT",
                       index, type_name(a), gltf_component_name(a->component_type),
                       item->string);
        }
        if (*count && a->count != *count)
            return bad(c, where,
                       "accessor %d has %u elements, other attributes of the primitive %u "
                       "(every attribute has one element per vertex)",
                       index, a->count, *count);
        *count = a->count;
    }
    return 0;
}

/* The primitive's index values (or, without indices, its vertex count) against its vertices
 * and mode. */
static int check_indices(checker *c, const char *pointer, int index, uint32_t vertices,
                         int mode, int compressed)
{
    char where[POINTER];
    static const uint32_t minimum[] = {1, 2, 2, 2, 3, 3, 3};
    static const char *const modes[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP",
                                        "TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"};
    uint32_t count = vertices;
    if (index >= 0) {
        const gltf_accessor *a = &c->accessors[index];
        at(where, "%s/indices", pointer);
        if (a->components != 1 || (a->component_type != GLTF_UNSIGNED_BYTE &&
                                   a->component_type != GLTF_UNSIGNED_SHORT &&
                                   a->component_type != GLTF_UNSIGNED_INT) ||
            a->normalized)
            return bad(c, where,
                       "accessor %d is %s of %s%s: indices are SCALAR of UNSIGNED_BYTE, "
                       "UNSIGNED_SHORT or UNSIGNED_INT",
                       index, type_name(a), a->normalized ? "normalized " : "",
                       gltf_component_name(a->component_type));
        if (a->data.buffer >= 0 && a->stride != a->element_size)
            return bad(c, where,
                       "accessor %d lies in a bufferView with a byteStride (%zu): indices are "
                       "packed tightly",
                       index, a->stride);
        count = a->count;
        if (!compressed && check_data(c, where, index))
            return -1;
        if (!compressed) {
            uint32_t *values = xmalloc(sizeof(uint32_t) * (size_t)a->count);
            uint32_t largest = a->component_type == GLTF_UNSIGNED_BYTE    ? 0xFFu
                               : a->component_type == GLTF_UNSIGNED_SHORT ? 0xFFFFu
                                                                          : 0xFFFFFFFFu;
            int status = gltf_accessor_read_indices(c->doc, a, values);
            for (uint32_t i = 0; i < a->count && !status; i++) {
                if (values[i] == largest)
                    status = bad(c, where,
                                 "accessor %d, element %u: %u, the largest %s, which glTF "
                                 "reserves (primitive restart)",
                                 index, i, values[i], gltf_component_name(a->component_type));
                else if (values[i] >= vertices)
                    status = bad(c, where,
                                 "accessor %d, element %u: index %u, but the primitive has %u "
                                 "vertices",
                                 index, i, values[i], vertices);
                if (!(i & 0xFFFFF))
                    advance(c, 0);
            }
            free(values);
            if (status)
                return -1;
        }
    }
    if (count < minimum[mode])
        return bad(c, index >= 0 ? where : pointer,
                   "%u %s: a %s primitive needs at least %u", count,
                   index >= 0 ? "indices" : "vertices", modes[mode], minimum[mode]);
    if (mode == MODE_TRIANGLES && count % 3)
        warn("%s: %s: %u %s, not a multiple of 3: the last %u form no triangle and are ignored",
             c->path, index >= 0 ? where : pointer, count, index >= 0 ? "indices" : "vertices",
             count % 3);
    return 0;
}

static int check_primitive(checker *c, const cJSON *primitive, const char *pointer)
{
    char where[POINTER];
    cJSON *attributes, *targets, *extensions;
    double mode;
    int indices, material;
    if (!cJSON_IsObject(primitive))
        return bad(c, pointer, "not an object");
    if (shaped_member(c, primitive, pointer, "attributes", 0, &attributes) ||
        shaped_member(c, primitive, pointer, "targets", 1, &targets) ||
        shaped_member(c, primitive, pointer, "extensions", 0, &extensions) ||
        integer_member(c, primitive, pointer, "mode", 0, 6, 0, MODE_TRIANGLES, &mode) ||
        reference_member(c, primitive, pointer, "indices", T_ACCESSORS, 0, &indices) ||
        reference_member(c, primitive, pointer, "material", T_MATERIALS, 0, &material))
        return -1;
    if (!attributes)
        return bad(c, at(where, "%s/attributes", pointer), "missing (it is required)");
    const cJSON *draco = member(extensions, "KHR_draco_mesh_compression");
    uint32_t vertices = 0;
    if (check_attributes(c, attributes, at(where, "%s/attributes", pointer), 0, draco != NULL,
                         &vertices))
        return -1;
    if (!member(attributes, "POSITION"))
        return bad(c, where, "no POSITION: a primitive without vertex positions cannot be read");
    if (draco) {
        cJSON *draco_attributes;
        int view;
        char part[POINTER];
        at(part, "%s/extensions/KHR_draco_mesh_compression", pointer);
        if (!cJSON_IsObject(draco))
            return bad(c, part, "not an object");
        if (reference_member(c, draco, part, "bufferView", T_VIEWS, 1, &view) ||
            shaped_member(c, draco, part, "attributes", 0, &draco_attributes))
            return -1;
    }
    const cJSON *target;
    int t = 0;
    cJSON_ArrayForEach(target, targets)
    {
        uint32_t target_count = vertices;
        at(where, "%s/targets/%d", pointer, t++);
        if (!cJSON_IsObject(target))
            return bad(c, where, "not an object");
        if (check_attributes(c, target, where, 1, 0, &target_count))
            return -1;
    }
    return check_indices(c, pointer, indices, vertices, (int)mode, draco != NULL);
}

static int check_meshes(checker *c)
{
    const table *t = &c->tables[T_MESHES];
    char pointer[POINTER], where[POINTER];
    for (int m = 0; m < t->count; m++) {
        cJSON *primitives, *weights;
        at(pointer, "/meshes/%d", m);
        if (shaped_member(c, t->items[m], pointer, "primitives", 1, &primitives) ||
            shaped_member(c, t->items[m], pointer, "weights", 1, &weights))
            return -1;
        if (!primitives || cJSON_GetArraySize(primitives) == 0)
            return bad(c, at(where, "%s/primitives", pointer), "%s (a mesh has one or more)",
                       primitives ? "empty" : "missing");
        const cJSON *primitive;
        int p = 0;
        cJSON_ArrayForEach(primitive, primitives)
        {
            if (check_primitive(c, primitive, at(where, "%s/primitives/%d", pointer, p++)))
                return -1;
            advance(c, 1);
        }
    }
    return 0;
}

/* ---- nodes and scenes ---- */

static int check_node(checker *c, int n)
{
    const cJSON *node = c->tables[T_NODES].items[n];
    char pointer[POINTER], where[POINTER];
    double values[16];
    int present, index;
    cJSON *children, *extensions;
    at(pointer, "/nodes/%d", n);
    if (reference_member(c, node, pointer, "mesh", T_MESHES, 0, &index) ||
        reference_member(c, node, pointer, "camera", T_CAMERAS, 0, &index) ||
        reference_member(c, node, pointer, "skin", T_SKINS, 0, &index) ||
        numbers_member(c, node, pointer, "matrix", 16, values, &present) ||
        numbers_member(c, node, pointer, "translation", 3, values, &present) ||
        numbers_member(c, node, pointer, "scale", 3, values, &present) ||
        numbers_member(c, node, pointer, "rotation", 4, values, &present) ||
        shaped_member(c, node, pointer, "children", 1, &children) ||
        shaped_member(c, node, pointer, "extensions", 0, &extensions))
        return -1;
    if (present) {
        double length = values[0] * values[0] + values[1] * values[1] + values[2] * values[2] +
                        values[3] * values[3];
        if (fabs(length - 1) > 0.01)
            return bad(c, at(where, "%s/rotation", pointer),
                       "a quaternion of length %.4g: a rotation is a unit quaternion",
                       sqrt(length));
    }
    if (member(node, "skin") && !member(node, "mesh"))
        return bad(c, at(where, "%s/skin", pointer), "a skin on a node without a mesh");
    const cJSON *light = member(member(extensions, "KHR_lights_punctual"), "light");
    if (member(extensions, "KHR_lights_punctual")) {
        at(where, "%s/extensions/KHR_lights_punctual", pointer);
        if (!light)
            return bad(c, where, "no light index");
        if (reference_member(c, member(extensions, "KHR_lights_punctual"), where, "light",
                             T_LIGHTS, 1, &index))
            return -1;
    }
    const cJSON *child;
    int k = 0;
    cJSON_ArrayForEach(child, children)
    {
        int index_child;
        at(where, "%s/children/%d", pointer, k++);
        if (reference_item(c, child, where, T_NODES, &index_child))
            return -1;
        if (c->parent[index_child] >= 0)
            return bad(c, where, "node %d is already a child of node %d (a node has one parent)",
                       index_child, c->parent[index_child]);
        if (index_child == n)
            return bad(c, where, "node %d is its own child", n);
        c->parent[index_child] = n;
    }
    return 0;
}

static int check_nodes(checker *c)
{
    const table *t = &c->tables[T_NODES];
    c->parent = xmalloc(sizeof(int) * ((size_t)t->count + 1));
    for (int n = 0; n < t->count; n++)
        c->parent[n] = -1;
    for (int n = 0; n < t->count; n++)
        if (check_node(c, n))
            return -1;
    /* with one parent each, a cycle is a walk up that comes back: each node walked once */
    char *state = xcalloc((size_t)t->count + 1, 1); /* 1: on the walk now, 2: leads to a root */
    int status = 0;
    for (int n = 0; n < t->count && !status; n++) {
        int m = n;
        while (m >= 0 && state[m] == 0) {
            state[m] = 1;
            m = c->parent[m];
        }
        if (m >= 0 && state[m] == 1) {
            char where[POINTER];
            status = bad(c, at(where, "/nodes/%d/children", c->parent[m]),
                         "node %d is among its own ancestors: the hierarchy has a cycle", m);
        }
        for (m = n; m >= 0 && state[m] == 1; m = c->parent[m])
            state[m] = 2;
    }
    free(state);
    return status;
}

static int check_scenes(checker *c)
{
    const table *t = &c->tables[T_SCENES];
    char pointer[POINTER], where[POINTER];
    for (int s = 0; s < t->count; s++) {
        cJSON *nodes;
        at(pointer, "/scenes/%d", s);
        if (shaped_member(c, t->items[s], pointer, "nodes", 1, &nodes))
            return -1;
        const cJSON *item;
        int k = 0;
        cJSON_ArrayForEach(item, nodes)
        {
            int node;
            at(where, "%s/nodes/%d", pointer, k++);
            if (reference_item(c, item, where, T_NODES, &node))
                return -1;
            if (c->parent[node] >= 0)
                return bad(c, where, "node %d is a child of node %d: a scene lists root nodes",
                           node, c->parent[node]);
        }
    }
    return 0;
}

/* ---- cameras and lights ---- */

/* "camera 'name'" or "camera 3" into out. */
static const char *named_item(const cJSON *item, const char *kind, int index, char *out,
                              size_t size)
{
    const cJSON *name = member(item, "name");
    if (cJSON_IsString(name) && name->valuestring[0])
        snprintf(out, size, "%s '%.100s'", kind, name->valuestring);
    else
        snprintf(out, size, "%s %d", kind, index);
    return out;
}

static int check_camera(const checker *c, int index)
{
    const cJSON *camera = c->tables[T_CAMERAS].items[index];
    char pointer[POINTER], where[POINTER], name[160];
    const char *type;
    cJSON *projection;
    at(pointer, "/cameras/%d", index);
    named_item(camera, "camera", index, name, sizeof name);
    if (string_member(c, camera, pointer, "type", &type))
        return -1;
    if (!type || (strcmp(type, "perspective") != 0 && strcmp(type, "orthographic") != 0))
        return bad(c, at(where, "%s/type", pointer),
                   "%s: its type is %s%.20s%s, neither perspective nor orthographic", name,
                   type ? "'" : "", type ? type : "missing", type ? "'" : "");
    at(where, "%s/%s", pointer, type);
    if (shaped_member(c, camera, pointer, type, 0, &projection))
        return -1;
    if (!projection)
        return bad(c, where, "%s: its %s parameters are missing", name, type);
    double znear, zfar, a, b;
    char field[POINTER];
    if (number_member(c, projection, where, "znear", NAN, &znear) ||
        number_member(c, projection, where, "zfar", INFINITY, &zfar))
        return -1;
    if (strcmp(type, "perspective") == 0) {
        if (number_member(c, projection, where, "yfov", NAN, &a) ||
            number_member(c, projection, where, "aspectRatio", 1, &b))
            return -1;
        char value[32] = "missing";
        if (!isnan(a))
            snprintf(value, sizeof value, "%g", a);
        if (!(a > 0 && a < M_PI))
            return bad(c, at(field, "%s/yfov", where),
                       "%s: yfov %s: a perspective camera's vertical field of view lies above 0 "
                       "and below pi radians",
                       name, value);
        if (!(b > 0))
            return bad(c, at(field, "%s/aspectRatio", where),
                       "%s: aspectRatio %g: the film's width over its height is above 0", name, b);
        if (!(znear > 0)) {
            if (!isnan(znear))
                snprintf(value, sizeof value, "%g", znear);
            return bad(c, at(field, "%s/znear", where),
                       "%s: znear %s: a perspective camera's near plane lies above 0", name,
                       isnan(znear) ? "missing" : value);
        }
    } else {
        if (number_member(c, projection, where, "xmag", NAN, &a) ||
            number_member(c, projection, where, "ymag", NAN, &b))
            return -1;
        if (isnan(a) || isnan(b) || a == 0 || b == 0)
            return bad(c, where, "%s: xmag and ymag are required and not 0", name);
        if (!(znear >= 0))
            return bad(c, at(field, "%s/znear", where),
                       "%s: znear %s: an orthographic camera's near plane lies at 0 or above",
                       name, isnan(znear) ? "missing" : "below 0");
        if (isinf(zfar))
            return bad(c, at(field, "%s/zfar", where), "%s: zfar missing (an orthographic "
                       "camera has one)", name);
    }
    if (!(zfar > znear))
        return bad(c, at(field, "%s/zfar", where), "%s: zfar %g is not beyond znear %g", name,
                   zfar, znear);
    return 0;
}

static int check_light(const checker *c, int index)
{
    const cJSON *light = c->tables[T_LIGHTS].items[index];
    char pointer[POINTER], where[POINTER], name[160];
    const char *type;
    double intensity, range, colour[3];
    int present;
    at(pointer, "/extensions/KHR_lights_punctual/lights/%d", index);
    named_item(light, "light", index, name, sizeof name);
    if (string_member(c, light, pointer, "type", &type) ||
        number_member(c, light, pointer, "intensity", 1, &intensity) ||
        number_member(c, light, pointer, "range", INFINITY, &range) ||
        numbers_member(c, light, pointer, "color", 3, colour, &present))
        return -1;
    if (!type)
        return bad(c, at(where, "%s/type", pointer), "%s: no type (point, spot or directional)",
                   name);
    if (strcmp(type, "point") != 0 && strcmp(type, "spot") != 0 &&
        strcmp(type, "directional") != 0)
        return bad(c, at(where, "%s/type", pointer),
                   "%s: type '%.40s' is none of point, spot, directional", name, type);
    if (intensity < 0)
        return bad(c, at(where, "%s/intensity", pointer), "%s: intensity %g is below 0", name,
                   intensity);
    if (!(range > 0))
        return bad(c, at(where, "%s/range", pointer), "%s: range %g is not above 0", name, range);
    for (int k = 0; present && k < 3; k++)
        if (colour[k] < 0)
            return bad(c, at(where, "%s/color/%d", pointer, k), "%s: a colour below 0", name);
    const cJSON *spot = member(light, "spot");
    if (strcmp(type, "spot") != 0)
        return 0;
    at(where, "%s/spot", pointer);
    if (!cJSON_IsObject(spot))
        return bad(c, where, "%s: a spot light without its spot parameters (an object)", name);
    double inner, outer;
    char field[POINTER];
    if (number_member(c, spot, where, "innerConeAngle", 0, &inner) ||
        number_member(c, spot, where, "outerConeAngle", M_PI / 4, &outer))
        return -1;
    if (!(outer > 0 && outer <= M_PI / 2))
        return bad(c, at(field, "%s/outerConeAngle", where),
                   "%s: %g radians: the outer cone angle lies above 0 and at most pi/2", name,
                   outer);
    if (!(inner >= 0 && inner < outer))
        return bad(c, at(field, "%s/innerConeAngle", where),
                   "%s: %g radians: the inner cone angle lies from 0 to below the outer one (%g)",
                   name, inner, outer);
    return 0;
}

/* ---- materials, textures, images ---- */

/* A textureInfo object at object[name], when present: its index names a texture. */
static int check_texture_info(const checker *c, const cJSON *object, const char *pointer,
                              const char *name)
{
    const cJSON *info = member(object, name);
    char where[POINTER];
    int index;
    double texcoord;
    if (!info)
        return 0;
    at(where, "%s/%s", pointer, name);
    if (!cJSON_IsObject(info))
        return bad(c, where, "not an object");
    return reference_member(c, info, where, "index", T_TEXTURES, 1, &index) ||
                   integer_member(c, info, where, "texCoord", 0, 1e9, 0, 0, &texcoord)
               ? -1
               : 0;
}

static int check_materials(const checker *c)
{
    char pointer[POINTER], where[POINTER];
    for (int m = 0; m < c->tables[T_MATERIALS].count; m++) {
        const cJSON *material = c->tables[T_MATERIALS].items[m];
        cJSON *pbr;
        at(pointer, "/materials/%d", m);
        if (shaped_member(c, material, pointer, "pbrMetallicRoughness", 0, &pbr) ||
            check_texture_info(c, material, pointer, "normalTexture") ||
            check_texture_info(c, material, pointer, "occlusionTexture") ||
            check_texture_info(c, material, pointer, "emissiveTexture"))
            return -1;
        at(where, "%s/pbrMetallicRoughness", pointer);
        if (check_texture_info(c, pbr, where, "baseColorTexture") ||
            check_texture_info(c, pbr, where, "metallicRoughnessTexture"))
            return -1;
    }
    for (int t = 0; t < c->tables[T_TEXTURES].count; t++) {
        int index;
        at(pointer, "/textures/%d", t);
        if (reference_member(c, c->tables[T_TEXTURES].items[t], pointer, "source", T_IMAGES, 0,
                             &index) ||
            reference_member(c, c->tables[T_TEXTURES].items[t], pointer, "sampler", T_SAMPLERS,
                             0, &index))
            return -1;
    }
    for (int i = 0; i < c->tables[T_IMAGES].count; i++) {
        const cJSON *image = c->tables[T_IMAGES].items[i];
        const char *uri;
        int view;
        at(pointer, "/images/%d", i);
        if (string_member(c, image, pointer, "uri", &uri) ||
            reference_member(c, image, pointer, "bufferView", T_VIEWS, 0, &view))
            return -1;
        if (!uri == (view < 0))
            return bad(c, pointer, "an image has either a uri or a bufferView (%s)",
                       uri ? "here both" : "here neither");
        if (uri && strncmp(uri, "data:", 5) == 0) { /* Assimp decodes it: well formed? */
            gltf_bytes decoded;
            size_t at_fault;
            const char *why;
            int status = gltf_data_uri(uri, &decoded, &at_fault, &why);
            free(decoded.data);
            if (status)
                return bad(c, at(where, "%s/uri", pointer), "character %zu: %s", at_fault, why);
        }
    }
    return 0;
}

/* ---- skins and animations ---- */

static int check_skins(const checker *c)
{
    char pointer[POINTER], where[POINTER];
    for (int s = 0; s < c->tables[T_SKINS].count; s++) {
        const cJSON *skin = c->tables[T_SKINS].items[s], *item;
        cJSON *joints;
        int index, matrices;
        at(pointer, "/skins/%d", s);
        if (shaped_member(c, skin, pointer, "joints", 1, &joints) ||
            reference_member(c, skin, pointer, "skeleton", T_NODES, 0, &index) ||
            reference_member(c, skin, pointer, "inverseBindMatrices", T_ACCESSORS, 0, &matrices))
            return -1;
        if (!joints || cJSON_GetArraySize(joints) == 0)
            return bad(c, at(where, "%s/joints", pointer), "missing or empty");
        int k = 0;
        cJSON_ArrayForEach(item, joints)
        {
            if (reference_item(c, item, at(where, "%s/joints/%d", pointer, k++), T_NODES, &index))
                return -1;
        }
        if (matrices < 0) /* glTF: identity matrices; Assimp 5.2 reads them from nowhere */
            return bad(c, pointer,
                       "no inverseBindMatrices (identity, as glTF allows), which Assimp 5.2 "
                       "does not read (it crashes): give the skin its matrices");
        if (matrices >= 0) {
            const gltf_accessor *a = &c->accessors[matrices];
            if (check_data(c, at(where, "%s/inverseBindMatrices", pointer), matrices))
                return -1;
            if (a->components != 16 || a->component_type != GLTF_FLOAT ||
                a->count < (uint32_t)k)
                return bad(c, at(where, "%s/inverseBindMatrices", pointer),
                           "accessor %d is %u %s of %s: a skin of %d joints needs as many MAT4 "
                           "of FLOAT",
                           matrices, a->count, type_name(a),
                           gltf_component_name(a->component_type), k);
        }
    }
    return 0;
}

static int check_animation(const checker *c, int n)
{
    const cJSON *animation = c->tables[T_ANIMATIONS].items[n], *item;
    char pointer[POINTER], where[POINTER], part[POINTER];
    cJSON *channels, *samplers;
    at(pointer, "/animations/%d", n);
    if (shaped_member(c, animation, pointer, "channels", 1, &channels) ||
        shaped_member(c, animation, pointer, "samplers", 1, &samplers))
        return -1;
    if (!channels || !samplers)
        return bad(c, pointer, "an animation needs channels and samplers");
    int sampler_count = cJSON_GetArraySize(samplers), k = 0;
    int *output_per_key = xcalloc((size_t)sampler_count + 1, sizeof *output_per_key);
    const gltf_accessor **outputs = xcalloc((size_t)sampler_count + 1, sizeof *outputs);
    int status = 0;
    cJSON_ArrayForEach(item, samplers)
    {
        int input, output;
        const char *interpolation;
        at(where, "%s/samplers/%d", pointer, k);
        if (!cJSON_IsObject(item)) {
            status = bad(c, where, "not an object");
            break;
        }
        if ((status = reference_member(c, item, where, "input", T_ACCESSORS, 1, &input) ||
                      reference_member(c, item, where, "output", T_ACCESSORS, 1, &output) ||
                      string_member(c, item, where, "interpolation", &interpolation)))
            break;
        if ((status = check_data(c, at(part, "%s/input", where), input) ||
                      check_data(c, at(part, "%s/output", where), output)))
            break;
        const gltf_accessor *in = &c->accessors[input], *out = &c->accessors[output];
        int per_key = interpolation && strcmp(interpolation, "CUBICSPLINE") == 0 ? 3 : 1;
        if (interpolation && per_key == 1 && strcmp(interpolation, "LINEAR") != 0 &&
            strcmp(interpolation, "STEP") != 0) {
            status = bad(c, at(part, "%s/interpolation", where),
                         "'%.20s' is none of LINEAR, STEP, CUBICSPLINE", interpolation);
            break;
        }
        if (in->components != 1 || in->component_type != GLTF_FLOAT) {
            status = bad(c, at(part, "%s/input", where),
                         "accessor %d is %s of %s: key times are SCALAR of FLOAT", input,
                         type_name(in), gltf_component_name(in->component_type));
            break;
        }
        output_per_key[k] = per_key * (int)in->count;
        outputs[k] = out;
        k++;
    }
    k = 0;
    cJSON_ArrayForEach(item, channels)
    {
        if (status)
            break;
        const cJSON *target = member(item, "target");
        const char *path;
        int sampler, node;
        at(where, "%s/channels/%d", pointer, k++);
        if (!cJSON_IsObject(item) || !cJSON_IsObject(target)) {
            status = bad(c, where, "not an object with a target object");
            break;
        }
        double sampler_index;
        if ((status = integer_member(c, item, where, "sampler", 0, 2147483647.0, 1, 0,
                                     &sampler_index) ||
                      string_member(c, target, at(part, "%s/target", where), "path", &path) ||
                      reference_member(c, target, part, "node", T_NODES, 0, &node)))
            break;
        if (sampler_index >= sampler_count) {
            status = bad(c, at(part, "%s/sampler", where),
                         "%.0f, but the animation has %d samplers", sampler_index, sampler_count);
            break;
        }
        sampler = (int)sampler_index;
        if (!path) {
            status = bad(c, at(part, "%s/target/path", where), "missing (it is required)");
            break;
        }
        int components = strcmp(path, "translation") == 0 || strcmp(path, "scale") == 0 ? 3
                         : strcmp(path, "rotation") == 0                              ? 4
                         : strcmp(path, "weights") == 0                               ? 1
                                                                                      : 0;
        if (!components) { /* Assimp 5.2 reads any other path as a translation */
            status = bad(c, at(part, "%s/target/path", where),
                         "'%.40s' is none of translation, rotation, scale, weights (animation "
                         "pointers are not read)",
                         path);
            break;
        }
        if (node < 0) {
            status = bad(c, at(part, "%s/target/node", where),
                         "missing: a %s channel animates a node", path);
            break;
        }
        const gltf_accessor *out = outputs[sampler];
        if (!out)
            continue;
        /* as many outputs as keys (three per key for CUBICSPLINE); weights: that times the
         * number of morph targets */
        uint32_t needed = (uint32_t)output_per_key[sampler];
        if (out->components != components ||
            (components == 1 ? needed == 0 || out->count % needed != 0 : out->count != needed))
            status = bad(c, at(part, "%s/samplers/%d/output", pointer, sampler),
                         "%u %s, but a %s channel of that sampler needs %s%u %s", out->count,
                         type_name(out), path, components == 1 ? "a multiple of " : "", needed,
                         components == 3 ? "VEC3" : components == 4 ? "VEC4" : "SCALAR");
    }
    free(outputs);
    free(output_per_key);
    return status;
}

/* ---- the whole ---- */

static void free_checker(checker *c)
{
    for (int t = 0; t < TABLES; t++)
        free(c->tables[t].items);
    free(c->buffer_length);
    free(c->parent);
}

int gltf_validate(gltf_document *doc, progress *bar, gltf_checked *out)
{
    static const char *const names[TABLES][2] = {
        {"accessors", "accessors"}, {"animations", "animations"}, {"buffers", "buffers"},
        {"bufferViews", "bufferViews"}, {"cameras", "cameras"}, {"images", "images"},
        {"materials", "materials"}, {"meshes", "meshes"}, {"nodes", "nodes"},
        {"samplers", "samplers"}, {"scenes", "scenes"}, {"skins", "skins"},
        {"textures", "textures"}, {"lights", "lights"}};
    checker c;
    memset(&c, 0, sizeof c);
    memset(out, 0, sizeof *out);
    c.doc = doc;
    c.path = doc->path;
    c.root = doc->json;
    c.bar = bar;
    for (int t = 0; t < TABLES; t++)
        c.tables[t].name = names[t][0], c.tables[t].what = names[t][1];
    char pointer[POINTER] = "";
    int status = json_shape(&c, c.root, pointer, 0) || check_asset(&c) || check_extensions(&c);
    for (int t = 0; t < T_LIGHTS && !status; t++)
        status = read_table(&c, t, c.root, "");
    const cJSON *lights = member(member(c.root, "extensions"), "KHR_lights_punctual");
    if (!status && lights)
        status = read_table(&c, T_LIGHTS, lights, "/extensions/KHR_lights_punctual");
    int accessor_count = c.tables[T_ACCESSORS].count;
    c.accessors = xcalloc((size_t)accessor_count + 1, sizeof *c.accessors);
    int chosen;
    if (!status && reference_member(&c, c.root, "", "scene", T_SCENES, 0, &chosen))
        status = -1;
    if (!status && c.tables[T_SCENES].count == 0)
        status = bad(&c, "/scenes", "the file has no scene: nothing to simulate");
    if (!status)
        status = check_buffers(&c) || check_views(&c);
    for (int a = 0; a < accessor_count && !status; a++) {
        status = check_accessor(&c, a);
        advance(&c, 1);
    }
    if (!status)
        status = check_nodes(&c) || check_scenes(&c) || check_meshes(&c);
    for (int i = 0; i < c.tables[T_CAMERAS].count && !status; i++)
        status = check_camera(&c, i);
    for (int i = 0; i < c.tables[T_LIGHTS].count && !status; i++)
        status = check_light(&c, i);
    if (!status)
        status = check_materials(&c) || check_skins(&c);
    for (int i = 0; i < c.tables[T_ANIMATIONS].count && !status; i++)
        status = check_animation(&c, i);
    free_checker(&c);
    if (status) {
        free(c.accessors);
        return -1;
    }
    out->accessors = c.accessors;
    out->accessor_count = accessor_count;
    return 0;
}

void gltf_checked_free(gltf_checked *checked)
{
    free(checked->accessors);
    memset(checked, 0, sizeof *checked);
}
