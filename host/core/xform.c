/* xform.c — 4x4 affine transform maths (see xform.h). Row-major doubles, column vectors. */
#include "core/xform.h"

#include <math.h>
#include <string.h>

xform xform_identity(void)
{
    xform t;
    memset(&t, 0, sizeof t);
    t.m[0] = t.m[5] = t.m[10] = t.m[15] = 1.0;
    return t;
}

xform xform_multiply(const xform *a, const xform *b)
{
    xform out;
    for (int row = 0; row < 4; row++)
        for (int col = 0; col < 4; col++) {
            double sum = 0.0;
            for (int k = 0; k < 4; k++)
                sum += a->m[4 * row + k] * b->m[4 * k + col];
            out.m[4 * row + col] = sum;
        }
    return out;
}

/* The identity with x, y, z at the row-major positions `at` (one per row). */
static xform identity_with(const int at[3], double x, double y, double z)
{
    xform t = xform_identity();
    t.m[at[0]] = x;
    t.m[at[1]] = y;
    t.m[at[2]] = z;
    return t;
}

xform xform_translate(double x, double y, double z)
{
    static const int last_column[3] = {3, 7, 11};
    return identity_with(last_column, x, y, z);
}

xform xform_scale(double x, double y, double z)
{
    static const int diagonal[3] = {0, 5, 10};
    return identity_with(diagonal, x, y, z);
}

/* Rodrigues' formula: R = cos·I + sin·[a]× + (1 - cos)·a aᵀ for the unit axis a. */
xform xform_rotate(const double axis[3], double degrees)
{
    double a[3] = {axis[0], axis[1], axis[2]};
    xform t = xform_identity();
    if (xform_normalize(a) == 0.0)
        return t;
    double angle = degrees * (M_PI / 180.0);
    double s = sin(angle), c = cos(angle), k = 1.0 - c;
    t.m[0] = c + k * a[0] * a[0];
    t.m[1] = k * a[0] * a[1] - s * a[2];
    t.m[2] = k * a[0] * a[2] + s * a[1];
    t.m[4] = k * a[1] * a[0] + s * a[2];
    t.m[5] = c + k * a[1] * a[1];
    t.m[6] = k * a[1] * a[2] - s * a[0];
    t.m[8] = k * a[2] * a[0] - s * a[1];
    t.m[9] = k * a[2] * a[1] + s * a[0];
    t.m[10] = c + k * a[2] * a[2];
    return t;
}

int xform_lookat(const double origin[3], const double target[3], const double up[3], xform *out)
{
    double dir[3] = {target[0] - origin[0], target[1] - origin[1], target[2] - origin[2]};
    double left[3], new_up[3];
    if (xform_normalize(dir) == 0.0)
        return -1;
    xform_cross(up, dir, left);
    if (xform_normalize(left) < 1e-12)
        return -1;
    xform_cross(dir, left, new_up);
    *out = xform_identity();
    for (int row = 0; row < 3; row++) {
        out->m[4 * row + 0] = left[row];
        out->m[4 * row + 1] = new_up[row];
        out->m[4 * row + 2] = dir[row];
        out->m[4 * row + 3] = origin[row];
    }
    return 0;
}

xform xform_from_rows(const double values[16])
{
    xform t;
    memcpy(t.m, values, sizeof t.m);
    return t;
}

xform xform_from_3x3(const double values[9])
{
    xform t = xform_identity();
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 3; col++)
            t.m[4 * row + col] = values[3 * row + col];
    return t;
}

void xform_apply_point(const xform *t, const double p[3], double out[3])
{
    double r[4];
    for (int row = 0; row < 4; row++)
        r[row] = t->m[4 * row] * p[0] + t->m[4 * row + 1] * p[1] + t->m[4 * row + 2] * p[2] +
                 t->m[4 * row + 3];
    /* Affine transforms keep w = 1; divide anyway for a general 4x4 from a <matrix>. */
    double w = r[3] != 0.0 ? r[3] : 1.0;
    for (int i = 0; i < 3; i++)
        out[i] = r[i] / w;
}

