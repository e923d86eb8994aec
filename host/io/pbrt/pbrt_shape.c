/* pbrt_shape.c — Shape statements → world-space meshes, and ObjectInstance's copies of an
 * object's shapes.
 *
 *   trianglemesh  P, indices (may be left out for one triangle), uv, N
 *   plymesh       filename: ASCII or binary PLY through idmr's reader (io/mesh/mesh_io.h; polygons
 *                 fan-triangulated); a gzipped one (.ply.gz) is unpacked with zlib into a
 *                 temporary file under $TMPDIR (else /tmp), read, and removed
 *   bilinearmesh  P, indices (4 per patch: p00 p10 p01 p11), uv, N: two triangles per patch
 *   loopsubdiv    its control mesh (not subdivided: warned)
 *   sphere        radius (zmin, zmax, phimax: the whole sphere, warned), tessellated
 *   disk          height, radius (innerradius, phimax: the whole disk, warned), tessellated
 *   curve, cylinder, cone, paraboloid, hyperboloid: warned about and left out.
 *
 * Which side is the front (where an area light emits): pbrt takes a triangle's geometric normal
 * from its world-space winding, reversed when ReverseOrientation xor the CTM swaps handedness,
 * and turns it towards the shading normal where the mesh has normals (normals themselves
 * reversed by ReverseOrientation). The loader bakes that into the winding: with normals, each
 * triangle is wound to agree with its normals; without, the winding is reversed when
 * ReverseOrientation xor det(CTM) < 0 (the same rule gives a tessellated sphere's or disk's
 * outward side, which pbrt keeps under mirroring). Texture coordinates are stored as Mitsuba
 * reads them (v = 1 - pbrt's t, whose 0 is the image's bottom row). A mesh without N is shaded
 * flat, as in pbrt. The mesh keeps, for the writer, its statement's place and transform
 * (pbrt.h). */
#include "io/pbrt/pbrt_loader.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>
#include <unistd.h>

#include "core/error.h"
#include "io/mesh/mesh_io.h"
#include "core/shapes.h"

/* What a Shape statement gives besides its geometry. */
typedef struct shape_record {
    const char *name;
    const char *shape_type;
    const char *mesh_file; /* resolved, or NULL */
    const char *xml_file;
    int line;
    long offset;
    int reverse_orientation;
    int file_normals;
    int material; /* loader material index, or -1 */
} shape_record;

/* Winds each triangle so that its geometric normal agrees with the sum of its vertex normals. */
static void orient_by_normals(mesh_data *mesh)
{
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t *tri = &mesh->indices[3 * (size_t)t];
        const float *a = &mesh->positions[3 * (size_t)tri[0]],
                    *b = &mesh->positions[3 * (size_t)tri[1]],
                    *c = &mesh->positions[3 * (size_t)tri[2]];
        double u[3], v[3], n[3], sum[3];
        for (int k = 0; k < 3; k++) {
            u[k] = (double)b[k] - a[k];
            v[k] = (double)c[k] - a[k];
            sum[k] = (double)mesh->normals[3 * (size_t)tri[0] + k] +
                     mesh->normals[3 * (size_t)tri[1] + k] + mesh->normals[3 * (size_t)tri[2] + k];
        }
        xform_cross(u, v, n);
        if (xform_dot(n, sum) < 0.0) {
            uint32_t swap = tri[1];
            tri[1] = tri[2];
            tri[2] = swap;
        }
    }
}

/* Takes `mesh` (object space, owned) into the world under `to_world` and adds it to the scene
 * with the record's material and the current area light (`emits`). */
