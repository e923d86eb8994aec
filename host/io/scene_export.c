/* scene_export.c — `idmr convert`'s writing (see scene_export.h): the output's paths and the
 * checks that keep inputs safe, the names of meshes and materials in the output, the meshes as
 * world-space PLYs in the staged folder, then the format's own text (io/mitsuba/export_mitsuba.c,
 * io/pbrt/export_pbrt.c), published folder first, scene file last. */
#include "io/scene_export.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"
#include "core/files.h"
#include "io/export_internal.h"
#include "io/mesh/mesh_io.h"
#include "io/mitsuba_paths.h"
#include "io/mesh/ply_check.h"

/* ---- text ---- */

void export_printf(export_text *t, const char *fmt, ...)
{
    for (;;) {
        va_list args;
        va_start(args, fmt);
        size_t room = t->capacity - t->length;
        int n = vsnprintf(t->data ? t->data + t->length : NULL, room, fmt, args);
        va_end(args);
        if (n < 0)
            return;
        if ((size_t)n < room) {
            t->length += (size_t)n;
            return;
        }
        t->capacity = t->capacity * 2 + (size_t)n + 256;
        t->data = xrealloc(t->data, t->capacity);
    }
}

void export_text_free(export_text *t)
{
    free(t->data);
    memset(t, 0, sizeof *t);
}

const char *export_float(char buffer[32], double value)
{
    float f = (float)value;
    snprintf(buffer, 32, "%.9g", f == 0.0f ? 0.0 : (double)f); /* no "-0" */
    return buffer;
}

/* ---- geometry shared by the formats ---- */

static double normalize3(double v[3])
{
    double length = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (length > 0)
        for (int k = 0; k < 3; k++)
            v[k] /= length;
    return length;
}

void export_camera_frame(const idmr_camera *c, double right[3], double up[3], double forward[3],
                         double origin[3])
{
    for (int k = 0; k < 3; k++) {
        right[k] = c->right[k];
        up[k] = c->up[k];
        forward[k] = c->forward[k];
        origin[k] = c->origin[k];
    }
    normalize3(right);
    normalize3(up);
    normalize3(forward);
}

void export_frame_around(const double axis[3], double x[3], double y[3])
{
    /* The world axis least aligned with `axis`, made orthogonal to it. */
    double helper[3] = {0, 0, 0};
    int smallest = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(axis[k]) < fabs(axis[smallest]))
            smallest = k;
    helper[smallest] = 1;
    /* y = axis × helper, x = y × axis: (x, y, axis) right-handed. */
    y[0] = axis[1] * helper[2] - axis[2] * helper[1];
    y[1] = axis[2] * helper[0] - axis[0] * helper[2];
    y[2] = axis[0] * helper[1] - axis[1] * helper[0];
    normalize3(y);
    x[0] = y[1] * axis[2] - y[2] * axis[1];
    x[1] = y[2] * axis[0] - y[0] * axis[2];
    x[2] = y[0] * axis[1] - y[1] * axis[0];
    normalize3(x);
}

/* ---- paths and names ---- */

int scene_export_format_of(const char *path, scene_export_format *format)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (dot && (!slash || dot > slash + 1)) {
        if (!strcasecmp(dot, ".xml")) {
            *format = SCENE_EXPORT_MITSUBA;
            return 0;
        }
        if (!strcasecmp(dot, ".pbrt")) {
            *format = SCENE_EXPORT_PBRT;
            return 0;
        }
    }
    return error_set(IDMR_EXIT_INPUT,
                     "cannot write '%s': the output's extension names its format: .xml (a "
                     "Mitsuba 3 scene) or .pbrt (a pbrt-v4 scene)",
                     path);
}

