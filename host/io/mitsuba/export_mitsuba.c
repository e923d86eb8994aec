/* export_mitsuba.c — a scene as a Mitsuba 3 document (version 3.0.0), the inverse of the
 * loader's mapping (io/mitsuba/mitsuba_bsdf.c, mitsuba_emitter.c, mitsuba_sensor.c), so that
 * reading it back gives the same materials, lights and camera:
 *
 *   camera        <sensor type="perspective">: fov and fov_axis as read, to_world a matrix whose
 *                 columns are (-right, up, forward, origin) (Mitsuba's camera +x is the image's
 *                 left), film width × height
 *   DIFFUSE       diffuse, reflectance (an rgb, or a bitmap of the texture's file)
 *   GLOSSY        black diffuse part: roughconductor (material none, specular_reflectance,
 *                 ggx alpha); else roughplastic: diffuse_reflectance, specular_reflectance,
 *                 int_ior, ext_ior, ggx alpha; but the smooth plastic where alpha is below
 *                 IDMR_MIN_GLOSSY_ROUGHNESS, the roughness idmr simulates such a plastic with:
 *                 its base's Fresnel factors are the smooth interface's for any alpha
 *                 (kernels/lib/materials.h, brdf), so a near-smooth plastic renders as Mitsuba's
 *                 smooth plastic does (within 0.7 % on the pbrt-v4 coffee maker's floor),
 *                 while Mitsuba's roughplastic at alpha 0.001 renders it 0.9-1.8 % darker than
 *                 its own smooth plastic (its tabulated rough transmittance). Read back, such a
 *                 plastic has alpha 0, which idmr simulates alike.
 *   MIRROR        conductor, material none, specular_reflectance
 *   DIELECTRIC    dielectric or thindielectric, int_ior and ext_ior
 *   TWOSIDED      a twosided bsdf around the above; not around a dielectric, which is two-sided
 *                 anyway (Mitsuba 3 refuses to wrap a transmitting bsdf)
 *   mesh          <shape type="ply"> naming its world-space PLY (face_normals where it was
 *                 written without normals), the material by <ref>, an area emitter inside
 *   lights        point (position, intensity), spot (to_world with +z along the axis,
 *                 cutoff_angle, beam_width), directional (direction, irradiance), constant (a
 *                 1 × 1 environment) or envmap (the map written as <folder>/environment.exr, its
 *                 rotation as to_world), placed among the shapes so that they are read back in
 *                 the scene's order of lights.
 * Every number is written so that it reads back as the same float. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/export_internal.h"
#include "io/image.h"

#define INDENT "    "

/* `value` with the characters XML gives a meaning escaped, as an attribute value. */
static void put_attribute(export_text *t, const char *value)
{
    for (const char *c = value; *c; c++) {
        switch (*c) {
        case '&': export_printf(t, "&amp;"); break;
        case '<': export_printf(t, "&lt;"); break;
        case '>': export_printf(t, "&gt;"); break;
        case '"': export_printf(t, "&quot;"); break;
        default: export_printf(t, "%c", *c);
        }
    }
}

static void put_string(export_text *t, const char *indent, const char *name, const char *value)
{
    export_printf(t, "%s<string name=\"%s\" value=\"", indent, name);
    put_attribute(t, value);
    export_printf(t, "\"/>\n");
}

static void put_float(export_text *t, const char *indent, const char *name, double value)
{
    char b[32];
    export_printf(t, "%s<float name=\"%s\" value=\"%s\"/>\n", indent, name, export_float(b, value));
}

/* <tag name="name" value="x, y, z"/> (tag: rgb, point, vector). */
static void put_triple(export_text *t, const char *indent, const char *tag, const char *name,
                       const float v[3])
{
    char x[32], y[32], z[32];
    export_printf(t, "%s<%s name=\"%s\" value=\"%s, %s, %s\"/>\n", indent, tag, name,
                  export_float(x, v[0]), export_float(y, v[1]), export_float(z, v[2]));
}

