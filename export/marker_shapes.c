/*
 * export/marker_shapes.c -- the marker's pieces as shapes (docs/marker.md):
 * each piece copy, in each allowed orientation (0 and 180 degrees: the grain
 * stays true; the second copy of a Cut-2 piece mirrored x -> -x first), is
 * rasterized conservatively: a cell is set when it may touch the cut line
 * dilated by gap/2, so two placements whose cells are disjoint are at least
 * `gap` apart, exactly. A shape is kept as runs of set cells per row, so
 * concave outlines keep their hollows and other pieces can reach into them.
 * A Cut-2 piece is also one unit: copy 0 and its mirror image pushed against
 * its right side as close as their cells allow, in the four rotation
 * combinations. The column fill transposes the units it needs
 * (marker_demand_transpose) when it first runs: long markers never do.
 *
 * Separate from the search (export/marker.c) and the fabric grid
 * (export/marker_grid.c) because it is geometry done once per piece before
 * any pass: the search only reads the units it builds (export/internal.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ shapes */

static void shape_clear(marker_shape *s)
{
    free(s->row_start);
    free(s->runs);
    free(s->check_order);
    memset(s, 0, sizeof *s);
}

/* The shape's widest row, check order and probe rows, from its runs (row_start, runs, width, height set). */
static void shape_finish(marker_shape *s)
{
    s->widest = -1, s->widest_row = 0;
    for (int32_t y = 0; y < s->height; ++y)
        for (int32_t i = s->row_start[y]; i < s->row_start[y + 1]; ++i)
            if (s->runs[2 * i + 1] - s->runs[2 * i] > s->widest)
                s->widest = s->runs[2 * i + 1] - s->runs[2 * i], s->widest_row = y;
    /* Check order: the widest row, then every 64th row, every 32nd, ... (each row once). An obstacle spans many
     * rows, so a blocked position is found blocked after a few rows instead of after a row-by-row walk from the
     * bottom: the answer is the same, found sooner. */
    int32_t filled = 0, height = s->height;
    if (height > 0)
        s->check_order[filled++] = s->widest_row;
    for (int32_t stride = 64; stride >= 1; stride /= 2)
        for (int32_t r = 0; r < height; r += stride)
            if (r != s->widest_row && (stride == 64 || r % (2 * stride) != 0))
                s->check_order[filled++] = r;
    for (int k = 0; k < MARKER_PROBES; ++k) {
        int32_t r = k == 0 ? s->widest_row : (int32_t)((int64_t)(height - 1) * (k - 1) / (MARKER_PROBES - 2));
        s->probe_row[k] = r, s->probe_width[k] = -1;
        for (int32_t i = s->row_start[r]; i < s->row_start[r + 1]; ++i)
            if (s->runs[2 * i + 1] - s->runs[2 * i] > s->probe_width[k])
                s->probe_width[k] = s->runs[2 * i + 1] - s->runs[2 * i];
    }
}

/* The shape's arrays for `height` rows and `run_count` runs (width, height set). 0 when out of memory. */
static int shape_allocate(marker_shape *s, int32_t width, int32_t height, size_t run_count)
{
    memset(s, 0, sizeof *s);
    s->width = width, s->height = height, s->widest = -1;
    s->row_start = malloc(((size_t)height + 1) * sizeof(int32_t));
    s->runs = malloc((2 * run_count + 1) * sizeof(int32_t));
    s->check_order = malloc(((size_t)height + 1) * sizeof(int32_t));
    if (!s->row_start || !s->runs || !s->check_order) {
        shape_clear(s);
        return 0;
    }
    return 1;
}

/* The first index in [x, width) whose byte is not `value` (0 or 1), or width: eight bytes at a time. */
static int32_t next_byte_not(const uint8_t *row, int32_t x, int32_t width, uint8_t value)
{
    const uint64_t all = 0x0101010101010101ull * value;
    for (uint64_t word; x + 8 <= width; x += 8) {
        memcpy(&word, row + x, 8);
        if (word != all)
            break;
    }
    while (x < width && row[x] == value)
        ++x;
    return x;
}

