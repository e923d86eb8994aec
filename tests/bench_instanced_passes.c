/* bench_instanced_passes.c — `make bench`: the importance pass on an instanced scene (traced
 * through the two-level BVH, kernels/lib/surface.h) against the same scene written flat
 * (instanced_cornell.h: the Cornell box's knot placed three times, one copy turned, one
 * mirrored), both measured in this run:
 *
 *   instanced-passes: copies=3 seconds=<s> flat=<s> ratio=<instanced/flat> tracing=<s>
 *                     flat_tracing=<s> tracing_ratio=<instanced/flat> scene_bytes=<bytes>
 *                     flat_scene_bytes=<bytes> memory_ratio=<instanced/flat> device="<name>"
 *
 * seconds per iteration (build excluded) at the device's default photons, and of them the
 * tracing ones (camera paths, photon paths, shadow rays: what the two-level walk changes; the
 * grid and the gathers are the same); the scene bytes are the device's geometry and BVH (each
 * prototype once). The two alternate ROUNDS times after a
 * warm-up iteration each, and the best of each counts (shared machines are noisy). */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "core/error.h"
#include "device/bvh.h"
#include "device/device.h"
#include "instanced_cornell.h"
#include "io/mitsuba/mitsuba.h"
#include "passes/importance.h"

#define ITERATIONS 3
#define ROUNDS 2

typedef struct bench_scene {
    scene *s;
    bvh b;
    double best, tracing; /* per iteration: the pass, its camera and photon paths' tracing */
    uint64_t bytes;
} bench_scene;

static void fail(const char *what)
{
    fprintf(stderr, "bench_instanced_passes: %s: %s\n", what, error_message());
    exit(1);
}

/* Runs `iterations` of the pass on x; keeps the best seconds per iteration and the bytes. */
static void run(device *d, bench_scene *x, unsigned int iterations)
{
    importance_options o;
    importance_options_default(&o);
    o.sppm.iterations = iterations;
    importance_result r;
    if (importance_run(d, x->s, &x->b, &o, &r))
        fail("importance_run");
    double seconds = r.sppm.seconds.total / r.sppm.iterations;
    if (iterations == ITERATIONS && seconds < x->best) {
        x->best = seconds;
        x->tracing = (r.sppm.seconds.camera + r.sppm.seconds.photon + r.shadow_seconds) /
                     r.sppm.iterations;
    }
    x->bytes = r.sppm.geometry_bytes + r.sppm.bvh_bytes;
    importance_result_free(&r);
}

int main(void)
{
    char dir[] = "/tmp/idmr-bench-instanced-XXXXXX", path[4200];
    if (!mkdtemp(dir))
        return 1;
    bench_scene scenes[2] = {{.best = 1e30}, {.best = 1e30}}; /* instanced, flat */
    device d;
    if (device_open(&d, -1))
        fail("device_open");
    for (int flat = 0; flat < 2; flat++) {
        if (instanced_cornell_write(dir, flat, 1.0, path, sizeof path))
            fail("writing the scenes");
        warn_silence(1);
        scenes[flat].s = mitsuba_load(path);
        warn_silence(0);
        if (!scenes[flat].s)
            fail(path);
        if (bvh_build(scenes[flat].s, &scenes[flat].b))
            fail("bvh_build");
        run(&d, &scenes[flat], 1);
    }
    for (int round = 0; round < ROUNDS; round++)
        for (int flat = 0; flat < 2; flat++)
            run(&d, &scenes[flat], ITERATIONS);
    printf("instanced-passes: copies=%d seconds=%.3f flat=%.3f ratio=%.2f tracing=%.3f "
           "flat_tracing=%.3f tracing_ratio=%.2f scene_bytes=%llu flat_scene_bytes=%llu "
           "memory_ratio=%.3f device=\"%s\"\n",
           INSTANCED_CORNELL_COPIES, scenes[0].best, scenes[1].best,
           scenes[0].best / scenes[1].best, scenes[0].tracing, scenes[1].tracing,
           scenes[0].tracing / scenes[1].tracing, (unsigned long long)scenes[0].bytes,
           (unsigned long long)scenes[1].bytes, (double)scenes[0].bytes / (double)scenes[1].bytes,
           d.info.name);
    for (int k = 0; k < 2; k++) {
        bvh_free(&scenes[k].b);
        scene_free(scenes[k].s);
    }
    device_close(&d);
    char command[256];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    return system(command) == 0 ? 0 : 1;
}
