/* importance_file.c — an importance pass saved and read back (see importance_file.h). */
#include "passes/importance_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/files.h"

static const char MAGIC[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '3'};
/* Version 1's light sums left out the light seen through specular surfaces (importance.h). */
static const char MAGIC_VERSION_1[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '1'};
/* Version 2's weighted it IMPORTANCE_SEEN_LIGHT_WEIGHT times less. */
static const char MAGIC_VERSION_2[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '2'};
enum { KIND_CAMERA = 1, KIND_SHADOW = 2 };

/* The fixed-size part after the magic. */
typedef struct simulation_header {
    uint64_t fingerprint, triangles;
    uint32_t iterations, photons, width, height, kinds, seed;
    uint64_t hit_points, photon_records, gathered;
    double seen_light;
} simulation_header;

static uint64_t fnv1a(uint64_t hash, const void *bytes, size_t size)
{
    const unsigned char *b = bytes;
    for (size_t i = 0; i < size; i++)
        hash = (hash ^ b[i]) * 0x100000001b3ull;
    return hash;
}

int importance_file_fingerprint(const scene *s, uint64_t *fingerprint)
{
    uint64_t hash = 0xcbf29ce484222325ull;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        hash = fnv1a(hash, mesh->positions, 3 * sizeof(float) * mesh->vertex_count);
        hash = fnv1a(hash, mesh->indices, 3 * sizeof(uint32_t) * mesh->triangle_count);
    }
    FILE *f = fopen(s->file, "rb");
    if (!f)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s': %s", s->file, strerror(errno));
    unsigned char block[65536];
    size_t got;
    while ((got = fread(block, 1, sizeof block, f)) > 0)
        hash = fnv1a(hash, block, got);
    int failed = ferror(f);
    fclose(f);
    if (failed)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s'", s->file);
    *fingerprint = hash;
    return 0;
}

/* Sizes of the arrays after the header, in bytes. */
static size_t series_bytes(const simulation_header *h)
{
    return 2 * sizeof(double) * h->iterations;
}

static size_t sums_bytes(const simulation_header *h)
{
    return 3 * sizeof(double) * h->triangles;
}

static size_t pixels_bytes(const simulation_header *h)
{
    return sizeof(uint32_t) * (size_t)h->width * h->height;
}

int importance_file_write(const char *path, const scene *s, const importance_options *o,
                          const importance_result *r)
{
    simulation_header h = {.triangles = r->triangle_count,
                           .iterations = r->sppm.iterations,
                           .photons = r->sppm.photons,
                           .width = r->sppm.width,
                           .height = r->sppm.height,
                           .kinds = (o->gamma > 0 ? KIND_CAMERA : 0) |
                                    (o->shadow_weight > 0 ? KIND_SHADOW : 0),
                           .seed = o->sppm.seed,
                           .hit_points = r->sppm.hit_points,
                           .photon_records = r->sppm.photon_records,
                           .gathered = r->gathered,
                           .seen_light = r->seen_light};
    if (importance_file_fingerprint(s, &h.fingerprint))
        return -1;
    size_t size = sizeof MAGIC + sizeof h + series_bytes(&h) + sums_bytes(&h) + pixels_bytes(&h);
    unsigned char *bytes = xmalloc(size), *at = bytes;
    size_t per_series = sizeof(double) * h.iterations, per_kind = sizeof(double) * h.triangles;
    memcpy(at, MAGIC, sizeof MAGIC), at += sizeof MAGIC;
    memcpy(at, &h, sizeof h), at += sizeof h;
    memcpy(at, r->sppm.radius, per_series), at += per_series;
    memcpy(at, r->convergence, per_series), at += per_series;
    memcpy(at, r->camera, per_kind), at += per_kind;
    memcpy(at, r->light, per_kind), at += per_kind;
    memcpy(at, r->shadow, per_kind), at += per_kind;
    memcpy(at, r->pixel_triangle, pixels_bytes(&h));
    int status = files_write_atomic(path, bytes, size);
    free(bytes);
    return status;
}

/* The whole file into memory (*size bytes); NULL with the error set. */
static unsigned char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        error_set(IDMR_EXIT_INPUT, "--simulation: cannot read '%s': %s", path, strerror(errno));
        return NULL;
    }
    size_t capacity = 1 << 20, length = 0, got;
    unsigned char *bytes = xmalloc(capacity);
    while ((got = fread(bytes + length, 1, capacity - length, f)) > 0) {
        length += got;
        if (length == capacity)
            bytes = xrealloc(bytes, capacity *= 2);
    }
    int failed = ferror(f);
    fclose(f);
    if (failed) {
        free(bytes);
        error_set(IDMR_EXIT_INPUT, "--simulation: cannot read '%s'", path);
        return NULL;
    }
    *size = length;
    return bytes;
}

