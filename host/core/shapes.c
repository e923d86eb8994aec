/* shapes.c — built-in Mitsuba shapes as triangle meshes (see shapes.h for the layouts). */
#include "core/shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

static void shapes_allocate(mesh_data *out, uint32_t vertices, uint32_t triangles, int with_uv)
{
    memset(out, 0, sizeof *out);
    out->vertex_count = vertices;
    out->triangle_count = triangles;
    out->positions = xmalloc(sizeof(float) * 3 * vertices);
    out->indices = xmalloc(sizeof(uint32_t) * 3 * triangles);
    out->texcoords = with_uv ? xmalloc(sizeof(float) * 2 * vertices) : NULL;
}

static void shapes_set_vertex(mesh_data *mesh, uint32_t v, double x, double y, double z)
{
    mesh->positions[3 * v] = (float)x;
    mesh->positions[3 * v + 1] = (float)y;
    mesh->positions[3 * v + 2] = (float)z;
}

static void shapes_set_triangle(mesh_data *mesh, uint32_t t, uint32_t a, uint32_t b, uint32_t c)
{
    mesh->indices[3 * t] = a;
    mesh->indices[3 * t + 1] = b;
    mesh->indices[3 * t + 2] = c;
}

void shapes_rectangle(mesh_data *out)
{
    static const double corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    shapes_allocate(out, 4, 2, 1);
    for (uint32_t v = 0; v < 4; v++) {
        shapes_set_vertex(out, v, corners[v][0], corners[v][1], 0.0);
        out->texcoords[2 * v] = (float)((corners[v][0] + 1.0) / 2.0);
        out->texcoords[2 * v + 1] = (float)((corners[v][1] + 1.0) / 2.0);
    }
    shapes_set_triangle(out, 0, 0, 1, 2);
    shapes_set_triangle(out, 1, 0, 2, 3);
}

void shapes_cube(mesh_data *out)
{
    /* Vertex v has x = +1 if bit 0 is set, y = +1 if bit 1, z = +1 if bit 2. Each face is a
     * quad listed counter-clockwise seen from outside. */
    static const uint32_t faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    shapes_allocate(out, 8, 12, 0);
    for (uint32_t v = 0; v < 8; v++)
        shapes_set_vertex(out, v, v & 1 ? 1.0 : -1.0, v & 2 ? 1.0 : -1.0, v & 4 ? 1.0 : -1.0);
    for (uint32_t f = 0; f < 6; f++) {
        const uint32_t *q = faces[f];
        shapes_set_triangle(out, 2 * f, q[0], q[1], q[2]);
        shapes_set_triangle(out, 2 * f + 1, q[0], q[2], q[3]);
    }
}

void shapes_disk(unsigned int segments, mesh_data *out)
{
    shapes_allocate(out, segments + 1, segments, 0);
    shapes_set_vertex(out, 0, 0.0, 0.0, 0.0);
    for (uint32_t i = 0; i < segments; i++) {
        double phi = 2.0 * M_PI * i / segments;
        shapes_set_vertex(out, i + 1, cos(phi), sin(phi), 0.0);
        shapes_set_triangle(out, i, 0, i + 1, (i + 1) % segments + 1);
    }
}

/* Vertex index of ring r (1 .. rings-1), segment s (wrapping) of a UV sphere. */
static uint32_t shapes_sphere_vertex(unsigned int segments, unsigned int r, unsigned int s)
{
    return 1 + (r - 1) * segments + s % segments;
}

void shapes_sphere(const double center[3], double radius, unsigned int rings, unsigned int segments,
                   mesh_data *out)
{
    uint32_t vertices = 2 + (rings - 1) * segments;
    uint32_t south = vertices - 1, t = 0;
    shapes_allocate(out, vertices, 2 * segments * (rings - 1), 0);
    shapes_set_vertex(out, 0, center[0], center[1], center[2] + radius);
    shapes_set_vertex(out, south, center[0], center[1], center[2] - radius);
    for (unsigned int r = 1; r < rings; r++) {
        double theta = M_PI * r / rings;
        for (unsigned int s = 0; s < segments; s++) {
            double phi = 2.0 * M_PI * s / segments;
            shapes_set_vertex(out, shapes_sphere_vertex(segments, r, s),
                              center[0] + radius * sin(theta) * cos(phi),
                              center[1] + radius * sin(theta) * sin(phi),
                              center[2] + radius * cos(theta));
        }
    }
    /* Mitsuba's sphere is smooth: its shading normal is the radial direction. */
    out->normals = xmalloc(sizeof(float) * 3 * vertices);
    for (uint32_t v = 0; v < vertices; v++)
        for (int k = 0; k < 3; k++)
            out->normals[3 * v + k] = (float)((out->positions[3 * v + k] - center[k]) / radius);
    for (unsigned int s = 0; s < segments; s++) {
        shapes_set_triangle(out, t++, 0, shapes_sphere_vertex(segments, 1, s),
                            shapes_sphere_vertex(segments, 1, s + 1));
        for (unsigned int r = 1; r + 1 < rings; r++) {
            uint32_t a = shapes_sphere_vertex(segments, r, s);
            uint32_t b = shapes_sphere_vertex(segments, r, s + 1);
            uint32_t c = shapes_sphere_vertex(segments, r + 1, s);
            uint32_t d = shapes_sphere_vertex(segments, r + 1, s + 1);
            shapes_set_triangle(out, t++, a, c, d);
            shapes_set_triangle(out, t++, a, d, b);
        }
        shapes_set_triangle(out, t++, shapes_sphere_vertex(segments, rings - 1, s), south,
                            shapes_sphere_vertex(segments, rings - 1, s + 1));
    }
}

