// decimate_collapse.hh — internal to the decimation files: our collapse loop (decimate.h says
// why it is ours), a decimater on OpenMesh's BaseDecimaterT, which runs the modules, with a heap
// of its own.
//
// The heap holds one entry per vertex that has a legal collapse: its priority (the modules'
// collapse_priority of its best collapse), the vertex's and its target's distance from their
// importance source (remapped importance, decimate.h: vertex_distance; 0 without it), the
// importance of that collapse's target and a version. Ties in priority go to the vertex farthest
// from its source, then to the least important target, then to the target closest to its
// source, then to the lower vertex index. Re-scoring a vertex
// pushes a new entry with a new version; popped entries whose version is not the vertex's latest
// are stale and skipped. Per vertex: version_, target_ (the halfedge of its best collapse),
// live_ (has a current entry) and stored_ (that entry, for the heap check of the tests).
#ifndef IDMR_DECIMATE_COLLAPSE_HH
#define IDMR_DECIMATE_COLLAPSE_HH

#include <OpenMesh/Tools/Decimater/BaseDecimaterT.hh>

#include <cstdint>
#include <queue>
#include <utility>
#include <vector>

#include "reduce/decimate_modules.hh"
#include "reduce/decimate_openmesh.hh"

namespace idmr_decimate {

class ReductionDecimater : public OpenMesh::Decimater::BaseDecimaterT<Mesh> {
  public:
    typedef OpenMesh::Decimater::BaseDecimaterT<Mesh> Base;
    explicit ReductionDecimater(Mesh &mesh)
        : Base(mesh), mesh_(mesh), importance_(nullptr), attributes_(nullptr),
          distance_(nullptr)
    {
    }

    // Tie-break source: the importance module, or none.
    void set_importance(ModImportanceT<Mesh> *importance) { importance_ = importance; }

    // The corners' attributes, when the mesh has them: vertices are then counted once per wedge.
    void set_attributes(const AttributeTable *attributes) { attributes_ = attributes; }

    // Per mesh vertex, the collapses between it and its importance source (decimate.h,
    // vertex_distance), for the ties; none: all 0.
    void set_distances(const std::vector<uint32_t> *distance) { distance_ = distance; }

    // Collapses until target_vertices are left (counted once per wedge) or no legal collapse
    // remains; returns the number of collapses. verify: after every collapse add the stale heap entries to *violations
    // (tests); removed_ring_only: re-score as OpenMesh's DecimaterT does (tests).
    size_t decimate_to(size_t target_vertices, bool verify, bool removed_ring_only,
                       uint64_t *violations);

  private:
    struct Entry {
        float priority;
        uint32_t distance;
        double target_importance;
        uint32_t target_distance;
        int vertex;
        unsigned version;
        bool operator>(const Entry &o) const
        {
            if (priority != o.priority)
                return priority > o.priority;
            if (distance != o.distance)
                return distance < o.distance;
            if (target_importance != o.target_importance)
                return target_importance > o.target_importance;
            if (target_distance != o.target_distance)
                return target_distance > o.target_distance;
            return vertex > o.vertex;
        }
    };

    uint32_t distance(Mesh::VertexHandle v) const
    {
        return distance_ ? (*distance_)[v.idx()] : 0;
    }

    bool collapse_legal(const CollapseInfo &ci);
    bool opposite_vertices(const CollapseInfo &ci, Mesh::VertexHandle *vl, Mesh::VertexHandle *vr);
    bool rings_share_only(Mesh::VertexHandle v0, Mesh::VertexHandle v1, Mesh::VertexHandle vl,
                          Mesh::VertexHandle vr);
    bool best_collapse(Mesh::VertexHandle v, Entry *entry, Mesh::HalfedgeHandle *target);
    bool least_important_collapse(Mesh::VertexHandle v, Entry *entry, Mesh::HalfedgeHandle *target);
    void heap_vertex(Mesh::VertexHandle v);
    size_t heap_all_vertices();
    void reheap_after_collapse(const CollapseInfo &ci, bool removed_ring_only,
                               const std::vector<Mesh::VertexHandle> &removed_ring);
    uint64_t count_stale();
    size_t wedges_around(const CollapseInfo &ci, bool with_v0);

    Mesh &mesh_;
    ModImportanceT<Mesh> *importance_;
    const AttributeTable *attributes_;
    const std::vector<uint32_t> *distance_;
    std::vector<uint32_t> scratch_;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
    std::vector<unsigned> version_;
    std::vector<Mesh::HalfedgeHandle> target_;
    std::vector<bool> live_;
    std::vector<Entry> stored_;
    struct Candidate {
        double importance;
        uint32_t distance;
        Mesh::HalfedgeHandle halfedge;
    };
    std::vector<Candidate> candidates_;
    std::vector<Mesh::VertexHandle> ring_;
};

} // namespace idmr_decimate

#endif
