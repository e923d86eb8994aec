/* pbrt_light.c — AreaLightSource and LightSource → lights.
 *
 *   AreaLightSource "diffuse"  L × scale for the shapes that follow in the attribute block;
 *                              idmr's area lights emit from the front side only (the side pbrt
 *                              emits from: the loader winds the mesh to face it), so twosided
 *                              is warned; an image (filename) is not read (warned)
 *   point     I × scale at the CTM's image of `from`
 *   spot      I × scale at `from` towards `to`; coneangle is the cutoff, coneangle - conedeltaangle
 *             where the falloff starts
 *   distant   L × scale travelling from `from` to `to` (defaults (0,0,0) to (0,0,1))
 *   infinite  constant L × scale (a 1 × 1 environment), or `filename`: pbrt-v4's equal-area
 *             octahedral square map, resampled (nearest texel) to an equirectangular map of
 *             2N × N for an N × N square in Mitsuba's frame, with the CTM's rotation as the
 *             environment's to_world
 *   goniometric, projection    warned about and left out.
 * `power` and `illuminance` (photometric normalisation) are warned about and not applied.
 * Colours: rgb as written; blackbody, named and sampled spectra are normalised to luminance 1,
 * as pbrt-v4 normalises a light's spectrum before its scale. */
#include "io/pbrt/pbrt_loader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image.h"
#include "core/spectrum.h"

/* Planck's law (relative spectral radiance at `lambda` nm for temperature T kelvin). */
static double planck(double lambda_nm, double kelvin)
{
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double l = lambda_nm * 1e-9;
    return (2.0 * h * c * c) / (pow(l, 5) * (exp((h * c) / (l * kb * kelvin)) - 1.0));
}

static void normalise_luminance(float rgb[3])
{
    float y = idmr_luminance(rgb[0], rgb[1], rgb[2]);
    if (y > 0.0f)
        for (int k = 0; k < 3; k++)
            rgb[k] /= y;
}

int pbrt_light_color(pbrt_loader *ld, const char *file, pbrt_params *params, const char *name,
                     const float fallback[3], float out[3])
{
    pbrt_param *p = pbrt_param_find(params, name);
    for (int k = 0; k < 3; k++)
        out[k] = fallback[k];
    if (!p)
        return 0;
    if (strcmp(p->type, "rgb") == 0 || strcmp(p->type, "color") == 0) {
        for (int k = 0; k < 3; k++)
            out[k] = (float)p->numbers[k];
    } else if (strcmp(p->type, "blackbody") == 0) {
        double lambda[471], value[471];
        if (p->numbers[0] <= 0.0)
            return pbrt_fail(file, p->line, "\"blackbody %s\": the temperature must be positive",
                             name);
        for (int i = 0; i < 471; i++) {
            lambda[i] = 360.0 + i;
            value[i] = planck(lambda[i], p->numbers[0]);
        }
        spectrum_to_rgb(lambda, value, 471, SPECTRUM_EMISSION, out);
        normalise_luminance(out);
    } else if (strcmp(p->type, "spectrum") == 0) {
        if (p->string_count) {
            if (strncmp(p->strings[0], "stdillum-", 9) != 0)
                pbrt_warn(file, p->line,
                          "\"spectrum %s\" [ \"%s\" ]: not a spectrum idmr knows: white is used",
                          name, p->strings[0]);
            out[0] = out[1] = out[2] = 1.0f; /* a standard illuminant: white at luminance 1 */
        } else if (p->number_count == 1) {
            out[0] = out[1] = out[2] = (float)p->numbers[0];
        } else {
            if (pbrt_sampled_spectrum(file, p, name, SPECTRUM_EMISSION, out))
                return -1;
            normalise_luminance(out);
        }
    } else if (strcmp(p->type, "float") == 0) {
        out[0] = out[1] = out[2] = (float)p->numbers[0];
    } else {
        return pbrt_fail(file, p->line, "\"%s %s\": a light's colour is rgb, spectrum or blackbody",
                         p->type, name);
    }
    for (int k = 0; k < 3; k++)
        if (!(out[k] >= 0.0f))
            return pbrt_fail(file, p->line, "\"%s %s\": emission must not be negative", p->type,
                             name);
    return 0;
}

static int light_scale(const char *file, int line, pbrt_params *params, float rgb[3])
{
    double scale;
    if (pbrt_param_float(file, params, "scale", 1.0, &scale))
        return -1;
    if (!(scale >= 0.0))
        return pbrt_fail(file, line, "scale must not be negative");
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)(rgb[k] * scale);
    if (pbrt_param_find(params, "power") || pbrt_param_find(params, "illuminance"))
        pbrt_warn(file, line, "power/illuminance is not applied: the light's own radiance and "
                              "scale are used");
    return 0;
}

