/*
 * tests/segment/test_goals.c -- the goals of one panel (pz_segment_goals):
 *  - an open cylinder (developable disk): strain below 0.01, no flip,
 *    4 corners (the rectangle's turns);
 *  - a closed tube cut along one ruling (a self-seam): a disk again with 4
 *    junction corners where the seam meets the rims, strain below 0.01;
 *  - a hemisphere fails S = 0.01 with a strain reason and passes S = 0.5;
 *  - a closed tube (a ring, two loops) is NOT_DISK and is not flattened;
 *  - a flat panel whose top border is a saw-tooth staircase shared with two
 *    neighbours counts its 3 junctions and 2 rectangle turns (5), not one
 *    per tooth; with C = 4 it fails on corners only (and is not flattened);
 *  - a panel that is two separate pieces is NOT_DISK;
 *  - a dart (a slit from the outline to a tip inside) adds no corner, with
 *    its mouth on the border or at a seam; on a dome it flattens as one dart
 *    that opens by more than 2 degrees;
 *  - pz_goal_describe names each failure;
 *  - piece shapes: pz_piece_width of flat rectangles; a band along the hem is
 *    narrow and small, a strap between two borders is narrow by the input
 *    (not judged), a whole component is neither.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "segment/segment.h"
#include "test_meshes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

static pz_goal_options goal_options(double max_strain, int32_t max_corners)
{
    pz_goal_options options = {0};
    options.max_strain = max_strain;
    options.max_corners = max_corners;
    options.grain[2] = 1;
    return options;
}

/* Evaluates the panel made of every face of mesh with the given cut flags (NULL: none). */
static pz_goal_result evaluate_all(const pz_mesh *mesh, const pz_topology *topology, const uint8_t *cut,
                                   const pz_goal_options *options)
{
    int32_t *ids = malloc((size_t)mesh->face_count * sizeof(int32_t));
    uint8_t *none = calloc((size_t)topology->edge_count, 1);
    REQUIRE(ids && none, "out of memory");
    for (int32_t f = 0; f < mesh->face_count; ++f)
        ids[f] = f;
    pz_goal_result result;
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut ? cut : none, ids, mesh->face_count, options, &result, &ctx),
               ctx);
    free(ids);
    free(none);
    return result;
}

static void test_open_cylinder(void)
{
    pz_generate_options generate = {.target_faces = 1200, .open = 1};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_CYLINDER, &generate, &mesh, &ctx), ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_goal_options options = goal_options(0.05, 8);
    pz_goal_result result = evaluate_all(mesh, topology, NULL, &options);
    CHECK(result.failures == 0, "open cylinder fails: %u", result.failures);
    CHECK(result.boundary_loops == 1, "%d loops", (int)result.boundary_loops);
    CHECK(result.corners == 4, "open cylinder has %d corners, expected 4", (int)result.corners);
    CHECK(result.max_abs_strain >= 0 && result.max_abs_strain < 0.01, "strain %g", result.max_abs_strain);
    CHECK(result.flipped_triangles == 0, "%d flipped", (int)result.flipped_triangles);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* A tube of 24 x 8 squares: the edges of the ruling at column 0 cut (a self-seam), or no cut (a ring). */
static void test_tube(void)
{
    const int columns = 24, rows = 8;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_TUBE, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v) /* radius 30 mm, rows 10 mm: near-equilateral faces */
        for (int k = 0; k < 3; ++k)
            mesh->positions[3 * v + k] *= k < 2 ? 30.0 : 10.0;
    pz_topology *topology = test_topology(mesh, &ctx);
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(cut, "out of memory");
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        int32_t a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        if (a % columns == 0 && b % columns == 0)
            cut[e] = 1;
    }
    pz_goal_options options = goal_options(0.05, 8);
    pz_goal_result opened = evaluate_all(mesh, topology, cut, &options);
    CHECK(opened.failures == 0, "tube cut along a ruling fails: %u", opened.failures);
    CHECK(opened.corners == 4, "cut tube has %d corners, expected 4", (int)opened.corners);
    CHECK(opened.max_abs_strain >= 0 && opened.max_abs_strain < 0.01, "strain %g", opened.max_abs_strain);

    pz_goal_result ring = evaluate_all(mesh, topology, NULL, &options);
    CHECK(ring.failures & PZ_GOAL_NOT_DISK, "a ring passes as a disk");
    CHECK(ring.boundary_loops == 2, "ring has %d loops", (int)ring.boundary_loops);
    CHECK(ring.max_abs_strain == -1, "a ring was flattened");
    char text[256];
    pz_goal_describe(&ring, &options, text, sizeof text);
    CHECK(strstr(text, "not a disk") != NULL, "describe: %s", text);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

