/* mitsuba_write.c — the reduced scene's XML (see mitsuba_write.h for what is changed).
 *
 * Two passes over raw libxml2 trees. The first reads the scene and, depth-first in document
 * order as the loader does, every fragment it includes (one tree per file, keyed by realpath),
 * collecting the <default> parameters, the path rewrites (node, attribute, new value), the
 * include links (node → fragment) and the <shape> node of each replacement; it also notes
 * which fragments must be copied. The second edits the trees that are written (the scene and
 * the copies) and writes them, copies first and the scene last; a replaced <shape> is edited by
 * mitsuba_write_shape.c. All state lives in one `writer`; every function that can fail returns
 * -1 with the error set. */
#include "io/mitsuba/mitsuba_write.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlsave.h>

#include "core/error.h"
#include "core/files.h"
#include "io/mitsuba/mitsuba_params.h"
#include "io/mitsuba_paths.h"
#include "io/mitsuba/mitsuba_write_shape.h"
#include "io/mitsuba/mitsuba_xml.h"

#define WRITE_INCLUDES_DIR "includes"
#define WRITE_ASSETS_DIR "assets"

typedef struct write_doc {
    char *path; /* as the loader names it: the scene path as given, or dir(includer)/written */
    char *real; /* realpath, the key that identifies a file */
    xmlDocPtr doc;
    int has_declaration; /* the file starts with <?xml ...?> */
    int replaced;        /* holds a replaced shape */
    int fallback;        /* a relative path in it resolved only from the scene's directory */
    int copy;            /* fragment written under outdir/includes/ */
    char *copy_name;     /* "includes/<name>", relative to outdir */
} write_doc;

typedef struct write_path_edit {
    xmlNodePtr node;
    const char *attribute; /* "value" or "filename" */
    char *value;           /* the absolute path it names */
} write_path_edit;

/* A file copied beside the output scene (--bundle). */
typedef struct write_asset {
    char *real; /* the input file */
    char *name; /* "assets/<name>", relative to outdir */
} write_asset;

typedef struct write_include {
    xmlNodePtr node; /* the <include> element */
    size_t parent;   /* document holding it */
    size_t child;    /* the fragment it names */
} write_include;

typedef struct writer {
    const char *outdir;
    char *outdir_real;
    int bundle; /* copy what the scene names under outdir/assets/ */
    char *scene_dir;
    write_doc *docs; /* the scene first */
    size_t doc_count;
    mitsuba_params params; /* <default> values, as the loader reads them */
    write_path_edit *edits;
    size_t edit_count;
    write_include *includes;
    size_t include_count;
    const mitsuba_replacement *replacements;
    size_t replacement_count;
    char **replacement_real; /* realpath of each replacement's xml_file, or NULL */
    xmlNodePtr *shapes;      /* the <shape> node of each replacement, once found */
    write_asset *assets;
    size_t asset_count;
} writer;

/* ---------------------------------------------------------------------------------------- */
/* Reading documents                                                                        */

/* Whether the file's first bytes (after a UTF-8 byte order mark) are an XML declaration. */
static int file_has_declaration(const char *path)
{
    unsigned char head[8] = {0};
    FILE *f = fopen(path, "rb");
    if (!f)
        return 1;
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    size_t skip = n >= 3 && head[0] == 0xEF && head[1] == 0xBB && head[2] == 0xBF ? 3 : 0;
    return n >= skip + 5 && memcmp(head + skip, "<?xml", 5) == 0;
}

/* The absolute path to write for `written`: realpath of what the loader resolves it to, or
 * the absolute form of its first candidate when nothing exists there. */
static char *resolve_absolute(const writer *w, const write_doc *doc, const char *written,
                              int *fallback)
{
    char *path = mitsuba_resolve(doc->path, w->scene_dir, written, fallback);
    char *real = mitsuba_path_real(path);
    if (!real)
        real = mitsuba_path_absolute(path);
    free(path);
    return real;
}

/* ---------------------------------------------------------------------------------------- */
/* Pass 1: walking the documents                                                            */

static int walk(writer *w, size_t doc, xmlNodePtr parent, int depth);

/* The index of the document whose realpath is `real`, or doc_count. */
static size_t doc_find(const writer *w, const char *real)
{
    size_t i = 0;
    while (i < w->doc_count && strcmp(w->docs[i].real, real) != 0)
        i++;
    return i;
}

