/*
 * export/internal.h -- what the files of one export part share, not part of
 * the public interface (export/export.h is): the layout of pattern-tiled.pdf
 * (export/pdf_tiled.c), pieces cut on the fold, and the marker's pieces
 * (export/marker.c: the search over orders, the build, marker.svg;
 * export/marker_shapes.c: pieces rasterized into shapes and placement units;
 * export/marker_grid.c: the fabric grid and one greedy pass). docs/marker.md
 * describes the method.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_EXPORT_INTERNAL_H
#define PZ_EXPORT_INTERNAL_H

#include "export/export.h"

#include <stdint.h>

/* ------------------------------------------------------------------ pieces cut on the fold (fold.c) */

/* Every piece that is its own mirror image (panel_mirror[panel] == panel) and symmetric about an axis within
 * 0.25 mm becomes its half with the fold marked (docs/export.md, "Cut on the fold"); the others stay. Call after
 * the notches, before the areas and boxes. PZ_ERR_NOMEM. */
pz_status pz_pieces_fold(pz_pieces *pieces, const int32_t *panel_mirror, pz_ctx *ctx);

/* ------------------------------------------------------------------ marker: shapes and units */

/* Rows of a shape whose longest run a fabric row must hold before any column is tried there. */
#define MARKER_PROBES 8

/* A rasterized unit: per row, runs of set cells; column c covers [c, c + 1) x resolution, local to the shape. */
typedef struct marker_shape {
    int32_t width, height;
    int32_t *row_start;    /* height + 1: the runs of row r are runs[2 row_start[r] .. 2 row_start[r + 1]) */
    int32_t *runs;         /* first, last column of each run (inclusive) */
    int32_t widest_row;    /* the row of the longest run ... */
    int32_t widest;        /* ... and its length - 1 (-1 for an empty shape) */
    int32_t probe_row[MARKER_PROBES];   /* rows spread over the height ... */
    int32_t probe_width[MARKER_PROBES]; /* ... and their longest run - 1 */
    int32_t *check_order;  /* height: the rows in the order marker_grid.c checks them (widest first, then strided) */
} marker_shape;

/* What gets placed in one go: one piece copy, or a mirrored pair, in fixed orientations. */
typedef struct marker_unit {
    int member_count;
    pz_marker_placement members[2]; /* offsets map piece coordinates to unit-local mm */
    marker_shape shape;
    double lo[2], hi[2];            /* cut-line extent, unit-local mm */
} marker_unit;

/* The raster every shape is drawn on: cell size (mm), how far a cell reaches (gap / 2 plus half a cell
 * diagonal), the fabric's width (mm). */
typedef struct marker_raster {
    double resolution, reach, width_mm;
} marker_raster;

/* Everything one piece may be placed as: its copies in both rotations, and for a Cut-2 piece the pairs, each
 * also transposed ([1]) for the column fill. */
typedef struct marker_demand {
    int32_t piece;
    int copies;                  /* 1, or 2 for a Cut-2 piece */
    marker_unit singles[2][2][2];  /* [transposed][copy][0: 0 degrees, 1: 180] */
    marker_unit pairs[2][4];       /* copies == 2: [transposed](copy 0, copy 1) turned (0,0) (0,180) (180,0) (180,180) */
    double keys[3];              /* area, height, width: the fixed orders */
    int transposed;              /* the [1] units are made (marker_demand_transpose) */
} marker_demand;

/* Rasterizes the closed polygon `points` (n x 2) into `cells` (width x height, row-major, lower-left at `origin`,
 * square cells of `resolution` mm): every cell whose centre is inside, or within `reach` of an edge, is set (so
 * with reach = margin + half a cell diagonal every cell the polygon dilated by margin touches). 0 when out of
 * memory. */
int marker_draw_polygon(uint8_t *cells, int32_t width, int32_t height, const double *points, int32_t n,
                        const double origin[2], double resolution, double reach);

/* Every way piece `index` may be placed (its copies in both rotations, the pairs of a Cut-2 piece), not yet
 * transposed. 0 when out of memory; marker_demand_clear frees what was built either way. */
