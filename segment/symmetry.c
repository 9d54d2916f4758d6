/*
 * segment/symmetry.c -- the garment's mirror plane (pietroni2022 Sec. 3,
 * Fig. 3a, and Sec. 4.2, "Symmetry": the layout is built on one side and
 * copied to the other; docs/segment.md, "Symmetry").
 *
 * A draped or scanned garment is only nearly symmetric, in any orientation,
 * and its meshing is not symmetric at all, so the plane is fitted to the
 * surface, not to vertex pairs:
 *  - candidates: the x, y and z axes and the principal axes of the
 *    area-weighted vertices (a symmetric body has its plane's normal among
 *    them; when two principal moments are within 15 % the two axes are
 *    arbitrary in their plane, which is then sampled every 15 degrees), each
 *    plane through the area centroid;
 *  - ICP on the plane: every sample vertex is mirrored, matched to the
 *    closest point of the surface (its nearest vertex through a uniform grid,
 *    then the closest point of the faces around it, and that face's normal),
 *    and the plane refitted by one Gauss-Newton step, point to plane, on the
 *    nearest 80 % of the pairs (fit_refit). Every candidate gets
 *    COARSE_ITERATIONS steps on COARSE_SAMPLES vertices, the best REFINED up
 *    to FINE_ITERATIONS on SAMPLES, until the plane settles;
 *  - the residual is the larger of two 90th percentiles over every vertex:
 *    its mirror image's distance to the surface, and, for border vertices,
 *    to the border (the RMS of the first is kept too); AUTO accepts a plane
 *    whose residual is below 1.5 % of the bounding-box diagonal
 *    (tolerance_rel): the draped DiffAvatar T-shirt measures 1.0 %, a plane
 *    across it 2.5 % or more;
 *  - a plane within 1 degree of a coordinate axis whose axis-normal fit is
 *    within 10 % as good is snapped to it: garments are modelled upright.
 * The grid search gives up beyond 5 % of the diagonal (a mirror image that
 * far from every vertex: no mirror, -1, counted at that distance in the
 * residual), which keeps far-off images of an asymmetric plane from scanning
 * the whole grid. The final maps cover every vertex and face: O(V + F)
 * expected (25-90 ms on 2-4K-vertex garments, 0.3-0.4 s on a 25K-vertex
 * bodice).
 *
 * Mirroring a path maps its vertices through vertex_mirror, closes gaps with
 * pz_trace_path_through, and gives every mirrored vertex the arm of its
 * cross closest to the reflected arm of the original.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_TOLERANCE_REL 0.015
#define RESIDUAL_PERCENTILE 0.9
#define SEARCH_LIMIT_REL 0.05      /* give up a nearest-vertex search beyond this times the diagonal */
#define SIDE_TOLERANCE_EDGES 0.5
#define SAMPLES 1000               /* vertices a plane is fitted to */
#define FIT_KEEP 0.8               /* share of the pairs (the nearest) each refit uses */
#define COARSE_ITERATIONS 2        /* ICP iterations for every candidate, on COARSE_SAMPLES */
#define COARSE_SAMPLES 500
#define FINE_ITERATIONS 15         /* at most, for the best REFINED candidates */
#define REFINED 3
#define SETTLED_OFFSET 1e-9       /* an axis's plane settled: its offset moved less x diag */
#define AXIS_ITERATIONS 60
#define SETTLED_RAD 1e-4           /* the plane settled: its normal turned less, its offset moved less x diag */
#define SIMILAR_MOMENTS 1.15       /* principal moments this close: their axes are sampled in their plane */
#define SAMPLED_STEP_DEG 15.0
#define DUPLICATE_DEG 3.0          /* candidate normals closer than this are one */
#define SNAP_DEG 1.0
#define SNAP_SLACK 1.1

/* ---------------------------------------------------------------- uniform vertex grid */

typedef struct vertex_grid {
    const double *positions;
    double origin[3], cell;
    int32_t dims[3];
    int32_t *cell_start;  /* cell count + 1 */
    int32_t *items;       /* vertices sorted by cell */
} vertex_grid;

static void grid_free(vertex_grid *grid)
{
    free(grid->cell_start), free(grid->items);
    memset(grid, 0, sizeof *grid);
}

static int32_t grid_coord(const vertex_grid *grid, const double *p, int axis)
{
    return (int32_t)floor((p[axis] - grid->origin[axis]) / grid->cell);
}

static size_t grid_cell(const vertex_grid *grid, int32_t x, int32_t y, int32_t z)
{
    return ((size_t)z * (size_t)grid->dims[1] + (size_t)y) * (size_t)grid->dims[0] + (size_t)x;
}