int pbrt_read_area_light(pbrt_loader *ld, const char *file, int line, const char *type,
                         pbrt_params *params)
{
    static const float one[3] = {1, 1, 1};
    if (strcmp(type, "diffuse") != 0)
        return pbrt_fail(file, line, "AreaLightSource: unknown type '%s' (pbrt-v4 has \"diffuse\")",
                         type);
    int twosided;
    pbrt_area_light *light = &ld->state.area_light;
    if (pbrt_light_color(ld, file, params, "L", one, light->radiance) ||
        light_scale(file, line, params, light->radiance) ||
        pbrt_param_bool(file, params, "twosided", 0, &twosided))
        return -1;
    if (twosided)
        pbrt_warn(file, line,
                  "AreaLightSource: twosided is not simulated: the light emits from its front "
                  "side only");
    if (pbrt_param_find(params, "filename"))
        pbrt_warn(file, line, "AreaLightSource: an emission image is not read: L is used");
    if (ld->current_object)
        pbrt_warn(file, line, "AreaLightSource inside an object: instances do not emit");
    light->active = 1;
    return 0;
}

/* A point of the light's space (parameter `name`) in the world. */
static int light_point(const pbrt_loader *ld, const char *file, pbrt_params *params,
                       const char *name, const double fallback[3], double out[3])
{
    double p[3];
    if (pbrt_param_point3(file, params, name, fallback, p))
        return -1;
    xform_apply_point(&ld->state.ctm, p, out);
    return 0;
}

/* The light's from → to direction in the world, normalised. */
static int light_direction(const pbrt_loader *ld, const char *file, int line, pbrt_params *params,
                           double from[3], double direction[3])
{
    static const double zero[3] = {0, 0, 0}, z[3] = {0, 0, 1};
    double to[3];
    if (light_point(ld, file, params, "from", zero, from) ||
        light_point(ld, file, params, "to", z, to))
        return -1;
    for (int k = 0; k < 3; k++)
        direction[k] = to[k] - from[k];
    if (xform_normalize(direction) == 0.0)
        return pbrt_fail(file, line, "from and to are the same point");
    return 0;
}

/* pbrt-v4's equal-area mapping of a unit direction to the square [0,1]² (Clarberg's octahedral
 * map): the +z pole at the centre, -z at the corners, the sign of x and y choosing the
 * quadrant. */
static void sphere_to_square(const double d[3], double *u, double *v)
{
    double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
    double r = sqrt(fmax(0.0, 1.0 - az));
    double big = fmax(ax, ay), small = fmin(ax, ay);
    double phi = big == 0.0 ? 0.0 : atan2(small, big) * (2.0 / M_PI);
    if (ax < ay)
        phi = 1.0 - phi;
    double b = phi * r, a = r - b;
    if (d[2] < 0.0) {
        double t = a;
        a = 1.0 - b;
        b = 1.0 - t;
    }
    a = copysign(a, d[0]);
    b = copysign(b, d[1]);
    *u = 0.5 * (a + 1.0);
    *v = 0.5 * (b + 1.0);
}

/* The equirectangular map (Mitsuba's frame: idmr/environment.h) of pbrt's octahedral square
 * `square` (n × n, top row first), read in the light's own frame. */
static float *octahedral_to_equirect(const float *square, int n, int *width, int *height)
{
    int w = 2 * n, h = n;
    float *rgb = xmalloc(3 * (size_t)w * h * sizeof *rgb);
    for (int row = 0; row < h; row++) {
        double theta = (row + 0.5) / h * M_PI;
        for (int col = 0; col < w; col++) {
            double phi = (col + 0.5) / w * 2.0 * M_PI;
            double d[3] = {sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi)};
            double u, v;
            sphere_to_square(d, &u, &v);
            int x = (int)(u * n), y = (int)(v * n);
            x = x < 0 ? 0 : x >= n ? n - 1 : x;
            y = y < 0 ? 0 : y >= n ? n - 1 : y;
            memcpy(&rgb[3 * ((size_t)row * w + col)], &square[3 * ((size_t)y * n + x)],
                   3 * sizeof(float));
        }
    }
    *width = w;
    *height = h;
    return rgb;
}

/* The rotation of the CTM (columns normalised), row-major 3 × 3. */
static int ctm_rotation(const pbrt_loader *ld, const char *file, int line, double rotation[9])
{
    for (int c = 0; c < 3; c++) {
        double column[3] = {ld->state.ctm.m[c], ld->state.ctm.m[4 + c], ld->state.ctm.m[8 + c]};
        if (xform_normalize(column) == 0.0)
            return pbrt_fail(file, line, "LightSource \"infinite\": the transform is singular");
        for (int r = 0; r < 3; r++)
            rotation[3 * r + c] = column[r];
    }
    return 0;
}

