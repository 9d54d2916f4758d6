/*
 * tests/export/test_pieces.c -- pattern pieces (pz_pieces_build) and their
 * cut line (the offset of export/offset.c).
 *
 * The cut line is checked against the sew line point by point and notch
 * pairs by arc length (tests/export/piece_checks.h). Cases: known answers (a
 * square), shapes that make raw offsets loop (an acute spike, a narrow slot,
 * random star polygons), per-edge allowances; a generated bodice in
 * quarters (notch pairs at equal arc length, mirrored pairs, allowances on
 * seams vs hems, the allowance file); every shared garment (its UV panels
 * or two halves, LSCM: the patterns `panelize run` makes are checked by
 * test_run_patterns.c).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "export/export.h"
#include "export/notches.h"
#include "export/offset.h"
#include "export_fixtures.h"
#include "piece_checks.h"
#include "test_files.h"
#include "generate/generate.h"

#include <float.h>

static pz_ctx ctx;

#define PI 3.14159265358979323846

/* Offsets a polygon with the given allowances and checks it. */
static void offset_case(const double *points, int32_t n, const double *allowance, const char *what, double **cut_out,
                        int32_t *cut_count_out)
{
    double *cut = NULL;
    int32_t cut_count = 0;
    REQUIRE_OK(pz_offset_polygon(points, n, allowance, &cut, &cut_count, &ctx), ctx);
    outline_check o = {points, n, allowance, NULL, NULL, 0, NULL};
    check_result r = check_cut(&o, cut, cut_count);
    expect_good_cut(&r, what);
    CHECK(pz_polygon_signed_area(cut, cut_count) > pz_polygon_signed_area(points, n), "%s: cut area", what);
    if (cut_out) {
        *cut_out = cut;
        *cut_count_out = cut_count;
    } else
        free(cut);
}

/* ---------------------------------------------------------------- offsets: known answers and hard shapes */

static void test_square(void)
{
    const double square[8] = {0, 0, 100, 0, 100, 100, 0, 100}, ten[4] = {10, 10, 10, 10};
    double *cut;
    int32_t count;
    offset_case(square, 4, ten, "square", &cut, &count);
    CHECK(count == 4, "a square's cut line has %d corners", (int)count);
    CHECK(fabs(pz_polygon_signed_area(cut, count) - 120.0 * 120.0) < 1e-6, "area %.6f",
          pz_polygon_signed_area(cut, count));
    for (int32_t i = 0; i < count; ++i)
        CHECK(fabs(fabs(cut[2 * i]) - (cut[2 * i] < 50 ? 10 : 110)) < 1e-9, "corner %d at %g", (int)i, cut[2 * i]);
    free(cut);
    /* One edge with 25 mm: that side moves 25, the others 10; corners stay mitred (square). */
    const double mixed[4] = {25, 10, 10, 10};
    offset_case(square, 4, mixed, "square, 25 mm bottom", &cut, &count);
    CHECK(count == 4 && fabs(pz_polygon_signed_area(cut, count) - 120.0 * 135.0) < 1e-6, "%d corners, area %.3f",
          (int)count, pz_polygon_signed_area(cut, count));
    free(cut);
    /* No allowance: the cut line is the sew line. */
    const double zero[4] = {0, 0, 0, 0};
    REQUIRE_OK(pz_offset_polygon(square, 4, zero, &cut, &count, &ctx), ctx);
    CHECK(count == 4 && fabs(pz_polygon_signed_area(cut, count) - 100.0 * 100.0) < 1e-9, "0 mm: %d corners, area %.3f",
          (int)count, pz_polygon_signed_area(cut, count));
    free(cut);
    /* Zero-length and repeated points are tolerated. */
    const double repeated[10] = {0, 0, 100, 0, 100, 0, 100, 100, 0, 100};
    const double five[5] = {10, 10, 10, 10, 10};
    offset_case(repeated, 5, five, "square with a repeated point", NULL, NULL);
    const double line[6] = {0, 0, 1, 0, 2, 0};
    double *none = NULL;
    int32_t none_count = 0;
    CHECK(pz_offset_polygon(line, 2, five, &none, &none_count, &ctx) == PZ_ERR_DATA && !none, "two points: %s",
          ctx.error);
}

