/* mesh_stl.c — the STL reader (see mesh_stl.h): the format decided from the file's first bytes
 * and its size, ASCII read line by line through a small state machine, binary in blocks of
 * facets; corners welded at bit-identical positions through an open-addressing table. */
#include "io/mesh/mesh_stl.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "core/error.h"

#define STL_HEADER_BYTES 84 /* 80 bytes of header, the facet count */
#define STL_FACET_BYTES 50
#define STL_SNIFF_BYTES 512 /* bytes that must be text for a file to be read as ASCII */
#define EMPTY_SLOT 0xffffffffu

/* The mesh being built: welded positions and the triangles' corners. */
typedef struct stl_builder {
    const char *path;
    float *positions;
    uint32_t vertex_count, vertex_capacity;
    uint32_t *indices;
    uint64_t corner_count, corner_capacity;
    uint32_t *table; /* vertex per slot, EMPTY_SLOT when free; a power of two in size */
    size_t table_size;
} stl_builder;

static uint32_t position_hash(const uint32_t bits[3])
{
    uint32_t h = 0;
    for (int k = 0; k < 3; k++) {
        h ^= bits[k];
        h *= 0x9e3779b1u;
        h ^= h >> 15;
    }
    return h;
}

/* The position's bits, -0 folded into 0. */
static void position_bits(const float p[3], uint32_t bits[3])
{
    for (int k = 0; k < 3; k++) {
        float folded = p[k] + 0.0f;
        memcpy(&bits[k], &folded, sizeof bits[k]);
    }
}

static void table_insert(stl_builder *b, uint32_t vertex)
{
    uint32_t bits[3];
    position_bits(&b->positions[3 * (size_t)vertex], bits);
    size_t mask = b->table_size - 1;
    size_t slot = position_hash(bits) & mask;
    while (b->table[slot] != EMPTY_SLOT)
        slot = (slot + 1) & mask;
    b->table[slot] = vertex;
}

static void table_grow(stl_builder *b)
{
    b->table_size = b->table_size ? 2 * b->table_size : 1024;
    free(b->table);
    b->table = xmalloc(sizeof(uint32_t) * b->table_size);
    memset(b->table, 0xff, sizeof(uint32_t) * b->table_size);
    for (uint32_t v = 0; v < b->vertex_count; v++)
        table_insert(b, v);
}

/* Adds one corner at position p (finite): the vertex already there, or a new one. 0, or -1 with
 * the error set when the mesh outgrows 32-bit indices. */
static int add_corner(stl_builder *b, const float p[3])
{
    if (2 * ((size_t)b->vertex_count + 1) > b->table_size)
        table_grow(b);
    uint32_t bits[3];
    position_bits(p, bits);
    size_t mask = b->table_size - 1;
    size_t slot = position_hash(bits) & mask;
    uint32_t vertex = EMPTY_SLOT;
    for (; b->table[slot] != EMPTY_SLOT; slot = (slot + 1) & mask) {
        uint32_t other[3];
        position_bits(&b->positions[3 * (size_t)b->table[slot]], other);
        if (memcmp(bits, other, sizeof bits) == 0) {
            vertex = b->table[slot];
            break;
        }
    }
    if (vertex == EMPTY_SLOT) {
        if (b->vertex_count == UINT32_MAX - 1)
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': more than %u vertices",
                             b->path, UINT32_MAX - 1);
        if (b->vertex_count == b->vertex_capacity) {
            b->vertex_capacity = b->vertex_capacity ? 2 * b->vertex_capacity : 1024;
            b->positions = xrealloc(b->positions, 3 * sizeof(float) * b->vertex_capacity);
        }
        vertex = b->vertex_count++;
        memcpy(&b->positions[3 * (size_t)vertex], p, 3 * sizeof(float));
        b->table[slot] = vertex;
    }
    if (b->corner_count == 3 * (uint64_t)(UINT32_MAX / 3))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': more than %u triangles",
                         b->path, UINT32_MAX / 3);
    if (b->corner_count == b->corner_capacity) {
        b->corner_capacity = b->corner_capacity ? 2 * b->corner_capacity : 3072;
        b->indices = xrealloc(b->indices, sizeof(uint32_t) * b->corner_capacity);
    }
    b->indices[b->corner_count++] = vertex;
    return 0;
}

static void builder_free(stl_builder *b)
{
    free(b->positions);
    free(b->indices);
    free(b->table);
}

/* Hands the built mesh to `out` (whose arrays it takes over). */
static void builder_finish(stl_builder *b, mesh_data *out)
{
    out->vertex_count = b->vertex_count;
    out->triangle_count = (uint32_t)(b->corner_count / 3);
    out->positions = b->positions ? b->positions : xmalloc(sizeof(float));
    out->indices = b->indices ? b->indices : xmalloc(sizeof(uint32_t));
    b->positions = NULL;
    b->indices = NULL;
    free(b->table);
    b->table = NULL;
}

/* ---- binary ---- */

