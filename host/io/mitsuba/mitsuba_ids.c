/* mitsuba_ids.c — the id table: every top-level declaration with an id (bsdf, texture, area
 * emitter), in declaration order, for the <ref id=...> elements after it. An entry points into
 * its document's tree; a bsdf's entry also keeps what its declaration parsed. */
#include "io/mitsuba/mitsuba_loader.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"

static mitsuba_id *id_find(loader *ld, const char *id)
{
    for (size_t i = 0; i < ld->id_count; i++)
        if (strcmp(ld->ids[i].id, id) == 0)
            return &ld->ids[i];
    return NULL;
}

int mitsuba_id_register(loader *ld, xmlNodePtr node)
{
    const char *id = mitsuba_attr(node, "id");
    if (!id)
        return 0;
    if (id_find(ld, id))
        return mitsuba_fail(node, "duplicate id '%s'", id);
    ld->ids = xrealloc(ld->ids, (ld->id_count + 1) * sizeof *ld->ids);
    ld->ids[ld->id_count].id = xstrdup(id);
    ld->ids[ld->id_count].node = node;
    ld->ids[ld->id_count].bsdf = NULL;
    ld->ids[ld->id_count].material = -1;
    ld->id_count++;
    return 0;
}

mitsuba_id *mitsuba_ref_resolve(loader *ld, xmlNodePtr ref)
{
    const char *id;
    if (mitsuba_require_attr(ref, "id", &id))
        return NULL;
    mitsuba_id *entry = id_find(ld, id);
    if (!entry)
        mitsuba_fail(ref, "unknown id '%s' (ids must be declared before they are referenced)", id);
    return entry;
}

void mitsuba_ids_free(loader *ld)
{
    for (size_t i = 0; i < ld->id_count; i++) {
        free(ld->ids[i].id);
        free(ld->ids[i].bsdf);
    }
    free(ld->ids);
}
