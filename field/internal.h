/*
 * field/internal.h -- small 3-vector helpers shared by the files of field/
 * (not public).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_FIELD_INTERNAL_H
#define PZ_FIELD_INTERNAL_H

#include <math.h>

#define FIELD_PI 3.14159265358979323846

static inline void sub3(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}
static inline double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline void cross3(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}
/* Scales v to unit length (a zero vector stays zero); returns the old length. */
static inline double normalize3(double *v)
{
    double length = sqrt(dot3(v, v));
    if (length > 0.0)
        v[0] /= length, v[1] /= length, v[2] /= length;
    return length;
}

#endif
