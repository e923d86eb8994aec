/* test_gltf_inputs.c — glTF inputs that are wrong, or right but unusual, as gltf_load reads
 * them (host/io/gltf/gltf_document.c, gltf_validate.c, gltf.cc). Each case is a small document
 * built here from one scene, drawn below, and changed in one place:
 *
 *        2 ---- 3     4 vertices in z = 0, normals +z; triangles 0 1 2 and 2 1 3 (indices
 *        |    / |     UNSIGNED_SHORT); uv (u, v) = (x, y), stored three ways: FLOAT (the one
 *        |  /   |     used), normalized UNSIGNED_BYTE and normalized UNSIGNED_SHORT; node
 *        0 ---- 1     "ground" holds the mesh; the buffer is a base64 data: URI, or a GLB's BIN
 *                     chunk.
 *
 *   - bad data is refused (exit code IDMR_EXIT_INPUT) with a message that names the file, the
 *     JSON pointer of the fault and what is wrong: an index out of range (Assimp dropped the
 *     triangle), invalid base64 (it moved a vertex), BYTE positions and a byteStride shorter
 *     than the element (garbage), extensionsRequired naming meshopt compression, quantization,
 *     GPU instancing or a vendor's extension, and their neighbours (misaligned offsets, data past
 *     its bufferView or buffer, attributes of different counts, a strip of two indices, the
 *     restart index, a node with two parents or in a cycle, a member named twice, sparse
 *     element numbers that do not increase);
 *   - what the specification allows is read right: normalized UNSIGNED_BYTE and UNSIGNED_SHORT
 *     uv (Assimp 5.2 copied their bytes into floats), an interleaved bufferView, a sparse
 *     accessor (but one over an interleaved bufferView is refused: Assimp 5.2 reads its base as
 *     if packed, past its end: found by fuzzing), Draco (which Assimp decodes: Debian's Draco
 *     sample), a required texture format (warned, not refused);
 *   - a camera with yfov <= 0, a negative aspect ratio or znear 0 is refused by name (it was
 *     called orthographic and replaced by the default framing);
 *   - lights: an unknown type is named as such (it was "missing spot parameters"); a light on two
 *     nodes is two lights, and lights and cameras on nodes that share a name stand at their own
 *     node (Assimp's name lookup put them all at the first);
 *   - damaged JSON and GLB headers name the line and column, or the byte (they were "No suitable
 *     reader found");
 *   - 20,000 nodes of one name with 2,000 lights and 2,000 cameras load in seconds (the mesh
 *     names' suffix search and Assimp's name validation were quadratic: minutes), and a long
 *     load shows progress unless --quiet.
 * Runs from the repository root (bin/idmr), as `make test` does. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "command_common.h"
#include "gltf_common.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/error.h"
#include "core/scene.h"
#include "io/gltf/gltf.h"

#define DRACO_MODEL "/usr/share/assimp/models/glTF2/draco/2CylinderEngine.gltf"

static char dir[64];

static int make_dir(void **state)
{
    (void)state;
    make_temp_dir(dir, "idmr-test-gltf-inputs");
    warn_silence(1);
    return 0;
}

static int remove_dir(void **state)
{
    (void)state;
    remove_tree(dir);
    return 0;
}

/* ---- the scene drawn above ---- */

typedef struct bytes {
    unsigned char data[512];
    size_t size;
} bytes;

enum { POSITIONS = 0, NORMALS = 48, INDICES = 96, UV_BYTE = 108, UV_SHORT = 116, UV_FLOAT = 132,
       BUFFER_SIZE = 164 };

static void put(bytes *b, size_t at, const void *value, size_t size)
{
    memcpy(b->data + at, value, size);
    if (at + size > b->size)
        b->size = at + size;
}

static cJSON *parse(const char *text)
{
    cJSON *json = cJSON_Parse(text);
    if (!json)
        fail_msg("test JSON does not parse near: %.60s", cJSON_GetErrorPtr());
    return json;
}

