// decimate_reference.cc — decimate_reference_mesh() (see decimate.h): the reference the collapse
// engine is tested against. The welded rebuild (decimate_weld.cc) of the flat weld's repaired
// triangles (weld.h: twins set aside, windings turned to agree), OpenMesh's decimater with our
// modules (decimate_modules.hh) and our heap-ordered collapse loop (decimate_collapse.cc), one
// collapse at a time, and the copy of the result into a decimate_output, turned faces turned
// back and twins repeated after the faces.
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>
#include <vector>

#include "reduce/decimate_collapse.hh"
#include "reduce/decimate_modules.hh"
#include "reduce/decimate_openmesh.hh"

extern "C" {
#include "core/error.h"
#include "reduce/weld.h"
}

using namespace idmr_decimate;

namespace {

// The module handles of one decimater: the normal limit and the history always, the attributes
// where the mesh has them, and one priority module: the importance, the quadric or the weighted
// quadric one (with the boundary lock).
struct Modules {
    ModNormalLimitT<Mesh>::Handle normal_limit;
    ModHistoryT<Mesh>::Handle history;
    ModAttributesT<Mesh>::Handle attributes;
    ModImportanceT<Mesh>::Handle importance;
    OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
    ModWeightedQuadricT<Mesh>::Handle weighted_quadric;
    ModBoundaryLockT<Mesh>::Handle boundary_lock;
};

// Adds and sets up the modules of `method`. Returns false when the decimater does not
// initialise: OpenMesh accepts exactly one priority (non-binary) module and otherwise returns
// false from initialize() without a word.
bool add_modules(ReductionDecimater &decimater, Modules &modules, Mesh &mesh,
                 decimate_method method, const decimate_input *in,
                 const std::vector<double> &importance, const AttributeTable &attributes,
                 uint32_t *collapsed_into)
{
    decimater.add(modules.normal_limit);
    decimater.add(modules.history);
    decimater.module(modules.normal_limit)
        .set_max_angle(in->max_normal_angle > 0 ? in->max_normal_angle : 60.0);
    decimater.module(modules.history).set_history(collapsed_into);
    if (attributes.present()) {
        decimater.add(modules.attributes);
        decimater.module(modules.attributes).set_table(&attributes);
        decimater.module(modules.attributes).set_seams_free(in->seams_free != 0);
        decimater.set_attributes(&attributes);
    }
    if (method == DECIMATE_IMPORTANCE) {
        decimater.add(modules.importance);
        for (auto v : mesh.vertices())
            decimater.module(modules.importance).importance(v) = importance[v.idx()];
        decimater.set_importance(&decimater.module(modules.importance));
    } else if (method == DECIMATE_COMBINED) {
        decimater.add(modules.weighted_quadric);
        decimater.add(modules.boundary_lock);
        decimater.module(modules.boundary_lock)
            .set_max_deviation(in->boundary_tolerance > 0 ? in->boundary_tolerance
                                                          : DECIMATE_BOUNDARY_TOLERANCE);
        for (auto v : mesh.vertices())
            decimater.module(modules.weighted_quadric).importance(v) = importance[v.idx()];
        decimater.module(modules.weighted_quadric)
            .set_attributes(&attributes, in->uv_weight, in->normal_weight);
    } else {
        decimater.add(modules.quadric);
    }
    return decimater.initialize(); // runs the modules' initialize(): importance is set by now
}

// The output's vertices with attributes: each mesh vertex once per wedge, in vertex order, its
// wedges in the order of its faces; `corner_out` gets, per face, the output vertex of each corner.
// The faces' corner sets name vertices by their index before garbage collection: old_index.
void split_wedges(Mesh &mesh, const AttributeTable &attributes,
                  const std::vector<uint32_t> &old_index,
                  std::vector<std::array<uint32_t, 3>> &corner_out, std::vector<uint32_t> &first_of,
                  std::vector<uint32_t> &vertex_of, std::vector<uint32_t> &id_of)
{
    corner_out.assign(mesh.n_faces(), {{0, 0, 0}});
    first_of.assign(mesh.n_vertices(), 0);
    std::vector<std::pair<uint32_t, uint32_t>> wedges; // (attribute id, output vertex)
    for (auto v : mesh.vertices()) {
        wedges.clear();
        first_of[v.idx()] = (uint32_t)vertex_of.size();
        int named = (int)old_index[v.idx()];
        for (auto f : mesh.vf_range(v)) {
            const CornerSet &set = mesh.property(attributes.corners, f);
            uint32_t id = corner_id(set, named);
            auto found = std::find_if(wedges.begin(), wedges.end(),
                                      [id](const std::pair<uint32_t, uint32_t> &w) {
                                          return w.first == id;
                                      });
            uint32_t index;
            if (found != wedges.end()) {
                index = found->second;
            } else {
                index = (uint32_t)vertex_of.size();
                wedges.emplace_back(id, index);
                vertex_of.push_back((uint32_t)v.idx());
                id_of.push_back(id);
            }
            for (int k = 0; k < 3; k++)
                if (set.vertex[k] == named)
                    corner_out[f.idx()][k] = index;
        }
        if (wedges.empty()) { // no faces (not expected after garbage collection): itself
            vertex_of.push_back((uint32_t)v.idx());
            id_of.push_back(0);
        }
    }
}


// What the flat weld's repairs leave on each face: turned for the decimater, and how many
// twins repeat it in its winding and against it (weld.h).
struct FaceRepairs {
    bool turned = false;
    uint32_t same = 0, reversed = 0;
};

// Compacts the mesh and copies its vertices and faces into out->mesh (a vertex once per wedge
// where the mesh has attributes), each face in the winding of its input triangle, then every
// face again for each of its twins; out->output_index maps the decimater's vertices to their
// (first) place in it (garbage collection does not keep their order).
void copy_out(Mesh &mesh, const AttributeTable &attributes,
              OpenMesh::FPropHandleT<FaceRepairs> repairs, decimate_output *out)
{
    size_t n = mesh.n_vertices();
    out->history_count = (uint32_t)n;
    OpenMesh::VPropHandleT<uint32_t> before;
    mesh.add_property(before);
    for (auto v : mesh.all_vertices())
        mesh.property(before, v) = (uint32_t)v.idx();
    mesh.garbage_collection();
    // Without attributes every vertex is one output vertex and a face's corners are its vertices.
    std::vector<std::array<uint32_t, 3>> corner_out;
    std::vector<uint32_t> first_of, vertex_of, id_of, old_index;
    for (auto v : mesh.vertices())
        old_index.push_back(mesh.property(before, v));
    if (attributes.present()) {
        split_wedges(mesh, attributes, old_index, corner_out, first_of, vertex_of, id_of);
    } else {
        for (auto v : mesh.vertices()) {
            first_of.push_back((uint32_t)v.idx());
            vertex_of.push_back((uint32_t)v.idx());
        }
    }
    out->output_index = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    for (size_t v = 0; v < n; v++)
        out->output_index[v] = DECIMATE_REMOVED;
    for (auto v : mesh.vertices())
        out->output_index[mesh.property(before, v)] = first_of[v.idx()];
    mesh.remove_property(before);
    size_t count = vertex_of.size(), triangles = 0;
    for (auto f : mesh.faces()) {
        const FaceRepairs &r = mesh.property(repairs, f);
        triangles += 1 + r.same + r.reversed;
    }
    out->mesh.vertex_count = (uint32_t)count;
    out->mesh.triangle_count = (uint32_t)triangles;
    out->mesh.positions = (float *)xmalloc(3 * sizeof(float) * (count + 1));
    out->mesh.indices = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (triangles + 1));
    for (size_t i = 0; i < count; i++)
        for (int k = 0; k < 3; k++)
            out->mesh.positions[3 * i + k] = mesh.point(Mesh::VertexHandle((int)vertex_of[i]))[k];
    // The face's output vertices as the decimater winds it.
    auto corners_of = [&](Mesh::FaceHandle f, uint32_t c[3]) {
        if (attributes.present()) {
            for (int k = 0; k < 3; k++)
                c[k] = corner_out[f.idx()][k];
            return;
        }
        int k = 0;
        for (auto v : mesh.fv_range(f))
            c[k++] = (uint32_t)v.idx();
    };
    size_t corner = 0;
    auto put = [&](const uint32_t c[3], bool reverse) {
        out->mesh.indices[corner++] = c[0];
        out->mesh.indices[corner++] = c[reverse ? 2 : 1];
        out->mesh.indices[corner++] = c[reverse ? 1 : 2];
    };
    for (auto f : mesh.faces()) {
        uint32_t c[3];
        corners_of(f, c);
        put(c, mesh.property(repairs, f).turned);
    }
    for (auto f : mesh.faces()) {
        const FaceRepairs &r = mesh.property(repairs, f);
        uint32_t c[3];
        corners_of(f, c);
        for (uint32_t i = 0; i < r.same + r.reversed; i++)
            put(c, i >= r.same);
    }
    if (attributes.present())
        copy_attribute_values(attributes.uv_floats, attributes.normal_floats,
                              attributes.values.data(), id_of, &out->mesh);
}

