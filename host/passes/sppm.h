/* sppm.h — the one stochastic progressive photon mapping core under both passes: the importance
 * pass (passes/importance.h, paper 3.2–4.1) and the renderer (passes/render.h).
 *
 * The core owns everything the two share: the scene's upload (device/device_scene.h), the
 * program (kernels/sppm.cl built for the pass and the scene's features), the hit points of one
 * camera path per pixel, the photon slots (IDMR_PATH_VERTICES records per path, of the pass's
 * record type), the hash grid over the hit points (passes/hit_point_grid.h), the per-iteration
 * parameters, the radius schedule, the iteration loop with its stop rules, progress, timings
 * and snapshots. A pass plugs in through an sppm_pass: its build defines, its record size, and
 * hooks for what only it does — its own buffers and kernels, its gather after the grid is
 * built, reading its accumulators back, its snapshot, and work after the last iteration.
 *
 * One iteration: camera_paths → photon_paths → grid → pass->gather → pass->collect.
 *
 * Gather radius: what the camera sees sets it, not the scene's extent. r_1 is 2.5 pixel
 * footprints at the median distance of the first iteration's hit points from the camera
 * (distance × the angle a pixel of the hit-point image spans, 2 tan(fov_x / 2) / width), so a
 * close-up of a large scene gathers over a few pixels, not over a tenth of the image; a camera
 * that sees nothing falls back to 5 × |scene box diagonal| / width. options.radius > 0 sets r_1
 * instead (renders to be compared with each other take one radius, so a different geometry or
 * seed cannot change their bias). Then
 * r_{n+1}² = r_n² (n + α) / (n + 1): one global radius per iteration, so that every iteration
 * is an independent estimate at its own radius (Knaus and Zwicker's probabilistic formulation
 * of progressive photon mapping). Both passes use it.
 *
 * Stops: after options.iterations, after the iteration in which options.time_limit seconds pass
 * (when > 0), or when the pass's collect hook says so.
 *
 * Several devices (sppm_run_devices): each gets a core of its own (upload, program, buffers).
 * Every device traces all camera paths (about 5 % of an iteration; every device's gather needs
 * all hit points, and the camera streams are keyed by pixel, so devices that compute alike
 * find the same hit points), but only the first device's camera paths add what the pass
 * records (idmr_sppm_params.camera_sums; the importance pass also casts its shadow rays there
 * alone). The photon paths of an iteration are split into contiguous ranges, one per device:
 * device k traces paths [first_k, first_k + count_k), path p drawing from the stream keyed
 * by p wherever it runs, gathers them against its own grid and walks them back. The collect
 * hook gets every device's core and adds their integer sums before converting them, so the
 * result is the one device's bit for bit, whatever the split. The split starts by the
 * options' weights (default: compute units) and, unless fixed, follows each device's measured
 * photon pass seconds per path after iterations 1 to SPPM_REBALANCE_ITERATIONS. A device's
 * slots hold SPPM_SHARE_HEADROOM times its first share (at most all paths), and its memory is
 * checked on its own: the whole scene plus those slots. The first device's radius rules (it
 * decides it from its hit points); one host thread per device drives the devices at once,
 * meeting after the paths (radius) and after the gathers (collect). */
#ifndef IDMR_SPPM_H
#define IDMR_SPPM_H

#include <stddef.h>
#include <stdint.h>

#include "core/scene.h"
#include "device/bvh.h"
#include "device/device.h"
#include "device/device_scene.h"
#include "idmr/sppm_layout.h"
#include "passes/hit_point_grid.h"

