/* pbrt_write.c — the reduced pbrt-v4 scene (see pbrt.h): the input text copied with edits.
 *
 * The scene file and, depth-first in statement order, every file it includes are read and cut
 * into statements by the reader's lexer (pbrt_lexer.c); the writer only needs where things are,
 * not what they mean (the loader has checked the scene). Three kinds of edit, each a byte span
 * of one file and its new text:
 *   shape    a replaced Shape statement, from its keyword to its last token, becomes
 *            `Shape "plymesh" "string filename" [ "<ply>" ]` followed by the statement's
 *            parameters that do not describe geometry, copied as written (a material
 *            parameter, "texture alpha", ...). The geometric ones dropped: P, indices, uv, st,
 *            N, S, faceIndices, filename, radius, zmin, zmax, phimax, height, innerradius,
 *            levels.
 *   path     the value of a "filename" (or "mapname", "emissionfilename", "normalmap") string
 *            parameter of any
 *            statement but Film (whose filename is the renderer's output), and a spectrum
 *            parameter's string that names an existing file: a relative path is resolved as the
 *            reader resolves it (from the scene's directory) and written relative to outdir, or
 *            absolute when the two share no directory below the root. Absolute paths stay.
 *   include  Include/Import: a file is copied (to outdir/includes/<name>, made unique) when it
 *            holds a replaced shape, a relative path, or an Include of a copied file, since
 *            pbrt resolves every relative path from the scene's directory, which is now outdir;
 *            otherwise the Include names it where it is (relative to outdir, as a path).
 * The copies are written first, the scene last, each through a temporary name and rename(). */
#include "io/pbrt/pbrt_loader.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"
#include "core/files.h"
#include "io/mitsuba_paths.h"

#define PBRT_INCLUDES_DIR "includes"
#define PBRT_MAX_FILES 4096

typedef struct write_edit {
    size_t start, end;
    char *text;  /* the new text; a path edit holds the resolved path until finish_path_edits */
    int is_path;
} write_edit;

typedef struct write_file {
    char *path; /* as the reader names it */
    char *real;
    char *text;
    size_t size;
    write_edit *edits;
    size_t edit_count;
    int copy;       /* written under outdir (the scene always) */
    char *out_name; /* "scene.pbrt" or "includes/<name>" */
    int has_paths;  /* holds a relative path (edited) */
    int replaced;   /* holds a replaced shape */
} write_file;

typedef struct write_link {
    size_t parent, child;
    size_t start, end; /* the Include's string token */
} write_link;

typedef struct pbrt_writer {
    const char *outdir;
    char *outdir_real;
    char *scene_dir;
    write_file *files;
    size_t file_count;
    write_link *links;
    size_t link_count;
    const pbrt_replacement *replacements;
    size_t replacement_count;
    char **replacement_real;
    int *replacement_used;
} pbrt_writer;

static void add_edit(write_file *f, size_t start, size_t end, char *text, int is_path)
{
    f->edits = xrealloc(f->edits, (f->edit_count + 1) * sizeof *f->edits);
    f->edits[f->edit_count++] = (write_edit){start, end, text, is_path};
}

/* `value` as a pbrt string token: quoted, with " and \ escaped. */
static char *quoted(const char *value)
{
    size_t n = strlen(value);
    char *out = xmalloc(2 * n + 3), *p = out;
    *p++ = '"';
    for (size_t i = 0; i < n; i++) {
        if (value[i] == '"' || value[i] == '\\')
            *p++ = '\\';
        *p++ = value[i];
    }
    *p++ = '"';
    *p = '\0';
    return out;
}

/* A path the output names for the input file `resolved`: relative to outdir, else absolute. */
static char *path_from_outdir(const pbrt_writer *w, const char *resolved)
{
    char *real = mitsuba_path_real(resolved);
    char *target = real ? real : mitsuba_path_absolute(resolved);
    char *relative = mitsuba_path_relative(w->outdir_real, target);
    if (relative) {
        free(target);
        return relative;
    }
    return target;
}

/* ---- reading the files ---- */

/* A parameter as the writer sees it: its declaration token and its value tokens' span. */
typedef struct raw_param {
    char *type, *name;
    size_t start, end;      /* declaration to last value */
    pbrt_token first_value; /* the first value token (a string's span for paths) */
    int string_count;
} raw_param;

static int statement_is(const pbrt_token *t, const char *const *words)
{
    for (size_t i = 0; words[i]; i++)
        if (pbrt_token_is(t, words[i]))
            return 1;
    return 0;
}

