/* mesh_text.c — the strict OBJ and OFF readers (see mesh_text.h). */
#include "io/mesh/mesh_text.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

/* A growable array of floats or of int64 values. */
typedef struct float_list {
    float *data;
    size_t count, capacity;
} float_list;

typedef struct index_list {
    int64_t *data;
    size_t count, capacity;
} index_list;

static void float_push(float_list *l, float value)
{
    if (l->count == l->capacity) {
        l->capacity = l->capacity ? 2 * l->capacity : 1024;
        l->data = xrealloc(l->data, l->capacity * sizeof *l->data);
    }
    l->data[l->count++] = value;
}

static void index_push(index_list *l, int64_t value)
{
    if (l->count == l->capacity) {
        l->capacity = l->capacity ? 2 * l->capacity : 1024;
        l->data = xrealloc(l->data, l->capacity * sizeof *l->data);
    }
    l->data[l->count++] = value;
}

/* Where a reader is: the file, its current line (1-based) and the text after the keyword. */
typedef struct text_cursor {
    const char *path;
    long line;
    const char *at;
} text_cursor;

static void skip_blanks(text_cursor *c)
{
    while (*c->at == ' ' || *c->at == '\t' || *c->at == '\r')
        c->at++;
}

/* The next whitespace-separated number. 1 when read, 0 at the end of the line, -1 (error set)
 * for a token that is not a finite number. */
static int next_number(text_cursor *c, double *value)
{
    skip_blanks(c);
    if (*c->at == '\0' || *c->at == '\n' || *c->at == '#')
        return 0;
    char *end;
    errno = 0;
    *value = strtod(c->at, &end);
    size_t length = strcspn(c->at, " \t\r\n");
    if (end != c->at + length || !isfinite(*value)) {
        error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: '%.*s' is not a finite number",
                  c->path, c->line, (int)(length < 40 ? length : 40), c->at);
        return -1;
    }
    c->at = end;
    return 1;
}

/* Reads at least `min` and at most `max` numbers (the rest of the line must be empty); returns
 * how many, or -1 with the error set. */
static int read_numbers(text_cursor *c, double *values, int min, int max, const char *what)
{
    int n = 0, got;
    while (n < max && (got = next_number(c, &values[n])) == 1)
        n++;
    if (n < max && got < 0)
        return -1;
    if (n < min)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: %s needs %d numbers",
                         c->path, c->line, what, min);
    return n;
}

/* ---------------------------------------------------------------------------------------- */
/* OBJ                                                                                      */

typedef struct obj_reader {
    text_cursor cursor;
    float_list positions, texcoords, normals; /* as the file defines them */
    index_list corners; /* per triangle corner: position, texcoord, normal (-1: none) */
    int any_texcoords, any_normals;
} obj_reader;

/* One index of a face corner: `text` .. `end`, of `count` elements defined so far; -1 for an
 * empty field. Returns 0, or -1 with the error set. */
static int obj_index(obj_reader *r, const char *text, const char *end, size_t count,
                     const char *kind, int64_t *out)
{
    if (text == end) {
        *out = -1;
        return 0;
    }
    char *stop;
    errno = 0;
    long long value = strtoll(text, &stop, 10);
    if (stop != end || errno)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: '%.*s' is not a %s "
                         "index",
                         r->cursor.path, r->cursor.line, (int)(end - text), text, kind);
    long long resolved = value < 0 ? (long long)count + value : value - 1;
    if (value == 0 || resolved < 0 || resolved >= (long long)count)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: %s index %lld is out "
                         "of range (%zu defined before this line)",
                         r->cursor.path, r->cursor.line, kind, value, count);
    *out = resolved;
    return 0;
}

