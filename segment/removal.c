/*
 * segment/removal.c -- the last two steps of the layout (pietroni2022
 * Sec. 4.2): removal of redundant path segments and darts.
 *
 * Segments: the cut edges split at *nodes*, the vertices on the garment's
 * border or where the number of cut edges is not 2 (junctions and tips);
 * a cycle of cut edges without a node is one closed segment.
 *
 * Removal: in reverse insertion order (a segment's order is the latest
 * inserted path among its edges), sketched segments never, the segments on
 * the symmetry plane last (Sec. 4.2, "Symmetry"), each segment is uncut
 * together with its mirror image (the stretch of its mirror segment between
 * the images of its vertices: mirror_edges; a segment of half 1 that is the
 * image of one of half 0 is not tried on its own, and a stub of a few edges
 * the two sides' different junctions leave goes with it); the removal is
 * kept when every panel it touches still meets the goals (a mirror pair
 * judged as one piece: seg_panel_failures). Neither a removal nor a dart is tried next
 * to a panel that already fails on strain or injectivity (re-gluing only
 * adds faces to it). A removal that would leave a cut ending
 * inside a panel (a T-junction stub) is skipped: such partial seams are the
 * darts' business. Passes repeat (at most REMOVAL_PASSES) while one removes
 * something, since a removal merges its neighbours into longer segments.
 *
 * Darts: the remaining segments between two panels (not a panel and
 * itself, not their own mirror image), ordered by the angle defect of the
 * region they span (positive, low first; saddles last: Fig. 10), are split into DART_PIECES
 * sub-paths; the segment is re-glued from its end of lower curvature, and the
 * dart kept is the one glued furthest for which every panel touched meets
 * the goals. The part left open is a slit whose free end is the dart tip.
 * Limits (Sec. 3.1): the open part at least DART_MIN_PIECES pieces and at
 * most DART_MAX_EXTENT_FRACTION of the merged panel's extent (its
 * bounding-box diagonal: "the dart length usually should not exceed a
 * fraction of the patch length"), every dart of the panel opening by at
 * least DART_MIN_OPENING_DEG in the flattening ("opening angles sufficiently
 * large") and taking in min_dart_intake_mm at its mouth (a goal of the
 * judge), and the panel's strain below that of the segment fully glued (a
 * dart takes in fabric where the closed seam strains it). A dart adds no
 * corner (segment/goals.c), so re-gluing part of a seam is judged on strain
 * and injectivity, as a pattern maker would.
 *
 * Slivers: what is left under a piece-shape goal at the end is merged into a
 * neighbour, trading strain alone (seg_merge_slivers, below).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define REMOVAL_PASSES 3
#define DART_PIECES 8
#define DART_MIN_PIECES 2
#define DART_MAX_EXTENT_FRACTION 0.5
/* A dart opening by less takes in under 3.5 mm per 10 cm of its length: not worth sewing. */
#define DART_MIN_OPENING_DEG 2.0
/* No dart is tried along a segment whose fully re-glued panel strains by more than this times S. */
#define DART_MAX_RELIEF 2.0

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

static int32_t other_end(const seg_layout *layout, int32_t e, int32_t v)
{
    int32_t h = layout->topology->edge_halfedge[2 * e];
    int32_t a = pz_he_from(layout->topology, h);
    return a == v ? pz_he_to(layout->topology, h) : a;
}

static int is_node(const seg_layout *layout, int32_t v)
{
    return layout->topology->vertex_on_boundary[v] || seg_cut_degree(layout, v) != 2;
}

/* The unvisited cut edge at v, or -1. */
static int32_t next_cut_edge(const seg_layout *layout, int32_t v, const uint8_t *visited)
{
    for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i) {
        int32_t e = layout->vertex_edges[i];
        if (layout->edge_cut[e] && !visited[e])
            return e;
    }
    return -1;
}

/* Walks a chain from v along edge e until a node (or back to the start); appends it to out. */
static int walk_segment(const seg_layout *layout, int32_t v, int32_t e, uint8_t *visited, seg_segment *out)
{
    int32_t capacity = 16, start = v;
    out->edges = malloc((size_t)capacity * sizeof(int32_t));
    out->vertices = malloc(((size_t)capacity + 1) * sizeof(int32_t));
    if (!out->edges || !out->vertices)
        return 0;
    out->vertices[0] = v;
    out->owner = -1;
    while (e >= 0) {
        if (out->edge_count == capacity) {
            capacity *= 2;
            int32_t *edges = realloc(out->edges, (size_t)capacity * sizeof(int32_t));
            int32_t *vertices = edges ? realloc(out->vertices, ((size_t)capacity + 1) * sizeof(int32_t)) : NULL;
            if (edges)
                out->edges = edges;
            if (vertices)
                out->vertices = vertices;
            if (!edges || !vertices)
                return 0;
        }
        visited[e] = 1;
        int32_t owner = layout->edge_owner[e];
        if (owner > out->owner)
            out->owner = owner;
        if (owner >= 0)
            out->sketch |= layout->paths[owner].sketch;
        out->edges[out->edge_count++] = e;
        v = other_end(layout, e, v);
        out->vertices[out->edge_count] = v;
        if (v == start) {
            out->closed = 1;
            break;
        }
        e = is_node(layout, v) ? -1 : next_cut_edge(layout, v, visited);
    }
    return 1;
}

static int append_segment(seg_segments *out, int32_t *capacity)
{
    if (out->count < *capacity)
        return 1;
    *capacity = *capacity ? 2 * *capacity : 32;
    seg_segment *grown = realloc(out->items, (size_t)*capacity * sizeof(seg_segment));
    if (!grown)
        return 0;
    out->items = grown;
    return 1;
}

