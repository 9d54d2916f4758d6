/*
 * export/tiled_layout.c -- the pages of pattern-tiled.pdf (docs/export.md,
 * "pattern-tiled.pdf"); export/pdf_tiled.c draws them.
 *
 * Every drawn piece is an item with the box of its cut line. An item that
 * fits the printable area (paper minus 10 mm margins), as it is or turned 90
 * degrees (its grainline is drawn with it), is printed whole on one page:
 * the items are packed onto pages as boxes (MaxRects: each, largest first,
 * into the free rectangle of any page so far that it leaves the least
 * short-side room in, 6 mm apart), so several share a page. The items larger
 * than a page are nested together on one sheet cut into tiles
 * (export/tiled_sheet.c); neighbouring tiles share a 10 mm band, and a tile
 * whose own part (without the bands shared with the tiles above and to the
 * left) meets no cut line is not printed. A tile page's part away from the
 * cut lines on it (their boxes clipped to the tile) and from the bands it
 * shares with printed neighbours takes whole items like any page. The 10 cm
 * scale box goes last, into any room left (on a page of its own only when
 * there is none), and its page becomes the first.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double kPaperMargin = 10.0; /* unprintable border of a page */
static const double kOverlap = 10.0;     /* shared by neighbouring tiles */
static const double kItemGap = 6.0;      /* between whole items on a page */
static const double kMaxPages = 20000.0; /* a home print of more pages is not a pattern anyone prints */
/* The scale box's item: the 100 mm square, its caption above (export/pdf_tiled.c). */
static const double kScaleItem[2] = {100.0, 108.0};

/* ------------------------------------------------------------------ geometry */

static int same_word(const char *a, const char *b)
{
    for (; *a && *b; ++a, ++b)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b))
            return 0;
    return *a == *b;
}