/* One corner "i", "i/j", "i//k" or "i/j/k" into three indices. */
static int obj_corner(obj_reader *r, const char *token, size_t length, int64_t corner[3])
{
    static const char *const kinds[3] = {"vertex", "texture coordinate", "normal"};
    size_t counts[3] = {r->positions.count / 3, r->texcoords.count / 2, r->normals.count / 3};
    const char *field = token, *end = token + length;
    for (int k = 0; k < 3; k++) {
        if (field > end) { /* fewer fields than three: past the token's end */
            corner[k] = -1;
            continue;
        }
        const char *slash = memchr(field, '/', (size_t)(end - field));
        const char *field_end = slash ? slash : end;
        if (obj_index(r, field, field_end, counts[k], kinds[k], &corner[k]))
            return -1;
        field = field_end + 1;
    }
    if (corner[0] < 0)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a face corner "
                         "without a vertex index",
                         r->cursor.path, r->cursor.line);
    r->any_texcoords |= corner[1] >= 0;
    r->any_normals |= corner[2] >= 0;
    return 0;
}

/* "f c1 c2 c3 ...": fan-triangulated into corners. */
static int obj_face(obj_reader *r)
{
    int64_t first[3], previous[3], current[3];
    int count = 0;
    text_cursor *c = &r->cursor;
    for (;;) {
        skip_blanks(c);
        size_t length = strcspn(c->at, " \t\r\n#");
        if (length == 0)
            break;
        if (obj_corner(r, c->at, length, current))
            return -1;
        c->at += length;
        if (count == 0)
            memcpy(first, current, sizeof first);
        if (count >= 2) {
            const int64_t *triangle[3] = {first, previous, current};
            for (int corner = 0; corner < 3; corner++)
                for (int k = 0; k < 3; k++)
                    index_push(&r->corners, triangle[corner][k]);
        }
        memcpy(previous, current, sizeof previous);
        count++;
    }
    if (count < 3)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a face needs 3 "
                         "corners, this one has %d",
                         c->path, c->line, count);
    return 0;
}

/* One statement (the keyword already read). */
static int obj_statement(obj_reader *r, const char *keyword, size_t length)
{
    double values[4];
    int n;
    if (length == 1 && keyword[0] == 'v') {
        if ((n = read_numbers(&r->cursor, values, 3, 4, "a vertex (v)")) < 0)
            return -1;
        for (int k = 0; k < 3; k++)
            float_push(&r->positions, (float)values[k]);
    } else if (length == 2 && strncmp(keyword, "vt", 2) == 0) {
        if ((n = read_numbers(&r->cursor, values, 1, 3, "a texture coordinate (vt)")) < 0)
            return -1;
        float_push(&r->texcoords, (float)values[0]);
        float_push(&r->texcoords, n > 1 ? (float)values[1] : 0.0f);
    } else if (length == 2 && strncmp(keyword, "vn", 2) == 0) {
        if ((n = read_numbers(&r->cursor, values, 3, 3, "a normal (vn)")) < 0)
            return -1;
        for (int k = 0; k < 3; k++)
            float_push(&r->normals, (float)values[k]);
    } else if (length == 1 && keyword[0] == 'f') {
        return obj_face(r);
    } else if (!isalpha((unsigned char)keyword[0])) {
        /* other statements (g, o, s, usemtl, ...) are skipped, but every one is a word: this is
         * no statement (a stray byte-order mark, binary data) */
        return error_set(IDMR_EXIT_INPUT,
                         "cannot read mesh '%s': line %ld: not an OBJ statement (it starts with "
                         "byte 0x%02X)",
                         r->cursor.path, r->cursor.line, (unsigned char)keyword[0]);
    }
    return 0;
}

/* A hash of a corner's three indices. */
static uint64_t corner_hash(const int64_t *corner)
{
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; k++)
        h = (h ^ (uint64_t)corner[k]) * 1099511628211ull;
    return h ^ (h >> 29);
}

/* The distinct corners become the output's vertices (first use first), the triangles index
 * them. */
