/* mitsuba.c — Mitsuba XML → scene (see mitsuba.h for what is read and how the two dialects
 * are unified).
 *
 * Sections, in order: messages, small tree helpers, the document (reading, <default>
 * substitution, name normalisation), paths, numbers and properties, transforms, the id table,
 * colours, bsdfs, the sensor, emitters, shapes, and the top level. Every function that can fail returns
 * -1 with the error set through error_set()/error_prefix() and 0 on success. Nodes of included
 * documents stay alive until the load ends, since the id table points into them. */
#include "io/mitsuba.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include <libxml/parser.h>
#include <libxml/tree.h>

#include "core/error.h"
#include "io/image.h"
#include "io/mesh_io.h"
#include "io/mitsuba_text.h"
#include "io/shapes.h"
#include "io/spectrum.h"
#include "io/xform.h"

#define MITSUBA_MAX_NESTING 16
#define MITSUBA_MESSAGE_MAX 1024
/* Attribute that keeps a normalised property name's original spelling, for messages. */
#define MITSUBA_WRITTEN_NAME "idmr_written_name"

/* Mitsuba's defaults (documented in both manuals). */
#define MITSUBA_IOR_BK7 1.5046
#define MITSUBA_IOR_POLYPROPYLENE 1.49
#define MITSUBA_IOR_AIR 1.000277
#define MITSUBA_ALPHA 0.1
#define MITSUBA_FILM_WIDTH 768
#define MITSUBA_FILM_HEIGHT 576
#define MITSUBA_SPOT_CUTOFF 20.0
#define MITSUBA_FOCAL_LENGTH_MM 50.0


struct bsdf_parsed;

typedef struct mitsuba_id {
    char *id;
    xmlNodePtr node;
    struct bsdf_parsed *bsdf; /* a bsdf as parsed at its declaration (parsed once: warnings too) */
    int material; /* scene material made from this bsdf, or -1 until first referenced */
} mitsuba_id;

typedef struct loader {
    scene *s;
    xmlDocPtr *docs; /* the scene file first, then included fragments */
    size_t doc_count;
    mitsuba_params params; /* <default> values */
    mitsuba_id *ids;
    size_t id_count;
    int major_version;    /* 0 for Mitsuba 0.x files, else 3 */
    int default_material; /* the shared diffuse 0.5, or -1 until needed */
    int environment_warned;
} loader;

/* ---------------------------------------------------------------------------------------- */
/* Messages                                                                                 */

static const char *node_file(xmlNodePtr node)
{
    return node->doc && node->doc->URL ? (const char *)node->doc->URL : "?";
}

/* `<tag type="..." name="..." id="...">` with the attributes in document order. */
static void node_describe(xmlNodePtr node, char *out, size_t size)
{
    size_t used = (size_t)snprintf(out, size, "<%s", (const char *)node->name);
    for (xmlAttrPtr a = node->properties; a && used < size; a = a->next) {
        const char *key = (const char *)a->name;
        if (strcmp(key, "type") && strcmp(key, "name") && strcmp(key, "id"))
            continue;
        const char *value = a->children && a->children->content
                                ? (const char *)a->children->content
                                : "";
        /* Show a property name as the file spells it (intIOR, not int_ior). */
        if (strcmp(key, "name") == 0 && mitsuba_attr(node, MITSUBA_WRITTEN_NAME))
            value = mitsuba_attr(node, MITSUBA_WRITTEN_NAME);
        used += (size_t)snprintf(out + used, size - used, " %s=\"%s\"", key, value);
    }
    if (used < size)
        snprintf(out + used, size - used, ">");
}

