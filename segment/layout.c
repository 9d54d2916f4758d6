/*
 * segment/layout.c -- the automatic patch layout of pietroni2022 Sec. 4.2:
 * greedy insertion of field-aligned paths until every panel meets its
 * goals, recursion into the panels that still fail, then removal of
 * redundant segments and darts (segment/removal.c).
 *
 * The layout is a set of cut-edge flags; panels are the face components
 * across uncut edges, numbered in order of their first face. Every step
 * changes a few flags, relabels the panels (flooding only the panels next to
 * the changed edges, then renumbering: seg_label_panels) and evaluates the
 * panels whose goals are not known yet: an evaluation (pz_segment_goals) is cached
 * under a 64-bit hash of the panel's faces and of the neighbour seen across
 * each of its outline edges (the corners depend on it), so a panel that a
 * step did not touch is never flattened again. The panels to evaluate are
 * flattened in parallel (OpenMP, one thread inside each flattening); the
 * results are written by panel index, so nothing depends on the thread count.
 *
 * Insertion (docs/segment.md): sketches are snapped and inserted first. Then,
 * while some panel fails and the budget lasts, among the candidates that cut
 * an uncut edge inside a failing panel and meet no inserted path
 * tangentially, the one farthest from the inserted paths (mean M4 distance,
 * border included) is inserted, with its mirror image when a symmetry plane
 * is in use. When no candidate helps, candidates are traced again on each
 * failing panel's own submesh (one level of recursion per round, at most
 * max_depth rounds); panels that still fail get a cut through their worst
 * vertex (segment/fallback.c).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_MAX_CORNERS 8
#define DEFAULT_MAX_STRAIN 0.05
#define DEFAULT_MAX_CANDIDATES 96
#define DEFAULT_MAX_DEPTH 2
/* Insertions per level at most: a guarantee that the run ends. */
#define MAX_INSERTIONS_PER_LEVEL 64
#define MAX_AUTO_RESIDUAL_EDGES 0.25
/*
 * Panels to evaluate with fewer faces than this in all are flattened on one
 * thread: waking a second thread costs more than they do when the cores are
 * shared (the wetsuit of ../shared/data, ~1,100 evaluations of small panels:
 * 4.5 s with 2 threads, 0.85 s with 1 at load 7.6; docs/segment.md).
 */
#define PARALLEL_MIN_FACES 4000

/* ---------------------------------------------------------------- helpers */

