/*
 * segment/truing.c -- seam truing: the seams of a layout, traced along mesh
 * edges, become smooth lines on the surface.
 *
 * A path on mesh edges that runs at an angle to the triangulation is a
 * staircase: on the shared garments its consecutive edges turn by 15-20
 * degrees on average, and a flattened seam shows a zig-zag of a few
 * millimetres that no pattern maker would cut. The paper smooths the paths
 * and re-projects them onto the surface, updating the mesh (pietroni2022
 * Sec. 4.2). Here the mesh keeps its connectivity and face order (garment.obj
 * stays face-for-face the input): the vertices of every cut chain move onto a
 * smoothed copy of the chain, projected back onto the original surface, and
 * their neighbours relax so the triangles stay well shaped. Steps:
 *
 *  1. Chains: maximal runs of cut edges between nodes (a vertex with a cut
 *     degree other than 2, or on the border). Chain ends stay; so do corners,
 *     where the chain turns by more than corner_deg in the tangent plane
 *     between the chords to the vertices three edges behind and ahead
 *     (the corners the segmentation counted stay corners).
 *  2. Smoothing: Taubin's lambda/mu filter along each chain (no shrinkage),
 *     `passes` times: it removes the wavelengths of a few edges (the
 *     staircase) and keeps the seam's course.
 *  3. Projection: each chain vertex goes to the closest point of the
 *     original surface (faces within two rings of it) to its smoothed
 *     position, at most max_move_rel times its shortest edge away.
 *  4. Relaxation: the vertices next to the chains (not on a chain, not on the
 *     border) move towards the centroid of their neighbours, tangentially,
 *     projected back onto the original surface, a few times.
 *  5. Safety: a face whose normal turned by more than 60 degrees from the
 *     original, or whose area fell below a fifth of it, sends its moved
 *     vertices half-way back, up to 6 times, then all the way.
 *  6. Poses follow: every moved vertex lands on an original face with
 *     barycentric coordinates; the same combination of that face's pose
 *     positions is its position in each pose.
 *
 * Cost: O(V + F) plus a constant per chain vertex (two rings). The result is
 * deterministic (one thread, fixed orders).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/segment.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_PASSES 20
#define DEFAULT_MAX_MOVE_REL 0.5
#define DEFAULT_CORNER_DEG 50.0
/* Corners are measured between the chords to the chain vertices this many edges behind and ahead:
 * wide enough that a staircase's steps (90 degrees per edge, 45 over two edges) average out. */
#define CORNER_WINDOW 3
#define TAUBIN_LAMBDA 0.5
#define TAUBIN_MU -0.53
#define RELAX_ITERATIONS 4
#define RELAX_STEP 0.5
#define SAFETY_ROUNDS 6
#define MIN_AREA_RATIO 0.2
#define MIN_NORMAL_COS 0.5 /* 60 degrees */

/* Where a moved vertex sits on the original surface. */
typedef struct surface_point {
    int32_t face;    /* -1: not moved */
    double bary[3];
} surface_point;

typedef struct truing {
    pz_mesh *mesh;
    const pz_topology *topology;
    const uint8_t *edge_cut;
    double *rest;               /* vertex_count x 3: the original positions (the surface) */
    int32_t *vertex_face_offsets, *vertex_faces;  /* CSR: faces around each vertex */
    int32_t *vertex_edge_offsets, *vertex_edges;  /* CSR: edges around each vertex */
    int32_t *cut_degree;
    uint8_t *on_chain;          /* 1: a chain vertex that may move, 2: a fixed chain vertex */
    surface_point *where;       /* vertex_count */
    double *original_normals;   /* face_count x 3, unnormalized (twice the area) */
    int32_t *ring;              /* scratch for one-rings */
    int32_t ring_capacity;
    int32_t *faces_near;        /* scratch: faces within two rings */
    uint8_t *face_mark;         /* face_count scratch marks */
    int32_t faces_near_capacity;
} truing;

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: truing: out of memory");
}

static void face_normal(const double *positions, const int32_t *face, double *normal)
{
    double e1[3], e2[3];
    pz_vec3_sub(positions + 3 * face[1], positions + 3 * face[0], e1);
    pz_vec3_sub(positions + 3 * face[2], positions + 3 * face[0], e2);
    pz_vec3_cross(e1, e2, normal);
}

