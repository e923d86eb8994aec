/* gltf_accessor.c — reading the elements of glTF accessors (see gltf_accessor.h). */
#include "io/gltf/gltf_accessor.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

size_t gltf_component_size(int component_type)
{
    switch (component_type) {
    case GLTF_BYTE:
    case GLTF_UNSIGNED_BYTE:
        return 1;
    case GLTF_SHORT:
    case GLTF_UNSIGNED_SHORT:
        return 2;
    case GLTF_UNSIGNED_INT:
    case GLTF_FLOAT:
        return 4;
    default:
        return 0;
    }
}

const char *gltf_component_name(int component_type)
{
    static _Thread_local char unknown[32];
    switch (component_type) {
    case GLTF_BYTE:
        return "BYTE";
    case GLTF_UNSIGNED_BYTE:
        return "UNSIGNED_BYTE";
    case GLTF_SHORT:
        return "SHORT";
    case GLTF_UNSIGNED_SHORT:
        return "UNSIGNED_SHORT";
    case GLTF_UNSIGNED_INT:
        return "UNSIGNED_INT";
    case GLTF_FLOAT:
        return "FLOAT";
    default:
        snprintf(unknown, sizeof unknown, "%d", component_type);
        return unknown;
    }
}

size_t gltf_element_size(int component_type, int components, int rows)
{
    size_t column = gltf_component_size(component_type) * (size_t)rows;
    size_t columns = rows > 0 ? (size_t)(components / rows) : 0;
    return columns > 1 ? columns * ((column + 3) & ~(size_t)3) : column;
}

/* The bytes of place `p` on: NULL with the error set when its buffer cannot be read. */
static const unsigned char *bytes_at(gltf_document *doc, gltf_place p)
{
    const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(doc->json, "buffers");
    const gltf_bytes *bytes =
        gltf_document_buffer(doc, p.buffer, cJSON_GetArrayItem(buffers, p.buffer));
    return bytes ? bytes->data + p.offset : NULL;
}

/* Component k of the element at `element` (its first byte), as glTF reads it. */
static float component(const gltf_accessor *a, const unsigned char *element, int k)
{
    size_t size = gltf_component_size(a->component_type);
    size_t column = (size * (size_t)a->rows + 3) & ~(size_t)3;
    const unsigned char *c =
        element + (a->components > a->rows ? (size_t)(k / a->rows) * column : 0) +
        (size_t)(k % a->rows) * size;
    uint32_t u = 0;
    for (size_t i = 0; i < size; i++) /* little-endian, as glTF */
        u |= (uint32_t)c[i] << (8 * i);
    float value;
    switch (a->component_type) {
    case GLTF_FLOAT:
        memcpy(&value, &u, sizeof value);
        return value;
    case GLTF_BYTE:
        value = (float)(int8_t)u;
        return a->normalized ? (value / 127.0f < -1.0f ? -1.0f : value / 127.0f) : value;
    case GLTF_SHORT:
        value = (float)(int16_t)u;
        return a->normalized ? (value / 32767.0f < -1.0f ? -1.0f : value / 32767.0f) : value;
    case GLTF_UNSIGNED_BYTE:
        return a->normalized ? (float)u / 255.0f : (float)u;
    case GLTF_UNSIGNED_SHORT:
        return a->normalized ? (float)u / 65535.0f : (float)u;
    default:
        return (float)u;
    }
}

/* The sparse element numbers of `a` into numbers[sparse_count]; 0 or -1. */
static int sparse_numbers(gltf_document *doc, const gltf_accessor *a, uint32_t *numbers)
{
    const unsigned char *p = bytes_at(doc, a->sparse_indices);
    if (!p)
        return -1;
    size_t size = gltf_component_size(a->sparse_index_type);
    for (uint32_t i = 0; i < a->sparse_count; i++) {
        uint32_t u = 0;
        for (size_t b = 0; b < size; b++)
            u |= (uint32_t)p[i * size + b] << (8 * b);
        numbers[i] = u;
    }
    return 0;
}

int gltf_accessor_read_floats(gltf_document *doc, const gltf_accessor *a, float *out)
{
    size_t n = (size_t)a->components;
    if (a->data.buffer < 0) {
        memset(out, 0, sizeof(float) * n * a->count);
    } else {
        const unsigned char *p = bytes_at(doc, a->data);
        if (!p)
            return -1;
        for (uint32_t e = 0; e < a->count; e++)
            for (size_t k = 0; k < n; k++)
                out[e * n + k] = component(a, p + (size_t)e * a->stride, (int)k);
    }
    if (!a->sparse_count)
        return 0;
    uint32_t *numbers = xmalloc(sizeof(uint32_t) * a->sparse_count);
    const unsigned char *values = NULL;
    int status = sparse_numbers(doc, a, numbers);
    if (!status && !(values = bytes_at(doc, a->sparse_values)))
        status = -1;
    for (uint32_t i = 0; i < a->sparse_count && !status; i++)
        for (size_t k = 0; k < n; k++)
            out[(size_t)numbers[i] * n + k] =
                component(a, values + (size_t)i * a->element_size, (int)k);
    free(numbers);
    return status;
}

int gltf_accessor_read_indices(gltf_document *doc, const gltf_accessor *a, uint32_t *out)
{
    size_t size = gltf_component_size(a->component_type);
    if (a->data.buffer < 0) {
        memset(out, 0, sizeof(uint32_t) * a->count);
    } else {
        const unsigned char *p = bytes_at(doc, a->data);
        if (!p)
            return -1;
        for (uint32_t e = 0; e < a->count; e++) {
            const unsigned char *c = p + (size_t)e * a->stride;
            uint32_t u = 0;
            for (size_t b = 0; b < size; b++)
                u |= (uint32_t)c[b] << (8 * b);
            out[e] = u;
        }
    }
    if (!a->sparse_count)
        return 0;
    uint32_t *numbers = xmalloc(sizeof(uint32_t) * a->sparse_count);
    const unsigned char *values = NULL;
    int status = sparse_numbers(doc, a, numbers);
    if (!status && !(values = bytes_at(doc, a->sparse_values)))
        status = -1;
    for (uint32_t i = 0; i < a->sparse_count && !status; i++) {
        uint32_t u = 0;
        for (size_t b = 0; b < size; b++)
            u |= (uint32_t)values[(size_t)i * size + b] << (8 * b);
        out[numbers[i]] = u;
    }
    free(numbers);
    return status;
}
