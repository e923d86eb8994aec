/* device_scene.h — a scene's data on the OpenCL device, as the light transport kernels read it
 * (kernels/lib/scene.h, kernels/lib/traverse.h), in the order kernels take them (SCENE_BUFFERS):
 *
 *   nodes, leaves            the BVH (idmr/bvh_layout.h); of an instanced scene every
 *                            prototype's, each once (device/bvh.h)
 *   top_nodes, instances     an instanced scene's top level and instance records
 *                            (idmr/instance_bvh_layout.h); a flat scene binds 16-byte
 *                            placeholders, not counted, that its program never reads
 *   triangle_normals         float4 per scene triangle: unit winding normal, w = the offset
 *                            of rays leaving it, from its vertices (idmr/ray.h)
 *   triangle_shading         uint4 per scene triangle: its corners' shading normals packed
 *                            (idmr/normal_packing.h), w = 1; all zero: shaded flat
 *   triangle_materials       uint per scene triangle
 *   materials, lights        idmr_material[], idmr_light[] (lights with cdf_offset filled)
 *   light_cdf                float per light: cumulative power, last entry 1
 *   emitter_cdf              per area light, its triangles' cumulative area (each light's
 *                            stretch ends at 1), in light order
 *   emitter_triangles        3 float4 per emitter_cdf entry: v0 (w = the offset of rays
 *                            leaving it), v1 - v0, v2 - v0
 *   environment              the environment map and its sampling CDFs (idmr/environment.h)
 * Per-triangle buffers are indexed by scene-global triangle number (scene_mesh.first_triangle):
 * a later copy of an instanced shape shares its representative's triangles (core/scene.h), so
 * they hold each prototype once, with the representative's world-space data. Also the scene's
 * bounding sphere. */
#ifndef IDMR_DEVICE_SCENE_H
#define IDMR_DEVICE_SCENE_H

#include "device/bvh.h"
#include "device/device.h"
#include "core/scene.h"

typedef struct device_scene {
    cl_mem nodes;
    cl_mem leaves;
    cl_mem top_nodes;
    cl_mem instances;
    cl_mem triangle_normals;
    cl_mem triangle_shading;
    cl_mem triangle_materials;
    cl_mem materials;
    cl_mem lights;
    cl_mem light_cdf;
    cl_mem emitter_cdf;
    cl_mem emitter_triangles;
    cl_mem environment;
    unsigned int light_count;
    float center[3];
    float radius;      /* bounding sphere of the scene box */
    int instanced;     /* traced through the two-level BVH (IDMR_FEATURE_INSTANCES) */
    uint64_t bytes;    /* device memory of all the above */
    uint64_t bvh_bytes; /* of which the BVH (nodes and leaves; top nodes and instances) */
} device_scene;

/* Device memory of the scene's buffers other than the BVH (what `idmr info` and the passes
 * report as geometry), as device_scene_upload() allocates them: each prototype's triangles
 * once. */
uint64_t device_scene_geometry_bytes(const scene *s);

/* Uploads scene `s` with its BVH `b` (bvh_build(s): two-level exactly where the scene has
 * IDMR_FEATURE_INSTANCES). A scene without lights is accepted (the light buffers then hold one
 * unused entry). Returns 0, or -1 with the error set. */
int device_scene_upload(device *d, const scene *s, const bvh *b, device_scene *out);
void device_scene_release(device_scene *ds);

/* The buffers a kernel's SCENE_BUFFERS parameters take (kernels/lib/scene.h). */
#define DEVICE_SCENE_BUFFERS 13u

/* Binds the scene's buffers as arguments first .. first + DEVICE_SCENE_BUFFERS - 1 of `kernel`
 * (named `kernel_name` in errors). Returns 0, or -1 with the error set. */
int device_scene_set_args(const device_scene *ds, cl_kernel kernel, const char *kernel_name,
                          unsigned int first);

#endif