static uint64_t mix(uint64_t hash, uint64_t value)
{
    /* splitmix64 finalizer over the running hash: cheap and well spread. */
    uint64_t z = hash ^ (value + 0x9e3779b97f4a7c15ull + (hash << 6) + (hash >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

int32_t seg_edge_between(const seg_layout *layout, int32_t a, int32_t b)
{
    if (a < 0 || b < 0)
        return -1;
    const pz_topology *t = layout->topology;
    for (int32_t i = layout->vertex_edge_offsets[a]; i < layout->vertex_edge_offsets[a + 1]; ++i) {
        int32_t e = layout->vertex_edges[i], h = t->edge_halfedge[2 * e];
        int32_t other = pz_he_from(t, h) == a ? pz_he_to(t, h) : pz_he_from(t, h);
        if (other == b)
            return e;
    }
    return -1;
}

int32_t seg_cut_degree(const seg_layout *layout, int32_t v)
{
    int32_t degree = 0;
    for (int32_t i = layout->vertex_edge_offsets[v]; i < layout->vertex_edge_offsets[v + 1]; ++i)
        degree += layout->edge_cut[layout->vertex_edges[i]] != 0;
    return degree;
}

int32_t seg_mirror_edge(const seg_layout *layout, int32_t e)
{
    if (!layout->symmetry.found)
        return -1;
    const pz_topology *t = layout->topology;
    int32_t h = t->edge_halfedge[2 * e];
    return seg_edge_between(layout, layout->symmetry.vertex_mirror[pz_he_from(t, h)],
                            layout->symmetry.vertex_mirror[pz_he_to(t, h)]);
}

static pz_status build_vertex_edges(seg_layout *layout, pz_ctx *ctx)
{
    const pz_topology *t = layout->topology;
    int32_t n = t->vertex_count;
    layout->vertex_edge_offsets = calloc((size_t)n + 1, sizeof(int32_t));
    layout->vertex_edges = malloc((size_t)2 * t->edge_count * sizeof(int32_t) + 1);
    int32_t *fill = calloc((size_t)n + 1, sizeof(int32_t));
    if (!layout->vertex_edge_offsets || !layout->vertex_edges || !fill) {
        free(fill);
        return nomem(ctx);
    }
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        ++layout->vertex_edge_offsets[pz_he_from(t, h) + 1];
        ++layout->vertex_edge_offsets[pz_he_to(t, h) + 1];
    }
    for (int32_t v = 0; v < n; ++v)
        layout->vertex_edge_offsets[v + 1] += layout->vertex_edge_offsets[v];
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t h = t->edge_halfedge[2 * e];
        int32_t a = pz_he_from(t, h), b = pz_he_to(t, h);
        layout->vertex_edges[layout->vertex_edge_offsets[a] + fill[a]++] = e;
        layout->vertex_edges[layout->vertex_edge_offsets[b] + fill[b]++] = e;
    }
    free(fill);
    return PZ_OK;
}

/* ---------------------------------------------------------------- panels */

/*
 * Panels are the face components across uncut edges, numbered in order of
 * their first (smallest) face, each panel's faces increasing. The first
 * labelling floods the whole mesh. Later ones are local: only the panels next
 * to an edge whose flag changed since the last labelling (labelled_cut keeps
 * the flags it saw) are flooded again; every other panel keeps its faces,
 * since an unchanged uncut edge joins two faces of one panel. Then all panels
 * are renumbered by first face, which moves the face lists and rewrites
 * face_panel of the panels whose number changed: sequential passes, where a
 * flood of the whole mesh cost 0.5 ms per step on the wetsuit (20K faces,
 * ~5,000 relabellings). The result is the full flood's, label for label.
 */
static void flood_panel(const seg_layout *layout, int32_t seed, int32_t label, int32_t unlabelled, int32_t *stack)
{
    const pz_topology *t = layout->topology;
    int32_t top = 0;
    layout->face_panel[seed] = label;
    stack[top++] = seed;
    while (top > 0) {
        int32_t f = stack[--top];
        for (int k = 0; k < 3; ++k) {
            int32_t g = t->twin[3 * f + k];
            if (g < 0 || layout->edge_cut[t->halfedge_edge[3 * f + k]] ||
                layout->face_panel[pz_he_face(g)] != unlabelled)
                continue;
            layout->face_panel[pz_he_face(g)] = label;
            stack[top++] = pz_he_face(g);
        }
    }
}

/* Resizes the per-panel arrays to `panels` and marks every panel unevaluated. */
static pz_status panel_arrays_resize(seg_layout *layout, int32_t panels, pz_ctx *ctx)
{
    int32_t *offsets = realloc(layout->panel_offsets, ((size_t)panels + 1) * sizeof(int32_t));
    if (offsets)
        layout->panel_offsets = offsets;
    pz_goal_result *goals = realloc(layout->panel_goals, ((size_t)panels + 1) * sizeof(pz_goal_result));
    if (goals)
        layout->panel_goals = goals;
    uint8_t *evaluated = realloc(layout->panel_evaluated, (size_t)panels + 1);
    if (evaluated)
        layout->panel_evaluated = evaluated;
    if (!offsets || !goals || !evaluated)
        return nomem(ctx);
    memset(evaluated, 0, (size_t)panels + 1);
    layout->panel_count = panels;
    return PZ_OK;
}

/* The first labelling: a flood from every face not reached yet, in face order. */
static pz_status label_all(seg_layout *layout, pz_ctx *ctx)
{
    int32_t faces = layout->topology->face_count, panels = 0;
    memset(layout->face_panel, 0xff, (size_t)faces * sizeof(int32_t));
    for (int32_t seed = 0; seed < faces; ++seed)
        if (layout->face_panel[seed] < 0)
            flood_panel(layout, seed, panels++, -1, layout->label_stack);
    pz_status status = panel_arrays_resize(layout, panels, ctx);
    if (status)
        return status;
    int32_t *offsets = layout->panel_offsets;
    memset(offsets, 0, ((size_t)panels + 1) * sizeof(int32_t));
    for (int32_t f = 0; f < faces; ++f)
        ++offsets[layout->face_panel[f] + 1];
    for (int32_t p = 0; p < panels; ++p)
        offsets[p + 1] += offsets[p];
    int32_t *cursor = layout->label_stack; /* the flood is over: its stack is free */
    memcpy(cursor, offsets, (size_t)panels * sizeof(int32_t));
    for (int32_t f = 0; f < faces; ++f)
        layout->panel_faces[cursor[layout->face_panel[f]]++] = f;
    return PZ_OK;
}

uint64_t pz_segment_face_set_key(const int32_t *faces, int32_t count)
{
    uint64_t hash = mix(0xfacade, (uint64_t)count);
    for (int32_t i = 0; i < count; ++i)
        hash = mix(hash, (uint64_t)faces[i]);
    return hash ? hash : 1;
}

/* 1 when panel p's face set is one of the caller's vetoed panels (a short list: linear scan). */
static int panel_vetoed(const seg_layout *layout, int32_t p);

/* What the layout adds to an evaluation (cached as evaluated): the strain margin and the vetoes. */
static void layout_verdicts(const seg_layout *layout, int32_t p, pz_goal_result *goals)
{
    if (goals->max_abs_strain >= 0 && goals->max_abs_strain > layout->accept_strain)
        goals->failures |= PZ_GOAL_STRAIN;
    if (panel_vetoed(layout, p))
        goals->failures |= PZ_GOAL_VETOED;
}

static int panel_vetoed(const seg_layout *layout, int32_t p)
{
    if (layout->options->vetoed_count <= 0)
        return 0;
    int32_t first = layout->panel_offsets[p], count = layout->panel_offsets[p + 1] - first;
    uint64_t key = pz_segment_face_set_key(layout->panel_faces + first, count);
    for (int32_t i = 0; i < layout->options->vetoed_count; ++i)
        if (layout->options->vetoed[i] == key)
            return 1;
    return 0;
}

/* Merges the increasing lists a[0..na-1] and b[0..nb-1] into out. */
static void merge_faces(const int32_t *a, int32_t na, const int32_t *b, int32_t nb, int32_t *out)
{
    int32_t i = 0, j = 0, k = 0;
    while (i < na && j < nb)
        out[k++] = a[i] < b[j] ? a[i++] : b[j++];
    while (i < na)
        out[k++] = a[i++];
    while (j < nb)
        out[k++] = b[j++];
}

/* The edges whose flag changed since the last labelling, into out (their count); labelled_cut catches up.
 * Eight flags are compared at a time: a step changes a few of ~30K. */
static int32_t changed_edges(seg_layout *layout, int32_t *out)
{
    int32_t edges = layout->topology->edge_count, count = 0;
    for (int32_t base = 0; base < edges; base += 8) {
        if (base + 8 <= edges) {
            uint64_t now, then;
            memcpy(&now, layout->edge_cut + base, 8);
            memcpy(&then, layout->labelled_cut + base, 8);
            if (now == then)
                continue;
        }
        for (int32_t e = base; e < base + 8 && e < edges; ++e)
            if (layout->edge_cut[e] != layout->labelled_cut[e]) {
                layout->labelled_cut[e] = layout->edge_cut[e];
                out[count++] = e;
            }
    }
    return count;
}

/*
 * Sorts label_region[0..count-1], made of `runs` increasing runs starting at
 * run_start[0..runs-1] (run_start[runs] = count), by merging neighbouring
 * runs pass after pass: O(count log runs). label_spare is scratch.
 */
static void merge_runs(seg_layout *layout, int32_t *run_start, int32_t runs, int32_t count)
{
    run_start[runs] = count;
    while (runs > 1) {
        int32_t merged = 0;
        for (int32_t r = 0; r < runs; r += 2, ++merged) {
            int32_t a = run_start[r], b = run_start[r + 1], end = r + 1 < runs ? run_start[r + 2] : b;
            merge_faces(layout->label_region + a, b - a, layout->label_region + b, end - b, layout->label_spare + a);
            run_start[merged] = a;
        }
        run_start[merged] = count;
        runs = merged;
        int32_t *sorted = layout->label_spare;
        layout->label_spare = layout->label_region;
        layout->label_region = sorted;
    }
}

/*
 * The faces of the panels next to the changed edges, increasing, into
 * layout->label_region (returns their count); `touched` (old panel_count)
 * gets 1 for those panels. Each panel's list is increasing already.
 */
static int32_t touched_region(seg_layout *layout, const int32_t *changed, int32_t changed_count, uint8_t *touched,
                              int32_t *run_start)
{
    const pz_topology *t = layout->topology;
    int32_t count = 0, runs = 0;
    for (int32_t i = 0; i < changed_count; ++i)
        for (int side = 0; side < 2; ++side) {
            int32_t h = t->edge_halfedge[2 * changed[i] + side];
            int32_t p = h < 0 ? -1 : layout->face_panel[pz_he_face(h)];
            if (p < 0 || touched[p])
                continue;
            touched[p] = 1;
            int32_t first = layout->panel_offsets[p], n = layout->panel_offsets[p + 1] - first;
            memcpy(layout->label_region + count, layout->panel_faces + first, (size_t)n * sizeof(int32_t));
            run_start[runs++] = count;
            count += n;
        }
    merge_runs(layout, run_start, runs, count);
    return count;
}

/* One panel of the new labelling: an old panel kept whole, or a component of the flooded region. */
typedef struct label_piece {
    int32_t first_face;
    int32_t old_panel;   /* -1 for a component */
    int32_t size;
} label_piece;

/*
 * Renumbers: kept panels and components merged by first face (both lists
 * are in that order already), then the face lists and face_panel rewritten.
 * Component c's faces carry the label -2 - c in face_panel on entry.
 */
static pz_status renumber(seg_layout *layout, const uint8_t *touched, const label_piece *components,
                          int32_t component_count, int32_t region_count, pz_ctx *ctx)
{
    int32_t old_count = layout->panel_count, kept = 0;
    for (int32_t p = 0; p < old_count; ++p)
        kept += !touched[p];
    int32_t panels = kept + component_count;
    label_piece *order = malloc(((size_t)panels + 1) * sizeof *order);
    int32_t *old_offsets = malloc(((size_t)old_count + 1) * sizeof(int32_t));
    int32_t *component_label = malloc(((size_t)component_count + 1) * sizeof(int32_t));
    int32_t *cursor = malloc(((size_t)component_count + 1) * sizeof(int32_t)); /* component -> next slot */
    if (!order || !old_offsets || !component_label || !cursor) {
        free(order), free(old_offsets), free(component_label), free(cursor);
        return nomem(ctx);
    }
    memcpy(old_offsets, layout->panel_offsets, ((size_t)old_count + 1) * sizeof(int32_t));
    int32_t n = 0, c = 0;
    for (int32_t p = 0; p <= old_count; ++p) {
        int32_t first = p < old_count ? layout->panel_faces[old_offsets[p]] : INT32_MAX;
        if (p < old_count && touched[p])
            continue;
        for (; c < component_count && components[c].first_face < first; ++c)
            order[n++] = components[c];
        if (p < old_count)
            order[n++] = (label_piece){first, p, old_offsets[p + 1] - old_offsets[p]};
    }
    pz_status status = panel_arrays_resize(layout, panels, ctx);
    int32_t *faces_out = layout->label_spare, *offsets = layout->panel_offsets;
    for (int32_t q = 0; !status && q < panels; ++q) {
        offsets[q + 1] = (q ? offsets[q] : 0) + order[q].size;
        int32_t old = order[q].old_panel;
        if (old < 0) {
            component_label[-2 - layout->face_panel[order[q].first_face]] = q;
            continue;
        }
        memcpy(faces_out + offsets[q], layout->panel_faces + old_offsets[old], (size_t)order[q].size * sizeof(int32_t));
        if (old != q)
            for (int32_t i = offsets[q]; i < offsets[q + 1]; ++i)
                layout->face_panel[faces_out[i]] = q;
    }
    if (!status) {
        offsets[0] = 0;
        /* Components: the region is increasing, so is each component's list. */
        for (int32_t k = 0; k < component_count; ++k)
            cursor[k] = offsets[component_label[k]];
        for (int32_t i = 0; i < region_count; ++i) {
            int32_t f = layout->label_region[i], k = -2 - layout->face_panel[f];
            faces_out[cursor[k]++] = f;
            layout->face_panel[f] = component_label[k];
        }
        layout->label_spare = layout->panel_faces;
        layout->panel_faces = faces_out;
    }
    free(order), free(old_offsets), free(component_label), free(cursor);
    return status;
}

/* A later labelling: floods only the panels next to the edges whose flag changed. */
static pz_status label_changed(seg_layout *layout, pz_ctx *ctx)
{
    int32_t changed_count = changed_edges(layout, layout->label_stack);
    if (changed_count == 0) {
        memset(layout->panel_evaluated, 0, (size_t)layout->panel_count + 1);
        return PZ_OK;
    }
    uint8_t *touched = calloc((size_t)layout->panel_count + 1, 1);
    int32_t *run_start = malloc(((size_t)layout->panel_count + 2) * sizeof(int32_t));
    if (!touched || !run_start) {
        free(touched), free(run_start);
        return nomem(ctx);
    }
    /* The changed edges are read before the first flood reuses the stack. */
    int32_t region_count = touched_region(layout, layout->label_stack, changed_count, touched, run_start);
    free(run_start);
    for (int32_t i = 0; i < region_count; ++i)
        layout->face_panel[layout->label_region[i]] = -1;
    /* At most one component per region face. */
    label_piece *components = malloc(((size_t)region_count + 1) * sizeof *components);
    int32_t component_count = 0;
    for (int32_t i = 0; components && i < region_count; ++i) {
        int32_t seed = layout->label_region[i];
        if (layout->face_panel[seed] != -1)
            continue;
        flood_panel(layout, seed, -2 - component_count, -1, layout->label_stack);
        components[component_count++] = (label_piece){seed, -1, 0};
    }
    for (int32_t i = 0; components && i < region_count; ++i)
        ++components[-2 - layout->face_panel[layout->label_region[i]]].size;
    pz_status status = components ? renumber(layout, touched, components, component_count, region_count, ctx)
                                  : nomem(ctx);
    free(components);
    free(touched);
    return status;
}

pz_status seg_label_panels(seg_layout *layout, pz_ctx *ctx)
{
    if (layout->labels_valid)
        return PZ_OK; /* no cut changed since: labels and evaluations stand */
    pz_status status;
    if (layout->labelled) {
        status = label_changed(layout, ctx);
    } else {
        memcpy(layout->labelled_cut, layout->edge_cut, (size_t)layout->topology->edge_count);
        status = label_all(layout, ctx);
    }
    /* After a failure the labels are unknown: the next call floods everything. */
    layout->labelled = status == PZ_OK;
    layout->labels_valid = status == PZ_OK;
    return status;
}

/* Cache key of panel p: its faces and, for every outline edge, the first face of the panel across. */
static uint64_t panel_key(const seg_layout *layout, int32_t p)
{
    const pz_topology *t = layout->topology;
    uint64_t hash = mix(0x5eed, (uint64_t)(layout->panel_offsets[p + 1] - layout->panel_offsets[p]));
    for (int32_t i = layout->panel_offsets[p]; i < layout->panel_offsets[p + 1]; ++i) {
        int32_t f = layout->panel_faces[i];
        hash = mix(hash, (uint64_t)f);
        for (int k = 0; k < 3; ++k) {
            int32_t g = t->twin[3 * f + k];
            if (g >= 0 && !layout->edge_cut[t->halfedge_edge[3 * f + k]])
                continue;
            int64_t across = g < 0 ? -1 : layout->face_panel[pz_he_face(g)] == p
                                               ? -2
                                               : layout->panel_faces[layout->panel_offsets[layout->face_panel[pz_he_face(g)]]];
            hash = mix(hash, (uint64_t)(3 * (int64_t)f + k) ^ ((uint64_t)across << 32));
        }
    }
    return hash ? hash : 1;
}

static seg_cache_entry *cache_slot(pz_segment_cache *cache, uint64_t key)
{
    int32_t mask = cache->capacity - 1;
    for (int32_t i = (int32_t)(key & (uint64_t)mask);; i = (i + 1) & mask)
        if (cache->entries[i].key == key || cache->entries[i].key == 0)
            return cache->entries + i;
}

static pz_status cache_store(pz_segment_cache *cache, uint64_t key, const pz_goal_result *goals, pz_ctx *ctx)
{
    if (2 * (cache->count + 1) > cache->capacity) {
        int32_t old_capacity = cache->capacity;
        seg_cache_entry *old = cache->entries;
        cache->capacity = old_capacity ? 2 * old_capacity : 256;
        cache->entries = calloc((size_t)cache->capacity, sizeof(seg_cache_entry));
        if (!cache->entries) {
            cache->entries = old;
            cache->capacity = old_capacity;
            return nomem(ctx);
        }
        for (int32_t i = 0; i < old_capacity; ++i)
            if (old[i].key)
                *cache_slot(cache, old[i].key) = old[i];
        free(old);
    }
    seg_cache_entry *slot = cache_slot(cache, key);
    if (!slot->key)
        ++cache->count;
    slot->key = key;
    slot->goals = *goals;
    return PZ_OK;
}

pz_segment_cache *pz_segment_cache_create(void)
{
    return calloc(1, sizeof(pz_segment_cache));
}

void pz_segment_cache_free(pz_segment_cache **cache)
{
    if (!cache || !*cache)
        return;
    free((*cache)->entries);
    free(*cache);
    *cache = NULL;
}

/* One evaluation; a failed flattening (not out of memory) counts as a panel that is not injective. */
static pz_status evaluate_one(const seg_layout *layout, int32_t p, seg_goal_scratch *scratch, pz_goal_result *out)
{
    pz_ctx local;
    pz_ctx_init(&local);
    local.quiet = 1;
    const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
    int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    pz_status status = seg_goals(layout->mesh, layout->topology, layout->edge_cut, layout->face_panel, faces, count,
                                 &layout->goals, scratch, out, &local);
    if (status && status != PZ_ERR_NOMEM) {
        memset(out, 0, sizeof *out);
        out->failures = PZ_GOAL_NOT_INJECTIVE;
        out->max_abs_strain = -1;
        out->min_dart_opening_deg = -1;
        out->boundary_loops = 1;
        status = PZ_OK;
    }
    return status;
}

pz_status seg_evaluate_panels(seg_layout *layout, const uint8_t *want, pz_ctx *ctx)
{
    int32_t panels = layout->panel_count, misses = 0;
    int32_t *miss = malloc(((size_t)panels + 1) * sizeof(int32_t));
    uint64_t *keys = malloc(((size_t)panels + 1) * sizeof(uint64_t));
    if (!miss || !keys) {
        free(miss);
        free(keys);
        return nomem(ctx);
    }
    for (int32_t p = 0; p < panels; ++p) {
        if ((want && !want[p]) || layout->panel_evaluated[p])
            continue;
        keys[p] = panel_key(layout, p);
        seg_cache_entry *slot = layout->cache->capacity ? cache_slot(layout->cache, keys[p]) : NULL;
        if (slot && slot->key) {
            layout->panel_goals[p] = slot->goals;
            layout_verdicts(layout, p, &layout->panel_goals[p]);
            layout->panel_evaluated[p] = 1;
        } else {
            miss[misses++] = p;
        }
    }
    pz_status status = PZ_OK;
    pz_status *statuses = malloc(((size_t)misses + 1) * sizeof(pz_status));
    if (!statuses)
        status = nomem(ctx);
    int64_t miss_faces = 0;
    for (int32_t i = 0; i < misses; ++i)
        miss_faces += layout->panel_offsets[miss[i] + 1] - layout->panel_offsets[miss[i]];
    int parallel = misses > 1 && miss_faces >= PARALLEL_MIN_FACES && !status;
    /* One evaluation scratch per thread that may run (kept across calls). */
    for (int32_t t = 0; t < (parallel ? layout->threads : 1) && !status; ++t)
        if (!layout->goal_scratch[t] && !(layout->goal_scratch[t] = seg_goal_scratch_new(layout->topology->face_count)))
            status = nomem(ctx);
    parallel = parallel && !status;
#pragma omp parallel for schedule(dynamic, 1) num_threads(layout->threads) if (parallel)
    for (int32_t i = 0; i < misses; ++i) {
        if (status)
            continue;
        /* Flattening and metrics open parallel regions of their own; inside an inactive region (one
         * thread or one miss) they would wake every core for each small panel. This sets the
         * thread count of this implicit task only. */
        omp_set_num_threads(1);
        statuses[i] = evaluate_one(layout, miss[i], layout->goal_scratch[omp_get_thread_num()],
                                   layout->panel_goals + miss[i]);
    }
    for (int32_t i = 0; i < misses && !status; ++i) {
        if (statuses[i])
            status = nomem(ctx);
        else {
            /* Stored as evaluated: the vetoes may change from call to call, the evaluation does not. */
            status = cache_store(layout->cache, keys[miss[i]], layout->panel_goals + miss[i], ctx);
            layout_verdicts(layout, miss[i], &layout->panel_goals[miss[i]]);
        }
        layout->panel_evaluated[miss[i]] = 1;
    }
    layout->evaluation_count += misses;
    layout->evaluated_faces += miss_faces;
    free(statuses);
    free(miss);
    free(keys);
    return status;
}

void seg_progress(seg_layout *layout, const char *stage)
{
    if (!layout->options->on_progress)
        return;
    double worst = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        if (layout->panel_evaluated[p])
            worst = fmax(worst, layout->panel_goals[p].max_abs_strain);
    layout->options->on_progress(layout->options->user, stage, layout->panel_count, worst);
}

static int32_t failing_panels(const seg_layout *layout)
{
    int32_t failing = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        failing += layout->panel_goals[p].failures != 0;
    return failing;
}

/* ---------------------------------------------------------------- paths */

static pz_status add_path(seg_layout *layout, const pz_trace_path *path, int sketch, pz_ctx *ctx)
{
    if (layout->path_count == layout->path_capacity) {
        int32_t capacity = layout->path_capacity ? 2 * layout->path_capacity : 16;
        seg_path *grown = realloc(layout->paths, (size_t)capacity * sizeof(seg_path));
        if (!grown)
            return nomem(ctx);
        layout->paths = grown;
        layout->path_capacity = capacity;
    }
    seg_path *slot = layout->paths + layout->path_count;
    memset(slot, 0, sizeof *slot);
    pz_status status = pz_trace_path_copy(path, &slot->path, ctx);
    if (status)
        return status;
    slot->sketch = sketch;
    int32_t index = layout->path_count++;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t e = seg_edge_between(layout, path->vertices[i], path->vertices[(i + 1) % n]);
        if (e < 0 || layout->edge_cut[e])
            continue;
        layout->edge_cut[e] = 1;
        layout->labels_valid = 0;
        layout->edge_owner[e] = index;
    }
    return PZ_OK;
}