/* <transform name="to_world"> of a row-major 4 × 4 matrix. */
static void put_matrix(export_text *t, const char *indent, const double m[16])
{
    char b[32];
    export_printf(t, "%s<transform name=\"to_world\">\n%s" INDENT "<matrix value=\"", indent,
                  indent);
    for (int i = 0; i < 16; i++)
        export_printf(t, "%s%s", i ? " " : "", export_float(b, m[i]));
    export_printf(t, "\"/>\n%s</transform>\n", indent);
}

/* A reflectance: an rgb, or a bitmap of the material's texture. */
static void put_reflectance(const export_job *job, export_text *t, const char *indent,
                            const char *name, const idmr_material *m)
{
    if (m->texture < 0 || (size_t)m->texture >= job->s->texture_count) {
        put_triple(t, indent, "rgb", name, m->reflectance);
        return;
    }
    export_printf(t, "%s<texture type=\"bitmap\" name=\"%s\">\n", indent, name);
    char inner[64];
    snprintf(inner, sizeof inner, "%s" INDENT, indent);
    put_string(t, inner, "filename", job->texture_files[m->texture]);
    export_printf(t, "%s</texture>\n", indent);
}

/* A glossy material with a diffuse part written as Mitsuba's smooth plastic (above). */
static int plastic_is_smooth(const idmr_material *m)
{
    return m->roughness < IDMR_MIN_GLOSSY_ROUGHNESS;
}

static void put_bsdf_body(const export_job *job, export_text *t, const char *indent,
                          const idmr_material *m)
{
    int black = m->texture < 0 && m->reflectance[0] == 0.0f && m->reflectance[1] == 0.0f &&
                m->reflectance[2] == 0.0f;
    switch (m->kind) {
    case IDMR_MATERIAL_GLOSSY:
        if (black) {
            put_string(t, indent, "material", "none");
            put_triple(t, indent, "rgb", "specular_reflectance", m->specular);
        } else {
            put_reflectance(job, t, indent, "diffuse_reflectance", m);
            put_triple(t, indent, "rgb", "specular_reflectance", m->specular);
            put_float(t, indent, "int_ior", m->int_ior);
            put_float(t, indent, "ext_ior", m->ext_ior);
        }
        if (black || !plastic_is_smooth(m)) {
            put_string(t, indent, "distribution", "ggx");
            put_float(t, indent, "alpha", m->roughness);
        }
        break;
    case IDMR_MATERIAL_MIRROR:
        put_string(t, indent, "material", "none");
        put_triple(t, indent, "rgb", "specular_reflectance", m->specular);
        break;
    case IDMR_MATERIAL_DIELECTRIC:
        put_float(t, indent, "int_ior", m->int_ior);
        put_float(t, indent, "ext_ior", m->ext_ior);
        break;
    default:
        put_reflectance(job, t, indent, "reflectance", m);
    }
}

static const char *bsdf_type(const idmr_material *m)
{
    int black = m->texture < 0 && m->reflectance[0] == 0.0f && m->reflectance[1] == 0.0f &&
                m->reflectance[2] == 0.0f;
    switch (m->kind) {
    case IDMR_MATERIAL_GLOSSY:
        return black ? "roughconductor" : plastic_is_smooth(m) ? "plastic" : "roughplastic";
    case IDMR_MATERIAL_MIRROR:
        return "conductor";
    case IDMR_MATERIAL_DIELECTRIC:
        return (m->flags & IDMR_MATERIAL_THIN) ? "thindielectric" : "dielectric";
    default:
        return "diffuse";
    }
}

