/* xform.h — 4x4 affine transforms: the scene loaders' (Mitsuba <transform> elements, pbrt-v4
 * statements, glTF nodes) and the instances' placements (core/scene.h).
 *
 * An xform holds a row-major 4x4 matrix in double precision: m[4*row + col]. Points are
 * column vectors, p' = M p, so the translation sits in m[3], m[7], m[11]. Composition follows
 * Mitsuba: each child of a <transform> left-multiplies what came before (M = child * M), so
 * later operations apply after earlier ones. Angles are in degrees, as in Mitsuba files. */
#ifndef IDMR_XFORM_H
#define IDMR_XFORM_H

typedef struct xform {
    double m[16];
} xform;

xform xform_identity(void);

/* a * b: apply b first, then a. */
xform xform_multiply(const xform *a, const xform *b);

xform xform_translate(double x, double y, double z);
xform xform_scale(double x, double y, double z);

/* Right-handed rotation by `degrees` about `axis` (any length but zero). */
xform xform_rotate(const double axis[3], double degrees);

/* Mitsuba's lookat: camera space +z looks from origin to target, +y is `up` made orthogonal,
 * +x = up × direction (which is image-left for a Mitsuba camera). Returns -1 when target equals
 * origin or up is parallel to the viewing direction, else 0. */
int xform_lookat(const double origin[3], const double target[3], const double up[3], xform *out);

/* From 16 row-major values, or from a 3x3 row-major linear part (no translation). */
xform xform_from_rows(const double values[16]);
xform xform_from_3x3(const double values[9]);

void xform_apply_point(const xform *t, const double p[3], double out[3]);
void xform_apply_vector(const xform *t, const double v[3], double out[3]);

/* Transforms `count` xyz float points in place. */
void xform_apply_points(const xform *t, float *xyz, unsigned long count);

/* Transforms `count` xyz float normals in place by the inverse transpose of the linear part
 * (its cofactor matrix: the same direction, without inverting) and normalises them; a normal
 * that is zero, or that the transform collapses, becomes zero. Orientation is not kept under a
 * mirroring transform (callers orient shading normals by the geometric one). */
void xform_apply_normals(const xform *t, float *xyz, unsigned long count);

/* Determinant of the linear 3x3 part (negative: the transform mirrors). */
double xform_determinant3(const xform *t);

/* Moves a triangle mesh by `t` as Mitsuba moves a built-in shape or an instance: `count`
 * points by t, their normals (NULL: none) by its inverse transpose, and under a mirror
 * (det < 0) the winding of the `triangle_count` triangles of `indices` reversed, so that the
 * surface keeps its side. */
void xform_apply_keeping_side(const xform *t, float *positions, float *normals,
                              unsigned long count, unsigned int *indices,
                              unsigned long triangle_count);

/* The inverse of an affine transform (the last row taken as 0 0 0 1) into *out: 0, or -1 when
 * its linear part is singular (or not finite). */
int xform_invert_affine(const xform *t, xform *out);

void xform_to_float(const xform *t, float out[16]);

/* Small 3-vector helpers shared by the loader. */
double xform_dot(const double a[3], const double b[3]);
void xform_cross(const double a[3], const double b[3], double out[3]);
/* Normalises v in place; returns its former length. */
double xform_normalize(double v[3]);

#endif
