/* pass_setup.h — what `importance` and `render` run their pass on: an open OpenCL device and
 * the scene's BVH, set up before and released after the command's own work. */
#ifndef IDMR_CLI_PASS_SETUP_H
#define IDMR_CLI_PASS_SETUP_H
#include "core/scene.h"
#include "device/bvh.h"
#include "device/device.h"

/* A command's pass and outputs on the device `d` with BVH `b`; 0, or -1 with the error set. */
typedef int (*pass_work)(device *d, const scene *s, const bvh *b, void *context);

/* Opens device `device_index` (-1: the default), builds the BVH of `s`, runs `work` with
 * `context`, then frees the BVH and closes the device. Returns 0, or -1 with the error of the
 * first step that failed set. */
int pass_setup_run(const scene *s, int device_index, pass_work work, void *context);

#endif
