// decimate_attributes.hh — internal to the decimation files: texture coordinates and shading
// normals per triangle corner, kept through the collapses (decimate.h, "Attributes").
//
// An attribute set (uv and/or normal, as the input has them) gets an id: input vertices at one
// welded position with bit-identical attributes share it. Each face stores, per corner, the
// corner's vertex and its attribute id (CornerSet, a face property: OpenMesh's edge collapse
// re-links halfedges of the removed triangles into their neighbours, so halfedge properties
// would move between faces; faces keep their handles). A vertex's wedges are the distinct ids
// among its corners.
//
// ModAttributesT (binary) allows the collapses that keep the seams (as decimate.h says) and leave
// every moved triangle's corner normals on its front side, and after a collapse moves the
// removed vertex's corners onto the kept vertex: a corner of the wedge the left triangle had at
// v0 takes that triangle's id at v1, one of the right triangle's wedge the right one's, any
// other (seams free only) the left's, or the right's on a boundary.
#ifndef IDMR_DECIMATE_ATTRIBUTES_HH
#define IDMR_DECIMATE_ATTRIBUTES_HH

#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace idmr_decimate {

// One face's corners: the vertex (index) and attribute id of each.
struct CornerSet {
    int vertex[3];
    uint32_t id[3];
};

// The attribute sets of a mesh: `stride` floats per id (uv first, then the normal).
struct AttributeTable {
    int uv_floats = 0;     // 2 when the input has texture coordinates
    int normal_floats = 0; // 3 when it has normals
    std::vector<float> values;
    OpenMesh::FPropHandleT<CornerSet> corners; // valid when the input has attributes

    int stride() const { return uv_floats + normal_floats; }
    bool present() const { return stride() > 0; }
};

// The attribute id of a face's corner at `vertex` (one of the face's vertices).
inline uint32_t corner_id(const CornerSet &set, int vertex)
{
    for (int k = 0; k < 3; k++)
        if (set.vertex[k] == vertex)
            return set.id[k];
    return set.id[0]; // not reached for a face around `vertex`
}

// The number of v's wedges: distinct attribute ids among its corners; 1 without attributes or
// faces. `scratch` is working space.
template <class MeshT>
unsigned wedge_count(MeshT &mesh, const AttributeTable &table, typename MeshT::VertexHandle v,
                     std::vector<uint32_t> &scratch)
{
    if (!table.present())
        return 1;
    scratch.clear();
    for (auto f : mesh.vf_range(v)) {
        uint32_t id = corner_id(mesh.property(table.corners, f), v.idx());
        if (std::find(scratch.begin(), scratch.end(), id) == scratch.end())
            scratch.push_back(id);
    }
    return scratch.empty() ? 1u : (unsigned)scratch.size();
}

