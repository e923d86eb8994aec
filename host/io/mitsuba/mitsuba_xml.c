/* mitsuba_xml.c — reading a Mitsuba document and accessing its elements, attributes and
 * property names, alike for the loader and the writer (see mitsuba_xml.h). */
#include "io/mitsuba/mitsuba_xml.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include <libxml/parser.h>

#include "core/error.h"

#define MITSUBA_PARSE_MESSAGE_MAX 1024

static void trim_trailing_space(char *text)
{
    size_t length = strlen(text);
    while (length > 0 && isspace((unsigned char)text[length - 1]))
        text[--length] = '\0';
}

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
        char message[MITSUBA_PARSE_MESSAGE_MAX];
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

int mitsuba_is_tag(xmlNodePtr node, const char *tag)
{
    return node && node->type == XML_ELEMENT_NODE && strcmp((const char *)node->name, tag) == 0;
}

int mitsuba_is_property(xmlNodePtr node, const char *snake)
{
    const char *name = mitsuba_attr(node, "name");
    char normal[256];
    if (!name)
        return 0;
    mitsuba_snake_case(name, normal, sizeof normal);
    return strcmp(normal, snake) == 0;
}

const char *mitsuba_attr_value(xmlAttrPtr attribute)
{
    return attribute->children && attribute->children->content
               ? (const char *)attribute->children->content
               : "";
}

const char *mitsuba_attr(xmlNodePtr node, const char *name)
{
    xmlAttrPtr attribute = xmlHasProp(node, (const xmlChar *)name);
    return attribute ? mitsuba_attr_value(attribute) : NULL;
}

xmlNodePtr mitsuba_first_element(xmlNodePtr node)
{
    while (node && node->type != XML_ELEMENT_NODE)
        node = node->next;
    return node;
}
