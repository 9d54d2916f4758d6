/*
 * export/offset.c -- the cut line: a polygon offset outward by a distance per
 * edge, with the corners pattern makers draw and no loops.
 *
 * Method (the idea of Clipper's offsetting, done with an exact outer-face
 * walk instead of a winding-number fill):
 *  1. A raw offset curve C: every edge moved out by its distance; at a convex
 *     corner the two moved edges are joined by the mitre (while it stays
 *     within PZ_OFFSET_MITRE_LIMIT allowances), else cut off square at the
 *     allowance (the cap is perpendicular to the corner's bisector, so every
 *     point of it lies at least one allowance from the corner), or, where the
 *     allowance changes on a gentle corner, by an arc whose radius runs from
 *     one allowance to the other. At a concave corner the moved edges meet
 *     at their intersection when it lies on both; otherwise (short edges) C
 *     goes back through the corner itself (A -> p -> B).
 *  2. C may cross itself (concave parts where offsets overlap). Let U be the
 *     union of the polygon, every edge's strip (the rectangle between the edge
 *     and its moved copy) and every convex corner's join. Every boundary point
 *     of U lies on C (the strip sides at a corner lie inside the neighbouring
 *     strip or join), so the unbounded face of the arrangement of C is exactly
 *     the outside of U, and its boundary is the true cut line.
 *  3. The arrangement: every crossing of two segments (a sweep over the
 *     segments sorted by min x, keeping those whose x range is still open:
 *     O(n log n + n a) with a the few segments a vertical line meets), the
 *     segments split there, coincident nodes merged (union-find), neighbours
 *     sorted by angle. The outer face is walked from the leftmost node,
 *     always taking the rightmost turn (the first edge counter-clockwise from
 *     the way back), which keeps the outside on the right: the result is the
 *     outer boundary, counter-clockwise, touching itself at most at points.
 *
 * Memory: O(n + k) for n raw points and k crossings. Fails with PZ_ERR_NOMEM,
 * PZ_ERR_DATA (degenerate polygon), PZ_ERR_INTERNAL (walk did not close).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "export/offset.h"

#include "core/util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PZ_PI 3.14159265358979323846

/* ---------------------------------------------------------------- growable point list */

typedef struct point_list {
    double *xy;
    int32_t count;
    size_t capacity;
    int failed;
} point_list;

static void push(point_list *list, double x, double y)
{
    if (list->failed)
        return;
    if (!pz_grow((void **)&list->xy, &list->capacity, 2 * ((size_t)list->count + 1), sizeof(double))) {
        list->failed = 1;
        return;
    }
    list->xy[2 * list->count] = x;
    list->xy[2 * list->count + 1] = y;
    ++list->count;
}

