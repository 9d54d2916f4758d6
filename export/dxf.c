/*
 * export/dxf.c -- pattern.dxf: ASCII DXF R12 (AC1009) in the AAMA / ASTM
 * D6673 layer convention, the format CAD and cutting systems (Gerber,
 * Lectra, Optitex, CLO3D) exchange pattern pieces in.
 *
 * Layout of the file:
 *   HEADER    $ACADVER AC1009, $INSBASE, $EXTMIN/$EXTMAX (the sheet),
 *             $INSUNITS 4 (mm), $MEASUREMENT 1 (metric)
 *   TABLES    LTYPE (CONTINUOUS), LAYER 0 1 4 6 7 8 14, STYLE (STANDARD);
 *             left out with dxf_strict (some cutters reject anything else)
 *   BLOCKS    one block per drawn piece, in the piece's own coordinates (mm):
 *               layer 1   cut line (closed POLYLINE) and the piece text:
 *                         "Piece Name: ...", "Quantity: N", "Size: ..."
 *               layer 14  sew line (closed POLYLINE)
 *               layer 4   notches: LINEs from the cut line inward, as long
 *                         as the notch is deep (one per place: the ends of
 *                         two seams at a corner are one notch)
 *               layer 6   mirror line: the fold of a piece cut on the fold
 *                         (--fold; its text adds "Place on fold")
 *               layer 7   grain line (a LINE along the warp, tail to head)
 *               layer 8   internal lines: dart legs, fold lines, tip marks,
 *                         the "place on fold" bracket
 *   ENTITIES  one INSERT per block at its place on the sheet (the layout of
 *             pattern.svg), plus the style text on layer 1: "Style Name:",
 *             "Sample Size:", "Units: METRIC".
 * Text is 7-bit ASCII: other characters become \U+XXXX (AutoCAD's escape,
 * read by R12 readers), or '?' with dxf_strict. Block names keep letters,
 * digits, '_' and '-', and get "_K" (the panel) when two would clash.
 * The second piece of a mirrored pair is not written: its partner's
 * "Quantity: 2" asks for the mirrored cut, as AAMA files do.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/notches.h"
#include "export/stream_status.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SHEET_GAP_MM 20.0
#define TEXT_MM 5.0

typedef struct dxf {
    FILE *file;
    int strict;
} dxf;

static void group(const dxf *d, int code, const char *value)
{
    fprintf(d->file, "%3d\n%s\n", code, value);
}

static void group_int(const dxf *d, int code, int value)
{
    fprintf(d->file, "%3d\n%6d\n", code, value);
}

static void group_real(const dxf *d, int code, double value)
{
    fprintf(d->file, "%3d\n%.6f\n", code, value + 0.0);
}

/* A point: x under `code`, y under code + 10, z = 0 under code + 20 (10/20/30, 11/21/31). */
static void group_point(const dxf *d, int code, double x, double y)
{
    group_real(d, code, x);
    group_real(d, code + 10, y);
    group_real(d, code + 20, 0);
}

/* Decodes one UTF-8 sequence at *text (advancing it); returns the code point, or '?' for a bad one. */
static unsigned long utf8_next(const unsigned char **text)
{
    const unsigned char *s = *text;
    int extra = s[0] >= 0xf0 ? 3 : s[0] >= 0xe0 ? 2 : s[0] >= 0xc0 ? 1 : 0;
    unsigned long code = extra == 3 ? s[0] & 0x07u : extra == 2 ? s[0] & 0x0fu : s[0] & 0x1fu;
    ++*text;
    if (extra == 0)
        return '?';
    for (int i = 0; i < extra; ++i) {
        if ((**text & 0xc0) != 0x80)
            return '?';
        code = (code << 6) | (**text & 0x3fu);
        ++*text;
    }
    return code;
}

/* A group-code value of free text, 7-bit ASCII. */
static void group_text(const dxf *d, int code, const char *text)
{
    fprintf(d->file, "%3d\n", code);
    const unsigned char *s = (const unsigned char *)text;
    while (*s) {
        if (*s < 0x80) {
            if (*s >= 0x20)
                fputc(*s, d->file);
            ++s;
            continue;
        }
        unsigned long point = utf8_next(&s);
        if (d->strict || point == '?' || point > 0xffff)
            fputc('?', d->file);
        else
            fprintf(d->file, "\\U+%04lX", point);
    }
    fputc('\n', d->file);
}

static void vertex_xy(const dxf *d, const char *layer, double x, double y)
{
    group(d, 0, "VERTEX");
    group(d, 8, layer);
    group_point(d, 10, x, y);
}

static void polyline(const dxf *d, const char *layer, const double *points, int32_t count, int closed)
{
    group(d, 0, "POLYLINE");
    group(d, 8, layer);
    group_int(d, 66, 1);
    group_point(d, 10, 0, 0);
    group_int(d, 70, closed ? 1 : 0);
    for (int32_t i = 0; i < count; ++i)
        vertex_xy(d, layer, points[2 * i], points[2 * i + 1]);
    group(d, 0, "SEQEND");
    group(d, 8, layer);
}

