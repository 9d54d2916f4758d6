/*
 * prepare/weld.c -- step 1 of the preparation (prepare/prepare.c): vertices
 * closer than the weld distance join, and the edges that welding joined
 * become seams. Also the half-edges sorted by edge that the repair and the
 * corner search use.
 *
 * A uniform grid of cells 4x the weld distance hashed into an
 * open-addressing table; each vertex looks at the 1-8 cells its ball meets:
 * O(n) expected; union-find keeps the smallest index as the representative,
 * whose position and poses the cluster takes (all points in one cell would
 * be O(n^2)). An edge whose two faces did not share it before welding is a
 * welded seam: an existing seam of the export, kept as a constraint and
 * returned as a polyline (a sketch curve for the field stage).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Half-edges sorted by edge                                                 */
/* ------------------------------------------------------------------------ */

/*
 * Every half-edge with its undirected key, sorted by (lo, hi, half-edge):
 * equal edges are adjacent. A counting sort on lo (half-edges enter their
 * bucket in increasing order), then an insertion sort of each bucket on hi,
 * stable: O(F) for the few edges a vertex has, where qsort took 0.5 s of a
 * 1M-face preparation.
 */
prep_halfedge_key *prep_sorted_halfedges(const int32_t *faces, int32_t face_count)
{
    size_t count = 3 * (size_t)face_count;
    int32_t vertices = 0;
    for (size_t h = 0; h < count; ++h)
        vertices = faces[h] >= vertices ? faces[h] + 1 : vertices;
    prep_halfedge_key *keys = malloc(count * sizeof *keys + 1);
    size_t *start = calloc((size_t)vertices + 2, sizeof *start);
    if (!keys || !start) {
        free(keys);
        free(start);
        return NULL;
    }
    for (size_t h = 0; h < count; ++h) {
        int32_t a = faces[h], b = faces[pz_he_next((int32_t)h)];
        ++start[(a < b ? a : b) + 2];
    }
    for (int32_t v = 0; v < vertices; ++v)
        start[v + 2] += start[v + 1];
    for (size_t h = 0; h < count; ++h) {
        int32_t a = faces[h], b = faces[pz_he_next((int32_t)h)];
        keys[start[(a < b ? a : b) + 1]++] = (prep_halfedge_key){a < b ? a : b, a < b ? b : a, (int32_t)h, 0};
    }
    /* start[v] .. start[v + 1] now holds the bucket of v */
    for (int32_t v = 0; v < vertices; ++v)
        for (size_t i = start[v] + 1; i < start[v + 1]; ++i) {
            prep_halfedge_key key = keys[i];
            size_t j = i;
            for (; j > start[v] && keys[j - 1].hi > key.hi; --j)
                keys[j] = keys[j - 1];
            keys[j] = key;
        }
    free(start);
    return keys;
}

/* ------------------------------------------------------------------------ */
/* 1. Weld                                                                   */
/* ------------------------------------------------------------------------ */

/*
 * A uniform grid of cells WELD_CELL_FACTOR x the weld distance, hashed into an
 * open-addressing table of vertex lists. A slot keeps only the first vertex
 * of its cell: the cell is recomputed from that vertex's position when
 * probing, so the table is 4 bytes a slot (it was 28 with the cell stored:
 * 117 MB for a 1M-face scan, all of it touched at random).
 */
#define WELD_CELL_FACTOR 4.0
typedef struct weld_grid {
    double cell;
    size_t mask;            /* table size - 1 (a power of two) */
    int32_t *slot;          /* first vertex of the cell stored in each slot, -1 empty */
    int32_t *next;          /* next vertex in the same cell */
    const double *positions;
} weld_grid;

static size_t cell_hash(const int64_t cell[3])
{
    uint64_t h = (uint64_t)cell[0] * 0x9E3779B97F4A7C15ull ^ (uint64_t)cell[1] * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)cell[2] * 0x165667B19E3779F9ull;
    return (size_t)(h ^ (h >> 31));
}

