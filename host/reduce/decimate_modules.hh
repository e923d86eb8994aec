// decimate_modules.hh — internal to the decimation files: our three OpenMesh decimater modules
// (the semantics are in decimate.h).
//
//   ModImportanceT   priority (non-binary): a collapse of v0 costs the importance of v0's one-ring,
//                    centre included; after it the kept vertex v1 holds v0's importance as well
//   ModWeightedQuadricT
//                    priority: the Garland–Heckbert quadric error of moving v0 onto v1, each
//                    face's plane weighted by its area × (its importance + a floor), each open
//                    boundary edge holding a plane through it across its face (so openings keep
//                    their outline), and where the mesh has texture coordinates or normals,
//                    their error under the same weights (AttributeQuadrics); v1 takes v0's
//                    quadric
//   ModNormalLimitT  binary: no remaining face around v0 may turn by more than the limit or become
//                    degenerate
//   ModBoundaryLockT binary (combined only): a boundary vertex goes only where the outline stays
//                    within 1 % of its length
//   ModHistoryT      binary, always legal: records, per removed vertex, the vertex it went into
//
// OpenMesh's decimater accepts exactly one priority module; decimate.cc adds ModImportanceT,
// ModWeightedQuadricT or OpenMesh's ModQuadricT, never two, and checks initialize().
#ifndef IDMR_DECIMATE_MODULES_HH
#define IDMR_DECIMATE_MODULES_HH

#include <OpenMesh/Core/Utils/vector_traits.hh>
#include <OpenMesh/Core/Geometry/QuadricT.hh>
#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

extern "C" {
#include "core/error.h"
#include "reduce/decimate.h"
}

#include "reduce/decimate_attributes.hh"

namespace idmr_decimate {

// Non-binary: priority = importance of the vertex and its one-ring; the kept vertex inherits the
// removed one's importance.
template <class MeshT> class ModImportanceT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModImportanceT, MeshT, Importance);
    explicit ModImportanceT(MeshT &mesh) : Base(mesh, false) { mesh.add_property(importance_); }
    ~ModImportanceT() override { Base::mesh().remove_property(importance_); }

    double &importance(typename MeshT::VertexHandle v)
    {
        return Base::mesh().property(importance_, v);
    }

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
        CHECK_FINITE(sum, "ring importance");
        return (float)std::min(sum, (double)FLT_MAX / 2);
    }

    void postprocess_collapse(const CollapseInfo &ci) override
    {
        importance(ci.v1) += importance(ci.v0);
    }

  private:
    OpenMesh::VPropHandleT<double> importance_;
};

