/* scene.c — building, finalising and querying the in-memory scene (see scene.h). */
#include "core/scene.h"

#include <float.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/xform.h"

scene *scene_create(const char *file)
{
    scene *s = xcalloc(1, sizeof *s);
    s->file = xstrdup(file ? file : "");
    char *copy = xstrdup(s->file);
    s->dir = xstrdup(dirname(copy));
    free(copy);
    return s;
}

void scene_free(scene *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->mesh_count; i++) {
        scene_mesh *m = &s->meshes[i];
        if (m->source && s->free_mesh_source)
            s->free_mesh_source(m->source);
        free(m->name);
        free(m->shape_type);
        free(m->file);
        free(m->xml_file);
        free(m->instance_xml_file);
        free(m->positions);
        free(m->indices);
        free(m->texcoords);
        free(m->normals);
    }
    for (size_t i = 0; i < s->material_count; i++) {
        free(s->material_info[i].name);
        free(s->material_info[i].bsdf_type);
    }
    for (size_t i = 0; i < s->texture_count; i++) {
        free(s->textures[i].file);
        free(s->textures[i].rgb);
    }
    free(s->meshes);
    free(s->numbered_meshes);
    free(s->mesh_names);
    free(s->mesh_name_next);
    free(s->materials);
    free(s->material_info);
    free(s->lights);
    free(s->textures);
    free(s->environment.rgb);
    free(s->environment.file);
    free(s->file);
    free(s->dir);
    free(s);
}

/* FNV-1a of a name. */
static size_t name_hash(const char *name)
{
    uint64_t h = 1469598103934665603ull;
    for (const unsigned char *c = (const unsigned char *)name; *c; c++)
        h = (h ^ *c) * 1099511628211ull;
    return (size_t)(h ^ (h >> 32));
}

/* The slot of mesh_names that holds `name`, or the empty slot where it would go. */
static size_t name_slot(const scene *s, const char *name)
{
    size_t mask = s->mesh_name_capacity - 1, slot = name_hash(name) & mask;
    while (s->mesh_names[slot] && strcmp(s->meshes[s->mesh_names[slot] - 1].name, name) != 0)
        slot = (slot + 1) & mask;
    return slot;
}

static int mesh_name_taken(const scene *s, const char *name)
{
    return s->mesh_name_capacity && s->mesh_names[name_slot(s, name)] != 0;
}

/* Indexes mesh `index` by its name, growing the index to keep it at most half full (each
 * name keeps the suffix its repeats try next). */
static void index_mesh_name(scene *s, size_t index)
{
    if (2 * (s->mesh_count + 1) > s->mesh_name_capacity) {
        size_t *old = s->mesh_names, old_capacity = s->mesh_name_capacity;
        unsigned *old_next = s->mesh_name_next;
        s->mesh_name_capacity = old_capacity ? 2 * old_capacity : 64;
        s->mesh_names = xcalloc(s->mesh_name_capacity, sizeof *s->mesh_names);
        s->mesh_name_next = xcalloc(s->mesh_name_capacity, sizeof *s->mesh_name_next);
        for (size_t j = 0; j < old_capacity; j++)
            if (old[j]) {
                size_t slot = name_slot(s, s->meshes[old[j] - 1].name);
                s->mesh_names[slot] = old[j];
                s->mesh_name_next[slot] = old_next[j];
            }
        free(old_next);
        free(old);
    }
    s->mesh_names[name_slot(s, s->meshes[index].name)] = index + 1;
}

/* `array` of `count` items of `size` bytes with room for one more: it doubles when full, its
 * capacity the next power of two (not one item at a time: 20,000 meshes copied 20,000 times). */
static void *grown(void *array, size_t count, size_t size)
{
    if (count & (count - 1)) /* not a power of two: room left */
        return array;
    return xrealloc(array, (count ? 2 * count : 1) * size);
}

/* "name", or "name.2", "name.3", ... when taken: the first that is free. Names are only ever
 * added, so the search for a repeated name goes on from where the last one for it stopped
 * (10,000 nodes of one name: linear, not quadratic). */
