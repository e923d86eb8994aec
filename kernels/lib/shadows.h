/* shadows.h — shadow importance (Bethe, Jendersie and Grosch, "Preserving Shadow Silhouettes in
 * Illumination-Driven Mesh Reduction", 2020; the paper's own outlook, section 6): a shadow is part
 * of the image even when the object casting it is not, so the triangles that cast the shadows the
 * camera sees get importance of their own.
 *
 * From each hit point one shadow ray goes to a point of a light chosen in proportion to power
 * (shadow_light_sample, lib/lights.h). The first triangle it meets, the occluder, gets the weight
 *     w = (1 - |c|) / max(|c|, 0.1) × cos_receiver × reach × sharpness,   c = n_occluder · d
 * A ray that grazes the occluder (|c| small) passes its silhouette as seen from the light, which
 * draws the shadow's outline. 1 - |c| is Eq. 2's weight; the division undoes the foreshortening
 * (rays from the receiver reach a surface more thinly the more they graze it, in proportion to
 * |c|), so that the importance per area is 1 - |c|, highest on the silhouette ring, where Eq. 2
 * alone would peak halfway between ring and cap. cos_receiver is the cosine at the receiver (a
 * light grazing it lights it little), reach the share of the light that gets there (a spot's
 * falloff). sharpness = footprint / (footprint + penumbra) weighs sharp shadows above soft ones:
 * the penumbra's width at the receiver, light size × (receiver to occluder) / (occluder to light),
 * against the width a pixel covers there (distance from the camera × 2 tan(fov_x / 2) / width).
 * Point, spot and directional lights cast sharp shadows (sharpness 1); environments none. */
#ifndef IDMR_KERNEL_SHADOWS_H
#define IDMR_KERNEL_SHADOWS_H

#include "idmr/camera.h"
#include "idmr/sppm_layout.h"
#include "idmr/weight.h"
#include "lib/lights.h"
#include "lib/scene.h"
#include "lib/surface.h"

/* The shadow weight of hit point hp's shadow ray (above), its occluder's triangle into *occluder
 * and the instance it is on into *occluder_instance (0 in a flat scene); 0 when the ray reaches
 * the light or no light reaches hp. */
inline float shadow_occluder_weight(const scene_view *scene, const idmr_sppm_params *params,
                                    const idmr_camera *camera, global const idmr_hit_point *hp,
                                    idmr_rng *rng, uint *occluder, uint *occluder_instance)
{
    float3 p = vload3(0, hp->position), n = vload3(0, hp->normal);
    float3 d;
    float distance, size, reach;
    if (!shadow_light_sample(scene, params, p, rng, &d, &distance, &size, &reach))
        return 0.0f;
    float cos_receiver = dot(d, n);
    if (!(cos_receiver > 0.0f))
        return 0.0f; /* the light is on the other side of the receiving surface */
    float3 origin = offset_origin(p, n, hp->offset);
    float tmax = isinf(distance) ? INFINITY : distance * (1.0f - 1e-4f); /* short of the light */
    surface found = trace_surface(scene, origin, d, tmax);
    idmr_hit hit = found.hit;
    if (hit.triangle == IDMR_NO_HIT)
        return 0.0f;
    *occluder = hit.triangle;
    *occluder_instance = found.instance;
    float3 m = found.normal;
    float grazing = idmr_eq2_weight(m.x, m.y, m.z, d.x, d.y, d.z); /* 1 - |c| */
    float silhouette = grazing / fmax(1.0f - grazing, 0.1f);
    float footprint = length(p - vload3(0, camera->origin)) * 2.0f * camera->tan_half_x /
                      (float)params->width;
    float penumbra = isinf(distance) ? 0.0f : size * hit.t / fmax(distance - hit.t, 1e-30f);
    float sharpness = footprint > 0.0f ? footprint / (footprint + penumbra) : 1.0f;
    return silhouette * cos_receiver * reach * sharpness;
}

#endif