static void line(const dxf *d, const char *layer, const double a[2], const double b[2])
{
    group(d, 0, "LINE");
    group(d, 8, layer);
    group_point(d, 10, a[0], a[1]);
    group_point(d, 11, b[0], b[1]);
}

static void text(const dxf *d, const char *layer, double x, double y, double height, const char *content)
{
    group(d, 0, "TEXT");
    group(d, 8, layer);
    group_point(d, 10, x, y);
    group_real(d, 40, height);
    group_text(d, 1, content);
}

/* ---------------------------------------------------------------- sections */

static void header(const dxf *d, const double size[2])
{
    group(d, 0, "SECTION");
    group(d, 2, "HEADER");
    group(d, 9, "$ACADVER");
    group(d, 1, "AC1009");
    group(d, 9, "$INSBASE");
    group_point(d, 10, 0, 0);
    group(d, 9, "$EXTMIN");
    group_point(d, 10, 0, 0);
    group(d, 9, "$EXTMAX");
    group_point(d, 10, size[0], size[1]);
    group(d, 9, "$INSUNITS");
    group_int(d, 70, 4);
    group(d, 9, "$MEASUREMENT");
    group_int(d, 70, 1);
    group(d, 0, "ENDSEC");
}

static void table_begin(const dxf *d, const char *name, int entries)
{
    group(d, 0, "TABLE");
    group(d, 2, name);
    group_int(d, 70, entries);
}

static void tables(const dxf *d)
{
    static const struct { const char *name; int colour; } layers[] = {
        {"0", 7}, {"1", 7}, {"4", 1}, {"6", 6}, {"7", 3}, {"8", 5}, {"14", 8},
    };
    group(d, 0, "SECTION");
    group(d, 2, "TABLES");
    table_begin(d, "LTYPE", 1);
    group(d, 0, "LTYPE");
    group(d, 2, "CONTINUOUS");
    group_int(d, 70, 0);
    group(d, 3, "Solid line");
    group_int(d, 72, 65);
    group_int(d, 73, 0);
    group_real(d, 40, 0);
    group(d, 0, "ENDTAB");
    table_begin(d, "LAYER", (int)(sizeof layers / sizeof layers[0]));
    for (size_t i = 0; i < sizeof layers / sizeof layers[0]; ++i) {
        group(d, 0, "LAYER");
        group(d, 2, layers[i].name);
        group_int(d, 70, 0);
        group_int(d, 62, layers[i].colour);
        group(d, 6, "CONTINUOUS");
    }
    group(d, 0, "ENDTAB");
    table_begin(d, "STYLE", 1);
    group(d, 0, "STYLE");
    group(d, 2, "STANDARD");
    group_int(d, 70, 0);
    group_real(d, 40, 0);
    group_real(d, 41, 1);
    group_real(d, 50, 0);
    group_int(d, 71, 0);
    group_real(d, 42, TEXT_MM);
    group(d, 3, "txt");
    group(d, 4, "");
    group(d, 0, "ENDTAB");
    group(d, 0, "ENDSEC");
}

/* A piece name with only [A-Za-z0-9_-] ("piece" when nothing is left). */
static void sanitize(const char *name, char out[64])
{
    size_t length = 0;
    for (; name[length] && length < 47; ++length) {
        unsigned char c = (unsigned char)name[length];
        out[length] = c < 0x80 && (isalnum(c) || c == '_' || c == '-') ? (char)c : '_';
    }
    out[length] = '\0';
    if (length == 0)
        snprintf(out, 64, "piece");
}

typedef char block_label[64];

typedef struct named {
    const char *name;
    int32_t piece;
    int clash;
} named;

static int compare_named(const void *a, const void *b)
{
    const named *x = a, *y = b;
    int order = strcmp(x->name, y->name);
    return order ? order : (x->piece > y->piece) - (x->piece < y->piece);
}

/*
 * The block name of every drawn piece (names: piece_count): its sanitized
 * name, with "_K" (the panel) appended when another drawn piece's is the
 * same -- found by sorting, O(P log P), and repeated should an appended name
 * meet another. 0 when out of memory.
 */
static int block_names(const pz_pieces *pieces, block_label *names)
{
    named *order = malloc(((size_t)pieces->piece_count + 1) * sizeof *order);
    if (!order)
        return 0;
    int32_t count = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored) {
            sanitize(pieces->pieces[p].name, names[p]);
            order[count++] = (named){names[p], p, 0};
        }
    for (int round = 0, clashes = 1; clashes && round < 4; ++round) {
        qsort(order, (size_t)count, sizeof *order, compare_named);
        clashes = 0;
        for (int32_t i = 0; i < count; ++i)  /* marked first: the names change below */
            order[i].clash = (i > 0 && strcmp(order[i].name, order[i - 1].name) == 0) ||
                             (i + 1 < count && strcmp(order[i].name, order[i + 1].name) == 0);
        for (int32_t i = 0; i < count; ++i)
            if (order[i].clash) {
                char *name = names[order[i].piece];
                size_t length = strlen(name);
                snprintf(name + length, sizeof(block_label) - length, "_%d", (int)pieces->pieces[order[i].piece].panel);
                clashes = 1;
            }
    }
    free(order);
    return 1;
}

