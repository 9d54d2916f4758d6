/*
 * pipeline/mirror.c -- exact mirror pieces (docs/segment.md, "Exact mirror
 * pieces"): a layout made on one half of a garment and mirrored gives pairs
 * of panels that are mirror images, cut from one pattern piece ("Cut 2
 * mirrored"), and panels crossed by the plane that are their own mirror
 * image (cut on the fold). The joint flattening makes them mirror images
 * only nearly (the garment is only nearly symmetric, the solver not exactly
 * symmetric); here they are made exact, pair by pair, through the pairing of
 * their outlines (anchors and the 2D reflection: pipeline/mirror_pairing.c):
 *
 *  - the flattenings averaged: every vertex moves to the mean of its point
 *    and the partner's point at its mirror image (through the surface: the
 *    closest point near the mirror vertex's copy), taken back through the
 *    reflection; on an exactly symmetric garment that alone makes the pair
 *    exact, interior included, and two near copies of one flattening average
 *    to one as good;
 *  - the outlines made one curve: between two anchors, the average of the two
 *    stretches at equal arc-length fractions; every outline vertex moves to
 *    its closest point on it (the partner's through the reflection), corner
 *    anchors to the curve's corner: both outlines sample one curve, exactly
 *    up to the sagitta of its chords;
 *  - the interior follows the outline's small move harmonically (cotan
 *    weights, conjugate gradients, the outline fixed);
 *  - a pair is kept as it was flattened when this would push a panel past
 *    the strain goal (the sides differ more than the pieces can absorb).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/mirror_internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MIN_GAP_MM 5.0       /* a correspondence may land this far from the vertex's own point, or twice the anchors' */
#define STRAIN_SLACK 1.02   /* a piece already past the strain goal may get this much worse, no more */
#define CG_ITERATIONS 500
#define CG_TOLERANCE 1e-10  /* relative residual of the harmonic solve */

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
            pl_mirror2_back(map, old + 2 * L[i], out->points + 2 * k);
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
    int corner = pl_turn_deg(A, na, from->a, old) > PL_MIRROR_CORNER_DEG || pl_turn_deg(B, nb, from->b, old) > PL_MIRROR_CORNER_DEG;
    for (int side = 0; ok && side < 2; ++side) {
        const stretch *own = side ? &sb : &sa;
        const int32_t *L = side ? B : A;
        int32_t length = side ? nb : na, start = side ? from->b : from->a, step = side ? -1 : 1;
        for (int32_t k = corner ? 1 : 0; k + 1 < own->count; ++k) {
            double c[2];
            closest_on_polyline(curve, n, own->points + 2 * k, c);
            int32_t v = L[((start + step * k) % length + length) % length];
            if (side)
                pl_mirror2_apply(r, c, uv + 2 * v);
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
        pl_mirror2_back(r, old + 2 * B[anchors[k].b], back);
        target[0] = 0.5 * (old[2 * A[anchors[k].a]] + back[0]);
        target[1] = 0.5 * (old[2 * A[anchors[k].a] + 1] + back[1]);
        memcpy(uv + 2 * A[anchors[k].a], target, sizeof target);
        pl_mirror2_apply(r, target, uv + 2 * B[anchors[k].b]);
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
            pl_mirror2_back(r, here, back);
        else
            pl_mirror2_apply(r, here, back);
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
        pl_mirror2_apply(r, old + 2 * pr->A[pr->anchors[k].a], x);
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
    int done = pl_pairing_make(pattern, o, c->symmetry->vertex_mirror, p, q, positions[0], positions[1], old, &pr) &&
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
    pl_pairing_free(&pr);
    return done;
}

/* ---------------------------------------------------------------- an exactly symmetric garment */

/* The garment's mirror map is exact when every vertex's mirror vertex lies at its reflection (the symmetrized
 * garment, pipeline/mirror_garment.c): within this (mm). */
#define EXACT_MAP_MM 1e-6

/* 1 when every cut-mesh vertex's garment vertex has its mirror vertex at its exact reflection. */
static int garment_exactly_symmetric(const correspondence *c)
{
    const pz_pattern *pattern = c->pattern;
    const pz_symmetry *symmetry = c->symmetry;
    for (int32_t v = 0; v < pattern->mesh->vertex_count; ++v) {
        int32_t g = pattern->vertex_origin[v], m = g >= 0 && g < symmetry->vertex_count ? symmetry->vertex_mirror[g] : -1;
        if (m < 0 || c->copy_start[m] == c->copy_start[m + 1])
            return 0;
        double image[3];
        pz_symmetry_reflect_point(symmetry, pattern->mesh->positions + 3 * (size_t)v, image);
        if (pz_vec3_distance(image, pattern->mesh->positions + 3 * (size_t)c->copies[c->copy_start[m]]) > EXACT_MAP_MM)
            return 0;
    }
    return 1;
}

/*
 * The cut-mesh vertex map of panel p onto q through the faces: corner k of a
 * face of p goes to the corner of its mirror face holding the mirror vertex
 * (exact on a symmetric garment whose layout is symmetric, copies along
 * darts and cuts included). map: cut vertex count, -1 outside p. 0 when a
 * face's image is not in q or a vertex would map to two.
 */
static int panel_vertex_map(const correspondence *c, int32_t p, int32_t q, int32_t *map)
{
    const pz_pattern *pattern = c->pattern;
    const pz_mesh *mesh = pattern->mesh;
    const pz_symmetry *symmetry = c->symmetry;
    if (symmetry->face_count != mesh->face_count)
        return 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        if (pattern->face_panel[f] != p)
            continue;
        int32_t image = symmetry->face_mirror[f];
        if (image < 0 || pattern->face_panel[image] != q)
            return 0;
        for (int k = 0; k < 3; ++k) {
            int32_t v = mesh->faces[3 * (size_t)f + k], mirror = symmetry->vertex_mirror[pattern->vertex_origin[v]];
            int32_t w = -1;
            for (int j = 0; j < 3; ++j)
                if (pattern->vertex_origin[mesh->faces[3 * (size_t)image + j]] == mirror)
                    w = mesh->faces[3 * (size_t)image + j];
            if (w < 0 || (map[v] >= 0 && map[v] != w))
                return 0;
            map[v] = w;
        }
    }
    return 1;
}

