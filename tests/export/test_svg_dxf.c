/*
 * tests/export/test_svg_dxf.c -- pattern.svg and pattern.dxf, read back by
 * real readers.
 *
 *  - The sheet layout: drawn pieces' cut boxes do not overlap, lie on the
 *    sheet and below the reserved band; mirrored pieces are left out.
 *  - pattern.svg: width/height in mm with a matching viewBox, one <g> per
 *    drawn piece with separate cut and sew paths, notches, grainline, texts
 *    (escaped), the 10 cm scale box; rsvg-convert renders it, and at 1 px/mm
 *    (--dpi-x 25.4) the image is as large as the sheet.
 *  - pattern.dxf (normal and --dxf-strict): /usr/bin/python3 with ezdxf
 *    (tests/export/check_dxf.py) reads it, audit() finds no errors, every
 *    piece is a block inserted once whose closed layer-1 polyline has our cut
 *    vertex count and perimeter, with the sew line, notches, grain line,
 *    dart lines on their layers. Strict: no TABLES section, 7-bit ASCII only;
 *    normal: non-ASCII text as \U+XXXX; pieces of the same name get distinct
 *    block names.
 * Readers that are not installed skip their part (the test exits 77), which
 * fails the test when CI=true (tests/export/readers.h).
 * The skirt of ../shared/data (darts) is written too (a skipped part without
 * the data).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "export/export.h"
#include "export_fixtures.h"
#include "piece_checks.h"
#include "readers.h"
#include "generate/generate.h"

static pz_ctx ctx;

static int count_of(const char *text, const char *needle)
{
    int count = 0;
    for (const char *at = text; (at = strstr(at, needle)); at += strlen(needle))
        ++count;
    return count;
}

/* A written file of the scratch directory, NUL-terminated (free it). */
static char *read_output(const char *file_name)
{
    char path[512];
    size_t size = 0;
    char *text = (char *)test_read_file(test_temp_path(path, sizeof path, file_name), &size);
    REQUIRE(text, "cannot read %s", path);
    text[size] = '\0';
    return text;
}

/* Runs a writer into the scratch directory; returns the file's text (free it), its path and size. */
static char *write_file(const char *file_name, pz_export_writer writer, const pz_export_inputs *inputs,
                        char *path, size_t *size)
{
    test_temp_path(path, 512, file_name);
    FILE *file = fopen(path, "w");
    REQUIRE(file, "cannot create %s", path);
    REQUIRE_OK(writer(file, inputs, file_name, &ctx), ctx);
    REQUIRE(fclose(file) == 0, "close %s", path);
    char *text = read_output(file_name);
    *size = strlen(text);
    return text;
}

static int32_t drawn_count(const pz_pieces *pieces)
{
    int32_t drawn = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        drawn += !pieces->pieces[p].mirrored;
    return drawn;
}

/* ---------------------------------------------------------------- layout */

static void check_layout(const pz_pieces *pieces, double gap, double band)
{
    double *offsets = malloc(2 * (size_t)pieces->piece_count * sizeof(double)), size[2];
    REQUIRE(offsets, "out of memory");
    pz_pieces_sheet_layout(pieces, gap, band, offsets, size);
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *a = &pieces->pieces[p];
        if (a->mirrored)
            continue;
        double lo[2] = {a->bbox_min[0] + offsets[2 * p], a->bbox_min[1] + offsets[2 * p + 1]};
        double hi[2] = {a->bbox_max[0] + offsets[2 * p], a->bbox_max[1] + offsets[2 * p + 1]};
        CHECK(lo[0] >= gap - 1e-9 && lo[1] >= gap - 1e-9 && hi[0] <= size[0] - gap + 1e-9 &&
                  hi[1] <= size[1] - band - gap + 1e-9,
              "piece %d off the sheet: [%g %g]-[%g %g] on %g x %g", (int)p, lo[0], lo[1], hi[0], hi[1], size[0],
              size[1]);
        for (int32_t q = p + 1; q < pieces->piece_count; ++q) {
            const pz_piece *b = &pieces->pieces[q];
            if (b->mirrored)
                continue;
            double blo[2] = {b->bbox_min[0] + offsets[2 * q], b->bbox_min[1] + offsets[2 * q + 1]};
            double bhi[2] = {b->bbox_max[0] + offsets[2 * q], b->bbox_max[1] + offsets[2 * q + 1]};
            int apart = blo[0] >= hi[0] + gap - 1e-9 || lo[0] >= bhi[0] + gap - 1e-9 ||
                        blo[1] >= hi[1] + gap - 1e-9 || lo[1] >= bhi[1] + gap - 1e-9;
            CHECK(apart, "pieces %d and %d overlap on the sheet", (int)p, (int)q);
        }
    }
    free(offsets);
}