static char *unique_mesh_name(scene *s, const char *name)
{
    if (!mesh_name_taken(s, name))
        return xstrdup(name);
    size_t slot = name_slot(s, name), size = strlen(name) + 24;
    char *candidate = xmalloc(size);
    for (unsigned suffix = s->mesh_name_next[slot] > 2 ? s->mesh_name_next[slot] : 2;; suffix++) {
        snprintf(candidate, size, "%s.%u", name, suffix);
        if (!mesh_name_taken(s, candidate)) {
            s->mesh_name_next[slot] = suffix + 1;
            return candidate;
        }
    }
}

uint32_t scene_triangles_drop_repeating(uint32_t *indices, uint32_t *triangle_count)
{
    uint32_t kept = 0;
    for (uint32_t t = 0; t < *triangle_count; t++) {
        const uint32_t *ix = &indices[3 * (size_t)t];
        if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2])
            continue;
        if (kept != t)
            memmove(&indices[3 * (size_t)kept], ix, 3 * sizeof *ix);
        kept++;
    }
    uint32_t dropped = *triangle_count - kept;
    *triangle_count = kept;
    return dropped;
}

scene_mesh *scene_add_mesh(scene *s, const char *name, const char *shape_type, const char *file,
                           int xml_line, uint32_t vertex_count, float *positions,
                           uint32_t triangle_count, uint32_t *indices, float *texcoords)
{
    char *unique = unique_mesh_name(s, name && *name ? name : (shape_type ? shape_type : "mesh"));
    s->meshes = grown(s->meshes, s->mesh_count, sizeof *s->meshes);
    scene_mesh *m = &s->meshes[s->mesh_count++];
    memset(m, 0, sizeof *m);
    m->name = unique;
    m->shape_type = xstrdup(shape_type ? shape_type : "");
    m->file = file ? xstrdup(file) : NULL;
    m->xml_line = xml_line;
    if (indices)
        m->triangles_dropped = scene_triangles_drop_repeating(indices, &triangle_count);
    scene_mesh_set_geometry(m, vertex_count, positions, triangle_count, indices, texcoords, NULL);
    m->light = -1;
    index_mesh_name(s, s->mesh_count - 1);
    return m;
}

/* The placement carrying the geometry of mesh `first` (a representative: placed by its
 * instance_to_world) to where `copy_to_world` places the copy named `copy_name`:
 * copy_to_world × first's instance_to_world^-1 (row-major 4x4). 0, or -1 with the error set
 * when the first's transform is singular. */
static int placement_from_first(const scene *s, size_t first, const char *copy_name,
                                const double copy_to_world[16], xform *placement)
{
    xform first_world = xform_from_rows(s->meshes[first].instance_to_world), first_object;
    if (xform_invert_affine(&first_world, &first_object))
        return error_set(IDMR_EXIT_INPUT,
                         "mesh '%s': the transform of its shape's first instance is singular, "
                         "so its copy '%s' cannot be placed from it",
                         s->meshes[first].name, copy_name);
    xform copy_world = xform_from_rows(copy_to_world);
    *placement = xform_multiply(&copy_world, &first_object);
    return 0;
}

int scene_instance_placement(const scene *s, size_t m, double object_to_world[16])
{
    xform placement = xform_identity();
    const scene_mesh *mesh = &s->meshes[m];
    if (scene_mesh_is_later_copy(s, m) &&
        placement_from_first(s, mesh->instance_first, mesh->name, mesh->instance_to_world,
                             &placement))
        return -1;
    memcpy(object_to_world, placement.m, sizeof placement.m);
    return 0;
}

/* Mesh m's box (a later copy's): the representative's vertices carried by the placement when
 * they are in memory, else the eight corners of the representative's box carried so (a
 * bound, not the exact box). */
static void later_copy_box(scene *s, size_t m, const xform *placement)
{
    scene_mesh *mesh = &s->meshes[m];
    const scene_mesh *first = &s->meshes[mesh->instance_first];
    for (int k = 0; k < 3; k++) {
        mesh->box_min[k] = FLT_MAX;
        mesh->box_max[k] = -FLT_MAX;
    }
    uint32_t points = first->released ? (first->vertex_count ? 8 : 0) : first->vertex_count;
    for (uint32_t v = 0; v < points; v++) {
        double p[3], world[3];
        for (int k = 0; k < 3; k++)
            p[k] = first->released ? ((v >> k) & 1 ? first->box_max[k] : first->box_min[k])
                                   : first->positions[3 * (size_t)v + k];
        xform_apply_point(placement, p, world);
        for (int k = 0; k < 3; k++) {
            mesh->box_min[k] = fminf(mesh->box_min[k], (float)world[k]);
            mesh->box_max[k] = fmaxf(mesh->box_max[k], (float)world[k]);
        }
    }
}

