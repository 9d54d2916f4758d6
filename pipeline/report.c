/*
 * pipeline/report.c -- report.json (docs/flatten.md, docs/run.md,
 * docs/metrics.md): the input, the parameters, every panel's metrics (the
 * worst over the poses), the back-end's own result, seams and darts, the
 * summary; pz_run adds each panel's goals, the segmentation and the
 * preparation. Built from a pz_result alone.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"
#include "core/vec.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What the flatten part of the report reads, gathered from the result. */
typedef struct report_view {
    const char *const *input_paths;
    int input_count;
    int32_t vertices, faces, poses;
    const char *units;
    int units_guessed;
    const char *panels_source;
    const char *backend;
    int iterations;
    double weights[4];
    pz_fabric fabric;
    double grain[3];
    int32_t grain_hint_count;
    const char *grain_source;
    const pz_textile_result *textile;      /* textile only, else NULL */
    const pz_wirewarp_result *wirewarp;    /* wirewarp only, else NULL */
    int progressive;
    int32_t feature_count;
    const pz_skipped_feature *skipped_features;
    int32_t skipped_feature_count;
    const pz_springmass_result *springmass; /* springmass only, else NULL */
    int relax_full;
    int orthotropic;
    double backend_ms;
    const double *uv;
    int layout_moved;
    double timings_ms[6];                   /* read, pattern, flatten, metrics, write, total */
    const pz_pattern *pattern;
    const pz_metrics *const *metrics;
    int metrics_count;
    const char *const *panel_names;
} report_view;

/* ---------------------------------------------------------------- report.json */

typedef struct json_builder {
    int failed;
} json_builder;

static void add_number(json_builder *builder, cJSON *object, const char *key, double value, int decimals)
{
    /* + 0.0 turns a rounded -0 into 0 */
    if (!cJSON_AddNumberToObject(object, key, pz_round(value, decimals) + 0.0))
        builder->failed = 1;
}

static cJSON *add_object(json_builder *builder, cJSON *parent, const char *key)
{
    cJSON *object = cJSON_AddObjectToObject(parent, key);
    if (!object)
        builder->failed = 1;
    return object;
}

static cJSON *add_array(json_builder *builder, cJSON *parent, const char *key)
{
    cJSON *array = cJSON_AddArrayToObject(parent, key);
    if (!array)
        builder->failed = 1;
    return array;
}

static cJSON *append_object(json_builder *builder, cJSON *array)
{
    cJSON *object = cJSON_CreateObject();
    if (!object || !cJSON_AddItemToArray(array, object)) {
        cJSON_Delete(object);
        builder->failed = 1;
        return NULL;
    }
    return object;
}

static void add_doubles(json_builder *builder, cJSON *parent, const char *key, const double *values, int count,
                        int decimals)
{
    double rounded[8];
    for (int i = 0; i < count && i < 8; ++i)
        rounded[i] = pz_round(values[i], decimals);
    cJSON *array = cJSON_CreateDoubleArray(rounded, count);
    if (!array || !cJSON_AddItemToObject(parent, key, array)) {
        cJSON_Delete(array);
        builder->failed = 1;
    }
}

/* max and p95 (magnitudes): the largest over the poses measured; mean (signed): the one of largest magnitude. */
static void add_stat(json_builder *builder, cJSON *parent, const char *key, const report_view *report,
                     int32_t panel, size_t offset, int decimals)
{
    cJSON *object = cJSON_AddObjectToObject(parent, key);
    if (!object) {
        builder->failed = 1;
        return;
    }
    pz_stat worst = {-DBL_MAX, -DBL_MAX, 0};
    for (int i = 0; i < report->metrics_count; ++i) {
        const pz_stat *stat = (const pz_stat *)((const char *)&report->metrics[i]->panels[panel] + offset);
        worst.max = fmax(worst.max, stat->max);
        worst.p95 = fmax(worst.p95, stat->p95);
        if (i == 0 || fabs(stat->mean) > fabs(worst.mean))
            worst.mean = stat->mean;
    }
    add_number(builder, object, "max", worst.max, decimals);
    add_number(builder, object, "p95", worst.p95, decimals);
    add_number(builder, object, "mean", worst.mean, decimals);
}

static void add_input(json_builder *builder, cJSON *root, const report_view *report)
{
    cJSON *input = add_object(builder, root, "input");
    if (!input)
        return;
    if (!cJSON_AddStringToObject(input, "file", report->input_paths[0]))
        builder->failed = 1;
    cJSON *files = cJSON_CreateStringArray(report->input_paths, report->input_count);
    if (!files || !cJSON_AddItemToObject(input, "files", files)) {
        cJSON_Delete(files);
        builder->failed = 1;
    }
    add_number(builder, input, "vertices", report->vertices, 0);
    add_number(builder, input, "faces", report->faces, 0);
    add_number(builder, input, "poses", report->poses, 0);
    if (!cJSON_AddStringToObject(input, "units", report->units) ||
        !cJSON_AddBoolToObject(input, "units_guessed", report->units_guessed) ||
        !cJSON_AddStringToObject(input, "panels_from", report->panels_source))
        builder->failed = 1;
}

