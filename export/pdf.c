/*
 * export/pdf.c -- pattern.pdf (one sheet at 1:1) and pattern-tiled.pdf (the
 * same sheet cut into A4 or Letter pages for home printing), through cairo.
 *
 * The sheet: every drawn piece (pz_piece.mirrored == 0) where
 * pz_pieces_sheet_layout puts it (the layout of pattern.svg: rows, tallest
 * first, 20 mm apart), under a band with the title and the 10 cm scale box (a
 * 100 x 100 mm square at the top left, drawn as one rectangle so its size can
 * be read back from the PDF; the first tile always shows it whole). Pieces
 * keep their pattern orientation (the grain runs up the page). 1 mm = 72 /
 * 25.4 pt.
 *
 * Each piece: cut line (solid, 0.5 mm), sew line (dashed, 0.3 mm), notches
 * (cut from the cut line inward by their depth, with their labels; notches
 * at one place drawn once, labels joined: "X5 I1"), internal
 * lines (darts), the grain arrow, and its name, cut count ("Cut 1" / "Cut 2
 * mirrored"), garment, size and extent as text.
 *
 * The 1:1 sheet is one page when it fits Acrobat's 200 in (5080 mm) page
 * limit; a larger sheet is cut into several 1:1 pages of at most 5000 mm,
 * between pieces where a gap allows (sheet_pages below), each labelled
 * "part K of N".
 *
 * Tiles: printable area = paper minus 10 mm margins; neighbouring tiles share
 * 10 mm (the overlap band, dashed on the page). A tile whose printable area
 * meets no ink (no cut line, no scale box, no title) is dropped, and so is
 * one whose only ink lies in the bands it shares with the tiles above and to
 * the left (those print it). The cover page shows the sheet scaled to fit
 * with the tile grid, each tile's "row, column" and dropped tiles greyed. Every tile page has trim marks at
 * the printable area's corners and "row R col C, page N of M" (N, M count
 * PDF pages, cover included) in its bottom margin.
 *
 * Text that is not UTF-8 is shown with '?' (cairo refuses it). The creation
 * date is SOURCE_DATE_EPOCH's when set (byte-identical output), else now.
 * Errors: PZ_ERR_CREATE when the stream fails, PZ_ERR_USAGE for a paper
 * other than a4 or letter, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L /* gmtime_r */
#include "export/export.h"
#include "export/notches.h"
#include "export/stream_status.h"
#include "export/xml_text.h"

#include <cairo-pdf.h>
#include <cairo.h>
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PT_PER_MM (72.0 / 25.4)

/*
 * cairo's text goes through fontconfig, which keeps what it resolved for the
 * life of the process (only FcFini frees it, and a library must not call
 * that): LeakSanitizer reports it at exit of every program that wrote a PDF.
 * In sanitizer builds only, this file names that leak through LSan's
 * documented hook, so the programs linking it (the CLI, the tests) stay clean,
 * and asks LSan not to list the suppressions it used at exit (the CLI's
 * stderr must stay one line on failure and empty with --quiet;
 * LSAN_OPTIONS still overrides).
 */
#if defined(__SANITIZE_ADDRESS__)
#define PZ_PDF_LSAN_HOOK 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PZ_PDF_LSAN_HOOK 1
#endif
#endif
#ifdef PZ_PDF_LSAN_HOOK
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:libfontconfig.so\n";
}
const char *__lsan_default_options(void);
const char *__lsan_default_options(void)
{
    return "print_suppressions=0";
}
#endif

static const double kPieceGap = 20.0;      /* between pieces on the sheet */
static const double kScaleBox = 100.0;     /* the scale square's side */
static const double kTitleBand = 16.0;     /* title line above the content */
static const double kPaperMargin = 10.0;   /* unprintable border of a tile page */
static const double kOverlap = 10.0;       /* shared by neighbouring tiles */

/* ------------------------------------------------------------------ the sheet layout */

/* One item on the sheet: a piece (index >= 0) or the scale box (-1); lower-left of its box. */
typedef struct sheet_item {
    int32_t piece;
    double offset[2];          /* added to piece coordinates */
    double lo[2], hi[2];       /* its box on the sheet */
} sheet_item;

typedef struct sheet {
    int32_t item_count;
    sheet_item *items;
    double width, height;      /* mm */
} sheet;

/* The pieces as pz_pieces_sheet_layout puts them (the layout of pattern.svg), the scale box and the title
 * in the band reserved above them. */