static void test_hemisphere(void)
{
    pz_generate_options generate = {.target_faces = 1200};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_generate(PZ_SHAPE_HEMISPHERE, &generate, &mesh, &ctx), ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    pz_goal_options strict = goal_options(0.01, 8), loose = goal_options(0.5, 8);
    pz_goal_result tight = evaluate_all(mesh, topology, NULL, &strict);
    CHECK(tight.failures == PZ_GOAL_STRAIN, "hemisphere at S = 0.01: failures %u", tight.failures);
    CHECK(tight.max_abs_strain > 0.01, "strain %g", tight.max_abs_strain);
    CHECK(tight.corners == 0, "a hemisphere has %d corners", (int)tight.corners);
    char text[256];
    pz_goal_describe(&tight, &strict, text, sizeof text);
    CHECK(strstr(text, "strain 0.0") != NULL && strstr(text, "> 0.01") != NULL, "describe: %s", text);
    /* S = 0: a tiny strain keeps its digits ("strain 0.0000 > 0.0000" told nothing). */
    pz_goal_result tiny = {.failures = PZ_GOAL_STRAIN, .boundary_loops = 1, .max_abs_strain = 3.25e-5,
                           .max_seam_mismatch = -1, .min_dart_opening_deg = -1};
    pz_goal_options zero = strict;
    zero.max_strain = 0;
    pz_goal_describe(&tiny, &zero, text, sizeof text);
    CHECK(strcmp(text, "strain 3.25e-05 > 0") == 0, "describe at S = 0: '%s'", text);
    pz_goal_result relaxed = evaluate_all(mesh, topology, NULL, &loose);
    CHECK(relaxed.failures == 0, "hemisphere at S = 0.5: failures %u (strain %g)", relaxed.failures,
          relaxed.max_abs_strain);
    pz_goal_describe(&relaxed, &loose, text, sizeof text);
    CHECK(strcmp(text, "ok") == 0, "describe: %s", text);
    printf("hemisphere strain %.4f\n", relaxed.max_abs_strain);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* Flat 30 x 20 grid: panel 0 below a one-square saw-tooth (row 10 or 11), above it
 * panel 1 (left half) and 2 (right half). */
static void test_saw_tooth(void)
{
    const int columns = 30, rows = 20;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    int32_t *label = malloc((size_t)mesh->face_count * sizeof(int32_t));
    int32_t *ids = malloc((size_t)mesh->face_count * sizeof(int32_t));
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(label && ids && cut, "out of memory");
    int32_t count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        int i = (f / 2) % columns, j = (f / 2) / columns;
        label[f] = j < 10 + i % 2 ? 0 : i < columns / 2 ? 1 : 2;
        if (label[f] == 0)
            ids[count++] = f;
    }
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e], t = topology->edge_halfedge[2 * e + 1];
        cut[e] = t >= 0 && label[pz_he_face(h)] != label[pz_he_face(t)];
    }
    pz_goal_options options = goal_options(0.05, 8);
    pz_goal_result result;
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut, ids, count, &options, &result, &ctx), ctx);
    CHECK(result.corners == 5, "saw-tooth panel has %d corners, expected 5", (int)result.corners);
    CHECK(result.failures == 0, "saw-tooth panel fails: %u", result.failures);
    CHECK(result.max_abs_strain >= 0 && result.max_abs_strain < 1e-3, "flat panel strain %g",
          result.max_abs_strain);
    pz_goal_options few = goal_options(0.05, 4);
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut, ids, count, &few, &result, &ctx), ctx);
    CHECK(result.failures == PZ_GOAL_CORNERS, "C = 4: failures %u", result.failures);
    CHECK(result.max_abs_strain == -1, "a panel with too many corners was flattened");

    /* Two squares far apart: one panel in two pieces. */
    int32_t apart[4] = {0, 1, 2 * (columns * rows - 1), 2 * (columns * rows - 1) + 1};
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut, apart, 4, &options, &result, &ctx), ctx);
    CHECK(result.failures & PZ_GOAL_NOT_DISK, "two pieces pass as a disk");

    /* Bad input is a usage error. */
    int32_t repeated[2] = {0, 0};
    CHECK(pz_segment_goals(mesh, topology, cut, repeated, 2, &options, &result, &ctx) == PZ_ERR_USAGE,
          "repeated face accepted");
    free(label);
    free(ids);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* Cuts the vertical grid line x = column between rows from and to (a flat grid, columns + 1 vertices wide). */
