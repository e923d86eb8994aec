/* info_text.c — the text form of `idmr info`, read from the info object (command_info.c).
 * Counts by kind list the kinds in the order of their enums (core/scene.h), as their names
 * appear in the object. */
#include "cli/info_text.h"

#include <stdio.h>
#include <string.h>

#include "core/scene.h"

static double number(const cJSON *object, const char *key)
{
    return cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(object, key));
}

static const char *string(const cJSON *object, const char *key)
{
    return cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(object, key));
}

static const cJSON *item(const cJSON *object, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(object, key);
}

/* Element k of the [x, y, z] array `key` of `object`. */
static double component(const cJSON *object, const char *key, int k)
{
    return cJSON_GetNumberValue(cJSON_GetArrayItem(item(object, key), k));
}

static void print_meshes(const cJSON *info)
{
    const cJSON *meshes = item(info, "meshes"), *m;
    printf("meshes (%d): %llu vertices", cJSON_GetArraySize(meshes),
           (unsigned long long)number(info, "vertices"));
    if (number(info, "vertices_stored") != number(info, "vertices"))
        printf(" (%llu stored: an instanced shape once)",
               (unsigned long long)number(info, "vertices_stored"));
    printf(", %llu triangles", (unsigned long long)number(info, "triangles"));
    unsigned long long dropped_in_all = (unsigned long long)number(info, "triangles_dropped");
    if (dropped_in_all)
        printf(" (%llu more in the files repeat a vertex: dropped)", dropped_in_all);
    printf("\n");
    printf("  %-24s %-10s %10s %10s  %-22s %s\n", "name", "shape", "vertices", "triangles",
           "material", "kind");
    cJSON_ArrayForEach(m, meshes)
    {
        printf("  %-24.24s %-10.10s %10u %10u  %-22.22s %s%s", string(m, "name"),
               string(m, "shape"), (unsigned)number(m, "vertices"),
               (unsigned)number(m, "triangles"), string(m, "material"), string(m, "material_kind"),
               cJSON_IsTrue(item(m, "emitter")) ? ", emitter" : "");
        unsigned int dropped = (unsigned int)number(m, "triangles_dropped");
        if (dropped)
            printf("; %u triangle%s dropped (a repeated vertex)", dropped, dropped == 1 ? "" : "s");
        if (cJSON_IsString(item(m, "instance_of")))
            printf("; a copy of %s", string(m, "instance_of"));
        printf("\n");
    }
}

/* "\n<key> (N):" and " n <kind>" for each kind named by kind_name(0 .. kind_count - 1) that
 * `field` of some element of array `key` holds. */
static void print_kinds(const cJSON *info, const char *key, const char *field,
                        unsigned int kind_count, const char *(*kind_name)(unsigned int kind))
{
    const cJSON *array = item(info, key), *element;
    printf("\n%s (%d):", key, cJSON_GetArraySize(array));
    for (unsigned int kind = 0; kind < kind_count; kind++) {
        size_t n = 0;
        cJSON_ArrayForEach(element, array)
        {
            n += !strcmp(string(element, field), kind_name(kind));
        }
        if (n)
            printf(" %zu %s", n, kind_name(kind));
    }
}

static void print_camera(const cJSON *info)
{
    const cJSON *c = item(info, "camera");
    if (!c) {
        printf("camera: none\n");
        return;
    }
    printf("camera: %ux%u, fov %g (%s), at (%g, %g, %g) looking (%g, %g, %g)\n",
           (unsigned)number(c, "width"), (unsigned)number(c, "height"), number(c, "fov"),
           string(c, "fov_axis"), component(c, "origin", 0), component(c, "origin", 1),
           component(c, "origin", 2), component(c, "forward", 0), component(c, "forward", 1),
           component(c, "forward", 2));
}

static void print_bbox_and_features(const cJSON *info)
{
    const cJSON *bbox = item(info, "bbox"), *feature;
    printf("bbox: (%g, %g, %g) .. (%g, %g, %g)\n", component(bbox, "min", 0),
           component(bbox, "min", 1), component(bbox, "min", 2), component(bbox, "max", 0),
           component(bbox, "max", 1), component(bbox, "max", 2));
    printf("features:");
    cJSON_ArrayForEach(feature, item(info, "features"))
    {
        printf(" %s", feature->valuestring);
    }
    printf("\n");
}

static void print_bytes(const cJSON *memory, const char *key)
{
    printf("  %-10s %10.2f MiB\n", key, number(memory, key) / 1048576.0);
}

static void print_device(const cJSON *info)
{
    const cJSON *memory = item(info, "device_memory"), *tree = item(info, "bvh");
    printf("device memory:\n");
    print_bytes(memory, "geometry");
    if (!tree)
        return;
    print_bytes(memory, "bvh");
    print_bytes(memory, "total");
    printf("bvh: %llu nodes, %llu leaves, %llu triangle references, depth %d, built in %.2f s\n",
           (unsigned long long)number(tree, "nodes"), (unsigned long long)number(tree, "leaves"),
           (unsigned long long)number(tree, "triangle_references"), (int)number(tree, "depth"),
           number(tree, "build_seconds"));
}

void info_text_print(const cJSON *info)
{
    printf("scene %s\n\n", string(info, "scene"));
    print_meshes(info);
    print_kinds(info, "materials", "kind", IDMR_MATERIAL_KIND_COUNT, scene_material_kind_name);
    print_kinds(info, "lights", "type", IDMR_LIGHT_KIND_COUNT, scene_light_kind_name);
    printf("\n");
    print_camera(info);
    print_bbox_and_features(info);
    print_device(info);
}