/* The header checked against the file's length, the scene and the weights. */
static int check_header(const char *path, const simulation_header *h, size_t size,
                        const scene *s, const importance_options *o)
{
    uint64_t fingerprint;
    if (importance_file_fingerprint(s, &fingerprint))
        return -1;
    size_t expected = sizeof MAGIC + sizeof *h;
    if (h->triangles > SIZE_MAX / 32 || (uint64_t)h->width * h->height > SIZE_MAX / 8 ||
        (expected += series_bytes(h) + sums_bytes(h) + pixels_bytes(h)) != size)
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' is %zu bytes, not the %zu its header describes "
                         "(truncated or damaged)",
                         path, size, expected);
    if (h->triangles != (uint64_t)s->triangle_count || h->fingerprint != fingerprint)
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was made from another scene than '%s' (or from "
                         "this one before it changed): run `idmr importance` on it again",
                         path, s->file);
    if (h->iterations == 0)
        return error_set(IDMR_EXIT_INPUT, "--simulation: '%s' holds no iteration", path);
    if (!(h->seen_light >= 0) || !isfinite(h->seen_light))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' has a seen-light sum of %g (damaged)", path,
                         h->seen_light);
    if (o->gamma > 0 && !(h->kinds & KIND_CAMERA))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was made with --gamma 0 and holds no camera "
                         "importance to weight by %g",
                         path, o->gamma);
    if (o->shadow_weight > 0 && !(h->kinds & KIND_SHADOW))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was made with --shadow-weight 0 and holds no shadow "
                         "importance to weight by %g",
                         path, o->shadow_weight);
    return 0;
}

/* Copies `size` bytes from *at into a new array, and moves *at past them. */
static void *take(const unsigned char **at, size_t size)
{
    void *out = xmalloc(size ? size : 1);
    memcpy(out, *at, size);
    *at += size;
    return out;
}

int importance_file_read(const char *path, const scene *s, const importance_options *o,
                         importance_result *r)
{
    memset(r, 0, sizeof *r);
    size_t size = 0;
    unsigned char *bytes = read_all(path, &size);
    if (!bytes)
        return -1;
    simulation_header h;
    int status = 0;
    if (size >= sizeof MAGIC && !memcmp(bytes, MAGIC_VERSION_1, sizeof MAGIC))
        status = error_set(IDMR_EXIT_INPUT,
                           "--simulation: '%s' was written by an older idmr, whose light "
                           "importance left out the light seen through glass and mirrors; run "
                           "`idmr importance` again",
                           path);
    else if (size >= sizeof MAGIC && !memcmp(bytes, MAGIC_VERSION_2, sizeof MAGIC))
        status = error_set(IDMR_EXIT_INPUT,
                           "--simulation: '%s' was written by an older idmr, whose light "
                           "importance weighted the light seen through glass and mirrors %g "
                           "times less; run `idmr importance` again",
                           path, IMPORTANCE_SEEN_LIGHT_WEIGHT);
    else if (size < sizeof MAGIC + sizeof h || memcmp(bytes, MAGIC, sizeof MAGIC))
        status = error_set(IDMR_EXIT_INPUT,
                           "--simulation: '%s' is not a simulation file of idmr (the "
                           "simulation.bin that `idmr importance` writes)",
                           path);
    if (!status) {
        memcpy(&h, bytes + sizeof MAGIC, sizeof h);
        status = check_header(path, &h, size, s, o);
    }
    if (!status) {
        const unsigned char *at = bytes + sizeof MAGIC + sizeof h;
        size_t per_series = sizeof(double) * h.iterations, per_kind = sizeof(double) * h.triangles;
        r->triangle_count = (size_t)h.triangles;
        r->sppm.radius = take(&at, per_series);
        r->convergence = take(&at, per_series);
        r->camera = take(&at, per_kind);
        r->light = take(&at, per_kind);
        r->shadow = take(&at, per_kind);
        r->pixel_triangle = take(&at, pixels_bytes(&h));
        r->sppm.iterations = h.iterations;
        r->sppm.photons = h.photons;
        r->sppm.width = h.width;
        r->sppm.height = h.height;
        r->sppm.hit_points = h.hit_points;
        r->sppm.photon_records = h.photon_records;
        r->gathered = h.gathered;
        r->seen_light = h.seen_light;
    }
    free(bytes);
    return status;
}
