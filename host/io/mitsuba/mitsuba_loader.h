/* mitsuba_loader.h — what the files of the Mitsuba loader share (internal: the public API is
 * mitsuba.h, whose comment says what is read).
 *
 * The loader reads each file into a tree (mitsuba_xml.h), substitutes its <default> parameters
 * and snake_cases its property names in place, then walks the top-level elements in document
 * order, adding to one `scene` as it goes. The files, one job each:
 *
 *   mitsuba_document.c   reading and preparing documents, includes, the top-level walk,
 *                        mitsuba_load()
 *   mitsuba_messages.c   errors and warnings that name file, line and element
 *   mitsuba_unread.c     warnings for properties and elements no reader asked for
 *   mitsuba_values.c     numbers and typed properties (<float name= value=> and friends)
 *   mitsuba_transform.c  <transform> properties
 *   mitsuba_ids.c        the id table behind <ref id=...>
 *   mitsuba_color.c      colours, spectra and bitmap textures
 *   mitsuba_bsdf.c       <bsdf> → material
 *   mitsuba_sensor.c     <sensor> → camera
 *   mitsuba_emitter.c    <emitter> → light
 *   mitsuba_shape.c      <shape> → world-space mesh with its material and area light;
 *                        shapegroups and their instances (each group shape held once)
 *
 * Every function here that can fail returns -1 with the error set through mitsuba_fail() (or
 * error_set()/error_prefix()) and 0 on success, unless it says otherwise. Nodes of included
 * documents stay alive until the load ends, since the id table points into them. */
#ifndef IDMR_MITSUBA_LOADER_H
#define IDMR_MITSUBA_LOADER_H

#include <stddef.h>

#include <libxml/tree.h>

#include "core/scene.h"
#include "io/mitsuba/mitsuba_params.h"
#include "io/mitsuba_paths.h"
#include "io/mitsuba/mitsuba_xml.h"
#include "core/xform.h"

/* Attribute that keeps a normalised property name's original spelling, for messages. */
#define MITSUBA_WRITTEN_NAME "idmr_written_name"

/* A <bsdf> read into a material, before it is added to the scene. */
typedef struct bsdf_parsed {
    idmr_material material;
    char type[32];      /* the innermost Mitsuba type */
    xmlNodePtr texture; /* bitmap for the diffuse reflectance, or NULL */
} bsdf_parsed;

/* A declaration that <ref id=...> can name. */
typedef struct mitsuba_id {
    char *id;
    xmlNodePtr node;
    bsdf_parsed *bsdf; /* a bsdf as parsed at its declaration (parsed once: warnings too) */
    int material;      /* scene material made from this bsdf, or -1 until first referenced */
} mitsuba_id;

typedef struct loader {
    scene *s;
    xmlDocPtr *docs; /* the scene file first, then included fragments */
    size_t doc_count;
    mitsuba_params params; /* <default> values */
    mitsuba_id *ids;
    size_t id_count;
    int major_version;    /* 0 for Mitsuba 0.x files, else 3 */
    int default_material; /* the shared diffuse 0.5, or -1 until needed */
    size_t include_count; /* <include> elements read so far */
    uint32_t release_from; /* mesh files with at least this many vertices are released once
                              read (scene_mesh_release: streaming); 0: none */
    /* Per shapegroup shape an instance placed: its node and the mesh index of its first copy,
     * the representative that holds its geometry (core/scene.h: instanced). */
    struct group_shape_copies {
        xmlNodePtr shape;
        size_t first_copy;
    } *group_shapes;
    size_t group_shape_count;
} loader;

/* What was not read (mitsuba_unread.c). Marks node (may be NULL) as read by some reader;
 * mitsuba_prop_find() does it for what it finds, a reader that picks a nested plugin by hand
 * calls it. */
void mitsuba_mark_read(xmlNodePtr node);
/* After a load: a warning for each property or nested element of a plugin that was read
 * which no reader marked and that is not a known Mitsuba property idmr has no use for. */
void mitsuba_warn_unread(xmlDocPtr *docs, size_t doc_count);

