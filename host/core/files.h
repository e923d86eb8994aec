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

/* An output directory written as a unit. files_stage_begin() makes a staging directory beside
 * `final` (its parent created if missing), named final.partial-XXXXXX, into `staging` (size
 * bytes), and arranges for it to be removed if the process ends before files_stage_end():
 * through exit() (the out-of-memory path included) or a signal (SIGINT, SIGTERM, SIGHUP,
 * SIGQUIT, SIGABRT, SIGPIPE, SIGXFSZ; one the process was started ignoring stays ignored). The
 * run writes every file there. files_stage_end() with success publishes it: renamed to `final`
 * when final is missing or empty (one step: a reader sees all of it or none); where final held
 * something when the staging began (written into with --force), each file is moved in by
 * rename(), replacing one of the same name; where final was missing or empty then but holds
 * something now (another run on the same output published first), nothing is moved and the
 * error says so. Without success it removes the staging directory. Either way nothing
 * half-written is left. 0, or -1 with the error set. */
int files_stage_begin(const char *final, char *staging, size_t size);
int files_stage_end(const char *staging, const char *final, int success);

/* Removes a file or a directory tree (not following links), with system calls only (safe in a
 * signal handler). 0, or -1 with errno set. */
int files_remove_tree(const char *path);

/* Whether `dir` is a directory that holds an entry (one that cannot be opened counts as
 * empty). */
int files_directory_has_entries(const char *dir);

/* Creates `dir` (and parents) if missing; an existing non-directory is an error. Returns 0, or
 * -1 with the error set naming the directory. */
int files_make_directory(const char *dir);

#ifdef __cplusplus
}
#endif

#endif
