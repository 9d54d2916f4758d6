/*
 * tests/export/fixture_export_b.h -- pieces and patterns for the marker, PDF,
 * GLB and HTML tests and bench_marker (export helper B): hand-made pieces
 * whose every number is known, and a real flattened pattern:
 *  - fixture_piece_polygon: a piece from a counter-clockwise polygon (the sew
 *    line) with the cut line offset by a constant allowance (mitred; fine for
 *    the convex and L-shaped polygons used here), grainline along +v through
 *    the centre, one notch per sew corner;
 *  - fixture_pattern_build: the generated bodice cut into `panel_count`
 *    sectors around its vertical axis, flattened with LSCM, its metrics;
 *    fixture_pattern_export adds pz_pieces_build's pieces, the marker and
 *    the writers' inputs;
 * Everything is freed with fixture_pieces_free / fixture_pattern_free.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_FIXTURE_EXPORT_B_H
#define PZ_FIXTURE_EXPORT_B_H

#include "export/export.h"
#include "../test_util.h"
#include "generate/generate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static inline double fixture_polygon_area(const double *p, int32_t n)
{
    double area = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = &p[2 * i], *b = &p[2 * ((i + 1) % n)];
        area += a[0] * b[1] - b[0] * a[1];
    }
    return area / 2.0;
}

/* Offsets a counter-clockwise polygon outward by `distance` with mitred corners. */
static inline void fixture_offset(const double *p, int32_t n, double distance, double *out)
{
    for (int32_t i = 0; i < n; ++i) {
        const double *prev = &p[2 * ((i + n - 1) % n)], *here = &p[2 * i], *next = &p[2 * ((i + 1) % n)];
        double e0[2] = {here[0] - prev[0], here[1] - prev[1]}, e1[2] = {next[0] - here[0], next[1] - here[1]};
        double l0 = hypot(e0[0], e0[1]), l1 = hypot(e1[0], e1[1]);
        double n0[2] = {e0[1] / l0, -e0[0] / l0}, n1[2] = {e1[1] / l1, -e1[0] / l1}; /* outward for CCW */
        double m[2] = {n0[0] + n1[0], n0[1] + n1[1]};
        double ml = hypot(m[0], m[1]);
        double scale = ml > 1e-9 ? 2.0 / (ml * ml) : 1.0; /* 1 / cos(half angle), along the bisector */
        if (scale > 4.0)
            scale = 4.0;
        out[2 * i] = here[0] + distance * m[0] * scale;
        out[2 * i + 1] = here[1] + distance * m[1] * scale;
    }
}

/* Fills `piece` from a CCW polygon (copied). */
static inline void fixture_piece_polygon(pz_piece *piece, int32_t panel, const char *name, const double *sew, int32_t n,
                                  double allowance)
{
    memset(piece, 0, sizeof *piece);
    piece->panel = panel;
    snprintf(piece->name, sizeof piece->name, "%s", name);
    piece->cut_quantity = 1;
    piece->mirror_piece = -1;
    piece->sew_count = piece->cut_count = n;
    piece->sew = malloc((size_t)n * 2 * sizeof(double));
    piece->cut = malloc((size_t)n * 2 * sizeof(double));
    piece->sew_vertex = calloc((size_t)n, sizeof(int32_t));
    piece->sew_allowance = malloc((size_t)n * sizeof(double));
    piece->notches = calloc((size_t)n, sizeof(pz_notch));
    REQUIRE(piece->sew && piece->cut && piece->sew_vertex && piece->sew_allowance && piece->notches, "out of memory");
    memcpy(piece->sew, sew, (size_t)n * 2 * sizeof(double));
    fixture_offset(sew, n, allowance, piece->cut);
    piece->bbox_min[0] = piece->bbox_min[1] = INFINITY;
    piece->bbox_max[0] = piece->bbox_max[1] = -INFINITY;
    for (int32_t i = 0; i < n; ++i) {
        piece->sew_allowance[i] = allowance;
        for (int d = 0; d < 2; ++d) {
            piece->bbox_min[d] = fmin(piece->bbox_min[d], piece->cut[2 * i + d]);
            piece->bbox_max[d] = fmax(piece->bbox_max[d], piece->cut[2 * i + d]);
        }
    }
    piece->notch_count = n;
    for (int32_t i = 0; i < n; ++i) {
        pz_notch *notch = &piece->notches[i];
        notch->position[0] = sew[2 * i], notch->position[1] = sew[2 * i + 1];
        double dx = piece->cut[2 * i] - sew[2 * i], dy = piece->cut[2 * i + 1] - sew[2 * i + 1];
        double length = hypot(dx, dy);
        notch->direction[0] = length > 0 ? dx / length : 0, notch->direction[1] = length > 0 ? dy / length : 1;
        notch->cut_point[0] = piece->cut[2 * i], notch->cut_point[1] = piece->cut[2 * i + 1];
        notch->depth_mm = 5.0;
        notch->seam = -1, notch->dart = -1;
        snprintf(notch->label, sizeof notch->label, "A%d", (int)i + 1);
    }
    double cx = (piece->bbox_min[0] + piece->bbox_max[0]) / 2, cy = (piece->bbox_min[1] + piece->bbox_max[1]) / 2;
    double h = piece->bbox_max[1] - piece->bbox_min[1];
    piece->grain[0][0] = cx, piece->grain[0][1] = cy - h / 4;
    piece->grain[1][0] = cx, piece->grain[1][1] = cy + h / 4;
    piece->area_mm2 = fixture_polygon_area(piece->cut, n);
    piece->sew_area_mm2 = fixture_polygon_area(sew, n);
}