double pz_polygon_signed_area(const double *points, int32_t count)
{
    double twice = 0;
    for (int32_t i = 0; i < count; ++i) {
        const double *a = &points[2 * i], *b = &points[2 * ((i + 1) % count)];
        twice += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * twice;
}

/* ---------------------------------------------------------------- raw offset curve */

typedef struct corner {
    double p[2];
    double u1[2], n1[2], d1, len1;   /* incoming edge: direction, outward normal, allowance, length */
    double u2[2], n2[2], d2, len2;   /* outgoing edge */
} corner;

/* The two moved edges' intersection; 0 when they are (nearly) parallel. */
static int mitre_point(const corner *c, double m[2])
{
    if (fabs(c->d1 - c->d2) <= 1e-9 * (1 + c->d1)) {
        /* Equal allowances: along the bisector, stable for nearly straight corners. */
        double denominator = 1 + c->n1[0] * c->n2[0] + c->n1[1] * c->n2[1];
        if (denominator < 1e-12)
            return 0;
        m[0] = c->p[0] + c->d1 * (c->n1[0] + c->n2[0]) / denominator;
        m[1] = c->p[1] + c->d1 * (c->n1[1] + c->n2[1]) / denominator;
        return 1;
    }
    double det = c->n1[0] * c->n2[1] - c->n1[1] * c->n2[0];
    if (fabs(det) < 1e-6)
        return 0;
    m[0] = c->p[0] + (c->d1 * c->n2[1] - c->d2 * c->n1[1]) / det;
    m[1] = c->p[1] + (c->n1[0] * c->d2 - c->n2[0] * c->d1) / det;
    return 1;
}

/* Square cap: the moved edges cut by the line perpendicular to the bisector at the larger allowance. */
static void square_cap(const corner *c, point_list *out)
{
    double b[2] = {c->n1[0] + c->n2[0], c->n1[1] + c->n2[1]};
    double length = hypot(b[0], b[1]);
    if (length < 1e-9) {  /* a spike turning back on itself: cap straight ahead */
        b[0] = c->u1[0];
        b[1] = c->u1[1];
    } else {
        b[0] /= length;
        b[1] /= length;
    }
    double cap = fmax(c->d1, c->d2);
    double a[2] = {c->p[0] + c->d1 * c->n1[0], c->p[1] + c->d1 * c->n1[1]};
    double e[2] = {c->p[0] + c->d2 * c->n2[0], c->p[1] + c->d2 * c->n2[1]};
    double t1 = (cap - c->d1 * (b[0] * c->n1[0] + b[1] * c->n1[1])) / (b[0] * c->u1[0] + b[1] * c->u1[1]);
    double t2 = (cap - c->d2 * (b[0] * c->n2[0] + b[1] * c->n2[1])) / (b[0] * c->u2[0] + b[1] * c->u2[1]);
    push(out, a[0] + t1 * c->u1[0], a[1] + t1 * c->u1[1]);
    push(out, e[0] + t2 * c->u2[0], e[1] + t2 * c->u2[1]);
}

/* Arc around the corner from the incoming to the outgoing normal, radius running d1 -> d2. */
static void blended_arc(const corner *c, point_list *out)
{
    double from = atan2(c->n1[1], c->n1[0]), turn = atan2(c->n2[1], c->n2[0]) - from;
    while (turn < 0)
        turn += 2 * PZ_PI;
    while (turn >= 2 * PZ_PI)
        turn -= 2 * PZ_PI;
    int steps = (int)ceil(turn / (5.0 * PZ_PI / 180.0));
    if (steps < 1)
        steps = 1;
    for (int j = 0; j <= steps; ++j) {
        double s = (double)j / steps, angle = from + s * turn, radius = c->d1 + s * (c->d2 - c->d1);
        push(out, c->p[0] + radius * cos(angle), c->p[1] + radius * sin(angle));
    }
}

/* 1 when m lies on both moved edges (within their lengths). */
static int on_both_moved_edges(const corner *c, const double m[2])
{
    double r[2] = {m[0] - c->p[0], m[1] - c->p[1]};
    double along_in = r[0] * c->u1[0] + r[1] * c->u1[1];    /* <= 0 and >= -len1 */
    double along_out = r[0] * c->u2[0] + r[1] * c->u2[1];   /* >= 0 and <= len2 */
    return along_in <= 1e-9 && along_in >= -c->len1 && along_out >= -1e-9 && along_out <= c->len2;
}

/*
 * 1 when m lies beyond the incoming edge's end and before the outgoing edge's
 * start: the corner's own region. With unequal allowances the mitre of a
 * convex corner can fall inside the wider edge's strip; it is then no join.
 */
static int in_wedge(const corner *c, const double m[2])
{
    double r[2] = {m[0] - c->p[0], m[1] - c->p[1]};
    return r[0] * c->u1[0] + r[1] * c->u1[1] >= -1e-9 && r[0] * c->u2[0] + r[1] * c->u2[1] <= 1e-9;
}

static void join_corner(const corner *c, point_list *out)
{
    double sine = c->u1[0] * c->u2[1] - c->u1[1] * c->u2[0];
    double cosine = c->u1[0] * c->u2[0] + c->u1[1] * c->u2[1];
    double a[2] = {c->p[0] + c->d1 * c->n1[0], c->p[1] + c->d1 * c->n1[1]};
    double b[2] = {c->p[0] + c->d2 * c->n2[0], c->p[1] + c->d2 * c->n2[1]};
    double m[2] = {c->p[0], c->p[1]};
    int has_mitre = mitre_point(c, m);
    int straight = fabs(sine) < 1e-9 && cosine > 0;
    if (sine > 0 || (fabs(sine) < 1e-9 && cosine <= 0) || (straight && !has_mitre)) {
        double limit = PZ_OFFSET_MITRE_LIMIT * fmax(c->d1, c->d2);
        if (has_mitre && hypot(m[0] - c->p[0], m[1] - c->p[1]) <= limit && in_wedge(c, m))
            push(out, m[0], m[1]);
        else if (fabs(c->d1 - c->d2) <= 1e-9 * (1 + c->d1) || cosine <= 0)
            square_cap(c, out);
        else
            blended_arc(c, out);
        return;
    }
    if (has_mitre && (straight || on_both_moved_edges(c, m))) {
        push(out, m[0], m[1]);
        return;
    }
    /* Concave with short edges: through the corner; the loop it makes lies inside U. */
    push(out, a[0], a[1]);
    push(out, c->p[0], c->p[1]);
    push(out, b[0], b[1]);
}

/*
 * Drops repeated points; an edge's allowance is kept with its start (distance
 * and d may be NULL: points only). Returns the count kept.
 */
static int32_t distinct_points(const double *points, const double *distance, int32_t count, double *xy, double *d)
{
    int32_t kept = 0;
    for (int32_t i = 0; i < count; ++i) {
        if (kept > 0 && hypot(points[2 * i] - xy[2 * kept - 2], points[2 * i + 1] - xy[2 * kept - 1]) < 1e-9) {
            if (d)
                d[kept - 1] = distance[i];
            continue;
        }
        xy[2 * kept] = points[2 * i];
        xy[2 * kept + 1] = points[2 * i + 1];
        if (d)
            d[kept] = distance[i];
        ++kept;
    }
    while (kept > 1 && hypot(xy[0] - xy[2 * kept - 2], xy[1] - xy[2 * kept - 1]) < 1e-9)
        --kept;
    return kept;
}

static void edge_frame(const double *xy, int32_t count, int32_t i, double u[2], double n[2], double *length)
{
    const double *a = &xy[2 * i], *b = &xy[2 * ((i + 1) % count)];
    *length = hypot(b[0] - a[0], b[1] - a[1]);
    u[0] = (b[0] - a[0]) / *length;
    u[1] = (b[1] - a[1]) / *length;
    n[0] = u[1];   /* right of the direction: outward for a counter-clockwise polygon */
    n[1] = -u[0];
}

static void raw_offset(const double *xy, const double *d, int32_t count, point_list *out)
{
    for (int32_t i = 0; i < count; ++i) {
        int32_t previous = (i + count - 1) % count;
        corner c;
        c.p[0] = xy[2 * i];
        c.p[1] = xy[2 * i + 1];
        edge_frame(xy, count, previous, c.u1, c.n1, &c.len1);
        edge_frame(xy, count, i, c.u2, c.n2, &c.len2);
        c.d1 = d[previous];
        c.d2 = d[i];
        join_corner(&c, out);
    }
}

/* ---------------------------------------------------------------- crossings */

typedef struct crossing {
    int32_t segment;
    int32_t node;
    double t;
} crossing;

typedef struct sweep {
    const double *xy;
    int32_t count;
    int32_t *order;     /* segments by min x */
    double *min_x, *max_x;
} sweep;

typedef struct keyed {
    double key;
    int32_t id;
} keyed;

static int compare_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return (x->key > y->key) - (x->key < y->key);
    return (x->id > y->id) - (x->id < y->id);
}

