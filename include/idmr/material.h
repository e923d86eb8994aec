/* idmr/material.h — a surface's scattering as the kernels see it (48 bytes).
 *
 * Every Mitsuba bsdf maps onto one of four kinds (host/io/mitsuba/mitsuba_bsdf.c does the mapping):
 *   DIFFUSE     diffuse                         reflectance
 *   GLOSSY      roughconductor, plastic,        reflectance (diffuse part, black for metals),
 *               roughplastic                    specular, roughness (GGX alpha), int/ext IOR
 *   MIRROR      conductor                       specular (normal-incidence colour)
 *   DIELECTRIC  dielectric, thindielectric      int_ior, ext_ior, flags THIN
 * `twosided` sets IDMR_MATERIAL_TWOSIDED on its inner bsdf; `mask` is replaced by its inner bsdf.
 * texture >= 0 indexes the scene's textures for a bitmap reflectance; `reflectance` then holds
 * the texture's mean, for code paths that do not look textures up. */
#ifndef IDMR_MATERIAL_H
#define IDMR_MATERIAL_H

#include "idmr/layout.h"

#define IDMR_MATERIAL_DIFFUSE 0u
#define IDMR_MATERIAL_GLOSSY 1u
#define IDMR_MATERIAL_MIRROR 2u
#define IDMR_MATERIAL_DIELECTRIC 3u
#define IDMR_MATERIAL_KIND_COUNT 4u

#define IDMR_MATERIAL_TWOSIDED (1u << 0)
#define IDMR_MATERIAL_THIN (1u << 1)

/* The least GGX alpha a glossy lobe is simulated with (kernels/lib/materials.h): a smoother one
 * is simulated as this rough, so that no glossy lobe is a delta the density estimate cannot
 * see. */
#define IDMR_MIN_GLOSSY_ROUGHNESS 0.05f

typedef struct idmr_material {
    float reflectance[3]; /* linear RGB albedo of the diffuse part */
    unsigned int kind;
    float specular[3]; /* linear RGB of the specular part */
    float roughness;   /* GGX alpha; 0 for smooth kinds */
    float int_ior;
    float ext_ior;
    int texture; /* index into the scene's textures, or -1 */
    unsigned int flags;
} idmr_material;

IDMR_STATIC_ASSERT(sizeof(idmr_material) == 48, "idmr_material must be 48 bytes");
IDMR_OFFSET_ASSERT(idmr_material, kind, 12);
IDMR_OFFSET_ASSERT(idmr_material, specular, 16);
IDMR_OFFSET_ASSERT(idmr_material, int_ior, 32);

#endif
