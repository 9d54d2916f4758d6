/*
 * prepare/decimate.c -- step 4 of the preparation (prepare/prepare.c):
 * decimation by thinning, when the mesh has more than 4x the faces
 * remeshing will produce: down to 2x, seams and outline locked, so
 * remeshing works on a small mesh. Thinning (rounds of independent
 * half-edge collapses, below) does the bulk in O(F) per round; CGAL edge
 * collapse (prepare/cgal_shim.cpp) finishes only when thinning stalls
 * (prepare/remesh.c decides).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
        prep_face_normal(p[0], p[1], p[2], before);
        prep_face_normal(q[0], q[1], q[2], after);
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
            longest[i] = fmax(longest[i], prep_squared_distance3(p, s->positions + 3 * (size_t)ring_a.vertex[j]));
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

pz_status prep_thin_out(const pz_cgal_surface *in, int32_t target_faces, double max_edge, pz_cgal_surface *out,
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
