/* reduce_common.h — shared by the end-to-end tests of `idmr reduce` (test_reduce.c on the
 * shipped Cornell box, test_reduce_scenes.c on scenes the tests write): the OpenCL device of the
 * program (group setup), small options (3 iterations of 20,000 photons), mkdtemp directories
 * under /tmp, file and report access, and one successful reduction (its directory, report and
 * reduced scene). Header-only (static functions): each program includes it once, after
 * cmocka.h. Runs from the repository root. */
#ifndef IDMR_TESTS_REDUCE_COMMON_H
#define IDMR_TESTS_REDUCE_COMMON_H

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/error.h"
#include "io/mitsuba/mitsuba.h"
#include "io/scene_load.h"
#include "reduce/reduce.h"
#include "test_support.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define CORNELL_DIR IDMR_ROOT "/data/cornell"
#define CORNELL CORNELL_DIR "/scene.xml"
#define KNOT CORNELL_DIR "/meshes/knot.ply"


static inline void small_options(reduce_options *o)
{
    reduce_options_default(o);
    o->target = 0.1;
    o->importance.sppm.iterations = 3;
    o->importance.sppm.photons = 20000;
    o->importance.sppm.progress = 0;
    o->threads = 2;
}

static inline void temp_dir(char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/test_reduce.XXXXXX");
    assert_non_null(mkdtemp(dir));
}

static inline void remove_tree(const char *dir)
{
    char command[4200];
    assert_true(strncmp(dir, "/tmp/test_reduce.", 17) == 0);
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    assert_int_equal(system(command), 0);
}

static inline char *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot open %s: %s", path, strerror(errno));
    fseek(f, 0, SEEK_END);
    long length = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc((size_t)length + 1);
    assert_int_equal(fread(data, 1, (size_t)length, f), (size_t)length);
    data[length] = 0;
    fclose(f);
    *size = (size_t)length;
    return data;
}

static inline void write_file(const char *path, const char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

static inline int file_exists(const char *dir, const char *name)
{
    char path[4200];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return stat(path, &st) == 0;
}

static inline cJSON *read_report(const char *dir)
{
    char path[4200];
    size_t size;
    snprintf(path, sizeof path, "%s/report.json", dir);
    char *text = read_file(path, &size);
    cJSON *report = cJSON_Parse(text);
    free(text);
    if (!report)
        fail_msg("%s is not JSON", path);
    return report;
}

static inline double number(const cJSON *object, const char *key)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, key);
    if (!cJSON_IsNumber(item))
        fail_msg("report: no number '%s'", key);
    return item->valuedouble;
}

static inline const cJSON *mesh_entry(const cJSON *report, const char *name)
{
    const cJSON *mesh;
    cJSON_ArrayForEach(mesh, cJSON_GetObjectItemCaseSensitive(report, "meshes"))
    {
        const cJSON *n = cJSON_GetObjectItemCaseSensitive(mesh, "name");
        if (cJSON_IsString(n) && strcmp(n->valuestring, name) == 0)
            return mesh;
    }
    fail_msg("report: no mesh '%s'", name);
    return NULL;
}


/* The same mesh in both scenes: same counts, same world-space positions and triangles. */
static inline void assert_same_mesh(const scene_mesh *a, const scene_mesh *b)
{
    assert_int_equal(a->vertex_count, b->vertex_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    assert_memory_equal(a->positions, b->positions, 3 * sizeof(float) * a->vertex_count);
    assert_memory_equal(a->indices, b->indices, 3 * sizeof(uint32_t) * a->triangle_count);
}

static inline int is_decimated(const cJSON *entry)
{
    const cJSON *decimated = cJSON_GetObjectItemCaseSensitive(entry, "decimated");
    assert_true(cJSON_IsBool(decimated));
    return cJSON_IsTrue(decimated);
}

/* The report against the reduced scene: every mesh's vertices_after is what the output scene
 * holds, their sum is vertices_after; returns that sum. */
static inline uint64_t check_report_against_output(const cJSON *report, const scene *in,
                                                   const scene *out)
{
    uint64_t sum = 0;
    assert_int_equal(out->mesh_count, in->mesh_count);
    for (size_t m = 0; m < in->mesh_count; m++) {
        const cJSON *entry = mesh_entry(report, in->meshes[m].name);
        const scene_mesh *reduced = test_find_mesh(out, in->meshes[m].name);
        double before = number(entry, "vertices_before"), after = number(entry, "vertices_after");
        double factor = number(entry, "factor");
        assert_true(factor > 0 && factor <= 1);
        assert_true(after <= before);
        assert_int_equal((uint64_t)after, reduced->vertex_count);
        if (!is_decimated(entry)) {
            assert_true(factor == 1);
            assert_same_mesh(&in->meshes[m], reduced);
        }
        sum += reduced->vertex_count;
    }
    assert_int_equal(sum, out->vertex_count);
    assert_int_equal((uint64_t)number(report, "vertices_after"), sum);
    return sum;
}

/* reduce_run() must succeed. */
static inline void reduce_ok(scene *s, const char *dir, const reduce_options *o)
{
    if (reduce_run(device_test_device(), s, dir, o))
        fail_msg("reduce --method %s: %s", reduce_method_name(o->method), error_message());
}

/* reduce_run() must fail with an input error whose message holds `fragment`. */
static inline void expect_input_error(scene *s, const char *dir, const reduce_options *o,
                                      const char *fragment)
{
    error_clear();
    assert_int_equal(reduce_run(device_test_device(), s, dir, o), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    if (!strstr(error_message(), fragment))
        fail_msg("expected \"%s\" in: %s", fragment, error_message());
}

/* One successful reduction: a fresh output directory, its report and its reduced scene. */
typedef struct reduction {
    char dir[64];
    cJSON *report;
    scene *out;
} reduction;

static inline void reduction_run(reduction *r, scene *s, const reduce_options *o)
{
    temp_dir(r->dir, sizeof r->dir);
    reduce_ok(s, r->dir, o);
    r->report = read_report(r->dir);
    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", r->dir);
    r->out = test_load_scene(path);
}

static inline void reduction_free(reduction *r)
{
    cJSON_Delete(r->report);
    scene_free(r->out);
    remove_tree(r->dir);
}

static inline void assert_method(const cJSON *report, const char *name)
{
    const cJSON *method = cJSON_GetObjectItemCaseSensitive(report, "method");
    assert_true(cJSON_IsString(method) && strcmp(method->valuestring, name) == 0);
}

#endif
