/*
 * mesh/validate.c -- finding what is wrong with a mesh, and the repairs a
 * command may ask for before it refuses one.
 *
 * Algorithm. One pass over the vertices finds non-finite coordinates (rest
 * pose and every pose). One pass over the faces finds indices out of range or
 * repeated in a face ("bad" faces, left out of every later check), zero-area
 * faces and the referenced vertices. A face is degenerate when it repeats a
 * vertex or when its area is at most 1e-12 * d^2, d the diagonal of the
 * bounding box of the finite vertices: a relative threshold, so that the test
 * means the same in millimetres and in metres, and far below any face a
 * garment mesh could mean (a 1 m garment would need a face under 1 um^2).
 *
 * The half-edges of the other faces are then grouped by undirected edge: a
 * counting sort on the smaller endpoint (O(F)), then each bucket (a handful
 * of entries) sorted by (larger endpoint, third vertex of the face, id).
 * In each edge group:
 *  - duplicates: every face is examined once, in the group of the edge
 *    between its two smallest vertices, where faces with the same vertex set
 *    share the third vertex and so sit next to each other. Later copies are
 *    duplicates and are left out of the edge checks, so that one repeated face
 *    is reported as that and not also as the non-manifold edges it causes;
 *  - more than two faces: a non-manifold edge;
 *  - exactly two faces: a manifold edge, inconsistent when both faces run it
 *    the same way. Its two faces' corners at each endpoint are joined in a
 *    union-find over corners; afterwards the corners of a vertex fall into one
 *    set per fan, so a vertex with two or more sets is a non-manifold vertex
 *    (a bow-tie). Endpoints of non-manifold edges are not counted again as
 *    non-manifold vertices: the edge line already explains them.
 * Time O(F) (plus small sorts); scratch about 26 bytes per face.
 *
 * Failure. pz_mesh_validate fails only for lack of memory (PZ_ERR_NOMEM);
 * what it finds is reported in the pz_validation struct. pz_mesh_prepare
 * turns remaining problems into PZ_ERR_INVALID_MESH with a one-line message.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "mesh.h"
#include "core/util.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* Relative area threshold for a degenerate face: area <= eps * diagonal^2. */
#define PZ_DEGENERATE_AREA_EPS 1e-12

enum face_flag { FACE_BAD = 1, FACE_DEGENERATE = 2, FACE_DUPLICATE = 4 };
enum vertex_flag { VERTEX_REFERENCED = 1, VERTEX_ON_NONMANIFOLD_EDGE = 2, VERTEX_FAN = 4, VERTEX_FANS = 8 };

/* Where each kind of problem was first seen, for the messages. */
typedef struct first_seen {
    int32_t nonfinite_vertex;
    int32_t bad_face;
    int32_t degenerate_face;
    int32_t duplicate_face, duplicate_of;
    int32_t nonmanifold_edge[2];
    int32_t nonmanifold_vertex;
    int32_t inconsistent_edge[2];
    int32_t unreferenced_vertex;
} first_seen;

/* Half-edges of the usable faces grouped by undirected edge (see the header). */
typedef struct edge_groups {
    int32_t *offsets;    /* vertex_count + 1: bucket of the smaller endpoint */
    int32_t *halfedges;  /* offsets[vertex_count] entries */
} edge_groups;

typedef struct group_entry {
    int32_t other, third, halfedge;
} group_entry;

static void edge_groups_free(edge_groups *groups)
{
    free(groups->offsets);
    free(groups->halfedges);
    groups->offsets = groups->halfedges = NULL;
}

static int32_t min_i32(int32_t a, int32_t b) { return a < b ? a : b; }
static int32_t max_i32(int32_t a, int32_t b) { return a > b ? a : b; }

static int32_t halfedge_low(const int32_t *faces, int32_t h) { return min_i32(faces[h], faces[pz_he_next(h)]); }
static int32_t halfedge_high(const int32_t *faces, int32_t h) { return max_i32(faces[h], faces[pz_he_next(h)]); }

static int entry_less(const group_entry *a, const group_entry *b)
{
    if (a->other != b->other) return a->other < b->other;
    if (a->third != b->third) return a->third < b->third;
    return a->halfedge < b->halfedge;
}

