/* mesh_data.h — the neutral triangle-mesh record: what every mesh reader fills (io/mesh/: the
 * OpenMesh bridge mesh_io.h, the OBJ/OFF, STL and PLY readers), what the built-in shapes are
 * tessellated into (core/shapes.h), and what the scene writers and the decimation take. Plain C
 * arrays, no library behind them, so no reader or bridge needs another for the record. */
#ifndef IDMR_MESH_DATA_H
#define IDMR_MESH_DATA_H

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
    uint32_t triangles_dropped; /* mesh_io_read(): triangles of the file that repeat a vertex,
                                   left out (see io/mesh/mesh_io.h) */
} mesh_data;

/* Frees what mesh_io_read() allocated; `mesh` may be NULL. */
void mesh_data_free(mesh_data *mesh);

#ifdef __cplusplus
}
#endif

#endif