/* The reflection x -> M x + t (M = [[cos, sin], [sin, -cos]]) taking the points uv[v] closest to uv[map[v]], over
 * the vertices of `list` (least squares: the reflection Procrustes problem). */
static mirror2 fit_vertex_reflection(const int32_t *list, int32_t n, const int32_t *map, const double *uv)
{
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i)
        for (int d = 0; d < 2; ++d)
            ca[d] += uv[2 * list[i] + d] / n, cb[d] += uv[2 * map[list[i]] + d] / n;
    double sc = 0, ss = 0;
    for (int32_t i = 0; i < n; ++i) {
        double ax = uv[2 * list[i]] - ca[0], ay = uv[2 * list[i] + 1] - ca[1];
        double bx = uv[2 * map[list[i]]] - cb[0], by = uv[2 * map[list[i]] + 1] - cb[1];
        sc += bx * ax - by * ay, ss += bx * ay + by * ax;
    }
    double length = hypot(sc, ss);
    double cs = length > 0 ? sc / length : 1, sn = length > 0 ? ss / length : 0;
    mirror2 r = {{{cs, sn}, {sn, -cs}}, {0, 0}};
    r.t[0] = cb[0] - (r.m[0][0] * ca[0] + r.m[0][1] * ca[1]);
    r.t[1] = cb[1] - (r.m[1][0] * ca[0] + r.m[1][1] * ca[1]);
    return r;
}

/*
 * Panel p and its partner q (q == p: crossed by the plane) made exact mirror
 * images through the exact vertex map: the reflection fitted to the two
 * flattenings, each vertex of p moved to the mean of its point and its
 * image's point reflected back, and q's vertices to the reflections of p's.
 * For a panel crossed by the plane the map is an involution and the fitted
 * reflection too, so the mean is its own mirror image. Two near copies of one
 * flattening average to one as good. 0 when the map is not exact (the
 * layout is not symmetric there): the caller pairs the outlines instead.
 * map, list: cut vertex count each, map all -1 (left so).
 */
