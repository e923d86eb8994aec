/* refine_weights.h — the pixel weights of `idmr reduce --refine` (reduce_refine.c): where the
 * first reduction changed the image, as integer weights for the importance pass's hit points
 * (passes/importance.h: pixel_weights). Pure arithmetic on images, for a test to check by hand.
 *
 * From the check renders, the original's A1, A2 and the reduced scene's B1, B2 (seeds 1 and 2,
 * RGB, width × height): per pixel the paired change c = Σ_rgb (A1 - B1)(A2 - B2), whose mean is
 * the squared change without render noise (io/image_compare.h). Per tile of `tile` × `tile`
 * pixels (the last row and column of tiles may be smaller) its mean m and the standard error s
 * of that mean over the tile's pixels; the tile's value is max(0, m - REFINE_NOISE_SIGMAS s):
 * a tile whose change is within the noise, or negative, gets 0. Each pixel gets its tile's value
 * scaled so that the largest tile gets `max_weight`, rounded (and 0 everywhere when no tile is
 * above 0). */
#ifndef IDMR_REFINE_WEIGHTS_H
#define IDMR_REFINE_WEIGHTS_H

#include <stdint.h>

/* How many standard errors a tile's mean change must stand above 0 to count. */
#define REFINE_NOISE_SIGMAS 2.0

/* Fills weights[width × height]; returns how many pixels got a weight above 0. */
uint64_t refine_pixel_weights(const float *a1, const float *a2, const float *b1, const float *b2,
                              unsigned int width, unsigned int height, unsigned int tile,
                              uint32_t max_weight, uint32_t *weights);

#endif
