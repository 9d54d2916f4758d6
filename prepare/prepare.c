/*
 * prepare/prepare.c -- scan-ready input (issue 8, docs/prepare.md): turns a scan
 * or an export (millions of faces, slivers, non-manifold vertices, fragments,
 * unwelded panels) into the manifold, well-shaped mesh the paper assumes
 * ("otherwise we uniformly remesh with standard tools").
 *
 * Steps, in order, on a copy of the input (which is in mm):
 *  1. weld: vertices closer than --weld join (a uniform grid of cells 4x
 *     the weld distance hashed into an open-addressing table; each vertex
 *     looks at the 1-8 cells its ball meets: O(n) expected; union-find keeps
 *     the smallest index as the representative, whose position and poses
 *     the cluster takes; all points in one cell would be O(n^2)). An edge
 *     whose two faces did not share it before welding is a welded seam: an
 *     existing seam of the export, kept as a constraint and returned as a
 *     polyline (a sketch curve for the field stage).
 *  2. repair: faces with a NaN/Inf corner are dropped; degenerate and
 *     duplicate faces dropped (pz_mesh_prepare); faces beyond the first two
 *     on an edge dropped; non-manifold vertices split, one copy per fan
 *     (corners joined across manifold edges by union-find); faces oriented
 *     consistently (pz_mesh_prepare); only the passes a first validation
 *     calls for run. Renumbering by pz_mesh_prepare is
 *     followed through a temporary extra pose holding each vertex's index
 *     (poses are compacted with the vertices), so seams survive it.
 *  3. fragments: components under 1% of the total area are dropped (--keep
 *     all keeps them). Nothing left is PZ_ERR_INVALID_MESH.
 *  4. decimate when the mesh has more than 4x the faces remeshing will
 *     produce: down to 2x, seams and outline locked, so remeshing works on
 *     a small mesh. Thinning (rounds of independent half-edge collapses,
 *     below) does the bulk in O(F) per round; CGAL edge collapse
 *     (prepare/cgal_shim.cpp) finishes only when thinning stalls.
 *  5. remesh (CGAL isotropic_remeshing, Botsch & Kobbelt 2004) to the target
 *     edge L; by default L gives ~20K faces: the equilateral edge
 *     F = A / (sqrt(3)/4 L^2)  =>  L = sqrt(4 A / (sqrt(3) F)), lengthened
 *     by sqrt(1.19) (CGAL's mean edge is shorter than its target), corrected
 *     by up to two more passes when the count misses by over 10%. Outline
 *     and seams constrained; their corners (turns measured at the scale of
 *     the edge) and crease vertices locked.
 *  6. poses: each output vertex is projected on the repaired rest mesh
 *     (AABB tree); its barycentric coordinates in that face place it in every
 *     other pose, so one connectivity serves all poses. Labels go the same
 *     way (closest face to each output face's centroid). UVs are dropped.
 *     One projection (one tree of the rest input) serves poses, labels and
 *     the rest pose's Hausdorff distance.
 *  7. hausdorff: symmetric sampled distance between the repaired input and
 *     the output (output vertices and centroids against the input, input
 *     vertices against the output), per pose, compared to 0.5% of the
 *     bounding-box diagonal; exceeding it is reported, not fatal.
 *
 * Automatic mode (pz_prepare_auto, `run --prepare auto`) runs 4-7 only for
 * a mesh over 10000 faces (remeshed to 10000; beyond the Hausdorff bound,
 * again at twice the faces up to 40000, then undone) or one with under 95%
 * of its faces well shaped (remeshed at its own density, undone when that
 * leaves the bound); see auto_decide, retry_denser and docs/prepare.md.
 *
 * Memory: a few arrays of 3F ints and the CGAL structures (~250 B/face for a
 * Surface_mesh, ~150 B/face for an AABB tree); for a 1M-face input the peak
 * is ~0.35 GB (2M faces: 0.8 GB), in the Hausdorff step (bench/bench_prepare.c). Failure: every
 * error leaves *out NULL and frees everything.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/prepare.h"

#include "prepare/cgal_shim.h"
#include "core/util.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_WELD_MM 0.01
#define DEFAULT_FACES 20000
#define DEFAULT_FRAGMENT_FRACTION 0.01
#define DEFAULT_ITERATIONS 5
#define HAUSDORFF_FRACTION 0.005
/* A target edge giving fewer faces than this is longer than the garment allows. */
#define MIN_EXPECTED_FACES 100
#define MAX_EXPECTED_FACES 10000000.0
/* Decimate first when the input has more than DECIMATE_ABOVE x the faces wanted, down to DECIMATE_TO x. */
#define DECIMATE_ABOVE 4
#define DECIMATE_TO 2
#define SQRT3 1.7320508075688772
/* Remesh a second time when the face count misses the one asked for by more than this fraction. */
#define REMESH_FACE_TOLERANCE 0.1
#define REMESH_CORRECTIONS 2
/*
 * CGAL splits edges over 4/3 L and collapses those under 4/5 L, so its edges
 * end up shorter than L on average: remeshing to the equilateral edge of N
 * faces gave 1.19 N (median over the 15 shared garments and surfaces at
 * 2000, 5000 and 20000 faces; 1.05-1.50). The first pass therefore aims at
 * an edge sqrt(1.19) longer, which lands within REMESH_FACE_TOLERANCE
 * mostly, and saves the corrected pass (half of the remeshing time).
 */
#define REMESH_EDGE_SHRINK 1.19
/* An outline vertex farther than this fraction of the Hausdorff bound from its chord at the remeshing scale is kept. */
#define OUTLINE_TOLERANCE 0.25

/* Undirected edges as vertex pairs: the welded seams of the working mesh. */
typedef struct edge_list {
    int32_t count;
    size_t capacity;
    int32_t *pairs;
} edge_list;

static int edge_list_add(edge_list *list, int32_t a, int32_t b)
{
    if (!pz_grow((void **)&list->pairs, &list->capacity, 2 * (size_t)list->count + 2, sizeof(int32_t)))
        return 0;
    list->pairs[2 * list->count] = a < b ? a : b;
    list->pairs[2 * list->count + 1] = a < b ? b : a;
    ++list->count;
    return 1;
}

typedef struct step_state {
    pz_ctx *ctx;
    const char *name;
    pz_prepare_report *report;
} step_state;

/* Records a step's outcome and notes it on stderr ("NAME: prepare: STEP: detail"). */
static void step_done(step_state *state, pz_prepare_step_id id, int ran, double started, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void step_done(step_state *state, pz_prepare_step_id id, int ran, double started, const char *fmt, ...)
{
    pz_prepare_step *step = &state->report->steps[id];
    va_list args;
    va_start(args, fmt);
    vsnprintf(step->detail, sizeof step->detail, fmt, args);
    va_end(args);
    step->ran = ran;
    step->seconds = pz_seconds() - started;
    pz_note(state->ctx, "%s: prepare: %s: %s (%.2f s)", state->name, step->name, step->detail, step->seconds);
}

/* ------------------------------------------------------------------------ */
/* Working on faces                                                          */
/* ------------------------------------------------------------------------ */


/* A half-edge keyed by its undirected edge, for sorting. */
typedef struct halfedge_key {
    int32_t lo, hi, halfedge, pad;
} halfedge_key;

/*
 * Every half-edge with its undirected key, sorted by (lo, hi, half-edge):
 * equal edges are adjacent. A counting sort on lo (half-edges enter their
 * bucket in increasing order), then an insertion sort of each bucket on hi,
 * stable: O(F) for the few edges a vertex has, where qsort took 0.5 s of a
 * 1M-face preparation.
 */
static halfedge_key *sorted_halfedges(const int32_t *faces, int32_t face_count)
{
    size_t count = 3 * (size_t)face_count;
    int32_t vertices = 0;
    for (size_t h = 0; h < count; ++h)
        vertices = faces[h] >= vertices ? faces[h] + 1 : vertices;
    halfedge_key *keys = malloc(count * sizeof *keys + 1);
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
        keys[start[(a < b ? a : b) + 1]++] = (halfedge_key){a < b ? a : b, a < b ? b : a, (int32_t)h, 0};
    }
    /* start[v] .. start[v + 1] now holds the bucket of v */
    for (int32_t v = 0; v < vertices; ++v)
        for (size_t i = start[v] + 1; i < start[v + 1]; ++i) {
            halfedge_key key = keys[i];
            size_t j = i;
            for (; j > start[v] && keys[j - 1].hi > key.hi; --j)
                keys[j] = keys[j - 1];
            keys[j] = key;
        }
    free(start);
    return keys;
}

