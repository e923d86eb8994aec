/* pbrt_loader.h — what the files of the pbrt-v4 reader share (internal: the public API is
 * pbrt.h, whose comment says what is read).
 *
 * A file is read whole into memory and cut into tokens (pbrt_lexer.c); the statement walk
 * (pbrt_document.c) keeps pbrt's graphics state (CTM, ReverseOrientation, material, area light)
 * and hands each statement with its parameter list (pbrt_params.c) to the reader of its kind.
 * The files, one job each:
 *
 *   pbrt_lexer.c     tokens: words, numbers, quoted strings, brackets; comments skipped; each
 *                    token with its line and byte offset
 *   pbrt_params.c    parameter lists ("type name" value(s)) and typed look-ups; unused ones
 *                    warned about
 *   pbrt_messages.c  errors and warnings naming file, line and statement; warnings once each
 *   pbrt_document.c  the statement walk, graphics state, transforms, Include, objects and
 *                    instances, pbrt_load()
 *   pbrt_camera.c    Camera and Film → idmr_camera
 *   pbrt_material.c  Texture, Material, MakeNamedMaterial → materials
 *   pbrt_light.c     LightSource and AreaLightSource → lights, the infinite light's map
 *   pbrt_shape.c     Shape → world-space meshes
 *   pbrt_write.c     the reduced scene's text (pbrt_write_reduced, pbrt_mesh_to_object_space)
 *
 * Every function here that can fail returns -1 with the error set and 0 on success, unless it
 * says otherwise. */
#ifndef IDMR_PBRT_LOADER_H
#define IDMR_PBRT_LOADER_H

#include <stddef.h>

#include "core/scene.h"
#include "io/pbrt/pbrt.h"
#include "core/spectrum.h"
#include "core/xform.h"

/* ---- tokens (pbrt_lexer.c) ---- */

typedef enum pbrt_token_kind {
    PBRT_TOKEN_END,    /* the end of the text */
    PBRT_TOKEN_WORD,   /* an unquoted word: a statement keyword, true/false */
    PBRT_TOKEN_NUMBER, /* an unquoted token starting with a digit, a sign or a dot */
    PBRT_TOKEN_STRING, /* "..." (text is the content between the quotes, escapes not undone) */
    PBRT_TOKEN_OPEN,   /* [ */
    PBRT_TOKEN_CLOSE,  /* ] */
} pbrt_token_kind;

typedef struct pbrt_token {
    pbrt_token_kind kind;
    const char *text; /* points into the file's text */
    size_t length;
    size_t offset; /* byte offset of the token's first character (a string's opening quote) */
    size_t end;    /* byte offset just past it (past a string's closing quote) */
    int line;
} pbrt_token;

typedef struct pbrt_lexer {
    const char *file; /* for messages */
    const char *text;
    size_t size;
    size_t pos;
    int line;
    pbrt_token peeked;
    int has_peeked;
} pbrt_lexer;

/* A lexer over text[0, size) (not copied; it must outlive the lexer). */
void pbrt_lexer_init(pbrt_lexer *lx, const char *file, const char *text, size_t size);
/* The next token into *out (PBRT_TOKEN_END at the end); -1 with the error set on an
 * unterminated string or a stray character. */
int pbrt_lexer_next(pbrt_lexer *lx, pbrt_token *out);
/* The next token without taking it. */
int pbrt_lexer_peek(pbrt_lexer *lx, pbrt_token *out);
/* A string token's content with its escapes (\n \t \\ \" ...) undone; malloc'd. */
char *pbrt_token_string(const pbrt_token *t);
/* Whether token t is the word `word`. */
int pbrt_token_is(const pbrt_token *t, const char *word);
/* Parses a number token strictly (the whole token, finite); -1 with the error set naming
 * file and line otherwise. */
int pbrt_token_number(const pbrt_lexer *lx, const pbrt_token *t, double *out);

/* ---- parameter lists (pbrt_params.c) ---- */

typedef struct pbrt_param {
    char *type; /* float, integer, bool, string, texture, rgb, spectrum, blackbody, point2, ... */
    char *name;
    double *numbers; /* numbers and bools (1/0) */
    size_t number_count;
    char **strings; /* strings, textures, named spectra */
    size_t string_count;
    int line;
    size_t offset, end; /* the parameter's span in the file: its "type name" to its last value */
    int used;
} pbrt_param;

typedef struct pbrt_params {
    pbrt_param *items;
    size_t count;
} pbrt_params;

