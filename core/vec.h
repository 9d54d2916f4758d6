/*
 * core/vec.h -- small 3-vector maths shared by every stage (header only).
 * Vectors are `double[3]`; results are written to `out`, which may alias an
 * input.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_CORE_VEC_H
#define PZ_CORE_VEC_H

#include <math.h>

#define PZ_PI 3.14159265358979323846

static inline void pz_vec3_sub(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}

static inline double pz_vec3_dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline void pz_vec3_cross(const double *a, const double *b, double *out)
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}

static inline double pz_vec3_norm(const double *a) { return sqrt(pz_vec3_dot(a, a)); }

static inline double pz_vec3_distance(const double *a, const double *b)
{
    double d[3];
    pz_vec3_sub(a, b, d);
    return pz_vec3_norm(d);
}

/* Scales v to unit length (a zero vector stays zero); returns the old length. */
static inline double pz_vec3_normalize(double *v)
{
    double length = sqrt(pz_vec3_dot(v, v));
    if (length > 0.0)
        v[0] /= length, v[1] /= length, v[2] /= length;
    return length;
}

#endif /* PZ_CORE_VEC_H */
