/* test_report.c — scripts/report, what accuracy costs in time, and the measures it shares with
 * scripts/evaluate (scripts/evaluation.py):
 *   - its computing pieces (Pareto front, the sweep's points, the stop rule's agreement test,
 *     points.csv) by their unit tests, tests/report_units.py;
 *   - the pooling of a method's reduction errors over its importance seeds (`evaluate
 *     --importance-seeds`) by its unit tests, tests/evaluation_units.py;
 *   - a two-point sweep (quadric and combined at D = 0.1 on the shipped Cornell box, tiny
 *     renders) end to end: points.csv has exactly the report's columns and one row per point,
 *     every value a finite number where the point has one (quadric runs no importance pass, so
 *     its importance settings are empty and nothing else is), report.md and the plots exist.
 * Runs from the repository root (as `make test` does); about a minute on 2 cores. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "command_common.h"

static char work[64];

static int make_work_dir(void **state)
{
    (void)state;
    make_temp_dir(work, "idmr-test-report");
    return 0;
}

static int remove_work_dir(void **state)
{
    (void)state;
    remove_tree(work);
    return 0;
}

/* The unit tests of scripts/report and of scripts/evaluation.py. */
static void test_units(void **state)
{
    (void)state;
    static const char *const scripts[] = {"tests/report_units.py", "tests/evaluation_units.py"};
    for (size_t k = 0; k < sizeof scripts / sizeof *scripts; k++) {
        run_result r = run("/usr/bin/python3 %s", scripts[k]);
        fprintf(stderr, "%s", r.err);
        assert_succeeded(&r);
        run_free(&r);
    }
}

/* The columns of points.csv, as scripts/report's COLUMNS names them; those a quadric point
 * leaves empty. */
static const char *const COLUMNS[] = {
    "scene", "sweeps", "label", "method", "target", "stop", "importance_iterations",
    "iterations_run", "photons", "gamma", "shadow_weight", "vertices", "importance_seconds",
    "reduction_seconds", "preparation_seconds", "render_seconds_per_iteration", "render_seconds",
    "device_bytes", "reduction_rmse", "standard_error", "flip", "rmse_vs_reference",
    "equal_time_iterations", "rmse_equal_time"};
enum { COLUMN_COUNT = sizeof COLUMNS / sizeof *COLUMNS, TEXT_COLUMNS = 4 };
static const char *const QUADRIC_EMPTY[] = {"stop", "importance_iterations", "iterations_run",
                                            "photons", "gamma", "shadow_weight"};

static int quadric_empty(const char *column)
{
    for (size_t k = 0; k < sizeof QUADRIC_EMPTY / sizeof *QUADRIC_EMPTY; k++)
        if (!strcmp(QUADRIC_EMPTY[k], column))
            return 1;
    return 0;
}

/* Splits a CSV line without quoted fields (points.csv has none) into at most `max` fields. */
static size_t split(char *line, char **fields, size_t max)
{
    size_t n = 0;
    line[strcspn(line, "\r\n")] = '\0';
    for (char *field = line; n < max; n++) {
        fields[n] = field;
        char *comma = strchr(field, ',');
        if (!comma)
            return n + 1;
        *comma = '\0';
        field = comma + 1;
    }
    return n + 1; /* more fields than max */
}

static void exists(const char *name)
{
    char path[256];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", work, name);
    if (stat(path, &st) || st.st_size == 0)
        fail_msg("scripts/report did not write %s", path);
}

static void test_two_point_sweep(void **state)
{
    (void)state;
    run_result r = run("scripts/report data/cornell/scene.xml -o %s --sweeps targets "
                       "--targets 0.1 --methods quadric,combined --pixels 1600 --iterations 2 "
                       "--reference-iterations 4 --photons 20000 --iteration-counts 10",
                       work);
    assert_succeeded(&r);
    run_free(&r);
    char path[256], line[4096];
    snprintf(path, sizeof path, "%s/points.csv", work);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char *fields[COLUMN_COUNT + 1];
    assert_non_null(fgets(line, sizeof line, f));
    assert_int_equal(split(line, fields, COLUMN_COUNT + 1), COLUMN_COUNT);
    for (size_t c = 0; c < COLUMN_COUNT; c++)
        assert_string_equal(fields[c], COLUMNS[c]);
    int rows = 0, seen_quadric = 0, seen_combined = 0;
    while (fgets(line, sizeof line, f)) {
        rows++;
        assert_int_equal(split(line, fields, COLUMN_COUNT + 1), COLUMN_COUNT);
        int quadric = !strcmp(fields[3], "quadric");
        seen_quadric |= quadric;
        seen_combined |= !strcmp(fields[3], "combined");
        for (size_t c = TEXT_COLUMNS; c < COLUMN_COUNT; c++) {
            if (!strcmp(COLUMNS[c], "stop")) {
                assert_string_equal(fields[c], quadric ? "" : "rule");
                continue;
            }
            if (quadric && quadric_empty(COLUMNS[c])) {
                if (fields[c][0])
                    fail_msg("quadric's %s is '%s', not empty", COLUMNS[c], fields[c]);
                continue;
            }
            char *end;
            double value = strtod(fields[c], &end);
            if (!fields[c][0] || *end || !isfinite(value) || value < 0)
                fail_msg("%s of %s is '%s', not a finite number >= 0", COLUMNS[c], fields[2],
                         fields[c]);
        }
    }
    fclose(f);
    assert_int_equal(rows, 2);
    assert_true(seen_quadric && seen_combined);
    exists("report.md");
    exists("cornell-pareto.png");
    exists("cornell-targets.png");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_units),
        cmocka_unit_test(test_two_point_sweep),
    };
    return cmocka_run_group_tests(tests, make_work_dir, remove_work_dir);
}
