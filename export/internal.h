/*
 * export/internal.h -- what the files of one export part share, not part of
 * the public interface (export/export.h is). Today: the marker's pieces
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
} marker_demand;

/* Every way piece `index` may be placed (its copies in both rotations, the pairs of a Cut-2 piece, all also
 * transposed). 0 when out of memory; marker_demand_clear frees what was built either way. */
int marker_demand_build(const marker_raster *raster, const pz_pieces *pieces, int32_t index, marker_demand *out);
void marker_demand_clear(marker_demand *d);

/* ------------------------------------------------------------------ marker: the fabric grid */

/* Stretch lengths fit in 16 bits (marker_grid_make keeps the columns below 32000): half the memory traffic. */
typedef int16_t marker_stretch;
#define MARKER_MAX_COLUMNS 32000

typedef struct marker_grid {
    marker_raster raster;
    int32_t margin;        /* cells left of x = 0 and below y = 0: the gap may hang over the edge */
    int32_t columns;       /* grid columns, margins included */
    int32_t rows;          /* rows allocated (everything above is free) */
    int32_t dirty_rows;    /* rows written since the last reset */
    uint8_t *occupied;     /* rows x columns */
    marker_stretch *free_run; /* rows x columns: free cells from here rightwards, or minus the occupied ones */
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

/* The empty grid of a fabric width_mm wide with pieces gap_mm apart (no rows yet: marker_grid_grow). */
marker_grid marker_grid_make(double width_mm, double gap_mm);
/* At least `rows` rows allocated (new ones free). 0 when out of memory. */
int marker_grid_grow(marker_grid *g, int32_t rows);
void marker_grid_free(marker_grid *g);
/* 1 when pass score a is better than b: shorter, then (within 1e-6 mm) a lower sum of tops. */
int marker_score_better(marker_score a, marker_score b);
/*
 * One greedy pass on grid g (the fabric, or its transpose for the column fill): placements into out (count
 * written, fabric coordinates either way). order[i] = demand * 3 + turn: turn 0 takes the candidate whose top
 * ends lowest, 1 and 2 the first or second half of the candidates only (copy 0 at 0 or 180 degrees) unless
 * none of those fits. On a transposed grid a unit that fits nowhere (taller than the length tried) ends the
 * pass with an infinite score.
 */
pz_status marker_nest_pass(marker_grid *g, const pz_pieces *pieces, const marker_demand *demands, const int32_t *order,
                           int32_t count, pz_marker_placement *out, int32_t *out_count, marker_score *score,
                           pz_ctx *ctx);

#endif
