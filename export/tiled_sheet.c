/*
 * export/tiled_sheet.c -- the pieces larger than a page, nested together on
 * one sheet cut into tiles for pattern-tiled.pdf (export/tiled_layout.c
 * prints the sheet's inked tiles as pages).
 *
 * Each piece printed on its own grid of tiles leaves the tiles along its
 * edges mostly empty (the shared wetsuit: its pieces' own grids are about
 * twice their area). On one sheet, a piece's edge tiles take the edges of
 * others. Greedy, largest piece first: every position on a lattice of
 * kShifts x kShifts points per tile and both turns (0 and 90 degrees) is
 * scored by the tiles it would ink that no piece has inked yet; positions
 * are tried from the fewest new tiles (then the highest, then the leftmost)
 * until one where the piece, dilated by half the gap, meets no other on a
 * raster of kCell mm cells (conservative: cells that may touch the dilated
 * cut line are set, so pieces whose cells are disjoint are a gap apart).
 * The sheet is as many tiles wide as the widest piece needs, at least twice
 * the square root of the tiles the pieces would ink on their own.
 *
 * Sheet coordinates: mm, x right, y down from the sheet's top-left; tile
 * (r, c) covers [c sx, c sx + printable] x [r sy, r sy + printable], its own
 * part starts a shared band further (export/internal.h: tiled_own_part).
 * Pieces stay at least one band from the sheet's top and left, so every
 * point of a piece lies in exactly one tile's own part.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { kShifts = 4 };                  /* lattice points per tile step along each axis */
static const double kCell = 5.0;       /* mm: the raster that keeps pieces apart */
static const double kMaxTiles = 20000; /* as tiled_layout.c's page limit */
/* The sheet's width in tiles over the square root of the tiles the pieces ink on their own: a wide sheet lets
 * more pieces meet along their long sides (the wetsuit, 6 x 6 shifts: 390 pages at 0.1, 386 at 0.7, 379 at 1.5,
 * 375 at 3). */
static const double kSheetWidth = 2.0;

/* One turn of one piece: its raster as runs per row (rows from the top), and per lattice shift the tiles it
 * inks relative to the tile its box's top-left lies in. */
typedef struct sheet_shape {
    tiled_item item;           /* the turn and box */
    int32_t margin;            /* cells of the raster beyond the box on every side */
    int32_t rows;
    int32_t *row_start, *runs; /* runs of row k: runs[2 row_start[k] .. 2 row_start[k + 1]), first and last cell */
    int32_t tile_start[kShifts * kShifts + 1];
    int32_t *tiles;            /* (dr, dc) pairs */
    int32_t tile_rows, tile_columns; /* the largest dr + 1, dc + 1 */
} sheet_shape;

typedef struct sheet {
    int32_t columns, rows;     /* raster cells across, rows allocated */
    int32_t *prefix;           /* rows x (columns + 1): occupied cells left of each cell, per row */
    int32_t tile_columns, tile_rows; /* tiles across, rows of tiles allocated */
    uint8_t *inked;            /* tile_rows x tile_columns: a placed piece inks it (by the lattice score) */
    int32_t used_tile_rows;
} sheet;

static void shape_free(sheet_shape *s)
{
    free(s->row_start);
    free(s->runs);
    free(s->tiles);
}

/* The lattice offset of shift k along axis d, from the tile's corner (always at least the band in). */
static double shift_mm(const tiled_layout *layout, int d, int k)
{
    return layout->overlap + layout->step[d] * k / kShifts;
}