/* ---------------------------------------------------------------- svg */

static void check_svg(const pz_export_inputs *inputs, const char *tag)
{
    const pz_pieces *pieces = inputs->pieces;
    char path[512], file_name[64];
    size_t size = 0;
    snprintf(file_name, sizeof file_name, "%s.svg", tag);
    char *svg = write_file(file_name, pz_export_write_svg, inputs, path, &size);
    double width = 0, height = 0, box[4] = {0, 0, 0, 0};
    const char *at = strstr(svg, "<svg ");
    REQUIRE(at && sscanf(strstr(at, "width=\""), "width=\"%lfmm\" height=\"%lfmm\"", &width, &height) == 2,
            "%s: no width/height in mm", tag);
    REQUIRE(sscanf(strstr(at, "viewBox=\""), "viewBox=\"%lf %lf %lf %lf\"", &box[0], &box[1], &box[2], &box[3]) == 4,
            "%s: no viewBox", tag);
    CHECK(box[0] == 0 && box[1] == 0 && fabs(box[2] - width) < 1e-3 && fabs(box[3] - height) < 1e-3,
          "%s: viewBox %g %g %g %g for %g x %g mm", tag, box[0], box[1], box[2], box[3], width, height);
    int32_t drawn = drawn_count(pieces);
    CHECK(count_of(svg, "class=\"piece\"") == drawn && count_of(svg, "class=\"cut\"") == drawn &&
              count_of(svg, "class=\"sew\"") == drawn && count_of(svg, "class=\"grainline\"") == drawn,
          "%s: %d pieces drawn: %d groups, %d cut, %d sew paths", tag, (int)drawn, count_of(svg, "class=\"piece\""),
          count_of(svg, "class=\"cut\""), count_of(svg, "class=\"sew\""));
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        char id[48];
        snprintf(id, sizeof id, "<g id=\"panel_%d\"", (int)pieces->pieces[p].panel);
        CHECK((strstr(svg, id) != NULL) == !pieces->pieces[p].mirrored, "%s: group %s", tag, id);
    }
    int32_t labels = 0, doubled = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored) {
            labels += distinct_notches(&pieces->pieces[p]);
            doubled += pieces->pieces[p].cut_quantity == 2;
            /* Every notch's own label is shown (alone, or joined with those at the same place). */
            for (int32_t i = 0; i < pieces->pieces[p].notch_count; ++i) {
                char shown[40];
                snprintf(shown, sizeof shown, "%s<", pieces->pieces[p].notches[i].label);
                char joined[40];
                snprintf(joined, sizeof joined, "%s ", pieces->pieces[p].notches[i].label);
                CHECK(strstr(svg, shown) || strstr(svg, joined), "%s: notch label %s not shown", tag, shown);
            }
        }
    CHECK(count_of(svg, "class=\"notch-label\"") == labels, "%s: %d notch labels, %d notches at distinct places", tag,
          count_of(svg, "class=\"notch-label\""), (int)labels);
    CHECK(count_of(svg, ">Cut 2 mirrored<") == doubled && count_of(svg, ">Cut 1<") == drawn - doubled,
          "%s: cut counts", tag);
    CHECK(strstr(svg, "width=\"100.000\" height=\"100.000\"") && strstr(svg, "10 cm"), "%s: no 10 cm scale box", tag);
    CHECK(!strstr(svg, "<&") && strstr(svg, "</svg>\n"), "%s: escaping or end", tag);
    if (reader_available("rsvg-convert --version", "rsvg-convert")) {
        char command[1200], png[512];
        test_temp_path(png, sizeof png, "pattern.png");
        snprintf(command, sizeof command, "rsvg-convert --dpi-x 25.4 --dpi-y 25.4 -o '%s' '%s'", png, path);
        CHECK(reader_run(command) == 0, "%s: rsvg-convert failed", tag);
        size_t png_size = 0;
        unsigned char *image = test_read_file(png, &png_size);
        CHECK(image && png_size > 24, "%s: no PNG", tag);
        if (image && png_size > 24) {
            /* PNG IHDR: width and height, big-endian, at bytes 16 and 20; 1 px per mm. */
            long w = (long)image[16] << 24 | (long)image[17] << 16 | (long)image[18] << 8 | image[19];
            long h = (long)image[20] << 24 | (long)image[21] << 16 | (long)image[22] << 8 | image[23];
            CHECK(labs(w - lround(width)) <= 1 && labs(h - lround(height)) <= 1, "%s: %ld x %ld px for %g x %g mm",
                  tag, w, h, width, height);
        }
        free(image);
    }
    free(svg);
}