static int obj_build(obj_reader *r, mesh_data *out)
{
    size_t corners = r->corners.count / 3;
    if (corners / 3 > UINT32_MAX / 3)
        return error_set(IDMR_EXIT_INPUT, "mesh '%s' is too large for 32-bit indices",
                         r->cursor.path);
    size_t capacity = 16;
    while (capacity < 2 * corners)
        capacity *= 2;
    uint32_t *table = xmalloc(capacity * sizeof *table); /* vertex + 1, 0: empty */
    memset(table, 0, capacity * sizeof *table);
    uint32_t *first_corner = xmalloc(corners * sizeof *first_corner); /* per output vertex */
    out->triangle_count = (uint32_t)(corners / 3);
    out->indices = xmalloc(corners * sizeof *out->indices);
    uint32_t vertices = 0;
    for (size_t i = 0; i < corners; i++) {
        const int64_t *corner = &r->corners.data[3 * i];
        size_t slot = corner_hash(corner) & (capacity - 1);
        while (table[slot] &&
               memcmp(&r->corners.data[3 * (size_t)first_corner[table[slot] - 1]], corner,
                      3 * sizeof *corner) != 0)
            slot = (slot + 1) & (capacity - 1);
        if (!table[slot]) {
            first_corner[vertices] = (uint32_t)i;
            table[slot] = ++vertices;
        }
        out->indices[i] = table[slot] - 1;
    }
    free(table);
    out->vertex_count = vertices;
    out->positions = xmalloc(3 * sizeof(float) * vertices);
    if (r->any_texcoords)
        out->texcoords = xcalloc(2 * (size_t)vertices, sizeof(float));
    if (r->any_normals)
        out->normals = xcalloc(3 * (size_t)vertices, sizeof(float));
    for (uint32_t v = 0; v < vertices; v++) {
        const int64_t *corner = &r->corners.data[3 * (size_t)first_corner[v]];
        memcpy(&out->positions[3 * (size_t)v], &r->positions.data[3 * corner[0]],
               3 * sizeof(float));
        if (out->texcoords && corner[1] >= 0)
            memcpy(&out->texcoords[2 * (size_t)v], &r->texcoords.data[2 * corner[1]],
                   2 * sizeof(float));
        if (out->normals && corner[2] >= 0)
            memcpy(&out->normals[3 * (size_t)v], &r->normals.data[3 * corner[2]],
                   3 * sizeof(float));
    }
    free(first_corner);
    return 0;
}

/* Opens `path` for a reader, with the error set naming it when it cannot. */
/* Steps over a UTF-8 byte-order mark at the start of line 1 (editors on Windows write one). */
static void skip_byte_order_mark(text_cursor *c)
{
    if (c->line == 1 && memcmp(c->at, "\xEF\xBB\xBF", 3) == 0)
        c->at += 3;
}

static FILE *open_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", path, strerror(errno));
    return f;
}

int mesh_text_read_obj(const char *path, mesh_data *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = open_text(path);
    if (!f)
        return -1;
    obj_reader r;
    memset(&r, 0, sizeof r);
    r.cursor.path = path;
    char *line = NULL;
    size_t size = 0;
    int status = 0;
    while (status == 0 && getline(&line, &size, f) >= 0) {
        r.cursor.line++;
        r.cursor.at = line;
        skip_byte_order_mark(&r.cursor);
        skip_blanks(&r.cursor);
        size_t length = strcspn(r.cursor.at, " \t\r\n");
        const char *keyword = r.cursor.at;
        r.cursor.at += length;
        if (length && keyword[0] != '#')
            status = obj_statement(&r, keyword, length);
    }
    if (status == 0 && ferror(f))
        status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': read error", path);
    free(line);
    fclose(f);
    if (status == 0)
        status = obj_build(&r, out);
    free(r.positions.data);
    free(r.texcoords.data);
    free(r.normals.data);
    free(r.corners.data);
    if (status)
        mesh_data_free(out);
    return status;
}

/* ---------------------------------------------------------------------------------------- */
/* OFF                                                                                      */

/* The next line that holds something other than a comment; 0 at the end of the file. */
static int off_next_line(FILE *f, char **line, size_t *size, text_cursor *c)
{
    while (getline(line, size, f) >= 0) {
        c->line++;
        c->at = *line;
        skip_byte_order_mark(c);
        skip_blanks(c);
        if (*c->at && *c->at != '\n' && *c->at != '#')
            return 1;
    }
    return 0;
}

