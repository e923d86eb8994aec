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
