/* files.c — atomic output files and directories (see files.h). */
#include "core/files.h"

#define _GNU_SOURCE /* nftw, mkstemps */
#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"

/* The process's umask (read without changing it). */
static mode_t umask_value(void)
{
    mode_t mask = umask(0);
    umask(mask);
    return mask;
}

int files_create_temporary(const char *path, const char *suffix, char *temporary, size_t size)
{
    int written = snprintf(temporary, size, "%s.tmpXXXXXX%s", path, suffix);
    if (written < 0 || (size_t)written >= size)
        return error_set(IDMR_EXIT_FAILURE, "path too long: '%s'", path);
    int fd = mkstemps(temporary, (int)strlen(suffix));
    if (fd < 0)
        return error_set(IDMR_EXIT_FAILURE, "cannot create '%s': %s", temporary, strerror(errno));
    fchmod(fd, 0666 & ~umask_value());
    return fd;
}

int files_write_atomic(const char *path, const void *bytes, size_t size)
{
    char temporary[4096];
    int fd = files_create_temporary(path, "", temporary, sizeof temporary);
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

int files_copy_atomic(const char *source, const char *path)
{
    struct stat from, to;
    if (stat(source, &from) != 0)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s': %s", source, strerror(errno));
    if (stat(path, &to) == 0 && from.st_dev == to.st_dev && from.st_ino == to.st_ino)
        return error_set(IDMR_EXIT_INPUT,
                         "'%s' is the input '%s' itself: not overwritten (inputs are never "
                         "written)",
                         path, source);
    FILE *in = fopen(source, "rb");
    if (!in)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s': %s", source, strerror(errno));
    char temporary[4096];
    int fd = files_create_temporary(path, "", temporary, sizeof temporary);
    if (fd < 0) {
        fclose(in);
        return -1;
    }
    FILE *out = fdopen(fd, "wb");
    if (!out)
        close(fd);
    char buffer[1 << 16];
    size_t n;
    int ok = out != NULL;
    while (ok && (n = fread(buffer, 1, sizeof buffer, in)) > 0)
        ok = fwrite(buffer, 1, n, out) == n;
    int read_failed = ferror(in);
    fclose(in);
    ok = (out && fclose(out) == 0) && ok && !read_failed;
    if (!ok || rename(temporary, path) != 0) {
        error_set(IDMR_EXIT_FAILURE, "cannot copy '%s' to '%s': %s", source, path,
                  read_failed ? "read error" : strerror(errno));
        unlink(temporary);
        return -1;
    }
    return 0;
}

/* mkdir that accepts an existing entry; 0, or -1 with the error set. */
static int make_one_directory(const char *path)
{
    if (mkdir(path, 0777) != 0 && errno != EEXIST)
        return error_set(IDMR_EXIT_FAILURE, "cannot create directory '%s': %s", path,
                         strerror(errno));
    return 0;
}

int files_make_directory(const char *dir)
{
    char path[4096];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path)
        return error_set(IDMR_EXIT_FAILURE, "path too long: '%s'", dir);
    for (char *c = path + 1; *c; c++) {
        if (*c != '/')
            continue;
        *c = '\0';
        if (make_one_directory(path))
            return -1;
        *c = '/';
    }
    if (make_one_directory(path))
        return -1;
    struct stat info;
    if (stat(path, &info) != 0 || !S_ISDIR(info.st_mode))
        return error_set(IDMR_EXIT_FAILURE, "'%s' exists and is not a directory", path);
    return 0;
}

/* ---- staged output directories ---- */

static int remove_entry(const char *path, const struct stat *info, int kind, struct FTW *where)
{
    (void)info, (void)kind, (void)where;
    return remove(path) == 0 || errno == ENOENT ? 0 : -1;
}