/* CSR adjacency: for each vertex, the faces (or edges) around it, in increasing order. */
static pz_status build_adjacency(truing *t, pz_ctx *ctx)
{
    const pz_topology *top = t->topology;
    int32_t nv = t->mesh->vertex_count, nf = t->mesh->face_count, ne = top->edge_count;
    t->vertex_face_offsets = calloc((size_t)nv + 2, sizeof(int32_t));
    t->vertex_faces = malloc((size_t)3 * nf * sizeof(int32_t) + 1);
    t->vertex_edge_offsets = calloc((size_t)nv + 2, sizeof(int32_t));
    t->vertex_edges = malloc((size_t)2 * ne * sizeof(int32_t) + 1);
    if (!t->vertex_face_offsets || !t->vertex_faces || !t->vertex_edge_offsets || !t->vertex_edges)
        return nomem(ctx);
    for (int32_t i = 0; i < 3 * nf; ++i)
        ++t->vertex_face_offsets[t->mesh->faces[i] + 2];
    for (int32_t v = 0; v < nv; ++v)
        t->vertex_face_offsets[v + 2] += t->vertex_face_offsets[v + 1];
    for (int32_t i = 0; i < 3 * nf; ++i)
        t->vertex_faces[t->vertex_face_offsets[t->mesh->faces[i] + 1]++] = i / 3;
    for (int32_t e = 0; e < ne; ++e) {
        int32_t h = top->edge_halfedge[2 * e];
        ++t->vertex_edge_offsets[pz_he_from(top, h) + 2];
        ++t->vertex_edge_offsets[pz_he_to(top, h) + 2];
    }
    for (int32_t v = 0; v < nv; ++v)
        t->vertex_edge_offsets[v + 2] += t->vertex_edge_offsets[v + 1];
    for (int32_t e = 0; e < ne; ++e) {
        int32_t h = top->edge_halfedge[2 * e];
        t->vertex_edges[t->vertex_edge_offsets[pz_he_from(top, h) + 1]++] = e;
        t->vertex_edges[t->vertex_edge_offsets[pz_he_to(top, h) + 1]++] = e;
    }
    return PZ_OK;
}

static int32_t edge_other(const pz_topology *top, int32_t e, int32_t v)
{
    int32_t h = top->edge_halfedge[2 * e];
    int32_t a = pz_he_from(top, h), b = pz_he_to(top, h);
    return a == v ? b : a;
}

/* ---------------------------------------------------------------- projection */

/* The faces within two rings of vertex v (faces around v and around its neighbours) into t->faces_near. */
static int32_t faces_near(truing *t, int32_t v)
{
    int32_t count = 0;
    for (int32_t i = t->vertex_face_offsets[v]; i < t->vertex_face_offsets[v + 1]; ++i) {
        const int32_t *face = t->mesh->faces + 3 * t->vertex_faces[i];
        for (int k = 0; k < 3; ++k) {
            int32_t u = face[k];
            for (int32_t j = t->vertex_face_offsets[u]; j < t->vertex_face_offsets[u + 1]; ++j) {
                int32_t f = t->vertex_faces[j];
                if (t->face_mark[f] || count >= t->faces_near_capacity)
                    continue;
                t->face_mark[f] = 1;
                t->faces_near[count++] = f;
            }
        }
    }
    for (int32_t i = 0; i < count; ++i)
        t->face_mark[t->faces_near[i]] = 0;
    return count;
}

/* Projects p onto the original surface near vertex v: writes the point and where it lies. */
static void project(truing *t, int32_t v, const double *p, double *out, surface_point *at)
{
    int32_t count = faces_near(t, v);
    double best = INFINITY;
    at->face = -1;
    for (int32_t i = 0; i < count; ++i) {
        int32_t f = t->faces_near[i];
        const int32_t *face = t->mesh->faces + 3 * f;
        double bary[3], q[3];
        pz_geom_closest_on_triangle(p, t->rest + 3 * face[0], t->rest + 3 * face[1], t->rest + 3 * face[2], bary);
        for (int d = 0; d < 3; ++d)
            q[d] = bary[0] * t->rest[3 * face[0] + d] + bary[1] * t->rest[3 * face[1] + d] +
                   bary[2] * t->rest[3 * face[2] + d];
        double distance = pz_vec3_distance(p, q);
        if (distance < best) {
            best = distance;
            memcpy(out, q, sizeof q);
            at->face = f;
            memcpy(at->bary, bary, sizeof bary);
        }
    }
    if (at->face < 0)
        memcpy(out, t->rest + 3 * v, 3 * sizeof(double));
}

