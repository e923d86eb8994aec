// mesh_io.cc — the OpenMesh bridge behind mesh_io.h: reads a mesh file into flat C arrays and
// writes PLY files with per-vertex properties.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <cerrno>
#include <utility>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <strings.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

extern "C" {
#include "core/error.h"
#include "core/files.h"
#include "io/mesh_io.h"
#include "io/mesh_text.h"
#include "io/ply_check.h"
}

// OpenMesh reports every non-manifold face it has to split (and every face the decimater's
// mesh builder tries and fails to attach) on its log streams; idmr reports what matters
// itself, so they stay quiet. Once, thread-safely (a function-local static), since decimation
// runs on worker threads.
extern "C" void mesh_io_silence_openmesh_logs(void)
{
    static const bool silenced = [] {
        omlog().disable();
        omout().disable();
        omerr().disable();
        return true;
    }();
    (void)silenced;
}

namespace {

typedef OpenMesh::TriMesh_ArrayKernelT<> TriMesh;

bool has_extension(const char *path, const char *extension)
{
    size_t length = std::strlen(path), wanted = std::strlen(extension);
    return length > wanted && strcasecmp(path + length - wanted, extension) == 0;
}

// A regular file that can be opened; a PLY file also well formed (io/ply_check.h).
int check_readable(const char *path)
{
    struct stat info;
    if (stat(path, &info) != 0)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, strerror(errno));
    if (!S_ISREG(info.st_mode))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': not a regular file", path);
    return has_extension(path, ".ply") ? ply_check(path) : 0;
}

// Reads the formats idmr leaves to OpenMesh (PLY, STL, OM) into `out`.
int read_openmesh(const char *path, mesh_data *out)
{
    mesh_io_silence_openmesh_logs();
    TriMesh mesh;
    mesh.request_vertex_texcoords2D();
    mesh.request_vertex_normals();
    OpenMesh::IO::Options options = OpenMesh::IO::Options::VertexTexCoord;
    options += OpenMesh::IO::Options::VertexNormal;
    bool ok;
    try {
        ok = OpenMesh::IO::read_mesh(mesh, path, options);
    } catch (const std::exception &e) {
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, e.what());
    }
    if (!ok)
        return error_set(IDMR_EXIT_INPUT,
                         "cannot read mesh '%s': OpenMesh could not parse it (unknown "
                         "extension or malformed file)",
                         path);
    if (mesh.n_vertices() > UINT32_MAX || mesh.n_faces() > UINT32_MAX / 3)
        return error_set(IDMR_EXIT_INPUT, "mesh '%s' is too large for 32-bit indices", path);

    out->vertex_count = (uint32_t)mesh.n_vertices();
    out->triangle_count = (uint32_t)mesh.n_faces();
    out->positions = (float *)xmalloc(3 * sizeof(float) * out->vertex_count);
    out->indices = (uint32_t *)xmalloc(3 * sizeof(uint32_t) * out->triangle_count);
    for (auto v : mesh.vertices()) {
        const TriMesh::Point &p = mesh.point(v);
        for (int k = 0; k < 3; k++)
            out->positions[3 * (size_t)v.idx() + k] = p[k];
    }
    size_t corner = 0;
    for (auto f : mesh.faces())
        for (auto v : mesh.fv_range(f))
            out->indices[corner++] = (uint32_t)v.idx();
    if (options.check(OpenMesh::IO::Options::VertexNormal)) {
        out->normals = (float *)xmalloc(3 * sizeof(float) * out->vertex_count);
        for (auto v : mesh.vertices()) {
            const TriMesh::Normal &n = mesh.normal(v);
            for (int k = 0; k < 3; k++)
                out->normals[3 * (size_t)v.idx() + k] = n[k];
        }
    }
    if (options.check(OpenMesh::IO::Options::VertexTexCoord)) {
        out->texcoords = (float *)xmalloc(2 * sizeof(float) * out->vertex_count);
        for (auto v : mesh.vertices()) {
            const TriMesh::TexCoord2D &uv = mesh.texcoord2D(v);
            out->texcoords[2 * (size_t)v.idx()] = uv[0];
            out->texcoords[2 * (size_t)v.idx() + 1] = uv[1];
        }
    }
    return 0;
}

