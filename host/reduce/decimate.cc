// decimate.cc — the OpenMesh side of the reduction (see decimate.h): mesh rebuild with welding,
// the importance, normal-limit and history modules, our collapse loop, and the thread pool.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/BaseDecimaterT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModBaseT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <queue>
#include <thread>
#include <unordered_map>
#include <vector>

extern "C" {
#include "reduce/decimate.h"
#include "core/error.h"
}

namespace {

struct Traits : public OpenMesh::DefaultTraits {
    VertexAttributes(OpenMesh::Attributes::Status);
    EdgeAttributes(OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Status);
    HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
};
typedef OpenMesh::TriMesh_ArrayKernelT<Traits> Mesh;
typedef OpenMesh::Decimater::CollapseInfoT<Mesh> CollapseInfo;

// ---- modules ----

// Non-binary: priority = importance of the vertex and its one-ring; the kept vertex inherits the
// removed one's importance.
template <class MeshT> class ModImportanceT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModImportanceT, MeshT, Importance);
    explicit ModImportanceT(MeshT &mesh) : Base(mesh, false) { mesh.add_property(importance_); }
    ~ModImportanceT() override { Base::mesh().remove_property(importance_); }

    double &importance(typename MeshT::VertexHandle v) { return Base::mesh().property(importance_, v); }

    double ring_sum(typename MeshT::VertexHandle v)
    {
        double sum = importance(v);
        for (auto w : Base::mesh().vv_range(v))
            sum += importance(w);
        return sum;
    }

    float collapse_priority(const CollapseInfo &ci) override
    {
        double sum = ring_sum(ci.v0);
        return (float)std::min(sum, (double)FLT_MAX / 2);
    }

    void postprocess_collapse(const CollapseInfo &ci) override
    {
        importance(ci.v1) += importance(ci.v0);
    }

  private:
    OpenMesh::VPropHandleT<double> importance_;
};

// Binary: rejects a collapse that turns a remaining face around v0 by more than the limit or
// makes it degenerate.
template <class MeshT> class ModNormalLimitT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModNormalLimitT, MeshT, NormalLimit);
    explicit ModNormalLimitT(MeshT &mesh) : Base(mesh, true), min_cos_(0.5) {}

    void set_max_angle(double degrees) { min_cos_ = std::cos(degrees * M_PI / 180.0); }

    float collapse_priority(const CollapseInfo &ci) override
    {
        MeshT &mesh = Base::mesh();
        for (auto f : mesh.vf_range(ci.v0)) {
            if (f == ci.fl || f == ci.fr)
                continue;
            typename MeshT::Point p[3], q[3];
            int k = 0;
            for (auto v : mesh.fv_range(f)) {
                p[k] = mesh.point(v);
                q[k] = v == ci.v0 ? ci.p1 : p[k];
                k++;
            }
            OpenMesh::Vec3d a(p[0][0], p[0][1], p[0][2]), b(p[1][0], p[1][1], p[1][2]),
                c(p[2][0], p[2][1], p[2][2]);
            OpenMesh::Vec3d a2(q[0][0], q[0][1], q[0][2]), b2(q[1][0], q[1][1], q[1][2]),
                c2(q[2][0], q[2][1], q[2][2]);
            OpenMesh::Vec3d before = OpenMesh::cross(b - a, c - a);
            OpenMesh::Vec3d after = OpenMesh::cross(b2 - a2, c2 - a2);
            double lb = before.norm(), la = after.norm();
            if (!(la > 0))
                return Base::ILLEGAL_COLLAPSE;
            if (!(lb > 0))
                continue; // already degenerate: any direction is an improvement
            if (OpenMesh::dot(before, after) < min_cos_ * lb * la)
                return Base::ILLEGAL_COLLAPSE;
        }
        return Base::LEGAL_COLLAPSE;
    }

  private:
    double min_cos_;
};

