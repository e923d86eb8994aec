/* importance_file.c — an importance pass saved and read back (see importance_file.h). */
#include "passes/importance_file.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"
#include "core/hash.h"
#include "core/files.h"

static const char MAGIC[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '5'};
/* Version 4 had no copy totals: read for a scene without instances (it lacks nothing there),
 * refused for one with them. */
static const char MAGIC_VERSION_4[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '4'};
/* Version 1's light sums left out the light seen through specular surfaces (importance.h). */
static const char MAGIC_VERSION_1[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '1'};
/* Version 2's weighted it IMPORTANCE_SEEN_LIGHT_WEIGHT times less. */
static const char MAGIC_VERSION_2[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '2'};
/* Version 3 had no checksum: a damaged file could pass for a good one. */
static const char MAGIC_VERSION_3[8] = {'I', 'D', 'M', 'R', 'S', 'I', 'M', '3'};
enum { KIND_CAMERA = 1, KIND_SHADOW = 2 };

/* The fixed-size part after the magic; version 4's ends before `meshes` (0 for it). */
typedef struct simulation_header {
    uint64_t fingerprint, triangles;
    uint32_t iterations, photons, width, height, kinds, seed;
    uint64_t hit_points, photon_records, gathered;
    double seen_light;
    uint64_t meshes; /* the copy totals' length: the scene's meshes */
} simulation_header;

#define HEADER_VERSION_4 offsetof(simulation_header, meshes)

int importance_file_fingerprint(const scene *s, uint64_t *fingerprint)
{
    uint64_t hash = HASH_FNV1A_START;
    for (size_t m = 0; m < s->mesh_count; m++) {
        const scene_mesh *mesh = &s->meshes[m];
        if (scene_mesh_is_later_copy(s, m)) { /* no geometry of its own: where it is placed */
            hash = hash_fnv1a(hash, mesh->instance_to_world, sizeof mesh->instance_to_world);
            continue;
        }
        hash = hash_fnv1a(hash, mesh->positions, 3 * sizeof(float) * mesh->vertex_count);
        hash = hash_fnv1a(hash, mesh->indices, 3 * sizeof(uint32_t) * mesh->triangle_count);
    }
    FILE *f = fopen(s->file, "rb");
    if (!f)
        return error_set(IDMR_EXIT_INPUT, "cannot read '%s': %s", s->file, strerror(errno));
    unsigned char block[65536];
    size_t got;
    while ((got = fread(block, 1, sizeof block, f)) > 0)
        hash = hash_fnv1a(hash, block, got);
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

static size_t copies_bytes(const simulation_header *h)
{
    return 3 * sizeof(double) * h->meshes;
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
                           .seen_light = r->seen_light,
                           .meshes = s->mesh_count};
    if (r->mesh_count != s->mesh_count)
        return error_set(IDMR_EXIT_FAILURE,
                         "simulation: the pass has copy totals of %zu meshes, the scene %zu",
                         r->mesh_count, s->mesh_count);
    if (importance_file_fingerprint(s, &h.fingerprint))
        return -1;
    size_t body = sizeof MAGIC + sizeof h + series_bytes(&h) + sums_bytes(&h) +
                  copies_bytes(&h) + pixels_bytes(&h);
    size_t size = body + sizeof(uint64_t);
    unsigned char *bytes = xmalloc(size), *at = bytes;
    size_t per_series = sizeof(double) * h.iterations, per_kind = sizeof(double) * h.triangles;
    size_t per_copies = sizeof(double) * h.meshes;
    memcpy(at, MAGIC, sizeof MAGIC), at += sizeof MAGIC;
    memcpy(at, &h, sizeof h), at += sizeof h;
    memcpy(at, r->sppm.radius, per_series), at += per_series;
    memcpy(at, r->convergence, per_series), at += per_series;
    memcpy(at, r->camera, per_kind), at += per_kind;
    memcpy(at, r->light, per_kind), at += per_kind;
    memcpy(at, r->shadow, per_kind), at += per_kind;
    memcpy(at, r->copy_camera, per_copies), at += per_copies;
    memcpy(at, r->copy_light, per_copies), at += per_copies;
    memcpy(at, r->copy_shadow, per_copies), at += per_copies;
    memcpy(at, r->pixel_triangle, pixels_bytes(&h)), at += pixels_bytes(&h);
    uint64_t checksum = hash_fnv1a(HASH_FNV1A_START, bytes, body);
    memcpy(at, &checksum, sizeof checksum);
    int status = files_write_atomic(path, bytes, size);
    free(bytes);
    return status;
}