/* Reads the counts after the header keyword (on its line or the next). */
static int off_counts(FILE *f, char **line, size_t *size, text_cursor *c, double counts[3])
{
    double value;
    int got = next_number(c, &value);
    if (got < 0)
        return -1;
    if (got == 0 && !off_next_line(f, line, size, c))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': no vertex and face counts "
                         "after the OFF header",
                         c->path);
    if (got == 1) {
        counts[0] = value;
        if (read_numbers(c, counts + 1, 1, 2, "the OFF counts") < 0)
            return -1;
    } else if (read_numbers(c, counts, 2, 3, "the OFF counts") < 0) {
        return -1;
    }
    for (int k = 0; k < 2; k++)
        if (counts[k] < 0 || counts[k] != floor(counts[k]) || counts[k] > UINT32_MAX)
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: the counts must "
                             "be whole numbers below 2^32",
                             c->path, c->line);
    return 0;
}

static int off_read(FILE *f, const char *path, mesh_data *out)
{
    text_cursor c = {path, 0, NULL};
    char *line = NULL;
    size_t size = 0;
    double counts[3] = {0, 0, 0}, values[3];
    int status = 0;
    if (!off_next_line(f, &line, &size, &c)) {
        free(line);
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': the file is empty", path);
    }
    size_t keyword = strcspn(c.at, " \t\r\n");
    if (keyword < 3 || keyword > 5 || strncmp(c.at + keyword - 3, "OFF", 3) != 0 ||
        strspn(c.at, "CN") != keyword - 3)
        status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': not an OFF file (its first "
                           "line is not OFF, COFF, NOFF or CNOFF)",
                           path);
    c.at += keyword;
    if (status == 0)
        status = off_counts(f, &line, &size, &c, counts);
    uint32_t vertices = (uint32_t)counts[0], faces = (uint32_t)counts[1];
    float_list positions = {0};
    index_list triangles = {0};
    for (uint32_t v = 0; status == 0 && v < vertices; v++) {
        if (!off_next_line(f, &line, &size, &c)) {
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': its header says %u "
                               "vertices, the file holds %u",
                               path, vertices, v);
            break;
        }
        double xyz[3];
        for (int k = 0; k < 3 && status == 0; k++) {
            int got = next_number(&c, &xyz[k]);
            if (got == 0)
                status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a vertex "
                                   "needs 3 numbers",
                                   path, c.line);
            else if (got < 0)
                status = -1;
        }
        for (int k = 0; k < 3 && status == 0; k++)
            float_push(&positions, (float)xyz[k]);
    }
    for (uint32_t face = 0; status == 0 && face < faces; face++) {
        if (!off_next_line(f, &line, &size, &c)) {
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': its header says %u "
                               "faces, the file holds %u",
                               path, faces, face);
            break;
        }
        double n;
        if (next_number(&c, &n) != 1 || n < 3 || n != floor(n)) {
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: a face must "
                               "start with its corner count, 3 or more",
                               path, c.line);
            break;
        }
        int64_t first = 0, previous = 0;
        for (long k = 0; status == 0 && k < (long)n; k++) {
            int got = next_number(&c, &values[0]);
            if (got <= 0 || values[0] < 0 || values[0] >= vertices ||
                values[0] != floor(values[0])) {
                status = got < 0 ? -1
                                 : error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: "
                                             "corner %ld of %ld is missing or not a vertex index "
                                             "from 0 to %u",
                                             path, c.line, k + 1, (long)n, vertices - 1);
                break;
            }
            int64_t index = (int64_t)values[0];
            if (k == 0)
                first = index;
            if (k >= 2) {
                index_push(&triangles, first);
                index_push(&triangles, previous);
                index_push(&triangles, index);
            }
            previous = index;
        }
    }
    free(line);
    if (status == 0 && triangles.count / 3 > UINT32_MAX / 3)
        status = error_set(IDMR_EXIT_INPUT, "mesh '%s' is too large for 32-bit indices", path);
    if (status == 0) {
        out->vertex_count = vertices;
        out->positions = positions.data;
        positions.data = NULL;
        out->triangle_count = (uint32_t)(triangles.count / 3);
        out->indices = xmalloc(triangles.count * sizeof *out->indices);
        for (size_t i = 0; i < triangles.count; i++)
            out->indices[i] = (uint32_t)triangles.data[i];
    }
    free(positions.data);
    free(triangles.data);
    return status;
}

int mesh_text_read_off(const char *path, mesh_data *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = open_text(path);
    if (!f)
        return -1;
    int status = off_read(f, path, out);
    fclose(f);
    if (status)
        mesh_data_free(out);
    return status;
}
