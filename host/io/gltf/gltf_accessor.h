/* gltf_accessor.h — the elements of a glTF accessor, read from the document's buffers
 * (io/gltf/gltf_document.h) once io/gltf/gltf_validate.h has checked that they lie where it says.
 *
 * An accessor is `count` elements of `components` numbers each (SCALAR 1, VEC2 2, VEC3 3,
 * VEC4 4, MAT2 4, MAT3 9, MAT4 16) of one component type, element i at byte offset + i × stride
 * of its buffer. A matrix is stored by columns, each column starting on a 4-byte boundary (a
 * MAT3 of bytes takes 12 bytes, not 9). Without a bufferView every element is zero. A sparse
 * accessor then replaces `sparse_count` elements: the element numbers (strictly increasing, of
 * an unsigned integer type) and their values are read from two further places. A normalized
 * integer reads as glTF says: unsigned c / max, signed max(c / max, -1). */
#ifndef IDMR_GLTF_ACCESSOR_H
#define IDMR_GLTF_ACCESSOR_H

#include <stddef.h>
#include <stdint.h>

#include "io/gltf/gltf_document.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
    GLTF_BYTE = 5120,
    GLTF_UNSIGNED_BYTE = 5121,
    GLTF_SHORT = 5122,
    GLTF_UNSIGNED_SHORT = 5123,
    GLTF_UNSIGNED_INT = 5125,
    GLTF_FLOAT = 5126,
};

/* Where an accessor's bytes are: a buffer (-1: none, all zeros) and the byte of element 0. */
typedef struct gltf_place {
    int buffer;
    size_t offset;
} gltf_place;

typedef struct gltf_accessor {
    int component_type; /* GLTF_BYTE ... GLTF_FLOAT */
    int components;     /* numbers per element */
    int rows;           /* numbers per column (a matrix's rows; else `components`) */
    int normalized;
    uint32_t count;
    gltf_place data;
    size_t stride;       /* bytes from an element to the next */
    size_t element_size; /* bytes of one element (columns padded) */
    uint32_t sparse_count;
    int sparse_index_type;
    gltf_place sparse_indices, sparse_values; /* the values tightly packed */
} gltf_accessor;

/* Bytes of one component of `component_type` (0 for an unknown type). */
size_t gltf_component_size(int component_type);

/* The type's name as glTF spells it ("UNSIGNED_SHORT"; "5130" style for unknown ones: static). */
const char *gltf_component_name(int component_type);

/* Bytes of one element: `components` numbers in columns of `rows`, each column padded to 4
 * bytes. */
size_t gltf_element_size(int component_type, int components, int rows);

/* Reads every element of accessor `a` of `doc` as floats into out[count × components] (normalized
 * integers as glTF says, others as their value). 0, or -1 with the error set (a buffer that
 * cannot be read). */
int gltf_accessor_read_floats(gltf_document *doc, const gltf_accessor *a, float *out);

/* Reads every element of a SCALAR accessor of an unsigned integer type into out[count]. 0, or -1
 * with the error set. */
int gltf_accessor_read_indices(gltf_document *doc, const gltf_accessor *a, uint32_t *out);

#ifdef __cplusplus
}
#endif

#endif