/* Reads a parameter list; *params malloc'd. Returns the end of the last token taken. */
static int read_raw_params(pbrt_lexer *lx, raw_param **params, size_t *count, size_t *end)
{
    *params = NULL;
    *count = 0;
    for (;;) {
        pbrt_token t;
        if (pbrt_lexer_peek(lx, &t))
            return -1;
        if (t.kind != PBRT_TOKEN_STRING)
            return 0;
        pbrt_lexer_next(lx, &t);
        raw_param p;
        memset(&p, 0, sizeof p);
        char *declaration = pbrt_token_string(&t);
        char type[64] = "", name[256] = "";
        sscanf(declaration, "%63s %255s", type, name);
        free(declaration);
        p.type = xstrdup(type);
        p.name = xstrdup(name);
        p.start = t.offset;
        pbrt_token v;
        if (pbrt_lexer_next(lx, &v))
            goto fail_param;
        if (v.kind == PBRT_TOKEN_OPEN) {
            int first = 1;
            for (;;) {
                if (pbrt_lexer_next(lx, &v))
                    goto fail_param;
                if (v.kind == PBRT_TOKEN_CLOSE)
                    break;
                if (v.kind == PBRT_TOKEN_END) {
                    pbrt_fail(lx->file, v.line, "'[' without a matching ']'");
                    goto fail_param;
                }
                if (first)
                    p.first_value = v;
                first = 0;
                p.string_count += v.kind == PBRT_TOKEN_STRING;
            }
        } else {
            p.first_value = v;
            p.string_count = v.kind == PBRT_TOKEN_STRING;
        }
        p.end = *end = v.end;
        *params = xrealloc(*params, (*count + 1) * sizeof **params);
        (*params)[(*count)++] = p;
        continue;
    fail_param:
        free(p.type);
        free(p.name);
        return -1;
    }
}

static void free_raw_params(raw_param *params, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        free(params[i].type);
        free(params[i].name);
    }
    free(params);
}

static int is_path_param(const raw_param *p, const char *statement, const pbrt_writer *w,
                         char **resolved)
{
    *resolved = NULL;
    if (p->string_count != 1 || p->first_value.kind != PBRT_TOKEN_STRING)
        return 0;
    char *value = pbrt_token_string(&p->first_value);
    int path = 0;
    if (strcmp(p->type, "string") == 0 &&
        (strcmp(p->name, "filename") == 0 || strcmp(p->name, "mapname") == 0 ||
         strcmp(p->name, "emissionfilename") == 0 || strcmp(p->name, "normalmap") == 0))
        path = strcmp(statement, "Film") != 0;
    else if (strcmp(p->type, "spectrum") == 0) {
        char *candidate = mitsuba_path_join(w->scene_dir, value);
        path = access(candidate, R_OK) == 0;
        free(candidate);
    }
    if (path && value[0] != '/')
        *resolved = mitsuba_path_join(w->scene_dir, value);
    free(value);
    return *resolved != NULL;
}

static int is_geometric(const char *name)
{
    static const char *const geometric[] = {
        "P",      "indices", "uv",     "st",     "N",      "S",           "faceIndices", "filename",
        "radius", "zmin",    "zmax",   "phimax", "height", "innerradius", "levels",      NULL};
    for (size_t i = 0; geometric[i]; i++)
        if (strcmp(name, geometric[i]) == 0)
            return 1;
    return 0;
}

/* The replacement (index) of the Shape at `offset` in file `f`, or -1. */
static int find_replacement(pbrt_writer *w, const write_file *f, size_t offset, int line)
{
    int found = -1;
    for (size_t r = 0; r < w->replacement_count; r++) {
        if ((size_t)w->replacements[r].offset != offset || !w->replacement_real[r] ||
            strcmp(w->replacement_real[r], f->real) != 0)
            continue;
        if (found < 0) {
            found = (int)r;
        } else if (!w->replacement_used[r]) {
            warn("%s:%d: Shape: one statement makes several meshes (an instanced object): the "
                 "reduced mesh of the first is written for all",
                 f->path, line);
        }
        w->replacement_used[r] = 1;
    }
    return found;
}

static char *shape_text(const write_file *f, const char *ply, const raw_param *params,
                        size_t count)
{
    char *q = quoted(ply);
    size_t size = strlen(q) + 64;
    for (size_t i = 0; i < count; i++)
        size += params[i].end - params[i].start + 8;
    char *out = xmalloc(size);
    size_t used = (size_t)snprintf(out, size, "Shape \"plymesh\" \"string filename\" [ %s ]", q);
    free(q);
    for (size_t i = 0; i < count; i++) {
        if (is_geometric(params[i].name))
            continue;
        used += (size_t)snprintf(out + used, size - used, "\n    %.*s",
                                 (int)(params[i].end - params[i].start),
                                 f->text + params[i].start);
    }
    return out;
}

