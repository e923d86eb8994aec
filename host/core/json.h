/* json.h — reports as JSON (through cJSON): built as cJSON trees, then printed on stdout
 * (`--json` flags) or written atomically to a file (core/files.h). */
#ifndef IDMR_JSON_H
#define IDMR_JSON_H

#include <cjson/cJSON.h>

/* Prints `json` (formatted) on stdout; 0, or -1 with the error set. */
int json_print(const cJSON *json);

/* Writes `json` (formatted, with a final newline) atomically to `path`; 0, or -1. */
int json_write(const cJSON *json, const char *path);

/* Adds a [x, y, z] array of three floats to `object` under `name`. */
cJSON *json_add_vec3(cJSON *object, const char *name, const float v[3]);

#endif
