/* test_mpi.c — MPI ranks that share one importance pass (core/ranks.h, `mpirun -n N idmr ...`):
 * the ranks trace disjoint ranges of the same photon streams and add their 64-bit integer sums
 * with MPI_Allreduce, so what they write must be the single process's byte for byte. Every case
 * runs bin/idmr under mpirun (--oversubscribe: this machine may have fewer cores than ranks)
 * beside the same command run plainly:
 *
 *   - `reduce` on 2 ranks: scene.xml, every PLY (reduced meshes, importance maps), the
 *     importance image, the convergence series, and report.json without what differs by
 *     nature (seconds, device bytes, the rank's devices and the rank count);
 *   - `reduce` on 2 ranks with the stop rule deciding (a loose --factor-tolerance): it stops
 *     after the same iteration on every rank, the one the plain run stops after; and a time
 *     limit that passes in the first iteration stops every rank after it;
 *   - `importance` on 2 and on 3 ranks (paths split unevenly): simulation.bin byte for byte;
 *   - `reduce --passes 2 --initial 0.5` on 2 ranks of two PoCL devices each (--device all):
 *     the same reduced scene as one process on one device;
 *   - the glass of water (13 meshes decimated, shared by 3 ranks and copied back): the same
 *     reduced scene;
 *   - a rank that fails (an MPMD command line gives rank 1 a scene that does not exist, or
 *     another seed, which the ranks' first meeting in the pass refuses): the run exits with
 *     the failing rank's code, the message names the rank, and nothing is left (no output, no
 *     staging directory);
 *   - `render` under mpirun is refused with a message.
 *
 * In a build without MPI (the Makefile found no Open MPI) every case is skipped, and counted
 * as skipped: never as passed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "command_common.h"
#include "core/ranks.h"

#define MPIRUN "mpirun --oversubscribe"
#define SCENE "data/cornell/scene.xml"
#define FAST "--photons 20000 --resolution 0.25 --quiet"

/* A build without MPI skips; one with it needs mpirun (a missing mpirun fails the test). */
static void need_mpi(void)
{
    if (!ranks_built()) {
        fprintf(stderr, "test_mpi: this build has no MPI (Open MPI not found): skipped\n");
        skip();
    }
    run_result r = run("command -v mpirun");
    assert_succeeded(&r);
    run_free(&r);
}

/* report.json as JSON text without the keys that differ by nature between runs (any key
 * holding "seconds" or "bytes", the devices of the rank that wrote it, the rank count), keys
 * sorted: what the importance pass and the reduction computed. */
#define REPORT_CORE                                                                            \
    "python3 -c 'import json, sys\n"                                                           \
    "def core(v):\n"                                                                           \
    "    if isinstance(v, dict):\n"                                                            \
    "        return {k: core(x) for k, x in v.items() if not (\"seconds\" in k or \"bytes\" "  \
    "in k or k in (\"devices\", \"ranks\"))}\n"                                                \
    "    if isinstance(v, list):\n"                                                            \
    "        return [core(x) for x in v]\n"                                                    \
    "    return v\n"                                                                           \
    "print(json.dumps(core(json.load(open(sys.argv[1]))), sort_keys=True, indent=1))' "

/* The two reduced scenes in dir/one (one process) and dir/two (`ranks` ranks): every file the
 * same byte for byte, except report.json, whose computed part is. */
static void assert_same_reduction(const char *dir, int ranks)
{
    run_result r = run("cd %s && diff -r -x report.json one two && "
                       REPORT_CORE "one/report.json > one.core && " REPORT_CORE
                       "two/report.json > two.core && diff one.core two.core && "
                       "grep -q '\"ranks\":[[:space:]]*%d' two/report.json && "
                       "! grep -q '\"ranks\"' one/report.json && ls one/meshes/*.ply >/dev/null",
                       dir, ranks);
    assert_succeeded(&r);
    run_free(&r);
}

