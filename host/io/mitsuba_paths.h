/* mitsuba_paths.h — the paths a Mitsuba scene names, resolved as the loader resolves them (from
 * the directory of the file that names them, then from the scene's), shared with the writer so
 * that it rewrites every path to what the loader read. Every result is malloc'd. */
#ifndef IDMR_MITSUBA_PATHS_H
#define IDMR_MITSUBA_PATHS_H

/* dir/file (file itself when absolute or dir is empty or "."). */
char *mitsuba_path_join(const char *dir, const char *file);

/* The directory of a path ("" when it has none). */
char *mitsuba_path_directory(const char *path);

/* "dir/<base name of path>", made unique with -2, -3, ... before the extension while
 * `taken(name, context)` says another output has that name (the bundled copies of the Mitsuba
 * and glTF writers). */
char *mitsuba_path_unique(const char *dir, const char *path,
                          int (*taken)(const char *name, const void *context),
                          const void *context);

/* The realpath of an existing path, or NULL. */
char *mitsuba_path_real(const char *path);

/* The absolute form of a path that may not exist: cwd/path, without resolving links. */
char *mitsuba_path_absolute(const char *path);

/* `target` (an absolute path) relative to the directory `from_dir` (absolute), e.g.
 * "../scene/textures/wood.png"; NULL when the two share no directory below the root, or when
 * either holds "." or ".." components (a path that was never resolved). */
char *mitsuba_path_relative(const char *from_dir, const char *target);

/* `written` resolved as the loader resolves it: from the directory of `naming_file`, then from
 * `scene_dir`; when neither exists, the first. *from_scene_dir (may be NULL) is set when only
 * the second found it. */
char *mitsuba_resolve(const char *naming_file, const char *scene_dir, const char *written,
                      int *from_scene_dir);

#endif
