/*
 * export/fold.c -- pieces cut on the fold (pz_export_options.fold, --fold;
 * docs/export.md, "Cut on the fold"). A piece that is its own mirror image
 * (a panel the mirror plane crosses, made exactly symmetric by the pipeline:
 * docs/segment.md, "Exact mirror pieces") is drawn as its half, the fold
 * line straight along its axis, as pattern makers draw it: the fabric is
 * folded, the half laid with the fold line on the fold, and cut once.
 *
 *  - the axis: a symmetric outline's axis is one of its principal axes (the
 *    second moments of its area); of the two, the one the outline reflects
 *    onto itself through, within FOLD_TOLERANCE_MM (every sew vertex's image
 *    against the sew line), else the piece stays whole;
 *  - the half: the sew line clipped to the side of the axis (the left of the
 *    axis drawn along +v, so the grain and the drawing keep their sense);
 *    the new edge on the axis is the fold: no allowance there (the cut line
 *    is the half's offset with 0 along the fold), no notches;
 *  - the mark: a bracket beside the fold, its two legs ending in arrows at
 *    the fold ("place on fold"), as internal lines (every writer draws
 *    them), and the piece's text says "Cut 1 on fold"; DXF writes the fold
 *    line on AAMA layer 6 (mirror line).
 * Notches and internal lines (darts) on the other half go with it.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"
#include "export/offset.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FOLD_TOLERANCE_MM 0.25  /* the outline is its own mirror image within this (exact pieces: < 0.15 mm) */
#define BRACKET_INSET 0.08      /* the bracket's distance from the fold, times the half's width across it */
#define BRACKET_SPAN 0.6        /* its length, times the fold's */

/* Distance from x to the closed polygon points[0..n-1]. */
static double to_polygon(const double *x, const double *points, int32_t n)
{
    double best = INFINITY;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = points + 2 * i, *b = points + 2 * ((i + 1) % n);
        double ab[2] = {b[0] - a[0], b[1] - a[1]}, length2 = ab[0] * ab[0] + ab[1] * ab[1];
        double t = length2 > 0 ? ((x[0] - a[0]) * ab[0] + (x[1] - a[1]) * ab[1]) / length2 : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        best = fmin(best, hypot(x[0] - a[0] - t * ab[0], x[1] - a[1] - t * ab[1]));
    }
    return best;
}

/* The largest distance of the sew vertices reflected through the line (point c, unit direction d) to the sew line. */
static double reflection_residual(const pz_piece *piece, const double c[2], const double d[2])
{
    double worst = 0;
    for (int32_t i = 0; i < piece->sew_count; ++i) {
        const double *p = piece->sew + 2 * i;
        double rel[2] = {p[0] - c[0], p[1] - c[1]}, along = rel[0] * d[0] + rel[1] * d[1];
        double image[2] = {c[0] + 2 * along * d[0] - rel[0], c[1] + 2 * along * d[1] - rel[1]};
        worst = fmax(worst, to_polygon(image, piece->sew, piece->sew_count));
    }
    return worst;
}

/* The symmetry axis of the sew line (a point and a unit direction, +v first); 0 when it has none. */
static int find_axis(const pz_piece *piece, double c[2], double d[2])
{
    int32_t n = piece->sew_count;
    double area = 0, cx = 0, cy = 0;
    d[0] = 0, d[1] = 1;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = piece->sew + 2 * i, *b = piece->sew + 2 * ((i + 1) % n);
        double cross = a[0] * b[1] - a[1] * b[0];
        area += cross, cx += (a[0] + b[0]) * cross, cy += (a[1] + b[1]) * cross;
    }
    if (!(fabs(area) > 0))
        return 0;
    c[0] = cx / (3 * area), c[1] = cy / (3 * area);
    double xx = 0, yy = 0, xy = 0; /* second moments about the centroid (Green's theorem on the polygon) */
    for (int32_t i = 0; i < n; ++i) {
        double ax = piece->sew[2 * i] - c[0], ay = piece->sew[2 * i + 1] - c[1];
        double bx = piece->sew[2 * ((i + 1) % n)] - c[0], by = piece->sew[2 * ((i + 1) % n) + 1] - c[1];
        double cross = ax * by - bx * ay;
        xx += (ay * ay + ay * by + by * by) * cross, yy += (ax * ax + ax * bx + bx * bx) * cross;
        xy += (ax * by + 2 * ax * ay + 2 * bx * by + bx * ay) * cross;
    }
    double angle = 0.5 * atan2(xy, yy - xx), best = INFINITY; /* xx, yy, xy: 12, 12, 24 times the moments */
    for (int k = 0; k < 2; ++k) {
        double theta = angle + k * PZ_PI / 2, axis[2] = {cos(theta), sin(theta)};
        if (axis[1] < 0 || (axis[1] == 0 && axis[0] < 0))
            axis[0] = -axis[0], axis[1] = -axis[1];
        double residual = reflection_residual(piece, c, axis);
        if (residual < best)
            best = residual, d[0] = axis[0], d[1] = axis[1];
    }
    return best <= FOLD_TOLERANCE_MM;
}

