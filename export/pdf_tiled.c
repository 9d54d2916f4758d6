/*
 * export/pdf_tiled.c -- pattern-tiled.pdf: the pieces on A4 or Letter pages
 * for a home printer, as export/tiled_layout.c lays them out (docs/export.md,
 * "pattern-tiled.pdf"), drawn with pattern.pdf's functions
 * (export/pdf_internal.h).
 *
 * Page 1, the cover: the title, how to print and assemble, where every piece
 * is (its page, or the pages of the sheet it is nested on), and a map of the
 * sheet of the pieces larger than a page: the pieces' outlines with the
 * printed tiles and their page numbers. Then the pages: each has trim marks
 * just outside the printable area's corners and "page N of M" (the cover
 * counted) in its bottom margin, with a tile's "sheet row R col C" and the
 * names of the pieces on it; a tile page dashes the 10 mm bands it shares
 * with printed neighbours (lay them over each other when assembling).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"
#include "export/pdf_internal.h"

#include <cairo-pdf.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double kPaperMargin = 10.0; /* unprintable border of a page (as tiled_layout.c's) */
static const double kScaleBox = 100.0;   /* the scale square's side */
static const double kScaleLeft = 0.0;    /* its left edge in the scale box's item (tiled_layout.c: 100 x 108) */

/* User space: millimetres, y up, (0, 0) at the printable area's lower left. */
static void printable_space(cairo_t *cr, const tiled_layout *layout)
{
    cairo_scale(cr, PT_PER_MM, PT_PER_MM);
    cairo_translate(cr, kPaperMargin, layout->paper[1] - kPaperMargin);
    cairo_scale(cr, 1, -1);
}

static void draw_scale_box(cairo_t *cr)
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.3);
    cairo_set_dash(cr, NULL, 0, 0);
    cairo_rectangle(cr, kScaleLeft, 0, kScaleBox, kScaleBox);
    cairo_stroke(cr);
    pdf_text(cr, kScaleLeft + 35, 47, 10.0, "10 cm");
    pdf_text(cr, kScaleLeft, kScaleBox + 3, 4.0, "print at 100%: this square is 10 cm");
}

/* Item `index` as page `page` shows it (whole, or its part on this tile: the page's clip cuts the rest). */
static void draw_item(cairo_t *cr, const tiled_layout *layout, const pz_pieces *pieces, int32_t index,
                      int32_t page)
{
    const tiled_item *item = &layout->items[index];
    double move[2], zero[2] = {0, 0};
    if (!tiled_item_on_page(layout, index, page, move))
        return;
    cairo_save(cr);
    cairo_translate(cr, move[0], move[1]);
    if (item->turned) {
        cairo_matrix_t turn; /* (x, y) -> (-y, x), exactly */
        cairo_matrix_init(&turn, 0, 1, -1, 0, 0, 0);
        cairo_transform(cr, &turn);
    }
    if (item->piece < 0)
        draw_scale_box(cr);
    else
        pdf_draw_piece(cr, pieces, &pieces->pieces[item->piece], zero);
    cairo_restore(cr);
}

static int tile_printed(const tiled_layout *layout, int32_t row, int32_t column)
{
    return row >= 0 && column >= 0 && row < layout->sheet_rows && column < layout->sheet_columns &&
           layout->tile_page[row * layout->sheet_columns + column] >= 0;
}

