/* mitsuba_text.h — what the Mitsuba loader (mitsuba.c) and the reduced-scene writer
 * (mitsuba_write.c) must do alike, so that the writer resolves every value exactly as the
 * loader does: element and attribute access, the include depth, `<default>` parameters and
 * `$name` substitution, and the resolution of relative paths (from the directory of the file
 * that names them, then from the scene's). */
#ifndef IDMR_MITSUBA_TEXT_H
#define IDMR_MITSUBA_TEXT_H

#include <stddef.h>

#include <libxml/tree.h>

/* <include> elements nest at most this deep (the loader and the writer follow the same). */
#define MITSUBA_MAX_INCLUDE_DEPTH 16

/* Whether node is an element named `tag`. */
int mitsuba_is_tag(xmlNodePtr node, const char *tag);

/* An attribute's value as stored in the tree (no copy), "" for an empty one, NULL if absent. */
const char *mitsuba_attr(xmlNodePtr node, const char *name);

/* The <default name= value=> parameters of a scene; the first definition of a name wins. */
typedef struct mitsuba_params {
    char **names;
    char **values;
    size_t count;
} mitsuba_params;

/* The value of parameter name[0 .. length), or NULL. */
const char *mitsuba_params_lookup(const mitsuba_params *p, const char *name, size_t length);

/* Adds name = value unless name is defined already. */
void mitsuba_params_add(mitsuba_params *p, const char *name, const char *value);
void mitsuba_params_free(mitsuba_params *p);

/* A malloc'd copy of `text` with each $name replaced by its value, or NULL if a parameter is
 * undefined; then `missing` (size bytes) gets its "$name". */
char *mitsuba_substitute(const mitsuba_params *p, const char *text, char *missing, size_t size);

/* dir/file (file itself when absolute or dir is empty or "."), and the directory of a path
 * ("" when it has none); both malloc'd. */
char *mitsuba_path_join(const char *dir, const char *file);
char *mitsuba_path_directory(const char *path);

/* `written` resolved as the loader resolves it: from the directory of `naming_file`, then from
 * `scene_dir`; when neither exists, the first. *from_scene_dir (may be NULL) is set when only
 * the second found it. Malloc'd. */
char *mitsuba_resolve(const char *naming_file, const char *scene_dir, const char *written,
                      int *from_scene_dir);

#endif
