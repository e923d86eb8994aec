/* reduce.c — the reduction pipeline behind `idmr reduce` (see reduce.h). */
#include "reduce/reduce.h"

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "reduce/budget.h"
#include "device/bvh.h"
#include "core/error.h"
#include "passes/importance_outputs.h"
#include "io/mesh_io.h"
#include "io/mitsuba_write.h"
#include "core/files.h"
#include "core/json.h"
#include "core/progress.h"

void reduce_options_default(reduce_options *o)
{
    memset(o, 0, sizeof *o);
    importance_options_default(&o->importance);
    o->target = 0.1;
    o->method = DECIMATE_IMPORTANCE;
    o->min_vertices = 16;
    o->max_normal_angle = 60.0;
}

/* OUTDIR: created if missing; an existing non-empty one needs force; never the scene's own
 * directory (inputs are never written). */
static int prepare_outdir(const scene *s, const char *outdir, int force)
{
    char scene_dir[PATH_MAX], out[PATH_MAX];
    DIR *dir = opendir(outdir);
    if (dir) {
        struct dirent *entry;
        int empty = 1;
        while ((entry = readdir(dir)))
            if (strcmp(entry->d_name, ".") && strcmp(entry->d_name, ".."))
                empty = 0;
        closedir(dir);
        if (!empty && !force)
            return error_set(IDMR_EXIT_INPUT,
                             "output directory '%s' exists and is not empty (use --force to write "
                             "into it)",
                             outdir);
    }
    if (files_make_directory(outdir))
        return -1;
    if (realpath(s->dir, scene_dir) && realpath(outdir, out) && strcmp(scene_dir, out) == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "output directory '%s' is the scene's own directory: choose another "
                         "(inputs are never overwritten)",
                         outdir);
    char meshes[PATH_MAX];
    snprintf(meshes, sizeof meshes, "%s/meshes", outdir);
    return files_make_directory(meshes);
}

static int is_kept(const reduce_options *o, const char *name)
{
    for (size_t i = 0; i < o->keep_count; i++)
        if (strcmp(o->keep[i], name) == 0)
            return 1;
    return 0;
}

/* Emitters and meshes named with --keep are never decimated. */
static int is_pinned(const reduce_options *o, const scene_mesh *mesh)
{
    return mesh->light >= 0 || is_kept(o, mesh->name);
}

typedef struct reduce_state {
    size_t count;
    double **vertex_importance;
    decimate_input *input;
    decimate_output *output;
    char **ply; /* relative to outdir, for decimated meshes */
    budget_plan plan;
    unsigned int compensation_rounds;
    double seconds_importance, seconds_budget, seconds_decimation, seconds_write;
} reduce_state;

static void state_free(reduce_state *st)
{
    for (size_t m = 0; m < st->count; m++) {
        free(st->vertex_importance ? st->vertex_importance[m] : NULL);
        if (st->output)
            decimate_output_free(&st->output[m]);
        free(st->ply ? st->ply[m] : NULL);
    }
    free(st->vertex_importance);
    free(st->input);
    free(st->output);
    free(st->ply);
    budget_plan_free(&st->plan);
}

const char *reduce_method_name(const reduce_options *o)
{
    if (o->method == DECIMATE_QUADRIC)
        return "quadric";
    return o->quadric_collapses ? "importance-quadric" : "importance";
}