typedef struct sppm_options {
    unsigned int iterations; /* at most this many */
    unsigned int photons;    /* photon paths per iteration; 0: sppm_default_photons() */
    unsigned int seed;       /* default 1 */
    float alpha;             /* radius reduction α of the SPPM schedule (default 0.7) */
    float resolution;        /* scale of the scene's film for the hit-point image (default 1) */
    unsigned int max_depth;  /* camera path: surface interactions at most (default
                                IDMR_CAMERA_DEPTH; the renderer's IDMR_RENDER_DEPTH) */
    double radius;           /* first gather radius; 0: from what the camera sees (below) */
    double time_limit;       /* seconds; > 0 stops after the iteration in which they pass */
    size_t local_size;       /* work-group size; 0 lets the runtime choose */
    uint64_t device_budget;  /* device bytes the run may allocate (sppm_memory_of); 0: the
                                device's global memory is the only limit */
    bvh *release_bvh;        /* NULL, or the BVH the run is given: its host arrays are freed
                                (bvh_free) once uploaded, so that on a device sharing the
                                host's memory they do not sit beside the device's copy */
    int generic;             /* build the all-features program instead of the scene's */
    const double *split;     /* several devices: the first split of the photon paths, one
                                weight > 0 per device (NULL: by compute units) */
    int fixed_split;         /* keep the first split (no rebalancing; for tests) */
    int progress;            /* report progress on stderr */
} sppm_options;

/* Defaults, with `iterations` as the iteration count (each pass has its own). */
void sppm_options_default(sppm_options *o, unsigned int iterations);

/* Photon paths per iteration when none are asked for: 1,000,000 on a GPU (the paper's
 * figure); 500,000 on a CPU, which keeps an iteration of the DRAGON CORNELL BOX (871k
 * triangles) near 0.68 s on 2 cores with PoCL (make bench). */
unsigned int sppm_default_photons(const device *d);

/* The build options of kernels/sppm.cl for `pass` (IDMR_SPPM_IMPORTANCE or IDMR_SPPM_RENDER)
 * on a scene with feature bits `features`, plus the pass's own defines (may be NULL): the one
 * place they are made, for the runs and for `idmr kernels`. Malloc'd. */
char *sppm_build_options(const device *d, unsigned int features, int pass,
                         const char *pass_defines);

/* The feature bits a pass's program is built for on scene s: the scene's materials and lights
 * (every kind with o->generic) and its IDMR_FEATURE_INSTANCES bit. */
unsigned int sppm_program_features(const scene *s, const sppm_options *o);

/* r_1² (above) from the `count` hit points of the first iteration, for a hit-point image
 * `width` pixels wide (a tiny positive value when nothing has extent), and r_{n+1}² from r_n²
 * after iteration n (counted from 0). */
double sppm_initial_radius2(const scene *s, unsigned int width, const idmr_hit_point *hit_points,
                            size_t count);
double sppm_next_radius2(double radius2, unsigned int n, float alpha);

/* Devices one run takes at most; iterations after which the split follows the measured speeds;
 * a device's photon slots against its first share. */
#define SPPM_MAX_DEVICES 16
#define SPPM_REBALANCE_ITERATIONS 3
#define SPPM_SHARE_HEADROOM 1.5

typedef struct sppm_seconds {
    double build;                                 /* kernel build (or program cache load) */
    double camera, photon, grid, gather, collect; /* summed over iterations */
    double total;                                 /* all iterations, build excluded */
} sppm_seconds;

/* One device of a run: what it took of the photon paths. */
typedef struct sppm_device_share {
    int index;                /* its number (`idmr devices`) */
    char name[128];
    unsigned int capacity;    /* photon paths its slots hold */
    unsigned int last_paths;  /* photon paths it traced in the last iteration */
    uint64_t paths;           /* photon paths it traced, all iterations */
    double photon_seconds;    /* its photon passes, summed */
    uint64_t bytes;           /* its device memory: geometry, BVH and buffers */
} sppm_device_share;

/* What a run of the core did, for the passes' results and reports. With several devices the
 * bytes are the first device's (each device's are in device[]), each stage's seconds the most
 * any device spent in it, and the build seconds those of all devices' builds (made in turn). */