static int sweep_init(sweep *s, const double *xy, int32_t count)
{
    s->xy = xy;
    s->count = count;
    s->order = malloc((size_t)count * sizeof(int32_t) + 1);
    s->min_x = malloc((size_t)count * sizeof(double) + 1);
    s->max_x = malloc((size_t)count * sizeof(double) + 1);
    keyed *keys = malloc((size_t)count * sizeof(keyed) + 1);
    if (!s->order || !s->min_x || !s->max_x || !keys) {
        free(keys);
        return 0;
    }
    for (int32_t i = 0; i < count; ++i) {
        double a = xy[2 * i], b = xy[2 * ((i + 1) % count)];
        s->min_x[i] = fmin(a, b);
        s->max_x[i] = fmax(a, b);
        keys[i] = (keyed){s->min_x[i], i};
    }
    qsort(keys, (size_t)count, sizeof(keyed), compare_keyed);
    for (int32_t i = 0; i < count; ++i)
        s->order[i] = keys[i].id;
    free(keys);
    return 1;
}

static void sweep_free(sweep *s)
{
    free(s->order);
    free(s->min_x);
    free(s->max_x);
}

/* Where segments i and j meet: 1 with the parameters on each, 0 when apart or parallel. */
static int segment_hit(const double *xy, int32_t count, int32_t i, int32_t j, double *ti, double *tj)
{
    const double *p = &xy[2 * i], *p2 = &xy[2 * ((i + 1) % count)];
    const double *q = &xy[2 * j], *q2 = &xy[2 * ((j + 1) % count)];
    double r[2] = {p2[0] - p[0], p2[1] - p[1]}, s[2] = {q2[0] - q[0], q2[1] - q[1]};
    double denominator = r[0] * s[1] - r[1] * s[0];
    if (fabs(denominator) <= 1e-14 * hypot(r[0], r[1]) * hypot(s[0], s[1]))
        return 0;
    double w[2] = {q[0] - p[0], q[1] - p[1]};
    *ti = (w[0] * s[1] - w[1] * s[0]) / denominator;
    *tj = (w[0] * r[1] - w[1] * r[0]) / denominator;
    const double eps = 1e-12;
    return *ti >= -eps && *ti <= 1 + eps && *tj >= -eps && *tj <= 1 + eps;
}

