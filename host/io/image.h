/* image.h — the OpenImageIO bridge: reading and writing images (textures, renders, error
 * images); comparing them is io/image_compare.h.
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

/* Writes linear float RGB (3 floats per pixel, top row first) as OpenEXR (32-bit floats) or any
 * format OpenImageIO picks by the extension, through a temporary file and rename. */
int image_write_rgb_float(const char *path, int width, int height, const float *rgb);

/* Width, height and channel count of an image file, without reading its pixels. */
int image_info(const char *path, int *width, int *height, int *channels);

/* A false-colour ramp for t in [0, 1] (clamped): black, violet, red, orange, pale yellow;
 * brightness rises monotonically, so it reads in grey too. NaN maps to black. */
void image_false_colour(float t, unsigned char rgb[3]);

#ifdef __cplusplus
}
#endif

#endif