/* 1 when the path has an uncut interior edge inside a failing panel. */
static int splits_failing(const seg_layout *layout, const pz_trace_path *path)
{
    const pz_topology *t = layout->topology;
    int32_t n = path->vertex_count, edges = path->closed ? n : n - 1;
    for (int32_t i = 0; i < edges; ++i) {
        int32_t e = seg_edge_between(layout, path->vertices[i], path->vertices[(i + 1) % n]);
        if (e < 0 || layout->edge_cut[e] || t->edge_halfedge[2 * e + 1] < 0)
            continue;
        if (layout->panel_goals[layout->face_panel[pz_he_face(t->edge_halfedge[2 * e])]].failures)
            return 1;
    }
    return 0;
}

static int tangential_to_inserted(const seg_layout *layout, const pz_trace_path *path)
{
    for (int32_t i = 0; i < layout->path_count; ++i)
        if (pz_trace_paths_tangential(path, &layout->paths[i].path, layout->mesh->vertex_count))
            return 1;
    return 0;
}

/* Mean signed distance of points (vertex ids) to the plane; 0 without one. */
static double plane_side(const seg_layout *layout, const int32_t *vertices, int32_t n)
{
    const pz_symmetry *s = &layout->symmetry;
    if (!s->found || n <= 0)
        return 0;
    double side = 0;
    for (int32_t j = 0; j < n; ++j) {
        const double *p = layout->mesh->positions + 3 * vertices[j];
        side += s->normal[0] * p[0] + s->normal[1] * p[1] + s->normal[2] * p[2] - s->offset;
    }
    return side / n;
}

