/*
 * export/pieces.c -- pattern pieces for the cutting table: sew line, cut line
 * with per-edge allowance, grainline, areas, mirrored pairs, and the sheet
 * layout shared by the writers. Notches and dart lines: export/notches.c;
 * the offset itself: export/offset.c. Choices: docs/export.md.
 *
 * Sew line: the panel's boundary loop of the cut mesh in uv (every panel is a
 * disk, so it has one), turned counter-clockwise. Allowance per sew edge: the
 * seam's (per-seam override, else seam_allowance_mm) when both ends are
 * consecutive vertices of one side of a seam or of a dart leg, else the hem
 * allowance (open edges: hems, necklines, armholes).
 *
 * Darts: the cut line is the offset of the sew line with every dart's V
 * bridged by the straight line between its two mouth ends (a folded dart:
 * the fabric inside the V is folded into the dart, never cut away), so the
 * allowance never dips into a dart. The bridge takes the larger allowance of
 * the outline edges on either side of the mouth. A dart whose mouth is wider
 * than PZ_DART_FOLD_LIMIT allowances would fold too much fabric: it is cut
 * out, the cut line following its legs with the seam allowance.
 *
 * Mirrored pairs: panel_mirror names a candidate; the pair is kept when the
 * second piece, mirrored (u -> -u), matches the first after the best rigid
 * motion within 1 mm RMS: both outlines resampled to 256 points by arc
 * length, every cyclic shift tried with a closed-form 2D Procrustes, then the
 * RMS distance of the first outline's samples to the moved second polyline.
 *
 * Memory: O(V) per build for the vertex maps, O(n) per piece outline.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/internal.h"

#include "export/notches.h"
#include "export/offset.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MIRROR_SAMPLES 256
#define MIRROR_RMS_MM 1.0

/* ---------------------------------------------------------------- free */

static void piece_clear(pz_piece *piece)
{
    free(piece->sew);
    free(piece->sew_vertex);
    free(piece->sew_allowance);
    free(piece->cut);
    free(piece->notches);
    for (int32_t i = 0; i < piece->line_count; ++i)
        free(piece->lines[i].points);
    free(piece->lines);
}

void pz_pieces_free(pz_pieces **pieces)
{
    if (!pieces || !*pieces)
        return;
    for (int32_t i = 0; i < (*pieces)->piece_count; ++i)
        piece_clear(&(*pieces)->pieces[i]);
    free((*pieces)->pieces);
    free(*pieces);
    *pieces = NULL;
}

/* ---------------------------------------------------------------- outlines */

void pz_piece_edge_normal(const pz_piece *piece, int32_t i, double normal[2])
{
    int32_t j = (i + 1) % piece->sew_count;
    double dx = piece->sew[2 * j] - piece->sew[2 * i], dy = piece->sew[2 * j + 1] - piece->sew[2 * i + 1];
    double length = hypot(dx, dy);
    normal[0] = length > 0 ? dy / length : 0;
    normal[1] = length > 0 ? -dx / length : 0;
}

/* The loop of each panel: the longest in uv when a panel has several (it should have one). */
static pz_status panel_loops(const pz_pattern *pattern, const pz_topology *topology, const pz_loops *loops,
                             const double *uv, int32_t *panel_loop, pz_ctx *ctx)
{
    double *best = calloc((size_t)pattern->panel_count + 1, sizeof(double));
    if (!best)
        return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory building pieces");
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        panel_loop[p] = -1;
    for (int32_t l = 0; l < loops->loop_count; ++l) {
        int32_t first = loops->loop_offsets[l], end = loops->loop_offsets[l + 1];
        int32_t panel = pattern->face_panel[pz_he_face(topology->vertex_halfedge[loops->loop_vertices[first]])];
        double length = 0;
        for (int32_t j = first; j < end; ++j) {
            int32_t a = loops->loop_vertices[j], b = loops->loop_vertices[j + 1 < end ? j + 1 : first];
            length += hypot(uv[2 * b] - uv[2 * a], uv[2 * b + 1] - uv[2 * a + 1]);
        }
        if (panel_loop[panel] < 0 || length > best[panel]) {
            panel_loop[panel] = l;
            best[panel] = length;
        }
    }
    free(best);
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        if (panel_loop[p] < 0)
            return pz_error(ctx, PZ_ERR_DATA, "export: panel %d has no boundary (a closed panel)", (int)p);
    return PZ_OK;
}

