/* reduce_options.c — the options of `idmr reduce`: defaults, the method's name, and the options
 * stage, which checks them against each other and the scene (see reduce.h, reduce_stages.h). */
#include <math.h>
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
    o->error.step = REDUCE_ERROR_STEP;
    o->error.iterations = REDUCE_ERROR_ITERATIONS;
    o->error.resolution = REDUCE_ERROR_RESOLUTION;
    o->error.photons = REDUCE_ERROR_PHOTONS;
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

/* --max-error (or --max-error-relative) at least 0 and finite, the search's step and check
 * renders sane, and none of the options that set the target or stage the reduction beside it
 * (--memory-budget, --initial, --passes): the search reuses one importance pass of the whole
 * scene for every budget it measures. */
static int reduce_error_options_check(const reduce_options *o)
{
    const reduce_error_options *e = &o->error;
    if (e->bound == REDUCE_ERROR_NONE)
        return 0;
    const char *name = e->bound == REDUCE_ERROR_RELATIVE ? "--max-error-relative" : "--max-error";
    if (!(e->max_error >= 0) || !isfinite(e->max_error))
        return error_set(IDMR_EXIT_INPUT, "%s must be a finite number of at least 0, not %g",
                         name, e->max_error);
    if (!(e->step > 0 && e->step <= 10))
        return error_set(IDMR_EXIT_INPUT, "--max-error-step must be in (0, 10], not %g",
                         e->step);
    if (e->iterations < 1)
        return error_set(IDMR_EXIT_INPUT, "--check-iterations must be at least 1");
    if (!(e->resolution > 0 && e->resolution <= 4))
        return error_set(IDMR_EXIT_INPUT, "--check-resolution must be in (0, 4], not %g",
                         e->resolution);
    if (o->memory_budget || o->initial < 1 || o->passes > 1)
        return error_set(IDMR_EXIT_INPUT, "%s searches the target over one importance pass of "
                                          "the whole scene: it cannot be combined with "
                                          "--memory-budget, --initial or --passes",
                         name);
    return 0;
}

/* --target and --initial in (0, 1], --passes in 1 .. REDUCE_MAX_PASSES and only with a method
 * that has an importance pass (and not with --simulation, a pass of the whole scene); every
 * --keep name is a mesh of the scene. */
int reduce_options_check(const reduce_state *st)
{
    const reduce_options *o = st->options;
    const scene *s = st->scene;
    if (!(o->target > 0 && o->target <= 1))
        return error_set(IDMR_EXIT_INPUT, "--target must be in (0, 1], not %g", o->target);
    if (!(o->initial > 0 && o->initial <= 1))
        return error_set(IDMR_EXIT_INPUT, "--initial must be in (0, 1], not %g", o->initial);
    if (o->passes < 1 || o->passes > REDUCE_MAX_PASSES)
        return error_set(IDMR_EXIT_INPUT, "--passes must be 1 to %u, not %u", REDUCE_MAX_PASSES,
                         o->passes);
    int staged = o->initial < 1 || o->passes > 1;
    if (staged && !reduce_method_uses_importance(o->method))
        return error_set(IDMR_EXIT_INPUT, "--initial and --passes are for the methods with an "
                                          "importance pass, not '%s'",
                         reduce_method_name(o->method));
    if ((staged || o->memory_budget) && o->simulation)
        return error_set(IDMR_EXIT_INPUT, "--simulation is a pass over the whole scene: it "
                                          "cannot be combined with --initial, --passes or "
                                          "--memory-budget");
    if (reduce_error_options_check(o))
        return -1;
    if (o->refine > REDUCE_MAX_REFINE)
        return error_set(IDMR_EXIT_INPUT, "--refine must be 0 to %u, not %u", REDUCE_MAX_REFINE,
                         o->refine);
    if (o->refine && !reduce_method_uses_importance(o->method))
        return error_set(IDMR_EXIT_INPUT, "--refine moves importance: it is for the methods "
                                          "with an importance pass, not '%s'",
                         reduce_method_name(o->method));
    if (o->refine && (o->memory_budget || staged))
        return error_set(IDMR_EXIT_INPUT, "--refine mixes an importance pass of the whole "
                                          "original scene into the importance: it cannot be "
                                          "combined with --memory-budget, --initial or "
                                          "--passes");
    if (o->refine && (!(o->error.resolution > 0 && o->error.resolution <= 4) ||
                      o->error.iterations < 1))
        return error_set(IDMR_EXIT_INPUT, "--check-resolution must be in (0, 4] and "
                                          "--check-iterations at least 1");
    for (size_t k = 0; k < o->keep_count; k++) {
        size_t m = 0;
        while (m < s->mesh_count && strcmp(s->meshes[m].name, o->keep[k]))
            m++;
        if (m == s->mesh_count)
            return error_set(IDMR_EXIT_INPUT, "--keep %s: the scene has no mesh of that name "
                                              "(see `idmr info`)", o->keep[k]);
    }
    return 0;
}