static void add_parameters(json_builder *builder, cJSON *root, const report_view *report)
{
    cJSON *parameters = add_object(builder, root, "parameters");
    if (!parameters)
        return;
    if (!cJSON_AddStringToObject(parameters, "backend", report->backend))
        builder->failed = 1;
    add_number(builder, parameters, "iterations", report->iterations, 0);
    cJSON *weights = add_object(builder, parameters, "weights");
    if (weights) {
        add_number(builder, weights, "stretch", report->weights[0], 6);
        add_number(builder, weights, "rigid", report->weights[1], 6);
        add_number(builder, weights, "dart", report->weights[2], 6);
        add_number(builder, weights, "seam", report->weights[3], 6);
    }
    cJSON *fabric = add_object(builder, parameters, "fabric");
    if (fabric) {
        add_number(builder, fabric, "k_su_N_per_mm", report->fabric.k_su, 6);
        add_number(builder, fabric, "k_sv_N_per_mm", report->fabric.k_sv, 6);
        add_number(builder, fabric, "k_r_N_per_mm_rad", report->fabric.k_r, 6);
    }
    add_doubles(builder, parameters, "grain", report->grain, 3, 6);
    add_number(builder, parameters, "grain_hints", report->grain_hint_count, 0);
    if (report->grain_source && !cJSON_AddStringToObject(parameters, "grain_source", report->grain_source))
        builder->failed = 1;
    if (report->wirewarp && !cJSON_AddStringToObject(parameters, "scheme", report->progressive ? "progressive" : "global"))
        builder->failed = 1;
    if (report->springmass) {
        if (!cJSON_AddStringToObject(parameters, "relax", report->relax_full ? "full" : "heap") ||
            !cJSON_AddBoolToObject(parameters, "orthotropic", report->orthotropic))
            builder->failed = 1;
    }
    if (report->textile) {
        cJSON *textile = add_object(builder, parameters, "textile_result");
        if (textile) {
            add_number(builder, textile, "iterations_run", report->textile->iterations_run, 0);
            add_number(builder, textile, "initial_energy", report->textile->initial_energy, 6);
            add_number(builder, textile, "final_energy", report->textile->final_energy, 6);
            if (!cJSON_AddBoolToObject(textile, "converged", report->textile->converged))
                builder->failed = 1;
        }
    }
}

static void add_timings(json_builder *builder, cJSON *root, const report_view *report)
{
    static const char *const names[6] = {"read", "pattern", "flatten", "metrics", "write", "total"};
    cJSON *timings = add_object(builder, root, "timings_ms");
    for (int i = 0; timings && i < 6; ++i)
        add_number(builder, timings, names[i], report->timings_ms[i], 3);
}

static void add_panels(json_builder *builder, cJSON *root, const report_view *report)
{
    cJSON *panels = add_array(builder, root, "panels");
    const pz_metrics *rest = report->metrics[0];
    for (int32_t p = 0; panels && p < rest->panel_count; ++p) {
        const pz_panel_metrics *m = &rest->panels[p];
        cJSON *panel = append_object(builder, panels);
        if (!panel)
            return;
        add_number(builder, panel, "id", p, 0);
        const char *name = report->panel_names ? report->panel_names[p] : NULL;
        if (name && !cJSON_AddStringToObject(panel, "name", name))
            builder->failed = 1;
        add_number(builder, panel, "faces", m->face_count, 0);
        add_number(builder, panel, "area_3d_mm2", m->area_3d_mm2, 3);
        add_number(builder, panel, "area_2d_mm2", m->area_2d_mm2, 3);
        add_stat(builder, panel, "strain_warp", report, p, offsetof(pz_panel_metrics, strain_warp), 8);
        add_stat(builder, panel, "strain_weft", report, p, offsetof(pz_panel_metrics, strain_weft), 8);
        add_stat(builder, panel, "shear_deg", report, p, offsetof(pz_panel_metrics, shear_deg), 6);
        add_number(builder, panel, "orthotropic_energy", m->orthotropic_energy, 6);
        add_number(builder, panel, "arap_energy", m->arap_energy, 6);
        add_number(builder, panel, "E_len", m->e_len, 12);
        add_number(builder, panel, "E_ang", m->e_ang, 12);
        add_number(builder, panel, "E_area", m->e_area, 12);
        add_number(builder, panel, "E_shape", m->e_shape, 12);
        add_number(builder, panel, "flipped_triangles", m->flipped_triangles, 0);
        add_number(builder, panel, "boundary_self_intersections", m->boundary_self_intersections, 0);
    }
}

static void add_bool(json_builder *builder, cJSON *object, const char *key, int value)
{
    if (!cJSON_AddBoolToObject(object, key, value))
        builder->failed = 1;
}

static void add_string(json_builder *builder, cJSON *object, const char *key, const char *value)
{
    if (!cJSON_AddStringToObject(object, key, value))
        builder->failed = 1;
}