/* The document and its buffer's bytes. */
static cJSON *base_scene(bytes *b)
{
    memset(b, 0, sizeof *b);
    const float positions[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const float normals[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const uint16_t indices[6] = {0, 1, 2, 2, 1, 3};
    const uint8_t uv_byte[8] = {0, 0, 255, 0, 0, 255, 255, 255};
    const uint16_t uv_short[8] = {0, 0, 65535, 0, 0, 65535, 65535, 65535};
    const float uv_float[8] = {0, 0, 1, 0, 0, 1, 1, 1};
    put(b, POSITIONS, positions, sizeof positions);
    put(b, NORMALS, normals, sizeof normals);
    put(b, INDICES, indices, sizeof indices);
    put(b, UV_BYTE, uv_byte, sizeof uv_byte);
    put(b, UV_SHORT, uv_short, sizeof uv_short);
    put(b, UV_FLOAT, uv_float, sizeof uv_float);
    return parse(
        "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
        " \"nodes\": [{\"name\": \"ground\", \"mesh\": 0}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1,\n"
        "   \"TEXCOORD_0\": 5}, \"indices\": 2}]}],\n"
        " \"buffers\": [{\"byteLength\": 164}],\n"
        " \"bufferViews\": [\n"
        "   {\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
        "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 48},\n"
        "   {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 12},\n"
        "   {\"buffer\": 0, \"byteOffset\": 108, \"byteLength\": 8},\n"
        "   {\"buffer\": 0, \"byteOffset\": 116, \"byteLength\": 16},\n"
        "   {\"buffer\": 0, \"byteOffset\": 132, \"byteLength\": 32}],\n"
        " \"accessors\": [\n"
        "   {\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\",\n"
        "    \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
        "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
        "   {\"bufferView\": 2, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"},\n"
        "   {\"bufferView\": 3, \"componentType\": 5121, \"normalized\": true, \"count\": 4,\n"
        "    \"type\": \"VEC2\"},\n"
        "   {\"bufferView\": 4, \"componentType\": 5123, \"normalized\": true, \"count\": 4,\n"
        "    \"type\": \"VEC2\"},\n"
        "   {\"bufferView\": 5, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC2\"}]}");
}

static char *base64(const unsigned char *data, size_t size)
{
    static const char digits[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * (size / 3 + 1) + 1), *o = out;
    for (size_t i = 0; i < size; i += 3) {
        uint32_t v = (uint32_t)data[i] << 16 | (i + 1 < size ? (uint32_t)data[i + 1] << 8 : 0) |
                     (i + 2 < size ? data[i + 2] : 0);
        *o++ = digits[v >> 18 & 63], *o++ = digits[v >> 12 & 63];
        *o++ = i + 1 < size ? digits[v >> 6 & 63] : '=';
        *o++ = i + 2 < size ? digits[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

static void write_file(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* dir/name: a .gltf with the bytes as the data: URI of buffer 0 (unless it has a uri), or a .glb
 * with them as its BIN chunk. Returns the path (static). */
static const char *write_scene(cJSON *doc, const bytes *b, const char *name)
{
    static char path[128];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    cJSON *buffer = cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "buffers"), 0);
    int glb = strstr(name, ".glb") != NULL;
    if (!glb && buffer && !cJSON_GetObjectItem(buffer, "uri")) {
        char *digits = base64(b->data, b->size);
        char *uri = malloc(strlen(digits) + 64);
        sprintf(uri, "data:application/octet-stream;base64,%s", digits);
        cJSON_AddStringToObject(buffer, "uri", uri);
        free(uri);
        free(digits);
    }
    char *text = cJSON_Print(doc);
    if (!glb) {
        write_file(path, text, strlen(text));
    } else {
        size_t total;
        unsigned char *glb_bytes = glb_pack(text, b->data, b->size, &total);
        write_file(path, glb_bytes, total);
        free(glb_bytes);
    }
    free(text);
    return path;
}

/* doc's item at a path of member names and array indices ("accessors", "0"): NULL ends it. */
static cJSON *item_at(cJSON *doc, ...)
{
    va_list args;
    va_start(args, doc);
    cJSON *item = doc;
    for (const char *step; item && (step = va_arg(args, const char *));)
        item = cJSON_IsArray(item) ? cJSON_GetArrayItem(item, atoi(step))
                                   : cJSON_GetObjectItem(item, step);
    va_end(args);
    if (!item)
        fail_msg("the test's document has no such item");
    return item;
}

/* Sets object[name] to the JSON text `value`. */
static void set(cJSON *object, const char *name, const char *value)
{
    cJSON_DeleteItemFromObject(object, name);
    cJSON_AddItemToObject(object, name, parse(value));
}

/* Fails unless loading `path` is refused as bad input with a message that holds the path and
 * each of the `expected` strings (NULL-terminated). */
static void assert_refused(const char *path, ...)
{
    error_clear();
    scene *s = gltf_load(path);
    if (s) {
        scene_free(s);
        fail_msg("%s was accepted", path);
    }
    const char *message = error_message();
    if (error_code() != IDMR_EXIT_INPUT)
        fail_msg("%s: exit code %d, not IDMR_EXIT_INPUT: %s", path, error_code(), message);
    if (!strstr(message, path))
        fail_msg("the message does not name the file: %s", message);
    va_list args;
    va_start(args, path);
    for (const char *expected; (expected = va_arg(args, const char *));)
        if (!strstr(message, expected))
            fail_msg("the message lacks '%s': %s", expected, message);
    va_end(args);
    printf("  refused: %s\n", message);
}

static scene *load_or_fail(const char *path)
{
    error_clear();
    scene *s = gltf_load(path);
    if (!s)
        fail_msg("%s: %s", path, error_message());
    return s;
}

/* ---- bad data ---- */

static void test_index_out_of_range(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    const uint16_t seven = 7;
    put(&b, INDICES + 10, &seven, 2); /* triangle 2 1 3 becomes 2 1 7 */
    assert_refused(write_scene(doc, &b, "index.gltf"), "/meshes/0/primitives/0/indices",
                   "element 5", "index 7", "4 vertices", NULL);
    const uint16_t restart = 65535;
    put(&b, INDICES + 10, &restart, 2);
    cJSON_DeleteItemFromObject(item_at(doc, "buffers", "0", NULL), "uri"); /* the new bytes */
    assert_refused(write_scene(doc, &b, "restart.gltf"), "/meshes/0/primitives/0/indices",
                   "65535", "reserves", NULL);
    cJSON_Delete(doc);
}

static void test_bad_base64(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    const char *path = write_scene(doc, &b, "base64.gltf");
    cJSON *uri = item_at(doc, "buffers", "0", "uri", NULL);
    char *text = strdup(uri->valuestring), *comma = strchr(text, ',');
    comma[9] = '!'; /* a byte of the first vertex */
    cJSON_SetValuestring(uri, text);
    path = write_scene(doc, &b, "base64.gltf");
    assert_refused(path, "/buffers/0/uri", "character", "not a base64 digit", NULL);
    comma[9] = 'A';
    strcpy(comma + 1 + 4 * 10 + 1, "="); /* cut inside a group of four */
    cJSON_SetValuestring(uri, text);
    assert_refused(write_scene(doc, &b, "base64.gltf"), "/buffers/0/uri",
                   "ends inside a group of four", NULL);
    free(text);
    cJSON_Delete(doc);
}

static void test_component_types_and_strides(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    cJSON *position = item_at(doc, "accessors", "0", NULL);
    set(position, "componentType", "5120"); /* BYTE positions */
    cJSON_DeleteItemFromObject(position, "min"), cJSON_DeleteItemFromObject(position, "max");
    assert_refused(write_scene(doc, &b, "byte.gltf"), "/meshes/0/primitives/0/attributes/POSITION",
                   "VEC3 of BYTE", "VEC3 of FLOAT", NULL);
    set(position, "componentType", "5126");
    set(item_at(doc, "bufferViews", "0", NULL), "byteStride", "8"); /* shorter than a VEC3 */
    assert_refused(write_scene(doc, &b, "stride.gltf"), "/accessors/0", "byteStride of 8",
                   "12 bytes", NULL);
    cJSON_DeleteItemFromObject(item_at(doc, "bufferViews", "0", NULL), "byteStride");
    set(item_at(doc, "accessors", "1", NULL), "byteOffset", "2"); /* a float at byte 50 */
    assert_refused(write_scene(doc, &b, "offset.gltf"), "/accessors/1/byteOffset",
                   "not a multiple of 4", NULL);
    set(item_at(doc, "accessors", "1", NULL), "byteOffset", "4"); /* runs past its view */
    assert_refused(write_scene(doc, &b, "past-view.gltf"), "/accessors/1", "bufferView 1", NULL);
    set(item_at(doc, "accessors", "1", NULL), "byteOffset", "0");
    set(item_at(doc, "bufferViews", "5", NULL), "byteLength", "40"); /* past its buffer */
    assert_refused(write_scene(doc, &b, "past-buffer.gltf"), "/bufferViews/5",
                   "outside buffer 0", NULL);
    set(item_at(doc, "bufferViews", "5", NULL), "byteLength", "32");
    set(item_at(doc, "accessors", "1", NULL), "count", "3"); /* NORMAL: 3 of 4 vertices */
    assert_refused(write_scene(doc, &b, "counts.gltf"), "/meshes/0/primitives/0/attributes/",
                   "3 elements", "4", NULL);
    set(item_at(doc, "accessors", "1", NULL), "count", "4");
    set(item_at(doc, "meshes", "0", "primitives", "0", "attributes", NULL), "TEXCOORD_0", "3");
    set(item_at(doc, "accessors", "3", NULL), "normalized", "false"); /* bytes as numbers */
    assert_refused(write_scene(doc, &b, "uv.gltf"), "/meshes/0/primitives/0/attributes/TEXCOORD_0",
                   "UNSIGNED_BYTE", NULL);
    cJSON_Delete(doc);
}

static void test_required_extensions(void **state)
{
    (void)state;
    const char *cases[][2] = {
        {"EXT_meshopt_compression", "does not decode"},
        {"KHR_mesh_quantization", "quantized"},
        {"EXT_mesh_gpu_instancing", "instances"},
        {"VENDOR_special_geometry", "does not implement"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        bytes b;
        cJSON *doc = base_scene(&b);
        char list[96];
        snprintf(list, sizeof list, "[\"%s\"]", cases[i][0]);
        set(doc, "extensionsUsed", list);
        set(doc, "extensionsRequired", list);
        if (i == 0) { /* meshopt's fallback buffer: no uri ("a missing buffer URI" before) */
            cJSON_AddItemToArray(
                cJSON_GetObjectItem(doc, "buffers"),
                parse("{\"byteLength\": 64, \"extensions\": {\"EXT_meshopt_compression\": "
                      "{\"fallback\": true}}}"));
        }
        assert_refused(write_scene(doc, &b, "required.gltf"), "/extensionsRequired/0",
                       cases[i][0], cases[i][1], NULL);
        cJSON_Delete(doc);
    }
}

static void test_structure(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    cJSON *primitive = item_at(doc, "meshes", "0", "primitives", "0", NULL);
    set(primitive, "mode", "5"); /* a strip of two indices */
    set(item_at(doc, "accessors", "2", NULL), "count", "2");
    assert_refused(write_scene(doc, &b, "strip.gltf"), "/meshes/0/primitives/0/indices",
                   "2 indices", "TRIANGLE_STRIP", "at least 3", NULL);
    cJSON_DeleteItemFromObject(primitive, "mode");
    set(item_at(doc, "accessors", "2", NULL), "count", "6");
    set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0, \"children\": [1]}, {\"children\": "
                      "[2]}, {\"children\": [1]}]");
    assert_refused(write_scene(doc, &b, "two-parents.gltf"), "/nodes/2/children/0",
                   "already a child of node 0", NULL);
    set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0}, {\"children\": [2]}, "
                      "{\"children\": [1]}]");
    assert_refused(write_scene(doc, &b, "cycle.gltf"), "/nodes/", "cycle", NULL);
    set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0, \"rotation\": [0, 0, 0, 2]}]");
    assert_refused(write_scene(doc, &b, "rotation.gltf"), "/nodes/0/rotation", "unit", NULL);
    set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0}]");
    /* a member twice: cJSON keeps both, as a text would have them */
    cJSON_AddItemToObject(item_at(doc, "accessors", "0", NULL), "count", cJSON_CreateNumber(3));
    assert_refused(write_scene(doc, &b, "twice.gltf"), "/accessors/0/count", "named twice", NULL);
    cJSON_Delete(doc);
    /* sparse element numbers must increase */
    doc = base_scene(&b);
    const uint16_t numbers[2] = {2, 1};
    put(&b, BUFFER_SIZE, numbers, sizeof numbers);
    set(item_at(doc, "buffers", "0", NULL), "byteLength", "168");
    cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "bufferViews"),
                         parse("{\"buffer\": 0, \"byteOffset\": 164, \"byteLength\": 4}"));
    cJSON_AddItemToObject(item_at(doc, "accessors", "0", NULL), "sparse",
                          parse("{\"count\": 2, \"indices\": {\"bufferView\": 6, "
                                "\"componentType\": 5123}, \"values\": {\"bufferView\": 0}}"));
    assert_refused(write_scene(doc, &b, "sparse.gltf"), "/accessors/0/sparse/indices",
                   "must increase", NULL);
    cJSON_Delete(doc);
}

