/*
 * param/metrics.c -- how well a flattened pattern fits its 3D garment.
 *
 * Every per-triangle figure comes from the affine map f from the pattern
 * triangle (u, v in mm) to the garment triangle (x, y, z in mm) and its
 * Jacobian J = [dX/du dX/dv] (3 x 2). The warp runs along +v of the pattern
 * (grainline drawn vertically) and the weft along +u, so (docs/metrics.md):
 *   strain_warp = |dX/dv| - 1      (param.h's |J_1| - 1: J_1 is the warp column)
 *   strain_weft = |dX/du| - 1
 *   shear_deg   = angle(dX/du, dX/dv) in degrees - 90
 * positive strain = the fabric is stretched when worn. This is pietroni2022
 * Sec. 4.3 Eq. 1 (s = |J_i|) with the columns named by thread.
 *
 * Per panel: the stats of those three (max = max |x|, p95 = 95th percentile
 * of |x| by nearest rank, mean = 3D-area-weighted signed mean); mccartney2005
 * Eqs. 5-9 orthotropic energy 0.5 A (K_su (S_u - 1)^2 + K_sv (S_v - 1)^2 +
 * K_r phi^2) with S_u = |dX/du| (weft, the paper's u), S_v = |dX/dv| (warp),
 * phi = 90 deg - angle (the paper's collapsing shear, Eq. A.2) and A the 2D
 * area (the paper integrates over du dv); ARAP sum A_2d ((s1 - 1)^2 + (s2 -
 * 1)^2) with s1, s2 the singular values of J (||J - R||_F^2 for the closest
 * R with orthonormal columns); wang2008 Eq. 26 E_len over the panel's
 * boundary edges and Eq. 27 E_ang over all its corner angles; wang2002 Eq. 4
 * E_S = sum |A - A'| / sum A over its triangles and Eq. 6 E_C = sum |L - L'|
 * / sum L over its edges; flipped triangles (signed 2D area <= 0 relative to
 * the sign of the panel's total signed area); boundary self-intersections.
 *
 * Boundary self-intersections: each panel's boundary segments are bucketed
 * into a uniform grid of about one cell per segment (count_crossings); two
 * segments are tested only when they share a cell and their bounding boxes
 * overlap, each pair once. O(n + b), b the pairs listed in a common cell:
 * O(n + k) for outlines, whose edges are short against the piece; all pairs
 * only in degenerate inputs (every segment spanning the piece). Segments
 * sharing a vertex are neighbours, not crossings.
 *
 * Seams: polyline lengths in 3D and of both sides in 2D, and the RMS
 * residual after the best reflection (a 2D Procrustes fit with det = -1,
 * closed form) of side a onto side b, the symmetry pietroni2022 Eqs. 7-8
 * asks for. Darts: leg lengths (tip joined to the leg end nearer to it in
 * 3D), and the RMS residual of leg b mirrored onto leg a about the best
 * axis through the tip (closed form, the axis that minimises that residual).
 *
 * Cost O(F log F) (connectivity, sorting for percentiles; the crossing grid is O(F) for outlines).
 * Failure: PZ_ERR_USAGE for a pose that does not exist, PZ_ERR_NOMEM.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* One triangle                                                              */
/* ------------------------------------------------------------------------ */

/* dX/du and dX/dv of the map pattern -> garment; returns twice the signed 2D area (0: degenerate). */
static double triangle_jacobian(const double p3[3][3], const double p2[3][2], double du[3], double dv[3])
{
    double e1u = p2[1][0] - p2[0][0], e1v = p2[1][1] - p2[0][1];
    double e2u = p2[2][0] - p2[0][0], e2v = p2[2][1] - p2[0][1];
    double det = e1u * e2v - e2u * e1v;
    for (int k = 0; k < 3; ++k) {
        double E1 = p3[1][k] - p3[0][k], E2 = p3[2][k] - p3[0][k];
        du[k] = det != 0 ? (E1 * e2v - E2 * e1v) / det : 0;
        dv[k] = det != 0 ? (E2 * e1u - E1 * e2u) / det : 0;
    }
    return det;
}

/* Angle between the thread directions in 3D, radians (pi/2 for a degenerate map). */
static double thread_angle(const double du[3], const double dv[3])
{
    double lu = pz_vec3_norm(du), lv = pz_vec3_norm(dv);
    if (lu == 0 || lv == 0)
        return PZ_PI / 2;
    double c = pz_vec3_dot(du, dv) / (lu * lv);
    return acos(c > 1 ? 1 : c < -1 ? -1 : c);
}

