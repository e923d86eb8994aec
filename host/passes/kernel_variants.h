/* kernel_variants.h — every program the kernels can be built as, so that one command (`idmr
 * kernels`, run by `make kernels`) compiles them all on a device: a kernel error then fails the
 * build instead of surfacing in a test or a user's run, and the program cache is warm.
 *
 * The variants cover every branch of the #if's in kernels/: for each pass of kernels/sppm.cl,
 * every feature on (the generic program), every feature but one (each bit's #else side), and a
 * minimal scene (diffuse surfaces, an area light), every feature with IDMR_FEATURE_INSTANCES (the
 * two-level BVH's tracing); the importance pass also without accumulating,
 * without camera importance and without shadow rays; both passes with 32-bit atomics in place
 * of 64-bit ones; and
 * kernels/trace.cl. */
#ifndef IDMR_KERNEL_VARIANTS_H
#define IDMR_KERNEL_VARIANTS_H

#include <stddef.h>

#include "device/device.h"

typedef struct kernel_variant {
    char label[128];  /* e.g. "sppm.cl render features=0x3ff" */
    const char *file; /* under kernels/ */
    char *options;    /* build options, malloc'd */
} kernel_variant;

/* The variants for device `d` into a malloc'd array; returns their count. */
size_t kernel_variants_list(const device *d, kernel_variant **variants);
void kernel_variants_free(kernel_variant *variants, size_t count);

#endif