static size_t group_end(const halfedge_key *keys, size_t count, size_t begin)
{
    size_t end = begin + 1;
    while (end < count && keys[end].lo == keys[begin].lo && keys[end].hi == keys[begin].hi)
        ++end;
    return end;
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

static int is_finite3(const double *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* Coordinates beyond this many cells from the origin are not welded (the cell index would overflow). */
#define WELD_MAX_CELL 4.0e15

static int weldable(const double *p, double cell)
{
    return is_finite3(p) && fabs(p[0]) / cell < WELD_MAX_CELL && fabs(p[1]) / cell < WELD_MAX_CELL &&
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
static pz_status find_welded_seams(const pz_mesh *mesh, const int32_t *old_faces, edge_list *seams, pz_ctx *ctx)
{
    halfedge_key *keys = sorted_halfedges(mesh->faces, mesh->face_count);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding welded seams");
    size_t count = 3 * (size_t)mesh->face_count;
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = group_end(keys, count, begin);
        if (end - begin != 2 || keys[begin].lo == keys[begin].hi)
            continue;
        int32_t h1 = keys[begin].halfedge, h2 = keys[begin + 1].halfedge;
        int twins = old_faces[h1] == old_faces[pz_he_next(h2)] && old_faces[pz_he_next(h1)] == old_faces[h2];
        if (!twins && !edge_list_add(seams, keys[begin].lo, keys[begin].hi)) {
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

static pz_status weld(pz_mesh *mesh, double distance, edge_list *seams, int32_t *welded, pz_ctx *ctx)
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

/* ------------------------------------------------------------------------ */
/* 2. Repair                                                                 */
/* ------------------------------------------------------------------------ */

/*
 * Runs pz_mesh_prepare quietly while following its vertex renumbering: a
 * temporary last pose holds each vertex's old index in x (poses are compacted
 * with the vertices), which then renumbers the seams. *validity gets
 * pz_mesh_prepare's own status (PZ_ERR_INVALID_MESH when problems remain).
 * renumbered (NULL: not wanted) gets the old -> new vertex table (-1:
 * dropped; malloc'd, the caller frees it).
 */
static pz_status prepare_tracked(pz_mesh *mesh, const char *name, unsigned flags, edge_list *seams,
                                 pz_status *validity, int32_t **renumbered, pz_ctx *ctx)
{
    int32_t old_count = mesh->vertex_count;
    double *ids = malloc(3 * (size_t)old_count * sizeof(double) + 1);
    int32_t *new_index = malloc((size_t)old_count * sizeof(int32_t) + 1);
    if (!ids || !new_index) {
        free(ids);
        free(new_index);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d vertices", (int)old_count);
    }
    for (int32_t v = 0; v < old_count; ++v) {
        ids[3 * v] = v;
        ids[3 * v + 1] = ids[3 * v + 2] = 0.0;
        new_index[v] = -1;
    }
    pz_status status = pz_mesh_add_pose(mesh, ids, ctx);
    free(ids);
    if (status) {
        free(new_index);
        return status;
    }
    int quiet = ctx->quiet;
    ctx->quiet = 1;
    *validity = pz_mesh_prepare(mesh, name, flags, ctx);
    ctx->quiet = quiet;
    const double *id_pose = mesh->poses + (size_t)(mesh->pose_count - 1) * mesh->vertex_count * 3;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        new_index[(int32_t)id_pose[3 * v]] = v;
    if (--mesh->pose_count == 0) {
        free(mesh->poses);
        mesh->poses = NULL;
    }
    int32_t kept = 0;
    for (int32_t e = 0; e < seams->count; ++e) {
        int32_t a = new_index[seams->pairs[2 * e]], b = new_index[seams->pairs[2 * e + 1]];
        if (a >= 0 && b >= 0) {
            seams->pairs[2 * kept] = a;
            seams->pairs[2 * kept + 1] = b;
            ++kept;
        }
    }
    seams->count = kept;
    if (renumbered)
        *renumbered = new_index;
    else
        free(new_index);
    return PZ_OK;
}

static int32_t drop_nonfinite_faces(pz_mesh *mesh, uint8_t *drop)
{
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        drop[f] = 0;
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            drop[f] |= !is_finite3(mesh->positions + 3 * (size_t)v);
            for (int32_t p = 0; p < mesh->pose_count; ++p)
                drop[f] |= !is_finite3(mesh->poses + ((size_t)p * mesh->vertex_count + v) * 3);
        }
    }
    return pz_mesh_drop_faces(mesh, drop);
}

/* Drops every face beyond the first two on an edge. */
static pz_status drop_nonmanifold_edge_faces(pz_mesh *mesh, uint8_t *drop, int32_t *dropped, pz_ctx *ctx)
{
    halfedge_key *keys = sorted_halfedges(mesh->faces, mesh->face_count);
    if (!keys)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory checking edges");
    memset(drop, 0, (size_t)mesh->face_count);
    size_t count = 3 * (size_t)mesh->face_count;
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = group_end(keys, count, begin);
        for (size_t i = begin + 2; i < end; ++i)
            drop[pz_he_face(keys[i].halfedge)] = 1;
    }
    free(keys);
    *dropped = pz_mesh_drop_faces(mesh, drop);
    return PZ_OK;
}

/* Marks seam half-edges (binary search of each half-edge in the sorted seam list). */
static int pair_compare(const void *pa, const void *pb)
{
    const int32_t *a = pa, *b = pb;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static void mark_seam_halfedges(const pz_mesh *mesh, edge_list *seams, uint8_t *is_seam)
{
    if (seams->count == 0) { /* qsort and bsearch may not take the NULL of an empty list */
        memset(is_seam, 0, 3 * (size_t)mesh->face_count);
        return;
    }
    qsort(seams->pairs, (size_t)seams->count, 2 * sizeof(int32_t), pair_compare);
    for (int32_t h = 0; h < 3 * mesh->face_count; ++h) {
        int32_t a = mesh->faces[h], b = mesh->faces[pz_he_next(h)];
        int32_t key[2] = {a < b ? a : b, a < b ? b : a};
        is_seam[h] = bsearch(key, seams->pairs, (size_t)seams->count, 2 * sizeof(int32_t), pair_compare) != NULL;
    }
}

/* Gives every fan of a vertex but the first its own copy (corners joined across two-face edges). */
static pz_status split_fans(pz_mesh *mesh, int32_t *corner_parent, int32_t *fan_vertex, int32_t *split,
                            pz_ctx *ctx)
{
    size_t corners = 3 * (size_t)mesh->face_count;
    halfedge_key *keys = sorted_halfedges(mesh->faces, mesh->face_count);
    uint8_t *taken = calloc((size_t)mesh->vertex_count + 1, 1);
    int32_t *source = malloc(corners * sizeof(int32_t) + 1);
    if (!keys || !taken || !source) {
        free(keys);
        free(taken);
        free(source);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory splitting vertices");
    }
    for (size_t c = 0; c < corners; ++c) {
        corner_parent[c] = (int32_t)c;
        fan_vertex[c] = -1;
    }
    for (size_t begin = 0, end; begin < corners; begin = end) {
        end = group_end(keys, corners, begin);
        if (end - begin != 2)
            continue;
        int32_t h1 = keys[begin].halfedge, h2 = keys[begin + 1].halfedge;
        int same_way = mesh->faces[h1] == mesh->faces[h2];
        pz_union_find_join(corner_parent, h1, same_way ? h2 : pz_he_next(h2));
        pz_union_find_join(corner_parent, pz_he_next(h1), same_way ? pz_he_next(h2) : h2);
    }
    free(keys);
    int32_t count = mesh->vertex_count;
    for (size_t c = 0; c < corners; ++c) {
        int32_t root = pz_union_find_root(corner_parent, (int32_t)c), v = mesh->faces[c];
        if (fan_vertex[root] < 0) {
            if (!taken[v]) {
                taken[v] = 1;
                fan_vertex[root] = v;
            } else {
                source[count - mesh->vertex_count] = v;
                fan_vertex[root] = count++;
            }
        }
        mesh->faces[c] = fan_vertex[root];
    }
    free(taken);
    *split = count - mesh->vertex_count;
    pz_status status = PZ_OK;
    if (*split) {
        int32_t n = mesh->vertex_count;
        double *positions = realloc(mesh->positions, 3 * (size_t)count * sizeof(double));
        double *poses = mesh->pose_count ? malloc((size_t)mesh->pose_count * count * 3 * sizeof(double)) : NULL;
        if (positions)
            mesh->positions = positions;
        if (!positions || (mesh->pose_count && !poses)) {
            free(poses);
            free(source);
            return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory splitting vertices");
        }
        for (int32_t i = 0; i < *split; ++i)
            memcpy(positions + 3 * (size_t)(n + i), positions + 3 * (size_t)source[i], 3 * sizeof(double));
        for (size_t p = 0; p < (size_t)mesh->pose_count; ++p) {
            memcpy(poses + p * count * 3, mesh->poses + p * n * 3, (size_t)n * 3 * sizeof(double));
            for (int32_t i = 0; i < *split; ++i)
                memcpy(poses + (p * count + n + i) * 3, mesh->poses + (p * n + source[i]) * 3, 3 * sizeof(double));
        }
        if (poses) {
            free(mesh->poses);
            mesh->poses = poses;
        }
        mesh->vertex_count = count;
    }
    free(source);
    return status;
}

/* Non-manifold edges then vertices; seams are carried by their half-edges. */
static pz_status make_manifold(pz_mesh *mesh, edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    size_t corners = 3 * (size_t)mesh->face_count;
    uint8_t *flags = malloc(corners + 1);
    int32_t *corner_parent = malloc(corners * sizeof(int32_t) + 1);
    int32_t *fan_vertex = malloc(corners * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!flags || !corner_parent || !fan_vertex)
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d faces", (int)mesh->face_count);
    if (!status)
        status = drop_nonmanifold_edge_faces(mesh, flags, &report->nonmanifold_edge_faces, ctx);
    if (!status) {
        mark_seam_halfedges(mesh, seams, flags);
        status = split_fans(mesh, corner_parent, fan_vertex, &report->split_vertices, ctx);
    }
    if (!status) {
        seams->count = 0;
        for (int32_t h = 0; h < 3 * mesh->face_count && !status; ++h)
            if (flags[h] && mesh->faces[h] < mesh->faces[pz_he_next(h)] &&
                !edge_list_add(seams, mesh->faces[h], mesh->faces[pz_he_next(h)]))
                status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory keeping seams");
    }
    free(flags);
    free(corner_parent);
    free(fan_vertex);
    return status;
}

/* Orients the faces consistently, counting the flips (pz_mesh_prepare swaps corners 1 and 2 of the minority). */
static pz_status orient(pz_mesh *mesh, const char *name, edge_list *seams, pz_prepare_report *report,
                        pz_status *validity, pz_ctx *ctx)
{
    int32_t *old_second = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    if (!old_second)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory orienting faces");
    for (int32_t f = 0; f < mesh->face_count; ++f)
        old_second[f] = mesh->faces[3 * f + 1];
    int32_t faces = mesh->face_count, *new_index = NULL;
    /* it also drops the vertices earlier passes stranded (a fin's tip), renumbering the rest */
    pz_status status = prepare_tracked(mesh, name, PZ_REPAIR_ORIENT, seams, validity, &new_index, ctx);
    report->flipped_faces = 0;
    if (!status && mesh->face_count == faces)
        for (int32_t f = 0; f < faces; ++f)
            report->flipped_faces += mesh->faces[3 * f + 1] != new_index[old_second[f]];
    free(old_second);
    free(new_index);
    return status;
}

/*
 * Runs only the repairs a first validation calls for: a clean 1M-face scan
 * costs that one validation (0.09 s) instead of every pass (0.7 s).
 * Dropping faces can split a vertex's fan, and dropping the third face of
 * an edge can leave the other two disagreeing, so after either the later
 * checks run regardless.
 */
static pz_status repair(pz_mesh *mesh, const char *name, edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    uint8_t *drop = malloc((size_t)mesh->face_count + 1);
    if (!drop)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory repairing %d faces", (int)mesh->face_count);
    report->nonfinite_faces = drop_nonfinite_faces(mesh, drop);
    free(drop);
    pz_validation found;
    pz_status status = pz_mesh_validate(mesh, &found, ctx), validity = PZ_OK;
    if (status)
        return status;
    int dropping = found.bad_indices || found.degenerate_faces || found.duplicate_faces;
    int splitting = dropping || found.nonmanifold_edges || found.nonmanifold_vertices;
    int orienting = splitting || found.inconsistent_edges;
    int32_t faces_before = mesh->face_count, degenerate = found.degenerate_faces;
    unsigned flags = dropping ? PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES : 0;
    if (dropping || found.unreferenced_vertices || report->nonfinite_faces)
        status = prepare_tracked(mesh, name, flags, seams, &validity, NULL, ctx); /* also drops unused vertices */
    pz_validation_clear(&found);
    int32_t dropped = faces_before - mesh->face_count;
    report->degenerate_faces = degenerate < dropped ? degenerate : dropped;
    report->duplicate_faces = dropped - report->degenerate_faces;
    if (!status && splitting && mesh->face_count > 0)
        status = make_manifold(mesh, seams, report, ctx);
    if (!status && orienting && mesh->face_count > 0) {
        status = orient(mesh, name, seams, report, &validity, ctx);
        if (!status && validity != PZ_OK)
            status = validity; /* still invalid (not orientable): pz_mesh_prepare's message names the problem */
    }
    return status;
}

/* ------------------------------------------------------------------------ */
/* 3. Fragments                                                              */
/* ------------------------------------------------------------------------ */

static pz_status drop_fragments(pz_mesh *mesh, const char *name, double fraction, pz_prepare_keep keep,
                                edge_list *seams, pz_prepare_report *report, pz_ctx *ctx)
{
    int32_t *component = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    double *face_area = malloc((size_t)mesh->face_count * sizeof(double) + 1);
    double *area = NULL;
    uint8_t *drop = NULL;
    pz_status status = PZ_OK;
    if (!component || !face_area) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding components");
        goto done;
    }
    int32_t count = pz_mesh_face_components(mesh, component, ctx);
    if (count < 0) {
        status = (pz_status)count;
        goto done;
    }
    report->components = count;
    area = calloc((size_t)count + 1, sizeof(double));
    drop = malloc((size_t)mesh->face_count + 1);
    if (!area || !drop) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding components");
        goto done;
    }
    pz_geom_face_areas(mesh, face_area);
    double total = 0.0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        area[component[f]] += face_area[f];
        total += face_area[f];
    }
    int32_t largest = 0;
    for (int32_t c = 1; c < count; ++c)
        if (area[c] > area[largest])
            largest = c;
    if (keep == PZ_PREPARE_KEEP_ALL || count <= 1)
        goto done;
    for (int32_t c = 0; c < count; ++c)
        if (c != largest && area[c] < fraction * total)
            ++report->dropped_components;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        drop[f] = component[f] != largest && area[component[f]] < fraction * total;
    if (report->dropped_components) {
        report->dropped_component_faces = pz_mesh_drop_faces(mesh, drop);
        pz_status validity = PZ_OK;
        status = prepare_tracked(mesh, name, 0, seams, &validity, NULL, ctx); /* drops the stranded vertices */
    }
done:
    free(component);
    free(face_area);
    free(area);
    free(drop);
    return status;
}

