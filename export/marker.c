/*
 * export/marker.c -- the marker: every piece nested on a strip of fabric
 * (x across the fabric width, y along its length), and marker.svg.
 *
 * Method (docs/marker.md): raster bottom-left fill over the true shapes,
 * with a search over the order in which pieces are placed, then a column
 * fill at fixed lengths below the best for short markers.
 *  - Grid: square cells of `resolution` mm (fabric width / 1000, at least
 *    1 mm). Each piece copy, in each allowed orientation (0 and 180 degrees:
 *    the grain stays true; the second copy of a Cut-2 piece mirrored x -> -x
 *    first), is rasterized conservatively: a cell is set when it may touch
 *    the cut line dilated by gap/2. Two placements whose cells are disjoint
 *    are therefore at least `gap` apart, exactly. A shape is kept as runs of
 *    set cells per row, so concave outlines keep their hollows and other
 *    pieces can reach into them.
 *  - A Cut-2 piece is one unit: copy 0 and its mirror image pushed against
 *    its right side as close as their cells allow, in the four rotation
 *    combinations. When no combination fits across the fabric the copies go
 *    separately.
 *  - A unit goes to the lowest, then leftmost, grid position where every
 *    run lies on free cells, in the rotation whose top ends lowest. The
 *    fabric keeps, per cell, a signed stretch length (the free cells from
 *    here rightwards, or minus the occupied ones): a run is one lookup, and
 *    a blocked run says how far right the next candidate is, so a fabric row
 *    costs O(obstacles in it), not O(width). Before a row is tried, eight
 *    probe rows of the shape must meet fabric rows with a long enough free
 *    stretch; maxima over blocks of 32 rows let a probe skip a block at once.
 *    A position is checked row by row in a strided order (widest row, then
 *    every 64th, 32nd, ...): a blocked one is found blocked after a few rows.
 *    Placing a shape mends only the stretches around its runs.
 *  - Order: greedy passes over four fixed orders (area, height, width,
 *    large and small alternating), then walks of a local search (swap two
 *    pieces, move one, or pin one's rotation), each new walk from a random
 *    order once the last one stalls, keeping the shortest marker (ties: the
 *    lower sum of the units' tops).
 *  - Column fill (markers up to two fabric widths long): the same machinery
 *    on the transposed fabric fills across the width under a fixed length L
 *    (leftmost, then lowest), so the marker ends level at L where the
 *    bottom-left fill leaves a ragged top; L steps down below the best
 *    marker while a local search finds orders that fit the width.
 *  - Budgets are counted in grid_find's steps and in passes, not timed:
 *    deterministic, no threads, no clock, a fixed xorshift seed; a marker of
 *    many pieces on a long fabric gets fewer passes.
 * Memory: the shapes' runs (O(cells on their rows)), three bytes per fabric
 * cell (occupancy, 16-bit stretch). Fails with PZ_ERR_DATA for a piece wider than the fabric
 * or with a cut-line coordinate out of range, PZ_ERR_USAGE for a fabric
 * width out of range, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/stream_status.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Grid cells across the fabric: finer wastes less fabric to the raster, coarser is faster. */
#define CELLS_ACROSS 1000.0
/* The local search's budget, counted in grid_find's steps (rows and positions tried, about 100-300 ns each):
 * deterministic, unlike a clock. At most SEARCH_MAX_PASSES passes in all, fewer for few pieces (a few orders
 * cover them: SEARCH_PASSES_PER_PIECE per piece beyond the first, on top of the fixed orders) ... */
#define SEARCH_WORK 3000000
#define SEARCH_MAX_PASSES 1000
#define SEARCH_PASSES_PER_PIECE 100
/* ... in walks: a walk that has not improved on its own best for this many passes starts again from a random
 * order (the landscape is rugged: independent walks find more than one long one). */
#define SEARCH_STALL 100
/* The column fill (search_columns): only for markers up to this many fabric widths long (a ragged top costs
 * little of a long marker, and the transposed grid is as wide as the marker is long); its own budget of steps
 * and passes, the passes it may spend on one length without fitting the fabric's width, and how far below the
 * best length it tries next (a fraction of it). */
#define COLUMN_MAX_WIDTHS 2.0
#define COLUMN_WORK 1000000
#define COLUMN_MAX_PASSES 150
#define COLUMN_STALL 60
#define COLUMN_STEP 0.005

/* ------------------------------------------------------------------ transforms */

void pz_marker_place_points(const pz_piece *piece, const pz_marker_placement *placement, const double *points,
                            int32_t point_count, double *out)
{
    (void)piece;
    double sx = placement->mirrored ? -1.0 : 1.0, sy = 1.0;
    if (placement->rotation_deg == 180)
        sx = -sx, sy = -sy;
    for (int32_t i = 0; i < point_count; ++i) {
        out[2 * i] = sx * points[2 * i] + placement->offset[0];
        out[2 * i + 1] = sy * points[2 * i + 1] + placement->offset[1];
    }
}

/* ------------------------------------------------------------------ shapes */

/* Rows of a shape whose longest run a fabric row must hold before any column is tried there. */
#define PROBES 8

/* A rasterized unit: per row, runs of set cells; column c covers [c, c + 1) x resolution, local to the shape. */
typedef struct shape {
    int32_t width, height;
    int32_t *row_start;    /* height + 1: the runs of row r are runs[2 row_start[r] .. 2 row_start[r + 1]) */
    int32_t *runs;         /* first, last column of each run (inclusive) */
    int32_t widest_row;    /* the row of the longest run ... */
    int32_t widest;        /* ... and its length - 1 (-1 for an empty shape) */
    int32_t probe_row[PROBES], probe_width[PROBES]; /* rows spread over the height and their longest run - 1 */
    int32_t *check_order;  /* height: the rows in the order grid_blocked checks them (widest first, then strided) */
} shape;

static void shape_clear(shape *s)
{
    free(s->row_start);
    free(s->runs);
    free(s->check_order);
    memset(s, 0, sizeof *s);
}

/* The runs of a width x height cell bitmap. 0 when out of memory. */
static int shape_from_cells(shape *s, const uint8_t *cells, int32_t width, int32_t height)
{
    memset(s, 0, sizeof *s);
    size_t count = 0;
    for (size_t i = 0; i < (size_t)width * (size_t)height; ++i)
        count += cells[i] && (i % (size_t)width == 0 || !cells[i - 1]);
    s->width = width, s->height = height, s->widest = -1;
    s->row_start = malloc(((size_t)height + 1) * sizeof(int32_t));
    s->runs = malloc((2 * count + 1) * sizeof(int32_t));
    s->check_order = malloc(((size_t)height + 1) * sizeof(int32_t));
    if (!s->row_start || !s->runs || !s->check_order) {
        shape_clear(s);
        return 0;
    }
    int32_t run = 0;
    for (int32_t y = 0; y < height; ++y) {
        const uint8_t *row = cells + (size_t)y * (size_t)width;
        s->row_start[y] = run;
        for (int32_t x = 0; x < width; ++x) {
            if (!row[x] || (x > 0 && row[x - 1]))
                continue;
            int32_t last = x;
            while (last + 1 < width && row[last + 1])
                ++last;
            s->runs[2 * run] = x, s->runs[2 * run + 1] = last;
            if (last - x > s->widest)
                s->widest = last - x, s->widest_row = y;
            ++run;
        }
    }
    s->row_start[height] = run;
    /* Check order: the widest row, then every 64th row, every 32nd, ... (each row once). An obstacle spans many
     * rows, so a blocked position is found blocked after a few rows instead of after a row-by-row walk from the
     * bottom: the answer is the same, found sooner. */
    int32_t filled = 0;
    if (height > 0)
        s->check_order[filled++] = s->widest_row;
    for (int32_t stride = 64; stride >= 1; stride /= 2)
        for (int32_t r = 0; r < height; r += stride)
            if (r != s->widest_row && (stride == 64 || r % (2 * stride) != 0))
                s->check_order[filled++] = r;
    for (int k = 0; k < PROBES; ++k) {
        int32_t r = k == 0 ? s->widest_row : (int32_t)((int64_t)(height - 1) * (k - 1) / (PROBES - 2));
        s->probe_row[k] = r, s->probe_width[k] = -1;
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i)
            if (s->runs[2 * i + 1] - s->runs[2 * i] > s->probe_width[k])
                s->probe_width[k] = s->runs[2 * i + 1] - s->runs[2 * i];
    }
    return 1;
}

