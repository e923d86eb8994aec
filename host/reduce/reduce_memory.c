/* reduce_memory.c — the budget policy of `idmr reduce --memory-budget BYTES` (reduce.h,
 * reduce_stages.h), the one place whose decisions read the budget: the target and initial
 * reduction it allows (the memory plan), whether there is anything to remove, the importance
 * pass's device limit, how many meshes are decimated at once, the check that the reduced scene
 * fits it (the memory fit, which asks reduce_run() to decimate again) and that the run's peak
 * stayed within it.
 *
 * Device memory is what the passes allocate, computed by the function that sizes their
 * allocations (passes/sppm.h, sppm_memory_of, through render_memory and importance_memory):
 * geometry buffers, BVH, the SPPM core's buffers and the pass's own. Rendering the reduced scene
 * is costed at the scene's film (resolution 1) and this run's --photons per iteration (the
 * device's default, as `idmr render` takes it, when none are given).
 *
 * The plan. Apart from the BVH, a pass's memory is a line in the triangles of the meshes the
 * reduction may decimate (the free triangles): evaluated once for the scene and once for a view
 * without those triangles, it gives the fixed part (the film's and photons' buffers, the meshes
 * that are kept) and the cost per free triangle. The BVH is estimated at
 * REDUCE_BVH_BYTES_PER_TRIANGLE per triangle (Embree's SBVH flattened as bvh_layout.h: 84 bytes
 * on the Cornell box, 88 on the glass of water), since building the whole scene's BVH is what a
 * scene too large for the device cannot afford; the fit below corrects what the estimate misses.
 * With the free triangles scaled by D, the largest D whose render fits REDUCE_MEMORY_MARGIN
 * (reduce.h) of the budget becomes the target where it is below --target; and when the
 * importance pass over the whole scene would not fit (and no --initial was given), the largest
 * D0 whose importance pass fits is the initial reduction.
 * The importance pass itself is run with the budget as its device limit
 * (reduce_memory_device_limit), so it fails with a message rather than allocate more.
 *
 * A device that shares the host's memory (device_info.host_unified: a CPU, as PoCL's) has its
 * buffers in the process's resident memory, beside what the host holds while the pass runs, so
 * there the importance pass's line also counts: what the process holds when the plan is made
 * (the OpenCL runtime, the scene as loaded, its large meshes released: streaming), the collapse
 * histories of the initial reduction (HISTORY_BYTES_PER_VERTEX per vertex of the meshes that may
 * be decimated), and per simulated triangle HOST_BYTES_PER_TRIANGLE: the scene it simulates, the
 * sums read back and, until uploaded, its BVH. The initial reduction so chosen keeps the whole
 * process within the budget while the pass runs; the decimation takes only as many meshes at a
 * time as keep it there too (reduce_memory_meshes_in_flight), and the fit's BVH build is made
 * with the remapped importance on disk (below). The plan starts the process's peak over, and a
 * run that peaks above the budget all the same is an error, its scene not written
 * (reduce_memory_check_peak). bench-outofcore reports the peak.
 *
 * The fit. After the last decimation the reduced scene's BVH is built and its render memory
 * computed exactly; above the budget, the target is lowered in proportion to the excess over
 * the fixed part and the plan and decimation run again (at most FIT_ROUNDS times). On a device
 * that shares the host's memory, the remapped importance, which only such a decimation needs,
 * waits in the staging directory while the BVH is built (reduce_memory_fit_spills says so;
 * reduce_run() moves it out and back). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/error.h"
#include "core/progress.h"
#include "device/bvh.h"
#include "passes/render.h"
#include "reduce/reduce_stages.h"

/* The decimations the fit may run again. */
#define FIT_ROUNDS 3
/* What the host holds beside a device that shares its memory (above): per original vertex the
 * collapse history (decimate.h: welded_of, collapsed_into, output_index); per simulated triangle
 * an estimate: its geometry (about 24 bytes) and the three importance sums read back (24), with
 * room for the moment of the upload, when the host's copy of the BVH (about as large as the
 * device's, freed once uploaded) sits beside the device's before the photon and film buffers
 * are allocated. */
#define HISTORY_BYTES_PER_VERTEX 12.0
#define HOST_BYTES_PER_TRIANGLE 100.0

/* A pass's device memory without the BVH, as fixed + per_triangle × (free triangles kept). */
typedef struct memory_line {
    double fixed, per_triangle;
    uint64_t fixed_triangles, free_triangles; /* in the scene as loaded */
} memory_line;

typedef enum memory_pass { RENDER_PASS, IMPORTANCE_PASS } memory_pass;

static const char *const PASS_NAMES[] = {"rendering the reduced scene", "the importance pass"};

/* The render the budget is for: the scene's film, and this run's photons per iteration (the
 * device's default when none were given). */
