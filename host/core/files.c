/* files.c — atomic output files and directories (see files.h). */
#include "core/files.h"

#define _GNU_SOURCE /* mkstemps, getdents64 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
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

/* Removes the entry `name` in the directory `parent` (a descriptor), a directory with all it
 * holds, without following links. Only system calls and the stack: safe in a signal handler, and
 * when the heap is spent or damaged (an exit through the out-of-memory path, an abort). A
 * directory is read again until a pass over it removes nothing, as entries removed while it is
 * read may move the others. 0, or -1 with errno set. */
static int remove_at(int parent, const char *name)
{
    if (unlinkat(parent, name, 0) == 0 || errno == ENOENT)
        return 0;
    if (errno != EISDIR && errno != EPERM)
        return -1;
    int dir = openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (dir < 0)
        return -1;
    int status = 0;
    for (int removed = 1; status == 0 && removed;) {
        removed = 0;
        if (lseek(dir, 0, SEEK_SET) != 0)
            break;
        char entries[4096] __attribute__((aligned(8)));
        ssize_t length;
        while (status == 0 && (length = getdents64(dir, entries, sizeof entries)) > 0)
            for (ssize_t at = 0; status == 0 && at < length;) {
                const struct dirent64 *entry = (const struct dirent64 *)(entries + at);
                at += entry->d_reclen;
                if (!strcmp(entry->d_name, ".") || !strcmp(entry->d_name, ".."))
                    continue;
                status = remove_at(dir, entry->d_name);
                removed = 1;
            }
    }
    int saved = errno;
    close(dir);
    errno = saved;
    if (status == 0 && unlinkat(parent, name, AT_REMOVEDIR) != 0 && errno != ENOENT)
        status = -1;
    return status;
}

int files_remove_tree(const char *path)
{
    return remove_at(AT_FDCWD, path);
}

/* The staging directory that an interrupt or an exit before files_stage_end() removes (one at a
 * time), the process that made it (a child of a fork leaves it to its parent), whether the
 * final directory held something when it was made (only then may the run's files be moved in
 * among others), and the handlers it replaced. */
static char staged_directory[PATH_MAX];
static pid_t staged_by;
static int staged_over_entries;
static const int staged_signals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT,
                                     SIGABRT, SIGPIPE, SIGXFSZ};
#define STAGED_SIGNAL_COUNT (sizeof staged_signals / sizeof *staged_signals)
static struct sigaction previous_actions[STAGED_SIGNAL_COUNT];

/* Removes the staging directory if this process made it and has not published it. */
static void remove_staged_directory(void)
{
    if (staged_directory[0] && staged_by == getpid()) {
        int saved = errno;
        files_remove_tree(staged_directory);
        errno = saved;
    }
    staged_directory[0] = '\0';
}

/* Removes the staging directory, then dies of the signal as it would have: SIGABRT from an
 * assertion or std::terminate (an uncaught std::bad_alloc), SIGPIPE from a closed pipe,
 * SIGXFSZ from a file size limit, and the interrupts. */
static void remove_staging_and_die(int signal_number)
{
    remove_staged_directory();
    for (size_t i = 0; i < STAGED_SIGNAL_COUNT; i++)
        sigaction(staged_signals[i], &previous_actions[i], NULL);
    raise(signal_number);
}

/* Catches the staged signals, except one the process was started ignoring (a run under nohup,
 * or in the background of a script, keeps ignoring SIGINT and SIGHUP, as it should), and
 * removes the staging directory on exit() too: the out-of-memory path (core/error.h: xmalloc)
 * and every other exit that is not a signal. */
static void watch_staging(const char *staging, int over_entries)
{
    static int exit_handler_registered;
    if (!exit_handler_registered)
        exit_handler_registered = atexit(remove_staged_directory) == 0;
    snprintf(staged_directory, sizeof staged_directory, "%s", staging);
    staged_by = getpid();
    staged_over_entries = over_entries;
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = remove_staging_and_die;
    sigemptyset(&action.sa_mask);
    for (size_t i = 0; i < STAGED_SIGNAL_COUNT; i++)
        sigaddset(&action.sa_mask, staged_signals[i]);
    for (size_t i = 0; i < STAGED_SIGNAL_COUNT; i++) {
        sigaction(staged_signals[i], NULL, &previous_actions[i]);
        if (previous_actions[i].sa_handler != SIG_IGN)
            sigaction(staged_signals[i], &action, NULL);
    }
}

static void unwatch_staging(void)
{
    for (size_t i = 0; i < STAGED_SIGNAL_COUNT; i++)
        sigaction(staged_signals[i], &previous_actions[i], NULL);
    staged_directory[0] = '\0';
}

int files_directory_has_entries(const char *dir)
{
    DIR *handle = opendir(dir);
    if (!handle)
        return 0;
    struct dirent *entry;
    int entries = 0;
    while (!entries && (entry = readdir(handle)))
        entries = strcmp(entry->d_name, ".") && strcmp(entry->d_name, "..");
    closedir(handle);
    return entries;
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
    watch_staging(staging, files_directory_has_entries(trimmed));
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

/* Publishes `staging` as `final`: rename() puts it there in one step where final is missing or
 * an empty directory, and fails where final holds something. Then, where final held something
 * already when the run began (written into with --force, or `importance -o` into a directory
 * of earlier outputs), the files are moved in among the others; where it did not, final was
 * filled by another run meanwhile, and this run's output is not mixed into it. */
static int publish(const char *staging, const char *final)
{
    if (rename(staging, final) == 0)
        return 0;
    int reason = errno;
    struct stat info;
    int is_directory = stat(final, &info) == 0 && S_ISDIR(info.st_mode);
    if (is_directory && (staged_over_entries || !files_directory_has_entries(final)))
        return move_into(staging, final); /* a directory through a link, or one with entries */
    if (is_directory)
        return error_set(IDMR_EXIT_INPUT,
                         "output directory '%s' was filled by another run while this one ran "
                         "(two runs on one output directory?): this run's output was not mixed "
                         "into it and is removed; run again with another output directory",
                         final);
    return error_set(IDMR_EXIT_FAILURE, "cannot move '%s' to '%s': %s", staging, final,
                     strerror(reason));
}

int files_stage_end(const char *staging, const char *final, int success)
{
    int status = success ? publish(staging, final) : 0;
    if (files_remove_tree(staging) != 0 && errno != ENOENT && status == 0)
        status = error_set(IDMR_EXIT_FAILURE, "cannot remove '%s': %s", staging,
                           strerror(errno));
    unwatch_staging();
    return status;
}
