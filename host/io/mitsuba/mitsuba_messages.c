/* mitsuba_messages.c — the loader's errors and warnings, each naming the file, the line and the
 * element it is about: "file:line: <tag type=".." name=".." id="..">: what is wrong". A
 * property name is shown as the file spells it (intIOR, not int_ior). */
#include "io/mitsuba/mitsuba_loader.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "core/error.h"

#define MITSUBA_MESSAGE_MAX 1024
#define MITSUBA_ELEMENT_MAX 256

const char *mitsuba_node_file(xmlNodePtr node)
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
        const char *value = mitsuba_attr_value(a);
        if (strcmp(key, "name") == 0 && mitsuba_attr(node, MITSUBA_WRITTEN_NAME))
            value = mitsuba_attr(node, MITSUBA_WRITTEN_NAME);
        used += (size_t)snprintf(out + used, size - used, " %s=\"%s\"", key, value);
    }
    if (used < size)
        snprintf(out + used, size - used, ">");
}

/* Formats "file:line: <element>: what" and sets it as the error (is_error; returns -1) or
 * prints it as a warning (returns 0). */
static int node_report(int is_error, xmlNodePtr node, const char *fmt, va_list args)
{
    char element[MITSUBA_ELEMENT_MAX], what[MITSUBA_MESSAGE_MAX];
    vsnprintf(what, sizeof what, fmt, args);
    node_describe(node, element, sizeof element);
    const char *file = mitsuba_node_file(node);
    long line = xmlGetLineNo(node);
    if (is_error)
        return error_set(IDMR_EXIT_INPUT, "%s:%ld: %s: %s", file, line, element, what);
    warn("%s:%ld: %s: %s", file, line, element, what);
    return 0;
}

int mitsuba_fail(xmlNodePtr node, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    int status = node_report(1, node, fmt, args);
    va_end(args);
    return status;
}

int mitsuba_fail_prefix(xmlNodePtr node)
{
    char element[MITSUBA_ELEMENT_MAX];
    node_describe(node, element, sizeof element);
    return error_prefix("%s:%ld: %s", mitsuba_node_file(node), xmlGetLineNo(node), element);
}

void mitsuba_warn_at(xmlNodePtr node, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    node_report(0, node, fmt, args);
    va_end(args);
}

int mitsuba_require_attr(xmlNodePtr node, const char *name, const char **out)
{
    *out = mitsuba_attr(node, name);
    if (!*out)
        return mitsuba_fail(node, "missing attribute '%s'", name);
    return 0;
}