static void put_material(const export_job *job, export_text *t, size_t index)
{
    const idmr_material *m = &job->s->materials[index];
    const char *id = job->material_names[index];
    int twosided = (m->flags & IDMR_MATERIAL_TWOSIDED) && m->kind != IDMR_MATERIAL_DIELECTRIC;
    const char *indent = twosided ? INDENT INDENT INDENT : INDENT INDENT;
    if (twosided) {
        export_printf(t, INDENT "<bsdf type=\"twosided\" id=\"%s\">\n", id);
        export_printf(t, INDENT INDENT "<bsdf type=\"%s\">\n", bsdf_type(m));
    } else {
        export_printf(t, INDENT "<bsdf type=\"%s\" id=\"%s\">\n", bsdf_type(m), id);
    }
    put_bsdf_body(job, t, indent, m);
    if (twosided)
        export_printf(t, INDENT INDENT "</bsdf>\n");
    export_printf(t, INDENT "</bsdf>\n");
}

static void put_sensor(const export_job *job, export_text *t)
{
    const scene *s = job->s;
    if (!s->has_camera)
        return;
    double right[3], up[3], forward[3], origin[3];
    export_camera_frame(&s->camera, right, up, forward, origin);
    double m[16];
    for (int k = 0; k < 3; k++) {
        m[4 * k + 0] = -right[k];
        m[4 * k + 1] = up[k];
        m[4 * k + 2] = forward[k];
        m[4 * k + 3] = origin[k];
    }
    m[12] = m[13] = m[14] = 0.0;
    m[15] = 1.0;
    double fov = s->camera_info.fov_degrees;
    const char *axis = s->camera_info.fov_axis;
    if (!axis[0] || !(fov > 0.0)) { /* not recorded: the horizontal angle of the frame */
        fov = 2.0 * atan(s->camera.tan_half_x) * 180.0 / M_PI;
        axis = "x";
    }
    export_printf(t, INDENT "<sensor type=\"perspective\">\n");
    put_float(t, INDENT INDENT, "fov", fov);
    put_string(t, INDENT INDENT, "fov_axis", axis);
    put_matrix(t, INDENT INDENT, m);
    export_printf(t,
                  INDENT INDENT "<film type=\"hdrfilm\">\n" INDENT INDENT INDENT
                                "<integer name=\"width\" value=\"%u\"/>\n" INDENT INDENT INDENT
                                "<integer name=\"height\" value=\"%u\"/>\n" INDENT INDENT
                                "</film>\n" INDENT "</sensor>\n",
                  s->camera.width, s->camera.height);
}

/* The environment: a constant for a 1 × 1 map, else the map as an EXR in the folder. */
static int put_environment(export_job *job, export_text *t)
{
    const scene_environment *e = &job->s->environment;
    if (e->width == 1 && e->height == 1) {
        export_printf(t, INDENT "<emitter type=\"constant\">\n");
        put_triple(t, INDENT INDENT, "rgb", "radiance", e->rgb);
        export_printf(t, INDENT "</emitter>\n");
        return 0;
    }
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/environment.exr", job->staging);
    if (image_write_rgb_float(path, e->width, e->height, e->rgb))
        return -1;
    size_t length = strlen(job->folder_name) + 32;
    free(job->environment_file);
    job->environment_file = xmalloc(length);
    snprintf(job->environment_file, length, "%s/environment.exr", job->folder_name);
    double m[16] = {0};
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 3; col++)
            m[4 * row + col] = e->to_world[3 * row + col];
    m[15] = 1.0;
    export_printf(t, INDENT "<emitter type=\"envmap\">\n");
    put_string(t, INDENT INDENT, "filename", job->environment_file);
    put_matrix(t, INDENT INDENT, m);
    export_printf(t, INDENT "</emitter>\n");
    return 0;
}

