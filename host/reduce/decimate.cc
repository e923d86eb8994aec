// decimate.cc — decimate_mesh() and decimate_measure() (see decimate.h), the product path: the
// input welded on flat arrays (weld.h), or, where that finds the surface non-manifold, the
// OpenMesh rebuild (decimate_weld.cc) laid out flat; the collapse engine (collapse.h) on them;
// and the result split per wedge into a decimate_output.
#include <algorithm>
#include <cstring>
#include <exception>
#include <vector>

#include "reduce/decimate_openmesh.hh"

extern "C" {
#include "core/error.h"
#include "reduce/collapse.h"
#include "reduce/weld.h"
}

using namespace idmr_decimate;

namespace {

// The welded mesh on flat arrays, as the engine takes it, with its attribute table.
struct FlatMesh {
    std::vector<float> positions;
    std::vector<uint32_t> triangles, corner_ids;
    std::vector<uint8_t> locked;
    std::vector<double> importance;
    int uv_floats = 0, normal_floats = 0;
    std::vector<float> attributes; // uv_floats + normal_floats per id
    int stride() const { return uv_floats + normal_floats; }
};

// Lays the welded mesh out flat: vertex i is mesh vertex i; a face's corners in the order it
// was added (its corner set where the mesh has attributes).
void flatten(Mesh &mesh, const AttributeTable &attributes, FlatMesh &flat)
{
    size_t n = mesh.n_vertices();
    flat.uv_floats = attributes.uv_floats;
    flat.normal_floats = attributes.normal_floats;
    flat.attributes = attributes.values;
    flat.positions.resize(3 * n);
    flat.locked.assign(n, 0);
    for (auto v : mesh.all_vertices()) {
        const Mesh::Point &p = mesh.point(v);
        for (int k = 0; k < 3; k++)
            flat.positions[3 * (size_t)v.idx() + k] = p[k];
        flat.locked[v.idx()] = mesh.status(v).locked();
    }
    flat.triangles.reserve(3 * mesh.n_faces());
    if (attributes.present())
        flat.corner_ids.reserve(3 * mesh.n_faces());
    for (auto f : mesh.faces()) {
        if (attributes.present()) {
            const CornerSet &set = mesh.property(attributes.corners, f);
            for (int k = 0; k < 3; k++) {
                flat.triangles.push_back((uint32_t)set.vertex[k]);
                flat.corner_ids.push_back(set.id[k]);
            }
            continue;
        }
        for (auto v : mesh.fv_range(f))
            flat.triangles.push_back((uint32_t)v.idx());
    }
}

// The reduced mesh into out->mesh: every vertex of a live triangle once per wedge (distinct
// corner id), in vertex order, its wedges in the order its corners come in the triangle list;
// out->output_index[v] is v's first output vertex, or DECIMATE_REMOVED.
void write_output(const FlatMesh &flat, decimate_output *out)
{
    size_t n = flat.locked.size(), corners = flat.triangles.size();
    bool split = flat.stride() > 0;
    // Per vertex, its live corners in triangle order (a counting sort).
    std::vector<uint32_t> start(n + 1, 0), corner_of;
    size_t live = 0;
    for (size_t c = 0; c < corners; c += 3)
        if (flat.triangles[c] != COLLAPSE_NONE) {
            for (int k = 0; k < 3; k++)
                start[flat.triangles[c + k] + 1]++;
            live++;
        }
    for (size_t v = 0; v < n; v++)
        start[v + 1] += start[v];
    corner_of.resize(start[n]);
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t c = 0; c < corners; c++)
        if (flat.triangles[c - c % 3] != COLLAPSE_NONE)
            corner_of[fill[flat.triangles[c]]++] = (uint32_t)c;

    std::vector<uint32_t> output_of(corners, 0), vertex_of, id_of;
    out->output_index = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    for (size_t v = 0; v < n; v++) {
        out->output_index[v] = DECIMATE_REMOVED;
        size_t first = vertex_of.size();
        for (uint32_t i = start[v]; i < start[v + 1]; i++) {
            uint32_t c = corner_of[i], id = split ? flat.corner_ids[c] : 0;
            size_t w = first;
            while (w < vertex_of.size() && id_of[w] != id)
                w++;
            if (w == vertex_of.size()) {
                vertex_of.push_back((uint32_t)v);
                id_of.push_back(id);
            }
            output_of[c] = (uint32_t)w;
        }
        if (vertex_of.size() > first)
            out->output_index[v] = (uint32_t)first;
    }
    size_t count = vertex_of.size();
    mesh_data *m = &out->mesh;
    m->vertex_count = (uint32_t)count;
    m->triangle_count = (uint32_t)live;
    m->positions = (float *)xmalloc(3 * sizeof(float) * (count + 1));
    m->indices = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (live + 1));
    for (size_t i = 0; i < count; i++)
        std::memcpy(&m->positions[3 * i], &flat.positions[3 * (size_t)vertex_of[i]],
                    3 * sizeof(float));
    size_t written = 0;
    for (size_t c = 0; c < corners; c++)
        if (flat.triangles[c - c % 3] != COLLAPSE_NONE)
            m->indices[written++] = output_of[c];
    if (!split)
        return;
    int stride = flat.stride();
    if (flat.uv_floats)
        m->texcoords = (float *)xmalloc(2 * sizeof(float) * (count + 1));
    if (flat.normal_floats)
        m->normals = (float *)xmalloc(3 * sizeof(float) * (count + 1));
    for (size_t i = 0; i < count; i++) {
        const float *value = &flat.attributes[(size_t)stride * id_of[i]];
        for (int k = 0; k < flat.uv_floats; k++)
            m->texcoords[2 * i + k] = value[k];
        for (int k = 0; k < flat.normal_floats; k++)
            m->normals[3 * i + k] = value[flat.uv_floats + k];
    }
}