void pz_metrics_triangle_strain(const double p3[3][3], const double p2[3][2], double *strain_warp,
                                double *strain_weft, double *shear_deg)
{
    double du[3], dv[3];
    if (triangle_jacobian(p3, p2, du, dv) == 0) {
        /* A collapsed pattern triangle has no finite strain; it is counted as flipped instead. */
        *strain_warp = *strain_weft = *shear_deg = 0;
        return;
    }
    *strain_warp = pz_vec3_norm(dv) - 1;
    *strain_weft = pz_vec3_norm(du) - 1;
    *shear_deg = thread_angle(du, dv) * 180 / PZ_PI - 90;
}

/* Singular values of the 3 x 2 J from its Gram matrix J^T J. */
static void singular_values(const double du[3], const double dv[3], double *s1, double *s2)
{
    double a = pz_vec3_dot(du, du), b = pz_vec3_dot(du, dv), c = pz_vec3_dot(dv, dv);
    double mean = (a + c) / 2, radius = sqrt((a - c) * (a - c) / 4 + b * b);
    double l1 = mean + radius, l2 = mean - radius;
    *s1 = sqrt(l1 > 0 ? l1 : 0);
    *s2 = sqrt(l2 > 0 ? l2 : 0);
}

static double area3(const double p3[3][3])
{
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = p3[1][k] - p3[0][k];
        e2[k] = p3[2][k] - p3[0][k];
    }
    double n[3];
    pz_vec3_cross(e1, e2, n);
    return pz_vec3_norm(n) / 2;
}

static double corner_angle3(const double *a, const double *b, const double *c)
{
    double x[3], y[3];
    pz_vec3_sub(b, a, x);
    pz_vec3_sub(c, a, y);
    double lx = pz_vec3_norm(x), ly = pz_vec3_norm(y);
    if (lx == 0 || ly == 0)
        return 0;
    double cosine = pz_vec3_dot(x, y) / (lx * ly);
    return acos(cosine > 1 ? 1 : cosine < -1 ? -1 : cosine);
}

static double corner_angle2(const double *a, const double *b, const double *c)
{
    double x0 = b[0] - a[0], x1 = b[1] - a[1], y0 = c[0] - a[0], y1 = c[1] - a[1];
    return fabs(atan2(x0 * y1 - x1 * y0, x0 * y0 + x1 * y1));
}

static double distance2(const double *a, const double *b) { return hypot(a[0] - b[0], a[1] - b[1]); }

/* ------------------------------------------------------------------------ */
/* Boundary self-intersections                                               */
/* ------------------------------------------------------------------------ */

typedef struct segment {
    double x0, y0, x1, y1;   /* x0 <= x1 */
    double ylo, yhi;
    int32_t a, b;            /* vertex ids, to skip neighbours */
} segment;