static render_options budget_render(const reduce_state *st)
{
    render_options render;
    render_options_default(&render);
    render.sppm.photons = st->options->importance.sppm.photons;
    return render;
}

/* The pass's memory of scene s (BVH excluded). */
static int memory_of(const reduce_state *st, memory_pass pass, const scene *s, uint64_t *bytes)
{
    sppm_memory m;
    int status;
    if (pass == RENDER_PASS) {
        render_options render = budget_render(st);
        status = render_memory(st->device, s, 0, &render, &m);
    } else {
        status = importance_memory(st->device, s, 0, &st->options->importance, &m);
    }
    *bytes = status ? 0 : sppm_memory_total(&m);
    return status;
}

/* The pass's line, from the scene and a view of it without the free triangles. */
static int line_of(const reduce_state *st, memory_pass pass, memory_line *line)
{
    scene *bare = scene_view(st->scene);
    line->fixed_triangles = line->free_triangles = 0;
    for (size_t m = 0; m < st->count; m++) {
        /* A later copy of an instanced shape takes no memory of its own: its triangles are
         * its representative's (core/scene.h), whose count the view's finalize gives it. */
        if (reduce_instance_follower(st, m))
            continue;
        if (reduce_decimatable(st, m)) {
            line->free_triangles += st->scene->meshes[m].triangle_count;
            bare->meshes[m].vertex_count = bare->meshes[m].triangle_count = 0;
        } else {
            line->fixed_triangles += st->scene->meshes[m].triangle_count;
        }
    }
    uint64_t full = 0, fixed = 0;
    int status = scene_finalize(bare) || memory_of(st, pass, st->scene, &full) ||
                 memory_of(st, pass, bare, &fixed);
    scene_view_free(bare);
    line->fixed = (double)fixed;
    line->per_triangle = line->free_triangles
                             ? ((double)full - (double)fixed) / (double)line->free_triangles
                             : 0.0;
    return status;
}

/* The pass's bytes at fraction D of the free triangles, with `bvh` bytes per triangle. */
static double bytes_at(const memory_line *line, double d, double bvh_per_triangle)
{
    double free_kept = d * (double)line->free_triangles;
    return line->fixed + line->per_triangle * free_kept +
           bvh_per_triangle * ((double)line->fixed_triangles + free_kept);
}

/* The largest D in [0, 1] whose bytes stay within REDUCE_MEMORY_MARGIN of the budget; -1 when
 * not even D = 0 does. */
static double fitting_fraction(const memory_line *line, double bvh_per_triangle,
                               uint64_t budget)
{
    double room = REDUCE_MEMORY_MARGIN * (double)budget - bytes_at(line, 0.0, bvh_per_triangle);
    if (room < 0)
        return -1.0;
    double per_d = bytes_at(line, 1.0, bvh_per_triangle) - bytes_at(line, 0.0, bvh_per_triangle);
    return per_d > room ? room / per_d : 1.0;
}

#define MIB(x) ((double)(x) / 1048576.0)

/* Vertices of the meshes that may be decimated. */
static double decimatable_vertices(const reduce_state *st)
{
    double vertices = 0;
    for (size_t m = 0; m < st->count; m++)
        if (reduce_decimatable(st, m))
            vertices += (double)st->scene->meshes[m].vertex_count;
    return vertices;
}

/* The host's memory beside a device that shares it (above), added to the importance pass's
 * line: what the process holds now, and the host's bytes per simulated triangle. */
static void add_host_memory(memory_line *importance)
{
    importance->fixed += (double)resident_bytes() +
                         HOST_BYTES_PER_TRIANGLE * (double)importance->fixed_triangles;
    importance->per_triangle += HOST_BYTES_PER_TRIANGLE;
}

/* On a device that shares the host's memory: the largest mesh that may be decimated, read again
 * and decimated beside what the process holds now, must fit the budget (the decimation takes one
 * mesh at a time at the least: reduce_memory_meshes_in_flight). */
static int refuse_in_flight(const reduce_state *st, uint64_t budget)
{
    size_t largest = st->count;
    for (size_t m = 0; m < st->count; m++)
        if (reduce_decimatable(st, m) &&
            (largest == st->count ||
             st->scene->meshes[m].vertex_count > st->scene->meshes[largest].vertex_count))
            largest = m;
    if (largest == st->count)
        return 0;
    double held = (double)resident_bytes();
    double mesh = REDUCE_IN_FLIGHT_BYTES_PER_VERTEX * (double)st->scene->meshes[largest].vertex_count;
    if (held + mesh <= (double)budget)
        return 0;
    return error_set(IDMR_EXIT_INPUT,
                     "--memory-budget %.1f MiB: device '%s' shares the host's memory; the "
                     "process holds %.1f MiB (the scene as loaded, the OpenCL runtime), and "
                     "reading mesh '%s' (%u vertices) again to decimate or rewrite it takes "
                     "about %.1f MiB more: raise the budget to at least %.1f MiB",
                     MIB(budget), st->device->info.name, MIB(held),
                     st->scene->meshes[largest].name, st->scene->meshes[largest].vertex_count,
                     MIB(mesh), MIB(held + mesh));
}

