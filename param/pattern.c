/*
 * param/pattern.c -- a garment and a panel id per face become a pattern: the
 * cut mesh in which every panel is one disk, plus its seams and darts. This
 * file holds steps 1-4 and the entry points; steps 5 and 6 (seams, darts,
 * explicit correspondences) are param/pattern_seams.c, on the state of
 * param/pattern_internal.h.
 *
 * Algorithm (docs/pattern.md has the details and the file format):
 *  1. Panel ids are checked (0..K-1, every id used).
 *  2. Cut flags over the garment's edges: an edge whose two faces have
 *     different panels, an edge in `extra_cuts`, and the legs of a closed
 *     dart (an explicit dart whose leg pairs name the same garment vertex).
 *  3. The garment is cut and every panel analysed on the cut mesh: its
 *     faces must form one edge-connected piece (else PZ_ERR_DATA: we refuse
 *     rather than renumber panels behind the caller's back), with Euler
 *     characteristic chi = V - E + F and b boundary loops, genus
 *     g = (2 - chi - b) / 2. g > 0 or b = 0 cannot become a disk by cutting
 *     paths between loops: PZ_ERR_DATA. With b > 1 loops, loops are joined
 *     one at a time by the shortest edge path (multi-source Dijkstra over
 *     the panel's interior edges, 3D lengths in mm, O(E log V) per loop)
 *     from the loops already joined to the nearest other loop; the path
 *     edges join the cut flags. A disk with b loops needs b - 1 such paths
 *     (chi rises by one per path: V grows by the path's interior vertices
 *     plus one, E by the path's edges).
 *  4. The garment is cut again with the final flags (pz_mesh_cut: the cut
 *     mesh keeps face order, so half-edge h of the cut mesh is half-edge h
 *     of the garment). Every panel is verified to be one disk: a failure is
 *     PZ_ERR_INTERNAL naming the panel.
 *  5. Seams: each cut edge of the garment has two sides (its two half-edges,
 *     now boundary half-edges of the cut mesh). Cut edges are chained
 *     through a garment vertex when exactly two cut edges meet there and
 *     their sides use the same two copies of it, so a chain stops where
 *     three panels meet, at the garment boundary, and where the panel pair
 *     changes. Side A is the side of the lower panel id (for a self-seam:
 *     the half-edge running along the chain); the chain runs in the
 *     direction of side A's half-edges (panel_a on the left). A closed chain
 *     (a ring seam) repeats its first pair at the end. A self-chain with
 *     exactly one end where both sides share one copy (a slit stopping
 *     inside its panel: the darts of a UV pattern) becomes a dart instead,
 *     tip = that copy, legs from the open end towards it.
 *  6. Explicit correspondences (garment vertex ids) are mapped to copies:
 *     a seam whose pairs name the same vertex lies on a cut and takes the
 *     copies on the two sides of its cut edges (those edges leave the
 *     automatic seams); a seam between distinct vertices (separate panels,
 *     e.g. the skirt data) takes, for each side, the boundary copy in the
 *     side's majority panel. Darts likewise.
 *
 * Cost: O(F log F) for connectivity plus O(E log V) per extra loop. Memory:
 * a few int32 per half-edge. Failure leaves *out NULL and frees everything.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "core/heap.h"
#include "param/pattern_internal.h"
#include "core/util.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Frees an array of seams (or darts) and their vertex lists; NULL is fine. */
static void free_seams(pz_seam *seams, int32_t count)
{
    for (int32_t i = 0; seams && i < count; ++i) {
        free(seams[i].side_a);
        free(seams[i].side_b);
    }
    free(seams);
}

static void free_darts(pz_dart *darts, int32_t count)
{
    for (int32_t i = 0; darts && i < count; ++i) {
        free(darts[i].leg_a);
        free(darts[i].leg_b);
    }
    free(darts);
}

