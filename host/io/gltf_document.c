/* gltf_document.c — glTF and GLB files as JSON documents and bytes (see gltf_document.h). */
#include "io/gltf_document.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

/* Parses `length` bytes of JSON text that start at byte `base` of the file. */
static int parse_json(gltf_document *doc, const char *text, size_t length, size_t base)
{
    if (length >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) /* a UTF-8 byte-order mark */
        text += 3, length -= 3, base += 3;
    const char *end = NULL;
    doc->json = cJSON_ParseWithLengthOpts(text, length, &end, 0);
    if (!doc->json) {
        size_t offset = end && end >= text ? (size_t)(end - text) : 0;
        return error_set(IDMR_EXIT_INPUT, "%s: byte %zu: not valid JSON", doc->path, base + offset);
    }
    if (!cJSON_IsObject(doc->json))
        return error_set(IDMR_EXIT_INPUT, "%s: byte %zu: the document is not a JSON object",
                         doc->path, base);
    return 0;
}

/* The .glb container in `file` (see gltf_document.h). */
static int read_glb(gltf_document *doc, const gltf_bytes *file)
{
    const unsigned char *p = file->data;
    if (file->size < GLB_HEADER + GLB_CHUNK_HEADER)
        return error_set(IDMR_EXIT_INPUT, "%s: %zu bytes: too short for a GLB header", doc->path,
                         file->size);
    if (read_u32(p + 4) != 2)
        return error_set(IDMR_EXIT_INPUT, "%s: byte 4: GLB version %u (only 2 is read)", doc->path,
                         read_u32(p + 4));
    size_t total = read_u32(p + 8); /* what follows it is not the GLB's */
    if (total > file->size || total < GLB_HEADER + GLB_CHUNK_HEADER)
        return error_set(IDMR_EXIT_INPUT,
                         "%s: byte 8: the header gives a length of %zu bytes, the file has %zu",
                         doc->path, total, file->size);
    size_t at = GLB_HEADER;
    for (int chunk = 0; at < total; chunk++) {
        if (total - at < GLB_CHUNK_HEADER)
            return error_set(IDMR_EXIT_INPUT, "%s: byte %zu: a chunk header cut short", doc->path,
                             at);
        size_t length = read_u32(p + at), type = read_u32(p + at + 4);
        size_t start = at + GLB_CHUNK_HEADER;
        if (length > total - start)
            return error_set(IDMR_EXIT_INPUT,
                             "%s: byte %zu: a chunk of %zu bytes, but %zu remain in the GLB",
                             doc->path, at, length, total - start);
        if (chunk == 0 && type != GLB_CHUNK_JSON)
            return error_set(IDMR_EXIT_INPUT, "%s: byte %zu: the first chunk is not JSON",
                             doc->path, at);
        if (chunk == 0 && parse_json(doc, (const char *)p + start, length, start))
            return -1;
        if (chunk == 1 && type == GLB_CHUNK_BIN) {
            doc->bin.data = xmalloc(length + 1);
            memcpy(doc->bin.data, p + start, length);
            doc->bin.size = length;
        }
        at = start + ((length + 3) & ~(size_t)3);
    }
    return 0;
}

int gltf_document_read(const char *path, gltf_document *doc)
{
    memset(doc, 0, sizeof *doc);
    doc->path = xstrdup(path);
    doc->dir = mitsuba_path_directory(path);
    gltf_bytes file;
    int status = read_all(path, path, &file);
    if (!status) {
        doc->binary = file.size >= 4 && read_u32(file.data) == GLB_MAGIC;
        status = doc->binary ? read_glb(doc, &file)
                             : parse_json(doc, (const char *)file.data, file.size, 0);
    }
    free(file.data);
    if (!status) {
        const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(doc->json, "buffers");
        doc->buffer_count = cJSON_IsArray(buffers) ? cJSON_GetArraySize(buffers) : 0;
        doc->loaded = xcalloc((size_t)doc->buffer_count + 1, sizeof *doc->loaded);
    } else {
        gltf_document_free(doc);
    }
    return status;
}