/* Whether every triangle of mesh m (in memory, or released with no_area noted) has no area. */
static int mesh_has_no_area(const scene_mesh *m)
{
    if (m->released)
        return m->no_area;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        if (scene_mesh_triangle_area(m, t) != 0.0)
            return 0;
    return 1;
}

scene_mesh *scene_add_instance_copy(scene *s, size_t representative, const char *name,
                                    const double to_world[16])
{
    xform placement;
    if (placement_from_first(s, representative, name, to_world, &placement))
        return NULL;
    char *unique = unique_mesh_name(s, name && *name ? name : s->meshes[representative].name);
    s->meshes = grown(s->meshes, s->mesh_count, sizeof *s->meshes);
    size_t c = s->mesh_count++;
    scene_mesh *first = &s->meshes[representative], *copy = &s->meshes[c];
    memset(copy, 0, sizeof *copy);
    copy->name = unique;
    copy->shape_type = xstrdup(first->shape_type);
    copy->file = first->file ? xstrdup(first->file) : NULL;
    copy->xml_file = first->xml_file ? xstrdup(first->xml_file) : NULL;
    copy->xml_line = first->xml_line;
    copy->vertex_count = first->vertex_count;
    copy->triangle_count = first->triangle_count;
    copy->triangles_dropped = first->triangles_dropped;
    copy->file_normals = first->file_normals;
    copy->flat_normals = first->flat_normals;
    copy->material = first->material;
    copy->light = -1;
    copy->released = 1;
    copy->had_texcoords = first->released ? first->had_texcoords : first->texcoords != NULL;
    copy->had_normals = first->released ? first->had_normals : first->normals != NULL;
    copy->no_area = mesh_has_no_area(first);
    copy->instanced = 1;
    copy->instance_first = representative;
    memcpy(copy->instance_to_world, to_world, sizeof copy->instance_to_world);
    s->meshes[first->instance_last ? first->instance_last : representative].instance_next = c;
    first->instance_last = c;
    later_copy_box(s, c, &placement);
    index_mesh_name(s, c);
    return copy;
}

uint32_t scene_add_material(scene *s, const char *name, const char *bsdf_type,
                            const idmr_material *material)
{
    size_t n = s->material_count + 1;
    s->materials = xrealloc(s->materials, n * sizeof *s->materials);
    s->material_info = xrealloc(s->material_info, n * sizeof *s->material_info);
    s->materials[n - 1] = *material;
    s->material_info[n - 1].name = xstrdup(name);
    s->material_info[n - 1].bsdf_type = xstrdup(bsdf_type);
    s->material_count = n;
    return (uint32_t)(n - 1);
}

int scene_add_light(scene *s, const idmr_light *light)
{
    s->lights = grown(s->lights, s->light_count, sizeof *s->lights);
    s->lights[s->light_count] = *light;
    return (int)s->light_count++;
}

int scene_find_texture(const scene *s, const char *file)
{
    for (size_t i = 0; i < s->texture_count; i++)
        if (strcmp(s->textures[i].file, file) == 0)
            return (int)i;
    return -1;
}

int scene_add_texture(scene *s, const char *file, int width, int height, float *rgb)
{
    scene_texture t = {.width = width, .height = height, .rgb = rgb};
    double sum[3] = {0, 0, 0};
    size_t pixels = (size_t)t.width * (size_t)t.height;
    for (size_t p = 0; p < pixels; p++)
        for (int c = 0; c < 3; c++)
            sum[c] += t.rgb[3 * p + c];
    for (int c = 0; c < 3; c++)
        t.mean[c] = pixels ? (float)(sum[c] / (double)pixels) : 0.0f;
    t.file = xstrdup(file);
    s->textures = xrealloc(s->textures, (s->texture_count + 1) * sizeof *s->textures);
    s->textures[s->texture_count] = t;
    return (int)s->texture_count++;
}

