/* test_device.c — the OpenCL runtime (host/device/device.c) and the device-test driver
 * (tests/device_test.c): discovery, the choice of device through IDMR_DEVICE, the driver's
 * device list (IDMR_TEST_DEVICES) and work-group sizes, and per device: what a failed kernel
 * build reports, an oversized buffer, and device_run() covering its range exactly once for
 * every work-group size. Also includes every shared layout header so that their
 * _Static_asserts are checked by this compiler. */
#include <sys/stat.h>
#include <unistd.h>

#include "idmr/bvh_layout.h"
#include "idmr/camera.h"
#include "idmr/features.h"
#include "idmr/importance_layout.h"
#include "idmr/light.h"
#include "idmr/material.h"
#include "idmr/ray.h"
#include "idmr/render_layout.h"
#include "idmr/sppm_layout.h"
#include "test_support.h"

/* ---- discovery (host) ---- */

static void test_list_devices(void **state)
{
    device_info *list;
    size_t count;
    assert_int_equal(device_list(&list, &count), 0);
    assert_true(count >= 1);
    for (size_t i = 0; i < count; i++) {
        assert_int_equal(list[i].index, (int)i);
        assert_true(list[i].compute_units >= 1);
        assert_true(list[i].global_memory > 0);
        assert_true(strlen(list[i].name) > 0);
    }
    free(list);
}

/* device_open(-1) with IDMR_DEVICE set to `value`: the status, and the device opened. */
static int open_with_environment(const char *value, int index, int *opened)
{
    setenv("IDMR_DEVICE", value, 1);
    device d;
    int status = device_open(&d, index);
    unsetenv("IDMR_DEVICE");
    *opened = status ? -1 : d.info.index;
    if (!status)
        device_close(&d);
    return status;
}

static void test_idmr_device_chooses(void **state)
{
    int opened;
    assert_int_equal(open_with_environment("0", -1, &opened), 0);
    assert_int_equal(opened, 0);
}

static void test_idmr_device_that_does_not_exist(void **state)
{
    int opened;
    assert_int_equal(open_with_environment("999", -1, &opened), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "device 999 does not exist"));
}

static void test_idmr_device_not_a_number(void **state)
{
    int opened;
    assert_int_equal(open_with_environment("gpu", -1, &opened), -1);
    assert_non_null(strstr(error_message(), "IDMR_DEVICE='gpu'"));
}

/* An explicit --device wins over the environment. */
static void test_explicit_device_wins(void **state)
{
    int opened;
    assert_int_equal(open_with_environment("999", 0, &opened), 0);
    assert_int_equal(opened, 0);
}

/* ---- the driver's device list and work-group sizes (host) ---- */

static void test_all_devices_without_a_list(void **state)
{
    int indices[3];
    size_t selected;
    assert_int_equal(device_test_select(NULL, 3, indices, &selected), 0);
    assert_int_equal(selected, 3);
    assert_int_equal(device_test_select("", 3, indices, &selected), 0);
    assert_int_equal(selected, 3);
    assert_true(indices[0] == 0 && indices[1] == 1 && indices[2] == 2);
}

static void test_devices_in_the_order_listed(void **state)
{
    int indices[3];
    size_t selected;
    assert_int_equal(device_test_select("2, 0", 3, indices, &selected), 0);
    assert_int_equal(selected, 2);
    assert_true(indices[0] == 2 && indices[1] == 0);
    assert_int_equal(device_test_select("1", 3, indices, &selected), 0);
    assert_true(selected == 1 && indices[0] == 1);
}

/* A list that names no device, one that does not exist, or one twice: an input error. */
static void test_bad_device_lists(void **state)
{
    const char *bad[] = {"a", "1,", ",1", "1;2", "-1", "3", "99999999999999999999", "1,1"};
    int indices[3];
    size_t selected;
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        error_clear();
        assert_int_equal(device_test_select(bad[i], 3, indices, &selected), -1);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
        assert_non_null(strstr(error_message(), "IDMR_TEST_DEVICES"));
        assert_int_equal(selected, 0);
    }
    assert_non_null(strstr(error_message(), "twice"));
}

static void expect_sizes(size_t max, const size_t *expected, size_t count)
{
    size_t sizes[DEVICE_TEST_MAX_SIZES];
    assert_int_equal(device_test_local_sizes(max, sizes), count);
    assert_memory_equal(sizes, expected, count * sizeof *sizes);
}

/* 0, 1, 7, 64, capped at the device's largest work-group and without repeats. */
static void test_sweep_sizes_capped_at_the_device(void **state)
{
    expect_sizes(4096, (const size_t[]){0, 1, 7, 64}, 4);
    expect_sizes(64, (const size_t[]){0, 1, 7, 64}, 4);
    expect_sizes(32, (const size_t[]){0, 1, 7, 32}, 4);
    expect_sizes(7, (const size_t[]){0, 1, 7}, 3);
    expect_sizes(1, (const size_t[]){0, 1}, 2);
}

/* ---- per device ---- */

/* IDMR_ROOT for the device tests: kernels/broken.cl does not compile, kernels/ids.cl writes
 * each work-item's global id, +1, into out[id] when id < n. */