/* A file that does not start with MAGIC (`magic`: its first 8 bytes, NULL where it is shorter):
 * one of an older version, each with what it lacked, or no simulation file. */
static int refuse_other_file(const char *path, const unsigned char *magic)
{
    static const struct {
        const char *magic, *lacked;
    } older[] = {
        {MAGIC_VERSION_1, "whose light importance left out the light seen through glass and "
                          "mirrors"},
        {MAGIC_VERSION_2, "whose light importance weighted the light seen through glass and "
                          "mirrors %g times less"},
        {MAGIC_VERSION_3, "without the checksum that proves a simulation file undamaged"},
    };
    for (size_t i = 0; magic && i < sizeof older / sizeof *older; i++) {
        if (memcmp(magic, older[i].magic, sizeof MAGIC))
            continue;
        char lacked[160];
        snprintf(lacked, sizeof lacked, older[i].lacked, IMPORTANCE_SEEN_LIGHT_WEIGHT);
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was written by an older idmr, %s; run `idmr "
                         "importance SCENE -o DIR` again and pass DIR/simulation.bin",
                         path, lacked);
    }
    return error_set(IDMR_EXIT_INPUT,
                     "--simulation: '%s' is not a simulation file of idmr (the "
                     "simulation.bin that `idmr importance` writes)",
                     path);
}

/* What a file that is not a regular one is, for the message. */
static const char *file_kind(mode_t mode)
{
    return S_ISDIR(mode)    ? "a directory"
           : S_ISFIFO(mode) ? "a FIFO (named pipe)"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISSOCK(mode) ? "a socket"
                            : "not a regular file";
}

/* The file's size that the header promises (magic, a header of header_bytes, arrays,
 * checksum), or 0 where it overflows. */
static uint64_t promised_size(const simulation_header *h, size_t header_bytes)
{
    uint64_t pixels = (uint64_t)h->width * h->height;
    if (h->triangles > (UINT64_MAX >> 8) || pixels > (UINT64_MAX >> 8) ||
        h->meshes > (UINT64_MAX >> 8))
        return 0;
    uint64_t size = sizeof MAGIC + header_bytes + 2 * sizeof(double) * (uint64_t)h->iterations +
                    3 * sizeof(double) * h->triangles + 3 * sizeof(double) * h->meshes +
                    sizeof(uint32_t) * pixels + sizeof(uint64_t);
    return size > SIZE_MAX ? 0 : size;
}

/* Reads exactly `size` bytes at the file position; 0, or -1 with errno set (0: the file ended
 * first). */
static int read_exactly(int fd, void *bytes, size_t size)
{
    unsigned char *at = bytes;
    while (size > 0) {
        ssize_t got = read(fd, at, size);
        if (got < 0 && errno == EINTR)
            continue;
        if (got == 0)
            errno = 0;
        if (got <= 0)
            return -1;
        at += got;
        size -= (size_t)got;
    }
    return 0;
}

/* The error of a failed read_exactly(). */
static int read_failure(const char *path)
{
    return error_set(IDMR_EXIT_INPUT, "--simulation: cannot read '%s': %s", path,
                     errno ? strerror(errno) : "it ended before its size (changed while read?)");
}

/* The whole file into memory (*size bytes) and its header into *h, checked before it is read: a
 * regular file (a device such as /dev/zero would be read without end, a FIFO would block), a
 * simulation file of this version or version 4 (*header_bytes: its header's size) whose header
 * promises the file's size, whose checksum holds. NULL with the error set. */
