/* reduce_options.c — the options of `idmr reduce`: defaults, the method's name, and which
 * meshes the options keep as they are (see reduce.h, reduce_stages.h). */
#include <string.h>

#include "reduce/reduce_stages.h"

void reduce_options_default(reduce_options *o)
{
    memset(o, 0, sizeof *o);
    importance_options_default(&o->importance);
    o->target = 0.1;
    o->method = DECIMATE_IMPORTANCE;
    o->min_vertices = 16;
    o->max_normal_angle = 60.0;
}

const char *reduce_method_name(const reduce_options *o)
{
    if (o->method == DECIMATE_QUADRIC)
        return "quadric";
    return o->quadric_collapses ? "importance-quadric" : "importance";
}

static int is_kept(const reduce_options *o, const char *name)
{
    for (size_t i = 0; i < o->keep_count; i++)
        if (strcmp(o->keep[i], name) == 0)
            return 1;
    return 0;
}

int reduce_mesh_pinned(const reduce_options *o, const scene_mesh *mesh)
{
    return mesh->light >= 0 || is_kept(o, mesh->name);
}
