/*
 * segment/fallback.c -- the last resort of the insertion: a cut through the
 * worst vertex of a panel that field-aligned candidates could not fix.
 *
 * Some panels fail whatever field-aligned path is offered: a vertex where
 * limbs meet can carry an angle excess of several radians (the wetsuit of
 * ../shared/data has one at -6.8 rad over 30 faces), and no panel holding it
 * inside flattens within a few percent; a small panel may have no candidate
 * of its own at all. For each such panel the vertex to cut through is the
 * inner vertex of largest |angle defect| (strain or injectivity failures) or
 * the inner vertex farthest from the outline (corner failures: a cut across
 * the middle halves the outline). The cut is the shortest edge path from the
 * vertex to the outline, continued by the shortest path from the vertex to
 * the outline that avoids the first one: a border-to-border path through
 * the vertex (Dijkstra over the panel's inner edges, 3D lengths). Its arms
 * are the graph's arms closest to the path's direction, so distances and
 * tangency tests treat it like any other path. At most SEG_FALLBACK_ROUNDS
 * rounds and SEG_FALLBACK_MAX_CUTS cuts in all: when the goals cannot be met
 * (S = 0 on a sphere) the cuts would otherwise double the panels each round.
 * With a symmetry plane the
 * panels on the positive side are left to the mirror images of their
 * partners' cuts, unless a round made no cut while such panels still fail
 * (their mirror images meet the goals): then they are cut themselves.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"

#include "core/heap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Scratch over garment vertices for one panel. */
typedef struct panel_scratch {
    uint8_t *state;     /* vertex_count: 0 not in panel, 1 inner, 2 on the outline, 3 blocked */
    double *distance;   /* vertex_count */
    int32_t *previous;  /* vertex_count */
    pz_heap queue;      /* room for 2 * edge_count pushes, reserved: a push never fails */
} panel_scratch;

static double edge_length(const seg_layout *layout, int32_t a, int32_t b)
{
    const double *p = layout->mesh->positions + 3 * a, *q = layout->mesh->positions + 3 * b;
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
}

/* 1 when edge e lies inside panel p (uncut, both faces in p). */
static int inner_edge(const seg_layout *layout, int32_t e, int32_t p)
{
    const pz_topology *t = layout->topology;
    int32_t a = t->edge_halfedge[2 * e], b = t->edge_halfedge[2 * e + 1];
    return b >= 0 && !layout->edge_cut[e] && layout->face_panel[pz_he_face(a)] == p &&
           layout->face_panel[pz_he_face(b)] == p;
}

/* Marks panel p's vertices: 1 inner, 2 on its outline. */
static void mark_panel(const seg_layout *layout, int32_t p, panel_scratch *s)
{
    const pz_topology *t = layout->topology;
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
        for (int k = 0; k < 3; ++k)
            s->state[t->faces[3 * layout->panel_faces[i] + k]] = 1;
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * layout->panel_faces[i] + k;
            if (!inner_edge(layout, t->halfedge_edge[h], p)) {
                s->state[pz_he_from(t, h)] = 2;
                s->state[pz_he_to(t, h)] = 2;
            }
        }
}

static void unmark_panel(const seg_layout *layout, int32_t p, panel_scratch *s)
{
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
        for (int k = 0; k < 3; ++k)
            s->state[layout->topology->faces[3 * layout->panel_faces[i] + k]] = 0;
}

/*
 * Dijkstra from `source` over panel p's inner edges through inner vertices;
 * stops at the first outline vertex reached (returned, -1 none). With
 * `all` set it runs to the end instead (distances for the farthest vertex).
 */
