/*
 * prepare/prepare.c -- scan-ready input (issue 8, docs/prepare.md): turns a scan
 * or an export (millions of faces, slivers, non-manifold vertices, fragments,
 * unwelded panels) into the manifold, well-shaped mesh the paper assumes
 * ("otherwise we uniformly remesh with standard tools").
 *
 * Steps, in order, on a copy of the input (which is in mm); each file's
 * header has the details:
 *  1. weld: vertices closer than --weld join; edges welding joined are
 *     seams, kept as constraints and returned as polylines (prepare/weld.c).
 *  2. repair: non-finite, degenerate, duplicate and non-manifold-edge faces
 *     dropped, non-manifold vertices split, faces oriented, seams followed
 *     through every renumbering (prepare/repair.c).
 *  3. fragments: components under 1% of the total area are dropped (--keep
 *     all keeps them). Nothing left is PZ_ERR_INVALID_MESH (prepare/repair.c).
 *  4. decimate when the mesh has more than 4x the faces remeshing will
 *     produce: thinning, then CGAL edge collapse when thinning stalls
 *     (prepare/decimate.c, prepare/remesh.c).
 *  5. remesh (CGAL isotropic_remeshing, Botsch & Kobbelt 2004) to the target
 *     edge, by default the one giving ~20K faces; outline, seams, their
 *     corners and creases kept (prepare/remesh.c).
 *  6. poses and labels carried from the repaired rest mesh to the output
 *     through closest points (prepare/carry.c).
 *  7. hausdorff: symmetric sampled distance between the repaired input and
 *     the output, per pose, against 0.5% of the bounding-box diagonal;
 *     exceeding it is reported, not fatal (prepare/carry.c).
 *
 * Automatic mode (pz_prepare_auto, `run --prepare auto`) runs 4-7 only for
 * a mesh over 10000 faces (remeshed to 10000; beyond the Hausdorff bound,
 * again at twice the faces up to 40000, then undone) or one with under 95%
 * of its faces well shaped (remeshed at its own density, undone when that
 * leaves the bound); see prepare/auto.c and docs/prepare.md.
 *
 * Memory: a few arrays of 3F ints and the CGAL structures (~250 B/face for a
 * Surface_mesh, ~150 B/face for an AABB tree); for a 1M-face input the peak
 * is ~0.35 GB (2M faces: 0.8 GB), in the Hausdorff step (bench/bench_prepare.c).
 * Failure: every error leaves *out NULL and frees everything.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "prepare/internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_WELD_MM 0.01
#define DEFAULT_FACES 20000
#define DEFAULT_FRAGMENT_FRACTION 0.01
#define DEFAULT_ITERATIONS 5
#define HAUSDORFF_FRACTION 0.005

void prep_step_done(prep_step_state *state, pz_prepare_step_id id, int ran, double started, const char *fmt, ...)
{
    pz_prepare_step *step = &state->report->steps[id];
    va_list args;
    va_start(args, fmt);
    vsnprintf(step->detail, sizeof step->detail, fmt, args);
    va_end(args);
    step->ran = ran;
    step->seconds = pz_seconds() - started;
    pz_note(state->ctx, "%s: prepare: %s: %s (%.2f s)", state->name, step->name, step->detail, step->seconds);
}

double prep_well_shaped_fraction(const pz_mesh *mesh)
{
    if (mesh->face_count == 0)
        return 1.0;
    double *angles = malloc(3 * (size_t)mesh->face_count * sizeof(double));
    if (!angles)
        return 0.0;
    pz_geom_corner_angles(mesh, angles);
    int32_t good = 0;
    double limit = 20.0 * 3.14159265358979323846 / 180.0;
    for (int32_t f = 0; f < mesh->face_count; ++f)
        good += angles[3 * f] > limit && angles[3 * f + 1] > limit && angles[3 * f + 2] > limit;
    free(angles);
    return (double)good / mesh->face_count;
}

/* ------------------------------------------------------------------------ */
/* Seams as polylines                                                        */
/* ------------------------------------------------------------------------ */

/*
 * Chains the seam edges into polylines: open chains start at vertices whose
 * seam degree is not 2 (ends and junctions), then the closed loops remain.
 */
