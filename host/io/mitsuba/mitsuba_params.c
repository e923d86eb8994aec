/* mitsuba_params.c — <default> parameters and $name substitution (see mitsuba_params.h). */
#include "io/mitsuba/mitsuba_params.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/mitsuba/mitsuba_xml.h"

const char *mitsuba_params_lookup(const mitsuba_params *p, const char *name, size_t length)
{
    for (size_t i = 0; i < p->count; i++)
        if (strlen(p->names[i]) == length && strncmp(p->names[i], name, length) == 0)
            return p->values[i];
    return NULL;
}

void mitsuba_params_add(mitsuba_params *p, const char *name, const char *value)
{
    if (mitsuba_params_lookup(p, name, strlen(name)))
        return;
    p->names = xrealloc(p->names, (p->count + 1) * sizeof *p->names);
    p->values = xrealloc(p->values, (p->count + 1) * sizeof *p->values);
    p->names[p->count] = xstrdup(name);
    p->values[p->count] = xstrdup(value);
    p->count++;
}

xmlNodePtr mitsuba_params_collect(mitsuba_params *p, xmlNodePtr root)
{
    xmlNodePtr incomplete = NULL;
    MITSUBA_FOR_EACH_ELEMENT(child, root)
    {
        if (!mitsuba_is_tag(child, "default"))
            continue;
        const char *name = mitsuba_attr(child, "name"), *value = mitsuba_attr(child, "value");
        if (name && value)
            mitsuba_params_add(p, name, value);
        else if (!incomplete)
            incomplete = child;
    }
    return incomplete;
}

void mitsuba_params_free(mitsuba_params *p)
{
    for (size_t i = 0; i < p->count; i++) {
        free(p->names[i]);
        free(p->values[i]);
    }
    free(p->names);
    free(p->values);
    memset(p, 0, sizeof *p);
}

static int is_param_char(char c)
{
    return isalnum((unsigned char)c) || c == '_';
}

char *mitsuba_substitute(const mitsuba_params *p, const char *text, char *missing, size_t size)
{
    size_t capacity = strlen(text) + 1, used = 0;
    char *out = xmalloc(capacity);
    for (const char *c = text; *c;) {
        const char *piece = c;
        size_t length = 1;
        if (*c == '$') {
            size_t n = 1;
            while (is_param_char(c[n]))
                n++;
            piece = mitsuba_params_lookup(p, c + 1, n - 1);
            if (!piece) {
                snprintf(missing, size, "%.*s", (int)n, c);
                free(out);
                return NULL;
            }
            length = strlen(piece);
            c += n;
        } else {
            c++;
        }
        if (used + length + 1 > capacity) {
            capacity = 2 * (used + length + 1);
            out = xrealloc(out, capacity);
        }
        memcpy(out + used, piece, length);
        used += length;
    }
    out[used] = '\0';
    return out;
}
