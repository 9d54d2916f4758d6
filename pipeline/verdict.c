/*
 * pipeline/verdict.c -- the final verdict on a pattern: every panel judged
 * by the one goal judge (pz_goal_judge, segment/goals.c) on its figures from
 * the final flattening: disk and corners on the garment's cut outline (the
 * trued seams), strain and injectivity from the metrics of every pose, the
 * seam and dart length mismatch from the pattern's seams. The verdict rounds
 * of the segmentation (segmentation.c) call the same judge.
 *
 * And the flattened pieces' own mirror symmetry (measured by pipeline/mirror.c).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int pl_faces_by_panel(const pz_pattern *pattern, int32_t **offsets, int32_t **order)
{
    int32_t panels = pattern->panel_count, faces = pattern->mesh->face_count;
    *offsets = calloc((size_t)panels + 2, sizeof(int32_t));
    *order = malloc(((size_t)faces + 1) * sizeof(int32_t));
    if (!*offsets || !*order)
        return 0;
    for (int32_t f = 0; f < faces; ++f)
        ++(*offsets)[pattern->face_panel[f] + 2];
    for (int32_t p = 0; p < panels; ++p)
        (*offsets)[p + 2] += (*offsets)[p + 1];
    for (int32_t f = 0; f < faces; ++f)
        (*order)[(*offsets)[pattern->face_panel[f] + 1]++] = f;
    return 1;
}

/* Each panel's worst seam or dart length mismatch (relative), into mismatch (panel_count, zeroed). */
static void seam_mismatch_by_panel(const pz_metrics *metrics, int32_t panel_count, double *mismatch)
{
    for (int32_t s = 0; s < metrics->seam_count; ++s) {
        const pz_seam_metrics *seam = &metrics->seams[s];
        int32_t sides[2] = {seam->panel_a, seam->panel_b};
        for (int k = 0; k < 2; ++k)
            if (sides[k] >= 0 && sides[k] < panel_count)
                mismatch[sides[k]] = fmax(mismatch[sides[k]], seam->mismatch_rel);
    }
}

/*
 * The figures of the pieces as cut (docs/segment.md, "Piece shapes"): each panel's width on the pattern
 * (pz_piece_width in 2D, from the cut mesh's boundary: the outline and the dart legs), its extent across
 * the grain (in u: the warp runs along v) and its darts' smallest intake. The area share and whether the
 * input forces the shape stay the garment's (pz_segment_goals).
 */
static pz_status piece_figures(const pz_pattern *pattern, const double *uv, const pz_metrics *metrics,
                               const int32_t *face_offsets, const int32_t *face_ids, const pz_goal_options *goals,
                               pz_goal_result *panels, pz_ctx *ctx)
{
    const pz_mesh *cut = pattern->mesh;
    pz_topology *topology = NULL;
    int32_t *local = malloc((size_t)cut->vertex_count * sizeof(int32_t) + 1);
    int32_t *faces = malloc((size_t)cut->face_count * 3 * sizeof(int32_t) + 1);
    double *points = malloc((size_t)cut->vertex_count * 2 * sizeof(double) + 1);
    uint8_t *source = malloc((size_t)cut->vertex_count + 1);
    pz_status status = local && faces && points && source ? pz_topology_build(cut, &topology, ctx)
                                                          : pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory");
    if (local)
        memset(local, 0xff, (size_t)cut->vertex_count * sizeof(int32_t));
    for (int32_t p = 0; status == PZ_OK && p < pattern->panel_count; ++p) {
        pz_goal_result *figures = &panels[p];
        int32_t count = 0, vertices = 0;
        double lo = INFINITY, hi = -INFINITY;
        for (int32_t i = face_offsets[p]; i < face_offsets[p + 1]; ++i, ++count)
            for (int k = 0; k < 3; ++k) {
                int32_t v = cut->faces[3 * face_ids[i] + k];
                if (local[v] < 0) {
                    local[v] = vertices;
                    memcpy(points + 2 * vertices, uv + 2 * v, 2 * sizeof(double));
                    source[vertices++] = topology->vertex_on_boundary[v];
                    lo = fmin(lo, uv[2 * v]);
                    hi = fmax(hi, uv[2 * v]);
                }
                faces[3 * count + k] = local[v];
            }
        figures->across_grain_mm = hi >= lo ? hi - lo : 0;
        if (goals->min_piece_width_mm > 0)
            status = pz_piece_width(vertices, points, 2, count, faces, source, &figures->min_width_mm, ctx);
        for (int32_t i = face_offsets[p]; i < face_offsets[p + 1]; ++i)
            for (int k = 0; k < 3; ++k)
                local[cut->faces[3 * face_ids[i] + k]] = -1;
    }
    for (int32_t d = 0; status == PZ_OK && d < pattern->dart_count && d < metrics->dart_count; ++d) {
        pz_goal_result *figures = &panels[pattern->darts[d].panel];
        double intake = metrics->darts[d].intake_mm;
        ++figures->darts;
        if (figures->min_dart_intake_mm < 0 || intake < figures->min_dart_intake_mm)
            figures->min_dart_intake_mm = intake;
    }
    pz_topology_free(&topology);
    free(local);
    free(faces);
    free(points);
    free(source);
    return status;
}

