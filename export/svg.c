/*
 * export/svg.c -- pattern.svg: every drawn piece at 1:1 on one sheet.
 *
 * 1 user unit = 1 mm; width and height carry "mm" and the viewBox is the
 * sheet in mm, so any viewer or printer keeps the scale. SVG's y axis points
 * down: a sheet point (x, y up) is drawn at (x, height - y), so the warp
 * (+v) points up on paper. Pieces are laid out by pz_pieces_sheet_layout
 * (rows, cut-line boxes, no overlap) below a band holding the title and the
 * 10 cm scale box.
 *
 * Each piece is one <g id="panel_K" class="piece"> with separate paths:
 * class "cut" (solid), "sew" (dashed), "notch" (from the cut line inward),
 * "dart" (legs, fold line, tip mark), "grainline" (with its arrowhead), and
 * texts: name, cut count ("Cut 1", "Cut 2 mirrored"), garment, size, the
 * piece's extent (cut-line box, mm), notch labels (notches at one place,
 * such as the ends of two seams at a corner, drawn once: "X5 I1"). The second piece of a
 * mirrored pair is not drawn (its partner says "Cut 2 mirrored").
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/notches.h"
#include "export/stream_status.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdlib.h>

#define SHEET_GAP_MM 20.0
#define BAND_MM 140.0       /* title + 10 cm scale box */
#define SCALE_MM 100.0

typedef struct sheet {
    FILE *file;
    double height;
    double offset[2];
} sheet;

static void point(const sheet *s, const char *command, const double p[2])
{
    fprintf(s->file, "%s%.3f %.3f", command, p[0] + s->offset[0], s->height - (p[1] + s->offset[1]));
}

static void polyline(const sheet *s, const double *points, int32_t count, int closed)
{
    for (int32_t i = 0; i < count; ++i)
        point(s, i == 0 ? "M" : " L", &points[2 * i]);
    if (closed)
        fputs(" Z", s->file);
}

/* Text at a piece point, `size` mm high, centred. */
static void text(const sheet *s, const char *class_name, const double p[2], double size, const char *content)
{
    fprintf(s->file, "<text class=\"%s\" x=\"%.3f\" y=\"%.3f\" font-size=\"%.2f\" text-anchor=\"middle\">",
            class_name, p[0] + s->offset[0], s->height - (p[1] + s->offset[1]), size);
    pz_xml_put_text(s->file, content);
    fputs("</text>\n", s->file);
}

/* Notches from the cut line inward, drawn once per place with their labels joined ("X5 I1"). 0: out of memory. */
static int write_notches(const sheet *s, const pz_piece *piece)
{
    if (piece->notch_count == 0)
        return 1;
    char(*labels)[PZ_NOTCH_LABELS_MAX] = malloc((size_t)piece->notch_count * sizeof *labels);
    if (!labels || !pz_piece_notch_labels(piece, labels)) {
        free(labels);
        return 0;
    }
    fputs("<path class=\"notch\" fill=\"none\" stroke=\"#000000\" stroke-width=\"0.5\" d=\"", s->file);
    for (int32_t i = 0, drawn = 0; i < piece->notch_count; ++i) {
        const pz_notch *n = &piece->notches[i];
        if (!labels[i][0])
            continue;
        double inner[2] = {n->cut_point[0] - n->depth_mm * n->direction[0],
                           n->cut_point[1] - n->depth_mm * n->direction[1]};
        point(s, drawn++ == 0 ? "M" : " M", n->cut_point);
        point(s, " L", inner);
    }
    fputs("\"/>\n", s->file);
    for (int32_t i = 0; i < piece->notch_count; ++i) {
        const pz_notch *n = &piece->notches[i];
        double at[2] = {n->position[0] - 4 * n->direction[0], n->position[1] - 4 * n->direction[1] - 1};
        if (labels[i][0])
            text(s, "notch-label", at, 3.0, labels[i]);
    }
    free(labels);
    return 1;
}

static void write_grainline(const sheet *s, const pz_piece *piece)
{
    const double *tail = piece->grain[0], *head = piece->grain[1];
    double length = head[1] - tail[1], arrow = fmin(0.08 * length, 15.0);
    double left[2] = {head[0] - 0.5 * arrow, head[1] - arrow}, right[2] = {head[0] + 0.5 * arrow, head[1] - arrow};
    fputs("<path class=\"grainline\" fill=\"none\" stroke=\"#b00000\" stroke-width=\"0.8\" d=\"", s->file);
    point(s, "M", tail);
    point(s, " L", head);
    point(s, " M", left);
    point(s, " L", head);
    point(s, " L", right);
    fputs("\"/>\n", s->file);
}