static void add_wirewarp_result(json_builder *builder, cJSON *object, const report_view *report)
{
    const pz_wirewarp_result *r = report->wirewarp;
    add_string(builder, object, "scheme", report->progressive ? "progressive" : "global");
    add_number(builder, object, "feature_curves", report->feature_count, 0);
    add_number(builder, object, "wire_patches", r->wire_patch_count, 0);
    add_number(builder, object, "wire_nodes", r->wire_node_count, 0);
    add_number(builder, object, "wire_edges", r->wire_edge_count, 0);
    add_number(builder, object, "locked_angles", r->locked_count, 0);
    add_number(builder, object, "constraints", r->constraint_count, 0);
    add_number(builder, object, "newton_iterations", r->iterations, 0);
    add_number(builder, object, "e_len_wires", r->e_len_wires, 15);
    add_number(builder, object, "max_wire_error", r->max_wire_error, 15);
    add_number(builder, object, "constraint_residual", r->constraint_residual, 15);
    add_bool(builder, object, "best_effort", r->best_effort);
    add_bool(builder, object, "interior_fallback", r->interior_fallback);
    add_bool(builder, object, "interior_inverse_length", r->interior_inverse_length);
    add_bool(builder, object, "injective", r->injective);
    add_number(builder, object, "flipped_triangles", r->flipped_triangles, 0);
    add_number(builder, object, "angle_ms", r->angle_ms, 3);
    add_number(builder, object, "layout_ms", r->layout_ms, 3);
    add_number(builder, object, "interior_ms", r->interior_ms, 3);
    /* What a best-effort result gave up (docs/wirewarp.md "Results that are not errors"). */
    add_number(builder, object, "trimmed_feature_edges", r->trimmed_feature_edges, 0);
    add_number(builder, object, "untangled_vertices", r->untangled_vertices, 0);
    int32_t listed = r->relaxed_key_curve_count < PZ_WIREWARP_RELAXED_MAX ? r->relaxed_key_curve_count
                                                                           : PZ_WIREWARP_RELAXED_MAX;
    cJSON *relaxed = cJSON_CreateIntArray(r->relaxed_key_curves, listed);
    if (!relaxed || !cJSON_AddItemToObject(object, "relaxed_key_curves", relaxed)) {
        cJSON_Delete(relaxed);
        builder->failed = 1;
    }
    add_number(builder, object, "relaxed_key_curve_count", r->relaxed_key_curve_count, 0);
    add_number(builder, object, "relaxed_key_angle_deg", r->relaxed_key_angle * 180 / 3.14159265358979323846, 6);
    cJSON *skipped = add_array(builder, object, "skipped_feature_curves");
    for (int32_t i = 0; skipped && i < report->skipped_feature_count; ++i) {
        cJSON *curve = append_object(builder, skipped);
        if (!curve)
            return;
        add_number(builder, curve, "curve", report->skipped_features[i].curve, 0);
        add_string(builder, curve, "problem", report->skipped_features[i].problem);
    }
}

static const char *stop_name(int stop)
{
    switch (stop) {
    case PZ_SPRINGMASS_STOP_ACCURACY: return "accuracy";
    case PZ_SPRINGMASS_STOP_VARIATION: return "energy variation";
    case PZ_SPRINGMASS_STOP_ITERATIONS: return "iteration cap";
    default: return "none";
    }
}

static const char *seam_kind_name(pz_seam_kind kind)
{
    return kind == PZ_SEAM_KIND_DART ? "dart" : kind == PZ_SEAM_KIND_GUSSET ? "gusset" : "none";
}

/* The crest line of one panel: cut-mesh vertices, their 3D points (mm) and pattern points (mm). */
static void add_cutting_line(json_builder *builder, cJSON *object, const report_view *report,
                             const pz_springmass_panel *panel)
{
    cJSON *line = add_object(builder, object, "cutting_line");
    cJSON *vertices = line ? cJSON_CreateIntArray(panel->cut_vertices, panel->cut_vertex_count) : NULL;
    if (!vertices || !cJSON_AddItemToObject(line, "vertices", vertices)) {
        cJSON_Delete(vertices);
        builder->failed = 1;
        return;
    }
    cJSON *points = add_array(builder, line, "points_3d_mm");
    cJSON *points_2d = add_array(builder, line, "points_2d_mm");
    const pz_mesh *mesh = report->pattern->mesh;
    for (int32_t i = 0; points && points_2d && i < panel->cut_vertex_count; ++i) {
        int32_t v = panel->cut_vertices[i];
        const double *x = mesh->positions + 3 * (size_t)v;
        double xyz[3] = {pz_round(x[0], 6), pz_round(x[1], 6), pz_round(x[2], 6)};
        cJSON *point = cJSON_CreateDoubleArray(xyz, 3);
        if (!point || !cJSON_AddItemToArray(points, point)) {
            cJSON_Delete(point);
            builder->failed = 1;
        }
        double uv[2] = {pz_round(report->uv[2 * (size_t)v], 6), pz_round(report->uv[2 * (size_t)v + 1], 6)};
        cJSON *point_2d = cJSON_CreateDoubleArray(uv, 2);
        if (!point_2d || !cJSON_AddItemToArray(points_2d, point_2d)) {
            cJSON_Delete(point_2d);
            builder->failed = 1;
        }
    }
}