static double orient(double ax, double ay, double bx, double by, double cx, double cy)
{
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

static int on_segment(double ax, double ay, double bx, double by, double px, double py)
{
    return fmin(ax, bx) <= px && px <= fmax(ax, bx) && fmin(ay, by) <= py && py <= fmax(ay, by);
}

/* 1 when the closed segments meet (crossing, touching or overlapping). */
static int segments_meet(const segment *s, const segment *t)
{
    double d1 = orient(t->x0, t->y0, t->x1, t->y1, s->x0, s->y0);
    double d2 = orient(t->x0, t->y0, t->x1, t->y1, s->x1, s->y1);
    double d3 = orient(s->x0, s->y0, s->x1, s->y1, t->x0, t->y0);
    double d4 = orient(s->x0, s->y0, s->x1, s->y1, t->x1, t->y1);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
        return 1;
    return (d1 == 0 && on_segment(t->x0, t->y0, t->x1, t->y1, s->x0, s->y0)) ||
           (d2 == 0 && on_segment(t->x0, t->y0, t->x1, t->y1, s->x1, s->y1)) ||
           (d3 == 0 && on_segment(s->x0, s->y0, s->x1, s->y1, t->x0, t->y0)) ||
           (d4 == 0 && on_segment(s->x0, s->y0, s->x1, s->y1, t->x1, t->y1));
}

/* A uniform grid over the segments' bounding box, about one cell per
 * segment; each segment is listed in every cell its bounding box covers
 * (CSR: cell_start, entries). */
typedef struct segment_grid {
    double x_min, y_min, cell;
    int32_t nx, ny;
    int32_t *cell_start, *entries;
} segment_grid;

static int32_t grid_cell_index(const segment_grid *g, double value, double origin, int32_t cells)
{
    double k = floor((value - origin) / g->cell);
    return !(k > 0) ? 0 : k >= cells ? cells - 1 : (int32_t)k; /* NaN: cell 0 */
}

/* Runs `body` with `cell` set to every cell the bounding box of segment s covers. */
#define FOR_CELLS(g, s, body)                                                                  \
    for (int32_t cy = grid_cell_index(g, (s)->ylo, (g)->y_min, (g)->ny),                      \
                 cy_end = grid_cell_index(g, (s)->yhi, (g)->y_min, (g)->ny);                  \
         cy <= cy_end; ++cy)                                                                   \
        for (int32_t cx = grid_cell_index(g, (s)->x0, (g)->x_min, (g)->nx),                   \
                     cx_end = grid_cell_index(g, (s)->x1, (g)->x_min, (g)->nx);               \
             cx <= cx_end; ++cx) {                                                             \
            int32_t cell = cy * (g)->nx + cx;                                                  \
            body                                                                               \
        }

/* Builds the grid; 0 when out of memory. */
static int grid_build(segment_grid *g, const segment *segments, int32_t count)
{
    double x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
    for (int32_t i = 0; i < count; ++i) {
        x_min = fmin(x_min, segments[i].x0);
        x_max = fmax(x_max, segments[i].x1);
        y_min = fmin(y_min, segments[i].ylo);
        y_max = fmax(y_max, segments[i].yhi);
    }
    double width = fmax(x_max - x_min, 0), height = fmax(y_max - y_min, 0);
    /* About `count` square cells; O(count) whatever the shape (no side above 4 count cells). */
    double cell = sqrt(fmax(width * height, 0) / count);
    if (!(cell > 0) || !isfinite(cell))
        cell = fmax(fmax(width, height) / count, 1e-300);
    cell = fmax(cell, fmax(width, height) / (4.0 * count));
    g->x_min = x_min;
    g->y_min = y_min;
    g->cell = cell;
    if (!(width < INFINITY && height < INFINITY)) { /* infinite coordinates: one cell, every pair tested */
        g->cell = 1;
        g->nx = g->ny = 1;
    } else {
        g->nx = (int32_t)fmin(width / cell + 1, 4.0 * count);
        g->ny = (int32_t)fmin(height / cell + 1, 4.0 * count);
        if ((int64_t)g->nx * g->ny > 4 * (int64_t)count + 4) { /* rounding: keep the budget */
            g->cell *= 2;
            g->nx = (int32_t)(width / g->cell + 1);
            g->ny = (int32_t)(height / g->cell + 1);
        }
    }
    size_t cells = (size_t)g->nx * (size_t)g->ny;
    g->cell_start = calloc(cells + 1, sizeof(int32_t));
    g->entries = NULL;
    if (!g->cell_start)
        return 0;
    int64_t total = 0;
    for (int32_t i = 0; i < count; ++i)
        FOR_CELLS(g, &segments[i], { ++g->cell_start[cell + 1]; ++total; })
    if (total > INT32_MAX)
        return 0;
    for (size_t c = 0; c < cells; ++c)
        g->cell_start[c + 1] += g->cell_start[c];
    int32_t *fill = malloc(cells * sizeof(int32_t) + 1);
    g->entries = malloc((size_t)total * sizeof(int32_t) + 1);
    if (!fill || !g->entries) {
        free(fill);
        return 0;
    }
    memcpy(fill, g->cell_start, cells * sizeof(int32_t));
    for (int32_t i = 0; i < count; ++i)
        FOR_CELLS(g, &segments[i], { g->entries[fill[cell]++] = i; })
    free(fill);
    return 1;
}

/*
 * Pairs of non-neighbouring segments that meet; -1 when out of memory. When
 * `marked` is given, marked[v] = 1 for both end vertices of every segment
 * in such a pair. Each pair whose bounding boxes overlap is tested in the
 * one grid cell holding the lower-left corner of their boxes' intersection,
 * so it is counted once. Cost: O(n) to build, plus, per cell, the pairs of
 * segments listed in it: O(n + b) with b the pairs whose bounding boxes
 * share a cell, for outlines (edges short against the piece, about one per
 * cell); a crowd of segments in one cell, or segments spanning many cells,
 * costs more, up to all pairs in a degenerate case.
 */
static int32_t count_crossings(const segment *segments, int32_t count, uint8_t *marked)
{
    if (count < 2)
        return 0;
    segment_grid grid;
    if (!grid_build(&grid, segments, count)) {
        free(grid.cell_start);
        free(grid.entries);
        return -1;
    }
    int32_t crossings = 0, cells = grid.nx * grid.ny;
    for (int32_t c = 0; c < cells; ++c) {
        int32_t first = grid.cell_start[c], last = grid.cell_start[c + 1];
        for (int32_t i = first; i < last; ++i) {
            const segment *s = &segments[grid.entries[i]];
            for (int32_t j = i + 1; j < last; ++j) {
                const segment *t = &segments[grid.entries[j]];
                if (t->x1 < s->x0 || s->x1 < t->x0 || t->yhi < s->ylo || s->yhi < t->ylo)
                    continue;
                if (t->a == s->a || t->a == s->b || t->b == s->a || t->b == s->b)
                    continue;
                /* The pair's own cell: where the intersection of the boxes starts. */
                int32_t cx = grid_cell_index(&grid, fmax(s->x0, t->x0), grid.x_min, grid.nx);
                int32_t cy = grid_cell_index(&grid, fmax(s->ylo, t->ylo), grid.y_min, grid.ny);
                if (cy * grid.nx + cx != c || !segments_meet(s, t))
                    continue;
                ++crossings;
                if (marked)
                    marked[s->a] = marked[s->b] = marked[t->a] = marked[t->b] = 1;
            }
        }
    }
    free(grid.cell_start);
    free(grid.entries);
    return crossings;
}

/* ------------------------------------------------------------------------ */
/* Reflections (seams and darts)                                             */
/* ------------------------------------------------------------------------ */

/*
 * Sum of squared distances after the best reflection R (det -1) mapping the
 * points a_i onto c_i, both given relative to their own centres. For R =
 * [[cos t, sin t], [sin t, -cos t]], sum c.Ra = cos t A + sin t B, at most
 * sqrt(A^2 + B^2).
 */
static double best_reflection_residual2(const double *a, const double *c, int32_t n)
{
    double A = 0, B = 0, norms = 0;
    for (int32_t i = 0; i < n; ++i) {
        const double *p = a + 2 * i, *q = c + 2 * i;
        A += q[0] * p[0] - q[1] * p[1];
        B += q[0] * p[1] + q[1] * p[0];
        norms += p[0] * p[0] + p[1] * p[1] + q[0] * q[0] + q[1] * q[1];
    }
    double r = norms - 2 * sqrt(A * A + B * B);
    return r > 0 ? r : 0;
}

static double polyline2(const double *uv, const int32_t *ids, int32_t n)
{
    double length = 0;
    for (int32_t i = 0; i + 1 < n; ++i)
        length += distance2(uv + 2 * ids[i], uv + 2 * ids[i + 1]);
    return length;
}

static double polyline3(const double *positions, const int32_t *ids, int32_t n)
{
    double length = 0;
    for (int32_t i = 0; i + 1 < n; ++i)
        length += pz_vec3_distance(positions + 3 * ids[i], positions + 3 * ids[i + 1]);
    return length;
}

static int seam_metrics(const pz_seam *seam, const double *positions, const double *uv, pz_seam_metrics *m)
{
    int32_t n = seam->pair_count;
    m->panel_a = seam->panel_a;
    m->panel_b = seam->panel_b;
    m->length_3d_mm = polyline3(positions, seam->side_a, n);
    m->length_a_mm = polyline2(uv, seam->side_a, n);
    m->length_b_mm = polyline2(uv, seam->side_b, n);
    m->mismatch_rel = m->length_3d_mm > 0 ? fabs(m->length_a_mm - m->length_b_mm) / m->length_3d_mm : 0;
    double *a = malloc((size_t)n * 4 * sizeof(double) + 1);
    if (!a)
        return 0;
    double *c = a + 2 * n, ca[2] = {0, 0}, cc[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            ca[k] += uv[2 * seam->side_a[i] + k] / n;
            cc[k] += uv[2 * seam->side_b[i] + k] / n;
        }
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            a[2 * i + k] = uv[2 * seam->side_a[i] + k] - ca[k];
            c[2 * i + k] = uv[2 * seam->side_b[i] + k] - cc[k];
        }
    m->reflection_residual_mm = n > 0 ? sqrt(best_reflection_residual2(a, c, n) / n) : 0;
    free(a);
    return 1;
}

