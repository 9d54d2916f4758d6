/*
 * segment/budget.c -- fewer pieces at the least strain (docs/segment.md, "A piece budget and the
 * trade-off"): the piece budget of pz_segment_options.max_pieces, and the merge sequence behind the
 * trade-off curve (pz_segment_merge_sequence).
 *
 * A merge removes one seam segment (with its mirror image) that joins two different panels. Each step
 * takes, among the merges that leave no stub and keep every panel a disk that flattens injectively,
 * the one that leaves fewer bands round the body (segment/preference.c), then the least worst strain
 * of the layout, then the least strain of the merged panel. Corners and S no longer stop a merge (the
 * corner bound would stop merges a designer asked for; S is what the budget trades away). Sketched and
 * seeded seams stay.
 *
 * Every trial is a merged panel (the union of two panels' faces, its slits): its figures do not depend
 * on its neighbours once corners no longer count, so they are kept by face set and slits across the
 * steps of one sequence (a step flattens only the merges next to the previous one), and the trials a
 * step needs are flattened in parallel, each thread on its own copy of the cut flags. The flattening is
 * the evaluation's (segment/goals.c, 5 textile iterations aiming at S) with the corner bound lifted.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* The corner bound while merging: every disk is flattened. */
#define BUDGET_CORNERS 100000
/* The trade-off's merge sequence flattens at most this many new trials a step, the most promising ones (the
 * budget, a designer's explicit request, tries them all). */
#define TRADEOFF_TRIALS 4
/* What a merged panel must still be. */
#define BUDGET_HARD_FAILURES (PZ_GOAL_NOT_DISK | PZ_GOAL_NOT_INJECTIVE)

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

/* ---------------------------------------------------------------- merged panels, kept by faces and slits */

typedef struct merged_figures {
    uint64_t key;              /* 0: empty slot */
    pz_goal_result goals;
    seg_shape shape;
} merged_figures;

typedef struct merged_memo {
    merged_figures *slots;
    int32_t capacity, count;
} merged_memo;

static merged_figures *memo_slot(merged_memo *memo, uint64_t key)
{
    int32_t mask = memo->capacity - 1, i = (int32_t)(key & (uint64_t)mask);
    while (memo->slots[i].key && memo->slots[i].key != key)
        i = (i + 1) & mask;
    return memo->slots + i;
}

/* The figures kept under key, or NULL. */
static const merged_figures *memo_find(const merged_memo *memo, uint64_t key)
{
    if (memo->capacity == 0)
        return NULL;
    const merged_figures *slot = memo_slot((merged_memo *)memo, key);
    return slot->key ? slot : NULL;
}

static int memo_store(merged_memo *memo, const merged_figures *figures)
{
    if (2 * (memo->count + 1) > memo->capacity) {
        merged_memo grown = {NULL, memo->capacity ? 2 * memo->capacity : 64, 0};
        grown.slots = calloc((size_t)grown.capacity, sizeof *grown.slots);
        if (!grown.slots)
            return 0;
        for (int32_t i = 0; i < memo->capacity; ++i)
            if (memo->slots[i].key)
                *memo_slot(&grown, memo->slots[i].key) = memo->slots[i], ++grown.count;
        free(memo->slots);
        *memo = grown;
    }
    merged_figures *slot = memo_slot(memo, figures->key);
    if (!slot->key)
        ++memo->count;
    *slot = *figures;
    return 1;
}

