/* test_gltf.c — glTF 2.0 read through Assimp (host/io/gltf/gltf.cc), on the real models of
 * Debian's assimp-testmodels (/usr/share/assimp/models/glTF2; scripts/install-deps.sh installs
 * them: a missing model fails the test, it never skips):
 *   - Cameras.gltf: the perspective camera at its node (0.5, 0.5, 3) looking down -z with
 *     yfov 0.7 (tan_half_y = tan 0.35) on a square film; the orthographic one is skipped;
 *   - BoxTextured.gltf: one mesh of 24 vertices and 12 triangles with normals and uv (v turned
 *     as Mitsuba reads it: the file's uv lie in [0, 6] × [0, 1]), its base colour texture read
 *     from beside the file; no camera (framed from +z) and no light (a white environment);
 *   - 2CylinderEngine.glb (115 mesh instances under rotated and translated nodes): written back
 *     with every instance replaced by its own world-space triangles, it reads back with the
 *     same counts, triangles, materials and positions (to 1e-5 of the scene's diagonal), so the
 *     transforms go out and back exactly; written with every instance decimated to a quarter,
 *     it reads back with those counts and the same bounding box (to 1 %);
 *   - a glTF written by the test: glass (transmission, IOR), rough gold under a mirroring node
 *     (its winding turned back), a two-sided emissive lamp (an area light), and a point, a spot
 *     (cone angles, turned by its node) and a directional light where their nodes put them;
 *   - a missing file, and Debian's broken samples (an index out of range, which Assimp dropped
 *     in silence, views past their buffer, a node its own ancestor, wrong types), are errors
 *     naming the file and where it is wrong.
 * The reduced scenes io/gltf/gltf_write.c writes are read by readers nobody here wrote
 * (scripts/gltf-check, from .venv: trimesh's loader, pygltflib, the glTF JSON schema, and checks of
 * POSITION min and max, index ranges and unit normals), and by Assimp again:
 *   - a lit scene (KHR_lights_punctual on two nodes, object-valued extras on nodes, asset, scene,
 *     meshes, primitives, materials and a camera; an emissive panel sharing the ground's
 *     accessors) reduced by `idmr reduce` (Assimp's exporter aborted on it) keeps every node,
 *     light, camera, material, scene, asset and mesh description exactly, one vertex for each
 *     the report counts, one buffer; as a .glb with a vendor extension on a node, the BIN chunk
 *     keeps the input's data and accessors where they were;
 *   - a two-primitive mesh used by three nodes (under a scaled parent; one mirrored and turned;
 *     one by a matrix): two reduced differently get meshes of their own, the third keeps mesh 0,
 *     and every instance lies where the loader put it, facing as it did;
 *   - scenes trimesh exported (.glb; .gltf with four external buffers and shared accessors)
 *     reduce into files trimesh reads with the reported vertices, extras and camera kept;
 *   - the textured box written back keeps uv (not turned), normals and texture, also bundled;
 *   - real files of other exporters decimated to half (test_real_models_written_back says
 *     which) come out without a problem, and Assimp reads back each instance as written.
 * Runs from the repository root (bin/idmr, scripts/), as `make test` does. */
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
#include <unistd.h>

#include "core/error.h"
#include "core/files.h"
#include "io/gltf/gltf.h"
#include "core/shapes.h"
#include "reduce/decimate.h"

#define MODELS "/usr/share/assimp/models/glTF2"
#define CAMERAS MODELS "/cameras/Cameras.gltf"
#define BOX MODELS "/BoxTextured-glTF/BoxTextured.gltf"
#define ENGINE MODELS "/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"

static scene *load_or_fail(const char *path)
{
    if (access(path, R_OK))
        fail_msg("%s is missing: scripts/install-deps.sh installs assimp-testmodels", path);
    scene *s = gltf_load(path);
    if (!s)
        fail_msg("%s", error_message());
    /* these tests read every node's mesh, shared ones too: a later copy of a shared primitive
     * holds its geometry only once restored (core/scene.h) */
    for (size_t m = 0; m < s->mesh_count; m++)
        if (scene_mesh_restore(s, m))
            fail_msg("%s", error_message());
    return s;
}

static void test_camera_at_its_node(void **state)
{
    (void)state;
    scene *s = load_or_fail(CAMERAS);
    assert_true(s->has_camera);
    const idmr_camera *c = &s->camera;
    const float origin[3] = {0.5f, 0.5f, 3.0f}, forward[3] = {0, 0, -1}, up[3] = {0, 1, 0},
                right[3] = {1, 0, 0};
    for (int k = 0; k < 3; k++) {
        assert_float_equal(c->origin[k], origin[k], 1e-6);
        assert_float_equal(c->forward[k], forward[k], 1e-6);
        assert_float_equal(c->up[k], up[k], 1e-6);
        assert_float_equal(c->right[k], right[k], 1e-6);
    }
    assert_float_equal(c->tan_half_y, tan(0.35), 1e-6);
    assert_float_equal(c->tan_half_x, tan(0.35), 1e-6);
    assert_int_equal(c->width, 1024);
    assert_int_equal(c->height, 1024);
    scene_free(s);
}

static void test_box_textured(void **state)
{
    (void)state;
    scene *s = load_or_fail(BOX);
    assert_int_equal(s->mesh_count, 1);
    const scene_mesh *m = &s->meshes[0];
    assert_int_equal(m->vertex_count, 24);
    assert_int_equal(m->triangle_count, 12);
    assert_non_null(m->texcoords);
    assert_non_null(m->normals);
    assert_true(m->file_normals);
    assert_true(m->flat_normals); /* a box: each face's vertices carry its normal */
    float u_low = INFINITY, u_high = -INFINITY, v_low = INFINITY, v_high = -INFINITY;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        u_low = fminf(u_low, m->texcoords[2 * v]), u_high = fmaxf(u_high, m->texcoords[2 * v]);
        v_low = fminf(v_low, m->texcoords[2 * v + 1]);
        v_high = fmaxf(v_high, m->texcoords[2 * v + 1]);
    }
    assert_float_equal(u_low, 0, 1e-6);
    assert_float_equal(u_high, 6, 1e-6);
    assert_float_equal(v_low, 0, 1e-6);
    assert_float_equal(v_high, 1, 1e-6);
    const idmr_material *material = &s->materials[m->material];
    assert_int_equal(material->kind, IDMR_MATERIAL_DIFFUSE);
    assert_true(material->texture >= 0);
    const char *file = s->textures[material->texture].file;
    assert_non_null(strstr(file, "CesiumLogoFlat.png"));
    assert_true(s->has_camera); /* framed from +z */
    assert_float_equal(s->camera.forward[2], -1, 1e-6);
    assert_int_equal(s->light_count, 1);
    assert_int_equal(s->lights[0].kind, IDMR_LIGHT_ENVIRONMENT);
    scene_free(s);
}

/* The mesh as `idmr reduce` decimates it: normals only where they are the file's and smooth. */
static mesh_data world_mesh(const scene_mesh *m)
{
    mesh_data d = shapes_scene_mesh_view(m);
    if (!m->file_normals || m->flat_normals)
        d.normals = NULL;
    return d;
}

/* A decimated copy of scene mesh `m` (about `share` of its vertices, at least 3) into *out, as
 * `idmr reduce --method quadric` makes it. */