static void test_acute_and_slot(void)
{
    /* A 10-degree spike: the mitre would be 11 allowances long; it is cut off square. */
    double spike[6] = {0, 0, 300, 0, 0, 0};
    spike[4] = 300 * cos(10 * PI / 180);
    spike[5] = 300 * sin(10 * PI / 180);
    const double ten[8] = {10, 10, 10, 10, 10, 10, 10, 10};
    double *cut;
    int32_t count;
    offset_case(spike, 3, ten, "10-degree spike", &cut, &count);
    double reach = 0;
    for (int32_t i = 0; i < count; ++i)
        reach = fmax(reach, cut[2 * i]);
    CHECK(reach < 300 + 2 * 10 + 1e-9, "the spike's cut line reaches x = %.3f", reach);
    free(cut);
    /* A U with a 8 mm slot: the offsets of the slot's walls overlap and the cut line bridges it. */
    const double slot[16] = {0, 0, 100, 0, 100, 100, 54, 100, 54, 20, 46, 20, 46, 100, 0, 100};
    offset_case(slot, 8, ten, "slot", &cut, &count);
    int dips = 0;
    for (int32_t i = 0; i < count; ++i)
        dips += cut[2 * i + 1] < 105 && cut[2 * i] > 40 && cut[2 * i] < 60;
    CHECK(dips == 0 && count <= 8, "the cut line enters the slot (%d points, %d corners)", dips, (int)count);
    free(cut);
    /* A wide slot (40 mm): the cut line follows it in. */
    const double wide[16] = {0, 0, 100, 0, 100, 100, 70, 100, 70, 20, 30, 20, 30, 100, 0, 100};
    offset_case(wide, 8, ten, "wide slot", &cut, &count);
    double deepest = DBL_MAX;
    for (int32_t i = 0; i < count; ++i)
        if (cut[2 * i] > 35 && cut[2 * i] < 65)
            deepest = fmin(deepest, cut[2 * i + 1]);
    CHECK(fabs(deepest - 30) < 1e-9, "the cut line in the wide slot reaches y = %.3f (30 expected)", deepest);
    free(cut);
}

/* Star polygons with random radii: concave corners, short edges and overlapping offsets everywhere. */
static void test_random_stars(void)
{
    uint64_t state = 12345;
    int failures_before = 0;
    (void)failures_before;
    for (int trial = 0; trial < 60; ++trial) {
        int32_t n = 8 + trial % 40;
        double *points = malloc(2 * (size_t)n * sizeof(double)), *allowance = malloc((size_t)n * sizeof(double));
        REQUIRE(points && allowance, "out of memory");
        for (int32_t i = 0; i < n; ++i) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            double radius = 40 + 160 * (double)(state >> 11) / 9007199254740992.0;
            double angle = 2 * PI * i / n;
            points[2 * i] = radius * cos(angle);
            points[2 * i + 1] = radius * sin(angle);
            allowance[i] = trial % 3 == 0 ? 5 + 10 * (double)((state >> 20) % 3) : 10;
        }
        char what[64];
        snprintf(what, sizeof what, "star %d (%d points)", trial, (int)n);
        offset_case(points, n, allowance, what, NULL, NULL);
        free(points);
        free(allowance);
    }
}


