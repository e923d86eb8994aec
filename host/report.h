/* report.h — JSON output (through cJSON) and atomic file writes.
 *
 * Reports are built as cJSON trees and either printed (`idmr info --json`) or written with
 * report_write_file(), which writes a temporary file beside the target and renames it, so a
 * reader never sees a half-written report and an interrupted run leaves no partial file. */
#ifndef IDMR_REPORT_H
#define IDMR_REPORT_H

#include <cjson/cJSON.h>
#include <stddef.h>

/* Writes `bytes` to `path` through a temporary file and rename(). 0, or -1 with the error set. */
int report_write_file(const char *path, const void *bytes, size_t size);

/* Prints `json` (formatted) on stdout, or writes it atomically to `path`; 0 or -1. */
int report_print_json(const cJSON *json);
int report_write_json(const cJSON *json, const char *path);

/* Adds a [x, y, z] array of three floats. */
cJSON *report_add_vec3(cJSON *object, const char *name, const float v[3]);

#endif