static void decimate_to(const scene_mesh *m, double share, decimate_output *out)
{
    mesh_data in = world_mesh(m);
    decimate_input d;
    memset(&d, 0, sizeof d);
    d.name = m->name;
    d.positions = in.positions;
    d.vertex_count = in.vertex_count;
    d.indices = in.indices;
    d.triangle_count = in.triangle_count;
    d.texcoords = in.texcoords;
    d.normals = in.normals;
    d.target_vertices = (uint64_t)fmax(3, share * in.vertex_count);
    d.max_normal_angle = 60;
    if (decimate_mesh(&d, DECIMATE_QUADRIC, out))
        fail_msg("%s", error_message());
}

/* Writes `s` (read from ENGINE) with every instance replaced by meshes[i] into a fresh
 * directory and reads it back. */
static scene *write_and_read(const scene *s, const mesh_data *meshes, char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/idmr-test-gltf-XXXXXX");
    assert_non_null(mkdtemp(dir));
    gltf_replacement *replacements = calloc(s->mesh_count, sizeof *replacements);
    for (size_t i = 0; i < s->mesh_count; i++)
        replacements[i] = (gltf_replacement){s->meshes[i].xml_line, &meshes[i], 0};
    if (gltf_write_reduced(s->file, dir, replacements, s->mesh_count, 0))
        fail_msg("%s", error_message());
    free(replacements);
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, gltf_output_name(s->file));
    assert_string_equal(gltf_output_name(s->file), "scene.glb");
    return load_or_fail(path);
}

static void test_engine_written_back_unchanged(void **state)
{
    (void)state;
    scene *s = load_or_fail(ENGINE);
    assert_int_equal(s->mesh_count, 115);
    mesh_data *meshes = calloc(s->mesh_count, sizeof *meshes);
    for (size_t i = 0; i < s->mesh_count; i++)
        meshes[i] = world_mesh(&s->meshes[i]);
    char dir[64];
    scene *back = write_and_read(s, meshes, dir, sizeof dir);
    assert_int_equal(back->mesh_count, s->mesh_count);
    assert_int_equal(back->material_count, s->material_count);
    double tolerance = 1e-5 * scene_diagonal(s), worst = 0;
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *a = &s->meshes[i], *b = &back->meshes[i];
        assert_int_equal(a->vertex_count, b->vertex_count);
        assert_int_equal(a->triangle_count, b->triangle_count);
        assert_memory_equal(a->indices, b->indices, sizeof(uint32_t) * 3 * a->triangle_count);
        for (size_t k = 0; k < 3 * (size_t)a->vertex_count; k++)
            worst = fmax(worst, fabs((double)a->positions[k] - b->positions[k]));
    }
    printf("positions out and back: at most %.3g apart (diagonal %.4g)\n", worst,
           scene_diagonal(s));
    assert_true(worst <= tolerance);
    scene_free(back);
    free(meshes);
    files_remove_tree(dir);
    scene_free(s);
}

static void test_engine_decimated_round_trip(void **state)
{
    (void)state;
    scene *s = load_or_fail(ENGINE);
    decimate_output *outputs = calloc(s->mesh_count, sizeof *outputs);
    mesh_data *meshes = calloc(s->mesh_count, sizeof *meshes);
    uint64_t total = 0;
    for (size_t i = 0; i < s->mesh_count; i++) {
        decimate_to(&s->meshes[i], 0.25, &outputs[i]);
        meshes[i] = outputs[i].mesh;
        total += meshes[i].vertex_count;
    }
    char dir[64];
    scene *back = write_and_read(s, meshes, dir, sizeof dir);
    assert_int_equal(back->mesh_count, s->mesh_count);
    assert_int_equal(back->vertex_count, total);
    assert_true(back->vertex_count < s->vertex_count / 2);
    double diagonal = scene_diagonal(s);
    for (int k = 0; k < 3; k++) {
        assert_float_equal(back->bbox_min[k], s->bbox_min[k], 0.01 * diagonal);
        assert_float_equal(back->bbox_max[k], s->bbox_max[k], 0.01 * diagonal);
    }
    for (size_t i = 0; i < s->mesh_count; i++) {
        assert_int_equal(back->meshes[i].vertex_count, meshes[i].vertex_count);
        decimate_output_free(&outputs[i]);
    }
    scene_free(back);
    free(meshes);
    free(outputs);
    files_remove_tree(dir);
    scene_free(s);
}

/* A glTF written here: three one-triangle meshes (glass through KHR_materials_transmission and
 * _ior; rough gold under a mirroring node; a two-sided emissive lamp) and the three
 * KHR_lights_punctual kinds (a point light at (0, 2, 0), a spot at (0, 3, 0) turned to look
 * down, a directional light along its node's -z). */
static const char LIGHTS_GLTF[] =
    "{\"asset\": {\"version\": \"2.0\"},\n"
    " \"extensionsUsed\": [\"KHR_lights_punctual\", \"KHR_materials_transmission\",\n"
    "                    \"KHR_materials_ior\"],\n"
    " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [\n"
    "   {\"type\": \"point\", \"color\": [1, 0.5, 0.25], \"intensity\": 4},\n"
    "   {\"type\": \"spot\", \"intensity\": 2,\n"
    "    \"spot\": {\"innerConeAngle\": 0.2, \"outerConeAngle\": 0.5}},\n"
    "   {\"type\": \"directional\", \"intensity\": 3}]}},\n"
    " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 2, 3, 4, 5]}],\n"
    " \"nodes\": [\n"
    "   {\"mesh\": 0},\n"
    "   {\"mesh\": 1, \"translation\": [5, 0, 0], \"scale\": [-1, 1, 1]},\n"
    "   {\"mesh\": 2, \"translation\": [10, 0, 0]},\n"
    "   {\"translation\": [0, 2, 0],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
    "   {\"translation\": [0, 3, 0], \"rotation\": [-0.70710678, 0, 0, 0.70710678],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},\n"
    "   {\"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}}],\n"
    " \"meshes\": [\n"
    "   {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "                    \"material\": 0}]},\n"
    "   {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "                    \"material\": 1}]},\n"
    "   {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "                    \"material\": 2}]}],\n"
    " \"materials\": [\n"
    "   {\"name\": \"glass\",\n"
    "    \"pbrMetallicRoughness\": {\"metallicFactor\": 0, \"roughnessFactor\": 0},\n"
    "    \"extensions\": {\"KHR_materials_transmission\": {\"transmissionFactor\": 1},\n"
    "                   \"KHR_materials_ior\": {\"ior\": 1.33}}},\n"
    "   {\"name\": \"gold\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [1, 0.8, 0.3, 1],\n"
    "    \"metallicFactor\": 1, \"roughnessFactor\": 0.5}},\n"
    "   {\"name\": \"lamp\", \"emissiveFactor\": [1, 1, 1], \"doubleSided\": true,\n"
    "    \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.5, 0.5, 0.5, 1]}}],\n"
    " \"buffers\": [{\"uri\": \"triangle.bin\", \"byteLength\": 44}],\n"
    " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
    "                 {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}],\n"
    " \"accessors\": [\n"
    "   {\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\",\n"
    "    \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
    "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}]}\n";