/* A name made of letters, digits, '-', '_' and inner '.', the rest turned into '_'. */
static void safe_name(const char *name, char *out, size_t size)
{
    size_t n = 0;
    for (const char *c = name; c && *c && n + 1 < size && n < 120; c++) {
        int keep = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                   (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' || (*c == '.' && n > 0);
        out[n++] = keep ? *c : '_';
    }
    out[n] = '\0';
}

/* The names given so far, compared without case (a case-blind file system holds one file for
 * "Wall.ply" and "wall.ply"): open addressing over pointers to the names, which their arrays
 * own. */
typedef struct name_set {
    const char **slots;
    size_t capacity, count; /* capacity a power of two, at least twice count */
} name_set;

static uint64_t name_hash(const char *name)
{
    uint64_t h = 1469598103934665603ull; /* FNV-1a over the lower-case bytes */
    for (const char *c = name; *c; c++) {
        char lower = *c >= 'A' && *c <= 'Z' ? (char)(*c - 'A' + 'a') : *c;
        h = (h ^ (unsigned char)lower) * 1099511628211ull;
    }
    return h;
}

static int name_set_has(const name_set *set, const char *name)
{
    if (!set->capacity)
        return 0;
    for (size_t i = name_hash(name) & (set->capacity - 1); set->slots[i];
         i = (i + 1) & (set->capacity - 1))
        if (strcasecmp(set->slots[i], name) == 0)
            return 1;
    return 0;
}

static void name_set_add(name_set *set, const char *name)
{
    if (2 * (set->count + 1) > set->capacity) {
        name_set grown = {xcalloc(set->capacity ? 2 * set->capacity : 64, sizeof(char *)),
                          set->capacity ? 2 * set->capacity : 64, 0};
        for (size_t i = 0; i < set->capacity; i++)
            if (set->slots[i])
                name_set_add(&grown, set->slots[i]);
        free(set->slots);
        *set = grown;
    }
    size_t i = name_hash(name) & (set->capacity - 1);
    while (set->slots[i])
        i = (i + 1) & (set->capacity - 1);
    set->slots[i] = name;
    set->count++;
}

/* `name` made safe (`fallback` when nothing is left of it; one that starts with '_', which
 * Mitsuba keeps for itself, gets `fallback` before it) and unique in `taken` by a suffix .2,
 * .3, ... (Mitsuba's ids of shapes and bsdfs share one namespace, so one set holds both);
 * malloc'd, and added to `taken`. */
static char *give_name(name_set *taken, const char *name, const char *fallback)
{
    char safe[128], base[160], candidate[192];
    safe_name(name, safe, sizeof safe);
    snprintf(base, sizeof base, "%s%s", !safe[0] || safe[0] == '_' ? fallback : "", safe);
    snprintf(candidate, sizeof candidate, "%s", base);
    for (unsigned suffix = 2; name_set_has(taken, candidate); suffix++)
        snprintf(candidate, sizeof candidate, "%s.%u", base, suffix);
    char *given = xstrdup(candidate);
    name_set_add(taken, given);
    return given;
}

/* out_dir, folder_name and folder from job->out. */
static int plan_paths(export_job *job)
{
    const char *slash = strrchr(job->out, '/');
    const char *base = slash ? slash + 1 : job->out;
    const char *dot = strrchr(base, '.');
    size_t stem = dot ? (size_t)(dot - base) : strlen(base);
    if (stem == 0 || stem >= sizeof job->folder_name)
        return error_set(IDMR_EXIT_INPUT, "cannot write '%s': its name needs a stem of 1 to %zu "
                                          "characters (the mesh folder is named after it)",
                         job->out, sizeof job->folder_name - 1);
    snprintf(job->folder_name, sizeof job->folder_name, "%.*s", (int)stem, base);
    int n = slash ? snprintf(job->out_dir, sizeof job->out_dir, "%.*s",
                             (int)(slash - job->out), job->out)
                  : snprintf(job->out_dir, sizeof job->out_dir, ".");
    if (slash == job->out)
        n = snprintf(job->out_dir, sizeof job->out_dir, "/");
    int m = snprintf(job->folder, sizeof job->folder, "%s/%s", job->out_dir, job->folder_name);
    if (n < 0 || m < 0 || (size_t)m >= sizeof job->folder)
        return error_set(IDMR_EXIT_INPUT, "path too long: '%s'", job->out);
    return 0;
}

/* Inputs are never written; what exists is replaced only with `force`. */
static int check_outputs(const export_job *job, int force)
{
    if (scene_check_output_file(job->s, job->out) ||
        scene_check_output_directory(job->s, job->folder))
        return -1;
    struct stat st;
    if (stat(job->out, &st) == 0) {
        if (S_ISDIR(st.st_mode))
            return error_set(IDMR_EXIT_INPUT, "cannot write '%s': it is a directory", job->out);
        if (!force)
            return error_set(IDMR_EXIT_INPUT,
                             "'%s' exists: give --force to replace it (and the files of the "
                             "same names in %s/)",
                             job->out, job->folder);
    }
    if (stat(job->folder, &st) == 0) {
        if (!S_ISDIR(st.st_mode))
            return error_set(IDMR_EXIT_INPUT,
                             "cannot write the meshes into '%s': it exists and is not a "
                             "directory",
                             job->folder);
        if (!force && files_directory_has_entries(job->folder))
            return error_set(IDMR_EXIT_INPUT,
                             "'%s' holds files: give --force to write the meshes into it",
                             job->folder);
    }
    return 0;
}

/* Names for meshes (those with triangles) and the materials they use. */
static void plan_names(export_job *job)
{
    scene *s = job->s;
    job->mesh_names = xcalloc(s->mesh_count + 1, sizeof *job->mesh_names);
    job->mesh_files = xcalloc(s->mesh_count + 1, sizeof *job->mesh_files);
    job->material_names = xcalloc(s->material_count + 1, sizeof *job->material_names);
    job->texture_files = xcalloc(s->texture_count + 1, sizeof *job->texture_files);
    name_set taken = {NULL, 0, 0};
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (s->meshes[m].triangle_count == 0) {
            warn("%s: mesh '%s' has no triangles: left out", job->out, s->meshes[m].name);
            continue;
        }
        job->mesh_names[m] = give_name(&taken, s->meshes[m].name, "mesh");
        size_t length = strlen(job->folder_name) + strlen(job->mesh_names[m]) + 8;
        job->mesh_files[m] = xmalloc(length);
        snprintf(job->mesh_files[m], length, "%s/%s.ply", job->folder_name, job->mesh_names[m]);
    }
    /* Materials after every mesh has its name, so that a material's never takes one. */
    for (size_t m = 0; m < s->mesh_count; m++) {
        uint32_t material = s->meshes[m].material;
        if (job->mesh_names[m] && material < s->material_count &&
            !job->material_names[material])
            job->material_names[material] =
                give_name(&taken, s->material_info[material].name, "material");
    }
    free(taken.slots);
}

