/* gltf.h — glTF 2.0 scenes (.gltf, .glb) in and out, through Assimp: the second scene format
 * beside Mitsuba XML (io/mitsuba/mitsuba.h, the primary one).
 *
 * Reading (gltf_load): the file is read as its own document and checked as the glTF
 * specification says (io/gltf/gltf_validate.h: what Assimp 5.2 would drop, misread or crash on is
 * refused, naming the file and the JSON pointer, line and column, or GLB byte at fault); then
 * Assimp imports it (triangulated, primitives sorted by type); lights and the camera are read
 * from the document at the nodes of the default scene, and texture coordinates of normalized
 * integers (which Assimp 5.2 garbles) from its accessors. Loading shows progress once it has
 * taken a second, unless the command line said --quiet (core/progress.h).
 * Every node that holds a triangle mesh gives one scene mesh per mesh it holds (an instance),
 * in world space (the node's transforms applied, the winding turned where they mirror), named
 * "<node>/<mesh>" and numbered in the order of a depth-first walk from the root: its xml_file is
 * the glTF file and its xml_line that number, which the writer finds it by. What is mapped:
 *
 *   glTF                              idmr
 *   POSITION, NORMAL, TEXCOORD_0      positions, shading normals, uv (no NORMAL: shaded flat,
 *                                     as glTF says; v as Mitsuba reads it, 1 - Assimp's)
 *   pbrMetallicRoughness:
 *     transmission >= 0.5             dielectric, int_ior = KHR_materials_ior (1.5)
 *     (KHR_materials_transmission)    (rough glass as smooth, as the Mitsuba loader does)
 *     metallic >= 0.5                 conductor: base colour as specular, GGX alpha = rough²;
 *                                     alpha < 0.001: a mirror
 *     roughness >= 0.5                diffuse, base colour (and its texture)
 *     otherwise                       roughplastic: base colour (and texture) diffuse, white
 *                                     specular, alpha = roughness², int_ior as above
 *   doubleSided                       two-sided
 *   emissiveFactor (× strength)       an area light of that radiance on the mesh
 *   baseColorTexture                  a texture (sRGB, linearised); embedded images are not
 *                                     read (warned: the base colour factor is used)
 *   KHR_lights_punctual point, spot,  point, spot (inner/outer cone), directional, one for each
 *   directional                       node that names it; colour × intensity (cd, lx) taken as
 *                                     W/sr, W/m² one for one, as glTF viewers render it
 *   no light, no emissive material    a uniform white environment, radiance 1 (warned)
 *   camera (perspective, the first    the pinhole camera: yfov, aspect ratio (film 1024 wide;
 *   a node holds, depth first)        --resolution scales it); none: the whole scene framed
 *                                     from +z with a 45° yfov (warned)
 * Orthographic cameras, skins, morph targets and animations are not simulated (warned).
 *
 * Writing (gltf_write_reduced, gltf_write.c): the input's own JSON document is rewritten
 * (cJSON), not exported by Assimp: every node, camera, light, material, texture, sampler,
 * animation, extension and extras comes out as it went in. Only the replaced instances change:
 * each becomes its primitive's POSITION (with min and max), NORMAL and TEXCOORD_0 (where the
 * reduced mesh has them) and indices, in its node's local space, every vertex the reduction
 * kept written (nothing welded); other vertex channels such as tangents and colours, and
 * morph targets, are dropped with a warning, since they no longer match. A mesh that nodes
 * share stays shared by the nodes left alone; a node whose instances were replaced writes into
 * a copy of its own unless every node naming the mesh was replaced, and a node whose
 * replacements are all shared names the mesh of the node that writes them. Data no longer referenced
 * is dropped and the rest written into outdir/scene.bin beside outdir/scene.gltf, or the BIN
 * chunk of outdir/scene.glb, as the input was (with an extension whose references are unknown,
 * nothing is renumbered: the input's buffers stay and the new data is added). Relative texture
 * paths are rewritten relative to outdir (absolute where none exists; with bundle, copies
 * under outdir/assets/). outdir is the staging directory that `idmr reduce` publishes whole
 * (reduce_stages.h), so no reader sees a half-written file. */
#ifndef IDMR_GLTF_H
#define IDMR_GLTF_H

#include <stddef.h>

#include "core/scene.h"
#include "core/mesh_data.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Whether `path` names a glTF file (.gltf or .glb, any case). */
int gltf_is_scene_file(const char *path);

/* Loads `path` and returns the finalized scene, or NULL with the error set (IDMR_EXIT_INPUT)
 * naming the file, where it is wrong and why (or Assimp's reason). */
scene *gltf_load(const char *path);

typedef struct gltf_replacement {
    int instance;          /* scene_mesh.xml_line of the mesh */
    const mesh_data *mesh; /* its reduced triangles, world space */
    /* 1: the instance is a copy of a primitive that another node's replacement reduces (its
     * reduction moved: reduce/reduce_instances.c); its node names that node's mesh, and `mesh`
     * is not read. */
    int shared;
} gltf_replacement;

/* The reduced scene's name in outdir: "scene.glb" for a .glb input, else "scene.gltf". */
const char *gltf_output_name(const char *scene_file);

/* Writes outdir/gltf_output_name(scene_file) (and outdir/scene.bin for a .gltf; see above);
 * with `bundle`, every texture file is copied to outdir/assets/ and named there. Returns 0, or
 * -1 with the error set naming the file (and the JSON path or byte offset where the input is at
 * fault). */
int gltf_write_reduced(const char *scene_file, const char *outdir,
                       const gltf_replacement *replacements, size_t count, int bundle);

#ifdef __cplusplus
}
#endif

#endif
