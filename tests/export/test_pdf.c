/*
 * tests/export/test_pdf.c -- pattern.pdf and pattern-tiled.pdf, read back
 * with poppler's tools (pdfinfo, pdftoppm, pdftotext; the test is skipped,
 * exit 77, when they are missing, and fails then under CI=true):
 *  - both render (pdftoppm exits 0);
 *  - pattern.pdf is one page; the tiled PDF's pages are A4 or Letter as
 *    asked; a sheet larger than a PDF page may be (14400 pt, 5.08 m) is
 *    several 1:1 pages, each within that, covering the sheet;
 *  - the 10 cm scale box measures 100 mm, on the sheet and on page 2 of the
 *    tiled PDF where its layout put it: rendered at 254 dpi (0.1 mm per
 *    pixel, the spacing of its edges measured, within 0.2 mm), and in the
 *    PDF's own units (a 283.465 pt rectangle in a content stream drawn
 *    without scaling, within 0.01 mm: tests/export/pdf_scale_box.py);
 *  - the tiled PDF's layout has every property of tiled_checks.h (pieces
 *    whole where they fit a page, nothing overlapping, every cut line
 *    printed, no blank tile) and the PDF is its pages plus the cover; every
 *    page has ink inside its printable area (rendered and counted), its trim
 *    marks (the eight corner ticks found in the rendered margin) and its
 *    "page N of M" label; every piece is named in it;
 *  - packing: 20 pieces of 80 x 120 mm take 5 A4 pages (four a page) and the
 *    scale box a sixth; two 300 x 100 mm pieces share their two tiles;
 *  - piece names and "Cut 2 mirrored" are in the text; a Latin-1 name is
 *    shown with '?' for its non-UTF-8 bytes (cairo would refuse it);
 *  - with SOURCE_DATE_EPOCH two writes a second apart are byte-identical;
 *  - an unknown paper is PZ_ERR_USAGE, a 100 x 100 m piece PZ_ERR_DATA
 *    (before any raster is made); a stream that cannot be written gives
 *    PZ_ERR_CREATE.
 * Pieces: 12 hand-made rectangles and L-shapes, and pz_pieces_build's for
 * the 4 panels of a flattened bodice (notches, dart lines).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "fixture_export_b.h"
#include "readers.h"
#include "tiled_checks.h"

#include <stdio.h>
#include <unistd.h>

static pz_ctx ctx;
static char dir[] = "/tmp/pz_pdf_XXXXXX";
static int have_python; /* /usr/bin/python3 runs pdf_scale_box.py */

/* Runs a shell command, returns its stdout (malloc'd, NUL-terminated) or NULL when it fails. */
static char *run(const char *command)
{
    FILE *pipe = popen(command, "r");
    if (!pipe)
        return NULL;
    size_t size = 0, capacity = 1 << 16;
    char *text = malloc(capacity);
    REQUIRE(text, "out of memory");
    size_t got;
    while ((got = fread(text + size, 1, capacity - size - 1, pipe)) > 0) {
        size += got;
        if (size + 1 == capacity) {
            text = realloc(text, capacity *= 2);
            REQUIRE(text, "out of memory");
        }
    }
    text[size] = 0;
    if (pclose(pipe) != 0) {
        free(text);
        return NULL;
    }
    return text;
}

static int pdf_pages(const char *path, double size_pt[2])
{
    char command[600];
    snprintf(command, sizeof command, "pdfinfo '%s'", path);
    char *info = run(command);
    REQUIRE(info, "pdfinfo failed on %s", path);
    int pages = -1;
    const char *at = strstr(info, "Pages:");
    if (at)
        pages = atoi(at + 6);
    at = strstr(info, "Page size:");
    if (at)
        sscanf(at + 10, " %lf x %lf", &size_pt[0], &size_pt[1]);
    free(info);
    return pages;
}

