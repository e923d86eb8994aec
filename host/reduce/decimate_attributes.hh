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
// AttributeQuadrics holds the combined method's attribute error term (decimate.h, "The
// attribute error term"), which ModWeightedQuadricT adds to its cost.
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

// Where a collapse of v0 into v1 sends v0's corners: the left triangle's wedge at v0 to its id at
// v1, the right one's likewise, any other to the left's (the right's on a boundary).
struct CollapseMapping {
    uint32_t left_from, left_to, right_from, right_to, nearest_to;
    uint32_t to(uint32_t id) const
    {
        return id == left_from ? left_to : id == right_from ? right_to : nearest_to;
    }
};

template <class MeshT>
CollapseMapping collapse_mapping(MeshT &mesh, const AttributeTable &table,
                                 const OpenMesh::Decimater::CollapseInfoT<MeshT> &ci)
{
    int v0 = ci.v0.idx(), v1 = ci.v1.idx();
    typename MeshT::FaceHandle side = ci.fl.is_valid() ? ci.fl : ci.fr;
    CollapseMapping m;
    m.left_from = m.right_from = UINT32_MAX;
    m.nearest_to = side.is_valid() ? corner_id(mesh.property(table.corners, side), v1) : 0;
    m.left_to = m.right_to = m.nearest_to;
    if (ci.fl.is_valid()) {
        m.left_from = corner_id(mesh.property(table.corners, ci.fl), v0);
        m.left_to = corner_id(mesh.property(table.corners, ci.fl), v1);
    }
    if (ci.fr.is_valid()) {
        m.right_from = corner_id(mesh.property(table.corners, ci.fr), v0);
        m.right_to = corner_id(mesh.property(table.corners, ci.fr), v1);
    }
    return m;
}

// The attribute error term of the combined method's collapse cost (decimate.h, "Attributes"):
// per attribute set (id), the quadric in position p and attribute values s of
//   E(p, s) = sum over the faces f with a corner of that id: w_f sum over channels c of
//             (g_fc . p + d_fc - s_c)^2,
// where g_fc . p + d_fc is the face's own linear interpolation of channel c, extended over its
// plane (Hoppe's attribute quadrics). Channels are scaled into lengths first (uv_scale and
// normal_scale per unit of attribute), so E adds to the geometric quadric's squared distances
// under the same face weights w_f. A collapse of v0 into v1 costs, for each of v0's ids W and
// its image T at v1, E_W at (p1, s_T), plus E_T at (p1, s_T) once per T: how far the kept
// corner's attributes lie from what the faces that met there showed; afterwards T takes W's
// quadric. Stored per id as its terms (the 3 × 3 matrix, per channel the sum of w g, the sum of
// w, the sum of w d g, per channel the sum of w d, the sum of w d²); positions relative to the
// mesh's centre, against cancellation.
class AttributeQuadrics {
  public:
    void reset(const AttributeTable &table, size_t ids, double uv_scale, double normal_scale,
               const OpenMesh::Vec3d &centre)
    {
        channels_ = table.stride();
        uv_floats_ = table.uv_floats;
        uv_scale_ = uv_scale;
        normal_scale_ = normal_scale;
        centre_ = centre;
        values_ = &table.values;
        terms_.assign(ids * stride(), 0.0);
    }

