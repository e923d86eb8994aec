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
 * ITERATIONS iterations, after a warm-up, the two scenes' runs alternating. A second line gives
 * the best run's seconds per stage. memory_ratio is the device memory of the scene
 * (geometry and BVH), total_memory_ratio includes the SPPM buffers, which do not shrink. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_common.h"
#include "device/bvh.h"
#include "device/device.h"
#include "core/error.h"
#include "io/mitsuba/mitsuba.h"
#include "reduce/reduce.h"
#include "passes/render.h"

#define TARGET 0.1
#define REDUCE_ITERATIONS 10
#define ROUNDS 3
#define ITERATIONS 4

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

/* One scene to render: loaded, its BVH built, its best timings so far. */
typedef struct timed_scene {
    scene *s;
    bvh b;
    uint64_t scene_bytes;  /* device memory: geometry and BVH */
    uint64_t buffer_bytes; /*                the SPPM buffers */
    sppm_seconds best;     /* per iteration, of the fastest run */
    double best_total;
} timed_scene;

static void prepare(device *d, const char *path, timed_scene *t)
{
    memset(t, 0, sizeof *t);
    t->s = load(path);
    if (bvh_build(t->s, &t->b))
        die();
    render_options o;
    render_options_default(&o);
    o.sppm.iterations = 1; /* warm-up: program build or cache load, first-touch costs */
    render_result r;
    if (render_run(d, t->s, &t->b, &o, &r))
        die();
    t->scene_bytes = r.sppm.geometry_bytes + r.sppm.bvh_bytes;
    t->buffer_bytes = r.sppm.buffer_bytes;
    t->best_total = 1e30;
    render_result_free(&r);
}

static void time_once(device *d, timed_scene *t)
{
    render_options o;
    render_options_default(&o);
    o.sppm.iterations = ITERATIONS;
    render_result r;
    if (render_run(d, t->s, &t->b, &o, &r))
        die();
    double per_iteration = r.sppm.seconds.total / r.sppm.iterations;
    if (per_iteration < t->best_total) {
        t->best_total = per_iteration;
        t->best = r.sppm.seconds;
        double n = r.sppm.iterations;
        t->best.camera /= n;
        t->best.photon /= n;
        t->best.grid /= n;
        t->best.gather /= n;
    }
    render_result_free(&r);
}

static void release(timed_scene *t)
{
    bvh_free(&t->b);
    scene_free(t->s);
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
    o.importance.sppm.iterations = REDUCE_ITERATIONS;
    o.force = 1;
    warn_silence(1);
    int status = reduce_run(&d, s, outdir, &o);
    warn_silence(0);
    scene_free(s);
    if (status)
        die();
    char reduced[sizeof outdir + 16];
    snprintf(reduced, sizeof reduced, "%s/scene.xml", outdir);
    /* Alternating rounds, so that the machine's drift falls on both scenes alike. */
    timed_scene original, reduced_scene;
    prepare(&d, box, &original);
    prepare(&d, reduced, &reduced_scene);
    for (int round = 0; round < ROUNDS; round++) {
        time_once(&d, &original);
        time_once(&d, &reduced_scene);
    }
    double scene_before = (double)original.scene_bytes;
    double scene_after = (double)reduced_scene.scene_bytes;
    printf("render-speedup: scene=dragon-box target=%g original=%.3f reduced=%.3f speedup=%.2f "
           "memory_ratio=%.3f total_memory_ratio=%.3f\n",
           TARGET, original.best_total, reduced_scene.best_total,
           original.best_total / reduced_scene.best_total, scene_after / scene_before,
           (scene_after + reduced_scene.buffer_bytes) / (scene_before + original.buffer_bytes));
    printf("render-speedup: stages original camera=%.3f photon=%.3f grid=%.3f gather=%.3f; "
           "reduced camera=%.3f photon=%.3f grid=%.3f gather=%.3f\n",
           original.best.camera, original.best.photon, original.best.grid, original.best.gather,
           reduced_scene.best.camera, reduced_scene.best.photon, reduced_scene.best.grid,
           reduced_scene.best.gather);
    release(&original);
    release(&reduced_scene);
    device_close(&d);
    char command[256];
    snprintf(command, sizeof command, "rm -rf %s", outdir);
    if (system(command) != 0)
        fprintf(stderr, "bench_render: could not remove %s\n", outdir);
    bench_remove_dragon_box(box);
    return 0;
}
