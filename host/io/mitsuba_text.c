/* mitsuba_text.c — parameters, substitution and path resolution shared by the Mitsuba loader
 * and writer (see mitsuba_text.h). */
#include "io/mitsuba_text.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"

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

char *mitsuba_path_join(const char *dir, const char *file)
{
    if (file[0] == '/' || !dir || !dir[0] || strcmp(dir, ".") == 0)
        return xstrdup(file);
    size_t size = strlen(dir) + strlen(file) + 2;
    char *out = xmalloc(size);
    snprintf(out, size, "%s/%s", dir, file);
    return out;
}

char *mitsuba_path_directory(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return xstrdup("");
    if (slash == path)
        return xstrdup("/");
    char *dir = xstrdup(path);
    dir[slash - path] = '\0';
    return dir;
}

char *mitsuba_resolve(const char *naming_file, const char *scene_dir, const char *written,
                      int *from_scene_dir)
{
    if (from_scene_dir)
        *from_scene_dir = 0;
    char *dir = mitsuba_path_directory(naming_file);
    char *first = mitsuba_path_join(dir, written);
    free(dir);
    if (written[0] == '/' || access(first, F_OK) == 0)
        return first;
    char *second = mitsuba_path_join(scene_dir, written);
    if (access(second, F_OK) == 0) {
        free(first);
        if (from_scene_dir)
            *from_scene_dir = 1;
        return second;
    }
    free(second);
    return first;
}

int mitsuba_is_tag(xmlNodePtr node, const char *tag)
{
    return node && node->type == XML_ELEMENT_NODE && strcmp((const char *)node->name, tag) == 0;
}

const char *mitsuba_attr(xmlNodePtr node, const char *name)
{
    xmlAttrPtr a = xmlHasProp(node, (const xmlChar *)name);
    if (!a)
        return NULL;
    return a->children && a->children->content ? (const char *)a->children->content : "";
}
