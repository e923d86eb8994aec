// gltf.cc — glTF 2.0 scenes read through Assimp (the mapping is in gltf.h; the reduced scene is
// written by gltf_write.c, from the file's own JSON).
#include <assimp/Importer.hpp>
#include <assimp/ProgressHandler.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unordered_map>
#include <strings.h>
#include <vector>

extern "C" {
#include "core/error.h"
#include "core/progress.h"
#include "io/gltf/gltf.h"
#include "io/gltf/gltf_validate.h"
#include "io/image.h"
#include "io/mitsuba_paths.h"
#include "core/shapes.h"
#include "core/xform.h"
}

namespace {

// A primitive per aiMesh, triangulated; the instances' numbering (collect_instances) is the one
// gltf_write.c's walk() makes again from the file's JSON when it writes the reduced meshes.
// Not aiProcess_ValidateDataStructure: it matches every light's and camera's name against every
// node (10,000 lights: seconds per thousand); the file is checked before (gltf_validate.h) and
// what is taken from Assimp's scene is checked where it is read (add_instance).
const unsigned IMPORT_FLAGS = aiProcess_Triangulate | aiProcess_SortByPType;

const unsigned FILM_WIDTH = 1024;        // the film's width; the height follows the aspect
const double DEFAULT_YFOV = M_PI / 4;    // no camera: the framing camera's vertical fov
const double DEFAULT_ASPECT = 4.0 / 3.0; // no aspect ratio given

// One node's use of one triangle mesh, with the node's world transform.
struct Instance {
    aiNode *node;
    unsigned slot; // index into node->mMeshes
    aiMatrix4x4 world;
};

bool is_triangle_mesh(const aiMesh *mesh)
{
    return mesh->mNumFaces > 0 && (mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) &&
           !(mesh->mPrimitiveTypes & (aiPrimitiveType_POINT | aiPrimitiveType_LINE));
}

// Depth-first from the root, the node's meshes in order: the instances' numbering (gltf_write.c
// walks the JSON the same way: keep the two together).
void collect_instances(const aiScene *scene, aiNode *node, const aiMatrix4x4 &parent,
                       std::vector<Instance> &out)
{
    aiMatrix4x4 world = parent * node->mTransformation;
    for (unsigned k = 0; k < node->mNumMeshes; k++)
        if (node->mMeshes[k] < scene->mNumMeshes &&
            is_triangle_mesh(scene->mMeshes[node->mMeshes[k]]))
            out.push_back(Instance{node, k, world});
    for (unsigned c = 0; c < node->mNumChildren; c++)
        collect_instances(scene, node->mChildren[c], world, out);
}

double determinant3(const aiMatrix4x4 &m)
{
    return m.a1 * (m.b2 * m.c3 - m.b3 * m.c2) - m.a2 * (m.b1 * m.c3 - m.b3 * m.c1) +
           m.a3 * (m.b1 * m.c2 - m.b2 * m.c1);
}

// The matrix normals transform with: the inverse transpose of the linear part.
aiMatrix3x3 normal_matrix(const aiMatrix4x4 &m)
{
    aiMatrix3x3 linear(m);
    return linear.Inverse().Transpose();
}

aiVector3D unit(aiVector3D v)
{
    float length = v.Length();
    return length > 0 && std::isfinite(length) ? v / length : aiVector3D(0, 0, 0);
}

int fail(const char *path, const std::string &why)
{
    return error_set(IDMR_EXIT_INPUT, "%s: %s", path, why.c_str());
}

// Imports `path` into `importer`; NULL with the error set.
const aiScene *import(Assimp::Importer &importer, const char *path)
{
    const aiScene *scene = importer.ReadFile(path, IMPORT_FLAGS);
    if (!scene) {
        fail(path, std::string("not a glTF scene Assimp can read: ") + importer.GetErrorString());
        return nullptr;
    }
    if (!scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        fail(path, "Assimp read an incomplete scene (no nodes or meshes)");
        return nullptr;
    }
    return scene;
}

// ---- reading ----

// A node the default scene reaches, with its world transform (from the file's JSON).
struct Placed {
    const cJSON *node;
    int index;
    xform world;
};

struct Loader {
    const char *path;
    std::string dir;
    const aiScene *ai;
    scene *s;
    std::vector<int> material_of; // per aiMaterial: the scene's material, or -1 before first use
    bool warned_embedded = false;
    gltf_document *doc;            // the file's JSON and buffers, checked (gltf_validate.h)
    const gltf_checked *checked;
    std::vector<Placed> placed;    // depth first from the default scene's roots
    std::vector<const cJSON *> primitive_of; // per instance: its glTF primitive
};

const cJSON *member(const cJSON *object, const char *name)
{
    return cJSON_IsObject(object) ? cJSON_GetObjectItemCaseSensitive(object, name) : nullptr;
}

// object[name] as a number, `fallback` when it is none.
double number(const cJSON *object, const char *name, double fallback)
{
    const cJSON *item = member(object, name);
    return cJSON_IsNumber(item) ? item->valuedouble : fallback;
}

// The items of the array `array` (none when it is not one).
std::vector<const cJSON *> items(const cJSON *array)
{
    std::vector<const cJSON *> out;
    const cJSON *item;
    if (cJSON_IsArray(array))
        cJSON_ArrayForEach(item, array) out.push_back(item);
    return out;
}

// Every node of the default scene ("scene", else the first) with its world transform, a node
// before its children, as Assimp imports them. The hierarchy is checked (no cycle, one parent),
// so the walk ends; it keeps its own stack (a deep chain of nodes needs no deep recursion).
std::vector<Placed> place_nodes(const cJSON *root)
{
    std::vector<const cJSON *> nodes = items(member(root, "nodes"));
    std::vector<const cJSON *> scenes = items(member(root, "scenes"));
    size_t chosen = (size_t)number(root, "scene", 0);
    std::vector<Placed> out;
    if (chosen >= scenes.size())
        return out;
    std::vector<Placed> stack;
    std::vector<const cJSON *> roots = items(member(scenes[chosen], "nodes"));
    for (size_t r = roots.size(); r-- > 0;) {
        int index = (int)roots[r]->valuedouble;
        stack.push_back(Placed{nodes[index], index, gltf_node_transform(nodes[index])});
    }
    while (!stack.empty()) {
        Placed p = stack.back();
        stack.pop_back();
        out.push_back(p);
        std::vector<const cJSON *> children = items(member(p.node, "children"));
        for (size_t k = children.size(); k-- > 0;) {
            int index = (int)children[k]->valuedouble;
            xform local = gltf_node_transform(nodes[index]);
            stack.push_back(Placed{nodes[index], index, xform_multiply(&p.world, &local)});
        }
    }
    return out;
}

// Per instance, the glTF primitive it was made from: the triangle primitives (triangles, strip,
// fan) of each node's mesh, the nodes depth first (`placed`), as collect_instances and
// gltf_write.c's walk() number them. (Assimp's own mesh order is another: it reads the meshes
// as nodes reach them.)
std::vector<const cJSON *> instance_primitives(const cJSON *root,
                                               const std::vector<Placed> &placed)
{
    std::vector<const cJSON *> meshes = items(member(root, "meshes")), out;
    for (const Placed &p : placed) {
        const cJSON *mesh = member(p.node, "mesh");
        if (!cJSON_IsNumber(mesh))
            continue;
        for (const cJSON *primitive : items(member(meshes[(size_t)mesh->valuedouble], "primitives"))) {
            double mode = number(primitive, "mode", 4);
            if (mode == 4 || mode == 5 || mode == 6)
                out.push_back(primitive);
        }
    }
    return out;
}

float material_float(const aiMaterial *m, const char *key, unsigned type, unsigned index,
                     float fallback)
{
    float value;
    return m->Get(key, type, index, value) == AI_SUCCESS && std::isfinite(value) ? value
                                                                                 : fallback;
}

// The base colour's texture, read and added to the scene on first use; -1 when the material
// has none or it cannot be used.
int base_texture(Loader &ld, const aiMaterial *m)
{
    aiString file;
    if (m->GetTexture(aiTextureType_BASE_COLOR, 0, &file) != AI_SUCCESS &&
        m->GetTexture(aiTextureType_DIFFUSE, 0, &file) != AI_SUCCESS)
        return -1;
    if (file.length == 0)
        return -1;
    if (file.data[0] == '*' || ld.ai->GetEmbeddedTexture(file.C_Str())) {
        if (!ld.warned_embedded)
            warn("%s: embedded textures are not read: materials use their base colour factor",
                 ld.path);
        ld.warned_embedded = true;
        return -1;
    }
    char *resolved = mitsuba_path_join(ld.dir.c_str(), file.C_Str());
    int texture = scene_find_texture(ld.s, resolved);
    if (texture < 0) {
        int width, height;
        float *rgb;
        if (image_read_rgb(resolved, &width, &height, &rgb)) {
            error_prefix("%s: base colour texture '%s'", ld.path, file.C_Str());
            free(resolved);
            return -2;
        }
        texture = scene_add_texture(ld.s, resolved, width, height, rgb);
    }
    free(resolved);
    return texture;
}

// The scene material of Assimp material `index` (gltf.h's table); -1 with the error set.
int material(Loader &ld, unsigned index)
{
    if (ld.material_of[index] >= 0)
        return ld.material_of[index];
    const aiMaterial *m = ld.ai->mMaterials[index];
    idmr_material out;
    memset(&out, 0, sizeof out);
    aiColor4D base(1, 1, 1, 1);
    if (m->Get(AI_MATKEY_BASE_COLOR, base) != AI_SUCCESS)
        m->Get(AI_MATKEY_COLOR_DIFFUSE, base);
    float metallic = material_float(m, AI_MATKEY_METALLIC_FACTOR, 1.0f);
    float roughness = std::min(1.0f, std::max(0.0f, material_float(m, AI_MATKEY_ROUGHNESS_FACTOR,
                                                                   1.0f)));
    float transmission = material_float(m, AI_MATKEY_TRANSMISSION_FACTOR, 0.0f);
    float ior = material_float(m, AI_MATKEY_REFRACTI, 1.5f);
    int two_sided = 0;
    m->Get(AI_MATKEY_TWOSIDED, two_sided);
    float colour[3] = {std::max(0.0f, base.r), std::max(0.0f, base.g), std::max(0.0f, base.b)};
    float alpha = roughness * roughness;
    out.texture = -1;
    out.int_ior = ior >= 1.0f ? ior : 1.5f;
    out.ext_ior = 1.0f;
    const char *type;
    if (transmission >= 0.5f) {
        out.kind = IDMR_MATERIAL_DIELECTRIC;
        type = "dielectric";
    } else if (metallic >= 0.5f) {
        out.kind = alpha < 0.001f ? IDMR_MATERIAL_MIRROR : IDMR_MATERIAL_GLOSSY;
        out.roughness = out.kind == IDMR_MATERIAL_GLOSSY ? alpha : 0.0f;
        for (int k = 0; k < 3; k++)
            out.specular[k] = std::min(1.0f, colour[k]);
        type = out.kind == IDMR_MATERIAL_MIRROR ? "conductor" : "roughconductor";
    } else {
        out.kind = roughness >= 0.5f ? IDMR_MATERIAL_DIFFUSE : IDMR_MATERIAL_GLOSSY;
        for (int k = 0; k < 3; k++) {
            out.reflectance[k] = std::min(1.0f, colour[k]);
            out.specular[k] = out.kind == IDMR_MATERIAL_GLOSSY ? 1.0f : 0.0f;
        }
        out.roughness = out.kind == IDMR_MATERIAL_GLOSSY ? alpha : 0.0f;
        int texture = base_texture(ld, m);
        if (texture == -2)
            return -1;
        if (texture >= 0) { // the texture times the factor: its mean times the factor
            out.texture = texture;
            for (int k = 0; k < 3; k++)
                out.reflectance[k] = std::min(1.0f, ld.s->textures[texture].mean[k] * colour[k]);
        }
        type = out.kind == IDMR_MATERIAL_DIFFUSE ? "diffuse" : "roughplastic";
    }
    if (two_sided)
        out.flags |= IDMR_MATERIAL_TWOSIDED;
    aiString name;
    std::string label = m->Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length
                            ? name.C_Str()
                            : "material" + std::to_string(index);
    ld.material_of[index] = (int)scene_add_material(ld.s, label.c_str(), type, &out);
    return ld.material_of[index];
}

// The emitted radiance of a material (emissive factor × strength); false when it emits none.
bool emission(const aiMaterial *m, float radiance[3])
{
    aiColor3D emissive(0, 0, 0);
    if (m->Get(AI_MATKEY_COLOR_EMISSIVE, emissive) != AI_SUCCESS)
        return false;
    float strength = material_float(m, AI_MATKEY_EMISSIVE_INTENSITY, 1.0f);
    radiance[0] = std::max(0.0f, emissive.r * strength);
    radiance[1] = std::max(0.0f, emissive.g * strength);
    radiance[2] = std::max(0.0f, emissive.b * strength);
    return radiance[0] > 0 || radiance[1] > 0 || radiance[2] > 0;
}

// Whether Assimp 5.2 reads accessor `a` wrong: it copies the bytes of integers (normalized
// UNSIGNED_BYTE and UNSIGNED_SHORT texture coordinates) into floats. (The base of a sparse
// accessor it reads as if packed, past its end where it is not: gltf_validate refuses those.)
bool assimp_misreads(const gltf_accessor *a)
{
    return a->component_type != GLTF_FLOAT;
}

// Attribute `name` of the primitive instance `number` was made from, read here into `out`
// (vertex_count × its components) where Assimp misreads it. 1 when it was, 0 when Assimp's
// values stand, -1 with the error set.
int own_values(Loader &ld, int number, const char *name, uint32_t vertex_count,
               std::vector<float> &out)
{
    const cJSON *primitive = ld.primitive_of[(size_t)number];
    const cJSON *reference = member(member(primitive, "attributes"), name);
    if (!primitive || !cJSON_IsNumber(reference))
        return 0;
    int index = (int)reference->valuedouble;
    const gltf_accessor *a = &ld.checked->accessors[index];
    if (!assimp_misreads(a))
        return 0;
    if (member(member(primitive, "extensions"), "KHR_draco_mesh_compression") ||
        a->count != vertex_count)
        return fail(ld.path, "accessor " + std::to_string(index) + ": " + name +
                                 " of integers in a Draco-compressed primitive is not read "
                                 "(Assimp 5.2 garbles it)");
    out.resize((size_t)a->count * a->components);
    return gltf_accessor_read_floats(ld.doc, a, out.data()) ? -1 : 1;
}

// A node's world transform as row-major 4x4 doubles (core/scene.h: instance_to_world).
void world_rows(const Instance &instance, double rows[16])
{
    const aiMatrix4x4 &w = instance.world;
    const double values[16] = {w.a1, w.a2, w.a3, w.a4, w.b1, w.b2, w.b3, w.b4,
                               w.c1, w.c2, w.c3, w.c4, w.d1, w.d2, w.d3, w.d4};
    std::memcpy(rows, values, sizeof values);
}

// A primitive that several nodes name is one prototype (core/scene.h: instanced): the first
// node's instance (scene mesh `number`, just added) holds its geometry, in that node's world
// space, and is marked as its representative here, so that `idmr reduce` reduces the
// primitive once and the nodes keep sharing it (reduce/reduce_instances.c).
void mark_first_copy(Loader &ld, const Instance &instance, size_t number)
{
    scene_mesh *mesh = &ld.s->meshes[number];
    mesh->instanced = 1;
    mesh->instance_first = number;
    world_rows(instance, mesh->instance_to_world);
}

// A later node's instance of such a primitive (scene mesh `number`): no geometry of its own,
// placed by its node's world transform from the first one's (scene_add_instance_copy).
int add_later_copy(Loader &ld, const Instance &instance, int number, size_t first)
{
    const aiMesh *mesh = ld.ai->mMeshes[instance.node->mMeshes[instance.slot]];
    std::string name = std::string(instance.node->mName.C_Str()) + "/" + mesh->mName.C_Str();
    double rows[16];
    world_rows(instance, rows);
    scene_mesh *copy = scene_add_instance_copy(ld.s, first, name.c_str(), rows);
    if (!copy)
        return fail(ld.path, error_message());
    copy->xml_line = number;
    return 0;
}

int add_instance(Loader &ld, const Instance &instance, int number)
{
    const aiMesh *mesh = ld.ai->mMeshes[instance.node->mMeshes[instance.slot]];
    if (!mesh->mVertices || mesh->mMaterialIndex >= ld.ai->mNumMaterials)
        return fail(ld.path, std::string("Assimp made mesh '") + mesh->mName.C_Str() +
                                 "' without positions or with no material");
    for (unsigned f = 0; f < mesh->mNumFaces; f++)
        for (unsigned k = 0; k < mesh->mFaces[f].mNumIndices; k++)
            if (mesh->mFaces[f].mIndices[k] >= mesh->mNumVertices)
                return fail(ld.path, std::string("Assimp made mesh '") + mesh->mName.C_Str() +
                                         "' with a face index past its vertices");
    const aiMatrix4x4 &world = instance.world;
    aiMatrix3x3 normals = normal_matrix(world);
    bool mirrored = determinant3(world) < 0;
    uint32_t vertex_count = mesh->mNumVertices;
    std::vector<float> own_positions, own_uv, own_normals; // where Assimp misreads them
    int own_p = own_values(ld, number, "POSITION", vertex_count, own_positions);
    int own_t = own_p < 0 ? -1 : own_values(ld, number, "TEXCOORD_0", vertex_count, own_uv);
    int own_n = own_t < 0 ? -1 : own_values(ld, number, "NORMAL", vertex_count, own_normals);
    if (own_n < 0)
        return -1;
    float *positions = (float *)xmalloc(sizeof(float) * 3 * (vertex_count + 1));
    float *texcoords = nullptr, *normal_values = nullptr;
    for (uint32_t v = 0; v < vertex_count; v++) {
        const float *q = own_p ? &own_positions[3 * (size_t)v] : nullptr;
        aiVector3D p = world * (q ? aiVector3D(q[0], q[1], q[2]) : mesh->mVertices[v]);
        positions[3 * v] = p.x, positions[3 * v + 1] = p.y, positions[3 * v + 2] = p.z;
    }
    if (mesh->HasTextureCoords(0)) { /* v as Mitsuba reads it: the file's, 1 - Assimp's */
        texcoords = (float *)xmalloc(sizeof(float) * 2 * (vertex_count + 1));
        for (uint32_t v = 0; v < vertex_count; v++) {
            texcoords[2 * v] = own_t ? own_uv[2 * (size_t)v] : mesh->mTextureCoords[0][v].x;
            texcoords[2 * v + 1] =
                own_t ? own_uv[2 * (size_t)v + 1] : 1.0f - mesh->mTextureCoords[0][v].y;
        }
    }
    if (mesh->HasNormals()) {
        normal_values = (float *)xmalloc(sizeof(float) * 3 * (vertex_count + 1));
        for (uint32_t v = 0; v < vertex_count; v++) {
            const float *q = own_n ? &own_normals[3 * (size_t)v] : nullptr;
            aiVector3D n = unit(normals * (q ? aiVector3D(q[0], q[1], q[2]) : mesh->mNormals[v]));
            normal_values[3 * v] = n.x, normal_values[3 * v + 1] = n.y,
                              normal_values[3 * v + 2] = n.z;
        }
    }
    std::vector<uint32_t> indices;
    indices.reserve(3 * (size_t)mesh->mNumFaces);
    for (unsigned f = 0; f < mesh->mNumFaces; f++) {
        const aiFace &face = mesh->mFaces[f];
        if (face.mNumIndices != 3)
            continue;
        indices.push_back(face.mIndices[0]);
        indices.push_back(face.mIndices[mirrored ? 2 : 1]);
        indices.push_back(face.mIndices[mirrored ? 1 : 2]);
    }
    uint32_t *index_copy = (uint32_t *)xmalloc(sizeof(uint32_t) * (indices.size() + 1));
    std::copy(indices.begin(), indices.end(), index_copy);
    std::string name = std::string(instance.node->mName.C_Str()) + "/" + mesh->mName.C_Str();
    scene_mesh *added = scene_add_mesh(ld.s, name.c_str(), "gltf", ld.path, number, vertex_count,
                                       positions, (uint32_t)(indices.size() / 3), index_copy,
                                       texcoords);
    added->xml_file = xstrdup(ld.path);
    added->normals = normal_values;
    if (normal_values) {
        mesh_data view = shapes_scene_mesh_view(added);
        added->file_normals = 1;
        added->flat_normals = shapes_normals_flat(&view);
    }
    int m = material(ld, mesh->mMaterialIndex);
    if (m < 0)
        return -1;
    added->material = (uint32_t)m;
    idmr_light light;
    memset(&light, 0, sizeof light);
    if (emission(ld.ai->mMaterials[mesh->mMaterialIndex], light.emission)) {
        light.kind = IDMR_LIGHT_AREA;
        added->light = scene_add_light(ld.s, &light);
    }
    return 0;
}

// What a node's placement makes of its origin and of its -z axis.
void place(const xform &world, float position[3], float direction[3])
{
    const double origin[3] = {0, 0, 0}, down[3] = {0, 0, -1};
    double p[3], d[3];
    xform_apply_point(&world, origin, p);
    xform_apply_vector(&world, down, d);
    if (!(xform_normalize(d) > 0) || !std::isfinite(d[0] + d[1] + d[2]))
        d[0] = d[1] = d[2] = 0;
    for (int k = 0; k < 3; k++)
        position[k] = (float)p[k], direction[k] = (float)d[k];
}

// "kind 'name'" of a camera or light (else of its node; else its number).
std::string label(const char *kind, const cJSON *item, const cJSON *node, int index)
{
    const cJSON *name = member(item, "name");
    if (!cJSON_IsString(name) || !name->valuestring[0])
        name = member(node, "name");
    if (cJSON_IsString(name) && name->valuestring[0])
        return std::string(kind) + " '" + name->valuestring + "'";
    return std::string(kind) + " " + std::to_string(index);
}

// KHR_lights_punctual, one light for each node that names one (gltf_validate.c checked them),
// read from the file's JSON: colour × intensity, a spot's cone angles, placed by its node.
int add_lights(Loader &ld)
{
    std::vector<const cJSON *> lights =
        items(member(member(member(ld.doc->json, "extensions"), "KHR_lights_punctual"), "lights"));
    for (const Placed &p : ld.placed) {
        const cJSON *reference =
            member(member(member(p.node, "extensions"), "KHR_lights_punctual"), "light");
        if (!cJSON_IsNumber(reference))
            continue;
        int index = (int)reference->valuedouble;
        const cJSON *l = lights[(size_t)index];
        const cJSON *type = member(l, "type"), *colour = member(l, "color");
        double intensity = number(l, "intensity", 1);
        idmr_light light;
        memset(&light, 0, sizeof light);
        for (int k = 0; k < 3; k++) {
            const cJSON *c = cJSON_GetArrayItem(colour, k);
            light.emission[k] =
                (float)std::max(0.0, (cJSON_IsNumber(c) ? c->valuedouble : 1.0) * intensity);
        }
        place(p.world, light.position, light.direction);
        if (strcmp(type->valuestring, "point") == 0) {
            light.kind = IDMR_LIGHT_POINT;
        } else if (strcmp(type->valuestring, "spot") == 0) {
            light.kind = IDMR_LIGHT_SPOT;
            const cJSON *spot = member(l, "spot");
            double outer = number(spot, "outerConeAngle", M_PI / 4);
            double inner = number(spot, "innerConeAngle", 0);
            light.cos_cutoff = (float)std::cos(outer);
            light.cos_falloff_start = (float)std::cos(inner);
        } else {
            light.kind = IDMR_LIGHT_DIRECTIONAL;
        }
        float length = light.direction[0] * light.direction[0] +
                       light.direction[1] * light.direction[1] +
                       light.direction[2] * light.direction[2];
        if (length == 0 && light.kind != IDMR_LIGHT_POINT)
            return fail(ld.path, label("light", l, p.node, index) + " (/nodes/" +
                                     std::to_string(p.index) +
                                     "): its node's transform is degenerate");
        scene_add_light(ld.s, &light);
    }
    return 0;
}

// The camera frame from origin, forward and up (world space); false when degenerate.
bool set_frame(idmr_camera *camera, aiVector3D origin, aiVector3D forward, aiVector3D up)
{
    forward = unit(forward);
    up = unit(up - forward * (up * forward));
    aiVector3D right = forward ^ up;
    if (forward.SquareLength() == 0 || up.SquareLength() == 0 || right.SquareLength() == 0)
        return false;
    const aiVector3D *from[4] = {&origin, &forward, &right, &up};
    float *to[4] = {camera->origin, camera->forward, camera->right, camera->up};
    for (int i = 0; i < 4; i++)
        to[i][0] = from[i]->x, to[i][1] = from[i]->y, to[i][2] = from[i]->z;
    return true;
}

void set_film(scene *s, double yfov, double aspect)
{
    idmr_camera *camera = &s->camera;
    camera->width = FILM_WIDTH;
    camera->height = (unsigned)std::max(1.0, std::round(FILM_WIDTH / aspect));
    camera->tan_half_y = (float)std::tan(yfov / 2);
    camera->tan_half_x = (float)(std::tan(yfov / 2) * camera->width / camera->height);
    s->camera_info.fov_degrees = (float)(yfov * 180 / M_PI);
    snprintf(s->camera_info.fov_axis, sizeof s->camera_info.fov_axis, "y");
    s->has_camera = 1;
}

// The first perspective camera a node of the default scene holds (depth first; read from the
// file's JSON, checked by gltf_validate.c); none: the scene framed from +z (needs the bounding
// box: frame_scene).
int add_camera(Loader &ld)
{
    std::vector<const cJSON *> cameras = items(member(ld.doc->json, "cameras"));
    for (const Placed &p : ld.placed) {
        const cJSON *reference = member(p.node, "camera");
        if (!cJSON_IsNumber(reference))
            continue;
        int index = (int)reference->valuedouble;
        const cJSON *c = cameras[(size_t)index];
        std::string name = label("camera", c, p.node, index);
        if (strcmp(member(c, "type")->valuestring, "perspective") != 0) {
            warn("%s: %s is orthographic: not simulated", ld.path, name.c_str());
            continue;
        }
        const cJSON *perspective = member(c, "perspective");
        double yfov = number(perspective, "yfov", DEFAULT_YFOV);
        double aspect = number(perspective, "aspectRatio", DEFAULT_ASPECT);
        const xform &w = p.world;
        aiVector3D origin((float)w.m[3], (float)w.m[7], (float)w.m[11]);
        aiVector3D forward(-(float)w.m[2], -(float)w.m[6], -(float)w.m[10]);
        aiVector3D up((float)w.m[1], (float)w.m[5], (float)w.m[9]);
        if (!set_frame(&ld.s->camera, origin, forward, up))
            return fail(ld.path, name + " (/nodes/" + std::to_string(p.index) +
                                     "): its node's transform is degenerate");
        set_film(ld.s, yfov, aspect);
        for (int k = 0; k < 16; k++)
            ld.s->camera_info.to_world[k] = (float)w.m[k];
        return 0;
    }
    return 0;
}

// No camera in the file: the bounding sphere framed from +z (after scene_finalize).
void frame_scene(Loader &ld)
{
    scene *s = ld.s;
    aiVector3D low(s->bbox_min[0], s->bbox_min[1], s->bbox_min[2]);
    aiVector3D high(s->bbox_max[0], s->bbox_max[1], s->bbox_max[2]);
    aiVector3D centre = (low + high) * 0.5f;
    float radius = std::max(1e-6f, (high - low).Length() / 2);
    float distance = radius / (float)std::sin(DEFAULT_YFOV / 2);
    set_frame(&s->camera, centre + aiVector3D(0, 0, distance), aiVector3D(0, 0, -1),
              aiVector3D(0, 1, 0));
    set_film(s, DEFAULT_YFOV, DEFAULT_ASPECT);
    warn("%s: no perspective camera: the whole scene is framed from +z (yfov 45 degrees); "
         "add a camera to reduce for the view you render",
         ld.path);
}

// No light and no emissive material: a uniform white sky (radiance 1), as glTF viewers light
// such a model by an environment of their own.
int add_default_light(Loader &ld)
{
    if (ld.s->light_count > 0)
        return 0;
    warn("%s: no light and no emissive material: lit by a uniform white environment "
         "(radiance 1), as a viewer would",
         ld.path);
    float *white = (float *)xmalloc(sizeof(float) * 3);
    white[0] = white[1] = white[2] = 1.0f;
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    return scene_add_environment(ld.s, nullptr, 1, 1, white, identity) < 0 ? -1 : 0;
}

void warn_unsimulated(const Loader &ld)
{
    if (ld.ai->mNumAnimations)
        warn("%s: %u animations are not simulated: the scene is taken as it stands", ld.path,
             ld.ai->mNumAnimations);
    for (unsigned i = 0; i < ld.ai->mNumMeshes; i++)
        if (ld.ai->mMeshes[i]->mNumBones || ld.ai->mMeshes[i]->mNumAnimMeshes) {
            warn("%s: skins and morph targets are not simulated: meshes in their rest pose",
                 ld.path);
            return;
        }
}

} // namespace

