/* mitsuba_bsdf.c — <bsdf> elements → materials: diffuse, dielectric, thindielectric,
 * roughdielectric (as smooth, warned), conductor, roughconductor, plastic, roughplastic, and the
 * wrappers twosided, mask (opacity ignored), bumpmap and normalmap (their nested bsdf, warned).
 * A bsdf is parsed into a bsdf_parsed without touching the scene; it becomes a scene material
 * (its texture loaded) when a shape first uses it, so an unused declaration adds nothing. */
#include "io/mitsuba/mitsuba_loader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/image.h"

/* Wrappers (twosided, mask, ...) nest at most this deep. */
#define MITSUBA_MAX_NESTING 16

/* Mitsuba's defaults (documented in both manuals). */
#define MITSUBA_IOR_BK7 1.5046
#define MITSUBA_IOR_POLYPROPYLENE 1.49
#define MITSUBA_IOR_AIR 1.000277
#define MITSUBA_ALPHA 0.1

typedef struct named_value {
    const char *name;
    double value;
} named_value;

/* Mitsuba's named indices of refraction (its documentation's table). */
static const named_value mitsuba_iors[] = {
    {"vacuum", 1.0},          {"helium", 1.00004},         {"hydrogen", 1.00013},
    {"air", MITSUBA_IOR_AIR}, {"carbon dioxide", 1.00045}, {"water", 1.3330},
    {"acetone", 1.36},        {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
    {"glycerol", 1.4729},     {"benzene", 1.501},          {"silicone oil", 1.52045},
    {"bromine", 1.661},       {"water ice", 1.31},         {"fused quartz", 1.458},
    {"pyrex", 1.470},         {"acrylic glass", 1.49},     {"polypropylene", 1.49},
    {"bk7", MITSUBA_IOR_BK7}, {"sodium chloride", 1.544},  {"amber", 1.55},
    {"pet", 1.5750},          {"diamond", 2.419},
};

typedef struct named_color {
    const char *name;
    float rgb[3];
} named_color;

/* Normal-incidence reflectance of common metals in linear sRGB (the approximations tabulated in
 * Real-Time Rendering, 4th ed., Table 9.2). */
static const named_color mitsuba_conductors[] = {
    {"none", {1.0f, 1.0f, 1.0f}},       {"Ag", {0.972f, 0.960f, 0.915f}},
    {"Al", {0.913f, 0.922f, 0.924f}},   {"Au", {1.000f, 0.782f, 0.344f}},
    {"Cu", {0.955f, 0.638f, 0.538f}},   {"Cr", {0.549f, 0.556f, 0.554f}},
};

/* An index of refraction: a number, or one of Mitsuba's names in a <string>. */
static int prop_ior(xmlNodePtr plugin, const char *name, double fallback, double *out)
{
    xmlNodePtr prop = mitsuba_prop_find(plugin, name);
    *out = fallback;
    if (!prop)
        return 0;
    if (mitsuba_is_tag(prop, "string")) {
        const char *value;
        if (mitsuba_require_attr(prop, "value", &value))
            return -1;
        for (size_t i = 0; i < sizeof mitsuba_iors / sizeof *mitsuba_iors; i++)
            if (strcasecmp(value, mitsuba_iors[i].name) == 0) {
                *out = mitsuba_iors[i].value;
                return 0;
            }
        return mitsuba_fail(prop, "unknown index of refraction '%s'", value);
    }
    if (mitsuba_prop_float(plugin, name, fallback, out))
        return -1;
    if (*out <= 0.0)
        return mitsuba_fail(prop, "an index of refraction must be positive");
    return 0;
}

static int bsdf_alpha(xmlNodePtr node, double *alpha)
{
    const char *distribution;
    double u, v;
    if (mitsuba_prop_string(node, "distribution", "beckmann", &distribution))
        return -1;
    if (strcmp(distribution, "ggx") && strcmp(distribution, "beckmann"))
        mitsuba_warn_at(node, "microfacet distribution '%s' treated as ggx", distribution);
    if (mitsuba_prop_float(node, "alpha", MITSUBA_ALPHA, alpha))
        return -1;
    if (!mitsuba_prop_find(node, "alpha") &&
        (mitsuba_prop_find(node, "alpha_u") || mitsuba_prop_find(node, "alpha_v"))) {
        /* Anisotropic roughness: the kernels are isotropic, take the geometric mean. */
        if (mitsuba_prop_float(node, "alpha_u", MITSUBA_ALPHA, &u) ||
            mitsuba_prop_float(node, "alpha_v", MITSUBA_ALPHA, &v))
            return -1;
        *alpha = sqrt(u * v);
    }
    if (*alpha < 0.0)
        return mitsuba_fail(node, "roughness must not be negative");
    return 0;
}

static int bsdf_diffuse(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    out->material.kind = IDMR_MATERIAL_DIFFUSE;
    return mitsuba_prop_color(ld, node, "reflectance", 0.5f, out->material.reflectance,
                              &out->texture);
}

static int bsdf_dielectric(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    double int_ior, ext_ior;
    out->material.kind = IDMR_MATERIAL_DIELECTRIC;
    if (prop_ior(node, "int_ior", MITSUBA_IOR_BK7, &int_ior) ||
        prop_ior(node, "ext_ior", MITSUBA_IOR_AIR, &ext_ior))
        return -1;
    out->material.int_ior = (float)int_ior;
    out->material.ext_ior = (float)ext_ior;
    for (int k = 0; k < 3; k++)
        out->material.specular[k] = 1.0f;
    if (strcmp(out->type, "thindielectric") == 0)
        out->material.flags |= IDMR_MATERIAL_THIN;
    if (strcmp(out->type, "roughdielectric") == 0)
        mitsuba_warn_at(node, "roughdielectric is treated as a smooth dielectric");
    return 0;
}

/* Normal-incidence Fresnel reflectance of a conductor with complex index eta + i k. */
static float conductor_f0(double eta, double k)
{
    return (float)(((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k));
}

/* The conductor's colour at normal incidence: eta/k if given, else the named material. */
static int conductor_color(loader *ld, xmlNodePtr node, float f0[3])
{
    if (mitsuba_prop_find(node, "eta")) {
        float eta[3], k[3];
        double ext_eta;
        if (mitsuba_prop_color(ld, node, "eta", 1.0f, eta, NULL) ||
            mitsuba_prop_color(ld, node, "k", 0.0f, k, NULL) ||
            prop_ior(node, "ext_eta", MITSUBA_IOR_AIR, &ext_eta))
            return -1;
        for (int c = 0; c < 3; c++)
            f0[c] = conductor_f0(eta[c] / ext_eta, k[c] / ext_eta);
        return 0;
    }
    const char *material;
    /* Mitsuba 0.6 defaults to copper, 3.x to a perfect mirror. */
    if (mitsuba_prop_string(node, "material", ld->major_version == 0 ? "Cu" : "none", &material))
        return -1;
    for (size_t i = 0; i < sizeof mitsuba_conductors / sizeof *mitsuba_conductors; i++)
        if (strcasecmp(material, mitsuba_conductors[i].name) == 0) {
            memcpy(f0, mitsuba_conductors[i].rgb, sizeof(float) * 3);
            return 0;
        }
    mitsuba_warn_at(node,
                    "conductor material '%s' is not known here: using a grey reflectance of 0.9",
                    material);
    f0[0] = f0[1] = f0[2] = 0.9f;
    return 0;
}

static int bsdf_conductor(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    float f0[3], tint[3];
    double alpha = 0.0;
    int rough = strcmp(out->type, "roughconductor") == 0;
    out->material.kind = rough ? IDMR_MATERIAL_GLOSSY : IDMR_MATERIAL_MIRROR;
    if (conductor_color(ld, node, f0) ||
        mitsuba_prop_color(ld, node, "specular_reflectance", 1.0f, tint, NULL))
        return -1;
    if (rough && bsdf_alpha(node, &alpha))
        return -1;
    for (int k = 0; k < 3; k++) {
        out->material.reflectance[k] = 0.0f;
        out->material.specular[k] = f0[k] * tint[k];
    }
    out->material.roughness = (float)alpha;
    return 0;
}

static int bsdf_plastic(loader *ld, xmlNodePtr node, bsdf_parsed *out)
{
    double int_ior, ext_ior, alpha = 0.0;
    out->material.kind = IDMR_MATERIAL_GLOSSY;
    if (mitsuba_prop_color(ld, node, "diffuse_reflectance", 0.5f, out->material.reflectance,
                           &out->texture) ||
        mitsuba_prop_color(ld, node, "specular_reflectance", 1.0f, out->material.specular,
                           NULL) ||
        prop_ior(node, "int_ior", MITSUBA_IOR_POLYPROPYLENE, &int_ior) ||
        prop_ior(node, "ext_ior", MITSUBA_IOR_AIR, &ext_ior))
        return -1;
    if (strcmp(out->type, "roughplastic") == 0 && bsdf_alpha(node, &alpha))
        return -1;
    out->material.int_ior = (float)int_ior;
    out->material.ext_ior = (float)ext_ior;
    out->material.roughness = (float)alpha;
    return 0;
}

/* A wrapper (twosided, mask, bumpmap, normalmap): its nested bsdf, inline or by reference,
 * two-sided for twosided. */
static int bsdf_wrapper(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out)
{
    const char *wrapper = mitsuba_attr(node, "type");
    xmlNodePtr inner = NULL;
    int inner_count = 0;
    MITSUBA_FOR_EACH_ELEMENT(child, node)
    {
        xmlNodePtr candidate = child;
        if (mitsuba_is_tag(child, "ref")) {
            mitsuba_id *entry = mitsuba_ref_resolve(ld, child);
            if (!entry)
                return -1;
            candidate = entry->node;
        }
        if (!mitsuba_is_tag(candidate, "bsdf"))
            continue;
        mitsuba_mark_read(child);
        if (!inner_count++)
            inner = candidate;
    }
    if (!inner)
        return mitsuba_fail(node, "a %s bsdf needs a nested bsdf", wrapper);
    if (inner_count > 1)
        mitsuba_warn_at(node, "only the first nested bsdf is used (for both sides)");
    if (strcmp(wrapper, "bumpmap") == 0 || strcmp(wrapper, "normalmap") == 0)
        mitsuba_warn_at(node, "%s is not simulated: using its nested bsdf", wrapper);
    unsigned int flags = strcmp(wrapper, "twosided") == 0 ? IDMR_MATERIAL_TWOSIDED : 0u;
    if (mitsuba_parse_bsdf(ld, inner, depth + 1, out))
        return -1;
    out->material.flags |= flags;
    return 0;
}

typedef int (*bsdf_reader)(loader *ld, xmlNodePtr node, bsdf_parsed *out);

static const struct {
    const char *type;
    bsdf_reader read;
} bsdf_readers[] = {
    {"diffuse", bsdf_diffuse},           {"dielectric", bsdf_dielectric},
    {"thindielectric", bsdf_dielectric}, {"roughdielectric", bsdf_dielectric},
    {"conductor", bsdf_conductor},       {"roughconductor", bsdf_conductor},
    {"plastic", bsdf_plastic},           {"roughplastic", bsdf_plastic},
};

static int is_bsdf_wrapper(const char *type)
{
    return strcmp(type, "twosided") == 0 || strcmp(type, "mask") == 0 ||
           strcmp(type, "bumpmap") == 0 || strcmp(type, "normalmap") == 0;
}

int mitsuba_parse_bsdf(loader *ld, xmlNodePtr node, int depth, bsdf_parsed *out)
{
    const char *type;
    if (depth > MITSUBA_MAX_NESTING)
        return mitsuba_fail(node, "bsdfs nested too deeply");
    if (mitsuba_require_attr(node, "type", &type))
        return -1;
    if (is_bsdf_wrapper(type))
        return bsdf_wrapper(ld, node, depth, out);
    memset(out, 0, sizeof *out);
    out->material.int_ior = out->material.ext_ior = 1.0f;
    out->material.texture = -1;
    snprintf(out->type, sizeof out->type, "%s", type);
    for (size_t i = 0; i < sizeof bsdf_readers / sizeof *bsdf_readers; i++)
        if (strcmp(type, bsdf_readers[i].type) == 0)
            return bsdf_readers[i].read(ld, node, out);
    return mitsuba_fail(node, "unsupported bsdf type '%s'", type);
}

/* The scene's texture of image file `path`, read (through OpenImageIO) and added on first use.
 * Returns its index, or -1 with the error set if the image cannot be read. */
static int read_texture(scene *s, const char *path)
{
    int texture = scene_find_texture(s, path);
    if (texture >= 0)
        return texture;
    int width, height;
    float *rgb;
    if (image_read_rgb(path, &width, &height, &rgb))
        return -1;
    return scene_add_texture(s, path, width, height, rgb);
}

int mitsuba_bsdf_add(loader *ld, const bsdf_parsed *parsed, const char *name)
{
    idmr_material material = parsed->material;
    if (parsed->texture) {
        const char *written;
        xmlNodePtr filename = mitsuba_prop_find(parsed->texture, "filename");
        if (mitsuba_prop_string(parsed->texture, "filename", NULL, &written))
            return -1;
        char *path = mitsuba_resolve_path(ld, filename, written);
        int texture = read_texture(ld->s, path);
        free(path);
        if (texture < 0)
            return mitsuba_fail_prefix(parsed->texture);
        material.texture = texture;
        memcpy(material.reflectance, ld->s->textures[texture].mean, sizeof material.reflectance);
    }
    return (int)scene_add_material(ld->s, name, parsed->type, &material);
}

int mitsuba_bsdf_by_id(loader *ld, mitsuba_id *entry)
{
    if (entry->material >= 0)
        return entry->material;
    if (!entry->bsdf)
        return mitsuba_fail(entry->node, "'%s' is not a bsdf", entry->id);
    entry->material = mitsuba_bsdf_add(ld, entry->bsdf, entry->id);
    return entry->material;
}

int mitsuba_bsdf_default(loader *ld)
{
    if (ld->default_material < 0) {
        idmr_material material;
        memset(&material, 0, sizeof material);
        material.kind = IDMR_MATERIAL_DIFFUSE;
        material.reflectance[0] = material.reflectance[1] = material.reflectance[2] = 0.5f;
        material.int_ior = material.ext_ior = 1.0f;
        material.texture = -1;
        ld->default_material = (int)scene_add_material(ld->s, "default", "diffuse", &material);
    }
    return ld->default_material;
}
