/* ply_check.c — idmr's PLY reader (see ply_check.h): the header parsed into elements and
 * properties, the body read value by value (ascii tokens or binary of either byte order), each
 * checked; ply_read() keeps what a mesh needs on the way (the vertex element's roles, the face
 * element's index lists fan-triangulated), ply_check() keeps nothing. */
#include "io/mesh/ply_check.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include "core/error.h"
#include "core/mesh_data.h"

#define PLY_HEADER_MAX (1 << 16) /* bytes of header read at most */
#define PLY_PROPERTIES_MAX 64    /* per element */
#define PLY_ELEMENTS_MAX 64

typedef enum ply_type {
    PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32, PLY_FLOAT64,
    PLY_TYPE_NONE
} ply_type;

static const struct {
    const char *name, *alias;
    int size;
} ply_types[] = {
    [PLY_INT8] = {"char", "int8", 1},      [PLY_UINT8] = {"uchar", "uint8", 1},
    [PLY_INT16] = {"short", "int16", 2},   [PLY_UINT16] = {"ushort", "uint16", 2},
    [PLY_INT32] = {"int", "int32", 4},     [PLY_UINT32] = {"uint", "uint32", 4},
    [PLY_FLOAT32] = {"float", "float32", 4}, [PLY_FLOAT64] = {"double", "float64", 8},
};

static ply_type type_named(const char *name)
{
    for (int t = 0; t < PLY_TYPE_NONE; t++)
        if (strcmp(name, ply_types[t].name) == 0 || strcmp(name, ply_types[t].alias) == 0)
            return (ply_type)t;
    return PLY_TYPE_NONE;
}

/* What a vertex property is to the mesh (ply_read keeps these, and nothing else). */
typedef enum ply_role {
    ROLE_NONE, ROLE_X, ROLE_Y, ROLE_Z, ROLE_NX, ROLE_NY, ROLE_NZ, ROLE_U, ROLE_V, ROLE_COUNT
} ply_role;

static const struct {
    const char *name;
    ply_role role;
} ply_role_names[] = {
    {"x", ROLE_X},          {"y", ROLE_Y},          {"z", ROLE_Z},
    {"nx", ROLE_NX},        {"ny", ROLE_NY},        {"nz", ROLE_NZ},
    {"u", ROLE_U},          {"v", ROLE_V},          {"s", ROLE_U},
    {"t", ROLE_V},          {"texture_u", ROLE_U},  {"texture_v", ROLE_V},
    {"texture_s", ROLE_U},  {"texture_t", ROLE_V},
};

typedef struct ply_property {
    ply_type type;
    ply_type count_type; /* PLY_TYPE_NONE unless a list */
    int is_face_indices; /* the face element's vertex_indices (or vertex_index) list */
    ply_role role;       /* of a scalar property of the vertex element, the first of its role */
} ply_property;

typedef struct ply_element {
    char name[64];
    uint64_t count;
    ply_property properties[PLY_PROPERTIES_MAX];
    int property_count;
} ply_element;

typedef enum ply_format { PLY_ASCII, PLY_BINARY_LE, PLY_BINARY_BE } ply_format;

typedef struct ply_reader {
    const char *path;
    FILE *f;
    ply_format format;
    ply_element elements[PLY_ELEMENTS_MAX];
    int element_count;
    long line; /* ascii: the line of the body being read */
    uint64_t vertices; /* the vertex element's count; UINT64_MAX without one */
    unsigned roles;    /* bit per ply_role the vertex element has */
    /* ply_read: what is kept (mesh NULL: ply_check keeps nothing). */
    mesh_data *mesh;
    size_t vertex_capacity, corner_capacity, index_capacity;
    uint32_t *corners; /* the face being read */
    uint64_t index_count;
} ply_reader;

/* An error about header line `number`; returns -1. */
static int header_fail(const ply_reader *r, long number, const char *what)
{
    return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': PLY header line %ld: %s", r->path,
                     number, what);
}

/* ---------------------------------------------------------------------------------------- */
/* The header                                                                               */

/* A face element whose corner list is named neither vertex_indices nor vertex_index (writers
 * name it vertex_ids, indices, ...): its one list of integers is the corner list. Several such
 * lists and none of the usual names: an error naming them, as no rule can tell which it is. */