// Winds every triangle so that its geometric normal agrees with the sum of its vertex
// normals; returns how many it turned.
uint32_t orient_by_normals(mesh_data *m)
{
    uint32_t turned = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        uint32_t *ix = &m->indices[3 * (size_t)t];
        TriMesh::Point p[3];
        TriMesh::Normal sum(0, 0, 0);
        for (int c = 0; c < 3; c++) {
            const float *v = &m->positions[3 * (size_t)ix[c]];
            const float *n = &m->normals[3 * (size_t)ix[c]];
            p[c] = TriMesh::Point(v[0], v[1], v[2]);
            sum += TriMesh::Normal(n[0], n[1], n[2]);
        }
        if (OpenMesh::dot(OpenMesh::cross(p[1] - p[0], p[2] - p[0]), sum) < 0) {
            std::swap(ix[1], ix[2]);
            turned++;
        }
    }
    return turned;
}

} // namespace

extern "C" int mesh_io_read(const char *path, mesh_data *out)
{
    return mesh_io_read_oriented(path, out, 0, nullptr);
}

extern "C" int mesh_io_read_oriented(const char *path, mesh_data *out, int orient,
                                     uint32_t *flipped)
{
    if (flipped)
        *flipped = 0;
    std::memset(out, 0, sizeof *out);
    if (check_readable(path) != 0)
        return -1;
    int status = has_extension(path, ".obj")   ? mesh_text_read_obj(path, out)
                 : has_extension(path, ".off") ? mesh_text_read_off(path, out)
                                               : read_openmesh(path, out);
    if (status == 0 && out->triangle_count == 0)
        status = error_set(IDMR_EXIT_INPUT, "mesh '%s' has no faces", path);
    if (status) {
        mesh_data_free(out);
        return -1;
    }
    if (orient && out->normals) {
        uint32_t turned = orient_by_normals(out);
        if (flipped)
            *flipped = turned;
    }
    return 0;
}

extern "C" int mesh_io_write_ply(const char *path, const mesh_data *mesh, const float *values,
                                 const char *value_name, const unsigned char *colors)
{
    mesh_io_silence_openmesh_logs();
    TriMesh out;
    OpenMesh::IO::Options options = OpenMesh::IO::Options::Binary;
    if (colors) {
        out.request_vertex_colors();
        options += OpenMesh::IO::Options::VertexColor;
    }
    if (mesh->texcoords) {
        out.request_vertex_texcoords2D();
        options += OpenMesh::IO::Options::VertexTexCoord;
    }
    if (mesh->normals) {
        out.request_vertex_normals();
        options += OpenMesh::IO::Options::VertexNormal;
    }
    OpenMesh::VPropHandleT<float> property;
    if (values) {
        out.add_property(property, value_name);
        out.property(property).set_persistent(true);
        options += OpenMesh::IO::Options::Custom;
    }
    std::vector<TriMesh::VertexHandle> handles(mesh->vertex_count);
    auto add_vertex = [&](uint32_t v) {
        const float *p = &mesh->positions[3 * (size_t)v];
        TriMesh::VertexHandle h = out.add_vertex(TriMesh::Point(p[0], p[1], p[2]));
        if (colors)
            out.set_color(h, TriMesh::Color(colors[3 * (size_t)v], colors[3 * (size_t)v + 1],
                                            colors[3 * (size_t)v + 2]));
        if (values)
            out.property(property, h) = values[v];
        if (mesh->texcoords)
            out.set_texcoord2D(h, TriMesh::TexCoord2D(mesh->texcoords[2 * (size_t)v],
                                                      mesh->texcoords[2 * (size_t)v + 1]));
        if (mesh->normals) {
            const float *n = &mesh->normals[3 * (size_t)v];
            out.set_normal(h, TriMesh::Normal(n[0], n[1], n[2]));
        }
        return h;
    };
    for (uint32_t v = 0; v < mesh->vertex_count; v++)
        handles[v] = add_vertex(v);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *ix = &mesh->indices[3 * (size_t)t];
        if (out.add_face(handles[ix[0]], handles[ix[1]], handles[ix[2]]).is_valid())
            continue;
        out.add_face(add_vertex(ix[0]), add_vertex(ix[1]), add_vertex(ix[2]));
    }

    std::vector<char> name(std::strlen(path) + 32);
    int fd = files_create_temporary(path, ".ply", name.data(), name.size());
    if (fd < 0)
        return -1;
    close(fd);
    bool ok;
    try {
        ok = OpenMesh::IO::write_mesh(out, name.data(), options);
    } catch (const std::exception &e) {
        ok = false;
    }
    if (!ok || rename(name.data(), path) != 0) {
        unlink(name.data());
        return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s'", path);
    }
    return 0;
}

extern "C" void mesh_data_free(mesh_data *mesh)
{
    if (!mesh)
        return;
    std::free(mesh->positions);
    std::free(mesh->indices);
    std::free(mesh->texcoords);
    std::free(mesh->normals);
    std::memset(mesh, 0, sizeof *mesh);
}
