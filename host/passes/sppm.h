/* sppm.h — the options of the SPPM core that both passes run on (the importance pass,
 * passes/importance.h, and the renderer, passes/render.h). */
#ifndef IDMR_SPPM_H
#define IDMR_SPPM_H

#include <stddef.h>

#include "device/device.h"

typedef struct sppm_options {
    unsigned int iterations; /* at most this many */
    unsigned int photons;    /* photon paths per iteration; 0: sppm_default_photons() */
    unsigned int seed;       /* default 1 */
    float alpha;             /* radius reduction α of the SPPM schedule (default 0.7) */
    float resolution;        /* scale of the scene's film for the hit-point image (default 1) */
    double time_limit;       /* seconds; > 0 stops after the iteration in which they pass */
    size_t local_size;       /* work-group size; 0 lets the runtime choose */
    int generic;             /* build the all-features program instead of the scene's */
    int progress;            /* report progress on stderr */
} sppm_options;

/* Defaults, with `iterations` as the iteration count (each pass has its own). */
void sppm_options_default(sppm_options *o, unsigned int iterations);

/* Photon paths per iteration when none are asked for: 1,000,000 on a GPU (the paper's
 * figure); 500,000 on a CPU, which keeps an iteration of the DRAGON CORNELL BOX (871k
 * triangles) near 0.68 s on 2 cores with PoCL (make bench). */
unsigned int sppm_default_photons(const device *d);

#endif