static pz_status sheet_build(const pz_pieces *pieces, sheet *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    double *offsets = malloc(((size_t)pieces->piece_count + 1) * 2 * sizeof(double));
    out->items = malloc(((size_t)pieces->piece_count + 1) * sizeof *out->items);
    if (!offsets || !out->items) {
        free(offsets);
        free(out->items);
        return pz_error(ctx, PZ_ERR_NOMEM, "pdf: out of memory");
    }
    double size[2];
    pz_pieces_sheet_layout(pieces, kPieceGap, kTitleBand + kScaleBox + kPieceGap, offsets, size);
    out->width = size[0], out->height = size[1];
    /* The scale box first, top left under the title: tile (1, 1) of the tiled PDF shows all of it. */
    sheet_item *box = &out->items[out->item_count++];
    box->piece = -1;
    box->lo[0] = kPieceGap, box->lo[1] = size[1] - kTitleBand - kScaleBox;
    box->hi[0] = box->lo[0] + kScaleBox, box->hi[1] = box->lo[1] + kScaleBox;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        if (piece->mirrored || piece->cut_count < 3)
            continue;
        sheet_item *item = &out->items[out->item_count++];
        item->piece = p;
        for (int d = 0; d < 2; ++d) {
            item->offset[d] = offsets[2 * p + d];
            item->lo[d] = piece->bbox_min[d] + item->offset[d];
            item->hi[d] = piece->bbox_max[d] + item->offset[d];
        }
    }
    free(offsets);
    return PZ_OK;
}

/* ------------------------------------------------------------------ drawing (sheet mm, y up) */

/* Sets up `cr` so user space is sheet millimetres with y up, the sheet's (0, 0) at the page's lower left. */
static void sheet_space(cairo_t *cr, double sheet_height)
{
    cairo_scale(cr, PT_PER_MM, PT_PER_MM);
    cairo_translate(cr, 0, sheet_height);
    cairo_scale(cr, 1, -1);
}

/* cairo refuses text that is not UTF-8, and fails the whole surface with it. */
static void show_text(cairo_t *cr, const char *text)
{
    char clean[256];
    cairo_show_text(cr, pz_utf8_clean(text, clean, sizeof clean));
}

/* Text at (x, y) (sheet mm, y up), `size` mm high, upright. */
static void draw_text(cairo_t *cr, double x, double y, double size, const char *text)
{
    cairo_save(cr);
    cairo_move_to(cr, x, y);
    cairo_scale(cr, 1, -1);
    cairo_set_font_size(cr, size);
    show_text(cr, text);
    cairo_restore(cr);
}

static void path_polyline(cairo_t *cr, const double *points, int32_t n, const double offset[2], int closed)
{
    for (int32_t i = 0; i < n; ++i) {
        double x = points[2 * i] + offset[0], y = points[2 * i + 1] + offset[1];
        if (i == 0)
            cairo_move_to(cr, x, y);
        else
            cairo_line_to(cr, x, y);
    }
    if (closed)
        cairo_close_path(cr);
}

static void draw_arrow(cairo_t *cr, const double tail[2], const double head[2], double head_size)
{
    double dx = head[0] - tail[0], dy = head[1] - tail[1], length = hypot(dx, dy);
    cairo_move_to(cr, tail[0], tail[1]);
    cairo_line_to(cr, head[0], head[1]);
    cairo_stroke(cr);
    if (length <= 0)
        return;
    dx /= length, dy /= length;
    cairo_move_to(cr, head[0], head[1]);
    cairo_line_to(cr, head[0] - head_size * (dx - 0.4 * dy), head[1] - head_size * (dy + 0.4 * dx));
    cairo_line_to(cr, head[0] - head_size * (dx + 0.4 * dy), head[1] - head_size * (dy - 0.4 * dx));
    cairo_close_path(cr);
    cairo_fill(cr);
}

/* The piece's texts, stacked at the centre of its sew line's box. */
static void draw_piece_texts(cairo_t *cr, const pz_pieces *pieces, const pz_piece *piece, const double offset[2],
                             double scale)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int32_t i = 0; i < piece->sew_count; ++i)
        for (int d = 0; d < 2; ++d) {
            lo[d] = fmin(lo[d], piece->sew[2 * i + d]);
            hi[d] = fmax(hi[d], piece->sew[2 * i + d]);
        }
    char lines[5][96];
    snprintf(lines[0], sizeof lines[0], "%s", piece->name);
    snprintf(lines[1], sizeof lines[1], "%s", piece->cut_quantity >= 2 ? "Cut 2 mirrored" : "Cut 1");
    snprintf(lines[2], sizeof lines[2], "%s", pieces->garment_name);
    snprintf(lines[3], sizeof lines[3], "size %s", pieces->size_name);
    snprintf(lines[4], sizeof lines[4], "%.0f x %.0f mm", piece->bbox_max[0] - piece->bbox_min[0],
             piece->bbox_max[1] - piece->bbox_min[1]);
    double size = 5.0 * scale, x = (lo[0] + hi[0]) / 2 + offset[0] + 3 * scale;
    double y = (lo[1] + hi[1]) / 2 + offset[1] + 2 * size;
    for (int l = 0; l < 5; ++l, y -= 1.4 * size)
        draw_text(cr, x, y, l == 0 ? 1.3 * size : size, lines[l]);
}