static double segment_distance(double px, double py, const double *a, const double *b)
{
    double dx = b[0] - a[0], dy = b[1] - a[1];
    double length2 = dx * dx + dy * dy;
    double t = length2 > 0 ? ((px - a[0]) * dx + (py - a[1]) * dy) / length2 : 0.0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double ex = a[0] + t * dx - px, ey = a[1] + t * dy - py;
    return sqrt(ex * ex + ey * ey);
}

/*
 * Rasterizes the closed polygon `points` (n x 2, already transformed) into
 * `cells` (width x height) with its lower-left at `origin`: cells whose
 * centre is inside, and cells whose centre lies within `reach` of an edge
 * (reach = gap/2 + half the cell diagonal, so every cell touching the
 * dilated polygon is set). 0 when out of memory.
 */
static int draw_polygon(uint8_t *cells, int32_t width, int32_t height, const double *points, int32_t n,
                        const double origin[2], double resolution, double reach)
{
    /* Inside: even-odd scanline through each row's centre. */
    double *crossings = malloc((size_t)(n + 1) * sizeof(double));
    if (!crossings)
        return 0;
    for (int32_t y = 0; y < height; ++y) {
        double cy = origin[1] + (y + 0.5) * resolution;
        int32_t count = 0;
        for (int32_t i = 0; i < n; ++i) {
            const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % n)];
            if ((a[1] > cy) != (b[1] > cy))
                crossings[count++] = a[0] + (cy - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
        }
        for (int32_t i = 1; i < count; ++i) /* insertion sort: few crossings per row */
            for (int32_t j = i; j > 0 && crossings[j] < crossings[j - 1]; --j) {
                double t = crossings[j];
                crossings[j] = crossings[j - 1], crossings[j - 1] = t;
            }
        for (int32_t i = 0; i + 1 < count; i += 2) {
            int32_t x0 = (int32_t)ceil((crossings[i] - origin[0]) / resolution - 0.5);
            int32_t x1 = (int32_t)floor((crossings[i + 1] - origin[0]) / resolution - 0.5);
            for (int32_t x = x0 < 0 ? 0 : x0; x <= x1 && x < width; ++x)
                cells[(size_t)y * (size_t)width + (size_t)x] = 1;
        }
    }
    free(crossings);
    /* Near the outline: every cell within reach of an edge. */
    for (int32_t i = 0; i < n; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % n)];
        int32_t x0 = (int32_t)floor((fmin(a[0], b[0]) - reach - origin[0]) / resolution);
        int32_t x1 = (int32_t)ceil((fmax(a[0], b[0]) + reach - origin[0]) / resolution);
        int32_t y0 = (int32_t)floor((fmin(a[1], b[1]) - reach - origin[1]) / resolution);
        int32_t y1 = (int32_t)ceil((fmax(a[1], b[1]) + reach - origin[1]) / resolution);
        for (int32_t y = y0 < 0 ? 0 : y0; y <= y1 && y < height; ++y)
            for (int32_t x = x0 < 0 ? 0 : x0; x <= x1 && x < width; ++x) {
                uint8_t *cell = &cells[(size_t)y * (size_t)width + (size_t)x];
                if (!*cell && segment_distance(origin[0] + (x + 0.5) * resolution,
                                               origin[1] + (y + 0.5) * resolution, a, b) <= reach)
                    *cell = 1;
            }
    }
    return 1;
}

/* ------------------------------------------------------------------ units */

/* What gets placed in one go: one piece copy, or a mirrored pair, in fixed orientations. */
typedef struct unit {
    int member_count;
    pz_marker_placement members[2]; /* offsets map piece coordinates to unit-local mm */
    shape shape;
    double lo[2], hi[2];            /* cut-line extent, unit-local mm */
} unit;

typedef struct raster {
    double resolution, reach, width_mm;
} raster;

static void unit_clear(unit *u)
{
    shape_clear(&u->shape);
}

static void points_bounds(const double *points, int32_t n, double lo[2], double hi[2])
{
    lo[0] = lo[1] = INFINITY, hi[0] = hi[1] = -INFINITY;
    for (int32_t i = 0; i < n; ++i)
        for (int d = 0; d < 2; ++d) {
            lo[d] = fmin(lo[d], points[2 * i + d]);
            hi[d] = fmax(hi[d], points[2 * i + d]);
        }
}

/* One piece copy as a unit; its shape starts `reach` below and left of its cut line. 0 when out of memory. */
static int unit_single(const raster *raster, const pz_piece *piece, int32_t index, int copy, int rotation, unit *out)
{
    memset(out, 0, sizeof *out);
    pz_marker_placement placement = {index, copy, rotation, copy == 1, {0, 0}};
    double *points = malloc((size_t)piece->cut_count * 2 * sizeof(double));
    if (!points)
        return 0;
    pz_marker_place_points(piece, &placement, piece->cut, piece->cut_count, points);
    double lo[2], hi[2];
    points_bounds(points, piece->cut_count, lo, hi);
    double origin[2] = {lo[0] - raster->reach, lo[1] - raster->reach};
    int32_t width = (int32_t)ceil((hi[0] + raster->reach - origin[0]) / raster->resolution) + 1;
    int32_t height = (int32_t)ceil((hi[1] + raster->reach - origin[1]) / raster->resolution) + 1;
    uint8_t *cells = calloc((size_t)width * (size_t)height, 1);
    int ok = cells &&
             draw_polygon(cells, width, height, points, piece->cut_count, origin, raster->resolution, raster->reach) &&
             shape_from_cells(&out->shape, cells, width, height);
    free(cells);
    free(points);
    placement.offset[0] = -origin[0], placement.offset[1] = -origin[1];
    out->member_count = 1;
    out->members[0] = placement;
    for (int d = 0; d < 2; ++d)
        out->lo[d] = lo[d] - origin[d], out->hi[d] = hi[d] - origin[d];
    return ok;
}

typedef struct interval {
    int32_t first, last;
} interval;

static int compare_intervals(const void *a, const void *b)
{
    const interval *x = a, *y = b;
    return (x->first > y->first) - (x->first < y->first);
}

