/*
 * param/pattern_seams.c -- steps 5 and 6 of pz_pattern_build (the overview
 * is in param/pattern.c, the details in docs/pattern.md): seams from the cut
 * edges of the garment, chained through vertices where exactly two cut edges
 * meet with the same two copies, side A on the lower panel id; a self-chain
 * that stops inside its panel becomes a dart; and explicit correspondences
 * (garment vertex ids) mapped to copies of the cut mesh.
 *
 * Separate from param/pattern.c because it starts where that file's cutting
 * ends: it reads the final cut mesh and writes only the seams and darts of
 * the builder (param/pattern_internal.h).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "param/pattern_internal.h"
#include "core/util.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* 5. Seams from cut edges                                                   */
/* ------------------------------------------------------------------------ */

/* The cut-mesh copy of garment vertex v on the side of half-edge h (v is one of its ends). */
static int32_t side_copy(const pattern_builder *b, int32_t h, int32_t v)
{
    const int32_t *faces = b->cut_mesh->faces;
    return pz_he_from(b->topology, h) == v ? faces[h] : faces[pz_he_next(h)];
}

static int32_t other_end(const pattern_builder *b, int32_t e, int32_t v)
{
    int32_t h = b->topology->edge_halfedge[2 * e];
    return pz_he_from(b->topology, h) == v ? pz_he_to(b->topology, h) : pz_he_from(b->topology, h);
}

static int is_seam_edge(const pattern_builder *b, int32_t e)
{
    return b->cut[e] && b->topology->edge_halfedge[2 * e + 1] >= 0 && !b->explicit_edge[e];
}

/* The other seam edge through v that continues edge e (same two copies of v), or -1. */
static int32_t continuation(const pattern_builder *b, int32_t e, int32_t v)
{
    int32_t found = -1, count = 0;
    for (int32_t i = b->vertex_edge_offsets[v]; i < b->vertex_edge_offsets[v + 1]; ++i) {
        int32_t f = b->vertex_edges[i];
        if (b->cut[f] && b->topology->edge_halfedge[2 * f + 1] >= 0) { /* every interior cut edge counts */
            ++count;
            if (f != e && is_seam_edge(b, f))
                found = f;
        }
    }
    if (count != 2 || found < 0)
        return -1;
    const int32_t *eh = b->topology->edge_halfedge;
    int32_t a0 = side_copy(b, eh[2 * e], v), a1 = side_copy(b, eh[2 * e + 1], v);
    int32_t b0 = side_copy(b, eh[2 * found], v), b1 = side_copy(b, eh[2 * found + 1], v);
    return ((a0 == b0 && a1 == b1) || (a0 == b1 && a1 == b0)) ? found : -1;
}

static pz_status append_seam(pattern_builder *b, pz_seam *seam, pz_ctx *ctx)
{
    if (!pz_grow((void **)&b->seams, &b->seam_capacity, (size_t)b->seam_count + 1, sizeof(pz_seam))) {
        free(seam->side_a);
        free(seam->side_b);
        return pattern_no_memory(b, ctx);
    }
    b->seams[b->seam_count++] = *seam;
    return PZ_OK;
}

/*
 * The chain of seam edges containing `start`, in order, into chain_edges;
 * returns the edge count and the chain's first vertex in *first_vertex. The
 * chain is walked backwards to its start (or once around when it is closed:
 * it then ends where it starts), then forwards, marking edges visited.
 */
static int32_t walk_chain(const pattern_builder *b, int32_t start, uint8_t *visited, int32_t *chain_edges,
                          int32_t *first_vertex)
{
    int32_t e = start, v = pz_he_from(b->topology, b->topology->edge_halfedge[2 * start]);
    for (;;) {
        int32_t previous = continuation(b, e, v);
        if (previous < 0 || previous == start)
            break;
        v = other_end(b, previous, v);
        e = previous;
    }
    int32_t edge_count = 0;
    *first_vertex = v;
    for (;;) {
        chain_edges[edge_count++] = e;
        visited[e] = 1;
        v = other_end(b, e, v);
        int32_t next = continuation(b, e, v);
        if (next < 0 || visited[next])
            return edge_count;
        e = next;
    }
}

