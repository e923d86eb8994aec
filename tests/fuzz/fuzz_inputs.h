/* fuzz_inputs.h — how one fuzzer input is fed to idmr's readers, shared by the libFuzzer
 * targets (tests/fuzz/fuzz_*.c, `make fuzz`) and by test_fuzz_inputs.c, which replays every
 * stored input (seeds and the crashes and hangs fuzzing found) in `make test`.
 *
 *   fuzz_scene_input   the bytes are a scene in up to six files, split at lines that read
 *                      FUZZ_FILE_SEPARATOR: scene.xml, a.xml, b.xml (for <include>), m.obj,
 *                      m.ply, m.off (for shapes); the scene is loaded with mitsuba_load()
 *   fuzz_mesh_input    the bytes are one mesh file of the given extension, read with
 *                      mesh_io_read_oriented() (as a shape with vertex normals is read)
 *   fuzz_simulation_input
 *                      the bytes are a simulation file (`idmr importance` DIR/simulation.bin,
 *                      passes/importance_file.h), read with importance_file_read() for the
 *                      shipped Cornell box without its knot (fuzz_simulation_scene); where
 *                      the bytes start with the magic and hold a header, their scene
 *                      fingerprint and closing checksum are first set to what the reader
 *                      expects, so the fuzzer reaches the checks behind them (a damaged
 *                      checksum is a compare that needs no fuzzing)
 *   fuzz_pbrt_input    the bytes are a pbrt-v4 scene in up to three files, split as for
 *                      fuzz_scene_input: scene.pbrt, a.pbrt (for Include), m.ply (for plymesh);
 *                      the scene is loaded with pbrt_load()
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
#include "io/gltf/gltf.h"
#include "io/mesh/mesh_io.h"
#include "io/mitsuba/mitsuba.h"
#include "io/pbrt/pbrt.h"
#include "passes/importance_file.h"

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

static const char *const fuzz_pbrt_files[] = {"scene.pbrt", "a.pbrt", "m.ply"};
#define FUZZ_PBRT_FILES (sizeof fuzz_pbrt_files / sizeof *fuzz_pbrt_files)

static inline int fuzz_pbrt_input(const uint8_t *data, size_t size, const char *dir)
{
    size_t length = strlen(FUZZ_FILE_SEPARATOR);
    for (size_t f = 0; f < FUZZ_PBRT_FILES; f++) {
        size_t end = fuzz_part_end(data, size);
        if (fuzz_write(dir, fuzz_pbrt_files[f], data, end))
            abort(); /* the harness's own failure, not the reader's */
        size_t next = end + length <= size ? end + length : size;
        data += next;
        size -= next;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/scene.pbrt", dir);
    error_clear();
    scene *s = pbrt_load(path);
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

/* The scene the simulation target reads for: IDMR_ROOT/data/cornell/scene.xml with the knot's
 * shape left out (its walls, block and light: a few dozen triangles, so a simulation file of
 * it is small), written to dir/cornell-walls.xml and loaded; NULL with the error set. */
static inline scene *fuzz_simulation_scene(const char *root, const char *dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/data/cornell/scene.xml", root);
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    static char xml[1 << 16];
    size_t size = fread(xml, 1, sizeof xml - 1, f);
    fclose(f);
    xml[size] = 0;
    char *knot = strstr(xml, "<shape type=\"ply\" id=\"knot\">");
    char *end = knot ? strstr(knot, "</shape>") : NULL;
    if (!end)
        return NULL;
    end += strlen("</shape>");
    memmove(knot, end, strlen(end) + 1);
    if (fuzz_write(dir, "cornell-walls.xml", (const uint8_t *)xml, strlen(xml)))
        return NULL;
    snprintf(path, sizeof path, "%s/cornell-walls.xml", dir);
    return mitsuba_load(path);
}

#define FUZZ_SIMULATION_HEADER 80 /* magic (8) and the fixed header (72; version 5: 80) */

static inline uint64_t fuzz_fnv1a(const uint8_t *bytes, size_t size)
{
    uint64_t hash = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < size; i++)
        hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    return hash;
}

static inline int fuzz_simulation_input(const uint8_t *data, size_t size, const char *dir,
                                        const scene *s)
{
    uint8_t *bytes = malloc(size ? size : 1);
    memcpy(bytes, data, size);
    uint64_t fingerprint;
    if (importance_file_fingerprint(s, &fingerprint))
        abort();
    if (size >= FUZZ_SIMULATION_HEADER + sizeof(uint64_t) &&
        (memcmp(bytes, "IDMRSIM4", 8) == 0 || memcmp(bytes, "IDMRSIM5", 8) == 0)) {
        memcpy(bytes + 8, &fingerprint, sizeof fingerprint);
        uint64_t checksum = fuzz_fnv1a(bytes, size - sizeof checksum);
        memcpy(bytes + size - sizeof checksum, &checksum, sizeof checksum);
    }
    int written = fuzz_write(dir, "simulation.bin", bytes, size);
    free(bytes);
    if (written)
        abort();
    char path[4096];
    snprintf(path, sizeof path, "%s/simulation.bin", dir);
    error_clear();
    importance_options o;
    importance_options_default(&o);
    importance_result r;
    int status = importance_file_read(path, s, &o, &r);
    importance_result_free(&r);
    return status == 0;
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
