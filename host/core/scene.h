/* scene.h — the in-memory scene every pass works on.
 *
 * A scene is what a Mitsuba file describes, reduced to what idmr simulates: triangle meshes in
 * world space (every shape is tessellated on load), materials (idmr/material.h), lights
 * (idmr/light.h), one pinhole camera (idmr/camera.h) and textures. Triangles are numbered
 * scene-globally: mesh m's triangle t is scene triangle meshes[m].first_triangle + t; the
 * importance buffers, the BVH and area lights all use that numbering.
 *
 * Building: scene_create(), then scene_add_*() from a loader (host/io/mitsuba/mitsuba*.c), then
 * scene_finalize(), which numbers the triangles, fills the area lights' triangle ranges,
 * areas and powers, the bounding box and the feature bits. */
#ifndef IDMR_SCENE_H
#define IDMR_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include "idmr/camera.h"
#include "idmr/features.h"
#include "idmr/light.h"
#include "idmr/material.h"

typedef struct scene_mesh {
    char *name;       /* unique in the scene: the shape's id, else the file's stem, else type+n */
    char *shape_type; /* Mitsuba shape type: obj, ply, rectangle, cube, sphere, disk, ... */
    char *file;       /* resolved path of the mesh file; NULL for built-in shapes */
    char *xml_file;   /* the XML file holding the <shape> element (the scene or an include);
                         a glTF scene: the glTF file */
    int xml_line;     /* line of the <shape> element in that file; a glTF scene: the number
                         of the mesh instance (io/gltf/gltf.h) */
    uint32_t vertex_count;
    uint32_t triangle_count;
    float *positions;  /* world space, xyz per vertex */
    uint32_t *indices; /* three vertex indices per triangle */
    float *texcoords;  /* uv per vertex as Mitsuba reads them (an OBJ's v turned), or NULL */
    float *normals;    /* world-space unit shading normal per vertex, or NULL: shaded flat.
                        * The loader sets them (core/shapes.h: shapes_smooth_normals); a zero
                        * normal shades its triangles flat. Owned by the scene. */
    int file_normals;  /* the normals are the mesh file's own; 0: computed by the loader, or
                        * none (a reduced mesh writes both kinds unless told to leave computed
                        * ones to the reader: reduce.h, recompute_normals) */
    int flat_normals;  /* the file's normals shade the mesh flat (core/shapes.h:
                        * shapes_normals_flat): a reduced mesh says face_normals instead */
    uint32_t triangles_dropped; /* triangles the file gave that repeat a vertex (f 1 2 1, the
                                   joins of a triangle strip), left out on load (io/mesh/mesh_io.h)
                                   and so in no numbering: `idmr info` counts them */
    uint32_t material; /* index into scene.materials */
    int light;         /* index into scene.lights if the shape is an area emitter, else -1 */
    uint32_t first_triangle; /* set by scene_finalize() */
    /* Streaming (scene_mesh_release): a mesh the loader can read again may have its geometry
     * (positions, indices, texcoords, normals) out of memory; the counts, flags and these stay. */
    int released;            /* the geometry is not in memory: scene_mesh_restore() reads it */
    int no_area;             /* of a released mesh: every triangle degenerate */
    int had_texcoords, had_normals; /* of a released mesh: what its geometry holds */
    float box_min[3], box_max[3]; /* of a released mesh: its bounding box */
    struct scene_mesh_source *source; /* how the loader reads it again; NULL: it cannot */
    /* A pbrt-v4 scene (io/pbrt/pbrt.h), for the writer; zero for the other formats. */
    long source_offset;         /* byte offset of the `Shape` keyword in xml_file */
    double object_to_world[16]; /* row-major: the transform the shape's points were given in */
    int source_flipped;         /* the loader reversed the winding the statement gives */
    /* A Mitsuba scene's copy of a shapegroup's shape placed by a <shape type="instance">
     * (io/mitsuba/mitsuba_shape.c): the file and line of the
     * instance element (xml_file and xml_line name the group's <shape>); NULL and 0 for any
     * other mesh. */
    char *instance_xml_file;
    int instance_xml_line;
    /* A copy an instance placed (instanced set): of a Mitsuba shapegroup's shape (above), of a
     * pbrt-v4 object's shape placed by ObjectInstance, of a glTF primitive whose mesh several
     * nodes name. The shape is the scene's prototype, held once:
     *   - instance_first is the mesh index of the first copy of the same shape, its
     *     representative (itself for that copy), instance_next the next copy, or 0 after the
     *     last (a later copy is never mesh 0), instance_last (of the representative) the last;
     *   - instance_to_world (row-major 4x4) is the instance's transform: a copy's points are
     *     instance_to_world times the prototype's (the shape's own transform applied), its
     *     winding reversed where the transform mirrors;
     *   - the representative holds the geometry, in its own world space; a later copy
     *     (scene_mesh_is_later_copy) holds none: it is released (`released`, its box set) and
     *     without a source, its counts are the representative's, its triangles are the
     *     representative's (first_triangle: every per-triangle buffer, the importance
     *     included, is per prototype and sums over the copies), and scene_mesh_restore() makes
     *     its world-space geometry from the representative's (scene_instance_placement).
     * All zero for any other mesh. */
    int instanced;
    size_t instance_first, instance_next, instance_last;
    double instance_to_world[16];
} scene_mesh;