/* ---- what the specification allows ---- */

static void assert_uv(const scene *s, double tolerance)
{
    assert_int_equal(s->mesh_count, 1);
    const scene_mesh *m = &s->meshes[0];
    assert_non_null(m->texcoords);
    for (uint32_t v = 0; v < m->vertex_count; v++) { /* uv = xy, v as the file has it */
        assert_float_equal(m->texcoords[2 * v], m->positions[3 * v], tolerance);
        assert_float_equal(m->texcoords[2 * v + 1], m->positions[3 * v + 1], tolerance);
    }
}

static void test_normalized_texcoords(void **state)
{
    (void)state;
    const char *accessors[2] = {"3", "4"}; /* UNSIGNED_BYTE, UNSIGNED_SHORT */
    for (int i = 0; i < 2; i++) {
        for (int glb = 0; glb < 2; glb++) {
            bytes b;
            cJSON *doc = base_scene(&b);
            set(item_at(doc, "meshes", "0", "primitives", "0", "attributes", NULL), "TEXCOORD_0",
                accessors[i]);
            scene *s = load_or_fail(write_scene(doc, &b, glb ? "uv.glb" : "uv.gltf"));
            assert_uv(s, 1e-6);
            scene_free(s);
            cJSON_Delete(doc);
        }
    }
    /* two meshes, the second (bytes) reached first: Assimp numbers its meshes as nodes reach
     * them, not as the file lists them */
    bytes b;
    cJSON *doc = base_scene(&b);
    cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "meshes"),
                         parse("{\"primitives\": [{\"attributes\": {\"POSITION\": 0, "
                               "\"TEXCOORD_0\": 3}, \"indices\": 2}]}"));
    set(doc, "nodes", "[{\"name\": \"second\", \"mesh\": 1, \"children\": [1]}, "
                      "{\"name\": \"first\", \"mesh\": 0}]");
    scene *s = load_or_fail(write_scene(doc, &b, "two-meshes.gltf"));
    assert_int_equal(s->mesh_count, 2);
    for (int m = 0; m < 2; m++)
        for (uint32_t v = 0; v < 4; v++)
            for (int k = 0; k < 2; k++)
                assert_float_equal(s->meshes[m].texcoords[2 * v + k],
                                   s->meshes[m].positions[3 * v + k], 1e-6);
    scene_free(s);
    cJSON_Delete(doc);
}