double scene_environment_pixel_solid_angle(int width, int height, int row)
{
    return 2.0 * M_PI / width *
           (cos(M_PI * row / height) - cos(M_PI * (row + 1) / height));
}

/* The inverse of a row-major 3x3 matrix; 0 when it is singular. */
static int invert3(const double m[9], double out[9])
{
    double c[9] = {m[4] * m[8] - m[5] * m[7], m[5] * m[6] - m[3] * m[8],
                   m[3] * m[7] - m[4] * m[6], m[2] * m[7] - m[1] * m[8],
                   m[0] * m[8] - m[2] * m[6], m[1] * m[6] - m[0] * m[7],
                   m[1] * m[5] - m[2] * m[4], m[2] * m[3] - m[0] * m[5],
                   m[0] * m[4] - m[1] * m[3]}; /* cofactors */
    double det = m[0] * c[0] + m[1] * c[1] + m[2] * c[2];
    if (!(fabs(det) > 1e-12))
        return 0;
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 3; col++)
            out[3 * row + col] = c[3 * col + row] / det;
    return 1;
}

/* Checks the map's values (setting negative ones to 0); its mean radiance over the sphere and
 * the integral of its luminance. 0, or -1 with the error set. */
static int environment_sums(int width, int height, float *rgb, float mean[3], double *integral)
{
    double sum[3] = {0, 0, 0};
    *integral = 0;
    for (int y = 0; y < height; y++) {
        double solid_angle = scene_environment_pixel_solid_angle(width, height, y);
        for (int x = 0; x < width; x++) {
            float *pixel = &rgb[3 * ((size_t)y * width + x)];
            for (int c = 0; c < 3; c++) {
                if (!isfinite(pixel[c]))
                    return error_set(IDMR_EXIT_INPUT,
                                     "environment map pixel (%d, %d) is not finite (%g)", x, y,
                                     pixel[c]);
                pixel[c] = pixel[c] > 0 ? pixel[c] : 0.0f;
                sum[c] += pixel[c] * solid_angle;
            }
            *integral += idmr_luminance(pixel[0], pixel[1], pixel[2]) * solid_angle;
        }
    }
    for (int c = 0; c < 3; c++)
        mean[c] = (float)(sum[c] / (4.0 * M_PI));
    return 0;
}

int scene_add_environment(scene *s, const char *file, int width, int height, float *rgb,
                          const double to_world[9])
{
    scene_environment *e = &s->environment;
    idmr_light light;
    memset(&light, 0, sizeof light);
    light.kind = IDMR_LIGHT_ENVIRONMENT;
    int status = 0;
    if (e->width)
        status = error_set(IDMR_EXIT_INPUT, "a second environment emitter: a scene has at most "
                                            "one (constant or envmap), as in Mitsuba 3");
    else if (width < 1 || height < 1)
        status = error_set(IDMR_EXIT_INPUT, "an environment map of %d x %d pixels", width, height);
    else if (!invert3(to_world, e->to_map))
        status = error_set(IDMR_EXIT_INPUT, "the environment's to_world is singular");
    else
        status = environment_sums(width, height, rgb, light.emission, &e->luminance_integral);
    if (status) {
        free(rgb);
        return -1;
    }
    e->width = width;
    e->height = height;
    e->rgb = rgb;
    memcpy(e->to_world, to_world, sizeof e->to_world);
    e->file = file ? xstrdup(file) : NULL;
    return scene_add_light(s, &light);
}

/* Whether the input file `input` (may be NULL) is `real` or, with `below`, lies under it. */
static int input_at(const char *input, const char *real, int below)
{
    char input_real[PATH_MAX];
    if (!input || !realpath(input, input_real))
        return 0;
    size_t length = strlen(real);
    if (!below)
        return strcmp(input_real, real) == 0;
    return strncmp(input_real, real, length) == 0 &&
           (input_real[length] == '/' || strcmp(real, "/") == 0);
}

/* The first file the scene reads that is at `output` (see input_at), or NULL; NULL too when
 * output does not exist. */
