/* main.c — the idmr command line: global options, subcommands, exit codes.
 *
 *   idmr [-v] devices [--json]
 *   idmr [-v] info SCENE [--json] [--no-bvh]
 *   idmr [-v] importance SCENE -o DIR [options]
 *   idmr [-v] reduce SCENE --target D -o OUTDIR [options]
 *   idmr [-v] render SCENE -o IMAGE [options]
 *   idmr compare A B [--diff DIFF.png] [--diff-max E] [--json]
 *
 * Exit codes (error.h): 0 success, 1 runtime failure, 2 bad input or usage. Every failure
 * prints one "idmr: ..." message naming the file, element or call that failed. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <errno.h>
#include <math.h>

#include "device/bvh.h"
#include "device/device.h"
#include "device/device_scene.h"
#include "core/error.h"
#include "io/image_compare.h"
#include "passes/importance.h"
#include "passes/importance_outputs.h"
#include "io/mitsuba.h"
#include "reduce/reduce.h"
#include "passes/render.h"
#include "core/files.h"
#include "core/json.h"
#include "core/scene.h"

#define IDMR_VERSION "0.1.0"

static void print_usage(FILE *out)
{
    fputs("usage: idmr [-v] COMMAND [options]\n"
          "\n"
          "Illumination-driven mesh reduction: learn which triangles carry the light a camera\n"
          "sees, then decimate a Mitsuba scene to a vertex budget.\n"
          "\n"
          "commands:\n"
          "  devices [--json]          list OpenCL platforms and devices\n"
          "  info SCENE [--json]       meshes, materials, lights, camera, bounding box, feature\n"
          "                            bits and device memory of a Mitsuba scene\n"
          "      --no-bvh              skip the BVH build (memory then excludes the BVH)\n"
          "  importance SCENE -o DIR   learn which triangles carry the light the camera sees;\n"
          "                            writes DIR/report.json, convergence.csv, importance.png\n"
          "                            and importance/<mesh>.ply\n"
          "      --iterations N        iterations (default 100)\n"
          "      --tolerance E         stop once the change per iteration stays below E\n"
          "      --photons P           photon paths per iteration (default 1,000,000 on a GPU,\n"
          "                            500,000 on a CPU)\n"
          "      --gamma G             weight of camera paths against light paths (default 1)\n"
          "      --alpha A             SPPM radius reduction (default 0.7)\n"
          "      --resolution F        scale of the scene's film for hit points (default 1)\n"
          "      --seed S              random seed (default 1)\n"
          "      --device N            OpenCL device (see `idmr devices`)\n"
          "      --quiet               no progress on stderr\n"
          "      --generic             kernels with every feature, not only the scene's\n"
          "  reduce SCENE --target D -o OUTDIR\n"
          "                            the reduced scene: OUTDIR/scene.xml and meshes/*.ply with\n"
          "                            about D of all vertices; takes the options of importance\n"
          "      --method M            importance (default: the paper's), quadric (uniform D,\n"
          "                            view-independent) or importance-quadric (importance\n"
          "                            budgets per mesh, quadric collapses within each)\n"
          "      --min-vertices N      meshes this small are not decimated (default 16)\n"
          "      --max-normal-angle A  no collapse turns a face more than A degrees (default 60)\n"
          "      --keep NAME           never decimate mesh NAME (repeatable; emitters never are)\n"
          "      --threads N           decimation threads (default: all cores)\n"
          "      --force               write into a non-empty OUTDIR\n"
          "  render SCENE -o IMAGE     stochastic progressive photon mapping: IMAGE.exr (linear),\n"
          "                            IMAGE.png (sRGB) and IMAGE.json (timings, device memory)\n"
          "      --iterations N        iterations (default 64)\n"
          "      --photons P           photon paths per iteration (default as for importance)\n"
          "      --time-limit S        stop after the iteration in which S seconds pass\n"
          "      --alpha A             radius reduction (default 0.7)\n"
          "      --seed S, --resolution F, --device N, --quiet, --generic   as for importance\n"
          "      --exposure EV         PNG brightness: linear values times 2^EV (default 0)\n"
          "  compare A B [--diff D.png] [--json]\n"
          "                            RMSE, PSNR and relative MSE of image A against the\n"
          "                            reference B (linear RGB), and a false-colour error image\n"
          "      --diff-max E          top of the error image's ramp (default: the 99th\n"
          "                            percentile of the error)\n"
          "\n"
          "global options:\n"
          "  -v, --verbose             log progress, kernel build options and timings\n"
          "  -h, --help                this text\n"
          "      --version             print the version\n"
          "\n"
          "environment:\n"
          "  IDMR_DEVICE=N             default OpenCL device (see `idmr devices`)\n"
          "  IDMR_ROOT=DIR             directory holding kernels/ and include/\n"
          "  IDMR_CACHE_DIR=DIR        compiled kernel cache (default ~/.cache/idmr; off: none)\n",
          out);
}

static int fail(void)
{
    fprintf(stderr, "idmr: %s\n", error_message());
    return error_code();
}

static int usage_error(const char *fmt, const char *arg)
{
    fputs("idmr: ", stderr);
    fprintf(stderr, fmt, arg);
    fputs("\n(see `idmr --help`)\n", stderr);
    return IDMR_EXIT_INPUT;
}

/* Strict number parsing for options: the whole argument, finite, in range. */
static int parse_unsigned(const char *option, const char *text, unsigned long min,
                          unsigned long max, unsigned int *out)
{
    char *end;
    errno = 0;
    unsigned long value = strtoul(text, &end, 10);
    if (errno || end == text || *end || text[0] == '-' || value < min || value > max)
        return error_set(IDMR_EXIT_INPUT, "%s: '%s' is not a whole number from %lu to %lu", option,
                         text, min, max);
    *out = (unsigned int)value;
    return 0;
}

