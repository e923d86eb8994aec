/* reduce_outdir.c — the output directory of `idmr reduce` (see reduce_stages.h): created if
 * missing, refused when it holds something and --force was not given, and never the scene's own
 * directory, however it is spelled (inputs are never written). */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"
#include "reduce/reduce_stages.h"

/* Whether dir exists and holds an entry; a directory that cannot be opened counts as empty
 * (files_make_directory() then says what is wrong with it). */
static int directory_has_entries(const char *dir)
{
    DIR *handle = opendir(dir);
    if (!handle)
        return 0;
    struct dirent *entry;
    int entries = 0;
    while ((entry = readdir(handle)))
        if (strcmp(entry->d_name, ".") && strcmp(entry->d_name, ".."))
            entries = 1;
    closedir(handle);
    return entries;
}

/* Whether outdir (if it exists) is the directory scene_dir names. */
static int is_scene_directory(const char *outdir, const char *scene_dir)
{
    char scene_real[PATH_MAX], out_real[PATH_MAX];
    return realpath(scene_dir, scene_real) && realpath(outdir, out_real) &&
           strcmp(scene_real, out_real) == 0;
}

int reduce_outdir_prepare(const char *outdir, const char *scene_dir, int force)
{
    if (is_scene_directory(outdir, scene_dir))
        return error_set(IDMR_EXIT_INPUT,
                         "output directory '%s' is the scene's own directory: choose another "
                         "(inputs are never overwritten)",
                         outdir);
    if (!force && directory_has_entries(outdir))
        return error_set(IDMR_EXIT_INPUT,
                         "output directory '%s' exists and is not empty (use --force to write "
                         "into it)",
                         outdir);
    if (files_make_directory(outdir))
        return -1;
    char meshes[PATH_MAX];
    snprintf(meshes, sizeof meshes, "%s/meshes", outdir);
    return files_make_directory(meshes);
}