static int scan_file(pbrt_writer *w, const char *path, int depth, size_t *index);

/* The statements of file `index`, collecting its edits and include links. */
static int scan_statements(pbrt_writer *w, size_t index, int depth)
{
    static const char *const one_string_params[] = {
        "Shape",      "Camera",      "Film",        "Material",        "MakeNamedMaterial",
        "AreaLightSource", "LightSource", "Sampler", "Integrator",     "PixelFilter",
        "Accelerator", "MakeNamedMedium", "Attribute", NULL};
    pbrt_lexer lx;
    pbrt_lexer_init(&lx, w->files[index].path, w->files[index].text, w->files[index].size);
    for (;;) {
        pbrt_token t;
        if (pbrt_lexer_next(&lx, &t))
            return -1;
        if (t.kind == PBRT_TOKEN_END)
            return 0;
        if (t.kind != PBRT_TOKEN_WORD) /* arguments of statements that take no parameters */
            continue;
        int leading = statement_is(&t, one_string_params) ? 1
                      : pbrt_token_is(&t, "Texture")     ? 3
                      : pbrt_token_is(&t, "Option")      ? 0
                                                         : -1;
        if (pbrt_token_is(&t, "Include") || pbrt_token_is(&t, "Import")) {
            pbrt_token name;
            if (pbrt_lexer_next(&lx, &name))
                return -1;
            if (name.kind != PBRT_TOKEN_STRING)
                return pbrt_fail(lx.file, name.line, "Include: expected a file name");
            char *written = pbrt_token_string(&name);
            char *child_path = mitsuba_path_join(w->scene_dir, written);
            free(written);
            size_t child;
            int status = scan_file(w, child_path, depth + 1, &child);
            free(child_path);
            if (status)
                return error_prefix("%s:%d: Include", w->files[index].path, name.line);
            w->links = xrealloc(w->links, (w->link_count + 1) * sizeof *w->links);
            w->links[w->link_count++] = (write_link){index, child, name.offset, name.end};
            continue;
        }
        if (leading < 0)
            continue;
        char statement[32];
        snprintf(statement, sizeof statement, "%.*s", (int)t.length, t.text);
        size_t end = t.end;
        for (int i = 0; i < leading; i++) {
            pbrt_token arg;
            if (pbrt_lexer_next(&lx, &arg))
                return -1;
            end = arg.end;
        }
        raw_param *params;
        size_t count;
        if (read_raw_params(&lx, &params, &count, &end))
            return -1;
        write_file *f = &w->files[index];
        for (size_t i = 0; i < count; i++) {
            char *resolved;
            if (is_path_param(&params[i], statement, w, &resolved)) {
                /* The text is made once the output paths are known. */
                add_edit(f, params[i].first_value.offset, params[i].first_value.end, resolved, 1);
                f->has_paths = 1;
            }
        }
        if (pbrt_token_is(&t, "Shape")) {
            int r = find_replacement(w, f, t.offset, t.line);
            if (r >= 0) {
                /* A shape edit replaces the path edits inside it. */
                while (f->edit_count && f->edits[f->edit_count - 1].start >= t.offset) {
                    free(f->edits[f->edit_count - 1].text);
                    f->edit_count--;
                }
                char *text = shape_text(f, w->replacements[r].ply, params, count);
                add_edit(f, t.offset, end, text, 0);
                f->replaced = 1;
            }
        }
        free_raw_params(params, count);
    }
}

/* Reads `path` (once per file: keyed by realpath) and its includes; *index gets its entry. */
static int scan_file(pbrt_writer *w, const char *path, int depth, size_t *index)
{
    if (depth > 32)
        return error_set(IDMR_EXIT_INPUT, "%s: files included in each other too deeply", path);
    char *real = mitsuba_path_real(path);
    if (!real)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s'", path);
    for (size_t i = 0; i < w->file_count; i++)
        if (strcmp(w->files[i].real, real) == 0) {
            free(real);
            *index = i;
            return 0;
        }
    if (w->file_count >= PBRT_MAX_FILES) {
        free(real);
        return error_set(IDMR_EXIT_INPUT, "%s: more than %d files included", path,
                         PBRT_MAX_FILES);
    }
    write_file f;
    memset(&f, 0, sizeof f);
    f.text = pbrt_read_text(path, &f.size);
    if (!f.text) {
        free(real);
        return -1;
    }
    f.path = xstrdup(path);
    f.real = real;
    w->files = xrealloc(w->files, (w->file_count + 1) * sizeof *w->files);
    w->files[w->file_count] = f;
    *index = w->file_count++;
    return scan_statements(w, *index, depth);
}

