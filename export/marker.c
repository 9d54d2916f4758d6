/*
 * export/marker.c -- the marker: every piece nested on a strip of fabric
 * (x across the fabric width, y along its length), and marker.svg.
 *
 * Method (docs/marker.md): raster bottom-left fill.
 *  - Each piece (in each of its two allowed orientations, 0 and 180 degrees:
 *    the grain stays true) is rasterized on a grid of `resolution` mm cells,
 *    conservatively: a cell is set when it may touch the cut line dilated by
 *    gap/2. Two placements whose masks share no cell are therefore at least
 *    `gap` apart, exactly (no tolerance on the polygons themselves).
 *  - A Cut-2 piece is one unit: the first copy and its mirror image (x -> -x,
 *    grain still along +y) pushed against it on the right, same rotation.
 *    When the pair is wider than the fabric the two copies go separately.
 *  - Units are placed one by one; for each the fabric grid is scanned row by
 *    row from the bottom, and within a row from the left; the first free
 *    position (per-row free-run lengths make each mask row an O(1) test) is
 *    the lowest for that orientation. The orientation whose piece top ends
 *    lowest wins (ties: 0 degrees), which fills holes left below.
 *  - That greedy pass runs for four piece orders (area, height, width, and
 *    area with large and small pieces alternating); the shortest marker wins.
 *  - The result is deterministic: no threads, no randomness.
 * Memory: one byte per grid cell of the masks, two int32 per fabric cell.
 * Fails with PZ_ERR_DATA for a piece wider than the fabric, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/export.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

/* ------------------------------------------------------------------ masks */

/* A piece (or a pair) rasterized: width x height cells, origin at grid cell (0, 0). */
typedef struct mask {
    int32_t width, height;
    uint8_t *cells;        /* height rows of width */
    int32_t *row_first;    /* height: first set column, or -1 for an empty row */
    int32_t *row_last;     /* height: last set column */
} mask;

static void mask_clear(mask *m)
{
    free(m->cells);
    free(m->row_first);
    free(m->row_last);
    memset(m, 0, sizeof *m);
}

static int mask_alloc(mask *m, int32_t width, int32_t height)
{
    m->width = width, m->height = height;
    m->cells = calloc((size_t)width * (size_t)height, 1);
    m->row_first = malloc((size_t)height * sizeof(int32_t));
    m->row_last = malloc((size_t)height * sizeof(int32_t));
    return m->cells && m->row_first && m->row_last;
}

/* Fills each row's extent. A row's set cells are taken as one run (holes inside a row are filled):
 * conservative, and what makes the fit test O(1) per row. */
