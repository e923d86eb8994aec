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

/* Writes an 8-bit RGB image (format by extension: .png, .jpg, ...) through a temporary file
 * and rename. Returns 0, or -1 with the error set naming the file. */
int image_write_rgb8(const char *path, int width, int height, const unsigned char *rgb);

/* A false-colour ramp for t in [0, 1] (clamped): black, violet, red, orange, pale yellow;
 * brightness rises monotonically, so it reads in grey too. NaN maps to black. */
void image_false_colour(float t, unsigned char rgb[3]);

#ifdef __cplusplus
}
#endif

#endif
