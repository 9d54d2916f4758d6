/*
 * export/notches.c -- notches and dart lines of the pattern pieces.
 *
 * Seam notches: seam i gets the letters A..Z, AA, AB, ... (bijective base 26).
 * Along each side (side_a on panel_a, side_b on panel_b) arc length is
 * measured in the pattern plane from the seam's start (side_a[0] and
 * side_b[0] are the same garment vertex). Notches sit at arc 0, at every
 * notch_spacing_mm while at least a quarter spacing remains before the
 * shorter side's end, and at each side's own end: notch j has the label
 * <letters><j+1> on both partners, and, apart from the end notch, the same arc
 * length on both (the end notches sit at each side's own end: they differ by
 * the seam's length mismatch, which the metrics report). A seam on the hidden
 * piece of a "Cut 2 mirrored" pair shares its letters and notch count with
 * its mirror twin (below), so the mirrored cut's labels match its partner's.
 * A notch's direction is the outward normal of the sew edge it lies on (at a
 * vertex, the mean of the two edges' normals); it is
 * drawn from where that ray meets the cut line, inward, min(notch_depth_mm,
 * the local allowance) long, so it never reaches the sew line.
 *
 * Darts: the mouth is found by walking the outline away from the tip while
 * the vertices belong to the dart's legs. A mouth at most PZ_DART_FOLD_LIMIT
 * allowances wide is folded (the cut line closes the V), a wider one cut out.
 * Notches "D<k>" at both mouth ends, pointing out of the line that closes the
 * V (folded) or along the outline's normal there (cut out); lines: both legs (mouth to
 * tip), the fold line (the mouth's midpoint to the tip) and a 4 mm cross at
 * the tip (the drill-hole mark).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/notches.h"

#include "core/util.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TIP_MARK_MM 2.0

int32_t pz_outline_edge(const pz_pieces *pieces, const pz_outline_map *map, int32_t a, int32_t b)
{
    int32_t piece = map->loop_piece[a];
    if (piece < 0 || map->loop_piece[b] != piece)
        return -1;
    int32_t n = pieces->pieces[piece].sew_count, i = map->loop_index[a], j = map->loop_index[b];
    if ((i + 1) % n == j)
        return i;
    if ((j + 1) % n == i)
        return j;
    return -1;
}

void pz_notch_label(int32_t seam, int32_t index, char label[16])
{
    char letters[8];
    int length = 0;
    for (int32_t k = seam + 1; k > 0 && length < 7; k = (k - 1) / 26)
        letters[length++] = (char)('A' + (k - 1) % 26);
    char *out = label;
    while (length > 0)
        *out++ = letters[--length];
    snprintf(out, (size_t)(16 - (out - label)), "%d", (int)(index + 1));
}

/* ---------------------------------------------------------------- drawn labels */

typedef struct notch_at {
    double x, y;
    int32_t index;
} notch_at;

static int compare_notch_at(const void *a, const void *b)
{
    const notch_at *p = a, *q = b;
    if (p->x != q->x)
        return (p->x > q->x) - (p->x < q->x);
    if (p->y != q->y)
        return (p->y > q->y) - (p->y < q->y);
    return (p->index > q->index) - (p->index < q->index);
}

int pz_piece_notch_labels(const pz_piece *piece, char (*labels)[PZ_NOTCH_LABELS_MAX])
{
    notch_at *order = malloc(((size_t)piece->notch_count + 1) * sizeof *order);
    if (!order)
        return 0;
    for (int32_t i = 0; i < piece->notch_count; ++i) {
        order[i] = (notch_at){piece->notches[i].position[0], piece->notches[i].position[1], i};
        labels[i][0] = '\0';
    }
    qsort(order, (size_t)piece->notch_count, sizeof *order, compare_notch_at);
    for (int32_t first = 0, next; first < piece->notch_count; first = next) {
        char *label = labels[order[first].index];
        for (next = first; next < piece->notch_count && order[next].x == order[first].x &&
                           order[next].y == order[first].y;
             ++next) {
            size_t used = strlen(label);
            snprintf(label + used, PZ_NOTCH_LABELS_MAX - used, "%s%s", used ? " " : "",
                     piece->notches[order[next].index].label);
        }
    }
    free(order);
    return 1;
}

