/* mitsuba_write.h — the reduced scene's XML: the input Mitsuba document with reduced meshes
 * swapped in.
 *
 * The input is read again as a raw libxml2 tree (blanks, comments, <default> elements and
 * $name references kept; none of the loader's substitution or camelCase normalisation), edited
 * in place and written to outdir/scene.xml, so the output reads like the input:
 *
 *   replaced shape  (found by the file and line of its <shape> element, as the loader records
 *                   them in scene_mesh.xml_file/xml_line) becomes type="ply" with
 *                   <string name="filename" value="<ply>"/> (an existing filename property is
 *                   overwritten, else one is added as the first child). Removed: to_world /
 *                   toWorld (the PLY holds world-space positions) and flip_normals /
 *                   flipNormals (the PLY holds the loader's final winding, a flip is baked in);
 *                   for a sphere its center and radius; for an obj its flip_tex_coords,
 *                   shape_index and collapse (obj-only properties, which Mitsuba 3 would reject
 *                   on a ply). Everything else (bsdf, emitter, refs, id, comments) is kept.
 *   instances       shapegroups and instances stay as written. A replaced shape inside a
 *                   shapegroup is edited as any replaced shape; its PLY holds the group's own
 *                   space (the caller moves the reduced geometry there: reduce_instances.c),
 *                   and every instance places it.
 *   paths           every other relative path — a property named filename (<string
 *                   name="filename" value=...>, for meshes, bitmaps, envmaps, ...) and every
 *                   filename="..." attribute (<spectrum filename>, <include filename>) — is
 *                   resolved as the loader resolves it (the naming file's directory, then the
 *                   scene's) to a file (realpath; a path that resolves to nothing: the absolute
 *                   form of the loader's first candidate), and rewritten relative to outdir,
 *                   in the scene and in the copies under includes/ alike: Mitsuba 3 resolves
 *                   every document's paths from the scene's directory, idmr's loader from the
 *                   naming document's and then the scene's. So an output folder beside its
 *                   input (or inside the same tree) can be moved with it. The path is written
 *                   absolute instead when outdir and the file share no directory below the
 *                   root, or when idmr's loader would find another file through the relative
 *                   form. Absolute paths stay as written. A value holding $name references is
 *                   resolved with the <default> values (collected as the loader does: per file,
 *                   in include order, the first definition wins) and written resolved; one that
 *                   names an undefined parameter is left unchanged (the loader rejects such a
 *                   scene anyway).
 *   bundle          (bundle != 0) every file a path names (relative or absolute: textures,
 *                   envmaps, meshes not replaced) is copied to outdir/assets/<base name> (made
 *                   unique with -2, -3, ...; one copy per file) and named "assets/<name>", and
 *                   every fragment is copied under includes/: outdir then holds all the scene
 *                   reads and can be moved or sent anywhere. A copy that would replace a file
 *                   the scene reads is refused.
 *   includes        a fragment is written as a rewritten copy under outdir/includes/ (its base
 *                   name, made unique with -2, -3, ... before the extension) when it holds a
 *                   replaced shape, when it includes a fragment that is copied, or when one of
 *                   its relative paths resolved only through the scene's directory (it would no
 *                   longer resolve from outdir); the <include> then names "includes/<name>".
 *                   Other fragments stay where they are and are included by their path
 *                   (relative, as above). A fragment included twice is copied once.
 * Paths written into the output (the PLY, the copies) are relative to outdir, the scene's
 * directory: Mitsuba's file resolver finds them from there, and so does idmr's loader, whose
 * second candidate is the scene's directory.
 *
 * Line numbers are counted exactly as the loader counts them (same parser options), so a
 * replacement names a <shape> by what mitsuba_load() recorded. */
#ifndef IDMR_MITSUBA_WRITE_H
#define IDMR_MITSUBA_WRITE_H

#include <stddef.h>

typedef struct mitsuba_replacement {
    const char *xml_file; /* scene_mesh.xml_file of the shape */
    int xml_line;         /* scene_mesh.xml_line */
    const char *ply;      /* the new mesh, relative to outdir, e.g. "meshes/knot.ply" */
    int face_normals;     /* the mesh is shaded flat: the shape says face_normals */
} mitsuba_replacement;

/* Writes outdir/scene.xml (and outdir/includes/ copies where needed, outdir/assets/ with
 * `bundle`; see above) for the scene file `scene_file` with `count` shapes replaced. outdir
 * must exist; the input files are never written; every file goes through a temporary name and
 * rename(), the scene last. Returns 0, or -1 with the error set naming the file (and line):
 * unreadable or malformed XML, an unresolvable include, a replacement whose file:line matches
 * no <shape> element (or more than one), two replacements of one shape, a failed write or
 * copy. */
int mitsuba_write_reduced(const char *scene_file, const char *outdir,
                          const mitsuba_replacement *replacements, size_t count, int bundle);

#endif
