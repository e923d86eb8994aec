// decimate_openmesh.hh — internal to the decimation files (decimate*.cc; the C API is decimate.h):
// the OpenMesh mesh type they share and the welded rebuild that turns a decimate_input into one.
//
// Mesh: a triangle mesh with status bits on vertices, edges and faces (deleted, locked) and
// previous-halfedge links, as OpenMesh's decimater needs. Vertex i of the rebuilt mesh is welded
// vertex i (decimate_output's welded_of and collapsed_into are in these indices); the patch and
// loose-face copies follow the welded vertices.
#ifndef IDMR_DECIMATE_OPENMESH_HH
#define IDMR_DECIMATE_OPENMESH_HH

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/CollapseInfoT.hh>

#include <vector>

#include "reduce/decimate_attributes.hh"

extern "C" {
#include "reduce/decimate.h"
#include "reduce/weld.h"
}

namespace idmr_decimate {

struct Traits : public OpenMesh::DefaultTraits {
    VertexAttributes(OpenMesh::Attributes::Status);
    EdgeAttributes(OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Status);
    HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
};
typedef OpenMesh::TriMesh_ArrayKernelT<Traits> Mesh;
typedef OpenMesh::Decimater::CollapseInfoT<Mesh> CollapseInfo;

// Builds `mesh` from `in` (decimate_weld.cc): welded vertices, faces attached with retries, the
// rest patched or loose and locked. Fills out->welded_of and the welding counts of `out`
// (vertices_welded, vertices_uncollapsible, faces_patched, faces_loose, faces_dropped), and
// `importance` per mesh vertex (the largest of the input vertices welded into it), and, where the
// input has texture coordinates or normals, `attributes` (its table and the faces' corners).
// face_triangle (may be null) gets, per mesh face in index order, the input triangle it was made
// from. Throws what OpenMesh throws.
void build_welded_mesh(const decimate_input *in, Mesh &mesh, decimate_output *out,
                       std::vector<double> &importance, AttributeTable &attributes,
                       std::vector<uint32_t> *face_triangle = nullptr);

// The output vertices' texture coordinates and normals from an attribute table (uv_floats +
// normal_floats per id, uv first): output vertex i takes id_of[i]'s.
void copy_attribute_values(int uv_floats, int normal_floats, const float *values,
                           const std::vector<uint32_t> &id_of, mesh_data *out);

// decimate_mesh() and decimate_reference_mesh() around their work (`decimate`): the output
// cleared, importance required by the methods that read it, and what OpenMesh throws turned
// into the error path.
int decimate_guarded(const decimate_input *in, decimate_method method, decimate_output *out,
                     int (*decimate)(const decimate_input *, decimate_method, decimate_output *));

// The OpenMesh rebuild's input: the flat weld's kept triangles, turned as it turned them, in its
// order (its twins and the triangles that weld into zero area left out), over the input's
// vertices.
std::vector<uint32_t> repaired_indices(const decimate_input *in, const weld_result &flat);

// Per mesh vertex (n of them), the least vertex_distance of the input vertices welded into it;
// empty when the input has no distances.
std::vector<uint32_t> welded_distances(const decimate_input *in, const decimate_output *out,
                                       size_t n);

} // namespace idmr_decimate

#endif