static void cut_vertical(const pz_topology *topology, int columns, int column, int from, int to, uint8_t *cut)
{
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e];
        int32_t a = pz_he_from(topology, h), b = pz_he_to(topology, h);
        int ia = a % (columns + 1), ib = b % (columns + 1), ja = a / (columns + 1), jb = b / (columns + 1);
        if (ia == column && ib == column && ja >= from && jb >= from && ja <= to && jb <= to)
            cut[e] = 1;
    }
}

/*
 * A dart is no corner of the outline a cutter sees (docs/segment.md): a
 * 30 x 20 flat rectangle with a slit from the bottom border up to row 8 keeps
 * its 4 corners (not 4 + tip + 2 mouth ends), flattens with the slit as a
 * dart; a slit whose mouth sits at a junction (the bottom half is a
 * neighbouring panel) adds no corner either (2 junctions + 2 turns).
 */
static void test_dart_corners(void)
{
    const int columns = 30, rows = 20;
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    int32_t *ids = malloc((size_t)mesh->face_count * sizeof(int32_t));
    REQUIRE(cut && ids, "out of memory");
    cut_vertical(topology, columns, 15, 0, 8, cut);
    pz_goal_options options = goal_options(0.05, 8);
    pz_goal_result result = evaluate_all(mesh, topology, cut, &options);
    CHECK(result.corners == 4, "slit rectangle has %d corners, expected 4", (int)result.corners);
    /* Flat, the slit's legs lie on each other (they touch: not injective); on a dome (positive curvature at
     * the tip) the dart opens. */
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double *p = mesh->positions + 3 * v, dx = p[0] - 15, dy = p[1] - 8;
        p[2] = -0.015 * (dx * dx + dy * dy);
    }
    pz_goal_options loose = goal_options(0.5, 8);
    result = evaluate_all(mesh, topology, cut, &loose);
    CHECK(result.failures == 0, "slit dome fails: %u", result.failures);
    CHECK(result.corners == 4, "slit dome has %d corners, expected 4", (int)result.corners);
    CHECK(result.darts == 1, "slit dome has %d darts", (int)result.darts);
    CHECK(result.min_dart_opening_deg > 2, "the dome's dart opens by %g degrees", result.min_dart_opening_deg);
    printf("dome dart: opening %.1f degrees, strain %.3f\n", result.min_dart_opening_deg, result.max_abs_strain);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        mesh->positions[3 * v + 2] = 0;

    /* The top half (rows 10..19) is the panel; the slit runs down from row 16 to the seam at row 10. */
    memset(cut, 0, (size_t)topology->edge_count);
    int32_t count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        if ((f / 2) / columns >= 10)
            ids[count++] = f;
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e], t = topology->edge_halfedge[2 * e + 1];
        int above_h = (pz_he_face(h) / 2) / columns >= 10, above_t = t >= 0 && (pz_he_face(t) / 2) / columns >= 10;
        cut[e] = t >= 0 && above_h != above_t;
    }
    cut_vertical(topology, columns, 15, 10, 16, cut);
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut, ids, count, &options, &result, &ctx), ctx);
    CHECK(!(result.failures & (PZ_GOAL_CORNERS | PZ_GOAL_NOT_DISK)), "panel with a dart at its seam fails: %u",
          result.failures);
    CHECK(result.corners == 4, "panel with a dart at its seam has %d corners, expected 4", (int)result.corners);
    free(ids);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
}

/* pz_piece_width on flat rectangles of unit squares (2D points): twice the largest inscribed distance. */
static double rectangle_width(int columns, int rows, double size)
{
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    pz_topology *topology = test_topology(mesh, &ctx);
    double *points = malloc((size_t)mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(points, "out of memory");
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 2; ++k)
            points[2 * v + k] = size * mesh->positions[3 * v + k];
    double width = -1;
    REQUIRE_OK(pz_piece_width(mesh->vertex_count, points, 2, mesh->face_count, mesh->faces,
                              topology->vertex_on_boundary, &width, &ctx), ctx);
    free(points);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    return width;
}

/* Flat grid of 10 mm squares, `columns` x `rows`; label[f] from `band`: the panel of each face. */
typedef int (*band_label)(int column, int row);

static int hem_band(int column, int row)
{
    (void)column;
    return row < 2;  /* a band 20 mm wide along the bottom border */
}

static int strap(int column, int row)
{
    (void)row;
    return column >= 5 && column < 25;  /* the whole height of a 20 mm grid: border on both long sides */
}

