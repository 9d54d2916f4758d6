/*
 * tests/export/piece_checks.h -- the checks every export test applies to
 * pattern pieces (pz_pieces_build), shared by test_pieces.c and
 * test_run_patterns.c:
 *  - the cut line against the sew line, point by point (a sample at least
 *    every millimetre): for every sew edge, its distance is at least that
 *    edge's allowance (at an edge end where the allowance changes: the
 *    smaller one) minus 0.1 mm; where the nearest sew feature is an edge's
 *    interior the distance is that edge's allowance within 0.1 mm; where it
 *    is a corner, at most PZ_OFFSET_MITRE_LIMIT allowances (mitre or square
 *    cap). The legs of a folded dart count for the lower bound only and its
 *    mouth has no upper bound (the cut line crosses the dart's V); a dart
 *    cut out is an outline like any other.
 *    The cut line never crosses itself and encloses every sew point;
 *  - notch pairs: every seam's labels once on each side, at equal arc
 *    length within 0.5 mm (the end notches: within the seam's length
 *    mismatch).
 * `PZ_DEBUG_CUT=1` prints the first sample that breaks the allowance rule of
 * each failing outline. Needs test_util.h (CHECK, REQUIRE).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_PIECE_CHECKS_H
#define PZ_TEST_PIECE_CHECKS_H

#include "../test_util.h"
#include "export/export.h"
#include "export/notches.h"
#include "export/offset.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- the cut line checker */

typedef struct outline_check {
    const double *sew;
    int32_t sew_count;
    const double *allowance;
    const uint8_t *leg_edge;      /* sew_count or NULL: edges of a dart leg */
    const uint8_t *free_vertex;   /* sew_count or NULL: no upper bound near these (dart mouths) */
    int32_t bridge_count;         /* darts closed across their mouth: sew index pairs */
    const int32_t *bridges;
} outline_check;

typedef struct check_result {
    int32_t samples, violations, crossings, outside;
    double worst_low, worst_high;  /* mm below / above the allowed band */
} check_result;

static inline double segment_distance(const double p[2], const double *a, const double *b, double *t_out)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], length2 = dx * dx + dy * dy;
    double t = length2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2 : 0;
    t = fmin(1, fmax(0, t));
    /* Within a micrometre of an end counts as the end (a strip's side has its foot exactly there). */
    double length = sqrt(length2);
    if (t * length < 1e-6)
        t = 0;
    else if ((1 - t) * length < 1e-6)
        t = 1;
    *t_out = t;
    return hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}

static inline int point_in_polygon(const double p[2], const double *poly, int32_t n)
{
    int inside = 0;
    for (int32_t i = 0, j = n - 1; i < n; j = i++) {
        const double *a = &poly[2 * i], *b = &poly[2 * j];
        if ((a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0])
            inside = !inside;
    }
    return inside;
}

/* 1 when p lies beyond both edges of sew vertex v (its corner region). */
static inline int in_wedge(const outline_check *o, const double p[2], int32_t v)
{
    int32_t n = o->sew_count, previous = (v + n - 1) % n, next = (v + 1) % n;
    const double *a = &o->sew[2 * previous], *c = &o->sew[2 * v], *b = &o->sew[2 * next];
    double in[2] = {c[0] - a[0], c[1] - a[1]}, out[2] = {b[0] - c[0], b[1] - c[1]}, r[2] = {p[0] - c[0], p[1] - c[1]};
    return r[0] * in[0] + r[1] * in[1] >= -1e-9 && r[0] * out[0] + r[1] * out[1] <= 1e-9;
}

/* 1 when p lies in the corner region of sew vertex v within the mitre limit. */
static inline int in_corner(const outline_check *o, const double p[2], int32_t v)
{
    int32_t n = o->sew_count, previous = (v + n - 1) % n;
    double reach = PZ_OFFSET_MITRE_LIMIT * fmax(o->allowance[previous], o->allowance[v]) + 0.1;
    return in_wedge(o, p, v) && hypot(p[0] - o->sew[2 * v], p[1] - o->sew[2 * v + 1]) <= reach;
}