static unsigned char *read_checked(const char *path, size_t *size, simulation_header *h,
                                   size_t *header_bytes)
{
    /* O_NONBLOCK: opening a FIFO does not wait for a writer; fstat() then refuses it. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        error_set(IDMR_EXIT_INPUT, "--simulation: cannot read '%s': %s", path, strerror(errno));
        return NULL;
    }
    struct stat info;
    if (fstat(fd, &info) != 0) {
        error_set(IDMR_EXIT_INPUT, "--simulation: cannot read '%s': %s", path, strerror(errno));
        close(fd);
        return NULL;
    }
    if (!S_ISREG(info.st_mode)) {
        error_set(IDMR_EXIT_INPUT,
                  "--simulation: '%s' is %s; give the simulation.bin that `idmr importance` "
                  "writes",
                  path, file_kind(info.st_mode));
        close(fd);
        return NULL;
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    unsigned char head[sizeof MAGIC + sizeof(simulation_header)];
    size_t have = (uint64_t)info.st_size < sizeof head ? (size_t)info.st_size : sizeof head;
    int status = read_exactly(fd, head, have) ? read_failure(path) : 0;
    int version_4 =
        !status && have >= sizeof MAGIC && !memcmp(head, MAGIC_VERSION_4, sizeof MAGIC);
    if (!status && !version_4 && (have < sizeof MAGIC || memcmp(head, MAGIC, sizeof MAGIC)))
        status = refuse_other_file(path, have < sizeof MAGIC ? NULL : head);
    *header_bytes = version_4 ? HEADER_VERSION_4 : sizeof *h;
    size_t head_bytes = sizeof MAGIC + *header_bytes;
    if (!status && have < head_bytes)
        status = error_set(IDMR_EXIT_INPUT,
                           "--simulation: '%s' is %zu bytes, shorter than the header of a "
                           "simulation file (truncated)",
                           path, have);
    uint64_t promised = 0;
    if (!status) {
        memset(h, 0, sizeof *h);
        memcpy(h, head + sizeof MAGIC, *header_bytes);
        promised = promised_size(h, *header_bytes);
        if (promised == 0)
            status = error_set(IDMR_EXIT_INPUT,
                               "--simulation: '%s': its header's counts (%llu triangles, %llu "
                               "meshes, a %ux%u image) describe a file larger than any "
                               "(damaged)",
                               path, (unsigned long long)h->triangles,
                               (unsigned long long)h->meshes, h->width, h->height);
        else if (promised != (uint64_t)info.st_size)
            status = error_set(IDMR_EXIT_INPUT,
                               "--simulation: '%s' is %llu bytes, not the %llu its header "
                               "describes (truncated or damaged)",
                               path, (unsigned long long)info.st_size,
                               (unsigned long long)promised);
    }
    unsigned char *bytes = NULL;
    if (!status) {
        /* `have` <= promised: a file holds at least its magic, header and checksum */
        bytes = xmalloc((size_t)promised);
        memcpy(bytes, head, have);
        if (read_exactly(fd, bytes + have, (size_t)promised - have))
            status = read_failure(path);
    }
    if (!status) {
        uint64_t stored,
            computed = hash_fnv1a(HASH_FNV1A_START, bytes, (size_t)promised - sizeof stored);
        memcpy(&stored, bytes + promised - sizeof stored, sizeof stored);
        if (stored != computed)
            status = error_set(IDMR_EXIT_INPUT,
                               "--simulation: '%s' is damaged: its checksum does not match its "
                               "contents; run `idmr importance SCENE -o DIR` again and pass "
                               "DIR/simulation.bin",
                               path);
    }
    close(fd);
    if (status) {
        free(bytes);
        return NULL;
    }
    *size = (size_t)promised;
    return bytes;
}

/* Whether scene s has an instanced shape (whose copies have totals of their own). */
static int has_instances(const scene *s)
{
    for (size_t m = 0; m < s->mesh_count; m++)
        if (s->meshes[m].instanced)
            return 1;
    return 0;
}

/* The header (of a version 4 file where version_4) checked against the scene and the weights,
 * and for values no pass writes. */
static int check_header(const char *path, const simulation_header *h, int version_4,
                        const scene *s, const importance_options *o)
{
    if (h->iterations == 0)
        return error_set(IDMR_EXIT_INPUT, "--simulation: '%s' holds no iteration (damaged)",
                         path);
    if (h->photons == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' has a photon count of 0 per iteration (damaged)",
                         path);
    if (h->width == 0 || h->height == 0)
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' has a hit-point image of %ux%u pixels (damaged)",
                         path, h->width, h->height);
    if (h->kinds & ~(uint32_t)(KIND_CAMERA | KIND_SHADOW))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' has unknown kinds of importance (bits 0x%x; "
                         "damaged)",
                         path, h->kinds);
    if (!(h->seen_light >= 0) || !isfinite(h->seen_light))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' has a seen-light sum of %g (damaged)", path,
                         h->seen_light);
    uint64_t fingerprint;
    if (importance_file_fingerprint(s, &fingerprint))
        return -1;
    if (h->triangles != (uint64_t)s->triangle_count || h->fingerprint != fingerprint ||
        (!version_4 && h->meshes != (uint64_t)s->mesh_count))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was made from another scene than '%s' (or from "
                         "this one before it changed): run `idmr importance` on it again",
                         path, s->file);
    if (version_4 && has_instances(s))
        return error_set(IDMR_EXIT_INPUT,
                         "--simulation: '%s' was written by an older idmr, without the totals "
                         "of each instance's own importance that '%s' (a scene with instances) "
                         "needs; run `idmr importance SCENE -o DIR` again and pass "
                         "DIR/simulation.bin",
                         path, s->file);
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

