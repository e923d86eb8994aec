/* bench_specialise.c — `make bench`: what building kernels for the scene's features saves.
 *
 *   specialisation: scene=<name> pass=importance|render generic=<s/iter> specialised=<s/iter>
 *                   speedup=<x>
 *   program-build: cold=<s> cached=<s> speedup=<x>
 *
 * The importance iteration and the render iteration of the shipped Cornell box (diffuse, one
 * area light) and of the glass of water (dielectrics, glossy metal), with the program built for
 * the scene and with the all-features program (--generic); best of ROUNDS, after one warm-up
 * iteration each. The build
 * of the importance program with PoCL's own cache off (in a child process), then from idmr's
 * program cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/bvh.h"
#include "device/device.h"
#include "device/program.h"
#include "core/error.h"
#include "passes/importance.h"
#include "io/mitsuba/mitsuba.h"
#include "passes/render.h"
#include "core/progress.h"

#define ROUNDS 2
#define ITERATIONS 3

enum pass { PASS_IMPORTANCE, PASS_RENDER };
static const char *const pass_names[] = {"importance", "render"};

static void die(void)
{
    fprintf(stderr, "bench_specialise: %s\n", error_message());
    exit(1);
}

/* Seconds per iteration of `iterations` iterations of the pass with its default photons. */
static double per_iteration(device *d, const scene *s, const bvh *b, enum pass pass, int generic,
                            unsigned int iterations)
{
    render_options render;
    importance_options importance;
    render_options_default(&render);
    importance_options_default(&importance);
    render.sppm.iterations = importance.sppm.iterations = iterations;
    render.sppm.generic = importance.sppm.generic = generic;
    render_result rr;
    importance_result ir;
    int status = pass == PASS_RENDER ? render_run(d, s, b, &render, &rr)
                                     : importance_run(d, s, b, &importance, &ir);
    if (status)
        die();
    const sppm_summary *summary = pass == PASS_RENDER ? &rr.sppm : &ir.sppm;
    double seconds = summary->seconds.total / summary->iterations;
    if (pass == PASS_RENDER)
        render_result_free(&rr);
    else
        importance_result_free(&ir);
    return seconds;
}

static void bench_scene(device *d, const char *name, const char *path)
{
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    bvh b;
    if (!s || bvh_build(s, &b))
        die();
    for (enum pass pass = PASS_IMPORTANCE; pass <= PASS_RENDER; pass++) {
        double best[2] = {1e30, 1e30};
        for (int generic = 0; generic < 2; generic++)
            per_iteration(d, s, &b, pass, generic, 1);
        for (int round = 0; round < ROUNDS; round++)
            for (int generic = 0; generic < 2; generic++) {
                double seconds = per_iteration(d, s, &b, pass, generic, ITERATIONS);
                if (seconds < best[generic])
                    best[generic] = seconds;
            }
        printf("specialisation: scene=%s pass=%s generic=%.3f specialised=%.3f speedup=%.2f\n",
               name, pass_names[pass], best[1], best[0], best[1] / best[0]);
        fflush(stdout);
    }
    bvh_free(&b);
    scene_free(s);
}

static void bench_build(device *d)
{
    char cache[] = "/tmp/idmr-bench-cache-XXXXXX";
    if (!mkdtemp(cache))
        return;
    setenv("IDMR_CACHE_DIR", cache, 1);
    char *options = device_build_options(d, IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA,
                                         "-D IDMR_SPPM_PASS=1 -D IDMR_ACCUMULATE_IMPORTANCE=1 "
                                         "-D IDMR_CAMERA_IMPORTANCE=1");
    cl_program program;
    double t0 = monotonic_seconds();
    if (device_build_program(d, "sppm.cl", options, &program))
        die();
    double cold = monotonic_seconds() - t0;
    clReleaseProgram(program);
    t0 = monotonic_seconds();
    if (device_build_program(d, "sppm.cl", options, &program) || !device_last_build_cached()) {
        fprintf(stderr, "bench_specialise: the second build did not come from the cache\n");
        exit(1);
    }
    double cached = monotonic_seconds() - t0;
    clReleaseProgram(program);
    printf("program-build: kernel=sppm.cl pass=importance cold=%.2f cached=%.3f speedup=%.0f\n",
           cold, cached, cold / cached);
    free(options);
    char command[256];
    snprintf(command, sizeof command, "rm -rf %s", cache);
    if (system(command) != 0)
        fprintf(stderr, "bench_specialise: could not remove %s\n", cache);
    unsetenv("IDMR_CACHE_DIR");
}

int main(int argc, char **argv)
{
    /* The cold build runs in a child with PoCL's own kernel cache off, so that "cold" is a real
     * compile while the iterations below keep PoCL's cache for its lazy work-group compiles. */
    if (argc > 1 && strcmp(argv[1], "build") == 0) {
        device d;
        if (device_open(&d, -1))
            die();
        bench_build(&d);
        device_close(&d);
        return 0;
    }
    char command[4200];
    snprintf(command, sizeof command, "POCL_KERNEL_CACHE=0 %s build", argv[0]);
    fflush(stdout);
    if (system(command) != 0)
        fprintf(stderr, "bench_specialise: the build measurement failed\n");
    device d;
    if (device_open(&d, -1))
        die();
    bench_scene(&d, "cornell", "data/cornell/scene.xml");
    bench_scene(&d, "glass-of-water", "../shared/data/scenes/glass-of-water/scene-without-mesh000.xml");
    device_close(&d);
    return 0;
}
