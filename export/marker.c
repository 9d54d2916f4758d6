/*
 * export/marker.c -- the marker: every piece nested on a strip of fabric
 * (x across the fabric width, y along its length), and marker.svg. This
 * file holds the search over orders, the build and marker.svg; the pieces'
 * shapes are made in export/marker_shapes.c, the fabric grid and one greedy
 * pass are export/marker_grid.c (shared through export/internal.h).
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
 *  - A Cut-2 piece goes as a pair (copy 0 and its mirror image pushed against
 *    its right side as close as their cells allow, in the four rotation
 *    combinations) or as two copies placed each on its own: the order says
 *    which (an entry per copy, MARKER_ENTRY). A pair that fits nowhere across
 *    the fabric goes as its copies.
 *  - A unit goes to the lowest, then leftmost, grid position where every
 *    run lies on free cells, in the rotation whose top ends lowest. The
 *    fabric is a bitmap checked a word (64 cells) at a time; a blocked run
 *    says how far right the next candidate is, so a fabric row costs
 *    O(obstacles in it), not O(width). Before a row is tried, eight probe
 *    rows of the shape must meet fabric rows with a long enough free
 *    stretch; maxima over blocks of 32 rows let a probe skip a block at once.
 *    A position is checked row by row in a strided order (widest row, then
 *    every 64th, 32nd, ...): a blocked one is found blocked after a few rows
 *    (export/marker_grid.c).
 *  - Order: greedy passes over four fixed orders (area, height, width,
 *    large and small alternating; each with the pairs kept and split), then
 *    walks of a local search (swap two entries, move one, pin one's
 *    rotation, or split or join a pair), each new walk from a random order
 *    once the last one stalls, keeping the shortest marker (ties: the lower
 *    sum of the units' tops). The search stops as soon as a marker is within
 *    a cell of the shortest possible (the tallest piece; the pieces' area over
 *    the width).
 *  - Column fill (markers up to two fabric widths long): the same machinery
 *    on the transposed fabric fills across the width under a fixed length L
 *    (leftmost, then lowest), so the marker ends level at L where the
 *    bottom-left fill leaves a ragged top; L steps down below the best
 *    marker while a local search finds orders that fit the width.
 *  - Coarse search, fine finish: the search runs on cells 1.5 times as
 *    large (width / 667), its 8 best orders once more on the fine cells;
 *    the shortest marker of both is kept.
 *  - Budgets are counted in grid_find's steps and in passes, not timed:
 *    deterministic, no threads, no clock, a fixed xorshift seed; a marker of
 *    many pieces on a long fabric gets fewer passes.
 * Memory: the shapes' runs (O(cells on their rows)), a bit per fabric cell.
 * Fails with PZ_ERR_DATA for a piece wider than the fabric or with a
 * cut-line coordinate out of range, PZ_ERR_USAGE for a fabric width out of
 * range, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"
#include "export/stream_status.h"
#include "export/xml_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* The search runs on cells of fabric width / SEARCH_CELLS_ACROSS (2.25 mm on 1500 mm: a pass costs about half of
 * one on the 1.5 mm cells of FINAL_CELLS_ACROSS), then the ELITE best orders it found run once more on the fine
 * cells, where pieces keep less room around them; the shortest marker of either grid is kept. 3 mm cells (500
 * across) were 2.3x faster than the fine search alone but lost 1-1.6 points on two of the shared garments; at
 * 2.25 mm none of them loses. */
#define SEARCH_CELLS_ACROSS 667.0
#define FINAL_CELLS_ACROSS 1000.0
#define ELITE 8

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

/* ------------------------------------------------------------------ the search over orders */

/* The fixed orders: by area, height, width (decreasing), and by area with large and small pieces alternating; each
 * with the Cut-2 pieces paired and, when there are any, split. */
enum { kFixedOrders = 4 };

/* The entries of the demands in `demands_in_order` (count of them) into order, each demand's copies one after the
 * other, every Cut-2 piece split when `split`. */