static int place_mesh(pbrt_loader *ld, const shape_record *rec, mesh_data *mesh,
                      const xform *to_world, int emits)
{
    double det = xform_determinant3(to_world);
    if (!(fabs(det) > 0.0) || !isfinite(det)) {
        mesh_data_free(mesh);
        return pbrt_fail(rec->xml_file, rec->line, "Shape \"%s\": the transform is singular",
                         rec->shape_type);
    }
    int flipped = rec->reverse_orientation ^ (det < 0.0);
    xform_apply_points(to_world, mesh->positions, mesh->vertex_count);
    if (mesh->normals) {
        xform_apply_normals(to_world, mesh->normals, mesh->vertex_count);
        if (flipped) /* the cofactor turns a normal under a mirror; R reverses it */
            shapes_reverse_normals(mesh);
        orient_by_normals(mesh);
    } else if (flipped) {
        shapes_flip_winding(mesh);
    }
    for (uint32_t v = 0; mesh->texcoords && v < mesh->vertex_count; v++)
        mesh->texcoords[2 * (size_t)v + 1] = 1.0f - mesh->texcoords[2 * (size_t)v + 1];
    int material = pbrt_material_scene_index(ld, rec->material);
    if (material < 0) {
        mesh_data_free(mesh);
        return error_prefix("%s:%d: Shape", rec->xml_file, rec->line);
    }
    int flat = rec->file_normals && shapes_normals_flat(mesh);
    scene_mesh *added = scene_add_mesh(ld->s, rec->name, rec->shape_type, rec->mesh_file,
                                       rec->line, mesh->vertex_count, mesh->positions,
                                       mesh->triangle_count, mesh->indices, mesh->texcoords);
    added->normals = mesh->normals;
    added->triangles_dropped += mesh->triangles_dropped;
    added->file_normals = rec->file_normals && mesh->normals;
    added->flat_normals = flat;
    added->material = (uint32_t)material;
    added->xml_file = xstrdup(rec->xml_file);
    added->source_offset = rec->offset;
    memcpy(added->object_to_world, to_world->m, sizeof added->object_to_world);
    added->source_flipped = flipped;
    if (emits) {
        idmr_light light;
        memset(&light, 0, sizeof light);
        light.kind = IDMR_LIGHT_AREA;
        memcpy(light.emission, ld->state.area_light.radiance, sizeof light.emission);
        added->light = scene_add_light(ld->s, &light);
    }
    memset(mesh, 0, sizeof *mesh); /* the scene owns the arrays now */
    return 0;
}

/* A copy of a mesh's arrays. */
static void mesh_copy(const mesh_data *from, mesh_data *to)
{
    *to = *from;
    size_t v = from->vertex_count, t = from->triangle_count;
    to->positions = xmalloc(3 * v * sizeof(float) + 1);
    memcpy(to->positions, from->positions, 3 * v * sizeof(float));
    to->indices = xmalloc(3 * t * sizeof(uint32_t) + 1);
    memcpy(to->indices, from->indices, 3 * t * sizeof(uint32_t));
    to->texcoords = NULL;
    to->normals = NULL;
    if (from->texcoords) {
        to->texcoords = xmalloc(2 * v * sizeof(float));
        memcpy(to->texcoords, from->texcoords, 2 * v * sizeof(float));
    }
    if (from->normals) {
        to->normals = xmalloc(3 * v * sizeof(float));
        memcpy(to->normals, from->normals, 3 * v * sizeof(float));
    }
}

/* A float array parameter of type `type` (or its aliases) with a multiple of `per` values. */
static int number_array(const char *file, pbrt_params *params, const char *name,
                        const char *const *types, size_t per, pbrt_param **out)
{
    if (pbrt_param_typed(file, params, name, types, 0, out))
        return -1;
    pbrt_param *p = *out;
    if (p && p->number_count % per)
        return pbrt_fail(file, p->line, "\"%s %s\": %zu values, not a multiple of %zu", p->type,
                         p->name, p->number_count, per);
    return 0;
}

/* The vertex arrays shared by trianglemesh, bilinearmesh and loopsubdiv: P, uv, N (checked to
 * match P's count), and indices (a multiple of `corners`, each below the vertex count; may be
 * left out when P has exactly `corners` points). The corners are copied to *corner_indices
 * (malloc'd), *corner_count of them. */
