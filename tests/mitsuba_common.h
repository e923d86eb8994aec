/* mitsuba_common.h — what the Mitsuba reader and writer tests (tests/test_mitsuba.c,
 * tests/test_mitsuba_write.c) share: temporary directories and the files written into them,
 * files read back whole, scenes loaded (or the test failed), meshes found by name and measured,
 * the real scenes in ../shared/data (a missing data directory fails a test, it never skips),
 * and cmocka tests made from a table of cases, one named test per case. Header-only (static
 * functions): each program includes it once, after <cmocka.h>. */
#ifndef IDMR_TESTS_MITSUBA_COMMON_H
#define IDMR_TESTS_MITSUBA_COMMON_H

#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"
#include "core/scene.h"
#include "io/mitsuba/mitsuba.h"
#include "test_support.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define SCENES IDMR_ROOT "/../shared/data/scenes"

/* ---- temporary directories and files ---- */

/* Creates a fresh /tmp/idmr-test-<tag>-XXXXXX into dir (64 bytes); 0 or -1. */
static inline int temp_dir_make(char dir[64], const char *tag)
{
    snprintf(dir, 64, "/tmp/idmr-test-%s-XXXXXX", tag);
    return mkdtemp(dir) ? 0 : -1;
}

/* Removes dir and everything under it; 0 or -1. */
static inline int temp_dir_remove(const char *dir)
{
    char command[128];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    return system(command) == 0 ? 0 : -1;
}

/* dir/name into a static buffer (one of four, so that a few can be alive at once). */
static inline const char *path_in(const char *dir, const char *name)
{
    static char paths[4][2 * PATH_MAX];
    static int next;
    char *path = paths[next++ % 4];
    snprintf(path, sizeof paths[0], "%s/%s", dir, name);
    return path;
}

/* Writes `text` to dir/name (its directory must exist); returns the path (as path_in). */
static inline const char *write_text(const char *dir, const char *name, const char *text)
{
    const char *path = path_in(dir, name);
    FILE *f = fopen(path, "w");
    if (!f)
        fail_msg("cannot write %s", path);
    fputs(text, f);
    fclose(f);
    return path;
}

static inline void make_subdir(const char *dir, const char *name)
{
    const char *path = path_in(dir, name);
    if (mkdir(path, 0755) != 0)
        fail_msg("cannot make directory %s", path);
}

static inline int file_exists(const char *path)
{
    return access(path, F_OK) == 0;
}

/* The whole file, malloc'd and NUL-terminated (*size, if non-NULL, gets its length); NULL if it
 * cannot be read. */
static inline char *read_all(const char *path, size_t *size)
{
    int fd = open(path, O_RDONLY);
    struct stat info;
    if (fd < 0)
        return NULL;
    if (fstat(fd, &info) != 0) {
        close(fd);
        return NULL;
    }
    char *bytes = malloc((size_t)info.st_size + 1);
    assert_non_null(bytes);
    ssize_t got = read(fd, bytes, (size_t)info.st_size);
    close(fd);
    assert_int_equal(got, info.st_size);
    bytes[got] = '\0';
    if (size)
        *size = (size_t)got;
    return bytes;
}

/* ---- scenes ---- */


static inline void mesh_bbox(const scene_mesh *m, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = FLT_MAX;
        hi[k] = -FLT_MAX;
    }
    for (uint32_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], m->positions[3 * v + k]);
            hi[k] = fmaxf(hi[k], m->positions[3 * v + k]);
        }
}

static inline void require_shared_data(void)
{
    if (access(SCENES, R_OK) != 0)
        fail_msg("%s is missing: the real-scene tests need ../shared/data (see DESIGN.md); "
                 "they fail rather than skip",
                 SCENES);
}

/* ---- tests from tables ---- */

#define ARRAY_COUNT(array) (sizeof(array) / sizeof(array)[0])

/* Appends one test per element of the array `cases` (structs with a `name`) to the array
 * `tests`, which holds `count` tests so far: the test is named by its case and runs `function`
 * with the case as *state. Exits when `tests` is full. */
#define ADD_CASE_TESTS(tests, count, function, cases)                                           \
    for (size_t case_ = 0; case_ < ARRAY_COUNT(cases); case_++) {                               \
        if ((count) == ARRAY_COUNT(tests)) {                                                    \
            fprintf(stderr, "%s: more tests than room for them\n", __FILE__);                  \
            exit(1);                                                                            \
        }                                                                                       \
        (tests)[(count)++] = (struct CMUnitTest){(cases)[case_].name, (function), NULL, NULL,  \
                                                 (void *)&(cases)[case_]};                      \
    }

#endif