static void write_lights_scene(char *dir, size_t size, char *path, size_t path_size)
{
    snprintf(dir, size, "/tmp/idmr-test-gltf-XXXXXX");
    assert_non_null(mkdtemp(dir));
    char bin[128];
    snprintf(bin, sizeof bin, "%s/triangle.bin", dir);
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t indices[4] = {0, 1, 2, 0};
    FILE *f = fopen(bin, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(positions, sizeof positions, 1, f), 1);
    assert_int_equal(fwrite(indices, sizeof indices, 1, f), 1);
    fclose(f);
    snprintf(path, path_size, "%s/lights.gltf", dir);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(LIGHTS_GLTF, f);
    fclose(f);
}

static void check_vector(const float *v, float x, float y, float z)
{
    assert_float_equal(v[0], x, 1e-5);
    assert_float_equal(v[1], y, 1e-5);
    assert_float_equal(v[2], z, 1e-5);
}

static void test_lights_and_materials(void **state)
{
    (void)state;
    char dir[64], path[128];
    write_lights_scene(dir, sizeof dir, path, sizeof path);
    scene *s = load_or_fail(path);
    assert_int_equal(s->mesh_count, 3);
    const idmr_material *glass = &s->materials[s->meshes[0].material];
    assert_int_equal(glass->kind, IDMR_MATERIAL_DIELECTRIC);
    assert_float_equal(glass->int_ior, 1.33, 1e-6);
    const idmr_material *gold = &s->materials[s->meshes[1].material];
    assert_int_equal(gold->kind, IDMR_MATERIAL_GLOSSY);
    assert_float_equal(gold->roughness, 0.25, 1e-6);
    check_vector(gold->specular, 1, 0.8f, 0.3f);
    check_vector(gold->reflectance, 0, 0, 0);
    /* The mirroring node turns the winding back: the triangle still faces +z. */
    double n[3];
    const scene_mesh *mirrored = &s->meshes[1];
    const float *p = mirrored->positions;
    const uint32_t *ix = mirrored->indices;
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++)
        e1[k] = p[3 * ix[1] + k] - p[3 * ix[0] + k], e2[k] = p[3 * ix[2] + k] - p[3 * ix[0] + k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    assert_true(n[2] > 0 && fabs(n[0]) < 1e-6 && fabs(n[1]) < 1e-6);
    assert_float_equal(s->bbox_min[0], 0, 1e-6);
    assert_float_equal(s->bbox_max[0], 11, 1e-6);
    const scene_mesh *lamp = &s->meshes[2];
    assert_true(lamp->light >= 0);
    assert_true(s->materials[lamp->material].flags & IDMR_MATERIAL_TWOSIDED);
    const idmr_light *area = &s->lights[lamp->light];
    assert_int_equal(area->kind, IDMR_LIGHT_AREA);
    check_vector(area->emission, 1, 1, 1);
    assert_int_equal(s->light_count, 4);
    const idmr_light *point = &s->lights[1], *spot = &s->lights[2], *sun = &s->lights[3];
    assert_int_equal(point->kind, IDMR_LIGHT_POINT);
    check_vector(point->position, 0, 2, 0);
    check_vector(point->emission, 4, 2, 1);
    assert_int_equal(spot->kind, IDMR_LIGHT_SPOT);
    check_vector(spot->position, 0, 3, 0);
    check_vector(spot->direction, 0, -1, 0);
    check_vector(spot->emission, 2, 2, 2);
    assert_float_equal(spot->cos_cutoff, cos(0.5), 1e-6);
    assert_float_equal(spot->cos_falloff_start, cos(0.2), 1e-6);
    assert_int_equal(sun->kind, IDMR_LIGHT_DIRECTIONAL);
    check_vector(sun->direction, 0, 0, -1);
    check_vector(sun->emission, 3, 3, 3);
    scene_free(s);
    files_remove_tree(dir);
}

static void check_refused(const char *path, const char *expected)
{
    scene *s = gltf_load(path);
    assert_null(s);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), path));
    assert_non_null(strstr(error_message(), expected));
    error_clear();
}

static void test_bad_files_refused(void **state)
{
    (void)state;
    check_refused("/nonexistent/scene.gltf", "cannot read it");
    /* Debian's broken samples, each refused where it is broken (test_gltf_inputs.c: more) */
    const char *broken[][2] = {
        {"/IndexOutOfRange/AllIndicesOutOfRange.gltf", "/meshes/0/primitives/0/indices"},
        {"/IndexOutOfRange/IndexOutOfRange.gltf", "index 255, but the primitive has 24"},
        {"/IncorrectVertexArrays/Cube.gltf", "/bufferViews/2"},
        {"/RecursiveNodes/RecursiveNodes.gltf", "cycle"},
        {"/wrongTypes/badArray.gltf", "/meshes/0/primitives: not an array"},
        {"/SchemaFailures/sceneWrongType.gltf", "/scene: \"hello\""},
    };
    for (size_t i = 0; i < sizeof broken / sizeof *broken; i++) {
        char path[256];
        snprintf(path, sizeof path, "%s%s", MODELS, broken[i][0]);
        if (access(path, R_OK))
            fail_msg("%s is missing: scripts/install-deps.sh installs assimp-testmodels", path);
        check_refused(path, broken[i][1]);
    }
}

/* ---- the reduced scene as readers nobody here wrote see it (scripts/gltf-check: trimesh,
 * pygltflib and the glTF JSON schema) ---- */

/* A glTF document under construction with its binary data. */
typedef struct test_bin {
    unsigned char *data;
    size_t size;
} test_bin;

static cJSON *parse_or_fail(const char *text)
{
    cJSON *json = cJSON_Parse(text);
    if (!json)
        fail_msg("not JSON near: %.80s", cJSON_GetErrorPtr());
    return json;
}

/* Appends `size` bytes at a 4-byte boundary as a new bufferView of buffer 0; its index. */
static int add_view(cJSON *doc, test_bin *bin, const void *bytes, size_t size)
{
    size_t offset = (bin->size + 3) & ~(size_t)3;
    bin->data = realloc(bin->data, offset + size);
    memset(bin->data + bin->size, 0, offset - bin->size);
    memcpy(bin->data + offset, bytes, size);
    bin->size = offset + size;
    cJSON *views = cJSON_GetObjectItem(doc, "bufferViews");
    cJSON *view = cJSON_CreateObject();
    cJSON_AddNumberToObject(view, "buffer", 0);
    cJSON_AddNumberToObject(view, "byteOffset", (double)offset);
    cJSON_AddNumberToObject(view, "byteLength", (double)size);
    cJSON_AddItemToArray(views, view);
    return cJSON_GetArraySize(views) - 1;
}

static int add_accessor(cJSON *doc, int view, int component, int count, const char *type)
{
    cJSON *accessors = cJSON_GetObjectItem(doc, "accessors");
    cJSON *accessor = cJSON_CreateObject();
    cJSON_AddNumberToObject(accessor, "bufferView", view);
    cJSON_AddNumberToObject(accessor, "componentType", component);
    cJSON_AddNumberToObject(accessor, "count", count);
    cJSON_AddStringToObject(accessor, "type", type);
    cJSON_AddItemToArray(accessors, accessor);
    return cJSON_GetArraySize(accessors) - 1;
}

/* An n × n grid over [-1, 1]² in z = 0.2 sin(3x) cos(2y), with its normals, uv (x, y mapped to
 * [0, 1]) and 2 (n-1)² triangles as unsigned shorts, added to `doc` (bufferViews, accessors)
 * and `bin`: the accessors POSITION, NORMAL, TEXCOORD_0 and indices, from the returned one on. */