/* Signed distance of p from the axis (positive on its left). */
static double side_of(const double *p, const double c[2], const double d[2])
{
    return d[0] * (p[1] - c[1]) - d[1] * (p[0] - c[0]);
}

/*
 * The sew line clipped to the left of the axis (Sutherland-Hodgman against
 * one line): points kept with their vertex and the allowance of the edge
 * leaving them, crossings added; the edge from the second crossing back to
 * the first (along the axis) is the fold, allowance 0. Returns the point
 * count (0: the axis does not cut the piece in two), fold_at: the index of
 * the fold's first point.
 */
static int32_t clip_half(const pz_piece *piece, const double c[2], const double d[2], double *points, int32_t *vertex,
                         double *allowance, int32_t *fold_at)
{
    int32_t n = piece->sew_count, count = 0, crossings = 0;
    *fold_at = -1;
    for (int32_t i = 0; i < n; ++i) {
        int32_t j = (i + 1) % n;
        const double *a = piece->sew + 2 * i, *b = piece->sew + 2 * j;
        double sa = side_of(a, c, d), sb = side_of(b, c, d);
        if (sa >= 0) {
            memcpy(points + 2 * count, a, 2 * sizeof(double));
            vertex[count] = piece->sew_vertex[i], allowance[count++] = piece->sew_allowance[i];
        }
        if ((sa >= 0) != (sb >= 0)) { /* the edge crosses the axis */
            double t = sa / (sa - sb);
            points[2 * count] = a[0] + t * (b[0] - a[0]), points[2 * count + 1] = a[1] + t * (b[1] - a[1]);
            vertex[count] = piece->sew_vertex[sa >= 0 ? i : j];
            /* leaving the half: the fold starts here; entering it: the crossed edge goes on */
            allowance[count] = sa >= 0 ? 0 : piece->sew_allowance[i];
            if (sa >= 0)
                *fold_at = count;
            ++count, ++crossings;
        }
    }
    return crossings == 2 && *fold_at >= 0 ? count : 0;
}

/* Appends a polyline to the piece's internal lines; 0 when out of memory. */
static int add_line(pz_piece *piece, const double *points, int32_t count)
{
    pz_piece_line *grown = realloc(piece->lines, ((size_t)piece->line_count + 1) * sizeof *grown);
    if (!grown)
        return 0;
    piece->lines = grown;
    pz_piece_line *line = &piece->lines[piece->line_count];
    line->points = malloc(2 * (size_t)count * sizeof(double));
    if (!line->points)
        return 0;
    memcpy(line->points, points, 2 * (size_t)count * sizeof(double));
    line->point_count = count;
    ++piece->line_count;
    return 1;
}

/* The "place on fold" bracket: a line beside the fold, its legs ending in arrows on it. */
static int add_bracket(pz_piece *piece, const double from[2], const double to[2], double width)
{
    double along[2] = {to[0] - from[0], to[1] - from[1]}, length = hypot(along[0], along[1]);
    if (!(length > 0))
        return 1;
    along[0] /= length, along[1] /= length;
    double inward[2] = {-along[1], along[0]}; /* the half runs counter-clockwise: its inside is the fold's left */
    double inset = fmin(BRACKET_INSET * width, 40.0), margin = 0.5 * (1 - BRACKET_SPAN) * length;
    double head = fmin(0.3 * inset, 8.0);
    double p0[2] = {from[0] + margin * along[0], from[1] + margin * along[1]};
    double p1[2] = {to[0] - margin * along[0], to[1] - margin * along[1]};
    double bracket[8] = {p0[0], p0[1], p0[0] + inset * inward[0], p0[1] + inset * inward[1],
                         p1[0] + inset * inward[0], p1[1] + inset * inward[1], p1[0], p1[1]};
    int ok = add_line(piece, bracket, 4);
    for (int end = 0; ok && end < 2; ++end) { /* arrowheads pointing at the fold */
        const double *tip = end ? p1 : p0;
        double arrow[6] = {tip[0] + head * (inward[0] + 0.5 * along[0]), tip[1] + head * (inward[1] + 0.5 * along[1]),
                           tip[0], tip[1],
                           tip[0] + head * (inward[0] - 0.5 * along[0]), tip[1] + head * (inward[1] - 0.5 * along[1])};
        ok = add_line(piece, arrow, 3);
    }
    return ok;
}