/* Moves v towards target (clamped to `limit` from its original position), projected onto the surface. */
static void move_vertex(truing *t, int32_t v, const double *target, double limit)
{
    double step[3], clamped[3];
    pz_vec3_sub(target, t->rest + 3 * v, step);
    double length = pz_vec3_norm(step);
    double scale = length > limit ? limit / length : 1;
    for (int d = 0; d < 3; ++d)
        clamped[d] = t->rest[3 * v + d] + scale * step[d];
    project(t, v, clamped, t->mesh->positions + 3 * v, &t->where[v]);
}

static double shortest_edge(const truing *t, int32_t v)
{
    double shortest = INFINITY;
    for (int32_t i = t->vertex_edge_offsets[v]; i < t->vertex_edge_offsets[v + 1]; ++i) {
        int32_t other = edge_other(t->topology, t->vertex_edges[i], v);
        shortest = fmin(shortest, pz_vec3_distance(t->rest + 3 * v, t->rest + 3 * other));
    }
    return isfinite(shortest) ? shortest : 0;
}

/* ---------------------------------------------------------------- chains */

/* The unit normal of the original surface at v (area-weighted face normals). */
static void vertex_normal(const truing *t, int32_t v, double normal[3])
{
    normal[0] = normal[1] = normal[2] = 0;
    for (int32_t i = t->vertex_face_offsets[v]; i < t->vertex_face_offsets[v + 1]; ++i)
        for (int d = 0; d < 3; ++d)
            normal[d] += t->original_normals[3 * t->vertex_faces[i] + d];
    double length = pz_vec3_norm(normal);
    for (int d = 0; d < 3; ++d)
        normal[d] = length > 0 ? normal[d] / length : 0;
}

/* The turn at `at` in the surface's tangent plane (the geodesic turn: a seam that bends only with the
 * surface, round a body, turns by 0). */
static double tangent_turn_deg(const truing *t, int32_t v, const double *before, const double *at, const double *after)
{
    double normal[3], a[3], b[3];
    vertex_normal(t, v, normal);
    pz_vec3_sub(at, before, a);
    pz_vec3_sub(after, at, b);
    double na = pz_vec3_dot(a, normal), nb = pz_vec3_dot(b, normal);
    for (int d = 0; d < 3; ++d) {
        a[d] -= na * normal[d];
        b[d] -= nb * normal[d];
    }
    double la = pz_vec3_norm(a), lb = pz_vec3_norm(b);
    if (!(la > 0) || !(lb > 0))
        return 0;
    double c = pz_vec3_dot(a, b) / (la * lb);
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180 / PZ_PI;
}

/* Summed tangential turn between consecutive edges of a chain (positions), and the number of turns. */
static double chain_turns(const truing *t, const double *positions, const int32_t *chain, int32_t n, int closed,
                          int32_t *turns)
{
    double sum = 0;
    *turns = 0;
    for (int32_t i = closed ? 0 : 1; i < (closed ? n : n - 1); ++i) {
        int32_t prev = chain[(i + n - 1) % n], next = chain[(i + 1) % n];
        sum += tangent_turn_deg(t, chain[i], positions + 3 * prev, positions + 3 * chain[i], positions + 3 * next);
        ++*turns;
    }
    return sum;
}

/*
 * Smooths one chain (n vertices, closed or not) and moves its free vertices.
 * fixed[i] marks ends and corners.
 */