static uint32_t le32(const unsigned char *bytes)
{
    return (uint32_t)bytes[0] | (uint32_t)bytes[1] << 8 | (uint32_t)bytes[2] << 16 |
           (uint32_t)bytes[3] << 24;
}

static float le_float(const unsigned char *bytes)
{
    uint32_t bits = le32(bytes);
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

static int read_binary(FILE *f, uint32_t facets, stl_builder *b)
{
    enum { BLOCK = 4096 };
    unsigned char *block = xmalloc((size_t)BLOCK * STL_FACET_BYTES);
    int status = 0;
    if (fseek(f, STL_HEADER_BYTES, SEEK_SET) != 0)
        status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", b->path,
                           strerror(errno));
    for (uint32_t first = 0; !status && first < facets;) {
        uint32_t count = facets - first < BLOCK ? facets - first : BLOCK;
        if (fread(block, STL_FACET_BYTES, count, f) != count) {
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': it ends inside facet %u "
                               "(byte %llu); was it changed while read?",
                               b->path, first + 1,
                               (unsigned long long)STL_HEADER_BYTES +
                                   (unsigned long long)STL_FACET_BYTES * first);
            break;
        }
        for (uint32_t i = 0; !status && i < count; i++) {
            const unsigned char *record = block + (size_t)STL_FACET_BYTES * i;
            for (int corner = 0; !status && corner < 3; corner++) {
                float p[3];
                for (int k = 0; k < 3; k++)
                    p[k] = le_float(record + 12 + 12 * corner + 4 * k);
                if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
                    unsigned long long offset = STL_HEADER_BYTES +
                                                (unsigned long long)STL_FACET_BYTES * (first + i) +
                                                12 + 12 * (unsigned)corner;
                    status = error_set(IDMR_EXIT_INPUT,
                                       "cannot read mesh '%s': facet %u (byte %llu): vertex %d "
                                       "is (%g, %g, %g), not a finite point",
                                       b->path, first + i + 1, offset, corner + 1, (double)p[0],
                                       (double)p[1], (double)p[2]);
                    break;
                }
                status = add_corner(b, p);
            }
        }
        first += count;
    }
    free(block);
    return status;
}

/* ---- ASCII ---- */

typedef enum stl_state {
    OUTSIDE,   /* before "solid" or after "endsolid" */
    IN_SOLID,  /* "facet" or "endsolid" next */
    IN_FACET,  /* "outer loop" next */
    IN_LOOP,   /* "vertex" (three) or "endloop" next */
    AFTER_LOOP /* "endfacet" next */
} stl_state;

typedef struct stl_text {
    stl_builder *b;
    long line;
    stl_state state;
    uint64_t facet;  /* facets begun, 1-based number of the current one */
    int corners;     /* vertices read in the current loop */
    int solids;
} stl_text;

/* The next whitespace-separated word from *at into word (cut to size), advancing *at; 0 when
 * the line has none. */
static int next_word(const char **at, char *word, size_t size)
{
    const char *s = *at;
    while (*s && isspace((unsigned char)*s))
        s++;
    if (!*s)
        return 0;
    size_t length = 0;
    while (s[length] && !isspace((unsigned char)s[length]))
        length++;
    snprintf(word, size, "%.*s", (int)length, s);
    *at = s + length;
    return 1;
}

static int text_fail(const stl_text *t, const char *expected, const char *found)
{
    return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: expected %s, found '%s'",
                     t->b->path, t->line, expected, found);
}

/* "vertex x y z": three finite numbers and nothing after them. */
static int text_vertex(stl_text *t, const char *rest)
{
    float p[3];
    char word[64];
    for (int k = 0; k < 3; k++) {
        if (!next_word(&rest, word, sizeof word))
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a vertex needs 3 "
                             "numbers (x y z), it has %d",
                             t->b->path, t->line, k);
        char *end;
        errno = 0;
        double value = strtod(word, &end);
        if (*end || end == word || !isfinite(value) || !isfinite((float)value))
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: '%s' is not a "
                             "finite number",
                             t->b->path, t->line, word);
        p[k] = (float)value;
    }
    if (next_word(&rest, word, sizeof word))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a vertex has 3 "
                         "numbers, found '%s' after them",
                         t->b->path, t->line, word);
    return add_corner(t->b, p);
}

