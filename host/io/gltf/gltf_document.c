/* gltf_document.c — glTF and GLB files as JSON documents and bytes (see gltf_document.h). */
#include "io/gltf/gltf_document.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/error.h"
#include "core/files.h"
#include "io/mitsuba_paths.h"

enum {
    GLB_MAGIC = 0x46546C67,      /* "glTF" */
    GLB_CHUNK_JSON = 0x4E4F534A, /* "JSON" */
    GLB_CHUNK_BIN = 0x004E4942,  /* "BIN\0" */
    GLB_HEADER = 12,
    GLB_CHUNK_HEADER = 8,
};

static uint32_t read_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void write_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

/* The whole regular file `path` into *out (one byte more, zeroed: text can be parsed in
 * place). 0, or -1 with the error set naming `what` (the file as the document names it). */
static int read_all(const char *path, const char *what, gltf_bytes *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f)
        return error_set(IDMR_EXIT_INPUT, "%s: cannot read it: %s", what, strerror(errno));
    struct stat info;
    if (fstat(fileno(f), &info) != 0 || !S_ISREG(info.st_mode)) {
        fclose(f);
        return error_set(IDMR_EXIT_INPUT, "%s: not a regular file", what);
    }
    size_t size = (size_t)info.st_size;
    unsigned char *data = xmalloc(size + 1);
    size_t got = fread(data, 1, size, f);
    int failed = ferror(f);
    fclose(f);
    if (failed || got != size) {
        free(data);
        return error_set(IDMR_EXIT_INPUT, "%s: read %zu of its %zu bytes", what, got, size);
    }
    data[size] = 0;
    out->data = data;
    out->size = size;
    return 0;
}

/* The line and column (both from 1; a column counts bytes) of byte `offset` of `text`. */
static void line_column(const char *text, size_t offset, size_t *line, size_t *column)
{
    *line = 1, *column = 1;
    for (size_t i = 0; i < offset; i++) {
        if (text[i] == '\n')
            ++*line, *column = 1;
        else
            ++*column;
    }
}

/* What stands at byte `offset` of a JSON text of `length` bytes that cJSON could not read. */
static void describe_fault(const char *text, size_t length, size_t *offset, char *what,
                           size_t size)
{
    size_t rest = *offset;
    while (rest < length && strchr(" \t\r\n", text[rest]) && text[rest])
        rest++;
    if (rest >= length) /* only white space after where cJSON stopped: the text ends early */
        *offset = length;
    if (rest < length && strchr("[{\"", text[rest]) && text[rest]) {
        /* cJSON stops at the start of a value it could not finish: when the value never
         * closes, the text ends inside it */
        int depth = 0, in_string = 0;
        size_t at = rest;
        for (; at < length; at++) {
            char c = text[at];
            if (in_string) {
                if (c == '\\')
                    at++;
                else if (c == '"')
                    in_string = 0;
            } else if (c == '"') {
                in_string = 1;
            } else if (c == '[' || c == '{') {
                depth++;
            } else if (c == ']' || c == '}') {
                depth--;
            }
            if (!in_string && depth == 0)
                break;
        }
        if (at >= length)
            *offset = length;
    }
    unsigned char c = *offset < length ? (unsigned char)text[*offset] : 0;
    if (*offset >= length)
        snprintf(what, size, "the text ends inside the JSON document (cut short?)");
    else if (c == 0)
        snprintf(what, size, "a NUL byte inside the JSON document");
    else if (c >= 0x20 && c < 0x7F)
        snprintf(what, size, "not valid JSON at '%c'", c);
    else
        snprintf(what, size, "not valid JSON at byte 0x%02X", c);
}

/* Sets the error for a fault at byte `offset` of the JSON text that starts at byte `base` of
 * the file: its line and column, and in a .glb its byte offset as well. */