static int entry_compare(const void *pa, const void *pb)
{
    const group_entry *a = pa, *b = pb;
    return entry_less(a, b) ? -1 : entry_less(b, a) ? 1 : 0;
}

/* Buckets are tiny on real meshes (insertion sort); a pathological vertex
 * with many edges falls back to qsort so the whole stays O(F log F). */
static void sort_bucket(const int32_t *faces, int32_t *halfedges, int32_t count, group_entry *scratch)
{
    for (int32_t i = 0; i < count; ++i) {
        int32_t h = halfedges[i];
        scratch[i] = (group_entry){halfedge_high(faces, h), faces[pz_he_prev(h)], h};
    }
    if (count > 24) {
        qsort(scratch, (size_t)count, sizeof *scratch, entry_compare);
    } else {
        for (int32_t i = 1; i < count; ++i) {
            group_entry moving = scratch[i];
            int32_t j = i;
            for (; j > 0 && entry_less(&moving, &scratch[j - 1]); --j)
                scratch[j] = scratch[j - 1];
            scratch[j] = moving;
        }
    }
    for (int32_t i = 0; i < count; ++i)
        halfedges[i] = scratch[i].halfedge;
}

static pz_status edge_groups_build(const pz_mesh *mesh, const uint8_t *face_flags, edge_groups *groups,
                                   pz_ctx *ctx)
{
    const int32_t *faces = mesh->faces;
    int32_t vertex_count = mesh->vertex_count, halfedge_count = 3 * mesh->face_count;
    groups->offsets = calloc((size_t)vertex_count + 2, sizeof(int32_t));
    groups->halfedges = malloc((size_t)halfedge_count * sizeof(int32_t) + 1);
    if (!groups->offsets || !groups->halfedges) {
        edge_groups_free(groups);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory validating %d faces", (int)mesh->face_count);
    }
    for (int32_t h = 0; h < halfedge_count; ++h)
        if (!(face_flags[pz_he_face(h)] & FACE_BAD))
            ++groups->offsets[halfedge_low(faces, h) + 2];
    int32_t largest = 0;
    for (int32_t v = 0; v < vertex_count; ++v) {
        largest = max_i32(largest, groups->offsets[v + 2]);
        groups->offsets[v + 2] += groups->offsets[v + 1];
    }
    for (int32_t h = 0; h < halfedge_count; ++h)
        if (!(face_flags[pz_he_face(h)] & FACE_BAD))
            groups->halfedges[groups->offsets[halfedge_low(faces, h) + 1]++] = h;
    group_entry *scratch = malloc((size_t)largest * sizeof *scratch + 1);
    if (!scratch) {
        edge_groups_free(groups);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory validating %d faces", (int)mesh->face_count);
    }
    for (int32_t v = 0; v < vertex_count; ++v)
        sort_bucket(faces, groups->halfedges + groups->offsets[v], groups->offsets[v + 1] - groups->offsets[v],
                    scratch);
    free(scratch);
    return PZ_OK;
}

/* End (exclusive) of the edge group starting at index `begin` of bucket `v`. */
static int32_t group_end(const int32_t *faces, const edge_groups *groups, int32_t v, int32_t begin)
{
    int32_t other = halfedge_high(faces, groups->halfedges[begin]), end = begin + 1;
    while (end < groups->offsets[v + 1] && halfedge_high(faces, groups->halfedges[end]) == other)
        ++end;
    return end;
}

/* ------------------------------------------------------------------------ */
/* The checks                                                                */
/* ------------------------------------------------------------------------ */