/* Buckets the vertices in use (used[v] != 0) by a counting sort over the cells. Returns 0 when out of memory. */
static int grid_build(const pz_mesh *mesh, const uint8_t *used, double cell, vertex_grid *grid)
{
    memset(grid, 0, sizeof *grid);
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    grid->positions = mesh->positions;
    grid->cell = cell;
    size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
        grid->origin[k] = lo[k];
        grid->dims[k] = (int32_t)fmin(1024.0, floor((hi[k] - lo[k]) / cell) + 1);
        cells *= (size_t)grid->dims[k];
    }
    grid->cell_start = calloc(cells + 2, sizeof(int32_t));
    grid->items = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    if (!grid->cell_start || !grid->items)
        return 0;
    size_t *cell_of = malloc(((size_t)mesh->vertex_count + 1) * sizeof(size_t));
    if (!cell_of)
        return 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (!used[v])
            continue;
        int32_t c[3];
        for (int k = 0; k < 3; ++k) {
            c[k] = grid_coord(grid, mesh->positions + 3 * (size_t)v, k);
            c[k] = c[k] < 0 ? 0 : c[k] >= grid->dims[k] ? grid->dims[k] - 1 : c[k];
        }
        cell_of[v] = grid_cell(grid, c[0], c[1], c[2]);
        ++grid->cell_start[cell_of[v] + 2];
    }
    for (size_t c = 2; c < cells + 2; ++c)
        grid->cell_start[c] += grid->cell_start[c - 1];
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (used[v])
            grid->items[grid->cell_start[cell_of[v] + 1]++] = v;
    free(cell_of);
    return 1;
}

static void visit_cell(const vertex_grid *grid, int32_t x, int32_t y, int32_t z, const double *p, int32_t *best,
                       double *best_d2)
{
    size_t c = grid_cell(grid, x, y, z);
    for (int32_t i = grid->cell_start[c]; i < grid->cell_start[c + 1]; ++i) {
        const double *q = grid->positions + 3 * (size_t)grid->items[i];
        double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
        if (d2 < *best_d2 || (d2 == *best_d2 && grid->items[i] < *best))
            *best_d2 = d2, *best = grid->items[i];
    }
}

static int32_t clamp_range(int32_t value, int32_t dim)
{
    return value < 0 ? 0 : value >= dim ? dim - 1 : value;
}

/* Visits the cells at Chebyshev distance r from cell c that lie in the grid. */
static void visit_ring(const vertex_grid *grid, const int32_t c[3], int32_t r, const double *p, int32_t *best,
                       double *best_d2)
{
    int32_t lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = clamp_range(c[k] - r, grid->dims[k]), hi[k] = clamp_range(c[k] + r, grid->dims[k]);
        if (c[k] + r < 0 || c[k] - r >= grid->dims[k])
            return; /* the ring misses the grid along this axis */
    }
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y) {
            if (abs(x - c[0]) == r || abs(y - c[1]) == r) {
                for (int32_t z = lo[2]; z <= hi[2]; ++z)
                    visit_cell(grid, x, y, z, p, best, best_d2);
                continue;
            }
            if (c[2] - r >= 0 && c[2] - r < grid->dims[2])
                visit_cell(grid, x, y, c[2] - r, p, best, best_d2);
            if (r > 0 && c[2] + r >= 0 && c[2] + r < grid->dims[2])
                visit_cell(grid, x, y, c[2] + r, p, best, best_d2);
        }
}

/* The vertex nearest to p within max_distance (ties: lowest index), or -1; its distance in *distance. */
static int32_t grid_nearest(const vertex_grid *grid, const double *p, double max_distance, double *distance)
{
    int32_t c[3], best = -1;
    double best_d2 = INFINITY;
    for (int k = 0; k < 3; ++k)
        c[k] = grid_coord(grid, p, k);
    int32_t max_ring = (int32_t)ceil(max_distance / grid->cell) + 1;
    for (int32_t r = 0; r <= max_ring; ++r) {
        visit_ring(grid, c, r, p, &best, &best_d2);
        /* Every cell beyond ring r lies at least r cells from p. */
        if (best >= 0 && sqrt(best_d2) <= r * grid->cell)
            break;
    }
    *distance = sqrt(best_d2);
    if (best >= 0 && *distance > max_distance)
        best = -1;
    return best;
}

/* ---------------------------------------------------------------- the surface */

/* The garment as the fit queries it: its vertex grid and faces. */
typedef struct surface {
    const pz_mesh *mesh;
    const pz_topology *topology;
    vertex_grid grid;
    double limit;      /* searches give up beyond this distance */
    double diagonal;
} surface;

/*
 * The point of the surface closest to p among the faces around p's nearest
 * vertex (exact on a fine mesh up to the rare case where the closest face
 * does not touch the nearest vertex, then within about an edge's sagitta).
 * Returns that face (-1 when no vertex lies within the search limit: then
 * *distance = limit); *vertex the nearest vertex.
 */
