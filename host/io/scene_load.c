/* scene_load.c — a scene file of any format in (see scene_load.h). */
#include "io/scene_load.h"

#include "core/progress.h"
#include "io/gltf/gltf.h"
#include "io/mitsuba/mitsuba.h"
#include "io/pbrt/pbrt.h"

/* The scene with the seconds its loading took. */
static scene *timed(scene *s, double start)
{
    if (s)
        s->load_seconds = monotonic_seconds() - start;
    return s;
}

scene *scene_load(const char *path)
{
    double start = monotonic_seconds();
    if (pbrt_is_scene_file(path))
        return timed(pbrt_load(path), start);
    return timed(gltf_is_scene_file(path) ? gltf_load(path) : mitsuba_load(path), start);
}

scene *scene_load_streaming(const char *path, uint32_t release_from)
{
    double start = monotonic_seconds();
    if (pbrt_is_scene_file(path)) /* loaded whole */
        return timed(pbrt_load(path), start);
    return timed(gltf_is_scene_file(path) ? gltf_load(path)
                                          : mitsuba_load_streaming(path, release_from),
                 start);
}

int scene_is_gltf(const scene *s) { return gltf_is_scene_file(s->file); }

int scene_is_pbrt(const scene *s) { return pbrt_is_scene_file(s->file); }
