/* importance_file.h — an importance pass saved and read back: DIR/simulation.bin of
 * `idmr importance`, read by `idmr reduce --simulation FILE`. It holds the per-triangle sums
 * before any weight (importance.h: camera, light, shadow), so γ, σ, the target and the method
 * can all be varied over one simulation.
 *
 * Layout, in the writer's byte order (the magic is read back only in the same order):
 *   char[8]  "IDMRSIM5" (versions 1 to 3 are refused, each saying what it lacked and how to
 *            make the file again: version 1's light sums lacked the seen light, version 2's
 *            weighted it IMPORTANCE_SEEN_LIGHT_WEIGHT times less, version 3 had no checksum;
 *            version 4, without `meshes` and the copy totals, is read for a scene without
 *            instances, where it lacks nothing, and refused for one with them)
 *   uint64   scene fingerprint, triangles
 *   uint32   iterations, photons per iteration, hit-point image width, height,
 *            kinds (bit 0: camera importance accumulated, γ > 0; bit 1: shadow rays, σ > 0),
 *            seed
 *   uint64   hit points, photon records, gathered (first iteration)
 *   double   seen light (importance_result.seen_light)
 *   uint64   meshes (the scene's)
 *   double   gather radius [iterations], convergence Δ [iterations]
 *   double   camera [triangles], light [triangles], shadow [triangles]
 *   double   each copy's own totals (importance.h, "Copies"): camera [meshes], light [meshes],
 *            shadow [meshes]; 0 for a mesh that is not instanced
 *   uint32   the triangle seen through each pixel centre [width × height]
 *   uint64   checksum: FNV-1a over every byte before it
 * The fingerprint is FNV-1a over every mesh's positions and indices, in scene order, and the
 * bytes of the scene's XML file (its camera, lights and materials; not those of files it
 * includes): a simulation is never applied to another scene or a changed one.
 *
 * The reader trusts nothing before it has checked it: only a regular file is opened for reading
 * (a device such as /dev/zero has no end, a FIFO blocks), the header is read first and the file
 * must be exactly the size it promises, then the checksum must hold over the whole file, then
 * the header's counts and the arrays' values must be ones a pass writes. */
#ifndef IDMR_IMPORTANCE_FILE_H
#define IDMR_IMPORTANCE_FILE_H

#include <stdint.h>

#include "core/scene.h"
#include "passes/importance.h"

/* The scene's fingerprint (above). 0, or -1 with the error set (the XML cannot be read). */
int importance_file_fingerprint(const scene *s, uint64_t *fingerprint);

/* Writes the pass `r` (run with the options `o`) to `path`, atomically. 0, or -1 with the error
 * set. */
int importance_file_write(const char *path, const scene *s, const importance_options *o,
                          const importance_result *r);

/* Reads `path` into `r` (free it with importance_result_free(), also on failure) for scene `s`,
 * to be weighted by the options `o`. Errors, naming the file: not a regular file, not a
 * simulation file or one of an older version, truncated or too long, a checksum that does not
 * hold (damaged), a header no pass writes (no iteration, no photons, an empty image, unknown
 * kinds), another scene (fingerprint or triangle count), a weight the simulation cannot serve
 * (γ > 0 without camera importance, σ > 0 without shadow rays), a version 4 file for a scene
 * with instances, a radius, change or sum that is NaN, infinite or negative (naming the
 * triangle and its mesh; a copy total: its mesh), a copy total on a mesh that is not
 * instanced. 0, or -1 with the error set (IDMR_EXIT_INPUT). */
int importance_file_read(const char *path, const scene *s, const importance_options *o,
                         importance_result *r);

#endif
