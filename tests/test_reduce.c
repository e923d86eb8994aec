/* test_reduce.c — `idmr reduce` end to end through reduce_run() (host/reduce.c): importance
 * pass, budget, decimation, reduced scene, report.
 *
 *   importance   the shipped Cornell box to D = 0.1: the files, the report's keys and figures,
 *                the reduced scene loads and holds the reported vertex count, ~10 % of the
 *                input; the emitter and the small meshes are untouched; the inputs unchanged
 *   outdir       an existing non-empty OUTDIR needs force; the scene's own directory never
 *   quadric      every decimated mesh gets the same factor (up to rounding); no importance pass
 *   compensation vertices a mesh cannot give up are taken from the others, meeting the target
 *   file names   two mesh names that make the same PLY name get distinct files
 *   keep         keeping the knot leaves nothing to decimate; an unknown name is an error
 *   target       D outside (0, 1] is an error; D = 1 decimates nothing
 *
 * One OpenCL device for the file (device_open(-1)); the importance pass is kept small (3
 * iterations of 20,000 photons). Output goes to fresh mkdtemp directories under /tmp; scenes
 * that the tests must be able to damage are copies. Runs from the repository root. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "core/error.h"
#include "io/mitsuba.h"
#include "reduce/reduce.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif
#define CORNELL_DIR IDMR_ROOT "/data/cornell"
#define CORNELL CORNELL_DIR "/scene.xml"
#define KNOT CORNELL_DIR "/meshes/knot.ply"

static device dev;

static int group_setup(void **state)
{
    if (device_open(&dev, -1)) {
        fprintf(stderr, "test_reduce: %s\n", error_message());
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    device_close(&dev);
    return 0;
}

/* ---- helpers ---- */

static void small_options(reduce_options *o)
{
    reduce_options_default(o);
    o->target = 0.1;
    o->importance.sppm.iterations = 3;
    o->importance.sppm.photons = 20000;
    o->importance.sppm.progress = 0;
    o->threads = 2;
}

static void temp_dir(char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/test_reduce.XXXXXX");
    assert_non_null(mkdtemp(dir));
}

static void remove_tree(const char *dir)
{
    char command[4200];
    assert_true(strncmp(dir, "/tmp/test_reduce.", 17) == 0);
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    assert_int_equal(system(command), 0);
}

static char *read_file(const char *path, size_t *size)
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

static void write_file(const char *path, const char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

static int file_exists(const char *dir, const char *name)
{
    char path[4200];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return stat(path, &st) == 0;
}

static cJSON *read_report(const char *dir)
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

static double number(const cJSON *object, const char *key)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, key);
    if (!cJSON_IsNumber(item))
        fail_msg("report: no number '%s'", key);
    return item->valuedouble;
}

static const cJSON *mesh_entry(const cJSON *report, const char *name)
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

static scene *load(const char *path)
{
    scene *s = mitsuba_load(path);
    if (!s)
        fail_msg("loading %s: %s", path, error_message());
    return s;
}

static const scene_mesh *find_mesh(const scene *s, const char *name)
{
    for (size_t m = 0; m < s->mesh_count; m++)
        if (strcmp(s->meshes[m].name, name) == 0)
            return &s->meshes[m];
    fail_msg("scene %s: no mesh '%s'", s->file, name);
    return NULL;
}

