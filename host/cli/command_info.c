/* command_info.c — `idmr info SCENE [--json] [--no-bvh]`: what a scene holds (meshes,
 * materials, lights, camera, bounding box, feature bits) and what it costs on a device
 * (geometry and BVH bytes, the BVH's shape). The scene is described once, as a JSON object;
 * --json prints that object, the text form is printed from it (info_text.h).
 *
 * The object: {scene, meshes: [{name, shape, file?, vertices, triangles, triangles_dropped,
 * material, material_kind, emitter}], materials: [{name, bsdf, kind}], lights: [{type, emission, power,
 * area?, map?: {file?, width, height}}] (emission: an environment's mean radiance), camera?: {origin, forward, up, fov, fov_axis, width, height}, bbox: {min, max},
 * features: [name], vertices, triangles, triangles_dropped, device_memory: {geometry, bvh?, total?}, bvh?: {nodes,
 * leaves, triangle_references, degenerate_triangles, depth, build_seconds}}; the keys marked ?
 * are left out when the scene has no such thing (or --no-bvh). triangles_dropped counts the
 * triangles of the mesh files that repeat a vertex, left out on load (core/scene.h). */
#include <getopt.h>

#include "cli/commands.h"
#include "cli/info_text.h"
#include "cli/options.h"
#include "core/json.h"
#include "core/scene.h"
#include "device/bvh.h"
#include "device/device_scene.h"
#include "io/scene_load.h"

static cJSON *meshes_json(const scene *s)
{
    cJSON *meshes = cJSON_CreateArray();
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *m = &s->meshes[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", m->name);
        cJSON_AddStringToObject(o, "shape", m->shape_type);
        if (m->file)
            cJSON_AddStringToObject(o, "file", m->file);
        cJSON_AddNumberToObject(o, "vertices", m->vertex_count);
        cJSON_AddNumberToObject(o, "triangles", m->triangle_count);
        cJSON_AddNumberToObject(o, "triangles_dropped", m->triangles_dropped);
        cJSON_AddStringToObject(o, "material", s->material_info[m->material].name);
        cJSON_AddStringToObject(o, "material_kind",
                                scene_material_kind_name(s->materials[m->material].kind));
        cJSON_AddBoolToObject(o, "emitter", m->light >= 0);
        if (m->instanced && m->instance_first != i) /* a later copy of an instanced shape */
            cJSON_AddStringToObject(o, "instance_of", s->meshes[m->instance_first].name);
        cJSON_AddItemToArray(meshes, o);
    }
    return meshes;
}

static cJSON *materials_json(const scene *s)
{
    cJSON *materials = cJSON_CreateArray();
    for (size_t i = 0; i < s->material_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", s->material_info[i].name);
        cJSON_AddStringToObject(o, "bsdf", s->material_info[i].bsdf_type);
        cJSON_AddStringToObject(o, "kind", scene_material_kind_name(s->materials[i].kind));
        cJSON_AddItemToArray(materials, o);
    }
    return materials;
}

static cJSON *lights_json(const scene *s)
{
    cJSON *lights = cJSON_CreateArray();
    for (size_t i = 0; i < s->light_count; i++) {
        const idmr_light *l = &s->lights[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "type", scene_light_kind_name(l->kind));
        json_add_vec3(o, "emission", l->emission);
        cJSON_AddNumberToObject(o, "power", l->power);
        if (l->kind == IDMR_LIGHT_AREA)
            cJSON_AddNumberToObject(o, "area", l->area);
        if (l->kind == IDMR_LIGHT_ENVIRONMENT) {
            cJSON *map = cJSON_AddObjectToObject(o, "map");
            if (s->environment.file)
                cJSON_AddStringToObject(map, "file", s->environment.file);
            cJSON_AddNumberToObject(map, "width", s->environment.width);
            cJSON_AddNumberToObject(map, "height", s->environment.height);
        }
        cJSON_AddItemToArray(lights, o);
    }
    return lights;
}

static cJSON *camera_json(const scene *s)
{
    cJSON *camera = cJSON_CreateObject();
    json_add_vec3(camera, "origin", s->camera.origin);
    json_add_vec3(camera, "forward", s->camera.forward);
    json_add_vec3(camera, "up", s->camera.up);
    cJSON_AddNumberToObject(camera, "fov", s->camera_info.fov_degrees);
    cJSON_AddStringToObject(camera, "fov_axis", s->camera_info.fov_axis);
    cJSON_AddNumberToObject(camera, "width", s->camera.width);
    cJSON_AddNumberToObject(camera, "height", s->camera.height);
    return camera;
}