/* A file the scene reads, named relative to the output's directory (absolute where the two
 * share no directory below the root). */
static char *path_from_output(const export_job *job, const char *file)
{
    char *dir = mitsuba_path_real(job->out_dir);
    char *target = mitsuba_path_real(file);
    if (!target)
        target = mitsuba_path_absolute(file);
    char *relative = dir ? mitsuba_path_relative(dir, target) : NULL;
    free(dir);
    if (!relative)
        return target;
    free(target);
    return relative;
}

/* Every mesh written into the staging folder, read back and checked. */
static int write_meshes(export_job *job)
{
    scene *s = job->s;
    for (size_t m = 0; m < s->mesh_count; m++) {
        if (!job->mesh_names[m])
            continue;
        if (scene_mesh_restore(s, m))
            return -1;
        const scene_mesh *mesh = &s->meshes[m];
        /* A mesh shaded flat by its file's normals (or with none) is written without them:
         * the reader then shades it flat (Mitsuba's face_normals; pbrt without "N"). */
        int smooth = mesh->normals && !mesh->flat_normals;
        mesh_data data = {mesh->vertex_count, mesh->triangle_count, mesh->positions,
                          mesh->indices,      mesh->texcoords,      smooth ? mesh->normals : NULL,
                          0};
        char path[PATH_MAX + 200];
        snprintf(path, sizeof path, "%s/%s.ply", job->staging, job->mesh_names[m]);
        if (mesh_io_write_ply(path, &data, NULL, NULL, NULL) || ply_check_written(path))
            return -1;
        if (scene_mesh_is_later_copy(s, m))
            scene_mesh_release(s, m); /* made from its representative's for this file only */
    }
    return 0;
}

static void job_free(export_job *job)
{
    size_t counts[3] = {job->s->mesh_count, job->s->mesh_count, job->s->material_count};
    char **lists[3] = {job->mesh_names, job->mesh_files, job->material_names};
    for (int l = 0; l < 3; l++) {
        for (size_t i = 0; lists[l] && i < counts[l]; i++)
            free(lists[l][i]);
        free(lists[l]);
    }
    for (size_t t = 0; job->texture_files && t < job->s->texture_count; t++)
        free(job->texture_files[t]);
    free(job->texture_files);
    free(job->environment_file);
}

int scene_export(scene *s, const char *out, int force)
{
    scene_export_format format;
    if (scene_export_format_of(out, &format))
        return -1;
    export_job job;
    memset(&job, 0, sizeof job);
    job.s = s;
    job.out = out;
    if (plan_paths(&job) || check_outputs(&job, force))
        return -1;
    plan_names(&job);
    export_text text = {0};
    int status = files_stage_begin(job.folder, job.staging, sizeof job.staging);
    if (status) {
        job_free(&job);
        return -1;
    }
    for (size_t t = 0; t < s->texture_count; t++)
        job.texture_files[t] = path_from_output(&job, s->textures[t].file);
    status = write_meshes(&job);
    if (!status)
        status = format == SCENE_EXPORT_MITSUBA ? export_mitsuba(&job, &text)
                                                : export_pbrt(&job, &text);
    if (files_stage_end(job.staging, job.folder, !status))
        status = -1;
    if (!status)
        status = files_write_atomic(out, text.data, text.length);
    export_text_free(&text);
    job_free(&job);
    return status;
}