pz_status seg_segments_build(const seg_layout *layout, seg_segments *out, pz_ctx *ctx)
{
    out->count = 0;
    out->items = NULL;
    const pz_topology *t = layout->topology;
    uint8_t *visited = calloc((size_t)t->edge_count + 1, 1);
    if (!visited)
        return nomem(ctx);
    int32_t capacity = 0;
    int ok = 1;
    /* Chains from nodes first, then the cycles that have none; vertex and edge order keep it deterministic. */
    for (int pass = 0; pass < 2 && ok; ++pass)
        for (int32_t v = 0; v < t->vertex_count && ok; ++v) {
            if (pass == 0 && !is_node(layout, v))
                continue;
            for (int32_t e; ok && (e = next_cut_edge(layout, v, visited)) >= 0;) {
                if (!(ok = append_segment(out, &capacity)))
                    break;
                seg_segment *s = out->items + out->count++;
                memset(s, 0, sizeof *s);
                ok = walk_segment(layout, v, e, visited, s);
            }
        }
    free(visited);
    if (!ok) {
        seg_segments_clear(out);
        return nomem(ctx);
    }
    return PZ_OK;
}

void seg_segments_clear(seg_segments *segments)
{
    for (int32_t i = 0; i < segments->count; ++i) {
        free(segments->items[i].edges);
        free(segments->items[i].vertices);
    }
    free(segments->items);
    segments->items = NULL;
    segments->count = 0;
}

/* ---------------------------------------------------------------- edit sets */

/* ---------------------------------------------------------------- mirror segments */

/*
 * The mirror image of a segment: the segment the mirror images of its
 * vertices (vertex_mirror) touch most, each image voting for the segments of
 * the cut edges at it, at least half of the segment's vertices agreeing.
 * Segment-level rather than edge by edge: on a garment that is only nearly
 * symmetric the images of an edge's two ends are often not neighbours (the
 * mirrored path closed that gap with other edges), so an edge-wise map misses
 * part of the mirror seam, and uncutting the rest would leave a stub.
 */

void seg_mirror_map_free(seg_mirror_map *map)
{
    free(map->edge_segment), free(map->votes), free(map->touched), free(map->mirror), free(map->claimed);
    memset(map, 0, sizeof *map);
}

static int32_t mirror_segment(const seg_layout *layout, seg_mirror_map *map, int32_t index);

/* The half a segment lies in (segment/mirror.c): the one most of its edges lie inside; 2 on the plane cut,
 * -1 without halves. */
static int segment_half(const seg_layout *layout, const seg_segment *s)
{
    if (!layout->face_half)
        return -1;
    const pz_topology *t = layout->topology;
    int32_t inside[2] = {0, 0};
    for (int32_t i = 0; i < s->edge_count; ++i) {
        int32_t a = t->edge_halfedge[2 * s->edges[i]], b = t->edge_halfedge[2 * s->edges[i] + 1];
        uint8_t half = layout->face_half[pz_he_face(a)];
        if (b < 0 || layout->face_half[pz_he_face(b)] == half)
            ++inside[half];
    }
    return inside[0] + inside[1] == 0 ? 2 : inside[1] > inside[0];
}

/* 0 when out of memory. Without a plane the map is empty (every segment without a mirror). */
int seg_mirror_map_build(const seg_layout *layout, const seg_segments *segments, seg_mirror_map *map)
{
    memset(map, 0, sizeof *map);
    map->segments = segments;
    if (!layout->symmetry.found)
        return 1;
    size_t count = (size_t)segments->count + 1;
    map->edge_segment = malloc(((size_t)layout->topology->edge_count + 1) * sizeof(int32_t));
    map->votes = calloc(count, sizeof(int32_t));
    map->touched = malloc(count * sizeof(int32_t));
    map->mirror = malloc(count * sizeof(int32_t));
    map->claimed = calloc(count, 1);
    if (!map->edge_segment || !map->votes || !map->touched || !map->mirror || !map->claimed) {
        seg_mirror_map_free(map);
        return 0;
    }
    memset(map->edge_segment, 0xff, (size_t)layout->topology->edge_count * sizeof(int32_t));
    for (int32_t i = 0; i < segments->count; ++i) {
        map->mirror[i] = -2;
        for (int32_t k = 0; k < segments->items[i].edge_count; ++k)
            map->edge_segment[segments->items[i].edges[k]] = i;
    }
    /* The layout is made on half 0: a segment there decides for its image on half 1, which is not tried on its
     * own (the two sides' segments need not match one to one, so trying both could uncut one side alone). */
    for (int32_t i = 0; i < segments->count; ++i) {
        if (segment_half(layout, segments->items + i) != 0)
            continue;
        int32_t m = mirror_segment(layout, map, i);
        if (m >= 0 && segment_half(layout, segments->items + m) == 1)
            map->claimed[m] = 1;
    }
    return 1;
}

/* The mirror segment of segment `index` by the votes of its vertices' images (-1 none). */
static int32_t vote_mirror(const seg_layout *layout, seg_mirror_map *map, int32_t index)
{
    const seg_segment *s = map->segments->items + index;
    const int32_t *vertex_mirror = layout->symmetry.vertex_mirror;
    int32_t touched = 0, n = s->closed ? s->edge_count : s->edge_count + 1;
    for (int32_t i = 0; i < n; ++i) {
        int32_t w = vertex_mirror[s->vertices[i]];
        if (w < 0)
            continue;
        int32_t voted[16], voted_count = 0; /* a vertex votes once per segment, though two of its edges lie on it */
        for (int32_t j = layout->vertex_edge_offsets[w]; j < layout->vertex_edge_offsets[w + 1]; ++j) {
            int32_t other = map->edge_segment[layout->vertex_edges[j]];
            int seen = other < 0;
            for (int32_t k = 0; k < voted_count && !seen; ++k)
                seen = voted[k] == other;
            if (seen || voted_count == 16)
                continue;
            voted[voted_count++] = other;
            if (map->votes[other]++ == 0)
                map->touched[touched++] = other;
        }
    }
    int32_t best = -1, best_votes = 0;
    for (int32_t k = 0; k < touched; ++k) {
        int32_t other = map->touched[k];
        if (map->votes[other] > best_votes || (map->votes[other] == best_votes && other < best))
            best = other, best_votes = map->votes[other];
    }
    for (int32_t k = 0; k < touched; ++k)
        map->votes[map->touched[k]] = 0;
    return 2 * best_votes >= n ? best : -1;
}

