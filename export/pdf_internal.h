/*
 * export/pdf_internal.h -- what the two PDF writers share, not part of the
 * public interface (export/export.h is): export/pdf.c (pattern.pdf, the 1:1
 * sheet) draws pieces and runs the cairo stream; export/pdf_tiled.c
 * (pattern-tiled.pdf, pages for a home printer) lays the pieces out on pages
 * and draws them with the same functions. Drawing functions take user space
 * in millimetres with y up.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_PDF_INTERNAL_H
#define PZ_EXPORT_PDF_INTERNAL_H

#include "export/export.h"

#include <cairo.h>
#include <stdio.h>

#define PT_PER_MM (72.0 / 25.4)

/* The PDF's stream: cairo calls pdf_write_stream; the first failure's errno is kept for the message. */
typedef struct pdf_stream {
    FILE *file;
    int error;
} pdf_stream;

cairo_status_t pdf_write_stream(void *closure, const unsigned char *data, unsigned int length);
/* Finishes and destroys the surface and `cr`, turning cairo's and the stream's state into a status
 * (PZ_ERR_NOMEM, PZ_ERR_CREATE naming `name`). */
pz_status pdf_finish(cairo_surface_t *surface, cairo_t *cr, pdf_stream *stream, const char *name, pz_ctx *ctx);
/* Title "<garment> (<size>): <what>", creator, and the dates from SOURCE_DATE_EPOCH when set. */
void pdf_set_metadata(cairo_surface_t *surface, const pz_pieces *pieces, const char *what);

/* Text that is not UTF-8 shown with '?' (cairo refuses it). */
void pdf_show_text(cairo_t *cr, const char *text);
/* Text at (x, y), `size` mm high, upright in a y-up user space. */
void pdf_text(cairo_t *cr, double x, double y, double size, const char *text);
/* The polyline `points` (n x 2) moved by `offset` as the current path. */
void pdf_polyline(cairo_t *cr, const double *points, int32_t n, const double offset[2], int closed);
/* Everything of one piece at `offset`: cut and sew lines, notches and labels, internal lines, grain arrow, texts. */
void pdf_draw_piece(cairo_t *cr, const pz_pieces *pieces, const pz_piece *piece, const double offset[2]);

#endif
