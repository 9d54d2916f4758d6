/*
 * segment/labels.c -- the panels of the layout's current cut flags: face
 * components across uncut edges, relabelled after every step of the layout
 * (segment/layout.c, insert.c, removal.c, fallback.c call seg_label_panels).
 *
 * Kept apart from the layout because it is a self-contained algorithm over
 * the seg_layout arrays (face_panel, panel_offsets, panel_faces and their
 * scratch) with one entry point; the evaluation of the panels it produces is
 * segment/evaluate.c.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"

#include <stdlib.h>
#include <string.h>

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

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
    seg_shape *shape = realloc(layout->panel_shape, ((size_t)panels + 1) * sizeof(seg_shape));
    if (shape)
        layout->panel_shape = shape;
    if (!offsets || !goals || !evaluated || !shape)
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
    ++layout->labelling; /* what was computed from the old labels (segment/mirror.c) is stale */
    return status;
}
