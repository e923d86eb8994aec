/* files.c — atomic output files and directories (see files.h). */
#include "core/files.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"

int files_create_temporary(const char *path, const char *suffix, char *temporary, size_t size)
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
    static char buffer[1 << 16];
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
