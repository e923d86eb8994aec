/* device_test.c — the device-test driver (see device_test.h): device selection, the work-group
 * sweep, one cmocka group per device, and a failed test where no device could be tested. */
#include "device_test.h"

#include <ctype.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

const char device_test_sweep[] = "work-group sweep";

static device current;
static int has_current;
static size_t sweep_sizes[DEVICE_TEST_MAX_SIZES];
static size_t sweep_count;

/* stdout line by line, so that print_message() lines and cmocka's stderr interleave in order
 * when a test program's output goes to a pipe (scripts/run-tests.sh). */
__attribute__((constructor)) static void line_buffered_stdout(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
}

device *device_test_device(void)
{
    return has_current ? &current : NULL;
}

size_t device_test_local_size(void **state)
{
    uintptr_t p = state ? (uintptr_t)*state : 0;
    if (p < (uintptr_t)sweep_sizes || p >= (uintptr_t)(sweep_sizes + sweep_count))
        fail_msg("device_test_local_size: this test is not listed with DEVICE_TEST_SWEEP");
    return *(const size_t *)*state;
}

size_t device_test_local_sizes(size_t max, size_t sizes[DEVICE_TEST_MAX_SIZES])
{
    static const size_t wanted[DEVICE_TEST_MAX_SIZES] = {0, 1, 7, 64};
    size_t n = 0;
    for (size_t i = 0; i < DEVICE_TEST_MAX_SIZES; i++) {
        size_t size = wanted[i] < max ? wanted[i] : max;
        int repeated = 0;
        for (size_t j = 0; j < n; j++)
            repeated |= sizes[j] == size;
        if (!repeated)
            sizes[n++] = size;
    }
    return n;
}

int device_test_select(const char *list, size_t device_count, int *indices, size_t *selected)
{
    *selected = 0;
    if (!list || !*list) {
        for (size_t i = 0; i < device_count; i++)
            indices[i] = (int)i;
        *selected = device_count;
        return 0;
    }
    size_t n = 0;
    for (const char *p = list;;) {
        while (*p == ' ')
            p++;
        if (!isdigit((unsigned char)*p))
            return error_set(IDMR_EXIT_INPUT,
                             "IDMR_TEST_DEVICES='%s' is not a comma-separated list of device "
                             "numbers (see `idmr devices`)",
                             list);
        char *end;
        errno = 0;
        long index = strtol(p, &end, 10);
        if (errno || index >= (long)device_count)
            return error_set(IDMR_EXIT_INPUT,
                             "IDMR_TEST_DEVICES='%s': device %.*s does not exist: there are %zu "
                             "(see `idmr devices`)",
                             list, (int)(end - p), p, device_count);
        for (size_t j = 0; j < n; j++)
            if (indices[j] == (int)index)
                return error_set(IDMR_EXIT_INPUT, "IDMR_TEST_DEVICES='%s' names device %ld twice",
                                 list, index);
        indices[n++] = (int)index;
        for (p = end; *p == ' '; p++)
            ;
        if (*p == '\0')
            break;
        if (*p != ',')
            return error_set(IDMR_EXIT_INPUT,
                             "IDMR_TEST_DEVICES='%s' is not a comma-separated list of device "
                             "numbers (see `idmr devices`)",
                             list);
        p++;
    }
    *selected = n;
    return 0;
}

/* ---- a device that could not be tested: one failed test that says why ---- */

static char failure[2048];

static void report_failure(void **state)
{
    fail_msg("%s", failure);
}

static int fail_group(const char *suite, const char *what, const char *why)
{
    char name[512];
    snprintf(name, sizeof name, "%s: %s", suite, what);
    snprintf(failure, sizeof failure, "%s: %s", name, why);
    fprintf(stderr, "device_test: %s\n", failure);
    const struct CMUnitTest test = {name, report_failure, NULL, NULL, NULL};
    int failed = _cmocka_run_group_tests(name, &test, 1, NULL, NULL);
    return failed > 0 ? failed : 1;
}

/* ---- one device ---- */

static int is_sweep(const struct CMUnitTest *test)
{
    return test->initial_state == (const void *)device_test_sweep;
}