/* The same mesh in both scenes: same counts, same world-space positions and triangles. */
static void assert_same_mesh(const scene_mesh *a, const scene_mesh *b)
{
    assert_int_equal(a->vertex_count, b->vertex_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    assert_memory_equal(a->positions, b->positions, 3 * sizeof(float) * a->vertex_count);
    assert_memory_equal(a->indices, b->indices, 3 * sizeof(uint32_t) * a->triangle_count);
}

/* The report against the reduced scene: every mesh's vertices_after is what the output scene
 * holds, their sum is vertices_after; returns that sum. */
static uint64_t check_report_against_output(const cJSON *report, const scene *in, const scene *out)
{
    uint64_t sum = 0;
    assert_int_equal(out->mesh_count, in->mesh_count);
    for (size_t m = 0; m < in->mesh_count; m++) {
        const cJSON *entry = mesh_entry(report, in->meshes[m].name);
        const scene_mesh *reduced = find_mesh(out, in->meshes[m].name);
        double before = number(entry, "vertices_before"), after = number(entry, "vertices_after");
        double factor = number(entry, "factor");
        assert_true(factor > 0 && factor <= 1);
        assert_true(after <= before);
        assert_int_equal((uint64_t)after, reduced->vertex_count);
        const cJSON *decimated = cJSON_GetObjectItemCaseSensitive(entry, "decimated");
        assert_true(cJSON_IsBool(decimated));
        if (!cJSON_IsTrue(decimated)) {
            assert_true(factor == 1);
            assert_same_mesh(&in->meshes[m], reduced);
        }
        sum += reduced->vertex_count;
    }
    assert_int_equal(sum, out->vertex_count);
    assert_int_equal((uint64_t)number(report, "vertices_after"), sum);
    return sum;
}

typedef struct file_state {
    char *data;
    size_t size;
    struct stat st;
} file_state;

static void remember(const char *path, file_state *f)
{
    f->data = read_file(path, &f->size);
    assert_int_equal(stat(path, &f->st), 0);
}

static void assert_unchanged(const char *path, file_state *f)
{
    size_t size;
    char *now = read_file(path, &size);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(size, f->size);
    assert_memory_equal(now, f->data, size);
    assert_true(st.st_mtim.tv_sec == f->st.st_mtim.tv_sec &&
                st.st_mtim.tv_nsec == f->st.st_mtim.tv_nsec);
    free(now);
    free(f->data);
}

/* ---- 1. the shipped Cornell box by importance ---- */

static void test_importance_cornell(void **state)
{
    file_state xml, knot;
    remember(CORNELL, &xml);
    remember(KNOT, &knot);
    char dir[64];
    temp_dir(dir, sizeof dir);
    scene *s = load(CORNELL);
    reduce_options o;
    small_options(&o);
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce: %s", error_message());

    assert_true(file_exists(dir, "scene.xml"));
    assert_true(file_exists(dir, "meshes/knot.ply"));
    assert_true(file_exists(dir, "report.json"));
    assert_true(file_exists(dir, "importance.png"));
    /* Only the knot is decimated (the box's meshes have at most 8 vertices). */
    assert_false(file_exists(dir, "meshes/light.ply"));
    assert_false(file_exists(dir, "meshes/block.ply"));

    cJSON *report = read_report(dir);
    const cJSON *method = cJSON_GetObjectItemCaseSensitive(report, "method");
    assert_true(cJSON_IsString(method) && strcmp(method->valuestring, "importance") == 0);
    assert_true(number(report, "target") == 0.1);
    uint64_t before = (uint64_t)number(report, "vertices_before");
    uint64_t after = (uint64_t)number(report, "vertices_after");
    uint64_t requested = (uint64_t)number(report, "vertices_requested");
    double missed = number(report, "vertices_missed");
    const cJSON *seconds = cJSON_GetObjectItemCaseSensitive(report, "seconds");
    assert_true(number(seconds, "importance") > 0);
    assert_true(number(seconds, "budget") >= 0);
    assert_true(number(seconds, "decimation") > 0);
    assert_true(number(seconds, "write") > 0);
    assert_int_equal(before, s->vertex_count); /* the Cornell meshes are manifold: no copies */
    assert_int_equal(requested, (uint64_t)llround(0.1 * (double)before));
    assert_true(missed == (double)after - (double)requested);

    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    scene *out = load(path);
    uint64_t total = check_report_against_output(report, s, out);
    print_message("  cornell: %llu -> %llu vertices (requested %llu, missed %+g); knot factor %.4f, "
                  "%g s importance, %g s decimation\n",
                  (unsigned long long)before, (unsigned long long)total,
                  (unsigned long long)requested, missed,
                  number(mesh_entry(report, "knot"), "factor"), number(seconds, "importance"),
                  number(seconds, "decimation"));
    double allowed = fmax(0.01 * (double)requested, fabs(missed));
    assert_true(fabs((double)total - (double)requested) <= allowed);
    assert_true(fabs((double)total - (double)requested) <= 0.01 * (double)requested);
    const cJSON *knot_entry = mesh_entry(report, "knot");
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(knot_entry, "decimated")));
    assert_true(number(knot_entry, "factor") < 0.2);
    /* The emitter is untouched and pinned. */
    assert_same_mesh(find_mesh(s, "light"), find_mesh(out, "light"));
    assert_true(cJSON_IsTrue(
        cJSON_GetObjectItemCaseSensitive(mesh_entry(report, "light"), "pinned")));
    /* The reduced knot keeps its place: its bounding box is within the input's. */
    const scene_mesh *k0 = find_mesh(s, "knot"), *k1 = find_mesh(out, "knot");
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < k0->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fminf(lo[a], k0->positions[3 * v + a]);
            hi[a] = fmaxf(hi[a], k0->positions[3 * v + a]);
        }
    for (uint32_t v = 0; v < k1->vertex_count; v++)
        for (int a = 0; a < 3; a++)
            assert_true(k1->positions[3 * v + a] >= lo[a] - 1e-5f &&
                        k1->positions[3 * v + a] <= hi[a] + 1e-5f);
    cJSON_Delete(report);
    scene_free(out);
    scene_free(s);
    assert_unchanged(CORNELL, &xml);
    assert_unchanged(KNOT, &knot);
    remove_tree(dir);
}