/* Copies loop l into the piece's sew line, counter-clockwise, and fills the vertex map. */
static pz_status fill_sew_line(pz_piece *piece, const pz_loops *loops, int32_t l, const double *uv,
                               int32_t *loop_piece, int32_t *loop_index, int32_t piece_id, pz_ctx *ctx)
{
    int32_t first = loops->loop_offsets[l], count = loops->loop_offsets[l + 1] - first;
    piece->sew_count = count;
    piece->sew = malloc(2 * (size_t)count * sizeof(double));
    piece->sew_vertex = malloc((size_t)count * sizeof(int32_t));
    piece->sew_allowance = malloc((size_t)count * sizeof(double));
    if (!piece->sew || !piece->sew_vertex || !piece->sew_allowance)
        return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory building pieces");
    for (int32_t i = 0; i < count; ++i) {
        int32_t v = loops->loop_vertices[first + i];
        piece->sew_vertex[i] = v;
        piece->sew[2 * i] = uv[2 * v];
        piece->sew[2 * i + 1] = uv[2 * v + 1];
    }
    if (pz_polygon_signed_area(piece->sew, count) < 0) {  /* a piece flattened mirror-wise */
        for (int32_t i = 0, j = count - 1; i < j; ++i, --j) {
            int32_t v = piece->sew_vertex[i];
            piece->sew_vertex[i] = piece->sew_vertex[j];
            piece->sew_vertex[j] = v;
            for (int k = 0; k < 2; ++k) {
                double x = piece->sew[2 * i + k];
                piece->sew[2 * i + k] = piece->sew[2 * j + k];
                piece->sew[2 * j + k] = x;
            }
        }
    }
    for (int32_t i = 0; i < count; ++i) {
        loop_piece[piece->sew_vertex[i]] = piece_id;
        loop_index[piece->sew_vertex[i]] = i;
    }
    return PZ_OK;
}

static void mark_allowance(pz_pieces *pieces, const pz_outline_map *map, const int32_t *vertices, int32_t count,
                           int32_t tip, double allowance)
{
    for (int32_t j = 0; j < count; ++j) {
        int32_t next = j + 1 < count ? vertices[j + 1] : tip;
        if (next < 0)
            break;
        int32_t edge = pz_outline_edge(pieces, map, vertices[j], next);
        if (edge >= 0)
            pieces->pieces[map->loop_piece[vertices[j]]].sew_allowance[edge] = allowance;
    }
}

static void assign_allowances(pz_pieces *pieces, const pz_pattern *pattern, const pz_outline_map *map,
                              const pz_export_options *options)
{
    double seam = options->seam_allowance_mm;
    double hem = options->hem_allowance_mm >= 0 ? options->hem_allowance_mm : seam;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        for (int32_t i = 0; i < pieces->pieces[p].sew_count; ++i)
            pieces->pieces[p].sew_allowance[i] = hem;
    for (int32_t s = 0; s < pattern->seam_count; ++s) {
        const pz_seam *sm = &pattern->seams[s];
        double allowance = seam;
        if (options->seam_allowances_mm && options->seam_allowances_mm[s] >= 0)
            allowance = options->seam_allowances_mm[s];
        mark_allowance(pieces, map, sm->side_a, sm->pair_count, -1, allowance);
        mark_allowance(pieces, map, sm->side_b, sm->pair_count, -1, allowance);
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d) {
        const pz_dart *dart = &pattern->darts[d];
        mark_allowance(pieces, map, dart->leg_a, dart->pair_count, dart->tip, seam);
        mark_allowance(pieces, map, dart->leg_b, dart->pair_count, dart->tip, seam);
    }
}

/* ---------------------------------------------------------------- cut line */

/* 1 when sew index i lies strictly inside a bridged dart of this piece. */
static int inside_bridge(const pz_dart_mouth *mouths, int32_t dart_count, int32_t piece, int32_t n, int32_t i)
{
    for (int32_t d = 0; d < dart_count; ++d) {
        const pz_dart_mouth *m = &mouths[d];
        if (m->piece != piece || m->index_a < 0 || !m->folded)
            continue;
        int32_t from_a = (i - m->index_a + n) % n, span = (m->index_b - m->index_a + n) % n;
        if (from_a > 0 && from_a < span)
            return 1;
    }
    return 0;
}