static void test_interleaved_and_sparse(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    /* positions and normals interleaved: 24 bytes a vertex after the base data */
    for (int v = 0; v < 4; v++) {
        put(&b, BUFFER_SIZE + 24 * (size_t)v, b.data + POSITIONS + 12 * v, 12);
        put(&b, BUFFER_SIZE + 24 * (size_t)v + 12, b.data + NORMALS + 12 * v, 12);
    }
    set(item_at(doc, "buffers", "0", NULL), "byteLength", "260");
    cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "bufferViews"),
                         parse("{\"buffer\": 0, \"byteOffset\": 164, \"byteLength\": 96, "
                               "\"byteStride\": 24}"));
    set(item_at(doc, "accessors", "0", NULL), "bufferView", "6");
    set(item_at(doc, "accessors", "1", NULL), "bufferView", "6");
    set(item_at(doc, "accessors", "1", NULL), "byteOffset", "12");
    scene *s = load_or_fail(write_scene(doc, &b, "interleaved.gltf"));
    assert_uv(s, 1e-6); /* uv = xy: the positions came out right */
    assert_non_null(s->meshes[0].normals);
    assert_float_equal(s->meshes[0].normals[3 * 3 + 2], 1, 1e-6);
    scene_free(s);
    cJSON_Delete(doc);
    /* a sparse accessor moves vertex 3 to (1, 1, 0.5) */
    doc = base_scene(&b);
    const uint16_t number = 3;
    const float moved[3] = {1, 1, 0.5f};
    put(&b, BUFFER_SIZE, &number, 2);
    put(&b, BUFFER_SIZE + 4, moved, sizeof moved);
    set(item_at(doc, "buffers", "0", NULL), "byteLength", "180");
    cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "bufferViews"),
                         parse("{\"buffer\": 0, \"byteOffset\": 164, \"byteLength\": 16}"));
    cJSON_AddItemToObject(item_at(doc, "accessors", "0", NULL), "sparse",
                          parse("{\"count\": 1, \"indices\": {\"bufferView\": 6, "
                                "\"componentType\": 5123}, \"values\": {\"bufferView\": 6, "
                                "\"byteOffset\": 4}}"));
    set(item_at(doc, "accessors", "0", NULL), "max", "[1, 1, 0.5]");
    s = load_or_fail(write_scene(doc, &b, "sparse.gltf"));
    assert_float_equal(s->meshes[0].positions[3 * 3 + 2], 0.5, 1e-6);
    scene_free(s);
    /* the same over an interleaved bufferView: Assimp 5.2 reads its base as if packed, past its
     * end (vertices 1 to 3 from the bytes of normals, and a heap overflow): refused */
    for (int v = 0; v < 4; v++) {
        put(&b, 180 + 24 * (size_t)v, b.data + POSITIONS + 12 * v, 12);
        put(&b, 180 + 24 * (size_t)v + 12, b.data + NORMALS + 12 * v, 12);
    }
    set(item_at(doc, "buffers", "0", NULL), "byteLength", "276");
    cJSON_DeleteItemFromObject(item_at(doc, "buffers", "0", NULL), "uri"); /* the new bytes */
    cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "bufferViews"),
                         parse("{\"buffer\": 0, \"byteOffset\": 180, \"byteLength\": 96, "
                               "\"byteStride\": 24}"));
    set(item_at(doc, "accessors", "0", NULL), "bufferView", "7");
    assert_refused(write_scene(doc, &b, "sparse-strided.gltf"), "/accessors/0/sparse",
                   "byteStride (24)", NULL);
    cJSON_Delete(doc);
}

