/* export_pbrt.c — a scene as a pbrt-v4 file (pbrt.org/fileformat-v4):
 *
 *   camera     `Transform` (the camera-from-world matrix, see put_camera), `Camera "perspective"`
 *              with fov the angle of the shorter image axis, `Film "rgb"` of the film's size
 *   WorldBegin
 *   materials  `MakeNamedMaterial`: DIFFUSE diffuse; GLOSSY with a diffuse part coateddiffuse
 *              (reflectance, roughness = GGX alpha with remaproughness false, eta = int/ext IOR),
 *              without one conductor ("rgb reflectance" = specular, roughness); MIRROR conductor
 *              with roughness 0; DIELECTRIC dielectric or thindielectric (eta = int/ext IOR); a
 *              texture becomes `Texture "..." "spectrum" "imagemap"` of its file
 *   meshes     `Shape "plymesh"` of the world-space PLY, after `NamedMaterial`, inside
 *              AttributeBegin/End with `AreaLightSource "diffuse" "rgb L"` for an emitter
 *   lights     point ("rgb I", from), spot ("rgb I", from, to, coneangle = the cutoff,
 *              conedeltaangle = cutoff - beam width), distant ("rgb L" = irradiance, from 0 to
 *              the direction of travel), infinite ("rgb L" for a constant; else the map resampled
 *              into pbrt-v4's equal-area octahedral square, <folder>/environment.exr, with the
 *              map's rotation baked in).
 * What pbrt-v4 cannot say as idmr simulates it: a glossy material's specular tint (coateddiffuse
 * has none) and one-sided materials (pbrt's reflect on both sides). pbrt's "rgb" emission is
 * scaled to the colour space's illuminant, so rgb (1, 1, 1) has luminance 1, as in Mitsuba. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/export_internal.h"
#include "io/image.h"

/* The equal-area square's resolution: at least 64, about the equirectangular map's height. */
#define PBRT_ENVIRONMENT_MIN 64
#define PBRT_ENVIRONMENT_MAX 2048

/* A string in pbrt's quotes: '"' and '\' escaped. */
static void put_quoted(export_text *t, const char *value)
{
    export_printf(t, "\"");
    for (const char *c = value; *c; c++)
        export_printf(t, "%s%c", *c == '"' || *c == '\\' ? "\\" : "", *c);
    export_printf(t, "\"");
}

/* "<type> <name>" [ x y z ] */
static void put_triple(export_text *t, const char *type, const char *name, const float v[3])
{
    char x[32], y[32], z[32];
    export_printf(t, " \"%s %s\" [ %s %s %s ]", type, name, export_float(x, v[0]),
                  export_float(y, v[1]), export_float(z, v[2]));
}

static void put_float(export_text *t, const char *name, double value)
{
    char b[32];
    export_printf(t, " \"float %s\" [ %s ]", name, export_float(b, value));
}

/* The camera. pbrt's camera space is left-handed: +x is the image's right, +y its up, +z the
 * viewing direction (raster x grows with camera x, raster y falls with camera y). The CTM at
 * `Camera` is camera-from-world, so with idmr's frame (right r, up u, forward f, origin o: an
 * orthonormal, right-handed set for an unmirrored camera) it is the matrix whose rows are
 * (r, -r.o), (u, -u.o), (f, -f.o), (0 0 0 1). `Transform` takes the 16 numbers column by
 * column (pbrt transposes them), so the translation comes last. The same matrix is what
 * `Scale -1 1 1` followed by `LookAt o  o+f  u` gives: LookAt's camera +x is u × f, the image's
 * left in a right-handed world, and the Scale turns it to the right. fov: pbrt's is the angle of
 * the shorter image axis. */