static int add_grid(cJSON *doc, test_bin *bin, int n)
{
    int vertices = n * n, triangles = 2 * (n - 1) * (n - 1);
    float *positions = malloc(sizeof(float) * 3 * vertices);
    float *normals = malloc(sizeof(float) * 3 * vertices);
    float *uv = malloc(sizeof(float) * 2 * vertices);
    uint16_t *indices = malloc(sizeof(uint16_t) * 3 * triangles);
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int v = j * n + i;
            double x = -1 + 2.0 * i / (n - 1), y = -1 + 2.0 * j / (n - 1);
            double dx = 0.6 * cos(3 * x) * cos(2 * y), dy = -0.4 * sin(3 * x) * sin(2 * y);
            double length = sqrt(dx * dx + dy * dy + 1);
            float p[3] = {(float)x, (float)y, (float)(0.2 * sin(3 * x) * cos(2 * y))};
            for (int k = 0; k < 3; k++) {
                positions[3 * v + k] = p[k];
                low[k] = fmin(low[k], p[k]), high[k] = fmax(high[k], p[k]);
            }
            normals[3 * v] = (float)(-dx / length), normals[3 * v + 1] = (float)(-dy / length);
            normals[3 * v + 2] = (float)(1 / length);
            uv[2 * v] = (float)i / (n - 1), uv[2 * v + 1] = (float)j / (n - 1);
        }
    int t = 0;
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            uint16_t a = (uint16_t)(j * n + i), b = (uint16_t)(a + 1), c = (uint16_t)(a + n),
                     d = (uint16_t)(c + 1);
            const uint16_t two[6] = {a, b, d, a, d, c};
            memcpy(&indices[3 * t], two, sizeof two);
            t += 2;
        }
    int position = add_accessor(doc, add_view(doc, bin, positions, sizeof(float) * 3 * vertices),
                                5126, vertices, "VEC3");
    cJSON *accessor = cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "accessors"), position);
    cJSON_AddItemToObject(accessor, "min", cJSON_CreateDoubleArray(low, 3));
    cJSON_AddItemToObject(accessor, "max", cJSON_CreateDoubleArray(high, 3));
    add_accessor(doc, add_view(doc, bin, normals, sizeof(float) * 3 * vertices), 5126, vertices,
                 "VEC3");
    add_accessor(doc, add_view(doc, bin, uv, sizeof(float) * 2 * vertices), 5126, vertices,
                 "VEC2");
    add_accessor(doc, add_view(doc, bin, indices, sizeof(uint16_t) * 3 * triangles), 5123,
                 3 * triangles, "SCALAR");
    free(indices);
    free(uv);
    free(normals);
    free(positions);
    return position;
}

static void write_bytes(const char *path, const void *bytes, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* Writes `doc` with `bin` as dir/name: a .gltf with its buffer in dir/grid.bin, or a .glb (a
 * 12-byte header, the JSON chunk padded with spaces, the BIN chunk). Returns the path
 * (static). */
static const char *write_document(cJSON *doc, const test_bin *bin, const char *dir,
                                  const char *name)
{
    static char path[192];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    int glb = strstr(name, ".glb") != NULL;
    cJSON *buffer = cJSON_CreateObject();
    if (!glb)
        cJSON_AddStringToObject(buffer, "uri", "grid.bin");
    cJSON_AddNumberToObject(buffer, "byteLength", (double)bin->size);
    cJSON_DeleteItemFromObject(doc, "buffers");
    cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "buffers"), buffer);
    char *text = cJSON_Print(doc);
    if (!glb) {
        char bin_path[192];
        snprintf(bin_path, sizeof bin_path, "%s/grid.bin", dir);
        write_bytes(bin_path, bin->data, bin->size);
        write_bytes(path, text, strlen(text));
    } else {
        size_t total;
        unsigned char *glb_bytes = glb_pack(text, bin->data, bin->size, &total);
        write_bytes(path, glb_bytes, total);
        free(glb_bytes);
    }
    free(text);
    return path;
}

/* Whether `actual` holds all `expected` holds: the same members (a reader may add its
 * defaults), arrays of the same length with such elements, the same strings, numbers equal as
 * doubles. On the first difference, `where` says where (a JSON path). */
static int json_contains(const cJSON *expected, const cJSON *actual, char *where, size_t size)
{
    size_t length = strlen(where);
    if (cJSON_IsNumber(expected))
        return cJSON_IsNumber(actual) && actual->valuedouble == expected->valuedouble;
    if (cJSON_IsObject(expected)) {
        const cJSON *member;
        if (!cJSON_IsObject(actual))
            return 0;
        cJSON_ArrayForEach(member, expected)
        {
            snprintf(where + length, size - length, ".%s", member->string);
            if (!json_contains(member, cJSON_GetObjectItemCaseSensitive(actual, member->string),
                               where, size))
                return 0;
        }
        where[length] = '\0';
        return 1;
    }
    if (cJSON_IsArray(expected)) {
        if (!cJSON_IsArray(actual) || cJSON_GetArraySize(actual) != cJSON_GetArraySize(expected))
            return 0;
        for (int i = 0; i < cJSON_GetArraySize(expected); i++) {
            snprintf(where + length, size - length, "[%d]", i);
            if (!json_contains(cJSON_GetArrayItem(expected, i), cJSON_GetArrayItem(actual, i),
                               where, size))
                return 0;
        }
        where[length] = '\0';
        return 1;
    }
    return actual && cJSON_Compare(expected, actual, 1);
}

/* Fails unless document.name in the output holds input.name as it was. */
static void assert_kept(const cJSON *input, const cJSON *document, const char *name)
{
    char where[256];
    snprintf(where, sizeof where, "%s", name);
    const cJSON *expected = cJSON_GetObjectItem(input, name);
    assert_non_null(expected);
    if (!json_contains(expected, cJSON_GetObjectItem(document, name), where, sizeof where)) {
        char *text = cJSON_PrintUnformatted(cJSON_GetObjectItem(document, name));
        fail_msg("the output's %s differs from the input's (at %s): %.600s", name, where,
                 text ? text : "(none)");
    }
}

/* scripts/gltf-check inspect: the file as trimesh and pygltflib read it; fails on any problem
 * they or the schema find. */
static cJSON *inspect(const char *path)
{
    run_result r = run("scripts/gltf-check inspect %s", path);
    assert_succeeded(&r);
    cJSON *json = parse_or_fail(r.out);
    run_free(&r);
    const cJSON *problems = cJSON_GetObjectItem(json, "problems");
    assert_non_null(problems);
    if (cJSON_GetArraySize(problems) > 0) {
        char *text = cJSON_Print(problems);
        fail_msg("%s: %s", path, text);
    }
    return json;
}

/* `idmr reduce input --target target` into `out` with a short importance pass. */
static void reduce_with_idmr(const char *input, double target, const char *out)
{
    run_result r = run("bin/idmr reduce %s --target %g -o %s --iterations 4 --photons 20000 "
                       "--resolution 0.25 --quiet",
                       input, target, out);
    assert_succeeded(&r);
    run_free(&r);
}

static double report_number(const char *out, const char *key)
{
    char path[192];
    snprintf(path, sizeof path, "%s/report.json", out);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char *text = slurp(f);
    fclose(f);
    cJSON *report = parse_or_fail(text);
    free(text);
    const cJSON *value = cJSON_GetObjectItem(report, key);
    assert_true(cJSON_IsNumber(value));
    double number = value->valuedouble;
    cJSON_Delete(report);
    return number;
}

