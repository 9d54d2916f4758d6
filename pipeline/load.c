/*
 * pipeline/load.c -- the load stage: the caller's mesh copied (it stays the
 * caller's, unchanged), converted to millimetres, prepared when the run asks
 * for it (weld, repair, remesh: prepare/), repaired as the options ask and
 * validated.
 *
 * Vertex ids: the user's panels, seams and darts name the caller's vertices
 * and faces, so the map from the caller's ("raw") ids to the prepared
 * garment's is kept: dropping unreferenced vertices is a known compaction;
 * any other change (a repair that drops faces, the automatic preparation)
 * means the ids no longer apply, and ids_preserved says so.
 *
 * garment.obj keeps the input's coordinates exactly: positions_out holds the
 * caller's own numbers while the ids still match (x * 10 / 10 need not give
 * x back), and the prepared positions in the input's units otherwise.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#include "pipeline/internal.h"

#include "core/vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void pl_garment_clear(pl_garment *garment)
{
    pz_mesh_free(&garment->mesh);
    free(garment->raw_to_garment);
    memset(garment, 0, sizeof *garment);
}

/* Raw id -> id after dropping unreferenced vertices (the compaction pz_mesh_prepare does first). */
static pz_status map_raw_ids(const pz_mesh *mesh, pl_garment *garment, int32_t *kept, pz_ctx *ctx)
{
    garment->raw_vertex_count = mesh->vertex_count;
    garment->raw_face_count = mesh->face_count;
    garment->raw_to_garment = malloc(((size_t)mesh->vertex_count + 1) * sizeof(int32_t));
    if (!garment->raw_to_garment)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", "flatten");
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        garment->raw_to_garment[v] = -1;
    for (int32_t c = 0; c < 3 * mesh->face_count; ++c)
        if (mesh->faces[c] >= 0 && mesh->faces[c] < mesh->vertex_count)
            garment->raw_to_garment[mesh->faces[c]] = 0;
    *kept = 0;
    for (int32_t v = 0; v < mesh->vertex_count; ++v)
        if (garment->raw_to_garment[v] == 0)
            garment->raw_to_garment[v] = (*kept)++;
    return PZ_OK;
}

/*
 * The automatic preparation (pz_run): its steps are summarized in notes
 * here, not noted one by one. The prepared mesh replaces the garment only
 * when it changed something; result->prepared keeps the report.
 */
static pz_status prepare_automatically(const pz_run_options *options, pz_result *result, pz_mesh **mesh,
                                       int *changed, pz_ctx *ctx)
{
    *changed = 0;
    double start = pz_seconds();
    pz_prepare_options prepare_options = options->prepare_options;
    prepare_options.name = options->name;
    int quiet = ctx->quiet;
    ctx->quiet = 1;
    pz_status status = pz_prepare_auto(*mesh, &prepare_options, &result->prepared, ctx);
    ctx->quiet = quiet;
    result->timings.prepare = pz_elapsed_ms(start, pz_seconds());
    if (status != PZ_OK)
        return status;
    const pz_prepare_report *report = &result->prepared->report;
    /* Any step that changed the mesh (an orientation flip keeps the counts) makes the prepared one the
     * garment; the report steps say which ran. */
    int any_change = report->output_faces != report->input_faces || report->output_vertices != report->input_vertices;
    for (int i = 0; i < PZ_PREPARE_STEP_COUNT; ++i)
        any_change |= report->steps[i].ran && i != PZ_PREPARE_HAUSDORFF && i != PZ_PREPARE_POSES;
    for (int i = 0; i < PZ_PREPARE_STEP_COUNT; ++i) {
        const pz_prepare_step *step = &report->steps[i];
        /* A remesh that was tried and undone says why; one that was not needed stays quiet. */
        int tried = i == PZ_PREPARE_REMESH && strstr(step->detail, "undone") != NULL;
        if ((step->ran || tried) && i != PZ_PREPARE_HAUSDORFF)
            pz_note(ctx, "run: prepare: %s%s: %s", step->name, step->ran ? "" : " (not kept)", step->detail);
    }
    if (any_change) {
        pz_mesh_free(mesh);
        *mesh = result->prepared->mesh;
        result->prepared->mesh = NULL;
        *changed = 1;
    }
    return PZ_OK;
}