static void test_readable_extensions(void **state)
{
    (void)state;
    if (access(DRACO_MODEL, R_OK))
        fail_msg("%s is missing: scripts/install-deps.sh installs assimp-testmodels",
                 DRACO_MODEL);
    scene *s = load_or_fail(DRACO_MODEL); /* requires KHR_draco_mesh_compression */
    assert_true(s->mesh_count > 0);
    scene_free(s);
    bytes b;
    cJSON *doc = base_scene(&b);
    set(doc, "extensionsUsed", "[\"KHR_texture_basisu\", \"KHR_materials_emissive_strength\"]");
    set(doc, "extensionsRequired", "[\"KHR_texture_basisu\", \"KHR_materials_emissive_strength\"]");
    s = load_or_fail(write_scene(doc, &b, "basisu.gltf"));
    scene_free(s);
    cJSON_Delete(doc);
}

/* ---- cameras and lights ---- */

static void test_bad_cameras_refused(void **state)
{
    (void)state;
    const char *cases[][3] = {
        {"{\"yfov\": 0, \"znear\": 0.1}", "/cameras/0/perspective/yfov", "yfov 0"},
        {"{\"yfov\": -0.7, \"znear\": 0.1}", "/cameras/0/perspective/yfov", "yfov -0.7"},
        {"{\"yfov\": 0.7, \"aspectRatio\": -1.5, \"znear\": 0.1}",
         "/cameras/0/perspective/aspectRatio", "-1.5"},
        {"{\"yfov\": 0.7, \"znear\": 0}", "/cameras/0/perspective/znear", "znear"},
        {"{\"yfov\": 0.7, \"znear\": 1, \"zfar\": 0.5}", "/cameras/0/perspective/zfar", "zfar"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        bytes b;
        cJSON *doc = base_scene(&b);
        char camera[256];
        snprintf(camera, sizeof camera,
                 "[{\"name\": \"front\", \"type\": \"perspective\", \"perspective\": %s}]",
                 cases[i][0]);
        set(doc, "cameras", camera);
        set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0, \"children\": [1]}, "
                          "{\"camera\": 0, \"translation\": [0, 0, 5]}]");
        assert_refused(write_scene(doc, &b, "camera.gltf"), "camera 'front'", cases[i][1],
                       cases[i][2], NULL);
        cJSON_Delete(doc);
    }
}

