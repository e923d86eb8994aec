/* mitsuba_transform.c — <transform name="to_world"> properties: lookat, matrix (4x4 or 3x3),
 * translate, rotate and scale steps, each left-multiplying the product of the steps before it
 * (host/core/xform.h does the maths). */
#include "io/mitsuba/mitsuba_loader.h"

#include <math.h>

static int transform_lookat(xmlNodePtr node, xform *out)
{
    const char *origin_text, *target_text, *up_text = mitsuba_attr(node, "up");
    double origin[3], target[3], up[3] = {0.0, 1.0, 0.0};
    if (mitsuba_require_attr(node, "origin", &origin_text) ||
        mitsuba_require_attr(node, "target", &target_text) ||
        mitsuba_parse_exact(node, origin_text, origin, 3) ||
        mitsuba_parse_exact(node, target_text, target, 3))
        return -1;
    if (up_text && mitsuba_parse_exact(node, up_text, up, 3))
        return -1;
    if (!up_text) {
        /* Mitsuba picks any perpendicular up vector; take y unless the view is along y. */
        double dir[3] = {target[0] - origin[0], target[1] - origin[1], target[2] - origin[2]};
        xform_normalize(dir);
        if (fabs(dir[1]) > 0.999) {
            up[1] = 0.0;
            up[2] = 1.0;
        }
    }
    if (xform_lookat(origin, target, up, out))
        return mitsuba_fail(node, "degenerate lookat: target equals origin or up is parallel to "
                                  "the view");
    return 0;
}

static int transform_matrix(xmlNodePtr node, xform *out)
{
    const char *text;
    double values[16];
    int count;
    if (mitsuba_require_attr(node, "value", &text) ||
        mitsuba_parse_numbers(node, text, values, 16, &count))
        return -1;
    if (count == 16)
        *out = xform_from_rows(values);
    else if (count == 9)
        *out = xform_from_3x3(values);
    else
        return mitsuba_fail(node, "expected 16 (4x4) or 9 (3x3) numbers, got %d", count);
    return 0;
}

static int transform_translate(xmlNodePtr node, xform *out)
{
    double t[3];
    if (mitsuba_attr_vector(node, 0.0, t))
        return -1;
    *out = xform_translate(t[0], t[1], t[2]);
    return 0;
}

static int transform_rotate(xmlNodePtr node, xform *out)
{
    double axis[3], angle;
    const char *angle_text;
    if (mitsuba_attr_vector(node, 0.0, axis) || mitsuba_require_attr(node, "angle", &angle_text) ||
        mitsuba_parse_number(node, angle_text, &angle))
        return -1;
    if (xform_dot(axis, axis) == 0.0)
        return mitsuba_fail(node, "the rotation axis is zero");
    *out = xform_rotate(axis, angle);
    return 0;
}

static int transform_scale(xmlNodePtr node, xform *out)
{
    const char *value = mitsuba_attr(node, "value");
    double s[3];
    if (value ? mitsuba_parse_one_or_three(node, value, s) : mitsuba_attr_vector(node, 1.0, s))
        return -1;
    *out = xform_scale(s[0], s[1], s[2]);
    return 0;
}

typedef int (*transform_step_reader)(xmlNodePtr node, xform *out);

static const struct {
    const char *tag;
    transform_step_reader read;
} transform_steps[] = {
    {"lookat", transform_lookat}, {"matrix", transform_matrix}, {"translate", transform_translate},
    {"rotate", transform_rotate}, {"scale", transform_scale},
};

/* A <transform> element: each child left-multiplies the product so far. */
static int parse_transform(xmlNodePtr node, xform *out)
{
    *out = xform_identity();
    MITSUBA_FOR_EACH_ELEMENT(child, node)
    {
        transform_step_reader read = NULL;
        for (size_t i = 0; i < sizeof transform_steps / sizeof *transform_steps; i++)
            if (mitsuba_is_tag(child, transform_steps[i].tag))
                read = transform_steps[i].read;
        if (!read)
            return mitsuba_fail(child, "unknown transform operation");
        xform step;
        if (read(child, &step))
            return -1;
        *out = xform_multiply(&step, out);
    }
    return 0;
}

int mitsuba_prop_transform(xmlNodePtr plugin, const char *name, xform *out)
{
    xmlNodePtr prop;
    *out = xform_identity();
    if (mitsuba_prop_element(plugin, name, "transform", NULL, &prop))
        return -1;
    return prop ? parse_transform(prop, out) : 0;
}