// Whether the permutation of a twin's corner map is odd: the twin runs against its triangle.
bool reverses(const uint8_t corner[3])
{
    return (corner[0] + 1) % 3 != corner[1];
}

// The welded rebuild of the flat weld's repaired triangles, each face with its repairs.
void build_repaired(const decimate_input *in, Mesh &mesh, decimate_output *out,
                    std::vector<double> &importance, AttributeTable &attributes,
                    OpenMesh::FPropHandleT<FaceRepairs> &repairs)
{
    weld_result flat;
    weld_flat(in, 1, &flat);
    std::vector<uint32_t> indices = repaired_indices(in, flat);
    decimate_input repaired = *in;
    repaired.indices = indices.data();
    repaired.triangle_count = flat.triangle_count;
    std::vector<uint32_t> face_triangle;
    build_welded_mesh(&repaired, mesh, out, importance, attributes, &face_triangle);
    out->faces_dropped = flat.triangles_dropped;
    std::vector<int> face_of(flat.triangle_count, -1);
    for (size_t i = 0; i < face_triangle.size(); i++)
        face_of[face_triangle[i]] = (int)i;
    mesh.add_property(repairs);
    for (size_t i = 0; i < face_triangle.size(); i++)
        mesh.property(repairs, Mesh::FaceHandle((int)i)).turned =
            flat.turned && flat.turned[face_triangle[i]];
    for (uint32_t i = 0; i < flat.twin_count; i++) {
        FaceRepairs &r = mesh.property(repairs, Mesh::FaceHandle(face_of[flat.twins[i].primary]));
        (reverses(flat.twins[i].corner) ? r.reversed : r.same)++;
    }
    weld_result_free(&flat);
}