void tiled_turn(const tiled_item *item, const double point[2], double out[2])
{
    double x = point[0], y = point[1];
    out[0] = item->turned ? -y : x;
    out[1] = item->turned ? x : y;
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

int tiled_polygon_meets_box(const double *points, int32_t n, const double lo[2], const double hi[2])
{
    double centre[2] = {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2};
    int inside = 0;
    for (int32_t i = 0, j = n - 1; i < n; j = i++) {
        const double *p = &points[2 * i], *q = &points[2 * j];
        if (segment_meets_box(p, q, lo, hi))
            return 1;
        if ((p[1] > centre[1]) != (q[1] > centre[1]) &&
            centre[0] < (q[0] - p[0]) * (centre[1] - p[1]) / (q[1] - p[1]) + p[0])
            inside = !inside;
    }
    return inside;
}

/* Room for the points of a polygon of n points clipped against four sides: each side adds at most one point
 * per edge leaving it (half the crossings), so at most 1.5 times the points it gets, (1.5)^4 < 6 in all. */
#define CLIP_ROOM(n) (6 * (size_t)(n) + 16)

/* The box of the polygon clipped to [lo, hi] (Sutherland-Hodgman against the four sides); 0 when nothing is
 * left. `scratch` holds 2 x CLIP_ROOM(n) points. */
static int clipped_box(const double *points, int32_t n, const double lo[2], const double hi[2], double *scratch,
                       double box_lo[2], double box_hi[2])
{
    const int32_t room = (int32_t)CLIP_ROOM(n);
    double *in = scratch, *out = scratch + 2 * CLIP_ROOM(n);
    memcpy(in, points, 2 * (size_t)n * sizeof(double));
    int32_t count = n;
    for (int side = 0; side < 4 && count > 0; ++side) {
        int axis = side / 2, upper = side % 2;
        double limit = upper ? hi[axis] : lo[axis];
        int32_t kept = 0;
        for (int32_t i = 0; i < count; ++i) {
            const double *a = &in[2 * i], *b = &in[2 * ((i + 1) % count)];
            int a_in = upper ? a[axis] <= limit : a[axis] >= limit;
            int b_in = upper ? b[axis] <= limit : b[axis] >= limit;
            if (a_in && kept < room)
                memcpy(&out[2 * kept++], a, 2 * sizeof(double));
            if (a_in != b_in && kept < room) {
                double t = (limit - a[axis]) / (b[axis] - a[axis]);
                out[2 * kept + axis] = limit;
                out[2 * kept + 1 - axis] = a[1 - axis] + t * (b[1 - axis] - a[1 - axis]);
                ++kept;
            }
        }
        double *swap = in;
        in = out, out = swap;
        count = kept;
    }
    if (count == 0)
        return 0;
    box_lo[0] = box_lo[1] = INFINITY, box_hi[0] = box_hi[1] = -INFINITY;
    for (int32_t i = 0; i < count; ++i)
        for (int d = 0; d < 2; ++d) {
            box_lo[d] = fmin(box_lo[d], in[2 * i + d]);
            box_hi[d] = fmax(box_hi[d], in[2 * i + d]);
        }
    return 1;
}

/* ------------------------------------------------------------------ packing boxes onto pages (MaxRects) */

typedef struct rect {
    double lo[2], hi[2];
} rect;

/* Every page's maximal free rectangles. A thing of size (w, h) takes [at, at + (w, h) + gap]: two things whose
 * taken rectangles are disjoint are `gap` apart, and the bins are the printable area plus the gap. */
typedef struct packer {
    int32_t page_count, capacity;
    rect **free;       /* per page: its free rectangles */
    int32_t *count, *room;
} packer;

static void packer_free(packer *p)
{
    for (int32_t i = 0; i < p->page_count; ++i)
        free(p->free[i]);
    free(p->free);
    free(p->count);
    free(p->room);
}

static int rect_push(packer *p, int32_t page, rect r)
{
    if (p->count[page] == p->room[page]) {
        int32_t room = p->room[page] ? 2 * p->room[page] : 16;
        rect *grown = realloc(p->free[page], (size_t)room * sizeof *grown);
        if (!grown)
            return 0;
        p->free[page] = grown, p->room[page] = room;
    }
    p->free[page][p->count[page]++] = r;
    return 1;
}

/* A new page whose free part is the whole bin. */
static int packer_add_page(packer *p, const double bin[2])
{
    if (p->page_count == p->capacity) {
        int32_t capacity = p->capacity ? 2 * p->capacity : 16;
        rect **free_rects = realloc(p->free, (size_t)capacity * sizeof *free_rects);
        if (free_rects)
            p->free = free_rects;
        int32_t *count = realloc(p->count, (size_t)capacity * sizeof *count);
        if (count)
            p->count = count;
        int32_t *room = realloc(p->room, (size_t)capacity * sizeof *room);
        if (room)
            p->room = room;
        if (!free_rects || !count || !room)
            return 0;
        p->capacity = capacity;
    }
    int32_t page = p->page_count++;
    p->free[page] = NULL, p->count[page] = 0, p->room[page] = 0;
    return rect_push(p, page, (rect){{0, 0}, {bin[0], bin[1]}});
}

static int rect_contains(const rect *a, const rect *b)
{
    return a->lo[0] <= b->lo[0] && a->lo[1] <= b->lo[1] && a->hi[0] >= b->hi[0] && a->hi[1] >= b->hi[1];
}

/* Takes `used` out of the page's free rectangles: each one it meets is split into the (up to four) parts
 * beside it, then rectangles inside others are dropped. */
static int packer_take(packer *p, int32_t page, rect used)
{
    int32_t n = p->count[page];
    for (int32_t i = 0; i < n; ++i) {
        rect f = p->free[page][i];
        if (used.lo[0] >= f.hi[0] || used.hi[0] <= f.lo[0] || used.lo[1] >= f.hi[1] || used.hi[1] <= f.lo[1])
            continue;
        rect parts[4] = {{{f.lo[0], f.lo[1]}, {used.lo[0], f.hi[1]}}, {{used.hi[0], f.lo[1]}, {f.hi[0], f.hi[1]}},
                         {{f.lo[0], f.lo[1]}, {f.hi[0], used.lo[1]}}, {{f.lo[0], used.hi[1]}, {f.hi[0], f.hi[1]}}};
        p->free[page][i] = p->free[page][--n];
        p->count[page] = n;
        --i;
        for (int k = 0; k < 4; ++k)
            if (parts[k].hi[0] > parts[k].lo[0] && parts[k].hi[1] > parts[k].lo[1] && !rect_push(p, page, parts[k]))
                return 0;
    }
    rect *f = p->free[page];
    int32_t count = p->count[page];
    for (int32_t i = 0; i < count; ++i)
        for (int32_t j = 0; j < count; ++j)
            if (i != j && rect_contains(&f[j], &f[i]) && (!rect_contains(&f[i], &f[j]) || i > j)) {
                f[i--] = f[--count];
                break;
            }
    p->count[page] = count;
    return 1;
}

/* Where a thing of size[turn] (gap included) goes: the free rectangle it leaves least short-side room in over all
 * pages (ties: the earlier page, the higher, the further left). 0 when none holds it. */
static int packer_find(const packer *p, const double size[2][2], int turns, int32_t *page_out, int *turn_out,
                       double at[2])
{
    double best = INFINITY, best_top = -INFINITY, best_left = INFINITY;
    int found = 0;
    for (int32_t page = 0; page < p->page_count; ++page)
        for (int32_t i = 0; i < p->count[page]; ++i) {
            const rect *f = &p->free[page][i];
            for (int t = 0; t < turns; ++t) {
                double room_x = f->hi[0] - f->lo[0] - size[t][0], room_y = f->hi[1] - f->lo[1] - size[t][1];
                if (room_x < -1e-9 || room_y < -1e-9)
                    continue;
                double score = fmin(room_x, room_y), top = f->hi[1], left = f->lo[0];
                int better = !found || score < best - 1e-6 ||
                             (fabs(score - best) <= 1e-6 && (top > best_top + 1e-6 ||
                                                             (fabs(top - best_top) <= 1e-6 && left < best_left - 1e-6)));
                if (!better)
                    continue;
                found = 1, best = score, best_top = top, best_left = left;
                *page_out = page, *turn_out = t;
                at[0] = f->lo[0], at[1] = f->hi[1] - size[t][1]; /* top left of the free rectangle */
            }
        }
    return found;
}

/* ------------------------------------------------------------------ items and tiles */

void tiled_item_make(const pz_pieces *pieces, int32_t p, int turned, tiled_item *item)
{
    memset(item, 0, sizeof *item);
    item->piece = p, item->turned = turned;
    if (p < 0) {
        item->hi[0] = kScaleItem[0], item->hi[1] = kScaleItem[1];
        return;
    }
    const pz_piece *piece = &pieces->pieces[p];
    double a[2], b[2];
    tiled_turn(item, piece->bbox_min, a);
    tiled_turn(item, piece->bbox_max, b);
    for (int d = 0; d < 2; ++d)
        item->lo[d] = fmin(a[d], b[d]), item->hi[d] = fmax(a[d], b[d]);
}

double *tiled_sheet_outline(const pz_pieces *pieces, const tiled_item *item, const double at[2])
{
    const pz_piece *piece = &pieces->pieces[item->piece];
    double *points = malloc(((size_t)piece->cut_count + 1) * 2 * sizeof(double));
    for (int32_t i = 0; points && i < piece->cut_count; ++i) {
        double p[2];
        tiled_turn(item, &piece->cut[2 * i], p);
        points[2 * i] = at[0] + p[0] - item->lo[0];
        points[2 * i + 1] = at[1] + item->hi[1] - p[1];
    }
    return points;
}

/* Tile (row, column)'s region in sheet coordinates (x right, y down). */
static void tile_region(const tiled_layout *layout, int32_t row, int32_t column, double lo[2], double hi[2])
{
    lo[0] = column * layout->step[0], lo[1] = row * layout->step[1];
    hi[0] = lo[0] + layout->printable[0], hi[1] = lo[1] + layout->printable[1];
}

void tiled_own_part(const tiled_layout *layout, int32_t row, int32_t column, double lo[2], double hi[2])
{
    tile_region(layout, row, column, lo, hi);
    if (row > 0)
        lo[1] += layout->overlap;
    if (column > 0)
        lo[0] += layout->overlap;
}

int tiled_item_on_page(const tiled_layout *layout, int32_t index, int32_t page, double move[2])
{
    const tiled_item *item = &layout->items[index];
    const tiled_page *p = &layout->pages[page];
    if (!item->on_sheet) {
        move[0] = item->at[0] - item->lo[0], move[1] = item->at[1] - item->lo[1];
        return item->page == page;
    }
    if (p->row < 0)
        return 0;
    double lo[2], hi[2];
    tile_region(layout, p->row, p->column, lo, hi);
    /* Item point q -> sheet (at.x + q.x - lo.x, at.y + hi.y - q.y) -> page (sheet x - region x, printable height
     * - (sheet y - region y)): a translation, y up on both. */
    move[0] = item->at[0] - item->lo[0] - lo[0];
    move[1] = layout->printable[1] - item->at[1] - item->hi[1] + lo[1];
    double w = item->hi[0] - item->lo[0], h = item->hi[1] - item->lo[1];
    return item->at[0] < hi[0] && item->at[0] + w > lo[0] && item->at[1] < hi[1] && item->at[1] + h > lo[1];
}

/* ------------------------------------------------------------------ pages */

static int page_push(tiled_layout *layout, int32_t *capacity, tiled_page page)
{
    if (layout->page_count == *capacity) {
        *capacity = *capacity ? 2 * *capacity : 16;
        tiled_page *grown = realloc(layout->pages, (size_t)*capacity * sizeof *grown);
        if (!grown)
            return 0;
        layout->pages = grown;
    }
    layout->pages[layout->page_count++] = page;
    return 1;
}

static int printed(const tiled_layout *layout, int32_t row, int32_t column)
{
    return row >= 0 && column >= 0 && row < layout->sheet_rows && column < layout->sheet_columns &&
           layout->tile_page[row * layout->sheet_columns + column] >= 0;
}

/* What whole items may not take on tile page `page`: the bands it shares with printed neighbours, and the box of
 * every cut line on it clipped to the tile. */
static int tile_taken(packer *pk, const tiled_layout *layout, const pz_pieces *pieces, int32_t page)
{
    const tiled_page *p = &layout->pages[page];
    const double *size = layout->printable, g = layout->gap, band = layout->overlap;
    rect bands[4] = {{{0, 0}, {band + g, size[1] + g}}, {{size[0] - band, 0}, {size[0] + g, size[1] + g}},
                     {{0, size[1] - band}, {size[0] + g, size[1] + g}}, {{0, 0}, {size[0] + g, band + g}}};
    int neighbour[4] = {printed(layout, p->row, p->column - 1), printed(layout, p->row, p->column + 1),
                        printed(layout, p->row - 1, p->column), printed(layout, p->row + 1, p->column)};
    for (int k = 0; k < 4; ++k)
        if (neighbour[k] && !packer_take(pk, page, bands[k]))
            return 0;
    double lo[2], hi[2];
    tile_region(layout, p->row, p->column, lo, hi);
    for (int32_t i = 0; i < layout->item_count; ++i) {
        const tiled_item *item = &layout->items[i];
        double move[2];
        if (!item->on_sheet || !tiled_item_on_page(layout, i, page, move))
            continue;
        int32_t n = pieces->pieces[item->piece].cut_count;
        double *outline = tiled_sheet_outline(pieces, item, item->at);
        double *scratch = malloc(4 * CLIP_ROOM(n) * sizeof(double));
        double box_lo[2], box_hi[2];
        int ok = outline && scratch;
        if (ok && clipped_box(outline, n, lo, hi, scratch, box_lo, box_hi)) {
            /* Sheet y runs down, the page's up. */
            rect taken = {{box_lo[0] - lo[0], size[1] - (box_hi[1] - lo[1])},
                          {box_hi[0] - lo[0] + g, size[1] - (box_lo[1] - lo[1]) + g}};
            ok = packer_take(pk, page, taken);
        }
        free(outline);
        free(scratch);
        if (!ok)
            return 0;
    }
    return 1;
}

/* The sheet's printed tiles as pages, row by row, their free parts open to whole items. */
static pz_status lay_tiles(tiled_layout *layout, const pz_pieces *pieces, packer *pk, int32_t *page_capacity,
                           const double bin[2], pz_ctx *ctx)
{
    size_t tiles = (size_t)layout->sheet_rows * (size_t)layout->sheet_columns;
    layout->tile_page = malloc((tiles + 1) * sizeof *layout->tile_page);
    if (!layout->tile_page)
        return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    for (int32_t r = 0; r < layout->sheet_rows; ++r)
        for (int32_t c = 0; c < layout->sheet_columns; ++c) {
            double lo[2], hi[2];
            tiled_own_part(layout, r, c, lo, hi);
            int ink = 0;
            for (int32_t i = 0; i < layout->item_count && !ink; ++i) {
                const tiled_item *item = &layout->items[i];
                if (!item->on_sheet || item->at[0] > hi[0] || item->at[1] > hi[1] ||
                    item->at[0] + item->hi[0] - item->lo[0] < lo[0] || item->at[1] + item->hi[1] - item->lo[1] < lo[1])
                    continue;
                double *outline = tiled_sheet_outline(pieces, item, item->at);
                if (!outline)
                    return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
                ink = tiled_polygon_meets_box(outline, pieces->pieces[item->piece].cut_count, lo, hi);
                free(outline);
            }
            layout->tile_page[r * layout->sheet_columns + c] = ink ? layout->page_count : -1;
            if (ink && (!page_push(layout, page_capacity, (tiled_page){r, c}) || !packer_add_page(pk, bin)))
                return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
        }
    for (int32_t page = 0; page < layout->page_count; ++page)
        if (layout->pages[page].row >= 0 && !tile_taken(pk, layout, pieces, page))
            return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    return PZ_OK;
}

/* Items that fit a page: each into the best free rectangle of any page, a new page when none holds it; with
 * `upright`, turned only where it fits nowhere upright. */
static int find_room(const packer *pk, const double size[2][2], int turns, int upright, int32_t *page, int *turn,
                     double at[2])
{
    if (upright && packer_find(pk, size, 1, page, turn, at))
        return 1;
    return packer_find(pk, size, turns, page, turn, at);
}

static pz_status lay_whole(tiled_layout *layout, const pz_pieces *pieces, const int32_t *order, int32_t count,
                           int upright, packer *pk, int32_t *page_capacity, const double bin[2], pz_ctx *ctx)
{
    const double g = layout->gap;
    for (int32_t k = 0; k < count; ++k) {
        tiled_item *item = &layout->items[order[k]];
        if (item->on_sheet)
            continue;
        double w = item->hi[0] - item->lo[0], h = item->hi[1] - item->lo[1];
        double size[2][2] = {{w + g, h + g}, {h + g, w + g}};
        int turns = item->piece >= 0 ? 2 : 1, turn = 0;
        int32_t page = 0;
        double at[2];
        if (!find_room(pk, size, turns, upright, &page, &turn, at)) {
            if (layout->page_count >= kMaxPages)
                return pz_error(ctx, PZ_ERR_DATA, "pattern-tiled.pdf: more than %d pages; is the garment in the "
                                                  "right units (--units)?", (int)kMaxPages);
            if (!page_push(layout, page_capacity, (tiled_page){-1, -1}) || !packer_add_page(pk, bin))
                return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
            find_room(pk, size, turns, upright, &page, &turn, at); /* an item that fits a page fits an empty one */
        }
        if (turn)
            tiled_item_make(pieces, item->piece, !item->turned, item);
        item->page = page, item->at[0] = at[0], item->at[1] = at[1];
        rect used = {{at[0], at[1]}, {at[0] + size[turn][0], at[1] + size[turn][1]}};
        if (!packer_take(pk, page, used))
            return pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    }
    return PZ_OK;
}

/* Page `page` becomes the first, the pages before it move one on. */
static void move_to_front(tiled_layout *layout, int32_t page)
{
    tiled_page moved = layout->pages[page];
    memmove(layout->pages + 1, layout->pages, (size_t)page * sizeof *layout->pages);
    layout->pages[0] = moved;
    for (int32_t i = 0; i < layout->item_count; ++i)
        if (!layout->items[i].on_sheet)
            layout->items[i].page = layout->items[i].page == page ? 0 : layout->items[i].page + (layout->items[i].page < page);
    for (int32_t t = 0; t < layout->sheet_rows * layout->sheet_columns; ++t) {
        int32_t *p = &layout->tile_page[t];
        *p = *p < 0 ? *p : *p == page ? 0 : *p + (*p < page);
    }
}

/* Items by decreasing box area (the scale box, item 0, first), ties in piece order. */
static void sort_items(const tiled_layout *layout, int32_t *order)
{
    for (int32_t i = 0; i < layout->item_count; ++i)
        order[i] = i;
    for (int32_t i = 2; i < layout->item_count; ++i)
        for (int32_t j = i; j > 1; --j) {
            const tiled_item *a = &layout->items[order[j]], *b = &layout->items[order[j - 1]];
            double area_a = (a->hi[0] - a->lo[0]) * (a->hi[1] - a->lo[1]);
            double area_b = (b->hi[0] - b->lo[0]) * (b->hi[1] - b->lo[1]);
            if (area_a <= area_b)
                break;
            int32_t t = order[j];
            order[j] = order[j - 1], order[j - 1] = t;
        }
}

void tiled_layout_free(tiled_layout *layout)
{
    free(layout->items);
    free(layout->pages);
    free(layout->tile_page);
    memset(layout, 0, sizeof *layout);
}

/* The items: the scale box, then every drawn piece; the pieces larger than a page listed in `large`. */
static pz_status make_items(tiled_layout *out, const pz_pieces *pieces, int32_t *large, int32_t *large_count,
                            pz_ctx *ctx)
{
    tiled_item_make(pieces, -1, 0, &out->items[out->item_count++]);
    *large_count = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        if (piece->mirrored || piece->cut_count < 3)
            continue;
        for (int32_t i = 0; i < 2 * piece->cut_count; ++i)
            if (!isfinite(piece->cut[i]) || fabs(piece->cut[i]) > 1e6)
                return pz_error(ctx, PZ_ERR_DATA, "pattern-tiled.pdf: piece %s has a cut-line coordinate out of "
                                                  "range (%g)", piece->name, piece->cut[i]);
        tiled_item *item = &out->items[out->item_count];
        tiled_item_make(pieces, p, 0, item);
        double w = item->hi[0] - item->lo[0], h = item->hi[1] - item->lo[1];
        const double *room = out->printable;
        if (!((w <= room[0] && h <= room[1]) || (h <= room[0] && w <= room[1])))
            large[(*large_count)++] = out->item_count;
        ++out->item_count;
    }
    return PZ_OK;
}