/* The raster of the item's cut line dilated by half the gap, as runs of rows from the top. 0 when out of memory. */
static int shape_raster(sheet_shape *s, const tiled_layout *layout, const pz_pieces *pieces)
{
    const tiled_item *item = &s->item;
    double reach = layout->gap / 2 + kCell * 0.5 * sqrt(2.0) + 1e-9;
    s->margin = (int32_t)ceil(reach / kCell) + 1;
    int32_t width = (int32_t)ceil((item->hi[0] - item->lo[0]) / kCell) + 2 * s->margin + 1;
    s->rows = (int32_t)ceil((item->hi[1] - item->lo[1]) / kCell) + 2 * s->margin + 1;
    /* In sheet coordinates with the box's top-left at the origin: the raster's top-left cell corner at
     * (-margin, -margin) cells; marker_draw_polygon fills rows upwards from its origin, so y is negated. */
    double zero[2] = {0, 0};
    double *outline = tiled_sheet_outline(pieces, item, zero);
    int32_t n = pieces->pieces[item->piece].cut_count;
    uint8_t *cells = calloc((size_t)width * (size_t)s->rows, 1);
    if (!outline || !cells) {
        free(outline), free(cells);
        return 0;
    }
    for (int32_t i = 0; i < n; ++i)
        outline[2 * i + 1] = -outline[2 * i + 1];
    double origin[2] = {-s->margin * kCell, -(s->rows - s->margin) * kCell};
    int ok = marker_draw_polygon(cells, width, s->rows, outline, n, origin, kCell, reach);
    free(outline);
    size_t count = 0;
    for (size_t i = 0; ok && i < (size_t)width * (size_t)s->rows; ++i)
        count += cells[i] && (i % (size_t)width == 0 || !cells[i - 1]);
    s->row_start = malloc(((size_t)s->rows + 1) * sizeof(int32_t));
    s->runs = malloc((2 * count + 2) * sizeof(int32_t));
    ok = ok && s->row_start && s->runs;
    int32_t run = 0;
    for (int32_t k = 0; ok && k < s->rows; ++k) {
        const uint8_t *row = cells + (size_t)(s->rows - 1 - k) * (size_t)width; /* row k from the top */
        s->row_start[k] = run;
        for (int32_t x = 0; x < width; ++x)
            if (row[x] && (x == 0 || !row[x - 1])) {
                int32_t last = x;
                while (last + 1 < width && row[last + 1])
                    ++last;
                s->runs[2 * run] = x, s->runs[2 * run + 1] = last;
                ++run;
            }
    }
    if (ok)
        s->row_start[s->rows] = run;
    free(cells);
    return ok;
}

/* Per lattice shift, the tiles whose own part the cut line meets when the box's top-left sits at that shift in
 * tile (0, 0). 0 when out of memory. */
static int shape_tiles(sheet_shape *s, const tiled_layout *layout, const pz_pieces *pieces)
{
    const tiled_item *item = &s->item;
    double size[2] = {item->hi[0] - item->lo[0], item->hi[1] - item->lo[1]};
    int32_t span[2];
    for (int d = 0; d < 2; ++d)
        span[d] = (int32_t)ceil((layout->overlap + layout->step[d] + size[d]) / layout->step[d]) + 1;
    s->tiles = malloc(2 * (size_t)kShifts * kShifts * (size_t)span[0] * (size_t)span[1] * sizeof(int32_t) + 1);
    if (!s->tiles)
        return 0;
    int32_t count = 0;
    for (int k = 0; k < kShifts * kShifts; ++k) {
        s->tile_start[k] = count;
        double at[2] = {shift_mm(layout, 0, k % kShifts), shift_mm(layout, 1, k / kShifts)};
        double *outline = tiled_sheet_outline(pieces, item, at);
        if (!outline)
            return 0;
        for (int32_t r = 0; r < span[1]; ++r)
            for (int32_t c = 0; c < span[0]; ++c) {
                double lo[2], hi[2];
                tiled_own_part(layout, r, c, lo, hi);
                if (hi[0] < at[0] || hi[1] < at[1] || lo[0] > at[0] + size[0] || lo[1] > at[1] + size[1] ||
                    !tiled_polygon_meets_box(outline, pieces->pieces[item->piece].cut_count, lo, hi))
                    continue;
                s->tiles[2 * count] = r, s->tiles[2 * count + 1] = c;
                ++count;
                s->tile_rows = r + 1 > s->tile_rows ? r + 1 : s->tile_rows;
                s->tile_columns = c + 1 > s->tile_columns ? c + 1 : s->tile_columns;
            }
        free(outline);
    }
    s->tile_start[kShifts * kShifts] = count;
    return 1;
}

/* ------------------------------------------------------------------ the sheet */

