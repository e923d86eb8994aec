/* mesh_io.h — reading and writing triangle meshes from C (the bridge to OpenMesh, which reads
 * what idmr has no reader of its own for).
 *
 * OBJ and OFF are read by idmr's own strict readers (io/mesh/mesh_text.h: errors with file and
 * line, one vertex per distinct OBJ (v, vt, vn) corner), PLY (ascii and binary) by its own
 * (io/mesh/ply_check.h: every value checked, the vertices and faces exactly as the file has them),
 * STL by its own (io/mesh/mesh_stl.h: no texture coordinates or normals, errors with the line or
 * byte offset); OM by OpenMesh, which builds a half-edge mesh: a vertex where the surface is
 * not manifold is split into copies, so vertex_count may exceed the file's. Polygons are
 * fan-triangulated. Positions are as stored in the file (object space).
 *
 * Triangles that repeat a vertex (an OBJ's "f 1 2 1", a PLY face "3 0 1 0", the zero-area
 * joins of a triangle strip, an STL facet with two corners at one position) are dropped on
 * every format and counted in triangles_dropped: they have no area, so they change no image,
 * and no half-edge mesh can hold them (OpenMesh's add_face aborts on one). A vertex that only
 * they used goes with them. Every position, texture coordinate and normal read is finite, or
 * the read fails naming the file. The record read into, mesh_data, and mesh_data_free() are
 * declared in core/mesh_data.h. */
#ifndef IDMR_MESH_IO_H
#define IDMR_MESH_IO_H

#include <stdint.h>

#include "core/mesh_data.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads `path` into `out`. Returns 0, or -1 with the error set (error.h) naming the file:
 * missing, unreadable, unknown format, or no triangles. `out` is zeroed on failure. */
int mesh_io_read(const char *path, mesh_data *out);

/* As mesh_io_read(); in addition, when `orient` is set and the file has vertex normals, every
 * triangle is wound so that its geometric normal agrees with the sum of its vertex normals
 * (Mitsuba takes a mesh's front side — where area lights emit and one-sided bsdfs reflect —
 * from its normals, which some files give against the winding). *flipped (may be NULL) gets
 * the number of triangles turned. */
int mesh_io_read_oriented(const char *path, mesh_data *out, int orient, uint32_t *flipped);

/* Writes `mesh` as a binary little-endian PLY: vertex x y z, then nx ny nz and u v where it has
 * normals and texture coordinates, red green blue (uchar) with `colors` (3 bytes per vertex, may
 * be NULL), and a float property `value_name` with `values` (may be NULL); faces as a list
 * vertex_indices (uchar count, int index). Every triangle is written as given, on the vertices
 * given: idmr's own writer, not OpenMesh's, whose half-edge mesh gave the faces of a
 * non-manifold spot (a double-sided sheet's second layer) copies of their vertices, so a file
 * held more vertices than the mesh. A triangle that repeats a vertex or names one out of range
 * is refused (mesh_io_read() never gives one). The file is written under a temporary name,
 * every write and the close checked, and renamed. Returns 0, or -1 with the error set. */
int mesh_io_write_ply(const char *path, const mesh_data *mesh, const float *values,
                      const char *value_name, const unsigned char *colors);

/* Turns OpenMesh's own log output off (idmr reports what matters itself); idempotent and
 * thread-safe. Reading a mesh and decimating call it. */
void mesh_io_silence_openmesh_logs(void);

#ifdef __cplusplus
}
#endif

#endif