/* Page `page` rendered in grey at `dpi`, whole or (size_px > 0) a size_px square from (x0, y0) mm. */
static unsigned char *render(const char *path, int page, int dpi, double x0, double y0, int size_px, int *width,
                             int *height)
{
    char command[800], crop[128] = "";
    if (size_px > 0)
        snprintf(crop, sizeof crop, "-x %d -y %d -W %d -H %d", (int)(x0 / 25.4 * dpi), (int)(y0 / 25.4 * dpi),
                 size_px, size_px);
    snprintf(command, sizeof command, "pdftoppm -gray -r %d -f %d -l %d %s '%s'", dpi, page, page, crop, path);
    FILE *pipe = popen(command, "r");
    REQUIRE(pipe, "popen");
    int maximum = 0;
    REQUIRE(fscanf(pipe, "P5 %d %d %d", width, height, &maximum) == 3 && *width > 0 && *height > 0,
            "no PGM from %s page %d", path, page);
    fgetc(pipe);
    size_t count = (size_t)*width * (size_t)*height;
    unsigned char *pixels = malloc(count);
    REQUIRE(pixels && fread(pixels, 1, count, pipe) == count, "short PGM");
    pclose(pipe);
    return pixels;
}

/* Distance between the first and last lines (runs of 90 mm or more) across one axis, in mm; -1 if none. */
static double line_spacing(const unsigned char *pixels, int width, int height, int transposed)
{
    int lines = transposed ? width : height, along = transposed ? height : width;
    double first = -1, last = -1, first_sum = 0, last_sum = 0;
    int first_count = 0, last_count = 0;
    for (int l = 0; l < lines; ++l) {
        int run = 0, longest = 0;
        for (int a = 0; a < along; ++a) {
            unsigned char value = transposed ? pixels[a * width + l] : pixels[l * width + a];
            run = value < 128 ? run + 1 : 0;
            longest = run > longest ? run : longest;
        }
        if (longest < 900)
            continue;
        if (first < 0 || l - first <= 10) { /* the first line's pixel rows */
            if (first < 0)
                first = l;
            first_sum += l, ++first_count;
        } else {
            if (last < 0 || l - last > 10)
                last = l, last_sum = 0, last_count = 0;
            last_sum += l, ++last_count;
        }
    }
    if (!first_count || !last_count)
        return -1;
    return (last_sum / last_count - first_sum / first_count) / 10.0;
}

/* 1 when the page shows a 100 x 100 mm square (within 0.2 mm) in the 120 mm crop at (x0, y0) mm. */
static int has_scale_box(const char *path, int page, double x0, double y0)
{
    int width, height;
    unsigned char *pixels = render(path, page, 254, x0, y0, 1200, &width, &height);
    double across = line_spacing(pixels, width, height, 1), down = line_spacing(pixels, width, height, 0);
    free(pixels);
    printf("%s page %d: scale box %.2f x %.2f mm\n", strrchr(path, '/') + 1, page, across, down);
    return fabs(across - 100.0) < 0.2 && fabs(down - 100.0) < 0.2;
}

/* Dark pixels of page `page` rendered at 10 dpi, inside the printable area (paper minus 11 mm). */
static int ink_inside(const char *path, int page)
{
    int width, height, dark = 0;
    unsigned char *pixels = render(path, page, 10, 0, 0, 0, &width, &height);
    int border = (int)ceil(11.0 / 25.4 * 10.0);
    for (int y = border; y < height - border; ++y)
        for (int x = border; x < width - border; ++x)
            dark += pixels[y * width + x] < 160;
    free(pixels);
    return dark;
}

/* 1 when the page has the eight trim ticks: dark pixels 2-6 mm out from each printable corner, along
 * both edges, in the otherwise empty margin (rendered at 100 dpi). */
static int has_trim_marks(const char *path, int page, const double paper[2])
{
    int width, height, found = 0;
    unsigned char *pixels = render(path, page, 100, 0, 0, 0, &width, &height);
    const double margin = 10.0, px = 100 / 25.4;
    for (int corner = 0; corner < 4; ++corner) {
        double cx = corner % 2 ? paper[0] - margin : margin, cy = corner / 2 ? paper[1] - margin : margin;
        double out_x = corner % 2 ? 1 : -1, out_y = corner / 2 ? 1 : -1;
        for (int axis = 0; axis < 2; ++axis) {
            int dark = 0;
            for (double t = 2.0; t <= 6.0; t += 0.5) {
                int x = (int)lround((cx + (axis == 0 ? out_x * t : 0)) * px);
                int y = (int)lround((cy + (axis == 1 ? out_y * t : 0)) * px);
                for (int d = -1; d <= 1; ++d) {
                    int xx = axis == 1 ? x + d : x, yy = axis == 0 ? y + d : y;
                    if (xx >= 0 && yy >= 0 && xx < width && yy < height && pixels[yy * width + xx] < 200) {
                        ++dark;
                        break;
                    }
                }
            }
            found += dark >= 8; /* nearly every sample along the tick */
        }
    }
    free(pixels);
    return found == 8;
}