/* The brief's case: 2 iterations, target 0.2, on 2 ranks against one process. */
static void test_reduce_on_two_ranks_writes_the_same_scene(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *options = "--target 0.2 --iterations 2 " FAST;
    run_result r = run("bin/idmr reduce " SCENE " %s -o %s/one", options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run(MPIRUN " -n 2 bin/idmr reduce " SCENE " %s -o %s/two", options, dir);
    assert_succeeded(&r);
    /* one voice: rank 0's closing line, once */
    assert_null(strstr(r.err, "idmr: warning"));
    run_free(&r);
    assert_same_reduction(dir, 2);
    remove_tree(dir);
}

/* The stop rule decides: checkpoints every 5 iterations, a loose tolerance, at most 20; the
 * ranks stop together, after the plain run's iteration. */
static void test_stop_rule_decides_alike_on_the_ranks(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *options = "--target 0.3 --iterations 20 --factor-tolerance 0.5 "
                          "--ranking-tolerance 1 --photons 5000 --resolution 0.2 --quiet";
    run_result r = run("bin/idmr reduce " SCENE " %s -o %s/one", options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run(MPIRUN " -n 2 bin/idmr reduce " SCENE " %s -o %s/two", options, dir);
    assert_succeeded(&r);
    run_free(&r);
    assert_same_reduction(dir, 2);
    /* it did stop early (else this case tests nothing the first does not) */
    r = run("python3 -c 'import json, sys; r = json.load(open(sys.argv[1])); "
            "print(r[\"iterations\"] < 20)' %s/two/report.json",
            dir);
    assert_succeeded(&r);
    assert_string_equal(r.out, "True\n");
    run_free(&r);
    /* a time limit that passes in the first iteration: every rank stops after it, as one
     * process does */
    r = run("bin/idmr importance " SCENE " --iterations 50 --time-limit 0.001 " FAST
            " -o %s/time-one && " MPIRUN " -n 2 bin/idmr importance " SCENE
            " --iterations 50 --time-limit 0.001 " FAST " -o %s/time-two && "
            "cmp %s/time-one/simulation.bin %s/time-two/simulation.bin && "
            "grep -q '\"iterations\":[[:space:]]*1,' %s/time-two/report.json",
            dir, dir, dir, dir, dir);
    assert_succeeded(&r);
    run_free(&r);
    remove_tree(dir);
}

/* Two passes (--initial, --passes 2: the ranks decimate the first pass's result, which the
 * second simulates) on 2 ranks of two PoCL devices each (--device all in every rank): the
 * ranges split over ranks, then over each rank's devices; the same scene as one process on
 * one device. */
static void test_two_passes_on_ranks_of_two_devices(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *options = "--target 0.2 --iterations 3 --passes 2 --initial 0.5 " FAST;
    run_result r = run("bin/idmr reduce " SCENE " %s -o %s/one", options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("POCL_DEVICES='pthread pthread' " MPIRUN " -x POCL_DEVICES -n 2 bin/idmr reduce "
            SCENE " %s --device all -o %s/two",
            options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("grep -c '\"paths\"' %s/two/report.json", dir); /* rank 0's two devices */
    assert_succeeded(&r);
    assert_string_equal(r.out, "2\n");
    run_free(&r);
    assert_same_reduction(dir, 2);
    remove_tree(dir);
}

/* Bitterli's glass of water (16 meshes, 13 decimated: shared by the ranks, largest first, and
 * copied back to every rank) on 3 ranks: the one-process scene. */
static void test_decimation_shared_by_three_ranks(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *scene_path = "../shared/data/scenes/glass-of-water/scene-without-mesh000.xml";
    const char *options = "--target 0.3 --iterations 2 --photons 10000 --resolution 0.2 --quiet";
    run_result r = run("bin/idmr reduce %s %s -o %s/one", scene_path, options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run(MPIRUN " -n 3 bin/idmr reduce %s %s -o %s/two", scene_path, options, dir);
    assert_succeeded(&r);
    run_free(&r);
    r = run("ls %s/two/meshes | wc -l", dir);
    assert_succeeded(&r);
    assert_true(atoi(r.out) >= 10);
    run_free(&r);
    assert_same_reduction(dir, 3);
    remove_tree(dir);
}

/* `importance` on 2 and 3 ranks (20000 paths do not split evenly in 3): simulation.bin, the
 * importance maps and the convergence series byte for byte. */
static void test_importance_on_two_and_three_ranks(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *options = "--iterations 3 " FAST;
    run_result r = run("bin/idmr importance " SCENE " %s -o %s/one", options, dir);
    assert_succeeded(&r);
    run_free(&r);
    for (int ranks = 2; ranks <= 3; ranks++) {
        r = run(MPIRUN " -n %d bin/idmr importance " SCENE " %s -o %s/ranks%d", ranks, options,
                dir, ranks);
        assert_succeeded(&r);
        /* the closing line once (rank 0's), no MPI noise */
        assert_non_null(strstr(r.err, "iterations of 20000 photon paths"));
        assert_null(strstr(strstr(r.err, "iterations of 20000") + 1, "iterations of 20000"));
        run_free(&r);
        r = run("cd %s && cmp one/simulation.bin ranks%d/simulation.bin && "
                "cmp one/convergence.csv ranks%d/convergence.csv && "
                "cmp one/importance.png ranks%d/importance.png && "
                "diff -r one/importance ranks%d/importance",
                dir, ranks, ranks, ranks, ranks);
        assert_succeeded(&r);
        run_free(&r);
    }
    remove_tree(dir);
}

/* Nothing of the run is left beside OUTDIR (no output, no staging directory). */
static void assert_nothing_left(const char *dir)
{
    run_result r = run("ls -A %s", dir);
    assert_succeeded(&r);
    assert_string_equal(r.out, "");
    run_free(&r);
}

/* Rank 1 cannot read its scene (an MPMD command line gives it another): exit 2, the message
 * names rank 1 and the file, and rank 0, already in its pass, leaves nothing. */
static void test_a_failing_rank_fails_the_run(void **state)
{
    (void)state;
    need_mpi();
    char dir[64];
    make_temp_dir(dir, "idmr-test-mpi");
    const char *options = "--target 0.2 --iterations 2 " FAST;
    run_result r = run(MPIRUN " -n 1 bin/idmr reduce " SCENE " %s -o %s/out : "
                       "-n 1 bin/idmr reduce %s/missing.xml %s -o %s/out",
                       options, dir, dir, options, dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "idmr: rank 1 of 2: "));
    assert_non_null(strstr(r.err, "missing.xml"));
    run_free(&r);
    assert_nothing_left(dir);
    /* rank 1 runs the pass with another seed: refused where the ranks first meet in the
     * pass, naming rank 1 (its sums would belong to another simulation) */
    r = run(MPIRUN " -n 1 bin/idmr importance " SCENE " --iterations 2 " FAST " -o %s/out : "
                   "-n 1 bin/idmr importance " SCENE " --iterations 2 " FAST
                   " --seed 2 -o %s/out",
            dir, dir);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "idmr: rank 1 of 2: "));
    assert_non_null(strstr(r.err, "another scene or other options than on rank 0"));
    run_free(&r);
    assert_nothing_left(dir);
    remove_tree(dir);
}

/* The renderer is one process; `devices` says the build has MPI. */
static void test_render_refused_and_devices_says_mpi(void **state)
{
    (void)state;
    need_mpi();
    run_result r = run(MPIRUN " -n 2 bin/idmr render " SCENE " --iterations 1 -o /tmp/x.exr");
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "renderer runs as one process"));
    run_free(&r);
    r = run("bin/idmr devices");
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "mpi: Open MPI"));
    assert_non_null(strstr(r.out, "1 rank now"));
    run_free(&r);
    r = run(MPIRUN " -n 2 bin/idmr devices");
    assert_succeeded(&r);
    assert_non_null(strstr(r.out, "2 ranks now"));
    assert_null(strstr(strstr(r.out, "mpi:") + 1, "mpi:")); /* rank 0 alone prints */
    run_free(&r);
}

