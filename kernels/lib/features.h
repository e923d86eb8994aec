/* features.h — what a program is built for: the scene's feature bits (idmr/features.h) and, for
 * the SPPM kernels, the pass (idmr/sppm_layout.h). All of it comes from the host's one
 * function device_build_options(); impossible combinations stop the build here.
 *
 *   IDMR_FEATURES     material and light kinds present, and IDMR_FEATURE_INSTANCES where the
 *                     scene is traced through its two-level BVH (lib/surface.h);
 *                     HAS_FEATURE(bit) tests one or more
 *   IDMR_SPPM_PASS    IDMR_SPPM_IMPORTANCE or IDMR_SPPM_RENDER (kernels/sppm.cl only) */
#ifndef IDMR_KERNEL_FEATURES_H
#define IDMR_KERNEL_FEATURES_H

#include "idmr/features.h"
#include "idmr/sppm_layout.h"

#ifndef IDMR_FEATURES
#error "IDMR_FEATURES must be defined by the host (device_build_options)"
#endif
#define HAS_FEATURE(bit) ((IDMR_FEATURES & (bit)) != 0u)
#if (IDMR_FEATURES & ~(IDMR_FEATURES_ALL | IDMR_FEATURE_INSTANCES)) != 0u
#error "IDMR_FEATURES has bits no feature defines (idmr/features.h)"
#endif
#if !HAS_FEATURE(IDMR_FEATURES_LIGHTS)
#error "no light kind in IDMR_FEATURES: photon paths need an emitter"
#endif
#if HAS_FEATURE(IDMR_FEATURE_TEXTURED) && !HAS_FEATURE(IDMR_FEATURE_DIFFUSE | IDMR_FEATURE_GLOSSY)
#error "a texture without a diffuse or glossy material to carry it"
#endif

#ifdef IDMR_SPPM_PASS
#if IDMR_SPPM_PASS != IDMR_SPPM_IMPORTANCE && IDMR_SPPM_PASS != IDMR_SPPM_RENDER
#error "IDMR_SPPM_PASS must be IDMR_SPPM_IMPORTANCE or IDMR_SPPM_RENDER"
#endif
#define PASS_IMPORTANCE (IDMR_SPPM_PASS == IDMR_SPPM_IMPORTANCE)
#define PASS_RENDER (IDMR_SPPM_PASS == IDMR_SPPM_RENDER)
#endif

#endif
