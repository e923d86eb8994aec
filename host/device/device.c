/* device.c — OpenCL discovery, kernels, buffers and runs (see device.h). */
#include "device/device.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

const char *device_error_string(cl_int code)
{
    switch (code) {
#define CASE(name) \
    case name: return #name
        CASE(CL_SUCCESS);
        CASE(CL_DEVICE_NOT_FOUND);
        CASE(CL_DEVICE_NOT_AVAILABLE);
        CASE(CL_COMPILER_NOT_AVAILABLE);
        CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE);
        CASE(CL_OUT_OF_RESOURCES);
        CASE(CL_OUT_OF_HOST_MEMORY);
        CASE(CL_BUILD_PROGRAM_FAILURE);
        CASE(CL_INVALID_VALUE);
        CASE(CL_INVALID_PLATFORM);
        CASE(CL_INVALID_DEVICE);
        CASE(CL_INVALID_CONTEXT);
        CASE(CL_INVALID_COMMAND_QUEUE);
        CASE(CL_INVALID_MEM_OBJECT);
        CASE(CL_INVALID_BUILD_OPTIONS);
        CASE(CL_INVALID_PROGRAM);
        CASE(CL_INVALID_PROGRAM_EXECUTABLE);
        CASE(CL_INVALID_KERNEL_NAME);
        CASE(CL_INVALID_KERNEL);
        CASE(CL_INVALID_ARG_INDEX);
        CASE(CL_INVALID_ARG_VALUE);
        CASE(CL_INVALID_ARG_SIZE);
        CASE(CL_INVALID_KERNEL_ARGS);
        CASE(CL_INVALID_WORK_DIMENSION);
        CASE(CL_INVALID_WORK_GROUP_SIZE);
        CASE(CL_INVALID_WORK_ITEM_SIZE);
        CASE(CL_INVALID_GLOBAL_OFFSET);
        CASE(CL_INVALID_BUFFER_SIZE);
        CASE(CL_INVALID_OPERATION);
        CASE(CL_INVALID_GLOBAL_WORK_SIZE);
        CASE(CL_PLATFORM_NOT_FOUND_KHR);
#undef CASE
    default: return "unknown OpenCL error";
    }
}

int device_check(cl_int err, const char *call)
{
    if (err == CL_SUCCESS)
        return 0;
    return error_set(IDMR_EXIT_FAILURE, "%s failed: %s (%d)", call, device_error_string(err), err);
}

static const char *kind_name(cl_device_type type)
{
    if (type & CL_DEVICE_TYPE_GPU)
        return "gpu";
    if (type & CL_DEVICE_TYPE_CPU)
        return "cpu";
    if (type & CL_DEVICE_TYPE_ACCELERATOR)
        return "accelerator";
    return "other";
}

static void query_device(device_info *info)
{
    cl_device_type type = 0;
    char extensions[8192] = "";
    clGetPlatformInfo(info->platform, CL_PLATFORM_NAME, sizeof info->platform_name,
                      info->platform_name, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_NAME, sizeof info->name, info->name, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof info->compute_units,
                    &info->compute_units, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof info->global_memory,
                    &info->global_memory, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof info->max_allocation,
                    &info->max_allocation, NULL);
    cl_bool unified = CL_FALSE;
    clGetDeviceInfo(info->id, CL_DEVICE_HOST_UNIFIED_MEMORY, sizeof unified, &unified, NULL);
    info->host_unified = unified == CL_TRUE;
    clGetDeviceInfo(info->id, CL_DEVICE_OPENCL_C_VERSION, sizeof info->opencl_c_version,
                    info->opencl_c_version, NULL);
    clGetDeviceInfo(info->id, CL_DEVICE_EXTENSIONS, sizeof extensions - 1, extensions, NULL);
    snprintf(info->kind, sizeof info->kind, "%s", kind_name(type));
    info->int64_atomics = strstr(extensions, "cl_khr_int64_base_atomics") != NULL;
}