/* At least `tile_rows` rows of tiles (and the raster rows under them) allocated. 0 when out of memory. */
static int sheet_grow(sheet *sh, const tiled_layout *layout, int32_t tile_rows)
{
    if (tile_rows <= sh->tile_rows)
        return 1;
    int32_t grown = sh->tile_rows ? sh->tile_rows : 8;
    while (grown < tile_rows)
        grown *= 2;
    int32_t rows = (int32_t)ceil((grown * layout->step[1] + layout->printable[1]) / kCell) + 1;
    size_t stride = (size_t)sh->columns + 1;
    int32_t *prefix = realloc(sh->prefix, (size_t)rows * stride * sizeof *prefix);
    if (!prefix)
        return 0;
    sh->prefix = prefix;
    memset(prefix + (size_t)sh->rows * stride, 0, (size_t)(rows - sh->rows) * stride * sizeof *prefix);
    uint8_t *inked = realloc(sh->inked, (size_t)grown * (size_t)sh->tile_columns);
    if (!inked)
        return 0;
    sh->inked = inked;
    memset(inked + (size_t)sh->tile_rows * (size_t)sh->tile_columns, 0,
           (size_t)(grown - sh->tile_rows) * (size_t)sh->tile_columns);
    sh->rows = rows, sh->tile_rows = grown;
    return 1;
}

/* 1 when the shape's cells at cell (x, y) (its raster's top-left) are all free (rows past the sheet are). */
static int sheet_free(const sheet *sh, const sheet_shape *s, int32_t x, int32_t y)
{
    size_t stride = (size_t)sh->columns + 1;
    for (int32_t k = 0; k < s->rows; ++k) {
        if (y + k < 0 || y + k >= sh->rows)
            continue;
        const int32_t *prefix = sh->prefix + (size_t)(y + k) * stride;
        for (int32_t i = s->row_start[k]; i < s->row_start[k + 1]; ++i) {
            int32_t a = x + s->runs[2 * i], b = x + s->runs[2 * i + 1];
            if (a < 0 || b >= sh->columns || prefix[b + 1] - prefix[a] > 0)
                return 0;
        }
    }
    return 1;
}

/* Marks the shape's cells at (x, y) occupied (rows of the sheet only: the search keeps shapes inside). */
static void sheet_occupy(sheet *sh, const sheet_shape *s, int32_t x, int32_t y)
{
    size_t stride = (size_t)sh->columns + 1;
    for (int32_t k = 0; k < s->rows; ++k) {
        if (y + k < 0 || y + k >= sh->rows || s->row_start[k] == s->row_start[k + 1])
            continue;
        int32_t *prefix = sh->prefix + (size_t)(y + k) * stride;
        /* Back to occupancy per cell, add the runs, prefix sums again. */
        for (int32_t c = sh->columns; c > 0; --c)
            prefix[c] -= prefix[c - 1];
        for (int32_t i = s->row_start[k]; i < s->row_start[k + 1]; ++i)
            for (int32_t c = x + s->runs[2 * i]; c <= x + s->runs[2 * i + 1]; ++c)
                prefix[c + 1] = 1;
        for (int32_t c = 1; c <= sh->columns; ++c)
            prefix[c] += prefix[c - 1];
    }
}

typedef struct candidate {
    int32_t cost, bottom, column, row;
    int16_t turn, shift;
} candidate;

static int compare_candidates(const void *a, const void *b)
{
    const candidate *p = a, *q = b;
    if (p->cost != q->cost)
        return p->cost < q->cost ? -1 : 1;
    if (p->bottom != q->bottom)
        return p->bottom < q->bottom ? -1 : 1;
    if (p->row != q->row)
        return p->row < q->row ? -1 : 1;
    if (p->column != q->column)
        return p->column < q->column ? -1 : 1;
    if (p->turn != q->turn)
        return p->turn < q->turn ? -1 : 1;
    return (p->shift > q->shift) - (p->shift < q->shift);
}

/* The top-left cell of a shape placed with its box's top-left at `at` (mm; a whole number of cells). */
static void shape_cell(const sheet_shape *s, const double at[2], int32_t cell[2])
{
    for (int d = 0; d < 2; ++d)
        cell[d] = (int32_t)floor(at[d] / kCell + 1e-9) - s->margin;
}

/* The box's top-left on the sheet for tile (row, column) and lattice shift k, snapped down to whole cells. */
static void candidate_at(const tiled_layout *layout, const candidate *c, double at[2])
{
    at[0] = floor((c->column * layout->step[0] + shift_mm(layout, 0, c->shift % kShifts)) / kCell) * kCell;
    at[1] = floor((c->row * layout->step[1] + shift_mm(layout, 1, c->shift / kShifts)) / kCell) * kCell;
    /* Snapping must not bring a piece into the sheet's first band, which no tile owns alone. */
    for (int d = 0; d < 2; ++d)
        if (at[d] < layout->overlap)
            at[d] += kCell;
}