static void entries_of(const marker_demand *demands, const int32_t *demands_in_order, int32_t count, int split,
                       int32_t *order)
{
    int32_t entry_count = 0;
    for (int32_t i = 0; i < count; ++i) {
        int32_t d = demands_in_order[i];
        for (int c = 0; c < demands[d].copies; ++c)
            order[entry_count++] = MARKER_ENTRY(d, c, split && demands[d].copies == 2, 0);
    }
}

/* Fixed order `which` (0 .. 2 kFixedOrders - 1: from kFixedOrders on, the same with every Cut-2 piece split) of
 * `count` demands into order (their entries); scratch holds 2 count. */
static void fixed_order(const marker_demand *demands, int32_t count, int which, int32_t *order, int32_t *scratch)
{
    int split = which >= kFixedOrders;
    which %= kFixedOrders;
    int key = which == 3 ? 0 : which;
    int32_t *sorted = scratch, *alternating = scratch + count;
    for (int32_t i = 0; i < count; ++i)
        sorted[i] = i;
    /* Insertion sort, decreasing key, stable (demands are in piece order): few pieces, and deterministic. */
    for (int32_t i = 1; i < count; ++i)
        for (int32_t j = i; j > 0 && demands[sorted[j]].keys[key] > demands[sorted[j - 1]].keys[key]; --j) {
            int32_t t = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = t;
        }
    if (which == 3) {
        for (int32_t i = 0, large = 0, small = count - 1; i < count; ++i)
            alternating[i] = i % 2 == 0 ? sorted[large++] : sorted[small--];
        sorted = alternating;
    }
    entries_of(demands, sorted, count, split, order);
}

/* xorshift64*: a fixed sequence, so the search is deterministic. */
static uint64_t next_random(uint64_t *state)
{
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return *state * 2685821657736338717ull;
}

/* A random order of the `count` demands' entries (Fisher-Yates from the fixed xorshift sequence), every turn free,
 * each Cut-2 piece paired or split at random; *entry_count entries written. */
static void random_order(const marker_demand *demands, int32_t count, int32_t *order, int32_t entry_count,
                         uint64_t *state)
{
    for (int32_t d = 0, k = 0; d < count; ++d) {
        int split = demands[d].copies == 2 && next_random(state) % 2;
        for (int c = 0; c < demands[d].copies; ++c)
            order[k++] = MARKER_ENTRY(d, c, split, 0);
    }
    for (int32_t i = entry_count - 1; i > 0; --i) {
        int32_t j = (int32_t)(next_random(state) % (uint64_t)(i + 1)), t = order[i];
        order[i] = order[j], order[j] = t;
    }
}

/* Entry i's piece paired if it was split and split if it was paired: both of its entries. */
static void toggle_split(int32_t *order, int32_t count, int32_t i)
{
    int32_t demand = MARKER_ENTRY_DEMAND(order[i]);
    int step = MARKER_ENTRY_SPLIT(order[i]) ? -3 : 3;
    for (int32_t k = 0; k < count; ++k)
        if (MARKER_ENTRY_DEMAND(order[k]) == demand)
            order[k] += step;
}

/* A neighbour of `order` (count entries): one entry's turn changed, two entries swapped, one moved to another
 * place, or (when the marker has Cut-2 pieces: `has_pairs`) one Cut-2 piece paired or split. */