/* Everything of one piece at `offset` (sheet mm). */
static void draw_piece(cairo_t *cr, const pz_pieces *pieces, const pz_piece *piece, const double offset[2])
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.5);
    cairo_set_dash(cr, NULL, 0, 0);
    path_polyline(cr, piece->cut, piece->cut_count, offset, 1);
    cairo_stroke(cr);

    const double dash[2] = {3.0, 2.0};
    cairo_set_line_width(cr, 0.3);
    cairo_set_dash(cr, dash, 2, 0);
    path_polyline(cr, piece->sew, piece->sew_count, offset, 1);
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);

    for (int32_t l = 0; l < piece->line_count; ++l) {
        path_polyline(cr, piece->lines[l].points, piece->lines[l].point_count, offset, 0);
        cairo_stroke(cr);
    }
    /* Notches at one place (two seams' ends at a corner) once, their labels joined; each on its own when out of
     * memory for that. */
    char(*labels)[PZ_NOTCH_LABELS_MAX] = malloc(((size_t)piece->notch_count + 1) * sizeof *labels);
    int joined = labels && pz_piece_notch_labels(piece, labels);
    for (int32_t n = 0; n < piece->notch_count; ++n) {
        /* A notch is a cut from the cut line inward, depth_mm long (pz_notch). */
        const pz_notch *notch = &piece->notches[n];
        const char *label = joined ? labels[n] : notch->label;
        if (joined && !label[0])
            continue;
        double x = notch->cut_point[0] + offset[0], y = notch->cut_point[1] + offset[1];
        cairo_move_to(cr, x, y);
        cairo_line_to(cr, x - notch->depth_mm * notch->direction[0], y - notch->depth_mm * notch->direction[1]);
        cairo_stroke(cr);
        if (label[0])
            draw_text(cr, notch->position[0] + offset[0] - 6 * notch->direction[0] - 2,
                      notch->position[1] + offset[1] - 6 * notch->direction[1] - 1, 3.0, label);
    }
    free(labels);
    double tail[2] = {piece->grain[0][0] + offset[0], piece->grain[0][1] + offset[1]};
    double head[2] = {piece->grain[1][0] + offset[0], piece->grain[1][1] + offset[1]};
    cairo_set_line_width(cr, 0.5);
    draw_arrow(cr, tail, head, 6.0);
    draw_arrow(cr, head, tail, 6.0); /* a grainline is drawn with both heads */
    draw_piece_texts(cr, pieces, piece, offset, 1.0);
}

static void draw_scale_box(cairo_t *cr, const sheet_item *item)
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.3);
    cairo_set_dash(cr, NULL, 0, 0);
    cairo_rectangle(cr, item->lo[0], item->lo[1], kScaleBox, kScaleBox);
    cairo_stroke(cr);
    draw_text(cr, item->lo[0] + 35, item->lo[1] + 47, 10.0, "10 cm");
}

static void draw_title(cairo_t *cr, const pz_pieces *pieces, const sheet *sheet)
{
    char title[200];
    snprintf(title, sizeof title, "%s - size %s - %d pieces - print at 100%% (scale box = 10 cm)",
             pieces->garment_name, pieces->size_name, (int)(sheet->item_count - 1));
    cairo_set_source_rgb(cr, 0, 0, 0);
    draw_text(cr, kPieceGap, sheet->height - kTitleBand + 4, 6.0, title);
}

static int boxes_meet(const double alo[2], const double ahi[2], const double blo[2], const double bhi[2])
{
    return alo[0] <= bhi[0] && blo[0] <= ahi[0] && alo[1] <= bhi[1] && blo[1] <= ahi[1];
}

/* Room around an item's box for what is drawn outside it (notch labels, long text lines). */
static const double kInkReach = 80.0;

/* The sheet in sheet space; with a view box (lo, hi non-NULL) only the items that may show in it, so a
 * tile page does not carry every piece of the sheet. */
static void draw_sheet(cairo_t *cr, const pz_export_inputs *inputs, const sheet *sheet, const double *lo,
                       const double *hi)
{
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
    draw_title(cr, inputs->pieces, sheet);
    for (int32_t i = 0; i < sheet->item_count; ++i) {
        const sheet_item *item = &sheet->items[i];
        double item_lo[2] = {item->lo[0] - kInkReach, item->lo[1] - kInkReach};
        double item_hi[2] = {item->hi[0] + kInkReach, item->hi[1] + kInkReach};
        if (lo && hi && !boxes_meet(lo, hi, item_lo, item_hi))
            continue;
        if (item->piece < 0)
            draw_scale_box(cr, item);
        else
            draw_piece(cr, inputs->pieces, &inputs->pieces->pieces[item->piece], item->offset);
    }
}

/* ------------------------------------------------------------------ streams */

/* The PDF's stream: cairo calls write_stream; the first failure's errno is kept for the message. */
typedef struct pdf_stream {
    FILE *file;
    int error;
} pdf_stream;