static int is_finite3(const double *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

static void check_coordinates(const pz_mesh *mesh, pz_validation *out, first_seen *first)
{
    size_t vertex_count = (size_t)mesh->vertex_count;
    for (size_t v = 0; v < vertex_count; ++v) {
        int finite = is_finite3(mesh->positions + 3 * v);
        for (int32_t p = 0; finite && p < mesh->pose_count; ++p)
            finite = is_finite3(mesh->poses + ((size_t)p * vertex_count + v) * 3);
        if (!finite && out->nonfinite_coordinates++ == 0)
            first->nonfinite_vertex = (int32_t)v;
    }
}

/* Squared diagonal of the bounding box of the finite rest positions. */
static double finite_diagonal_squared(const pz_mesh *mesh)
{
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        const double *p = mesh->positions + 3 * v;
        if (!is_finite3(p))
            continue;
        for (int k = 0; k < 3; ++k) {
            low[k] = p[k] < low[k] ? p[k] : low[k];  /* not fmin: a libm call per coordinate */
            high[k] = p[k] > high[k] ? p[k] : high[k];
        }
    }
    double squared = 0.0;
    for (int k = 0; k < 3; ++k)
        if (high[k] >= low[k])
            squared += (high[k] - low[k]) * (high[k] - low[k]);
    return squared;
}

/* (2 area)^2, compared against (2 limit)^2 so that no square root is taken per face. */
static double twice_area_squared(const double *a, const double *b, const double *c)
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
    return x * x + y * y + z * z;
}

static void check_faces(const pz_mesh *mesh, uint8_t *face_flags, uint8_t *vertex_flags, pz_validation *out,
                        first_seen *first)
{
    double twice_limit = 2.0 * PZ_DEGENERATE_AREA_EPS * finite_diagonal_squared(mesh);
    double twice_limit_squared = twice_limit * twice_limit;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        const int32_t *corner = mesh->faces + 3 * f;
        int32_t out_of_range = 0;
        for (int k = 0; k < 3; ++k) {
            if (corner[k] < 0 || corner[k] >= mesh->vertex_count)
                ++out_of_range;
            else
                vertex_flags[corner[k]] |= VERTEX_REFERENCED;
        }
        int32_t equal_pairs = (corner[0] == corner[1]) + (corner[1] == corner[2]) + (corner[2] == corner[0]);
        int32_t repeated = equal_pairs == 3 ? 2 : equal_pairs;  /* a a b repeats one corner, a a a two */
        if (out_of_range + repeated) {
            face_flags[f] |= FACE_BAD;
            if (out->bad_indices == 0)
                first->bad_face = f;
            out->bad_indices += out_of_range + repeated;
        }
        /* A repeated corner is zero area whatever the positions; a face with
         * an index out of range has no area to speak of. */
        int degenerate = out_of_range ? 0
                         : repeated   ? 1
                                      : twice_area_squared(mesh->positions + 3 * corner[0], mesh->positions + 3 * corner[1],
                                                           mesh->positions + 3 * corner[2]) <= twice_limit_squared;
        if (degenerate) {
            face_flags[f] |= FACE_DEGENERATE;
            if (out->degenerate_faces++ == 0)
                first->degenerate_face = f;
        }
    }
}

/* Faces are compared in the group of the edge between their two smallest
 * vertices (third vertex > other end), where copies are adjacent. */
static void find_duplicates(const pz_mesh *mesh, const edge_groups *groups, uint8_t *face_flags,
                            pz_validation *out, first_seen *first)
{
    const int32_t *faces = mesh->faces;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        int32_t run_face = -1, run_third = -1, run_other = -1;
        for (int32_t i = groups->offsets[v]; i < groups->offsets[v + 1]; ++i) {
            int32_t h = groups->halfedges[i];
            int32_t other = halfedge_high(faces, h), third = faces[pz_he_prev(h)];
            if (third < other)
                continue;  /* not this face's smallest edge */
            if (other == run_other && third == run_third) {
                face_flags[pz_he_face(h)] |= FACE_DUPLICATE;
                if (out->duplicate_faces++ == 0) {
                    first->duplicate_face = pz_he_face(h);
                    first->duplicate_of = run_face;
                }
            } else {
                run_face = pz_he_face(h);
                run_other = other;
                run_third = third;
            }
        }
    }
}

/* The corner of half-edge h's face that sits at vertex v (v an end of h). */
static int32_t corner_at(const int32_t *faces, int32_t h, int32_t v)
{
    return faces[h] == v ? h : pz_he_next(h);
}