static void write_pdf(pz_status (*writer)(FILE *, const pz_export_inputs *, const char *, pz_ctx *),
                      const pz_export_inputs *inputs, const char *path)
{
    FILE *file = fopen(path, "wb");
    REQUIRE(file, "cannot write %s", path);
    REQUIRE_OK(writer(file, inputs, path, &ctx), ctx);
    REQUIRE(fclose(file) == 0, "close %s", path);
}

/* Writes both PDFs of `pieces` and checks everything above; the tiled PDF's pages (cover not counted). */
static int32_t check_pdfs(const pz_pieces *pieces, const char *paper, const char *tag)
{
    pz_export_options options;
    pz_export_options_default(&options);
    options.paper = paper;
    pz_export_inputs inputs = {.pieces = pieces, .options = &options};
    char sheet_path[300], tiled_path[300], command[1600];
    snprintf(sheet_path, sizeof sheet_path, "%s/%s-pattern.pdf", dir, tag);
    snprintf(tiled_path, sizeof tiled_path, "%s/%s-pattern-tiled.pdf", dir, tag);
    write_pdf(pz_export_write_pdf, &inputs, sheet_path);
    write_pdf(pz_export_write_pdf_tiled, &inputs, tiled_path);

    double size[2] = {0, 0};
    CHECK(pdf_pages(sheet_path, size) == 1, "%s: pages", sheet_path);
    CHECK(has_scale_box(sheet_path, 1, 10, 10), "%s: no 100 mm scale box", sheet_path);
    int pages = pdf_pages(tiled_path, size);
    int letter = strcmp(paper, "letter") == 0;
    CHECK(fabs(size[0] - (letter ? 612 : 595.28)) < 0.5 && fabs(size[1] - (letter ? 792 : 841.89)) < 0.5,
          "%s: page size %g x %g", tiled_path, size[0], size[1]);
    /* The layout's properties (tiled_checks.h), and the PDF has its pages: the cover and one per layout page. */
    int32_t laid = check_tiled_layout(pieces, paper, tag);
    CHECK(pages == laid + 1, "%s: %d pages for %d laid out and the cover", tiled_path, pages, (int)laid);
    /* The scale box on the first page after the cover, where the layout put it: 10 mm margins, y down. */
    tiled_layout layout;
    REQUIRE_OK(tiled_layout_build(pieces, paper, &layout, &ctx), ctx);
    CHECK(layout.items[0].page == 0, "%s: the scale box is on page %d", tag, (int)layout.items[0].page + 2);
    double box_left = 10 + layout.items[0].at[0], box_top = 10 + layout.printable[1] - (layout.items[0].at[1] + 100);
    tiled_layout_free(&layout);
    CHECK(has_scale_box(tiled_path, 2, box_left - 10, box_top - 10), "%s: no 100 mm scale box on page 2", tiled_path);
    /* And in the PDF's own units: a 283.465 pt rectangle drawn without scaling (pdf_scale_box.py). */
    const char *source = getenv("PZ_SOURCE_DIR");
    if (source && have_python) {
        for (int k = 0; k < 2; ++k) {
            snprintf(command, sizeof command, "/usr/bin/python3 '%s/tests/export/pdf_scale_box.py' '%s' >/dev/null",
                     source, k ? tiled_path : sheet_path);
            CHECK(system(command) == 0, "%s: no 100 x 100 mm rectangle in the PDF's units", k ? tiled_path : sheet_path);
        }
    }

    snprintf(command, sizeof command, "pdftoppm -r 8 '%s' %s/render && pdftoppm -r 8 '%s' %s/render && rm -f %s/render*",
             sheet_path, dir, tiled_path, dir, dir);
    CHECK(system(command) == 0, "pdftoppm failed on %s", tag);

    snprintf(command, sizeof command, "pdftotext -layout '%s' -", tiled_path);
    char *text = run(command);
    REQUIRE(text, "pdftotext failed on %s", tiled_path);
    for (int page = 2; page <= pages; ++page) {
        char label[64];
        snprintf(label, sizeof label, "page %d of %d", page, pages);
        CHECK(strstr(text, label) != NULL, "%s: no '%s'", tag, label);
        CHECK(ink_inside(tiled_path, page) > 0, "%s: page %d is blank", tag, page);
        double paper_mm[2] = {letter ? 215.9 : 210.0, letter ? 279.4 : 297.0};
        CHECK(has_trim_marks(tiled_path, page, paper_mm), "%s: page %d has no trim marks", tag, page);
    }
    /* Every piece is named on the cover (and where it is). */
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored && !strchr(pieces->pieces[p].name, '\xe9'))
            CHECK(strstr(text, pieces->pieces[p].name) != NULL, "%s: %s not in the tiled PDF", tag,
                  pieces->pieces[p].name);
    free(text);

    snprintf(command, sizeof command, "pdftotext '%s' -", sheet_path);
    text = run(command);
    REQUIRE(text, "pdftotext failed on %s", sheet_path);
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored && !strchr(pieces->pieces[p].name, '\xe9'))
            CHECK(strstr(text, pieces->pieces[p].name) != NULL, "%s: %s missing", tag, pieces->pieces[p].name);
    CHECK(strstr(tag, "boxes") == NULL || strstr(text, "dos_d?coup?") != NULL, "Latin-1 name not shown with '?'");
    CHECK(strstr(text, "10 cm") != NULL, "scale box label");
    free(text);
    printf("%s: tiled on %s: %d pages\n", tag, paper, pages);
    return laid;
}