/* How a loader reads a mesh's geometry again (the loader's own type), and the functions it
 * gives the scene for that: restore fills the mesh's geometry exactly as the load did. */
typedef struct scene_mesh_source scene_mesh_source;
typedef int (*scene_mesh_restore_fn)(const scene_mesh_source *source, scene_mesh *mesh);
typedef void (*scene_mesh_source_free_fn)(scene_mesh_source *source);

typedef struct scene_material_info {
    char *name;      /* the bsdf's id, or "<shape name>/bsdf" for an inline one */
    char *bsdf_type; /* the innermost Mitsuba type, e.g. roughplastic */
} scene_material_info;

typedef struct scene_texture {
    char *file; /* resolved path */
    int width;
    int height;
    float *rgb;      /* linear RGB, row-major, top row first */
    float mean[3];
} scene_texture;

typedef struct scene_camera_info {
    float fov_degrees; /* as given */
    char fov_axis[16]; /* x, y, diagonal, smaller, larger */
    float to_world[16]; /* row-major 4x4 */
} scene_camera_info;

/* The environment light's map: at most one per scene, as in Mitsuba 3. Equirectangular in
 * Mitsuba's frame (idmr/environment.h), linear radiance with the emitter's scale applied, top
 * row first; a constant environment is a 1 × 1 map. width 0: the scene has none. */
typedef struct scene_environment {
    int width, height;
    float *rgb;                /* 3 per pixel, no negative values */
    double to_world[9];        /* the map frame's rotation into the world, row-major */
    double to_map[9];          /* its inverse */
    double luminance_integral; /* ∫ Y(L(ω)) dω over the sphere */
    char *file;                /* the map's file; NULL for a constant */
} scene_environment;

typedef struct scene {
    char *file; /* the scene file as given */
    char *dir;  /* its directory: relative paths in the file resolve from here */

    scene_mesh *meshes;
    size_t mesh_count;
    size_t *mesh_names;         /* hash index of the mesh names: mesh index + 1, 0 empty */
    unsigned *mesh_name_next;   /* per slot of mesh_names: the suffix a repeat of its name
                                   tries first (every one below it is taken) */
    size_t mesh_name_capacity;  /* a power of two, at least twice mesh_count */

    idmr_material *materials;
    scene_material_info *material_info;
    size_t material_count;

    idmr_light *lights;
    size_t light_count;

    scene_texture *textures;
    size_t texture_count;

    scene_environment environment;

    idmr_camera camera;
    scene_camera_info camera_info;
    int has_camera;

    /* Set by scene_finalize(). */
    scene_mesh_restore_fn restore_mesh;        /* set by a loader that gives meshes sources */
    scene_mesh_source_free_fn free_mesh_source;
    uint64_t vertex_count;   /* stored: a prototype's vertices counted once */
    uint64_t triangle_count; /* numbered: a prototype's triangles counted once */
    uint64_t rendered_vertex_count; /* every copy counted: what a flattened scene would hold */
    uint64_t rendered_triangle_count;
    size_t *numbered_meshes;    /* the meshes that are not later copies, in order: their
                                   first_triangle increases (scene_mesh_of_triangle) */
    size_t numbered_mesh_count;
    float bbox_min[3];
    float bbox_max[3];
    unsigned int features; /* IDMR_FEATURE_* bits */
    double load_seconds;   /* set by scene_load(): reading the file and its meshes */
} scene;