/* The mirror segment of segment `index` (itself for a segment that is its own image), -1 none; computed once. */
static int32_t mirror_segment(const seg_layout *layout, seg_mirror_map *map, int32_t index)
{
    if (!map->mirror)
        return -1;
    if (map->mirror[index] == -2)
        map->mirror[index] = vote_mirror(layout, map, index);
    return map->mirror[index];
}

/*
 * The mirror image of edges[0..n-1] (segment `index`, or a part of it) into
 * out (room for the mirror segment's edge count): the stretch of the mirror
 * segment between the first and the last of its vertices that are images
 * of the part's vertices. The two sides' segments need not match one to one
 * (a junction an edge off on one side splits a segment there and not on the
 * other): a segment whose image is part of a longer one takes that part
 * only. Returns the count.
 */
static int32_t mirror_edges(const seg_layout *layout, seg_mirror_map *map, int32_t index, const int32_t *edges,
                            int32_t n, int32_t *out)
{
    int32_t m = mirror_segment(layout, map, index);
    if (m < 0 || m == index)
        return 0;
    const seg_segment *image = map->segments->items + m;
    const pz_topology *t = layout->topology;
    int32_t first = image->edge_count + 1, last = -1;
    for (int32_t i = 0; i < n; ++i) {
        int32_t h = t->edge_halfedge[2 * edges[i]];
        int32_t ends[2] = {pz_he_from(t, h), pz_he_to(t, h)};
        for (int k = 0; k < 2; ++k) {
            int32_t w = layout->symmetry.vertex_mirror[ends[k]];
            for (int32_t j = 0; w >= 0 && j <= image->edge_count; ++j)
                if (image->vertices[j] == w) {
                    first = j < first ? j : first;
                    last = j > last ? j : last;
                }
        }
    }
    if (last <= first)
        return 0;
    memcpy(out, image->edges + first, (size_t)(last - first) * sizeof(int32_t));
    return last - first;
}

/* edges[0..n-1] (segment `index` or a part of it from one end) and, with symmetry, their mirror image's edges
 * that are cut and not sketched. */
int seg_edge_set_make(const seg_layout *layout, seg_mirror_map *map, int32_t index, const int32_t *edges, int32_t n,
                      seg_edge_set *out)
{
    int32_t m = mirror_segment(layout, map, index);
    int32_t mirror_count = m >= 0 ? map->segments->items[m].edge_count : 0;
    out->count = 0;
    out->edges = malloc(((size_t)n + mirror_count) * sizeof(int32_t) + 1);
    if (!out->edges)
        return 0;
    for (int32_t i = 0; i < n; ++i)
        out->edges[out->count++] = edges[i];
    int32_t found = mirror_edges(layout, map, index, edges, n, out->edges + n);
    for (int32_t i = 0; i < found; ++i) {
        int32_t e = out->edges[n + i];
        if (!layout->edge_cut[e] || (layout->edge_owner[e] >= 0 && layout->paths[layout->edge_owner[e]].sketch))
            continue;
        int seen = 0;
        for (int32_t j = 0; j < n && !seen; ++j)
            seen = out->edges[j] == e;
        if (!seen)
            out->edges[out->count++] = e;
    }
    return 1;
}

void seg_edge_set_apply(seg_layout *layout, const seg_edge_set *set, uint8_t cut)
{
    for (int32_t i = 0; i < set->count; ++i)
        layout->edge_cut[set->edges[i]] = cut;
    layout->labels_valid = 0;
}

/* 1 when, with the set uncut, some inner vertex keeps exactly one cut edge (a stub). */
int seg_leaves_stub(seg_layout *layout, const seg_edge_set *set)
{
    const pz_topology *t = layout->topology;
    int labels_valid = layout->labels_valid; /* the flags come back as they were */
    seg_edge_set_apply(layout, set, 0);
    int stub = 0;
    for (int32_t i = 0; i < set->count && !stub; ++i) {
        int32_t h = t->edge_halfedge[2 * set->edges[i]];
        int32_t ends[2] = {pz_he_from(t, h), pz_he_to(t, h)};
        for (int k = 0; k < 2 && !stub; ++k)
            stub = !t->vertex_on_boundary[ends[k]] && seg_cut_degree(layout, ends[k]) == 1;
    }
    seg_edge_set_apply(layout, set, 1);
    layout->labels_valid = labels_valid;
    return stub;
}

/* The stubs a symmetric removal may take along: at most this many edges. */
#define MIRROR_STUB_EDGES 3

static int32_t other_cut_edge(const seg_layout *layout, int32_t v, int32_t not_e)
{
    for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i) {
        int32_t e = layout->vertex_edges[i];
        if (layout->edge_cut[e] && e != not_e)
            return e;
    }
    return -1;
}

static int removable_edge(const seg_layout *layout, int32_t e)
{
    return layout->edge_owner[e] < 0 || !layout->paths[layout->edge_owner[e]].sketch;
}

/*
 * With halves (segment/mirror.c), the sides' junctions need not match one to
 * one: a mirrored path may meet another an edge or two beyond where the
 * original meets its partner, so uncutting a segment and its image can leave
 * a stub of a few edges on one side where the other has none. Such stubs (at
 * most MIRROR_STUB_EDGES edges, no sketch) go with the set rather than block
 * the removal. Returns 0 when out of memory.
 */
static int take_mirror_stubs(seg_layout *layout, seg_edge_set *set)
{
    if (!layout->face_half)
        return 1;
    const pz_topology *t = layout->topology;
    int labels_valid = layout->labels_valid;
    int ok = 1;
    seg_edge_set_apply(layout, set, 0);
    for (int32_t i = 0; i < set->count && ok; ++i) {
        int32_t h = t->edge_halfedge[2 * set->edges[i]];
        int32_t ends[2] = {pz_he_from(t, h), pz_he_to(t, h)};
        for (int k = 0; k < 2 && ok; ++k) {
            int32_t v = ends[k];
            if (t->vertex_on_boundary[v] || seg_cut_degree(layout, v) != 1)
                continue;
            int32_t chain[MIRROR_STUB_EDGES + 1], length = 0, e = other_cut_edge(layout, v, -1);
            while (e >= 0 && length <= MIRROR_STUB_EDGES && removable_edge(layout, e)) {
                chain[length++] = e;
                v = other_end(layout, e, v);
                if (t->vertex_on_boundary[v] || seg_cut_degree(layout, v) != 2)
                    break; /* a node: the stub ends here */
                e = other_cut_edge(layout, v, e);
            }
            if (length == 0 || length > MIRROR_STUB_EDGES || !removable_edge(layout, chain[length - 1]))
                continue;
            int32_t *grown = realloc(set->edges, ((size_t)set->count + length) * sizeof(int32_t));
            if (!(ok = grown != NULL))
                break;
            set->edges = grown;
            for (int32_t j = 0; j < length; ++j) {
                set->edges[set->count++] = chain[j];
                layout->edge_cut[chain[j]] = 0;
            }
        }
    }
    seg_edge_set_apply(layout, set, 1);
    layout->labels_valid = labels_valid;
    return ok;
}

