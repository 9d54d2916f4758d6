/*
 * pipeline/mirror_pairing.c -- the pairing of two outlines for the exact
 * mirror pieces (pipeline/mirror.c; docs/segment.md, "Exact mirror
 * pieces"): anchors (outline vertices whose garment vertices are each
 * other's mirror vertex, either way, kept where they run in opposite cyclic
 * orders, thinned to a few edges apart, the corners of either outline
 * added), the 2D reflection through them, and the residual of the final
 * pattern's mirror pieces (pl_mirror_residual).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/mirror_internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MIN_ANCHORS 4

/* ---------------------------------------------------------------- outlines */


void pl_outlines_free(outlines *o)
{
    pz_loops_free(&o->loops);
    free(o->panel_loop);
}

int pl_outlines_build(const pz_pattern *pattern, const pz_topology *topology, outlines *o, pz_ctx *ctx)
{
    memset(o, 0, sizeof *o);
    int32_t *vertex_panel = malloc(((size_t)pattern->mesh->vertex_count + 1) * sizeof(int32_t));
    o->panel_loop = malloc(((size_t)pattern->panel_count + 1) * sizeof(int32_t));
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    if (!vertex_panel || !o->panel_loop || pz_topology_boundary_loops(topology, &o->loops, &quiet) != PZ_OK) {
        free(vertex_panel);
        return 0;
    }
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            vertex_panel[pattern->mesh->faces[3 * f + k]] = pattern->face_panel[f];
    for (int32_t p = 0; p < pattern->panel_count; ++p)
        o->panel_loop[p] = -1;
    for (int32_t l = 0; l < o->loops->loop_count; ++l) {
        int32_t length = o->loops->loop_offsets[l + 1] - o->loops->loop_offsets[l];
        int32_t p = vertex_panel[o->loops->loop_vertices[o->loops->loop_offsets[l]]], best = o->panel_loop[p];
        if (best < 0 || length > o->loops->loop_offsets[best + 1] - o->loops->loop_offsets[best])
            o->panel_loop[p] = l;
    }
    free(vertex_panel);
    return 1;
}

/* ---------------------------------------------------------------- anchors */


/* Longest strictly increasing subsequence of keys[0..n-1] (O(n log n)); its indices into keep, returns its length. */
static int32_t longest_increasing(const int32_t *keys, int32_t n, int32_t *keep)
{
    int32_t *tail = malloc(((size_t)n + 1) * sizeof(int32_t)), *parent = malloc(((size_t)n + 1) * sizeof(int32_t));
    int32_t length = 0;
    if (!tail || !parent) {
        free(tail), free(parent);
        return 0;
    }
    for (int32_t i = 0; i < n; ++i) {
        int32_t lo = 0, hi = length;
        while (lo < hi) {
            int32_t mid = (lo + hi) / 2;
            if (keys[tail[mid]] < keys[i])
                lo = mid + 1;
            else
                hi = mid;
        }
        parent[i] = lo > 0 ? tail[lo - 1] : -1;
        tail[lo] = i;
        if (lo == length)
            ++length;
    }
    for (int32_t k = length - 1, i = length ? tail[length - 1] : -1; k >= 0; --k, i = parent[i])
        keep[k] = i;
    free(tail), free(parent);
    return length;
}

static int compare_candidate(const void *l, const void *r)
{
    const int32_t *x = l, *y = r; /* (a, key, b): a ascending, key descending */
    if (x[0] != y[0])
        return x[0] < y[0] ? -1 : 1;
    return (x[1] < y[1]) - (x[1] > y[1]);
}

/*
 * The anchors of outline A against outline B (B == A for a panel crossed by
 * the plane): pairs (A[i], B[j]) where one's garment vertex has the other's
 * as its mirror vertex (either way), B's positions from position_b and A's
 * from position_a (mark_positions; a garment vertex the outline holds twice
 * gives both, and a vertex of A is not its own partner), kept where they run
 * in opposite cyclic orders (the longest such run). Returns the count (0
 * when out of memory or fewer than MIN_ANCHORS).
 */