/* Paths and panels farther than this (mean edges) on the positive side are left to their mirror images. */
#define MIRRORED_SIDE_EDGES 2.0

int seg_panel_mirrored_side(const seg_layout *layout, int32_t p)
{
    const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
    int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    if (!layout->symmetry.found)
        return 0;
    double side = 0;
    for (int32_t i = 0; i < count; ++i)
        side += plane_side(layout, layout->topology->faces + 3 * faces[i], 3);
    return side / count > MIRRORED_SIDE_EDGES * layout->mean_edge;
}

pz_status seg_insert_with_mirror(seg_layout *layout, const pz_trace_path *path, pz_ctx *ctx)
{
    pz_status status = add_path(layout, path, 0, ctx);
    if (status || !layout->symmetry.found)
        return status;
    pz_trace_path mirror;
    memset(&mirror, 0, sizeof mirror);
    pz_ctx local;
    pz_ctx_init(&local);
    if (pz_symmetry_mirror_path(&layout->symmetry, layout->graph, layout->mesh, layout->topology, path, &mirror,
                                &local) == PZ_OK)
        status = add_path(layout, &mirror, 0, ctx);
    pz_trace_path_clear(&mirror);
    return status;
}

/* A candidate and its mirror image (mirror.vertex_count 0: none, or the candidate is its own mirror). */
typedef struct seg_candidate {
    pz_trace_path path;
    pz_trace_path mirror;
    int usable;
} seg_candidate;

static void candidates_clear(seg_candidate *candidates, int32_t count)
{
    for (int32_t i = 0; i < count; ++i) {
        pz_trace_path_clear(&candidates[i].path);
        pz_trace_path_clear(&candidates[i].mirror);
    }
    free(candidates);
}

/* Share of a's vertices that b passes too. */
static double shared_fraction(const pz_trace_path *a, const pz_trace_path *b, uint8_t *mark)
{
    for (int32_t i = 0; i < b->vertex_count; ++i)
        mark[b->vertices[i]] = 1;
    int32_t shared = 0;
    for (int32_t i = 0; i < a->vertex_count; ++i)
        shared += mark[a->vertices[i]];
    for (int32_t i = 0; i < b->vertex_count; ++i)
        mark[b->vertices[i]] = 0;
    return a->vertex_count ? (double)shared / a->vertex_count : 0;
}