static cJSON *features_json(unsigned int features)
{
    cJSON *array = cJSON_CreateArray();
    for (unsigned int bit = 0; bit < IDMR_FEATURE_COUNT; bit++)
        if (features & (1u << bit))
            cJSON_AddItemToArray(array, cJSON_CreateString(scene_feature_name(1u << bit)));
    return array;
}

/* device_memory, and bvh when `b` is not NULL. */
static void add_device_json(cJSON *root, const scene *s, const bvh *b)
{
    cJSON *memory = cJSON_AddObjectToObject(root, "device_memory");
    cJSON_AddNumberToObject(memory, "geometry", (double)device_scene_geometry_bytes(s));
    if (!b)
        return;
    cJSON_AddNumberToObject(memory, "bvh", (double)bvh_device_bytes(b));
    cJSON_AddNumberToObject(memory, "total",
                            (double)(device_scene_geometry_bytes(s) + bvh_device_bytes(b)));
    cJSON *tree = cJSON_AddObjectToObject(root, "bvh");
    cJSON_AddNumberToObject(tree, "nodes", (double)b->node_count);
    cJSON_AddNumberToObject(tree, "leaves", (double)b->leaf_count);
    cJSON_AddNumberToObject(tree, "triangle_references", (double)b->reference_count);
    cJSON_AddNumberToObject(tree, "degenerate_triangles", (double)b->degenerate_count);
    cJSON_AddNumberToObject(tree, "depth", b->depth);
    cJSON_AddNumberToObject(tree, "build_seconds", b->build_seconds);
}

/* The scene as the object described at the top; `b` NULL: no BVH was built. */
static cJSON *info_json(const scene *s, const bvh *b)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON_AddItemToObject(root, "meshes", meshes_json(s));
    cJSON_AddItemToObject(root, "materials", materials_json(s));
    cJSON_AddItemToObject(root, "lights", lights_json(s));
    if (s->has_camera)
        cJSON_AddItemToObject(root, "camera", camera_json(s));
    cJSON *bbox = cJSON_AddObjectToObject(root, "bbox");
    json_add_vec3(bbox, "min", s->bbox_min);
    json_add_vec3(bbox, "max", s->bbox_max);
    cJSON_AddItemToObject(root, "features", features_json(s->features));
    /* Every copy counted (what a renderer holds flattened), and what the scene stores: an
     * instanced shape once, however many instances place it (the vertices `idmr reduce` plans
     * and counts: reduce/reduce_instances.c; the passes hold each prototype once too). */
    cJSON_AddNumberToObject(root, "vertices", (double)s->rendered_vertex_count);
    cJSON_AddNumberToObject(root, "vertices_stored", (double)s->vertex_count);
    cJSON_AddNumberToObject(root, "triangles", (double)s->rendered_triangle_count);
    cJSON_AddNumberToObject(root, "triangles_stored", (double)s->triangle_count);
    uint64_t dropped = 0;
    for (size_t m = 0; m < s->mesh_count; m++)
        dropped += s->meshes[m].triangles_dropped;
    cJSON_AddNumberToObject(root, "triangles_dropped", (double)dropped);
    add_device_json(root, s, b);
    return root;
}

/* Loads the scene and builds its BVH (unless !build_bvh); the object, or NULL with the error
 * set. */
static cJSON *describe_scene(const char *path, int build_bvh)
{
    scene *s = scene_load(path);
    if (!s)
        return NULL;
    bvh b;
    cJSON *root = NULL;
    if (!build_bvh)
        root = info_json(s, NULL);
    else if (!bvh_build(s, &b)) {
        root = info_json(s, &b);
        bvh_free(&b);
    }
    scene_free(s);
    return root;
}

int command_info(int argc, char **argv)
{
    int json = 0, build_bvh = 1;
    static const struct option options[] = {
        {"json", no_argument, NULL, 'j'}, {"no-bvh", no_argument, NULL, 'n'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        if (c == 'j')
            json = 1;
        else if (c == 'n')
            build_bvh = 0;
        else
            return option_error("info", c, argv, options);
    }
    int code = expect_one_scene("info", argc);
    if (code)
        return code;
    cJSON *root = describe_scene(argv[optind], build_bvh);
    if (!root)
        return fail();
    if (json)
        json_print(root);
    else
        info_text_print(root);
    cJSON_Delete(root);
    return 0;
}