static inline pz_pieces *fixture_pieces_alloc(int32_t count)
{
    pz_pieces *pieces = calloc(1, sizeof *pieces);
    REQUIRE(pieces, "out of memory");
    pieces->pieces = calloc((size_t)count, sizeof(pz_piece));
    REQUIRE(pieces->pieces, "out of memory");
    pieces->piece_count = count;
    snprintf(pieces->garment_name, sizeof pieces->garment_name, "fixture");
    snprintf(pieces->size_name, sizeof pieces->size_name, "base");
    return pieces;
}

static inline void fixture_pieces_free(pz_pieces *pieces)
{
    if (!pieces)
        return;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        pz_piece *piece = &pieces->pieces[p];
        free(piece->sew);
        free(piece->cut);
        free(piece->sew_vertex);
        free(piece->sew_allowance);
        free(piece->notches);
        for (int32_t l = 0; l < piece->line_count; ++l)
            free(piece->lines[l].points);
        free(piece->lines);
    }
    free(pieces->pieces);
    free(pieces);
}

/* A w x h rectangle, or an L (the top-right quarter cut away) when `l_shape`, lower-left at the origin. */
static inline void fixture_piece_box(pz_piece *piece, int32_t panel, const char *name, double w, double h, int l_shape)
{
    double rect[8] = {0, 0, w, 0, w, h, 0, h};
    double ell[12] = {0, 0, w, 0, w, h / 2, w / 2, h / 2, w / 2, h, 0, h};
    fixture_piece_polygon(piece, panel, name, l_shape ? ell : rect, l_shape ? 6 : 4, 10.0);
}

/* ------------------------------------------------------------------ a flattened bodice */

typedef struct fixture_pattern {
    pz_mesh *garment;
    pz_pattern *pattern;
    double *uv;
    pz_metrics *metrics;
    /* fixture_pattern_export: */
    pz_export_options options;   /* the defaults */
    pz_pieces *pieces;           /* pz_pieces_build */
    pz_marker *marker;           /* pz_marker_build */
    pz_export_inputs inputs;     /* all of the above (points into this struct: do not copy it) */
} fixture_pattern;

/* The bodice (about `faces` faces) cut into `panel_count` sectors around its vertical axis, LSCM-flattened. */
static inline void fixture_pattern_build(fixture_pattern *fixture, int32_t faces, int32_t panel_count)
{
    pz_ctx ctx = {0};
    memset(fixture, 0, sizeof *fixture);
    pz_generate_options generate = {.target_faces = faces};
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &generate, &fixture->garment, &ctx), ctx);
    pz_mesh *mesh = fixture->garment;
    double axis[3];
    pz_mesh_vertical_axis(mesh, axis);
    int horizontal[2] = {axis[0] != 0 ? 1 : 0, axis[2] != 0 ? 1 : 2};
    if (axis[1] != 0)
        horizontal[0] = 0, horizontal[1] = 2;
    int32_t *face_panel = malloc((size_t)mesh->face_count * sizeof(int32_t));
    REQUIRE(face_panel, "out of memory");
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
                c[d] += mesh->positions[3 * mesh->faces[3 * f + k] + d] / 3.0;
        double angle = atan2(c[horizontal[1]], c[horizontal[0]]) + 3.14159265358979323846; /* 0 .. 2 pi */
        int32_t panel = (int32_t)(angle / (2 * 3.14159265358979323846) * panel_count);
        face_panel[f] = panel >= panel_count ? panel_count - 1 : panel;
    }
    REQUIRE_OK(pz_pattern_build(mesh, face_panel, NULL, NULL, "bodice", &fixture->pattern, &ctx), ctx);
    free(face_panel);
    fixture->uv = malloc((size_t)fixture->pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(fixture->uv, "out of memory");
    REQUIRE_OK(pz_param_lscm_pattern(fixture->pattern, NULL, fixture->uv, &ctx), ctx);
    REQUIRE_OK(pz_metrics_compute(fixture->pattern, fixture->uv, 0, NULL, &fixture->metrics, &ctx), ctx);
}

/* Pieces, marker and writer inputs of a built fixture pattern, with the default options. */
static inline void fixture_pattern_export(fixture_pattern *fixture)
{
    pz_ctx ctx = {0};
    pz_export_options_default(&fixture->options);
    REQUIRE_OK(pz_pieces_build(fixture->pattern, fixture->uv, &fixture->options, NULL, NULL, &fixture->pieces, &ctx),
               ctx);
    REQUIRE_OK(pz_marker_build(fixture->pieces, &fixture->options, &fixture->marker, &ctx), ctx);
    fixture->inputs = (pz_export_inputs){.garment = fixture->garment, .pattern = fixture->pattern,
                                         .uv = fixture->uv, .metrics = fixture->metrics, .pieces = fixture->pieces,
                                         .marker = fixture->marker, .options = &fixture->options};
}

static inline void fixture_pattern_free(fixture_pattern *fixture)
{
    pz_marker_free(&fixture->marker);
    pz_pieces_free(&fixture->pieces);
    pz_metrics_free(&fixture->metrics);
    free(fixture->uv);
    pz_pattern_free(&fixture->pattern);
    pz_mesh_free(&fixture->garment);
}

#endif