/*
 * The smallest shift s >= 0 (cells) at which `right`, moved right by s, shares
 * no cell with `left` (both bottom-aligned): run (a, b) of right and (c, d)
 * of left on one row collide for s in [c - b, d - a]; the answer is the first
 * s not covered by those intervals. -1 when out of memory.
 */
static int32_t pair_shift(const shape *left, const shape *right)
{
    int32_t rows = left->height < right->height ? left->height : right->height;
    size_t count = 0;
    for (int32_t y = 0; y < rows; ++y)
        count += (size_t)(left->row_start[y + 1] - left->row_start[y]) *
                 (size_t)(right->row_start[y + 1] - right->row_start[y]);
    interval *forbidden = malloc((count + 1) * sizeof *forbidden);
    if (!forbidden)
        return -1;
    size_t n = 0;
    for (int32_t y = 0; y < rows; ++y)
        for (int32_t i = right->row_start[y]; i < right->row_start[y + 1]; ++i)
            for (int32_t j = left->row_start[y]; j < left->row_start[y + 1]; ++j)
                forbidden[n++] = (interval){left->runs[2 * j] - right->runs[2 * i + 1],
                                            left->runs[2 * j + 1] - right->runs[2 * i]};
    qsort(forbidden, n, sizeof *forbidden, compare_intervals);
    int32_t shift = 0;
    for (size_t k = 0; k < n && forbidden[k].first <= shift; ++k)
        if (forbidden[k].last >= shift)
            shift = forbidden[k].last + 1;
    free(forbidden);
    return shift;
}

/* Paints a shape's runs into a cell bitmap (width columns) at column offset `shift`. */
static void paint_shape(uint8_t *cells, int32_t width, const shape *s, int32_t shift)
{
    for (int32_t y = 0; y < s->height; ++y)
        for (int32_t i = s->row_start[y]; i < s->row_start[y + 1]; ++i)
            memset(cells + (size_t)y * (size_t)width + (size_t)(s->runs[2 * i] + shift), 1,
                   (size_t)(s->runs[2 * i + 1] - s->runs[2 * i] + 1));
}

/* The pair: `left` (copy 0) with `right` (copy 1, mirrored) pushed against its right side. 0 when out of memory. */
static int unit_pair(const raster *raster, const unit *left, const unit *right, unit *out)
{
    memset(out, 0, sizeof *out);
    int32_t shift = pair_shift(&left->shape, &right->shape);
    if (shift < 0)
        return 0;
    int32_t width = shift + right->shape.width > left->shape.width ? shift + right->shape.width : left->shape.width;
    int32_t height = left->shape.height > right->shape.height ? left->shape.height : right->shape.height;
    uint8_t *cells = calloc((size_t)width * (size_t)height, 1);
    if (!cells)
        return 0;
    paint_shape(cells, width, &left->shape, 0);
    paint_shape(cells, width, &right->shape, shift);
    int ok = shape_from_cells(&out->shape, cells, width, height);
    free(cells);
    double shift_mm = shift * raster->resolution;
    out->member_count = 2;
    out->members[0] = left->members[0];
    out->members[1] = right->members[0];
    out->members[1].offset[0] += shift_mm;
    out->lo[0] = fmin(left->lo[0], right->lo[0] + shift_mm);
    out->hi[0] = fmax(left->hi[0], right->hi[0] + shift_mm);
    out->lo[1] = fmin(left->lo[1], right->lo[1]);
    out->hi[1] = fmax(left->hi[1], right->hi[1]);
    return ok;
}

/*
 * The unit seen with x and y swapped, for the column fill (search_columns): the cells transposed (square cells,
 * so the raster stays conservative), the extent swapped; the members keep their fabric offsets (place_best swaps
 * the grid position back). 0 when out of memory.
 */
static int unit_transpose(const unit *in, unit *out)
{
    memset(out, 0, sizeof *out);
    const shape *s = &in->shape;
    uint8_t *cells = calloc((size_t)s->width * (size_t)s->height + 1, 1);
    if (!cells)
        return 0;
    for (int32_t y = 0; y < s->height; ++y)
        for (int32_t i = s->row_start[y]; i < s->row_start[y + 1]; ++i)
            for (int32_t x = s->runs[2 * i]; x <= s->runs[2 * i + 1]; ++x)
                cells[(size_t)x * (size_t)s->height + (size_t)y] = 1;
    int ok = shape_from_cells(&out->shape, cells, s->height, s->width);
    free(cells);
    out->member_count = in->member_count;
    memcpy(out->members, in->members, sizeof out->members);
    out->lo[0] = in->lo[1], out->lo[1] = in->lo[0];
    out->hi[0] = in->hi[1], out->hi[1] = in->hi[0];
    return ok;
}

/* Everything one piece may be placed as: its copies in both rotations, and for a Cut-2 piece the pairs, each
 * also transposed ([1]) for the column fill. */
typedef struct demand {
    int32_t piece;
    int copies;                  /* 1, or 2 for a Cut-2 piece */
    unit singles[2][2][2];       /* [transposed][copy][0: 0 degrees, 1: 180] */
    unit pairs[2][4];            /* copies == 2: [transposed](copy 0, copy 1) turned (0,0) (0,180) (180,0) (180,180) */
    double keys[3];              /* area, height, width: the fixed orders */
} demand;

static void demand_clear(demand *d)
{
    for (int t = 0; t < 2; ++t) {
        for (int c = 0; c < 2; ++c)
            for (int r = 0; r < 2; ++r)
                unit_clear(&d->singles[t][c][r]);
        for (int k = 0; k < 4; ++k)
            unit_clear(&d->pairs[t][k]);
    }
}

static int demand_build(const raster *raster, const pz_pieces *pieces, int32_t index, demand *out)
{
    memset(out, 0, sizeof *out);
    const pz_piece *piece = &pieces->pieces[index];
    out->piece = index;
    out->copies = piece->cut_quantity >= 2 ? 2 : 1;
    out->keys[0] = piece->area_mm2;
    out->keys[1] = piece->bbox_max[1] - piece->bbox_min[1];
    out->keys[2] = piece->bbox_max[0] - piece->bbox_min[0];
    for (int c = 0; c < out->copies; ++c)
        for (int r = 0; r < 2; ++r)
            if (!unit_single(raster, piece, index, c, 180 * r, &out->singles[0][c][r]) ||
                !unit_transpose(&out->singles[0][c][r], &out->singles[1][c][r]))
                return 0;
    for (int k = 0; out->copies == 2 && k < 4; ++k)
        if (!unit_pair(raster, &out->singles[0][0][k / 2], &out->singles[0][1][k % 2], &out->pairs[0][k]) ||
            !unit_transpose(&out->pairs[0][k], &out->pairs[1][k]))
            return 0;
    return 1;
}

/* ------------------------------------------------------------------ the fabric grid */

/* Stretch lengths fit in 16 bits (grid_make keeps the columns below 32000): half the memory traffic. */
typedef int16_t stretch;
#define MAX_COLUMNS 32000

/* Rows per block of the block maxima that let grid_find skip full stretches of fabric (divides 256). */
#define ROW_BLOCK 32

