/*
 * pipeline/pipeline.c -- pz_run and pz_flatten: the stages in order.
 *
 *   load (load.c) -> panels: the segmentation (segmentation.c: field,
 *   layout, truing) or the user's panels (panels.c) -> pattern
 *   (pz_pattern_build) -> flatten (flatten.c) -> [verdict round: the
 *   segmentation may veto panels and lay out again] -> layout of the pieces
 *   -> metrics on every pose -> the final verdict (verdict.c) -> mirror
 *   pairs, layout curves -> pieces and marker (export/).
 *
 * Data flows one way: each stage takes the previous stage's result; the
 * result owns everything it holds. Nothing is written here (write.c).
 *
 * Progress: prepare 0-10 %, field 10-20 %, segment 20-70 %, flatten 70-90 %,
 * pieces and marker 90-100 % (pz_progress through the context).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "pipeline/internal.h"
#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pl_stage(pz_ctx *ctx, const char *stage, double from, double to, const char *message)
{
    pz_progress_range(ctx, 0, 0);
    pz_progress(ctx, stage, from, "%s", message);
    pz_progress_range(ctx, from, to);
}

const char *pl_who(const pz_result *result)
{
    return result && result->from_run ? "run" : "flatten";
}

/* ---------------------------------------------------------------- options */

void pz_flatten_options_default(pz_flatten_options *options)
{
    memset(options, 0, sizeof *options);
    options->backend = PZ_BACKEND_TEXTILE;
    options->iterations = 20;
    options->weights[0] = 5, options->weights[1] = 1, options->weights[2] = 5, options->weights[3] = 5;
    options->fabric = pz_fabric_default();
}

void pz_run_options_default(pz_run_options *options)
{
    memset(options, 0, sizeof *options);
    options->units = PZ_UNITS_AUTO;
    options->prepare = 1;
    pz_prepare_options_default(&options->prepare_options);
    pz_field_options_default(&options->field);
    pz_goal_options_default(&options->goals);
    pz_segment_options_default(&options->segment);
    options->truing = 1;
    options->consolidate = 1;
    pz_flatten_options_default(&options->flatten);
    pz_export_options_default(&options->output);
}

/* ---------------------------------------------------------------- the result */

void pz_result_free(pz_result **result)
{
    pz_result *r = result ? *result : NULL;
    if (!r)
        return;
    pz_mesh_free(&r->garment);
    free(r->positions_out);
    if (r->panel_names && r->pattern)
        for (int32_t p = 0; p < r->pattern->panel_count; ++p)
            free(r->panel_names[p]);
    free(r->panel_names);
    pz_pattern_free(&r->pattern);
    free(r->uv);
    free(r->panel_grain_turn);
    free(r->panel_mirror);
    free(r->panel_mirror_residual_mm);
    pl_backend_outcome_clear(&r->backend);
    for (int i = 0; r->metrics && i < r->metrics_count; ++i)
        pz_metrics_free(&r->metrics[i]);
    free(r->metrics);
    free(r->verdict.panels);
    free(r->layout_offsets);
    free(r->layout_vertices);
    free(r->layout_is_dart);
    pz_segment_result_free(&r->segment);
    pz_prepare_result_free(&r->prepared);
    free(r->garment_name);
    free(r->seam_allowances);
    pz_pieces_free(&r->pieces);
    pz_marker_free(&r->marker);
    free(r);
    *result = NULL;
}

/* ---------------------------------------------------------------- stages after the flattening */

/*
 * The layout as polylines of garment vertices, from the pattern itself so
 * that given panels and the segmentation look the same: one polyline per
 * seam (its side a) and one per dart (tip, then leg a).
 */