/* ---------------------------------------------------------------- darts: mouths */

static int on_leg(const pz_dart *dart, int32_t v)
{
    for (int32_t i = 0; i < dart->pair_count; ++i)
        if (dart->leg_a[i] == v || dart->leg_b[i] == v)
            return 1;
    return 0;
}

void pz_pieces_find_dart_mouths(const pz_pattern *pattern, const pz_pieces *pieces, const pz_outline_map *map,
                                pz_dart_mouth *mouths)
{
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        pz_dart_mouth *m = &mouths[d];
        m->piece = map->loop_piece[dart->tip];
        m->index_a = m->index_b = -1;
        m->folded = 0;
        if (m->piece < 0)
            continue;
        const pz_piece *piece = &pieces->pieces[m->piece];
        int32_t n = piece->sew_count, tip = map->loop_index[dart->tip], back = 0, ahead = 0;
        while (back < n && on_leg(dart, piece->sew_vertex[(tip - back - 1 + n) % n]))
            ++back;
        while (ahead < n && on_leg(dart, piece->sew_vertex[(tip + ahead + 1) % n]))
            ++ahead;
        if (back == 0 || ahead == 0 || back + ahead + 3 > n)
            continue;  /* a dart that does not open onto the outline: drawn, not bridged */
        m->index_a = (tip - back + n) % n;
        m->index_b = (tip + ahead) % n;
        const double *a = &piece->sew[2 * m->index_a], *b = &piece->sew[2 * m->index_b];
        double allowance = fmax(piece->sew_allowance[(m->index_a + n - 1) % n], piece->sew_allowance[m->index_b]);
        m->folded = hypot(b[0] - a[0], b[1] - a[1]) <= PZ_DART_FOLD_LIMIT * allowance;
    }
}

/* ---------------------------------------------------------------- growable per-piece lists */

static int append_notch(pz_piece *piece, size_t *capacity, const pz_notch *notch)
{
    if (!pz_grow((void **)&piece->notches, capacity, (size_t)piece->notch_count + 1, sizeof(pz_notch)))
        return 0;
    piece->notches[piece->notch_count++] = *notch;
    return 1;
}

/* A copy of `count` points as a new internal line. */
static int append_line(pz_piece *piece, size_t *capacity, const double *points, int32_t count)
{
    if (!pz_grow((void **)&piece->lines, capacity, (size_t)piece->line_count + 1, sizeof(pz_piece_line)))
        return 0;
    double *copy = malloc(2 * (size_t)count * sizeof(double));
    if (!copy)
        return 0;
    memcpy(copy, points, 2 * (size_t)count * sizeof(double));
    piece->lines[piece->line_count++] = (pz_piece_line){count, copy};
    return 1;
}

/* ---------------------------------------------------------------- notch geometry */

/* Smallest t > 0 where position + t direction meets the cut line, or -1. */
static double ray_to_cut(const pz_piece *piece, const double position[2], const double direction[2])
{
    double best = -1;
    for (int32_t i = 0; i < piece->cut_count; ++i) {
        const double *a = &piece->cut[2 * i], *b = &piece->cut[2 * ((i + 1) % piece->cut_count)];
        double e[2] = {b[0] - a[0], b[1] - a[1]}, w[2] = {a[0] - position[0], a[1] - position[1]};
        double denominator = direction[0] * e[1] - direction[1] * e[0];
        if (fabs(denominator) < 1e-15)
            continue;
        double t = (w[0] * e[1] - w[1] * e[0]) / denominator, s = (w[0] * direction[1] - w[1] * direction[0]) / denominator;
        if (t > 1e-9 && s >= -1e-12 && s <= 1 + 1e-12 && (best < 0 || t < best))
            best = t;
    }
    return best;
}

