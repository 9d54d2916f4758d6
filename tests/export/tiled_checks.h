/*
 * tests/export/tiled_checks.h -- the properties of pattern-tiled.pdf's
 * layout (tiled_layout_build, export/internal.h), shared by test_pdf.c and
 * test_marker.c (every shared garment):
 *  - every drawn piece is one item, once; one that fits the printable area
 *    (as it is or turned) is whole on a page, one that does not is on the
 *    sheet;
 *  - a whole item lies inside its page's printable area and at least the
 *    gap from every other whole item's box on that page, and no cut line of
 *    the sheet shown on that page meets its box;
 *  - no two cut lines on the sheet are closer than the gap (exact polygon
 *    distance) and none reaches into the sheet's first band;
 *  - every point of every cut line on the sheet (sampled every 5 mm) lies
 *    in the own part of a printed tile (nothing is left unprinted), and
 *    every printed tile's own part meets a cut line;
 *  - pages are numbered once each: page_count = the pages the tiles and
 *    the whole items use.
 * Needs test_util.h (CHECK, REQUIRE) and marker_checks.h (polygon_distance).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_TEST_TILED_CHECKS_H
#define PZ_TEST_TILED_CHECKS_H

#include "export/internal.h"
#include "marker_checks.h"

/* The item's cut line on page `page`'s printable area (mm, y up); malloc'd. */
static inline double *tiled_check_outline(const tiled_layout *layout, const pz_pieces *pieces, int32_t i,
                                          int32_t page)
{
    const tiled_item *item = &layout->items[i];
    const pz_piece *piece = &pieces->pieces[item->piece];
    double move[2];
    tiled_item_on_page(layout, i, page, move);
    double *points = malloc(((size_t)piece->cut_count + 1) * 2 * sizeof(double));
    REQUIRE(points, "out of memory");
    for (int32_t k = 0; k < piece->cut_count; ++k) {
        tiled_turn(item, &piece->cut[2 * k], &points[2 * k]);
        points[2 * k] += move[0], points[2 * k + 1] += move[1];
    }
    return points;
}

/* The tile whose own part holds sheet point p (every point at least one band in has exactly one). */
static inline void tiled_check_owner(const tiled_layout *layout, const double p[2], int32_t *row, int32_t *column)
{
    *column = (int32_t)floor((p[0] - layout->overlap) / layout->step[0]);
    *row = (int32_t)floor((p[1] - layout->overlap) / layout->step[1]);
}