static pz_status build_layout_curves(pz_result *result, pz_ctx *ctx)
{
    const pz_pattern *pattern = result->pattern;
    int64_t total = 0;
    int32_t count = pattern->seam_count + pattern->dart_count;
    for (int32_t s = 0; s < pattern->seam_count; ++s)
        total += pattern->seams[s].pair_count;
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        total += pattern->darts[d].pair_count + 1;
    result->layout_offsets = malloc(((size_t)count + 1) * sizeof(int32_t));
    result->layout_vertices = malloc(((size_t)total + 1) * sizeof(int32_t));
    result->layout_is_dart = calloc((size_t)count + 1, 1);
    if (!result->layout_offsets || !result->layout_vertices || !result->layout_is_dart)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", pl_who(result));
    int32_t at = 0, curve = 0;
    for (int32_t s = 0; s < pattern->seam_count; ++s, ++curve) {
        result->layout_offsets[curve] = at;
        for (int32_t i = 0; i < pattern->seams[s].pair_count; ++i)
            result->layout_vertices[at++] = pattern->vertex_origin[pattern->seams[s].side_a[i]];
    }
    for (int32_t d = 0; d < pattern->dart_count; ++d, ++curve) {
        const pz_dart *dart = &pattern->darts[d];
        result->layout_offsets[curve] = at;
        result->layout_is_dart[curve] = 1;
        result->layout_vertices[at++] = pattern->vertex_origin[dart->tip];
        for (int32_t i = 0; i < dart->pair_count; ++i)
            result->layout_vertices[at++] = pattern->vertex_origin[dart->leg_a[i]];
    }
    result->layout_offsets[count] = at;
    result->layout_curve_count = count;
    return PZ_OK;
}

/* The mirror partner of each panel, from the segmentation's symmetry (NULL: no pairs). */
static pz_status find_mirror_panels(pz_result *result, pz_ctx *ctx)
{
    const pz_segment_result *segment = result->segment;
    if (!segment || segment->panel_count != result->pattern->panel_count || !segment->symmetry.found)
        return PZ_OK;
    result->panel_mirror = malloc(((size_t)segment->panel_count + 1) * sizeof(int32_t));
    if (!result->panel_mirror)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", pl_who(result));
    for (int32_t p = 0; p < segment->panel_count; ++p)
        result->panel_mirror[p] = segment->panels[p].mirror_panel;
    return PZ_OK;
}

/* The pieces (and the marker) every export file is drawn from. */
static pz_status build_pieces(pz_result *result, pz_ctx *ctx)
{
    if (pz_export_file_count == 0)
        return PZ_OK;
    pz_export_options *options = &result->options.output;
    pz_status status = PZ_OK;
    if (result->options.allowances_path) {
        status = pz_export_read_allowances(result->options.allowances_path, result->pattern,
                                           &result->seam_allowances, ctx);
        options->seam_allowances_mm = result->seam_allowances;
    }
    if (status == PZ_OK)
        status = pz_pieces_build(result->pattern, result->uv, options, result->panel_mirror,
                                 (const char *const *)result->panel_names, &result->pieces, ctx);
    if (status == PZ_OK && !result->options.defer_extras)
        status = pz_result_complete(result, ctx);
    return status;
}

int pl_result_completed(const pz_result *result)
{
    return !result || ((!result->from_run || result->tradeoff_measured) && (result->marker || !result->pieces));
}

pz_status pz_result_complete(pz_result *result, pz_ctx *ctx)
{
    if (!result)
        return PZ_OK;
    pz_status status = PZ_OK;
    if (result->from_run && !result->tradeoff_measured) {
        status = pl_measure_tradeoff(result, ctx);
        result->tradeoff_measured = status == PZ_OK;
    }
    if (status != PZ_OK || result->marker || !result->pieces)
        return status;
    status = pz_marker_build(result->pieces, &result->options.output, &result->marker, ctx);
    for (int32_t i = 0; status == PZ_OK && i < result->marker->unplaced_count; ++i) {
        const pz_piece *piece = &result->pieces->pieces[result->marker->unplaced[i]];
        pz_note(ctx, "warning: marker: piece %s (%.0f mm wide) does not fit on a fabric %.0f mm wide: left out of "
                "marker.svg (give a wider --fabric-width)", piece->name, piece->bbox_max[0] - piece->bbox_min[0],
                result->marker->fabric_width_mm);
    }
    return status;
}

/* The widest piece the fabric takes across its grain: its width less the allowance on both sides (a cut
 * piece lies grain-true on the roll, docs/marker.md). The piece-width goal of a run that sets none. */
static double usable_fabric_width(const pz_export_options *output)
{
    double allowance = fmax(output->seam_allowance_mm, output->hem_allowance_mm);
    return fmax(output->fabric_width_mm - 2 * fmax(allowance, 0), 1);
}

/* ---------------------------------------------------------------- the pipeline */