static void perturb(const marker_demand *demands, int32_t *order, int32_t count, int has_pairs, uint64_t *state)
{
    int32_t i = (int32_t)(next_random(state) % (uint64_t)count);
    int32_t j = (int32_t)(next_random(state) % (uint64_t)(count - 1));
    j += j >= i;
    uint64_t move = next_random(state) % (has_pairs ? 4 : 3);
    if (move == 3 && demands[MARKER_ENTRY_DEMAND(order[i])].copies == 2) {
        toggle_split(order, count, i);
        return;
    }
    if (move == 0 || move == 3) {
        int turn = MARKER_ENTRY_TURN(order[i]);
        order[i] += (turn + 1 + (int32_t)(next_random(state) % 2)) % 3 - turn;
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
    marker_grid grid;                  /* the bottom-left fill's */
    marker_grid column;                /* the column fill's (transposed; columns == 0 until column_grid makes it) */
    const pz_pieces *pieces;
    const marker_demand *demands;
    int32_t demand_count;       /* demands: the drawn pieces that fit the fabric */
    int32_t count;              /* order entries: one per copy (a Cut-2 piece has two) */
    int has_pairs;              /* some demand is a Cut-2 piece: the search may split pairs */
    int32_t *order, *trial_order, *scratch;
    pz_marker_placement *trial; /* a pass's placements */
    pz_marker *best;            /* the best pass so far (placements, placement_count) */
    marker_score best_score;      /* its true length (along the fabric) and tops */
    int32_t passes;
    int64_t work;               /* grid_find's steps over all passes */
    uint64_t random;            /* xorshift state */
    double work_scale;          /* the step budgets' share on this grid: its cells across / FINAL_CELLS_ACROSS */
    double shortest_possible;   /* no marker is shorter (mm): the tallest piece, the pieces' area over the width */
    /* The best few passes (their orders, and the column fill's length for a transposed one, else 0), best first:
     * the fine grid runs them again (pz_marker_build). NULL orders: none kept. */
    int32_t *elite_orders;
    marker_score elite_score[ELITE];
    double elite_length[ELITE];
    int elite_count;
} search;

/* Keeps `order` among the ELITE best passes when it is (an order already kept at the same length is not kept
 * twice). */
static void elite_offer(search *s, const int32_t *order, marker_score score, double column_length)
{
    if (!s->elite_orders)
        return;
    int at = s->elite_count;
    while (at > 0 && marker_score_better(score, s->elite_score[at - 1]))
        --at;
    if (at >= ELITE)
        return;
    for (int k = 0; k < s->elite_count; ++k)
        if (s->elite_length[k] == column_length &&
            memcmp(s->elite_orders + (size_t)k * (size_t)s->count, order, (size_t)s->count * sizeof *order) == 0)
            return;
    int last = s->elite_count < ELITE ? s->elite_count : ELITE - 1;
    for (int k = last; k > at; --k) {
        s->elite_score[k] = s->elite_score[k - 1], s->elite_length[k] = s->elite_length[k - 1];
        memcpy(s->elite_orders + (size_t)k * (size_t)s->count, s->elite_orders + (size_t)(k - 1) * (size_t)s->count,
               (size_t)s->count * sizeof *order);
    }
    s->elite_score[at] = score, s->elite_length[at] = column_length;
    memcpy(s->elite_orders + (size_t)at * (size_t)s->count, order, (size_t)s->count * sizeof *order);
    s->elite_count += s->elite_count < ELITE;
}

/* 1 when the best marker so far is within a cell of the shortest possible: no order can do better on this grid
 * (a piece's lowest position leaves up to a cell below it), and the search can stop. */
static int search_at_bound(const search *s)
{
    return s->passes > 0 && s->best_score.length <= s->shortest_possible + s->grid.raster.resolution + 1e-9;
}

/* Runs one pass over `order` on grid g; keeps it in s->best when its marker is shorter (a column fill's only when
 * it fits the fabric's width). *score: the pass's, in g's axes. */
static pz_status search_try(search *s, marker_grid *g, const int32_t *order, marker_score *score, pz_ctx *ctx)
{
    int32_t placed = 0;
    pz_status status = marker_nest_pass(g, s->pieces, s->demands, order, s->count, s->trial, &placed, score, ctx);
    ++s->passes;
    s->work += g->work;
    g->work = 0;
    marker_score marker = *score;
    if (g->transposed)
        marker = (marker_score){score->length <= g->fabric_width_mm ? score->across : INFINITY, score->tops, 0};
    if (status == PZ_OK && isfinite(marker.length))
        elite_offer(s, order, marker, g->transposed ? g->raster.width_mm : 0.0);
    if (status == PZ_OK && isfinite(marker.length) && (s->passes == 1 || marker_score_better(marker, s->best_score))) {
        s->best_score = marker;
        s->best->placement_count = placed;
        memcpy(s->best->placements, s->trial, (size_t)placed * sizeof *s->trial);
    }
    return status;
}

/* `order`, just run with `score`, becomes the search's current order. */
static void search_adopt(search *s, const int32_t *order, const marker_score *score, marker_score *current)
{
    *current = *score;
    if (order != s->order)
        memcpy(s->order, order, (size_t)s->count * sizeof *s->order);
}

/* The fixed orders on grid g (the first always, the others while s->work is below budget); the best of them into
 * s->order, its score into *current. */
static pz_status search_fixed(search *s, marker_grid *g, int64_t budget, marker_score *current, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    marker_score score;
    *current = (marker_score){INFINITY, INFINITY, 0};
    int orders = s->has_pairs ? 2 * kFixedOrders : kFixedOrders;
    for (int which = 0; which < orders && (which == 0 || (s->work < budget && !search_at_bound(s))) && status == PZ_OK;
         ++which) {
        fixed_order(s->demands, s->demand_count, which, s->trial_order, s->scratch);
        status = search_try(s, g, s->trial_order, &score, ctx);
        if (status == PZ_OK && marker_score_better(score, *current))
            search_adopt(s, s->trial_order, &score, current);
    }
    return status;
}

/* One neighbour of s->order on grid g; it replaces s->order when no worse than *current (so the search walks
 * along plateaus of equal length). */
static pz_status search_step(search *s, marker_grid *g, marker_score *current, marker_score *score, pz_ctx *ctx)
{
    memcpy(s->trial_order, s->order, (size_t)s->count * sizeof *s->order);
    perturb(s->demands, s->trial_order, s->count, s->has_pairs, &s->random);
    pz_status status = search_try(s, g, s->trial_order, score, ctx);
    if (status == PZ_OK && !marker_score_better(*current, *score))
        search_adopt(s, s->trial_order, score, current);
    return status;
}

/* The bottom-left fill: the fixed orders, then walks of a local search, the first from the best of them, each
 * further one from a random order once the last has gone SEARCH_STALL passes without improving on its own best.
 * The first order always runs; every other pass only while the work budget lasts, so a marker of many pieces on a
 * long fabric (where one pass costs the most) gets fewer passes. */
static pz_status search_rows(search *s, pz_ctx *ctx)
{
    marker_score current, score;
    /* Steps scale with the cells along the fabric: the budget is set for FINAL_CELLS_ACROSS. */
    const int64_t budget = (int64_t)(SEARCH_WORK * s->work_scale);
    pz_status status = search_fixed(s, &s->grid, budget, &current, ctx);
    int32_t since_better = 0;
    marker_score walk_best = current;
    int32_t max_passes = kFixedOrders + SEARCH_PASSES_PER_PIECE * (s->demand_count - 1);
    max_passes = max_passes < SEARCH_MAX_PASSES ? max_passes : SEARCH_MAX_PASSES;
    while (s->work < budget && s->passes < max_passes && s->count > 1 && status == PZ_OK && !search_at_bound(s)) {
        if (since_better >= SEARCH_STALL) { /* a new walk */
            random_order(s->demands, s->demand_count, s->order, s->count, &s->random);
            status = search_try(s, &s->grid, s->order, &score, ctx);
            search_adopt(s, s->order, &score, &current);
            walk_best = current, since_better = 0;
            continue;
        }
        status = search_step(s, &s->grid, &current, &score, ctx);
        if (marker_score_better(current, walk_best))
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
    /* The units transposed, the first time a column fill runs (search_open made the demands, so they are ours). */
    marker_demand *demands = (marker_demand *)s->demands;
    for (int32_t i = 0; i < s->demand_count; ++i)
        if (!marker_demand_transpose(&demands[i]))
            return -1;
    marker_grid g = {.raster = s->grid.raster, .margin = s->grid.margin, .transposed = 1,
              .fabric_width_mm = s->grid.raster.width_mm};
    g.raster.width_mm = length_mm;
    g.columns = (int32_t)ceil(length_mm / g.raster.resolution) + 2 * g.margin + 3;
    if (g.columns >= MARKER_MAX_COLUMNS)
        return 0;
    s->column = g;
    return marker_grid_grow(&s->column, 1) ? 1 : -1;
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
    for (int32_t i = 0; i < s->demand_count; ++i)
        tallest = fmax(tallest, s->demands[i].singles[0][0][0].hi[1] - s->demands[i].singles[0][0][0].lo[1]);
    int64_t budget = s->work + (int64_t)(COLUMN_WORK * s->work_scale);
    int32_t max_passes = s->passes + COLUMN_MAX_PASSES, since_feasible = 0;
    pz_status status = PZ_OK;
    marker_score current, score;
    int first = 1;
    while (status == PZ_OK && s->work < budget && s->passes < max_passes && since_feasible < COLUMN_STALL &&
           !search_at_bound(s)) {
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
    pz_status status = search_rows(s, ctx);
    if (status == PZ_OK && s->count > 0 && s->best_score.length <= COLUMN_MAX_WIDTHS * s->grid.raster.width_mm &&
        !search_at_bound(s))
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
static int wider_than_fabric(const marker_raster *raster, const pz_piece *piece)
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
static pz_status build_demands(const marker_raster *raster, const pz_pieces *pieces, marker_demand *demands,
                               int32_t *count, pz_marker *marker, pz_ctx *ctx)
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
        if (!marker_demand_build(raster, pieces, p, &demands[(*count)++]))
            return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    }
    return PZ_OK;
}

/* A search's memory on a grid of `cells_across` cells: the demands of every drawn piece that fits (the others in
 * s->best->unplaced), the orders, the placements, the elite's orders when `elite`. */
static pz_status search_open(search *s, const pz_pieces *pieces, double width_mm, double gap_mm, double cells_across,
                             int elite, pz_ctx *ctx)
{
    size_t n = (size_t)pieces->piece_count + 1;
    *s = (search){.grid = marker_grid_make(width_mm, gap_mm, cells_across, 1.0), .pieces = pieces};
    marker_demand *demands = calloc(n, sizeof *demands);
    s->demands = demands;
    s->order = malloc(3 * 2 * n * sizeof(int32_t)); /* the order, a trial order, scratch: 2 entries a piece */
    s->trial = malloc(2 * n * sizeof *s->trial);
    s->best = calloc(1, sizeof *s->best);
    if (s->best) {
        s->best->placements = malloc(2 * n * sizeof *s->best->placements);
        s->best->unplaced = malloc(n * sizeof *s->best->unplaced);
    }
    if (elite)
        s->elite_orders = malloc((size_t)ELITE * 2 * n * sizeof(int32_t));
    if (!demands || !s->order || !s->trial || !s->best || !s->best->placements || !s->best->unplaced ||
        (elite && !s->elite_orders) || !marker_grid_grow(&s->grid, 1))
        return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    s->trial_order = s->order + 2 * n, s->scratch = s->order + 4 * n;
    s->random = 0x9e3779b97f4a7c15ull;
    s->work_scale = cells_across / FINAL_CELLS_ACROSS;
    pz_status status = build_demands(&s->grid.raster, pieces, demands, &s->demand_count, s->best, ctx);
    double area = 0.0;
    for (int32_t i = 0; i < s->demand_count; ++i) {
        s->count += demands[i].copies;
        s->has_pairs |= demands[i].copies == 2;
        const pz_piece *piece = &pieces->pieces[demands[i].piece];
        area += demands[i].copies * piece->area_mm2;
        s->shortest_possible = fmax(s->shortest_possible, piece->bbox_max[1] - piece->bbox_min[1]);
    }
    s->shortest_possible = fmax(s->shortest_possible, area / width_mm);
    return status;
}

/* Frees what search_open made, s->best too unless `keep_best`. */
static void search_close(search *s, int keep_best)
{
    marker_demand *demands = (marker_demand *)s->demands;
    for (int32_t i = 0; demands && i < s->pieces->piece_count; ++i)
        marker_demand_clear(&demands[i]);
    free(demands);
    free(s->order);
    free(s->trial);
    free(s->elite_orders);
    marker_grid_free(&s->grid);
    marker_grid_free(&s->column);
    if (!keep_best)
        pz_marker_free(&s->best);
}

/* The coarse search's elite orders run on the fine search's grids: rows, then the column fill's at their lengths (the transposed grid made for the longest). */
static pz_status replay_elite(const search *coarse, search *fine, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    marker_score score;
    double longest = 0.0;
    for (int k = 0; k < coarse->elite_count && status == PZ_OK; ++k) {
        const int32_t *order = coarse->elite_orders + (size_t)k * (size_t)coarse->count;
        if (coarse->elite_length[k] == 0.0) {
            status = search_try(fine, &fine->grid, order, &score, ctx);
        }
        longest = fmax(longest, coarse->elite_length[k]);
    }
    if (status != PZ_OK || longest == 0.0)
        return status;
    int made = column_grid(fine, longest);
    if (made < 0)
        return pz_error(ctx, PZ_ERR_NOMEM, "marker: out of memory");
    for (int k = 0; made && k < coarse->elite_count && status == PZ_OK; ++k) {
        if (coarse->elite_length[k] == 0.0)
            continue;
        column_grid(fine, coarse->elite_length[k]); /* not longer than the grid made: only the limit moves */
        status = search_try(fine, &fine->column, coarse->elite_orders + (size_t)k * (size_t)coarse->count, &score,
                            ctx);
    }
    return status;
}

/*
 * The search on coarse cells, its elite once more on fine ones, the shortest marker of both (into *best, the other
 * search's freed). When a piece fits the fabric on fine cells but not on coarse ones (within a few mm of its
 * width), the search runs on the fine cells alone.
 */
static pz_status search_both(const pz_pieces *pieces, double width_mm, double gap_mm, pz_marker **best,
                             pz_ctx *ctx)
{
    search coarse, fine;
    pz_status status = search_open(&fine, pieces, width_mm, gap_mm, FINAL_CELLS_ACROSS, 0, ctx);
    if (status == PZ_OK)
        status = search_open(&coarse, pieces, width_mm, gap_mm, SEARCH_CELLS_ACROSS, 1, ctx);
    else
        coarse = (search){.pieces = pieces};
    int coarse_usable = status == PZ_OK && coarse.demand_count == fine.demand_count;
    if (status == PZ_OK)
        status = search_run(coarse_usable ? &coarse : &fine, ctx);
    if (status == PZ_OK && coarse_usable)
        status = replay_elite(&coarse, &fine, ctx);
    int fine_wins = status == PZ_OK && fine.passes > 0 &&
                    (!coarse_usable || marker_score_better(fine.best_score, coarse.best_score));
    if (status == PZ_OK) {
        const search *kept = fine_wins ? &fine : &coarse;
        kept->best->passes = coarse.passes + fine.passes;
        kept->best->shortest_possible_mm = fine.shortest_possible;
        *best = kept->best;
    }
    search_close(&coarse, status == PZ_OK && !fine_wins);
    search_close(&fine, status == PZ_OK && fine_wins);
    return status;
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
    pz_marker *marker = NULL;
    status = search_both(pieces, width_mm, gap_mm, &marker, ctx);
    if (status != PZ_OK)
        return status;
    marker->fabric_width_mm = width_mm;
    marker->length_mm = marker->placement_count ? marker_length(pieces, marker) : 0.0;
    double area = 0.0;
    for (int32_t p = 0; p < marker->placement_count; ++p)
        area += pieces->pieces[marker->placements[p].piece].area_mm2;
    marker->efficiency = marker->length_mm > 0 ? area / (width_mm * marker->length_mm) : 0.0;
    marker->efficiency_bound =
        marker->shortest_possible_mm > 0 ? fmin(1.0, area / (width_mm * marker->shortest_possible_mm)) : 0.0;
    marker->ms = (pz_seconds() - start) * 1000.0;
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
             cJSON_AddNumberToObject(json, "shortest_possible_mm", round(marker->shortest_possible_mm * 10) / 10) &&
             cJSON_AddNumberToObject(json, "efficiency_bound", round(marker->efficiency_bound * 10000) / 10000) &&
             cJSON_AddNumberToObject(json, "pieces", marker->placement_count) &&
             cJSON_AddNumberToObject(json, "passes", marker->passes) &&
             cJSON_AddNumberToObject(json, "ms", round(marker->ms * 10) / 10) &&
             cJSON_AddStringToObject(json, "method",
                                     "raster bottom-left fill over true shapes, order search with restarts on "
                                     "coarse cells (Cut-2 pairs kept or split), its best orders again on fine "
                                     "cells, column fill below the best length, rotations 0/180");
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
