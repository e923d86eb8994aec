/* command_importance.c — `idmr importance SCENE -o DIR [options]`: the importance pass on the
 * scene (passes/importance.h) and its outputs in DIR (passes/importance_outputs.h), written
 * into a staging directory published as DIR when all succeeded (core/files.h: nothing
 * half-written on failure or interrupt), with the simulation itself (simulation.bin,
 * passes/importance_file.h: `idmr reduce --simulation` reuses it), then one summary line on
 * stderr. Options: the importance pass's (options.h). Under mpirun every rank runs the pass on
 * its share of the photon paths (core/ranks.h) and rank 0 writes the outputs. */
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/pass_setup.h"
#include "core/files.h"
#include "core/ranks.h"
#include "io/scene_load.h"
#include "passes/importance.h"
#include "passes/importance_file.h"
#include "passes/importance_outputs.h"

/* What the pass runs with, and what it gives back. */
typedef struct importance_cli_job {
    importance_options options;
    const char *output; /* DIR */
    char staging[2048]; /* where the outputs are written, published as DIR at the end */
    importance_result result;
} importance_cli_job;

static enum option_parse parse_option(int c, void *context, pass_arguments *arguments)
{
    importance_cli_job *job = context;
    return parse_importance_option(c, &job->options, &arguments->devices);
}

/* The pass and its outputs: this command's calls into passes/. */
static int run_pass(device *d, unsigned int count, const scene *s, const bvh *b,
                    void *context)
{
    importance_cli_job *job = context;
    if (importance_run_devices(d, count, s, b, &job->options, &job->result))
        return -1;
    if (ranks_rank() != 0) /* under mpirun, rank 0 writes the outputs */
        return 0;
    cJSON *report = importance_report_json(s, d, &job->options, &job->result);
    importance_weights weights = importance_weights_of(&job->options);
    double **values = importance_vertex_values(&job->result, s, &weights);
    char simulation[4096];
    snprintf(simulation, sizeof simulation, "%s/simulation.bin", job->staging);
    int status =
        importance_write_outputs(job->staging, report, s, &job->options, &job->result, values) ||
        importance_file_write(simulation, s, &job->options, &job->result);
    importance_vertex_values_free(values, s);
    cJSON_Delete(report);
    return status;
}

static void print_summary(const importance_cli_job *job)
{
    const importance_result *r = &job->result;
    char devices[256] = "";
    if (r->sppm.devices > 1) {
        /* "on devices 0, 1 (paths 41%, 59%)": each device's share of all the paths */
        size_t used = (size_t)snprintf(devices, sizeof devices, " on devices");
        for (unsigned int k = 0; k < r->sppm.devices && used < sizeof devices; k++)
            used += (size_t)snprintf(devices + used, sizeof devices - used, "%s %d",
                                     k ? "," : "", r->sppm.device[k].index);
        double all = (double)r->sppm.photons * r->sppm.iterations;
        for (unsigned int k = 0; k < r->sppm.devices && used < sizeof devices && all > 0; k++)
            used += (size_t)snprintf(devices + used, sizeof devices - used, "%s%.0f%%",
                                     k ? ", " : " (paths ",
                                     100.0 * (double)r->sppm.device[k].paths / all);
        if (used < sizeof devices && all > 0)
            snprintf(devices + used, sizeof devices - used, ")");
    }
    fprintf(stderr,
            "idmr: %u iterations of %u photon paths in %.1f s%s; outputs in %s/ (report.json, "
            "importance.png, importance/*.ply, convergence.csv, simulation.bin)\n",
            r->sppm.iterations, r->sppm.photons, r->sppm.seconds.total, devices, job->output);
}

int command_importance(int argc, char **argv)
{
    static const struct option table[] = {IMPORTANCE_LONG_OPTIONS, {0, 0, 0, 0}};
    importance_cli_job job;
    memset(&job, 0, sizeof job);
    importance_options_default(&job.options);
    job.options.sppm.progress = 1;
    pass_arguments arguments = {.command = "importance"};
    int code = parse_pass_arguments(argc, argv, table, parse_option, &job, &arguments);
    if (code)
        return code;
    if (!arguments.output)
        return usage_error("importance: -o DIR is required");
    job.output = arguments.output;
    scene *s = scene_load(arguments.scene);
    if (!s)
        return fail();
    int status = scene_check_output_directory(s, job.output) ||
                 (ranks_rank() == 0 &&
                  files_stage_begin(job.output, job.staging, sizeof job.staging));
    if (!status)
        status = pass_setup_run(s, &arguments.devices, run_pass, &job);
    /* Under mpirun, DIR is published once every rank has done its part (core/ranks.h). */
    status = ranks_sync(status, NULL);
    if (job.staging[0])
        status = files_stage_end(job.staging, job.output, !status) || status ? -1 : 0;
    code = status ? fail() : 0;
    if (!status && ranks_rank() == 0)
        print_summary(&job);
    importance_result_free(&job.result);
    scene_free(s);
    return code;
}