static void put_camera(const export_job *job, export_text *t)
{
    const scene *s = job->s;
    if (!s->has_camera) {
        export_printf(t, "# the input has no camera: pbrt's default one\n");
        return;
    }
    double r[3], u[3], f[3], o[3];
    export_camera_frame(&s->camera, r, u, f, o);
    double rows[3][3] = {{r[0], r[1], r[2]}, {u[0], u[1], u[2]}, {f[0], f[1], f[2]}};
    double translation[3];
    for (int i = 0; i < 3; i++)
        translation[i] = -(rows[i][0] * o[0] + rows[i][1] * o[1] + rows[i][2] * o[2]);
    char b[32];
    export_printf(t, "# camera from world; the same as Scale -1 1 1  LookAt");
    for (int k = 0; k < 9; k++) {
        double value = k < 3 ? o[k] : k < 6 ? o[k - 3] + f[k - 3] : u[k - 6];
        export_printf(t, " %s", export_float(b, value));
    }
    export_printf(t, "\nTransform [");
    for (int column = 0; column < 4; column++)
        for (int row = 0; row < 4; row++) {
            double value = row == 3 ? (column == 3 ? 1.0 : 0.0)
                           : column == 3 ? translation[row]
                                         : rows[row][column];
            export_printf(t, " %s", export_float(b, value));
        }
    export_printf(t, " ]\n");
    double shorter = s->camera.width <= s->camera.height ? s->camera.tan_half_x
                                                          : s->camera.tan_half_y;
    export_printf(t, "Camera \"perspective\"");
    put_float(t, "fov", 2.0 * atan(shorter) * 180.0 / M_PI);
    export_printf(t, "\n");
    export_printf(t, "Film \"rgb\" \"integer xresolution\" [ %u ] \"integer yresolution\" [ %u ]"
                     " \"string filename\" [ ",
                  s->camera.width, s->camera.height);
    char image[300];
    snprintf(image, sizeof image, "%s.exr", job->folder_name);
    put_quoted(t, image);
    export_printf(t, " ]\n");
}

/* The texture of material `index`, declared before its material: "<material name>:reflectance". */
static void put_texture(const export_job *job, export_text *t, size_t index)
{
    const idmr_material *m = &job->s->materials[index];
    export_printf(t, "Texture ");
    char name[300];
    snprintf(name, sizeof name, "%s:reflectance", job->material_names[index]);
    put_quoted(t, name);
    export_printf(t, " \"spectrum\" \"imagemap\" \"string filename\" [ ");
    put_quoted(t, job->texture_files[m->texture]);
    export_printf(t, " ]\n");
}

static int has_texture(const export_job *job, const idmr_material *m)
{
    return m->texture >= 0 && (size_t)m->texture < job->s->texture_count;
}

static void put_reflectance(const export_job *job, export_text *t, size_t index)
{
    const idmr_material *m = &job->s->materials[index];
    if (!has_texture(job, m)) {
        put_triple(t, "rgb", "reflectance", m->reflectance);
        return;
    }
    char name[300];
    snprintf(name, sizeof name, "%s:reflectance", job->material_names[index]);
    export_printf(t, " \"texture reflectance\" ");
    put_quoted(t, name);
}

static void put_material(const export_job *job, export_text *t, size_t index)
{
    const idmr_material *m = &job->s->materials[index];
    int black = !has_texture(job, m) && m->reflectance[0] == 0.0f &&
                m->reflectance[1] == 0.0f && m->reflectance[2] == 0.0f;
    if (has_texture(job, m) &&
        (m->kind == IDMR_MATERIAL_DIFFUSE || m->kind == IDMR_MATERIAL_GLOSSY))
        put_texture(job, t, index);
    export_printf(t, "MakeNamedMaterial ");
    put_quoted(t, job->material_names[index]);
    export_printf(t, "\n   ");
    switch (m->kind) {
    case IDMR_MATERIAL_GLOSSY:
        if (black) {
            export_printf(t, " \"string type\" [ \"conductor\" ]");
            put_triple(t, "rgb", "reflectance", m->specular);
        } else {
            export_printf(t, " \"string type\" [ \"coateddiffuse\" ]");
            put_reflectance(job, t, index);
            put_float(t, "eta", m->ext_ior > 0 ? m->int_ior / m->ext_ior : m->int_ior);
        }
        put_float(t, "roughness", m->roughness);
        export_printf(t, " \"bool remaproughness\" [ false ]");
        break;
    case IDMR_MATERIAL_MIRROR:
        export_printf(t, " \"string type\" [ \"conductor\" ]");
        put_triple(t, "rgb", "reflectance", m->specular);
        put_float(t, "roughness", 0.0);
        break;
    case IDMR_MATERIAL_DIELECTRIC:
        export_printf(t, " \"string type\" [ \"%s\" ]",
                      (m->flags & IDMR_MATERIAL_THIN) ? "thindielectric" : "dielectric");
        put_float(t, "eta", m->ext_ior > 0 ? m->int_ior / m->ext_ior : m->int_ior);
        break;
    default:
        export_printf(t, " \"string type\" [ \"diffuse\" ]");
        put_reflectance(job, t, index);
    }
    export_printf(t, "\n");
}