// The flat weld's result as the engine's input (it was found manifold: nothing is patched or
// locked). Takes welded_of into out.
void from_weld(weld_result &weld, FlatMesh &flat, decimate_output *out)
{
    size_t n = weld.vertex_count, corners = 3 * (size_t)weld.triangle_count;
    flat.positions.assign(weld.positions, weld.positions + 3 * n);
    flat.triangles.assign(weld.triangles, weld.triangles + corners);
    if (weld.corner_ids)
        flat.corner_ids.assign(weld.corner_ids, weld.corner_ids + corners);
    flat.locked.assign(n, 0);
    flat.importance.assign(weld.importance, weld.importance + n);
    flat.uv_floats = weld.uv_floats;
    flat.normal_floats = weld.normal_floats;
    if (weld.attributes)
        flat.attributes.assign(weld.attributes,
                               weld.attributes + (size_t)flat.stride() * weld.attribute_count);
    out->welded_of = weld.welded_of;
    weld.welded_of = nullptr;
    out->vertices_welded = weld.vertices_counted;
    out->faces_dropped = weld.triangles_dropped;
}

// The welded mesh the engine starts from: the flat weld where the surface is manifold, else the
// OpenMesh rebuild (which fills out's welding figures itself).
void prepare(const decimate_input *in, FlatMesh &flat, decimate_output *out)
{
    weld_result weld;
    weld_flat(in, &weld);
    if (weld.non_manifold_vertices == 0) {
        from_weld(weld, flat, out);
        weld_result_free(&weld);
        return;
    }
    weld_result_free(&weld);
    Mesh mesh;
    AttributeTable attributes;
    build_welded_mesh(in, mesh, out, flat.importance, attributes);
    flatten(mesh, attributes, flat);
}

// decimate_mesh() without the exception boundary.
int decimate_welded(const decimate_input *in, decimate_method method, decimate_output *out)
{
    FlatMesh flat;
    prepare(in, flat, out); // an OpenMesh mesh is freed before the engine runs
    size_t n = flat.locked.size();
    std::vector<uint32_t> distance = welded_distances(in, out, n);
    flat.importance.resize(n, 0.0);
    collapse_mesh cm;
    std::memset(&cm, 0, sizeof cm);
    cm.vertex_count = (uint32_t)n;
    cm.positions = flat.positions.data();
    cm.triangle_count = (uint32_t)(flat.triangles.size() / 3);
    cm.triangles = flat.triangles.data();
    if (flat.stride() > 0) {
        cm.corner_ids = flat.corner_ids.data();
        cm.attributes = flat.attributes.data();
        cm.attribute_count = (uint32_t)(flat.attributes.size() / flat.stride());
        cm.uv_floats = flat.uv_floats;
        cm.normal_floats = flat.normal_floats;
    }
    cm.locked = flat.locked.data();
    cm.importance = in->vertex_importance ? flat.importance.data() : nullptr;
    cm.distance = distance.empty() ? nullptr : distance.data();

    collapse_options options;
    std::memset(&options, 0, sizeof options);
    options.method = method;
    // The target counts all vertices (once per wedge), the locked copies of loose faces
    // included: the collapsible surface gets what remains after them.
    options.target_vertices = std::min<uint64_t>(in->target_vertices, out->vertices_welded);
    options.max_normal_angle = in->max_normal_angle > 0 ? in->max_normal_angle : 60.0;
    options.boundary_tolerance =
        in->boundary_tolerance > 0 ? in->boundary_tolerance : DECIMATE_BOUNDARY_TOLERANCE;
    options.seams_free = in->seams_free;
    options.uv_weight = in->uv_weight;
    options.normal_weight = in->normal_weight;
    options.threads = in->threads ? in->threads : 1;

    out->history_count = (uint32_t)n;
    out->collapsed_into = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    collapse_result result;
    std::memset(&result, 0, sizeof result);
    result.collapsed_into = out->collapsed_into;
    if (collapse_run(&cm, &options, &result)) {
        error_prefix("mesh '%s'", in->name);
        decimate_output_free(out);
        return -1;
    }
    out->collapses = result.collapses;
    out->passes = result.passes;
    write_output(flat, out);
    return 0;
}

} // namespace

extern "C" int decimate_mesh(const decimate_input *in, decimate_method method,
                             decimate_output *out)
{
    std::memset(out, 0, sizeof *out);
    if (method != DECIMATE_QUADRIC && !in->vertex_importance)
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': importance decimation without importance",
                         in->name);
    try {
        return decimate_welded(in, method, out);
    } catch (const std::exception &e) {
        decimate_output_free(out);
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
}

extern "C" int decimate_measure(const decimate_input *in, uint32_t *vertices,
                                uint32_t *uncollapsible)
{
    decimate_output out;
    std::memset(&out, 0, sizeof out);
    try {
        FlatMesh flat;
        prepare(in, flat, &out);
    } catch (const std::exception &e) {
        decimate_output_free(&out);
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
    *vertices = out.vertices_welded;
    *uncollapsible = out.vertices_uncollapsible;
    decimate_output_free(&out);
    return 0;
}

extern "C" void decimate_output_free_history(decimate_output *out)
{
    std::free(out->collapsed_into);
    std::free(out->output_index);
    std::free(out->welded_of);
    out->collapsed_into = out->output_index = out->welded_of = nullptr;
    out->history_count = 0;
}

extern "C" void decimate_output_free(decimate_output *out)
{
    mesh_data_free(&out->mesh);
    decimate_output_free_history(out);
    std::memset(out, 0, sizeof *out);
}
