/* gltf_validate.h — a glTF 2.0 document (io/gltf/gltf_document.h) checked as the specification says
 * before Assimp reads it: Assimp 5.2 drops triangles whose indices are out of range, reads
 * bytes of any component type as floats, takes a byteStride shorter than the element, and
 * ignores extensionsRequired, all without a word. What is checked:
 *
 *   structure     every top-level array of objects; asset.version 2.x; no JSON object with a
 *                 member named twice; every reference an index that exists (scene, nodes,
 *                 meshes, accessors, bufferViews, buffers, materials, textures, images,
 *                 samplers, skins, cameras, lights, animation samplers)
 *   extensions    extensionsRequired names only extensions idmr reads (KHR_draco_mesh_
 *                 compression, which Assimp decodes; lights, materials, texture transforms,
 *                 XMP; texture formats and WebGL techniques with a warning: such textures are
 *                 not read, such shaders not run); meshopt compression, mesh quantization, GPU
 *                 instancing, animation pointers and any other are refused
 *   buffers       byteLength, the bytes behind it (file, BIN chunk, well-formed base64)
 *   bufferViews   within their buffer; byteStride 4 to 252, a multiple of 4
 *   accessors     componentType, type, count, normalized; byteOffset aligned to the component;
 *                 byteStride at least the element; every element within the bufferView; sparse
 *                 element numbers increasing and below count
 *   primitives    POSITION VEC3 FLOAT; NORMAL VEC3 FLOAT; TANGENT VEC4 FLOAT; TEXCOORD_n VEC2
 *                 FLOAT or normalized UNSIGNED_BYTE/SHORT; COLOR_n VEC3/VEC4 FLOAT or normalized
 *                 UNSIGNED_BYTE/SHORT; JOINTS_n VEC4 UNSIGNED_BYTE/SHORT; WEIGHTS_n VEC4 FLOAT or
 *                 normalized UNSIGNED_BYTE/SHORT; all of one count; indices SCALAR of an
 *                 unsigned type, without a byteStride, each below the vertex count and not the
 *                 type's largest value; enough of them for the mode (a strip needs three)
 *   nodes         one parent at most, no cycle, scenes' nodes roots; matrix or translation,
 *                 unit rotation, scale as finite numbers
 *   cameras       perspective: yfov in (0, π), aspectRatio > 0, znear > 0, zfar > znear;
 *                 orthographic: xmag, ymag not 0, zfar > znear >= 0
 *   lights        KHR_lights_punctual: type point, spot or directional; a spot's cone angles
 *                 0 <= inner < outer <= π/2; intensity >= 0, range > 0, colour of three numbers
 *   skins, animations  joints, inverse bind matrices (MAT4 FLOAT, one per joint; required,
 *                 since Assimp 5.2 crashes without), channel targets (a node, and a path of
 *                 the four glTF defines) and samplers (input SCALAR FLOAT, output as many per
 *                 key as its interpolation and path ask)
 *
 * A Draco-compressed primitive's data is decoded by Assimp: its accessors are checked, its
 * index values are not. Every error names the file, the JSON pointer of what is wrong
 * (/accessors/3/byteOffset) and why; cameras and lights also by name. */
#ifndef IDMR_GLTF_VALIDATE_H
#define IDMR_GLTF_VALIDATE_H

#include "io/gltf/gltf_accessor.h"
#include "io/gltf/gltf_document.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gltf_checked {
    gltf_accessor *accessors; /* per accessor of the document, where its elements lie */
    int accessor_count;
} gltf_checked;

/* Checks `doc` (above) and fills *out (zeroed on failure). Buffers are loaded on the way (a
 * caller that needs memory back frees them with gltf_document_release_buffers). `bar` (may be
 * NULL) is given one unit of work per accessor and per mesh primitive (progress.h). 0, or -1
 * with the error set (IDMR_EXIT_INPUT). */
struct progress;
int gltf_validate(gltf_document *doc, struct progress *bar, gltf_checked *out);

void gltf_checked_free(gltf_checked *checked);

#ifdef __cplusplus
}
#endif

#endif
