/* command_reduce.c — `idmr reduce SCENE --target D -o OUTDIR [options]`: the reduced scene
 * (reduce/reduce.h: importance pass, budget, decimation, writing OUTDIR); `--max-error E` (or
 * `--max-error-relative F`) instead of --target searches the smallest D within that image
 * error (reduce_error_budget.c); `--refine N` refines the reduction by its measured change
 * (reduce_refine.c). Options: the importance pass's (options.h) and the
 * reduction's own. */
#include <malloc.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/pass_setup.h"
#include "core/error.h"
#include "device/device.h"
#include "io/scene_load.h"
#include "reduce/reduce.h"

/* The options, and whether --target was given (it has no default on the command line). */
typedef struct reduce_cli_request {
    reduce_options options;
    int have_target;
    int error_bounds; /* --max-error and --max-error-relative given: at most one may be */
    int search_options; /* --max-error-step given: only with --max-error(-relative) */
    int check_options;  /* --check-* given: only with it or --refine */
} reduce_cli_request;

/* --max-error E or --max-error-relative F (reduce.h, reduce_error_options). */
static enum option_parse parse_error_bound(reduce_cli_request *request, const char *name,
                                           reduce_error_bound bound)
{
    request->error_bounds++;
    request->options.error.bound = bound;
    return option_result(parse_double(name, optarg, 0, 1e30, &request->options.error.max_error));
}

static enum option_parse parse_option(int c, void *context, pass_arguments *arguments)
{
    reduce_cli_request *request = context;
    reduce_options *o = &request->options;
    unsigned int whole;
    switch (c) {
    case OPT_TARGET:
        request->have_target = 1;
        return option_result(parse_double("--target", optarg, 1e-9, 1, &o->target));
    case OPT_METHOD:
        return option_result(reduce_method_parse(optarg, &o->method));
    case OPT_MIN_VERTICES:
        if (parse_unsigned("--min-vertices", optarg, 0, 0xffffffffu, &whole))
            return OPTION_BAD_VALUE;
        o->min_vertices = whole;
        return OPTION_TAKEN;
    case OPT_MAX_NORMAL_ANGLE:
        return option_result(
            parse_double("--max-normal-angle", optarg, 1, 180, &o->max_normal_angle));
    case OPT_UV_WEIGHT:
        return option_result(parse_double("--uv-weight", optarg, 0, 1e6, &o->uv_weight));
    case OPT_NORMAL_WEIGHT:
        return option_result(parse_double("--normal-weight", optarg, 0, 1e6, &o->normal_weight));
    case OPT_KEEP:
        o->keep[o->keep_count++] = optarg;
        return OPTION_TAKEN;
    case OPT_FORCE:
        o->force = 1;
        return OPTION_TAKEN;
    case OPT_BUNDLE:
        o->bundle = 1;
        return OPTION_TAKEN;
    case OPT_RECOMPUTE_NORMALS:
        o->recompute_normals = 1;
        return OPTION_TAKEN;
    case OPT_THREADS:
        return option_result(parse_unsigned("--threads", optarg, 1, 1024, &o->threads));
    case OPT_FACTOR_TOLERANCE:
        return option_result(
            parse_double("--factor-tolerance", optarg, 0, 2, &o->factor_tolerance));
    case OPT_SIMULATION:
        o->simulation = optarg;
        return OPTION_TAKEN;
    case OPT_INITIAL:
        return option_result(parse_double("--initial", optarg, 1e-9, 1, &o->initial));
    case OPT_PASSES:
        return option_result(
            parse_unsigned("--passes", optarg, 1, REDUCE_MAX_PASSES, &o->passes));
    case OPT_MEMORY_BUDGET:
        return option_result(parse_bytes("--memory-budget", optarg, &o->memory_budget));
    case OPT_RANKING_TOLERANCE:
        return option_result(
            parse_double("--ranking-tolerance", optarg, 0, 2, &o->ranking_tolerance));
    case OPT_MAX_ERROR:
        return parse_error_bound(request, "--max-error", REDUCE_ERROR_ABSOLUTE);
    case OPT_MAX_ERROR_RELATIVE:
        return parse_error_bound(request, "--max-error-relative", REDUCE_ERROR_RELATIVE);
    case OPT_MAX_ERROR_STEP:
        request->search_options++;
        break;
    case OPT_CHECK_ITERATIONS:
    case OPT_CHECK_RESOLUTION:
    case OPT_CHECK_PHOTONS:
        request->check_options++;
        break;
    case OPT_REFINE:
        return option_result(parse_unsigned("--refine", optarg, 0, REDUCE_MAX_REFINE, &o->refine));
    default:
        break;
    }
    switch (c) {
    case OPT_MAX_ERROR_STEP:
        return option_result(parse_double("--max-error-step", optarg, 1e-6, 10, &o->error.step));
    case OPT_CHECK_ITERATIONS:
        return option_result(
            parse_unsigned("--check-iterations", optarg, 1, 1u << 20, &o->error.iterations));
    case OPT_CHECK_RESOLUTION:
        return option_result(
            parse_double("--check-resolution", optarg, 1e-3, 4, &o->error.resolution));
    case OPT_CHECK_PHOTONS:
        return option_result(
            parse_unsigned("--check-photons", optarg, 1, 1u << 30, &o->error.photons));
    default:
        return parse_importance_option(c, &o->importance, &arguments->devices);
    }
}

