/* mitsuba_unread.c — what the loader did not read, said out loud: a property whose name no
 * reader asked for (a misspelling such as `radiance2`), a property without a name, an element
 * in a place where nothing reads it. Each is a warning naming file, line and element; idmr goes
 * on without it.
 *
 * Warn, not fail: Mitsuba 3 rejects a property its plugin does not query, but idmr reads only
 * what the light transport it simulates needs, so a scene written for Mitsuba carries many
 * valid properties idmr has no use for (a film's pixel format, a sampler's sample count). Those
 * are listed below and pass in silence; anything else is reported. The reduced scene keeps
 * every property as written, so Mitsuba 3 still judges them when it renders the output.
 *
 * How "read" is known: every reader finds its properties through mitsuba_prop_find() (or picks
 * a nested plugin by hand), which marks the node. After a successful load, the plugins idmr
 * read are walked once; a warning repeated for the same element, type and name (a thousand
 * shapes with the same misspelling) is printed once, with the count of repeats. */
#include "io/mitsuba/mitsuba_loader.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

/* The value of a node's _private (libxml2 leaves that field to the application) once read. */
static char read_marker;

void mitsuba_mark_read(xmlNodePtr node)
{
    if (node)
        node->_private = &read_marker;
}

static int is_read(xmlNodePtr node)
{
    return node->_private == &read_marker;
}

/* Elements whose children are plugins' properties or nested plugins (and are walked). */
static int is_plugin(xmlNodePtr node)
{
    static const char *const plugins[] = {"scene",   "shape", "bsdf",   "emitter", "sensor",
                                          "texture", "film",  "sampler", "rfilter", "medium",
                                          "phase",   "volume", "integrator"};
    for (size_t i = 0; i < sizeof plugins / sizeof *plugins; i++)
        if (mitsuba_is_tag(node, plugins[i]))
            return 1;
    return 0;
}

/* Valid Mitsuba 3 properties and plugins that idmr does not read, by the element they are in
 * ("*": of any type) and their name ("<tag>": a nested plugin of that tag, whatever its name).
 * Those that change only how the renderer samples or stores its image pass in silence; those
 * that change what the image shows (an effect idmr does not simulate) are warned about, once,
 * with what idmr does instead. */
static const struct {
    const char *parent, *type, *name;
    int warn;
    const char *why;
} ignored[] = {
    {"sensor", "*", "<sampler>", 0, "the sample count is the renderer's"},
    {"sensor", "*", "near_clip", 0, "idmr clips nothing"},
    {"sensor", "*", "far_clip", 0, "idmr clips nothing"},
    {"sensor", "*", "focus_distance", 0, "a pinhole camera (thinlens is warned about)"},
    {"sensor", "thinlens", "aperture_radius", 0, "a pinhole camera (thinlens is warned about)"},
    {"sensor", "*", "shutter_open", 0, "no motion blur"},
    {"sensor", "*", "shutter_close", 0, "no motion blur"},
    {"sensor", "*", "principal_point_offset_x", 1, "the principal point is the film's centre"},
    {"sensor", "*", "principal_point_offset_y", 1, "the principal point is the film's centre"},
    {"film", "*", "<rfilter>", 0, "the pixel filter is the renderer's"},
    {"film", "*", "file_format", 0, "the output format is the renderer's"},
    {"film", "*", "pixel_format", 0, "the output format is the renderer's"},
    {"film", "*", "component_format", 0, "the output format is the renderer's"},
    {"film", "*", "sample_border", 0, "the pixel filter is the renderer's"},
    {"film", "*", "compensate", 0, "the output format is the renderer's"},
    {"film", "*", "banner", 0, "the output format is the renderer's (Mitsuba 0.x)"},
    {"film", "*", "high_quality_edges", 0, "the pixel filter is the renderer's (Mitsuba 0.x)"},
    {"film", "*", "crop_offset_x", 1, "idmr learns from the whole film"},
    {"film", "*", "crop_offset_y", 1, "idmr learns from the whole film"},
    {"film", "*", "crop_width", 1, "idmr learns from the whole film"},
    {"film", "*", "crop_height", 1, "idmr learns from the whole film"},
    {"bsdf", "plastic", "nonlinear", 0, "idmr's plastic is linear"},
    {"bsdf", "roughplastic", "nonlinear", 0, "idmr's plastic is linear"},
    {"bsdf", "*", "sample_visible", 0, "how the renderer samples a microfacet lobe"},
    {"bsdf", "*", "specular_transmittance", 1, "the transmittance is 1"},
    {"bsdf", "mask", "opacity", 1, "the surface is opaque"},
    {"emitter", "envmap", "mis_compensation", 0, "how the renderer samples the map"},
    {"emitter", "spot", "texture", 1, "the spot's beam is uniform"},
    {"texture", "*", "filter_type", 0, "textures are looked up at the nearest texel"},
    {"texture", "*", "wrap_mode", 0, "textures repeat"},
    {"texture", "*", "raw", 1, "textures are read as sRGB colours"},
    {"texture", "*", "to_uv", 1, "texture coordinates are used as the mesh has them"},
    {"texture", "*", "accel", 0, "how the renderer looks textures up"},
};