/* The polygon the cut line offsets: the sew line with dart V's bridged. */
static pz_status cut_line(pz_piece *piece, int32_t piece_id, const pz_dart_mouth *mouths, int32_t dart_count,
                          pz_ctx *ctx)
{
    int32_t n = piece->sew_count, kept = 0;
    double *basis = malloc(2 * (size_t)n * sizeof(double) + 1), *distance = malloc((size_t)n * sizeof(double) + 1);
    if (!basis || !distance) {
        free(basis);
        free(distance);
        return pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory building pieces");
    }
    for (int32_t i = 0; i < n; ++i) {
        if (inside_bridge(mouths, dart_count, piece_id, n, i))
            continue;
        basis[2 * kept] = piece->sew[2 * i];
        basis[2 * kept + 1] = piece->sew[2 * i + 1];
        distance[kept] = piece->sew_allowance[i];
        for (int32_t d = 0; d < dart_count; ++d)
            if (mouths[d].piece == piece_id && mouths[d].folded && mouths[d].index_a == i) {
                int32_t after = mouths[d].index_b;
                double before = piece->sew_allowance[(i + n - 1) % n];
                distance[kept] = fmax(before, piece->sew_allowance[after]);
            }
        ++kept;
    }
    pz_status status = pz_offset_polygon(basis, kept, distance, &piece->cut, &piece->cut_count, ctx);
    free(basis);
    free(distance);
    if (status != PZ_OK) {
        char reason[sizeof ctx->error];
        snprintf(reason, sizeof reason, "%s", ctx->error);
        return pz_error(ctx, status, "%s (piece %s)", reason, piece->name);
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- grain, areas, box */

static void polygon_centroid(const double *points, int32_t count, double centroid[2])
{
    double twice = 0, cx = 0, cy = 0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
        double cross = a[0] * b[1] - a[1] * b[0];
        twice += cross;
        cx += (a[0] + b[0]) * cross;
        cy += (a[1] + b[1]) * cross;
    }
    centroid[0] = fabs(twice) > 0 ? cx / (3 * twice) : points[0];
    centroid[1] = fabs(twice) > 0 ? cy / (3 * twice) : points[1];
}

static void finish_piece(pz_piece *piece)
{
    piece->bbox_min[0] = piece->bbox_min[1] = DBL_MAX;
    piece->bbox_max[0] = piece->bbox_max[1] = -DBL_MAX;
    for (int32_t i = 0; i < piece->cut_count; ++i)
        for (int k = 0; k < 2; ++k) {
            piece->bbox_min[k] = fmin(piece->bbox_min[k], piece->cut[2 * i + k]);
            piece->bbox_max[k] = fmax(piece->bbox_max[k], piece->cut[2 * i + k]);
        }
    piece->area_mm2 = pz_polygon_signed_area(piece->cut, piece->cut_count);
    piece->sew_area_mm2 = pz_polygon_signed_area(piece->sew, piece->sew_count);
    double centroid[2], low = DBL_MAX, high = -DBL_MAX;
    polygon_centroid(piece->sew, piece->sew_count, centroid);
    for (int32_t i = 0; i < piece->sew_count; ++i) {
        low = fmin(low, piece->sew[2 * i + 1]);
        high = fmax(high, piece->sew[2 * i + 1]);
    }
    double half = 0.3 * (high - low);
    piece->grain[0][0] = piece->grain[1][0] = centroid[0];
    piece->grain[0][1] = centroid[1] - half;
    piece->grain[1][1] = centroid[1] + half;
}

/* ---------------------------------------------------------------- mirrored pairs */

/* n samples at equal arc length along a closed polygon (optionally mirrored u -> -u and reversed). */
static void resample(const double *points, int32_t count, int mirror, int32_t n, double *out)
{
    double perimeter = 0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
        perimeter += hypot(b[0] - a[0], b[1] - a[1]);
    }
    double walked = 0;
    int32_t i = 0;
    for (int32_t k = 0; k < n; ++k) {
        double target = perimeter * k / n;
        for (;;) {
            const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
            double length = hypot(b[0] - a[0], b[1] - a[1]);
            if (walked + length >= target || i == count - 1) {
                double t = length > 0 ? fmin(1, fmax(0, (target - walked) / length)) : 0;
                int32_t slot = mirror ? (n - k) % n : k;   /* mirroring reverses the turning sense */
                out[2 * slot] = (mirror ? -1 : 1) * (a[0] + t * (b[0] - a[0]));
                out[2 * slot + 1] = a[1] + t * (b[1] - a[1]);
                break;
            }
            walked += length;
            ++i;
        }
    }
}