typedef struct grid {
    raster raster;
    int32_t margin;        /* cells left of x = 0 and below y = 0: the gap may hang over the edge */
    int32_t columns;       /* grid columns, margins included */
    int32_t rows;          /* rows allocated (everything above is free) */
    int32_t dirty_rows;    /* rows written since the last reset */
    uint8_t *occupied;     /* rows x columns */
    stretch *free_run;     /* rows x columns: free cells from here rightwards, or minus the occupied ones */
    int32_t *longest_run;  /* rows: the longest free run of each row */
    int32_t *block_longest; /* rows / ROW_BLOCK: the longest free run of each block of rows */
    int64_t work;          /* rows and positions tried by grid_find: the search's budget counts them */
    int transposed;        /* 1: the column fill's grid, x along the fabric's length (search_columns) */
    double fabric_width_mm; /* transposed: the fabric's width, the most a pass may use along the grid's y */
} grid;

static void grid_free(grid *g)
{
    free(g->occupied);
    free(g->free_run);
    free(g->longest_run);
    free(g->block_longest);
}

/* Rows [from, to) free again (from and to multiples of ROW_BLOCK, or to = from). */
static void grid_clear_rows(grid *g, int32_t from, int32_t to)
{
    for (int32_t b = from / ROW_BLOCK; b < (to + ROW_BLOCK - 1) / ROW_BLOCK; ++b)
        g->block_longest[b] = g->columns;
    for (int32_t y = from; y < to; ++y) {
        g->longest_run[y] = g->columns;
        memset(g->occupied + (size_t)y * (size_t)g->columns, 0, (size_t)g->columns);
        stretch *run = g->free_run + (size_t)y * (size_t)g->columns;
        for (int32_t x = 0; x < g->columns; ++x)
            run[x] = (stretch)(g->columns - x);
    }
}

static int grid_grow(grid *g, int32_t rows)
{
    if (rows <= g->rows)
        return 1;
    int32_t new_rows = g->rows ? g->rows : 256;
    while (new_rows < rows)
        new_rows *= 2;
    size_t cells = (size_t)new_rows * (size_t)g->columns;
    uint8_t *occupied = realloc(g->occupied, cells);
    if (!occupied)
        return 0;
    g->occupied = occupied;
    stretch *free_run = realloc(g->free_run, cells * sizeof(stretch));
    if (!free_run)
        return 0;
    g->free_run = free_run;
    int32_t *longest_run = realloc(g->longest_run, (size_t)new_rows * sizeof(int32_t));
    if (!longest_run)
        return 0;
    g->longest_run = longest_run;
    int32_t *block_longest = realloc(g->block_longest, (size_t)(new_rows / ROW_BLOCK) * sizeof(int32_t));
    if (!block_longest)
        return 0;
    g->block_longest = block_longest;
    grid_clear_rows(g, g->rows, new_rows);
    g->rows = new_rows;
    return 1;
}

/* Everything free again, for the next pass. */
static void grid_reset(grid *g)
{
    grid_clear_rows(g, 0, (g->dirty_rows + ROW_BLOCK - 1) / ROW_BLOCK * ROW_BLOCK);
    g->dirty_rows = 0;
}

/* The last index below `before` whose byte is not `value`, or -1: eight bytes at a time (long free or occupied
 * stretches are the common case on a fabric row). */
static int32_t last_byte_not(const uint8_t *row, int32_t before, uint8_t value)
{
    const uint64_t all = 0x0101010101010101ull * value;
    int32_t x = before;
    while (x >= 8) {
        uint64_t word;
        memcpy(&word, row + x - 8, 8);
        if (word != all)
            break;
        x -= 8;
    }
    while (--x >= 0 && row[x] == value) {
    }
    return x;
}

/*
 * Marks columns [first, last] of row y (free until now) occupied and mends
 * the stretch counts around them: cells in the run and to its left, back to
 * where the stretch that ends at the run began. The row's longest free
 * stretch is walked again (one step per stretch) only when the stretch the
 * run cut into was the longest. Cells right of the run keep their counts.
 */
static void grid_fill_run(grid *g, int32_t y, int32_t first, int32_t last)
{
    uint8_t *row = g->occupied + (size_t)y * (size_t)g->columns;
    stretch *run = g->free_run + (size_t)y * (size_t)g->columns;
    int32_t start = last_byte_not(row, first, 0) + 1; /* the free stretch the run cuts into begins here */
    int32_t cut = run[start];                         /* and was this long */
    memset(row + first, 1, (size_t)(last - first + 1));
    /* The occupied stretch through the run ends (exclusive) at `end`: an occupied cell counts -(end - x). */
    int32_t end = last + 1;
    if (end < g->columns && run[end] < 0)
        end -= run[end];
    for (int32_t x = first; x <= last; ++x)
        run[x] = (stretch)(x - end);
    /* Left of the run: a free stretch now ends at `first`, or an occupied one grows. */
    if (start < first)
        for (int32_t x = start; x < first; ++x)
            run[x] = (stretch)(first - x);
    else
        for (int32_t x = last_byte_not(row, first, 1) + 1; x < first; ++x)
            run[x] = (stretch)(x - end);
    if (cut < g->longest_run[y])
        return; /* the longest stretch is elsewhere, untouched */
    int32_t longest = 0;
    for (int32_t x = 0; x < g->columns; x += run[x] > 0 ? run[x] : -run[x])
        longest = run[x] > longest ? run[x] : longest;
    g->longest_run[y] = longest;
}

/*
 * 0 when the shape fits with its cell (0, 0) at grid cell (x, y); else the
 * next column worth trying on this row. A run (a, b) whose first cell is
 * occupied moves past the occupied stretch; one whose free stretch ends
 * inside it moves past the stretch that blocks it (no position in between
 * can work). The widest row is tried first: it fails most often.
 */
static int32_t grid_blocked(const grid *g, const shape *s, int32_t x, int32_t y)
{
    for (int32_t k = 0; k < s->height; ++k) {
        int32_t r = s->check_order[k];
        if (y + r >= g->rows)
            continue; /* rows above the allocated ones are empty */
        const stretch *run = g->free_run + (size_t)(y + r) * (size_t)g->columns + x;
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i) {
            int32_t first = s->runs[2 * i], stretch = run[first];
            if (stretch <= 0)
                return x - stretch;
            if (stretch <= s->runs[2 * i + 1] - first)
                return x + stretch - run[first + stretch];
        }
    }
    return 0;
}

/* The leftmost column in [x_lo, x_hi] of row y where shape s fits; -1 when none (or when a probe row shows that
 * none can). *skip_to: past y, the first row worth trying next (y + 1 unless a block of rows can be skipped). */
static int32_t grid_row_fit(grid *g, const shape *s, int32_t y, int32_t x_lo, int32_t x_hi, int32_t *skip_to)
{
    ++g->work;
    /* A probe row needs a fabric row with a free run as long as its own: a block of fabric rows none of which
     * has one moves y past that block at once, a single such row moves y by one. */
    int hopeless = 0;
    *skip_to = y + 1;
    for (int k = 0; k < PROBES; ++k) {
        int32_t at = y + s->probe_row[k];
        if (at >= g->rows)
            continue;
        if (g->block_longest[at / ROW_BLOCK] <= s->probe_width[k]) {
            int32_t past = (at / ROW_BLOCK + 1) * ROW_BLOCK - s->probe_row[k];
            *skip_to = past > *skip_to ? past : *skip_to;
        }
        hopeless |= g->longest_run[at] <= s->probe_width[k];
    }
    if (hopeless || *skip_to > y + 1)
        return -1;
    for (int32_t x = x_lo; x <= x_hi;) {
        int32_t next = grid_blocked(g, s, x, y);
        ++g->work;
        if (next == 0)
            return x;
        x = next > x ? next : x + 1;
    }
    return -1;
}

