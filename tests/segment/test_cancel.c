/*
 * tests/segment/test_cancel.c -- cancellation and progress of the
 * segmentation (pz_segment) and of the cross-field (pz_field_compute),
 * through pz_ctx.cancel and pz_ctx.progress, on the generated bodice (about
 * 3,000 faces, at S = 0.04 where it gets darts as in test_segment.c):
 *  - the cancel flag set before the call: PZ_ERR_CANCELLED, *out NULL, the
 *    message says "cancelled", for both calls;
 *  - an uncancelled run reports progress through ctx->progress with stage
 *    "segment", fractions within 0..1 that never decrease, the last 1, and
 *    through options->on_progress at its own stages;
 *  - the flag set from the progress callback: after the first report of
 *    ctx->progress, and after the first report of each stage that
 *    options->on_progress reported in the uncancelled run (candidates,
 *    insert, remove, darts): PZ_ERR_CANCELLED, *out NULL, no report after
 *    the flag was set, so every loop of the layout checks it between steps;
 *    the time from the flag to the return is printed. Under ASan (the
 *    sanitizer run of scripts/test.sh) LeakSanitizer checks that a cancelled
 *    run frees everything;
 *  - a run cancelled with a shared evaluation cache leaves the cache usable:
 *    a later run with that cache gives the same layout as a fresh run.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "generate/generate.h"
#include "segment/segment.h"
#include "test_meshes.h"

#include <stdlib.h>
#include <string.h>

static pz_ctx ctx;

/* What *out holds before each call: pz_segment must set it to NULL when it fails. */
static pz_segment_result not_written;

static void release(pz_segment_result **result)
{
    if (*result != &not_written)
        pz_segment_result_free(result);
}

/* What the callbacks saw; `cancel` is the flag ctx.cancel points at. */
typedef struct watch {
    int cancel;
    const char *cancel_at;   /* on_progress: set the flag at the first report of this stage (NULL: never) */
    int cancel_at_context;   /* ctx->progress: set the flag at its first report */
    int reports, reports_after_cancel;
    double cancelled_at;     /* pz_seconds() when the flag was set */
    char stages[8][16];      /* the distinct on_progress stages, in order */
    int stage_count;
    double last_fraction;
    int fraction_reports, fractions_decreasing, fractions_outside;
} watch;

static void on_progress(void *user, const char *stage, int32_t panel_count, double worst_strain)
{
    (void)panel_count, (void)worst_strain;
    watch *w = user;
    ++w->reports;
    if (w->cancel) {
        ++w->reports_after_cancel;
        return;
    }
    int seen = 0;
    for (int i = 0; i < w->stage_count; ++i)
        seen |= strcmp(w->stages[i], stage) == 0;
    if (!seen && w->stage_count < 8)
        snprintf(w->stages[w->stage_count++], sizeof w->stages[0], "%s", stage);
    if (w->cancel_at && strcmp(stage, w->cancel_at) == 0) {
        w->cancel = 1;
        w->cancelled_at = pz_seconds();
    }
}

static void on_context_progress(void *user, const char *stage, double fraction, const char *message)
{
    (void)message;
    watch *w = user;
    if (w->cancel) {
        ++w->reports_after_cancel;
        return;
    }
    w->fractions_outside += strcmp(stage, "segment") != 0 || !(fraction >= 0 && fraction <= 1);
    w->fractions_decreasing += w->fraction_reports > 0 && fraction < w->last_fraction;
    w->last_fraction = fraction;
    ++w->fraction_reports;
    if (w->cancel_at_context) {
        w->cancel = 1;
        w->cancelled_at = pz_seconds();
    }
}

typedef struct garment {
    pz_mesh *mesh;
    pz_topology *topology;
    pz_field *field;
} garment;

static garment bodice(void)
{
    pz_generate_options options = {3000, 0, 0};
    garment g = {NULL, NULL, NULL};
    REQUIRE_OK(pz_generate(PZ_SHAPE_BODICE, &options, &g.mesh, &ctx), ctx);
    g.topology = test_topology(g.mesh, &ctx);
    REQUIRE_OK(pz_field_compute(g.mesh, g.topology, NULL, &g.field, &ctx), ctx);
    return g;
}

/* pz_segment with the callbacks of `w` (its flag as ctx's cancel flag) and an optional shared cache. */
static pz_status segment(const garment *g, watch *w, pz_segment_cache *cache, pz_segment_result **out, pz_ctx *run)
{
    pz_ctx_init(run);
    run->quiet = 0;
    run->progress = on_context_progress;
    run->progress_user = w;
    run->cancel = &w->cancel;
    pz_segment_options options;
    pz_segment_options_default(&options);
    options.max_strain = 0.04; /* the bodice gets darts (test_segment.c): every stage of the layout runs */
    options.on_progress = on_progress;
    options.user = w;
    options.cache = cache;
    *out = &not_written;
    return pz_segment(g->mesh, g->topology, g->field, &options, out, run);
}