// Non-binary: the importance-weighted quadric error of a collapse. Face f contributes its plane's
// quadric weighted by area(f) × (I(f) + floor), with I(f) the mean importance (per area) of its
// vertices and the floor a small share of the mesh's mean, so unseen faces still rank their
// collapses by geometry, last. An open boundary edge contributes the plane through it
// perpendicular to its face, weighted by boundary_weight × length² × (I(f) + floor): moving a
// boundary vertex off the outline costs as much as a fold, so holes and openings keep their shape.
// With attributes (set_attributes), each face's weight also goes to the attribute quadrics of its
// corners' ids, whose error joins the cost (decimate_attributes.hh, AttributeQuadrics).
template <class MeshT> class ModWeightedQuadricT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModWeightedQuadricT, MeshT, WeightedQuadric);
    typedef OpenMesh::Geometry::QuadricT<double> Quadric;
    typedef typename MeshT::VertexHandle VertexHandle;

    explicit ModWeightedQuadricT(MeshT &mesh)
        : Base(mesh, false), floor_share_(0.01), boundary_weight_(10.0)
    {
        mesh.add_property(quadric_);
        mesh.add_property(importance_);
    }
    ~ModWeightedQuadricT() override
    {
        Base::mesh().remove_property(quadric_);
        Base::mesh().remove_property(importance_);
    }

    double &importance(VertexHandle v) { return Base::mesh().property(importance_, v); }

    // The corners' attributes and their weights (decimate.h: uv_weight, normal_weight); without
    // a table, or with both weights 0, the cost is geometric only.
    void set_attributes(const AttributeTable *table, double uv_weight, double normal_weight)
    {
        table_ = table;
        uv_weight_ = uv_weight;
        normal_weight_ = normal_weight;
    }

    void initialize() override
    {
        MeshT &mesh = Base::mesh();
        for (auto v : mesh.vertices())
            quadric(v).clear();
        bool attributes = start_attribute_quadrics();
        double floor = importance_floor();
        for (auto f : mesh.faces()) {
            OpenMesh::Vec3d p[3];
            double face_importance = face_points(f, p) + floor;
            OpenMesh::Vec3d n = OpenMesh::cross(p[1] - p[0], p[2] - p[0]);
            double twice_area = n.norm();
            if (!(twice_area > 0))
                continue;
            n /= twice_area;
            Quadric plane(n[0], n[1], n[2], -OpenMesh::dot(n, p[0]));
            double weight = 0.5 * twice_area * face_importance;
            plane *= weight;
            for (auto v : mesh.fv_range(f))
                quadric(v) += plane;
            add_boundary_planes(f, n, face_importance);
            if (attributes) {
                const CornerSet &set = mesh.property(table_->corners, f);
                OpenMesh::Vec3d q[3];
                for (int k = 0; k < 3; k++)
                    q[k] = point(VertexHandle(set.vertex[k]));
                attribute_quadrics_.add_face(q, set.id, weight);
            }
        }
    }

    float collapse_priority(const CollapseInfo &ci) override
    {
        Quadric q = quadric(ci.v0);
        q += quadric(ci.v1);
        const typename MeshT::Point &p = ci.p1;
        OpenMesh::Vec3d p1(p[0], p[1], p[2]);
        double error = q(p1);
        if (attributes_weighted_) {
            ids_of(ci);
            for (size_t k = 0; k < from_.size(); k++) {
                error += attribute_quadrics_.error(from_[k], p1, to_[k]);
                if (std::find(to_.begin(), to_.begin() + k, to_[k]) == to_.begin() + k)
                    error += attribute_quadrics_.error(to_[k], p1, to_[k]);
            }
        }
        CHECK_FINITE(error, "weighted quadric error");
        return (float)std::min(std::max(error, 0.0), (double)FLT_MAX / 2);
    }

    void preprocess_collapse(const CollapseInfo &ci) override
    {
        if (attributes_weighted_)
            ids_of(ci);
    }

    void postprocess_collapse(const CollapseInfo &ci) override
    {
        quadric(ci.v1) += quadric(ci.v0);
        if (attributes_weighted_)
            for (size_t k = 0; k < from_.size(); k++)
                attribute_quadrics_.merge(from_[k], to_[k]);
    }

  private:
    // Sets up the attribute quadrics where the mesh has an attribute with a weight, a uv
    // difference of 1 counting as uv_weight × the mesh's extent (its bounding box's longest
    // side), a normal's as normal_weight × the extent. Returns whether it did.
    bool start_attribute_quadrics()
    {
        attributes_weighted_ = table_ && table_->present() &&
                               ((table_->uv_floats && uv_weight_ > 0) ||
                                (table_->normal_floats && normal_weight_ > 0));
        if (!attributes_weighted_)
            return false;
        MeshT &mesh = Base::mesh();
        OpenMesh::Vec3d low(DBL_MAX, DBL_MAX, DBL_MAX), high = -low;
        for (auto v : mesh.vertices()) {
            OpenMesh::Vec3d q = point(v);
            for (int k = 0; k < 3; k++) {
                low[k] = std::min(low[k], q[k]);
                high[k] = std::max(high[k], q[k]);
            }
        }
        OpenMesh::Vec3d size = high - low;
        double extent = std::max(size[0], std::max(size[1], size[2]));
        if (!(extent > 0) || !std::isfinite(extent))
            return attributes_weighted_ = false;
        attribute_quadrics_.reset(*table_, table_->values.size() / table_->stride(),
                                  uv_weight_ * extent, normal_weight_ * extent,
                                  (low + high) * 0.5);
        return true;
    }

    // The collapse's removed vertex's distinct attribute ids into from_, and each one's image at
    // the kept vertex into to_.
    void ids_of(const CollapseInfo &ci)
    {
        MeshT &mesh = Base::mesh();
        CollapseMapping mapping = collapse_mapping(mesh, *table_, ci);
        from_.clear();
        to_.clear();
        for (auto f : mesh.vf_range(ci.v0)) {
            uint32_t id = corner_id(mesh.property(table_->corners, f), ci.v0.idx());
            if (std::find(from_.begin(), from_.end(), id) != from_.end())
                continue;
            from_.push_back(id);
            to_.push_back(mapping.to(id));
        }
    }

    OpenMesh::Vec3d point(VertexHandle v)
    {
        const typename MeshT::Point &q = Base::mesh().point(v);
        return OpenMesh::Vec3d(q[0], q[1], q[2]);
    }

    Quadric &quadric(VertexHandle v) { return Base::mesh().property(quadric_, v); }

    // The face's corners into p[3]; returns its importance, the mean of its vertices'.
    double face_points(typename MeshT::FaceHandle f, OpenMesh::Vec3d p[3])
    {
        MeshT &mesh = Base::mesh();
        double sum = 0;
        int k = 0;
        for (auto v : mesh.fv_range(f)) {
            const typename MeshT::Point &q = mesh.point(v);
            p[k++] = OpenMesh::Vec3d(q[0], q[1], q[2]);
            sum += importance(v);
        }
        return sum / 3.0;
    }

    // floor_share_ of the area-weighted mean importance over the mesh (1 when it has none).
    double importance_floor()
    {
        MeshT &mesh = Base::mesh();
        double weighted = 0, area = 0;
        for (auto f : mesh.faces()) {
            OpenMesh::Vec3d p[3];
            double face_importance = face_points(f, p);
            double a = 0.5 * OpenMesh::cross(p[1] - p[0], p[2] - p[0]).norm();
            weighted += a * face_importance;
            area += a;
        }
        double mean = area > 0 ? weighted / area : 0;
        return mean > 0 && std::isfinite(mean) ? floor_share_ * mean : 1.0;
    }

    // For each edge of face f on an open boundary: the plane through it perpendicular to the
    // face (unit normal n), into the quadrics of its two vertices.
    void add_boundary_planes(typename MeshT::FaceHandle f, const OpenMesh::Vec3d &n,
                             double face_importance)
    {
        MeshT &mesh = Base::mesh();
        for (auto h : mesh.fh_range(f)) {
            if (!mesh.is_boundary(mesh.opposite_halfedge_handle(h)))
                continue;
            const typename MeshT::Point &a = mesh.point(mesh.from_vertex_handle(h));
            const typename MeshT::Point &b = mesh.point(mesh.to_vertex_handle(h));
            OpenMesh::Vec3d pa(a[0], a[1], a[2]), edge = OpenMesh::Vec3d(b[0], b[1], b[2]) - pa;
            OpenMesh::Vec3d across = OpenMesh::cross(edge, n);
            double length = across.norm();
            if (!(length > 0))
                continue;
            across /= length;
            Quadric plane(across[0], across[1], across[2], -OpenMesh::dot(across, pa));
            plane *= boundary_weight_ * edge.sqrnorm() * face_importance;
            quadric(mesh.from_vertex_handle(h)) += plane;
            quadric(mesh.to_vertex_handle(h)) += plane;
        }
    }

    double floor_share_, boundary_weight_;
    const AttributeTable *table_ = nullptr;
    double uv_weight_ = 0, normal_weight_ = 0;
    bool attributes_weighted_ = false;
    AttributeQuadrics attribute_quadrics_;
    std::vector<uint32_t> from_, to_; // ids_of()
    OpenMesh::VPropHandleT<Quadric> quadric_;
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
            OpenMesh::Vec3d before, after; // the face's normal now and with v0 moved to p1
            face_normals(mesh, f, ci, &before, &after);
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
    // Unnormalised normals of face f before and after the collapse, in double.
    static void face_normals(MeshT &mesh, typename MeshT::FaceHandle f, const CollapseInfo &ci,
                             OpenMesh::Vec3d *before, OpenMesh::Vec3d *after)
    {
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
        *before = OpenMesh::cross(b - a, c - a);
        *after = OpenMesh::cross(b2 - a2, c2 - a2);
    }

    double min_cos_;
};