typedef struct sppm_summary {
    unsigned int width, height; /* hit-point image */
    unsigned int photons;       /* photon paths per iteration */
    unsigned int iterations;    /* run */
    double *radius;             /* gather radius per iteration run */
    uint64_t hit_points;        /* valid hit points, first iteration */
    uint64_t photon_records;    /* photon records stored, first iteration */
    uint64_t geometry_bytes;    /* device memory: the scene's geometry buffers */
    uint64_t bvh_bytes;         /*                the BVH */
    uint64_t buffer_bytes;      /*                the core's and the pass's buffers */
    char *build_options;
    sppm_seconds seconds;
    unsigned int devices;       /* devices the run used */
    sppm_device_share device[SPPM_MAX_DEVICES];
} sppm_summary;

void sppm_summary_free(sppm_summary *summary);

/* Copies of the core's buffers after the last iteration run (for tests and debugging). */
typedef struct sppm_snapshot {
    idmr_sppm_params params;
    idmr_hit_point *hit_points; /* params.width * params.height */
    /* the pass's records by slot: path p's record j at p * IDMR_PATH_VERTICES + j for
     * j < path_length[p], zero past it (copied out of the device's list) */
    void *photon_records;
    uint32_t *path_length;   /* params.path_count */
    uint32_t *record_index;  /* the device's: path p's record j at list place
                                record_index[p * IDMR_PATH_VERTICES + j] */
    size_t stored;           /* records in the device's list */
} sppm_snapshot;

void sppm_snapshot_free(sppm_snapshot *snapshot);

/* A copy, in slot order (as photon_records above), of `list`: one element of `bytes` per record
 * of the device's list, in the list's order (the records themselves, or what a kernel wrote per
 * record). Slots without a record are zero. */
void *sppm_snapshot_by_slot(const sppm_snapshot *snapshot, const void *list, size_t bytes);

/* The core while it runs; the pass's hooks read it and add their kernels' work. */
typedef struct sppm {
    device *dev;
    unsigned int index;     /* its place among the run's devices: 0 is the first, whose camera
                               paths (and the pass's camera-side work) count */
    const scene *scene;
    const sppm_options *options;
    device_scene uploaded;
    cl_program program;
    cl_kernel camera_paths, photon_paths;
    /* photon_records: the records of all photon paths, one after the other (kernels/sppm.cl,
     * photon_paths), stored_count of them, the gathers' list; record_index: where each path's
     * records sit in it (idmr/sppm_layout.h) */
    cl_mem hit_points, path_length, photon_records, stored_count, record_index;
    size_t stored;                  /* the list's length this iteration, read back */
    hit_point_grid grid;
    unsigned int pixels;
    size_t slots;                   /* photon records at most: capacity × IDMR_PATH_VERTICES */
    unsigned int capacity;          /* photon paths the slots hold (all of them on one device) */
    unsigned int rank_first, rank_paths; /* this MPI rank's photon paths (all in one process) */
    double radius2;                 /* this iteration's gather radius², for the grid */
    uint64_t buffer_bytes;          /* the core's and the pass's buffers on this device */
    sppm_seconds seconds;           /* this device's stages, summed */
    double photon_pass_seconds;     /* the last iteration's photon pass (for the split) */
    unsigned int camera_pass_argument; /* camera_paths' first argument after the core's */
    unsigned int photon_pass_argument; /* photon_paths' first argument after the core's */
    idmr_sppm_params params; /* this iteration's (path_first, device_paths: this device's) */
    sppm_summary *summary;
} sppm;