static int json_fault(const gltf_document *doc, const char *text, size_t offset, size_t base,
                      const char *what)
{
    size_t line, column;
    line_column(text, offset, &line, &column);
    if (doc->binary)
        return error_set(IDMR_EXIT_INPUT, "%s: byte %zu (line %zu, column %zu of the JSON chunk): %s",
                         doc->path, base + offset, line, column, what);
    return error_set(IDMR_EXIT_INPUT, "%s: line %zu, column %zu: %s", doc->path, line, column,
                     what);
}

/* The offset of the first byte of `text` that is not well-formed UTF-8 (no overlong forms,
 * surrogates or code points above U+10FFFF), or `length`. */
static size_t utf8_invalid(const char *text, size_t length)
{
    const unsigned char *t = (const unsigned char *)text;
    for (size_t i = 0; i < length;) {
        unsigned char c = t[i];
        size_t n = c < 0x80 ? 1 : c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3
                              : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
        if (!n || i + n > length)
            return i;
        for (size_t k = 1; k < n; k++)
            if ((t[i + k] & 0xC0) != 0x80)
                return i;
        if ((c == 0xE0 && t[i + 1] < 0xA0) || (c == 0xED && t[i + 1] >= 0xA0) ||
            (c == 0xF0 && t[i + 1] < 0x90) || (c == 0xF4 && t[i + 1] >= 0x90))
            return i;
        i += n;
    }
    return length;
}

/* Parses `length` bytes of JSON text that start at byte `base` of the file. Only white space
 * (and a GLB's padding) may follow the document. */
static int parse_json(gltf_document *doc, const char *text, size_t length, size_t base)
{
    if (length >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) /* a UTF-8 byte-order mark */
        text += 3, length -= 3, base += 3;
    const char *end = NULL;
    char what[128];
    size_t invalid = utf8_invalid(text, length);
    if (invalid < length)
        return json_fault(doc, text, invalid, base, "not UTF-8 text (glTF's JSON is UTF-8)");
    doc->json = cJSON_ParseWithLengthOpts(text, length, &end, 0);
    if (!doc->json) {
        size_t offset = end && end >= text && end <= text + length ? (size_t)(end - text) : 0;
        describe_fault(text, length, &offset, what, sizeof what);
        return json_fault(doc, text, offset, base, what);
    }
    for (size_t at = (size_t)(end - text); at < length; at++)
        if (!strchr(" \t\r\n", text[at]) && !(doc->binary && text[at] == '\0'))
            return json_fault(doc, text, at, base, "text after the end of the JSON document");
    if (!cJSON_IsObject(doc->json))
        return json_fault(doc, text, 0, base, "the document is not a JSON object");
    return 0;
}

/* The .glb container in doc->file (see gltf_document.h). */
static int read_glb(gltf_document *doc)
{
    const unsigned char *p = doc->file.data;
    size_t size = doc->file.size;
    if (size < GLB_HEADER + GLB_CHUNK_HEADER)
        return error_set(IDMR_EXIT_INPUT, "%s: %zu bytes: too short for a GLB header and its "
                         "JSON chunk (20 bytes)", doc->path, size);
    if (read_u32(p + 4) != 2)
        return error_set(IDMR_EXIT_INPUT, "%s: byte 4: GLB version %u (only 2 is read)", doc->path,
                         read_u32(p + 4));
    size_t total = read_u32(p + 8); /* what follows it is not the GLB's */
    if (total > size || total < GLB_HEADER + GLB_CHUNK_HEADER)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: byte 8: the header gives a length of %zu bytes, the file has %zu%s",
                         doc->path, total, size, total > size ? " (cut short?)" : "");
    size_t at = GLB_HEADER;
    for (int chunk = 0; at < total; chunk++) {
        if (total - at < GLB_CHUNK_HEADER)
            return error_set(IDMR_EXIT_INPUT, "%s: byte %zu: a chunk header cut short (%zu of its "
                             "8 bytes before the GLB's end)", doc->path, at, total - at);
        size_t length = read_u32(p + at), type = read_u32(p + at + 4);
        size_t start = at + GLB_CHUNK_HEADER;
        if (length > total - start)
            return error_set(IDMR_EXIT_INPUT,
                             "%s: byte %zu: a chunk of %zu bytes, but %zu remain in the GLB",
                             doc->path, at, length, total - start);
        if (chunk == 0 && type != GLB_CHUNK_JSON)
            return error_set(IDMR_EXIT_INPUT,
                             "%s: byte %zu: the first chunk is of type 0x%08zX, not JSON",
                             doc->path, at + 4, type);
        if (chunk == 0 && parse_json(doc, (const char *)p + start, length, start))
            return -1;
        if (chunk == 1 && type == GLB_CHUNK_BIN) {
            doc->bin.data = (unsigned char *)p + start;
            doc->bin.size = length;
            doc->has_bin = 1;
            doc->bin_offset = start;
        }
        at = start + ((length + 3) & ~(size_t)3);
    }
    return 0;
}

