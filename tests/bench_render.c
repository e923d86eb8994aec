/* bench_render.c — `make bench`: what a reduction saves at render time, on the paper's DRAGON
 * CORNELL BOX (871k triangles; its Table 1 measured 1.07–1.28x for in-core scenes).
 *
 *   render-speedup: scene=dragon-box target=0.1 original=<s/iter> reduced=<s/iter>
 *                   speedup=<x> memory_ratio=<reduced/original> total_memory_ratio=<...>
 *
 * The box is written on the fly (bench_common.h) and reduced to D = 0.1 with the importance
 * method (REDUCE_ITERATIONS importance iterations: the render time depends on how many
 * vertices are left, not on how well they were chosen). Both scenes are then rendered with the
 * same photons and hit points; a render iteration's seconds are the best of ROUNDS runs of
 * ITERATIONS iterations, after a warm-up. memory_ratio is the device memory of the scene
 * (geometry and BVH), total_memory_ratio includes the SPPM buffers, which do not shrink. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "bvh.h"
#include "device.h"
#include "error.h"
#include "mitsuba.h"
#include "reduce.h"
#include "render.h"

#define TARGET 0.1
#define REDUCE_ITERATIONS 10
#define ROUNDS 2
#define ITERATIONS 3

static void die(void)
{
    fprintf(stderr, "bench_render: %s\n", error_message());
    exit(1);
}

static scene *load(const char *path)
{
    warn_silence(1);
    scene *s = mitsuba_load(path);
    warn_silence(0);
    if (!s)
        die();
    return s;
}

/* Best seconds per render iteration of `path`, and its device memory. */
static double seconds_per_iteration(device *d, const char *path, render_memory *memory)
{
    scene *s = load(path);
    bvh b;
    if (bvh_build(s, &b))
        die();
    render_options o;
    render_options_default(&o);
    render_result r;
    o.iterations = 1;
    if (render_run(d, s, &b, &o, &r))
        die();
    *memory = r.memory;
    render_result_free(&r);
    double best = 1e30;
    o.iterations = ITERATIONS;
    for (int round = 0; round < ROUNDS; round++) {
        if (render_run(d, s, &b, &o, &r))
            die();
        double seconds = r.seconds.total / r.iterations;
        best = seconds < best ? seconds : best;
        render_result_free(&r);
    }
    bvh_free(&b);
    scene_free(s);
    return best;
}

int main(void)
{
    const char *box = bench_write_dragon_box();
    if (!box)
        return 1;
    device d;
    if (device_open(&d, -1))
        die();
    char outdir[] = "/tmp/idmr-bench-reduced-XXXXXX";
    if (!mkdtemp(outdir))
        return 1;
    scene *s = load(box);
    reduce_options o;
    reduce_options_default(&o);
    o.target = TARGET;
    o.importance.iterations = REDUCE_ITERATIONS;
    o.force = 1;
    warn_silence(1);
    int status = reduce_run(&d, s, outdir, &o);
    warn_silence(0);
    scene_free(s);
    if (status)
        die();
    char reduced[sizeof outdir + 16];
    snprintf(reduced, sizeof reduced, "%s/scene.xml", outdir);
    render_memory original_memory, reduced_memory;
    double original = seconds_per_iteration(&d, box, &original_memory);
    double after = seconds_per_iteration(&d, reduced, &reduced_memory);
    double scene_before = (double)(original_memory.geometry + original_memory.bvh);
    double scene_after = (double)(reduced_memory.geometry + reduced_memory.bvh);
    printf("render-speedup: scene=dragon-box target=%g original=%.3f reduced=%.3f speedup=%.2f "
           "memory_ratio=%.3f total_memory_ratio=%.3f\n",
           TARGET, original, after, original / after, scene_after / scene_before,
           (scene_after + reduced_memory.sppm) / (scene_before + original_memory.sppm));
    device_close(&d);
    char command[256];
    snprintf(command, sizeof command, "rm -rf %s", outdir);
    if (system(command) != 0)
        fprintf(stderr, "bench_render: could not remove %s\n", outdir);
    bench_remove_dragon_box(box);
    return 0;
}
