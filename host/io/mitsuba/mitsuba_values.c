/* mitsuba_values.c — numbers and typed properties: the text of value="..." attributes (numbers
 * separated by commas and/or white space) and the property elements of a plugin, found by their
 * name (<float name="fov" value="45"/>, <integer>, <boolean>, <string>, <point>, <vector>). A
 * reader checks the element type before it reads the value, so a message names the element
 * that is wrong. */
#include "io/mitsuba/mitsuba_loader.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---------------------------------------------------------------------------------------- */
/* Numbers                                                                                  */

/* Past the white space that follows `end`, where a number's text stopped. */
static const char *skip_space(const char *end)
{
    while (isspace((unsigned char)*end))
        end++;
    return end;
}

int mitsuba_parse_number(xmlNodePtr node, const char *text, double *out)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    const char *rest = skip_space(end);
    if (rest == text || *rest || !isfinite(value) || errno == ERANGE)
        return mitsuba_fail(node, "'%s' is not a number", text);
    *out = value;
    return 0;
}

static int parse_integer(xmlNodePtr node, const char *text, long *out)
{
    char *end;
    errno = 0;
    long value = strtol(text, &end, 10);
    const char *rest = skip_space(end);
    if (rest == text || *rest || errno == ERANGE)
        return mitsuba_fail(node, "'%s' is not an integer", text);
    *out = value;
    return 0;
}

static int parse_boolean(xmlNodePtr node, const char *text, int *out)
{
    if (strcasecmp(text, "true") == 0)
        *out = 1;
    else if (strcasecmp(text, "false") == 0)
        *out = 0;
    else
        return mitsuba_fail(node, "'%s' is not a boolean (true or false)", text);
    return 0;
}

static int is_separator(char c)
{
    return c == ',' || isspace((unsigned char)c);
}

int mitsuba_next_token(const char **cursor, char *token, size_t size)
{
    const char *p = *cursor;
    while (is_separator(*p))
        p++;
    size_t length = 0;
    while (p[length] && !is_separator(p[length]))
        length++;
    snprintf(token, size, "%.*s", (int)length, p);
    *cursor = p + length;
    return length > 0;
}

int mitsuba_parse_numbers(xmlNodePtr node, const char *text, double *out, int max, int *count)
{
    char token[128];
    *count = 0;
    for (const char *p = text; mitsuba_next_token(&p, token, sizeof token);) {
        if (*count == max)
            return mitsuba_fail(node, "'%s': more than %d numbers", text, max);
        if (mitsuba_parse_number(node, token, &out[(*count)++]))
            return -1;
    }
    return 0;
}

int mitsuba_parse_exact(xmlNodePtr node, const char *text, double *out, int expected)
{
    int count;
    if (mitsuba_parse_numbers(node, text, out, expected, &count))
        return -1;
    if (count != expected)
        return mitsuba_fail(node, "'%s': expected %d numbers, got %d", text, expected, count);
    return 0;
}

int mitsuba_parse_one_or_three(xmlNodePtr node, const char *text, double out[3])
{
    int count;
    if (mitsuba_parse_numbers(node, text, out, 3, &count))
        return -1;
    if (count == 1)
        out[1] = out[2] = out[0];
    else if (count != 3)
        return mitsuba_fail(node, "'%s': expected 1 or 3 numbers", text);
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
    return mitsuba_parse_number(node, text, out);
}

int mitsuba_attr_vector(xmlNodePtr node, double fallback, double out[3])
{
    const char *value = mitsuba_attr(node, "value");
    if (value)
        return mitsuba_parse_exact(node, value, out, 3);
    return attr_number(node, "x", fallback, &out[0]) ||
                   attr_number(node, "y", fallback, &out[1]) ||
                   attr_number(node, "z", fallback, &out[2])
               ? -1
               : 0;
}

/* ---------------------------------------------------------------------------------------- */
/* Properties: <float name="..." value="..."/> and friends, children of a plugin element     */

xmlNodePtr mitsuba_prop_find(xmlNodePtr plugin, const char *name)
{
    MITSUBA_FOR_EACH_ELEMENT(child, plugin)
    {
        const char *child_name = mitsuba_attr(child, "name");
        if (child_name && strcmp(child_name, name) == 0) {
            mitsuba_mark_read(child);
            return child;
        }
    }
    return NULL;
}

int mitsuba_prop_element(xmlNodePtr plugin, const char *name, const char *tag, const char *also,
                         xmlNodePtr *prop)
{
    *prop = mitsuba_prop_find(plugin, name);
    if (!*prop || mitsuba_is_tag(*prop, tag) || (also && mitsuba_is_tag(*prop, also)))
        return 0;
    return mitsuba_fail(*prop, "expected <%s>", tag);
}

/* The typed properties that carry a value attribute, and the elements they are written as. */
typedef enum value_type { VALUE_FLOAT, VALUE_INTEGER, VALUE_BOOLEAN, VALUE_STRING } value_type;

static const struct {
    const char *tag, *also;
} value_elements[] = {
    [VALUE_FLOAT] = {"float", "integer"},
    [VALUE_INTEGER] = {"integer", NULL},
    [VALUE_BOOLEAN] = {"boolean", NULL},
    [VALUE_STRING] = {"string", NULL},
};

/* Reads the value of the property `name` as `type` into out (a double, long, int or const
 * char *, in that order); out is left alone when the property is absent. */
static int prop_read(xmlNodePtr plugin, const char *name, value_type type, void *out)
{
    xmlNodePtr prop;
    const char *value;
    if (mitsuba_prop_element(plugin, name, value_elements[type].tag, value_elements[type].also,
                             &prop))
        return -1;
    if (!prop)
        return 0;
    if (mitsuba_require_attr(prop, "value", &value))
        return -1;
    switch (type) {
    case VALUE_FLOAT:
        return mitsuba_parse_number(prop, value, out);
    case VALUE_INTEGER:
        return parse_integer(prop, value, out);
    case VALUE_BOOLEAN:
        return parse_boolean(prop, value, out);
    case VALUE_STRING:
        *(const char **)out = value;
        return 0;
    }
    return 0;
}

int mitsuba_prop_float(xmlNodePtr plugin, const char *name, double fallback, double *out)
{
    *out = fallback;
    return prop_read(plugin, name, VALUE_FLOAT, out);
}

int mitsuba_prop_int(xmlNodePtr plugin, const char *name, long fallback, long *out)
{
    *out = fallback;
    return prop_read(plugin, name, VALUE_INTEGER, out);
}

int mitsuba_prop_bool(xmlNodePtr plugin, const char *name, int fallback, int *out)
{
    *out = fallback;
    return prop_read(plugin, name, VALUE_BOOLEAN, out);
}

int mitsuba_prop_string(xmlNodePtr plugin, const char *name, const char *fallback,
                        const char **out)
{
    *out = fallback;
    return prop_read(plugin, name, VALUE_STRING, (void *)out);
}

int mitsuba_prop_vector(xmlNodePtr plugin, const char *name, double out[3], int *found)
{
    xmlNodePtr prop;
    *found = 0;
    if (mitsuba_prop_element(plugin, name, "point", "vector", &prop))
        return -1;
    *found = prop != NULL;
    return prop ? mitsuba_attr_vector(prop, 0.0, out) : 0;
}