/* Reads a document (scene or fragment) and walks it; *index gets its number. */
static int doc_open(writer *w, const char *path, int depth, size_t *index)
{
    char *real = mitsuba_path_real(path);
    if (!real)
        return error_set(IDMR_EXIT_INPUT, "cannot read scene '%s': %s", path, strerror(errno));
    *index = doc_find(w, real);
    if (*index < w->doc_count) { /* included before: one tree, one copy */
        free(real);
        return 0;
    }
    xmlDocPtr tree = mitsuba_read_xml(path);
    if (!tree) {
        free(real);
        return -1;
    }
    w->docs = xrealloc(w->docs, (w->doc_count + 1) * sizeof *w->docs);
    write_doc *d = &w->docs[w->doc_count];
    memset(d, 0, sizeof *d);
    d->path = xstrdup(path);
    d->real = real;
    d->doc = tree;
    d->has_declaration = file_has_declaration(path);
    *index = w->doc_count++;
    xmlNodePtr root = xmlDocGetRootElement(tree);
    mitsuba_params_collect(&w->params, root); /* an incomplete <default>: the loader says so */
    return walk(w, *index, root, depth);
}

/* A path in `attribute` of `node`: records what it names (absolute), for pass 2 to rewrite. An
 * absolute path stays as written, unless --bundle copies what it names. */
static void note_path(writer *w, size_t doc, xmlNodePtr node, const char *attribute)
{
    const char *written = mitsuba_attr(node, attribute);
    char missing[128];
    int fallback;
    if (!written || !written[0])
        return;
    char *value = strchr(written, '$')
                      ? mitsuba_substitute(&w->params, written, missing, sizeof missing)
                      : xstrdup(written);
    if (!value) /* an undefined parameter: left as written (the loader rejects it) */
        return;
    if (value[0] == '/' && !strchr(written, '$') && !w->bundle) {
        free(value);
        return;
    }
    char *absolute = resolve_absolute(w, &w->docs[doc], value, &fallback);
    free(value);
    w->docs[doc].fallback |= fallback;
    w->edits = xrealloc(w->edits, (w->edit_count + 1) * sizeof *w->edits);
    w->edits[w->edit_count++] = (write_path_edit){node, attribute, absolute};
}

static int walk_include(writer *w, size_t doc, xmlNodePtr node, int depth)
{
    const char *written = mitsuba_attr(node, "filename");
    const char *path_of = w->docs[doc].path;
    char missing[128];
    int fallback;
    if (!written)
        return error_set(IDMR_EXIT_INPUT, "%s:%ld: <include>: missing attribute 'filename'",
                         path_of, xmlGetLineNo(node));
    if (depth >= MITSUBA_MAX_INCLUDE_DEPTH)
        return error_set(IDMR_EXIT_INPUT, "%s:%ld: <include>: includes nested too deeply",
                         path_of, xmlGetLineNo(node));
    char *value = mitsuba_substitute(&w->params, written, missing, sizeof missing);
    if (!value)
        return error_set(IDMR_EXIT_INPUT,
                         "%s:%ld: <include>: undefined parameter '%s' (no <default name=\"%s\">)",
                         path_of, xmlGetLineNo(node), missing, missing + 1);
    char *path = mitsuba_resolve(path_of, w->scene_dir, value, &fallback);
    free(value);
    w->docs[doc].fallback |= fallback;
    size_t child;
    int status = doc_open(w, path, depth + 1, &child);
    free(path);
    if (status)
        return error_prefix("%s:%ld: <include filename=\"%s\">", w->docs[doc].path,
                            xmlGetLineNo(node), written);
    w->includes = xrealloc(w->includes, (w->include_count + 1) * sizeof *w->includes);
    w->includes[w->include_count++] = (write_include){node, doc, child};
    return 0;
}

/* Whether the file `real` (NULL: not found) or `path` is document d. */
static int is_doc_file(const write_doc *d, const char *real, const char *path)
{
    return real ? strcmp(real, d->real) == 0 : strcmp(path, d->path) == 0;
}

