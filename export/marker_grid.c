/*
 * export/marker_grid.c -- the marker's fabric grid and one greedy pass over
 * it (docs/marker.md): a unit goes to the lowest, then leftmost, grid
 * position where every run of its shape lies on free cells, in the rotation
 * whose top ends lowest. The fabric is a bitmap, a bit per cell and 64 cells
 * to a word: a run is checked a word at a time, and one that meets an
 * occupied cell says how far right the next candidate is (past the occupied
 * stretch it met: no position in between can work), so a fabric row costs
 * O(obstacles in it), not O(width). Placing a shape sets its runs' bits and
 * finds each touched row's longest free stretch again; a new pass clears the
 * rows used (a 13 m marker on 2.25 mm cells: 0.5 MB). Before a row is
 * tried, eight probe rows of the shape must meet fabric rows with a long
 * enough free stretch; maxima over blocks of 32 rows let a probe skip a block
 * at once. A position is checked row by row in a strided order (widest row,
 * then every 64th, 32nd, ...): a blocked one is found blocked after a few
 * rows.
 *
 * Separate from the search over orders (export/marker.c), which runs many
 * passes and only calls marker_nest_pass, and from the shapes
 * (export/marker_shapes.c): this is the inner loop, with its own data.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ the fabric grid */

/* Rows per block of the block maxima that let grid_find skip full stretches of fabric (divides 256). */
#define ROW_BLOCK 32

void marker_grid_free(marker_grid *g)
{
    free(g->occupied);
    free(g->longest_run);
    free(g->block_longest);
}

/* The row's words: bit x % 64 of word x / 64 set when cell x is occupied. */
static uint64_t *grid_row(const marker_grid *g, int32_t y)
{
    return g->occupied + (size_t)y * (size_t)g->words;
}

/* Rows [from, to) free again (from and to multiples of ROW_BLOCK, or to = from). */
static void grid_clear_rows(marker_grid *g, int32_t from, int32_t to)
{
    for (int32_t b = from / ROW_BLOCK; b < (to + ROW_BLOCK - 1) / ROW_BLOCK; ++b)
        g->block_longest[b] = g->columns;
    for (int32_t y = from; y < to; ++y)
        g->longest_run[y] = g->columns;
    if (to > from)
        memset(grid_row(g, from), 0, (size_t)(to - from) * (size_t)g->words * sizeof *g->occupied);
}

