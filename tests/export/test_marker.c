/*
 * tests/export/test_marker.c -- the marker (pz_marker_build) and marker.svg:
 *  - 20 rectangles and L-shapes, some cut twice: the properties of
 *    marker_checks.h (every copy placed once, rotations 0 or 180 only,
 *    inside the fabric, no two cut lines closer than the gap, Cut-2 copies
 *    mirror images, length and efficiency recomputed), the
 *    same result twice (determinism);
 *  - L-shapes nest into each other's notch: efficiency above what their
 *    bounding boxes allow on a shelf;
 *  - a Cut-2 pair that cannot sit beside a tall piece is split, its copies
 *    one above the other; a marker as short as its tallest piece ends the
 *    search;
 *  - concave star-like pieces of random sizes, some cut twice, on short
 *    markers where the column fill runs too: the marker properties;
 *  - a piece wider than the fabric, or with a NaN coordinate: PZ_ERR_DATA
 *    naming it;
 *  - report.json's marker object and marker.svg (one group per placement,
 *    width in mm, rsvg-convert renders it when installed);
 *  - every garment of ../shared/data/garments (panels from its UVs where it
 *    has them, else one panel), LSCM-flattened, pieces from pz_pieces_build:
 *    the marker properties above, and every writer of this part (marker.svg,
 *    pattern.pdf, pattern-tiled.pdf, garment.glb, report.html) succeeds;
 *    pattern-tiled.pdf's layout has the properties of tiled_checks.h and at
 *    most twice the pages the cut lines' area could fill (A4 tiles advance
 *    180 x 267 mm; 1.16-1.78x today) (skipped without the shared data).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "fixture_export_b.h"
#include "marker_checks.h"
#include "tiled_checks.h"
#include "io/io.h"
#include "readers.h"

#include <stdio.h>
#include <unistd.h>

static pz_ctx ctx;

/* ------------------------------------------------------------------ cases */

static pz_pieces *twenty_pieces(void)
{
    pz_pieces *pieces = fixture_pieces_alloc(20);
    for (int32_t p = 0; p < 20; ++p) {
        char name[32];
        snprintf(name, sizeof name, "piece_%d", (int)p);
        double w = 120 + 37 * (p % 7), h = 200 + 53 * (p % 5);
        fixture_piece_box(&pieces->pieces[p], p, name, w, h, p % 3 == 0);
        if (p % 4 == 1)
            pieces->pieces[p].cut_quantity = 2;
    }
    return pieces;
}

