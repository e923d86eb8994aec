/* reduce_options.c — the options of `idmr reduce`: defaults, the method's name, and which
 * meshes the options keep as they are (see reduce.h, reduce_stages.h). */
#include <string.h>

#include "core/error.h"

#include "reduce/reduce_stages.h"

void reduce_options_default(reduce_options *o)
{
    memset(o, 0, sizeof *o);
    importance_options_default(&o->importance);
    o->target = 0.1;
    o->method = REDUCE_COMBINED;
    o->factor_tolerance = FACTOR_STOP_TOLERANCE;
    o->ranking_tolerance = FACTOR_STOP_RANKING_TOLERANCE;
    o->initial = 1.0;
    o->passes = 1;
    o->min_vertices = 16;
    o->max_normal_angle = 60.0;
    o->uv_weight = DECIMATE_UV_WEIGHT;
    o->normal_weight = DECIMATE_NORMAL_WEIGHT;
}

/* The methods, as --method names them, with how each chooses collapses. */
static const struct {
    const char *name;
    reduce_method method;
    decimate_method collapses;
} METHODS[] = {
    {"importance", REDUCE_IMPORTANCE, DECIMATE_IMPORTANCE},
    {"quadric", REDUCE_QUADRIC, DECIMATE_QUADRIC},
    {"importance-quadric", REDUCE_IMPORTANCE_QUADRIC, DECIMATE_QUADRIC},
    {"combined", REDUCE_COMBINED, DECIMATE_COMBINED},
};
#define METHOD_COUNT (sizeof METHODS / sizeof *METHODS)

const char *reduce_method_name(reduce_method method)
{
    for (size_t i = 0; i < METHOD_COUNT; i++)
        if (METHODS[i].method == method)
            return METHODS[i].name;
    return "unknown";
}

int reduce_method_parse(const char *name, reduce_method *method)
{
    for (size_t i = 0; i < METHOD_COUNT; i++)
        if (!strcmp(METHODS[i].name, name)) {
            *method = METHODS[i].method;
            return 0;
        }
    return error_set(IDMR_EXIT_INPUT,
                     "--method: '%s' is none of 'importance', 'quadric', 'importance-quadric' "
                     "and 'combined'",
                     name);
}

int reduce_method_uses_importance(reduce_method method) { return method != REDUCE_QUADRIC; }

decimate_method reduce_method_collapses(reduce_method method)
{
    for (size_t i = 0; i < METHOD_COUNT; i++)
        if (METHODS[i].method == method)
            return METHODS[i].collapses;
    return DECIMATE_QUADRIC;
}

static int is_kept(const reduce_options *o, const char *name)
{
    for (size_t i = 0; i < o->keep_count; i++)
        if (strcmp(o->keep[i], name) == 0)
            return 1;
    return 0;
}

/* Whether every triangle of the mesh is degenerate (zero area): welded, it has no surface to
 * decimate, and its collapses would leave a mesh without faces that no reader loads. */
static int has_no_area(const scene_mesh *mesh)
{
    for (uint32_t t = 0; t < mesh->triangle_count; t++)
        if (scene_mesh_triangle_area(mesh, t) > 0.0)
            return 0;
    return 1;
}

int reduce_mesh_pinned(const reduce_options *o, const scene_mesh *mesh)
{
    return mesh->light >= 0 || is_kept(o, mesh->name) ||
           (mesh->released ? mesh->no_area : has_no_area(mesh));
}