/* Drops the notches and internal lines that lie right of the axis (beyond the fold, on the half not drawn). */
static void drop_other_half(pz_piece *piece, const double c[2], const double d[2])
{
    int32_t kept = 0;
    for (int32_t i = 0; i < piece->notch_count; ++i)
        if (side_of(piece->notches[i].position, c, d) > 1e-6)
            piece->notches[kept++] = piece->notches[i];
    piece->notch_count = kept;
    kept = 0;
    for (int32_t i = 0; i < piece->line_count; ++i) {
        double mean[2] = {0, 0};
        for (int32_t k = 0; k < piece->lines[i].point_count; ++k)
            mean[0] += piece->lines[i].points[2 * k], mean[1] += piece->lines[i].points[2 * k + 1];
        int32_t n = piece->lines[i].point_count > 0 ? piece->lines[i].point_count : 1;
        mean[0] /= n, mean[1] /= n;
        if (side_of(mean, c, d) >= 0)
            piece->lines[kept++] = piece->lines[i];
        else
            free(piece->lines[i].points);
    }
    piece->line_count = kept;
}

/* Folds one piece; 1 when folded (or left whole: not symmetric), 0 when out of memory. */
static int fold_piece(pz_piece *piece, pz_ctx *ctx)
{
    double c[2], d[2];
    if (piece->mirrored || !find_axis(piece, c, d))
        return 1;
    int32_t room = piece->sew_count + 2, fold_at = -1;
    double *points = malloc(2 * (size_t)room * sizeof(double)), *allowance = malloc((size_t)room * sizeof(double));
    int32_t *vertex = malloc((size_t)room * sizeof(int32_t));
    int ok = points && allowance && vertex;
    int32_t count = ok ? clip_half(piece, c, d, points, vertex, allowance, &fold_at) : 0;
    double *cut = NULL;
    int32_t cut_count = 0;
    if (ok && count >= 3 && pz_offset_polygon(points, count, allowance, &cut, &cut_count, ctx) == PZ_OK) {
        double from[2], to[2], width = 0;
        memcpy(from, points + 2 * fold_at, sizeof from);
        memcpy(to, points + 2 * ((fold_at + 1) % count), sizeof to);
        for (int32_t i = 0; i < count; ++i)
            width = fmax(width, side_of(points + 2 * i, c, d));
        free(piece->sew), free(piece->sew_vertex), free(piece->sew_allowance), free(piece->cut);
        piece->sew = points, piece->sew_vertex = vertex, piece->sew_allowance = allowance;
        piece->sew_count = count;
        piece->cut = cut, piece->cut_count = cut_count;
        points = NULL, vertex = NULL, allowance = NULL;
        drop_other_half(piece, c, d);
        piece->on_fold = 1;
        memcpy(piece->fold[0], from, sizeof from);
        memcpy(piece->fold[1], to, sizeof to);
        ok = add_bracket(piece, from, to, width);
    } else {
        free(cut);
    }
    free(points), free(allowance), free(vertex);
    return ok;
}

pz_status pz_pieces_fold(pz_pieces *pieces, const int32_t *panel_mirror, pz_ctx *ctx)
{
    for (int32_t p = 0; panel_mirror && p < pieces->piece_count; ++p) {
        pz_piece *piece = &pieces->pieces[p];
        if (panel_mirror[piece->panel] != piece->panel)
            continue;
        pz_ctx quiet;
        pz_ctx_quiet(ctx, &quiet);
        if (!fold_piece(piece, &quiet))
            return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory folding piece %s", piece->name);
    }
    return PZ_OK;
}

const char *pz_piece_cut_text(const pz_piece *piece)
{
    return piece->cut_quantity >= 2 ? "Cut 2 mirrored" : piece->on_fold ? "Cut 1 on fold" : "Cut 1";
}
