/* device.h — the OpenCL runtime: discovery, choice, kernels, buffers, runs, error strings
 * (building programs is device/program.h).
 *
 * Devices are numbered across all platforms in platform order (what `idmr devices` lists);
 * device_open() takes that number, or -1 for the default: $IDMR_DEVICE if set, else the first
 * GPU, else device 0. */
#ifndef IDMR_DEVICE_H
#define IDMR_DEVICE_H

#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl.h>
#ifndef CL_PLATFORM_NOT_FOUND_KHR
#define CL_PLATFORM_NOT_FOUND_KHR -1001 /* cl_khr_icd: the ICD loader found no platform */
#endif
#include <stddef.h>
#include <stdint.h>

typedef struct device_info {
    int index; /* across all platforms */
    cl_platform_id platform;
    cl_device_id id;
    char platform_name[128];
    char name[128];
    char kind[16]; /* gpu, cpu, accelerator, other */
    cl_uint compute_units;
    cl_ulong global_memory;
    cl_ulong max_allocation;
    int host_unified; /* CL_DEVICE_HOST_UNIFIED_MEMORY: its memory is the host's (a CPU device,
                         PoCL): its buffers count in the process's resident memory */
    char opencl_c_version[64];
    int int64_atomics; /* cl_khr_int64_base_atomics */
} device_info;

typedef struct device {
    device_info info;
    cl_context context;
    cl_command_queue queue;
} device;

/* Lists every device of every platform. Returns 0, or -1 with the error set: no platform (exit
 * code IDMR_EXIT_INPUT, the message says how to install PoCL). *devices is malloc'd. */
int device_list(device_info **devices, size_t *count);

/* Opens device `index` (-1: default, see above) with a context and an in-order queue. */
int device_open(device *d, int index);
void device_close(device *d);

/* Creates kernel `name`, with the error naming it on failure. */
int device_create_kernel(cl_program program, const char *name, cl_kernel *kernel);

/* A buffer of `bytes` (copied from `host` when not NULL); `what` names it in errors
 * (e.g. "BVH nodes"), which also say how much memory the device has. */
int device_buffer(device *d, cl_mem_flags flags, size_t bytes, const void *host, const char *what,
                  cl_mem *buffer);

/* One buffer of a group that device_buffers() creates. */
typedef struct device_buffer_request {
    cl_mem *buffer;
    size_t bytes;
    const char *what;
} device_buffer_request;

/* Creates read-write buffers for `count` requests in order, adding their sizes to *bytes.
 * Returns 0, or -1 with the error set (buffers made so far stay for the caller to release). */
int device_buffers(device *d, const device_buffer_request *requests, size_t count,
                   uint64_t *bytes);

/* Releases the non-NULL kernels and buffers of arrays of `count`, setting them to NULL. */
void device_release_kernels(cl_kernel *kernels, size_t count);
void device_release_buffers(cl_mem *buffers, size_t count);

/* Blocking read of `bytes` from `buffer` into `host`. */
int device_read(device *d, cl_mem buffer, size_t bytes, void *host, const char *what);

/* Fills the first `bytes` of `buffer` (a multiple of 4) with zeros, queued in order. */
int device_clear(device *d, cl_mem buffer, size_t bytes, const char *what);

/* One kernel argument: DEVICE_ARG(x) passes sizeof x and &x. */
typedef struct device_arg {
    size_t size;
    const void *value;
} device_arg;
#define DEVICE_ARG(x) ((device_arg){sizeof(x), &(x)})

/* Sets `count` arguments of `kernel` in order, from argument `first` on:
 * DEVICE_SET_ARGS(k, "name", DEVICE_ARG(a), ...) from argument 0,
 * DEVICE_SET_ARGS_FROM(k, "name", first, DEVICE_ARG(a), ...) from argument `first`, and
 * DEVICE_SET_ARG(k, "name", index, a) one argument. */
int device_set_args(cl_kernel kernel, const char *kernel_name, cl_uint first,
                    const device_arg *args, size_t count);
#define DEVICE_SET_ARGS_FROM(kernel, name, first, ...)                                      \
    device_set_args(kernel, name, first, (const device_arg[]){__VA_ARGS__},                 \
                    sizeof((const device_arg[]){__VA_ARGS__}) / sizeof(device_arg))
#define DEVICE_SET_ARGS(kernel, name, ...) DEVICE_SET_ARGS_FROM(kernel, name, 0, __VA_ARGS__)
#define DEVICE_SET_ARG(kernel, name, index, value)                                          \
    DEVICE_SET_ARGS_FROM(kernel, name, index, DEVICE_ARG(value))

/* Enqueues a 1-D range of `global` work-items (rounded up to `local`, 0 = let the runtime
 * choose) and waits for it. */
int device_run(device *d, cl_kernel kernel, const char *kernel_name, size_t global, size_t local);

/* "CL_OUT_OF_RESOURCES" etc. */
const char *device_error_string(cl_int code);

/* Records "call: CL_ERROR_NAME" as the error when err != CL_SUCCESS; returns -1 then, else 0. */
int device_check(cl_int err, const char *call);

#endif