static uint64_t mix(uint64_t hash, uint64_t value)
{
    uint64_t z = hash ^ (value + 0x9e3779b97f4a7c15ull + (hash << 6) + (hash >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static int compare_int32(const void *l, const void *r)
{
    int32_t a = *(const int32_t *)l, b = *(const int32_t *)r;
    return (a > b) - (a < b);
}

typedef struct budget_state {
    merged_memo memo;
    uint8_t *in_group;         /* face_count scratch: faces of the merged panel being keyed */
    int32_t *edges;            /* edge_count scratch */
    uint8_t **cuts;            /* per thread: a copy of the cut flags */
    int threads;
    int32_t most_trials;       /* > 0: flatten at most this many new trials a step, the most promising */
    int32_t max_corners;       /* > 0: merged panels keep this corner bound and are no bands (the trade-off) */
    int alone;                 /* 1: a seam is removed without its mirror image (no mirrored merge was valid) */
} budget_state;

/* ---------------------------------------------------------------- a trial */

/*
 * The memo key of a panel: its faces (increasing) and the slits it keeps, the cut edges inside it that
 * `set` (may be NULL) does not uncut. 0 when out of memory.
 */
static int memo_key(const seg_layout *layout, budget_state *state, const int32_t *faces, int32_t count,
                    const seg_edge_set *set, uint64_t *out)
{
    const pz_topology *t = layout->topology;
    uint64_t key = pz_segment_face_set_key(faces, count);
    for (int32_t i = 0; i < count; ++i)
        state->in_group[faces[i]] = 1;
    for (int32_t i = 0; set && i < set->count; ++i)
        state->edges[set->edges[i]] = 1; /* uncut by the trial */
    int32_t slits = 0;
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t h = 3 * faces[i] + k, g = t->twin[h], e = t->halfedge_edge[h];
            if (g >= 0 && g < h && layout->edge_cut[e] && state->edges[e] != 1 && state->in_group[pz_he_face(g)])
                state->edges[e] = 2, ++slits;
        }
    int32_t listed = 0;
    int32_t *slit_list = malloc((size_t)slits * sizeof(int32_t) + 1);
    for (int32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t e = t->halfedge_edge[3 * faces[i] + k];
            if (state->edges[e] == 2) {
                if (slit_list)
                    slit_list[listed++] = e;
                state->edges[e] = 0;
            }
        }
    for (int32_t i = 0; set && i < set->count; ++i)
        state->edges[set->edges[i]] = 0;
    for (int32_t i = 0; i < count; ++i)
        state->in_group[faces[i]] = 0;
    if (!slit_list)
        return 0;
    qsort(slit_list, (size_t)listed, sizeof(int32_t), compare_int32);
    for (int32_t i = 0; i < listed; ++i)
        key = mix(key, (uint64_t)slit_list[i]);
    free(slit_list);
    *out = key ? key : 1;
    return 1;
}

/*
 * Every panel's figures: from the memo where it knows the panel (its figures do not depend on its
 * neighbours once corners no longer count), evaluated otherwise and kept there.
 */
static pz_status evaluate_from_memo(seg_layout *layout, budget_state *state, pz_ctx *ctx)
{
    pz_status status = seg_label_panels(layout, ctx);
    uint64_t *keys = status ? NULL : malloc(((size_t)layout->panel_count + 1) * sizeof(uint64_t));
    if (!status && !keys)
        status = nomem(ctx);
    for (int32_t p = 0; p < layout->panel_count && !status; ++p) {
        const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
        int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
        if (!memo_key(layout, state, faces, count, NULL, keys + p)) {
            status = nomem(ctx);
            break;
        }
        const merged_figures *known = layout->panel_evaluated[p] ? NULL : memo_find(&state->memo, keys[p]);
        if (known) {
            layout->panel_goals[p] = known->goals;
            layout->panel_evaluated[p] = 1;
            seg_panel_shape(layout, p);
        }
    }
    if (!status)
        status = seg_evaluate_panels(layout, NULL, ctx);
    for (int32_t p = 0; p < layout->panel_count && !status; ++p) {
        merged_figures figures = {keys[p], layout->panel_goals[p], layout->panel_shape[p]};
        if (!memo_find(&state->memo, keys[p]) && !memo_store(&state->memo, &figures))
            status = nomem(ctx);
    }
    free(keys);
    return status;
}

/* One merged panel of a trial: faces (increasing), its key, and the trial's edge set to uncut. */
typedef struct merged_panel {
    int32_t *faces, count;
    uint64_t key;
    const seg_edge_set *set;
    merged_figures figures;    /* filled from the memo or by the flattening */
    int known;
    int skipped;               /* its trial is not among the step's most promising: not flattened */
} merged_panel;

/* What a trial merge gives. */
typedef struct merge_trial {
    int valid;          /* every merged panel a disk flattening injectively */
    int32_t bands;      /* bands round the body in the layout after the merge */
    double worst;       /* the layout's worst strain after the merge */
    double merged;      /* the merged panels' worst strain */
    int32_t pieces;     /* panels after the merge */
} merge_trial;

/* 1 when trial a is the better merge (see the file's comment). */
static int better(const merge_trial *a, const merge_trial *b)
{
    if (a->valid != b->valid)
        return a->valid > b->valid;
    if (a->bands != b->bands)
        return a->bands < b->bands;
    if (a->worst != b->worst)
        return a->worst < b->worst;
    return a->merged < b->merged;
}


/*
 * The merged panels of uncutting `set`: the panels on both sides of its edges, joined (union-find over
 * the few panels involved). Appends them to *panels (faces allocated). 0 when out of memory.
 */
static int merged_panels_of(const seg_layout *layout, budget_state *state, const seg_edge_set *set,
                            merged_panel **panels, int32_t *count, int32_t *capacity)
{
    const pz_topology *t = layout->topology;
    /* The panels involved and their union: a small list. */
    int32_t involved[64], parent[64], n = 0;
    for (int32_t i = 0; i < set->count; ++i) {
        int32_t ends[2] = {-1, -1};
        for (int k = 0; k < 2; ++k) {
            int32_t h = t->edge_halfedge[2 * set->edges[i] + k];
            if (h < 0)
                continue;
            int32_t p = layout->face_panel[pz_he_face(h)], j = 0;
            while (j < n && involved[j] != p)
                ++j;
            if (j == n) {
                if (n == 64)
                    return 1; /* an absurd merge: not tried */
                involved[n] = p, parent[n] = n, ++n;
            }
            ends[k] = j;
        }
        if (ends[0] >= 0 && ends[1] >= 0) {
            int32_t a = ends[0], b = ends[1];
            while (parent[a] != a)
                a = parent[a];
            while (parent[b] != b)
                b = parent[b];
            if (a != b)
                parent[a > b ? a : b] = a < b ? a : b;
        }
    }
    for (int32_t root = 0; root < n; ++root) {
        if (parent[root] != root)
            continue;
        int32_t faces = 0;
        for (int32_t j = 0; j < n; ++j) {
            int32_t r = j;
            while (parent[r] != r)
                r = parent[r];
            if (r == root)
                faces += layout->panel_offsets[involved[j] + 1] - layout->panel_offsets[involved[j]];
        }
        if (*count == *capacity) {
            *capacity = *capacity ? 2 * *capacity : 32;
            merged_panel *grown = realloc(*panels, (size_t)*capacity * sizeof **panels);
            if (!grown)
                return 0;
            *panels = grown;
        }
        merged_panel *m = *panels + (*count)++;
        memset(m, 0, sizeof *m);
        m->set = set;
        m->faces = malloc((size_t)faces * sizeof(int32_t) + 1);
        if (!m->faces)
            return 0;
        for (int32_t j = 0; j < n; ++j) {
            int32_t r = j;
            while (parent[r] != r)
                r = parent[r];
            if (r != root)
                continue;
            int32_t p = involved[j], first = layout->panel_offsets[p], size = layout->panel_offsets[p + 1] - first;
            memcpy(m->faces + m->count, layout->panel_faces + first, (size_t)size * sizeof(int32_t));
            m->count += size;
        }
        qsort(m->faces, (size_t)m->count, sizeof(int32_t), compare_int32);
        uint64_t key = 0;
        if (!memo_key(layout, state, m->faces, m->count, set, &key))
            return 0;
        m->key = key ? key : 1;
        const merged_figures *known = memo_find(&state->memo, m->key);
        if (known) {
            m->figures = *known;
            m->known = 1;
        }
    }
    return 1;
}

/* Flattens the merged panels not known yet, in parallel (each thread on its own copy of the cut flags). */
static pz_status flatten_unknown(seg_layout *layout, budget_state *state, merged_panel *panels, int32_t count,
                                 pz_ctx *ctx)
{
    int32_t *todo = malloc((size_t)count * sizeof(int32_t) + 1), todo_count = 0;
    pz_status *statuses = calloc((size_t)count + 1, sizeof(pz_status));
    pz_status status = todo && statuses ? PZ_OK : nomem(ctx);
    for (int32_t i = 0; i < count && !status; ++i) {
        int seen = 0; /* the same merged panel twice in one step (a mirror pair's trials): flattened once */
        for (int32_t j = 0; j < todo_count && !seen; ++j)
            seen = panels[todo[j]].key == panels[i].key;
        if (!panels[i].known && !panels[i].skipped && !seen)
            todo[todo_count++] = i;
    }
    for (int32_t t = 0; t < state->threads && !status; ++t)
        if (!layout->goal_scratch[t] && !(layout->goal_scratch[t] = seg_goal_scratch_new(layout->topology->face_count)))
            status = nomem(ctx);
    size_t edges = (size_t)layout->topology->edge_count;
    for (int t = 0; t < state->threads && !status; ++t)
        memcpy(state->cuts[t], layout->edge_cut, edges);
#pragma omp parallel for schedule(dynamic, 1) num_threads(state->threads) if (todo_count > 1 && !status)
    for (int32_t i = 0; i < todo_count; ++i) {
        if (status || pz_cancelled(ctx)) {
            statuses[i] = PZ_ERR_CANCELLED;
            continue;
        }
        omp_set_num_threads(1);
        int thread = omp_get_thread_num();
        uint8_t *cuts = state->cuts[thread];
        merged_panel *m = panels + todo[i];
        for (int32_t k = 0; k < m->set->count; ++k)
            cuts[m->set->edges[k]] = 0;
        pz_ctx local;
        pz_ctx_quiet(ctx, &local);
        statuses[i] = seg_goals(layout->mesh, layout->topology, cuts, NULL, m->faces, m->count, &layout->goals,
                                layout->goal_scratch[thread], &m->figures.goals, &local);
        if (statuses[i] && statuses[i] != PZ_ERR_NOMEM && statuses[i] != PZ_ERR_CANCELLED) {
            memset(&m->figures.goals, 0, sizeof m->figures.goals);
            m->figures.goals.failures = PZ_GOAL_NOT_INJECTIVE; /* as an evaluation counts a failed flattening */
            m->figures.goals.max_abs_strain = -1;
            statuses[i] = PZ_OK;
        }
        for (int32_t k = 0; k < m->set->count; ++k)
            cuts[m->set->edges[k]] = 1;
    }
    for (int32_t i = 0; i < todo_count && !status; ++i) {
        if (statuses[i] == PZ_ERR_CANCELLED)
            status = pz_error(ctx, PZ_ERR_CANCELLED, "segment: cancelled");
        else if (statuses[i])
            status = nomem(ctx);
        if (status)
            break;
        merged_panel *m = panels + todo[i];
        m->figures.key = m->key;
        seg_faces_shape(layout, m->faces, m->count, &m->figures.shape);
        m->known = 1;
        if (!memo_store(&state->memo, &m->figures))
            status = nomem(ctx);
    }
    layout->evaluation_count += todo_count;
    /* Trials that shared a flattened panel take its figures. */
    for (int32_t i = 0; i < count && !status; ++i)
        if (!panels[i].known) {
            const merged_figures *known = memo_find(&state->memo, panels[i].key);
            if (known)
                panels[i].figures = *known, panels[i].known = 1;
        }
    free(todo);
    free(statuses);
    return status;
}

/* ---------------------------------------------------------------- a step */

/* The worst strain and the bands of the current panels (evaluated), skipping those flagged in `skip`. */
static void layout_figures(const seg_layout *layout, const uint8_t *skip, double *worst, int32_t *bands)
{
    *worst = -1;
    *bands = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p) {
        if (skip && skip[p])
            continue;
        *worst = fmax(*worst, layout->panel_goals[p].max_abs_strain);
        *bands += seg_panel_is_band(layout, p);
    }
}

static int figures_band(const seg_layout *layout, const merged_figures *f)
{
    return seg_shape_is_band(layout, &f->shape);
}

/* The trial of segment i's set from its merged panels [first, last). */
static void judge_trial(const seg_layout *layout, const budget_state *state, const merged_panel *panels,
                        int32_t first, int32_t last, uint8_t *skip, merge_trial *out)
{
    memset(out, 0, sizeof *out);
    out->valid = last > first;
    out->merged = -1;
    int32_t involved = 0;
    const pz_topology *t = layout->topology;
    for (int32_t i = first; i < last; ++i) {
        const merged_panel *m = panels + i;
        if (!m->known || m->skipped || (m->figures.goals.failures & BUDGET_HARD_FAILURES))
            out->valid = 0;
        /* The trade-off keeps the run's other goals: the corner bound (a merged panel's corners only drop as its
         * neighbours merge later, so its count here stays an upper bound) and no band. */
        if (state->max_corners > 0 &&
            (m->figures.goals.corners > state->max_corners || figures_band(layout, &m->figures)))
            out->valid = 0;
        out->merged = fmax(out->merged, m->figures.goals.max_abs_strain);
        out->bands += figures_band(layout, &m->figures);
        for (int32_t k = 0; k < m->set->count; ++k)
            for (int s = 0; s < 2; ++s) {
                int32_t h = t->edge_halfedge[2 * m->set->edges[k] + s];
                if (h >= 0 && !skip[layout->face_panel[pz_he_face(h)]])
                    skip[layout->face_panel[pz_he_face(h)]] = 1, ++involved;
            }
    }
    double rest;
    int32_t rest_bands;
    layout_figures(layout, skip, &rest, &rest_bands);
    out->worst = fmax(rest, out->merged);
    out->bands += rest_bands;
    out->pieces = layout->panel_count - involved + (last - first);
    memset(skip, 0, (size_t)layout->panel_count + 1);
}

/* One merge: the best valid trial, applied (its merged panels' figures put in place). *merged = 0: none. */
/* The segment's edges alone, without their mirror images. 0 when out of memory. */
static int edge_set_alone(const seg_segment *s, seg_edge_set *out)
{
    out->count = s->edge_count;
    out->edges = malloc((size_t)s->edge_count * sizeof(int32_t) + 1);
    if (out->edges)
        memcpy(out->edges, s->edges, (size_t)s->edge_count * sizeof(int32_t));
    return out->edges != NULL;
}

/* A trial's promise before flattening: bands last, then the worst strain of the panels it joins, then area. */
typedef struct trial_promise {
    int32_t trial;
    int band;
    double parts_strain, area;
} trial_promise;

static int compare_promise(const void *l, const void *r)
{
    const trial_promise *a = l, *b = r;
    if (a->band != b->band)
        return a->band - b->band;
    if (a->parts_strain != b->parts_strain)
        return a->parts_strain < b->parts_strain ? -1 : 1;
    if (a->area != b->area)
        return a->area < b->area ? -1 : 1;
    return (a->trial > b->trial) - (a->trial < b->trial);
}

/*
 * Keeps, among the trials whose merged panels are not all known, the `most` most promising; the panels of
 * the others are marked skipped (not flattened this step). 0 when out of memory.
 */
static int keep_promising(const seg_layout *layout, merged_panel *panels, const int32_t *first, int32_t trials,
                          int32_t most)
{
    trial_promise *promise = malloc(((size_t)trials + 1) * sizeof *promise);
    if (!promise)
        return 0;
    int32_t unknown = 0;
    const pz_topology *t = layout->topology;
    for (int32_t i = 0; i < trials; ++i) {
        int all_known = 1;
        trial_promise p = {i, 0, -1, 0};
        for (int32_t j = first[i]; j < first[i + 1]; ++j) {
            merged_panel *m = panels + j;
            all_known &= m->known;
            seg_shape shape;
            seg_faces_shape(layout, m->faces, m->count, &shape);
            p.area += shape.area;
            p.band |= seg_shape_is_band(layout, &shape);
            for (int32_t k = 0; k < m->set->count; ++k)
                for (int side = 0; side < 2; ++side) {
                    int32_t h = t->edge_halfedge[2 * m->set->edges[k] + side];
                    if (h >= 0)
                        p.parts_strain = fmax(p.parts_strain,
                                              layout->panel_goals[layout->face_panel[pz_he_face(h)]].max_abs_strain);
                }
        }
        if (!all_known && first[i + 1] > first[i])
            promise[unknown++] = p;
    }
    qsort(promise, (size_t)unknown, sizeof *promise, compare_promise);
    for (int32_t i = most; i < unknown; ++i)
        for (int32_t j = first[promise[i].trial]; j < first[promise[i].trial + 1]; ++j)
            panels[j].skipped = !panels[j].known;
    free(promise);
    return 1;
}

static pz_status merge_step(seg_layout *layout, budget_state *state, int32_t *merged, merge_trial *chosen, pz_ctx *ctx)
{
    *merged = 0;
    seg_segments segments;
    pz_status status = seg_segments_build(layout, &segments, ctx);
    if (status)
        return status;
    seg_edge_set *sets = calloc((size_t)segments.count + 1, sizeof *sets);
    int32_t *first = malloc(((size_t)segments.count + 2) * sizeof(int32_t));
    uint8_t *skip = calloc((size_t)layout->panel_count + 1, 1);
    merged_panel *panels = NULL;
    int32_t panel_count = 0, panel_capacity = 0;
    seg_mirror_map map;
    memset(&map, 0, sizeof map);
    if (!sets || !first || !skip || !seg_mirror_map_build(layout, &segments, &map))
        status = nomem(ctx);
    const pz_topology *t = layout->topology;
    for (int32_t i = 0; i < segments.count && !status; ++i) {
        first[i] = panel_count;
        const seg_segment *s = segments.items + i;
        int32_t h = t->edge_halfedge[2 * s->edges[0]], g = t->edge_halfedge[2 * s->edges[0] + 1];
        if (s->sketch || !seg_all_cut(layout, s) || g < 0 ||
            layout->face_panel[pz_he_face(h)] == layout->face_panel[pz_he_face(g)])
            continue; /* kept by the designer, or joins a panel with itself: no piece fewer */
        if (!state->alone && map.claimed && map.claimed[i])
            continue; /* a seam of half 1 that is the image of one of half 0 goes with it */
        if (!(state->alone ? edge_set_alone(s, sets + i)
                           : seg_edge_set_make(layout, &map, i, s->edges, s->edge_count, sets + i)))
            status = nomem(ctx);
        else if (seg_leaves_stub(layout, sets + i))
            continue;
        else if (!merged_panels_of(layout, state, sets + i, &panels, &panel_count, &panel_capacity))
            status = nomem(ctx);
    }
    first[segments.count] = panel_count;
    /* The most promising trials first; more when none of them is valid, until every trial was tried. */
    int32_t best = -1;
    merge_trial best_trial;
    memset(&best_trial, 0, sizeof best_trial);
    for (int32_t most = state->most_trials; !status && best < 0; most += state->most_trials) {
        int more = 0;
        for (int32_t i = 0; i < panel_count; ++i)
            panels[i].skipped = 0;
        if (state->most_trials > 0 && !keep_promising(layout, panels, first, segments.count, most))
            status = nomem(ctx);
        for (int32_t i = 0; i < panel_count; ++i)
            more |= panels[i].skipped;
        if (!status)
            status = pz_check_cancel(ctx, "segment");
        if (!status)
            status = flatten_unknown(layout, state, panels, panel_count, ctx);
        for (int32_t i = 0; i < segments.count && !status; ++i) {
            merge_trial trial;
            judge_trial(layout, state, panels, first[i], first[i + 1], skip, &trial);
            if (trial.valid && (best < 0 || better(&trial, &best_trial)))
                best = i, best_trial = trial;
        }
        if (!more || state->most_trials <= 0)
            break;
    }
    if (!status && best >= 0) {
        seg_edge_set_apply(layout, sets + best, 0);
        status = seg_label_panels(layout, ctx);
        /* The merged panels' figures are known: put them in place of an evaluation. */
        for (int32_t i = first[best]; i < first[best + 1] && !status; ++i) {
            int32_t p = layout->face_panel[panels[i].faces[0]];
            layout->panel_goals[p] = panels[i].figures.goals;
            layout->panel_evaluated[p] = 1;
            seg_panel_shape(layout, p);
        }
        if (!status)
            status = evaluate_from_memo(layout, state, ctx);
        *merged = 1;
        *chosen = best_trial;
    }
    for (int32_t i = 0; i < panel_count; ++i)
        free(panels[i].faces);
    free(panels);
    for (int32_t i = 0; sets && i < segments.count; ++i)
        free(sets[i].edges);
    free(sets);
    free(first);
    free(skip);
    seg_mirror_map_free(&map);
    seg_segments_clear(&segments);
    return status;
}

static void state_free(budget_state *state)
{
    free(state->memo.slots);
    free(state->in_group);
    free(state->edges);
    for (int t = 0; state->cuts && t < state->threads; ++t)
        free(state->cuts[t]);
    free(state->cuts);
}

static pz_status state_init(seg_layout *layout, budget_state *state, pz_ctx *ctx)
{
    memset(state, 0, sizeof *state);
    state->threads = layout->threads;
    state->in_group = calloc((size_t)layout->topology->face_count + 1, 1);
    state->edges = calloc((size_t)layout->topology->edge_count + 1, sizeof(int32_t));
    state->cuts = calloc((size_t)state->threads, sizeof *state->cuts);
    int ok = state->in_group && state->edges && state->cuts;
    for (int t = 0; ok && t < state->threads; ++t)
        ok = (state->cuts[t] = malloc((size_t)layout->topology->edge_count + 1)) != NULL;
    if (!ok) {
        state_free(state);
        return nomem(ctx);
    }
    return PZ_OK;
}

/*
 * Lifts S's verdict (strain judged for the report only) and, for the budget, the corner bound (every disk
 * flattened), and evaluates the current panels under them: the cache key carries the bound
 * (segment/evaluate.c), so these evaluations never mix with the goal-bound ones.
 */
static pz_status lift_goals(seg_layout *layout, int lift_corners, pz_ctx *ctx)
{
    if (lift_corners)
        layout->goals.max_corners = BUDGET_CORNERS;
    layout->accept_strain = INFINITY;
    pz_status status = seg_label_panels(layout, ctx);
    if (!status) {
        memset(layout->panel_evaluated, 0, (size_t)layout->panel_count + 1);
        status = seg_evaluate_panels(layout, NULL, ctx);
    }
    return status;
}

/*
 * Merges while the panels exceed `pieces` and the worst strain stays within `stop_strain`; record (may be
 * NULL) gets the layout after each merge.
 */
static pz_status merge_down(seg_layout *layout, int32_t pieces, double stop_strain, int32_t most_trials,
                            int32_t max_corners, pz_segment_tradeoff *record, int32_t *unmirrored, pz_ctx *ctx)
{
    budget_state state;
    pz_status status = state_init(layout, &state, ctx);
    state.most_trials = most_trials;
    state.max_corners = max_corners;
    if (!status)
        status = evaluate_from_memo(layout, &state, ctx); /* the current panels, kept */
    while (!status && layout->panel_count > pieces) {
        int32_t merged = 0;
        merge_trial chosen;
        memset(&chosen, 0, sizeof chosen);
        status = merge_step(layout, &state, &merged, &chosen, ctx);
        /* The budget merges mirror pairs of seams while it can (a mirror pair is one pattern piece cut
         * twice); when none is left, one seam alone (a tube opened by one seam is no mirror image of itself
         * unless the seam lies on the plane): the designer's count comes first. Such merges are counted
         * (*unmirrored): the layout is no longer symmetric, and panelize run then keeps the layout without
         * the plane (pipeline/segmentation.c, choose_symmetry). */
        if (!status && !merged && layout->symmetry.found && !state.alone && record == NULL) {
            state.alone = 1;
            status = merge_step(layout, &state, &merged, &chosen, ctx);
        }
        if (status || !merged)
            break;
        if (state.alone && unmirrored)
            ++*unmirrored;
        if (record && record->count < PZ_TRADEOFF_STEPS) {
            record->pieces[record->count] = layout->panel_count;
            record->worst_strain[record->count] = chosen.worst;
            ++record->count;
        }
        seg_progress(layout, "budget", ctx);
        if (chosen.worst > stop_strain)
            break;
    }
    state_free(&state);
    return status;
}

pz_status seg_budget_merge(seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    int32_t budget = layout->options->max_pieces;
    result->max_pieces = budget;
    result->budget_met = 1;
    if (budget <= 0)
        return PZ_OK;
    pz_status status = seg_label_panels(layout, ctx);
    if (status || layout->panel_count <= budget)
        return status;
    int32_t before = layout->panel_count;
    status = lift_goals(layout, 1, ctx);
    if (!status)
        status = merge_down(layout, budget, INFINITY, 0, 0, NULL, &result->budget_unmirrored, ctx);
    result->budget_merges = before - layout->panel_count;
    result->budget_met = !status && layout->panel_count <= budget;
    return status;
}

pz_status seg_merge_sequence(seg_layout *layout, double stop_strain, pz_segment_tradeoff *out, pz_ctx *ctx)
{
    int32_t max_corners = layout->goals.max_corners;
    /* The trade-off keeps the corner bound: a merged panel over it is not even flattened. */
    pz_status status = lift_goals(layout, 0, ctx);
    if (status)
        return status;
    double worst;
    int32_t bands;
    layout_figures(layout, NULL, &worst, &bands);
    out->count = 1;
    out->pieces[0] = layout->panel_count;
    out->worst_strain[0] = worst;
    return merge_down(layout, 1, stop_strain, TRADEOFF_TRIALS, max_corners, out, NULL, ctx);
}