/* Outward direction and allowance at sew vertex i: the mean of its two edges. */
static void vertex_frame(const pz_piece *piece, int32_t i, double direction[2], double *allowance)
{
    int32_t n = piece->sew_count, previous = (i + n - 1) % n;
    double a[2], b[2];
    pz_piece_edge_normal(piece, previous, a);
    pz_piece_edge_normal(piece, i, b);
    double x = a[0] + b[0], y = a[1] + b[1], length = hypot(x, y);
    direction[0] = length > 1e-12 ? x / length : b[0];
    direction[1] = length > 1e-12 ? y / length : b[1];
    *allowance = fmin(piece->sew_allowance[previous], piece->sew_allowance[i]);
}

static void finish_notch(const pz_piece *piece, pz_notch *notch, double allowance, double depth)
{
    double t = ray_to_cut(piece, notch->position, notch->direction);
    if (t < 0)
        t = allowance;
    notch->cut_point[0] = notch->position[0] + t * notch->direction[0];
    notch->cut_point[1] = notch->position[1] + t * notch->direction[1];
    notch->depth_mm = fmin(depth, fmin(allowance, t));
}

/* One side of a seam: its vertices and their cumulative arc length in the pattern plane. */
typedef struct seam_side {
    const int32_t *vertices;
    int32_t count;
    double *arc;       /* count */
} seam_side;

static int side_arcs(seam_side *side, const double *uv)
{
    side->arc = malloc((size_t)side->count * sizeof(double) + 1);
    if (!side->arc)
        return 0;
    side->arc[0] = 0;
    for (int32_t j = 1; j < side->count; ++j) {
        int32_t a = side->vertices[j - 1], b = side->vertices[j];
        side->arc[j] = side->arc[j - 1] + hypot(uv[2 * b] - uv[2 * a], uv[2 * b + 1] - uv[2 * a + 1]);
    }
    return 1;
}

/* The notch at arc length s on a side; 0 when the side is not on an outline. */
static int seam_notch(const pz_pieces *pieces, const pz_outline_map *map, const seam_side *side, const double *uv,
                      double s, const pz_export_options *options, pz_notch *notch, int32_t *piece_out)
{
    int32_t j = 0;
    while (j + 2 < side->count && side->arc[j + 1] < s)
        ++j;
    int32_t a = side->vertices[j], b = side->vertices[j + 1];
    double length = side->arc[j + 1] - side->arc[j];
    double t = length > 0 ? fmin(1, fmax(0, (s - side->arc[j]) / length)) : 0;
    int32_t piece_id = map->loop_piece[a];
    if (piece_id < 0)
        return 0;
    const pz_piece *piece = &pieces->pieces[piece_id];
    /* At a vertex, exactly the vertex (a + 1 (b - a) need not be b): the notch of the next seam starting there
     * is then at the very same point, and the writers draw the two as one. */
    int32_t at_vertex = t <= 1e-12 ? a : t >= 1 - 1e-12 ? b : -1;
    for (int d = 0; d < 2; ++d)
        notch->position[d] = at_vertex >= 0 ? uv[2 * at_vertex + d] : uv[2 * a + d] + t * (uv[2 * b + d] - uv[2 * a + d]);
    notch->arc_mm = s;
    double allowance;
    int32_t edge = pz_outline_edge(pieces, map, a, b);
    if (t > 1e-9 && t < 1 - 1e-9 && edge >= 0) {
        pz_piece_edge_normal(piece, edge, notch->direction);
        allowance = piece->sew_allowance[edge];
    } else {
        int32_t at = t >= 0.5 ? b : a;
        if (map->loop_piece[at] != piece_id)
            return 0;
        vertex_frame(piece, map->loop_index[at], notch->direction, &allowance);
    }
    finish_notch(piece, notch, allowance, options->notch_depth_mm);
    *piece_out = piece_id;
    return 1;
}

/* ---------------------------------------------------------------- mirror twins */