static int32_t find_anchors(const int32_t *A, int32_t na, const int32_t *B, int32_t nb, const int32_t *origin,
                            const int32_t *mirror, const int32_t *position_a, const int32_t *position_b, anchor *out)
{
    size_t room = 2 * ((size_t)na + nb) + 1;
    int32_t *candidates = malloc(3 * room * sizeof(int32_t)), count = 0;
    int32_t *keys = malloc(room * sizeof(int32_t)), *keep = malloc(room * sizeof(int32_t));
    if (!candidates || !keys || !keep) {
        free(candidates), free(keys), free(keep);
        return 0;
    }
    for (int side = 0; side < 2; ++side) {
        const int32_t *from = side ? B : A, *position = side ? position_a : position_b;
        for (int32_t i = 0; i < (side ? nb : na); ++i) {
            int32_t m = mirror[origin[from[i]]];
            for (int copy = 0; m >= 0 && copy < 2; ++copy) {
                int32_t j = position[2 * (size_t)m + copy];
                if (j < 0 || (A == B && j == i))
                    continue;
                candidates[3 * count] = side ? j : i, candidates[3 * count + 2] = side ? i : j;
                ++count;
            }
        }
    }
    int32_t kept = 0;
    if (count >= MIN_ANCHORS) {
        /* Opposite orders: as a runs forward, b runs backward, cyclically from the first candidate's b. */
        int32_t b0 = candidates[2];
        for (int32_t k = 0; k < count; ++k)
            candidates[3 * k + 1] = ((b0 - candidates[3 * k + 2]) % nb + nb) % nb;
        qsort(candidates, (size_t)count, 3 * sizeof(int32_t), compare_candidate);
        for (int32_t k = 0; k < count; ++k)
            keys[k] = candidates[3 * k + 1];
        kept = longest_increasing(keys, count, keep);
        for (int32_t k = 0; k < kept; ++k)
            out[k] = (anchor){candidates[3 * keep[k]], candidates[3 * keep[k] + 2]};
    }
    free(candidates), free(keys), free(keep);
    return kept >= MIN_ANCHORS ? kept : 0;
}

/* ---------------------------------------------------------------- the 2D reflection */


void pl_mirror2_apply(const mirror2 *r, const double *x, double *out)
{
    double y0 = r->m[0][0] * x[0] + r->m[0][1] * x[1] + r->t[0], y1 = r->m[1][0] * x[0] + r->m[1][1] * x[1] + r->t[1];
    out[0] = y0, out[1] = y1;
}

/* The inverse: M is its own inverse (symmetric, orthogonal), so x = M (y - t). */
void pl_mirror2_back(const mirror2 *r, const double *y, double *out)
{
    double d[2] = {y[0] - r->t[0], y[1] - r->t[1]};
    out[0] = r->m[0][0] * d[0] + r->m[0][1] * d[1];
    out[1] = r->m[1][0] * d[0] + r->m[1][1] * d[1];
}

/*
 * The reflection that best maps points a[k] onto b[k] (least squares,
 * Procrustes on the u-flipped points). involution: a reflection about a line
 * (the translation's part along the line, a glide, dropped), as a piece that
 * is its own mirror image needs.
 */
static mirror2 fit_reflection(const double *a, const double *b, int32_t n, int involution)
{
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t k = 0; k < n; ++k)
        ca[0] -= a[2 * k], ca[1] += a[2 * k + 1], cb[0] += b[2 * k], cb[1] += b[2 * k + 1];
    for (int d = 0; d < 2; ++d)
        ca[d] /= n, cb[d] /= n;
    double dot = 0, cross = 0;
    for (int32_t k = 0; k < n; ++k) {
        double x = -a[2 * k] - ca[0], y = a[2 * k + 1] - ca[1], u = b[2 * k] - cb[0], v = b[2 * k + 1] - cb[1];
        dot += x * u + y * v, cross += x * v - y * u;
    }
    double angle = atan2(cross, dot), c = cos(angle), s = sin(angle);
    mirror2 r;
    /* rotation(angle) . diag(-1, 1) */
    r.m[0][0] = -c, r.m[0][1] = -s, r.m[1][0] = -s, r.m[1][1] = c;
    r.t[0] = cb[0] - (c * ca[0] - s * ca[1]);
    r.t[1] = cb[1] - (s * ca[0] + c * ca[1]);
    if (involution) { /* keep t's part across the line: M t = -t */
        double mt[2] = {r.m[0][0] * r.t[0] + r.m[0][1] * r.t[1], r.m[1][0] * r.t[0] + r.m[1][1] * r.t[1]};
        r.t[0] = 0.5 * (r.t[0] - mt[0]), r.t[1] = 0.5 * (r.t[1] - mt[1]);
    }
    return r;
}