/* The entry of ignored[] for child of parent, or -1. */
static int ignored_entry(xmlNodePtr parent, xmlNodePtr child)
{
    const char *type = mitsuba_attr(parent, "type");
    const char *name = mitsuba_attr(child, "name");
    char tag[64];
    snprintf(tag, sizeof tag, "<%s>", (const char *)child->name);
    for (size_t i = 0; i < sizeof ignored / sizeof *ignored; i++) {
        if (!mitsuba_is_tag(parent, ignored[i].parent))
            continue;
        if (strcmp(ignored[i].type, "*") != 0 && (!type || strcmp(type, ignored[i].type) != 0))
            continue;
        if (strcmp(ignored[i].name, tag) == 0 || (name && strcmp(ignored[i].name, name) == 0))
            return (int)i;
    }
    return -1;
}

/* "<tag attribute="value">", or "<tag>" without that attribute (a property's name as the file
 * spells it). */
static void describe(xmlNodePtr node, const char *attribute, char *out, size_t size)
{
    const char *value = mitsuba_attr(node, attribute);
    if (strcmp(attribute, "name") == 0 && mitsuba_attr(node, MITSUBA_WRITTEN_NAME))
        value = mitsuba_attr(node, MITSUBA_WRITTEN_NAME);
    if (value)
        snprintf(out, size, "<%s %s=\"%s\">", (const char *)node->name, attribute, value);
    else
        snprintf(out, size, "<%s>", (const char *)node->name);
}

/* One kind of warning (an element in a plugin of a type) and how often it came. */
typedef struct unread_kind {
    char what[512];  /* "<float name="x"> in <bsdf type="y">" */
    char first[512]; /* "file:line" of the first */
    size_t count;
} unread_kind;

typedef struct unread_log {
    unread_kind *kinds;
    size_t count, capacity;
} unread_log;

/* Whether `what` (child, described) is the first warning of its kind; a repeat is counted. */
static int first_of_kind(unread_log *log, const char *what, xmlNodePtr child)
{
    for (size_t i = 0; i < log->count; i++)
        if (strcmp(log->kinds[i].what, what) == 0) {
            log->kinds[i].count++;
            return 0;
        }
    if (log->count == log->capacity) {
        log->capacity = log->capacity ? 2 * log->capacity : 16;
        log->kinds = xrealloc(log->kinds, log->capacity * sizeof *log->kinds);
    }
    unread_kind *kind = &log->kinds[log->count++];
    snprintf(kind->what, sizeof kind->what, "%s", what);
    snprintf(kind->first, sizeof kind->first, "%s:%ld", mitsuba_node_file(child),
             xmlGetLineNo(child));
    kind->count = 1;
    return 1;
}

/* The warning for child, which no reader marked, of plugin (entry: its ignored[] row or -1). */
static void warn_unread(unread_log *log, xmlNodePtr plugin, xmlNodePtr child, int entry)
{
    char child_text[240], plugin_text[240], what[512];
    describe(child, "name", child_text, sizeof child_text);
    describe(plugin, "type", plugin_text, sizeof plugin_text);
    snprintf(what, sizeof what, "%s in %s", child_text, plugin_text);
    if (!first_of_kind(log, what, child))
        return;
    if (entry >= 0)
        mitsuba_warn_at(child, "not simulated: %s", ignored[entry].why);
    else if (mitsuba_attr(child, "name"))
        mitsuba_warn_at(child, "ignored: not a property idmr reads in %s (misspelled? Mitsuba 3 "
                               "rejects a property its plugin does not know)",
                        plugin_text);
    else if (is_plugin(child))
        mitsuba_warn_at(child, "ignored: idmr reads no such element in %s", plugin_text);
    else
        mitsuba_warn_at(child, "ignored: a property needs a name attribute");
}

/* Walks the children of a plugin that was read. */
static void check_plugin(unread_log *log, xmlNodePtr plugin)
{
    MITSUBA_FOR_EACH_ELEMENT(child, plugin)
    {
        int entry = is_read(child) ? -1 : ignored_entry(plugin, child);
        if (is_read(child) && is_plugin(child))
            check_plugin(log, child);
        else if (!is_read(child) && (entry < 0 || ignored[entry].warn))
            warn_unread(log, plugin, child, entry);
    }
}

void mitsuba_warn_unread(xmlDocPtr *docs, size_t doc_count)
{
    unread_log log = {0};
    for (size_t d = 0; d < doc_count; d++) {
        MITSUBA_FOR_EACH_ELEMENT(top, xmlDocGetRootElement(docs[d]))
        {
            if (is_read(top) && is_plugin(top))
                check_plugin(&log, top);
        }
    }
    for (size_t i = 0; i < log.count; i++)
        if (log.kinds[i].count > 1)
            warn("%s: %s: the warning came %zu times in all, the first here", log.kinds[i].first,
                 log.kinds[i].what, log.kinds[i].count);
    free(log.kinds);
}
