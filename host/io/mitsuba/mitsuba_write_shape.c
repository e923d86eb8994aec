/* mitsuba_write_shape.c — a replaced <shape> element becomes a reference to its PLY (see
 * mitsuba_write_shape.h). Elements are removed with the blank text before them (their
 * indentation) and added with the indentation of their siblings, so the output reads like the
 * input. */
#include "io/mitsuba/mitsuba_write_shape.h"

#include <stdio.h>
#include <string.h>

#include "io/mitsuba/mitsuba_xml.h"

void mitsuba_unlink_with_indent(xmlNodePtr node)
{
    xmlNodePtr before = node->prev;
    if (before && before->type == XML_TEXT_NODE && xmlIsBlankNode(before)) {
        xmlUnlinkNode(before);
        xmlFreeNode(before);
    }
    xmlUnlinkNode(node);
}

/* Unlinks and frees `node` with the blank text before it (its indentation). */
static void remove_with_indent(xmlNodePtr node)
{
    mitsuba_unlink_with_indent(node);
    xmlFreeNode(node);
}

/* The whitespace after the last newline of a blank text node before `node` ("" if none). */
static void indentation_of(xmlNodePtr node, char *out, size_t size)
{
    out[0] = '\0';
    xmlNodePtr before = node ? node->prev : NULL;
    if (!before || before->type != XML_TEXT_NODE || !xmlIsBlankNode(before) || !before->content)
        return;
    const char *text = (const char *)before->content;
    const char *line = strrchr(text, '\n');
    snprintf(out, size, "%s", line ? line + 1 : text);
}

/* Adds element before `first`, the shape's first element child, indented as `first` is. */
static void add_before_first(xmlNodePtr shape, xmlNodePtr first, xmlNodePtr element)
{
    char indent[256], text[300];
    indentation_of(first, indent, sizeof indent);
    snprintf(text, sizeof text, "\n%s", indent);
    xmlAddPrevSibling(first, element);
    if (first->prev == element && element->prev && element->prev->type == XML_TEXT_NODE) {
        /* [blank][element][first]: give `first` its own indentation back. */
        xmlAddPrevSibling(first, xmlNewDocText(shape->doc, (const xmlChar *)text));
    } else if (indent[0]) {
        xmlAddPrevSibling(element, xmlNewDocText(shape->doc, (const xmlChar *)text));
    }
}

/* Each blank text in `node`'s subtree indented by `from` after a newline is indented by `to`
 * instead (what follows `from` is kept: deeper levels stay deeper). */
static void shift_indentation(xmlNodePtr node, const char *from, const char *to)
{
    for (xmlNodePtr child = node->children; child; child = child->next) {
        if (child->type == XML_ELEMENT_NODE)
            shift_indentation(child, from, to);
        if (child->type != XML_TEXT_NODE || !xmlIsBlankNode(child) || !child->content)
            continue;
        const char *text = (const char *)child->content;
        const char *line = strrchr(text, '\n');
        if (!line || strncmp(line + 1, from, strlen(from)) != 0)
            continue;
        char shifted[600];
        snprintf(shifted, sizeof shifted, "%.*s\n%s%s", (int)(line - text), text, to,
                 line + 1 + strlen(from));
        xmlNodeSetContent(child, (const xmlChar *)shifted);
    }
}

void mitsuba_insert_before(xmlNodePtr sibling, xmlNodePtr element, xmlNodePtr indented_as)
{
    char from[256], to[256];
    indentation_of(indented_as, from, sizeof from);
    indentation_of(sibling, to, sizeof to);
    shift_indentation(element, from, to);
    add_before_first(sibling->parent, sibling, element);
}

/* Adds element as the only element child of `shape`, one level deeper than the shape. */
static void add_only_child(xmlNodePtr shape, xmlNodePtr element)
{
    char indent[256], text[300];
    indentation_of(shape, indent, sizeof indent);
    const char *unit = strchr(indent, '\t') ? "\t" : "    ";
    snprintf(text, sizeof text, "\n%s%s", indent, unit);
    xmlNodePtr tail = shape->last;
    if (tail && tail->type == XML_TEXT_NODE && xmlIsBlankNode(tail)) {
        /* [... blank before </shape>]: the element goes before it, indented. */
        xmlAddPrevSibling(tail, element);
        xmlAddPrevSibling(element, xmlNewDocText(shape->doc, (const xmlChar *)text));
        return;
    }
    xmlAddChild(shape, xmlNewDocText(shape->doc, (const xmlChar *)text));
    xmlAddChild(shape, element);
    snprintf(text, sizeof text, "\n%s", indent);
    xmlAddChild(shape, xmlNewDocText(shape->doc, (const xmlChar *)text));
}

