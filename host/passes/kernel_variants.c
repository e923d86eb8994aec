/* kernel_variants.c — the list of kernel program variants (see kernel_variants.h). */
#include "device/program.h"
#include "passes/kernel_variants.h"

#include <stdio.h>
#include <stdlib.h>

#include "core/error.h"
#include "idmr/features.h"
#include "idmr/sppm_layout.h"
#include "passes/importance.h"
#include "passes/sppm.h"

#define MAX_VARIANTS 64

static void add_sppm(const device *d, int pass, unsigned int features, int accumulates,
                     int camera_importance, int shadows, kernel_variant *list, size_t *count)
{
    if (*count == MAX_VARIANTS) {
        fprintf(stderr, "idmr: kernel_variants: more than %d variants\n", MAX_VARIANTS);
        abort(); /* the list is fixed in this file: a programming error */
    }
    kernel_variant *v = &list[(*count)++];
    char defines[128] = "";
    if (pass == IDMR_SPPM_IMPORTANCE)
        importance_defines(accumulates, camera_importance, shadows, defines, sizeof defines);
    v->file = "sppm.cl";
    v->options = sppm_build_options(d, features, pass, pass == IDMR_SPPM_IMPORTANCE ? defines
                                                                                      : NULL);
    snprintf(v->label, sizeof v->label, "sppm.cl %s features=0x%03x%s%s%s%s",
             pass == IDMR_SPPM_IMPORTANCE ? "importance" : "render", features,
             accumulates ? "" : " no-accumulation", camera_importance ? "" : " no-camera-importance",
             pass == IDMR_SPPM_IMPORTANCE && !shadows ? " no-shadows" : "",
             d->info.int64_atomics ? "" : " 32-bit-atomics");
}

/* The feature sets each pass is built for: all, all but one bit, a minimal scene. */
static size_t feature_sets(unsigned int sets[IDMR_FEATURE_COUNT + 2])
{
    size_t n = 0;
    sets[n++] = IDMR_FEATURES_ALL;
    for (unsigned int bit = 0; bit < IDMR_FEATURE_COUNT; bit++)
        sets[n++] = IDMR_FEATURES_ALL & ~(1u << bit);
    sets[n++] = IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_AREA;
    return n;
}

size_t kernel_variants_list(const device *d, kernel_variant **variants)
{
    kernel_variant *list = xcalloc(MAX_VARIANTS, sizeof *list);
    size_t count = 0;
    unsigned int sets[IDMR_FEATURE_COUNT + 2];
    size_t set_count = feature_sets(sets);
    const int passes[2] = {IDMR_SPPM_IMPORTANCE, IDMR_SPPM_RENDER};
    for (int p = 0; p < 2; p++) {
        for (size_t k = 0; k < set_count; k++)
            add_sppm(d, passes[p], sets[k], 1, 1, 1, list, &count);
        /* traced through the two-level BVH (lib/surface.h) */
        add_sppm(d, passes[p], IDMR_FEATURES_ALL | IDMR_FEATURE_INSTANCES, 1, 1, 1, list, &count);
    }
    add_sppm(d, IDMR_SPPM_IMPORTANCE, IDMR_FEATURES_ALL, 0, 1, 1, list, &count);
    add_sppm(d, IDMR_SPPM_IMPORTANCE, IDMR_FEATURES_ALL, 1, 0, 1, list, &count);
    add_sppm(d, IDMR_SPPM_IMPORTANCE, IDMR_FEATURES_ALL, 1, 1, 0, list, &count);
    if (d->info.int64_atomics) { /* the other side of IDMR_INT64_ATOMICS too */
        device narrow = *d;
        narrow.info.int64_atomics = 0;
        for (int p = 0; p < 2; p++)
            add_sppm(&narrow, passes[p], IDMR_FEATURES_ALL, 1, 1, 1, list, &count);
    }
    kernel_variant *trace = &list[count++];
    trace->file = "trace.cl";
    trace->options = device_build_options(d, 0, NULL);
    snprintf(trace->label, sizeof trace->label, "trace.cl");
    *variants = list;
    return count;
}

void kernel_variants_free(kernel_variant *variants, size_t count)
{
    for (size_t i = 0; i < count; i++)
        free(variants[i].options);
    free(variants);
}