static void reverse_pairs(pz_seam *seam)
{
    for (int32_t i = 0, j = seam->pair_count - 1; i < j; ++i, --j) {
        int32_t swap = seam->side_a[i];
        seam->side_a[i] = seam->side_a[j];
        seam->side_a[j] = swap;
        swap = seam->side_b[i];
        seam->side_b[i] = seam->side_b[j];
        seam->side_b[j] = swap;
    }
}

/* Pairs the copies along one chain (edge_count edges from first_vertex) and appends the seam. */
static pz_status pair_chain(pattern_builder *b, const int32_t *chain_edges, int32_t edge_count, int32_t first_vertex,
                            pz_ctx *ctx)
{
    const pz_topology *t = b->topology;
    pz_seam seam = {0};
    seam.pair_count = edge_count + 1;
    seam.side_a = malloc((size_t)seam.pair_count * sizeof(int32_t));
    seam.side_b = malloc((size_t)seam.pair_count * sizeof(int32_t));
    if (!seam.side_a || !seam.side_b) {
        free(seam.side_a);
        free(seam.side_b);
        return pattern_no_memory(b, ctx);
    }
    /* Side A of the first edge: the lower panel, or (a self-seam) the half-edge running along the chain. */
    int32_t h0 = t->edge_halfedge[2 * chain_edges[0]], h1 = t->edge_halfedge[2 * chain_edges[0] + 1];
    int32_t p0 = b->face_panel[pz_he_face(h0)], p1 = b->face_panel[pz_he_face(h1)];
    int32_t side_a_he = p0 < p1 ? h0 : p1 < p0 ? h1 : (pz_he_from(t, h0) == first_vertex ? h0 : h1);
    int32_t side_b_he = side_a_he == h0 ? h1 : h0;
    seam.panel_a = b->face_panel[pz_he_face(side_a_he)];
    seam.panel_b = b->face_panel[pz_he_face(side_b_he)];
    int32_t u = first_vertex;
    seam.side_a[0] = side_copy(b, side_a_he, u);
    seam.side_b[0] = side_copy(b, side_b_he, u);
    for (int32_t i = 0; i < edge_count; ++i) {
        int32_t ce = chain_edges[i];
        int32_t g0 = t->edge_halfedge[2 * ce], g1 = t->edge_halfedge[2 * ce + 1];
        /* Side A's half-edge of this edge is the one using side A's copy of the shared vertex u
         * (the copies continue: that is how chains were cut). */
        int32_t ha = side_copy(b, g0, u) == seam.side_a[i] ? g0 : g1, hb = ha == g0 ? g1 : g0;
        u = other_end(b, ce, u);
        seam.side_a[i + 1] = side_copy(b, ha, u);
        seam.side_b[i + 1] = side_copy(b, hb, u);
    }
    /* Orient along panel_a's boundary (panel_a on the left): side A's half-edges run with the chain. */
    if (pz_he_from(t, side_a_he) != first_vertex)
        reverse_pairs(&seam);
    return append_seam(b, &seam, ctx);
}

/*
 * A self-seam with exactly one end where its two sides share one copy of the
 * vertex is a slit ending inside its panel: a dart, sewn in 3D and open in
 * the pattern (the skirt's UV islands carry two each). It becomes a pz_dart:
 * the tip is that shared copy, the legs run from the open end towards it.
 * Seams opening a tube or joining loops end on the boundary at both ends
 * (two copies each) and stay seams. Moves the last seam into the darts.
 */
static pz_status seam_to_dart_if_slit(pattern_builder *b, pz_ctx *ctx)
{
    pz_seam *seam = &b->seams[b->seam_count - 1];
    int32_t last = seam->pair_count - 1;
    int tip_first = seam->side_a[0] == seam->side_b[0], tip_last = seam->side_a[last] == seam->side_b[last];
    if (seam->panel_a != seam->panel_b || last < 1 || tip_first == tip_last)
        return PZ_OK;
    if (!pz_grow((void **)&b->darts, &b->dart_capacity, (size_t)b->dart_count + 1, sizeof(pz_dart)))
        return pattern_no_memory(b, ctx);
    if (tip_first)
        reverse_pairs(seam);
    pz_dart *dart = &b->darts[b->dart_count++];
    dart->panel = seam->panel_a;
    dart->tip = seam->side_a[last];
    dart->pair_count = last;
    dart->leg_a = seam->side_a;
    dart->leg_b = seam->side_b;
    --b->seam_count;
    return PZ_OK;
}