/* ------------------------------------------------------------------------ */
/* 4-5. Decimation and remeshing                                             */
/* ------------------------------------------------------------------------ */

static pz_cgal_surface surface_view(const pz_mesh *mesh, const edge_list *seams)
{
    pz_cgal_surface view = {mesh->vertex_count, mesh->face_count, seams->count, mesh->positions, mesh->faces,
                            seams->pairs, 0, NULL};
    return view;
}

/*
 * Thinning: the bulk of the decimation, cheaply. CGAL's edge collapse
 * re-evaluates every edge of the kept vertex's 2-ring after each collapse
 * (~10-20 us a collapse here: 9-20 s for a 1M-face scan), although on a
 * dense scan nearly every collapse is trivial. Thinning runs rounds of half-edge
 * collapses instead: a vertex merges into a neighbour, which keeps its
 * position (every vertex left is an input vertex, so the surface moves by
 * no more than the sagitta of the new edges). The collapses of one round
 * are far enough apart to be checked against the mesh as it was when the
 * round began (a vertex -> faces table built once per round):
 *
 *   collapse c -> d after a -> b needs c outside N[a] and N[b] (it would
 *   rewrite faces a -> b read) and c, d outside N[a] (a -> b rewrote faces
 *   around a, which c -> d would read),
 *
 * with N[v] = v and its neighbours. Checks for a -> b: a is interior (not on
 * the outline or a seam, which therefore keep every vertex and edge); the
 * link condition (the only common neighbours of a and b are the two
 * opposite the edge, and not both of valence 3: a tetrahedron); no face
 * around a turns by more than acos(THIN_MIN_COS) = 45 degrees (75 let a
 * noisy scan drift over the Hausdorff bound: rounds compound small turns); no
 * new edge longer than the limit (the remeshing edge, so remeshing then only
 * splits a little).
 * Among a's neighbours, b is the one giving the shortest longest new edge.
 * Rounds (vertices in index order: deterministic) go on until the face
 * count is reached or a round removes under THIN_MIN_GAIN of the faces.
 */
#define THIN_MAX_VALENCE 32
#define THIN_MIN_COS 0.7
#define THIN_MIN_GAIN 0.005

typedef struct thin_state {
    int32_t vertex_count;
    int32_t face_total, face_count;   /* faces in the arrays; still alive */
    const double *positions;          /* borrowed */
    int32_t *faces;                   /* dead faces have faces[3f] = -1 until the round ends */
    int32_t *offset, *incident;       /* vertex -> faces, rebuilt every round */
    uint8_t *locked;                  /* outline and seam vertices: never removed */
    int32_t *no_remove, *no_end;      /* round number: may not be removed / be an end of a collapse */
    int32_t round;
} thin_state;

typedef struct thin_ring {
    int32_t count, vertex[THIN_MAX_VALENCE];
} thin_ring;

static void thin_index(thin_state *s)
{
    memset(s->offset, 0, ((size_t)s->vertex_count + 1) * sizeof(int32_t));
    for (int32_t c = 0; c < 3 * s->face_total; ++c)
        ++s->offset[s->faces[c] + 1];
    for (int32_t v = 0; v < s->vertex_count; ++v)
        s->offset[v + 1] += s->offset[v];
    for (int32_t c = 0; c < 3 * s->face_total; ++c)
        s->incident[s->offset[s->faces[c]]++] = c / 3;
    for (int32_t v = s->vertex_count; v > 0; --v) /* the fill moved every start one list on */
        s->offset[v] = s->offset[v - 1];
    s->offset[0] = 0;
}

static int ring_has(const thin_ring *ring, int32_t v)
{
    for (int32_t i = 0; i < ring->count; ++i)
        if (ring->vertex[i] == v)
            return 1;
    return 0;
}

/* v's neighbours through its live faces; 0 when there are more than THIN_MAX_VALENCE. */
static int thin_neighbours(const thin_state *s, int32_t v, thin_ring *ring)
{
    ring->count = 0;
    for (int32_t i = s->offset[v]; i < s->offset[v + 1]; ++i) {
        const int32_t *c = s->faces + 3 * (size_t)s->incident[i];
        for (int k = 0; k < 3 && c[0] >= 0; ++k)
            if (c[k] != v && !ring_has(ring, c[k])) {
                if (ring->count == THIN_MAX_VALENCE)
                    return 0;
                ring->vertex[ring->count++] = c[k];
            }
    }
    return 1;
}

/* Locks the vertices on the outline (an edge with one face) or too crowded to look at. */
static void thin_lock_outline(thin_state *s)
{
    for (int32_t v = 0; v < s->vertex_count; ++v) {
        int32_t seen[2 * THIN_MAX_VALENCE], times[2 * THIN_MAX_VALENCE], count = 0, open = 0;
        for (int32_t i = s->offset[v]; i < s->offset[v + 1] && !s->locked[v]; ++i) {
            const int32_t *c = s->faces + 3 * (size_t)s->incident[i];
            for (int k = 0; k < 3; ++k) {
                if (c[k] == v)
                    continue;
                int32_t j = 0;
                while (j < count && seen[j] != c[k])
                    ++j;
                if (j == count) {
                    if (count == 2 * THIN_MAX_VALENCE) {
                        s->locked[v] = 1;
                        break;
                    }
                    seen[count] = c[k];
                    times[count++] = 0;
                }
                ++times[j];
            }
        }
        for (int32_t j = 0; j < count; ++j)
            open += times[j] != 2;
        if (open || count == 0)
            s->locked[v] = 1;
    }
}

static void face_normal(const double *a, const double *b, const double *c, double n[3])
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

static double squared_distance3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

/* Whether a -> b keeps the surface manifold and unfolded (a's ring given; b's gathered here). */
static int thin_valid(const thin_state *s, int32_t a, int32_t b, const thin_ring *ring_a, thin_ring *ring_b)
{
    int32_t shared = 0, opposite[2] = {-1, -1};
    for (int32_t i = s->offset[a]; i < s->offset[a + 1]; ++i) {
        const int32_t *c = s->faces + 3 * (size_t)s->incident[i];
        if (c[0] >= 0 && (c[0] == b || c[1] == b || c[2] == b)) {
            if (shared == 2)
                return 0;
            opposite[shared++] = (int32_t)((int64_t)c[0] + c[1] + c[2] - a - b);
        }
    }
    if (shared != 2 || !thin_neighbours(s, b, ring_b) || (ring_a->count == 3 && ring_b->count == 3))
        return 0;
    for (int32_t i = 0; i < ring_b->count; ++i) {
        int32_t v = ring_b->vertex[i];
        if (v != a && v != opposite[0] && v != opposite[1] && ring_has(ring_a, v))
            return 0; /* the link condition */
    }
    for (int32_t i = s->offset[a]; i < s->offset[a + 1]; ++i) {
        const int32_t *c = s->faces + 3 * (size_t)s->incident[i];
        if (c[0] < 0 || c[0] == b || c[1] == b || c[2] == b)
            continue;
        const double *p[3], *q[3];
        for (int k = 0; k < 3; ++k) {
            p[k] = s->positions + 3 * (size_t)c[k];
            q[k] = c[k] == a ? s->positions + 3 * (size_t)b : p[k];
        }
        double before[3], after[3];
        face_normal(p[0], p[1], p[2], before);
        face_normal(q[0], q[1], q[2], after);
        double dot = before[0] * after[0] + before[1] * after[1] + before[2] * after[2];
        double lengths = sqrt((before[0] * before[0] + before[1] * before[1] + before[2] * before[2]) *
                              (after[0] * after[0] + after[1] * after[1] + after[2] * after[2]));
        if (!(dot > THIN_MIN_COS * lengths))
            return 0;
    }
    return 1;
}

static void thin_collapse(thin_state *s, int32_t a, int32_t b, const thin_ring *ring_a, const thin_ring *ring_b)
{
    for (int32_t i = s->offset[a]; i < s->offset[a + 1]; ++i) {
        int32_t *c = s->faces + 3 * (size_t)s->incident[i];
        if (c[0] == b || c[1] == b || c[2] == b) {
            c[0] = -1;
            --s->face_count;
        } else {
            for (int k = 0; k < 3; ++k)
                if (c[k] == a)
                    c[k] = b;
        }
    }
    s->no_remove[a] = s->no_end[a] = s->no_remove[b] = s->round;
    for (int32_t i = 0; i < ring_a->count; ++i)
        s->no_remove[ring_a->vertex[i]] = s->no_end[ring_a->vertex[i]] = s->round;
    for (int32_t i = 0; i < ring_b->count; ++i)
        s->no_remove[ring_b->vertex[i]] = s->round;
}