static int light_infinite(pbrt_loader *ld, const char *file, int line, pbrt_params *params)
{
    static const float one[3] = {1, 1, 1};
    const char *written;
    double rotation[9];
    float color[3];
    if (pbrt_param_string(file, params, "filename", NULL, &written) ||
        ctm_rotation(ld, file, line, rotation))
        return -1;
    if (ld->current_object)
        return pbrt_fail(file, line, "LightSource inside an object definition");
    if (!written) {
        if (pbrt_light_color(ld, file, params, "L", one, color) ||
            light_scale(file, line, params, color))
            return -1;
        float *rgb = xmalloc(3 * sizeof *rgb);
        memcpy(rgb, color, sizeof color);
        return scene_add_environment(ld->s, NULL, 1, 1, rgb, rotation) < 0
                   ? error_prefix("%s:%d: LightSource \"infinite\"", file, line)
                   : 0;
    }
    if (pbrt_param_find(params, "L"))
        return pbrt_fail(file, line, "LightSource \"infinite\": give L or filename, not both");
    pbrt_param_find(params, "portal");
    float scale_rgb[3] = {1, 1, 1};
    if (light_scale(file, line, params, scale_rgb))
        return -1;
    char *path = pbrt_resolve_path(ld, written);
    int n, other;
    float *square;
    if (image_read_rgb(path, &n, &other, &square)) {
        free(path);
        return error_prefix("%s:%d: LightSource \"infinite\"", file, line);
    }
    if (n != other) {
        free(square);
        free(path);
        return pbrt_fail(file, line,
                         "LightSource \"infinite\": '%s' is %dx%d: pbrt-v4 needs a square "
                         "(equal-area octahedral) map",
                         written, n, other);
    }
    int width, height;
    float *rgb = octahedral_to_equirect(square, n, &width, &height);
    free(square);
    for (size_t i = 0; i < 3 * (size_t)width * height; i++)
        rgb[i] *= scale_rgb[0];
    int index = scene_add_environment(ld->s, path, width, height, rgb, rotation);
    free(path);
    return index < 0 ? error_prefix("%s:%d: LightSource \"infinite\"", file, line) : 0;
}

int pbrt_read_light(pbrt_loader *ld, const char *file, int line, const char *type,
                    pbrt_params *params)
{
    static const float one[3] = {1, 1, 1};
    static const double zero[3] = {0, 0, 0};
    idmr_light light;
    memset(&light, 0, sizeof light);
    if (strcmp(type, "infinite") == 0)
        return light_infinite(ld, file, line, params);
    if (ld->current_object)
        return pbrt_fail(file, line, "LightSource inside an object definition");
    if (strcmp(type, "point") == 0) {
        double position[3];
        light.kind = IDMR_LIGHT_POINT;
        if (light_point(ld, file, params, "from", zero, position) ||
            pbrt_light_color(ld, file, params, "I", one, light.emission) ||
            light_scale(file, line, params, light.emission))
            return -1;
        for (int k = 0; k < 3; k++)
            light.position[k] = (float)position[k];
    } else if (strcmp(type, "spot") == 0) {
        double from[3], direction[3], cone, delta;
        light.kind = IDMR_LIGHT_SPOT;
        if (light_direction(ld, file, line, params, from, direction) ||
            pbrt_light_color(ld, file, params, "I", one, light.emission) ||
            light_scale(file, line, params, light.emission) ||
            pbrt_param_float(file, params, "coneangle", 30.0, &cone) ||
            pbrt_param_float(file, params, "conedeltaangle", 5.0, &delta))
            return -1;
        if (!(cone > 0.0 && cone <= 180.0))
            return pbrt_fail(file, line, "spot: coneangle must be in (0, 180] degrees");
        double start = fmax(0.0, fmin(cone, cone - delta));
        for (int k = 0; k < 3; k++) {
            light.position[k] = (float)from[k];
            light.direction[k] = (float)direction[k];
        }
        light.cos_cutoff = (float)cos(cone * M_PI / 180.0);
        light.cos_falloff_start = (float)cos(start * M_PI / 180.0);
    } else if (strcmp(type, "distant") == 0) {
        double from[3], direction[3];
        light.kind = IDMR_LIGHT_DIRECTIONAL;
        if (light_direction(ld, file, line, params, from, direction) ||
            pbrt_light_color(ld, file, params, "L", one, light.emission) ||
            light_scale(file, line, params, light.emission))
            return -1;
        for (int k = 0; k < 3; k++)
            light.direction[k] = (float)direction[k];
    } else if (strcmp(type, "goniometric") == 0 || strcmp(type, "projection") == 0) {
        for (size_t i = 0; i < params->count; i++)
            params->items[i].used = 1;
        pbrt_warn(file, line, "LightSource \"%s\" is not simulated by idmr: left out", type);
        return 0;
    } else {
        return pbrt_fail(file, line, "LightSource: unknown type '%s'", type);
    }
    scene_add_light(ld->s, &light);
    return 0;
}