static pz_status chain_seams(pz_prepare_result *result, const int32_t *pairs, int32_t edge_count, pz_ctx *ctx)
{
    int32_t n = result->mesh->vertex_count;
    int32_t *offset = calloc((size_t)n + 2, sizeof(int32_t));
    int32_t *adjacent = malloc(2 * (size_t)edge_count * sizeof(int32_t) + 1); /* edge ids per vertex */
    uint8_t *used = calloc((size_t)edge_count + 1, 1);
    result->seam_offsets = malloc(((size_t)edge_count + 2) * sizeof(int32_t));
    result->seam_vertices = malloc(2 * (size_t)edge_count * sizeof(int32_t) + 1);
    if (!offset || !adjacent || !used || !result->seam_offsets || !result->seam_vertices) {
        free(offset);
        free(adjacent);
        free(used);
        return pz_error(ctx, PZ_ERR_NOMEM, "prepare: out of memory chaining seams");
    }
    for (int32_t e = 0; e < 2 * edge_count; ++e)
        ++offset[pairs[e] + 2];
    for (int32_t v = 0; v < n; ++v)
        offset[v + 2] += offset[v + 1];
    for (int32_t e = 0; e < 2 * edge_count; ++e)
        adjacent[offset[pairs[e] + 1]++] = e / 2;
    /* offset[v] .. offset[v+1] now lists v's seam edges */
    int32_t written = 0;
    result->seam_offsets[0] = 0;
    for (int pass = 0; pass < 2; ++pass)
        for (int32_t start = 0; start < n; ++start) {
            int32_t degree = offset[start + 1] - offset[start];
            if (pass == 0 ? (degree == 0 || degree == 2) : degree == 0)
                continue;
            for (int32_t i = offset[start]; i < offset[start + 1]; ++i) {
                if (used[adjacent[i]])
                    continue;
                int32_t v = start, e = adjacent[i];
                result->seam_vertices[written++] = v;
                while (e >= 0) {
                    used[e] = 1;
                    v = pairs[2 * e] == v ? pairs[2 * e + 1] : pairs[2 * e];
                    result->seam_vertices[written++] = v;
                    e = -1;
                    if (offset[v + 1] - offset[v] == 2) /* continue through a plain seam vertex */
                        for (int32_t j = offset[v]; j < offset[v + 1]; ++j)
                            if (!used[adjacent[j]])
                                e = adjacent[j];
                }
                result->seam_offsets[++result->seam_count] = written;
            }
        }
    free(offset);
    free(adjacent);
    free(used);
    return PZ_OK;
}

/* ------------------------------------------------------------------------ */
/* The driver                                                                */
/* ------------------------------------------------------------------------ */

void pz_prepare_result_free(pz_prepare_result **result)
{
    if (!result || !*result)
        return;
    pz_mesh_free(&(*result)->mesh);
    free((*result)->seam_offsets);
    free((*result)->seam_vertices);
    free(*result);
    *result = NULL;
}

static void fill_plan(const pz_prepare_options *options, prep_plan *plan)
{
    plan->weld = options->weld_distance == 0.0 ? DEFAULT_WELD_MM : options->weld_distance;
    plan->fraction = options->fragment_fraction > 0.0 ? options->fragment_fraction : DEFAULT_FRAGMENT_FRACTION;
    plan->target_faces = options->target_faces > 0 ? options->target_faces : DEFAULT_FACES;
    plan->target_edge = options->target_edge;
    plan->iterations = options->iterations > 0 ? options->iterations : DEFAULT_ITERATIONS;
}

static const char *const step_names[PZ_PREPARE_STEP_COUNT] = {"weld", "repair", "fragments", "decimate",
                                                              "remesh", "poses", "hausdorff"};