/* The pages of a layout whose items are made and nested: the sheet's tiles, the whole items (largest first,
 * `order` their order after sort_items), the scale box where room is left, its page first. */
static pz_status lay_pages(tiled_layout *layout, const pz_pieces *pieces, int32_t *order, int upright, pz_ctx *ctx)
{
    const double bin[2] = {layout->printable[0] + layout->gap, layout->printable[1] + layout->gap};
    packer pk = {0};
    int32_t page_capacity = 0;
    for (int32_t i = 0; i < layout->item_count; ++i)
        if (!layout->items[i].on_sheet) /* upright again: a trial before may have turned it */
            tiled_item_make(pieces, layout->items[i].piece, 0, &layout->items[i]);
    pz_status status = lay_tiles(layout, pieces, &pk, &page_capacity, bin, ctx);
    if (status == PZ_OK) {
        sort_items(layout, order);
        status = lay_whole(layout, pieces, order + 1, layout->item_count - 1, upright, &pk, &page_capacity, bin, ctx);
    }
    if (status == PZ_OK)
        status = lay_whole(layout, pieces, order, 1, upright, &pk, &page_capacity, bin, ctx);
    if (status == PZ_OK)
        move_to_front(layout, layout->items[0].page);
    packer_free(&pk);
    return status;
}