void xform_apply_vector(const xform *t, const double v[3], double out[3])
{
    double r[3];
    for (int row = 0; row < 3; row++)
        r[row] = t->m[4 * row] * v[0] + t->m[4 * row + 1] * v[1] + t->m[4 * row + 2] * v[2];
    memcpy(out, r, sizeof r);
}

void xform_apply_points(const xform *t, float *xyz, unsigned long count)
{
    for (unsigned long i = 0; i < count; i++) {
        double p[3] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}, q[3];
        xform_apply_point(t, p, q);
        for (int k = 0; k < 3; k++)
            xyz[3 * i + k] = (float)q[k];
    }
}

void xform_apply_normals(const xform *t, float *xyz, unsigned long count)
{
    const double *m = t->m;
    /* cofactor[row][col] of the 3x3 linear part, m[4 * row + col] */
    double c[9] = {m[5] * m[10] - m[6] * m[9], m[6] * m[8] - m[4] * m[10], m[4] * m[9] - m[5] * m[8],
                   m[2] * m[9] - m[1] * m[10], m[0] * m[10] - m[2] * m[8], m[1] * m[8] - m[0] * m[9],
                   m[1] * m[6] - m[2] * m[5], m[2] * m[4] - m[0] * m[6], m[0] * m[5] - m[1] * m[4]};
    for (unsigned long i = 0; i < count; i++) {
        double n[3], out[3];
        for (int k = 0; k < 3; k++)
            n[k] = xyz[3 * i + k];
        for (int row = 0; row < 3; row++)
            out[row] = c[3 * row] * n[0] + c[3 * row + 1] * n[1] + c[3 * row + 2] * n[2];
        double length = xform_normalize(out);
        for (int k = 0; k < 3; k++)
            xyz[3 * i + k] = length > 0 ? (float)out[k] : 0.0f;
    }
}

double xform_determinant3(const xform *t)
{
    const double *m = t->m;
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

int xform_invert_affine(const xform *t, xform *out)
{
    const double *m = t->m;
    double det = xform_determinant3(t);
    if (!(det != 0.0 && isfinite(det)))
        return -1;
    /* the inverse of the linear part: its cofactors, transposed, over the determinant */
    double inverse[9] = {
        m[5] * m[10] - m[6] * m[9], m[2] * m[9] - m[1] * m[10], m[1] * m[6] - m[2] * m[5],
        m[6] * m[8] - m[4] * m[10], m[0] * m[10] - m[2] * m[8], m[2] * m[4] - m[0] * m[6],
        m[4] * m[9] - m[5] * m[8],  m[1] * m[8] - m[0] * m[9],  m[0] * m[5] - m[1] * m[4]};
    *out = xform_identity();
    for (int row = 0; row < 3; row++) {
        double translation = 0.0;
        for (int col = 0; col < 3; col++) {
            out->m[4 * row + col] = inverse[3 * row + col] / det;
            translation -= out->m[4 * row + col] * m[4 * col + 3];
        }
        out->m[4 * row + 3] = translation;
    }
    return 0;
}

void xform_to_float(const xform *t, float out[16])
{
    for (int i = 0; i < 16; i++)
        out[i] = (float)t->m[i];
}

double xform_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void xform_cross(const double a[3], const double b[3], double out[3])
{
    double r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(out, r, sizeof r);
}

double xform_normalize(double v[3])
{
    double length = sqrt(xform_dot(v, v));
    if (length > 0.0)
        for (int i = 0; i < 3; i++)
            v[i] /= length;
    return length;
}

void xform_apply_keeping_side(const xform *t, float *positions, float *normals,
                              unsigned long count, unsigned int *indices,
                              unsigned long triangle_count)
{
    xform_apply_points(t, positions, count);
    if (normals)
        xform_apply_normals(t, normals, count);
    if (!(xform_determinant3(t) < 0.0))
        return;
    /* the cofactor's normals point to det × the inverse transpose's: turn them back */
    for (unsigned long i = 0; normals && i < 3 * count; i++)
        normals[i] = -normals[i];
    for (unsigned long k = 0; k < triangle_count; k++) {
        unsigned int swap = indices[3 * k + 1];
        indices[3 * k + 1] = indices[3 * k + 2];
        indices[3 * k + 2] = swap;
    }
}