/* Removes a if it can go: into the neighbour whose longest new edge is shortest and within the limit. */
static int thin_vertex(thin_state *s, int32_t a, double limit_squared)
{
    thin_ring ring_a, ring_b;
    if (s->locked[a] || s->no_remove[a] == s->round || s->no_end[a] == s->round || !thin_neighbours(s, a, &ring_a))
        return 0;
    double longest[THIN_MAX_VALENCE];
    for (int32_t i = 0; i < ring_a.count; ++i) {
        const double *p = s->positions + 3 * (size_t)ring_a.vertex[i];
        longest[i] = s->no_end[ring_a.vertex[i]] == s->round ? INFINITY : 0.0;
        for (int32_t j = 0; j < ring_a.count && longest[i] <= limit_squared; ++j)
            longest[i] = fmax(longest[i], squared_distance3(p, s->positions + 3 * (size_t)ring_a.vertex[j]));
    }
    for (;;) {
        int32_t best = -1;
        for (int32_t i = 0; i < ring_a.count; ++i)
            if (longest[i] <= limit_squared && (best < 0 || longest[i] < longest[best]))
                best = i;
        if (best < 0)
            return 0;
        longest[best] = INFINITY; /* tried */
        int32_t b = ring_a.vertex[best];
        if (thin_valid(s, a, b, &ring_a, &ring_b)) {
            thin_collapse(s, a, b, &ring_a, &ring_b);
            return 1;
        }
    }
}

/* Drops the faces the round killed (in place, order kept) and re-indexes. */
static void thin_end_round(thin_state *s)
{
    int32_t live = 0;
    for (int32_t f = 0; f < s->face_total; ++f)
        if (s->faces[3 * f] >= 0)
            memmove(s->faces + 3 * (size_t)live++, s->faces + 3 * (size_t)f, 3 * sizeof(int32_t));
    s->face_total = live;
    thin_index(s);
}

/* *out: the vertices still used and the live faces of s, seams renumbered. */
static pz_status thin_export(const thin_state *s, const pz_cgal_surface *in, pz_cgal_surface *out, pz_ctx *ctx)
{
    int32_t *new_index = malloc((size_t)s->vertex_count * sizeof(int32_t) + 1);
    if (!new_index)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory thinning");
    int32_t kept = 0;
    for (int32_t v = 0; v < s->vertex_count; ++v)
        new_index[v] = s->offset[v + 1] > s->offset[v] ? kept++ : -1;
    out->vertex_count = kept;
    out->face_count = s->face_total;
    out->positions = malloc(3 * (size_t)kept * sizeof(double) + 1);
    out->faces = malloc(3 * (size_t)s->face_total * sizeof(int32_t) + 1);
    out->edges = malloc(2 * (size_t)in->edge_count * sizeof(int32_t) + 1);
    if (!out->positions || !out->faces || !out->edges) {
        free(new_index);
        pz_cgal_surface_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory thinning");
    }
    for (int32_t v = 0; v < s->vertex_count; ++v)
        if (new_index[v] >= 0)
            memcpy(out->positions + 3 * (size_t)new_index[v], s->positions + 3 * (size_t)v, 3 * sizeof(double));
    for (size_t c = 0; c < 3 * (size_t)s->face_total; ++c)
        out->faces[c] = new_index[s->faces[c]];
    for (int32_t e = 0; e < 2 * in->edge_count; e += 2) /* seam vertices are locked: always still used */
        if (new_index[in->edges[e]] >= 0 && new_index[in->edges[e + 1]] >= 0) {
            out->edges[2 * out->edge_count] = new_index[in->edges[e]];
            out->edges[2 * out->edge_count++ + 1] = new_index[in->edges[e + 1]];
        }
    free(new_index);
    return PZ_OK;
}

/*
 * Thins `in` (manifold, oriented) towards target_faces, no new edge longer
 * than max_edge; *out gets the result (malloc'd, seams renumbered).
 */
static pz_status thin_out(const pz_cgal_surface *in, int32_t target_faces, double max_edge, pz_cgal_surface *out,
                          pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    int32_t n = in->vertex_count;
    size_t corners = 3 * (size_t)in->face_count;
    thin_state s = {n, in->face_count, in->face_count, in->positions, malloc(corners * sizeof(int32_t) + 1),
                    malloc(((size_t)n + 1) * sizeof(int32_t)), malloc(corners * sizeof(int32_t) + 1),
                    calloc((size_t)n + 1, 1), calloc((size_t)n + 1, sizeof(int32_t)),
                    calloc((size_t)n + 1, sizeof(int32_t)), 0};
    pz_status status = PZ_OK;
    if (!s.faces || !s.offset || !s.incident || !s.locked || !s.no_remove || !s.no_end)
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory thinning %d faces", (int)in->face_count);
    if (!status) {
        memcpy(s.faces, in->faces, corners * sizeof(int32_t));
        thin_index(&s);
        thin_lock_outline(&s);
        for (int32_t e = 0; e < 2 * in->edge_count; ++e)
            s.locked[in->edges[e]] = 1;
        double limit = max_edge * max_edge;
        while (s.face_count > target_faces) {
            int32_t before = s.face_count;
            ++s.round;
            for (int32_t v = 0; v < n && s.face_count > target_faces; ++v)
                thin_vertex(&s, v, limit);
            thin_end_round(&s);
            if (before - s.face_count < THIN_MIN_GAIN * before)
                break;
        }
        status = thin_export(&s, in, out, ctx);
    }
    free(s.faces);
    free(s.offset);
    free(s.incident);
    free(s.locked);
    free(s.no_remove);
    free(s.no_end);
    return status;
}

/* Counts one line edge a-b at both ends; the first two neighbours of each vertex are kept. */
static void add_line_end(int32_t *degree, int32_t *neighbour, int32_t a, int32_t b)
{
    if (degree[a] < 0) /* on a crease: locked anyway */
        return;
    if (degree[a] < 2)
        neighbour[2 * a + degree[a]] = b;
    ++degree[a];
}

static void add_line_edge(int32_t *degree, int32_t *neighbour, int32_t a, int32_t b)
{
    add_line_end(degree, neighbour, a, b);
    add_line_end(degree, neighbour, b, a);
}

/* Cosine of the angle between the normals of the faces of half-edges g and h. */
static double normal_cos(const pz_cgal_surface *surface, int32_t g, int32_t h)
{
    double n[2][3];
    int32_t faces[2] = {pz_he_face(g), pz_he_face(h)};
    for (int i = 0; i < 2; ++i) {
        const int32_t *c = surface->faces + 3 * (size_t)faces[i];
        face_normal(surface->positions + 3 * (size_t)c[0], surface->positions + 3 * (size_t)c[1],
                    surface->positions + 3 * (size_t)c[2], n[i]);
    }
    double dot = n[0][0] * n[1][0] + n[0][1] * n[1][1] + n[0][2] * n[1][2];
    double lengths = sqrt((n[0][0] * n[0][0] + n[0][1] * n[0][1] + n[0][2] * n[0][2]) *
                          (n[1][0] * n[1][0] + n[1][1] * n[1][1] + n[1][2] * n[1][2]));
    return lengths > 0.0 ? dot / lengths : 1.0;
}

/* The next vertex along a line after `at`, coming from `previous` (at has degree 2). */
static int32_t line_next(const int32_t *neighbour, int32_t previous, int32_t at)
{
    return neighbour[2 * at] == previous ? neighbour[2 * at + 1] : neighbour[2 * at];
}

/*
 * The shape of a line at v (degree 2) at the scale of the remeshing: the
 * cosine of its turn between the points `reach` away along the line on
 * either side (or its ends), and v's distance from the chord between those
 * two points. A jagged line (a seam following mesh edges, a noisy outline)
 * turns at every vertex, but not at the scale of the remeshing; the chord
 * distance is what removing v (and its neighbours within reach) would move
 * the line by.
 */
static void line_shape(const pz_cgal_surface *s, const int32_t *degree, const int32_t *neighbour, int32_t v,
                       double reach, double *cosine, double *deviation)
{
    const double *p = s->positions + 3 * (size_t)v;
    const double *ends[2];
    for (int side = 0; side < 2; ++side) {
        int32_t previous = v, at = neighbour[2 * v + side];
        for (int32_t steps = 0; steps < s->vertex_count && at != v && degree[at] == 2 &&
                                squared_distance3(p, s->positions + 3 * (size_t)at) < reach * reach;
             ++steps) {
            int32_t next = line_next(neighbour, previous, at);
            previous = at;
            at = next;
        }
        ends[side] = s->positions + 3 * (size_t)at;
    }
    double in[3], out[3], chord[3], dot = 0.0, in_length = 0.0, out_length = 0.0, chord_length = 0.0, along = 0.0;
    for (int k = 0; k < 3; ++k) {
        in[k] = p[k] - ends[0][k];
        out[k] = ends[1][k] - p[k];
        chord[k] = ends[1][k] - ends[0][k];
        dot += in[k] * out[k];
        in_length += in[k] * in[k];
        out_length += out[k] * out[k];
        chord_length += chord[k] * chord[k];
        along += in[k] * chord[k];
    }
    double lengths = sqrt(in_length * out_length);
    *cosine = lengths > 0.0 ? dot / lengths : 1.0;
    double t = chord_length > 0.0 ? fmin(1.0, fmax(0.0, along / chord_length)) : 0.0;
    *deviation = 0.0;
    for (int k = 0; k < 3; ++k)
        *deviation += (in[k] - t * chord[k]) * (in[k] - t * chord[k]);
    *deviation = sqrt(*deviation);
}

/* Whether v ranks first (lowest `rank`) among the line vertices closer than `reach` (the lower index on a tie). */
static int sharpest_around(const pz_cgal_surface *s, const int32_t *degree, const int32_t *neighbour,
                           const double *rank, int32_t v, double reach)
{
    const double *p = s->positions + 3 * (size_t)v;
    for (int side = 0; side < 2; ++side) {
        int32_t previous = v, at = neighbour[2 * v + side];
        for (int32_t steps = 0; steps < s->vertex_count && at != v && degree[at] == 2 &&
                                squared_distance3(p, s->positions + 3 * (size_t)at) < reach * reach;
             ++steps) {
            if (rank[at] < rank[v] || (rank[at] == rank[v] && at < v))
                return 0;
            int32_t next = line_next(neighbour, previous, at);
            previous = at;
            at = next;
        }
    }
    return 1;
}

/* Joins the two ends of a crease edge in the union-find `crease` (-1: not on a crease). */
static void join_crease(int32_t *crease, int32_t a, int32_t b)
{
    if (crease[a] < 0)
        crease[a] = a;
    if (crease[b] < 0)
        crease[b] = b;
    pz_union_find_join(crease, a, b);
}