/* ---- 2. the output directory ---- */

/* A copy of the Cornell box in a fresh directory (so a failure cannot write into data/). */
static void copy_cornell(char *dir, size_t size)
{
    temp_dir(dir, size);
    char path[4200];
    size_t length;
    char *xml = read_file(CORNELL, &length);
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    write_file(path, xml, length);
    free(xml);
    snprintf(path, sizeof path, "%s/meshes", dir);
    assert_int_equal(mkdir(path, 0755), 0);
    char *ply = read_file(KNOT, &length);
    snprintf(path, sizeof path, "%s/meshes/knot.ply", dir);
    write_file(path, ply, length);
    free(ply);
}

static void test_outdir(void **state)
{
    char dir[64], copy[64], path[4200];
    temp_dir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/something.txt", dir);
    write_file(path, "keep me\n", 8);
    scene *s = load(CORNELL);
    reduce_options o;
    small_options(&o);
    o.method = DECIMATE_QUADRIC; /* the directory checks come first; no importance pass needed */

    error_clear();
    assert_int_equal(reduce_run(&dev, s, dir, &o), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "--force"));
    assert_false(file_exists(dir, "scene.xml"));
    assert_false(file_exists(dir, "meshes"));

    o.force = 1;
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce --force: %s", error_message());
    assert_true(file_exists(dir, "scene.xml"));
    assert_true(file_exists(dir, "meshes/knot.ply"));
    assert_true(file_exists(dir, "something.txt"));
    scene_free(s);
    remove_tree(dir);

    /* The scene's own directory, however it is spelled, even with force. */
    copy_cornell(copy, sizeof copy);
    snprintf(path, sizeof path, "%s/scene.xml", copy);
    s = load(path);
    file_state xml, knot;
    char xml_path[4200], knot_path[4200];
    snprintf(xml_path, sizeof xml_path, "%s/scene.xml", copy);
    snprintf(knot_path, sizeof knot_path, "%s/meshes/knot.ply", copy);
    remember(xml_path, &xml);
    remember(knot_path, &knot);
    const char *spellings[] = {"%s", "%s/", "%s/meshes/..", "%s/./."};
    for (size_t i = 0; i < sizeof spellings / sizeof *spellings; i++) {
        char outdir[4200];
        snprintf(outdir, sizeof outdir, spellings[i], copy);
        o.force = 1;
        error_clear();
        assert_int_equal(reduce_run(&dev, s, outdir, &o), -1);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
        assert_non_null(strstr(error_message(), "scene's own directory"));
        o.force = 0;
        error_clear();
        assert_int_equal(reduce_run(&dev, s, outdir, &o), -1);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    }
    assert_false(file_exists(copy, "report.json"));
    assert_unchanged(xml_path, &xml);
    assert_unchanged(knot_path, &knot);
    scene_free(s);
    remove_tree(copy);
}

