// decimate.cc — decimate_mesh() and decimate_measure() (see decimate.h), the product path: the
// input welded on flat arrays (weld.h), or, where that finds the surface non-manifold, the
// OpenMesh rebuild (decimate_weld.cc) laid out flat; the collapse engine (collapse.h) on them;
// and the result split per wedge into a decimate_output.
#include <algorithm>
#include <cstring>
#include <exception>
#include <unordered_map>
#include <vector>

#include "reduce/decimate_openmesh.hh"

extern "C" {
#include "core/error.h"
#include "core/progress.h"
#include "reduce/collapse.h"
#include "reduce/weld.h"
}

using namespace idmr_decimate;

namespace {

// The engine needs every attribute id used by one vertex (collapse.h), but the rebuild's patch
// and loose copies carry the ids of the welded vertex they copy: such an id gets a copy of its
// values for each further vertex that uses it.
void own_attribute_ids(weld_result *flat)
{
    int stride = flat->uv_floats + flat->normal_floats;
    std::vector<uint32_t> owner(flat->attribute_count, COLLAPSE_NONE);
    std::vector<float> values(flat->attributes, flat->attributes + (size_t)stride *
                                                                   flat->attribute_count);
    std::unordered_map<uint64_t, uint32_t> copy_of; // (vertex << 32 | id) -> its own id
    for (size_t c = 0; c < 3 * (size_t)flat->triangle_count; c++) {
        uint32_t v = flat->triangles[c], id = flat->corner_ids[c];
        if (owner[id] == COLLAPSE_NONE)
            owner[id] = v;
        if (owner[id] == v)
            continue;
        uint64_t key = (uint64_t)v << 32 | id;
        auto found = copy_of.find(key);
        if (found == copy_of.end()) {
            uint32_t fresh = (uint32_t)(values.size() / stride);
            for (int k = 0; k < stride; k++) {
                float value = values[(size_t)stride * id + k]; // (the vector may move)
                values.push_back(value);
            }
            found = copy_of.emplace(key, fresh).first;
        }
        flat->corner_ids[c] = found->second;
    }
    if (copy_of.empty())
        return;
    std::free(flat->attributes);
    flat->attributes = (float *)xmalloc(sizeof(float) * (values.size() + 1));
    std::copy(values.begin(), values.end(), flat->attributes);
    flat->attribute_count = (uint32_t)(values.size() / stride);
}

// Lays the OpenMesh rebuild out flat, as the flat weld gives its result: vertex i is mesh vertex
// i (its loose copies locked); a face's corners in the order it was added (its corner set where
// the mesh has attributes), each attribute id its vertex's own.
void flatten(Mesh &mesh, const AttributeTable &attributes, const std::vector<double> &importance,
             weld_result *flat)
{
    size_t n = mesh.n_vertices(), faces = mesh.n_faces();
    std::memset(flat, 0, sizeof *flat);
    flat->vertex_count = (uint32_t)n;
    flat->positions = (float *)xmalloc(3 * sizeof(float) * (n + 1));
    flat->locked = (uint8_t *)xcalloc(n + 1, 1);
    flat->importance = (double *)xcalloc(n + 1, sizeof(double));
    std::copy(importance.begin(), importance.begin() + std::min(n, importance.size()),
              flat->importance);
    for (auto v : mesh.all_vertices()) {
        const Mesh::Point &p = mesh.point(v);
        for (int k = 0; k < 3; k++)
            flat->positions[3 * (size_t)v.idx() + k] = p[k];
        flat->locked[v.idx()] = mesh.status(v).locked();
    }
    flat->triangle_count = (uint32_t)faces;
    flat->triangles = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (faces + 1));
    if (attributes.present()) {
        flat->corner_ids = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (faces + 1));
        flat->uv_floats = attributes.uv_floats;
        flat->normal_floats = attributes.normal_floats;
        flat->attribute_count = (uint32_t)(attributes.values.size() / attributes.stride());
        flat->attributes = (float *)xmalloc(sizeof(float) * (attributes.values.size() + 1));
        std::copy(attributes.values.begin(), attributes.values.end(), flat->attributes);
    }
    size_t corner = 0;
    for (auto f : mesh.faces()) {
        if (attributes.present()) {
            const CornerSet &set = mesh.property(attributes.corners, f);
            for (int k = 0; k < 3; k++, corner++) {
                flat->triangles[corner] = (uint32_t)set.vertex[k];
                flat->corner_ids[corner] = set.id[k];
            }
            continue;
        }
        for (auto v : mesh.fv_range(f))
            flat->triangles[corner++] = (uint32_t)v.idx();
    }
    if (attributes.present())
        own_attribute_ids(flat);
}