void gltf_document_free(gltf_document *doc)
{
    for (int i = 0; i < doc->buffer_count; i++)
        free(doc->loaded[i].data);
    free(doc->loaded);
    free(doc->bin.data);
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

/* Decodes base64 text (padding optional, nothing else allowed); 0, or -1 at the offset of the
 * first byte that is not base64 (*bad). */
static int base64_decode(const char *text, gltf_bytes *out, size_t *bad)
{
    size_t length = strlen(text);
    for (int pad = 0; pad < 2 && length > 0 && text[length - 1] == '='; pad++)
        length--;
    if (length % 4 == 1) { /* one digit alone holds no byte */
        *bad = length - 1;
        return -1;
    }
    out->data = xmalloc(length / 4 * 3 + 3);
    out->size = 0;
    uint32_t bits = 0;
    int held = 0;
    for (size_t i = 0; i < length; i++) {
        int digit = base64_digit((unsigned char)text[i]);
        if (digit < 0) {
            *bad = i;
            free(out->data);
            out->data = NULL;
            return -1;
        }
        bits = bits << 6 | (uint32_t)digit;
        held += 6;
        if (held >= 8) {
            held -= 8;
            out->data[out->size++] = (unsigned char)(bits >> held);
        }
    }
    return 0;
}

const gltf_bytes *gltf_document_buffer(gltf_document *doc, int index, const cJSON *buffer)
{
    if (index < 0 || index >= doc->buffer_count) {
        error_set(IDMR_EXIT_INPUT, "%s: buffers[%d]: no such buffer", doc->path, index);
        return NULL;
    }
    gltf_bytes *bytes = &doc->loaded[index];
    const cJSON *uri = cJSON_GetObjectItemCaseSensitive(buffer, "uri");
    const cJSON *length = cJSON_GetObjectItemCaseSensitive(buffer, "byteLength");
    double byte_length = cJSON_IsNumber(length) ? length->valuedouble : -1;
    if (!bytes->data) {
        int status;
        if (!uri) {
            if (!(doc->binary && index == 0 && doc->bin.data)) {
                error_set(IDMR_EXIT_INPUT,
                          "%s: buffers[%d]: no uri, and not the BIN chunk of a GLB", doc->path,
                          index);
                return NULL;
            }
            bytes->data = xmalloc(doc->bin.size + 1);
            memcpy(bytes->data, doc->bin.data, doc->bin.size);
            bytes->size = doc->bin.size;
            status = 0;
        } else if (!cJSON_IsString(uri)) {
            error_set(IDMR_EXIT_INPUT, "%s: buffers[%d].uri is not a string", doc->path, index);
            return NULL;
        } else if (strncmp(uri->valuestring, "data:", 5) == 0) {
            const char *comma = strchr(uri->valuestring, ',');
            size_t bad = 0;
            if (!comma || comma - uri->valuestring < 12 || strncmp(comma - 7, ";base64", 7) != 0)
                status = error_set(IDMR_EXIT_INPUT,
                                   "%s: buffers[%d].uri: a data: URI that is not base64", doc->path,
                                   index);
            else if (base64_decode(comma + 1, bytes, &bad))
                status =
                    error_set(IDMR_EXIT_INPUT, "%s: buffers[%d].uri: character %zu is not base64",
                              doc->path, index, (size_t)(comma + 1 - uri->valuestring) + bad);
            else
                status = 0;
        } else if (gltf_uri_has_scheme(uri->valuestring)) {
            status = error_set(IDMR_EXIT_INPUT, "%s: buffers[%d].uri '%s': not a local file",
                               doc->path, index, uri->valuestring);
        } else {
            char *decoded = gltf_uri_decode(uri->valuestring);
            char *file = mitsuba_path_join(doc->dir, decoded);
            char what[4096];
            snprintf(what, sizeof what, "%s: buffers[%d] '%s'", doc->path, index, file);
            status = read_all(file, what, bytes);
            free(file);
            free(decoded);
        }
        if (status)
            return NULL;
    }
    if (!(byte_length >= 0) || byte_length > (double)bytes->size) {
        error_set(IDMR_EXIT_INPUT, "%s: buffers[%d]: byteLength %.0f, but it holds %zu bytes",
                  doc->path, index, byte_length, bytes->size);
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