/* The runs of a width x height cell bitmap (bytes 0 or 1). 0 when out of memory. */
static int shape_from_cells(marker_shape *s, const uint8_t *cells, int32_t width, int32_t height)
{
    size_t count = 0;
    for (int32_t y = 0; y < height; ++y) {
        const uint8_t *row = cells + (size_t)y * (size_t)width;
        for (int32_t x = next_byte_not(row, 0, width, 0); x < width; x = next_byte_not(row, x, width, 0)) {
            x = next_byte_not(row, x, width, 1);
            ++count;
        }
    }
    if (!shape_allocate(s, width, height, count))
        return 0;
    int32_t run = 0;
    for (int32_t y = 0; y < height; ++y) {
        const uint8_t *row = cells + (size_t)y * (size_t)width;
        s->row_start[y] = run;
        for (int32_t x = next_byte_not(row, 0, width, 0); x < width; x = next_byte_not(row, x, width, 0)) {
            int32_t end = next_byte_not(row, x, width, 1);
            s->runs[2 * run] = x, s->runs[2 * run + 1] = end - 1;
            ++run;
            x = end;
        }
    }
    s->row_start[height] = run;
    shape_finish(s);
    return 1;
}

/* The squared distance from (px, py) to segment ab. */
static double segment_distance2(double px, double py, const double *a, const double *b)
{
    double dx = b[0] - a[0], dy = b[1] - a[1];
    double length2 = dx * dx + dy * dy;
    double t = length2 > 0 ? ((px - a[0]) * dx + (py - a[1]) * dy) / length2 : 0.0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double ex = a[0] + t * dx - px, ey = a[1] + t * dy - py;
    return ex * ex + ey * ey;
}

/*
 * Rasterizes the closed polygon `points` (n x 2, already transformed) into
 * `cells` (width x height) with its lower-left at `origin`: cells whose
 * centre is inside, and cells whose centre lies within `reach` of an edge
 * (reach = gap/2 + half the cell diagonal, so every cell touching the
 * dilated polygon is set). 0 when out of memory.
 */
int marker_draw_polygon(uint8_t *cells, int32_t width, int32_t height, const double *points, int32_t n,
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
    const double reach2 = reach * reach;
    for (int32_t i = 0; i < n; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % n)];
        int32_t x0 = (int32_t)floor((fmin(a[0], b[0]) - reach - origin[0]) / resolution);
        int32_t x1 = (int32_t)ceil((fmax(a[0], b[0]) + reach - origin[0]) / resolution);
        int32_t y0 = (int32_t)floor((fmin(a[1], b[1]) - reach - origin[1]) / resolution);
        int32_t y1 = (int32_t)ceil((fmax(a[1], b[1]) + reach - origin[1]) / resolution);
        for (int32_t y = y0 < 0 ? 0 : y0; y <= y1 && y < height; ++y)
            for (int32_t x = x0 < 0 ? 0 : x0; x <= x1 && x < width; ++x) {
                uint8_t *cell = &cells[(size_t)y * (size_t)width + (size_t)x];
                if (!*cell && segment_distance2(origin[0] + (x + 0.5) * resolution,
                                                origin[1] + (y + 0.5) * resolution, a, b) <= reach2)
                    *cell = 1;
            }
    }
    return 1;
}

/* ------------------------------------------------------------------ units */

static void unit_clear(marker_unit *u)
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
static int unit_single(const marker_raster *raster, const pz_piece *piece, int32_t index, int copy, int rotation,
                       marker_unit *out)
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
             marker_draw_polygon(cells, width, height, points, piece->cut_count, origin, raster->resolution, raster->reach) &&
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
static int32_t pair_shift(const marker_shape *left, const marker_shape *right)
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

/* Appends run [first, last] to row `run` of the shape being built, joined to the run before when they touch (as
 * the cells of both would read). */
