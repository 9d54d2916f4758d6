/*
 * pipeline/flatten.c -- the param stage as the pipeline drives it: the
 * chosen back-end flattens every panel (textile by default: pietroni2022
 * Sec. 4.3; LSCM; WireWarping, wang2008, with feature curves snapped leniently:
 * a curve off the mesh is left out with a warning; spring-mass, wang2002 with
 * the IISERM heap relaxation, orthotropic with a given fabric), the pieces
 * are laid out apart when they overlap, and the metrics are taken on every
 * pose.
 *
 * Layout: the back-ends place pieces as they like; when two pieces' bounding
 * boxes overlap, every piece is moved into rows ("shelves", tallest first),
 * found by a sort and a sweep over the boxes, O(P log P) in the panel count.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include "core/vec.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const backend_names[PZ_BACKEND_COUNT] = {"textile", "lscm", "wirewarp", "springmass"};

const char *pz_backend_name(pz_backend backend)
{
    return backend >= 0 && backend < PZ_BACKEND_COUNT ? backend_names[backend] : "unknown";
}

pz_backend pz_backend_parse(const char *name)
{
    for (int b = 0; name && b < PZ_BACKEND_COUNT; ++b)
        if (strcmp(name, backend_names[b]) == 0)
            return (pz_backend)b;
    return PZ_BACKEND_COUNT;
}

void pl_backend_outcome_clear(pz_backend_outcome *outcome)
{
    pz_springmass_result_clear(&outcome->springmass);
    free(outcome->skipped);
    memset(outcome, 0, sizeof *outcome);
}

/* ---------------------------------------------------------------- back-ends */

/* The feature curves a snap left out, growing as it reports them. */
typedef struct skipped_list {
    pz_backend_outcome *outcome;
    size_t capacity;
    int failed;                          /* out of memory while recording one */
} skipped_list;

/* pz_feature_curves_snap_lenient's report of a curve it left out. */
static void record_skipped_curve(void *user, int32_t curve, const char *problem)
{
    skipped_list *list = user;
    pz_backend_outcome *outcome = list->outcome;
    if ((size_t)outcome->skipped_count == list->capacity) {
        size_t capacity = list->capacity ? 2 * list->capacity : 4;
        pz_skipped_feature *bigger = realloc(outcome->skipped, capacity * sizeof *bigger);
        if (!bigger) {
            list->failed = 1;
            return;
        }
        outcome->skipped = bigger;
        list->capacity = capacity;
    }
    pz_skipped_feature *skipped = &outcome->skipped[outcome->skipped_count++];
    skipped->curve = curve;
    snprintf(skipped->problem, sizeof skipped->problem, "%s", problem);
}

/*
 * The features file: read in the input's units, converted like the mesh, snapped to the cut mesh's
 * edges. A malformed file fails (exit 65); a well-formed curve that cannot be snapped (off the mesh,
 * across panels) is left out and recorded in outcome->skipped (a warning and report.json say so): a
 * best-effort result. *kept_from gets, per curve used, its index in the file.
 */
static pz_status read_feature_curves(const char *path, const pz_pattern *pattern, double mm_per_unit,
                                     pz_feature_curves **out, int32_t **kept_from, pz_backend_outcome *outcome,
                                     pz_ctx *ctx)
{
    *out = NULL;
    *kept_from = NULL;
    if (!path)
        return PZ_OK;
    pl_feature_file file;
    pz_status status = pl_read_features(path, mm_per_unit, &file, ctx);
    if (status != PZ_OK)
        return status;
    uint8_t *skipped = calloc((size_t)file.curve_count + 1, 1);
    *kept_from = malloc((size_t)file.curve_count * sizeof(int32_t) + 1);
    skipped_list list = {outcome, 0, 0};
    if (!skipped || !*kept_from)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    if (status == PZ_OK)
        status = pz_feature_curves_snap_lenient(pattern, file.polylines, file.curve_count, 0, out, skipped,
                                                record_skipped_curve, &list, ctx);
    if (status == PZ_OK && list.failed)
        status = pz_error(ctx, PZ_ERR_NOMEM, "flatten: out of memory");
    for (int32_t c = 0, k = 0; status == PZ_OK && c < file.curve_count; ++c)
        if (!skipped[c])
            (*kept_from)[k++] = c;
    pl_feature_file_clear(&file);
    free(skipped);
    if (status != PZ_OK) {
        pz_feature_curves_free(out);
        free(*kept_from);
        *kept_from = NULL;
    }
    return status;
}