pz_status pattern_find_automatic_seams(pattern_builder *b, pz_ctx *ctx)
{
    b->dart_capacity = (size_t)b->dart_count; /* the explicit darts' array is exactly that long */
    int32_t edge_count = b->topology->edge_count;
    uint8_t *visited = calloc((size_t)edge_count + 1, 1);
    int32_t *chain_edges = malloc((size_t)edge_count * sizeof(int32_t) + 1);
    pz_status status = PZ_OK;
    if (!visited || !chain_edges)
        status = pattern_no_memory(b, ctx);
    for (int32_t e = 0; e < edge_count && !status; ++e)
        if (is_seam_edge(b, e) && !visited[e]) {
            int32_t first_vertex, count = walk_chain(b, e, visited, chain_edges, &first_vertex);
            status = pair_chain(b, chain_edges, count, first_vertex, ctx);
            if (!status)
                status = seam_to_dart_if_slit(b, ctx);
        }
    free(visited);
    free(chain_edges);
    return status;
}

/* ------------------------------------------------------------------------ */
/* 6. Explicit correspondences                                               */
/* ------------------------------------------------------------------------ */

pz_status pattern_index_copies(pattern_builder *b, pz_ctx *ctx)
{
    int32_t ng = b->garment->vertex_count, nc = b->cut_mesh->vertex_count;
    b->copy_offsets = calloc((size_t)ng + 1, sizeof(int32_t));
    b->copies = malloc((size_t)nc * sizeof(int32_t) + 1);
    int32_t *fill = malloc((size_t)ng * sizeof(int32_t) + 1);
    if (!b->copy_offsets || !b->copies || !fill) {
        free(fill);
        return pattern_no_memory(b, ctx);
    }
    for (int32_t c = 0; c < nc; ++c)
        ++b->copy_offsets[b->vertex_origin[c] + 1];
    for (int32_t v = 0; v < ng; ++v)
        b->copy_offsets[v + 1] += b->copy_offsets[v];
    memcpy(fill, b->copy_offsets, (size_t)ng * sizeof(int32_t));
    for (int32_t c = 0; c < nc; ++c)
        b->copies[fill[b->vertex_origin[c]]++] = c;
    free(fill);
    return PZ_OK;
}

static pz_status check_vertex_ids(const pattern_builder *b, const char *what, int32_t index, const int32_t *ids,
                                  int32_t count, pz_ctx *ctx)
{
    for (int32_t i = 0; i < count; ++i)
        if (ids[i] < 0 || ids[i] >= b->garment->vertex_count)
            return pz_error(ctx, PZ_ERR_DATA, "%s: %s %d: vertex %d out of range (the garment has %d vertices)", b->path,
                            what, (int)index, (int)ids[i], (int)b->garment->vertex_count);
    return PZ_OK;
}

/*
 * A chain of garment vertices along cut edges -> the copies on its two sides.
 * Side A is the side of the half-edge running from ids[0] to ids[1]. Marks
 * the edges explicit.
 */
static pz_status map_cut_chain(pattern_builder *b, const char *what, int32_t index, const int32_t *ids, int32_t count,
                               int32_t *side_a, int32_t *side_b, int32_t *panel_a, int32_t *panel_b, pz_ctx *ctx)
{
    const pz_topology *t = b->topology;
    for (int32_t i = 0; i + 1 < count; ++i) {
        int32_t e = pattern_find_edge(b, ids[i], ids[i + 1]);
        if (e < 0 || !b->cut[e] || t->edge_halfedge[2 * e + 1] < 0)
            return pz_error(ctx, PZ_ERR_DATA, "%s: %s %d: vertices %d-%d are not joined by a cut edge", b->path, what,
                            (int)index, (int)ids[i], (int)ids[i + 1]);
        if (b->explicit_edge[e])
            return pz_error(ctx, PZ_ERR_DATA, "%s: %s %d: edge %d-%d is already in another seam or dart", b->path, what,
                            (int)index, (int)ids[i], (int)ids[i + 1]);
        int32_t g0 = t->edge_halfedge[2 * e], g1 = t->edge_halfedge[2 * e + 1], ha, hb;
        if (i == 0)
            ha = pz_he_from(t, g0) == ids[0] ? g0 : g1;
        else if (side_copy(b, g0, ids[i]) == side_a[i])
            ha = g0;
        else if (side_copy(b, g1, ids[i]) == side_a[i])
            ha = g1;
        else
            return pz_error(ctx, PZ_ERR_DATA, "%s: %s %d: the cut through vertex %d branches", b->path, what, (int)index,
                            (int)ids[i]);
        hb = ha == g0 ? g1 : g0;
        if (i == 0) {
            side_a[0] = side_copy(b, ha, ids[0]);
            side_b[0] = side_copy(b, hb, ids[0]);
            *panel_a = b->face_panel[pz_he_face(ha)];
            *panel_b = b->face_panel[pz_he_face(hb)];
        }
        side_a[i + 1] = side_copy(b, ha, ids[i + 1]);
        side_b[i + 1] = side_copy(b, hb, ids[i + 1]);
        b->explicit_edge[e] = 1;
    }
    return PZ_OK;
}

