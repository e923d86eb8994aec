/* image.h — the OpenImageIO bridge: reading textures (and later writing and comparing images).
 *
 * Pixels cross the bridge as linear float RGB, row-major, top row first. 8-bit files (JPEG,
 * PNG, ...) are taken as sRGB-encoded and linearised; float files (EXR, HDR) as linear. */
#ifndef IDMR_IMAGE_H
#define IDMR_IMAGE_H

#ifdef __cplusplus
extern "C" {
#endif

/* Reads `path` into a malloc'd linear RGB array (grey is replicated, alpha dropped).
 * Returns 0, or -1 with the error set (error.h) naming the file and OpenImageIO's reason. */
int image_read_rgb(const char *path, int *width, int *height, float **rgb);

#ifdef __cplusplus
}
#endif

#endif