static void check_edges(const pz_mesh *mesh, const edge_groups *groups, const uint8_t *face_flags,
                        uint8_t *vertex_flags, int32_t *corner_parent, pz_validation *out, first_seen *first)
{
    const int32_t *faces = mesh->faces;
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        for (int32_t begin = groups->offsets[v]; begin < groups->offsets[v + 1];) {
            int32_t end = group_end(faces, groups, v, begin);
            int32_t count = 0, pair[2] = {-1, -1};
            for (int32_t i = begin; i < end; ++i) {
                int32_t h = groups->halfedges[i];
                if (face_flags[pz_he_face(h)] & FACE_DUPLICATE)
                    continue;
                if (count < 2)
                    pair[count] = h;
                ++count;
            }
            int32_t low = v, high = halfedge_high(faces, groups->halfedges[begin]);
            if (count > 2) {
                vertex_flags[low] |= VERTEX_ON_NONMANIFOLD_EDGE;
                vertex_flags[high] |= VERTEX_ON_NONMANIFOLD_EDGE;
                if (out->nonmanifold_edges++ == 0) {
                    first->nonmanifold_edge[0] = low;
                    first->nonmanifold_edge[1] = high;
                }
            } else if (count == 2) {
                pz_union_find_join(corner_parent, corner_at(faces, pair[0], low), corner_at(faces, pair[1], low));
                pz_union_find_join(corner_parent, corner_at(faces, pair[0], high), corner_at(faces, pair[1], high));
                if (faces[pair[0]] == faces[pair[1]] && out->inconsistent_edges++ == 0) {
                    first->inconsistent_edge[0] = low;
                    first->inconsistent_edge[1] = high;
                }
            }
            begin = end;
        }
    }
}

/* One union-find set per fan: count the sets of each vertex (saturating at 2). */
static void check_fans(const pz_mesh *mesh, const uint8_t *face_flags, uint8_t *vertex_flags,
                       int32_t *corner_parent, pz_validation *out, first_seen *first)
{
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c) {
        if (face_flags[pz_he_face(c)] & (FACE_BAD | FACE_DUPLICATE) || pz_union_find_root(corner_parent, c) != c)
            continue;
        uint8_t *flags = vertex_flags + mesh->faces[c];
        *flags |= (*flags & VERTEX_FAN) ? VERTEX_FANS : VERTEX_FAN;
    }
    for (int32_t v = 0; v < mesh->vertex_count; ++v) {
        if (!(vertex_flags[v] & VERTEX_REFERENCED)) {
            if (out->unreferenced_vertices++ == 0)
                first->unreferenced_vertex = v;
        } else if ((vertex_flags[v] & VERTEX_FANS) && !(vertex_flags[v] & VERTEX_ON_NONMANIFOLD_EDGE)) {
            if (out->nonmanifold_vertices++ == 0)
                first->nonmanifold_vertex = v;
        }
    }
}