/*
 * Packing: 20 pieces of 80 x 120 mm go four to an A4 page (two by two, 6 mm apart: the best any packing does,
 * five would need 20 % more room than a page has), so 5 pages, and the scale box on a sixth; and two pieces of
 * 300 x 100 mm, each two tiles wide on its own, share the same two tiles on the sheet (one above the other) with
 * the scale box on a page of its own: 3 pages, where printing each on its own would take 5.
 */
static void test_packing(void)
{
    pz_pieces *small = fixture_pieces_alloc(20);
    for (int32_t p = 0; p < 20; ++p) {
        char name[32];
        snprintf(name, sizeof name, "small_%d", (int)p);
        fixture_piece_box(&small->pieces[p], p, name, 60, 100, 0); /* cut line: 10 mm more on every side */
    }
    CHECK(check_pdfs(small, "a4", "packing") == 6, "20 pieces of 80 x 120 mm: not 6 pages");
    fixture_pieces_free(small);

    pz_pieces *long_pieces = fixture_pieces_alloc(2);
    for (int32_t p = 0; p < 2; ++p)
        fixture_piece_box(&long_pieces->pieces[p], p, p ? "strip_b" : "strip_a", 280, 80, 0);
    CHECK(check_pdfs(long_pieces, "a4", "sharing") == 3, "two 300 x 100 mm pieces do not share their tiles");
    fixture_pieces_free(long_pieces);
}