int device_list(device_info **devices, size_t *count)
{
    *devices = NULL;
    *count = 0;
    cl_uint platform_count = 0;
    cl_int err = clGetPlatformIDs(0, NULL, &platform_count);
    if (err == CL_PLATFORM_NOT_FOUND_KHR || platform_count == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "no OpenCL platform found. Install one, for example PoCL for the CPU: "
                         "`sudo apt-get install pocl-opencl-icd ocl-icd-opencl-dev` (or run "
                         "scripts/install-deps.sh); check with `clinfo -l`");
    if (device_check(err, "clGetPlatformIDs"))
        return -1;
    cl_platform_id *platforms = xcalloc(platform_count, sizeof *platforms);
    clGetPlatformIDs(platform_count, platforms, NULL);
    device_info *list = NULL;
    size_t n = 0;
    for (cl_uint p = 0; p < platform_count; p++) {
        cl_uint device_count = 0;
        if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, NULL, &device_count) != CL_SUCCESS)
            continue;
        cl_device_id *ids = xcalloc(device_count, sizeof *ids);
        clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, device_count, ids, NULL);
        list = xrealloc(list, (n + device_count) * sizeof *list);
        for (cl_uint d = 0; d < device_count; d++) {
            device_info *info = &list[n];
            memset(info, 0, sizeof *info);
            info->index = (int)n;
            info->platform = platforms[p];
            info->id = ids[d];
            query_device(info);
            n++;
        }
        free(ids);
    }
    free(platforms);
    if (n == 0) {
        free(list);
        return error_set(IDMR_EXIT_INPUT,
                         "OpenCL platforms found but no device; install PoCL for the CPU: "
                         "`sudo apt-get install pocl-opencl-icd`");
    }
    *devices = list;
    *count = n;
    return 0;
}

/* -1 → $IDMR_DEVICE, else the first GPU, else 0. */
static int choose_device(const device_info *list, size_t count, int requested)
{
    if (requested < 0) {
        const char *env = getenv("IDMR_DEVICE");
        if (env && *env) {
            char *end;
            long value = strtol(env, &end, 10);
            if (*end || value < 0)
                return error_set(IDMR_EXIT_INPUT, "IDMR_DEVICE='%s' is not a device number", env);
            requested = (int)value;
        }
    }
    if (requested < 0) {
        for (size_t i = 0; i < count; i++)
            if (strcmp(list[i].kind, "gpu") == 0)
                return (int)i;
        return 0;
    }
    if ((size_t)requested >= count)
        return error_set(IDMR_EXIT_INPUT,
                         "device %d does not exist: there are %zu (see `idmr devices`)",
                         requested, count);
    return requested;
}

int device_open(device *d, int index)
{
    memset(d, 0, sizeof *d);
    device_info *list;
    size_t count;
    if (device_list(&list, &count))
        return -1;
    int chosen = choose_device(list, count, index);
    if (chosen < 0) {
        free(list);
        return -1;
    }
    d->info = list[chosen];
    free(list);
    cl_int err;
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)d->info.platform,
                                      0};
    d->context = clCreateContext(props, 1, &d->info.id, NULL, NULL, &err);
    if (device_check(err, "clCreateContext"))
        return -1;
    d->queue = clCreateCommandQueue(d->context, d->info.id, 0, &err);
    if (device_check(err, "clCreateCommandQueue")) {
        clReleaseContext(d->context);
        d->context = NULL;
        return -1;
    }
    log_verbose("device %d: %s (%s, %s)", d->info.index, d->info.name, d->info.platform_name,
                d->info.kind);
    return 0;
}

void device_close(device *d)
{
    if (d->queue)
        clReleaseCommandQueue(d->queue);
    if (d->context)
        clReleaseContext(d->context);
    memset(d, 0, sizeof *d);
}

int device_create_kernel(cl_program program, const char *name, cl_kernel *kernel)
{
    cl_int err;
    *kernel = clCreateKernel(program, name, &err);
    if (err != CL_SUCCESS)
        return error_set(IDMR_EXIT_FAILURE, "clCreateKernel(%s) failed: %s", name,
                         device_error_string(err));
    return 0;
}