static void test_bodice(void)
{
    fixture f = fixture_generated(PZ_SHAPE_BODICE, 3000, 1);
    pz_export_options options;
    pz_export_options_default(&options);
    options.hem_allowance_mm = 25;
    options.garment_name = "bodice";
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, f.panel_mirror, NULL, &pieces, &ctx), ctx);
    REQUIRE(pieces->piece_count == 4, "%d pieces", (int)pieces->piece_count);
    CHECK(strcmp(pieces->garment_name, "bodice") == 0 && strcmp(pieces->size_name, "base") == 0, "names %s %s",
          pieces->garment_name, pieces->size_name);
    check_piece_cuts(f.pattern, pieces, "bodice");
    notch_pair_stats pairs = check_notch_pairs(f.pattern, pieces, f.uv, options.notch_spacing_mm, "bodice");
    check_drawn_labels(f.pattern, pieces, "bodice");
    printf("bodice: %d seams, notch pairs differ by %.2e mm at most (ends at the corners within %.1e mm; the sides "
           "differ by %.3f mm: textile length mismatch)\n",
           (int)f.pattern->seam_count, pairs.interior, pairs.end_corner, pairs.end_mismatch);
    /* Seam edges carry 10 mm, open edges (neck, waist) 25 mm, and both kinds exist on every piece. */
    int32_t mirrored = 0, doubled = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        int32_t seam_edges = 0, hem_edges = 0;
        for (int32_t i = 0; i < piece->sew_count; ++i) {
            seam_edges += piece->sew_allowance[i] == 10;
            hem_edges += piece->sew_allowance[i] == 25;
        }
        CHECK(seam_edges > 0 && hem_edges > 0 && seam_edges + hem_edges == piece->sew_count,
              "%s: %d seam and %d hem edges of %d", piece->name, (int)seam_edges, (int)hem_edges,
              (int)piece->sew_count);
        mirrored += piece->mirrored;
        doubled += piece->cut_quantity == 2;
        if (piece->mirrored)
            CHECK(pieces->pieces[piece->mirror_piece].cut_quantity == 2 &&
                      pieces->pieces[piece->mirror_piece].mirror_piece == p,
                  "%s: its partner does not carry Cut 2", piece->name);
    }
    /* The halves' jagged seams (faces split by their centroids) differ by millimetres: not mirror images. */
    printf("bodice: %d mirrored pairs\n", (int)doubled);
    CHECK(mirrored == doubled, "mirror pairs: %d mirrored, %d cut twice", (int)mirrored, (int)doubled);
    pz_pieces_free(&pieces);
    CHECK(pieces == NULL, "free sets NULL");
    pz_pieces_free(&pieces);

    /* Without a mirror map nothing is paired. */
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        CHECK(pieces->pieces[p].cut_quantity == 1 && !pieces->pieces[p].mirrored, "paired without a map");
    pz_pieces_free(&pieces);

    /* Per-seam allowance file: seam between panels 0 and 1 gets 15 mm. */
    char path[512];
    test_temp_path(path, sizeof path, "allowances.txt");
    int32_t a = f.pattern->seams[0].panel_a, b = f.pattern->seams[0].panel_b;
    char text[128];
    snprintf(text, sizeof text, "# panel panel mm\n\n%d %d 15 # front\n", (int)b, (int)a);
    test_write_file(path, text, strlen(text));
    double *allowances = NULL;
    REQUIRE_OK(pz_export_read_allowances(path, f.pattern, &allowances, &ctx), ctx);
    CHECK(allowances[0] == 15, "seam 0 gets %g", allowances[0]);
    options.seam_allowances_mm = allowances;
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    int32_t fifteen = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        for (int32_t i = 0; i < pieces->pieces[p].sew_count; ++i)
            fifteen += pieces->pieces[p].sew_allowance[i] == 15;
    CHECK(fifteen >= 2 * (f.pattern->seams[0].pair_count - 1), "%d edges with 15 mm", (int)fifteen);
    check_piece_cuts(f.pattern, pieces, "bodice, seam 0 at 15 mm");
    pz_pieces_free(&pieces);
    free(allowances);
    options.seam_allowances_mm = NULL;

    struct { const char *text, *expect; } bad[] = {
        {"0 1\n", "line 1: expected"}, {"0 1 x\n", "'x' is not a number"}, {"0 1 -2\n", "negative allowance"},
        {"0 9 10\n", "panel ids must be"}, {"0 0 10\n", "no seam joins panels 0 and 0"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        test_write_file(path, bad[i].text, strlen(bad[i].text));
        CHECK(pz_export_read_allowances(path, f.pattern, &allowances, &ctx) == PZ_ERR_DATA && !allowances &&
                  strstr(ctx.error, bad[i].expect) && strstr(ctx.error, path),
              "case %zu: %s", i, ctx.error);
    }
    CHECK(pz_export_read_allowances("/nonexistent/a.txt", f.pattern, &allowances, &ctx) == PZ_ERR_OPEN, "%s",
          ctx.error);
    options.seam_allowance_mm = -1;
    CHECK(pz_pieces_build(f.pattern, f.uv, &options, NULL, NULL, &pieces, &ctx) == PZ_ERR_USAGE && !pieces, "%s",
          ctx.error);
    fixture_free(&f);
}