static cairo_status_t write_stream(void *closure, const unsigned char *data, unsigned int length)
{
    pdf_stream *stream = closure;
    if (fwrite(data, 1, length, stream->file) == length)
        return CAIRO_STATUS_SUCCESS;
    if (!stream->error)
        stream->error = errno ? errno : EIO;
    return CAIRO_STATUS_WRITE_ERROR;
}

/* Finishes the surface and turns cairo's and the stream's state into a status. */
static pz_status finish(cairo_surface_t *surface, cairo_t *cr, pdf_stream *stream, const char *name, pz_ctx *ctx)
{
    cairo_status_t drawing = cr ? cairo_status(cr) : CAIRO_STATUS_SUCCESS;
    if (cr)
        cairo_destroy(cr);
    cairo_surface_finish(surface);
    cairo_status_t status = cairo_surface_status(surface);
    cairo_surface_destroy(surface);
    if (drawing == CAIRO_STATUS_NO_MEMORY || status == CAIRO_STATUS_NO_MEMORY)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    if (stream->error || ferror(stream->file))
        return pz_export_stream_status(stream->file, stream->error, name, ctx);
    if (drawing != CAIRO_STATUS_SUCCESS || status != CAIRO_STATUS_SUCCESS)
        return pz_error(ctx, PZ_ERR_CREATE, "%s: cannot write the PDF (%s)", name,
                        cairo_status_to_string(status != CAIRO_STATUS_SUCCESS ? status : drawing));
    return PZ_OK;
}

static void set_metadata(cairo_surface_t *surface, const pz_pieces *pieces, const char *what)
{
    char title[160], clean[160];
    snprintf(title, sizeof title, "%s (%s): %s", pieces->garment_name, pieces->size_name, what);
    cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_TITLE, pz_utf8_clean(title, clean, sizeof clean));
    cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_CREATOR, "panelize " PZ_VERSION_STRING);
    /* cairo stamps the current time; SOURCE_DATE_EPOCH (the reproducible-builds convention) fixes it,
     * so the same pattern gives the same bytes. */
    const char *epoch = getenv("SOURCE_DATE_EPOCH");
    char *end = NULL;
    long long seconds = epoch && *epoch ? strtoll(epoch, &end, 10) : -1;
    struct tm utc;
    time_t when = (time_t)seconds;
    char date[32];
    if (seconds >= 0 && end && *end == '\0' && gmtime_r(&when, &utc) &&
        strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc) > 0) {
        cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_CREATE_DATE, date);
        cairo_pdf_surface_set_metadata(surface, CAIRO_PDF_METADATA_MOD_DATE, date);
    }
}

/* ------------------------------------------------------------------ pages of the 1:1 sheet */

/*
 * Acrobat (and the PDF spec's implementation limits) allow pages up to 14400
 * units, 200 in = 5080 mm. A sheet larger than kPageLimit in either direction
 * is cut into several 1:1 pages, each at most kPageLimit: first into bands
 * (top down), then each band into parts (left to right). A cut goes through
 * the middle of the last gap between pieces (their boxes 20 mm apart) that
 * keeps the page within the limit and at least kMinPage long, so no piece is
 * split; only when there is no such gap (a piece or a row longer than the
 * limit) is the cut made at the limit, and the next page then starts
 * kOverlap before it (the shared band is printed on both, as on the tiled
 * pages).
 */
static const double kPageLimit = 5000.0;   /* mm; 14173 pt, under 14400 */
static const double kMaxTiles = 20000.0;   /* tiles of the home print's grid (a 40 x 30 m sheet of A4) */
static const double kMinPage = 1250.0;     /* a page cut at a gap is at least this long */

/* An item's extent along one axis. */
typedef struct span {
    double lo, hi;
} span;

static int compare_span(const void *a, const void *b)
{
    const span *p = a, *q = b;
    return (p->lo > q->lo) - (p->lo < q->lo);
}

/*
 * Cuts [from, to] along `axis` (0: x, rising; 1: y, falling from the top) where no item box whose other-axis
 * range meets [other_lo, other_hi] lies; writes the page starts and ends as pairs (at most 2 * capacity values),
 * returns the number of pages (0 when out of memory).
 */