int device_buffer(device *d, cl_mem_flags flags, size_t bytes, const void *host, const char *what,
                  cl_mem *buffer)
{
    cl_int err;
    if (bytes == 0)
        bytes = 16; /* a zero-sized buffer is invalid; kernels never read it */
    else if (bytes > d->info.max_allocation)
        return error_set(IDMR_EXIT_FAILURE,
                         "%s need %.1f MiB in one buffer, but device '%s' allows at most %.1f MiB "
                         "per buffer (%.1f MiB in all)",
                         what, bytes / 1048576.0, d->info.name, d->info.max_allocation / 1048576.0,
                         d->info.global_memory / 1048576.0);
    *buffer = clCreateBuffer(d->context, flags | (host ? CL_MEM_COPY_HOST_PTR : 0), bytes,
                             (void *)host, &err);
    if (err != CL_SUCCESS)
        return error_set(IDMR_EXIT_FAILURE,
                         "allocating %s (%.1f MiB) on device '%s' (%.1f MiB) failed: %s", what,
                         bytes / 1048576.0, d->info.name, d->info.global_memory / 1048576.0,
                         device_error_string(err));
    return 0;
}

int device_buffers(device *d, const device_buffer_request *requests, size_t count,
                   uint64_t *bytes)
{
    for (size_t i = 0; i < count; i++) {
        if (device_buffer(d, CL_MEM_READ_WRITE, requests[i].bytes, NULL, requests[i].what,
                          requests[i].buffer))
            return -1;
        *bytes += requests[i].bytes;
    }
    return 0;
}

void device_release_kernels(cl_kernel *kernels, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (kernels[i]) {
            clReleaseKernel(kernels[i]);
            kernels[i] = NULL;
        }
}

void device_release_buffers(cl_mem *buffers, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (buffers[i]) {
            clReleaseMemObject(buffers[i]);
            buffers[i] = NULL;
        }
}

int device_read(device *d, cl_mem buffer, size_t bytes, void *host, const char *what)
{
    cl_int err = clEnqueueReadBuffer(d->queue, buffer, CL_TRUE, 0, bytes, host, 0, NULL, NULL);
    if (err != CL_SUCCESS)
        return error_set(IDMR_EXIT_FAILURE, "reading %s from the device failed: %s", what,
                         device_error_string(err));
    return 0;
}

int device_clear(device *d, cl_mem buffer, size_t bytes, const char *what)
{
    cl_uint zero = 0;
    cl_int err = clEnqueueFillBuffer(d->queue, buffer, &zero, sizeof zero, 0, bytes, 0, NULL, NULL);
    if (err != CL_SUCCESS)
        return error_set(IDMR_EXIT_FAILURE, "clearing %s failed: %s", what,
                         device_error_string(err));
    return 0;
}

int device_set_args(cl_kernel kernel, const char *kernel_name, cl_uint first,
                    const device_arg *args, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        cl_uint index = first + (cl_uint)i;
        cl_int err = clSetKernelArg(kernel, index, args[i].size, args[i].value);
        if (err != CL_SUCCESS)
            return error_set(IDMR_EXIT_FAILURE, "clSetKernelArg(%s, %u) failed: %s", kernel_name,
                             index, device_error_string(err));
    }
    return 0;
}

int device_run(device *d, cl_kernel kernel, const char *kernel_name, size_t global, size_t local)
{
    if (global == 0)
        return 0;
    size_t rounded = local ? (global + local - 1) / local * local : global;
    cl_int err = clEnqueueNDRangeKernel(d->queue, kernel, 1, NULL, &rounded, local ? &local : NULL,
                                        0, NULL, NULL);
    if (err == CL_SUCCESS)
        err = clFinish(d->queue);
    if (err != CL_SUCCESS)
        return error_set(IDMR_EXIT_FAILURE, "running kernel %s (%zu work-items) failed: %s",
                         kernel_name, global, device_error_string(err));
    return 0;
}