/* ---- 3. quadric: one factor for all ---- */

/* DIR/scene.xml: the shipped Cornell box, its knot by absolute path, plus `extra` shapes. */
static void write_cornell_plus(const char *dir, const char *extra, char *scene_path, size_t size)
{
    size_t length;
    char *xml = read_file(CORNELL, &length);
    char *end = strstr(xml, "</scene>");
    assert_non_null(end);
    char knot[4096];
    assert_non_null(realpath(KNOT, knot));
    *end = 0;
    const char *relative = "value=\"meshes/knot.ply\"";
    char *first = strstr(xml, relative);
    assert_non_null(first);
    *first = 0;
    snprintf(scene_path, size, "%s/scene.xml", dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f, "%svalue=\"%s\"%s%s</scene>\n", xml, knot, first + strlen(relative), extra);
    assert_int_equal(fclose(f), 0);
    free(xml);
}

/* The Cornell box plus a second knot (moved) and a sphere (994 vertices): three meshes to
 * decimate. The file names the knot by its absolute path (it is written elsewhere). */
static void write_three_mesh_scene(const char *dir, char *scene_path, size_t size)
{
    char knot[4096], extra[8192];
    assert_non_null(realpath(KNOT, knot));
    snprintf(extra, sizeof extra,
             "    <shape type=\"ply\" id=\"knot2\">\n"
             "        <string name=\"filename\" value=\"%s\"/>\n"
             "        <transform name=\"to_world\">\n"
             "            <scale value=\"0.5\"/>\n"
             "            <translate x=\"-0.4\" y=\"0.4\" z=\"0.2\"/>\n"
             "        </transform>\n"
             "        <ref id=\"knot\"/>\n"
             "    </shape>\n"
             "    <shape type=\"sphere\" id=\"ball\">\n"
             "        <point name=\"center\" x=\"0.5\" y=\"0.5\" z=\"-0.3\"/>\n"
             "        <float name=\"radius\" value=\"0.2\"/>\n"
             "        <ref id=\"white\"/>\n"
             "    </shape>\n",
             knot);
    write_cornell_plus(dir, extra, scene_path, size);
}

static void test_quadric(void **state)
{
    char in_dir[64], dir[64], scene_path[4200];
    temp_dir(in_dir, sizeof in_dir);
    temp_dir(dir, sizeof dir);
    write_three_mesh_scene(in_dir, scene_path, sizeof scene_path);
    scene *s = load(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = DECIMATE_QUADRIC;
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce --method quadric: %s", error_message());
    assert_false(file_exists(dir, "importance.png"));
    assert_false(file_exists(dir, "importance"));
    assert_true(file_exists(dir, "meshes/knot.ply"));
    assert_true(file_exists(dir, "meshes/knot2.ply"));
    assert_true(file_exists(dir, "meshes/ball.ply"));

    cJSON *report = read_report(dir);
    const cJSON *method = cJSON_GetObjectItemCaseSensitive(report, "method");
    assert_true(cJSON_IsString(method) && strcmp(method->valuestring, "quadric") == 0);
    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    scene *out = load(path);
    uint64_t total = check_report_against_output(report, s, out);
    uint64_t requested = (uint64_t)number(report, "vertices_requested");
    /* Equal factors: (V_D - fixed) / free vertices, each within a vertex of it. */
    double fixed = 0, free_vertices = 0;
    const char *decimated[] = {"knot", "knot2", "ball"};
    for (size_t m = 0; m < s->mesh_count; m++) {
        int is_free = 0;
        for (int k = 0; k < 3; k++)
            is_free |= strcmp(s->meshes[m].name, decimated[k]) == 0;
        if (is_free)
            free_vertices += s->meshes[m].vertex_count;
        else
            fixed += s->meshes[m].vertex_count;
    }
    double uniform = ((double)requested - fixed) / free_vertices;
    for (int k = 0; k < 3; k++) {
        const cJSON *entry = mesh_entry(report, decimated[k]);
        double factor = number(entry, "factor"), before = number(entry, "vertices_before");
        double after = number(entry, "vertices_after");
        print_message("  quadric %s: factor %.5f (uniform %.5f), %g -> %g vertices\n",
                      decimated[k], factor, uniform, before, after);
        assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(entry, "decimated")));
        assert_true(fabs(factor * before - uniform * before) <= 1.0);
        assert_true(fabs(after - factor * before) <= fmax(1.0, 0.01 * factor * before));
    }
    assert_true(fabs((double)total - (double)requested) <= 0.01 * (double)requested);
    cJSON_Delete(report);
    scene_free(out);
    scene_free(s);
    remove_tree(dir);
    remove_tree(in_dir);
}