static int face_list_by_type(ply_reader *r, long number)
{
    for (int i = 0; i < r->element_count; i++) {
        ply_element *e = &r->elements[i];
        if (strcmp(e->name, "face") != 0)
            continue;
        ply_property *found = NULL;
        size_t lists = 0;
        for (int k = 0; k < e->property_count; k++) {
            ply_property *p = &e->properties[k];
            if (p->is_face_indices)
                return 0;
            if (p->count_type != PLY_TYPE_NONE && p->type < PLY_FLOAT32) {
                found = p;
                lists++;
            }
        }
        if (lists == 1)
            found->is_face_indices = 1;
        else if (lists > 1)
            return header_fail(r, number, "the face element has several lists of integers and "
                                          "none named vertex_indices or vertex_index: which holds "
                                          "the corners?");
    }
    return 0;
}

/* One header line (no newline), number `number`: what it declares into r, or an error. Sets
 * *done at "end_header". */
static int header_line(ply_reader *r, char *line, long number, int *seen_format, int *done)
{
    char *words[8];
    int count = 0;
    for (const char *p = line; *p; p++)
        if ((unsigned char)*p < 0x20 && *p != '\t')
            return header_fail(r, number, "a control character");
    for (char *w = strtok(line, " \t"); w && count < 8; w = strtok(NULL, " \t"))
        words[count++] = w;
    if (count == 0 || strcmp(words[0], "comment") == 0 || strcmp(words[0], "obj_info") == 0)
        return 0;
    if (strcmp(words[0], "end_header") == 0) {
        *done = 1;
        if (!*seen_format)
            return header_fail(r, number, "no \"format\" line before \"end_header\"");
        return face_list_by_type(r, number);
    }
    if (strcmp(words[0], "format") == 0) {
        if (count != 3 || strcmp(words[2], "1.0") != 0)
            return header_fail(r, number, "expected \"format ascii|binary_little_endian|"
                                          "binary_big_endian 1.0\"");
        if (strcmp(words[1], "ascii") == 0)
            r->format = PLY_ASCII;
        else if (strcmp(words[1], "binary_little_endian") == 0)
            r->format = PLY_BINARY_LE;
        else if (strcmp(words[1], "binary_big_endian") == 0)
            r->format = PLY_BINARY_BE;
        else
            return header_fail(r, number, "unknown PLY format");
        *seen_format = 1;
        return 0;
    }
    if (strcmp(words[0], "element") == 0) {
        char *end;
        errno = 0;
        unsigned long long n = count == 3 && isdigit((unsigned char)words[2][0])
                                   ? strtoull(words[2], &end, 10)
                                   : 0;
        if (count != 3 || !isdigit((unsigned char)words[2][0]) || *end || errno ||
            n > UINT32_MAX)
            return header_fail(r, number,
                               "expected \"element NAME COUNT\" with a count below 2^32");
        if (r->element_count == PLY_ELEMENTS_MAX)
            return header_fail(r, number, "too many elements");
        ply_element *e = &r->elements[r->element_count++];
        memset(e, 0, sizeof *e);
        if (strlen(words[1]) >= sizeof e->name)
            return header_fail(r, number, "an element name of more than 63 characters");
        memcpy(e->name, words[1], strlen(words[1]) + 1);
        e->count = n;
        if (strcmp(e->name, "vertex") == 0)
            r->vertices = n;
        return 0;
    }
    if (strcmp(words[0], "property") == 0) {
        if (r->element_count == 0)
            return header_fail(r, number, "a property before any element");
        ply_element *e = &r->elements[r->element_count - 1];
        if (e->property_count == PLY_PROPERTIES_MAX)
            return header_fail(r, number, "too many properties");
        ply_property *p = &e->properties[e->property_count++];
        int list = count >= 2 && strcmp(words[1], "list") == 0;
        if (list) {
            p->count_type = count == 5 ? type_named(words[2]) : PLY_TYPE_NONE;
            p->type = count == 5 ? type_named(words[3]) : PLY_TYPE_NONE;
            if (count != 5 || p->count_type == PLY_TYPE_NONE || p->type == PLY_TYPE_NONE ||
                p->count_type >= PLY_FLOAT32)
                return header_fail(r, number, "expected \"property list COUNT_TYPE TYPE NAME\" "
                                              "(an integer count type)");
            p->is_face_indices = strcmp(e->name, "face") == 0 &&
                                 (strcmp(words[4], "vertex_indices") == 0 ||
                                  strcmp(words[4], "vertex_index") == 0);
            return 0;
        }
        p->count_type = PLY_TYPE_NONE;
        p->type = count == 3 ? type_named(words[1]) : PLY_TYPE_NONE;
        if (p->type == PLY_TYPE_NONE)
            return header_fail(r, number, "expected \"property TYPE NAME\"");
        p->role = ROLE_NONE;
        if (strcmp(e->name, "vertex") == 0)
            for (size_t i = 0; i < sizeof ply_role_names / sizeof *ply_role_names; i++)
                if (strcmp(words[2], ply_role_names[i].name) == 0 &&
                    !(r->roles & 1u << ply_role_names[i].role)) {
                    p->role = ply_role_names[i].role;
                    r->roles |= 1u << p->role;
                }
        return 0;
    }
    return header_fail(r, number, "unknown PLY header line");
}

