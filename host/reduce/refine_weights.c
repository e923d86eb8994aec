/* refine_weights.c — the pixel weights of `idmr reduce --refine` (see refine_weights.h). */
#include "reduce/refine_weights.h"

#include <math.h>
#include <stdlib.h>

#include "core/error.h"

uint64_t refine_pixel_weights(const float *a1, const float *a2, const float *b1, const float *b2,
                              unsigned int width, unsigned int height, unsigned int tile,
                              uint32_t max_weight, uint32_t *weights)
{
    if (tile == 0)
        tile = 1;
    unsigned int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    double *value = xcalloc((size_t)tiles_x * tiles_y + 1, sizeof *value);
    double largest = 0;
    for (unsigned int ty = 0; ty < tiles_y; ty++)
        for (unsigned int tx = 0; tx < tiles_x; tx++) {
            double sum = 0, squares = 0;
            unsigned int n = 0;
            for (unsigned int y = ty * tile; y < height && y < (ty + 1) * tile; y++)
                for (unsigned int x = tx * tile; x < width && x < (tx + 1) * tile; x++) {
                    size_t i = 3 * ((size_t)y * width + x);
                    double c = 0;
                    for (int k = 0; k < 3; k++)
                        c += ((double)a1[i + k] - b1[i + k]) * ((double)a2[i + k] - b2[i + k]);
                    sum += c;
                    squares += c * c;
                    n++;
                }
            double mean = sum / n;
            double variance = n > 1 ? fmax(0.0, (squares - n * mean * mean) / (n - 1)) : 0.0;
            double v = mean - REFINE_NOISE_SIGMAS * sqrt(variance / n);
            v = isfinite(v) && v > 0 ? v : 0.0;
            value[(size_t)ty * tiles_x + tx] = v;
            largest = fmax(largest, v);
        }
    uint64_t weighted = 0;
    for (unsigned int y = 0; y < height; y++)
        for (unsigned int x = 0; x < width; x++) {
            double v = value[(size_t)(y / tile) * tiles_x + x / tile];
            uint32_t w = largest > 0 ? (uint32_t)lround(max_weight * v / largest) : 0;
            weights[(size_t)y * width + x] = w;
            weighted += w > 0;
        }
    free(value);
    return weighted;
}
