/*
 * pipeline/verdict.c -- the final verdict on a pattern: every panel judged
 * by the one goal judge (pz_goal_judge, segment/goals.c) on its figures from
 * the final flattening: disk and corners on the garment's cut outline (the
 * trued seams), strain and injectivity from the metrics of every pose, the
 * seam and dart length mismatch from the pattern's seams. The verdict rounds
 * of the segmentation (segmentation.c) call the same judge.
 *
 * And the flattened pieces' own mirror symmetry.
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

pz_status pl_judge_panels(const pz_mesh *garment, const pz_pattern *pattern, const double *uv,
                          const pz_metrics *metrics, const double *pose_strain, const pz_goal_options *goals,
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
        pl_judge_panels(result->garment, pattern, result->uv, result->metrics[0], pose_strain, &goals, verdict->panels,
                        &quiet);
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
    char why[256] = "";
    if (!layout_reachable && merged > 0)
        snprintf(why, sizeof why, " (%d pieces under %g mm or %g %% of the area merged into their neighbours rather "
                 "than cut: a sliver is never the answer to S; best effort written)", (int)merged,
                 goals.min_piece_width_mm, 100 * goals.min_piece_area);
    else if (!layout_reachable)
        snprintf(why, sizeof why, " (the layout could not meet them; best effort written)");
    pz_note(ctx, "run: goals %s: %d of %d panels miss them, %d exceed S = %g, worst strain %.3g%s",
            layout_reachable ? "not met" : "unreachable", (int)verdict->failing_panels, (int)pattern->panel_count,
            (int)verdict->over_strain_panels, goals.max_strain, verdict->worst_strain, why);
    return PZ_OK;
}

/* ---------------------------------------------------------------- pattern symmetry */

/*
 * The pattern's own mirror symmetry (docs/segment.md, "Symmetry"): for each
 * mirrored pair of panels (and each panel that is its own mirror image), the
 * 2D reflection that best maps every vertex's pattern point onto its mirror
 * vertex's point in the partner panel (least squares: the points reflected,
 * then the best rotation and translation, Kabsch in 2D), and the distances
 * left. Layout residual 0 says the seams are placed symmetrically; this says
 * the flattened pieces are mirror images of each other.
 */
typedef struct mirror_fit {
    double sum_sq;       /* squared residuals summed over the points */
    double max;          /* the largest residual, mm */
    int64_t count;
} mirror_fit;

/* Fits one panel pair: points a[i] (panel p) -> b[i] (its mirror panel), n pairs. */
static void fit_reflection(const double *a, const double *b, int32_t n, mirror_fit *fit)
{
    if (n < 3)
        return;
    double ca[2] = {0, 0}, cb[2] = {0, 0};
    for (int32_t i = 0; i < n; ++i) {
        ca[0] += a[2 * i], ca[1] += -a[2 * i + 1];  /* reflected about the u axis */
        cb[0] += b[2 * i], cb[1] += b[2 * i + 1];
    }
    for (int k = 0; k < 2; ++k)
        ca[k] /= n, cb[k] /= n;
    double h00 = 0, h01 = 0, h10 = 0, h11 = 0;
    for (int32_t i = 0; i < n; ++i) {
        double x = a[2 * i] - ca[0], y = -a[2 * i + 1] - ca[1];
        double u = b[2 * i] - cb[0], v = b[2 * i + 1] - cb[1];
        h00 += x * u, h01 += x * v, h10 += y * u, h11 += y * v;
    }
    double angle = atan2(h01 - h10, h00 + h11), c = cos(angle), s = sin(angle);
    for (int32_t i = 0; i < n; ++i) {
        double x = a[2 * i] - ca[0], y = -a[2 * i + 1] - ca[1];
        double du = c * x - s * y + cb[0] - b[2 * i], dv = s * x + c * y + cb[1] - b[2 * i + 1];
        double d2 = du * du + dv * dv;
        fit->sum_sq += d2;
        fit->max = fmax(fit->max, sqrt(d2));
        ++fit->count;
    }
}