/* ---- writing ---- */

static int name_taken(const char *name, const void *context)
{
    const pbrt_writer *w = context;
    for (size_t i = 0; i < w->file_count; i++)
        if (w->files[i].out_name && strcmp(w->files[i].out_name, name) == 0)
            return 1;
    return strcmp(name, "scene.pbrt") == 0;
}

/* The text of file f with its edits applied (edits in order of their start). */
static char *apply_edits(const pbrt_writer *w, size_t index, size_t *size)
{
    const write_file *f = &w->files[index];
    size_t count = f->edit_count;
    write_edit *edits = xmalloc((count + w->link_count + 1) * sizeof *edits);
    memcpy(edits, f->edits, count * sizeof *edits);
    for (size_t i = 0; i < w->link_count; i++) {
        const write_link *l = &w->links[i];
        if (l->parent != index)
            continue;
        const write_file *child = &w->files[l->child];
        char *target = child->copy ? xstrdup(child->out_name) : path_from_outdir(w, child->path);
        edits[count++] = (write_edit){l->start, l->end, quoted(target), 0};
        free(target);
    }
    /* Sort by start (insertion sort: few edits per file). */
    for (size_t i = 1; i < count; i++)
        for (size_t k = i; k > 0 && edits[k].start < edits[k - 1].start; k--) {
            write_edit swap = edits[k];
            edits[k] = edits[k - 1];
            edits[k - 1] = swap;
        }
    size_t capacity = f->size + 1, used = 0, at = 0;
    for (size_t i = 0; i < count; i++)
        capacity += strlen(edits[i].text) + 4096;
    char *out = xmalloc(capacity);
    for (size_t i = 0; i < count; i++) {
        const write_edit *e = &edits[i];
        if (e->start < at)
            continue; /* inside an earlier edit */
        memcpy(out + used, f->text + at, e->start - at);
        used += e->start - at;
        size_t n = strlen(e->text);
        memcpy(out + used, e->text, n);
        used += n;
        at = e->end;
    }
    memcpy(out + used, f->text + at, f->size - at);
    used += f->size - at;
    for (size_t i = f->edit_count; i < count; i++)
        free(edits[i].text);
    free(edits);
    *size = used;
    return out;
}

/* Turns the path edits' texts (absolute resolved paths for now) into quoted output paths. */
static void finish_path_edits(pbrt_writer *w)
{
    for (size_t i = 0; i < w->file_count; i++) {
        write_file *f = &w->files[i];
        for (size_t k = 0; k < f->edit_count; k++) {
            write_edit *e = &f->edits[k];
            if (!e->is_path)
                continue;
            char *target = path_from_outdir(w, e->text);
            free(e->text);
            e->text = quoted(target);
            free(target);
        }
    }
}

static void writer_free(pbrt_writer *w)
{
    for (size_t i = 0; i < w->file_count; i++) {
        write_file *f = &w->files[i];
        for (size_t k = 0; k < f->edit_count; k++)
            free(f->edits[k].text);
        free(f->edits);
        free(f->path);
        free(f->real);
        free(f->text);
        free(f->out_name);
    }
    free(w->files);
    free(w->links);
    for (size_t r = 0; r < w->replacement_count; r++)
        free(w->replacement_real[r]);
    free(w->replacement_real);
    free(w->replacement_used);
    free(w->outdir_real);
    free(w->scene_dir);
}