int marker_grid_grow(marker_grid *g, int32_t rows)
{
    if (rows <= g->rows)
        return 1;
    int32_t new_rows = g->rows ? g->rows : 256;
    while (new_rows < rows)
        new_rows *= 2;
    g->words = (g->columns + 63) / 64;
    uint64_t *occupied = realloc(g->occupied, (size_t)new_rows * (size_t)g->words * sizeof *occupied);
    if (!occupied)
        return 0;
    g->occupied = occupied;
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
static void grid_reset(marker_grid *g)
{
    grid_clear_rows(g, 0, (g->dirty_rows + ROW_BLOCK - 1) / ROW_BLOCK * ROW_BLOCK);
    g->dirty_rows = 0;
}

/* The first cell in [from, to] whose bit is `value` (1: occupied, 0: free), or to + 1: a word at a time. */
static int32_t first_cell(const uint64_t *row, int32_t from, int32_t to, int value)
{
    const uint64_t flip = value ? 0 : ~0ull; /* look for set bits of word ^ flip */
    uint32_t w = (uint32_t)from >> 6; /* from >= 0: shifts, not signed divisions (the inner loop of the search) */
    uint64_t word = (row[w] ^ flip) & (~0ull << ((uint32_t)from & 63));
    for (;;) {
        if (word) {
            int32_t at = (int32_t)(w << 6) + __builtin_ctzll(word);
            return at <= to ? at : to + 1;
        }
        if ((int32_t)(++w << 6) > to)
            return to + 1;
        word = row[w] ^ flip;
    }
}

/* Sets cells [first, last] of the row. */
static void set_cells(uint64_t *row, int32_t first, int32_t last)
{
    uint32_t w0 = (uint32_t)first >> 6, w1 = (uint32_t)last >> 6;
    uint64_t lo = ~0ull << ((uint32_t)first & 63), hi = ~0ull >> (63 - ((uint32_t)last & 63));
    if (w0 == w1) {
        row[w0] |= lo & hi;
        return;
    }
    row[w0] |= lo;
    for (uint32_t w = w0 + 1; w < w1; ++w)
        row[w] = ~0ull;
    row[w1] |= hi;
}

/* The longest stretch of free cells of row y (one step per stretch). */
static int32_t row_longest(const marker_grid *g, int32_t y)
{
    const uint64_t *row = grid_row(g, y);
    const int32_t last = g->columns - 1;
    int32_t longest = 0;
    for (int32_t x = first_cell(row, 0, last, 0); x <= last;) {
        int32_t end = first_cell(row, x, last, 1); /* free [x, end) */
        longest = end - x > longest ? end - x : longest;
        x = end > last ? end : first_cell(row, end, last, 0);
    }
    return longest;
}

/*
 * 0 when the shape fits with its cell (0, 0) at grid cell (x, y); else the
 * next column worth trying on this row: a run (a, b) that meets an occupied
 * cell moves past the occupied stretch it meets first (no position in
 * between can work). Rows go in the shape's check order (the widest row
 * first: it fails most often, then strided).
 */
static int32_t grid_blocked(const marker_grid *g, const marker_shape *s, int32_t x, int32_t y)
{
    const int32_t last = g->columns - 1;
    for (int32_t k = 0; k < s->height; ++k) {
        int32_t r = s->check_order[k];
        if (y + r >= g->rows)
            continue; /* rows above the allocated ones are empty */
        const uint64_t *row = grid_row(g, y + r);
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i) {
            int32_t first = x + s->runs[2 * i], blocked = first_cell(row, first, x + s->runs[2 * i + 1], 1);
            if (blocked <= x + s->runs[2 * i + 1])
                return first_cell(row, blocked, last, 0) - s->runs[2 * i];
        }
    }
    return 0;
}

/* The leftmost column in [x_lo, x_hi] of row y where shape s fits; -1 when none (or when a probe row shows that
 * none can). *skip_to: past y, the first row worth trying next (y + 1 unless a block of rows can be skipped). */
