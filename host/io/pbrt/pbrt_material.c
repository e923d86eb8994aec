/* pbrt_material.c — Texture, Material and MakeNamedMaterial → idmr materials.
 *
 * pbrt-v4's materials shade both sides of a surface, so every material but the dielectrics is
 * IDMR_MATERIAL_TWOSIDED. The mapping onto idmr's four kinds (idmr/material.h), with a warning
 * (once, naming file and line) where it loses something:
 *   diffuse              DIFFUSE     reflectance (default 0.5; an imagemap texture is read)
 *   coateddiffuse        GLOSSY      reflectance under a GGX coat: roughness (uroughness and
 *                                    vroughness: their geometric mean), eta as the coat's IOR;
 *                                    thickness, albedo, g not simulated (warned when given)
 *   conductor            MIRROR      smooth (alpha < 1e-3, pbrt's test), else GLOSSY with black
 *                                    diffuse; specular = normal-incidence Fresnel reflectance
 *                                    from eta and k (named metal spectra metal-X-eta/-k by a
 *                                    table of linear sRGB colours; rgb or sampled ones by the
 *                                    Fresnel formula), or `reflectance` when given
 *   coatedconductor      as conductor (conductor.eta, conductor.k, reflectance,
 *                        conductor.roughness); the dielectric coat is dropped (warned)
 *   dielectric           DIELECTRIC  eta (a number, or a named glass spectrum by its IOR at the
 *                                    d line); rough ones as smooth (warned)
 *   thindielectric       DIELECTRIC with THIN
 *   diffusetransmission  DIFFUSE     reflectance (default 0.25); the transmission is dropped
 *                                    (warned)
 *   interface, none, ""  DIELECTRIC with IOR 1 on both sides and THIN: light passes straight
 *                                    through, as through pbrt's invisible boundary
 *   mix                  the material of larger weight (`amount` < 0.5: the first); warned
 *   measured, hair, subsurface  DIFFUSE 0.5 (warned)
 * Roughness is remapped to a GGX alpha as pbrt-v4 does (alpha = sqrt(roughness)) unless
 * remaproughness is false. Float textures for roughness are not read (warned; the default is
 * used). A texture other than imagemap stands for a constant (its "value", "tex", else 0.5;
 * warned). */
#include "io/pbrt/pbrt_loader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image.h"
#include "core/spectrum.h"

typedef struct named_rgb {
    const char *name;
    float rgb[3];
} named_rgb;

/* Normal-incidence reflectance of pbrt-v4's named metals in linear sRGB (Ag, Al, Au, Cu: the
 * approximations tabulated in Real-Time Rendering, 4th ed., Table 9.2; CuZn brass; MgO and TiO2
 * from their refractive indices). */
static const named_rgb metals[] = {
    {"Ag", {0.972f, 0.960f, 0.915f}},   {"Al", {0.913f, 0.922f, 0.924f}},
    {"Au", {1.000f, 0.782f, 0.344f}},   {"Cu", {0.955f, 0.638f, 0.538f}},
    {"CuZn", {0.910f, 0.778f, 0.423f}}, {"MgO", {0.073f, 0.072f, 0.071f}},
    {"TiO2", {0.190f, 0.175f, 0.160f}},
};

typedef struct named_ior {
    const char *name;
    double ior;
} named_ior;

/* pbrt-v4's named glass spectra by their refractive index at the d line (587.6 nm). */
static const named_ior glasses[] = {
    {"glass-BK7", 1.5168},  {"glass-BAF10", 1.6700}, {"glass-FK51A", 1.4866},
    {"glass-LASF9", 1.8503}, {"glass-F5", 1.6034},   {"glass-F10", 1.6200},
    {"glass-F11", 1.6209},
};

/* The texture `name`: float and spectrum textures have names of their own in pbrt, so a
 * spectrum texture is looked for first (colours are what the materials read), then a float one. */
static const pbrt_texture *find_texture(const pbrt_loader *ld, const char *name)
{
    for (int want_float = 0; want_float < 2; want_float++)
        for (size_t i = ld->texture_count; i-- > 0;)
            if (ld->textures[i].is_float == want_float && strcmp(ld->textures[i].name, name) == 0)
                return &ld->textures[i];
    return NULL;
}

