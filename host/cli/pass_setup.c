/* pass_setup.c — devices and BVH around a pass command's work (pass_setup.h). */
#include "cli/pass_setup.h"

#include <stdlib.h>

#include "core/error.h"

int pass_setup_open_devices(const device_choice *choice, device *devices, unsigned int *count)
{
    int list[SPPM_MAX_DEVICES];
    unsigned int wanted = 1;
    list[0] = choice->index;
    if (choice->all) {
        device_info *infos;
        size_t found;
        if (device_list(&infos, &found))
            return -1;
        free(infos);
        if (found > SPPM_MAX_DEVICES)
            warn("--device all: %zu devices found; the first %d are used", found,
                 SPPM_MAX_DEVICES);
        wanted = found < SPPM_MAX_DEVICES ? (unsigned int)found : SPPM_MAX_DEVICES;
        if (wanted == 0)
            return error_set(IDMR_EXIT_INPUT, "--device all: no OpenCL device was found");
        for (unsigned int k = 0; k < wanted; k++)
            list[k] = (int)k;
    } else if (choice->count > 1) {
        device_info *infos;
        size_t found;
        if (device_list(&infos, &found))
            return -1;
        free(infos);
        wanted = choice->count;
        for (unsigned int k = 0; k < wanted; k++) {
            list[k] = choice->list[k];
            if ((size_t)list[k] >= found)
                return error_set(IDMR_EXIT_INPUT,
                                 "--device: device %d does not exist: there are %zu (see `idmr "
                                 "devices`)",
                                 list[k], found);
        }
    }
    for (*count = 0; *count < wanted; (*count)++)
        if (device_open(devices + *count, list[*count])) {
            if (wanted > 1)
                error_prefix("device %d", list[*count]);
            pass_setup_close_devices(devices, *count);
            *count = 0;
            return -1;
        }
    return 0;
}

void pass_setup_close_devices(device *devices, unsigned int count)
{
    for (unsigned int k = 0; k < count; k++)
        device_close(devices + k);
}

int pass_setup_run(const scene *s, const device_choice *choice, pass_work work, void *context)
{
    device devices[SPPM_MAX_DEVICES];
    unsigned int count;
    bvh b;
    int status = pass_setup_open_devices(choice, devices, &count);
    if (status)
        return status;
    status = bvh_build(s, &b);
    if (status)
        goto close_devices;
    status = work(devices, count, s, &b, context);
    bvh_free(&b);
close_devices:
    pass_setup_close_devices(devices, count);
    return status;
}