/* Runs every check; hands back the per-face flags when face_flags_out is not NULL. */
static pz_status classify(const pz_mesh *mesh, pz_validation *out, first_seen *first, uint8_t **face_flags_out,
                          pz_ctx *ctx)
{
    memset(out, 0, sizeof *out);
    memset(first, 0, sizeof *first);
    uint8_t *face_flags = calloc((size_t)mesh->face_count + 1, 1);
    uint8_t *vertex_flags = calloc((size_t)mesh->vertex_count + 1, 1);
    int32_t *corner_parent = malloc((size_t)mesh->face_count * 3 * sizeof(int32_t) + 1);
    edge_groups groups = {0};
    pz_status status = PZ_OK;
    if (!face_flags || !vertex_flags || !corner_parent)
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory validating %d faces", (int)mesh->face_count);
    if (!status) {
        check_coordinates(mesh, out, first);
        check_faces(mesh, face_flags, vertex_flags, out, first);
        status = edge_groups_build(mesh, face_flags, &groups, ctx);
    }
    if (!status) {
        for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
            corner_parent[c] = c;
        find_duplicates(mesh, &groups, face_flags, out, first);
        check_edges(mesh, &groups, face_flags, vertex_flags, corner_parent, out, first);
        check_fans(mesh, face_flags, vertex_flags, corner_parent, out, first);
    }
    edge_groups_free(&groups);
    free(corner_parent);
    free(vertex_flags);
    if (!status && face_flags_out)
        *face_flags_out = face_flags;
    else
        free(face_flags);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Reporting                                                                 */
/* ------------------------------------------------------------------------ */

static const char *plural(int32_t count, const char *one, const char *many) { return count == 1 ? one : many; }

static int add_problem(pz_validation *out, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int add_problem(pz_validation *out, const char *fmt, ...)
{
    char line[512];
    va_list args;
    va_start(args, fmt);
    vsnprintf(line, sizeof line, fmt, args);
    va_end(args);
    char **grown = realloc(out->problems, ((size_t)out->problem_count + 1) * sizeof *grown);
    if (!grown)
        return 0;
    out->problems = grown;
    size_t length = strlen(line) + 1;
    char *copy = malloc(length);
    if (!copy)
        return 0;
    memcpy(copy, line, length);
    out->problems[out->problem_count++] = copy;
    return 1;
}

/* One line per kind, most fundamental first (pz_mesh_prepare quotes the first). */
static int describe(pz_validation *out, const first_seen *first)
{
    int ok = 1;
    int32_t n;
    if ((n = out->nonfinite_coordinates))
        ok &= add_problem(out, "%d %s with non-finite coordinates (first: vertex %d)", (int)n,
                          plural(n, "vertex", "vertices"), (int)first->nonfinite_vertex);
    if ((n = out->bad_indices))
        ok &= add_problem(out, "%d bad face %s, out of range or repeated (first: face %d)", (int)n,
                          plural(n, "index", "indices"), (int)first->bad_face);
    if ((n = out->degenerate_faces))
        ok &= add_problem(out, "%d degenerate (zero-area) %s (first: face %d)", (int)n, plural(n, "face", "faces"),
                          (int)first->degenerate_face);
    if ((n = out->duplicate_faces))
        ok &= add_problem(out, "%d duplicate %s (first: face %d repeats face %d)", (int)n,
                          plural(n, "face", "faces"), (int)first->duplicate_face, (int)first->duplicate_of);
    if ((n = out->nonmanifold_edges))
        ok &= add_problem(out, "%d non-manifold %s, with more than two faces (first: vertices %d-%d)", (int)n,
                          plural(n, "edge", "edges"), (int)first->nonmanifold_edge[0],
                          (int)first->nonmanifold_edge[1]);
    if ((n = out->nonmanifold_vertices))
        ok &= add_problem(out, "%d non-manifold %s, where separate fans of faces meet (first: vertex %d)", (int)n,
                          plural(n, "vertex", "vertices"), (int)first->nonmanifold_vertex);
    if ((n = out->inconsistent_edges))
        ok &= add_problem(out, "%d inconsistently oriented %s, with both faces running the same way "
                          "(first: vertices %d-%d)", (int)n, plural(n, "edge", "edges"),
                          (int)first->inconsistent_edge[0], (int)first->inconsistent_edge[1]);
    if ((n = out->unreferenced_vertices))
        ok &= add_problem(out, "%d unreferenced %s (first: vertex %d)", (int)n, plural(n, "vertex", "vertices"),
                          (int)first->unreferenced_vertex);
    return ok;
}

pz_status pz_mesh_validate(const pz_mesh *mesh, pz_validation *out, pz_ctx *ctx)
{
    first_seen first;
    pz_status status = classify(mesh, out, &first, NULL, ctx);
    if (status) {
        memset(out, 0, sizeof *out);
        return status;
    }
    if (!describe(out, &first)) {
        pz_validation_clear(out);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory describing mesh problems");
    }
    return PZ_OK;
}

int pz_validation_ok(const pz_validation *v)
{
    return !v->nonfinite_coordinates && !v->bad_indices && !v->degenerate_faces && !v->duplicate_faces &&
           !v->nonmanifold_edges && !v->nonmanifold_vertices && !v->inconsistent_edges;
}

void pz_validation_clear(pz_validation *validation)
{
    for (int32_t i = 0; i < validation->problem_count; ++i)
        free(validation->problems[i]);
    free(validation->problems);
    memset(validation, 0, sizeof *validation);
}

/* ------------------------------------------------------------------------ */
/* Repairs                                                                   */
/* ------------------------------------------------------------------------ */

pz_status pz_mesh_drop_unreferenced(pz_mesh *mesh, int32_t *removed, pz_ctx *ctx)
{
    if (removed)
        *removed = 0;
    int32_t old_count = mesh->vertex_count;
    int32_t *new_index = malloc((size_t)old_count * sizeof(int32_t) + 1);
    if (!new_index)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory renumbering %d vertices", (int)old_count);
    for (int32_t v = 0; v < old_count; ++v)
        new_index[v] = -1;
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->faces[c] >= 0 && mesh->faces[c] < old_count)
            new_index[mesh->faces[c]] = 0;
    int32_t kept = 0;
    for (int32_t v = 0; v < old_count; ++v)
        if (new_index[v] == 0)
            new_index[v] = kept++;
    if (kept == old_count) {
        free(new_index);
        return PZ_OK;
    }
    /* Destinations never pass their sources (new index <= old, fewer rows per
     * pose), so the positions and poses compact in place, front to back. */
    for (int32_t v = 0; v < old_count; ++v)
        if (new_index[v] >= 0)
            memmove(mesh->positions + 3 * (size_t)new_index[v], mesh->positions + 3 * (size_t)v, 3 * sizeof(double));
    for (size_t p = 0; p < (size_t)mesh->pose_count; ++p)
        for (int32_t v = 0; v < old_count; ++v)
            if (new_index[v] >= 0)
                memmove(mesh->poses + (p * (size_t)kept + (size_t)new_index[v]) * 3,
                        mesh->poses + (p * (size_t)old_count + (size_t)v) * 3, 3 * sizeof(double));
    /* Out-of-range indices stay out of range so validation still reports them. */
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->faces[c] >= 0 && mesh->faces[c] < old_count)
            mesh->faces[c] = new_index[mesh->faces[c]];
    mesh->vertex_count = kept;
    free(new_index);
    if (removed)
        *removed = old_count - kept;
    return PZ_OK;
}

