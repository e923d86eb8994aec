/* render.h — the stochastic progressive photon mapping renderer behind `idmr render`, on the
 * SPPM core (passes/sppm.h, kernels/sppm.cl): what a reduction costs in image error and saves
 * in render time and device memory, measured on our own kernels (the paper's Table 1 renders
 * with SPPM too).
 *
 * Each iteration is an independent photon-mapping estimate of every pixel at that iteration's
 * global radius (sppm.h: r_1 = 5 |diagonal| / (w + h), r²_{n+1} = r²_n (n + α)/(n + 1)):
 *   L(pixel) = E + T Σ_photons f(ω_i, ω_o) Φ / (π r²)
 * with E the emission the camera path saw directly (or through specular surfaces), T the
 * specular throughput to the hit point, f its BRDF and Φ each photon's flux (light power /
 * photons emitted, times the path's scattering weights). The image is the mean of the
 * iterations' estimates (Knaus and Zwicker 2011): consistent, since the radius shrinks slowly
 * enough that the variance of the mean and the bias both vanish.
 *
 * What is simulated, and what is not:
 *   - materials and lights as in the importance pass (kernels/lib/materials.h, lights.h);
 *     glossy lobes have a roughness of at least 0.05 (a smooth plastic's coating becomes
 *     slightly rough);
 *   - geometric normals (no shading-normal interpolation): curved meshes show their facets;
 *   - textured reflectance by the texture's mean colour (textures are not looked up);
 *   - an environment by its map (idmr/environment.h): photons drawn by its luminance, seen by
 *     camera paths that leave the scene;
 *   - photon paths store at most 8 photons (non-specular surfaces) and end after 32 surface
 *     interactions; camera paths follow at most --max-depth surface interactions (default 64),
 *     with Russian roulette from the 16th (kernels/lib/paths.h).
 * Sums are exact: per pixel and channel in 64-bit fixed point (idmr/render_layout.h), and the
 * mean over iterations in double on the host; a render is bit-identical for the same seed,
 * device and options, whatever the work-group size. */
#ifndef IDMR_RENDER_H
#define IDMR_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "core/scene.h"
#include "device/bvh.h"
#include "device/device.h"
#include "idmr/render_layout.h"
#include "passes/sppm.h"

/* Copies of the last iteration's buffers, for tests. */
typedef struct render_snapshot {
    sppm_snapshot core;                /* hit points, path lengths, params, photon records */
    const idmr_render_photon *photons; /* core.photon_records as the pass's records */
} render_snapshot;

void render_snapshot_free(render_snapshot *snapshot);

typedef struct render_options {
    sppm_options sppm;         /* iterations default to 64 */
    render_snapshot *snapshot; /* when not NULL, receives the last iteration's buffers */
} render_options;

typedef struct render_result {
    float *image;      /* linear RGB, 3 floats per pixel, top row first: the mean */
    sppm_summary sppm; /* size (width, height), iterations, radii, photons, bytes, timings */
} render_result;

void render_options_default(render_options *o);

/* The device memory a render of scene s allocates, with a BVH of bvh_bytes (passes/sppm.h,
 * sppm_memory_of). 0, or -1 with the error set. */
int render_memory(const device *d, const scene *s, uint64_t bvh_bytes, const render_options *o,
                  sppm_memory *m);

/* Renders scene `s` (which needs a camera and a light) with BVH `b`. Returns 0, or -1 with the
 * error set; free `r` with render_result_free() either way. */
int render_run(device *d, const scene *s, const bvh *b, const render_options *o,
               render_result *r);
void render_result_free(render_result *r);

/* Writes the image as EXR (linear, 32-bit float) at `exr_path` and as PNG (sRGB, values × 2^ev
 * clamped to [0, 1]) at `png_path`; either may be NULL. Both atomically. */
int render_write_images(const render_result *r, const char *exr_path, const char *png_path,
                        double ev);

/* The render's report (IMAGE.json): size, iterations, photons, radii, seconds per iteration in
 * all and by stage, device memory by kind. */
cJSON *render_report_json(const scene *s, const device *d, const render_options *o,
                          const render_result *r);

#endif