static int parse_double(const char *option, const char *text, double min, double max,
                        double *out)
{
    char *end;
    errno = 0;
    double value = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(value) || value < min || value > max)
        return error_set(IDMR_EXIT_INPUT, "%s: '%s' is not a number from %g to %g", option, text,
                         min, max);
    *out = value;
    return 0;
}

/* ---- devices ---- */

static int command_devices(int argc, char **argv)
{
    int json = 0;
    static const struct option options[] = {{"json", no_argument, NULL, 'j'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "", options, NULL)) != -1) {
        if (c == 'j')
            json = 1;
        else
            return usage_error("devices: unknown option %s", argv[optind - 1]);
    }
    device_info *list;
    size_t count;
    if (device_list(&list, &count))
        return fail();
    if (json) {
        cJSON *root = cJSON_CreateArray();
        for (size_t i = 0; i < count; i++) {
            cJSON *d = cJSON_CreateObject();
            cJSON_AddNumberToObject(d, "index", list[i].index);
            cJSON_AddStringToObject(d, "platform", list[i].platform_name);
            cJSON_AddStringToObject(d, "name", list[i].name);
            cJSON_AddStringToObject(d, "kind", list[i].kind);
            cJSON_AddNumberToObject(d, "compute_units", list[i].compute_units);
            cJSON_AddNumberToObject(d, "global_memory", (double)list[i].global_memory);
            cJSON_AddStringToObject(d, "opencl_c_version", list[i].opencl_c_version);
            cJSON_AddBoolToObject(d, "int64_atomics", list[i].int64_atomics);
            cJSON_AddItemToArray(root, d);
        }
        json_print(root);
        cJSON_Delete(root);
    } else {
        printf("%-3s %-20s %-5s %5s %10s  %-22s %s\n", "#", "platform", "kind", "CUs", "memory",
               "OpenCL C", "device");
        for (size_t i = 0; i < count; i++)
            printf("%-3d %-20.20s %-5s %5u %7.1f GiB  %-22.22s %s%s\n", list[i].index,
                   list[i].platform_name, list[i].kind, list[i].compute_units,
                   list[i].global_memory / 1073741824.0, list[i].opencl_c_version, list[i].name,
                   list[i].int64_atomics ? "" : " (no 64-bit atomics)");
        const char *env = getenv("IDMR_DEVICE");
        printf("default: %s\n", env && *env ? "IDMR_DEVICE" : "first GPU, else device 0");
    }
    free(list);
    return 0;
}

/* ---- info ---- */

