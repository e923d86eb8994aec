// decimate_stock.cc — decimate_stock_quadric() (see decimate.h), the benchmark's baseline: stock
// OpenMesh, DecimaterT with ModQuadricT and nothing else, on the mesh as OpenMesh builds it (no
// welding, no patching: faces that do not attach are left out).
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <exception>
#include <vector>

#include "reduce/decimate_openmesh.hh"

extern "C" {
#include "core/error.h"
}

using idmr_decimate::Mesh;

extern "C" long decimate_stock_quadric(const decimate_input *in)
{
    try {
        Mesh mesh;
        std::vector<Mesh::VertexHandle> handles(in->vertex_count);
        for (uint32_t v = 0; v < in->vertex_count; v++) {
            const float *p = &in->positions[3 * (size_t)v];
            handles[v] = mesh.add_vertex(Mesh::Point(p[0], p[1], p[2]));
        }
        for (uint32_t t = 0; t < in->triangle_count; t++) {
            const uint32_t *ix = &in->indices[3 * (size_t)t];
            if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2])
                continue; // add_face aborts on a face that repeats a vertex
            mesh.add_face(handles[ix[0]], handles[ix[1]], handles[ix[2]]);
        }
        OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
        OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
        decimater.add(quadric);
        if (!decimater.initialize()) // exactly one priority module, as in decimate.cc
            return error_set(IDMR_EXIT_FAILURE, "mesh '%s': DecimaterT did not initialise",
                             in->name);
        decimater.decimate_to((size_t)in->target_vertices);
        mesh.garbage_collection();
        return (long)mesh.n_vertices();
    } catch (const std::exception &e) {
        return error_set(IDMR_EXIT_FAILURE, "mesh '%s': OpenMesh failed: %s", in->name, e.what());
    }
}