/* Whether the file extension of `path` is `extension` (any case). */
static int named(const char *path, const char *extension)
{
    const char *dot = strrchr(path, '.');
    return dot && strcasecmp(dot, extension) == 0;
}

int gltf_document_read(const char *path, gltf_document *doc)
{
    memset(doc, 0, sizeof *doc);
    doc->path = xstrdup(path);
    doc->dir = mitsuba_path_directory(path);
    int status = read_all(path, path, &doc->file);
    if (!status) {
        doc->binary = doc->file.size >= 4 && read_u32(doc->file.data) == GLB_MAGIC;
        if (doc->binary && named(path, ".gltf"))
            status = error_set(IDMR_EXIT_INPUT, "%s: byte 0: a GLB file (it begins with 'glTF') "
                               "named as JSON text (.gltf): name it .glb", path);
        else if (!doc->binary && named(path, ".glb"))
            status = error_set(IDMR_EXIT_INPUT, "%s: byte 0: not a GLB file: a .glb begins with "
                               "'glTF', this one with %02X %02X %02X %02X%s", path,
                               doc->file.size > 0 ? doc->file.data[0] : 0,
                               doc->file.size > 1 ? doc->file.data[1] : 0,
                               doc->file.size > 2 ? doc->file.data[2] : 0,
                               doc->file.size > 3 ? doc->file.data[3] : 0,
                               doc->file.size < 4 ? " (the file is shorter)" : "");
    }
    if (!status)
        status = doc->binary ? read_glb(doc)
                             : parse_json(doc, (const char *)doc->file.data, doc->file.size, 0);
    if (!status && !doc->binary) { /* the text is parsed: only a .glb's bytes are kept */
        free(doc->file.data);
        memset(&doc->file, 0, sizeof doc->file);
    }
    if (!status) {
        const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(doc->json, "buffers");
        doc->buffer_count = cJSON_IsArray(buffers) ? cJSON_GetArraySize(buffers) : 0;
        doc->loaded = xcalloc((size_t)doc->buffer_count + 1, sizeof *doc->loaded);
    } else {
        gltf_document_free(doc);
    }
    return status;
}

void gltf_document_release_buffers(gltf_document *doc)
{
    for (int i = 0; i < doc->buffer_count; i++) {
        free(doc->loaded[i].data);
        memset(&doc->loaded[i], 0, sizeof doc->loaded[i]);
    }
    free(doc->file.data); /* the JSON is parsed: only the BIN chunk was still needed */
    memset(&doc->file, 0, sizeof doc->file);
    doc->bin.data = NULL;
}

/* A released .glb's BIN chunk, read again. */
static int reload_bin(gltf_document *doc)
{
    if (read_all(doc->path, doc->path, &doc->file))
        return -1;
    if (doc->file.size < doc->bin_offset + doc->bin.size)
        return error_set(IDMR_EXIT_INPUT, "%s: shorter than when it was read (changed since?)",
                         doc->path);
    doc->bin.data = doc->file.data + doc->bin_offset;
    return 0;
}