static inline void check_sample(const outline_check *o, const double p[2], check_result *r)
{
    int32_t n = o->sew_count, nearest = -1;
    double nearest_distance = DBL_MAX, nearest_t = 0, low_needed = 0, low_distance = DBL_MAX;
    int low_bad = 0;
    for (int32_t e = 0; e < n; ++e) {
        double t, d = segment_distance(p, &o->sew[2 * e], &o->sew[2 * ((e + 1) % n)], &t);
        double need = o->allowance[e];
        const double *a = &o->sew[2 * e], *b = &o->sew[2 * ((e + 1) % n)];
        double outward = (p[0] - a[0]) * (b[1] - a[1]) - (p[1] - a[1]) * (b[0] - a[0]);
        if (t <= 0 || t >= 1) {
            /* Nearest at an end: in that corner's region, the smaller allowance there; elsewhere the
             * neighbouring edge rules. */
            int32_t v = t <= 0 ? e : (e + 1) % n;
            need = in_wedge(o, p, v) ? fmin(need, o->allowance[t <= 0 ? (e + n - 1) % n : (e + 1) % n]) : 0;
        }
        else if (outward < 0)  /* an allowance strip is one-sided: behind the edge, others rule */
            need = 0;
        if (d < need - 0.1 && need - d > low_needed - low_distance) {
            low_bad = 1;
            low_needed = need;
            low_distance = d;
        }
        if ((!o->leg_edge || !o->leg_edge[e]) && d < nearest_distance) {
            nearest_distance = d;
            nearest = e;
            nearest_t = t;
        }
    }
    ++r->samples;
    if (low_bad) {
        if (getenv("PZ_DEBUG_CUT") && r->worst_low == 0)
            fprintf(stderr, "inside: (%.3f, %.3f) %.3f mm from the sew line, %.3f needed\n", p[0], p[1], low_distance,
                    low_needed);
        ++r->violations;
        r->worst_low = fmax(r->worst_low, low_needed - low_distance);
        return;
    }
    if (nearest < 0)
        return;
    int interior = nearest_t > 1e-9 && nearest_t < 1 - 1e-9;
    if (interior && nearest_distance <= o->allowance[nearest] + 0.1)
        return;
    if (!interior) {
        int32_t v = nearest_t <= 1e-9 ? nearest : (nearest + 1) % n;
        if (o->free_vertex && o->free_vertex[v])
            return;
    }
    /* Above a dart's mouth: within the allowance of the line that closes it. */
    for (int32_t k = 0; k < o->bridge_count; ++k) {
        int32_t i = o->bridges[2 * k], j = o->bridges[2 * k + 1];
        double t, d = segment_distance(p, &o->sew[2 * i], &o->sew[2 * j], &t);
        double allowance = fmax(o->allowance[(i + n - 1) % n], o->allowance[j]);
        if (d <= allowance + 0.1)
            return;
        /* The corners the closing line makes at the mouth (mitres within the limit). */
        for (int end = 0; end < 2; ++end) {
            const double *m = &o->sew[2 * (end ? j : i)];
            if (hypot(p[0] - m[0], p[1] - m[1]) <= PZ_OFFSET_MITRE_LIMIT * allowance + 0.1)
                return;
        }
    }
    /* On the side of a wider edge's strip where the allowance steps down (pattern makers' step). */
    for (int32_t e = 0; e < n; ++e) {
        double t, d = segment_distance(p, &o->sew[2 * e], &o->sew[2 * ((e + 1) % n)], &t);
        if (t >= 0 && t <= 1 && d <= o->allowance[e] + 0.1 && (!o->leg_edge || !o->leg_edge[e]))
            return;
    }
    /* A mitre or cap: inside some corner's region (its nearest sew point may be another edge). */
    for (int32_t v = 0; v < n; ++v)
        if ((!o->free_vertex || !o->free_vertex[v]) && in_corner(o, p, v))
            return;
    if (getenv("PZ_DEBUG_CUT") && r->worst_high == 0)
        fprintf(stderr, "beyond: (%.3f, %.3f) nearest edge %d t %.4f distance %.3f\n", p[0], p[1], (int)nearest,
                nearest_t, nearest_distance);
    ++r->violations;
    r->worst_high = fmax(r->worst_high, nearest_distance - o->allowance[nearest]);
}

static inline check_result check_cut(const outline_check *o, const double *cut, int32_t cut_count)
{
    check_result r = {0};
    for (int32_t i = 0; i < cut_count; ++i) {
        const double *a = &cut[2 * i], *b = &cut[2 * ((i + 1) % cut_count)];
        int steps = (int)ceil(hypot(b[0] - a[0], b[1] - a[1]) / 1.0);
        for (int k = 0; k < (steps < 1 ? 1 : steps); ++k) {
            double t = (double)k / (steps < 1 ? 1 : steps), p[2] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
            check_sample(o, p, &r);
        }
    }
    r.crossings = pz_offset_self_intersections(cut, cut_count);
    for (int32_t i = 0; i < o->sew_count; ++i)
        r.outside += !point_in_polygon(&o->sew[2 * i], cut, cut_count);
    return r;
}