static int adjacent(int32_t i, int32_t j, int32_t count)
{
    return (i + 1) % count == j || (j + 1) % count == i;
}

/* Calls found(i, j, ti, tj, user) for every meeting of non-adjacent segments; 0 when out of memory. */
static int sweep_pairs(const double *xy, int32_t count,
                       int (*found)(int32_t, int32_t, double, double, void *), void *user)
{
    sweep s = {0};
    int32_t *active = malloc((size_t)count * sizeof(int32_t) + 1);
    if (!active || !sweep_init(&s, xy, count)) {
        free(active);
        sweep_free(&s);
        return 0;
    }
    int32_t active_count = 0, ok = 1;
    for (int32_t k = 0; k < count && ok; ++k) {
        int32_t i = s.order[k], kept = 0;
        for (int32_t a = 0; a < active_count; ++a) {
            int32_t j = active[a];
            if (s.max_x[j] < s.min_x[i])
                continue;
            active[kept++] = j;
            double ti, tj;
            if (!adjacent(i, j, count) && segment_hit(xy, count, i, j, &ti, &tj))
                ok = found(i, j, ti, tj, user);
        }
        active_count = kept;
        active[active_count++] = i;
    }
    free(active);
    sweep_free(&s);
    return ok;
}

static int count_hit(int32_t i, int32_t j, double ti, double tj, void *user)
{
    (void)i, (void)j, (void)ti, (void)tj;
    ++*(int32_t *)user;
    return 1;
}

int32_t pz_offset_self_intersections(const double *points, int32_t count)
{
    if (count < 4)
        return 0;
    int32_t hits = 0;
    return sweep_pairs(points, count, count_hit, &hits) ? hits : -1;
}

