/*
 * segment/layout.c -- the automatic patch layout of pietroni2022 Sec. 4.2:
 * greedy insertion of field-aligned paths until every panel meets its
 * goals, recursion into the panels that still fail, then removal of
 * redundant segments and darts. This file sets the layout up, runs its
 * stages in order (pz_segment) and makes the result; the stages are:
 *  - segment/insert.c: sketches, seeded cuts, greedy insertion, recursion;
 *  - segment/fallback.c: the cut through a failing panel's worst vertex;
 *  - segment/removal.c: segments, removal and darts;
 * on the shared state of segment/internal.h, with segment/labels.c (the
 * panels of the current cuts) and segment/evaluate.c (their goals, cached).
 *
 * The layout is a set of cut-edge flags; panels are the face components
 * across uncut edges, numbered in order of their first face. Every step
 * changes a few flags, relabels the panels (flooding only the panels next to
 * the changed edges, then renumbering: seg_label_panels) and evaluates the
 * panels whose goals are not known yet (seg_evaluate_panels, from the cache
 * when it can), so a panel that a step did not touch is never flattened
 * again.
 *
 * Progress and cancellation: every step reports through
 * pz_segment_options.on_progress and ctx->progress (stage "segment"), and the
 * cancel flag (pz_ctx.cancel) is checked between stages and steps, never
 * inside a parallel region; a cancelled call frees everything and returns
 * PZ_ERR_CANCELLED with *out NULL.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "segment/internal.h"
#include "core/vec.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_MAX_CANDIDATES 96
#define DEFAULT_MAX_DEPTH 2

/* ---------------------------------------------------------------- helpers */

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

/* ---------------------------------------------------------------- removal and darts */

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
    double start = pz_seconds();
    if (!status)
        status = seg_merge_slivers(layout, &result->merged_slivers, ctx);
    result->remove_ms += 1e3 * (pz_seconds() - start);
    return status;
}

/* ---------------------------------------------------------------- result */

/* Mirror panel of each panel (segment/mirror.c). */
static pz_status mirror_panels(const seg_layout *layout, pz_segment_result *result, pz_ctx *ctx)
{
    int32_t *mirror = malloc(((size_t)result->panel_count + 1) * sizeof(int32_t));
    if (!mirror)
        return nomem(ctx);
    pz_status status = seg_mirror_panels(layout, mirror, ctx);
    for (int32_t p = 0; p < result->panel_count; ++p)
        result->panels[p].mirror_panel = status ? -1 : mirror[p];
    free(mirror);
    return status;
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
        double d = pz_vec3_dot(s->normal, p) - s->offset;
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
        panel->copy = seg_pair_goals(layout, p, &panel->goals); /* a mirror pair is judged as one piece */
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
    pz_goal_options goals; /* the goals' defaults are defined once, in goals.c */
    pz_goal_options_default(&goals);
    options->max_corners = goals.max_corners;
    options->max_strain = goals.max_strain;
    options->min_piece_width_mm = goals.min_piece_width_mm;
    options->min_piece_area = goals.min_piece_area;
    options->max_piece_width_mm = goals.max_piece_width_mm;
    options->min_dart_intake_mm = goals.min_dart_intake_mm;
    options->symmetry = PZ_SYMMETRY_AUTO;
    options->darts = 1;
    options->grain[2] = 1;
}

static void layout_free(seg_layout *layout)
{
    if (layout->graph_borrowed)
        layout->graph = NULL;
    pz_trace_graph_free(&layout->graph);
    pz_symmetry_clear(&layout->symmetry);
    seg_mirror_free(layout);
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
    free(layout->panel_shape);
    seg_frame_clear(&layout->frame);
    free(layout->own_cache.entries);
    for (int32_t t = 0; layout->goal_scratch && t < layout->threads; ++t)
        seg_goal_scratch_free(layout->goal_scratch[t]);
    free(layout->goal_scratch);
}

