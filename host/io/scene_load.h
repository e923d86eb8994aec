/* scene_load.h — the one entry every command loads a scene through: a Mitsuba XML file
 * (io/mitsuba/mitsuba.h), a glTF 2.0 file (.gltf, .glb: io/gltf/gltf.h) or a pbrt-v4 file (.pbrt:
 * io/pbrt/pbrt.h), told apart by the extension. */
#ifndef IDMR_SCENE_LOAD_H
#define IDMR_SCENE_LOAD_H

#include <stdint.h>

#include "core/scene.h"

/* The finalized scene of `path`, or NULL with the error set (as the format's loader sets it). */
scene *scene_load(const char *path);

/* As scene_load(), with the mesh files of at least release_from vertices released once read
 * (io/mitsuba/mitsuba.h, mitsuba_load_streaming; a glTF or pbrt scene is loaded whole). */
scene *scene_load_streaming(const char *path, uint32_t release_from);

/* Whether the scene was read from a glTF file (and is written back as one). */
int scene_is_gltf(const scene *s);

/* Whether the scene was read from a pbrt-v4 file (and is written back as one). */
int scene_is_pbrt(const scene *s);

#endif