static int vertex_arrays(const char *file, int line, pbrt_params *params, size_t corners,
                         mesh_data *mesh, uint32_t **corner_indices, size_t *corner_count)
{
    static const char *const p_types[] = {"point3", "point", NULL};
    static const char *const uv_types[] = {"point2", "float", NULL};
    static const char *const n_types[] = {"normal", "normal3", NULL};
    static const char *const i_types[] = {"integer", NULL};
    pbrt_param *P, *uv, *N, *indices;
    if (number_array(file, params, "P", p_types, 3, &P) ||
        number_array(file, params, "uv", uv_types, 2, &uv) ||
        number_array(file, params, "N", n_types, 3, &N) ||
        number_array(file, params, "indices", i_types, corners, &indices))
        return -1;
    if (!uv && number_array(file, params, "st", uv_types, 2, &uv))
        return -1;
    if (!P)
        return pbrt_fail(file, line, "Shape: \"point3 P\" is missing");
    size_t vertices = P->number_count / 3;
    if (vertices == 0 || vertices > 0xFFFFFFF0u)
        return pbrt_fail(file, line, "Shape: \"point3 P\" holds %zu points", vertices);
    if (!indices && vertices != corners)
        return pbrt_fail(file, line, "Shape: \"integer indices\" is missing");
    if (uv && uv->number_count / 2 != vertices)
        return pbrt_fail(file, uv->line, "Shape: %zu uv values for %zu points",
                         uv->number_count / 2, vertices);
    if (N && N->number_count / 3 != vertices)
        return pbrt_fail(file, N->line, "Shape: %zu normals for %zu points", N->number_count / 3,
                         vertices);
    for (size_t i = 0; i < P->number_count; i++)
        if (fabs(P->numbers[i]) > FLT_MAX)
            return pbrt_fail(file, P->line, "Shape: \"point3 P\" value %g is beyond float range",
                             P->numbers[i]);
    size_t count = indices ? indices->number_count : corners;
    if (count == 0)
        return pbrt_fail(file, line, "Shape: no indices");
    uint32_t *corner = xmalloc(count * sizeof *corner);
    for (size_t i = 0; i < count; i++) {
        double value = indices ? indices->numbers[i] : (double)i;
        if (value < 0 || value >= (double)vertices) {
            free(corner);
            return pbrt_fail(file, indices->line, "Shape: index %g is out of range (%zu points)",
                             value, vertices);
        }
        corner[i] = (uint32_t)value;
    }
    mesh->vertex_count = (uint32_t)vertices;
    mesh->positions = xmalloc(3 * vertices * sizeof(float));
    for (size_t i = 0; i < 3 * vertices; i++)
        mesh->positions[i] = (float)P->numbers[i];
    if (uv) {
        mesh->texcoords = xmalloc(2 * vertices * sizeof(float));
        for (size_t i = 0; i < 2 * vertices; i++)
            mesh->texcoords[i] = (float)uv->numbers[i];
    }
    if (N) {
        mesh->normals = xmalloc(3 * vertices * sizeof(float));
        for (size_t i = 0; i < 3 * vertices; i++)
            mesh->normals[i] = (float)N->numbers[i];
    }
    if (pbrt_param_find(params, "S"))
        pbrt_warn(file, line, "Shape: tangents (S) are not read");
    pbrt_param_find(params, "faceIndices");
    *corner_indices = corner;
    *corner_count = count;
    return 0;
}

static int shape_triangles(const char *file, int line, pbrt_params *params, mesh_data *mesh)
{
    uint32_t *corners;
    size_t count;
    if (vertex_arrays(file, line, params, 3, mesh, &corners, &count))
        return -1;
    mesh->indices = corners;
    mesh->triangle_count = (uint32_t)(count / 3);
    return 0;
}

static int shape_bilinear(const char *file, int line, pbrt_params *params, mesh_data *mesh)
{
    uint32_t *corners;
    size_t count;
    if (vertex_arrays(file, line, params, 4, mesh, &corners, &count))
        return -1;
    size_t patches = count / 4;
    mesh->indices = xmalloc(6 * patches * sizeof *mesh->indices);
    for (size_t p = 0; p < patches; p++) {
        const uint32_t *q = &corners[4 * p]; /* p00 p10 p01 p11 */
        uint32_t tris[6] = {q[0], q[1], q[3], q[0], q[3], q[2]};
        memcpy(&mesh->indices[6 * p], tris, sizeof tris);
    }
    mesh->triangle_count = (uint32_t)(2 * patches);
    free(corners);
    return 0;
}

/* Reads the gzipped PLY at `path` into `mesh` through a temporary file (never beside the input:
 * its folder may be read-only). 0, or -1 with the error set naming the file. */
