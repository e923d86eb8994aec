/* spectrum.c — sampled spectrum → linear sRGB, and the sRGB transfer function (see spectrum.h
 * for the method). */
#include "core/spectrum.h"

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

/* CIE standard illuminant D65, relative spectral power at 360, 370, ..., 830 nm (CIE 15). */
#define D65_FIRST 360.0
#define D65_STEP 10.0
static const double d65_table[] = {
    46.6383, 52.0891, 49.9755, 54.6482, 82.7549, 91.486,  93.4318, 86.6823, 104.865, 117.008,
    117.812, 114.861, 115.923, 108.811, 109.354, 107.802, 104.79,  107.689, 104.405, 104.046,
    100.0,   96.3342, 95.788,  88.6856, 90.0062, 89.5991, 87.6987, 83.2886, 83.6992, 80.0268,
    80.2146, 82.2778, 78.2842, 69.7213, 71.6091, 74.349,  61.604,  69.8856, 75.087,  63.5927,
    46.4182, 66.8054, 63.3828, 64.304,  59.4519, 51.959,  57.4406, 60.3125};

/* D65 at `lambda` (360–830 nm), linear between the table's entries. */
static double d65(double lambda)
{
    int last = (int)(sizeof d65_table / sizeof d65_table[0]) - 1;
    double x = (lambda - D65_FIRST) / D65_STEP;
    int i = x <= 0.0 ? 0 : x >= last ? last - 1 : (int)x;
    double t = x - i;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    return d65_table[i] + t * (d65_table[i + 1] - d65_table[i]);
}

/* The spectrum at `lambda`: linear between samples, zero outside them; one sample is flat. */
static double spectrum_eval(const double *lambda, const double *value, int count, double at)
{
    if (count == 1)
        return value[0];
    if (at < lambda[0] || at > lambda[count - 1])
        return 0.0;
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

void spectrum_to_rgb(const double *lambda, const double *value, int count, spectrum_use use,
                     float rgb[3])
{
    double xyz[3] = {0.0, 0.0, 0.0}, y_integral = 0.0, out[3];
    if (count == 1 && use == SPECTRUM_REFLECTANCE) { /* D65 white is (1, 1, 1) by definition */
        rgb[0] = rgb[1] = rgb[2] = (float)value[0];
        return;
    }
    double step = (SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN) / SPECTRUM_STEPS;
    for (int i = 0; i < SPECTRUM_STEPS; i++) {
        double at = SPECTRUM_LAMBDA_MIN + (i + 0.5) * step, cmf[3];
        double illuminant = use == SPECTRUM_REFLECTANCE ? d65(at) : 1.0;
        double s = spectrum_eval(lambda, value, count, at) * illuminant;
        spectrum_cie_xyz(at, cmf);
        for (int k = 0; k < 3; k++)
            xyz[k] += s * cmf[k];
        y_integral += illuminant * cmf[1];
    }
    for (int k = 0; k < 3; k++)
        xyz[k] /= y_integral;
    spectrum_xyz_to_linear_srgb(xyz, out);
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)out[k];
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
