/* test_device.c — the OpenCL runtime (host/device.c): discovery, the choice of device through
 * IDMR_DEVICE, and what a failed kernel build reports. Also includes every shared layout header
 * so that their _Static_asserts are checked by this compiler. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "device/device.h"
#include "device/program.h"
#include "core/error.h"
#include "idmr/bvh_layout.h"
#include "idmr/camera.h"
#include "idmr/features.h"
#include "idmr/importance_layout.h"
#include "idmr/sppm_layout.h"
#include "idmr/light.h"
#include "idmr/material.h"
#include "idmr/ray.h"
#include "idmr/render_layout.h"

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

static void test_choice_by_environment(void **state)
{
    device d;
    setenv("IDMR_DEVICE", "0", 1);
    assert_int_equal(device_open(&d, -1), 0);
    assert_int_equal(d.info.index, 0);
    device_close(&d);

    setenv("IDMR_DEVICE", "999", 1);
    assert_int_equal(device_open(&d, -1), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "device 999 does not exist"));

    setenv("IDMR_DEVICE", "gpu", 1);
    assert_int_equal(device_open(&d, -1), -1);
    assert_non_null(strstr(error_message(), "IDMR_DEVICE='gpu'"));
    unsetenv("IDMR_DEVICE");

    /* An explicit --device wins over the environment. */
    setenv("IDMR_DEVICE", "999", 1);
    assert_int_equal(device_open(&d, 0), 0);
    device_close(&d);
    unsetenv("IDMR_DEVICE");
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* A kernel that does not compile: the error holds the options and the compiler's log. */
static void test_failed_build_reports_log_and_options(void **state)
{
    char root[] = "/tmp/idmr-kernels-XXXXXX";
    assert_non_null(mkdtemp(root));
    char path[512];
    snprintf(path, sizeof path, "%s/kernels", root);
    mkdir(path, 0700);
    snprintf(path, sizeof path, "%s/include", root);
    mkdir(path, 0700);
    snprintf(path, sizeof path, "%s/kernels/broken.cl", root);
    write_file(path, "kernel void broken(global float *x) { x[0] = undeclared_name; }\n");
    setenv("IDMR_ROOT", root, 1);

    device d;
    assert_int_equal(device_open(&d, -1), 0);
    char *options = device_build_options(&d, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA, "-D EXTRA=1");
    assert_non_null(strstr(options, "-D IDMR_FEATURES=0x21u"));
    assert_non_null(strstr(options, "-D EXTRA=1"));
    cl_program program;
    assert_int_equal(device_build_program(&d, "broken.cl", options, &program), -1);
    assert_non_null(strstr(error_message(), "undeclared_name"));
    assert_non_null(strstr(error_message(), "-D IDMR_FEATURES=0x21u"));
    assert_non_null(strstr(error_message(), "broken.cl"));

    assert_int_equal(device_build_program(&d, "absent.cl", options, &program), -1);
    assert_non_null(strstr(error_message(), "absent.cl"));
    free(options);
    device_close(&d);
    unsetenv("IDMR_ROOT");
    unlink(path);
    snprintf(path, sizeof path, "%s/kernels", root);
    rmdir(path);
    snprintf(path, sizeof path, "%s/include", root);
    rmdir(path);
    rmdir(root);
}

static void test_oversized_buffer_is_refused_with_sizes(void **state)
{
    device d;
    assert_int_equal(device_open(&d, -1), 0);
    cl_mem buffer;
    size_t too_big = (size_t)d.info.max_allocation + 1;
    assert_int_equal(device_buffer(&d, CL_MEM_READ_WRITE, too_big, NULL, "photon paths", &buffer),
                     -1);
    assert_non_null(strstr(error_message(), "photon paths"));
    assert_non_null(strstr(error_message(), "MiB"));
    device_close(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_list_devices),
        cmocka_unit_test(test_choice_by_environment),
        cmocka_unit_test(test_failed_build_reports_log_and_options),
        cmocka_unit_test(test_oversized_buffer_is_refused_with_sizes),
    };
    return cmocka_run_group_tests_name("device", tests, NULL, NULL);
}