/* The panel most of the copies of ids lie in. */
static int32_t majority_panel(const pattern_builder *b, const int32_t *ids, int32_t count, int32_t *votes)
{
    memset(votes, 0, (size_t)b->panel_count * sizeof(int32_t));
    int32_t best = 0;
    for (int32_t i = 0; i < count; ++i)
        for (int32_t k = b->copy_offsets[ids[i]]; k < b->copy_offsets[ids[i] + 1]; ++k) {
            int32_t p = b->vertex_panel[b->copies[k]];
            if (p >= 0 && ++votes[p] > votes[best])
                best = p;
        }
    return best;
}

/* The boundary copy of garment vertex v in `panel` (next to `previous` when several), or -1. */
static int32_t boundary_copy(const pattern_builder *b, int32_t v, int32_t panel, int32_t previous)
{
    int32_t chosen = -1;
    for (int32_t k = b->copy_offsets[v]; k < b->copy_offsets[v + 1]; ++k) {
        int32_t c = b->copies[k];
        if (b->vertex_panel[c] != panel || !b->cut_topology->vertex_on_boundary[c])
            continue;
        if (chosen < 0)
            chosen = c;
        if (previous >= 0) {
            int32_t ring[64];
            int32_t n = pz_topology_vertex_ring(b->cut_topology, c, ring, 64);
            for (int32_t i = 0; i < n && i < 64; ++i)
                if (ring[i] == previous)
                    return c;
        }
    }
    return chosen;
}

/* Boundary vertices of one side (separate panels) -> copies in the side's majority panel. */
static pz_status map_boundary_side(pattern_builder *b, const char *what, int32_t index, const int32_t *ids,
                                   int32_t count, int32_t *copies_out, int32_t *panel_out, int32_t *votes, pz_ctx *ctx)
{
    int32_t panel = majority_panel(b, ids, count, votes);
    for (int32_t i = 0; i < count; ++i) {
        copies_out[i] = boundary_copy(b, ids[i], panel, i ? copies_out[i - 1] : -1);
        if (copies_out[i] < 0)
            return pz_error(ctx, PZ_ERR_DATA, "%s: %s %d: vertex %d is not on a cut or the boundary of panel %d", b->path,
                            what, (int)index, (int)ids[i], (int)panel);
    }
    *panel_out = panel;
    return PZ_OK;
}

static pz_status map_explicit_seam(pattern_builder *b, const pz_seam *given, int32_t index, int32_t *votes, pz_ctx *ctx)
{
    pz_status status;
    if (given->pair_count < 2)
        return pz_error(ctx, PZ_ERR_DATA, "%s: seam %d has %d pairs (at least 2 needed)", b->path, (int)index,
                        (int)given->pair_count);
    if ((status = check_vertex_ids(b, "seam", index, given->side_a, given->pair_count, ctx)) ||
        (status = check_vertex_ids(b, "seam", index, given->side_b, given->pair_count, ctx)))
        return status;
    pz_seam seam = {0};
    seam.pair_count = given->pair_count;
    seam.side_a = malloc((size_t)seam.pair_count * sizeof(int32_t));
    seam.side_b = malloc((size_t)seam.pair_count * sizeof(int32_t));
    if (!seam.side_a || !seam.side_b) {
        free(seam.side_a);
        free(seam.side_b);
        return pattern_no_memory(b, ctx);
    }
    int on_cut = memcmp(given->side_a, given->side_b, (size_t)seam.pair_count * sizeof(int32_t)) == 0;
    if (on_cut)
        status = map_cut_chain(b, "seam", index, given->side_a, seam.pair_count, seam.side_a, seam.side_b,
                               &seam.panel_a, &seam.panel_b, ctx);
    else if (!(status = map_boundary_side(b, "seam", index, given->side_a, seam.pair_count, seam.side_a, &seam.panel_a,
                                          votes, ctx)))
        status = map_boundary_side(b, "seam", index, given->side_b, seam.pair_count, seam.side_b, &seam.panel_b, votes,
                                   ctx);
    if (status) {
        free(seam.side_a);
        free(seam.side_b);
        return status;
    }
    return append_seam(b, &seam, ctx);
}