static void test_lights_named(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    set(doc, "extensionsUsed", "[\"KHR_lights_punctual\"]");
    set(doc, "extensions", "{\"KHR_lights_punctual\": {\"lights\": [{\"name\": \"sky\", "
                           "\"type\": \"area\"}]}}");
    set(doc, "nodes", "[{\"name\": \"ground\", \"mesh\": 0, \"children\": [1]}, "
                      "{\"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}}]");
    assert_refused(write_scene(doc, &b, "light.gltf"),
                   "/extensions/KHR_lights_punctual/lights/0/type", "light 'sky'", "'area'",
                   "point, spot, directional", NULL);
    set(doc, "extensions", "{\"KHR_lights_punctual\": {\"lights\": [{\"type\": \"spot\"}]}}");
    assert_refused(write_scene(doc, &b, "spot.gltf"), "/extensions/KHR_lights_punctual/lights/0",
                   "spot parameters", NULL);
    cJSON_Delete(doc);
}

/* Two lights and the camera on nodes that share one name with the mesh node: each stands at its
 * own node; the light used by two nodes is two lights. */
static void test_lights_and_camera_at_their_nodes(void **state)
{
    (void)state;
    bytes b;
    cJSON *doc = base_scene(&b);
    set(doc, "extensionsUsed", "[\"KHR_lights_punctual\"]");
    set(doc, "extensions", "{\"KHR_lights_punctual\": {\"lights\": [{\"type\": \"point\", "
                           "\"intensity\": 2}]}}");
    set(doc, "cameras", "[{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.5, "
                        "\"znear\": 0.1}}]");
    set(doc, "nodes",
        "[{\"name\": \"part\", \"mesh\": 0, \"children\": [1, 2, 3]},\n"
        " {\"name\": \"part\", \"translation\": [0, 0, 3],\n"
        "  \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
        " {\"name\": \"part\", \"translation\": [5, 0, 3],\n"
        "  \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
        " {\"name\": \"part\", \"translation\": [0.5, 0.5, 4], \"camera\": 0}]");
    scene *s = load_or_fail(write_scene(doc, &b, "named.gltf"));
    assert_int_equal(s->light_count, 2);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_POINT);
    assert_float_equal(s->lights[0].position[0], 0, 1e-6);
    assert_float_equal(s->lights[0].position[2], 3, 1e-6);
    assert_float_equal(s->lights[1].position[0], 5, 1e-6);
    assert_float_equal(s->lights[1].emission[0], 2, 1e-6);
    assert_float_equal(s->camera.origin[0], 0.5, 1e-6);
    assert_float_equal(s->camera.origin[2], 4, 1e-6);
    assert_float_equal(s->camera.tan_half_y, tan(0.25), 1e-6);
    scene_free(s);
    cJSON_Delete(doc);
}