/* Positions of loop L's garment vertices in `position` (2 per garment vertex: where the loop holds it, and where
 * it holds it again: the two sides of a slit or of a seam the panel has with itself), or back to -1 (clear). */
static void mark_positions(const int32_t *L, int32_t n, const int32_t *origin, int32_t *position, int clear)
{
    for (int32_t i = 0; i < n; ++i) {
        int32_t *at = position + 2 * (size_t)origin[L[i]];
        if (clear)
            at[0] = at[1] = -1;
        else if (at[0] < 0)
            at[0] = i;
        else
            at[1] = i;
    }
}

/* ---------------------------------------------------------------- pairing two outlines */

#define CORNER_ROUNDS 4
#define ANCHOR_SPACING 6.0 /* anchors at least this many of the outline's mean edges apart, corners aside */


void pl_pairing_free(pairing *pr)
{
    free(pr->anchors);
    pr->anchors = NULL;
    pr->count = 0;
}

/* The turn (degrees) of loop L at position i, from its uv. */
double pl_turn_deg(const int32_t *L, int32_t n, int32_t i, const double *uv)
{
    const double *a = uv + 2 * L[(i + n - 1) % n], *b = uv + 2 * L[i], *c = uv + 2 * L[(i + 1) % n];
    double u[2] = {b[0] - a[0], b[1] - a[1]}, v[2] = {c[0] - b[0], c[1] - b[1]};
    return fabs(atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])) * 180 / PZ_PI;
}

static void pairing_fit(pairing *pr, const double *uv)
{
    double *a = malloc((2 * (size_t)pr->count + 2) * sizeof(double)), *b = malloc((2 * (size_t)pr->count + 2) * sizeof(double));
    if (!a || !b) {
        free(a), free(b);
        pr->count = 0;
        return;
    }
    for (int32_t k = 0; k < pr->count; ++k) {
        memcpy(a + 2 * k, uv + 2 * pr->A[pr->anchors[k].a], 2 * sizeof(double));
        memcpy(b + 2 * k, uv + 2 * pr->B[pr->anchors[k].b], 2 * sizeof(double));
    }
    pr->r = fit_reflection(a, b, pr->count, pr->involution);
    free(a), free(b);
}

/* The position strictly between from and to on loop L (forward, cyclic) whose point is nearest x (-1: none). */
static int32_t nearest_between(const int32_t *L, int32_t n, int32_t from, int32_t to, const double *x, const double *uv)
{
    int32_t best = -1;
    double best_d = INFINITY;
    for (int32_t i = (from + 1) % n; i != to; i = (i + 1) % n) {
        double d = hypot(uv[2 * L[i]] - x[0], uv[2 * L[i] + 1] - x[1]);
        if (d < best_d)
            best_d = d, best = i;
    }
    return best;
}

/* The sharpest corner strictly between from and to on loop L (forward), or -1 when none turns by PL_MIRROR_CORNER_DEG. */
static int32_t corner_between(const int32_t *L, int32_t n, int32_t from, int32_t to, const double *uv)
{
    int32_t best = -1;
    double best_turn = PL_MIRROR_CORNER_DEG;
    for (int32_t i = (from + 1) % n; i != to; i = (i + 1) % n) {
        double turn = pl_turn_deg(L, n, i, uv);
        if (turn > best_turn)
            best_turn = turn, best = i;
    }
    return best;
}

/* 1 when the anchors run in opposite cyclic orders (a forward, b backward), each a and b once. */
static int opposite_orders(const pairing *pr)
{
    for (int32_t k = 0; k < pr->count; ++k) {
        int32_t next = (k + 1) % pr->count;
        int32_t da = ((pr->anchors[next].a - pr->anchors[k].a) % pr->na + pr->na) % pr->na;
        int32_t db = ((pr->anchors[k].b - pr->anchors[next].b) % pr->nb + pr->nb) % pr->nb;
        if (pr->count > 1 && (da == 0 || db == 0))
            return 0;
    }
    int64_t turns_a = 0, turns_b = 0; /* the steps add up to one turn round each loop */
    for (int32_t k = 0; k < pr->count; ++k) {
        int32_t next = (k + 1) % pr->count;
        turns_a += ((pr->anchors[next].a - pr->anchors[k].a) % pr->na + pr->na) % pr->na;
        turns_b += ((pr->anchors[k].b - pr->anchors[next].b) % pr->nb + pr->nb) % pr->nb;
    }
    return turns_a == pr->na && turns_b == pr->nb;
}

