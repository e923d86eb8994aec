/* mitsuba_paths.c — joining, locating and resolving the paths of a Mitsuba scene (see
 * mitsuba_paths.h). */
#include "io/mitsuba_paths.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"

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

char *mitsuba_path_unique(const char *dir, const char *path,
                          int (*taken)(const char *name, const void *context),
                          const void *context)
{
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    const char *dot = strrchr(base, '.');
    int stem = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    const char *extension = dot && dot != base ? dot : "";
    char name[PATH_MAX];
    snprintf(name, sizeof name, "%s/%s", dir, base);
    for (int n = 2; taken(name, context); n++)
        snprintf(name, sizeof name, "%s/%.*s-%d%s", dir, stem, base, n, extension);
    return xstrdup(name);
}

char *mitsuba_path_real(const char *path)
{
    char buffer[PATH_MAX];
    return realpath(path, buffer) ? xstrdup(buffer) : NULL;
}

char *mitsuba_path_absolute(const char *path)
{
    char cwd[PATH_MAX];
    if (path[0] == '/' || !getcwd(cwd, sizeof cwd))
        return xstrdup(path);
    char *real_cwd = mitsuba_path_real(cwd);
    const char *relative = path[0] == '.' && path[1] == '/' ? path + 2 : path;
    char *out = mitsuba_path_join(real_cwd ? real_cwd : cwd, relative);
    free(real_cwd);
    return out;
}

/* The next component of a path at *p (skipping slashes): its length, 0 at the end. */
static size_t next_component(const char **p)
{
    while (**p == '/')
        (*p)++;
    size_t length = strcspn(*p, "/");
    return length;
}

/* Whether a path has a "." or ".." component. */
static int has_dot_component(const char *path)
{
    for (const char *p = path; next_component(&p); p += strcspn(p, "/")) {
        size_t length = strcspn(p, "/");
        if ((length == 1 && p[0] == '.') || (length == 2 && p[0] == '.' && p[1] == '.'))
            return 1;
    }
    return 0;
}

char *mitsuba_path_relative(const char *from_dir, const char *target)
{
    if (from_dir[0] != '/' || target[0] != '/' || has_dot_component(from_dir) ||
        has_dot_component(target))
        return NULL;
    /* Skip the components both share. */
    const char *a = from_dir, *b = target;
    size_t shared = 0;
    for (;;) {
        const char *a_next = a, *b_next = b;
        size_t la = next_component(&a_next), lb = next_component(&b_next);
        if (la == 0 || la != lb || strncmp(a_next, b_next, la) != 0)
            break;
        a = a_next + la;
        b = b_next + lb;
        shared++;
    }
    if (shared == 0)
        return NULL;
    size_t ups = 0;
    for (const char *p = a; next_component(&p); p += strcspn(p, "/"))
        ups++;
    while (*b == '/')
        b++;
    size_t size = 3 * ups + strlen(b) + 2;
    char *out = xmalloc(size), *end = out;
    for (size_t i = 0; i < ups; i++, end += 3)
        memcpy(end, "../", 3);
    strcpy(end, b);
    if (!out[0])
        strcpy(out, ".");
    else if (end > out && !*end && end[-1] == '/')
        end[-1] = '\0';
    return out;
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