/* The copy of a mirror pair is cut from its partner's piece, reflected: its outline's corners are the partner's. */
static void judge_copies(const pz_segment_result *segment, const pz_goal_options *goals, int32_t panel_count,
                         pz_goal_result *panels)
{
    if (!segment || segment->panel_count != panel_count)
        return;
    for (int32_t p = 0; p < panel_count; ++p) {
        int32_t q = segment->panels[p].mirror_panel;
        if (!segment->panels[p].copy || q < 0 || q >= panel_count || panels[p].corners < 0)
            continue;
        panels[p].corners = panels[q].corners;
        panels[p].failures = pz_goal_judge(goals, &panels[p]);
    }
}

pz_status pl_judge_panels(const pz_mesh *garment, const pz_pattern *pattern, const double *uv,
                          const pz_metrics *metrics, const double *pose_strain, const pz_goal_options *goals,
                          const pz_segment_result *segment,
                          pz_goal_result *panels, pz_ctx *ctx)
{
    int32_t panel_count = pattern->panel_count;
    const int32_t *cut_faces = pattern->mesh->faces;  /* the garment's faces, in order, on cut-mesh copies */
    pz_topology *topology = NULL;
    int32_t *face_ids = NULL, *face_offsets = NULL;
    uint8_t *edge_cut = NULL;
    double *mismatch = calloc((size_t)panel_count + 1, sizeof(double));
    pz_status status = pz_topology_build(garment, &topology, ctx);
    if (status == PZ_OK) {
        int bucketed = pl_faces_by_panel(pattern, &face_offsets, &face_ids);
        edge_cut = calloc((size_t)topology->edge_count + 1, 1);
        if (!bucketed || !edge_cut || !mismatch)
            status = pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory judging the goals");
    }
    if (status == PZ_OK) {
        /* An edge is cut when its two faces use different copies of one of its ends. */
        for (int32_t e = 0; e < topology->edge_count; ++e) {
            int32_t h = topology->edge_halfedge[2 * e], t = topology->edge_halfedge[2 * e + 1];
            if (t >= 0)
                edge_cut[e] = cut_faces[h] != cut_faces[pz_he_next(t)] || cut_faces[pz_he_next(h)] != cut_faces[t];
        }
        seam_mismatch_by_panel(metrics, panel_count, mismatch);
        for (int32_t d = 0; d < metrics->dart_count && d < pattern->dart_count; ++d) {
            int32_t panel = pattern->darts[d].panel;
            if (panel >= 0 && panel < panel_count)
                mismatch[panel] = fmax(mismatch[panel], metrics->darts[d].mismatch_rel);
        }
    }
    /* Disk and corners from the outline (an evaluation with no flattening: the final one decides the rest). */
    pz_goal_options shape_only = *goals;
    shape_only.textile_iterations = -1;
    for (int32_t p = 0; p < panel_count && status == PZ_OK; ++p) {
        pz_goal_result *figures = &panels[p];
        status = pz_segment_goals(garment, topology, edge_cut, face_ids + face_offsets[p],
                                  face_offsets[p + 1] - face_offsets[p], &shape_only, figures, ctx);
        if (status != PZ_OK)
            break;
        const pz_panel_metrics *panel = &metrics->panels[p];
        double strain = fmax(fmax(fabs(panel->strain_warp.max), fabs(panel->strain_weft.max)), 0.0);
        if (pose_strain)
            strain = fmax(strain, pose_strain[p]);
        figures->max_abs_strain = strain;
        figures->flipped_triangles = panel->flipped_triangles;
        figures->boundary_self_intersections = panel->boundary_self_intersections;
        figures->max_seam_mismatch = mismatch[p];
    }
    if (status == PZ_OK)
        status = piece_figures(pattern, uv, metrics, face_offsets, face_ids, goals, panels, ctx);
    for (int32_t p = 0; p < panel_count && status == PZ_OK; ++p)
        panels[p].failures = pz_goal_judge(goals, &panels[p]);
    if (status == PZ_OK)
        judge_copies(segment, goals, panel_count, panels);
    free(mismatch);
    free(edge_cut);
    free(face_offsets);
    free(face_ids);
    pz_topology_free(&topology);
    return status;
}