static int compare_anchor(const void *l, const void *r)
{
    const anchor *x = l, *y = r;
    return (x->a > y->a) - (x->a < y->a);
}

/*
 * Corners anchored: between two anchors, the sharpest corner of either
 * outline (turning more than PL_MIRROR_CORNER_DEG) gets the point of the other outline
 * nearest its reflection as its partner. Otherwise the common curve between
 * the anchors (onto_common) would round a corner that both pieces have at
 * different arc-length fractions, and fold the triangles there. With A == B
 * the swapped pair goes in too; a round whose insertions break the opposite
 * orders is undone.
 */
static void anchor_corners(pairing *pr, const double *uv)
{
    anchor *before = malloc(((size_t)pr->na + pr->nb + 1) * sizeof(anchor));
    if (!before)
        return;
    for (int round = 0; round < CORNER_ROUNDS; ++round) {
        int32_t count = pr->count, added = 0;
        memcpy(before, pr->anchors, (size_t)count * sizeof(anchor));
        for (int32_t k = 0; k < count && pr->count + 2 <= pr->na + pr->nb; ++k) {
            const anchor *from = before + k, *to = before + (k + 1) % count;
            int32_t i = corner_between(pr->A, pr->na, from->a, to->a, uv), j = -1;
            double x[2];
            if (i >= 0) {
                pl_mirror2_apply(&pr->r, uv + 2 * pr->A[i], x);
                j = nearest_between(pr->B, pr->nb, to->b, from->b, x, uv);
            } else if (!pr->involution && (j = corner_between(pr->B, pr->nb, to->b, from->b, uv)) >= 0) {
                pl_mirror2_back(&pr->r, uv + 2 * pr->B[j], x);
                i = nearest_between(pr->A, pr->na, from->a, to->a, x, uv);
            }
            if (i < 0 || j < 0)
                continue;
            pr->anchors[pr->count++] = (anchor){i, j};
            if (pr->involution && i != j)
                pr->anchors[pr->count++] = (anchor){j, i};
            ++added;
        }
        if (!added)
            break;
        qsort(pr->anchors, (size_t)pr->count, sizeof(anchor), compare_anchor);
        int32_t unique = 0; /* a corner found from both of its stretches (involution) goes in once */
        for (int32_t k = 0; k < pr->count; ++k)
            if (unique == 0 || pr->anchors[k].a != pr->anchors[unique - 1].a || pr->anchors[k].b != pr->anchors[unique - 1].b)
                pr->anchors[unique++] = pr->anchors[k];
        pr->count = unique;
        if (!opposite_orders(pr)) {
            memcpy(pr->anchors, before, (size_t)count * sizeof(anchor));
            pr->count = count;
            break;
        }
        pairing_fit(pr, uv);
    }
    free(before);
}

/*
 * Anchors at least ANCHOR_SPACING edges apart (the outline's mean edge on A),
 * corners of either outline kept. The vertex pairs of vertex_mirror are
 * nearest vertices, each off its true partner by up to half an edge: anchored
 * everywhere, the outlines would be pulled a little each way at every vertex,
 * a ripple the interior cannot follow without local strain. Between sparse
 * anchors the common curve (onto_common) shifts the vertices smoothly. With
 * A == B the anchors stay closed under the swap (both of a pair are kept or
 * neither: decided on the one with the smaller a).
 */
