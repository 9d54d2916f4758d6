/*
 * export/offset.h -- private to export/: the outward offset of a polygon
 * with a distance per edge (the cut line of a piece), and a self-intersection
 * count used to check it. Method and proofs: export/offset.c, docs/export.md.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_OFFSET_H
#define PZ_EXPORT_OFFSET_H

#include "mesh/mesh.h"

/* A mitre longer than this many allowances is cut off square (pattern makers' rule). */
#define PZ_OFFSET_MITRE_LIMIT 2.0

/**
 * Offsets a closed counter-clockwise polygon outward. points: count x 2;
 * distance: count, distance[i] > 0 for the edge points[i] -> points[i+1].
 * Convex corners are mitred while the mitre stays within
 * PZ_OFFSET_MITRE_LIMIT x the larger allowance, otherwise cut off square at
 * the allowance (equal allowances, or turns of 90 degrees and more) or, where
 * the allowance changes on a gentle corner, joined by an arc whose radius
 * runs from one allowance to the other. The result is the outer boundary of
 * the union of the polygon and every edge's and corner's allowance strip:
 * counter-clockwise, without self-crossings. *out (out_count x 2) is
 * malloc'd: the caller frees it. PZ_ERR_DATA for fewer than 3 distinct
 * points, PZ_ERR_INTERNAL when the boundary walk does not close.
 */
pz_status pz_offset_polygon(const double *points, int32_t count, const double *distance, double **out,
                            int32_t *out_count, pz_ctx *ctx);

/**
 * Crossings and touches between non-adjacent segments of a closed polygon
 * (count x 2), found by a sweep over x-sorted segments. -1 when out of memory.
 */
int32_t pz_offset_self_intersections(const double *points, int32_t count);

/** Signed area of a closed polygon (count x 2): > 0 when counter-clockwise. */
double pz_polygon_signed_area(const double *points, int32_t count);

#endif /* PZ_EXPORT_OFFSET_H */
