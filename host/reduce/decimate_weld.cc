// decimate_weld.cc — the mesh the decimater starts from (decimate.h, "Non-manifold input"):
// input vertices at identical positions welded into one, faces attached in order and retried
// until no more attach, what still fails patched onto copied vertices or left loose with locked
// copies, and vertices that no face uses removed.
//
// Mesh vertices in order of creation: the welded vertices (index = welded index, in order of
// first appearance in the input), then the patch copies, then three locked copies per loose face.
#include "reduce/decimate_openmesh.hh"

#include <algorithm>
#include <cstring>
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

// What the rebuild steps share: the input, the mesh being built, the output's welding figures,
// the importance per mesh vertex and the handle of each welded vertex.
struct WeldedBuild {
    const decimate_input *in;
    Mesh &mesh;
    decimate_output *out;
    std::vector<double> &importance;
    std::vector<Mesh::VertexHandle> handles;

    // The welded vertex of corner k of input triangle t.
    uint32_t welded_corner(uint32_t t, int k) const
    {
        return out->welded_of[in->indices[3 * (size_t)t + k]];
    }
};

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
        if (!b.mesh.add_face(b.handles[a], b.handles[c1], b.handles[c2]).is_valid())
            pending.push_back(t);
    }
    for (bool progress = true; progress && !pending.empty();) {
        progress = false;
        std::vector<uint32_t> still;
        for (uint32_t t : pending) {
            if (b.mesh.add_face(b.handles[b.welded_corner(t, 0)], b.handles[b.welded_corner(t, 1)],
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
        if (!b.mesh.add_face(a, c1, c2).is_valid())
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
        b.mesh.add_face(copy[0], copy[1], copy[2]);
        b.out->faces_loose++;
        b.out->vertices_uncollapsible += 3;
    }
}

// A position used only by patched or loose faces keeps a vertex without faces: remove it (it
// would never collapse, count against the budget, and be written out).
void remove_isolated_vertices(WeldedBuild &b)
{
    uint32_t isolated = 0;
    for (auto v : b.mesh.vertices())
        if (b.mesh.is_isolated(v)) {
            b.mesh.status(v).set_deleted(true);
            isolated++;
        }
    b.out->vertices_welded = (uint32_t)b.mesh.n_vertices() - isolated;
}

} // namespace

void build_welded_mesh(const decimate_input *in, Mesh &mesh, decimate_output *out,
                       std::vector<double> &importance)
{
    mesh_io_silence_openmesh_logs(); // failed add_face calls would each log a line
    WeldedBuild b{in, mesh, out, importance, {}};
    weld_vertices(b);
    std::vector<uint32_t> pending = attach_faces(b);
    std::vector<uint32_t> loose = patch_faces(b, pending);
    add_loose_faces(b, loose);
    remove_isolated_vertices(b);
}

} // namespace idmr_decimate
