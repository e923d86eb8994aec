/* reduce_passes.c — the stages of `idmr reduce` that let the importance pass run on a reduced
 * scene (paper 3.5; reduce.h, reduce_stages.h): the initial reduction (--initial D0), the scene
 * each pass simulates (a view of the scene with the reduced meshes), the importance copied back
 * to the original vertices (remap.h; moved to disk and back while the memory fit builds its BVH),
 * and the change from one pass to the next (--passes). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/progress.h"
#include "reduce/remap.h"
#include "reduce/reduce_stages.h"

/* Every released mesh (core/scene.h: streaming) read again. 0, or -1 with the error set. */
static int restore_all(reduce_state *st)
{
    for (size_t m = 0; m < st->count; m++)
        if (scene_mesh_restore(st->scene, m))
            return -1;
    return 0;
}

/* The view the importance pass simulates: the scene with each mesh that the history decimated
 * replaced by its decimated copy (the others as they are, read again where released). */
static int build_view(reduce_state *st)
{
    scene_view_free(st->view);
    st->view = reduce_view_of(st, st->history);
    st->simulated = st->view ? st->view : st->scene;
    return st->view ? 0 : -1;
}

/* Whether the initial reduction decimates mesh m: decimatable and not below the floor (an
 * instance's later copies get their first copy's reduction, moved: reduce_instances.c). */
static int initially_reduced(const reduce_state *st, size_t m)
{
    return reduce_decimatable(st, m) && st->scene->meshes[m].vertex_count >= REDUCE_INITIAL_FLOOR;
}

int reduce_initial(reduce_state *st)
{
    const reduce_options *o = st->options;
    if (!(st->initial < 1)) /* the passes simulate the scene itself: all of it in memory */
        return restore_all(st);
    double start = monotonic_seconds();
    decimate_input *inputs = xcalloc(st->count + 1, sizeof *inputs);
    uint64_t *targets = xcalloc(st->count + 1, sizeof *targets);
    unsigned char *selected = xcalloc(st->count + 1, 1);
    size_t n = 0;
    for (size_t m = 0; m < st->count; m++)
        if (initially_reduced(st, m)) {
            inputs[m] = reduce_decimation_input(st, m);
            targets[m] = (uint64_t)ceil(st->initial * (double)st->scene->meshes[m].vertex_count);
            selected[m] = 1;
            n++;
        }
    if (o->importance.sppm.progress)
        fprintf(stderr, "idmr: initial reduction: %zu meshes to %.4g of their vertices (quadric)\n",
                n, st->initial);
    st->history = xcalloc(st->count + 1, sizeof *st->history);
    int status = reduce_decimate_meshes(st, inputs, targets, selected, DECIMATE_QUADRIC,
                                        "initial reduction", 1, st->history);
    free(inputs);
    free(targets);
    free(selected);
    if (!status)
        status = build_view(st);
    st->vertices_initial = st->view ? st->view->vertex_count : 0;
    st->seconds_initial = monotonic_seconds() - start;
    return status;
}

void reduce_remap(reduce_state *st)
{
    if (!st->history)
        return;
    st->remapped = xcalloc(st->count + 1, sizeof *st->remapped);
    st->distance = xcalloc(st->count + 1, sizeof *st->distance);
    for (size_t m = 0; m < st->count; m++) {
        decimate_output *h = &st->history[m];
        if (!h->collapsed_into)
            continue; /* simulated as it is: its own values */
        uint32_t original = st->scene->meshes[m].vertex_count;
        st->remapped[m] = xcalloc((size_t)original + 1, sizeof *st->remapped[m]);
        st->distance[m] = xcalloc((size_t)original + 1, sizeof *st->distance[m]);
        remap_values(h, original, st->vertex_importance[m], st->remapped[m], st->distance[m]);
        /* The chains are followed: only the reduced mesh (the view's) is needed from here. */
        decimate_output_free_history(h);
    }
}

/* Frees the remapped importance (and closes its file where it was spilled). */
static void remapped_free(reduce_state *st)
{
    if (st->spill)
        fclose(st->spill);
    st->spill = NULL;
    for (size_t m = 0; st->remapped && m < st->count; m++) {
        free(st->remapped[m]);
        free(st->distance[m]);
    }
    free(st->remapped);
    free(st->distance);
    st->remapped = NULL;
    st->distance = NULL;
}

/* The spill file holds, per mesh in order, one byte saying whether the mesh has a remapped
 * importance, then its values and distances (vertex_count of each). */
int reduce_remapped_spill(reduce_state *st)
{
    if (!st->remapped)
        return 0;
    char path[2100];
    snprintf(path, sizeof path, "%s/.remapped", st->staging);
    FILE *f = fopen(path, "w+b");
    if (!f)
        return error_set(IDMR_EXIT_FAILURE, "%s: cannot create it to hold the remapped "
                                            "importance meanwhile: %s", path, strerror(errno));
    remove(path); /* unnamed from here: it goes with the process whatever happens */
    int written = 1;
    for (size_t m = 0; m < st->count; m++) {
        unsigned char present = st->remapped[m] != NULL;
        written = written && fwrite(&present, 1, 1, f) == 1;
        if (!present) /* no values: nothing more (fwrite takes no null pointer, even for 0) */
            continue;
        size_t n = st->scene->meshes[m].vertex_count;
        written = written && fwrite(st->remapped[m], sizeof *st->remapped[m], n, f) == n &&
                  fwrite(st->distance[m], sizeof *st->distance[m], n, f) == n;
    }
    if (!written || fflush(f)) {
        fclose(f);
        return error_set(IDMR_EXIT_FAILURE, "%s: cannot write the remapped importance: %s",
                         st->staging, strerror(errno));
    }
    for (size_t m = 0; m < st->count; m++) {
        free(st->remapped[m]);
        free(st->distance[m]);
        st->remapped[m] = NULL;
        st->distance[m] = NULL;
    }
    st->spill = f;
    return 0;
}

int reduce_remapped_restore(reduce_state *st)
{
    if (!st->spill)
        return 0;
    rewind(st->spill);
    int read = 1;
    for (size_t m = 0; m < st->count && read; m++) {
        unsigned char present = 0;
        read = fread(&present, 1, 1, st->spill) == 1;
        if (!read || !present)
            continue;
        size_t n = st->scene->meshes[m].vertex_count;
        st->remapped[m] = xcalloc(n + 1, sizeof *st->remapped[m]);
        st->distance[m] = xcalloc(n + 1, sizeof *st->distance[m]);
        read = fread(st->remapped[m], sizeof *st->remapped[m], n, st->spill) == n &&
               fread(st->distance[m], sizeof *st->distance[m], n, st->spill) == n;
    }
    fclose(st->spill);
    st->spill = NULL;
    return read ? 0 : error_set(IDMR_EXIT_FAILURE, "%s: cannot read the remapped importance "
                                                    "back", st->staging);
}

/* Frees the history and the view of it. */
static void history_free(reduce_state *st)
{
    scene_view_free(st->view);
    st->view = NULL;
    st->simulated = st->scene;
    for (size_t m = 0; st->history && m < st->count; m++)
        decimate_output_free(&st->history[m]);
    free(st->history);
    st->history = NULL;
}

int reduce_next_pass(reduce_state *st, decimate_output *output)
{
    remapped_free(st);
    history_free(st);
    /* The last pass's output is the next pass's history: decimated from the originals. Meshes
     * it did not decimate have no output, and are simulated as they are. */
    st->history = output;
    return build_view(st);
}

void reduce_passes_free(reduce_state *st)
{
    remapped_free(st);
    history_free(st);
}