/* Relabels and evaluates the panels next to the set's edges (a mirror pair's both panels); *ok = 1 when none fails a
 * goal in `mask` (nor, with `bands`, is a band round the body: segment/preference.c). */
static pz_status panels_pass(seg_layout *layout, const seg_edge_set *set, unsigned mask, int bands, int *ok,
                             pz_ctx *ctx)
{
    *ok = 0;
    pz_status status = seg_label_panels(layout, ctx);
    if (status)
        return status;
    uint8_t *want = calloc((size_t)layout->panel_count + 1, 1);
    if (!want)
        return nomem(ctx);
    const pz_topology *t = layout->topology;
    for (int32_t i = 0; i < set->count; ++i)
        for (int s = 0; s < 2; ++s) {
            int32_t h = t->edge_halfedge[2 * set->edges[i] + s];
            if (h >= 0)
                want[layout->face_panel[pz_he_face(h)]] = 1;
        }
    for (int32_t p = 0; p < layout->panel_count; ++p) { /* a pair is judged together: both evaluated */
        int32_t q = want[p] == 1 ? seg_panel_partner(layout, p) : -1;
        if (q >= 0 && !want[q])
            want[q] = 2;
    }
    /* A band is known from the faces alone: no flattening for it. */
    for (int32_t p = 0; bands && p < layout->panel_count; ++p) {
        if (!want[p])
            continue;
        seg_panel_shape(layout, p);
        if (seg_panel_is_band(layout, p)) {
            free(want);
            return PZ_OK;
        }
    }
    status = seg_evaluate_panels(layout, want, ctx);
    *ok = !status;
    for (int32_t p = 0; p < layout->panel_count && *ok; ++p)
        if (want[p] && ((seg_panel_failures(layout, p) & mask) || (bands && seg_panel_is_band(layout, p))))
            *ok = 0;
    free(want);
    return status;
}

/* Every goal but the piece shapes: merging panels never makes one narrower or smaller (its largest circle
 * and its area only grow), so a panel next to the set that misses them (a sketch's sliver) blocks nothing;
 * and no band round the body (segment/preference.c). */
static pz_status panels_ok(seg_layout *layout, const seg_edge_set *set, int *ok, pz_ctx *ctx)
{
    return panels_pass(layout, set, ~(unsigned)PZ_GOAL_SHAPE, 1, ok, ctx);
}

/*
 * *worth = 0 when a panel next to the set already fails on strain or
 * injectivity: re-gluing only adds faces to it, so the trial would fail (with
 * unreachable goals, S = 0, this spares a flattening per segment).
 */
static pz_status worth_trying(seg_layout *layout, const seg_edge_set *set, int *worth, pz_ctx *ctx)
{
    return panels_pass(layout, set, PZ_GOAL_STRAIN | PZ_GOAL_NOT_INJECTIVE | PZ_GOAL_VETOED, 0, worth, ctx);
}

/* ---------------------------------------------------------------- removal */

/* 1 for a segment of the cut between the two halves (segment/mirror.c), or, without halves, one lying on the
 * plane. */
static int on_plane(const seg_layout *layout, const seg_segment *s)
{
    if (!layout->symmetry.found)
        return 0;
    for (int32_t i = 0; i < s->edge_count; ++i)
        if (layout->edge_plane ? !layout->edge_plane[s->edges[i]]
                               : layout->symmetry.vertex_side[s->vertices[i]] != 1 ||
                                     layout->symmetry.vertex_side[s->vertices[i + 1]] != 1)
            return 0;
    return 1;
}

/* A segment's removal key (no global state for qsort's comparator: pz_segment may run in several threads). */
typedef struct removal_order {
    int on_plane;
    int32_t owner, first_edge, segment;
} removal_order;

/* Removal order: off-plane before on-plane, then latest inserted first, then by first edge. */
static int compare_removal(const void *l, const void *r)
{
    const removal_order *a = l, *b = r;
    if (a->on_plane != b->on_plane)
        return a->on_plane - b->on_plane;
    if (a->owner != b->owner)
        return a->owner > b->owner ? -1 : 1;
    return (a->first_edge > b->first_edge) - (a->first_edge < b->first_edge);
}

int seg_all_cut(const seg_layout *layout, const seg_segment *s)
{
    for (int32_t i = 0; i < s->edge_count; ++i)
        if (!layout->edge_cut[s->edges[i]])
            return 0;
    return 1;
}

/* Tries to uncut segment `index` (with its mirror); *removed = 1 when kept uncut. */
static pz_status try_remove(seg_layout *layout, seg_mirror_map *map, int32_t index, int *removed, pz_ctx *ctx)
{
    *removed = 0;
    const seg_segment *s = map->segments->items + index;
    seg_edge_set set;
    if (!seg_edge_set_make(layout, map, index, s->edges, s->edge_count, &set) || !take_mirror_stubs(layout, &set)) {
        free(set.edges);
        return nomem(ctx);
    }
    int worth = 0;
    int stub = seg_leaves_stub(layout, &set);
    pz_status status = stub ? PZ_OK : worth_trying(layout, &set, &worth, ctx);
    if (!status && worth) {
        int ok = 0;
        seg_edge_set_apply(layout, &set, 0);
        status = panels_ok(layout, &set, &ok, ctx);
        if (!status && !ok) {
            seg_edge_set_apply(layout, &set, 1);
            status = seg_label_panels(layout, ctx);
        }
        *removed = ok && !status;
    }
    free(set.edges);
    return status;
}

