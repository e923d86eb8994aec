/* ply_check.h — idmr's PLY reader. It began as a check that proved a file well formed before
 * OpenMesh read it (OpenMesh's PLY reader trusts its input: it loops forever on a file cut off
 * inside its header or on a NUL in an element count, crashes on a property declared before any
 * element, and misreads or runs away on a face whose corner count disagrees with the data that
 * follows; all found by fuzzing, tests/fuzz/regressions/ply). Since the check read every value
 * anyway, it now keeps what a mesh needs: OpenMesh's reader also split every vertex where the
 * surface is not manifold into copies (a double-sided sheet read back with twice its vertices,
 * the copies' normals left uninitialised), and lost triangles of files with more face
 * properties than it expected.
 *
 *   header   "ply", one "format ascii|binary_little_endian|binary_big_endian 1.0", then
 *            "element NAME COUNT" (COUNT below 2^32), "property TYPE NAME" and
 *            "property list COUNT_TYPE TYPE NAME" (an integer count type) after an element,
 *            "comment" and "obj_info" lines, "end_header"; no other line, no control character,
 *            at most 64 KiB
 *   body     every value the header promises is there; an ascii integer is a whole number that
 *            fits its type, every number is finite; a face's vertex_indices (or vertex_index)
 *            list has at least 3 corners, each an index below the vertex count
 *   kept     (ply_read) of the element "vertex": x, y, z; nx, ny, nz where all three are
 *            declared; u, v (or s, t, texture_u, texture_v, texture_s, texture_t) where both
 *            are; of the element "face": its vertex_indices lists, fan-triangulated. Every other
 *            element and property (colours, a face's second list, flags) is read, checked and
 *            left. A vertex value beyond a float's range is an error.
 *
 * Data after the last element is left alone, as OpenMesh and Mitsuba 3 leave it. Both return 0,
 * or -1 with the error set (IDMR_EXIT_INPUT) naming the file and the header line, the body line
 * (ascii) or the element. */
#ifndef IDMR_PLY_CHECK_H
#define IDMR_PLY_CHECK_H

#include "core/mesh_data.h"

/* Proves `path` well formed, keeping nothing. */
int ply_check(const char *path);

/* Reads `path` into `out` (zeroed first, freed on failure): the vertices in file order, the
 * faces fan-triangulated in file order; a file without a vertex element, or one without x, y
 * and z, is an error. Triangles that repeat a vertex are kept (mesh_io_read() drops them). */
int ply_read(const char *path, mesh_data *out);

/* The same check on a PLY idmr has just written (mesh_io_write_ply): a second line behind the
 * writer's own checks: a file cut short by a full disk or a file size limit never passes as
 * written. A file that fails the check is removed. 0, or -1 with the error set
 * (IDMR_EXIT_FAILURE: "cannot write mesh", naming the file and what is wrong with it). */
int ply_check_written(const char *path);

#endif
