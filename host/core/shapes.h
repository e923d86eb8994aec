/* shapes.h — tessellation of Mitsuba's built-in shapes into triangle meshes (object space).
 *
 * Each function fills a mesh_data (core/mesh_data.h, the same record a mesh file is read into)
 * with malloc'd arrays; the loader then transforms it to world space and hands the arrays to
 * the scene. All surfaces are wound counter-clockwise seen from the side their geometric
 * normal points to (outward for closed shapes), and closed shapes share their vertices
 * (watertight, so the decimator sees no seams):
 *   rectangle  [-1,1]² in z = 0, normal +z, 4 vertices, 2 triangles, uv = (x+1)/2, (y+1)/2
 *   cube       [-1,1]³, 8 vertices, 12 triangles
 *   disk       unit disk in z = 0, normal +z: a centre vertex and `segments` rim vertices
 *   sphere     UV sphere about `center`, poles on ±z: 2 + (rings-1)·segments vertices,
 *              2·segments·(rings-1) triangles (1984 with the default 32 × 32), with radial
 *              vertex normals (Mitsuba's sphere is smooth); the others have none (flat). */
#ifndef IDMR_SHAPES_H
#define IDMR_SHAPES_H

#include "core/scene.h"
#include "core/mesh_data.h"
#include "core/xform.h"

#define SHAPES_DISK_SEGMENTS 64
#define SHAPES_SPHERE_RINGS 32
#define SHAPES_SPHERE_SEGMENTS 32

void shapes_rectangle(mesh_data *out);
void shapes_cube(mesh_data *out);
/* segments >= 3 */
void shapes_disk(unsigned int segments, mesh_data *out);
/* rings >= 2, segments >= 3 */
void shapes_sphere(const double center[3], double radius, unsigned int rings, unsigned int segments,
                   mesh_data *out);

/* Reverses every triangle's winding (Mitsuba's flip_normals). */
void shapes_flip_winding(mesh_data *mesh);

/* Reverses every normal (if any). After shapes_transform() under a mirroring transform it
 * turns the cofactor-transformed normals (xform_apply_normals) into the inverse transpose's,
 * the surface's side kept. */
void shapes_reverse_normals(mesh_data *mesh);

/* Applies `to_world` to the positions (and the normals, if any: xform_apply_normals); the
 * winding is kept. (For built-in shapes Mitsuba
 * transforms the normal, so a mirroring transform needs shapes_flip_winding() as well; for
 * mesh files Mitsuba's geometric normal follows the winding, so they are left alone.) */
void shapes_transform(mesh_data *mesh, const xform *to_world);

/* Moves geometry by `to_world` as Mitsuba moves a built-in shape or an instance: points by it,
 * normals by its inverse transpose, and under a mirror the winding flipped (the surface keeps
 * its side). Its inverse moves the geometry back exactly so (up to rounding). */
void shapes_transform_keeping_side(mesh_data *mesh, const xform *to_world);

/* Replaces the mesh's normals by smooth vertex normals, as Mitsuba computes them for a mesh
 * file without normals that is not marked face_normals: at each vertex the unit normals of the
 * triangles around it, weighted by the triangle's angle at that vertex (Thürmer and Wüthrich
 * 1998: independent of how a flat region is triangulated). Zero-area triangles add nothing; a
 * vertex only they touch gets a zero normal (the kernels then shade it flat). */
void shapes_smooth_normals(mesh_data *mesh);

/* The scene mesh's arrays (positions, indices, uv, normals) as a mesh_data that does not own
 * them: never mesh_data_free() it. */
mesh_data shapes_scene_mesh_view(const scene_mesh *m);

/* Whether the mesh's normals shade it flat: at every corner of every triangle of non-zero area
 * the normal is within about 0.8 degrees of the triangle's geometric normal (cosine at least
 * SHAPES_FLAT_COS; a zero normal, which the kernels shade flat, counts as flat). A mesh split
 * at every edge to carry face normals (an OBJ with one vn per face) is; 0 without normals. */
#define SHAPES_FLAT_COS 0.9999
int shapes_normals_flat(const mesh_data *mesh);

/* Signed volume enclosed by a closed mesh (positive when wound outward); for tests. */
double shapes_signed_volume(const mesh_data *mesh);

#endif
