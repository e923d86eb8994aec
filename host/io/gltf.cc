// gltf.cc — glTF 2.0 scenes read through Assimp (the mapping is in gltf.h; the reduced scene is
// written by gltf_write.c, from the file's own JSON).
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <strings.h>
#include <vector>

extern "C" {
#include "core/error.h"
#include "io/gltf.h"
#include "io/image.h"
#include "io/mitsuba_paths.h"
#include "io/shapes.h"
}

namespace {

// A primitive per aiMesh, triangulated; the instances' numbering (collect_instances) is the one
// gltf_write.c's walk() makes again from the file's JSON when it writes the reduced meshes.
const unsigned IMPORT_FLAGS =
    aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure;

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
        if (is_triangle_mesh(scene->mMeshes[node->mMeshes[k]]))
            out.push_back(Instance{node, k, world});
    for (unsigned c = 0; c < node->mNumChildren; c++)
        collect_instances(scene, node->mChildren[c], world, out);
}

// The transform of the node named `name` (a camera's or light's), world space; identity when
// no node has that name. glTF places cameras and lights at their node's origin looking down
// its -z, with +y up; that is what is read (Assimp 5.2 also copies the node's translation
// into the camera's and light's own position, which would count it twice).
aiMatrix4x4 node_world(const aiScene *scene, const aiString &name)
{
    aiMatrix4x4 world;
    for (const aiNode *node = scene->mRootNode->FindNode(name); node; node = node->mParent)
        world = node->mTransformation * world;
    return world;
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

struct Loader {
    const char *path;
    std::string dir;
    const aiScene *ai;
    scene *s;
    std::vector<int> material_of; // per aiMaterial: the scene's material, or -1 before first use
    bool warned_embedded = false;
};

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

int add_instance(Loader &ld, const Instance &instance, int number)
{
    const aiMesh *mesh = ld.ai->mMeshes[instance.node->mMeshes[instance.slot]];
    const aiMatrix4x4 &world = instance.world;
    aiMatrix3x3 normals = normal_matrix(world);
    bool mirrored = determinant3(world) < 0;
    uint32_t vertex_count = mesh->mNumVertices;
    float *positions = (float *)xmalloc(sizeof(float) * 3 * (vertex_count + 1));
    float *texcoords = nullptr, *normal_values = nullptr;
    for (uint32_t v = 0; v < vertex_count; v++) {
        aiVector3D p = world * mesh->mVertices[v];
        positions[3 * v] = p.x, positions[3 * v + 1] = p.y, positions[3 * v + 2] = p.z;
    }
    if (mesh->HasTextureCoords(0)) {
        texcoords = (float *)xmalloc(sizeof(float) * 2 * (vertex_count + 1));
        for (uint32_t v = 0; v < vertex_count; v++) {
            texcoords[2 * v] = mesh->mTextureCoords[0][v].x;
            texcoords[2 * v + 1] = 1.0f - mesh->mTextureCoords[0][v].y;
        }
    }
    if (mesh->HasNormals()) {
        normal_values = (float *)xmalloc(sizeof(float) * 3 * (vertex_count + 1));
        for (uint32_t v = 0; v < vertex_count; v++) {
            aiVector3D n = unit(normals * mesh->mNormals[v]);
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

int add_lights(Loader &ld)
{
    for (unsigned i = 0; i < ld.ai->mNumLights; i++) {
        const aiLight *l = ld.ai->mLights[i];
        aiMatrix4x4 world = node_world(ld.ai, l->mName);
        idmr_light light;
        memset(&light, 0, sizeof light);
        aiVector3D position = world * aiVector3D(0, 0, 0);
        aiVector3D direction = unit(aiMatrix3x3(world) * aiVector3D(0, 0, -1));
        light.emission[0] = std::max(0.0f, l->mColorDiffuse.r);
        light.emission[1] = std::max(0.0f, l->mColorDiffuse.g);
        light.emission[2] = std::max(0.0f, l->mColorDiffuse.b);
        light.position[0] = position.x, light.position[1] = position.y,
        light.position[2] = position.z;
        light.direction[0] = direction.x, light.direction[1] = direction.y,
        light.direction[2] = direction.z;
        switch (l->mType) {
        case aiLightSource_POINT:
            light.kind = IDMR_LIGHT_POINT;
            break;
        case aiLightSource_SPOT: {
            light.kind = IDMR_LIGHT_SPOT;
            float outer = std::min((float)M_PI / 2, std::max(0.0f, l->mAngleOuterCone));
            float inner = std::min(outer, std::max(0.0f, l->mAngleInnerCone));
            light.cos_cutoff = std::cos(outer);
            light.cos_falloff_start = std::cos(inner);
            break;
        }
        case aiLightSource_DIRECTIONAL:
            light.kind = IDMR_LIGHT_DIRECTIONAL;
            break;
        default:
            warn("%s: light '%s' is of a kind glTF does not define: ignored", ld.path,
                 l->mName.C_Str());
            continue;
        }
        if (direction.SquareLength() == 0 && light.kind != IDMR_LIGHT_POINT)
            return fail(ld.path, std::string("light '") + l->mName.C_Str() +
                                     "': its node's transform is degenerate");
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

// The first perspective camera; none: the scene framed from +z (needs the bounding box).
int add_camera(Loader &ld)
{
    for (unsigned i = 0; i < ld.ai->mNumCameras; i++) {
        const aiCamera *c = ld.ai->mCameras[i];
        if (c->mHorizontalFOV <= 0 || c->mOrthographicWidth > 0) {
            warn("%s: camera '%s' is orthographic: not simulated", ld.path, c->mName.C_Str());
            continue;
        }
        aiMatrix4x4 world = node_world(ld.ai, c->mName);
        aiMatrix3x3 linear(world);
        double aspect = c->mAspect > 0 ? c->mAspect : DEFAULT_ASPECT;
        // Assimp 5.2 stores glTF's yfov × aspect ratio as mHorizontalFOV (the full angle):
        // yfov is that divided by the aspect again.
        double yfov = c->mAspect > 0 ? c->mHorizontalFOV / c->mAspect : c->mHorizontalFOV;
        if (!(yfov > 0 && yfov < M_PI))
            return fail(ld.path, std::string("camera '") + c->mName.C_Str() +
                                     "': its field of view is not between 0 and 180 degrees");
        if (!set_frame(&ld.s->camera, world * aiVector3D(0, 0, 0), linear * aiVector3D(0, 0, -1),
                       linear * aiVector3D(0, 1, 0)))
            return fail(ld.path, std::string("camera '") + c->mName.C_Str() +
                                     "': its node's transform is degenerate");
        set_film(ld.s, yfov, aspect);
        for (int k = 0; k < 16; k++)
            ld.s->camera_info.to_world[k] = world[k / 4][k % 4];
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

extern "C" scene *gltf_load(const char *path)
{
    try {
        Assimp::Importer importer;
        const aiScene *ai = import(importer, path);
        if (!ai)
            return nullptr;
        char *dir = mitsuba_path_directory(path);
        Loader ld{path, dir, ai, scene_create(path), std::vector<int>(ai->mNumMaterials, -1)};
        free(dir);
        std::vector<Instance> instances;
        collect_instances(ai, ai->mRootNode, aiMatrix4x4(), instances);
        int status = instances.empty() ? fail(path, "holds no triangle mesh") : 0;
        for (size_t i = 0; i < instances.size() && !status; i++)
            status = add_instance(ld, instances[i], (int)i);
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