/* Each panel's worst |warp| or |weft| strain over the extra poses' metrics; NULL without poses (or memory). */
static double *strain_over_poses(const pz_result *result)
{
    if (result->metrics_count <= 1)
        return NULL;
    int32_t panel_count = result->pattern->panel_count;
    double *strain = calloc((size_t)panel_count + 1, sizeof(double));
    for (int i = 1; strain && i < result->metrics_count; ++i)
        for (int32_t p = 0; p < panel_count && p < result->metrics[i]->panel_count; ++p) {
            const pz_panel_metrics *panel = &result->metrics[i]->panels[p];
            strain[p] = fmax(strain[p], fmax(fabs(panel->strain_warp.max), fabs(panel->strain_weft.max)));
        }
    return strain;
}

/* The reasons line: a summary, then the failing panels, cut at a whole panel. */
static void write_reasons(pz_verdict *verdict, const pz_goal_options *goals, int32_t panel_count)
{
    char *reasons = verdict->reasons;
    size_t size = sizeof verdict->reasons;
    int written = snprintf(reasons, size, "%d of %d panels miss the goals (%d exceed S = %g, worst strain %.3g): ",
                           (int)verdict->failing_panels, (int)panel_count, (int)verdict->over_strain_panels,
                           goals->max_strain, verdict->worst_strain);
    size_t used = written > 0 && (size_t)written < size ? (size_t)written : 0;
    for (int32_t p = 0, listed = 0; p < panel_count; ++p) {
        if (!verdict->panels[p].failures)
            continue;
        char text[256];
        pz_goal_describe(&verdict->panels[p], goals, text, sizeof text);
        written = snprintf(reasons + used, size - used, "%spanel %d: %s", listed++ ? "; " : "", (int)p, text);
        if (written < 0 || used + (size_t)written >= size) {
            /* Cut at a whole panel and say so, rather than mid-word. */
            reasons[used] = '\0';
            snprintf(reasons + used, size - used, "%s...", listed > 1 ? "; " : "");
            break;
        }
        used += (size_t)written;
    }
}

/* The share of the garment's area whose warp or weft strain exceeds s in the rest pose or another. */
static double area_over_strain(const pz_result *result, double s)
{
    const pz_mesh *mesh = result->pattern->mesh;
    double *areas = malloc((size_t)mesh->face_count * sizeof(double) + 1);
    if (!areas)
        return -1;
    pz_geom_face_areas(mesh, areas);
    double over = 0, total = 0;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        int exceeds = 0;
        for (int i = 0; i < result->metrics_count && !exceeds; ++i) {
            const pz_metrics *m = result->metrics[i];
            exceeds = f < m->face_count && fmax(fabs(m->strain_warp[f]), fabs(m->strain_weft[f])) > s;
        }
        over += exceeds ? areas[f] : 0;
        total += areas[f];
    }
    free(areas);
    return total > 0 ? over / total : 0;
}