static int32_t grid_row_fit(marker_grid *g, const marker_shape *s, int32_t y, int32_t x_lo, int32_t x_hi,
                            int32_t *skip_to)
{
    ++g->work;
    /* A probe row needs a fabric row with a free run as long as its own: a block of fabric rows none of which
     * has one moves y past that block at once, a single such row moves y by one. */
    int hopeless = 0;
    *skip_to = y + 1;
    for (int k = 0; k < MARKER_PROBES; ++k) {
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
static int grid_find(marker_grid *g, const marker_unit *u, int32_t *x_out, int32_t *y_out)
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
    const marker_shape *s = &u->shape;
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

/* Marks the shape's cells at (x, y) occupied and updates the rows' longest free stretches and the blocks'. 0 when
 * out of memory. */
static int grid_occupy(marker_grid *g, const marker_shape *s, int32_t x, int32_t y)
{
    if (!marker_grid_grow(g, y + s->height))
        return 0;
    for (int32_t r = 0; r < s->height; ++r) {
        if (s->row_start[r] == s->row_start[r + 1])
            continue;
        uint64_t *row = grid_row(g, y + r);
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i)
            set_cells(row, x + s->runs[2 * i], x + s->runs[2 * i + 1]);
        g->longest_run[y + r] = row_longest(g, y + r);
    }
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

int marker_score_better(marker_score a, marker_score b)
{
    if (fabs(a.length - b.length) > 1e-6)
        return a.length < b.length;
    return a.tops < b.tops - 1e-6;
}

/* Places the unit of the lowest top among `candidates`; *placed = 0 when none fits across the fabric. */
static int place_best(marker_grid *g, const marker_unit *candidates, int count, pz_marker_placement *out,
                      int32_t *out_count, marker_score *score, int *placed)
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
    const marker_unit *u = &candidates[best];
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

/* One copy of a piece on its own: the candidate of the pinned turn (1, 2) if it fits, else of either turn. *fitted
 * = 0 when neither fits across the fabric. 0 when out of memory. */
static int place_single(marker_grid *g, const marker_demand *d, int copy, int turn, pz_marker_placement *out,
                        int32_t *out_count, marker_score *score, int *fitted)
{
    const int t = g->transposed;
    int ok = 1;
    *fitted = 0;
    if (turn)
        ok = place_best(g, d->singles[t][copy] + (turn - 1), 1, out, out_count, score, fitted);
    if (ok && !*fitted)
        ok = place_best(g, d->singles[t][copy], 2, out, out_count, score, fitted);
    return ok;
}

/*
 * One greedy pass on grid g (the fabric, or its transpose for the column fill): placements into out (count
 * written, fabric coordinates either way). Each order entry is one copy of a piece (MARKER_ENTRY_* decode it): a
 * Cut-2 piece has two entries. Paired (split bit clear), the pair goes at its copy 0's entry and copy 1's entry is
 * passed over; split, each copy goes at its own entry. Turn 0 takes the candidate whose top ends lowest, 1 and 2
 * the first or second half of the candidates only (copy 0 at 0 or 180 degrees; for a split copy, that copy)
 * unless none of those fits. A pair that fits nowhere across the fabric goes as its two copies. On a transposed
 * grid a unit that fits nowhere (taller than the length tried) ends the pass with an infinite score.
 */
pz_status marker_nest_pass(marker_grid *g, const pz_pieces *pieces, const marker_demand *demands, const int32_t *order,
                           int32_t count, pz_marker_placement *out, int32_t *out_count, marker_score *score,
                           pz_ctx *ctx)
{
    grid_reset(g);
    *out_count = 0;
    *score = (marker_score){0, 0, 0};
    const int t = g->transposed;
    for (int32_t i = 0; i < count; ++i) {
        const marker_demand *d = &demands[MARKER_ENTRY_DEMAND(order[i])];
        int copy = MARKER_ENTRY_COPY(order[i]), turn = MARKER_ENTRY_TURN(order[i]), placed = 0, ok = 1;
        int paired = d->copies == 2 && !MARKER_ENTRY_SPLIT(order[i]);
        if (paired && copy == 1)
            continue; /* placed with copy 0 */
        if (paired) {
            if (turn)
                ok = place_best(g, d->pairs[t] + 2 * (turn - 1), 2, out, out_count, score, &placed);
            if (ok && !placed)
                ok = place_best(g, d->pairs[t], 4, out, out_count, score, &placed);
        }
        /* split: this copy; paired but no pair fits across: both copies, each its best turn */
        int first = paired ? 0 : copy, last = paired ? d->copies - 1 : copy;
        for (int c = first; ok && !placed && c <= last; ++c) {
            int fitted = 0;
            ok = place_single(g, d, c, turn, out, out_count, score, &fitted);
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

marker_grid marker_grid_make(double width_mm, double gap_mm, double cells_across, double finest_mm)
{
    marker_grid g = {.raster = {0, 0, width_mm}};
    g.raster.resolution =
        fmax(fmax(finest_mm, width_mm / cells_across), (width_mm + gap_mm + 8.0) / (MARKER_MAX_COLUMNS - 32));
    g.raster.reach = gap_mm / 2.0 + g.raster.resolution * 0.5 * sqrt(2.0) + 1e-9;
    g.margin = (int32_t)ceil(g.raster.reach / g.raster.resolution) + 1;
    g.columns = (int32_t)ceil(width_mm / g.raster.resolution) + 2 * g.margin + 3;
    return g;
}