extern "C" int gltf_is_scene_file(const char *path)
{
    const char *dot = strrchr(path, '.');
    return dot && (strcasecmp(dot, ".gltf") == 0 || strcasecmp(dot, ".glb") == 0);
}

namespace {

// The checked document, freed on every way out of gltf_load.
struct Checked {
    gltf_document doc;
    gltf_checked checked;
    progress bar; // the whole load: accessors, primitives, Assimp's import, instances
    Checked() : doc(), checked(), bar() {}
    ~Checked()
    {
        progress_end(&bar);
        gltf_checked_free(&checked);
        gltf_document_free(&doc);
    }
};

// How much of the load is done when Assimp calls (it does at its start and end, and between
// its post-processing steps): the import counts as one unit of work.
class ImportProgress : public Assimp::ProgressHandler {
public:
    explicit ImportProgress(progress *bar) : bar_(bar), start_(bar->done) {}
    bool Update(float share) override
    {
        progress_update(bar_, start_ + (share >= 1.0f ? 1u : 0u), nullptr);
        return true; // go on
    }

private:
    progress *bar_;
    unsigned start_;
};

// The scene of Assimp's import (the document checked): instances, lights, camera. NULL with the
// error set.
scene *build(const char *path, const aiScene *ai, Checked &file)
{
    char *dir = mitsuba_path_directory(path);
    Loader ld{path,
              dir,
              ai,
              scene_create(path),
              std::vector<int>(ai->mNumMaterials, -1),
              false,
              &file.doc,
              &file.checked,
              place_nodes(file.doc.json),
              {}};
    free(dir);
    ld.primitive_of = instance_primitives(file.doc.json, ld.placed);
    std::vector<Instance> instances;
    collect_instances(ai, ai->mRootNode, aiMatrix4x4(), instances);
    int status = instances.empty() ? fail(path, "holds no triangle mesh") : 0;
    if (!status && instances.size() != ld.primitive_of.size())
        status = fail(path, "Assimp found " + std::to_string(instances.size()) +
                                " triangle mesh instances, the file has " +
                                std::to_string(ld.primitive_of.size()));
    progress_set_total(&file.bar, file.bar.done + (unsigned)instances.size());
    // A primitive several nodes name is held once (mark_first_copy), unless it emits: an area
    // light is never instanced, so each node's emitting copy is a mesh of its own.
    std::unordered_map<const cJSON *, size_t> uses, first_copy;
    for (size_t i = 0; i < instances.size(); i++)
        uses[ld.primitive_of[i]]++;
    for (size_t i = 0; i < instances.size() && !status; i++) {
        const cJSON *primitive = ld.primitive_of[i];
        auto first = first_copy.find(primitive);
        if (first != first_copy.end()) {
            status = add_later_copy(ld, instances[i], (int)i, first->second);
        } else {
            status = add_instance(ld, instances[i], (int)i);
            if (!status && uses[primitive] > 1 && ld.s->meshes[i].light < 0) {
                mark_first_copy(ld, instances[i], i);
                first_copy[primitive] = i;
            }
        }
        progress_advance(&file.bar, 1, nullptr);
    }
    if (!status)
        status = add_lights(ld);
    if (!status)
        status = add_camera(ld);
    if (!status)
        status = add_default_light(ld);
    if (!status)
        warn_unsimulated(ld);
    if (!status && scene_finalize(ld.s))
        status = error_prefix("%s", path);
    if (!status && !ld.s->has_camera)
        frame_scene(ld);
    if (status) {
        scene_free(ld.s);
        return nullptr;
    }
    return ld.s;
}

} // namespace