int pbrt_read_texture(pbrt_loader *ld, const char *file, int line, const char *name,
                      const char *type, const char *class_name, pbrt_params *params)
{
    if (strcmp(type, "spectrum") && strcmp(type, "float") && strcmp(type, "color"))
        return pbrt_fail(file, line, "Texture \"%s\": type '%s' is neither spectrum nor float",
                         name, type);
    pbrt_texture texture;
    memset(&texture, 0, sizeof texture);
    texture.is_float = strcmp(type, "float") == 0;
    texture.value[0] = texture.value[1] = texture.value[2] = 0.5f;
    if (strcmp(class_name, "imagemap") == 0) {
        const char *written;
        if (pbrt_param_string(file, params, "filename", NULL, &written))
            return -1;
        if (!written)
            return pbrt_fail(file, line, "Texture \"%s\": an imagemap needs a filename", name);
        texture.file = pbrt_resolve_path(ld, written);
        static const char *const quiet[] = {"filter", "maxanisotropy", "wrap", "encoding",
                                            "mapping", NULL};
        for (size_t i = 0; quiet[i]; i++)
            pbrt_param_find(params, quiet[i]);
        double scale, uscale, vscale;
        int invert;
        if (pbrt_param_float(file, params, "scale", 1.0, &scale) ||
            pbrt_param_bool(file, params, "invert", 0, &invert) ||
            pbrt_param_float(file, params, "uscale", 1.0, &uscale) ||
            pbrt_param_float(file, params, "vscale", 1.0, &vscale)) {
            free(texture.file);
            return -1;
        }
        if (scale != 1.0 || invert)
            pbrt_warn(file, line, "Texture \"imagemap\": scale and invert are not applied");
        if (uscale != 1.0 || vscale != 1.0)
            pbrt_warn(file, line, "Texture \"imagemap\": uscale/vscale are not applied");
        if (texture.is_float)
            pbrt_warn(file, line, "Texture \"%s\": float image textures are not read: 0.5 is used",
                      name);
    } else {
        static const char *const value_names[] = {"value", "tex", "tex1", NULL};
        for (size_t i = 0; value_names[i]; i++) {
            pbrt_param *p = pbrt_param_find(params, value_names[i]);
            if (p && p->number_count == 1)
                texture.value[0] = texture.value[1] = texture.value[2] = (float)p->numbers[0];
            else if (p && p->number_count == 3 && strcmp(p->type, "rgb") == 0)
                for (int k = 0; k < 3; k++)
                    texture.value[k] = (float)p->numbers[k];
            if (p)
                break;
        }
        for (size_t i = 0; i < params->count; i++)
            params->items[i].used = 1;
        if (strcmp(class_name, "constant") != 0)
            pbrt_warn(file, line,
                      "Texture \"%s\": idmr reads imagemap textures only: a constant (%g %g %g) "
                      "stands for it",
                      class_name, texture.value[0], texture.value[1], texture.value[2]);
    }
    texture.name = xstrdup(name);
    texture.class_name = xstrdup(class_name);
    ld->textures = xrealloc(ld->textures, (ld->texture_count + 1) * sizeof *ld->textures);
    ld->textures[ld->texture_count++] = texture;
    return 0;
}

/* The d-line IOR of a named glass, or 0. */
static double glass_ior(const char *name)
{
    for (size_t i = 0; i < sizeof glasses / sizeof *glasses; i++)
        if (strcmp(name, glasses[i].name) == 0)
            return glasses[i].ior;
    return 0.0;
}

