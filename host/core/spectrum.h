/* spectrum.h — colour conversions for the scene loader: sampled spectra and sRGB to linear RGB.
 *
 * A Mitsuba <spectrum value="λ1:v1, λ2:v2, ..."> is a piecewise-linear function of wavelength
 * (nm), zero outside its first and last sample. spectrum_to_rgb() turns it into the linear sRGB
 * triple the renderer works with, as Mitsuba 3's RGB variants do, so a scene shows the colours
 * there and here (checked against Mitsuba 3.9 in tests/test_mitsuba.c):
 *
 *   emission     (a spectrum inside an <emitter>): XYZ = ∫ s(λ) cmf(λ) dλ / ∫ ȳ(λ) dλ. A flat
 *                spectrum 1 is equal-energy white, linear sRGB (1.2049, 0.9484, 0.9087).
 *   reflectance  (everywhere else): the spectrum as lit by CIE illuminant D65, XYZ =
 *                ∫ s(λ) D65(λ) cmf(λ) dλ / ∫ D65(λ) ȳ(λ) dλ. A flat spectrum 1 is D65 white,
 *                linear sRGB (1, 1, 1): a reflectance keeps its albedo.
 * Both integrate over 360–830 nm in 1 nm midpoint steps, with the CIE 1931 2° colour matching
 * functions of the multi-lobe piecewise-Gaussian fit of Wyman, Sloan and Shirley, "Simple
 * Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), 2013, and D65 as
 * tabulated by the CIE at 10 nm (linear between); then RGB = M · XYZ with the XYZ → linear sRGB
 * (D65) matrix of IEC 61966-2-1. A grey spectrum (one value v, no wavelengths) is the flat
 * spectrum v: (v, v, v) as a reflectance, v times equal-energy white as an emission, as in
 * Mitsuba 3. */
#ifndef IDMR_SPECTRUM_H
#define IDMR_SPECTRUM_H

/* The CIE 1931 2° colour matching functions at `lambda` nm (analytic fit, see above). */
void spectrum_cie_xyz(double lambda, double xyz[3]);

/* What a spectrum describes, which decides its conversion (see above). */
typedef enum spectrum_use { SPECTRUM_REFLECTANCE, SPECTRUM_EMISSION } spectrum_use;

/* Linear sRGB of the piecewise-linear spectrum through (lambda[i], value[i]), i < count, zero
 * outside [lambda[0], lambda[count-1]]. lambda must be strictly increasing and count >= 1; a
 * single sample is the flat spectrum of its value (lambda may then be NULL), exactly (v, v, v)
 * as a reflectance. */
void spectrum_to_rgb(const double *lambda, const double *value, int count, spectrum_use use,
                     float rgb[3]);

/* The sRGB transfer function inverted: an sRGB-encoded value in [0,1] to linear. */
float spectrum_srgb_to_linear(float encoded);

/* The sRGB transfer function: a linear value to sRGB-encoded (0 for NaN or negatives; values
 * above 1 stay above 1, for the caller to clamp). */
float spectrum_linear_to_srgb(float linear);

#endif