int32_t pz_mesh_drop_faces(pz_mesh *mesh, const uint8_t *drop)
{
    int32_t kept = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        if (drop[f])
            continue;
        memmove(mesh->faces + 3 * kept, mesh->faces + 3 * f, 3 * sizeof(int32_t));
        if (mesh->corner_uvs)
            memmove(mesh->corner_uvs + 3 * kept, mesh->corner_uvs + 3 * f, 3 * sizeof(int32_t));
        if (mesh->face_labels)
            mesh->face_labels[kept] = mesh->face_labels[f];
        ++kept;
    }
    int32_t dropped = mesh->face_count - kept;
    mesh->face_count = kept;
    return dropped;
}

static pz_status drop_flagged_faces(pz_mesh *mesh, const char *path, unsigned repair_flags, pz_ctx *ctx)
{
    pz_validation counts;
    first_seen first;
    uint8_t *face_flags = NULL;
    pz_status status = classify(mesh, &counts, &first, &face_flags, ctx);
    if (status)
        return status;
    int32_t degenerate = 0, duplicate = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        uint8_t flags = face_flags[f];
        /* Out-of-range faces are not repaired: the file is wrong, not the surface. */
        int out_of_range = 0;
        for (int k = 0; k < 3; ++k)
            out_of_range |= mesh->faces[3 * f + k] < 0 || mesh->faces[3 * f + k] >= mesh->vertex_count;
        int drop_degenerate = (repair_flags & PZ_REPAIR_DROP_DEGENERATE) && (flags & FACE_DEGENERATE) && !out_of_range;
        int drop_duplicate = (repair_flags & PZ_REPAIR_DROP_DUPLICATES) && (flags & FACE_DUPLICATE);
        degenerate += drop_degenerate;
        duplicate += drop_duplicate && !drop_degenerate;
        face_flags[f] = (uint8_t)(drop_degenerate || drop_duplicate);
    }
    pz_mesh_drop_faces(mesh, face_flags);
    free(face_flags);
    if (degenerate)
        pz_note(ctx, "%s: dropped %d degenerate %s", path, (int)degenerate, plural(degenerate, "face", "faces"));
    if (duplicate)
        pz_note(ctx, "%s: dropped %d duplicate %s", path, (int)duplicate, plural(duplicate, "face", "faces"));
    return PZ_OK;
}