/* Three flat quadrilaterals: 0 and 1 mirror images (1 also moved and turned), 2 a different shape. */
static void test_mirrored_pairs(void)
{
    const double shape[4][2] = {{0, 0}, {100, 0}, {80, 150}, {0, 150}};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(12, 6, &mesh, &ctx), ctx);
    double angle = 0.3, c = cos(angle), s = sin(angle);
    for (int k = 0; k < 4; ++k) {
        double *a = &mesh->positions[3 * k], *b = &mesh->positions[3 * (4 + k)], *d = &mesh->positions[3 * (8 + k)];
        a[0] = shape[k][0];
        a[1] = shape[k][1];
        double x = -shape[k][0], y = shape[k][1];   /* mirrored, turned and moved */
        b[0] = 400 + c * x - s * y;
        b[1] = 50 + s * x + c * y;
        d[0] = 600 + shape[k][0] * (k == 2 ? 1.3 : 1);
        d[1] = shape[k][1];
    }
    const int32_t faces[18] = {0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 8, 9, 10, 8, 10, 11};
    memcpy(mesh->faces, faces, sizeof faces);
    mesh->unit_scale = 1;
    const int32_t face_panel[6] = {0, 0, 1, 1, 2, 2}, mirror[3] = {1, 0, 1};
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, face_panel, NULL, NULL, "quads", &pattern, &ctx), ctx);
    double uv[24];
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v) {
        uv[2 * v] = pattern->mesh->positions[3 * v];
        uv[2 * v + 1] = pattern->mesh->positions[3 * v + 1];
    }
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    const char *names[3] = {"front", NULL, ""};
    REQUIRE_OK(pz_pieces_build(pattern, uv, &options, mirror, names, &pieces, &ctx), ctx);
    const pz_piece *p = pieces->pieces;
    CHECK(p[0].cut_quantity == 2 && p[0].mirror_piece == 1 && !p[0].mirrored, "piece 0: %d %d %d",
          (int)p[0].cut_quantity, (int)p[0].mirror_piece, p[0].mirrored);
    CHECK(p[1].mirrored && p[1].mirror_piece == 0, "piece 1: mirrored %d of %d", p[1].mirrored, (int)p[1].mirror_piece);
    CHECK(p[2].cut_quantity == 1 && !p[2].mirrored && p[2].mirror_piece == -1, "piece 2 paired");
    CHECK(strcmp(p[0].name, "front") == 0 && strcmp(p[1].name, "panel_1") == 0 && strcmp(p[2].name, "panel_2") == 0,
          "names %s %s %s", p[0].name, p[1].name, p[2].name);
    /* The quadrilateral's cut line: 4 mitred corners (the 60-degree-ish top corner stays within the limit). */
    CHECK(p[0].cut_count == 4 && p[0].sew_count == 4, "cut %d sew %d", (int)p[0].cut_count, (int)p[0].sew_count);
    CHECK(fabs(p[0].sew_area_mm2 - 0.5 * (100 + 80) * 150) < 1e-6, "sew area %.3f", p[0].sew_area_mm2);
    /* Grainline: 60% of the height through the centroid, along +v. */
    CHECK(fabs(p[0].grain[1][1] - p[0].grain[0][1] - 90) < 1e-9, "grain length %.3f",
          p[0].grain[1][1] - p[0].grain[0][1]);
    /* Open edges only, no seams: no notches. */
    CHECK(p[0].notch_count == 0 && p[0].line_count == 0, "%d notches", (int)p[0].notch_count);
    pz_pieces_free(&pieces);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