/*
 * Marks (degree -1) the vertices of every connected set of crease edges,
 * except a set that touches the outline or a seam (on_line) and spans less
 * than `edge` (its bounding-box diagonal). Thinning keeps every line vertex,
 * so a strip of the input's fine faces stays beside the lines, and on a
 * scan such a fold is noise: with +-0.4 mm noise, 1.2 mm edges fold by over
 * CREASE_DEGREES here and there, and locking them kept that strip (a
 * 1M-face unwelded bodice to 20000 faces: 95.8% well shaped, 676 of the 833
 * bad faces on the seam; 99.7% without them). Small folds away from the
 * lines are kept: ignoring them too smoothed the shared face scan's
 * features away (10000 faces: 2.66 mm from the input instead of 1.48).
 */
static void lock_long_creases(const pz_cgal_surface *surface, int32_t *crease, const uint8_t *on_line, double edge,
                              int32_t *degree)
{
    int32_t n = surface->vertex_count;
    double *box = malloc(6 * (size_t)n * sizeof(double) + 1); /* per root: lo xyz, hi xyz */
    uint8_t *touches = calloc((size_t)n + 1, 1);              /* per root: a vertex of the set is on a line */
    for (int32_t v = 0; v < n; ++v)
        if (crease[v] >= 0)
            crease[v] = pz_union_find_root(crease, v);
    for (int32_t v = 0; touches && v < n; ++v)
        if (crease[v] >= 0 && on_line[v])
            touches[crease[v]] = 1;
    for (int32_t v = 0; box && v < n; ++v)
        if (crease[v] == v)
            for (int k = 0; k < 3; ++k)
                box[6 * (size_t)v + k] = box[6 * (size_t)v + 3 + k] = surface->positions[3 * (size_t)v + k];
    for (int32_t v = 0; box && v < n; ++v)
        for (int k = 0; k < 3 && crease[v] >= 0; ++k) {
            double *root = box + 6 * (size_t)crease[v], x = surface->positions[3 * (size_t)v + k];
            root[k] = fmin(root[k], x);
            root[3 + k] = fmax(root[3 + k], x);
        }
    for (int32_t v = 0; v < n; ++v) {
        if (crease[v] < 0)
            continue;
        const double *root = box ? box + 6 * (size_t)crease[v] : NULL;
        /* out of memory for the boxes: every crease is kept, the safe side */
        if (!root || !touches || !touches[crease[v]] || squared_distance3(root, root + 3) >= edge * edge)
            degree[v] = -1;
    }
    free(box);
    free(touches);
}

/*
 * Vertices remeshing must keep. Corners of the lines it keeps (outline and
 * seams): ends, junctions (a seam meeting the outline or another seam), and
 * turns sharper than CORNER_DEGREES; collapsing one would cut the corner
 * off the garment. Turns are measured at the scale of half the remeshing
 * edge, and only one vertex per reach is locked (the sharpest): a line that
 * is jagged at the input's scale (a seam following mesh edges, a scanned
 * hem with noise) turns at every vertex, and locking all of them keeps its
 * tiny edges and slivers beside them (a 1M-face bodice with +-0.4 mm noise,
 * every outline turn locked: 97.0% of the faces well shaped, every bad one
 * on the outline). On the outline a vertex is also kept when it lies more
 * than `tolerance` from the chord between the points half an edge away (a
 * tight curve of the hem, which a turn at that scale can miss: remeshing
 * cut 7 mm off the side of a noisy bodice's hem, bound 3.7 mm), and the one
 * kept within a reach is the farthest from its chord, so the outline
 * remeshing leaves stays near the input's. And the vertices of creases
 * (faces folding by more than CREASE_DEGREES: a collar fold, a pressed
 * pleat) whose connected crease edges span at least an edge L
 * (lock_long_creases): tangential relaxation would round them off, by up to
 * half an edge.
 */
#define CORNER_DEGREES 30.0
#define CREASE_DEGREES 60.0
static pz_status find_corners(pz_cgal_surface *surface, double edge, double tolerance, pz_ctx *ctx)
{
    int32_t n = surface->vertex_count;
    int32_t *degree = calloc((size_t)n + 1, sizeof(int32_t));
    int32_t *neighbour = malloc(2 * (size_t)n * sizeof(int32_t) + 1);
    double *rank = malloc((size_t)n * sizeof(double) + 1);
    uint8_t *on_outline = calloc((size_t)n + 1, 1), *on_line = malloc((size_t)n + 1),
            *candidate = calloc((size_t)n + 1, 1);
    int32_t *crease = malloc((size_t)n * sizeof(int32_t) + 1);
    halfedge_key *keys = sorted_halfedges(surface->faces, surface->face_count);
    surface->locked = malloc((size_t)n * sizeof(int32_t) + 1);
    surface->locked_count = 0;
    pz_status status = PZ_OK;
    if (crease)
        memset(crease, 0xff, (size_t)n * sizeof(int32_t));
    if (!degree || !neighbour || !rank || !on_outline || !on_line || !candidate || !crease || !keys ||
        !surface->locked) {
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory finding corners");
        goto done;
    }
    size_t count = 3 * (size_t)surface->face_count;
    double crease_cos = cos(CREASE_DEGREES * 3.14159265358979323846 / 180.0);
    for (size_t begin = 0, end; begin < count; begin = end) {
        end = group_end(keys, count, begin);
        if (end == begin + 1) {
            add_line_edge(degree, neighbour, keys[begin].lo, keys[begin].hi);
            on_outline[keys[begin].lo] = on_outline[keys[begin].hi] = 1;
        }
        else if (end == begin + 2 && normal_cos(surface, keys[begin].halfedge, keys[begin + 1].halfedge) < crease_cos)
            join_crease(crease, keys[begin].lo, keys[begin].hi);
    }
    memcpy(on_line, on_outline, (size_t)n);
    for (int32_t e = 0; e < 2 * surface->edge_count; ++e)
        on_line[surface->edges[e]] = 1;
    lock_long_creases(surface, crease, on_line, edge, degree);
    for (int32_t e = 0; e < surface->edge_count; ++e)
        add_line_edge(degree, neighbour, surface->edges[2 * e], surface->edges[2 * e + 1]);
    double cos_limit = cos(CORNER_DEGREES * 3.14159265358979323846 / 180.0), reach = 0.5 * edge;
    for (int32_t v = 0; v < n; ++v) {
        rank[v] = 1.0;
        if (degree[v] != 2)
            continue;
        double cosine = 1.0, deviation = 0.0;
        line_shape(surface, degree, neighbour, v, reach, &cosine, &deviation);
        candidate[v] = cosine < cos_limit || (on_outline[v] && deviation > tolerance);
        rank[v] = on_outline[v] ? -deviation : cosine; /* lines are all outline or all seam */
    }
    for (int32_t v = 0; v < n; ++v) {
        int corner = degree[v] != 0 && degree[v] != 2; /* ends, junctions and creases (-1) */
        if (degree[v] == 2)
            corner = candidate[v] && sharpest_around(surface, degree, neighbour, rank, v, reach);
        if (corner)
            surface->locked[surface->locked_count++] = v;
    }
done:
    free(degree);
    free(neighbour);
    free(rank);
    free(on_outline);
    free(on_line);
    free(candidate);
    free(crease);
    free(keys);
    return status;
}

/* Face fraction whose smallest angle exceeds 20 degrees. */
static double well_shaped_fraction(const pz_mesh *mesh)
{
    if (mesh->face_count == 0)
        return 1.0;
    double *angles = malloc(3 * (size_t)mesh->face_count * sizeof(double));
    if (!angles)
        return 0.0;
    pz_geom_corner_angles(mesh, angles);
    int32_t good = 0;
    double limit = 20.0 * 3.14159265358979323846 / 180.0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        good += angles[3 * f] > limit && angles[3 * f + 1] > limit && angles[3 * f + 2] > limit;
    free(angles);
    return (double)good / mesh->face_count;
}

/* ------------------------------------------------------------------------ */
/* 6-7. Poses, labels and the Hausdorff distance                             */
/* ------------------------------------------------------------------------ */

/* Barycentric coordinates of p (on the plane of a b c, inside), clamped and normalised. */
static void barycentric(const double *a, const double *b, const double *c, const double *p, double w[3])
{
    double v0[3], v1[3], v2[3];
    for (int k = 0; k < 3; ++k) {
        v0[k] = b[k] - a[k];
        v1[k] = c[k] - a[k];
        v2[k] = p[k] - a[k];
    }
    double d00 = v0[0] * v0[0] + v0[1] * v0[1] + v0[2] * v0[2], d01 = v0[0] * v1[0] + v0[1] * v1[1] + v0[2] * v1[2];
    double d11 = v1[0] * v1[0] + v1[1] * v1[1] + v1[2] * v1[2], d20 = v2[0] * v0[0] + v2[1] * v0[1] + v2[2] * v0[2];
    double d21 = v2[0] * v1[0] + v2[1] * v1[1] + v2[2] * v1[2], denominator = d00 * d11 - d01 * d01;
    if (!(fabs(denominator) > 0.0)) {
        w[0] = 1.0;
        w[1] = w[2] = 0.0;
        return;
    }
    w[1] = fmax(0.0, (d11 * d20 - d01 * d21) / denominator);
    w[2] = fmax(0.0, (d00 * d21 - d01 * d20) / denominator);
    w[0] = fmax(0.0, 1.0 - w[1] - w[2]);
    double sum = w[0] + w[1] + w[2];
    for (int k = 0; k < 3; ++k)
        w[k] /= sum;
}