scene *scene_create(const char *file);
void scene_free(scene *s);

/* Adds a mesh and takes ownership of positions, indices and texcoords (malloc'd, may be NULL
 * when the counts are 0). name is copied and made unique. Triangles that repeat a vertex are
 * left out (scene_triangles_drop_repeating) and counted in the mesh's triangles_dropped; the
 * vertices stay as given. Returns the new mesh. */
scene_mesh *scene_add_mesh(scene *s, const char *name, const char *shape_type, const char *file,
                           int xml_line, uint32_t vertex_count, float *positions,
                           uint32_t triangle_count, uint32_t *indices, float *texcoords);

/* Adds a later copy of the instanced shape whose representative is mesh `representative`
 * (which the loader marked: instanced, instance_first itself, instance_to_world its own
 * placement), placed by `to_world` (row-major 4x4, as instance_to_world): no geometry of its
 * own (see scene_mesh), its box the representative's geometry carried by the placement (the
 * representative's box's corners when that is released), chained after the last copy. The name
 * is copied and made unique; file, shape type, XML place, material and flags are the
 * representative's. Returns the new mesh. */
scene_mesh *scene_add_instance_copy(scene *s, size_t representative, const char *name,
                                    const double to_world[16]);

/* Whether mesh m is an instanced shape's copy other than its first (no geometry of its own). */
static inline int scene_mesh_is_later_copy(const scene *s, size_t m)
{
    return s->meshes[m].instanced && s->meshes[m].instance_first != m;
}

/* The row-major 4x4 that carries mesh m's representative's world-space geometry to mesh m's:
 * T_m T_first^-1 of their instance_to_world (the identity for a mesh that is not a later copy).
 * Returns 0, or -1 with the error set when the representative's transform is singular. */
int scene_instance_placement(const scene *s, size_t m, double object_to_world[16]);

/* Removes from the `*triangle_count` triangles of `indices` those that name one vertex twice
 * (no area; no half-edge mesh, OpenMesh's included, can hold one), keeping the others in
 * order; sets *triangle_count to what remains and returns how many went. */
uint32_t scene_triangles_drop_repeating(uint32_t *indices, uint32_t *triangle_count);

/* Adds a material; returns its index. */
uint32_t scene_add_material(scene *s, const char *name, const char *bsdf_type,
                            const idmr_material *material);

/* Adds a light; returns its index. For an area light, set the mesh's `light` to it; the
 * triangle range, area and power are filled by scene_finalize(). */
int scene_add_light(scene *s, const idmr_light *light);

/* The index of the texture read from `file`, or -1 when none was added. */
int scene_find_texture(const scene *s, const char *file);

/* Adds the texture read from `file` (linear RGB, width × height, top row first) and takes
 * ownership of rgb (malloc'd); its mean is computed here. Returns its index. */
int scene_add_texture(scene *s, const char *file, int width, int height, float *rgb);

/* Adds the environment light: sets the scene's map (see scene_environment), taking ownership
 * of rgb (malloc'd; negative values are set to 0; freed on failure too), and adds an
 * IDMR_LIGHT_ENVIRONMENT light whose emission is the map's mean radiance over the sphere; file
 * may be NULL. Returns the light's index, or -1 with the error set when the scene has an
 * environment already, to_world is singular, or a value is not finite. */
int scene_add_environment(scene *s, const char *file, int width, int height, float *rgb,
                          const double to_world[9]);

/* Solid angle of a pixel in row `row` of an equirectangular map of width × height. */
double scene_environment_pixel_solid_angle(int width, int height, int row);

