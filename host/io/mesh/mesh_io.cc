// mesh_io.cc — the OpenMesh bridge behind mesh_io.h: reads a mesh file into flat C arrays
// (idmr's own readers for OBJ, OFF, PLY and STL, OpenMesh for OM), drops the triangles that
// repeat a vertex and checks every value finite, and writes PLY files with per-vertex
// properties (its own writer: triangles exactly as given, on the vertices given).
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <cerrno>
#include <cmath>
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
#include "core/scene.h"
#include "io/mesh/mesh_io.h"
#include "io/mesh/mesh_stl.h"
#include "io/mesh/mesh_text.h"
#include "io/mesh/ply_check.h"
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

// A regular file that can be opened.
int check_readable(const char *path)
{
    struct stat info;
    if (stat(path, &info) != 0)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, strerror(errno));
    if (!S_ISREG(info.st_mode))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': not a regular file", path);
    return 0;
}

// The first of `count` groups of `width` floats that holds a value that is not finite, or count.
uint32_t first_not_finite(const float *values, uint32_t count, int width)
{
    for (uint32_t i = 0; values && i < count; i++)
        for (int k = 0; k < width; k++)
            if (!std::isfinite(values[(size_t)width * i + k]))
                return i;
    return count;
}

// Every value read is finite (idmr's readers say so where they read, with the line; this covers
// what OpenMesh reads unchecked).
int check_finite(const char *path, const mesh_data *m)
{
    const struct {
        const float *values;
        int width;
        const char *what;
    } arrays[] = {{m->positions, 3, "position"},
                  {m->texcoords, 2, "texture coordinate"},
                  {m->normals, 3, "normal"}};
    for (const auto &a : arrays) {
        uint32_t v = first_not_finite(a.values, m->vertex_count, a.width);
        if (v < m->vertex_count)
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': vertex %u has a %s that "
                             "is not a finite number",
                             path, v, a.what);
    }
    return 0;
}

// Leaves out the triangles that repeat a vertex (counted in triangles_dropped), and the
// vertices only they used, which keep their order otherwise.
void drop_repeating_triangles(mesh_data *m)
{
    std::vector<unsigned char> used_before(m->vertex_count, 0), used_after(m->vertex_count, 0);
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; c++)
        used_before[m->indices[c]] = 1;
    uint32_t dropped = scene_triangles_drop_repeating(m->indices, &m->triangle_count);
    m->triangles_dropped += dropped;
    if (!dropped)
        return;
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; c++)
        used_after[m->indices[c]] = 1;
    std::vector<uint32_t> new_index(m->vertex_count);
    uint32_t kept = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        new_index[v] = kept;
        if (used_before[v] && !used_after[v])
            continue;
        if (kept != v) {
            std::memmove(&m->positions[3 * (size_t)kept], &m->positions[3 * (size_t)v],
                         3 * sizeof(float));
            if (m->texcoords)
                std::memmove(&m->texcoords[2 * (size_t)kept], &m->texcoords[2 * (size_t)v],
                             2 * sizeof(float));
            if (m->normals)
                std::memmove(&m->normals[3 * (size_t)kept], &m->normals[3 * (size_t)v],
                             3 * sizeof(float));
        }
        kept++;
    }
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; c++)
        m->indices[c] = new_index[m->indices[c]];
    m->vertex_count = kept;
}

// Reads the formats idmr leaves to OpenMesh (OM, and whatever else it knows) into `out`.
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
                 : has_extension(path, ".stl") ? mesh_stl_read(path, out)
                 : has_extension(path, ".ply") ? ply_read(path, out)
                                               : read_openmesh(path, out);
    if (status == 0) {
        drop_repeating_triangles(out);
        status = check_finite(path, out);
    }
    if (status == 0 && out->triangle_count == 0)
        status = out->triangles_dropped
                     ? error_set(IDMR_EXIT_INPUT, "mesh '%s' has no faces: each of its %u "
                                 "triangles repeats a vertex",
                                 path, out->triangles_dropped)
                     : error_set(IDMR_EXIT_INPUT, "mesh '%s' has no faces", path);
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

