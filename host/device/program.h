/* program.h — kernel programs: the OpenCL C 1.2 sources under kernels/, built with
 * "-I kernels -I include" and the options of device_build_options() (the one place options are
 * made; -v logs them), and cached as binaries. A failed build reports the build log and the
 * options. */
#ifndef IDMR_PROGRAM_H
#define IDMR_PROGRAM_H

#include <stdint.h>

#include "device/device.h"

/* The directory holding kernels/ and include/: $IDMR_ROOT, else the source tree idmr was
 * built from. */
const char *device_source_root(void);

/* Kernel build options for a scene with feature bits `features` plus `extra` defines (may be
 * NULL), as one malloc'd string. */
char *device_build_options(const device *d, unsigned int features, const char *extra);

/* Builds kernels/<file> with `options`. On failure the error holds the build log.
 *
 * Built programs are cached in $IDMR_CACHE_DIR, else $XDG_CACHE_HOME/idmr, else ~/.cache/idmr,
 * as binaries keyed by a 64-bit hash of the device (name, driver and platform versions), the
 * options, and the text of every file under kernels/ and include/idmr/ — so a second run of the
 * same scene does not rebuild, and a changed kernel source or option never reuses a stale
 * program (we key it ourselves rather than trust the runtime's cache). IDMR_CACHE_DIR=off turns
 * the cache off. A cache that cannot be read or written is skipped with a verbose log line. */
int device_build_program(device *d, const char *file, const char *options, cl_program *program);

/* The cache key of a build and whether the last device_build_program() found its program in
 * the cache (for tests and `make bench`). */
uint64_t device_program_key(const device *d, const char *file, const char *options);
int device_last_build_cached(void);

#endif