/* Reads the parameter list following a statement's arguments: pairs of "type name" and a value
 * ([ values ] or one unbracketed value) until the next token is not a string. Checks the
 * values against the type (numbers for float, integer, point*, vector*, normal*, rgb,
 * blackbody; strings for string and texture; bools for bool; numbers or one string for
 * spectrum) and the count (a multiple of 2 or 3 for the vector types, exactly 3 for rgb). */
int pbrt_params_read(pbrt_lexer *lx, pbrt_params *out);
void pbrt_params_free(pbrt_params *params);

/* The parameter `name` (any type, marked used), or NULL. */
pbrt_param *pbrt_param_find(pbrt_params *params, const char *name);
/* The parameter `name` checked to have one of the types (NULL-terminated, the first named in
 * the message) and `count` values (0: any); *out NULL when absent. 0, or -1 with the error set
 * (file and line). */
int pbrt_param_typed(const char *file, pbrt_params *params, const char *name,
                     const char *const *types, size_t count, pbrt_param **out);
/* Typed look-ups: the fallback when absent; a parameter of another type, or with another count
 * than one value, is an error naming it. */
int pbrt_param_float(const char *file, pbrt_params *params, const char *name, double fallback,
                     double *out);
int pbrt_param_int(const char *file, pbrt_params *params, const char *name, long fallback,
                   long *out);
int pbrt_param_bool(const char *file, pbrt_params *params, const char *name, int fallback,
                    int *out);
int pbrt_param_string(const char *file, pbrt_params *params, const char *name,
                      const char *fallback, const char **out);
/* A point/vector of 3 (point3, point, vector3, vector, normal, normal3). */
/* A "spectrum" parameter given as wavelength-value pairs (nm, increasing) as linear RGB for
 * `use`; -1 with the error set (file and line) where the wavelengths do not increase. */
int pbrt_sampled_spectrum(const char *file, const pbrt_param *p, const char *name,
                          spectrum_use use, float out[3]);
int pbrt_param_point3(const char *file, pbrt_params *params, const char *name,
                      const double fallback[3], double out[3]);
/* Warns (once per statement kind and parameter) about each parameter no reader used. */
void pbrt_params_warn_unused(const char *file, const char *statement, const pbrt_params *params);

/* ---- messages (pbrt_messages.c) ---- */

/* Sets "file:line: what" as the error (IDMR_EXIT_INPUT); returns -1. */
int pbrt_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Prints "file:line: what" as a warning unless the same `what` was warned before in this load
 * (pbrt_warnings_reset() starts a load). */