int pbrt_material_color(pbrt_loader *ld, const char *file, pbrt_params *params,
                        const char *name, const float fallback[3], float out[3],
                        char **texture_file)
{
    pbrt_param *p = pbrt_param_find(params, name);
    for (int k = 0; k < 3; k++)
        out[k] = fallback[k];
    if (!p)
        return 0;
    if (strcmp(p->type, "rgb") == 0 || strcmp(p->type, "color") == 0) {
        for (int k = 0; k < 3; k++)
            out[k] = (float)p->numbers[k];
    } else if (strcmp(p->type, "float") == 0) {
        if (p->number_count != 1)
            return pbrt_fail(file, p->line, "\"float %s\": one value expected", name);
        out[0] = out[1] = out[2] = (float)p->numbers[0];
    } else if (strcmp(p->type, "spectrum") == 0) {
        if (p->number_count == 1)
            out[0] = out[1] = out[2] = (float)p->numbers[0];
        else if (p->number_count >= 2) {
            if (pbrt_sampled_spectrum(file, p, name, SPECTRUM_REFLECTANCE, out))
                return -1;
        } else {
            pbrt_warn(file, p->line,
                      "\"spectrum %s\" [ \"%s\" ]: named or file spectra are not read here: "
                      "%g is used",
                      name, p->strings[0], fallback[0]);
        }
    } else if (strcmp(p->type, "blackbody") == 0) {
        pbrt_warn(file, p->line, "\"blackbody %s\" as a reflectance: %g is used", name,
                  fallback[0]);
    } else if (strcmp(p->type, "texture") == 0) {
        const pbrt_texture *t = find_texture(ld, p->strings[0]);
        if (!t)
            return pbrt_fail(file, p->line, "\"texture %s\": no texture named '%s'", name,
                             p->strings[0]);
        for (int k = 0; k < 3; k++)
            out[k] = t->value[k];
        if (t->file && !t->is_float) {
            if (texture_file) {
                free(*texture_file);
                *texture_file = xstrdup(t->file);
            } else {
                pbrt_warn(file, p->line,
                          "\"texture %s\": an image texture is read only for a reflectance: "
                          "0.5 is used",
                          name);
            }
        }
    } else {
        return pbrt_fail(file, p->line, "\"%s %s\": a colour is rgb, spectrum, float or texture",
                         p->type, name);
    }
    for (int k = 0; k < 3; k++)
        if (!(out[k] >= 0.0f))
            out[k] = 0.0f;
    return 0;
}

/* A float parameter that may also be given as a texture (not read: warned, fallback). */
static int float_or_texture(const char *file, pbrt_params *params, const char *name,
                            double fallback, double *out)
{
    pbrt_param *p = pbrt_param_find(params, name);
    *out = fallback;
    if (p && strcmp(p->type, "texture") == 0) {
        pbrt_warn(file, p->line, "\"texture %s\": float textures are not read: %g is used", name,
                  fallback);
        return 0;
    }
    return pbrt_param_float(file, params, name, fallback, out);
}

/* GGX alpha from roughness / uroughness / vroughness (with `prefix`, e.g. "interface."). */
static int material_alpha(const char *file, pbrt_params *params, const char *prefix,
                          double *alpha)
{
    char name[64], uname[64], vname[64];
    double r, u, v;
    int remap;
    snprintf(name, sizeof name, "%sroughness", prefix);
    snprintf(uname, sizeof uname, "%suroughness", prefix);
    snprintf(vname, sizeof vname, "%svroughness", prefix);
    if (float_or_texture(file, params, name, 0.0, &r) ||
        float_or_texture(file, params, uname, r, &u) ||
        float_or_texture(file, params, vname, r, &v) ||
        pbrt_param_bool(file, params, "remaproughness", 1, &remap))
        return -1;
    if (u < 0.0 || v < 0.0)
        return pbrt_fail(file, pbrt_param_find(params, name) ? pbrt_param_find(params, name)->line : 0,
                         "roughness must not be negative");
    if (remap) {
        u = sqrt(u);
        v = sqrt(v);
    }
    *alpha = sqrt(u * v);
    return 0;
}