static int32_t split_axis(const sheet *sheet, int axis, double from, double to, double other_lo, double other_hi,
                          double *bounds, int32_t capacity)
{
    span *spans = malloc(((size_t)sheet->item_count + 2) * sizeof(span));
    if (!spans)
        return 0;
    int32_t count = 0, other = 1 - axis;
    /* In "distance from `from`" units, so both directions are one rising walk. */
    double sign = axis == 0 ? 1.0 : -1.0, length = fabs(to - from);
    for (int32_t i = 0; i < sheet->item_count; ++i) {
        const sheet_item *item = &sheet->items[i];
        if (item->hi[other] < other_lo || item->lo[other] > other_hi)
            continue;
        double a = sign * (item->lo[axis] - from), b = sign * (item->hi[axis] - from);
        spans[count++] = (span){fmin(a, b), fmax(a, b)};
    }
    if (axis == 1)   /* the title line along the top */
        spans[count++] = (span){0, kTitleBand};
    qsort(spans, (size_t)count, sizeof(span), compare_span);
    int32_t pages = 0;
    double start = 0;
    while (pages < capacity) {
        double end = length;
        if (length - start > kPageLimit) {
            /* The middle of the last gap between the merged spans that ends the page within the limit. */
            double reach = start + kPageLimit, covered = start, cut = -1;
            int32_t i = 0;
            for (; i < count && spans[i].lo < reach; ++i) {
                if (spans[i].lo > covered)
                    cut = 0.5 * (covered + spans[i].lo);
                covered = fmax(covered, spans[i].hi);
            }
            /* Free from `covered` to the next span (beyond the reach): its middle, or the reach. */
            double next = i < count ? spans[i].lo : length;
            if (covered < reach)
                cut = fmin(0.5 * (covered + next), reach);
            /* A gap too near the page's start would make a sliver of a page: cut through at the reach. */
            end = cut >= start + kMinPage ? cut : reach;
        }
        bounds[2 * pages] = from + sign * start;
        bounds[2 * pages + 1] = from + sign * end;
        ++pages;
        if (end >= length)
            break;
        /* A cut through ink (no gap): the next page repeats the overlap band. */
        int through_ink = 0;
        for (int32_t i = 0; i < count && !through_ink; ++i)
            through_ink = spans[i].lo < end && spans[i].hi > end;
        start = through_ink ? end - kOverlap : end;
    }
    free(spans);
    return pages;
}

/* The page regions of the sheet (lo x, lo y, hi x, hi y each; malloc'd), row by row from the top. */
static int32_t sheet_pages(const sheet *sheet, double **regions)
{
    /* Every page but the last advances at least kMinPage less the overlap along its axis. */
    int32_t capacity = (int32_t)(fmax(sheet->width, sheet->height) / (kMinPage - kOverlap)) + 2;
    double *rows = malloc(2 * (size_t)capacity * sizeof(double));
    double *columns = malloc(2 * (size_t)capacity * sizeof(double));
    *regions = malloc(4 * (size_t)capacity * (size_t)capacity * sizeof(double));
    int32_t count = 0, row_count = rows && columns && *regions
                                       ? split_axis(sheet, 1, sheet->height, 0, 0, sheet->width, rows, capacity)
                                       : 0;
    for (int32_t r = 0; r < row_count; ++r) {
        double top = rows[2 * r], bottom = rows[2 * r + 1];
        int32_t column_count = split_axis(sheet, 0, 0, sheet->width, bottom, top, columns, capacity);
        for (int32_t c = 0; c < column_count; ++c, ++count) {
            double *region = &(*regions)[4 * count];
            region[0] = columns[2 * c], region[1] = bottom, region[2] = columns[2 * c + 1], region[3] = top;
        }
        if (column_count == 0)
            row_count = 0, count = 0;
    }
    free(rows);
    free(columns);
    if (count == 0) {
        free(*regions);
        *regions = NULL;
    }
    return count;
}

/* A page of a split sheet: which part it is, in its top-left corner. */
static void draw_part_label(cairo_t *cr, const double *region, int32_t part, int32_t parts)
{
    char text[160];
    snprintf(text, sizeof text, "part %d of %d of the 1:1 sheet (a PDF page holds at most 5.08 m): join at the "
             "cut edges", (int)part, (int)parts);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    draw_text(cr, region[0] + 4, region[3] - 6, 4.0, text);
}

pz_status pz_export_write_pdf(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    sheet sheet;
    pz_status status = sheet_build(inputs->pieces, &sheet, ctx);
    if (status != PZ_OK)
        return status;
    double whole[4] = {0, 0, sheet.width, sheet.height}, *regions = whole;
    int32_t parts = 1;
    if (sheet.width > kPageLimit || sheet.height > kPageLimit) {
        parts = sheet_pages(&sheet, &regions);
        if (parts == 0) {
            free(sheet.items);
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
        }
    }
    pdf_stream stream = {file, 0};
    cairo_surface_t *surface = cairo_pdf_surface_create_for_stream(
        write_stream, &stream, (regions[2] - regions[0]) * PT_PER_MM, (regions[3] - regions[1]) * PT_PER_MM);
    set_metadata(surface, inputs->pieces, "pattern, 1:1");
    cairo_t *cr = cairo_create(surface);
    for (int32_t k = 0; k < parts; ++k) {
        const double *region = &regions[4 * k];
        cairo_pdf_surface_set_size(surface, (region[2] - region[0]) * PT_PER_MM, (region[3] - region[1]) * PT_PER_MM);
        cairo_save(cr);
        /* Sheet point (region lo x, region hi y), the region's top-left, at the page's top-left. */
        cairo_translate(cr, -region[0] * PT_PER_MM, -(sheet.height - region[3]) * PT_PER_MM);
        sheet_space(cr, sheet.height);
        cairo_rectangle(cr, region[0], region[1], region[2] - region[0], region[3] - region[1]);
        cairo_clip(cr);
        draw_sheet(cr, inputs, &sheet, parts > 1 ? region : NULL, parts > 1 ? region + 2 : NULL);
        if (parts > 1)
            draw_part_label(cr, region, k + 1, parts);
        cairo_restore(cr);
        cairo_show_page(cr);
    }
    if (regions != whole)
        free(regions);
    free(sheet.items);
    return finish(surface, cr, &stream, name, ctx);
}