static cJSON *features_json(unsigned int features)
{
    cJSON *array = cJSON_CreateArray();
    for (unsigned int bit = 0; bit < IDMR_FEATURE_COUNT; bit++)
        if (features & (1u << bit))
            cJSON_AddItemToArray(array, cJSON_CreateString(scene_feature_name(1u << bit)));
    return array;
}

static cJSON *info_json(const scene *s, const bvh *b)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", s->file);
    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *m = &s->meshes[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", m->name);
        cJSON_AddStringToObject(o, "shape", m->shape_type);
        if (m->file)
            cJSON_AddStringToObject(o, "file", m->file);
        cJSON_AddNumberToObject(o, "vertices", m->vertex_count);
        cJSON_AddNumberToObject(o, "triangles", m->triangle_count);
        cJSON_AddStringToObject(o, "material", s->material_info[m->material].name);
        cJSON_AddStringToObject(o, "material_kind",
                                scene_material_kind_name(s->materials[m->material].kind));
        cJSON_AddBoolToObject(o, "emitter", m->light >= 0);
        cJSON_AddItemToArray(meshes, o);
    }
    cJSON *materials = cJSON_AddArrayToObject(root, "materials");
    for (size_t i = 0; i < s->material_count; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "name", s->material_info[i].name);
        cJSON_AddStringToObject(o, "bsdf", s->material_info[i].bsdf_type);
        cJSON_AddStringToObject(o, "kind", scene_material_kind_name(s->materials[i].kind));
        cJSON_AddItemToArray(materials, o);
    }
    cJSON *lights = cJSON_AddArrayToObject(root, "lights");
    for (size_t i = 0; i < s->light_count; i++) {
        const idmr_light *l = &s->lights[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "type", scene_light_kind_name(l->kind));
        json_add_vec3(o, "emission", l->emission);
        cJSON_AddNumberToObject(o, "power", l->power);
        if (l->kind == IDMR_LIGHT_AREA)
            cJSON_AddNumberToObject(o, "area", l->area);
        cJSON_AddItemToArray(lights, o);
    }
    if (s->has_camera) {
        cJSON *cam = cJSON_AddObjectToObject(root, "camera");
        json_add_vec3(cam, "origin", s->camera.origin);
        json_add_vec3(cam, "forward", s->camera.forward);
        json_add_vec3(cam, "up", s->camera.up);
        cJSON_AddNumberToObject(cam, "fov", s->camera_info.fov_degrees);
        cJSON_AddStringToObject(cam, "fov_axis", s->camera_info.fov_axis);
        cJSON_AddNumberToObject(cam, "width", s->camera.width);
        cJSON_AddNumberToObject(cam, "height", s->camera.height);
    }
    cJSON *bbox = cJSON_AddObjectToObject(root, "bbox");
    json_add_vec3(bbox, "min", s->bbox_min);
    json_add_vec3(bbox, "max", s->bbox_max);
    cJSON_AddItemToObject(root, "features", features_json(s->features));
    cJSON_AddNumberToObject(root, "vertices", (double)s->vertex_count);
    cJSON_AddNumberToObject(root, "triangles", (double)s->triangle_count);
    cJSON *memory = cJSON_AddObjectToObject(root, "device_memory");
    cJSON_AddNumberToObject(memory, "geometry", (double)device_scene_geometry_bytes(s));
    if (b) {
        cJSON_AddNumberToObject(memory, "bvh", (double)bvh_device_bytes(b));
        cJSON_AddNumberToObject(memory, "total",
                                (double)(device_scene_geometry_bytes(s) + bvh_device_bytes(b)));
        cJSON *tree = cJSON_AddObjectToObject(root, "bvh");
        cJSON_AddNumberToObject(tree, "nodes", (double)b->node_count);
        cJSON_AddNumberToObject(tree, "leaves", (double)b->leaf_count);
        cJSON_AddNumberToObject(tree, "triangle_references", (double)b->reference_count);
        cJSON_AddNumberToObject(tree, "degenerate_triangles", (double)b->degenerate_count);
        cJSON_AddNumberToObject(tree, "depth", b->depth);
        cJSON_AddNumberToObject(tree, "build_seconds", b->build_seconds);
    }
    return root;
}

static void print_bytes(const char *label, double bytes)
{
    printf("  %-10s %10.2f MiB\n", label, bytes / 1048576.0);
}