/* The process's peak resident memory since the last reset_peak_resident() (VmHWM), in bytes;
 * 0 where the system does not say. */
static double peak_resident_bytes(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    double kib = 0;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %lf kB", &kib) == 1)
            break;
    if (f)
        fclose(f);
    return kib * 1024.0;
}

/* Starts the peak over (Linux: "5" into clear_refs), so a run measures its own peak, not an
 * earlier one of the same process (a test). */
static void reset_peak_resident(void)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (f) {
        fputs("5", f);
        fclose(f);
    }
}

int reduce_memory_plan(reduce_state *st)
{
    const reduce_options *o = st->options;
    uint64_t budget = o->memory_budget;
    if (!budget)
        return 0;
    reset_peak_resident(); /* the run's own peak, for reduce_memory_check_peak() */
    /* Without an importance pass (quadric) only the render is costed: nothing else runs. */
    int simulates = reduce_method_uses_importance(o->method);
    memory_line render, importance;
    if (line_of(st, RENDER_PASS, &render) ||
        (simulates && line_of(st, IMPORTANCE_PASS, &importance)))
        return -1;
    int last_pass = simulates ? IMPORTANCE_PASS : RENDER_PASS;
    double per_triangle = REDUCE_BVH_BYTES_PER_TRIANGLE;
    st->render_fixed_bytes = render.fixed + per_triangle * (double)render.fixed_triangles;
    const memory_line *lines[] = {&render, &importance};
    for (int pass = RENDER_PASS; pass <= last_pass; pass++)
        if (fitting_fraction(lines[pass], per_triangle, budget) < 0)
            return error_set(IDMR_EXIT_INPUT,
                             "--memory-budget %.1f MiB: %s needs about %.1f MiB even with every "
                             "mesh that may be decimated gone (the buffers of its film and "
                             "photons, and the %llu triangles of meshes that are kept): raise "
                             "the budget, or lower the photons or the film size",
                             MIB(budget), PASS_NAMES[pass],
                             MIB(bytes_at(lines[pass], 0.0, per_triangle)),
                             (unsigned long long)lines[pass]->fixed_triangles);
    double d = fitting_fraction(&render, per_triangle, budget);
    if (d < st->target)
        st->target = d;
    if (st->device->info.host_unified && refuse_in_flight(st, budget))
        return -1;
    /* Nothing to remove: reduce_run writes the scene as it is, with no pass to cost. */
    if (!(st->target < 1)) {
        if (o->importance.sppm.progress)
            fprintf(stderr,
                    "idmr: memory budget %.1f MiB: rendering the scene as it is needs about "
                    "%.1f MiB, within the budget: nothing to reduce\n",
                    MIB(budget), MIB(bytes_at(&render, 1.0, per_triangle)));
        return 0;
    }
    char simulated[160] = "";
    if (simulates) {
        int shared = st->device->info.host_unified;
        if (shared)
            add_host_memory(&importance);
        double d0 = fitting_fraction(&importance, per_triangle, budget);
        double histories = shared ? HISTORY_BYTES_PER_VERTEX * decimatable_vertices(st) : 0;
        int histories_counted = 0;
        if (!(o->initial < 1) && d0 < 1) {
            /* Reduced first: its collapse histories are held while the pass runs. */
            importance.fixed += histories;
            histories_counted = 1;
            d0 = fitting_fraction(&importance, per_triangle, budget);
            if (d0 < 0)
                return error_set(IDMR_EXIT_INPUT,
                                 "--memory-budget %.1f MiB: device '%s' shares the host's "
                                 "memory, and what this run holds while the importance pass "
                                 "runs on even the smallest initial reduction needs about "
                                 "%.1f MiB: raise the budget",
                                 MIB(budget), st->device->info.name,
                                 MIB(bytes_at(&importance, 0.0, per_triangle)));
            st->initial = d0;
        }
        /* Each pass after the first simulates the last one's result, the scene at the target
         * (with the collapse histories of that decimation held for the remapping). */
        if (o->passes > 1) {
            double later = bytes_at(&importance, st->target, per_triangle) +
                           (histories_counted ? 0 : histories);
            if (later > REDUCE_MEMORY_MARGIN * (double)budget)
                return error_set(IDMR_EXIT_INPUT,
                                 "--memory-budget %.1f MiB: with --passes %u, pass 2 simulates "
                                 "the scene reduced to the target %.4g, and its importance pass "
                                 "needs about %.1f MiB%s: give --passes 1, a smaller --target "
                                 "or a larger budget",
                                 MIB(budget), o->passes, st->target, MIB(later),
                                 shared ? " with what the host holds meanwhile (the device "
                                          "shares its memory)"
                                        : "");
        }
        snprintf(simulated, sizeof simulated, ", its importance pass %.1f MiB%s",
                 MIB(bytes_at(&importance, 1.0, per_triangle)),
                 shared ? " (with what the host holds meanwhile: the device shares its memory)"
                        : "");
    }
    if (o->importance.sppm.progress) {
        char initial[64] = "none";
        if (st->initial < 1)
            snprintf(initial, sizeof initial, "%.4g%s", st->initial,
                     o->initial < 1 ? "" : " (for the budget)");
        fprintf(stderr,
                "idmr: memory budget %.1f MiB: rendering the scene as it is needs about %.1f "
                "MiB%s; target %.4g%s, initial reduction %s\n",
                MIB(budget), MIB(bytes_at(&render, 1.0, per_triangle)), simulated, st->target,
                st->target < o->target ? " (for the budget)" : "", initial);
    }
    return 0;
}