/* Leg length: the polyline of the leg plus the step from its end nearer the tip (in 3D) to the tip. */
static double leg_length(const double *points, int dimension, const double *positions, const int32_t *leg, int32_t n,
                         int32_t tip)
{
    int tip_after_last = pz_vec3_distance(positions + 3 * leg[n - 1], positions + 3 * tip) <
                         pz_vec3_distance(positions + 3 * leg[0], positions + 3 * tip);
    int32_t end = tip_after_last ? leg[n - 1] : leg[0];
    if (dimension == 2)
        return polyline2(points, leg, n) + distance2(points + 2 * end, points + 2 * tip);
    return polyline3(points, leg, n) + pz_vec3_distance(points + 3 * end, points + 3 * tip);
}

static int dart_metrics(const pz_dart *dart, const double *positions, const double *uv, pz_dart_metrics *m)
{
    int32_t n = dart->pair_count;
    if (n < 1)
        return 1;
    m->leg_a_mm = leg_length(uv, 2, positions, dart->leg_a, n, dart->tip);
    m->leg_b_mm = leg_length(uv, 2, positions, dart->leg_b, n, dart->tip);
    double length_3d = (leg_length(positions, 3, positions, dart->leg_a, n, dart->tip) +
                        leg_length(positions, 3, positions, dart->leg_b, n, dart->tip)) / 2;
    m->mismatch_rel = length_3d > 0 ? fabs(m->leg_a_mm - m->leg_b_mm) / length_3d : 0;
    /* The mouth: the legs' ends farther from the tip (a leg may be listed from either end). */
    int32_t mouth = pz_vec3_distance(positions + 3 * dart->leg_a[n - 1], positions + 3 * dart->tip) <
                            pz_vec3_distance(positions + 3 * dart->leg_a[0], positions + 3 * dart->tip)
                        ? 0
                        : n - 1;
    m->intake_mm = distance2(uv + 2 * dart->leg_a[mouth], uv + 2 * dart->leg_b[mouth]);
    double *b = malloc((size_t)n * 4 * sizeof(double) + 1);
    if (!b)
        return 0;
    double *a = b + 2 * n;
    const double *tip = uv + 2 * dart->tip;
    for (int32_t i = 0; i < n; ++i)
        for (int k = 0; k < 2; ++k) {
            b[2 * i + k] = uv[2 * dart->leg_b[i] + k] - tip[k];
            a[2 * i + k] = uv[2 * dart->leg_a[i] + k] - tip[k];
        }
    /* The axis passes through the tip: no centring, the tip is the fixed point. */
    m->symmetry_residual_mm = sqrt(best_reflection_residual2(b, a, n) / n);
    free(b);
    return 1;
}