/*
 * Takes the traced paths into candidates. With a symmetry plane a path is
 * kept when its mean vertex lies on the negative side or on the plane (the
 * sources of one side), and is paired with its mirror image; a path that is
 * (nearly: 80% of its vertices) its own mirror image stays alone; a path
 * that meets its mirror image tangentially otherwise would leave slivers
 * and is dropped.
 */
static pz_status make_candidates(seg_layout *layout, pz_trace_paths *traced, seg_candidate **out, int32_t *count,
                                 pz_ctx *ctx)
{
    *out = NULL;
    *count = 0;
    int32_t n = traced ? traced->path_count : 0;
    seg_candidate *candidates = calloc((size_t)n + 1, sizeof(seg_candidate));
    uint8_t *mark = calloc((size_t)layout->mesh->vertex_count + 1, 1);
    if (!candidates || !mark) {
        free(candidates);
        free(mark);
        return nomem(ctx);
    }
    const pz_symmetry *s = &layout->symmetry;
    int32_t kept = 0;
    for (int32_t i = 0; i < n; ++i) {
        pz_trace_path *path = &traced->paths[i];
        if (plane_side(layout, path->vertices, path->vertex_count) > MIRRORED_SIDE_EDGES * layout->mean_edge)
            continue;
        seg_candidate *c = candidates + kept;
        c->path = *path; /* moved: the traced list gives up its arrays */
        memset(path, 0, sizeof *path);
        c->usable = 1;
        if (s->found) {
            pz_ctx local;
            pz_ctx_init(&local);
            if (pz_symmetry_mirror_path(s, layout->graph, layout->mesh, layout->topology, &c->path, &c->mirror,
                                        &local) != PZ_OK) {
                memset(&c->mirror, 0, sizeof c->mirror);
                c->usable = 0;
            } else if (shared_fraction(&c->path, &c->mirror, mark) >= 0.8) {
                pz_trace_path_clear(&c->mirror);
            } else if (pz_trace_paths_tangential(&c->path, &c->mirror, layout->mesh->vertex_count)) {
                c->usable = 0;
            }
        }
        ++kept;
    }
    free(mark);
    *out = candidates;
    *count = kept;
    return PZ_OK;
}

/* 1 when some usable candidate (or its mirror) splits a failing panel: otherwise no distance is needed. */
static int any_helpful(const seg_layout *layout, const seg_candidate *candidates, int32_t count)
{
    for (int32_t i = 0; i < count; ++i)
        if (candidates[i].usable && (splits_failing(layout, &candidates[i].path) ||
                                     (candidates[i].mirror.vertex_count && splits_failing(layout, &candidates[i].mirror))))
            return 1;
    return 0;
}

/*
 * Greedy insertion over one pool of candidates (pietroni2022 Sec. 4.2):
 * farthest first among those that split a failing panel and meet no
 * inserted path tangentially. Returns the number inserted in *inserted.
 */
static pz_status insert_greedy(seg_layout *layout, seg_candidate *candidates, int32_t count, int32_t *inserted,
                               pz_ctx *ctx)
{
    *inserted = 0;
    double *distance = malloc((size_t)layout->graph->node_count * sizeof(double) + 1);
    pz_trace_path *in_paths = NULL;
    if (!distance)
        return nomem(ctx);
    pz_status status = PZ_OK;
    /* The distance covers paths[0 .. measured - 1]; each round adds the paths inserted since (-1: none yet). */
    int32_t measured = -1;
    for (int round = 0; round < MAX_INSERTIONS_PER_LEVEL && !status; ++round) {
        if ((status = seg_evaluate_panels(layout, NULL, ctx)))
            break;
        if (!failing_panels(layout) || !any_helpful(layout, candidates, count))
            break;
        free(in_paths);
        in_paths = malloc(((size_t)layout->path_count + 1) * sizeof(pz_trace_path));
        if (!in_paths) {
            status = nomem(ctx);
            break;
        }
        for (int32_t i = 0; i < layout->path_count; ++i)
            in_paths[i] = layout->paths[i].path;
        status = measured < 0 ? pz_trace_distance(layout->graph, in_paths, layout->path_count, 1, distance, ctx)
                              : pz_trace_distance_add(layout->graph, in_paths + measured, layout->path_count - measured,
                                                      distance, ctx);
        measured = layout->path_count;
        if (status)
            break;
        int32_t best = -1;
        double best_distance = -1;
        for (int32_t i = 0; i < count; ++i) {
            seg_candidate *c = candidates + i;
            if (!c->usable)
                continue;
            if (!splits_failing(layout, &c->path) && !(c->mirror.vertex_count && splits_failing(layout, &c->mirror)))
                continue;
            double d = pz_trace_path_mean_distance(&c->path, distance);
            if (!(d > best_distance))
                continue;
            if (tangential_to_inserted(layout, &c->path) ||
                (c->mirror.vertex_count && tangential_to_inserted(layout, &c->mirror))) {
                c->usable = 0; /* inserted paths only grow: it stays tangential */
                continue;
            }
            best = i;
            best_distance = d;
        }
        if (best < 0)
            break;
        candidates[best].usable = 0;
        status = add_path(layout, &candidates[best].path, 0, ctx);
        if (!status && candidates[best].mirror.vertex_count)
            status = add_path(layout, &candidates[best].mirror, 0, ctx);
        if (!status)
            status = seg_label_panels(layout, ctx);
        ++*inserted;
        if (!status && (status = seg_evaluate_panels(layout, NULL, ctx)) == PZ_OK)
            seg_progress(layout, "insert");
    }
    free(in_paths);
    free(distance);
    return status;
}

uint8_t seg_closest_arm(const pz_trace_graph *graph, int32_t v, const double d[3])
{
    const double *n = graph->vertex_normals + 3 * v, *a = graph->vertex_arms + 3 * v;
    double b[3] = {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]};
    double along = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    double across = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
    if (fabs(along) >= fabs(across))
        return along >= 0 ? 0 : 2;
    return across >= 0 ? 1 : 3;
}

/* Arm k of vertex v of a graph as a 3D direction. */
static void arm_direction(const pz_trace_graph *graph, int32_t v, int k, double d[3])
{
    const double *n = graph->vertex_normals + 3 * v, *a = graph->vertex_arms + 3 * v;
    double b[3] = {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]};
    double ca = k == 0 ? 1 : k == 2 ? -1 : 0, cb = k == 1 ? 1 : k == 3 ? -1 : 0;
    for (int i = 0; i < 3; ++i)
        d[i] = ca * a[i] + cb * b[i];
}

/* Candidates traced on panel p's own submesh, mapped back to the garment (vertices and arms). */
static pz_status panel_candidates(seg_layout *layout, int32_t p, pz_trace_paths **out, pz_ctx *ctx)
{
    *out = NULL;
    const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
    int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    pz_mesh *sub = NULL;
    int32_t *vertex_map = NULL, *face_map = NULL;
    pz_topology *topology = NULL;
    pz_trace_graph *graph = NULL;
    double *arms = NULL;
    pz_ctx local;
    pz_ctx_init(&local);
    local.quiet = 1;
    pz_status status = pz_mesh_extract(layout->mesh, faces, count, &sub, &vertex_map, &face_map, ctx);
    if (status)
        return status;
    /* A panel pinched at a vertex has no topology: it gets no candidates of its own. */
    if (pz_topology_build(sub, &topology, &local) == PZ_OK) {
        arms = malloc((size_t)count * 3 * sizeof(double));
        if (!arms)
            status = nomem(ctx);
        for (int32_t f = 0; arms && f < count; ++f)
            memcpy(arms + 3 * f, layout->field->directions + 3 * face_map[f], 3 * sizeof(double));
        pz_trace_candidate_options options = {0};
        options.border_sources = layout->max_candidates / 4 > 4 ? layout->max_candidates / 4 : 4;
        options.interior_sources = options.border_sources;
        options.threads = layout->threads;
        if (!status && pz_trace_graph_build(sub, topology, arms, &layout->options->graph, &graph, &local) == PZ_OK &&
            pz_trace_candidates(graph, sub, topology, &options, out, &local) == PZ_OK) {
            for (int32_t i = 0; i < (*out)->path_count; ++i) {
                pz_trace_path *path = &(*out)->paths[i];
                for (int32_t j = 0; j < path->vertex_count; ++j) {
                    double d[3];
                    arm_direction(graph, path->vertices[j], path->arms[j], d);
                    path->vertices[j] = vertex_map[path->vertices[j]];
                    path->arms[j] = seg_closest_arm(layout->graph, path->vertices[j], d);
                }
            }
        }
    }
    pz_trace_graph_free(&graph);
    free(arms);
    pz_topology_free(&topology);
    free(vertex_map);
    free(face_map);
    pz_mesh_free(&sub);
    return status;
}