    // Adds the face with corners at p[k] and ids id[k], weighted w.
    void add_face(const OpenMesh::Vec3d p[3], const uint32_t id[3], double w)
    {
        OpenMesh::Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0], n = OpenMesh::cross(e1, e2);
        double n2 = n.sqrnorm();
        if (!(n2 > 0) || !(w > 0))
            return;
        // The dual basis of (e1, e2) in the face's plane: g = (s1 - s0) e1* + (s2 - s0) e2*.
        OpenMesh::Vec3d dual1 = OpenMesh::cross(e2, n) / n2, dual2 = OpenMesh::cross(n, e1) / n2;
        OpenMesh::Vec3d p0 = p[0] - centre_;
        double face[max_stride] = {0};
        Terms t = terms(face);
        *t.weight = w;
        for (int ch = 0; ch < channels_; ch++) {
            double s0 = value(id[0], ch), s1 = value(id[1], ch), s2 = value(id[2], ch);
            OpenMesh::Vec3d g = dual1 * (s1 - s0) + dual2 * (s2 - s0);
            double d = s0 - OpenMesh::dot(g, p0);
            for (int i = 0, k = 0; i < 3; i++)
                for (int j = i; j < 3; j++)
                    t.matrix[k++] += w * g[i] * g[j];
            for (int k = 0; k < 3; k++) {
                t.gradient[3 * ch + k] += w * g[k];
                t.linear[k] += w * d * g[k];
            }
            t.offset[ch] += w * d;
            *t.constant += w * d * d;
        }
        for (int k = 0; k < 3; k++) {
            double *q = &terms_[(size_t)id[k] * stride()];
            for (int i = 0; i < stride(); i++)
                q[i] += face[i];
        }
    }

    // E_id at `position` with the attribute values of id `at`.
    double error(uint32_t id, const OpenMesh::Vec3d &position, uint32_t at)
    {
        Terms t = terms(&terms_[(size_t)id * stride()]);
        OpenMesh::Vec3d p = position - centre_;
        const double *m = t.matrix;
        double e = m[0] * p[0] * p[0] + m[3] * p[1] * p[1] + m[5] * p[2] * p[2] +
                   2 * (m[1] * p[0] * p[1] + m[2] * p[0] * p[2] + m[4] * p[1] * p[2]) +
                   2 * (t.linear[0] * p[0] + t.linear[1] * p[1] + t.linear[2] * p[2]) +
                   *t.constant;
        for (int ch = 0; ch < channels_; ch++) {
            const double *g = &t.gradient[3 * ch];
            double s = value(at, ch), gp = g[0] * p[0] + g[1] * p[1] + g[2] * p[2];
            e += *t.weight * s * s - 2 * s * gp - 2 * t.offset[ch] * s;
        }
        return e > 0 ? e : 0.0;
    }

    // `into` takes the quadric of `from`.
    void merge(uint32_t from, uint32_t into)
    {
        if (from == into)
            return;
        const double *f = &terms_[(size_t)from * stride()];
        double *t = &terms_[(size_t)into * stride()];
        for (int k = 0; k < stride(); k++)
            t[k] += f[k];
    }

  private:
    static const int max_channels = 5; // uv and normal
    static const int max_stride = 6 + 3 * max_channels + 1 + 3 + max_channels + 1;

    // One id's terms, laid out in this order.
    struct Terms {
        double *matrix;   // the upper triangle of sum w g g^T, row by row
        double *gradient; // per channel: sum w g
        double *weight;   // sum w
        double *linear;   // sum over channels of w d g
        double *offset;   // per channel: sum w d
        double *constant; // sum over channels of w d²
    };

    int stride() const { return 6 + 3 * channels_ + 1 + 3 + channels_ + 1; }

    Terms terms(double *q) const
    {
        Terms t;
        t.matrix = q;
        t.gradient = q + 6;
        t.weight = t.gradient + 3 * channels_;
        t.linear = t.weight + 1;
        t.offset = t.linear + 3;
        t.constant = t.offset + channels_;
        return t;
    }

    double value(uint32_t id, int channel) const
    {
        double v = (*values_)[(size_t)channels_ * id + channel];
        return v * (channel < uv_floats_ ? uv_scale_ : normal_scale_);
    }

    int channels_ = 0, uv_floats_ = 0;
    double uv_scale_ = 0, normal_scale_ = 0;
    OpenMesh::Vec3d centre_;
    const std::vector<float> *values_ = nullptr;
    std::vector<double> terms_;
};

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
    CollapseMapping mapping_of(const CollapseInfo &ci)
    {
        return collapse_mapping(Base::mesh(), *table_, ci);
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
        CollapseMapping mapping = mapping_of(ci);
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
    CollapseMapping mapping_;
};

} // namespace idmr_decimate

#endif