/* The lowest, then leftmost, grid cell where the unit fits with its cut line inside the fabric; 0 if none. */
static int grid_find(grid *g, const unit *u, int32_t *x_out, int32_t *y_out)
{
    const double resolution = g->raster.resolution;
    int32_t x_lo = (int32_t)ceil(-u->lo[0] / resolution) + g->margin;
    int32_t x_hi = (int32_t)floor((g->raster.width_mm - u->hi[0]) / resolution) + g->margin;
    int32_t y_lo = (int32_t)ceil(-u->lo[1] / resolution) + g->margin;
    if (x_lo < 0)
        x_lo = 0;
    if (x_hi + u->shape.width > g->columns)
        x_hi = g->columns - u->shape.width;
    if (y_lo < 0)
        y_lo = 0;
    if (x_lo > x_hi || u->shape.widest < 0)
        return 0;
    const shape *s = &u->shape;
    for (int32_t y = y_lo; y <= g->rows;) {
        int32_t skip_to, x = grid_row_fit(g, s, y, x_lo, x_hi, &skip_to);
        if (x >= 0) {
            *x_out = x, *y_out = y;
            return 1;
        }
        y = skip_to;
    }
    return 0; /* not reached: a free row takes any shape that fits across */
}

static int grid_occupy(grid *g, const shape *s, int32_t x, int32_t y)
{
    if (!grid_grow(g, y + s->height))
        return 0;
    for (int32_t r = 0; r < s->height; ++r)
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i)
            grid_fill_run(g, y + r, x + s->runs[2 * i], x + s->runs[2 * i + 1]);
    for (int32_t b = y / ROW_BLOCK; b <= (y + s->height - 1) / ROW_BLOCK; ++b) {
        int32_t longest = 0;
        for (int32_t r = b * ROW_BLOCK; r < (b + 1) * ROW_BLOCK; ++r)
            longest = g->longest_run[r] > longest ? g->longest_run[r] : longest;
        g->block_longest[b] = longest;
    }
    if (y + s->height > g->dirty_rows)
        g->dirty_rows = y + s->height;
    return 1;
}

/* ------------------------------------------------------------------ one greedy pass */

/* What a pass achieved: the marker's length (the highest cut-line point along the grid's y), the sum of the
 * units' tops, and the farthest cut-line point across (the grid's x). On a transposed grid, length is how much
 * of the fabric's width the pass used and across the marker's true length. */
typedef struct pass_score {
    double length, tops, across;
} pass_score;

static int score_better(pass_score a, pass_score b)
{
    if (fabs(a.length - b.length) > 1e-6)
        return a.length < b.length;
    return a.tops < b.tops - 1e-6;
}

/* Places the unit of the lowest top among `candidates`; *placed = 0 when none fits across the fabric. */
static int place_best(grid *g, const unit *candidates, int count, pz_marker_placement *out, int32_t *out_count,
                      pass_score *score, int *placed)
{
    int best = -1;
    int32_t best_x = 0, best_y = 0;
    double best_top = INFINITY;
    for (int k = 0; k < count; ++k) {
        int32_t x, y;
        if (g->transposed && candidates[k].hi[1] - candidates[k].lo[1] > g->fabric_width_mm)
            continue; /* wider than the fabric: a pair that must go as two copies */
        if (!grid_find(g, &candidates[k], &x, &y))
            continue;
        double top = (y - g->margin) * g->raster.resolution + candidates[k].hi[1];
        if (top < best_top - 1e-9) /* the first on a tie: 0 degrees first */
            best = k, best_x = x, best_y = y, best_top = top;
    }
    *placed = best >= 0;
    if (best < 0)
        return 1;
    const unit *u = &candidates[best];
    if (!grid_occupy(g, &u->shape, best_x, best_y))
        return 0;
    double at[2] = {(best_x - g->margin) * g->raster.resolution, (best_y - g->margin) * g->raster.resolution};
    for (int m = 0; m < u->member_count; ++m) {
        pz_marker_placement placement = u->members[m];
        placement.offset[0] += at[g->transposed], placement.offset[1] += at[!g->transposed];
        out[(*out_count)++] = placement;
    }
    score->length = fmax(score->length, best_top);
    score->tops += best_top;
    score->across = fmax(score->across, at[0] + u->hi[0]);
    return 1;
}

/*
 * One greedy pass on grid g (the fabric, or its transpose for the column fill): placements into out (count
 * written, fabric coordinates either way). order[i] = demand * 3 + turn: turn 0 takes the candidate whose top
 * ends lowest, 1 and 2 the first or second half of the candidates only (copy 0 at 0 or 180 degrees) unless
 * none of those fits. On a transposed grid a unit that fits nowhere (taller than the length tried) ends the
 * pass with an infinite score.
 */
static pz_status nest_pass(grid *g, const pz_pieces *pieces, const demand *demands, const int32_t *order,
                           int32_t count, pz_marker_placement *out, int32_t *out_count, pass_score *score,
                           pz_ctx *ctx)
{
    grid_reset(g);
    *out_count = 0;
    *score = (pass_score){0, 0, 0};
    const int t = g->transposed;
    for (int32_t i = 0; i < count; ++i) {
        const demand *d = &demands[order[i] / 3];
        int turn = order[i] % 3, placed = 0, ok = 1;
        if (d->copies == 2) {
            if (turn)
                ok = place_best(g, d->pairs[t] + 2 * (turn - 1), 2, out, out_count, score, &placed);
            if (ok && !placed)
                ok = place_best(g, d->pairs[t], 4, out, out_count, score, &placed);
        }
        for (int c = 0; ok && !placed && c < d->copies; ++c) {
            int fitted = 0;
            if (turn)
                ok = place_best(g, d->singles[t][c] + (turn - 1), 1, out, out_count, score, &fitted);
            if (ok && !fitted)
                ok = place_best(g, d->singles[t][c], 2, out, out_count, score, &fitted);
            if (ok && !fitted && t) {
                score->length = INFINITY; /* longer than the column fill's length: this length fails */
                return PZ_OK;
            }
            if (ok && !fitted) {
                const pz_piece *piece = &pieces->pieces[d->piece];
                return pz_error(ctx, PZ_ERR_DATA, "marker: piece %s (%.0f mm wide) does not fit on a fabric %.0f mm wide",
                                piece->name, piece->bbox_max[0] - piece->bbox_min[0], g->raster.width_mm);
            }
        }
        if (!ok)
            return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    }
    return PZ_OK;
}

/* ------------------------------------------------------------------ the search over orders */

/* The fixed orders: by area, height, width (decreasing), and by area with large and small pieces alternating. */
enum { kFixedOrders = 4 };

static void fixed_order(const demand *demands, int32_t count, int which, int32_t *order, int32_t *scratch)
{
    int key = which == 3 ? 0 : which;
    for (int32_t i = 0; i < count; ++i)
        order[i] = 3 * i;
    /* Insertion sort, decreasing key, stable (demands are in piece order): few pieces, and deterministic. */
    for (int32_t i = 1; i < count; ++i)
        for (int32_t j = i; j > 0 && demands[order[j] / 3].keys[key] > demands[order[j - 1] / 3].keys[key]; --j) {
            int32_t t = order[j];
            order[j] = order[j - 1], order[j - 1] = t;
        }
    if (which != 3)
        return;
    for (int32_t i = 0, large = 0, small = count - 1; i < count; ++i)
        scratch[i] = i % 2 == 0 ? order[large++] : order[small--];
    memcpy(order, scratch, (size_t)count * sizeof *order);
}