/* One recursion level: candidates on every failing panel's submesh, inserted greedily. */
static pz_status recurse_failing(seg_layout *layout, int32_t *inserted, pz_ctx *ctx)
{
    *inserted = 0;
    int32_t panels = layout->panel_count;
    pz_trace_paths *pooled = calloc(1, sizeof *pooled);
    if (!pooled)
        return nomem(ctx);
    pz_status status = PZ_OK;
    for (int32_t p = 0; p < panels && !status; ++p) {
        if (!layout->panel_goals[p].failures)
            continue;
        pz_trace_paths *paths = NULL;
        status = panel_candidates(layout, p, &paths, ctx);
        if (status || !paths)
            continue;
        pz_trace_path *grown = realloc(pooled->paths, ((size_t)pooled->path_count + paths->path_count + 1) *
                                                          sizeof(pz_trace_path));
        if (!grown) {
            status = nomem(ctx);
        } else {
            pooled->paths = grown;
            memcpy(grown + pooled->path_count, paths->paths, (size_t)paths->path_count * sizeof(pz_trace_path));
            pooled->path_count += paths->path_count;
            paths->path_count = 0; /* moved */
        }
        pz_trace_paths_free(&paths);
    }
    seg_candidate *candidates = NULL;
    int32_t count = 0;
    if (!status)
        status = make_candidates(layout, pooled, &candidates, &count, ctx);
    if (!status)
        status = insert_greedy(layout, candidates, count, inserted, ctx);
    candidates_clear(candidates, count);
    pz_trace_paths_free(&pooled);
    return status;
}

/* ---------------------------------------------------------------- stages */

static pz_status insert_sketches(seg_layout *layout, pz_ctx *ctx)
{
    const pz_sketch *sketch = layout->options->sketch;
    if (!sketch)
        return PZ_OK;
    for (int32_t i = 0; i < sketch->curve_count; ++i) {
        int32_t first = sketch->curve_offsets[i], n = sketch->curve_offsets[i + 1] - first;
        const double *points = sketch->points + 3 * first;
        const double *last = points + 3 * (n - 1);
        /* A curve whose ends coincide is closed. */
        int closed = n > 2 && fabs(points[0] - last[0]) + fabs(points[1] - last[1]) + fabs(points[2] - last[2]) <
                                  1e-9 * (1 + fabs(points[0]));
        char name[32];
        snprintf(name, sizeof name, "sketch curve %d", (int)i);
        pz_trace_path path;
        memset(&path, 0, sizeof path);
        pz_status status = pz_trace_snap_polyline(layout->graph, layout->mesh, layout->topology, points,
                                                  closed ? n - 1 : n, closed, 0, name, &path, ctx);
        if (!status)
            status = add_path(layout, &path, SEG_SKETCH, ctx);
        pz_trace_path_clear(&path);
        if (status)
            return status;
    }
    return PZ_OK;
}

/* options->seed_cuts: cut from the start, owned by one empty path marked SEG_SEEDED (never removed). */
static pz_status insert_seeds(seg_layout *layout, pz_ctx *ctx)
{
    const uint8_t *seeds = layout->options->seed_cuts;
    if (!seeds)
        return PZ_OK;
    pz_trace_path empty;
    memset(&empty, 0, sizeof empty);
    pz_status status = add_path(layout, &empty, SEG_SEEDED, ctx);
    if (status)
        return status;
    int32_t index = layout->path_count - 1;
    for (int32_t e = 0; e < layout->topology->edge_count; ++e) {
        if (!seeds[e] || layout->edge_cut[e])
            continue;
        layout->edge_cut[e] = 1;
        layout->edge_owner[e] = index;
        layout->labels_valid = 0;
    }
    return PZ_OK;
}

static pz_status insert_all(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_trace_candidate_options options = {0};
    options.border_sources = layout->max_candidates / 2;
    options.interior_sources = layout->max_candidates / 2;
    options.threads = layout->threads;
    pz_trace_paths *traced = NULL;
    pz_status status = pz_trace_candidates(layout->graph, layout->mesh, layout->topology, &options, &traced, ctx);
    seg_candidate *candidates = NULL;
    int32_t count = 0;
    if (!status)
        status = make_candidates(layout, traced, &candidates, &count, ctx);
    pz_trace_paths_free(&traced);
    result->candidate_count = count;
    result->candidates_ms = 1e3 * (pz_seconds() - start);
    start = pz_seconds();
    if (!status)
        seg_progress(layout, "candidates");
    int32_t inserted = 0;
    if (!status)
        status = insert_greedy(layout, candidates, count, &inserted, ctx);
    candidates_clear(candidates, count);
    for (int32_t depth = 0; !status && depth < layout->max_depth && failing_panels(layout); ++depth) {
        int32_t more = 0;
        status = recurse_failing(layout, &more, ctx);
        if (!more)
            break;
    }
    if (!status && failing_panels(layout))
        status = seg_fallback_cuts(layout, &inserted, ctx);
    result->insert_ms = 1e3 * (pz_seconds() - start);
    return status;
}

/*
 * Removal, then darts, then removal again: a dart merges two panels, after
 * which a seam next to them may go (the merged panel has its corners back
 * once the dart closes at the seam). Rounds repeat while a dart is made, at
 * most REMOVE_DART_ROUNDS.
 */
#define REMOVE_DART_ROUNDS 3
static pz_status remove_and_dart(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    pz_status status = PZ_OK;
    for (int round = 0; round < REMOVE_DART_ROUNDS && !status; ++round) {
        double start = pz_seconds();
        int32_t removed = 0, darts = 0;
        status = seg_remove_pass(layout, &removed, ctx);
        result->removed_count += removed;
        result->remove_ms += 1e3 * (pz_seconds() - start);
        if (status || !layout->options->darts || (round > 0 && removed == 0))
            break;
        start = pz_seconds();
        status = seg_dart_pass(layout, &darts, ctx);
        result->darts_ms += 1e3 * (pz_seconds() - start);
        if (darts == 0)
            break;
    }
    return status;
}

/* ---------------------------------------------------------------- result */

static int compare_int64(const void *l, const void *r)
{
    int64_t a = *(const int64_t *)l, b = *(const int64_t *)r;
    return (a > b) - (a < b);
}

/*
 * Mirror panel of each panel: the panel holding most of its faces' mirror
 * images (itself when it straddles the plane). Votes are (panel, mirror
 * panel) pairs sorted and counted: O(F log F), whatever the panel count.
 */
