/* export_internal.h — what the scene writers of `idmr convert` share (io/scene_export.c): the
 * job (paths, the names given to meshes and materials, the files written into the staging
 * folder), a growing text buffer, and the camera frame both formats start from. Each format
 * gives one function that writes what only it needs into the staging folder and then appends
 * the scene's text. */
#ifndef IDMR_EXPORT_INTERNAL_H
#define IDMR_EXPORT_INTERNAL_H

#include <limits.h>
#include <stddef.h>

#include "core/scene.h"

/* A text that grows as it is written (never fails: xrealloc). */
typedef struct export_text {
    char *data;
    size_t length, capacity;
} export_text;

void export_printf(export_text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void export_text_free(export_text *t);

typedef struct export_job {
    scene *s;
    const char *out;          /* the scene file to write */
    char out_dir[PATH_MAX];   /* its directory ("." when it has none) */
    char folder_name[256];    /* the mesh folder, relative to out_dir: OUT's stem */
    char folder[PATH_MAX];    /* out_dir/folder_name, where it is published */
    char staging[PATH_MAX];   /* where its files are written first */
    char **mesh_names;        /* per mesh: its name in the output (unique, file-safe) or NULL
                                 when it is left out (no triangles) */
    char **mesh_files;        /* per mesh: "<folder_name>/<mesh_name>.ply", relative to out_dir */
    char **material_names;    /* per material: unique, file-safe; NULL when no mesh written
                                 uses it */
    char **texture_files;     /* per texture: its path as the scene names it (relative to
                                 out_dir where possible) */
    char *environment_file;   /* "<folder_name>/environment.exr" once a format wrote it */
} export_job;

/* The writers: files of their own into job->staging (the environment map), then the scene's
 * text into `text`. 0, or -1 with the error set. */
int export_mitsuba(export_job *job, export_text *text);
int export_pbrt(export_job *job, export_text *text);

/* The camera as a frame: image right, image up, forward (unit, world space) and the origin;
 * both formats build their camera transform from it (scene_camera_info's to_world is in the
 * input format's own convention, a glTF node's for a glTF scene). */
void export_camera_frame(const idmr_camera *c, double right[3], double up[3], double forward[3],
                         double origin[3]);

/* Two unit vectors completing unit `axis` to an orthonormal frame (x, y, axis), right-handed. */
void export_frame_around(const double axis[3], double x[3], double y[3]);

/* A float as the shortest text that reads back as the same float ("%.9g"). */
const char *export_float(char buffer[32], double value);

#endif