/* Everything one call holds besides the result. */
typedef struct pipeline_run {
    const pz_panels *panels;         /* the user's panels, or NULL with a segmenter */
    pl_garment garment;
    pl_segmenter *segmenter;         /* pz_run without panels */
    pl_panel_choice choice;
    pz_correspondences correspondences;
    pl_symmetric symmetric;          /* the garment made exactly symmetric (mirror_garment.c) */
    pz_sketch *grain_hints;          /* the designer's grain hints in millimetres (grain_hints.c), or NULL */
} pipeline_run;

static void pipeline_run_clear(pipeline_run *run)
{
    pl_garment_clear(&run->garment);
    pl_segmenter_free(&run->segmenter);
    pl_panel_choice_clear(&run->choice);
    pz_correspondences_clear(&run->correspondences);
    pl_symmetric_clear(&run->symmetric);
    pz_sketch_free(&run->grain_hints);
}

/* The panels for this round: the segmentation's (its vertices may move: seam truing, and garment.obj's
 * positions of the moved vertices follow, the others keep the input's exact numbers), or the user's. */
static pz_status choose_panels(pipeline_run *run, pz_result *result, int round, pz_ctx *ctx)
{
    pz_mesh *mesh = run->garment.mesh;
    if (!run->segmenter) {
        pz_status status = pl_user_panels(run->panels, &run->garment, result, &run->choice, ctx);
        if (status == PZ_OK && round == 0)
            status = pl_user_correspondences(run->panels, &run->garment, run->choice.panel_count,
                                             &run->correspondences, ctx);
        return status;
    }
    size_t size = (size_t)mesh->vertex_count * 3;
    double *before = malloc(size * sizeof(double) + 1);
    if (!before)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    memcpy(before, mesh->positions, size * sizeof(double));
    pz_status status = pl_segmenter_choose(run->segmenter, mesh, &run->choice, ctx);
    if (status == PZ_OK && pl_segmenter_plane_used(run->segmenter)) /* trued seams stay exact mirror images */
        pl_symmetric_resettle(&run->symmetric, mesh);
    for (size_t v = 0; status == PZ_OK && v < size / 3; ++v)
        if (memcmp(before + 3 * v, mesh->positions + 3 * v, 3 * sizeof(double)) != 0)
            for (int d = 0; d < 3; ++d)
                result->positions_out[3 * v + d] = mesh->positions[3 * v + d] / mesh->unit_scale;
    free(before);
    return status;
}

/*
 * Whether the layout on the symmetric garment is kept: when it uses the
 * plane, or when the run's S was out of reach and a looser setting's sound
 * layout is written (issue 15: laying the garment out again as loaded would
 * repeat the probe and the looser layouts, about twice the time, for a
 * garment within the snap distance of this one; the report names the
 * symmetrized distance).
 */
static int keeps_symmetric_garment(const pipeline_run *run)
{
    return pl_segmenter_plane_used(run->segmenter) || pl_segmenter_wrote_looser(run->segmenter);
}

/* Panels, pattern and flattening, again while the segmentation's verdict rounds reject the flattening. */
static pz_status flatten_rounds(pipeline_run *run, pz_result *result, pz_ctx *ctx)
{
    const pz_run_options *options = &result->options;
    const char *name = options->name ? options->name : "garment";
    double strain_limit = result->from_run ? options->goals.max_strain : 0;
    pz_status status = PZ_OK;
    double mark, now;
    for (int round = 0; status == PZ_OK; ++round) {
        if (round > 0) {
            pl_backend_outcome_clear(&result->backend);
            free(result->uv);
            result->uv = NULL;
            pz_pattern_free(&result->pattern);
            pl_panel_choice_clear(&run->choice);
        }
        mark = pz_seconds();
        status = choose_panels(run, result, round, ctx);
        result->timings.panels += pz_elapsed_ms(mark, pz_seconds());
        /* The symmetric garment without the plane's layout is not kept: no flattening of it (redo_as_loaded). */
        if (status == PZ_OK && run->symmetric.active && !keeps_symmetric_garment(run))
            return PZ_OK;
        if (status == PZ_OK)
            status = pz_pattern_build(run->garment.mesh, run->choice.face_panel, run->choice.extra_cuts,
                                      &run->correspondences, name, &result->pattern, ctx);
        result->timings.pattern += pz_elapsed_ms(mark, now = pz_seconds()), mark = now;
        if (status == PZ_OK && !(result->uv = calloc(2 * (size_t)result->pattern->mesh->vertex_count + 2,
                                                     sizeof(double))))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", pl_who(result));
        free(result->panel_grain_turn);
        result->panel_grain_turn = NULL;
        if (status == PZ_OK)
            status = pl_panel_grain(result->pattern, result->grain, run->grain_hints,
                                    run->segmenter ? pl_segmenter_layout(run->segmenter) : NULL,
                                    &result->panel_grain_turn, &result->grain_hinted_panels, ctx);
        if (status == PZ_OK) {
            char message[64];
            snprintf(message, sizeof message, "%d panels", (int)result->pattern->panel_count);
            pl_stage(ctx, "flatten", 0.7, 0.9, message);
            status = pl_flatten_pattern(options, result->pattern, run->garment.mesh->unit_scale, result->grain,
                                        result->panel_grain_turn,
                                        run->segmenter ? pl_segmenter_flatten_strain(run->segmenter, strain_limit)
                                                       : strain_limit,
                                        result->uv, &result->backend, ctx);
        }
        if (status == PZ_OK && run->segmenter) /* mirror pieces exact before the verdict judges them */
            status = pl_segmenter_exact_mirrors(run->segmenter, result->pattern, result->uv, ctx);
        int accepted = 1;
        if (status == PZ_OK && run->segmenter)
            accepted = pl_segmenter_accept(run->segmenter, result->pattern, result->uv, ctx);
        result->timings.flatten += pz_elapsed_ms(mark, now = pz_seconds()), mark = now;
        if (status == PZ_OK && !accepted)
            status = pz_check_cancel(ctx, pl_who(result));
        if (status != PZ_OK || accepted)
            break;
    }
    result->panels_source = run->choice.source;
    return status;
}