// Binary, always legal: records which vertex each removed vertex went into.
template <class MeshT> class ModHistoryT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModHistoryT, MeshT, History);
    explicit ModHistoryT(MeshT &mesh) : Base(mesh, true), into_(nullptr) {}
    void set_history(uint32_t *into) { into_ = into; }
    float collapse_priority(const CollapseInfo &) override { return Base::LEGAL_COLLAPSE; }
    void postprocess_collapse(const CollapseInfo &ci) override
    {
        if (into_)
            into_[ci.v0.idx()] = (uint32_t)ci.v1.idx();
    }

  private:
    uint32_t *into_;
};

// ---- the collapse loop ----

class ReductionDecimater : public OpenMesh::Decimater::BaseDecimaterT<Mesh> {
  public:
    typedef OpenMesh::Decimater::BaseDecimaterT<Mesh> Base;
    explicit ReductionDecimater(Mesh &mesh) : Base(mesh), mesh_(mesh), importance_(nullptr) {}

    // Tie-break source: the importance module, or none.
    void set_importance(ModImportanceT<Mesh> *importance) { importance_ = importance; }

    struct Entry {
        float priority;
        double target_importance;
        int vertex;
        unsigned version;
        bool operator>(const Entry &o) const
        {
            if (priority != o.priority)
                return priority > o.priority;
            if (target_importance != o.target_importance)
                return target_importance > o.target_importance;
            return vertex > o.vertex;
        }
    };

    // The legality test of BaseDecimaterT::is_collapse_legal, with our own topology check in
    // place of OpenMesh's TriConnectivity::is_collapse_ok (Debian's library spends a third of
    // the decimation there on property type-name checks). The conditions: the link condition
    // (the one-rings of v0 and v1 share exactly the opposite vertices vl, vr), no triangle
    // whose other two edges are both boundary, a boundary vertex only into a boundary vertex
    // along a boundary edge, no collapse that leaves two valence-3 neighbours joined, and v0
    // keeps at least two faces.
    bool collapse_legal(const CollapseInfo &ci)
    {
        Mesh::VertexHandle v0 = ci.v0, v1 = ci.v1;
        if (mesh_.status(v0).locked() || mesh_.status(v0).deleted() || mesh_.status(v1).deleted() ||
            mesh_.status(mesh_.edge_handle(ci.v0v1)).deleted())
            return false;
        Mesh::HalfedgeHandle v0v1 = ci.v0v1, v1v0 = ci.v1v0;
        Mesh::VertexHandle vl, vr;
        // The triangle on side h of the edge: its opposite vertex, and whether its other two
        // edges are both boundary (collapsing would leave a dangling edge).
        auto side = [&](Mesh::HalfedgeHandle h, Mesh::VertexHandle *opposite) {
            Mesh::HalfedgeHandle h1 = mesh_.next_halfedge_handle(h);
            Mesh::HalfedgeHandle h2 = mesh_.next_halfedge_handle(h1);
            *opposite = mesh_.to_vertex_handle(h1);
            return mesh_.is_boundary(mesh_.opposite_halfedge_handle(h1)) &&
                   mesh_.is_boundary(mesh_.opposite_halfedge_handle(h2));
        };
        if (!mesh_.is_boundary(v0v1) && side(v0v1, &vl))
            return false;
        if (!mesh_.is_boundary(v1v0) && side(v1v0, &vr))
            return false;
        if (vl == vr)
            return false;
        bool b0 = mesh_.is_boundary(v0), b1 = mesh_.is_boundary(v1);
        if (b0 && b1 && !mesh_.is_boundary(v0v1) && !mesh_.is_boundary(v1v0))
            return false;
        ring_.clear();
        for (auto w : mesh_.vv_range(v1))
            ring_.push_back(w);
        for (auto w : mesh_.vv_range(v0))
            if (w != vl && w != vr && std::find(ring_.begin(), ring_.end(), w) != ring_.end())
                return false;
        if (vl.is_valid() && vr.is_valid() && mesh_.find_halfedge(vl, vr).is_valid() &&
            mesh_.valence(vl) == 3 && mesh_.valence(vr) == 3)
            return false;
        if (b0 && (!b1 || (vl.is_valid() && vr.is_valid())))
            return false;
        if (mesh_.cw_rotated_halfedge_handle(mesh_.cw_rotated_halfedge_handle(v0v1)) == v0v1)
            return false;
        return true;
    }

