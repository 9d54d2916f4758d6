/*
 * pipeline/mirror.c -- exact mirror pieces (docs/segment.md, "Exact mirror
 * pieces"): a layout made on one half of a garment and mirrored gives pairs
 * of panels that are mirror images, cut from one pattern piece ("Cut 2
 * (mirror)"), and panels crossed by the plane that are their own mirror
 * image (cut on the fold). The joint flattening makes them mirror images
 * only nearly (the garment is only nearly symmetric); here they are made
 * exact:
 *
 *  - anchors: the outline vertices whose garment vertex and its mirror
 *    (vertex_mirror) are each other's mirror, on the partner's outline (the
 *    same outline for a panel crossed by the plane), kept where they run in
 *    opposite cyclic orders (a reflection reverses the outline: the longest
 *    such run, O(n log n)); at least MIN_ANCHORS;
 *  - the 2D reflection that best maps the piece's anchors onto the
 *    partner's (a reflection about a line for a panel crossed by the plane);
 *  - each anchor pair moves to the average of the piece's point and the
 *    partner's point reflected back, and the partner's to its reflection;
 *    every other outline vertex slides onto the chord between its two
 *    anchors (at its own arc-length fraction): both outlines are then the
 *    same polyline through the anchors, one reflected, exactly (the move is
 *    a sagitta of a trued seam: tenths of a millimetre);
 *  - the interior follows the outline's displacement, harmonically (conjugate
 *    gradients on the panel's graph Laplacian, the outline fixed), so the
 *    flattening's strain changes only by the boundary's small move.
 *
 * The residual (the distance of every outline vertex of one piece to the
 * other's outline reflected, both ways) is measured after, on the final
 * pattern (pl_measure_pattern_symmetry).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MIN_ANCHORS 4
#define MIN_GAP_MM 5.0       /* a correspondence may land this far from the vertex's own point, or twice the anchors' */
#define STRAIN_SLACK 1.02   /* a piece already past the strain goal may get this much worse, no more */
#define CG_ITERATIONS 500
#define CG_TOLERANCE 1e-10  /* relative residual of the harmonic solve */

/* ---------------------------------------------------------------- outlines */

/* The longest boundary loop of each panel of the cut mesh (cut-mesh vertices in loop order). */
typedef struct outlines {
    pz_loops *loops;
    int32_t *panel_loop;    /* panel_count: the loop of each panel, -1 */
} outlines;

static void outlines_free(outlines *o)
{
    pz_loops_free(&o->loops);
    free(o->panel_loop);
}

static int outlines_build(const pz_pattern *pattern, const pz_topology *topology, outlines *o, pz_ctx *ctx)
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

typedef struct anchor {
    int32_t a, b;    /* positions in the piece's outline and in the partner's */
} anchor;

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

/* x -> M x + t, M a reflection matrix (det -1). */
typedef struct mirror2 {
    double m[2][2], t[2];
} mirror2;

static void apply(const mirror2 *r, const double *x, double *out)
{
    double y0 = r->m[0][0] * x[0] + r->m[0][1] * x[1] + r->t[0], y1 = r->m[1][0] * x[0] + r->m[1][1] * x[1] + r->t[1];
    out[0] = y0, out[1] = y1;
}

/* The inverse: M is its own inverse (symmetric, orthogonal), so x = M (y - t). */
static void apply_inverse(const mirror2 *r, const double *y, double *out)
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

#define CORNER_DEG 40.0   /* an outline vertex turning more is a corner: both outlines must have it as an anchor */
#define CORNER_ROUNDS 4
#define ANCHOR_SPACING 6.0 /* anchors at least this many of the outline's mean edges apart, corners aside */

/* Panel p's outline A, its partner q's outline B (the same for a panel crossed by the plane), the anchors between
 * them and the reflection through the anchors. */
typedef struct pairing {
    const int32_t *A, *B;
    int32_t na, nb;
    anchor *anchors;     /* room for na + nb */
    int32_t count;       /* 0: no pairing */
    mirror2 r;
    int involution;      /* 1: A == B */
} pairing;

static void pairing_free(pairing *pr)
{
    free(pr->anchors);
    pr->anchors = NULL;
    pr->count = 0;
}

/* The turn (degrees) of loop L at position i, from its uv. */
static double turn_deg(const int32_t *L, int32_t n, int32_t i, const double *uv)
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

