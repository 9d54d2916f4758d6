/*
 * io/polygon.h -- the triangulation of a polygon the readers share (OBJ, OFF
 * and PLY faces of more than three corners); internal to io/.
 *
 * Not a fan: a fan gives its first corner every triangle, and a CAD cap of
 * 5,000 or 200,000 corners then has one vertex joined to all the others,
 * which every later step (the remeshing above all) pays for quadratically.
 * Corners are joined level by level instead: (0,1,2), (2,3,4), ... then
 * (0,2,4), (4,6,8), ... then (0,4,8), ..., each level halving what is left,
 * so no vertex is in more than about 2 log2(n) triangles. A triangle or a
 * quad gives a fan's triangles in a fan's order, keep the polygon's orientation,
 * and cover a convex polygon (a non-convex one is as ill-defined as with a
 * fan). n - 2 triangles in all.
 *
 *     io_polygon_walk walk = {corner_count, 1, 0};
 *     size_t corner[3];
 *     while (io_polygon_next(&walk, corner)) ... polygon[corner[0]], ...
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef PZ_IO_POLYGON_H
#define PZ_IO_POLYGON_H

#include <stddef.h>

typedef struct io_polygon_walk {
    size_t corner_count; /* the polygon's, at least 3 */
    size_t step;         /* start at 1 */
    size_t at;           /* start at 0 */
} io_polygon_walk;

/* The next triangle's three corners (positions in the polygon), in the polygon's order; 0 after the last. */
static inline int io_polygon_next(io_polygon_walk *walk, size_t corner[3])
{
    while (walk->step < walk->corner_count) {
        if (walk->at + walk->step >= walk->corner_count) {
            walk->step *= 2;
            walk->at = 0;
            continue;
        }
        size_t first = walk->at, middle = first + walk->step, last = first + 2 * walk->step;
        walk->at = last;
        if (last < walk->corner_count) {
            corner[0] = first, corner[1] = middle, corner[2] = last;
            return 1;
        }
        if (first == 0)
            continue; /* two corners left: nothing more to cut at this level */
        /* The level's last triangle closes on corner 0, written from it (a quad as a fan writes it). */
        corner[0] = 0, corner[1] = first, corner[2] = middle;
        return 1;
    }
    return 0;
}

#endif