static const char *input_at_output(const scene *s, const char *output, int below)
{
    char real[PATH_MAX];
    if (!realpath(output, real))
        return NULL;
    if (input_at(s->file, real, below))
        return s->file;
    for (size_t i = 0; i < s->mesh_count; i++) {
        if (input_at(s->meshes[i].file, real, below))
            return s->meshes[i].file;
        if (input_at(s->meshes[i].xml_file, real, below))
            return s->meshes[i].xml_file;
    }
    for (size_t i = 0; i < s->texture_count; i++)
        if (input_at(s->textures[i].file, real, below))
            return s->textures[i].file;
    return input_at(s->environment.file, real, below) ? s->environment.file : NULL;
}

int scene_check_output_directory(const scene *s, const char *dir)
{
    const char *input = input_at_output(s, dir, 1);
    return input ? error_set(IDMR_EXIT_INPUT,
                             "output directory '%s' holds '%s', which the scene reads: choose "
                             "another (inputs are never overwritten)",
                             dir, input)
                 : 0;
}

int scene_check_output_file(const scene *s, const char *path)
{
    const char *input = input_at_output(s, path, 0);
    return input ? error_set(IDMR_EXIT_INPUT,
                             "output '%s' is '%s', which the scene reads: choose another "
                             "(inputs are never overwritten)",
                             path, input)
                 : 0;
}

static void triangle_vertices(const scene_mesh *m, uint32_t t, const float *v[3])
{
    for (int k = 0; k < 3; k++)
        v[k] = &m->positions[3 * (size_t)m->indices[3 * (size_t)t + k]];
}

double scene_mesh_triangle_area(const scene_mesh *m, uint32_t t)
{
    const float *v[3];
    triangle_vertices(m, t, v);
    return triangle_area(v[0], v[1], v[2]);
}

double triangle_area(const float *a, const float *b, const float *c)
{
    const float *v[3] = {a, b, c};
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)v[1][k] - v[0][k];
        e2[k] = (double)v[2][k] - v[0][k];
    }
    double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
    return 0.5 * sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
}

double scene_diagonal(const scene *s)
{
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double e = (double)s->bbox_max[k] - s->bbox_min[k];
        d2 += e > 0 ? e * e : 0;
    }
    return sqrt(d2);
}

/* Luminance of a linear RGB triple (idmr_luminance): lights are chosen by luminous power. */
static double luminance(const float rgb[3])
{
    return idmr_luminance(rgb[0], rgb[1], rgb[2]);
}

/* Area lights: triangle range and area from their mesh; power by kind. A spot's power uses the
 * solid angle of its cutoff cone; a directional light's, the scene's bounding disc. */
static void finalize_lights(scene *s)
{
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *m = &s->meshes[i];
        if (m->light < 0)
            continue;
        idmr_light *l = &s->lights[m->light];
        l->first_triangle = m->first_triangle;
        l->triangle_count = m->triangle_count;
        double area = 0;
        for (uint32_t t = 0; t < m->triangle_count; t++)
            area += scene_mesh_triangle_area(m, t);
        l->area = (float)area;
    }
    double radius = 0.5 * scene_diagonal(s);
    for (size_t i = 0; i < s->light_count; i++) {
        idmr_light *l = &s->lights[i];
        double y = luminance(l->emission);
        switch (l->kind) {
        case IDMR_LIGHT_AREA: {
            /* Two-sided materials still emit from the front side only (Mitsuba's area light). */
            l->power = (float)(M_PI * l->area * y);
            break;
        }
        case IDMR_LIGHT_POINT:
            l->power = (float)(4.0 * M_PI * y);
            break;
        case IDMR_LIGHT_SPOT:
            l->power = (float)(2.0 * M_PI * (1.0 - 0.5 * (l->cos_falloff_start + l->cos_cutoff)) * y);
            break;
        case IDMR_LIGHT_DIRECTIONAL:
            l->power = (float)(M_PI * radius * radius * y);
            break;
        case IDMR_LIGHT_ENVIRONMENT:
            /* Through the bounding disc from every direction: π r² ∫ Y(L) dω (4π r² × π y for
             * a uniform environment). */
            l->power = (float)(M_PI * radius * radius * s->environment.luminance_integral);
            break;
        }
    }
}