/* ---- the environment map in pbrt-v4's equal-area octahedral square ---- */

/* The direction of point (u, v) of the equal-area square (Clarberg's mapping, as pbrt-v4 lays it
 * out: the square's centre is +z, its corners -z). */
static void equal_area_direction(double u, double v, double w[3])
{
    double a = 2 * u - 1, b = 2 * v - 1;
    double signed_distance = 1 - (fabs(a) + fabs(b));
    double r = 1 - fabs(signed_distance);
    double phi = (r == 0 ? 1 : (fabs(b) - fabs(a)) / r + 1) * M_PI / 4;
    double z = copysign(1 - r * r, signed_distance);
    double sine = r * sqrt(fmax(0.0, 2 - r * r));
    w[0] = copysign(cos(phi), a) * sine;
    w[1] = copysign(sin(phi), b) * sine;
    w[2] = z;
}

/* The equirectangular map's pixel (idmr/environment.h's frame) seen in world direction w. */
static const float *environment_lookup(const scene_environment *e, const double w[3])
{
    double d[3];
    for (int i = 0; i < 3; i++)
        d[i] = e->to_map[3 * i] * w[0] + e->to_map[3 * i + 1] * w[1] + e->to_map[3 * i + 2] * w[2];
    double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double u = atan2(d[0], -d[2]) / (2 * M_PI);
    u -= floor(u);
    double v = acos(fmax(-1.0, fmin(1.0, d[1] / (length > 0 ? length : 1)))) / M_PI;
    int x = (int)(u * e->width), y = (int)(v * e->height);
    x = x < 0 ? 0 : x >= e->width ? e->width - 1 : x;
    y = y < 0 ? 0 : y >= e->height ? e->height - 1 : y;
    return e->rgb + 3 * ((size_t)y * e->width + x);
}

/* The map resampled (4 samples a pixel) into an N × N equal-area square, row 0 at v = 0, in the
 * world frame (the light's own transform is the identity). */
static int write_environment(export_job *job)
{
    const scene_environment *e = &job->s->environment;
    int n = e->height < PBRT_ENVIRONMENT_MIN   ? PBRT_ENVIRONMENT_MIN
            : e->height > PBRT_ENVIRONMENT_MAX ? PBRT_ENVIRONMENT_MAX
                                               : e->height;
    float *square = xcalloc(3 * (size_t)n * n, sizeof *square);
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) {
            float *pixel = square + 3 * ((size_t)y * n + x);
            for (int sample = 0; sample < 4; sample++) {
                double w[3];
                equal_area_direction((x + 0.25 + 0.5 * (sample & 1)) / n,
                                     (y + 0.25 + 0.5 * (sample >> 1)) / n, w);
                const float *value = environment_lookup(e, w);
                for (int c = 0; c < 3; c++)
                    pixel[c] += 0.25f * value[c];
            }
        }
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/environment.exr", job->staging);
    int status = image_write_rgb_float(path, n, n, square);
    free(square);
    if (status)
        return -1;
    size_t length = strlen(job->folder_name) + 32;
    free(job->environment_file);
    job->environment_file = xmalloc(length);
    snprintf(job->environment_file, length, "%s/environment.exr", job->folder_name);
    return 0;
}