static void info_print(const scene *s, const bvh *b)
{
    printf("scene %s\n\n", s->file);
    printf("meshes (%zu): %llu vertices, %llu triangles\n", s->mesh_count,
           (unsigned long long)s->vertex_count, (unsigned long long)s->triangle_count);
    printf("  %-24s %-10s %10s %10s  %-22s %s\n", "name", "shape", "vertices", "triangles",
           "material", "kind");
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *m = &s->meshes[i];
        printf("  %-24.24s %-10.10s %10u %10u  %-22.22s %s%s\n", m->name, m->shape_type,
               m->vertex_count, m->triangle_count, s->material_info[m->material].name,
               scene_material_kind_name(s->materials[m->material].kind),
               m->light >= 0 ? ", emitter" : "");
    }
    printf("\nmaterials (%zu):", s->material_count);
    for (unsigned int kind = 0; kind < IDMR_MATERIAL_KIND_COUNT; kind++) {
        size_t n = 0;
        for (size_t i = 0; i < s->material_count; i++)
            n += s->materials[i].kind == kind;
        if (n)
            printf(" %zu %s", n, scene_material_kind_name(kind));
    }
    printf("\nlights (%zu):", s->light_count);
    for (unsigned int kind = 0; kind < IDMR_LIGHT_KIND_COUNT; kind++) {
        size_t n = 0;
        for (size_t i = 0; i < s->light_count; i++)
            n += s->lights[i].kind == kind;
        if (n)
            printf(" %zu %s", n, scene_light_kind_name(kind));
    }
    printf("\n");
    if (s->has_camera) {
        const idmr_camera *c = &s->camera;
        printf("camera: %ux%u, fov %g (%s), at (%g, %g, %g) looking (%g, %g, %g)\n", c->width,
               c->height, s->camera_info.fov_degrees, s->camera_info.fov_axis, c->origin[0],
               c->origin[1], c->origin[2], c->forward[0], c->forward[1], c->forward[2]);
    } else {
        printf("camera: none\n");
    }
    printf("bbox: (%g, %g, %g) .. (%g, %g, %g)\n", s->bbox_min[0], s->bbox_min[1], s->bbox_min[2],
           s->bbox_max[0], s->bbox_max[1], s->bbox_max[2]);
    printf("features:");
    for (unsigned int bit = 0; bit < IDMR_FEATURE_COUNT; bit++)
        if (s->features & (1u << bit))
            printf(" %s", scene_feature_name(1u << bit));
    printf("\ndevice memory:\n");
    print_bytes("geometry", (double)device_scene_geometry_bytes(s));
    if (b) {
        print_bytes("bvh", (double)bvh_device_bytes(b));
        print_bytes("total", (double)(device_scene_geometry_bytes(s) + bvh_device_bytes(b)));
        printf("bvh: %zu nodes, %zu leaves, %zu triangle references, depth %d, built in %.2f s\n",
               b->node_count, b->leaf_count, b->reference_count, b->depth, b->build_seconds);
    }
}

static int command_info(int argc, char **argv)
{
    int json = 0, build = 1;
    static const struct option options[] = {
        {"json", no_argument, NULL, 'j'}, {"no-bvh", no_argument, NULL, 'n'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "", options, NULL)) != -1) {
        if (c == 'j')
            json = 1;
        else if (c == 'n')
            build = 0;
        else
            return usage_error("info: unknown option %s", argv[optind - 1]);
    }
    if (optind != argc - 1)
        return usage_error("info: expected one SCENE argument%s", "");
    scene *s = mitsuba_load(argv[optind]);
    if (!s)
        return fail();
    bvh b;
    if (build && bvh_build(s, &b)) {
        scene_free(s);
        return fail();
    }
    if (json) {
        cJSON *root = info_json(s, build ? &b : NULL);
        json_print(root);
        cJSON_Delete(root);
    } else {
        info_print(s, build ? &b : NULL);
    }
    if (build)
        bvh_free(&b);
    scene_free(s);
    return 0;
}

/* ---- importance ---- */