pz_status pl_final_verdict(pz_result *result, int layout_reachable, pz_ctx *ctx)
{
    pz_verdict *verdict = &result->verdict;
    const pz_pattern *pattern = result->pattern;
    pz_goal_options goals = result->options.goals;
    memcpy(goals.grain, result->grain, sizeof goals.grain);
    verdict->judged = 1;
    verdict->reachable = layout_reachable;
    verdict->panels = calloc((size_t)pattern->panel_count + 1, sizeof *verdict->panels);
    if (!verdict->panels)
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory judging the goals");
    double *pose_strain = strain_over_poses(result);
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pz_status status =
        pl_judge_panels(result->garment, pattern, result->uv, result->metrics[0], pose_strain, &goals, result->segment,
                        verdict->panels, &quiet);
    free(pose_strain);
    if (status != PZ_OK)
        return pz_error(ctx, status, "%s", quiet.error);
    verdict->goals_met = 1;
    verdict->area_over_strain = area_over_strain(result, goals.max_strain);
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        const pz_goal_result *panel = &verdict->panels[p];
        verdict->failing_panels += panel->failures != 0;
        verdict->over_strain_panels += (panel->failures & PZ_GOAL_STRAIN) != 0;
        verdict->worst_strain = fmax(verdict->worst_strain, panel->max_abs_strain);
        verdict->worst_seam_mismatch = fmax(verdict->worst_seam_mismatch, panel->max_seam_mismatch);
    }
    if (verdict->failing_panels == 0)
        return PZ_OK;
    verdict->goals_met = 0;
    write_reasons(verdict, &goals, pattern->panel_count);
    /* Where the layout merged slivers, S was given up on purpose: say so (docs/segment.md, "Piece shapes"). */
    int32_t merged = result->segment ? result->segment->merged_slivers : 0;
    char why[512] = "";
    if (!layout_reachable && result->looser_written_strain > 0)
        snprintf(why, sizeof why, " (sound pieces cannot meet it: the layout made for S = %g is written instead of "
                 "slivers)", result->looser_written_strain);
    else if (!layout_reachable && merged > 0)
        snprintf(why, sizeof why, " (%d pieces under %g mm or %g %% of the area merged into their neighbours rather "
                 "than cut: a sliver is never the answer to S; best effort written)", (int)merged,
                 goals.min_piece_width_mm, 100 * goals.min_piece_area);
    else if (!layout_reachable)
        snprintf(why, sizeof why, " (the layout could not meet them; best effort written)");
    /* The S that can be met, from the looser settings laid out first: the one figure a user can act on. */
    if (!layout_reachable && result->looser_reachable_strain > 0) {
        size_t used = strlen(why);
        snprintf(why + used, sizeof why - used, "; S = %g cannot be met here, S = %g can (%d panels)",
                 goals.max_strain, result->looser_reachable_strain, (int)result->looser_reachable_panels);
    }
    pz_note(ctx, "run: goals %s: %d of %d panels miss them, %d exceed S = %g, worst strain %.3g%s",
            layout_reachable ? "not met" : "unreachable", (int)verdict->failing_panels, (int)pattern->panel_count,
            (int)verdict->over_strain_panels, goals.max_strain, verdict->worst_strain, why);
    return PZ_OK;
}

/* ---------------------------------------------------------------- pattern symmetry */

/* result->pattern_mirror_*: the final pattern's mirror pieces, measured on their outlines (pl_mirror_residual).
 * Left at -1 when they cannot be measured (no plane used, panels not the segmentation's). */
void pl_measure_pattern_symmetry(pz_result *result, pz_ctx *ctx)
{
    result->pattern_mirror_rms_mm = result->pattern_mirror_max_mm = -1;
    if (!result->segment)
        return;
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    result->panel_mirror_residual_mm = malloc(((size_t)result->pattern->panel_count + 1) * sizeof(double));
    pl_mirror_residual(result->pattern, result->uv, result->segment, &result->pattern_mirror_rms_mm,
                       &result->pattern_mirror_max_mm, result->panel_mirror_residual_mm, &quiet);
}