pz_status seg_remove_pass(seg_layout *layout, int32_t *removed, pz_ctx *ctx)
{
    *removed = 0;
    pz_status status = PZ_OK;
    for (int pass = 0; pass < REMOVAL_PASSES && !status; ++pass) {
        seg_segments segments;
        if ((status = seg_segments_build(layout, &segments, ctx)))
            break;
        removal_order *order = malloc(((size_t)segments.count + 1) * sizeof *order);
        seg_mirror_map map;
        if (!order || !seg_mirror_map_build(layout, &segments, &map)) {
            free(order);
            seg_segments_clear(&segments);
            return nomem(ctx);
        }
        for (int32_t i = 0; i < segments.count; ++i) {
            const seg_segment *s = segments.items + i;
            order[i] = (removal_order){on_plane(layout, s), s->owner, s->edges[0], i};
        }
        qsort(order, (size_t)segments.count, sizeof *order, compare_removal);
        int32_t before = *removed;
        for (int32_t i = 0; i < segments.count && !status; ++i) {
            const seg_segment *s = segments.items + order[i].segment;
            if (s->sketch || !seg_all_cut(layout, s) || (map.claimed && map.claimed[order[i].segment]))
                continue;
            if ((status = pz_check_cancel(ctx, "segment")))
                break;
            int done = 0;
            status = try_remove(layout, &map, order[i].segment, &done, ctx);
            if (done) {
                ++*removed;
                seg_progress(layout, "remove", ctx);
            }
        }
        free(order);
        seg_mirror_map_free(&map);
        seg_segments_clear(&segments);
        if (*removed == before)
            break;
    }
    if (!status)
        status = seg_label_panels(layout, ctx);
    return status;
}

/* ---------------------------------------------------------------- darts */

typedef struct dart_order {
    int32_t segment;
    double defect;  /* angle defect summed over the segment's inner vertices */
} dart_order;

static int compare_darts(const void *l, const void *r)
{
    const dart_order *a = l, *b = r;
    int saddle_a = a->defect < 0, saddle_b = b->defect < 0;
    if (saddle_a != saddle_b)
        return saddle_a - saddle_b;
    double ka = fabs(a->defect), kb = fabs(b->defect);
    if (ka != kb)
        return ka < kb ? -1 : 1;
    return (a->segment > b->segment) - (a->segment < b->segment);
}

/*
 * The Gaussian curvature of the region a segment spans (Sec. 4.2): the angle
 * defect summed over the inner vertices of the segment and of their one-ring,
 * each once (mark: vertex_count flags, left cleared). The ring smooths the
 * vertex-scale noise of the defect along a path on mesh edges.
 */
static double band_defect(const seg_layout *layout, const double *defect, const seg_segment *s, uint8_t *mark,
                          int32_t *visited)
{
    int32_t count = 0;
    double sum = 0;
    for (int32_t i = 0; i <= s->edge_count; ++i) {
        int32_t v = s->vertices[i];
        for (int32_t j = layout->vertex_edge_offsets[v] - 1; j < layout->vertex_edge_offsets[v + 1]; ++j) {
            int32_t u = j < layout->vertex_edge_offsets[v] ? v : other_end(layout, layout->vertex_edges[j], v);
            if (mark[u])
                continue;
            mark[u] = 1;
            visited[count++] = u;
            if (!layout->topology->vertex_on_boundary[u])
                sum += defect[u];
        }
    }
    for (int32_t i = 0; i < count; ++i)
        mark[visited[i]] = 0;
    return sum;
}

static double defect_sum(const seg_layout *layout, const double *defect, const int32_t *vertices, int32_t n)
{
    double sum = 0;
    for (int32_t i = 0; i < n; ++i)
        if (!layout->topology->vertex_on_boundary[vertices[i]])
            sum += defect[vertices[i]];
    return sum;
}

/* Bounding-box diagonal of panels a and b together (the panel they make once re-glued). */
static double merged_extent(const seg_layout *layout, int32_t a, int32_t b)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int side = 0; side < 2; ++side) {
        int32_t p = side ? b : a;
        for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
            for (int c = 0; c < 3; ++c) {
                const double *x = layout->mesh->positions + 3 * layout->topology->faces[3 * layout->panel_faces[i] + c];
                for (int k = 0; k < 3; ++k) {
                    lo[k] = fmin(lo[k], x[k]);
                    hi[k] = fmax(hi[k], x[k]);
                }
            }
    }
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* 1 when the two panels on the sides of edge e, joined, make a band round the body (segment/preference.c). */
static int merged_is_band(const seg_layout *layout, int32_t e)
{
    const pz_topology *t = layout->topology;
    int32_t a = layout->face_panel[pz_he_face(t->edge_halfedge[2 * e])];
    int32_t b = layout->face_panel[pz_he_face(t->edge_halfedge[2 * e + 1])];
    int32_t na = layout->panel_offsets[a + 1] - layout->panel_offsets[a];
    int32_t nb = layout->panel_offsets[b + 1] - layout->panel_offsets[b];
    int32_t *faces = malloc(((size_t)na + nb + 1) * sizeof(int32_t));
    if (!faces)
        return 0;
    memcpy(faces, layout->panel_faces + layout->panel_offsets[a], (size_t)na * sizeof(int32_t));
    memcpy(faces + na, layout->panel_faces + layout->panel_offsets[b], (size_t)nb * sizeof(int32_t));
    seg_shape shape;
    seg_faces_shape(layout, faces, na + nb, &shape);
    int band = seg_shape_is_band(layout, &shape);
    free(faces);
    return band;
}

static double edges_length(const seg_layout *layout, const int32_t *edges, int32_t n)
{
    double sum = 0;
    for (int32_t i = 0; i < n; ++i) {
        int32_t h = layout->topology->edge_halfedge[2 * edges[i]];
        const double *a = layout->mesh->positions + 3 * pz_he_from(layout->topology, h);
        const double *b = layout->mesh->positions + 3 * pz_he_to(layout->topology, h);
        sum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    }
    return sum;
}