namespace {

// Appends `value` as 4 little-endian bytes.
void put_le32(std::vector<unsigned char> &out, uint32_t value)
{
    for (int k = 0; k < 4; k++)
        out.push_back((unsigned char)(value >> (8 * k)));
}

void put_float(std::vector<unsigned char> &out, float value)
{
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    put_le32(out, bits);
}

// The PLY of mesh_io_write_ply() into `f`; whether every byte was written.
bool write_ply_file(FILE *f, const mesh_data *mesh, const float *values, const char *value_name,
                    const unsigned char *colors)
{
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by idmr\n"
                         "element vertex " + std::to_string(mesh->vertex_count) +
                         "\nproperty float x\nproperty float y\nproperty float z\n";
    if (mesh->normals)
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    if (mesh->texcoords)
        header += "property float u\nproperty float v\n";
    if (colors)
        header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (values)
        header += std::string("property float ") + value_name + "\n";
    header += "element face " + std::to_string(mesh->triangle_count) +
              "\nproperty list uchar int vertex_indices\nend_header\n";
    if (std::fwrite(header.data(), 1, header.size(), f) != header.size())
        return false;
    std::vector<unsigned char> block;
    const size_t flush_at = 1 << 16;
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        for (int k = 0; k < 3; k++)
            put_float(block, mesh->positions[3 * (size_t)v + k]);
        for (int k = 0; mesh->normals && k < 3; k++)
            put_float(block, mesh->normals[3 * (size_t)v + k]);
        for (int k = 0; mesh->texcoords && k < 2; k++)
            put_float(block, mesh->texcoords[2 * (size_t)v + k]);
        for (int k = 0; colors && k < 3; k++)
            block.push_back(colors[3 * (size_t)v + k]);
        if (values)
            put_float(block, values[v]);
        if (block.size() >= flush_at) {
            if (std::fwrite(block.data(), 1, block.size(), f) != block.size())
                return false;
            block.clear();
        }
    }
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        block.push_back(3);
        for (int k = 0; k < 3; k++)
            put_le32(block, mesh->indices[3 * (size_t)t + k]);
        if (block.size() >= flush_at) {
            if (std::fwrite(block.data(), 1, block.size(), f) != block.size())
                return false;
            block.clear();
        }
    }
    return std::fwrite(block.data(), 1, block.size(), f) == block.size() && std::fflush(f) == 0;
}

} // namespace

extern "C" int mesh_io_write_ply(const char *path, const mesh_data *mesh, const float *values,
                                 const char *value_name, const unsigned char *colors)
{
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *ix = &mesh->indices[3 * (size_t)t];
        for (int k = 0; k < 3; k++)
            if (ix[k] >= mesh->vertex_count)
                return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s': triangle %u names "
                                 "vertex %u of %u",
                                 path, t, ix[k], mesh->vertex_count);
        if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2])
            return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s': triangle %u repeats a "
                             "vertex (%u %u %u)",
                             path, t, ix[0], ix[1], ix[2]);
    }
    if (mesh->vertex_count > (uint32_t)INT32_MAX)
        return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s': %u vertices are more than a "
                         "PLY int index holds",
                         path, mesh->vertex_count);
    std::vector<char> name(std::strlen(path) + 32);
    int fd = files_create_temporary(path, ".ply", name.data(), name.size());
    if (fd < 0)
        return -1;
    FILE *f = fdopen(fd, "wb");
    if (!f) {
        int saved = errno;
        close(fd);
        unlink(name.data());
        return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s': %s", path, strerror(saved));
    }
    bool ok = write_ply_file(f, mesh, values, value_name, colors);
    int saved = errno;
    ok = std::fclose(f) == 0 && ok;
    if (!ok || rename(name.data(), path) != 0) {
        if (ok)
            saved = errno;
        unlink(name.data());
        return error_set(IDMR_EXIT_FAILURE, "cannot write mesh '%s': %s", path,
                         saved ? strerror(saved) : "a write failed");
    }
    return 0;
}