int files_remove_tree(const char *path)
{
    return nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The staging directory an interrupt removes (one at a time), and the handlers it replaced. */
static char interrupted_staging[PATH_MAX];
static const int staged_signals[] = {SIGINT, SIGTERM, SIGHUP};
static struct sigaction previous_actions[3];

/* Removes the staging directory, then dies of the signal as it would have. (nftw is not
 * async-signal-safe; the process ends right after, and a run interrupted while it allocates
 * is the price of leaving no half-written output.) */
static void remove_staging_and_die(int signal_number)
{
    if (interrupted_staging[0])
        files_remove_tree(interrupted_staging);
    for (size_t i = 0; i < sizeof staged_signals / sizeof *staged_signals; i++)
        sigaction(staged_signals[i], &previous_actions[i], NULL);
    raise(signal_number);
}

/* Catches the staged signals, except one the process was started ignoring (a run under nohup,
 * or in the background of a script, keeps ignoring SIGINT and SIGHUP, as it should). */
static void watch_signals(const char *staging)
{
    snprintf(interrupted_staging, sizeof interrupted_staging, "%s", staging);
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = remove_staging_and_die;
    sigemptyset(&action.sa_mask);
    for (size_t i = 0; i < sizeof staged_signals / sizeof *staged_signals; i++) {
        sigaction(staged_signals[i], NULL, &previous_actions[i]);
        if (previous_actions[i].sa_handler != SIG_IGN)
            sigaction(staged_signals[i], &action, NULL);
    }
}

static void unwatch_signals(void)
{
    for (size_t i = 0; i < sizeof staged_signals / sizeof *staged_signals; i++)
        sigaction(staged_signals[i], &previous_actions[i], NULL);
    interrupted_staging[0] = '\0';
}

int files_stage_begin(const char *final, char *staging, size_t size)
{
    char trimmed[PATH_MAX];
    snprintf(trimmed, sizeof trimmed, "%s", final);
    for (size_t n = strlen(trimmed); n > 1 && trimmed[n - 1] == '/'; n--)
        trimmed[n - 1] = '\0';
    char *slash = strrchr(trimmed, '/');
    if (slash && slash != trimmed) {
        *slash = '\0';
        if (files_make_directory(trimmed))
            return -1;
        *slash = '/';
    }
    int written = snprintf(staging, size, "%s.partial-XXXXXX", trimmed);
    if (written < 0 || (size_t)written >= size)
        return error_set(IDMR_EXIT_FAILURE, "path too long: '%s'", final);
    if (!mkdtemp(staging))
        return error_set(IDMR_EXIT_FAILURE, "cannot create '%s': %s", staging, strerror(errno));
    chmod(staging, 0777 & ~umask_value());
    watch_signals(staging);
    return 0;
}

/* Moves every entry of directory `from` into `to` (created if missing), replacing files of
 * the same name and merging directories. */
static int move_into(const char *from, const char *to)
{
    if (files_make_directory(to))
        return -1;
    DIR *dir = opendir(from);
    if (!dir)
        return error_set(IDMR_EXIT_FAILURE, "cannot read '%s': %s", from, strerror(errno));
    int status = 0;
    struct dirent *entry;
    while (status == 0 && (entry = readdir(dir))) {
        if (!strcmp(entry->d_name, ".") || !strcmp(entry->d_name, ".."))
            continue;
        char source[PATH_MAX], target[PATH_MAX];
        snprintf(source, sizeof source, "%s/%s", from, entry->d_name);
        snprintf(target, sizeof target, "%s/%s", to, entry->d_name);
        struct stat info, existing;
        if (lstat(source, &info) == 0 && S_ISDIR(info.st_mode) &&
            stat(target, &existing) == 0 && S_ISDIR(existing.st_mode))
            status = move_into(source, target);
        else if (rename(source, target) != 0)
            status = error_set(IDMR_EXIT_FAILURE, "cannot move '%s' to '%s': %s", source,
                               target, strerror(errno));
    }
    closedir(dir);
    return status;
}

/* Whether `dir` is missing, or an empty directory (then removed, to be replaced). */
static int replaceable(const char *dir)
{
    struct stat info;
    if (stat(dir, &info) != 0)
        return errno == ENOENT;
    return S_ISDIR(info.st_mode) && rmdir(dir) == 0;
}

int files_stage_end(const char *staging, const char *final, int success)
{
    int status = 0;
    if (success) {
        if (!(replaceable(final) && rename(staging, final) == 0))
            status = move_into(staging, final);
    }
    if (files_remove_tree(staging) != 0 && errno != ENOENT && status == 0)
        status = error_set(IDMR_EXIT_FAILURE, "cannot remove '%s': %s", staging,
                           strerror(errno));
    unwatch_signals();
    return status;
}
