/* mitsuba.h — the Mitsuba scene loader: a Mitsuba 0.5/0.6 or 3.x XML file in, a scene out.
 *
 * Both dialects are read by one code path: after parsing, `$name` references in attribute
 * values are replaced by the file's <default name= value=> parameters, and every property name
 * is normalised from camelCase to snake_case (toWorld → to_world, intIOR → int_ior), so the
 * rest of the loader only knows the 3.x spelling. What is read (everything else is an error
 * naming the file, line and element, except what is listed as ignored):
 *
 *   sensor    perspective (thinlens: as a pinhole, with a warning): fov, fov_axis, focal_length,
 *             to_world; film width/height. Mitsuba camera space looks along +z with +x pointing
 *             to the image's LEFT and +y up, so the camera's `right` vector is the world image
 *             of -x: right = -to_world(+x), up = to_world(+y), forward = to_world(+z),
 *             re-orthonormalised (a mirroring <scale x="-1"/> therefore mirrors the image, as in
 *             Mitsuba). No sensor: a warning, and has_camera stays 0.
 *   shape     obj, off (io/mesh/mesh_text.h), ply, stl (through OpenMesh), rectangle, cube, disk,
 *             sphere (tessellated, host/core/shapes.h); to_world, flip_normals; a bsdf by <ref> or
 *             inline (none: diffuse 0.5, as Mitsuba); an area emitter inline or by <ref>.
 *   bsdf      diffuse, dielectric, thindielectric, roughdielectric (as smooth, warned),
 *             conductor, roughconductor, plastic, roughplastic, twosided, mask (opacity
 *             ignored), bumpmap/normalmap (inner bsdf, warned). A bitmap texture is accepted for
 *             the diffuse reflectance (reflectance / diffuse_reflectance).
 *   emitter   point, spot, directional, area (inside a shape, or by id), constant (radiance),
 *             envmap (filename, scale, to_world): the scene's one environment, sampled by its
 *             map (idmr/environment.h; a constant is a 1 × 1 map).
 *   texture   bitmap (top level with an id, or inline).
 *   include   <include filename=...>: the fragment's elements are read in place.
 *   ignored   integrator, sampler, rfilter, other film settings, unknown properties.
 * Colours: rgb (linear), srgb (linearised), spectrum (grey value or λ:v pairs,
 * host/core/spectrum.h), float (grey). Relative paths resolve from the directory of the file that
 * names them, then from the scene's directory. The loader's files are listed in
 * mitsuba_loader.h. */
#ifndef IDMR_MITSUBA_H
#define IDMR_MITSUBA_H

#include <stdint.h>

#include "core/scene.h"

/* Loads `path` and returns the finalized scene, or NULL with the error set (IDMR_EXIT_INPUT for
 * bad input); messages read "file:line: <element type="...">: what is wrong". */
scene *mitsuba_load(const char *path);

/* As mitsuba_load(), with every mesh file of at least release_from vertices (emitters excepted)
 * released as soon as it is read (core/scene.h, scene_mesh_release), so the load never holds
 * more than one such mesh: the scene's geometry is read again mesh by mesh where it is needed
 * (scene_mesh_restore). release_from 0: none released. */
scene *mitsuba_load_streaming(const char *path, uint32_t release_from);

#endif