static int read_header(ply_reader *r)
{
    char *line = NULL;
    size_t capacity = 0, bytes = 0;
    long number = 0;
    int seen_format = 0, done = 0, status = 0;
    ssize_t length;
    while (status == 0 && !done) {
        length = getline(&line, &capacity, r->f);
        if (length <= 0 || line[length - 1] != '\n') {
            status = error_set(IDMR_EXIT_INPUT,
                               number == 0 ? "cannot read mesh '%s': not a PLY file (it does not "
                                             "start with the line \"ply\")"
                                           : "cannot read mesh '%s': its PLY header has no "
                                             "\"end_header\" line (a truncated file?)",
                               r->path);
            break;
        }
        number++;
        bytes += (size_t)length;
        if (bytes > PLY_HEADER_MAX) {
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': a PLY header over 64 KiB",
                               r->path);
            break;
        }
        line[--length] = '\0';
        if (length > 0 && line[length - 1] == '\r')
            line[--length] = '\0';
        if (memchr(line, '\0', (size_t)length)) /* a NUL inside the line */
            status = header_fail(r, number, "a control character");
        else if (number == 1 && strcmp(line, "ply") != 0)
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': not a PLY file (it does "
                               "not start with the line \"ply\")", r->path);
        else if (number > 1)
            status = header_line(r, line, number, &seen_format, &done);
    }
    free(line);
    r->line = number + 1;
    return status;
}

/* ---------------------------------------------------------------------------------------- */
/* The body                                                                                 */

/* The next ascii token into token (size bytes); 0 at the end of the file. */
static int next_token(ply_reader *r, char *token, size_t size)
{
    int c;
    while ((c = getc(r->f)) != EOF && isspace(c))
        r->line += c == '\n';
    if (c == EOF)
        return 0;
    size_t n = 0;
    for (; c != EOF && !isspace(c); c = getc(r->f))
        if (n + 1 < size)
            token[n++] = (char)c;
    if (c == '\n')
        ungetc(c, r->f);
    token[n] = '\0';
    return 1;
}

/* An error about value `index` of element e (with the body line where the file is ascii);
 * returns -1. Formatted only when it happens: the body is read value by value. */
static int value_fail(const ply_reader *r, const ply_element *e, uint64_t index,
                      const char *what)
{
    if (r->format == PLY_ASCII)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': line %ld: element '%s' %llu: %s",
                         r->path, r->line, e->name, (unsigned long long)index, what);
    return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': element '%s' %llu: %s", r->path,
                     e->name, (unsigned long long)index, what);
}