/* A segment can become a dart when it is open, long enough and neither end is a tip already. */
static int dart_candidate(const seg_layout *layout, seg_mirror_map *map, int32_t index)
{
    const seg_segment *s = map->segments->items + index;
    if (s->sketch || s->closed || s->edge_count < 2 * DART_MIN_PIECES || !seg_all_cut(layout, s))
        return 0;
    const pz_topology *t = layout->topology;
    int32_t ends[2] = {s->vertices[0], s->vertices[s->edge_count]};
    for (int k = 0; k < 2; ++k)
        if (!t->vertex_on_boundary[ends[k]] && seg_cut_degree(layout, ends[k]) < 3)
            return 0;
    /* A seam between a panel and itself (a tube's opening) closes into a ring when re-glued. */
    int32_t h = t->edge_halfedge[2 * s->edges[0]], g = t->edge_halfedge[2 * s->edges[0] + 1];
    if (g < 0 || layout->face_panel[pz_he_face(h)] == layout->face_panel[pz_he_face(g)])
        return 0;
    /* A segment that is its own mirror image would be re-glued from both ends at once: a slit with two
     * tips, no dart. */
    return mirror_segment(layout, map, index) != index && !on_plane(layout, s) &&
           !(map->claimed && map->claimed[index]);
}

/* The edges of segment s oriented from its end of lower angle defect (the end re-glued first). */
static void orient_from_low_end(const seg_layout *layout, const seg_segment *s, const double *defect, int32_t *edges)
{
    int32_t n = s->edge_count, half = (n + 1) / 2;
    int reverse = defect_sum(layout, defect, s->vertices + n - half + 1, half) <
                  defect_sum(layout, defect, s->vertices, half);
    for (int32_t i = 0; i < n; ++i)
        edges[i] = reverse ? s->edges[n - 1 - i] : s->edges[i];
}

/*
 * Re-glues edges[0..glued-1] (with their mirror images), evaluates the panels
 * touched and puts the flags back: *ok = 1 when every such panel meets the
 * goals; *probe = the goals of the panel holding edge probe_edge.
 */
static pz_status measure_glued(seg_layout *layout, seg_mirror_map *map, int32_t index, const int32_t *edges,
                               int32_t glued, int32_t probe_edge, int *ok, pz_goal_result *probe, pz_ctx *ctx)
{
    seg_edge_set set;
    if (!seg_edge_set_make(layout, map, index, edges, glued, &set))
        return nomem(ctx);
    seg_edge_set_apply(layout, &set, 0);
    pz_status status = panels_ok(layout, &set, ok, ctx);
    if (!status)
        *probe = layout->panel_goals[layout->face_panel[pz_he_face(layout->topology->edge_halfedge[2 * probe_edge])]];
    seg_edge_set_apply(layout, &set, 1);
    free(set.edges);
    return status;
}

/*
 * 0 when the fully re-glued segment (goals `full`: the removal's trial,
 * cached) tells that no dart along it can meet the goals: its panel is no
 * disk or has too many corners (a dart adds no corner, so every dart along
 * the segment leaves the same corners), or its strain exceeds
 * DART_MAX_RELIEF times S (a dart relieves part of the strain of the glued
 * seam, not all of it: on the 8 shared garments and the generated bodice
 * every dart made had a fully glued strain within 1.21 S, and the trials
 * above 2 S, a quarter of those flattened, made none).
 */
static int dart_hopeful(const seg_layout *layout, const pz_goal_result *full)
{
    return !(full->failures & (PZ_GOAL_NOT_DISK | PZ_GOAL_CORNERS)) &&
           full->max_abs_strain <= DART_MAX_RELIEF * layout->goals.max_strain;
}

/*
 * Re-glues segment s from its lower-curvature end (Sec. 4.2) and keeps the
 * dart glued furthest that meets the goals; *made = 1 when one is kept.
 * The candidate lengths go from the shortest dart to the longest: the first
 * that passes is the one the paper's progressive re-gluing reaches when
 * the goals hold all the way, and a panel held together by a small glued
 * piece (a long dart) flattens badly in a few iterations from the LSCM
 * start, which would stop the progressive re-gluing at its first step
 * (measured: strain 0.2-0.5 there on the generated skirt). Darts longer than
 * DART_MAX_EXTENT_FRACTION of the merged panel's extent are not evaluated.
 */
static pz_status try_dart(seg_layout *layout, seg_mirror_map *map, int32_t index, const double *defect, int *made,
                          pz_ctx *ctx)
{
    *made = 0;
    const seg_segment *s = map->segments->items + index;
    int32_t n = s->edge_count, pieces = n < DART_PIECES ? n : DART_PIECES;
    int32_t *edges = malloc((size_t)n * sizeof(int32_t));
    if (!edges)
        return nomem(ctx);
    orient_from_low_end(layout, s, defect, edges);
    seg_edge_set whole;
    if (!seg_edge_set_make(layout, map, index, edges, n, &whole)) {
        free(edges);
        return nomem(ctx);
    }
    int worth = 0;
    pz_status status = worth_trying(layout, &whole, &worth, ctx);
    free(whole.edges);
    /* A dart joins the two panels into one (with a slit): never into a band round the body. */
    if (!status && worth && merged_is_band(layout, edges[0]))
        worth = 0;
    const pz_topology *t = layout->topology;
    double max_leg = 0;
    if (!status && worth) {
        int32_t a = layout->face_panel[pz_he_face(t->edge_halfedge[2 * edges[0]])];
        int32_t b = layout->face_panel[pz_he_face(t->edge_halfedge[2 * edges[0] + 1])];
        max_leg = DART_MAX_EXTENT_FRACTION * merged_extent(layout, a, b);
    }
    pz_goal_result goals;
    memset(&goals, 0, sizeof goals);
    int ok = 0;
    if (!status && worth && !(status = measure_glued(layout, map, index, edges, n, edges[0], &ok, &goals, ctx)))
        worth = dart_hopeful(layout, &goals);
    double glued_strain = goals.max_abs_strain;  /* with the whole segment glued: the dart must lower it */
    int32_t best = 0;
    for (int32_t k = pieces - DART_MIN_PIECES; worth && k >= 1 && !status && best == 0; --k) {
        int32_t glued = (int32_t)((int64_t)k * n / pieces);
        if (edges_length(layout, edges + glued, n - glued) > max_leg)
            break; /* longer still for smaller k */
        if ((status = measure_glued(layout, map, index, edges, glued, edges[glued], &ok, &goals, ctx)))
            break;
        if (ok && (goals.darts == 0 || goals.min_dart_opening_deg >= DART_MIN_OPENING_DEG) &&
            goals.max_abs_strain < glued_strain)
            best = glued;
        if (goals.failures & PZ_GOAL_NOT_DISK)
            break; /* the merged panel's topology does not depend on the dart's length */
    }
    if (!status && best > 0) {
        seg_edge_set set;
        if (!seg_edge_set_make(layout, map, index, edges, best, &set)) {
            status = nomem(ctx);
        } else {
            seg_edge_set_apply(layout, &set, 0);
            free(set.edges);
            *made = 1;
        }
    }
    free(edges);
    if (!status)
        status = seg_label_panels(layout, ctx);
    return status;
}

