/* spectrum.c — sampled spectrum → linear sRGB, and the sRGB transfer function (see spectrum.h
 * for the method). */
#include "io/spectrum.h"

#include <math.h>
#include <stddef.h>

#define SPECTRUM_LAMBDA_MIN 360.0
#define SPECTRUM_LAMBDA_MAX 830.0
#define SPECTRUM_STEPS 470 /* 1 nm */

/* A Gaussian with different widths left and right of its peak (Wyman et al., Eq. 1). */
static double spectrum_lobe(double lambda, double mu, double sigma_left, double sigma_right)
{
    double t = (lambda - mu) / (lambda < mu ? sigma_left : sigma_right);
    return exp(-0.5 * t * t);
}

void spectrum_cie_xyz(double lambda, double xyz[3])
{
    xyz[0] = 1.056 * spectrum_lobe(lambda, 599.8, 37.9, 31.0) +
             0.362 * spectrum_lobe(lambda, 442.0, 16.0, 26.7) -
             0.065 * spectrum_lobe(lambda, 501.1, 20.4, 26.2);
    xyz[1] = 0.821 * spectrum_lobe(lambda, 568.8, 46.9, 40.5) +
             0.286 * spectrum_lobe(lambda, 530.9, 16.3, 31.1);
    xyz[2] = 1.217 * spectrum_lobe(lambda, 437.0, 11.8, 36.0) +
             0.681 * spectrum_lobe(lambda, 459.0, 26.0, 13.8);
}

/* The spectrum at `lambda`: linear between samples, end values held outside. */
static double spectrum_eval(const double *lambda, const double *value, int count, double at)
{
    if (at <= lambda[0])
        return value[0];
    if (at >= lambda[count - 1])
        return value[count - 1];
    int lo = 0, hi = count - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (lambda[mid] <= at)
            lo = mid;
        else
            hi = mid;
    }
    double t = (at - lambda[lo]) / (lambda[hi] - lambda[lo]);
    return value[lo] + t * (value[hi] - value[lo]);
}

static void spectrum_xyz_to_linear_srgb(const double xyz[3], double rgb[3])
{
    static const double m[9] = {3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108,
                                0.0415560, 0.0556434,  -0.2040259, 1.0572252};
    for (int row = 0; row < 3; row++)
        rgb[row] = m[3 * row] * xyz[0] + m[3 * row + 1] * xyz[1] + m[3 * row + 2] * xyz[2];
}

/* Unbalanced linear sRGB of a spectrum; a NULL lambda means the flat spectrum 1. */
static void spectrum_raw_rgb(const double *lambda, const double *value, int count, double rgb[3])
{
    double xyz[3] = {0.0, 0.0, 0.0}, y_integral = 0.0;
    double step = (SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN) / SPECTRUM_STEPS;
    for (int i = 0; i < SPECTRUM_STEPS; i++) {
        double at = SPECTRUM_LAMBDA_MIN + (i + 0.5) * step, cmf[3];
        double s = lambda ? spectrum_eval(lambda, value, count, at) : 1.0;
        spectrum_cie_xyz(at, cmf);
        for (int k = 0; k < 3; k++)
            xyz[k] += s * cmf[k];
        y_integral += cmf[1];
    }
    for (int k = 0; k < 3; k++)
        xyz[k] /= y_integral;
    spectrum_xyz_to_linear_srgb(xyz, rgb);
}

void spectrum_to_rgb(const double *lambda, const double *value, int count, float rgb[3])
{
    double white[3], raw[3];
    spectrum_raw_rgb(NULL, NULL, 0, white);
    spectrum_raw_rgb(lambda, value, count, raw);
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)(raw[k] / white[k]);
}

float spectrum_srgb_to_linear(float encoded)
{
    if (encoded <= 0.04045f)
        return encoded / 12.92f;
    return powf((encoded + 0.055f) / 1.055f, 2.4f);
}

float spectrum_linear_to_srgb(float linear)
{
    if (!(linear > 0.0031308f))
        return linear > 0 ? 12.92f * linear : 0.0f;
    return 1.055f * powf(linear, 1.0f / 2.4f) - 0.055f;
}
