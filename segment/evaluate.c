/*
 * segment/evaluate.c -- the goals of the layout's panels: each panel of the
 * current labelling (segment/labels.c) is evaluated by pz_segment_goals'
 * private form (seg_goals, segment/goals.c) unless the evaluation cache
 * already holds it, and the layout's own verdicts (strain margin, vetoes)
 * are added. Also the progress reports of the layout's steps.
 *
 * Separate from segment/layout.c because it is the one place that flattens
 * panels (in parallel, OpenMP) and the one owner of the cache's layout: an
 * evaluation is cached under a 64-bit hash of the panel's faces and of the
 * neighbour seen across each of its outline edges (the corners depend on
 * it), so a panel that a step did not touch is never flattened again. The
 * results are written by panel index, so nothing depends on the thread
 * count.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/*
 * Panels to evaluate with fewer faces than this in all are flattened on one
 * thread: waking a second thread costs more than they do when the cores are
 * shared (the wetsuit of ../shared/data, ~1,100 evaluations of small panels:
 * 4.5 s with 2 threads, 0.85 s with 1 at load 7.6; docs/segment.md).
 */
#define PARALLEL_MIN_FACES 4000

static pz_status nomem(pz_ctx *ctx)
{
    return pz_error(ctx, PZ_ERR_NOMEM, "segment: out of memory");
}

static uint64_t mix(uint64_t hash, uint64_t value)
{
    /* splitmix64 finalizer over the running hash: cheap and well spread. */
    uint64_t z = hash ^ (value + 0x9e3779b97f4a7c15ull + (hash << 6) + (hash >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

uint64_t pz_segment_face_set_key(const int32_t *faces, int32_t count)
{
    uint64_t hash = mix(0xfacade, (uint64_t)count);
    for (int32_t i = 0; i < count; ++i)
        hash = mix(hash, (uint64_t)faces[i]);
    return hash ? hash : 1;
}

/* 1 when panel p's face set is one of the caller's vetoed panels (a short list: linear scan). */
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

/* What the layout adds to an evaluation (cached as evaluated): the strain margin and the vetoes. */
static void layout_verdicts(const seg_layout *layout, int32_t p, pz_goal_result *goals)
{
    if (goals->max_abs_strain >= 0 && goals->max_abs_strain > layout->accept_strain)
        goals->failures |= PZ_GOAL_STRAIN;
    if (panel_vetoed(layout, p))
        goals->failures |= PZ_GOAL_VETOED;
}

/* Cache key of panel p: the corner bound (above it a panel is not flattened: the piece budget lifts it,
 * segment/budget.c), its faces and, for every outline edge, the first face of the panel across. */
static uint64_t panel_key(const seg_layout *layout, int32_t p)
{
    const pz_topology *t = layout->topology;
    uint64_t hash = mix(mix(0x5eed, (uint64_t)layout->goals.max_corners),
                        (uint64_t)(layout->panel_offsets[p + 1] - layout->panel_offsets[p]));
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

/* One evaluation; a failed flattening (not out of memory, not cancelled) counts as a panel that is not
 * injective. The flattening sees the caller's cancel flag (`parent`: read only, this runs in parallel). */
static pz_status evaluate_one(const seg_layout *layout, int32_t p, seg_goal_scratch *scratch, pz_goal_result *out,
                              const pz_ctx *parent)
{
    pz_ctx local;
    pz_ctx_quiet(parent, &local);
    const int32_t *faces = layout->panel_faces + layout->panel_offsets[p];
    int32_t count = layout->panel_offsets[p + 1] - layout->panel_offsets[p];
    pz_status status = seg_goals(layout->mesh, layout->topology, layout->edge_cut, layout->face_panel, faces, count,
                                 &layout->goals, scratch, out, &local);
    if (status && status != PZ_ERR_NOMEM && status != PZ_ERR_CANCELLED) {
        memset(out, 0, sizeof *out);
        out->failures = PZ_GOAL_NOT_INJECTIVE;
        out->max_abs_strain = -1;
        out->min_dart_opening_deg = -1;
        out->min_width_mm = out->area_share = out->across_grain_mm = out->min_dart_intake_mm = -1;
        out->boundary_loops = 1;
        status = PZ_OK;
    }
    return status;
}

pz_status seg_evaluate_panels(seg_layout *layout, const uint8_t *want, pz_ctx *ctx)
{
    pz_status cancelled = pz_check_cancel(ctx, "segment");
    if (cancelled)
        return cancelled;
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
            seg_panel_shape(layout, p);
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
        /* Once cancelled, the evaluations left are skipped (the flag is only read here; the error is
         * recorded after the parallel loop). */
        if (pz_cancelled(ctx)) {
            statuses[i] = PZ_ERR_CANCELLED;
            continue;
        }
        /* Flattening and metrics open parallel regions of their own; inside an inactive region (one
         * thread or one miss) they would wake every core for each small panel. This sets the
         * thread count of this implicit task only. */
        omp_set_num_threads(1);
        statuses[i] = evaluate_one(layout, miss[i], layout->goal_scratch[omp_get_thread_num()],
                                   layout->panel_goals + miss[i], ctx);
    }
    for (int32_t i = 0; i < misses && !status; ++i) {
        if (statuses[i] == PZ_ERR_CANCELLED)
            status = pz_error(ctx, PZ_ERR_CANCELLED, "segment: cancelled"); /* nothing of it is cached */
        else if (statuses[i])
            status = nomem(ctx);
        else {
            /* Stored as evaluated: the vetoes may change from call to call, the evaluation does not. */
            status = cache_store(layout->cache, keys[miss[i]], layout->panel_goals + miss[i], ctx);
            layout_verdicts(layout, miss[i], &layout->panel_goals[miss[i]]);
        }
        layout->panel_evaluated[miss[i]] = 1;
        seg_panel_shape(layout, miss[i]);
    }
    layout->evaluation_count += misses;
    layout->evaluated_faces += miss_faces;
    free(statuses);
    free(miss);
    free(keys);
    return status;
}

/*
 * ctx->progress gets the fraction of the whole pz_segment call: the stages are parts of it (seg_progress_part
 * sets where the current one ends), and as the steps of a stage are not counted in advance, each step goes a
 * twentieth of the way to the part's end. The fraction never decreases.
 */
void seg_progress(seg_layout *layout, const char *stage, pz_ctx *ctx)
{
    int report = ctx && ctx->progress && !ctx->quiet;
    if (!layout->options->on_progress && !report)
        return;
    double worst = 0;
    for (int32_t p = 0; p < layout->panel_count; ++p)
        if (layout->panel_evaluated[p])
            worst = fmax(worst, layout->panel_goals[p].max_abs_strain);
    if (layout->options->on_progress)
        layout->options->on_progress(layout->options->user, stage, layout->panel_count, worst);
    layout->progress += (layout->progress_limit - layout->progress) / 20;
    if (!pz_cancelled(ctx)) /* on_progress may just have asked to stop: the run ends at the next check */
        pz_progress(ctx, "segment", layout->progress, "%s: %d panels, worst strain %.3f", stage,
                    (int)layout->panel_count, worst);
}

void seg_progress_part(seg_layout *layout, double limit, const char *stage, pz_ctx *ctx)
{
    if (layout->progress < layout->progress_limit)
        layout->progress = layout->progress_limit; /* the part before is done */
    layout->progress_limit = limit;
    pz_progress(ctx, "segment", layout->progress, "%s", stage);
}