static void test_twenty(void)
{
    pz_pieces *pieces = twenty_pieces();
    pz_export_options options;
    pz_export_options_default(&options);
    options.fabric_width_mm = 1500;
    options.gap_mm = 5;
    pz_marker *marker = NULL, *again = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    printf("20 pieces (%d placements): length %.1f mm, efficiency %.3f, %.1f ms\n", (int)marker->placement_count,
           marker->length_mm, marker->efficiency, marker->ms);
    /* 0.797 with the previous search (one walk, 150 passes, no column fill), 0.815 now. */
    CHECK(marker->efficiency > 0.8, "efficiency %.3f", marker->efficiency);
    REQUIRE_OK(pz_marker_build(pieces, &options, &again, &ctx), ctx);
    CHECK(again->placement_count == marker->placement_count &&
              memcmp(again->placements, marker->placements,
                     (size_t)marker->placement_count * sizeof *marker->placements) == 0,
          "two builds differ");

    /* A narrow fabric and a wide gap: same properties. */
    pz_marker *narrow = NULL;
    options.fabric_width_mm = 600;
    options.gap_mm = 12;
    REQUIRE_OK(pz_marker_build(pieces, &options, &narrow, &ctx), ctx);
    check_marker(pieces, narrow, &options);
    CHECK(narrow->length_mm > marker->length_mm, "narrow %g, wide %g", narrow->length_mm, marker->length_mm);

    /* report.json */
    cJSON *json = pz_marker_report_json(marker);
    REQUIRE(json, "no json");
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(json, "length_mm")) &&
              fabs(cJSON_GetObjectItem(json, "efficiency")->valuedouble - marker->efficiency) < 1e-4 &&
              cJSON_GetObjectItem(json, "pieces")->valueint == marker->placement_count &&
              cJSON_GetObjectItem(json, "fabric_width_mm")->valuedouble == 1500,
          "marker json");
    cJSON_Delete(json);

    /* marker.svg: one group per placement, sizes in mm; rendered by rsvg-convert when installed. */
    char dir[] = "/tmp/pz_marker_XXXXXX";
    REQUIRE(mkdtemp(dir), "mkdtemp");
    char path[256], command[600];
    snprintf(path, sizeof path, "%s/marker.svg", dir);
    FILE *file = fopen(path, "w");
    REQUIRE(file, "cannot write %s", path);
    pz_export_options svg_options;
    pz_export_options_default(&svg_options);
    pz_export_inputs inputs = {.pieces = pieces, .marker = marker, .options = &svg_options};
    REQUIRE_OK(pz_export_write_marker_svg(file, &inputs, "marker.svg", &ctx), ctx);
    long size = ftell(file);
    fclose(file);
    char *text = malloc((size_t)size + 1);
    file = fopen(path, "r");
    REQUIRE(text && file && fread(text, 1, (size_t)size, file) == (size_t)size, "read back");
    fclose(file);
    text[size] = 0;
    int groups = 0;
    for (const char *at = text; (at = strstr(at, "<g class=\"piece\"")); ++at)
        ++groups;
    CHECK(groups == marker->placement_count, "%d groups", groups);
    CHECK(strstr(text, "width=\"1500.00mm\"") != NULL, "width in mm");
    CHECK(strstr(text, "efficiency") != NULL, "efficiency text");
    free(text);
    if (reader_available("command -v rsvg-convert", "rsvg-convert")) {
        snprintf(command, sizeof command, "rsvg-convert -o %s/marker.png %s", dir, path);
        CHECK(system(command) == 0, "rsvg-convert failed on %s", path);
    }
    snprintf(command, sizeof command, "rm -rf %s", dir);
    CHECK(system(command) == 0, "cleanup");

    pz_marker_free(&narrow);
    pz_marker_free(&again);
    pz_marker_free(&marker);
    CHECK(marker == NULL, "free sets NULL");
    fixture_pieces_free(pieces);
}

/* Ls nest: the marker is shorter than their bounding boxes laid on shelves would need. */
static void test_nesting(void)
{
    pz_pieces *pieces = fixture_pieces_alloc(8);
    double box_area = 0.0;
    for (int32_t p = 0; p < 8; ++p) {
        fixture_piece_box(&pieces->pieces[p], p, "ell", 400, 400, 1);
        box_area += (pieces->pieces[p].bbox_max[0] - pieces->pieces[p].bbox_min[0]) *
                    (pieces->pieces[p].bbox_max[1] - pieces->pieces[p].bbox_min[1]);
    }
    pz_export_options options;
    pz_export_options_default(&options);
    options.fabric_width_mm = 900;
    pz_marker *marker = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    int rotated = 0;
    for (int32_t i = 0; i < marker->placement_count; ++i)
        rotated += marker->placements[i].rotation_deg == 180;
    printf("8 L-shapes on 900 mm: length %.1f mm (bounding boxes alone need %.1f), efficiency %.3f, %d rotated\n",
           marker->length_mm, box_area / 900.0, marker->efficiency, rotated);
    CHECK(marker->length_mm < box_area / 900.0, "no nesting: %g", marker->length_mm);
    CHECK(rotated > 0, "never used 180 degrees");
    pz_marker_free(&marker);
    fixture_pieces_free(pieces);
}