/* xorshift64*: a fixed sequence, so the search is deterministic. */
static uint64_t next_random(uint64_t *state)
{
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return *state * 2685821657736338717ull;
}

/* A random order (Fisher-Yates from the fixed xorshift sequence), every piece's turn free. */
static void random_order(int32_t *order, int32_t count, uint64_t *state)
{
    for (int32_t i = 0; i < count; ++i)
        order[i] = 3 * i;
    for (int32_t i = count - 1; i > 0; --i) {
        int32_t j = (int32_t)(next_random(state) % (uint64_t)(i + 1)), t = order[i];
        order[i] = order[j], order[j] = t;
    }
}

/* A neighbour of `order`: one piece's turn changed, two pieces swapped, or one moved to another place. */
static void perturb(int32_t *order, int32_t count, uint64_t *state)
{
    int32_t i = (int32_t)(next_random(state) % (uint64_t)count);
    int32_t j = (int32_t)(next_random(state) % (uint64_t)(count - 1));
    j += j >= i;
    uint64_t move = next_random(state) % 3;
    if (move == 0) {
        order[i] = order[i] / 3 * 3 + (order[i] % 3 + 1 + (int32_t)(next_random(state) % 2)) % 3;
        return;
    }
    if (move == 1) {
        int32_t t = order[i];
        order[i] = order[j], order[j] = t;
        return;
    }
    int32_t moved = order[i];
    if (i < j)
        memmove(order + i, order + i + 1, (size_t)(j - i) * sizeof *order);
    else
        memmove(order + j + 1, order + j, (size_t)(i - j) * sizeof *order);
    order[j] = moved;
}

typedef struct search {
    grid grid;                  /* the bottom-left fill's */
    grid column;                /* the column fill's (transposed; columns == 0 until column_grid makes it) */
    const pz_pieces *pieces;
    const demand *demands;
    int32_t count;              /* demands */
    int32_t *order, *trial_order, *scratch;
    pz_marker_placement *trial; /* a pass's placements */
    pz_marker *best;            /* the best pass so far (placements, placement_count) */
    pass_score best_score;      /* its true length (along the fabric) and tops */
    int32_t passes;
    int64_t work;               /* grid_find's steps over all passes */
    uint64_t random;            /* xorshift state */
} search;

/* Runs one pass over `order` on grid g; keeps it in s->best when its marker is shorter (a column fill's only when
 * it fits the fabric's width). *score: the pass's, in g's axes. */
static pz_status search_try(search *s, grid *g, const int32_t *order, pass_score *score, pz_ctx *ctx)
{
    int32_t placed = 0;
    pz_status status = nest_pass(g, s->pieces, s->demands, order, s->count, s->trial, &placed, score, ctx);
    ++s->passes;
    s->work += g->work;
    g->work = 0;
    pass_score marker = *score;
    if (g->transposed)
        marker = (pass_score){score->length <= g->fabric_width_mm ? score->across : INFINITY, score->tops, 0};
    if (status == PZ_OK && isfinite(marker.length) && (s->passes == 1 || score_better(marker, s->best_score))) {
        s->best_score = marker;
        s->best->placement_count = placed;
        memcpy(s->best->placements, s->trial, (size_t)placed * sizeof *s->trial);
    }
    return status;
}

/* `order`, just run with `score`, becomes the search's current order. */
static void search_adopt(search *s, const int32_t *order, const pass_score *score, pass_score *current)
{
    *current = *score;
    if (order != s->order)
        memcpy(s->order, order, (size_t)s->count * sizeof *s->order);
}

/* The fixed orders on grid g (the first always, the others while s->work is below budget); the best of them into
 * s->order, its score into *current. */
static pz_status search_fixed(search *s, grid *g, int64_t budget, pass_score *current, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    pass_score score;
    *current = (pass_score){INFINITY, INFINITY, 0};
    for (int which = 0; which < kFixedOrders && (which == 0 || s->work < budget) && status == PZ_OK; ++which) {
        fixed_order(s->demands, s->count, which, s->trial_order, s->scratch);
        status = search_try(s, g, s->trial_order, &score, ctx);
        if (status == PZ_OK && score_better(score, *current))
            search_adopt(s, s->trial_order, &score, current);
    }
    return status;
}

/* One neighbour of s->order on grid g; it replaces s->order when no worse than *current (so the search walks
 * along plateaus of equal length). */
static pz_status search_step(search *s, grid *g, pass_score *current, pass_score *score, pz_ctx *ctx)
{
    memcpy(s->trial_order, s->order, (size_t)s->count * sizeof *s->order);
    perturb(s->trial_order, s->count, &s->random);
    pz_status status = search_try(s, g, s->trial_order, score, ctx);
    if (status == PZ_OK && !score_better(*current, *score))
        search_adopt(s, s->trial_order, score, current);
    return status;
}

/* The bottom-left fill: the fixed orders, then walks of a local search, the first from the best of them, each
 * further one from a random order once the last has gone SEARCH_STALL passes without improving on its own best.
 * The first order always runs; every other pass only while the work budget lasts, so a marker of many pieces on a
 * long fabric (where one pass costs the most) gets fewer passes. */
static pz_status search_rows(search *s, pz_ctx *ctx)
{
    pass_score current, score;
    pz_status status = search_fixed(s, &s->grid, SEARCH_WORK, &current, ctx);
    int32_t since_better = 0;
    pass_score walk_best = current;
    int32_t max_passes = kFixedOrders + SEARCH_PASSES_PER_PIECE * (s->count - 1);
    max_passes = max_passes < SEARCH_MAX_PASSES ? max_passes : SEARCH_MAX_PASSES;
    while (s->work < SEARCH_WORK && s->passes < max_passes && s->count > 1 && status == PZ_OK) {
        if (since_better >= SEARCH_STALL) { /* a new walk */
            random_order(s->order, s->count, &s->random);
            status = search_try(s, &s->grid, s->order, &score, ctx);
            search_adopt(s, s->order, &score, &current);
            walk_best = current, since_better = 0;
            continue;
        }
        status = search_step(s, &s->grid, &current, &score, ctx);
        if (score_better(current, walk_best))
            walk_best = current, since_better = 0;
        else
            ++since_better;
    }
    return status;
}

/* s->column set for a marker of length_mm: a transposed grid (its rows run across the fabric), made once for the
 * first (the longest) length tried; a shorter length only moves the limit grid_find keeps the units below (the
 * cells past it stay free and unused). 0 when that length needs more columns than a grid may have, -1 when out
 * of memory. */
static int column_grid(search *s, double length_mm)
{
    if (s->column.columns) {
        s->column.raster.width_mm = length_mm;
        return 1;
    }
    grid g = {.raster = s->grid.raster, .margin = s->grid.margin, .transposed = 1,
              .fabric_width_mm = s->grid.raster.width_mm};
    g.raster.width_mm = length_mm;
    g.columns = (int32_t)ceil(length_mm / g.raster.resolution) + 2 * g.margin + 3;
    if (g.columns >= MAX_COLUMNS)
        return 0;
    s->column = g;
    return grid_grow(&s->column, 1) ? 1 : -1;
}