pz_status tiled_layout_build(const pz_pieces *pieces, const char *paper, tiled_layout *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    paper = paper ? paper : "a4";
    int letter = same_word(paper, "letter");
    if (!letter && !same_word(paper, "a4"))
        return pz_error(ctx, PZ_ERR_USAGE, "pattern-tiled.pdf: paper '%s' is not a4 or letter", paper);
    out->paper[0] = letter ? 215.9 : 210.0;
    out->paper[1] = letter ? 279.4 : 297.0;
    out->gap = kItemGap, out->overlap = kOverlap;
    for (int d = 0; d < 2; ++d) {
        out->printable[d] = out->paper[d] - 2 * kPaperMargin;
        out->step[d] = out->printable[d] - kOverlap;
    }
    size_t n = (size_t)pieces->piece_count + 1;
    out->items = calloc(n, sizeof *out->items);
    int32_t *order = malloc(2 * n * sizeof *order), large_count = 0;
    pz_status status = out->items && order ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
    if (status == PZ_OK)
        status = make_items(out, pieces, order + n, &large_count, ctx);
    if (status == PZ_OK && large_count > 0)
        status = tiled_sheet_nest(out, pieces, order + n, large_count, ctx);
    /* The pages twice: whole items turned wherever the best short-side fit says, or upright where they fit
     * upright; the one with fewer pages is kept (neither is better on every pattern: 80 x 120 mm pieces go four
     * to an A4 page upright, three turned). */
    for (int upright = 0; upright < 2 && status == PZ_OK; ++upright) {
        tiled_layout trial = *out;
        trial.pages = NULL, trial.tile_page = NULL, trial.page_count = 0;
        trial.items = malloc(n * sizeof *trial.items);
        if (!trial.items) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "pattern-tiled.pdf: out of memory");
            break;
        }
        memcpy(trial.items, out->items, (size_t)out->item_count * sizeof *trial.items);
        status = lay_pages(&trial, pieces, order, upright, ctx);
        if (status == PZ_OK && (upright == 0 || trial.page_count < out->page_count)) {
            free(out->items), free(out->pages), free(out->tile_page);
            *out = trial;
        } else {
            tiled_layout_free(&trial);
        }
    }
    free(order);
    if (status != PZ_OK)
        tiled_layout_free(out);
    return status;
}

pz_status pz_export_check_tiled_area(double area_mm2, const char *paper, const char *name, pz_ctx *ctx)
{
    double width = paper && same_word(paper, "letter") ? 215.9 : 210.0;
    double height = paper && same_word(paper, "letter") ? 279.4 : 297.0;
    double page_mm2 = (width - 2 * kPaperMargin - kOverlap) * (height - 2 * kPaperMargin - kOverlap);
    if (!(area_mm2 > 2.0 * kMaxPages * page_mm2))
        return PZ_OK;
    return pz_error(ctx, PZ_ERR_DATA,
                    "%s: %.0f m2 of garment cannot fit in %d pages of pattern-tiled.pdf; is the garment in the right "
                    "units (--units)?",
                    name, area_mm2 * 1e-6, (int)kMaxPages);
}