/*
 * Mirror twins. When symmetry keeps a pair (Q, Q') as one "Cut 2 mirrored"
 * piece, Q' is not drawn: the user cuts Q twice, once mirrored, so the
 * mirrored copy carries Q's notches. A seam S with a side on Q' is then
 * matched at the table by its mirror image S' (the seam on Q that S reflects
 * to): S and S' share one label and one notch count, notch j counted from
 * mirror-image ends, so "A1" on a drawn piece meets "A1" on the mirrored cut
 * of its partner. S' is the seam between the mirror panels of S's panels
 * (a kept pair's partner, else the segmentation's panel_mirror) whose ends
 * lie nearest S's ends reflected in the mirror plane; the plane is estimated
 * from the kept pairs (normal along the difference of the two outlines'
 * centroids, through their midpoints), which exist whenever a piece is hidden.
 */
typedef struct seam_twins {
    int32_t *twin;       /* seam_count: the mirror-image seam sharing the label, or -1 */
    uint8_t *flipped;    /* seam_count: 1 when the twin runs the other way (notches counted from its end) */
    int32_t *label;      /* seam_count: the label's letter index (twins share one) */
} seam_twins;

/* Mean 3D position of a piece's outline vertices. */
static void outline_centroid(const pz_piece *piece, const double *positions, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    for (int32_t i = 0; i < piece->sew_count; ++i)
        for (int d = 0; d < 3; ++d)
            out[d] += positions[3 * (size_t)piece->sew_vertex[i] + d] / piece->sew_count;
}

/* The mirror plane (unit normal, a point on it) from the kept pairs; 0 when there is none. */
static int mirror_plane(const pz_pieces *pieces, const double *positions, double normal[3], double point[3])
{
    int32_t pairs = 0;
    normal[0] = normal[1] = normal[2] = point[0] = point[1] = point[2] = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        int32_t q = pieces->pieces[p].mirror_piece;
        if (q <= p)
            continue;
        double a[3], b[3], d[3];
        outline_centroid(&pieces->pieces[p], positions, a);
        outline_centroid(&pieces->pieces[q], positions, b);
        for (int k = 0; k < 3; ++k)
            d[k] = a[k] - b[k];
        double sign = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2] < 0 ? -1 : 1;
        for (int k = 0; k < 3; ++k) {
            normal[k] += sign * d[k];
            point[k] += 0.5 * (a[k] + b[k]);
        }
        ++pairs;
    }
    double length = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (pairs == 0 || !(length > 0))
        return 0;
    for (int k = 0; k < 3; ++k) {
        normal[k] /= length;
        point[k] /= pairs;
    }
    return 1;
}

static double distance3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* The panel a seam side on `panel` reflects to: a kept pair's partner, else the segmentation's mirror. */
static int32_t mirror_of(const pz_pieces *pieces, const int32_t *panel_mirror, int32_t panel)
{
    if (pieces->pieces[panel].mirror_piece >= 0)
        return pieces->pieces[panel].mirror_piece;
    int32_t m = panel_mirror ? panel_mirror[panel] : -1;
    return m >= 0 && m < pieces->piece_count ? m : -1;
}

typedef struct seam_key {
    int64_t panels;      /* min panel * count + max panel */
    int32_t seam;
} seam_key;

static int compare_seam_key(const void *a, const void *b)
{
    const seam_key *p = a, *q = b;
    if (p->panels != q->panels)
        return (p->panels > q->panels) - (p->panels < q->panels);
    return (p->seam > q->seam) - (p->seam < q->seam);
}

static int64_t panel_pair_key(int32_t a, int32_t b, int32_t count)
{
    return (int64_t)(a < b ? a : b) * count + (a < b ? b : a);
}