/*
 * The column fill: fix the marker's length L below the best one found, and fill the fabric across its width
 * instead of along its length -- each unit to the leftmost, then lowest, place with its top below L (the
 * bottom-left fill on the transposed fabric). The columns so filled end level at L, where the bottom-left fill
 * leaves a ragged top. A local search over the order minimizes the width used; as soon as a pass fits the
 * fabric's width, its marker is kept (its length is at most L) and L goes one step below it.
 */
static pz_status search_columns(search *s, pz_ctx *ctx)
{
    const double resolution = s->grid.raster.resolution;
    double tallest = 0.0;
    for (int32_t i = 0; i < s->count; ++i)
        tallest = fmax(tallest, s->demands[i].singles[0][0][0].hi[1] - s->demands[i].singles[0][0][0].lo[1]);
    int64_t budget = s->work + COLUMN_WORK;
    int32_t max_passes = s->passes + COLUMN_MAX_PASSES, since_feasible = 0;
    pz_status status = PZ_OK;
    pass_score current, score;
    int first = 1;
    while (status == PZ_OK && s->work < budget && s->passes < max_passes && since_feasible < COLUMN_STALL) {
        double length = s->best_score.length - fmax(2 * resolution, COLUMN_STEP * s->best_score.length);
        if (length < tallest + 2 * resolution)
            break;
        int made = column_grid(s, length);
        if (made < 0)
            return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
        if (made == 0)
            break;
        if (first) {
            status = search_fixed(s, &s->column, budget, &current, ctx);
            first = 0;
        } else { /* the current order again, at the new length */
            status = search_try(s, &s->column, s->order, &score, ctx);
            search_adopt(s, s->order, &score, &current);
        }
        while (status == PZ_OK && current.length > s->column.fabric_width_mm && s->work < budget &&
               s->passes < max_passes && since_feasible < COLUMN_STALL && s->count > 1) {
            status = search_step(s, &s->column, &current, &score, ctx);
            ++since_feasible;
        }
        if (current.length <= s->column.fabric_width_mm)
            since_feasible = 0;
    }
    return status;
}

/* The bottom-left fill's search, then the column fill's below its best length; the shortest marker of all. The
 * budgets are counted, not timed: deterministic. */
static pz_status search_run(search *s, pz_ctx *ctx)
{
    s->random = 0x9e3779b97f4a7c15ull;
    pz_status status = search_rows(s, ctx);
    if (status == PZ_OK && s->count > 0 && s->best_score.length <= COLUMN_MAX_WIDTHS * s->grid.raster.width_mm)
        status = search_columns(s, ctx);
    return status;
}

/* ------------------------------------------------------------------ building */

/* Used length: the highest point of any placed cut line. */
static double marker_length(const pz_pieces *pieces, const pz_marker *marker)
{
    double length = 0.0;
    for (int32_t p = 0; p < marker->placement_count; ++p) {
        const pz_marker_placement *placement = &marker->placements[p];
        const pz_piece *piece = &pieces->pieces[placement->piece];
        for (int32_t i = 0; i < piece->cut_count; ++i) {
            double point[2];
            pz_marker_place_points(piece, placement, &piece->cut[2 * i], 1, point);
            length = fmax(length, point[1]);
        }
    }
    return length;
}

/* Refuses what cannot be rasterized: non-finite coordinates, outlines longer than the grid can index. */
static pz_status check_pieces(const pz_pieces *pieces, double width_mm, pz_ctx *ctx)
{
    const double largest_mm = 1e6; /* a kilometre of fabric: far beyond any marker, far inside int32 cells */
    if (!isfinite(width_mm) || width_mm > largest_mm)
        return pz_error(ctx, PZ_ERR_USAGE, "marker: fabric width %g mm is out of range", width_mm);
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        for (int32_t i = 0; i < 2 * piece->cut_count; ++i)
            if (!isfinite(piece->cut[i]) || fabs(piece->cut[i]) > largest_mm)
                return pz_error(ctx, PZ_ERR_DATA, "marker: piece %s has a cut-line coordinate out of range (%g)",
                                piece->name, piece->cut[i]);
    }
    return PZ_OK;
}

/* 1 when the piece's cut line is wider than the fabric (in cells: the raster rounds a width up to whole
 * cells and keeps its reach clear of the edges). */
static int wider_than_fabric(const raster *raster, const pz_piece *piece)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int32_t i = 0; i < piece->cut_count; ++i) {
        lo = fmin(lo, piece->cut[2 * i]);
        hi = fmax(hi, piece->cut[2 * i]);
    }
    return hi - lo + 2 * raster->resolution > raster->width_mm;
}

/* The demands of every drawn piece (mirrored == 0, a cut line to place) that fits the fabric's width;
 * *count written, the others listed in marker->unplaced. */
static pz_status build_demands(const raster *raster, const pz_pieces *pieces, demand *demands, int32_t *count,
                               pz_marker *marker, pz_ctx *ctx)
{
    *count = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p) {
        const pz_piece *piece = &pieces->pieces[p];
        if (piece->mirrored || piece->cut_count < 3)
            continue;
        if (wider_than_fabric(raster, piece)) {
            marker->unplaced[marker->unplaced_count++] = p;
            continue;
        }
        if (!demand_build(raster, pieces, p, &demands[(*count)++]))
            return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    }
    return PZ_OK;
}

static grid grid_make(double width_mm, double gap_mm)
{
    grid g = {.raster = {0, 0, width_mm}};
    g.raster.resolution = fmax(fmax(1.0, width_mm / CELLS_ACROSS), (width_mm + gap_mm + 8.0) / (MAX_COLUMNS - 32));
    g.raster.reach = gap_mm / 2.0 + g.raster.resolution * 0.5 * sqrt(2.0) + 1e-9;
    g.margin = (int32_t)ceil(g.raster.reach / g.raster.resolution) + 1;
    g.columns = (int32_t)ceil(width_mm / g.raster.resolution) + 2 * g.margin + 3;
    return g;
}

pz_status pz_marker_build(const pz_pieces *pieces, const pz_export_options *options, pz_marker **out, pz_ctx *ctx)
{
    *out = NULL;
    double width_mm = options->fabric_width_mm > 0 ? options->fabric_width_mm : 1500.0;
    double gap_mm = options->gap_mm >= 0 ? options->gap_mm : 0.0;
    double start = pz_seconds();
    pz_status status = check_pieces(pieces, width_mm, ctx);
    if (status != PZ_OK)
        return status;
    size_t n = (size_t)pieces->piece_count + 1;
    search s = {.grid = grid_make(width_mm, gap_mm), .pieces = pieces};
    demand *demands = calloc(n, sizeof *demands);
    s.order = malloc(3 * n * sizeof(int32_t));
    s.trial = malloc(2 * n * sizeof *s.trial);
    s.best = calloc(1, sizeof *s.best);
    if (s.best) {
        s.best->placements = malloc(2 * n * sizeof *s.best->placements);
        s.best->unplaced = malloc(n * sizeof *s.best->unplaced);
    }
    if (!demands || !s.order || !s.trial || !s.best || !s.best->placements || !s.best->unplaced ||
        !grid_grow(&s.grid, 1))
        status = pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    if (status == PZ_OK) {
        s.trial_order = s.order + n, s.scratch = s.order + 2 * n;
        s.demands = demands;
        status = build_demands(&s.grid.raster, pieces, demands, &s.count, s.best, ctx);
    }
    if (status == PZ_OK)
        status = search_run(&s, ctx);
    pz_marker *marker = s.best;
    if (status == PZ_OK) {
        marker->fabric_width_mm = width_mm;
        marker->length_mm = marker->placement_count ? marker_length(pieces, marker) : 0.0;
        double area = 0.0;
        for (int32_t p = 0; p < marker->placement_count; ++p)
            area += pieces->pieces[marker->placements[p].piece].area_mm2;
        marker->efficiency = marker->length_mm > 0 ? area / (width_mm * marker->length_mm) : 0.0;
        marker->passes = s.passes;
        marker->ms = (pz_seconds() - start) * 1000.0;
    }
    for (int32_t i = 0; demands && i < pieces->piece_count; ++i)
        demand_clear(&demands[i]);
    free(demands);
    free(s.order);
    free(s.trial);
    grid_free(&s.grid);
    grid_free(&s.column);
    if (status != PZ_OK) {
        pz_marker_free(&marker);
        return status;
    }
    *out = marker;
    return PZ_OK;
}