/* Best rotation + translation of q onto p (n points, paired with shift); writes rotation (c, s) and the RMS. */
static double procrustes(const double *p, const double *q, int32_t n, int32_t shift, double *c, double *s,
                         double t[2])
{
    double pc[2] = {0, 0}, qc[2] = {0, 0};
    for (int32_t k = 0; k < n; ++k)
        for (int d = 0; d < 2; ++d) {
            pc[d] += p[2 * k + d] / n;
            qc[d] += q[2 * ((k + shift) % n) + d] / n;
        }
    double a = 0, b = 0, pp = 0, qq = 0;
    for (int32_t k = 0; k < n; ++k) {
        const double *qk = &q[2 * ((k + shift) % n)];
        double px = p[2 * k] - pc[0], py = p[2 * k + 1] - pc[1], qx = qk[0] - qc[0], qy = qk[1] - qc[1];
        a += qx * px + qy * py;
        b += qx * py - qy * px;
        pp += px * px + py * py;
        qq += qx * qx + qy * qy;
    }
    double norm = hypot(a, b);
    *c = norm > 0 ? a / norm : 1;
    *s = norm > 0 ? b / norm : 0;
    t[0] = pc[0] - (*c * qc[0] - *s * qc[1]);
    t[1] = pc[1] - (*s * qc[0] + *c * qc[1]);
    return sqrt(fmax(0, (pp + qq - 2 * norm) / n));
}

static double point_segment_distance(const double p[2], const double a[2], const double b[2])
{
    double dx = b[0] - a[0], dy = b[1] - a[1], length2 = dx * dx + dy * dy;
    double t = length2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2 : 0;
    t = fmin(1, fmax(0, t));
    return hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}

/* RMS distance (mm) of piece a's outline to piece b's mirrored outline after the best rigid motion. */
static double mirror_rms(const pz_piece *a, const pz_piece *b)
{
    double *p = malloc(4 * MIRROR_SAMPLES * sizeof(double));
    if (!p)
        return DBL_MAX;
    double *q = p + 2 * MIRROR_SAMPLES;
    resample(a->sew, a->sew_count, 0, MIRROR_SAMPLES, p);
    resample(b->sew, b->sew_count, 1, MIRROR_SAMPLES, q);
    double best = DBL_MAX, c = 1, s = 0, t[2] = {0, 0};
    for (int32_t shift = 0; shift < MIRROR_SAMPLES; ++shift) {
        double cs, sn, tt[2], rms = procrustes(p, q, MIRROR_SAMPLES, shift, &cs, &sn, tt);
        if (rms < best) {
            best = rms;
            c = cs;
            s = sn;
            t[0] = tt[0];
            t[1] = tt[1];
        }
    }
    /* Sample phase slides points along the outline: measure to the moved polyline instead. */
    double sum = 0;
    for (int32_t k = 0; k < MIRROR_SAMPLES; ++k) {
        double nearest = DBL_MAX;
        for (int32_t i = 0; i < MIRROR_SAMPLES; ++i) {
            const double *u = &q[2 * i], *v = &q[2 * ((i + 1) % MIRROR_SAMPLES)];
            double a2[2] = {c * u[0] - s * u[1] + t[0], s * u[0] + c * u[1] + t[1]};
            double b2[2] = {c * v[0] - s * v[1] + t[0], s * v[0] + c * v[1] + t[1]};
            nearest = fmin(nearest, point_segment_distance(&p[2 * k], a2, b2));
        }
        sum += nearest * nearest;
    }
    free(p);
    return sqrt(sum / MIRROR_SAMPLES);
}

static void find_mirrored_pairs(pz_pieces *pieces, const int32_t *panel_mirror)
{
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        pieces->pieces[p].mirror_piece = -1;
        pieces->pieces[p].cut_quantity = 1;
    }
    if (!panel_mirror)
        return;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        int32_t q = panel_mirror[p];
        if (q <= p || q >= pieces->piece_count || pieces->pieces[q].mirror_piece >= 0 ||
            pieces->pieces[p].mirror_piece >= 0)
            continue;
        if (mirror_rms(&pieces->pieces[p], &pieces->pieces[q]) > MIRROR_RMS_MM)
            continue;
        pieces->pieces[p].cut_quantity = 2;
        pieces->pieces[p].mirror_piece = q;
        pieces->pieces[q].mirror_piece = p;
        pieces->pieces[q].mirrored = 1;
    }
}

