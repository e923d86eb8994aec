/* test_files.c — output files and directories (host/core/files.h): atomic files, copies that
 * refuse to overwrite their source, and staged output directories, published as a unit or
 * merged into a non-empty directory on success, removed on failure and on an interrupt. */
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "core/files.h"

static char temp_dir[64];

static int make_temp_dir(void **state)
{
    return temp_dir_make(temp_dir, "files");
}

static int remove_temp_dir(void **state)
{
    return temp_dir_remove(temp_dir);
}

static int exists(const char *path)
{
    struct stat info;
    return stat(path, &info) == 0;
}

/* Whether temp_dir holds an entry whose name starts with `prefix` (1) or none (0). */
static int has_entry_prefixed(const char *prefix)
{
    char command[256];
    snprintf(command, sizeof command, "test $(ls -a %s | grep -c '^%s') -eq 0", temp_dir,
             prefix);
    return system(command) == 0 ? 0 : 1;
}

/* Staged into a missing directory: nothing at the final path until the end, then all of it. */
static void test_stage_publishes_as_a_unit(void **state)
{
    char final[128], staging[256];
    snprintf(final, sizeof final, "%s/new/out", temp_dir);
    assert_int_equal(files_stage_begin(final, staging, sizeof staging), 0);
    assert_non_null(strstr(staging, "/new/out.partial-"));
    assert_int_equal(files_make_directory(path_in(staging, "meshes")), 0);
    assert_int_equal(files_write_atomic(path_in(staging, "meshes/a.ply"), "a", 1), 0);
    assert_int_equal(files_write_atomic(path_in(staging, "scene.xml"), "s", 1), 0);
    assert_false(exists(final));
    assert_int_equal(files_stage_end(staging, final, 1), 0);
    assert_true(exists(path_in(final, "meshes/a.ply")));
    assert_true(exists(path_in(final, "scene.xml")));
    assert_false(exists(staging));
}

/* Into a non-empty directory (--force): files of the same name replaced, others kept,
 * directories merged. */
static void test_stage_merges_into_a_full_directory(void **state)
{
    char final[128], staging[256];
    snprintf(final, sizeof final, "%s/full", temp_dir);
    assert_int_equal(files_make_directory(path_in(final, "meshes")), 0);
    assert_int_equal(files_write_atomic(path_in(final, "meshes/old.ply"), "o", 1), 0);
    assert_int_equal(files_write_atomic(path_in(final, "scene.xml"), "old", 3), 0);
    assert_int_equal(files_stage_begin(final, staging, sizeof staging), 0);
    assert_int_equal(files_make_directory(path_in(staging, "meshes")), 0);
    assert_int_equal(files_write_atomic(path_in(staging, "meshes/new.ply"), "n", 1), 0);
    assert_int_equal(files_write_atomic(path_in(staging, "scene.xml"), "new", 3), 0);
    assert_int_equal(files_stage_end(staging, final, 1), 0);
    assert_true(exists(path_in(final, "meshes/old.ply")));
    assert_true(exists(path_in(final, "meshes/new.ply")));
    size_t size;
    char *text = read_all(path_in(final, "scene.xml"), &size);
    assert_int_equal(size, 3);
    assert_memory_equal(text, "new", 3);
    free(text);
    assert_false(exists(staging));
}

/* A failed run leaves nothing: no final directory, no staging directory. */
static void test_stage_failure_leaves_nothing(void **state)
{
    char final[128], staging[256];
    snprintf(final, sizeof final, "%s/failed", temp_dir);
    assert_int_equal(files_stage_begin(final, staging, sizeof staging), 0);
    assert_int_equal(files_write_atomic(path_in(staging, "report.json"), "{}", 2), 0);
    assert_int_equal(files_stage_end(staging, final, 0), 0);
    assert_false(exists(final));
    assert_false(exists(staging));
    assert_int_equal(has_entry_prefixed("failed"), 0);
}

/* Interrupted (SIGINT, SIGTERM) while staged: the staging directory is removed and the process
 * dies of the signal, as it would have. */
static void test_stage_interrupt_leaves_nothing(void **state)
{
    const int signals[2] = {SIGINT, SIGTERM};
    for (int i = 0; i < 2; i++) {
        char final[128];
        snprintf(final, sizeof final, "%s/interrupted%d", temp_dir, i);
        pid_t child = fork();
        assert_true(child >= 0);
        if (child == 0) {
            char staging[256];
            signal(signals[i], SIG_DFL); /* a test run in the background starts ignoring SIGINT */
            if (files_stage_begin(final, staging, sizeof staging) ||
                files_write_atomic(path_in(staging, "half.ply"), "h", 1))
                _exit(3);
            raise(signals[i]);
            _exit(4); /* not reached */
        }
        int status;
        assert_int_equal(waitpid(child, &status, 0), child);
        assert_true(WIFSIGNALED(status) && WTERMSIG(status) == signals[i]);
        assert_false(exists(final));
        snprintf(final, sizeof final, "interrupted%d", i);
        assert_int_equal(has_entry_prefixed(final), 0);
    }
}

/* A signal the process started ignoring (nohup, a script's background job) stays ignored while
 * an output is staged: the run goes on and publishes its output. */
static void test_stage_keeps_ignored_signals_ignored(void **state)
{
    char final[128];
    snprintf(final, sizeof final, "%s/under-nohup", temp_dir);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        char staging[256];
        signal(SIGHUP, SIG_IGN);
        if (files_stage_begin(final, staging, sizeof staging) ||
            files_write_atomic(path_in(staging, "done.ply"), "d", 1))
            _exit(3);
        raise(SIGHUP);
        _exit(files_stage_end(staging, final, 1) == 0 ? 0 : 5);
    }
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    assert_true(exists(path_in(final, "done.ply")));
}

/* A copy onto its own source is refused, and the source stays as it was. */
static void test_copy_refuses_its_source(void **state)
{
    const char *source = write_text(temp_dir, "texture.png", "pixels");
    char alias[128];
    snprintf(alias, sizeof alias, "%s/./texture.png", temp_dir);
    error_clear();
    assert_int_equal(files_copy_atomic(source, alias), -1);
    assert_non_null(strstr(error_message(), "never written"));
    assert_int_equal(files_copy_atomic(source, path_in(temp_dir, "copy.png")), 0);
    size_t size;
    char *text = read_all(path_in(temp_dir, "copy.png"), &size);
    assert_int_equal(size, 6);
    assert_memory_equal(text, "pixels", 6);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stage_publishes_as_a_unit),
        cmocka_unit_test(test_stage_merges_into_a_full_directory),
        cmocka_unit_test(test_stage_failure_leaves_nothing),
        cmocka_unit_test(test_stage_interrupt_leaves_nothing),
        cmocka_unit_test(test_stage_keeps_ignored_signals_ignored),
        cmocka_unit_test(test_copy_refuses_its_source),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