static double distance3(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* Largest distance from `queries` to the surface (positions, faces of `surface`). */
static pz_status max_distance(const double *positions, const pz_mesh *surface, const double *queries,
                              int32_t query_count, double *result, pz_ctx *ctx)
{
    double *closest = malloc(3 * (size_t)query_count * sizeof(double) + 1);
    int32_t *face = malloc((size_t)query_count * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!closest || !face)
        status = pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory measuring distances");
    if (!status)
        status = pz_cgal_closest_points(positions, surface->vertex_count, surface->faces, surface->face_count,
                                        queries, query_count, closest, face, ctx);
    *result = 0.0;
    for (int32_t q = 0; !status && q < query_count; ++q)
        *result = fmax(*result, distance3(queries + 3 * (size_t)q, closest + 3 * (size_t)q));
    free(closest);
    free(face);
    return status;
}

/*
 * The output's samples, its face centroids then its vertices (rest pose),
 * each with its closest point on the rest input and the input face that
 * point lies on: one AABB tree of the input (1M faces: ~0.5 s to build)
 * serves the poses, the labels and every Hausdorff distance.
 */
typedef struct projection {
    int32_t count;    /* output faces + output vertices */
    double *samples;  /* count x 3 */
    double *closest;  /* count x 3, on the rest input */
    int32_t *face;    /* count: the input face of each closest point */
} projection;

static void projection_clear(projection *projection)
{
    free(projection->samples);
    free(projection->closest);
    free(projection->face);
    memset(projection, 0, sizeof *projection);
}

/* Face centroids of the output in `positions`, then its vertices, into samples (count x 3). */
static void output_samples(const pz_mesh *output, const double *positions, double *samples)
{
    for (int32_t f = 0; f < output->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            samples[3 * (size_t)f + k] = (positions[3 * (size_t)output->faces[3 * f] + k] +
                                          positions[3 * (size_t)output->faces[3 * f + 1] + k] +
                                          positions[3 * (size_t)output->faces[3 * f + 2] + k]) / 3.0;
    memcpy(samples + 3 * (size_t)output->face_count, positions, 3 * (size_t)output->vertex_count * sizeof(double));
}

static pz_status project_on_input(const pz_mesh *input, const pz_mesh *output, projection *out, pz_ctx *ctx)
{
    out->count = output->face_count + output->vertex_count;
    out->samples = malloc(3 * (size_t)out->count * sizeof(double) + 1);
    out->closest = malloc(3 * (size_t)out->count * sizeof(double) + 1);
    out->face = malloc((size_t)out->count * sizeof(int32_t) + 1);
    if (!out->samples || !out->closest || !out->face)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory projecting on the input");
    output_samples(output, output->positions, out->samples);
    return pz_cgal_closest_points(input->positions, input->vertex_count, input->faces, input->face_count,
                                  out->samples, out->count, out->closest, out->face, ctx);
}

/* `point` (on rest face `face` of input) carried into `pose` by its barycentric coordinates. */
static void carry(const pz_mesh *input, const double *pose, int32_t face, const double *point, double out[3])
{
    const int32_t *corner = input->faces + 3 * (size_t)face;
    double w[3];
    barycentric(input->positions + 3 * (size_t)corner[0], input->positions + 3 * (size_t)corner[1],
                input->positions + 3 * (size_t)corner[2], point, w);
    for (int k = 0; k < 3; ++k)
        out[k] = w[0] * pose[3 * (size_t)corner[0] + k] + w[1] * pose[3 * (size_t)corner[1] + k] +
                 w[2] * pose[3 * (size_t)corner[2] + k];
}

/* Places every output vertex in each pose of `input` through its closest point on the rest input. */
static pz_status transfer_poses(const pz_mesh *input, const projection *projection, pz_mesh *output, pz_ctx *ctx)
{
    int32_t n = output->vertex_count, first = output->face_count; /* the vertices follow the centroids */
    double *poses = malloc((size_t)input->pose_count * n * 3 * sizeof(double) + 1);
    if (!poses)
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory transferring poses");
    for (size_t p = 0; p < (size_t)input->pose_count; ++p)
        for (int32_t v = 0; v < n; ++v)
            carry(input, input->poses + p * input->vertex_count * 3, projection->face[first + v],
                  projection->closest + 3 * (size_t)(first + v), poses + (p * n + v) * 3);
    output->poses = poses;
    output->pose_count = input->pose_count;
    return PZ_OK;
}

/* Each output face takes the label of the input face closest to its centroid. */
static pz_status transfer_labels(const pz_mesh *input, const projection *projection, pz_mesh *output, pz_ctx *ctx)
{
    if (!input->face_labels)
        return PZ_OK;
    int32_t n = output->face_count;
    output->face_labels = malloc((size_t)n * sizeof(int32_t) + 1);
    output->label_names = input->label_names ? calloc((size_t)input->label_count + 1, sizeof(char *)) : NULL;
    output->label_count = input->label_count;
    if (!output->face_labels || (input->label_names && !output->label_names))
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory transferring labels");
    for (int32_t l = 0; output->label_names && l < input->label_count; ++l)
        if (input->label_names[l]) {
            output->label_names[l] = malloc(strlen(input->label_names[l]) + 1);
            if (!output->label_names[l])
                return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory transferring labels");
            strcpy(output->label_names[l], input->label_names[l]);
        }
    for (int32_t f = 0; f < n; ++f)
        output->face_labels[f] = input->face_labels[projection->face[f]];
    return PZ_OK; /* on failure the caller frees output with its partial labels */
}

/*
 * Symmetric sampled Hausdorff distance between the input and the output in
 * pose p (0 = rest): the output's samples against the input surface (for
 * the rest pose the projection has them already), the input's vertices
 * against the output surface. An extra pose needs a tree of the input in
 * that pose: the closest points of the rest pose carried into it would only
 * bound the distance from above (the jumpsuit front's poses: 0.53 mm
 * against 0.26 mm measured, over the bound of 0.51 mm).
 */
static pz_status pose_hausdorff(const pz_mesh *input, const pz_mesh *output, const projection *projection, int32_t p,
                                double *result, pz_ctx *ctx)
{
    const double *input_pose = p ? input->poses + (size_t)(p - 1) * input->vertex_count * 3 : input->positions;
    const double *output_pose = p ? output->poses + (size_t)(p - 1) * output->vertex_count * 3 : output->positions;
    double to_input = 0.0, to_output = 0.0;
    pz_status status = PZ_OK;
    if (p == 0) {
        for (int32_t s = 0; s < projection->count; ++s)
            to_input = fmax(to_input, distance3(projection->samples + 3 * (size_t)s,
                                                projection->closest + 3 * (size_t)s));
    } else {
        double *samples = malloc(3 * (size_t)projection->count * sizeof(double) + 1);
        if (!samples)
            return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory measuring distances");
        output_samples(output, output_pose, samples);
        status = max_distance(input_pose, input, samples, projection->count, &to_input, ctx);
        free(samples);
    }
    if (!status)
        status = max_distance(output_pose, output, input_pose, input->vertex_count, &to_output, ctx);
    *result = fmax(to_input, to_output);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Seams as polylines                                                        */
/* ------------------------------------------------------------------------ */

/*
 * Chains the seam edges into polylines: open chains start at vertices whose
 * seam degree is not 2 (ends and junctions), then the closed loops remain.
 */
static pz_status chain_seams(pz_prepare_result *result, const int32_t *pairs, int32_t edge_count, pz_ctx *ctx)
{
    int32_t n = result->mesh->vertex_count;
    int32_t *offset = calloc((size_t)n + 2, sizeof(int32_t));
    int32_t *adjacent = malloc(2 * (size_t)edge_count * sizeof(int32_t) + 1); /* edge ids per vertex */
    uint8_t *used = calloc((size_t)edge_count + 1, 1);
    result->seam_offsets = malloc(((size_t)edge_count + 2) * sizeof(int32_t));
    result->seam_vertices = malloc(2 * (size_t)edge_count * sizeof(int32_t) + 1);
    if (!offset || !adjacent || !used || !result->seam_offsets || !result->seam_vertices) {
        free(offset);
        free(adjacent);
        free(used);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory chaining seams");
    }
    for (int32_t e = 0; e < 2 * edge_count; ++e)
        ++offset[pairs[e] + 2];
    for (int32_t v = 0; v < n; ++v)
        offset[v + 2] += offset[v + 1];
    for (int32_t e = 0; e < 2 * edge_count; ++e)
        adjacent[offset[pairs[e] + 1]++] = e / 2;
    /* offset[v] .. offset[v+1] now lists v's seam edges */
    int32_t written = 0;
    result->seam_offsets[0] = 0;
    for (int pass = 0; pass < 2; ++pass)
        for (int32_t start = 0; start < n; ++start) {
            int32_t degree = offset[start + 1] - offset[start];
            if (pass == 0 ? (degree == 0 || degree == 2) : degree == 0)
                continue;
            for (int32_t i = offset[start]; i < offset[start + 1]; ++i) {
                if (used[adjacent[i]])
                    continue;
                int32_t v = start, e = adjacent[i];
                result->seam_vertices[written++] = v;
                while (e >= 0) {
                    used[e] = 1;
                    v = pairs[2 * e] == v ? pairs[2 * e + 1] : pairs[2 * e];
                    result->seam_vertices[written++] = v;
                    e = -1;
                    if (offset[v + 1] - offset[v] == 2) /* continue through a plain seam vertex */
                        for (int32_t j = offset[v]; j < offset[v + 1]; ++j)
                            if (!used[adjacent[j]])
                                e = adjacent[j];
                }
                result->seam_offsets[++result->seam_count] = written;
            }
        }
    free(offset);
    free(adjacent);
    free(used);
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* The driver                                                                */
/* ------------------------------------------------------------------------ */

void pz_prepare_result_free(pz_prepare_result **result)
{
    if (!result || !*result)
        return;
    pz_mesh_free(&(*result)->mesh);
    free((*result)->seam_offsets);
    free((*result)->seam_vertices);
    free(*result);
    *result = NULL;
}

typedef struct prepare_plan {
    double weld, fraction, target_edge;
    int32_t target_faces;
    int iterations;
} prepare_plan;

static void fill_plan(const pz_prepare_options *options, prepare_plan *plan)
{
    plan->weld = options->weld_distance == 0.0 ? DEFAULT_WELD_MM : options->weld_distance;
    plan->fraction = options->fragment_fraction > 0.0 ? options->fragment_fraction : DEFAULT_FRAGMENT_FRACTION;
    plan->target_faces = options->target_faces > 0 ? options->target_faces : DEFAULT_FACES;
    plan->target_edge = options->target_edge;
    plan->iterations = options->iterations > 0 ? options->iterations : DEFAULT_ITERATIONS;
}

static const char *const step_names[PZ_PREPARE_STEP_COUNT] = {"weld", "repair", "fragments", "decimate",
                                                              "remesh", "poses", "hausdorff"};

/* Steps 1-3 on *work. */
static pz_status clean(pz_mesh *work, const char *name, const prepare_plan *plan, pz_prepare_keep keep,
                       edge_list *seams, step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = state->report;
    double started = pz_seconds();
    pz_status status = PZ_OK;
    if (plan->weld > 0.0 && (status = weld(work, plan->weld, seams, &report->welded_vertices, ctx)))
        return status;
    report->seam_edges = seams->count;
    if (plan->weld > 0.0)
        step_done(state, PZ_PREPARE_WELD, report->welded_vertices > 0, started,
                  "%d vertices welded within %g mm, %d seam edges", (int)report->welded_vertices, plan->weld,
                  (int)report->seam_edges);
    else
        step_done(state, PZ_PREPARE_WELD, 0, started, "off");
    started = pz_seconds();
    if ((status = repair(work, name, seams, report, ctx)))
        return status;
    if (work->face_count == 0)
        return pz_error(ctx, PZ_ERR_INVALID_MESH,
                        "%s: nothing left after repair (%d faces: all degenerate, duplicate or not finite)", name,
                        (int)report->input_faces);
    int repaired = report->nonfinite_faces + report->degenerate_faces + report->duplicate_faces +
                   report->nonmanifold_edge_faces + report->split_vertices + report->flipped_faces;
    step_done(state, PZ_PREPARE_REPAIR, repaired > 0, started,
              "dropped %d non-finite, %d degenerate, %d duplicate, %d non-manifold-edge faces; split %d "
              "non-manifold vertices; flipped %d faces",
              (int)report->nonfinite_faces, (int)report->degenerate_faces, (int)report->duplicate_faces,
              (int)report->nonmanifold_edge_faces, (int)report->split_vertices, (int)report->flipped_faces);
    started = pz_seconds();
    if ((status = drop_fragments(work, name, plan->fraction, keep, seams, report, ctx)))
        return status;
    step_done(state, PZ_PREPARE_FRAGMENTS, report->dropped_components > 0, started,
              "%d components, dropped %d under %g%% of the area (%d faces)%s", (int)report->components,
              (int)report->dropped_components, 100.0 * plan->fraction, (int)report->dropped_component_faces,
              keep == PZ_PREPARE_KEEP_ALL ? "; --keep all" : "");
    return PZ_OK;
}

/* The edge length to remesh to; PZ_ERR_USAGE when it would give too few or too many faces. */
static pz_status choose_edge(const pz_mesh *work, const char *name, const prepare_plan *plan, double *edge,
                             double *expected_faces, pz_ctx *ctx)
{
    double area = pz_geom_total_area(work);
    *edge = plan->target_edge > 0.0 ? plan->target_edge : sqrt(4.0 * area / (SQRT3 * plan->target_faces));
    *expected_faces = 4.0 * area / (SQRT3 * *edge * *edge);
    double longest = sqrt(4.0 * area / (SQRT3 * MIN_EXPECTED_FACES));
    if (*expected_faces < MIN_EXPECTED_FACES)
        return pz_error(ctx, PZ_ERR_USAGE,
                        "%s: target edge %g mm is too long for this garment (area %.0f mm^2: about %.0f faces; at "
                        "most %.1f mm)", name, *edge, area, *expected_faces, longest);
    if (*expected_faces > MAX_EXPECTED_FACES)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: target edge %g mm is too short (about %.0f faces)", name, *edge,
                        *expected_faces);
    if (plan->target_edge <= 0.0) /* asked for faces: aim where CGAL lands on them */
        *edge *= sqrt(REMESH_EDGE_SHRINK);
    return PZ_OK;
}

/*
 * Remeshing again when the face count misses `expected` by more than
 * REMESH_FACE_TOLERANCE (faces asked for, not an edge). The count is a
 * steep, uneven function of the edge: CGAL leaves edges between 4/5 and 4/3
 * of the target alone, so from a mesh a little finer than wanted nothing
 * changes until the target passes 5/4 of its edges, then a lot does (a
 * 16K-face bodice: 15892 faces at 11 mm, 13766 at 11.84, 10622 at 12.5).
 * So the edge is first scaled as if faces went as 1 / edge^2, then, once
 * one pass gave too many faces and one too few, taken by the secant
 * through the two in log-log; the pass closest to `expected` is kept.
 * *remeshed holds the first pass on entry and the kept one on return.
 */
static pz_status correct_face_count(const pz_cgal_surface *source, double expected, int iterations, double *edge,
                                    pz_cgal_surface *remeshed, int *passes, pz_ctx *ctx)
{
    double over_edge = 0.0, over_miss = 0.0, under_edge = 0.0, under_miss = 0.0, kept_edge = *edge;
    pz_cgal_surface trial = {0};
    pz_status status = PZ_OK;
    double miss = remeshed->face_count / expected;
    for (int pass = 1; pass <= REMESH_CORRECTIONS && fabs(miss - 1.0) > REMESH_FACE_TOLERANCE; ++pass) {
        if (miss > 1.0)
            over_edge = *edge, over_miss = miss;
        else
            under_edge = *edge, under_miss = miss;
        if (over_edge > 0.0 && under_edge > 0.0 && under_miss > 0.0) /* log miss linear in log edge between them */
            *edge = exp(log(over_edge) + log(under_edge / over_edge) * log(over_miss) / log(over_miss / under_miss));
        else
            *edge *= sqrt(fmax(miss, 0.25));
        if ((status = pz_cgal_remesh(source, *edge, iterations, &trial, ctx)))
            break;
        ++*passes;
        double trial_miss = trial.face_count / expected;
        if (fabs(log(trial_miss)) < fabs(log(remeshed->face_count / expected))) {
            pz_cgal_surface swap = *remeshed;
            *remeshed = trial;
            trial = swap;
            kept_edge = *edge;
        }
        pz_cgal_surface_clear(&trial);
        miss = trial_miss;
    }
    *edge = kept_edge;
    return status;
}

/* Steps 4-5: *out gets the remeshed surface (positions, faces; seams in out_seams). */
static pz_status decimate_and_remesh(const pz_mesh *work, const edge_list *seams, const char *name,
                                     const prepare_plan *plan, const char *why, pz_mesh **out,
                                     pz_cgal_surface *remeshed, step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = state->report;
    double edge = 0.0, expected = 0.0;
    pz_status status = choose_edge(work, name, plan, &edge, &expected, ctx);
    if (status)
        return status;
    pz_cgal_surface source = surface_view(work, seams), thinned = {0}, decimated = {0};
    double started = pz_seconds();
    if (work->face_count > DECIMATE_ABOVE * expected) {
        int32_t wanted = (int32_t)(DECIMATE_TO * expected);
        if ((status = thin_out(&source, wanted, edge / sqrt(REMESH_EDGE_SHRINK), &thinned, ctx)))
            return status;
        source = thinned;
        int32_t thin_faces = thinned.face_count;
        if (thinned.face_count > 1.5 * wanted) {
            status = pz_cgal_decimate(&thinned, wanted, &decimated, ctx);
            pz_cgal_surface_clear(&thinned);
            if (status)
                return status;
            source = decimated;
        }
        report->decimated_faces = source.face_count;
        if (source.face_count == thin_faces)
            step_done(state, PZ_PREPARE_DECIMATE, 1, started, "%d -> %d faces (thinning)", (int)work->face_count,
                      thin_faces);
        else
            step_done(state, PZ_PREPARE_DECIMATE, 1, started, "%d -> %d faces (thinning) -> %d (edge collapse)",
                      (int)work->face_count, thin_faces, (int)source.face_count);
    } else {
        step_done(state, PZ_PREPARE_DECIMATE, 0, started, "not needed: %d faces, at most %.0f wanted",
                  (int)work->face_count, DECIMATE_ABOVE * expected);
    }
    started = pz_seconds();
    status = find_corners(&source, edge, OUTLINE_TOLERANCE * report->hausdorff_bound, ctx);
    if (!status)
        status = pz_cgal_remesh(&source, edge, plan->iterations, remeshed, ctx);
    int passes = 1;
    if (!status && plan->target_edge <= 0.0)
        status = correct_face_count(&source, expected, plan->iterations, &edge, remeshed, &passes, ctx);
    free(source.locked);
    source.locked = NULL;
    pz_cgal_surface_clear(&thinned);
    pz_cgal_surface_clear(&decimated);
    if (status)
        return status;
    if ((status = pz_mesh_create(remeshed->vertex_count, remeshed->face_count, out, ctx)))
        return status;
    memcpy((*out)->positions, remeshed->positions, 3 * (size_t)remeshed->vertex_count * sizeof(double));
    memcpy((*out)->faces, remeshed->faces, 3 * (size_t)remeshed->face_count * sizeof(int32_t));
    report->target_edge = edge;
    step_done(state, PZ_PREPARE_REMESH, 1, started, "edge %.2f mm, %d iterations, %d pass%s: %d faces%s%s", edge,
              plan->iterations, passes, passes > 1 ? "es" : "", (int)remeshed->face_count, *why ? "; " : "", why);
    return PZ_OK;
}

/* Steps 6-7 on the remeshed output. */
static pz_status carry_and_measure(const pz_mesh *work, pz_mesh *output, step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = state->report;
    double started = pz_seconds();
    projection projection = {0};
    /* the step that first needs the projection pays for it: poses and labels, else the Hausdorff distance */
    int carrying = work->pose_count > 0 || work->face_labels;
    pz_status status = carrying ? project_on_input(work, output, &projection, ctx) : PZ_OK;
    if (!status && work->pose_count > 0)
        status = transfer_poses(work, &projection, output, ctx);
    if (!status)
        status = transfer_labels(work, &projection, output, ctx);
    if (status) {
        projection_clear(&projection);
        return status;
    }
    if (work->pose_count > 0)
        step_done(state, PZ_PREPARE_POSES, 1, started, "%d poses carried over by barycentric coordinates",
                  (int)work->pose_count);
    else
        step_done(state, PZ_PREPARE_POSES, 0, started, "no extra poses");
    started = pz_seconds();
    if (!carrying)
        status = project_on_input(work, output, &projection, ctx);
    if (!status)
        status = pose_hausdorff(work, output, &projection, 0, &report->hausdorff, ctx);
    for (int32_t p = 1; !status && p <= work->pose_count; ++p) {
        double d = 0.0;
        status = pose_hausdorff(work, output, &projection, p, &d, ctx);
        report->pose_hausdorff_max = fmax(report->pose_hausdorff_max, d);
    }
    projection_clear(&projection);
    if (status)
        return status;
    report->within_bound = report->hausdorff <= report->hausdorff_bound &&
                           report->pose_hausdorff_max <= report->hausdorff_bound;
    step_done(state, PZ_PREPARE_HAUSDORFF, 1, started, "%.3f mm (poses: %.3f mm), bound %.3f mm: %s",
              report->hausdorff, report->pose_hausdorff_max, report->hausdorff_bound,
              report->within_bound ? "within" : "EXCEEDED: the shape changed more than 0.5% of the diagonal");
    return PZ_OK;
}

/*
 * Automatic mode (`panelize run --prepare auto`), measured in
 * docs/prepare.md: the field, tracing and segmentation did best on the
 * paper's densities (2-8K faces) and worse, and 2-4x slower, from ~12K
 * faces on; so a mesh over AUTO_MAX_FACES is remeshed to that (decimated
 * first when huge). Below it the density is kept: refining a coarse mesh
 * adds no shape (the new vertices lie on the old facets) and did not help
 * the pipeline (better in 3 of 7 runs, worse in 4). A mesh with fewer than
 * AUTO_WELL_SHAPED of its faces free of angles under 20 degrees (the
 * paper's "well shaped") is remeshed at its own face count; when that moves
 * the shape beyond the Hausdorff bound (a coarse mesh: remeshing at its own
 * density cuts across its curved facets, the wetsuit's 2274 faces moved
 * 47.8 mm against a bound of 25.1 mm), the input's triangles are kept.
 */
#define AUTO_MAX_FACES 10000
#define AUTO_WELL_SHAPED 0.95

typedef enum auto_need { NEED_NOTHING = 0, NEED_DENSITY, NEED_SHAPE } auto_need;

/* What automatic mode does with `work`: the face count to remesh to in plan->target_faces, why in `why`. */
static auto_need auto_decide(const pz_mesh *work, const pz_prepare_options *options, double well_shaped,
                             prepare_plan *plan, char *why, size_t size)
{
    int32_t most = options->target_faces > 0 ? options->target_faces : AUTO_MAX_FACES;
    if (work->face_count > most) {
        plan->target_faces = most;
        snprintf(why, size, "auto: %d faces, more than the %d the field and segmentation work best with",
                 (int)work->face_count, (int)most);
        return NEED_DENSITY;
    }
    if (well_shaped < AUTO_WELL_SHAPED) {
        plan->target_faces = work->face_count;
        snprintf(why, size, "auto: %.1f%% of the faces have every angle over 20 degrees (under %.0f%%): remeshed "
                 "at the input's %d faces", 100.0 * well_shaped, 100.0 * AUTO_WELL_SHAPED, (int)work->face_count);
        return NEED_SHAPE;
    }
    snprintf(why, size, "not needed: %d faces (at most %d), %.1f%% of them with every angle over 20 degrees",
             (int)work->face_count, (int)most, 100.0 * well_shaped);
    return NEED_NOTHING;
}

/* Steps 4-7 when remeshing: result->mesh and its seams. */
static pz_status remesh_all(const pz_mesh *work, const edge_list *seams, const char *name, const prepare_plan *plan,
                            const char *why, pz_prepare_result *result, step_state *state, pz_ctx *ctx)
{
    pz_cgal_surface remeshed = {0};
    pz_status status = decimate_and_remesh(work, seams, name, plan, why, &result->mesh, &remeshed, state, ctx);
    if (!status)
        status = carry_and_measure(work, result->mesh, state, ctx);
    if (!status)
        status = chain_seams(result, remeshed.edges, remeshed.edge_count, ctx);
    pz_cgal_surface_clear(&remeshed);
    return status;
}

/* Steps 4-7 when the repaired mesh is the result; *work passes to result->mesh. */
static pz_status keep_repaired(pz_mesh **work, const edge_list *seams, const prepare_plan *plan, const char *why,
                               int undone, pz_prepare_result *result, step_state *state, pz_ctx *ctx)
{
    double now = pz_seconds();
    step_done(state, PZ_PREPARE_DECIMATE, 0, now, "%s", undone ? "not needed: remeshing was undone" : why);
    step_done(state, PZ_PREPARE_REMESH, 0, now, "%s", why);
    step_done(state, PZ_PREPARE_POSES, 0, now, "%d poses kept as they are", (int)(*work)->pose_count);
    step_done(state, PZ_PREPARE_HAUSDORFF, 0, now, "geometry unchanged (welding moves vertices by at most %g mm)",
              plan->weld > 0.0 ? plan->weld : 0.0);
    result->mesh = *work; /* the result frees it from here on */
    *work = NULL;
    return chain_seams(result, seams->pairs, seams->count, ctx);
}

/* Drops the remeshed result (auto mode: a remesh that is undone or tried again). */
static void discard_remesh(pz_prepare_result *result)
{
    pz_prepare_report *report = &result->report;
    pz_mesh_free(&result->mesh);
    free(result->seam_offsets);
    free(result->seam_vertices);
    result->seam_offsets = result->seam_vertices = NULL;
    result->seam_count = 0;
    report->decimated_faces = 0;
    report->target_edge = 0.0;
    report->hausdorff = report->pose_hausdorff_max = 0.0;
    report->within_bound = 1;
}

/* A remesh for shape that moved the shape too much is undone: the report says what was tried. */
static void undo_remesh(pz_prepare_result *result, char *why, size_t size)
{
    pz_prepare_report *report = &result->report;
    snprintf(why, size, "auto: undone: remeshed for shape (%d faces), it moved %.2f mm from the input (bound "
             "%.2f mm): the input's triangles are kept", (int)result->mesh->face_count, report->hausdorff,
             report->hausdorff_bound);
    discard_remesh(result);
}

/*
 * Auto mode, a fine mesh remeshed to fewer faces beyond the Hausdorff bound
 * (a scan with detail finer than the count can hold: the shared face scan,
 * 34K faces, was 1.48 mm from its input at 10000 faces, bound 1.04 mm): the
 * face count is doubled, up to AUTO_RETRY_MAX_FACES and below the input's
 * own count, until the result is within the bound. A badly shaped input
 * (under AUTO_WELL_SHAPED) is then remeshed at its own count, as in the
 * shape case. When no remesh is within the bound, the input is kept as it
 * is (*undone set; the remesh detail lists the counts tried).
 */
#define AUTO_RETRY_MAX_FACES 40000

static pz_status retry_denser(const pz_mesh *work, const edge_list *seams, const char *name, prepare_plan *plan,
                              double work_shaped, char *why, size_t size, int *undone, pz_prepare_result *result,
                              step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = &result->report;
    char tried[120] = "";
    size_t used = 0;
    pz_status status = PZ_OK;
    int own_count_tried = 0;
    while (!status && !report->within_bound) {
        used += (size_t)snprintf(tried + used, sizeof tried - used, "%s%d faces %.2f mm", used ? ", " : "",
                                 (int)result->mesh->face_count, report->hausdorff);
        used = used < sizeof tried ? used : sizeof tried - 1;
        int32_t next = 2 * plan->target_faces;
        if (next > AUTO_RETRY_MAX_FACES || next >= work->face_count) {
            if (own_count_tried || work_shaped >= AUTO_WELL_SHAPED)
                break;
            next = work->face_count; /* badly shaped: its own density is the last try */
            own_count_tried = 1;
        }
        discard_remesh(result);
        plan->target_faces = next;
        snprintf(why, size, "auto: %d faces; beyond the bound %.2f mm at %s: retried at %d faces",
                 (int)work->face_count, report->hausdorff_bound, tried, (int)next);
        status = remesh_all(work, seams, name, plan, why, result, state, ctx);
    }
    if (status || report->within_bound)
        return status;
    snprintf(why, size, "auto: undone: beyond the bound %.2f mm at %s: the input's %d faces (%.1f%% well shaped) "
             "are kept", report->hausdorff_bound, tried, (int)work->face_count, 100.0 * work_shaped);
    discard_remesh(result);
    *undone = 1;
    return PZ_OK;
}

static pz_status run_prepare(const pz_mesh *mesh, const pz_prepare_options *options, const char *name,
                             pz_prepare_result *result, pz_ctx *ctx)
{
    pz_prepare_report *report = &result->report;
    step_state state = {ctx, name, report};
    prepare_plan plan;
    fill_plan(options, &plan);
    report->input_vertices = mesh->vertex_count;
    report->input_faces = mesh->face_count;
    pz_mesh *work = NULL;
    edge_list seams = {0};
    pz_status status = pz_mesh_copy(mesh, &work, ctx);
    if (!status)
        status = clean(work, name, &plan, options->keep, &seams, &state, ctx);
    if (!status) {
        double lo[3], hi[3];
        pz_mesh_bbox(work, lo, hi);
        report->bbox_diagonal = distance3(lo, hi);
        report->hausdorff_bound = HAUSDORFF_FRACTION * report->bbox_diagonal;
        report->within_bound = 1;
    }
    char why[256] = "";
    auto_need need = NEED_DENSITY;
    int undone = 0, automatic = 0;
    double work_shaped = 1.0;
    if (!status && options->no_remesh) {
        need = NEED_NOTHING;
        snprintf(why, sizeof why, "off");
    } else if (!status && options->automatic && plan.target_edge <= 0.0) {
        automatic = 1;
        work_shaped = well_shaped_fraction(work);
        need = auto_decide(work, options, work_shaped, &plan, why, sizeof why);
    }
    if (!status && need != NEED_NOTHING) {
        status = remesh_all(work, &seams, name, &plan, why, result, &state, ctx);
        if (!status && automatic && need == NEED_DENSITY && !report->within_bound)
            status = retry_denser(work, &seams, name, &plan, work_shaped, why, sizeof why, &undone, result, &state,
                                  ctx);
        if (!status && need == NEED_SHAPE && !report->within_bound) {
            undo_remesh(result, why, sizeof why);
            undone = 1;
        }
        if (undone)
            need = NEED_NOTHING;
    }
    if (!status && need == NEED_NOTHING)
        status = keep_repaired(&work, &seams, &plan, why, undone, result, &state, ctx);
    if (!status) {
        report->output_vertices = result->mesh->vertex_count;
        report->output_faces = result->mesh->face_count;
        report->min_angle_over_20_fraction = well_shaped_fraction(result->mesh);
    }
    free(seams.pairs);
    pz_mesh_free(&work);
    return status;
}

pz_status pz_prepare(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_prepare_options defaults = {0};
    if (!options)
        options = &defaults;
    const char *name = options->name ? options->name : "mesh";
    if (mesh->face_count == 0 || mesh->vertex_count == 0)
        return pz_error(ctx, PZ_ERR_INVALID_MESH, "%s: the mesh has no faces", name);
    if (!isfinite(options->weld_distance) || !isfinite(options->target_edge) || options->target_edge < 0.0 ||
        options->target_faces < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: bad preparation options", name);
    pz_prepare_result *result = calloc(1, sizeof *result);
    if (!result)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    for (int s = 0; s < PZ_PREPARE_STEP_COUNT; ++s)
        result->report.steps[s].name = step_names[s];
    pz_status status = run_prepare(mesh, options, name, result, ctx);
    if (status) {
        pz_prepare_result_free(&result);
        return status;
    }
    *out = result;
    return PZ_OK;
}

pz_status pz_prepare_auto(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out,
                          pz_ctx *ctx)
{
    pz_prepare_options automatic = {0};
    if (options)
        automatic = *options;
    automatic.automatic = 1;
    return pz_prepare(mesh, &automatic, out, ctx);
}

pz_status pz_prepare_write_seams(const pz_prepare_result *result, const char *path, pz_ctx *ctx)
{
    pz_output out;
    pz_status status = pz_output_open(&out, path, "w", ctx);
    if (status)
        return status;
    fputs("{\"curves\": [", out.file);
    for (int32_t s = 0; s < result->seam_count; ++s) {
        fputs(s ? ",\n  [" : "\n  [", out.file);
        for (int32_t i = result->seam_offsets[s]; i < result->seam_offsets[s + 1]; ++i) {
            const double *p = result->mesh->positions + 3 * (size_t)result->seam_vertices[i];
            fprintf(out.file, "%s[%.6f, %.6f, %.6f]", i > result->seam_offsets[s] ? ", " : "", p[0], p[1], p[2]);
        }
        fputc(']', out.file);
    }
    fputs(result->seam_count ? "\n]}\n" : "]}\n", out.file);
    return pz_output_commit(&out, ctx);
}