void gltf_document_free(gltf_document *doc)
{
    gltf_document_release_buffers(doc);
    free(doc->loaded);
    cJSON_Delete(doc->json);
    free(doc->dir);
    free(doc->path);
    memset(doc, 0, sizeof *doc);
}

/* The value of one base64 digit, or -1. */
static int base64_digit(unsigned char c)
{
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    if (c >= 'a' && c <= 'z')
        return c - 'a' + 26;
    if (c >= '0' && c <= '9')
        return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
}

/* Decodes base64 text (RFC 4648: padding optional, but where it is, the text is whole groups of
 * four; nothing outside the alphabet, no white space); 0, or -1 with the offset of the first
 * byte at fault in *bad and what is wrong in *why. */
static int base64_decode(const char *text, gltf_bytes *out, size_t *bad, const char **why)
{
    size_t length = strlen(text), padded = length;
    int pad = 0;
    while (pad < 2 && length > 0 && text[length - 1] == '=')
        length--, pad++;
    out->data = NULL;
    out->size = 0;
    for (size_t i = 0; i < length; i++)
        if (base64_digit((unsigned char)text[i]) < 0) {
            *bad = i;
            *why = text[i] == '=' ? "padding ('=') before the end" : "not a base64 digit";
            return -1;
        }
    if (length % 4 == 1 || (pad && padded % 4 != 0)) { /* one digit alone holds no byte */
        *bad = padded;
        *why = "the base64 text ends inside a group of four digits (cut short?)";
        return -1;
    }
    out->data = xmalloc(length / 4 * 3 + 3);
    uint32_t bits = 0;
    int held = 0;
    for (size_t i = 0; i < length; i++) {
        bits = bits << 6 | (uint32_t)base64_digit((unsigned char)text[i]);
        held += 6;
        if (held >= 8) {
            held -= 8;
            out->data[out->size++] = (unsigned char)(bits >> held);
        }
    }
    return 0;
}

int gltf_data_uri(const char *uri, gltf_bytes *out, size_t *bad, const char **why)
{
    const char *comma = strchr(uri, ',');
    memset(out, 0, sizeof *out);
    *bad = 0;
    if (!comma || comma - uri < 12 || strncmp(comma - 7, ";base64", 7) != 0) {
        *why = "a data: URI that is not base64 (glTF embeds data as data:...;base64,...)";
        return -1;
    }
    for (const char *c = uri + 5; c < comma; c++)
        if (*c <= ' ' || *c >= 0x7F) { /* a media type is printable ASCII */
            *bad = (size_t)(c - uri);
            *why = "not a character of a media type";
            return -1;
        }
    if (comma - uri >= 127) { /* Assimp 5.2 keeps the data's offset in a signed char */
        *bad = (size_t)(comma - uri);
        *why = "more characters before the data than Assimp 5.2 can skip (126)";
        return -1;
    }
    if (base64_decode(comma + 1, out, bad, why)) {
        *bad += (size_t)(comma + 1 - uri);
        return -1;
    }
    return 0;
}

/* The bytes of buffer `index` (not yet loaded) into *bytes; 0, or -1 with the error set. */
static int load_buffer(gltf_document *doc, int index, const cJSON *uri, gltf_bytes *bytes)
{
    if (!cJSON_IsString(uri))
        return error_set(IDMR_EXIT_INPUT, "%s: /buffers/%d/uri: not a string", doc->path, index);
    const char *text = uri->valuestring;
    if (strncmp(text, "data:", 5) == 0) {
        size_t bad;
        const char *why;
        if (gltf_data_uri(text, bytes, &bad, &why))
            return error_set(IDMR_EXIT_INPUT, "%s: /buffers/%d/uri: character %zu: %s",
                             doc->path, index, bad, why);
        return 0;
    }
    if (gltf_uri_has_scheme(text))
        return error_set(IDMR_EXIT_INPUT, "%s: /buffers/%d/uri '%s': not a local file", doc->path,
                         index, text);
    char *decoded = gltf_uri_decode(text);
    char *file = mitsuba_path_join(doc->dir, decoded);
    char what[4096];
    snprintf(what, sizeof what, "%s: /buffers/%d/uri '%s'", doc->path, index, file);
    int status = read_all(file, what, bytes);
    free(file);
    free(decoded);
    return status;
}