static int32_t surface_closest(const surface *s, const double *p, double closest[3], double *distance, int32_t *vertex)
{
    double vertex_distance;
    int32_t v = grid_nearest(&s->grid, p, s->limit, &vertex_distance);
    *vertex = v;
    if (v < 0) {
        *distance = s->limit;
        memcpy(closest, p, 3 * sizeof(double));
        return -1;
    }
    const pz_topology *t = s->topology;
    const double *x = s->mesh->positions;
    memcpy(closest, x + 3 * (size_t)v, 3 * sizeof(double));
    double best = vertex_distance;
    int32_t best_face = pz_he_face(t->vertex_halfedge[v]);
    int32_t start = t->vertex_halfedge[v], h = start;
    do {
        int32_t f = pz_he_face(h);
        const int32_t *corner = t->faces + 3 * (size_t)f;
        const double *a = x + 3 * (size_t)corner[0], *b = x + 3 * (size_t)corner[1], *c = x + 3 * (size_t)corner[2];
        double bary[3], q[3];
        pz_geom_closest_on_triangle(p, a, b, c, bary);
        for (int k = 0; k < 3; ++k)
            q[k] = bary[0] * a[k] + bary[1] * b[k] + bary[2] * c[k];
        double d = pz_vec3_distance(p, q);
        if (d < best) {
            best = d, best_face = f;
            memcpy(closest, q, sizeof q);
        }
        h = t->twin[pz_he_prev(h)];
    } while (h >= 0 && h != start);
    *distance = best;
    return best_face;
}

/* ---------------------------------------------------------------- planes */

typedef struct plane {
    double normal[3], offset;
} plane;

static void reflect(const plane *pl, const double *p, double *out)
{
    double t = pz_vec3_dot(pl->normal, p) - pl->offset;
    for (int k = 0; k < 3; ++k)
        out[k] = p[k] - 2 * t * pl->normal[k];
}

static int compare_double(const void *l, const void *r)
{
    double a = *(const double *)l, b = *(const double *)r;
    return (a > b) - (a < b);
}

/* The value below which `share` of values[0..n-1] lie (sorts them). */
static double percentile(double *values, int32_t n, double share)
{
    if (n <= 0)
        return 0;
    qsort(values, (size_t)n, sizeof(double), compare_double);
    int32_t at = (int32_t)ceil(share * n) - 1;
    return values[at < 0 ? 0 : at >= n ? n - 1 : at];
}

/* The fit's working set: sample vertices, their matches, distances. */
typedef struct fit {
    const surface *s;
    const int32_t *samples;
    int32_t count;
    double centroid[3];  /* positions are taken relative to it (the normal equations stay well scaled) */
    double *matched;     /* 3 x count: the surface point closest to each sample's mirror image */
    double *normals;     /* 3 x count: the unit normal of the face it lies on */
    double *distance;    /* count */
    double *sorted;      /* count: scratch */
} fit;

/* Matches every sample's mirror image; returns the residual (RESIDUAL_PERCENTILE of the distances). */
static double fit_match(fit *f, const plane *pl)
{
    const double *x = f->s->mesh->positions;
    const int32_t *faces = f->s->mesh->faces;
    for (int32_t i = 0; i < f->count; ++i) {
        double m[3], u[3], v[3];
        int32_t vertex;
        reflect(pl, x + 3 * (size_t)f->samples[i], m);
        int32_t face = surface_closest(f->s, m, f->matched + 3 * (size_t)i, f->distance + i, &vertex);
        double *normal = f->normals + 3 * (size_t)i;
        memset(normal, 0, 3 * sizeof(double));
        if (face < 0)
            continue;
        const int32_t *corner = faces + 3 * (size_t)face;
        pz_vec3_sub(x + 3 * (size_t)corner[1], x + 3 * (size_t)corner[0], u);
        pz_vec3_sub(x + 3 * (size_t)corner[2], x + 3 * (size_t)corner[0], v);
        pz_vec3_cross(u, v, normal);
        pz_vec3_normalize(normal);
    }
    memcpy(f->sorted, f->distance, (size_t)f->count * sizeof(double));
    return percentile(f->sorted, f->count, RESIDUAL_PERCENTILE);
}

/* Two unit vectors completing n to an orthonormal frame. */
static void tangent_frame(const double n[3], double u[3], double v[3])
{
    double helper[3] = {fabs(n[0]) < 0.6 ? 1 : 0, fabs(n[0]) < 0.6 ? 0 : 1, 0};
    pz_vec3_cross(n, helper, u);
    pz_vec3_normalize(u);
    pz_vec3_cross(n, u, v);
}