static void mask_rows(mask *m)
{
    for (int32_t y = 0; y < m->height; ++y) {
        const uint8_t *row = m->cells + (size_t)y * (size_t)m->width;
        int32_t first = -1, last = -1;
        for (int32_t x = 0; x < m->width; ++x)
            if (row[x]) {
                if (first < 0)
                    first = x;
                last = x;
            }
        m->row_first[y] = first, m->row_last[y] = last;
    }
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
 * Rasterizes the closed polygon `points` (n x 2, already transformed) with its
 * lower-left at `origin`: cells whose centre is inside, and cells whose centre
 * lies within `reach` of an edge (reach = gap/2 + half the cell diagonal, so
 * every cell touching the dilated polygon is set). 0 when out of memory.
 */
static int mask_draw_polygon(mask *m, const double *points, int32_t n, const double origin[2], double resolution,
                             double reach)
{
    /* Inside: even-odd scanline through each row's centre. */
    double *crossings = malloc((size_t)(n + 1) * sizeof(double));
    if (!crossings)
        return 0;
    for (int32_t y = 0; y < m->height; ++y) {
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
            for (int32_t x = x0 < 0 ? 0 : x0; x <= x1 && x < m->width; ++x)
                m->cells[(size_t)y * (size_t)m->width + (size_t)x] = 1;
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
        for (int32_t y = y0 < 0 ? 0 : y0; y <= y1 && y < m->height; ++y)
            for (int32_t x = x0 < 0 ? 0 : x0; x <= x1 && x < m->width; ++x) {
                uint8_t *cell = &m->cells[(size_t)y * (size_t)m->width + (size_t)x];
                if (!*cell && segment_distance(origin[0] + (x + 0.5) * resolution,
                                               origin[1] + (y + 0.5) * resolution, a, b) <= reach)
                    *cell = 1;
            }
    }
    return 1;
}

/* ------------------------------------------------------------------ units */

/* What gets placed in one go: one piece copy, or a mirrored pair side by side, in one orientation.
 * Coordinates are local to the mask: cell (c, r) covers [c, c+1) x [r, r+1) times the resolution. */
typedef struct unit {
    int member_count;
    pz_marker_placement members[2]; /* offsets map piece coordinates to mask-local mm */
    mask shape;
    double lo[2], hi[2];            /* cut-line extent, mask-local mm */
} unit;

typedef struct nest {
    double resolution, reach, width_mm;
    int32_t margin;        /* grid cells left of x = 0 and below y = 0: the gap may hang over the edge */
    int32_t columns;       /* grid columns, margins included */
    int32_t rows;          /* rows allocated (everything above is free) */
    uint8_t *occupied;     /* rows x columns */
    int32_t *free_run;     /* rows x columns: free cells from here rightwards */
    int32_t *longest_run;  /* rows: the longest free run of each row */
} nest;

static void unit_clear(unit *u)
{
    mask_clear(&u->shape);
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

/* One piece copy as a unit; its mask starts `reach` below and left of its cut line. */
static int unit_single(const nest *nest, const pz_piece *piece, int32_t index, int copy, int rotation, unit *out)
{
    memset(out, 0, sizeof *out);
    pz_marker_placement placement = {index, copy, rotation, copy == 1, {0, 0}};
    double *points = malloc((size_t)piece->cut_count * 2 * sizeof(double));
    if (!points)
        return 0;
    pz_marker_place_points(piece, &placement, piece->cut, piece->cut_count, points);
    double lo[2], hi[2];
    points_bounds(points, piece->cut_count, lo, hi);
    double origin[2] = {lo[0] - nest->reach, lo[1] - nest->reach};
    int32_t width = (int32_t)ceil((hi[0] + nest->reach - origin[0]) / nest->resolution) + 1;
    int32_t height = (int32_t)ceil((hi[1] + nest->reach - origin[1]) / nest->resolution) + 1;
    int ok = mask_alloc(&out->shape, width, height) &&
             mask_draw_polygon(&out->shape, points, piece->cut_count, origin, nest->resolution, nest->reach);
    if (ok)
        mask_rows(&out->shape);
    else
        mask_clear(&out->shape);
    free(points);
    placement.offset[0] = -origin[0], placement.offset[1] = -origin[1];
    out->member_count = 1;
    out->members[0] = placement;
    for (int d = 0; d < 2; ++d)
        out->lo[d] = lo[d] - origin[d], out->hi[d] = hi[d] - origin[d];
    return ok;
}

/* 1 when b, shifted right by `shift` cells, shares a cell with a (both bottom-aligned). */
static int masks_collide(const mask *a, const mask *b, int32_t shift)
{
    int32_t rows = a->height < b->height ? a->height : b->height;
    for (int32_t y = 0; y < rows; ++y)
        if (a->row_first[y] >= 0 && b->row_first[y] >= 0 && b->row_first[y] + shift <= a->row_last[y])
            return 1;
    return 0;
}

/* The pair: `left` (copy 0) with `right` (copy 1, mirrored) pushed against its right side. */
static int unit_pair(const nest *nest, const unit *left, const unit *right, unit *out)
{
    memset(out, 0, sizeof *out);
    int32_t shift = 0;
    while (shift < left->shape.width && masks_collide(&left->shape, &right->shape, shift))
        ++shift;
    int32_t width = shift + right->shape.width > left->shape.width ? shift + right->shape.width : left->shape.width;
    int32_t height = left->shape.height > right->shape.height ? left->shape.height : right->shape.height;
    if (!mask_alloc(&out->shape, width, height)) {
        mask_clear(&out->shape);
        return 0;
    }
    for (int32_t y = 0; y < height; ++y)
        for (int32_t x = 0; x < width; ++x) {
            int in_left = y < left->shape.height && x < left->shape.width &&
                          left->shape.cells[(size_t)y * (size_t)left->shape.width + (size_t)x];
            int in_right = y < right->shape.height && x >= shift && x - shift < right->shape.width &&
                           right->shape.cells[(size_t)y * (size_t)right->shape.width + (size_t)(x - shift)];
            out->shape.cells[(size_t)y * (size_t)width + (size_t)x] = (uint8_t)(in_left || in_right);
        }
    mask_rows(&out->shape);
    double shift_mm = shift * nest->resolution;
    out->member_count = 2;
    out->members[0] = left->members[0];
    out->members[1] = right->members[0];
    out->members[1].offset[0] += shift_mm;
    out->lo[0] = fmin(left->lo[0], right->lo[0] + shift_mm);
    out->hi[0] = fmax(left->hi[0], right->hi[0] + shift_mm);
    out->lo[1] = fmin(left->lo[1], right->lo[1]);
    out->hi[1] = fmax(left->hi[1], right->hi[1]);
    return 1;
}

/* ------------------------------------------------------------------ the fabric grid */

static int nest_grow(nest *nest, int32_t rows)
{
    if (rows <= nest->rows)
        return 1;
    int32_t new_rows = nest->rows ? nest->rows : 256;
    while (new_rows < rows)
        new_rows *= 2;
    size_t cells = (size_t)new_rows * (size_t)nest->columns;
    uint8_t *occupied = realloc(nest->occupied, cells);
    if (!occupied)
        return 0;
    nest->occupied = occupied;
    int32_t *free_run = realloc(nest->free_run, cells * sizeof(int32_t));
    if (!free_run)
        return 0;
    nest->free_run = free_run;
    int32_t *longest_run = realloc(nest->longest_run, (size_t)new_rows * sizeof(int32_t));
    if (!longest_run)
        return 0;
    nest->longest_run = longest_run;
    for (int32_t y = nest->rows; y < new_rows; ++y) {
        nest->longest_run[y] = nest->columns;
        memset(nest->occupied + (size_t)y * (size_t)nest->columns, 0, (size_t)nest->columns);
        for (int32_t x = 0; x < nest->columns; ++x)
            nest->free_run[(size_t)y * (size_t)nest->columns + (size_t)x] = nest->columns - x;
    }
    nest->rows = new_rows;
    return 1;
}

static void nest_update_row(nest *nest, int32_t y)
{
    const uint8_t *row = nest->occupied + (size_t)y * (size_t)nest->columns;
    int32_t *run = nest->free_run + (size_t)y * (size_t)nest->columns;
    int32_t count = 0, longest = 0;
    for (int32_t x = nest->columns - 1; x >= 0; --x) {
        count = row[x] ? 0 : count + 1;
        run[x] = count;
        longest = count > longest ? count : longest;
    }
    nest->longest_run[y] = longest;
}

/* 1 when the mask fits with its cell (0, 0) at grid cell (x, y): one lookup per mask row. */
static int nest_fits(const nest *nest, const mask *shape, int32_t x, int32_t y)
{
    for (int32_t r = 0; r < shape->height; ++r) {
        int32_t first = shape->row_first[r];
        if (first < 0)
            continue;
        if (y + r >= nest->rows)
            return 1; /* rows above the allocated ones are empty */
        int32_t run = nest->free_run[(size_t)(y + r) * (size_t)nest->columns + (size_t)(x + first)];
        if (run <= shape->row_last[r] - first)
            return 0;
    }
    return 1;
}

/* The lowest, then leftmost, grid cell where the unit fits with its cut line inside the fabric. */
static int nest_find(const nest *nest, const unit *u, int32_t *x_out, int32_t *y_out)
{
    int32_t x_lo = (int32_t)ceil(-u->lo[0] / nest->resolution) + nest->margin;
    int32_t x_hi = (int32_t)floor((nest->width_mm - u->hi[0]) / nest->resolution) + nest->margin;
    int32_t y_lo = (int32_t)ceil(-u->lo[1] / nest->resolution) + nest->margin;
    if (x_lo < 0)
        x_lo = 0;
    if (x_hi + u->shape.width > nest->columns)
        x_hi = nest->columns - u->shape.width;
    if (y_lo < 0)
        y_lo = 0;
    if (x_lo > x_hi)
        return 0;
    /* The mask's widest row: a fabric row whose longest free run is shorter cannot take it anywhere. */
    int32_t widest_row = 0, widest = -1;
    for (int32_t r = 0; r < u->shape.height; ++r)
        if (u->shape.row_first[r] >= 0 && u->shape.row_last[r] - u->shape.row_first[r] > widest)
            widest = u->shape.row_last[r] - u->shape.row_first[r], widest_row = r;
    for (int32_t y = y_lo; y <= nest->rows; ++y) {
        if (y + widest_row < nest->rows && nest->longest_run[y + widest_row] <= widest)
            continue;
        for (int32_t x = x_lo; x <= x_hi; ++x)
            if (nest_fits(nest, &u->shape, x, y)) {
                *x_out = x, *y_out = y;
                return 1;
            }
    }
    return 0; /* not reached: the first row above the allocated ones is empty */
}

static int nest_occupy(nest *nest, const mask *shape, int32_t x, int32_t y)
{
    if (!nest_grow(nest, y + shape->height))
        return 0;
    for (int32_t r = 0; r < shape->height; ++r) {
        for (int32_t c = 0; c < shape->width; ++c)
            if (shape->cells[(size_t)r * (size_t)shape->width + (size_t)c])
                nest->occupied[(size_t)(y + r) * (size_t)nest->columns + (size_t)(x + c)] = 1;
        nest_update_row(nest, y + r);
    }
    return 1;
}

/* ------------------------------------------------------------------ building */

/* A piece and the key that orders the placement (larger first). */
typedef struct demand {
    int32_t piece;
    double key;
} demand;

static int demand_by_key(const void *a, const void *b)
{
    const demand *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? 1 : -1;
    return x->piece < y->piece ? -1 : x->piece > y->piece;
}

/* The orders tried: by area, by height, by width, and by area with large and small pieces alternating
 * (a small piece then fills the room a large one leaves beside it). */
enum { kOrderCount = 4 };

static void order_pieces(const pz_pieces *pieces, int which, demand *order, int32_t count, demand *scratch)
{
    for (int32_t i = 0; i < count; ++i) {
        const pz_piece *piece = &pieces->pieces[order[i].piece];
        double width = piece->bbox_max[0] - piece->bbox_min[0], height = piece->bbox_max[1] - piece->bbox_min[1];
        order[i].key = which == 1 ? height : which == 2 ? width : piece->area_mm2;
    }
    qsort(order, (size_t)count, sizeof *order, demand_by_key);
    if (which != 3)
        return;
    for (int32_t i = 0, large = 0, small = count - 1; i < count; ++i)
        scratch[i] = i % 2 == 0 ? order[large++] : order[small--];
    memcpy(order, scratch, (size_t)count * sizeof *order);
}

/* Cell size: fine enough that the rasterization wastes little, coarse enough to stay fast. */
static double nest_resolution(double width_mm)
{
    double resolution = width_mm / 600.0;
    return resolution < 1.0 ? 1.0 : resolution;
}

/* A candidate unit of piece `index` in one rotation: the mirrored pair when `pair`, else copy `copy`. */
static int unit_build(const nest *nest, const pz_piece *piece, int32_t index, int pair, int copy, int rotation,
                      unit *out)
{
    if (!pair)
        return unit_single(nest, piece, index, copy, rotation, out);
    unit left = {0}, right = {0};
    int ok = unit_single(nest, piece, index, 0, rotation, &left) &&
             unit_single(nest, piece, index, 1, rotation, &right) && unit_pair(nest, &left, &right, out);
    unit_clear(&left);
    unit_clear(&right);
    return ok;
}

/* Places the unit (pair or copy) in its better rotation; *placed = 0 when it fits nowhere across the fabric. */
static pz_status place_unit(nest *nest, const pz_pieces *pieces, int32_t index, int pair, int copy,
                            pz_marker *marker, int *placed, pz_ctx *ctx)
{
    const pz_piece *piece = &pieces->pieces[index];
    unit best = {0};
    int32_t best_x = 0, best_y = 0;
    double best_top = INFINITY;
    for (int rotation = 0; rotation <= 180; rotation += 180) {
        unit candidate = {0};
        int32_t x = 0, y = 0;
        if (!unit_build(nest, piece, index, pair, copy, rotation, &candidate)) {
            unit_clear(&candidate);
            unit_clear(&best);
            return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
        }
        /* The lower top wins: 0 degrees on a tie. */
        double top = INFINITY;
        if (nest_find(nest, &candidate, &x, &y))
            top = (y - nest->margin) * nest->resolution + candidate.hi[1];
        if (top < best_top - 1e-9) {
            unit_clear(&best);
            best = candidate, best_x = x, best_y = y, best_top = top;
        } else {
            unit_clear(&candidate);
        }
    }
    *placed = isfinite(best_top);
    if (!*placed)
        return PZ_OK;
    if (!nest_occupy(nest, &best.shape, best_x, best_y)) {
        unit_clear(&best);
        return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    }
    for (int m = 0; m < best.member_count; ++m) {
        pz_marker_placement placement = best.members[m];
        placement.offset[0] += (best_x - nest->margin) * nest->resolution;
        placement.offset[1] += (best_y - nest->margin) * nest->resolution;
        marker->placements[marker->placement_count++] = placement;
    }
    unit_clear(&best);
    return PZ_OK;
}

/* Every copy of one piece: a Cut-2 piece as a pair, or its copies one by one when the pair is too wide. */
static pz_status place_piece(nest *nest, const pz_pieces *pieces, int32_t index, pz_marker *marker, pz_ctx *ctx)
{
    const pz_piece *piece = &pieces->pieces[index];
    int copies = piece->cut_quantity >= 2 ? 2 : 1, placed = 0;
    pz_status status = PZ_OK;
    if (copies == 2 && ((status = place_unit(nest, pieces, index, 1, 0, marker, &placed, ctx)) != PZ_OK || placed))
        return status;
    for (int copy = 0; copy < copies; ++copy) {
        if ((status = place_unit(nest, pieces, index, 0, copy, marker, &placed, ctx)) != PZ_OK)
            return status;
        if (!placed)
            return pz_error(ctx, PZ_ERR_DATA, "marker: piece %s (%.0f mm wide) does not fit on a fabric %.0f mm wide",
                            piece->name, piece->bbox_max[0] - piece->bbox_min[0], nest->width_mm);
    }
    return PZ_OK;
}

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

/* One greedy pass over the pieces in `order`: placements into marker (count reset). */
static pz_status nest_run(const pz_pieces *pieces, const demand *order, int32_t count, double width_mm,
                          double gap_mm, pz_marker *marker, pz_ctx *ctx)
{
    nest nest = {0};
    nest.resolution = nest_resolution(width_mm);
    nest.reach = gap_mm / 2.0 + nest.resolution * 0.5 * sqrt(2.0) + 1e-9;
    nest.width_mm = width_mm;
    nest.margin = (int32_t)ceil(nest.reach / nest.resolution) + 1;
    nest.columns = (int32_t)ceil(width_mm / nest.resolution) + 2 * nest.margin + 3;
    marker->placement_count = 0;
    pz_status status = nest_grow(&nest, 1) ? PZ_OK : pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    for (int32_t i = 0; i < count && status == PZ_OK; ++i)
        status = place_piece(&nest, pieces, order[i].piece, marker, ctx);
    free(nest.occupied);
    free(nest.free_run);
    free(nest.longest_run);
    return status;
}

pz_status pz_marker_build(const pz_pieces *pieces, const pz_export_options *options, pz_marker **out, pz_ctx *ctx)
{
    *out = NULL;
    double width_mm = options->fabric_width_mm > 0 ? options->fabric_width_mm : 1500.0;
    double gap_mm = options->gap_mm >= 0 ? options->gap_mm : 0.0;
    double start = pz_seconds();
    pz_marker *marker = calloc(1, sizeof *marker), trial = {0};
    int32_t capacity = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored)
            capacity += pieces->pieces[p].cut_quantity >= 2 ? 2 : 1;
    demand *order = malloc(((size_t)pieces->piece_count + 1) * 2 * sizeof *order);
    trial.placements = malloc(((size_t)capacity + 1) * sizeof *trial.placements);
    if (!marker || !order || !trial.placements ||
        !(marker->placements = malloc(((size_t)capacity + 1) * sizeof *marker->placements))) {
        free(order);
        free(trial.placements);
        pz_marker_free(&marker);
        return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    }
    marker->fabric_width_mm = width_mm;
    pz_status status = check_pieces(pieces, width_mm, ctx);
    if (status != PZ_OK) {
        free(order);
        free(trial.placements);
        pz_marker_free(&marker);
        return status;
    }
    int32_t order_count = 0;
    for (int32_t p = 0; p < pieces->piece_count; ++p)
        if (!pieces->pieces[p].mirrored && pieces->pieces[p].cut_count >= 3)
            order[order_count++] = (demand){p, 0.0};
    /* Greedy passes in several orders; the shortest marker wins (the first on a tie: deterministic). */
    marker->length_mm = INFINITY;
    for (int which = 0; which < kOrderCount && status == PZ_OK; ++which) {
        order_pieces(pieces, which, order, order_count, order + pieces->piece_count + 1);
        status = nest_run(pieces, order, order_count, width_mm, gap_mm, &trial, ctx);
        double length = status == PZ_OK ? marker_length(pieces, &trial) : INFINITY;
        if (length < marker->length_mm) {
            marker->length_mm = length;
            marker->placement_count = trial.placement_count;
            memcpy(marker->placements, trial.placements, (size_t)trial.placement_count * sizeof *trial.placements);
        }
    }
    free(trial.placements);
    free(order);
    if (status != PZ_OK) {
        pz_marker_free(&marker);
        return status;
    }
    double area = 0.0;
    for (int32_t p = 0; p < marker->placement_count; ++p)
        area += pieces->pieces[marker->placements[p].piece].area_mm2;
    if (marker->placement_count == 0)
        marker->length_mm = 0.0;
    marker->efficiency = marker->length_mm > 0 ? area / (width_mm * marker->length_mm) : 0.0;
    marker->ms = (pz_seconds() - start) * 1000.0;
    *out = marker;
    return PZ_OK;
}

void pz_marker_free(pz_marker **marker)
{
    if (!marker || !*marker)
        return;
    free((*marker)->placements);
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
             cJSON_AddNumberToObject(json, "ms", round(marker->ms * 10) / 10) &&
             cJSON_AddStringToObject(json, "method", "raster bottom-left fill, rotations 0/180");
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
    fprintf(file, ", fabric %.0f mm, length %.1f mm, efficiency %.1f %%, %d pieces</text>\n", width, length,
            marker->efficiency * 100.0, (int)marker->placement_count);
    fprintf(file, "<rect class=\"fabric\" x=\"0\" y=\"0\" width=\"%.2f\" height=\"%.2f\" fill=\"#fff\" "
                  "stroke=\"#00f\" stroke-width=\"0.5\"/>\n",
            width, length);
    for (int32_t p = 0; p < marker->placement_count; ++p) {
        const pz_marker_placement *placement = &marker->placements[p];
        if (!svg_placement(file, &inputs->pieces->pieces[placement->piece], placement, length))
            return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    }
    fputs("</svg>\n", file);
    return ferror(file) ? pz_error(ctx, PZ_ERR_CREATE, "%s: write error", name) : PZ_OK;
}
