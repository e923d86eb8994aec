/* mitsuba_emitter.c — <emitter> elements → lights: point, spot, directional, area (inside a
 * shape, or declared with an id for shapes to <ref>), constant (radiance) and envmap (filename,
 * scale, to_world): the scene's one environment map (scene_add_environment; a constant is a
 * 1 × 1 map). */
#include "io/mitsuba/mitsuba_loader.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image.h"

/* Mitsuba's default spot cutoff angle (degrees, documented in both manuals). */
#define MITSUBA_SPOT_CUTOFF 20.0

static int emitter_point(loader *ld, xmlNodePtr node, idmr_light *light)
{
    static const double zero[3] = {0, 0, 0};
    double position[3];
    int found;
    xform to_world;
    light->kind = IDMR_LIGHT_POINT;
    if (mitsuba_prop_vector(node, "position", position, &found) ||
        mitsuba_prop_transform(node, "to_world", &to_world) ||
        mitsuba_prop_color(ld, node, "intensity", 1.0f, light->emission, NULL))
        return -1;
    if (!found)
        xform_apply_point(&to_world, zero, position);
    for (int k = 0; k < 3; k++)
        light->position[k] = (float)position[k];
    return 0;
}

/* Position and unit +z axis of an emitter's to_world. */
static int emitter_frame(xmlNodePtr node, double position[3], double axis[3])
{
    static const double zero[3] = {0, 0, 0}, z[3] = {0, 0, 1};
    xform to_world;
    if (mitsuba_prop_transform(node, "to_world", &to_world))
        return -1;
    xform_apply_point(&to_world, zero, position);
    xform_apply_vector(&to_world, z, axis);
    if (xform_normalize(axis) == 0.0)
        return mitsuba_fail(node, "to_world maps +z to zero");
    return 0;
}

static int emitter_spot(loader *ld, xmlNodePtr node, idmr_light *light)
{
    double position[3], axis[3], cutoff, beam;
    light->kind = IDMR_LIGHT_SPOT;
    if (emitter_frame(node, position, axis) ||
        mitsuba_prop_color(ld, node, "intensity", 1.0f, light->emission, NULL) ||
        mitsuba_prop_float(node, "cutoff_angle", MITSUBA_SPOT_CUTOFF, &cutoff) ||
        mitsuba_prop_float(node, "beam_width", cutoff * 0.75, &beam))
        return -1;
    if (cutoff <= 0.0 || cutoff > 180.0)
        return mitsuba_fail(node, "cutoff_angle must be in (0, 180] degrees");
    if (beam > cutoff)
        beam = cutoff;
    for (int k = 0; k < 3; k++) {
        light->position[k] = (float)position[k];
        light->direction[k] = (float)axis[k];
    }
    light->cos_cutoff = (float)cos(cutoff * M_PI / 180.0);
    light->cos_falloff_start = (float)cos(beam * M_PI / 180.0);
    return 0;
}

static int emitter_directional(loader *ld, xmlNodePtr node, idmr_light *light)
{
    double position[3], direction[3];
    int found;
    light->kind = IDMR_LIGHT_DIRECTIONAL;
    if (mitsuba_prop_vector(node, "direction", direction, &found) ||
        mitsuba_prop_color(ld, node, "irradiance", 1.0f, light->emission, NULL))
        return -1;
    if (!found && emitter_frame(node, position, direction))
        return -1;
    if (xform_normalize(direction) == 0.0)
        return mitsuba_fail(node, "the direction is zero");
    for (int k = 0; k < 3; k++)
        light->direction[k] = (float)direction[k];
    return 0;
}

int mitsuba_emitter_area(loader *ld, xmlNodePtr node, idmr_light *light)
{
    light->kind = IDMR_LIGHT_AREA;
    return mitsuba_prop_color(ld, node, "radiance", 1.0f, light->emission, NULL);
}

/* The linear part of an emitter's to_world, row-major. */
static int emitter_rotation(xmlNodePtr node, double rotation[9])
{
    xform to_world;
    if (mitsuba_prop_transform(node, "to_world", &to_world))
        return -1;
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 3; col++)
            rotation[3 * row + col] = to_world.m[4 * row + col];
    return 0;
}

/* constant (radiance: a 1 × 1 map) and envmap (filename, scale, to_world): the scene's
 * environment light. */
static int emitter_environment(loader *ld, xmlNodePtr node, const char *type)
{
    double to_world[9];
    int width = 1, height = 1;
    float *rgb = NULL;
    char *path = NULL;
    if (strcmp(type, "constant") == 0) {
        static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(to_world, identity, sizeof to_world);
        rgb = xmalloc(3 * sizeof *rgb);
        if (mitsuba_prop_color(ld, node, "radiance", 1.0f, rgb, NULL)) {
            free(rgb);
            return -1;
        }
    } else {
        const char *file;
        double scale;
        if (mitsuba_prop_string(node, "filename", NULL, &file) ||
            mitsuba_prop_float(node, "scale", 1.0, &scale) || emitter_rotation(node, to_world))
            return -1;
        if (!file)
            return mitsuba_fail(node, "an envmap needs a filename");
        path = mitsuba_resolve_path(ld, node, file);
        if (image_read_rgb(path, &width, &height, &rgb)) {
            free(path);
            return mitsuba_fail_prefix(node);
        }
        for (size_t i = 0; i < 3 * (size_t)width * height; i++)
            rgb[i] = (float)(rgb[i] * scale);
    }
    int index = scene_add_environment(ld->s, path, width, height, rgb, to_world);
    free(path);
    return index < 0 ? mitsuba_fail_prefix(node) : 0;
}

/* A declared area emitter: checked here, registered for <ref> from shapes, added with each
 * shape that refers to it. */
static int emitter_area_declaration(loader *ld, xmlNodePtr node, idmr_light *light)
{
    if (!mitsuba_attr(node, "id"))
        return mitsuba_fail(node, "an area emitter must be inside a shape (or have an id)");
    return mitsuba_emitter_area(ld, node, light) || mitsuba_id_register(ld, node) ? -1 : 0;
}

int mitsuba_load_emitter(loader *ld, xmlNodePtr node)
{
    const char *type;
    idmr_light light;
    int status;
    memset(&light, 0, sizeof light);
    if (mitsuba_require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "area") == 0)
        return emitter_area_declaration(ld, node, &light);
    if (strcmp(type, "point") == 0)
        status = emitter_point(ld, node, &light);
    else if (strcmp(type, "spot") == 0)
        status = emitter_spot(ld, node, &light);
    else if (strcmp(type, "directional") == 0)
        status = emitter_directional(ld, node, &light);
    else if (strcmp(type, "envmap") == 0 || strcmp(type, "constant") == 0)
        return emitter_environment(ld, node, type);
    else
        return mitsuba_fail(node, "unsupported emitter type '%s'", type);
    if (status)
        return -1;
    scene_add_light(ld->s, &light);
    return 0;
}
