/* pass_setup.h — what `importance`, `reduce` and `render` run their pass on: the open OpenCL
 * devices that --device chose and the scene's BVH, set up before and released after the
 * command's own work. */
#ifndef IDMR_CLI_PASS_SETUP_H
#define IDMR_CLI_PASS_SETUP_H
#include "cli/options.h"
#include "core/scene.h"
#include "device/bvh.h"
#include "device/device.h"

/* A command's pass and outputs on the `count` open devices `devices` (the first is the one a
 * single-device command uses) with BVH `b`; 0, or -1 with the error set. */
typedef int (*pass_work)(device *devices, unsigned int count, const scene *s, const bvh *b,
                         void *context);

/* Opens the devices of `choice` into devices[SPPM_MAX_DEVICES] (`all`: every device `idmr
 * devices` lists, in its order) and sets *count. Returns 0, or -1 with the error set (a device
 * that does not open is named; those opened before it are closed again). */
int pass_setup_open_devices(const device_choice *choice, device *devices, unsigned int *count);
void pass_setup_close_devices(device *devices, unsigned int count);

/* Opens the devices of `choice`, builds the BVH of `s`, runs `work` with `context`, then frees
 * the BVH and closes the devices. Returns 0, or -1 with the error of the first step that
 * failed set. */
int pass_setup_run(const scene *s, const device_choice *choice, pass_work work, void *context);

#endif