/* Solves the 3x3 system a x = b (Cramer); 0 when singular. */
static int solve3(const double a[3][3], const double b[3], double x[3])
{
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (!(fabs(det) > 0) || !isfinite(det))
        return 0;
    for (int c = 0; c < 3; ++c) {
        double m[3][3];
        memcpy(m, a, sizeof m);
        for (int r = 0; r < 3; ++r)
            m[r][c] = b[r];
        x[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
    }
    return 1;
}

#define MAX_TURN_RAD 0.2   /* a refit turns the normal by at most this much */

/*
 * One Gauss-Newton refit from the current matches, point to plane: the
 * nearest FIT_KEEP of the pairs, each residual the distance of the mirrored
 * sample to the tangent plane at its match, e = (R(p) - q) . m, linearised in
 * the plane's parameters (the normal turned by a u + b v, the offset moved by
 * c): R(p) changes by -2 [(delta . p - c) n + (n . p - d) delta]. With
 * fixed_normal only c moves. Point to plane rather than point to point: the
 * closest point of the surface slides along it, and the fit converges in a
 * few steps instead of creeping. Returns how far the plane moved (angle in
 * radians plus offset change / diagonal).
 */
static double fit_refit(fit *f, plane *pl, int fixed_normal)
{
    memcpy(f->sorted, f->distance, (size_t)f->count * sizeof(double));
    double keep = percentile(f->sorted, f->count, FIT_KEEP);
    const double *x = f->s->mesh->positions, *n = pl->normal;
    double u[3], v[3];
    tangent_frame(n, u, v);
    double offset = pl->offset - pz_vec3_dot(n, f->centroid); /* the plane n . (p - centroid) = offset */
    double normal_matrix[3][3] = {{0}}, rhs[3] = {0, 0, 0};
    for (int32_t i = 0; i < f->count; ++i) {
        const double *m = f->normals + 3 * (size_t)i, *q = f->matched + 3 * (size_t)i;
        if (f->distance[i] > keep || pz_vec3_dot(m, m) == 0)
            continue;
        double p[3], mirrored[3], gap[3];
        pz_vec3_sub(x + 3 * (size_t)f->samples[i], f->centroid, p);
        double t = pz_vec3_dot(n, p) - offset, nm = pz_vec3_dot(n, m);
        for (int k = 0; k < 3; ++k)
            mirrored[k] = p[k] - 2 * t * n[k] + f->centroid[k];
        pz_vec3_sub(mirrored, q, gap);
        double e = pz_vec3_dot(gap, m);
        double row[3] = {fixed_normal ? 0 : 2 * (pz_vec3_dot(u, p) * nm + t * pz_vec3_dot(u, m)),
                         fixed_normal ? 0 : 2 * (pz_vec3_dot(v, p) * nm + t * pz_vec3_dot(v, m)), -2 * nm};
        for (int r = 0; r < 3; ++r) {
            rhs[r] += row[r] * e;
            for (int c = 0; c < 3; ++c)
                normal_matrix[r][c] += row[r] * row[c];
        }
    }
    double trace = normal_matrix[0][0] + normal_matrix[1][1] + normal_matrix[2][2];
    for (int r = 0; r < 3; ++r)  /* a little damping; fixes the turn when the normal is held */
        normal_matrix[r][r] += 1e-9 * trace + (fixed_normal && r < 2 ? 1 : 0);
    double step[3];
    if (!solve3(normal_matrix, rhs, step))
        return 0;
    double turn = hypot(step[0], step[1]);
    if (turn > MAX_TURN_RAD)
        for (int k = 0; k < 2; ++k)
            step[k] *= MAX_TURN_RAD / turn;
    plane next;
    for (int k = 0; k < 3; ++k)
        next.normal[k] = n[k] + step[0] * u[k] + step[1] * v[k];
    pz_vec3_normalize(next.normal);
    next.offset = pz_vec3_dot(next.normal, f->centroid) + offset + step[2];
    double moved = acos(fmin(1, fmax(-1, pz_vec3_dot(next.normal, n)))) + fabs(step[2]) / f->s->diagonal;
    *pl = next;
    return moved;
}

/*
 * Up to `iterations` match-and-refit steps (fewer once the plane settles); returns the final residual. An
 * axis's plane (fixed_normal) settles to SETTLED_OFFSET: the same fixed point whether it starts from the
 * centroid (--symmetry x) or from a free fit snapped to the axis (AUTO), so both give the same plane and
 * the same layout.
 */
static double fit_plane(fit *f, plane *pl, int fixed_normal, int iterations)
{
    double settled = fixed_normal ? SETTLED_OFFSET : SETTLED_RAD;
    for (int i = 0; i < (fixed_normal ? AXIS_ITERATIONS : iterations); ++i) {
        fit_match(f, pl);
        if (fit_refit(f, pl, fixed_normal) < settled)
            break;
    }
    return fit_match(f, pl);
}

/* ---------------------------------------------------------------- candidates */

/* Area centroid, and the area-weighted covariance of the vertices (each weighs a third of its faces' areas). */
static void moments(const pz_mesh *mesh, double centroid[3], double covariance[3][3])
{
    double total = 0, sum[3] = {0, 0, 0}, second[3][3] = {{0}};
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *corner = mesh->faces + 3 * (size_t)f;
        const double *p[3] = {mesh->positions + 3 * (size_t)corner[0], mesh->positions + 3 * (size_t)corner[1],
                              mesh->positions + 3 * (size_t)corner[2]};
        double u[3], v[3], n[3];
        pz_vec3_sub(p[1], p[0], u), pz_vec3_sub(p[2], p[0], v), pz_vec3_cross(u, v, n);
        double area = 0.5 * pz_vec3_norm(n);
        total += area;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < 3; ++i) {
                sum[i] += area / 3 * p[c][i];
                for (int j = 0; j < 3; ++j)
                    second[i][j] += area / 3 * p[c][i] * p[c][j];
            }
    }
    for (int i = 0; i < 3; ++i)
        centroid[i] = total > 0 ? sum[i] / total : 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            covariance[i][j] = total > 0 ? second[i][j] / total - centroid[i] * centroid[j] : 0;
}

