/* device_test.h — the one driver of the device tests, in the manner of PoCL's own test suite:
 * every test of a program runs on every OpenCL device, and a work-group sweep once per
 * work-group size.
 *
 * Which devices: every device `idmr devices` lists, in its numbering, or only those named in
 * IDMR_TEST_DEVICES, a comma-separated list of those indices (IDMR_TEST_DEVICES=1, =0,1; unset
 * or empty: all). No OpenCL device at all, an index that does not exist, a malformed list, or
 * a device that does not open is a failed test that says so — never a skip, never a pass.
 *
 * Per device, in order: the device is opened (device_open() with its index; IDMR_DEVICE plays
 * no part), the program's group setup runs, then its tests as one cmocka group named
 * "<suite> on device <index> (<name>)", then the group teardown, and the device is closed.
 * cmocka prints no group names, so every test's name carries the same " on device <index>
 * (<name>)": a failure line names device and case. Tests reach the device through
 * device_test_device(). Per-device state (a built program, a cached run) is made again for each
 * device: build it in the group setup or on first use, and free it in the group teardown.
 * Before each group a line "[ DEVICE   ] <suite>: device <index> (<name>), ..." names the
 * device, its largest work-group and the sweep's sizes; after the last, "[ DEVICES  ] <suite>
 * ran on N of M device(s): ..." lists the devices tested.
 *
 * Work-group sizes: a test listed with DEVICE_TEST_SWEEP(f) runs once per size of
 * device_test_local_sizes() — 0 (the runtime chooses), 1, 7 and 64, each capped at the device's
 * CL_DEVICE_MAX_WORK_GROUP_SIZE, without repeats — as the case "f(local=<size>)", which reads
 * its size with device_test_local_size(state). Other entries are cmocka's own (cmocka_unit_test,
 * cmocka_unit_test_setup_teardown, a named prestate entry) and run once per device as they are.
 *
 *     const struct CMUnitTest tests[] = {
 *         cmocka_unit_test(test_camera_pass_matches_embree),
 *         DEVICE_TEST_SWEEP(test_same_sums_for_any_local_size),
 *     };
 *     return DEVICE_TEST_RUN("importance", tests, group_setup, group_teardown) != 0;
 *
 * Programs are built once per device and test program where the test allows: the kernels come
 * from device_build_program(), whose cache ($IDMR_CACHE_DIR, else ~/.cache/idmr) keys binaries
 * by device, options and sources, so a second build of the same program is a cache load. */
#ifndef IDMR_TESTS_DEVICE_TEST_H
#define IDMR_TESTS_DEVICE_TEST_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "device/device.h"

/* The initial state that marks an entry of a test list as a work-group sweep. */
extern const char device_test_sweep[];
#define DEVICE_TEST_SWEEP(f) {#f, f, NULL, NULL, (void *)device_test_sweep}

/* Runs the `count` tests on each selected device (see above), with `setup` and `teardown`
 * (either may be NULL) around each device's group. Returns the number of failed tests,
 * counting a device that could not be tested, or no device at all, as one failed test. */
int device_test_run(const char *suite, const struct CMUnitTest *tests, size_t count,
                    CMFixtureFunction setup, CMFixtureFunction teardown);
#define DEVICE_TEST_RUN(suite, tests, setup, teardown)                                        \
    device_test_run(suite, tests, sizeof(tests) / sizeof((tests)[0]), setup, teardown)

/* main() of a program with host tests too: the `host_count` host tests once, as the cmocka
 * group "<suite> (host)", then the device tests as device_test_run(). Returns the exit
 * status: 0 when every test passed, else 1. */
int device_test_main(const char *suite, const struct CMUnitTest *host_tests, size_t host_count,
                     const struct CMUnitTest *tests, size_t count, CMFixtureFunction setup,
                     CMFixtureFunction teardown);
#define DEVICE_TEST_MAIN(suite, host_tests, tests, setup, teardown)                           \
    device_test_main(suite, host_tests, sizeof(host_tests) / sizeof((host_tests)[0]), tests,   \
                     sizeof(tests) / sizeof((tests)[0]), setup, teardown)

/* The device of the running group (NULL outside device_test_run()). */
device *device_test_device(void);

/* The work-group size of the running sweep case; fails the test in a test not listed with
 * DEVICE_TEST_SWEEP. */
size_t device_test_local_size(void **state);

/* The sweep's work-group sizes for a device whose CL_DEVICE_MAX_WORK_GROUP_SIZE is `max`:
 * 0, 1, 7, 64 capped at max and without repeats, in that order, into sizes[]; returns how
 * many (at most DEVICE_TEST_MAX_SIZES). */
#define DEVICE_TEST_MAX_SIZES 4
size_t device_test_local_sizes(size_t max, size_t sizes[DEVICE_TEST_MAX_SIZES]);

/* Parses an IDMR_TEST_DEVICES list for a machine with `device_count` devices into
 * indices[device_count] in the order given; *selected gets how many. NULL or "" selects every
 * device. Returns 0, or -1 with the error set (exit code IDMR_EXIT_INPUT) for a list that is
 * not comma-separated device numbers, names a device that does not exist, or names one twice. */
int device_test_select(const char *list, size_t device_count, int *indices, size_t *selected);

#endif