/* Reads one value of `type` into *value. Integers must fit the type, floats must be finite. */
static int read_value(ply_reader *r, ply_type type, const ply_element *e, uint64_t index,
                      double *value)
{
    static const char *const ends = "the file ends here (the header promises more)";
    char what[128];
    if (r->format == PLY_ASCII) {
        char token[64];
        if (!next_token(r, token, sizeof token))
            return value_fail(r, e, index, ends);
        char *end;
        errno = 0;
        if (type < PLY_FLOAT32) /* an integer as OpenMesh reads one: digits only */
            *value = (double)strtoll(token, &end, 10);
        else
            *value = strtod(token, &end);
        if (*end || end == token || errno == ERANGE || !isfinite(*value)) {
            snprintf(what, sizeof what, "'%s' is not a %s", token,
                     type < PLY_FLOAT32 ? "whole number" : "finite number");
            return value_fail(r, e, index, what);
        }
    } else {
        unsigned char bytes[8];
        int size = ply_types[type].size;
        if (fread(bytes, 1, (size_t)size, r->f) != (size_t)size)
            return value_fail(r, e, index, ends);
        if (r->format == PLY_BINARY_BE)
            for (int i = 0; i < size / 2; i++) {
                unsigned char t = bytes[i];
                bytes[i] = bytes[size - 1 - i];
                bytes[size - 1 - i] = t;
            }
        int8_t i8; uint8_t u8; int16_t i16; uint16_t u16; int32_t i32; uint32_t u32; float f32;
        double f64;
        switch (type) {
        case PLY_INT8: memcpy(&i8, bytes, 1); *value = i8; break;
        case PLY_UINT8: memcpy(&u8, bytes, 1); *value = u8; break;
        case PLY_INT16: memcpy(&i16, bytes, 2); *value = i16; break;
        case PLY_UINT16: memcpy(&u16, bytes, 2); *value = u16; break;
        case PLY_INT32: memcpy(&i32, bytes, 4); *value = i32; break;
        case PLY_UINT32: memcpy(&u32, bytes, 4); *value = u32; break;
        case PLY_FLOAT32: memcpy(&f32, bytes, 4); *value = f32; break;
        default: memcpy(&f64, bytes, 8); *value = f64; break;
        }
        return isfinite(*value) ? 0 : value_fail(r, e, index, "a value that is not finite");
    }
    static const double low[] = {-128, 0, -32768, 0, -2147483648.0, 0},
                        high[] = {127, 255, 32767, 65535, 2147483647.0, 4294967295.0};
    if (type < PLY_FLOAT32 && (*value != floor(*value) || *value < low[type] ||
                               *value > high[type])) {
        snprintf(what, sizeof what, "%g is not a %s", *value, ply_types[type].name);
        return value_fail(r, e, index, what);
    }
    return 0;
}

/* Makes room for `needed` elements of `size` bytes in *array (capacity doubling, so a header
 * that promises more than the file holds costs only what is read). */
static void reserve(void **array, size_t *capacity, size_t needed, size_t size)
{
    if (needed <= *capacity)
        return;
    size_t grown = *capacity ? *capacity : 256;
    while (grown < needed)
        grown *= 2;
    *array = xrealloc(*array, grown * size);
    *capacity = grown;
}

/* ply_read: vertex `index`'s values by role into the mesh's arrays. */
static void keep_vertex(ply_reader *r, uint64_t index, const float value[ROLE_COUNT])
{
    mesh_data *m = r->mesh;
    size_t capacity = r->vertex_capacity;
    reserve((void **)&m->positions, &capacity, (size_t)index + 1, 3 * sizeof(float));
    if (capacity != r->vertex_capacity) {
        if (m->normals)
            m->normals = xrealloc(m->normals, capacity * 3 * sizeof(float));
        if (m->texcoords)
            m->texcoords = xrealloc(m->texcoords, capacity * 2 * sizeof(float));
        r->vertex_capacity = capacity;
    }
    memcpy(&m->positions[3 * index], &value[ROLE_X], 3 * sizeof(float));
    if (m->normals)
        memcpy(&m->normals[3 * index], &value[ROLE_NX], 3 * sizeof(float));
    if (m->texcoords)
        memcpy(&m->texcoords[2 * index], &value[ROLE_U], 2 * sizeof(float));
    m->vertex_count = (uint32_t)(index + 1);
}

/* ply_read: the face's `count` corners fan-triangulated into the mesh. */
static int keep_face(ply_reader *r, const uint32_t *corners, size_t count)
{
    mesh_data *m = r->mesh;
    if (r->index_count + 3 * (uint64_t)(count - 2) > 3 * (uint64_t)(UINT32_MAX / 3))
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': more than %u triangles",
                         r->path, UINT32_MAX / 3);
    reserve((void **)&m->indices, &r->index_capacity,
            (size_t)r->index_count + 3 * (count - 2), sizeof(uint32_t));
    for (size_t i = 1; i + 1 < count; i++) {
        m->indices[r->index_count++] = corners[0];
        m->indices[r->index_count++] = corners[i];
        m->indices[r->index_count++] = corners[i + 1];
    }
    m->triangle_count = (uint32_t)(r->index_count / 3);
    return 0;
}