/* ---------------------------------------------------------------- arrangement */

typedef struct arrangement {
    const double *xy;          /* raw curve: node i < count is its point i */
    int32_t count;
    crossing *crossings;       /* two per meeting */
    int32_t crossing_count;
    size_t crossing_capacity;
    double *node_xy;           /* every node */
    int32_t node_count;
    size_t node_capacity;
    int32_t *parent;           /* union-find over nodes */
} arrangement;

static int add_node(arrangement *a, double x, double y)
{
    if (!pz_grow((void **)&a->node_xy, &a->node_capacity, 2 * ((size_t)a->node_count + 1), sizeof(double)))
        return -1;
    a->node_xy[2 * a->node_count] = x;
    a->node_xy[2 * a->node_count + 1] = y;
    return a->node_count++;
}

static int record_crossing(int32_t i, int32_t j, double ti, double tj, void *user)
{
    arrangement *a = user;
    const double *p = &a->xy[2 * i], *p2 = &a->xy[2 * ((i + 1) % a->count)];
    int node = add_node(a, p[0] + ti * (p2[0] - p[0]), p[1] + ti * (p2[1] - p[1]));
    if (node < 0 ||
        !pz_grow((void **)&a->crossings, &a->crossing_capacity, (size_t)a->crossing_count + 2, sizeof(crossing)))
        return 0;
    a->crossings[a->crossing_count++] = (crossing){i, node, fmin(fmax(ti, 0), 1)};
    a->crossings[a->crossing_count++] = (crossing){j, node, fmin(fmax(tj, 0), 1)};
    return 1;
}

static int compare_crossings(const void *x, const void *y)
{
    const crossing *a = x, *b = y;
    if (a->segment != b->segment)
        return (a->segment > b->segment) - (a->segment < b->segment);
    if (a->t != b->t)
        return (a->t > b->t) - (a->t < b->t);
    return (a->node > b->node) - (a->node < b->node);
}

/* Crossings at a segment's end become that end's node. */
static void merge_nodes(arrangement *a)
{
    for (int32_t n = 0; n < a->node_count; ++n)
        a->parent[n] = n;
    const double eps = 1e-9;
    for (int32_t k = 0; k < a->crossing_count; ++k) {
        const crossing *c = &a->crossings[k];
        if (c->t < eps)
            pz_union_find_join(a->parent, c->node, c->segment);
        else if (c->t > 1 - eps)
            pz_union_find_join(a->parent, c->node, (c->segment + 1) % a->count);
    }
}

typedef struct graph {
    int32_t *offsets;    /* node_count + 1 */
    int32_t *targets;    /* neighbours, sorted by angle per node */
    double *angles;      /* direction of each edge */
} graph;

typedef struct directed_edge {
    int32_t from, to;
    double angle;
} directed_edge;

static int compare_by_nodes(const void *x, const void *y)
{
    const directed_edge *a = x, *b = y;
    if (a->from != b->from)
        return (a->from > b->from) - (a->from < b->from);
    return (a->to > b->to) - (a->to < b->to);
}

static int compare_by_angle(const void *x, const void *y)
{
    const directed_edge *a = x, *b = y;
    if (a->from != b->from)
        return (a->from > b->from) - (a->from < b->from);
    if (a->angle != b->angle)
        return (a->angle > b->angle) - (a->angle < b->angle);
    return (a->to > b->to) - (a->to < b->to);
}

static void add_edge(const arrangement *a, directed_edge *edges, int32_t *count, int32_t from, int32_t to)
{
    const double *p = &a->node_xy[2 * from], *q = &a->node_xy[2 * to];
    edges[(*count)++] = (directed_edge){from, to, atan2(q[1] - p[1], q[0] - p[0])};
}