static int exact_pair_mapped(const correspondence *c, int32_t p, int32_t q, int32_t *map, int32_t *list,
                             double *uv)
{
    const pz_mesh *mesh = c->pattern->mesh;
    int ok = panel_vertex_map(c, p, q, map);
    int32_t n = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (map[v] >= 0)
            list[n++] = v;
    for (int32_t i = 0; ok && p == q && i < n; ++i) /* an involution on p's vertices */
        ok = map[map[list[i]]] == list[i];
    if (ok && n > 0) {
        mirror2 r = fit_vertex_reflection(list, n, map, uv);
        if (p == q) {
            double *mean = malloc((2 * (size_t)n + 1) * sizeof(double));
            if (!mean)
                ok = 0;
            for (int32_t i = 0; mean && i < n; ++i) {
                double back[2];
                pl_mirror2_back(&r, uv + 2 * map[list[i]], back);
                mean[2 * i] = 0.5 * (uv[2 * list[i]] + back[0]);
                mean[2 * i + 1] = 0.5 * (uv[2 * list[i] + 1] + back[1]);
            }
            for (int32_t i = 0; mean && i < n; ++i)
                memcpy(uv + 2 * list[i], mean + 2 * i, 2 * sizeof(double));
            free(mean);
        } else {
            for (int32_t i = 0; i < n; ++i) {
                int32_t v = list[i];
                double back[2];
                pl_mirror2_back(&r, uv + 2 * map[v], back);
                uv[2 * v] = 0.5 * (uv[2 * v] + back[0]);
                uv[2 * v + 1] = 0.5 * (uv[2 * v + 1] + back[1]);
                pl_mirror2_apply(&r, uv + 2 * v, uv + 2 * map[v]);
            }
        }
    }
    for (int32_t i = 0; i < n; ++i)
        map[list[i]] = -1;
    return ok && n > 0;
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
    int32_t *local_list = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    correspondence c;
    memset(&c, 0, sizeof c);
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_status status = positions[0] && positions[1] && local && old && mid ? pz_topology_build(mesh, &topology, &quiet)
                                                                            : PZ_ERR_NOMEM;
    if (status == PZ_OK && (!pl_outlines_build(pattern, topology, &o, ctx) ||
                            !correspondence_build(pattern, topology, symmetry, &c)))
        status = PZ_ERR_NOMEM;
    if (status == PZ_OK) {
        memcpy(old, uv, 2 * (size_t)mesh->vertex_count * sizeof(double));
        for (int32_t g = 0; g < 2 * symmetry->vertex_count; ++g)
            positions[0][g] = positions[1][g] = -1;
        for (int32_t v = 0; v < mesh->vertex_count; ++v)
            local[v] = -1;
        int mapped = local_list && garment_exactly_symmetric(&c);
        for (int32_t p = 0; p < pattern->panel_count; ++p) {
            int32_t q = segment->panels[p].mirror_panel;
            int self = q == p, pair = q >= 0 && q != p && segment->panels[q].copy && !segment->panels[p].copy &&
                                     segment->panels[q].mirror_panel == p;
            if (!self && !pair)
                continue;
            ++*pieces;
            if (mapped && exact_pair_mapped(&c, p, q, local, local_list, uv))
                ++*exact;
            else
                *exact += exact_pair(&c, &o, p, q, max_strain, positions, local, old, mid, uv);
        }
    }
    pl_outlines_free(&o);
    correspondence_free(&c);
    pz_topology_free(&topology);
    free(positions[0]), free(positions[1]), free(local), free(old), free(mid), free(local_list);
    if (status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: out of memory making the mirror pieces exact");
    if (status != PZ_OK) /* a cut mesh without topology: leave the pieces as flattened */
        return PZ_OK;
    return PZ_OK;
}