/* Every value of the arrays as a pass writes them: radii positive, changes and sums finite and
 * not negative; the first that is not is named, with the file. */
static int check_values(const char *path, const importance_result *r, const scene *s)
{
    for (unsigned int n = 0; n < r->sppm.iterations; n++) {
        if (!(r->sppm.radius[n] > 0) || !isfinite(r->sppm.radius[n]))
            return error_set(IDMR_EXIT_INPUT,
                             "--simulation: '%s': the gather radius of iteration %u is %g "
                             "(damaged)",
                             path, n + 1, r->sppm.radius[n]);
        if (!(r->convergence[n] >= 0) || !isfinite(r->convergence[n]))
            return error_set(IDMR_EXIT_INPUT,
                             "--simulation: '%s': the convergence change of iteration %u is %g "
                             "(damaged)",
                             path, n + 1, r->convergence[n]);
    }
    const struct {
        const char *name;
        const double *sums;
    } kinds[] = {{"camera", r->camera}, {"light", r->light}, {"shadow", r->shadow}};
    for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++)
        for (size_t t = 0; t < r->triangle_count; t++) {
            double sum = kinds[k].sums[t];
            if (sum >= 0 && isfinite(sum))
                continue;
            size_t m = scene_mesh_of_triangle(s, t), first = s->meshes[m].first_triangle;
            return error_set(IDMR_EXIT_INPUT,
                             "--simulation: '%s': the %s importance sum of triangle %zu (mesh "
                             "'%s', its triangle %zu) is %g; it must be finite and >= 0 "
                             "(damaged, or written by a failed pass)",
                             path, kinds[k].name, t, s->meshes[m].name, t - first, sum);
        }
    const double *copies[3] = {r->copy_camera, r->copy_light, r->copy_shadow};
    for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++)
        for (size_t m = 0; m < r->mesh_count; m++) {
            double sum = copies[k][m];
            if (sum >= 0 && isfinite(sum) && (sum == 0 || s->meshes[m].instanced))
                continue;
            return error_set(IDMR_EXIT_INPUT,
                             "--simulation: '%s': the %s importance total of mesh '%s' as a "
                             "copy is %g; it must be finite and >= 0, and 0 for a mesh that is "
                             "not instanced (damaged, or written by a failed pass)",
                             path, kinds[k].name, s->meshes[m].name, sum);
        }
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
    size_t size = 0, header_bytes = 0;
    simulation_header h;
    unsigned char *bytes = read_checked(path, &size, &h, &header_bytes);
    if (!bytes)
        return -1;
    int version_4 = header_bytes != sizeof h;
    int status = check_header(path, &h, version_4, s, o);
    if (!status) {
        const unsigned char *at = bytes + sizeof MAGIC + header_bytes;
        size_t per_series = sizeof(double) * h.iterations, per_kind = sizeof(double) * h.triangles;
        r->triangle_count = (size_t)h.triangles;
        r->sppm.radius = take(&at, per_series);
        r->convergence = take(&at, per_series);
        r->camera = take(&at, per_kind);
        r->light = take(&at, per_kind);
        r->shadow = take(&at, per_kind);
        /* version 4 (a scene without instances, check_header): every copy total is 0 */
        r->mesh_count = s->mesh_count;
        double **copies[3] = {&r->copy_camera, &r->copy_light, &r->copy_shadow};
        for (int k = 0; k < 3; k++)
            *copies[k] = version_4 ? xcalloc(s->mesh_count + 1, sizeof(double))
                                   : take(&at, sizeof(double) * h.meshes);
        r->pixel_triangle = take(&at, pixels_bytes(&h));
        r->sppm.iterations = h.iterations;
        r->sppm.photons = h.photons;
        r->sppm.width = h.width;
        r->sppm.height = h.height;
        r->sppm.hit_points = h.hit_points;
        r->sppm.photon_records = h.photon_records;
        r->gathered = h.gathered;
        r->seen_light = h.seen_light;
        status = check_values(path, r, s);
    }
    free(bytes);
    return status;
}