/* Directed edges (both ways) between consecutive nodes along every segment, deduplicated. */
static int32_t split_edges(arrangement *a, directed_edge **out)
{
    size_t capacity = 2 * ((size_t)a->count + (size_t)a->crossing_count) + 2;
    directed_edge *edges = malloc(capacity * sizeof(directed_edge));
    if (!edges)
        return -1;
    int32_t edge_count = 0, k = 0;
    for (int32_t s = 0; s < a->count; ++s) {
        int32_t from = pz_union_find_root(a->parent, s);
        for (;; ++k) {
            int end = k >= a->crossing_count || a->crossings[k].segment != s;
            int32_t to = pz_union_find_root(a->parent, end ? (s + 1) % a->count : a->crossings[k].node);
            if (to != from) {
                add_edge(a, edges, &edge_count, from, to);
                add_edge(a, edges, &edge_count, to, from);
                from = to;
            }
            if (end)
                break;
        }
    }
    qsort(edges, (size_t)edge_count, sizeof(directed_edge), compare_by_nodes);
    int32_t unique = 0;
    for (int32_t e = 0; e < edge_count; ++e)
        if (unique == 0 || edges[e].from != edges[unique - 1].from || edges[e].to != edges[unique - 1].to)
            edges[unique++] = edges[e];
    qsort(edges, (size_t)unique, sizeof(directed_edge), compare_by_angle);
    *out = edges;
    return unique;
}

static int build_graph(const arrangement *a, const directed_edge *edges, int32_t edge_count, graph *g)
{
    g->offsets = calloc((size_t)a->node_count + 1, sizeof(int32_t));
    g->targets = malloc((size_t)edge_count * sizeof(int32_t) + 1);
    g->angles = malloc((size_t)edge_count * sizeof(double) + 1);
    if (!g->offsets || !g->targets || !g->angles)
        return 0;
    for (int32_t e = 0; e < edge_count; ++e) {
        ++g->offsets[edges[e].from + 1];
        g->targets[e] = edges[e].to;
        g->angles[e] = edges[e].angle;
    }
    for (int32_t n = 0; n < a->node_count; ++n)
        g->offsets[n + 1] += g->offsets[n];
    return 1;
}

static void graph_free(graph *g)
{
    free(g->offsets);
    free(g->targets);
    free(g->angles);
}

/* The neighbour slot of `node` first counter-clockwise from the direction `back` (the rightmost turn). */
static int32_t rightmost_turn(const graph *g, int32_t node, double back)
{
    int32_t best = -1;
    double best_delta = 0;
    for (int32_t e = g->offsets[node]; e < g->offsets[node + 1]; ++e) {
        double delta = fmod(g->angles[e] - back + 4 * PZ_PI, 2 * PZ_PI);
        if (delta <= 0)
            delta = 2 * PZ_PI;   /* the way back: only for a dead end */
        if (best < 0 || delta < best_delta) {
            best = e;
            best_delta = delta;
        }
    }
    return best;
}

static pz_status walk_outer_face(const arrangement *a, const graph *g, point_list *out, pz_ctx *ctx)
{
    int32_t start = -1;
    for (int32_t n = 0; n < a->node_count; ++n) {
        if (g->offsets[n + 1] == g->offsets[n])
            continue;
        const double *p = &a->node_xy[2 * n];
        if (start < 0 || p[0] < a->node_xy[2 * start] ||
            (p[0] == a->node_xy[2 * start] && p[1] < a->node_xy[2 * start + 1]))
            start = n;
    }
    if (start < 0)
        return pz_error(ctx, PZ_ERR_INTERNAL, "export: cut line: empty offset curve");
    /* At the leftmost node the outside is to the west: arrive as if heading south. */
    int32_t first = rightmost_turn(g, start, 0.5 * PZ_PI), edge = first, node = start;
    int32_t limit = g->offsets[a->node_count] + 2;
    for (int32_t steps = 0; steps <= limit; ++steps) {
        push(out, a->node_xy[2 * node], a->node_xy[2 * node + 1]);
        int32_t next = g->targets[edge];
        /* The way back from `next`, computed exactly as its reverse edge's angle was. */
        const double *from = &a->node_xy[2 * next], *to = &a->node_xy[2 * node];
        double back = atan2(to[1] - from[1], to[0] - from[0]);
        node = next;
        edge = rightmost_turn(g, node, back);
        if (node == start && edge == first)
            return out->failed ? pz_error(ctx, PZ_ERR_NOMEM, "export: cut line: out of memory") : PZ_OK;
    }
    return pz_error(ctx, PZ_ERR_INTERNAL, "export: cut line: the outer boundary walk did not close");
}