/* A light that is not an area light. */
static int put_light(export_job *job, export_text *t, const idmr_light *l)
{
    switch (l->kind) {
    case IDMR_LIGHT_POINT:
        export_printf(t, INDENT "<emitter type=\"point\">\n");
        put_triple(t, INDENT INDENT, "point", "position", l->position);
        put_triple(t, INDENT INDENT, "rgb", "intensity", l->emission);
        break;
    case IDMR_LIGHT_SPOT: {
        double axis[3] = {l->direction[0], l->direction[1], l->direction[2]}, x[3], y[3];
        export_frame_around(axis, x, y);
        double m[16] = {x[0], y[0], axis[0], l->position[0], x[1], y[1], axis[1], l->position[1],
                        x[2], y[2], axis[2], l->position[2], 0,    0,    0,       1};
        double cutoff = acos(fmin(1.0, fmax(-1.0, l->cos_cutoff))) * 180.0 / M_PI;
        double beam = acos(fmin(1.0, fmax(-1.0, l->cos_falloff_start))) * 180.0 / M_PI;
        export_printf(t, INDENT "<emitter type=\"spot\">\n");
        put_matrix(t, INDENT INDENT, m);
        put_float(t, INDENT INDENT, "cutoff_angle", cutoff);
        put_float(t, INDENT INDENT, "beam_width", fmin(beam, cutoff));
        put_triple(t, INDENT INDENT, "rgb", "intensity", l->emission);
        break;
    }
    case IDMR_LIGHT_DIRECTIONAL:
        export_printf(t, INDENT "<emitter type=\"directional\">\n");
        put_triple(t, INDENT INDENT, "vector", "direction", l->direction);
        put_triple(t, INDENT INDENT, "rgb", "irradiance", l->emission);
        break;
    case IDMR_LIGHT_ENVIRONMENT:
        return put_environment(job, t);
    default:
        return 0;
    }
    export_printf(t, INDENT "</emitter>\n");
    return 0;
}

static void put_shape(const export_job *job, export_text *t, size_t m)
{
    const scene_mesh *mesh = &job->s->meshes[m];
    export_printf(t, INDENT "<shape type=\"ply\" id=\"%s\">\n", job->mesh_names[m]);
    put_string(t, INDENT INDENT, "filename", job->mesh_files[m]);
    if (!mesh->normals || mesh->flat_normals)
        export_printf(t, INDENT INDENT "<boolean name=\"face_normals\" value=\"true\"/>\n");
    if (mesh->material < job->s->material_count)
        export_printf(t, INDENT INDENT "<ref id=\"%s\"/>\n", job->material_names[mesh->material]);
    if (mesh->light >= 0 && (size_t)mesh->light < job->s->light_count) {
        export_printf(t, INDENT INDENT "<emitter type=\"area\">\n");
        put_triple(t, INDENT INDENT INDENT, "rgb", "radiance",
                   job->s->lights[mesh->light].emission);
        export_printf(t, INDENT INDENT "</emitter>\n");
    }
    export_printf(t, INDENT "</shape>\n");
}

int export_mitsuba(export_job *job, export_text *t)
{
    const scene *s = job->s;
    export_printf(t, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
                     "<!-- Written by idmr convert: every mesh is a world-space PLY in ");
    put_attribute(t, job->folder_name);
    export_printf(t, "/. -->\n<scene version=\"3.0.0\">\n");
    put_sensor(job, t);
    for (size_t i = 0; i < s->material_count; i++)
        if (job->material_names[i])
            put_material(job, t, i);
    /* Shapes in mesh order, each light that is not an area light written before the first
     * shape whose area light comes after it: the loader numbers lights in document order. */
    size_t next_light = 0;
    for (size_t m = 0; m <= s->mesh_count; m++) {
        int light = m < s->mesh_count && job->mesh_names[m] ? s->meshes[m].light : -1;
        if (m < s->mesh_count && !job->mesh_names[m])
            continue;
        size_t until = m == s->mesh_count ? s->light_count : light >= 0 ? (size_t)light : 0;
        for (; next_light < until; next_light++)
            if (s->lights[next_light].kind != IDMR_LIGHT_AREA &&
                put_light(job, t, &s->lights[next_light]))
                return -1;
        if (light >= 0 && next_light == (size_t)light)
            next_light++;
        if (m < s->mesh_count)
            put_shape(job, t, m);
    }
    export_printf(t, "</scene>\n");
    return 0;
}