/* Adds <string name="filename" value="ply"/> as the shape's first element child, indented as
 * its siblings are (or one level deeper than the shape when it has none). */
static void add_filename(xmlNodePtr shape, const char *ply)
{
    xmlNodePtr first = xmlFirstElementChild(shape);
    xmlNodePtr element = xmlNewDocNode(shape->doc, NULL, (const xmlChar *)"string", NULL);
    xmlNewProp(element, (const xmlChar *)"name", (const xmlChar *)"filename");
    xmlNewProp(element, (const xmlChar *)"value", (const xmlChar *)ply);
    if (first)
        add_before_first(shape, first, element);
    else
        add_only_child(shape, element);
}

/* Whether child is one of the `count` properties `names`. */
static int is_any_property(xmlNodePtr child, const char *const *names, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (mitsuba_is_property(child, names[i]))
            return 1;
    return 0;
}

/* Whether a property of a shape of type `type` no longer applies once it is a world-space PLY. */
static int property_dropped(const char *type, xmlNodePtr child)
{
    static const char *const always[] = {"to_world", "flip_normals"};
    static const char *const sphere[] = {"center", "radius"};
    static const char *const obj[] = {"flip_tex_coords", "shape_index", "collapse"};
    return is_any_property(child, always, sizeof always / sizeof *always) ||
           (strcmp(type, "sphere") == 0 &&
            is_any_property(child, sphere, sizeof sphere / sizeof *sphere)) ||
           (strcmp(type, "obj") == 0 && is_any_property(child, obj, sizeof obj / sizeof *obj));
}

/* Whether the document is in the dialect before Mitsuba 2 (camelCase names: version 0.x, 1.x). */
static int is_old_dialect(xmlDocPtr doc)
{
    xmlNodePtr root = xmlDocGetRootElement(doc);
    xmlChar *version = root ? xmlGetProp(root, (const xmlChar *)"version") : NULL;
    int old_dialect = version && version[0] >= '0' && version[0] <= '1' && version[1] == '.';
    xmlFree(version);
    return old_dialect;
}

/* A built-in shape with edges (all but the sphere), or one whose normals were flat
 * (flat_normals), is shaded flat; as a PLY without normals Mitsuba would smooth it (a cube's
 * corners), so it says face_normals, in the document's dialect (faceNormals before version 2),
 * unless it already does. */
static void keep_flat_shading(xmlNodePtr shape, const char *type, int flat_normals)
{
    static const char *const flat[] = {"rectangle", "cube", "disk"};
    int is_flat = flat_normals;
    for (size_t i = 0; i < sizeof flat / sizeof *flat; i++)
        is_flat |= strcmp(type, flat[i]) == 0;
    if (!is_flat)
        return;
    for (xmlNodePtr child = xmlFirstElementChild(shape); child; child = xmlNextElementSibling(child))
        if (mitsuba_is_property(child, "face_normals"))
            return;
    int old_dialect = is_old_dialect(shape->doc);
    xmlNodePtr element = xmlNewDocNode(shape->doc, NULL, (const xmlChar *)"boolean", NULL);
    xmlNewProp(element, (const xmlChar *)"name",
               (const xmlChar *)(old_dialect ? "faceNormals" : "face_normals"));
    xmlNewProp(element, (const xmlChar *)"value", (const xmlChar *)"true");
    add_only_child(shape, element);
}

void mitsuba_shape_to_ply(xmlNodePtr shape, const char *ply, int face_normals)
{
    char type[64];
    const char *written_type = mitsuba_attr(shape, "type");
    snprintf(type, sizeof type, "%s", written_type ? written_type : "");
    xmlNodePtr filename = NULL;
    for (xmlNodePtr child = xmlFirstElementChild(shape), next; child; child = next) {
        next = xmlNextElementSibling(child);
        if (mitsuba_is_tag(child, "bsdf") || mitsuba_is_tag(child, "emitter") ||
            mitsuba_is_tag(child, "ref"))
            continue;
        if (mitsuba_is_property(child, "filename") && !filename)
            filename = child;
        else if (property_dropped(type, child))
            remove_with_indent(child);
    }
    keep_flat_shading(shape, type, face_normals);
    xmlSetProp(shape, (const xmlChar *)"type", (const xmlChar *)"ply");
    if (filename)
        xmlSetProp(filename, (const xmlChar *)"value", (const xmlChar *)ply);
    else
        add_filename(shape, ply);
}