int pbrt_write_reduced(const char *scene_file, const char *outdir,
                       const pbrt_replacement *replacements, size_t count)
{
    pbrt_writer w;
    memset(&w, 0, sizeof w);
    w.outdir = outdir;
    w.replacements = replacements;
    w.replacement_count = count;
    w.replacement_real = xcalloc(count + 1, sizeof *w.replacement_real);
    w.replacement_used = xcalloc(count + 1, sizeof *w.replacement_used);
    for (size_t r = 0; r < count; r++)
        w.replacement_real[r] = mitsuba_path_real(replacements[r].file);
    w.outdir_real = mitsuba_path_real(outdir);
    w.scene_dir = mitsuba_path_directory(scene_file);
    int status = -1;
    size_t scene_index;
    if (!w.outdir_real) {
        error_set(IDMR_EXIT_FAILURE, "output directory '%s' does not exist", outdir);
        goto done;
    }
    if (scan_file(&w, scene_file, 0, &scene_index))
        goto done;
    for (size_t r = 0; r < count; r++)
        if (!w.replacement_used[r]) {
            error_set(IDMR_EXIT_FAILURE,
                      "%s:%d: no Shape statement at byte %ld to replace with '%s'",
                      replacements[r].file, replacements[r].line, replacements[r].offset,
                      replacements[r].ply);
            goto done;
        }
    /* Which files are copied: the scene; files with replaced shapes or relative paths; files
     * including a copied file (to a fixpoint). */
    w.files[scene_index].copy = 1;
    for (size_t i = 0; i < w.file_count; i++)
        w.files[i].copy |= w.files[i].replaced || w.files[i].has_paths;
    for (int changed = 1; changed;) {
        changed = 0;
        for (size_t i = 0; i < w.link_count; i++)
            if (w.files[w.links[i].child].copy && !w.files[w.links[i].parent].copy)
                w.files[w.links[i].parent].copy = changed = 1;
    }
    w.files[scene_index].out_name = xstrdup("scene.pbrt");
    int need_includes_dir = 0;
    for (size_t i = 0; i < w.file_count; i++)
        if (w.files[i].copy && i != scene_index) {
            w.files[i].out_name =
                mitsuba_path_unique(PBRT_INCLUDES_DIR, w.files[i].path, name_taken, &w);
            need_includes_dir = 1;
        }
    finish_path_edits(&w);
    if (need_includes_dir) {
        char dir[PATH_MAX];
        snprintf(dir, sizeof dir, "%s/%s", outdir, PBRT_INCLUDES_DIR);
        if (files_make_directory(dir))
            goto done;
    }
    /* The copies first, the scene last. */
    for (size_t pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < w.file_count; i++) {
            if (!w.files[i].copy || (pass == 0) == (i == scene_index))
                continue;
            size_t size;
            char *text = apply_edits(&w, i, &size);
            char path[PATH_MAX];
            snprintf(path, sizeof path, "%s/%s", outdir, w.files[i].out_name);
            int failed = files_write_atomic(path, text, size);
            free(text);
            if (failed)
                goto done;
        }
    status = 0;
done:
    writer_free(&w);
    return status;
}

int pbrt_mesh_to_object_space(const scene_mesh *m, const mesh_data *world, mesh_data *out)
{
    xform to_world, to_object;
    memcpy(to_world.m, m->object_to_world, sizeof to_world.m);
    memset(out, 0, sizeof *out);
    if (xform_invert_affine(&to_world, &to_object))
        return error_set(IDMR_EXIT_FAILURE, "%s:%d: mesh '%s': its transform cannot be inverted",
                         m->xml_file ? m->xml_file : "?", m->xml_line, m->name);
    size_t v = world->vertex_count, t = world->triangle_count;
    out->vertex_count = world->vertex_count;
    out->triangle_count = world->triangle_count;
    out->positions = xmalloc(3 * v * sizeof(float) + 1);
    memcpy(out->positions, world->positions, 3 * v * sizeof(float));
    xform_apply_points(&to_object, out->positions, v);
    out->indices = xmalloc(3 * t * sizeof(uint32_t) + 1);
    memcpy(out->indices, world->indices, 3 * t * sizeof(uint32_t));
    if (m->source_flipped) /* pbrt reverses it again on reading */
        for (size_t i = 0; i < t; i++) {
            uint32_t swap = out->indices[3 * i + 1];
            out->indices[3 * i + 1] = out->indices[3 * i + 2];
            out->indices[3 * i + 2] = swap;
        }
    if (world->texcoords) {
        out->texcoords = xmalloc(2 * v * sizeof(float));
        for (size_t i = 0; i < v; i++) {
            out->texcoords[2 * i] = world->texcoords[2 * i];
            out->texcoords[2 * i + 1] = 1.0f - world->texcoords[2 * i + 1];
        }
    }
    if (world->normals) {
        out->normals = xmalloc(3 * v * sizeof(float));
        memcpy(out->normals, world->normals, 3 * v * sizeof(float));
        xform_apply_normals(&to_object, out->normals, v);
        if (m->source_flipped)
            for (size_t i = 0; i < 3 * v; i++)
                out->normals[i] = -out->normals[i];
    }
    return 0;
}