    // The best collapse of v: least priority, then least important target.
    bool best_collapse(Mesh::VertexHandle v, Entry *entry, Mesh::HalfedgeHandle *target)
    {
        if (importance_)
            return least_important_collapse(v, entry, target);
        bool found = false;
        for (auto h : mesh_.voh_range(v)) {
            CollapseInfo ci(mesh_, h);
            if (!collapse_legal(ci))
                continue;
            float priority = collapse_priority(ci);
            if (priority < 0)
                continue;
            Entry candidate{priority, 0.0, v.idx(), 0};
            if (!found || entry->operator>(candidate)) {
                *entry = candidate;
                *target = h;
                found = true;
            }
        }
        return found;
    }

    // With the importance module every collapse of v has the same priority (v's ring sum), so
    // the best is the first legal one in order of target importance: no need to test them all.
    bool least_important_collapse(Mesh::VertexHandle v, Entry *entry, Mesh::HalfedgeHandle *target)
    {
        candidates_.clear();
        for (auto h : mesh_.voh_range(v))
            candidates_.emplace_back(importance_->importance(mesh_.to_vertex_handle(h)), h);
        std::sort(candidates_.begin(), candidates_.end(),
                  [](const std::pair<double, Mesh::HalfedgeHandle> &a,
                     const std::pair<double, Mesh::HalfedgeHandle> &b) {
                      return a.first < b.first || (a.first == b.first && a.second < b.second);
                  });
        for (const auto &candidate : candidates_) {
            CollapseInfo ci(mesh_, candidate.second);
            if (!collapse_legal(ci))
                continue;
            float priority = collapse_priority(ci);
            if (priority < 0)
                continue;
            *entry = Entry{priority, candidate.first, v.idx(), 0};
            *target = candidate.second;
            return true;
        }
        return false;
    }

    void heap_vertex(Mesh::VertexHandle v)
    {
        unsigned version = ++version_[v.idx()];
        Entry entry;
        Mesh::HalfedgeHandle target;
        if (mesh_.status(v).deleted() || mesh_.status(v).locked() ||
            !best_collapse(v, &entry, &target)) {
            live_[v.idx()] = false;
            return;
        }
        entry.version = version;
        target_[v.idx()] = target;
        live_[v.idx()] = true;
        stored_[v.idx()] = entry;
        heap_.push(entry);
    }

    // Heap entries that a fresh evaluation would score differently (tests).
    uint64_t count_stale()
    {
        uint64_t stale = 0;
        for (auto v : mesh_.vertices()) {
            if (!live_[v.idx()] || mesh_.status(v).deleted())
                continue;
            Entry fresh;
            Mesh::HalfedgeHandle target;
            if (!best_collapse(v, &fresh, &target) || fresh.priority != stored_[v.idx()].priority ||
                target != target_[v.idx()])
                stale++;
        }
        return stale;
    }

