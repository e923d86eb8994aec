/* json.c — printing and writing cJSON reports (see json.h). */
#include "core/json.h"

#include <stdio.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"

int json_print(const cJSON *json)
{
    char *text = cJSON_Print(json);
    if (!text)
        return error_set(IDMR_EXIT_FAILURE, "cannot format JSON (out of memory)");
    puts(text);
    cJSON_free(text);
    return 0;
}

int json_write(const cJSON *json, const char *path)
{
    char *text = cJSON_Print(json);
    if (!text)
        return error_set(IDMR_EXIT_FAILURE, "cannot format JSON for '%s'", path);
    size_t length = strlen(text);
    text[length] = '\n'; /* over the terminating NUL: the length is passed explicitly */
    int status = files_write_atomic(path, text, length + 1);
    cJSON_free(text);
    return status;
}

cJSON *json_add_vec3(cJSON *object, const char *name, const float v[3])
{
    const double values[3] = {v[0], v[1], v[2]};
    cJSON *array = cJSON_CreateDoubleArray(values, 3);
    cJSON_AddItemToObject(object, name, array);
    return array;
}
