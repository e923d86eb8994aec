/* pass_setup.c — device and BVH around a pass command's work (pass_setup.h). */
#include "cli/pass_setup.h"

int pass_setup_run(const scene *s, int device_index, pass_work work, void *context)
{
    device d;
    bvh b;
    int status = device_open(&d, device_index);
    if (status)
        return status;
    status = bvh_build(s, &b);
    if (status)
        goto close_device;
    status = work(&d, s, &b, context);
    bvh_free(&b);
close_device:
    device_close(&d);
    return status;
}
