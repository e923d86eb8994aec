/* spectrum.h — colour conversions for the scene loader: sampled spectra and sRGB to linear RGB.
 *
 * A Mitsuba <spectrum value="λ1:v1, λ2:v2, ..."> is a piecewise-linear function of wavelength
 * (nm). spectrum_to_rgb() turns it into the linear sRGB triple the renderer works with:
 *
 *   1. XYZ = ∫ s(λ) cmf(λ) dλ / ∫ ȳ(λ) dλ over 360–830 nm (1 nm midpoint steps), with the
 *      CIE 1931 2° colour matching functions taken from the multi-lobe piecewise-Gaussian fit
 *      of Wyman, Sloan and Shirley, "Simple Analytic Approximations to the CIE XYZ Color
 *      Matching Functions", JCGT 2(2), 2013. Outside the sampled range the end values are held
 *      (Mitsuba takes zero there; for the usual 400–700 nm reflectance data this keeps a flat
 *      spectrum flat instead of losing ~1% of luminance to the tails).
 *   2. RGB = M · XYZ with the XYZ → linear sRGB (D65) matrix of IEC 61966-2-1.
 *   3. White balance: each channel is divided by the RGB of the flat spectrum s(λ) = 1, so a
 *      flat spectrum of value v maps exactly to (v, v, v) (a von Kries scaling in RGB from the
 *      equal-energy white to D65 white).
 * A reflectance spectrum thus becomes the RGB albedo a renderer would use under white light,
 * and an emission spectrum keeps its luminance scale. */
#ifndef IDMR_SPECTRUM_H
#define IDMR_SPECTRUM_H

/* The CIE 1931 2° colour matching functions at `lambda` nm (analytic fit, see above). */
void spectrum_cie_xyz(double lambda, double xyz[3]);

/* Linear sRGB of the piecewise-linear spectrum through (lambda[i], value[i]), i < count.
 * lambda must be strictly increasing and count >= 1 (a single sample is a flat spectrum). */
void spectrum_to_rgb(const double *lambda, const double *value, int count, float rgb[3]);

/* The sRGB transfer function inverted: an sRGB-encoded value in [0,1] to linear. */
float spectrum_srgb_to_linear(float encoded);

/* The sRGB transfer function: a linear value to sRGB-encoded (0 for NaN or negatives; values
 * above 1 stay above 1, for the caller to clamp). */
float spectrum_linear_to_srgb(float linear);

#endif
