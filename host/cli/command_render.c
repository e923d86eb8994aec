/* command_render.c — `idmr render SCENE -o IMAGE [options]`: the SPPM render of the scene
 * (passes/render.h) into IMAGE.exr (linear), IMAGE.png (sRGB, --exposure) and IMAGE.json (its
 * report), the directory created if missing; then one summary line on stdout. IMAGE may end
 * in .exr or .png: either names the same three files. Options: the SPPM core's (options.h) and
 * --exposure; the importance pass's own are refused. */
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/pass_setup.h"
#include "core/error.h"
#include "core/files.h"
#include "core/json.h"
#include "core/ranks.h"
#include "io/scene_load.h"
#include "passes/render.h"

/* Where the render goes: the three files, and the directory to create ("" if none). */
typedef struct render_cli_paths {
    char exr[4200], png[4200], json[4200];
    char directory[4096];
} render_cli_paths;

/* What the render runs with, and what it gives back. */
typedef struct render_cli_job {
    render_options options;
    double exposure; /* EV of the PNG */
    render_cli_paths paths;
    render_result result;
} render_cli_job;

/* The paths of `-o image`: its stem (without a trailing ".exr" or ".png") with each
 * extension, and the stem's directory. -1 (a usage error printed) when the stem has no name
 * of its own (it ends in '/'), which would give hidden files "DIR/.exr". A directory of the
 * stem's name may exist: `-o out/reduced.exr` beside the reduced scene out/reduced/ is fine. */
static int render_paths_from(const char *image, render_cli_paths *paths)
{
    char stem[4096];
    snprintf(stem, sizeof stem, "%s", image);
    size_t length = strlen(stem);
    if (length > 4 &&
        (!strcasecmp(stem + length - 4, ".exr") || !strcasecmp(stem + length - 4, ".png")))
        stem[length - 4] = '\0';
    length = strlen(stem);
    if (length == 0 || stem[length - 1] == '/')
        return usage_error("render: -o '%s' names a directory; give the image's path in it, "
                           "such as '%simage'",
                           image, stem);
    snprintf(paths->exr, sizeof paths->exr, "%s.exr", stem);
    snprintf(paths->png, sizeof paths->png, "%s.png", stem);
    snprintf(paths->json, sizeof paths->json, "%s.json", stem);
    snprintf(paths->directory, sizeof paths->directory, "%s", stem);
    char *slash = strrchr(paths->directory, '/');
    if (slash && slash != paths->directory)
        *slash = '\0';
    else
        paths->directory[0] = '\0';
    return 0;
}

static enum option_parse parse_option(int c, void *context, pass_arguments *arguments)
{
    render_cli_job *job = context;
    if (c == OPT_EXPOSURE)
        return option_result(parse_double("--exposure", optarg, -64, 64, &job->exposure));
    if (c == OPT_GAMMA || c == OPT_TOLERANCE || c == OPT_SHADOW_WEIGHT)
        return OPTION_IMPORTANCE_ONLY;
    return parse_sppm_option(c, &job->options.sppm, &arguments->devices);
}

/* The three files of the render, each written whole or not at all; where one cannot be written
 * (a full disk), those this run wrote before it are removed, and the image's directory too if
 * this run made it: a failed render leaves no part of itself. 0, or -1 with the error set. */
static int write_outputs(render_cli_job *job, const scene *s, const device *d)
{
    const render_cli_paths *paths = &job->paths;
    int made_directory = paths->directory[0] && access(paths->directory, F_OK) != 0;
    const char *written[3];
    size_t count = 0;
    int status = paths->directory[0] && files_make_directory(paths->directory);
    if (!status && !(status = render_write_images(&job->result, paths->exr, NULL, 0)))
        written[count++] = paths->exr;
    if (!status && !(status = render_write_images(&job->result, NULL, paths->png, job->exposure)))
        written[count++] = paths->png;
    if (!status) {
        cJSON *report = render_report_json(s, d, &job->options, &job->result);
        status = json_write(report, paths->json);
        cJSON_Delete(report);
    }
    if (status) {
        while (count > 0)
            unlink(written[--count]);
        if (made_directory)
            rmdir(paths->directory);
    }
    return status;
}

/* The render and its outputs: this command's calls into passes/. The image's directory is made
 * only once the render is done, so an interrupted render leaves no empty one behind. */
static int run_pass(device *d, unsigned int count, const scene *s, const bvh *b, void *context)
{
    (void)count; /* one: command_render() refuses more */
    render_cli_job *job = context;
    if (render_run(d, s, b, &job->options, &job->result))
        return -1;
    return write_outputs(job, s, d);
}

static void print_summary(const render_cli_job *job)
{
    const sppm_summary *run = &job->result.sppm;
    double n = run->iterations, mib = 1048576.0;
    printf("%s: %ux%u, %u iterations of %u photon paths, %.3f s per iteration (camera %.3f, "
           "photons %.3f, grid %.3f, gather %.3f); device memory %.1f MiB (geometry %.1f, "
           "BVH %.1f, SPPM %.1f)\n",
           job->paths.exr, run->width, run->height, run->iterations, run->photons,
           run->seconds.total / n, run->seconds.camera / n, run->seconds.photon / n,
           run->seconds.grid / n, run->seconds.gather / n,
           (run->geometry_bytes + run->bvh_bytes + run->buffer_bytes) / mib,
           run->geometry_bytes / mib, run->bvh_bytes / mib, run->buffer_bytes / mib);
}

int command_render(int argc, char **argv)
{
    static const struct option table[] = {
        IMPORTANCE_LONG_OPTIONS, {"exposure", required_argument, NULL, OPT_EXPOSURE}, {0, 0, 0, 0}};
    render_cli_job job;
    memset(&job, 0, sizeof job);
    render_options_default(&job.options);
    job.options.sppm.progress = 1;
    pass_arguments arguments = {.command = "render"};
    int code = parse_pass_arguments(argc, argv, table, parse_option, &job, &arguments);
    if (code)
        return code;
    if (!arguments.output)
        return usage_error("render: -o IMAGE is required");
    if (device_choice_several(&arguments.devices))
        return usage_error("render: --device takes one device number: the renderer runs on one "
                           "device (the importance pass, `importance` and `reduce`, takes "
                           "--device all or a list)");
    if (ranks_count() > 1)
        return usage_error("render: the renderer runs as one process: run it without mpirun "
                           "(%d ranks were started; `importance` and `reduce` share their "
                           "importance pass between ranks)",
                           ranks_count());
    if (render_paths_from(arguments.output, &job.paths))
        return IDMR_EXIT_INPUT;
    scene *s = scene_load(arguments.scene);
    if (!s)
        return fail();
    int status = scene_check_output_file(s, job.paths.exr) ||
                 scene_check_output_file(s, job.paths.png) ||
                 scene_check_output_file(s, job.paths.json);
    if (!status)
        status = pass_setup_run(s, &arguments.devices, run_pass, &job);
    code = status ? fail() : 0;
    if (!status)
        print_summary(&job);
    render_result_free(&job.result);
    scene_free(s);
    return code;
}