// decimate_mesh() without the exception boundary.
int decimate_welded(const decimate_input *in, decimate_method method, decimate_output *out)
{
    Mesh mesh;
    std::vector<double> importance;
    AttributeTable attributes;
    OpenMesh::FPropHandleT<FaceRepairs> repairs;
    build_repaired(in, mesh, out, importance, attributes, repairs);
    size_t n = mesh.n_vertices();
    out->collapsed_into = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    for (size_t v = 0; v < n; v++)
        out->collapsed_into[v] = (uint32_t)v;

    ReductionDecimater decimater(mesh);
    std::vector<uint32_t> distance = welded_distances(in, out, n);
    if (!distance.empty())
        decimater.set_distances(&distance);
    Modules modules;
    if (!add_modules(decimater, modules, mesh, method, in, importance, attributes,
                     out->collapsed_into)) {
        decimate_output_free(out);
        return error_set(IDMR_EXIT_FAILURE,
                         "mesh '%s': the OpenMesh decimater did not initialise (it needs "
                         "exactly one priority module)",
                         in->name);
    }
    // The target counts all vertices (once per wedge), the locked copies of loose faces
    // included: the collapsible surface gets what remains after them.
    size_t target = (size_t)std::min<uint64_t>(in->target_vertices, out->vertices_welded);
    out->collapses = (uint32_t)decimater.decimate_to(target, in->verify_heap != 0,
                                                     in->reheap_removed_ring_only != 0,
                                                     &out->heap_violations);
    copy_out(mesh, attributes, repairs, out); // collapsed_into is in welded indices already
    return 0;
}

} // namespace

extern "C" int decimate_reference_mesh(const decimate_input *in, decimate_method method,
                                       decimate_output *out)
{
    return decimate_guarded(in, method, out, decimate_welded);
}

