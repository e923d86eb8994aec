/* pbrt_messages.c — the pbrt reader's errors and warnings: "file:line: what". A warning is printed
 * once per load for each distinct text (twenty shapes with the same unsupported parameter give
 * one line, naming the first); the texts seen are kept in a small table that
 * pbrt_warnings_reset() empties at the start of a load. */
#include "io/pbrt/pbrt_loader.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

#define PBRT_MESSAGE_MAX 1024

static char **warned;
static size_t warned_count;

int pbrt_fail(const char *file, int line, const char *fmt, ...)
{
    char what[PBRT_MESSAGE_MAX];
    va_list args;
    va_start(args, fmt);
    vsnprintf(what, sizeof what, fmt, args);
    va_end(args);
    return error_set(IDMR_EXIT_INPUT, "%s:%d: %s", file, line, what);
}

void pbrt_warn(const char *file, int line, const char *fmt, ...)
{
    char what[PBRT_MESSAGE_MAX];
    va_list args;
    va_start(args, fmt);
    vsnprintf(what, sizeof what, fmt, args);
    va_end(args);
    for (size_t i = 0; i < warned_count; i++)
        if (strcmp(warned[i], what) == 0)
            return;
    warned = xrealloc(warned, (warned_count + 1) * sizeof *warned);
    warned[warned_count++] = xstrdup(what);
    warn("%s:%d: %s", file, line, what);
}

void pbrt_warnings_reset(void)
{
    for (size_t i = 0; i < warned_count; i++)
        free(warned[i]);
    free(warned);
    warned = NULL;
    warned_count = 0;
}