/* Places one piece (its two turns in shapes[0..1]) at the candidate of fewest new tiles where it fits. */
static pz_status place_piece(tiled_layout *layout, sheet *sh, const sheet_shape shapes[2], tiled_item *item,
                             pz_ctx *ctx)
{
    int32_t tall = shapes[0].tile_rows > shapes[1].tile_rows ? shapes[0].tile_rows : shapes[1].tile_rows;
    int32_t rows = sh->used_tile_rows + tall + 1;
    if (!sheet_grow(sh, layout, rows + tall + 1))
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    size_t capacity = 2 * (size_t)kShifts * kShifts * (size_t)rows * (size_t)sh->tile_columns;
    candidate *list = malloc((capacity + 1) * sizeof *list);
    if (!list)
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    size_t count = 0;
    double width_mm = sh->columns * kCell;
    for (int t = 0; t < 2; ++t) {
        const sheet_shape *s = &shapes[t];
        double w = s->item.hi[0] - s->item.lo[0];
        for (int k = 0; k < kShifts * kShifts; ++k)
            for (int32_t r = 0; r < rows; ++r)
                for (int32_t c = 0; c < sh->tile_columns; ++c) {
                    candidate cand = {0, 0, c, r, (int16_t)t, (int16_t)k};
                    double at[2];
                    candidate_at(layout, &cand, at);
                    if (at[0] + w + layout->gap > width_mm)
                        continue;
                    for (int32_t i = s->tile_start[k]; i < s->tile_start[k + 1]; ++i) {
                        int32_t tr = r + s->tiles[2 * i], tc = c + s->tiles[2 * i + 1];
                        cand.cost += tc >= sh->tile_columns || !sh->inked[tr * sh->tile_columns + tc];
                        cand.bottom = tr > cand.bottom ? tr : cand.bottom;
                    }
                    list[count++] = cand;
                }
    }
    /* By cost (a counting sort: costs are tile counts), each cost's candidates sorted only when the search reaches
     * them: most pieces find room among the cheapest few. */
    int32_t max_cost = 0;
    for (size_t i = 0; i < count; ++i)
        max_cost = list[i].cost > max_cost ? list[i].cost : max_cost;
    size_t *start = calloc((size_t)max_cost + 2, sizeof *start);
    candidate *sorted = malloc((count + 1) * sizeof *sorted);
    if (!start || !sorted) {
        free(start), free(sorted), free(list);
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    }
    for (size_t i = 0; i < count; ++i)
        ++start[list[i].cost + 1];
    for (int32_t c = 0; c <= max_cost; ++c)
        start[c + 1] += start[c];
    for (size_t i = 0; i < count; ++i)
        sorted[start[list[i].cost]++] = list[i];
    free(list);
    list = sorted;
    size_t chosen = count;
    for (size_t level = 0, i = 0; i < count && chosen == count; ++level) {
        size_t end = start[level]; /* after the counting pass, start[c] is where cost c ends */
        qsort(list + i, end - i, sizeof *list, compare_candidates);
        for (; i < end && chosen == count; ++i) {
            double at[2];
            int32_t cell[2];
            candidate_at(layout, &list[i], at);
            shape_cell(&shapes[list[i].turn], at, cell);
            if (sheet_free(sh, &shapes[list[i].turn], cell[0], cell[1]))
                chosen = i;
        }
        i = end;
    }
    free(start);
    if (chosen == count) { /* not reached: below every piece the sheet is free */
        free(list);
        return pz_error(ctx, PZ_ERR_INTERNAL, "pattern-tiled.pdf: no room on the sheet");
    }
    const candidate *c = &list[chosen];
    const sheet_shape *s = &shapes[c->turn];
    double at[2];
    int32_t cell[2];
    candidate_at(layout, c, at);
    shape_cell(s, at, cell);
    sheet_occupy(sh, s, cell[0], cell[1]);
    for (int32_t i = s->tile_start[c->shift]; i < s->tile_start[c->shift + 1]; ++i) {
        int32_t tr = c->row + s->tiles[2 * i], tc = c->column + s->tiles[2 * i + 1];
        if (tc < sh->tile_columns)
            sh->inked[tr * sh->tile_columns + tc] = 1;
        sh->used_tile_rows = tr + 1 > sh->used_tile_rows ? tr + 1 : sh->used_tile_rows;
    }
    *item = s->item;
    item->on_sheet = 1, item->at[0] = at[0], item->at[1] = at[1];
    free(list);
    return PZ_OK;
}

