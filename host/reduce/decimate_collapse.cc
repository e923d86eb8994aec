// decimate_collapse.cc — our collapse loop (see decimate_collapse.hh for the heap, decimate.h for
// why the loop is ours): the legality test, the best collapse of a vertex, the heap and the loop.
#include "reduce/decimate_collapse.hh"

#include <algorithm>

namespace idmr_decimate {

// The legality test of BaseDecimaterT::is_collapse_legal, with our own topology check in place
// of OpenMesh's TriConnectivity::is_collapse_ok (Debian's library spends a third of the
// decimation there on property type-name checks). The conditions: the link condition (the
// one-rings of v0 and v1 share exactly the opposite vertices vl, vr), no triangle whose other
// two edges are both boundary, a boundary vertex only into a boundary vertex along a boundary
// edge, no collapse that leaves two valence-3 neighbours joined, and v0 keeps at least two faces.
bool ReductionDecimater::collapse_legal(const CollapseInfo &ci)
{
    Mesh::VertexHandle v0 = ci.v0, v1 = ci.v1;
    if (mesh_.status(v0).locked() || mesh_.status(v0).deleted() || mesh_.status(v1).deleted() ||
        mesh_.status(mesh_.edge_handle(ci.v0v1)).deleted())
        return false;
    Mesh::HalfedgeHandle v0v1 = ci.v0v1, v1v0 = ci.v1v0;
    Mesh::VertexHandle vl, vr;
    if (!opposite_vertices(ci, &vl, &vr))
        return false;
    bool b0 = mesh_.is_boundary(v0), b1 = mesh_.is_boundary(v1);
    if (b0 && b1 && !mesh_.is_boundary(v0v1) && !mesh_.is_boundary(v1v0))
        return false;
    if (!rings_share_only(v0, v1, vl, vr))
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

// The vertices opposite the edge in its two triangles (invalid on a boundary side). False when
// a triangle's other two edges are both boundary (collapsing would leave a dangling edge) or
// both sides have the same opposite vertex.
bool ReductionDecimater::opposite_vertices(const CollapseInfo &ci, Mesh::VertexHandle *vl,
                                           Mesh::VertexHandle *vr)
{
    auto side = [&](Mesh::HalfedgeHandle h, Mesh::VertexHandle *opposite) {
        Mesh::HalfedgeHandle h1 = mesh_.next_halfedge_handle(h);
        Mesh::HalfedgeHandle h2 = mesh_.next_halfedge_handle(h1);
        *opposite = mesh_.to_vertex_handle(h1);
        return mesh_.is_boundary(mesh_.opposite_halfedge_handle(h1)) &&
               mesh_.is_boundary(mesh_.opposite_halfedge_handle(h2));
    };
    if (!mesh_.is_boundary(ci.v0v1) && side(ci.v0v1, vl))
        return false;
    if (!mesh_.is_boundary(ci.v1v0) && side(ci.v1v0, vr))
        return false;
    return *vl != *vr;
}

// The link condition: the one-rings of v0 and v1 share no vertex but vl and vr.
bool ReductionDecimater::rings_share_only(Mesh::VertexHandle v0, Mesh::VertexHandle v1,
                                          Mesh::VertexHandle vl, Mesh::VertexHandle vr)
{
    ring_.clear();
    for (auto w : mesh_.vv_range(v1))
        ring_.push_back(w);
    for (auto w : mesh_.vv_range(v0))
        if (w != vl && w != vr && std::find(ring_.begin(), ring_.end(), w) != ring_.end())
            return false;
    return true;
}

// The best collapse of v: least priority, then least important target, then the target closest
// to its importance source.
bool ReductionDecimater::best_collapse(Mesh::VertexHandle v, Entry *entry,
                                       Mesh::HalfedgeHandle *target)
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
        Mesh::VertexHandle to = mesh_.to_vertex_handle(h);
        Entry candidate{priority, distance(v), 0.0, distance(to), v.idx(), 0};
        if (!found || entry->operator>(candidate)) {
            *entry = candidate;
            *target = h;
            found = true;
        }
    }
    return found;
}