/* Seam s's best mirror twin among the seams joining its panels' mirrors (sorted keys), or -1. */
static int32_t find_twin(const pz_pattern *pattern, const pz_pieces *pieces, const int32_t *panel_mirror,
                         const seam_key *keys, const double normal[3], const double point[3], int32_t s,
                         uint8_t *flipped, double *score)
{
    const pz_seam *seam = &pattern->seams[s];
    int32_t ma = mirror_of(pieces, panel_mirror, seam->panel_a), mb = mirror_of(pieces, panel_mirror, seam->panel_b);
    if (ma < 0 || mb < 0 || seam->pair_count < 2)
        return -1;
    const double *positions = pattern->mesh->positions;
    double ends[2][3];
    for (int e = 0; e < 2; ++e) {   /* S's ends reflected in the plane */
        const double *x = &positions[3 * (size_t)seam->side_a[e ? seam->pair_count - 1 : 0]];
        double along = (x[0] - point[0]) * normal[0] + (x[1] - point[1]) * normal[1] + (x[2] - point[2]) * normal[2];
        for (int k = 0; k < 3; ++k)
            ends[e][k] = x[k] - 2 * along * normal[k];
    }
    seam_key probe = {panel_pair_key(ma, mb, pieces->piece_count), -1};
    size_t lo = 0, hi = (size_t)pattern->seam_count;
    while (lo < hi) {   /* the first key >= probe */
        size_t mid = (lo + hi) / 2;
        if (compare_seam_key(&keys[mid], &probe) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    int32_t best = -1;
    *score = INFINITY;
    for (size_t i = lo; i < (size_t)pattern->seam_count && keys[i].panels == probe.panels; ++i) {
        const pz_seam *other = &pattern->seams[keys[i].seam];
        if (other->pair_count < 2)
            continue;
        const double *start = &positions[3 * (size_t)other->side_a[0]];
        const double *end = &positions[3 * (size_t)other->side_a[other->pair_count - 1]];
        double same = distance3(ends[0], start) + distance3(ends[1], end);
        double reverse = distance3(ends[0], end) + distance3(ends[1], start);
        if (fmin(same, reverse) < *score) {
            *score = fmin(same, reverse);
            best = keys[i].seam;
            *flipped = reverse < same;
        }
    }
    return best;
}

static pz_status seam_twins_build(const pz_pieces *pieces, const pz_pattern *pattern, const int32_t *panel_mirror,
                                  seam_twins *twins, pz_ctx *ctx)
{
    int32_t count = pattern->seam_count;
    twins->twin = malloc(((size_t)count + 1) * sizeof(int32_t));
    twins->label = malloc(((size_t)count + 1) * sizeof(int32_t));
    twins->flipped = calloc((size_t)count + 1, 1);
    double *scores = malloc(((size_t)count + 1) * sizeof(double));
    seam_key *keys = malloc(((size_t)count + 1) * sizeof(seam_key));
    if (!twins->twin || !twins->label || !twins->flipped || !scores || !keys) {
        free(scores);
        free(keys);
        return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory placing notches");
    }
    for (int32_t s = 0; s < count; ++s) {
        twins->twin[s] = -1;
        scores[s] = INFINITY;
        keys[s] = (seam_key){panel_pair_key(pattern->seams[s].panel_a, pattern->seams[s].panel_b, pieces->piece_count),
                             s};
    }
    qsort(keys, (size_t)count, sizeof(seam_key), compare_seam_key);
    double normal[3], point[3];
    int have_plane = mirror_plane(pieces, pattern->mesh->positions, normal, point);
    for (int32_t s = 0; have_plane && s < count; ++s) {
        const pz_seam *seam = &pattern->seams[s];
        if (!pieces->pieces[seam->panel_a].mirrored && !pieces->pieces[seam->panel_b].mirrored)
            continue;   /* both sides drawn: their own label matches already */
        uint8_t flipped = 0;
        double score;
        int32_t t = find_twin(pattern, pieces, panel_mirror, keys, normal, point, s, &flipped, &score);
        if (t < 0 || t == s || score >= scores[s] || score >= scores[t])
            continue;
        for (int32_t k = 0; k < 2; ++k) {   /* a better match replaces an earlier one on either seam */
            int32_t u = k ? t : s, old = twins->twin[u];
            if (old >= 0) {
                twins->twin[old] = -1;
                scores[old] = INFINITY;
            }
        }
        twins->twin[s] = t, twins->twin[t] = s;
        twins->flipped[s] = twins->flipped[t] = flipped;
        scores[s] = scores[t] = score;
    }
    /* Letters: one per seam, twins sharing the first one's; consecutive. */
    int32_t next = 0;
    for (int32_t s = 0; s < count; ++s)
        twins->label[s] = twins->twin[s] >= 0 && twins->twin[s] < s ? twins->label[twins->twin[s]] : next++;
    free(scores);
    free(keys);
    return PZ_OK;
}

static void seam_twins_free(seam_twins *twins)
{
    free(twins->twin);
    free(twins->flipped);
    free(twins->label);
}

/* ---------------------------------------------------------------- seams */

/* The shorter side's length of seam s in the pattern plane. */
static double seam_shorter_side(const pz_pattern *pattern, const double *uv, int32_t s)
{
    const pz_seam *seam = &pattern->seams[s];
    double length[2] = {0, 0};
    const int32_t *side[2] = {seam->side_a, seam->side_b};
    for (int32_t j = 1; j < seam->pair_count; ++j)
        for (int k = 0; k < 2; ++k)
            length[k] += hypot(uv[2 * side[k][j]] - uv[2 * side[k][j - 1]],
                               uv[2 * side[k][j] + 1] - uv[2 * side[k][j - 1] + 1]);
    return fmin(length[0], length[1]);
}

static pz_status add_seam_notches(pz_pieces *pieces, const pz_pattern *pattern, const double *uv,
                                  const pz_outline_map *map, const pz_export_options *options,
                                  const seam_twins *twins, size_t *capacity, int32_t s, pz_ctx *ctx)
{
    const pz_seam *seam = &pattern->seams[s];
    if (seam->pair_count < 2)
        return PZ_OK;
    seam_side sides[2] = {{seam->side_a, seam->pair_count, NULL}, {seam->side_b, seam->pair_count, NULL}};
    int ok = side_arcs(&sides[0], uv) && side_arcs(&sides[1], uv);
    double length[2] = {0, 0};
    if (ok) {
        length[0] = sides[0].arc[seam->pair_count - 1];
        length[1] = sides[1].arc[seam->pair_count - 1];
    }
    /* A mirror twin has the same notches, counted from its mirror-image end. */
    int32_t twin = twins->twin[s];
    int from_end = twin >= 0 && twin < s && twins->flipped[s];
    double spacing = options->notch_spacing_mm, shorter = fmin(length[0], length[1]);
    if (twin >= 0)
        shorter = fmin(shorter, seam_shorter_side(pattern, uv, twin));
    int32_t interior = shorter > 1.25 * spacing ? (int32_t)floor((shorter - 0.25 * spacing) / spacing) : 0;
    for (int32_t j = 0; ok && j <= interior + 1; ++j) {
        for (int k = 0; k < 2 && ok; ++k) {
            double arc = j == interior + 1 ? length[k] : j * spacing;
            if (from_end)
                arc = length[k] - arc;
            pz_notch notch = {.seam = s, .dart = -1};
            pz_notch_label(twins->label[s], j, notch.label);
            int32_t piece = -1;
            if (seam_notch(pieces, map, &sides[k], uv, arc, options, &notch, &piece))
                ok = append_notch(&pieces->pieces[piece], &capacity[piece], &notch);
        }
    }
    free(sides[0].arc);
    free(sides[1].arc);
    return ok ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory placing notches");
}

/* ---------------------------------------------------------------- darts */

static int add_dart_notches(pz_piece *piece, size_t *capacity, const pz_dart_mouth *mouth, int32_t d,
                            const pz_export_options *options)
{
    const double *a = &piece->sew[2 * mouth->index_a], *b = &piece->sew[2 * mouth->index_b];
    double dx = b[0] - a[0], dy = b[1] - a[1], length = hypot(dx, dy);
    if (length <= 0)
        return 1;
    int32_t ends[2] = {mouth->index_a, mouth->index_b};
    for (int k = 0; k < 2; ++k) {
        pz_notch notch = {.seam = -1, .dart = d, .arc_mm = 0};
        snprintf(notch.label, sizeof notch.label, "D%d", (int)(d + 1));
        notch.position[0] = piece->sew[2 * ends[k]];
        notch.position[1] = piece->sew[2 * ends[k] + 1];
        double allowance = piece->sew_allowance[k == 0 ? (ends[0] + piece->sew_count - 1) % piece->sew_count : ends[1]];
        if (mouth->folded) {  /* out of the line that closes the V */
            notch.direction[0] = dy / length;
            notch.direction[1] = -dx / length;
        } else {
            double ignored;
            vertex_frame(piece, ends[k], notch.direction, &ignored);
        }
        finish_notch(piece, &notch, allowance, options->notch_depth_mm);
        if (!append_notch(piece, capacity, &notch))
            return 0;
    }
    return 1;
}

static int add_leg_line(pz_piece *piece, size_t *capacity, const int32_t *leg, int32_t count, int32_t tip,
                        const double *uv)
{
    double *points = malloc(2 * ((size_t)count + 1) * sizeof(double));
    if (!points)
        return 0;
    for (int32_t i = 0; i <= count; ++i) {
        int32_t v = i < count ? leg[i] : tip;
        points[2 * i] = uv[2 * v];
        points[2 * i + 1] = uv[2 * v + 1];
    }
    int ok = append_line(piece, capacity, points, count + 1);
    free(points);
    return ok;
}

static int add_dart_lines(pz_piece *piece, size_t *capacity, const pz_dart *dart, const double *uv)
{
    if (dart->pair_count < 1)
        return 1;
    const double *tip = &uv[2 * dart->tip], *a = &uv[2 * dart->leg_a[0]], *b = &uv[2 * dart->leg_b[0]];
    double fold[4] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), tip[0], tip[1]};
    double cross[8] = {tip[0] - TIP_MARK_MM, tip[1], tip[0] + TIP_MARK_MM, tip[1],
                       tip[0], tip[1] - TIP_MARK_MM, tip[0], tip[1] + TIP_MARK_MM};
    return add_leg_line(piece, capacity, dart->leg_a, dart->pair_count, dart->tip, uv) &&
           add_leg_line(piece, capacity, dart->leg_b, dart->pair_count, dart->tip, uv) &&
           append_line(piece, capacity, fold, 2) && append_line(piece, capacity, cross, 2) &&
           append_line(piece, capacity, cross + 4, 2);
}

