/* reduce.c — the reduction pipeline behind `idmr reduce` (see reduce.h): reduce_run() runs the
 * stages in order over one reduce_state and decides every loop back (the next importance pass;
 * the decimation again where the memory fit asks for it). reduce_stages.h lists the stages, the
 * files they live in and the fields each writes; this file holds no stage, and no stage calls
 * into it. */
#include "reduce/reduce.h"

#include <stdio.h>
#include <stdlib.h>

#include "core/error.h"
#include "core/ranks.h"
#include "reduce/reduce_stages.h"

/* Frees what the budget and decimation stages left, so that they can run again. */
static void forget_reduction(reduce_state *st)
{
    reduce_decimation_forget(st);
    reduce_budget_forget(st);
}

static void state_free(reduce_state *st)
{
    /* The importance first: its values are per vertex of the simulated scene, which
     * reduce_passes_free() frees. */
    reduce_importance_forget(st);
    reduce_write_free(st);
    forget_reduction(st);
    reduce_passes_free(st);
    reduce_error_budget_free(st);
    reduce_refine_free(st);
    free(st->passes);
}

/* The record of the pass that just ended (report.json: passes). */
static int record_pass(reduce_state *st, double seconds_importance, double seconds_reduction)
{
    const sppm_summary *run = &st->importance.sppm;
    reduce_pass_record *p = &st->passes[st->pass_count++];
    p->seconds_importance = st->seconds_importance - seconds_importance;
    p->seconds_reduction = st->seconds_budget + st->seconds_decimation - seconds_reduction;
    p->vertices_simulated = st->simulated->vertex_count;
    p->vertices_after = st->vertices_after;
    p->device_bytes = st->options->simulation
                          ? 0
                          : run->geometry_bytes + run->bvh_bytes + run->buffer_bytes;
    p->iterations = run->iterations;
    return 0;
}

/* Between passes: the last pass's importance and reduction forgotten, its output handed on as
 * the history whose view the next pass simulates. The importance goes before the view that
 * reduce_next_pass() replaces: its values are per vertex of that scene. */
static int next_pass(reduce_state *st)
{
    decimate_output *output = reduce_decimation_take_output(st);
    forget_reduction(st);
    reduce_importance_forget(st);
    return reduce_next_pass(st, output);
}

/* One importance pass and the reduction of the originals after it; from the second on, the
 * importance pass runs on the last one's result. */
static int run_pass(reduce_state *st, unsigned int pass)
{
    double importance_before = st->seconds_importance;
    double reduction_before = st->seconds_budget + st->seconds_decimation;
    if (pass > 1 && next_pass(st))
        return -1;
    if (st->options->passes > 1 && st->options->importance.sppm.progress && ranks_rank() == 0)
        fprintf(stderr, "idmr: pass %u of %u: importance on %llu vertices\n", pass,
                st->options->passes, (unsigned long long)st->simulated->vertex_count);
    /* Under mpirun every rank runs every stage (the importance pass and the decimation are
     * shared: core/ranks.h, reduce_ranks.c); rank 0 alone writes. With --max-error (one
     * process only: below) the target is searched for: the budget and decimation run at every
     * D the search measures, and last at the D it found. */
    if (reduce_importance(st))
        return -1;
    int status = st->options->error.bound != REDUCE_ERROR_NONE
                     ? reduce_error_budget(st)
                     : reduce_plan_budget(st) || reduce_decimation(st);
    /* --refine (one pass only, reduce_options.c): the reduction refined at its D */
    status = status || reduce_refine(st);
    return status || record_pass(st, importance_before, reduction_before);
}

int reduce_run(device *d, scene *s, const char *outdir, const reduce_options *o)
{
    return reduce_run_devices(d, 1, s, outdir, o);
}

int reduce_run_devices(device *devices, unsigned int count, scene *s, const char *outdir,
                       const reduce_options *o)
{
    if (count > 1 && o->memory_budget)
        return error_set(IDMR_EXIT_INPUT,
                         "reduce: --memory-budget plans the scene for one device: give one "
                         "--device number (%u devices were chosen)",
                         count);
    if (ranks_count() > 1 && o->memory_budget)
        return error_set(IDMR_EXIT_INPUT,
                         "reduce: --memory-budget plans the scene for one device: run it "
                         "without mpirun (%d ranks were started)",
                         ranks_count());
    if (ranks_count() > 1 && o->refine)
        return error_set(IDMR_EXIT_INPUT,
                         "reduce: --refine renders its checks in one process: run it "
                         "without mpirun (%d ranks were started)",
                         ranks_count());
    if (ranks_count() > 1 && o->error.bound != REDUCE_ERROR_NONE)
        return error_set(IDMR_EXIT_INPUT,
                         "reduce: --max-error renders its checks in one process: run it "
                         "without mpirun (%d ranks were started)",
                         ranks_count());
    int lead = ranks_rank() == 0; /* writes the output (under mpirun, rank 0 alone) */
    reduce_state st = {.device = devices, .device_count = count, .scene = s, .simulated = s,
                       .outdir = outdir, .options = o, .count = s->mesh_count,
                       .target = o->target, .initial = o->initial};
    st.passes = xcalloc(REDUCE_MAX_PASSES + 1, sizeof *st.passes);
    int status = reduce_options_check(&st);
    /* On a device that shares the host's memory, the budget bounds the whole process: the
     * importance pass's program is built before the plan measures what the process holds, since
     * PoCL compiling it later, inside the planned run, took the process 110-120 MiB above the
     * plan (README, `make bench-outofcore`); the pass then finds it cached. */
    if (!status && o->memory_budget && devices[0].info.host_unified &&
        reduce_method_uses_importance(o->method))
        status = importance_build_program(devices, s, &o->importance);
    status = status || reduce_memory_plan(&st);
    /* The budget leaves nothing to remove (the scene renders within it as it is): the scene is
     * written as it is, without an initial reduction or an importance pass to find that out. */
    reduce_options as_is;
    if (!status && reduce_memory_nothing_to_remove(&st) &&
        reduce_method_uses_importance(o->method)) {
        as_is = *o;
        as_is.method = REDUCE_QUADRIC;
        as_is.passes = 1;
        as_is.initial = 1.0;
        st.options = o = &as_is;
        st.initial = 1.0;
    }
    status = status || (lead && reduce_outdir_prepare(&st)) || reduce_initial(&st);
    for (unsigned int pass = 1; !status && pass <= o->passes; pass++)
        status = run_pass(&st, pass);
    /* Under a memory budget, the reduced scene decimated again at a lower target while its
     * render does not fit (the fit says so); the remapped importance, which only that
     * decimation needs, out of memory while the fit measures, where the fit says so. */
    for (int again = 1; !status && again;) {
        status = (reduce_memory_fit_spills(&st) && reduce_remapped_spill(&st)) ||
                 reduce_memory_fit(&st, &again);
        if (status || !again)
            break;
        status = reduce_remapped_restore(&st);
        if (status)
            break;
        forget_reduction(&st);
        status = reduce_plan_budget(&st) || reduce_decimation(&st);
        if (!status && st.pass_count) /* the last pass's reduction is this one now */
            st.passes[st.pass_count - 1].vertices_after = st.vertices_after;
    }
    status = status || (lead && (reduce_write(&st) || reduce_report_write(&st) ||
                                 reduce_memory_check_peak(&st)));
    /* Published only once every rank has done its part (core/ranks.h; one process: no-op). */
    status = ranks_sync(status, NULL);
    status = reduce_outdir_finish(&st, !status);
    if (!status && lead)
        reduce_report_summary(&st);
    state_free(&st);
    return status ? -1 : 0;
}