/* Every property above; returns the number of pages (cover not counted). */
static inline int32_t check_tiled_layout(const pz_pieces *pieces, const char *paper, const char *tag)
{
    pz_ctx ctx = {0};
    ctx.quiet = 1;
    tiled_layout layout;
    REQUIRE_OK(tiled_layout_build(pieces, paper, &layout, &ctx), ctx);
    const double *room = layout.printable, g = layout.gap;
    int32_t drawn = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        drawn += !pieces->pieces[p].mirrored && pieces->pieces[p].cut_count >= 3;
    CHECK(layout.item_count == drawn + 1 && layout.items[0].piece < 0, "%s: %d items for %d pieces", tag,
          (int)layout.item_count, (int)drawn);
    uint8_t *page_used = calloc((size_t)layout.page_count + 1, 1);
    REQUIRE(page_used, "out of memory");
    for (int32_t i = 0; i < layout.item_count; ++i) {
        const tiled_item *a = &layout.items[i];
        double w = a->hi[0] - a->lo[0], h = a->hi[1] - a->lo[1];
        int fits = (w <= room[0] && h <= room[1]) || (h <= room[0] && w <= room[1]);
        const char *name = a->piece >= 0 ? pieces->pieces[a->piece].name : "scale box";
        for (int32_t j = 0; j < i; ++j)
            CHECK(a->piece != layout.items[j].piece, "%s: %s is two items", tag, name);
        CHECK(a->on_sheet == !fits, "%s: %s (%.0f x %.0f mm) %s", tag, name, w, h,
              fits ? "fits a page but is split" : "is larger than a page but whole");
        if (a->on_sheet) {
            CHECK(a->at[0] >= layout.overlap && a->at[1] >= layout.overlap, "%s: %s in the sheet's first band", tag,
                  name);
            continue;
        }
        CHECK(a->page >= 0 && a->page < layout.page_count, "%s: %s on page %d", tag, name, (int)a->page);
        page_used[a->page] = 1;
        CHECK(a->at[0] >= -1e-9 && a->at[1] >= -1e-9 && a->at[0] + w <= room[0] + 1e-9 && a->at[1] + h <= room[1] + 1e-9,
              "%s: %s leaves the printable area", tag, name);
        for (int32_t j = 0; j < i; ++j) {
            const tiled_item *b = &layout.items[j];
            if (b->on_sheet || b->page != a->page)
                continue;
            double bw = b->hi[0] - b->lo[0], bh = b->hi[1] - b->lo[1];
            int apart = a->at[0] + w + g <= b->at[0] + 1e-9 || b->at[0] + bw + g <= a->at[0] + 1e-9 ||
                        a->at[1] + h + g <= b->at[1] + 1e-9 || b->at[1] + bh + g <= a->at[1] + 1e-9;
            CHECK(apart, "%s: %s and item %d overlap on page %d", tag, name, (int)j, (int)a->page);
        }
        /* No cut line of the sheet meets the box on this page. */
        for (int32_t j = 0; j < layout.item_count; ++j) {
            double move[2];
            if (!layout.items[j].on_sheet || !tiled_item_on_page(&layout, j, a->page, move))
                continue;
            double *outline = tiled_check_outline(&layout, pieces, j, a->page);
            double lo[2] = {a->at[0], a->at[1]}, hi[2] = {a->at[0] + w, a->at[1] + h};
            CHECK(!tiled_polygon_meets_box(outline, pieces->pieces[layout.items[j].piece].cut_count, lo, hi),
                  "%s: %s on page %d lies on the sheet's %s", tag, name, (int)a->page,
                  pieces->pieces[layout.items[j].piece].name);
            free(outline);
        }
    }
    /* The sheet: pieces a gap apart, every cut-line point printed, every printed tile inked. */
    double **outlines = calloc((size_t)layout.item_count + 1, sizeof *outlines);
    REQUIRE(outlines, "out of memory");
    uint8_t *inked = calloc((size_t)layout.sheet_rows * (size_t)layout.sheet_columns + 1, 1);
    REQUIRE(inked, "out of memory");
    int32_t unprinted = 0;
    for (int32_t i = 0; i < layout.item_count; ++i) {
        const tiled_item *a = &layout.items[i];
        if (!a->on_sheet)
            continue;
        const pz_piece *piece = &pieces->pieces[a->piece];
        outlines[i] = tiled_sheet_outline(pieces, a, a->at);
        REQUIRE(outlines[i], "out of memory");
        for (int32_t j = 0; j < i; ++j)
            if (outlines[j]) {
                double d = polygon_distance(outlines[i], piece->cut_count, outlines[j],
                                            pieces->pieces[layout.items[j].piece].cut_count);
                CHECK(d >= g - 1e-6, "%s: %s and %s are %.2f mm apart on the sheet", tag, piece->name,
                      pieces->pieces[layout.items[j].piece].name, d);
            }
        for (int32_t k = 0; k < piece->cut_count; ++k) {
            const double *p = &outlines[i][2 * k], *q = &outlines[i][2 * ((k + 1) % piece->cut_count)];
            int32_t samples = (int32_t)ceil(hypot(q[0] - p[0], q[1] - p[1]) / 5.0);
            for (int32_t s = 0; s <= samples; ++s) {
                double t = samples ? (double)s / samples : 0, x[2] = {p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])};
                int32_t r, c;
                tiled_check_owner(&layout, x, &r, &c);
                int ok = r >= 0 && c >= 0 && r < layout.sheet_rows && c < layout.sheet_columns &&
                         layout.tile_page[r * layout.sheet_columns + c] >= 0;
                unprinted += !ok;
                if (ok)
                    inked[r * layout.sheet_columns + c] = 1;
            }
        }
    }
    CHECK(unprinted == 0, "%s: %d points of the sheet's cut lines on no printed tile", tag, (int)unprinted);
    int32_t tiles = 0, empty = 0;
    for (int32_t t = 0; t < layout.sheet_rows * layout.sheet_columns; ++t) {
        int32_t page = layout.tile_page[t];
        if (page < 0)
            continue;
        ++tiles;
        CHECK(page < layout.page_count && layout.pages[page].row * layout.sheet_columns + layout.pages[page].column == t,
              "%s: tile %d and its page %d disagree", tag, (int)t, (int)page);
        if (page < layout.page_count)
            page_used[page] = 1;
        /* A cut line may cross a tile's own part between two samples without a sample in it: look closer. */
        if (!inked[t]) {
            double lo[2], hi[2];
            tiled_own_part(&layout, t / layout.sheet_columns, t % layout.sheet_columns, lo, hi);
            int any = 0;
            for (int32_t i = 0; i < layout.item_count && !any; ++i)
                any = outlines[i] &&
                      tiled_polygon_meets_box(outlines[i], pieces->pieces[layout.items[i].piece].cut_count, lo, hi);
            empty += !any;
        }
    }
    CHECK(empty == 0, "%s: %d printed tiles without a cut line", tag, (int)empty);
    int32_t unused = 0;
    for (int32_t page = 0; page < layout.page_count; ++page)
        unused += !page_used[page];
    CHECK(unused == 0, "%s: %d pages hold nothing", tag, (int)unused);
    printf("%s: %d pages on %s (%d tiles of a %d x %d sheet)\n", tag, (int)layout.page_count, paper ? paper : "a4",
           (int)tiles, (int)layout.sheet_rows, (int)layout.sheet_columns);
    for (int32_t i = 0; i < layout.item_count; ++i)
        free(outlines[i]);
    free(outlines);
    free(inked);
    free(page_used);
    int32_t pages = layout.page_count;
    tiled_layout_free(&layout);
    return pages;
}

#endif