/* The sharpest corner strictly between from and to on loop L (forward), or -1 when none turns by CORNER_DEG. */
static int32_t corner_between(const int32_t *L, int32_t n, int32_t from, int32_t to, const double *uv)
{
    int32_t best = -1;
    double best_turn = CORNER_DEG;
    for (int32_t i = (from + 1) % n; i != to; i = (i + 1) % n) {
        double turn = turn_deg(L, n, i, uv);
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
 * outline (turning more than CORNER_DEG) gets the point of the other outline
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
                apply(&pr->r, uv + 2 * pr->A[i], x);
                j = nearest_between(pr->B, pr->nb, to->b, from->b, x, uv);
            } else if (!pr->involution && (j = corner_between(pr->B, pr->nb, to->b, from->b, uv)) >= 0) {
                apply_inverse(&pr->r, uv + 2 * pr->B[j], x);
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
        int corner = turn_deg(pr->A, pr->na, x->a, uv) > CORNER_DEG || turn_deg(pr->B, pr->nb, x->b, uv) > CORNER_DEG;
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
static int pairing_make(const pz_pattern *pattern, const outlines *o, const int32_t *mirror, int32_t p, int32_t q,
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

/* ---------------------------------------------------------------- the outline made exact */



/* A stretch of an outline between two anchors as a polyline (its old uv points, mapped through `map` when given)
 * parametrised by arc length, 0 .. 1. */
typedef struct stretch {
    double *points;   /* 2 x count */
    double *at;       /* count: arc-length fraction of each point */
    int32_t count;
} stretch;

/* The vertices of loop L from position `from` to `to` (inclusive, cyclic; backward when step is -1). */
static int stretch_make(const int32_t *L, int32_t n, int32_t from, int32_t to, int step, const double *old,
                        const mirror2 *map, stretch *out)
{
    int32_t count = ((step > 0 ? to - from : from - to) % n + n) % n + 1;
    out->count = count;
    out->points = malloc((2 * (size_t)count + 2) * sizeof(double));
    out->at = malloc(((size_t)count + 1) * sizeof(double));
    if (!out->points || !out->at)
        return 0;
    double length = 0;
    for (int32_t k = 0, i = from; k < count; ++k, i = ((i + step) % n + n) % n) {
        if (map)
            apply_inverse(map, old + 2 * L[i], out->points + 2 * k);
        else
            memcpy(out->points + 2 * k, old + 2 * L[i], 2 * sizeof(double));
        if (k > 0)
            length += hypot(out->points[2 * k] - out->points[2 * k - 2], out->points[2 * k + 1] - out->points[2 * k - 1]);
        out->at[k] = length;
    }
    for (int32_t k = 0; k < count; ++k)
        out->at[k] = length > 0 ? out->at[k] / length : (count > 1 ? (double)k / (count - 1) : 0);
    return 1;
}

static void stretch_free(stretch *s)
{
    free(s->points), free(s->at);
}

/* The stretch's point at fraction t (linear between its points). */
static void stretch_at(const stretch *s, double t, double *out)
{
    int32_t k = 1;
    while (k < s->count - 1 && s->at[k] < t)
        ++k;
    double span = s->at[k] - s->at[k - 1], u = span > 0 ? (t - s->at[k - 1]) / span : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    for (int d = 0; d < 2; ++d)
        out[d] = s->points[2 * (k - 1) + d] + u * (s->points[2 * k + d] - s->points[2 * (k - 1) + d]);
}

/* The point of polyline points[0..n-1] (2D) closest to x, into out. */
static void closest_on_polyline(const double *points, int32_t n, const double *x, double *out)
{
    double best = INFINITY;
    memcpy(out, points, 2 * sizeof(double));
    for (int32_t k = 0; k + 1 < n; ++k) {
        const double *a = points + 2 * k, *b = points + 2 * k + 2;
        double ab[2] = {b[0] - a[0], b[1] - a[1]}, length2 = ab[0] * ab[0] + ab[1] * ab[1];
        double t = length2 > 0 ? ((x[0] - a[0]) * ab[0] + (x[1] - a[1]) * ab[1]) / length2 : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double q[2] = {a[0] + t * ab[0], a[1] + t * ab[1]}, d = hypot(x[0] - q[0], x[1] - q[1]);
        if (d < best)
            best = d, out[0] = q[0], out[1] = q[1];
    }
}

/*
 * The common curve between two anchors: the average, at equal arc-length
 * fractions, of the piece's stretch and the partner's reflected back (a
 * polyline through the fractions of both). Every vertex of either stretch
 * goes to the point of the curve closest to it (the partner's reflected
 * back, then again): both outlines are then samples of one curve, the
 * second reflected, and each vertex moves across the outline by half the two
 * pieces' difference there, not along it (a slide along the outline would
 * shear the triangles next to it).
 */
static int onto_common(const int32_t *A, int32_t na, const int32_t *B, int32_t nb, const anchor *from,
                       const anchor *to, const mirror2 *r, const double *old, double *uv)
{
    stretch sa, sb;
    memset(&sa, 0, sizeof sa), memset(&sb, 0, sizeof sb);
    int ok = stretch_make(A, na, from->a, to->a, 1, old, NULL, &sa) &&
             stretch_make(B, nb, from->b, to->b, -1, old, r, &sb);
    double *curve = ok ? malloc((2 * ((size_t)sa.count + sb.count) + 2) * sizeof(double)) : NULL;
    ok = ok && curve;
    int32_t n = 0;
    for (int32_t i = 0, j = 0; ok && (i < sa.count || j < sb.count);) { /* the union of the fractions, in order */
        double t = j >= sb.count || (i < sa.count && sa.at[i] <= sb.at[j]) ? sa.at[i++] : sb.at[j++];
        double p[2], q[2];
        stretch_at(&sa, t, p), stretch_at(&sb, t, q);
        curve[2 * n] = 0.5 * (p[0] + q[0]), curve[2 * n + 1] = 0.5 * (p[1] + q[1]);
        ++n;
    }
    /* The stretch's vertices from its first anchor (a corner anchor stays at its average, set before) up to the
     * next anchor (which starts the next stretch). */
    int corner = turn_deg(A, na, from->a, old) > CORNER_DEG || turn_deg(B, nb, from->b, old) > CORNER_DEG;
    for (int side = 0; ok && side < 2; ++side) {
        const stretch *own = side ? &sb : &sa;
        const int32_t *L = side ? B : A;
        int32_t length = side ? nb : na, start = side ? from->b : from->a, step = side ? -1 : 1;
        for (int32_t k = corner ? 1 : 0; k + 1 < own->count; ++k) {
            double c[2];
            closest_on_polyline(curve, n, own->points + 2 * k, c);
            int32_t v = L[((start + step * k) % length + length) % length];
            if (side)
                apply(r, c, uv + 2 * v);
            else
                memcpy(uv + 2 * v, c, sizeof c);
        }
    }
    free(curve);
    stretch_free(&sa), stretch_free(&sb);
    return ok;
}

/*
 * Makes outline B the exact reflection of outline A through the anchors (A ==
 * B for a panel crossed by the plane, whose anchors are then closed under
 * the pairing): anchor pairs to their averages, the other vertices onto the
 * common curves between them (onto_common). old: a copy of uv. 0 when out of
 * memory.
 */
static int exact_outlines(const int32_t *A, int32_t na, const int32_t *B, int32_t nb, const anchor *anchors,
                          int32_t count, const mirror2 *r, const double *old, double *uv)
{
    for (int32_t k = 0; k < count; ++k) {
        double back[2], target[2];
        apply_inverse(r, old + 2 * B[anchors[k].b], back);
        target[0] = 0.5 * (old[2 * A[anchors[k].a]] + back[0]);
        target[1] = 0.5 * (old[2 * A[anchors[k].a] + 1] + back[1]);
        memcpy(uv + 2 * A[anchors[k].a], target, sizeof target);
        apply(r, target, uv + 2 * B[anchors[k].b]);
    }
    int ok = 1;
    for (int32_t k = 0; k < count && ok; ++k)
        ok = onto_common(A, na, B, nb, anchors + k, anchors + (k + 1) % count, r, old, uv);
    return ok;
}

/* ---------------------------------------------------------------- the interior follows */

#define MIN_COTAN 0.01   /* cotan weights clamped: an obtuse angle must not make the system indefinite */

/* A panel's cut-mesh vertices, its faces, the cotan-weighted graph between them (CSR) and which are fixed. */
typedef struct panel_graph {
    int32_t count;
    int32_t *vertices;      /* count: cut-mesh vertices */
    int32_t *offsets;       /* count + 1 */
    int32_t *neighbours;    /* local indices */
    double *weights;        /* per neighbour entry: the edge's cotan weight */
    uint8_t *fixed;         /* count */
    int32_t face_count;
    int32_t *faces;         /* face_count x 3 local indices */
    double *cotan;          /* face_count x 3: half the cotangent opposite each edge k -> k+1 */
} panel_graph;

static void panel_graph_free(panel_graph *g)
{
    free(g->vertices), free(g->offsets), free(g->neighbours), free(g->weights), free(g->fixed);
    free(g->faces), free(g->cotan);
    memset(g, 0, sizeof *g);
}

/* Triangle f of the cut mesh laid flat (corner 0 at the origin, corner 1 on +x) and its half-cotangents. */
static void flat_triangle(const pz_mesh *mesh, int32_t f, double flat[6], double cotan[3])
{
    const double *x[3];
    for (int k = 0; k < 3; ++k)
        x[k] = mesh->positions + 3 * (size_t)mesh->faces[3 * f + k];
    double e1[3], e2[3], n[3];
    pz_vec3_sub(x[1], x[0], e1), pz_vec3_sub(x[2], x[0], e2), pz_vec3_cross(e1, e2, n);
    double l1 = pz_vec3_norm(e1), twice_area = pz_vec3_norm(n);
    flat[0] = flat[1] = 0;
    flat[2] = l1, flat[3] = 0;
    flat[4] = l1 > 0 ? pz_vec3_dot(e2, e1) / l1 : 0, flat[5] = l1 > 0 ? twice_area / l1 : 0;
    for (int k = 0; k < 3; ++k) { /* edge k -> k+1 is opposite corner k+2 */
        const double *o = flat + 2 * ((k + 2) % 3), *a = flat + 2 * k, *b = flat + 2 * ((k + 1) % 3);
        double u[2] = {a[0] - o[0], a[1] - o[1]}, v[2] = {b[0] - o[0], b[1] - o[1]};
        double cross = fabs(u[0] * v[1] - u[1] * v[0]);
        double c = cross > 0 ? (u[0] * v[0] + u[1] * v[1]) / cross : 0;
        cotan[k] = 0.5 * fmax(c, MIN_COTAN);
    }
}

/* The graph of panel p; local: cut-mesh vertex -> local index (-1 elsewhere; left as found). 0 when out of memory. */
static int panel_graph_build(const pz_pattern *pattern, const pz_topology *topology, int32_t p, int32_t *local,
                             panel_graph *g)
{
    memset(g, 0, sizeof *g);
    const pz_mesh *mesh = pattern->mesh;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        g->face_count += pattern->face_panel[f] == p;
    size_t faces = (size_t)g->face_count;
    g->vertices = malloc((3 * faces + 1) * sizeof(int32_t));
    g->faces = malloc((3 * faces + 1) * sizeof(int32_t));
    g->cotan = malloc((3 * faces + 1) * sizeof(double));
    int32_t *face_ids = malloc((faces + 1) * sizeof(int32_t));
    if (!g->vertices || !g->faces || !g->cotan || !face_ids) {
        free(face_ids);
        return 0;
    }
    for (int32_t f = 0, t = 0; f < mesh->face_count; ++f) {
        if (pattern->face_panel[f] != p)
            continue;
        face_ids[t] = f;
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * f + k];
            if (local[v] < 0)
                local[v] = g->count, g->vertices[g->count++] = v;
            g->faces[3 * t + k] = local[v];
        }
        double flat[6];
        flat_triangle(mesh, f, flat, g->cotan + 3 * (size_t)t);
        ++t;
    }
    g->offsets = calloc((size_t)g->count + 2, sizeof(int32_t));
    g->fixed = calloc((size_t)g->count + 1, 1);
    g->neighbours = malloc((6 * faces + 1) * sizeof(int32_t));
    g->weights = malloc((6 * faces + 1) * sizeof(double));
    int32_t *fill = calloc((size_t)g->count + 1, sizeof(int32_t));
    int ok = g->offsets && g->fixed && g->neighbours && g->weights && fill;
    /* Each edge once per direction: a half-edge (its weight and its twin's), a border half-edge's reverse too. */
    for (int pass = 0; ok && pass < 2; ++pass) {
        for (int32_t t = 0; t < g->face_count; ++t)
            for (int k = 0; k < 3; ++k) {
                int32_t h = 3 * face_ids[t] + k, twin = topology->twin[h];
                int32_t a = g->faces[3 * t + k], b = g->faces[3 * t + (k + 1) % 3];
                /* A border edge's two entries carry half its weight each: the sum below makes it whole. */
                double w = twin >= 0 ? g->cotan[3 * t + k] : 0.5 * g->cotan[3 * t + k];
                if (!pass) {
                    ++g->offsets[a + 1];
                    if (twin < 0)
                        ++g->offsets[b + 1];
                    continue;
                }
                g->neighbours[g->offsets[a] + fill[a]] = b, g->weights[g->offsets[a] + fill[a]++] = w;
                if (twin < 0)
                    g->neighbours[g->offsets[b] + fill[b]] = a, g->weights[g->offsets[b] + fill[b]++] = w;
            }
        if (!pass)
            for (int32_t i = 0; i < g->count; ++i)
                g->offsets[i + 1] += g->offsets[i];
    }
    free(fill), free(face_ids);
    if (!ok)
        return 0;
    /* An edge has an entry each way, a -> b from its face and b -> a from the twin's (for a border edge, from the
     * same face): the edge's weight is their sum, written into both. */
    for (int32_t i = 0; i < g->count; ++i)
        for (int32_t k = g->offsets[i]; k < g->offsets[i + 1]; ++k) {
            int32_t j = g->neighbours[k];
            for (int32_t l = g->offsets[j]; l < g->offsets[j + 1]; ++l)
                if (g->neighbours[l] == i && l != k) {
                    if (i < j) { /* sum once, write both */
                        double sum = g->weights[k] + g->weights[l];
                        g->weights[k] = g->weights[l] = sum;
                    }
                    break;
                }
        }
    for (int32_t i = 0; i < g->count; ++i)
        g->fixed[i] = topology->vertex_on_boundary[g->vertices[i]];
    return 1;
}

/* y = L x on the free vertices (the cotan Laplacian, fixed vertices as zero). */
static void laplacian(const panel_graph *g, const double *x, double *y)
{
    for (int32_t i = 0; i < g->count; ++i) {
        if (g->fixed[i]) {
            y[i] = 0;
            continue;
        }
        double sum = 0;
        for (int32_t k = g->offsets[i]; k < g->offsets[i + 1]; ++k) {
            int32_t j = g->neighbours[k];
            sum += g->weights[k] * (x[i] - (g->fixed[j] ? 0 : x[j]));
        }
        y[i] = sum;
    }
}

/*
 * Solves L d = rhs on the free vertices, the fixed ones holding their values
 * of d (moved to the right-hand side): conjugate gradients from d's free
 * values. 0 when out of memory.
 */
static int solve_free(const panel_graph *g, const double *rhs, double *d)
{
    int32_t n = g->count;
    double *r = malloc(((size_t)n + 1) * sizeof(double)), *p = malloc(((size_t)n + 1) * sizeof(double));
    double *q = malloc(((size_t)n + 1) * sizeof(double));
    if (!r || !p || !q) {
        free(r), free(p), free(q);
        return 0;
    }
    laplacian(g, d, q);
    double rr = 0, bb = 0;
    for (int32_t i = 0; i < n; ++i) {
        double b = 0;
        for (int32_t k = g->offsets[i]; !g->fixed[i] && k < g->offsets[i + 1]; ++k)
            if (g->fixed[g->neighbours[k]])
                b += g->weights[k] * d[g->neighbours[k]];
        b = g->fixed[i] ? 0 : b + (rhs ? rhs[i] : 0);
        r[i] = b - q[i];
        p[i] = r[i];
        rr += r[i] * r[i], bb += b * b;
    }
    for (int iteration = 0; iteration < CG_ITERATIONS && rr > CG_TOLERANCE * CG_TOLERANCE * (bb > 0 ? bb : 1); ++iteration) {
        laplacian(g, p, q);
        double pq = 0;
        for (int32_t i = 0; i < n; ++i)
            pq += p[i] * q[i];
        if (!(pq > 0))
            break;
        double alpha = rr / pq, next = 0;
        for (int32_t i = 0; i < n; ++i) {
            if (g->fixed[i])
                continue;
            d[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            next += r[i] * r[i];
        }
        for (int32_t i = 0; i < n; ++i)
            p[i] = g->fixed[i] ? 0 : r[i] + next / rr * p[i];
        rr = next;
    }
    free(r), free(p), free(q);
    return 1;
}

/*
 * The interior of panel p follows its outline's move (old -> uv): the
 * displacement extended harmonically (cotan weights). Not re-optimised: the
 * flattening's own interior is the best for its goals (an as-rigid-as-possible
 * relaxation, tried, doubled the strain of pieces whose outline moved by
 * 0.05 mm), and the outline moves by a fraction of the pieces' difference.
 * local: all -1, left so.
 */
static int follow(const pz_pattern *pattern, const pz_topology *topology, int32_t p, const double *old, double *uv,
                  int32_t *local)
{
    panel_graph g;
    int ok = panel_graph_build(pattern, topology, p, local, &g);
    double *x = ok ? malloc(((size_t)g.count + 1) * sizeof(double)) : NULL;
    double *y = ok ? malloc(((size_t)g.count + 1) * sizeof(double)) : NULL;
    ok = ok && x && y;
    for (int c = 0; ok && c < 2; ++c) { /* the displacement, harmonic, as the start */
        double *d = c ? y : x;
        for (int32_t i = 0; i < g.count; ++i)
            d[i] = g.fixed[i] ? uv[2 * g.vertices[i] + c] - old[2 * g.vertices[i] + c] : 0;
        ok = solve_free(&g, NULL, d);
        for (int32_t i = 0; i < g.count; ++i)
            d[i] += old[2 * g.vertices[i] + c];
    }
    for (int32_t i = 0; ok && i < g.count; ++i)
        if (!g.fixed[i])
            uv[2 * g.vertices[i]] = x[i], uv[2 * g.vertices[i] + 1] = y[i];
    for (int32_t i = 0; i < g.count; ++i)
        local[g.vertices[i]] = -1;
    free(x), free(y);
    panel_graph_free(&g);
    return ok;
}

/* ---------------------------------------------------------------- the pattern */

/* The largest warp or weft strain of panel p's triangles in uv (the grain along v, as the back-ends lay it). */
static double panel_strain(const pz_pattern *pattern, int32_t p, const double *uv)
{
    const pz_mesh *mesh = pattern->mesh;
    double worst = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        if (pattern->face_panel[f] != p)
            continue;
        const int32_t *c = mesh->faces + 3 * (size_t)f;
        double e1[3], e2[3], d1[2], d2[2];
        pz_vec3_sub(mesh->positions + 3 * (size_t)c[1], mesh->positions + 3 * (size_t)c[0], e1);
        pz_vec3_sub(mesh->positions + 3 * (size_t)c[2], mesh->positions + 3 * (size_t)c[0], e2);
        for (int k = 0; k < 2; ++k)
            d1[k] = uv[2 * c[1] + k] - uv[2 * c[0] + k], d2[k] = uv[2 * c[2] + k] - uv[2 * c[0] + k];
        double det = d1[0] * d2[1] - d1[1] * d2[0];
        if (!(fabs(det) > 0))
            return INFINITY;
        /* J = [e1 e2] [d1 d2]^-1: its columns are the 3D images of the u and v directions. */
        double ju[3], jv[3];
        for (int k = 0; k < 3; ++k) {
            ju[k] = (e1[k] * d2[1] - e2[k] * d1[1]) / det;
            jv[k] = (-e1[k] * d2[0] + e2[k] * d1[0]) / det;
        }
        worst = fmax(worst, fmax(fabs(pz_vec3_norm(ju) - 1), fabs(pz_vec3_norm(jv) - 1)));
    }
    return worst;
}

/* Puts panel p's uv back as it was (old). */
static void restore_panel(const pz_pattern *pattern, int32_t p, const double *old, double *uv)
{
    for (int32_t f = 0; f < pattern->mesh->face_count; ++f)
        for (int k = 0; pattern->face_panel[f] == p && k < 3; ++k) {
            int32_t v = pattern->mesh->faces[3 * (size_t)f + k];
            uv[2 * v] = old[2 * v], uv[2 * v + 1] = old[2 * v + 1];
        }
}

/* ---------------------------------------------------------------- the flattenings averaged */

/* What the averaging reads: the cut mesh's copies of each garment vertex (CSR), its topology, the plane. */
typedef struct correspondence {
    const pz_pattern *pattern;
    const pz_topology *topology;   /* of the cut mesh */
    const pz_symmetry *symmetry;
    int32_t *copy_start;           /* garment vertex count + 1 */
    int32_t *copies;               /* cut-mesh vertices by garment vertex */
} correspondence;

static void correspondence_free(correspondence *c)
{
    free(c->copy_start), free(c->copies);
}

static int correspondence_build(const pz_pattern *pattern, const pz_topology *topology, const pz_symmetry *symmetry,
                                correspondence *c)
{
    memset(c, 0, sizeof *c);
    c->pattern = pattern, c->topology = topology, c->symmetry = symmetry;
    int32_t garment = symmetry->vertex_count, n = pattern->mesh->vertex_count;
    c->copy_start = calloc((size_t)garment + 2, sizeof(int32_t));
    c->copies = malloc(((size_t)n + 1) * sizeof(int32_t));
    if (!c->copy_start || !c->copies)
        return 0;
    for (int32_t v = 0; v < n; ++v)
        if (pattern->vertex_origin[v] >= 0 && pattern->vertex_origin[v] < garment)
            ++c->copy_start[pattern->vertex_origin[v] + 2];
    for (int32_t g = 0; g < garment; ++g)
        c->copy_start[g + 2] += c->copy_start[g + 1];
    for (int32_t v = 0; v < n; ++v)
        if (pattern->vertex_origin[v] >= 0 && pattern->vertex_origin[v] < garment)
            c->copies[c->copy_start[pattern->vertex_origin[v] + 1]++] = v;
    return 1;
}

/* The panel of a cut-mesh vertex (any of its faces'). */
static int32_t vertex_panel(const correspondence *c, int32_t v)
{
    int32_t h = c->topology->vertex_halfedge[v];
    return h >= 0 ? c->pattern->face_panel[pz_he_face(h)] : -1;
}

/* The closest point to x among the faces around cut vertex v and its neighbours: uv interpolated there from uv. */
static void interpolate_near(const correspondence *c, int32_t v, const double *x, const double *uv, double out[2])
{
    const pz_topology *t = c->topology;
    const pz_mesh *mesh = c->pattern->mesh;
    double best = INFINITY;
    out[0] = uv[2 * v], out[1] = uv[2 * v + 1];
    int32_t start = t->vertex_halfedge[v], h = start;
    do { /* the neighbours of v, and v itself through each */
        int32_t centres[2] = {v, pz_he_to(t, h)};
        for (int k = 0; k < 2; ++k) {
            int32_t s = t->vertex_halfedge[centres[k]], g = s;
            do {
                const int32_t *corner = mesh->faces + 3 * (size_t)pz_he_face(g);
                double bary[3];
                pz_geom_closest_on_triangle(x, mesh->positions + 3 * (size_t)corner[0],
                                            mesh->positions + 3 * (size_t)corner[1],
                                            mesh->positions + 3 * (size_t)corner[2], bary);
                double q[3] = {0, 0, 0};
                for (int i = 0; i < 3; ++i)
                    for (int d = 0; d < 3; ++d)
                        q[d] += bary[i] * mesh->positions[3 * (size_t)corner[i] + d];
                double distance = pz_vec3_distance(x, q);
                if (distance < best) {
                    best = distance;
                    for (int d = 0; d < 2; ++d)
                        out[d] = bary[0] * uv[2 * corner[0] + d] + bary[1] * uv[2 * corner[1] + d] +
                                 bary[2] * uv[2 * corner[2] + d];
                }
                g = t->twin[pz_he_prev(g)];
            } while (g >= 0 && g != s);
        }
        h = t->twin[pz_he_prev(h)];
    } while (h >= 0 && h != start);
}

/*
 * The uv of panel `to` at the mirror image of cut vertex v, taken back by
 * `back` (r^-1 or r) into v's piece: the closest point around each copy, in
 * panel `to`, of v's garment vertex's mirror vertex, the one whose point
 * taken back lands nearest v's own. A vertex next to a cut has copies on both
 * of its sides, and its mirror image can fall on the faces of the wrong one
 * (a cut through the faces the plane crosses zig-zags across it): only the
 * flattening tells which side the image belongs to. 0 when the mirror vertex
 * has no copy in that panel (v's image falls outside it), or when the point
 * lands farther than `limit` from v's (the image found on the wrong side of
 * a cut whose other side holds no copy).
 */
static int mirrored_uv(const correspondence *c, int32_t v, int32_t to, const mirror2 *r, int inverse, double limit,
                       const double *uv, double out[2])
{
    int32_t g = c->pattern->vertex_origin[v], m = g >= 0 ? c->symmetry->vertex_mirror[g] : -1;
    if (m < 0)
        return 0;
    double image[3], best = INFINITY;
    pz_symmetry_reflect_point(c->symmetry, c->pattern->mesh->positions + 3 * (size_t)v, image);
    for (int32_t i = c->copy_start[m]; i < c->copy_start[m + 1]; ++i) {
        int32_t w = c->copies[i];
        if (vertex_panel(c, w) != to)
            continue;
        double here[2], back[2];
        interpolate_near(c, w, image, uv, here);
        if (inverse)
            apply_inverse(r, here, back);
        else
            apply(r, here, back);
        double gap = hypot(back[0] - uv[2 * v], back[1] - uv[2 * v + 1]);
        if (gap < best)
            best = gap, out[0] = back[0], out[1] = back[1];
    }
    return best <= limit;
}

/*
 * Both flattenings averaged through the surface correspondence: every vertex
 * of panel p moves to the mean of its point and the partner's point at its
 * mirror image, mapped back (r^-1), and the partner's likewise (r), from the
 * flattenings as they were (old). On an exactly symmetric garment the two
 * then are exact mirror images, interior included; on a nearly symmetric one
 * nearly, and the outline step finishes the job with small moves. Averaging
 * the whole field rather than only the outline keeps the strain: two near
 * copies of one flattening average to one as good. A vertex whose mirror
 * image falls outside the partner keeps its point.
 */
static void average_fields(const correspondence *c, const pairing *pr, int32_t p, int32_t q, const double *old,
                           double *uv)
{
    const pz_mesh *mesh = c->pattern->mesh;
    const mirror2 *r = &pr->r;
    double fit = 0; /* how far the two flattenings differ at the anchors: a correspondence farther off is wrong */
    for (int32_t k = 0; k < pr->count; ++k) {
        double x[2];
        apply(r, old + 2 * pr->A[pr->anchors[k].a], x);
        fit = fmax(fit, hypot(x[0] - old[2 * pr->B[pr->anchors[k].b]], x[1] - old[2 * pr->B[pr->anchors[k].b] + 1]));
    }
    double limit = fmax(MIN_GAP_MM, 2 * fit);
    for (int side = 0; side < 2; ++side) {
        int32_t from = side ? q : p, to = side ? p : q;
        if (side && p == q)
            break;
        for (int32_t f = 0; f < mesh->face_count; ++f) {
            if (c->pattern->face_panel[f] != from)
                continue;
            for (int k = 0; k < 3; ++k) {
                int32_t v = mesh->faces[3 * (size_t)f + k];
                double mapped[2] = {0, 0};
                if (!mirrored_uv(c, v, to, r, !side, limit, old, mapped))
                    continue;
                uv[2 * v] = 0.5 * (old[2 * v] + mapped[0]);
                uv[2 * v + 1] = 0.5 * (old[2 * v + 1] + mapped[1]);
            }
        }
    }
}

/*
 * Makes panel p and its partner q (q == p: crossed by the plane) exact mirror
 * images (average_fields, then exact_outlines with the interior following);
 * 1 when done. Not when that would push either past the strain goal S (or
 * one already past it by more than 2 % further): the garment's two sides
 * differ there by more than the pieces can absorb (the pair stays as
 * flattened, its residual reported). old: the pattern as flattened; mid:
 * scratch as large as uv.
 */
static int exact_pair(const correspondence *c, const outlines *o, int32_t p, int32_t q, double max_strain,
                      int32_t *positions[2], int32_t *local, const double *old, double *mid, double *uv)
{
    const pz_pattern *pattern = c->pattern;
    size_t values = 2 * (size_t)pattern->mesh->vertex_count;
    pairing pr;
    int done = pairing_make(pattern, o, c->symmetry->vertex_mirror, p, q, positions[0], positions[1], old, &pr) &&
               pr.count > 0;
    if (done) {
        average_fields(c, &pr, p, q, old, uv);
        memcpy(mid, uv, values * sizeof(double));
        done = exact_outlines(pr.A, pr.na, pr.B, pr.nb, pr.anchors, pr.count, &pr.r, mid, uv) &&
               follow(pattern, c->topology, p, mid, uv, local) &&
               (p == q || follow(pattern, c->topology, q, mid, uv, local));
    }
    for (int side = 0; done && side < 2; ++side) {
        int32_t panel = side ? q : p;
        done = panel_strain(pattern, panel, uv) <= fmax(max_strain, STRAIN_SLACK * panel_strain(pattern, panel, old));
    }
    if (!done) {
        restore_panel(pattern, p, old, uv);
        restore_panel(pattern, q, old, uv);
    }
    pairing_free(&pr);
    return done;
}

pz_status pl_exact_mirror_pieces(const pz_pattern *pattern, const pz_segment_result *segment, double max_strain,
                                 double *uv, int32_t *exact, int32_t *pieces, pz_ctx *ctx)
{
    *pieces = 0;
    *exact = 0;
    const pz_symmetry *symmetry = &segment->symmetry;
    if (!symmetry->found || !symmetry->vertex_mirror || segment->panel_count != pattern->panel_count)
        return PZ_OK;
    const pz_mesh *mesh = pattern->mesh;
    pz_topology *topology = NULL;
    outlines o;
    memset(&o, 0, sizeof o);
    int32_t *positions[2] = {malloc((2 * (size_t)symmetry->vertex_count + 1) * sizeof(int32_t)),
                             malloc((2 * (size_t)symmetry->vertex_count + 1) * sizeof(int32_t))};
    int32_t *local = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    double *old = malloc((2 * (size_t)mesh->vertex_count + 2) * sizeof(double));
    double *mid = malloc((2 * (size_t)mesh->vertex_count + 2) * sizeof(double));
    correspondence c;
    memset(&c, 0, sizeof c);
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_status status = positions[0] && positions[1] && local && old && mid ? pz_topology_build(mesh, &topology, &quiet)
                                                                            : PZ_ERR_NOMEM;
    if (status == PZ_OK && (!outlines_build(pattern, topology, &o, ctx) ||
                            !correspondence_build(pattern, topology, symmetry, &c)))
        status = PZ_ERR_NOMEM;
    if (status == PZ_OK) {
        memcpy(old, uv, 2 * (size_t)mesh->vertex_count * sizeof(double));
        for (int32_t g = 0; g < 2 * symmetry->vertex_count; ++g)
            positions[0][g] = positions[1][g] = -1;
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            local[v] = -1;
        for (int32_t p = 0; p < pattern->panel_count; ++p) {
            int32_t q = segment->panels[p].mirror_panel;
            int self = q == p, pair = q >= 0 && q != p && segment->panels[q].copy && !segment->panels[p].copy &&
                                     segment->panels[q].mirror_panel == p;
            if (self || pair) {
                ++*pieces;
                *exact += exact_pair(&c, &o, p, q, max_strain, positions, local, old, mid, uv);
            }
        }
    }
    outlines_free(&o);
    correspondence_free(&c);
    pz_topology_free(&topology);
    free(positions[0]), free(positions[1]), free(local), free(old), free(mid);
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: out of memory making the mirror pieces exact");
    if (status != PZ_OK) /* a cut mesh without topology: leave the pieces as flattened */
        return PZ_OK;
    return PZ_OK;
}

/* ---------------------------------------------------------------- the residual */

/* Distance from point x to the closed polygon of loop L (n vertices) with points mapped through r (NULL: as is). */
static double to_polygon(const double *x, const int32_t *L, int32_t n, const double *uv, const mirror2 *r)
{
    double best = INFINITY, a[2], b[2];
    for (int32_t i = 0; i < n; ++i) {
        if (r)
            apply(r, uv + 2 * L[i], a), apply(r, uv + 2 * L[(i + 1) % n], b);
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
    if (!pairing_make(pattern, o, mirror, p, q, positions[0], positions[1], uv, &pr))
        return 0;
    for (int32_t i = 0; pr.count > 0 && i < pr.na; ++i) { /* A reflected against B */
        double x[2];
        apply(&pr.r, uv + 2 * pr.A[i], x);
        double d = to_polygon(x, pr.B, pr.nb, uv, NULL);
        *sum += d * d, ++*count, *largest = fmax(*largest, d);
    }
    for (int32_t j = 0; pr.count > 0 && j < pr.nb; ++j) { /* B against A reflected */
        double d = to_polygon(uv + 2 * pr.B[j], pr.A, pr.na, uv, &pr.r);
        *sum += d * d, ++*count, *largest = fmax(*largest, d);
    }
    pairing_free(&pr);
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
    if (status == PZ_OK && !outlines_build(pattern, topology, &o, ctx))
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
    outlines_free(&o);
    pz_topology_free(&topology);
    free(positions[0]), free(positions[1]);
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: out of memory measuring the mirror pieces");
    if (count > 0)
        *rms = sqrt(sum / count), *largest = worst;
    return PZ_OK;
}
