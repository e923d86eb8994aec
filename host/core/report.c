/* report.c — JSON printing and atomic writes (see report.h). */
#include "core/report.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"

int report_create_temporary(const char *path, const char *suffix, char *temporary, size_t size)
{
    int written = snprintf(temporary, size, "%s.tmpXXXXXX%s", path, suffix);
    if (written < 0 || (size_t)written >= size)
        return error_set(IDMR_EXIT_FAILURE, "path too long: '%s'", path);
    int fd = mkstemps(temporary, (int)strlen(suffix));
    if (fd < 0)
        return error_set(IDMR_EXIT_FAILURE, "cannot create '%s': %s", temporary, strerror(errno));
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    return fd;
}

int report_write_file(const char *path, const void *bytes, size_t size)
{
    char temporary[4096];
    int fd = report_create_temporary(path, "", temporary, sizeof temporary);
    if (fd < 0)
        return -1;
    FILE *f = fdopen(fd, "wb");
    if (!f)
        close(fd);
    int ok = f && fwrite(bytes, 1, size, f) == size;
    ok = (f && fclose(f) == 0) && ok;
    if (!ok || rename(temporary, path) != 0) {
        error_set(IDMR_EXIT_FAILURE, "cannot write '%s': %s", path, strerror(errno));
        unlink(temporary);
        return -1;
    }
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

double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void progress_begin(progress *p, const char *label, unsigned int total, int enabled)
{
    p->label = label;
    p->total = total ? total : 1;
    p->enabled = enabled;
    p->terminal = isatty(STDERR_FILENO);
    p->next_line = 0;
    p->start = monotonic_seconds();
}

void progress_update(progress *p, unsigned int done, const char *detail)
{
    if (!p->enabled)
        return;
    double elapsed = monotonic_seconds() - p->start;
    double fraction = (double)done / p->total;
    double remaining = done ? elapsed * (p->total - done) / done : 0;
    if (p->terminal) {
        char bar[31];
        int filled = (int)(fraction * 30 + 0.5);
        for (int i = 0; i < 30; i++)
            bar[i] = i < filled ? '#' : '.';
        bar[30] = '\0';
        fprintf(stderr, "\r%s [%s] %u/%u  %.1fs, %.1fs left  %s\033[K", p->label, bar, done,
                p->total, elapsed, remaining, detail ? detail : "");
        fflush(stderr);
    } else if (done >= p->next_line || done == p->total) {
        fprintf(stderr, "%s: %u/%u (%.0f%%) %.1fs %s\n", p->label, done, p->total,
                100.0 * fraction, elapsed, detail ? detail : "");
        p->next_line = done + (p->total + 9) / 10;
    }
}

void progress_end(progress *p)
{
    if (p->enabled && p->terminal)
        fputc('\n', stderr);
}

int report_make_directory(const char *dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s", dir);
    for (char *c = path + 1; *c; c++) {
        if (*c != '/')
            continue;
        *c = '\0';
        if (mkdir(path, 0777) != 0 && errno != EEXIST)
            return error_set(IDMR_EXIT_FAILURE, "cannot create directory '%s': %s", path,
                             strerror(errno));
        *c = '/';
    }
    if (mkdir(path, 0777) != 0 && errno != EEXIST)
        return error_set(IDMR_EXIT_FAILURE, "cannot create directory '%s': %s", path,
                         strerror(errno));
    struct stat info;
    if (stat(path, &info) != 0 || !S_ISDIR(info.st_mode))
        return error_set(IDMR_EXIT_FAILURE, "'%s' exists and is not a directory", path);
    return 0;
}