const gltf_bytes *gltf_document_buffer(gltf_document *doc, int index, const cJSON *buffer)
{
    if (index < 0 || index >= doc->buffer_count) {
        error_set(IDMR_EXIT_INPUT, "%s: /buffers/%d: no such buffer", doc->path, index);
        return NULL;
    }
    const gltf_bytes *bytes = &doc->loaded[index];
    const cJSON *uri = cJSON_GetObjectItemCaseSensitive(buffer, "uri");
    const cJSON *length = cJSON_GetObjectItemCaseSensitive(buffer, "byteLength");
    double byte_length = cJSON_IsNumber(length) ? length->valuedouble : -1;
    if (!uri) {
        if (doc->has_bin && !doc->bin.data && reload_bin(doc))
            return NULL;
        if (!(doc->binary && index == 0 && doc->bin.data)) {
            error_set(IDMR_EXIT_INPUT,
                      "%s: /buffers/%d: no uri, and not the BIN chunk of a GLB (%s)", doc->path,
                      index,
                      !doc->binary ? "a .gltf has none"
                      : index     ? "only buffer 0 can be it"
                                  : "the file has no BIN chunk");
            return NULL;
        }
        bytes = &doc->bin; /* not copied */
    } else if (!bytes->data && load_buffer(doc, index, uri, &doc->loaded[index])) {
        return NULL;
    }
    if (!(byte_length >= 0) || byte_length > (double)bytes->size) {
        error_set(IDMR_EXIT_INPUT, "%s: /buffers/%d/byteLength: %.0f, but %s holds %zu bytes",
                  doc->path, index, byte_length, uri ? "its uri" : "the BIN chunk", bytes->size);
        return NULL;
    }
    return bytes;
}

