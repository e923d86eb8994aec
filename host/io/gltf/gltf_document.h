/* gltf_document.h — a glTF 2.0 file as its own JSON document and binary data (cJSON): what the
 * loader checks before Assimp reads the file (io/gltf/gltf_validate.h) and what the writer rewrites
 * (io/gltf/gltf.h: gltf_write_reduced) without going through Assimp.
 *
 * A .gltf file is its JSON text; a .glb file is a 12-byte header ("glTF", version 2, total
 * length), a JSON chunk and an optional BIN chunk (each an 8-byte length and type, then the
 * data padded to 4 bytes), all little-endian. Buffer i's bytes are the BIN chunk (a .glb's
 * buffer 0 without a uri), a base64 data: URI, or a file its uri names relative to the glTF
 * file (percent-encoded, as URIs are). Every error names the file and where in it the fault
 * is: a line and column of the JSON text, a byte offset of a GLB, or a JSON pointer
 * (/buffers/2/uri). */
#ifndef IDMR_GLTF_DOCUMENT_H
#define IDMR_GLTF_DOCUMENT_H

#include <stddef.h>

#include <cjson/cJSON.h>

#include "core/xform.h"

typedef struct gltf_bytes {
    unsigned char *data;
    size_t size;
} gltf_bytes;

typedef struct gltf_document {
    char *path;
    char *dir;          /* the directory URIs resolve from ("" for the working directory) */
    int binary;         /* read from a .glb container */
    cJSON *json;        /* the document; the caller may change it */
    gltf_bytes bin;     /* the .glb's BIN chunk (data NULL when it has none), inside `file` */
    gltf_bytes file;    /* a .glb's bytes, whole (the BIN chunk is not copied) */
    int has_bin;        /* the .glb has a BIN chunk, at byte bin_offset (also once released) */
    size_t bin_offset;
    gltf_bytes *loaded; /* per entry of the original buffers array, loaded on first use */
    int buffer_count;   /* entries of `loaded` */
} gltf_document;

/* Reads `path`: a .glb by its magic ("glTF"), else JSON text. A file named .glb that is no GLB,
 * or one named .gltf that is, is refused (Assimp picks its reader by the name). 0, or -1 with
 * the error set (IDMR_EXIT_INPUT) naming the file and where it is wrong (the line and column
 * of a JSON fault, and in a .glb its byte offset); `doc` is zeroed on failure. */
int gltf_document_read(const char *path, gltf_document *doc);

/* The bytes of buffer `index` as the file had it (`buffer` is its JSON object: uri and
 * byteLength are read from it), at least byteLength of them; loaded once and kept (a .glb's
 * BIN chunk is not copied). NULL with the error set when they cannot be read, the base64 of a
 * data: URI is not well formed, or they are fewer than byteLength. */
const gltf_bytes *gltf_document_buffer(gltf_document *doc, int index, const cJSON *buffer);

/* The bytes of a data: URI (base64, its media type printable ASCII and short enough for
 * Assimp 5.2) into *out (malloc'd). 0, or -1 with *bad the offset in `uri` of the first
 * character at fault and *why what is wrong. */
int gltf_data_uri(const char *uri, gltf_bytes *out, size_t *bad, const char **why);

/* Frees the buffers loaded so far, and a .glb's bytes (gltf_document_buffer loads them again
 * when asked). */
void gltf_document_release_buffers(gltf_document *doc);

void gltf_document_free(gltf_document *doc);

/* Whether a uri has a scheme (data:, http:, file:): not a path relative to the glTF file. */
int gltf_uri_has_scheme(const char *uri);

/* A uri's path with %XX sequences decoded (malloc'd). */
char *gltf_uri_decode(const char *uri);

/* A path as a uri: every byte but letters, digits, "-._~/" percent-encoded (malloc'd). */
char *gltf_uri_encode(const char *path);

/* A node's local transform (row-major, xform.h): its matrix (column-major in the file), else
 * translation × rotation × scale, each where given (glTF's order, which Assimp reads the same).
 * Values that are missing or not numbers count as absent. */
xform gltf_node_transform(const cJSON *node);

/* Replaces every number in `item` by the shortest decimal text that reads back as the same
 * double (an integer below 10^15 as an integer; a raw item, printed as it is): cJSON prints a
 * number with 15 digits whenever they come close to it, which moves the last bits of a value such
 * as a float's min and max. Call it last, right before printing: cJSON_IsNumber() no longer holds
 * for them. */
void gltf_numbers_exact(cJSON *item);

/* Writes `json` and `bin` (may be empty) as a .glb to `path`, atomically (core/files.h). 0, or
 * -1 with the error set. */
int gltf_write_glb(const char *path, const cJSON *json, const unsigned char *bin, size_t size);

#endif