static int32_t shortest_to_outline(const seg_layout *layout, int32_t p, int32_t source, int all, panel_scratch *s,
                                   const int32_t *sources, int32_t source_count)
{
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t v = layout->topology->faces[3 * layout->panel_faces[i] + k];
            s->distance[v] = INFINITY;
            s->previous[v] = -1;
        }
    pz_heap_clear(&s->queue);
    if (sources) {
        for (int32_t i = 0; i < source_count; ++i) {
            s->distance[sources[i]] = 0;
            pz_heap_push(&s->queue, 0, sources[i]);
        }
    } else {
        s->distance[source] = 0;
        pz_heap_push(&s->queue, 0, source);
    }
    double key;
    int32_t v;
    while (pz_heap_pop(&s->queue, &key, &v)) {
        if (key > s->distance[v])
            continue;
        if (!all && v != source && s->state[v] == 2)
            return v;
        if (v != source && s->state[v] != 1 && !sources)
            continue;
        for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i) {
            int32_t e = layout->vertex_edges[i];
            if (!inner_edge(layout, e, p))
                continue;
            int32_t h = layout->topology->edge_halfedge[2 * e];
            int32_t w = pz_he_from(layout->topology, h) == v ? pz_he_to(layout->topology, h) : pz_he_from(layout->topology, h);
            if (s->state[w] == 3 || s->state[w] == 0)
                continue;
            double d = key + edge_length(layout, v, w);
            if (d < s->distance[w]) {
                s->distance[w] = d;
                s->previous[w] = v;
                pz_heap_push(&s->queue, d, w);
            }
        }
    }
    return -1;
}

/* The inner vertex of panel p to cut through, or -1. */
static int32_t worst_vertex(const seg_layout *layout, int32_t p, const double *defect, panel_scratch *s)
{
    int by_corners = !(layout->panel_goals[p].failures & (PZ_GOAL_STRAIN | PZ_GOAL_NOT_INJECTIVE | PZ_GOAL_VETOED));
    int32_t best = -1;
    double best_key = -1;
    if (by_corners) {
        /* Distances from the whole outline: the farthest inner vertex is the panel's middle. */
        int32_t count = 0;
        int32_t *outline = malloc(((size_t)layout->panel_offsets[p + 1] - layout->panel_offsets[p]) * 3 * sizeof(int32_t) + 1);
        if (!outline)
            return -1;
        for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
            for (int k = 0; k < 3; ++k) {
                int32_t v = layout->topology->faces[3 * layout->panel_faces[i] + k];
                if (s->state[v] == 2)
                    outline[count++] = v; /* repeats are harmless sources */
            }
        shortest_to_outline(layout, p, -1, 1, s, outline, count);
        free(outline);
    }
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t v = layout->topology->faces[3 * layout->panel_faces[i] + k];
            if (s->state[v] != 1)
                continue;
            double key = by_corners ? (isfinite(s->distance[v]) ? s->distance[v] : -1) : fabs(defect[v]);
            if (key > best_key || (key == best_key && v < best)) {
                best_key = key;
                best = v;
            }
        }
    return best;
}

/* Appends the chain end -> ... -> source (following previous[]) reversed or not into vertices. */
static int32_t chain(const panel_scratch *s, int32_t end, int32_t *vertices)
{
    int32_t n = 0;
    for (int32_t v = end; v >= 0; v = s->previous[v])
        vertices[n++] = v;
    return n; /* end first, source last */
}

/* The border-to-border path through vertex v of panel p into *out; 0 when there is none. */
static int cut_through(seg_layout *layout, int32_t p, int32_t v, panel_scratch *s, pz_trace_path *out)
{
    int32_t room = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    room = 3 * room + 2;
    int32_t *first = malloc((size_t)room * sizeof(int32_t)), *second = malloc((size_t)room * sizeof(int32_t));
    int ok = 0;
    int32_t a = first && second ? shortest_to_outline(layout, p, v, 0, s, NULL, 0) : -1;
    if (a >= 0) {
        int32_t n1 = chain(s, a, first); /* a ... v */
        for (int32_t i = 0; i < n1 - 1; ++i)
            s->state[first[i]] = 3;
        int32_t b = shortest_to_outline(layout, p, v, 0, s, NULL, 0);
        for (int32_t i = 0; i < n1 - 1; ++i)
            s->state[first[i]] = i == 0 ? 2 : 1;
        if (b >= 0) {
            int32_t n2 = chain(s, b, second); /* b ... v */
            int32_t n = n1 + n2 - 1;
            out->vertices = malloc((size_t)n * sizeof(int32_t));
            out->arms = malloc((size_t)n);
            if (out->vertices && out->arms) {
                memcpy(out->vertices, first, (size_t)n1 * sizeof(int32_t));
                for (int32_t i = 1; i < n2; ++i)
                    out->vertices[n1 - 1 + i] = second[n2 - 1 - i];
                out->vertex_count = n;
                out->kind = PZ_TRACE_BORDER;
                ok = 1;
            }
        }
    }
    free(first);
    free(second);
    if (!ok) {
        pz_trace_path_clear(out);
        return 0;
    }
    for (int32_t i = 0; i < out->vertex_count; ++i) {
        int32_t from = out->vertices[i > 0 ? i - 1 : i], to = out->vertices[i + 1 < out->vertex_count ? i + 1 : i];
        const double *p0 = layout->mesh->positions + 3 * from, *p1 = layout->mesh->positions + 3 * to;
        double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        out->arms[i] = seg_closest_arm(layout->graph, out->vertices[i], d);
        if (i > 0)
            out->length_mm += edge_length(layout, out->vertices[i - 1], out->vertices[i]);
    }
    out->cost = out->length_mm;
    return 1;
}

