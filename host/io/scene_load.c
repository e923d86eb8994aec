/* scene_load.c — a scene file of either format in (see scene_load.h). */
#include "io/scene_load.h"

#include "io/gltf.h"
#include "io/mitsuba.h"

scene *scene_load(const char *path)
{
    return gltf_is_scene_file(path) ? gltf_load(path) : mitsuba_load(path);
}

scene *scene_load_streaming(const char *path, uint32_t release_from)
{
    return gltf_is_scene_file(path) ? gltf_load(path)
                                    : mitsuba_load_streaming(path, release_from);
}

int scene_is_gltf(const scene *s) { return gltf_is_scene_file(s->file); }