static int read_gzipped_ply(const char *path, mesh_data *mesh)
{
    const char *dir = getenv("TMPDIR");
    char temporary[4096];
    snprintf(temporary, sizeof temporary, "%s/idmr-plymesh-XXXXXX.ply", dir && *dir ? dir : "/tmp");
    int fd = mkstemps(temporary, 4);
    if (fd < 0)
        return error_set(IDMR_EXIT_FAILURE, "cannot create a temporary file to unpack '%s': %s",
                         path, strerror(errno));
    gzFile in = gzopen(path, "rb");
    int status = in ? 0 : error_set(IDMR_EXIT_INPUT, "cannot open '%s': %s", path, strerror(errno));
    char buffer[1 << 16];
    int got = 0;
    while (!status && (got = gzread(in, buffer, sizeof buffer)) > 0)
        for (int done = 0; done < got && !status;) {
            ssize_t put = write(fd, buffer + done, (size_t)(got - done));
            if (put < 0)
                status = error_set(IDMR_EXIT_FAILURE, "cannot unpack '%s' into '%s': %s", path,
                                   temporary, strerror(errno));
            else
                done += (int)put;
        }
    if (!status && got < 0) {
        int code;
        status = error_set(IDMR_EXIT_INPUT, "cannot unpack '%s': %s", path, gzerror(in, &code));
    }
    if (in)
        gzclose(in);
    if (close(fd) != 0 && !status)
        status = error_set(IDMR_EXIT_FAILURE, "cannot unpack '%s' into '%s': %s", path,
                           temporary, strerror(errno));
    if (!status && mesh_io_read(temporary, mesh))
        status = error_prefix("'%s' (unpacked)", path);
    unlink(temporary);
    return status;
}

static int shape_plymesh(pbrt_loader *ld, const char *file, int line, pbrt_params *params,
                         mesh_data *mesh, char **path)
{
    const char *written;
    if (pbrt_param_string(file, params, "filename", NULL, &written))
        return -1;
    if (!written)
        return pbrt_fail(file, line, "Shape \"plymesh\": \"string filename\" is missing");
    size_t n = strlen(written);
    int gzipped = n >= 3 && strcmp(written + n - 3, ".gz") == 0;
    *path = pbrt_resolve_path(ld, written);
    if (access(*path, R_OK) != 0)
        return pbrt_fail(file, line, "Shape \"plymesh\": cannot read '%s' (%s): %s", written,
                         *path, strerror(errno));
    if (pbrt_param_find(params, "displacement") || pbrt_param_find(params, "edgelength"))
        pbrt_warn(file, line, "Shape \"plymesh\": displacement is not simulated by idmr");
    if (gzipped ? read_gzipped_ply(*path, mesh) : mesh_io_read(*path, mesh))
        return error_prefix("%s:%d: Shape \"plymesh\"", file, line);
    return 0;
}

static int shape_sphere(const char *file, int line, pbrt_params *params, mesh_data *mesh)
{
    double radius, zmin, zmax, phimax;
    if (pbrt_param_float(file, params, "radius", 1.0, &radius) ||
        pbrt_param_float(file, params, "zmin", -radius, &zmin) ||
        pbrt_param_float(file, params, "zmax", radius, &zmax) ||
        pbrt_param_float(file, params, "phimax", 360.0, &phimax))
        return -1;
    if (!(radius > 0.0))
        return pbrt_fail(file, line, "Shape \"sphere\": the radius must be positive");
    if (zmin > -radius || zmax < radius || phimax < 360.0)
        pbrt_warn(file, line, "Shape \"sphere\": zmin, zmax and phimax are not read: the whole "
                              "sphere is used");
    static const double center[3] = {0, 0, 0};
    shapes_sphere(center, radius, SHAPES_SPHERE_RINGS, SHAPES_SPHERE_SEGMENTS, mesh);
    return 0;
}

