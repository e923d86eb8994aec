// decimate_modules.hh — internal to the decimation files: our three OpenMesh decimater modules
// (the semantics are in decimate.h).
//
//   ModImportanceT   priority (non-binary): a collapse of v0 costs the importance of v0's one-ring,
//                    centre included; after it the kept vertex v1 holds v0's importance as well
//   ModNormalLimitT  binary: no remaining face around v0 may turn by more than the limit or become
//                    degenerate
//   ModHistoryT      binary, always legal: records, per removed vertex, the vertex it went into
//
// OpenMesh's decimater accepts exactly one priority module; decimate.cc adds ModImportanceT or
// OpenMesh's ModQuadricT, never both, and checks initialize().
#ifndef IDMR_DECIMATE_MODULES_HH
#define IDMR_DECIMATE_MODULES_HH

#include <OpenMesh/Tools/Decimater/ModBaseT.hh>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>

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