static void piece_block(const dxf *d, const pz_pieces *pieces, int32_t p, const char *name)
{
    const pz_piece *piece = &pieces->pieces[p];
    char line_text[160];
    group(d, 0, "BLOCK");
    group(d, 8, "0");
    group(d, 2, name);
    group_int(d, 70, 0);
    group_point(d, 10, 0, 0);
    group(d, 3, name);
    polyline(d, "1", piece->cut, piece->cut_count, 1);
    polyline(d, "14", piece->sew, piece->sew_count, 1);
    /* Two seams' ends at one corner are one notch for the cutter (all of them when out of memory for that). */
    char(*labels)[PZ_NOTCH_LABELS_MAX] = malloc(((size_t)piece->notch_count + 1) * sizeof *labels);
    int joined = labels && pz_piece_notch_labels(piece, labels);
    for (int32_t i = 0; i < piece->notch_count; ++i) {
        const pz_notch *n = &piece->notches[i];
        if (joined && !labels[i][0])
            continue;
        double inner[2] = {n->cut_point[0] - n->depth_mm * n->direction[0],
                           n->cut_point[1] - n->depth_mm * n->direction[1]};
        line(d, "4", n->cut_point, inner);
    }
    free(labels);
    line(d, "7", piece->grain[0], piece->grain[1]);
    if (piece->on_fold) /* AAMA layer 6: the mirror line, the fold a piece is cut on */
        line(d, "6", piece->fold[0], piece->fold[1]);
    for (int32_t i = 0; i < piece->line_count; ++i)
        polyline(d, "8", piece->lines[i].points, piece->lines[i].point_count, 0);
    double x = piece->grain[0][0] + TEXT_MM, y = 0.5 * (piece->grain[0][1] + piece->grain[1][1]) + 2 * TEXT_MM;
    snprintf(line_text, sizeof line_text, "Piece Name: %s", piece->name);
    text(d, "1", x, y, TEXT_MM, line_text);
    snprintf(line_text, sizeof line_text, "Quantity: %d", (int)piece->cut_quantity);
    text(d, "1", x, y - 1.5 * TEXT_MM, TEXT_MM, line_text);
    snprintf(line_text, sizeof line_text, "Size: %s", pieces->size_name);
    text(d, "1", x, y - 3 * TEXT_MM, TEXT_MM, line_text);
    if (piece->on_fold)
        text(d, "1", x, y - 4.5 * TEXT_MM, TEXT_MM, "Place on fold");
    group(d, 0, "ENDBLK");
    group(d, 8, "0");
}

static void insert(const dxf *d, const char *name, const double offset[2])
{
    group(d, 0, "INSERT");
    group(d, 8, "0");
    group(d, 2, name);
    group_point(d, 10, offset[0], offset[1]);
}

pz_status pz_export_write_dxf(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    const pz_pieces *pieces = inputs->pieces;
    double *offsets = malloc(2 * (size_t)pieces->piece_count * sizeof(double) + 1), size[2];
    if (!offsets)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    pz_pieces_sheet_layout(pieces, SHEET_GAP_MM, 4 * TEXT_MM, offsets, size);
    block_label *names = malloc(((size_t)pieces->piece_count + 1) * sizeof *names);
    if (!names || !block_names(pieces, names)) {
        free(names);
        free(offsets);
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    }
    dxf d = {file, inputs->options && inputs->options->dxf_strict};
    header(&d, size);
    if (!d.strict)
        tables(&d);
    group(&d, 0, "SECTION");
    group(&d, 2, "BLOCKS");
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored)
            piece_block(&d, pieces, p, names[p]);
    group(&d, 0, "ENDSEC");
    group(&d, 0, "SECTION");
    group(&d, 2, "ENTITIES");
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored)
            insert(&d, names[p], &offsets[2 * p]);
    char line_text[160];
    snprintf(line_text, sizeof line_text, "Style Name: %s", pieces->garment_name);
    text(&d, "1", SHEET_GAP_MM, size[1] - 1.5 * TEXT_MM, TEXT_MM, line_text);
    snprintf(line_text, sizeof line_text, "Sample Size: %s", pieces->size_name);
    text(&d, "1", SHEET_GAP_MM, size[1] - 3 * TEXT_MM, TEXT_MM, line_text);
    text(&d, "1", SHEET_GAP_MM, size[1] - 4.5 * TEXT_MM, TEXT_MM, "Units: METRIC");
    group(&d, 0, "ENDSEC");
    group(&d, 0, "EOF");
    free(names);
    free(offsets);
    return pz_export_stream_status(file, 0, name, ctx);
}
