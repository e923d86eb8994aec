/* idmr/weight.h — the paper's Eq. 2, shared by the kernels and the host references.
 *
 * A path segment arriving at a triangle adds 1 - |n · d| to its importance, with n the unit
 * geometric normal and d the unit direction of the segment: 0 head-on, 1 at grazing incidence,
 * so silhouettes keep their detail. Neither n nor d needs to be unit length here. A zero-length
 * segment or a zero normal (a degenerate triangle) carries no direction and adds 0. */
#ifndef IDMR_WEIGHT_H
#define IDMR_WEIGHT_H

#include "idmr/layout.h"

#ifndef __OPENCL_VERSION__
#include <math.h>
#endif

IDMR_INLINE float idmr_eq2_weight(float nx, float ny, float nz, float dx, float dy, float dz)
{
    /* NaN anywhere: no direction (x != x only for NaN; fmax below would skip it). */
    if (nx != nx || ny != ny || nz != nz || dx != dx || dy != dy || dz != dz)
        return 0.0f;
    /* Scale both by their largest component first: no overflow for huge coordinates, no
     * underflow for tiny ones. */
    float dm = fmax(fabs(dx), fmax(fabs(dy), fabs(dz)));
    float nm = fmax(fabs(nx), fmax(fabs(ny), fabs(nz)));
    if (!(dm > 0.0f) || !(nm > 0.0f) || !(dm < INFINITY) || !(nm < INFINITY))
        return 0.0f;
    dx /= dm;
    dy /= dm;
    dz /= dm;
    nx /= nm;
    ny /= nm;
    nz /= nm;
    float c = fabs(nx * dx + ny * dy + nz * dz) /
              (sqrt(dx * dx + dy * dy + dz * dz) * sqrt(nx * nx + ny * ny + nz * nz));
    float w = 1.0f - c;
    return w < 0.0f ? 0.0f : (w > 1.0f ? 1.0f : w);
}

#endif