static void thin_anchors(pairing *pr, const double *uv)
{
    double length = 0;
    for (int32_t i = 0; i < pr->na; ++i)
        length += hypot(uv[2 * pr->A[(i + 1) % pr->na]] - uv[2 * pr->A[i]],
                        uv[2 * pr->A[(i + 1) % pr->na] + 1] - uv[2 * pr->A[i] + 1]);
    double spacing = ANCHOR_SPACING * length / pr->na, along = 0, last = -INFINITY;
    uint8_t *keep = calloc((size_t)pr->count + 1, 1);
    if (!keep)
        return;
    int32_t k = 0;
    for (int32_t i = 0; i < pr->na && k < pr->count; ++i) {
        if (i > 0)
            along += hypot(uv[2 * pr->A[i]] - uv[2 * pr->A[i - 1]], uv[2 * pr->A[i] + 1] - uv[2 * pr->A[i - 1] + 1]);
        if (pr->anchors[k].a != i)
            continue;
        const anchor *x = pr->anchors + k;
        int corner = pl_turn_deg(pr->A, pr->na, x->a, uv) > PL_MIRROR_CORNER_DEG || pl_turn_deg(pr->B, pr->nb, x->b, uv) > PL_MIRROR_CORNER_DEG;
        if (corner || along - last >= spacing || x->a == x->b)
            keep[k] = 1, last = along;
        ++k;
    }
    if (pr->involution) /* the pair of a kept anchor is kept */
        for (int32_t k1 = 0; k1 < pr->count; ++k1)
            for (int32_t k2 = 0; keep[k1] && k2 < pr->count; ++k2)
                if (pr->anchors[k2].a == pr->anchors[k1].b && pr->anchors[k1].a < pr->anchors[k1].b)
                    keep[k2] = 1;
    if (pr->involution) /* and an anchor whose pair is dropped goes */
        for (int32_t k1 = 0; k1 < pr->count; ++k1)
            for (int32_t k2 = 0; keep[k1] && k2 < pr->count; ++k2)
                if (pr->anchors[k2].a == pr->anchors[k1].b && !keep[k2])
                    keep[k1] = 0;
    int32_t kept = 0;
    for (int32_t j = 0; j < pr->count; ++j)
        if (keep[j])
            pr->anchors[kept++] = pr->anchors[j];
    free(keep);
    if (kept >= MIN_ANCHORS)
        pr->count = kept;
}

/* For A == B: only anchors whose swapped pair is an anchor too (or on the line: a == b) stay. */
static void keep_paired(pairing *pr)
{
    int32_t kept = 0;
    for (int32_t k = 0; k < pr->count; ++k) {
        int paired = pr->anchors[k].a == pr->anchors[k].b;
        for (int32_t l = 0; l < pr->count && !paired; ++l)
            paired = pr->anchors[l].a == pr->anchors[k].b && pr->anchors[l].b == pr->anchors[k].a;
        if (paired)
            pr->anchors[kept++] = pr->anchors[k];
    }
    pr->count = kept >= MIN_ANCHORS ? kept : 0;
}

/*
 * Pairs panel p's outline with q's (q == p: crossed by the plane): anchors,
 * corners, the reflection. position_a, position_b: 2 x garment vertex count, all -1 (left so).
 * 0 when out of memory; pr->count 0 when the outlines cannot be paired.
 */
int pl_pairing_make(const pz_pattern *pattern, const outlines *o, const int32_t *mirror, int32_t p, int32_t q,
                        int32_t *position_a, int32_t *position_b, const double *uv, pairing *pr)
{
    memset(pr, 0, sizeof *pr);
    if (o->panel_loop[p] < 0 || o->panel_loop[q] < 0)
        return 1;
    pr->A = o->loops->loop_vertices + o->loops->loop_offsets[o->panel_loop[p]];
    pr->B = o->loops->loop_vertices + o->loops->loop_offsets[o->panel_loop[q]];
    pr->na = o->loops->loop_offsets[o->panel_loop[p] + 1] - o->loops->loop_offsets[o->panel_loop[p]];
    pr->nb = o->loops->loop_offsets[o->panel_loop[q] + 1] - o->loops->loop_offsets[o->panel_loop[q]];
    pr->involution = p == q;
    pr->anchors = malloc(((size_t)pr->na + pr->nb + 1) * sizeof(anchor));
    if (!pr->anchors)
        return 0;
    mark_positions(pr->A, pr->na, pattern->vertex_origin, position_a, 0);
    mark_positions(pr->B, pr->nb, pattern->vertex_origin, position_b, 0);
    pr->count = find_anchors(pr->A, pr->na, pr->B, pr->nb, pattern->vertex_origin, mirror, position_a, position_b,
                             pr->anchors);
    mark_positions(pr->A, pr->na, pattern->vertex_origin, position_a, 1);
    mark_positions(pr->B, pr->nb, pattern->vertex_origin, position_b, 1);
    if (pr->involution)
        keep_paired(pr);
    if (pr->count >= MIN_ANCHORS) {
        pairing_fit(pr, uv);
        thin_anchors(pr, uv);
        pairing_fit(pr, uv);
        anchor_corners(pr, uv);
    }
    return 1;
}

/* ---------------------------------------------------------------- the residual */