static pz_status check_options(const pz_segment_options *options, pz_ctx *ctx)
{
    if (!(options->strain_margin >= 0 && options->strain_margin <= 0.9))
        return pz_error(ctx, PZ_ERR_USAGE, "segment: strain margin %g is not within 0 .. 0.9", options->strain_margin);
    if (!(options->max_strain >= 0) || options->max_corners < 0 || options->max_candidates < 0 || options->max_pieces < 0 ||
        options->max_depth < 0 || options->threads < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: negative strain, corner, candidate, depth or thread option");
    if (!(options->min_piece_width_mm >= 0) || !(options->min_piece_area >= 0 && options->min_piece_area < 1) ||
        !(options->max_piece_width_mm >= 0) || !(options->min_dart_intake_mm >= 0))
        return pz_error(ctx, PZ_ERR_USAGE, "segment: a piece-shape goal is negative (or an area share not below 1)");
    double g = pz_vec3_norm(options->grain);
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
    pz_goal_options defaults;
    pz_goal_options_default(&defaults);
    layout->goals.max_corners = options->max_corners > 0 ? options->max_corners : defaults.max_corners;
    layout->goals.max_strain = options->max_strain;
    layout->goals.min_piece_width_mm = options->min_piece_width_mm;
    layout->goals.min_piece_area = options->min_piece_area;
    layout->goals.max_piece_width_mm = options->max_piece_width_mm;
    layout->goals.min_dart_intake_mm = options->min_dart_intake_mm;
    layout->accept_strain = (1 - options->strain_margin) * options->max_strain;
    double g = pz_vec3_norm(options->grain);
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

/* The plane, from the options (pz_symmetry_detect: AUTO uses it when the garment lies within 1.5 % of its
 * bounding-box diagonal of its mirror image; a given axis or plane is always used). */
static pz_status detect_symmetry(seg_layout *layout, pz_ctx *ctx)
{
    return pz_symmetry_detect(layout->mesh, layout->topology, layout->options->symmetry, layout->options->symmetry_plane,
                              0, &layout->symmetry, ctx);
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
    if (!status)
        status = pz_check_cancel(ctx, "segment");
    if (status)
        return status;
    double start = pz_seconds();
    pz_segment_result *result = calloc(1, sizeof *result);
    seg_layout layout;
    memset(&layout, 0, sizeof layout);
    if (!result)
        return nomem(ctx);
    status = layout_init(&layout, mesh, topology, field, options, ctx);
    /* The parts of the run for ctx->progress, as shares of the time: the graph and candidates take a few per
     * cent, insertion and removal with darts each a third to two thirds (the shared garments' report.json). */
    if (!status) {
        seg_progress_part(&layout, 0.05, "trace graph", ctx);
        if (options->prebuilt_graph) {
            if (options->prebuilt_graph->vertex_count != mesh->vertex_count)
                status = pz_error(ctx, PZ_ERR_USAGE, "segment: a prebuilt graph of another mesh");
            layout.graph = (pz_trace_graph *)options->prebuilt_graph; /* read only here, never freed */
            layout.graph_borrowed = 1;
        } else
            status = pz_trace_graph_build(mesh, topology, field->directions, &options->graph, &layout.graph, ctx);
    }
    if (!status && !(status = pz_check_cancel(ctx, "segment")))
        status = detect_symmetry(&layout, ctx);
    if (!status)
        status = seg_frame_init(&layout, ctx);
    result->graph_ms = 1e3 * (pz_seconds() - start);
    if (!status && !(status = pz_check_cancel(ctx, "segment")))
        status = seg_insert_sketches(&layout, ctx);
    if (!status)
        status = seg_insert_seeds(&layout, ctx);
    if (!status) /* after the sketches and seeds: an edge of theirs on the plane stays theirs, never removed */
        status = seg_plane_cut(&layout, ctx);
    if (!status)
        status = seg_label_panels(&layout, ctx);
    if (!status) {
        seg_progress_part(&layout, 0.4, "insert", ctx);
        status = seg_insert_all(&layout, result, ctx);
    }
    result->inserted_count = layout.path_count;
    result->removed_count = layout.removed_early;
    result->stopped_unsound = layout.stopped_unsound;
    if (!status && !layout.stopped_unsound) {
        seg_progress_part(&layout, 0.97, "remove", ctx);
        status = remove_and_dart(&layout, result, ctx);
    }
    if (!status) {
        double budget_start = pz_seconds();
        status = seg_budget_merge(&layout, result, ctx);
        result->budget_ms = 1e3 * (pz_seconds() - budget_start);
    }
    if (!status) {
        seg_progress_part(&layout, 1.0, "result", ctx);
        status = fill_result(&layout, result, ctx);
    }
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
    pz_progress(ctx, "segment", 1.0, "%d panels%s", (int)result->panel_count,
                result->goals_met ? "" : ", goals not met");
    *out = result;
    return PZ_OK;
}

pz_status pz_segment_merge_sequence(const pz_mesh *mesh, const pz_topology *topology,
                                    const pz_segment_options *options, const uint8_t *edge_cut, double stop_strain,
                                    pz_segment_tradeoff *out, pz_ctx *ctx)
{
    if (!mesh || !topology || !options || !edge_cut || !out)
        return pz_error(ctx, PZ_ERR_USAGE, "segment: merge sequence without a mesh, options, cuts or output");
    memset(out, 0, sizeof *out);
    pz_status status = check_options(options, ctx);
    if (status)
        return status;
    double start = pz_seconds();
    seg_layout layout;
    memset(&layout, 0, sizeof layout);
    status = layout_init(&layout, mesh, topology, NULL, options, ctx);
    if (!status)
        status = detect_symmetry(&layout, ctx);
    if (!status)
        status = seg_frame_init(&layout, ctx);
    if (!status)
        status = seg_insert_seeds(&layout, ctx);
    for (int32_t e = 0; !status && e < topology->edge_count; ++e)
        layout.edge_cut[e] |= edge_cut[e] != 0;
    if (!status)
        status = seg_label_panels(&layout, ctx);
    if (!status)
        status = seg_merge_sequence(&layout, stop_strain, out, ctx);
    layout_free(&layout);
    out->ms = 1e3 * (pz_seconds() - start);
    return status;
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