static int put_light(export_job *job, export_text *t, const idmr_light *l)
{
    switch (l->kind) {
    case IDMR_LIGHT_POINT:
        export_printf(t, "LightSource \"point\"");
        put_triple(t, "rgb", "I", l->emission);
        put_triple(t, "point3", "from", l->position);
        break;
    case IDMR_LIGHT_SPOT: {
        float to[3];
        for (int k = 0; k < 3; k++)
            to[k] = l->position[k] + l->direction[k];
        double cutoff = acos(fmin(1.0, fmax(-1.0, l->cos_cutoff))) * 180.0 / M_PI;
        double beam = acos(fmin(1.0, fmax(-1.0, l->cos_falloff_start))) * 180.0 / M_PI;
        export_printf(t, "LightSource \"spot\"");
        put_triple(t, "rgb", "I", l->emission);
        put_triple(t, "point3", "from", l->position);
        put_triple(t, "point3", "to", to);
        put_float(t, "coneangle", cutoff);
        put_float(t, "conedeltaangle", fmax(0.0, cutoff - beam));
        break;
    }
    case IDMR_LIGHT_DIRECTIONAL: {
        static const float origin[3] = {0, 0, 0};
        export_printf(t, "LightSource \"distant\"");
        put_triple(t, "rgb", "L", l->emission);
        put_triple(t, "point3", "from", origin);
        put_triple(t, "point3", "to", l->direction);
        break;
    }
    case IDMR_LIGHT_ENVIRONMENT: {
        const scene_environment *e = &job->s->environment;
        export_printf(t, "LightSource \"infinite\"");
        if (e->width == 1 && e->height == 1) {
            put_triple(t, "rgb", "L", e->rgb);
            break;
        }
        if (write_environment(job))
            return -1;
        export_printf(t, " \"string filename\" [ ");
        put_quoted(t, job->environment_file);
        export_printf(t, " ]");
        break;
    }
    default:
        return 0;
    }
    export_printf(t, "\n");
    return 0;
}

static void put_shape(const export_job *job, export_text *t, size_t m)
{
    const scene_mesh *mesh = &job->s->meshes[m];
    int emitter = mesh->light >= 0 && (size_t)mesh->light < job->s->light_count;
    export_printf(t, "AttributeBegin # ");
    export_printf(t, "%s\n", job->mesh_names[m]);
    if (emitter) {
        export_printf(t, "    AreaLightSource \"diffuse\"");
        put_triple(t, "rgb", "L", job->s->lights[mesh->light].emission);
        export_printf(t, "\n");
    }
    if (mesh->material < job->s->material_count) {
        export_printf(t, "    NamedMaterial ");
        put_quoted(t, job->material_names[mesh->material]);
        export_printf(t, "\n");
    }
    export_printf(t, "    Shape \"plymesh\" \"string filename\" [ ");
    put_quoted(t, job->mesh_files[m]);
    export_printf(t, " ]\nAttributeEnd\n");
}

int export_pbrt(export_job *job, export_text *t)
{
    const scene *s = job->s;
    export_printf(t, "# pbrt-v4 scene written by idmr convert: every mesh is a world-space PLY "
                     "in %s/\n",
                  job->folder_name);
    put_camera(job, t);
    export_printf(t, "\nWorldBegin\n\n");
    for (size_t i = 0; i < s->material_count; i++)
        if (job->material_names[i])
            put_material(job, t, i);
    export_printf(t, "\n");
    for (size_t l = 0; l < s->light_count; l++)
        if (s->lights[l].kind != IDMR_LIGHT_AREA && put_light(job, t, &s->lights[l]))
            return -1;
    export_printf(t, "\n");
    for (size_t m = 0; m < s->mesh_count; m++)
        if (job->mesh_names[m])
            put_shape(job, t, m);
    return 0;
}