/* ------------------------------------------------------------------------ */
/* Per panel                                                                 */
/* ------------------------------------------------------------------------ */

static int compare_doubles(const void *l, const void *r)
{
    double a = *(const double *)l, b = *(const double *)r;
    return (a > b) - (a < b);
}

/* Stats of values[faces[i]] over one panel; scratch holds count doubles. */
static pz_stat panel_stat(const double *values, const double *weights, const int32_t *faces, int32_t count,
                          double *scratch)
{
    pz_stat stat = {0, 0, 0};
    double weight = 0, sum = 0;
    for (int32_t i = 0; i < count; ++i) {
        double x = values[faces[i]];
        scratch[i] = fabs(x);
        sum += weights[faces[i]] * x;
        weight += weights[faces[i]];
    }
    if (count == 0)
        return stat;
    qsort(scratch, (size_t)count, sizeof(double), compare_doubles);
    stat.max = scratch[count - 1];
    int32_t rank = (int32_t)ceil(0.95 * count) - 1;
    stat.p95 = scratch[rank < 0 ? 0 : rank];
    stat.mean = weight > 0 ? sum / weight : 0;
    return stat;
}

/* Everything measured triangle by triangle, kept for the per-panel sums. */
typedef struct face_figures {
    double *area_3d, *area_2d_signed, *orthotropic, *arap;
    double *angle_error;   /* sum over the 3 corners of |theta0 - theta| / theta0 */
} face_figures;

static void measure_faces(const pz_mesh *mesh, const double *positions, const double *uv, const pz_fabric *fabric,
                          pz_metrics *m, face_figures *ff)
{
    /* Below a few thousand faces a team costs more than the loop (fork/join,
     * and libgomp's workers spinning after it on a busy machine). */
#pragma omp parallel for schedule(static) if (mesh->face_count >= 8192)
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        double p3[3][3], p2[3][2], du[3], dv[3];
        const int32_t *corner = mesh->faces + 3 * f;
        for (int k = 0; k < 3; ++k) {
            memcpy(p3[k], positions + 3 * corner[k], sizeof p3[k]);
            memcpy(p2[k], uv + 2 * corner[k], sizeof p2[k]);
        }
        pz_metrics_triangle_strain((const double(*)[3])p3, (const double(*)[2])p2, &m->strain_warp[f],
                                   &m->strain_weft[f], &m->shear_deg[f]);
        double det = triangle_jacobian((const double(*)[3])p3, (const double(*)[2])p2, du, dv);
        double area_2d = fabs(det) / 2, s1, s2;
        ff->area_3d[f] = area3((const double(*)[3])p3);
        ff->area_2d_signed[f] = det / 2;
        singular_values(du, dv, &s1, &s2);
        ff->arap[f] = det != 0 ? area_2d * ((s1 - 1) * (s1 - 1) + (s2 - 1) * (s2 - 1)) : 0;
        double su = pz_vec3_norm(du) - 1, sv = pz_vec3_norm(dv) - 1, phi = PZ_PI / 2 - thread_angle(du, dv);
        ff->orthotropic[f] = det != 0 ? 0.5 * area_2d * (fabric->k_su * su * su + fabric->k_sv * sv * sv) +
                                            0.5 * area_2d * fabric->k_r * phi * phi
                                      : 0;
        double error = 0;
        for (int k = 0; k < 3; ++k) {
            double theta0 = corner_angle3(p3[k], p3[(k + 1) % 3], p3[(k + 2) % 3]);
            double theta = corner_angle2(p2[k], p2[(k + 1) % 3], p2[(k + 2) % 3]);
            error += theta0 > 0 ? fabs(theta0 - theta) / theta0 : 0;
        }
        ff->angle_error[f] = error;
    }
}