static pz_goal_result shape_of(int columns, int rows, band_label band, const pz_goal_options *options)
{
    pz_mesh *mesh = test_grid(columns, rows, TEST_GRID_FLAT, 0, &ctx);
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int k = 0; k < 2; ++k)
            mesh->positions[3 * v + k] *= 10;
    pz_topology *topology = test_topology(mesh, &ctx);
    int32_t *label = malloc((size_t)mesh->face_count * sizeof(int32_t));
    int32_t *ids = malloc((size_t)mesh->face_count * sizeof(int32_t));
    uint8_t *cut = calloc((size_t)topology->edge_count, 1);
    REQUIRE(label && ids && cut, "out of memory");
    int32_t count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        label[f] = band((f / 2) % columns, (f / 2) / columns);
        if (label[f])
            ids[count++] = f;
    }
    for (int32_t e = 0; e < topology->edge_count; ++e) {
        int32_t h = topology->edge_halfedge[2 * e], t = topology->edge_halfedge[2 * e + 1];
        cut[e] = t >= 0 && label[pz_he_face(h)] != label[pz_he_face(t)];
    }
    pz_goal_result result;
    REQUIRE_OK(pz_segment_goals(mesh, topology, cut, ids, count, options, &result, &ctx), ctx);
    free(label);
    free(ids);
    free(cut);
    pz_topology_free(&topology);
    pz_mesh_free(&mesh);
    return result;
}

/*
 * Piece shapes (docs/segment.md, "Piece shapes"): the width of flat rectangles; a band cut off along the
 * hem is narrow (its seam makes it so) and small; a strap the garment itself makes narrow (border on both
 * long sides, seams at its ends) is not judged narrow; a whole component is neither narrow nor small.
 */
static void test_piece_shapes(void)
{
    double wide = rectangle_width(20, 20, 5), strip = rectangle_width(40, 6, 5), thin = rectangle_width(40, 1, 5);
    CHECK(fabs(wide - 100) < 3, "a 100 mm square is %.2f mm wide", wide);
    CHECK(fabs(strip - 30) < 2, "a 200 x 30 mm strip is %.2f mm wide", strip);
    CHECK(thin > 2 && thin < 6, "a strip one square (5 mm) wide is %.2f mm wide", thin);

    pz_goal_options options = goal_options(0.05, 8);
    pz_goal_options_default(&options);
    options.textile_iterations = -1;  /* the shape alone */
    pz_goal_result band = shape_of(30, 20, hem_band, &options);
    CHECK(band.min_width_mm > 18 && band.min_width_mm < 22 && !band.width_forced, "hem band: %.1f mm wide, forced %d",
          band.min_width_mm, band.width_forced);
    CHECK(fabs(band.area_share - 0.1) < 1e-9 && !band.area_forced, "hem band: area share %g", band.area_share);
    CHECK(band.failures == PZ_GOAL_NARROW, "hem band: failures %u", band.failures);
    options.min_piece_area = 0.2;
    band = shape_of(30, 20, hem_band, &options);
    CHECK(band.failures == (PZ_GOAL_NARROW | PZ_GOAL_SMALL), "hem band, 20 %% minimum area: failures %u",
          band.failures);
    char text[256];
    pz_goal_describe(&band, &options, text, sizeof text);
    CHECK(strstr(text, "mm wide < 40 mm") && strstr(text, "of the area < 20%"), "describe: '%s'", text);
    options.min_piece_area = 0.01;
    options.min_piece_width_mm = 15;
    band = shape_of(30, 20, hem_band, &options);
    CHECK(band.failures == 0, "hem band, 15 mm minimum: failures %u", band.failures);

    pz_goal_options_default(&options);
    options.textile_iterations = -1;
    pz_goal_result held = shape_of(30, 2, strap, &options);
    CHECK(held.min_width_mm < 25 && held.width_forced && held.failures == 0,
          "strap: %.1f mm wide, forced %d, failures %u", held.min_width_mm, held.width_forced, held.failures);
    options.min_piece_width_mm = 120;  /* farther from its end seams than 100 mm nowhere: narrow by them */
    held = shape_of(30, 2, strap, &options);
    CHECK(!held.width_forced && (held.failures & PZ_GOAL_NARROW), "strap, 120 mm minimum: forced %d, failures %u",
          held.width_forced, held.failures);
    pz_goal_options_default(&options);
    options.textile_iterations = -1;
    options.min_piece_area = 0.5;
    pz_goal_result whole = shape_of(30, 2, hem_band, &options);  /* every face: one component */
    CHECK(whole.width_forced && whole.area_forced && fabs(whole.area_share - 1) < 1e-9 && whole.failures == 0,
          "whole component: forced %d %d, share %g, failures %u", whole.width_forced, whole.area_forced,
          whole.area_share, whole.failures);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    test_open_cylinder();
    test_tube();
    test_hemisphere();
    test_saw_tooth();
    test_dart_corners();
    test_piece_shapes();
    return test_finish();
}
