/* command_common.h — shared by the tests that run commands (test_cli.c, bin/idmr end to end;
 * test_mitsuba_renders.c, idmr's output in Mitsuba 3): a shell command line run with its
 * stdout, stderr and exit status captured, and temporary directories. Header-only (static
 * functions): each program includes it once, after cmocka.h. */
#ifndef IDMR_TESTS_COMMAND_COMMON_H
#define IDMR_TESTS_COMMAND_COMMON_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

typedef struct run_result {
    char *command;
    int status;
    char *out;
    char *err;
} run_result;

static char *slurp(FILE *f)
{
    size_t size = 0, capacity = 4096;
    char *text = malloc(capacity);
    size_t got;
    while ((got = fread(text + size, 1, capacity - size - 1, f)) > 0) {
        size += got;
        if (capacity - size < 2) {
            capacity *= 2;
            text = realloc(text, capacity);
        }
    }
    text[size] = '\0';
    return text;
}

/* Runs a shell command line (printf-style); captures stdout, stderr and the exit status. */
static run_result run(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static run_result run(const char *fmt, ...)
{
    char command[2048], err_path[] = "/tmp/idmr-test-cli-XXXXXX";
    va_list args;
    va_start(args, fmt);
    vsnprintf(command, sizeof command, fmt, args);
    va_end(args);
    int fd = mkstemp(err_path);
    close(fd);
    char line[4096];
    snprintf(line, sizeof line, "%s 2>%s", command, err_path);
    FILE *p = popen(line, "r");
    run_result r;
    r.command = strdup(command);
    r.out = slurp(p);
    int status = pclose(p);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    FILE *e = fopen(err_path, "r");
    r.err = slurp(e);
    fclose(e);
    unlink(err_path);
    return r;
}

static void run_free(run_result *r)
{
    free(r->command);
    free(r->out);
    free(r->err);
}

/* A run that must succeed: fails the test with its stderr otherwise. */
static void assert_succeeded(const run_result *r)
{
    if (r->status != 0)
        fail_msg("'%s' failed (%d): %s", r->command, r->status, r->err);
}

/* A new directory /tmp/<prefix>-XXXXXX into dir (64 bytes). */
static void make_temp_dir(char *dir, const char *prefix)
{
    snprintf(dir, 64, "/tmp/%s-XXXXXX", prefix);
    assert_non_null(mkdtemp(dir));
}

static void remove_tree(const char *dir)
{
    char command[128];
    snprintf(command, sizeof command, "rm -rf %s", dir);
    assert_int_equal(system(command), 0);
}

#endif
