/* image_compare.c — image comparison and the paired reduction error (see image_compare.h). */
#include "io/image_compare.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image.h"

/* A linear RGB image read from a file. */
typedef struct rgb_image {
    const char *path;
    int width, height, channels;
    float *rgb;
} rgb_image;

/* Reads `path`, refusing non-finite values (NaN, ±inf) with the file, count and first pixel. */
static int read_finite(const char *path, rgb_image *image)
{
    memset(image, 0, sizeof *image);
    image->path = path;
    int w, h;
    if (image_info(path, &w, &h, &image->channels) ||
        image_read_rgb(path, &image->width, &image->height, &image->rgb))
        return -1;
    size_t values = 3 * (size_t)image->width * (size_t)image->height, bad = 0, first = 0;
    for (size_t i = 0; i < values; i++)
        if (!isfinite(image->rgb[i]) && bad++ == 0)
            first = i / 3;
    if (bad) {
        free(image->rgb);
        image->rgb = NULL;
        return error_set(IDMR_EXIT_INPUT,
                         "image '%s' holds %zu values that are NaN or infinite (the first at "
                         "pixel (%zu, %zu)): it cannot be compared",
                         path, bad, first % (size_t)w, first / (size_t)w);
    }
    return 0;
}

/* Reads `count` images that must share size and channel count; on failure none stays read. */
static int read_alike(const char *const *paths, rgb_image *images, int count)
{
    for (int i = 0; i < count; i++) {
        const rgb_image *first = &images[0];
        if (read_finite(paths[i], &images[i]) ||
            (i > 0 && (images[i].width != first->width || images[i].height != first->height ||
                       images[i].channels != first->channels))) {
            if (images[i].rgb)
                error_set(IDMR_EXIT_INPUT,
                          "cannot compare '%s' (%dx%d, %d channels) with '%s' (%dx%d, %d "
                          "channels): sizes or channels differ",
                          images[i].path, images[i].width, images[i].height, images[i].channels,
                          first->path, first->width, first->height, first->channels);
            for (int k = 0; k <= i; k++)
                free(images[k].rgb);
            return -1;
        }
    }
    return 0;
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Writes the per-pixel error in false colour, `top` at the top of the ramp. */
static int write_error_image(const char *path, const float *error, int width, int height,
                             float top)
{
    size_t pixels = (size_t)width * (size_t)height;
    unsigned char *rgb = xmalloc(3 * pixels);
    for (size_t p = 0; p < pixels; p++)
        image_false_colour(top > 0 ? error[p] / top : 0.0f, &rgb[3 * p]);
    int status = image_write_rgb8(path, width, height, rgb);
    free(rgb);
    return status;
}

int image_compare(const char *a, const char *b, const char *diff_path, double diff_max,
                  image_comparison *out)
{
    memset(out, 0, sizeof *out);
    const char *paths[2] = {a, b};
    rgb_image images[2];
    if (read_alike(paths, images, 2))
        return -1;
    const float *pa = images[0].rgb, *pb = images[1].rgb;
    size_t pixels = (size_t)images[0].width * (size_t)images[0].height;
    double sum2 = 0, relative = 0, peak = 1, largest = 0;
    float *error = xmalloc((pixels ? pixels : 1) * sizeof *error);
    for (size_t p = 0; p < pixels; p++) {
        double e = 0;
        for (int c = 0; c < 3; c++) {
            double x = pa[3 * p + c], y = pb[3 * p + c], d = x - y;
            sum2 += d * d;
            relative += d * d / (y * y + 0.01);
            peak = fmax(peak, y);
            largest = fmax(largest, fabs(d));
            e += fabs(d) / 3;
        }
        error[p] = (float)e;
    }
    double n = 3.0 * (double)(pixels ? pixels : 1);
    out->width = images[0].width;
    out->height = images[0].height;
    out->channels = images[0].channels;
    out->rmse = sqrt(sum2 / n);
    out->psnr = out->rmse > 0 ? 20.0 * log10(peak / out->rmse) : INFINITY;
    out->relative_mse = relative / n;
    out->max_error = largest;
    float *sorted = xmalloc((pixels ? pixels : 1) * sizeof *sorted);
    memcpy(sorted, error, pixels * sizeof *sorted);
    qsort(sorted, pixels, sizeof *sorted, compare_floats);
    out->error_p99 = pixels ? sorted[(size_t)(0.99 * (double)(pixels - 1))] : 0.0;
    int status = 0;
    if (diff_path) {
        float top = diff_max > 0 ? (float)diff_max : (float)out->error_p99;
        if (!(top > 0))
            top = pixels ? sorted[pixels - 1] : 0.0f;
        status = write_error_image(diff_path, error, out->width, out->height, top);
    }
    free(sorted);
    free(error);
    free(images[0].rgb);
    free(images[1].rgb);
    return status;
}

void image_paired_error_of(const float *a1, const float *a2, const float *b1, const float *b2,
                           int width, int height, int tile, image_paired_error *out)
{
    memset(out, 0, sizeof *out);
    out->width = width;
    out->height = height;
    if (tile <= 0)
        tile = IMAGE_PAIRED_TILE;
    int smaller_side = width < height ? width : height;
    if (tile > smaller_side / 4) /* at least 4 x 4 tiles, or the spread has nothing to go on */
        tile = smaller_side / 4 > 0 ? smaller_side / 4 : 1;
    double values = 3.0 * (double)width * (double)height;
    if (!(values > 0))
        return;
    int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    size_t tiles = (size_t)tiles_x * (size_t)tiles_y;
    double *tile_noise = xcalloc(tiles, sizeof *tile_noise);
    double product_sum = 0, noisy_sum = 0;
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t t = (size_t)(y / tile) * (size_t)tiles_x + (size_t)(x / tile);
            for (int c = 0; c < 3; c++) {
                size_t i = 3 * ((size_t)y * (size_t)width + (size_t)x) + (size_t)c;
                double d1 = (double)a1[i] - b1[i], d2 = (double)a2[i] - b2[i];
                product_sum += d1 * d2;
                noisy_sum += d1 * d1;
                tile_noise[t] += 0.5 * (d1 * d1 - d2 * d2);
            }
        }
    out->tiles = (unsigned int)tiles;
    out->mse = product_sum / values;
    double variance = 0; /* of the estimate: Σ over tiles of (their share of the noise term)² */
    for (size_t t = 0; t < tiles; t++)
        variance += (tile_noise[t] / values) * (tile_noise[t] / values);
    out->mse_standard_error = sqrt(variance);
    out->rmse = out->mse > 0 ? sqrt(out->mse) : 0.0;
    double high = out->mse + out->mse_standard_error, low = out->mse - out->mse_standard_error;
    out->rmse_standard_error = 0.5 * (sqrt(high > 0 ? high : 0) - sqrt(low > 0 ? low : 0));
    out->noisy_rmse = sqrt(noisy_sum / values);
    free(tile_noise);
}

int image_compare_paired(const char *a1, const char *a2, const char *b1, const char *b2,
                         int tile, image_paired_error *out)
{
    memset(out, 0, sizeof *out);
    const char *paths[4] = {a1, a2, b1, b2};
    rgb_image images[4];
    if (read_alike(paths, images, 4))
        return -1;
    image_paired_error_of(images[0].rgb, images[1].rgb, images[2].rgb, images[3].rgb,
                          images[0].width, images[0].height, tile, out);
    for (int i = 0; i < 4; i++)
        free(images[i].rgb);
    return 0;
}