/* Everything of a lit scene but its geometry: a point light and a spot on nodes
 * (KHR_lights_punctual, each node with object-valued extras), a perspective camera, two
 * materials (one emissive through KHR_materials_emissive_strength, so its mesh is an area
 * light and is not reduced), extras on the asset, the scene, meshes, primitives and materials.
 * Both meshes use the same grid accessors (as trimesh writes a mesh used twice). With
 * `vendor`, node "ground" also carries an extension the writer does not know. */
static cJSON *lit_scene(int vendor, test_bin *bin)
{
    cJSON *doc = parse_or_fail(
        "{\"asset\": {\"version\": \"2.0\", \"generator\": \"test_gltf\", \"copyright\": \"CC0\","
        "  \"extras\": {\"note\": \"asset extras\"}},"
        " \"extensionsUsed\": [\"KHR_lights_punctual\", \"KHR_materials_emissive_strength\"],"
        " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": ["
        "   {\"name\": \"bulb\", \"type\": \"point\", \"color\": [1, 0.9, 0.8], \"intensity\": 40,"
        "    \"range\": 25, \"extras\": {\"watts\": 60}},"
        "   {\"name\": \"cone\", \"type\": \"spot\", \"intensity\": 30,"
        "    \"spot\": {\"innerConeAngle\": 0.2, \"outerConeAngle\": 0.6}}]}},"
        " \"scene\": 0,"
        " \"scenes\": [{\"name\": \"main\", \"nodes\": [0, 1, 2, 3, 4],"
        "   \"extras\": {\"layers\": [\"a\", \"b\"]}}],"
        " \"nodes\": ["
        "   {\"name\": \"ground\", \"mesh\": 0,"
        "    \"extras\": {\"tag\": {\"a\": 1, \"b\": [1, 2, {\"c\": null}]}, \"label\": \"g\"}},"
        "   {\"name\": \"lamp\", \"translation\": [0, 0, 3],"
        "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}},"
        "    \"extras\": {\"fixture\": {\"model\": \"x1\", \"dimmable\": true}}},"
        "   {\"name\": \"spot\", \"translation\": [1, 0, 3],"
        "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},"
        "   {\"name\": \"eye\", \"translation\": [0, -3, 3],"
        "    \"rotation\": [0.3826834323650898, 0, 0, 0.9238795325112867], \"camera\": 0,"
        "    \"extras\": {\"lens\": {\"mm\": 35}}},"
        "   {\"name\": \"panel\", \"mesh\": 1, \"translation\": [0.5, 0.25, 1.5],"
        "    \"scale\": [0.25, 0.25, 0.25]}],"
        " \"cameras\": [{\"name\": \"view\", \"type\": \"perspective\", \"perspective\":"
        "   {\"yfov\": 0.6981317007977318, \"aspectRatio\": 1.7777777777777777,"
        "    \"znear\": 0.05, \"zfar\": 100}, \"extras\": {\"iso\": 100}}],"
        " \"meshes\": ["
        "   {\"name\": \"ground\", \"primitives\": [{\"attributes\": {}, \"material\": 0,"
        "     \"extras\": {\"primitive\": {\"id\": 1}}}],"
        "    \"extras\": {\"scanned\": {\"by\": \"hand\"}}},"
        "   {\"name\": \"panel\", \"primitives\": [{\"attributes\": {}, \"material\": 1}]}],"
        " \"materials\": ["
        "   {\"name\": \"clay\", \"pbrMetallicRoughness\":"
        "    {\"baseColorFactor\": [0.8, 0.7, 0.6, 1], \"metallicFactor\": 0,"
        "     \"roughnessFactor\": 0.9}, \"extras\": {\"source\": {\"lib\": \"x\"}}},"
        "   {\"name\": \"glow\", \"emissiveFactor\": [1, 0.5, 0.25],"
        "    \"extensions\": {\"KHR_materials_emissive_strength\": {\"emissiveStrength\": 2}}}],"
        " \"bufferViews\": [], \"accessors\": []}");
    int grid = add_grid(doc, bin, 24);
    cJSON *mesh;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItem(doc, "meshes"))
    {
        cJSON *primitive = cJSON_GetArrayItem(cJSON_GetObjectItem(mesh, "primitives"), 0);
        cJSON *attributes = cJSON_GetObjectItem(primitive, "attributes");
        cJSON_AddNumberToObject(attributes, "POSITION", grid);
        cJSON_AddNumberToObject(attributes, "NORMAL", grid + 1);
        cJSON_AddNumberToObject(attributes, "TEXCOORD_0", grid + 2);
        cJSON_AddNumberToObject(primitive, "indices", grid + 3);
    }
    if (vendor) {
        cJSON_AddItemToArray(cJSON_GetObjectItem(doc, "extensionsUsed"),
                             cJSON_CreateString("VENDOR_idmr_marker"));
        cJSON *ground = cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "nodes"), 0);
        cJSON_AddItemToObject(ground, "extensions",
                              parse_or_fail("{\"VENDOR_idmr_marker\": {\"id\": 7, "
                                            "\"parts\": [{\"x\": 1}]}}"));
    }
    return doc;
}

/* The meshes' names, extras and primitives' materials and extras (not their geometry). */
static cJSON *mesh_descriptions(const cJSON *doc)
{
    cJSON *meshes = cJSON_Duplicate(cJSON_GetObjectItem(doc, "meshes"), 1), *mesh, *primitive;
    cJSON_ArrayForEach(mesh, meshes)
    {
        cJSON_ArrayForEach(primitive, cJSON_GetObjectItem(mesh, "primitives"))
        {
            cJSON_DeleteItemFromObject(primitive, "attributes");
            cJSON_DeleteItemFromObject(primitive, "indices");
        }
    }
    cJSON *holder = cJSON_CreateObject();
    cJSON_AddItemToObject(holder, "meshes", meshes);
    return holder;
}

/* What a reduced lit_scene() must keep: every node, camera, light, material, scene, asset and
 * mesh description as it went in; one vertex for each the report counts; fewer than before.
 * Returns what gltf-check saw. */
static cJSON *check_lit_scene_kept(const cJSON *input, const char *out, const char *output)
{
    char path[192];
    snprintf(path, sizeof path, "%s/%s", out, output);
    cJSON *seen = inspect(path);
    const cJSON *document = cJSON_GetObjectItem(seen, "json");
    const char *kept[] = {"nodes", "cameras", "extensions", "extensionsUsed", "scenes",
                          "materials", "asset", "scene"};
    for (size_t i = 0; i < sizeof kept / sizeof *kept; i++)
        assert_kept(input, document, kept[i]);
    cJSON *expected = mesh_descriptions(input), *actual = mesh_descriptions(document);
    assert_kept(expected, actual, "meshes");
    cJSON_Delete(actual);
    cJSON_Delete(expected);
    double after = report_number(out, "vertices_after");
    assert_true(after < report_number(out, "vertices_before"));
    assert_int_equal(cJSON_GetObjectItem(seen, "vertices")->valuedouble, after);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(seen, "instances")), 2);
    scene *back = load_or_fail(path); /* and Assimp reads it as idmr's loader does */
    assert_int_equal(back->vertex_count, after);
    assert_true(back->has_camera);
    assert_float_equal(back->camera.tan_half_y, tan(0.6981317007977318 / 2), 1e-6);
    assert_int_equal(back->light_count, 3); /* the point, the spot, the glowing panel */
    scene_free(back);
    return seen;
}