/* Frees mesh's geometry arrays. */
static void free_geometry(scene_mesh *mesh)
{
    free(mesh->positions);
    free(mesh->indices);
    free(mesh->texcoords);
    free(mesh->normals);
    mesh->positions = mesh->texcoords = mesh->normals = NULL;
    mesh->indices = NULL;
}

void scene_mesh_release(scene *s, size_t m)
{
    scene_mesh *mesh = &s->meshes[m];
    if (scene_mesh_is_later_copy(s, m)) {
        free_geometry(mesh); /* its box and flags were set when it was added */
        mesh->released = 1;
        return;
    }
    if (!mesh->source || !s->restore_mesh || mesh->light >= 0 || mesh->released)
        return;
    mesh->had_texcoords = mesh->texcoords != NULL;
    mesh->had_normals = mesh->normals != NULL;
    mesh->no_area = 1;
    for (uint32_t t = 0; t < mesh->triangle_count && mesh->no_area; t++)
        mesh->no_area = scene_mesh_triangle_area(mesh, t) == 0.0;
    for (int k = 0; k < 3; k++) {
        mesh->box_min[k] = FLT_MAX;
        mesh->box_max[k] = -FLT_MAX;
    }
    for (uint32_t v = 0; v < mesh->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            mesh->box_min[k] = fminf(mesh->box_min[k], mesh->positions[3 * (size_t)v + k]);
            mesh->box_max[k] = fmaxf(mesh->box_max[k], mesh->positions[3 * (size_t)v + k]);
        }
    free_geometry(mesh);
    mesh->released = 1;
}

void scene_mesh_set_geometry(scene_mesh *mesh, uint32_t vertex_count, float *positions,
                             uint32_t triangle_count, uint32_t *indices, float *texcoords,
                             float *normals)
{
    mesh->vertex_count = vertex_count;
    mesh->positions = positions;
    mesh->triangle_count = triangle_count;
    mesh->indices = indices;
    mesh->texcoords = texcoords;
    mesh->normals = normals;
    mesh->released = 0;
}

/* Makes later copy m's world-space geometry from its representative's (read again for the
 * while if it is released). 0, or -1 with the error set. */
static int restore_later_copy(scene *s, size_t m)
{
    size_t r = s->meshes[m].instance_first;
    int first_was_released = s->meshes[r].released;
    double rows[16];
    if (scene_instance_placement(s, m, rows) || scene_mesh_restore(s, r))
        return -1;
    const scene_mesh *first = &s->meshes[r];
    scene_mesh *copy = &s->meshes[m];
    size_t v = first->vertex_count, t = first->triangle_count;
    scene_mesh_set_geometry(copy, first->vertex_count,
                            xmemdup(first->positions, 3 * v * sizeof *first->positions),
                            first->triangle_count,
                            xmemdup(first->indices, 3 * t * sizeof *first->indices),
                            xmemdup(first->texcoords, 2 * v * sizeof *first->texcoords),
                            xmemdup(first->normals, 3 * v * sizeof *first->normals));
    xform placement = xform_from_rows(rows);
    xform_apply_keeping_side(&placement, copy->positions, copy->normals, v, copy->indices, t);
    if (first_was_released)
        scene_mesh_release(s, r);
    return 0;
}

int scene_mesh_restore(scene *s, size_t m)
{
    scene_mesh *mesh = &s->meshes[m];
    if (!mesh->released)
        return 0;
    if (scene_mesh_is_later_copy(s, m))
        return restore_later_copy(s, m);
    uint32_t vertices = mesh->vertex_count, triangles = mesh->triangle_count;
    if (s->restore_mesh(mesh->source, mesh))
        return -1;
    if (mesh->vertex_count != vertices || mesh->triangle_count != triangles)
        return error_set(IDMR_EXIT_INPUT,
                         "mesh '%s': read again from %s, it has %u vertices and %u triangles, "
                         "not the %u and %u it had (was the file changed?)",
                         mesh->name, mesh->file ? mesh->file : "its file", mesh->vertex_count,
                         mesh->triangle_count, vertices, triangles);
    return 0;
}