/* Normal-incidence Fresnel reflectance of a conductor with complex index eta + i k. */
static float conductor_f0(double eta, double k)
{
    return (float)(((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k));
}

/* The named metal of "metal-X-eta" / "metal-X-k", or NULL. */
static const named_rgb *named_metal(const char *spectrum)
{
    if (strncmp(spectrum, "metal-", 6) != 0)
        return NULL;
    const char *element = spectrum + 6;
    const char *dash = strchr(element, '-');
    size_t length = dash ? (size_t)(dash - element) : strlen(element);
    for (size_t i = 0; i < sizeof metals / sizeof *metals; i++)
        if (strlen(metals[i].name) == length && strncmp(element, metals[i].name, length) == 0)
            return &metals[i];
    return NULL;
}

/* The conductor's normal-incidence colour from `reflectance`, else eta and k (with prefix). */
static int conductor_color(pbrt_loader *ld, const char *file, int line, pbrt_params *params,
                           const char *prefix, float f0[3])
{
    char eta_name[64], k_name[64];
    snprintf(eta_name, sizeof eta_name, "%seta", prefix);
    snprintf(k_name, sizeof k_name, "%sk", prefix);
    if (pbrt_param_find(params, "reflectance")) {
        static const float one[3] = {1, 1, 1};
        pbrt_param_find(params, eta_name);
        pbrt_param_find(params, k_name);
        return pbrt_material_color(ld, file, params, "reflectance", one, f0, NULL);
    }
    pbrt_param *eta = pbrt_param_find(params, eta_name), *k = pbrt_param_find(params, k_name);
    const named_rgb *metal = NULL;
    if (!eta && !k)
        metal = named_metal("metal-Cu-eta"); /* pbrt-v4's default conductor is copper */
    else if (eta && eta->string_count)
        metal = named_metal(eta->strings[0]);
    else if (!eta && k && k->string_count)
        metal = named_metal(k->strings[0]);
    if (metal) {
        memcpy(f0, metal->rgb, sizeof(float) * 3);
        return 0;
    }
    if ((eta && eta->string_count) || (k && k->string_count)) {
        pbrt_warn(file, line,
                  "conductor: spectrum '%s' is not a metal idmr knows: a grey reflectance of 0.9 "
                  "is used",
                  eta && eta->string_count ? eta->strings[0] : k->strings[0]);
        f0[0] = f0[1] = f0[2] = 0.9f;
        return 0;
    }
    static const float one[3] = {1, 1, 1}, zero[3] = {0, 0, 0};
    float e[3], kk[3];
    if (pbrt_material_color(ld, file, params, eta_name, one, e, NULL) ||
        pbrt_material_color(ld, file, params, k_name, zero, kk, NULL))
        return -1;
    for (int c = 0; c < 3; c++)
        f0[c] = conductor_f0(e[c], kk[c]);
    return 0;
}

static int read_conductor(pbrt_loader *ld, const char *file, int line, pbrt_params *params,
                          const char *prefix, idmr_material *m)
{
    float f0[3];
    double alpha;
    if (conductor_color(ld, file, line, params, prefix, f0) ||
        material_alpha(file, params, prefix, &alpha))
        return -1;
    m->kind = alpha < 1e-3 ? IDMR_MATERIAL_MIRROR : IDMR_MATERIAL_GLOSSY;
    m->roughness = alpha < 1e-3 ? 0.0f : (float)alpha;
    for (int k = 0; k < 3; k++) {
        m->reflectance[k] = 0.0f;
        m->specular[k] = f0[k];
    }
    return 0;
}

/* An index of refraction: a number, or a named glass spectrum. */
static int read_eta(const char *file, int line, pbrt_params *params, const char *name,
                    double *out)
{
    pbrt_param *p = pbrt_param_find(params, name);
    *out = 1.5;
    if (!p)
        return 0;
    if (strcmp(p->type, "spectrum") == 0) {
        if (p->string_count) {
            double ior = glass_ior(p->strings[0]);
            if (ior == 0.0) {
                pbrt_warn(file, p->line, "spectrum '%s' is not a glass idmr knows: eta 1.5 is used",
                          p->strings[0]);
                ior = 1.5;
            }
            *out = ior;
        } else if (p->number_count == 1) {
            *out = p->numbers[0];
        } else {
            /* A sampled IOR: its value nearest the d line (587.6 nm). */
            size_t best = 0;
            for (size_t i = 0; i < p->number_count / 2; i++)
                if (fabs(p->numbers[2 * i] - 587.6) < fabs(p->numbers[2 * best] - 587.6))
                    best = i;
            *out = p->numbers[2 * best + 1];
            pbrt_warn(file, p->line, "a dispersive eta is read at 587.6 nm (%g)", *out);
        }
    } else if (pbrt_param_float(file, params, name, 1.5, out)) {
        return -1;
    }
    if (!(*out > 0.0))
        return pbrt_fail(file, p->line, "eta must be positive");
    return 0;
}

static void warn_given(const char *file, int line, pbrt_params *params, const char *type,
                       const char *const *names)
{
    for (size_t i = 0; names[i]; i++)
        if (pbrt_param_find(params, names[i]))
            pbrt_warn(file, line, "%s: \"%s\" is not simulated by idmr", type, names[i]);
}

/* The material parameters every type may have. */
static void common_params(const char *file, int line, pbrt_params *params, const char *type)
{
    if (pbrt_param_find(params, "displacement"))
        pbrt_warn(file, line, "%s: displacement is not simulated by idmr", type);
    if (pbrt_param_find(params, "normalmap"))
        pbrt_warn(file, line, "%s: normalmap is not simulated by idmr", type);
}

/* Reads material `type` into m; *texture_file gets an image for the reflectance. */
static int read_material_type(pbrt_loader *ld, const char *file, int line, const char *type,
                              pbrt_params *params, idmr_material *m, char **texture_file,
                              int depth)
{
    static const float half[3] = {0.5f, 0.5f, 0.5f}, quarter[3] = {0.25f, 0.25f, 0.25f};
    memset(m, 0, sizeof *m);
    m->int_ior = m->ext_ior = 1.0f;
    m->texture = -1;
    m->flags = IDMR_MATERIAL_TWOSIDED;
    common_params(file, line, params, type);
    if (strcmp(type, "diffuse") == 0) {
        m->kind = IDMR_MATERIAL_DIFFUSE;
        return pbrt_material_color(ld, file, params, "reflectance", half, m->reflectance,
                                   texture_file);
    }
    if (strcmp(type, "coateddiffuse") == 0) {
        static const char *const lost[] = {"thickness", "albedo", "g", NULL};
        double alpha, eta;
        m->kind = IDMR_MATERIAL_GLOSSY;
        if (pbrt_material_color(ld, file, params, "reflectance", half, m->reflectance,
                                texture_file) ||
            material_alpha(file, params, "", &alpha) || read_eta(file, line, params, "eta", &eta))
            return -1;
        warn_given(file, line, params, "coateddiffuse", lost);
        pbrt_param_find(params, "maxdepth");
        pbrt_param_find(params, "nsamples");
        m->specular[0] = m->specular[1] = m->specular[2] = 1.0f;
        m->roughness = (float)alpha;
        m->int_ior = (float)eta;
        return 0;
    }
    if (strcmp(type, "conductor") == 0)
        return read_conductor(ld, file, line, params, "", m);
    if (strcmp(type, "coatedconductor") == 0) {
        double alpha, eta;
        if (read_conductor(ld, file, line, params, "conductor.", m) ||
            material_alpha(file, params, "interface.", &alpha) ||
            read_eta(file, line, params, "interface.eta", &eta))
            return -1;
        static const char *const quiet[] = {"thickness", "albedo", "g", "maxdepth", "nsamples",
                                            NULL};
        for (size_t i = 0; quiet[i]; i++)
            pbrt_param_find(params, quiet[i]);
        pbrt_warn(file, line,
                  "coatedconductor: the dielectric coat is not simulated: the conductor beneath "
                  "is used");
        return 0;
    }
    if (strcmp(type, "dielectric") == 0 || strcmp(type, "thindielectric") == 0) {
        double eta, alpha = 0.0;
        m->kind = IDMR_MATERIAL_DIELECTRIC;
        m->flags = strcmp(type, "thindielectric") == 0 ? IDMR_MATERIAL_THIN : 0u;
        if (read_eta(file, line, params, "eta", &eta) ||
            (strcmp(type, "dielectric") == 0 && material_alpha(file, params, "", &alpha)))
            return -1;
        if (alpha >= 1e-3)
            pbrt_warn(file, line, "dielectric: a rough dielectric is treated as smooth");
        m->int_ior = (float)eta;
        m->specular[0] = m->specular[1] = m->specular[2] = 1.0f;
        return 0;
    }
    if (strcmp(type, "diffusetransmission") == 0) {
        float transmittance[3];
        double scale;
        m->kind = IDMR_MATERIAL_DIFFUSE;
        if (pbrt_material_color(ld, file, params, "reflectance", quarter, m->reflectance,
                                texture_file) ||
            pbrt_material_color(ld, file, params, "transmittance", quarter, transmittance, NULL) ||
            pbrt_param_float(file, params, "scale", 1.0, &scale))
            return -1;
        for (int k = 0; k < 3; k++)
            m->reflectance[k] = (float)fmin(1.0, m->reflectance[k] * scale);
        pbrt_warn(file, line,
                  "diffusetransmission: the transmitted part is not simulated: a diffuse "
                  "reflector");
        return 0;
    }
    if (strcmp(type, "interface") == 0 || strcmp(type, "none") == 0 || type[0] == '\0') {
        m->kind = IDMR_MATERIAL_DIELECTRIC;
        m->flags = IDMR_MATERIAL_THIN;
        m->specular[0] = m->specular[1] = m->specular[2] = 1.0f;
        return 0;
    }
    if (strcmp(type, "mix") == 0) {
        pbrt_param *materials = pbrt_param_find(params, "materials");
        double amount;
        if (!materials || strcmp(materials->type, "string") || materials->string_count != 2)
            return pbrt_fail(file, line, "mix: \"string materials\" must name two materials");
        if (float_or_texture(file, params, "amount", 0.5, &amount))
            return -1;
        const char *chosen = materials->strings[amount < 0.5 ? 0 : 1];
        int index = pbrt_find_material(ld, chosen);
        if (index < 0)
            return pbrt_fail(file, line, "mix: no material named '%s'", chosen);
        if (depth > 16)
            return pbrt_fail(file, line, "mix: materials mixed too deeply");
        pbrt_warn(file, line, "mix: not simulated: the material of the larger weight is used");
        *m = ld->materials[index].material;
        if (ld->materials[index].texture_file) {
            free(*texture_file);
            *texture_file = xstrdup(ld->materials[index].texture_file);
        }
        return 0;
    }
    if (strcmp(type, "measured") == 0 || strcmp(type, "hair") == 0 ||
        strcmp(type, "subsurface") == 0) {
        for (size_t i = 0; i < params->count; i++)
            params->items[i].used = 1;
        pbrt_warn(file, line, "material \"%s\" is not simulated by idmr: a diffuse 0.5 stands for it",
                  type);
        m->kind = IDMR_MATERIAL_DIFFUSE;
        memcpy(m->reflectance, half, sizeof half);
        return 0;
    }
    return pbrt_fail(file, line, "unknown material type '%s'", type);
}

int pbrt_read_material(pbrt_loader *ld, const char *file, int line, const char *name,
                       const char *type, pbrt_params *params)
{
    const char *material_type = type;
    if (!material_type && pbrt_param_string(file, params, "type", NULL, &material_type))
        return -1;
    if (!material_type)
        return pbrt_fail(file, line, "MakeNamedMaterial \"%s\": no \"string type\"", name);
    pbrt_material entry;
    memset(&entry, 0, sizeof entry);
    if (read_material_type(ld, file, line, material_type, params, &entry.material,
                           &entry.texture_file, 0)) {
        free(entry.texture_file);
        return -1;
    }
    char label[512];
    if (name)
        snprintf(label, sizeof label, "%s", name);
    else
        snprintf(label, sizeof label, "%s@%s:%d", material_type,
                 strrchr(file, '/') ? strrchr(file, '/') + 1 : file, line);
    entry.name = xstrdup(label);
    entry.type = xstrdup(material_type);
    entry.scene_index = -1;
    if (name)
        for (size_t i = 0; i < ld->material_count; i++)
            if (strcmp(ld->materials[i].name, name) == 0)
                pbrt_warn(file, line, "MakeNamedMaterial \"%s\": redefined (the later one is used)",
                          name);
    ld->materials = xrealloc(ld->materials, (ld->material_count + 1) * sizeof *ld->materials);
    ld->materials[ld->material_count] = entry;
    return (int)ld->material_count++;
}

int pbrt_find_material(const pbrt_loader *ld, const char *name)
{
    for (size_t i = ld->material_count; i-- > 0;)
        if (strcmp(ld->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

int pbrt_material_scene_index(pbrt_loader *ld, int index)
{
    if (index < 0) {
        if (ld->default_material < 0) {
            idmr_material m;
            memset(&m, 0, sizeof m);
            m.kind = IDMR_MATERIAL_DIFFUSE;
            m.reflectance[0] = m.reflectance[1] = m.reflectance[2] = 0.5f;
            m.int_ior = m.ext_ior = 1.0f;
            m.texture = -1;
            m.flags = IDMR_MATERIAL_TWOSIDED;
            ld->default_material = (int)scene_add_material(ld->s, "default", "diffuse", &m);
        }
        return ld->default_material;
    }
    pbrt_material *entry = &ld->materials[index];
    if (entry->scene_index >= 0)
        return entry->scene_index;
    idmr_material m = entry->material;
    if (entry->texture_file) {
        int texture = scene_find_texture(ld->s, entry->texture_file);
        if (texture < 0) {
            int width, height;
            float *rgb;
            if (image_read_rgb(entry->texture_file, &width, &height, &rgb))
                return error_prefix("material '%s'", entry->name);
            texture = scene_add_texture(ld->s, entry->texture_file, width, height, rgb);
        }
        m.texture = texture;
        memcpy(m.reflectance, ld->s->textures[texture].mean, sizeof m.reflectance);
    }
    entry->scene_index = (int)scene_add_material(ld->s, entry->name, entry->type, &m);
    return entry->scene_index;
}