enum {
    OPT_ITERATIONS = 256,
    OPT_TOLERANCE,
    OPT_PHOTONS,
    OPT_GAMMA,
    OPT_ALPHA,
    OPT_RESOLUTION,
    OPT_SEED,
    OPT_DEVICE,
    OPT_QUIET,
    OPT_LOCAL_SIZE,
    OPT_GENERIC,
    OPT_TARGET,
    OPT_METHOD,
    OPT_MIN_VERTICES,
    OPT_MAX_NORMAL_ANGLE,
    OPT_KEEP,
    OPT_FORCE,
    OPT_THREADS,
    OPT_TIME_LIMIT,
    OPT_EXPOSURE,
};

/* Options of the SPPM core, shared by `importance`, `reduce` and `render`. */
#define SPPM_LONG_OPTIONS                                                                   \
    {"output", required_argument, NULL, 'o'},                                               \
        {"iterations", required_argument, NULL, OPT_ITERATIONS},                            \
        {"photons", required_argument, NULL, OPT_PHOTONS},                                  \
        {"alpha", required_argument, NULL, OPT_ALPHA},                                      \
        {"resolution", required_argument, NULL, OPT_RESOLUTION},                            \
        {"seed", required_argument, NULL, OPT_SEED},                                        \
        {"time-limit", required_argument, NULL, OPT_TIME_LIMIT},                            \
        {"device", required_argument, NULL, OPT_DEVICE},                                    \
        {"quiet", no_argument, NULL, OPT_QUIET},                                            \
        {"local-size", required_argument, NULL, OPT_LOCAL_SIZE},                            \
        {"generic", no_argument, NULL, OPT_GENERIC}

/* Options of the importance pass, shared by `importance` and `reduce`. */
#define IMPORTANCE_LONG_OPTIONS                                                             \
    SPPM_LONG_OPTIONS, {"tolerance", required_argument, NULL, OPT_TOLERANCE},               \
        {"gamma", required_argument, NULL, OPT_GAMMA}

/* Applies SPPM option `c`; returns 1 if it was one, 0 if not, -1 on a bad value. */
static int parse_sppm_option(int c, sppm_options *o, int *device_index)
{
    double value;
    unsigned int whole;
    switch (c) {
    case OPT_ITERATIONS:
        return parse_unsigned("--iterations", optarg, 1, 1000000, &o->iterations) ? -1 : 1;
    case OPT_PHOTONS:
        return parse_unsigned("--photons", optarg, 1, 1u << 26, &o->photons) ? -1 : 1;
    case OPT_ALPHA:
        if (parse_double("--alpha", optarg, 1e-3, 1, &value))
            return -1;
        o->alpha = (float)value;
        return 1;
    case OPT_RESOLUTION:
        if (parse_double("--resolution", optarg, 1e-3, 16, &value))
            return -1;
        o->resolution = (float)value;
        return 1;
    case OPT_SEED:
        return parse_unsigned("--seed", optarg, 0, 0xffffffffu, &o->seed) ? -1 : 1;
    case OPT_TIME_LIMIT:
        return parse_double("--time-limit", optarg, 0, 1e9, &o->time_limit) ? -1 : 1;
    case OPT_DEVICE:
        if (parse_unsigned("--device", optarg, 0, 1000, &whole))
            return -1;
        *device_index = (int)whole;
        return 1;
    case OPT_QUIET:
        o->progress = 0;
        return 1;
    case OPT_LOCAL_SIZE:
        if (parse_unsigned("--local-size", optarg, 0, 4096, &whole))
            return -1;
        o->local_size = whole;
        return 1;
    case OPT_GENERIC:
        o->generic = 1;
        return 1;
    default:
        return 0;
    }
}

/* Applies importance option `c` (the SPPM ones included); returns as parse_sppm_option(). */
static int parse_importance_option(int c, importance_options *o, int *device_index)
{
    double value;
    switch (c) {
    case OPT_TOLERANCE:
        return parse_double("--tolerance", optarg, 0, 1e30, &o->tolerance) ? -1 : 1;
    case OPT_GAMMA:
        if (parse_double("--gamma", optarg, 0, 1e6, &value))
            return -1;
        o->gamma = (float)value;
        return 1;
    default:
        return parse_sppm_option(c, &o->sppm, device_index);
    }
}

