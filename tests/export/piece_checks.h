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
 *  - notch pairs: every seam's labels once on each side, each notch's arc
 *    measured from its 2D position along its side's sew line: interior
 *    partners within 0.5 mm and every notch spacing along, the end notches
 *    at the seam's ends (within 0.01 mm; the two ends differ by the seam's
 *    length mismatch);
 *  - labels on the drawn pieces: the piece that stands for each side of a
 *    seam (its drawn mirror partner when the side's piece is hidden) carries
 *    the seam's labels.
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

/* ---------------------------------------------------------------- notches */

/* Where a notch's position falls on a seam side (a polyline of cut-mesh vertices in uv): the arc length from the
 * side's start to the nearest point, and that point's distance. */
static inline double side_arc_of(const double *uv, const int32_t *side, int32_t count, const double p[2],
                                 double *distance)
{
    double walked = 0, best_arc = 0;
    *distance = DBL_MAX;
    for (int32_t k = 1; k < count; ++k) {
        const double *a = &uv[2 * side[k - 1]], *b = &uv[2 * side[k]];
        double t, d = segment_distance(p, a, b, &t), length = hypot(b[0] - a[0], b[1] - a[1]);
        if (d < *distance) {
            *distance = d;
            best_arc = walked + t * length;
        }
        walked += length;
    }
    return best_arc;
}

/* The number after a label's letters ("AB3" -> 3). */
static inline int notch_number(const char *label)
{
    while (*label >= 'A' && *label <= 'Z')
        ++label;
    return atoi(label);
}

typedef struct notch_pair_stats {
    double interior;      /* largest arc difference of interior partners, measured from the notches' positions */
    double end_corner;    /* largest distance of an end notch from its seam end */
    double end_mismatch;  /* largest length difference of a seam's two sides (what end notches differ by) */
    int32_t notches;
} notch_pair_stats;

/* One notch of a seam, located on its side independently of the arc_mm the export stored. */
typedef struct located_notch {
    int32_t side, number;
    double arc, off_line;
    const pz_notch *notch;
} located_notch;

/*
 * Every seam's notches: each label once on each side; every notch on its side's sew line (within 1e-6 mm);
 * the first and last (the seam's ends) within 0.01 mm of the side's end vertices, both partners at the same
 * end; the others at (number - 1) x spacing from the end the first sits at (within 0.01 mm) and at equal arc
 * length on both partners within 0.5 mm. The arc of a notch is measured from its 2D position along the side,
 * not taken from pz_notch.arc_mm.
 */
static inline notch_pair_stats check_notch_pairs(const pz_pattern *pattern, const pz_pieces *pieces, const double *uv,
                                                 double spacing, const char *what)
{
    notch_pair_stats stats = {0, 0, 0, 0};
    int32_t *first = calloc((size_t)pattern->seam_count + 2, sizeof(int32_t));
    REQUIRE(first, "out of memory");
    for (int32_t p = 0; p < pieces->piece_count; ++p)   /* notches bucketed by seam */
        for (int32_t i = 0; i < pieces->pieces[p].notch_count; ++i)
            if (pieces->pieces[p].notches[i].seam >= 0)
                ++first[pieces->pieces[p].notches[i].seam + 2];
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        first[s + 2] += first[s + 1];
    located_notch *located = malloc(((size_t)first[pattern->seam_count + 1] + 1) * sizeof *located);
    REQUIRE(located, "out of memory");
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        for (int32_t i = 0; i < pieces->pieces[p].notch_count; ++i) {
            const pz_notch *n = &pieces->pieces[p].notches[i];
            if (n->seam < 0)
                continue;
            const pz_seam *seam = &pattern->seams[n->seam];
            located_notch l = {-1, notch_number(n->label), 0, DBL_MAX, n};
            for (int k = 0; k < 2; ++k) {   /* the side on this piece the notch lies on (a self-seam has both) */
                if ((k ? seam->panel_b : seam->panel_a) != pieces->pieces[p].panel)
                    continue;
                double off, arc = side_arc_of(uv, k ? seam->side_b : seam->side_a, seam->pair_count, n->position, &off);
                if (l.side >= 0 && fabs(off - l.off_line) < 1e-9)
                    l.side = -2;   /* on both sides (a self-seam's shared end): either slot */
                else if (off < l.off_line)
                    l.side = k, l.arc = arc, l.off_line = off;
            }
            located[first[n->seam + 1]++] = l;
        }
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        int32_t begin = first[s], end = first[s + 1], last = 0, bad = 0;
        double length[2] = {0, 0};
        const int32_t *side[2] = {seam->side_a, seam->side_b};
        for (int32_t k = 1; k < seam->pair_count; ++k)
            for (int h = 0; h < 2; ++h)
                length[h] += hypot(uv[2 * side[h][k]] - uv[2 * side[h][k - 1]],
                                   uv[2 * side[h][k] + 1] - uv[2 * side[h][k - 1] + 1]);
        stats.end_mismatch = fmax(stats.end_mismatch, fabs(length[0] - length[1]));
        for (int32_t i = begin; i < end; ++i)
            last = located[i].number > last ? located[i].number : last;
        int from_end = -1;   /* 1 when notch 1 sits at the sides' far ends (a mirror twin counted from there) */
        for (int32_t number = 1; number <= last; ++number) {
            const located_notch *pair[2] = {NULL, NULL};
            int count[2] = {0, 0};
            for (int32_t i = begin; i < end; ++i)
                if (located[i].number == number && located[i].side >= 0) {
                    pair[located[i].side] = &located[i];
                    ++count[located[i].side];
                }
            for (int32_t i = begin; i < end; ++i)
                if (located[i].number == number && located[i].side == -2) {
                    int k = count[0] ? 1 : 0;
                    pair[k] = &located[i];
                    ++count[k];
                }
            if (count[0] != 1 || count[1] != 1) {
                CHECK(0, "%s: seam %d label %d: %d and %d notches on its sides", what, (int)s, (int)number, count[0],
                      count[1]);
                ++bad;
                continue;
            }
            for (int k = 0; k < 2; ++k)
                CHECK(pair[k]->off_line < 1e-6, "%s: seam %d notch %s is %.2e mm off its sew line", what, (int)s,
                      pair[k]->notch->label, pair[k]->off_line);
            if (number == 1 || number == last) {
                for (int k = 0; k < 2; ++k) {
                    const double *a = &uv[2 * side[k][0]], *b = &uv[2 * side[k][seam->pair_count - 1]];
                    const double *at = pair[k]->notch->position;
                    double to_start = hypot(at[0] - a[0], at[1] - a[1]), to_end = hypot(at[0] - b[0], at[1] - b[1]);
                    int at_end = to_end < to_start;
                    if (number == 1 && k == 0)
                        from_end = at_end;
                    CHECK(at_end == (number == 1 ? from_end : !from_end), "%s: seam %d notch %s at the wrong end",
                          what, (int)s, pair[k]->notch->label);
                    stats.end_corner = fmax(stats.end_corner, fmin(to_start, to_end));
                    CHECK(fmin(to_start, to_end) < 0.01, "%s: seam %d end notch %s %.3f mm from the seam's end", what,
                          (int)s, pair[k]->notch->label, fmin(to_start, to_end));
                }
                continue;
            }
            /* Along each side from the end both count from (the seam's start, or a mirror twin's far end). */
            double along[2];
            for (int k = 0; k < 2; ++k) {
                along[k] = from_end ? length[k] - pair[k]->arc : pair[k]->arc;
                CHECK(fabs(along[k] - (number - 1) * spacing) < 0.01, "%s: seam %d notch %s %.3f mm along, not %.0f",
                      what, (int)s, pair[k]->notch->label, along[k], (number - 1) * spacing);
            }
            double difference = fabs(along[0] - along[1]);
            stats.interior = fmax(stats.interior, difference);
            CHECK(difference <= 0.5, "%s: seam %d notch %s at %.3f and %.3f mm", what, (int)s, pair[0]->notch->label,
                  along[0], along[1]);
        }
        CHECK(end - begin >= 4 && bad == 0, "%s: seam %d has %d notches, %d labels unpaired", what, (int)s,
              (int)(end - begin), (int)bad);
        stats.notches += end - begin;
    }
    free(located);
    free(first);
    return stats;
}

