/* mesh_text.h — strict readers of the two text mesh formats, OBJ and OFF, behind mesh_io_read()
 * (which sends every other format to OpenMesh). They exist because OpenMesh's readers lose or
 * invent data without a word on files real exporters write: a NaN vertex line is skipped (later
 * indices shift onto the wrong vertices), faces with indices out of range are dropped, an OFF
 * header's face count is trusted over the file, and an OBJ vertex gets one texture coordinate
 * and one normal however many its faces give it.
 *
 *   OBJ  v (x y z [w]), vt (u [v [w]]), vn (x y z), f with corners i, i/j, i//k or i/j/k
 *        (negative: relative to the elements defined so far); polygons are fan-triangulated.
 *        A vertex of the result is one distinct (v, vt, vn) triple, as in Mitsuba 3's reader,
 *        so seams and creases stay split. When some corners give a texture coordinate or a
 *        normal and others do not, the others get (0, 0) or a zero normal. Every other
 *        statement (o, g, s, usemtl, mtllib, l, p, comments) is ignored.
 *   OFF  "OFF" (or COFF, NOFF, CNOFF: the extra per-vertex values are ignored), the counts
 *        "vertices faces edges", the vertex lines (x y z ...), the face lines (n i1 .. in
 *        [colour]); # starts a comment. Polygons are fan-triangulated.
 * Errors name the file and line (set with error.h, IDMR_EXIT_INPUT): a number that is not
 * finite or not a number, an index of 0 or one that names an element not defined before it, a
 * face with fewer than 3 corners, an OFF file that holds fewer vertices or faces than its
 * header says, more than 2^32 - 1 vertices or triangles. (A file without faces reads as an
 * empty mesh; mesh_io_read() says so, for every format.) */
#ifndef IDMR_MESH_TEXT_H
#define IDMR_MESH_TEXT_H

#include "core/mesh_data.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Read `path` into `out` (zeroed first, freed on failure). 0, or -1 with the error set. */
int mesh_text_read_obj(const char *path, mesh_data *out);
int mesh_text_read_off(const char *path, mesh_data *out);

#ifdef __cplusplus
}
#endif

#endif
