/*
 * tests/export/marker_checks.h -- every property the issue asks of a marker
 * (pz_marker_build), shared by test_marker.c and test_run_patterns.c: every
 * copy placed once, rotations 0 or 180 only, every cut line inside
 * [0, width] and above y = 0, no two placed cut lines closer than the gap
 * (exact polygon distance, crossings and containment included), the second
 * copy of a Cut-2 piece the mirror image of the first and placed beside it
 * (a pair), length = the highest placed point, efficiency = areas / (width
 * x length). Needs test_util.h (CHECK, REQUIRE).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_MARKER_CHECKS_H
#define PZ_TEST_MARKER_CHECKS_H

#include "../test_util.h"
#include "export/export.h"
#include "piece_checks.h"

#include <math.h>
#include <stdlib.h>

/* ------------------------------------------------------------------ geometry checks */

static inline double point_segment(const double *p, const double *a, const double *b)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
}

static inline int segments_cross(const double *a, const double *b, const double *c, const double *d)
{
    double d1 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    double d2 = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
    double d3 = (d[0] - c[0]) * (a[1] - c[1]) - (d[1] - c[1]) * (a[0] - c[0]);
    double d4 = (d[0] - c[0]) * (b[1] - c[1]) - (d[1] - c[1]) * (b[0] - c[0]);
    return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

/* Distance between two closed polygons; 0 when they cross or one contains the other. */
static inline double polygon_distance(const double *p, int32_t n, const double *q, int32_t m)
{
    if (point_in_polygon(p, q, m) || point_in_polygon(q, p, n))
        return 0.0;
    double best = INFINITY;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = &p[2 * i], *b = &p[2 * ((i + 1) % n)];
        for (int32_t j = 0; j < m; ++j) {
            const double *c = &q[2 * j], *d = &q[2 * ((j + 1) % m)];
            if (segments_cross(a, b, c, d))
                return 0.0;
            best = fmin(best, fmin(fmin(point_segment(a, c, d), point_segment(b, c, d)),
                                   fmin(point_segment(c, a, b), point_segment(d, a, b))));
        }
    }
    return best;
}

static inline double *placed(const pz_pieces *pieces, const pz_marker_placement *placement)
{
    const pz_piece *piece = &pieces->pieces[placement->piece];
    double *points = malloc((size_t)piece->cut_count * 2 * sizeof(double));
    REQUIRE(points, "out of memory");
    pz_marker_place_points(piece, placement, piece->cut, piece->cut_count, points);
    return points;
}