/* Edge sums over the whole cut mesh, accumulated per panel: E_C (all edges) and E_len (boundary edges). */
static void measure_edges(const pz_pattern *pattern, const pz_topology *t, const double *positions, const double *uv,
                          double *length_sum, double *length_error_sum, double *wire_error_sum, int32_t *wire_count)
{
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e], p = pattern->face_panel[pz_he_face(h)];
        int32_t a = pz_he_from(t, h), b = pz_he_to(t, h);
        double l0 = pz_vec3_distance(positions + 3 * a, positions + 3 * b), l = distance2(uv + 2 * a, uv + 2 * b);
        length_sum[p] += l0;
        length_error_sum[p] += fabs(l0 - l);
        if (t->edge_halfedge[2 * e + 1] < 0) {
            wire_error_sum[p] += l0 > 0 ? fabs(l0 - l) / l0 : 0;
            ++wire_count[p];
        }
    }
}

static segment outline_segment(const double *uv, int32_t a, int32_t b)
{
    const double *pa = uv + 2 * a, *pb = uv + 2 * b;
    segment s = {0};
    int swap = pa[0] > pb[0];
    s.x0 = swap ? pb[0] : pa[0];
    s.y0 = swap ? pb[1] : pa[1];
    s.x1 = swap ? pa[0] : pb[0];
    s.y1 = swap ? pa[1] : pb[1];
    s.ylo = fmin(pa[1], pb[1]);
    s.yhi = fmax(pa[1], pb[1]);
    s.a = a;
    s.b = b;
    return s;
}

int32_t pz_metrics_outline_crossings(const int32_t *edges, int32_t count, const double *uv)
{
    return pz_metrics_outline_crossings_marked(edges, count, uv, NULL);
}

int32_t pz_metrics_outline_crossings_marked(const int32_t *edges, int32_t count, const double *uv, uint8_t *marked)
{
    segment *segments = malloc((size_t)count * sizeof(segment) + 1);
    if (!segments)
        return -1;
    for (int32_t i = 0; i < count; ++i)
        segments[i] = outline_segment(uv, edges[2 * i], edges[2 * i + 1]);
    int32_t crossings = count_crossings(segments, count, marked);
    free(segments);
    return crossings;
}

/* Boundary self-intersections of every panel (only within a panel: pieces are laid out apart). */
static int count_panel_crossings(const pz_pattern *pattern, const pz_topology *t, const double *uv, pz_metrics *m)
{
    segment *segments = malloc((size_t)t->halfedge_count * sizeof(segment) + 1);
    int32_t *offsets = calloc((size_t)pattern->panel_count + 1, sizeof(int32_t));
    int32_t *fill = malloc((size_t)pattern->panel_count * sizeof(int32_t) + 1);
    int ok = segments && offsets && fill;
    for (int32_t h = 0; ok && h < t->halfedge_count; ++h)
        if (t->twin[h] < 0)
            ++offsets[pattern->face_panel[pz_he_face(h)] + 1];
    for (int32_t p = 0; ok && p < pattern->panel_count; ++p)
        offsets[p + 1] += offsets[p];
    if (ok)
        memcpy(fill, offsets, (size_t)pattern->panel_count * sizeof(int32_t));
    for (int32_t h = 0; ok && h < t->halfedge_count; ++h) {
        if (t->twin[h] >= 0)
            continue;
        segments[fill[pattern->face_panel[pz_he_face(h)]]++] = outline_segment(uv, pz_he_from(t, h), pz_he_to(t, h));
    }
    for (int32_t p = 0; ok && p < pattern->panel_count; ++p) {
        int32_t crossings = count_crossings(segments + offsets[p], offsets[p + 1] - offsets[p], NULL);
        if (crossings < 0)
            ok = 0;
        else
            m->panels[p].boundary_self_intersections = crossings;
    }
    free(segments);
    free(offsets);
    free(fill);
    return ok;
}

