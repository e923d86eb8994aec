/* mitsuba_color.c — colour-valued properties: <rgb> (linear), <srgb> (linearised), <spectrum>
 * (a grey value, or wavelength:value pairs; converted by host/core/spectrum.h as an emission inside
 * an <emitter>, else as a reflectance, as Mitsuba 3 does), <float> (grey), and bitmap <texture>s
 * (inline or by <ref>), which only a diffuse reflectance accepts. */
#include "io/mitsuba/mitsuba_loader.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/spectrum.h"

/* How a <spectrum> converts: as an emission when an <emitter> holds it, else as a reflectance. */
static spectrum_use spectrum_use_of(xmlNodePtr node)
{
    for (xmlNodePtr up = node->parent; up && up->type == XML_ELEMENT_NODE; up = up->parent)
        if (mitsuba_is_tag(up, "emitter"))
            return SPECTRUM_EMISSION;
    return SPECTRUM_REFLECTANCE;
}

/* "400:0.5, 500:0.7, ...": increasing wavelengths (nm) with their values. */
static int parse_spectrum_pairs(xmlNodePtr node, const char *text, float rgb[3])
{
    size_t capacity = 1;
    for (const char *p = text; *p; p++)
        capacity += *p == ':';
    double *lambda = xmalloc(capacity * sizeof *lambda), *value = xmalloc(capacity * sizeof *value);
    int count = 0, status = 0;
    char token[128];
    for (const char *p = text; status == 0 && mitsuba_next_token(&p, token, sizeof token);) {
        char *colon = strchr(token, ':');
        if (!colon) {
            status = mitsuba_fail(node, "'%s' is not a wavelength:value pair", token);
            break;
        }
        *colon = '\0';
        status = mitsuba_parse_number(node, token, &lambda[count]) ||
                 mitsuba_parse_number(node, colon + 1, &value[count]);
        if (status == 0 && count > 0 && lambda[count] <= lambda[count - 1])
            status = mitsuba_fail(node, "wavelengths must increase (%g after %g)", lambda[count],
                                  lambda[count - 1]);
        count++;
    }
    if (status == 0 && count == 0)
        status = mitsuba_fail(node, "empty spectrum");
    if (status == 0)
        spectrum_to_rgb(lambda, value, count, spectrum_use_of(node), rgb);
    free(lambda);
    free(value);
    return status ? -1 : 0;
}

static int parse_spectrum(xmlNodePtr node, const char *value, float rgb[3])
{
    if (mitsuba_attr(node, "filename"))
        return mitsuba_fail(node, "spectra from files are not supported");
    if (strchr(value, ':'))
        return parse_spectrum_pairs(node, value, rgb);
    double grey;
    if (mitsuba_parse_number(node, value, &grey))
        return -1;
    spectrum_to_rgb(NULL, &grey, 1, spectrum_use_of(node), rgb);
    return 0;
}

int mitsuba_texture_check(xmlNodePtr node)
{
    const char *type;
    if (mitsuba_require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "bitmap") != 0)
        return mitsuba_fail(node, "unsupported texture type '%s' (only bitmap)", type);
    if (!mitsuba_prop_find(node, "filename"))
        return mitsuba_fail(node, "a bitmap needs a <string name=\"filename\">");
    return 0;
}

/* <rgb>, <srgb> or <float>: one or three numbers (one is grey); srgb is linearised. */
static int parse_rgb(xmlNodePtr prop, const char *value, float rgb[3])
{
    double values[3];
    if (mitsuba_parse_one_or_three(prop, value, values))
        return -1;
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)values[k];
    if (mitsuba_is_tag(prop, "srgb"))
        for (int k = 0; k < 3; k++)
            rgb[k] = spectrum_srgb_to_linear(rgb[k]);
    return 0;
}

/* A colour-valued property node, or a bitmap texture (inline or by reference; then *texture is
 * set and rgb is left alone). */
static int parse_color(loader *ld, xmlNodePtr prop, float rgb[3], xmlNodePtr *texture)
{
    const char *value = NULL;
    if (mitsuba_is_tag(prop, "ref")) {
        mitsuba_id *entry = mitsuba_ref_resolve(ld, prop);
        if (!entry)
            return -1;
        if (!mitsuba_is_tag(entry->node, "texture"))
            return mitsuba_fail(prop, "'%s' is not a texture", entry->id);
        prop = entry->node;
    }
    if (mitsuba_is_tag(prop, "texture")) {
        if (mitsuba_texture_check(prop))
            return -1;
        *texture = prop;
        return 0;
    }
    if (!mitsuba_is_tag(prop, "rgb") && !mitsuba_is_tag(prop, "srgb") &&
        !mitsuba_is_tag(prop, "spectrum") && !mitsuba_is_tag(prop, "float"))
        return mitsuba_fail(prop,
                            "expected a colour (<rgb>, <srgb>, <spectrum>, <float> or <texture>)");
    if (mitsuba_require_attr(prop, "value", &value))
        return -1;
    if (mitsuba_is_tag(prop, "spectrum"))
        return parse_spectrum(prop, value, rgb);
    return parse_rgb(prop, value, rgb);
}

int mitsuba_prop_color(loader *ld, xmlNodePtr plugin, const char *name, float fallback,
                       float rgb[3], xmlNodePtr *texture)
{
    xmlNodePtr prop = mitsuba_prop_find(plugin, name), found = NULL;
    rgb[0] = rgb[1] = rgb[2] = fallback;
    if (texture)
        *texture = NULL;
    if (!prop)
        return 0;
    if (parse_color(ld, prop, rgb, &found))
        return -1;
    if (found && texture)
        *texture = found;
    else if (found)
        mitsuba_warn_at(prop, "a texture is only supported as diffuse reflectance: using %g",
                        fallback);
    return 0;
}