void shapes_flip_winding(mesh_data *mesh)
{
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t swap = mesh->indices[3 * t + 1];
        mesh->indices[3 * t + 1] = mesh->indices[3 * t + 2];
        mesh->indices[3 * t + 2] = swap;
    }
}

void shapes_reverse_normals(mesh_data *mesh)
{
    for (size_t i = 0; mesh->normals && i < 3 * (size_t)mesh->vertex_count; i++)
        mesh->normals[i] = -mesh->normals[i];
}

void shapes_transform(mesh_data *mesh, const xform *to_world)
{
    xform_apply_points(to_world, mesh->positions, mesh->vertex_count);
    if (mesh->normals)
        xform_apply_normals(to_world, mesh->normals, mesh->vertex_count);
}

void shapes_transform_keeping_side(mesh_data *mesh, const xform *to_world)
{
    xform_apply_keeping_side(to_world, mesh->positions, mesh->normals, mesh->vertex_count,
                             mesh->indices, mesh->triangle_count);
}

/* The angle at corner a of triangle (a, b, c), in double. */
static double corner_angle(const float *a, const float *b, const float *c)
{
    double u[3], v[3], cross[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)b[k] - a[k];
        v[k] = (double)c[k] - a[k];
    }
    xform_cross(u, v, cross);
    return atan2(sqrt(xform_dot(cross, cross)), xform_dot(u, v));
}

/* Triangle t's corners into p and its unit geometric normal (by its winding) into n; returns 0
 * for a zero-area triangle (n is then zero). */
static double triangle_normal(const mesh_data *mesh, uint32_t t, const float *p[3], double n[3])
{
    const uint32_t *ix = &mesh->indices[3 * (size_t)t];
    for (int k = 0; k < 3; k++)
        p[k] = &mesh->positions[3 * (size_t)ix[k]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)p[1][k] - p[0][k];
        e2[k] = (double)p[2][k] - p[0][k];
    }
    xform_cross(e1, e2, n);
    return xform_normalize(n);
}

void shapes_smooth_normals(mesh_data *mesh)
{
    free(mesh->normals);
    double *sum = xcalloc(3 * (size_t)mesh->vertex_count, sizeof *sum);
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *ix = &mesh->indices[3 * (size_t)t];
        const float *p[3];
        double n[3];
        if (triangle_normal(mesh, t, p, n) == 0.0)
            continue; /* a zero-area triangle has no direction to give */
        for (int corner = 0; corner < 3; corner++) {
            double angle = corner_angle(p[corner], p[(corner + 1) % 3], p[(corner + 2) % 3]);
            for (int k = 0; k < 3; k++)
                sum[3 * (size_t)ix[corner] + k] += angle * n[k];
        }
    }
    mesh->normals = xmalloc(sizeof(float) * 3 * (size_t)mesh->vertex_count);
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        double *n = &sum[3 * (size_t)v];
        double length = xform_normalize(n);
        for (int k = 0; k < 3; k++)
            mesh->normals[3 * (size_t)v + k] = length > 0 ? (float)n[k] : 0.0f;
    }
    free(sum);
}

mesh_data shapes_scene_mesh_view(const scene_mesh *m)
{
    mesh_data view;
    memset(&view, 0, sizeof view);
    view.vertex_count = m->vertex_count;
    view.triangle_count = m->triangle_count;
    view.positions = m->positions;
    view.indices = m->indices;
    view.texcoords = m->texcoords;
    view.normals = m->normals;
    return view;
}

int shapes_normals_flat(const mesh_data *mesh)
{
    if (!mesh->normals)
        return 0;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const float *p[3];
        double n[3];
        if (triangle_normal(mesh, t, p, n) == 0.0)
            continue;
        for (int corner = 0; corner < 3; corner++) {
            const float *given = &mesh->normals[3 * (size_t)mesh->indices[3 * (size_t)t + corner]];
            double g[3] = {given[0], given[1], given[2]};
            if (xform_normalize(g) > 0.0 && xform_dot(g, n) < SHAPES_FLAT_COS)
                return 0;
        }
    }
    return 1;
}

double shapes_signed_volume(const mesh_data *mesh)
{
    double volume = 0.0;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        double p[3][3], cross[3];
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                p[k][i] = mesh->positions[3 * mesh->indices[3 * t + k] + i];
        xform_cross(p[1], p[2], cross);
        volume += xform_dot(p[0], cross) / 6.0;
    }
    return volume;
}