/* Messages (mitsuba_messages.c): "file:line: <tag type=.. name=.. id=..>: what". */
const char *mitsuba_node_file(xmlNodePtr node);
int mitsuba_fail(xmlNodePtr node, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Puts "file:line: <element>" in front of an error set by another module. */
int mitsuba_fail_prefix(xmlNodePtr node);
void mitsuba_warn_at(xmlNodePtr node, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* *out = node's attribute `name`; missing, it is an error. */
int mitsuba_require_attr(xmlNodePtr node, const char *name, const char **out);

/* Numbers (mitsuba_values.c); `node` is the element the text came from, for messages. */
int mitsuba_parse_number(xmlNodePtr node, const char *text, double *out);
/* Copies the next token of text separated by commas and/or white space into token (size
 * bytes, truncated) and moves *cursor past it; 0 when no token is left. */
int mitsuba_next_token(const char **cursor, char *token, size_t size);
/* Up to `max` numbers separated by commas and/or white space; *count gets how many (more than
 * max is an error). */
int mitsuba_parse_numbers(xmlNodePtr node, const char *text, double *out, int max, int *count);
/* Exactly `expected` numbers. */
int mitsuba_parse_exact(xmlNodePtr node, const char *text, double *out, int expected);
/* One number (copied to all three) or three. */
int mitsuba_parse_one_or_three(xmlNodePtr node, const char *text, double out[3]);
/* A 3-vector from value="x, y, z" or from x= y= z= attributes (missing ones: fallback). */
int mitsuba_attr_vector(xmlNodePtr node, double fallback, double out[3]);

/* Properties, the children of a plugin element found by their name (mitsuba_values.c). Each
 * reader sets *out to the fallback when the property is absent; a property of another element
 * type than expected is an error. */
xmlNodePtr mitsuba_prop_find(xmlNodePtr plugin, const char *name);
/* *prop = the property `name` if present (NULL otherwise), checked to be a <tag> or <also>
 * (also may be NULL). */
int mitsuba_prop_element(xmlNodePtr plugin, const char *name, const char *tag, const char *also,
                         xmlNodePtr *prop);
int mitsuba_prop_float(xmlNodePtr plugin, const char *name, double fallback, double *out);
int mitsuba_prop_int(xmlNodePtr plugin, const char *name, long fallback, long *out);
int mitsuba_prop_bool(xmlNodePtr plugin, const char *name, int fallback, int *out);
int mitsuba_prop_string(xmlNodePtr plugin, const char *name, const char *fallback,
                        const char **out);
/* A <point> or <vector>; *found tells whether it was there (out is untouched when not). */
int mitsuba_prop_vector(xmlNodePtr plugin, const char *name, double out[3], int *found);
/* A <transform> (mitsuba_transform.c); the identity when absent. */
int mitsuba_prop_transform(xmlNodePtr plugin, const char *name, xform *out);

/* `written` resolved against the directory of the file that names it (the file of `node`),
 * then the scene's; malloc'd. */
static inline char *mitsuba_resolve_path(const loader *ld, xmlNodePtr node, const char *written)
{
    return mitsuba_resolve(mitsuba_node_file(node), ld->s->dir, written, NULL);
}

/* The id table (mitsuba_ids.c). Registers node under its id attribute (none: nothing to do). */
int mitsuba_id_register(loader *ld, xmlNodePtr node);
/* The declaration a <ref id=...> points to; NULL with the error set when unknown. */
mitsuba_id *mitsuba_ref_resolve(loader *ld, xmlNodePtr ref);
void mitsuba_ids_free(loader *ld);

/* Colours (mitsuba_color.c). Checks a <texture>: a bitmap with a filename. */
int mitsuba_texture_check(xmlNodePtr node);
/* A colour property (rgb, srgb, spectrum, float) with a grey default. A bitmap texture
 * (inline or by reference) is accepted where `texture` is non-NULL (*texture is set, rgb keeps
 * the default); elsewhere it is warned about and the default kept. */
int mitsuba_prop_color(loader *ld, xmlNodePtr plugin, const char *name, float fallback,
                       float rgb[3], xmlNodePtr *texture);

/* BSDFs (mitsuba_bsdf.c). Reads a <bsdf> into out without touching the scene. */
int mitsuba_parse_bsdf(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out);
/* Adds a parsed bsdf to the scene, loading its texture; returns the material index or -1. */
int mitsuba_bsdf_add(loader *ld, const bsdf_parsed *parsed, const char *name);
/* The material of a declared bsdf, added on its first reference; the index or -1. */
int mitsuba_bsdf_by_id(loader *ld, mitsuba_id *entry);
/* Mitsuba's default material (diffuse 0.5), added on first use; its index. */
int mitsuba_bsdf_default(loader *ld);

/* The top-level elements (mitsuba_sensor.c, mitsuba_emitter.c, mitsuba_shape.c). */
int mitsuba_load_sensor(loader *ld, xmlNodePtr node);
int mitsuba_load_emitter(loader *ld, xmlNodePtr node);
int mitsuba_load_shape(loader *ld, xmlNodePtr node);
/* An area emitter's radiance into light (the shape fills in the rest). */
int mitsuba_emitter_area(loader *ld, xmlNodePtr node, idmr_light *light);

#endif