static int fail(xmlNodePtr node, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail(xmlNodePtr node, const char *fmt, ...)
{
    char what[MITSUBA_MESSAGE_MAX], element[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(what, sizeof what, fmt, args);
    va_end(args);
    node_describe(node, element, sizeof element);
    return error_set(IDMR_EXIT_INPUT, "%s:%ld: %s: %s", node_file(node), xmlGetLineNo(node),
                     element, what);
}

/* Puts "file:line: <element>" in front of an error set by another module. */
static int fail_prefix(xmlNodePtr node)
{
    char element[256];
    node_describe(node, element, sizeof element);
    return error_prefix("%s:%ld: %s", node_file(node), xmlGetLineNo(node), element);
}

static void warn_at(xmlNodePtr node, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn_at(xmlNodePtr node, const char *fmt, ...)
{
    char what[MITSUBA_MESSAGE_MAX], element[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(what, sizeof what, fmt, args);
    va_end(args);
    node_describe(node, element, sizeof element);
    warn("%s:%ld: %s: %s", node_file(node), xmlGetLineNo(node), element, what);
}

/* ---------------------------------------------------------------------------------------- */
/* Small tree helpers                                                                       */

static xmlNodePtr first_element(xmlNodePtr node)
{
    while (node && node->type != XML_ELEMENT_NODE)
        node = node->next;
    return node;
}

#define FOR_EACH_ELEMENT(child, parent)                                                         \
    for (xmlNodePtr child = first_element((parent)->children); child;                          \
         child = first_element(child->next))

static int require_attr(xmlNodePtr node, const char *name, const char **out)
{
    *out = mitsuba_attr(node, name);
    if (!*out)
        return fail(node, "missing attribute '%s'", name);
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* The document: reading, <default> parameters, name normalisation                          */

void mitsuba_snake_case(const char *name, char *out, size_t size)
{
    size_t used = 0;
    if (size == 0)
        return;
    for (size_t i = 0; name[i] && used + 1 < size; i++) {
        unsigned char c = (unsigned char)name[i];
        if (i > 0 && isupper(c)) {
            unsigned char prev = (unsigned char)name[i - 1];
            unsigned char next = (unsigned char)name[i + 1];
            int boundary = islower(prev) || isdigit(prev) || (isupper(prev) && islower(next));
            if (boundary && prev != '_' && used + 2 < size)
                out[used++] = '_';
        }
        out[used++] = (char)tolower(c);
    }
    out[used] = '\0';
}

static void trim_trailing_space(char *text)
{
    size_t length = strlen(text);
    while (length > 0 && isspace((unsigned char)text[length - 1]))
        text[--length] = '\0';
}

/* Parses `path` into a document; a parse error names the file and line. */
xmlDocPtr mitsuba_read_xml(const char *path)
{
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        error_set(IDMR_EXIT_INPUT, "cannot read scene '%s': %s", path, strerror(errno));
        return NULL;
    }
    fclose(probe);
    xmlParserCtxtPtr context = xmlNewParserCtxt();
    if (!context) {
        error_set(IDMR_EXIT_FAILURE, "%s: cannot create an XML parser", path);
        return NULL;
    }
    int options = XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES;
    xmlDocPtr doc = xmlCtxtReadFile(context, path, NULL, options);
    if (!doc) {
        const xmlError *e = xmlCtxtGetLastError(context);
        char message[MITSUBA_MESSAGE_MAX];
        snprintf(message, sizeof message, "%s", e && e->message ? e->message : "unknown error");
        trim_trailing_space(message);
        error_set(IDMR_EXIT_INPUT, "%s:%d: malformed XML: %s", path, e ? e->line : 0, message);
    } else if (!xmlDocGetRootElement(doc)) {
        error_set(IDMR_EXIT_INPUT, "%s: empty document", path);
        xmlFreeDoc(doc);
        doc = NULL;
    }
    xmlFreeParserCtxt(context);
    return doc;
}

/* Records the <default> elements directly under `root`; an earlier definition wins. */
static int collect_params(loader *ld, xmlNodePtr root)
{
    FOR_EACH_ELEMENT(child, root)
    {
        const char *name, *value;
        if (!mitsuba_is_tag(child, "default"))
            continue;
        if (require_attr(child, "name", &name) || require_attr(child, "value", &value))
            return -1;
        mitsuba_params_add(&ld->params, name, value);
    }
    return 0;
}

/* Returns a malloc'd copy of `text` with each $name replaced by its <default> value. */
static char *substitute(const loader *ld, xmlNodePtr node, const char *text)
{
    char missing[256];
    char *out = mitsuba_substitute(&ld->params, text, missing, sizeof missing);
    if (!out)
        fail(node, "undefined parameter '%s' (no <default name=\"%s\">)", missing, missing + 1);
    return out;
}

/* Substitutes parameters in every attribute and snake_cases every property name, in place. */
static int prepare_tree(loader *ld, xmlNodePtr node)
{
    if (mitsuba_is_tag(node, "default"))
        return 0;
    for (xmlAttrPtr a = node->properties; a; a = a->next) {
        const char *value = a->children && a->children->content
                                ? (const char *)a->children->content
                                : "";
        char *fixed = NULL;
        if (strchr(value, '$') && !(fixed = substitute(ld, node, value)))
            return -1;
        if (strcmp((const char *)a->name, "name") == 0) {
            char snake[256];
            const char *written = fixed ? fixed : value;
            mitsuba_snake_case(written, snake, sizeof snake);
            if (strcmp(snake, written) != 0)
                xmlSetProp(node, (const xmlChar *)MITSUBA_WRITTEN_NAME, (const xmlChar *)written);
            free(fixed);
            fixed = xstrdup(snake);
        }
        if (fixed)
            xmlSetProp(node, a->name, (const xmlChar *)fixed);
        free(fixed);
    }
    FOR_EACH_ELEMENT(child, node)
    {
        if (prepare_tree(ld, child))
            return -1;
    }
    return 0;
}

/* Reads a scene file or fragment, checks its root, and prepares it; returns its <scene>. */
static xmlNodePtr open_document(loader *ld, const char *path)
{
    xmlDocPtr doc = mitsuba_read_xml(path);
    if (!doc)
        return NULL;
    ld->docs = xrealloc(ld->docs, (ld->doc_count + 1) * sizeof *ld->docs);
    ld->docs[ld->doc_count++] = doc;
    xmlNodePtr root = xmlDocGetRootElement(doc);
    if (!mitsuba_is_tag(root, "scene")) {
        fail(root, "the root element must be <scene>");
        return NULL;
    }
    if (collect_params(ld, root) || prepare_tree(ld, root))
        return NULL;
    return root;
}

/* "0.5.0" → 0, "3.0.0" → 3; files without a version are read as 3.x. */
static int parse_major_version(xmlNodePtr root)
{
    const char *version = mitsuba_attr(root, "version");
    return version && atoi(version) < 1 ? 0 : 3;
}

/* ---------------------------------------------------------------------------------------- */
/* Paths                                                                                    */

/* `written` resolved against the directory of the file that names it, then the scene's. */
static char *resolve_path(const loader *ld, xmlNodePtr node, const char *written)
{
    return mitsuba_resolve(node_file(node), ld->s->dir, written, NULL);
}

/* ---------------------------------------------------------------------------------------- */
/* Numbers                                                                                  */

static int parse_number(xmlNodePtr node, const char *text, double *out)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    while (end && isspace((unsigned char)*end))
        end++;
    if (end == text || *end || !isfinite(value) || errno == ERANGE)
        return fail(node, "'%s' is not a number", text);
    *out = value;
    return 0;
}

static int parse_integer(xmlNodePtr node, const char *text, long *out)
{
    char *end;
    errno = 0;
    long value = strtol(text, &end, 10);
    while (end && isspace((unsigned char)*end))
        end++;
    if (end == text || *end || errno == ERANGE)
        return fail(node, "'%s' is not an integer", text);
    *out = value;
    return 0;
}

static int is_separator(char c)
{
    return c == ',' || isspace((unsigned char)c);
}

/* Parses up to `max` numbers separated by commas and/or white space into out; *count gets how
 * many there were (more than max is an error). */
static int parse_numbers(xmlNodePtr node, const char *text, double *out, int max, int *count)
{
    char token[128];
    *count = 0;
    for (const char *p = text;;) {
        while (is_separator(*p))
            p++;
        if (!*p)
            return 0;
        size_t length = 0;
        while (p[length] && !is_separator(p[length]))
            length++;
        if (*count == max)
            return fail(node, "'%s': more than %d numbers", text, max);
        snprintf(token, sizeof token, "%.*s", (int)length, p);
        if (parse_number(node, token, &out[(*count)++]))
            return -1;
        p += length;
    }
}

/* Exactly `expected` numbers from text. */
static int parse_exact(xmlNodePtr node, const char *text, double *out, int expected)
{
    int count;
    if (parse_numbers(node, text, out, expected, &count))
        return -1;
    if (count != expected)
        return fail(node, "'%s': expected %d numbers, got %d", text, expected, count);
    return 0;
}

/* An optional numeric attribute. */
static int attr_number(xmlNodePtr node, const char *name, double fallback, double *out)
{
    const char *text = mitsuba_attr(node, name);
    if (!text) {
        *out = fallback;
        return 0;
    }
    return parse_number(node, text, out);
}

/* A 3-vector from value="x, y, z" or from x= y= z= attributes (missing ones: fallback). */
static int attr_vector(xmlNodePtr node, double fallback, double out[3])
{
    const char *value = mitsuba_attr(node, "value");
    if (value)
        return parse_exact(node, value, out, 3);
    return attr_number(node, "x", fallback, &out[0]) || attr_number(node, "y", fallback, &out[1]) ||
                   attr_number(node, "z", fallback, &out[2])
               ? -1
               : 0;
}

/* ---------------------------------------------------------------------------------------- */
/* Properties: <float name="..." value="..."/> and friends, children of a plugin element     */

static xmlNodePtr prop_find(xmlNodePtr plugin, const char *name)
{
    FOR_EACH_ELEMENT(child, plugin)
    {
        const char *child_name = mitsuba_attr(child, "name");
        if (child_name && strcmp(child_name, name) == 0)
            return child;
    }
    return NULL;
}

static int prop_expect(xmlNodePtr prop, const char *tag, const char *also)
{
    if (mitsuba_is_tag(prop, tag) || (also && mitsuba_is_tag(prop, also)))
        return 0;
    return fail(prop, "expected <%s>", tag);
}

static int prop_float(xmlNodePtr plugin, const char *name, double fallback, double *out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    const char *value;
    *out = fallback;
    if (!prop)
        return 0;
    if (prop_expect(prop, "float", "integer") || require_attr(prop, "value", &value))
        return -1;
    return parse_number(prop, value, out);
}

static int prop_int(xmlNodePtr plugin, const char *name, long fallback, long *out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    const char *value;
    *out = fallback;
    if (!prop)
        return 0;
    if (prop_expect(prop, "integer", NULL) || require_attr(prop, "value", &value))
        return -1;
    return parse_integer(prop, value, out);
}

static int prop_bool(xmlNodePtr plugin, const char *name, int fallback, int *out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    const char *value;
    *out = fallback;
    if (!prop)
        return 0;
    if (prop_expect(prop, "boolean", NULL) || require_attr(prop, "value", &value))
        return -1;
    if (strcasecmp(value, "true") == 0)
        *out = 1;
    else if (strcasecmp(value, "false") == 0)
        *out = 0;
    else
        return fail(prop, "'%s' is not a boolean (true or false)", value);
    return 0;
}

static int prop_string(xmlNodePtr plugin, const char *name, const char *fallback, const char **out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    *out = fallback;
    if (!prop)
        return 0;
    if (prop_expect(prop, "string", NULL))
        return -1;
    return require_attr(prop, "value", out);
}

/* A <point> or <vector>; *found tells whether it was there. */
static int prop_vector(xmlNodePtr plugin, const char *name, double out[3], int *found)
{
    xmlNodePtr prop = prop_find(plugin, name);
    *found = prop != NULL;
    if (!prop)
        return 0;
    if (prop_expect(prop, "point", "vector"))
        return -1;
    return attr_vector(prop, 0.0, out);
}

/* ---------------------------------------------------------------------------------------- */
/* Transforms                                                                               */

static int transform_lookat(xmlNodePtr node, xform *out)
{
    const char *origin_text, *target_text, *up_text = mitsuba_attr(node, "up");
    double origin[3], target[3], up[3] = {0.0, 1.0, 0.0};
    if (require_attr(node, "origin", &origin_text) || require_attr(node, "target", &target_text) ||
        parse_exact(node, origin_text, origin, 3) || parse_exact(node, target_text, target, 3))
        return -1;
    if (up_text && parse_exact(node, up_text, up, 3))
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
        return fail(node, "degenerate lookat: target equals origin or up is parallel to the view");
    return 0;
}

static int transform_matrix(xmlNodePtr node, xform *out)
{
    const char *text;
    double values[16];
    int count;
    if (require_attr(node, "value", &text) || parse_numbers(node, text, values, 16, &count))
        return -1;
    if (count == 16)
        *out = xform_from_rows(values);
    else if (count == 9)
        *out = xform_from_3x3(values);
    else
        return fail(node, "expected 16 (4x4) or 9 (3x3) numbers, got %d", count);
    return 0;
}

static int transform_rotate(xmlNodePtr node, xform *out)
{
    double axis[3], angle;
    const char *angle_text;
    if (attr_vector(node, 0.0, axis) || require_attr(node, "angle", &angle_text) ||
        parse_number(node, angle_text, &angle))
        return -1;
    if (xform_dot(axis, axis) == 0.0)
        return fail(node, "the rotation axis is zero");
    *out = xform_rotate(axis, angle);
    return 0;
}

static int transform_scale(xmlNodePtr node, xform *out)
{
    const char *value = mitsuba_attr(node, "value");
    double s[3];
    int count;
    if (value) {
        if (parse_numbers(node, value, s, 3, &count))
            return -1;
        if (count == 1)
            s[1] = s[2] = s[0];
        else if (count != 3)
            return fail(node, "'%s': expected 1 or 3 numbers", value);
    } else if (attr_vector(node, 1.0, s)) {
        return -1;
    }
    *out = xform_scale(s[0], s[1], s[2]);
    return 0;
}

/* A <transform> element: each child left-multiplies the product so far. */
static int parse_transform(xmlNodePtr node, xform *out)
{
    *out = xform_identity();
    FOR_EACH_ELEMENT(child, node)
    {
        xform step;
        double t[3];
        int status;
        if (mitsuba_is_tag(child, "lookat"))
            status = transform_lookat(child, &step);
        else if (mitsuba_is_tag(child, "matrix"))
            status = transform_matrix(child, &step);
        else if (mitsuba_is_tag(child, "translate")) {
            status = attr_vector(child, 0.0, t);
            step = xform_translate(t[0], t[1], t[2]);
        } else if (mitsuba_is_tag(child, "rotate"))
            status = transform_rotate(child, &step);
        else if (mitsuba_is_tag(child, "scale"))
            status = transform_scale(child, &step);
        else
            return fail(child, "unknown transform operation");
        if (status)
            return -1;
        *out = xform_multiply(&step, out);
    }
    return 0;
}

static int prop_transform(xmlNodePtr plugin, const char *name, xform *out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    *out = xform_identity();
    if (!prop)
        return 0;
    if (prop_expect(prop, "transform", NULL))
        return -1;
    return parse_transform(prop, out);
}

/* ---------------------------------------------------------------------------------------- */
/* The id table                                                                             */

static mitsuba_id *id_find(loader *ld, const char *id)
{
    for (size_t i = 0; i < ld->id_count; i++)
        if (strcmp(ld->ids[i].id, id) == 0)
            return &ld->ids[i];
    return NULL;
}

static int id_register(loader *ld, xmlNodePtr node)
{
    const char *id = mitsuba_attr(node, "id");
    if (!id)
        return 0;
    if (id_find(ld, id))
        return fail(node, "duplicate id '%s'", id);
    ld->ids = xrealloc(ld->ids, (ld->id_count + 1) * sizeof *ld->ids);
    ld->ids[ld->id_count].id = xstrdup(id);
    ld->ids[ld->id_count].node = node;
    ld->ids[ld->id_count].bsdf = NULL;
    ld->ids[ld->id_count].material = -1;
    ld->id_count++;
    return 0;
}

/* The declaration a <ref id=...> points to. */
static mitsuba_id *ref_resolve(loader *ld, xmlNodePtr ref)
{
    const char *id;
    if (require_attr(ref, "id", &id))
        return NULL;
    mitsuba_id *entry = id_find(ld, id);
    if (!entry)
        fail(ref, "unknown id '%s' (ids must be declared before they are referenced)", id);
    return entry;
}

/* ---------------------------------------------------------------------------------------- */
/* Colours                                                                                  */

static int parse_spectrum_pairs(xmlNodePtr node, const char *text, float rgb[3])
{
    size_t capacity = 1;
    for (const char *p = text; *p; p++)
        capacity += *p == ':';
    double *lambda = xmalloc(capacity * sizeof *lambda), *value = xmalloc(capacity * sizeof *value);
    int count = 0, status = 0;
    char token[128];
    for (const char *p = text; status == 0;) {
        while (is_separator(*p))
            p++;
        if (!*p)
            break;
        size_t length = 0;
        while (p[length] && !is_separator(p[length]))
            length++;
        snprintf(token, sizeof token, "%.*s", (int)length, p);
        p += length;
        char *colon = strchr(token, ':');
        if (!colon) {
            status = fail(node, "'%s' is not a wavelength:value pair", token);
            break;
        }
        *colon = '\0';
        status = parse_number(node, token, &lambda[count]) ||
                 parse_number(node, colon + 1, &value[count]);
        if (status == 0 && count > 0 && lambda[count] <= lambda[count - 1])
            status = fail(node, "wavelengths must increase (%g after %g)", lambda[count],
                          lambda[count - 1]);
        count++;
    }
    if (status == 0 && count == 0)
        status = fail(node, "empty spectrum");
    if (status == 0)
        spectrum_to_rgb(lambda, value, count, rgb);
    free(lambda);
    free(value);
    return status ? -1 : 0;
}

/* One or three numbers (one is grey). */
static int parse_triple(xmlNodePtr node, const char *text, float rgb[3])
{
    double values[3];
    int count;
    if (parse_numbers(node, text, values, 3, &count))
        return -1;
    if (count == 1)
        values[1] = values[2] = values[0];
    else if (count != 3)
        return fail(node, "'%s': expected 1 or 3 numbers", text);
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)values[k];
    return 0;
}

static int parse_spectrum(xmlNodePtr node, const char *value, float rgb[3])
{
    if (mitsuba_attr(node, "filename"))
        return fail(node, "spectra from files are not supported");
    if (strchr(value, ':'))
        return parse_spectrum_pairs(node, value, rgb);
    double grey;
    if (parse_number(node, value, &grey))
        return -1;
    rgb[0] = rgb[1] = rgb[2] = (float)grey;
    return 0;
}

static int texture_check(xmlNodePtr node)
{
    const char *type;
    if (require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "bitmap") != 0)
        return fail(node, "unsupported texture type '%s' (only bitmap)", type);
    if (!prop_find(node, "filename"))
        return fail(node, "a bitmap needs a <string name=\"filename\">");
    return 0;
}

/* A colour-valued property node: rgb, srgb, spectrum, float, or a bitmap texture (inline or by
 * reference; then *texture is set and rgb is left alone). */
static int parse_color(loader *ld, xmlNodePtr prop, float rgb[3], xmlNodePtr *texture)
{
    const char *value = NULL;
    if (mitsuba_is_tag(prop, "ref")) {
        mitsuba_id *entry = ref_resolve(ld, prop);
        if (!entry)
            return -1;
        if (!mitsuba_is_tag(entry->node, "texture"))
            return fail(prop, "'%s' is not a texture", entry->id);
        prop = entry->node;
    }
    if (mitsuba_is_tag(prop, "texture")) {
        if (texture_check(prop))
            return -1;
        *texture = prop;
        return 0;
    }
    if (!mitsuba_is_tag(prop, "rgb") && !mitsuba_is_tag(prop, "srgb") && !mitsuba_is_tag(prop, "spectrum") &&
        !mitsuba_is_tag(prop, "float"))
        return fail(prop, "expected a colour (<rgb>, <srgb>, <spectrum>, <float> or <texture>)");
    if (require_attr(prop, "value", &value))
        return -1;
    if (mitsuba_is_tag(prop, "spectrum"))
        return parse_spectrum(prop, value, rgb);
    if (parse_triple(prop, value, rgb))
        return -1;
    if (mitsuba_is_tag(prop, "srgb"))
        for (int k = 0; k < 3; k++)
            rgb[k] = spectrum_srgb_to_linear(rgb[k]);
    return 0;
}

/* A colour property with a grey default. A texture is accepted where `texture` is non-NULL;
 * elsewhere it is warned about and the default kept. */
static int prop_color(loader *ld, xmlNodePtr plugin, const char *name, float fallback,
                      float rgb[3], xmlNodePtr *texture)
{
    xmlNodePtr prop = prop_find(plugin, name), found = NULL;
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
        warn_at(prop, "a texture is only supported as diffuse reflectance: using %g", fallback);
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* BSDFs                                                                                    */

typedef struct bsdf_parsed {
    idmr_material material;
    char type[32];      /* the innermost Mitsuba type */
    xmlNodePtr texture; /* bitmap for the diffuse reflectance, or NULL */
} bsdf_parsed;

typedef struct named_value {
    const char *name;
    double value;
} named_value;

/* Mitsuba's named indices of refraction (its documentation's table). */
static const named_value mitsuba_iors[] = {
    {"vacuum", 1.0},          {"helium", 1.00004},         {"hydrogen", 1.00013},
    {"air", MITSUBA_IOR_AIR}, {"carbon dioxide", 1.00045}, {"water", 1.3330},
    {"acetone", 1.36},        {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
    {"glycerol", 1.4729},     {"benzene", 1.501},          {"silicone oil", 1.52045},
    {"bromine", 1.661},       {"water ice", 1.31},         {"fused quartz", 1.458},
    {"pyrex", 1.470},         {"acrylic glass", 1.49},     {"polypropylene", 1.49},
    {"bk7", MITSUBA_IOR_BK7}, {"sodium chloride", 1.544},  {"amber", 1.55},
    {"pet", 1.5750},          {"diamond", 2.419},
};

typedef struct named_color {
    const char *name;
    float rgb[3];
} named_color;

/* Normal-incidence reflectance of common metals in linear sRGB (the approximations tabulated in
 * Real-Time Rendering, 4th ed., Table 9.2). */
static const named_color mitsuba_conductors[] = {
    {"none", {1.0f, 1.0f, 1.0f}},       {"Ag", {0.972f, 0.960f, 0.915f}},
    {"Al", {0.913f, 0.922f, 0.924f}},   {"Au", {1.000f, 0.782f, 0.344f}},
    {"Cu", {0.955f, 0.638f, 0.538f}},   {"Cr", {0.549f, 0.556f, 0.554f}},
};

static int prop_ior(xmlNodePtr plugin, const char *name, double fallback, double *out)
{
    xmlNodePtr prop = prop_find(plugin, name);
    *out = fallback;
    if (!prop)
        return 0;
    if (mitsuba_is_tag(prop, "string")) {
        const char *value;
        if (require_attr(prop, "value", &value))
            return -1;
        for (size_t i = 0; i < sizeof mitsuba_iors / sizeof *mitsuba_iors; i++)
            if (strcasecmp(value, mitsuba_iors[i].name) == 0) {
                *out = mitsuba_iors[i].value;
                return 0;
            }
        return fail(prop, "unknown index of refraction '%s'", value);
    }
    if (prop_float(plugin, name, fallback, out))
        return -1;
    if (*out <= 0.0)
        return fail(prop, "an index of refraction must be positive");
    return 0;
}

static int bsdf_alpha(xmlNodePtr node, double *alpha)
{
    const char *distribution;
    double u, v;
    if (prop_string(node, "distribution", "beckmann", &distribution))
        return -1;
    if (strcmp(distribution, "ggx") && strcmp(distribution, "beckmann"))
        warn_at(node, "microfacet distribution '%s' treated as ggx", distribution);
    if (prop_float(node, "alpha", MITSUBA_ALPHA, alpha))
        return -1;
    if (!prop_find(node, "alpha") && (prop_find(node, "alpha_u") || prop_find(node, "alpha_v"))) {
        /* Anisotropic roughness: the kernels are isotropic, take the geometric mean. */
        if (prop_float(node, "alpha_u", MITSUBA_ALPHA, &u) ||
            prop_float(node, "alpha_v", MITSUBA_ALPHA, &v))
            return -1;
        *alpha = sqrt(u * v);
    }
    if (*alpha < 0.0)
        return fail(node, "roughness must not be negative");
    return 0;
}

static int bsdf_diffuse(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    out->material.kind = IDMR_MATERIAL_DIFFUSE;
    return prop_color(ld, node, "reflectance", 0.5f, out->material.reflectance, &out->texture);
}

static int bsdf_dielectric(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    double int_ior, ext_ior;
    out->material.kind = IDMR_MATERIAL_DIELECTRIC;
    if (prop_ior(node, "int_ior", MITSUBA_IOR_BK7, &int_ior) ||
        prop_ior(node, "ext_ior", MITSUBA_IOR_AIR, &ext_ior))
        return -1;
    out->material.int_ior = (float)int_ior;
    out->material.ext_ior = (float)ext_ior;
    for (int k = 0; k < 3; k++)
        out->material.specular[k] = 1.0f;
    if (strcmp(out->type, "thindielectric") == 0)
        out->material.flags |= IDMR_MATERIAL_THIN;
    if (strcmp(out->type, "roughdielectric") == 0)
        warn_at(node, "roughdielectric is treated as a smooth dielectric");
    return 0;
}

/* Normal-incidence Fresnel reflectance of a conductor with complex index eta + i k. */
static float conductor_f0(double eta, double k)
{
    return (float)(((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k));
}

/* The conductor's colour at normal incidence: eta/k if given, else the named material. */
static int conductor_color(loader *ld, xmlNodePtr node, float f0[3])
{
    if (prop_find(node, "eta")) {
        float eta[3], k[3];
        double ext_eta;
        if (prop_color(ld, node, "eta", 1.0f, eta, NULL) ||
            prop_color(ld, node, "k", 0.0f, k, NULL) ||
            prop_ior(node, "ext_eta", MITSUBA_IOR_AIR, &ext_eta))
            return -1;
        for (int c = 0; c < 3; c++)
            f0[c] = conductor_f0(eta[c] / ext_eta, k[c] / ext_eta);
        return 0;
    }
    const char *material;
    /* Mitsuba 0.6 defaults to copper, 3.x to a perfect mirror. */
    if (prop_string(node, "material", ld->major_version == 0 ? "Cu" : "none", &material))
        return -1;
    for (size_t i = 0; i < sizeof mitsuba_conductors / sizeof *mitsuba_conductors; i++)
        if (strcasecmp(material, mitsuba_conductors[i].name) == 0) {
            memcpy(f0, mitsuba_conductors[i].rgb, sizeof(float) * 3);
            return 0;
        }
    warn_at(node, "conductor material '%s' is not known here: using a grey reflectance of 0.9",
            material);
    f0[0] = f0[1] = f0[2] = 0.9f;
    return 0;
}

static int bsdf_conductor(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    float f0[3], tint[3];
    double alpha = 0.0;
    int rough = strcmp(out->type, "roughconductor") == 0;
    out->material.kind = rough ? IDMR_MATERIAL_GLOSSY : IDMR_MATERIAL_MIRROR;
    if (conductor_color(ld, node, f0) ||
        prop_color(ld, node, "specular_reflectance", 1.0f, tint, NULL))
        return -1;
    if (rough && bsdf_alpha(node, &alpha))
        return -1;
    for (int k = 0; k < 3; k++) {
        out->material.reflectance[k] = 0.0f;
        out->material.specular[k] = f0[k] * tint[k];
    }
    out->material.roughness = (float)alpha;
    return 0;
}

static int bsdf_plastic(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    double int_ior, ext_ior, alpha = 0.0;
    out->material.kind = IDMR_MATERIAL_GLOSSY;
    if (prop_color(ld, node, "diffuse_reflectance", 0.5f, out->material.reflectance,
                   &out->texture) ||
        prop_color(ld, node, "specular_reflectance", 1.0f, out->material.specular, NULL) ||
        prop_ior(node, "int_ior", MITSUBA_IOR_POLYPROPYLENE, &int_ior) ||
        prop_ior(node, "ext_ior", MITSUBA_IOR_AIR, &ext_ior))
        return -1;
    if (strcmp(out->type, "roughplastic") == 0 && bsdf_alpha(node, &alpha))
        return -1;
    out->material.int_ior = (float)int_ior;
    out->material.ext_ior = (float)ext_ior;
    out->material.roughness = (float)alpha;
    return 0;
}

static int parse_bsdf(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out);

/* The bsdf nested in a wrapper (twosided, mask, bumpmap): inline or by reference. */
static int bsdf_wrapper(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out)
{
    const char *wrapper = mitsuba_attr(node, "type");
    xmlNodePtr inner = NULL;
    int inner_count = 0;
    FOR_EACH_ELEMENT(child, node)
    {
        xmlNodePtr candidate = child;
        if (mitsuba_is_tag(child, "ref")) {
            mitsuba_id *entry = ref_resolve(ld, child);
            if (!entry)
                return -1;
            candidate = entry->node;
        }
        if (!mitsuba_is_tag(candidate, "bsdf"))
            continue;
        if (!inner_count++)
            inner = candidate;
    }
    if (!inner)
        return fail(node, "a %s bsdf needs a nested bsdf", wrapper);
    if (inner_count > 1)
        warn_at(node, "only the first nested bsdf is used (for both sides)");
    if (strcmp(wrapper, "bumpmap") == 0 || strcmp(wrapper, "normalmap") == 0)
        warn_at(node, "%s is not simulated: using its nested bsdf", wrapper);
    unsigned int flags = strcmp(wrapper, "twosided") == 0 ? IDMR_MATERIAL_TWOSIDED : 0u;
    if (parse_bsdf(ld, inner, depth + 1, out))
        return -1;
    out->material.flags |= flags;
    return 0;
}

typedef int (*bsdf_reader)(loader *ld, xmlNodePtr node, bsdf_parsed *out);

static const struct {
    const char *type;
    bsdf_reader read;
} bsdf_readers[] = {
    {"diffuse", bsdf_diffuse},         {"dielectric", bsdf_dielectric},
    {"thindielectric", bsdf_dielectric}, {"roughdielectric", bsdf_dielectric},
    {"conductor", bsdf_conductor},     {"roughconductor", bsdf_conductor},
    {"plastic", bsdf_plastic},         {"roughplastic", bsdf_plastic},
};

static int is_bsdf_wrapper(const char *type)
{
    return strcmp(type, "twosided") == 0 || strcmp(type, "mask") == 0 ||
           strcmp(type, "bumpmap") == 0 || strcmp(type, "normalmap") == 0;
}

/* Reads a <bsdf> into out without touching the scene (textures are loaded when it is added). */
static int parse_bsdf(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out)
{
    const char *type;
    if (depth > MITSUBA_MAX_NESTING)
        return fail(node, "bsdfs nested too deeply");
    if (require_attr(node, "type", &type))
        return -1;
    if (is_bsdf_wrapper(type))
        return bsdf_wrapper(ld, node, depth, out);
    memset(out, 0, sizeof *out);
    out->material.int_ior = out->material.ext_ior = 1.0f;
    out->material.texture = -1;
    snprintf(out->type, sizeof out->type, "%s", type);
    for (size_t i = 0; i < sizeof bsdf_readers / sizeof *bsdf_readers; i++)
        if (strcmp(type, bsdf_readers[i].type) == 0)
            return bsdf_readers[i].read(ld, node, out);
    return fail(node, "unsupported bsdf type '%s'", type);
}

/* Adds a parsed bsdf to the scene, loading its texture; returns the material index or -1. */
static int bsdf_add(loader *ld, const bsdf_parsed *parsed, const char *name)
{
    idmr_material material = parsed->material;
    if (parsed->texture) {
        const char *written;
        xmlNodePtr filename = prop_find(parsed->texture, "filename");
        if (prop_string(parsed->texture, "filename", NULL, &written))
            return -1;
        char *path = resolve_path(ld, filename, written);
        int texture = scene_add_texture(ld->s, path);
        free(path);
        if (texture < 0)
            return fail_prefix(parsed->texture);
        material.texture = texture;
        memcpy(material.reflectance, ld->s->textures[texture].mean, sizeof material.reflectance);
    }
    return (int)scene_add_material(ld->s, name, parsed->type, &material);
}

/* The material of a top-level bsdf, added on its first use. */
/* The material of a declared bsdf, added on its first reference from what its declaration
 * parsed. */
static int bsdf_by_id(loader *ld, mitsuba_id *entry)
{
    if (entry->material >= 0)
        return entry->material;
    if (!entry->bsdf)
        return fail(entry->node, "'%s' is not a bsdf", entry->id);
    entry->material = bsdf_add(ld, entry->bsdf, entry->id);
    return entry->material;
}

static int bsdf_default(loader *ld)
{
    if (ld->default_material < 0) {
        idmr_material material;
        memset(&material, 0, sizeof material);
        material.kind = IDMR_MATERIAL_DIFFUSE;
        material.reflectance[0] = material.reflectance[1] = material.reflectance[2] = 0.5f;
        material.int_ior = material.ext_ior = 1.0f;
        material.texture = -1;
        ld->default_material = (int)scene_add_material(ld->s, "default", "diffuse", &material);
    }
    return ld->default_material;
}

/* ---------------------------------------------------------------------------------------- */
/* The sensor                                                                               */

/* Parses "50mm" or "50" (millimetres of a 35 mm film). */
static int parse_focal_length(xmlNodePtr node, const char *text, double *mm)
{
    char number[64];
    size_t length = strlen(text);
    if (length >= 2 && strcmp(text + length - 2, "mm") == 0)
        length -= 2;
    snprintf(number, sizeof number, "%.*s", (int)length, text);
    if (parse_number(node, number, mm))
        return -1;
    if (*mm <= 0.0)
        return fail(node, "focal length must be positive");
    return 0;
}

/* fov and its axis: from fov/fov_axis, or from focal_length (35 mm film diagonal), as Mitsuba. */
static int sensor_fov(xmlNodePtr node, double *fov, char axis[16])
{
    const char *fov_axis, *focal;
    if (prop_find(node, "fov")) {
        xmlNodePtr prop = prop_find(node, "fov");
        if (prop_float(node, "fov", 0.0, fov) || prop_string(node, "fov_axis", "x", &fov_axis))
            return -1;
        if (*fov <= 0.0 || *fov >= 180.0)
            return fail(prop, "fov must be between 0 and 180 degrees");
        static const char *axes[] = {"x", "y", "diagonal", "smaller", "larger"};
        for (size_t i = 0; i < sizeof axes / sizeof *axes; i++)
            if (strcmp(fov_axis, axes[i]) == 0) {
                snprintf(axis, 16, "%s", fov_axis);
                return 0;
            }
        return fail(prop_find(node, "fov_axis"), "unknown fov_axis '%s'", fov_axis);
    }
    double mm = MITSUBA_FOCAL_LENGTH_MM;
    if (prop_string(node, "focal_length", NULL, &focal))
        return -1;
    if (focal && parse_focal_length(prop_find(node, "focal_length"), focal, &mm))
        return -1;
    *fov = 2.0 * atan(sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)) * 180.0 / M_PI;
    snprintf(axis, 16, "diagonal");
    return 0;
}

static int sensor_film(xmlNodePtr sensor, long *width, long *height)
{
    *width = MITSUBA_FILM_WIDTH;
    *height = MITSUBA_FILM_HEIGHT;
    FOR_EACH_ELEMENT(film, sensor)
    {
        if (!mitsuba_is_tag(film, "film"))
            continue;
        if (prop_int(film, "width", MITSUBA_FILM_WIDTH, width) ||
            prop_int(film, "height", MITSUBA_FILM_HEIGHT, height))
            return -1;
        if (*width < 1 || *height < 1 || *width > 65536 || *height > 65536)
            return fail(film, "film size %ldx%ld out of range", *width, *height);
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
        return fail(node, "the sensor's to_world transform is degenerate");
    for (int k = 0; k < 3; k++) {
        camera->origin[k] = (float)origin[k];
        camera->forward[k] = (float)forward[k];
        camera->up[k] = (float)up[k];
        camera->right[k] = (float)-left[k];
    }
    return 0;
}

static int load_sensor(loader *ld, xmlNodePtr node)
{
    const char *type;
    double fov, tan_x, tan_y;
    long width, height;
    xform to_world;
    char axis[16];
    if (require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "perspective") && strcmp(type, "thinlens"))
        return fail(node, "unsupported sensor type '%s'", type);
    if (ld->s->has_camera) {
        warn_at(node, "only the first sensor is used: ignored");
        return 0;
    }
    if (strcmp(type, "thinlens") == 0)
        warn_at(node, "thinlens sensor treated as a pinhole (no depth of field)");
    if (sensor_fov(node, &fov, axis) || prop_transform(node, "to_world", &to_world) ||
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

/* ---------------------------------------------------------------------------------------- */
/* Emitters                                                                                 */

static int emitter_point(loader *ld, xmlNodePtr node, idmr_light *light)
{
    static const double zero[3] = {0, 0, 0};
    double position[3];
    int found;
    xform to_world;
    light->kind = IDMR_LIGHT_POINT;
    if (prop_vector(node, "position", position, &found) ||
        prop_transform(node, "to_world", &to_world) ||
        prop_color(ld, node, "intensity", 1.0f, light->emission, NULL))
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
    if (prop_transform(node, "to_world", &to_world))
        return -1;
    xform_apply_point(&to_world, zero, position);
    xform_apply_vector(&to_world, z, axis);
    if (xform_normalize(axis) == 0.0)
        return fail(node, "to_world maps +z to zero");
    return 0;
}

static int emitter_spot(loader *ld, xmlNodePtr node, idmr_light *light)
{
    double position[3], axis[3], cutoff, beam;
    light->kind = IDMR_LIGHT_SPOT;
    if (emitter_frame(node, position, axis) ||
        prop_color(ld, node, "intensity", 1.0f, light->emission, NULL) ||
        prop_float(node, "cutoff_angle", MITSUBA_SPOT_CUTOFF, &cutoff) ||
        prop_float(node, "beam_width", cutoff * 0.75, &beam))
        return -1;
    if (cutoff <= 0.0 || cutoff > 180.0)
        return fail(node, "cutoff_angle must be in (0, 180] degrees");
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
    if (prop_vector(node, "direction", direction, &found) ||
        prop_color(ld, node, "irradiance", 1.0f, light->emission, NULL))
        return -1;
    if (!found && emitter_frame(node, position, direction))
        return -1;
    if (xform_normalize(direction) == 0.0)
        return fail(node, "the direction is zero");
    for (int k = 0; k < 3; k++)
        light->direction[k] = (float)direction[k];
    return 0;
}

static int emitter_area(loader *ld, xmlNodePtr node, idmr_light *light)
{
    light->kind = IDMR_LIGHT_AREA;
    return prop_color(ld, node, "radiance", 1.0f, light->emission, NULL);
}

/* constant (radiance) and envmap (filename, scale): an environment light of uniform radiance,
 * an envmap's being the map's mean. */
static int emitter_environment(loader *ld, xmlNodePtr node, const char *type, idmr_light *light)
{
    light->kind = IDMR_LIGHT_ENVIRONMENT;
    if (strcmp(type, "constant") == 0)
        return prop_color(ld, node, "radiance", 1.0f, light->emission, NULL);
    const char *file;
    double scale;
    if (prop_string(node, "filename", NULL, &file) || prop_float(node, "scale", 1.0, &scale))
        return -1;
    if (!file)
        return fail(node, "an envmap needs a filename");
    char *path = resolve_path(ld, node, file);
    int width, height;
    float *rgb;
    if (image_read_rgb(path, &width, &height, &rgb)) {
        free(path);
        return fail_prefix(node);
    }
    /* The mean radiance over the sphere: rows of an equirectangular map weighted by sin θ. */
    double sum[3] = {0, 0, 0}, weight = 0;
    for (int y = 0; y < height; y++) {
        double w = sin(M_PI * (y + 0.5) / height);
        for (int x = 0; x < width; x++)
            for (int c = 0; c < 3; c++)
                sum[c] += w * rgb[3 * ((size_t)y * width + x) + c];
        weight += w * width;
    }
    for (int c = 0; c < 3; c++)
        light->emission[c] = weight > 0 ? (float)(scale * sum[c] / weight) : 0.0f;
    free(rgb);
    free(path);
    if (!ld->environment_warned)
        warn_at(node,
                "envmap emitter: simulated as uniform light of its mean radiance (%.3g, %.3g, "
                "%.3g) from all directions; the map's directional structure is ignored",
                light->emission[0], light->emission[1], light->emission[2]);
    ld->environment_warned = 1;
    return 0;
}

static int load_emitter(loader *ld, xmlNodePtr node)
{
    const char *type;
    idmr_light light;
    int status;
    memset(&light, 0, sizeof light);
    if (require_attr(node, "type", &type))
        return -1;
    if (strcmp(type, "point") == 0)
        status = emitter_point(ld, node, &light);
    else if (strcmp(type, "spot") == 0)
        status = emitter_spot(ld, node, &light);
    else if (strcmp(type, "directional") == 0)
        status = emitter_directional(ld, node, &light);
    else if (strcmp(type, "area") == 0) {
        /* Declared for <ref> from shapes; checked here, added with each shape. */
        if (!mitsuba_attr(node, "id"))
            return fail(node, "an area emitter must be inside a shape (or have an id)");
        return emitter_area(ld, node, &light) || id_register(ld, node) ? -1 : 0;
    } else if (strcmp(type, "envmap") == 0 || strcmp(type, "constant") == 0)
        status = emitter_environment(ld, node, type, &light);
    else
        return fail(node, "unsupported emitter type '%s'", type);
    if (status)
        return -1;
    scene_add_light(ld->s, &light);
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* Shapes                                                                                   */

static int is_mesh_file_type(const char *type)
{
    return strcmp(type, "obj") == 0 || strcmp(type, "ply") == 0 || strcmp(type, "off") == 0 ||
           strcmp(type, "stl") == 0;
}

/* Reads a mesh file shape; *file gets the resolved path, *written the path as in the file. */
static int shape_read_file(loader *ld, xmlNodePtr node, mesh_data *mesh, char **file,
                           const char **written)
{
    if (prop_string(node, "filename", NULL, written))
        return -1;
    if (!*written)
        return fail(node, "missing <string name=\"filename\">");
    *file = resolve_path(ld, prop_find(node, "filename"), *written);
    if (access(*file, R_OK) != 0)
        return fail(node, "cannot read '%s' (%s): %s", *written, *file, strerror(errno));
    /* Mitsuba's front side comes from the file's normals unless face_normals is set. */
    int face_normals;
    if (prop_bool(node, "face_normals", 0, &face_normals))
        return -1;
    if (mesh_io_read_oriented(*file, mesh, !face_normals, NULL))
        return fail_prefix(node);
    return 0;
}

static int shape_sphere(xmlNodePtr node, mesh_data *mesh)
{
    double center[3] = {0, 0, 0}, radius;
    int found;
    if (prop_vector(node, "center", center, &found) || prop_float(node, "radius", 1.0, &radius))
        return -1;
    if (radius <= 0.0)
        return fail(node, "the radius must be positive");
    shapes_sphere(center, radius, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, mesh);
    return 0;
}

/* Tessellates a built-in shape; returns 1 if `type` is not one. */
static int shape_builtin(xmlNodePtr node, const char *type, mesh_data *mesh)
{
    if (strcmp(type, "rectangle") == 0)
        shapes_rectangle(mesh);
    else if (strcmp(type, "cube") == 0)
        shapes_cube(mesh);
    else if (strcmp(type, "disk") == 0)
        shapes_disk(SHAPES_DISK_SEGMENTS, mesh);
    else if (strcmp(type, "sphere") == 0)
        return shape_sphere(node, mesh);
    else
        return 1;
    return 0;
}

/* The shape's geometry in world space. */
static int shape_geometry(loader *ld, xmlNodePtr node, const char *type, mesh_data *mesh,
                          char **file, const char **written)
{
    xform to_world;
    int flip, builtin = !is_mesh_file_type(type);
    memset(mesh, 0, sizeof *mesh);
    if (strcmp(type, "serialized") == 0)
        return fail(node, "unsupported shape type 'serialized' (convert the mesh to PLY or OBJ)");
    if (prop_transform(node, "to_world", &to_world) || prop_bool(node, "flip_normals", 0, &flip))
        return -1;
    if (!builtin && shape_read_file(ld, node, mesh, file, written))
        return -1;
    if (builtin) {
        int status = shape_builtin(node, type, mesh);
        if (status > 0)
            return fail(node, "unsupported shape type '%s'", type);
        if (status < 0)
            return -1;
    }
    shapes_transform(mesh, &to_world);
    /* A built-in shape's normal is transformed as a normal, so a mirror flips its winding. */
    if (builtin && xform_determinant3(&to_world) < 0.0)
        flip = !flip;
    if (flip)
        shapes_flip_winding(mesh);
    return 0;
}

/* The shape's bsdf and area emitter nodes (inline or by reference; NULL if none). */
static int shape_parts(loader *ld, xmlNodePtr node, xmlNodePtr *bsdf, mitsuba_id **bsdf_entry,
                       xmlNodePtr *emitter)
{
    *bsdf = *emitter = NULL;
    *bsdf_entry = NULL;
    FOR_EACH_ELEMENT(child, node)
    {
        xmlNodePtr target = child;
        mitsuba_id *entry = NULL;
        if (mitsuba_is_tag(child, "ref")) {
            if (!(entry = ref_resolve(ld, child)))
                return -1;
            target = entry->node;
        }
        if (mitsuba_is_tag(target, "bsdf") && !*bsdf) {
            *bsdf = target;
            *bsdf_entry = entry;
        } else if (mitsuba_is_tag(target, "emitter") && !*emitter) {
            *emitter = target;
        } else if (mitsuba_is_tag(child, "ref") && !mitsuba_is_tag(target, "bsdf") && !mitsuba_is_tag(target, "emitter")) {
            return fail(child, "'%s' is neither a bsdf nor an emitter", entry->id);
        }
    }
    if (*emitter && strcmp(mitsuba_attr(*emitter, "type") ? mitsuba_attr(*emitter, "type") : "", "area") != 0)
        return fail(*emitter, "only area emitters can be attached to a shape");
    return 0;
}

/* The shape's name: its id, else the mesh file's stem, else its type. */
static void shape_name(xmlNodePtr node, const char *type, const char *written, char *out,
                       size_t size)
{
    const char *id = mitsuba_attr(node, "id");
    if (id && id[0]) {
        snprintf(out, size, "%s", id);
        return;
    }
    if (!written) {
        snprintf(out, size, "%s", type);
        return;
    }
    const char *base = strrchr(written, '/') ? strrchr(written, '/') + 1 : written;
    const char *dot = strrchr(base, '.');
    int length = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(out, size, "%.*s", length, base);
}

/* The material for a shape: its referenced bsdf, its inline one (already parsed), or the
 * default. */
static int shape_material(loader *ld, const bsdf_parsed *inline_bsdf, mitsuba_id *entry,
                          const char *mesh_name)
{
    if (entry)
        return bsdf_by_id(ld, entry);
    if (!inline_bsdf)
        return bsdf_default(ld);
    char name[512];
    snprintf(name, sizeof name, "%s/bsdf", mesh_name);
    return bsdf_add(ld, inline_bsdf, name);
}

static int load_shape(loader *ld, xmlNodePtr node)
{
    const char *type, *written = NULL;
    xmlNodePtr bsdf, emitter;
    mitsuba_id *bsdf_entry;
    idmr_light light;
    bsdf_parsed inline_bsdf;
    mesh_data mesh;
    char *file = NULL, name[256];
    memset(&light, 0, sizeof light);
    if (require_attr(node, "type", &type) || shape_parts(ld, node, &bsdf, &bsdf_entry, &emitter))
        return -1;
    /* Parse an inline bsdf (a referenced one was parsed at its declaration) and the emitter
     * before the (possibly slow) mesh read. */
    if ((bsdf && !bsdf_entry && parse_bsdf(ld, bsdf, 0, &inline_bsdf)) ||
        (emitter && emitter_area(ld, emitter, &light)))
        return -1;
    if (shape_geometry(ld, node, type, &mesh, &file, &written)) {
        mesh_data_free(&mesh);
        free(file);
        return -1;
    }
    shape_name(node, type, written, name, sizeof name);
    scene_mesh *added = scene_add_mesh(ld->s, name, type, file, (int)xmlGetLineNo(node),
                                       mesh.vertex_count, mesh.positions, mesh.triangle_count,
                                       mesh.indices, mesh.texcoords);
    free(file);
    int material = shape_material(ld, bsdf && !bsdf_entry ? &inline_bsdf : NULL, bsdf_entry,
                                  added->name);
    if (material < 0)
        return -1;
    added->material = (uint32_t)material;
    added->xml_file = xstrdup(node_file(node));
    added->light = emitter ? scene_add_light(ld->s, &light) : -1;
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* The top level                                                                            */

static int load_children(loader *ld, xmlNodePtr root, int include_depth);

static int load_include(loader *ld, xmlNodePtr node, int include_depth)
{
    const char *written;
    if (include_depth >= MITSUBA_MAX_INCLUDE_DEPTH)
        return fail(node, "includes nested too deeply");
    if (require_attr(node, "filename", &written))
        return -1;
    char *path = resolve_path(ld, node, written);
    xmlNodePtr root = open_document(ld, path);
    free(path);
    if (!root)
        return fail_prefix(node);
    return load_children(ld, root, include_depth + 1);
}

/* A top-level bsdf or texture: checked now, registered for references, added when used. */
static int load_declaration(loader *ld, xmlNodePtr node)
{
    bsdf_parsed parsed;
    if (mitsuba_is_tag(node, "bsdf") ? parse_bsdf(ld, node, 0, &parsed) : texture_check(node))
        return -1;
    if (id_register(ld, node))
        return -1;
    if (mitsuba_is_tag(node, "bsdf") && mitsuba_attr(node, "id")) {
        mitsuba_id *entry = &ld->ids[ld->id_count - 1];
        entry->bsdf = xmalloc(sizeof parsed);
        *entry->bsdf = parsed;
    }
    return 0;
}

static int load_children(loader *ld, xmlNodePtr root, int include_depth)
{
    FOR_EACH_ELEMENT(child, root)
    {
        int status = 0;
        if (mitsuba_is_tag(child, "default") || mitsuba_is_tag(child, "integrator"))
            continue;
        if (mitsuba_is_tag(child, "sensor"))
            status = load_sensor(ld, child);
        else if (mitsuba_is_tag(child, "bsdf") || mitsuba_is_tag(child, "texture"))
            status = load_declaration(ld, child);
        else if (mitsuba_is_tag(child, "shape"))
            status = load_shape(ld, child);
        else if (mitsuba_is_tag(child, "emitter"))
            status = load_emitter(ld, child);
        else if (mitsuba_is_tag(child, "include"))
            status = load_include(ld, child, include_depth);
        else
            status = fail(child, "unsupported element <%s>", (const char *)child->name);
        if (status)
            return -1;
    }
    return 0;
}

static void loader_free(loader *ld)
{
    for (size_t i = 0; i < ld->doc_count; i++)
        xmlFreeDoc(ld->docs[i]);
    free(ld->docs);
    mitsuba_params_free(&ld->params);
    for (size_t i = 0; i < ld->id_count; i++) {
        free(ld->ids[i].id);
        free(ld->ids[i].bsdf);
    }
    free(ld->ids);
}

scene *mitsuba_load(const char *path)
{
    loader ld;
    memset(&ld, 0, sizeof ld);
    ld.default_material = -1;
    xmlInitParser();
    ld.s = scene_create(path);
    xmlNodePtr root = open_document(&ld, path);
    int status = root ? 0 : -1;
    if (status == 0) {
        ld.major_version = parse_major_version(root);
        status = load_children(&ld, root, 0);
    }
    if (status == 0 && !ld.s->has_camera)
        warn("%s: no <sensor>: the scene has no camera", path);
    if (status == 0)
        status = scene_finalize(ld.s);
    loader_free(&ld);
    if (status) {
        scene_free(ld.s);
        return NULL;
    }
    return ld.s;
}
