/*
 * segment/symmetry.c -- the garment's mirror plane (pietroni2022 Sec. 4.2,
 * "Symmetry": the layout is built on one side and copied to the other).
 *
 * Detection: the candidate planes are x = c, y = c, z = c through the area
 * centroid c (garments are modelled upright and facing an axis, so an
 * axis-aligned plane is enough; a tilted scan would need a PCA frame first).
 * Every vertex is mirrored through the plane and matched to the nearest
 * vertex through a uniform grid (cells of max(2 mean edges, diagonal / 50),
 * rings searched outwards until no nearer vertex can exist). The search
 * gives up beyond 10 % of the bounding-box diagonal (a mirror image that far
 * from every vertex: no mirror, -1, counted at that distance in the
 * residual), which keeps far-off images of an asymmetric plane from scanning
 * the whole grid; any plane worth using has residuals orders of magnitude
 * smaller. The residual is the RMS of the matched distances. O(V) expected.
 *
 * Mirroring a path maps its vertices through vertex_mirror, closes gaps with
 * pz_trace_path_through, and gives every mirrored vertex the arm of its
 * cross closest to the reflected arm of the original.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SYMMETRY_DEFAULT_TOLERANCE_REL 0.005
#define SYMMETRY_SEARCH_LIMIT_REL 0.1    /* give up a nearest-vertex search beyond this times the diagonal */
#define SYMMETRY_SIDE_TOLERANCE_EDGES 0.5

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

/* ---------------------------------------------------------------- detection */

void pz_symmetry_clear(pz_symmetry *symmetry)
{
    if (!symmetry)
        return;
    free(symmetry->vertex_mirror), free(symmetry->vertex_side);
    memset(symmetry, 0, sizeof *symmetry);
    symmetry->axis = -1;
}

static void area_centroid(const pz_mesh *mesh, double centroid[3])
{
    double total = 0.0, sum[3] = {0, 0, 0};
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const double *a = mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f];
        const double *b = mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + 1];
        const double *c = mesh->positions + 3 * (size_t)mesh->faces[3 * (size_t)f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double area = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        total += area;
        for (int k = 0; k < 3; ++k)
            sum[k] += area * (a[k] + b[k] + c[k]) / 3.0;
    }
    for (int k = 0; k < 3; ++k)
        centroid[k] = total > 0.0 ? sum[k] / total : 0.0;
}

/* Mirrors every vertex in use through the plane normal to `axis` at `offset`; returns the residual RMS. */
static double mirror_plane(const pz_mesh *mesh, const vertex_grid *grid, const uint8_t *used, int axis,
                           double offset, double limit, int32_t *mirror)
{
    double sum = 0.0;
    int32_t count = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        mirror[v] = -1;
        if (!used[v])
            continue;
        double p[3] = {mesh->positions[3 * (size_t)v], mesh->positions[3 * (size_t)v + 1],
                       mesh->positions[3 * (size_t)v + 2]};
        p[axis] = 2.0 * offset - p[axis];
        double distance;
        mirror[v] = grid_nearest(grid, p, limit, &distance);
        if (mirror[v] < 0)
            distance = limit;
        sum += distance * distance;
        ++count;
    }
    return count ? sqrt(sum / count) : 0.0;
}

static void fill_sides(const pz_mesh *mesh, int axis, double offset, double tolerance, uint8_t *side)
{
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        double d = mesh->positions[3 * (size_t)v + axis] - offset;
        side[v] = fabs(d) <= tolerance ? 1 : d < 0.0 ? 0 : 2;
    }
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

/* Tries the axes first..last and keeps the smallest residual in *out (vertex_mirror filled). */
static int best_plane(const pz_mesh *mesh, const vertex_grid *grid, const uint8_t *used, int first, int last,
                      double diagonal, pz_symmetry *out)
{
    double centroid[3];
    area_centroid(mesh, centroid);
    int32_t *trial = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    out->vertex_mirror = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    if (!trial || !out->vertex_mirror) {
        free(trial);
        return 0;
    }
    out->residual_mm = INFINITY;
    for (int axis = first; axis <= last; ++axis) {
        double residual = mirror_plane(mesh, grid, used, axis, centroid[axis],
                                       SYMMETRY_SEARCH_LIMIT_REL * diagonal, trial);
        if (residual < out->residual_mm) {
            int32_t *swap = out->vertex_mirror;
            out->vertex_mirror = trial, trial = swap;
            out->residual_mm = residual, out->axis = axis, out->offset = centroid[axis];
        }
    }
    free(trial);
    out->residual_rel = diagonal > 0.0 ? out->residual_mm / diagonal : 0.0;
    out->normal[0] = out->normal[1] = out->normal[2] = 0.0;
    out->normal[out->axis] = 1.0;
    return 1;
}

pz_status pz_symmetry_detect(const pz_mesh *mesh, const pz_topology *topology, pz_symmetry_mode mode,
                             double tolerance_rel, pz_symmetry *out, pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    out->axis = -1;
    if (mode < PZ_SYMMETRY_AUTO || mode > PZ_SYMMETRY_Z || !(tolerance_rel >= 0.0))
        return pz_error(ctx, PZ_ERR_USAGE, "symmetry: bad mode %d or tolerance %g", (int)mode, tolerance_rel);
    if (mode == PZ_SYMMETRY_OFF || mesh->face_count == 0)
        return PZ_OK;
    double tolerance = tolerance_rel > 0.0 ? tolerance_rel : SYMMETRY_DEFAULT_TOLERANCE_REL, diagonal = 0.0;
    double mean_edge = pz_field_mean_edge_length(mesh, topology);
    vertex_grid grid;
    uint8_t *used = used_vertices(mesh, topology, &diagonal);
    int ok = used && grid_build(mesh, used, fmax(2.0 * mean_edge, diagonal / 50.0), &grid);
    int first = mode == PZ_SYMMETRY_AUTO ? 0 : (int)mode - PZ_SYMMETRY_X;
    int last = mode == PZ_SYMMETRY_AUTO ? 2 : first;
    ok = ok && best_plane(mesh, &grid, used, first, last, diagonal, out);
    grid_free(&grid);
    free(used);
    if (ok && (mode != PZ_SYMMETRY_AUTO || out->residual_rel < tolerance)) {
        out->found = 1;
        out->vertex_count = mesh->vertex_count;
        out->vertex_side = malloc((size_t)mesh->vertex_count + 1);
        ok = out->vertex_side != NULL;
        if (ok)
            fill_sides(mesh, out->axis, out->offset, SYMMETRY_SIDE_TOLERANCE_EDGES * mean_edge, out->vertex_side);
    } else if (ok) { /* AUTO, no plane good enough: keep the best residual for the report, nothing else */
        free(out->vertex_mirror);
        out->vertex_mirror = NULL;
        out->axis = -1;
    }
    if (!ok) {
        pz_symmetry_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "symmetry: out of memory for %d vertices", (int)mesh->vertex_count);
    }
    return PZ_OK;
}

/* ---------------------------------------------------------------- mirrored paths */

/* The arm at mirrored vertex w closest to the reflection of arm `arm` at v. */
static int reflected_arm(const pz_symmetry *symmetry, const pz_trace_graph *graph, int32_t v, int arm, int32_t w)
{
    double direction[3];
    pz_trace_arm_direction(graph, v, arm, direction);
    direction[symmetry->axis] = -direction[symmetry->axis];
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