/* ---------------------------------------------------------------- build */

static void copy_name(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s", name);
}

static pz_status check_options(const pz_export_options *options, pz_ctx *ctx)
{
    if (!(options->seam_allowance_mm >= 0) || !(options->notch_spacing_mm > 0) || !(options->notch_depth_mm >= 0))
        return pz_error(ctx, PZ_ERR_USAGE,
                        "export: seam allowance %g mm, notch spacing %g mm, notch depth %g mm: allowance and depth "
                        "must be >= 0, spacing > 0",
                        options->seam_allowance_mm, options->notch_spacing_mm, options->notch_depth_mm);
    return PZ_OK;
}

static pz_status build_outlines(pz_pieces *pieces, const pz_pattern *pattern, const double *uv,
                                int32_t *loop_piece, int32_t *loop_index, const char *const *panel_names,
                                pz_ctx *ctx)
{
    pz_topology *topology = NULL;
    pz_loops *loops = NULL;
    int32_t *panel_loop = malloc((size_t)pattern->panel_count * sizeof(int32_t) + 1);
    pz_status status = panel_loop ? pz_topology_build(pattern->mesh, &topology, ctx)
                                  : pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory building pieces");
    if (status == PZ_OK)
        status = pz_topology_boundary_loops(topology, &loops, ctx);
    if (status == PZ_OK)
        status = panel_loops(pattern, topology, loops, uv, panel_loop, ctx);
    for (int32_t p = 0; p < pieces->piece_count && status == PZ_OK; ++p) {
        pz_piece *piece = &pieces->pieces[p];
        piece->panel = p;
        const char *name = panel_names && panel_names[p] && *panel_names[p] ? panel_names[p] : NULL;
        if (name)
            copy_name(piece->name, sizeof piece->name, name);
        else
            snprintf(piece->name, sizeof piece->name, "panel_%d", (int)p);
        status = fill_sew_line(piece, loops, panel_loop[p], uv, loop_piece, loop_index, p, ctx);
    }
    free(panel_loop);
    pz_loops_free(&loops);
    pz_topology_free(&topology);
    return status;
}

pz_status pz_pieces_build(const pz_pattern *pattern, const double *uv, const pz_export_options *options,
                          const int32_t *panel_mirror, const char *const *panel_names, pz_pieces **out,
                          pz_ctx *ctx)
{
    *out = NULL;
    pz_status status = check_options(options, ctx);
    if (status != PZ_OK)
        return status;
    int32_t vertex_count = pattern->mesh->vertex_count;
    pz_pieces *pieces = calloc(1, sizeof *pieces);
    int32_t *loop_piece = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    int32_t *loop_index = malloc((size_t)vertex_count * sizeof(int32_t) + 1);
    pz_dart_mouth *mouths = malloc((size_t)pattern->dart_count * sizeof(pz_dart_mouth) + 1);
    if (pieces)
        pieces->pieces = calloc((size_t)pattern->panel_count + 1, sizeof(pz_piece));
    if (!pieces || !pieces->pieces || !loop_piece || !loop_index || !mouths)
        status = pz_error(ctx, PZ_ERR_NOMEM, "export: out of memory building pieces");
    if (status == PZ_OK) {
        pieces->piece_count = pattern->panel_count;
        copy_name(pieces->garment_name, sizeof pieces->garment_name,
                  options->garment_name && *options->garment_name ? options->garment_name : "garment");
        copy_name(pieces->size_name, sizeof pieces->size_name,
                  options->size_name && *options->size_name ? options->size_name : "base");
        for (int32_t v = 0; v < vertex_count; ++v)
            loop_piece[v] = loop_index[v] = -1;
        status = build_outlines(pieces, pattern, uv, loop_piece, loop_index, panel_names, ctx);
    }
    pz_outline_map map = {loop_piece, loop_index};
    if (status == PZ_OK) {
        assign_allowances(pieces, pattern, &map, options);
        pz_pieces_find_dart_mouths(pattern, pieces, &map, mouths);
    }
    for (int32_t p = 0; status == PZ_OK && p < pieces->piece_count; ++p)
        status = cut_line(&pieces->pieces[p], p, mouths, pattern->dart_count, ctx);
    if (status == PZ_OK) {   /* pairs before notches: a hidden piece's seams take their twins' labels */
        find_mirrored_pairs(pieces, panel_mirror);
        status = pz_pieces_add_notches(pieces, pattern, uv, &map, mouths, panel_mirror, options, ctx);
    }
    if (status == PZ_OK && options->fold)
        status = pz_pieces_fold(pieces, panel_mirror, ctx);
    if (status == PZ_OK)
        for (int32_t p = 0; p < pieces->piece_count; ++p)
            finish_piece(&pieces->pieces[p]);
    free(loop_piece);
    free(loop_index);
    free(mouths);
    if (status != PZ_OK) {
        pz_pieces_free(&pieces);
        return status;
    }
    *out = pieces;
    return PZ_OK;
}