pz_status seg_dart_pass(seg_layout *layout, int32_t *darts, pz_ctx *ctx)
{
    *darts = 0;
    double *defect = malloc((size_t)layout->mesh->vertex_count * sizeof(double) + 1);
    if (!defect)
        return nomem(ctx);
    pz_geom_angle_defect(layout->mesh, layout->topology, defect);
    seg_segments segments;
    pz_status status = seg_segments_build(layout, &segments, ctx);
    dart_order *order = status ? NULL : malloc(((size_t)segments.count + 1) * sizeof(dart_order));
    int32_t vertex_count = layout->topology->vertex_count;
    uint8_t *mark = calloc((size_t)vertex_count + 1, 1);
    int32_t *visited = malloc(((size_t)vertex_count + 1) * sizeof(int32_t));
    seg_mirror_map map;
    memset(&map, 0, sizeof map);
    if (!status && (!order || !mark || !visited || !seg_mirror_map_build(layout, &segments, &map)))
        status = nomem(ctx);
    for (int32_t i = 0; !status && i < segments.count; ++i) {
        order[i].segment = i;
        order[i].defect = band_defect(layout, defect, segments.items + i, mark, visited);
    }
    if (!status)
        qsort(order, (size_t)segments.count, sizeof(dart_order), compare_darts);
    for (int32_t i = 0; !status && i < segments.count; ++i) {
        if (!dart_candidate(layout, &map, order[i].segment))
            continue;
        if ((status = pz_check_cancel(ctx, "segment")))
            break;
        int made = 0;
        status = try_dart(layout, &map, order[i].segment, defect, &made, ctx);
        if (made) {
            ++*darts;
            /* From the cache (the trial evaluated them): the progress shows their strain. */
            status = seg_evaluate_panels(layout, NULL, ctx);
            seg_progress(layout, "darts", ctx);
        }
    }
    free(order);
    free(mark);
    free(visited);
    seg_mirror_map_free(&map);
    seg_segments_clear(&segments);
    free(defect);
    return status;
}

/* ---------------------------------------------------------------- slivers */

/* How the panels next to a removed segment fare: a merge is made only when unmended is 0 (it trades
 * strain alone); of those, the fewest shapes still missed, then the lowest strain, win. */
typedef struct merge_score {
    int32_t shape;       /* panels still under a piece-shape goal */
    int32_t unmended;    /* panels missing a goal other than strain and the shapes (corners, injectivity, ...) */
    double strain;       /* the worst strain among them (INFINITY: one was not flattened) */
} merge_score;

static int merge_better(const merge_score *a, const merge_score *b)
{
    if (a->shape != b->shape)
        return a->shape < b->shape;
    return a->strain < b->strain;
}

/* Uncuts the set, scores the panels next to it and cuts it again; *ring = 1 when one is no disk. */
static pz_status score_merge(seg_layout *layout, const seg_edge_set *set, merge_score *score, int *ring, pz_ctx *ctx)
{
    seg_edge_set_apply(layout, set, 0);
    pz_status status = seg_label_panels(layout, ctx);
    uint8_t *want = status ? NULL : calloc((size_t)layout->panel_count + 1, 1);
    if (!status && !want)
        status = nomem(ctx);
    const pz_topology *t = layout->topology;
    for (int32_t i = 0; want && i < set->count; ++i)
        for (int s = 0; s < 2; ++s)
            if (t->edge_halfedge[2 * set->edges[i] + s] >= 0)
                want[layout->face_panel[pz_he_face(t->edge_halfedge[2 * set->edges[i] + s])]] = 1;
    if (!status)
        status = seg_evaluate_panels(layout, want, ctx);
    *score = (merge_score){0, 0, 0};
    *ring = 0;
    for (int32_t p = 0; !status && p < layout->panel_count; ++p) {
        if (!want[p])
            continue;
        const pz_goal_result *goals = &layout->panel_goals[p];
        *ring |= (goals->failures & PZ_GOAL_NOT_DISK) != 0;
        score->shape += (goals->failures & PZ_GOAL_SHAPE) != 0;
        score->unmended += (goals->failures & ~(unsigned)(PZ_GOAL_SHAPE | PZ_GOAL_STRAIN)) != 0;
        score->strain = fmax(score->strain, goals->max_abs_strain >= 0 ? goals->max_abs_strain : INFINITY);
    }
    free(want);
    seg_edge_set_apply(layout, set, 1);
    return status;
}

/* The sliver to merge next: the smallest panel missing a shape goal that has not been given up, or -1. */
static int32_t next_sliver(const seg_layout *layout, const uint8_t *given_up)
{
    int32_t best = -1;
    for (int32_t p = 0; p < layout->panel_count; ++p) {
        int32_t size = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
        if ((layout->panel_goals[p].failures & PZ_GOAL_SHAPE) && !given_up[layout->panel_faces[layout->panel_offsets[p]]] &&
            (best < 0 || size < layout->panel_offsets[best + 1] - layout->panel_offsets[best]))
            best = p;
    }
    return best;
}

/*
 * Adds to the set the cut chains it would leave dangling: uncut, an inner end of its edges with one cut
 * edge left is a stub, and the chain from it up to the next node goes too (a slit that separates nothing:
 * both its sides are the merged panel). 0 when out of memory.
 */