int main(void)
{
    /* Open MPI refuses root without these (test machines and CI run as root). */
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    /* Containers often forbid the cross-process reads of Open MPI's single-copy transfers
     * ("Read -1, expected ..., errno = 1"): copy through shared memory instead. */
    setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 0);
    /* The sanitizer build exports LSAN_OPTIONS: there Open MPI's own allocations, some in
     * components it has unloaded by exit (no name to suppress them by), would fail every rank.
     * The leak check is off for the programs this test starts; the other tests keep it on for
     * idmr run plainly. */
    const char *leak_options = getenv("LSAN_OPTIONS");
    if (leak_options) {
        char options[2048];
        snprintf(options, sizeof options, "%s:detect_leaks=0", leak_options);
        setenv("LSAN_OPTIONS", options, 1);
    }
    unsetenv("IDMR_DEVICE");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reduce_on_two_ranks_writes_the_same_scene),
        cmocka_unit_test(test_stop_rule_decides_alike_on_the_ranks),
        cmocka_unit_test(test_importance_on_two_and_three_ranks),
        cmocka_unit_test(test_two_passes_on_ranks_of_two_devices),
        cmocka_unit_test(test_decimation_shared_by_three_ranks),
        cmocka_unit_test(test_a_failing_rank_fails_the_run),
        cmocka_unit_test(test_render_refused_and_devices_says_mpi),
    };
    return cmocka_run_group_tests_name("mpi ranks", tests, NULL, NULL) != 0;
}