static void test_cancelled_before(const garment *g)
{
    watch w;
    memset(&w, 0, sizeof w);
    w.cancel = 1;
    pz_ctx run;
    pz_segment_result *result = NULL;
    pz_status status = segment(g, &w, NULL, &result, &run);
    CHECK(status == PZ_ERR_CANCELLED && result == NULL, "segment, flag set before: status %d, result %p", status,
          (void *)result);
    CHECK(strstr(run.error, "cancelled") != NULL, "segment: message '%s'", run.error);
    CHECK(w.reports_after_cancel == 0, "segment, flag set before: %d progress reports", w.reports_after_cancel);
    release(&result);

    pz_field *field = (pz_field *)g->field; /* not NULL: pz_field_compute must reset it */
    pz_ctx field_ctx;
    pz_ctx_init(&field_ctx);
    field_ctx.quiet = 1;
    field_ctx.cancel = &w.cancel;
    status = pz_field_compute(g->mesh, g->topology, NULL, &field, &field_ctx);
    CHECK(status == PZ_ERR_CANCELLED && field == NULL, "field, flag set before: status %d, field %p", status,
          (void *)field);
    CHECK(strstr(field_ctx.error, "field: cancelled") != NULL, "field: message '%s'", field_ctx.error);
}

/* The uncancelled run: its on_progress stages into *stages, and the context's fractions checked. */
static pz_segment_result *test_progress(const garment *g, watch *w)
{
    memset(w, 0, sizeof *w);
    pz_ctx run;
    pz_segment_result *result = NULL;
    REQUIRE_OK(segment(g, w, NULL, &result, &run), run);
    printf("uncancelled: %d panels, %d on_progress reports, %d context reports, stages:", (int)result->panel_count,
           w->reports, w->fraction_reports);
    for (int i = 0; i < w->stage_count; ++i)
        printf(" %s", w->stages[i]);
    printf("\n");
    CHECK(w->fraction_reports >= w->reports && w->fraction_reports > 2, "%d context reports, %d on_progress",
          w->fraction_reports, w->reports);
    CHECK(w->fractions_decreasing == 0 && w->fractions_outside == 0,
          "context progress: %d decreasing fractions, %d outside 0..1 or not 'segment'", w->fractions_decreasing,
          w->fractions_outside);
    CHECK(w->last_fraction == 1.0, "context progress ends at %g", w->last_fraction);
    REQUIRE(w->stage_count >= 3 && strcmp(w->stages[0], "candidates") == 0,
            "expected candidates, insert, remove or darts reports, got %d stages", w->stage_count);
    return result;
}

/* Cancels at the first report of `stage` (NULL: at the context's first report). */
static void test_cancel_at(const garment *g, const char *stage)
{
    watch w;
    memset(&w, 0, sizeof w);
    w.cancel_at = stage;
    w.cancel_at_context = stage == NULL;
    pz_ctx run;
    pz_segment_result *result = NULL;
    pz_status status = segment(g, &w, NULL, &result, &run);
    double seconds = pz_seconds() - w.cancelled_at;
    const char *label = stage ? stage : "the context's first report";
    printf("cancelled at %s: status %d (%s), returned %.3f s after the flag\n", label, status, run.error, seconds);
    CHECK(w.cancel, "%s: never reported, so never cancelled", label);
    CHECK(status == PZ_ERR_CANCELLED && result == NULL, "cancelled at %s: status %d, result %p", label, status,
          (void *)result);
    CHECK(strcmp(run.error, "segment: cancelled") == 0, "cancelled at %s: message '%s'", label, run.error);
    CHECK(w.reports_after_cancel == 0, "cancelled at %s: %d reports after the flag", label, w.reports_after_cancel);
    release(&result);
}

static int same_layout(const pz_segment_result *a, const pz_segment_result *b)
{
    return a->panel_count == b->panel_count && a->face_count == b->face_count && a->edge_count == b->edge_count &&
           memcmp(a->face_panel, b->face_panel, (size_t)a->face_count * sizeof(int32_t)) == 0 &&
           memcmp(a->edge_cut, b->edge_cut, (size_t)a->edge_count) == 0;
}

static void test_cache_after_cancel(const garment *g, const pz_segment_result *fresh, const char *stage)
{
    pz_segment_cache *cache = pz_segment_cache_create();
    REQUIRE(cache, "out of memory");
    watch w;
    memset(&w, 0, sizeof w);
    w.cancel_at = stage;
    pz_ctx run;
    pz_segment_result *result = NULL;
    CHECK(segment(g, &w, cache, &result, &run) == PZ_ERR_CANCELLED && result == NULL, "cache run: not cancelled");
    release(&result);
    memset(&w, 0, sizeof w);
    REQUIRE_OK(segment(g, &w, cache, &result, &run), run);
    CHECK(same_layout(result, fresh), "after a run cancelled at %s, the cache gives another layout (%d panels, %d fresh)",
          stage, (int)result->panel_count, (int)fresh->panel_count);
    CHECK(result->evaluation_count < fresh->evaluation_count, "the cache was not used: %d evaluations, %d fresh",
          (int)result->evaluation_count, (int)fresh->evaluation_count);
    pz_segment_result_free(&result);
    pz_segment_cache_free(&cache);
}

int main(void)
{
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    garment g = bodice();
    test_cancelled_before(&g);
    watch stages;
    pz_segment_result *fresh = test_progress(&g, &stages);
    test_cancel_at(&g, NULL);
    for (int i = 0; i < stages.stage_count; ++i)
        test_cancel_at(&g, stages.stages[i]);
    test_cache_after_cancel(&g, fresh, stages.stages[stages.stage_count - 1]);
    pz_segment_result_free(&fresh);
    pz_field_free(&g.field);
    pz_topology_free(&g.topology);
    pz_mesh_free(&g.mesh);
    return test_finish();
}