static void test_boxes(void)
{
    pz_pieces *pieces = fixture_pieces_alloc(12);
    for (int32_t p = 0; p < 12; ++p) {
        char name[32];
        snprintf(name, sizeof name, "piece_%d", (int)p);
        fixture_piece_box(&pieces->pieces[p], p, name, 120 + 37 * (p % 7), 200 + 53 * (p % 5), p % 3 == 0);
        if (p % 4 == 1)
            pieces->pieces[p].cut_quantity = 2;
    }
    /* A name in Latin-1 (not UTF-8), as a file may give it: shown with '?', the PDF still written. */
    snprintf(pieces->pieces[3].name, sizeof pieces->pieces[3].name, "dos_d\xe9" "coup\xe9");
    check_pdfs(pieces, "a4", "boxes");
    char command[600];
    snprintf(command, sizeof command, "pdftotext %s/boxes-pattern.pdf -", dir);
    char *text = run(command);
    CHECK(text && strstr(text, "Cut 2 mirrored") && strstr(text, "Cut 1"), "cut counts");
    free(text);

    /* A paper size the tiler does not know. */
    pz_export_options a3;
    pz_export_options_default(&a3);
    a3.paper = "a3";
    pz_export_inputs a3_inputs = {.pieces = pieces, .options = &a3};
    FILE *sink = tmpfile();
    REQUIRE(sink, "tmpfile");
    CHECK(pz_export_write_pdf_tiled(sink, &a3_inputs, "tiled.pdf", &ctx) == PZ_ERR_USAGE && strstr(ctx.error, "a3"),
          "%s", ctx.error);
    fclose(sink);

    /* A piece of 100 x 100 m (a garment read in the wrong units) is refused before any raster is made. */
    pz_pieces *huge = fixture_pieces_alloc(1);
    fixture_piece_box(&huge->pieces[0], 0, "huge", 100000, 100000, 0);
    pz_export_options huge_options;
    pz_export_options_default(&huge_options);
    pz_export_inputs huge_inputs = {.pieces = huge, .options = &huge_options};
    sink = tmpfile();
    REQUIRE(sink, "tmpfile");
    CHECK(pz_export_write_pdf_tiled(sink, &huge_inputs, "tiled.pdf", &ctx) == PZ_ERR_DATA && strstr(ctx.error, "units"),
          "a 100 m piece: %s", ctx.error);
    fclose(sink);
    fixture_pieces_free(huge);

    /* With SOURCE_DATE_EPOCH the same pattern gives the same bytes (cairo would stamp the time). */
    pz_export_options same;
    pz_export_options_default(&same);
    pz_export_inputs same_inputs = {.pieces = pieces, .options = &same};
    REQUIRE(setenv("SOURCE_DATE_EPOCH", "1700000000", 1) == 0, "setenv");
    size_t sizes[2] = {0, 0};
    char *bytes[2];
    for (int k = 0; k < 2; ++k) {
        FILE *stream = tmpfile();
        REQUIRE(stream, "tmpfile");
        REQUIRE_OK(pz_export_write_pdf_tiled(stream, &same_inputs, "tiled.pdf", &ctx), ctx);
        sizes[k] = (size_t)ftell(stream);
        rewind(stream);
        bytes[k] = malloc(sizes[k] + 1);
        REQUIRE(bytes[k] && fread(bytes[k], 1, sizes[k], stream) == sizes[k], "read back");
        fclose(stream);
        if (k == 0)
            sleep(1); /* a second later: only the fixed date can make the bytes equal */
    }
    CHECK(sizes[0] == sizes[1] && memcmp(bytes[0], bytes[1], sizes[0]) == 0, "two writes differ");
    int dated = 0;
    for (size_t i = 0; i + 14 <= sizes[0] && !dated; ++i)
        dated = memcmp(bytes[0] + i, "20231114221320", 14) == 0; /* 1700000000 in UTC */
    CHECK(dated, "creation date not from SOURCE_DATE_EPOCH");
    free(bytes[0]);
    free(bytes[1]);
    unsetenv("SOURCE_DATE_EPOCH");

    /* A stream that fails: /dev/full refuses every write. */
    FILE *full = fopen("/dev/full", "wb");
    if (full) {
        pz_export_options options;
        pz_export_options_default(&options);
        pz_export_inputs inputs = {.pieces = pieces, .options = &options};
        CHECK(pz_export_write_pdf(full, &inputs, "full.pdf", &ctx) == PZ_ERR_CREATE && strstr(ctx.error, "full.pdf"),
              "%s", ctx.error);
        fclose(full);
    }
    fixture_pieces_free(pieces);
}

/*
 * A sheet wider and taller than a PDF page may be (Acrobat: 14400 pt = 5080 mm): 36 pieces of about 1 m and a
 * 5.6 m long one. pattern.pdf must be several 1:1 pages, each at most 14400 pt, "part K of N" on each, covering
 * the sheet (their areas add up to the sheet's, plus at most the overlap bands of the cut through the long
 * piece), the scale box 100 mm in the PDF's units, every piece's name in the text, and poppler renders them.
 */