static int read_element(ply_reader *r, const ply_element *e, uint64_t index)
{
    float kept[ROLE_COUNT] = {0};
    int is_vertex = r->mesh && strcmp(e->name, "vertex") == 0;
    for (int k = 0; k < e->property_count; k++) {
        const ply_property *p = &e->properties[k];
        double value, count = 1;
        if (p->count_type != PLY_TYPE_NONE && read_value(r, p->count_type, e, index, &count))
            return -1;
        if (p->is_face_indices && count < 3)
            return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': face %llu has %g corners "
                             "(a face needs 3)", r->path, (unsigned long long)index, count);
        for (double i = 0; i < count; i++) {
            if (read_value(r, p->type, e, index, &value))
                return -1;
            if (p->is_face_indices && (value < 0 || value >= (double)r->vertices))
                return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': face %llu: vertex "
                                 "index %.0f is out of range (%llu vertices)", r->path,
                                 (unsigned long long)index, value,
                                 (unsigned long long)r->vertices);
            if (p->is_face_indices && r->mesh) {
                reserve((void **)&r->corners, &r->corner_capacity, (size_t)i + 1,
                        sizeof *r->corners);
                r->corners[(size_t)i] = (uint32_t)value;
            }
            if (is_vertex && p->role != ROLE_NONE) {
                kept[p->role] = (float)value;
                if (!isfinite(kept[p->role]))
                    return value_fail(r, e, index, "a value beyond the range of a float");
            }
        }
        if (p->is_face_indices && r->mesh && keep_face(r, r->corners, (size_t)count))
            return -1;
    }
    if (is_vertex)
        keep_vertex(r, index, kept);
    return 0;
}

/* Reads the whole file; with r->mesh set, keeps the mesh (its arrays freed on failure). */
static int read_file(ply_reader *r)
{
    r->vertices = UINT64_MAX;
    r->f = fopen(r->path, "rb");
    if (!r->f)
        return error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': %s", r->path, strerror(errno));
    int status = read_header(r);
    if (status == 0 && r->mesh) {
        const unsigned position = 1u << ROLE_X | 1u << ROLE_Y | 1u << ROLE_Z;
        const unsigned normal = 1u << ROLE_NX | 1u << ROLE_NY | 1u << ROLE_NZ;
        const unsigned uv = 1u << ROLE_U | 1u << ROLE_V;
        if (r->vertices == UINT64_MAX)
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': no \"element vertex\" "
                               "in its header", r->path);
        else if ((r->roles & position) != position)
            status = error_set(IDMR_EXIT_INPUT, "cannot read mesh '%s': its vertex element has "
                               "no x, y and z properties", r->path);
        /* Arrays of one element, grown with the vertices: normals and uv only where the
         * header gives every component. */
        if ((r->roles & normal) == normal)
            r->mesh->normals = xmalloc(3 * sizeof(float));
        if ((r->roles & uv) == uv)
            r->mesh->texcoords = xmalloc(2 * sizeof(float));
        r->mesh->positions = xmalloc(3 * sizeof(float));
        r->vertex_capacity = 1;
        r->mesh->indices = xmalloc(3 * sizeof(uint32_t));
        r->index_capacity = 3;
    }
    /* An element without properties holds no bytes, however many it counts (a loop over 2^31
     * of nothing was a hang the fuzzer found). */
    for (int e = 0; status == 0 && e < r->element_count; e++)
        for (uint64_t i = 0; status == 0 && r->elements[e].property_count > 0 &&
                             i < r->elements[e].count;
             i++)
            status = read_element(r, &r->elements[e], i);
    fclose(r->f);
    free(r->corners);
    if (status && r->mesh)
        mesh_data_free(r->mesh);
    return status;
}

int ply_check(const char *path)
{
    ply_reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    return read_file(&r);
}

int ply_read(const char *path, mesh_data *out)
{
    ply_reader r;
    memset(&r, 0, sizeof r);
    memset(out, 0, sizeof *out);
    r.path = path;
    r.mesh = out;
    return read_file(&r);
}

int ply_check_written(const char *path)
{
    if (ply_check(path) == 0)
        return 0;
    char reason[1024];
    snprintf(reason, sizeof reason, "%s", error_message());
    unlink(path);
    return error_set(IDMR_EXIT_FAILURE,
                     "cannot write mesh '%s': the file came out incomplete (is the disk full, "
                     "or a file size limit reached?): %s",
                     path, reason);
}