static int shape_disk(const char *file, int line, pbrt_params *params, mesh_data *mesh)
{
    double height, radius, inner, phimax;
    if (pbrt_param_float(file, params, "height", 0.0, &height) ||
        pbrt_param_float(file, params, "radius", 1.0, &radius) ||
        pbrt_param_float(file, params, "innerradius", 0.0, &inner) ||
        pbrt_param_float(file, params, "phimax", 360.0, &phimax))
        return -1;
    if (!(radius > 0.0))
        return pbrt_fail(file, line, "Shape \"disk\": the radius must be positive");
    if (inner > 0.0 || phimax < 360.0)
        pbrt_warn(file, line, "Shape \"disk\": innerradius and phimax are not read: the whole "
                              "disk is used");
    shapes_disk(SHAPES_DISK_SEGMENTS, mesh);
    xform t = xform_translate(0, 0, height), s = xform_scale(radius, radius, 1);
    xform m = xform_multiply(&t, &s);
    xform_apply_points(&m, mesh->positions, mesh->vertex_count);
    return 0;
}

/* The mesh's name: the PLY file's stem, else the shape type; inside an object, prefixed with
 * the object's name. */
static void shape_name(const pbrt_loader *ld, const char *type, const char *written, char *out,
                       size_t size)
{
    char base[256];
    if (written) {
        const char *b = strrchr(written, '/') ? strrchr(written, '/') + 1 : written;
        const char *dot = strchr(b, '.');
        int length = dot && dot != b ? (int)(dot - b) : (int)strlen(b);
        snprintf(base, sizeof base, "%.*s", length, b);
    } else {
        snprintf(base, sizeof base, "%s", type);
    }
    if (ld->current_object)
        snprintf(out, size, "%s/%s", ld->current_object->name, base);
    else
        snprintf(out, size, "%s", base);
}

static int is_skipped_type(const char *type)
{
    static const char *const skipped[] = {"curve", "cylinder", "cone", "paraboloid",
                                          "hyperboloid", NULL};
    for (size_t i = 0; skipped[i]; i++)
        if (strcmp(type, skipped[i]) == 0)
            return 1;
    return 0;
}

int pbrt_read_shape(pbrt_loader *ld, const char *file, int line, long offset, const char *type,
                    pbrt_params *params)
{
    mesh_data mesh;
    char *mesh_path = NULL;
    int status;
    memset(&mesh, 0, sizeof mesh);
    if (is_skipped_type(type)) {
        for (size_t i = 0; i < params->count; i++)
            params->items[i].used = 1;
        pbrt_warn(file, line, "Shape \"%s\" is not simulated by idmr: left out", type);
        return 0;
    }
    if (strcmp(type, "trianglemesh") == 0)
        status = shape_triangles(file, line, params, &mesh);
    else if (strcmp(type, "plymesh") == 0)
        status = shape_plymesh(ld, file, line, params, &mesh, &mesh_path);
    else if (strcmp(type, "bilinearmesh") == 0)
        status = shape_bilinear(file, line, params, &mesh);
    else if (strcmp(type, "loopsubdiv") == 0) {
        long levels;
        status = pbrt_param_int(file, params, "levels", 3, &levels);
        if (!status)
            status = shape_triangles(file, line, params, &mesh);
        if (!status)
            pbrt_warn(file, line, "Shape \"loopsubdiv\": not subdivided: its control mesh is used");
    } else if (strcmp(type, "sphere") == 0)
        status = shape_sphere(file, line, params, &mesh);
    else if (strcmp(type, "disk") == 0)
        status = shape_disk(file, line, params, &mesh);
    else
        return pbrt_fail(file, line, "Shape: unknown shape type '%s'", type);
    if (status) {
        mesh_data_free(&mesh);
        free(mesh_path);
        return -1;
    }
    if (pbrt_param_find(params, "alpha"))
        pbrt_warn(file, line, "Shape: alpha (cut-outs) is not simulated by idmr");
    pbrt_param_find(params, "emissionfilename");
    const char *written = NULL;
    if (mesh_path)
        pbrt_param_string(file, params, "filename", NULL, &written);
    char name[512];
    shape_name(ld, type, written, name, sizeof name);
    int file_normals = mesh.normals != NULL && strcmp(type, "sphere") != 0;
    if (ld->current_object) {
        pbrt_object *o = ld->current_object;
        if (ld->state.area_light.active)
            pbrt_warn(file, line, "Shape inside an object under an AreaLightSource: instances do "
                                  "not emit");
        o->shapes = xrealloc(o->shapes, (o->shape_count + 1) * sizeof *o->shapes);
        pbrt_object_shape *shape = &o->shapes[o->shape_count++];
        memset(shape, 0, sizeof *shape);
        shape->mesh = mesh;
        shape->name = xstrdup(name);
        shape->shape_type = xstrdup(type);
        shape->file = mesh_path;
        shape->xml_file = xstrdup(file);
        shape->line = line;
        shape->offset = offset;
        shape->object_to_world = ld->state.ctm;
        shape->flipped = ld->state.reverse_orientation;
        shape->file_normals = file_normals;
        shape->material = ld->state.material;
        return 0;
    }
    shape_record rec = {name, type, mesh_path, file, line, offset, ld->state.reverse_orientation,
                        file_normals, ld->state.material};
    status = place_mesh(ld, &rec, &mesh, &ld->state.ctm, ld->state.area_light.active);
    free(mesh_path);
    return status;
}