static void append_run(marker_shape *s, int32_t row_first_run, int32_t *run, int32_t first, int32_t last)
{
    if (*run > row_first_run && s->runs[2 * (*run - 1) + 1] + 1 >= first) {
        if (last > s->runs[2 * (*run - 1) + 1])
            s->runs[2 * (*run - 1) + 1] = last;
        return;
    }
    s->runs[2 * *run] = first, s->runs[2 * *run + 1] = last;
    ++*run;
}

/* The union of `left` and `right` moved right by `shift` cells (they share no cell), row by row: the two rows'
 * runs merged in order of their first cell. 0 when out of memory. */
static int shape_from_pair(marker_shape *s, const marker_shape *left, const marker_shape *right, int32_t shift,
                           int32_t width, int32_t height)
{
    if (!shape_allocate(s, width, height, (size_t)left->row_start[left->height] + (size_t)right->row_start[right->height]))
        return 0;
    int32_t run = 0;
    for (int32_t y = 0; y < height; ++y) {
        s->row_start[y] = run;
        int32_t i = y < left->height ? left->row_start[y] : 0, i_end = y < left->height ? left->row_start[y + 1] : 0;
        int32_t j = y < right->height ? right->row_start[y] : 0, j_end = y < right->height ? right->row_start[y + 1] : 0;
        while (i < i_end || j < j_end) {
            if (j >= j_end || (i < i_end && left->runs[2 * i] <= right->runs[2 * j] + shift)) {
                append_run(s, s->row_start[y], &run, left->runs[2 * i], left->runs[2 * i + 1]);
                ++i;
            } else {
                append_run(s, s->row_start[y], &run, right->runs[2 * j] + shift, right->runs[2 * j + 1] + shift);
                ++j;
            }
        }
    }
    s->row_start[height] = run;
    shape_finish(s);
    return 1;
}

/* The pair: `left` (copy 0) with `right` (copy 1, mirrored) pushed against its right side. 0 when out of memory. */
static int unit_pair(const marker_raster *raster, const marker_unit *left, const marker_unit *right, marker_unit *out)
{
    memset(out, 0, sizeof *out);
    int32_t shift = pair_shift(&left->shape, &right->shape);
    if (shift < 0)
        return 0;
    int32_t width = shift + right->shape.width > left->shape.width ? shift + right->shape.width : left->shape.width;
    int32_t height = left->shape.height > right->shape.height ? left->shape.height : right->shape.height;
    int ok = shape_from_pair(&out->shape, &left->shape, &right->shape, shift, width, height);
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
static int unit_transpose(const marker_unit *in, marker_unit *out)
{
    memset(out, 0, sizeof *out);
    const marker_shape *s = &in->shape;
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

void marker_demand_clear(marker_demand *d)
{
    for (int t = 0; t < 2; ++t) {
        for (int c = 0; c < 2; ++c)
            for (int r = 0; r < 2; ++r)
                unit_clear(&d->singles[t][c][r]);
        for (int k = 0; k < 4; ++k)
            unit_clear(&d->pairs[t][k]);
    }
}

int marker_demand_build(const marker_raster *raster, const pz_pieces *pieces, int32_t index, marker_demand *out)
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
            if (!unit_single(raster, piece, index, c, 180 * r, &out->singles[0][c][r]))
                return 0;
    for (int k = 0; out->copies == 2 && k < 4; ++k)
        if (!unit_pair(raster, &out->singles[0][0][k / 2], &out->singles[0][1][k % 2], &out->pairs[0][k]))
            return 0;
    return 1;
}

int marker_demand_transpose(marker_demand *d)
{
    if (d->transposed)
        return 1;
    for (int c = 0; c < d->copies; ++c)
        for (int r = 0; r < 2; ++r)
            if (!unit_transpose(&d->singles[0][c][r], &d->singles[1][c][r]))
                return 0;
    for (int k = 0; d->copies == 2 && k < 4; ++k)
        if (!unit_transpose(&d->pairs[0][k], &d->pairs[1][k]))
            return 0;
    d->transposed = 1;
    return 1;
}