static inline void expect_good_cut(const check_result *r, const char *what)
{
    CHECK(r->violations == 0 && r->crossings == 0 && r->outside == 0,
          "%s: %d of %d samples off the allowance (worst %.3f mm inside, %.3f mm beyond), %d self-crossings, "
          "%d sew points outside the cut line",
          what, (int)r->violations, (int)r->samples, r->worst_low, r->worst_high, (int)r->crossings, (int)r->outside);
}

/* ---------------------------------------------------------------- pieces */

/* Leg edges, leg vertices and the mouths (sew index pairs) of the folded darts of a piece. */
static inline int32_t dart_flags(const pz_pattern *pattern, const pz_piece *piece, uint8_t *leg_edge, uint8_t *free_vertex,
                          int32_t *bridges)
{
    int32_t n = piece->sew_count, bridge_count = 0;
    memset(leg_edge, 0, (size_t)n);
    memset(free_vertex, 0, (size_t)n);
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        uint8_t *on = calloc((size_t)n, 1);
        REQUIRE(on, "out of memory");
        int32_t tip = -1;
        for (int32_t i = 0; i < n; ++i) {
            int32_t a = piece->sew_vertex[i];
            on[i] = a == dart->tip;
            if (a == dart->tip)
                tip = i;
            for (int32_t k = 0; k < dart->pair_count; ++k)
                on[i] |= a == dart->leg_a[k] || a == dart->leg_b[k];
        }
        if (tip >= 0) {
            int32_t back = 0, ahead = 0;
            while (back < n && on[(tip - back - 1 + n) % n] && piece->sew_vertex[(tip - back - 1 + n) % n] != dart->tip)
                ++back;
            while (ahead < n && on[(tip + ahead + 1) % n])
                ++ahead;
            int32_t a = (tip - back + n) % n, b = (tip + ahead) % n;
            double width = hypot(piece->sew[2 * b] - piece->sew[2 * a], piece->sew[2 * b + 1] - piece->sew[2 * a + 1]);
            double allowance = fmax(piece->sew_allowance[(a + n - 1) % n], piece->sew_allowance[b]);
            if (back > 0 && ahead > 0 && back + ahead + 3 <= n && width <= PZ_DART_FOLD_LIMIT * allowance) {
                bridges[2 * bridge_count] = a;
                bridges[2 * bridge_count++ + 1] = b;
                /* Folded: the V lies inside the cut line; its legs bound it from below only. A dart cut
                 * out keeps its legs as ordinary edges, the allowance on both sides of them. */
                for (int32_t i = 0; i < n; ++i) {
                    leg_edge[i] |= on[i] && on[(i + 1) % n];
                    free_vertex[i] |= on[i];
                }
            }
        }
        free(on);
    }
    return bridge_count;
}

static inline void check_piece_cuts(const pz_pattern *pattern, const pz_pieces *pieces, const char *what)
{
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        uint8_t *flags = malloc(2 * (size_t)piece->sew_count);
        int32_t *bridges = malloc(2 * ((size_t)pattern->dart_count + 1) * sizeof(int32_t));
        REQUIRE(flags && bridges, "out of memory");
        int32_t bridge_count = dart_flags(pattern, piece, flags, flags + piece->sew_count, bridges);
        outline_check o = {piece->sew,   piece->sew_count, piece->sew_allowance, flags, flags + piece->sew_count,
                           bridge_count, bridges};
        check_result r = check_cut(&o, piece->cut, piece->cut_count);
        char name[160];
        snprintf(name, sizeof name, "%s: %s", what, piece->name);
        expect_good_cut(&r, name);
        CHECK(piece->area_mm2 > piece->sew_area_mm2 && piece->sew_area_mm2 > 0, "%s: areas %.1f / %.1f", name,
              piece->area_mm2, piece->sew_area_mm2);
        CHECK(piece->grain[1][1] > piece->grain[0][1] && piece->grain[1][0] == piece->grain[0][0],
              "%s: grainline not along +v", name);
        free(flags);
        free(bridges);
    }
}