/* Distance from point x to the closed polygon of loop L (n vertices) with points mapped through r (NULL: as is). */
static double to_polygon(const double *x, const int32_t *L, int32_t n, const double *uv, const mirror2 *r)
{
    double best = INFINITY, a[2], b[2];
    for (int32_t i = 0; i < n; ++i) {
        if (r)
            pl_mirror2_apply(r, uv + 2 * L[i], a), pl_mirror2_apply(r, uv + 2 * L[(i + 1) % n], b);
        else
            memcpy(a, uv + 2 * L[i], sizeof a), memcpy(b, uv + 2 * L[(i + 1) % n], sizeof b);
        double ab[2] = {b[0] - a[0], b[1] - a[1]}, length2 = ab[0] * ab[0] + ab[1] * ab[1];
        double t = length2 > 0 ? ((x[0] - a[0]) * ab[0] + (x[1] - a[1]) * ab[1]) / length2 : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        best = fmin(best, hypot(x[0] - a[0] - t * ab[0], x[1] - a[1] - t * ab[1]));
    }
    return best;
}

/* Panel p against its partner q: the sum of squared outline distances both ways, their count and largest. */
static int pair_residual(const pz_pattern *pattern, const outlines *o, const int32_t *mirror, int32_t p, int32_t q,
                         int32_t *positions[2], const double *uv, double *sum, int32_t *count, double *largest)
{
    pairing pr;
    if (!pl_pairing_make(pattern, o, mirror, p, q, positions[0], positions[1], uv, &pr))
        return 0;
    for (int32_t i = 0; pr.count > 0 && i < pr.na; ++i) { /* A reflected against B */
        double x[2];
        pl_mirror2_apply(&pr.r, uv + 2 * pr.A[i], x);
        double d = to_polygon(x, pr.B, pr.nb, uv, NULL);
        *sum += d * d, ++*count, *largest = fmax(*largest, d);
    }
    for (int32_t j = 0; pr.count > 0 && j < pr.nb; ++j) { /* B against A reflected */
        double d = to_polygon(uv + 2 * pr.B[j], pr.A, pr.na, uv, &pr.r);
        *sum += d * d, ++*count, *largest = fmax(*largest, d);
    }
    pl_pairing_free(&pr);
    return 1;
}

pz_status pl_mirror_residual(const pz_pattern *pattern, const double *uv, const pz_segment_result *segment,
                             double *rms, double *largest, double *panel_largest, pz_ctx *ctx)
{
    *rms = *largest = -1;
    for (int32_t p = 0; panel_largest && p < pattern->panel_count; ++p)
        panel_largest[p] = -1;
    const pz_symmetry *symmetry = &segment->symmetry;
    if (!symmetry->found || !symmetry->vertex_mirror || segment->panel_count != pattern->panel_count)
        return PZ_OK;
    pz_topology *topology = NULL;
    outlines o;
    memset(&o, 0, sizeof o);
    int32_t *positions[2] = {malloc((2 * (size_t)symmetry->vertex_count + 1) * sizeof(int32_t)),
                             malloc((2 * (size_t)symmetry->vertex_count + 1) * sizeof(int32_t))};
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_status status = positions[0] && positions[1] ? pz_topology_build(pattern->mesh, &topology, &quiet) : PZ_ERR_NOMEM;
    if (status == PZ_OK && !pl_outlines_build(pattern, topology, &o, ctx))
        status = PZ_ERR_NOMEM;
    double sum = 0, worst = 0;
    int32_t count = 0;
    for (int32_t g = 0; status == PZ_OK && g < 2 * symmetry->vertex_count; ++g)
        positions[0][g] = positions[1][g] = -1;
    for (int32_t p = 0; status == PZ_OK && p < pattern->panel_count; ++p) {
        int32_t q = segment->panels[p].mirror_panel;
        if (!(q == p || (q > p && segment->panels[q].mirror_panel == p))) /* each pair once */
            continue;
        double pair_worst = 0;
        int32_t before = count;
        if (!pair_residual(pattern, &o, symmetry->vertex_mirror, p, q, positions, uv, &sum, &count, &pair_worst))
            status = PZ_ERR_NOMEM;
        worst = fmax(worst, pair_worst);
        if (panel_largest && count > before)
            panel_largest[p] = panel_largest[q] = pair_worst;
    }
    pl_outlines_free(&o);
    pz_topology_free(&topology);
    free(positions[0]), free(positions[1]);
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: out of memory measuring the mirror pieces");
    if (count > 0)
        *rms = sqrt(sum / count), *largest = worst;
    return PZ_OK;
}