/* A flat rectangle with a V dart from its top edge, as a pattern of one panel (mouth 20 or 60 mm wide). */
static void dart_case(double half_mouth, int expect_folded)
{
    pz_pattern *pattern = calloc(1, sizeof *pattern);
    REQUIRE(pattern, "out of memory");
    REQUIRE_OK(pz_mesh_create(7, 5, &pattern->mesh, &ctx), ctx);
    const double xy[7][2] = {{0, 0}, {200, 0}, {200, 100}, {100 + half_mouth, 100}, {100, 40}, {100 - half_mouth, 100},
                             {0, 100}};
    const int32_t faces[15] = {0, 1, 4, 1, 2, 3, 1, 3, 4, 0, 4, 5, 0, 5, 6};
    double uv[14];
    for (int v = 0; v < 7; ++v) {
        pattern->mesh->positions[3 * v] = uv[2 * v] = xy[v][0];
        pattern->mesh->positions[3 * v + 1] = uv[2 * v + 1] = xy[v][1];
    }
    memcpy(pattern->mesh->faces, faces, sizeof faces);
    pattern->mesh->unit_scale = 1;
    pattern->panel_count = 1;
    pattern->face_panel = calloc(5, sizeof(int32_t));
    pattern->vertex_origin = malloc(7 * sizeof(int32_t));
    pattern->darts = calloc(1, sizeof(pz_dart));
    REQUIRE(pattern->face_panel && pattern->vertex_origin && pattern->darts, "out of memory");
    for (int v = 0; v < 7; ++v)
        pattern->vertex_origin[v] = v;
    pattern->dart_count = 1;
    pattern->darts[0] = (pz_dart){0, 4, 1, malloc(sizeof(int32_t)), malloc(sizeof(int32_t))};
    REQUIRE(pattern->darts[0].leg_a && pattern->darts[0].leg_b, "out of memory");
    pattern->darts[0].leg_a[0] = 5;
    pattern->darts[0].leg_b[0] = 3;
    pz_export_options options;
    pz_export_options_default(&options);
    options.hem_allowance_mm = 15;
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(pattern, uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    const pz_piece *piece = &pieces->pieces[0];
    char what[64];
    snprintf(what, sizeof what, "dart %.0f mm wide", 2 * half_mouth);
    check_piece_cuts(pattern, pieces, what);
    /* Folded: the cut line runs straight across the mouth, 15 mm (the hem's) above it; cut out: it dips in. */
    const double in_mouth[2] = {100, 95};
    CHECK(point_in_polygon(in_mouth, piece->cut, piece->cut_count) == expect_folded, "%s: folded %d expected", what,
          expect_folded);
    const double above[2] = {100, 115};
    double nearest = DBL_MAX, t;
    for (int32_t i = 0; i < piece->cut_count; ++i)
        nearest = fmin(nearest, segment_distance(above, &piece->cut[2 * i],
                                                 &piece->cut[2 * ((i + 1) % piece->cut_count)], &t));
    CHECK((nearest < 1e-6) == expect_folded, "%s: the cut line passes %.3f mm from (100, 115)", what, nearest);
    /* The legs carry the seam allowance, the other edges the hem's. */
    int32_t seam_edges = 0;
    for (int32_t i = 0; i < piece->sew_count; ++i)
        seam_edges += piece->sew_allowance[i] == 10;
    CHECK(seam_edges == 2, "%s: %d edges with the seam allowance", what, (int)seam_edges);
    /* Notches D1 at both mouth ends, from the cut line inward; legs, fold line and a tip cross drawn. */
    CHECK(piece->notch_count == 2 && strcmp(piece->notches[0].label, "D1") == 0 &&
              strcmp(piece->notches[1].label, "D1") == 0 && piece->notches[0].dart == 0 && piece->notches[0].seam == -1,
          "%s: %d notches", what, (int)piece->notch_count);
    for (int32_t i = 0; i < piece->notch_count; ++i)
        CHECK(piece->notches[i].depth_mm > 0 && piece->notches[i].depth_mm <= 5 &&
                  point_in_polygon(piece->notches[i].position, piece->cut, piece->cut_count),
              "%s: notch %d depth %.3f", what, (int)i, piece->notches[i].depth_mm);
    CHECK(piece->line_count == 5, "%s: %d internal lines", what, (int)piece->line_count);
    pz_pieces_free(&pieces);
    pz_pattern_free(&pattern);
}

/*
 * Labels on a "Cut 2 mirrored" pair: three flat strips side by side, the centre one (panel 0) its own mirror
 * image, the right (1) and left (2) mirror images of each other, so 2 is hidden and 1 is cut twice. The seam
 * 0-2 reaches the hidden piece: its labels must be those of its twin 0-1, so the mirrored cut of panel 1 carries
 * what panel 0's left edge carries, notch for notch at mirror-image places (the same height).
 */
static void test_mirrored_labels(void)
{
    const double columns[4] = {-150, -50, 50, 150};
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_create(16, 18, &mesh, &ctx), ctx);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double *x = &mesh->positions[3 * (4 * c + r)];
            x[0] = columns[c], x[1] = 130.0 * r, x[2] = 0;
        }
    int32_t face_panel[18], f = 0;
    const int32_t strip_panel[3] = {2, 0, 1};
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r, f += 2) {
            int32_t a = 4 * c + r, b = 4 * (c + 1) + r;
            const int32_t two[6] = {a, b, b + 1, a, b + 1, a + 1};
            memcpy(&mesh->faces[3 * f], two, sizeof two);
            face_panel[f] = face_panel[f + 1] = strip_panel[c];
        }
    mesh->unit_scale = 1;
    pz_pattern *pattern = NULL;
    REQUIRE_OK(pz_pattern_build(mesh, face_panel, NULL, NULL, "strips", &pattern, &ctx), ctx);
    double *uv = malloc(2 * (size_t)pattern->mesh->vertex_count * sizeof(double));
    REQUIRE(uv, "out of memory");
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v)
        uv[2 * v] = pattern->mesh->positions[3 * v], uv[2 * v + 1] = pattern->mesh->positions[3 * v + 1];
    const int32_t mirror[3] = {0, 2, 1};
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(pattern, uv, &options, mirror, NULL, &pieces, &ctx), ctx);
    const pz_piece *centre = &pieces->pieces[0], *right = &pieces->pieces[1];
    REQUIRE(right->cut_quantity == 2 && pieces->pieces[2].mirrored && pattern->seam_count == 2,
            "pair not kept (%d, %d) or %d seams", (int)right->cut_quantity, pieces->pieces[2].mirrored,
            (int)pattern->seam_count);
    check_notch_pairs(pattern, pieces, uv, options.notch_spacing_mm, "strips");
    CHECK(check_drawn_labels(pattern, pieces, "strips") == 1, "seam 0-2 does not reach the hidden piece");
    int matched = 0;
    for (int32_t i = 0; i < right->notch_count; ++i)
        for (int32_t j = 0; j < centre->notch_count; ++j)
            if (centre->notches[j].position[0] < 0 && strcmp(centre->notches[j].label, right->notches[i].label) == 0) {
                ++matched;
                CHECK(fabs(centre->notches[j].position[1] - right->notches[i].position[1]) < 1e-9,
                      "%s at height %.3f on the centre, %.3f on the mirrored cut", right->notches[i].label,
                      centre->notches[j].position[1], right->notches[i].position[1]);
            }
    printf("strips: %d notches on the cut-2 piece, %d of them matched on the centre's left edge (%s .. %s)\n",
           (int)right->notch_count, matched, right->notches[0].label, right->notches[right->notch_count - 1].label);
    CHECK(matched == right->notch_count && right->notch_count == 5, "%d of %d matched", matched,
          (int)right->notch_count);
    pz_pieces_free(&pieces);
    free(uv);
    pz_pattern_free(&pattern);
    pz_mesh_free(&mesh);
}