static pz_status outer_boundary(const double *xy, int32_t count, point_list *out, pz_ctx *ctx)
{
    arrangement a = {.xy = xy, .count = count};
    graph g = {0};
    directed_edge *edges = NULL;
    pz_status status = PZ_OK;
    for (int32_t i = 0; i < count && status == PZ_OK; ++i)
        if (add_node(&a, xy[2 * i], xy[2 * i + 1]) < 0)
            status = PZ_ERR_NOMEM;
    if (status == PZ_OK && !sweep_pairs(xy, count, record_crossing, &a))
        status = PZ_ERR_NOMEM;
    if (status == PZ_OK) {
        if (a.crossing_count > 0)  /* crossings is NULL when there are none */
            qsort(a.crossings, (size_t)a.crossing_count, sizeof(crossing), compare_crossings);
        a.parent = malloc((size_t)a.node_count * sizeof(int32_t) + 1);
        if (!a.parent)
            status = PZ_ERR_NOMEM;
    }
    int32_t edge_count = -1;
    if (status == PZ_OK) {
        merge_nodes(&a);
        edge_count = split_edges(&a, &edges);
        if (edge_count < 0 || !build_graph(&a, edges, edge_count, &g))
            status = PZ_ERR_NOMEM;
    }
    if (status == PZ_ERR_NOMEM)
        pz_error(ctx, status, "export: cut line: out of memory");
    else
        status = walk_outer_face(&a, &g, out, ctx);
    graph_free(&g);
    free(edges);
    free(a.crossings);
    free(a.node_xy);
    free(a.parent);
    return status;
}

/* ---------------------------------------------------------------- entry */

pz_status pz_offset_polygon(const double *points, int32_t count, const double *distance, double **out,
                            int32_t *out_count, pz_ctx *ctx)
{
    *out = NULL;
    *out_count = 0;
    double *xy = malloc(2 * (size_t)count * sizeof(double) + 1), *d = malloc((size_t)count * sizeof(double) + 1);
    if (!xy || !d) {
        free(xy);
        free(d);
        return pz_error(ctx, PZ_ERR_NOMEM, "export: cut line: out of memory");
    }
    int32_t kept = distinct_points(points, distance, count, xy, d);
    if (kept < 3) {
        free(xy);
        free(d);
        return pz_error(ctx, PZ_ERR_DATA, "export: cut line: a piece outline with %d distinct points", (int)kept);
    }
    point_list raw = {0}, boundary = {0};
    raw_offset(xy, d, kept, &raw);
    free(xy);
    free(d);
    pz_status status = PZ_OK;
    if (raw.failed)
        status = pz_error(ctx, PZ_ERR_NOMEM, "export: cut line: out of memory");
    /* The walk needs distinct consecutive points too. */
    if (status == PZ_OK) {
        double *clean = malloc(2 * (size_t)raw.count * sizeof(double) + 1);
        if (!clean)
            status = pz_error(ctx, PZ_ERR_NOMEM, "export: cut line: out of memory");
        else
            status = outer_boundary(clean, distinct_points(raw.xy, NULL, raw.count, clean, NULL), &boundary, ctx);
        free(clean);
    }
    free(raw.xy);
    if (status != PZ_OK) {
        free(boundary.xy);
        return status;
    }
    *out = boundary.xy;
    *out_count = boundary.count;
    return PZ_OK;
}
