/*
 * field/internal.h -- what the cross-field's files share, not part of the
 * public interface (field/field.h is): the per-face frames of
 * field/crossfield.c, read by the sketch snapping of field/sketch.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_FIELD_INTERNAL_H
#define PZ_FIELD_INTERNAL_H

#include "field/field.h"

/* A frame per face: e1 along its first edge, e2 = n x e1 (crossfield.c, frames_build). */
typedef struct field_frames {
    double *e1, *e2, *n;  /* face_count x 3 each */
    double *area;         /* face_count */
    double mean_area;
} field_frames;

/* Per-face 4th-power sums of the sketch tangents in the faces' frames (re, im: face_count each, added to):
 * the polylines sampled every quarter mean edge, each sample snapped to the closest face. 0 when out of
 * memory. field/sketch.c. */
int field_sketch_accumulate(const pz_mesh *mesh, const field_frames *fr, const pz_sketch *sketch, double mean_edge,
                            double *re, double *im);

#endif