/* ---------------------------------------------------------------- dxf */

static void check_dxf(pz_export_inputs *inputs, pz_export_options *options, const char *tag)
{
    const pz_pieces *pieces = inputs->pieces;
    char expected_path[512], path[512], file_name[64];
    snprintf(file_name, sizeof file_name, "%s-expected.txt", tag);
    test_temp_path(expected_path, sizeof expected_path, file_name);
    piece_checks_write_dxf_expected(pieces, expected_path);
    int checker = reader_available("/usr/bin/python3 -c 'import ezdxf'", "ezdxf (/usr/bin/python3)");
    const char *source = getenv("PZ_SOURCE_DIR");
    for (int strict = 0; strict < 2; ++strict) {
        options->dxf_strict = strict;
        snprintf(file_name, sizeof file_name, "%s%s.dxf", tag, strict ? "-strict" : "");
        size_t size = 0;
        char *dxf = write_file(file_name, pz_export_write_dxf, inputs, path, &size);
        CHECK(strstr(dxf, "AC1009") && strstr(dxf, "$INSUNITS") && strstr(dxf, "\nEOF\n"), "%s: header or end",
              file_name);
        CHECK((strstr(dxf, "\nTABLES\n") == NULL) == strict, "%s: TABLES section %s", file_name,
              strict ? "present" : "missing");
        int ascii = 1;
        for (size_t i = 0; i < size; ++i)
            ascii &= (unsigned char)dxf[i] < 0x80;
        CHECK(ascii, "%s: bytes beyond 7-bit ASCII", file_name);
        CHECK(count_of(dxf, "\nINSERT\n") == drawn_count(pieces), "%s: %d INSERTs", file_name,
              count_of(dxf, "\nINSERT\n"));
        if (checker && source) {
            char command[1600];
            snprintf(command, sizeof command, "/usr/bin/python3 '%s/tests/export/check_dxf.py' '%s' '%s'", source, path,
                     expected_path);
            char log_path[600], what[120];
            snprintf(log_path, sizeof log_path, "%s.log", path);
            snprintf(what, sizeof what, "%s: ezdxf check", file_name);
            reader_passes(command, log_path, what);
        }
        free(dxf);
    }
    options->dxf_strict = 0;
}

/* ---------------------------------------------------------------- cases */

