/* gltf_common.h — shared by the glTF tests (test_gltf.c, test_gltf_inputs.c): a little-endian
 * 32-bit word and a GLB container built around a JSON text and a binary chunk. Header-only
 * (static functions). */
#ifndef IDMR_TESTS_GLTF_COMMON_H
#define IDMR_TESTS_GLTF_COMMON_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16),
    p[3] = (unsigned char)(v >> 24);
}

/* A GLB (malloc'd, *total bytes): the 12-byte header, the JSON chunk padded with spaces, the BIN
 * chunk padded with zeros. */
static unsigned char *glb_pack(const char *text, const void *bin, size_t bin_size, size_t *total)
{
    size_t json = (strlen(text) + 3) & ~(size_t)3, data = (bin_size + 3) & ~(size_t)3;
    *total = 12 + 8 + json + 8 + data;
    unsigned char *glb = calloc(*total, 1);
    memcpy(glb, "glTF", 4);
    put_u32(glb + 4, 2), put_u32(glb + 8, (uint32_t)*total);
    put_u32(glb + 12, (uint32_t)json), memcpy(glb + 16, "JSON", 4);
    memset(glb + 20, ' ', json);
    memcpy(glb + 20, text, strlen(text));
    put_u32(glb + 20 + json, (uint32_t)data), memcpy(glb + 24 + json, "BIN", 4);
    if (bin_size)
        memcpy(glb + 28 + json, bin, bin_size);
    return glb;
}

#endif