/* The RMS and largest residual (mm) over every mirrored panel pair; -1 when there is no pair. */
static pz_status pattern_mirror_residual(const pz_pattern *pattern, const double *uv, const int32_t *vertex_mirror,
                                         int32_t garment_vertices, const int32_t *panel_mirror, double *rms,
                                         double *max, pz_ctx *ctx)
{
    *rms = *max = -1;
    const pz_mesh *cut = pattern->mesh;
    int32_t *vertex_panel = malloc(((size_t)cut->vertex_count + 1) * sizeof(int32_t));
    int32_t *copy_start = calloc((size_t)garment_vertices + 2, sizeof(int32_t));
    int32_t *copies = malloc(((size_t)cut->vertex_count + 1) * sizeof(int32_t));
    double *a = malloc(((size_t)cut->vertex_count + 1) * 2 * sizeof(double));
    double *b = malloc(((size_t)cut->vertex_count + 1) * 2 * sizeof(double));
    if (!vertex_panel || !copy_start || !copies || !a || !b) {
        free(vertex_panel), free(copy_start), free(copies), free(a), free(b);
        return pz_error(ctx, PZ_ERR_NOMEM, "run: out of memory measuring the pattern's symmetry");
    }
    for (int32_t f = 0; f < cut->face_count; ++f)
        for (int k = 0; k < 3; ++k)
            vertex_panel[cut->faces[3 * f + k]] = pattern->face_panel[f];
    /* The cut-mesh copies of each garment vertex (CSR), to find a vertex's mirror in a given panel. */
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        ++copy_start[pattern->vertex_origin[v] + 2];
    for (int32_t g = 0; g < garment_vertices; ++g)
        copy_start[g + 2] += copy_start[g + 1];
    for (int32_t v = 0; v < cut->vertex_count; ++v)
        copies[copy_start[pattern->vertex_origin[v] + 1]++] = v;
    mirror_fit fit = {0, 0, 0};
    for (int32_t p = 0; p < pattern->panel_count; ++p) {
        int32_t m = panel_mirror[p];
        if (m < p)
            continue;  /* each pair once (m == p: a panel that is its own mirror image) */
        int32_t n = 0;
        for (int32_t v = 0; v < cut->vertex_count; ++v) {
            int32_t g = pattern->vertex_origin[v], mirror = vertex_panel[v] == p ? vertex_mirror[g] : -1;
            if (mirror < 0 || mirror >= garment_vertices)
                continue;
            for (int32_t i = copy_start[mirror]; i < copy_start[mirror + 1]; ++i)
                if (vertex_panel[copies[i]] == m) {
                    memcpy(a + 2 * n, uv + 2 * v, 2 * sizeof(double));
                    memcpy(b + 2 * n, uv + 2 * copies[i], 2 * sizeof(double));
                    ++n;
                    break;
                }
        }
        fit_reflection(a, b, n, &fit);
    }
    if (fit.count > 0) {
        *rms = sqrt(fit.sum_sq / (double)fit.count);
        *max = fit.max;
    }
    free(vertex_panel), free(copy_start), free(copies), free(a), free(b);
    return PZ_OK;
}

/* result->pattern_mirror_*: the final pattern's mirror symmetry, measured on its points (uv). Left at -1
 * when it cannot be measured (no symmetry found, panels not the segmentation's). */
void pl_measure_pattern_symmetry(pz_result *result, pz_ctx *ctx)
{
    result->pattern_mirror_rms_mm = result->pattern_mirror_max_mm = -1;
    const pz_segment_result *segment = result->segment;
    const pz_pattern *pattern = result->pattern;
    if (!segment || !segment->symmetry.found || segment->panel_count != pattern->panel_count || !result->panel_mirror)
        return;
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    pattern_mirror_residual(pattern, result->uv, segment->symmetry.vertex_mirror, segment->symmetry.vertex_count,
                            result->panel_mirror, &result->pattern_mirror_rms_mm, &result->pattern_mirror_max_mm,
                            &quiet);
}