/* ------------------------------------------------------------------ tiles */

typedef struct tiling {
    double paper[2];           /* mm, portrait */
    double printable[2];
    double step[2];            /* printable minus the overlap */
    int32_t columns, rows;
    uint8_t *inked;            /* rows x columns */
    int32_t page_count;        /* inked tiles */
} tiling;

/* The sheet region of tile (row, column): rows count from the top of the sheet. */
static void tile_region(const tiling *tiling, const sheet *sheet, int32_t row, int32_t column, double lo[2],
                        double hi[2])
{
    lo[0] = column * tiling->step[0];
    hi[0] = lo[0] + tiling->printable[0];
    hi[1] = sheet->height - row * tiling->step[1];
    lo[1] = hi[1] - tiling->printable[1];
}

/* 1 when segment a-b meets the box (Liang-Barsky clipping). */
static int segment_meets_box(const double *a, const double *b, const double lo[2], const double hi[2])
{
    double t0 = 0, t1 = 1, d[2] = {b[0] - a[0], b[1] - a[1]};
    for (int axis = 0; axis < 2; ++axis) {
        double p[2] = {-d[axis], d[axis]}, q[2] = {a[axis] - lo[axis], hi[axis] - a[axis]};
        for (int k = 0; k < 2; ++k) {
            if (p[k] == 0) {
                if (q[k] < 0)
                    return 0;
            } else {
                double t = q[k] / p[k];
                if (p[k] < 0)
                    t0 = fmax(t0, t);
                else
                    t1 = fmin(t1, t);
            }
        }
    }
    return t0 <= t1;
}

/* 1 when the closed polygon (offset) has ink in the box: an edge crosses it, or it covers the box. */
static int polygon_meets_box(const double *points, int32_t n, const double offset[2], const double lo[2],
                             const double hi[2])
{
    double centre[2] = {(lo[0] + hi[0]) / 2 - offset[0], (lo[1] + hi[1]) / 2 - offset[1]};
    int inside = 0;
    for (int32_t i = 0, j = n - 1; i < n; j = i++) {
        double a[2] = {points[2 * i] + offset[0], points[2 * i + 1] + offset[1]};
        double b[2] = {points[2 * j] + offset[0], points[2 * j + 1] + offset[1]};
        if (segment_meets_box(a, b, lo, hi))
            return 1;
        const double *p = &points[2 * i], *q = &points[2 * j];
        if ((p[1] > centre[1]) != (q[1] > centre[1]) &&
            centre[0] < (q[0] - p[0]) * (centre[1] - p[1]) / (q[1] - p[1]) + p[0])
            inside = !inside;
    }
    return inside;
}

static int tile_inked(const pz_pieces *pieces, const sheet *sheet, const double lo[2], const double hi[2])
{
    double title_lo[2] = {kPieceGap, sheet->height - kTitleBand};
    double title_hi[2] = {sheet->width / 2, sheet->height - kTitleBand + 10};
    if (boxes_meet(lo, hi, title_lo, title_hi))
        return 1;
    for (int32_t i = 0; i < sheet->item_count; ++i) {
        const sheet_item *item = &sheet->items[i];
        if (!boxes_meet(lo, hi, item->lo, item->hi))
            continue;
        if (item->piece < 0)
            return 1;
        const pz_piece *piece = &pieces->pieces[item->piece];
        if (polygon_meets_box(piece->cut, piece->cut_count, item->offset, lo, hi))
            return 1;
    }
    return 0;
}

/* ASCII case-insensitive equality. */
static int same_word(const char *a, const char *b)
{
    for (; *a && *b; ++a, ++b)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b))
            return 0;
    return *a == *b;
}