static void export_case(const fixture *f, const char *const *names, const char *tag)
{
    pz_export_options options;
    pz_export_options_default(&options);
    options.garment_name = "bodice <test> & co";
    options.size_name = "M";
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(f->pattern, f->uv, &options, f->panel_mirror, names, &pieces, &ctx), ctx);
    pz_export_inputs inputs = {.garment = f->garment, .pattern = f->pattern, .uv = f->uv, .pieces = pieces,
                               .options = &options, .panel_names = names};
    check_layout(pieces, 20, 140);
    check_layout(pieces, 5, 0);
    check_svg(&inputs, tag);
    check_dxf(&inputs, &options, tag);
    pz_pieces_free(&pieces);
}

static void test_bodice(void)
{
    fixture f = fixture_generated(PZ_SHAPE_BODICE, 2000, 1);
    const char *names[4] = {"Vorderteil \xc3\x9c", NULL, "back", NULL};
    export_case(&f, names, "bodice");
    /* Text: escaped in SVG; \U+00DC in DXF, '?' when strict. */
    char *svg = read_output("bodice.svg"), *dxf = read_output("bodice.dxf"), *strict = read_output("bodice-strict.dxf");
    CHECK(strstr(svg, "bodice &lt;test&gt; &amp; co") && strstr(svg, "Vorderteil \xc3\x9c"), "svg text");
    CHECK(strstr(dxf, "Piece Name: Vorderteil \\U+00DC") && strstr(dxf, "Style Name: bodice <test> & co"), "dxf text");
    CHECK(strstr(strict, "Piece Name: Vorderteil ?\n") != NULL, "strict dxf text");
    free(svg);
    free(dxf);
    free(strict);
    fixture_free(&f);
}

/* Pieces with the same name get distinct block names: "_K" (the panel) appended, again if that clashes. */
static void test_block_names(void)
{
    fixture f = fixture_generated(PZ_SHAPE_BODICE, 2000, 1);
    const char *names[4] = {"front", "front", "front_1", "back"};
    pz_export_options options;
    pz_export_options_default(&options);
    pz_pieces *pieces = NULL;
    REQUIRE_OK(pz_pieces_build(f.pattern, f.uv, &options, NULL, names, &pieces, &ctx), ctx);
    pz_export_inputs inputs = {.pattern = f.pattern, .uv = f.uv, .pieces = pieces, .options = &options};
    char path[512];
    size_t size = 0;
    char *dxf = write_file("names.dxf", pz_export_write_dxf, &inputs, path, &size);
    const char *expected[4] = {"front_0", "front_1_1", "front_1_2", "back"};
    for (int i = 0; i < 4; ++i) {
        char block[80], insert[80];
        snprintf(block, sizeof block, "\nBLOCK\n  8\n0\n  2\n%s\n", expected[i]);
        snprintf(insert, sizeof insert, "\nINSERT\n  8\n0\n  2\n%s\n", expected[i]);
        CHECK(count_of(dxf, block) == 1 && count_of(dxf, insert) == 1, "block %s: %d defined, %d inserted", expected[i],
              count_of(dxf, block), count_of(dxf, insert));
    }
    free(dxf);
    pz_pieces_free(&pieces);
    fixture_free(&f);
}

/* The skirt's true UV pattern has darts: dart lines and notches must come through. */
static void test_skirt(void)
{
    const char *dir = test_shared_data();
    if (!dir) {
        test_skip_part("skirt (no ../shared/data)");
        return;
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/garments/parafashion-skirt.obj", dir);
    fixture f;
    REQUIRE(fixture_shared(&f, path, 1), "skirt");
    REQUIRE(f.pattern->dart_count > 0, "the skirt has no darts");
    export_case(&f, NULL, "skirt");
    fixture_free(&f);
}

int main(void)
{
    test_temp_dir_create("pz_export_svg_dxf");
    test_bodice();
    test_block_names();
    test_skirt();
    if (!getenv("PZ_KEEP_OUTPUT"))
        test_remove_tree(test_temp_dir);
    else
        printf("output kept in %s\n", test_temp_dir);
    return test_finish();
}
