// decimate_weld.cc — the mesh the decimater starts from (decimate.h, "Non-manifold input"):
// input vertices at identical positions welded into one, faces attached in order and retried
// until no more attach, what still fails patched onto copied vertices or left loose with locked
// copies, and vertices that no face uses removed.
//
// Where the input has attributes, input vertices welded into one position keep one attribute id
// per distinct (bit-identical) attribute set, and every face records its corners' ids
// (decimate_attributes.hh).
//
// Mesh vertices in order of creation: the welded vertices (index = welded index, in order of
// first appearance in the input), then the patch copies, then three locked copies per loose face.
#include "reduce/decimate_openmesh.hh"

#include <algorithm>
#include <cstring>
#include <exception>
#include <unordered_map>

extern "C" {
#include "core/error.h"
}

namespace idmr_decimate {
namespace {

// A position as its bit pattern (after folding -0 into 0), for welding exact duplicates.
struct PositionKey {
    float x, y, z;
    bool operator==(const PositionKey &o) const
    {
        return std::memcmp(this, &o, sizeof *this) == 0;
    }
};
struct PositionHash {
    size_t operator()(const PositionKey &k) const
    {
        uint32_t w[3];
        std::memcpy(w, &k, sizeof w);
        return ((size_t)w[0] * 73856093u) ^ ((size_t)w[1] * 19349663u) ^ ((size_t)w[2] * 83492791u);
    }
};

// A welded vertex and the bit pattern of an attribute set at it, for numbering attribute sets.
struct AttributeKey {
    uint32_t welded;
    uint32_t bits[5];
    bool operator==(const AttributeKey &o) const
    {
        return std::memcmp(this, &o, sizeof *this) == 0;
    }
};
struct AttributeHash {
    size_t operator()(const AttributeKey &k) const
    {
        size_t h = k.welded;
        for (uint32_t b : k.bits)
            h = h * 1000003u ^ b;
        return h;
    }
};

// What the rebuild steps share: the input, the mesh being built, the output's welding figures,
// the importance per mesh vertex, the handle of each welded vertex, and the attribute table with
// the attribute id of each input vertex.
struct WeldedBuild {
    const decimate_input *in;
    Mesh &mesh;
    decimate_output *out;
    std::vector<double> &importance;
    AttributeTable &attributes;
    std::vector<Mesh::VertexHandle> handles;
    std::vector<uint32_t> attribute_of;
    std::vector<uint32_t> face_triangle; // per face added, its input triangle

    // The welded vertex of corner k of input triangle t.
    uint32_t welded_corner(uint32_t t, int k) const
    {
        return out->welded_of[in->indices[3 * (size_t)t + k]];
    }