/* A pass on the core. Hooks return 0, or -1 with the error set. */
typedef struct sppm_pass {
    const char *name;            /* "importance", "render": the progress label */
    int pass;                    /* IDMR_SPPM_IMPORTANCE or IDMR_SPPM_RENDER */
    const char *defines;         /* more build options (-D ...), or NULL */
    int ranks;                   /* under mpirun: the collect hook adds its sums over the ranks
                                    (core/ranks.h), so the photon paths are split over them */
    size_t photon_record_bytes;  /* one record of the photon slots */
    void *state;                 /* the pass's own data, handed to every hook */
    /* The bytes of the pass's own device buffers (prepare's and finish's) on scene s with a
     * hit-point image of `pixels` and `slots` photon slots, from the sizes its hooks allocate
     * (NULL: none). */
    uint64_t (*pass_bytes)(const scene *s, unsigned int pixels, size_t slots);
    /* Once the program is built and the core's buffers exist, on each device's core in turn:
     * creates the pass's kernels and buffers (adding their bytes to core->buffer_bytes), binds
     * camera_paths' records (argument core->camera_pass_argument) and any arguments of its own
     * that photon_paths takes (from core->photon_pass_argument), and may set constant params. */
    int (*prepare)(sppm *core, void *state);
    /* Every iteration, once the grid is built: the pass's gather kernels, on every device's
     * core at once (one host thread each: touch only what belongs to core->index). */
    int (*gather)(sppm *core, void *state);
    /* Every iteration, with the `count` devices' cores: reads the pass's accumulators back,
     * adds them up (as integers, before any conversion) and clears them; iteration n (from 0)
     * has just finished. Sets *stop to end the run early, and may write a progress detail. */
    int (*collect)(sppm *cores, unsigned int count, void *state, unsigned int n, int *stop,
                   char *detail, size_t detail_size);
    /* When a snapshot is asked for: copies the pass's buffers of the iteration (may be NULL). */
    int (*snapshot)(sppm *core, void *state);
    /* After the last iteration, on the first device's core, before the cores are released (may
     * be NULL); adds the bytes of any buffer it allocates to core->buffer_bytes. */
    int (*finish)(sppm *core, void *state);
    /* Releases what prepare created; always called, once (also when a run fails before
     * prepare: the state is then as the pass made it). */
    void (*release)(void *state);
} sppm_pass;

/* The device memory of a run, by part, as sppm_run() allocates it: the scene's geometry
 * buffers (device_scene_geometry_bytes), its BVH, the core's buffers (the hit-point grid, hit
 * points, photon path lengths and slots) and the pass's own (sppm_pass.pass_bytes); a buffer
 * that is freed within the run counts for the whole run. */
typedef struct sppm_memory {
    uint64_t geometry, bvh, core, pass;
} sppm_memory;

/* What a run of `pass` with options o on scene s, with a BVH of bvh_bytes on the device
 * (bvh_device_bytes), allocates: the one function the run's allocations and every budget use
 * (sppm_run() fails if they ever disagree). 0, or -1 with the error set (options or scene the
 * run would refuse). */
int sppm_memory_of(const device *d, const scene *s, uint64_t bvh_bytes, const sppm_options *o,
                   const sppm_pass *pass, sppm_memory *m);
uint64_t sppm_memory_total(const sppm_memory *m);

/* Runs `pass` on scene `s` (which needs a camera and a light) with BVH `b`: validates the
 * options, checks its device memory (sppm_memory_of) against options.device_budget and the
 * device's global memory before allocating anything, uploads, builds, iterates, and releases
 * everything. `summary` is filled (free it
 * with sppm_summary_free() either way); `snapshot` (may be NULL) receives the last iteration's
 * core buffers. Returns 0, or -1 with the error set. */
int sppm_run(device *d, const scene *s, const bvh *b, const sppm_options *o, sppm_pass *pass,
             sppm_summary *summary, sppm_snapshot *snapshot);

/* sppm_run() on the `count` devices of `devices` at once (above; at most SPPM_MAX_DEVICES):
 * each device's memory is checked on its own, errors name the device. A snapshot is taken
 * on one device only (refused with several). */
int sppm_run_devices(device *devices, unsigned int count, const scene *s, const bvh *b,
                     const sppm_options *o, sppm_pass *pass, sppm_summary *summary,
                     sppm_snapshot *snapshot);

/* Splits `total` photon paths over `count` devices in proportion to `weight` (each > 0), none
 * above its `capacity` (Σ capacity >= total), into counts[]; whole paths, deterministic. */
void sppm_split_paths(unsigned int total, unsigned int count, const double *weight,
                      const unsigned int *capacity, unsigned int *counts);

#endif
