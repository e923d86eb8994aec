/* scene.h — a scene's data on the device, as every light transport kernel reads it: the
 * buffers device_scene uploads (host/device/device_scene.h), passed to a kernel as the
 * parameter list SCENE_BUFFERS in this order and bundled in a scene_view for the device
 * functions:
 *
 *   nodes, leaves          the BVH (idmr/bvh_layout.h); of an instanced scene, every
 *                          prototype's (idmr/instance_bvh_layout.h)
 *   top_nodes, instances   an instanced scene's top level and instance records; a flat
 *                          scene binds placeholders that its program never reads
 *   triangle_normals       float4 per scene triangle: unit winding normal, w = the offset
 *                          of rays leaving it (idmr/ray.h)
 *   triangle_shading       uint4 per scene triangle: corner shading normals (lib/shading.h)
 *   triangle_materials     uint per scene triangle: index into materials
 *   materials, lights      idmr_material[], idmr_light[]
 *   light_cdf              per light: cumulative power, last entry 1
 *   emitter_cdf            per area light, its triangles' cumulative area (in light order)
 *   emitter_triangles      3 float4 per emitter_cdf entry: v0 (w = the offset of rays
 *                          leaving it), v1 - v0, v2 - v0
 *   environment            the environment map and its CDFs (idmr/environment.h)
 * Triangles are numbered scene-globally (the traversal returns that index); a later copy of an
 * instanced shape shares its representative's triangles, so every per-triangle buffer is per
 * prototype and holds the representative's world-space data (lib/surface.h carries it to the
 * copy hit). */
#ifndef IDMR_KERNEL_SCENE_H
#define IDMR_KERNEL_SCENE_H

#include "idmr/bvh_layout.h"
#include "idmr/instance_bvh_layout.h"
#include "idmr/light.h"
#include "idmr/material.h"
#include "idmr/ray.h"

#define SCENE_BUFFERS                                                                        \
    global const idmr_bvh_node *nodes, global const idmr_triangle4 *leaves,                  \
        global const idmr_bvh_node *top_nodes, global const idmr_instance *instances,        \
        global const float4 *triangle_normals, global const uint4 *triangle_shading,         \
        global const uint *triangle_materials,                                               \
        global const idmr_material *materials, global const idmr_light *lights,              \
        global const float *light_cdf, global const float *emitter_cdf,                      \
        global const float4 *emitter_triangles, global const float *environment

typedef struct scene_view {
    global const idmr_bvh_node *nodes;
    global const idmr_triangle4 *leaves;
    global const idmr_bvh_node *top_nodes;
    global const idmr_instance *instances;
    global const float4 *triangle_normals;
    global const uint4 *triangle_shading;
    global const uint *triangle_materials;
    global const idmr_material *materials;
    global const idmr_light *lights;
    global const float *light_cdf;
    global const float *emitter_cdf;
    global const float4 *emitter_triangles;
    global const float *environment;
} scene_view;

/* The scene_view of a kernel that takes SCENE_BUFFERS. */
#define SCENE_VIEW()                                                                         \
    ((scene_view){nodes, leaves, top_nodes, instances, triangle_normals, triangle_shading,  \
                  triangle_materials, materials, lights, light_cdf, emitter_cdf,             \
                  emitter_triangles, environment})

/* The material of scene triangle t. */
inline global const idmr_material *triangle_material(const scene_view *scene, uint t)
{
    return scene->materials + scene->triangle_materials[t];
}

/* How far a ray leaving the surface of `triangle` at a point reached from `ray_origin` starts
 * off it (idmr/ray.h). */
inline float surface_offset(const scene_view *scene, uint triangle, float3 ray_origin)
{
    float3 a = fabs(ray_origin);
    return fmax(scene->triangle_normals[triangle].w,
                IDMR_RAY_OFFSET_SCALE * fmax(a.x, fmax(a.y, a.z)));
}

/* Moves surface point p `offset` to the side `side` (a unit normal) points to. */
inline float3 offset_origin(float3 p, float3 side, float offset)
{
    return p + side * offset;
}

#endif