static void cell_of(const weld_grid *grid, const double *p, int64_t cell[3])
{
    for (int k = 0; k < 3; ++k)
        cell[k] = (int64_t)floor(p[k] / grid->cell);
}

/* The slot holding `cell` or the empty slot where it would go (linear probing). */
static size_t find_slot(const weld_grid *grid, const int64_t cell[3])
{
    size_t s = cell_hash(cell) & grid->mask;
    while (grid->slot[s] >= 0) {
        int64_t other[3];
        cell_of(grid, grid->positions + 3 * (size_t)grid->slot[s], other);
        if (other[0] == cell[0] && other[1] == cell[1] && other[2] == cell[2])
            return s;
        s = (s + 1) & grid->mask;
    }
    return s;
}

/* Coordinates beyond this many cells from the origin are not welded (the cell index would overflow). */
#define WELD_MAX_CELL 4.0e15

static int weldable(const double *p, double cell)
{
    return prep_is_finite3(p) && fabs(p[0]) / cell < WELD_MAX_CELL && fabs(p[1]) / cell < WELD_MAX_CELL &&
           fabs(p[2]) / cell < WELD_MAX_CELL;
}

/* Joins v with the vertices already in `cell` that lie within sqrt(limit). */
static void join_in_cell(const weld_grid *grid, const int64_t cell[3], int32_t v, double limit, int32_t *parent)
{
    const double *p = grid->positions + 3 * (size_t)v;
    for (int32_t u = grid->slot[find_slot(grid, cell)]; u >= 0; u = grid->next[u]) {
        const double *q = grid->positions + 3 * (size_t)u;
        double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        if (dx * dx + dy * dy + dz * dz <= limit)
            pz_union_find_join(parent, u, v);
    }
}

/*
 * parent[v]: union-find of the vertices within `distance`. Vertices go in
 * index order, each joined with the earlier ones in the cells its ball meets
 * and then inserted. With cells of WELD_CELL_FACTOR x distance, the ball
 * crosses at most one face of its cell on each axis, and only when it is
 * that close to it: 1.5^3 = 3.4 cells on average (8 with cells of twice the
 * distance, which the ball always leaves on every axis).
 */
static pz_status weld_clusters(const pz_mesh *mesh, double distance, int32_t *parent, pz_ctx *ctx)
{
    int32_t n = mesh->vertex_count;
    weld_grid grid = {WELD_CELL_FACTOR * distance, 0, NULL, NULL, mesh->positions};
    size_t size = 64;
    while (size < 2 * (size_t)n)
        size *= 2;
    grid.mask = size - 1;
    grid.slot = malloc(size * sizeof(int32_t));
    grid.next = malloc((size_t)n * sizeof(int32_t) + 1);
    if (!grid.slot || !grid.next) {
        free(grid.slot);
        free(grid.next);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory welding %d vertices", (int)n);
    }
    memset(grid.slot, 0xff, size * sizeof(int32_t));
    double limit = distance * distance, reach = 1.01 * distance; /* reach: margin for the rounding of p / cell */
    for (int32_t v = 0; v < n; ++v) {
        const double *p = mesh->positions + 3 * (size_t)v;
        parent[v] = v;
        grid.next[v] = -1;
        if (!weldable(p, grid.cell))
            continue;
        int64_t cell[3], side[3], probe[3];
        for (int k = 0; k < 3; ++k) {
            double scaled = p[k] / grid.cell;
            cell[k] = (int64_t)floor(scaled);
            double offset = (scaled - (double)cell[k]) * grid.cell; /* from the cell's lower face */
            side[k] = offset < reach ? -1 : offset > grid.cell - reach ? 1 : 0;
        }
        for (int corner = 0; corner < 8; ++corner) {
            int skip = 0;
            for (int k = 0; k < 3; ++k) {
                int across = (corner >> k) & 1;
                skip |= across && side[k] == 0;
                probe[k] = cell[k] + across * side[k];
            }
            if (!skip)
                join_in_cell(&grid, probe, v, limit, parent);
        }
        size_t s = find_slot(&grid, cell);
        grid.next[v] = grid.slot[s];
        grid.slot[s] = v;
    }
    free(grid.slot);
    free(grid.next);
    return PZ_OK;
}