/* Eigen-decomposition of a symmetric 3x3 matrix (cyclic Jacobi): values ascending, vectors[k] unit. */
static void eigen3(const double matrix[3][3], double values[3], double vectors[3][3])
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    memcpy(a, matrix, sizeof a);
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        if (off <= 1e-15 * (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2])) || off == 0)
            break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0)
                    continue;
                double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; ++k) { /* a = J^T a J */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq, a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk, a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq, v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (a[order[j]][order[j]] < a[order[i]][order[i]]) {
                int swap = order[i];
                order[i] = order[j], order[j] = swap;
            }
    for (int i = 0; i < 3; ++i) {
        values[i] = a[order[i]][order[i]];
        for (int k = 0; k < 3; ++k)
            vectors[i][k] = v[k][order[i]];
    }
}

#define MAX_CANDIDATES 32

/* Adds direction d (unit) unless a candidate within DUPLICATE_DEG is there already. */
static void add_direction(double directions[][3], int *count, const double d[3])
{
    for (int i = 0; i < *count; ++i)
        if (fabs(pz_vec3_dot(directions[i], d)) > cos(DUPLICATE_DEG * PZ_PI / 180))
            return;
    if (*count < MAX_CANDIDATES)
        memcpy(directions[(*count)++], d, 3 * sizeof(double));
}

/* The candidate normals: the axes, the principal axes, and directions between principal axes of similar moment. */
static int candidate_directions(const double covariance[3][3], double directions[][3])
{
    int count = 0;
    for (int k = 0; k < 3; ++k) {
        double axis[3] = {k == 0, k == 1, k == 2};
        add_direction(directions, &count, axis);
    }
    double values[3], vectors[3][3];
    eigen3(covariance, values, vectors);
    for (int k = 0; k < 3; ++k)
        add_direction(directions, &count, vectors[k]);
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j) {
            if (!(values[j] <= SIMILAR_MOMENTS * values[i]) || !(values[i] > 0))
                continue;
            for (double deg = SAMPLED_STEP_DEG; deg < 180 - 1e-9; deg += SAMPLED_STEP_DEG) {
                double c = cos(deg * PZ_PI / 180), s = sin(deg * PZ_PI / 180), d[3];
                for (int k = 0; k < 3; ++k)
                    d[k] = c * vectors[i][k] + s * vectors[j][k];
                add_direction(directions, &count, d);
            }
        }
    return count;
}

/* Every k-th vertex in use, at most SAMPLES of them. */
static int32_t *sample_vertices(const pz_mesh *mesh, const uint8_t *used, int32_t *count)
{
    int32_t in_use = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        in_use += used[v] != 0;
    int32_t stride = in_use > SAMPLES ? (in_use + SAMPLES - 1) / SAMPLES : 1;
    int32_t *samples = malloc(((size_t)in_use / stride + 2) * sizeof(int32_t));
    *count = 0;
    if (!samples)
        return NULL;
    for (int32_t v = 0, seen = 0; v < mesh->vertex_count; ++v)
        if (used[v] && seen++ % stride == 0)
            samples[(*count)++] = v;
    return samples;
}

typedef struct trial {
    plane pl;
    double residual;
} trial;

static int compare_trial(const void *l, const void *r)
{
    const trial *a = l, *b = r;
    return (a->residual > b->residual) - (a->residual < b->residual);
}

/* The same fit on every k-th sample, at most `most` of them (buffer: room for f->count); shares f's scratch. */
static fit fit_subset(const fit *f, int32_t most, int32_t *buffer)
{
    fit sub = *f;
    int32_t stride = f->count > most ? (f->count + most - 1) / most : 1;
    sub.count = 0;
    for (int32_t i = 0; i < f->count; i += stride)
        buffer[sub.count++] = f->samples[i];
    sub.samples = buffer;
    return sub;
}

/* The best plane for AUTO: every candidate coarsely, the best REFINED to convergence, then the axis snap.
 * buffer: room for f->count samples. */
static plane best_plane(fit *f, const double centroid[3], const double covariance[3][3], int32_t *buffer, int *axis)
{
    double directions[MAX_CANDIDATES][3];
    int count = candidate_directions(covariance, directions);
    trial trials[MAX_CANDIDATES];
    fit coarse = fit_subset(f, COARSE_SAMPLES, buffer);
    for (int i = 0; i < count; ++i) {
        memcpy(trials[i].pl.normal, directions[i], 3 * sizeof(double));
        trials[i].pl.offset = pz_vec3_dot(directions[i], centroid);
        trials[i].residual = fit_plane(&coarse, &trials[i].pl, 0, COARSE_ITERATIONS);
    }
    qsort(trials, (size_t)count, sizeof *trials, compare_trial);
    for (int i = 0; i < count && i < REFINED; ++i)
        trials[i].residual = fit_plane(f, &trials[i].pl, 0, FINE_ITERATIONS);
    qsort(trials, (size_t)(count < REFINED ? count : REFINED), sizeof *trials, compare_trial);
    trial best = trials[0];
    *axis = -1;
    for (int k = 0; k < 3; ++k) {
        if (fabs(best.pl.normal[k]) < cos(SNAP_DEG * PZ_PI / 180))
            continue;
        trial snapped = best;
        memset(snapped.pl.normal, 0, sizeof snapped.pl.normal);
        snapped.pl.normal[k] = 1;
        snapped.pl.offset = best.pl.offset * (best.pl.normal[k] < 0 ? -1 : 1);
        snapped.residual = fit_plane(f, &snapped.pl, 1, FINE_ITERATIONS);
        if (snapped.residual <= SNAP_SLACK * best.residual + 1e-9 * f->s->diagonal) {
            best = snapped;
            *axis = k;
        }
    }
    return best.pl;
}

