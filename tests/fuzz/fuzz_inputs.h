/* fuzz_inputs.h — how one fuzzer input is fed to idmr's readers, shared by the libFuzzer
 * targets (tests/fuzz/fuzz_*.c, `make fuzz`) and by test_fuzz_inputs.c, which replays every
 * stored input (seeds and the crashes and hangs fuzzing found) in `make test`.
 *
 *   fuzz_scene_input   the bytes are a scene in up to six files, split at lines that read
 *                      FUZZ_FILE_SEPARATOR: scene.xml, a.xml, b.xml (for <include>), m.obj,
 *                      m.ply, m.off (for shapes); the scene is loaded with mitsuba_load()
 *   fuzz_mesh_input    the bytes are one mesh file of the given extension, read with
 *                      mesh_io_read_oriented() (as a shape with vertex normals is read)
 *   fuzz_gltf_input    the bytes are one glTF file: scene.glb when they begin with "glTF",
 *                      else scene.gltf (its buffers as data: URIs or the GLB's BIN chunk), loaded
 *                      with gltf_load(): the document reader and checks, then Assimp on what
 *                      they let through
 *
 * Either returns whether the reader accepted the input; a rejected input must leave a message
 * (the error set), never a crash, a hang or a leak. Files go to a directory the caller made. */
#ifndef IDMR_FUZZ_INPUTS_H
#define IDMR_FUZZ_INPUTS_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/scene.h"
#include "io/gltf.h"
#include "io/mesh_io.h"
#include "io/mitsuba.h"

#define FUZZ_FILE_SEPARATOR "--idmr-fuzz-next-file--\n"

static const char *const fuzz_scene_files[] = {"scene.xml", "a.xml", "b.xml",
                                                "m.obj",     "m.ply", "m.off"};
#define FUZZ_SCENE_FILES (sizeof fuzz_scene_files / sizeof *fuzz_scene_files)

/* Writes size bytes to dir/name; 0 on success. */
static inline int fuzz_write(const char *dir, const char *name, const uint8_t *data, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(data, 1, size, f) == size;
    return fclose(f) == 0 && ok ? 0 : -1;
}

/* Where the separator next occurs in data[0 .. size), or size. */
static inline size_t fuzz_part_end(const uint8_t *data, size_t size)
{
    size_t length = strlen(FUZZ_FILE_SEPARATOR);
    for (size_t i = 0; i + length <= size; i++)
        if (memcmp(data + i, FUZZ_FILE_SEPARATOR, length) == 0)
            return i;
    return size;
}

static inline int fuzz_scene_input(const uint8_t *data, size_t size, const char *dir)
{
    size_t length = strlen(FUZZ_FILE_SEPARATOR);
    for (size_t f = 0; f < FUZZ_SCENE_FILES; f++) {
        size_t end = fuzz_part_end(data, size);
        if (fuzz_write(dir, fuzz_scene_files[f], data, end))
            abort(); /* the harness's own failure, not the reader's */
        size_t next = end + length <= size ? end + length : size;
        data += next;
        size -= next;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    error_clear();
    scene *s = mitsuba_load(path);
    if (!s)
        return 0;
    scene_free(s);
    return 1;
}

static inline int fuzz_mesh_input(const uint8_t *data, size_t size, const char *dir,
                                  const char *extension)
{
    char name[64], path[4096];
    snprintf(name, sizeof name, "mesh%s", extension);
    if (fuzz_write(dir, name, data, size))
        abort();
    snprintf(path, sizeof path, "%s/%s", dir, name);
    error_clear();
    mesh_data mesh;
    uint32_t flipped = 0;
    if (mesh_io_read_oriented(path, &mesh, 1, &flipped))
        return 0;
    mesh_data_free(&mesh);
    return 1;
}

static inline int fuzz_gltf_input(const uint8_t *data, size_t size, const char *dir)
{
    const char *name = size >= 4 && memcmp(data, "glTF", 4) == 0 ? "scene.glb" : "scene.gltf";
    char path[4096];
    if (fuzz_write(dir, name, data, size))
        abort();
    snprintf(path, sizeof path, "%s/%s", dir, name);
    error_clear();
    scene *s = gltf_load(path);
    if (!s)
        return 0;
    scene_free(s);
    return 1;
}

#endif