int marker_demand_build(const marker_raster *raster, const pz_pieces *pieces, int32_t index, marker_demand *out);
/* The units transposed ([1]) for the column fill, once. 0 when out of memory. */
int marker_demand_transpose(marker_demand *d);
void marker_demand_clear(marker_demand *d);

/* ------------------------------------------------------------------ marker: the fabric grid */

/* The grid's columns stay below this (the transposed grid of a long marker is refused above it). */
#define MARKER_MAX_COLUMNS 32000

typedef struct marker_grid {
    marker_raster raster;
    int32_t margin;        /* cells left of x = 0 and below y = 0: the gap may hang over the edge */
    int32_t columns;       /* grid columns, margins included */
    int32_t words;         /* 64-bit words a row of the occupancy bitmap takes: ceil(columns / 64) */
    int32_t rows;          /* rows allocated (everything above is free) */
    int32_t dirty_rows;    /* rows written since the last reset */
    uint64_t *occupied;    /* rows x words: bit x % 64 of word x / 64 set when cell x of the row is occupied */
    int32_t *longest_run;  /* rows: the longest free run of each row */
    int32_t *block_longest; /* rows / ROW_BLOCK (32): the longest free run of each block of rows */
    int64_t work;          /* rows and positions tried by grid_find: the search's budget counts them */
    int transposed;        /* 1: the column fill's grid, x along the fabric's length (search_columns) */
    double fabric_width_mm; /* transposed: the fabric's width, the most a pass may use along the grid's y */
} marker_grid;

/* What a pass achieved: the marker's length (the highest cut-line point along the grid's y), the sum of the
 * units' tops, and the farthest cut-line point across (the grid's x). On a transposed grid, length is how much
 * of the fabric's width the pass used and across the marker's true length. */
typedef struct marker_score {
    double length, tops, across;
} marker_score;

/* The empty grid of a fabric width_mm wide with pieces gap_mm apart (no rows yet: marker_grid_grow): cells of
 * width_mm / cells_across mm, at least finest_mm (and few enough that a row has fewer than MARKER_MAX_COLUMNS). */
marker_grid marker_grid_make(double width_mm, double gap_mm, double cells_across, double finest_mm);
/* At least `rows` rows allocated (new ones free). 0 when out of memory. */
int marker_grid_grow(marker_grid *g, int32_t rows);
void marker_grid_free(marker_grid *g);
/* 1 when pass score a is better than b: shorter, then (within 1e-6 mm) a lower sum of tops. */
int marker_score_better(marker_score a, marker_score b);
/* An order entry: one copy of a piece (demand, copy 0 or 1), whether a Cut-2 piece goes as a pair or its copies
 * separately (split: the same on both its entries), and its turn (0: the best, 1 or 2: pinned to 0 or 180
 * degrees for copy 0, or for a split copy that copy). */
#define MARKER_ENTRY(demand, copy, split, turn) ((((demand) * 2 + (copy)) * 2 + (split)) * 3 + (turn))
#define MARKER_ENTRY_DEMAND(entry) ((entry) / 12)
#define MARKER_ENTRY_COPY(entry) ((entry) / 6 % 2)
#define MARKER_ENTRY_SPLIT(entry) ((entry) / 3 % 2)
#define MARKER_ENTRY_TURN(entry) ((entry) % 3)
/*
 * One greedy pass on grid g (the fabric, or its transpose for the column fill) over the `count` entries of
 * `order`: placements into out (count written, fabric coordinates either way). A paired Cut-2 piece goes as a pair
 * at its copy 0's entry (its copy 1's passed over), falling back on its two copies when no pair fits across the
 * fabric; a split one copy by copy. Turn 0 takes the candidate whose top ends lowest, 1 and 2 the first or second
 * half of the candidates only unless none of those fits. On a transposed grid a unit that fits nowhere (taller
 * than the length tried) ends the pass with an infinite score.
 */
pz_status marker_nest_pass(marker_grid *g, const pz_pieces *pieces, const marker_demand *demands, const int32_t *order,
                           int32_t count, pz_marker_placement *out, int32_t *out_count, marker_score *score,
                           pz_ctx *ctx);

/* ------------------------------------------------------------------ pattern-tiled.pdf's layout */