static cJSON *reduce_report(const scene *s, const device *d, const reduce_options *o,
                            const importance_result *r, const reduce_state *st, uint64_t after)
{
    cJSON *root = o->method == DECIMATE_IMPORTANCE ? importance_report_json(s, d, &o->importance, r)
                                                   : cJSON_CreateObject();
    if (o->method != DECIMATE_IMPORTANCE) {
        cJSON_AddStringToObject(root, "scene", s->file);
        cJSON_AddItemToObject(root, "meshes", cJSON_CreateArray());
        cJSON_AddItemToObject(root, "seconds", cJSON_CreateObject());
    }
    cJSON_AddNumberToObject(root, "target", o->target);
    cJSON_AddStringToObject(root, "method", reduce_method_name(o));
    cJSON_AddNumberToObject(root, "max_normal_angle", o->max_normal_angle);
    cJSON_AddNumberToObject(root, "min_vertices", (double)o->min_vertices);
    cJSON_AddNumberToObject(root, "vertices_before", (double)st->plan.total_before);
    cJSON_AddNumberToObject(root, "vertices_requested", (double)st->plan.total_requested);
    cJSON_AddNumberToObject(root, "vertices_planned", (double)st->plan.total_planned);
    cJSON_AddNumberToObject(root, "vertices_after", (double)after);
    cJSON_AddNumberToObject(root, "vertices_missed", (double)after - (double)st->plan.total_requested);
    cJSON_AddBoolToObject(root, "uniform_fallback", st->plan.uniform_fallback);
    cJSON_AddNumberToObject(root, "compensation_rounds", st->compensation_rounds);
    cJSON *seconds = cJSON_GetObjectItem(root, "seconds");
    cJSON_AddNumberToObject(seconds, "importance", st->seconds_importance);
    cJSON_AddNumberToObject(seconds, "budget", st->seconds_budget);
    cJSON_AddNumberToObject(seconds, "decimation", st->seconds_decimation);
    cJSON_AddNumberToObject(seconds, "write", st->seconds_write);
    cJSON *meshes = cJSON_GetObjectItem(root, "meshes");
    for (size_t m = 0; m < s->mesh_count; m++) {
        cJSON *mesh = cJSON_GetArrayItem(meshes, (int)m);
        if (!mesh) {
            mesh = cJSON_CreateObject();
            cJSON_AddStringToObject(mesh, "name", s->meshes[m].name);
            cJSON_AddNumberToObject(mesh, "vertices", s->meshes[m].vertex_count);
            cJSON_AddNumberToObject(mesh, "triangles", s->meshes[m].triangle_count);
            cJSON_AddItemToArray(meshes, mesh);
        }
        int decimated = st->plan.decimate[m];
        cJSON_AddNumberToObject(mesh, "factor", st->plan.factor[m]);
        cJSON_AddBoolToObject(mesh, "decimated", decimated);
        cJSON_AddNumberToObject(mesh, "vertices_before", s->meshes[m].vertex_count);
        cJSON_AddNumberToObject(mesh, "vertices_target", (double)st->plan.target[m]);
        cJSON_AddNumberToObject(mesh, "vertices_after", decimated ? st->output[m].mesh.vertex_count
                                                                  : s->meshes[m].vertex_count);
        cJSON_AddNumberToObject(mesh, "triangles_after",
                                decimated ? st->output[m].mesh.triangle_count
                                          : s->meshes[m].triangle_count);
        if (decimated) {
            cJSON_AddNumberToObject(mesh, "vertices_welded", st->output[m].vertices_welded);
            cJSON_AddNumberToObject(mesh, "vertices_uncollapsible",
                                    st->output[m].vertices_uncollapsible);
            cJSON_AddNumberToObject(mesh, "faces_patched", st->output[m].faces_patched);
            cJSON_AddNumberToObject(mesh, "faces_loose", st->output[m].faces_loose);
            cJSON_AddStringToObject(mesh, "file", st->ply[m]);
        }
        cJSON_AddBoolToObject(mesh, "pinned", is_pinned(o, &s->meshes[m]));
    }
    return root;
}

#define COMPENSATION_ROUNDS 3

/* Whether an earlier mesh's PLY has the name mesh m's would get. */
static int ply_name_taken(const reduce_state *st, size_t m)
{
    for (size_t k = 0; k < m; k++)
        if (st->ply[k] && strcmp(st->ply[k], st->ply[m]) == 0)
            return 1;
    return 0;
}

/* Decimates the meshes flagged in `redo` to st->plan.target, replacing earlier outputs. */
static int decimate_selected(reduce_state *st, decimate_method method, unsigned int threads,
                             const unsigned char *redo)
{
    decimate_input *jobs = xcalloc(st->count + 1, sizeof *jobs);
    decimate_output *results = xcalloc(st->count + 1, sizeof *results);
    int *job_status = xcalloc(st->count + 1, sizeof *job_status);
    char(*job_messages)[512] = xcalloc(st->count + 1, sizeof *job_messages);
    size_t *job_mesh = xcalloc(st->count + 1, sizeof *job_mesh);
    size_t n = 0;
    for (size_t m = 0; m < st->count; m++)
        if (redo[m]) {
            jobs[n] = st->input[m];
            jobs[n].target_vertices = st->plan.target[m];
            job_mesh[n++] = m;
        }
    decimate_many(jobs, results, job_status, job_messages, n, method, threads);
    int status = 0;
    for (size_t j = 0; j < n; j++) {
        decimate_output_free(&st->output[job_mesh[j]]);
        st->output[job_mesh[j]] = results[j];
        if (job_status[j] && !status)
            status = error_set(IDMR_EXIT_FAILURE, "%s", job_messages[j]);
    }
    free(jobs);
    free(results);
    free(job_status);
    free(job_messages);
    free(job_mesh);
    return status;
}