/* A mesh that cannot give up any vertex (200 separate triangles: no collapse is legal) beside
 * the knot, reduced with uniform factors: the confetti keeps all 600 vertices, and the
 * compensation rounds take them from the knot, so the total still meets the target exactly. */
static void test_compensation(void **state)
{
    char in_dir[64], dir[64], scene_path[4200], confetti[4200];
    temp_dir(in_dir, sizeof in_dir);
    temp_dir(dir, sizeof dir);
    snprintf(confetti, sizeof confetti, "%s/confetti.obj", in_dir);
    FILE *f = fopen(confetti, "w");
    assert_non_null(f);
    for (int t = 0; t < 200; t++) {
        float x = -0.9f + 0.09f * (float)(t % 20), y = -0.9f + 0.09f * (float)(t / 20);
        fprintf(f, "v %g %g 0.5\nv %g %g 0.5\nv %g %g 0.5\n", x, y, x + 0.05f, y, x, y + 0.05f);
    }
    for (int t = 0; t < 200; t++)
        fprintf(f, "f %d %d %d\n", 3 * t + 1, 3 * t + 2, 3 * t + 3);
    assert_int_equal(fclose(f), 0);
    write_cornell_plus(in_dir,
                       "    <shape type=\"obj\" id=\"confetti\">\n"
                       "        <string name=\"filename\" value=\"confetti.obj\"/>\n"
                       "        <ref id=\"white\"/>\n"
                       "    </shape>\n",
                       scene_path, sizeof scene_path);

    scene *s = load(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = DECIMATE_QUADRIC;
    o.target = 0.2;
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce: %s", error_message());
    cJSON *report = read_report(dir);
    const cJSON *confetti_entry = mesh_entry(report, "confetti");
    print_message("  confetti %g -> %g vertices; total %g for %g requested, %g compensation "
                  "rounds\n",
                  number(confetti_entry, "vertices_before"), number(confetti_entry, "vertices_after"),
                  number(report, "vertices_after"), number(report, "vertices_requested"),
                  number(report, "compensation_rounds"));
    assert_true(number(confetti_entry, "vertices_after") == 600);
    assert_true(number(report, "compensation_rounds") >= 1);
    assert_true(number(report, "vertices_after") == number(report, "vertices_requested"));
    cJSON_Delete(report);
    scene_free(s);
    remove_tree(in_dir);
    remove_tree(dir);
}

/* Two meshes whose names make the same file name ("knot x" and "knot_x") get two files. */
static void test_file_name_collision(void **state)
{
    char in_dir[64], dir[64], scene_path[4200], knot[4096];
    temp_dir(in_dir, sizeof in_dir);
    temp_dir(dir, sizeof dir);
    assert_non_null(realpath(KNOT, knot));
    snprintf(scene_path, sizeof scene_path, "%s/scene.xml", in_dir);
    FILE *f = fopen(scene_path, "w");
    assert_non_null(f);
    fprintf(f,
            "<scene version=\"3.0.0\">\n"
            "  <sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0, 0, 4\" "
            "target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor>\n"
            "  <shape type=\"ply\" id=\"knot x\"><string name=\"filename\" value=\"%s\"/></shape>\n"
            "  <shape type=\"ply\" id=\"knot_x\"><string name=\"filename\" value=\"%s\"/>\n"
            "    <transform name=\"to_world\"><translate x=\"2\"/></transform></shape>\n"
            "</scene>\n",
            knot, knot);
    assert_int_equal(fclose(f), 0);
    scene *s = load(scene_path);
    reduce_options o;
    small_options(&o);
    o.method = DECIMATE_QUADRIC; /* no light needed */
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce: %s", error_message());
    assert_true(file_exists(dir, "meshes/knot_x.ply"));
    assert_true(file_exists(dir, "meshes/knot_x.2.ply"));
    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    scene *out = load(path);
    assert_int_equal(out->mesh_count, 2);
    /* Each kept its own geometry: the second is the one moved by x = 2. */
    assert_true(out->meshes[1].positions[0] > out->meshes[0].positions[0] + 1.0f);
    scene_free(out);
    scene_free(s);
    remove_tree(in_dir);
    remove_tree(dir);
}

/* ---- 4. keep ---- */

static void test_keep(void **state)
{
    char dir[64];
    temp_dir(dir, sizeof dir);
    scene *s = load(CORNELL);
    reduce_options o;
    small_options(&o);
    const char *keep[] = {"knot"};
    o.keep = keep;
    o.keep_count = 1;
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce --keep knot: %s", error_message());
    cJSON *report = read_report(dir);
    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    scene *out = load(path);
    uint64_t total = check_report_against_output(report, s, out);
    assert_int_equal(total, s->vertex_count);
    assert_int_equal((uint64_t)number(report, "vertices_before"), s->vertex_count);
    assert_false(file_exists(dir, "meshes/knot.ply"));
    const cJSON *knot = mesh_entry(report, "knot");
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(knot, "pinned")));
    assert_true(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(knot, "decimated")));
    for (size_t m = 0; m < s->mesh_count; m++)
        assert_same_mesh(&s->meshes[m], find_mesh(out, s->meshes[m].name));
    cJSON_Delete(report);
    scene_free(out);
    remove_tree(dir);

    /* A name the scene does not have: an error naming it, nothing written. */
    temp_dir(dir, sizeof dir);
    const char *unknown[] = {"knot", "no_such_mesh"};
    o.keep = unknown;
    o.keep_count = 2;
    error_clear();
    assert_int_equal(reduce_run(&dev, s, dir, &o), -1);
    assert_int_equal(error_code(), IDMR_EXIT_INPUT);
    assert_non_null(strstr(error_message(), "no_such_mesh"));
    assert_false(file_exists(dir, "scene.xml"));
    assert_false(file_exists(dir, "meshes"));
    scene_free(s);
    remove_tree(dir);
}