static void test_darts(void)
{
    dart_case(10, 1);   /* 20 mm mouth: folded (limit: 4 x 15 mm) */
    dart_case(35, 0);   /* 70 mm: cut out */
}

static void test_labels(void)
{
    char label[16];
    pz_notch_label(0, 0, label);
    CHECK(strcmp(label, "A1") == 0, "%s", label);
    pz_notch_label(25, 11, label);
    CHECK(strcmp(label, "Z12") == 0, "%s", label);
    pz_notch_label(26, 0, label);
    CHECK(strcmp(label, "AA1") == 0, "%s", label);
    pz_notch_label(26 + 26 * 26, 2, label);   /* after ZZ */
    CHECK(strcmp(label, "AAA3") == 0, "%s", label);
}

/* ---------------------------------------------------------------- shared garments */

static void test_shared(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("shared garments (no ../shared/data)");
        return;
    }
    int built = 0;
    for (size_t g = 0; g < sizeof fixture_garments / sizeof fixture_garments[0]; ++g) {
        char path[1024];
        snprintf(path, sizeof path, "%s/garments/%s", dir, fixture_garments[g].file);
        fixture f;
        if (!fixture_shared(&f, path, fixture_garments[g].use_uv))
            continue;
        ++built;
        pz_export_options options;
        pz_export_options_default(&options);
        pz_pieces *pieces = NULL;
        double start = pz_seconds();
        REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, NULL, NULL, &pieces, &ctx), ctx);
        double ms = 1000 * (pz_seconds() - start);
        check_piece_cuts(f.pattern, pieces, fixture_garments[g].file);
        int32_t notches = 0, cut_points = 0;
        for (int32_t p = 0; p < pieces->piece_count; ++p) {
            notches += pieces->pieces[p].notch_count;
            cut_points += pieces->pieces[p].cut_count;
        }
        notch_pair_stats pairs = check_notch_pairs(f.pattern, pieces, f.uv, options.notch_spacing_mm,
                                                   fixture_garments[g].file);
        printf("%-26s %2d pieces, %2d seams, %d darts, %4d notches, %5d cut points, pairs %.1e mm (ends at the "
               "corners within %.1e mm, sides differ by %.2f mm), %.1f ms\n",
               fixture_garments[g].file, (int)pieces->piece_count, (int)f.pattern->seam_count,
               (int)f.pattern->dart_count, (int)notches, (int)cut_points, pairs.interior, pairs.end_corner,
               pairs.end_mismatch, ms);
        pz_pieces_free(&pieces);
        fixture_free(&f);
    }
    int listed = (int)(sizeof fixture_garments / sizeof fixture_garments[0]);
    CHECK(built == listed, "only %d of the %d shared garments could be built", built, listed);
}

int main(void)
{
    test_temp_dir_create("pz_export_pieces");
    test_square();
    test_acute_and_slot();
    test_random_stars();
    test_labels();
    test_mirrored_pairs();
    test_mirrored_labels();
    test_darts();
    test_bodice();
    test_shared();
    test_remove_tree(test_temp_dir);
    return test_finish();
}