/* The extent (bounding-box diagonal) of positions (vertex_count x 3). */
static double extent_of(const double *positions, int32_t vertex_count)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int32_t v = 0; v < vertex_count; ++v)
        for (int k = 0; k < 3; ++k)
            lo[k] = fmin(lo[k], positions[3 * (size_t)v + k]), hi[k] = fmax(hi[k], positions[3 * (size_t)v + k]);
    return vertex_count > 0 ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                   (hi[2] - lo[2]) * (hi[2] - lo[2]))
                            : 0.0;
}

/*
 * Extra poses are refused, not repaired, when they cannot be the same garment
 * in another position: a non-finite coordinate (a repair would drop the
 * garment's faces for a pose's fault), or a size more than twice or less than
 * half the rest pose's (a pose in other units: the layout would chase a
 * thousandfold strain).
 */
static pz_status check_poses(const pz_mesh *mesh, const char *name, pz_ctx *ctx)
{
    double rest = extent_of(mesh->positions, mesh->vertex_count);
    for (int32_t p = 0; p < mesh->pose_count; ++p) {
        const double *pose = mesh->poses + (size_t)p * mesh->vertex_count * 3;
        for (size_t i = 0; i < 3 * (size_t)mesh->vertex_count; ++i)
            if (!isfinite(pose[i]))
                return pz_error(ctx, PZ_ERR_DATA, "%s: pose %d: vertex %d has a non-finite coordinate", name,
                                (int)p + 1, (int)(i / 3));
        double extent = extent_of(pose, mesh->vertex_count);
        if (rest > 0 && (extent > 2 * rest || extent < 0.5 * rest))
            return pz_error(ctx, PZ_ERR_DATA,
                            "%s: pose %d is %.4g units across where the rest pose is %.4g: not the same garment, or "
                            "in other units (convert it to the rest pose's)",
                            name, (int)p + 1, extent, rest);
    }
    return PZ_OK;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/*
 * How much the poses stretch the surface: every edge's relative length change
 * against the rest pose, over all poses; the median and the 95th percentile.
 * A strain goal below what the poses themselves change cannot be met in
 * every pose: said before the long work (docs/run.md).
 */
static void measure_pose_spread(const pz_mesh *mesh, pz_result *result, pz_ctx *ctx)
{
    result->pose_edge_change_median = result->pose_edge_change_p95 = 0;
    if (mesh->pose_count == 0 || mesh->face_count == 0)
        return;
    size_t count = 3 * (size_t)mesh->face_count * (size_t)mesh->pose_count;
    double *change = malloc(count * sizeof(double));
    if (!change)
        return;
    size_t n = 0;
    for (int32_t p = 0; p < mesh->pose_count; ++p) {
        const double *pose = mesh->poses + (size_t)p * mesh->vertex_count * 3;
        for (int32_t f = 0; f < mesh->face_count; ++f)
            for (int k = 0; k < 3; ++k) {
                int32_t a = mesh->faces[3 * (size_t)f + k], b = mesh->faces[3 * (size_t)f + (k + 1) % 3];
                double rest = pz_vec3_distance(mesh->positions + 3 * (size_t)a, mesh->positions + 3 * (size_t)b);
                double posed = pz_vec3_distance(pose + 3 * (size_t)a, pose + 3 * (size_t)b);
                if (rest > 0)
                    change[n++] = fabs(posed / rest - 1.0);
            }
    }
    qsort(change, n, sizeof(double), compare_double);
    if (n > 0) {
        result->pose_edge_change_median = change[n / 2];
        result->pose_edge_change_p95 = change[(size_t)(0.95 * (double)(n - 1))];
    }
    free(change);
    if (result->from_run && result->pose_edge_change_p95 > result->options.goals.max_strain)
        pz_note(ctx, "run: the poses change 5 %% of the edge lengths by more than %.3g (median %.3g): a strain goal "
                "below about %.2g is unlikely to be met in every pose (S = %g)",
                result->pose_edge_change_p95, result->pose_edge_change_median, result->pose_edge_change_p95,
                result->options.goals.max_strain);
}

/* garment.obj's vertex positions in the input's units (see the file comment). */
static pz_status output_positions(const pz_mesh *input, const pl_garment *garment, pz_result *result, pz_ctx *ctx)
{
    const pz_mesh *mesh = garment->mesh;
    result->positions_out = malloc(((size_t)mesh->vertex_count + 1) * 3 * sizeof(double));
    if (!result->positions_out)
        return pz_error(ctx, PZ_ERR_NOMEM, "%s: out of memory", pl_who(result));
    if (garment->ids_preserved) {
        for (int32_t v = 0; v < garment->raw_vertex_count; ++v)
            if (garment->raw_to_garment[v] >= 0)
                memcpy(result->positions_out + 3 * (size_t)garment->raw_to_garment[v],
                       input->positions + 3 * (size_t)v, 3 * sizeof(double));
        return PZ_OK;
    }
    for (size_t i = 0; i < 3 * (size_t)mesh->vertex_count; ++i)
        result->positions_out[i] = mesh->positions[i] / mesh->unit_scale;
    return PZ_OK;
}

/* The warp direction: the options' grain, or the garment's vertical axis. */
static void choose_grain(const pz_run_options *options, const pz_mesh *mesh, pz_result *result)
{
    if (options->flatten.grain_given) {
        memcpy(result->grain, options->flatten.grain, sizeof result->grain);
        result->grain_source = "given";
        return;
    }
    /* y-up (glTF, CLO3D, Blender) and z-up (scanners, CAD) garments both get the warp along their height. */
    pz_mesh_vertical_axis(mesh, result->grain);
    result->grain_source = result->grain[1] > 0.5 ? "vertical axis (y)" : "vertical axis (z)";
}

pz_status pl_load(const pz_mesh *input, const pz_run_options *options, int prepare, pz_result *result,
                  pl_garment *garment, pz_ctx *ctx)
{
    memset(garment, 0, sizeof *garment);
    if (!input || input->vertex_count < 0 || input->face_count < 0)
        return pz_error(ctx, PZ_ERR_USAGE, "%s: no mesh", pl_who(result));
    int32_t kept = 0;
    pz_status status = pz_mesh_copy(input, &garment->mesh, ctx);
    if (status == PZ_OK)
        status = map_raw_ids(input, garment, &kept, ctx);
    if (status != PZ_OK)
        return status;
    const char *name = options->name ? options->name : "garment";
    if ((status = check_poses(garment->mesh, name, ctx)) != PZ_OK)
        return status;
    pz_mesh_to_mm(garment->mesh, options->units, &result->units);
    result->units_guessed = options->units == PZ_UNITS_AUTO;
    measure_pose_spread(garment->mesh, result, ctx);
    int prepared = 0;
    if (prepare && (status = prepare_automatically(options, result, &garment->mesh, &prepared, ctx)) != PZ_OK)
        return status;
    status = pz_mesh_prepare_quietly_first(&garment->mesh, name, options->repair_flags, ctx);
    if (status != PZ_OK)
        return status;
    const pz_mesh *mesh = garment->mesh;
    garment->ids_preserved = !prepared && mesh->face_count == garment->raw_face_count && mesh->vertex_count == kept;
    status = output_positions(input, garment, result, ctx);
    if (status != PZ_OK)
        return status;
    choose_grain(options, mesh, result);
    return PZ_OK;
}