    // Adds the face (a, b, c) for input triangle t (its corners k = 0, 1, 2) and records the
    // corners' attribute ids. Returns the face (invalid if it could not be attached).
    Mesh::FaceHandle add_face(uint32_t t, Mesh::VertexHandle a, Mesh::VertexHandle b,
                              Mesh::VertexHandle c)
    {
        Mesh::FaceHandle f = mesh.add_face(a, b, c);
        if (f.is_valid())
            face_triangle.push_back(t);
        if (f.is_valid() && attributes.present()) {
            CornerSet &set = mesh.property(attributes.corners, f);
            Mesh::VertexHandle corner[3] = {a, b, c};
            for (int k = 0; k < 3; k++) {
                set.vertex[k] = corner[k].idx();
                set.id[k] = attribute_of[in->indices[3 * (size_t)t + k]];
            }
        }
        return f;
    }
};

// Numbers the attribute sets: per welded vertex, one id per bit-distinct set (uv, normal as the
// input has them, -0 folded into 0); fills the table's values.
void number_attributes(WeldedBuild &b)
{
    AttributeTable &table = b.attributes;
    table.uv_floats = b.in->texcoords ? 2 : 0;
    table.normal_floats = b.in->normals ? 3 : 0;
    if (!table.present())
        return;
    b.mesh.add_property(table.corners);
    std::unordered_map<AttributeKey, uint32_t, AttributeHash> id_of;
    b.attribute_of.resize(b.in->vertex_count);
    for (uint32_t v = 0; v < b.in->vertex_count; v++) {
        float value[5] = {0, 0, 0, 0, 0};
        int n = 0;
        for (int k = 0; k < table.uv_floats; k++)
            value[n++] = b.in->texcoords[2 * (size_t)v + k] + 0.0f;
        for (int k = 0; k < table.normal_floats; k++)
            value[n++] = b.in->normals[3 * (size_t)v + k] + 0.0f;
        AttributeKey key;
        std::memset(&key, 0, sizeof key);
        key.welded = b.out->welded_of[v];
        std::memcpy(key.bits, value, sizeof(float) * n);
        auto found = id_of.find(key);
        if (found != id_of.end()) {
            b.attribute_of[v] = found->second;
            continue;
        }
        uint32_t id = (uint32_t)id_of.size();
        id_of.emplace(key, id);
        b.attribute_of[v] = id;
        table.values.insert(table.values.end(), value, value + n);
    }
}

// One mesh vertex per distinct position; a welded vertex keeps the largest importance of the
// input vertices welded into it.
void weld_vertices(WeldedBuild &b)
{
    std::unordered_map<PositionKey, uint32_t, PositionHash> first_at;
    b.out->welded_of = (uint32_t *)xmalloc(sizeof(uint32_t) * (b.in->vertex_count + 1));
    for (uint32_t v = 0; v < b.in->vertex_count; v++) {
        const float *p = &b.in->positions[3 * (size_t)v];
        PositionKey key{p[0] + 0.0f, p[1] + 0.0f, p[2] + 0.0f}; // +0.0f folds -0 into 0
        auto found = first_at.find(key);
        double value = b.in->vertex_importance ? b.in->vertex_importance[v] : 0.0;
        if (found != first_at.end()) {
            b.out->welded_of[v] = found->second;
            b.importance[found->second] = std::max(b.importance[found->second], value);
            continue;
        }
        uint32_t index = (uint32_t)b.handles.size();
        first_at.emplace(key, index);
        b.out->welded_of[v] = index;
        b.handles.push_back(b.mesh.add_vertex(Mesh::Point(p[0], p[1], p[2])));
        b.importance.push_back(value);
    }
}

// Attaches the faces in input order, then retries the failed ones while any attaches (a face
// may attach once its neighbours are in); drops faces that weld into zero area. Returns the
// faces that still fail.
std::vector<uint32_t> attach_faces(WeldedBuild &b)
{
    std::vector<uint32_t> pending;
    for (uint32_t t = 0; t < b.in->triangle_count; t++) {
        uint32_t a = b.welded_corner(t, 0), c1 = b.welded_corner(t, 1), c2 = b.welded_corner(t, 2);
        if (a == c1 || c1 == c2 || a == c2) {
            b.out->faces_dropped++;
            continue;
        }
        if (!b.add_face(t, b.handles[a], b.handles[c1], b.handles[c2]).is_valid())
            pending.push_back(t);
    }
    for (bool progress = true; progress && !pending.empty();) {
        progress = false;
        std::vector<uint32_t> still;
        for (uint32_t t : pending) {
            if (b.add_face(t, b.handles[b.welded_corner(t, 0)], b.handles[b.welded_corner(t, 1)],
                           b.handles[b.welded_corner(t, 2)])
                    .is_valid())
                progress = true;
            else
                still.push_back(t);
        }
        pending.swap(still);
    }
    return pending;
}

// What still fails sits at non-manifold edges of the main surface. Those faces get their own
// copies of the vertices, shared among themselves, so connected ones form a separate patch that
// can still be decimated. Returns the faces that cannot join even that.
std::vector<uint32_t> patch_faces(WeldedBuild &b, const std::vector<uint32_t> &pending)
{
    std::unordered_map<uint32_t, Mesh::VertexHandle> patch_copy;
    auto copy_of = [&](uint32_t welded) {
        auto found = patch_copy.find(welded);
        if (found != patch_copy.end())
            return found->second;
        Mesh::Point p = b.mesh.point(b.handles[welded]); // a copy: add_vertex may move the points
        Mesh::VertexHandle h = b.mesh.add_vertex(p);
        b.importance.push_back(b.importance[welded]);
        patch_copy.emplace(welded, h);
        return h;
    };
    std::vector<uint32_t> loose;
    for (uint32_t t : pending) {
        Mesh::VertexHandle a = copy_of(b.welded_corner(t, 0)), c1 = copy_of(b.welded_corner(t, 1)),
                           c2 = copy_of(b.welded_corner(t, 2));
        if (!b.add_face(t, a, c1, c2).is_valid())
            loose.push_back(t);
    }
    b.out->faces_patched = (uint32_t)(pending.size() - loose.size());
    return loose;
}

// A loose face gets three copies of its own, locked: they cannot be collapsed.
void add_loose_faces(WeldedBuild &b, const std::vector<uint32_t> &loose)
{
    for (uint32_t t : loose) {
        Mesh::VertexHandle copy[3];
        for (int k = 0; k < 3; k++) {
            uint32_t welded = b.welded_corner(t, k);
            Mesh::Point p = b.mesh.point(b.handles[welded]); // a copy, as in patch_faces
            copy[k] = b.mesh.add_vertex(p);
            b.mesh.status(copy[k]).set_locked(true);
            b.importance.push_back(b.importance[welded]);
        }
        b.add_face(t, copy[0], copy[1], copy[2]);
        b.out->faces_loose++;
        b.out->vertices_uncollapsible += 3;
    }
}

// A position used only by patched or loose faces keeps a vertex without faces: remove it (it
// would never collapse, count against the budget, and be written out). Counts the rest as
// vertices_welded, once per wedge.
void remove_isolated_vertices(WeldedBuild &b)
{
    uint32_t kept = 0;
    std::vector<uint32_t> scratch;
    for (auto v : b.mesh.vertices()) {
        if (b.mesh.is_isolated(v))
            b.mesh.status(v).set_deleted(true);
        else
            kept += wedge_count(b.mesh, b.attributes, v, scratch);
    }
    b.out->vertices_welded = kept;
}

} // namespace

void build_welded_mesh(const decimate_input *in, Mesh &mesh, decimate_output *out,
                       std::vector<double> &importance, AttributeTable &attributes,
                       std::vector<uint32_t> *face_triangle)
{
    mesh_io_silence_openmesh_logs(); // failed add_face calls would each log a line
    WeldedBuild b{in, mesh, out, importance, attributes, {}, {}, {}};
    weld_vertices(b);
    number_attributes(b);
    std::vector<uint32_t> pending = attach_faces(b);
    std::vector<uint32_t> loose = patch_faces(b, pending);
    add_loose_faces(b, loose);
    remove_isolated_vertices(b);
    if (face_triangle)
        face_triangle->swap(b.face_triangle);
}

void copy_attribute_values(int uv_floats, int normal_floats, const float *values,
                           const std::vector<uint32_t> &id_of, mesh_data *out)
{
    size_t n = id_of.size();
    int stride = uv_floats + normal_floats;
    if (uv_floats)
        out->texcoords = (float *)xmalloc(2 * sizeof(float) * (n + 1));
    if (normal_floats)
        out->normals = (float *)xmalloc(3 * sizeof(float) * (n + 1));
    for (size_t i = 0; i < n; i++) {
        const float *value = &values[(size_t)stride * id_of[i]];
        for (int k = 0; k < uv_floats; k++)
            out->texcoords[2 * i + k] = value[k];
        for (int k = 0; k < normal_floats; k++)
            out->normals[3 * i + k] = value[uv_floats + k];
    }
}

int decimate_guarded(const decimate_input *in, decimate_method method, decimate_output *out,
                     int (*decimate)(const decimate_input *, decimate_method, decimate_output *))
{
    std::memset(out, 0, sizeof *out);
    if (method != DECIMATE_QUADRIC && !in->vertex_importance)
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': importance decimation without importance",
                         in->name);
    try {
        return decimate(in, method, out);
    } catch (const std::exception &e) {
        decimate_output_free(out);
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
}

std::vector<uint32_t> welded_distances(const decimate_input *in, const decimate_output *out,
                                       size_t n)
{
    std::vector<uint32_t> distance;
    if (!in->vertex_distance)
        return distance;
    distance.assign(n, 0);
    std::vector<bool> seen(n, false);
    for (uint32_t i = 0; i < in->vertex_count; i++) {
        uint32_t w = out->welded_of[i];
        if (w >= n)
            continue;
        distance[w] = seen[w] ? std::min(distance[w], in->vertex_distance[i]) : in->vertex_distance[i];
        seen[w] = true;
    }
    return distance;
}

// The rebuild's input: the flat weld's kept triangles, turned as it turned them, in its order
// (its twins and the triangles that weld into zero area left out), over the input's vertices.
std::vector<uint32_t> repaired_indices(const decimate_input *in, const weld_result &flat)
{
    std::vector<uint32_t> indices(3 * (size_t)flat.triangle_count);
    for (uint32_t k = 0; k < flat.triangle_count; k++) {
        const uint32_t *ix = &in->indices[3 * (size_t)flat.kept_from[k]];
        bool turned = flat.turned && flat.turned[k];
        indices[3 * (size_t)k] = ix[0];
        indices[3 * (size_t)k + 1] = ix[turned ? 2 : 1];
        indices[3 * (size_t)k + 2] = ix[turned ? 1 : 2];
    }
    return indices;
}

} // namespace idmr_decimate
