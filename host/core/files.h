/* files.h — output files written atomically, and output directories.
 *
 * Every file idmr writes goes through a temporary name beside its target and a rename(), so a
 * reader never sees a half-written file and an interrupted run leaves no partial one. Inputs
 * are never written: callers check that an output path is not a file the scene reads. */
#ifndef IDMR_FILES_H
#define IDMR_FILES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Creates an empty temporary file beside `path` — named path.tmpXXXXXX plus `suffix` (the
 * extension a writer picks the format by, or "") — with the permissions a new file gets under
 * the umask. Its name goes to `temporary` (size bytes). Returns an open descriptor, or -1 with
 * the error set. */
int files_create_temporary(const char *path, const char *suffix, char *temporary, size_t size);

/* Writes `bytes` to `path` through a temporary file and rename(). 0, or -1 with the error set. */
int files_write_atomic(const char *path, const void *bytes, size_t size);

/* Copies the file `source` to `path` through a temporary file and rename(). A `path` that is
 * `source` itself (however spelled) is refused: inputs are never written. 0, or -1 with the
 * error set naming the file that could not be read or written. */
int files_copy_atomic(const char *source, const char *path);

/* Creates `dir` (and parents) if missing; an existing non-directory is an error. Returns 0, or
 * -1 with the error set naming the directory. */
int files_make_directory(const char *dir);

#ifdef __cplusplus
}
#endif

#endif