static pz_status flatten_wirewarp(const pz_flatten_options *settings, const pz_pattern *pattern, double mm_per_unit,
                                  const double grain[3], double *uv, pz_backend_outcome *outcome, pz_ctx *ctx)
{
    pz_feature_curves *features = NULL;
    int32_t *kept_from = NULL;
    pz_status status =
        read_feature_curves(settings->features_path, pattern, mm_per_unit, &features, &kept_from, outcome, ctx);
    if (status != PZ_OK)
        return status;
    outcome->feature_count = features ? features->curve_count : 0;
    pz_wirewarp_options options = {0};
    options.scheme = settings->progressive;
    options.grain_given = 1;
    memcpy(options.grain, grain, sizeof options.grain);
    status = pz_param_wirewarp(pattern, &options, features, uv, &outcome->wirewarp, ctx);
    /* The user knows the curves by their place in the file. */
    pz_wirewarp_result *r = &outcome->wirewarp;
    for (int32_t i = 0; kept_from && i < r->relaxed_key_curve_count && i < PZ_WIREWARP_RELAXED_MAX; ++i)
        r->relaxed_key_curves[i] = kept_from[r->relaxed_key_curves[i]];
    pz_feature_curves_free(&features);
    free(kept_from);
    return status;
}

void pl_warn_wirewarp(const pz_run_options *options, const pz_backend_outcome *outcome, pz_ctx *ctx)
{
    if (options->flatten.backend != PZ_BACKEND_WIREWARP)
        return;
    const char *file = options->flatten.features_path ? options->flatten.features_path : "--features";
    for (int32_t i = 0; i < outcome->skipped_count; ++i)
        pz_note(ctx, "warning: %s: %s; the curve is left out, the pattern is flattened with the %d other%s", file,
                outcome->skipped[i].problem, (int)outcome->feature_count, outcome->feature_count == 1 ? "" : "s");
    const pz_wirewarp_result *r = &outcome->wirewarp;
    if (r->relaxed_key_curve_count > 0) {
        char list[160] = "";
        size_t used = 0;
        for (int32_t i = 0; i < r->relaxed_key_curve_count && i < PZ_WIREWARP_RELAXED_MAX && used < sizeof list; ++i)
            used += (size_t)snprintf(list + used, sizeof list - used, "%s%d", i ? ", " : "",
                                     (int)r->relaxed_key_curves[i]);
        pz_note(ctx, "warning: %s: key curve%s %s%s over-constrain%s the pattern (the pieces cannot close with "
                "their angles fixed, wang2008 Figs. 13-14): best effort, %s angles relaxed by up to %.2f degrees, "
                "wire lengths kept (worst error %.2g)", file, r->relaxed_key_curve_count == 1 ? "" : "s", list,
                r->relaxed_key_curve_count > PZ_WIREWARP_RELAXED_MAX ? ", ..." : "",
                r->relaxed_key_curve_count == 1 ? "s" : "", r->relaxed_key_curve_count == 1 ? "its" : "their",
                r->relaxed_key_angle * 180 / PZ_PI, r->max_wire_error);
    }
    if (r->trimmed_feature_edges > 0 || r->flipped_triangles > 0 || !(r->constraint_residual <= 1e-9))
        pz_note(ctx, "warning: wirewarp: best effort: %d edge%s given up at dangling feature-curve ends, %d face%s "
                "still flipped, constraint residual %.2g, worst wire error %.2g",
                (int)r->trimmed_feature_edges, r->trimmed_feature_edges == 1 ? "" : "s", (int)r->flipped_triangles,
                r->flipped_triangles == 1 ? "" : "s", r->constraint_residual, r->max_wire_error);
}

static pz_status flatten_springmass(const pz_flatten_options *settings, const pz_pattern *pattern,
                                    const double grain[3], double *uv, pz_backend_outcome *outcome, pz_ctx *ctx)
{
    pz_springmass_options options = {0};
    options.relax = settings->relax_full;
    /* A given fabric asks for McCartney's warp/weft/shear energy; without it, isotropic springs (wang2002). */
    options.orthotropic = settings->fabric_given;
    options.fabric = settings->fabric;
    options.grain_given = 1;
    memcpy(options.grain, grain, sizeof options.grain);
    /* The trial cut classifies each suggested cutting line as dart or gusset (mccartney2005). */
    options.trial_cut = 1;
    return pz_param_springmass(pattern, &options, uv, &outcome->springmass, ctx);
}

static pz_status flatten_textile(const pz_flatten_options *settings, const pz_pattern *pattern,
                                 const double grain[3], const double *panel_turn, double strain_limit, double *uv,
                                 pz_textile_result *result, pz_ctx *ctx)
{
    pz_textile_options options = {0};
    options.iterations = settings->iterations;
    options.weights_given = 1;
    options.weight_stretch = settings->weights[0];
    options.weight_rigid = settings->weights[1];
    options.weight_dart = settings->weights[2];
    options.weight_seam = settings->weights[3];
    options.grain_given = 1;
    memcpy(options.grain, grain, sizeof options.grain);
    options.use_poses = pattern->mesh->pose_count > 0;
    options.strain_limit = strain_limit;
    options.panel_grain_turn = panel_turn;
    return pz_param_textile(pattern, &options, uv, result, ctx);
}