    size_t decimate_to(size_t target_vertices, bool verify, bool removed_ring_only,
                       uint64_t *violations)
    {
        size_t n = mesh_.n_vertices();
        version_.assign(n, 0);
        target_.assign(n, Mesh::HalfedgeHandle());
        live_.assign(n, false);
        stored_.assign(n, Entry{0, 0, 0, 0});
        size_t alive = 0;
        for (auto v : mesh_.vertices())
            if (!mesh_.status(v).deleted()) {
                alive++;
                heap_vertex(v);
            }
        size_t collapses = 0;
        std::vector<Mesh::VertexHandle> support;
        while (!heap_.empty() && alive > target_vertices) {
            Entry top = heap_.top();
            heap_.pop();
            if (top.version != version_[top.vertex] || !live_[top.vertex])
                continue;
            live_[top.vertex] = false;
            Mesh::HalfedgeHandle h = target_[top.vertex];
            CollapseInfo ci(mesh_, h);
            if (!collapse_legal(ci) || collapse_priority(ci) < 0) {
                heap_vertex(ci.v0);
                continue;
            }
            support.clear();
            for (auto w : mesh_.vv_range(ci.v0))
                support.push_back(w);
            preprocess_collapse(ci);
            mesh_.collapse(h);
            postprocess_collapse(ci);
            collapses++;
            alive--;
            if (removed_ring_only) {
                for (auto w : support)
                    heap_vertex(w);
            } else {
                heap_vertex(ci.v1);
                for (auto w : mesh_.vv_range(ci.v1))
                    heap_vertex(w);
            }
            if (verify)
                *violations += count_stale();
        }
        return collapses;
    }

  private:
    Mesh &mesh_;
    ModImportanceT<Mesh> *importance_;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
    std::vector<unsigned> version_;
    std::vector<Mesh::HalfedgeHandle> target_;
    std::vector<bool> live_;
    std::vector<Entry> stored_;
    std::vector<std::pair<double, Mesh::HalfedgeHandle>> candidates_;
    std::vector<Mesh::VertexHandle> ring_;
};

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

// Builds the OpenMesh mesh: welded vertices, faces attached with retries, the rest loose.
void build_mesh(const decimate_input *in, Mesh &mesh, decimate_output *out,
                std::vector<double> &importance)
{
    mesh_io_silence_openmesh_logs(); // failed add_face calls below would each log a line
    std::unordered_map<PositionKey, uint32_t, PositionHash> first_at;
    out->welded_of = (uint32_t *)xmalloc(sizeof(uint32_t) * (in->vertex_count + 1));
    std::vector<Mesh::VertexHandle> handles;
    for (uint32_t v = 0; v < in->vertex_count; v++) {
        const float *p = &in->positions[3 * (size_t)v];
        PositionKey key{p[0] + 0.0f, p[1] + 0.0f, p[2] + 0.0f}; // +0.0f folds -0 into 0
        auto found = first_at.find(key);
        double value = in->vertex_importance ? in->vertex_importance[v] : 0.0;
        if (found != first_at.end()) {
            out->welded_of[v] = found->second;
            importance[found->second] = std::max(importance[found->second], value);
            continue;
        }
        uint32_t index = (uint32_t)handles.size();
        first_at.emplace(key, index);
        out->welded_of[v] = index;
        handles.push_back(mesh.add_vertex(Mesh::Point(p[0], p[1], p[2])));
        importance.push_back(value);
    }
    std::vector<uint32_t> pending;
    for (uint32_t t = 0; t < in->triangle_count; t++) {
        const uint32_t *ix = &in->indices[3 * (size_t)t];
        uint32_t a = out->welded_of[ix[0]], b = out->welded_of[ix[1]], c = out->welded_of[ix[2]];
        if (a == b || b == c || a == c) {
            out->faces_dropped++;
            continue;
        }
        if (!mesh.add_face(handles[a], handles[b], handles[c]).is_valid())
            pending.push_back(t);
    }
    // Faces that failed may attach once their neighbours are in.
    for (bool progress = true; progress && !pending.empty();) {
        progress = false;
        std::vector<uint32_t> still;
        for (uint32_t t : pending) {
            const uint32_t *ix = &in->indices[3 * (size_t)t];
            if (mesh.add_face(handles[out->welded_of[ix[0]]], handles[out->welded_of[ix[1]]],
                              handles[out->welded_of[ix[2]]])
                    .is_valid())
                progress = true;
            else
                still.push_back(t);
        }
        pending.swap(still);
    }
    // What still fails sits at non-manifold edges of the main surface. Those faces get their own
    // copies of the vertices, shared among themselves, so connected ones form a separate patch
    // that can still be decimated; a face that cannot join even that stays loose and locked.
    std::unordered_map<uint32_t, Mesh::VertexHandle> patch_copy;
    auto copy_of = [&](uint32_t welded) {
        auto found = patch_copy.find(welded);
        if (found != patch_copy.end())
            return found->second;
        Mesh::Point p = mesh.point(handles[welded]); // a copy: add_vertex may move the points
        Mesh::VertexHandle h = mesh.add_vertex(p);
        importance.push_back(importance[welded]);
        patch_copy.emplace(welded, h);
        return h;
    };
    std::vector<uint32_t> loose;
    for (uint32_t t : pending) {
        const uint32_t *ix = &in->indices[3 * (size_t)t];
        Mesh::VertexHandle a = copy_of(out->welded_of[ix[0]]), b = copy_of(out->welded_of[ix[1]]),
                           c = copy_of(out->welded_of[ix[2]]);
        if (!mesh.add_face(a, b, c).is_valid())
            loose.push_back(t);
    }
    for (uint32_t t : loose) {
        const uint32_t *ix = &in->indices[3 * (size_t)t];
        Mesh::VertexHandle copy[3];
        for (int k = 0; k < 3; k++) {
            Mesh::Point p = mesh.point(handles[out->welded_of[ix[k]]]); // a copy, as above
            copy[k] = mesh.add_vertex(p);
            mesh.status(copy[k]).set_locked(true);
            importance.push_back(importance[out->welded_of[ix[k]]]);
        }
        mesh.add_face(copy[0], copy[1], copy[2]);
        out->faces_loose++;
        out->vertices_uncollapsible += 3;
    }
    out->faces_patched = (uint32_t)(pending.size() - loose.size());
    // A position used only by patched or loose faces keeps a vertex without faces: remove it
    // (it would never collapse, count against the budget, and be written out).
    uint32_t isolated = 0;
    for (auto v : mesh.vertices())
        if (mesh.is_isolated(v)) {
            mesh.status(v).set_deleted(true);
            isolated++;
        }
    out->vertices_welded = (uint32_t)mesh.n_vertices() - isolated;
}

} // namespace