/* Layout of the pieces, metrics on every pose, names. */
static pz_status measure(pipeline_run *run, pz_result *result, pz_ctx *ctx)
{
    double mark = pz_seconds(), now;
    pl_warn_wirewarp(&result->options, &result->backend, ctx);  /* once, for the pattern kept */
    pz_status status = pl_pattern_layout(result->pattern, result->uv, PL_LAYOUT_GAP_MM, &result->layout_moved, ctx);
    result->timings.flatten += pz_elapsed_ms(mark, now = pz_seconds()), mark = now;
    if (status == PZ_OK) {
        result->metrics_count = 1 + result->pattern->mesh->pose_count;
        if (!(result->metrics = calloc((size_t)result->metrics_count, sizeof *result->metrics)))
            status = pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", pl_who(result));
    }
    if (status == PZ_OK)
        status = pl_measure(result->pattern, result->uv, &result->options.flatten.fabric, result->metrics,
                            result->metrics_count, ctx);
    result->timings.metrics = pz_elapsed_ms(mark, pz_seconds());
    /* Names belong to the panels as chosen; should the pattern number them otherwise, show none. */
    if (status == PZ_OK && result->pattern->panel_count == run->choice.panel_count) {
        result->panel_names = run->choice.names;
        run->choice.names = NULL;
    }
    return status;
}

/*
 * The symmetric garment was not worth it (its layout does not use the plane,
 * or a piece budget's mirrored layout misses the goals): the garment is given
 * back as loaded and the run made again as it was before symmetrizing (the
 * plane found again, mirrored layouts on the garment as it is), so a run that
 * does not keep the symmetric garment is unchanged.
 */
static pz_status redo_as_loaded(pipeline_run *run, pz_result *result, pz_ctx *ctx)
{
    pz_note(ctx, "run: symmetry: the layout %s: the garment as loaded is laid out again",
            pl_segmenter_plane_used(run->segmenter) ? "made with the plane misses the goals" : "does not use the plane");
    pl_backend_outcome_clear(&result->backend);
    free(result->uv);
    result->uv = NULL;
    pz_pattern_free(&result->pattern);
    pl_panel_choice_clear(&run->choice);
    pl_symmetric_restore(&run->symmetric, result, &run->garment);
    pl_segmenter *first = run->segmenter;
    run->segmenter = NULL;
    pz_status status = pl_segmenter_create(&result->options, result->prepared, result->grain, &run->segmenter, ctx);
    if (status == PZ_OK) /* said once, before the long work: the symmetric garment's outlook stands */
        pl_segmenter_take_outlook(run->segmenter, first);
    if (status == PZ_OK)
        pl_segmenter_give_grain_hints(run->segmenter, run->grain_hints);
    pl_segmenter_free(&first);
    return status == PZ_OK ? flatten_rounds(run, result, ctx) : status;
}