pz_status pl_flatten_pattern(const pz_run_options *options, const pz_pattern *pattern, double mm_per_unit,
                             const double grain[3], const double *panel_turn, double strain_limit, double *uv,
                             pz_backend_outcome *outcome, pz_ctx *ctx)
{
    const pz_flatten_options *settings = &options->flatten;
    double start = pz_seconds();
    pz_status status = pz_check_cancel(ctx, "flatten");
    if (status != PZ_OK)
        return status;
    switch (settings->backend) {
    case PZ_BACKEND_LSCM: status = pz_param_lscm_pattern(pattern, grain, uv, ctx); break;
    case PZ_BACKEND_WIREWARP:
        status = flatten_wirewarp(settings, pattern, mm_per_unit, grain, uv, outcome, ctx);
        break;
    case PZ_BACKEND_SPRINGMASS: status = flatten_springmass(settings, pattern, grain, uv, outcome, ctx); break;
    default:
        status = flatten_textile(settings, pattern, grain, panel_turn, strain_limit, uv, &outcome->textile, ctx);
        break;
    }
    /* The other back-ends have no grain term of their own: pieces with a grain hint are turned to it. */
    if (status == PZ_OK && settings->backend != PZ_BACKEND_TEXTILE)
        status = pz_param_turn_to_panel_grain(pattern, grain, panel_turn, uv, ctx);
    outcome->ms = pz_elapsed_ms(start, pz_seconds());
    return status;
}

pz_status pl_flatten_for_verdict(const pz_run_options *options, const pz_pattern *pattern, const double grain[3],
                                 const double *panel_turn, double strain_limit, double *uv, pz_ctx *ctx)
{
    if (options->flatten.backend == PZ_BACKEND_LSCM) {
        pz_status status = pz_param_lscm_pattern(pattern, grain, uv, ctx);
        return status == PZ_OK ? pz_param_turn_to_panel_grain(pattern, grain, panel_turn, uv, ctx) : status;
    }
    pz_textile_result result;
    return flatten_textile(&options->flatten, pattern, grain, panel_turn, strain_limit, uv, &result, ctx);
}

pz_status pl_measure(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric, pz_metrics **metrics,
                     int count, pz_ctx *ctx)
{
    for (int pose = 0; pose < count; ++pose) {
        pz_status status = pz_metrics_compute(pattern, uv, pose, fabric, &metrics[pose], ctx);
        if (status != PZ_OK)
            return status;
    }
    return PZ_OK;
}

double *pl_strain_of_poses(const pz_pattern *pattern, const double *uv, const pz_fabric *fabric, pz_ctx *ctx)
{
    double *strain = calloc((size_t)pattern->panel_count + 1, sizeof(double));
    pz_ctx quiet;
    pz_ctx_quiet(ctx, &quiet);
    for (int32_t pose = 1; strain && pose <= pattern->mesh->pose_count; ++pose) {
        pz_metrics *metrics = NULL;
        if (pz_metrics_compute(pattern, uv, pose, fabric, &metrics, &quiet) != PZ_OK) {
            free(strain);
            return NULL;
        }
        for (int32_t p = 0; p < pattern->panel_count && p < metrics->panel_count; ++p) {
            const pz_panel_metrics *panel = &metrics->panels[p];
            strain[p] = fmax(strain[p], fmax(fabs(panel->strain_warp.max), fabs(panel->strain_weft.max)));
        }
        pz_metrics_free(&metrics);
    }
    return strain;
}

/* ---------------------------------------------------------------- per-panel boxes */

typedef struct panel_box {
    double lo[2], hi[2];
    double area, centroid[2];  /* signed 2D area and area centroid of the piece */
    int32_t panel;
} panel_box;

