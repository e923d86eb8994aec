/* test_gltf.c — glTF 2.0 in and out through Assimp (host/io/gltf.cc), on the real models of
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
 *   - a missing file and a file Assimp rejects are errors naming the file. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"
#include "core/files.h"
#include "io/gltf.h"
#include "io/shapes.h"
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

/* Writes `s` (read from ENGINE) with every instance replaced by meshes[i] into a fresh
 * directory and reads it back. */
static scene *write_and_read(const scene *s, const mesh_data *meshes, char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/idmr-test-gltf-XXXXXX");
    assert_non_null(mkdtemp(dir));
    gltf_replacement *replacements = calloc(s->mesh_count, sizeof *replacements);
    for (size_t i = 0; i < s->mesh_count; i++)
        replacements[i] = (gltf_replacement){s->meshes[i].xml_line, &meshes[i]};
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
        mesh_data in = world_mesh(&s->meshes[i]);
        decimate_input d;
        memset(&d, 0, sizeof d);
        d.name = s->meshes[i].name;
        d.positions = in.positions;
        d.vertex_count = in.vertex_count;
        d.indices = in.indices;
        d.triangle_count = in.triangle_count;
        d.texcoords = in.texcoords;
        d.normals = in.normals;
        d.target_vertices = in.vertex_count / 4 > 4 ? in.vertex_count / 4 : 4;
        d.max_normal_angle = 60;
        if (decimate_mesh(&d, DECIMATE_QUADRIC, &outputs[i]))
            fail_msg("%s", error_message());
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
    check_refused("/nonexistent/scene.gltf", "Unable to open");
    const char *broken = MODELS "/IndexOutOfRange/AllIndicesOutOfRange.gltf";
    if (access(broken, R_OK))
        fail_msg("%s is missing: scripts/install-deps.sh installs assimp-testmodels", broken);
    check_refused(broken, "not a glTF scene Assimp can read");
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