static void true_chain(truing *t, const int32_t *chain, int32_t n, int closed, uint8_t *fixed, double *points,
                       double *scratch, const pz_truing_options *options)
{
    const double *rest = t->rest;
    int window = CORNER_WINDOW;
    for (int32_t i = 0; i < n; ++i) {
        fixed[i] = !closed && (i == 0 || i == n - 1);
        if (fixed[i])
            continue;
        int32_t before = closed ? chain[(i - window + n) % n] : chain[i - window < 0 ? 0 : i - window];
        int32_t after = closed ? chain[(i + window) % n] : chain[i + window > n - 1 ? n - 1 : i + window];
        if (tangent_turn_deg(t, chain[i], rest + 3 * before, rest + 3 * chain[i], rest + 3 * after) > options->corner_deg)
            fixed[i] = 1;
    }
    for (int32_t i = 0; i < n; ++i)
        memcpy(points + 3 * i, rest + 3 * chain[i], 3 * sizeof(double));
    for (int pass = 0; pass < 2 * options->passes; ++pass) {
        double factor = pass % 2 ? TAUBIN_MU : TAUBIN_LAMBDA;
        for (int32_t i = 0; i < n; ++i) {
            if (fixed[i]) {
                memcpy(scratch + 3 * i, points + 3 * i, 3 * sizeof(double));
                continue;
            }
            const double *a = points + 3 * ((i + n - 1) % n), *b = points + 3 * ((i + 1) % n), *p = points + 3 * i;
            for (int d = 0; d < 3; ++d)
                scratch[3 * i + d] = p[d] + factor * ((a[d] + b[d]) / 2 - p[d]);
        }
        memcpy(points, scratch, (size_t)3 * n * sizeof(double));
    }
    for (int32_t i = 0; i < n; ++i) {
        int32_t v = chain[i];
        if (fixed[i] || t->topology->vertex_on_boundary[v]) {
            t->on_chain[v] = 2;
            continue;
        }
        move_vertex(t, v, points + 3 * i, options->max_move_rel * shortest_edge(t, v));
    }
}

/* Walks the chain starting with edge `first` from node `start`; returns its vertex count. */
static int32_t walk_chain(truing *t, int32_t start, int32_t first, uint8_t *edge_done, int32_t *chain, int *closed)
{
    const pz_topology *top = t->topology;
    int32_t n = 0, v = start, e = first;
    chain[n++] = v;
    *closed = 0;
    for (;;) {
        edge_done[e] = 1;
        v = edge_other(top, e, v);
        if (v == start) {
            *closed = 1;
            return n;
        }
        chain[n++] = v;
        if (t->cut_degree[v] != 2 || top->vertex_on_boundary[v])
            return n;
        int32_t next = -1;
        for (int32_t i = t->vertex_edge_offsets[v]; i < t->vertex_edge_offsets[v + 1] && next < 0; ++i) {
            int32_t candidate = t->vertex_edges[i];
            if (t->edge_cut[candidate] && !edge_done[candidate])
                next = candidate;
        }
        if (next < 0)
            return n;
        e = next;
    }
}

/* ---------------------------------------------------------------- relaxation and safety */

static void relax(truing *t, const uint8_t *relaxing, const pz_truing_options *options)
{
    int32_t nv = t->mesh->vertex_count;
    double *positions = t->mesh->positions;
    for (int it = 0; it < RELAX_ITERATIONS; ++it)
        for (int32_t v = 0; v < nv; ++v) {
            if (!relaxing[v])
                continue;
            int32_t count = pz_topology_vertex_ring(t->topology, v, t->ring, t->ring_capacity);
            if (count <= 0 || count > t->ring_capacity)
                continue;
            double centroid[3] = {0, 0, 0};
            for (int32_t i = 0; i < count; ++i)
                for (int d = 0; d < 3; ++d)
                    centroid[d] += positions[3 * t->ring[i] + d] / count;
            double target[3];
            for (int d = 0; d < 3; ++d)
                target[d] = positions[3 * v + d] + RELAX_STEP * (centroid[d] - positions[3 * v + d]);
            move_vertex(t, v, target, options->max_move_rel * shortest_edge(t, v));
        }
}