/*
 * Consistent orientation by breadth-first search over faces joined by
 * manifold edges: a neighbour that runs the shared edge the same way must
 * have the opposite orientation. Per component, the smaller side is flipped
 * (so a mesh with a few flipped faces keeps its majority orientation). A
 * component that meets a contradiction (a Moebius band) is not orientable
 * and is left unchanged; validation then still reports it.
 */
typedef struct orient_result {
    int32_t flipped_faces, nonorientable_components;
} orient_result;

static void flip_face(pz_mesh *mesh, int32_t f)
{
    int32_t swap = mesh->faces[3 * f + 1];
    mesh->faces[3 * f + 1] = mesh->faces[3 * f + 2];
    mesh->faces[3 * f + 2] = swap;
    if (mesh->corner_uvs) {
        swap = mesh->corner_uvs[3 * f + 1];
        mesh->corner_uvs[3 * f + 1] = mesh->corner_uvs[3 * f + 2];
        mesh->corner_uvs[3 * f + 2] = swap;
    }
}

/* across[h]: the other half-edge of h's edge when exactly two faces share it, else -1. */
static void pair_manifold_edges(const pz_mesh *mesh, const edge_groups *groups, int32_t *across)
{
    for (int32_t h = 0; h < 3 * mesh->face_count; ++h)
        across[h] = -1;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        for (int32_t begin = groups->offsets[v]; begin < groups->offsets[v + 1];) {
            int32_t end = group_end(mesh->faces, groups, v, begin);
            if (end - begin == 2) {
                across[groups->halfedges[begin]] = groups->halfedges[begin + 1];
                across[groups->halfedges[begin + 1]] = groups->halfedges[begin];
            }
            begin = end;
        }
}

/* Orients the component of `seed`; its faces land in queue[0..size). side[f] is 1 or -1. */
static void orient_component(pz_mesh *mesh, const int32_t *across, int8_t *side, int32_t *queue, int32_t seed,
                             orient_result *result)
{
    int32_t size = 0, head = 0, flips = 0, contradiction = 0;
    side[seed] = 1;
    queue[size++] = seed;
    while (head < size) {
        int32_t f = queue[head++];
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * f + k, g_h = across[h];
            if (g_h < 0)
                continue;
            int32_t g = pz_he_face(g_h);
            int8_t wanted = (int8_t)(mesh->faces[h] == mesh->faces[g_h] ? -side[f] : side[f]);
            if (!side[g]) {
                side[g] = wanted;
                flips += wanted < 0;
                queue[size++] = g;
            } else if (side[g] != wanted) {
                contradiction = 1;
            }
        }
    }
    if (contradiction) {
        ++result->nonorientable_components;
        return;
    }
    int8_t flip_side = flips * 2 > size ? 1 : -1;
    for (int32_t i = 0; i < size; ++i)
        if (side[queue[i]] == flip_side) {
            flip_face(mesh, queue[i]);
            ++result->flipped_faces;
        }
}

static pz_status orient_faces(pz_mesh *mesh, orient_result *result, pz_ctx *ctx)
{
    memset(result, 0, sizeof *result);
    int32_t face_count = mesh->face_count;
    uint8_t *face_flags = calloc((size_t)face_count + 1, 1);
    int32_t *across = malloc((size_t)face_count * 3 * sizeof(int32_t) + 1);
    int32_t *queue = malloc((size_t)face_count * sizeof(int32_t) + 1);
    int8_t *side = calloc((size_t)face_count + 1, 1);
    edge_groups groups = {0};
    pz_status status = PZ_OK;
    if (!face_flags || !across || !queue || !side)
        status = pz_error(ctx, PZ_ERR_NOMEM, "out of memory orienting %d faces", (int)face_count);
    if (!status) {
        /* Faces with bad indices take no part, as in validation. */
        for (int32_t f = 0; f < face_count; ++f) {
            const int32_t *corner = mesh->faces + 3 * f;
            for (int k = 0; k < 3; ++k)
                if (corner[k] < 0 || corner[k] >= mesh->vertex_count || corner[k] == corner[(k + 1) % 3])
                    face_flags[f] = FACE_BAD;
        }
        status = edge_groups_build(mesh, face_flags, &groups, ctx);
    }
    if (!status) {
        pair_manifold_edges(mesh, &groups, across);
        edge_groups_free(&groups);
        for (int32_t f = 0; f < face_count; ++f)
            if (!side[f] && !face_flags[f])
                orient_component(mesh, across, side, queue, f, result);
    }
    edge_groups_free(&groups);
    free(face_flags);
    free(across);
    free(queue);
    free(side);
    return status;
}