pz_status seg_fallback_cuts(seg_layout *layout, int32_t *inserted, pz_ctx *ctx)
{
    *inserted = 0;
    int32_t vertices = layout->mesh->vertex_count;
    panel_scratch s;
    s.state = calloc((size_t)vertices + 1, 1);
    s.distance = malloc(((size_t)vertices + 1) * sizeof(double));
    s.previous = malloc(((size_t)vertices + 1) * sizeof(int32_t));
    memset(&s.queue, 0, sizeof s.queue);
    s.queue.capacity = (size_t)2 * layout->topology->edge_count + 2;
    s.queue.keys = malloc(s.queue.capacity * sizeof(double));
    s.queue.items = malloc(s.queue.capacity * sizeof(int32_t));
    double *defect = malloc(((size_t)vertices + 1) * sizeof(double));
    pz_status status = PZ_OK;
    if (!s.state || !s.distance || !s.previous || !s.queue.keys || !s.queue.items || !defect)
        status = pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
    if (!status)
        pz_geom_angle_defect(layout->mesh, layout->topology, defect);
    int both_sides = 0;
    for (int round = 0; !status && round < SEG_FALLBACK_ROUNDS; ++round) {
        if ((status = pz_check_cancel(ctx, "segment")) || (status = seg_evaluate_panels(layout, NULL, ctx)))
            break;
        int32_t before = *inserted;
        /* One cut per failing panel of this labelling; paths are collected first (labels change on insertion). */
        int32_t panels = layout->panel_count, made = 0;
        pz_trace_path *cuts = calloc((size_t)panels + 1, sizeof(pz_trace_path));
        if (!cuts) {
            status = pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
            break;
        }
        int32_t skipped = 0;
        for (int32_t p = 0; p < panels; ++p) {
            if (!(layout->panel_goals[p].failures & PZ_GOAL_SPLIT_MENDS))
                continue;
            if (!both_sides && seg_panel_mirrored_side(layout, p)) {
                ++skipped;
                continue;
            }
            mark_panel(layout, p, &s);
            int32_t v = worst_vertex(layout, p, defect, &s);
            if (v >= 0 && cut_through(layout, p, v, &s, cuts + made))
                ++made;
            unmark_panel(layout, p, &s);
        }
        if (*inserted + made > SEG_FALLBACK_MAX_CUTS)
            made = SEG_FALLBACK_MAX_CUTS - *inserted; /* unreachable goals must not shred a big mesh */
        for (int32_t i = 0; i < made && !status; ++i) {
            status = seg_insert_with_mirror(layout, cuts + i, ctx);
            ++*inserted;
        }
        for (int32_t i = 0; i < panels; ++i)
            pz_trace_path_clear(cuts + i);
        free(cuts);
        if (!status)
            status = seg_label_panels(layout, ctx);
        if (!status && (status = seg_evaluate_panels(layout, NULL, ctx)) == PZ_OK)
            seg_progress(layout, "insert", ctx);
        if (*inserted == before) {
            /* A failing panel whose mirror image meets the goals gets no cut by mirroring: cut it itself. */
            if (both_sides || !skipped)
                break;
            both_sides = 1;
        }
    }
    free(s.state);
    free(s.distance);
    free(s.previous);
    pz_heap_free(&s.queue);
    free(defect);
    return status;
}
