/* pbrt_camera.c — Camera "perspective" and Film → the scene's pinhole camera.
 *
 * The CTM at the Camera statement is pbrt's camera-from-world transform; its inverse places the
 * camera. pbrt's camera space looks along +z with +y up and +x to the image's RIGHT (its raster
 * x grows with camera x, its raster y falls with camera y), so right = W(+x), up = W(+y),
 * forward = W(+z) for W = world-from-camera, re-orthonormalised. `fov` spans the shorter image
 * axis (default 90 degrees); the film's xresolution and yresolution (default 1280 × 720) give
 * the other. camera_info.to_world is stored as a Mitsuba sensor would need it (Mitsuba's camera
 * +x is image-left): W with its x column negated. */
#include "io/pbrt/pbrt_loader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

int pbrt_read_camera(pbrt_loader *ld, const char *file, int line, const char *type,
                     pbrt_params *params)
{
    if (ld->in_world)
        return pbrt_fail(file, line, "Camera after WorldBegin");
    if (strcmp(type, "perspective") && strcmp(type, "orthographic") &&
        strcmp(type, "realistic") && strcmp(type, "spherical"))
        return pbrt_fail(file, line, "Camera: unknown camera type '%s'", type);
    if (strcmp(type, "perspective") != 0)
        return pbrt_fail(file, line,
                         "Camera \"%s\": only the perspective camera is simulated by idmr", type);
    double fov, lens_radius;
    if (pbrt_param_float(file, params, "fov", 90.0, &fov) ||
        pbrt_param_float(file, params, "lensradius", 0.0, &lens_radius))
        return -1;
    if (!(fov > 0.0 && fov < 180.0))
        return pbrt_fail(file, line, "Camera: fov %g is not between 0 and 180 degrees", fov);
    if (lens_radius > 0.0)
        pbrt_warn(file, line, "Camera: lensradius > 0: depth of field is not simulated (a pinhole)");
    pbrt_param_find(params, "focaldistance");
    if (pbrt_param_find(params, "screenwindow"))
        pbrt_warn(file, line, "Camera: screenwindow is not read: the full film is used");
    if (pbrt_param_find(params, "frameaspectratio"))
        pbrt_warn(file, line, "Camera: frameaspectratio is not read: the film's is used");
    pbrt_param_find(params, "shutteropen");
    pbrt_param_find(params, "shutterclose");
    ld->camera_seen = 1;
    ld->camera_from_world = ld->state.ctm;
    ld->fov = fov;
    free(ld->camera_file);
    ld->camera_file = xstrdup(file);
    ld->camera_line = line;
    if (ld->s->has_camera)
        ld->s->has_camera = 0; /* a later Camera replaces an earlier one, as in pbrt */
    /* pbrt names the camera's space "camera" (its world-from-camera transform). */
    xform world_from_camera;
    if (xform_invert_affine(&ld->camera_from_world, &world_from_camera))
        return pbrt_fail(file, line, "Camera: the current transform cannot be inverted");
    /* set_coordinate_system is the document's; a CoordinateSystem statement does the same. */
    for (size_t i = 0; i < ld->coordinate_system_count; i++)
        if (strcmp(ld->coordinate_systems[i].name, "camera") == 0) {
            ld->coordinate_systems[i].ctm = world_from_camera;
            return 0;
        }
    ld->coordinate_systems = xrealloc(ld->coordinate_systems, (ld->coordinate_system_count + 1) *
                                                                  sizeof *ld->coordinate_systems);
    ld->coordinate_systems[ld->coordinate_system_count++] =
        (pbrt_named_xform){xstrdup("camera"), world_from_camera};
    return 0;
}

int pbrt_read_film(pbrt_loader *ld, const char *file, int line, const char *type,
                   pbrt_params *params)
{
    long width, height;
    if (strcmp(type, "rgb") && strcmp(type, "gbuffer") && strcmp(type, "spectral") &&
        strcmp(type, "image"))
        return pbrt_fail(file, line, "Film: unknown film type '%s'", type);
    if (pbrt_param_int(file, params, "xresolution", 1280, &width) ||
        pbrt_param_int(file, params, "yresolution", 720, &height))
        return -1;
    if (width < 1 || height < 1 || width > 65536 || height > 65536)
        return pbrt_fail(file, line, "Film: resolution %ldx%ld out of range", width, height);
    /* Output settings that do not change what the camera sees. */
    static const char *const quiet[] = {"filename", "savefp16", "sensor", "iso", "whitebalance",
                                        "exposuretime", "maxcomponentvalue", "diagonal", NULL};
    for (size_t i = 0; quiet[i]; i++)
        pbrt_param_find(params, quiet[i]);
    if (pbrt_param_find(params, "cropwindow") || pbrt_param_find(params, "pixelbounds"))
        pbrt_warn(file, line, "Film: cropwindow/pixelbounds are not read: the full film is used");
    ld->film_width = width;
    ld->film_height = height;
    return 0;
}

/* v minus its projections on the unit vectors a (and b if non-NULL), normalised. */
static double orthogonalize(double v[3], const double a[3], const double *b)
{
    double da = xform_dot(v, a), db = b ? xform_dot(v, b) : 0.0;
    for (int k = 0; k < 3; k++)
        v[k] -= da * a[k] + (b ? db * b[k] : 0.0);
    return xform_normalize(v);
}

int pbrt_camera_finish(pbrt_loader *ld)
{
    if (!ld->camera_seen)
        return 0;
    static const double zero[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    xform w;
    double origin[3], forward[3], up[3], right[3];
    if (xform_invert_affine(&ld->camera_from_world, &w))
        return pbrt_fail(ld->camera_file, ld->camera_line,
                         "Camera: the current transform cannot be inverted");
    xform_apply_point(&w, zero, origin);
    xform_apply_vector(&w, z, forward);
    xform_apply_vector(&w, y, up);
    xform_apply_vector(&w, x, right);
    if (xform_normalize(forward) == 0.0 || orthogonalize(up, forward, NULL) < 1e-9 ||
        orthogonalize(right, forward, up) < 1e-9)
        return pbrt_fail(ld->camera_file, ld->camera_line,
                         "Camera: the camera transform is degenerate");
    idmr_camera *c = &ld->s->camera;
    memset(c, 0, sizeof *c);
    for (int k = 0; k < 3; k++) {
        c->origin[k] = (float)origin[k];
        c->forward[k] = (float)forward[k];
        c->up[k] = (float)up[k];
        c->right[k] = (float)right[k];
    }
    double t = tan(ld->fov * M_PI / 360.0);
    double width = (double)ld->film_width, height = (double)ld->film_height;
    c->width = (unsigned int)ld->film_width;
    c->height = (unsigned int)ld->film_height;
    if (width >= height) {
        c->tan_half_y = (float)t;
        c->tan_half_x = (float)(t * width / height);
    } else {
        c->tan_half_x = (float)t;
        c->tan_half_y = (float)(t * height / width);
    }
    ld->s->camera_info.fov_degrees = (float)ld->fov;
    snprintf(ld->s->camera_info.fov_axis, sizeof ld->s->camera_info.fov_axis, "smaller");
    xform mitsuba = w;
    for (int r = 0; r < 3; r++)
        mitsuba.m[4 * r] = -mitsuba.m[4 * r];
    xform_to_float(&mitsuba, ld->s->camera_info.to_world);
    ld->s->has_camera = 1;
    return 0;
}