// Binary: an open boundary keeps its outline. A boundary vertex v0 may only go into a boundary
// neighbour v1 (the legality test sees to that), which replaces the outline u - v0 - v1 (u its
// other boundary neighbour) by u - v1; the collapse is legal only if v0 lies within
// max_deviation × |u - v1| of that segment, so corners stay, straight or gently curved runs
// thin out (a circle keeps about 80 vertices at the default 1 %), and no hole closes or
// opening grows over: a wall keeps covering what it covered.
template <class MeshT> class ModBoundaryLockT : public OpenMesh::Decimater::ModBaseT<MeshT> {
  public:
    DECIMATING_MODULE(ModBoundaryLockT, MeshT, BoundaryLock);
    explicit ModBoundaryLockT(MeshT &mesh)
        : Base(mesh, true), max_deviation_(DECIMATE_BOUNDARY_TOLERANCE)
    {
    }

    // The limit as a share of the new edge's length; infinite: every collapse is legal.
    void set_max_deviation(double share) { max_deviation_ = share; }

    float collapse_priority(const CollapseInfo &ci) override
    {
        MeshT &mesh = Base::mesh();
        if (!mesh.is_boundary(ci.v0) || std::isinf(max_deviation_))
            return Base::LEGAL_COLLAPSE;
        typename MeshT::HalfedgeHandle out = mesh.halfedge_handle(ci.v0);
        if (!mesh.is_boundary(out))
            return Base::ILLEGAL_COLLAPSE; // not a simple boundary vertex: keep it
        typename MeshT::VertexHandle next = mesh.to_vertex_handle(out);
        typename MeshT::VertexHandle previous =
            mesh.from_vertex_handle(mesh.prev_halfedge_handle(out));
        typename MeshT::VertexHandle u = next == ci.v1 ? previous : next;
        if (u == ci.v1 || (next != ci.v1 && previous != ci.v1))
            return Base::ILLEGAL_COLLAPSE;
        OpenMesh::Vec3d a = point(u), b = point(ci.v1), p = point(ci.v0);
        OpenMesh::Vec3d chord = b - a;
        double length2 = chord.sqrnorm();
        double t = length2 > 0 ? std::min(1.0, std::max(0.0, OpenMesh::dot(p - a, chord) / length2))
                               : 0.0;
        double deviation2 = (p - (a + chord * t)).sqrnorm();
        return deviation2 <= max_deviation_ * max_deviation_ * length2 ? Base::LEGAL_COLLAPSE
                                                                        : Base::ILLEGAL_COLLAPSE;
    }

  private:
    OpenMesh::Vec3d point(typename MeshT::VertexHandle v)
    {
        const typename MeshT::Point &q = Base::mesh().point(v);
        return OpenMesh::Vec3d(q[0], q[1], q[2]);
    }

    double max_deviation_;
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

} // namespace idmr_decimate

#endif