/* Steps 1-3 on *work. */
static pz_status clean(pz_mesh *work, const char *name, const prep_plan *plan, pz_prepare_keep keep,
                       prep_edge_list *seams, prep_step_state *state, pz_ctx *ctx)
{
    pz_prepare_report *report = state->report;
    double started = pz_seconds();
    pz_status status = PZ_OK;
    if (plan->weld > 0.0 && (status = prep_weld(work, plan->weld, seams, &report->welded_vertices, ctx)))
        return status;
    report->seam_edges = seams->count;
    if (plan->weld > 0.0)
        prep_step_done(state, PZ_PREPARE_WELD, report->welded_vertices > 0, started,
                       "%d vertices welded within %g mm, %d seam edges", (int)report->welded_vertices, plan->weld,
                       (int)report->seam_edges);
    else
        prep_step_done(state, PZ_PREPARE_WELD, 0, started, "off");
    started = pz_seconds();
    if ((status = prep_repair(work, name, seams, report, ctx)))
        return status;
    if (work->face_count == 0)
        return pz_error(ctx, PZ_ERR_INVALID_MESH,
                        "%s: nothing left after repair (%d faces: all degenerate, duplicate or not finite)", name,
                        (int)report->input_faces);
    int repaired = report->nonfinite_faces + report->degenerate_faces + report->duplicate_faces +
                   report->nonmanifold_edge_faces + report->split_vertices + report->flipped_faces;
    prep_step_done(state, PZ_PREPARE_REPAIR, repaired > 0, started,
                   "dropped %d non-finite, %d degenerate, %d duplicate, %d non-manifold-edge faces; split %d "
                   "non-manifold vertices; flipped %d faces",
                   (int)report->nonfinite_faces, (int)report->degenerate_faces, (int)report->duplicate_faces,
                   (int)report->nonmanifold_edge_faces, (int)report->split_vertices, (int)report->flipped_faces);
    started = pz_seconds();
    if ((status = prep_drop_fragments(work, name, plan->fraction, keep, seams, report, ctx)))
        return status;
    prep_step_done(state, PZ_PREPARE_FRAGMENTS, report->dropped_components > 0, started,
                   "%d components, dropped %d under %g%% of the area (%d faces)%s", (int)report->components,
                   (int)report->dropped_components, 100.0 * plan->fraction, (int)report->dropped_component_faces,
                   keep == PZ_PREPARE_KEEP_ALL ? "; --keep all" : "");
    return PZ_OK;
}

pz_status prep_remesh_all(const pz_mesh *work, const prep_edge_list *seams, const char *name, const prep_plan *plan,
                          const char *why, pz_prepare_result *result, prep_step_state *state, pz_ctx *ctx)
{
    pz_cgal_surface remeshed = {0};
    /* Cancellation is checked between the steps: each is under a second on a 50K-face garment. */
    pz_status status = pz_check_cancel(ctx, name);
    if (!status)
        status = prep_decimate_and_remesh(work, seams, name, plan, why, &result->mesh, &remeshed, state, ctx);
    if (!status)
        status = pz_check_cancel(ctx, name);
    if (!status)
        status = prep_carry_and_measure(work, result->mesh, state, ctx);
    if (!status)
        status = chain_seams(result, remeshed.edges, remeshed.edge_count, ctx);
    pz_cgal_surface_clear(&remeshed);
    return status;
}

/* Steps 4-7 when the repaired mesh is the result; *work passes to result->mesh. */
static pz_status keep_repaired(pz_mesh **work, const prep_edge_list *seams, const prep_plan *plan, const char *why,
                               int undone, pz_prepare_result *result, prep_step_state *state, pz_ctx *ctx)
{
    double now = pz_seconds();
    prep_step_done(state, PZ_PREPARE_DECIMATE, 0, now, "%s", undone ? "not needed: remeshing was undone" : why);
    prep_step_done(state, PZ_PREPARE_REMESH, 0, now, "%s", why);
    prep_step_done(state, PZ_PREPARE_POSES, 0, now, "%d poses kept as they are", (int)(*work)->pose_count);
    prep_step_done(state, PZ_PREPARE_HAUSDORFF, 0, now, "geometry unchanged (welding moves vertices by at most %g mm)",
                   plan->weld > 0.0 ? plan->weld : 0.0);
    result->mesh = *work; /* the result frees it from here on */
    *work = NULL;
    return chain_seams(result, seams->pairs, seams->count, ctx);
}

