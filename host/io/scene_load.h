/* scene_load.h — the one entry every command loads a scene through: a Mitsuba XML file
 * (io/mitsuba.h) or a glTF 2.0 file (.gltf, .glb: io/gltf.h), told apart by the extension. */
#ifndef IDMR_SCENE_LOAD_H
#define IDMR_SCENE_LOAD_H

#include "core/scene.h"

/* The finalized scene of `path`, or NULL with the error set (as the format's loader sets it). */
scene *scene_load(const char *path);

/* Whether the scene was read from a glTF file (and is written back as one). */
int scene_is_gltf(const scene *s);

#endif
