/* mitsuba_sensor.c — the first <sensor> → the scene's pinhole camera: perspective (thinlens as
 * a pinhole, warned), fov with fov_axis (or focal_length on a 35 mm film), to_world, and the
 * film's width and height. Mitsuba's camera space looks along +z with +x pointing to the
 * image's LEFT and +y up, so right = -to_world(+x), up = to_world(+y), forward = to_world(+z),
 * re-orthonormalised; a mirroring to_world therefore mirrors the image, as in Mitsuba. */
#include "io/mitsuba/mitsuba_loader.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Mitsuba's defaults (documented in both manuals). */
#define MITSUBA_FILM_WIDTH 768
#define MITSUBA_FILM_HEIGHT 576
#define MITSUBA_FOCAL_LENGTH_MM 50.0

/* Parses "50mm" or "50" (millimetres of a 35 mm film). */
static int parse_focal_length(xmlNodePtr node, const char *text, double *mm)
{
    char number[64];
    size_t length = strlen(text);
    if (length >= 2 && strcmp(text + length - 2, "mm") == 0)
        length -= 2;
    snprintf(number, sizeof number, "%.*s", (int)length, text);
    if (mitsuba_parse_number(node, number, mm))
        return -1;
    if (*mm <= 0.0)
        return mitsuba_fail(node, "focal length must be positive");
    return 0;
}

/* fov and its axis: from fov/fov_axis, or from focal_length (35 mm film diagonal), as Mitsuba. */
static int sensor_fov(xmlNodePtr node, double *fov, char axis[16])
{
    const char *fov_axis, *focal;
    if (mitsuba_prop_find(node, "fov")) {
        xmlNodePtr prop = mitsuba_prop_find(node, "fov");
        if (mitsuba_prop_float(node, "fov", 0.0, fov) ||
            mitsuba_prop_string(node, "fov_axis", "x", &fov_axis))
            return -1;
        if (*fov <= 0.0 || *fov >= 180.0)
            return mitsuba_fail(prop, "fov must be between 0 and 180 degrees");
        static const char *axes[] = {"x", "y", "diagonal", "smaller", "larger"};
        for (size_t i = 0; i < sizeof axes / sizeof *axes; i++)
            if (strcmp(fov_axis, axes[i]) == 0) {
                snprintf(axis, 16, "%s", fov_axis);
                return 0;
            }
        return mitsuba_fail(mitsuba_prop_find(node, "fov_axis"), "unknown fov_axis '%s'",
                            fov_axis);
    }
    double mm = MITSUBA_FOCAL_LENGTH_MM;
    if (mitsuba_prop_string(node, "focal_length", NULL, &focal))
        return -1;
    if (focal && parse_focal_length(mitsuba_prop_find(node, "focal_length"), focal, &mm))
        return -1;
    *fov = 2.0 * atan(sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)) * 180.0 / M_PI;
    snprintf(axis, 16, "diagonal");
    return 0;
}

static int sensor_film(xmlNodePtr sensor, long *width, long *height)
{
    *width = MITSUBA_FILM_WIDTH;
    *height = MITSUBA_FILM_HEIGHT;
    MITSUBA_FOR_EACH_ELEMENT(film, sensor)
    {
        if (!mitsuba_is_tag(film, "film"))
            continue;
        mitsuba_mark_read(film);
        if (mitsuba_prop_int(film, "width", MITSUBA_FILM_WIDTH, width) ||
            mitsuba_prop_int(film, "height", MITSUBA_FILM_HEIGHT, height))
            return -1;
        if (*width < 1 || *height < 1 || *width > 65536 || *height > 65536)
            return mitsuba_fail(film, "film size %ldx%ld out of range", *width, *height);
        break;
    }
    return 0;
}

/* tan of the half angles along x and y from a fov measured along `axis`. */
static void sensor_tan_half(double fov, const char *axis, double width, double height,
                            double *tan_x, double *tan_y)
{
    double t = tan(fov * M_PI / 360.0);
    if (strcmp(axis, "smaller") == 0)
        axis = width > height ? "y" : "x";
    else if (strcmp(axis, "larger") == 0)
        axis = width > height ? "x" : "y";
    if (strcmp(axis, "x") == 0) {
        *tan_x = t;
        *tan_y = t * height / width;
    } else if (strcmp(axis, "y") == 0) {
        *tan_y = t;
        *tan_x = t * width / height;
    } else { /* diagonal */
        double diagonal = sqrt(width * width + height * height);
        *tan_x = t * width / diagonal;
        *tan_y = t * height / diagonal;
    }
}

/* v minus its projections on the unit vectors a (and b if non-NULL), normalised. */
static double orthogonalize(double v[3], const double a[3], const double *b)
{
    double da = xform_dot(v, a), db = b ? xform_dot(v, b) : 0.0;
    for (int k = 0; k < 3; k++)
        v[k] -= da * a[k] + (b ? db * b[k] : 0.0);
    return xform_normalize(v);
}

/* The camera frame: forward = M(+z), up = M(+y), right = -M(+x) (Mitsuba's +x is image-left). */
static int sensor_frame(xmlNodePtr node, const xform *to_world, idmr_camera *camera)
{
    static const double zero[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    double origin[3], forward[3], up[3], left[3];
    xform_apply_point(to_world, zero, origin);
    xform_apply_vector(to_world, z, forward);
    xform_apply_vector(to_world, y, up);
    xform_apply_vector(to_world, x, left);
    if (xform_normalize(forward) == 0.0 || orthogonalize(up, forward, NULL) < 1e-9 ||
        orthogonalize(left, forward, up) < 1e-9)
        return mitsuba_fail(node, "the sensor's to_world transform is degenerate");
    for (int k = 0; k < 3; k++) {
        camera->origin[k] = (float)origin[k];
        camera->forward[k] = (float)forward[k];
        camera->up[k] = (float)up[k];
        camera->right[k] = (float)-left[k];
    }
    return 0;
}

int mitsuba_load_sensor(loader *ld, xmlNodePtr node)
{
    const char *type;
    double fov, tan_x, tan_y;
    long width, height;
    xform to_world;
    char axis[16];
    if (mitsuba_require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "perspective") && strcmp(type, "thinlens"))
        return mitsuba_fail(node, "unsupported sensor type '%s'", type);
    if (ld->s->has_camera) {
        mitsuba_warn_at(node, "only the first sensor is used: ignored");
        return 0;
    }
    mitsuba_mark_read(node);
    if (strcmp(type, "thinlens") == 0)
        mitsuba_warn_at(node, "thinlens sensor treated as a pinhole (no depth of field)");
    if (sensor_fov(node, &fov, axis) || mitsuba_prop_transform(node, "to_world", &to_world) ||
        sensor_film(node, &width, &height))
        return -1;
    idmr_camera *camera = &ld->s->camera;
    memset(camera, 0, sizeof *camera);
    if (sensor_frame(node, &to_world, camera))
        return -1;
    sensor_tan_half(fov, axis, (double)width, (double)height, &tan_x, &tan_y);
    camera->width = (unsigned int)width;
    camera->height = (unsigned int)height;
    camera->tan_half_x = (float)tan_x;
    camera->tan_half_y = (float)tan_y;
    ld->s->camera_info.fov_degrees = (float)fov;
    snprintf(ld->s->camera_info.fov_axis, sizeof ld->s->camera_info.fov_axis, "%s", axis);
    xform_to_float(&to_world, ld->s->camera_info.to_world);
    ld->s->has_camera = 1;
    return 0;
}
