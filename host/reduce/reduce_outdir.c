/* reduce_outdir.c — the output directory of `idmr reduce` (see reduce_stages.h): created if
 * missing, refused when it holds something and --force was not given, and never a directory
 * that holds a file the scene reads (the scene's own directory, however it is spelled, or one
 * above it: inputs are never written). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/error.h"
#include "core/files.h"
#include "reduce/reduce_stages.h"

int reduce_outdir_prepare(reduce_state *st)
{
    const char *outdir = st->outdir;
    if (scene_check_output_directory(st->scene, outdir))
        return -1;
    struct stat info;
    if (stat(outdir, &info) == 0 && !S_ISDIR(info.st_mode))
        return error_set(IDMR_EXIT_INPUT, "output directory '%s' exists and is not a directory",
                         outdir);
    if (!st->options->force && files_directory_has_entries(outdir))
        return error_set(IDMR_EXIT_INPUT,
                         "output directory '%s' exists and is not empty (use --force to write "
                         "into it)",
                         outdir);
    return files_stage_begin(outdir, st->staging, sizeof st->staging);
}

int reduce_outdir_finish(reduce_state *st, int success)
{
    if (!st->staging[0])
        return success ? 0 : -1;
    return files_stage_end(st->staging, st->outdir, success) || !success ? -1 : 0;
}