static void add_springmass_result(json_builder *builder, cJSON *object, const report_view *report)
{
    const pz_springmass_result *r = report->springmass;
    add_string(builder, object, "relax", report->relax_full ? "full" : "heap");
    add_bool(builder, object, "orthotropic", report->orthotropic);
    add_number(builder, object, "phase_one_energy", r->phase_one_energy, 6);
    add_number(builder, object, "final_energy", r->final_energy, 6);
    add_number(builder, object, "node_relaxations", (double)r->node_relaxations, 0);
    add_number(builder, object, "phase_one_relaxations", (double)r->phase_one_relaxations, 0);
    add_number(builder, object, "energy_evaluations", (double)r->energy_evaluations, 0);
    add_number(builder, object, "phase_one_ms", r->phase_one_ms, 3);
    add_number(builder, object, "phase_two_ms", r->phase_two_ms, 3);
    add_number(builder, object, "matched_pairs", r->matched_pairs, 0);
    add_number(builder, object, "unmatched_panels", r->unmatched_panels, 0);
    add_number(builder, object, "retried_panels", r->retried_panels, 0);
    add_number(builder, object, "max_seam_mismatch", r->max_seam_mismatch, 8);
    cJSON *panels = add_array(builder, object, "panels");
    for (int32_t p = 0; panels && p < r->panel_count; ++p) {
        const pz_springmass_panel *m = &r->panels[p];
        cJSON *panel = append_object(builder, panels);
        if (!panel)
            return;
        add_number(builder, panel, "id", m->panel, 0);
        add_string(builder, panel, "stop", stop_name(m->stop));
        add_number(builder, panel, "sweeps", m->iterations, 0);
        add_number(builder, panel, "phase_one_energy", m->phase_one_energy, 6);
        add_number(builder, panel, "final_energy", m->final_energy, 6);
        add_number(builder, panel, "E_area", m->e_area, 12);
        add_number(builder, panel, "E_shape", m->e_shape, 12);
        add_number(builder, panel, "max_energy_vertex", m->max_energy_vertex, 0);
        add_string(builder, panel, "seam_kind", seam_kind_name(m->cut_kind));
        add_number(builder, panel, "cut_opening_mm2", m->cut_opening_mm2, 3);
        add_number(builder, panel, "cut_energy", m->cut_energy, 6);
        add_cutting_line(builder, panel, report, m);
    }
    /* Indexed by cut-mesh vertex = the vt index of garment.obj. */
    add_string(builder, object, "energy_map_vertices", "pattern (vt of garment.obj)");
    add_number(builder, object, "energy_map_count", r->vertex_count, 0);
    cJSON *map = cJSON_CreateArray();
    for (int32_t v = 0; map && v < r->vertex_count; ++v) {
        cJSON *value = cJSON_CreateNumber(pz_round(r->vertex_energy[v], 9) + 0.0);
        if (!value || !cJSON_AddItemToArray(map, value)) {
            cJSON_Delete(value);
            cJSON_Delete(map);
            map = NULL;
        }
    }
    if (!map || !cJSON_AddItemToObject(object, "energy_map", map)) {
        cJSON_Delete(map);
        builder->failed = 1;
    }
}

/* backend_result: what the chosen back-end itself reports (the metrics above are shared by all). */
static void add_backend_result(json_builder *builder, cJSON *root, const report_view *report)
{
    cJSON *object = add_object(builder, root, "backend_result");
    if (!object)
        return;
    add_string(builder, object, "backend", report->backend);
    add_number(builder, object, "ms", report->backend_ms, 3);
    if (report->textile) {
        add_number(builder, object, "iterations_run", report->textile->iterations_run, 0);
        add_number(builder, object, "initial_energy", report->textile->initial_energy, 6);
        add_number(builder, object, "final_energy", report->textile->final_energy, 6);
        add_bool(builder, object, "converged", report->textile->converged);
        add_number(builder, object, "damped_steps", report->textile->damped_steps, 0);
    }
    if (report->wirewarp)
        add_wirewarp_result(builder, object, report);
    if (report->springmass)
        add_springmass_result(builder, object, report);
}

static void add_seams_and_darts(json_builder *builder, cJSON *root, const report_view *report)
{
    const pz_metrics *rest = report->metrics[0];
    cJSON *seams = add_array(builder, root, "seams");
    for (int32_t s = 0; seams && s < rest->seam_count; ++s) {
        const pz_seam_metrics *m = &rest->seams[s];
        cJSON *seam = append_object(builder, seams);
        if (!seam)
            return;
        add_number(builder, seam, "id", s, 0);
        int panels[2] = {m->panel_a, m->panel_b};
        cJSON *pair = cJSON_CreateIntArray(panels, 2);
        if (!pair || !cJSON_AddItemToObject(seam, "panels", pair)) {
            cJSON_Delete(pair);
            builder->failed = 1;
        }
        if (s < report->pattern->seam_count)
            add_number(builder, seam, "vertex_pairs", report->pattern->seams[s].pair_count, 0);
        add_number(builder, seam, "length_3d_mm", m->length_3d_mm, 4);
        add_number(builder, seam, "length_a_mm", m->length_a_mm, 4);
        add_number(builder, seam, "length_b_mm", m->length_b_mm, 4);
        add_number(builder, seam, "mismatch_rel", m->mismatch_rel, 8);
        add_number(builder, seam, "reflection_residual_mm", m->reflection_residual_mm, 6);
    }
    cJSON *darts = add_array(builder, root, "darts");
    for (int32_t d = 0; darts && d < rest->dart_count; ++d) {
        const pz_dart_metrics *m = &rest->darts[d];
        cJSON *dart = append_object(builder, darts);
        if (!dart)
            return;
        add_number(builder, dart, "id", d, 0);
        if (d < report->pattern->dart_count) {
            add_number(builder, dart, "panel", report->pattern->darts[d].panel, 0);
            add_number(builder, dart, "vertex_pairs", report->pattern->darts[d].pair_count, 0);
        }
        add_number(builder, dart, "leg_a_mm", m->leg_a_mm, 4);
        add_number(builder, dart, "leg_b_mm", m->leg_b_mm, 4);
        add_number(builder, dart, "mismatch_rel", m->mismatch_rel, 8);
        add_number(builder, dart, "symmetry_residual_mm", m->symmetry_residual_mm, 6);
        add_number(builder, dart, "intake_mm", m->intake_mm, 4);
    }
}