static char root[] = "/tmp/idmr-kernels-XXXXXX";

static void write_kernel(const char *name, const char *text)
{
    char path[512];
    snprintf(path, sizeof path, "%s/kernels/%s", root, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static int kernels_setup(void **state)
{
    char path[512];
    if (!mkdtemp(root))
        return -1;
    snprintf(path, sizeof path, "%s/kernels", root);
    mkdir(path, 0700);
    snprintf(path, sizeof path, "%s/include", root);
    mkdir(path, 0700);
    write_kernel("broken.cl", "kernel void broken(global float *x) { x[0] = undeclared_name; }\n");
    write_kernel("ids.cl", "kernel void ids(global uint *out, uint n)\n"
                           "{\n"
                           "    uint i = get_global_id(0);\n"
                           "    if (i < n)\n"
                           "        out[i] += i + 1;\n"
                           "}\n");
    setenv("IDMR_ROOT", root, 1);
    return 0;
}

static int kernels_teardown(void **state)
{
    unsetenv("IDMR_ROOT");
    int status = test_remove_directory(root);
    snprintf(root, sizeof root, "/tmp/idmr-kernels-XXXXXX");
    return status;
}

/* A kernel that does not compile: the error holds the options, the compiler's log and the
 * file. */
static void test_failed_build_reports_log_and_options(void **state)
{
    device *d = device_test_device();
    char *options = device_build_options(d, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA, "-D EXTRA=1");
    assert_non_null(strstr(options, "-D IDMR_FEATURES=0x21u"));
    assert_non_null(strstr(options, "-D EXTRA=1"));
    cl_program program;
    int status = device_build_program(d, "broken.cl", options, &program);
    free(options);
    assert_int_equal(status, -1);
    assert_non_null(strstr(error_message(), "undeclared_name"));
    assert_non_null(strstr(error_message(), "-D IDMR_FEATURES=0x21u"));
    assert_non_null(strstr(error_message(), "broken.cl"));
}

static void test_missing_kernel_file_is_named(void **state)
{
    cl_program program;
    assert_int_equal(device_build_program(device_test_device(), "absent.cl", "", &program), -1);
    assert_non_null(strstr(error_message(), "absent.cl"));
}

static void test_oversized_buffer_is_refused_with_sizes(void **state)
{
    device *d = device_test_device();
    cl_mem buffer;
    size_t too_big = (size_t)d->info.max_allocation + 1;
    assert_int_equal(device_buffer(d, CL_MEM_READ_WRITE, too_big, NULL, "photon paths", &buffer),
                     -1);
    assert_non_null(strstr(error_message(), "photon paths"));
    assert_non_null(strstr(error_message(), "MiB"));
}

/* device_run() of n = 1000 work-items (not a multiple of 7 or 64) rounds the range up to the
 * work-group size: every id below n adds itself + 1 exactly once, and the sentinels after
 * out[n - 1] stay 0. */
static void test_run_covers_the_range_once(void **state)
{
    device *d = device_test_device();
    enum { n = 1000, padded = 1100 };
    cl_uint out[padded], count = n;
    cl_program program = NULL;
    cl_kernel kernel = NULL;
    cl_mem buffer = NULL;
    int status = device_build_program(d, "ids.cl", "", &program) ||
                 device_create_kernel(program, "ids", &kernel) ||
                 device_buffer(d, CL_MEM_READ_WRITE, sizeof out, NULL, "ids", &buffer) ||
                 device_clear(d, buffer, sizeof out, "ids") ||
                 DEVICE_SET_ARGS(kernel, "ids", DEVICE_ARG(buffer), DEVICE_ARG(count)) ||
                 device_run(d, kernel, "ids", n, device_test_local_size(state)) ||
                 device_read(d, buffer, sizeof out, out, "ids");
    device_release_buffers(&buffer, 1);
    device_release_kernels(&kernel, 1);
    if (program)
        clReleaseProgram(program);
    if (status)
        fail_msg("%s", error_message());
    for (cl_uint i = 0; i < padded; i++)
        assert_int_equal(out[i], i < n ? i + 1 : 0);
}

int main(void)
{
    const struct CMUnitTest host_tests[] = {
        cmocka_unit_test(test_list_devices),
        cmocka_unit_test(test_idmr_device_chooses),
        cmocka_unit_test(test_idmr_device_that_does_not_exist),
        cmocka_unit_test(test_idmr_device_not_a_number),
        cmocka_unit_test(test_explicit_device_wins),
        cmocka_unit_test(test_all_devices_without_a_list),
        cmocka_unit_test(test_devices_in_the_order_listed),
        cmocka_unit_test(test_bad_device_lists),
        cmocka_unit_test(test_sweep_sizes_capped_at_the_device),
    };
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_failed_build_reports_log_and_options),
        cmocka_unit_test(test_missing_kernel_file_is_named),
        cmocka_unit_test(test_oversized_buffer_is_refused_with_sizes),
        DEVICE_TEST_SWEEP(test_run_covers_the_range_once),
    };
    return DEVICE_TEST_MAIN("device", host_tests, tests, kernels_setup, kernels_teardown);
}