/*
 * The run up to its verdict: load (prepare, symmetrize), the panels (the
 * segmentation's, with its rounds, or the user's), the flattening, the
 * metrics, the final verdict (pz_run) and the layout's curves; *out is the
 * caller's (NULL on error). finish() makes the rest.
 */
static pz_status lay_out(const pz_mesh *mesh, const pz_panels *panels, const pz_run_options *options, int from_run,
                         pz_result **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_result *result = calloc(1, sizeof *result);
    if (!result)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", from_run ? "run" : "flatten");
    result->from_run = from_run;
    if (options)
        result->options = *options;
    else
        pz_run_options_default(&result->options);
    if (from_run && !(result->options.goals.max_piece_width_mm > 0))
        result->options.goals.max_piece_width_mm = usable_fabric_width(&result->options.output);
    pipeline_run run;
    memset(&run, 0, sizeof run);
    run.panels = panels;
    int segment = from_run && !panels;
    /* Progress: this call's stages share the whole 0..1 (pl_stage); a new call starts from 0. */
    ctx->progress_last = 0;
    pl_stage(ctx, segment ? "prepare" : "load", 0, 0.1, options && options->name ? options->name : "");
    pz_status status = pl_load(mesh, &result->options, segment && result->options.prepare, result, &run.garment, ctx);
    if (status == PZ_OK && segment)
        status = pl_symmetrize_garment(&result->options, result, &run.garment, &run.symmetric, ctx);
    if (status == PZ_OK)
        status = pl_gather_grain_hints(&result->options, run.garment.mesh, &run.grain_hints, ctx);
    result->grain_hint_count = run.grain_hints ? run.grain_hints->curve_count : 0;
    if (status == PZ_OK && segment)
        status = pl_segmenter_create(&result->options, result->prepared, result->grain, &run.segmenter, ctx);
    if (status == PZ_OK && segment)
        pl_segmenter_give_grain_hints(run.segmenter, run.grain_hints);
    if (status == PZ_OK && run.symmetric.active)
        pl_segmenter_give_plane(run.segmenter, &run.symmetric.symmetry);
    if (status == PZ_OK)
        status = flatten_rounds(&run, result, ctx);
    /* The symmetric garment is kept with a layout that uses the plane; a piece budget's mirrored layout (no
     * verdict rounds drop its plane) also only when its flattening meets the goals. */
    if (status == PZ_OK && run.symmetric.active &&
        (!keeps_symmetric_garment(&run) ||
         (result->options.segment.max_pieces > 0 && pl_symmetric_misses_goals(result, run.garment.mesh, ctx))))
        status = redo_as_loaded(&run, result, ctx);
    if (status == PZ_OK)
        status = measure(&run, result, ctx);
    if (run.segmenter)
        pl_segmenter_report(run.segmenter, result);
    pl_symmetric_report(&run.symmetric, result, status == PZ_OK ? ctx : NULL);
    if (status == PZ_OK) {
        /* The garment as flattened belongs to the result from here. */
        result->garment = run.garment.mesh;
        run.garment.mesh = NULL;
    }
    if (status == PZ_OK && from_run)
        status = pl_final_verdict(result, !result->segment || result->segment->goals_met, ctx);
    if (status == PZ_OK)
        status = build_layout_curves(result, ctx);
    pipeline_run_clear(&run);
    result->options.panels = NULL;  /* the caller's, and not needed beyond this call */
    if (status == PZ_OK)
        status = pz_check_cancel(ctx, pl_who(result));
    if (status != PZ_OK) {
        pz_result_free(&result);
        return status;
    }
    *out = result;
    return PZ_OK;
}

/* The rest of a run laid out (lay_out): the trade-off, mirror pieces, names, the pieces and the marker (the
 * trade-off and the marker left to pz_result_complete with options.defer_extras); the
 * total time from `start`. The result stays the caller's (freed by it on error too). */