/* A Cut-2 piece whose pair leaves no room beside a tall piece: its copies go one above the other beside it (the
 * search splits the pair), a marker near the tall piece's length; two pieces side by side at their height stop the
 * search at once (no marker can be shorter than its tallest piece). */
static void test_split_pairs(void)
{
    pz_pieces *pieces = fixture_pieces_alloc(2);
    fixture_piece_box(&pieces->pieces[0], 0, "pocket", 440, 300, 0); /* cut lines 460 x 320 */
    pieces->pieces[0].cut_quantity = 2;
    fixture_piece_box(&pieces->pieces[1], 1, "back", 480, 600, 0); /* 500 x 620 */
    pz_export_options options;
    pz_export_options_default(&options);
    options.fabric_width_mm = 1000;
    options.gap_mm = 5;
    pz_marker *marker = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    /* Paired: 460 + 5 + 460 beside 500 does not fit 1000, so 620 + 5 + 320 = 945 mm; split: 645 mm. */
    printf("a pair beside a tall piece: length %.1f mm, efficiency %.3f, %d passes\n", marker->length_mm,
           marker->efficiency, (int)marker->passes);
    CHECK(marker->length_mm < 660, "the pair was not split: %.1f mm", marker->length_mm);
    pz_marker_free(&marker);

    fixture_pieces_free(pieces);
    pieces = fixture_pieces_alloc(2);
    fixture_piece_box(&pieces->pieces[0], 0, "front", 440, 600, 0);
    fixture_piece_box(&pieces->pieces[1], 1, "back", 480, 600, 0);
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    CHECK(marker->length_mm < 620 + 2.25 + 1e-9, "side by side: %.1f mm", marker->length_mm);
    CHECK(fabs(marker->shortest_possible_mm - 620) < 1e-6, "shortest possible %.3f mm", marker->shortest_possible_mm);
    CHECK(marker->efficiency <= marker->efficiency_bound + 1e-12 &&
              marker->efficiency > marker->efficiency_bound * 620 / (620 + 2.25 + 1e-6),
          "efficiency %.4f, bound %.4f", marker->efficiency, marker->efficiency_bound);
    CHECK(marker->passes <= 3, "%d passes after the shortest possible marker", (int)marker->passes);
    pz_marker_free(&marker);
    fixture_pieces_free(pieces);
}

/* A jagged star-like piece: n corners alternating between the outer radii rx, ry and a random fraction of them. */
static void star_piece(pz_piece *piece, int32_t index, double rx, double ry, int32_t n, uint64_t *state)
{
    double sew[2 * 24];
    for (int32_t i = 0; i < n; ++i) {
        *state = *state * 6364136223846793005ull + 1442695040888963407ull; /* LCG: fixed sequence */
        double inner = 0.55 + 0.4 * (double)(*state >> 40) / (double)(1ull << 24);
        double r = i % 2 ? inner : 1.0, angle = 2 * 3.14159265358979323846 * i / n;
        sew[2 * i] = rx * r * cos(angle), sew[2 * i + 1] = ry * r * sin(angle);
    }
    char name[32];
    snprintf(name, sizeof name, "star_%d", (int)index);
    fixture_piece_polygon(piece, index, name, sew, n, 3.0);
}

/*
 * Concave pieces of random sizes (a fixed sequence), some cut twice, on short markers (at most two fabric widths
 * long, where the column fill runs after the bottom-left fill): every marker property. The column fill's marker
 * is the one kept on instance 6 (and on 9 of the first 60 instances: all 60 passed these checks when written).
 */