/* The device's group: every test once, each sweep once per size, named for the device. */
static struct CMUnitTest *expand(const struct CMUnitTest *tests, size_t count, const char *label,
                                 size_t *cases)
{
    *cases = 0;
    for (size_t i = 0; i < count; i++)
        *cases += is_sweep(&tests[i]) ? sweep_count : 1;
    struct CMUnitTest *group = xcalloc(*cases, sizeof *group);
    size_t c = 0;
    for (size_t i = 0; i < count; i++)
        for (size_t j = 0; j < (is_sweep(&tests[i]) ? sweep_count : 1); j++, c++) {
            char name[640];
            group[c] = tests[i];
            if (is_sweep(&tests[i])) {
                snprintf(name, sizeof name, "%s(local=%zu) on %s", tests[i].name,
                         sweep_sizes[j], label);
                group[c].initial_state = &sweep_sizes[j];
            } else {
                snprintf(name, sizeof name, "%s on %s", tests[i].name, label);
            }
            group[c].name = xstrdup(name);
        }
    return group;
}

static int run_on_device(const char *suite, const struct CMUnitTest *tests, size_t count,
                         CMFixtureFunction setup, CMFixtureFunction teardown,
                         const device_info *info)
{
    char label[320];
    snprintf(label, sizeof label, "device %d (%s)", info->index, info->name);
    if (device_open(&current, info->index)) {
        char what[400];
        snprintf(what, sizeof what, "%s does not open", label);
        return fail_group(suite, what, error_message());
    }
    size_t max = 0;
    cl_int err = clGetDeviceInfo(current.info.id, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof max,
                                 &max, NULL);
    if (err != CL_SUCCESS || max == 0) {
        device_close(&current);
        char what[400];
        snprintf(what, sizeof what, "%s has no CL_DEVICE_MAX_WORK_GROUP_SIZE", label);
        return fail_group(suite, what, device_error_string(err));
    }
    sweep_count = device_test_local_sizes(max, sweep_sizes);
    has_current = 1;

    size_t cases;
    struct CMUnitTest *group = expand(tests, count, label, &cases);

    char group_name[400], sizes[64] = "";
    snprintf(group_name, sizeof group_name, "%s on %s", suite, label);
    for (size_t j = 0; j < sweep_count; j++)
        snprintf(sizes + strlen(sizes), sizeof sizes - strlen(sizes), "%s%zu", j ? " " : "",
                 sweep_sizes[j]);
    printf("[ DEVICE   ] %s: %s, %s, max work-group size %zu, sweep sizes %s\n", suite, label,
           current.info.platform_name, max, sizes);
    int failed = _cmocka_run_group_tests(group_name, group, cases, setup, teardown);

    for (size_t c = 0; c < cases; c++)
        free((char *)group[c].name);
    free(group);
    has_current = 0;
    sweep_count = 0;
    device_close(&current);
    return failed > 0 ? failed : failed < 0 ? 1 : 0;
}

int device_test_run(const char *suite, const struct CMUnitTest *tests, size_t count,
                    CMFixtureFunction setup, CMFixtureFunction teardown)
{
    device_info *list;
    size_t device_count;
    if (device_list(&list, &device_count))
        return fail_group(suite, "no OpenCL device", error_message());
    int *indices = xcalloc(device_count, sizeof *indices);
    size_t selected;
    int failed = 0;
    if (device_test_select(getenv("IDMR_TEST_DEVICES"), device_count, indices, &selected))
        failed = fail_group(suite, "IDMR_TEST_DEVICES", error_message());
    char ran[512] = "";
    for (size_t k = 0; k < selected; k++) {
        const device_info *info = &list[indices[k]];
        failed += run_on_device(suite, tests, count, setup, teardown, info);
        snprintf(ran + strlen(ran), sizeof ran - strlen(ran), "%s%d (%s)", k ? ", " : "",
                 info->index, info->name);
    }
    if (selected)
        printf("[ DEVICES  ] %s ran on %zu of %zu device(s): %s\n", suite, selected, device_count,
               ran);
    free(indices);
    free(list);
    return failed;
}

int device_test_main(const char *suite, const struct CMUnitTest *host_tests, size_t host_count,
                     const struct CMUnitTest *tests, size_t count, CMFixtureFunction setup,
                     CMFixtureFunction teardown)
{
    char host_suite[256];
    snprintf(host_suite, sizeof host_suite, "%s (host)", suite);
    int failed = _cmocka_run_group_tests(host_suite, host_tests, host_count, NULL, NULL);
    failed += device_test_run(suite, tests, count, setup, teardown);
    return failed != 0;
}