/* ---------------------------------------------------------------- detection */

void pz_symmetry_clear(pz_symmetry *symmetry)
{
    if (!symmetry)
        return;
    free(symmetry->vertex_mirror), free(symmetry->vertex_side), free(symmetry->face_mirror);
    memset(symmetry, 0, sizeof *symmetry);
    symmetry->axis = -1;
}

pz_status pz_symmetry_copy(const pz_symmetry *symmetry, pz_symmetry *out, pz_ctx *ctx)
{
    *out = *symmetry;
    out->vertex_mirror = NULL, out->vertex_side = NULL, out->face_mirror = NULL;
    size_t vertices = (size_t)symmetry->vertex_count, faces = (size_t)symmetry->face_count;
    if (symmetry->vertex_mirror && (out->vertex_mirror = malloc(vertices * sizeof(int32_t) + 1)))
        memcpy(out->vertex_mirror, symmetry->vertex_mirror, vertices * sizeof(int32_t));
    if (symmetry->vertex_side && (out->vertex_side = malloc(vertices + 1)))
        memcpy(out->vertex_side, symmetry->vertex_side, vertices);
    if (symmetry->face_mirror && (out->face_mirror = malloc(faces * sizeof(int32_t) + 1)))
        memcpy(out->face_mirror, symmetry->face_mirror, faces * sizeof(int32_t));
    if ((symmetry->vertex_mirror && !out->vertex_mirror) || (symmetry->vertex_side && !out->vertex_side) ||
        (symmetry->face_mirror && !out->face_mirror)) {
        pz_symmetry_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetry: out of memory copying the mirror maps");
    }
    return PZ_OK;
}

void pz_symmetry_reflect_point(const pz_symmetry *symmetry, const double p[3], double out[3])
{
    plane pl = {{symmetry->normal[0], symmetry->normal[1], symmetry->normal[2]}, symmetry->offset};
    reflect(&pl, p, out);
}

void pz_symmetry_reflect_direction(const pz_symmetry *symmetry, const double d[3], double out[3])
{
    double t = pz_vec3_dot(symmetry->normal, d);
    for (int k = 0; k < 3; ++k)
        out[k] = d[k] - 2 * t * symmetry->normal[k];
}

/* The vertices faces use, and the bounding-box diagonal. */
static uint8_t *used_vertices(const pz_mesh *mesh, const pz_topology *topology, double *diagonal)
{
    uint8_t *used = malloc((size_t)mesh->vertex_count + 1);
    if (!used)
        return NULL;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        used[v] = topology->vertex_halfedge[v] >= 0;
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    *diagonal = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
    return used;
}

/* Distance from p to the border edges at border vertex w (their closest point). */
static double border_distance(const surface *s, int32_t w, const double *p)
{
    const pz_topology *t = s->topology;
    const double *x = s->mesh->positions;
    double best = pz_vec3_distance(p, x + 3 * (size_t)w);
    int32_t start = t->vertex_halfedge[w], h = start;
    do {
        int32_t edges[2] = {h, pz_he_prev(h)}; /* the face's two half-edges at w */
        for (int k = 0; k < 2; ++k) {
            if (t->twin[edges[k]] >= 0)
                continue;
            const double *a = x + 3 * (size_t)pz_he_from(t, edges[k]), *b = x + 3 * (size_t)pz_he_to(t, edges[k]);
            double ab[3], ap[3];
            pz_vec3_sub(b, a, ab), pz_vec3_sub(p, a, ap);
            double length2 = pz_vec3_dot(ab, ab), u = length2 > 0 ? pz_vec3_dot(ap, ab) / length2 : 0;
            u = u < 0 ? 0 : u > 1 ? 1 : u;
            double q[3] = {a[0] + u * ab[0], a[1] + u * ab[1], a[2] + u * ab[2]};
            best = fmin(best, pz_vec3_distance(p, q));
        }
        h = t->twin[pz_he_prev(h)];
    } while (h >= 0 && h != start);
    return best;
}

/*
 * The maps of the chosen plane over every vertex and face: vertex_mirror,
 * vertex_side, face_mirror, and the residual: the larger of the
 * RESIDUAL_PERCENTILE of the surface distances over all vertices in use and
 * that of the border vertices' distances to the border (the surface distance
 * cannot see a garment stretched along itself, one side wider than the
 * other; its border can), with the RMS of the surface distances. A border
 * vertex maps to the border vertex nearest its mirror image (border: the
 * grid of border vertices; NULL: none), since the border's mirror image is
 * the border: a mirrored path then ends on the border where the original
 * does. Returns 0 when out of memory.
 */