/* lit_scene(vendor) written as dir/name (*doc, *bin) and reduced by `idmr reduce` into dir/out
 * (a new dir, 64 bytes), checked by check_lit_scene_kept; returns what gltf-check saw. */
static cJSON *reduce_lit_scene(int vendor, const char *name, char *dir, cJSON **doc,
                               test_bin *bin)
{
    char out[96];
    make_temp_dir(dir, "idmr-test-gltf");
    *doc = lit_scene(vendor, bin);
    const char *input = write_document(*doc, bin, dir, name);
    snprintf(out, sizeof out, "%s/out", dir);
    reduce_with_idmr(input, 0.7, out);
    return check_lit_scene_kept(*doc, out, gltf_output_name(name));
}

/* A glTF with a light and object-valued extras on nodes (Assimp's exporter aborted in its
 * scene combiner on either) reduces, and the output keeps nodes, lights, camera, materials,
 * extras and extensions exactly; unused data is dropped: one buffer, scene.bin. */
static void test_reduce_keeps_lights_camera_extras(void **state)
{
    (void)state;
    char dir[64];
    test_bin bin = {NULL, 0};
    cJSON *doc;
    cJSON *seen = reduce_lit_scene(0, "lit.gltf", dir, &doc, &bin);
    const cJSON *buffers = cJSON_GetObjectItem(cJSON_GetObjectItem(seen, "json"), "buffers");
    assert_int_equal(cJSON_GetArraySize(buffers), 1);
    assert_string_equal(cJSON_GetObjectItem(cJSON_GetArrayItem(buffers, 0), "uri")->valuestring,
                        "scene.bin");
    cJSON_Delete(seen);
    cJSON_Delete(doc);
    free(bin.data);
    remove_tree(dir);
}

/* The same scene as a GLB, with an extension the writer does not know on a node: nothing is
 * renumbered, the BIN chunk keeps the input's data and adds the new. */
static void test_reduce_glb_with_unknown_extension(void **state)
{
    (void)state;
    char dir[64], path[128];
    test_bin bin = {NULL, 0};
    cJSON *doc;
    cJSON *seen = reduce_lit_scene(1, "lit.glb", dir, &doc, &bin);
    snprintf(path, sizeof path, "%s/out/scene.bin", dir);
    assert_int_equal(access(path, F_OK), -1); /* all in the .glb */
    const cJSON *document = cJSON_GetObjectItem(seen, "json");
    const cJSON *buffers = cJSON_GetObjectItem(document, "buffers");
    assert_int_equal(cJSON_GetArraySize(buffers), 1);
    assert_null(cJSON_GetObjectItem(cJSON_GetArrayItem(buffers, 0), "uri"));
    assert_true(cJSON_GetObjectItem(cJSON_GetArrayItem(buffers, 0), "byteLength")->valuedouble >
                bin.size);
    /* the input's four accessors kept where they were (the panel still uses them), the ground's
     * new ones after them */
    const cJSON *accessors = cJSON_GetObjectItem(document, "accessors");
    assert_true(cJSON_GetArraySize(accessors) > 4);
    for (int i = 0; i < 4; i++) {
        char where[64] = "";
        assert_true(json_contains(cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "accessors"), i),
                                  cJSON_GetArrayItem(accessors, i), where, sizeof where));
    }
    cJSON_Delete(seen);
    cJSON_Delete(doc);
    free(bin.data);
    remove_tree(dir);
}

/* The instance trimesh places at node `node` with `vertices` vertices (exactly one). */
static const cJSON *instance_at(const cJSON *seen, const char *node, uint32_t vertices)
{
    const cJSON *instance, *found = NULL;
    int matches = 0;
    cJSON_ArrayForEach(instance, cJSON_GetObjectItem(seen, "instances"))
    {
        if (strcmp(cJSON_GetObjectItem(instance, "node")->valuestring, node) == 0 &&
            cJSON_GetArraySize(cJSON_GetObjectItem(instance, "vertices")) == (int)vertices)
            found = instance, matches++;
    }
    if (matches != 1)
        fail_msg("%d instances of %u vertices at node %s", matches, vertices, node);
    return found;
}

/* Fails unless trimesh's instance holds `mesh` (world space): the same vertices in order
 * (to `tolerance`) and the same triangles, facing the same way. */
static void assert_instance_is(const cJSON *instance, const mesh_data *mesh, double tolerance)
{
    const cJSON *vertices = cJSON_GetObjectItem(instance, "vertices");
    const cJSON *faces = cJSON_GetObjectItem(instance, "faces");
    assert_int_equal(cJSON_GetArraySize(vertices), mesh->vertex_count);
    assert_int_equal(cJSON_GetArraySize(faces), mesh->triangle_count);
    double worst = 0;
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        const cJSON *p = cJSON_GetArrayItem(vertices, (int)v);
        for (int k = 0; k < 3; k++)
            worst = fmax(worst, fabs(cJSON_GetArrayItem(p, k)->valuedouble -
                                     mesh->positions[3 * v + k]));
    }
    assert_true(worst <= tolerance);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const cJSON *face = cJSON_GetArrayItem(faces, (int)t);
        for (int k = 0; k < 3; k++)
            assert_int_equal(cJSON_GetArrayItem(face, k)->valueint, mesh->indices[3 * t + k]);
    }
}

/* One mesh of two primitives (grids of 20² and 12² vertices with normals) that three nodes
 * name: "left" and "right" (mirrored, turned) under a scaled "group", and "kept" at the root;
 * a camera at "eye". Its bytes go to `bin`. */
static cJSON *shared_mesh_document(test_bin *bin)
{
    cJSON *doc = parse_or_fail(
        "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0,"
        " \"scenes\": [{\"nodes\": [0, 3, 4]}],"
        " \"nodes\": ["
        "   {\"name\": \"group\", \"children\": [1, 2], \"scale\": [2, 2, 2]},"
        "   {\"name\": \"left\", \"mesh\": 0, \"translation\": [-3, 0, 0]},"
        "   {\"name\": \"right\", \"mesh\": 0, \"translation\": [3, 0, 0],"
        "    \"rotation\": [0, 0.5, 0, 0.8660254037844386], \"scale\": [-1, 1, 1]},"
        "   {\"name\": \"kept\", \"mesh\": 0,"
        "    \"matrix\": [1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, -5, 1]},"
        "   {\"name\": \"eye\", \"translation\": [0, 0, 12], \"camera\": 0}],"
        " \"cameras\": [{\"type\": \"perspective\","
        "   \"perspective\": {\"yfov\": 0.9, \"aspectRatio\": 1.5, \"znear\": 0.1}}],"
        " \"meshes\": [{\"name\": \"pair\", \"primitives\": ["
        "   {\"attributes\": {}}, {\"attributes\": {}, \"mode\": 4}]}],"
        " \"bufferViews\": [], \"accessors\": []}");
    cJSON *primitives = cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "meshes"),
                                                                0),
                                            "primitives");
    const int sizes[2] = {20, 12};
    for (int p = 0; p < 2; p++) {
        int grid = add_grid(doc, bin, sizes[p]);
        cJSON *primitive = cJSON_GetArrayItem(primitives, p);
        cJSON_AddNumberToObject(cJSON_GetObjectItem(primitive, "attributes"), "POSITION", grid);
        cJSON_AddNumberToObject(cJSON_GetObjectItem(primitive, "attributes"), "NORMAL",
                                grid + 1);
        cJSON_AddNumberToObject(primitive, "indices", grid + 3);
    }
    return doc;
}