/* Finds the replacements that name this <shape>. */
static int note_shape(writer *w, size_t doc, xmlNodePtr node)
{
    const write_doc *d = &w->docs[doc];
    long line = xmlGetLineNo(node);
    for (size_t i = 0; i < w->replacement_count; i++) {
        const mitsuba_replacement *r = &w->replacements[i];
        if (!is_doc_file(d, w->replacement_real[i], r->xml_file) || r->xml_line != line)
            continue;
        if (w->shapes[i])
            return error_set(IDMR_EXIT_INPUT,
                             "%s:%ld: more than one <shape> element on this line; cannot tell "
                             "which one to replace by '%s'",
                             d->path, line, r->ply);
        w->shapes[i] = node;
        w->docs[doc].replaced = 1;
    }
    return 0;
}

/* Walks the elements under `parent` in document order. <default> values stay as written. */
static int walk(writer *w, size_t doc, xmlNodePtr parent, int depth)
{
    MITSUBA_FOR_EACH_ELEMENT(node, parent)
    {
        if (mitsuba_is_tag(node, "default"))
            continue;
        if (mitsuba_is_tag(node, "include")) {
            if (walk_include(w, doc, node, depth))
                return -1;
            continue;
        }
        if (mitsuba_is_tag(node, "shape") && note_shape(w, doc, node))
            return -1;
        if (mitsuba_is_property(node, "filename") && mitsuba_attr(node, "value"))
            note_path(w, doc, node, "value");
        if (mitsuba_attr(node, "filename"))
            note_path(w, doc, node, "filename");
        if (walk(w, doc, node, depth))
            return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* Pass 2: editing and writing                                                              */

/* Whether `name` already names an output: a fragment's copy or a bundled file. */
static int output_name_taken(const char *name, const void *context)
{
    const writer *w = context;
    for (size_t j = 1; j < w->doc_count; j++)
        if (w->docs[j].copy_name && strcmp(w->docs[j].copy_name, name) == 0)
            return 1;
    for (size_t j = 0; j < w->asset_count; j++)
        if (strcmp(w->assets[j].name, name) == 0)
            return 1;
    return 0;
}

/* Whether `real` is a file the scene reads: one of its documents, or a path one of them names
 * (an edit's value is the realpath of what exists). */
static int is_scene_input(const writer *w, const char *real)
{
    for (size_t i = 0; i < w->doc_count; i++)
        if (strcmp(w->docs[i].real, real) == 0)
            return 1;
    for (size_t i = 0; i < w->edit_count; i++)
        if (strcmp(w->edits[i].value, real) == 0)
            return 1;
    return 0;
}

/* The name of real's copy under outdir/assets/ (--bundle), copying it on first use. */
static int bundle_file(writer *w, const char *real, const char **name)
{
    for (size_t i = 0; i < w->asset_count; i++)
        if (strcmp(w->assets[i].real, real) == 0) {
            *name = w->assets[i].name;
            return 0;
        }
    char *asset = mitsuba_path_unique(WRITE_ASSETS_DIR, real, output_name_taken, w);
    char *target = mitsuba_path_join(w->outdir, asset);
    char *target_real = mitsuba_path_real(target);
    int status = 0;
    if (target_real && is_scene_input(w, target_real))
        status = error_set(IDMR_EXIT_INPUT,
                           "bundling '%s' would overwrite '%s', which the scene reads: choose "
                           "another output directory (inputs are never overwritten)",
                           real, target);
    if (status == 0) {
        char *dir = mitsuba_path_join(w->outdir, WRITE_ASSETS_DIR);
        status = files_make_directory(dir);
        free(dir);
    }
    if (status == 0)
        status = files_copy_atomic(real, target);
    free(target);
    free(target_real);
    if (status) {
        free(asset);
        return -1;
    }
    w->assets = xrealloc(w->assets, (w->asset_count + 1) * sizeof *w->assets);
    w->assets[w->asset_count++] = (write_asset){xstrdup(real), asset};
    *name = asset;
    return 0;
}

/* Whether idmr's loader, reading outdir/out_doc, resolves `relative` to the file `absolute`
 * names (true when that file does not exist: nothing to tell apart). */
static int resolves_to(const writer *w, const char *out_doc, const char *relative,
                       const char *absolute)
{
    char *target = mitsuba_path_real(absolute);
    if (!target)
        return 1;
    char *doc_path = mitsuba_path_join(w->outdir, out_doc);
    char *resolved = mitsuba_resolve(doc_path, w->outdir, relative, NULL);
    char *resolved_real = mitsuba_path_real(resolved);
    int same = resolved_real && strcmp(resolved_real, target) == 0;
    free(target);
    free(doc_path);
    free(resolved);
    free(resolved_real);
    return same;
}

/* What outdir/out_doc says for the input file `absolute`: with --bundle, its copy under assets/
 * (an existing file); else its path relative to outdir, when idmr's loader finds the same file
 * through it from out_doc (Mitsuba 3 resolves from the scene's directory, outdir, in any
 * document); else `absolute`. *text is malloc'd. */
static int output_path(writer *w, const char *out_doc, const char *absolute, char **text)
{
    char *real = w->bundle ? mitsuba_path_real(absolute) : NULL;
    if (real) {
        const char *name;
        int status = bundle_file(w, real, &name);
        free(real);
        *text = status ? NULL : xstrdup(name);
        return status;
    }
    char *relative = mitsuba_path_relative(w->outdir_real, absolute);
    if (relative && resolves_to(w, out_doc, relative, absolute)) {
        *text = relative;
        return 0;
    }
    free(relative);
    *text = xstrdup(absolute);
    return 0;
}

/* Which fragments are copied, and under which names; returns how many. */
static size_t plan_copies(writer *w)
{
    size_t copies = 0;
    for (size_t i = 1; i < w->doc_count; i++)
        w->docs[i].copy = w->docs[i].replaced || w->docs[i].fallback || w->bundle;
    /* A fragment that includes a copy must point at it, so it is copied too. */
    for (int changed = 1; changed;) {
        changed = 0;
        for (size_t i = 0; i < w->include_count; i++) {
            write_doc *parent = &w->docs[w->includes[i].parent];
            if (w->includes[i].parent > 0 && !parent->copy && w->docs[w->includes[i].child].copy)
                parent->copy = changed = 1;
        }
    }
    for (size_t i = 1; i < w->doc_count; i++)
        if (w->docs[i].copy) {
            w->docs[i].copy_name = mitsuba_path_unique(WRITE_INCLUDES_DIR, w->docs[i].path,
                                                      output_name_taken, w);
            copies++;
        }
    return copies;
}

/* Serialises a tree as it was read (no reformatting) and writes it atomically. */
static int write_tree(const write_doc *d, const char *target)
{
    xmlBufferPtr buffer = xmlBufferCreate();
    if (!buffer)
        return error_set(IDMR_EXIT_FAILURE, "%s: out of memory serialising XML", target);
    const char *encoding = d->doc->encoding ? (const char *)d->doc->encoding : "UTF-8";
    int options = d->has_declaration ? 0 : XML_SAVE_NO_DECL;
    xmlSaveCtxtPtr save = xmlSaveToBuffer(buffer, encoding, options);
    long written = save ? xmlSaveDoc(save, d->doc) : -1;
    if (save)
        xmlSaveClose(save);
    int status = 0;
    if (written < 0)
        status = error_set(IDMR_EXIT_FAILURE, "%s: cannot serialise the XML of '%s'", target,
                           d->path);
    else
        status = files_write_atomic(target, xmlBufferContent(buffer),
                                    (size_t)xmlBufferLength(buffer));
    xmlBufferFree(buffer);
    return status;
}

/* Sets `attribute` of `node` to what outdir/target says for the input file `absolute`. */
static int set_path(writer *w, const char *target, xmlNodePtr node, const char *attribute,
                    const char *absolute)
{
    char *text;
    if (output_path(w, target, absolute, &text))
        return -1;
    xmlSetProp(node, (const xmlChar *)attribute, (const xmlChar *)text);
    free(text);
    return 0;
}

/* Applies the edits that fall in document `index` and writes it to outdir/target. */
static int write_doc_out(writer *w, size_t index, const char *target)
{
    write_doc *d = &w->docs[index];
    for (size_t i = 0; i < w->edit_count; i++)
        if (w->edits[i].node->doc == d->doc &&
            set_path(w, target, w->edits[i].node, w->edits[i].attribute, w->edits[i].value))
            return -1;
    for (size_t i = 0; i < w->include_count; i++) {
        const write_include *link = &w->includes[i];
        if (link->parent != index)
            continue;
        const write_doc *child = &w->docs[link->child];
        if (child->copy)
            xmlSetProp(link->node, (const xmlChar *)"filename",
                       (const xmlChar *)child->copy_name);
        else if (set_path(w, target, link->node, "filename", child->real))
            return -1;
    }
    for (size_t i = 0; i < w->replacement_count; i++)
        if (w->shapes[i]->doc == d->doc)
            mitsuba_shape_to_ply(w->shapes[i], w->replacements[i].ply,
                                 w->replacements[i].face_normals);
    char *path = mitsuba_path_join(w->outdir, target);
    int status = write_tree(d, path);
    free(path);
    return status;
}

/* ---------------------------------------------------------------------------------------- */
/* The entry point                                                                          */

static void writer_free(writer *w)
{
    for (size_t i = 0; i < w->doc_count; i++) {
        free(w->docs[i].path);
        free(w->docs[i].real);
        free(w->docs[i].copy_name);
        xmlFreeDoc(w->docs[i].doc);
    }
    free(w->docs);
    mitsuba_params_free(&w->params);
    for (size_t i = 0; i < w->edit_count; i++)
        free(w->edits[i].value);
    free(w->edits);
    free(w->includes);
    for (size_t i = 0; i < w->replacement_count; i++)
        free(w->replacement_real[i]);
    free(w->replacement_real);
    free(w->shapes);
    for (size_t i = 0; i < w->asset_count; i++) {
        free(w->assets[i].real);
        free(w->assets[i].name);
    }
    free(w->assets);
    free(w->scene_dir);
    free(w->outdir_real);
}

/* Checks that each replacement found its shape and that no shape is replaced twice. */
static int check_replacements(const writer *w)
{
    for (size_t i = 0; i < w->replacement_count; i++) {
        const mitsuba_replacement *r = &w->replacements[i];
        if (!w->shapes[i])
            return error_set(IDMR_EXIT_INPUT,
                             "%s:%d: no <shape> element at this line of the scene (replacement "
                             "by '%s')",
                             r->xml_file, r->xml_line, r->ply);
        for (size_t j = 0; j < i; j++)
            if (w->shapes[j] == w->shapes[i])
                return error_set(IDMR_EXIT_INPUT, "%s:%d: <shape> replaced twice ('%s', '%s')",
                                 r->xml_file, r->xml_line, w->replacements[j].ply, r->ply);
    }
    return 0;
}

/* Makes outdir/includes when a fragment is copied, and writes the copies. */
static int write_copies(writer *w)
{
    if (plan_copies(w) == 0)
        return 0;
    char *dir = mitsuba_path_join(w->outdir, WRITE_INCLUDES_DIR);
    int status = files_make_directory(dir);
    free(dir);
    for (size_t i = 1; i < w->doc_count && status == 0; i++)
        if (w->docs[i].copy)
            status = write_doc_out(w, i, w->docs[i].copy_name);
    return status;
}

int mitsuba_write_reduced(const char *scene_file, const char *outdir,
                          const mitsuba_replacement *replacements, size_t count, int bundle)
{
    writer w;
    memset(&w, 0, sizeof w);
    xmlInitParser();
    w.outdir = outdir;
    w.bundle = bundle;
    w.outdir_real = mitsuba_path_real(outdir);
    if (!w.outdir_real)
        return error_set(IDMR_EXIT_FAILURE, "output directory '%s': %s", outdir,
                         strerror(errno));
    w.scene_dir = mitsuba_path_directory(scene_file);
    w.replacements = replacements;
    w.replacement_count = count;
    w.replacement_real = xcalloc(count ? count : 1, sizeof *w.replacement_real);
    w.shapes = xcalloc(count ? count : 1, sizeof *w.shapes);
    for (size_t i = 0; i < count; i++) {
        const char *xml_file = replacements[i].xml_file;
        w.replacement_real[i] = xml_file ? mitsuba_path_real(xml_file) : NULL;
    }
    for (size_t i = 0; i < count; i++)
        if (!replacements[i].xml_file || !replacements[i].ply) {
            writer_free(&w);
            return error_set(IDMR_EXIT_FAILURE, "replacement %zu of %s has no %s", i,
                             scene_file, replacements[i].ply ? "xml_file" : "ply");
        }
    size_t scene_index;
    int status = doc_open(&w, scene_file, 0, &scene_index);
    if (status == 0)
        status = check_replacements(&w);
    if (status == 0)
        status = write_copies(&w);
    if (status == 0)
        status = write_doc_out(&w, 0, "scene.xml");
    writer_free(&w);
    return status;
}
