/* error.h — the one error path of the host.
 *
 * A failing function records what failed (with the file, element, line or call it concerns)
 * through error_set() and returns its failure value; the caller either adds nothing and
 * passes the failure up, or prefixes context with error_prefix(). main() prints the message
 * once and chooses the exit code from error_code(). The message is thread-local, so meshes
 * decimated on worker threads keep their own. */
#ifndef IDMR_ERROR_H
#define IDMR_ERROR_H

/* Exit codes of the CLI. */
enum {
    IDMR_EXIT_OK = 0,
    IDMR_EXIT_FAILURE = 1, /* a runtime failure: OpenCL, Embree, out of memory, writing output */
    IDMR_EXIT_INPUT = 2,   /* bad input or usage: scene, mesh, option, no OpenCL platform */
};

/* Records a printf-style message with exit code `code`; always returns -1. */
int error_set(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Prepends "prefix: " to the recorded message; returns -1. */
int error_prefix(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* The recorded message ("" if none) and its exit code (IDMR_EXIT_FAILURE if none). */
const char *error_message(void);
int error_code(void);
void error_clear(void);

/* Prints "idmr: warning: ..." on stderr (unless warnings are silenced). */
void warn(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void warn_silence(int silent);

/* CHECK_FINITE(value, what): in debug and sanitize builds (the Makefile defines
 * IDMR_CHECK_FINITE there), the first intermediate that is NaN or infinite stops the process with
 * a message naming it and the line; release builds compile the check away. Placed where the
 * numbers of a pass meet: importance sums and amounts, the gather radius, pixel estimates,
 * decimation factors and collapse costs. */
#ifdef IDMR_CHECK_FINITE
#define CHECK_FINITE(value, what) check_finite((double)(value), what, __FILE__, __LINE__)
#else
#define CHECK_FINITE(value, what) ((void)0)
#endif
void check_finite(double value, const char *what, const char *file, int line);

/* Allocation that ends the process with a message when memory runs out (never NULL). */
#include <stddef.h>
void *xmalloc(size_t size) __attribute__((returns_nonnull, malloc));
void *xcalloc(size_t count, size_t size) __attribute__((returns_nonnull, malloc));
void *xrealloc(void *ptr, size_t size) __attribute__((returns_nonnull));
char *xstrdup(const char *s) __attribute__((returns_nonnull, malloc));
/* A malloc'd copy of the `bytes` bytes at `from`, or NULL when from is NULL. */
void *xmemdup(const void *from, size_t bytes) __attribute__((malloc));

/* Verbose log ("idmr: ..." on stderr), printed only after log_set_verbose(1) (the -v flag). */
void log_verbose(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void log_set_verbose(int verbose);
int log_is_verbose(void);

#endif
