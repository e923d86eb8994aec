/* ply_check.h — proves a PLY file well formed before OpenMesh reads it. OpenMesh's PLY reader
 * trusts its input: it loops forever on a file cut off inside its header or on a NUL in an
 * element count, crashes on a property declared before any element, and misreads or runs away
 * on a face whose corner count disagrees with the data that follows (all found by fuzzing,
 * tests/fuzz/regressions/ply). So idmr reads the file once itself, keeping nothing:
 *
 *   header   "ply", one "format ascii|binary_little_endian|binary_big_endian 1.0", then
 *            "element NAME COUNT" (COUNT below 2^32), "property TYPE NAME" and
 *            "property list COUNT_TYPE TYPE NAME" (an integer count type) after an element,
 *            "comment" and "obj_info" lines, "end_header"; no other line, no control character,
 *            at most 64 KiB
 *   body     every value the header promises is there; an ascii integer is a whole number that
 *            fits its type, every number is finite; a face's vertex_indices (or vertex_index)
 *            list has at least 3 corners, each an index below the vertex count
 *
 * Data after the last element is left alone, as OpenMesh and Mitsuba 3 leave it. Returns 0, or
 * -1 with the error set (IDMR_EXIT_INPUT) naming the file and the header line, the body line
 * (ascii) or the element. */
#ifndef IDMR_PLY_CHECK_H
#define IDMR_PLY_CHECK_H

int ply_check(const char *path);

/* The same check on a PLY idmr has just written (mesh_io_write_ply): OpenMesh's writer does not
 * report a failed write, so a file cut short by a full disk or a file size limit would pass as
 * written. A file that fails the check is removed. 0, or -1 with the error set
 * (IDMR_EXIT_FAILURE: "cannot write mesh", naming the file and what is wrong with it). */
int ply_check_written(const char *path);

#endif