/* Lowers the targets of the decimated meshes that met theirs by `excess` vertices in all, in
 * proportion to their room above the floor, and flags them in `redo`. False if none has room. */
static int compensate(reduce_state *st, const scene *s, uint64_t excess,
                      uint64_t floor_vertices, unsigned char *redo)
{
    uint64_t room = 0;
    for (size_t m = 0; m < st->count; m++) {
        redo[m] = 0;
        uint64_t target = st->plan.target[m];
        if (st->plan.decimate[m] && st->output[m].mesh.vertex_count <= target &&
            target > floor_vertices)
            room += target - floor_vertices;
    }
    if (room == 0)
        return 0;
    uint64_t taken = 0;
    for (size_t m = 0; m < st->count && taken < excess; m++) {
        uint64_t target = st->plan.target[m];
        if (!st->plan.decimate[m] || st->output[m].mesh.vertex_count > target ||
            target <= floor_vertices)
            continue;
        uint64_t share = (uint64_t)ceil((double)excess * (target - floor_vertices) / room);
        if (share > target - floor_vertices)
            share = target - floor_vertices;
        if (share > excess - taken)
            share = excess - taken;
        if (share == 0)
            continue;
        st->plan.target[m] = target - share;
        st->plan.factor[m] = (double)st->plan.target[m] / s->meshes[m].vertex_count;
        taken += share;
        redo[m] = 1;
    }
    return taken > 0;
}

