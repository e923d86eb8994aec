/* error.c — thread-local error message, warnings and checked allocation (see error.h). */
#include "core/error.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ERROR_MAX 2048

static _Thread_local char error_text[ERROR_MAX];
static _Thread_local int error_exit_code = IDMR_EXIT_FAILURE;
static int warnings_silenced;

int error_set(int code, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(error_text, sizeof error_text, fmt, args);
    va_end(args);
    error_exit_code = code;
    return -1;
}

int error_prefix(const char *fmt, ...)
{
    char prefix[ERROR_MAX];
    char joined[2 * ERROR_MAX + 4];
    va_list args;
    va_start(args, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, args);
    va_end(args);
    snprintf(joined, sizeof joined, "%s: %s", prefix, error_text);
    size_t length = strlen(joined);
    if (length >= ERROR_MAX)
        length = ERROR_MAX - 1;
    memcpy(error_text, joined, length);
    error_text[length] = '\0';
    return -1;
}

const char *error_message(void) { return error_text; }
int error_code(void) { return error_exit_code; }

void error_clear(void)
{
    error_text[0] = '\0';
    error_exit_code = IDMR_EXIT_FAILURE;
}

/* One line on stderr: prefix, the formatted message, a newline. */
static void print_line(const char *prefix, const char *fmt, va_list args)
{
    fputs(prefix, stderr);
    vfprintf(stderr, fmt, args);
    fputc('\n', stderr);
}

void check_finite(double value, const char *what, const char *file, int line)
{
    if (isfinite(value))
        return;
    fprintf(stderr, "idmr: internal error: %s is %g (%s:%d)\n", what, value, file, line);
    abort();
}

void warn(const char *fmt, ...)
{
    if (warnings_silenced)
        return;
    va_list args;
    va_start(args, fmt);
    print_line("idmr: warning: ", fmt, args);
    va_end(args);
}

void warn_silence(int silent) { warnings_silenced = silent; }

static void *check_allocation(void *ptr, size_t size)
{
    if (!ptr && size) {
        fprintf(stderr, "idmr: out of memory (allocating %zu bytes)\n", size);
        exit(IDMR_EXIT_FAILURE);
    }
    return ptr;
}

void *xmalloc(size_t size) { return check_allocation(malloc(size ? size : 1), size); }
void *xcalloc(size_t count, size_t size)
{
    return check_allocation(calloc(count ? count : 1, size ? size : 1), count * size);
}
void *xrealloc(void *ptr, size_t size) { return check_allocation(realloc(ptr, size ? size : 1), size); }
char *xstrdup(const char *s) { return check_allocation(strdup(s ? s : ""), 1); }

void *xmemdup(const void *from, size_t bytes)
{
    if (!from)
        return NULL;
    void *to = xmalloc(bytes ? bytes : 1);
    memcpy(to, from, bytes);
    return to;
}

static int verbose_logging;

void log_set_verbose(int verbose) { verbose_logging = verbose; }
int log_is_verbose(void) { return verbose_logging; }

void log_verbose(const char *fmt, ...)
{
    if (!verbose_logging)
        return;
    va_list args;
    va_start(args, fmt);
    print_line("idmr: ", fmt, args);
    va_end(args);
}