/* ---- where damaged files are damaged ---- */

static void test_damaged_json_and_glb(void **state)
{
    (void)state;
    char path[128];
    snprintf(path, sizeof path, "%s/broken.gltf", dir);
    const char *text = "{\"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [1, 2,, 3]}\n";
    write_file(path, text, strlen(text));
    assert_refused(path, "line 2, column 18", "not valid JSON at ','", NULL);
    text = "{\"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [";
    write_file(path, text, strlen(text));
    assert_refused(path, "line 2, column 13", "cut short", NULL);
    text = "{\"asset\": {\"version\": \"2.0\"}} trailing";
    write_file(path, text, strlen(text));
    assert_refused(path, "line 1, column 31", "after the end", NULL);

    bytes b;
    cJSON *doc = base_scene(&b);
    const char *glb = write_scene(doc, &b, "damaged.glb");
    size_t size = 0;
    FILE *f = fopen(glb, "rb");
    assert_non_null(f);
    char *data = slurp(f);
    fseek(f, 0, SEEK_END);
    size = (size_t)ftell(f);
    fclose(f);
    unsigned char *copy = malloc(size);
    struct {
        size_t at;
        uint32_t value;
        const char *where, *what;
    } cases[] = {
        {4, 3, "byte 4", "version 3"},
        {8, 100000, "byte 8", "length of 100000"},
        {12, 100000, "byte 12", "a chunk of 100000 bytes"},
        {16, 0x004E4942, "byte 16", "not JSON"},
        {0, 0x12345678, "byte 0", "not a GLB file"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        memcpy(copy, data, size);
        put_u32(copy + cases[i].at, cases[i].value);
        write_file(glb, copy, size);
        assert_refused(glb, cases[i].where, cases[i].what, NULL);
    }
    memcpy(copy, data, size);
    copy[20] = '#'; /* the JSON chunk's first byte */
    write_file(glb, copy, size);
    assert_refused(glb, "byte 20", "line 1, column 1 of the JSON chunk", NULL);
    memcpy(copy, data, size);
    write_file(path, copy, size); /* a GLB named .gltf */
    assert_refused(path, "byte 0", "a GLB file", ".glb", NULL);
    free(copy);
    free(data);
    cJSON_Delete(doc);
}

/* ---- many nodes ---- */

/* A scene of `nodes` nodes named "part" holding the mesh, every tenth also a point light and
 * every tenth a camera, written as dir/name. */
static const char *write_many_nodes(int nodes, int named, const char *name)
{
    bytes b;
    cJSON *doc = base_scene(&b);
    cJSON *array = cJSON_CreateArray(), *roots = cJSON_CreateArray(), *cameras = cJSON_CreateArray();
    for (int n = 0; n < nodes; n++) {
        cJSON *node = cJSON_CreateObject();
        char label[32];
        snprintf(label, sizeof label, "part%d", n);
        cJSON_AddStringToObject(node, "name", named ? "part" : label);
        cJSON_AddNumberToObject(node, "mesh", 0);
        const double at[3] = {2.0 * n, 0, 0};
        cJSON_AddItemToObject(node, "translation", cJSON_CreateDoubleArray(at, 3));
        if (n % 10 == 1)
            cJSON_AddItemToObject(node, "extensions",
                                  parse("{\"KHR_lights_punctual\": {\"light\": 0}}"));
        if (n % 10 == 2) {
            cJSON_AddNumberToObject(node, "camera", cJSON_GetArraySize(cameras));
            cJSON_AddItemToArray(cameras, parse("{\"type\": \"perspective\", \"perspective\": "
                                                "{\"yfov\": 0.7, \"znear\": 0.1}}"));
        }
        cJSON_AddItemToArray(array, node);
        cJSON_AddItemToArray(roots, cJSON_CreateNumber(n));
    }
    cJSON_ReplaceItemInObject(doc, "nodes", array);
    cJSON_ReplaceItemInObject(item_at(doc, "scenes", "0", NULL), "nodes", roots);
    cJSON_AddItemToObject(doc, "cameras", cameras);
    set(doc, "extensionsUsed", "[\"KHR_lights_punctual\"]");
    set(doc, "extensions", "{\"KHR_lights_punctual\": {\"lights\": [{\"type\": \"point\"}]}}");
    const char *path = write_scene(doc, &b, name);
    cJSON_Delete(doc);
    return path;
}

static double seconds_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void test_many_nodes_load_in_linear_time(void **state)
{
    (void)state;
    const char *path = write_many_nodes(20000, 1, "many.gltf");
    double start = seconds_now();
    scene *s = load_or_fail(path);
    double took = seconds_now() - start;
    printf("  20,000 nodes of one name, 2,000 lights, 2,000 cameras: %.2f s\n", took);
    assert_int_equal(s->mesh_count, 20000);
    assert_int_equal(s->light_count, 2000);
    assert_string_equal(s->meshes[0].name, "part/meshes[0]");
    assert_string_equal(s->meshes[19999].name, "part/meshes[0].20000");
    assert_float_equal(s->lights[1999].position[0], 2.0 * 19991, 1e-3);
    assert_float_equal(s->camera.origin[0], 2.0 * 2, 1e-6); /* the first camera */
    scene_free(s);
    /* before: 40 s and more on the test machine (quadratic); now well under a second */
    if (took > 10)
        fail_msg("loading took %.1f s", took);
}

/* A load long enough to show progress (at least a second and a half without --quiet) shows it,
 * and under --quiet does not. `idmr importance` loads the scene, then fails on a device that
 * does not exist. */
static void test_long_load_progress_unless_quiet(void **state)
{
    (void)state;
    for (int nodes = 100000;; nodes *= 2) {
        const char *path = write_many_nodes(nodes, 0, "long.gltf");
        double start = seconds_now();
        run_result loud = run("bin/idmr importance %s -o %s/out --device 999", path, dir);
        double took = seconds_now() - start;
        assert_int_not_equal(loud.status, 0); /* after loading: no device 999 */
        printf("  %d nodes: %.1f s\n", nodes, took);
        if (took < 2.5 && nodes < 1600000) { /* too quick to show progress: a longer one */
            run_free(&loud);
            continue;
        }
        if (!strstr(loud.err, "loading glTF"))
            fail_msg("%.1f s of loading without progress: %s", took, loud.err);
        run_result quiet = run("bin/idmr importance %s -o %s/out --device 999 --quiet", path, dir);
        assert_int_not_equal(quiet.status, 0);
        if (strstr(quiet.err, "loading glTF"))
            fail_msg("progress under --quiet: %s", quiet.err);
        run_free(&quiet);
        run_free(&loud);
        unlink(path);
        break;
    }
}

int main(void)
{
    (void)assert_succeeded; /* command_common.h's, unused here */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_index_out_of_range),
        cmocka_unit_test(test_bad_base64),
        cmocka_unit_test(test_component_types_and_strides),
        cmocka_unit_test(test_required_extensions),
        cmocka_unit_test(test_structure),
        cmocka_unit_test(test_normalized_texcoords),
        cmocka_unit_test(test_interleaved_and_sparse),
        cmocka_unit_test(test_readable_extensions),
        cmocka_unit_test(test_bad_cameras_refused),
        cmocka_unit_test(test_lights_named),
        cmocka_unit_test(test_lights_and_camera_at_their_nodes),
        cmocka_unit_test(test_damaged_json_and_glb),
        cmocka_unit_test(test_many_nodes_load_in_linear_time),
        cmocka_unit_test(test_long_load_progress_unless_quiet),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
