/* mitsuba_document.c — the loader's entry point (mitsuba_load) and its documents: each file is
 * read (mitsuba_xml.h), its <default> parameters collected, then prepared in place — every
 * `$name` in an attribute substituted and every property name snake_cased, its spelling kept
 * for messages — so that the section readers know only the 3.x dialect. The top-level elements
 * are then read in document order; an <include>'s fragment is read in its place. */
#include "io/mitsuba/mitsuba.h"

#include <stdlib.h>
#include <string.h>

#include <libxml/parser.h>

#include "core/error.h"
#include "io/mitsuba/mitsuba_loader.h"
#include "io/mitsuba_paths.h"

/* ---------------------------------------------------------------------------------------- */
/* Documents: reading, <default> parameters, name normalisation                             */

/* Records the <default> elements directly under `root`; an earlier definition wins. */
static int collect_params(loader *ld, xmlNodePtr root)
{
    const char *name, *value;
    xmlNodePtr incomplete = mitsuba_params_collect(&ld->params, root);
    if (incomplete && (mitsuba_require_attr(incomplete, "name", &name) ||
                       mitsuba_require_attr(incomplete, "value", &value)))
        return -1;
    return 0;
}

/* Returns a malloc'd copy of `text` with each $name replaced by its <default> value. */
static char *substitute(const loader *ld, xmlNodePtr node, const char *text)
{
    char missing[256];
    char *out = mitsuba_substitute(&ld->params, text, missing, sizeof missing);
    if (!out)
        mitsuba_fail(node, "undefined parameter '%s' (no <default name=\"%s\">)", missing,
                     missing + 1);
    return out;
}

/* Substitutes parameters in every attribute and snake_cases every property name, in place. */
static int prepare_tree(loader *ld, xmlNodePtr node)
{
    if (mitsuba_is_tag(node, "default"))
        return 0;
    for (xmlAttrPtr a = node->properties; a; a = a->next) {
        const char *value = mitsuba_attr_value(a);
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
    MITSUBA_FOR_EACH_ELEMENT(child, node)
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
        mitsuba_fail(root, "the root element must be <scene>");
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
/* The top level                                                                            */

static int load_children(loader *ld, xmlNodePtr root, int include_depth);

static int load_include(loader *ld, xmlNodePtr node, int include_depth)
{
    const char *written;
    if (include_depth >= MITSUBA_MAX_INCLUDE_DEPTH)
        return mitsuba_fail(node, "includes nested too deeply");
    if (++ld->include_count > MITSUBA_MAX_INCLUDES)
        return mitsuba_fail(node, "more than %d includes read for one scene (fragments that "
                                  "include others several times, level after level?)",
                            MITSUBA_MAX_INCLUDES);
    if (mitsuba_require_attr(node, "filename", &written))
        return -1;
    char *path = mitsuba_resolve_path(ld, node, written);
    xmlNodePtr root = open_document(ld, path);
    free(path);
    if (!root)
        return mitsuba_fail_prefix(node);
    return load_children(ld, root, include_depth + 1);
}

/* A top-level bsdf or texture: checked now, registered for references, added when used. */
static int load_declaration(loader *ld, xmlNodePtr node)
{
    bsdf_parsed parsed;
    int is_bsdf = mitsuba_is_tag(node, "bsdf");
    if (is_bsdf ? mitsuba_parse_bsdf(ld, node, 0, &parsed) : mitsuba_texture_check(node))
        return -1;
    if (mitsuba_id_register(ld, node))
        return -1;
    if (is_bsdf && mitsuba_attr(node, "id")) {
        mitsuba_id *entry = &ld->ids[ld->id_count - 1];
        entry->bsdf = xmalloc(sizeof parsed);
        *entry->bsdf = parsed;
    }
    return 0;
}

static int load_element(loader *ld, xmlNodePtr child, int include_depth)
{
    if (mitsuba_is_tag(child, "default") || mitsuba_is_tag(child, "integrator"))
        return 0;
    if (!mitsuba_is_tag(child, "include") && !mitsuba_is_tag(child, "sensor"))
        mitsuba_mark_read(child); /* a sensor is marked if it is the one used */
    if (mitsuba_is_tag(child, "sensor"))
        return mitsuba_load_sensor(ld, child);
    if (mitsuba_is_tag(child, "bsdf") || mitsuba_is_tag(child, "texture"))
        return load_declaration(ld, child);
    if (mitsuba_is_tag(child, "shape"))
        return mitsuba_load_shape(ld, child);
    if (mitsuba_is_tag(child, "emitter"))
        return mitsuba_load_emitter(ld, child);
    if (mitsuba_is_tag(child, "include"))
        return load_include(ld, child, include_depth);
    return mitsuba_fail(child, "unsupported element <%s>", (const char *)child->name);
}

static int load_children(loader *ld, xmlNodePtr root, int include_depth)
{
    MITSUBA_FOR_EACH_ELEMENT(child, root)
    {
        if (load_element(ld, child, include_depth))
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
    mitsuba_ids_free(ld);
    free(ld->group_shapes);
}

scene *mitsuba_load(const char *path) { return mitsuba_load_streaming(path, 0); }

scene *mitsuba_load_streaming(const char *path, uint32_t release_from)
{
    loader ld;
    memset(&ld, 0, sizeof ld);
    ld.default_material = -1;
    ld.release_from = release_from;
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
        mitsuba_warn_unread(ld.docs, ld.doc_count);
    if (status == 0)
        status = scene_finalize(ld.s);
    loader_free(&ld);
    if (status) {
        scene_free(ld.s);
        return NULL;
    }
    return ld.s;
}
