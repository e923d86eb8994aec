/* test_files.c — output files and directories (host/core/files.h): atomic files, copies that
 * refuse to overwrite their source, and staged output directories, published as a unit or
 * merged into a non-empty directory on success, removed on failure, on an interrupt, on an
 * abort and on every exit() (the out-of-memory path among them); a second run staged into the
 * same missing directory is refused rather than merged; every write checked (a file size
 * limit makes writes fail part-way, as a full disk does). */
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/resource.h>
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


/* The argument that makes this program the child of stage_then_end (main). */
#define STAGE_CHILD "--stage-then-end"

#if defined(__SANITIZE_ADDRESS__)
/* LeakSanitizer's own hook: off in the child of stage_then_end, which ends through exit() on
 * purpose with its staging state held. */
static int stage_child;
int __lsan_is_turned_off(void);
int __lsan_is_turned_off(void) { return stage_child; }
#endif

/* The child of stage_then_end: stages `final`, then ends as `how` says. */
static int stage_then_end_child(const char *final, int how)
{
#if defined(__SANITIZE_ADDRESS__)
    stage_child = 1;
#endif
    char staging[256];
    signal(SIGABRT, SIG_DFL);
    if (files_stage_begin(final, staging, sizeof staging) ||
        files_make_directory(path_in(staging, "meshes")) ||
        files_write_atomic(path_in(staging, "meshes/half.ply"), "h", 1))
        _exit(3);
    if (how == 1) {
#if defined(__SANITIZE_ADDRESS__)
        exit(IDMR_EXIT_FAILURE); /* ASan ends a failed allocation itself, without exit() */
#else
        volatile size_t huge = SIZE_MAX / 4;
        free(xmalloc(huge));
        _exit(4); /* not reached: xmalloc exits */
#endif
    }
    if (how == 2)
        abort();
    exit(IDMR_EXIT_FAILURE);
}

/* A staged child that ends through exit() — xmalloc's out-of-memory path, or any other exit
 * that is not a signal — or through abort(): the staging directory is removed all the same.
 * `how`: 0 exit(), 1 xmalloc of more than the address space, 2 abort(). The child is this
 * program run again (stage_then_end_child), not a forked copy: a copy of a process with threads
 * cannot end through exit(), whose library finalizers wait for threads the copy does not have
 * (the sanitize build's, log4cplus's through OpenImageIO, hung there). */
static void stage_then_end(const char *name, int how)
{
    char final[128], how_text[8];
    snprintf(final, sizeof final, "%s/%s", temp_dir, name);
    snprintf(how_text, sizeof how_text, "%d", how);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        execl("/proc/self/exe", "test_files", STAGE_CHILD, final, how_text, (char *)NULL);
        _exit(127);
    }
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    if (how == 2)
        assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT);
    else
        assert_true(WIFEXITED(status) && WEXITSTATUS(status) == IDMR_EXIT_FAILURE);
    assert_false(exists(final));
    if (has_entry_prefixed(name))
        fail_msg("'%s' left a staging directory behind in %s", name, temp_dir);
}

static void test_stage_exit_leaves_nothing(void **state)
{
    stage_then_end("exited", 0);
}

static void test_stage_out_of_memory_leaves_nothing(void **state)
{
    stage_then_end("out-of-memory", 1);
}

static void test_stage_abort_leaves_nothing(void **state)
{
    stage_then_end("aborted", 2);
}

/* Two runs staged into the same missing directory (two `idmr reduce -o OUT` at once): the first
 * to finish publishes; the second is refused with a message, and its files are not mixed in. */
static void test_stage_second_run_is_refused(void **state)
{
    char final[128], first[256], second[256];
    snprintf(final, sizeof final, "%s/raced", temp_dir);
    assert_int_equal(files_stage_begin(final, first, sizeof first), 0);
    assert_int_equal(files_write_atomic(path_in(first, "scene.xml"), "first", 5), 0);
    int staged[2];
    assert_int_equal(pipe(staged), 0);
    pid_t child = fork(); /* the second run: one staging directory per process */
    assert_true(child >= 0);
    if (child == 0) {
        if (files_stage_begin(final, second, sizeof second) ||
            files_write_atomic(path_in(second, "scene.xml"), "second", 6) ||
            files_write_atomic(path_in(second, "only-second.ply"), "s", 1) ||
            write(staged[1], "s", 1) != 1)
            _exit(3);
        while (!exists(final)) /* the first publishes meanwhile */
            usleep(1000);
        error_clear();
        int refused = files_stage_end(second, final, 1) == -1 &&
                      strstr(error_message(), "another run") && strstr(error_message(), final);
        if (!refused)
            fprintf(stderr, "second run: '%s'\n", error_message());
        _exit(refused ? 0 : 5);
    }
    char byte;
    assert_int_equal(read(staged[0], &byte, 1), 1); /* both started while OUT was missing */
    close(staged[0]);
    close(staged[1]);
    assert_int_equal(files_stage_end(first, final, 1), 0);
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    size_t size;
    char *text = read_all(path_in(final, "scene.xml"), &size);
    assert_int_equal(size, 5);
    assert_memory_equal(text, "first", 5);
    free(text);
    assert_false(exists(path_in(final, "only-second.ply")));
    assert_int_equal(has_entry_prefixed("raced.partial"), 0);
}

/* In a child whose files may be at most `limit` bytes, with SIGXFSZ ignored (a write past the
 * limit fails with EFBIG part-way, as one on a full disk fails with ENOSPC): writes `size` bytes
 * to `path` through files_write_atomic() and exits with its status, 0 or 1. */
static int write_limited(const char *path, size_t size, rlim_t limit)
{
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        struct rlimit file_size = {limit, limit};
        signal(SIGXFSZ, SIG_IGN);
        if (setrlimit(RLIMIT_FSIZE, &file_size))
            _exit(3);
        char *bytes = calloc(size, 1);
        _exit(files_write_atomic(path, bytes, size) == 0 ? 0 : 1);
    }
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    return WEXITSTATUS(status);
}

/* A write cut short fails, and leaves neither the file nor its temporary name. */
static void test_write_cut_short_fails(void **state)
{
    const char *path = path_in(temp_dir, "limited.bin");
    assert_int_equal(write_limited(path, 200000, 65536), 1);
    assert_false(exists(path));
    assert_int_equal(has_entry_prefixed("limited"), 0);
    assert_int_equal(write_limited(path, 1000, 65536), 0);
    assert_true(exists(path));
}

int main(int argc, char **argv)
{
    if (argc == 4 && strcmp(argv[1], STAGE_CHILD) == 0)
        return stage_then_end_child(argv[2], atoi(argv[3]));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stage_publishes_as_a_unit),
        cmocka_unit_test(test_stage_merges_into_a_full_directory),
        cmocka_unit_test(test_stage_failure_leaves_nothing),
        cmocka_unit_test(test_stage_interrupt_leaves_nothing),
        cmocka_unit_test(test_stage_keeps_ignored_signals_ignored),
        cmocka_unit_test(test_copy_refuses_its_source),
        cmocka_unit_test(test_stage_exit_leaves_nothing),
        cmocka_unit_test(test_stage_out_of_memory_leaves_nothing),
        cmocka_unit_test(test_stage_abort_leaves_nothing),
        cmocka_unit_test(test_stage_second_run_is_refused),
        cmocka_unit_test(test_write_cut_short_fails),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