/*
 * Seams: a welded edge whose two faces used different vertex pairs before
 * welding (they were not twins). old_faces are the faces before renumbering.
 */
static pz_status find_welded_seams(const pz_mesh *mesh, const int32_t *old_faces, prep_edge_list *seams, pz_ctx *ctx)
{
    prep_halfedge_key *keys = prep_sorted_halfedges(mesh->faces, mesh->face_count);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding welded seams");
    size_t count = 3 * (size_t)mesh->face_count;
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = prep_group_end(keys, count, begin);
        if (end - begin != 2 || keys[begin].lo == keys[begin].hi)
            continue;
        int32_t h1 = keys[begin].halfedge, h2 = keys[begin + 1].halfedge;
        int twins = old_faces[h1] == old_faces[pz_he_next(h2)] && old_faces[pz_he_next(h1)] == old_faces[h2];
        if (!twins && !prep_edge_list_add(seams, keys[begin].lo, keys[begin].hi)) {
            free(keys);
            return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding welded seams");
        }
    }
    free(keys);
    return PZ_OK;
}

/* Merges the clusters into their representatives (in place: new index <= old). */
static void apply_weld(pz_mesh *mesh, int32_t *parent)
{
    int32_t n = mesh->vertex_count, kept = 0;
    int32_t *new_index = parent; /* reused: roots are visited before their members (root = smallest) */
    for (int32_t v = 0; v < n; ++v) {
        int32_t root = parent[v]; /* compressed by the caller: the root itself */
        if (root == v) {
            memmove(mesh->positions + 3 * (size_t)kept, mesh->positions + 3 * (size_t)v, 3 * sizeof(double));
            for (size_t p = 0; p < (size_t)mesh->pose_count; ++p)
                memmove(mesh->poses + (p * (size_t)n + (size_t)kept) * 3,
                        mesh->poses + (p * (size_t)n + (size_t)v) * 3, 3 * sizeof(double));
            new_index[v] = -1 - kept++; /* negative: marks a root's final index */
        } else {
            new_index[v] = new_index[root]; /* root < v already holds -1 - its index */
        }
    }
    /* Poses were compacted with stride n: close the gaps between them. */
    for (size_t p = 1; p < (size_t)mesh->pose_count; ++p)
        memmove(mesh->poses + p * (size_t)kept * 3, mesh->poses + p * (size_t)n * 3,
                (size_t)kept * 3 * sizeof(double));
    for (size_t c = 0; c < 3 * (size_t)mesh->face_count; ++c)
        mesh->faces[c] = -1 - new_index[mesh->faces[c]];
    mesh->vertex_count = kept;
}

pz_status prep_weld(pz_mesh *mesh, double distance, prep_edge_list *seams, int32_t *welded, pz_ctx *ctx)
{
    *welded = 0;
    int32_t n = mesh->vertex_count;
    int32_t *parent = malloc((size_t)n * sizeof(int32_t) + 1);
    int32_t *old_faces = malloc(3 * (size_t)mesh->face_count * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!parent || !old_faces)
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory welding %d vertices", (int)n);
    if (!status)
        status = weld_clusters(mesh, distance, parent, ctx);
    if (!status) {
        /* parent[u] <= u always (the smaller root wins), so one pass in index
         * order points every vertex straight at its root. */
        for (int32_t v = 0; v < n; ++v) {
            parent[v] = parent[parent[v]];
            *welded += parent[v] != v;
        }
        if (*welded) {
            memcpy(old_faces, mesh->faces, 3 * (size_t)mesh->face_count * sizeof(int32_t));
            apply_weld(mesh, parent);
            status = find_welded_seams(mesh, old_faces, seams, ctx);
        }
    }
    free(parent);
    free(old_faces);
    return status;
}