/* The reduction: this command's call into reduce/. */
static int run_reduce(const pass_arguments *arguments, const reduce_options *o)
{
    /* Under a memory budget the large meshes are read mesh by mesh where they are needed
     * (streaming: reduce.h), not held all at once; and every block of a mebibyte or more is
     * mapped on its own, so freeing a mesh hands its memory back at once (glibc otherwise raises
     * that threshold as large blocks are freed, and keeps them in its heaps). */
    if (o->memory_budget)
        mallopt(M_MMAP_THRESHOLD, 1 << 20);
    scene *s = o->memory_budget ? scene_load_streaming(arguments->scene, REDUCE_INITIAL_FLOOR)
                                : scene_load(arguments->scene);
    if (!s)
        return fail();
    device devices[SPPM_MAX_DEVICES];
    unsigned int count;
    int status = pass_setup_open_devices(&arguments->devices, devices, &count);
    if (!status) {
        status = reduce_run_devices(devices, count, s, arguments->output, o);
        pass_setup_close_devices(devices, count);
    }
    int code = status ? fail() : 0;
    scene_free(s);
    return code;
}

int command_reduce(int argc, char **argv)
{
    static const struct option table[] = {
        IMPORTANCE_LONG_OPTIONS,
        {"target", required_argument, NULL, OPT_TARGET},
        {"method", required_argument, NULL, OPT_METHOD},
        {"min-vertices", required_argument, NULL, OPT_MIN_VERTICES},
        {"max-normal-angle", required_argument, NULL, OPT_MAX_NORMAL_ANGLE},
        {"uv-weight", required_argument, NULL, OPT_UV_WEIGHT},
        {"normal-weight", required_argument, NULL, OPT_NORMAL_WEIGHT},
        {"recompute-normals", no_argument, NULL, OPT_RECOMPUTE_NORMALS},
        {"keep", required_argument, NULL, OPT_KEEP},
        {"force", no_argument, NULL, OPT_FORCE},
        {"bundle", no_argument, NULL, OPT_BUNDLE},
        {"threads", required_argument, NULL, OPT_THREADS},
        {"factor-tolerance", required_argument, NULL, OPT_FACTOR_TOLERANCE},
        {"ranking-tolerance", required_argument, NULL, OPT_RANKING_TOLERANCE},
        {"simulation", required_argument, NULL, OPT_SIMULATION},
        {"initial", required_argument, NULL, OPT_INITIAL},
        {"passes", required_argument, NULL, OPT_PASSES},
        {"memory-budget", required_argument, NULL, OPT_MEMORY_BUDGET},
        {"max-error", required_argument, NULL, OPT_MAX_ERROR},
        {"max-error-relative", required_argument, NULL, OPT_MAX_ERROR_RELATIVE},
        {"max-error-step", required_argument, NULL, OPT_MAX_ERROR_STEP},
        {"check-iterations", required_argument, NULL, OPT_CHECK_ITERATIONS},
        {"check-resolution", required_argument, NULL, OPT_CHECK_RESOLUTION},
        {"check-photons", required_argument, NULL, OPT_CHECK_PHOTONS},
        {"refine", required_argument, NULL, OPT_REFINE},
        {0, 0, 0, 0}};
    reduce_cli_request request = {0};
    reduce_options_default(&request.options);
    request.options.importance.sppm.progress = 1;
    request.options.keep = xcalloc((size_t)argc + 1, sizeof *request.options.keep);
    pass_arguments arguments = {.command = "reduce"};
    int code = parse_pass_arguments(argc, argv, table, parse_option, &request, &arguments);
    int searched = request.options.error.bound != REDUCE_ERROR_NONE;
    if (!code && request.error_bounds > 1)
        code = usage_error("reduce: give one of --max-error E and --max-error-relative F, not "
                           "both");
    if (!code && searched && request.have_target)
        code = usage_error("reduce: --target D and --max-error are exclusive: --max-error "
                           "searches for the target");
    if (!code && !searched && request.search_options)
        code = usage_error("reduce: --max-error-step is for --max-error or "
                           "--max-error-relative");
    if (!code && !searched && !request.options.refine && request.check_options)
        code = usage_error("reduce: --check-* are for --max-error, --max-error-relative or "
                           "--refine");
    if (!code && (!arguments.output ||
                  (!request.have_target && !request.options.memory_budget && !searched)))
        code = usage_error("reduce: -o OUTDIR and --target D or --memory-budget BYTES (or "
                           "--max-error E) are required");
    if (!code && !request.have_target)
        request.options.target = 1.0; /* the budget alone sets it */
    if (!code && request.options.simulation &&
        !reduce_method_uses_importance(request.options.method))
        code = usage_error("reduce: --simulation is for the methods with importance, not '%s'",
                           reduce_method_name(request.options.method));
    if (!code)
        code = run_reduce(&arguments, &request.options);
    free((void *)request.options.keep);
    return code;
}