// With the importance module every collapse of v has the same priority (v's ring sum), so the
// best is the first legal one in order of target importance (then of the target's distance from
// its importance source): no need to test them all.
bool ReductionDecimater::least_important_collapse(Mesh::VertexHandle v, Entry *entry,
                                                  Mesh::HalfedgeHandle *target)
{
    candidates_.clear();
    for (auto h : mesh_.voh_range(v)) {
        Mesh::VertexHandle to = mesh_.to_vertex_handle(h);
        candidates_.push_back(Candidate{importance_->importance(to), distance(to), h});
    }
    std::sort(candidates_.begin(), candidates_.end(), [](const Candidate &a, const Candidate &b) {
        if (a.importance != b.importance)
            return a.importance < b.importance;
        if (a.distance != b.distance)
            return a.distance < b.distance;
        return a.halfedge < b.halfedge;
    });
    for (const auto &candidate : candidates_) {
        CollapseInfo ci(mesh_, candidate.halfedge);
        if (!collapse_legal(ci))
            continue;
        float priority = collapse_priority(ci);
        if (priority < 0)
            continue;
        *entry = Entry{priority, distance(v), candidate.importance, candidate.distance, v.idx(),
                       0};
        *target = candidate.halfedge;
        return true;
    }
    return false;
}

// Re-scores v: a new heap entry for its best collapse, or none (it is no longer live).
void ReductionDecimater::heap_vertex(Mesh::VertexHandle v)
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

// The wedges of the vertices a collapse changes: v1, vl, vr (they lose corners), and v0 when
// with_v0 (before the collapse).
size_t ReductionDecimater::wedges_around(const CollapseInfo &ci, bool with_v0)
{
    size_t sum = 0;
    Mesh::VertexHandle touched[4] = {ci.v0, ci.v1, ci.vl, ci.vr};
    for (int k = with_v0 ? 0 : 1; k < 4; k++)
        if (touched[k].is_valid())
            sum += wedge_count(mesh_, *attributes_, touched[k], scratch_);
    return sum;
}

// Resets the per-vertex records and scores every vertex; returns how many are not deleted,
// counted once per wedge.
size_t ReductionDecimater::heap_all_vertices()
{
    size_t n = mesh_.n_vertices();
    version_.assign(n, 0);
    target_.assign(n, Mesh::HalfedgeHandle());
    live_.assign(n, false);
    stored_.assign(n, Entry{0, 0, 0, 0, 0, 0});
    size_t alive = 0;
    for (auto v : mesh_.vertices())
        if (!mesh_.status(v).deleted()) {
            alive += attributes_ ? wedge_count(mesh_, *attributes_, v, scratch_) : 1;
            heap_vertex(v);
        }
    return alive;
}

// After a collapse: the kept vertex and its whole new one-ring (its importance changed their
// ring sums), or, as OpenMesh's DecimaterT does, only the removed vertex's former ring.
void ReductionDecimater::reheap_after_collapse(const CollapseInfo &ci, bool removed_ring_only,
                                               const std::vector<Mesh::VertexHandle> &removed_ring)
{
    if (removed_ring_only) {
        for (auto w : removed_ring)
            heap_vertex(w);
        return;
    }
    heap_vertex(ci.v1);
    for (auto w : mesh_.vv_range(ci.v1))
        heap_vertex(w);
}

// Heap entries that a fresh evaluation would score differently (tests).
uint64_t ReductionDecimater::count_stale()
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

size_t ReductionDecimater::decimate_to(size_t target_vertices, bool verify, bool removed_ring_only,
                                       uint64_t *violations)
{
    size_t alive = heap_all_vertices();
    size_t collapses = 0;
    std::vector<Mesh::VertexHandle> removed_ring;
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
        removed_ring.clear();
        for (auto w : mesh_.vv_range(ci.v0))
            removed_ring.push_back(w);
        size_t before = attributes_ ? wedges_around(ci, true) : 1;
        preprocess_collapse(ci);
        mesh_.collapse(h);
        postprocess_collapse(ci);
        collapses++;
        alive -= before - (attributes_ ? wedges_around(ci, false) : 0);
        reheap_after_collapse(ci, removed_ring_only, removed_ring);
        if (verify)
            *violations += count_stale();
    }
    return collapses;
}

} // namespace idmr_decimate