/* Trim marks just outside the printable area's corners; a tile's shared bands dashed; the label. */
static void draw_frame(cairo_t *cr, const tiled_layout *layout, const pz_pieces *pieces, int32_t page)
{
    const double w = layout->printable[0], h = layout->printable[1], tick = 6.0, away = 1.0, band = layout->overlap;
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.2);
    cairo_set_dash(cr, NULL, 0, 0);
    const double corner[4][2] = {{0, 0}, {w, 0}, {0, h}, {w, h}};
    for (int k = 0; k < 4; ++k) {
        double sx = k % 2 ? 1 : -1, sy = k / 2 ? 1 : -1;
        cairo_move_to(cr, corner[k][0] + sx * away, corner[k][1]);
        cairo_line_to(cr, corner[k][0] + sx * (away + tick), corner[k][1]);
        cairo_move_to(cr, corner[k][0], corner[k][1] + sy * away);
        cairo_line_to(cr, corner[k][0], corner[k][1] + sy * (away + tick));
    }
    cairo_stroke(cr);
    const tiled_page *p = &layout->pages[page];
    char label[240];
    int used = snprintf(label, sizeof label, "page %d of %d", (int)page + 2, (int)layout->page_count + 1);
    if (p->row >= 0) {
        const double dash[2] = {2.0, 2.0};
        cairo_set_dash(cr, dash, 2, 0);
        cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
        const double lines[4][4] = {{band, 0, band, h}, {w - band, 0, w - band, h}, {0, h - band, w, h - band},
                                    {0, band, w, band}};
        const int present[4] = {tile_printed(layout, p->row, p->column - 1), tile_printed(layout, p->row, p->column + 1),
                                tile_printed(layout, p->row - 1, p->column), tile_printed(layout, p->row + 1, p->column)};
        for (int k = 0; k < 4; ++k)
            if (present[k]) {
                cairo_move_to(cr, lines[k][0], lines[k][1]);
                cairo_line_to(cr, lines[k][2], lines[k][3]);
            }
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        cairo_set_source_rgb(cr, 0, 0, 0);
        used += snprintf(label + used, sizeof label - (size_t)used, " - sheet row %d col %d", (int)p->row + 1,
                         (int)p->column + 1);
    }
    int named = 0;
    for (int32_t i = 0; i < layout->item_count && used < (int)sizeof label - 1; ++i) {
        double move[2];
        if (layout->items[i].piece >= 0 && tiled_item_on_page(layout, i, page, move))
            used += snprintf(label + used, sizeof label - (size_t)used, "%s%s", named++ ? ", " : ": ",
                             pieces->pieces[layout->items[i].piece].name);
    }
    pdf_text(cr, 8, -6, 3.5, label);
}

/* The cover's map of the sheet in the box [0, w] x [0, h] (page mm, y up): outlines, printed tiles, pages. */
static void draw_sheet_map(cairo_t *cr, const tiled_layout *layout, const pz_pieces *pieces, double w, double h)
{
    if (layout->sheet_rows == 0)
        return;
    double size[2] = {layout->sheet_columns * layout->step[0] + layout->overlap,
                      layout->sheet_rows * layout->step[1] + layout->overlap};
    double scale = fmin(w / size[0], h / size[1]);
    cairo_save(cr);
    /* Sheet coordinates (y down from the sheet's top-left) into the box's top-left. */
    cairo_translate(cr, 0, h);
    cairo_scale(cr, scale, -scale);
    cairo_set_line_width(cr, 0.3 / scale);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    for (int32_t i = 0; i < layout->item_count; ++i) {
        const tiled_item *item = &layout->items[i];
        if (!item->on_sheet)
            continue;
        double *outline = tiled_sheet_outline(pieces, item, item->at);
        if (!outline)
            continue; /* out of memory: that outline is not drawn */
        double zero[2] = {0, 0};
        pdf_polyline(cr, outline, pieces->pieces[item->piece].cut_count, zero, 1);
        cairo_stroke(cr);
        free(outline);
    }
    char text[16];
    for (int32_t r = 0; r < layout->sheet_rows; ++r)
        for (int32_t c = 0; c < layout->sheet_columns; ++c) {
            int32_t page = layout->tile_page[r * layout->sheet_columns + c];
            if (page < 0)
                continue;
            double x = c * layout->step[0], y = r * layout->step[1];
            cairo_set_source_rgb(cr, 0, 0, 0.8);
            cairo_rectangle(cr, x, y, layout->printable[0], layout->printable[1]);
            cairo_stroke(cr);
            snprintf(text, sizeof text, "%d", (int)page + 2);
            cairo_save(cr); /* the map's y runs down, as text does: no flip */
            cairo_move_to(cr, x + 0.4 * layout->step[0], y + 0.55 * layout->step[1]);
            cairo_set_font_size(cr, fmin(4.0 / scale, 0.3 * layout->step[0]));
            cairo_show_text(cr, text);
            cairo_restore(cr);
        }
    cairo_restore(cr);
}