static void add_summary(json_builder *builder, cJSON *root, const report_view *report)
{
    cJSON *summary = add_object(builder, root, "summary");
    if (!summary)
        return;
    const pz_metrics *rest = report->metrics[0];
    double max_abs_strain = 0;
    int injective = 1;
    for (int i = 0; i < report->metrics_count; ++i) {
        max_abs_strain = fmax(max_abs_strain, report->metrics[i]->max_abs_strain);
        injective &= report->metrics[i]->injective != 0;
    }
    int32_t flipped = 0, intersections = 0;
    for (int32_t p = 0; p < rest->panel_count; ++p) {
        flipped += rest->panels[p].flipped_triangles;
        intersections += rest->panels[p].boundary_self_intersections;
    }
    add_number(builder, summary, "panel_count", rest->panel_count, 0);
    add_number(builder, summary, "seam_count", rest->seam_count, 0);
    add_number(builder, summary, "dart_count", rest->dart_count, 0);
    add_number(builder, summary, "max_abs_strain", max_abs_strain, 8);
    cJSON *by_pose = add_array(builder, summary, "max_abs_strain_by_pose");
    for (int i = 0; by_pose && i < report->metrics_count; ++i) {
        cJSON *value = cJSON_CreateNumber(pz_round(report->metrics[i]->max_abs_strain, 8) + 0.0);
        if (!value || !cJSON_AddItemToArray(by_pose, value)) {
            cJSON_Delete(value);
            builder->failed = 1;
        }
    }
    if (!cJSON_AddBoolToObject(summary, "injective", injective))
        builder->failed = 1;
    add_number(builder, summary, "flipped_triangles", flipped, 0);
    add_number(builder, summary, "boundary_self_intersections", intersections, 0);
    add_number(builder, summary, "max_seam_mismatch_rel", rest->max_seam_mismatch_rel, 8);
    if (!cJSON_AddBoolToObject(summary, "layout_moved", report->layout_moved))
        builder->failed = 1;
}

