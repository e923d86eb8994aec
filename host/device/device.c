/* device.c — OpenCL discovery, program build and buffers (see device.h). */
#include "device/device.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/error.h"
#include "core/files.h"

#ifndef IDMR_ROOT
#define IDMR_ROOT "."
#endif

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

const char *device_source_root(void)
{
    const char *env = getenv("IDMR_ROOT");
    return env && *env ? env : IDMR_ROOT;
}

char *device_build_options(const device *d, unsigned int features, const char *extra)
{
    const char *root = device_source_root();
    size_t size = 2 * strlen(root) + (extra ? strlen(extra) : 0) + 256;
    char *options = xmalloc(size);
    snprintf(options, size,
             "-cl-std=CL1.2 -I %s/kernels -I %s/include -D IDMR_FEATURES=0x%xu "
             "-D IDMR_INT64_ATOMICS=%d%s%s",
             root, root, features, d->info.int64_atomics, extra ? " " : "", extra ? extra : "");
    return options;
}

static char *read_text_file(const char *path, size_t *length)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = xmalloc((size_t)size + 1);
    size_t got = fread(text, 1, (size_t)size, f);
    fclose(f);
    text[got] = '\0';
    *length = got;
    return text;
}

/* ---- program cache ---- */

static _Thread_local int last_build_cached;

int device_last_build_cached(void) { return last_build_cached; }

static uint64_t fnv1a(uint64_t hash, const void *bytes, size_t size)
{
    const unsigned char *p = bytes;
    for (size_t i = 0; i < size; i++) {
        hash ^= p[i];
        hash *= 1099511628211ull;
    }
    return hash;
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Hashes the names and contents of the files under `dir` (sub-directories included), in name
 * order. */
static uint64_t hash_directory(uint64_t hash, const char *dir)
{
    DIR *handle = opendir(dir);
    if (!handle)
        return fnv1a(hash, dir, strlen(dir));
    char **names = NULL;
    size_t count = 0;
    struct dirent *entry;
    while ((entry = readdir(handle))) {
        if (entry->d_name[0] == '.')
            continue;
        names = xrealloc(names, (count + 1) * sizeof *names);
        names[count++] = xstrdup(entry->d_name);
    }
    closedir(handle);
    qsort(names, count, sizeof *names, compare_names);
    for (size_t i = 0; i < count; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        hash = fnv1a(hash, names[i], strlen(names[i]) + 1);
        struct stat info;
        if (stat(path, &info) == 0 && S_ISDIR(info.st_mode)) {
            hash = hash_directory(hash, path);
            free(names[i]);
            continue;
        }
        size_t length;
        char *text = read_text_file(path, &length);
        if (text)
            hash = fnv1a(hash, text, length);
        free(text);
        free(names[i]);
    }
    free(names);
    return hash;
}

uint64_t device_program_key(const device *d, const char *file, const char *options)
{
    char version[256] = "", driver[256] = "";
    clGetPlatformInfo(d->info.platform, CL_PLATFORM_VERSION, sizeof version - 1, version, NULL);
    clGetDeviceInfo(d->info.id, CL_DRIVER_VERSION, sizeof driver - 1, driver, NULL);
    uint64_t hash = 14695981039346656037ull;
    const char *parts[] = {d->info.name, version, driver, file, options};
    for (size_t i = 0; i < sizeof parts / sizeof *parts; i++)
        hash = fnv1a(hash, parts[i], strlen(parts[i]) + 1);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/kernels", device_source_root());
    hash = hash_directory(hash, dir);
    snprintf(dir, sizeof dir, "%s/include/idmr", device_source_root());
    return hash_directory(hash, dir);
}

/* The cache directory (created), or NULL when the cache is off or unusable. */
static const char *cache_directory(char *out, size_t size)
{
    const char *env = getenv("IDMR_CACHE_DIR");
    if (env && strcmp(env, "off") == 0)
        return NULL;
    if (env && *env)
        snprintf(out, size, "%s", env);
    else if (getenv("XDG_CACHE_HOME") && *getenv("XDG_CACHE_HOME"))
        snprintf(out, size, "%s/idmr", getenv("XDG_CACHE_HOME"));
    else if (getenv("HOME") && *getenv("HOME"))
        snprintf(out, size, "%s/.cache/idmr", getenv("HOME"));
    else
        return NULL;
    char partial[4096];
    snprintf(partial, sizeof partial, "%s", out);
    for (char *c = partial + 1; *c; c++)
        if (*c == '/') {
            *c = '\0';
            mkdir(partial, 0777);
            *c = '/';
        }
    if (mkdir(partial, 0777) != 0 && errno != EEXIST) {
        log_verbose("program cache %s unusable: %s", out, strerror(errno));
        return NULL;
    }
    return out;
}

static cl_program load_cached(device *d, const char *path, const char *options)
{
    size_t size;
    unsigned char *binary = (unsigned char *)read_text_file(path, &size);
    if (!binary)
        return NULL;
    cl_int status, err;
    const unsigned char *binaries[] = {binary};
    cl_program program =
        clCreateProgramWithBinary(d->context, 1, &d->info.id, &size, binaries, &status, &err);
    free(binary);
    if (err != CL_SUCCESS || status != CL_SUCCESS) {
        if (program)
            clReleaseProgram(program);
        return NULL;
    }
    if (clBuildProgram(program, 1, &d->info.id, options, NULL, NULL) != CL_SUCCESS) {
        clReleaseProgram(program);
        return NULL;
    }
    return program;
}

static void store_cached(cl_program program, const char *path)
{
    size_t size = 0;
    if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, NULL) !=
            CL_SUCCESS ||
        size == 0)
        return;
    unsigned char *binary = xmalloc(size);
    unsigned char *binaries[] = {binary};
    if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof binaries, binaries, NULL) ==
            CL_SUCCESS &&
        files_write_atomic(path, binary, size) != 0)
        log_verbose("program cache: %s", error_message());
    free(binary);
}