/* Page 1: what the pages hold and where each piece is. */
static void draw_cover(cairo_t *cr, const tiled_layout *layout, const pz_pieces *pieces)
{
    const double w = layout->printable[0], h = layout->printable[1];
    char text[240];
    cairo_set_source_rgb(cr, 0, 0, 0);
    snprintf(text, sizeof text, "%s - size %s - pattern for home printing", pieces->garment_name, pieces->size_name);
    pdf_text(cr, 0, h - 8, 5.0, text);
    int32_t whole = 0, sheet = 0;
    for (int32_t i = 0; i < layout->item_count; ++i)
        if (layout->items[i].piece >= 0) {
            sheet += layout->items[i].on_sheet;
            whole += !layout->items[i].on_sheet;
        }
    snprintf(text, sizeof text, "%d pages of %s after this one: %d pieces whole on a page, %d across pages",
             (int)layout->page_count, layout->paper[0] > 211 ? "Letter" : "A4", (int)whole, (int)sheet);
    pdf_text(cr, 0, h - 16, 3.5, text);
    pdf_text(cr, 0, h - 21, 3.5, "Print at 100% (page 2 has a 10 cm square). Pieces across pages lie on one sheet (map");
    pdf_text(cr, 0, h - 26, 3.5, "below): trim its pages on their trim marks, lay the dashed 1 cm bands over each other.");
    /* One line per piece in the upper half; the font shrinks so that every piece has its line. */
    int32_t lines = layout->item_count > 1 ? layout->item_count - 1 : 1;
    double room = sheet ? h / 2 - 34 : h - 40;
    double size = fmin(3.5, room / (1.4 * lines)), y = h - 34;
    for (int32_t i = 0; i < layout->item_count; ++i) {
        const tiled_item *item = &layout->items[i];
        if (item->piece < 0)
            continue;
        const pz_piece *piece = &pieces->pieces[item->piece];
        if (!item->on_sheet) {
            snprintf(text, sizeof text, "%s (%s): page %d%s", piece->name, pz_piece_cut_text(piece),
                     (int)item->page + 2, item->turned ? ", turned" : "");
        } else {
            int used = snprintf(text, sizeof text, "%s (%s): sheet, pages", piece->name, pz_piece_cut_text(piece));
            double move[2];
            for (int32_t page = 0; page < layout->page_count && used < (int)sizeof text - 8; ++page)
                if (layout->pages[page].row >= 0 && tiled_item_on_page(layout, i, page, move))
                    used += snprintf(text + used, sizeof text - (size_t)used, " %d", (int)page + 2);
        }
        pdf_text(cr, 0, y, size, text);
        y -= 1.4 * size;
    }
    if (sheet)
        draw_sheet_map(cr, layout, pieces, w, h / 2 - 5);
}

pz_status pz_export_write_pdf_tiled(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    tiled_layout layout;
    const char *paper = inputs->options ? inputs->options->paper : NULL;
    pz_status status = tiled_layout_build(inputs->pieces, paper, &layout, ctx);
    if (status != PZ_OK)
        return status;
    pdf_stream stream = {file, 0};
    cairo_surface_t *surface = cairo_pdf_surface_create_for_stream(pdf_write_stream, &stream,
                                                                   layout.paper[0] * PT_PER_MM,
                                                                   layout.paper[1] * PT_PER_MM);
    pdf_set_metadata(surface, inputs->pieces, "tiled pattern");
    cairo_t *cr = cairo_create(surface);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
    cairo_save(cr);
    printable_space(cr, &layout);
    draw_cover(cr, &layout, inputs->pieces);
    cairo_restore(cr);
    cairo_show_page(cr);
    for (int32_t page = 0; page < layout.page_count; ++page) {
        cairo_save(cr);
        printable_space(cr, &layout);
        draw_frame(cr, &layout, inputs->pieces, page);
        cairo_rectangle(cr, 0, 0, layout.printable[0], layout.printable[1]);
        cairo_clip(cr);
        for (int32_t i = 0; i < layout.item_count; ++i)
            draw_item(cr, &layout, inputs->pieces, i, page);
        cairo_restore(cr);
        cairo_show_page(cr);
    }
    tiled_layout_free(&layout);
    return pdf_finish(surface, cr, &stream, name, ctx);
}