static int command_importance(int argc, char **argv)
{
    static const struct option options[] = {IMPORTANCE_LONG_OPTIONS, {0, 0, 0, 0}};
    importance_options o;
    importance_options_default(&o);
    o.sppm.progress = 1;
    const char *output = NULL;
    int device_index = -1;
    int c;
    while ((c = getopt_long(argc, argv, "o:", options, NULL)) != -1) {
        if (c == 'o') {
            output = optarg;
            continue;
        }
        int parsed = parse_importance_option(c, &o, &device_index);
        if (parsed < 0)
            return fail();
        if (parsed == 0)
            return usage_error("importance: unknown option %s", argv[optind - 1]);
    }
    if (optind != argc - 1)
        return usage_error("importance: expected one SCENE argument%s", "");
    if (!output)
        return usage_error("importance: -o DIR is required%s", "");
    scene *s = mitsuba_load(argv[optind]);
    if (!s)
        return fail();
    device d;
    bvh b;
    importance_result r;
    memset(&r, 0, sizeof r);
    int status = device_open(&d, device_index);
    if (!status) {
        status = bvh_build(s, &b);
        if (!status) {
            status = importance_run(&d, s, &b, &o, &r);
            if (!status) {
                cJSON *report = importance_report_json(s, &d, &o, &r);
                double **values = importance_vertex_values(&r, s, o.gamma);
                status = importance_write_outputs(output, report, s, &o, &r, values);
                importance_vertex_values_free(values, s);
                cJSON_Delete(report);
            }
            bvh_free(&b);
        }
        device_close(&d);
    }
    int code = status ? fail() : 0;
    if (!status)
        fprintf(stderr,
                "idmr: %u iterations of %u photon paths in %.1f s; outputs in %s/ (report.json, "
                "importance.png, importance/*.ply, convergence.csv)\n",
                r.sppm.iterations, r.sppm.photons, r.sppm.seconds.total, output);
    importance_result_free(&r);
    scene_free(s);
    return code;
}

/* ---- render ---- */

/* IMAGE without a trailing ".exr" or ".png" (either names the same three outputs), into stem
 * (size bytes). */
static void image_stem(const char *image, char *stem, size_t size)
{
    snprintf(stem, size, "%s", image);
    size_t length = strlen(stem);
    if (length > 4 &&
        (!strcasecmp(stem + length - 4, ".exr") || !strcasecmp(stem + length - 4, ".png")))
        stem[length - 4] = '\0';
}

