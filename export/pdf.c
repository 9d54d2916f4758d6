/*
 * export/pdf.c -- pattern.pdf (one sheet at 1:1) through cairo, and the
 * drawing of pieces that pattern-tiled.pdf (export/pdf_tiled.c) shares.
 *
 * The sheet: every drawn piece (pz_piece.mirrored == 0) where
 * pz_pieces_sheet_layout puts it (the layout of pattern.svg: rows, tallest
 * first, 20 mm apart), under a band with the title and the 10 cm scale box (a
 * 100 x 100 mm square at the top left, drawn as one rectangle so its size can
 * be read back from the PDF). Pieces
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
 * pattern-tiled.pdf (the pieces on A4 or Letter pages) is export/pdf_tiled.c,
 * which draws with this file's functions (export/pdf_internal.h).
 *
 * Text that is not UTF-8 is shown with '?' (cairo refuses it). The creation
 * date is SOURCE_DATE_EPOCH's when set (byte-identical output), else now.
 * Errors: PZ_ERR_CREATE when the stream fails, PZ_ERR_USAGE for a paper
 * other than a4 or letter, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L /* gmtime_r */
#include "export/pdf_internal.h"
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
static const double kOverlap = 10.0;       /* printed on both pages where a cut goes through ink */

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
    /* The scale box first, top left under the title. */
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
void pdf_show_text(cairo_t *cr, const char *text)
{
    char clean[256];
    cairo_show_text(cr, pz_utf8_clean(text, clean, sizeof clean));
}

/* Text at (x, y) (sheet mm, y up), `size` mm high, upright. */
void pdf_text(cairo_t *cr, double x, double y, double size, const char *text)
{
    cairo_save(cr);
    cairo_move_to(cr, x, y);
    cairo_scale(cr, 1, -1);
    cairo_set_font_size(cr, size);
    pdf_show_text(cr, text);
    cairo_restore(cr);
}

void pdf_polyline(cairo_t *cr, const double *points, int32_t n, const double offset[2], int closed)
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
    snprintf(lines[1], sizeof lines[1], "%s", pz_piece_cut_text(piece));
    snprintf(lines[2], sizeof lines[2], "%s", pieces->garment_name);
    snprintf(lines[3], sizeof lines[3], "size %s", pieces->size_name);
    snprintf(lines[4], sizeof lines[4], "%.0f x %.0f mm", piece->bbox_max[0] - piece->bbox_min[0],
             piece->bbox_max[1] - piece->bbox_min[1]);
    double size = 5.0 * scale, x = (lo[0] + hi[0]) / 2 + offset[0] + 3 * scale;
    double y = (lo[1] + hi[1]) / 2 + offset[1] + 2 * size;
    for (int l = 0; l < 5; ++l, y -= 1.4 * size)
        pdf_text(cr, x, y, l == 0 ? 1.3 * size : size, lines[l]);
}

/* Everything of one piece at `offset` (sheet mm). */
void pdf_draw_piece(cairo_t *cr, const pz_pieces *pieces, const pz_piece *piece, const double offset[2])
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.5);
    cairo_set_dash(cr, NULL, 0, 0);
    pdf_polyline(cr, piece->cut, piece->cut_count, offset, 1);
    cairo_stroke(cr);

    const double dash[2] = {3.0, 2.0};
    cairo_set_line_width(cr, 0.3);
    cairo_set_dash(cr, dash, 2, 0);
    pdf_polyline(cr, piece->sew, piece->sew_count, offset, 1);
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);

    for (int32_t l = 0; l < piece->line_count; ++l) {
        pdf_polyline(cr, piece->lines[l].points, piece->lines[l].point_count, offset, 0);
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
            pdf_text(cr, notch->position[0] + offset[0] - 6 * notch->direction[0] - 2,
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
    pdf_text(cr, item->lo[0] + 35, item->lo[1] + 47, 10.0, "10 cm");
}

static void draw_title(cairo_t *cr, const pz_pieces *pieces, const sheet *sheet)
{
    char title[200];
    snprintf(title, sizeof title, "%s - size %s - %d pieces - print at 100%% (scale box = 10 cm)",
             pieces->garment_name, pieces->size_name, (int)(sheet->item_count - 1));
    cairo_set_source_rgb(cr, 0, 0, 0);
    pdf_text(cr, kPieceGap, sheet->height - kTitleBand + 4, 6.0, title);
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
            pdf_draw_piece(cr, inputs->pieces, &inputs->pieces->pieces[item->piece], item->offset);
    }
}

/* ------------------------------------------------------------------ streams */

cairo_status_t pdf_write_stream(void *closure, const unsigned char *data, unsigned int length)
{
    pdf_stream *stream = closure;
    if (fwrite(data, 1, length, stream->file) == length)
        return CAIRO_STATUS_SUCCESS;
    if (!stream->error)
        stream->error = errno ? errno : EIO;
    return CAIRO_STATUS_WRITE_ERROR;
}

/* Finishes the surface and turns cairo's and the stream's state into a status. */
pz_status pdf_finish(cairo_surface_t *surface, cairo_t *cr, pdf_stream *stream, const char *name, pz_ctx *ctx)
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

void pdf_set_metadata(cairo_surface_t *surface, const pz_pieces *pieces, const char *what)
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
    pdf_text(cr, region[0] + 4, region[3] - 6, 4.0, text);
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
        pdf_write_stream, &stream, (regions[2] - regions[0]) * PT_PER_MM, (regions[3] - regions[1]) * PT_PER_MM);
    pdf_set_metadata(surface, inputs->pieces, "pattern, 1:1");
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
    return pdf_finish(surface, cr, &stream, name, ctx);
}