void pbrt_warn(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void pbrt_warnings_reset(void);

/* ---- the loader's state (pbrt_document.c and the readers) ---- */

/* A material as read, added to the scene when a shape first uses it. */
typedef struct pbrt_material {
    char *name; /* MakeNamedMaterial's name, or "<type>@<file's base name>:<line>" */
    char *type; /* the pbrt material type */
    idmr_material material;
    char *texture_file; /* resolved image for the reflectance, or NULL */
    int scene_index;    /* -1 until a shape uses it */
} pbrt_material;

/* A Texture statement. */
typedef struct pbrt_texture {
    char *name;
    char *class_name; /* imagemap, constant, scale, ... */
    char *file;       /* imagemap: the resolved filename */
    float value[3];   /* what the texture stands for where it is not an image */
    int is_float;     /* a "float" texture (else "spectrum") */
} pbrt_texture;

/* The area light that shapes get (AreaLightSource). */
typedef struct pbrt_area_light {
    int active;
    float radiance[3];
} pbrt_area_light;

typedef struct pbrt_graphics_state {
    xform ctm;
    int reverse_orientation;
    int material; /* index into loader.materials, or -1: pbrt's default diffuse 0.5 */
    pbrt_area_light area_light;
} pbrt_graphics_state;

/* A shape inside ObjectBegin/End, kept until each ObjectInstance puts a copy in the world. */
typedef struct pbrt_object_shape {
    mesh_data mesh; /* in the object's space (the CTM at the Shape applied) */
    char *name;
    char *shape_type;
    char *file;     /* mesh file, or NULL */
    char *xml_file; /* file of the Shape statement */
    int line;
    long offset;
    xform object_to_world; /* the CTM at the Shape */
    int flipped;
    int file_normals, flat_normals;
    int material; /* loader material index, or -1 */
    int copied;        /* an ObjectInstance has placed it */
    size_t first_copy; /* then the scene mesh of its first copy, the representative that holds
                          its geometry (core/scene.h: instanced) */
} pbrt_object_shape;

typedef struct pbrt_object {
    char *name;
    pbrt_object_shape *shapes;
    size_t shape_count;
} pbrt_object;

typedef struct pbrt_named_xform {
    char *name;
    xform ctm;
} pbrt_named_xform;

typedef struct pbrt_loader {
    scene *s;
    char *scene_dir; /* relative paths resolve from here */
    pbrt_graphics_state state;
    pbrt_graphics_state *stack;
    char *stack_kind; /* 'A' AttributeBegin, 'T' TransformBegin, 'O' ObjectBegin */
    size_t stack_count;
    int in_world;
    pbrt_material *materials;
    size_t material_count;
    int default_material; /* scene index of the default diffuse 0.5, or -1 */
    pbrt_texture *textures;
    size_t texture_count;
    pbrt_named_xform *coordinate_systems;
    size_t coordinate_system_count;
    pbrt_object *objects;
    size_t object_count;
    pbrt_object *current_object; /* inside ObjectBegin, or NULL */
    int include_depth;
    /* The camera as read (pbrt_camera.c), set up once the film is known. */
    int camera_seen;
    xform camera_from_world;
    double fov;
    char *camera_file; /* the Camera statement's file (malloc'd), for messages */
    int camera_line;
    long film_width, film_height;
} pbrt_loader;

/* A whole file in a malloc'd, NUL-terminated buffer (*size its bytes); NULL with the error set
 * naming the file. For the reader and the writer (pbrt_write.c). */
char *pbrt_read_text(const char *path, size_t *size);

/* A resolved path for `written` (from the scene's directory unless absolute); malloc'd. */
char *pbrt_resolve_path(const pbrt_loader *ld, const char *written);

/* The readers. Each gets the statement's file and line, its arguments, and its parameters (the
 * caller warns about what they did not use). */
int pbrt_read_camera(pbrt_loader *ld, const char *file, int line, const char *type,
                     pbrt_params *params);
int pbrt_read_film(pbrt_loader *ld, const char *file, int line, const char *type,
                   pbrt_params *params);
/* Sets the scene's camera from what Camera and Film gave (at WorldBegin or the end). */
int pbrt_camera_finish(pbrt_loader *ld);

int pbrt_read_texture(pbrt_loader *ld, const char *file, int line, const char *name,
                      const char *type, const char *class_name, pbrt_params *params);
/* Reads a material (type from `type`, or the "string type" parameter when type is NULL) into
 * a new entry of ld->materials; returns its index or -1. */
int pbrt_read_material(pbrt_loader *ld, const char *file, int line, const char *name,
                       const char *type, pbrt_params *params);
/* The named material's index, or -1 (no error set). */
int pbrt_find_material(const pbrt_loader *ld, const char *name);
/* The scene material index of loader material `index` (-1: the default), added on first use;
 * -1 with the error set when its texture cannot be read. */
int pbrt_material_scene_index(pbrt_loader *ld, int index);

int pbrt_read_area_light(pbrt_loader *ld, const char *file, int line, const char *type,
                         pbrt_params *params);
int pbrt_read_light(pbrt_loader *ld, const char *file, int line, const char *type,
                    pbrt_params *params);
/* Colour of a light's spectrum parameter `name` (rgb as is; blackbody, named and sampled
 * spectra normalised to luminance 1, as pbrt-v4 normalises light spectra); fallback when
 * absent. */
int pbrt_light_color(pbrt_loader *ld, const char *file, pbrt_params *params, const char *name,
                     const float fallback[3], float out[3]);

/* A colour parameter of a material: rgb, spectrum (sampled, named, or constant), blackbody,
 * float; a texture's stand-in value (and *texture_file its image, when texture_file is
 * non-NULL and the texture is an imagemap). */
int pbrt_material_color(pbrt_loader *ld, const char *file, pbrt_params *params,
                        const char *name, const float fallback[3], float out[3],
                        char **texture_file);

int pbrt_read_shape(pbrt_loader *ld, const char *file, int line, long offset, const char *type,
                    pbrt_params *params);
/* Puts a copy of every shape of object `name` into the world under `instance_to_world`. */
int pbrt_instance_object(pbrt_loader *ld, const char *file, int line, const char *name,
                         const xform *instance_to_world);
void pbrt_objects_free(pbrt_loader *ld);

#endif