scene *scene_view(const scene *s)
{
    scene *view = xmalloc(sizeof *view);
    *view = *s;
    view->meshes = xmalloc((s->mesh_count + 1) * sizeof *view->meshes);
    if (s->mesh_count)
        memcpy(view->meshes, s->meshes, s->mesh_count * sizeof *view->meshes);
    view->lights = xmalloc((s->light_count + 1) * sizeof *view->lights);
    if (s->light_count)
        memcpy(view->lights, s->lights, s->light_count * sizeof *view->lights);
    view->numbered_meshes = NULL; /* its own, from its scene_finalize() */
    view->numbered_mesh_count = 0;
    return view;
}

void scene_view_free(scene *view)
{
    if (!view)
        return;
    free(view->meshes);
    free(view->lights);
    free(view->numbered_meshes);
    free(view);
}

int scene_finalize(scene *s)
{
    uint64_t triangles = 0, vertices = 0, rendered_triangles = 0, rendered_vertices = 0;
    int later_copies = 0;
    free(s->numbered_meshes);
    s->numbered_meshes = xmalloc((s->mesh_count + 1) * sizeof *s->numbered_meshes);
    s->numbered_mesh_count = 0;
    for (size_t i = 0; i < s->mesh_count; i++) {
        scene_mesh *m = &s->meshes[i];
        if (scene_mesh_is_later_copy(s, i)) {
            /* its triangles are its representative's (numbered before it: the first copy comes
             * first), its box follows the representative's geometry */
            const scene_mesh *first = &s->meshes[m->instance_first];
            m->vertex_count = first->vertex_count;
            m->triangle_count = first->triangle_count;
            m->first_triangle = first->first_triangle;
            double rows[16];
            if (scene_instance_placement(s, i, rows))
                return -1;
            xform placement = xform_from_rows(rows);
            later_copy_box(s, i, &placement);
            rendered_triangles += m->triangle_count;
            rendered_vertices += m->vertex_count;
            later_copies = 1;
            continue;
        }
        s->numbered_meshes[s->numbered_mesh_count++] = i;
        if (triangles + m->triangle_count > UINT32_MAX - 1)
            return error_set(IDMR_EXIT_INPUT,
                             "%s: more than %u triangles in the scene (at mesh '%s'): the "
                             "kernels index triangles with 32 bits",
                             s->file, UINT32_MAX - 1, m->name);
        m->first_triangle = (uint32_t)triangles;
        triangles += m->triangle_count;
        vertices += m->vertex_count;
        rendered_triangles += m->triangle_count;
        rendered_vertices += m->vertex_count;
        for (uint64_t t = 0; !m->released && t < 3 * (uint64_t)m->triangle_count; t++)
            if (m->indices[t] >= m->vertex_count)
                return error_set(IDMR_EXIT_INPUT, "%s: mesh '%s': triangle %llu uses vertex %u of %u",
                                 s->file, m->name, (unsigned long long)(t / 3), m->indices[t],
                                 m->vertex_count);
    }
    s->triangle_count = triangles;
    s->vertex_count = vertices;
    s->rendered_triangle_count = rendered_triangles;
    s->rendered_vertex_count = rendered_vertices;

    for (int k = 0; k < 3; k++) {
        s->bbox_min[k] = FLT_MAX;
        s->bbox_max[k] = -FLT_MAX;
    }
    for (size_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *m = &s->meshes[i];
        if (m->released && m->vertex_count)
            for (int k = 0; k < 3; k++) { /* its box was checked when it was loaded */
                s->bbox_min[k] = fminf(s->bbox_min[k], m->box_min[k]);
                s->bbox_max[k] = fmaxf(s->bbox_max[k], m->box_max[k]);
            }
        for (uint32_t v = 0; !m->released && v < m->vertex_count; v++)
            for (int k = 0; k < 3; k++) {
                float x = m->positions[3 * (size_t)v + k];
                if (!isfinite(x))
                    return error_set(IDMR_EXIT_INPUT, "%s: mesh '%s': vertex %u is not finite",
                                     s->file, m->name, v);
                if (fabsf(x) > SCENE_COORDINATE_LIMIT)
                    return error_set(IDMR_EXIT_INPUT,
                                     "%s:%d: mesh '%s': vertex %u has coordinate %g, beyond "
                                     "the %g up to which idmr's 32-bit float arithmetic is "
                                     "scale-invariant: scale the scene down",
                                     m->xml_file ? m->xml_file : s->file, m->xml_line, m->name,
                                     v, x, SCENE_COORDINATE_LIMIT);
                s->bbox_min[k] = fminf(s->bbox_min[k], x);
                s->bbox_max[k] = fmaxf(s->bbox_max[k], x);
            }
    }
    if (vertices == 0)
        for (int k = 0; k < 3; k++)
            s->bbox_min[k] = s->bbox_max[k] = 0.0f;

    finalize_lights(s);

    unsigned int features = 0;
    static const unsigned int material_feature[IDMR_MATERIAL_KIND_COUNT] = {
        IDMR_FEATURE_DIFFUSE, IDMR_FEATURE_GLOSSY, IDMR_FEATURE_MIRROR, IDMR_FEATURE_DIELECTRIC};
    for (size_t i = 0; i < s->mesh_count; i++) {
        const idmr_material *mat = &s->materials[s->meshes[i].material];
        if (s->meshes[i].triangle_count == 0)
            continue;
        features |= material_feature[mat->kind];
        if (mat->texture >= 0)
            features |= IDMR_FEATURE_TEXTURED;
    }
    static const unsigned int light_feature[IDMR_LIGHT_KIND_COUNT] = {
        IDMR_FEATURE_AREA, IDMR_FEATURE_POINT, IDMR_FEATURE_SPOT, IDMR_FEATURE_DIRECTIONAL,
        IDMR_FEATURE_ENVIRONMENT};
    for (size_t i = 0; i < s->light_count; i++)
        features |= light_feature[s->lights[i].kind];
    if (later_copies)
        features |= IDMR_FEATURE_INSTANCES;
    s->features = features;
    return 0;
}