extern "C" scene *gltf_load(const char *path)
{
    Checked file;
    progress_begin(&file.bar, "loading glTF", 1, !progress_quiet()); // the total once read
    progress_delay(&file.bar, 1.0);
    if (gltf_document_read(path, &file.doc))
        return nullptr;
    // one unit per accessor and primitive checked, one for Assimp, one per instance (at first
    // a primitive per node that names a mesh, then as Assimp found them); shown once loading
    // has taken a second
    unsigned work = (unsigned)cJSON_GetArraySize(member(file.doc.json, "accessors")) + 1;
    std::vector<const cJSON *> meshes = items(member(file.doc.json, "meshes"));
    for (const cJSON *mesh : meshes)
        work += (unsigned)cJSON_GetArraySize(member(mesh, "primitives"));
    for (const cJSON *node : items(member(file.doc.json, "nodes"))) {
        double mesh = number(node, "mesh", -1);
        if (mesh >= 0 && mesh < (double)meshes.size())
            work += (unsigned)cJSON_GetArraySize(member(meshes[(size_t)mesh], "primitives"));
    }
    progress_set_total(&file.bar, work);
    if (gltf_validate(&file.doc, &file.bar, &file.checked))
        return nullptr;
    gltf_document_release_buffers(&file.doc); // Assimp reads its own; read again if needed
    try {
        Assimp::Importer importer;
        importer.SetProgressHandler(new ImportProgress(&file.bar)); // the importer owns it
        const aiScene *ai = import(importer, path);
        if (!ai)
            return nullptr;
        progress_advance(&file.bar, 1, nullptr);
        return build(path, ai, file);
    } catch (const std::exception &e) {
        error_set(IDMR_EXIT_INPUT, "%s: Assimp failed: %s", path, e.what());
        return nullptr;
    }
}

extern "C" const char *gltf_output_name(const char *scene_file)
{
    const char *dot = strrchr(scene_file, '.');
    return dot && strcasecmp(dot, ".glb") == 0 ? "scene.glb" : "scene.gltf";
}