/* 1 when face f is acceptable at the current positions. */
static int face_ok(const truing *t, int32_t f)
{
    double normal[3];
    face_normal(t->mesh->positions, t->mesh->faces + 3 * f, normal);
    const double *original = t->original_normals + 3 * f;
    double area = pz_vec3_norm(normal), original_area = pz_vec3_norm(original);
    if (!(original_area > 0))
        return 1;
    return area >= MIN_AREA_RATIO * original_area &&
           pz_vec3_dot(normal, original) >= MIN_NORMAL_COS * area * original_area;
}

/* Sends the moved vertices of bad faces half-way back (or all the way in the last round). Returns bad faces. */
static int32_t settle(truing *t, int last_round)
{
    int32_t nf = t->mesh->face_count, bad = 0;
    for (int32_t f = 0; f < nf; ++f) {
        if (face_ok(t, f))
            continue;
        ++bad;
        const int32_t *face = t->mesh->faces + 3 * f;
        for (int k = 0; k < 3; ++k) {
            int32_t v = face[k];
            if (t->where[v].face < 0)
                continue;
            double target[3];
            for (int d = 0; d < 3; ++d)
                target[d] = last_round ? t->rest[3 * v + d] : (t->rest[3 * v + d] + t->mesh->positions[3 * v + d]) / 2;
            if (last_round) {
                memcpy(t->mesh->positions + 3 * v, target, sizeof target);
                t->where[v].face = -1;
            } else {
                project(t, v, target, t->mesh->positions + 3 * v, &t->where[v]);
            }
        }
    }
    return bad;
}

/* Every moved vertex's pose positions: the same barycentric combination of its face's original pose
 * positions (read from a copy: the face's corners may have moved too). */
static pz_status move_poses(truing *t, pz_ctx *ctx)
{
    pz_mesh *mesh = t->mesh;
    size_t size = (size_t)mesh->vertex_count * 3;
    double *original = mesh->pose_count ? malloc(size * sizeof(double)) : NULL;
    if (mesh->pose_count && !original)
        return nomem(ctx);
    for (int32_t pose = 0; pose < mesh->pose_count; ++pose) {
        double *positions = mesh->poses + (size_t)pose * size;
        memcpy(original, positions, size * sizeof(double));
        for (int32_t v = 0; v < mesh->vertex_count; ++v) {
            const surface_point *at = &t->where[v];
            if (at->face < 0)
                continue;
            const int32_t *face = mesh->faces + 3 * at->face;
            for (int d = 0; d < 3; ++d)
                positions[3 * v + d] = at->bary[0] * original[3 * face[0] + d] + at->bary[1] * original[3 * face[1] + d] +
                                       at->bary[2] * original[3 * face[2] + d];
        }
    }
    free(original);
    return PZ_OK;
}

static void truing_free(truing *t)
{
    free(t->rest);
    free(t->vertex_face_offsets);
    free(t->vertex_faces);
    free(t->vertex_edge_offsets);
    free(t->vertex_edges);
    free(t->cut_degree);
    free(t->on_chain);
    free(t->where);
    free(t->original_normals);
    free(t->ring);
    free(t->faces_near);
    free(t->face_mark);
}

static pz_status truing_init(truing *t, pz_ctx *ctx)
{
    pz_mesh *mesh = t->mesh;
    size_t nv = (size_t)mesh->vertex_count, nf = (size_t)mesh->face_count;
    t->rest = malloc(nv * 3 * sizeof(double) + 1);
    t->cut_degree = calloc(nv + 1, sizeof(int32_t));
    t->on_chain = calloc(nv + 1, 1);
    t->where = malloc((nv + 1) * sizeof(surface_point));
    t->original_normals = malloc(nf * 3 * sizeof(double) + 1);
    t->face_mark = calloc(nf + 1, 1);
    if (!t->rest || !t->cut_degree || !t->on_chain || !t->where || !t->original_normals || !t->face_mark)
        return nomem(ctx);
    pz_status status = build_adjacency(t, ctx);
    if (status)
        return status;
    memcpy(t->rest, mesh->positions, nv * 3 * sizeof(double));
    int32_t max_valence = 0, max_faces = 0;
    for (size_t v = 0; v < nv; ++v) {
        t->where[v].face = -1;
        int32_t valence = t->vertex_edge_offsets[v + 1] - t->vertex_edge_offsets[v];
        int32_t faces = t->vertex_face_offsets[v + 1] - t->vertex_face_offsets[v];
        max_valence = valence > max_valence ? valence : max_valence;
        max_faces = faces > max_faces ? faces : max_faces;
    }
    t->ring_capacity = max_valence + 2;
    t->faces_near_capacity = (max_valence + 1) * max_faces + 1;
    t->ring = malloc((size_t)t->ring_capacity * sizeof(int32_t));
    t->faces_near = malloc((size_t)t->faces_near_capacity * sizeof(int32_t));
    if (!t->ring || !t->faces_near)
        return nomem(ctx);
    for (size_t f = 0; f < nf; ++f)
        face_normal(mesh->positions, mesh->faces + 3 * f, t->original_normals + 3 * f);
    for (int32_t e = 0; e < t->topology->edge_count; ++e)
        if (t->edge_cut[e]) {
            int32_t h = t->topology->edge_halfedge[2 * e];
            ++t->cut_degree[pz_he_from(t->topology, h)];
            ++t->cut_degree[pz_he_to(t->topology, h)];
        }
    return PZ_OK;
}