static void write_labels(const sheet *s, const pz_piece *piece, const pz_pieces *pieces)
{
    double width = piece->bbox_max[0] - piece->bbox_min[0], height = piece->bbox_max[1] - piece->bbox_min[1];
    double size = fmax(4.0, fmin(16.0, 0.05 * fmin(width, height)));
    double at[2] = {piece->grain[0][0] + 2.5 * size, 0.5 * (piece->grain[0][1] + piece->grain[1][1]) + 2 * size};
    char line[160];
    text(s, "name", at, size, piece->name);
    at[1] -= 1.4 * size;
    text(s, "cut-count", at, 0.8 * size, pz_piece_cut_text(piece));
    at[1] -= 1.2 * size;
    text(s, "garment", at, 0.8 * size, pieces->garment_name);
    at[1] -= 1.2 * size;
    snprintf(line, sizeof line, "Size: %s", pieces->size_name);
    text(s, "size", at, 0.8 * size, line);
    at[1] -= 1.2 * size;
    snprintf(line, sizeof line, "%.0f x %.0f mm (cut)", width, height);
    text(s, "dimensions", at, 0.7 * size, line);
}

/* One piece's group. 0 when out of memory. */
static int write_piece(sheet *s, const pz_piece *piece, const pz_pieces *pieces, const double offset[2])
{
    s->offset[0] = offset[0];
    s->offset[1] = offset[1];
    fprintf(s->file, "<g id=\"panel_%d\" class=\"piece\">\n", (int)piece->panel);
    fputs("<path class=\"cut\" fill=\"none\" stroke=\"#000000\" stroke-width=\"0.6\" d=\"", s->file);
    polyline(s, piece->cut, piece->cut_count, 1);
    fputs("\"/>\n<path class=\"sew\" fill=\"none\" stroke=\"#404040\" stroke-width=\"0.3\" "
          "stroke-dasharray=\"3 1.5\" d=\"",
          s->file);
    polyline(s, piece->sew, piece->sew_count, 1);
    fputs("\"/>\n", s->file);
    if (!write_notches(s, piece))
        return 0;
    if (piece->line_count > 0) {
        fputs("<path class=\"dart\" fill=\"none\" stroke=\"#0050b0\" stroke-width=\"0.4\" d=\"", s->file);
        for (int32_t i = 0; i < piece->line_count; ++i) {
            if (i > 0)
                fputc(' ', s->file);
            polyline(s, piece->lines[i].points, piece->lines[i].point_count, 0);
        }
        fputs("\"/>\n", s->file);
    }
    write_grainline(s, piece);
    write_labels(s, piece, pieces);
    fputs("</g>\n", s->file);
    return 1;
}

static void write_band(const sheet *s, const pz_pieces *pieces)
{
    double top = SHEET_GAP_MM;
    fprintf(s->file, "<text class=\"title\" x=\"%.3f\" y=\"%.3f\" font-size=\"8\">", SHEET_GAP_MM, top);
    pz_xml_put_text(s->file, pieces->garment_name);
    fputs(" - size ", s->file);
    pz_xml_put_text(s->file, pieces->size_name);
    fputs(" - 1:1, units mm</text>\n", s->file);
    double y = top + 6;
    fprintf(s->file,
            "<g id=\"scale\"><rect class=\"scale\" x=\"%.3f\" y=\"%.3f\" width=\"%.3f\" height=\"%.3f\" "
            "fill=\"none\" stroke=\"#000000\" stroke-width=\"0.3\"/>\n"
            "<text x=\"%.3f\" y=\"%.3f\" font-size=\"6\" text-anchor=\"middle\">10 cm x 10 cm</text></g>\n",
            SHEET_GAP_MM, y, SCALE_MM, SCALE_MM, SHEET_GAP_MM + 0.5 * SCALE_MM, y + 0.5 * SCALE_MM);
}

pz_status pz_export_write_svg(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    const pz_pieces *pieces = inputs->pieces;
    double *offsets = malloc(2 * (size_t)pieces->piece_count * sizeof(double) + 1), size[2];
    if (!offsets)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    pz_pieces_sheet_layout(pieces, SHEET_GAP_MM, BAND_MM, offsets, size);
    size[0] = fmax(size[0], SCALE_MM + 2 * SHEET_GAP_MM + 200);
    sheet s = {file, size[1], {0, 0}};
    fprintf(file,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<!-- panelize: pattern pieces at 1:1, 1 user unit = 1 mm; solid = cut line, dashed = sew line -->\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.3fmm\" height=\"%.3fmm\" "
            "viewBox=\"0 0 %.3f %.3f\" font-family=\"sans-serif\">\n",
            size[0], size[1], size[0], size[1]);
    write_band(&s, pieces);
    int ok = 1;
    for (int32_t p = 0; p < pieces->piece_count && ok; ++p)
        if (!pieces->pieces[p].mirrored)
            ok = write_piece(&s, &pieces->pieces[p], pieces, &offsets[2 * p]);
    fputs("</svg>\n", file);
    free(offsets);
    if (!ok)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    return pz_export_stream_status(file, 0, name, ctx);
}