/* One line of an ASCII file. */
static int text_line(stl_text *t, const char *line)
{
    char keyword[64], second[64];
    const char *rest = line;
    if (!next_word(&rest, keyword, sizeof keyword))
        return 0; /* a blank line */
    switch (t->state) {
    case OUTSIDE:
        if (strcasecmp(keyword, "solid") != 0)
            return text_fail(t, "'solid'", keyword);
        t->state = IN_SOLID;
        t->solids++;
        return 0;
    case IN_SOLID:
        if (strcasecmp(keyword, "endsolid") == 0) {
            t->state = OUTSIDE;
            return 0;
        }
        if (strcasecmp(keyword, "facet") != 0)
            return text_fail(t, "'facet' or 'endsolid'", keyword);
        t->state = IN_FACET;
        t->facet++;
        return 0;
    case IN_FACET:
        if (strcasecmp(keyword, "outer") != 0 || !next_word(&rest, second, sizeof second) ||
            strcasecmp(second, "loop") != 0)
            return text_fail(t, "'outer loop'", keyword);
        t->state = IN_LOOP;
        t->corners = 0;
        return 0;
    case IN_LOOP:
        if (strcasecmp(keyword, "vertex") == 0) {
            if (t->corners == 3)
                return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: facet %llu "
                                 "has a fourth vertex (an STL facet is a triangle)",
                                 t->b->path, t->line, (unsigned long long)t->facet);
            t->corners++;
            return text_vertex(t, rest);
        }
        if (strcasecmp(keyword, "endloop") != 0)
            return text_fail(t, t->corners < 3 ? "'vertex'" : "'endloop'", keyword);
        if (t->corners < 3)
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: facet %llu has "
                             "%d vertices (an STL facet has 3)",
                             t->b->path, t->line, (unsigned long long)t->facet, t->corners);
        t->state = AFTER_LOOP;
        return 0;
    case AFTER_LOOP:
        if (strcasecmp(keyword, "endfacet") != 0)
            return text_fail(t, "'endfacet'", keyword);
        t->state = IN_SOLID;
        return 0;
    }
    return 0;
}

static int read_ascii(FILE *f, stl_builder *b)
{
    stl_text t = {.b = b, .state = OUTSIDE};
    char *line = NULL;
    size_t capacity = 0;
    int status = 0;
    ssize_t length;
    while (!status && (length = getline(&line, &capacity, f)) >= 0) {
        t.line++;
        if (memchr(line, '\0', (size_t)length))
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld holds a NUL byte "
                               "(not an ASCII STL file)",
                               b->path, t.line);
        else if ((status = text_line(&t, line)) != 0 && line[length - 1] != '\n')
            /* what is wrong with the last line is that the file ends in it */
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': the file ends in the "
                               "middle of line %ld, %s %llu (cut short?)",
                               b->path, t.line, t.state == IN_SOLID ? "after facet" : "inside facet",
                               (unsigned long long)t.facet);
    }
    free(line);
    if (status)
        return status;
    if (ferror(f))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", b->path, strerror(errno));
    if (t.state == IN_SOLID)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': the file ends at line %ld "
                         "without 'endsolid', after %llu complete facets (cut short?)",
                         b->path, t.line, (unsigned long long)t.facet);
    if (t.state != OUTSIDE)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': the file ends at line %ld "
                         "inside facet %llu (cut short?)",
                         b->path, t.line, (unsigned long long)t.facet);
    if (t.solids == 0)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': no 'solid' in it", b->path);
    return 0;
}

/* ---- the format ---- */

/* Whether the first bytes read as the start of an ASCII file: "solid" after blanks, and text. */
static int looks_ascii(const unsigned char *bytes, size_t size)
{
    size_t at = 0;
    while (at < size && isspace(bytes[at]))
        at++;
    if (size - at < 5 || strncasecmp((const char *)bytes + at, "solid", 5) != 0)
        return 0;
    for (size_t i = 0; i < size; i++)
        if (bytes[i] == 0 || (bytes[i] < 0x20 && !isspace(bytes[i])) || bytes[i] == 0x7f)
            return 0;
    return 1;
}

int mesh_stl_read(const char *path, mesh_data *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, strerror(errno));
    struct stat info;
    if (fstat(fileno(f), &info) != 0) {
        fclose(f);
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, strerror(errno));
    }
    unsigned long long size = (unsigned long long)info.st_size;
    unsigned char start[STL_SNIFF_BYTES];
    size_t got = fread(start, 1, sizeof start, f);
    stl_builder b = {.path = path};
    int status;
    int binary_size = 0;
    uint32_t facets = 0;
    if (got >= STL_HEADER_BYTES) {
        facets = le32(start + 80);
        binary_size = size == STL_HEADER_BYTES + (unsigned long long)STL_FACET_BYTES * facets;
    }
    if (binary_size) {
        status = read_binary(f, facets, &b);
    } else if (looks_ascii(start, got)) {
        rewind(f);
        status = read_ascii(f, &b);
    } else if (got >= STL_HEADER_BYTES) {
        status = error_set(IDMR_EXIT_INPUT,
                           "cannot read mesh '%s': a binary STL file whose header says %u facets "
                           "(84 + 50 x %u = %llu bytes), but the file has %llu bytes (%s)",
                           path, facets, facets,
                           STL_HEADER_BYTES + (unsigned long long)STL_FACET_BYTES * facets, size,
                           size < STL_HEADER_BYTES + (unsigned long long)STL_FACET_BYTES * facets
                               ? "cut short?"
                               : "bytes after the last facet");
    } else {
        status = error_set(IDMR_EXIT_INPUT,
                           "cannot read mesh '%s': not an STL file (%llu bytes: shorter than a "
                           "binary STL's 84-byte header, and not ASCII text starting 'solid')",
                           path, size);
    }
    fclose(f);
    if (status) {
        builder_free(&b);
        return -1;
    }
    builder_finish(&b, out);
    return 0;
}