/*
 * What the cutter holds: every drawn piece, and for a "Cut 2 mirrored" piece
 * its mirrored copy too, which carries the drawn piece's notches. Every seam
 * must be matchable there: the piece standing for each of its sides (the
 * side's own piece, or the drawn partner of a hidden one) carries every label
 * of the seam. Returns the number of seams with a side on a hidden piece.
 */
static inline int32_t check_drawn_labels(const pz_pattern *pattern, const pz_pieces *pieces, const char *what)
{
    int32_t hidden_sides = 0, unmatched = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        int hidden = 0, missing = 0;
        for (int k = 0; k < 2; ++k) {
            const pz_piece *own = &pieces->pieces[k ? seam->panel_b : seam->panel_a];
            const pz_piece *drawn = own->mirrored ? &pieces->pieces[own->mirror_piece] : own;
            hidden |= own->mirrored;
            CHECK(!drawn->mirrored, "%s: the partner of hidden %s is hidden too", what, own->name);
            for (int32_t i = 0; i < own->notch_count; ++i) {
                if (own->notches[i].seam != s)
                    continue;
                int found = 0;
                for (int32_t j = 0; j < drawn->notch_count && !found; ++j)
                    found = strcmp(drawn->notches[j].label, own->notches[i].label) == 0;
                missing += !found;
            }
        }
        hidden_sides += hidden;
        unmatched += missing > 0;
        CHECK(missing == 0, "%s: seam %d (panels %d, %d): %d labels not on the drawn piece that stands for its side",
              what, (int)s, (int)seam->panel_a, (int)seam->panel_b, missing);
    }
    printf("%s: %d of %d seams reach a hidden mirrored piece, %d of them unmatched on the drawn pieces\n", what,
           (int)hidden_sides, (int)pattern->seam_count, (int)unmatched);
    return hidden_sides;
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