static pz_status finish(pz_result *result, double start, pz_ctx *ctx)
{
    int from_run = result->from_run;
    pz_status status = PZ_OK;
    if (from_run && !result->options.defer_extras) {
        status = pl_measure_tradeoff(result, ctx);
        result->tradeoff_measured = status == PZ_OK;
    }
    if (status == PZ_OK)
        status = find_mirror_panels(result, ctx);
    if (status == PZ_OK && from_run)
        status = pl_name_pieces(result, ctx);
    if (status == PZ_OK)
        pl_measure_pattern_symmetry(result, ctx);
    double mark = pz_seconds();
    /* The pieces carry the garment's name: the input's base name, unless the options name one. */
    if (status == PZ_OK && !result->options.output.garment_name && result->options.name) {
        result->garment_name = pl_base_name(result->options.name);
        result->options.output.garment_name = result->garment_name;
    }
    if (status == PZ_OK) {
        pl_stage(ctx, "export", 0.9, 1.0, "pieces and marker");
        status = build_pieces(result, ctx);
    }
    result->timings.pieces = pz_elapsed_ms(mark, pz_seconds());
    result->timings.total = pz_elapsed_ms(start, pz_seconds());
    pz_progress_range(ctx, 0, 0);
    if (status == PZ_OK)
        status = pz_check_cancel(ctx, pl_who(result));
    if (status == PZ_OK)
        pz_progress(ctx, "done", 1, "%d panels", (int)result->pattern->panel_count);
    return status;
}

static pz_status execute(const pz_mesh *mesh, const pz_panels *panels, const pz_run_options *options, int from_run,
                         pz_result **out, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_status status = lay_out(mesh, panels, options, from_run, out, ctx);
    if (status == PZ_OK && (status = finish(*out, start, ctx)) != PZ_OK)
        pz_result_free(out);
    return status;
}

/* ---------------------------------------------------------------- consolidation */

/*
 * The length (mm) of the layout's seams that lie on the mirror plane: a seam
 * edge whose two ends are on it (within CONSOLIDATION_PLANE_TOLERANCE of the
 * garment's bounding-box diagonal; the symmetric garment has its plane
 * vertices exactly on it).
 */
