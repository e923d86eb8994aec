/* mitsuba_write_shape.h — one edit of the reduced-scene writer: a <shape> element of a raw
 * Mitsuba tree turned into a reference to its reduced, world-space PLY (mitsuba_write.h says
 * what is removed and what is kept), indented as the element's siblings are; elements inserted
 * and unlinked with their indentation. */
#ifndef IDMR_MITSUBA_WRITE_SHAPE_H
#define IDMR_MITSUBA_WRITE_SHAPE_H

#include <libxml/tree.h>

/* Makes `shape` type="ply" with <string name="filename" value="ply"/> (an existing filename
 * property is overwritten, else one is added as the first child) and removes the properties
 * that a world-space PLY no longer has. A rectangle, cube or disk gets face_normals (the PLY
 * carries no normals, and they are flat), as does any shape when `face_normals` is set. */
void mitsuba_shape_to_ply(xmlNodePtr shape, const char *ply, int face_normals);

/* Inserts `element` (a copy of `indented_as`) before `sibling`, indented as `sibling` is, its
 * inner lines moved with it. */
void mitsuba_insert_before(xmlNodePtr sibling, xmlNodePtr element, xmlNodePtr indented_as);

/* Unlinks `node` from its tree with the blank text before it (its indentation, freed); the
 * node itself is not freed (the caller frees it: xmlFreeNode). */
void mitsuba_unlink_with_indent(xmlNodePtr node);

#endif
