/* mesh_stl.h — idmr's own STL reader, behind mesh_io_read(). OpenMesh's reader had three faults
 * on files real exporters write: it left texture coordinates and vertex normals that an STL file
 * never has in the mesh (uninitialised: the reduction stalled on them and the written PLY held
 * NaN uv), it loaded the facets before the cut of a truncated ASCII file without a word, and it
 * refused a binary file whose facet count disagrees with its size as "has no faces".
 *
 *   binary  an 80-byte header, a little-endian uint32 facet count N, then N records of 50 bytes
 *           (normal, three vertices: 12 little-endian floats; a 2-byte attribute count, ignored);
 *           the file is exactly 84 + 50 N bytes long
 *   ASCII   "solid [name]", then per facet "facet normal nx ny nz", "outer loop", three
 *           "vertex x y z", "endloop", "endfacet", and "endsolid [name]"; keywords in any case,
 *           several solids one after another; the facet normal is read and ignored (exporters
 *           write NaN there for degenerate facets)
 * A file is ASCII when it starts with "solid" and its first bytes are text, and its size is not
 * that of a binary file whose header starts with "solid" (some exporters write such headers).
 *
 * Vertices at bit-identical positions (-0 and 0 alike) are one vertex, in order of first
 * appearance, as OpenMesh's reader welds them; so a facet with two corners at one position
 * becomes a triangle that repeats a vertex (mesh_io_read() drops and counts those). The mesh has
 * no texture coordinates and no normals. Errors (error.h, IDMR_EXIT_INPUT) name the file and
 * where: the line of an ASCII file (a vertex coordinate that is not a finite number, a keyword
 * out of place, a file that ends inside a facet or a solid), the facet and byte offset of a
 * binary one (a coordinate that is not finite), or the byte counts of a binary file whose size
 * disagrees with its facet count. */
#ifndef IDMR_MESH_STL_H
#define IDMR_MESH_STL_H

#include "core/mesh_data.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads `path` into `out` (zeroed first, freed on failure). 0, or -1 with the error set. */
int mesh_stl_read(const char *path, mesh_data *out);

#ifdef __cplusplus
}
#endif

#endif
