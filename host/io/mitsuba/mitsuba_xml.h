/* mitsuba_xml.h — the XML layer under the Mitsuba loader (mitsuba_*.c) and the reduced-scene
 * writer (mitsuba_write*.c), so that both see a file alike: the document read with the same
 * parser options (so that line numbers agree), element and attribute access, property names in
 * either dialect (camelCase → snake_case), and how deep <include>s may nest. The <default>
 * parameters are in mitsuba_params.h, path resolution in mitsuba_paths.h. */
#ifndef IDMR_MITSUBA_XML_H
#define IDMR_MITSUBA_XML_H

#include <stddef.h>

#include <libxml/tree.h>

/* <include> elements nest at most this deep (the loader and the writer follow the same), and a
 * scene reads at most this many (each is read where it stands: a few includes per level over a
 * dozen levels would otherwise be read millions of times). */
#define MITSUBA_MAX_INCLUDE_DEPTH 16
#define MITSUBA_MAX_INCLUDES 4096

/* The raw document (no substitution or renaming), read with the options the loader uses, so
 * that line numbers agree with scene_mesh.xml_line: network off, blanks kept, big line numbers.
 * NULL with the error set ("file:line: malformed XML: ..."). Free with xmlFreeDoc(). */
xmlDocPtr mitsuba_read_xml(const char *path);

/* Writes the snake_case form of a camelCase property name (toWorld → to_world, intIOR →
 * int_ior; snake_case stays as it is) into out (truncated to size). */
void mitsuba_snake_case(const char *name, char *out, size_t size);

/* Whether node is an element named `tag`. */
int mitsuba_is_tag(xmlNodePtr node, const char *tag);

/* Whether node's name attribute is the property `snake` in either dialect (toWorld matches
 * to_world). */
int mitsuba_is_property(xmlNodePtr node, const char *snake);

/* An attribute's value as stored in the tree (no copy), "" for an empty one. */
const char *mitsuba_attr_value(xmlAttrPtr attribute);

/* The value of node's attribute `name` (as mitsuba_attr_value), NULL if absent. */
const char *mitsuba_attr(xmlNodePtr node, const char *name);

/* The first element among node and its following siblings, or NULL. */
xmlNodePtr mitsuba_first_element(xmlNodePtr node);

/* Loops `child` over the element children of `parent`, in document order. */
#define MITSUBA_FOR_EACH_ELEMENT(child, parent)                                                 \
    for (xmlNodePtr child = mitsuba_first_element((parent)->children); child;                  \
         child = mitsuba_first_element(child->next))

#endif