// The welded mesh the engine starts from: the flat weld where the surface is manifold (its
// welding figures into out), else the OpenMesh rebuild of the flat weld's repaired triangles
// (which fills them itself; weld.h), with the flat weld's turns and twins carried over to its
// faces. out takes welded_of either way. Unchecked: the flat weld as it is, whose fans the
// engine checks (collapse_mesh.fans_unchecked), and out->vertices_welded is left to the engine's
// count.
void prepare(const decimate_input *in, bool unchecked, weld_result *flat, decimate_output *out)
{
    weld_flat(in, !unchecked, flat);
    if (unchecked || flat->non_manifold_vertices == 0) {
        out->welded_of = flat->welded_of;
        flat->welded_of = nullptr;
        out->vertices_welded = flat->vertices_counted;
        out->faces_dropped = flat->triangles_dropped;
        return;
    }
    weld_result repaired = *flat; // what the rebuild carries over (freed below)
    std::memset(flat, 0, sizeof *flat);
    std::vector<uint32_t> indices = repaired_indices(in, repaired);
    decimate_input rebuilt_from = *in;
    rebuilt_from.indices = indices.data();
    rebuilt_from.triangle_count = repaired.triangle_count;
    Mesh mesh;
    AttributeTable attributes;
    std::vector<double> importance;
    std::vector<uint32_t> face_triangle;
    build_welded_mesh(&rebuilt_from, mesh, out, importance, attributes, &face_triangle);
    out->faces_dropped = repaired.triangles_dropped;
    flatten(mesh, attributes, importance, flat);
    // Every repaired triangle is one face (none welds into zero area): face i was triangle
    // face_triangle[i].
    std::vector<uint32_t> face_of(repaired.triangle_count, COLLAPSE_NONE);
    for (size_t i = 0; i < face_triangle.size(); i++)
        face_of[face_triangle[i]] = (uint32_t)i;
    flat->kept_from = (uint32_t *)xmalloc(sizeof(uint32_t) * (flat->triangle_count + 1));
    for (uint32_t i = 0; i < flat->triangle_count; i++)
        flat->kept_from[i] = repaired.kept_from[face_triangle[i]];
    if (repaired.turned) {
        flat->turned = (uint8_t *)xcalloc(flat->triangle_count + 1, 1);
        for (uint32_t i = 0; i < flat->triangle_count; i++)
            flat->turned[i] = repaired.turned[face_triangle[i]];
        flat->triangles_turned = repaired.triangles_turned;
    }
    flat->twins = repaired.twins;
    flat->twin_count = repaired.twin_count;
    repaired.twins = nullptr;
    for (uint32_t i = 0; i < flat->twin_count; i++)
        flat->twins[i].primary = face_of[flat->twins[i].primary];
    weld_result_free(&repaired);
}