static int fill_maps(const surface *s, const vertex_grid *border, const uint8_t *used, double mean_edge,
                     pz_symmetry *out)
{
    const pz_mesh *mesh = s->mesh;
    plane pl = {{out->normal[0], out->normal[1], out->normal[2]}, out->offset};
    out->vertex_count = mesh->vertex_count;
    out->face_count = mesh->face_count;
    out->vertex_mirror = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    out->vertex_side = malloc((size_t)mesh->vertex_count + 1);
    out->face_mirror = malloc(((size_t)mesh->face_count + 1) * sizeof(int32_t));
    double *distance = malloc(((size_t)mesh->vertex_count + 1) * sizeof(double));
    double *along_border = malloc(((size_t)mesh->vertex_count + 1) * sizeof(double));
    if (!out->vertex_mirror || !out->vertex_side || !out->face_mirror || !distance || !along_border) {
        free(distance), free(along_border);
        return 0;
    }
    int32_t n = 0, border_n = 0;
    double sum = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * (size_t)v;
        double side = pz_vec3_dot(pl.normal, p) - pl.offset;
        out->vertex_side[v] = fabs(side) <= SIDE_TOLERANCE_EDGES * mean_edge ? 1 : side < 0 ? 0 : 2;
        out->vertex_mirror[v] = -1;
        if (!used[v])
            continue;
        double m[3], q[3], d, border_d;
        reflect(&pl, p, m);
        surface_closest(s, m, q, &d, &out->vertex_mirror[v]);
        int32_t on_border = border && s->topology->vertex_on_boundary[v] ? grid_nearest(border, m, s->limit, &border_d) : -1;
        if (on_border >= 0) {
            out->vertex_mirror[v] = on_border;
            along_border[border_n++] = border_distance(s, on_border, m);
        }
        distance[n++] = d;
        sum += d * d;
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *corner = mesh->faces + 3 * (size_t)f;
        double c[3], m[3], q[3], d;
        int32_t vertex;
        for (int k = 0; k < 3; ++k)
            c[k] = (mesh->positions[3 * (size_t)corner[0] + k] + mesh->positions[3 * (size_t)corner[1] + k] +
                    mesh->positions[3 * (size_t)corner[2] + k]) / 3;
        reflect(&pl, c, m);
        out->face_mirror[f] = surface_closest(s, m, q, &d, &vertex);
    }
    out->rms_mm = n ? sqrt(sum / n) : 0;
    out->residual_mm = fmax(percentile(distance, n, RESIDUAL_PERCENTILE),
                            percentile(along_border, border_n, RESIDUAL_PERCENTILE));
    free(along_border);
    out->residual_rel = s->diagonal > 0 ? out->residual_mm / s->diagonal : 0;
    free(distance);
    return 1;
}

static pz_status check_mode(pz_symmetry_mode mode, const double plane_in[4], double tolerance_rel, pz_ctx *ctx)
{
    if (mode < PZ_SYMMETRY_AUTO || mode > PZ_SYMMETRY_PLANE || !(tolerance_rel >= 0.0))
        return pz_error(ctx, PZ_ERR_USAGE, "symmetry: bad mode %d or tolerance %g", (int)mode, tolerance_rel);
    if (mode == PZ_SYMMETRY_PLANE) {
        double length = plane_in ? pz_vec3_norm(plane_in) : 0;
        if (!plane_in || !(length > 0) || !isfinite(length) || !isfinite(plane_in[3]))
            return pz_error(ctx, PZ_ERR_USAGE, "symmetry: the plane's normal must be finite and non-zero");
    }
    return PZ_OK;
}

/* The plane of a given mode: found (the caller decides whether to use it), *axis set for an axis plane. */
static int choose_plane(fit *f, pz_symmetry_mode mode, const double plane_in[4], int32_t *buffer, plane *pl, int *axis)
{
    double centroid[3], covariance[3][3];
    moments(f->s->mesh, centroid, covariance);
    memcpy(f->centroid, centroid, sizeof centroid);
    *axis = -1;
    if (mode == PZ_SYMMETRY_PLANE) {
        double length = pz_vec3_norm(plane_in);
        for (int k = 0; k < 3; ++k)
            pl->normal[k] = plane_in[k] / length;
        pl->offset = plane_in[3] / length;
        for (int k = 0; k < 3; ++k)
            if (fabs(pl->normal[k]) == 1)
                *axis = k;
        return 1;
    }
    if (mode == PZ_SYMMETRY_AUTO) {
        *pl = best_plane(f, centroid, covariance, buffer, axis);
        return 1;
    }
    int k = (int)mode - PZ_SYMMETRY_X; /* a given axis: its offset fitted */
    memset(pl->normal, 0, sizeof pl->normal);
    pl->normal[k] = 1;
    pl->offset = centroid[k];
    fit_plane(f, pl, 1, FINE_ITERATIONS);
    *axis = k;
    return 1;
}