int device_build_program(device *d, const char *file, const char *options, cl_program *program)
{
    *program = NULL;
    last_build_cached = 0;
    char path[4096], cache[4096], cached_path[4096 + 64];
    snprintf(path, sizeof path, "%s/kernels/%s", device_source_root(), file);
    const char *dir = cache_directory(cache, sizeof cache);
    uint64_t key = 0;
    if (dir) {
        key = device_program_key(d, file, options);
        snprintf(cached_path, sizeof cached_path, "%s/%016llx.bin", dir, (unsigned long long)key);
        cl_program cached = load_cached(d, cached_path, options);
        if (cached) {
            log_verbose("%s: program %016llx from the cache (options: %s)", path,
                        (unsigned long long)key, options);
            *program = cached;
            last_build_cached = 1;
            return 0;
        }
    }
    size_t length;
    char *source = read_text_file(path, &length);
    if (!source)
        return error_set(IDMR_EXIT_FAILURE,
                         "cannot read kernel source '%s' (set IDMR_ROOT to the directory that "
                         "holds kernels/ and include/)",
                         path);
    log_verbose("building %s with options: %s", path, options);
    cl_int err;
    const char *sources[] = {source};
    cl_program built = clCreateProgramWithSource(d->context, 1, sources, &length, &err);
    free(source);
    if (device_check(err, "clCreateProgramWithSource"))
        return -1;
    err = clBuildProgram(built, 1, &d->info.id, options, NULL, NULL);
    if (err != CL_SUCCESS) {
        size_t log_size = 0;
        clGetProgramBuildInfo(built, d->info.id, CL_PROGRAM_BUILD_LOG, 0, NULL, &log_size);
        char *log = xcalloc(1, log_size + 1);
        clGetProgramBuildInfo(built, d->info.id, CL_PROGRAM_BUILD_LOG, log_size, log, NULL);
        error_set(IDMR_EXIT_FAILURE, "building kernel %s failed (%s)\noptions: %s\nbuild log:\n%s",
                  path, device_error_string(err), options, log);
        free(log);
        clReleaseProgram(built);
        return -1;
    }
    if (dir)
        store_cached(built, cached_path);
    *program = built;
    return 0;
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