// Binary: the seam rules of decimate.h; keeps the corners' ids through each collapse.
template <class MeshT> class ModAttributesT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModAttributesT, MeshT, Attributes);
    typedef typename MeshT::VertexHandle VertexHandle;
    typedef typename MeshT::FaceHandle FaceHandle;

    explicit ModAttributesT(MeshT &mesh) : Base(mesh, true), table_(nullptr), seams_free_(false)
    {
    }

    void set_table(const AttributeTable *table) { table_ = table; }
    void set_seams_free(bool free) { seams_free_ = free; }

    unsigned wedges(VertexHandle v) { return wedge_count(Base::mesh(), *table_, v, wedges_); }

    float collapse_priority(const CollapseInfo &ci) override
    {
        if (!seams_kept(ci) || !normals_face_out(ci))
            return Base::ILLEGAL_COLLAPSE;
        return Base::LEGAL_COLLAPSE;
    }

    void preprocess_collapse(const CollapseInfo &ci) override
    {
        mapping_ = mapping_of(ci);
        moved_.clear();
        for (auto f : Base::mesh().vf_range(ci.v0))
            if (f != ci.fl && f != ci.fr)
                moved_.push_back(f);
    }

    void postprocess_collapse(const CollapseInfo &ci) override
    {
        int v0 = ci.v0.idx(), v1 = ci.v1.idx();
        for (FaceHandle f : moved_) {
            CornerSet &set = corners(f);
            for (int k = 0; k < 3; k++) {
                if (set.vertex[k] != v0)
                    continue;
                set.vertex[k] = v1;
                set.id[k] = mapping_.to(set.id[k]);
            }
        }
    }

  private:
    // Where a collapse sends the removed vertex's corners: the left triangle's wedge at v0 to
    // its id at v1, the right one's likewise, any other to the left's (the right's on a
    // boundary).
    struct Mapping {
        uint32_t left_from, left_to, right_from, right_to, nearest_to;
        uint32_t to(uint32_t id) const
        {
            return id == left_from ? left_to : id == right_from ? right_to : nearest_to;
        }
    };

    Mapping mapping_of(const CollapseInfo &ci)
    {
        int v0 = ci.v0.idx(), v1 = ci.v1.idx();
        FaceHandle side = ci.fl.is_valid() ? ci.fl : ci.fr;
        Mapping m;
        m.left_from = m.right_from = UINT32_MAX;
        m.nearest_to = side.is_valid() ? corner_id(corners(side), v1) : 0;
        m.left_to = m.right_to = m.nearest_to;
        if (ci.fl.is_valid()) {
            m.left_from = corner_id(corners(ci.fl), v0);
            m.left_to = corner_id(corners(ci.fl), v1);
        }
        if (ci.fr.is_valid()) {
            m.right_from = corner_id(corners(ci.fr), v0);
            m.right_to = corner_id(corners(ci.fr), v1);
        }
        return m;
    }

    // The seam rules of decimate.h (always true with seams free).
    bool seams_kept(const CollapseInfo &ci)
    {
        if (seams_free_)
            return true;
        unsigned wedges = this->wedges(ci.v0);
        bool left = ci.fl.is_valid(), right = ci.fr.is_valid();
        if (wedges == 1) {
            // Both triangles of the edge must share the wedge of v1 the corners go to.
            if (left && right &&
                corner_id(corners(ci.fl), ci.v1.idx()) != corner_id(corners(ci.fr), ci.v1.idx()))
                return false;
            return true;
        }
        // Two wedges: only along the seam (it crosses the edge at both ends), and only where
        // the seam is one simple run through v0 (two changes of id around it).
        if (wedges != 2 || !left || !right || seam_changes(ci.v0) != 2)
            return false;
        if (corner_id(corners(ci.fl), ci.v0.idx()) == corner_id(corners(ci.fr), ci.v0.idx()) ||
            corner_id(corners(ci.fl), ci.v1.idx()) == corner_id(corners(ci.fr), ci.v1.idx()))
            return false;
        return true;
    }

    // With normals: every triangle the collapse moves keeps each corner's normal on its front
    // side (a positive dot with its geometric normal), so the interpolated shading normal never
    // vanishes or turns behind the surface (where a renderer would normalise a zero vector).
    bool normals_face_out(const CollapseInfo &ci)
    {
        if (!table_->normal_floats)
            return true;
        MeshT &mesh = Base::mesh();
        Mapping mapping = mapping_of(ci);
        for (auto f : mesh.vf_range(ci.v0)) {
            if (f == ci.fl || f == ci.fr)
                continue;
            const CornerSet &set = corners(f);
            OpenMesh::Vec3d p[3];
            uint32_t id[3];
            for (int k = 0; k < 3; k++) {
                bool moved = set.vertex[k] == ci.v0.idx();
                const typename MeshT::Point &q =
                    moved ? ci.p1 : mesh.point(VertexHandle(set.vertex[k]));
                p[k] = OpenMesh::Vec3d(q[0], q[1], q[2]);
                id[k] = moved ? mapping.to(set.id[k]) : set.id[k];
            }
            OpenMesh::Vec3d g = OpenMesh::cross(p[1] - p[0], p[2] - p[0]);
            for (int k = 0; k < 3; k++) {
                const float *n =
                    &table_->values[(size_t)table_->stride() * id[k] + table_->uv_floats];
                if (!(g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0))
                    return false;
            }
        }
        return true;
    }

    CornerSet &corners(FaceHandle f) { return Base::mesh().property(table_->corners, f); }

    // How often the attribute id changes between faces that follow each other around v
    // (cyclically for an inner vertex).
    unsigned seam_changes(VertexHandle v)
    {
        MeshT &mesh = Base::mesh();
        unsigned changes = 0;
        bool first = true, inner = !mesh.is_boundary(v);
        uint32_t previous = 0, start = 0;
        // Around a boundary vertex the faces run from the boundary halfedge's far side on.
        for (auto h : mesh.voh_range(v)) {
            FaceHandle f = mesh.face_handle(h);
            if (!f.is_valid())
                continue;
            uint32_t id = corner_id(corners(f), v.idx());
            if (first)
                start = id;
            else if (id != previous)
                changes++;
            previous = id;
            first = false;
        }
        if (inner && !first && previous != start)
            changes++;
        return changes;
    }

    const AttributeTable *table_;
    bool seams_free_;
    std::vector<uint32_t> wedges_;
    std::vector<FaceHandle> moved_;
    Mapping mapping_;
};

} // namespace idmr_decimate

#endif
