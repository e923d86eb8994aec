/* bench_importance.c — `make bench`: one importance iteration against the same camera and
 * photon work without accumulating importance (IDMR_ACCUMULATE_IMPORTANCE=0: no Eq. 2 atomics in the
 * camera pass, no reverse path walk), on the DRAGON CORNELL BOX (bench_common.h).
 *
 *   importance-iteration: seconds=<s> plain=<s> ratio=<importance/plain> photons=<n> ...
 *
 *   scaling: devices=<n> ranks=1 seconds=<s> speedup=<one device's seconds / s>
 *   scaling: devices=1 ranks=<n> seconds=<s> speedup=<one process's seconds / s>
 *
 * the pass on every OpenCL device at once (importance_run_devices: photon paths split, the
 * same sums bit for bit) against the default device alone, per iteration; where PoCL is asked
 * for no devices in particular, POCL_DEVICES="pthread pthread" gives it two CPU devices (on a
 * machine of 2 cores they share those cores: no speed-up is to be expected there).
 *
 * and the pass shared by MPI ranks (`mpirun -n 2 bin/idmr importance`, core/ranks.h) against
 * `bin/idmr importance` run plainly, per iteration as each run's report.json gives it (where the
 * build has no MPI, or mpirun is missing, that line says so instead). On 2 cores the ranks
 * share them (each PoCL device starts a thread per core): no speed-up is to be expected there.
 *
 * Each variant runs one iteration first (the runtime compiles kernels lazily on first use),
 * then ITERATIONS; the variants alternate ROUNDS times and the best per-iteration time of each
 * counts (shared machines are noisy; the least disturbed run is the truest). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "bench_common.h"
#include "device/bvh.h"
#include "device/device.h"
#include "core/error.h"
#include "core/ranks.h"
#include "passes/importance.h"
#include "io/mitsuba/mitsuba.h"

#define ITERATIONS 3
#define ROUNDS 2

static double seconds_on(device *d, unsigned int count, const scene *s, const bvh *b,
                         int accumulate_importance, unsigned int iterations, importance_result *r)
{
    importance_options o;
    importance_options_default(&o);
    o.sppm.iterations = iterations;
    o.accumulate_importance = accumulate_importance;
    if (importance_run_devices(d, count, s, b, &o, r)) {
        fprintf(stderr, "bench_importance: %s\n", error_message());
        exit(1);
    }
    return r->sppm.seconds.total / r->sppm.iterations;
}

static double seconds_per_iteration(device *d, const scene *s, const bvh *b,
                                    int accumulate_importance, unsigned int iterations,
                                    importance_result *r)
{
    return seconds_on(d, 1, s, b, accumulate_importance, iterations, r);
}

/* The scaling line: every device against the default one, best of ROUNDS each. */
static void scaling(device *d, const scene *s, const bvh *b)
{
    device_info *infos;
    size_t found;
    if (device_list(&infos, &found)) {
        fprintf(stderr, "bench_importance: %s\n", error_message());
        exit(1);
    }
    free(infos);
    unsigned int count = found < SPPM_MAX_DEVICES ? (unsigned int)found : SPPM_MAX_DEVICES;
    device all[SPPM_MAX_DEVICES];
    for (unsigned int k = 0; k < count; k++)
        if (device_open(all + k, (int)k)) {
            fprintf(stderr, "bench_importance: %s\n", error_message());
            exit(1);
        }
    importance_result r;
    double one = 1e30, several = 1e30;
    seconds_on(all, count, s, b, 1, 1, &r);
    importance_result_free(&r);
    for (int round = 0; round < ROUNDS; round++) {
        double seconds = seconds_on(d, 1, s, b, 1, ITERATIONS, &r);
        one = seconds < one ? seconds : one;
        importance_result_free(&r);
        seconds = seconds_on(all, count, s, b, 1, ITERATIONS, &r);
        several = seconds < several ? seconds : several;
        importance_result_free(&r);
    }
    printf("scaling: devices=1 ranks=1 seconds=%.3f speedup=1.00 device=\"%s\"\n", one,
           d->info.name);
    printf("scaling: devices=%u ranks=1 seconds=%.3f speedup=%.2f\n", count, several,
           one / several);
    for (unsigned int k = 0; k < count; k++)
        device_close(all + k);
}

/* A whole text file, malloc'd, or NULL. */
static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t size = 0, capacity = 1 << 16, got;
    char *text = xmalloc(capacity);
    while ((got = fread(text + size, 1, capacity - size - 1, f)) > 0)
        if ((size += got) + 1 >= capacity)
            text = xrealloc(text, capacity *= 2);
    text[size] = '\0';
    fclose(f);
    return text;
}

/* `launcher bin/idmr importance SCENE` (RANK_ITERATIONS iterations, default photons): the
 * seconds per iteration its report.json gives (build excluded), or a negative value. */