void pz_marker_free(pz_marker **marker)
{
    if (!marker || !*marker)
        return;
    free((*marker)->placements);
    free((*marker)->unplaced);
    free(*marker);
    *marker = NULL;
}

cJSON *pz_marker_report_json(const pz_marker *marker)
{
    cJSON *json = cJSON_CreateObject();
    if (!json)
        return NULL;
    int ok = cJSON_AddNumberToObject(json, "length_mm", round(marker->length_mm * 10) / 10) &&
             cJSON_AddNumberToObject(json, "efficiency", round(marker->efficiency * 10000) / 10000) &&
             cJSON_AddNumberToObject(json, "fabric_width_mm", marker->fabric_width_mm) &&
             cJSON_AddNumberToObject(json, "pieces", marker->placement_count) &&
             cJSON_AddNumberToObject(json, "passes", marker->passes) &&
             cJSON_AddNumberToObject(json, "ms", round(marker->ms * 10) / 10) &&
             cJSON_AddStringToObject(json, "method",
                                     "raster bottom-left fill over true shapes, order search with restarts, "
                                     "column fill below the best length, rotations 0/180");
    cJSON *unplaced = ok ? cJSON_AddArrayToObject(json, "unplaced") : NULL;
    ok = ok && unplaced;
    for (int32_t i = 0; ok && i < marker->unplaced_count; ++i)
        ok = cJSON_AddItemToArray(unplaced, cJSON_CreateNumber(marker->unplaced[i]));
    if (!ok)
        cJSON_Delete(json);
    return ok ? json : NULL;
}

/* ------------------------------------------------------------------ marker.svg */

/* A polyline of placed points as an SVG path (y flipped: the fabric's y grows upwards on the page). */
static void svg_path(FILE *file, const double *points, int32_t n, int closed, double length, const char *style)
{
    fprintf(file, "<path %s d=\"", style);
    for (int32_t i = 0; i < n; ++i)
        fprintf(file, "%s%.2f %.2f", i ? " L" : "M", points[2 * i], length - points[2 * i + 1]);
    fprintf(file, "%s\"/>\n", closed ? " Z" : "");
}

/* Writes one placement: cut line, sew line, grain arrow (rotating with the piece), name. */
static int svg_placement(FILE *file, const pz_piece *piece, const pz_marker_placement *placement, double length)
{
    int32_t n = piece->cut_count > piece->sew_count ? piece->cut_count : piece->sew_count;
    double *points = malloc(((size_t)n + 3) * 2 * sizeof(double));
    if (!points)
        return 0;
    fprintf(file, "<g class=\"piece\" data-piece=\"%d\" data-copy=\"%d\" data-rotation=\"%d\">\n",
            (int)placement->piece, (int)placement->copy, placement->rotation_deg);
    pz_marker_place_points(piece, placement, piece->cut, piece->cut_count, points);
    svg_path(file, points, piece->cut_count, 1, length, "class=\"cut\" fill=\"#f4efe4\" stroke=\"#000\" stroke-width=\"0.6\"");
    pz_marker_place_points(piece, placement, piece->sew, piece->sew_count, points);
    svg_path(file, points, piece->sew_count, 1, length,
             "class=\"sew\" fill=\"none\" stroke=\"#555\" stroke-width=\"0.3\" stroke-dasharray=\"3 2\"");
    double grain[2][2];
    pz_marker_place_points(piece, placement, &piece->grain[0][0], 2, &grain[0][0]);
    svg_path(file, &grain[0][0], 2, 0, length,
             "class=\"grain\" fill=\"none\" stroke=\"#000\" stroke-width=\"0.5\" marker-end=\"url(#arrow)\"");
    double centre[2] = {(grain[0][0] + grain[1][0]) / 2, (grain[0][1] + grain[1][1]) / 2};
    fprintf(file, "<text x=\"%.2f\" y=\"%.2f\" font-size=\"12\" font-family=\"sans-serif\">", centre[0] + 4,
            length - centre[1]);
    pz_xml_put_text(file, piece->name);
    fprintf(file, "%s</text>\n", placement->mirrored ? " (mirrored)" : "");
    fputs("</g>\n", file);
    free(points);
    return 1;
}

pz_status pz_export_write_marker_svg(FILE *file, const pz_export_inputs *inputs, const char *name, pz_ctx *ctx)
{
    const pz_marker *marker = inputs->marker;
    if (!marker)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: no marker was built", name);
    double width = marker->fabric_width_mm, length = marker->length_mm, band = 40.0;
    fprintf(file,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.2fmm\" height=\"%.2fmm\" "
            "viewBox=\"0 %.2f %.2f %.2f\">\n",
            width, length + band, -band, width, length + band);
    fputs("<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"10\" refY=\"5\" markerWidth=\"8\" "
          "markerHeight=\"8\" orient=\"auto\"><path d=\"M0 0 L10 5 L0 10 Z\"/></marker></defs>\n",
          file);
    fprintf(file, "<text x=\"5\" y=\"%.2f\" font-size=\"14\" font-family=\"sans-serif\">marker: ", -band / 2);
    pz_xml_put_text(file, inputs->pieces->garment_name);
    fprintf(file, ", fabric %.0f mm, length %.1f mm, efficiency %.1f %%, %d pieces", width, length,
            marker->efficiency * 100.0, (int)marker->placement_count);
    for (int32_t i = 0; i < marker->unplaced_count; ++i) {
        fputs(i ? ", " : "; wider than the fabric, not placed: ", file);
        pz_xml_put_text(file, inputs->pieces->pieces[marker->unplaced[i]].name);
    }
    fputs("</text>\n", file);
    fprintf(file, "<rect class=\"fabric\" x=\"0\" y=\"0\" width=\"%.2f\" height=\"%.2f\" fill=\"#fff\" "
                  "stroke=\"#00f\" stroke-width=\"0.5\"/>\n",
            width, length);
    for (int32_t p = 0; p < marker->placement_count; ++p) {
        const pz_marker_placement *placement = &marker->placements[p];
        if (!svg_placement(file, &inputs->pieces->pieces[placement->piece], placement, length))
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    }
    fputs("</svg>\n", file);
    return pz_export_stream_status(file, 0, name, ctx);
}