/* Every chain of cut edges: vertices flattened in `vertices`, chain c is offsets[c] .. offsets[c+1]-1. */
typedef struct chain_set {
    int32_t count;
    int32_t *offsets;   /* count + 1 */
    int32_t *vertices;
    uint8_t *closed;    /* count */
} chain_set;

static void chain_set_clear(chain_set *chains)
{
    free(chains->offsets);
    free(chains->vertices);
    free(chains->closed);
    memset(chains, 0, sizeof *chains);
}

/* Open chains from the nodes first, then the closed loops left (all of cut degree 2). A chain has at
 * most edge_count + 1 vertices and there are at most edge_count chains. */
static pz_status collect_chains(truing *t, chain_set *chains, pz_ctx *ctx)
{
    const pz_topology *top = t->topology;
    int32_t nv = t->mesh->vertex_count, cut_edges = 0;
    for (int32_t e = 0; e < top->edge_count; ++e)
        cut_edges += t->edge_cut[e] != 0;
    uint8_t *edge_done = calloc((size_t)top->edge_count + 1, 1);
    chains->offsets = malloc(((size_t)cut_edges + 2) * sizeof(int32_t));
    chains->vertices = malloc(((size_t)2 * cut_edges + 1) * sizeof(int32_t));
    chains->closed = malloc((size_t)cut_edges + 1);
    if (!edge_done || !chains->offsets || !chains->vertices || !chains->closed) {
        free(edge_done);
        return nomem(ctx);
    }
    chains->offsets[0] = 0;
    for (int pass = 0; pass < 2; ++pass)
        for (int32_t v = 0; v < nv; ++v) {
            int node = t->cut_degree[v] != 2 || top->vertex_on_boundary[v];
            if (t->cut_degree[v] == 0 || (pass == 0 && !node))
                continue;
            for (int32_t i = t->vertex_edge_offsets[v]; i < t->vertex_edge_offsets[v + 1]; ++i) {
                int32_t e = t->vertex_edges[i];
                if (!t->edge_cut[e] || edge_done[e])
                    continue;
                int closed;
                int32_t first = chains->offsets[chains->count];
                int32_t n = walk_chain(t, v, e, edge_done, chains->vertices + first, &closed);
                chains->closed[chains->count] = (uint8_t)closed;
                chains->offsets[++chains->count] = first + n;
            }
        }
    free(edge_done);
    return PZ_OK;
}

/* Mean tangential turn between consecutive edges over all chains at the given positions. */
static double mean_turn(const truing *t, const chain_set *chains, const double *positions)
{
    double sum = 0;
    int32_t turns = 0;
    for (int32_t c = 0; c < chains->count; ++c) {
        int32_t count;
        sum += chain_turns(t, positions, chains->vertices + chains->offsets[c], chains->offsets[c + 1] - chains->offsets[c],
                           chains->closed[c], &count);
        turns += count;
    }
    return turns ? sum / turns : 0;
}