/* One mesh of two primitives (grids of 400 and 144 vertices) used by three nodes: "left" and
 * "right" (mirrored, turned) under a scaled "group", and "kept" at the root. left has both
 * primitives reduced, right only the first (to other counts), kept none: each reduced node gets
 * a mesh of its own, kept keeps the original (mesh 0), and every instance is where the
 * loader put it, facing as it did. */
static void test_shared_mesh_reduced_per_node(void **state)
{
    (void)state;
    char dir[64];
    make_temp_dir(dir, "idmr-test-gltf");
    test_bin bin = {NULL, 0};
    cJSON *doc = shared_mesh_document(&bin);
    const char *input = write_document(doc, &bin, dir, "shared.gltf");
    scene *s = load_or_fail(input);
    assert_int_equal(s->mesh_count, 6); /* left 0, 1; right 0, 1; kept 0, 1 */
    const char *nodes[6] = {"left", "left", "right", "right", "kept", "kept"};
    for (int i = 0; i < 6; i++)
        assert_int_equal(strncmp(s->meshes[i].name, nodes[i], strlen(nodes[i])), 0);
    const double shares[3] = {0.25, 0.34, 0.5};
    decimate_output outputs[3];
    gltf_replacement replacements[3];
    for (int r = 0; r < 3; r++) {
        decimate_to(&s->meshes[r], shares[r], &outputs[r]);
        replacements[r] = (gltf_replacement){s->meshes[r].xml_line, &outputs[r].mesh, 0};
    }
    char out[96];
    snprintf(out, sizeof out, "%s/out", dir);
    assert_int_equal(files_make_directory(out), 0);
    if (gltf_write_reduced(input, out, replacements, 3, 0))
        fail_msg("%s", error_message());
    char path[128];
    snprintf(path, sizeof path, "%s/scene.gltf", out);
    cJSON *seen = inspect(path);
    const cJSON *document = cJSON_GetObjectItem(seen, "json");
    assert_kept(doc, document, "cameras");
    const cJSON *out_nodes = cJSON_GetObjectItem(document, "nodes");
    int left = cJSON_GetObjectItem(cJSON_GetArrayItem(out_nodes, 1), "mesh")->valueint;
    int right = cJSON_GetObjectItem(cJSON_GetArrayItem(out_nodes, 2), "mesh")->valueint;
    int kept = cJSON_GetObjectItem(cJSON_GetArrayItem(out_nodes, 3), "mesh")->valueint;
    assert_int_equal(kept, 0);
    assert_true(left != 0 && right != 0 && left != right);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(document, "meshes")), 3);
    double tolerance = 1e-5 * scene_diagonal(s);
    mesh_data expected[6];
    for (int i = 0; i < 6; i++)
        expected[i] = i < 3 ? outputs[i].mesh : shapes_scene_mesh_view(&s->meshes[i]);
    for (int i = 0; i < 6; i++)
        assert_instance_is(instance_at(seen, nodes[i], expected[i].vertex_count), &expected[i],
                           tolerance);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(seen, "instances")), 6);
    cJSON_Delete(seen);
    scene *back = load_or_fail(path); /* the same instances, in the same order, for Assimp */
    assert_int_equal(back->mesh_count, 6);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(back->meshes[i].vertex_count, expected[i].vertex_count);
        assert_memory_equal(back->meshes[i].indices, expected[i].indices,
                            sizeof(uint32_t) * 3 * expected[i].triangle_count);
    }
    scene_free(back);
    for (int r = 0; r < 3; r++)
        decimate_output_free(&outputs[r]);
    scene_free(s);
    cJSON_Delete(doc);
    free(bin.data);
    remove_tree(dir);
}

/* The share of mesh m's triangles whose geometric normal agrees with their corners' normals. */
static double share_facing_their_normals(const scene_mesh *m)
{
    uint32_t agree = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = &m->indices[3 * (size_t)t];
        const float *p[3], *n[3];
        for (int c = 0; c < 3; c++)
            p[c] = &m->positions[3 * (size_t)ix[c]], n[c] = &m->normals[3 * (size_t)ix[c]];
        double e1[3], e2[3], dot = 0;
        for (int k = 0; k < 3; k++)
            e1[k] = (double)p[1][k] - p[0][k], e2[k] = (double)p[2][k] - p[0][k];
        double g[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            dot += g[k] * ((double)n[0][k] + n[1][k] + n[2][k]);
        agree += dot > 0;
    }
    return m->triangle_count ? (double)agree / m->triangle_count : 1.0;
}

/* `idmr reduce` keeps a mesh that several nodes name shared (reduce/reduce_instances.c): each
 * primitive is reduced once, all three nodes still name the one mesh, the report counts its
 * vertices once (and every copy in vertices_rendered_after), and each copy read back, the
 * mirrored one included, faces as its input did. */
static void test_reduce_keeps_shared_mesh_shared(void **state)
{
    (void)state;
    char dir[64], out[96], path[128];
    make_temp_dir(dir, "idmr-test-gltf");
    test_bin bin = {NULL, 0};
    cJSON *doc = shared_mesh_document(&bin);
    const char *input = write_document(doc, &bin, dir, "shared.gltf");
    snprintf(out, sizeof out, "%s/out", dir);
    reduce_with_idmr(input, 0.3, out);
    snprintf(path, sizeof path, "%s/scene.gltf", out);
    cJSON *seen = inspect(path);
    const cJSON *document = cJSON_GetObjectItem(seen, "json");
    const cJSON *nodes = cJSON_GetObjectItem(document, "nodes");
    for (int node = 1; node <= 3; node++)
        assert_int_equal(cJSON_GetObjectItem(cJSON_GetArrayItem(nodes, node), "mesh")->valueint,
                         0);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(document, "meshes")), 1);
    scene *in = load_or_fail(input), *back = load_or_fail(path);
    assert_int_equal(back->mesh_count, 6); /* left 0, 1; right 0, 1; kept 0, 1 */
    for (int i = 0; i < 6; i++) {
        assert_int_equal(back->meshes[i].vertex_count, back->meshes[i % 2].vertex_count);
        assert_true(back->meshes[i].vertex_count < in->meshes[i].vertex_count);
        assert_float_equal(share_facing_their_normals(&back->meshes[i]),
                           share_facing_their_normals(&in->meshes[i]), 0.02);
    }
    assert_int_equal(report_number(out, "vertices_after"),
                     back->meshes[0].vertex_count + back->meshes[1].vertex_count);
    assert_int_equal(report_number(out, "vertices_after"), back->vertex_count); /* stored */
    assert_int_equal(report_number(out, "vertices_rendered_after"), back->rendered_vertex_count);
    scene_free(back);
    scene_free(in);
    cJSON_Delete(seen);
    cJSON_Delete(doc);
    free(bin.data);
    remove_tree(dir);
}

/* A scene exported by another tool (trimesh: an icosphere used by two nodes through shared
 * accessors, a box, scene extras, a camera at no node; four external buffers in the .gltf)
 * reduces into a file trimesh reads with the vertices the report counts, the extras and the
 * camera kept. */