#define CONSOLIDATION_PLANE_TOLERANCE 1e-3
static double plane_seam_length(const pz_result *result)
{
    const pz_mesh *mesh = result->garment;
    const double *n = result->symmetry.normal, d = result->symmetry.offset;
    double lo[3], hi[3];
    pz_mesh_bbox(mesh, lo, hi);
    double tolerance = CONSOLIDATION_PLANE_TOLERANCE * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
                                                            (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                                            (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double length = 0;
    for (int32_t c = 0; c < result->layout_curve_count; ++c) {
        if (result->layout_is_dart && result->layout_is_dart[c])
            continue;
        for (int32_t i = result->layout_offsets[c]; i + 1 < result->layout_offsets[c + 1]; ++i) {
            const double *a = mesh->positions + 3 * (size_t)result->layout_vertices[i];
            const double *b = mesh->positions + 3 * (size_t)result->layout_vertices[i + 1];
            if (fabs(pz_vec3_dot(n, a) - d) <= tolerance && fabs(pz_vec3_dot(n, b) - d) <= tolerance)
                length += pz_vec3_distance(a, b);
        }
    }
    return length;
}

/* 1 unless the first pattern's mirror pieces were all exact ("Cut 2": one piece drafted, cut twice) and the
 * second's are not: fewer pieces are no gain when a pair can no longer be cut from one piece (the T-shirt's
 * four pieces, laid out on the garment as loaded, could not be made exact within S). */
static int exact_as_before(const pz_result *first, const pz_result *second)
{
    int first_exact = first->symmetry_used && first->mirror_pieces > 0 &&
                      first->exact_mirror_pieces == first->mirror_pieces;
    int second_exact = !second->symmetry_used || second->exact_mirror_pieces == second->mirror_pieces;
    return !first_exact || second_exact;
}

/* 1 when the run's layout may have one piece too many: a layout of three or more pieces of a garment with a
 * mirror plane that met every goal, laid out by the segmentation with no piece budget (the designer's count
 * stands) and not a looser goal's layout written for an impossible one. */
static int worth_consolidating(const pz_result *result)
{
    const pz_run_options *options = &result->options;
    pz_goal_options defaults;
    pz_goal_options_default(&defaults);
    /* Goals stricter than the defaults are laid out over the ladder of looser ones, whose final cuts they keep
     * so that a stricter goal never has fewer pieces (docs/segment.md, "Monotone panel counts"); a layout made
     * again with a budget would not keep them, so those runs stand as laid out. */
    int stricter = options->goals.max_strain < defaults.max_strain || options->goals.max_corners < defaults.max_corners;
    return options->consolidate && result->segment && result->verdict.judged && result->verdict.goals_met &&
           !options->panels &&
           options->segment.max_pieces <= 0 && result->symmetry.found && result->garment && !stricter &&
           result->looser_written_strain <= 0 && result->pattern->panel_count >= 3;
}

/*
 * Fewer pieces where every goal allows (pietroni2022 Fig. 11: the seam on the
 * mirror plane removed where the goals allow; docs/run.md, "Consolidation").
 * The greedy layout judges its removals on quick flattenings of the traced
 * seams, and keeps seams the goals would let go: the DiffAvatar T-shirt's
 * front in two mirror halves (merged, its traced outline counts 12 corners
 * against C = 8), the shirt in 7 pieces where front, back and two sleeves
 * meet every goal. So once the run's layout meets its goals, the run is made
 * again as `--max-pieces N-1` makes it (the layout merged down, mirror pairs
 * together, judged on its joint flattening, laid out again without the plane
 * when that misses), and that pattern replaces the first when it too meets
 * every goal and has no more seam on the mirror plane (Fig. 11's direction:
 * the budget could otherwise trade side seams for a centre front and back,
 * cutting a tube bodice into left and right halves). *first is replaced or
 * kept; the notes say which.
 */
static pz_status consolidate(const pz_mesh *garment, pz_result **first, pz_ctx *ctx)
{
    if (!worth_consolidating(*first))
        return PZ_OK;
    double start = pz_seconds();
    int32_t pieces = (*first)->pattern->panel_count;
    pz_run_options fewer = (*first)->options;
    fewer.segment.max_pieces = pieces - 1;
    fewer.output.garment_name = NULL; /* the first result's: set again from the name */
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_result *second = NULL;
    pz_progress(ctx, "consolidate", 0.9, "at most %d pieces", (int)pieces - 1);
    pz_status status = lay_out(garment, NULL, &fewer, 1, &second, &quiet);
    if (status == PZ_ERR_CANCELLED || status == PZ_ERR_NOMEM)
        return pz_error(ctx, status, "run: %s", quiet.error);
    int fewer_met = status == PZ_OK && second->verdict.goals_met && second->pattern->panel_count < pieces;
    int plane_kept = fewer_met && second->symmetry.found &&
                     plane_seam_length(second) <= plane_seam_length(*first) + 1e-6;
    int kept = plane_kept && exact_as_before(*first, second);
    pz_note(ctx, "run: consolidation: the layout of at most %d pieces has %d%s (%.0f ms)%s", (int)pieces - 1,
            second ? (int)second->pattern->panel_count : 0,
            !second ? ", not made"
                    : !fewer_met ? ", goals missed"
                    : !plane_kept ? ", more seam on the mirror plane"
                    : !kept ? ", its mirror pieces not exact" : ", every goal met",
            pz_elapsed_ms(start, pz_seconds()), kept ? ": kept" : ": the first stands");
    if (!kept) {
        pz_result_free(&second);
        return PZ_OK;
    }
    /* No budget was asked for: the report shows none, and says where the pieces came from. */
    second->options.segment.max_pieces = 0;
    if (second->segment) {
        second->segment->max_pieces = 0;
        second->segment->budget_met = 1;
    }
    second->consolidated_from = pieces;
    pz_result_free(first);
    *first = second;
    return PZ_OK;
}

pz_status pz_run(const pz_mesh *garment, const pz_run_options *options, pz_result **out, pz_ctx *ctx)
{
    double start = pz_seconds();
    pz_run_options local;
    if (options)
        local = *options;
    else
        pz_run_options_default(&local);
    /* Without the caller's cache, one of the run's own: a consolidation trial lays the same garment out
     * again with the same plane and field. */
    pz_run_cache *own = local.cache || local.panels ? NULL : pz_run_cache_create();
    if (own)
        local.cache = own;
    pz_status status = lay_out(garment, local.panels, &local, 1, out, ctx);
    if (status == PZ_OK)
        status = consolidate(garment, out, ctx);
    if (status == PZ_OK)
        status = finish(*out, start, ctx);
    if (status != PZ_OK)
        pz_result_free(out);
    if (*out && own)
        (*out)->options.cache = NULL; /* the run's own, freed here */
    pz_run_cache_free(&own);
    return status;
}

pz_status pz_flatten(const pz_mesh *garment, const pz_panels *panels, const pz_run_options *options,
                     pz_result **out, pz_ctx *ctx)
{
    return execute(garment, panels, options, 0, out, ctx);
}
