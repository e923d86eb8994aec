/* report.c — JSON printing and atomic writes (see report.h). */
#include "report.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"

int report_write_file(const char *path, const void *bytes, size_t size)
{
    size_t length = strlen(path) + 16;
    char *temporary = xmalloc(length);
    snprintf(temporary, length, "%s.tmpXXXXXX", path);
    int fd = mkstemp(temporary);
    if (fd < 0) {
        error_set(IDMR_EXIT_FAILURE, "cannot create '%s': %s", temporary, strerror(errno));
        free(temporary);
        return -1;
    }
    FILE *f = fdopen(fd, "wb");
    int ok = f && fwrite(bytes, 1, size, f) == size;
    ok = (f && fclose(f) == 0) && ok;
    if (!ok || rename(temporary, path) != 0) {
        error_set(IDMR_EXIT_FAILURE, "cannot write '%s': %s", path, strerror(errno));
        unlink(temporary);
        free(temporary);
        return -1;
    }
    free(temporary);
    return 0;
}

int report_print_json(const cJSON *json)
{
    char *text = cJSON_Print(json);
    if (!text)
        return error_set(IDMR_EXIT_FAILURE, "cannot format JSON (out of memory)");
    puts(text);
    cJSON_free(text);
    return 0;
}

int report_write_json(const cJSON *json, const char *path)
{
    char *text = cJSON_Print(json);
    if (!text)
        return error_set(IDMR_EXIT_FAILURE, "cannot format JSON for '%s'", path);
    size_t length = strlen(text);
    text[length] = '\n';
    int status = report_write_file(path, text, length + 1);
    cJSON_free(text);
    return status;
}

cJSON *report_add_vec3(cJSON *object, const char *name, const float v[3])
{
    const double values[3] = {v[0], v[1], v[2]};
    cJSON *array = cJSON_CreateDoubleArray(values, 3);
    cJSON_AddItemToObject(object, name, array);
    return array;
}