static pz_status tiling_build(const pz_export_inputs *inputs, const sheet *sheet, tiling *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    const char *paper = inputs->options && inputs->options->paper ? inputs->options->paper : "a4";
    int letter = same_word(paper, "letter");
    if (!letter && !same_word(paper, "a4"))
        return pz_error(ctx, PZ_ERR_USAGE, "pattern-tiled.pdf: paper '%s' is not a4 or letter", paper);
    out->paper[0] = letter ? 215.9 : 210.0;
    out->paper[1] = letter ? 279.4 : 297.0;
    for (int d = 0; d < 2; ++d) {
        out->printable[d] = out->paper[d] - 2 * kPaperMargin;
        out->step[d] = out->printable[d] - kOverlap;
    }
    out->columns = (int32_t)ceil((sheet->width - kOverlap) / out->step[0]);
    out->rows = (int32_t)ceil((sheet->height - kOverlap) / out->step[1]);
    out->columns = out->columns < 1 ? 1 : out->columns;
    out->rows = out->rows < 1 ? 1 : out->rows;
    /* A pattern no printer would tile (a garment read in the wrong units: 90 m tall) is refused, not drawn
     * for ever: a home print of more than kMaxTiles pages is not a pattern anyone prints. */
    if ((double)out->rows * (double)out->columns > kMaxTiles)
        return pz_error(ctx, PZ_ERR_DATA,
                        "pattern-tiled.pdf: the pattern is %.0f x %.0f mm, %d x %d pages: more than %d; is the garment "
                        "in the right units (--units)?",
                        sheet->width, sheet->height, (int)out->rows, (int)out->columns, (int)kMaxTiles);
    out->inked = calloc((size_t)out->rows * (size_t)out->columns, 1);
    if (!out->inked)
        return pz_error(ctx, PZ_ERR_NOMEM, "pdf: out of memory");
    for (int32_t r = 0; r < out->rows; ++r)
        for (int32_t c = 0; c < out->columns; ++c) {
            double lo[2], hi[2];
            tile_region(out, sheet, r, c, lo, hi);
            /* Ink only in the band shared with the tile above or to the left is printed there already. */
            if (r > 0)
                hi[1] -= kOverlap;
            if (c > 0)
                lo[0] += kOverlap;
            uint8_t inked = (uint8_t)tile_inked(inputs->pieces, sheet, lo, hi);
            out->inked[r * out->columns + c] = inked;
            out->page_count += inked;
        }
    return PZ_OK;
}

/* Page 1: the sheet scaled to fit, the tile grid over it, each tile's row and column. */
static void draw_cover(cairo_t *cr, const pz_export_inputs *inputs, const sheet *sheet, const tiling *tiling)
{
    double grid_w = tiling->columns * tiling->step[0] + kOverlap, grid_h = tiling->rows * tiling->step[1] + kOverlap;
    double room[2] = {tiling->printable[0], tiling->printable[1] - 40};
    double scale = fmin(room[0] / grid_w, room[1] / grid_h);
    double origin[2] = {kPaperMargin, kPaperMargin + 30};
    char text[200];
    cairo_save(cr);
    cairo_scale(cr, PT_PER_MM, PT_PER_MM);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 7);
    cairo_move_to(cr, kPaperMargin, kPaperMargin + 8);
    snprintf(text, sizeof text, "%s - size %s - tiled pattern", inputs->pieces->garment_name,
             inputs->pieces->size_name);
    show_text(cr, text);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 4);
    cairo_move_to(cr, kPaperMargin, kPaperMargin + 16);
    snprintf(text, sizeof text, "%d of %d x %d tiles printed (blank ones dropped), %s, 1 cm overlap: print at 100%%",
             (int)tiling->page_count, (int)tiling->rows, (int)tiling->columns,
             tiling->paper[0] > 211 ? "Letter" : "A4");
    cairo_show_text(cr, text);
    cairo_move_to(cr, kPaperMargin, kPaperMargin + 22);
    cairo_show_text(cr, "Trim each page on its trim marks, overlap the dashed bands, check the 10 cm box.");

    /* The sheet, scaled: y up inside the grid's box. */
    cairo_save(cr);
    cairo_translate(cr, origin[0], origin[1]);
    cairo_scale(cr, scale, scale);
    cairo_save(cr);
    cairo_translate(cr, 0, grid_h);
    cairo_scale(cr, 1, -1);
    cairo_translate(cr, 0, grid_h - sheet->height); /* the sheet's top at the grid's top */
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_line_width(cr, 0.6 / scale);
    for (int32_t i = 0; i < sheet->item_count; ++i) {
        const sheet_item *item = &sheet->items[i];
        if (item->piece < 0) {
            cairo_rectangle(cr, item->lo[0], item->lo[1], kScaleBox, kScaleBox);
        } else {
            const pz_piece *piece = &inputs->pieces->pieces[item->piece];
            path_polyline(cr, piece->cut, piece->cut_count, item->offset, 1);
        }
        cairo_stroke(cr);
    }
    cairo_restore(cr);
    cairo_set_line_width(cr, 0.3 / scale);
    cairo_set_font_size(cr, 4.0 / scale);
    for (int32_t r = 0; r < tiling->rows; ++r)
        for (int32_t c = 0; c < tiling->columns; ++c) {
            double x = c * tiling->step[0], y = r * tiling->step[1];
            int inked = tiling->inked[r * tiling->columns + c];
            cairo_rectangle(cr, x, y, tiling->printable[0], tiling->printable[1]);
            if (!inked) {
                cairo_set_source_rgba(cr, 0.5, 0.5, 0.5, 0.25);
                cairo_fill_preserve(cr);
            }
            cairo_set_source_rgb(cr, 0, 0, inked ? 0.8 : 0.4);
            cairo_stroke(cr);
            snprintf(text, sizeof text, "%d,%d", (int)r + 1, (int)c + 1);
            cairo_move_to(cr, x + 0.5 * tiling->step[0] - 6.0 / scale, y + 0.5 * tiling->step[1]);
            cairo_show_text(cr, text);
        }
    cairo_restore(cr);
    cairo_restore(cr);
}