static int command_render(int argc, char **argv)
{
    static const struct option options[] = {IMPORTANCE_LONG_OPTIONS,
                                            {"exposure", required_argument, NULL, OPT_EXPOSURE},
                                            {0, 0, 0, 0}};
    render_options o;
    render_options_default(&o);
    o.sppm.progress = 1;
    const char *output = NULL;
    double exposure = 0;
    int device_index = -1, c;
    while ((c = getopt_long(argc, argv, "o:", options, NULL)) != -1) {
        if (c == 'o') {
            output = optarg;
        } else if (c == OPT_EXPOSURE) {
            if (parse_double("--exposure", optarg, -64, 64, &exposure))
                return fail();
        } else if (c == OPT_GAMMA || c == OPT_TOLERANCE) {
            return usage_error("render: %s is an importance pass option", argv[optind - 1]);
        } else {
            int parsed = parse_sppm_option(c, &o.sppm, &device_index);
            if (parsed < 0)
                return fail();
            if (parsed == 0)
                return usage_error("render: unknown option %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1)
        return usage_error("render: expected one SCENE argument%s", "");
    if (!output)
        return usage_error("render: -o IMAGE is required%s", "");
    char stem[4096], exr[4200], png[4200], json[4200], directory[4096];
    image_stem(output, stem, sizeof stem);
    snprintf(exr, sizeof exr, "%s.exr", stem);
    snprintf(png, sizeof png, "%s.png", stem);
    snprintf(json, sizeof json, "%s.json", stem);
    snprintf(directory, sizeof directory, "%s", stem);
    char *slash = strrchr(directory, '/');
    scene *s = mitsuba_load(argv[optind]);
    if (!s)
        return fail();
    device d;
    bvh b;
    render_result r;
    memset(&r, 0, sizeof r);
    int status = 0;
    if (slash && slash != directory) { /* the images' directory, created if missing */
        *slash = '\0';
        status = files_make_directory(directory);
    }
    if (!status)
        status = device_open(&d, device_index);
    if (!status) {
        status = bvh_build(s, &b);
        if (!status) {
            status = render_run(&d, s, &b, &o, &r) || render_write_images(&r, exr, png, exposure);
            if (!status) {
                cJSON *report = render_report_json(s, &d, &o, &r);
                status = json_write(report, json);
                cJSON_Delete(report);
            }
            bvh_free(&b);
        }
        device_close(&d);
    }
    int code = status ? fail() : 0;
    if (!status) {
        const sppm_summary *run = &r.sppm;
        double n = run->iterations;
        printf("%s: %ux%u, %u iterations of %u photon paths, %.3f s per iteration (camera %.3f, "
               "photons %.3f, grid %.3f, gather %.3f); device memory %.1f MiB (geometry %.1f, "
               "BVH %.1f, SPPM %.1f)\n",
               exr, run->width, run->height, run->iterations, run->photons,
               run->seconds.total / n, run->seconds.camera / n, run->seconds.photon / n,
               run->seconds.grid / n, run->seconds.gather / n,
               (run->geometry_bytes + run->bvh_bytes + run->buffer_bytes) / 1048576.0,
               run->geometry_bytes / 1048576.0, run->bvh_bytes / 1048576.0,
               run->buffer_bytes / 1048576.0);
    }
    render_result_free(&r);
    scene_free(s);
    return code;
}

/* ---- compare ---- */

static int command_compare(int argc, char **argv)
{
    static const struct option options[] = {{"diff", required_argument, NULL, 'd'},
                                            {"diff-max", required_argument, NULL, 'm'},
                                            {"json", no_argument, NULL, 'j'},
                                            {0, 0, 0, 0}};
    const char *diff = NULL;
    double diff_max = 0;
    int json = 0, c;
    while ((c = getopt_long(argc, argv, "", options, NULL)) != -1) {
        if (c == 'd')
            diff = optarg;
        else if (c == 'm') {
            if (parse_double("--diff-max", optarg, 1e-30, 1e30, &diff_max))
                return fail();
        } else if (c == 'j')
            json = 1;
        else
            return usage_error("compare: unknown option %s", argv[optind - 1]);
    }
    if (optind != argc - 2)
        return usage_error("compare: expected two images, A and the reference B%s", "");
    image_comparison result;
    if (image_compare(argv[optind], argv[optind + 1], diff, diff_max, &result))
        return fail();
    if (json) {
        cJSON *root = cJSON_CreateObject();
        cJSON_AddStringToObject(root, "a", argv[optind]);
        cJSON_AddStringToObject(root, "b", argv[optind + 1]);
        cJSON_AddNumberToObject(root, "width", result.width);
        cJSON_AddNumberToObject(root, "height", result.height);
        cJSON_AddNumberToObject(root, "rmse", result.rmse);
        if (isfinite(result.psnr))
            cJSON_AddNumberToObject(root, "psnr", result.psnr);
        else
            cJSON_AddNullToObject(root, "psnr"); /* identical images: infinite */
        cJSON_AddNumberToObject(root, "relative_mse", result.relative_mse);
        cJSON_AddNumberToObject(root, "max_error", result.max_error);
        cJSON_AddNumberToObject(root, "error_p99", result.error_p99);
        json_print(root);
        cJSON_Delete(root);
    } else {
        printf("rmse %.6g  psnr %.2f dB  relative_mse %.6g  max_error %.6g  (%dx%d)\n", result.rmse,
               result.psnr, result.relative_mse, result.max_error, result.width, result.height);
    }
    return 0;
}

/* ---- reduce ---- */

static int command_reduce(int argc, char **argv)
{
    static const struct option options[] = {
        IMPORTANCE_LONG_OPTIONS,
        {"target", required_argument, NULL, OPT_TARGET},
        {"method", required_argument, NULL, OPT_METHOD},
        {"min-vertices", required_argument, NULL, OPT_MIN_VERTICES},
        {"max-normal-angle", required_argument, NULL, OPT_MAX_NORMAL_ANGLE},
        {"keep", required_argument, NULL, OPT_KEEP},
        {"force", no_argument, NULL, OPT_FORCE},
        {"threads", required_argument, NULL, OPT_THREADS},
        {0, 0, 0, 0}};
    reduce_options o;
    reduce_options_default(&o);
    o.importance.sppm.progress = 1;
    const char *output = NULL;
    int device_index = -1, have_target = 0;
    const char **keep = xcalloc((size_t)argc + 1, sizeof *keep);
    int c, code = 0;
    while ((c = getopt_long(argc, argv, "o:", options, NULL)) != -1 && !code) {
        unsigned int whole;
        int status = 0;
        switch (c) {
        case 'o':
            output = optarg;
            break;
        case OPT_TARGET:
            status = parse_double("--target", optarg, 1e-9, 1, &o.target);
            have_target = 1;
            break;
        case OPT_METHOD:
            if (!strcmp(optarg, "importance"))
                o.method = DECIMATE_IMPORTANCE;
            else if (!strcmp(optarg, "quadric"))
                o.method = DECIMATE_QUADRIC;
            else if (!strcmp(optarg, "importance-quadric")) {
                o.method = DECIMATE_IMPORTANCE;
                o.quadric_collapses = 1;
            } else
                status = error_set(IDMR_EXIT_INPUT,
                                   "--method: '%s' is none of 'importance', 'quadric' and "
                                   "'importance-quadric'",
                                   optarg);
            break;
        case OPT_MIN_VERTICES:
            status = parse_unsigned("--min-vertices", optarg, 0, 0xffffffffu, &whole);
            o.min_vertices = whole;
            break;
        case OPT_MAX_NORMAL_ANGLE:
            status = parse_double("--max-normal-angle", optarg, 1, 180, &o.max_normal_angle);
            break;
        case OPT_KEEP:
            keep[o.keep_count++] = optarg;
            break;
        case OPT_FORCE:
            o.force = 1;
            break;
        case OPT_THREADS:
            status = parse_unsigned("--threads", optarg, 1, 1024, &o.threads);
            break;
        default: {
            int parsed = parse_importance_option(c, &o.importance, &device_index);
            if (parsed < 0)
                status = -1;
            else if (parsed == 0)
                code = usage_error("reduce: unknown option %s", argv[optind - 1]);
        }
        }
        if (status)
            code = fail();
    }
    o.keep = keep;
    if (!code && optind != argc - 1)
        code = usage_error("reduce: expected one SCENE argument%s", "");
    if (!code && (!output || !have_target))
        code = usage_error("reduce: --target D and -o OUTDIR are required%s", "");
    scene *s = code ? NULL : mitsuba_load(argv[optind]);
    if (!code && !s)
        code = fail();
    if (!code) {
        device d;
        int status = device_open(&d, device_index);
        if (!status) {
            status = reduce_run(&d, s, output, &o);
            device_close(&d);
        }
        if (status)
            code = fail();
    }
    scene_free(s);
    free(keep);
    return code;
}

int main(int argc, char **argv)
{
    int first = 1;
    for (; first < argc && argv[first][0] == '-'; first++) {
        const char *arg = argv[first];
        if (!strcmp(arg, "-v") || !strcmp(arg, "--verbose")) {
            log_set_verbose(1);
        } else if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            print_usage(stdout);
            return 0;
        } else if (!strcmp(arg, "--version")) {
            printf("idmr %s\n", IDMR_VERSION);
            return 0;
        } else {
            return usage_error("unknown option %s", arg);
        }
    }
    if (first >= argc) {
        print_usage(stderr);
        return IDMR_EXIT_INPUT;
    }
    const char *command = argv[first];
    int sub_argc = argc - first;
    char **sub_argv = argv + first;
    optind = 1;
    if (!strcmp(command, "devices"))
        return command_devices(sub_argc, sub_argv);
    if (!strcmp(command, "info"))
        return command_info(sub_argc, sub_argv);
    if (!strcmp(command, "importance"))
        return command_importance(sub_argc, sub_argv);
    if (!strcmp(command, "reduce"))
        return command_reduce(sub_argc, sub_argv);
    if (!strcmp(command, "render"))
        return command_render(sub_argc, sub_argv);
    if (!strcmp(command, "compare"))
        return command_compare(sub_argc, sub_argv);
    if (!strcmp(command, "help")) {
        print_usage(stdout);
        return 0;
    }
    return usage_error("unknown command '%s'", command);
}