static void reduce_trimesh_export(const char *name, const char *output)
{
    char dir[64], input[128], out[96], path[160];
    make_temp_dir(dir, "idmr-test-gltf");
    snprintf(input, sizeof input, "%s/%s", dir, name);
    run_result r = run("scripts/gltf-check trimesh-scene %s", input);
    assert_succeeded(&r);
    run_free(&r);
    cJSON *original = inspect(input);
    snprintf(out, sizeof out, "%s/out", dir);
    reduce_with_idmr(input, 0.3, out);
    snprintf(path, sizeof path, "%s/%s", out, output);
    cJSON *seen = inspect(path);
    const cJSON *before = cJSON_GetObjectItem(original, "json");
    const cJSON *document = cJSON_GetObjectItem(seen, "json");
    assert_kept(before, document, "scenes");
    assert_kept(before, document, "nodes");
    assert_kept(before, document, "cameras");
    assert_kept(before, document, "asset");
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(seen, "instances")), 3);
    assert_int_equal(cJSON_GetObjectItem(seen, "vertices")->valuedouble,
                     report_number(out, "vertices_after"));
    assert_true(report_number(out, "vertices_after") <
                0.5 * cJSON_GetObjectItem(original, "vertices")->valuedouble);
    cJSON_Delete(seen);
    cJSON_Delete(original);
    remove_tree(dir);
}

static void test_reduce_trimesh_glb(void **state)
{
    (void)state;
    reduce_trimesh_export("trimesh.glb", "scene.glb");
}

static void test_reduce_trimesh_gltf(void **state)
{
    (void)state;
    reduce_trimesh_export("trimesh.gltf", "scene.gltf");
}

/* BoxTextured written back unchanged reads back with the same uv (not turned), normals,
 * positions and texture; with bundle, the texture is a copy under assets/. */
static void test_box_written_back(void **state)
{
    (void)state;
    scene *s = load_or_fail(BOX);
    for (int bundle = 0; bundle <= 1; bundle++) {
        char dir[64];
        make_temp_dir(dir, "idmr-test-gltf");
        mesh_data mesh = shapes_scene_mesh_view(&s->meshes[0]);
        gltf_replacement replacement = {s->meshes[0].xml_line, &mesh, 0};
        if (gltf_write_reduced(BOX, dir, &replacement, 1, bundle))
            fail_msg("%s", error_message());
        char path[128];
        snprintf(path, sizeof path, "%s/scene.gltf", dir);
        cJSON_Delete(inspect(path));
        scene *back = load_or_fail(path);
        const scene_mesh *a = &s->meshes[0], *b = &back->meshes[0];
        assert_int_equal(b->vertex_count, a->vertex_count);
        for (uint32_t v = 0; v < a->vertex_count; v++)
            for (int k = 0; k < 3; k++) {
                assert_float_equal(b->positions[3 * v + k], a->positions[3 * v + k], 1e-6);
                assert_float_equal(b->normals[3 * v + k], a->normals[3 * v + k], 1e-6);
                if (k < 2)
                    assert_float_equal(b->texcoords[2 * v + k], a->texcoords[2 * v + k], 1e-6);
            }
        const idmr_material *material = &back->materials[b->material];
        assert_true(material->texture >= 0);
        const char *file = back->textures[material->texture].file;
        assert_non_null(strstr(file, bundle ? "/assets/CesiumLogoFlat.png" : "CesiumLogoFlat"));
        scene_free(back);
        remove_tree(dir);
    }
    scene_free(s);
}

/* Real files of other exporters (assimp-testmodels), every instance decimated to half and
 * written back: Draco-compressed primitives (an extension whose references the writer does not
 * follow: nothing renumbered; Draco no longer listed once no primitive uses it), morph targets
 * (kept, moving nothing), a skin, buffers and images in data: URIs, an image in the GLB's
 * BIN chunk, KHR_techniques_webgl shaders beside the file, texture transforms, a triangle fan
 * and a strip. Each output has no problem for trimesh, pygltflib and the schema, and Assimp
 * reads back every instance with the vertices written. */
static void test_real_models_written_back(void **state)
{
    (void)state;
    const char *models[] = {
        "/draco/2CylinderEngine.gltf",
        "/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
        "/simple_skin/simple_skin.gltf",
        "/BoxTextured-glTF-Embedded/BoxTextured.gltf",
        "/BoxTextured-glTF-Binary/BoxTextured.glb",
        "/BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf",
        "/textureTransform/TextureTransformTest.gltf",
        "/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf",
        "/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_06.gltf",
    };
    for (size_t f = 0; f < sizeof models / sizeof *models; f++) {
        char model[256];
        snprintf(model, sizeof model, "%s%s", MODELS, models[f]);
        scene *s = load_or_fail(model);
        decimate_output *outputs = calloc(s->mesh_count, sizeof *outputs);
        gltf_replacement *replacements = calloc(s->mesh_count, sizeof *replacements);
        for (size_t i = 0; i < s->mesh_count; i++) {
            decimate_to(&s->meshes[i], 0.5, &outputs[i]);
            replacements[i] = (gltf_replacement){s->meshes[i].xml_line, &outputs[i].mesh, 0};
        }
        char dir[64];
        make_temp_dir(dir, "idmr-test-gltf");
        if (gltf_write_reduced(model, dir, replacements, s->mesh_count, 0))
            fail_msg("%s", error_message());
        char path[128];
        snprintf(path, sizeof path, "%s/%s", dir, gltf_output_name(model));
        cJSON *seen = inspect(path);
        const cJSON *document = cJSON_GetObjectItem(seen, "json");
        char *text = cJSON_PrintUnformatted(document);
        assert_null(strstr(text, "KHR_draco_mesh_compression")); /* every primitive replaced */
        free(text);
        cJSON_Delete(seen);
        scene *back = load_or_fail(path);
        assert_int_equal(back->mesh_count, s->mesh_count);
        for (size_t i = 0; i < s->mesh_count; i++) {
            assert_int_equal(back->meshes[i].vertex_count, outputs[i].mesh.vertex_count);
            assert_int_equal(back->meshes[i].triangle_count, outputs[i].mesh.triangle_count);
            decimate_output_free(&outputs[i]);
        }
        printf("%s: %llu -> %llu vertices\n", models[f],
               (unsigned long long)s->vertex_count, (unsigned long long)back->vertex_count);
        scene_free(back);
        free(replacements);
        free(outputs);
        scene_free(s);
        remove_tree(dir);
    }
}

int main(void)
{
    warn_silence(1);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_at_its_node),
        cmocka_unit_test(test_box_textured),
        cmocka_unit_test(test_lights_and_materials),
        cmocka_unit_test(test_engine_written_back_unchanged),
        cmocka_unit_test(test_engine_decimated_round_trip),
        cmocka_unit_test(test_bad_files_refused),
        cmocka_unit_test(test_reduce_keeps_lights_camera_extras),
        cmocka_unit_test(test_reduce_glb_with_unknown_extension),
        cmocka_unit_test(test_shared_mesh_reduced_per_node),
        cmocka_unit_test(test_reduce_keeps_shared_mesh_shared),
        cmocka_unit_test(test_reduce_trimesh_glb),
        cmocka_unit_test(test_reduce_trimesh_gltf),
        cmocka_unit_test(test_box_written_back),
        cmocka_unit_test(test_real_models_written_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