/* Faces grouped by panel (CSR). */
static int group_faces(const pz_pattern *pattern, int32_t **offsets_out, int32_t **faces_out)
{
    int32_t nf = pattern->mesh->face_count, np = pattern->panel_count;
    int32_t *offsets = calloc((size_t)np + 1, sizeof(int32_t));
    int32_t *faces = malloc((size_t)nf * sizeof(int32_t) + 1);
    int32_t *fill = malloc((size_t)np * sizeof(int32_t) + 1);
    if (!offsets || !faces || !fill) {
        free(offsets);
        free(faces);
        free(fill);
        return 0;
    }
    for (int32_t f = 0; f < nf; ++f)
        ++offsets[pattern->face_panel[f] + 1];
    for (int32_t p = 0; p < np; ++p)
        offsets[p + 1] += offsets[p];
    memcpy(fill, offsets, (size_t)np * sizeof(int32_t));
    for (int32_t f = 0; f < nf; ++f)
        faces[fill[pattern->face_panel[f]]++] = f;
    free(fill);
    *offsets_out = offsets;
    *faces_out = faces;
    return 1;
}

static void panel_sums(pz_panel_metrics *pm, const face_figures *ff, const int32_t *faces, int32_t count)
{
    double signed_total = 0, area_error = 0, angle_error = 0;
    for (int32_t i = 0; i < count; ++i) {
        int32_t f = faces[i];
        pm->area_3d_mm2 += ff->area_3d[f];
        pm->area_2d_mm2 += fabs(ff->area_2d_signed[f]);
        signed_total += ff->area_2d_signed[f];
        pm->orthotropic_energy += ff->orthotropic[f];
        pm->arap_energy += ff->arap[f];
        area_error += fabs(ff->area_3d[f] - fabs(ff->area_2d_signed[f]));
        angle_error += ff->angle_error[f];
    }
    double orientation = signed_total >= 0 ? 1 : -1; /* the panel's majority (by area) orientation */
    for (int32_t i = 0; i < count; ++i)
        pm->flipped_triangles += orientation * ff->area_2d_signed[faces[i]] <= 0;
    pm->e_area = pm->area_3d_mm2 > 0 ? area_error / pm->area_3d_mm2 : 0;
    pm->e_ang = count > 0 ? angle_error / (3.0 * count) : 0;
}

/* ------------------------------------------------------------------------ */
/* Entry points                                                              */
/* ------------------------------------------------------------------------ */

void pz_metrics_free(pz_metrics **metrics)
{
    if (!metrics || !*metrics)
        return;
    pz_metrics *m = *metrics;
    free(m->strain_warp);
    free(m->strain_weft);
    free(m->shear_deg);
    free(m->panels);
    free(m->seams);
    free(m->darts);
    free(m);
    *metrics = NULL;
}

static pz_status allocate_metrics(const pz_pattern *pattern, pz_metrics **out, pz_ctx *ctx)
{
    size_t nf = (size_t)pattern->mesh->face_count;
    pz_metrics *m = calloc(1, sizeof *m);
    if (m) {
        m->face_count = pattern->mesh->face_count;
        m->panel_count = pattern->panel_count;
        m->seam_count = pattern->seam_count;
        m->dart_count = pattern->dart_count;
        m->strain_warp = malloc(nf * sizeof(double) + 1);
        m->strain_weft = malloc(nf * sizeof(double) + 1);
        m->shear_deg = malloc(nf * sizeof(double) + 1);
        m->panels = calloc((size_t)pattern->panel_count + 1, sizeof(pz_panel_metrics));
        m->seams = calloc((size_t)pattern->seam_count + 1, sizeof(pz_seam_metrics));
        m->darts = calloc((size_t)pattern->dart_count + 1, sizeof(pz_dart_metrics));
    }
    if (!m || !m->strain_warp || !m->strain_weft || !m->shear_deg || !m->panels || !m->seams || !m->darts) {
        pz_metrics_free(&m);
        return pz_error(ctx, PZ_ERR_NOMEM, "metrics: out of memory for %d faces", (int)nf);
    }
    *out = m;
    return PZ_OK;
}

static void face_figures_free(face_figures *ff)
{
    free(ff->area_3d);
    free(ff->area_2d_signed);
    free(ff->orthotropic);
    free(ff->arap);
    free(ff->angle_error);
}

static int face_figures_alloc(face_figures *ff, size_t nf)
{
    ff->area_3d = malloc(nf * sizeof(double) + 1);
    ff->area_2d_signed = malloc(nf * sizeof(double) + 1);
    ff->orthotropic = malloc(nf * sizeof(double) + 1);
    ff->arap = malloc(nf * sizeof(double) + 1);
    ff->angle_error = malloc(nf * sizeof(double) + 1);
    return ff->area_3d && ff->area_2d_signed && ff->orthotropic && ff->arap && ff->angle_error;
}

