/* mesh_io.h — the OpenMesh bridge: reading and writing triangle meshes from C.
 *
 * OBJ and OFF are read by idmr's own strict readers (io/mesh_text.h: errors with file and
 * line, one vertex per distinct OBJ (v, vt, vn) corner); every other format OpenMesh reads (PLY
 * ascii/binary, after io/ply_check.h has proven it well formed; STL, OM) by OpenMesh, which
 * builds a half-edge mesh: a vertex where the surface
 * is not manifold is split into copies, so vertex_count may exceed the file's. Polygons are
 * fan-triangulated. Positions are as stored in the file (object space). */
#ifndef IDMR_MESH_IO_H
#define IDMR_MESH_IO_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mesh_data {
    uint32_t vertex_count;
    uint32_t triangle_count;
    float *positions;  /* xyz per vertex, malloc'd */
    uint32_t *indices; /* three per triangle, malloc'd */
    float *texcoords;  /* uv per vertex if the file has them, else NULL; malloc'd */
    float *normals;    /* xyz per vertex if the file has them (not normalised), else NULL;
                        * malloc'd */
} mesh_data;

/* Reads `path` into `out`. Returns 0, or -1 with the error set (error.h) naming the file:
 * missing, unreadable, unknown format, or no triangles. `out` is zeroed on failure. */
int mesh_io_read(const char *path, mesh_data *out);

/* As mesh_io_read(); in addition, when `orient` is set and the file has vertex normals, every
 * triangle is wound so that its geometric normal agrees with the sum of its vertex normals
 * (Mitsuba takes a mesh's front side — where area lights emit and one-sided bsdfs reflect —
 * from its normals, which some files give against the winding). *flipped (may be NULL) gets
 * the number of triangles turned. */
int mesh_io_read_oriented(const char *path, mesh_data *out, int orient, uint32_t *flipped);

/* Writes `mesh` as a binary PLY through OpenMesh, with its texture coordinates (u, v) and
 * normals (nx, ny, nz) where it has them, an optional per-vertex float property `value_name`
 * (values may be NULL) and optional per-vertex RGB colours (colors: 3 bytes per vertex, may be
 * NULL). The file is written under a temporary name and renamed. A face that
 * OpenMesh cannot attach (a non-manifold spot) is written with copies of its vertices, as
 * OpenMesh's reader does. Returns 0, or -1 with the error set. */
int mesh_io_write_ply(const char *path, const mesh_data *mesh, const float *values,
                      const char *value_name, const unsigned char *colors);

/* Frees what mesh_io_read() allocated; `mesh` may be NULL. */
void mesh_data_free(mesh_data *mesh);

/* Turns OpenMesh's own log output off (idmr reports what matters itself); idempotent and
 * thread-safe. Reading a mesh and decimating call it. */
void mesh_io_silence_openmesh_logs(void);

#ifdef __cplusplus
}
#endif

#endif