// The live triangles (`live` of them), each wound as the input had it (a turned one turned
// back), followed by the twins of the live ones (weld.h), each on its triangle's corners in its
// own winding, into m's indices: corner c (3 t + k) as output vertex output_of(c).
template <typename OutputOf>
static void write_triangles(const weld_result &flat, size_t live, OutputOf output_of, mesh_data *m)
{
    size_t corners = 3 * (size_t)flat.triangle_count, twins = 0;
    for (uint32_t i = 0; i < flat.twin_count; i++)
        twins += flat.triangles[3 * (size_t)flat.twins[i].primary] != COLLAPSE_NONE;
    m->triangle_count = (uint32_t)(live + twins);
    m->indices = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * (live + twins + 1));
    size_t written = 0;
    for (size_t c = 0; c < corners; c += 3) {
        if (flat.triangles[c] == COLLAPSE_NONE)
            continue;
        bool turned = flat.turned && flat.turned[c / 3];
        m->indices[written++] = output_of(c);
        m->indices[written++] = output_of(c + (turned ? 2 : 1));
        m->indices[written++] = output_of(c + (turned ? 1 : 2));
    }
    for (uint32_t i = 0; i < flat.twin_count; i++) {
        size_t c = 3 * (size_t)flat.twins[i].primary;
        if (flat.triangles[c] == COLLAPSE_NONE)
            continue;
        for (int k = 0; k < 3; k++)
            m->indices[written++] = output_of(c + flat.twins[i].corner[k]);
    }
}

// write_output() without attributes: a vertex is one wedge, so its output vertex is its place
// among the vertices of live triangles, as the corner sort with attributes would number it.
static void write_output_unsplit(const weld_result &flat, decimate_output *out)
{
    size_t n = flat.vertex_count, corners = 3 * (size_t)flat.triangle_count, live = 0;
    uint32_t *index = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    std::fill(index, index + n, DECIMATE_REMOVED);
    for (size_t c = 0; c < corners; c += 3)
        if (flat.triangles[c] != COLLAPSE_NONE) {
            for (int k = 0; k < 3; k++)
                index[flat.triangles[c + k]] = 0; // a vertex of a live triangle: numbered below
            live++;
        }
    uint32_t count = 0;
    for (size_t v = 0; v < n; v++)
        if (index[v] != DECIMATE_REMOVED)
            index[v] = count++;
    mesh_data *m = &out->mesh;
    m->vertex_count = count;
    m->positions = (float *)xmalloc(3 * sizeof(float) * ((size_t)count + 1));
    for (size_t v = 0; v < n; v++)
        if (index[v] != DECIMATE_REMOVED)
            std::memcpy(&m->positions[3 * (size_t)index[v]], &flat.positions[3 * v],
                        3 * sizeof(float));
    write_triangles(flat, live, [&](size_t c) { return index[flat.triangles[c]]; }, m);
    out->output_index = index;
}

// The reduced mesh into out->mesh: every vertex of a live triangle once per wedge (distinct
// corner id), in vertex order, its wedges in the order its corners come in the triangle list;
// out->output_index[v] is v's first output vertex, or DECIMATE_REMOVED. The triangles as
// write_triangles writes them.
void write_output(const weld_result &flat, decimate_output *out)
{
    if (!flat.corner_ids) {
        write_output_unsplit(flat, out);
        return;
    }
    size_t n = flat.vertex_count, corners = 3 * (size_t)flat.triangle_count;
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
            uint32_t c = corner_of[i], id = flat.corner_ids[c];
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
    m->positions = (float *)xmalloc(3 * sizeof(float) * (count + 1));
    for (size_t i = 0; i < count; i++)
        std::memcpy(&m->positions[3 * i], &flat.positions[3 * (size_t)vertex_of[i]],
                    3 * sizeof(float));
    write_triangles(flat, live, [&](size_t c) { return output_of[c]; }, m);
    copy_attribute_values(flat.uv_floats, flat.normal_floats, flat.attributes, id_of, m);
}

