/* report.h — JSON output (through cJSON) and atomic file writes.
 *
 * Reports are built as cJSON trees and either printed (`idmr info --json`) or written with
 * report_write_file(), which writes a temporary file beside the target and renames it, so a
 * reader never sees a half-written report and an interrupted run leaves no partial file. */
#ifndef IDMR_REPORT_H
#define IDMR_REPORT_H

#include <cjson/cJSON.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Creates an empty temporary file beside `path` — named path.tmpXXXXXX plus `suffix` (the
 * extension a writer picks the format by, or "") — with the permissions a new file gets under
 * the umask. Its name goes to `temporary` (size bytes). Returns an open descriptor, or -1 with
 * the error set. */
int report_create_temporary(const char *path, const char *suffix, char *temporary, size_t size);

/* Writes `bytes` to `path` through a temporary file and rename(). 0, or -1 with the error set. */
int report_write_file(const char *path, const void *bytes, size_t size);

/* Prints `json` (formatted) on stdout, or writes it atomically to `path`; 0 or -1. */
int report_print_json(const cJSON *json);
int report_write_json(const cJSON *json, const char *path);

/* Adds a [x, y, z] array of three floats. */
cJSON *report_add_vec3(cJSON *object, const char *name, const float v[3]);

/* Creates `dir` (and parents) if missing; an existing non-directory is an error. Returns 0, or
 * -1 with the error set naming the directory. */
int report_make_directory(const char *dir);

/* Seconds on the monotonic clock, for timings in reports and progress. */
double monotonic_seconds(void);

/* A progress display on stderr for long work: a bar redrawn in place when stderr is a
 * terminal, otherwise one line at every tenth of the work. */
typedef struct progress {
    const char *label;
    unsigned int total;
    int enabled;
    int terminal;
    unsigned int next_line; /* non-terminal: the next count that gets a line */
    double start;
} progress;

void progress_begin(progress *p, const char *label, unsigned int total, int enabled);
/* `done` of total finished; `detail` (may be NULL) is shown after the bar. */
void progress_update(progress *p, unsigned int done, const char *detail);
void progress_end(progress *p);

#ifdef __cplusplus
}
#endif

#endif