/* Trim marks just outside the printable area's corners, the overlap bands, the label. */
static void draw_tile_frame(cairo_t *cr, const tiling *tiling, int32_t row, int32_t column, int page, int pages)
{
    const double m = kPaperMargin, w = tiling->printable[0], h = tiling->printable[1], tick = 6.0, away = 1.0;
    cairo_save(cr);
    cairo_scale(cr, PT_PER_MM, PT_PER_MM);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.2);
    const double corner[4][2] = {{m, m}, {m + w, m}, {m, m + h}, {m + w, m + h}};
    for (int k = 0; k < 4; ++k) {
        double sx = k % 2 ? 1 : -1, sy = k / 2 ? 1 : -1;
        cairo_move_to(cr, corner[k][0] + sx * away, corner[k][1]);
        cairo_line_to(cr, corner[k][0] + sx * (away + tick), corner[k][1]);
        cairo_move_to(cr, corner[k][0], corner[k][1] + sy * away);
        cairo_line_to(cr, corner[k][0], corner[k][1] + sy * (away + tick));
    }
    cairo_stroke(cr);
    /* The bands the next tile covers (right and below), dashed. */
    const double dash[2] = {2.0, 2.0};
    cairo_set_dash(cr, dash, 2, 0);
    cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
    if (column + 1 < tiling->columns) {
        cairo_move_to(cr, m + w - kOverlap, m);
        cairo_line_to(cr, m + w - kOverlap, m + h);
    }
    if (row + 1 < tiling->rows) {
        cairo_move_to(cr, m, m + h - kOverlap);
        cairo_line_to(cr, m + w, m + h - kOverlap);
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);
    char label[96];
    snprintf(label, sizeof label, "row %d col %d, page %d of %d", (int)row + 1, (int)column + 1, page, pages);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 3.5);
    cairo_move_to(cr, m + 8, m + h + 6);
    cairo_show_text(cr, label);
    cairo_restore(cr);
}

static void draw_tile(cairo_t *cr, const pz_export_inputs *inputs, const sheet *sheet, const tiling *tiling,
                      int32_t row, int32_t column)
{
    double lo[2], hi[2];
    tile_region(tiling, sheet, row, column, lo, hi);
    cairo_save(cr);
    cairo_rectangle(cr, kPaperMargin * PT_PER_MM, kPaperMargin * PT_PER_MM, tiling->printable[0] * PT_PER_MM,
                    tiling->printable[1] * PT_PER_MM);
    cairo_clip(cr);
    /* Sheet point (lo[0], hi[1]) (the region's top-left) lands on the printable area's top-left. */
    cairo_translate(cr, (kPaperMargin - lo[0]) * PT_PER_MM, (kPaperMargin - (sheet->height - hi[1])) * PT_PER_MM);
    sheet_space(cr, sheet->height);
    draw_sheet(cr, inputs, sheet, lo, hi);
    cairo_restore(cr);
}

pz_status pz_export_write_pdf_tiled(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    sheet sheet;
    pz_status status = sheet_build(inputs->pieces, &sheet, ctx);
    if (status != PZ_OK)
        return status;
    tiling tiling;
    if ((status = tiling_build(inputs, &sheet, &tiling, ctx)) != PZ_OK) {
        free(sheet.items);
        return status;
    }
    pdf_stream stream = {file, 0};
    cairo_surface_t *surface = cairo_pdf_surface_create_for_stream(write_stream, &stream, tiling.paper[0] * PT_PER_MM,
                                                                   tiling.paper[1] * PT_PER_MM);
    set_metadata(surface, inputs->pieces, "tiled pattern");
    cairo_t *cr = cairo_create(surface);
    draw_cover(cr, inputs, &sheet, &tiling);
    cairo_show_page(cr);
    int page = 1, pages = tiling.page_count + 1;
    for (int32_t r = 0; r < tiling.rows; ++r)
        for (int32_t c = 0; c < tiling.columns; ++c) {
            if (!tiling.inked[r * tiling.columns + c])
                continue;
            draw_tile(cr, inputs, &sheet, &tiling, r, c);
            draw_tile_frame(cr, &tiling, r, c, ++page, pages);
            cairo_show_page(cr);
        }
    free(tiling.inked);
    free(sheet.items);
    return finish(surface, cr, &stream, name, ctx);
}