void pz_pattern_free(pz_pattern **pattern)
{
    if (!pattern || !*pattern)
        return;
    pz_pattern *p = *pattern;
    pz_mesh_free(&p->mesh);
    free(p->vertex_origin);
    free(p->face_panel);
    free_seams(p->seams, p->seam_count);
    free_darts(p->darts, p->dart_count);
    free(p);
    *pattern = NULL;
}

void pz_correspondences_clear(pz_correspondences *correspondences)
{
    if (!correspondences)
        return;
    for (int32_t i = 0; i < correspondences->seam_count; ++i) {
        free(correspondences->seams[i].side_a);
        free(correspondences->seams[i].side_b);
    }
    free(correspondences->seams);
    for (int32_t i = 0; i < correspondences->dart_count; ++i) {
        free(correspondences->darts[i].leg_a);
        free(correspondences->darts[i].leg_b);
    }
    free(correspondences->darts);
    memset(correspondences, 0, sizeof *correspondences);
}

/* ------------------------------------------------------------------------ */
/* Shared helpers (the state is pattern_builder, param/pattern_internal.h)   */
/* ------------------------------------------------------------------------ */

pz_status pattern_no_memory(pattern_builder *b, pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory building the pattern", b->path);
}

/* CSR of the edges at each garment vertex, for looking edges up by their ends. */
static pz_status index_vertex_edges(pattern_builder *b, pz_ctx *ctx)
{
    const pz_topology *t = b->topology;
    b->vertex_edge_offsets = calloc((size_t)t->vertex_count + 1, sizeof(int32_t));
    b->vertex_edges = malloc((size_t)t->edge_count * 2 * sizeof(int32_t) + 1);
    if (!b->vertex_edge_offsets || !b->vertex_edges)
        return pattern_no_memory(b, ctx);
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        ++b->vertex_edge_offsets[pz_he_from(t, h) + 1];
        ++b->vertex_edge_offsets[pz_he_to(t, h) + 1];
    }
    for (int32_t v = 0; v < t->vertex_count; ++v)
        b->vertex_edge_offsets[v + 1] += b->vertex_edge_offsets[v];
    int32_t *fill = malloc((size_t)t->vertex_count * sizeof(int32_t) + 1);
    if (!fill)
        return pattern_no_memory(b, ctx);
    memcpy(fill, b->vertex_edge_offsets, (size_t)t->vertex_count * sizeof(int32_t));
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        b->vertex_edges[fill[pz_he_from(t, h)]++] = e;
        b->vertex_edges[fill[pz_he_to(t, h)]++] = e;
    }
    free(fill);
    return PZ_OK;
}

/* The garment edge between u and v, or -1. */
int32_t pattern_find_edge(const pattern_builder *b, int32_t u, int32_t v)
{
    const pz_topology *t = b->topology;
    for (int32_t i = b->vertex_edge_offsets[u]; i < b->vertex_edge_offsets[u + 1]; ++i) {
        int32_t e = b->vertex_edges[i], h = t->edge_halfedge[2 * e];
        int32_t from = pz_he_from(t, h), to = pz_he_to(t, h);
        if ((from == u && to == v) || (from == v && to == u))
            return e;
    }
    return -1;
}

/* ------------------------------------------------------------------------ */
/* 1-2. Panel ids and cut flags                                              */
/* ------------------------------------------------------------------------ */

static pz_status check_panel_ids(pattern_builder *b, pz_ctx *ctx)
{
    int32_t max_id = -1;
    for (int32_t f = 0; f < b->garment->face_count; ++f) {
        int32_t id = b->face_panel[f];
        if (id < 0 || id >= b->garment->face_count)
            return pz_error(ctx, PZ_ERR_DATA, "%s: face %d has panel id %d (ids run 0..K-1)", b->path, (int)f, (int)id);
        if (id > max_id)
            max_id = id;
    }
    b->panel_count = max_id + 1;
    uint8_t *used = calloc((size_t)b->panel_count + 1, 1);
    if (!used)
        return pattern_no_memory(b, ctx);
    for (int32_t f = 0; f < b->garment->face_count; ++f)
        used[b->face_panel[f]] = 1;
    int32_t unused = -1;
    for (int32_t p = 0; p < b->panel_count && unused < 0; ++p)
        if (!used[p])
            unused = p;
    free(used);
    if (unused >= 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: panel %d has no faces (ids must be 0..%d, every one used)", b->path,
                        (int)unused, (int)b->panel_count - 1);
    return PZ_OK;
}