/* The reduced scene's render memory, exactly: its BVH built on the host. */
static int measure_reduced(reduce_state *st)
{
    scene *reduced = reduce_view_of(st, st->output);
    if (!reduced)
        return -1;
    bvh b;
    int status = bvh_build(reduced, &b);
    if (!status) {
        render_options render = budget_render(st);
        status = render_memory(st->device, reduced, bvh_device_bytes(&b), &render,
                               &st->render_memory);
        bvh_free(&b);
    }
    scene_view_free(reduced);
    return status;
}

size_t reduce_memory_meshes_in_flight(const reduce_state *st, const uint32_t *vertices,
                                      size_t count)
{
    uint64_t budget = st->options->memory_budget;
    if (!budget || !st->device->info.host_unified)
        return count;
    double held = (double)resident_bytes();
    size_t fitting = 1;
    while (fitting < count) {
        held += REDUCE_IN_FLIGHT_BYTES_PER_VERTEX * (double)vertices[fitting - 1];
        if (held + REDUCE_IN_FLIGHT_BYTES_PER_VERTEX * (double)vertices[fitting] > (double)budget)
            break;
        fitting++;
    }
    return fitting;
}

int reduce_memory_fit(reduce_state *st, int *again)
{
    uint64_t budget = st->options->memory_budget;
    *again = 0;
    if (!budget)
        return 0;
    if (measure_reduced(st))
        return -1;
    double total = (double)sppm_memory_total(&st->render_memory);
    if (total <= (double)budget)
        return 0;
    double fixed = st->render_fixed_bytes;
    if (st->fit_rounds == FIT_ROUNDS || total <= fixed)
        return error_set(IDMR_EXIT_FAILURE,
                         "--memory-budget %.1f MiB: the reduced scene still needs %.1f MiB to "
                         "render after %u smaller targets (now %.4g); give a smaller --target",
                         MIB(budget), MIB(total), st->fit_rounds, st->target);
    st->fit_rounds++;
    st->target *= (REDUCE_MEMORY_MARGIN * (double)budget - fixed) / (total - fixed);
    if (st->options->importance.sppm.progress)
        fprintf(stderr,
                "idmr: the reduced scene needs %.1f MiB to render, above the budget of %.1f MiB: "
                "decimating again to %.4g\n",
                MIB(total), MIB(budget), st->target);
    *again = 1;
    return 0;
}

int reduce_memory_fit_spills(const reduce_state *st)
{
    return st->options->memory_budget && st->device->info.host_unified;
}

uint64_t reduce_memory_device_limit(const reduce_state *st)
{
    return st->options->memory_budget;
}

int reduce_memory_nothing_to_remove(const reduce_state *st)
{
    return st->options->memory_budget && !(st->target < 1);
}

/* Where the device shares the host's memory the budget bounds the whole process: a run that
 * went above it (the plan's estimates missed) is an error, not a result. */
int reduce_memory_check_peak(const reduce_state *st)
{
    uint64_t budget = st->options->memory_budget;
    if (!budget || !st->device->info.host_unified)
        return 0;
    double peak = peak_resident_bytes();
    if (peak <= (double)budget)
        return 0;
    return error_set(IDMR_EXIT_FAILURE,
                     "--memory-budget %.1f MiB: the process peaked at %.1f MiB (device '%s' "
                     "shares the host's memory, so the budget bounds the whole process); the "
                     "reduced scene is not written: raise the budget or lower --target",
                     MIB(budget), MIB(peak), st->device->info.name);
}