/* Every property the issue asks of a marker. */
static inline void check_marker(const pz_pieces *pieces, const pz_marker *marker, const pz_export_options *options)
{
    int32_t expected = 0;
    double area = 0.0, top = 0.0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        expected += pieces->pieces[p].mirrored ? 0 : pieces->pieces[p].cut_quantity;
    /* Pieces left out must be wider than the fabric (their copies are not placed). */
    for (int32_t i = 0; i < marker->unplaced_count; ++i) {
        const pz_piece *piece = &pieces->pieces[marker->unplaced[i]];
        double lo = INFINITY, hi = -INFINITY;
        for (int32_t k = 0; k < piece->cut_count; ++k)
            lo = fmin(lo, piece->cut[2 * k]), hi = fmax(hi, piece->cut[2 * k]);
        CHECK(hi - lo > marker->fabric_width_mm - 20, "piece %s (%.0f mm) left out of a %.0f mm fabric", piece->name,
              hi - lo, marker->fabric_width_mm);
        expected -= piece->cut_quantity;
    }
    CHECK(marker->placement_count == expected, "%d placements, %d copies", (int)marker->placement_count,
          (int)expected);
    double **points = calloc((size_t)marker->placement_count, sizeof *points);
    REQUIRE(points, "out of memory");
    for (int32_t i = 0; i < marker->placement_count; ++i) {
        const pz_marker_placement *placement = &marker->placements[i];
        const pz_piece *piece = &pieces->pieces[placement->piece];
        CHECK(placement->rotation_deg == 0 || placement->rotation_deg == 180, "rotation %d", placement->rotation_deg);
        CHECK(placement->mirrored == (placement->copy == 1), "copy %d mirrored %d", (int)placement->copy,
              placement->mirrored);
        points[i] = placed(pieces, placement);
        for (int32_t k = 0; k < piece->cut_count; ++k) {
            double x = points[i][2 * k], y = points[i][2 * k + 1];
            CHECK(x >= -1e-9 && x <= options->fabric_width_mm + 1e-9 && y >= -1e-9, "%s at (%g, %g)", piece->name, x,
                  y);
            top = fmax(top, y);
        }
        area += piece->area_mm2;
    }
    int32_t too_close = 0;
    double closest = INFINITY;
    for (int32_t i = 0; i < marker->placement_count; ++i)
        for (int32_t j = i + 1; j < marker->placement_count; ++j) {
            const pz_piece *a = &pieces->pieces[marker->placements[i].piece];
            const pz_piece *b = &pieces->pieces[marker->placements[j].piece];
            double d = polygon_distance(points[i], a->cut_count, points[j], b->cut_count);
            closest = fmin(closest, d);
            too_close += d < options->gap_mm - 1e-6;
        }
    CHECK(too_close == 0, "%d pairs closer than the %.1f mm gap (closest %.3f)", (int)too_close, options->gap_mm,
          closest);
    /* Cut-2 pieces: the two copies are mirror images of each other (x -> c - x at the same rotation, y -> c - y
     * when one is turned 180 degrees: the grain stays along y), side by side as a pair or each on its own (the
     * search chooses). */
    for (int32_t i = 0; i < marker->placement_count; ++i)
        for (int32_t j = 0; j < marker->placement_count; ++j) {
            const pz_marker_placement *first = &marker->placements[i], *second = &marker->placements[j];
            if (first->piece != second->piece || first->copy != 0 || second->copy != 1)
                continue;
            const pz_piece *piece = &pieces->pieces[first->piece];
            int turned = first->rotation_deg != second->rotation_deg, mirror_axis = turned ? 1 : 0;
            double sum = points[i][mirror_axis] + points[j][mirror_axis];
            double diff = points[j][1 - mirror_axis] - points[i][1 - mirror_axis];
            double worst = 0.0;
            for (int32_t k = 0; k < piece->cut_count; ++k)
                worst = fmax(worst, fmax(fabs(points[i][2 * k + mirror_axis] + points[j][2 * k + mirror_axis] - sum),
                                         fabs(points[j][2 * k + 1 - mirror_axis] - points[i][2 * k + 1 - mirror_axis] -
                                              diff)));
            CHECK(worst < 1e-9, "%s: copies not mirror images (%g)", piece->name, worst);
        }
    for (int32_t i = 0; i < marker->placement_count; ++i)
        free(points[i]);
    free(points);
    CHECK(fabs(marker->length_mm - top) < 1e-9, "length %g, top %g", marker->length_mm, top);
    CHECK(fabs(marker->efficiency - area / (options->fabric_width_mm * top)) < 1e-12, "efficiency %g",
          marker->efficiency);
    CHECK(marker->efficiency > 0 && marker->efficiency <= 1, "efficiency %g", marker->efficiency);
    /* What no nesting can pass: no marker is shorter than its tallest piece or its area over the width. */
    double tallest = 0.0;
    for (int32_t i = 0; i < marker->placement_count; ++i) {
        const pz_piece *piece = &pieces->pieces[marker->placements[i].piece];
        tallest = fmax(tallest, piece->bbox_max[1] - piece->bbox_min[1]);
    }
    CHECK(fabs(marker->shortest_possible_mm - fmax(tallest, area / options->fabric_width_mm)) < 1e-6 &&
              marker->length_mm >= marker->shortest_possible_mm - 1e-9 &&
              marker->efficiency <= marker->efficiency_bound + 1e-12,
          "shortest possible %g (length %g), efficiency bound %g (efficiency %g)", marker->shortest_possible_mm,
          marker->length_mm, marker->efficiency_bound, marker->efficiency);
}

#endif /* PZ_TEST_MARKER_CHECKS_H */