static pz_status true_all_chains(truing *t, const chain_set *chains, const pz_truing_options *options, pz_ctx *ctx)
{
    int32_t longest = 0;
    for (int32_t c = 0; c < chains->count; ++c)
        longest = chains->offsets[c + 1] - chains->offsets[c] > longest ? chains->offsets[c + 1] - chains->offsets[c]
                                                                          : longest;
    uint8_t *fixed = malloc((size_t)longest + 1);
    double *points = malloc(((size_t)longest + 1) * 3 * sizeof(double));
    double *scratch = malloc(((size_t)longest + 1) * 3 * sizeof(double));
    if (!fixed || !points || !scratch) {
        free(fixed), free(points), free(scratch);
        return nomem(ctx);
    }
    for (int32_t c = 0; c < chains->count; ++c) {
        int32_t n = chains->offsets[c + 1] - chains->offsets[c];
        if (n >= (chains->closed[c] ? 4 : 3))
            true_chain(t, chains->vertices + chains->offsets[c], n, chains->closed[c], fixed, points, scratch, options);
    }
    free(fixed), free(points), free(scratch);
    return PZ_OK;
}

pz_status pz_segment_true_seams(pz_mesh *mesh, const pz_topology *topology, const uint8_t *edge_cut,
                                const pz_truing_options *options, pz_truing_result *result, pz_ctx *ctx)
{
    if (!mesh || !topology || !edge_cut || topology->face_count != mesh->face_count)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: truing: no mesh, topology or cut edges");
    pz_truing_options settings = {0};
    if (options)
        settings = *options;
    if (settings.passes <= 0)
        settings.passes = DEFAULT_PASSES;
    if (!(settings.max_move_rel > 0))
        settings.max_move_rel = DEFAULT_MAX_MOVE_REL;
    if (!(settings.corner_deg > 0))
        settings.corner_deg = DEFAULT_CORNER_DEG;
    pz_truing_result outcome;
    memset(&outcome, 0, sizeof outcome);
    truing t;
    memset(&t, 0, sizeof t);
    t.mesh = mesh;
    t.topology = topology;
    t.edge_cut = edge_cut;
    chain_set chains = {0};
    pz_status status = truing_init(&t, ctx);
    if (!status)
        status = collect_chains(&t, &chains, ctx);
    if (!status) {
        outcome.chain_count = chains.count;
        outcome.mean_turn_before_deg = mean_turn(&t, &chains, t.rest);
        status = true_all_chains(&t, &chains, &settings, ctx);
    }
    uint8_t *relaxing = status ? NULL : calloc((size_t)mesh->vertex_count + 1, 1);
    if (!status && !relaxing)
        status = nomem(ctx);
    if (!status) {
        /* The neighbours of moved chain vertices (off the chains and the border) relax. */
        for (int32_t v = 0; v < mesh->vertex_count; ++v) {
            if (t.where[v].face < 0)
                continue;
            t.on_chain[v] = 1;
            ++outcome.moved_vertices;
        }
        for (int32_t v = 0; v < mesh->vertex_count; ++v) {
            if (t.on_chain[v] != 1)
                continue;
            int32_t count = pz_topology_vertex_ring(topology, v, t.ring, t.ring_capacity);
            for (int32_t i = 0; i < count && i < t.ring_capacity; ++i) {
                int32_t u = t.ring[i];
                if (!t.on_chain[u] && !t.cut_degree[u] && !topology->vertex_on_boundary[u])
                    relaxing[u] = 1;
            }
        }
        relax(&t, relaxing, &settings);
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            outcome.relaxed_vertices += relaxing[v] && t.where[v].face >= 0;
        for (int round = 0; round <= SAFETY_ROUNDS; ++round)
            if (settle(&t, round == SAFETY_ROUNDS) == 0)
                break;
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            if (t.where[v].face >= 0)
                outcome.max_move_mm =
                    fmax(outcome.max_move_mm, pz_vec3_distance(t.rest + 3 * v, mesh->positions + 3 * v));
        status = move_poses(&t, ctx);
        outcome.mean_turn_after_deg = mean_turn(&t, &chains, mesh->positions);
    }
    free(relaxing);
    chain_set_clear(&chains);
    truing_free(&t);
    if (!status && result)
        *result = outcome;
    return status;
}