pz_status tiled_sheet_nest(tiled_layout *layout, const pz_pieces *pieces, const int32_t *which, int32_t count,
                           pz_ctx *ctx)
{
    sheet_shape *shapes = calloc(2 * (size_t)count + 1, sizeof *shapes);
    int32_t *order = malloc(((size_t)count + 1) * sizeof *order);
    sheet sh = {0};
    pz_status status = shapes && order ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    double own_tiles = 0, box_tiles = 0;
    int32_t widest = 1;
    /* Before any raster is made: a garment in the wrong units (90 m tall) is refused, not rasterized. */
    for (int32_t i = 0; status == PZ_OK && i < count; ++i) {
        const tiled_item *item = &layout->items[which[i]];
        box_tiles += ceil((item->hi[0] - item->lo[0]) / layout->step[0] + 1) *
                     ceil((item->hi[1] - item->lo[1]) / layout->step[1] + 1);
    }
    if (status == PZ_OK && box_tiles > kMaxTiles)
        status = pz_error(ctx, PZ_ERR_DATA, "pattern-tiled.pdf: the pieces need more than %d pages; is the garment "
                                            "in the right units (--units)?", (int)kMaxTiles);
    for (int32_t i = 0; status == PZ_OK && i < count; ++i) {
        for (int t = 0; t < 2 && status == PZ_OK; ++t) {
            sheet_shape *s = &shapes[2 * i + t];
            tiled_item_make(pieces, layout->items[which[i]].piece, t, &s->item);
            if (!shape_raster(s, layout, pieces) || !shape_tiles(s, layout, pieces))
                status = pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
        }
        if (status != PZ_OK)
            break;
        const sheet_shape *narrow = shapes[2 * i].tile_columns <= shapes[2 * i + 1].tile_columns ? &shapes[2 * i]
                                                                                                : &shapes[2 * i + 1];
        widest = narrow->tile_columns > widest ? narrow->tile_columns : widest;
        own_tiles += narrow->tile_start[1] - narrow->tile_start[0];
    }
    if (status == PZ_OK && own_tiles > kMaxTiles)
        status = pz_error(ctx, PZ_ERR_DATA, "pattern-tiled.pdf: the pieces need more than %d pages; is the garment "
                                            "in the right units (--units)?", (int)kMaxTiles);
    if (status == PZ_OK) {
        sh.tile_columns = (int32_t)ceil(kSheetWidth * sqrt(own_tiles));
        sh.tile_columns = sh.tile_columns > widest ? sh.tile_columns : widest;
        sh.columns = (int32_t)ceil((sh.tile_columns * layout->step[0] + layout->overlap) / kCell);
        /* Largest box first. */
        for (int32_t i = 0; i < count; ++i)
            order[i] = i;
        for (int32_t i = 1; i < count; ++i)
            for (int32_t j = i; j > 0; --j) {
                const tiled_item *a = &shapes[2 * order[j]].item, *b = &shapes[2 * order[j - 1]].item;
                if ((a->hi[0] - a->lo[0]) * (a->hi[1] - a->lo[1]) <= (b->hi[0] - b->lo[0]) * (b->hi[1] - b->lo[1]))
                    break;
                int32_t t = order[j];
                order[j] = order[j - 1], order[j - 1] = t;
            }
    }
    for (int32_t k = 0; status == PZ_OK && k < count; ++k)
        status = place_piece(layout, &sh, &shapes[2 * order[k]], &layout->items[which[order[k]]], ctx);
    if (status == PZ_OK) {
        layout->sheet_columns = sh.tile_columns;
        layout->sheet_rows = sh.used_tile_rows;
    }
    for (int32_t i = 0; shapes && i < 2 * count; ++i)
        shape_free(&shapes[i]);
    free(shapes);
    free(order);
    free(sh.prefix);
    free(sh.inked);
    return status;
}