static void test_random_shapes(void)
{
    uint64_t state = 12345;
    for (int instance = 0; instance < 7; ++instance) {
        int32_t count = 5 + instance % 4;
        pz_pieces *pieces = fixture_pieces_alloc(count);
        for (int32_t p = 0; p < count; ++p) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            double rx = 60 + (double)(state >> 56), ry = 100 + (double)((state >> 44) & 255);
            star_piece(&pieces->pieces[p], p, rx, ry, 10 + 2 * (int32_t)(p % 4), &state);
            if (p % 3 == 1)
                pieces->pieces[p].cut_quantity = 2;
        }
        pz_export_options options;
        pz_export_options_default(&options);
        options.fabric_width_mm = instance % 2 ? 1000 : 1500;
        options.gap_mm = 5;
        pz_marker *marker = NULL;
        REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
        check_marker(pieces, marker, &options);
        printf("random shapes %d: %d placements on %.0f mm, length %.1f mm, efficiency %.3f, %d passes\n", instance,
               (int)marker->placement_count, options.fabric_width_mm, marker->length_mm, marker->efficiency,
               (int)marker->passes);
        pz_marker_free(&marker);
        fixture_pieces_free(pieces);
    }
}

static void test_too_wide(void)
{
    pz_pieces *pieces = fixture_pieces_alloc(2);
    fixture_piece_box(&pieces->pieces[0], 0, "small", 100, 100, 0);
    fixture_piece_box(&pieces->pieces[1], 1, "wide_one", 1700, 100, 0);
    pz_export_options options;
    pz_export_options_default(&options);
    options.fabric_width_mm = 1500;
    /* A piece wider than the fabric cannot be cut from it with the grain kept: it is left out and listed,
     * the rest is nested as usual. */
    pz_marker *marker = NULL;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    CHECK(marker->unplaced_count == 1 && marker->unplaced[0] == 1, "unplaced: %d", (int)marker->unplaced_count);
    CHECK(marker->placement_count == 1 && marker->placements[0].piece == 0, "placements: %d",
          (int)marker->placement_count);
    cJSON *json = pz_marker_report_json(marker);
    cJSON *unplaced = json ? cJSON_GetObjectItem(json, "unplaced") : NULL;
    CHECK(unplaced && cJSON_GetArraySize(unplaced) == 1 && cJSON_GetArrayItem(unplaced, 0)->valueint == 1,
          "report.json marker.unplaced");
    cJSON_Delete(json);
    pz_marker_free(&marker);
    /* Coordinates that cannot be rasterized. */
    marker = (pz_marker *)&options; /* must come back NULL */
    pieces->pieces[0].cut[3] = NAN;
    CHECK(pz_marker_build(pieces, &options, &marker, &ctx) == PZ_ERR_DATA && strstr(ctx.error, "small") && !marker,
          "NaN: %s", ctx.error);
    /* A Cut-2 piece too wide as a pair but not alone: the copies go one above the other. */
    fixture_pieces_free(pieces);
    pieces = fixture_pieces_alloc(1);
    fixture_piece_box(&pieces->pieces[0], 0, "half", 900, 300, 0);
    pieces->pieces[0].cut_quantity = 2;
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    CHECK(marker->length_mm > 600, "length %g", marker->length_mm);
    pz_marker_free(&marker);
    fixture_pieces_free(pieces);
}