// The engine on the welded mesh `flat` (prepare's; its fans unchecked or not), into out's
// history; its seconds into out. Returns 0, or -1 with the error set.
int collapse_welded(const decimate_input *in, decimate_method method, weld_result &flat,
                    bool unchecked, decimate_output *out, collapse_result *result)
{
    size_t n = flat.vertex_count;
    std::vector<uint32_t> distance = welded_distances(in, out, n);
    collapse_mesh cm;
    std::memset(&cm, 0, sizeof cm);
    cm.vertex_count = (uint32_t)n;
    cm.positions = flat.positions;
    cm.triangle_count = flat.triangle_count;
    cm.triangles = flat.triangles;
    cm.corner_ids = flat.corner_ids;
    cm.attributes = flat.attributes;
    cm.attribute_count = flat.attribute_count;
    cm.uv_floats = flat.uv_floats;
    cm.normal_floats = flat.normal_floats;
    cm.locked = flat.locked;
    cm.importance = in->vertex_importance ? flat.importance : nullptr;
    cm.distance = distance.empty() ? nullptr : distance.data();
    cm.fans_unchecked = unchecked;

    collapse_options options;
    std::memset(&options, 0, sizeof options);
    options.method = method;
    // The target counts all vertices (once per wedge), the locked copies of loose faces
    // included: the collapsible surface gets what remains after them. (Unchecked, the welded
    // count is the engine's own: above it, the engine stops before its first pass.)
    options.target_vertices = unchecked ? in->target_vertices
                                        : std::min<uint64_t>(in->target_vertices,
                                                             out->vertices_welded);
    options.max_normal_angle = in->max_normal_angle > 0 ? in->max_normal_angle : 60.0;
    options.boundary_tolerance =
        in->boundary_tolerance > 0 ? in->boundary_tolerance : DECIMATE_BOUNDARY_TOLERANCE;
    options.seams_free = in->seams_free;
    options.uv_weight = in->uv_weight;
    options.normal_weight = in->normal_weight;
    options.threads = in->threads ? in->threads : 1;

    out->history_count = (uint32_t)n;
    out->collapsed_into = (uint32_t *)xmalloc(sizeof(uint32_t) * (n + 1));
    std::memset(result, 0, sizeof *result);
    result->collapsed_into = out->collapsed_into;
    double start = monotonic_seconds();
    if (collapse_run(&cm, &options, result)) {
        error_prefix("mesh '%s'", in->name);
        return -1;
    }
    out->seconds_collapse += monotonic_seconds() - start;
    return 0;
}

// decimate_mesh() without the exception boundary. The flat weld goes to the engine unchecked;
// where the engine finds a vertex whose triangles are not one fan, before any collapse, the mesh
// is welded again with the check and its repairs (or rebuilt), and the engine starts anew.
int decimate_welded(const decimate_input *in, decimate_method method, decimate_output *out)
{
    double start = monotonic_seconds();
    weld_result flat;
    prepare(in, true, &flat, out);
    out->seconds_weld = monotonic_seconds() - start;
    collapse_result result;
    int failed = collapse_welded(in, method, flat, true, out, &result);
    if (!failed && result.non_manifold_vertices) {
        start = monotonic_seconds();
        std::free(out->collapsed_into);
        std::free(out->welded_of);
        out->collapsed_into = out->welded_of = nullptr;
        weld_result_free(&flat);
        prepare(in, false, &flat, out); // an OpenMesh mesh is freed before the engine runs
        out->seconds_weld += monotonic_seconds() - start;
        failed = collapse_welded(in, method, flat, false, out, &result);
    } else if (!failed)
        out->vertices_welded = (uint32_t)result.vertices_before;
    if (failed) {
        weld_result_free(&flat);
        decimate_output_free(out);
        return -1;
    }
    out->collapses = result.collapses;
    out->passes = result.passes;
    start = monotonic_seconds();
    write_output(flat, out);
    weld_result_free(&flat);
    out->seconds_output = monotonic_seconds() - start;
    return 0;
}

} // namespace

extern "C" int decimate_mesh(const decimate_input *in, decimate_method method,
                             decimate_output *out)
{
    return decimate_guarded(in, method, out, decimate_welded);
}

extern "C" int decimate_measure(const decimate_input *in, uint32_t *vertices,
                                uint32_t *uncollapsible)
{
    decimate_output out;
    std::memset(&out, 0, sizeof out);
    try {
        weld_result flat;
        prepare(in, false, &flat, &out);
        weld_result_free(&flat);
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