int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o)
{
    if (!(o->target > 0 && o->target <= 1))
        return error_set(IDMR_EXIT_INPUT, "--target must be in (0, 1], not %g", o->target);
    for (size_t k = 0; k < o->keep_count; k++) {
        size_t m = 0;
        while (m < s->mesh_count && strcmp(s->meshes[m].name, o->keep[k]))
            m++;
        if (m == s->mesh_count)
            return error_set(IDMR_EXIT_INPUT, "--keep %s: the scene has no mesh of that name "
                                              "(see `idmr info`)", o->keep[k]);
    }
    if (prepare_outdir(s, outdir, o->force))
        return -1;

    reduce_state st;
    memset(&st, 0, sizeof st);
    st.count = s->mesh_count;
    importance_result r;
    memset(&r, 0, sizeof r);
    int status = 0;

    /* Importance. */
    double start = monotonic_seconds();
    bvh b;
    memset(&b, 0, sizeof b);
    if (o->method == DECIMATE_IMPORTANCE) {
        status = bvh_build(s, &b) || importance_run(d, s, &b, &o->importance, &r);
        if (!status) {
            st.vertex_importance = xcalloc(st.count + 1, sizeof *st.vertex_importance);
            for (size_t m = 0; m < st.count; m++) {
                st.vertex_importance[m] =
                    xmalloc((s->meshes[m].vertex_count + 1) * sizeof **st.vertex_importance);
                importance_mesh_vertices(&r, s, m, o->importance.gamma, st.vertex_importance[m]);
            }
        }
    }
    st.seconds_importance = monotonic_seconds() - start;

    /* Budget. */
    start = monotonic_seconds();
    st.input = xcalloc(st.count + 1, sizeof *st.input);
    st.output = xcalloc(st.count + 1, sizeof *st.output);
    st.ply = xcalloc(st.count + 1, sizeof *st.ply);
    budget_mesh *budget = xcalloc(st.count + 1, sizeof *budget);
    for (size_t m = 0; m < st.count && !status; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        decimate_input *in = &st.input[m];
        in->name = mesh->name;
        in->positions = mesh->positions;
        in->vertex_count = mesh->vertex_count;
        in->indices = mesh->indices;
        in->triangle_count = mesh->triangle_count;
        in->vertex_importance = st.vertex_importance ? st.vertex_importance[m] : NULL;
        in->max_normal_angle = o->max_normal_angle;
        budget[m].name = mesh->name;
        /* Counted as the scene holds them, so the totals match what `idmr info` says of the
         * input and of the reduced scene. */
        budget[m].vertices = mesh->vertex_count;
        budget[m].pinned = is_pinned(o, mesh);
        if (o->method == DECIMATE_IMPORTANCE) {
            double camera, light;
            importance_mesh_sums(&r, s, m, o->importance.gamma, &budget[m].importance, &camera,
                                 &light);
        } else {
            budget[m].importance = 1.0; /* equal factors: the uniform D of the baseline */
        }
    }
    if (!status)
        status = budget_distribute(budget, st.count, o->target, o->min_vertices, &st.plan);
    free(budget);
    st.seconds_budget = monotonic_seconds() - start;

    /* Decimation of the meshes the plan decimates, in parallel, largest first; then up to
     * COMPENSATION_ROUNDS rounds that take what meshes could not give up (too few legal
     * collapses) from the meshes that met their targets and have room above the floor. */
    start = monotonic_seconds();
    uint64_t after = 0;
    unsigned int threads = o->threads ? o->threads : (unsigned int)sysconf(_SC_NPROCESSORS_ONLN);
    unsigned char *redo = xcalloc(st.count + 1, 1);
    for (size_t m = 0; m < st.count && !status; m++) /* no plan if an earlier stage failed */
        redo[m] = (unsigned char)st.plan.decimate[m];
    progress bar;
    progress_begin(&bar, "decimation", COMPENSATION_ROUNDS + 1, o->importance.sppm.progress);
    for (unsigned int round = 0; !status && round <= COMPENSATION_ROUNDS; round++) {
        status = decimate_selected(&st, o->method == DECIMATE_IMPORTANCE && !o->quadric_collapses
                                            ? DECIMATE_IMPORTANCE
                                            : DECIMATE_QUADRIC,
                                   threads, redo);
        progress_update(&bar, round + 1, NULL);
        after = 0;
        for (size_t m = 0; m < st.count; m++)
            after += st.plan.decimate[m] ? st.output[m].mesh.vertex_count : s->meshes[m].vertex_count;
        if (status || after <= st.plan.total_requested || round == COMPENSATION_ROUNDS ||
            !compensate(&st, s, after - st.plan.total_requested, o->min_vertices, redo))
            break;
        st.compensation_rounds = round + 1;
    }
    progress_end(&bar);
    free(redo);
    st.seconds_decimation = monotonic_seconds() - start;

    /* Output. */
    start = monotonic_seconds();
    mitsuba_replacement *replacements = xcalloc(st.count + 1, sizeof *replacements);
    size_t replaced = 0;
    for (size_t m = 0; m < st.count && !status; m++) {
        if (!st.plan.decimate[m])
            continue;
        char name[256], path[PATH_MAX];
        importance_file_name(s->meshes[m].name, name, sizeof name);
        size_t length = strlen(name) + 32;
        st.ply[m] = xmalloc(length);
        snprintf(st.ply[m], length, "meshes/%s.ply", name);
        /* Two mesh names can make the same file name ("a/b", "a_b"): number the later ones. */
        for (unsigned int suffix = 2; ply_name_taken(&st, m); suffix++)
            snprintf(st.ply[m], length, "meshes/%s.%u.ply", name, suffix);
        snprintf(path, sizeof path, "%s/%s", outdir, st.ply[m]);
        status = mesh_io_write_ply(path, &st.output[m].mesh, NULL, NULL, NULL);
        replacements[replaced++] =
            (mitsuba_replacement){s->meshes[m].xml_file, s->meshes[m].xml_line, st.ply[m]};
    }
    if (!status)
        status = mitsuba_write_reduced(s->file, outdir, replacements, replaced);
    free(replacements);
    st.seconds_write = monotonic_seconds() - start;
    if (!status) {
        cJSON *report = reduce_report(s, d, o, &r, &st, after);
        if (o->method == DECIMATE_IMPORTANCE) {
            status = importance_write_outputs(outdir, report, s, &o->importance, &r,
                                              st.vertex_importance);
        } else {
            char path[PATH_MAX];
            snprintf(path, sizeof path, "%s/report.json", outdir);
            status = json_write(report, path);
        }
        cJSON_Delete(report);
        if (!status)
            fprintf(stderr,
                    "idmr: %llu -> %llu vertices (target %.4g: %llu), %zu of %zu meshes decimated; "
                    "reduced scene in %s/scene.xml\n",
                    (unsigned long long)st.plan.total_before, (unsigned long long)after, o->target,
                    (unsigned long long)st.plan.total_requested, replaced, st.count, outdir);
    }
    if (b.nodes)
        bvh_free(&b);
    importance_result_free(&r);
    state_free(&st);
    return status ? -1 : 0;
}
