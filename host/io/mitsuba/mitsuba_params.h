/* mitsuba_params.h — a Mitsuba scene's <default name= value=> parameters and the `$name`
 * references that use them, shared by the loader and the writer so that both resolve a value
 * alike. The parameters are collected per file, in include order; the first definition of a
 * name wins. */
#ifndef IDMR_MITSUBA_PARAMS_H
#define IDMR_MITSUBA_PARAMS_H

#include <stddef.h>

#include <libxml/tree.h>

typedef struct mitsuba_params {
    char **names;
    char **values;
    size_t count;
} mitsuba_params;

/* The value of parameter name[0 .. length), or NULL. */
const char *mitsuba_params_lookup(const mitsuba_params *p, const char *name, size_t length);

/* Adds name = value unless name is defined already. */
void mitsuba_params_add(mitsuba_params *p, const char *name, const char *value);

/* Adds the <default> elements directly under `root`. Returns the first <default> that lacks
 * its name or value (it is skipped), or NULL when every one was complete. */
xmlNodePtr mitsuba_params_collect(mitsuba_params *p, xmlNodePtr root);

void mitsuba_params_free(mitsuba_params *p);

/* A malloc'd copy of `text` with each $name replaced by its value, or NULL if a parameter is
 * undefined; then `missing` (size bytes) gets its "$name". */
char *mitsuba_substitute(const mitsuba_params *p, const char *text, char *missing, size_t size);

#endif
