/* program.c — kernel programs: build options, building from kernels/, and the program cache
 * (see program.h). */
#include "device/program.h"

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

#define FNV1A_START 14695981039346656037ull

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
    uint64_t hash = FNV1A_START;
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

/* A cache file: this header, then the binary. The binary's size and hash are checked before it
 * is handed to the OpenCL runtime, which does not survive a truncated or damaged binary. */
#define CACHE_MAGIC "IDMRPRG1"
typedef struct cache_header {
    char magic[8];
    uint64_t size;
    uint64_t hash; /* FNV-1a of the binary */
} cache_header;

/* The binary of cache file `path`, or NULL when there is none or it does not check out (a
 * damaged file is warned about; the caller rebuilds and replaces it). */
static unsigned char *read_cached_binary(const char *path, size_t *size)
{
    size_t length;
    unsigned char *file = (unsigned char *)read_text_file(path, &length);
    if (!file)
        return NULL;
    cache_header header;
    if (length < sizeof header || memcmp(file, CACHE_MAGIC, sizeof header.magic) != 0) {
        log_verbose("program cache %s: not a cache file of this version", path);
        free(file);
        return NULL;
    }
    memcpy(&header, file, sizeof header);
    const unsigned char *binary = file + sizeof header;
    if (header.size != length - sizeof header ||
        fnv1a(FNV1A_START, binary, (size_t)header.size) != header.hash) {
        warn("program cache file %s is damaged (its size or checksum does not match its "
             "header); rebuilding it",
             path);
        free(file);
        return NULL;
    }
    memmove(file, binary, (size_t)header.size);
    *size = (size_t)header.size;
    return file;
}

static cl_program load_cached(device *d, const char *path, const char *options)
{
    size_t size;
    unsigned char *binary = read_cached_binary(path, &size);
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
    cache_header header;
    unsigned char *file = xmalloc(sizeof header + size);
    unsigned char *binaries[] = {file + sizeof header};
    if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof binaries, binaries, NULL) !=
        CL_SUCCESS) {
        free(file);
        return;
    }
    memcpy(header.magic, CACHE_MAGIC, sizeof header.magic);
    header.size = size;
    header.hash = fnv1a(FNV1A_START, binaries[0], size);
    memcpy(file, &header, sizeof header);
    if (files_write_atomic(path, file, sizeof header + size) != 0)
        log_verbose("program cache: %s", error_message());
    free(file);
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
