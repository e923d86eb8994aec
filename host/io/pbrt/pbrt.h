/* pbrt.h — pbrt-v4 scenes (.pbrt): the reader (a file in, a world-space scene out) and
 * the writer of a reduced scene (the input text with reduced shapes swapped for PLY files).
 *
 * What is read (host/io/pbrt/pbrt_loader.h lists the files; README "pbrt-v4 scenes" says it for
 * users):
 *   statements  Include, Import (as Include), AttributeBegin/End, TransformBegin/End, Identity,
 *               Translate, Scale, Rotate, LookAt, CoordinateSystem, CoordSysTransform,
 *               Transform, ConcatTransform, ReverseOrientation, WorldBegin (WorldEnd of v3 is
 *               accepted), Camera "perspective", Film (xresolution, yresolution),
 *               MakeNamedMaterial, NamedMaterial, Material, Texture, Shape, AreaLightSource,
 *               LightSource, ObjectBegin/End, ObjectInstance (an object's shapes held
 *               once: later instances add copies without geometry, core/scene.h).
 *               Statements for what idmr does not simulate (Integrator, Sampler,
 *               PixelFilter, ColorSpace, Option, media,
 *               Attribute, ActiveTransform, TransformTimes, ...) are warned about once.
 *   materials   diffuse, coateddiffuse, conductor, coatedconductor, dielectric, thindielectric,
 *               diffusetransmission, interface, mix, mapped onto idmr's four kinds
 *               (pbrt_material.c says how; a mapping that loses something is warned once).
 *   shapes      trianglemesh, plymesh (ASCII and binary PLY; gzipped PLY is refused),
 *               bilinearmesh (two triangles per patch), sphere and disk (tessellated),
 *               loopsubdiv (its control mesh, warned); curve, cylinder, cone, paraboloid and
 *               hyperboloid are warned about and left out.
 *   lights      AreaLightSource "diffuse", LightSource point, spot, distant, infinite
 *               (constant L, or an image: pbrt's equal-area octahedral map is resampled to
 *               idmr's equirectangular environment); goniometric and projection lights are
 *               warned about and left out.
 * Relative paths resolve from the directory of the scene file, as pbrt-v4 resolves them (also
 * in included files). Errors name the file and line ("file:line: Statement: what") and the load
 * fails; a warning names the first file and line it applies to.
 *
 * Per mesh, the loader records for the writer: xml_file (the file holding the Shape
 * statement), xml_line (its line), source_offset (the byte offset of its `Shape` keyword),
 * object_to_world (the transform its points were given in: the CTM at the Shape statement, an
 * instance's transform in front) and source_flipped (the loader reversed the winding the file
 * gives). */
#ifndef IDMR_PBRT_H
#define IDMR_PBRT_H

#include <stddef.h>

#include "core/scene.h"
#include "core/mesh_data.h"

/* Whether `path` names a pbrt scene (ends in .pbrt). */
int pbrt_is_scene_file(const char *path);

/* Loads `path` and returns the finalized scene, or NULL with the error set (IDMR_EXIT_INPUT for
 * bad input). */
scene *pbrt_load(const char *path);

/* The reduced world-space `world` mesh of scene mesh `m` put back into the space its Shape
 * statement gives points in (the inverse of m->object_to_world, in double), with the winding,
 * normals and texture coordinates as pbrt reads them, so the statement keeps its place under its
 * own transform and ReverseOrientation. *out owns new arrays (mesh_data_free). 0, or -1 with the
 * error set when the transform cannot be inverted. */
int pbrt_mesh_to_object_space(const scene_mesh *m, const mesh_data *world, mesh_data *out);

typedef struct pbrt_replacement {
    const char *file; /* scene_mesh.xml_file of the shape */
    long offset;      /* scene_mesh.source_offset */
    int line;         /* scene_mesh.xml_line (for messages) */
    const char *ply;  /* the new mesh, relative to outdir, e.g. "meshes/Mesh013.ply" */
} pbrt_replacement;

/* Writes outdir/scene.pbrt: the scene file's text with each replaced Shape statement turned
 * into `Shape "plymesh" "string filename" [ "<ply>" ]` (its non-geometric parameters kept as
 * written) and every relative path (textures, PLYs not replaced, spectrum files, Includes)
 * rewritten to resolve from outdir (absolute where no relative form exists). An included file
 * that holds a replaced shape, a relative path, or an Include of such a file is written as a
 * rewritten copy under outdir/includes/ and included from there; other included files are
 * named by their path. Every file goes through a temporary name and rename(); the input is
 * never written. Two replacements of one statement (the meshes of an instanced object) keep
 * the first, with a warning. 0, or -1 with the error set. */
int pbrt_write_reduced(const char *scene_file, const char *outdir,
                       const pbrt_replacement *replacements, size_t count);

#endif