static pz_status drop_unreferenced_noting(pz_mesh *mesh, const char *path, pz_ctx *ctx)
{
    int32_t removed = 0;
    pz_status status = pz_mesh_drop_unreferenced(mesh, &removed, ctx);
    if (!status && removed)
        pz_note(ctx, "%s: dropped %d unreferenced %s", path, (int)removed, plural(removed, "vertex", "vertices"));
    return status;
}

pz_status pz_mesh_prepare(pz_mesh *mesh, const char *path, unsigned repair_flags, pz_ctx *ctx)
{
    pz_status status = drop_unreferenced_noting(mesh, path, ctx);
    if (!status && (repair_flags & (PZ_REPAIR_DROP_DEGENERATE | PZ_REPAIR_DROP_DUPLICATES))) {
        status = drop_flagged_faces(mesh, path, repair_flags, ctx);
        if (!status)
            status = drop_unreferenced_noting(mesh, path, ctx);  /* dropped faces may strand vertices */
    }
    if (!status && (repair_flags & PZ_REPAIR_ORIENT)) {
        orient_result oriented;
        status = orient_faces(mesh, &oriented, ctx);
        if (!status && oriented.flipped_faces)
            pz_note(ctx, "%s: flipped %d %s to orient the surface consistently", path, (int)oriented.flipped_faces,
                    plural(oriented.flipped_faces, "face", "faces"));
        if (!status && oriented.nonorientable_components)
            pz_note(ctx, "%s: %d %s not orientable (like a Moebius band)", path,
                    (int)oriented.nonorientable_components,
                    plural(oriented.nonorientable_components, "component is", "components are"));
    }
    if (status)
        return status;
    pz_validation validation;
    if ((status = pz_mesh_validate(mesh, &validation, ctx)))
        return status;
    if (pz_validation_ok(&validation)) {
        pz_validation_clear(&validation);
        return PZ_OK;
    }
    int32_t more = validation.problem_count - 1 - (validation.unreferenced_vertices > 0);
    if (more > 0)
        pz_error(ctx, PZ_ERR_INVALID_MESH, "%s: invalid mesh: %s; %d more kind%s of problem (run `panelize info %s`)",
                 path, validation.problems[0], (int)more, more == 1 ? "" : "s", path);
    else
        pz_error(ctx, PZ_ERR_INVALID_MESH, "%s: invalid mesh: %s (run `panelize info %s`)", path,
                 validation.problems[0], path);
    pz_validation_clear(&validation);
    return PZ_ERR_INVALID_MESH;
}

/*
 * pz_mesh_prepare notes each repair as it makes it, but a run that then
 * fails must print its one error line only. So a copy is prepared quietly
 * first; only when that succeeds is the preparation repeated aloud (it is
 * deterministic), or, in a quiet context, the prepared copy simply kept.
 */
pz_status pz_mesh_prepare_quietly_first(pz_mesh **mesh, const char *name, unsigned repair_flags, pz_ctx *ctx)
{
    pz_mesh *trial = NULL;
    pz_status status = pz_mesh_copy(*mesh, &trial, ctx);
    if (status != PZ_OK)
        return status;
    int quiet = ctx->quiet;
    ctx->quiet = 1;
    status = pz_mesh_prepare(trial, name, repair_flags, ctx);
    ctx->quiet = quiet;
    if (status == PZ_OK && quiet) {
        pz_mesh_free(mesh);
        *mesh = trial;
        return PZ_OK;
    }
    pz_mesh_free(&trial);
    if (status != PZ_OK)
        return status;
    return pz_mesh_prepare(*mesh, name, repair_flags, ctx);
}
