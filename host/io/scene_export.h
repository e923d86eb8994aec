/* scene_export.h — a loaded scene written whole in another renderer's format (`idmr convert`):
 * what idmr read, written so that idmr (and the other renderer) reads it back as the same scene.
 *
 * The format is the one OUT's extension names (any case):
 *   .xml    a Mitsuba 3 scene (io/mitsuba/export_mitsuba.c)
 *   .pbrt   a pbrt-v4 scene (io/pbrt/export_pbrt.c)
 * Every mesh is written as a world-space binary PLY (positions, the shading normals where the
 * mesh has smooth ones, texture coordinates) into a folder beside OUT named after OUT's stem:
 * `-o out/cornell.xml` writes out/cornell.xml and out/cornell/<mesh>.ply; the environment map,
 * if any, goes there too (out/cornell/environment.exr). The scene names them relative to its own
 * directory, and textures by their path relative to it (absolute where no relative path
 * exists), so the output can move with its folder.
 *
 * Writing is all or nothing: the folder is staged (core/files.h: files_stage_begin) and
 * published before the scene file, which goes through a temporary name and rename(). Inputs are
 * never written (scene_check_output_file, scene_check_output_directory). An existing OUT, or a
 * folder that holds something, is refused unless `force` is set (then the folder's files of the
 * same names are replaced and OUT overwritten). */
#ifndef IDMR_SCENE_EXPORT_H
#define IDMR_SCENE_EXPORT_H

#include "core/scene.h"

typedef enum scene_export_format {
    SCENE_EXPORT_MITSUBA,
    SCENE_EXPORT_PBRT,
} scene_export_format;

/* The format `path`'s extension names; -1 with the error set (IDMR_EXIT_INPUT) for any other
 * extension, naming those it takes. */
int scene_export_format_of(const char *path, scene_export_format *format);

/* Writes `s` (a finalized scene: scene_load()) to `out` in the format of its extension (see
 * above); a released mesh is read back first (scene_mesh_restore). 0, or -1 with the error set:
 * an unknown extension, an output that is an input, an existing output without `force`, a failed
 * write. */
int scene_export(scene *s, const char *out, int force);

#endif