/* The scene's last mesh, the first copy of object shape `shape`, placed by
 * `instance_to_world`: made the representative of that shape's copies (core/scene.h). */
static void mark_first_copy(scene *s, pbrt_object_shape *shape, const xform *instance_to_world)
{
    size_t copy = s->mesh_count - 1;
    scene_mesh *mesh = &s->meshes[copy];
    mesh->instanced = 1;
    mesh->instance_first = copy;
    memcpy(mesh->instance_to_world, instance_to_world->m, sizeof mesh->instance_to_world);
    shape->copied = 1;
    shape->first_copy = copy;
}

/* A later copy of object shape `shape` (placed once already), placed by `instance_to_world`:
 * no geometry of its own (core/scene.h: scene_add_instance_copy). 0, or -1 with the error set. */
static int add_later_copy(pbrt_loader *ld, const char *file, int line, pbrt_object_shape *shape,
                          const xform *instance_to_world)
{
    size_t first = shape->first_copy;
    scene_mesh *copy = scene_add_instance_copy(ld->s, first, shape->name, instance_to_world->m);
    if (!copy)
        return pbrt_fail(file, line, "ObjectInstance: %s", error_message());
    const scene_mesh *representative = &ld->s->meshes[first];
    copy->source_offset = representative->source_offset;
    copy->source_flipped = representative->source_flipped;
    xform to_world = xform_multiply(instance_to_world, &shape->object_to_world);
    memcpy(copy->object_to_world, to_world.m, sizeof copy->object_to_world);
    return 0;
}

int pbrt_instance_object(pbrt_loader *ld, const char *file, int line, const char *name,
                         const xform *instance_to_world)
{
    pbrt_object *o = NULL;
    for (size_t i = 0; i < ld->object_count; i++)
        if (strcmp(ld->objects[i].name, name) == 0)
            o = &ld->objects[i];
    if (!o)
        return pbrt_fail(file, line, "ObjectInstance: no object named '%s'", name);
    for (size_t i = 0; i < o->shape_count; i++) {
        pbrt_object_shape *shape = &o->shapes[i];
        if (shape->copied) {
            if (add_later_copy(ld, file, line, shape, instance_to_world))
                return -1;
            continue;
        }
        mesh_data copy;
        mesh_copy(&shape->mesh, &copy);
        xform to_world = xform_multiply(instance_to_world, &shape->object_to_world);
        shape_record rec = {shape->name,  shape->shape_type, shape->file,
                            shape->xml_file, shape->line,    shape->offset,
                            shape->flipped, shape->file_normals, shape->material};
        if (place_mesh(ld, &rec, &copy, &to_world, 0))
            return -1;
        mark_first_copy(ld->s, shape, instance_to_world);
    }
    return 0;
}

void pbrt_objects_free(pbrt_loader *ld)
{
    for (size_t i = 0; i < ld->object_count; i++) {
        pbrt_object *o = &ld->objects[i];
        for (size_t k = 0; k < o->shape_count; k++) {
            pbrt_object_shape *shape = &o->shapes[k];
            mesh_data_free(&shape->mesh);
            free(shape->name);
            free(shape->shape_type);
            free(shape->file);
            free(shape->xml_file);
        }
        free(o->shapes);
        free(o->name);
    }
    free(ld->objects);
    ld->objects = NULL;
    ld->object_count = 0;
}