/* One shared garment: pattern, pieces, marker, and every writer of this part. */
static void check_garment(const char *dir, const char *file)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/garments/%s", dir, file);
    pz_mesh *mesh = NULL;
    REQUIRE_OK(pz_mesh_read(path, &mesh, &ctx), ctx);
    pz_mesh_to_mm(mesh, PZ_UNITS_AUTO, NULL);
    int32_t *face_panel = calloc((size_t)mesh->face_count, sizeof(int32_t)), panel_count = 1;
    uint8_t *extra = NULL;
    REQUIRE(face_panel, "out of memory");
    if (mesh->corner_uvs)
        REQUIRE_OK(pz_pattern_panels_from_uv(mesh, face_panel, &panel_count, &extra, &ctx), ctx);
    pz_pattern *pattern = NULL;
    if (pz_pattern_build(mesh, face_panel, extra, NULL, path, &pattern, &ctx) != PZ_OK) {
        CHECK(0, "%s: no pattern: %s", file, ctx.error);
        free(extra), free(face_panel), pz_mesh_free(&mesh);
        return;
    }
    double *uv = malloc((size_t)pattern->mesh->vertex_count * 2 * sizeof(double));
    REQUIRE(uv, "out of memory");
    REQUIRE_OK(pz_param_lscm_pattern(pattern, NULL, uv, &ctx), ctx);
    pz_metrics *metrics = NULL;
    REQUIRE_OK(pz_metrics_compute(pattern, uv, 0, NULL, &metrics, &ctx), ctx);
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(pattern, uv, &options, NULL, NULL, &pieces, &ctx), ctx);
    pz_marker *marker = NULL;
    double widest = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        widest = fmax(widest, pieces->pieces[p].bbox_max[0] - pieces->pieces[p].bbox_min[0]);
    if (widest > options.fabric_width_mm) {
        /* One panel for a whole garment can be wider than the fabric: left out, then laid on a wider one. */
        REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
        CHECK(marker->unplaced_count >= 1, "%s: the wide piece was placed", file);
        pz_marker_free(&marker);
        options.fabric_width_mm = ceil(widest) + 100;
    }
    REQUIRE_OK(pz_marker_build(pieces, &options, &marker, &ctx), ctx);
    check_marker(pieces, marker, &options);
    printf("%s: %d pieces, marker %.1f mm, efficiency %.3f, %.1f ms\n", file, (int)pieces->piece_count,
           marker->length_mm, marker->efficiency, marker->ms);
    cJSON *report = cJSON_CreateObject();
    cJSON_AddItemToObject(report, "marker", pz_marker_report_json(marker));
    pz_export_inputs inputs = {.garment = mesh, .pattern = pattern, .uv = uv, .metrics = metrics, .pieces = pieces,
                               .marker = marker, .options = &options, .report = report};
    pz_export_writer writers[5] = {pz_export_write_marker_svg, pz_export_write_pdf, pz_export_write_pdf_tiled,
                                   pz_export_write_glb, pz_export_write_report_html};
    for (int w = 0; w < 5; ++w) {
        FILE *sink = tmpfile();
        REQUIRE(sink, "tmpfile");
        CHECK(writers[w](sink, &inputs, file, &ctx) == PZ_OK && ftell(sink) > 100, "%s: writer %d: %s", file, w,
              ctx.error);
        fclose(sink);
    }
    cJSON_Delete(report);
    /* pattern-tiled.pdf's layout: its properties, and its pages against the fewest the cut lines could fill. */
    int32_t pages = check_tiled_layout(pieces, "a4", file);
    double area = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        area += pieces->pieces[p].mirrored ? 0 : pieces->pieces[p].area_mm2;
    double bound = ceil(area / (180.0 * 267.0));
    printf("%s: pattern-tiled.pdf %d pages, area bound %.0f (%.2fx)\n", file, (int)pages, bound, pages / bound);
    CHECK(pages <= 2 * bound + 1, "%s: pattern-tiled.pdf has %d pages, more than twice the %.0f its cut lines could "
          "fill", file, (int)pages, bound);
    pz_marker_free(&marker);
    pz_pieces_free(&pieces);
    pz_metrics_free(&metrics);
    free(uv);
    pz_pattern_free(&pattern);
    free(extra);
    free(face_panel);
    pz_mesh_free(&mesh);
}

static void test_garments(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("garments (no ../shared/data)");
        return;
    }
    const char *files[] = {"diffavatar-tshirt.obj", "diffavatar-shirt.obj", "parafashion-skirt.obj",
                           "parafashion-dress.ply", "parafashion-leggings.ply", "parafashion-shirt.obj",
                           "parafashion-wetsuit.obj", "shirtfront-panel.obj"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i)
        check_garment(dir, files[i]);
}

int main(void)
{
    ctx.quiet = 1;
    test_twenty();
    test_garments();
    test_nesting();
    test_split_pairs();
    test_random_shapes();
    test_too_wide();
    return test_finish();
}