/* One thing on the pages: a piece (piece >= 0) or the scale box (-1), in its own frame: piece coordinates,
 * turned 90 degrees counter-clockwise ((x, y) -> (-y, x)) when `turned`. */
typedef struct tiled_item {
    int32_t piece;
    int turned;
    double lo[2], hi[2]; /* its box in its frame (the cut line's, turned) */
    int on_sheet;        /* 0: whole on page `page`; 1: larger than a page, nested on the sheet of tiles */
    int32_t page;
    double at[2];        /* whole: its box's lower-left on the page's printable area (mm, y up); on the sheet:
                          * its box's top-left on the sheet (mm, x right, y down from the sheet's top-left) */
} tiled_item;

/* A page: the sheet's tile (row, column), or (-1, -1) for a page of whole items only. Whole items also go into
 * the free parts of tile pages. */
typedef struct tiled_page {
    int32_t row, column;
} tiled_page;

typedef struct tiled_layout {
    double paper[2];       /* mm, portrait */
    double printable[2];   /* paper minus the margins */
    double step[2];        /* from one tile to the next: printable minus the shared band */
    double overlap;        /* the band neighbouring tiles share */
    double gap;            /* between whole items, and between them and a tile's ink */
    int32_t item_count, page_count;
    tiled_item *items;
    tiled_page *pages;
    int32_t sheet_rows, sheet_columns;
    int32_t *tile_page;    /* sheet_rows x sheet_columns: the page printing each tile, -1 for a blank tile */
} tiled_layout;

/*
 * The pages of pattern-tiled.pdf (docs/export.md, "pattern-tiled.pdf"): every drawn piece that fits a page
 * (turned 90 degrees if need be) whole on one page, several packed on a page; the pieces larger than a page
 * nested together on one sheet cut into tiles (tiled_sheet_nest), its blank tiles dropped; whole pieces packed
 * into the tiles' free parts too. The scale box last, where room is left, its page first. PZ_ERR_USAGE for a paper other than
 * a4/letter (NULL = a4), PZ_ERR_DATA for more than 20,000 pages, PZ_ERR_NOMEM. The caller frees with
 * tiled_layout_free.
 */
pz_status tiled_layout_build(const pz_pieces *pieces, const char *paper, tiled_layout *out, pz_ctx *ctx);
void tiled_layout_free(tiled_layout *layout);
/* Where page `page` shows item `item`: the translation from the item's frame to the page's printable area (mm, y
 * up) into move; 1 when the page shows the item (whole, or some of it on this tile). */
int tiled_item_on_page(const tiled_layout *layout, int32_t item, int32_t page, double move[2]);
/* The item's frame point of a piece point (turned when the item is). */
void tiled_turn(const tiled_item *item, const double point[2], double out[2]);

/* Shared by export/tiled_layout.c and export/tiled_sheet.c. */
/* The item of piece p (-1: the scale box) in turn `turned`, its box set. */
void tiled_item_make(const pz_pieces *pieces, int32_t p, int turned, tiled_item *item);
/* The piece's cut line in sheet coordinates for an item whose box's top-left is at `at` (malloc'd, cut_count
 * points; NULL when out of memory). */
double *tiled_sheet_outline(const pz_pieces *pieces, const tiled_item *item, const double at[2]);
/* The own part of tile (row, column) in sheet coordinates: its region without the bands it shares with the tiles
 * above and to the left (which print what lies there). */
void tiled_own_part(const tiled_layout *layout, int32_t row, int32_t column, double lo[2], double hi[2]);
/* 1 when the closed polygon has ink in the box: an edge meets it, or it covers the box. */
int tiled_polygon_meets_box(const double *points, int32_t n, const double lo[2], const double hi[2]);
/* Nests the items `which` (count of them, all larger than a page) on the sheet: sets their turn, box, on_sheet
 * and at, and layout->sheet_rows, sheet_columns. PZ_ERR_NOMEM, PZ_ERR_DATA when the sheet passes 20,000 tiles. */
pz_status tiled_sheet_nest(tiled_layout *layout, const pz_pieces *pieces, const int32_t *which, int32_t count,
                           pz_ctx *ctx);

#endif