static cJSON *flatten_report_json(const report_view *report)
{
    json_builder builder = {0};
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return NULL;
    add_input(&builder, root, report);
    add_parameters(&builder, root, report);
    add_timings(&builder, root, report);
    add_panels(&builder, root, report);
    add_seams_and_darts(&builder, root, report);
    add_summary(&builder, root, report);
    add_backend_result(&builder, root, report);
    if (builder.failed) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

/* ---------------------------------------------------------------- pz_run's own keys */

static int add_plain_number(cJSON *object, const char *name, double value)
{
    return cJSON_AddNumberToObject(object, name, value) != NULL;
}

/* Each panel's corners, darts, mirror partner and goals. */
static int extend_panels(const pz_result *result, cJSON *root)
{
    const pz_pattern *pattern = result->pattern;
    cJSON *list = cJSON_GetObjectItem(root, "panels");
    int ok = 1;
    int32_t *darts = calloc((size_t)pattern->panel_count + 1, sizeof(int32_t));
    if (!darts)
        return 0;
    for (int32_t d = 0; d < pattern->dart_count; ++d)
        ++darts[pattern->darts[d].panel];
    int32_t p = 0;
    for (cJSON *item = list ? list->child : NULL; item && p < pattern->panel_count; item = item->next, ++p) {
        const pz_goal_result *goals = &result->verdict.panels[p];
        ok &= add_plain_number(item, "corners", goals->corners);
        ok &= add_plain_number(item, "darts", darts[p]);
        ok &= add_plain_number(item, "mirror_panel", result->panel_mirror ? result->panel_mirror[p] : -1);
        /* The piece-shape figures the goals were judged on (docs/segment.md, "Piece shapes"). */
        ok &= add_plain_number(item, "area_share", pz_round(goals->area_share, 6));
        ok &= add_plain_number(item, "width_mm", pz_round(goals->min_width_mm, 3));
        ok &= add_plain_number(item, "across_grain_mm", pz_round(goals->across_grain_mm, 3));
        ok &= cJSON_AddBoolToObject(item, "shape_forced_by_input", goals->width_forced || goals->area_forced) != NULL;
        ok &= add_plain_number(item, "mirror_residual_mm",
                               result->panel_mirror_residual_mm ? pz_round(result->panel_mirror_residual_mm[p], 6) : -1);
        /* A grain hint's turn of the piece's warp from the global grain (docs/run.md, "Grain hints"). */
        if (result->panel_grain_turn)
            ok &= add_plain_number(item, "grain_turn_deg", pz_round(result->panel_grain_turn[p] * 180 / PZ_PI, 3));
        char text[256];
        pz_goal_describe(goals, &result->options.goals, text, sizeof text);
        ok &= cJSON_AddBoolToObject(item, "goals_met", goals->failures == 0) != NULL;
        if (goals->failures)
            ok &= cJSON_AddStringToObject(item, "goals", text) != NULL;
    }
    free(darts);
    return ok;
}

static int extend_symmetry(const pz_result *result, cJSON *object)
{
    const pz_segment_result *segment = result->segment;
    cJSON *symmetry = cJSON_AddObjectToObject(object, "symmetry");
    if (!symmetry)
        return 0;
    /* The plane the run found (or was given) before the field; the layout's own copy when it used it. */
    const pz_symmetry *plane = &result->symmetry;
    int used = result->symmetry_used && segment->symmetry.found;
    static const char *const axes[] = {"x", "y", "z"};
    int ok = cJSON_AddBoolToObject(symmetry, "found", plane->found) != NULL;
    ok &= cJSON_AddBoolToObject(symmetry, "used", used) != NULL;
    ok &= cJSON_AddBoolToObject(symmetry, "rejected_by_verdict", result->symmetry_rejected) != NULL;
    ok &= cJSON_AddBoolToObject(symmetry, "sketch_not_symmetric", result->symmetry_sketch_asymmetric) != NULL;
    ok &= cJSON_AddStringToObject(symmetry, "axis", !plane->found ? "none"
                                                     : plane->axis >= 0 && plane->axis < 3 ? axes[plane->axis]
                                                                                           : "oblique") != NULL;
    cJSON *normal = cJSON_AddArrayToObject(symmetry, "normal");
    for (int k = 0; normal && k < 3; ++k)
        ok &= cJSON_AddItemToArray(normal, cJSON_CreateNumber(pz_round(plane->normal[k], 9)));
    ok &= normal != NULL;
    ok &= add_plain_number(symmetry, "offset", plane->offset);
    ok &= add_plain_number(symmetry, "mesh_residual_mm", plane->residual_mm);
    ok &= add_plain_number(symmetry, "mesh_residual_rel", pz_round(plane->residual_rel, 6));
    ok &= add_plain_number(symmetry, "mesh_rms_mm", plane->rms_mm);
    /* The garment laid out (garment.obj) is the input made exactly symmetric: how far the input is from it. */
    ok &= cJSON_AddBoolToObject(symmetry, "symmetrized", result->symmetrized) != NULL;
    ok &= add_plain_number(symmetry, "symmetrized_max_mm", pz_round(result->symmetrized_max_mm, 4));
    ok &= add_plain_number(symmetry, "symmetrized_p95_mm", pz_round(result->symmetrized_p95_mm, 4));
    ok &= add_plain_number(symmetry, "pieces_with_plane", result->pieces_with_symmetry);
    ok &= add_plain_number(symmetry, "pieces_without_plane", result->pieces_without_symmetry);
    ok &= add_plain_number(symmetry, "layout_residual_mm", used ? segment->symmetry_residual_mm : 0);
    ok &= add_plain_number(symmetry, "mirror_pieces", used ? result->mirror_pieces : 0);
    ok &= add_plain_number(symmetry, "exact_mirror_pieces", used ? result->exact_mirror_pieces : 0);
    ok &= add_plain_number(symmetry, "pattern_residual_mm", pz_round(result->pattern_mirror_rms_mm, 6));
    ok &= add_plain_number(symmetry, "pattern_residual_max_mm", pz_round(result->pattern_mirror_max_mm, 6));
    return ok;
}

static int extend_segmentation(const pz_result *result, cJSON *root)
{
    cJSON *object = cJSON_AddObjectToObject(root, "segmentation");
    if (!object)
        return 0;
    const pz_run_options *options = &result->options;
    const pz_segment_result *segment = result->segment;
    int ok = cJSON_AddStringToObject(object, "panels", segment ? "automatic" : "given") != NULL;
    ok &= add_plain_number(object, "max_corners", options->goals.max_corners);
    ok &= add_plain_number(object, "max_strain", options->goals.max_strain);
    ok &= add_plain_number(object, "max_seam_mismatch", options->goals.max_seam_mismatch);
    ok &= cJSON_AddBoolToObject(object, "darts", options->segment.darts) != NULL;
    ok &= add_plain_number(object, "field_singularities", result->field_singularities);
    ok &= add_plain_number(object, "verdict_rounds", result->verdict_rounds);
    cJSON *truing = cJSON_AddObjectToObject(object, "truing");
    ok &= truing != NULL && cJSON_AddBoolToObject(truing, "on", options->truing && !result->truing_dropped) != NULL;
    ok &= truing != NULL && cJSON_AddBoolToObject(truing, "dropped", result->truing_dropped) != NULL;
    if (truing && options->truing && !result->truing_dropped) {
        const pz_truing_result *t = &result->truing;
        ok &= add_plain_number(truing, "moved_vertices", t->moved_vertices);
        ok &= add_plain_number(truing, "relaxed_vertices", t->relaxed_vertices);
        ok &= add_plain_number(truing, "max_move_mm", pz_round(t->max_move_mm, 3));
        ok &= add_plain_number(truing, "mean_turn_before_deg", pz_round(t->mean_turn_before_deg, 2));
        ok &= add_plain_number(truing, "mean_turn_after_deg", pz_round(t->mean_turn_after_deg, 2));
    }
    ok &= add_plain_number(object, "vetoed_panels", result->vetoed_panels);
    ok &= cJSON_AddBoolToObject(object, "consolidate", result->options.consolidate) != NULL;
    ok &= cJSON_AddBoolToObject(object, "mirror_sketch", result->options.mirror_sketch) != NULL;
    ok &= cJSON_AddBoolToObject(object, "field_reused", result->field_reused) != NULL;
    if (result->consolidated_from > 0) /* the first layout's pieces, before consolidation (docs/run.md) */
        ok &= add_plain_number(object, "consolidated_from", result->consolidated_from);
    /* Monotone panel counts: the looser settings laid out first, their cuts kept (docs/segment.md). */
    cJSON *ladder = cJSON_AddObjectToObject(object, "looser_goals");
    ok &= ladder != NULL;
    if (ladder) {
        ok &= add_plain_number(ladder, "settings", result->looser_settings);
        ok &= add_plain_number(ladder, "most_panels", result->looser_most_panels);
        ok &= cJSON_AddBoolToObject(ladder, "seeded", result->looser_seeded) != NULL;
        if (result->looser_reachable_strain > 0) {
            ok &= add_plain_number(ladder, "reachable_strain", result->looser_reachable_strain);
            ok &= add_plain_number(ladder, "reachable_panels", result->looser_reachable_panels);
            if (result->looser_written_strain > 0)
                ok &= add_plain_number(ladder, "written_strain", result->looser_written_strain);
            if (result->looser_direct) {
                ok &= cJSON_AddBoolToObject(ladder, "direct", 1) != NULL;
                ok &= add_plain_number(ladder, "probe_panels", result->looser_probe_panels);
            }
        }
        cJSON *timings = cJSON_AddObjectToObject(ladder, "timings_ms");
        ok &= timings && add_plain_number(timings, "total", pz_round(result->timings.looser_goals, 3));
    }
    if (!segment)
        return ok;
    ok &= add_plain_number(object, "candidates", segment->candidate_count);
    ok &= add_plain_number(object, "inserted", segment->inserted_count);
    ok &= add_plain_number(object, "removed", segment->removed_count);
    ok &= add_plain_number(object, "evaluations", segment->evaluation_count);
    ok &= add_plain_number(object, "merged_slivers", segment->merged_slivers);
    ok &= add_plain_number(object, "dart_count", segment->dart_count);
    ok &= cJSON_AddBoolToObject(object, "layout_goals_met", segment->goals_met) != NULL;
    if (segment->max_pieces > 0) {
        cJSON *budget = cJSON_AddObjectToObject(object, "max_pieces");
        ok &= budget && add_plain_number(budget, "pieces", segment->max_pieces);
        ok &= budget && cJSON_AddBoolToObject(budget, "met", segment->budget_met) != NULL;
        ok &= budget && add_plain_number(budget, "merges", segment->budget_merges);
        ok &= budget && add_plain_number(budget, "unmirrored_merges", segment->budget_unmirrored);
    }
    ok &= extend_symmetry(result, object);
    cJSON *timings = cJSON_AddObjectToObject(object, "timings_ms");
    ok &= timings != NULL;
    if (timings) {
        ok &= add_plain_number(timings, "graph", segment->graph_ms);
        ok &= add_plain_number(timings, "candidates", segment->candidates_ms);
        ok &= add_plain_number(timings, "insert", segment->insert_ms);
        ok &= add_plain_number(timings, "remove", segment->remove_ms);
        ok &= add_plain_number(timings, "darts", segment->darts_ms);
        ok &= add_plain_number(timings, "budget", segment->budget_ms);
        ok &= add_plain_number(timings, "tradeoff", result->tradeoff.ms);
        ok &= add_plain_number(timings, "total", segment->total_ms);
    }
    return ok;
}

static int extend_prepare(const pz_result *result, cJSON *root)
{
    cJSON *object = cJSON_AddObjectToObject(root, "prepare");
    if (!object)
        return 0;
    int automatic = result->options.prepare && result->segment != NULL;
    int ok = cJSON_AddStringToObject(object, "mode", automatic ? "auto" : "off") != NULL;
    if (!result->prepared)
        return ok;
    const pz_prepare_report *report = &result->prepared->report;
    cJSON *steps = cJSON_AddArrayToObject(object, "steps");
    ok &= steps != NULL;
    for (int i = 0; steps && i < PZ_PREPARE_STEP_COUNT; ++i) {
        cJSON *step = cJSON_CreateObject();
        ok &= step && cJSON_AddItemToArray(steps, step);
        if (!step)
            break;
        ok &= cJSON_AddStringToObject(step, "name", report->steps[i].name ? report->steps[i].name : "") != NULL;
        ok &= cJSON_AddBoolToObject(step, "ran", report->steps[i].ran) != NULL;
        ok &= cJSON_AddStringToObject(step, "detail", report->steps[i].detail) != NULL;
    }
    ok &= add_plain_number(object, "input_faces", report->input_faces);
    ok &= add_plain_number(object, "output_faces", report->output_faces);
    ok &= add_plain_number(object, "hausdorff_mm", report->hausdorff);
    ok &= add_plain_number(object, "welded_seams", result->prepared->seam_count);
    return ok;
}

/* "tradeoff": the pieces each strain goal of the grid needs (null: not measured that strictly), from the final
 * layout's merge sequence; "tradeoff_sequence": the sequence itself. Only for a segmentation. */
static int extend_tradeoff(const pz_result *result, cJSON *root)
{
    const pz_segment_tradeoff *tradeoff = &result->tradeoff;
    if (!result->segment)
        return 1;
    cJSON *curve = cJSON_AddArrayToObject(root, "tradeoff");
    cJSON *sequence = cJSON_AddArrayToObject(root, "tradeoff_sequence");
    int ok = curve && sequence;
    for (int i = 0; ok && tradeoff->count > 0 && i < PZ_TRADEOFF_GRID_COUNT; ++i) {
        cJSON *point = cJSON_CreateObject();
        ok = point && cJSON_AddItemToArray(curve, point);
        int32_t pieces = pz_tradeoff_pieces(tradeoff, pz_tradeoff_grid[i]);
        ok = ok && add_plain_number(point, "max_strain", pz_tradeoff_grid[i]);
        ok = ok && (pieces > 0 ? add_plain_number(point, "pieces", pieces) : cJSON_AddNullToObject(point, "pieces") != NULL);
    }
    for (int32_t i = 0; ok && i < tradeoff->count; ++i) {
        cJSON *step = cJSON_CreateObject();
        ok = step && cJSON_AddItemToArray(sequence, step);
        ok = ok && add_plain_number(step, "pieces", tradeoff->pieces[i]);
        ok = ok && add_plain_number(step, "worst_strain", pz_round(tradeoff->worst_strain[i], 6));
    }
    return ok;
}

/* "strain_outlook": can S be met with sound pieces (docs/run.md, "Can S be met?"). */
static int extend_outlook(const pz_result *result, cJSON *root)
{
    const pz_strain_outlook *outlook = &result->outlook;
    if (!outlook->measured)
        return 1;
    cJSON *object = cJSON_AddObjectToObject(root, "strain_outlook");
    int ok = object != NULL;
    ok = ok && cJSON_AddBoolToObject(object, "reachable", outlook->reachable) != NULL;
    ok = ok && add_plain_number(object, "suggested_max_strain", pz_round(outlook->suggested_strain, 4));
    ok = ok && add_plain_number(object, "pose_spread", pz_round(outlook->pose_spread, 6));
    ok = ok && add_plain_number(object, "piece_strain", pz_round(outlook->piece_strain, 6));
    ok = ok && add_plain_number(object, "piece_area_mm2", pz_round(outlook->piece_area_mm2, 1));
    ok = ok && add_plain_number(object, "samples", outlook->samples);
    ok = ok && add_plain_number(object, "ms", pz_round(outlook->ms, 3));
    return ok;
}

/* The goals, the segmentation and the preparation: what pz_run adds to pz_flatten's report. */
static int extend_run_report(const pz_result *result, cJSON *root)
{
    int ok = extend_panels(result, root);
    cJSON *summary = cJSON_GetObjectItem(root, "summary");
    if (ok && summary) {
        ok &= cJSON_AddBoolToObject(summary, "goals_met", result->verdict.goals_met) != NULL;
        ok &= add_plain_number(summary, "max_seam_mismatch_any_rel", pz_round(result->verdict.worst_seam_mismatch, 6));
        ok &= add_plain_number(summary, "area_over_max_strain", pz_round(result->verdict.area_over_strain, 6));
        if (!result->verdict.goals_met)
            ok &= cJSON_AddStringToObject(summary, "goals_reasons", result->verdict.reasons) != NULL;
    }
    cJSON *timings = cJSON_GetObjectItem(root, "timings_ms");
    if (ok && timings) {
        ok &= add_plain_number(timings, "prepare", pz_round(result->timings.prepare, 3));
        ok &= add_plain_number(timings, "field", pz_round(result->timings.field, 3));
        ok &= add_plain_number(timings, "segment", pz_round(result->timings.segment, 3));
    }
    return ok && extend_segmentation(result, root) && extend_prepare(result, root) && extend_tradeoff(result, root) &&
           extend_outlook(result, root);
}

/* ---------------------------------------------------------------- the report */

static void fill_view(const pz_result *result, report_view *view)
{
    const pz_run_options *options = &result->options;
    const pz_flatten_options *flatten = &options->flatten;
    static const char *const unnamed[1] = {"garment"};
    memset(view, 0, sizeof *view);
    if (options->input_files && options->input_file_count > 0) {
        view->input_paths = options->input_files;
        view->input_count = options->input_file_count;
    } else {
        view->input_paths = options->name ? &options->name : unnamed;
        view->input_count = 1;
    }
    view->vertices = result->garment->vertex_count;
    view->faces = result->garment->face_count;
    view->poses = result->garment->pose_count;
    view->units = pz_units_str(result->units);
    view->units_guessed = result->units_guessed;
    view->panels_source = result->panels_source;
    view->backend = pz_backend_name(flatten->backend);
    view->iterations = flatten->iterations;
    memcpy(view->weights, flatten->weights, sizeof view->weights);
    view->fabric = flatten->fabric;
    memcpy(view->grain, result->grain, sizeof view->grain);
    view->grain_hint_count = result->grain_hint_count;
    view->grain_source = result->grain_source;
    view->textile = flatten->backend == PZ_BACKEND_TEXTILE ? &result->backend.textile : NULL;
    view->wirewarp = flatten->backend == PZ_BACKEND_WIREWARP ? &result->backend.wirewarp : NULL;
    view->progressive = flatten->progressive;
    view->feature_count = result->backend.feature_count;
    view->skipped_features = result->backend.skipped;
    view->skipped_feature_count = result->backend.skipped_count;
    view->springmass = flatten->backend == PZ_BACKEND_SPRINGMASS ? &result->backend.springmass : NULL;
    view->relax_full = flatten->relax_full;
    view->orthotropic = flatten->fabric_given;
    view->backend_ms = result->backend.ms;
    view->uv = result->uv;
    view->layout_moved = result->layout_moved;
    const pz_timings *t = &result->timings;
    double timings[6] = {t->read, t->pattern, t->flatten, t->metrics, t->write, t->read + t->total + t->write};
    memcpy(view->timings_ms, timings, sizeof timings);
    view->pattern = result->pattern;
    view->metrics = (const pz_metrics *const *)result->metrics;
    view->metrics_count = result->metrics_count;
    view->panel_names = (const char *const *)result->panel_names;
}

cJSON *pz_result_report(const pz_result *result)
{
    if (!result || !result->pattern || !result->metrics)
        return NULL;
    report_view view;
    fill_view(result, &view);
    cJSON *root = flatten_report_json(&view);
    int failed = !root;
    if (root && result->marker) {
        cJSON *marker = pz_marker_report_json(result->marker);
        failed |= !marker || !cJSON_AddItemToObject(root, "marker", marker);
    }
    cJSON *input = root ? cJSON_GetObjectItem(root, "input") : NULL;
    if (input && result->garment->pose_count > 0) {
        cJSON *spread = cJSON_AddObjectToObject(input, "pose_edge_change");
        failed |= !spread || !add_plain_number(spread, "median", pz_round(result->pose_edge_change_median, 6)) ||
                  !add_plain_number(spread, "p95", pz_round(result->pose_edge_change_p95, 6));
    }
    if (root && !failed && result->from_run)
        failed |= !extend_run_report(result, root);
    if (failed) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}