/* Per-panel figures: stats, sums, edge errors and crossings. Returns 0 when out of memory. */
static int measure_panels(const pz_pattern *pattern, const pz_topology *t, const double *positions, const double *uv,
                          const face_figures *ff, pz_metrics *m)
{
    int32_t np = pattern->panel_count, *offsets = NULL, *faces = NULL;
    double *scratch = malloc((size_t)pattern->mesh->face_count * sizeof(double) + 1);
    double *edge_sums = calloc((size_t)np * 3 + 1, sizeof(double));
    int32_t *wire_count = calloc((size_t)np + 1, sizeof(int32_t));
    int ok = scratch && edge_sums && wire_count && group_faces(pattern, &offsets, &faces);
    if (ok) {
        measure_edges(pattern, t, positions, uv, edge_sums, edge_sums + np, edge_sums + 2 * np, wire_count);
        for (int32_t p = 0; p < np; ++p) {
            pz_panel_metrics *pm = &m->panels[p];
            const int32_t *panel_faces = faces + offsets[p];
            int32_t count = offsets[p + 1] - offsets[p];
            pm->panel = p;
            pm->face_count = count;
            pm->strain_warp = panel_stat(m->strain_warp, ff->area_3d, panel_faces, count, scratch);
            pm->strain_weft = panel_stat(m->strain_weft, ff->area_3d, panel_faces, count, scratch);
            pm->shear_deg = panel_stat(m->shear_deg, ff->area_3d, panel_faces, count, scratch);
            panel_sums(pm, ff, panel_faces, count);
            pm->e_shape = edge_sums[p] > 0 ? edge_sums[np + p] / edge_sums[p] : 0;
            pm->e_len = wire_count[p] > 0 ? edge_sums[2 * np + p] / wire_count[p] : 0;
        }
        ok = count_panel_crossings(pattern, t, uv, m);
    }
    free(scratch);
    free(edge_sums);
    free(wire_count);
    free(offsets);
    free(faces);
    return ok;
}

static void summarize(pz_metrics *m)
{
    m->injective = 1;
    for (int32_t p = 0; p < m->panel_count; ++p) {
        const pz_panel_metrics *pm = &m->panels[p];
        m->max_abs_strain = fmax(m->max_abs_strain, fmax(pm->strain_warp.max, pm->strain_weft.max));
        if (pm->flipped_triangles || pm->boundary_self_intersections)
            m->injective = 0;
    }
    for (int32_t s = 0; s < m->seam_count; ++s)
        m->max_seam_mismatch_rel = fmax(m->max_seam_mismatch_rel, m->seams[s].mismatch_rel);
}

pz_fabric pz_fabric_default(void)
{
    return (pz_fabric){0.946, 0.548, 0.159};
}

pz_status pz_metrics_compute(const pz_pattern *pattern, const double *uv, int pose, const pz_fabric *fabric,
                             pz_metrics **out, pz_ctx *ctx)
{
    *out = NULL;
    const pz_mesh *mesh = pattern->mesh;
    if (pose < 0 || pose > mesh->pose_count)
        return pz_error(ctx, PZ_ERR_USAGE, "metrics: pose %d does not exist (the pattern has %d extra poses)", pose,
                        (int)mesh->pose_count);
    const double *positions = pose == 0 ? mesh->positions : mesh->poses + (size_t)(pose - 1) * mesh->vertex_count * 3;
    pz_fabric constants = pz_fabric_default();
    if (fabric) {
        constants.k_su = fabric->k_su > 0 ? fabric->k_su : constants.k_su;
        constants.k_sv = fabric->k_sv > 0 ? fabric->k_sv : constants.k_sv;
        constants.k_r = fabric->k_r > 0 ? fabric->k_r : constants.k_r;
    }
    pz_topology *t = NULL;
    pz_status status = pz_topology_build(mesh, &t, ctx);
    if (status)
        return status;
    pz_metrics *m = NULL;
    face_figures ff = {0};
    if ((status = allocate_metrics(pattern, &m, ctx))) {
        pz_topology_free(&t);
        return status;
    }
    int ok = face_figures_alloc(&ff, (size_t)mesh->face_count);
    if (ok) {
        measure_faces(mesh, positions, uv, &constants, m, &ff);
        ok = measure_panels(pattern, t, positions, uv, &ff, m);
    }
    for (int32_t s = 0; ok && s < pattern->seam_count; ++s) {
        m->seams[s].seam = s;
        ok = seam_metrics(&pattern->seams[s], positions, uv, &m->seams[s]);
    }
    for (int32_t d = 0; ok && d < pattern->dart_count; ++d) {
        m->darts[d].dart = d;
        ok = dart_metrics(&pattern->darts[d], positions, uv, &m->darts[d]);
    }
    face_figures_free(&ff);
    pz_topology_free(&t);
    if (!ok) {
        pz_metrics_free(&m);
        return pz_error(ctx, PZ_ERR_NOMEM, "metrics: out of memory for %d faces", (int)mesh->face_count);
    }
    summarize(m);
    *out = m;
    return PZ_OK;
}
