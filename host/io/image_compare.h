/* image_compare.h — how far one image is from another, in linear RGB (images are read through
 * the OpenImageIO bridge, io/image.h; 8-bit files are linearised from sRGB).
 *
 * image_compare: A against a reference B — RMSE, PSNR, relative MSE, largest and 99th-percentile
 * error, and a false-colour error image.
 *
 * image_compare_paired: the change a scene reduction makes to the *converged* image, with render
 * noise cancelled. Render the original scene (A) and the reduced one (B) with two independent
 * seeds each (A1, B1 with seed 1; A2, B2 with seed 2). The noise of seed 1 is independent of the
 * noise of seed 2, so per pixel and channel
 *     E[(A1 - B1)(A2 - B2)] = (E[A] - E[B])²,
 * the squared difference of the converged images; its mean over pixels and channels is an
 * unbiased estimate of the reduction's MSE (it can come out below zero from noise). Using the
 * same seed for A1 and B1 only helps: their noise is correlated and partly cancels in A1 - B1.
 *     reduction_rmse = sqrt(max(0, mse)).
 * Its standard error is that of the render noise in it, not of the change's spread over the
 * image. With x1 = A1 - B1 = d + n1 and x2 = A2 - B2 = d + n2 (d the change, n1 and n2 the two
 * seeds' independent noise), the estimate's error per value is d (n1 + n2) + n1 n2, and
 *     z = (x1² - x2²) / 2 = d (n1 - n2) + (n1² - n2²) / 2
 * has mean 0 and, for Gaussian noise, exactly that variance and that covariance between
 * neighbouring pixels. Otherwise its noise-only part, (n1² - n2²) / 2, has (κ - 1) / 2 times the
 * variance of n1 n2 (κ the noise's kurtosis, 3 for Gaussian): render noise, with its fireflies,
 * has heavier tails than Gaussian, so its error is overstated rather than hidden.
 * Summed over square tiles (tile × tile pixels, 16 by default, at most a quarter of the image's
 * smaller side), which hold the noise's correlation between neighbours (photon mapping shares
 * photons across a gather radius), taken as independent:
 *     se(mse) = sqrt(Σ_t (Σ_{values in t} z / values)²).
 * A change confined to a few pixels (the glints of a glass model) is thus measured to the
 * precision the noise allows; a spread of tile means would count the change itself as noise.
 * On the RMSE scale, se(rmse) is half the width of [sqrt(max(0, mse - se)), sqrt(max(0, mse +
 * se))]: se / (2 rmse) for a clear change, at most sqrt(se) when the change is within its noise.
 * For contrast, `noisy_rmse` is the plain RMSE of A1 against B1, which holds the renders' noise
 * as well.
 *
 * Images with NaN or infinite values are refused with an error naming the file, the count and
 * the first pixel: a comparison with them would be meaningless. */
#ifndef IDMR_IMAGE_COMPARE_H
#define IDMR_IMAGE_COMPARE_H

typedef struct image_comparison {
    int width, height, channels;
    double rmse;         /* over all pixels and the R, G, B channels, linear values */
    double psnr;         /* 20 log10(peak / rmse), peak = max(1, largest value of b); INFINITY
                            when the images are equal */
    double relative_mse; /* mean of (a - b)² / (b² + 0.01) over pixels and channels */
    double max_error;    /* largest |a - b| */
    double error_p99;    /* 99th percentile of the per-pixel error (mean |a - b| over R, G, B) */
} image_comparison;

/* Compares image a with the reference b (same size and channel count, else an error naming
 * both files and their sizes). If diff_path is not NULL, writes the per-pixel error |a - b|
 * (mean over R, G, B) in false colour, scaled so that diff_max is the top of the ramp, or the
 * 99th percentile when diff_max <= 0 (a common diff_max makes several difference images
 * comparable). Returns 0, or -1 with the error set. */
int image_compare(const char *a, const char *b, const char *diff_path, double diff_max,
                  image_comparison *out);

#define IMAGE_PAIRED_TILE 16

typedef struct image_paired_error {
    int width, height;
    unsigned int tiles;         /* tiles the standard errors come from */
    double mse;                 /* mean of (a1 - b1)(a2 - b2): unbiased, may be < 0 */
    double mse_standard_error;
    double rmse;                /* sqrt(max(0, mse)): the reduction RMSE */
    double rmse_standard_error;
    double noisy_rmse;          /* RMSE of a1 against b1, render noise included */
} image_paired_error;

/* The paired reduction error (above) of four images of one size: a1, a2 the original scene,
 * b1, b2 the reduced one, a1 and b1 rendered with one seed, a2 and b2 with another. tile <= 0
 * takes IMAGE_PAIRED_TILE. Returns 0, or -1 with the error set naming the file at fault. */
int image_compare_paired(const char *a1, const char *a2, const char *b1, const char *b2,
                         int tile, image_paired_error *out);

/* The same on linear RGB pixel arrays (3 floats per pixel, width × height, finite values). */
void image_paired_error_of(const float *a1, const float *a2, const float *b1, const float *b2,
                           int width, int height, int tile, image_paired_error *out);

#endif