static pz_status run_prepare(const pz_mesh *mesh, const pz_prepare_options *options, const char *name,
                             pz_prepare_result *result, pz_ctx *ctx)
{
    pz_prepare_report *report = &result->report;
    prep_step_state state = {ctx, name, report};
    prep_plan plan;
    fill_plan(options, &plan);
    report->input_vertices = mesh->vertex_count;
    report->input_faces = mesh->face_count;
    pz_mesh *work = NULL;
    prep_edge_list seams = {0};
    pz_status status = pz_mesh_copy(mesh, &work, ctx);
    if (!status)
        status = clean(work, name, &plan, options->keep, &seams, &state, ctx);
    if (!status)
        status = pz_check_cancel(ctx, name);
    if (!status) {
        double lo[3], hi[3];
        pz_mesh_bbox(work, lo, hi);
        report->bbox_diagonal = prep_distance3(lo, hi);
        report->hausdorff_bound = HAUSDORFF_FRACTION * report->bbox_diagonal;
        report->within_bound = 1;
    }
    char why[256] = "";
    prep_auto_need need = PREP_NEED_DENSITY;
    int undone = 0, automatic = 0;
    double work_shaped = 1.0;
    if (!status && options->no_remesh) {
        need = PREP_NEED_NOTHING;
        snprintf(why, sizeof why, "off");
    } else if (!status && options->automatic && plan.target_edge <= 0.0) {
        automatic = 1;
        work_shaped = prep_well_shaped_fraction(work);
        need = prep_auto_decide(work, options, work_shaped, &plan, why, sizeof why);
    }
    if (!status && need != PREP_NEED_NOTHING) {
        status = prep_remesh_all(work, &seams, name, &plan, why, result, &state, ctx);
        if (status == PZ_ERR_USAGE && automatic) {
            /* The automatic mode chose the density itself: a mesh too coarse or too small to remesh at it (a
             * two-triangle quad) is kept as it is, never a usage error the user did not make. */
            snprintf(why, sizeof why, "auto: not remeshed: %.200s", ctx->error);
            pz_mesh_free(&result->mesh);
            status = PZ_OK;
            need = PREP_NEED_NOTHING;
        }
        if (!status && automatic && need == PREP_NEED_DENSITY && !report->within_bound)
            status = prep_retry_denser(work, &seams, name, &plan, work_shaped, why, sizeof why, &undone, result, &state,
                                       ctx);
        if (!status && need == PREP_NEED_SHAPE && !report->within_bound) {
            prep_undo_remesh(result, why, sizeof why);
            undone = 1;
        }
        if (undone)
            need = PREP_NEED_NOTHING;
    }
    if (!status && need == PREP_NEED_NOTHING)
        status = keep_repaired(&work, &seams, &plan, why, undone, result, &state, ctx);
    if (!status) {
        report->output_vertices = result->mesh->vertex_count;
        report->output_faces = result->mesh->face_count;
        report->min_angle_over_20_fraction = prep_well_shaped_fraction(result->mesh);
    }
    free(seams.pairs);
    pz_mesh_free(&work);
    return status;
}

pz_status pz_prepare(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_prepare_options defaults = {0};
    if (!options)
        options = &defaults;
    const char *name = options->name ? options->name : "mesh";
    if (mesh->face_count == 0 || mesh->vertex_count == 0)
        return pz_error(ctx, PZ_ERR_INVALID_MESH, "%s: the mesh has no faces", name);
    if (!isfinite(options->weld_distance) || !isfinite(options->target_edge) || options->target_edge < 0.0 ||
        options->target_faces < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: bad preparation options", name);
    pz_prepare_result *result = calloc(1, sizeof *result);
    if (!result)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", name);
    for (int s = 0; s < PZ_PREPARE_STEP_COUNT; ++s)
        result->report.steps[s].name = step_names[s];
    pz_status status = run_prepare(mesh, options, name, result, ctx);
    if (status) {
        pz_prepare_result_free(&result);
        return status;
    }
    *out = result;
    return PZ_OK;
}

pz_status pz_prepare_auto(const pz_mesh *mesh, const pz_prepare_options *options, pz_prepare_result **out,
                          pz_ctx *ctx)
{
    pz_prepare_options automatic = {0};
    if (options)
        automatic = *options;
    automatic.automatic = 1;
    return pz_prepare(mesh, &automatic, out, ctx);
}

pz_status pz_prepare_write_seams(const pz_prepare_result *result, const char *path, pz_ctx *ctx)
{
    pz_output out;
    pz_status status = pz_output_open(&out, path, "w", ctx);
    if (status)
        return status;
    fputs("{\"curves\": [", out.file);
    for (int32_t s = 0; s < result->seam_count; ++s) {
        fputs(s ? ",\n  [" : "\n  [", out.file);
        for (int32_t i = result->seam_offsets[s]; i < result->seam_offsets[s + 1]; ++i) {
            const double *p = result->mesh->positions + 3 * (size_t)result->seam_vertices[i];
            fprintf(out.file, "%s[%.6f, %.6f, %.6f]", i > result->seam_offsets[s] ? ", " : "", p[0], p[1], p[2]);
        }
        fputc(']', out.file);
    }
    fputs(result->seam_count ? "\n]}\n" : "]}\n", out.file);
    return pz_output_commit(&out, ctx);
}

void pz_prepare_options_default(pz_prepare_options *options)
{
    memset(options, 0, sizeof *options);
}