#define RANK_ITERATIONS 4
static double command_seconds(const char *launcher, const char *scene_path, const char *out)
{
    char command[4096];
    snprintf(command, sizeof command,
             "rm -rf %s && %s bin/idmr importance %s --device 0 --iterations %d --quiet -o %s",
             out, launcher, scene_path, RANK_ITERATIONS, out);
    if (system(command) != 0) {
        fprintf(stderr, "bench_importance: '%s' failed\n", command);
        return -1;
    }
    char report_path[4096];
    snprintf(report_path, sizeof report_path, "%s/report.json", out);
    char *text = read_text(report_path);
    cJSON *report = text ? cJSON_Parse(text) : NULL;
    const cJSON *total = cJSON_GetObjectItem(cJSON_GetObjectItem(report, "seconds"), "total");
    const cJSON *iterations = cJSON_GetObjectItem(report, "iterations");
    double seconds = cJSON_IsNumber(total) && cJSON_IsNumber(iterations) &&
                             iterations->valuedouble > 0
                         ? total->valuedouble / iterations->valuedouble
                         : -1;
    cJSON_Delete(report);
    free(text);
    return seconds;
}

/* The ranks line: 2 MPI ranks against one process, one device each, best of ROUNDS each. */
static void scaling_ranks(const char *scene_path)
{
    if (!ranks_built() || system("command -v mpirun >/dev/null 2>&1") != 0) {
        printf("scaling: ranks not measured (%s)\n",
               ranks_built() ? "mpirun not found" : "this build has no MPI");
        return;
    }
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 0); /* as test_mpi */
    char out[4096];
    snprintf(out, sizeof out, "%.4000s.ranks-out", scene_path);
    double one = 1e30, two = 1e30;
    for (int round = 0; round < ROUNDS; round++) {
        double a = command_seconds("", scene_path, out);
        double b = command_seconds("mpirun --oversubscribe -n 2", scene_path, out);
        if (a < 0 || b < 0)
            exit(1);
        one = a < one ? a : one;
        two = b < two ? b : two;
    }
    char command[4200];
    snprintf(command, sizeof command, "rm -rf %s", out);
    if (system(command) != 0)
        fprintf(stderr, "bench_importance: cannot remove %s\n", out);
    printf("scaling: devices=1 ranks=1 seconds=%.3f speedup=1.00 (bin/idmr importance)\n", one);
    printf("scaling: devices=1 ranks=2 seconds=%.3f speedup=%.2f (mpirun -n 2)\n", two,
           one / two);
}

int main(void)
{
    setenv("POCL_DEVICES", "pthread pthread", 0); /* before the first OpenCL call */
    const char *path = bench_write_dragon_box();
    scene *s = path ? mitsuba_load(path) : NULL;
    if (!s) {
        fprintf(stderr, "bench_importance: %s\n", path ? error_message() : "cannot write scene");
        return 1;
    }
    device d;
    bvh b;
    if (device_open(&d, -1) || bvh_build(s, &b)) {
        fprintf(stderr, "bench_importance: %s\n", error_message());
        return 1;
    }
    double best[2] = {1e30, 1e30};
    importance_result r;
    for (int variant = 0; variant < 2; variant++) {
        seconds_per_iteration(&d, s, &b, variant, 1, &r);
        importance_result_free(&r);
    }
    double stage[2][6] = {{0}};
    for (int round = 0; round < ROUNDS; round++)
        for (int variant = 0; variant < 2; variant++) {
            double seconds = seconds_per_iteration(&d, s, &b, variant, ITERATIONS, &r);
            if (seconds < best[variant]) {
                best[variant] = seconds;
                double *st = stage[variant];
                st[0] = r.sppm.seconds.camera / r.sppm.iterations;
                st[1] = r.sppm.seconds.photon / r.sppm.iterations;
                st[2] = r.sppm.seconds.grid / r.sppm.iterations;
                st[3] = (r.sppm.seconds.gather - r.path_seconds - r.shadow_seconds) /
                        r.sppm.iterations;
                st[4] = r.path_seconds / r.sppm.iterations;
                st[5] = r.shadow_seconds / r.sppm.iterations;
            }
            importance_result_free(&r);
        }
    printf("importance-iteration: seconds=%.3f plain=%.3f ratio=%.2f photons=%u triangles=%llu "
           "device=\"%s\"\n",
           best[1], best[0], best[1] / best[0], sppm_default_photons(&d),
           (unsigned long long)s->triangle_count, d.info.name);
    printf("importance-iteration: stages camera=%.3f photon=%.3f grid=%.3f shadow=%.3f "
           "gather=%.3f path=%.3f gather/photon=%.2f (plain: camera=%.3f photon=%.3f)\n",
           stage[1][0], stage[1][1], stage[1][2], stage[1][5], stage[1][3], stage[1][4],
           stage[1][3] / stage[1][1], stage[0][0], stage[0][1]);
    scaling(&d, s, &b);
    scaling_ranks(path);
    bvh_free(&b);
    device_close(&d);
    scene_free(s);
    bench_remove_dragon_box(path);
    return 0;
}