/* Outputs never touch inputs. The files a scene reads are its file, the XML file of each
 * shape, each mesh file, texture and the environment map. scene_check_output_directory()
 * refuses a directory that is, or lies above, one of them (the scene's own directory, however
 * spelled, or any of its parents); scene_check_output_file() refuses a path that is one of
 * them. Both compare realpaths; a path that does not exist yet passes. 0, or -1 with the error
 * set (IDMR_EXIT_INPUT) naming the output and the input. */
int scene_check_output_directory(const scene *s, const char *dir);
int scene_check_output_file(const scene *s, const char *path);

/* The largest coordinate magnitude a scene may have. The importance pass is scale-invariant up
 * to it (test_importance_invariants: the Cornell box scaled to coordinates of 5.6e10); from
 * about 1e12 on its 32-bit float arithmetic loses light importance, from 1e15 camera
 * importance, and beyond 1e38 the BVH builder's binning overflows (Embree aborts). */
#define SCENE_COORDINATE_LIMIT 1e11f

/* Streaming. scene_mesh_release() frees mesh m's geometry, first noting its bounding box and
 * whether it has area (scene_finalize() and the reduction use those while it is out); a mesh
 * without a source, an emitter, and one already released are left as they are.
 * scene_mesh_restore() reads a released mesh's geometry again through the loader (0 when it is
 * in memory already); the counts must be those it had, or it fails naming the mesh. 0, or -1
 * with the error set. A later copy of an instanced shape is released from its creation; restoring
 * it makes its world-space geometry from its representative's (restored first if need be),
 * and releasing it frees that again. */
void scene_mesh_release(scene *s, size_t m);
int scene_mesh_restore(scene *s, size_t m);

/* Points mesh's geometry at the arrays given (taking them over or sharing them is the caller's
 * affair) and marks it in memory. */
void scene_mesh_set_geometry(scene_mesh *mesh, uint32_t vertex_count, float *positions,
                             uint32_t triangle_count, uint32_t *indices, float *texcoords,
                             float *normals);

/* A view of `s`: a copy of the scene struct with its own arrays of meshes and lights, sharing
 * everything else (names, materials, textures, the meshes' geometry) with `s`, which must
 * outlive it unchanged. The caller may point a view mesh's positions, indices, texcoords and
 * normals (with their counts) at other geometry, then must scene_finalize() the view before
 * use. Freed with scene_view_free(), which frees only the view's own arrays, never the geometry. */
scene *scene_view(const scene *s);
void scene_view_free(scene *view);

/* Numbers triangles (a later copy's are its representative's, its counts set to the
 * representative's), completes area lights, computes bbox and feature bits
 * (IDMR_FEATURE_INSTANCES when a later copy exists). Returns 0, or -1
 * with the error set (for example a scene with more than 2^32 - 1 triangles, or a coordinate
 * beyond SCENE_COORDINATE_LIMIT). */
int scene_finalize(scene *s);

/* Area of triangle t of mesh m, from the cross product in double: accurate for slivers, and
 * exactly 0 for degenerate triangles (collinear or repeated vertices). */
double scene_mesh_triangle_area(const scene_mesh *m, uint32_t t);
/* The area of the triangle (a, b, c), in double from the float corners (0 exactly when the
 * edges' cross product is: what "degenerate" means everywhere in idmr). */
double triangle_area(const float *a, const float *b, const float *c);

/* Area of scene triangle `triangle` (0 for degenerate ones). */
double scene_triangle_area(const scene *s, uint64_t triangle);

/* Length of the bounding box's diagonal (0 for an empty scene). */
double scene_diagonal(const scene *s);

/* Which mesh holds scene triangle `triangle` (binary search over first_triangle); never a later
 * copy of an instanced shape (its triangles are its representative's). */
size_t scene_mesh_of_triangle(const scene *s, uint64_t triangle);

/* Names, for reports. */
const char *scene_feature_name(unsigned int feature_bit);
const char *scene_material_kind_name(unsigned int kind);
const char *scene_light_kind_name(unsigned int kind);

#endif
