/* idmr/features.h — the scene feature bits: which material and light kinds a scene holds.
 *
 * Computed once by scene_finalize() from the loaded scene, printed by `idmr info`, and turned
 * into kernel build options by device_build_options(), so that a kernel compiles in only the
 * branches a scene needs. The names are in scene_feature_name(). */
#ifndef IDMR_FEATURES_H
#define IDMR_FEATURES_H

#define IDMR_FEATURE_DIFFUSE (1u << 0)     /* Lambertian surfaces */
#define IDMR_FEATURE_GLOSSY (1u << 1)      /* rough conductors, (rough) plastic */
#define IDMR_FEATURE_MIRROR (1u << 2)      /* smooth conductors */
#define IDMR_FEATURE_DIELECTRIC (1u << 3)  /* smooth (thin) dielectrics */
#define IDMR_FEATURE_TEXTURED (1u << 4)    /* a bitmap reflectance somewhere */
#define IDMR_FEATURE_AREA (1u << 5)        /* area emitters on shapes */
#define IDMR_FEATURE_POINT (1u << 6)       /* point lights */
#define IDMR_FEATURE_SPOT (1u << 7)        /* spot lights */
#define IDMR_FEATURE_DIRECTIONAL (1u << 8) /* directional lights */
#define IDMR_FEATURE_ENVIRONMENT (1u << 9) /* constant and envmap emitters */
#define IDMR_FEATURE_COUNT 10

#define IDMR_FEATURES_ALL ((1u << IDMR_FEATURE_COUNT) - 1u) /* the generic program */
#define IDMR_FEATURES_LIGHTS                                                                     \
    (IDMR_FEATURE_AREA | IDMR_FEATURE_POINT | IDMR_FEATURE_SPOT | IDMR_FEATURE_DIRECTIONAL |    \
     IDMR_FEATURE_ENVIRONMENT)

/* Not a material or light but the scene's structure: instanced shapes held once, traced
 * through the two-level BVH (idmr/instance_bvh_layout.h). Outside IDMR_FEATURE_COUNT and
 * IDMR_FEATURES_ALL: whether a program traces instances is decided apart from what it
 * shades. */
#define IDMR_FEATURE_INSTANCES (1u << 10)

/* Surfaces that continue a camera path instead of ending it in a hit point. */
#define IDMR_FEATURES_SPECULAR (IDMR_FEATURE_MIRROR | IDMR_FEATURE_DIELECTRIC)

#endif