size_t scene_mesh_of_triangle(const scene *s, uint64_t triangle)
{
    if (s->numbered_mesh_count == 0)
        return 0;
    size_t lo = 0, hi = s->numbered_mesh_count;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->meshes[s->numbered_meshes[mid]].first_triangle <= triangle)
            lo = mid;
        else
            hi = mid;
    }
    /* The last mesh starting at or before `triangle`: an empty mesh shares its first_triangle
     * with the next one, so it is never the last such mesh unless no mesh follows it. */
    return s->numbered_meshes[lo];
}

double scene_triangle_area(const scene *s, uint64_t triangle)
{
    size_t m = scene_mesh_of_triangle(s, triangle);
    return scene_mesh_triangle_area(&s->meshes[m], (uint32_t)(triangle - s->meshes[m].first_triangle));
}

const char *scene_feature_name(unsigned int feature_bit)
{
    switch (feature_bit) {
    case IDMR_FEATURE_DIFFUSE: return "diffuse";
    case IDMR_FEATURE_GLOSSY: return "glossy";
    case IDMR_FEATURE_MIRROR: return "mirror";
    case IDMR_FEATURE_DIELECTRIC: return "dielectric";
    case IDMR_FEATURE_TEXTURED: return "textured";
    case IDMR_FEATURE_AREA: return "area";
    case IDMR_FEATURE_POINT: return "point";
    case IDMR_FEATURE_SPOT: return "spot";
    case IDMR_FEATURE_DIRECTIONAL: return "directional";
    case IDMR_FEATURE_ENVIRONMENT: return "environment";
    default: return "unknown";
    }
}

const char *scene_material_kind_name(unsigned int kind)
{
    static const char *names[IDMR_MATERIAL_KIND_COUNT] = {"diffuse", "glossy", "mirror",
                                                          "dielectric"};
    return kind < IDMR_MATERIAL_KIND_COUNT ? names[kind] : "unknown";
}

const char *scene_light_kind_name(unsigned int kind)
{
    static const char *names[IDMR_LIGHT_KIND_COUNT] = {"area", "point", "spot", "directional",
                                                       "environment"};
    return kind < IDMR_LIGHT_KIND_COUNT ? names[kind] : "unknown";
}