int gltf_uri_has_scheme(const char *uri)
{
    const char *c = uri;
    if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z')))
        return 0;
    while ((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
           *c == '+' || *c == '-' || *c == '.')
        c++;
    return *c == ':';
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

char *gltf_uri_decode(const char *uri)
{
    char *out = xmalloc(strlen(uri) + 1), *o = out;
    for (const char *c = uri; *c; c++) {
        int high = c[0] == '%' ? hex_digit(c[1]) : -1, low = high >= 0 ? hex_digit(c[2]) : -1;
        if (low >= 0) {
            *o++ = (char)(high * 16 + low);
            c += 2;
        } else {
            *o++ = *c;
        }
    }
    *o = '\0';
    return out;
}

char *gltf_uri_encode(const char *path)
{
    static const char hex[] = "0123456789ABCDEF";
    char *out = xmalloc(3 * strlen(path) + 1), *o = out;
    for (const unsigned char *c = (const unsigned char *)path; *c; c++) {
        if ((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
            strchr("-._~/", *c)) {
            *o++ = (char)*c;
        } else {
            *o++ = '%';
            *o++ = hex[*c >> 4];
            *o++ = hex[*c & 15];
        }
    }
    *o = '\0';
    return out;
}

/* Reads object[name] as exactly `count` numbers; 0 when it is no such array. */
static int numbers_of(const cJSON *object, const char *name, double *values, int count)
{
    const cJSON *array = cJSON_GetObjectItemCaseSensitive(object, name), *item;
    if (!cJSON_IsArray(array) || cJSON_GetArraySize(array) != count)
        return 0;
    int i = 0;
    cJSON_ArrayForEach(item, array)
    {
        if (!cJSON_IsNumber(item))
            return 0;
        values[i++] = item->valuedouble;
    }
    return 1;
}

xform gltf_node_transform(const cJSON *node)
{
    double v[16];
    if (numbers_of(node, "matrix", v, 16)) {
        double rows[16];
        for (int row = 0; row < 4; row++)
            for (int col = 0; col < 4; col++)
                rows[4 * row + col] = v[4 * col + row];
        return xform_from_rows(rows);
    }
    xform t = xform_identity();
    if (numbers_of(node, "translation", v, 3))
        t = xform_translate(v[0], v[1], v[2]);
    if (numbers_of(node, "rotation", v, 4)) { /* x, y, z, w */
        double x = v[0], y = v[1], z = v[2], w = v[3];
        const double r[9] = {
            1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
            2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
        xform rotation = xform_from_3x3(r);
        t = xform_multiply(&t, &rotation);
    }
    if (numbers_of(node, "scale", v, 3)) {
        xform scale = xform_scale(v[0], v[1], v[2]);
        t = xform_multiply(&t, &scale);
    }
    return t;
}

void gltf_numbers_exact(cJSON *item)
{
    cJSON *child = item ? item->child : NULL;
    while (child) {
        cJSON *next = child->next;
        if (cJSON_IsNumber(child)) {
            char text[32];
            double value = child->valuedouble;
            if (value == floor(value) && fabs(value) < 1e15) /* an integer (an index) as one */
                snprintf(text, sizeof text, "%.0f", value);
            else
                for (int digits = 1; digits <= 17; digits++) {
                    snprintf(text, sizeof text, "%.*g", digits, value);
                    if (strtod(text, NULL) == value)
                        break;
                }
            cJSON *raw = cJSON_CreateRaw(text);
            raw->string = child->string; /* the member's name moves to its new value */
            raw->type |= child->type & cJSON_StringIsConst;
            child->string = NULL;
            cJSON_ReplaceItemViaPointer(item, child, raw);
        } else {
            gltf_numbers_exact(child);
        }
        child = next;
    }
}

int gltf_write_glb(const char *path, const cJSON *json, const unsigned char *bin, size_t size)
{
    char *text = cJSON_PrintUnformatted(json);
    if (!text)
        return error_set(IDMR_EXIT_FAILURE, "cannot format the glTF JSON of '%s'", path);
    size_t json_length = strlen(text), json_padded = (json_length + 3) & ~(size_t)3;
    size_t bin_padded = (size + 3) & ~(size_t)3;
    size_t total =
        GLB_HEADER + GLB_CHUNK_HEADER + json_padded + (size ? GLB_CHUNK_HEADER + bin_padded : 0);
    if (total > UINT32_MAX) {
        cJSON_free(text);
        return error_set(IDMR_EXIT_FAILURE, "'%s': %zu bytes, more than a GLB can hold (4 GiB)",
                         path, total);
    }
    unsigned char *glb = xcalloc(total, 1), *p = glb;
    write_u32(p, GLB_MAGIC), write_u32(p + 4, 2), write_u32(p + 8, (uint32_t)total);
    p += GLB_HEADER;
    write_u32(p, (uint32_t)json_padded), write_u32(p + 4, GLB_CHUNK_JSON);
    p += GLB_CHUNK_HEADER;
    memcpy(p, text, json_length);
    memset(p + json_length, ' ', json_padded - json_length); /* JSON pads with spaces */
    p += json_padded;
    if (size) {
        write_u32(p, (uint32_t)bin_padded), write_u32(p + 4, GLB_CHUNK_BIN);
        memcpy(p + GLB_CHUNK_HEADER, bin, size); /* BIN pads with zeros (calloc) */
    }
    cJSON_free(text);
    int status = files_write_atomic(path, glb, total);
    free(glb);
    return status;
}