static pz_status panel_boxes(const pz_pattern *pattern, const double *uv, panel_box **out, pz_ctx *ctx)
{
    int32_t panel_count = pattern->panel_count;
    panel_box *boxes = malloc(((size_t)panel_count + 1) * sizeof *boxes);
    if (!boxes)
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    for (int32_t p = 0; p < panel_count; ++p) {
        boxes[p] = (panel_box){{DBL_MAX, DBL_MAX}, {-DBL_MAX, -DBL_MAX}, 0, {0, 0}, p};
    }
    const pz_mesh *mesh = pattern->mesh;
    for (int32_t f = 0; f < mesh->face_count; ++f) {
        panel_box *box = &boxes[pattern->face_panel[f]];
        const double *a = &uv[2 * mesh->faces[3 * f]], *b = &uv[2 * mesh->faces[3 * f + 1]],
                     *c = &uv[2 * mesh->faces[3 * f + 2]];
        const double *corners[3] = {a, b, c};
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 2; ++d) {
                box->lo[d] = fmin(box->lo[d], corners[k][d]);
                box->hi[d] = fmax(box->hi[d], corners[k][d]);
            }
        double area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        box->area += area;
        for (int d = 0; d < 2; ++d)
            box->centroid[d] += area * (a[d] + b[d] + c[d]) / 3.0;
    }
    for (int32_t p = 0; p < panel_count; ++p) {
        panel_box *box = &boxes[p];
        if (fabs(box->area) > 0) {
            box->centroid[0] /= box->area;
            box->centroid[1] /= box->area;
        } else {
            box->centroid[0] = 0.5 * (box->lo[0] + box->hi[0]);
            box->centroid[1] = 0.5 * (box->lo[1] + box->hi[1]);
        }
    }
    *out = boxes;
    return PZ_OK;
}

/* ---------------------------------------------------------------- layout */

static int compare_box_lo_x(const void *a, const void *b)
{
    const panel_box *x = a, *y = b;
    return (x->lo[0] > y->lo[0]) - (x->lo[0] < y->lo[0]);
}

static int compare_box_height(const void *a, const void *b)
{
    const panel_box *x = a, *y = b;
    double hx = x->hi[1] - x->lo[1], hy = y->hi[1] - y->lo[1];
    if (hx != hy)
        return (hx < hy) - (hx > hy);  /* tallest first */
    return (x->panel > y->panel) - (x->panel < y->panel);
}

/* 1 when two boxes overlap: a sweep over the boxes sorted by min x. */
static int boxes_overlap(panel_box *boxes, int32_t count)
{
    qsort(boxes, (size_t)count, sizeof *boxes, compare_box_lo_x);
    for (int32_t i = 0; i < count; ++i)
        for (int32_t j = i + 1; j < count && boxes[j].lo[0] < boxes[i].hi[0]; ++j)
            if (boxes[j].lo[1] < boxes[i].hi[1] && boxes[i].lo[1] < boxes[j].hi[1])
                return 1;
    return 0;
}

pz_status pl_pattern_layout(const pz_pattern *pattern, double *uv, double gap_mm, int *moved, pz_ctx *ctx)
{
    *moved = 0;
    int32_t panel_count = pattern->panel_count;
    panel_box *boxes = NULL;
    pz_status status = panel_boxes(pattern, uv, &boxes, ctx);
    if (status != PZ_OK)
        return status;
    if (!boxes_overlap(boxes, panel_count)) {
        free(boxes);
        return PZ_OK;
    }
    double *shift = calloc(2 * (size_t)panel_count + 1, sizeof(double));
    if (!shift) {
        free(boxes);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    }
    /* Rows about as wide as the layout will be tall: the square root of the total box area. */
    double box_area = 0, widest = 0;
    for (int32_t i = 0; i < panel_count; ++i) {
        double width = boxes[i].hi[0] - boxes[i].lo[0], height = boxes[i].hi[1] - boxes[i].lo[1];
        box_area += (width + gap_mm) * (height + gap_mm);
        widest = fmax(widest, width);
    }
    double row_width = fmax(widest, 1.2 * sqrt(box_area));
    qsort(boxes, (size_t)panel_count, sizeof *boxes, compare_box_height);
    double x = 0, row_top = 0, row_height = 0;
    for (int32_t i = 0; i < panel_count; ++i) {
        const panel_box *box = &boxes[i];
        double width = box->hi[0] - box->lo[0], height = box->hi[1] - box->lo[1];
        if (x > 0 && x + width > row_width) {
            row_top -= row_height + gap_mm;
            x = 0;
            row_height = 0;
        }
        shift[2 * box->panel] = x - box->lo[0];
        shift[2 * box->panel + 1] = row_top - box->hi[1];
        x += width + gap_mm;
        row_height = fmax(row_height, height);
    }
    /* Each cut-mesh vertex belongs to one panel: move it with that panel's shift. */
    const pz_mesh *mesh = pattern->mesh;
    uint8_t *done = calloc((size_t)mesh->vertex_count + 1, 1);
    if (!done) {
        free(shift);
        free(boxes);
        return pz_error(ctx, PZ_ERR_NOMEM, "out of memory laying out %d panels", (int)panel_count);
    }
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c) {
        int32_t v = mesh->faces[c], p = pattern->face_panel[c / 3];
        if (done[v])
            continue;
        done[v] = 1;
        uv[2 * v] += shift[2 * p];
        uv[2 * v + 1] += shift[2 * p + 1];
    }
    free(done);
    free(shift);
    free(boxes);
    *moved = 1;
    return PZ_OK;
}