extern "C" int decimate_mesh(const decimate_input *in, decimate_method method,
                             decimate_output *out)
{
    std::memset(out, 0, sizeof *out);
    if (method == DECIMATE_IMPORTANCE && !in->vertex_importance)
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': importance decimation without importance",
                         in->name);
    try {
        Mesh mesh;
        std::vector<double> importance;
        build_mesh(in, mesh, out, importance);
        size_t n = mesh.n_vertices();
        out->collapsed_into = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
        for (size_t v = 0; v < n; v++)
            out->collapsed_into[v] = (uint32_t)v;

        ReductionDecimater decimater(mesh);
        ModNormalLimitT<Mesh>::Handle normal_limit;
        ModHistoryT<Mesh>::Handle history;
        ModImportanceT<Mesh>::Handle importance_module;
        OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
        decimater.add(normal_limit);
        decimater.add(history);
        decimater.module(normal_limit)
            .set_max_angle(in->max_normal_angle > 0 ? in->max_normal_angle : 60.0);
        decimater.module(history).set_history(out->collapsed_into);
        if (method == DECIMATE_IMPORTANCE) {
            decimater.add(importance_module);
            for (auto v : mesh.vertices())
                decimater.module(importance_module).importance(v) = importance[v.idx()];
            decimater.set_importance(&decimater.module(importance_module));
        } else {
            decimater.add(quadric);
        }
        // OpenMesh accepts exactly one priority (non-binary) module and otherwise returns false
        // here without a word.
        if (!decimater.initialize()) {
            decimate_output_free(out);
            return error_set(IDMR_EXIT_FAILURE,
                             "mesh '%s': the OpenMesh decimater did not initialise (it needs "
                             "exactly one priority module)",
                             in->name);
        }
        // The target counts all vertices, the locked copies of loose faces included: the
        // collapsible surface gets what remains after them.
        out->collapses = (uint32_t)decimater.decimate_to(
            (size_t)std::min<uint64_t>(in->target_vertices, n), in->verify_heap != 0,
            in->reheap_removed_ring_only != 0, &out->heap_violations);

        // Compact and copy out (the history, collapsed_into, is in welded indices already).
        mesh.garbage_collection();
        out->mesh.vertex_count = (uint32_t)mesh.n_vertices();
        out->mesh.triangle_count = (uint32_t)mesh.n_faces();
        out->mesh.positions = (float *)xmalloc(3 * sizeof(float) * (mesh.n_vertices() + 1));
        out->mesh.indices = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (mesh.n_faces() + 1));
        for (auto v : mesh.vertices())
            for (int k = 0; k < 3; k++)
                out->mesh.positions[3 * (size_t)v.idx() + k] = mesh.point(v)[k];
        size_t corner = 0;
        for (auto f : mesh.faces())
            for (auto v : mesh.fv_range(f))
                out->mesh.indices[corner++] = (uint32_t)v.idx();
    } catch (const std::exception &e) {
        decimate_output_free(out);
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
    return 0;
}