static pz_status mirror_panels(const seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    for (int32_t p = 0; p < result->panel_count; ++p)
        result->panels[p].mirror_panel = -1;
    if (!layout->symmetry.found)
        return PZ_OK;
    const pz_topology *t = layout->topology;
    const int32_t *mirror = layout->symmetry.vertex_mirror;
    int64_t panels = result->panel_count;
    int64_t *votes = malloc((size_t)t->face_count * sizeof(int64_t) + 1);
    if (!votes)
        return nomem(ctx);
    int32_t count = 0;
    for (int32_t f = 0; f < t->face_count; ++f) {
        const int32_t *v = t->faces + 3 * f;
        int32_t e = seg_edge_between(layout, mirror[v[0]], mirror[v[1]]);
        for (int s = 0; e >= 0 && s < 2; ++s) {
            int32_t h = t->edge_halfedge[2 * e + s];
            if (h >= 0 && t->faces[pz_he_prev(h)] == mirror[v[2]]) {
                votes[count++] = result->face_panel[f] * panels + result->face_panel[pz_he_face(h)];
                break;
            }
        }
    }
    qsort(votes, (size_t)count, sizeof(int64_t), compare_int64);
    int32_t best_votes = 0;
    for (int32_t i = 0; i < count;) {
        int32_t j = i;
        while (j < count && votes[j] == votes[i])
            ++j;
        int32_t p = (int32_t)(votes[i] / panels), q = (int32_t)(votes[i] % panels);
        if (i == 0 || votes[i] / panels != votes[i - 1] / panels)
            best_votes = 0; /* a new panel's runs start */
        if (j - i > best_votes) {
            best_votes = j - i;
            result->panels[p].mirror_panel = q;
        }
        i = j;
    }
    free(votes);
    return PZ_OK;
}

/* RMS distance of the cut edges' mirrored midpoints to the nearest cut-edge midpoint. Over at most
 * RESIDUAL_SAMPLES cut edges (every k-th) against all: quadratic otherwise on a shredded mesh. */
#define RESIDUAL_SAMPLES 4096
static double symmetry_residual(const seg_layout *layout)
{
    const pz_symmetry *s = &layout->symmetry;
    if (!s->found)
        return 0;
    const pz_topology *t = layout->topology;
    int32_t n = 0;
    double *mid = malloc((size_t)3 * t->edge_count * sizeof(double) + 1);
    if (!mid)
        return -1;
    for (int32_t e = 0; e < t->edge_count; ++e) {
        if (!layout->edge_cut[e])
            continue;
        int32_t h = t->edge_halfedge[2 * e];
        const double *a = layout->mesh->positions + 3 * pz_he_from(t, h), *b = layout->mesh->positions + 3 * pz_he_to(t, h);
        for (int k = 0; k < 3; ++k)
            mid[3 * n + k] = 0.5 * (a[k] + b[k]);
        ++n;
    }
    double sum = 0;
    int32_t stride = n > RESIDUAL_SAMPLES ? (n + RESIDUAL_SAMPLES - 1) / RESIDUAL_SAMPLES : 1, samples = 0;
    for (int32_t i = 0; i < n; i += stride, ++samples) {
        const double *p = mid + 3 * i;
        double d = s->normal[0] * p[0] + s->normal[1] * p[1] + s->normal[2] * p[2] - s->offset;
        double q[3] = {p[0] - 2 * d * s->normal[0], p[1] - 2 * d * s->normal[1], p[2] - 2 * d * s->normal[2]};
        double best = INFINITY;
        for (int32_t j = 0; j < n; ++j) {
            double dx = mid[3 * j] - q[0], dy = mid[3 * j + 1] - q[1], dz = mid[3 * j + 2] - q[2];
            best = fmin(best, dx * dx + dy * dy + dz * dz);
        }
        sum += best;
    }
    free(mid);
    return samples ? sqrt(sum / samples) : 0;
}

/* Curves of the final layout: its segments, darts oriented from their tip. */
static pz_status make_curves(const seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    seg_segments segments = {0, NULL};
    pz_status status = seg_segments_build(layout, &segments, ctx);
    if (status)
        return status;
    result->curves = calloc((size_t)segments.count + 1, sizeof(pz_layout_curve));
    if (!result->curves) {
        seg_segments_clear(&segments);
        return nomem(ctx);
    }
    const pz_topology *t = layout->topology;
    for (int32_t i = 0; i < segments.count; ++i) {
        seg_segment *s = segments.items + i;
        pz_layout_curve *c = result->curves + result->curve_count++;
        int32_t n = s->closed ? s->edge_count : s->edge_count + 1;
        c->closed = s->closed;
        c->vertex_count = n;
        c->vertices = malloc((size_t)n * sizeof(int32_t));
        if (!c->vertices) {
            status = nomem(ctx);
            break;
        }
        int32_t first = s->vertices[0], last = s->vertices[s->edge_count];
        int tip_first = !s->closed && !t->vertex_on_boundary[first] && seg_cut_degree(layout, first) == 1;
        int tip_last = !s->closed && !t->vertex_on_boundary[last] && seg_cut_degree(layout, last) == 1;
        for (int32_t j = 0; j < n; ++j)
            c->vertices[j] = tip_last && !tip_first ? s->vertices[n - 1 - j] : s->vertices[j];
        /* A sketched curve that ends inside a panel is a dart of the pattern all the same
         * (pz_pattern_build makes one of every slit): kind dart, marked sketched. */
        c->sketched = (s->sketch & SEG_SKETCH) != 0;
        c->kind = (tip_first || tip_last) ? PZ_LAYOUT_DART : c->sketched ? PZ_LAYOUT_SKETCH : PZ_LAYOUT_SEAM;
        if (c->kind == PZ_LAYOUT_DART) {
            ++result->dart_count;
            int32_t face = pz_he_face(t->edge_halfedge[2 * s->edges[0]]);
            ++result->panels[result->face_panel[face]].darts;
        }
    }
    seg_segments_clear(&segments);
    return status;
}

static pz_status fill_result(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    const pz_topology *t = layout->topology;
    pz_status status = seg_label_panels(layout, ctx);
    if (!status)
        status = seg_evaluate_panels(layout, NULL, ctx);
    if (status)
        return status;
    result->face_count = t->face_count;
    result->edge_count = t->edge_count;
    result->panel_count = layout->panel_count;
    result->face_panel = malloc((size_t)t->face_count * sizeof(int32_t) + 1);
    result->edge_cut = malloc((size_t)t->edge_count + 1);
    result->extra_cuts = calloc((size_t)t->edge_count + 1, 1);
    result->panels = calloc((size_t)layout->panel_count + 1, sizeof(pz_segment_panel));
    if (!result->face_panel || !result->edge_cut || !result->extra_cuts || !result->panels)
        return nomem(ctx);
    memcpy(result->face_panel, layout->face_panel, (size_t)t->face_count * sizeof(int32_t));
    memcpy(result->edge_cut, layout->edge_cut, (size_t)t->edge_count);
    for (int32_t e = 0; e < t->edge_count; ++e) {
        int32_t a = t->edge_halfedge[2 * e], b = t->edge_halfedge[2 * e + 1];
        result->extra_cuts[e] = layout->edge_cut[e] && b >= 0 &&
                                layout->face_panel[pz_he_face(a)] == layout->face_panel[pz_he_face(b)];
    }
    result->goals_met = 1;
    size_t used = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p) {
        pz_segment_panel *panel = result->panels + p;
        panel->face_count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
        panel->goals = layout->panel_goals[p];
        panel->corners = panel->goals.corners;
        if (!panel->goals.failures)
            continue;
        result->goals_met = 0;
        char text[160];
        pz_goal_describe(&panel->goals, &layout->goals, text, sizeof text);
        if (used < sizeof result->reasons) {
            int n = snprintf(result->reasons + used, sizeof result->reasons - used, "%spanel %d: %s",
                             used ? "; " : "", (int)p, text);
            used += n > 0 ? (size_t)n : 0;
        }
    }
    if (!status)
        status = mirror_panels(layout, result, ctx);
    if (!status)
        status = make_curves(layout, result, ctx);
    result->symmetry_residual_mm = symmetry_residual(layout);
    return status;
}

/* ---------------------------------------------------------------- public */

void pz_segment_options_default(pz_segment_options *options)
{
    memset(options, 0, sizeof *options);
    options->max_corners = DEFAULT_MAX_CORNERS;
    options->max_strain = DEFAULT_MAX_STRAIN;
    options->symmetry = PZ_SYMMETRY_AUTO;
    options->darts = 1;
    options->grain[2] = 1;
}