/* Every seam's notch labels appear once on each side, at equal arc length (ends: the seam's length mismatch). */
static inline double check_notch_pairs(const pz_pattern *pattern, const pz_pieces *pieces, const double *uv,
                                const char *what, double *worst_end)
{
    double worst = 0;
    *worst_end = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        int32_t count = 0, unpaired = 0;
        for (int32_t p = 0; p < pieces->piece_count; ++p)
            for (int32_t i = 0; i < pieces->pieces[p].notch_count; ++i) {
                const pz_notch *a = &pieces->pieces[p].notches[i];
                if (a->seam != s)
                    continue;
                ++count;
                int partners = 0;
                double arc = 0;
                for (int32_t q = 0; q < pieces->piece_count; ++q)
                    for (int32_t j = 0; j < pieces->pieces[q].notch_count; ++j) {
                        const pz_notch *b = &pieces->pieces[q].notches[j];
                        if (b != a && b->seam == s && strcmp(a->label, b->label) == 0) {
                            ++partners;
                            arc = b->arc_mm;
                        }
                    }
                if (partners != 1) {
                    ++unpaired;
                    continue;
                }
                /* The seam's sides' lengths: the end notch may differ by their mismatch only. */
                const pz_seam *seam = &pattern->seams[s];
                double length[2] = {0, 0};
                for (int32_t k = 1; k < seam->pair_count; ++k) {
                    const int32_t *side[2] = {seam->side_a, seam->side_b};
                    for (int h = 0; h < 2; ++h)
                        length[h] += hypot(uv[2 * side[h][k]] - uv[2 * side[h][k - 1]],
                                           uv[2 * side[h][k] + 1] - uv[2 * side[h][k - 1] + 1]);
                }
                double allowed = 0.5;
                if (fabs(a->arc_mm - length[0]) < 1e-9 || fabs(a->arc_mm - length[1]) < 1e-9) {
                    allowed = fmax(allowed, fabs(length[0] - length[1]) + 1e-6);
                    *worst_end = fmax(*worst_end, fabs(a->arc_mm - arc));
                } else
                    worst = fmax(worst, fabs(a->arc_mm - arc));
                CHECK(fabs(a->arc_mm - arc) <= allowed, "%s: seam %d notch %s at %.3f and %.3f mm", what, (int)s,
                      a->label, a->arc_mm, arc);
            }
        CHECK(count >= 4 && unpaired == 0, "%s: seam %d has %d notches, %d unpaired", what, (int)s, (int)count,
              (int)unpaired);
    }
    return worst;
}

/* ---------------------------------------------------------------- pattern.dxf read back */

static inline double polyline_perimeter(const double *points, int32_t count)
{
    double length = 0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
        length += hypot(b[0] - a[0], b[1] - a[1]);
    }
    return length;
}

/* The block name pattern.dxf gives a piece (as export/dxf.c sanitizes it; names here are unique). */
static inline void expected_block(const char *name, char out[64])
{
    size_t length = 0;
    for (; name[length] && length < 47; ++length) {
        unsigned char c = (unsigned char)name[length];
        out[length] = (c >= '0' && c <= '9') || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_' || c == '-'
                          ? (char)c : '_';
    }
    out[length] = '\0';
}

/* The notches a writer draws: one per place (notches at exactly one point, the ends of two seams at a corner,
 * are one); O(n^2) in the piece's notches, which is few. */
static inline int32_t distinct_notches(const pz_piece *piece)
{
    int32_t count = 0;
    for (int32_t i = 0; i < piece->notch_count; ++i) {
        int seen = 0;
        for (int32_t j = 0; j < i && !seen; ++j)
            seen = piece->notches[j].position[0] == piece->notches[i].position[0] &&
                   piece->notches[j].position[1] == piece->notches[i].position[1];
        count += !seen;
    }
    return count;
}

/* What tests/export/check_dxf.py expects of pattern.dxf: one line per drawn piece, `BLOCK CUT_COUNT
 * CUT_PERIMETER SEW_COUNT SEW_PERIMETER NOTCHES LINES`. */
static inline void piece_checks_write_dxf_expected(const pz_pieces *pieces, const char *path)
{
    FILE *expected = fopen(path, "w");
    REQUIRE(expected, "cannot create %s", path);
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        if (piece->mirrored)
            continue;
        char block[64];
        expected_block(piece->name, block);
        fprintf(expected, "%s %d %.9f %d %.9f %d %d\n", block, (int)piece->cut_count,
                polyline_perimeter(piece->cut, piece->cut_count), (int)piece->sew_count,
                polyline_perimeter(piece->sew, piece->sew_count), (int)distinct_notches(piece), (int)piece->line_count);
    }
    REQUIRE(fclose(expected) == 0, "cannot write %s", path);
}

#endif /* PZ_TEST_PIECE_CHECKS_H */