static void test_wide_sheet(void)
{
    const int32_t count = 37;
    pz_pieces *pieces = fixture_pieces_alloc(count);
    for (int32_t p = 0; p < count; ++p) {
        char name[32];
        snprintf(name, sizeof name, "wide_%d", (int)p);
        if (p == count - 1)
            fixture_piece_box(&pieces->pieces[p], p, name, 400, 5600, 0);
        else
            fixture_piece_box(&pieces->pieces[p], p, name, 800 + 13 * (p % 9), 1100 + 29 * (p % 5), p % 4 == 0);
    }
    pz_export_options options;
    pz_export_options_default(&options);
    pz_export_inputs inputs = {.pieces = pieces, .options = &options};
    char path[300], command[1200];
    snprintf(path, sizeof path, "%s/wide-pattern.pdf", dir);
    write_pdf(pz_export_write_pdf, &inputs, path);
    /* The sheet as pdf.c lays it out: pieces 20 mm apart below a 136 mm band (title, scale box). */
    double *offsets = malloc(2 * (size_t)count * sizeof(double)), sheet[2];
    REQUIRE(offsets, "out of memory");
    pz_pieces_sheet_layout(pieces, 20.0, 136.0, offsets, sheet);
    free(offsets);
    double size[2];
    int pages = pdf_pages(path, size);
    snprintf(command, sizeof command, "pdfinfo -f 1 -l %d '%s'", pages, path);
    char *info = run(command);
    REQUIRE(info, "pdfinfo failed");
    double area = 0, largest = 0;
    int listed = 0;
    for (const char *at = info; (at = strstr(at, "Page ")); ++at) {
        int page;
        double w, h;
        if (sscanf(at, "Page %d size: %lf x %lf", &page, &w, &h) != 3)
            continue;
        ++listed;
        largest = fmax(largest, fmax(w, h));
        area += (w / (72 / 25.4)) * (h / (72 / 25.4));
    }
    free(info);
    double sheet_area = sheet[0] * sheet[1], overlap = 10.0 * 2 * fmax(sheet[0], sheet[1]);
    printf("wide sheet %.0f x %.0f mm: %d pages, the largest side %.0f pt, pages cover %.4f of the sheet\n", sheet[0],
           sheet[1], pages, largest, area / sheet_area);
    CHECK(sheet[0] > 5080 && sheet[1] > 5080, "the layout is not wider and taller than a page: %.0f x %.0f", sheet[0],
          sheet[1]);
    CHECK(pages > 1 && listed == pages && largest <= 14400, "%d pages (%d listed), largest side %.0f pt", pages, listed,
          largest);
    CHECK(area >= sheet_area - 1 && area <= sheet_area + overlap, "pages cover %.0f of %.0f mm2", area, sheet_area);
    snprintf(command, sizeof command, "pdftotext '%s' -", path);
    char *text = run(command);
    REQUIRE(text, "pdftotext failed");
    char label[64];
    for (int page = 1; page <= pages; ++page) {
        snprintf(label, sizeof label, "part %d of %d", page, pages);
        CHECK(strstr(text, label) != NULL, "no '%s'", label);
    }
    for (int32_t p = 0; p < count; ++p) {
        snprintf(label, sizeof label, "%s\n", pieces->pieces[p].name);
        CHECK(strstr(text, label) != NULL, "%s missing", pieces->pieces[p].name);
    }
    free(text);
    const char *source = getenv("PZ_SOURCE_DIR");
    if (source && have_python) {
        snprintf(command, sizeof command, "/usr/bin/python3 '%s/tests/export/pdf_scale_box.py' '%s' >/dev/null", source,
                 path);
        CHECK(system(command) == 0, "%s: no 100 x 100 mm rectangle in the PDF's units", path);
    }
    snprintf(command, sizeof command, "pdftoppm -r 2 '%s' %s/wide && rm -f %s/wide-*", path, dir, dir);
    CHECK(system(command) == 0, "pdftoppm failed on %s", path);
    fixture_pieces_free(pieces);
}

static void test_bodice(void)
{
    fixture_pattern fixture;
    fixture_pattern_build(&fixture, 3000, 4);
    fixture_pattern_export(&fixture);
    check_pdfs(fixture.pieces, "letter", "bodice");
    fixture_pattern_free(&fixture);
}

int main(void)
{
    /* Without poppler nothing here can be read back: the whole test is skipped (a failure under CI=true). */
    if (!reader_available("command -v pdfinfo && command -v pdftoppm && command -v pdftotext",
                          "poppler-utils (pdfinfo, pdftoppm, pdftotext)"))
        return test_finish();
    have_python = reader_available("command -v /usr/bin/python3", "/usr/bin/python3");
    if (!getenv("PZ_SOURCE_DIR"))
        test_skip_part("the PDF's units (PZ_SOURCE_DIR unset: no pdf_scale_box.py)");
    REQUIRE(mkdtemp(dir), "mkdtemp");
    test_boxes();
    test_packing();
    test_wide_sheet();
    test_bodice();
    char command[300];
    snprintf(command, sizeof command, "rm -rf %s", dir);
    CHECK(system(command) == 0, "cleanup");
    return test_finish();
}