/* ---- 5. target ---- */

static void test_target(void **state)
{
    char dir[64];
    temp_dir(dir, sizeof dir);
    scene *s = load(CORNELL);
    reduce_options o;
    small_options(&o);
    const double bad[] = {0, -0.1, 1.0000001, 2, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        o.target = bad[i];
        error_clear();
        assert_int_equal(reduce_run(&dev, s, dir, &o), -1);
        assert_int_equal(error_code(), IDMR_EXIT_INPUT);
        assert_non_null(strstr(error_message(), "--target"));
        assert_false(file_exists(dir, "scene.xml"));
    }
    /* D = 1 keeps everything (quadric: no importance pass needed). */
    o.target = 1;
    o.method = DECIMATE_QUADRIC;
    if (reduce_run(&dev, s, dir, &o))
        fail_msg("reduce --target 1: %s", error_message());
    cJSON *report = read_report(dir);
    char path[4200];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    scene *out = load(path);
    assert_int_equal(check_report_against_output(report, s, out), s->vertex_count);
    assert_false(file_exists(dir, "meshes/knot.ply"));
    cJSON_Delete(report);
    scene_free(out);
    scene_free(s);
    remove_tree(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_importance_cornell),
        cmocka_unit_test(test_outdir),
        cmocka_unit_test(test_quadric),
        cmocka_unit_test(test_compensation),
        cmocka_unit_test(test_file_name_collision),
        cmocka_unit_test(test_keep),
        cmocka_unit_test(test_target),
    };
    return cmocka_run_group_tests_name("reduce", tests, group_setup, group_teardown);
}
