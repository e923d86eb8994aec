/* test_fuzz_inputs.c — replays every stored fuzzer input through the reader its target feeds
 * (tests/fuzz/fuzz_inputs.h), so that what fuzzing once found stays fixed in `make test`:
 *
 *   tests/fuzz/corpus/TARGET/       the hand-written seeds: valid inputs, each must be accepted
 *   tests/fuzz/regressions/TARGET/  inputs that once crashed, hung or were misread: a name
 *                                   starting "reject-" must be rejected with a message, one
 *                                   starting "accept-" accepted; any other (a crash-* or
 *                                   timeout-* file as libFuzzer names it) must only return
 *
 * TARGET is scene, pbrt, gltf, simulation, obj, off, ply or stl. A directory that is missing or empty
 * fails its test. Under `make test config=sanitize` the replay runs with ASan and UBSan, as the
 * fuzzer does. */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mitsuba_common.h"

#include "core/progress.h"
#include "fuzz/fuzz_inputs.h"

#define FUZZ_ROOT IDMR_ROOT "/tests/fuzz"

static char temp_dir[64];

static int make_temp_dir(void **state)
{
    warn_silence(1);
    progress_set_quiet(1);
    return temp_dir_make(temp_dir, "fuzz-inputs");
}

/* The scene the simulation target reads for, loaded at its first input. */
static scene *simulation_scene;

static int remove_temp_dir(void **state)
{
    scene_free(simulation_scene);
    simulation_scene = NULL;
    warn_silence(0);
    return temp_dir_remove(temp_dir);
}

/* Feeds one input to target's reader; whether it was accepted. */
static int replay(const char *target, const uint8_t *data, size_t size)
{
    if (strcmp(target, "scene") == 0)
        return fuzz_scene_input(data, size, temp_dir);
    if (strcmp(target, "simulation") == 0) {
        if (!simulation_scene)
            simulation_scene = fuzz_simulation_scene(IDMR_ROOT, temp_dir);
        if (!simulation_scene)
            fail_msg("cannot load the simulation target's scene: %s", error_message());
        return fuzz_simulation_input(data, size, temp_dir, simulation_scene);
    }
    if (strcmp(target, "gltf") == 0)
        return fuzz_gltf_input(data, size, temp_dir);
    if (strcmp(target, "pbrt") == 0)
        return fuzz_pbrt_input(data, size, temp_dir);
    char extension[8];
    snprintf(extension, sizeof extension, ".%s", target);
    return fuzz_mesh_input(data, size, temp_dir, extension);
}

/* Replays every file of FUZZ_ROOT/kind/target (kind: corpus or regressions), checking what its
 * name asks for; returns how many there were. */
static size_t replay_directory(const char *kind, const char *target)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/%s/%s", FUZZ_ROOT, kind, target);
    DIR *d = opendir(dir);
    if (!d)
        fail_msg("cannot open %s", dir);
    size_t count = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        char path[8192];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        size_t size = 0;
        char *data = read_all(path, &size);
        assert_non_null(data);
        int accepted = replay(target, (const uint8_t *)data, size);
        free(data);
        int must_accept = strcmp(kind, "corpus") == 0 || strncmp(e->d_name, "accept-", 7) == 0;
        int must_reject = strncmp(e->d_name, "reject-", 7) == 0;
        if (must_accept && !accepted)
            fail_msg("%s: rejected: %s", path, error_message());
        if (must_reject && (accepted || !error_message()[0]))
            fail_msg("%s: accepted, or rejected without a message", path);
        print_message("  %s: %s\n", e->d_name, accepted ? "accepted" : error_message());
        count++;
    }
    closedir(d);
    if (count == 0)
        fail_msg("%s holds no inputs", dir);
    return count;
}

/* The seeds and regressions of one target (the test's state: its name). */
static void test_target_inputs(void **state)
{
    replay_directory("corpus", *state);
    replay_directory("regressions", *state);
}

#define TARGET_TEST(name) {"test_" name "_inputs", test_target_inputs, NULL, NULL, (void *)name}

int main(void)
{
    const struct CMUnitTest tests[] = {
        TARGET_TEST("scene"), TARGET_TEST("gltf"), TARGET_TEST("simulation"),
        TARGET_TEST("obj"),   TARGET_TEST("off"),  TARGET_TEST("ply"),
        TARGET_TEST("stl"),   TARGET_TEST("pbrt"),
    };
    return cmocka_run_group_tests(tests, make_temp_dir, remove_temp_dir);
}