static int with_stubs(seg_layout *layout, seg_edge_set *set)
{
    const pz_topology *t = layout->topology;
    int32_t capacity = set->count + 16;
    int32_t *grown = realloc(set->edges, (size_t)capacity * sizeof(int32_t));
    if (!grown)
        return 0;
    set->edges = grown;
    int labels_valid = layout->labels_valid; /* the flags come back as they were */
    seg_edge_set_apply(layout, set, 0);
    int ok = 1;
    for (int32_t i = 0; ok && i < set->count; ++i) {
        int32_t h = t->edge_halfedge[2 * set->edges[i]];
        int32_t ends[2] = {pz_he_from(t, h), pz_he_to(t, h)};
        for (int k = 0; ok && k < 2; ++k)
            for (int32_t v = ends[k]; !t->vertex_on_boundary[v] && seg_cut_degree(layout, v) == 1;) {
                int32_t e = -1;
                for (int32_t j = layout->vertex_edge_offsets[v]; j < layout->vertex_edge_offsets[v + 1] && e < 0; ++j)
                    if (layout->edge_cut[layout->vertex_edges[j]])
                        e = layout->vertex_edges[j];
                if (layout->edge_owner[e] >= 0 && layout->paths[layout->edge_owner[e]].sketch)
                    break; /* a sketch stays, stub or not */
                if (set->count == capacity) {
                    capacity *= 2;
                    if (!(grown = realloc(set->edges, (size_t)capacity * sizeof(int32_t)))) {
                        ok = 0;
                        break;
                    }
                    set->edges = grown;
                }
                set->edges[set->count++] = e;
                layout->edge_cut[e] = 0;
                v = other_end(layout, e, v);
            }
    }
    seg_edge_set_apply(layout, set, 1);
    layout->labels_valid = labels_valid;
    return ok;
}

/* 1 when segment s separates panel p from another panel (not p from itself). */
static int bounds_panel(const seg_layout *layout, const seg_segment *s, int32_t p)
{
    const pz_topology *t = layout->topology;
    int32_t h = t->edge_halfedge[2 * s->edges[0]], g = t->edge_halfedge[2 * s->edges[0] + 1];
    if (g < 0)
        return 0;
    int32_t a = layout->face_panel[pz_he_face(h)], b = layout->face_panel[pz_he_face(g)];
    return a != b && (a == p || b == p);
}

/* The best seam of panel p to remove (a set with its mirror image) into *best; best->edges NULL: none
 * keeps the merged panels disks. */
static pz_status best_merge(seg_layout *layout, int32_t p, seg_edge_set *best, pz_ctx *ctx)
{
    best->edges = NULL;
    best->count = 0;
    seg_segments segments;
    seg_mirror_map map;
    memset(&map, 0, sizeof map);
    pz_status status = seg_segments_build(layout, &segments, ctx);
    if (!status && !seg_mirror_map_build(layout, &segments, &map))
        status = nomem(ctx);
    merge_score best_score = {0, 0, 0};
    for (int32_t i = 0; !status && i < segments.count; ++i) {
        const seg_segment *s = segments.items + i;
        /* A seam on half 1 that is the image of one on half 0 goes with it (seg_edge_set_make adds the image). */
        if (s->sketch || !seg_all_cut(layout, s) || !bounds_panel(layout, s, p) || (map.claimed && map.claimed[i]))
            continue;
        seg_edge_set set;
        if (!seg_edge_set_make(layout, &map, i, s->edges, s->edge_count, &set)) {
            status = nomem(ctx);
            break;
        }
        merge_score score;
        int ring = 1;
        if (!with_stubs(layout, &set))
            status = nomem(ctx);
        if (!status)
            status = score_merge(layout, &set, &score, &ring, ctx);
        if (!status && !ring && score.unmended == 0 && (!best->edges || merge_better(&score, &best_score))) {
            free(best->edges);
            *best = set;
            best_score = score;
        } else {
            free(set.edges);
        }
        /* The labels of the cut flags as they were (score_merge relabelled the trial). */
        if (!status)
            status = seg_label_panels(layout, ctx);
    }
    seg_mirror_map_free(&map);
    seg_segments_clear(&segments);
    return status;
}

/*
 * A sliver is never the answer to a strain goal (docs/segment.md, "Piece shapes"): the greedy insertion
 * may cut pieces under the minimum width or area on the way (its later removals usually merge them
 * again), and what is left at the end is merged into a neighbour even when the merged panel then
 * exceeds S: the layout says so rather than cut confetti. Only strain is traded: a merge that would miss
 * another goal (a ring, too many corners, a flip) is not made. Of the merges left, the one whose panels
 * meet every shape goal, then the one of lowest strain, is made; a sliver with none stays, reported
 * narrow or small. Smallest first, one seam at a time (with its mirror image; a cut the removal would
 * leave dangling goes with it).
 */
pz_status seg_merge_slivers(seg_layout *layout, int32_t *merged, pz_ctx *ctx)
{
    *merged = 0;
    if (layout->goals.min_piece_width_mm <= 0 && layout->goals.min_piece_area <= 0)
        return PZ_OK;
    uint8_t *given_up = calloc((size_t)layout->topology->face_count + 1, 1);
    if (!given_up)
        return nomem(ctx);
    pz_status status = PZ_OK;
    for (int32_t guard = 0; !status && guard < layout->topology->face_count; ++guard) {
        if ((status = pz_check_cancel(ctx, "segment")) || (status = seg_label_panels(layout, ctx)) ||
            (status = seg_evaluate_panels(layout, NULL, ctx)))
            break;
        int32_t p = next_sliver(layout, given_up);
        if (p < 0)
            break;
        seg_edge_set best;
        if ((status = best_merge(layout, p, &best, ctx)))
            break;
        if (!best.edges) {
            for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i)
                given_up[layout->panel_faces[i]] = 1;
            continue;
        }
        seg_edge_set_apply(layout, &best, 0);
        free(best.edges);
        ++*merged;
        seg_progress(layout, "merge slivers", ctx);
    }
    free(given_up);
    if (!status)
        status = seg_label_panels(layout, ctx);
    return status;
}