static pz_status map_explicit_dart(pattern_builder *b, const pz_dart *given, int32_t index, pz_dart *dart,
                                   int32_t *votes, pz_ctx *ctx)
{
    pz_status status;
    int32_t n = given->pair_count;
    if (n < 1)
        return pz_error(ctx, PZ_ERR_DATA, "%s: dart %d has no leg pairs", b->path, (int)index);
    if ((status = check_vertex_ids(b, "dart", index, &given->tip, 1, ctx)) ||
        (status = check_vertex_ids(b, "dart", index, given->leg_a, n, ctx)) ||
        (status = check_vertex_ids(b, "dart", index, given->leg_b, n, ctx)))
        return status;
    dart->pair_count = n;
    dart->leg_a = malloc((size_t)(n + 1) * sizeof(int32_t));
    dart->leg_b = malloc((size_t)(n + 1) * sizeof(int32_t));
    int32_t *chain = malloc((size_t)(n + 1) * sizeof(int32_t));
    if (!dart->leg_a || !dart->leg_b || !chain) {
        free(chain);
        return pattern_no_memory(b, ctx);
    }
    int closed = memcmp(given->leg_a, given->leg_b, (size_t)n * sizeof(int32_t)) == 0;
    if (closed) {
        /* Cut open before cutting the garment (cut_closed_darts): the chain legs..tip has two sides. */
        memcpy(chain, given->leg_a, (size_t)n * sizeof(int32_t));
        chain[n] = given->tip;
        int32_t panel_b;
        status = map_cut_chain(b, "dart", index, chain, n + 1, dart->leg_a, dart->leg_b, &dart->panel, &panel_b, ctx);
        if (!status)
            dart->tip = dart->leg_a[n];
    } else {
        memcpy(chain, given->leg_a, (size_t)n * sizeof(int32_t));
        chain[n] = given->tip;
        dart->panel = majority_panel(b, chain, n + 1, votes);
        dart->tip = boundary_copy(b, given->tip, dart->panel, -1);
        if (dart->tip < 0)
            status = pz_error(ctx, PZ_ERR_DATA, "%s: dart %d: tip %d is not on the boundary of panel %d", b->path,
                              (int)index, (int)given->tip, (int)dart->panel);
        for (int32_t i = 0; i < n && !status; ++i) {
            dart->leg_a[i] = boundary_copy(b, given->leg_a[i], dart->panel, i ? dart->leg_a[i - 1] : -1);
            dart->leg_b[i] = boundary_copy(b, given->leg_b[i], dart->panel, i ? dart->leg_b[i - 1] : -1);
            if (dart->leg_a[i] < 0 || dart->leg_b[i] < 0)
                status = pz_error(ctx, PZ_ERR_DATA, "%s: dart %d: leg pair %d-%d is not on the boundary of panel %d",
                                  b->path, (int)index, (int)given->leg_a[i], (int)given->leg_b[i], (int)dart->panel);
        }
    }
    free(chain);
    return status;
}

pz_status pattern_map_explicit(pattern_builder *b, const pz_correspondences *given, pz_ctx *ctx)
{
    int32_t *votes = malloc((size_t)b->panel_count * sizeof(int32_t) + 1);
    pz_status status = votes ? PZ_OK : pattern_no_memory(b, ctx);
    for (int32_t s = 0; given && s < given->seam_count && !status; ++s)
        status = map_explicit_seam(b, &given->seams[s], s, votes, ctx);
    if (!status && given && given->dart_count > 0) {
        b->darts = calloc((size_t)given->dart_count, sizeof(pz_dart));
        if (!b->darts)
            status = pattern_no_memory(b, ctx);
        for (int32_t d = 0; d < given->dart_count && !status; ++d) {
            b->dart_count = d + 1; /* so that a failure frees what was allocated */
            status = map_explicit_dart(b, &given->darts[d], d, &b->darts[d], votes, ctx);
        }
    }
    free(votes);
    return status;
}