static void layout_free(seg_layout *layout)
{
    pz_trace_graph_free(&layout->graph);
    pz_symmetry_clear(&layout->symmetry);
    free(layout->vertex_edge_offsets);
    free(layout->vertex_edges);
    free(layout->edge_cut);
    free(layout->edge_owner);
    for (int32_t i = 0; i < layout->path_count; ++i)
        pz_trace_path_clear(&layout->paths[i].path);
    free(layout->paths);
    free(layout->face_panel);
    free(layout->panel_offsets);
    free(layout->panel_faces);
    free(layout->labelled_cut);
    free(layout->label_stack);
    free(layout->label_region);
    free(layout->label_spare);
    free(layout->panel_goals);
    free(layout->panel_evaluated);
    free(layout->own_cache.entries);
    for (int32_t t = 0; layout->goal_scratch && t < layout->threads; ++t)
        seg_goal_scratch_free(layout->goal_scratch[t]);
    free(layout->goal_scratch);
}

static pz_status check_options(const pz_segment_options *options, pz_ctx *ctx)
{
    if (!(options->strain_margin >= 0 && options->strain_margin <= 0.9))
        return pz_error(ctx, PZ_ERR_USAGE, "segment: strain margin %g is not within 0 .. 0.9", options->strain_margin);
    if (!(options->max_strain >= 0) || options->max_corners < 0 || options->max_candidates < 0 ||
        options->max_depth < 0 || options->threads < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: negative strain, corner, candidate, depth or thread option");
    double g = sqrt(options->grain[0] * options->grain[0] + options->grain[1] * options->grain[1] +
                    options->grain[2] * options->grain[2]);
    if (!(g > 0))
        return pz_error(ctx, PZ_ERR_USAGE, "segment: the grain axis is zero");
    return PZ_OK;
}

static pz_status layout_init(seg_layout *layout, const pz_mesh *mesh, const pz_topology *topology,
                             const pz_field *field, const pz_segment_options *options, pz_ctx *ctx)
{
    layout->mesh = mesh;
    layout->topology = topology;
    layout->field = field;
    layout->options = options;
    layout->cache = options->cache ? options->cache : &layout->own_cache;
    layout->goals.max_corners = options->max_corners > 0 ? options->max_corners : DEFAULT_MAX_CORNERS;
    layout->goals.max_strain = options->max_strain;
    layout->accept_strain = (1 - options->strain_margin) * options->max_strain;
    double g = sqrt(options->grain[0] * options->grain[0] + options->grain[1] * options->grain[1] +
                    options->grain[2] * options->grain[2]);
    for (int k = 0; k < 3; ++k)
        layout->goals.grain[k] = options->grain[k] / g;
    layout->threads = options->threads > 0 ? options->threads : omp_get_max_threads();
    layout->goal_scratch = calloc((size_t)layout->threads, sizeof *layout->goal_scratch);
    if (!layout->goal_scratch)
        return nomem(ctx);
    layout->max_candidates = options->max_candidates > 0 ? options->max_candidates : DEFAULT_MAX_CANDIDATES;
    layout->max_depth = options->max_depth > 0 ? options->max_depth : DEFAULT_MAX_DEPTH;
    layout->mean_edge = pz_field_mean_edge_length(mesh, topology);
    size_t faces = (size_t)topology->face_count, edges = (size_t)topology->edge_count;
    layout->edge_cut = calloc(edges + 1, 1);
    layout->edge_owner = malloc((edges + 1) * sizeof(int32_t));
    layout->face_panel = malloc((faces + 1) * sizeof(int32_t));
    layout->panel_faces = malloc((faces + 1) * sizeof(int32_t));
    layout->labelled_cut = malloc(edges + 1);
    /* The flood's stack, and the changed edges before it: as many as the faces or the edges. */
    layout->label_stack = malloc(((faces > edges ? faces : edges) + 1) * sizeof(int32_t));
    layout->label_region = malloc((faces + 1) * sizeof(int32_t));
    layout->label_spare = malloc((faces + 1) * sizeof(int32_t));
    if (!layout->edge_cut || !layout->edge_owner || !layout->face_panel || !layout->panel_faces ||
        !layout->labelled_cut || !layout->label_stack || !layout->label_region || !layout->label_spare)
        return nomem(ctx);
    memset(layout->edge_owner, 0xff, edges * sizeof(int32_t));
    return build_vertex_edges(layout, ctx);
}

/*
 * The plane, from the options. A detected (AUTO) plane is dropped when its
 * residual exceeds MAX_AUTO_RESIDUAL_EDGES mean edges: mirror images of paths
 * go through the nearest-vertex map, and farther off they land on other
 * edges than the mirrored geometry (the shirt front of ../shared/data at 0.5
 * mean edge got a fragmented layout that missed the goals; without the plane
 * it meets them).
 */
static pz_status detect_symmetry(seg_layout *layout, pz_ctx *ctx)
{
    pz_symmetry_mode mode = layout->options->symmetry;
    pz_status status = pz_symmetry_detect(layout->mesh, layout->topology, mode, 0, &layout->symmetry, ctx);
    if (!status && mode == PZ_SYMMETRY_AUTO && layout->symmetry.found &&
        layout->symmetry.residual_mm > MAX_AUTO_RESIDUAL_EDGES * layout->mean_edge) {
        double residual_mm = layout->symmetry.residual_mm, residual_rel = layout->symmetry.residual_rel;
        pz_symmetry_clear(&layout->symmetry);
        layout->symmetry.axis = -1;
        layout->symmetry.residual_mm = residual_mm; /* kept for the report: why no plane */
        layout->symmetry.residual_rel = residual_rel;
    }
    return status;
}

pz_status pz_segment(const pz_mesh *mesh, const pz_topology *topology, const pz_field *field,
                     const pz_segment_options *options, pz_segment_result **out, pz_ctx *ctx)
{
    if (!out)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: no output");
    *out = NULL;
    if (!mesh || !topology || !field || !options || field->face_count != topology->face_count)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: no mesh, field or options, or a field of another mesh");
    pz_status status = check_options(options, ctx);
    if (status)
        return status;
    double start = pz_seconds();
    pz_segment_result *result = calloc(1, sizeof *result);
    seg_layout layout;
    memset(&layout, 0, sizeof layout);
    if (!result)
        return nomem(ctx);
    status = layout_init(&layout, mesh, topology, field, options, ctx);
    if (!status)
        status = pz_trace_graph_build(mesh, topology, field->directions, &options->graph, &layout.graph, ctx);
    if (!status)
        status = detect_symmetry(&layout, ctx);
    result->graph_ms = 1e3 * (pz_seconds() - start);
    if (!status)
        status = insert_sketches(&layout, ctx);
    if (!status)
        status = insert_seeds(&layout, ctx);
    if (!status)
        status = seg_label_panels(&layout, ctx);
    if (!status)
        status = insert_all(&layout, result, ctx);
    result->inserted_count = layout.path_count;
    if (!status)
        status = remove_and_dart(&layout, result, ctx);
    if (!status)
        status = fill_result(&layout, result, ctx);
    result->evaluation_count = layout.evaluation_count;
    if (!status) {
        result->symmetry = layout.symmetry; /* moved */
        memset(&layout.symmetry, 0, sizeof layout.symmetry);
    }
    layout_free(&layout);
    result->total_ms = 1e3 * (pz_seconds() - start);
    if (status) {
        pz_segment_result_free(&result);
        return status;
    }
    *out = result;
    return PZ_OK;
}

void pz_segment_result_free(pz_segment_result **result)
{
    if (!result || !*result)
        return;
    pz_segment_result *r = *result;
    free(r->face_panel);
    free(r->edge_cut);
    free(r->extra_cuts);
    free(r->panels);
    for (int32_t i = 0; i < r->curve_count; ++i)
        free(r->curves[i].vertices);
    free(r->curves);
    pz_symmetry_clear(&r->symmetry);
    free(r);
    *result = NULL;
}