/* ---------------------------------------------------------------- sheet layout */

typedef struct shelf_item {
    int32_t piece;
    double height;
} shelf_item;

static int compare_tallest(const void *x, const void *y)
{
    const shelf_item *a = x, *b = y;
    if (a->height != b->height)
        return (a->height < b->height) - (a->height > b->height);
    return (a->piece > b->piece) - (a->piece < b->piece);
}

/* Rows being filled left to right, top to bottom (y measured down from the band). */
typedef struct shelf {
    double row_width, gap, x, y, row_height, used_width;
} shelf;

static void shelf_place(shelf *s, const pz_piece *piece, double *offset)
{
    double width = piece->bbox_max[0] - piece->bbox_min[0], height = piece->bbox_max[1] - piece->bbox_min[1];
    if (s->x > 0 && s->x + width > s->row_width) {
        s->y += s->row_height + s->gap;
        s->x = 0;
        s->row_height = 0;
    }
    offset[0] = s->gap + s->x - piece->bbox_min[0];
    offset[1] = s->y;   /* the row's top, turned into a y-up offset at the end */
    s->x += width + s->gap;
    s->used_width = fmax(s->used_width, s->x);
    s->row_height = fmax(s->row_height, height);
}

void pz_pieces_sheet_layout(const pz_pieces *pieces, double gap_mm, double reserve_top_mm, double *offsets,
                            double size[2])
{
    int32_t count = 0;
    double box_area = 0, widest = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        offsets[2 * p] = offsets[2 * p + 1] = 0;
        if (piece->mirrored)
            continue;
        double width = piece->bbox_max[0] - piece->bbox_min[0], height = piece->bbox_max[1] - piece->bbox_min[1];
        box_area += (width + gap_mm) * (height + gap_mm);
        widest = fmax(widest, width);
        ++count;
    }
    /* Rows about as wide as the sheet will be tall, tallest pieces first. */
    shelf s = {fmax(widest, 1.2 * sqrt(box_area)), gap_mm, 0, 0, 0, 0};
    shelf_item *items = malloc((size_t)count * sizeof(shelf_item) + 1);
    if (items) {
        int32_t n = 0;
        for (int32_t p = 0; p < pieces->piece_count; ++p)
            if (!pieces->pieces[p].mirrored)
                items[n++] = (shelf_item){p, pieces->pieces[p].bbox_max[1] - pieces->pieces[p].bbox_min[1]};
        qsort(items, (size_t)count, sizeof(shelf_item), compare_tallest);
        for (int32_t i = 0; i < count; ++i)
            shelf_place(&s, &pieces->pieces[items[i].piece], &offsets[2 * items[i].piece]);
        free(items);
    } else {  /* out of memory: the same rows in piece order (less compact, still apart) */
        for (int32_t p = 0; p < pieces->piece_count; ++p)
            if (!pieces->pieces[p].mirrored)
                shelf_place(&s, &pieces->pieces[p], &offsets[2 * p]);
    }
    double pieces_height = count ? s.y + s.row_height : 0;
    size[0] = fmax(s.used_width + gap_mm, reserve_top_mm > 0 ? 2 * reserve_top_mm : 0);
    size[1] = pieces_height + 2 * gap_mm + reserve_top_mm;
    /* y up: the top of a piece's box sits offsets[2p+1] below the reserved band. */
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored)
            offsets[2 * p + 1] = size[1] - reserve_top_mm - gap_mm - offsets[2 * p + 1] - pieces->pieces[p].bbox_max[1];
}