pz_status pz_symmetry_detect(const pz_mesh *mesh, const pz_topology *topology, pz_symmetry_mode mode,
                             const double plane_in[4], double tolerance_rel, pz_symmetry *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    out->axis = -1;
    pz_status status = check_mode(mode, plane_in, tolerance_rel, ctx);
    if (status || mode == PZ_SYMMETRY_OFF || mesh->face_count == 0)
        return status;
    double tolerance = tolerance_rel > 0.0 ? tolerance_rel : DEFAULT_TOLERANCE_REL;
    double mean_edge = pz_field_mean_edge_length(mesh, topology);
    surface s = {mesh, topology, {0}, 0, 0};
    uint8_t *used = used_vertices(mesh, topology, &s.diagonal);
    s.limit = SEARCH_LIMIT_REL * s.diagonal;
    fit f = {&s, NULL, 0, {0, 0, 0}, NULL, NULL, NULL, NULL};
    int ok = used && grid_build(mesh, used, fmax(2.0 * mean_edge, s.diagonal / 50.0), &s.grid) &&
             (f.samples = sample_vertices(mesh, used, &f.count)) != NULL;
    f.matched = malloc((3 * (size_t)f.count + 1) * sizeof(double));
    f.normals = malloc((3 * (size_t)f.count + 1) * sizeof(double));
    f.distance = malloc(((size_t)f.count + 1) * sizeof(double));
    f.sorted = malloc(((size_t)f.count + 1) * sizeof(double));
    int32_t *buffer = malloc(((size_t)f.count + 1) * sizeof(int32_t));
    ok = ok && f.matched && f.normals && f.distance && f.sorted && buffer;
    plane pl;
    vertex_grid border;
    memset(&border, 0, sizeof border);
    if (ok && choose_plane(&f, mode, plane_in, buffer, &pl, &out->axis)) {
        memcpy(out->normal, pl.normal, sizeof pl.normal);
        out->offset = pl.offset;
        int32_t border_count = 0;
        for (int32_t v = 0; v < mesh->vertex_count; ++v) /* `used` becomes the border vertices in use */
            border_count += used[v] = used[v] && topology->vertex_on_boundary[v];
        ok = border_count == 0 || grid_build(mesh, used, s.grid.cell, &border);
        for (int32_t v = 0; ok && v < mesh->vertex_count; ++v)
            used[v] = topology->vertex_halfedge[v] >= 0;
        ok = ok && fill_maps(&s, border_count ? &border : NULL, used, mean_edge, out);
    }
    grid_free(&border);
    free(f.matched), free(f.normals), free(f.distance), free(f.sorted), free((void *)f.samples), free(buffer);
    grid_free(&s.grid);
    free(used);
    if (!ok) {
        pz_symmetry_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetry: out of memory for %d vertices", (int)mesh->vertex_count);
    }
    if (mode == PZ_SYMMETRY_AUTO && !(out->residual_rel < tolerance)) {
        /* No plane good enough: the best one's plane and residual stay for the report, not its maps. */
        free(out->vertex_mirror), free(out->vertex_side), free(out->face_mirror);
        out->vertex_mirror = NULL, out->vertex_side = NULL, out->face_mirror = NULL;
        out->vertex_count = out->face_count = 0;
        out->axis = -1;
        return PZ_OK;
    }
    out->found = 1;
    return PZ_OK;
}

/* ---------------------------------------------------------------- mirrored paths */

/* The arm at mirrored vertex w closest to the reflection of arm `arm` at v. */
static int reflected_arm(const pz_symmetry *symmetry, const pz_trace_graph *graph, int32_t v, int arm, int32_t w)
{
    double direction[3];
    pz_trace_arm_direction(graph, v, arm, direction);
    pz_symmetry_reflect_direction(symmetry, direction, direction);
    return pz_trace_closest_arm(graph, w, direction);
}

pz_status pz_symmetry_mirror_path(const pz_symmetry *symmetry, const pz_trace_graph *graph, const pz_mesh *mesh,
                                  const pz_topology *topology, const pz_trace_path *path, pz_trace_path *out,
                                  pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    if (!symmetry->found || !symmetry->vertex_mirror)
        return pz_error(ctx, PZ_ERR_USAGE, "symmetry: no mirror plane to mirror a path through");
    size_t count = (size_t)path->vertex_count;
    int32_t *mapped = malloc((count + 1) * sizeof(int32_t));
    int32_t *origin = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t)); /* mirrored vertex -> path index */
    if (!mapped || !origin) {
        free(mapped), free(origin);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetry: out of memory mirroring a path of %d vertices", (int)count);
    }
    for (size_t i = 0; i < count; ++i) {
        mapped[i] = symmetry->vertex_mirror[path->vertices[i]];
        if (mapped[i] < 0) {
            int32_t v = path->vertices[i];
            free(mapped), free(origin);
            return pz_error(ctx, PZ_ERR_DATA, "symmetry: path vertex %d has no mirror image on the mesh", (int)v);
        }
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        origin[v] = -1;
    for (size_t i = 0; i < count; ++i)
        if (origin[mapped[i]] < 0)
            origin[mapped[i]] = (int32_t)i;
    pz_status status = pz_trace_path_through(graph, mesh, topology, mapped, (int32_t)count, path->closed, out, ctx);
    if (!status) {
        out->kind = path->kind;
        for (int32_t i = 0; i < out->vertex_count; ++i) {
            int32_t w = out->vertices[i], source = origin[w];
            if (source >= 0) /* a mirrored vertex, not one filling a gap */
                out->arms[i] = (uint8_t)reflected_arm(symmetry, graph, path->vertices[source], path->arms[source], w);
        }
    }
    free(mapped), free(origin);
    return status;
}