extern "C" int decimate_measure(const decimate_input *in, uint32_t *vertices,
                                uint32_t *uncollapsible)
{
    decimate_output out;
    std::memset(&out, 0, sizeof out);
    try {
        Mesh mesh;
        std::vector<double> importance;
        build_mesh(in, mesh, &out, importance);
    } catch (const std::exception &e) {
        decimate_output_free(&out);
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
    *vertices = out.vertices_welded;
    *uncollapsible = out.vertices_uncollapsible;
    decimate_output_free(&out);
    return 0;
}

extern "C" long decimate_stock_quadric(const decimate_input *in)
{
    try {
        Mesh mesh;
        std::vector<Mesh::VertexHandle> handles(in->vertex_count);
        for (uint32_t v = 0; v < in->vertex_count; v++) {
            const float *p = &in->positions[3 * (size_t)v];
            handles[v] = mesh.add_vertex(Mesh::Point(p[0], p[1], p[2]));
        }
        for (uint32_t t = 0; t < in->triangle_count; t++) {
            const uint32_t *ix = &in->indices[3 * (size_t)t];
            mesh.add_face(handles[ix[0]], handles[ix[1]], handles[ix[2]]);
        }
        OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
        OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
        decimater.add(quadric);
        if (!decimater.initialize())
            return error_set(IDMR_EXIT_FAILURE, "mesh '%s': DecimaterT did not initialise",
                             in->name);
        decimater.decimate_to((size_t)in->target_vertices);
        mesh.garbage_collection();
        return (long)mesh.n_vertices();
    } catch (const std::exception &e) {
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
}

extern "C" void decimate_output_free(decimate_output *out)
{
    mesh_data_free(&out->mesh);
    std::free(out->collapsed_into);
    std::free(out->welded_of);
    std::memset(out, 0, sizeof *out);
}

extern "C" size_t decimate_many(const decimate_input *in, decimate_output *out, int *status,
                                char (*messages)[512], size_t count, decimate_method method,
                                unsigned int threads)
{
    std::vector<size_t> order(count);
    for (size_t i = 0; i < count; i++)
        order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return in[a].triangle_count > in[b].triangle_count;
    });
    std::atomic<size_t> next(0), failed(0);
    auto worker = [&]() {
        for (;;) {
            size_t k = next.fetch_add(1);
            if (k >= count)
                return;
            size_t i = order[k];
            status[i] = decimate_mesh(&in[i], method, &out[i]);
            if (status[i]) {
                failed++;
                if (messages)
                    std::snprintf(messages[i], sizeof messages[i], "%s", error_message());
            }
        }
    };
    if (threads < 1)
        threads = 1;
    std::vector<std::thread> pool;
    for (unsigned int t = 1; t < threads && t < count; t++)
        pool.emplace_back(worker);
    worker();
    for (auto &thread : pool)
        thread.join();
    return failed;
}