/* ---------------------------------------------------------------- entry */

pz_status pz_pieces_add_notches(pz_pieces *pieces, const pz_pattern *pattern, const double *uv,
                                const pz_outline_map *map, const pz_dart_mouth *mouths, const int32_t *panel_mirror,
                                const pz_export_options *options, pz_ctx *ctx)
{
    size_t *capacity = calloc(2 * (size_t)pieces->piece_count + 1, sizeof(size_t));
    if (!capacity)
        return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory placing notches");
    size_t *line_capacity = capacity + pieces->piece_count;
    seam_twins twins = {NULL, NULL, NULL};
    pz_status status = seam_twins_build(pieces, pattern, panel_mirror, &twins, ctx);
    for (int32_t s = 0; s < pattern->seam_count && status == PZ_OK; ++s)
        status = add_seam_notches(pieces, pattern, uv, map, options, &twins, capacity, s, ctx);
    seam_twins_free(&twins);
    for (int32_t d = 0; d < pattern->dart_count && status == PZ_OK; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        int32_t p = map->loop_piece[dart->tip];
        if (p < 0)
            continue;
        int ok = add_dart_lines(&pieces->pieces[p], &line_capacity[p], dart, uv);
        if (ok && mouths[d].index_a >= 0)
            ok = add_dart_notches(&pieces->pieces[p], &capacity[p], &mouths[d], d, options);
        if (!ok)
            status = pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory placing dart notches");
    }
    free(capacity);
    return status;
}