static void mark_panel_cuts(pattern_builder *b, const uint8_t *extra_cuts)
{
    const pz_topology *t = b->topology;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e], opposite = t->edge_halfedge[2 * e + 1];
        if (opposite < 0)
            continue;
        if (b->face_panel[pz_he_face(h)] != b->face_panel[pz_he_face(opposite)] || (extra_cuts && extra_cuts[e]))
            b->cut[e] = 1;
    }
}

/* A closed dart (every leg pair names one garment vertex) is cut open along
 * the chain leg_a[0] .. leg_a[n-1], tip, so that its legs become boundary. */
static pz_status cut_closed_darts(pattern_builder *b, const pz_correspondences *given, pz_ctx *ctx)
{
    for (int32_t d = 0; given && d < given->dart_count; ++d) {
        const pz_dart *dart = &given->darts[d];
        int closed = dart->pair_count > 0;
        for (int32_t i = 0; i < dart->pair_count; ++i)
            closed &= dart->leg_a[i] == dart->leg_b[i];
        if (!closed)
            continue;
        for (int32_t i = 0; i < dart->pair_count; ++i) {
            int32_t u = dart->leg_a[i], v = i + 1 < dart->pair_count ? dart->leg_a[i + 1] : dart->tip;
            int32_t e = pattern_find_edge(b, u, v);
            if (e < 0)
                return pz_error(ctx, PZ_ERR_DATA, "%s: dart %d: leg vertices %d-%d are not joined by an edge", b->path,
                                (int)d, (int)u, (int)v);
            b->cut[e] = 1;
        }
    }
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* 3. Panel analysis on a cut mesh                                           */
/* ------------------------------------------------------------------------ */

typedef struct panel_shape {
    int32_t vertices, edges, faces;
    int32_t components;
    int32_t loops;
} panel_shape;

/* Counts per panel on a cut mesh; also fills vertex_panel (cut-mesh vertices). */
static pz_status analyse_panels(pattern_builder *b, const pz_mesh *cut_mesh, const pz_topology *ct,
                                int32_t *vertex_panel, panel_shape *shape, pz_loops **loops_out, pz_ctx *ctx)
{
    memset(shape, 0, (size_t)b->panel_count * sizeof *shape);
    for (int32_t v = 0; v < cut_mesh->vertex_count; ++v)
        vertex_panel[v] = -1;
    for (int32_t f = 0; f < cut_mesh->face_count; ++f) {
        ++shape[b->face_panel[f]].faces;
        for (int k = 0; k < 3; ++k)
            vertex_panel[cut_mesh->faces[3 * f + k]] = b->face_panel[f];
    }
    for (int32_t v = 0; v < cut_mesh->vertex_count; ++v)
        if (vertex_panel[v] >= 0)
            ++shape[vertex_panel[v]].vertices;
    for (int32_t e = 0; e < ct->edge_count; ++e)
        ++shape[b->face_panel[pz_he_face(ct->edge_halfedge[2 * e])]].edges;
    int32_t *component = malloc((size_t)cut_mesh->face_count * sizeof(int32_t) + 1);
    if (!component)
        return pattern_no_memory(b, ctx);
    int32_t component_count = pz_topology_components(ct, component, ctx);
    if (component_count < 0) {
        free(component);
        return (pz_status)component_count;
    }
    /* Faces of one component share a panel (every edge between panels is cut). */
    int32_t *component_panel = malloc((size_t)component_count * sizeof(int32_t) + 1);
    if (!component_panel) {
        free(component);
        return pattern_no_memory(b, ctx);
    }
    for (int32_t c = 0; c < component_count; ++c)
        component_panel[c] = -1;
    for (int32_t f = 0; f < cut_mesh->face_count; ++f)
        component_panel[component[f]] = b->face_panel[f];
    for (int32_t c = 0; c < component_count; ++c)
        ++shape[component_panel[c]].components;
    free(component_panel);
    free(component);
    pz_status status = pz_topology_boundary_loops(ct, loops_out, ctx);
    if (status)
        return status;
    const pz_loops *loops = *loops_out;
    for (int32_t l = 0; l < loops->loop_count; ++l)
        ++shape[vertex_panel[loops->loop_vertices[loops->loop_offsets[l]]]].loops;
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* Dijkstra: joining the boundary loops of a panel                          */
/* ------------------------------------------------------------------------ */

/* Scratch for the loop-joining searches over one cut mesh. */
typedef struct path_search {
    const pz_topology *ct;
    const double *positions;
    int32_t *adjacency_offsets;  /* cut-mesh vertex -> interior edges (CSR) */
    int32_t *adjacency;          /* edge ids */
    int32_t *loop_of_vertex;     /* -1 off the boundary */
    double *distance;
    int32_t *previous_edge;      /* the edge a vertex was reached by, -1 for a source */
    uint8_t *joined;             /* vertex is in the joined set (a source) */
    pz_heap queue;
} path_search;

static void path_search_free(path_search *s)
{
    free(s->adjacency_offsets);
    free(s->adjacency);
    free(s->loop_of_vertex);
    free(s->distance);
    free(s->previous_edge);
    free(s->joined);
    pz_heap_free(&s->queue);
}

static int path_search_init(path_search *s, const pz_mesh *cut_mesh, const pz_topology *ct, const pz_loops *loops)
{
    memset(s, 0, sizeof *s);
    size_t nv = (size_t)cut_mesh->vertex_count;
    s->ct = ct;
    s->positions = cut_mesh->positions;
    s->adjacency_offsets = calloc(nv + 1, sizeof(int32_t));
    s->adjacency = malloc((size_t)ct->edge_count * 2 * sizeof(int32_t) + 1);
    s->loop_of_vertex = malloc(nv * sizeof(int32_t) + 1);
    s->distance = malloc(nv * sizeof(double) + 1);
    s->previous_edge = malloc(nv * sizeof(int32_t) + 1);
    s->joined = calloc(nv + 1, 1);
    if (!s->adjacency_offsets || !s->adjacency || !s->loop_of_vertex || !s->distance || !s->previous_edge || !s->joined)
        return 0;
    /* Boundary edges are left out: cutting them again would change nothing. */
    for (int32_t e = 0; e < ct->edge_count; ++e) {
        int32_t h = ct->edge_halfedge[2 * e];
        if (ct->edge_halfedge[2 * e + 1] < 0)
            continue;
        ++s->adjacency_offsets[pz_he_from(ct, h) + 1];
        ++s->adjacency_offsets[pz_he_to(ct, h) + 1];
    }
    for (size_t v = 0; v < nv; ++v)
        s->adjacency_offsets[v + 1] += s->adjacency_offsets[v];
    int32_t *fill = s->previous_edge; /* borrowed as scratch */
    memcpy(fill, s->adjacency_offsets, nv * sizeof(int32_t));
    for (int32_t e = 0; e < ct->edge_count; ++e) {
        int32_t h = ct->edge_halfedge[2 * e];
        if (ct->edge_halfedge[2 * e + 1] < 0)
            continue;
        s->adjacency[fill[pz_he_from(ct, h)]++] = e;
        s->adjacency[fill[pz_he_to(ct, h)]++] = e;
    }
    for (size_t v = 0; v < nv; ++v)
        s->loop_of_vertex[v] = -1;
    for (int32_t l = 0; l < loops->loop_count; ++l)
        for (int32_t i = loops->loop_offsets[l]; i < loops->loop_offsets[l + 1]; ++i)
            s->loop_of_vertex[loops->loop_vertices[i]] = l;
    return 1;
}

static void join_loop(path_search *s, const pz_loops *loops, int32_t l, uint8_t *loop_joined)
{
    loop_joined[l] = 1;
    for (int32_t i = loops->loop_offsets[l]; i < loops->loop_offsets[l + 1]; ++i)
        s->joined[loops->loop_vertices[i]] = 1;
}

/*
 * One multi-source Dijkstra from the joined vertices of `panel_vertices`
 * (count vertices) to the nearest vertex of a loop not joined yet. Returns
 * that vertex, -1 when none is reachable, -2 when out of memory.
 */
static int32_t nearest_loop_vertex(path_search *s, const int32_t *panel_vertices, int32_t count,
                                   const uint8_t *loop_joined)
{
    const pz_topology *ct = s->ct;
    pz_heap_clear(&s->queue);
    for (int32_t i = 0; i < count; ++i) {
        int32_t v = panel_vertices[i];
        s->distance[v] = s->joined[v] ? 0.0 : INFINITY;
        s->previous_edge[v] = -1;
        if (s->joined[v] && !pz_heap_push(&s->queue, 0.0, v))
            return -2;
    }
    double distance;
    int32_t v;
    while (pz_heap_pop(&s->queue, &distance, &v)) {
        if (distance > s->distance[v])
            continue; /* a stale entry */
        if (!s->joined[v] && s->loop_of_vertex[v] >= 0 && !loop_joined[s->loop_of_vertex[v]])
            return v;
        for (int32_t i = s->adjacency_offsets[v]; i < s->adjacency_offsets[v + 1]; ++i) {
            int32_t e = s->adjacency[i], h = ct->edge_halfedge[2 * e];
            int32_t w = pz_he_from(ct, h) == v ? pz_he_to(ct, h) : pz_he_from(ct, h);
            double d = distance + pz_vec3_distance(s->positions + 3 * (size_t)v, s->positions + 3 * (size_t)w);
            if (d < s->distance[w]) {
                s->distance[w] = d;
                s->previous_edge[w] = e;
                if (!pz_heap_push(&s->queue, d, w))
                    return -2;
            }
        }
    }
    return -1;
}

/* Joins the b loops of one panel with b - 1 shortest paths; flags their garment edges. */
static pz_status join_panel_loops(pattern_builder *b, path_search *s, const pz_loops *loops, int32_t panel,
                                  const int32_t *panel_vertices, int32_t count, uint8_t *loop_joined, pz_ctx *ctx)
{
    const pz_topology *ct = s->ct;
    int32_t first = -1, remaining = 0;
    for (int32_t l = 0; l < loops->loop_count; ++l)
        if (s->joined[loops->loop_vertices[loops->loop_offsets[l]]] == 0 &&
            b->vertex_panel[loops->loop_vertices[loops->loop_offsets[l]]] == panel) {
            if (first < 0)
                first = l;
            else
                ++remaining;
        }
    if (first < 0)
        return PZ_OK;
    join_loop(s, loops, first, loop_joined);
    for (; remaining > 0; --remaining) {
        int32_t target = nearest_loop_vertex(s, panel_vertices, count, loop_joined);
        if (target == -2)
            return pattern_no_memory(b, ctx);
        if (target < 0)
            return pz_error(ctx, PZ_ERR_INTERNAL, "%s: panel %d: no path joins its boundary loops", b->path, (int)panel);
        for (int32_t v = target; s->previous_edge[v] >= 0;) {
            int32_t e = s->previous_edge[v], h = ct->edge_halfedge[2 * e];
            b->cut[b->topology->halfedge_edge[h]] = 1; /* cut-mesh half-edge h is garment half-edge h */
            s->joined[v] = 1;
            v = pz_he_from(ct, h) == v ? pz_he_to(ct, h) : pz_he_from(ct, h);
        }
        join_loop(s, loops, s->loop_of_vertex[target], loop_joined);
    }
    return PZ_OK;
}

/* Cuts the garment with the current flags (replacing any earlier cut). */
static pz_status cut_garment(pattern_builder *b, pz_ctx *ctx)
{
    pz_topology_free(&b->cut_topology);
    pz_mesh_free(&b->cut_mesh);
    free(b->vertex_origin);
    b->vertex_origin = NULL;
    free(b->vertex_panel);
    b->vertex_panel = NULL;
    pz_status status = pz_mesh_cut(b->garment, b->topology, b->cut, &b->cut_mesh, &b->vertex_origin, ctx);
    if (!status)
        status = pz_topology_build(b->cut_mesh, &b->cut_topology, ctx);
    if (status)
        return status;
    b->vertex_panel = malloc((size_t)b->cut_mesh->vertex_count * sizeof(int32_t) + 1);
    return b->vertex_panel ? PZ_OK : pattern_no_memory(b, ctx);
}

/* Refuses panels that are not one disk-able piece; returns in *needs_paths whether any has b > 1. */
static pz_status check_panel_shapes(pattern_builder *b, const panel_shape *shape, int *needs_paths, pz_ctx *ctx)
{
    *needs_paths = 0;
    for (int32_t p = 0; p < b->panel_count; ++p) {
        const panel_shape *ps = &shape[p];
        if (ps->components != 1)
            return pz_error(ctx, PZ_ERR_DATA, "%s: panel %d is in %d separate pieces (a panel must be one connected piece)",
                            b->path, (int)p, (int)ps->components);
        int32_t chi = ps->vertices - ps->edges + ps->faces;
        int32_t genus = (2 - chi - ps->loops) / 2;
        if (genus > 0 || ps->loops == 0)
            return pz_error(ctx, PZ_ERR_DATA, "%s: panel %d is not a disk and cannot be cut (genus %d, %d boundary loops)",
                            b->path, (int)p, (int)genus, (int)ps->loops);
        if (ps->loops > 1)
            *needs_paths = 1;
    }
    return PZ_OK;
}

/* Vertices of the cut mesh grouped by panel (CSR). */
static int group_vertices_by_panel(const pattern_builder *b, int32_t **offsets_out, int32_t **vertices_out)
{
    int32_t nv = b->cut_mesh->vertex_count;
    int32_t *offsets = calloc((size_t)b->panel_count + 1, sizeof(int32_t));
    int32_t *vertices = malloc((size_t)nv * sizeof(int32_t) + 1);
    if (!offsets || !vertices) {
        free(offsets);
        free(vertices);
        return 0;
    }
    for (int32_t v = 0; v < nv; ++v)
        if (b->vertex_panel[v] >= 0)
            ++offsets[b->vertex_panel[v] + 1];
    for (int32_t p = 0; p < b->panel_count; ++p)
        offsets[p + 1] += offsets[p];
    int32_t *fill = malloc((size_t)b->panel_count * sizeof(int32_t) + 1);
    if (!fill) {
        free(offsets);
        free(vertices);
        return 0;
    }
    memcpy(fill, offsets, (size_t)b->panel_count * sizeof(int32_t));
    for (int32_t v = 0; v < nv; ++v)
        if (b->vertex_panel[v] >= 0)
            vertices[fill[b->vertex_panel[v]]++] = v;
    free(fill);
    *offsets_out = offsets;
    *vertices_out = vertices;
    return 1;
}

static pz_status add_cut_paths(pattern_builder *b, const pz_loops *loops, const panel_shape *shape, pz_ctx *ctx)
{
    path_search s;
    int32_t *offsets = NULL, *vertices = NULL;
    uint8_t *loop_joined = calloc((size_t)loops->loop_count + 1, 1);
    pz_status status = PZ_OK;
    if (!loop_joined || !path_search_init(&s, b->cut_mesh, b->cut_topology, loops) ||
        !group_vertices_by_panel(b, &offsets, &vertices)) {
        free(loop_joined);
        path_search_free(&s);
        return pattern_no_memory(b, ctx);
    }
    for (int32_t p = 0; p < b->panel_count && !status; ++p)
        if (shape[p].loops > 1)
            status = join_panel_loops(b, &s, loops, p, vertices + offsets[p], offsets[p + 1] - offsets[p], loop_joined,
                                      ctx);
    free(offsets);
    free(vertices);
    free(loop_joined);
    path_search_free(&s);
    return status;
}

/* Steps 3-4: cut, open every panel into a disk, cut again and verify. */
static pz_status cut_into_disks(pattern_builder *b, pz_ctx *ctx)
{
    panel_shape *shape = malloc((size_t)b->panel_count * sizeof *shape);
    pz_loops *loops = NULL;
    if (!shape)
        return pattern_no_memory(b, ctx);
    int needs_paths = 0;
    pz_status status = cut_garment(b, ctx);
    if (!status)
        status = analyse_panels(b, b->cut_mesh, b->cut_topology, b->vertex_panel, shape, &loops, ctx);
    if (!status)
        status = check_panel_shapes(b, shape, &needs_paths, ctx);
    if (!status && needs_paths) {
        status = add_cut_paths(b, loops, shape, ctx);
        pz_loops_free(&loops);
        if (!status)
            status = cut_garment(b, ctx);
        if (!status)
            status = analyse_panels(b, b->cut_mesh, b->cut_topology, b->vertex_panel, shape, &loops, ctx);
    }
    for (int32_t p = 0; p < b->panel_count && !status; ++p) {
        const panel_shape *ps = &shape[p];
        if (ps->components != 1 || ps->loops != 1 || ps->vertices - ps->edges + ps->faces != 1)
            status = pz_error(ctx, PZ_ERR_INTERNAL, "%s: panel %d is not a disk after cutting (%d pieces, %d loops, chi %d)",
                              b->path, (int)p, (int)ps->components, (int)ps->loops,
                              (int)(ps->vertices - ps->edges + ps->faces));
    }
    pz_loops_free(&loops);
    free(shape);
    return status;
}

/* ------------------------------------------------------------------------ */
/* Entry points                                                              */
/* ------------------------------------------------------------------------ */

static void builder_free(pattern_builder *b)
{
    pz_topology_free(&b->topology);
    free(b->cut);
    free(b->explicit_edge);
    free(b->vertex_edge_offsets);
    free(b->vertex_edges);
    pz_topology_free(&b->cut_topology);
    pz_mesh_free(&b->cut_mesh);
    free(b->vertex_origin);
    free(b->vertex_panel);
    free(b->copy_offsets);
    free(b->copies);
    free_seams(b->seams, b->seam_count);
    free_darts(b->darts, b->dart_count);
}

/* Moves the results out of the builder into a pattern. */
static pz_status hand_over(pattern_builder *b, pz_pattern **out, pz_ctx *ctx)
{
    pz_pattern *pattern = calloc(1, sizeof *pattern);
    int32_t *face_panel = malloc((size_t)b->garment->face_count * sizeof(int32_t) + 1);
    if (!pattern || !face_panel) {
        free(pattern);
        free(face_panel);
        return pattern_no_memory(b, ctx);
    }
    memcpy(face_panel, b->face_panel, (size_t)b->garment->face_count * sizeof(int32_t));
    pattern->mesh = b->cut_mesh;
    pattern->vertex_origin = b->vertex_origin;
    pattern->panel_count = b->panel_count;
    pattern->face_panel = face_panel;
    pattern->seam_count = b->seam_count;
    pattern->seams = b->seams;
    pattern->dart_count = b->dart_count;
    pattern->darts = b->darts;
    b->cut_mesh = NULL;
    b->vertex_origin = NULL;
    b->seams = NULL;
    b->seam_count = 0;
    b->darts = NULL;
    b->dart_count = 0;
    *out = pattern;
    return PZ_OK;
}

pz_status pz_pattern_build(const pz_mesh *garment, const int32_t *face_panel, const uint8_t *extra_cuts,
                           const pz_correspondences *explicit_correspondences, const char *path,
                           pz_pattern **out, pz_ctx *ctx)
{
    *out = NULL;
    pattern_builder b = {0};
    b.garment = garment;
    b.face_panel = face_panel;
    b.path = path ? path : "pattern";
    if (garment->face_count == 0)
        return pz_error(ctx, PZ_ERR_DATA, "%s: the garment has no faces", b.path);
    pz_status status = check_panel_ids(&b, ctx);
    if (!status)
        status = pz_topology_build(garment, &b.topology, ctx);
    if (!status) {
        b.cut = calloc((size_t)b.topology->edge_count + 1, 1);
        b.explicit_edge = calloc((size_t)b.topology->edge_count + 1, 1);
        if (!b.cut || !b.explicit_edge)
            status = pattern_no_memory(&b, ctx);
    }
    if (!status)
        status = index_vertex_edges(&b, ctx);
    if (!status) {
        mark_panel_cuts(&b, extra_cuts);
        status = cut_closed_darts(&b, explicit_correspondences, ctx);
    }
    if (!status)
        status = cut_into_disks(&b, ctx);
    if (!status)
        status = pattern_index_copies(&b, ctx);
    if (!status)
        status = pattern_map_explicit(&b, explicit_correspondences, ctx);
    if (!status)
        status = pattern_find_automatic_seams(&b, ctx);
    if (!status)
        status = hand_over(&b, out, ctx);
    builder_free(&b);
    return status;
}

/* 1 when the two sides of interior half-edge h share their UVs at both ends. */
static int same_uvs_across(const pz_mesh *mesh, const pz_topology *t, int32_t h)
{
    int32_t opposite = t->twin[h];
    /* h runs a -> b, opposite b -> a: corner h (a) faces corner next(opposite) (a). */
    int32_t pairs[2][2] = {{mesh->corner_uvs[h], mesh->corner_uvs[pz_he_next(opposite)]},
                           {mesh->corner_uvs[pz_he_next(h)], mesh->corner_uvs[opposite]}};
    for (int i = 0; i < 2; ++i) {
        int32_t x = pairs[i][0], y = pairs[i][1];
        /* Equal indices, or (files that repeat vt lines) exactly equal coordinates. */
        if (x != y && (mesh->uvs[2 * x] != mesh->uvs[2 * y] || mesh->uvs[2 * x + 1] != mesh->uvs[2 * y + 1]))
            return 0;
    }
    return 1;
}

pz_status pz_pattern_panels_from_uv(const pz_mesh *mesh, int32_t *face_panel, int32_t *panel_count,
                                    uint8_t **extra_cuts, pz_ctx *ctx)
{
    *extra_cuts = NULL;
    *panel_count = 0;
    if (!mesh->corner_uvs || mesh->uv_count == 0)
        return pz_error(ctx, PZ_ERR_DATA, "panels from UVs: the mesh has no UVs");
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->corner_uvs[c] < 0 || mesh->corner_uvs[c] >= mesh->uv_count)
            return pz_error(ctx, PZ_ERR_DATA, "panels from UVs: face %d has no UV at a corner", (int)(c / 3));
    pz_topology *t = NULL;
    pz_status status = pz_topology_build(mesh, &t, ctx);
    if (status)
        return status;
    uint8_t *cuts = calloc((size_t)t->edge_count + 1, 1);
    int32_t *parent = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    int32_t *root_panel = malloc((size_t)mesh->face_count * sizeof(int32_t) + 1);
    if (!cuts || !parent || !root_panel) {
        free(cuts);
        free(parent);
        free(root_panel);
        pz_topology_free(&t);
        return pz_error(ctx, PZ_ERR_NOMEM, "panels from UVs: out of memory");
    }
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        parent[f] = f;
        root_panel[f] = -1;
    }
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e], opposite = t->edge_halfedge[2 * e + 1];
        if (opposite < 0)
            continue;
        if (same_uvs_across(mesh, t, h))
            pz_union_find_join(parent, pz_he_face(h), pz_he_face(opposite));
        else
            cuts[e] = 1;
    }
    int32_t count = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        int32_t root = pz_union_find_root(parent, f);
        if (root_panel[root] < 0)
            root_panel[root] = count++;
        face_panel[f] = root_panel[root];
    }
    free(parent);
    free(root_panel);
    pz_topology_free(&t);
    *panel_count = count;
    *extra_cuts = cuts;
    return PZ_OK;
}
